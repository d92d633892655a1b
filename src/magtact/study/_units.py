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
    """``value`` in the user unit ``unit`` → SI, checked by :func:`check_si`."""
    try:
        si = to_si(float(value), unit)
    except (OverflowError, TypeError, ValueError):
        raise MagtactError(f"{what} must be a number, got {value!r}") from None
    return check_si(si, unit, what, value, bounds)
