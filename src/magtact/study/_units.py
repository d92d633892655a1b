"""Units at the user boundary.

magtact computes in SI (m, N, Pa, T, rad). Study files, CLI flags, tables and plot axes use
millimetres and kilopascals. Every conversion between the two goes through this module.
"""

from __future__ import annotations

import math

from .._errors import MagtactError

#: Value in SI = value in the user unit × num / den (kept as two integers so that a value such
#: as 2.97 mm becomes exactly the float nearest to 0.00297 m).
SCALE: dict[str, tuple[int, int]] = {
    "m": (1, 1),
    "mm": (1, 1000),
    "um": (1, 1_000_000),
    "kPa": (1000, 1),
    "Pa": (1, 1),
    "mT": (1, 1000),
    "uT": (1, 1_000_000),
    "N": (1, 1),
    "mN": (1, 1000),
    "per_mm": (1000, 1),
    "N_per_kPa": (1, 1000),
    "T": (1, 1),
    "rad": (1, 1),
    "A_per_m": (1, 1),
    "MA_per_m": (1_000_000, 1),
    "s": (1, 1),
    "K": (1, 1),
    "pct": (1, 100),
    "pct_per_K": (1, 100),
    "Hz": (1, 1),
    "": (1, 1),
}

#: Physical range in SI (inclusive) of a study value given in each user unit: lengths of a
#: sensor between 1 µm and 1 m, moduli between 1 Pa and 1 GPa, magnetisations between 1 A/m and
#: 10 MA/m (the strongest permanent magnets are near 1.1 MA/m), forces within ±1 MN, angles
#: between 0 and π/2. A setting may narrow its own range (``bounds`` in
#: :func:`magtact.study._model.setting`).
PHYSICAL: dict[str, tuple[float, float]] = {
    "mm": (1e-6, 1.0),
    "kPa": (1.0, 1e9),
    "A_per_m": (1.0, 1e7),
    "N": (-1e6, 1e6),
    "rad": (0.0, 1.5707963267948966),
}

#: Printable form of each unit suffix.
LABEL: dict[str, str] = {"A_per_m": "A/m", "MA_per_m": "MA/m", "um": "µm", "uT": "µT",
                         "per_mm": "1/mm", "N_per_kPa": "N/kPa", "pct": "%", "pct_per_K": "%/K",
                         "": "-"}

#: Permeability of free space used throughout [T·m/A] (docs/method.md §1).
MU0 = 1.257e-6


#: Angle unit whose factor is not a ratio of integers.
DEG = math.pi / 180.0


def to_si(value, unit: str):
    """Convert ``value`` given in the user unit ``unit`` (e.g. ``"mm"``) to SI."""
    if unit == "deg":
        return _scaled_float(value, DEG)
    num, den = SCALE[unit]
    return _scaled(value, num, den)


def from_si(value, unit: str):
    """Convert an SI ``value`` to the user unit ``unit`` (e.g. metres to ``"mm"``)."""
    if unit == "deg":
        return _scaled_float(value, 1.0 / DEG)
    num, den = SCALE[unit]
    return _scaled(value, den, num)


def _scaled_float(value, factor: float):
    if isinstance(value, (list, tuple)):
        return type(value)(v * factor for v in value)
    return value * factor


def _scaled(value, num: int, den: int):
    if isinstance(value, (list, tuple)):
        return type(value)(_scaled(v, num, den) for v in value)
    if num == den:
        return value
    return value * num / den if num > 1 else value / den


def mm(value):
    """Metres → millimetres (for tables and plot axes)."""
    return from_si(value, "mm")


def kpa(value):
    """Pascal → kilopascal (for tables and plot axes)."""
    return from_si(value, "kPa")


def mt(value):
    """Tesla → millitesla (for tables and plot axes)."""
    return from_si(value, "mT")


