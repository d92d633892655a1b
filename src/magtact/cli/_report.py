"""`magtact report`: rebuild the HTML report of a results folder."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ._app import app, console


@app.command("report")
def report_command(
    folder: Annotated[Path, typer.Argument(help="Results folder of 'magtact run'.")],
) -> None:
    """Rebuild FOLDER/report.html from the files in FOLDER (absent stages are reported)."""
    from ..report import build_report

    damaged: dict[str, str] = {}
    path = build_report(folder, damaged=damaged)
    for name, problem in sorted(damaged.items()):
        console.print(f"left out {name}: {problem}", highlight=False, markup=False)
    console.print(f"wrote {path}", highlight=False)
