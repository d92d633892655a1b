"""The error budget of a design: everything besides the force that moves the field, as a false
force ΔF = J ΔB in newtons (docs/method.md §12).

J = ∂F/∂B is the metamodels' Jacobian (:func:`magtact.sensitivity.dF_dB`); every row is a
false force per component (F_r, F_z), at rest (t = 0) and worst over the design's stable region
t ≤ t_m, θ ≤ θ_m, with the assumptions it rests on.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from .._errors import MagtactError
from .._files import UnreadableFile, read_result
from .._records import entry, from_json_or_none, keys, to_json
from .._sensor import Sensor
from ..designer import HallChip, hall_chip, resolution
from ..doe import check_design
from ..magnetics import hall_field
from ..metamodel import ModelSet
from ..optimise import DesignResult, per_design
from ..sensitivity import dF_dB, gamma
from ..study import Study, from_si, mm
from ..viscoelastic import (
    MEASURED_HYSTERESIS,
    SiliconeSweep,
    design_forces,
    implied_ratio,
    relaxation_of,
    time_json,
    time_response,
    unknown_time_json,
)
from . import _array, _fabrication

#: Points per side of the grid over the stable region (worst of the temperature rows and the
#: Jacobians the neighbours' crosstalk is read through).
N_BOX = 41
#: Components of every row.
COMPONENTS = ("F_r", "F_z")
#: Sources of the cited defaults (docs/method.md §12).
SOURCES = {
    "remanence_tc": "Advanced Magnetic Materials, 'What are temperature coefficients α and β "
                    "of permanent magnets' (advancedmagnets.com): typical sintered NdFeB "
                    "α = −0.09 to −0.12 %/°C; N48SH −0.119 %/°C from 20 to 150 °C",
    "earth_field": "World Magnetic Model / IGRF total intensity: 25 000 to 65 000 nT at the "
                   "Earth's surface (NOAA NCEI; as quoted in 'Earth's magnetic field', "
                   "Wikipedia, section Intensity)",
}


@dataclass(frozen=True)
class BudgetRow:
    """One row of the budget: a false force [N] of one force component.

    ``at_rest``: at t = 0; ``worst``: the largest over the stable region (NaN where a row has
    no such value, null in the file). ``group``: noise, temperature, stray field, neighbours,
    fabrication, model.
    """

    name: str = entry(kind=str)
    group: str = entry(kind=str)
    component: str = entry(kind=str)
    at_rest: float = entry(unit="mN", null_nan=True)
    worst: float = entry(unit="mN", null_nan=True)
    assumptions: str = entry(kind=str)

    def to_json(self) -> dict:
        """The row in ``budget.json``: forces in mN, a value that is not finite as null."""
        return to_json(self)

    @classmethod
    def from_json(cls, data) -> BudgetRow | None:
        """The row :meth:`to_json` wrote, in SI; None for anything else."""
        return from_json_or_none(cls, data)


@dataclass(frozen=True)
class Noise:
    """The field noise (σ_x, σ_z) [T] of a budget's noise row, as ``budget.json`` holds it."""

    x: float = entry("noise_x_uT", "uT")
    z: float = entry("noise_z_uT", "uT")


@dataclass(frozen=True)
class Resolution:
    """The resolution σ_F [N] of a design, as ``budget.json``'s ``resolution_mN`` holds it (the
    order of :attr:`Budget.resolution`)."""

    F_r_at_rest: float = entry("F_r_at_rest", "mN", null_nan=True)
    F_z_at_rest: float = entry("F_z_at_rest", "mN", null_nan=True)
    F_r_worst: float = entry("F_r_worst", "mN", null_nan=True)
    F_z_worst: float = entry("F_z_worst", "mN", null_nan=True)


#: Keys of the resolution in ``budget.json`` (the order of :attr:`Budget.resolution`).
RESOLUTION_KEYS = keys(Resolution)


@dataclass(frozen=True)
class ArrayInfo:
    """The array of a budget (:attr:`Budget.array` holds it as a dict of these names, in SI):
    the layout, the pitch of the neighbour rows [m], the smallest pitch [m] at which the
    crosstalk stays below the resolution (None without a noise figure) and the worst
    crosstalk [N] of one neighbour and of all."""

    layout: str = entry(kind=str)
    rings: int = entry(kind=int)
    pitch: float = entry(unit="mm")
    pitch_given: bool = entry(kind=bool)
    smallest_pitch: float | None = entry(unit="mm", optional=True)
    criterion: str = entry(kind=str)
    one_neighbour_worst: tuple = entry(unit="mN", levels=("list",), null_nan=True)
    all_neighbours_worst: tuple = entry(unit="mN", levels=("list",), null_nan=True)


