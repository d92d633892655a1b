"""``magtact fit``: symbolic-regression metamodels from the DOE data set."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from .._display import sig
from ._app import DataOpt, OutOpt, StudyArg, app, console, get_study, outputs, renamed, tables


@app.command()
def fit(
    study: StudyArg = None,
    out: OutOpt = Path("fit"),
    data: DataOpt = None,
    generations: Annotated[int | None, typer.Option(
        help="GP generations of the fit; default: the study's [metamodel] generations.",
        min=1, max=10_000)] = None,
    H_mm: Annotated[float | None, typer.Option(
        "--H", help="Body height H [mm] of the figures; default: the original design.")] = None,
    G_kpa: Annotated[float | None, typer.Option(
        "--G", help="Shear modulus G [kPa] of the figures; default: the original design.")] = None,
    _old_H: Annotated[str | None, renamed("--H-mm", "--H")] = None,
    _old_G: Annotated[str | None, renamed("--G-kpa", "--G")] = None,
) -> None:
    """Fit B_r, B_z, F_r/G, F_z/G; write model JSON files, metamodels.md and figures."""
    from ..doe import bundled_for, load_dataset
    from ..metamodel import write_fit_outputs
    from ..report import fit_figures
    from ..sensitivity import compare_with_data
    from ..study import check_holdout, checked_si

    s = get_study(study)
    if generations is not None:
        s = replace(s, metamodel=replace(s.metamodel, generations=generations))
    H = checked_si(H_mm, "mm", "--H") if H_mm is not None else None
    G = checked_si(G_kpa, "kPa", "--G") if G_kpa is not None else None
    ds = load_dataset(data) if data is not None else bundled_for(
        s, "compute its own (magtact doe STUDY --out DOE) and give it with --data DOE/doe.nc")
    check_holdout(s, ds.sizes.get("theta", 0), ds.sizes.get("H", 0),
                  str(data) if data is not None else "bundled with magtact", study)
    with outputs("fit", out, "metamodels.md") as o:
        result, files = write_fit_outputs(s, ds, o.folder, H=H, G=G,
                                          log=lambda msg: console.print(msg, highlight=False),
                                          gamma_check=compare_with_data, figures=fit_figures)
    tab = Table(title="held-out accuracy")
    for col in ("model", "R²", "max err / range", "max rel err", "time [s]"):
        tab.add_column(col)
    for k, r in result.reports.items():
        te = r.test
        tab.add_row(k, *(sig(v) for v in (te.r2, te.max_abs_err_over_range, te.max_rel_err))
                    if te else ("–",) * 3, sig(r.fit_time_s))
    tables().print(tab)
    console.print(f"wrote {len(files)} files (models, metamodels.md, figures) to {out}",
                  highlight=False)
    from ..metamodel import fit_quality  # a poor fit is said, not only written

    quality = fit_quality(result.model_set(s))
    if quality.is_poor:
        console.print(f"[bold yellow]warning:[/] {quality.message()}", highlight=False)

