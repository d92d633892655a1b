"""`magtact study`: validate a study file and print it in full, in user units."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from .._errors import MagtactError
from .._files import write_text
from ._app import StudyArg, app, get_study


@app.command("study")
def study_command(
    study: StudyArg = None,
    write: Annotated[Path | None, typer.Option("--write", help="Also write the full study here.")]
    = None,
) -> None:
    """Validate STUDY (every rule a command applies to it) and print every setting (mm, kPa,
    N), defaults filled in."""
    from ..study import check_study

    s = get_study(study)
    check_study(s, None if study is None else str(study))
    text = s.to_toml()
    if write is not None and write.is_dir():
        raise MagtactError(f"--write {write}: Is a directory")
    # an existing file is the user's (its comments, its order): never replaced
    same = write is not None and write.is_file() and write.read_bytes() == text.encode()
    if write is not None and not same and (write.exists() or write.is_symlink()):
        raise MagtactError(f"--write {write}: the file exists and magtact does not replace it; "
                           "remove it or name another file")
    typer.echo(text)
    if write is not None and not same:
        write_text(write, text)
