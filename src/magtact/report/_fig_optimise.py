"""Figures of the optimisation stage: maps over (H, G) and the Pareto set in three spaces."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..study import kpa, mm
from ._style import save, style, subplots

GR, GZ = r"$\Gamma_{r,\max}$", r"$\Gamma_{z,\max}$"
FR, FZ = r"$F_{r,\min}$", r"$F_{z,\max}$"


def _contours(ax, X, Y, Z, color, ls, label):
    cs = ax.contour(X, Y, Z, levels=8, colors=color, linestyles=ls, linewidths=1.0)
    ax.clabel(cs, fontsize=6, fmt="%.3g")
    ax.plot([], [], color=color, ls=ls, label=label)
    return cs


def draw_maps(maps, constraints) -> dict:
    """The figures of :func:`fig_maps` (matplotlib Figures, not saved), by name."""
    X, Y = np.meshgrid(mm(maps.H), kpa(maps.G), indexing="ij")
    with style():
        fig_o, ax = subplots(figsize=(3.4, 2.8))
        _contours(ax, X, Y, maps.Gamma_r_max, "C0", "solid", GR + " [N/T]")
        _contours(ax, X, Y, maps.Gamma_z_max, "C3", "dashed", GZ + " [N/T]")
        ax.set(xlabel="H [mm]", ylabel="G [kPa]")
        ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=2, frameon=False)

        fig_c, ax = subplots(figsize=(3.4, 2.8))
        _contours(ax, X, Y, maps.F_r_min, "C0", "solid", FR + " [N]")
        _contours(ax, X, Y, maps.F_z_max, "C3", "dashed", FZ + " [N]")
        for Z, level, color, ls in ((maps.F_r_min, constraints.F_r_c, "C0", "solid"),
                                    (maps.F_z_max, constraints.F_z_c, "C3", "dashed")):
            if Z.min() < level < Z.max():
                ax.contour(X, Y, Z, levels=[level], colors=color, linestyles=ls, linewidths=2.2)
        ax.plot([], [], color="k", lw=2.2, label="limits")
        ax.set(xlabel="H [mm]", ylabel="G [kPa]")
        ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=3, frameon=False)
    return {"maps_objectives": fig_o, "maps_constraints": fig_c}


def fig_maps(maps, constraints, out_dir: str | Path) -> list[Path]:
    """Contour maps over (H, G): objectives and constraints (two figures, PNG + SVG).

    ``maps_objectives``: Γ_r,max solid, Γ_z,max dashed [N/T]. ``maps_constraints``: F_r,min
    solid, F_z,max dashed [N], with the limits F_r,c and F_z,c drawn bold.
    """
    files = []
    with style():
        for name, fig in draw_maps(maps, constraints).items():
            files += save(fig, Path(out_dir) / name)
    return files


def fig_pareto(opt, path: str | Path) -> list[Path]:
    """Pareto set in objective, constraint and design space, chosen design highlighted.

    NSGA-II's set as points, the exact reduction's Pareto set as a thick line (markers show it
    when it is a single point) on its curve over all feasible H, the chosen design as a star
    (PNG + SVG).
    """
    with style():
        return save(draw_pareto(opt), path)


def draw_pareto(opt):
    """The figure of :func:`fig_pareto` (a matplotlib Figure, not saved)."""
    p, r, c = opt.pareto, opt.reduction, opt.constraints
    front = r.front
    chosen = opt.choice.design
    with style():
        fig, axs = subplots(1, 3, figsize=(7.0, 2.4))
        for ax in axs:
            ax.ticklabel_format(useOffset=False)
        ax = axs[0]
        feas = r.feasible
        ax.plot(r.Gamma_r[feas], r.Gamma_z[feas], "-", color="0.6", lw=1.0,
                label=r"$(H, G^*(H))$, all $H$")
        ax.plot(r.Gamma_r[front], r.Gamma_z[front], "o-", color="0.4", lw=2.5, ms=4, alpha=0.6,
                label="exact Pareto set")
        ax.plot(p.Gamma_r_max, p.Gamma_z_max, ".", color="C0", ms=3,
                label="NSGA-II" if p.generations else "exact front's designs")
        ax.plot(chosen.Gamma_r_max, chosen.Gamma_z_max, "*", color="C3", ms=10, label="chosen")
        ax.set(xlabel=GR + " [N/T]", ylabel=GZ + " [N/T]", title="Objective space")
        ax.legend(loc="upper right")

        ax = axs[1]
        ax.plot(p.F_r_min, p.F_z_max, ".", color="C0", ms=3)
        ax.plot(chosen.F_r_min, chosen.F_z_max, "*", color="C3", ms=10)
        ax.axvline(c.F_r_c, color="k", lw=0.8, ls="--", label="limits")
        ax.axhline(c.F_z_c, color="k", lw=0.8, ls="--")
        ax.legend(loc="upper left")
        ax.set(xlabel=FR + " [N]", ylabel=FZ + " [N]", title="Constraint space")

        ax = axs[2]
        ax.plot(mm(r.H[feas]), kpa(r.G_star[feas]), "-", color="0.6", lw=1.0,
                label=r"$G^*(H)$")
        ax.plot(mm(r.H[front]), kpa(r.G_star[front]), "o-", color="0.4", lw=2.5, ms=4,
                alpha=0.6)
        ax.plot(mm(p.H), kpa(p.G), ".", color="C0", ms=3)
        ax.plot(mm(chosen.H), kpa(chosen.G), "*", color="C3", ms=10)
        H_lo, H_hi = opt.study.design.H
        G_lo, G_hi = opt.study.design.G
        ax.set(xlabel="H [mm]", ylabel="G [kPa]", title="Design space",
               xlim=(mm(H_lo), mm(H_hi)), ylim=(kpa(G_lo), kpa(G_hi)))
        ax.legend(loc="upper right")
    return fig