#: Units of the fabrication figures that are not false forces in mN (each key carries its
#: unit: ``Gamma_r_0_N_per_T``, ``cal_r_mN``).
FABRICATION_UNITS = {"Gamma_r_0": "N_per_T", "Gamma_z_0": "N_per_T", "F_r_min": "N",
                     "F_z_max": "N"}


@dataclass(frozen=True)
class Fabrication:
    """The Monte Carlo of fabrication tolerances of a budget: percentiles (5/50/95 %) of each
    response, the linearised σ of each response per input, the inputs' 1 σ, in SI."""

    percentiles: dict = entry("percentiles_5_50_95", "mN", levels=("map", "list"),
                              key_units=FABRICATION_UNITS)
    samples: int = entry(kind=int)
    seed: int = entry(kind=int)
    by_input: dict = entry("sigma_per_input_linear", "mN", levels=("map", "map"),
                           key_units=FABRICATION_UNITS)
    sigmas: dict = entry("inputs_1_sigma", levels=("map",))


@dataclass(frozen=True)
class Environment:
    """The environment of a budget (:attr:`Budget.environment` holds it as a dict of these
    names, in SI): temperature change [K], the remanence's and the chip's temperature
    coefficients [1/K], the Earth's and a stray field [T], the field at rest [T] and the
    sources of the cited defaults."""

    delta_T: float = entry(unit="K")
    remanence_tc: float = entry(unit="pct_per_K")
    remanence_tc_tolerance: float = entry(unit="pct_per_K")
    chip_drift: float = entry(unit="pct_per_K")
    earth_field: float = entry(unit="uT")
    stray_field: float = entry(unit="uT")
    B_rest: tuple = entry(unit="mT", levels=("list",))
    sources: dict = entry(kind=str, levels=("map",))


@dataclass(frozen=True)
class Budget:
    """The error budget of design (H [m], G [Pa][, M_z]) (docs/method.md §12).

    Attributes
    ----------
    rows : tuple of BudgetRow
        In newtons.
    noise : (σ_x, σ_z) [T] or None
        The field noise of the noise row; ``noise_source`` says where it comes from.
    resolution : (σ_Fr,0, σ_Fz,0, σ_Fr,worst, σ_Fz,worst) [N] or None
    array : dict
        The names of :class:`ArrayInfo` and their values (empty without an array).
    fabrication : Fabrication or None
        The Monte Carlo of fabrication tolerances.
    environment : dict
        The names of :class:`Environment` and their values.
    not_modelled : tuple of str
    time : dict
        The time entry as ``budget.json`` holds it (read by
        :meth:`magtact.viscoelastic.TimeRecord.from_json`).
    """

    label: str = entry(kind=str)
    H: float = entry(unit="mm")
    G: float = entry(unit="kPa")
    M_z: float | None = entry(unit="A_per_m", optional=True)
    t_m: float = entry()
    theta_m: float = entry(unit="rad")
    chip: str = entry(kind=str)
    noise: tuple[float, float] | None = entry(kind=Noise, shape="tuple", inline=True,
                                              optional=True)
    noise_source: str = entry(kind=str)
    rows: tuple[BudgetRow, ...] = entry(kind=BudgetRow, levels=("list",))
    not_modelled: tuple[str, ...] = entry(kind=str, levels=("list",), default=(), kw_only=True)
    resolution: tuple[float, float, float, float] | None = entry(
        "resolution_mN", kind=Resolution, shape="tuple", optional=True, omit="none")
    array: dict = entry(kind=ArrayInfo, shape="dict", default_factory=dict)
    fabrication: Fabrication | None = entry(kind=Fabrication, omit="none", default=None)
    environment: dict = entry(kind=Environment, shape="dict", omit="empty",
                              default_factory=dict)
    time: dict = entry(kind=object, omit="empty", default_factory=dict)

    def largest(self, n: int = 3) -> list[BudgetRow]:
        """The ``n`` rows with the largest worst-case false force."""
        rows = [r for r in self.rows if math.isfinite(r.worst)]
        return sorted(rows, key=lambda r: -r.worst)[:n]

    def __str__(self) -> str:
        """The rows, largest first, in mN (3 significant figures; at most 25 lines)."""
        from .._display import budget_rows, text_block

        return text_block(*budget_rows(self))

    def _repr_html_(self) -> str:
        from .._display import budget_rows, html_block

        return html_block(*budget_rows(self))

    def to_json(self) -> dict:
        """Every number in user units, the unit in each key (mN, mm, kPa, µT): the budget as
        ``budget.json`` holds it."""
        return budget_json(self)

    @classmethod
    def from_json(cls, data) -> Budget | None:
        """The budget :meth:`to_json` wrote, back in SI (``time`` as the file holds it, in mN
        and s); None for anything else."""
        return from_json_or_none(cls, data)


