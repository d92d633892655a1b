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


def short(v, digits: int = DIGITS) -> str:
    """:func:`sig` without trailing zeros after the point (``5 N``, ``6.2 N``): for a figure
    a user wrote or a requirement states, not a measured one."""
    text = sig(v, digits)
    if "." in text and "e" not in text:
        text = text.rstrip("0").rstrip(".")
    return text


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
#: Widest line of a result object's ``str`` (longer values end in "…"; the notebook display
#: and the files keep them whole).
MAX_WIDTH = 100
#: Widest label column of a ``str``: a longer label ends in "…".
LABEL_WIDTH = 42


def clip(text: str, width: int) -> str:
    """``text`` cut to ``width`` characters, ending in "…" where it was cut."""
    return text if len(text) <= width else text[: max(width - 1, 0)] + "…"


#: Lines a long value of a ``str`` wraps onto at most (the last ends in "…" where cut).
MAX_VALUE_LINES = 3


def text_block(title: str, rows: list[tuple[str, str]]) -> str:
    """``title`` and ``(label, value)`` rows as aligned plain text: at most :data:`MAX_LINES`
    lines (rows past it are counted, not shown) of at most :data:`MAX_WIDTH` characters; a
    long value wraps onto :data:`MAX_VALUE_LINES` lines under itself."""
    import textwrap

    width = min(max((len(k) for k, _ in rows), default=0), LABEL_WIDTH)
    indent = " " * (width + 4)
    lines = [clip(title, MAX_WIDTH)]
    for n, (k, v) in enumerate(rows):
        wrapped = textwrap.wrap(str(v), MAX_WIDTH - len(indent), break_long_words=True) or [""]
        if len(wrapped) > MAX_VALUE_LINES:
            wrapped = wrapped[:MAX_VALUE_LINES]
            wrapped[-1] = clip(wrapped[-1] + " …", MAX_WIDTH - len(indent))
        block = [f"  {clip(k, width):<{width}}  {wrapped[0]}"] + [indent + w for w in wrapped[1:]]
        if len(lines) + len(block) > MAX_LINES - (n < len(rows) - 1):
            lines.append(f"  … {len(rows) - n} more rows")
            break
        lines += block
    return "\n".join(lines)


def html_block(title: str, rows: list[tuple[str, str]]) -> str:
    """The same rows as a small HTML table for notebooks (escaped)."""
    from html import escape

    body = "".join(f'<tr><th style="text-align:left">{escape(k)}</th>'
                   f'<td style="text-align:left">{escape(v)}</td></tr>' for k, v in rows)
    return f"<table><caption style=\"text-align:left\"><b>{escape(title)}</b></caption>" \
           f"{body}</table>"


class Shown:
    """Mixin of the records a user gets: ``str`` and the notebook's HTML from one method,
    ``_display_rows() -> (title, rows)``."""

    __slots__ = ()

    def __str__(self) -> str:
        return text_block(*self._display_rows())

    def _repr_html_(self) -> str:
        return html_block(*self._display_rows())


def quantity(v: float, unit: str) -> str:
    """An SI value of ``unit`` ("N", "Hz", "m", "T", "Pa") as a reader reads it: forces in mN
    below 1 N, lengths in mm, fields in mT, moduli in kPa; 3 significant figures."""
    if unit == "N":
        return mN(v)
    scale = {"m": (1e3, "mm"), "T": (1e3, "mT"), "Pa": (1e-3, "kPa")}
    k, label = scale.get(unit, (1.0, unit))
    return f"{sig(k * v)} {label}".rstrip()


#: A margin this small (SI, per unit) is a design on the requirement's limit: a design chosen
#: on a force constraint's boundary meets it to the precision of G (about 1e-8 relative).
ON_LIMIT = {"N": 1e-6, "Hz": 1e-6, "m": 1e-9}


def margin_text(margin, unit: str) -> str:
    """How far a design is beyond a requirement: "margin 1.2 N", "short by 177 mN", "margin 0
    (on the limit)", "margin not known"."""
    if margin is None or (isinstance(margin, float) and math.isnan(margin)):
        return "margin not known"
    m = float(margin)
    if abs(m) <= ON_LIMIT.get(unit, 0.0):
        return "margin 0 (on the limit)"
    return f"margin {quantity(m, unit)}" if m > 0 else f"short by {quantity(-m, unit)}"


