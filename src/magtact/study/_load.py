"""Loading, validating and writing study files (TOML, user units)."""

from __future__ import annotations

import difflib
import functools
import itertools
import math
import tomllib
from dataclasses import fields, replace
from importlib import resources
from pathlib import Path

from .._files import UnreadableFile, file_problem, read_text_capped
from ._errors import StudyError
from ._model import GEOMETRY, SECTIONS, Study, key_of
from ._rules import blamed, check_parts, check_physical, check_unit, unit_hint, written_keys
from ._units import LABEL, bounds_text, from_si, to_si

#: The built-in studies by name (``magtact.load(name)``, ``base = name``), each a study file.
PRESETS = {"magone": "magone.toml", "magone-publication": "magone_publication.toml",
           "magone-printed": "magone_printed.toml"}


def magone() -> Study:
    """The built-in MagOne study (G read as 10–50 kPa, original 29.4 kPa; docs/method.md §9)."""
    return load_study("magone")


def magone_printed() -> Study:
    """The MagOne study with G as printed in the publication (1–5 kPa, original 2.94 kPa)."""
    return load_study("magone-printed")


def load_study(source: str | Path | None = None) -> Study:
    """Load and validate a study.

    ``source`` is a TOML file path, a preset name (``"magone"``, ``"magone-printed"``) or
    ``None`` for the built-in MagOne study. A file may say ``base = "magone"`` (the default),
    another preset, another study file (``base = "mine.toml"``, relative to the file) or
    ``"none"``: keys it does not give are taken from that base, and with ``"none"`` every key
    must be given. Raises :class:`StudyError` naming the offending key.
    """
    if source is None:
        source = "magone"
    if isinstance(source, str) and source in PRESETS:
        return _preset(source)
    path = Path(source)
    return _study_of_text(_read_text(path), str(path))


@functools.cache
def _preset(name: str) -> Study:
    """A preset study: read once per process (a frozen value of the package's own file)."""
    text = resources.files("magtact.study").joinpath(PRESETS[name]).read_text("utf-8")
    return _study_of_text(text, f"preset '{name}'")


def _study_of_text(text: str, label: str) -> Study:
    """The study of a study file's ``text`` (``label`` names it in errors)."""
    try:
        data = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, ValueError) as exc:
        raise StudyError("file", f"is not valid TOML: {_clip(str(exc), 200)}", label) from None
    except (RecursionError, MemoryError):
        raise StudyError("file", "is not a study: its arrays or tables nest too deeply",
                         label) from None
    return study_from_dict(data, label)


#: Largest study file read [bytes] (the built-in study is about 3 kB).
MAX_FILE_BYTES = 1_000_000


def _read_text(path: Path) -> str:
    """The text of a study file (UTF-8, with or without a byte-order mark), or a StudyError."""
    problem = file_problem(path)
    if problem == "not found":
        raise StudyError("file", f"study file not found: {path}, and no preset has that name "
                                 f"(presets: {', '.join(PRESETS)})")
    if problem is not None:
        raise StudyError("file", f"is not a file: it is {problem} (a study is one TOML file)",
                         str(path))
    try:
        return read_text_capped(path, MAX_FILE_BYTES)
    except UnreadableFile as exc:
        raise StudyError("file", str(exc), str(path)) from None


def _clip(text: str, n: int = 60) -> str:
    return text if len(text) <= n else text[:n] + f"... ({len(text)} characters)"


def _show(value) -> str:
    """A value for a message: its repr, shortened (huge integers and strings included)."""
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 200:
        return f"an integer of about {int(value.bit_length() * math.log10(2)) + 1} digits"
    return _clip(repr(value))


