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

    console.print(f"wrote {build_report(folder)}", highlight=False)
