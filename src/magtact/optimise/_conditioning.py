"""How well-posed the stable-shear bound is: the move of t_m and F_z,max under a small F_r change.

The stable shear bounds (t_m, θ_m) are where F_r is smallest (docs/method.md §7.1).
Where that minimum is flat, a change of F_r far below the metamodels' error moves t_m a long
way, and F_z,max, the largest F_z for t ≤ t_m, follows. This module measures it per height on a
dense (t, θ) grid: t_tol is the smallest t at which F_r comes within ``tol`` of its range of the
minimum; the relative drop of F_z,max from the box up to t_m to the box up to t_tol is the
change a ``tol`` change in F_r can make. G cancels from every ratio.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..metamodel import ModelSet
from ..sensitivity import Responses
from ..study import Study
from ._design import as_responses


@dataclass(frozen=True)
class ShearBoundConditioning:
    """Per height (arrays of shape (n,)).

    Attributes
    ----------
    H : heights [m]
    tol : the change of F_r, as a fraction of its range over the loading domain
    t_m, theta_m : grid location of the minimum of F_r
    t_tol, theta_tol : the smallest t where F_r ≤ min + tol · range, and its θ
    f_z_max_m, f_z_max_tol : largest F_z / G over [0, t_m] × [0, θ_m] and over
        [0, t_tol] × [0, θ_tol] [N/Pa]
    """

    H: np.ndarray
    tol: float
    t_m: np.ndarray
    theta_m: np.ndarray
    t_tol: np.ndarray
    theta_tol: np.ndarray
    f_z_max_m: np.ndarray
    f_z_max_tol: np.ndarray

    @property
    def dt(self) -> np.ndarray:
        """t_m − t_tol [-]."""
        return self.t_m - self.t_tol

    @property
    def dF_z_rel(self) -> np.ndarray:
        """(F_z,max(t_m) − F_z,max(t_tol)) / F_z,max(t_m) [-] (NaN where F_z,max(t_m) = 0)."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(self.f_z_max_m != 0,
                            (self.f_z_max_m - self.f_z_max_tol) / self.f_z_max_m, np.nan)


def shear_bound_conditioning(models: Responses | ModelSet, study: Study, H, *,
                             tol: float = 0.01, n_t: int = 201, n_theta: int = 41
                             ) -> ShearBoundConditioning:
    """Measure the conditioning of the stable-shear bound at heights ``H`` [m] (see the module).

    Raises
    ------
    ValueError
        If ``tol`` is not in (0, 1).
    """
    if not 0 < tol < 1:
        raise ValueError(f"tol must be in (0, 1), got {tol}")
    H = np.atleast_1d(np.asarray(H, dtype=float))
    R = as_responses(models).at(H[:, None, None])
    tt = np.linspace(0.0, 1.0, n_t)
    th = np.linspace(0.0, study.loading.theta_max, n_theta)
    T, TH = np.meshgrid(tt, th, indexing="ij")
    fr = np.broadcast_to(R.value("f_r", T, TH), (H.size, n_t, n_theta))
    fz = np.broadcast_to(R.value("f_z", T, TH), (H.size, n_t, n_theta))
    flat = fr.reshape(H.size, -1)
    k = np.argmin(flat, axis=1)
    lo, hi = flat.min(axis=1), flat.max(axis=1)
    near = fr <= (lo + tol * (hi - lo))[:, None, None]
    first_t = np.argmax(near.any(axis=2), axis=1)  # smallest t index with a near point
    rows = np.arange(H.size)
    j_tol = np.argmax(np.where(near[rows, first_t], -fr[rows, first_t], -np.inf), axis=1)
    i_m, j_m = np.unravel_index(k, (n_t, n_theta))

    def box_max(i, j):
        mask = (np.arange(n_t)[None, :, None] <= i[:, None, None]) \
            & (np.arange(n_theta)[None, None, :] <= j[:, None, None])
        return np.max(np.where(mask, fz, -np.inf).reshape(H.size, -1), axis=1)

    return ShearBoundConditioning(H, tol, tt[i_m], th[j_m], tt[first_t], th[j_tol],
                                  box_max(i_m, j_m), box_max(first_t, j_tol))
