"""Figure of the error budget: the false force of every row in mN, log scale, the resolution
marked (docs/method.md §12)."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import TYPE_CHECKING

from .._errors import MagtactError
from ..study import from_si, kpa, mm
from ._style import save, style, subplots

if TYPE_CHECKING:
    from ..budget import Budget

#: Colours of the worst-case and at-rest bars.
WORST, REST = "C3", "C0"


def _budget(entry: Budget | dict) -> Budget:
    """A budget, or one read from its ``budget.json`` entry."""
    from ..budget import Budget

    if isinstance(entry, Budget):
        return entry
    b = Budget.from_json(entry)
    if b is None:
        raise MagtactError("not an error budget: expected a Budget or an entry of "
                           "budget.json's budgets (with its rows)")
    return b


def budget_labels(entry: Budget | dict) -> list[str]:
    """The row names of a budget (or its ``budget.json`` entry) in the order of the
    figure."""
    return list(dict.fromkeys(r.name for r in _budget(entry).rows))


def draw_budget(entry: Budget | dict):
    """The bar chart of one budget (a :class:`magtact.budget.Budget`, or an entry of
    ``budget.json``'s ``budgets``).

    Two panels, F_r and F_z: per row a bar of its worst false force over the stable region and
    one of its false force at rest [mN], on a log axis (a zero is not drawn); the resolution
    (1 σ, worst) as a dashed line. Returns the figure.
    """
    b = _budget(entry)
    names = budget_labels(b)
    value = {(r.name, r.component): r for r in b.rows}
    worst = {} if b.resolution is None else dict(zip(("F_r", "F_z"), b.resolution[2:],
                                                     strict=True))
    with style():
        fig, axes = subplots(1, 2, figsize=(9.5, 0.34 * len(names) + 1.6), sharey=True)
        y = list(range(len(names)))
        for ax, comp in zip(axes, ("F_r", "F_z"), strict=True):
            drawn = []
            for offset, key, colour, label in ((-0.2, "worst", WORST, "worst over the "
                                                "stable region"),
                                               (0.2, "at_rest", REST, "at rest")):
                ys, ws = [], []
                for k, n in enumerate(names):
                    r = value.get((n, comp))
                    v = None if r is None else from_si(getattr(r, key), "mN")
                    if v is not None and math.isfinite(v) and v > 0:
                        ys.append(k + offset)
                        ws.append(v)
                ax.barh(ys, ws, height=0.38, color=colour, label=label, gid=f"{comp}:{key}_mN")
                drawn += ws
            sigma = worst.get(comp)
            sigma = None if sigma is None or not math.isfinite(sigma) else from_si(sigma, "mN")
            if sigma:
                ax.axvline(sigma, color="k", ls="--", lw=1.0, label="resolution (1 σ, worst)")
                drawn.append(sigma)
            ax.set_xscale("log")
            if drawn:
                ax.set_xlim(min(drawn) / 3, max(drawn) * 3)
            ax.set_xlabel(f"false force in ${comp[0]}_{comp[2]}$ [mN]")
        axes[0].set_yticks(y, names)
        axes[0].invert_yaxis()
        handles, labels = axes[0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="outside lower center", ncol=3, frameon=False)
        fig.suptitle(f"{b.label}: H = {mm(b.H):.3g} mm, G = {kpa(b.G):.3g} kPa")
    return fig


def fig_budget(entry: Budget | dict, path: str | Path) -> list[Path]:
    """Draw :func:`draw_budget` and save it as ``path`` (PNG + SVG)."""
    return save(draw_budget(entry), path)


def budget_figures(doc: dict, folder: str | Path, formats: tuple[str, ...] = ("png",)
                   ) -> list[Path]:
    """The figures of ``budget.json`` (``doc``): ``budget_<label>.png`` per design and, where
    the budgets have time rows, ``time_<label>.png`` (:func:`time_figures`; the report embeds
    the PNG; add ``"svg"`` to ``formats`` for print)."""
    from ..budget import BudgetFile
    from ._fig_time import time_figures

    files = []
    read = BudgetFile.from_json(doc)
    for b in () if read is None else read.budgets:
        slug = re.sub(r"[^A-Za-z0-9]+", "_", b.label).strip("_")
        files += save(draw_budget(b), Path(folder) / f"budget_{slug or 'design'}", formats)
    return files + time_figures(doc, folder, formats)
