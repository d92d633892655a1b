"""``publication.json``: the document :meth:`Reproduction.write` writes and the types it is
read through (SI inside; the file holds user units as the seed records give them).

Reading is tolerant of a partial or forged file, as the other results files are: a missing
or mistyped number is NaN (a list of numbers: NaN where an entry is not a number), a missing
table is empty, and only a document that is not a JSON object is refused (None).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._files import json_dict, json_list, json_number, json_text
from ..study import to_si


def document(*, title: str, study: str, definition_of_study: str, seeds, workers: int,
             G_range, generations: int, population: int, wall_time_s: float, spread: dict,
             comparison: list[dict], records: list[dict]) -> dict:
    """The content of ``publication.json`` (before NaN is written as null)."""
    return {"title": title, "study": study, "definition_of_study": definition_of_study,
            "seeds": list(seeds), "workers": workers, "G_range_Pa": list(G_range),
            "gp": {"generations": generations, "population": population},
            "wall_time_s": wall_time_s, "spread": spread, "comparison": comparison,
            "records": records}


def _float(value) -> float:
    v = json_number(value)
    return math.nan if v is None else v


def _count(value) -> int | None:
    """A whole number of the file (not a boolean), else None."""
    return value if isinstance(value, int) and not isinstance(value, bool) else None


def _floats(value) -> np.ndarray:
    """A JSON list of numbers as floats; null (how NaN is written) or anything but a number
    becomes NaN."""
    return np.array([_float(v) for v in json_list(value)], dtype=float)


def _same_length(*arrays: np.ndarray) -> tuple[np.ndarray, ...]:
    """The arrays cut to the shortest (a forged file's curves of unequal length)."""
    n = min(a.size for a in arrays)
    return tuple(a[:n] for a in arrays)


@dataclass(frozen=True)
class DesignRow:
    """A design of a seed record: H [m], G [Pa], Γ_r,max, Γ_z,max [N/T], F_r,min, F_z,max [N],
    t_m, θ_m (NaN where the record has none, e.g. an infeasible choice)."""

    H: float = math.nan
    G: float = math.nan
    Gamma_r_max: float = math.nan
    Gamma_z_max: float = math.nan
    F_r_min: float = math.nan
    F_z_max: float = math.nan
    t_m: float = math.nan
    theta_m: float = math.nan

    @classmethod
    def from_json(cls, data) -> DesignRow:
        d = json_dict(data)
        return cls(to_si(_float(d.get("H_mm")), "mm"), to_si(_float(d.get("G_kPa")), "kPa"),
                   _float(d.get("Gamma_r_max")), _float(d.get("Gamma_z_max")),
                   _float(d.get("F_r_min")), _float(d.get("F_z_max")), _float(d.get("t_m")),
                   _float(d.get("theta_m")))


@dataclass(frozen=True)
class Sweep:
    """Per-unit-G extrema over H [m] of a fit: γ_r,max, γ_z,max [N/(T·Pa)], f_r,min, f_z,max
    [N/Pa] and t_m."""

    H: np.ndarray
    gamma_r_max: np.ndarray
    gamma_z_max: np.ndarray
    f_r_min: np.ndarray
    f_z_max: np.ndarray
    t_m: np.ndarray

    @classmethod
    def from_json(cls, data) -> Sweep:
        d = json_dict(data)
        H, *rest = _same_length(*(_floats(d.get(k)) for k in (
            "H_mm", "gamma_r_max", "gamma_z_max", "f_r_min", "f_z_max", "t_m")))
        return cls(to_si(H, "mm"), *rest)


@dataclass(frozen=True)
class Conditioning:
    """The stable-shear bound over H [m]: t_m, the smallest t within ``tol`` of the range
    (t_tol) and the relative drop of F_z,max between them."""

    H: np.ndarray
    tol: float
    t_m: np.ndarray
    t_tol: np.ndarray
    dF_z_rel: np.ndarray

    @classmethod
    def from_json(cls, data) -> Conditioning:
        d = json_dict(data)
        H, t_m, t_tol, drop = _same_length(*(_floats(d.get(k)) for k in (
            "H_mm", "t_m", "t_tol", "dF_z_rel")))
        return cls(to_si(H, "mm"), _float(d.get("tol")), t_m, t_tol, drop)


@dataclass(frozen=True)
class GammaZCurve:
    """Γ_z [N/T] along t at height H [m] and tilt θ [rad]."""

    t: np.ndarray
    Gamma_z: np.ndarray
    H: float
    theta: float

    @classmethod
    def from_json(cls, data) -> GammaZCurve:
        d = json_dict(data)
        t, g = _same_length(_floats(d.get("t")), _floats(d.get("Gamma_z")))
        return cls(t, g, to_si(_float(d.get("H_mm")), "mm"), _float(d.get("theta_rad")))


@dataclass(frozen=True)
class SeedRecord:
    """One (definition, seed) of the seed study (see :func:`magtact.publication.seed_study`)."""

    definition: str
    seed: int | None
    ok: bool
    original: DesignRow = field(default_factory=DesignRow)
    chosen: DesignRow = field(default_factory=DesignRow)
    sweep: Sweep | None = None
    conditioning: Conditioning | None = None
    gamma_z_curve: GammaZCurve | None = None

    @property
    def original_G(self) -> float:
        """G [Pa] of the original design."""
        return self.original.G

    @classmethod
    def from_json(cls, data) -> SeedRecord | None:
        """None for anything but a JSON object."""
        if not isinstance(data, dict):
            return None

        def part(key, kind):
            return kind.from_json(data[key]) if isinstance(data.get(key), dict) else None

        return cls(json_text(data.get("definition")), _count(data.get("seed")),
                   data.get("ok") is True, DesignRow.from_json(data.get("original")),
                   DesignRow.from_json(data.get("chosen")), part("sweep", Sweep),
                   part("conditioning", Conditioning), part("gamma_z_curve", GammaZCurve))


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
    for d, figs in json_dict(data).items():
        for k, f in json_dict(figs).items():
            if isinstance(f, dict) and "min" in f:
                rows.append(SpreadRow(str(d), str(k), json_text(f.get("label")),
                                      json_text(f.get("unit")), _count(f.get("n")),
                                      json_number(f.get("min")), json_number(f.get("max")),
                                      json_number(f.get("max_over_min"))))
    return tuple(rows)


@dataclass(frozen=True)
class ComparisonRow:
    """A row of the side-by-side table: ``cells`` per column ``"<definition>/<reading>"``
    (see :func:`magtact.publication.comparison`)."""

    quantity: str
    unit: str
    scale_free: bool
    publication: float | str
    cells: dict[str, dict]

    @property
    def columns(self) -> list[str]:
        return list(self.cells)

    def publication_text(self) -> str:
        from ._compare import publication_text

        return publication_text(self.publication)

    def cell_text(self, column: str) -> str:
        """The cell of ``column`` as ``median [min, max]`` or its text; "—" where it has
        neither."""
        from ._compare import cell_text

        cell = self.cells.get(column)
        try:
            return cell_text(cell) if isinstance(cell, dict) else "—"
        except (KeyError, TypeError, ValueError):
            return "—"

    @classmethod
    def from_json(cls, data) -> ComparisonRow | None:
        """None for anything but a JSON object."""
        if not isinstance(data, dict):
            return None
        pub = data.get("publication")
        pub = pub if isinstance(pub, str) else _float(pub)
        return cls(json_text(data.get("quantity")), json_text(data.get("unit")),
                   data.get("scale_free") is True, pub,
                   {k: json_dict(v) for k, v in data.items() if "/" in k})


@dataclass(frozen=True)
class PublicationFile:
    """``publication.json`` of :meth:`magtact.publication.Reproduction.write`."""

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
        G = [_float(v) for v in json_list(data.get("G_range_Pa"))]
        gp = json_dict(data.get("gp"))
        return cls(json_text(data.get("title")), json_text(data.get("study")),
                   json_text(data.get("definition_of_study"), "jacobian"),
                   tuple(s for s in map(_count, json_list(data.get("seeds"))) if s is not None),
                   _count(data.get("workers")), (G[0], G[1]) if len(G) == 2 else None,
                   _count(gp.get("generations")), _count(gp.get("population")),
                   _float(data.get("wall_time_s")), _spread(data.get("spread")),
                   tuple(r for r in map(ComparisonRow.from_json, json_list(
                       data.get("comparison"))) if r is not None),
                   tuple(r for r in map(SeedRecord.from_json, json_list(data.get("records")))
                         if r is not None))

    @classmethod
    def read(cls, path) -> PublicationFile | None:
        """:meth:`from_json` of the file ``path``; None where it is missing or not JSON."""
        import json
        from pathlib import Path

        try:
            return cls.from_json(json.loads(Path(path).read_text(encoding="utf-8")))
        except (OSError, ValueError, RecursionError):
            return None