@dataclass(frozen=True)
class BudgetFile:
    """``budget.json``: the error budgets of a folder (e.g. the chosen and the original design
    of a run), the study's name and the run that wrote it (``run_id`` as the file gives it,
    so that a value that is not text never names a run by accident)."""

    title: str = entry(kind=str, default="Error budget", kw_only=True)
    study: str = entry(kind=str, default="")
    run_id: str | None = entry(kind=object, default=None, kw_only=True)
    budgets: tuple[Budget, ...] = entry(kind=Budget, levels=("list",), kw_only=True)

    def to_json(self) -> dict:
        return to_json(self)

    @classmethod
    def from_json(cls, data, where: str = "budget.json") -> BudgetFile | None:
        """The file :meth:`to_json` wrote; None for anything else."""
        return from_json_or_none(cls, data, where)

    @classmethod
    def read(cls, path: str | Path) -> BudgetFile | None:
        """:meth:`from_json` of the file ``path``; None where it is missing or not JSON."""
        try:
            return cls.from_json(read_result(path, "json"), str(path))
        except UnreadableFile:
            return None


#: A false force below this fraction of the largest of its row is round-off of a zero (e.g. a
#: shear force at rest, zero by symmetry) and is written as 0.
ROUND_OFF = 1e-9


def _rows(name, group, at_rest, worst, assumptions) -> list[BudgetRow]:
    scale = max(float(np.max(np.abs(at_rest))), float(np.max(np.abs(worst))))
    tidy = [[0.0 if abs(float(v)) <= ROUND_OFF * scale else float(v) for v in x]
            for x in (at_rest, worst)]
    return [BudgetRow(name, group, c, a, w, assumptions)
            for c, a, w in zip(COMPONENTS, *tidy, strict=True)]


def noise_given(chip: HallChip, noise: tuple[float, float]) -> tuple[HallChip, str]:
    """The chip with the field noise ``noise`` = (σ_x, σ_z) [T] in place of its own, and the
    sentence that says so (the budget's ``noise_source``)."""
    given = ", ".join(f"{from_si(v, 'uT'):.3g}" for v in noise)
    own = (("that of the setting magtact picks per design" if chip.picked else "none")
           if chip.noise is None
           else ", ".join(f"{from_si(v, 'uT'):.3g}" for v in chip.noise) + f" µT at {chip.setting}")
    said = (f"given as {given} µT (x, z), in place of the chip's own figure "
            f"({chip.name}: {own})")
    return replace(chip, noise_x=float(noise[0]), noise_z=float(noise[1])), said


