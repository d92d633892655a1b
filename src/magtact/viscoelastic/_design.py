"""The time response of a design (H, G): its silicone's relaxation, a press and release at the
study's press time, a press held, the rate sweep, and the comparison with the MagOne's
measured hysteresis (docs/method.md §15)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from .._files import json_dict, json_list, json_number, json_text
from ..parts import SILICONES
from ..study import Study, from_si, to_si
from ._prony import Prony
from ._sensor import (
    MEASURED_HYSTERESIS,
    MEASURED_SOURCE,
    Creep,
    Loop,
    RateSweep,
    press_and_hold,
    press_cycle,
    rate_sweep,
)

#: Components of the forces (as the budget's rows).
COMPONENTS = ("F_r", "F_z")


def relaxation_of(study: Study, G: float, silicone: str | None = None
                  ) -> tuple[Prony | None, str]:
    """The relaxation modulus of the design's silicone (``silicone``, default the study's
    ``[material] silicone``) with G_∞ = ``G`` [Pa] (the design's G is the long-time modulus),
    and where it comes from.

    The study's ``[material] relaxation_g1/g2`` win where either is nonzero; else the
    catalogue's series of the silicone; else None, and the text says why.
    """
    m = study.material
    name = m.silicone if silicone is None else silicone
    if m.relaxation_g1 > 0 or m.relaxation_g2 > 0:
        g, tau = zip(*((gi, ti) for gi, ti in ((m.relaxation_g1, m.relaxation_tau1),
                                                (m.relaxation_g2, m.relaxation_tau2))
                       if gi > 0), strict=True)
        terms = ", ".join(f"g = {gi:.3g} at τ = {ti:.3g} s" for gi, ti in zip(g, tau,
                                                                               strict=True))
        source = (f"given by the study ([material] relaxation_*: {terms}; not a catalogue "
                  f"figure of {name})")
        return Prony.from_ratios(G, g, tau, source), source
    entry = SILICONES.get(name)
    if entry is not None and entry.relaxation is not None:
        r = entry.relaxation
        return Prony.from_ratios(G, r.g, r.tau, f"{name}: {r.source}"), f"{name}: {r.source}"
    why = ("no silicone named" if entry is None
           else f"no relaxation data for {name} ({entry.relaxation_note})")
    return None, (f"{why}; give the silicone's relaxation (its two strengths and time "
                  "constants) in the study's [material] section")


def design_forces(models, H: float, theta: float):
    """load ↦ (f_r, f_z) [N/Pa] of the metamodels along the path at (θ, H), shape (n, 2)."""
    def f(load):
        load = np.asarray(load, dtype=float)
        return np.stack([models.f_r.value(load, theta, H) * np.ones_like(load),
                         models.f_z.value(load, theta, H) * np.ones_like(load)], axis=-1)
    return f


@dataclass(frozen=True)
class TimeResponse:
    """The time rows of a design: at θ = 0 (a normal press) and θ = θ_m (the sheared press),
    each to the stable region's load t_m.

    Attributes
    ----------
    prony : Prony
        The relaxation with G_∞ = the design's G.
    loops, creeps : dict θ [rad] → Loop, Creep
    sweeps : dict θ → RateSweep
    hysteresis, creep : (2,) [N]
        The largest gap and |creep| per component (F_r, F_z) over both presses.
    measured : dict
        The MagOne's measured hysteresis (fraction and source) against this design's at the
        study's press time, and the smallest single-term ratio g that reaches it at any τ.
    """

    prony: Prony
    press_time: float
    hold: float
    calibrated_on: str
    t_m: float
    theta_m: float
    loops: dict
    creeps: dict
    sweeps: dict
    hysteresis: np.ndarray
    creep: np.ndarray
    measured: dict


def implied_ratio(f_of_load, t_peak: float, press_time: float, target: float,
                  calibrated_on: str = "long", component: int = -1, *, n: int = 100,
                  n_tau: int = 13) -> tuple[float, float]:
    """The smallest ratio g = G_1 / G_∞ of a one-term series whose hysteresis (gap / peak of
    ``component``) reaches ``target`` at ``press_time``, over τ; and the τ [s] where it does.

    For a given g the gap is largest near τ ~ the press time, so τ is searched over four
    decades around it and g found by bisection (the gap grows with g).
    """
    taus = press_time * np.geomspace(1e-2, 1e2, n_tau)

    def worst(g: float) -> tuple[float, float]:
        best = (-1.0, np.nan)
        for tau in taus:
            lp = press_cycle(Prony(1.0, (g,), (tau,)), f_of_load, t_peak, press_time,
                             calibrated_on=calibrated_on, n=n)
            best = max(best, (lp.gap[component] / lp.peak[component], tau))
        return best

    if worst(1e3)[0] < target:
        return np.inf, np.nan
    g = brentq(lambda x: worst(x)[0] - target, 1e-6, 1e3, xtol=1e-9, rtol=1e-4)
    return float(g), float(worst(g)[1])


def time_response(models, study: Study, H: float, G: float, t_m: float, theta_m: float,
                  prony: Prony | None = None, *, implied: tuple[float, float] | None = None
                  ) -> TimeResponse | None:
    """The :class:`TimeResponse` of design (H [m], G [Pa]) for the study's load history
    (``[environment] press_time_s, hold_s, calibrated_on``); None where the silicone's
    relaxation is not known (:func:`relaxation_of`). ``implied``: the result of
    :func:`implied_ratio` for the design's normal press, if already computed."""
    if prony is None:
        prony, _ = relaxation_of(study, G)
        if prony is None:
            return None
    env = study.environment
    T, hold, cal = env.press_time, env.hold, env.calibrated_on
    loops, creeps, sweeps = {}, {}, {}
    thetas = (0.0, float(theta_m)) if theta_m > 0 else (0.0,)
    for th in thetas:
        f = design_forces(models, H, th)
        loops[th] = press_cycle(prony, f, t_m, T, calibrated_on=cal)
        creeps[th] = press_and_hold(prony, f, t_m, T, hold, calibrated_on=cal)
        sweeps[th] = rate_sweep(prony, f, t_m, calibrated_on=cal, n=200)
    hyst = np.max([lp.gap for lp in loops.values()], axis=0)
    creep = np.max([np.abs(c.creep) for c in creeps.values()], axis=0)
    normal = loops[0.0]
    predicted = float(normal.gap[1] / normal.peak[1])
    g_min, tau_at = implied if implied is not None else implied_ratio(
        design_forces(models, H, 0.0), t_m, T, MEASURED_HYSTERESIS, cal)
    measured = {"fraction": MEASURED_HYSTERESIS, "source": MEASURED_SOURCE,
                "predicted_fraction": predicted, "peak_F_z": float(normal.peak[1]),
                "measured_F_z": MEASURED_HYSTERESIS * float(normal.peak[1]),
                "single_term_g_min": g_min, "single_term_tau": tau_at}
    return TimeResponse(prony, T, hold, cal, float(t_m), float(theta_m), loops, creeps, sweeps,
                        hyst, creep, measured)


def _every(n: int, most: int = 201) -> slice:
    return slice(None, None, max(1, -(-n // most)))


def time_json(r: TimeResponse, *, source: str | None = None,
              silicones: dict[str, SiliconeSweep] | None = None) -> dict:
    """Every number of a :class:`TimeResponse` in user units (mN, s), the unit in each key;
    the loops and creeps thinned to about 200 samples. With ``source`` (where the relaxation
    comes from, first) and ``silicones`` (the catalogue silicones' sweeps, last): the ``time``
    entry of a budget (read back by :meth:`TimeRecord.from_json`)."""
    def mN(a):
        return from_si(np.asarray(a, dtype=float), "mN").tolist()

    def loop(lp: Loop) -> dict:
        k = _every(len(lp.time))
        return {"time_s": lp.time[k].tolist(), "load_t": lp.load[k].tolist(),
                "F_true_mN": mN(lp.F_true[k]), "F_read_mN": mN(lp.F_read[k]),
                "hysteresis_mN": mN(lp.gap), "loop_area_mN2": (lp.area * 1e6).tolist(),
                "largest_error_mN": mN(lp.error), "peak_mN": mN(lp.peak)}

    def creep(c: Creep) -> dict:
        k = _every(len(c.time))
        return {"time_s": c.time[k].tolist(), "F_true_mN": mN(c.F_true[k]),
                "F_read_mN": mN(c.F_read[k]), "creep_mN": mN(c.creep),
                "error_at_end_mN": mN(c.error)}

    def sweep(s: RateSweep) -> dict:
        return {"press_time_s": s.press_times.tolist(), "hysteresis_mN": mN(s.gap),
                "loop_area_mN2": (s.area * 1e6).tolist(), "largest_error_mN": mN(s.error),
                "peak_mN": mN(s.peak)}

    p = r.prony
    m = r.measured
    head = {} if source is None else {"source": source}
    tail = {} if silicones is None else {
        "silicones": {name: sw.to_json() for name, sw in silicones.items()}}
    return head | {
        "relaxation": {"G_inf_kPa": from_si(p.G_inf, "kPa"), "g": list(p.ratios),
                       "tau_s": list(p.tau), "source": p.source},
        "press_time_s": r.press_time, "hold_s": r.hold, "calibrated_on": r.calibrated_on,
        "t_m": r.t_m, "theta_m_rad": r.theta_m, "components": list(COMPONENTS),
        "hysteresis_mN": mN(r.hysteresis), "creep_mN": mN(r.creep),
        "presses": [{"theta_rad": th, "loop": loop(r.loops[th]), "creep": creep(r.creeps[th]),
                     "rate_sweep": sweep(r.sweeps[th])} for th in r.loops],
        "measured": {"hysteresis_pct": 100 * m["fraction"], "source": m["source"],
                     "predicted_pct": 100 * m["predicted_fraction"],
                     "measured_mN_at_this_range": from_si(m["measured_F_z"], "mN"),
                     "single_term_g_min": None if not np.isfinite(m["single_term_g_min"])
                     else m["single_term_g_min"],
                     "single_term_tau_s": None if not np.isfinite(m["single_term_tau"])
                     else m["single_term_tau"]},
    } | tail


def unknown_time_json(source: str, press_time: float, hold: float, calibrated_on: str,
                      g_min: float, tau: float) -> dict:
    """The ``time`` entry of a budget whose silicone's relaxation is not known: why
    (``source``), the study's load history [s] and the MagOne's measured hysteresis with the
    smallest single-term ratio ``g_min`` (at ``tau`` [s]) that reaches it (None where none
    does)."""
    return {"source": source, "press_time_s": press_time, "hold_s": hold,
            "calibrated_on": calibrated_on,
            "measured": {"hysteresis_pct": 100 * MEASURED_HYSTERESIS, "source": MEASURED_SOURCE,
                         "single_term_g_min": None if not np.isfinite(g_min) else g_min,
                         "single_term_tau_s": None if not np.isfinite(tau) else tau}}


@dataclass(frozen=True)
class SiliconeSweep:
    """A silicone's hysteresis of the normal press against the press time.

    Attributes
    ----------
    source : str
        Where its relaxation comes from.
    press_times : ndarray
        Press times, rest to full load [s].
    hysteresis : ndarray
        The hysteresis of F_z at each press time, as a fraction of the peak F_z [1].
    """

    source: str
    press_times: np.ndarray
    hysteresis: np.ndarray

    @classmethod
    def of(cls, sweep: RateSweep, source: str) -> SiliconeSweep:
        """The F_z hysteresis of a :class:`RateSweep`."""
        return cls(source, np.asarray(sweep.press_times, dtype=float),
                   sweep.gap[:, 1] / sweep.peak[:, 1])

    def to_json(self) -> dict:
        """In user units (s, % of the peak F_z)."""
        return {"source": self.source, "press_time_s": self.press_times.tolist(),
                "hysteresis_pct": (100 * self.hysteresis).tolist()}

    @classmethod
    def from_json(cls, data) -> SiliconeSweep | None:
        """The sweep :meth:`to_json` wrote; None for anything but a JSON object with press
        times and hysteresis of equal length."""
        if not isinstance(data, dict):
            return None
        T, pct = _numbers(data.get("press_time_s")), _numbers(data.get("hysteresis_pct"))
        if T is None or pct is None or T.shape != pct.shape:
            return None
        return cls(json_text(data.get("source")), T, pct / 100)


@dataclass(frozen=True)
class TimePress:
    """One press of a time entry read back (:func:`time_json`), in SI.

    Attributes
    ----------
    theta : float
        The press's shear angle [rad] (0: the normal press).
    F_true, F_read : ndarray (n, 2)
        The true and the read force (F_r, F_z) [N] over the press and release.
    press_times : ndarray (m,)
        The rate sweep's press times [s].
    gap, peak : ndarray (m, 2)
        The sweep's hysteresis and peak force (F_r, F_z) [N] at each press time.
    """

    theta: float
    F_true: np.ndarray
    F_read: np.ndarray
    press_times: np.ndarray
    gap: np.ndarray
    peak: np.ndarray

    @classmethod
    def from_json(cls, data) -> TimePress | None:
        """The press :func:`time_json` wrote; None where it lacks the angle, the loop or the
        sweep (or gives arrays of the wrong shape)."""
        if not isinstance(data, dict):
            return None
        theta = json_number(data.get("theta_rad"))
        loop, sweep = json_dict(data.get("loop")), json_dict(data.get("rate_sweep"))
        true, read = (_numbers(loop.get(k), 2) for k in ("F_true_mN", "F_read_mN"))
        T = _numbers(sweep.get("press_time_s"))
        gap, peak = (_numbers(sweep.get(k), 2) for k in ("hysteresis_mN", "peak_mN"))
        if theta is None or any(a is None for a in (true, read, T, gap, peak)) or \
                true.shape != read.shape or not (len(T) == len(gap) == len(peak)):
            return None
        return cls(theta, to_si(true, "mN"), to_si(read, "mN"), T, to_si(gap, "mN"),
                   to_si(peak, "mN"))


@dataclass(frozen=True)
class TimeRecord:
    """The ``time`` entry of a budget (:func:`time_json` with its source and silicones, or
    :func:`unknown_time_json`) read back, in SI; a value the entry does not give is None.

    Attributes
    ----------
    source : str
        Where the relaxation comes from (or why it is not known).
    press_time : float or None
        The study's press time, rest to full load [s].
    hysteresis : ndarray (2,) or None
        The largest hysteresis of (F_r, F_z) over the presses [N].
    measured_hysteresis : float or None
        The MagOne's measured hysteresis, a fraction of the peak F_z [1].
    presses : tuple of TimePress
        Empty where the relaxation is not known.
    silicones : dict of str to SiliconeSweep
        The catalogue silicones with a cited relaxation, by name.
    """

    source: str
    press_time: float | None
    hysteresis: np.ndarray | None
    measured_hysteresis: float | None
    presses: tuple[TimePress, ...]
    silicones: dict[str, SiliconeSweep]

    @property
    def normal_press(self) -> TimePress | None:
        """The press at θ = 0, if there is one."""
        return next((p for p in self.presses if p.theta == 0.0), None)

    @classmethod
    def from_json(cls, data) -> TimeRecord | None:
        """The entry :func:`time_json` or :func:`unknown_time_json` wrote; None for anything
        but a non-empty JSON object (a press or silicone that does not read is left out)."""
        if not isinstance(data, dict) or not data:
            return None
        gap = _numbers(data.get("hysteresis_mN"))
        pct = json_number(json_dict(data.get("measured")).get("hysteresis_pct"))
        silicones = {name: sw for name, sw in ((n, SiliconeSweep.from_json(v)) for n, v in
                                              json_dict(data.get("silicones")).items())
                     if sw is not None}
        return cls(json_text(data.get("source")), json_number(data.get("press_time_s")),
                   None if gap is None or gap.shape != (2,) else to_si(gap, "mN"),
                   None if pct is None else pct / 100,
                   tuple(p for p in map(TimePress.from_json, json_list(data.get("presses")))
                         if p is not None), silicones)


def _numbers(value, columns: int | None = None) -> np.ndarray | None:
    """A JSON array of numbers (with ``columns``: of rows of that many numbers) as floats;
    None for anything else (a null reads as NaN)."""
    if not isinstance(value, list):
        return None
    try:
        a = np.asarray([np.nan if v is None else v for v in value] if columns is None
                       else [[np.nan if v is None else v for v in row] for row in value],
                       dtype=float)
    except (TypeError, ValueError):
        return None
    if a.ndim != (1 if columns is None else 2) or (columns is not None
                                                   and a.shape[1] != columns):
        return None
    return a