def study_from_dict(data: dict, source: str | None = None) -> Study:
    """Build a validated :class:`Study` from a TOML-shaped dict in user units."""
    if not isinstance(data, dict):
        raise StudyError("file", f"expected a table of sections, got {_show(data)}", source)
    data = dict(data)
    base_name = data.pop("base", "magone")
    if base_name == "none":
        base, complete = Study(), True
    elif isinstance(base_name, str) and base_name in PRESETS:
        base, complete = load_study(base_name), False
    elif isinstance(base_name, str) and base_name.lower().endswith(".toml"):
        base, complete = _base_file(base_name, source), False
    else:
        raise StudyError("base", f"expected one of {sorted(PRESETS) + ['none']} or a study "
                                 f"file (.toml), got {_show(base_name)}", source)
    top = {}
    for key in ("name", "description"):
        if key in data:
            value = data.pop(key)
            if not isinstance(value, str):
                raise StudyError(key, f"expected a string, got {_show(value)}", source)
            top[key] = value
    if complete and "name" not in top:
        raise StudyError("name", "is missing (required when base = 'none')", source)
    for key in data:
        if key not in SECTIONS:
            raise StudyError(_clip(str(key)), _unknown(str(key), SECTIONS, "section"), source)
        if not isinstance(data[key], dict):
            raise StudyError(key, f"expected a table [{key}], got {_show(data[key])}", source)
    sections = {}
    for name in SECTIONS:
        sections[name] = _section(name, getattr(base, name), data.get(name, {}), complete, source)
    study = _apply_parts(replace(base, **top, **sections), data.get("magnet", {}), source)
    study = _apply_requirements(study, base, source)
    if not complete:  # a complete file writes every key: its silicone is no choice made
        study = _apply_silicone(study, data, source)
        study = _apply_magnet_size(study, data)
    _check_standoff(study, source)
    try:
        _check_consistency(study, source)
        _check_silicones(study, source)
        check_physical(study, source)
    except StudyError as exc:  # the key the user wrote, where the rule names a base value
        raise blamed(exc, written_keys(data), source) from None
    _check_hall(study, source)
    return study


#: Study files being read as bases (a file that is its own base, directly or not, is refused).
_READING: list[Path] = []


def _base_file(name: str, source: str | None) -> Study:
    """The study a file names as its base (``base = "mine.toml"``): a path relative to the
    file that names it (to the current folder where the study is not a file)."""
    path = Path(name)
    if not path.is_absolute() and source and Path(source).suffix.lower() == ".toml":
        path = Path(source).parent / path
    key = path.resolve()
    if key in _READING:
        chain = " -> ".join(str(p) for p in [*_READING, key])
        raise StudyError("base", f"the study files name each other as base ({chain})", source)
    _READING.append(key)
    try:
        return load_study(path)
    finally:
        _READING.pop()


def _apply_parts(s: Study, given: dict, source) -> Study:
    """The magnet's grade sets M_z = B_r / μ0 (nominal B_r), its size R_m and H_m; a value the
    file also gives must agree (docs/method.md §10; :func:`magtact.study._rules.check_parts`)."""
    mg = s.magnet
    keys = {f.name: f"magnet.{key_of(f)}" for f in fields(mg)}
    own = {name: getattr(mg, name) for name in ("M_z", "R_m", "H_m")
           if keys[name].split(".", 1)[1] in given}
    values = check_parts(mg.grade, mg.size, own, keys, source)
    return replace(s, magnet=replace(mg, **values)) if values else s


def _apply_requirements(s: Study, base: Study, source) -> Study:
    """With ``[constraints] source = "requirements"`` the force constraints are the required
    forces (F_r,c = −F_r, F_z,c = F_z); a constraint value changed from its base's is refused,
    since it would not take effect."""
    c, r = s.constraints, s.requirements
    if c.source != "requirements":
        return s
    for name, derived, own in (("F_r_c", -r.F_r, "F_r_N"), ("F_z_c", r.F_z, "F_z_N")):
        value = getattr(c, name)
        if value != getattr(base.constraints, name) and value != derived:
            raise StudyError(f"constraints.{name}_N",
                             f"{value:g} N would not take effect: with constraints.source = "
                             f"'requirements' the force is requirements.{own} ({abs(derived):g} "
                             "N); change that, or set constraints.source = 'values'", source)
    return replace(s, constraints=replace(c, F_r_c=-r.F_r, F_z_c=r.F_z))


def _apply_silicone(s: Study, given: dict, source) -> Study:
    """A study that names the silicone its body is cast from (``[material] silicone``) and
    not the silicones to choose from (``[design] silicones``) chooses that silicone alone (no
    silicone, ``"none"``: G free over the design range)."""
    material, design = given.get("material", {}), given.get("design", {})
    if "silicone" not in material or "silicones" in design:
        return s
    name = s.material.silicone
    return replace(s, design=replace(s.design, silicones=() if name == "none" else (name,)))


