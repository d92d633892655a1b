"""`magtact study`: validate a study file and print it in full, in user units."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ._app import StudyArg, app, get_study


@app.command("study")
def study_command(
    study: StudyArg = None,
    write: Annotated[Path | None, typer.Option("--write", help="Also write the full study here.")]
    = None,
) -> None:
    """Validate STUDY and print every setting (mm, kPa, N), defaults filled in."""
    text = get_study(study).to_toml()
    typer.echo(text)
    if write is not None:
        write.write_text(text, encoding="utf-8")