def error_budget(models: ModelSet, study: Study, H: float, G: float, M_z: float | None = None,
                 *, label: str = "design", design: DesignResult | None = None,
                 noise: tuple[float, float] | None = None, dataset=None,
                 seeds: dict | None = None, samples: int | None = None,
                 chip: HallChip | None = None, sensor: Sensor | None = None) -> Budget:
    """The error budget of design (H [m], G [Pa][, M_z [A/m]]) (docs/method.md §12).

    Parameters
    ----------
    models : ModelSet
        The metamodels (J = ∂F/∂B from them).
    study : Study
        ``[hall]`` chip, ``[environment]``, ``[array]``, ``[tolerances]``.
    design : DesignResult, optional
        The design's extrema (:func:`magtact.optimise.per_design`), if already computed.
    noise : (σ_x, σ_z) [T], optional
        Field noise for the noise row where the study's chip has none (``hall.noise_*_uT``);
        the study's figure wins where it has one.
    dataset : xarray.Dataset, optional
        The DOE data set of the models (its ``err_F_z``, ``err_F_r``: the mesh's error).
    seeds : dict, optional
        A seed study (``publication.json`` of ``magtact reproduce``): its ``spread``.
    samples : int, optional
        Monte-Carlo samples; default ``tolerances.samples``.
    chip : HallChip, optional
        The chip at the setting the design's answer uses (:attr:`DesignAnswer.chip`); default
        the study's ``[hall]`` chip.
    sensor : Sensor, optional
        The design's parts: its magnet's magnetisation and the chip's standoff
        (:attr:`DesignAnswer.sensor`); default the study's own.

    Returns
    -------
    Budget

    Raises
    ------
    MagtactError
        For a study with geometric design variables besides H (fix them first).

    Notes
    -----
    Rows (each ΔF = J ΔB unless said otherwise):

    - noise: σ_F = √diag(J Σ_B Jᵀ) (:func:`magtact.designer.resolution`);
    - temperature: ΔB = α B ΔT (remanence, uncompensated), δα B ΔT (after compensation with
      the chip's temperature channel, α known to ± δα), s B ΔT (chip sensitivity drift);
    - stray fields: largest |J b| over directions of |b| = b: b Γ_k per component; the turn
      through 180°: 2 b Γ_k;
    - neighbours: the change of their superposed field when loaded (:mod:`._array`);
    - fabrication: one calibration shared by all units (:mod:`._fabrication`), 95th
      percentile;
    - model: the mesh's error × the force, the metamodels' held-out error, the seeds' spread;
    - time: the silicone's relaxation (:mod:`magtact.viscoelastic`): the hysteresis of a press
      and release in ``environment.press_time_s`` and the creep of a press held
      ``environment.hold_s``, read by a sensor calibrated on ``environment.calibrated_on``
      (not ΔF = J ΔB: the reading G_cal f(u) against the hereditary force).
    """
    if study.geometric_variables:
        raise MagtactError("the error budget is computed for one geometry: fix the geometric "
                           f"design variables ({', '.join(study.geometric_variables)}) with "
                           "study.at(...) and use models fitted to it")
    check_design(study, H, dataset)  # outside the data's domain the models extrapolate
    own = chip is None
    chip = hall_chip(study) if own else chip
    env, arr = study.environment, study.array
    if design is None:
        design = per_design(models, H, G, study, M_z)
    scale = design.field_scale
    if sensor is None:
        sensor = Sensor.of_study(study, H, G, M_z)
    place = {"M_z": sensor.M_z, "standoff": sensor.standoff}  # the design's magnet and chip
    rows: list[BudgetRow] = []
    not_modelled = ["the elastomer's mechanical coupling between taxels (only their fields "
                    "are superposed)",
                    "the silicone's G(T): no source for the temperature coefficient of the "
                    "elastomer's modulus",
                    "temperature gradients between magnet and chip (the chip's temperature "
                    "channel is taken as the magnet's temperature)"]

    # ---- noise -----------------------------------------------------------------------------
    if chip.noise is not None:
        noise_used, noise_source = chip.noise, (f"{chip.name}: [hall] of the study" if own
                                                else f"{chip.name} at {chip.setting}")
    elif noise is not None:
        noise_used = (float(noise[0]), float(noise[1]))
        noise_source = "given to the budget (the study's [hall] gives no noise figure)"
        chip = replace(chip, noise_x=noise_used[0], noise_z=noise_used[1])
    else:
        noise_used, noise_source = None, f"not known: give {' and '.join(chip.missing)}"
    res = None
    if noise_used is not None:
        r = resolution(models, study, design, chip)
        res = (r.sigma_r_0, r.sigma_z_0, r.sigma_r_worst, r.sigma_z_worst)
        rows += _rows("noise (1 σ)", "noise", res[:2], res[2:],
                      f"RMS field noise {from_si(noise_used[0], 'uT'):.3g} / "
                      f"{from_si(noise_used[1], 'uT'):.3g} µT (x / z), {noise_source}; "
                      "σ_F = √diag(J Σ_B Jᵀ)")

    # ---- Jacobians and field over the stable region -------------------------------------
    T, TH = np.meshgrid(np.linspace(0.0, design.t_m, N_BOX),
                        np.linspace(0.0, design.theta_m, N_BOX), indexing="ij")
    J = dF_dB(models, T, TH, H, G) / scale  # (N, N, 2, 2)
    J0 = dF_dB(models, 0.0, 0.0, H, G) / scale
    B = np.stack(hall_field(study, T, TH, H, solver="exact", **place), axis=-1)  # (N, N, 2)
    B0 = np.array([float(v) for v in hall_field(study, 0.0, 0.0, H, solver="exact", **place)])

    def through(dB_grid, dB_rest):
        worst = np.abs(np.einsum("...ij,...j->...i", J, dB_grid)).reshape(-1, 2).max(axis=0)
        return np.abs(J0 @ dB_rest), worst

    # ---- temperature -----------------------------------------------------------------------
    dT = env.delta_T
    a, da, sd = env.remanence_tc, env.remanence_tc_tolerance, env.chip_drift
    rows += _rows(f"temperature: magnet remanence, uncompensated (ΔT = {dT:g} K)",
                  "temperature", *through(a * dT * B, a * dT * B0),
                  f"ΔB = α B ΔT with α = {100 * a:.3g} %/K (environment.remanence_tc_pct_per_K;"
                  f" {SOURCES['remanence_tc']}); exact field at the Hall point")
    rows += _rows(f"temperature: remanence after compensation (ΔT = {dT:g} K)", "temperature",
                  *through(da * dT * B, da * dT * B0),
                  f"the chip's temperature channel corrects α B ΔT with the nominal α; α is "
                  f"known to ± {100 * da:.3g} %/K (environment.remanence_tc_tolerance_pct_per_K"
                  ", the width of the typical NdFeB range when the grade's own figure is not "
                  "given): ΔB = δα B ΔT")
    if sd != 0:
        rows += _rows(f"temperature: chip sensitivity drift, uncompensated (ΔT = {dT:g} K)",
                      "temperature", *through(sd * dT * B, sd * dT * B0),
                      f"the chip reads (1 + s ΔT) B, s = {100 * sd:.3g} %/K "
                      "(environment.chip_drift_pct_per_K)")
    else:
        not_modelled.append("the Hall chip's sensitivity drift: no cited figure (give "
                            "environment.chip_drift_pct_per_K)")

    # ---- stray fields ----------------------------------------------------------------------
    g0 = np.array([float(v) for v in gamma(models, 0.0, 0.0, H, G)]) / scale
    gw = np.array([design.Gamma_r_max, design.Gamma_z_max])
    for what, b, key in (("Earth's field", env.earth_field, "earth_field_uT"),
                         ("stray field", env.stray_field, "stray_field_uT")):
        if b <= 0:
            continue
        src = f"; {SOURCES['earth_field']}" if what == "Earth's field" else ""
        rows += _rows(f"{what}, worst orientation", "stray field", b * g0, b * gw,
                      f"|b| = {from_si(b, 'uT'):.3g} µT (environment.{key}{src}); largest "
                      "|J b| over directions: |b| Γ_k (a 3-axis field of that magnitude in "
                      "any direction)")
        rows += _rows(f"{what}, sensor turned through 180°", "stray field", 2 * b * g0,
                      2 * b * gw, "calibrated in one orientation and turned over: ΔB = 2 b")

    # ---- neighbours ------------------------------------------------------------------------
    pitch = arr.pitch if arr.pitch > 0 else 2 * study.body.R
    ct0 = _array.crosstalk(study, H, design.t_m, design.theta_m, J0, pitch, arr.layout,
                           arr.rings, **place)
    ctw = _array.crosstalk(study, H, design.t_m, design.theta_m, J, pitch, arr.layout,
                           arr.rings, **place)
    rows += _rows(f"neighbours loaded, pitch {mm(pitch):.3g} mm ({arr.layout}, {arr.rings} "
                  f"ring{'s' if arr.rings > 1 else ''})", "neighbours", ct0["worst"],
                  ctw["worst"],
                  ("array.pitch_mm" if arr.pitch > 0 else "no array.pitch_mm given: touching "
                   "bodies, pitch = 2 body.R") + "; each neighbour the same design loaded "
                  "through its stable region in any direction, alone or all alike; their "
                  "fields superposed (exact cylinder field); the field at rest is an offset "
                  "a calibration removes; mechanical coupling not modelled")
    smallest = None
    if res is not None:
        smallest = _array.smallest_pitch(study, H, design.t_m, design.theta_m, J,
                                         (res[2], res[3]), arr.layout, arr.rings, **place)
    array_info = asdict(ArrayInfo(
        arr.layout, arr.rings, pitch, arr.pitch > 0, smallest,
        "the worst crosstalk (one neighbour or all loaded alike, over this taxel's stable "
        "region) at most the worst resolution σ_F in both components",
        [float(v) for v in ctw["one"]], [float(v) for v in ctw["all"]]))

    # ---- fabrication -----------------------------------------------------------------------
    tol = study.tolerances
    n = tol.samples if samples is None else int(samples)
    unit = _fabrication.unit_context(models, study, H, G, sensor.M_z,
                                     (design.F_r_min, design.F_z_max), noise_used,
                                     sensor.standoff)
    mc = _fabrication.monte_carlo(lambda e: _fabrication.responses(unit, e),
                                  len(_fabrication.INPUTS), n, tol.seed)
    pct = _fabrication.percentiles(mc)
    by_input = _fabrication.contributions(lambda e: _fabrication.responses(unit, e),
                                          len(_fabrication.INPUTS))
    nominal = {"Gamma_r_0": g0[0], "Gamma_z_0": g0[1]}
    if res is not None:
        nominal |= {"sigma_Fr_0": res[0], "sigma_Fz_0": res[1]}
    for k, v in nominal.items():  # relative to the nominal unit → the metamodels' values
        pct[k] = [float(p * v) for p in pct[k]]
        by_input[k] = [float(c * v) for c in by_input[k]]
    assumptions_fab = (f"{n} units, seed {tol.seed}; 1 σ: G {100 * tol.G:.3g} %, remanence "
                       f"{100 * tol.remanence:.3g} %, magnet diameter / height "
                       f"{mm(tol.magnet_diameter):.3g} / {mm(tol.magnet_height):.3g} mm, chip "
                       f"lateral / vertical {mm(tol.chip_lateral):.3g} / "
                       f"{mm(tol.chip_vertical):.3g} mm, tilt "
                       f"{math.degrees(tol.magnet_tilt):.3g}° ([tolerances]); field by "
                       "magpylib, linearised at rest")
    rows += _rows("fabrication: one calibration for all units, not tared (95 %)",
                  "fabrication", (pct["offset_r"][2], pct["offset_z"][2]),
                  (pct["offset_r"][2], pct["offset_z"][2]),
                  "the field at rest of a unit differs from the nominal's: a false force "
                  "until it is tared; " + assumptions_fab)
    rows += _rows("fabrication: one calibration for all units, tared, at full range (95 %)",
                  "fabrication", (0.0, 0.0), (pct["cal_r"][2], pct["cal_z"][2]),
                  "a unit read with the nominal unit's J: error (J_nom J_i⁻¹ − I) F at the "
                  "full-range loads (F_r,min, F_z,max); " + assumptions_fab)

    # ---- the model's own error -------------------------------------------------------------
    rows += _model_rows(models, study, design, dataset, seeds)

    # ---- time: the silicone's relaxation -----------------------------------------------------
    time_rows, time_info = _time_rows(models, study, design, sensor.silicone)
    rows += time_rows
    if not time_rows:
        not_modelled.append("the silicone's relaxation in time (hysteresis, creep): "
                            + time_info["source"])

    inputs = _fabrication.INPUTS
    fabrication = Fabrication(
        pct, n, tol.seed, {k: dict(zip(inputs, v, strict=True)) for k, v in by_input.items()},
        dict(zip(inputs, _fabrication.sigmas(study).tolist(), strict=True)))
    env_info = asdict(Environment(dT, a, da, sd, env.earth_field, env.stray_field,
                                  B0.tolist(), SOURCES))
    return Budget(label, float(H), float(G), None if M_z is None else float(M_z), design.t_m,
                  design.theta_m, chip.name, noise_used, noise_source, tuple(rows),
                  not_modelled=tuple(not_modelled), resolution=res, array=array_info,
                  fabrication=fabrication, environment=env_info, time=time_info)


