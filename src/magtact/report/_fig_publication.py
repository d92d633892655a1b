"""Figures of the comparison with the publication: seed spread, Γ_z along t, Γ_max over H,
the resolution–range lines and the conditioning of the stable-shear bound."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..publication import Conditioning, SeedRecord, Sweep
from ..study import from_si
from ._style import colormap, save, style, subplots

#: Colour and marker of each sensitivity definition.
LOOK = {"jacobian": ("C0", "o"), "published": ("C3", "s")}


def _by_definition(records: list[SeedRecord]) -> dict[str, list[SeedRecord]]:
    out: dict[str, list[SeedRecord]] = {}
    for r in records:
        if r.ok:
            out.setdefault(r.definition, []).append(r)
    return out


def fig_seed_spread(records: list[SeedRecord], path: str | Path) -> list[Path]:
    """Γ_r,max and Γ_z,max of the original design and H* for every seed, per definition."""
    groups = _by_definition(records)
    with style():
        fig, axes = subplots(1, 3, figsize=(7.0, 2.5))
        for k, (value, label, log) in enumerate((
                (lambda r: r.original.Gamma_r_max, r"$\Gamma_{r,\max}$ original [N/T]", True),
                (lambda r: r.original.Gamma_z_max, r"$\Gamma_{z,\max}$ original [N/T]", True),
                (lambda r: from_si(r.chosen.H, "mm"), r"$H^*$ [mm]", False))):
            ax = axes[k]
            for i, (d, recs) in enumerate(groups.items()):
                vals = [value(r) for r in recs]
                color, marker = LOOK.get(d, ("k", "x"))
                x = i + np.linspace(-0.15, 0.15, len(vals))
                ax.plot(x, vals, marker, color=color, ms=4, label=d)
            ax.set_xticks(range(len(groups)), list(groups))
            ax.set_xlim(-0.6, len(groups) - 0.4)
            ax.set_ylabel(label)
            if log:
                ax.set_yscale("log")
        axes[0].legend(loc="best", frameon=False)
        return save(fig, path)


def fig_gamma_z_along_t(records: list[SeedRecord], path: str | Path) -> list[Path]:
    """Γ_z along t at the largest H and θ_max, one line per seed, one panel per definition."""
    groups = _by_definition(records)
    with style():
        fig, axes = subplots(1, max(len(groups), 1), figsize=(7.0, 2.6), squeeze=False)
        for ax, (d, recs) in zip(axes[0], groups.items(), strict=False):
            color, _ = LOOK.get(d, ("k", "x"))
            curves = [r.gamma_z_curve for r in recs if r.gamma_z_curve is not None]
            for c in curves:
                ax.plot(c.t, c.Gamma_z, color=color, lw=0.9, alpha=0.8)
            H, theta = (from_si(curves[0].H, "mm"), curves[0].theta) if curves else (np.nan,
                                                                                   np.nan)
            ax.set(xlabel="t [-]", ylabel=r"$\Gamma_z$ [N/T]",
                   title=f"{d}: H = {H:.3g} mm, θ = {theta:.3g} rad, {len(recs)} seeds")
        return save(fig, path)


def fig_gamma_over_H(records: list[SeedRecord], G: float, path: str | Path) -> list[Path]:
    """Γ_r,max(H) and Γ_z,max(H) at shear modulus G [Pa], one line per seed and definition."""
    groups = _by_definition(records)
    with style():
        fig, axes = subplots(1, 2, figsize=(7.0, 2.6))
        for d, recs in groups.items():
            color, _ = LOOK.get(d, ("k", "x"))
            sweeps = [r.sweep for r in recs if r.sweep is not None]
            for n, s in enumerate(sweeps):
                for ax, gam in zip(axes, (s.gamma_r_max, s.gamma_z_max), strict=True):
                    ax.plot(from_si(s.H, "mm"), G * gam, color=color, lw=0.8,
                            alpha=0.8, label=d if n == 0 else None)
        axes[0].set(xlabel="H [mm]", ylabel=r"$\Gamma_{r,\max}$ [N/T]", yscale="log")
        axes[1].set(xlabel="H [mm]", ylabel=r"$\Gamma_{z,\max}$ [N/T]", yscale="log")
        axes[0].legend(frameon=False)
        fig.suptitle(f"G = {from_si(G, 'kPa'):.3g} kPa", fontsize=9)
        return save(fig, path)


def fig_resolution_range(sweep: Sweep, G_range: tuple[float, float], path: str | Path,
                         n_lines: int = 5) -> list[Path]:
    """Worst sensitivity against measurable force: one line through the origin per H.

    For a height H every design (H, G) has Γ = G γ(H) and F = G f(H): over G it moves along a
    line through the origin of slope γ(H) / f(H). Solid over the G bounds, dotted to the
    origin. Left: Γ_z,max against F_z,max; right: Γ_r,max against |F_r,min|.
    """
    H = from_si(sweep.H, "mm")
    idx = np.unique(np.linspace(0, H.size - 1, n_lines).round().astype(int))
    G = np.linspace(0.0, G_range[1], 50)
    inside = G >= G_range[0]
    cmap = colormap("viridis")
    with style():
        fig, axes = subplots(1, 2, figsize=(7.0, 2.8))
        for n, i in enumerate(idx):
            color = cmap(n / max(len(idx) - 1, 1))
            for ax, g, f in ((axes[0], sweep.gamma_z_max, sweep.f_z_max),
                             (axes[1], sweep.gamma_r_max, sweep.f_r_min)):
                F = G * abs(f[i])
                Gam = G * g[i]
                ax.plot(F, Gam, ":", color=color, lw=0.8)
                ax.plot(F[inside], Gam[inside], "-", color=color, lw=1.6,
                        label=f"H = {H[i]:.3g} mm" if ax is axes[0] else None)
        axes[0].set(xlabel=r"$F_{z,\max}$ [N]", ylabel=r"$\Gamma_{z,\max}$ [N/T]")
        axes[1].set(xlabel=r"$|F_{r,\min}|$ [N]", ylabel=r"$\Gamma_{r,\max}$ [N/T]")
        axes[0].legend(frameon=False, fontsize=7)
        return save(fig, path)


def fig_conditioning(cond: Conditioning, path: str | Path) -> list[Path]:
    """t_m and t_tol over H, and the relative drop of F_z,max between them."""
    with style():
        fig, axes = subplots(1, 2, figsize=(7.0, 2.5))
        H = from_si(cond.H, "mm")
        axes[0].plot(H, cond.t_m, "C0-", label=r"$t_m$ (minimum of $F_r$)")
        axes[0].plot(H, cond.t_tol, "C1--",
                     label=f"smallest t within {cond.tol:.0%} of the range")
        axes[0].set(xlabel="H [mm]", ylabel="t [-]")
        axes[0].legend(frameon=False, fontsize=7)
        axes[1].plot(H, 100 * cond.dF_z_rel, "C3-")
        axes[1].set(xlabel="H [mm]", ylabel=r"drop of $F_{z,\max}$ [%]")
        return save(fig, path)

