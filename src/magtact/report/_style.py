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
    """Save ``fig`` as ``path`` with each suffix in ``formats``; return the files."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    written = []
    for fmt in formats:
        target = path.with_suffix("." + fmt)
        fig.savefig(target)
        written.append(target)
        if fig.get_layout_engine() is not None:
            # the first file fixed the layout; the others keep it instead of solving it again
            fig.set_layout_engine("none")
    return written
