"""The Hall chip's range as a constraint of the optimisation (docs/method.md §10).

The field along a path depends on the geometry only (H, t, θ), not on G, and so does the stable
region t ≤ t_m(H), θ ≤ θ_m(H): a chip that must stay within its range over the region the sensor
is used in restricts the heights, whatever the silicone.
"""

from __future__ import annotations

import numpy as np

from ..metamodel import ExactField
from ..study import Study, hall_chip

#: Grid over each height's stable region (fractions of t_m and θ_m) on which the field is read.
N_T, N_THETA = 41, 11


def chip_margin(study: Study, H, t_m, theta_m, geometry: dict | None = None) -> np.ndarray:
    """How far the exact field exceeds the chip's range over each height's stable region.

    .. math:: m(H) = \\max_{t \\le t_m,\\ θ \\le θ_m}
              \\max\\left(\\frac{|B_x|}{B_{x,\\mathrm{range}}},
              \\frac{|B_z|}{B_{z,\\mathrm{range}}}\\right) - 1

    Parameters
    ----------
    study : Study
        Geometry, loading path and the ``[hall]`` chip.
    H, t_m, theta_m : array_like, shape (n,)
        Heights [m] and their stable shear bounds (t_m, θ_m [rad]).
    geometry : dict of array_like, optional
        Each row's values [m] of the study's geometric design variables (shape (n,)); the
        field depends on the magnet's (R_m, H_m).

    Returns
    -------
    numpy.ndarray, shape (n,)
        ≤ 0 where the chip reads the whole stable region.
    """
    chip = hall_chip(study)
    H, t_m, theta_m = (np.atleast_1d(np.asarray(v, float)) for v in (H, t_m, theta_m))
    s = np.linspace(0.0, 1.0, N_T)[:, None, None]
    u = np.linspace(0.0, 1.0, N_THETA)[None, :, None]
    T, TH = s * t_m[None, None, :], u * theta_m[None, None, :]
    HH = np.broadcast_to(H[None, None, :], T.shape)
    B_r, B_z = ExactField(study, "B_r"), ExactField(study, "B_z")
    geo = {k: np.broadcast_to(np.asarray(v, float), H.shape)[None, None, :]
           for k, v in (geometry or {}).items() if k in B_r.geometry}
    ratio = np.maximum(np.abs(B_r.value(T, TH, HH, **geo)) / chip.range_x,
                       np.abs(B_z.value(T, TH, HH, **geo)) / chip.range_z)
    return ratio.max(axis=(0, 1)) - 1.0
