"""The Hall chip's setting as a design choice (docs/method.md §10).

For a design (H, G[, M_z]) the best setting of a chip with a setting table is the one with the
lowest force noise whose range holds the exact field over the loads the sensor must read (the
sensor problem: the stable region's points with G f_z ≤ ``[requirements] F_z_N``) or over
the design's stable region t ≤ t_m, θ ≤ θ_m (the publication's problem; or over its loads
t ≤ f t_m, f = ``[hall] read_fraction``), among the
settings the study allows (its fixed ``[hall]`` fields) whose sample rate reaches
``[requirements] rate_Hz``. The force noise of a setting is the root sum of squares of its worst
σ_Fr and σ_Fz over the stable region, σ_F = √diag(J Σ_B Jᵀ) with Σ_B = diag(σ_x², σ_z²) at the
upper end of the setting's noise interval (the end that holds under both assumptions). Ties go
to the lower end, then to the faster setting. Where no setting holds the field, those that
saturate at the largest load t compete, and the answer says so.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ..metamodel import ExactField, ModelSet
from ..parts import ChipSetting, SettingFigures, chip_part
from ..sensitivity import dF_dB
from ..study import Study, candidate_settings, setting_figures

#: Points per side of the grid over the stable box on which settings are compared.
N_GRID = 41


@dataclass(frozen=True)
class SettingChoice:
    """The chip setting chosen for one design.

    Attributes
    ----------
    figures : SettingFigures
        LSB, range, noise (interval) and rate of the setting.
    holds : bool
        Whether its range holds the exact field over the stable region (the part of it
        ``[hall] read_fraction`` asks for).
    B_max_x, B_max_z : float
        Largest |B_x|, |B_z| [T] over the stable region.
    sigma_r_worst, sigma_z_worst : float
        Worst σ_Fr, σ_Fz [N] on the comparison grid at the upper end of the noise.
    considered : int
        Settings compared (permitted, allowed by the study, fast enough, with a noise figure).
    """

    figures: SettingFigures
    holds: bool
    B_max_x: float
    B_max_z: float
    sigma_r_worst: float
    sigma_z_worst: float
    considered: int

    @property
    def setting(self) -> ChipSetting:
        return self.figures.setting


def setting_for(models: ModelSet, study: Study, design, *, M_z: float | None = None,
                standoff: float | None = None) -> SettingChoice | None:
    """The best chip setting for a design whose extrema are computed (``design``: a
    :class:`magtact.optimise.DesignResult`; see the module notes), or None for a chip without
    a setting table. ``M_z`` [A/m] and ``standoff`` [m]: the design's magnet and chip position
    (default: the design's M_z, else the study's; the study's standoff)."""
    if chip_part(study.hall.chip).table is None:
        return None
    H, G = design.H, design.G
    T, TH = np.meshgrid(np.linspace(0.0, design.t_m, N_GRID),
                        np.linspace(0.0, design.theta_m, N_GRID), indexing="ij")
    M_z = design.M_z if design.M_z is not None else M_z
    bx = np.abs(ExactField(study, "B_r", standoff, M_z).value(T, TH, H))  # (t, θ)
    bz = np.abs(ExactField(study, "B_z", standoff, M_z).value(T, TH, H))
    Bx_t, Bz_t = bx.max(axis=1), bz.max(axis=1)  # per load level
    Bx, Bz = float(Bx_t.max()), float(Bz_t.max())
    J = dF_dB(models, T, TH, H, G).reshape(-1, 2, 2) / design.field_scale
    A = J**2  # (points, force, field axis)
    figs = _fast_settings(study.hall, study.requirements.rate)
    if not figs:  # the loader refuses a rate no allowed setting reaches
        raise ValueError("no chip setting reaches the study's requirements.rate_Hz")
    sx = np.array([[f.sigma_x[0], f.sigma_x[1]] for f in figs])  # (settings, end)
    sz = np.array([[f.sigma_z[0], f.sigma_z[1]] for f in figs])
    # worst σ_F per setting, end and force: max over points of √(A_kx σx² + A_kz σz²)
    worst = np.full((len(figs), 2, 2), np.nan)  # (settings, end, force)
    for k in range(2):
        P = _maximal(A[:, k, :])
        if len(P):
            var = (P[None, None, :, 0] * sx[:, :, None] ** 2
                   + P[None, None, :, 1] * sz[:, :, None] ** 2)
            worst[..., k] = np.sqrt(var.max(axis=2))
    score = np.hypot(worst[..., 0], worst[..., 1])  # (settings, end)
    rx = np.array([f.range_x for f in figs])
    rz = np.array([f.range_z for f in figs])
    over = (Bx_t[None, :] > rx[:, None]) | (Bz_t[None, :] > rz[:, None])  # (settings, t)
    onset = np.where(over.any(axis=1), over.argmax(axis=1), N_GRID)  # first saturated level
    if study.optimise.problem == "sensor":  # hold the field over the required loads
        asked = G * models.f_z.value(T, TH, H) <= study.requirements.F_z  # (t, θ)
        sat = (bx[None] > rx[:, None, None]) | (bz[None] > rz[:, None, None])
        holds = ~(sat & asked[None]).any(axis=(1, 2))
    else:
        asked = T[:, 0] <= study.hall.read_fraction * design.t_m * (1 + 1e-12)  # levels
        holds = onset >= int(asked.sum())
    pool = holds if holds.any() else onset == onset.max()  # else those reading the farthest
    idx = np.flatnonzero(pool)
    rate = np.array([f.rate for f in figs])
    order = np.lexsort((-rate[idx], score[idx, 0], score[idx, 1]))
    k = int(idx[order[0]])
    return SettingChoice(figs[k], bool(holds[k]), Bx, Bz, float(worst[k, 1, 0]),
                         float(worst[k, 1, 1]), len(figs))


def _maximal(P: np.ndarray) -> np.ndarray:
    """The rows of ``P`` (n, 2) that no other row exceeds in both columns, NaN rows left out:
    a weighted sum with non-negative weights is largest at one of them, so the worst noise of
    every setting is found over these few points instead of the whole grid."""
    P = P[~np.isnan(P).any(axis=1)]
    P = P[np.lexsort((-P[:, 1], -P[:, 0]))]  # x falling, then y falling
    before = np.maximum.accumulate(np.concatenate(([-np.inf], P[:-1, 1])))
    return P[P[:, 1] > before]


@functools.lru_cache(maxsize=64)
def _fast_settings(hall, rate: float) -> tuple[SettingFigures, ...]:
    """The figures of the settings a study's ``[hall]`` allows that reach ``rate`` [Hz] and
    have a noise figure (they depend on the ``[hall]`` section alone: kept per section, since
    a grid of designs asks for them once per design)."""
    study = Study(hall=hall)
    return tuple(f for f in (setting_figures(study, s) for s in candidate_settings(study))
                 if f.rate >= rate and np.isfinite(f.sigma_x[1]) and np.isfinite(f.sigma_z[1]))
