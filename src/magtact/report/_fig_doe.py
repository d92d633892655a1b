"""Figure of a design of experiments: forces and Hall reading along the loading paths."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from ..study import from_si
from ._style import CMAP_SEQ, colormap, save, style, subplots


def fig_doe(ds: xr.Dataset, path: str | Path, *, G: float | None = None) -> list[Path]:
    """Plot F_z, F_r, B_z, B_r against t, one line per base height H, at θ = 0 and θ = θ_max.

    Parameters
    ----------
    ds : xarray.Dataset
        A DOE data set (``magtact.doe.run_doe`` / ``load_dataset`` layout).
    path : path
        Output file stem; PNG and SVG are written.
    G : float, optional
        Shear modulus [Pa] of the force panels; default: the G level nearest the middle.

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    g = ds.G.values[len(ds.G) // 2] if G is None else G
    forces = ds.sel(G=g, method="nearest")
    colours = colormap(CMAP_SEQ)(np.linspace(0.0, 0.85, ds.sizes["H"]))
    panels = [("F_z", 0, "$F_z$ [N]", "N"), ("F_r", -1, "$F_r$ [N]", "N"),
              ("B_z", 0, "$B_z$ [mT]", "mT"), ("B_r", -1, "$B_r$ [mT]", "mT")]
    with style():
        fig, axes = subplots(2, 2, figsize=(6.6, 4.8), sharex=True)
        for ax, (name, i_theta, label, unit) in zip(axes.flat, panels, strict=True):
            da = (forces if name.startswith("F") else ds)[name].isel(theta=i_theta)
            for k, colour in enumerate(colours):
                ax.plot(ds.t, from_si(da.isel(H=k), unit), color=colour, marker="o", ms=2,
                        label=f"H = {from_si(float(ds.H[k]), 'mm'):.3g} mm")
            title = f"θ = {float(ds.theta[i_theta]):.3g} rad"
            if name.startswith("F"):
                title += f", G = {from_si(float(forces.G), 'kPa'):.3g} kPa"
            ax.set_title(title)
            ax.set_ylabel(label)
        for ax in axes[-1]:
            ax.set_xlabel("load $t$ [-]")
        axes[0, 0].legend(frameon=False)
        return save(fig, path)
