"""FElupe model of the half sensor body: nearly incompressible neo-Hookean solid, rigid magnet,
two rigid plates with Coulomb friction, adaptive load stepping (docs/method.md §3)."""

from __future__ import annotations

import functools
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, fields

import felupe as fem
import numpy as np

from ..geometry import BodyMesh
from ..study import Mechanics
from ._face_contact import FaceContactRigidPlane

#: Default settings of the structural model: the study's (``magtact.study.Mechanics``).
_DEFAULT = Mechanics()

#: Contact of the body with the plates (the choices of the study's ``mechanics.contact``):
#: node-wise, or integrated at the faces' Gauss points.
CONTACTS: tuple[str, ...] = tuple(
    next(f for f in fields(Mechanics) if f.name == "contact").metadata["choices"])

#: Sparse direct solvers of the (unsymmetric) Newton systems (the choices of the study's
#: ``mechanics.solver``).
SOLVERS: tuple[str, ...] = tuple(
    next(f for f in fields(Mechanics) if f.name == "solver").metadata["choices"])


class NewtonFailed(Exception):
    """The Newton iterations of a load step diverged, stalled or produced non-finite values."""


class _Pardiso:
    """PARDISO (MKL, via pypardiso's public ``PyPardisoSolver``): ``factorize`` runs the
    analysis and the numerical factorisation of each Jacobian (PARDISO phase 12), ``solve``
    reuses that factorisation (phase 33: pypardiso recognises the factorised matrix).
    pypardiso's public API has no numerical-only factorisation (phase 22), so the analysis is
    repeated for every Jacobian although the pattern does not change during a path.
    """

    def __init__(self, threads: int):
        from pypardiso import PyPardisoSolver

        self.ps = PyPardisoSolver(mtype=11)  # real unsymmetric
        if threads > 0 and hasattr(self.ps.libmkl, "MKL_Set_Num_Threads"):
            self.ps.libmkl.MKL_Set_Num_Threads(int(threads))
        self.A = None

    def factorize(self, A) -> None:
        A = A.tocsr()
        A.sort_indices()
        self.ps.factorize(A)
        self.A = A

    def solve(self, b: np.ndarray) -> np.ndarray:
        return np.asarray(self.ps.solve(self.A, np.asarray(b, dtype=float))).ravel()

    def free(self) -> None:
        self.ps.free_memory(everything=True)
        self.A = None


class _SuperLU:
    """SciPy's SuperLU: factorise a CSC copy, solve with the factors."""

    def __init__(self, threads: int):
        self.lu = None

    def factorize(self, A) -> None:
        from scipy.sparse.linalg import splu

        self.lu = splu(A.tocsc())

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self.lu.solve(b)

    def free(self) -> None:
        self.lu = None


@functools.cache
def pardiso_available() -> bool:
    """Whether pypardiso and its MKL library can be loaded (installed with magtact on x86-64;
    MKL exists for x86-64 only)."""
    try:
        from pypardiso import PyPardisoSolver

        PyPardisoSolver()
    except (ImportError, OSError):
        return False
    return True


def _singular_errors() -> tuple[type[BaseException], ...]:
    """Exceptions by which the linear solvers report a singular matrix: SuperLU raises
    RuntimeError ("Factor is exactly singular"), PARDISO its PyPardisoError."""
    errors: tuple[type[BaseException], ...] = (RuntimeError, np.linalg.LinAlgError)
    try:
        from pypardiso.pardiso_wrapper import PyPardisoError
    except ImportError:
        return errors
    return (*errors, PyPardisoError)


def _linear_solver(name: str, threads: int):
    """The linear solver ``name``; ``"pardiso"`` falls back to SuperLU (with a warning) where
    pypardiso or MKL is not installed: both solve the same systems to round-off."""
    if name == "pardiso":
        if pardiso_available():
            return _Pardiso(threads)
        warnings.warn("pypardiso (MKL) is not installed: the Newton systems are solved by "
                      "SciPy's SuperLU (slower; pip install pypardiso, x86-64 only)",
                      RuntimeWarning, stacklevel=3)
        return _SuperLU(threads)
    if name == "superlu":
        return _SuperLU(threads)
    raise ValueError(f"unknown linear solver {name!r}; choose one of {SOLVERS}")


