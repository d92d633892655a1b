"""Axisymmetric finite-element field of the magnet: reduced scalar potential, P2 triangles.

Coordinates (r, z) with the magnet's centre at the origin (docs/method.md §2). SI units.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, replace
from functools import cached_property, lru_cache

import numpy as np

from ..geometry import FieldMesh, field_mesh
from ..study import MU0, Study, StudyError, check_field_mesh


@dataclass(frozen=True, eq=False)
class FieldSolution:
    """Finite-element solution of the magnet's field; evaluate it with :meth:`B`.

    Attributes
    ----------
    mesh : FieldMesh
        The (r, z) triangle mesh (magnet centre at the origin).
    V : numpy.ndarray
        Reduced scalar potential at the P2 degrees of freedom [A], shape (n_dofs,).
    M_z, R_m, H_m : float
        Magnetisation [A/m], magnet radius and height [m].
    mesh_time, solve_time : float
        Wall-clock times of meshing and of assembly + solve [s].
    """

    mesh: FieldMesh
    V: np.ndarray
    M_z: float
    R_m: float
    H_m: float
    mesh_time: float
    solve_time: float
    _basis: object

    @property
    def n_dofs(self) -> int:
        """Number of P2 degrees of freedom."""
        return self.V.size

    @cached_property
    def _finder(self):
        from matplotlib.tri import Triangulation

        return Triangulation(*self.mesh.points, self.mesh.triangles.T).get_trifinder()

    def B(self, r, z) -> tuple[np.ndarray, np.ndarray]:
        """Flux density (B_r, B_z) [T] at points (r, z) [m] relative to the magnet's centre.

        Parameters
        ----------
        r, z : array_like
            Broadcastable coordinates [m]; r ≥ 0, inside the far box.

        Returns
        -------
        B_r, B_z : numpy.ndarray
            Each of the broadcast shape. B = −μ0 ∇V outside the magnet and
            μ0 (−∇V + M) inside; ∇V is the P1 (discontinuous) gradient of the P2 potential on
            the element holding the point.

        Raises
        ------
        ValueError
            For r < 0 or points outside the far box.
        """
        r, z = np.broadcast_arrays(np.asarray(r, dtype=float), np.asarray(z, dtype=float))
        shape = r.shape
        r, z = r.ravel(), z.ravel()
        if np.any(r < 0):
            raise ValueError("FieldSolution.B: r must be >= 0 (cylindrical radius)")
        if np.any(r > self.mesh.r_far) or np.any(np.abs(z) > self.mesh.z_far):
            raise ValueError(
                f"FieldSolution.B: points outside the far box r <= {self.mesh.r_far:g} m, "
                f"|z| <= {self.mesh.z_far:g} m")
        cells = self._finder(r, z)  # the triangle holding each point
        if np.any(cells < 0):  # pragma: no cover - the box check above excludes this
            raise ValueError("FieldSolution.B: points outside the mesh")
        Gr, Gz = _gradient_probes(self._basis, np.vstack([r, z]), cells)
        inside = (r < self.R_m) & (np.abs(z) < 0.5 * self.H_m)
        B_r = -MU0 * (Gr @ self.V)
        B_z = MU0 * (np.where(inside, self.M_z, 0.0) - Gz @ self.V)
        return B_r.reshape(shape), B_z.reshape(shape)


def _gradient_probes(basis, x: np.ndarray, cells: np.ndarray):
    """Sparse matrices mapping DOF values to ∂/∂r and ∂/∂z at points ``x`` (shape (2, n)),
    which lie in the triangles ``cells`` (shape (n,))."""
    from scipy.sparse import coo_matrix

    local = basis.mapping.invF(x[:, :, np.newaxis], tind=cells)
    grads = np.array([basis.elem.gbasis(basis.mapping, local, k, tind=cells)[0].grad[:, :, 0]
                      for k in range(basis.Nbfun)])  # (Nbfun, 2, n)
    rows = np.tile(np.arange(x.shape[1]), basis.Nbfun)
    cols = basis.element_dofs[:, cells].ravel()
    shape = (x.shape[1], basis.N)
    return tuple(coo_matrix((grads[:, d, :].ravel(), (rows, cols)), shape=shape).tocsr()
                 for d in range(2))


def solve_field(mesh: FieldMesh, R_m: float, H_m: float, M_z: float) -> FieldSolution:
    """Solve the axisymmetric reduced-scalar-potential problem on ``mesh``.

    Parameters
    ----------
    mesh : FieldMesh
        Mesh of the far box with the magnet's triangles flagged.
    R_m, H_m : float
        Magnet radius and height [m] (used to decide which points are inside the magnet).
    M_z : float
        Axial magnetisation [A/m].

    Returns
    -------
    FieldSolution
        ``solve_time`` covers assembly and solve; ``mesh_time`` is 0 (set by :func:`solve_fe`).

    Notes
    -----
    The body and the air have μr = 1 (docs/method.md §2). With H = −∇V, B = μ0 H outside and
    B = μ0 (H + M) inside the magnet, ∇·B = 0 in the domain and n·B = 0 on the far boundary
    (natural), the weak form over the meridian half-plane with the axisymmetric measure
    r dr dz (the 2π factor cancels) is

    .. math::

        \\int_\\Omega \\nabla V \\cdot \\nabla v \\; r \\, dr\\, dz
        = \\int_{\\text{magnet}} M_z \\frac{\\partial v}{\\partial z} \\; r \\, dr\\, dz
        \\quad \\forall v.

    The magnet's surface charge n·M enters through the right-hand side; the axis r = 0 needs
    no condition (the weight r makes it natural). V is defined up to a constant: one degree of
    freedom (the far corner r = r_far, z = z_far) is pinned to 0. Elements: P2 Lagrange
    triangles (``skfem.ElementTriP2``); the symmetric positive definite system is solved by
    SuperLU with a minimum-degree ordering of A + Aᵀ and no pivoting.
    """
    from scipy.sparse.linalg import splu
    from skfem import Basis, BilinearForm, ElementTriP2, LinearForm, MeshTri
    from skfem.helpers import dot, grad

    t0 = time.perf_counter()
    m = MeshTri(mesh.points, mesh.triangles)
    basis = Basis(m, ElementTriP2())

    @BilinearForm
    def stiffness(u, v, w):
        return dot(grad(u), grad(v)) * w.x[0]

    @LinearForm
    def source(v, w):
        return M_z * grad(v)[1] * w.x[0]

    A = stiffness.assemble(basis)
    magnet_basis = Basis(m, ElementTriP2(), elements=np.flatnonzero(mesh.in_magnet))
    b = source.assemble(magnet_basis)
    corner = int(np.argmax(mesh.points[0] + mesh.points[1]))  # node at (r_far, z_far)
    pinned = basis.nodal_dofs[0, corner]
    free = np.setdiff1d(np.arange(basis.N), [pinned])
    # symmetric positive definite: symmetric fill-reducing ordering, no pivoting
    lu = splu(A[free][:, free].tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
              options={"SymmetricMode": True})
    V = np.zeros(basis.N)
    V[free] = lu.solve(b[free])
    return FieldSolution(mesh=mesh, V=V, M_z=M_z, R_m=R_m, H_m=H_m, mesh_time=0.0,
                         solve_time=time.perf_counter() - t0, _basis=basis)


def solve_fe(study: Study) -> FieldSolution:
    """Mesh and solve the field of the study's magnet (cached per process).

    Parameters
    ----------
    study : Study
        Uses ``study.magnet`` (R_m, H_m, M_z) and the mesh settings of ``study.magnetics``
        (h_magnet, growth_near, near, growth, far_r, far_z).

    Returns
    -------
    FieldSolution
        The solution in the magnet's frame (centre at the origin). Repeated calls with the same
        magnet and mesh settings return the same object without meshing or solving again.

    Raises
    ------
    StudyError
        If the mesh settings are inconsistent (``growth_near`` ≥ ``growth``, a far box that
        does not enclose the magnet and its near zone).
    """
    m, f = study.magnet, study.magnetics
    if f.growth_near >= f.growth:
        raise StudyError("magnetics.growth_near", f"must be smaller than magnetics.growth "
                                                  f"({f.growth:g}), got {f.growth_near:g}")
    check_field_mesh(study)  # the far box: the study's rule, also run by magtact study
    with _LOCK:  # gmsh is not thread-safe; one solve per magnet and mesh in a process
        return _solve_cached(m.R_m, m.H_m, m.M_z, f.h_magnet, f.growth_near, f.near, f.growth,
                             f.far_r, f.far_z)


_LOCK = threading.Lock()


@lru_cache(maxsize=8)
def _solve_cached(R_m, H_m, M_z, h_magnet, growth_near, near, growth, far_r, far_z):
    t0 = time.perf_counter()
    mesh = field_mesh(R_m, H_m, h_magnet=h_magnet, growth_near=growth_near, near=near,
                      growth=growth, far_r=far_r, far_z=far_z)
    mesh_time = time.perf_counter() - t0
    return replace(solve_field(mesh, R_m, H_m, M_z), mesh_time=mesh_time)
