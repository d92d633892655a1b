"""The design card: the designer's answer for the chosen and the original design in user units
and plain words (no internal keys; the JSON keeps every number)."""

from __future__ import annotations

from pathlib import Path

from .._card import CardChoices
from .._files import write_json
from .._records import to_json
from ..study import from_si, kpa, mm


def _mN(v: float) -> str:
    return f"{from_si(v, 'mN'):.3g} mN"


def card_rows(answers, constraints=None, rtol: float = 1e-2
              ) -> tuple[list[str], list[list[str]]]:
    """Header and rows of the design card for a sequence of :class:`DesignAnswer`.

    ``constraints`` (a ``ForceConstraints``) adds which constraints are active at each design;
    a constraint is active where its margin is within ``rtol`` of its limit (the chip's range
    where the field's margin over the stable region is within ``rtol`` of the range).
    The seed spread is added by :func:`read_card`.
    """
    header = ["", *(a.label for a in answers)]
    chip = answers[0].chip
    rows: list[list[str]] = []

    def row(name, fn):
        rows.append([name, *(fn(a) for a in answers)])

    verdicts = [a.verdict for a in answers]
    if all(v is not None for v in verdicts):  # the verdict leads the card
        for i, r in enumerate(verdicts[0].requirements):
            rows.append([r.statement, *(_verdict_cell(v.requirements[i]) for v in verdicts)])
        if any(getattr(a, "robust", None) is not None for a in answers):
            row(UNITS_ROW, _units_cell)
    row("height H", lambda a: f"{mm(a.H):.3g} mm")
    row("shear modulus G", lambda a: f"{kpa(a.G):.3g} kPa")
    if any(a.parts is not None for a in answers):
        row("magnet (grade, size)", _magnet_text)
    if any(a.standoff > 0 for a in answers):
        row("chip standoff below the body", lambda a: f"{mm(a.standoff):.3g} mm")
    if all(v is not None and v.sigma_r == v.sigma_r for v in verdicts):
        row("force noise σ_F over the required loads, shear / normal (1 σ)",
            lambda a: f"{_mN(a.verdict.sigma_r)} / {_mN(a.verdict.sigma_z)}")
    if any(a.design.M_z is not None for a in answers):
        row("magnetisation M_z (magnet grade)",
            lambda a: "the magnet's own" if a.design.M_z is None
            else f"{from_si(a.design.M_z, 'MA_per_m'):.3g} MA/m")
    if any(a.chip.figures is not None for a in answers):
        row(f"{chip.name} setting and sample rate", _setting_text)
    if any(a.resolution is None for a in answers):
        keys = " and ".join(chip.missing)
        row(f"resolution with the {chip.name}",
            lambda a: f"give {keys} (RMS field noise at your chip setting, > 0)")
    else:
        if all(a.chip.figures is None for a in answers):
            note = f"{chip.name}, noise {from_si(chip.noise_x, 'uT'):.3g} / " \
                   f"{from_si(chip.noise_z, 'uT'):.3g} µT RMS (x / z)"
        else:
            note = f"{chip.name} at the setting above"
        row(f"shear resolution σ_Fr, unloaded / worst ({note})",
            lambda a: _sigma_text(a, "r"))
        row("normal resolution σ_Fz, unloaded / worst", lambda a: _sigma_text(a, "z"))
        if any(a.chip.figures is not None for a in answers):
            row("field noise σ_B of the setting (x / z, RMS, with LSB/√12) and its source",
                _noise_text)
    row("normal force range (largest F_z in the stable region)",
        lambda a: f"{a.design.F_z_max:.3g} N")
    row("shear force range (|F_r| before shear turns unstable)",
        lambda a: f"{-a.design.F_r_min:.3g} N")
    row("chip range (x / z) and saturation", _saturation_text)
    if any(a.parts is not None for a in answers):
        named = answers[0].parts.silicone if answers[0].parts is not None else "none"
        label = "silicones whose G range holds G"
        if named != "none":
            from ..parts import SILICONES

            lo, hi = SILICONES[named].G_range
            label += f" (the chosen sensor's {named}: {_kpa_range(lo, hi)})"
        row(label, _silicone_text)
    if constraints is not None:
        row("active constraints", lambda a: _active(a, constraints, rtol))
    if answers[0].tolerance > 0:
        d = answers[0].tolerance
        row(f"tolerance of G ± {d:.0%}",
            lambda a: f"forces at G − {d:.0%}: {(1 - d) * a.design.F_z_max:.3g} N normal, "
                      f"{-(1 - d) * a.design.F_r_min:.3g} N shear; Γ and σ_F × {1 + d:.3g} "
                      f"at G + {d:.0%}")
    return header, rows


