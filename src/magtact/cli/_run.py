"""`magtact run`: the whole study into one results folder, with its HTML report."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from ._app import (
    EXIT_INFEASIBLE,
    CacheOpt,
    StudyArg,
    WorkersOpt,
    app,
    check_out,
    console,
    get_study,
    out_dir,
    print_answer,
    renamed,
)


@app.command("run")
def run_command(
    study: StudyArg = None,
    out: Annotated[Path, typer.Option("--out", "-o", help="Output folder (created if needed).",
                                      callback=check_out)]
    = Path("results"),
    recompute: Annotated[bool, typer.Option(
        "--recompute", help="Run the study's own FE DOE (the full FE design of experiments, "
                            "cached) instead of using the data set bundled with magtact.")]
    = False,
    refit: Annotated[bool, typer.Option(
        "--refit", help="Fit the metamodels even when the fit shipped with magtact matches the "
                        "data and settings.")] = False,
    measured: Annotated[list[Path] | None, typer.Option(
        "--measured", help="CSV file of measured repeat tests of this sensor, for the "
                           "validation (repeat the option for several); default: the shipped "
                           "SYNTHETIC example of the MagOne sensor.")] = None,
    cache: CacheOpt = Path(".magtact-cache"),
    workers: WorkersOpt = None,
    evidence: Annotated[Path | None, typer.Option(
        "--evidence", help="Folder of benchmark results (*.json, e.g. bench/results of a source "
                           "checkout) to include in the report.")] = None,
    quiet: Annotated[bool, typer.Option(
        "--quiet", "-q", help="No progress lines on standard error; the answer and any warning "
                              "are still printed.")] = False,
    _old_data: Annotated[list[str] | None, renamed("--data", "--measured")] = None,
) -> None:
    """Run STUDY: field, DOE, metamodels, optimisation, validation; write OUT/report.html.

    Progress goes to standard error; the answer (each requirement met or not with its margin,
    and the parts) is printed last on standard output. Exit status 0: done; 3: no design meets
    the requirements (the answer says what binds and what to relax); 1: a stage failed.
    """
    from ..pipeline import run_study

    s = get_study(study)
    log = (lambda m: None) if quiet else (lambda m: console.print(m, highlight=False,
                                                                  markup=False))
    result = run_study(s, out_dir(out), recompute=recompute, refit=refit, data=measured,
                       cache=cache, workers=workers, command="magtact " + " ".join(sys.argv[1:]),
                       evidence=evidence, log=log)
    # warnings first (standard error), so that the answer ends the output
    for r in result.stages:  # a poor fit or a front gap: the answer stands, with its caveat
        for note in (n for n in r.notes if r.status == "warning" and n.startswith("WARNING")):
            console.print(f"[bold yellow]{escape(r.title)}:[/] {escape(note)}", highlight=False)
    bad = [r for r in result.stages if r.status not in ("ok", "warning")
           and not (result.infeasible and r.status == "skipped")]
    if bad:
        console.print("[bold yellow]incomplete:[/] "
                      + escape("; ".join(f"{r.title}: {r.status} ({r.message})" for r in bad)),
                      highlight=False)
    tail = [("report", f"{result.report} ({result.wall_time_s:.0f} s)")]
    if result.answer:
        tail.insert(0, ("card", str(result.folder / "optimise" / "card.json")))
        sys.stderr.flush()
        print_answer(result.answer, s.name, tail)
    else:
        console.print(f"report: {result.report} ({result.wall_time_s:.0f} s)", highlight=False)
    if result.infeasible:
        raise typer.Exit(EXIT_INFEASIBLE)
    if bad:
        raise typer.Exit(1)
