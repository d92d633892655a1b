"""What the sensor reads along a load history when its silicone relaxes: a press and release at
a given rate (hysteresis), a press held (creep), and the error against the press rate
(docs/method.md §15).

The sensor measures the magnet's displacement (through the field) and turns it into force with
the elastic map F = G_cal f(u) calibrated at one modulus; the true force is the hereditary
integral F(t) = ∫ G(t − s) df(u(s)) of the quasi-linear viscoelastic body.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .._errors import MagtactError
from ._prony import Prony, held_force, hereditary_force

#: Moduli a sensor may be calibrated on: the long-time G_∞ (a slow calibration) or the
#: instantaneous G(0) (a fast one).
CALIBRATIONS = ("long", "short")
#: Samples of one press (loading or unloading half of a cycle).
N_PRESS = 400
#: The measured hysteresis of the original MagOne sensor, as a fraction of its range.
MEASURED_HYSTERESIS = 0.034
MEASURED_SOURCE = ("H. Wang et al., 'Design Methodology for Magnetic Field-Based Soft Tri-Axis "
                   "Tactile Sensors', Sensors 16(9), 1356 (2016): hysteresis 3.4 % of the "
                   "MagOne's range; the press rate of that test is not in the stored excerpts "
                   "of the paper")


def calibration_modulus(prony: Prony, calibrated_on: str) -> float:
    """G_cal [Pa]: G_∞ for ``"long"``, G(0) for ``"short"``."""
    if calibrated_on not in CALIBRATIONS:
        raise MagtactError(f"calibrated_on must be one of {', '.join(CALIBRATIONS)}, got "
                           f"{calibrated_on!r}")
    return prony.G_inf if calibrated_on == "long" else prony.G0


def _check_time(name: str, value: float) -> float:
    v = float(value)
    if not np.isfinite(v) or v <= 0:
        raise MagtactError(f"{name} = {value!r} s must be a positive number of seconds")
    return v


@dataclass(frozen=True)
class Loop:
    """One press and release: the load rises linearly from 0 to ``t_peak`` in ``press_time``
    and falls back in the same time.

    Attributes
    ----------
    time : (n,) [s]
    load : (n,) the non-dimensional load t of the path (docs/method.md §1)
    F_true, F_read : (n, k) [N]
        The force of the relaxing body and the force the sensor reads (G_cal f), one column
        per component.
    gap : (k,) [N]
        Hysteresis: the largest difference between the readings of the loading and the
        unloading half at the same true force.
    area : (k,) [N²]
        The area enclosed by the loop F_read against F_true.
    error : (k,) [N]
        The largest |F_read − F_true| over the cycle.
    peak : (k,) [N]
        The largest |F_true| (the range the hysteresis is a fraction of).
    """

    press_time: float
    t_peak: float
    calibrated_on: str
    G_cal: float
    time: np.ndarray
    load: np.ndarray
    F_true: np.ndarray
    F_read: np.ndarray
    gap: np.ndarray
    area: np.ndarray
    error: np.ndarray
    peak: np.ndarray


@dataclass(frozen=True)
class Creep:
    """A press to ``t_peak`` in ``press_time``, then the true force held for ``hold``: the body
    creeps and the reading drifts.

    Attributes
    ----------
    creep : (k,) [N]
        The reading at the end of the hold minus the reading when the hold began.
    error : (k,) [N]
        F_read − F_true at the end of the hold.
    """

    press_time: float
    hold: float
    t_peak: float
    calibrated_on: str
    time: np.ndarray
    F_true: np.ndarray
    F_read: np.ndarray
    creep: np.ndarray
    error: np.ndarray


def _columns(f_of_load: Callable, load: np.ndarray) -> np.ndarray:
    f = np.asarray(f_of_load(load), dtype=float)
    if f.ndim not in (1, 2) or f.shape[0] != len(load):
        raise MagtactError(f"f_of_load must return an array (n,) or (n, k) for n = {len(load)} "
                           f"loads, got shape {f.shape}")
    return f[:, None] if f.ndim == 1 else f


def _branch_gap(F_true: np.ndarray, F_read: np.ndarray, n: int) -> float:
    """The largest |reading up − reading down| at equal true force of one component: the
    loading half is samples 0..n, the unloading half n..2n (each taken while its true force
    is monotone)."""
    s = 1.0 if F_true[n] >= 0 else -1.0  # make the loading half increasing
    x_up, y_up = s * F_true[: n + 1], F_read[: n + 1]
    x_dn, y_dn = s * F_true[n:], F_read[n:]
    up_end = int(np.argmax(x_up)) + 1
    dn_end = int(np.argmin(x_dn)) + 1  # the unloading half falls until its minimum
    x_up, y_up = x_up[:up_end], y_up[:up_end]
    x_dn, y_dn = x_dn[:dn_end][::-1], y_dn[:dn_end][::-1]
    lo, hi = max(x_up[0], x_dn[0]), min(x_up[-1], x_dn[-1])
    if not hi > lo:
        return 0.0
    levels = np.linspace(lo, hi, 4 * n + 1)
    return float(np.max(np.abs(np.interp(levels, x_up, y_up) - np.interp(levels, x_dn, y_dn))))


def press_cycle(prony: Prony, f_of_load: Callable, t_peak: float, press_time: float, *,
                calibrated_on: str = "long", n: int = N_PRESS) -> Loop:
    """The press and release of :class:`Loop` for a body of elastic force ``f_of_load``.

    Parameters
    ----------
    prony : Prony
        The relaxation modulus (G_∞ is the modulus the elastic map belongs to).
    f_of_load : callable
        load ↦ f = F_elastic / G [N/Pa], an array (n,) or (n, k) (k components), e.g. the
        metamodels' (f_r, f_z) along a path.
    t_peak : float
        The largest load (0 < t_peak).
    press_time : float
        Seconds from rest to ``t_peak`` (and back).
    calibrated_on : {"long", "short"}
        The modulus of the sensor's calibration (:func:`calibration_modulus`).
    n : int
        Samples per half cycle.
    """
    press_time = _check_time("press_time", press_time)
    if not (np.isfinite(t_peak) and t_peak > 0):
        raise MagtactError(f"t_peak = {t_peak!r} must be a positive load")
    G_cal = calibration_modulus(prony, calibrated_on)
    s = np.linspace(0.0, 1.0, n + 1)
    time = np.concatenate([s, 1.0 + s[1:]]) * press_time
    load = t_peak * np.concatenate([s, 1.0 - s[1:]])
    f = _columns(f_of_load, load)
    F_true = hereditary_force(prony, time, f)
    F_read = G_cal * f
    gap = np.array([_branch_gap(F_true[:, j], F_read[:, j], n) for j in range(f.shape[1])])
    area = np.abs(np.trapezoid(F_read, F_true, axis=0))
    error = np.max(np.abs(F_read - F_true), axis=0)
    peak = np.max(np.abs(F_true), axis=0)
    return Loop(press_time, float(t_peak), calibrated_on, G_cal, time, load, F_true, F_read,
                gap, area, error, peak)


def press_and_hold(prony: Prony, f_of_load: Callable, t_peak: float, press_time: float,
                   hold: float, *, calibrated_on: str = "long", n: int = N_PRESS) -> Creep:
    """The press and hold of :class:`Creep`: the load rises linearly to ``t_peak`` in
    ``press_time``, then the true force is held for ``hold`` seconds (time steps growing
    geometrically over the hold, which resolves every relaxation time)."""
    press_time = _check_time("press_time", press_time)
    hold = _check_time("hold", hold)
    if not (np.isfinite(t_peak) and t_peak > 0):
        raise MagtactError(f"t_peak = {t_peak!r} must be a positive load")
    G_cal = calibration_modulus(prony, calibrated_on)
    s = np.linspace(0.0, 1.0, n + 1)
    step0 = min(press_time / n, hold / n, *(t / 50 for t in prony.tau)) if prony.tau else \
        hold / n
    after = np.geomspace(step0, hold, 4 * n)
    time = np.concatenate([s * press_time, press_time + after])
    load = np.concatenate([t_peak * s, np.full(len(after), t_peak)])
    f = _columns(f_of_load, load)
    F_true, f_held = held_force(prony, time, f, n)
    F_read = G_cal * f_held
    creep = F_read[-1] - F_read[n]
    return Creep(press_time, hold, float(t_peak), calibrated_on, time, F_true, F_read, creep,
                 F_read[-1] - F_true[-1])


@dataclass(frozen=True)
class RateSweep:
    """Hysteresis, loop area and the largest error against the press time of a cycle."""

    press_times: np.ndarray
    gap: np.ndarray    # (m, k) [N]
    area: np.ndarray   # (m, k) [N²]
    error: np.ndarray  # (m, k) [N]
    peak: np.ndarray   # (m, k) [N]


def press_times_around(prony: Prony, n: int = 25, decades: float = 2.0) -> np.ndarray:
    """Press times [s] from ``decades`` below the shortest relaxation time to ``decades`` above
    the longest (1 ms to 1000 s for no relaxing term)."""
    if not prony.tau:
        return np.geomspace(1e-3, 1e3, n)
    return np.geomspace(min(prony.tau) * 10**-decades, max(prony.tau) * 10**decades, n)


def rate_sweep(prony: Prony, f_of_load: Callable, t_peak: float, press_times=None, *,
               calibrated_on: str = "long", n: int = N_PRESS) -> RateSweep:
    """:func:`press_cycle` over ``press_times`` [s] (default :func:`press_times_around`)."""
    press_times = (press_times_around(prony) if press_times is None
                   else np.asarray(press_times, dtype=float))
    loops = [press_cycle(prony, f_of_load, t_peak, T, calibrated_on=calibrated_on, n=n)
             for T in press_times]
    return RateSweep(press_times, *(np.array([getattr(lp, k) for lp in loops])
                                    for k in ("gap", "area", "error", "peak")))