def _verdict_cell(r) -> str:
    return r.answer


#: The card's row of the robust verdict (the report's first screen repeats it under the verdict).
UNITS_ROW = "units built that meet every requirement"


def _units_cell(a) -> str:
    """The robust verdict in a cell: the yield over every requirement with its interval, and
    the requirements the worst corner of the parts' tolerances fails (method.md §16)."""
    rob = getattr(a, "robust", None)
    if rob is None:
        return "not computed"
    lo, hi = rob.interval
    failed = [r.key for r in rob.requirements if not r.met]
    corner = ("the worst corner meets all" if not failed
              else f"the worst corner fails {', '.join(failed)}")
    return (f"{100 * rob.yield_fraction:.3g} % (95 % CI {100 * lo:.3g}–{100 * hi:.3g} %); "
            f"{corner}")


def parts_list(a) -> list[list[str]]:
    """The parts of a design as [label, value] pairs in user units: magnet, silicone, chip and
    its setting, standoff, height."""
    p = a.parts
    out = []
    if p is not None:
        out.append(["magnet", _magnet_text(a)])
        from .._display import silicone_words

        out.append(["silicone", silicone_words(p.silicone, a.G)])
    chip = a.chip.name + (f", {_setting_text(a)}" if a.chip.figures is not None else "")
    out.append(["Hall chip", chip])
    out.append(["chip standoff below the body", f"{mm(a.standoff):.3g} mm"])
    out.append(["body height H", f"{mm(a.H):.3g} mm"])
    return out


def _saturation_text(a) -> str:
    s = a.saturation
    rng = f"±{from_si(a.chip.range_x, 'mT'):.3g} / {from_si(a.chip.range_z, 'mT'):.3g} mT: "
    if not s.saturates:
        return (rng + f"not reached (largest |B| {from_si(s.B_max_x, 'mT'):.3g} / "
                f"{from_si(s.B_max_z, 'mT'):.3g} mT)")
    where = "inside" if s.in_region else "beyond"
    return (rng + f"saturates ({'shear' if s.axis == 'x' else 'normal'} axis) at t = {s.t:.2f}, "
            f"F_z = {s.F_z:.3g} N, {where} the stable region")


def _setting_text(a) -> str:
    f = a.chip.figures
    if f is None:
        return "no setting table"
    text = f"{f.words}; {f.rate:.4g} Hz (full XYZ read, {1e3 * f.conversion_time:.3g} ms)"
    c = a.choice
    if c is not None and not c.holds:
        text += ("; no allowed setting holds the field over the stable region (largest |B| "
                 f"{from_si(c.B_max_x, 'mT'):.3g} / {from_si(c.B_max_z, 'mT'):.3g} mT): the one "
                 "that saturates at the largest load")
    elif c is None and (a.study is None or a.study.optimise.problem != "sensor"):
        text += " (the study's)"
    return text


def _sigma_text(a, axis: str) -> str:
    r, low = a.resolution, a.resolution_low
    s0, sw = (r.sigma_r_0, r.sigma_r_worst) if axis == "r" else (r.sigma_z_0, r.sigma_z_worst)
    text = f"{_mN(s0)} / {_mN(sw)}"
    if low is not None:
        l0, lw = ((low.sigma_r_0, low.sigma_r_worst) if axis == "r"
                  else (low.sigma_z_0, low.sigma_z_worst))
        text += (f" (noise interval: {from_si(l0, 'mN'):.3g}–{from_si(s0, 'mN'):.3g} / "
                 f"{from_si(lw, 'mN'):.3g}–{from_si(sw, 'mN'):.3g} mN)")
    return text


