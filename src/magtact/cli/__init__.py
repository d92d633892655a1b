"""Command-line interface: a thin layer over the library (typer + rich)."""

from __future__ import annotations

import sys

from ..study import StudyError
from ._app import app, console

#: Errors a user can fix: printed as one message, no traceback, exit status 2.
USER_ERRORS: tuple[type[Exception], ...] = (StudyError, FileNotFoundError, ValueError)


def main() -> None:
    """Entry point of the ``magtact`` console script."""
    try:
        app(standalone_mode=False)
    except USER_ERRORS as exc:
        console.print(f"[bold red]error:[/] {exc}", highlight=False)
        sys.exit(2)
    except SystemExit:
        raise
    except Exception as exc:  # click's own usage errors arrive here in non-standalone mode
        import click

        if isinstance(exc, click.ClickException):
            exc.show()
            sys.exit(exc.exit_code)
        if isinstance(exc, click.exceptions.Abort):
            console.print("aborted")
            sys.exit(130)
        raise


__all__ = ["app", "main"]
