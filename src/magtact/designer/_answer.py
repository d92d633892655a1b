"""The designer's answer for one design: resolution with a named Hall chip, measuring range,
the chip's limits along the paths, and the margin for the tolerance of G (docs/method.md §10).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
from scipy.optimize import minimize

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
from ..study import MU0, HallChip, Study, from_si, hall_chip, mm, mt
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


def answer_json(a: DesignAnswer) -> dict:
    """Every number of an answer, in user units with the unit in each key (for files)."""
    r, s = a.resolution, a.saturation
    out = {
        "label": a.label, "H_mm": mm(a.H), "G_kPa": from_si(a.G, "kPa"),
        "M_z_A_per_m": None if a.design.M_z is None else from_si(a.design.M_z, "A_per_m"),
        "chip": a.chip.name, "chip_setting": a.chip.setting, "chip_source": a.chip.source,
        "noise_x_uT": None if a.chip.noise_x is None else from_si(a.chip.noise_x, "uT"),
        "noise_z_uT": None if a.chip.noise_z is None else from_si(a.chip.noise_z, "uT"),
        "range_x_mT": mt(a.chip.range_x), "range_z_mT": mt(a.chip.range_z),
        "F_r_min_N": a.design.F_r_min, "F_z_max_N": a.design.F_z_max,
        "Gamma_r_max_N_per_T": a.design.Gamma_r_max, "Gamma_z_max_N_per_T": a.design.Gamma_z_max,
        "t_m": a.design.t_m, "theta_m_rad": a.design.theta_m,
        "B_max_x_mT": mt(s.B_max_x), "B_max_z_mT": mt(s.B_max_z),
        "saturates": s.saturates, "saturation_t": s.t, "saturation_theta_rad": s.theta,
        "saturation_axis": s.axis, "saturation_F_r_N": s.F_r, "saturation_F_z_N": s.F_z,
        "chip_margin_stable_region": s.region_margin,
        "saturates_in_stable_region": s.in_region,
        "G_tolerance": a.tolerance, "worst_case_factor": a.worst_factor,
        "missing": list(a.chip.missing), "standoff_mm": mm(a.standoff),
    }
    if a.verdict is not None:
        v = a.verdict
        out |= {"verdict": v.to_json(), "meets_requirements": v.met,
                "sigma_Fr_required_loads_mN": from_si(v.sigma_r, "mN"),
                "sigma_Fz_required_loads_mN": from_si(v.sigma_z, "mN"),
                "saturation_F_z_N": None if np.isinf(v.F_saturation) else v.F_saturation}
    if a.robust is not None:
        out["robust_verdict"] = a.robust.to_json()
    f = a.chip.figures
    if f is not None:
        out |= {"setting": {k: v for k, v in f.setting.__dict__.items() if v is not None},
                "setting_words": f.words, "sample_rate_Hz": f.rate,
                "conversion_time_ms": f.conversion_time * 1e3,
                "LSB_x_uT": from_si(f.lsb_x, "uT"), "LSB_z_uT": from_si(f.lsb_z, "uT"),
                "noise_x_uT_interval": [from_si(v, "uT") for v in f.sigma_x],
                "noise_z_uT_interval": [from_si(v, "uT") for v in f.sigma_z],
                "noise_source": f.noise_source}
    if a.choice is not None:
        out |= {"setting_holds_field": a.choice.holds,
                "settings_compared": a.choice.considered,
                "B_max_stable_x_mT": mt(a.choice.B_max_x),
                "B_max_stable_z_mT": mt(a.choice.B_max_z)}
    if a.parts is not None:
        p = a.parts
        out |= {"magnet_grade": p.grade, "magnet_size": p.size, "silicone": p.silicone,
                "silicones_holding_G": list(p.inside), "silicone_softer": p.softer,
                "silicone_stiffer": p.stiffer}
        if p.grade != "custom":
            g = grade(p.grade)
            out["magnet_B_r_T"] = [g.B_r_min, g.B_r, g.B_r_max]
            out["magnet_M_z_spread_A_per_m"] = list(g.M_z(MU0))
    low = a.resolution_low
    if low is not None:
        out |= {"sigma_Fr_0_mN_low": from_si(low.sigma_r_0, "mN"),
                "sigma_Fz_0_mN_low": from_si(low.sigma_z_0, "mN"),
                "sigma_Fr_worst_mN_low": from_si(low.sigma_r_worst, "mN"),
                "sigma_Fz_worst_mN_low": from_si(low.sigma_z_worst, "mN")}
    if r is not None:
        out |= {"sigma_Fr_0_mN": from_si(r.sigma_r_0, "mN"),
                "sigma_Fz_0_mN": from_si(r.sigma_z_0, "mN"),
                "sigma_Fr_worst_mN": from_si(r.sigma_r_worst, "mN"),
                "sigma_Fz_worst_mN": from_si(r.sigma_z_worst, "mN"),
                "sigma_Fr_worst_at": list(r.where_r), "sigma_Fz_worst_at": list(r.where_z)}
    return out
