"""``reproduce``: the seed study under both definitions, the comparison table and its files."""

from __future__ import annotations

import json
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from tempfile import mkdtemp

from .._errors import MagtactError
from .._files import write_csv, write_text
from .._records import entry, from_json_lenient, keys, to_json
from ..study import Study
from ._compare import FIGURES, cell_text, comparison, publication_text, records_of, spread
from ._file import FIGURE_NAMES, ComparisonRow, FigureSpread, document
from ._seeds import DEFINITIONS, seed_study

#: GP generations per force fit in the seed study. Half the design fit's budget: the study
#: measures how answers spread between seeds, and on the MagOne DOE 50 and 100 generations
#: give the same spreads and conclusions (docs/verification.md, "The seed study") while
#: 8 seeds x 2 definitions take 6 instead of 15 minutes on two cores.
SEED_GENERATIONS = 50


@dataclass(frozen=True)
class Reproduction:
    """The seed study and the comparison with the publication.

    Attributes
    ----------
    study : Study
    seeds : tuple of int
    records : list of dict
        One per (definition, seed); see :func:`magtact.publication.seed_study`.
    spread : dict
        Per definition and figure: values over seeds, min, max, max/min.
    comparison : list of dict
        Rows of the side-by-side table (see :func:`magtact.publication.comparison`).
    wall_time_s : float
    workers : int
    """

    study: Study
    seeds: tuple[int, ...]
    records: list[dict]
    spread: dict
    comparison: list[dict]
    wall_time_s: float
    workers: int

    def write(self, out: str | Path) -> list[Path]:
        """Write ``publication.json`` (everything), ``seeds.csv``, ``spread.csv`` and
        ``comparison.csv`` (user units) into ``out``; return the files."""
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        doc = document(title="magtact and the publication", study=self.study.name,
                       definition_of_study=self.study.sensitivity.definition,
                       seeds=self.seeds, workers=self.workers, G_range=self.study.design.G,
                       generations=self.study.metamodel.generations,
                       population=self.study.metamodel.population,
                       wall_time_s=self.wall_time_s, spread=self.spread,
                       comparison=self.comparison, records=self.records)
        files = [_write(out / "publication.json", json.dumps(_finite(doc), indent=1,
                                                             ensure_ascii=False))]
        files.append(_table(out / "seeds.csv", SeedRow, [
            SeedRow(r.definition, r.seed, r.ok,
                    math.nan if r.fit_time_s is None else r.fit_time_s,
                    {k: _fmt(value(r)) for k, _, _, value in FIGURES}, r.gamma_z_trend or "")
            for r in records_of(self.records)]))
        files.append(_table(out / "spread.csv", SpreadCsvRow, [
            SpreadCsvRow(d, f.label, f.unit, f.n, _fmt(f.min), _fmt(f.max),
                         _fmt(f.max_over_min))
            for d, figs in self.spread.items()
            for f in (from_json_lenient(FigureSpread, figs[k]) for k in FIGURE_NAMES)]))
        rows = [r for r in map(ComparisonRow.from_json, self.comparison) if r is not None]
        cols = rows[0].columns if rows else []
        files.append(_table(out / "comparison.csv", ComparisonRow, [
            ComparisonRow(r.quantity, r.unit, "yes" if r.scale_free else "no",
                          publication_text(r.publication),
                          {c: cell_text(r.cells[c]) for c in cols}) for r in rows], cols))
        return files


@dataclass(frozen=True)
class SeedRow:
    """A row of ``seeds.csv``: a seed record's fit, its figures (:data:`FIGURES`, formatted)
    and the trend of Γ_z."""

    definition: str = entry(kind=str)
    seed: int | None = entry(kind=int, optional=True)
    ok: bool = entry(kind=bool)
    fit_time_s: float = entry()
    figures: dict[str, str] = entry(kind=str, levels=("map",), inline=True)
    gamma_z_trend: str = entry(kind=str)


