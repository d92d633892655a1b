"""The time response of a design (H, G): its silicone's relaxation, a press and release at the
study's press time, a press held, the rate sweep, and the comparison with the MagOne's
measured hysteresis (docs/method.md §15)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from .._records import entry, from_json_lenient, from_json_or_none, to_json
from ..parts import SILICONES
from ..study import Study
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
    measured : MeasuredPart
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
    measured: MeasuredPart


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
    measured = MeasuredPart(MEASURED_HYSTERESIS, MEASURED_SOURCE, g_min, tau_at,
                            predicted=predicted,
                            measured_at_this_range=MEASURED_HYSTERESIS * float(normal.peak[1]))
    return TimeResponse(prony, T, hold, cal, float(t_m), float(theta_m), loops, creeps, sweeps,
                        hyst, creep, measured)


def _every(n: int, most: int = 201) -> slice:
    return slice(None, None, max(1, -(-n // most)))


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

    source: str = entry(kind=str)
    press_times: np.ndarray = entry("press_time_s", "s", levels=("list",), array=True)
    hysteresis: np.ndarray = entry(unit="pct", levels=("list",), array=True)

    @classmethod
    def of(cls, sweep: RateSweep, source: str) -> SiliconeSweep:
        """The F_z hysteresis of a :class:`RateSweep`."""
        return cls(source, np.asarray(sweep.press_times, dtype=float),
                   sweep.gap[:, 1] / sweep.peak[:, 1])

    def to_json(self) -> dict:
        """In user units (s, % of the peak F_z)."""
        return to_json(self)

    @classmethod
    def from_json(cls, data) -> SiliconeSweep | None:
        """The sweep :meth:`to_json` wrote; None for anything else (press times and
        hysteresis of unequal length included)."""
        return _sweep_or_none(from_json_or_none(cls, data))


def _sweep_or_none(sw: SiliconeSweep | None) -> SiliconeSweep | None:
    """``sw`` where it holds press times and hysteresis of equal length, else None."""
    if sw is None or sw.press_times is None or sw.hysteresis is None or \
            sw.press_times.shape != sw.hysteresis.shape:
        return None
    return sw


@dataclass(frozen=True)
class RelaxationPart:
    """The relaxation of a time entry: G_∞ [Pa], the Prony ratios and times [s], its source."""

    G_inf: float = entry(unit="kPa")
    g: tuple = entry(levels=("list",))
    tau: tuple = entry(unit="s", levels=("list",))
    source: str = entry(kind=str)


@dataclass(frozen=True)
class LoopPart:
    """A press and release (:class:`Loop`) in a time entry, thinned to about 200 samples:
    time [s], load t, true and read force (F_r, F_z) [N], the hysteresis, loop area (held in
    mN², the unit of the file: the units module has no squared forces), largest error and
    peak per component [N]."""

    time: np.ndarray = entry(unit="s", levels=("list",), array=True)
    load_t: np.ndarray = entry(levels=("list",), array=True)
    F_true: np.ndarray = entry(unit="mN", levels=("list", "list"), array=True)
    F_read: np.ndarray = entry(unit="mN", levels=("list", "list"), array=True)
    hysteresis: np.ndarray = entry(unit="mN", levels=("list",), array=True)
    loop_area_mN2: np.ndarray = entry(levels=("list",), array=True)
    largest_error: np.ndarray = entry(unit="mN", levels=("list",), array=True)
    peak: np.ndarray = entry(unit="mN", levels=("list",), array=True)


@dataclass(frozen=True)
class CreepPart:
    """A press held (:class:`Creep`) in a time entry, thinned: time [s], true and read force
    [N], the creep and the error at the end per component [N]."""

    time: np.ndarray = entry(unit="s", levels=("list",), array=True)
    F_true: np.ndarray = entry(unit="mN", levels=("list", "list"), array=True)
    F_read: np.ndarray = entry(unit="mN", levels=("list", "list"), array=True)
    creep: np.ndarray = entry(unit="mN", levels=("list",), array=True)
    error_at_end: np.ndarray = entry(unit="mN", levels=("list",), array=True)


@dataclass(frozen=True)
class SweepPart:
    """A rate sweep (:class:`RateSweep`) in a time entry: press times [s] and, per press time
    and component, the hysteresis [N], loop area [mN², as :class:`LoopPart`], largest error and
    peak [N]."""

    press_time: np.ndarray = entry(unit="s", levels=("list",), array=True)
    hysteresis: np.ndarray = entry(unit="mN", levels=("list", "list"), array=True)
    loop_area_mN2: np.ndarray = entry(levels=("list", "list"), array=True)
    largest_error: np.ndarray = entry(unit="mN", levels=("list", "list"), array=True)
    peak: np.ndarray = entry(unit="mN", levels=("list", "list"), array=True)


@dataclass(frozen=True)
class PressPart:
    """One press of a time entry: its shear angle [rad], loop, creep and rate sweep."""

    theta: float = entry(unit="rad")
    loop: LoopPart = entry(kind=LoopPart)
    creep: CreepPart = entry(kind=CreepPart)
    rate_sweep: SweepPart = entry(kind=SweepPart)


@dataclass(frozen=True)
class MeasuredPart:
    """The MagOne's measured hysteresis (a fraction of the peak F_z) and its source, this
    design's predicted one and its measured force at this range [N] (None: not computed), and
    the smallest single-term ratio g reaching it with its τ [s] (NaN, null in the file: none
    does)."""

    hysteresis: float = entry(unit="pct")
    source: str = entry(kind=str)
    predicted: float | None = entry(unit="pct", optional=True, omit="none", default=None,
                                    kw_only=True)
    measured_at_this_range: float | None = entry(
        "measured_mN_at_this_range", "mN", optional=True, omit="none", default=None,
        kw_only=True)
    single_term_g_min: float = entry(null_nan=True)
    single_term_tau: float = entry(unit="s", null_nan=True)


def _known(**kw):
    """A part of a time entry that only a known relaxation gives (left out otherwise)."""
    return entry(optional=True, omit="none", default=None, kw_only=True, **kw)


@dataclass(frozen=True)
class TimeEntry:
    """The ``time`` entry of a budget as written (:func:`time_json`, :func:`unknown_time_json`),
    in SI: where the relaxation comes from, the relaxation, the study's load history, the
    presses with their largest hysteresis and creep per component [N], the comparison with the
    measured hysteresis and the catalogue silicones' sweeps."""

    source: str | None = entry(kind=str, optional=True, omit="none", default=None,
                               kw_only=True)
    relaxation: RelaxationPart | None = _known(kind=RelaxationPart)
    press_time: float = entry(unit="s")
    hold: float = entry(unit="s")
    calibrated_on: str = entry(kind=str)
    t_m: float | None = _known()
    theta_m: float | None = _known(unit="rad")
    components: tuple | None = _known(kind=str, levels=("list",))
    hysteresis: np.ndarray | None = _known(unit="mN", levels=("list",), array=True)
    creep: np.ndarray | None = _known(unit="mN", levels=("list",), array=True)
    presses: tuple | None = _known(kind=PressPart, levels=("list",))
    measured: MeasuredPart | None = entry(kind=MeasuredPart, optional=True, default=None,
                                          kw_only=True)
    silicones: dict | None = _known(kind=SiliconeSweep, levels=("map",))