def _uT(pair) -> str:
    lo, hi = (from_si(v, "uT") for v in pair)
    return f"{hi:.3g}" if lo == hi else f"{lo:.3g}–{hi:.3g}"


def _noise_text(a) -> str:
    f = a.chip.figures
    if f is None:
        return "as given in the study"
    if f.noise_source.startswith("measured"):
        src = "measured by the user (the study's hall.noise_*_uT)"
    elif f.setting.gain_sel is None:
        src = "the datasheet's typical figure"
    elif f.interval:
        src = ("datasheet Figs. 2–3 at GAIN_SEL 7, read off the plot; at this gain an "
               "interval: lower end the gain-7 noise in µT, upper end its LSB count × this "
               "gain's LSB")
    else:
        src = "datasheet Figs. 2–3 at GAIN_SEL 7, read off the plot"
    return f"{_uT(f.sigma_x)} / {_uT(f.sigma_z)} µT; {src}"


def _magnet_text(a) -> str:
    p = a.parts
    if p.grade == "custom":
        text = f"M_z {from_si(p.M_z, 'MA_per_m'):.3g} MA/m as given (no grade named)"
    else:
        from ..parts import grade

        g = grade(p.grade)
        text = (f"{p.grade} (B_r {g.B_r_min:.3g}–{g.B_r_max:.3g} T, max {g.max_temperature_C:g} "
                f"°C)")
    if p.R_m is None and p.size != "custom":
        from ..parts import SIZES

        z = SIZES[p.size]
        return text + f", ⌀{mm(2 * z.R_m):.3g} × {mm(z.H_m):.3g} mm"
    if p.R_m is None:
        return text
    return text + f", ⌀{mm(2 * p.R_m):.3g} × {mm(p.H_m):.3g} mm"


def silicone_table(opt) -> list[list[str]]:
    """The best sensor of each silicone the sensor problem chose from, as [silicone with its
    G range, the sensor in words] pairs (``opt``: its
    :class:`magtact.optimise.SensorOptimisation`; [] where it chose from one silicone)."""
    from ..parts import SILICONES

    if opt is None or len(opt.silicones) < 2:
        return []
    rows = []
    for name, d in zip(opt.silicones, opt.per_silicone, strict=True):
        label = (f"best with {name} ({_kpa_range(*SILICONES[name].G_range)})"
                 if name in SILICONES else f"best with {name}")
        if d is None:
            text = "no sensor meets the problem"
        else:
            chosen = d.silicone == opt.choice.silicone
            text = (f"σ_F {_mN(d.sigma_r)} / {_mN(d.sigma_z)} (shear / normal) at H "
                    f"{mm(d.H):.3g} mm, G {kpa(d.G):.3g} kPa, {d.grade}, chip "
                    f"{mm(d.standoff):.3g} mm below" + ("; the chosen silicone" if chosen
                                                        else ""))
        rows.append([label, text])
    return rows


def size_table(opt) -> list[list[str]]:
    """The best sensor of each magnet size the sensor problem chose from (the reduction's, on
    the nominal parts: the chosen size's is then designed for its tolerances), as [size, the
    sensor in words or why there is none] pairs (``opt``: its
    :class:`magtact.optimise.SensorOptimisation`; [] where it chose from one size)."""
    from ..parts import SIZES

    if opt is None or len(opt.sizes) < 2:
        return []
    rows = []
    for name, d, note in zip(opt.sizes, opt.per_size, opt.size_notes, strict=True):
        z = SIZES[name]
        label = f"nominal best, ⌀{mm(2 * z.R_m):.3g} × {mm(z.H_m):.3g} mm magnet"
        if d is None:
            text = note
        else:
            text = (f"σ_F {_mN(d.sigma_r)} / {_mN(d.sigma_z)} (shear / normal) at H "
                    f"{mm(d.H):.3g} mm, G {kpa(d.G):.3g} kPa ({d.silicone}), {d.grade}, chip "
                    f"{mm(d.standoff):.3g} mm below"
                    + (f"; {note}" if note else "")
                    + ("; the chosen size" if name == opt.size else ""))
        rows.append([label, text])
    return rows




