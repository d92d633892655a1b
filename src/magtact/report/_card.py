"""The design card: the designer's answer for the chosen and the original design in user units
and plain words (no internal keys; the JSON keeps every number)."""

from __future__ import annotations

import json
from pathlib import Path

from .._files import write_json
from ..study import from_si, kpa, mm


def _mN(v: float) -> str:
    return f"{from_si(v, 'mN'):.3g} mN"


def card_rows(answers, constraints=None, spread: dict | None = None, rtol: float = 1e-2
              ) -> tuple[list[str], list[list[str]]]:
    """Header and rows of the design card for a sequence of :class:`DesignAnswer`.

    ``constraints`` (a ``ForceConstraints``) adds which constraints are active at each design;
    ``spread`` (figure → text) adds the seed spread of the answer, where a seed study ran;
    a constraint is active where its margin is within ``rtol`` of its limit.
    """
    header = ["", *(a.label for a in answers)]
    chip = answers[0].chip
    rows: list[list[str]] = []

    def row(name, fn):
        rows.append([name, *(fn(a) for a in answers)])

    row("height H", lambda a: f"{mm(a.H):.3g} mm")
    row("shear modulus G", lambda a: f"{kpa(a.G):.3g} kPa")
    if chip.noise is None:
        keys = " and ".join(chip.missing)
        row(f"resolution with the {chip.name}",
            lambda a: f"give {keys} (RMS field noise at your chip setting, > 0)")
    else:
        note = f"{chip.name}, noise {from_si(chip.noise_x, 'uT'):.3g} / " \
               f"{from_si(chip.noise_z, 'uT'):.3g} µT RMS (x / z)"
        row(f"shear resolution σ_Fr, unloaded / worst ({note})",
            lambda a: f"{_mN(a.resolution.sigma_r_0)} / {_mN(a.resolution.sigma_r_worst)}")
        row("normal resolution σ_Fz, unloaded / worst",
            lambda a: f"{_mN(a.resolution.sigma_z_0)} / {_mN(a.resolution.sigma_z_worst)}")
    row("normal force range (largest F_z in the stable region)",
        lambda a: f"{a.design.F_z_max:.3g} N")
    row("shear force range (F_r before shear turns unstable)",
        lambda a: f"{a.design.F_r_min:.3g} N")
    row(f"chip range ({from_si(chip.range_x, 'mT'):.3g} / {from_si(chip.range_z, 'mT'):.3g} mT)",
        _saturation_text)
    if constraints is not None:
        row("active constraints", lambda a: _active(a, constraints, rtol))
    if answers[0].tolerance > 0:
        d = answers[0].tolerance
        row(f"tolerance of G ± {d:.0%}",
            lambda a: f"forces at G − {d:.0%}: {(1 - d) * a.design.F_z_max:.3g} N normal, "
                      f"{(1 - d) * a.design.F_r_min:.3g} N shear; Γ and σ_F × {1 + d:.3g} "
                      f"at G + {d:.0%}")
    for name, text in (spread or {}).items():
        rows.append([name, text, ""][: len(header)])
    return header, rows


def _saturation_text(a) -> str:
    s = a.saturation
    if not s.saturates:
        return (f"not reached (largest |B| {from_si(s.B_max_x, 'mT'):.3g} / "
                f"{from_si(s.B_max_z, 'mT'):.3g} mT)")
    return (f"saturates ({'shear' if s.axis == 'x' else 'normal'} axis) at t = {s.t:.2f}, "
            f"F_z = {s.F_z:.3g} N")


def _active(a, constraints, rtol: float) -> str:
    names = {"F_r": "shear", "F_z": "normal force"}
    active = constraints.active(a.design.F_r_min, a.design.F_z_max, rtol)
    return ", ".join(names[k] for k in active) or "none"


def write_card(answers, folder, constraints=None, rtol: float = 1e-2) -> Path:
    """Write ``card.json`` (the card's rows and every number of each answer) into ``folder``."""
    from ..designer import answer_json

    header, rows = card_rows(answers, constraints, rtol=rtol)
    return write_json(Path(folder) / "card.json",
                      {"header": header, "rows": rows,
                       "answers": [answer_json(a) for a in answers]}, indent=1,
                      ensure_ascii=False)


def read_card(folder) -> dict | None:
    """The card written by :func:`write_card`, or None."""
    path = Path(folder) / "card.json"
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