def time_json(r: TimeResponse, *, source: str | None = None,
              silicones: dict[str, SiliconeSweep] | None = None) -> dict:
    """Every number of a :class:`TimeResponse` in user units (mN, s), the unit in each key;
    the loops and creeps thinned to about 200 samples. With ``source`` (where the relaxation
    comes from, first) and ``silicones`` (the catalogue silicones' sweeps, last): the ``time``
    entry of a budget (:class:`TimeEntry`, read back by :meth:`TimeRecord.from_json`)."""
    def loop(lp: Loop) -> LoopPart:
        k = _every(len(lp.time))
        return LoopPart(lp.time[k], lp.load[k], lp.F_true[k], lp.F_read[k], lp.gap,
                        lp.area * 1e6, lp.error, lp.peak)

    def creep(c: Creep) -> CreepPart:
        k = _every(len(c.time))
        return CreepPart(c.time[k], c.F_true[k], c.F_read[k], c.creep, c.error)

    def sweep(s: RateSweep) -> SweepPart:
        return SweepPart(s.press_times, s.gap, s.area * 1e6, s.error, s.peak)

    p = r.prony
    return to_json(TimeEntry(
        source=source,
        relaxation=RelaxationPart(p.G_inf, tuple(p.ratios), tuple(p.tau), p.source),
        press_time=r.press_time, hold=r.hold, calibrated_on=r.calibrated_on, t_m=r.t_m,
        theta_m=r.theta_m, components=COMPONENTS, hysteresis=r.hysteresis, creep=r.creep,
        presses=tuple(PressPart(th, loop(r.loops[th]), creep(r.creeps[th]),
                                sweep(r.sweeps[th])) for th in r.loops),
        measured=r.measured,
        silicones=silicones))


