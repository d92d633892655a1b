"""``metamodels.md``: expressions (LaTeX and text) and the accuracy table."""

from __future__ import annotations

from pathlib import Path

import sympy as sp

from ..study import mm
from ._fit import FitResult
from ._parse import format_expression

_UNITS = {"B_r": "T", "B_z": "T", "f_r": "N/Pa", "f_z": "N/Pa"}
_WHY = {
    "anchor_x": "g(X, Z) − g(0, Z): zero on the axis (symmetry)",
    "log": "exp(g(X, Z)): positive, relative errors",
    "identity": "g",
    "anchor_q": "g(p, q, h) − g(p, 0, h): zero at θ = 0 (mirror symmetry)",
    "anchor_0": "g(p, q, h) − g(0, 0, h): zero when unloaded",
}


def _fmt(x, spec=".3g"):
    return "–" if x is None or x != x else format(x, spec)


def write_markdown(result: FitResult, path: str | Path, *, title: str = "Metamodels",
                   gamma_check: dict | None = None, exact_B: bool = False) -> Path:
    """Write the metamodel report (markdown with LaTeX) to ``path`` and return it."""
    lines = [f"# {title}", "",
             "Symbolic-regression models (docs/method.md §5). Variables: load t [-], shear angle "
             "θ [rad], base height H [m]; features p = t, q = t tan θ, h = H in mm, and the Hall "
             "point relative to the magnet's centre (X, Z) in mm. f = F / G [N/Pa].", "",
             f"Training data SHA-256: `{result.data_hash}`.", "",
             "Held-out (θ [rad], H [mm]) paths: "
             + ", ".join(f"({a:.4g}, {mm(b):.4g})" for a, b in result.holdout), "",
             "## Accuracy", "",
             "| model | transform | R² (held out) | max abs err / range | max rel err (abs) "
             "| max abs err | train: max abs err / range | fit time [s] | seed (tries) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for k, rep in result.reports.items():
        te = rep.test
        lines.append(
            f"| {k} | {rep.transform} | {_fmt(te.r2 if te else None, '.6f')} | "
            f"{_fmt(te.max_abs_err_over_range if te else None)} | "
            f"{_fmt(te.max_rel_err if te else None)} | "
            f"{_fmt(te.max_abs_err if te else None)} {_UNITS[k]} | "
            f"{_fmt(rep.train.max_abs_err_over_range)} | {rep.fit_time_s:.1f} | "
            f"{rep.seed} ({rep.tries}) |")
    lines += ["", "Relative errors are over points with |y| > 5 % of max |y|.", ""]
    if exact_B:
        lines += ["B_r and B_z: the exact closed-form field of the magnet (no fit error).", ""]
    if gamma_check:
        lines += ["## Sensitivity check", "",
                  "Γ of the models against Γ from finite differences of the DOE data "
                  f"(t ≥ {next(iter(gamma_check.values()))['t_min']}); relative difference:", "",
                  "| | where | median | 95th percentile | max | points |",
                  "|---|---|---|---|---|---|"]
        for k, v in gamma_check.items():
            for sfx, label in (("", "all"), ("_interior", "central differences only"),
                               ("_above_floor", f"Γ above {v['floor']:.0%} of its max")):
                if "median" + sfx in v:
                    lines.append(f"| {k} | {label} | {v['median' + sfx]:.3g} | "
                                 f"{v['p95' + sfx]:.3g} | {v['max' + sfx]:.3g} | "
                                 f"{v['n_points' + sfx]} |")
        lines.append("")
        lines += [f"{k}: {v['within_5_percent_above_floor']:.1%} of the points above the floor "
                  f"within 5 %; largest absolute difference {v['max_abs_over_max']:.2%} of "
                  "max Γ." for k, v in gamma_check.items()]
        lines += ["", "The data's finite differences along θ use the DOE's coarse θ levels, so "
                  "part of this difference is the error of the finite differences.", ""]
    lines += ["## Expressions", ""]
    for k, m in result.models.items():
        rep = result.reports[k]
        lines += [f"### {k} [{m.units}]", "",
                  f"Transform: {_WHY.get(rep.transform, rep.transform)}; features "
                  f"{', '.join(rep.features)}.", "",
                  "$$", f"{k} = " + sp.latex(m.expr), "$$", "",
                  "Text (B_r, B_z in T, p = t, q = t tan(theta), H in m):"
                  if {s.name for s in m.expr.free_symbols} & {"B_r", "B_z"}
                  else "Text (t, theta, H in SI):", "", "```", format_expression(m.expr), "```",
                  ""]
    path = Path(path)
    path.write_text("\n".join(lines))
    return path