def _kpa_range(lo: float, hi: float) -> str:
    return (f"{kpa(lo):.3g} kPa" if lo == hi else f"{kpa(lo):.3g}–{kpa(hi):.3g} kPa")


def _silicone_text(a) -> str:
    from ..parts import SILICONES

    p = a.parts

    def named(n):
        return f"{n} ({_kpa_range(*SILICONES[n].G_range)})"

    if p.inside:
        return ", ".join(named(n) for n in p.inside)
    around = [n for n in (p.softer, p.stiffer) if n is not None]
    return "none; between " + " and ".join(named(n) for n in around) if around else "none"


def _active(a, constraints, rtol: float) -> str:
    names = {"F_r": "shear", "F_z": "normal force"}
    active = [names[k] for k in constraints.active(a.design.F_r_min, a.design.F_z_max, rtol)]
    if abs(a.saturation.region_margin) <= rtol:
        active.append("chip range")
    return ", ".join(active) or "none"


def write_card(answers, folder, constraints=None, rtol: float = 1e-2, study=None,
               extra_rows: list[list[str]] | None = None,
               silicones: list[list[str]] | None = None,
               sizes: list[list[str]] | None = None) -> Path:
    """Write ``card.json`` (the card's rows and every number of each answer) into ``folder``.

    ``study`` names the study and its sensitivity definition, so that :func:`read_card` can add
    the seed spread of a ``magtact reproduce`` run of the same study. ``extra_rows`` (one cell
    per answer after the row's name, e.g. the error budget's largest rows) end the card.
    """
    from ..designer import answer_json

    header, rows = card_rows(answers, constraints, rtol=rtol)
    rows = rows + [list(r) for r in (extra_rows or [])]
    doc = {"header": header, "rows": rows, "answers": [answer_json(a) for a in answers]}
    if answers[0].verdict is not None:  # the chosen design's verdict and parts lead the card
        doc = {"verdict": answers[0].verdict.to_json(), "parts": parts_list(answers[0])} | doc
    doc |= to_json(CardChoices(silicones or (), sizes or ()))
    if study is not None:
        doc |= {"study": study.name, "definition": study.sensitivity.definition}
    return write_json(Path(folder) / "card.json", doc, indent=1, ensure_ascii=False)


def read_card(folder, publication=None) -> dict | None:
    """The card written by :func:`write_card`, or None.

    Its rows end with the seed spread of the answer: from ``publication/publication.json``
    (default ``../publication``, written by ``magtact reproduce`` into the same results folder)
    when that holds the same study, else a row saying how to measure it.
    """
    from ._fragments import load_json

    folder = Path(folder)
    card = load_json(folder / "card.json", card_problem)
    if card is None:
        return None
    publication = folder.parent / "publication" if publication is None else Path(publication)
    pub = load_json(publication / "publication.json")
    card["rows"] = card["rows"] + spread_rows(pub, card, len(card["header"]))
    return card


#: Most columns (designs) and rows a card may hold (the writer gives two designs and a few
#: tens of rows).
MAX_CARD_COLUMNS = 16
MAX_CARD_ROWS = 500


def card_problem(card) -> str | None:
    """What is wrong with a card document's shape (None where it is the shape
    :func:`write_card` writes): a header of at most :data:`MAX_CARD_COLUMNS` texts, at most
    :data:`MAX_CARD_ROWS` rows of as many texts, a verdict of requirement objects and parts
    of [label, value] pairs where given."""
    if not isinstance(card, dict):
        return "is not a design card (a JSON object)"
    header, rows = card.get("header"), card.get("rows")
    if not isinstance(header, list) or not 1 <= len(header) <= MAX_CARD_COLUMNS or not all(
            isinstance(h, str) for h in header):
        return f"header must be 1 to {MAX_CARD_COLUMNS} texts"
    if not isinstance(rows, list) or len(rows) > MAX_CARD_ROWS:
        return f"rows must be a list of at most {MAX_CARD_ROWS} rows"
    for k, r in enumerate(rows):
        if not isinstance(r, list) or len(r) != len(header) or not all(
                isinstance(c, str) for c in r):
            return f"row {k + 1} must be {len(header)} texts, one per header column"
    verdict, parts = card.get("verdict", []), card.get("parts", [])
    if not isinstance(verdict, list) or len(verdict) > MAX_CARD_ROWS or not all(
            isinstance(v, dict) for v in verdict):
        return f"verdict must be a list of at most {MAX_CARD_ROWS} requirements"
    if not isinstance(parts, list) or len(parts) > MAX_CARD_ROWS or not all(
            isinstance(q, list) and len(q) == 2 for q in parts):
        return f"parts must be a list of at most {MAX_CARD_ROWS} [label, value] pairs"
    return None