def mark(met) -> str:
    """✓ met, ✗ not met, ? not known."""
    return "✓" if met is True else ("?" if met is None else "✗")


def requirement_rows(items) -> list[tuple[str, str]]:
    """``(✓ requirement, answer; margin)`` rows of a verdict as written in ``card.json``
    (:meth:`magtact.designer.Verdict.to_json`)."""
    rows = []
    for v in items or []:
        if not isinstance(v, dict):
            continue
        statement = str(v.get("statement") or v.get("requirement", ""))
        answer = str(v.get("answer") or v.get("text", ""))
        margin = v.get("margin")
        # no margin: not known (met unknown) or not defined (a figure not reached at all)
        tail = (margin_text(margin, str(v.get("unit", "")))
                if "margin" in v and (margin is not None or v.get("met") is None) else "")
        rows.append((f"{mark(v.get('met'))} {statement}",
                     round_text(answer) + (f"; {tail}" if tail else "")))
    return rows


def verdict_title(items) -> str:
    """"every requirement met" / "1 of 3 requirements not met" for a verdict's items."""
    items = [v for v in items or [] if isinstance(v, dict)]
    bad = [v for v in items if v.get("met") is not True]
    if not bad:
        return f"every requirement met ({len(items)})"
    return f"{len(bad)} of {len(items)} requirements not met or not known"


def verdict_rows(verdict) -> tuple[str, list[tuple[str, str]]]:
    """Title and rows of a :class:`magtact.designer.Verdict`: each requirement with its answer
    and margin, then the force noise over the required loads and where the chip saturates."""
    items = verdict.to_json()
    rows = requirement_rows(items)
    if verdict.sigma_r == verdict.sigma_r:
        rows.append(("σ_F over the required loads", f"{mN(verdict.sigma_r)} shear, "
                                                     f"{mN(verdict.sigma_z)} normal"))
    rows.append(("chip saturates at", "never in the stable region"
                 if math.isinf(verdict.F_saturation) else N(verdict.F_saturation)))
    return "verdict: " + verdict_title(items), rows


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


def parts_rows(p) -> tuple[str, list[tuple[str, str]]]:
    """Title and rows of a design's parts (:class:`magtact.designer.Parts`): the magnet's
    grade and size, its magnetisation, the silicones whose G range holds the design's G."""
    size = None
    if getattr(p, "R_m", None) is not None:
        size = f"⌀{short(2e3 * p.R_m)} × {short(1e3 * p.H_m)} mm"
    elif p.size != "custom":
        from .parts import SIZES

        z = SIZES[p.size]
        size = f"⌀{short(2e3 * z.R_m)} × {short(1e3 * z.H_m)} mm"
    magnet = ("no grade named" if p.grade == "custom" else p.grade) + (
        f", {size}" if size else "")
    if p.inside:
        holds = ", ".join(p.inside)
    else:
        around = [n for n in (p.softer, p.stiffer) if n is not None]
        holds = ("none; between " + " and ".join(around)) if around else "none"
    rows = [("magnet", magnet), ("magnetisation M_z", f"{sig(1e-6 * p.M_z)} MA/m"),
            ("silicone", p.silicone),
            ("silicones whose G range holds G", holds)]
    return "parts", rows


def answer_rows(a) -> list[tuple[str, str]]:
    """The rows of a designer's answer (:class:`magtact.designer.DesignAnswer`) in mN, N, mm
    and kPa: the design, its verdict (each requirement with its margin), σ_F, the force ranges,
    the sensitivities and where the chip saturates."""
    d, r = a.design, a.resolution
    rows = [("design", _design_text(a))]
    if a.verdict is not None:
        rows += requirement_rows(a.verdict.to_json())
    if r is None:
        rows.append(("resolution", "unknown: give " + " and ".join(a.chip.missing)))
    else:
        rows += [("σ_Fr unloaded / worst", f"{mN(r.sigma_r_0)} / {mN(r.sigma_r_worst)}"),
                 ("σ_Fz unloaded / worst", f"{mN(r.sigma_z_0)} / {mN(r.sigma_z_worst)}")]
    rows += [("normal range F_z,max", N(d.F_z_max)),
             ("shear range |F_r,min|", N(abs(d.F_r_min))),
             ("Γ_r,max / Γ_z,max", f"{sig(d.Gamma_r_max)} / {sig(d.Gamma_z_max)} N/T"),
             (f"{a.chip.name} saturates", _saturation_text(a))]
    if a.parts is not None:
        rows.append(("magnet", parts_rows(a.parts)[1][0][1]))
    return rows


