"""Repeatability and model error of repeat indentation tests (docs/method.md §8)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._errors import MagtactError
from .._files import significant, write_csv
from .._floor import RELATIVE_FLOOR, above_floor
from .._records import entry, to_json
from ..geometry import shear_displacement
from ..study import mm
from ._filter import FilterSettings, bandpass
from ._io import RESPONSES, UNITS, DataError, Experiment
from ._model import PathModel

#: Default number of points of the common displacement grid.
N_GRID = 201
#: Most points of the common grid (a bound on the work of one validation).
MAX_GRID = 100_001
#: Smallest displacement range [m] the tests (and the model) must share: below it the
#: statistics compare sensor noise, not curves.
MIN_SHARED_RANGE = 1e-6
#: ... and at least this fraction of the shortest test's own displacement range.
MIN_SHARED_FRACTION = 0.05
#: Default guard: a ratio is evaluated only where |denominator| > FLOOR × max |denominator|.
FLOOR = RELATIVE_FLOOR


@dataclass(frozen=True)
class ResponseStats:
    """Statistics of one response ψ on the common grid (n points, N tests).

    Attributes
    ----------
    name, unit : str
        Response (``"B_r"``, ...) and its SI unit.
    curves : numpy.ndarray, shape (N, n)
        Filtered tests resampled on the grid.
    mean, std, model : numpy.ndarray, shape (n,)
        ψ_μ, ψ_σ (1/N form) and the model's ψ.
    c_v, eps : float
        Coefficient of variation and model error [%]; NaN if every point was excluded.
    c_v_at, eps_at : float
        u_z [m] where the maximum is reached (NaN if none).
    cv_excluded, eps_excluded : numpy.ndarray of bool, shape (n,)
        Grid points left out of c_v (|ψ_μ| too small) and of ε (|ψ_model| too small).
    """

    name: str
    unit: str
    curves: np.ndarray
    mean: np.ndarray
    std: np.ndarray
    model: np.ndarray
    c_v: float
    c_v_at: float
    eps: float
    eps_at: float
    cv_excluded: np.ndarray
    eps_excluded: np.ndarray


@dataclass(frozen=True)
class ValidationRow:
    """A row of a validation's table (CSV and JSON): the response, its c_v and ε [%] with the
    u_z [m] where each is largest, the u_z ranges left out of each, in words (mm), and the
    model. A c_v or ε that is not a number is null in the JSON file."""

    data: str = entry(kind=str)
    response: str = entry(kind=str)
    unit: str = entry(kind=str)
    n_tests: int = entry(kind=int)
    c_v: float = entry("c_v_percent", null_nan=True)
    c_v_at_u_z: float = entry(unit="mm", null_nan=True)
    eps: float = entry("eps_percent", null_nan=True)
    eps_at_u_z: float = entry(unit="mm", null_nan=True)
    c_v_excluded: str = entry(kind=str)
    eps_excluded: str = entry(kind=str)
    model: str = entry(kind=str)


@dataclass(frozen=True)
class Validation:
    """Result of :func:`validate`.

    Attributes
    ----------
    u_z, u_r : numpy.ndarray, shape (n,)
        Common displacement grid [m] (u_z from 0 downwards) and the shear displacement on it
        (the mean measured u_r, or −u_z tan θ when the files give none).
    stats : dict[str, ResponseStats]
        Per response ``B_r, B_z, F_r, F_z``.
    theta : float
        Shear angle [rad].
    n_tests : int
        Number N of tests (sensors × repeats).
    sensors : tuple[str, ...]
        Sensor labels.
    synthetic : bool
        True for generated example data; every table and figure says so.
    model_label : str
        Name of the model.
    filter : FilterSettings
        Filter used.
    floor : float
        Relative guard on the denominators.
    notes : tuple[str, ...]
        Things the user should know (grid clipped to the model's range, ...).
    """

    u_z: np.ndarray
    u_r: np.ndarray
    stats: dict[str, ResponseStats]
    theta: float
    n_tests: int
    sensors: tuple[str, ...]
    synthetic: bool
    model_label: str
    filter: FilterSettings
    floor: float
    notes: tuple[str, ...] = ()

    @property
    def title(self) -> str:
        """Title for tables and figures; says 'SYNTHETIC' for generated data."""
        kind = "SYNTHETIC example data" if self.synthetic else "experiment"
        return (f"Validation ({kind}): {len(self.sensors)} sensors, {self.n_tests} tests, "
                f"θ = {self.theta:.3f} rad")

    def excluded(self, response: str, measure: str = "eps") -> str:
        """The u_z ranges [mm] of ``response`` left out of ``measure`` (``"eps"`` or
        ``"c_v"``), in words."""
        s = self.stats[response]
        return _ranges_text(self.u_z, s.eps_excluded if measure == "eps" else s.cv_excluded)

    def row_records(self) -> list[ValidationRow]:
        """The table of c_v and ε: one record per response."""
        data = "synthetic" if self.synthetic else "experiment"
        return [ValidationRow(data, r, s.unit, self.n_tests, s.c_v, s.c_v_at, s.eps, s.eps_at,
                              self.excluded(r, "c_v"), self.excluded(r, "eps"),
                              self.model_label)
                for r, s in ((r, self.stats[r]) for r in RESPONSES)]

    def rows(self) -> list[dict[str, object]]:
        """The table of c_v and ε: one dict per response, user units (mm, %)."""
        return [to_json(r, null_nan=False) for r in self.row_records()]

    def write_csv(self, path: str | Path) -> Path:
        """Write :meth:`rows` as CSV; return the path."""
        rows = self.rows()
        return write_csv(path, list(rows[0]), [list(r.values()) for r in rows],
                         cell=significant(6))


def validate(experiment: Experiment, model: PathModel, *,
             filter: FilterSettings | None = None, n_grid: int = N_GRID,
             floor: float = FLOOR) -> Validation:
    """Filter, resample and compare repeat tests with a model (docs/method.md §8).

    Parameters
    ----------
    experiment : Experiment
        N ≥ 2 tests at one shear angle.
    model : PathModel
        Model of the same design at the same shear angle.
    filter : FilterSettings, optional
        Band-pass cut-offs [1/m of u_z]; default :class:`FilterSettings()` (low-pass at
        2 cycles/mm). ``FilterSettings(f_hi=None)`` disables filtering.
    n_grid : int
        Points of the common grid, spread uniformly over the u_z range that every test covers
        (and the model, if it declares a range).
    floor : float
        Guard: a ratio is evaluated only where its denominator exceeds ``floor`` times the
        largest |denominator| of that response on the grid.

    Returns
    -------
    Validation

    Notes
    -----
    Each test is first put on a uniform grid of its own range and sample count (linear
    interpolation), filtered there (:func:`bandpass`), then interpolated linearly on the common
    grid φ. Per response ψ with N tests:

    .. math::

        ψ_μ = \\frac1N \\sum_i ψ_i, \\quad ψ_σ = \\sqrt{\\frac1N \\sum_i (ψ_i − ψ_μ)^2},
        \\quad c_v = \\max_φ |ψ_σ / ψ_μ| · 100 \\%, \\quad
        ε = \\max_φ |(ψ_μ − ψ_{model}) / ψ_{model}| · 100 \\%.
    """
    filter = FilterSettings() if filter is None else filter
    if not 2 <= n_grid <= MAX_GRID:
        raise MagtactError(f"n_grid must be between 2 and {MAX_GRID:,}, got {n_grid}")
    if not 0.0 <= floor < 1.0:
        raise MagtactError(f"floor must be in [0, 1), got {floor}")
    if abs(model.theta - experiment.theta) > 1e-3:
        raise MagtactError(f"the model is at theta = {model.theta:.4g} rad but the data at "
                         f"{experiment.theta:.4g} rad: simulate the data's shear angle")
    curves = experiment.curves
    lo = max(float(c.u_z.min()) for c in curves)
    hi = min(float(c.u_z.max()) for c in curves)
    notes = []
    if model.u_z_range is not None:
        m_lo, m_hi = model.u_z_range
        if lo < m_lo - 1e-12 or hi > m_hi + 1e-12:
            notes.append(f"grid clipped to the model's range u_z in [{mm(m_lo):.4g}, "
                         f"{mm(m_hi):.4g}] mm (data common range [{mm(lo):.4g}, "
                         f"{mm(hi):.4g}] mm)")
        lo, hi = max(lo, m_lo), min(hi, m_hi)
    shortest = min(float(np.ptp(c.u_z)) for c in curves)
    least = max(MIN_SHARED_RANGE, MIN_SHARED_FRACTION * shortest)
    if not hi - lo >= least:
        share = (f"share only {mm(hi - lo):.3g} mm of displacement (u_z), less than "
                 f"{mm(least):.3g} mm (the larger of {mm(MIN_SHARED_RANGE) * 1e3:g} µm and "
                 f"{100 * MIN_SHARED_FRACTION:g} % of the shortest test's range)"
                 if hi > lo else "share no displacement range (u_z)")
        raise DataError(f"the tests {share}: "
                        + "; ".join(f"{c.source}, line {c.line}: [{mm(c.u_z.min()):.4g}, "
                                    f"{mm(c.u_z.max()):.4g}] mm" for c in curves)
                        + ("; the model's range: "
                           f"[{mm(model.u_z_range[0]):.4g}, {mm(model.u_z_range[1]):.4g}] mm"
                           if model.u_z_range is not None else ""))
    grid = np.linspace(hi, lo, n_grid)  # loading order: from the top downwards

    resampled = {r: np.empty((len(curves), n_grid)) for r in (*RESPONSES, "u_r")}
    for i, c in enumerate(curves):
        order = np.argsort(c.u_z)
        u = c.u_z[order]
        own = np.linspace(u[0], u[-1], u.size)
        series = dict(c.values)
        if c.u_r is not None:
            series["u_r"] = c.u_r
        for name, y in series.items():
            y_own = bandpass(np.interp(own, u, y[order]), own[1] - own[0], filter)
            resampled[name][i] = np.interp(grid, own, y_own)
    if all(c.u_r is not None for c in curves):
        u_r = resampled["u_r"].mean(axis=0)
    else:
        u_r = shear_displacement(grid, experiment.theta)
        if any(c.u_r is not None for c in curves):
            notes.append("u_r from the loading path (−u_z tan θ): not every file has u_r")

    predicted = model(grid)
    stats = {}
    for r in RESPONSES:
        ys = resampled[r]
        mean = ys.mean(axis=0)
        std = np.sqrt(((ys - mean) ** 2).mean(axis=0))
        c_v, c_v_at, cv_out = _guarded_max(std, mean, grid, floor)
        eps, eps_at, eps_out = _guarded_max(mean - predicted[r], predicted[r], grid, floor)
        stats[r] = ResponseStats(name=r, unit=UNITS[r], curves=ys, mean=mean, std=std,
                                 model=predicted[r], c_v=c_v, c_v_at=c_v_at, eps=eps,
                                 eps_at=eps_at, cv_excluded=cv_out, eps_excluded=eps_out)
    return Validation(u_z=grid, u_r=u_r, stats=stats, theta=experiment.theta,
                      n_tests=len(curves), sensors=experiment.sensors,
                      synthetic=experiment.synthetic, model_label=model.label, filter=filter,
                      floor=floor, notes=tuple(notes))


def _guarded_max(num, den, grid, floor):
    """max |num/den| × 100 over points where |den| > floor·max|den| → (value, where, excluded)."""
    excluded = ~above_floor(den, floor=floor)
    if excluded.all():
        return float("nan"), float("nan"), excluded
    ratio = np.where(excluded, -np.inf, np.abs(num) / np.where(excluded, 1.0, np.abs(den)))
    k = int(np.argmax(ratio))
    return float(ratio[k] * 100.0), float(grid[k]), excluded


def excluded_ranges(u_z: np.ndarray, mask: np.ndarray) -> list[tuple[float, float]]:
    """Contiguous runs of excluded grid points as (first u_z, last u_z) [m] pairs."""
    out = []
    k = 0
    while k < mask.size:
        if mask[k]:
            j = k
            while j + 1 < mask.size and mask[j + 1]:
                j += 1
            out.append((float(u_z[k]), float(u_z[j])))
            k = j + 1
        else:
            k += 1
    return out


def _ranges_text(u_z: np.ndarray, mask: np.ndarray) -> str:
    if not mask.any():
        return "none"
    if mask.all():
        return "all points (denominator vanishes)"
    parts = [f"{mm(a):.3g}..{mm(b):.3g} mm" for a, b in excluded_ranges(u_z, mask)]
    return f"{int(mask.sum())} pts, u_z " + "; ".join(parts)
