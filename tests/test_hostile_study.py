"""Hostile and absurd study files: a valid study or one StudyError naming the file and key.

The property tests generate TOML documents (valid keys with hostile values, unknown keys, deep
nesting, raw bytes) and check that :func:`magtact.study.load_study` either returns a study whose
every number lies within the physical bounds of its setting, or raises :class:`StudyError`;
nothing else may escape and nothing may take long.
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import fields
from pathlib import Path

import pytest
import tomli_w
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import deny_open
from magtact.study import PHYSICAL, Study, StudyError, load_study, magone, study_from_dict
from magtact.study._load import MAX_DATA_POINTS, MAX_FIELD_POINTS, MAX_FILE_BYTES, MAX_PATHS
from magtact.study._model import SECTIONS, key_of

# ---- the settings, from the dataclasses (so new settings are generated too) ------------------
SPECS = {name: {key_of(f): f for f in fields(getattr(Study(), name))} for name in SECTIONS}


def write(tmp_path: Path, text: str | bytes, name: str = "s.toml") -> Path:
    path = tmp_path / name
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text, encoding="utf-8")
    return path


def refused(path_or_data, key: str, *fragments: str) -> str:
    with pytest.raises(StudyError) as info:
        if isinstance(path_or_data, dict):
            study_from_dict(path_or_data, "bad.toml")
        else:
            load_study(path_or_data)
    message = str(info.value)
    assert info.value.key == key, message
    assert f"[{key}]" in message and "\n" not in message, message
    for fragment in fragments:
        assert fragment in message, (fragment, message)
    return message


# ---- files that cannot be read as a study -----------------------------------------------------
def test_utf8_byte_order_mark_is_accepted(tmp_path):
    path = write(tmp_path, b'\xef\xbb\xbfname = "with BOM"\n[doe]\nn_t = 11\n')
    s = load_study(path)
    assert s.name == "with BOM" and s.doe.n_t == 11


def test_not_utf8_names_file_and_byte(tmp_path):
    path = write(tmp_path, b'name = "caf\xe9"\n')
    msg = refused(path, "file", "is not UTF-8 text", "byte 0xe9 at offset 11")
    assert msg.startswith(str(path))


def test_folder_unreadable_and_oversized_files(tmp_path, monkeypatch):
    refused(tmp_path, "file", "is not a file")
    big = write(tmp_path, "# " + "x" * MAX_FILE_BYTES + "\n", "big.toml")
    refused(big, "file", f"at most {MAX_FILE_BYTES:,}")
    locked = write(tmp_path, 'name = "x"\n', "locked.toml")

    deny_open(monkeypatch, locked)
    msg = refused(locked, "file", "cannot be read: Permission denied")
    assert msg.startswith(str(locked))


def test_deep_nesting_is_refused(tmp_path):
    path = write(tmp_path, "x = " + "[" * 1000 + "]" * 1000 + "\n")
    refused(path, "file", "nest too deeply")
    path = write(tmp_path, "[doe]\nn_t = " + "[" * 50 + "1" + "]" * 50 + "\n")
    refused(path, "doe.n_t", "expected an integer, got [[[[")


def test_unhashable_values_and_odd_types():
    refused({"base": ["magone"]}, "base", "expected one of", "['magone']")
    refused({"base": {"a": 1}}, "base", "expected one of")
    refused({"magnet": {"placement": ["covered"]}}, "magnet.placement", "one of 'covered'")
    refused({"name": ["x"]}, "name", "expected a string")
    refused({"doe": {"n_t": {"a": 1}}}, "doe.n_t", "expected an integer")


def test_keys_with_line_breaks_are_escaped_in_one_line():
    with pytest.raises(StudyError) as info:
        study_from_dict({"design": {"H\nmm\x00": 3.0}}, "bad.toml")
    assert str(info.value).startswith("bad.toml: [design.H\\nmm\\x00] unknown key")
    assert "\n" not in str(info.value)


# ---- values that would overflow or vanish in the unit conversion ------------------------------
@pytest.mark.parametrize("section, key, value, fragments", [
    ("material", "G_ref_kPa", 1e306, ("between 0.001 and 1e+06 kPa", "1 to 1e+09 Pa in SI")),
    ("magnet", "H_m_mm", 4e-322, ("between 0.001 and 1000 mm", "1e-06 to 1 m in SI")),
    ("body", "R_h_mm", 4e-322, ("0 or between 0.001 and 1000 mm",)),
    ("design", "G_kPa", [1e-300, 1e300], ("between 0.001 and 1e+06 kPa", "1e-300")),
    ("design", "H_mm", [3.0, 1e308], ("between 0.001 and 1000 mm",)),
    ("magnet", "M_z_A_per_m", 1e12, ("between 1 and 1e+07 A/m",)),
    ("constraints", "F_r_c_N", -1e300, ("between -1e+06 and 1e+06 N",)),
    ("body", "R_mm", 10**400, ("integer of about 401 digits", "outside the range of a double")),
    ("loading", "mu_f", 1e200, ("between 0.001 and 10",)),
])
def test_values_checked_in_si_with_bounds_in_message(section, key, value, fragments):
    refused({section: {key: value}}, f"{section}.{key}", *fragments)


def test_edge_radius_refused_by_the_study_in_mm():
    refused({"mechanics": {"magnet_edge_radius_mm": 100.0}}, "mechanics.magnet_edge_radius_mm",
            "100 mm", "min(R_m, H_m) = 2 mm")


def test_unknown_element_refused_with_the_choices():
    refused({"mechanics": {"element": "tet10"}}, "mechanics.element", "'tet10'",
            "'hex8', 'hex20', 'hex27'")


def test_every_number_has_physical_bounds_that_hold_the_presets():
    """Each float setting is checked in SI; the built-in studies lie within the bounds."""
    for section, spec in SPECS.items():
        for key, f in spec.items():
            m = f.metadata
            if m["choices"] or isinstance(f.default, bool) or m["integer"]:
                assert m["integer"] is False or m["maximum"] is not None, f"{section}.{key}"
                continue
            assert m["bounds"] is not None, f"{section}.{key} has no physical bounds"
    assert set(PHYSICAL) <= {"mm", "kPa", "A_per_m", "N", "rad"}
    for s in (magone(), load_study("magone-printed")):
        assert_within_bounds(s)


# ---- work a study may ask for ------------------------------------------------------------------
@pytest.mark.parametrize("doe, key, fragment", [
    ({"n_t": 9223372036854775807}, "doe.n_t", "at most 1,001"),
    ({"n_t": 1000000}, "doe.n_t", "at most 1,001"),
    ({"n_t": 10**30}, "doe.n_t", "got 1000000000000000000000000000000"),
    ({"n_theta": 101, "n_H": 100}, "doe.n_H", f"at most {MAX_PATHS:,}"),
    ({"n_t": 1001, "n_theta": 50, "n_H": 50}, "doe.n_t", f"at most {MAX_FIELD_POINTS:,}"),
    ({"n_t": 1001, "n_theta": 10, "n_H": 10, "n_G": 1001}, "doe.n_G",
     f"at most {MAX_DATA_POINTS:,}"),
])
def test_doe_size_is_bounded(doe, key, fragment):
    refused({"doe": doe}, key, fragment)


def test_per_G_paths_and_mesh_size_are_bounded():
    refused({"doe": {"n_theta": 20, "n_H": 20, "n_G": 30}, "mechanics": {"scale_in_G": False}},
            "doe.n_G", "12,000 structural paths", f"at most {MAX_PATHS:,}")
    refused({"magnetics": {"h_magnet_mm": 1e-9}}, "magnetics.h_magnet_mm", "got 1e-09")
    refused({"magnetics": {"h_magnet_mm": 0.005}}, "magnetics.h_magnet_mm",
            "min(R_m, H_m)/200 = 0.01 mm")
    refused({"magnetics": {"h_magnet_mm": 3.0}}, "magnetics.h_magnet_mm",
            "at most min(R_m, H_m) = 2 mm")


# ---- property-based: generated TOML documents ----------------------------------------------------
def assert_within_bounds(s: Study) -> None:
    """The oracle of an accepted study: every number finite and within its setting's bounds."""
    for section in SECTIONS:
        sec = getattr(s, section)
        for f in fields(sec):
            value, m = getattr(sec, f.name), f.metadata
            values = value if isinstance(value, tuple) else (value,)
            for v in values:
                if isinstance(v, (str, bool)):
                    continue
                assert math.isfinite(v), (section, f.name, v)
                if m["maximum"] is not None:
                    assert v <= m["maximum"], (section, f.name, v)
                if m["bounds"] is not None and not (v == 0 and m["minimum"] == 0):
                    lo, hi = m["bounds"]
                    assert lo <= v <= hi, (section, f.name, v)
    d = s.doe
    assert d.n_theta * d.n_H <= MAX_PATHS and d.n_t * d.n_theta * d.n_H <= MAX_FIELD_POINTS
    assert d.n_t * d.n_theta * d.n_H * d.n_G <= MAX_DATA_POINTS


