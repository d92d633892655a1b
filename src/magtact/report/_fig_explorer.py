"""The designer's curves over the base height H at the chosen G, from the explorer's numbers
(``optimise/explorer.json``, :func:`magtact.report.explorer_data`): the resolution and the
normal range against where the chip saturates."""

from __future__ import annotations

import io

from ._style import style, subplots


def draw_design_curves(data: dict):
    """Two panels over H at the chosen design's G: σ_F worst (shear and normal) [mN], and the
    normal force range F_z,max with the force at which the chip saturates inside the stable
    region and the constraint F_z,c [N]. Returns the figure."""
    chosen, G_kPa = data["chosen"]["H_mm"], data["chosen"]["G_kPa"]
    j = min(range(len(data["G_kPa"])), key=lambda i: abs(data["G_kPa"][i] - G_kPa))
    grid = [row[j] for row in data["grid"]]  # the column of the chosen G
    G = 1e3 * data["G_kPa"][j]
    H = data["H_mm"]
    with style():
        fig, (left, right) = subplots(1, 2, figsize=(9.0, 3.0))
        for key, label, colour in (("sigma_r_worst", "σ_Fr, worst", "C0"),
                                   ("sigma_z_worst", "σ_Fz, worst", "C3")):
            if all(key in g for g in grid):
                left.plot(H, [1e3 * g[key] * G for g in grid], "o-", ms=3, color=colour,
                          label=label)
        left.set_xlabel("base height H [mm]")
        left.set_ylabel("resolution, 1 σ [mN]")
        left.axvline(chosen, color="0.5", ls=":", lw=1.0, label="chosen H")
        left.legend(frameon=False)
        right.plot(H, [g["F_z_max"] * G for g in grid], "o-", ms=3, color="C3",
                   label="normal range F_z,max")
        sat = [(h, g["sat_F_z"] * G) for h, g in zip(H, grid, strict=True)
               if g["saturates_in_region"] and g["sat_F_z"] is not None]
        if sat:
            right.plot(*zip(*sat, strict=True), "s--", ms=3, color="C1",
                       label="chip saturates at (inside the stable region)")
        right.axhline(data["constraints"]["F_z_c_N"], color="k", ls="--", lw=1.0,
                      label="required F_z,c")
        right.axvline(chosen, color="0.5", ls=":", lw=1.0)
        right.set_xlabel("base height H [mm]")
        right.set_ylabel("normal force [N]")
        right.legend(frameon=False, fontsize=7)
        fig.suptitle(f"over H at the chosen G = {G / 1e3:.3g} kPa")
    return fig


def design_curves_png(data: dict) -> bytes:
    """:func:`draw_design_curves` as PNG bytes (for the report, which embeds it)."""
    buf = io.BytesIO()
    draw_design_curves(data).savefig(buf, format="png")
    return buf.getvalue()