#: SI unit of each user unit, for messages.
SI_LABEL: dict[str, str] = {"mm": "m", "um": "m", "kPa": "Pa", "mT": "T", "uT": "T", "mN": "N",
                            "A_per_m": "A/m", "MA_per_m": "A/m", "deg": "rad", "per_mm": "1/m",
                            "pct": "-", "pct_per_K": "1/K"}


def bounds_text(unit: str, lo: float, hi: float) -> str:
    """``"between 0.001 and 1000 mm (1e-06 to 1 m in SI)"`` for SI bounds of a user unit."""
    text = f"between {from_si(lo, unit):g} and {from_si(hi, unit):g}"
    label, si_label = LABEL.get(unit, unit), SI_LABEL.get(unit, unit)
    if unit:
        text += f" {label}"
    if unit and si_label != label:
        text += f" ({lo:g} to {hi:g} {si_label} in SI)"
    return text


def check_si(si: float, unit: str, what: str, shown, bounds=None) -> float:
    """Return the SI value ``si`` if it is finite and within ``bounds`` (default: the physical
    range :data:`PHYSICAL` of ``unit``); else raise a MagtactError naming ``what`` (e.g. ``"--H"``
    or ``"data.csv: metadata 'design_h_mm'"``), the bounds and the value as given (``shown``)."""
    lo, hi = PHYSICAL[unit] if bounds is None else bounds
    if not (math.isfinite(si) and lo <= si <= hi):
        raise MagtactError(f"{what} must be {bounds_text(unit, lo, hi)}, got {shown!r}")
    return si


def checked_si(value: float, unit: str, what: str, bounds=None) -> float:
    """``value`` in the user unit ``unit`` → SI, checked by :func:`check_si` (and, with the
    default bounds, by :func:`unit_mistake`). ``value`` must be a number (int, float or a NumPy
    number); text such as ``"3"`` and booleans are refused, not read."""
    import numbers

    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise MagtactError(f"{what} must be a number, got {value!r}")
    try:
        si = to_si(float(value), unit)
    except (OverflowError, TypeError, ValueError):
        raise MagtactError(f"{what} must be a number, got {value!r}") from None
    hint = unit_mistake(unit, value, si) if bounds is None else None
    try:
        check_si(si, unit, what, value, bounds)
    except MagtactError as exc:
        raise MagtactError(f"{exc}" + ("" if hint is None else f": {hint}")) from None
    if hint is not None:
        raise MagtactError(f"{what} = {value!r}: {hint}")
    return si


#: What a value of a user unit plausibly is in a soft magnetic tactile sensor, in SI: its
#: quantity (for messages) and range. A value outside it that becomes plausible in a
#: neighbouring unit (:data:`NEIGHBOURS`) is a unit mistake. Wider than any design, narrower
#: than :data:`PHYSICAL`:
#:
#: * ``kPa``: an elastomer's shear modulus, 100 Pa to 5 MPa (the castable silicones of
#:   ``parts/data/silicones.toml`` span about 18 kPa, Ecoflex 00-10, to 1.3 MPa, Sylgard 184
#:   at 5:1; a tenth of the softest and four times the stiffest);
#: * ``mm``: a dimension of the body or the magnet, 0.1 mm to 100 mm;
#: * ``A_per_m``: a permanent magnet's magnetisation, 10 kA/m to 1.5 MA/m (the strongest
#:   sintered NdFeB of ``parts/data/magnets.toml``, N52, has B_r ≤ 1.46 T, M = B_r/μ0 ≤ 1.16
#:   MA/m);
#: * ``N``: a force on a body of centimetres, 0.1 mN to 1 kN in magnitude (1 kN on 1 cm² is
#:   10 MPa, beyond any silicone).
PLAUSIBLE: dict[str, tuple[str, float, float]] = {
    "kPa": ("an elastomer's shear modulus", 100.0, 5e6),
    "mm": ("a dimension of a soft tactile sensor", 1e-4, 0.1),
    "A_per_m": ("a permanent magnet's magnetisation", 1e4, 1.5e6),
    "N": ("a force on a soft tactile sensor", 1e-4, 1e3),
}

