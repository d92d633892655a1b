"""Command-line interface: a thin layer over the library (typer + rich)."""

from __future__ import annotations

import sys

from rich.markup import escape

from ..study import StudyError
from . import _study  # noqa: F401  (registers the command)
from . import _doe  # noqa: F401
from . import _validate  # noqa: F401
from . import _run  # noqa: F401
from . import _report  # noqa: F401
from . import _optimise  # noqa: F401
from . import _fit  # noqa: F401
from . import _field  # noqa: F401
from . import _simulate  # noqa: F401
from ._app import app, console

#: Errors a user can fix: printed as one message, no traceback, exit status 2.
USER_ERRORS: tuple[type[Exception], ...] = (StudyError, FileNotFoundError, ValueError)


def main() -> None:
    """Entry point of the ``magtact`` console script."""
    try:
        app()  # standalone: usage errors are printed by typer and exit 2
    except USER_ERRORS as exc:
        console.print(f"[bold red]error:[/] {escape(str(exc))}", highlight=False, soft_wrap=True)
        sys.exit(2)


__all__ = ["app", "main"]
