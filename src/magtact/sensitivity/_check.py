"""Γ from finite differences of the DOE data itself: an independent check of the models' Γ."""

from __future__ import annotations

from dataclasses import dataclass, make_dataclass

import numpy as np

from .._errors import MagtactError
from .._floor import RELATIVE_FLOOR, above_floor
from .._records import entry, to_json
from ..metamodel import ModelSet
from ._gamma import gamma, row_norms, through_displacement


def _mirrored(theta_levels: np.ndarray) -> bool:
    """Whether the θ grid starts at 0, where the data are continued to −θ by symmetry."""
    return bool(theta_levels[0] == 0)


def gamma_from_data(ds) -> tuple[np.ndarray, np.ndarray]:
    """γ_r, γ_z = Γ / G [N/(T·Pa)] on the DOE grid (t, θ, H) by finite differences.

    Derivatives along t and θ are second-order differences of the gridded data
    (``numpy.gradient``, one-sided of second order at the edges). When the first θ level is 0,
    the data are continued to −θ by the mirror symmetry of the sensor (F_r and B_r odd in θ,
    F_z and B_z even), so that the θ differences there are central too. With x = (t, θ),
    ∂F/∂B = (∂F/∂x)(∂B/∂x)⁻¹ (the map x → u cancels), which is singular at t = 0: values there
    are NaN.

    Returns
    -------
    gamma_r, gamma_z : numpy.ndarray
        Shape (n_t, n_theta, n_H).
    """
    t_, th_ = (np.asarray(ds[k].values, dtype=float) for k in ("t", "theta"))
    if len(t_) < 3 or len(th_) < 3:
        raise MagtactError("finite-difference Γ needs at least 3 levels of t and of theta")
    G = np.asarray(ds["G"].values, dtype=float)

    def arr(name):
        a = ds[name].transpose("t", "theta", "H", ...).values
        return (a / G).mean(axis=-1) if name.startswith("F") else np.asarray(a, dtype=float)

    ghost = int(_mirrored(th_))  # ghost level −θ_1, dropped after differencing
    th = np.concatenate([[-th_[1]], th_]) if ghost else th_

    def d(a, parity):
        if ghost:
            a = np.concatenate([parity * a[:, 1:2], a], axis=1)
        d_th = np.gradient(a, th, axis=1, edge_order=2)[:, ghost:]
        return np.stack([np.gradient(a[:, ghost:], t_, axis=0, edge_order=2), d_th], axis=-1)

    J = np.stack([d(arr("B_r"), -1), d(arr("B_z"), 1)], axis=-2)  # (..., B, x)
    dF = np.stack([d(arr("F_r"), -1), d(arr("F_z"), 1)], axis=-2)  # (..., F, x)
    S = np.full(J.shape, np.nan)
    ok = (np.abs(np.linalg.det(J)) > 0) & (t_ > 0)[:, None, None]
    S[ok] = through_displacement(dF[ok], J[ok])
    return row_norms(S)


def compare_with_data(models: ModelSet, ds, t_min: float = 0.2,
                      floor: float = RELATIVE_FLOOR) -> dict[str, dict[str, float]]:
    """Relative difference between the models' γ and the data's finite-difference γ.

    Points with t < ``t_min`` are excluded (the finite differences of the data are singular at
    t = 0). Returns, for ``gamma_r`` and ``gamma_z``, the median, 95th percentile and maximum of
    |γ_model − γ_data| / |γ_model| and the number of points, over all those points, (suffix
    ``_interior``) over the points where both differences are central (not on the last t level
    nor the last θ level, nor the first unless it is θ = 0): one-sided differences at the edges
    of a coarse grid are the least accurate part of the data's Γ, and (suffix
    ``_above_floor``) over the points where |γ_model| > ``floor`` · max |γ_model|, the
    convention of the metamodels' relative errors: where γ_r nearly vanishes (θ = 0 at large
    H), a relative difference says nothing. Also: ``within_5_percent_above_floor``, the
    fraction of those points where the relative difference is at most 5 %, and
    ``max_abs_over_max``, max |γ_model − γ_data| / max |γ_model| over all points with
    t ≥ ``t_min`` (the absolute difference on the scale of Γ, like the metamodels' error/range).
    """
    t_, th_, H_ = (np.asarray(ds[k].values, dtype=float) for k in ("t", "theta", "H"))
    T, TH, HH = np.meshgrid(t_, th_, H_, indexing="ij")
    data = gamma_from_data(ds)
    model = gamma(models, T, TH, HH, 1.0)
    keep = T >= t_min
    first = True if _mirrored(th_) else TH > th_.min()
    interior = keep & (T < t_.max()) & first & (TH < th_.max())
    out = {}
    for name, gm, gd in zip(("gamma_r", "gamma_z"), model, data, strict=True):
        diff = np.abs(gm - gd)
        scale = np.nanmax(np.abs(gm[keep]))
        rel_all = diff / np.abs(gm)
        above = keep & above_floor(gm, scale, floor)
        spreads = []
        for cls, mask in ((Spread, keep), (InteriorSpread, interior), (AboveFloorSpread, above)):
            rel = rel_all[mask]
            rel = rel[np.isfinite(rel)]
            spreads.append(cls(float(np.median(rel)), float(np.percentile(rel, 95)),
                               float(rel.max()), int(rel.size)) if rel.size else None)
        out[name] = to_json(GammaCheck(float(np.mean(rel_all[above] <= 0.05)),
                                       float(np.nanmax(diff[keep]) / scale), t_min, floor,
                                       all=spreads[0], interior=spreads[1],
                                       above_floor=spreads[2]))
    return out


def _spread_type(name: str, suffix: str, where: str) -> type:
    """The record of the relative difference |γ_model − γ_data| / |γ_model| over the points
    ``where``: its median, 95th percentile and largest value, and how many points; each key
    ends in ``suffix``."""
    return make_dataclass(name, [
        ("median", float, entry("median" + suffix)), ("p95", float, entry("p95" + suffix)),
        ("max", float, entry("max" + suffix)),
        ("n_points", int, entry("n_points" + suffix, kind=int))],
        frozen=True, namespace={"__doc__": f"The spread of the relative difference over {where}."})


Spread = _spread_type("Spread", "", "the points t ≥ t_min")
InteriorSpread = _spread_type("InteriorSpread", "_interior",
                              "the points where both differences of the data are central")
AboveFloorSpread = _spread_type("AboveFloorSpread", "_above_floor",
                                "the points where |γ_model| is above the floor")


def _spread(kind: type):
    """A spread of a :class:`GammaCheck`, left out where no point is left to it."""
    return entry(kind=kind, inline=True, optional=True, omit="none", default=None,
                 kw_only=True)


@dataclass(frozen=True)
class GammaCheck:
    """The check of one model's γ against the data's (:func:`compare_with_data`): the spreads
    of the relative difference, the fraction of the points above the floor within 5 %, the
    largest absolute difference over the largest |γ_model|, and the settings t_min, floor."""

    all: Spread | None = _spread(Spread)
    interior: InteriorSpread | None = _spread(InteriorSpread)
    above_floor: AboveFloorSpread | None = _spread(AboveFloorSpread)
    within_5_percent_above_floor: float = entry()
    max_abs_over_max: float = entry()
    t_min: float = entry()
    floor: float = entry()
