"""Spread across seeds and the side-by-side table of magtact against the publication.

Every force and sensitivity is G times a function of the geometry, so a reading of G that is
k times another's scales G*, Γ and F by k at the same H and leaves H*, ratios such as
Γ_z/Γ_r and F_r,min/F_z,max, trends and the Pareto set's shape unchanged: those rows are
"scale-free" and are the ones a comparison across readings can argue from. The reading "as
printed" is the study's own divided by ten (docs/method.md §9); under it the
default force constraints need a G outside the printed range.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from . import _reference as ref

#: The reading of G as printed, relative to the study's (magone reads 29.4 kPa for 2.94).
PRINTED = 0.1


def _get(rec: dict, path: str):
    v = rec
    for k in path.split("."):
        if not isinstance(v, dict) or k not in v:
            return math.nan
        v = v[k]
    return v


#: Per-seed figures whose spread is reported: key, label, unit, path in the record.
FIGURES: tuple[tuple[str, str, str, str], ...] = (
    ("acc_f_r", "held-out max error / range of F_r", "-", "accuracy.f_r.test_max_err_over_range"),
    ("acc_f_z", "held-out max error / range of F_z", "-", "accuracy.f_z.test_max_err_over_range"),
    ("Gamma_r_orig", "Γ_r,max at the original design", "N/T", "original.Gamma_r_max"),
    ("Gamma_z_orig", "Γ_z,max at the original design", "N/T", "original.Gamma_z_max"),
    ("H_star", "H* (default constraints)", "mm", "chosen.H_mm"),
    ("G_star", "G* (default constraints)", "kPa", "chosen.G_kPa"),
    ("Gamma_r_star", "Γ_r,max* (default constraints)", "N/T", "chosen.Gamma_r_max"),
    ("Gamma_z_star", "Γ_z,max* (default constraints)", "N/T", "chosen.Gamma_z_max"),
    ("H_star_ref", "H* (constraints of the original)", "mm", "chosen_reference.H_mm"),
    ("G_star_ref", "G* (constraints of the original)", "kPa", "chosen_reference.G_kPa"),
    ("sigma_Fr_star", "worst σ_Fr* with the study's chip", "mN", "chosen.sigma_Fr_worst_mN"),
    ("sigma_Fz_star", "worst σ_Fz* with the study's chip", "mN", "chosen.sigma_Fz_worst_mN"),
    ("branches", "Pareto branches (default constraints)", "-", "branches"),
)


def spread(records: list[dict]) -> dict[str, dict[str, dict]]:
    """Per definition and figure: the values over seeds, min, max, and max/min.

    A failed fit contributes nothing; ``n`` counts the seeds with a value.
    """
    out: dict[str, dict[str, dict]] = {}
    for d in dict.fromkeys(r["definition"] for r in records):
        recs = [r for r in records if r["definition"] == d and r["ok"]]
        figs = {}
        for key, label, unit, path in FIGURES:
            vals = np.array([_num(_get(r, path)) for r in recs], dtype=float)
            ok = vals[np.isfinite(vals)]
            lo = float(ok.min()) if ok.size else math.nan
            hi = float(ok.max()) if ok.size else math.nan
            figs[key] = {"label": label, "unit": unit, "values": vals.tolist(), "n": int(ok.size),
                         "min": lo, "max": hi,
                         "max_over_min": (hi / lo if lo != 0 else math.inf if hi > 0 else 1.0)
                         if ok.size else math.nan}
        trends = [r.get("gamma_z_trend", "?") for r in recs]
        figs["gamma_z_trend"] = {"label": "Γ_z along t at the largest H, θ_max", "unit": "-",
                                 "values": trends,
                                 "counts": {t: trends.count(t) for t in sorted(set(trends))}}
        figs["failed"] = {"label": "fits that failed", "unit": "-",
                          "values": [r["seed"] for r in records
                                     if r["definition"] == d and not r["ok"]]}
        out[d] = figs
    return out


def _curve(rec: dict) -> list:
    c = rec.get("gamma_z_curve") or {}
    return c.get("Gamma_z") or [math.nan]


def _argmin_t(rec: dict) -> float:
    c = rec.get("gamma_z_curve") or {}
    g = np.asarray(c.get("Gamma_z", []), dtype=float)
    return float(np.asarray(c["t"])[np.argmin(g)]) if g.size and np.ptp(g) > 0 else math.nan


def _ratio(a, b) -> float:
    a, b = _num(a), _num(b)
    return a / b if b != 0 else math.nan


def _num(v) -> float:
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def comparison(records: list[dict]) -> list[dict]:
    """Rows of the side-by-side table: the publication against magtact per definition and
    reading of G (median and range over seeds).

    Each row: ``quantity``, ``unit``, ``scale_free``, ``publication`` (G as printed) and, per
    column key ``"<definition>/<reading>"`` (reading ``study`` or ``printed``), a dict with
    ``median``, ``min``, ``max`` (NaN where undefined) or ``text``.
    """
    P = ref.DESIGNS
    rows: list[dict] = []

    def row(quantity, unit, scale_free, publication, value: Callable[[dict], float],
            scales: bool):
        cols = {}
        for d in dict.fromkeys(r["definition"] for r in records):
            recs = [r for r in records if r["definition"] == d and r["ok"]]
            vals = np.array([_num(value(r)) for r in recs], dtype=float)
            for reading, k in (("study", 1.0), ("printed", PRINTED)):
                v = vals * (k if scales else 1.0)
                ok = v[np.isfinite(v)]
                cols[f"{d}/{reading}"] = (
                    {"median": float(np.median(ok)), "min": float(ok.min()),
                     "max": float(ok.max())} if ok.size else {"text": "—"})
        rows.append({"quantity": quantity, "unit": unit, "scale_free": scale_free,
                     "publication": publication, **cols})

    o = "original"
    row("original design: Γ_r,max", "N/T", False, P[o]["Gamma_r_max"],
        lambda r: _get(r, "original.Gamma_r_max"), True)
    row("original design: Γ_z,max", "N/T", False, P[o]["Gamma_z_max"],
        lambda r: _get(r, "original.Gamma_z_max"), True)
    row("original design: Γ_z,max / Γ_r,max", "-", True,
        P[o]["Gamma_z_max"] / P[o]["Gamma_r_max"],
        lambda r: _ratio(_get(r, "original.Gamma_z_max"), _get(r, "original.Gamma_r_max")), False)
    row("original design: F_r,min", "N", False, P[o]["F_r_min"],
        lambda r: _get(r, "original.F_r_min"), True)
    row("original design: F_z,max", "N", False, P[o]["F_z_max"],
        lambda r: _get(r, "original.F_z_max"), True)
    row("original design: F_r,min / F_z,max", "-", True, P[o]["F_r_min"] / P[o]["F_z_max"],
        lambda r: _ratio(_get(r, "original.F_r_min"), _get(r, "original.F_z_max")), False)
    f = "fabricated"
    for g in ("Gamma_r_max", "Gamma_z_max"):
        label = "Γ_r,max" if g == "Gamma_r_max" else "Γ_z,max"
        row(f"fabricated (H = 4.1 mm) against original: change of {label}", "%", True,
            (P[f][g] / P[o][g] - 1) * 100,
            lambda r, g=g: (_ratio(_get(r, f"fabricated.{g}"), _get(r, f"original.{g}")) - 1) * 100,
            False)
    row("fabricated design: F_z,max", "N", False, P[f]["F_z_max"],
        lambda r: _get(r, "fabricated.F_z_max"), True)
    pd = P["optimum_default"]
    row("optimum, default constraints: H*", "mm", True, pd["H_mm"],
        lambda r: _get(r, "chosen.H_mm"), False)
    row("optimum, default constraints: G*", "kPa", False, pd["G_kPa"],
        lambda r: _get(r, "chosen.G_kPa"), True)
    row("optimum, default constraints: Γ_z,max* / Γ_r,max*", "-", True,
        pd["Gamma_z_max"] / pd["Gamma_r_max"],
        lambda r: _ratio(_get(r, "chosen.Gamma_z_max"), _get(r, "chosen.Gamma_r_max")), False)
    row("optimum, default constraints: Pareto branches", "-", True, ref.PARETO_BRANCHES,
        lambda r: r.get("branches", math.nan), False)
    pr = P["optimum_reference"]
    row("optimum, constraints of the original: H*", "mm", True, pr["H_mm"],
        lambda r: _get(r, "chosen_reference.H_mm"), False)
    row("optimum, constraints of the original: G*", "kPa", False, pr["G_kPa"],
        lambda r: _get(r, "chosen_reference.G_kPa"), True)
    row("Γ_z increasing along t at the largest H, θ_max (fraction of seeds)", "-", True, 1.0,
        lambda r: float(r.get("gamma_z_trend") == "increasing"), False)
    row("Γ_z(t = 1) / Γ_z(t = 0) at the largest H, θ_max", "-", True, "> 1 (increasing)",
        lambda r: _ratio(_curve(r)[-1], _curve(r)[0]), False)
    row("t where Γ_z is smallest along the path at the largest H, θ_max", "-", True,
        "0 (increasing)", lambda r: _argmin_t(r), False)
    _printed_feasibility(rows, records)
    return rows


def _printed_feasibility(rows: list[dict], records: list[dict]) -> None:
    """Under the printed reading the default constraints (in N) need the same G in Pa as under
    the study's, above the printed range: mark those cells."""
    for row in rows:
        if not row["quantity"].startswith("optimum, default constraints"):
            continue
        for key, cell in row.items():
            if key.endswith("/printed") and isinstance(cell, dict):
                d = key.split("/")[0]
                G = [_get(r, "chosen.G_kPa") for r in records if r["definition"] == d and r["ok"]]
                G = [g for g in G if np.isfinite(_num(g))]
                if G:  # the constraints are in N: the same G in Pa under either reading
                    row[key] = {"text": f"infeasible: needs G ≥ {min(G):.3g} kPa, above the "
                                        f"printed range ({_printed_range()})"}


def _printed_range() -> str:
    from ..study import from_si, magone_printed

    lo, hi = from_si(magone_printed().design.G, "kPa")
    return f"{lo:g}–{hi:g} kPa"


def publication_text(value) -> str:
    """The publication's cell: a number or a statement."""
    return f"{value:.3g}" if isinstance(value, int | float) else str(value)


def cell_text(cell: dict, digits: int = 3) -> str:
    """A table cell: ``median [min, max]`` or its text."""
    if "text" in cell:
        return cell["text"]
    m, lo, hi = cell["median"], cell["min"], cell["max"]
    if lo == hi:
        return f"{m:.{digits}g}"
    return f"{m:.{digits}g} [{lo:.{digits}g}, {hi:.{digits}g}]"
