"""The designer's answer for one design: resolution with a named Hall chip, measuring range,
the chip's limits along the paths, and the margin for the tolerance of G (docs/method.md §10).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
from scipy.optimize import minimize

from .._records import entry, to_json
from .._sensor import Sensor
from ..chip import (
    Saturation,
    SettingChoice,
    chip_margin,
    saturation,
    setting_for,
)
from ..doe import check_design
from ..metamodel import ModelSet
from ..optimise import DesignResult, per_design
from ..parts import SettingFigures, grade, silicones_around
from ..sensitivity import force_noise
from ..study import MU0, HallChip, Study, hall_chip
from ._verdict import Verdict, verdict

if TYPE_CHECKING:
    from ..tolerance import RobustVerdict

#: Points per side of the grid over the stable box (the worst σ_F starts from its best point).
N_BOX = 41


@dataclass(frozen=True)
class Resolution:
    """Force noise σ_F [N] from the chip's field noise (1 σ, RMS)."""

    sigma_r_0: float
    sigma_z_0: float
    sigma_r_worst: float
    sigma_z_worst: float
    #: (t, θ [rad]) of each worst value.
    where_r: tuple[float, float]
    where_z: tuple[float, float]


@dataclass(frozen=True)
class Parts:
    """The parts of a design: the magnet's grade and size as the study names them, and the
    silicones whose shear-modulus range holds G (docs/method.md §10)."""

    grade: str
    size: str
    M_z: float
    silicone: str
    #: Silicones whose G range holds G, and the nearest softer and stiffer ones outside.
    inside: tuple[str, ...]
    softer: str | None
    stiffer: str | None
    #: The magnet's radius and height [m] (None: not known).
    R_m: float | None = None
    H_m: float | None = None

    def __str__(self) -> str:
        from .._display import parts_rows, text_block

        return text_block(*parts_rows(self))

    def _repr_html_(self) -> str:
        from .._display import html_block, parts_rows

        return html_block(*parts_rows(self))


def parts_of(study: Study, sensor: Sensor) -> Parts:
    """The parts of ``sensor``, a design of ``study`` (whose magnet names its size)."""
    inside, below, above = silicones_around(sensor.G)
    return Parts(sensor.grade, study.magnet.size, sensor.M_z, sensor.silicone,
                 tuple(x.name for x in inside), None if below is None else below.name,
                 None if above is None else above.name, sensor.R_m, sensor.H_m)


@dataclass(frozen=True)
class DesignAnswer:
    """What a designer asks of design (H, G) with the study's Hall chip.

    Attributes
    ----------
    label : str
    design : DesignResult
        Extrema in the stable box: F_r,min, F_z,max [N], Γ_r,max, Γ_z,max [N/T], t_m, θ_m.
    chip : HallChip
    resolution : Resolution or None
        None when the chip's noise is not known (``chip.missing`` names the keys to give).
    saturation : Saturation
    tolerance : float
        δ of ``[constraints] G_tolerance``; the worst case is the stiffest body, G (1 + δ),
        where Γ and σ_F are (1 + δ) times larger (both ∝ G).
    """

    label: str
    design: DesignResult
    chip: HallChip
    resolution: Resolution | None
    saturation: Saturation
    tolerance: float
    #: The chip setting chosen for this design (chips with a setting table; None otherwise).
    choice: SettingChoice | None = None
    #: σ_F at the lower end of the setting's noise interval (None: no interval).
    resolution_low: Resolution | None = None
    #: The parts: magnet grade and size, silicones whose G range holds G.
    parts: Parts | None = None
    #: Each requirement of the study met or not, with its margin.
    verdict: Verdict | None = None
    #: The study (the problem) this design answers.
    study: Study | None = None
    #: Each requirement over the built units: worst corner, yield, what limits it
    #: (:func:`magtact.tolerance.robust_verdict`; None: not computed).
    robust: RobustVerdict | None = None
    #: The sensor this answer is for: its body, magnet, chip at its setting and standoff.
    sensor: Sensor | None = None

    @property
    def standoff(self) -> float:
        """The chip's distance below the body [m]."""
        return 0.0 if self.sensor is None else self.sensor.standoff

    @property
    def figures(self) -> SettingFigures | None:
        """LSB, range, noise and rate of the chip at the setting used (None: no table)."""
        return self.chip.figures

    @property
    def H(self) -> float:
        return self.design.H

    @property
    def G(self) -> float:
        return self.design.G

    @property
    def worst_factor(self) -> float:
        """Γ and σ_F at G (1 + δ) over their nominal values."""
        return 1.0 + self.tolerance

    def __str__(self) -> str:
        """The design, its verdict with margins, σ_F, ranges and saturation in mN, N, mm and
        kPa (at most 25 lines)."""
        from .._display import answer_rows, answer_title, text_block

        return text_block(answer_title(self), answer_rows(self))

    def _repr_html_(self) -> str:
        from .._display import answer_rows, answer_title, html_block

        return html_block(answer_title(self), answer_rows(self))