def _time_rows(models, study, design, silicone: str) -> tuple[list[BudgetRow], dict]:
    """The time rows (hysteresis, creep) and the ``time`` entry of budget.json for a body of
    ``silicone``; no rows where the silicone's relaxation is not known. The MagOne's measured
    hysteresis is compared in either case (the smallest one-term relaxation that reaches it)."""
    env = study.environment
    prony, source = relaxation_of(study, design.G, silicone)
    g_min, tau_at = implied_ratio(design_forces(models, design.H, 0.0), design.t_m,
                                  env.press_time, MEASURED_HYSTERESIS, env.calibrated_on)
    if prony is None:
        return [], unknown_time_json(source, env.press_time, env.hold, env.calibrated_on,
                                     g_min, tau_at)
    r = time_response(models, study, design.H, design.G, design.t_m, design.theta_m, prony,
                      implied=(g_min, tau_at))
    modulus = "long-time G_∞" if env.calibrated_on == "long" else "instantaneous G(0)"
    history = (f"the sensor calibrated on the {modulus} (environment.calibrated_on); presses "
               "to t_m at θ = 0 and θ_m, the worst of the two; relaxation "
               f"{prony.source}; quasi-linear viscoelastic body F(t) = ∫ G(t − s) df(u(s))")
    rows = _rows(f"time: hysteresis, press and release in {env.press_time:g} s", "time",
                 (0.0, 0.0), r.hysteresis,
                 "largest difference of the readings loading and unloading at equal true "
                 f"force, load rising linearly in environment.press_time_s; {history}")
    rows += _rows(f"time: creep over a {env.hold:g} s hold", "time", (0.0, 0.0), r.creep,
                  f"change of the reading while a full press is held at constant force for "
                  f"environment.hold_s after a press in environment.press_time_s; {history}")
    return rows, time_json(r, source=prony.source,
                           silicones=_silicone_sweeps(models, study, design))


