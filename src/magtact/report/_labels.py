"""Words and units for the keys of magtact's files, as the report shows them.

Files keep machine keys with the unit in the name (``Gamma_r_max_N_per_T``, ``G_kPa``); a
reader of the report sees ``Γ_r,max [N/T]`` and ``G [kPa]``. The rule is mechanical, so a key
the table below does not name is still shown in words: a unit suffix becomes ``[unit]``, Greek
names their letter, and the underscores after a symbol's subscript become commas
(``F_r_min`` → ``F_r,min``); keys that are words (``active_constraints``) read as words.
"""

from __future__ import annotations

from .._display import COEFFICIENT_DIGITS, DIGITS, round_text, sig, significant_digits

__all__ = ["COEFFICIENT_DIGITS", "DIGITS", "label", "name", "round_text", "sig",
           "significant_digits", "split_unit", "value_text"]

#: Unit suffixes of keys (longest first) and how they read.
UNITS: tuple[tuple[str, str], ...] = (
    ("_mN_per_uT", "mN/µT"), ("_N_per_T", "N/T"), ("_A_per_m", "A/m"),
    ("_MA_per_m", "MA/m"), ("_percent", "%"), ("_kPa", "kPa"), ("_MPa", "MPa"), ("_mm", "mm"),
    ("_mN", "mN"), ("_uT", "µT"), ("_mT", "mT"), ("_rad", "rad"), ("_deg", "°"), ("_Hz", "Hz"),
    ("_pct_per_K", "%/K"), ("_pct", "%"),
    ("_N", "N"), ("_s", "s"), ("_Pa", "Pa"), ("_K", "K"),
)
#: Names whose reading is not mechanical.
NAMES = {
    "G_star": "G*", "M_z_star": "M_z*", "g_r": "margin g_r", "g_z": "margin g_z",
    "t_m": "t_m (stable shear bound)", "theta_m": "θ_m (stable shear bound)",
    "n_t": "levels of t", "n_theta": "levels of θ", "n_H": "levels of H", "n_G": "levels of G",
    "R_m": "magnet radius R_m", "H_m": "magnet height H_m", "R": "body radius R",
}
GREEK = {"Gamma": "Γ", "gamma": "γ", "theta": "θ", "sigma": "σ", "mu": "μ", "delta": "δ",
         "eps": "ε", "alpha": "α"}
#: Subscript words kept as such after a symbol (F_r_min → F_r,min).
SUBSCRIPTS = {"min", "max", "c", "r", "z", "x", "y", "0", "rest", "sat", "m", "g", "f"}


def split_unit(key: str) -> tuple[str, str | None]:
    """(name, unit) of a key: ``"Gamma_r_max_N_per_T"`` → (``"Gamma_r_max"``, ``"N/T"``)."""
    for suffix, unit in UNITS:
        if key.endswith(suffix) and len(key) > len(suffix):
            return key[: -len(suffix)], unit
    return key, None


def name(key: str) -> str:
    """A key's name in words or symbols, without its unit."""
    if key in NAMES:
        return NAMES[key]
    parts = key.split("_")
    parts = [GREEK.get(p, p) for p in parts]
    head = parts[0]
    symbol = len(head) <= 2 or head in GREEK.values()
    k = 1
    while symbol and k < len(parts) and (parts[k] in SUBSCRIPTS or parts[k].isdigit()):
        k += 1
    if k > 1:  # a symbol with its subscripts, then words: u_z_range → u_z range
        return " ".join([head + "_" + ",".join(parts[1:k]), *parts[k:]])
    return " ".join(parts)


def label(key: str) -> str:
    """A file key as a reader sees it: name and ``[unit]`` (each part of a dotted key with its
    own unit: ``timings_s.total`` → ``timings [s] · total``)."""
    out = []
    for part in str(key).split("."):
        base, unit = split_unit(part)
        out.append(f"{name(base)} [{unit}]" if unit else name(base))
    return " · ".join(out)


def value_text(v) -> str:
    """A value as a reader sees it: ``None`` as a dash, floats to :data:`DIGITS` significant
    figures, booleans as yes/no."""
    if v is None:
        return "—"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return sig(v)
    return str(v)