def answer(models: ModelSet, study: Study, sensor: Sensor, label: str = "design",
           M_z: float | None = None) -> DesignAnswer:
    """The designer's answer for ``sensor``, a design (H, G) of ``study`` with its parts:
    the magnet's magnetisation, the chip at the sensor's standoff and setting (for a chip
    with a setting table whose setting neither the sensor nor the study fixes, at the best
    setting for this design, :func:`magtact.designer.best_setting`), the silicone. σ_F at the
    upper end of the setting's noise interval and, where it is an interval, at its lower end.

    ``models``: in the sensor problem with the exact field of the sensor's magnet at its
    standoff (:func:`magtact.chip.exact_field_models`). ``M_z`` [A/m] (where M_z is a design
    variable of models fitted at the study's magnet) scales the field and divides the force
    noise. A chip range below this design's field at rest shows as saturation at t = 0.
    """
    H, G = sensor.H, sensor.G
    check_design(study, H)  # outside the data's domain the models extrapolate
    chip = hall_chip(study, sensor.setting)
    place = {"M_z": sensor.M_z, "standoff": sensor.standoff}
    design = per_design(models, H, G, study, M_z)
    choice = setting_for(models, study, design, **place) if chip.picked else None
    if choice is not None:  # the chip at the setting chosen for this design
        chip = hall_chip(study, choice.setting)
    if chip.figures is not None:
        sensor = replace(sensor, setting=chip.figures.setting)
    sat = replace(saturation(study, models, H, G, chip, **place),
                  region_margin=float(chip_margin(study, H, design.t_m, design.theta_m,
                                                  chip=chip, **place)[0]))
    res = None if chip.noise is None else resolution(models, study, design, chip)
    low = None
    if chip.figures is not None and chip.figures.interval:
        f = chip.figures
        low = resolution(models, study, design, replace(chip, noise_x=f.sigma_x[0],
                                                        noise_z=f.sigma_z[0]))
    return DesignAnswer(label, design, chip, res, sat, study.constraints.G_tolerance, choice,
                        low, parts_of(study, sensor),
                        verdict(models, study, design, chip, **place), study, sensor=sensor)


def resolution(models: ModelSet, study: Study, design: DesignResult, chip: HallChip
               ) -> Resolution:
    """σ_F at t = 0 and its largest value over the stable box t ≤ t_m, θ ≤ θ_m."""
    H, G = design.H, design.G

    def sigma(t, theta):  # the models' Jacobian over the design's field scale
        return np.asarray(force_noise(models, t, theta, H, G, chip.noise)) / design.field_scale

    s0 = sigma(0.0, 0.0)
    T, TH = np.meshgrid(np.linspace(0.0, design.t_m, N_BOX),
                        np.linspace(0.0, design.theta_m, N_BOX), indexing="ij")
    grid = sigma(T, TH)
    worst, where = [], []
    for k in range(2):
        i = np.unravel_index(np.nanargmax(grid[k]), T.shape)
        x0 = np.array([T[i], TH[i]])
        best = (float(grid[k][i]), (float(x0[0]), float(x0[1])))
        bounds = [(0.0, design.t_m), (0.0, design.theta_m)]
        if design.t_m > 0 and design.theta_m > 0:  # polish the grid's best point
            r = minimize(lambda x, k=k: -float(sigma(x[0], x[1])[k]), x0, method="L-BFGS-B",
                         bounds=bounds)
            if np.isfinite(r.fun) and -r.fun > best[0]:
                best = (float(-r.fun), (float(r.x[0]), float(r.x[1])))
        worst.append(best[0])
        where.append(best[1])
    return Resolution(float(s0[0]), float(s0[1]), worst[0], worst[1], where[0], where[1])


