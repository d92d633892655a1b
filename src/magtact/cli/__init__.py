"""Command-line interface: a thin layer over the library (typer + rich)."""

from __future__ import annotations

import signal
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


class Terminated(BaseException):
    """The process was asked to stop (SIGTERM); raised in the main thread so that what is
    being written is left as it was (atomic writes remove their temporary file)."""


def _on_sigterm(signum, frame) -> None:
    raise Terminated("by SIGTERM")


def main() -> None:
    """Entry point of the ``magtact`` console script.

    Every non-zero exit says why: a user's error in one line (exit 2), a fault with its
    traceback (exit 1), a specification no design meets with its answer on standard output
    (exit 3: each requirement's best figure, what binds, what to relax), SIGTERM in one line
    (exit 143). A broken pipe is quiet only when it is
    the terminal's own output that was closed (``magtact ... | head``); any other, e.g. to a
    worker process that failed to start, is a fault with its traceback.
    """
    signal.signal(signal.SIGTERM, _on_sigterm)
    try:
        app()  # standalone: usage errors are printed by typer and exit 2
    except Terminated:
        console.print("[bold red]stopped:[/] terminated by a signal (SIGTERM); a run's earlier "
                      "results are left as they were", highlight=False, soft_wrap=True)
        sys.exit(128 + signal.SIGTERM)
    except USER_ERRORS as exc:
        if getattr(exc, "answer", None) is not None:  # no design meets the specification
            from ..report import infeasible_card
            from ._app import EXIT_INFEASIBLE, print_answer

            print_answer(infeasible_card(exc.answer), exc.answer.study or "the study")
            sys.exit(EXIT_INFEASIBLE)
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