def _apply_magnet_size(s: Study, given: dict) -> Study:
    """A study that sets its magnet's size (``[magnet] size``, ``R_m_mm`` or ``H_m_mm``) and
    not the sizes to choose from (``[design] magnet_sizes``) keeps that magnet."""
    magnet, design = given.get("magnet", {}), given.get("design", {})
    if "magnet_sizes" in design or not {"size", "R_m_mm", "H_m_mm"} & set(magnet):
        return s
    return replace(s, design=replace(s.design, magnet_sizes=()))


def _check_silicones(s: Study, source) -> None:
    """In the sensor problem, some silicone to choose from must reach a G of the design
    range."""
    from ..parts import SILICONES

    d = s.design
    if s.optimise.problem != "sensor" or not d.silicones:
        return
    ranges = {n: SILICONES[n].G_range for n in d.silicones}
    if not any(lo <= d.G[1] and hi >= d.G[0] for lo, hi in ranges.values()):
        shown = "; ".join(f"{n} {lo / 1e3:.4g}–{hi / 1e3:.4g} kPa" if hi > lo
                          else f"{n} {lo / 1e3:.4g} kPa" for n, (lo, hi) in ranges.items())
        raise StudyError("design.silicones",
                         f"no silicone to choose from reaches a G in the design range "
                         f"{d.G[0] / 1e3:g}–{d.G[1] / 1e3:g} kPa (design.G_kPa): {shown}; "
                         "widen design.G_kPa, name other silicones, or give [] for G free "
                         "over the design range", source)


def _check_standoff(s: Study, source) -> None:
    """A chip below the body in the publication's problem needs the exact field: fitted field
    models hold at the chip's place in the DOE (the body's base)."""
    if (s.hall.standoff > 0 and s.optimise.problem == "publication"
            and s.metamodel.b_model == "fit"):
        raise StudyError("hall.standoff_mm", "a chip below the body needs the exact field in "
                                             "the publication's problem: set metamodel.b_model "
                                             "= 'exact' (the sensor problem uses it always)",
                         source)


def _check_hall(s: Study, source) -> None:
    """The ``[hall]`` chip setting and sample rate against the chip's tables."""
    from ._hall import check_hall

    try:
        check_hall(s)
    except StudyError as exc:
        raise StudyError(exc.key, exc.reason, source) from None


def _unknown(key: str, allowed, what: str) -> str:
    close = difflib.get_close_matches(key, list(allowed), n=1)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    return f"unknown {what}{hint} (expected one of: {', '.join(allowed)})"


def _section(name: str, default, given: dict, complete: bool, source):
    spec = {key_of(f): f for f in fields(default)}
    for key in given:
        if key not in spec:
            raise StudyError(f"{name}.{_clip(str(key))}", _unknown(str(key), spec, "key"),
                             source)
    values = {}
    for key, f in spec.items():
        full = f"{name}.{key}"
        if key not in given:
            if complete and f.metadata.get("missing") is not None:
                values[f.name] = f.metadata["missing"]  # a file written before the key
            elif complete:
                raise StudyError(full, f"is missing; expected {_expected(f)}", source)
            continue
        values[f.name] = _convert(full, f, given[key], source)
    return replace(default, **values)


def _expected(f) -> str:
    m = f.metadata
    unit = LABEL.get(m["unit"], m["unit"])
    if m["choices"]:
        return ("a list of " if isinstance(f.default, tuple) else "one of ") + ", ".join(
            repr(c) for c in m["choices"])
    if isinstance(f.default, bool):
        return "true or false"
    if isinstance(f.default, tuple):
        return f"a range [low, high] in {unit}"
    if m["integer"]:
        return "an integer"
    return f"a number in {unit}" if m["unit"] else "a number"


