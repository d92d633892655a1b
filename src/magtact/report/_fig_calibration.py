"""Figure of the calibration: the firmware approximation's error over the stable region and the
size–error frontier of the candidates (docs/method.md §13)."""

from __future__ import annotations

import math
import re
from pathlib import Path

from matplotlib.ticker import LogFormatterSciNotation, NullLocator

from ..study import from_si
from ._style import CMAP_SEQ, save, style, subplots

_SUPERSCRIPT = str.maketrans("0123456789-", "⁰¹²³⁴⁵⁶⁷⁸⁹⁻")
#: Decades beyond which a log axis of the frontier has no minor ticks: there they are a comb of
#: marks a few pixels apart, and much of what the panel costs to draw.
MINOR_TICK_DECADES = 6


class _PlainLogFormatter(LogFormatterSciNotation):
    """The labels of matplotlib's log axis (``10³``, ``2×10⁻⁴``) as plain text.

    The same labels at the same ticks as :class:`matplotlib.ticker.LogFormatterSciNotation`,
    written with Unicode superscripts instead of mathtext, whose parsing is a large part of
    what a log axis of many decades costs to draw, again for each format and resolution.
    """

    def __call__(self, x, pos=None):
        """The label of ``x`` (empty where matplotlib leaves the tick without one)."""
        label = super().__call__(x, pos)
        found = re.fullmatch(r"\$\\mathdefault\{(.*)\}\$", label)
        if found is None:
            return label
        text = re.sub(r"\^\{(-?\d+)\}", lambda m: m.group(1).translate(_SUPERSCRIPT),
                      found.group(1).replace("\\times", "×"))
        return text.replace("-", "\N{MINUS SIGN}")


def draw_calibration(fig, cal) -> list:
    """Draw the three panels of :func:`fig_calibration` on ``fig``; returns the axes.

    Panels: the chosen approximation's |error| of F_r and of F_z [mN] over (t, θ) with the
    target σ_F in the title; the candidates' largest held-out error over σ_F against their
    size in bytes (1 = the target, filled marks: on the frontier).
    """
    # room between the panels: a colour bar's label never meets the next panel's axis label
    axes = fig.subplots(1, 3, gridspec_kw={"wspace": 0.12})
    g = cal.grid
    a = cal.firmware.chosen
    for ax, key, sigma, name in ((axes[0], "err_r", cal.sigma_F[0], "F_r"),
                                 (axes[1], "err_z", cal.sigma_F[1], "F_z")):
        # rasterised: as vector paths the grid's cells make the SVG slow to write and to show
        mesh = ax.pcolormesh(g["t"], g["theta"], from_si(g[key], "mN"), cmap=CMAP_SEQ,
                             shading="auto", rasterized=True)
        fig.colorbar(mesh, ax=ax, label=f"|error of ${name[0]}_{name[2]}$| [mN]")
        ax.set_xlabel("load t")
        ax.set_ylabel("shear angle θ [rad]")
        # the titles' height is given (y=1, as here and in the third panel): placed
        # automatically, each draw would measure the axes' tick labels again to find what
        # stands above the axes, which is nothing
        ax.set_title(f"${name[0]}_{name[2]}$: max {from_si(g[key].max(), 'mN'):.3g} mN, "
                     f"σ_F {from_si(sigma, 'mN'):.3g} mN", fontsize=8, y=1.0)
    ax = axes[2]
    points = cal.firmware.frontier_points()
    colours = {"features": "C2", "poly": "C0", "table": "C1"}
    for kind, marker in (("features", "^"), ("poly", "o"), ("table", "s")):
        sel = [p for p in points if p.kind == kind]
        for filled in (True, False):
            pts = [p for p in sel if p.on_frontier == filled]
            if pts:
                ax.plot([p.bytes for p in pts], [p.error_over_sigma for p in pts],
                        marker, color=colours[kind],
                        mfc=None if filled else "none", ls="none",
                        label=f"{kind}{' (frontier)' if filled else ''}")
    ax.plot([a.bytes], [max(a.err_r / cal.sigma_F[0], a.err_z / cal.sigma_F[1])], "*",
            color="C3", ms=10, label="chosen")
    ax.axhline(1.0, color="0.4", lw=0.8, ls="--")
    ax.set_xscale("log")
    ax.set_yscale("log")
    for axis, limits in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
        axis.set_major_formatter(_PlainLogFormatter())
        axis.set_minor_formatter(_PlainLogFormatter(labelOnlyBase=False))
        if math.log10(limits[1] / limits[0]) > MINOR_TICK_DECADES:
            axis.set_minor_locator(NullLocator())
    ax.set_xlabel("size [bytes]")
    ax.set_ylabel("largest error / $\\sigma_F$")
    reached = "target reached" if cal.firmware.reached else "target NOT reached"
    ax.set_title(f"firmware candidates ({reached})", fontsize=8, y=1.0)
    ax.legend(frameon=False, fontsize=6)
    noise = ", ".join(f"{from_si(v, 'uT'):.3g}" for v in cal.noise)
    fig.suptitle(f"calibration of H = {from_si(cal.map.H, 'mm'):.3g} mm, "
                 f"G = {from_si(cal.map.G, 'kPa'):.3g} kPa: "
                 f"{a.kind} ({a.bytes} bytes); σ_F for σ_B = ({noise}) µT", fontsize=8)
    return list(axes)


def calibration_figure(cal):
    """The calibration figure of a :class:`magtact.calibration.Calibration` as a
    :class:`matplotlib.figure.Figure` (for notebooks: :func:`magtact.figures`)."""
    with style():
        fig, _ = subplots(1, 1, figsize=(10.0, 3.4))
        fig.clear()
        draw_calibration(fig, cal)
    return fig


def fig_calibration(cal, path: str | Path) -> list[Path]:
    """The calibration figure (``calibration.png``/``.svg``) of a
    :class:`magtact.calibration.Calibration`."""
    with style():
        fig, _ = subplots(1, 1, figsize=(10.0, 3.4))
        fig.clear()
        draw_calibration(fig, cal)
        return save(fig, path)


def calibration_figures(cal, folder: str | Path) -> list[Path]:
    """The figures of the calibration stage: ``folder/calibration.{png,svg}``."""
    return fig_calibration(cal, Path(folder) / "calibration")