@dataclass(frozen=True)
class VerdictPart:
    """The verdict of an answer: each requirement met or not (:meth:`Verdict.to_json`), all
    met or not, and σ_F [N] worst over the required loads."""

    verdict: object = entry(kind=object)
    meets_requirements: bool = entry(kind=bool)
    sigma_Fr_required_loads: float = entry(unit="mN")
    sigma_Fz_required_loads: float = entry(unit="mN")


@dataclass(frozen=True)
class FiguresPart:
    """The chip at its setting: the setting's fields and words, its rate [Hz], conversion time
    [ms] (the units module has no ms: the field holds ms), LSB and noise interval [T]."""

    setting: dict = entry(kind=int, levels=("map",))
    setting_words: str = entry(kind=str)
    sample_rate: float = entry(unit="Hz")
    conversion_time_ms: float = entry()
    LSB_x: float = entry(unit="uT")
    LSB_z: float = entry(unit="uT")
    noise_x_interval: tuple = entry("noise_x_uT_interval", "uT", levels=("list",))
    noise_z_interval: tuple = entry("noise_z_uT_interval", "uT", levels=("list",))
    noise_source: str = entry(kind=str)


@dataclass(frozen=True)
class ChoicePart:
    """The setting chosen for the design: whether it holds the field, how many were compared,
    and the largest field [T] over the stable region."""

    setting_holds_field: bool = entry(kind=bool)
    settings_compared: int = entry(kind=int)
    B_max_stable_x: float = entry(unit="mT")
    B_max_stable_z: float = entry(unit="mT")


@dataclass(frozen=True)
class PartsPart:
    """The parts of an answer (:class:`Parts`) in the file."""

    magnet_grade: str = entry(kind=str)
    magnet_size: str = entry(kind=str)
    silicone: str = entry(kind=str)
    silicones_holding_G: tuple[str, ...] = entry(kind=str, levels=("list",))
    silicone_softer: str | None = entry(kind=str, optional=True)
    silicone_stiffer: str | None = entry(kind=str, optional=True)


@dataclass(frozen=True)
class GradePart:
    """The catalogue's remanence (least, nominal, most) [T] of the magnet's grade and the
    magnetisations [A/m] they give."""

    magnet_B_r: tuple = entry(unit="T", levels=("list",))
    magnet_M_z_spread: tuple = entry(unit="A_per_m", levels=("list",))


@dataclass(frozen=True)
class ResolutionPart:
    """σ_F [N] at rest and worst over the stable box, and (t, θ [rad]) of each worst value."""

    sigma_Fr_0: float = entry(unit="mN")
    sigma_Fz_0: float = entry(unit="mN")
    sigma_Fr_worst: float = entry(unit="mN")
    sigma_Fz_worst: float = entry(unit="mN")
    sigma_Fr_worst_at: tuple = entry(levels=("list",))
    sigma_Fz_worst_at: tuple = entry(levels=("list",))


@dataclass(frozen=True)
class LowPart:
    """σ_F [N] at the lower end of the setting's noise interval."""

    sigma_Fr_0: float = entry("sigma_Fr_0_mN_low", "mN")
    sigma_Fz_0: float = entry("sigma_Fz_0_mN_low", "mN")
    sigma_Fr_worst: float = entry("sigma_Fr_worst_mN_low", "mN")
    sigma_Fz_worst: float = entry("sigma_Fz_worst_mN_low", "mN")


def _part(kind: type, optional: bool = True):
    """An inline part of an answer, left out of the file where the answer has none."""
    return entry(kind=kind, inline=True, optional=optional, omit="none", default=None)