@dataclass(frozen=True)
class SpreadCsvRow:
    """A row of ``spread.csv``: a figure's range over the seeds of one definition (numbers
    formatted)."""

    definition: str = entry(kind=str)
    figure: str = entry(kind=str)
    unit: str = entry(kind=str)
    seeds: int = entry(kind=int)
    min: str = entry(kind=str)
    max: str = entry(kind=str)
    max_over_min: str = entry(kind=str)


def _table(path: Path, cls, rows: list, columns: list[str] = ()) -> Path:
    """Write records of type ``cls`` as the rows of a CSV table: their keys, then the
    ``columns`` of an inline map, as the header."""
    docs = [to_json(r) for r in rows]
    header = list(docs[0]) if docs else [*keys(cls), *columns]
    return write_csv(path, header, ([d[k] for k in header] for d in docs))


def reproduce(study: Study, *, seeds: int = 8, workers: int | None = None,
              data: str | Path | None = None, models: str | Path | None = None,
              definitions=DEFINITIONS, sweep_n: int = 201, cache: str | Path | None = None,
              generations: int | None = SEED_GENERATIONS,
              log: Callable[[str], None] | None = None) -> Reproduction:
    """Refit the force models with ``seeds`` seeds under each definition and compare.

    Parameters
    ----------
    study : Study
    seeds : int
        Number of seeds (``study.metamodel.seed`` and the next ones).
    workers : int, optional
        Worker processes (default: the number of cores).
    data : path, optional
        DOE data set file; default: the bundled MagOne data set (valid for the MagOne study
        only).
    models : path, optional
        Folder with the field models (``B_r.json``, ``B_z.json``) all fits share; default: the
        fit shipped for the bundled data set when it matches, else the field is fitted once.
    definitions : sequence of str
    sweep_n : int
        Heights of each fit's exact-reduction sweep.
    cache : path, optional
        Folder of finished records (see :func:`magtact.publication.seed_study`).
    generations : int or None
        GP generations of every force fit (default :data:`SEED_GENERATIONS`); None: the
        study's ``[metamodel] generations``.
    log : callable, optional

    Raises
    ------
    ValueError
        ``seeds`` < 1, an unknown definition, or the bundled data set with a study it was not
        computed for.
    """
    from ..doe import bundled_for, load_dataset
    from ..metamodel import fit_models, prefitted_dir
    from ..metamodel import save_model as save_models_field

    if not isinstance(seeds, int) or seeds < 1:
        raise MagtactError(f"--seeds must be a whole number of at least 1, got {seeds!r}")
    if generations is not None:
        study = replace(study, metamodel=replace(study.metamodel, generations=int(generations)))
    t0 = time.perf_counter()
    ds = load_dataset(data) if data is not None else bundled_for(
        study, "compute its own (magtact doe STUDY --out DOE) and give it with --data "
               "DOE/doe.nc")
    if models is None:
        if data is None and study.metamodel.b_model == "fit":
            models = prefitted_dir()  # fitted to this very data set
        else:
            if log:
                log("fitting the field models once (shared by every seed)")
            field = fit_models(ds, study, names=("B_r", "B_z")).model_set(study)
            models = Path(mkdtemp(prefix="magtact-field-"))
            for k in ("B_r", "B_z"):
                save_models_field(field[k], models / f"{k}.json")
    first = study.metamodel.seed
    chosen = tuple(range(first, first + seeds))
    n_workers = max(1, min(workers or os.cpu_count() or 1, seeds * len(definitions)))
    records = seed_study(study, ds, models, seeds=chosen, definitions=definitions,
                         workers=n_workers, data_path=data, sweep_n=sweep_n, cache=cache,
                         log=log)
    return Reproduction(study, chosen, records, spread(records), comparison(records),
                        time.perf_counter() - t0, n_workers)


def _fmt(v) -> str:
    return f"{v:.6g}" if isinstance(v, float) else str(v)


def _finite(x):
    """NaN and inf as null: publication.json stays valid JSON."""
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_finite(v) for v in x]
    return x


def _write(path: Path, text: str) -> Path:
    return write_text(path, text + "\n")
