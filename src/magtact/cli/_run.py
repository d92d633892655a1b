"""`magtact run`: the whole study into one results folder, with its HTML report."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer

from ._app import StudyArg, app, check_out, console, get_study, out_dir


@app.command("run")
def run_command(
    study: StudyArg = None,
    out: Annotated[Path, typer.Option("--out", "-o", help="Results folder (created).",
                                      callback=check_out)]
    = Path("results"),
    recompute: Annotated[bool, typer.Option(
        "--recompute", help="Run the full FE design of experiments (cached) instead of using "
                            "the data set bundled with magtact.")] = False,
    refit: Annotated[bool, typer.Option(
        "--refit", help="Fit the metamodels even when the fit shipped with magtact matches the "
                        "data and settings.")] = False,
    data: Annotated[list[Path] | None, typer.Option(
        "--data", help="Validation CSV file (repeat the option for several); default: the "
                       "shipped SYNTHETIC example.")] = None,
    cache: Annotated[Path, typer.Option("--cache", help="DOE job cache folder (--recompute).")]
    = Path(".magtact-cache"),
    workers: Annotated[int | None, typer.Option(
        "--workers", "-j", min=0,
        help="DOE worker processes (default: the number of cores).")] = None,
    evidence: Annotated[Path | None, typer.Option(
        "--evidence", help="Folder of benchmark results (*.json, e.g. bench/results of a source "
                           "checkout) to include in the report.")] = None,
) -> None:
    """Run STUDY: field, DOE, metamodels, optimisation, validation; write OUT/report.html."""
    from ..pipeline import run_study

    s = get_study(study)
    result = run_study(s, out_dir(out), recompute=recompute, refit=refit, data=data, cache=cache,
                       workers=workers, command="magtact " + " ".join(sys.argv[1:]),
                       evidence=evidence,
                       log=lambda m: console.print(m, highlight=False, markup=False))
    from ..report import read_card
    from ._optimise import print_card

    print_card(read_card(result.folder / "optimise"))
    console.print(f"report: {result.report} ({result.wall_time_s:.1f} s)", highlight=False)
    for r in result.stages:  # a poor fit or a front gap: the answer stands, with its caveat
        for note in (n for n in r.notes if r.status == "warning" and n.startswith("WARNING")):
            console.print(f"[bold yellow]{r.title}:[/] {note}", highlight=False)
    bad = [r for r in result.stages if r.status not in ("ok", "warning")]
    if bad:
        console.print("[bold yellow]incomplete:[/] "
                      + "; ".join(f"{r.title}: {r.status} ({r.message})" for r in bad),
                      highlight=False)
        raise typer.Exit(1)