@dataclass(frozen=True)
class AnswerRecord:
    """Every number of a :class:`DesignAnswer` as a file holds it (:func:`answer_json`), in
    SI; each part that the answer lacks (verdict, robust verdict, setting figures, the
    chosen setting, parts, grade, σ_F at the low end of the noise, σ_F) is left out.

    ``saturation_F_z`` [N] is where the chip saturates along the normal path, or, with a
    verdict, the verdict's saturation force (None: never).
    """

    label: str = entry(kind=str)
    H: float = entry(unit="mm")
    G: float = entry(unit="kPa")
    M_z: float | None = entry(unit="A_per_m", optional=True)
    chip: str = entry(kind=str)
    chip_setting: str = entry(kind=str)
    chip_source: str = entry(kind=str)
    noise_x: float | None = entry(unit="uT", optional=True)
    noise_z: float | None = entry(unit="uT", optional=True)
    range_x: float = entry(unit="mT")
    range_z: float = entry(unit="mT")
    F_r_min: float = entry(unit="N")
    F_z_max: float = entry(unit="N")
    Gamma_r_max: float = entry(unit="N_per_T")
    Gamma_z_max: float = entry(unit="N_per_T")
    t_m: float = entry()
    theta_m: float = entry(unit="rad")
    B_max_x: float = entry(unit="mT")
    B_max_z: float = entry(unit="mT")
    saturates: bool = entry(kind=bool)
    saturation_t: float | None = entry(optional=True)
    saturation_theta: float | None = entry(unit="rad", optional=True)
    saturation_axis: str | None = entry(kind=str, optional=True)
    saturation_F_r: float | None = entry(unit="N", optional=True)
    saturation_F_z: float | None = entry(unit="N", optional=True)
    chip_margin_stable_region: float = entry()
    saturates_in_stable_region: bool = entry(kind=bool)
    G_tolerance: float = entry()
    worst_case_factor: float = entry()
    missing: tuple[str, ...] = entry(kind=str, levels=("list",))
    standoff: float = entry(unit="mm")
    verdict: VerdictPart | None = _part(VerdictPart)
    robust_verdict: object = entry(kind=object, omit="none", default=None)
    figures: FiguresPart | None = _part(FiguresPart)
    choice: ChoicePart | None = _part(ChoicePart)
    parts: PartsPart | None = _part(PartsPart)
    grade: GradePart | None = _part(GradePart)
    resolution_low: LowPart | None = _part(LowPart)
    resolution: ResolutionPart | None = _part(ResolutionPart)


def answer_record(a: DesignAnswer) -> AnswerRecord:
    """The record of an answer (:class:`AnswerRecord`)."""
    d, s, chip, v, f, p = a.design, a.saturation, a.chip, a.verdict, a.chip.figures, a.parts
    saturation_F_z = s.F_z if v is None else None if np.isinf(v.F_saturation) \
        else v.F_saturation
    low, r = a.resolution_low, a.resolution
    return AnswerRecord(
        a.label, a.H, a.G, d.M_z, chip.name, chip.setting, chip.source, chip.noise_x,
        chip.noise_z, chip.range_x, chip.range_z, d.F_r_min, d.F_z_max, d.Gamma_r_max,
        d.Gamma_z_max, d.t_m, d.theta_m, s.B_max_x, s.B_max_z, s.saturates, s.t, s.theta,
        s.axis, s.F_r, saturation_F_z, s.region_margin, s.in_region, a.tolerance,
        a.worst_factor, tuple(chip.missing), a.standoff,
        verdict=None if v is None else VerdictPart(v.to_json(), v.met, v.sigma_r, v.sigma_z),
        robust_verdict=None if a.robust is None else a.robust.to_json(),
        figures=None if f is None else FiguresPart(
            {k: x for k, x in f.setting.__dict__.items() if x is not None}, f.words, f.rate,
            f.conversion_time * 1e3, f.lsb_x, f.lsb_z, tuple(f.sigma_x), tuple(f.sigma_z),
            f.noise_source),
        choice=None if a.choice is None else ChoicePart(
            a.choice.holds, a.choice.considered, a.choice.B_max_x, a.choice.B_max_z),
        parts=None if p is None else PartsPart(p.grade, p.size, p.silicone, tuple(p.inside),
                                               p.softer, p.stiffer),
        grade=None if p is None or p.grade == "custom" else _grade_part(p.grade),
        resolution_low=None if low is None else LowPart(
            low.sigma_r_0, low.sigma_z_0, low.sigma_r_worst, low.sigma_z_worst),
        resolution=None if r is None else ResolutionPart(
            r.sigma_r_0, r.sigma_z_0, r.sigma_r_worst, r.sigma_z_worst, tuple(r.where_r),
            tuple(r.where_z)))


def _grade_part(name: str) -> GradePart:
    g = grade(name)
    return GradePart((g.B_r_min, g.B_r, g.B_r_max), tuple(g.M_z(MU0)))


def answer_json(a: DesignAnswer) -> dict:
    """Every number of an answer, in user units with the unit in each key (for files):
    :class:`AnswerRecord`'s document."""
    return to_json(answer_record(a))
