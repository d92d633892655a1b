"""Live progress of a design of experiments: one row per job and an overall bar with ETA (rich)."""

from __future__ import annotations

import time

from rich.console import Console, Group
from rich.live import Live
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.table import Table

from ._jobs import Outcome

#: Above this many jobs the table lists only running and failed jobs.
MAX_ROWS = 40
_STYLE = {"cached": "dim", "queued": "", "running": "yellow", "done": "green", "failed": "red"}


class Display:
    """Per-job status table and overall progress bar; a no-op when ``console`` is ``None``.

    Parameters
    ----------
    jobs : list
        Every job of the study (objects with ``key`` and ``label``).
    console : rich.console.Console or None
        Where to draw (``None``: draw nothing).
    """

    def __init__(self, jobs: list, console: Console | None):
        self.console = console
        self.jobs = list(jobs)
        self.status = {job.key: "queued" for job in self.jobs}
        self.note = {job.key: "" for job in self.jobs}
        self.started: dict[str, float] = {}
        self.progress = Progress(TextColumn("{task.description}"), BarColumn(),
                                 MofNCompleteColumn(), TimeElapsedColumn(),
                                 TextColumn("ETA"), TimeRemainingColumn(), console=console)
        self.task = self.progress.add_task("jobs to compute", total=0)
        self.live = (Live(self, console=console, refresh_per_second=2, transient=False)
                     if console is not None else None)

    def __enter__(self) -> Display:
        if self.live is not None:
            self.live.__enter__()
        return self

    def __exit__(self, *exc) -> None:
        if self.live is not None:
            self.live.__exit__(*exc)
            if not self.console.is_terminal:  # the final frame ends without a line break
                self.console.line()

    def cached(self, job) -> None:
        """``job`` was found in the cache."""
        self.status[job.key] = "cached"

    def queue(self, n: int) -> None:
        """``n`` jobs are about to be computed."""
        self.progress.update(self.task, total=n)
        self.progress.reset(self.task, total=n)

    def start(self, job) -> None:
        """``job`` is running."""
        self.status[job.key] = "running"
        self.started[job.key] = time.perf_counter()

    def finish(self, job, outcome: Outcome) -> None:
        """``job`` finished (successfully or not)."""
        if outcome.entry is None:
            self.status[job.key] = "failed"
            self.note[job.key] = outcome.error or ""
        else:
            self.status[job.key] = "done"
            meta = outcome.entry.meta
            extra = (f", {meta['newton_iterations']} it, {meta['cutbacks']} cut-backs"
                     if "newton_iterations" in meta else "")
            self.note[job.key] = f"{outcome.wall_time:.1f} s{extra}"
        self.progress.advance(self.task)

    def __rich__(self) -> Group:
        table = Table(box=None, pad_edge=False, show_header=True, header_style="bold")
        table.add_column("job")
        table.add_column("status")
        table.add_column("")
        shown = self.jobs if len(self.jobs) <= MAX_ROWS else [
            j for j in self.jobs if self.status[j.key] in ("running", "failed")]
        now = time.perf_counter()
        for job in shown:
            status = self.status[job.key]
            note = self.note[job.key]
            if status == "running":
                note = f"{now - self.started[job.key]:.0f} s"
            table.add_row(job.label, f"[{_STYLE[status]}]{status}[/]" if _STYLE[status]
                          else status, note)
        counts = {s: sum(v == s for v in self.status.values()) for s in _STYLE}
        summary = ", ".join(f"{n} {s}" for s, n in counts.items() if n)
        return Group(table, summary, self.progress)
