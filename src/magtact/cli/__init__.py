"""Command-line interface: a thin layer over the library (typer + rich)."""

from __future__ import annotations

import sys

from rich.markup import escape

from .._errors import MagtactError
from . import (  # noqa: F401  (each module registers its command)
    _budget,
    _calibrate,
    _doe,
    _field,
    _fit,
    _optimise,
    _report,
    _reproduce,
    _run,
    _simulate,
    _study,
    _validate,
)
from ._app import app, console

#: Errors a user can fix: printed as one message, no traceback, exit status 2. Any other
#: exception is a fault of magtact or of a library and keeps its traceback.
USER_ERRORS: tuple[type[Exception], ...] = (MagtactError,)


def main() -> None:
    """Entry point of the ``magtact`` console script."""
    try:
        app()  # standalone: usage errors are printed by typer and exit 2
    except USER_ERRORS as exc:
        console.print(f"[bold red]error:[/] {escape(str(exc))}", highlight=False, soft_wrap=True)
        sys.exit(2)
    except OSError as exc:  # a file or folder the user named cannot be read or written
        console.print(f"[bold red]error:[/] {escape(os_message(exc))}", highlight=False,
                      soft_wrap=True)
        sys.exit(2)


def os_message(exc: OSError) -> str:
    """One line for a failed file operation: the file(s), then the system's reason."""
    files = [str(f) for f in (exc.filename, exc.filename2) if f is not None]
    reason = exc.strerror or str(exc)
    return f"{' -> '.join(files)}: {reason}" if files else reason


__all__ = ["app", "main"]
