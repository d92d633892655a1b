"""Figure of the time rows of the error budget: the loop of the force read against the true
force for a press and release, and the hysteresis against the press time (docs/method.md §15)."""

from __future__ import annotations

import re
from pathlib import Path

from ..study import from_si
from ._style import save, style, subplots


def _timed(doc: dict) -> list:
    """(label, time record) of every budget of ``doc`` with a normal press in its time rows."""
    from ..budget import BudgetFile
    from ..viscoelastic import TimeRecord

    read = BudgetFile.from_json(doc)
    out = []
    for b in () if read is None else read.budgets:
        t = TimeRecord.from_json(b.time)
        if t is not None and t.normal_press is not None:
            out.append((b.label, t))
    return out


def draw_time(doc: dict):
    """The time figure of ``budget.json`` (``doc``), or None when no budget has time rows.

    Left: F_z read against F_z true over the press and release of the first budget with time
    rows (the chosen design in a run) at the study's press time, the line F_read = F_true
    dashed. Right: the hysteresis [% of the peak F_z] of the normal press against the press
    time for every budget with time rows and every catalogue silicone with a cited
    relaxation (``time.silicones``).
    """
    entries = _timed(doc)
    if not entries:
        return None
    label, first = entries[0]
    press = first.normal_press
    with style():
        fig, (ax_l, ax_h) = subplots(1, 2, figsize=(8.0, 3.4))
        true = from_si(press.F_true[:, 1], "mN")
        read = from_si(press.F_read[:, 1], "mN")
        ax_l.plot(true, read, color="C3", gid="loop", label="press and release" + (
            "" if first.press_time is None else f" in {first.press_time:.3g} s"))
        lim = [min(true.min(), read.min(), 0.0), max(true.max(), read.max())]
        ax_l.plot(lim, lim, "k--", lw=0.8, label="read = true")
        ax_l.set_xlabel("true $F_z$ [mN]")
        ax_l.set_ylabel("read $F_z$ [mN]")
        if first.hysteresis is not None:
            gap = from_si(first.hysteresis[1], "mN")
            ax_l.set_title(f"{label}: hysteresis "
                           + (f"{gap / 1e3:.3g} N" if gap >= 1e3 else f"{gap:.3g} mN"))
        ax_l.legend(frameon=False)
        for k, (name, t) in enumerate(entries):
            p = t.normal_press
            ax_h.plot(p.press_times, 100 * p.gap[:, 1] / p.peak[:, 1], color=f"C{k}",
                      gid=f"sweep:{k}", label=f"{name} (relaxation of the study)")
        for j, (name, s) in enumerate(sorted(first.silicones.items())):
            ax_h.plot(s.press_times, 100 * s.hysteresis, ls=":", color=f"C{j + 3}",
                      gid=f"silicone:{name}", label=name)
        if first.measured_hysteresis:
            ax_h.axhline(100 * first.measured_hysteresis, color="k", lw=0.8, ls="--",
                         label="MagOne measured (Wang et al. 2016)")
        if first.press_time is not None:
            ax_h.axvline(first.press_time, color="0.6", lw=0.8)
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
    label = _timed(doc)[0][0]
    slug = re.sub(r"[^A-Za-z0-9]+", "_", str(label)).strip("_") or "design"
    return save(fig, Path(folder) / f"time_{slug}", formats)
