"""FElupe model of the half sensor body: nearly incompressible neo-Hookean solid, rigid magnet,
two rigid plates with Coulomb friction, adaptive load stepping (SPEC section 3)."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import felupe as fem
import numpy as np

from ..geometry import BodyMesh

#: Linear solvers of the Newton steps (name → function solving ``A x = b``).
SOLVERS = ("pardiso", "superlu")


def _linear_solver(name: str, threads: int) -> Callable:
    if name == "pardiso":
        import pypardiso
        from pypardiso.scipy_aliases import pypardiso_solver

        lib = pypardiso_solver.libmkl
        if threads > 0 and hasattr(lib, "MKL_Set_Num_Threads"):
            lib.MKL_Set_Num_Threads(int(threads))
        return pypardiso.spsolve
    if name == "superlu":
        from scipy.sparse.linalg import spsolve

        return spsolve
    raise ValueError(f"unknown linear solver {name!r}; choose one of {SOLVERS}")


class StepFailure(Exception):
    """A load step could not be converged with the smallest allowed step size."""

    def __init__(self, t: float, t_converged: float, reason: str):
        super().__init__(reason)
        self.t, self.t_converged, self.reason = t, t_converged, reason


@dataclass(frozen=True)
class Stepping:
    """Adaptive load stepping controls (sizes in units of the load t ∈ [0, 1])."""

    dt_initial: float = 0.05
    dt_min: float = 1e-4
    dt_max: float = 0.1
    max_iter: int = 12
    easy_iter: int = 5
    growth: float = 1.5
    cutback: float = 0.5
    tol: float = 1e-8


class _Timed:
    """Wrap a callable and accumulate its wall time into ``timings[key]``."""

    def __init__(self, fun: Callable, timings: dict, key: str):
        self.fun, self.timings, self.key = fun, timings, key

    def __call__(self, *args, **kwargs):
        t0 = time.perf_counter()
        try:
            return self.fun(*args, **kwargs)
        finally:
            self.timings[self.key] += time.perf_counter() - t0


class HalfBodyModel:
    """The half body y ≥ 0 between two rigid plates, loaded through its magnet.

    Boundary conditions: base z = 0 fixed (``base="clamped"``) or held only in z and, on the
    line x = 0, in x (``base="sliding"``: a frictionless support); symmetry u_y = 0 on y = 0;
    cavity nodes move with the rigid magnet by (u_r, 0, u_z); the upper plate (initially at the
    top face) moves by the same (u_r, 0, u_z); the lower plate is the plane z = 0. Both plates
    act on every node of the free outer surface by penalty contact (FElupe ``ContactRigidPlane``)
    with Coulomb friction μ_f; the penalty multipliers are relative to the solid's stiffness,
    so every force is proportional to G.

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

    Notes
    -----
    Material: the isochoric neo-Hookean energy W = G/2 (J^(-2/3) I_1 − 3) with a volumetric
    penalty K/2 (J̄ − 1)², K = bulk_ratio · G, in FElupe's ``SolidBodyNearlyIncompressible``
    (Q1/P0 hexahedra with the pressure and the volume ratio condensed per cell).
    """

    def __init__(self, bmesh: BodyMesh, G: float, bulk_ratio: float, mu_f: float, *,
                 base: str = "clamped", penalty: float = 5.0, elastic_slip: float = 2e-5,
                 solver: str = "pardiso", threads: int = 1):
        if base not in ("clamped", "sliding"):
            raise ValueError(f"base must be 'clamped' or 'sliding', got {base!r}")
        self.bmesh = bmesh
        self.G = float(G)
        self.timings = {"solid": 0.0, "contact": 0.0, "linear_solve": 0.0}
        self._solve = _Timed(_linear_solver(solver, threads), self.timings, "linear_solve")

        n = bmesh.n_points
        mesh = fem.Mesh(bmesh.points.copy(), bmesh.cells.copy(), "hexahedron")
        mesh.update(points=np.vstack([mesh.points, [[0.0, 0.0, 0.0], [0.0, 0.0, bmesh.z_top]]]))
        self.lower, self.upper = n, n + 1
        region = fem.RegionHexahedron(mesh)
        self.field = fem.FieldContainer([fem.Field(region, dim=3)])
        self.solid = fem.SolidBodyNearlyIncompressible(
            fem.NeoHooke(mu=self.G), self.field, bulk=bulk_ratio * self.G)
        kw = {"friction": mu_f, "multiplier": penalty, "items": [self.solid]}
        if mu_f > 0:
            kw["elastic_slip"] = elastic_slip
        self.contacts = [
            fem.ContactRigidPlane(self.field, bmesh.surface, self.lower, [0, 0, 1.0], **kw),
            fem.ContactRigidPlane(self.field, bmesh.surface, self.upper, [0, 0, -1.0], **kw),
        ]
        for item, key in [(self.solid, "solid")] + [(c, "contact") for c in self.contacts]:
            item.assemble.vector = _Timed(item.assemble.vector, self.timings, key)
            item.assemble.matrix = _Timed(item.assemble.matrix, self.timings, key)
        self.items = [self.solid, *self.contacts]

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
        #: Newton iterations of all steps, including those of failed steps
        self.iterations = 0
        #: (t_start, t_end, Newton iterations or -1 for a failed step) of every step tried
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
    def _newton(self, u_r: float, u_z: float, stepping: Stepping) -> int:
        """One load step to the magnet displacement (u_r, u_z) [m]; returns the iterations.

        Every iteration, converged or not, is added to ``self.iterations``."""
        ext = np.zeros(self.n_dofs)
        ext[self._moving_x] = u_r
        ext[self._moving_z] = u_z
        check = _Check()
        try:
            res = fem.newtonraphson(
                items=self.items, x0=self.field, dof1=self.dof1, dof0=self.dof0,
                ext0=ext[self.dof0], solver=self._solve, maxiter=stepping.max_iter,
                tol=stepping.tol, check=check, verbose=0,
            )
        finally:
            self.iterations += check.count
        self._fun = np.asarray(res.fun).copy()
        return int(res.iterations)

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
            steps), ``cutbacks``, ``steps`` (converged steps): counts.

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
                except (fem.tools.NewtonConvergenceError, ValueError, FloatingPointError,
                        np.linalg.LinAlgError, RuntimeError) as exc:
                    self._restore(chk)
                    self.log.append((t, t_try, -1))
                    cutbacks += 1
                    dt = (t_try - t) * st.cutback
                    if dt < st.dt_min:
                        raise StepFailure(t_try, t, str(exc).strip() or type(exc).__name__) from exc
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
        return {**out, "iterations": self.iterations, "cutbacks": cutbacks, "steps": steps}


class _Check:
    """FElupe's convergence check that gives up early: on a non-finite residual, and from the
    fourth iteration on when the residual norm has not fallen below half its best value (the
    contact active set cycles; a smaller step is cheaper than more iterations)."""

    def __init__(self):
        self.fnorms: list[float] = []
        self.count = 0

    def __call__(self, dx, x, f, xtol, ftol, dof1=None, dof0=None, items=None, eps=1e-3):
        xnorm, fnorm, success = fem.tools._newton.check(dx, x, f, xtol, ftol, dof1, dof0,
                                                        items, eps)
        if items is None:  # a trial evaluation of a plugin, not an iteration
            return xnorm, fnorm, success
        self.count += 1
        if not (np.isfinite(fnorm) and np.isfinite(xnorm)):
            raise fem.tools.NewtonConvergenceError("non-finite residual (inverted cells?)")
        if not success and len(self.fnorms) >= 3 and fnorm > 0.5 * min(self.fnorms):
            raise fem.tools.NewtonConvergenceError(
                f"no progress of the Newton iterations (residual {fnorm:.2e})")
        self.fnorms.append(fnorm)
        return xnorm, fnorm, success