def _silicone_sweeps(models, study, design) -> dict[str, SiliconeSweep]:
    """The hysteresis of F_z against the press time of the design's normal press for every
    catalogue silicone with a cited relaxation (its ratios and times at the design's G), by
    name."""
    from ..parts import SILICONES
    from ..viscoelastic import Prony, rate_sweep

    out = {}
    f = design_forces(models, design.H, 0.0)
    for name, sil in SILICONES.items():
        if sil.relaxation is None:
            continue
        r = sil.relaxation
        sw = rate_sweep(Prony.from_ratios(design.G, r.g, r.tau, r.source), f, design.t_m,
                        calibrated_on=study.environment.calibrated_on, n=200)
        out[name] = SiliconeSweep.of(sw, r.source)
    return out


def _model_rows(models, study, design, dataset, seeds) -> list[BudgetRow]:
    """The model's own error: mesh discretisation, held-out error, seed spread."""
    rows: list[BudgetRow] = []
    G, H = design.G, design.H
    F_ends = np.array([abs(design.F_r_min), design.F_z_max])
    if dataset is not None and "err_F_z" in dataset:
        Hs = np.asarray(dataset["H"].values)
        i = int(np.argmin(np.abs(Hs - H)))
        err = [float(np.nanmax(np.abs(dataset[f"err_{k}"].values[:, i]))) for k in COMPONENTS]
        rows += _rows("model: mesh discretisation", "model", (0.0, 0.0), np.array(err) * F_ends,
                      f"largest relative change of the paths at H = {mm(Hs[i]):.3g} mm against "
                      "the next finer mesh (err_F_r: min over t of F_r; err_F_z: F_z at t = 1)"
                      " times |F_r,min|, F_z,max; forces vanish at rest")
    held = []
    for k in ("f_r", "f_z"):
        acc = (getattr(models[k], "info", {}) or {}).get("accuracy", {}).get("test", {})
        held.append(acc.get("max_abs_err"))
    if all(v is not None for v in held):
        v = G * np.array(held, dtype=float)
        rows += _rows("model: metamodels' held-out error", "model", v, v,
                      "largest absolute error of f_r, f_z on the held-out (θ, H) paths, "
                      "times G")
    spread = ((seeds or {}).get("spread") or {}).get(models.definition) or {}
    if dataset is not None and all(f"acc_{k}" in spread for k in ("f_r", "f_z")):
        span = np.array([float((dataset[k] / dataset["G"]).max() - (dataset[k] / dataset["G"])
                               .min()) for k in COMPONENTS]) * G
        worst = np.array([spread[f"acc_{k}"]["max"] for k in ("f_r", "f_z")]) * span
        rows += _rows(f"model: GP seed spread ({spread['acc_f_z'].get('n', '?')} seeds)",
                      "model", worst, worst,
                      "the worst seed's held-out error over the data's range of F/G, times "
                      "that range at this G")
    return rows