def _node_classes(bmesh: BodyMesh) -> list[np.ndarray]:
    """The free-surface nodes of ``bmesh`` split into cell corners, mid-edge and mid-face nodes
    (one group for 8-node cells, two for 20-node cells)."""
    if bmesh.order == 1:
        return [bmesh.surface]
    groups = []
    for lo, hi in ((0, 8), (8, 20), (20, 26))[: 2 if bmesh.cells.shape[1] == 20 else 3]:
        groups.append(np.intersect1d(bmesh.surface, np.unique(bmesh.cells[:, lo:hi])))
    return groups


def _contact_faces(bmesh: BodyMesh, n_points: int):
    """Point mask and face filter of the faces that can touch a plate: the outer surface's
    faces, those next to the base included (a side folding onto the lower plate there), without
    the base, the symmetry plane and the cavity."""
    mask = np.zeros(n_points, dtype=bool)
    mask[np.union1d(bmesh.surface, bmesh.base)] = True
    on_base = np.zeros(n_points, dtype=bool)
    on_base[bmesh.base] = True
    y = np.abs(np.append(bmesh.points[:, 1], [0.0, 0.0]))
    tol = 1e-9 * bmesh.z_top

    def exclude(faces: np.ndarray) -> np.ndarray:
        return np.all(on_base[faces], axis=1) | np.all(y[faces] < tol, axis=1)

    return mask, exclude


#: FElupe cell type and region of the hexahedra with 8, 20 and 27 nodes; each region's default
#: quadrature: 2 × 2 × 2 Gauss points for 8 nodes, 3 × 3 × 3 for 20 and 27.
_CELLS = {8: ("hexahedron", fem.RegionHexahedron),
          20: ("hexahedron20", fem.RegionQuadraticHexahedron),
          27: ("hexahedron27", fem.RegionTriQuadraticHexahedron)}


class StepFailure(Exception):
    """A load step could not be converged with the smallest allowed step size.

    ``reached``: what :meth:`HalfBodyModel.solve_path` recorded before the failure (its
    outputs at the first ``len(reached["lower"])`` load levels), or None.
    """

    def __init__(self, t: float, t_converged: float, reason: str, reached: dict | None = None):
        super().__init__(reason)
        self.t, self.t_converged, self.reason, self.reached = t, t_converged, reason, reached


@dataclass(frozen=True)
class Stepping:
    """Adaptive load stepping and Newton controls (step sizes in units of the load t ∈ [0, 1]).

    A step that fails is restored and retried with dt × ``cutback``; a step that needed at most
    ``easy_iter`` Newton iterations lets dt grow × ``growth`` up to ``dt_max``. A step fails
    after ``max_iter`` iterations, or when, after two iterations that did not halve the best
    residual (from then on each update is backtracked up to ``line_search`` halvings until the
    residual decreases), three more fail to halve it, or when a residual stays non-finite after
    ``line_search`` halvings of the update. ``tol``: ‖r_free‖ / (‖r_prescribed‖ + ε) at
    convergence; ``tol_cycling``: the same once the contact state cycles. A point that grazes a
    plate (zero gap at the solution) makes the iterates alternate between holding it with the
    penalty, hundreds to thousands of times the stiffness of its surface, and releasing it a
    fraction of a nanometre off the plate; the released iterate's residual is the force that
    would hold the point there, and it stays above ``tol`` at any step size (docs/method.md §3).
    ``reuse_ratio``: an iteration that reduced the best residual so far by at least this factor
    keeps its tangent (and factorisation) for the next (0: a new tangent every iteration; 0.25
    stalled 27-node paths at first contacts).
    """

    dt_initial: float = _DEFAULT.dt_initial
    dt_min: float = _DEFAULT.dt_min
    dt_max: float = _DEFAULT.dt_max
    max_iter: int = _DEFAULT.max_newton
    easy_iter: int = 4
    growth: float = 1.5
    cutback: float = 0.5
    tol: float = _DEFAULT.newton_tol
    line_search: int = 4
    tol_cycling: float = 1e-5
    reuse_ratio: float = 0.0

    def __post_init__(self):
        if not 0 < self.dt_min <= self.dt_initial <= self.dt_max:
            raise ValueError(f"load steps must satisfy 0 < dt_min <= dt_initial <= dt_max, got "
                             f"{self.dt_min:g}, {self.dt_initial:g}, {self.dt_max:g}")


