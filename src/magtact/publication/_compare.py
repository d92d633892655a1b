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

from .._records import to_json
from ..study import from_si
from . import _reference as ref
from ._file import (  # noqa: F401 (cell_text, publication_text: the table's cells)
    FIGURE_NAMES,
    ComparisonRow,
    DefinitionSpread,
    FailedSpread,
    FigureSpread,
    SeedRecord,
    TrendSpread,
    cell_text,
    publication_text,
)

#: The reading of G as printed, relative to the study's (magone reads 29.4 kPa for 2.94).
PRINTED = 0.1


def _mm(v: float) -> float:
    return from_si(v, "mm")


def _kPa(v: float) -> float:
    return from_si(v, "kPa")


def _mN(v: float) -> float:
    return from_si(v, "mN")


#: Per-seed figures whose spread is reported: name (:class:`DefinitionSpread`'s fields, in
#: their order), label, unit, and the figure of a :class:`SeedRecord` in that unit.
FIGURES: tuple[tuple[str, str, str, Callable[[SeedRecord], float]], ...] = tuple(
    (name, *figure) for name, figure in zip(FIGURE_NAMES, (
        ("held-out max error / range of F_r", "-", lambda r: r.accuracy_of("f_r")),
        ("held-out max error / range of F_z", "-", lambda r: r.accuracy_of("f_z")),
        ("Γ_r,max at the original design", "N/T", lambda r: r.original.Gamma_r_max),
        ("Γ_z,max at the original design", "N/T", lambda r: r.original.Gamma_z_max),
        ("H* (default constraints)", "mm", lambda r: _mm(r.chosen.H)),
        ("G* (default constraints)", "kPa", lambda r: _kPa(r.chosen.G)),
        ("Γ_r,max* (default constraints)", "N/T", lambda r: r.chosen.Gamma_r_max),
        ("Γ_z,max* (default constraints)", "N/T", lambda r: r.chosen.Gamma_z_max),
        ("H* (constraints of the original)", "mm", lambda r: _mm(r.chosen_reference.H)),
        ("G* (constraints of the original)", "kPa", lambda r: _kPa(r.chosen_reference.G)),
        ("worst σ_Fr* with the study's chip", "mN",
         lambda r: _mN(r.chosen.resolution.sigma_Fr_worst) if r.chosen.resolution
         else math.nan),
        ("worst σ_Fz* with the study's chip", "mN",
         lambda r: _mN(r.chosen.resolution.sigma_Fz_worst) if r.chosen.resolution
         else math.nan),
        ("Pareto branches (default constraints)", "-",
         lambda r: math.nan if r.branches is None else r.branches),
    ), strict=True))


def records_of(docs: list[dict]) -> list[SeedRecord]:
    """The seed records of their documents (read field by field; a document that is no JSON
    object left out)."""
    return [r for r in map(SeedRecord.from_json, docs) if r is not None]


def spread(records: list[dict]) -> dict[str, dict[str, dict]]:
    """Per definition and figure: the values over seeds, min, max, and max/min (the document
    of a :class:`DefinitionSpread` per definition).

    A failed fit contributes nothing; ``n`` counts the seeds with a value.
    """
    out: dict[str, dict[str, dict]] = {}
    all_recs = records_of(records)
    for d in dict.fromkeys(r.definition for r in all_recs):
        recs = [r for r in all_recs if r.definition == d and r.ok]
        figs = {}
        for key, label, unit, value in FIGURES:
            vals = np.array([_num(value(r)) for r in recs], dtype=float)
            ok = vals[np.isfinite(vals)]
            lo = float(ok.min()) if ok.size else math.nan
            hi = float(ok.max()) if ok.size else math.nan
            figs[key] = FigureSpread(
                label, unit, tuple(vals.tolist()), int(ok.size), lo, hi,
                (hi / lo if lo != 0 else math.inf if hi > 0 else 1.0) if ok.size else math.nan)
        trends = [r.gamma_z_trend or "?" for r in recs]
        out[d] = to_json(DefinitionSpread(
            **figs,
            gamma_z_trend=TrendSpread("Γ_z along t at the largest H, θ_max", "-",
                                      tuple(trends),
                                      {t: trends.count(t) for t in sorted(set(trends))}),
            failed=FailedSpread("fits that failed", "-",
                                tuple(r.seed for r in all_recs
                                      if r.definition == d and not r.ok))),
            null_nan=False)  # NaN and inf kept (publication.json writes them as null)
    return out


def _curve(rec: SeedRecord) -> np.ndarray:
    c = rec.gamma_z_curve
    return c.Gamma_z if c is not None and c.Gamma_z.size else np.array([math.nan])


