"""``publication.json``: the records it is written from and read through (SI inside; the
spread and the side-by-side table hold the figures in the units they name).

Reading is tolerant of a partial or forged file, as the other results files are: a missing
or mistyped number is NaN (a list of numbers: empty where it is not one), a missing table is
empty, and only a document that is not a JSON object is refused (None).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .._records import entry, from_json_lenient, to_json


def _number(unit: str = "", key: str | None = None):
    """A number of a seed record: written as null where it is not finite (or left out where
    it is None), read as NaN where the file gives no number."""
    return entry(key, unit, null_nan=True, omit="none", default=None, fallback=math.nan)


def _curve(unit: str = ""):
    """A curve of a seed record: numbers (NaN written as null), an empty array where the file
    gives none."""
    return entry(unit=unit, levels=("list",), array=True, null_nan=True,
                 fallback=np.empty(0))


def _same_length(record) -> None:
    """Cut the curves of ``record`` (a frozen record of arrays) to the shortest (a forged
    file's curves of unequal length)."""
    arrays = {f.name: getattr(record, f.name) for f in record.__dataclass_fields__.values()
              if isinstance(getattr(record, f.name), np.ndarray)}
    n = min(a.size for a in arrays.values())
    for name, a in arrays.items():
        object.__setattr__(record, name, a[:n])


@dataclass(frozen=True)
class DesignRow:
    """A design of a seed record: H [m], G [Pa], Γ_r,max, Γ_z,max [N/T], F_r,min, F_z,max [N],
    t_m, θ_m (NaN where a file gives none, e.g. an infeasible choice)."""

    H: float = _number("mm")
    G: float = _number("kPa")
    Gamma_r_max: float = _number()
    Gamma_z_max: float = _number()
    F_r_min: float = _number()
    F_z_max: float = _number()
    t_m: float = _number()
    theta_m: float = _number()

    @classmethod
    def from_json(cls, data) -> DesignRow:
        """The design a seed record gives, NaN where it gives none."""
        return from_json_lenient(cls, data if isinstance(data, dict) else {})


@dataclass(frozen=True)
class Resolution:
    """σ_F [N] of a chosen design with the study's Hall chip: at rest and worst."""

    sigma_Fr_0: float = entry(unit="mN", null_nan=True)
    sigma_Fr_worst: float = entry(unit="mN", null_nan=True)
    sigma_Fz_0: float = entry(unit="mN", null_nan=True)
    sigma_Fz_worst: float = entry(unit="mN", null_nan=True)


@dataclass(frozen=True)
class ChosenRow(DesignRow):
    """The design chosen under a set of force constraints: the design, its active constraints,
    the constraints F_r,c, F_z,c [N] and (under the default constraints, where the chip's noise
    is known) its σ_F; or, where no design meets them, only why (``infeasible``)."""

    active: tuple[str, ...] | None = entry(kind=str, levels=("list",), omit="none",
                                           default=None)
    F_r_c: float = _number("N")
    F_z_c: float = _number("N")
    resolution: Resolution | None = entry(kind=Resolution, inline=True, optional=True,
                                          omit="none", default=None)
    infeasible: str | None = entry(kind=str, omit="none", default=None)


@dataclass(frozen=True)
class FitAccuracy:
    """The held-out accuracy of a force model: max |error| / range and R²."""

    test_max_err_over_range: float = entry(null_nan=True)
    test_r2: float = entry(null_nan=True)


@dataclass(frozen=True)
class Sweep:
    """Per-unit-G extrema over H [m] of a fit: γ_r,max, γ_z,max [N/(T·Pa)], f_r,min, f_z,max
    [N/Pa] and t_m."""

    H: np.ndarray = _curve("mm")
    gamma_r_max: np.ndarray = _curve()
    gamma_z_max: np.ndarray = _curve()
    f_r_min: np.ndarray = _curve()
    f_z_max: np.ndarray = _curve()
    t_m: np.ndarray = _curve()

    def __post_init__(self):
        _same_length(self)

    @classmethod
    def from_json(cls, data) -> Sweep:
        return from_json_lenient(cls, data if isinstance(data, dict) else {})


@dataclass(frozen=True)
class Conditioning:
    """The stable-shear bound over H [m]: t_m, the smallest t within ``tol`` of the range
    (t_tol) and the relative drop of F_z,max between them."""

    H: np.ndarray = _curve("mm")
    tol: float = entry(null_nan=True, fallback=math.nan)
    t_m: np.ndarray = _curve()
    t_tol: np.ndarray = _curve()
    dF_z_rel: np.ndarray = _curve()

    def __post_init__(self):
        _same_length(self)

    @classmethod
    def from_json(cls, data) -> Conditioning:
        return from_json_lenient(cls, data if isinstance(data, dict) else {})


@dataclass(frozen=True)
class GammaZCurve:
    """Γ_z [N/T] along t at height H [m] and tilt θ [rad]."""

    t: np.ndarray = _curve()
    Gamma_z: np.ndarray = _curve()
    H: float = entry(unit="mm", null_nan=True, fallback=math.nan)
    theta: float = entry(unit="rad", null_nan=True, fallback=math.nan)

    def __post_init__(self):
        _same_length(self)

    @classmethod
    def from_json(cls, data) -> GammaZCurve:
        return from_json_lenient(cls, data if isinstance(data, dict) else {})


#: The design of a record that gives none (every number NaN).
NO_DESIGN = DesignRow(*(math.nan,) * 8)
NO_CHOICE = ChosenRow(*(math.nan,) * 8)


def _part(kind: type, fallback=None):
    """A part of a seed record that a failed fit does not have (left out of the file)."""
    return entry(kind=kind, omit="none", default=None, fallback=fallback)


@dataclass(frozen=True)
class SeedRecord:
    """One (definition, seed) of the seed study (see :func:`magtact.publication.seed_study`),
    as its document is written (:meth:`to_json`; the parts a failed fit lacks left out) and
    read back field by field (:meth:`from_json`).

    Attributes
    ----------
    definition : str
    seed : int or None
    ok : bool
        Whether the fit succeeded (else ``message`` says why).
    fit_time_s : float or None
        The fit's wall time [s].
    accuracy : dict of str to FitAccuracy or None
        Per force model (``f_r``, ``f_z``).
    original, fabricated : DesignRow
        The publication's designs.
    sweep : Sweep or None
    chosen, chosen_reference : ChosenRow
        The design chosen under the default constraints and under those of the original.
    branches, branches_reference : int or None
        Branches of the exact reduction's Pareto set.
    conditioning : Conditioning or None
    gamma_z_curve : GammaZCurve or None
    gamma_z_trend : str or None
        ``"increasing"``, ``"decreasing"``, ``"constant"`` or ``"mixed"``.
    """

    definition: str = entry(kind=str, fallback="")
    seed: int | None = entry(kind=int, optional=True)
    ok: bool = entry(kind=bool, fallback=False)
    message: str = entry(kind=str, default="")
    fit_time_s: float | None = entry(omit="none", default=None)
    accuracy: dict | None = entry(kind=FitAccuracy, levels=("map",), optional=True,
                                  omit="none", default=None)
    original: DesignRow = _part(DesignRow, NO_DESIGN)
    fabricated: DesignRow = _part(DesignRow, NO_DESIGN)
    sweep: Sweep | None = _part(Sweep)
    chosen: ChosenRow = _part(ChosenRow, NO_CHOICE)
    branches: int | None = _part(int)
    chosen_reference: ChosenRow = _part(ChosenRow, NO_CHOICE)
    branches_reference: int | None = _part(int)
    conditioning: Conditioning | None = _part(Conditioning)
    gamma_z_curve: GammaZCurve | None = _part(GammaZCurve)
    gamma_z_trend: str | None = _part(str)

    @property
    def original_G(self) -> float:
        """G [Pa] of the original design."""
        return self.original.G

    def accuracy_of(self, model: str) -> float:
        """The held-out max |error| / range of force model ``model`` (NaN where none)."""
        a = (self.accuracy or {}).get(model)
        return math.nan if a is None else a.test_max_err_over_range

    def to_json(self) -> dict:
        """The record's document, a number that is not finite kept as it is (the seed study's
        cache keeps it; ``publication.json`` writes it as null)."""
        return to_json(self, null_nan=False)

    @classmethod
    def from_json(cls, data) -> SeedRecord | None:
        """None for anything but a JSON object."""
        if not isinstance(data, dict):
            return None
        record = from_json_lenient(cls, data)
        return None if record is None else replace(
            record, original=record.original or NO_DESIGN, chosen=record.chosen or NO_CHOICE)


# ---- the spread over seeds -----------------------------------------------------------------
@dataclass(frozen=True)
class FigureSpread:
    """A figure over the seeds of one definition: its values (in ``unit``, the unit of the
    table: the spread is a table of the publication's figures), how many are numbers, least,
    largest and largest over least (NaN, null in the file, where undefined)."""

    label: str = entry(kind=str)
    unit: str = entry(kind=str)
    values: tuple = entry(levels=("list",), null_nan=True)
    n: int = entry(kind=int)
    min: float = entry(null_nan=True)
    max: float = entry(null_nan=True)
    max_over_min: float = entry(null_nan=True)


@dataclass(frozen=True)
class TrendSpread:
    """The trend of Γ_z along t over the seeds: each seed's and how many of each."""

    label: str = entry(kind=str)
    unit: str = entry(kind=str)
    values: tuple[str, ...] = entry(kind=str, levels=("list",))
    counts: dict[str, int] = entry(kind=int, levels=("map",))


@dataclass(frozen=True)
class FailedSpread:
    """The seeds whose fit failed."""

    label: str = entry(kind=str)
    unit: str = entry(kind=str)
    values: tuple[int, ...] = entry(kind=int, levels=("list",))


def _figure():
    return entry(kind=FigureSpread)


@dataclass(frozen=True)
class DefinitionSpread:
    """The spread over the seeds of one definition, per figure (the figures in the order of
    :data:`magtact.publication._compare.FIGURES`)."""

    acc_f_r: FigureSpread = _figure()
    acc_f_z: FigureSpread = _figure()
    Gamma_r_orig: FigureSpread = _figure()
    Gamma_z_orig: FigureSpread = _figure()
    H_star: FigureSpread = _figure()
    G_star: FigureSpread = _figure()
    Gamma_r_star: FigureSpread = _figure()
    Gamma_z_star: FigureSpread = _figure()
    H_star_ref: FigureSpread = _figure()
    G_star_ref: FigureSpread = _figure()
    sigma_Fr_star: FigureSpread = _figure()
    sigma_Fz_star: FigureSpread = _figure()
    branches: FigureSpread = _figure()
    gamma_z_trend: TrendSpread = entry(kind=TrendSpread)
    failed: FailedSpread = entry(kind=FailedSpread)


#: The names of the figures whose spread is reported (:class:`DefinitionSpread`).
FIGURE_NAMES = tuple(f.name for f in DefinitionSpread.__dataclass_fields__.values()
                     if f.type in ("FigureSpread", FigureSpread))


@dataclass(frozen=True)
class SpreadRow:
    """A figure's range over the seeds of one definition (a figure with a numeric range)."""

    definition: str
    figure: str
    label: str
    unit: str
    n: int | None
    min: float | None
    max: float | None
    max_over_min: float | None


def _spread(data) -> tuple[SpreadRow, ...]:
    rows = []
    for d, figs in (data if isinstance(data, dict) else {}).items():
        for k, f in (figs if isinstance(figs, dict) else {}).items():
            fig = from_json_lenient(FigureSpread, f) if isinstance(f, dict) and "min" in f \
                else None
            if fig is not None:
                rows.append(SpreadRow(str(d), str(k), fig.label or "", fig.unit or "", fig.n,
                                      _finite(fig.min), _finite(fig.max),
                                      _finite(fig.max_over_min)))
    return tuple(rows)


def _finite(v: float | None) -> float | None:
    """A number read from the file; None where it gave none (null or not a number)."""
    return None if v is None or isinstance(v, float) and math.isnan(v) else v


# ---- the side-by-side table ----------------------------------------------------------------
def publication_text(value) -> str:
    """The publication's cell: a number or a statement."""
    return f"{value:.3g}" if isinstance(value, int | float) else str(value)


def cell_text(cell: dict, digits: int = 3) -> str:
    """A table cell: ``median [min, max]`` or its text."""
    if "text" in cell:
        return cell["text"]
    m, lo, hi = cell["median"], cell["min"], cell["max"]
    if lo == hi:
        return f"{m:.{digits}g}"
    return f"{m:.{digits}g} [{lo:.{digits}g}, {hi:.{digits}g}]"


@dataclass(frozen=True)
class ComparisonRow:
    """A row of the side-by-side table: ``cells`` per column ``"<definition>/<reading>"``
    (see :func:`magtact.publication.comparison`), each ``median``, ``min``, ``max`` or a
    ``text``; the publication's value a number or a statement."""

    quantity: str = entry(kind=str, fallback="")
    unit: str = entry(kind=str, fallback="")
    scale_free: bool = entry(kind=bool, fallback=False)
    publication: float | str = entry(kind=object, fallback=math.nan)
    cells: dict[str, dict] = entry(kind=object, levels=("map",), inline=True,
                                   default_factory=dict)

    @property
    def columns(self) -> list[str]:
        return list(self.cells)

    def publication_text(self) -> str:
        return publication_text(self.publication)

    def cell_text(self, column: str) -> str:
        """The cell of ``column`` as ``median [min, max]`` or its text; "—" where it has
        neither."""
        cell = self.cells.get(column)
        try:
            return cell_text(cell) if isinstance(cell, dict) else "—"
        except (KeyError, TypeError, ValueError):
            return "—"

    def to_json(self) -> dict:
        return to_json(self)

    @classmethod
    def from_json(cls, data) -> ComparisonRow | None:
        """None for anything but a JSON object (a cell that is no object reads as empty)."""
        if not isinstance(data, dict):
            return None
        row = from_json_lenient(cls, data)
        pub = row.publication
        pub = pub if isinstance(pub, str) else _number_or_nan(pub)
        return replace(row, publication=pub, cells={
            k: v if isinstance(v, dict) else {} for k, v in row.cells.items() if "/" in k})


def _number_or_nan(v) -> float:
    return float(v) if isinstance(v, int | float) and not isinstance(v, bool) else math.nan


# ---- the file --------------------------------------------------------------------------------
@dataclass(frozen=True)
class GpSettings:
    """The GP's budget of every force fit."""

    generations: int | None = entry(kind=int, optional=True)
    population: int | None = entry(kind=int, optional=True)


@dataclass(frozen=True)
class PublicationDocument:
    """``publication.json`` as :meth:`Reproduction.write` writes it: the study, its seeds and
    settings, and the documents of the spread (:class:`DefinitionSpread` per definition), the
    side-by-side table (:class:`ComparisonRow`) and the seed records (:class:`SeedRecord`).
    G's range [Pa], the wall time [s]."""

    title: str = entry(kind=str, fallback="")
    study: str = entry(kind=str, fallback="")
    definition_of_study: str = entry(kind=str, fallback="jacobian")
    seeds: tuple[int, ...] = entry(kind=int, levels=("list",), fallback=())
    workers: int | None = entry(kind=int, optional=True)
    G_range: tuple | None = entry(unit="Pa", levels=("list",), optional=True)
    gp: GpSettings = entry(kind=GpSettings, fallback=GpSettings(None, None))
    wall_time_s: float = entry(null_nan=True, fallback=math.nan)
    spread: dict = entry(kind=object, fallback=None)
    comparison: tuple = entry(kind=object, levels=("list",), fallback=())
    records: tuple = entry(kind=object, levels=("list",), fallback=())


def document(*, title: str, study: str, definition_of_study: str, seeds, workers: int,
             G_range, generations: int, population: int, wall_time_s: float, spread: dict,
             comparison: list[dict], records: list[dict]) -> dict:
    """The content of ``publication.json`` (:class:`PublicationDocument`)."""
    return to_json(PublicationDocument(
        title, study, definition_of_study, tuple(seeds), workers, tuple(G_range),
        GpSettings(generations, population), wall_time_s, spread, tuple(comparison),
        tuple(records)))


@dataclass(frozen=True)
class PublicationFile:
    """``publication.json`` of :meth:`magtact.publication.Reproduction.write`, read field by
    field (:class:`PublicationDocument`): a missing or mistyped number is NaN, a missing table
    is empty, and only a document that is not a JSON object is refused (None)."""

    title: str
    study: str
    definition_of_study: str
    seeds: tuple[int, ...]
    workers: int | None
    G_range: tuple[float, float] | None
    generations: int | None
    population: int | None
    wall_time_s: float
    spread: tuple[SpreadRow, ...]
    comparison: tuple[ComparisonRow, ...]
    records: tuple[SeedRecord, ...]

    @property
    def columns(self) -> list[str]:
        """Columns of the side-by-side table (those of its first row)."""
        return self.comparison[0].columns if self.comparison else []

    def reference_record(self) -> SeedRecord | None:
        """The record of the study's own definition and first seed (the study's own fit);
        else the first that succeeded."""
        recs = [r for r in self.records if r.ok]
        for r in recs:
            if r.definition == self.definition_of_study:
                return r
        return recs[0] if recs else None

    @classmethod
    def from_json(cls, data) -> PublicationFile | None:
        """None for anything but a JSON object."""
        if not isinstance(data, dict):
            return None
        d = from_json_lenient(PublicationDocument, data)
        G = d.G_range
        return cls(d.title, d.study, d.definition_of_study, d.seeds, d.workers,
                   (G[0], G[1]) if G is not None and len(G) == 2 else None,
                   d.gp.generations, d.gp.population, d.wall_time_s, _spread(d.spread),
                   tuple(r for r in map(ComparisonRow.from_json, d.comparison)
                         if r is not None),
                   tuple(r for r in map(SeedRecord.from_json, d.records) if r is not None))

    @classmethod
    def read(cls, path) -> PublicationFile | None:
        """:meth:`from_json` of the file ``path``; None where it is missing or not JSON."""
        import json
        from pathlib import Path

        try:
            return cls.from_json(json.loads(Path(path).read_text(encoding="utf-8")))
        except (OSError, ValueError, RecursionError):
            return None
