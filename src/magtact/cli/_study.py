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
    recompute: Annotated[bool, typer.Option(
        "--recompute", help="Check the study as 'magtact run --recompute' takes it (its own FE "
                            "DOE): without it, a study no bundled data set describes is "
                            "refused, as 'magtact run' refuses it.")] = False,
) -> None:
    """Validate STUDY (every rule a command applies to it, and what 'magtact run' checks: the
    bundled data describe it unless --recompute) and print every setting (mm, kPa, N),
    defaults filled in."""
    from ..study import check_study

    s = get_study(study)
    check_study(s, None if study is None else str(study))
    if not recompute:
        _check_data(s)
    text = s.to_toml()
    if write is not None and write.is_dir():
        raise MagtactError(f"--write {write}: Is a directory")
    # an existing file is the user's (its comments, its order): never replaced; it is the same
    # study only if it holds exactly these bytes (read no further than their length)
    same = write is not None and write.is_file() and _holds(write, text.encode())
    if write is not None and not same and (write.exists() or write.is_symlink()):
        raise MagtactError(f"--write {write}: the file exists and magtact does not replace it; "
                           "remove it or name another file")
    typer.echo(text)
    if write is not None and not same:
        write_text(write, text)


def _check_data(s) -> None:
    """Refuse, as ``magtact run`` does before its DOE stage, a study that no data set bundled
    with magtact describes (:func:`magtact.doe.bundled_for`), saying so and what to run."""
    from ..doe import bundled_for

    try:
        bundled_for(s, advice="check it with --recompute, and run it with magtact run "
                              "--recompute (its own FE DOE)")
    except MagtactError as exc:
        raise MagtactError(f"magtact run would refuse this study: {exc}") from None


def _holds(path: Path, data: bytes) -> bool:
    """Whether the regular file ``path`` holds exactly ``data`` (read through the size-capped
    reader: a larger file is not read)."""
    from .._files import UnreadableFile, read_bytes_capped

    try:
        return read_bytes_capped(path, len(data)) == data
    except UnreadableFile:
        return False