class HalfBodyModel:
    """The half body y ≥ 0 between two rigid plates, loaded through its magnet.

    Boundary conditions: base z = 0 fixed (``base="clamped"``) or held only in z and, on the
    line x = 0, in x (``base="sliding"``: a frictionless support); symmetry u_y = 0 on y = 0;
    cavity nodes move with the rigid magnet by (u_r, 0, u_z); the upper plate (initially at the
    top face) moves by the same (u_r, 0, u_z); the lower plate is the plane z = 0. Both plates
    act on every node of the free outer surface by penalty contact (FElupe ``ContactRigidPlane``;
    or on its faces, ``contact="faces"``) with Coulomb friction μ_f; the penalty multipliers are
    relative to the solid's stiffness, so every force is proportional to G.

    Parameters
    ----------
    bmesh : BodyMesh
        Hexahedral half-body mesh [m].
    G : float
        Shear modulus [Pa].
    bulk_ratio : float
        Bulk modulus / G of the nearly incompressible formulation.
    mu_f : float
        Coulomb friction coefficient of both plates.
    base : {"clamped", "sliding"}
        Support of the base.
    penalty : float
        Normal contact multiplier relative to the mean diagonal stiffness of the contact nodes.
    elastic_slip : float
        Allowable elastic slip γ [m] of sticking contact points: the tangential penalty is
        μ_f f_n / γ, so it vanishes with the normal force (robust Newton iterations) and is
        proportional to G like every force.
    solver : {"pardiso", "superlu"}
        Sparse direct solver of the (unsymmetric) Newton systems.
    threads : int
        Threads of the PARDISO solver (0: the library default).
    contact : {"nodes", "faces"}
        Contact at the nodes of the outer surface (FElupe ``ContactRigidPlane``) or integrated
        at the Gauss points of its faces (:class:`FaceContactRigidPlane`; what 20-node cells
        need, docs/method.md §3).
    penalty_per_node_class : bool
        Contact items per class of surface node (cell corners, mid-edge, mid-face nodes of
        27-node cells), each with its penalty relative to the mean diagonal stiffness of its own
        class instead of all surface nodes (the corner nodes of 27-node cells are far softer
        than the mid-face ones).

    Notes
    -----
    Material: the isochoric neo-Hookean energy W = G/2 (J^(-2/3) I_1 − 3) with a volumetric
    penalty K/2 (J̄ − 1)², K = bulk_ratio · G, in FElupe's ``SolidBodyNearlyIncompressible``:
    the pressure and the volume ratio are constant per cell and condensed, on trilinear (Q1/P0),
    20-node serendipity (Q2s/P0) or 27-node triquadratic (Q2/P0) hexahedra, after the cells of
    ``bmesh``. Contact acts on every node of the outer surface, mid-edge and mid-face nodes
    included.
    """

    def __init__(self, bmesh: BodyMesh, G: float, bulk_ratio: float, mu_f: float, *,
                 base: str = "clamped", penalty: float = _DEFAULT.contact_penalty,
                 elastic_slip: float = _DEFAULT.elastic_slip, solver: str = _DEFAULT.solver,
                 threads: int = _DEFAULT.threads, penalty_per_node_class: bool = False,
                 contact: str = _DEFAULT.contact):
        if base not in ("clamped", "sliding"):
            raise ValueError(f"base must be 'clamped' or 'sliding', got {base!r}")
        if contact not in CONTACTS:
            raise ValueError(f"contact must be one of {CONTACTS}, got {contact!r}")
        self.bmesh = bmesh
        self.G = float(G)
        self.timings = {"solid": 0.0, "contact": 0.0, "factorization": 0.0, "solve": 0.0}
        self._linear = _linear_solver(solver, threads)

        n = bmesh.n_points
        cell_type, region_type = _CELLS[bmesh.cells.shape[1]]
        mesh = fem.Mesh(bmesh.points.copy(), bmesh.cells.copy(), cell_type)
        mesh.update(points=np.vstack([mesh.points, [[0.0, 0.0, 0.0], [0.0, 0.0, bmesh.z_top]]]))
        self.lower, self.upper = n, n + 1
        region = region_type(mesh)
        self.field = fem.FieldContainer([fem.Field(region, dim=3)])
        self.solid = fem.SolidBodyNearlyIncompressible(
            fem.NeoHooke(mu=self.G), self.field, bulk=bulk_ratio * self.G)
        plates = ((self.lower, [0, 0, 1.0]), (self.upper, [0, 0, -1.0]))
        if contact == "faces":
            self.contacts = [  # the lower plate first, then the upper one
                FaceContactRigidPlane(self.field, *_contact_faces(bmesh, n + 2), centre, normal,
                                      friction=mu_f, elastic_slip=elastic_slip,
                                      multiplier=penalty, solid=self.solid)
                for centre, normal in plates]
        else:
            kw = {"friction": mu_f, "multiplier": penalty, "items": [self.solid]}
            if mu_f > 0:
                kw["elastic_slip"] = elastic_slip
            groups = _node_classes(bmesh) if penalty_per_node_class else [bmesh.surface]
            self.contacts = [  # all lower-plate items first, then the upper plate's
                fem.ContactRigidPlane(self.field, nodes, centre, normal, **kw)
                for centre, normal in plates for nodes in groups if len(nodes)]
        self.items = [self.solid, *self.contacts]
        self._timing_keys = ["solid"] + ["contact"] * len(self.contacts)

        # prescribed degrees of freedom (dof = 3 node + component)
        def dofs(nodes, comps):
            return (3 * np.asarray(nodes)[:, None] + np.asarray(comps)[None, :]).ravel()

        fixed = [dofs(bmesh.symmetry, [1]), dofs([self.lower], [0, 1, 2]),
                 dofs([self.upper], [1]), dofs(bmesh.cavity, [1])]
        if base == "clamped":
            fixed.append(dofs(bmesh.base, [0, 1, 2]))
        else:
            on_axis = bmesh.base[np.abs(bmesh.points[bmesh.base, 0]) < 1e-12 * bmesh.z_top]
            fixed += [dofs(bmesh.base, [2]), dofs(on_axis, [0])]
        self._moving_x = np.concatenate([dofs(bmesh.cavity, [0]), [3 * self.upper]])
        self._moving_z = np.concatenate([dofs(bmesh.cavity, [2]), [3 * self.upper + 2]])
        ndof = 3 * (n + 2)
        self.dof0 = np.unique(np.concatenate(fixed + [self._moving_x, self._moving_z]))
        self.dof1 = np.setdiff1d(np.arange(ndof), self.dof0)
        self.n_dofs = ndof
        self._fun = np.zeros(ndof)
        self._K10 = None
        self._eps = 1e-6 * self.G * bmesh.z_top**2  # force scale of the convergence check [N]
        #: Newton iterations (linear solves) and Jacobians of all steps, also of failed ones
        self.iterations = 0
        self.jacobians = 0
        #: (t_start, t_end, Newton iterations of the step or -1 if it failed) of every step tried
        self.log: list[tuple[float, float, int]] = []

    # ---- state ------------------------------------------------------------------------------
    @property
    def displacement(self) -> np.ndarray:
        """Displacement of the body's nodes [m], shape (n_points, 3)."""
        return self.field[0].values[: self.bmesh.n_points].copy()

    def reactions(self) -> dict[str, np.ndarray]:
        """Forces on the half body [N] at the last converged state, each of shape (3,).

        ``lower``: base reaction plus lower-plate contact force (the support acting on the body);
        ``upper``: upper-plate contact force; ``magnet``: force of the magnet on the body.
        """
        f = self._fun.reshape(-1, 3)
        return {
            "lower": f[self.bmesh.base].sum(axis=0) + f[self.lower],
            "upper": f[self.upper].copy(),
            "magnet": f[self.bmesh.cavity].sum(axis=0),
        }

    def _checkpoint(self):
        return [self.solid.checkpoint()] + [c.checkpoint() for c in self.contacts]

    def _restore(self, chk) -> None:
        self.solid.restore(chk[0])
        for c, k in zip(self.contacts, chk[1:], strict=True):
            c.restore(k)

    # ---- solution ---------------------------------------------------------------------------
    def _residual(self) -> np.ndarray:
        """Assemble the residual (internal minus external force) [N] at the current field.

        Cells turned inside out by a too large update give non-finite values (no warning: the
        line search and the step control handle them)."""
        f = np.zeros(self.n_dofs)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            for r in self._assemble("vector", field=self.field):
                r = np.asarray(r.todense()).ravel()
                f[: len(r)] += r
        return f

    def _assemble(self, kind: str, **kwargs) -> list:
        """``item.assemble.vector`` or ``.matrix`` of every item (FElupe's public assembly),
        its wall time added to ``timings["solid"]`` or ``timings["contact"]``."""
        out = []
        for item, key in zip(self.items, self._timing_keys, strict=True):
            t0 = time.perf_counter()
            out.append(getattr(item.assemble, kind)(**kwargs))
            self.timings[key] += time.perf_counter() - t0
        return out

    def _jacobian(self) -> None:
        """Assemble the tangent at the current state and factorise its free-free block."""
        matrices = self._assemble("matrix")
        K = matrices[0]
        for k in matrices[1:]:
            K = K + k
        K = K.tocsr()
        rows = K[self.dof1]
        t0 = time.perf_counter()
        try:
            self._linear.factorize(rows[:, self.dof1])
        except _singular_errors() as exc:  # a singular tangent: no convergence from here
            raise NewtonFailed(f"singular tangent ({type(exc).__name__}: {exc})") from exc
        self.timings["factorization"] += time.perf_counter() - t0
        self._K10 = rows[:, self.dof0].tocsr()
        self.jacobians += 1

    def _norm(self, f: np.ndarray) -> float:
        """Convergence measure ‖r_free‖ / (‖r_prescribed‖ + ε), ε ∝ G: G-invariant."""
        return float(np.linalg.norm(f[self.dof1]) / (np.linalg.norm(f[self.dof0]) + self._eps))

    def _line_search(self, u: np.ndarray, du: np.ndarray, halvings: int,
                     below: float = np.inf) -> tuple[np.ndarray, float]:
        """Residual after the update u += du (already applied), backtracking u ← u − α du with
        α = 1/2, 1/4, … while the residual is not finite (cells turned inside out) or not
        below ``below``. Outside the cycling mode of :meth:`_newton` ``below`` is infinite: a
        larger residual is accepted, since with contact it may grow before Newton's method
        converges. If no halving gets below ``below``, the smallest step is kept.

        Raises
        ------
        NewtonFailed
            If the residual is still not finite after ``halvings`` halvings.
        """
        f = self._residual()
        fnorm = self._norm(f)
        alpha = 1.0
        for _ in range(halvings):
            if np.isfinite(fnorm) and fnorm < below:
                break
            alpha /= 2
            u -= alpha * du
            f = self._residual()
            fnorm = self._norm(f)
        if not np.isfinite(fnorm):
            raise NewtonFailed("non-finite residual (inverted cells?)")
        return f, fnorm

    def _newton(self, u_r: float, u_z: float, st: Stepping) -> int:
        """One load step to the magnet displacement (u_r, u_z) [m]; returns its iterations.

        Newton's method on the free DOFs. The first iteration is the predictor with the tangent
        of the previous step's last iterate and the prescribed increment du0,
        K11 du1 = −r1 − K10 du0; every later iteration assembles and factorises a new tangent.
        When two iterations in a row do not halve the best residual so far, the contact state
        is cycling (a node crossing a plate or switching between stick and slip): from then on
        every update is backtracked until the residual decreases. Three more iterations
        without improvement fail the step. On success the contact state variables (stick
        reference, active set) are accepted.

        Raises
        ------
        NewtonFailed
            On non-finite values, a stall, or too many iterations.
        """
        ext = np.zeros(self.n_dofs)
        ext[self._moving_x] = u_r
        ext[self._moving_z] = u_z
        u = self.field[0].values.reshape(-1)  # a view: updates act on the field
        if self._K10 is None:
            self._jacobian()
        f, fnorm, best, stalled, cycling = self._fun, np.inf, np.inf, 0, False
        for it in range(1, st.max_iter + 1):
            du = np.zeros(self.n_dofs)
            du[self.dof0] = ext[self.dof0] - u[self.dof0]
            t0 = time.perf_counter()
            try:
                du[self.dof1] = self._linear.solve(-f[self.dof1] - self._K10 @ du[self.dof0])
            except _singular_errors() as exc:
                raise NewtonFailed(f"linear solve failed ({type(exc).__name__}: {exc})") from exc
            self.timings["solve"] += time.perf_counter() - t0
            u += du
            f, fnorm = self._line_search(u, du, st.line_search, fnorm if cycling else np.inf)
            self.iterations += 1
            if fnorm < st.tol or (cycling and fnorm < st.tol_cycling):
                for item in self.items:
                    item.results.update_statevars()
                self._fun = f
                return it
            stalled = stalled + 1 if fnorm > 0.5 * best else 0
            if stalled >= (3 if cycling else 2):
                if cycling:
                    raise NewtonFailed(
                        f"no progress of the Newton iterations (residual {fnorm:.2e})")
                cycling, stalled = True, 0
            contracted = bool(np.isfinite(best) and fnorm <= st.reuse_ratio * best)
            best = min(best, fnorm)
            if it < st.max_iter and (cycling or not contracted):
                self._jacobian()
        raise NewtonFailed(f"not converged in {st.max_iter} iterations (residual {fnorm:.2e})")

    def solve_path(self, path: Callable[[float], tuple[float, float]], t_levels, *,
                   stepping: Stepping | None = None,
                   on_level: Callable[[float], None] | None = None) -> dict:
        """Follow the load path from t = 0 and record the reactions at ``t_levels``.

        Parameters
        ----------
        path : callable
            t ↦ (u_r, u_z) [m], the displacement of the magnet and the upper plate.
        t_levels : (n,) array_like
            Increasing load levels in [0, 1] at which the forces are recorded.
        stepping : Stepping or None
            Step-size controls; a failed step is restored and retried with dt × cutback, a
            step that converged in at most ``easy_iter`` iterations lets dt grow × growth.
        on_level : callable or None
            Called with each recorded t (progress).

        Returns
        -------
        dict
            ``lower``, ``upper``, ``magnet``: (n, 3) forces on the half body [N] (see
            :meth:`reactions`); ``iterations`` (all Newton iterations, also those of failed
            steps), ``jacobians`` (tangents assembled and factorised), ``cutbacks``,
            ``steps`` (converged steps): counts.

        Raises
        ------
        StepFailure
            When a step fails with dt < ``stepping.dt_min``.
        """
        st = stepping or Stepping()
        t_levels = np.asarray(t_levels, dtype=float)
        if t_levels.ndim != 1 or np.any(np.diff(t_levels) <= 0) or t_levels[0] < 0:
            raise ValueError("t levels must be increasing and non-negative")
        out = {k: np.zeros((len(t_levels), 3)) for k in ("lower", "upper", "magnet")}
        cutbacks = steps = 0
        t, dt = 0.0, st.dt_initial
        for i, target in enumerate(t_levels):
            while t < target - 1e-12:
                t_try = min(t + dt, target)
                if target - t_try < 0.2 * dt:  # no sliver step before a level
                    t_try = target
                chk = self._checkpoint()
                try:
                    n_it = self._newton(*path(t_try), st)
                except NewtonFailed as exc:  # anything else is a bug: it propagates
                    self._restore(chk)
                    self._K10 = None  # the tangent belongs to the failed state
                    self.log.append((t, t_try, -1))
                    cutbacks += 1
                    dt = (t_try - t) * st.cutback
                    if dt < st.dt_min:
                        self._linear.free()
                        self._K10 = None
                        reached = {**{k: v[:i].copy() for k, v in out.items()},
                                   "iterations": self.iterations,
                                   "jacobians": self.jacobians, "cutbacks": cutbacks,
                                   "steps": steps}
                        raise StepFailure(t_try, t, str(exc).strip() or type(exc).__name__,
                                          reached) from exc
                    continue
                steps += 1
                self.log.append((t, t_try, n_it))
                if n_it <= st.easy_iter:
                    dt = min(st.dt_max, max(dt, t_try - t) * st.growth)
                t = t_try
            if target > 0:
                r = self.reactions()
                for k in out:
                    out[k][i] = r[k]
            if on_level is not None:
                on_level(float(target))
        self._linear.free()
        self._K10 = None  # the next path starts with a new factorisation
        return {**out, "iterations": self.iterations, "jacobians": self.jacobians,
                "cutbacks": cutbacks, "steps": steps}
