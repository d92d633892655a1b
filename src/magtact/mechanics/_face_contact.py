"""Penalty contact of the body's outer faces with a rigid plane, with Coulomb friction, integrated
at the faces' Gauss points (docs/method.md §3).

Node-wise contact pushes on each node alone, so it can only reproduce a contact pressure whose
consistent nodal forces are all compressive. That holds for 8- and 27-node hexahedra but not for
the 20-node serendipity face: under a uniform pressure its corners carry −1/12 of the face's
force, which node-wise contact cannot give, so the corners of a face pressed onto a plate lift
off. Here the gap, the penalty pressure and the friction traction live at the faces' Gauss
points and reach the nodes through the face's shape functions, as any surface traction does.
"""

from __future__ import annotations

from types import SimpleNamespace

import felupe as fem
import numpy as np
from scipy.sparse import coo_matrix

#: FElupe boundary regions (faces of the hexahedra, Gauss points on each face) by nodes per cell.
_BOUNDARY = {8: fem.RegionHexahedronBoundary, 20: fem.RegionQuadraticHexahedronBoundary,
             27: fem.RegionTriQuadraticHexahedronBoundary}


class FaceContactRigidPlane:
    r"""Contact of faces of a hexahedral mesh with a rigid plane through ``centre``.

    The plane moves with the centre point's displacement and does not rotate. At every Gauss
    point q of the faces, with the gap vector Δx_q = Σ_a N_a(ξ_q) x_a − x_c and the plane's
    outward normal n:

    .. math::

        g_q = Δx_q · n, \quad p_q = ε\, w_q\, φ(g_q), \quad
        \boldsymbol f_a = Σ_q N_a(ξ_q) \left(−p_q\, \boldsymbol n + \boldsymbol t_q\right),

    φ(g) = g²/(2δ) for −δ < g < 0, −g − δ/2 beyond, 0 off the plane (a C¹ penalty: with the
    kink of the plain one a point grazing the plane makes Newton's iterations alternate between
    holding and releasing it); w_q the Gauss weight times the face's reference area element,
    on 2 × 2 Gauss points per face (3 × 3 points over-constrain an 8-node face pressed onto a
    plate: the grazing contact of the top face then made Newton's iterations chatter at the
    first step of a path). ε [Pa/m]
    is the penalty per unit area: ``multiplier`` times the solid's mean diagonal normal
    stiffness of the face nodes, divided by the mean of Σ_q N_a² w_q, so a node feels about
    ``multiplier`` times its own stiffness, as with node-wise contact. It is evaluated once, in
    the undeformed state: a penalty updated per increment changes every contact force between
    increments, and after a failed increment it would follow the failed iterate.

    Friction: an elastic stick with the tangential penalty μ p_q / γ (γ the allowable elastic
    slip) and a return mapping onto the Coulomb limit |t_q| ≤ μ p_q, the corner between them
    rounded (``slip_blend``); the stick reference of a
    point that comes into contact within the increment is its point of first contact
    (interpolated to zero gap): the law FElupe's node-wise ``ContactRigidPlane`` applies at
    nodes, here at Gauss points. The tangent is consistent (unsymmetric when sliding). Forces
    are residual contributions: the plane acts on the body with −f_a and on its centre point
    with Σ_a f_a.

    Parameters
    ----------
    field : felupe.FieldContainer
        The displacement field (first field) on a hexahedral mesh.
    mask : (n_points,) ndarray of bool
        Points of the faces that can touch the plane: a face counts if all its points are in
        ``mask`` and it is not in ``exclude``.
    exclude : callable or None
        ``exclude(face_points)`` → bool per face, (n_faces, k) point indices: faces to drop.
    centre : int
        The point that carries the plane's displacement.
    normal : (3,) array_like
        The plane's outward normal (towards the body).
    friction : float
        Coulomb coefficient μ (0: frictionless).
    elastic_slip : float
        Allowable elastic slip γ [m] of sticking points (used if ``friction`` > 0).
    multiplier : float
        Penalty relative to the solid's nodal stiffness.
    solid : object
        The solid body (FElupe item) whose stiffness scales the penalty.
    smoothing : float
        Penetration δ [m] over which the penalty stiffness rises from 0 to ε w_q (0: the
        plain penalty).
    slip_blend : float
        κ: the friction traction turns from sticking to sliding over elastic slips of
        (1 ± κ) γ along a parabola (C¹; 0: the kink of the plain return mapping).
    """

    def __init__(self, field, mask, exclude, centre: int, normal, *, friction: float = 0.0,
                 elastic_slip: float = 5e-8, multiplier: float = 5.0, solid=None,
                 smoothing: float = 1e-7, slip_blend: float = 0.5):
        mesh = field.region.mesh
        self.field = field
        self.centre = int(centre)
        self.normal = np.asarray(normal, dtype=float) / np.linalg.norm(normal)
        self.friction = float(friction)
        self.elastic_slip = float(elastic_slip)
        self.multiplier = float(multiplier)
        self.smoothing = float(smoothing)
        self.slip_blend = float(slip_blend)
        self.solid = solid

        region = _BOUNDARY[mesh.cells.shape[1]](
            mesh, quadrature=fem.GaussLegendreBoundary(order=1, dim=3),
            mask=np.asarray(mask, dtype=bool))
        h = region.h[..., 0]  # the same Gauss points on every face (FElupe orders the cells)
        local = np.flatnonzero(np.abs(h).max(axis=1) > 1e-12)  # the face's own nodes
        faces = region.mesh.cells[:, local]
        keep = np.ones(len(faces), dtype=bool) if exclude is None else ~exclude(faces)
        self.faces = faces[keep]  # (n_faces, k)
        self.N = h[local]  # (k, n_qp)
        self.w = region.dV[:, keep].T  # (n_faces, n_qp) reference area × weight [m²]
        self.X = np.einsum("aq,fai->fqi", self.N, mesh.points[self.faces])
        self.nodes = np.unique(self.faces)
        # Σ_q N_a² w_q per face node: a node's share of the penalty (mean over the face nodes)
        share = np.zeros(mesh.npoints)
        np.add.at(share, self.faces, np.einsum("aq,fq->fa", self.N**2, self.w))
        self._share = float(share[self.nodes].mean())
        self._eps = self._penalty()

        self.assemble = SimpleNamespace(vector=self._vector, matrix=self._matrix)
        #: ``slip``: the Gauss points that slide in the last evaluated state
        self.results = SimpleNamespace(update_statevars=self._update_statevars, slip=None)
        dx = self._gaps().reshape(-1, 3)
        self.state = {"dx": dx, "dx_ref": dx.copy(), "active": dx @ self.normal < 0}
        self._trial = None

    # ---- kinematics ------------------------------------------------------------------------
    def _gaps(self) -> np.ndarray:
        """Gap vectors Δx_q [m] of all Gauss points, shape (n_faces, n_qp, 3)."""
        u = self.field[0].values
        return self.X + np.einsum("aq,fai->fqi", self.N, u[self.faces]) - (
            self.field.region.mesh.points[self.centre] + u[self.centre])

    def _penalty(self) -> float:
        """ε [Pa/m]: the solid's mean diagonal normal stiffness at the face nodes × multiplier,
        per unit of a node's share Σ_q N_a² w_q (called once, before any load step)."""
        K = self.solid.results.stiffness  # the undeformed solid's, if another item assembled it
        if K is None:
            K = self.solid.assemble.matrix(self.field)
        dof = 3 * self.nodes[:, None] + np.arange(3)[None, :]
        diag = K.diagonal()[dof]  # (n, 3)
        k_normal = float(np.mean(diag @ self.normal**2))
        return self.multiplier * k_normal / self._share

    # ---- the contact law at the Gauss points -----------------------------------------------
    def _evaluate(self, field=None):
        if field is not None:
            self.field = field
        n = self.normal
        dx = self._gaps().reshape(-1, 3)
        g = dx @ n
        active = g < 0
        idx = np.flatnonzero(active)
        lam = self._eps * self.w.reshape(-1)[idx]  # penalty per point [N/m]
        gc = g[idx]
        nn = np.outer(n, n)
        # C¹ penalty: f_n = λ g²/(2δ) for −δ < g < 0, λ (−g − δ/2) beyond; k_n = ∂f_n/∂(−g)
        d = self.smoothing
        soft = gc > -d
        fn = np.where(soft, lam * gc**2 / (2 * d) if d > 0 else 0.0, -lam * (gc + d / 2))
        kn = np.where(soft, -lam * gc / d if d > 0 else 0.0, lam)
        force = -fn[:, None] * n
        stiff = kn[:, None, None] * nn
        dx_ref = dx.copy()
        sliding = np.zeros(len(dx), dtype=bool)
        if self.friction > 0 and len(idx):
            mu, gamma = self.friction, self.elastic_slip
            Pt = np.eye(3) - nn
            dxc = dx[idx]
            e = (dxc - self.state["dx_ref"][idx]) @ Pt
            E = np.broadcast_to(Pt, (len(idx), 3, 3)).copy()
            new = ~self.state["active"][idx]
            if np.any(new):  # reference at the point of first contact within the increment
                dxn = self.state["dx"][idx][new]
                gn, gnew = dxn @ n, gc[new]
                delta = (dxc[new] - dxn) @ Pt
                s, ds = np.ones_like(gnew), np.zeros_like(gnew)
                first = gn > 0
                s[first] = -gnew[first] / (gn[first] - gnew[first])
                ds[first] = -gn[first] / (gn[first] - gnew[first]) ** 2
                e[new] = s[:, None] * delta
                E[new] = s[:, None, None] * Pt + ds[:, None, None] * np.einsum(
                    "pi,j->pij", delta, n)
            # |f_t| = μ f_n ψ(|e|/γ): ψ(x) = x (stick) up to 1 − κ, 1 (slide) from 1 + κ and
            # the C¹ parabola between; f_t = μ f_n a e with a = ψ/|e|
            kappa = self.slip_blend
            e_norm = np.linalg.norm(e, axis=1)
            x = e_norm / gamma
            lo, hi = 1 - kappa, 1 + kappa
            blend = (x > lo) & (x < hi)
            slide = x >= hi
            psi = np.where(x <= lo, x, 1.0)
            dpsi = np.where(x <= lo, 1.0, 0.0)
            if kappa > 0:
                psi[blend] = x[blend] - (x[blend] - lo) ** 2 / (4 * kappa)
                dpsi[blend] = 1 - (x[blend] - lo) / (2 * kappa)
            inner = x <= lo
            safe = np.where(inner, 1.0, e_norm)
            a = np.where(inner, 1 / gamma, psi / safe)
            da = np.where(inner, 0.0, dpsi / (gamma * safe) - psi / safe**2)  # ∂a/∂|e|
            eh = e / safe[:, None]
            ft = (mu * fn * a)[:, None] * e
            Kt = mu * (fn[:, None, None] * (a[:, None, None] * E + da[:, None, None]
                                            * np.einsum("pi,pj,pjk->pik", e, eh, E))
                       - (kn * a)[:, None, None] * np.einsum("pi,j->pij", e, n))
            e_ref = e.copy()
            e_ref[slide] = hi * gamma * eh[slide]  # the reference follows a sliding point
            force += ft
            stiff += Kt
            dx_ref[idx] = dxc - e_ref
            sliding[idx] = slide
        self._trial = {"dx": dx, "dx_ref": dx_ref, "active": active}
        self.results.slip = sliding
        return idx, force, stiff

    def _dofs(self, idx):
        """Point indices (face nodes, then the centre) and their shape-function values of the
        active Gauss points: (m, k + 1) each."""
        n_qp = self.N.shape[1]
        f, q = np.divmod(idx, n_qp)
        pts = np.concatenate([self.faces[f], np.full((len(idx), 1), self.centre)], axis=1)
        vals = np.concatenate([self.N[:, q].T, -np.ones((len(idx), 1))], axis=1)
        return pts, vals

    def _vector(self, field=None, parallel=False):
        idx, force, _ = self._evaluate(field)
        pts, vals = self._dofs(idx)
        rows = (3 * pts[:, :, None] + np.arange(3)).ravel()
        data = (vals[:, :, None] * force[:, None, :]).ravel()
        size = 3 * self.field.region.mesh.npoints
        return coo_matrix((data, (rows, np.zeros_like(rows))), shape=(size, 1)).tocsr()

    def _matrix(self, field=None, parallel=False):
        idx, _, stiff = self._evaluate(field)
        pts, vals = self._dofs(idx)
        dof = 3 * pts[:, :, None] + np.arange(3)  # (m, k+1, 3)
        m, k1 = pts.shape
        rows = np.broadcast_to(dof[:, :, None, :, None], (m, k1, k1, 3, 3)).ravel()
        cols = np.broadcast_to(dof[:, None, :, None, :], (m, k1, k1, 3, 3)).ravel()
        data = np.einsum("pa,pb,pij->pabij", vals, vals, stiff).ravel()
        size = 3 * self.field.region.mesh.npoints
        return coo_matrix((data, (rows, cols)), shape=(size, size)).tocsr()

    # ---- state -----------------------------------------------------------------------------
    def _update_statevars(self) -> None:
        """Accept the last evaluated (trial) state: the increment has converged."""
        if self._trial is not None:
            self.state = {k: v.copy() for k, v in self._trial.items()}

    def checkpoint(self) -> dict:
        """The state of the last converged increment (copies)."""
        return {k: v.copy() for k, v in self.state.items()}

    def restore(self, checkpoint: dict) -> None:
        """Go back to a :meth:`checkpoint` (a failed increment is retried from there)."""
        self.state = {k: v.copy() for k, v in checkpoint.items()}
        self._trial = None
