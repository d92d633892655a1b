"""One structural loading path of the sensor body (docs/method.md §3)."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .._errors import MagtactError
from ..geometry import body_mesh, loading_path
from ..study import Study
from ._model import HalfBodyModel, StepFailure, Stepping
from ._result import PathFailed, PathResult
from ._vtu import write_vtu


def stepping_of(study: Study) -> Stepping:
    """The load-stepping controls of a study's ``mechanics`` section."""
    m = study.mechanics
    return Stepping(dt_initial=m.dt_initial, dt_min=m.dt_min, dt_max=m.dt_max,
                    max_iter=m.max_newton, tol=m.newton_tol)


def build_model(study: Study, H: float, *, G: float | None = None,
                mesh: str | None = None) -> HalfBodyModel:
    """The FElupe half-body model of ``study`` for base height ``H`` [m] and shear modulus
    ``G`` [Pa] (default ``study.material.G_ref``), with the hexahedra of
    ``study.mechanics.element``."""
    m = study.mechanics
    order = 1 if m.element == "hex8" else 2
    return HalfBodyModel(
        body_mesh(study, H, mesh, order=order, serendipity=m.element == "hex20"),
        study.material.G_ref if G is None else G,
        study.material.bulk_ratio, study.loading.mu_f, penalty=m.contact_penalty,
        elastic_slip=m.elastic_slip, solver=m.solver, threads=m.threads, contact=m.contact,
    )


def simulate_path(study: Study, H: float, theta: float, *, G: float | None = None,
                  mesh: str | None = None, t=None, vtu: str | Path | None = None,
                  progress: Callable[[float], None] | None = None) -> PathResult:
    """Reaction forces of the sensor body along the loading path (θ, H) (docs/method.md §1, §3).

    The magnet and the upper plate move by (u_r, u_z) = ``loading_path(study, t, theta, H)``;
    the half body y ≥ 0 is solved by FElupe with adaptive load stepping and the forces are
    recorded at each level of ``t``.

    Parameters
    ----------
    study : Study
        Geometry, material, friction and solver settings.
    H : float
        Base height [m].
    theta : float
        Shear angle [rad], 0 ≤ θ.
    G : float or None
        Shear modulus [Pa] of the result; default ``study.material.G_ref``. With
        ``study.mechanics.scale_in_G`` the solve runs at G_ref and the forces are scaled by
        G / G_ref (exact for this model); otherwise the solve runs at G.
    mesh : {"coarse", "default", "accurate", "fine"} or None
        Mesh density; default ``study.mechanics.mesh``.
    t : (n_t,) array_like or None
        Increasing load levels in [0, 1]; default ``study.t_levels``.
    vtu : path or None
        If given, write the deformed half mesh at the last t there (VTU, with the displacement
        and its magnitude).
    progress : callable or None
        Called with each load level reached.

    Returns
    -------
    PathResult
        Forces F = (F_r, F_z) [N] of the full body: the force that the lower support (base
        z = 0 and the lower plate) exerts on the body, twice that of the half model. Sign
        convention (docs/method.md §3): F_z > 0 in compression; F_r < 0 when the magnet moves
        along +x, the support pulling the body back.

    Raises
    ------
    PathFailed
        If a step cannot be converged even with the smallest step size; it names t, θ, H and
        the last converged t, and holds the path over the levels reached (``partial``).

    Notes
    -----
    Model (:class:`~magtact.mechanics.HalfBodyModel`): hexahedral half body y ≥ 0
    (:func:`~magtact.geometry.body_mesh`), nearly incompressible neo-Hookean solid
    W = G/2 (J^(-2/3) I_1 − 3) + K/2 (J̄ − 1)², K = bulk_ratio · G (FElupe Q1/P0); base fixed;
    magnet cavity prescribed to (u_r, 0, u_z); u_y = 0 on y = 0; upper plate moving by
    (u_r, 0, u_z) and lower plate z = 0 in penalty contact with every free surface node,
    Coulomb friction μ_f with an elastic slip of ``mechanics.elastic_slip``.

    Forces: the half model carries the forces of y ≥ 0; by symmetry about y = 0 the full
    body's F_r, F_z are twice those, and its F_y vanishes. The reaction is read from the
    residual of the converged step at the base DOFs plus the lower plate's centre point.

    Solver: Newton's method with adaptive load steps (``mechanics.dt_*``), sparse direct
    solves with PARDISO (``mechanics.solver = "pardiso"``: about 10× faster than SciPy's
    SuperLU on the default mesh, see ``bench/results/mechanics_solver.json``).

    G-scaling: the material, the penalty multipliers (relative to the solid's stiffness) and
    the friction (elastic slip: tangential penalty ∝ normal force) are all proportional to G
    and the loading is displacement-controlled, so every force is proportional to G.
    """
    G_out = study.material.G_ref if G is None else float(G)
    if not G_out > 0:
        raise MagtactError(f"G must be positive, got {G_out}")
    if not H > 0:
        raise MagtactError(f"H must be positive, got {H}")
    if not 0 <= theta < np.pi / 2:
        raise MagtactError(f"theta must be in [0, pi/2), got {theta}")
    t = study.t_levels if t is None else np.atleast_1d(np.asarray(t, dtype=float))
    if t.ndim != 1 or len(t) == 0 or np.any(np.diff(t) <= 0) or t[0] < 0 or t[-1] > 1:
        raise MagtactError("t must be increasing values in [0, 1]")
    G_solve = study.material.G_ref if study.mechanics.scale_in_G else G_out

    t0 = time.perf_counter()
    model = build_model(study, H, G=G_solve, mesh=mesh)

    def path(tt: float) -> tuple[float, float]:
        u_r, u_z = loading_path(study, tt, theta, H)
        return float(u_r), float(u_z)

    def result_of(out: dict, levels: np.ndarray) -> PathResult:
        u_r, u_z = loading_path(study, levels, theta, H)
        result = PathResult(
            t=levels.copy(), u_r=np.broadcast_to(u_r, levels.shape).copy(),
            u_z=np.broadcast_to(u_z, levels.shape).copy(),
            F_r=2 * out["lower"][:, 0], F_z=2 * out["lower"][:, 2], G=G_solve, H=float(H),
            theta=float(theta), newton_iterations=out["iterations"], cutbacks=out["cutbacks"],
            steps=out["steps"], wall_time=time.perf_counter() - t0, n_dofs=model.n_dofs,
            n_cells=model.bmesh.n_cells, mesh=model.bmesh.name, timings=dict(model.timings),
            jacobians=out["jacobians"],
        )
        return result if G_solve == G_out else result.scaled(G_out)

    try:
        out = model.solve_path(path, t, stepping=stepping_of(study), on_level=progress)
    except StepFailure as exc:
        n = len(exc.reached["lower"]) if exc.reached is not None else 0
        partial = result_of(exc.reached, t[:n]) if n >= 2 else None
        raise PathFailed(exc.t, theta, H, exc.t_converged, exc.reason, partial) from exc
    if vtu is not None:
        write_vtu(vtu, model.bmesh, model.displacement)
    return result_of(out, t)