def answer_title(a) -> str:
    """Title of a designer's answer: its label, the chip and the verdict in a few words."""
    head = ("design" if a.label in ("", "design") else f"{a.label} design") + f", {a.chip.name}"
    if a.verdict is None:
        return head
    return f"{head}: {verdict_title(a.verdict.to_json())}"


def result_rows(result) -> tuple[str, list[tuple[str, str]]]:
    """Title and rows of a :class:`magtact.Result`: the chosen design's answer, the original
    design and the constraints (showing a result computes nothing: its error budgets are
    :func:`magtact.error_budgets`)."""
    c = result.constraints
    rows = answer_rows(result.chosen)
    rows[0] = ("chosen design", rows[0][1])
    o = result.original
    rows += [("original design", _design_text(o)),
             ("original σ_Fz worst", "unknown" if o.resolution is None
              else mN(o.resolution.sigma_z_worst)),
             ("force constraints", f"F_r,min ≤ {N(c.F_r_c)}, F_z,max ≥ {N(c.F_z_c)}"),
             ("active constraints", ", ".join(result.active_constraints) or "none")]
    title = f"magtact result: {result.study.name}"
    if result.chosen.verdict is not None:
        title += f"; chosen design: {verdict_title(result.chosen.verdict.to_json())}"
    return title, rows


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
    which = "" if budget.label in ("", "design") else f" ({budget.label})"
    title = (f"error budget of the design{which}: H {sig(1e3 * budget.H)} mm, "
             f"G {sig(1e-3 * budget.G)} kPa, {budget.chip}")
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


def infeasible_rows(doc: dict) -> tuple[str, list[tuple[str, str]]]:
    """Title and rows of the answer to a specification no design meets (the JSON of
    :class:`magtact.designer.Infeasible`): each requirement with the best figure reached and
    its margin, the requirement that binds and what to relax."""
    verdict = [v for v in doc.get("verdict") or [] if isinstance(v, dict)]
    rows = requirement_rows(verdict)
    binding = next((v for v in verdict if v.get("requirement") == doc.get("binding")), None)
    if binding is not None:
        rows.append(("binds", str(binding.get("statement", doc.get("binding")))))
    relax = doc.get("relaxation")
    others = [str(v.get("statement", v.get("requirement"))) for v in verdict
              if v.get("met") is False and v.get("requirement") not in ("normal", "shear")]
    if isinstance(relax, dict):
        rows.append(("relax", str(relax.get("text")) + (
            " and change: " + "; ".join(others) if others else " makes it feasible")))
    else:
        rows.append(("relax", "no change of one force requirement alone makes it feasible: "
                              "widen the design ranges or choose another magnet"))
    return "no design meets the requirements", rows


def sensor_map_rows(m) -> tuple[str, list[tuple[str, str]]]:
    """Title and rows of a design's field-to-force map (:class:`magtact.calibration.SensorMap`):
    the design, its stable region, the force ranges and where B and F come from."""
    F_r, F_z = m.ranges
    rows = [("design", f"H {sig(1e3 * m.H)} mm, G {sig(1e-3 * m.G)} kPa, "
                       f"M_z {sig(1e-6 * m.study.magnet.M_z * m.field_scale)} MA/m"),
            ("stable region", f"t ≤ {sig(m.t_m)}, θ ≤ {sig(m.theta_m)} rad"),
            ("force ranges", f"|F_r| up to {N(F_r)}, F_z up to {N(F_z)}"),
            ("field from", "the field models" if m.field_source == "models"
             else "the magnet's exact field"),
            ("forces from", "the force models" if m.force_source == "models"
             else "the FE forces of the data set"),
            ("use", "force(B) for readings B [T] (…, 3); field(F) for forces F [N] (…, 3)")]
    return "sensor map F(B)", rows


