"""Figures of the validation stage: mean ± std of repeat tests against the model."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..study import from_si, mm
from ._style import save, style, subplots

#: (response, abscissa, plot unit) of the four panels.
PANELS = (("B_r", "u_r", "mT"), ("B_z", "u_z", "mT"), ("F_r", "u_r", "N"), ("F_z", "u_z", "N"))


def fig_validation(validation, path: str | Path) -> list[Path]:
    """Mean ± std band of the tests against the model: B_r(u_r), B_z(u_z), F_r(u_r), F_z(u_z).

    Parameters
    ----------
    validation : magtact.validation.Validation
        Result of :func:`magtact.validation.validate`.
    path : path
        Output file stem; PNG and SVG are written.

    Returns
    -------
    list of Path
        The files written.
    """
    with style():
        fig, axes = subplots(2, 2, figsize=(6.8, 5.0))
        for ax, (name, x_name, unit) in zip(axes.flat, PANELS, strict=True):
            s = validation.stats[name]
            scale = from_si(1.0, unit)
            x = mm(validation.u_r if x_name == "u_r" else validation.u_z)
            for k, y in enumerate(s.curves):
                ax.plot(x, y * scale, color="0.75", lw=0.5,
                        label=f"tests (N = {validation.n_tests})" if k == 0 else None)
            ax.fill_between(x, (s.mean - s.std) * scale, (s.mean + s.std) * scale,
                            color="C0", alpha=0.3, lw=0, label="mean ± std")
            ax.plot(x, s.mean * scale, color="C0", label="mean")
            ax.plot(x, s.model * scale, "--", color="C3", label="model")
            excluded = s.eps_excluded
            if excluded.any() and not excluded.all():
                ax.plot(x[excluded], s.model[excluded] * scale, ".", color="C3", ms=2,
                        label="excluded from ε")
            sub = name.split("_")[1]
            xsub = x_name.split("_")[1]
            ax.set_xlabel(f"$u_{xsub}$ (mm)")
            ax.set_ylabel(f"${name[0]}_{sub}$ ({unit})")
            ax.set_title(f"${name[0]}_{sub}$: $c_v$ = {_pct(s.c_v)}, ε = {_pct(s.eps)}")
            if np.ptp(x) == 0:
                ax.text(0.5, 0.5, "u_r = 0 on this path", transform=ax.transAxes,
                        ha="center")
        axes.flat[0].legend(loc="best", frameon=False)
        fig.suptitle(validation.title + "\nmodel: " + validation.model_label, fontsize=8)
        return save(fig, path)


def _pct(value: float) -> str:
    return "n/a" if not np.isfinite(value) else f"{value:.2g} %"
