"""Figure of the magnet's field: B_r and B_z maps in the plane of shear, Hall point paths."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.colors import SymLogNorm
from matplotlib.patches import Rectangle

from ..study import MU0, Study, from_si
from ._style import CMAP_DIV, save, style, subplots

#: Half-decade colour levels of |B| [mT] below the magnet's polarisation.
_DECADES = np.array([1.0, 2.0, 5.0])


def fig_field(study: Study, path: str | Path, *, solver: str | None = None,
              n: int = 241) -> list[Path]:
    """Filled-contour maps of B_r (along the shear direction x) and B_z around the magnet.

    Parameters
    ----------
    study : Study
        Magnet, placement, loading path and field solver.
    path : path
        Output file stem; PNG and SVG are written.
    solver : {"fe", "exact"}, optional
        Field solver (default ``study.magnetics.solver``).
    n : int
        Grid points along x (z gets as many per mm).

    Returns
    -------
    list of pathlib.Path
        The files written.

    Notes
    -----
    The maps are drawn in the magnet's frame (its centre at the origin) on the plane y = 0,
    with a symmetric logarithmic colour scale (linear within ±1 mT) up to the polarisation
    μ0 M_z. The Hall point's paths for the original base height H and every shear angle level
    are drawn as lines from t = 0 to t = 1 (dots: the DOE load levels).
    """
    from ..geometry import hall_from_magnet_centre, loading_path
    from ..magnetics import magnet_field

    m = study.magnet
    H0 = study.design.H_original
    t = study.t_levels
    paths = [hall_from_magnet_centre(study, *loading_path(study, t, th, H0), H0)
             for th in study.theta_levels]
    _, z_deep = hall_from_magnet_centre(study, 0.0, 0.0, max(study.design.H[1], H0))
    x_reach = max(max(np.abs(px).max() for px, _ in paths), m.R_m)
    x_max = 1.6 * x_reach + 2e-3
    z_lo, z_hi = float(z_deep) - 1.5e-3, 0.5 * m.H_m + 3e-3
    x = np.linspace(-x_max, x_max, n)
    z = np.linspace(z_lo, z_hi, max(2, int(round(n * (z_hi - z_lo) / (2 * x_max)))))
    X, Z = np.meshgrid(x, z)
    B_x, B_z = magnet_field(study, X, Z, solver)
    J = from_si(MU0 * m.M_z, "mT")
    pos = np.concatenate([d * _DECADES for d in 10.0 ** np.arange(0, int(np.log10(J)) + 1)])
    pos = np.append(pos[pos < J], J)
    levels = np.concatenate([-pos[::-1], [0.0], pos])
    norm = SymLogNorm(linthresh=1.0, vmin=-J, vmax=J, base=10)
    ticks = [v for d in 10.0 ** np.arange(0, int(np.log10(J)) + 1) for v in (-d, d)] + [0.0]

    def mm(v):
        return from_si(np.asarray(v), "mm")

    with style():
        fig, axes = subplots(1, 2, figsize=(6.6, 3.9), sharey=True)
        for ax, B, title in ((axes[0], B_x, "$B_r$ (along $x$)"), (axes[1], B_z, "$B_z$")):
            values = np.clip(np.nan_to_num(from_si(B, "mT"), nan=0.0), -J, J)
            cs = ax.contourf(mm(X), mm(Z), values, levels=levels, norm=norm, cmap=CMAP_DIV)
            ax.add_patch(Rectangle((-mm(m.R_m), -mm(m.H_m) / 2), 2 * mm(m.R_m), mm(m.H_m),
                                   fill=False, ec="k", lw=0.9))
            for i, (px, pz) in enumerate(paths):
                ax.plot(mm(px), mm(pz), color="k", lw=0.8, marker=".", ms=2.5,
                        label=f"Hall point path, H = {mm(H0):.3g} mm" if i == 0 else None)
            ax.plot(0.0, mm(paths[0][1][0]), "k^", ms=4)
            ax.set_title(f"{title} [mT]")
            ax.set_xlabel("$x$ [mm]")
            ax.set_aspect("equal")
            ax.set_xlim(mm(x[0]), mm(x[-1]))
            ax.set_ylim(mm(z[0]), mm(z[-1]))
        axes[0].set_ylabel("$z - z_A$ [mm] (magnet centre $A$)")
        axes[0].legend(loc="lower left", frameon=False, fontsize=7)
        cb = fig.colorbar(cs, ax=axes, shrink=0.85, ticks=sorted(ticks))
        cb.set_label("$B$ [mT] (symmetric log scale)")
        cb.ax.set_yticklabels([f"{v:g}".replace("-", "\N{MINUS SIGN}") for v in sorted(ticks)])
        return save(fig, path)