def silicone_words(name: str, G: float) -> str:
    """The silicone to buy with the design's G [Pa] and the silicone's cited G range, in kPa
    (the card's and the sensor's one wording)."""
    from .parts import SILICONES

    if name == "none":
        return f"G {1e-3 * G:.3g} kPa (no silicone named)"
    if name not in SILICONES:
        return f"{name} (G {1e-3 * G:.3g} kPa)"
    lo, hi = SILICONES[name].G_range
    reach = f"{1e-3 * lo:.3g} kPa" if lo == hi else f"{1e-3 * lo:.3g}–{1e-3 * hi:.3g} kPa"
    return f"{name} (G {1e-3 * G:.3g} kPa; its range {reach})"


def sensor_parts_rows(sensor) -> tuple[str, list[tuple[str, str]]]:
    """Title and rows of one sensor (:class:`magtact.Sensor`): body, magnet and chip in mm,
    kPa and MA/m."""
    grade = "no grade named" if sensor.grade == "custom" else sensor.grade
    rows = [("body", f"H {sig(1e3 * sensor.H)} mm, radius {short(1e3 * sensor.R)} mm"),
            ("silicone", silicone_words(sensor.silicone, sensor.G)),
            ("magnet", f"{grade}, ⌀{short(2e3 * sensor.R_m)} × {short(1e3 * sensor.H_m)} mm, "
                       f"M_z {sig(1e-6 * sensor.M_z)} MA/m"),
            ("Hall chip", sensor.chip + ("" if sensor.setting is None
                                         else f", {sensor.setting.words()}")),
            ("chip standoff below the body", f"{short(1e3 * sensor.standoff)} mm")]
    return "sensor", rows


def run_rows(run) -> tuple[str, list[tuple[str, str]]]:
    """Title and rows of a run (:class:`magtact.pipeline.RunResult`): the answer in a line,
    each stage's status and the report."""
    rows = []
    answer = getattr(run, "answer", None)
    if answer:
        rows += requirement_rows(answer.get("verdict"))
    for r in run.stages:
        took = "" if r.wall_time_s is None else f" ({sig(r.wall_time_s)} s)"
        rows.append((r.title, clip(f"{r.status}{took} {r.message}", MAX_WIDTH - 40)))
    rows.append(("report", str(run.report)))
    title = f"magtact run: {run.folder} ({sig(run.wall_time_s)} s)"
    if answer and answer.get("verdict"):
        title += f"; {verdict_title(answer['verdict'])}"
    return title, rows


def study_rows(study) -> tuple[str, list[tuple[str, str]]]:
    """Title and rows of a :class:`magtact.study.Study`: the sensor, the design ranges and the
    requirements in mm, kPa, N and Hz (``study.to_toml()`` holds every setting)."""
    m, b, d, r = study.magnet, study.body, study.design, study.requirements

    def span(lo, hi, k, unit):
        return f"{short(k * lo)}–{short(k * hi)} {unit}" if lo != hi else f"{short(k * lo)} {unit}"

    grade = "no grade named" if m.grade == "custom" else m.grade
    rows = [("magnet", f"{grade}, ⌀{short(2e3 * m.R_m)} × {short(1e3 * m.H_m)} mm, "
                       f"M_z {sig(1e-6 * m.M_z)} MA/m, {m.placement}"),
            ("body", f"radius {short(1e3 * b.R)} mm, {study.material.silicone}"),
            ("body height H", span(*d.H, 1e3, "mm")),
            ("shear modulus G", span(*d.G, 1e-3, "kPa"))]
    for name, (lo, hi) in study.geometric_variables.items():
        rows.append((name, span(lo, hi, 1e3, "mm")))
    need = [f"0–{short(r.F_z)} N normal", f"0–{short(r.F_r)} N shear"]
    if r.rate > 0:
        need.append(f"{short(r.rate)} Hz")
    if r.resolution > 0:
        need.append(f"σ_F ≤ {short(1e3 * r.resolution)} mN")
    if r.R_max > 0:
        need.append(f"radius ≤ {short(1e3 * r.R_max)} mm")
    sensor = study.optimise.problem == "sensor"
    standoff = (span(*d.standoff, 1e3, "mm") if sensor and d.standoff[1] > 0
                else f"{short(1e3 * study.hall.standoff)} mm")
    rows += [("requirements", ", ".join(need)),
             ("Hall chip", f"{study.hall.chip}, {standoff} below the body"),
             ("problem", "the whole sensor (parts, chip setting)" if sensor
              else "the publication's (H, G)"),
             ("every setting", "study.to_toml()")]
    if study.description:
        rows.insert(0, ("description", study.description))
    return f"study {study.name}", rows
