"""Shared figure style: journal-like, readable when printed at one column width.

Figures are :class:`matplotlib.figure.Figure` objects made without pyplot, so drawing them
neither needs nor changes the user's matplotlib backend (a notebook keeps its inline plots).
"""

from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path

import matplotlib
from matplotlib.figure import Figure

RC = {
    "font.size": 9,
    "axes.titlesize": 9,
    "axes.labelsize": 9,
    "legend.fontsize": 8,
    "xtick.labelsize": 8,
    "ytick.labelsize": 8,
    "xtick.direction": "in",
    "ytick.direction": "in",
    "xtick.top": True,
    "ytick.right": True,
    "axes.linewidth": 0.8,
    "lines.linewidth": 1.2,
    "figure.dpi": 150,
    "savefig.dpi": 200,
    "savefig.bbox": "tight",
    "figure.constrained_layout.use": True,
}

#: Sequential and diverging colour maps used for every field plot.
CMAP_SEQ = "viridis"
CMAP_DIV = "RdBu_r"


@contextmanager
def style():
    """Context manager applying the magtact figure style."""
    with matplotlib.rc_context(RC):
        yield


def subplots(nrows: int = 1, ncols: int = 1, *, figsize: tuple[float, float], **kwargs):
    """A new figure and its axes, like :func:`matplotlib.pyplot.subplots` but without pyplot.

    Returns
    -------
    (matplotlib.figure.Figure, axes)
        ``axes`` as :meth:`matplotlib.figure.Figure.subplots` returns them.
    """
    fig = Figure(figsize=figsize)
    return fig, fig.subplots(nrows, ncols, **kwargs)


def colormap(name: str):
    """The registered colour map ``name``."""
    return matplotlib.colormaps[name]


def save(fig, path: str | Path, formats: tuple[str, ...] = ("png", "svg")) -> list[Path]:
    """Save ``fig`` as ``path`` with each suffix in ``formats``; return the files.

    Inside :func:`saved_in_background` the figure is handed to a worker process and the files
    exist when the block ends; elsewhere they exist on return."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    targets = [path.with_suffix("." + fmt) for fmt in formats]
    saver = _SAVERS[-1] if _SAVERS else None
    if saver is not None and saver.submit(fig, targets):
        return targets
    _write(fig, targets)
    return targets


def _write(fig, targets: list[Path]) -> None:
    for target in targets:
        fig.savefig(target)
        if fig.get_layout_engine() is not None:
            # the first file fixed the layout; the others keep it instead of solving it again
            fig.set_layout_engine("none")


def _write_pickled(data: bytes, targets: list[Path], rc: dict) -> None:
    """The worker's side of :class:`_Saver`: the figure and the style it was drawn in."""
    import pickle
    import warnings

    warnings.simplefilter("ignore")  # nothing of the worker reaches the terminal
    with matplotlib.rc_context(rc):
        _write(pickle.loads(data), targets)


class _Saver:
    """Figures written by one worker process while the caller goes on computing.

    ``tag`` names what the figures submitted from now on belong to (a run's stage);
    :meth:`finish` waits for every figure and returns the failures by tag."""

    def __init__(self):
        import multiprocessing
        import sys
        from concurrent.futures import ProcessPoolExecutor

        # fork where it is safe and cheap (the worker starts with everything imported); on
        # other systems a fresh interpreter
        method = "fork" if sys.platform.startswith("linux") else "spawn"
        self.pool = ProcessPoolExecutor(max_workers=1,
                                        mp_context=multiprocessing.get_context(method))
        self.jobs: list = []
        self.tag = ""

    def submit(self, fig, targets: list[Path]) -> bool:
        """Queue ``fig``; False where it cannot travel to the worker (it is then written
        here)."""
        import pickle

        try:
            data = pickle.dumps(fig)
        except Exception:  # an artist that does not pickle: written in this process
            return False
        rc = {k: v for k, v in matplotlib.rcParams.items() if k in _RC_TRAVELS}
        self.jobs.append((self.tag, targets,
                          self.pool.submit(_write_pickled, data, targets, rc)))
        return True

    def finish(self) -> dict[str, list[str]]:
        """Wait for every queued figure; ``{tag: ["file: error", ...]}`` of those that failed."""
        failed: dict[str, list[str]] = {}
        for tag, targets, job in self.jobs:
            try:
                job.result()
            except Exception as exc:
                failed.setdefault(tag, []).append(f"{targets[0].name}: "
                                                  f"{type(exc).__name__}: {exc}")
        self.jobs = []
        return failed


#: The rcParams a figure takes to its worker (those of the style and what savefig reads).
_RC_TRAVELS = frozenset(RC) | {k for k in matplotlib.rcParams if k.startswith(("savefig.",
                                                                                "svg.", "pdf.",
                                                                                "path."))}
_SAVERS: list[_Saver] = []


@contextmanager
def saved_in_background():
    """Within the block :func:`save` hands each figure to one worker process and returns at
    once, so that drawing files overlaps the computation that follows; yields the
    :class:`_Saver`, whose ``finish()`` waits for the figures (done again on leaving the
    block, where a failure raises ``RuntimeError`` naming the files). A figure that does not
    pickle is written at once, as outside the block."""
    saver = _Saver()
    _SAVERS.append(saver)
    try:
        yield saver
        failed = saver.finish()
        if failed:
            raise RuntimeError("figures not written: " + "; ".join(
                m for ms in failed.values() for m in ms))
    finally:
        _SAVERS.remove(saver)
        saver.pool.shutdown(wait=True, cancel_futures=True)
