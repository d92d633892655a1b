"""Numbers read from text the user gave: the usual decimal grammar, nothing Python-only.

``float()`` also accepts digit-group underscores (``1_0.0`` is 10.0), non-ASCII digits
(``'٣'`` is 3.0) and surrounding Unicode white space; a CSV cell or a command-line option
meaning something else must not be read as such a number. :func:`parse_float` and
:func:`parse_int` accept exactly

    float:  [+-]? (digits [. digits?] | . digits) ([eE] [+-]? digits)?   or  [+-]? (nan | inf |
            infinity)  (ASCII, any case)
    int:    [+-]? digits

with ASCII digits and spaces or tabs around; whether a value may be infinite or NaN is for the
caller to check (with a message naming the setting).
"""

from __future__ import annotations

import re

_FLOAT = re.compile(r"[+-]?(?:(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
                    r"|nan|inf|infinity)", re.IGNORECASE)
_INT = re.compile(r"[+-]?[0-9]+")
#: Longest number text read (digits beyond a double's precision carry nothing; Python refuses
#: integers of more than 4300 digits with a message about its own settings).
MAX_CHARS = 400


def parse_float(text: str) -> float:
    """``text`` as a float under the grammar of the module docstring.

    Raises
    ------
    ValueError
        If ``text`` is not such a number (the message quotes it, clipped).
    """
    s = text.strip(" \t")
    if len(s) > MAX_CHARS or not _FLOAT.fullmatch(s):
        raise ValueError(f"not a number: {_clip(text)}")
    return float(s)


def parse_int(text: str) -> int:
    """``text`` as an integer (ASCII digits, optional sign).

    Raises
    ------
    ValueError
        If ``text`` is not such an integer.
    """
    s = text.strip(" \t")
    if len(s) > MAX_CHARS or not _INT.fullmatch(s):
        raise ValueError(f"not an integer: {_clip(text)}")
    return int(s)


def _clip(text: str, n: int = 40) -> str:
    return repr(text) if len(text) <= n else repr(text[:n]) + f"... ({len(text)} characters)"
