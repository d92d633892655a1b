"""The calibration of a design (and optionally of a built unit), and its files
(docs/method.md §13)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from .._errors import MagtactError
from .._files import write_text
from .._records import entry, from_json_or_none, keys, to_json
from .._sensor import Sensor
from ..doe import check_design
from ..metamodel import ModelSet
from ..study import HallChip, Study, hall_chip
from ._fe import PathHoldout, fe_forces, has_height, path_holdout
from ._firmware import (
    DEGREES,
    TABLE_SIZES,
    FirmwareChoice,
    FrontierPoint,
    approximation_json,
    c_header,
    firmware_approximation,
    write_json,
    write_table_csv,
)
from ._map import FORCE_SOURCES, OK, MapDesign, SensorMap, sensor_map
from ._unit import DEFAULT_FIT, Presses, UnitCalibration, UnitRecord, calibrate_unit

#: Points per side of the (t, θ) grid of the error maps.
N_GRID = 41
#: Loads of the round-trip check.
N_ROUND_TRIP = 2000


@dataclass(frozen=True)
class Calibration:
    """Everything ``magtact calibrate`` delivers for one design.

    Attributes
    ----------
    map : SensorMap
        The design's map (or the built unit's corrected map when ``unit`` is given).
    noise : tuple of float
        σ_B (x, z) [T] of the Hall chip the resolution is computed with, and ``noise_source``
        where it comes from (the study's ``[hall]`` or given).
    sigma_F : tuple of float
        (σ_F,r, σ_F,z) [N]: the design's worst force resolution over the stable region
        (:func:`magtact.designer.resolution`), the firmware's target.
    round_trip : float
        Largest |F → B → F − F| over the region, relative to the force range.
    firmware : FirmwareChoice
    unit : UnitCalibration or None
    grid : dict
        ``t``, ``theta`` (n, n) and the chosen approximation's error ``err_r``, ``err_z`` [N]
        over the region, the maps of the report's figure.
    force_error : ForceError or None
        What limits the map's forces (:func:`force_model_error`): the metamodels' error against
        the DOE's FE paths at H, or the FE interpolant's error between paths.
    """

    map: SensorMap
    noise: tuple[float, float]
    noise_source: str
    sigma_F: tuple[float, float]
    round_trip: float
    firmware: FirmwareChoice
    unit: UnitCalibration | None
    grid: dict
    force_error: ForceError | None = None

    def __str__(self) -> str:
        """The map's design, target and firmware in mN, mm and kPa (a few lines)."""
        from .._display import calibration_rows, text_block

        return text_block(*calibration_rows(self))

    def _repr_html_(self) -> str:
        from .._display import calibration_rows, html_block

        return html_block(*calibration_rows(self))

    @property
    def force_limit(self) -> ForceError | None:
        """What limits the map's forces (:attr:`force_error`), in N."""
        return self.force_error

    def to_json(self) -> dict:
        """The summary in user units (``calibration.json``: :class:`CalibrationSummary`)."""
        return to_json(self.summary())

    def summary(self) -> CalibrationSummary:
        """The summary ``calibration.json`` holds (:class:`CalibrationSummary`)."""
        fw = self.firmware
        a = fw.chosen
        return CalibrationSummary(
            self.map.design_record(), self.noise, self.noise_source, self.sigma_F,
            self.round_trip,
            FirmwareSummary(fw.reached, fw.rule, tuple(fw.frontier_points()), a.kind, a.degree,
                            a.transform, a.bytes, a.multiplies, a.err_r, a.err_z),
            None if self.unit is None else self.unit.record(), self.map.force_source,
            self.force_error)


#: ``format`` of the calibration summary (``calibration.json``).
SUMMARY_FORMAT = "magtact-calibration-summary/1"

#: How to use the calibration's files, in words (``calibration.json``'s ``usage``).
USAGE = ("C: #include \"force.h\" (link with -lm); MAGTACT_REAL F[3], off[3]; "
         "magtact_force_tare(rest, n, off) once, from n readings rest[n][3] at rest (e.g. 16); "
         "int rc = magtact_force(bx, by, bz, off, F) (0 valid, 1 outside the region, 2 no "
         "field); bx, by, bz in T, F in N. Python: "
         "magtact.calibration.load_approximation(json.load(open('force_map.json'))"
         "['approximation']).evaluate(B)")


@dataclass(frozen=True)
class ForceError:
    """What limits the forces of a map (:func:`force_model_error`): where they come from, in
    words, and the largest error of F_r and F_z [N] (None where not measured); with the FE
    source, each path's leave-one-out error (``paths``), with the metamodels, the number of FE
    points compared (``points``)."""

    force_source: str = entry(kind=str)
    kind: str = entry(kind=str)
    F_r: float | None = entry(unit="mN", optional=True)
    F_z: float | None = entry(unit="mN", optional=True)
    paths: tuple[PathHoldout, ...] | None = entry(kind=PathHoldout, levels=("list",),
                                                  omit="none", default=None)
    points: int | None = entry(kind=int, omit="none", default=None)

    @classmethod
    def from_json(cls, data) -> ForceError | None:
        """The record of :func:`force_model_error`'s document; None for anything but such a
        document."""
        return from_json_or_none(cls, data, "calibration.json's force error")


@dataclass(frozen=True)
class FirmwareSummary:
    """The firmware map of ``calibration.json``: whether it reaches σ_F, how it was chosen,
    every candidate, and the chosen one (kind, degree or table size, transform of B_z, size,
    multiplies, largest error of F_r and F_z [N])."""

    reached: bool = entry(kind=bool)
    rule: str = entry(kind=str)
    frontier: tuple[FrontierPoint, ...] = entry(kind=FrontierPoint, levels=("list",))
    kind: str = entry(kind=str)
    degree: int = entry("degree_or_n", kind=int)
    transform: str = entry(kind=str)
    bytes: int = entry(kind=int)
    multiplies: int = entry(kind=int)
    err_r: float = entry("max_error_F_r_mN", "mN")
    err_z: float = entry("max_error_F_z_mN", "mN")


@dataclass(frozen=True)
class SigmaF:
    """The target σ_F,r, σ_F,z [N] of ``calibration.json``."""

    r: float = entry("sigma_F_r_mN", "mN")
    z: float = entry("sigma_F_z_mN", "mN")


@dataclass(frozen=True)
class CalibrationFiles:
    """The files of a calibration (``calibration.json``'s ``files``), by what they are."""

    c_header: str = entry(kind=str, default="force.h")
    json: str = entry(kind=str, default="force_map.json")
    csv_table: str = entry(kind=str, default="force_table.csv")


@dataclass(frozen=True)
class CalibrationSummary:
    """``calibration.json``: the design, the resolution the firmware is held to, the round
    trip, the firmware map, a built unit and what limits the forces; in SI.

    Attributes
    ----------
    design : MapDesign
        The design, its parts and its stable region.
    noise : tuple of float
        σ_B (x, z) [T] the resolution is computed with; ``noise_source`` where it comes from.
    sigma_F : (float, float)
        σ_F,r, σ_F,z [N], the firmware's target.
    round_trip : float
        Largest round-trip error F → B → F, relative to the force range.
    format : str
        The file's format (:data:`SUMMARY_FORMAT`).
    firmware : FirmwareSummary
    unit : UnitRecord or None
        A built unit's fit.
    force_source : str
    force_error : ForceError or None
    files : CalibrationFiles
    usage : str
    """

    format: str = entry(kind=str, default=SUMMARY_FORMAT, kw_only=True)
    design: MapDesign = entry(kind=MapDesign)
    noise: tuple[float, ...] = entry("noise_B_uT", "uT", levels=("list",))
    noise_source: str = entry(kind=str)
    sigma_F: tuple[float, float] = entry(kind=SigmaF, inline=True, shape="tuple")
    round_trip: float = entry("round_trip_rel")
    firmware: FirmwareSummary = entry(kind=FirmwareSummary)
    unit: UnitRecord | None = entry(kind=UnitRecord, optional=True)
    force_source: str = entry(kind=str)
    force_error: ForceError | None = entry("force_model_error", kind=ForceError,
                                           optional=True)
    files: CalibrationFiles = entry(kind=CalibrationFiles, default=CalibrationFiles())
    usage: str = entry(kind=str, default=USAGE)

    @classmethod
    def from_json(cls, data) -> CalibrationSummary | None:
        """The summary of ``calibration.json``'s document; None for a document of another
        format or shape."""
        s = from_json_or_none(cls, data, "calibration.json")
        return s if s is not None and s.format == SUMMARY_FORMAT else None

    @property
    def frontier(self) -> list[dict]:
        """Every firmware candidate in user units, as the file gives it."""
        return [p.to_json() for p in self.firmware.frontier]


def round_trip_error(smap: SensorMap, n: int = N_ROUND_TRIP, seed: int = 0) -> float:
    """Largest |F(B(F)) − F| over n loads of the region, relative to the force range
    (docs/method.md §13.1): forward through :meth:`SensorMap.field`, back through
    :meth:`SensorMap.force`."""
    L = smap.region_samples(n, seed)
    _, F = smap.at_load(L[:, 0], L[:, 1], L[:, 2])
    B, flag = smap.field(F)
    back = smap.force(np.where((flag == OK)[:, None], B, smap.at_load(0, 0)[0]))
    rng = np.array([smap.ranges[0], smap.ranges[0], smap.ranges[1]])
    err = np.abs(back.F - F) / rng
    if not ((flag == OK) & (back.flag == OK)).all():
        return float("inf")
    return float(err.max())


def error_grid(smap: SensorMap, choice: FirmwareChoice, n: int = N_GRID) -> dict:
    """The chosen approximation's error of F_r, F_z [N] on an n × n grid of (t, θ) over the
    region (φ = 0)."""
    T, TH = np.meshgrid(np.linspace(0.0, smap.t_m, n), np.linspace(0.0, smap.theta_m, n),
                        indexing="ij")
    B, F = smap.at_load(T, TH, 0.0)
    approx = choice.chosen.forces(B)
    return {"t": T, "theta": TH, "err_r": np.abs(approx[..., 0] - F[..., 0]),
            "err_z": np.abs(approx[..., 2] - F[..., 2])}


def force_source_for(force_source: str, dataset, H: float, presses: bool) -> str:
    """The force source a calibration uses (docs/method.md §13.4): ``"models"`` or ``"fe"`` as
    given; ``"auto"``: the FE paths for a built unit's fit (``presses``) when ``dataset`` holds
    paths at H, else the metamodels (the design's firmware map: smooth, so its compact
    approximation can reach σ_F).

    Raises
    ------
    MagtactError
        For an unknown name.
    """
    if force_source == "auto":
        return "fe" if presses and has_height(dataset, H) else "models"
    if force_source not in FORCE_SOURCES:
        raise MagtactError(f"force source {force_source!r} is unknown: choose auto, "
                           f"{', '.join(FORCE_SOURCES)}")
    return force_source


def force_model_error(smap: SensorMap, dataset) -> ForceError:
    """What limits the map's forces (docs/method.md §13.4). FE source: the interpolant's
    leave-one-θ-path-out error at H (:func:`path_holdout`; the interior paths' largest is the
    error between paths, the end paths' is extrapolation). Metamodel source: the models'
    largest error against the FE forces of the DOE's paths at H over the region (not measured
    where the data set holds no paths at H)."""
    if smap.fe is not None:
        paths = path_holdout(dataset, smap.H, smap.G, smap.t_m)
        inner = [p for p in paths if p.interior]
        return ForceError("fe", "FE interpolant, leave-one-theta-path-out at H (the interior "
                                "paths: between paths, at twice the paths' spacing)",
                          max(p.err_r for p in inner), max(p.err_z for p in inner),
                          paths=tuple(paths))
    if not has_height(dataset, smap.H):
        return ForceError("models", "not measured: no FE paths at this H", None, None)
    fe = fe_forces(dataset, smap.H)
    T, TH = np.meshgrid(np.concatenate([[0.0], fe.t]), fe.theta, indexing="ij")
    w = smap.features(T, TH)
    inside = smap.inside(w)
    fr, fz = fe.forces(w[..., 0], w[..., 1], smap.G)
    F = smap.F_of(w)
    return ForceError("models", "metamodels against the DOE's FE forces at H, over the "
                                "region's FE points",
                      float(np.abs(F[..., 0] - fr)[inside].max()),
                      float(np.abs(F[..., 2] - fz)[inside].max()), points=int(inside.sum()))


def _chip(study: Study, noise: tuple[float, float] | None,
          chip: HallChip | None = None) -> tuple[HallChip, str]:
    own = chip is None
    chip = hall_chip(study) if own else chip
    if noise is not None:
        sx, sz = (float(v) for v in noise)
        if not (sx > 0 and sz > 0):
            raise MagtactError(f"the field noise must be positive, got {noise} T")
        return HallChip(chip.name, sx, sz, chip.range_x, chip.range_z, "given",
                        "given to magtact calibrate"), "given"
    if chip.noise is None:
        raise MagtactError(f"the Hall chip's noise is not known ({', '.join(chip.missing)}): "
                           "give it in the study's [hall] or as --noise-uT")
    return chip, (f"the study's [hall] ({chip.name})" if own
                  else f"{chip.name} at {chip.setting}")


def calibrate(models: ModelSet, study: Study, H: float, G: float, M_z: float | None = None,
              noise: tuple[float, float] | None = None, presses: Presses | None = None,
              fit=DEFAULT_FIT, degrees=DEGREES, table_sizes=TABLE_SIZES,
              model_error: tuple[float, float] | None = None,
              chip: HallChip | None = None, force_source: str = "auto",
              dataset=None, sensor: Sensor | None = None) -> Calibration:
    """The calibration of design (H [m], G [Pa]) (docs/method.md §13): its map, the round-trip
    check, the resolution σ_F with the chip's noise (``noise`` = (σ_x, σ_z) [T], else the
    study's ``[hall]``), the firmware approximation held to σ_F, and, with ``presses``, the
    built unit's parameters and corrected map (whose approximation is then exported;
    ``model_error`` as in :func:`calibrate_unit`). ``chip``: the chip at the setting the
    design's answer uses (:attr:`magtact.designer.DesignAnswer.chip`), default the study's.
    ``force_source`` (``"auto"``, ``"fe"``, ``"models"``, :func:`force_source_for`) with
    ``dataset`` (the DOE data set of the models): where the map's forces come from.
    ``sensor``: the design's parts (:attr:`magtact.designer.DesignAnswer.sensor`: its magnet,
    the chip's setting and standoff, the silicone), default the study's own.

    Raises
    ------
    MagtactError
        Without a known noise, for a design without stable region, presses that do not
        identify the parameters of ``fit``, or the FE source without FE paths at H.
    """
    check_design(study, H, dataset)  # before any work: outside it the models extrapolate
    chip, noise_source = _chip(study, noise, chip)
    source = force_source_for(force_source, dataset, H, presses is not None)
    if source == "fe":  # what the data lack is said before the design's work
        fe_forces(dataset, H, study)
    # the candidates' least squares are small (N_TRAIN rows, at most a few hundred columns):
    # one BLAS thread does each in milliseconds, where threads that wait for a shared core
    # take a hundred times longer
    with threadpool_limits(limits=1, user_api="blas"):
        return _calibrate(models, study, H, G, M_z, chip, noise_source, source, presses, fit,
                          degrees, table_sizes, model_error, dataset, sensor)


def _calibrate(models, study, H, G, M_z, chip, noise_source, source, presses, fit, degrees,
               table_sizes, model_error, dataset, sensor) -> Calibration:
    from ..designer import resolution
    from ..optimise import per_design

    design = per_design(models, H, G, study, M_z)
    smap = sensor_map(models, study, H, G, M_z, design=design, force_source=source,
                      dataset=dataset, sensor=sensor)
    res = resolution(models, study, design, chip)
    sigma = (res.sigma_r_worst, res.sigma_z_worst)
    trip = round_trip_error(smap)
    unit = None
    target = smap
    if presses is not None:
        unit = calibrate_unit(smap, presses, fit=fit, model_error=model_error)
        target = unit.corrected
    choice = firmware_approximation(target, sigma, degrees=degrees, table_sizes=table_sizes)
    return Calibration(target, chip.noise, noise_source, sigma, trip, choice, unit,
                       error_grid(target, choice), force_model_error(smap, dataset))


def write_calibration_outputs(cal: Calibration, out_dir, figures=None) -> dict[str, Path]:
    """Write ``force.h`` (C99), ``force_map.json``, ``force_table.csv``, ``calibration.json``
    (the summary the report reads) and, with ``figures`` (e.g.
    :func:`magtact.report.calibration_figures`), the error figure. Returns the files by name."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    names = CalibrationFiles()
    header = out / names.c_header
    files = dict(zip(keys(CalibrationFiles), (
        header, write_json(approximation_json(cal.firmware, cal.map), out / names.json),
        write_table_csv(cal.map, out / names.csv_table)), strict=True))
    files["summary"] = write_json(cal.to_json(), out / "calibration.json")
    write_text(header, c_header(cal.firmware.chosen, cal.map, cal.firmware, noise=cal.noise))
    if cal.unit is not None:
        files["unit"] = write_json(cal.unit.to_json(), out / "unit.json")
    if figures is not None:
        for k, p in enumerate(figures(cal, out)):
            files[f"figure_{k}"] = Path(p)
    return files
