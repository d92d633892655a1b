"""The typer application and helpers shared by every command."""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from .._errors import MagtactError
from ..study import Study, load_study

app = typer.Typer(
    name="magtact",
    help="Design magnetic soft tactile sensors: field, mechanics, DOE, metamodels, optimisation.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
    # Plain help text: option help carries its unit in brackets ("[mm]", "[kPa]"), which
    # rich's markup would read as a style tag and drop.
    rich_markup_mode=None,
)
console = Console(stderr=True)


@app.callback()
def _root() -> None:
    """magtact: design magnetic soft tactile sensors by simulation and optimisation."""

#: The optional STUDY argument of every command: a TOML file or a preset name.
StudyArg = Annotated[
    str | None,
    typer.Argument(help="Study TOML file or preset ('magone', 'magone-printed'); "
                        "default: the built-in MagOne study."),
]


def check_out(path: Path) -> Path:
    """Option callback of ``--out``: refuse, before any work, a path that cannot become a
    folder (it or a parent is a file)."""
    for parent in (path, *path.parents):
        if parent.exists() and not parent.is_dir():
            raise typer.BadParameter(f"{parent} exists and is not a folder")
    return path


OutOpt = Annotated[Path, typer.Option("--out", "-o", help="Output folder (created if needed).",
                                      callback=check_out)]


def get_study(source: str | None) -> Study:
    """Load the study for a command (errors are reported by :func:`magtact.cli.main`)."""
    return load_study(source)


def out_dir(path: Path) -> Path:
    """Create and return an output folder, checked to be a folder this process can write.

    Raises
    ------
    MagtactError
        If ``path`` (or a parent) exists and is not a folder, or the folder is not writable.
    """
    for parent in (path, *path.parents):
        if parent.exists() and not parent.is_dir():
            raise MagtactError(f"--out {path}: {parent} exists and is not a folder")
    try:
        path.mkdir(parents=True, exist_ok=True)
        probe = tempfile.NamedTemporaryFile(dir=path, prefix=".magtact-write-test-")
        probe.close()
    except OSError as exc:
        raise MagtactError(f"--out {path}: cannot write there ({exc.strerror or exc})") from None
    return path
