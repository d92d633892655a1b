"""`magtact reproduce`: the publication's sensitivity beside magtact's, over GP seeds."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from ..publication import SEED_GENERATIONS
from ._app import DataOpt, StudyArg, WorkersOpt, app, check_out, console, get_study, outputs, tables


@app.command("reproduce")
def reproduce_command(
    study: StudyArg = None,
    out: Annotated[Path, typer.Option("--out", "-o", callback=check_out,
                                      help="Output folder (created if needed): a results folder "
                                      "of magtact run; the section lands in OUT/publication and "
                                      "OUT/report.html.")] = Path("results"),
    seeds: Annotated[int, typer.Option(
        "--seeds", help="GP seeds per sensitivity definition (at least 1).")] = 8,
    workers: WorkersOpt = None,
    data: DataOpt = None,
    generations: Annotated[int, typer.Option(
        "--generations", min=1, max=10_000,
        help="GP generations of the fit, for every force fit of the seed study (the design "
             "fit's is [metamodel] generations, 100 for magone).")] = SEED_GENERATIONS,
    definition: Annotated[list[str] | None, typer.Option(
        "--definition", metavar="[jacobian|published]",
        help="Sensitivity definition to include: jacobian or published (repeat for "
             "several); default: both.")] = None,
) -> None:
    """Refit the force models with N seeds under the Jacobian and the published definition of
    Γ, rerun the optimisation, and compare with the publication (CSV, JSON, figures, report)."""
    from ..publication import DEFINITIONS, ComparisonRow, reproduce
    from ..report import build_report, publication_figures

    if seeds < 1:
        raise typer.BadParameter(f"must be at least 1, got {seeds}", param_hint="--seeds")
    for d in definition or ():
        if d not in DEFINITIONS:
            raise typer.BadParameter(
                f"unknown sensitivity definition {d!r} ([sensitivity] definition): choose "
                f"from {', '.join(DEFINITIONS)}", param_hint="--definition")
    s = get_study(study)
    names = ("publication.json", "seeds.csv", "spread.csv", "comparison.csv")
    with outputs("reproduce", out, *(f"publication/{n}" for n in names)) as o:
        folder = o.folder / "publication"
        # the cache of fits stays in place (resumable; its entries are named by their inputs)
        result = reproduce(s, seeds=seeds, workers=1 if workers == 0 else workers, data=data,
                           cache=out / "publication" / "fits", generations=generations,
                           definitions=tuple(definition) if definition else DEFINITIONS,
                           log=lambda m: console.print(m, highlight=False, markup=False))
        files = result.write(folder)
        files += publication_figures(folder)
        o.place()
        report = build_report(out)  # the folder's lock is this command's
    folder = out / "publication"
    table = Table(title=f"magtact and the publication ({s.name}; median [min, max] over "
                        f"{seeds} seeds)")
    rows = [r for r in map(ComparisonRow.from_json, result.comparison) if r is not None]
    cols = rows[0].columns if rows else []
    for c in ["quantity", "scale-free", "publication", *cols]:
        table.add_column(c, justify="left" if c == "quantity" else "right")
    for r in rows:
        table.add_row(escape(f"{r.quantity} [{r.unit}]"), "yes" if r.scale_free else "no",
                      escape(r.publication_text()), *(escape(r.cell_text(c)) for c in cols))
    tables().print(table)
    console.print(f"{len(files)} files in {folder}; report {report} "
                  f"({result.wall_time_s:.0f} s, {result.workers} workers)", highlight=False)
