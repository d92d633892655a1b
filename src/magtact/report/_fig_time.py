"""Figure of the time rows of the error budget: the loop of the force read against the true
force for a press and release, and the hysteresis against the press time (docs/method.md §15)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ._style import save, style, subplots


def _normal_press(entry: dict) -> dict | None:
    for press in (entry.get("time") or {}).get("presses", []):
        if press["theta_rad"] == 0.0:
            return press
    return None


def draw_time(doc: dict):
    """The time figure of ``budget.json`` (``doc``), or None when no budget has time rows.

    Left: F_z read against F_z true over the press and release of the first budget with time
    rows (the chosen design in a run) at the study's press time, the line F_read = F_true
    dashed. Right: the hysteresis [% of the peak F_z] of the normal press against the press
    time for every budget with time rows and every catalogue silicone with a cited
    relaxation (``time.silicones``).
    """
    entries = [e for e in doc.get("budgets", []) if _normal_press(e) is not None]
    if not entries:
        return None
    first = entries[0]
    loop = _normal_press(first)["loop"]
    with style():
        fig, (ax_l, ax_h) = subplots(1, 2, figsize=(8.0, 3.4))
        true = np.asarray(loop["F_true_mN"])[:, 1]
        read = np.asarray(loop["F_read_mN"])[:, 1]
        ax_l.plot(true, read, color="C3", gid="loop",
                  label=f"press and release in {first['time']['press_time_s']:.3g} s")
        lim = [min(true.min(), read.min(), 0.0), max(true.max(), read.max())]
        ax_l.plot(lim, lim, "k--", lw=0.8, label="read = true")
        ax_l.set_xlabel("true $F_z$ [mN]")
        ax_l.set_ylabel("read $F_z$ [mN]")
        gap = first["time"]["hysteresis_mN"][1]
        ax_l.set_title(f"{first.get('label', '')}: hysteresis "
                       + (f"{gap / 1e3:.3g} N" if gap >= 1e3 else f"{gap:.3g} mN"))
        ax_l.legend(frameon=False)
        for k, e in enumerate(entries):
            sw = _normal_press(e)["rate_sweep"]
            gap = np.asarray(sw["hysteresis_mN"])[:, 1]
            peak = np.asarray(sw["peak_mN"])[:, 1]
            ax_h.plot(sw["press_time_s"], 100 * gap / peak, color=f"C{k}", gid=f"sweep:{k}",
                      label=f"{e.get('label', 'design')} (relaxation of the study)")
        for j, (name, s) in enumerate(sorted((first["time"].get("silicones") or {}).items())):
            ax_h.plot(s["press_time_s"], s["hysteresis_pct"], ls=":", color=f"C{j + 3}",
                      gid=f"silicone:{name}", label=name)
        m = first["time"].get("measured") or {}
        if m.get("hysteresis_pct"):
            ax_h.axhline(m["hysteresis_pct"], color="k", lw=0.8, ls="--",
                         label="MagOne measured (Wang et al. 2016)")
        ax_h.axvline(first["time"]["press_time_s"], color="0.6", lw=0.8)
        ax_h.set_xscale("log")
        ax_h.set_xlabel("press time, rest to full load [s]")
        ax_h.set_ylabel("hysteresis [% of peak $F_z$]")
        ax_h.legend(frameon=False, fontsize=7)
    return fig


def time_figures(doc: dict, folder: str | Path, formats: tuple[str, ...] = ("png",)
                 ) -> list[Path]:
    """``time_<label>.png`` of :func:`draw_time` (nothing when no budget has time rows)."""
    fig = draw_time(doc)
    if fig is None:
        return []
    label = next(e.get("label", "design") for e in doc["budgets"] if _normal_press(e))
    slug = re.sub(r"[^A-Za-z0-9]+", "_", str(label)).strip("_") or "design"
    return save(fig, Path(folder) / f"time_{slug}", formats)
