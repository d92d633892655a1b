"""How magtact writes a number for a reader: one helper, used by the report, the command line
and the ``str`` / notebook displays of results (files keep full precision).
"""

from __future__ import annotations

import math
import re

import numpy as np

#: Significant figures of every number the report and the displays show (the files keep
#: full precision); coefficients of formulas get :data:`COEFFICIENT_DIGITS`.
DIGITS = 3
COEFFICIENT_DIGITS = 4
#: A decimal number in running text (not part of a dotted version or a longer word).
_NUMBER = re.compile(r"(?<![\w.])-?\d+\.\d+(?:[eE][+-]?\d+)?(?![\w.]*\d)")


def sig(v, digits: int = DIGITS) -> str:
    """A number to ``digits`` significant figures, the one way the report writes a number.

    Integers are counts and stay whole; floats read ``12.3``, ``0.0123``, ``1110``, ``1.23e5``
    (``-0`` reads ``0``); NaN reads ``not a number`` and infinities ``∞``; anything else is
    ``str``.
    """
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
        return str(v)
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    v = float(v)
    if math.isnan(v):
        return "not a number"
    if math.isinf(v):
        return "∞" if v > 0 else "−∞"
    if v == 0:
        return "0"
    v = float(f"{v:.{digits - 1}e}")  # rounded first, so 9.996 reads 10.0
    if 1e-3 <= abs(v) < 1e5:  # positional: 1113.51 reads 1110, not 1.11e+03
        places = digits - 1 - math.floor(math.log10(abs(v)))
        return f"{v:.{max(places, 0)}f}"
    mantissa, exponent = f"{v:.{digits - 1}e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def significant_digits(text: str) -> int:
    """Significant digits of a number as written (``"0.0320"`` → 3, ``"22.5693"`` → 6,
    ``"1200"`` → 2: trailing zeros of a whole number are not counted)."""
    mantissa = re.split(r"[eE]", text.lstrip("+-−"))[0]
    digits = mantissa.replace(".", "").lstrip("0")
    if "." not in mantissa:
        digits = digits.rstrip("0")
    return len(digits)


def round_text(text: str, digits: int = DIGITS, above: int = 4) -> str:
    """``text`` with every decimal number of more than ``above`` significant digits written to
    ``digits`` (dotted versions such as ``1.2.3`` and numbers inside words are left alone)."""
    return _NUMBER.sub(lambda m: sig(float(m.group()), digits)
                       if significant_digits(m.group()) > above else m.group(), text)


#: Longest ``str`` of a result object (its notebook display shows the same rows).
MAX_LINES = 25


def text_block(title: str, rows: list[tuple[str, str]]) -> str:
    """``title`` and ``(label, value)`` rows as aligned plain text, at most :data:`MAX_LINES`
    lines (rows past it are counted, not shown)."""
    keep = rows[: MAX_LINES - 1]
    width = max((len(k) for k, _ in keep), default=0)
    lines = [title] + [f"  {k:<{width}}  {v}" for k, v in keep]
    if len(rows) > len(keep):
        lines[-1] = f"  … {len(rows) - len(keep) + 1} more rows"
    return "\n".join(lines)


def html_block(title: str, rows: list[tuple[str, str]]) -> str:
    """The same rows as a small HTML table for notebooks (escaped)."""
    from html import escape

    body = "".join(f'<tr><th style="text-align:left">{escape(k)}</th>'
                   f'<td style="text-align:left">{escape(v)}</td></tr>' for k, v in rows)
    return f"<table><caption style=\"text-align:left\"><b>{escape(title)}</b></caption>" \
           f"{body}</table>"


def mN(v) -> str:
    """A force [N] in mN below 1 N and in N from there (3 significant figures)."""
    return f"{sig(1e3 * v)} mN" if abs(v) < 1.0 else f"{sig(v)} N"


def N(v) -> str:
    """A force [N] in N, 3 significant figures."""
    return f"{sig(v)} N"


def _design_text(a) -> str:
    d = a.design
    text = f"H {sig(1e3 * a.H)} mm, G {sig(1e-3 * a.G)} kPa"
    return text if d.M_z is None else text + f", M_z {sig(1e-6 * d.M_z)} MA/m"


def _saturation_text(a) -> str:
    s = a.saturation
    if not s.saturates:
        return "never along the paths"
    where = "inside" if s.in_region else "beyond"
    axis = "shear" if s.axis == "x" else "normal"
    return f"{axis} axis at F_z = {N(s.F_z)} (t = {sig(s.t)}), {where} the stable region"


def answer_rows(a) -> list[tuple[str, str]]:
    """The rows of a designer's answer (:class:`magtact.designer.DesignAnswer`) in mN, N, mm
    and kPa."""
    d, r = a.design, a.resolution
    rows = [("design", _design_text(a))]
    if r is None:
        rows.append(("resolution", "unknown: give " + " and ".join(a.chip.missing)))
    else:
        rows += [("σ_Fr unloaded / worst", f"{mN(r.sigma_r_0)} / {mN(r.sigma_r_worst)}"),
                 ("σ_Fz unloaded / worst", f"{mN(r.sigma_z_0)} / {mN(r.sigma_z_worst)}")]
    rows += [("normal range F_z,max", N(d.F_z_max)), ("shear range F_r,min", N(d.F_r_min)),
             ("Γ_r,max / Γ_z,max", f"{sig(d.Gamma_r_max)} / {sig(d.Gamma_z_max)} N/T"),
             (f"{a.chip.name} saturates", _saturation_text(a))]
    return rows