FLOATS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(min_value=1e-3, max_value=1e3),  # mostly plausible user values
    st.sampled_from([0.0, -0.0, 5e-324, 4e-322, 1e-300, 1e300, 1e306, 1.7976931348623157e308]),
)
INTS = st.one_of(st.integers(-10, 2000), st.integers(), st.sampled_from(
    [0, 1, 2, 2**63 - 1, -(2**63), 10**30, 10**400]))
LEAVES = st.one_of(FLOATS, INTS, st.booleans(), st.text(max_size=20),
                   st.sampled_from(["covered", "flush", "fe", "exact", "magone", "none"]))
VALUES = st.recursive(LEAVES, lambda inner: st.one_of(
    st.lists(inner, max_size=3), st.dictionaries(st.text(max_size=5), inner, max_size=2)),
    max_leaves=6)


@st.composite
def documents(draw):
    """A TOML-shaped dict: known sections with known or misspelt keys and hostile values."""
    doc = {}
    if draw(st.booleans()):
        doc["base"] = draw(st.one_of(st.sampled_from(["magone", "magone-printed", "none"]),
                                     VALUES))
    if draw(st.booleans()):
        doc["name"] = draw(st.one_of(st.text(max_size=30), VALUES))
    for section in draw(st.lists(st.sampled_from([*SECTIONS, "geometry"]), max_size=4,
                                 unique=True)):
        spec = SPECS.get(section, {"R_mm": None})
        keys = draw(st.lists(st.one_of(st.sampled_from(sorted(spec)), st.text(max_size=8),
                                       st.sampled_from(["a\nb", "\x00", "R_mm\r", "\u2028"])),
                             max_size=4, unique=True))
        table = {}
        for key in keys:
            f = spec.get(key)
            if f is not None and isinstance(f.default, tuple):
                value = draw(st.one_of(st.lists(FLOATS | INTS, min_size=2, max_size=2), VALUES))
            else:
                value = draw(VALUES)
            table[key] = value
        doc[section] = draw(st.one_of(st.just(table), VALUES)) if section == "geometry" \
            else table
    return doc


