"""Analytic stand-in DOE data sets for the metamodel and sensitivity tests (no tests here).

B is the field of a point dipole at the magnet's centre (exact, smooth away from it); f is a
smooth function of the displacement with the symmetries of the real responses (f_r odd in u_r,
f_r = f_z = 0 unloaded).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from magtact.geometry import hall_from_magnet_centre, loading_path

K_DIPOLE = 1e-12  # μ0 m / 4π [T·m³]
AREA = np.pi * 6e-3**2


def dipole(x, z):
    r2 = x**2 + z**2
    return K_DIPOLE * 3 * x * z / r2**2.5, K_DIPOLE * (3 * z**2 - r2) / r2**2.5


def forces(u_r, u_z, H):
    e, s = -u_z / H, u_r / H
    f_z = AREA * e * (1 + 1.5 * e) * (1 + 0.2 * s**2)
    f_r = -AREA * s * (1 - 2.0 * e**2) * 0.8
    return f_r, f_z


def synthetic_doe(study, n_t: int = 11) -> xr.Dataset:
    """A DOE-layout data set over the study's (θ, H, G) levels with ``n_t`` levels of t."""
    t = np.linspace(0.0, 1.0, n_t)
    th, H, G = study.theta_levels, study.H_levels, study.G_levels
    T, TH, HH = np.meshgrid(t, th, H, indexing="ij")
    ur, uz = loading_path(study, T, TH, HH)
    x, z = hall_from_magnet_centre(study, ur, uz, HH)
    br, bz = dipole(x, z)
    fr, fz = forces(ur, uz, HH)
    d3, d4 = ("t", "theta", "H"), ("t", "theta", "H", "G")
    return xr.Dataset(
        {"u_r": (d3, ur, {"units": "m"}), "u_z": (d3, uz, {"units": "m"}),
         "B_r": (d3, br, {"units": "T"}), "B_z": (d3, bz, {"units": "T"}),
         "F_r": (d4, fr[..., None] * G, {"units": "N"}),
         "F_z": (d4, fz[..., None] * G, {"units": "N"})},
        coords={"t": t, "theta": th, "H": H, "G": G},
        attrs={"synthetic": "analytic test stand-in", "study_toml": study.to_toml()})
