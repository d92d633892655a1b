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
