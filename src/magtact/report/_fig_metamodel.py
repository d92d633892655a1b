"""Figures of the metamodel stage: the shear force map, the sensitivities, model vs data."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..geometry import loading_path
from ..study import LABEL, Study, from_si, kpa, mm
from ._style import CMAP_DIV, CMAP_SEQ, save, style, subplots


def _grid(study: Study, n: int = 121):
    t = np.linspace(0.0, 1.0, n)
    th = np.linspace(0.0, study.loading.theta_max, n)
    return np.meshgrid(t, th, indexing="ij")


def fig_force_map(models, study: Study, H: float, G: float, path: str | Path,
                  design=None) -> list[Path]:
    """F_r over (t, θ) and over (u_r, u_z) at design (H [m], G [Pa]).

    Shades the region F_r < 0, draws the line F_r = 0 and the optimiser's stable-shear box
    t ≤ t_m, θ ≤ θ_m up to the minimum of F_r (marked by a star). ``design`` is the
    optimiser's :class:`magtact.optimise.DesignResult` at (H, G); computed when not given.
    """
    if design is None:
        from ..optimise import per_design

        design = per_design(models, H, G, study)
    T, TH = _grid(study)
    F_r, _ = models.forces(T, TH, H, G)
    fmin, tm, thm = design.F_r_min, design.t_m, design.theta_m
    u_r, u_z = loading_path(study, T, TH, H)
    lim = np.max(np.abs(F_r))
    with style():
        fig, axes = subplots(1, 2, figsize=(7.0, 3.0))
        for ax, (x, y, xl, yl) in zip(axes, [
                (T, np.degrees(TH), "load $t$ [-]", r"shear angle $\theta$ [deg]"),
                (mm(u_r), mm(u_z), "$u_r$ [mm]", "$u_z$ [mm]")], strict=True):
            cs = ax.contourf(x, y, F_r, levels=21, cmap=CMAP_DIV, vmin=-lim, vmax=lim)
            ax.contourf(x, y, F_r, levels=[-np.inf, 0.0], colors="none", hatches=["////"])
            ax.contour(x, y, F_r, levels=[0.0], colors="k", linewidths=1.2)
            stable = (T <= tm) & (TH <= thm)
            ax.contour(x, y, stable.astype(float), levels=[0.5], colors="C2", linewidths=1.2,
                       linestyles="--")
            star = ((tm, np.degrees(thm)) if x is T else
                    tuple(mm(v) for v in loading_path(study, tm, thm, H)))
            ax.plot(*star, "*", color="C2", ms=9, mec="k", mew=0.5)
            ax.set_xlabel(xl)
            ax.set_ylabel(yl)
        cb = fig.colorbar(cs, ax=axes, shrink=0.9)
        cb.set_label("$F_r$ [N]")
        fig.suptitle(f"$F_r$ at H = {mm(H):.3g} mm, G = {kpa(G):.3g} kPa: hatched $F_r<0$, "
                     f"black $F_r=0$, dashed: stable region up to $F_{{r,min}}$ = {fmin:.3g} N")
        return save(fig, path)


def fig_gamma(models, study: Study, H: float, G: float, path: str | Path) -> list[Path]:
    """Γ_r and Γ_z [N/T] over (t, θ) at design (H [m], G [Pa])."""
    from ..sensitivity import gamma

    T, TH = _grid(study)
    gr, gz = gamma(models, T, TH, H, G)
    with style():
        fig, axes = subplots(1, 2, figsize=(7.0, 3.0))
        for ax, g, lab in zip(axes, (gr, gz), (r"$\Gamma_r$", r"$\Gamma_z$"), strict=True):
            cs = ax.contourf(T, np.degrees(TH), g, levels=21, cmap=CMAP_SEQ)
            ax.contour(T, np.degrees(TH), g, levels=cs.levels[::4], colors="k", linewidths=0.4)
            cb = fig.colorbar(cs, ax=ax)
            cb.set_label(lab + " [N/T]")
            ax.set_xlabel("load $t$ [-]")
            ax.set_ylabel(r"shear angle $\theta$ [deg]")
        fig.suptitle(f"Sensitivity at H = {mm(H):.3g} mm, G = {kpa(G):.3g} kPa")
        return save(fig, path)


def fig_parity(models, table: dict, test_mask: np.ndarray, path: str | Path) -> list[Path]:
    """Model against data for the four responses; held-out paths in orange."""
    names = [("B_r", "mT"), ("B_z", "mT"), ("f_r", "N_per_kPa"), ("f_z", "N_per_kPa")]
    label = {"B_r": "$B_r$", "B_z": "$B_z$", "f_r": "$f_r = F_r/G$", "f_z": "$f_z = F_z/G$"}
    with style():
        fig, axes = subplots(1, 4, figsize=(7.2, 2.1))
        for ax, (k, unit) in zip(axes, names, strict=True):
            y = from_si(np.asarray(table[k]), unit)
            geo = {g: table[g] for g in getattr(models[k], "geometry", ())}  # each row's
            y_hat = from_si(models[k].value(table["t"], table["theta"], table["H"], **geo), unit)
            ax.plot(y[~test_mask], y_hat[~test_mask], ".", ms=2, color="C0", label="train")
            ax.plot(y[test_mask], y_hat[test_mask], ".", ms=2, color="C1", label="held out")
            lo, hi = y.min(), y.max()
            ax.plot([lo, hi], [lo, hi], "k-", lw=0.6)
            ax.set_title(f"{label[k]} [{LABEL.get(unit, unit)}]")
            ax.set_xlabel("data")
        axes[0].set_ylabel("model")
        axes[0].legend(frameon=False, markerscale=3)
        return save(fig, path)