#: The study keys (section.setting) whose values are checked against :data:`PLAUSIBLE` of their
#: unit: the sensor's main dimensions, moduli, magnetisations and forces (not tolerances, edge
#: radii or mesh sizes, which are rightly far smaller than the sensor).
PLAUSIBLE_KEYS: frozenset[str] = frozenset({
    "body.R", "body.H_g", "body.R_g", "magnet.R_m", "magnet.H_m", "loading.dz_sat",
    "design.H", "design.H_original", "design.R_m", "design.H_m", "design.R", "array.pitch",
    "requirements.R_max",
    "material.G_ref", "design.G", "design.G_original",
    "magnet.M_z", "design.M_z",
    "constraints.F_r_c", "constraints.F_z_c", "requirements.F_z", "requirements.F_r",
})

#: The units a value of a user unit is most often mistaken for: (what the user may have
#: given, the factor from that unit to the key's unit).
NEIGHBOURS: dict[str, tuple[tuple[str, float], ...]] = {
    "kPa": (("pascals", 1e-3), ("MPa", 1e3)),
    "mm": (("metres", 1e3), ("micrometres", 1e-3)),
    "A_per_m": (("kA/m", 1e3), ("the remanence B_r in tesla (M = B_r / μ0)", 1 / MU0),
                ("the remanence B_r in mT (M = B_r / μ0)", 1e-3 / MU0)),
    "N": (("mN", 1e-3),),
}


def _plain(si: float, unit: str) -> str:
    """An SI value in the readable multiple of its quantity (``10 MPa``, ``2.5 µm``)."""
    steps = {"kPa": ((1e9, "GPa"), (1e6, "MPa"), (1e3, "kPa"), (1.0, "Pa")),
             "mm": ((1.0, "m"), (1e-3, "mm"), (1e-6, "µm"), (1e-9, "nm")),
             "A_per_m": ((1e6, "MA/m"), (1e3, "kA/m"), (1.0, "A/m")),
             "N": ((1e3, "kN"), (1.0, "N"), (1e-3, "mN"), (1e-6, "µN"))}[unit]
    a = abs(si)
    for factor, label in steps:
        if a >= factor:
            return f"{si / factor:.3g} {label}"
    factor, label = steps[-1]
    return f"{si / factor:.3g} {label}"


def unit_mistake(unit: str, value, si) -> str | None:
    """Why ``value`` (as written, in ``unit``; a number or a [low, high] pair, with ``si`` the
    same in SI) looks like a unit mistake, or None.

    A value is a mistake when it lies outside the plausible range :data:`PLAUSIBLE` of its unit
    and every number of it lies inside that range once read in one neighbouring unit
    (:data:`NEIGHBOURS`); zero is never a mistake (it means "not set" where a key allows it).
    The sentence names the quantity, the value in a readable unit and the likely unit, e.g.
    ``"10 MPa–50 MPa is not an elastomer's shear modulus (plausible: 100 Pa to 5 MPa); did you
    give pascals?"``.
    """
    if unit not in PLAUSIBLE:
        return None
    what, lo, hi = PLAUSIBLE[unit]
    values = [float(v) for v in (value if isinstance(value, list | tuple) else [value])]
    sis = [float(v) for v in (si if isinstance(si, list | tuple) else [si])]
    if all(v == 0 or lo <= abs(x) <= hi for v, x in zip(values, sis, strict=True)):
        return None
    likely = [name for name, factor in NEIGHBOURS[unit]
              if all(v == 0 or lo <= abs(to_si(v * factor, unit)) <= hi for v in values)]
    if not likely:
        return None
    shown = "–".join(_plain(x, unit) for x in sis)
    return (f"{shown} is not {what} (plausible: {_plain(lo, unit)} to {_plain(hi, unit)}); "
            f"did you give {' or '.join(likely)}?")
