"""Units at the user boundary.

magtact computes in SI (m, N, Pa, T, rad). Study files, CLI flags, tables and plot axes use
millimetres and kilopascals. Every conversion between the two goes through this module.
"""

from __future__ import annotations

import numpy as np

#: Factor that turns a value in the named user unit into SI.
TO_SI: dict[str, float] = {
    "mm": 1e-3,
    "kPa": 1e3,
    "N": 1.0,
    "T": 1.0,
    "mT": 1e-3,
    "rad": 1.0,
    "A_per_m": 1.0,
    "s": 1.0,
    "": 1.0,
}

#: Printable form of each unit suffix.
LABEL: dict[str, str] = {"A_per_m": "A/m", "": "-"}

#: Permeability of free space used throughout [T·m/A] (SPEC section 1).
MU0 = 1.257e-6


def to_si(value, unit: str):
    """Convert ``value`` given in the user unit ``unit`` (e.g. ``"mm"``) to SI."""
    return _scaled(value, TO_SI[unit])


def from_si(value, unit: str):
    """Convert an SI ``value`` to the user unit ``unit`` (e.g. metres to ``"mm"``)."""
    return _scaled(value, 1.0 / TO_SI[unit])


def _scaled(value, factor: float):
    if isinstance(value, (list, tuple)):
        return type(value)(v * factor for v in value)
    if isinstance(value, np.ndarray):
        return value * factor
    return value * factor


def mm(value):
    """Metres → millimetres (for tables and plot axes)."""
    return from_si(value, "mm")


def kpa(value):
    """Pascal → kilopascal (for tables and plot axes)."""
    return from_si(value, "kPa")
