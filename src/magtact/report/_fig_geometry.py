"""Figure of an optimisation over geometric design variables: both Pareto sets in objective
space, and in design space H against each geometric variable."""

from __future__ import annotations

from pathlib import Path

from ..study import mm
from ._style import save, style, subplots

LABELS = {"R_m": r"magnet radius $R_m$ [mm]", "H_m": r"magnet height $H_m$ [mm]",
          "R": r"body radius $R$ [mm]"}


def fig_geometry_pareto(result, out_dir: str | Path) -> list[Path]:
    """``geometry_pareto`` (PNG + SVG): left, Γ_z,max against Γ_r,max of NSGA-II's set (dots)
    and the exact set (crosses), the chosen design circled; then one panel per geometric
    variable: the sets' designs over (H, that variable)."""
    with style():
        return save(draw_geometry_pareto(result), Path(out_dir) / "geometry_pareto")


def draw_geometry_pareto(result):
    """The figure of :func:`fig_geometry_pareto` (a matplotlib Figure, not saved)."""
    n = 1 + len(result.variables)
    with style():
        fig, axes = subplots(1, n, figsize=(3.0 * n, 2.8))
        ax = axes[0]
        ax.plot(result.pareto.Gamma_r_max, result.pareto.Gamma_z_max, ".", color="C0",
                label="NSGA-II")
        ax.plot(result.exact.Gamma_r_max, result.exact.Gamma_z_max, "x", color="C3", ms=4,
                label="exact reduction")
        c = result.choice
        ax.plot([c.design.Gamma_r_max], [c.design.Gamma_z_max], "o", mfc="none", color="k",
                ms=8, label="chosen")
        ax.set(xlabel=r"$\Gamma_{r,\max}$ [N/T]", ylabel=r"$\Gamma_{z,\max}$ [N/T]")
        ax.legend(fontsize=6, frameon=False)
        for ax, name in zip(axes[1:], result.variables, strict=True):
            ax.plot(mm(result.pareto.values["H"]), mm(result.pareto.values[name]), ".",
                    color="C0")
            ax.plot(mm(result.exact.values["H"]), mm(result.exact.values[name]), "x",
                    color="C3", ms=4)
            ax.plot([mm(c.values["H"])], [mm(c.values[name])], "o", mfc="none", color="k",
                    ms=8)
            ax.set(xlabel="base height $H$ [mm]", ylabel=LABELS[name])
    return fig