def unknown_time_json(source: str, press_time: float, hold: float, calibrated_on: str,
                      g_min: float, tau: float) -> dict:
    """The ``time`` entry of a budget whose silicone's relaxation is not known
    (:class:`TimeEntry`): why (``source``), the study's load history [s] and the MagOne's
    measured hysteresis with the smallest single-term ratio ``g_min`` (at ``tau`` [s]) that
    reaches it (None where none does)."""
    return to_json(TimeEntry(
        source=source, press_time=press_time, hold=hold, calibrated_on=calibrated_on,
        measured=MeasuredPart(MEASURED_HYSTERESIS, MEASURED_SOURCE, g_min, tau)))


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
    def of(cls, p: PressPart | None) -> TimePress | None:
        """The press of a :class:`PressPart` read field by field; None where it lacks the
        angle, the loop or the sweep (or gives arrays of the wrong shape)."""
        if p is None or p.loop is None or p.rate_sweep is None:
            return None
        loop, sweep = p.loop, p.rate_sweep
        arrays = (loop.F_true, loop.F_read, sweep.press_time, sweep.hysteresis, sweep.peak)
        if p.theta is None or any(a is None for a in arrays):
            return None
        true, read, T, gap, peak = arrays
        if not (true.ndim == read.ndim == gap.ndim == peak.ndim == 2 and T.ndim == 1) or \
                true.shape != read.shape or true.shape[1] != 2 or gap.shape[1] != 2 or \
                peak.shape[1] != 2 or not len(T) == len(gap) == len(peak):
            return None
        return cls(p.theta, true, read, T, gap, peak)

    @classmethod
    def from_json(cls, data) -> TimePress | None:
        """The press :func:`time_json` wrote; None where it lacks the angle, the loop or the
        sweep (or gives arrays of the wrong shape)."""
        return cls.of(from_json_lenient(PressPart, data))


@dataclass(frozen=True)
class TimeRecord:
    """The ``time`` entry of a budget (:class:`TimeEntry`) read back, in SI; a value the entry
    does not give is None.

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
        """The entry :func:`time_json` or :func:`unknown_time_json` wrote, read field by
        field; None for anything but a non-empty JSON object (a press or silicone that does
        not read is left out)."""
        if not isinstance(data, dict) or not data:
            return None
        e = from_json_lenient(TimeEntry, data)
        gap = e.hysteresis
        measured = e.measured.hysteresis if e.measured is not None else None
        return cls(e.source or "", e.press_time,
                   None if gap is None or gap.shape != (2,) else gap, measured,
                   tuple(p for p in map(TimePress.of, e.presses or ()) if p is not None),
                   {name: sw for name, sw in (e.silicones or {}).items()
                    if _sweep_or_none(sw) is not None})