# ---- files -------------------------------------------------------------------------------


def budget_json(b: Budget) -> dict:
    """Every number of a budget in user units, the unit in each key (mN, mm, kPa, µT)."""
    return to_json(b)


def budget_card_rows(budgets, n: int = 3) -> list[list[str]]:
    """Rows for the design card, one column per budget (a :class:`Budget` or a sequence of
    them, e.g. the chosen and the original design): the ``n`` largest rows of the first
    budget in words, each with its worst and at-rest false force, and the smallest array
    pitch for crosstalk below the resolution."""
    budgets = [budgets] if isinstance(budgets, Budget) else list(budgets)

    def force(v: float) -> str:  # mN, or N from 1 N up
        return f"{v:.3g} N" if abs(v) >= 1.0 else f"{from_si(v, 'mN'):.3g} mN"

    def cell(b: Budget, name: str, component: str) -> str:
        for r in b.rows:
            if r.name == name and r.component == component:
                return f"{force(r.worst)} worst, {force(r.at_rest)} at rest"
        return "—"

    def label(r: BudgetRow) -> str:  # a time row names the relaxation it rests on
        if r.group != "time":
            return f"error budget: {r.name} ({r.component})"
        return (f"error budget: {r.name} ({r.component}; relaxation "
                f"{budgets[0].time.get('source', '')})")

    largest = budgets[0].largest(n)
    out = [[label(r), *(cell(b, r.name, r.component) for b in budgets)] for r in largest]
    # the time rows always: the larger component of each, unless already among the largest
    shown = {r.name for r in largest}
    time_rows = {}
    for r in budgets[0].rows:
        if r.group == "time" and r.name not in shown and \
                (r.name not in time_rows or r.worst > time_rows[r.name].worst):
            time_rows[r.name] = r
    out += [[label(r), *(cell(b, r.name, r.component) for b in budgets)]
            for r in time_rows.values()]
    if not any(r.group == "time" for r in budgets[0].rows) and budgets[0].time:
        out.append(["error budget: time (hysteresis, creep)",
                    *("not known: " + b.time.get("source", "") if b.time else "—"
                      for b in budgets)])
    pitches = [b.array.get("smallest_pitch") for b in budgets]
    if any(p is not None for p in pitches):
        out.append([f"smallest {budgets[0].array['layout']} array pitch for crosstalk below "
                    "the resolution", *("—" if p is None else f"{mm(p):.3g} mm"
                                        for p in pitches)])
    return out