def _convert(full: str, f, value, source):
    m = f.metadata
    if m["choices"] and isinstance(f.default, tuple):  # a list of names
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise StudyError(full, f"expected a list of names from {', '.join(m['choices'])}, "
                                   f"got {_show(value)}", source)
        for v in value:
            if v not in m["choices"]:
                raise StudyError(full, f"{_clip(v)!r}: " + _unknown(v, m["choices"], "name"),
                                 source)
        if len(set(value)) != len(value):
            raise StudyError(full, f"names a choice twice: {_show(value)}", source)
        return tuple(value)
    if m["choices"]:
        if not isinstance(value, str) or value not in m["choices"]:
            raise StudyError(full, f"expected {_expected(f)}, got {_show(value)}", source)
        return value
    if isinstance(f.default, bool):
        if not isinstance(value, bool):
            raise StudyError(full, f"expected true or false, got {_show(value)}", source)
        return value
    if isinstance(f.default, tuple):
        if not (isinstance(value, list) and len(value) == 2):
            raise StudyError(full, f"expected {_expected(f)}, got {_show(value)}", source)
        lo, hi = (_number(full, f, v, source) for v in value)
        if m["minimum"] == 0 and lo == hi == 0:  # [0, 0]: not a design variable
            return (0.0, 0.0)
        if not lo < hi:
            raise StudyError(full, f"range out of order: low {value[0]} must be below high "
                                   f"{value[1]}", source)
        pair = (_si(full, f, lo, source), _si(full, f, hi, source))
        check_unit(full, f"{full.split('.')[0]}.{f.name}", m["unit"], [lo, hi], pair, source)
        return pair
    value = _number(full, f, value, source)
    if m["integer"]:
        return value
    si = _si(full, f, value, source)
    check_unit(full, f"{full.split('.')[0]}.{f.name}", m["unit"], value, si, source)
    return si


def _number(full: str, f, value, source):
    """A number as written, checked for type, finiteness, sign and the written bounds."""
    m = f.metadata
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise StudyError(full, f"expected {_expected(f)}, got {_show(value)}", source)
    if m["integer"] and not isinstance(value, int):
        raise StudyError(full, f"expected an integer, got {_show(value)}", source)
    if not m["integer"]:
        try:
            value = float(value)
        except OverflowError:
            raise StudyError(full, f"{_show(value)} is outside the range of a double",
                             source) from None
        if not math.isfinite(value):
            raise StudyError(full, f"expected a finite number, got {value!r}", source)
    if m["positive"] and value <= 0:
        raise StudyError(full, f"must be positive, got {_show(value)}", source)
    if m["minimum"] is not None and value < m["minimum"]:
        raise StudyError(full, f"must be at least {m['minimum']}, got {_show(value)}", source)
    if m["maximum"] is not None and value > m["maximum"]:
        raise StudyError(full, f"must be at most {m['maximum']:,} (a bound on the work a study "
                               f"may ask for), got {_show(value)}", source)
    return value


def _si(full: str, f, value: float, source) -> float:
    """``value`` converted to SI and checked against the setting's physical bounds."""
    m = f.metadata
    unit = m["unit"]
    si = to_si(value, unit)
    bounds = m["bounds"]
    if bounds is None or (value == 0 and m["minimum"] == 0):
        return si
    lo, hi = bounds
    if not lo <= si <= hi:
        where = ("0 or " if m["minimum"] == 0 else "") + bounds_text(unit, lo, hi)
        hint = unit_hint(f"{full.split('.')[0]}.{f.name}", unit, value, si)
        raise StudyError(full, f"must be {where}, got {value!r}{hint}", source)
    return si