def _argmin_t(rec: SeedRecord) -> float:
    c = rec.gamma_z_curve
    if c is None or not c.Gamma_z.size or not np.ptp(c.Gamma_z) > 0:
        return math.nan
    return float(c.t[np.argmin(c.Gamma_z)])


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
    reading of G (median and range over seeds); the documents of :class:`ComparisonRow`.

    Each row: the quantity, its unit, whether it is scale-free, the publication's value (G
    as printed) and, per column ``"<definition>/<reading>"`` (reading ``study`` or
    ``printed``), a cell with ``median``, ``min``, ``max`` (NaN where undefined) or ``text``.
    """
    P = ref.DESIGNS
    rows: list[ComparisonRow] = []
    all_recs = records_of(records)

    def row(quantity, unit, scale_free, publication, value: Callable[[SeedRecord], float],
            scales: bool):
        cols = {}
        for d in dict.fromkeys(r.definition for r in all_recs):
            recs = [r for r in all_recs if r.definition == d and r.ok]
            vals = np.array([_num(value(r)) for r in recs], dtype=float)
            for reading, k in (("study", 1.0), ("printed", PRINTED)):
                v = vals * (k if scales else 1.0)
                ok = v[np.isfinite(v)]
                cols[f"{d}/{reading}"] = (
                    {"median": float(np.median(ok)), "min": float(ok.min()),
                     "max": float(ok.max())} if ok.size else {"text": "—"})
        rows.append(ComparisonRow(quantity, unit, scale_free, publication, cols))

    o = "original"
    row("original design: Γ_r,max", "N/T", False, P[o].Gamma_r_max,
        lambda r: r.original.Gamma_r_max, True)
    row("original design: Γ_z,max", "N/T", False, P[o].Gamma_z_max,
        lambda r: r.original.Gamma_z_max, True)
    row("original design: Γ_z,max / Γ_r,max", "-", True,
        P[o].Gamma_z_max / P[o].Gamma_r_max,
        lambda r: _ratio(r.original.Gamma_z_max, r.original.Gamma_r_max), False)
    row("original design: F_r,min", "N", False, P[o].F_r_min,
        lambda r: r.original.F_r_min, True)
    row("original design: F_z,max", "N", False, P[o].F_z_max,
        lambda r: r.original.F_z_max, True)
    row("original design: F_r,min / F_z,max", "-", True, P[o].F_r_min / P[o].F_z_max,
        lambda r: _ratio(r.original.F_r_min, r.original.F_z_max), False)
    f = "fabricated"
    for label, gamma in (("Γ_r,max", lambda d: d.Gamma_r_max),
                         ("Γ_z,max", lambda d: d.Gamma_z_max)):
        row(f"fabricated (H = 4.1 mm) against original: change of {label}", "%", True,
            (gamma(P[f]) / gamma(P[o]) - 1) * 100,
            lambda r, gamma=gamma: (_ratio(gamma(r.fabricated), gamma(r.original)) - 1) * 100,
            False)
    row("fabricated design: F_z,max", "N", False, P[f].F_z_max,
        lambda r: r.fabricated.F_z_max, True)
    pd = P["optimum_default"]
    row("optimum, default constraints: H*", "mm", True, _mm(pd.H),
        lambda r: _mm(r.chosen.H), False)
    row("optimum, default constraints: G*", "kPa", False, _kPa(pd.G),
        lambda r: _kPa(r.chosen.G), True)
    row("optimum, default constraints: Γ_z,max* / Γ_r,max*", "-", True,
        pd.Gamma_z_max / pd.Gamma_r_max,
        lambda r: _ratio(r.chosen.Gamma_z_max, r.chosen.Gamma_r_max), False)
    row("optimum, default constraints: Pareto branches", "-", True, ref.PARETO_BRANCHES,
        lambda r: math.nan if r.branches is None else r.branches, False)
    pr = P["optimum_reference"]
    row("optimum, constraints of the original: H*", "mm", True, _mm(pr.H),
        lambda r: _mm(r.chosen_reference.H), False)
    row("optimum, constraints of the original: G*", "kPa", False, _kPa(pr.G),
        lambda r: _kPa(r.chosen_reference.G), True)
    row("Γ_z increasing along t at the largest H, θ_max (fraction of seeds)", "-", True, 1.0,
        lambda r: float(r.gamma_z_trend == "increasing"), False)
    row("Γ_z(t = 1) / Γ_z(t = 0) at the largest H, θ_max", "-", True, "> 1 (increasing)",
        lambda r: _ratio(_curve(r)[-1], _curve(r)[0]), False)
    row("t where Γ_z is smallest along the path at the largest H, θ_max", "-", True,
        "0 (increasing)", lambda r: _argmin_t(r), False)
    _printed_feasibility(rows, all_recs)
    return [r.to_json() for r in rows]


def _printed_feasibility(rows: list[ComparisonRow], records: list[SeedRecord]) -> None:
    """Under the printed reading the default constraints (in N) need the same G in Pa as under
    the study's, above the printed range: mark those cells."""
    for row in rows:
        if not row.quantity.startswith("optimum, default constraints"):
            continue
        for key in list(row.cells):
            if key.endswith("/printed"):
                d = key.split("/")[0]
                G = [_kPa(r.chosen.G) for r in records if r.definition == d and r.ok]
                G = [g for g in G if np.isfinite(_num(g))]
                if G:  # the constraints are in N: the same G in Pa under either reading
                    row.cells[key] = {"text": f"infeasible: needs G ≥ {min(G):.3g} kPa, "
                                              f"above the printed range ({_printed_range()})"}


def _printed_range() -> str:
    from ..study import magone_printed

    lo, hi = from_si(magone_printed().design.G, "kPa")
    return f"{lo:g}–{hi:g} kPa"