#: Seed-study figures on the card: label, unit, key for the chosen and for the original design.
SPREAD: tuple[tuple[str, str, str, str | None], ...] = (
    ("height H", "mm", "H_star", None),
    ("shear modulus G", "kPa", "G_star", None),
    ("sensitivity Γ_r,max", "N/T", "Gamma_r_star", "Gamma_r_orig"),
    ("sensitivity Γ_z,max", "N/T", "Gamma_z_star", "Gamma_z_orig"),
    ("worst σ_Fr", "mN", "sigma_Fr_star", None),
    ("worst σ_Fz", "mN", "sigma_Fz_star", None),
)


def spread_rows(publication: dict | None, card: dict, columns: int) -> list[list[str]]:
    """Rows of the card for the seed spread (min – max over the GP seeds of a seed study); a
    figure whose count, minimum or maximum is not a number is left out."""
    from .._files import json_dict, json_text

    pad = max(columns - 2, 0)
    figs = None
    if isinstance(publication, dict) and publication.get("study") == card.get("study"):
        figs = json_dict(publication.get("spread")).get(json_text(card.get("definition")))
    if not isinstance(figs, dict):
        return [["seed spread of the answer",
                 "not measured: `magtact reproduce` refits the models with 8 GP seeds and "
                 "adds it here", *[""] * pad]]
    rows = []
    for label, unit, chosen, original in SPREAD:
        f = _spread(figs.get(chosen))
        if f is None:
            continue
        cells = [_range(f, unit)]
        if pad:
            o = _spread(figs.get(original)) if original else None
            cells.append(_range(o, unit) if o is not None else "(fixed)")
        rows.append([f"{label} over {f[0]:.0f} GP seeds (min – max)", *cells,
                     *[""] * max(pad - 1, 0)])
    return rows


def _spread(f) -> tuple[float, float, float] | None:
    """(n, min, max) of one seed-spread figure, or None where it is not three numbers, n > 0."""
    from .._files import json_dict, json_number

    f = json_dict(f)
    n, lo, hi = (json_number(f.get(k)) for k in ("n", "min", "max"))
    return None if None in (n, lo, hi) or not n > 0 else (n, lo, hi)


def _range(f: tuple[float, float, float], unit: str) -> str:
    return f"{f[1]:.3g} – {f[2]:.3g} {unit}"


def infeasible_card(answer, study=None) -> dict:
    """The card of a specification no design meets (:class:`magtact.designer.Infeasible`): the
    verdict (each requirement with the best figure reached), no parts, and rows saying what
    binds and what to relax; ``infeasible`` keeps the answer's JSON."""
    from .._display import infeasible_rows

    doc = answer.to_json()
    rows = [[k, v] for k, v in infeasible_rows(doc)[1][len(doc["verdict"]):]]
    card = {"verdict": doc["verdict"], "parts": [], "header": ["", "best reachable"],
            "rows": rows, "infeasible": doc}
    if study is not None:
        card |= {"study": study.name, "definition": study.sensitivity.definition}
    return card


def write_infeasible_card(answer, folder, study=None) -> Path:
    """Write :func:`infeasible_card` as ``card.json`` into ``folder``."""
    return write_json(Path(folder) / "card.json", infeasible_card(answer, study), indent=1,
                      ensure_ascii=False)