def _check_consistency(s: Study, source) -> None:
    """Checks that involve several keys; each names the key a user would change."""
    b, mg, ld = s.body, s.magnet, s.loading
    if not s.constraints.G_tolerance < 0.5:
        raise StudyError("constraints.G_tolerance", f"must be in [0, 0.5), got "
                                                    f"{s.constraints.G_tolerance:g}", source)
    if s.design.M_z[0] == 0 < s.design.M_z[1]:
        raise StudyError("design.M_z_A_per_m", "must be [0, 0] (fixed at magnet.M_z_A_per_m) "
                                               "or a positive range", source)
    for name, section in GEOMETRY.items():
        if getattr(s.design, name)[0] == 0 < getattr(s.design, name)[1]:
            raise StudyError(f"design.{name}_mm", f"must be [0, 0] (fixed at "
                                                  f"{section}.{name}_mm) or a positive range",
                             source)
    if s.geometric_variables:
        _check_geometry_corners(s, source)
    if mg.R_m >= b.R:
        raise StudyError("magnet.R_m_mm", f"the magnet ({_mm(mg.R_m)} mm radius) must be narrower "
                                          f"than the body (body.R_mm = {_mm(b.R)})", source)
    if b.R_g > b.R:
        raise StudyError("body.R_g_mm", f"must not exceed body.R_mm = {_mm(b.R)}", source)
    needed = 1.5 * mg.H_m if mg.placement == "covered" else mg.H_m
    if needed > b.H_g:
        raise StudyError("magnet.H_m_mm", f"the {mg.placement} magnet needs {_mm(needed)} mm of "
                                          f"the upper part but body.H_g_mm is {_mm(b.H_g)}", source)
    if b.R_h >= min(b.R - mg.R_m, b.H_g):
        raise StudyError("body.R_h_mm", f"edge radius {_mm(b.R_h)} mm must be smaller than the "
                                        "gap beside the magnet and the upper part's height", source)
    dz0_min = s.design.H[0] + b.H_g - mg.H_m
    if ld.dz_sat >= dz0_min:
        raise StudyError("loading.dz_sat_mm", f"the loading path cannot reach {_mm(ld.dz_sat)} mm: "
                                              f"it must be below the unloaded distance "
                                              f"{_mm(dz0_min)} mm at the smallest H", source)
    low_face = ld.dz_sat - (mg.H_m / 2 if mg.placement == "covered" else 0.0)
    if low_face <= 0:
        raise StudyError("loading.dz_sat_mm", "the magnet would reach the Hall sensor plane; "
                                              f"expected more than {_mm(ld.dz_sat - low_face)} mm",
                         source)
    if ld.theta_max > math.atan(ld.mu_f) + 1e-12:
        raise StudyError("loading.theta_max_rad", f"must not exceed atan(mu_f) = "
                                                  f"{math.atan(ld.mu_f):.6g} rad, got "
                                                  f"{ld.theta_max:.6g}", source)
    if s.mechanics.magnet_edge_radius >= min(mg.R_m, mg.H_m):
        raise StudyError("mechanics.magnet_edge_radius_mm",
                         f"the magnet's edge radius {_mm(s.mechanics.magnet_edge_radius)} mm must "
                         f"be smaller than its radius and height (min(R_m, H_m) = "
                         f"{_mm(min(mg.R_m, mg.H_m))} mm)", source)
    if 0 < s.array.pitch < 2 * b.R:
        raise StudyError("array.pitch_mm", f"a pitch of {_mm(s.array.pitch)} mm is smaller than "
                                           f"the body (diameter 2 body.R_mm = {_mm(2 * b.R)} "
                                           "mm): neighbouring bodies would overlap", source)
    _check_work(s, source)
    _check_order(s, source)
    for name in ("H_original", "G_original"):
        value, (lo, hi) = getattr(s.design, name), getattr(s.design, name[0])
        if not lo <= value <= hi:
            unit = "mm" if name[0] == "H" else "kPa"
            raise StudyError(f"design.{name}_{unit}", f"{from_si(value, unit):g} {unit} lies "
                                                      f"outside the design range", source)


def _check_geometry_corners(s: Study, source) -> None:
    """Every corner of the geometric design ranges (R_m, H_m, R; H over its whole range) must
    give a sensor the checks above accept; the message names the keys and the failing corner."""
    names = ["H", *s.geometric_variables]
    ranges = [s.design.H, *s.geometric_variables.values()]
    if s.metamodel.b_model != "exact" or s.sensitivity.definition != "jacobian":
        raise StudyError("design." + "_mm, design.".join(names[1:]) + "_mm",
                         "geometric design variables need the exact field (metamodel.b_model "
                         "= 'exact') and the Jacobian sensitivity (sensitivity.definition = "
                         "'jacobian'): a fitted field would have to learn the magnet's shape",
                         source)
    for name, (lo, hi) in s.geometric_variables.items():
        own = getattr(getattr(s, GEOMETRY[name]), name)
        if not lo <= own <= hi:
            raise StudyError(f"{GEOMETRY[name]}.{name}_mm", f"{_mm(own)} mm (the original "
                                                            f"design's) lies outside design."
                                                            f"{name}_mm = [{_mm(lo)}, {_mm(hi)}]",
                             source)
    for corner in itertools.product(*ranges[1:]):
        values = dict(zip(names[1:], corner, strict=True))
        try:
            _check_consistency(s.at(**values), None)
        except StudyError as exc:
            where = ", ".join(f"{k} = {_mm(v)} mm" for k, v in values.items())
            keys = ", ".join(f"design.{k}_mm" for k in names[1:])
            raise StudyError(keys, f"cannot be built at the corner {where} of the design "
                                   f"ranges: [{exc.key}] {exc.reason}", source) from None