def result_rows(result) -> tuple[str, list[tuple[str, str]]]:
    """Title and rows of a :class:`magtact.Result`: the chosen design's answer, the original
    design, the constraints (and the largest error-budget row where the budgets are computed
    already: showing a result computes nothing)."""
    c = result.constraints
    rows = answer_rows(result.chosen)
    rows[0] = ("chosen design", rows[0][1])
    o = result.original
    rows += [("original design", _design_text(o)),
             ("original σ_Fz worst", "unknown" if o.resolution is None
              else mN(o.resolution.sigma_z_worst)),
             ("force constraints", f"F_r,min ≤ {N(c.F_r_c)}, F_z,max ≥ {N(c.F_z_c)}"),
             ("active constraints", ", ".join(result.active_constraints) or "none")]
    budgets = result.__dict__.get("budgets")  # a cached property, computed or not
    if budgets:
        top = budgets[0].largest(1)
        if top:
            rows.append(("largest budget row", f"{top[0].name} ({top[0].component}): "
                                               f"{mN(top[0].worst)} worst"))
    return f"magtact result: {result.study.name} ({result.models_source})", rows


def budget_rows(budget) -> tuple[str, list[tuple[str, str]]]:
    """Title and rows of an error budget (:class:`magtact.budget.Budget`), largest first."""
    rows = []
    if budget.resolution is not None:
        r0, z0, rw, zw = budget.resolution
        rows.append(("resolution σ_Fr / σ_Fz worst", f"{mN(rw)} / {mN(zw)}"))
    ordered = sorted(budget.rows, key=lambda r: -(r.worst if math.isfinite(r.worst) else -1.0))
    for r in ordered:
        worst = mN(r.worst) if math.isfinite(r.worst) else "—"
        rest = mN(r.at_rest) if math.isfinite(r.at_rest) else "—"
        rows.append((f"{r.name} ({r.component})", f"worst {worst}, at rest {rest}"))
    pitch = (budget.array or {}).get("smallest_pitch")
    if pitch is not None:
        rows.append(("smallest array pitch", f"{sig(1e3 * pitch)} mm"))
    title = (f"error budget, {budget.label} design: H {sig(1e3 * budget.H)} mm, "
             f"G {sig(1e-3 * budget.G)} kPa ({budget.chip})")
    return title, rows


def calibration_rows(cal) -> tuple[str, list[tuple[str, str]]]:
    """Title and rows of a calibration (:class:`magtact.calibration.Calibration`)."""
    m, fw = cal.map, cal.firmware.chosen
    F_r, F_z = m.ranges
    rows = [("stable region", f"t ≤ {sig(m.t_m)}, θ ≤ {sig(m.theta_m)} rad"),
            ("force ranges", f"F_r {N(F_r)}, F_z {N(F_z)}"),
            ("field noise σ_B (x / z)",
             f"{sig(1e6 * cal.noise[0])} / {sig(1e6 * cal.noise[1])} µT ({cal.noise_source})"),
            ("target σ_Fr / σ_Fz", f"{mN(cal.sigma_F[0])} / {mN(cal.sigma_F[1])}"),
            ("round trip F → B → F", f"{sig(cal.round_trip)} of the force range"),
            ("firmware map", f"{fw.kind}, {fw.bytes} bytes, {fw.multiplies} multiplications"),
            ("firmware error F_r / F_z", f"{mN(fw.err_r)} / {mN(fw.err_z)}"),
            ("target reached", "yes" if cal.firmware.reached else "no")]
    if cal.unit is not None:
        rows.append(("built unit", "calibrated from its presses"))
    title = (f"calibration: H {sig(1e3 * m.H)} mm, G {sig(1e-3 * m.G)} kPa, forces from "
             f"{m.force_source}")
    return title, rows


class Card(dict):
    """The design card (:attr:`magtact.Result.card`): a dict (``header``, ``rows`` and, where
    the card has them, ``verdict`` and ``parts``) that prints as a few lines and shows as a
    table in a notebook."""

    def _rows(self) -> tuple[str, list[tuple[str, str]]]:
        header = [str(h) for h in self.get("header", [])]
        rows = []
        for v in self.get("verdict") or []:
            if isinstance(v, dict):
                rows.append((("✓ " if v.get("met") else "✗ ") + str(v.get("requirement", "")),
                             round_text(str(v.get("text", "")))))
        for p in self.get("parts") or []:
            if isinstance(p, (list, tuple)) and len(p) == 2:
                rows.append((str(p[0]), round_text(str(p[1]))))
        for r in self.get("rows", []):
            if isinstance(r, (list, tuple)) and r:
                rows.append((str(r[0]), " | ".join(round_text(str(c)) for c in r[1:])))
        return "design card: " + " | ".join(h for h in header if h), rows

    def __str__(self) -> str:
        return text_block(*self._rows())

    def _repr_html_(self) -> str:
        return html_block(*self._rows())