def load_or_refuse(load):
    """Run ``load``; return the study or None if refused with a one-line StudyError."""
    try:
        s = load()
    except StudyError as exc:
        message = str(exc)
        assert message.count("[") >= 1 and "\n" not in message and len(message) < 2000, message
        return None
    assert_within_bounds(s)
    return s


SETTINGS = settings(max_examples=300, deadline=2000, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


@SETTINGS
@given(documents())
def test_generated_documents_give_a_bounded_study_or_a_study_error(doc):
    with tempfile.TemporaryDirectory() as tmp:
        try:
            text = tomli_w.dumps(doc)
        except (TypeError, ValueError, OverflowError):
            return  # not expressible in TOML: not a file a user can hand in
        path = write(Path(tmp), text)
        s = load_or_refuse(lambda: load_study(path))
        if s is not None:  # an accepted study writes itself back to the same study
            assert load_study(write(Path(tmp), s.to_toml(), "back.toml")) == s


TOML_TOKENS = st.sampled_from([
    "[doe]\n", "[body]\n", "[magnet]\n", "[[doe]]\n", "n_t = ", "R_mm = ", "H_m_mm = ",
    "base = ", "name = ", "\n", "=", "[", "]", "{", "}", ",", '"', "'", "1", "-", ".", "e308",
    "nan", "inf", "true", "1979-05-27", "0x1F", "1_000", "\\", "\x00", "\ufeff", "é", "#",
])


@settings(max_examples=200, deadline=2000, derandomize=True)
@given(st.one_of(st.lists(TOML_TOKENS, max_size=40).map("".join),
                 st.binary(max_size=200)))
def test_raw_text_and_bytes_give_a_study_or_a_study_error(raw):
    with tempfile.TemporaryDirectory() as tmp:
        path = write(Path(tmp), raw.encode("utf-8") if isinstance(raw, str) else raw)
        load_or_refuse(lambda: load_study(path))


def test_bounds_in_si_units_are_said_once():
    refused({"constraints": {"F_z_c_N": 1e9}}, "constraints.F_z_c_N",
            "must be between -1e+06 and 1e+06 N, got 1000000000.0")
    msg = refused({"magnet": {"M_z_A_per_m": 0.5}}, "magnet.M_z_A_per_m")
    assert "between 1 and 1e+07 A/m, got 0.5" in msg and "in SI" not in msg