#: Most structural paths (loading paths solved by FE) a study's DOE may ask for.
MAX_PATHS = 10_000
#: Most field points (t × θ × H levels) a study's DOE may ask for.
MAX_FIELD_POINTS = 2_000_000
#: Most force points (t × θ × H × G levels) of a study's DOE data set (80 MB per force array).
MAX_DATA_POINTS = 10_000_000
#: Finest FE element at the magnet surface, as a fraction of the magnet's smaller dimension.
MIN_H_MAGNET_RATIO = 1 / 200


def _check_work(s: Study, source) -> None:
    """Bounds on the work a study asks for (each message says the bound)."""
    d, mg, fm = s.doe, s.magnet, s.magnetics
    paths = d.n_theta * d.n_H * (1 if s.mechanics.scale_in_G else d.n_G)
    paths *= math.prod(len(v) for v in s.geometry_levels.values())
    if paths > MAX_PATHS:
        key = "doe.n_G" if not s.mechanics.scale_in_G and d.n_G > 1 else "doe.n_H"
        raise StudyError(key, f"the DOE asks for {paths:,} structural paths (n_theta × n_H"
                              f"{'' if s.mechanics.scale_in_G else ' × n_G'}); at most "
                              f"{MAX_PATHS:,}", source)
    points = d.n_t * d.n_theta * d.n_H
    if points > MAX_FIELD_POINTS:
        raise StudyError("doe.n_t", f"the DOE asks for {points:,} field points (n_t × n_theta × "
                                    f"n_H); at most {MAX_FIELD_POINTS:,}", source)
    if points * d.n_G > MAX_DATA_POINTS:
        raise StudyError("doe.n_G", f"the DOE data set would hold {points * d.n_G:,} force points "
                                    f"(n_t × n_theta × n_H × n_G); at most {MAX_DATA_POINTS:,}",
                         source)
    finest = MIN_H_MAGNET_RATIO * min(mg.R_m, mg.H_m)
    if fm.h_magnet < finest:
        raise StudyError("magnetics.h_magnet_mm", f"an element size of {_mm(fm.h_magnet)} mm "
                                                  f"would mesh millions of cells; at least "
                                                  f"min(R_m, H_m)/200 = {_mm(finest)} mm",
                         source)
    if fm.h_magnet > min(mg.R_m, mg.H_m):
        raise StudyError("magnetics.h_magnet_mm", f"an element size of {_mm(fm.h_magnet)} mm "
                                                  f"does not resolve the magnet; at most "
                                                  f"min(R_m, H_m) = {_mm(min(mg.R_m, mg.H_m))} "
                                                  "mm", source)
    if not fm.growth_near < fm.growth:
        raise StudyError("magnetics.growth_near", f"must be below magnetics.growth = "
                                                  f"{fm.growth:g}, got {fm.growth_near:g}", source)


def _check_order(s: Study, source) -> None:
    """Settings that must keep an order among themselves, and settings bounded by the data the
    study's DOE produces."""
    m = s.mechanics
    if m.dt_min > m.dt_max:
        raise StudyError("mechanics.dt_min", f"the smallest load step ({m.dt_min:g}) must not "
                                             f"exceed the largest, mechanics.dt_max = "
                                             f"{m.dt_max:g}", source)
    if not m.dt_min <= m.dt_initial <= m.dt_max:
        raise StudyError("mechanics.dt_initial", f"the first load step ({m.dt_initial:g}) must "
                                                 f"lie in [mechanics.dt_min, mechanics.dt_max] "
                                                 f"= [{m.dt_min:g}, {m.dt_max:g}]", source)


def _mm(x: float) -> str:
    return f"{from_si(x, 'mm'):.6g}"
