"""`magtact field`: the magnet's field at the Hall point over the DOE grid, and field maps."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated

import typer

from ._app import OutOpt, Solver, StudyArg, app, console, get_study, outputs


@app.command("field")
def field_command(
    study: StudyArg = None,
    out: OutOpt = Path("field"),
    solver: Annotated[Solver | None, typer.Option(
        "--solver", help="'fe': axisymmetric finite elements; 'exact': closed form. "
                         "Default: the study's magnetics.solver.")] = None,
) -> None:
    """Write OUT/field.csv (t, θ, H, B_r, B_z over the DOE grid) and the B_r, B_z maps."""
    from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

    from ..magnetics import write_field_outputs
    from ..report import field_figures

    s = get_study(study)
    start = time.perf_counter()
    with outputs("field", out, "field.csv") as o, Progress(
            SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn(),
            console=console, transient=True) as bar:
        task = bar.add_task("field", total=None)
        files = write_field_outputs(s, o.folder, solver=None if solver is None else solver.value,
                                    progress=lambda text: bar.update(task, description=text),
                                    figures=field_figures)
        files = [o.final(f) for f in files]
    used = s.magnetics.solver if solver is None else solver.value
    console.print(f"field ({used}) of study '{s.name}': wrote "
                  + ", ".join(str(f) for f in files)
                  + f" in {time.perf_counter() - start:.1f} s", highlight=False)
