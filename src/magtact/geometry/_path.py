"""Sensor geometry in the plane of shear and the loading path (docs/method.md §1).

Coordinates: the Hall sensing point is the origin, on the axis at the base plane z = 0; z up;
shear along +x (which plays the role of r in the plane of shear). All lengths in metres.
"""

from __future__ import annotations

import numpy as np

from ..study import Study


def dz0(study: Study, H):
    """Unloaded magnet–sensor distance Δz0 = H + H_g − H_m [m].

    With ``placement = "covered"`` (default) this is the height of the magnet's centre above the
    Hall point; with ``"flush"`` the height of the magnet's lower face.
    """
    return np.asarray(H) + study.body.H_g - study.magnet.H_m


def magnet_span(study: Study, H) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper face heights (z_low, z_high) [m] of the unloaded magnet."""
    d0 = dz0(study, H)
    h = study.magnet.H_m
    if study.magnet.placement == "covered":
        return d0 - h / 2, d0 + h / 2
    return d0, d0 + h


def loading_path(study: Study, t, theta, H) -> tuple[np.ndarray, np.ndarray]:
    """Magnet displacement (u_r, u_z) [m] for load t ∈ [0, 1], shear angle θ [rad], height H [m].

    The loading path of docs/method.md §1 in general form:
    u_z = t (Δz_sat + H_m − H − H_g) = t (Δz_sat − Δz0), u_r = −u_z tan θ. u_z ≤ 0 (the magnet
    moves down), u_r ≥ 0 (along +x). Broadcasts.
    """
    t = np.asarray(t, dtype=float)
    u_z = t * (study.loading.dz_sat + study.magnet.H_m - np.asarray(H) - study.body.H_g)
    return shear_displacement(u_z, theta), u_z


def shear_displacement(u_z, theta):
    """u_r = −u_z tan θ [m]: the shear displacement that goes with u_z on a path of angle θ."""
    return -np.asarray(u_z, dtype=float) * np.tan(np.asarray(theta, dtype=float))


def hall_from_magnet_centre(study: Study, u_r, u_z, H, standoff=None
                            ) -> tuple[np.ndarray, np.ndarray]:
    """Position (x, z) [m] of the Hall point relative to the displaced magnet's centre.

    x is along the shear direction: the magnet has moved by +u_r, so the Hall point sits at
    x = −u_r; z = −(height of the magnet centre above the Hall point). The chip's standoff
    below the body (``standoff`` [m], default the study's ``[hall] standoff_mm``: a design's
    own chip position is given, never put into the study) adds to that height; the loading
    path, defined by the body's compression, does not change with it.
    """
    z_low, z_high = magnet_span(study, H)
    standoff = study.hall.standoff if standoff is None else standoff
    centre = 0.5 * (z_low + z_high) + np.asarray(u_z) + standoff
    return -np.asarray(u_r), -centre
