"""Field at the Hall sensing point along the loading path (docs/method.md §1, §2)."""

from __future__ import annotations

import numpy as np

from .._errors import MagtactError
from ..geometry import hall_from_magnet_centre, loading_path
from ..study import Study, StudyError, from_si
from ._exact import cylinder_field
from ._fe import solve_fe

SOLVERS = ("fe", "exact")


def hall_field(study: Study, t, theta, H, solver: str | None = None, *,
               M_z: float | None = None, standoff: float | None = None
               ) -> tuple[np.ndarray, np.ndarray]:
    """Flux density (B_r, B_z) [T] at the Hall point for load t, shear angle θ and height H.

    Parameters
    ----------
    study : Study
        Magnet, placement, loading path and field solver settings.
    t : array_like
        Non-dimensional load in [0, 1].
    theta : array_like
        Shear angle [rad].
    H : array_like
        Base height of the body [m]. ``t``, ``theta`` and ``H`` broadcast together.
    solver : {"fe", "exact"}, optional
        ``"fe"``: the axisymmetric finite-element solution (:func:`solve_fe`, solved once per
        process and magnet); ``"exact"``: the closed form :func:`cylinder_field`. Default:
        ``study.magnetics.solver``.
    M_z, standoff : float, optional
        A design's magnetisation [A/m] (the FE field, solved for the study's magnet, scales
        with it) and chip standoff [m]; default the study's.

    Returns
    -------
    B_r, B_z : numpy.ndarray
        Each of the broadcast shape of (t, theta, H) [T].

    Raises
    ------
    ValueError
        For an unknown solver.
    StudyError
        With the FE solver, if a Hall point lies farther from the magnet than the finely meshed
        zone (``magnetics.near``).

    Notes
    -----
    Sign conventions. x is the shear direction, z is up; the magnet moves by
    u = (u_r, u_z) (:func:`magtact.geometry.loading_path`, u_r ≥ 0 along +x, u_z ≤ 0), so the
    Hall point sits at (x, z) = (−u_r, −Δ_z) relative to the displaced magnet's centre, with Δ_z
    the height of the centre above the Hall point (covered or flush placement,
    :func:`magtact.geometry.hall_from_magnet_centre`). In the magnet's cylindrical frame
    ρ = |x| and the field is (B_ρ, B_z). ``B_r`` is the component along +x:

    .. math::

        B_r = B_x = \\operatorname{sign}(x)\\, B_\\rho(|x|, z) = -B_\\rho(u_r, z)
        \\quad (u_r > 0),

    Below a +z magnetised magnet the field points up and towards the axis (B_ρ < 0), and the
    Hall point of a magnet sheared along +x is on its −x side, so B_r > 0 there; B_r = 0 for
    θ = 0.
    ``B_z`` is the upward component; below an axially magnetised (+z) magnet it is positive.
    """
    u_r, u_z = loading_path(study, t, theta, H)
    x, z = hall_from_magnet_centre(study, u_r, u_z, H, standoff)
    if (study.magnetics.solver if solver is None else solver) == "fe":
        m = study.magnet
        gap = np.hypot(np.maximum(np.abs(x) - m.R_m, 0.0), np.maximum(np.abs(z) - m.H_m / 2, 0.0))
        if np.size(gap) and gap.max() > study.magnetics.near:
            raise StudyError("magnetics.near_mm",
                             f"the Hall point reaches {from_si(gap.max(), 'mm'):.4g} mm from the "
                             f"magnet, beyond the finely meshed zone near_mm = "
                             f"{from_si(study.magnetics.near, 'mm'):g}; increase near_mm")
    return magnet_field(study, x, z, solver, M_z)


def magnet_field(study: Study, x, z, solver: str | None = None, M_z: float | None = None
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Flux density (B_x, B_z) [T] in the plane y = 0 of the magnet's frame.

    Parameters
    ----------
    study : Study
        Magnet and field solver settings.
    x, z : array_like
        Broadcastable coordinates [m] relative to the magnet's centre (x along the shear
        direction, z along the magnet's axis, up).
    solver : {"fe", "exact"}, optional
        As in :func:`hall_field`.
    M_z : float, optional
        The magnet's magnetisation [A/m] instead of the study's.

    Returns
    -------
    B_x, B_z : numpy.ndarray
        Each of the broadcast shape; B_x = sign(x) B_ρ(|x|, z) by axial symmetry.
    """
    solver = study.magnetics.solver if solver is None else solver
    if solver not in SOLVERS:
        raise MagtactError(f"field solver must be one of {SOLVERS}, got {solver!r}")
    x, z = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(z, dtype=float))
    rho = np.abs(x)
    m = study.magnet
    if solver == "exact":
        B_rho, B_z = cylinder_field(rho, z, m.R_m, m.H_m, m.M_z if M_z is None else M_z)
    else:
        B_rho, B_z = solve_fe(study).B(rho, z)
        if M_z is not None:  # the field is linear in the magnetisation
            B_rho, B_z = B_rho * (M_z / m.M_z), B_z * (M_z / m.M_z)
    return np.sign(x) * B_rho, B_z