def write_budget_outputs(models: ModelSet, study: Study, designs, folder, figures=None, *,
                         noise=None, dataset=None, seeds=None, run_id: str | None = None
                         ) -> Path:
    """Write ``folder/budget.json`` (every number, :func:`budget_json`) for ``designs``.

    Parameters
    ----------
    designs : sequence of (label, DesignResult)
        E.g. the chosen and the original design of a run.
    figures : callable, optional
        ``figures(doc, folder)`` draws the figures of the JSON document (e.g.
        :func:`magtact.report.budget_figures`).
    noise, dataset, seeds
        As in :func:`error_budget`.
    run_id : str, optional
        The identifier of the run that writes the folder (``run.json``'s ``run_id``): the
        report shows a budget only if it names the report's run.

    Returns
    -------
    Path
        The JSON file.
    """
    budgets = []
    for label, d in designs:
        if not isinstance(d, DesignResult):
            raise MagtactError(f"design {label!r}: expected a DesignResult, got "
                               f"{type(d).__name__}")
        budgets.append(error_budget(models, study, d.H, d.G, d.M_z, label=label, design=d,
                                    noise=noise, dataset=dataset, seeds=seeds))
    return write_budgets(budgets, study, folder, figures, run_id=run_id)


def write_budgets(budgets, study: Study, folder, figures=None, *, run_id: str | None = None
                  ) -> Path:
    """Write ``folder/budget.json`` of computed budgets (and their figures, as
    :func:`write_budget_outputs`)."""
    from .._files import write_json

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    doc = BudgetFile(study.name, budgets=tuple(budgets), run_id=run_id).to_json()
    path = write_json(folder / "budget.json", doc, indent=1, ensure_ascii=False)
    if figures is not None:
        figures(doc, folder)
    return path
