"""The records of the JSON files (``magtact._records``): a document written from the
declarations reads back as the record, numbers convert through the units module and back to
the same file, and a document that is not the record is refused with a message that names the
file, the key and what was found."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from magtact._records import (
    RecordError,
    check_declarations,
    entry,
    from_json,
    from_json_lenient,
    from_json_or_none,
    keys,
    si_value,
    to_json,
    user_value,
)
from magtact.study import from_si, to_si


@dataclass(frozen=True)
class Pair:
    x: float = entry("pair_x_mm", "mm")
    y: float = entry("pair_y_mm", "mm")


@dataclass(frozen=True)
class Part:
    name: str = entry(kind=str)
    force: float = entry(unit="mN", null_nan=True)


@dataclass(frozen=True)
class Sample:
    """A record with every kind of declaration."""

    title: str = entry(kind=str, default="Sample", kw_only=True)
    H: float = entry(unit="mm")
    count: int = entry(kind=int)
    ok: bool = entry(kind=bool)
    M_z: float | None = entry(unit="A_per_m", optional=True)
    pair: tuple | None = entry(kind=Pair, shape="tuple", inline=True, optional=True)
    parts: tuple = entry(kind=Part, levels=("list",))
    loop: np.ndarray = entry(unit="mN", levels=("list",), array=True)
    named: dict = entry("named", "mN", levels=("map", "list"), key_units={"gain": "N_per_T"})
    extra: dict = entry(kind=Part, shape="dict", default_factory=dict)
    note: object = entry(kind=object, omit="empty", default_factory=dict)
    shape: tuple | None = entry("shape_mm", kind=Pair, shape="tuple", optional=True,
                                omit="none", default=None)


def _sample(**change) -> Sample:
    values = dict(H=3e-3, count=4, ok=True, M_z=1.1e6, pair=(1e-3, 2e-3),
                  parts=(Part("a", 1e-3), Part("b", math.nan)), loop=np.array([0.0, 2e-3]),
                  named={"gain": (1.0, 2.0), "cal_r": (1e-3, 2e-3)},
                  extra={"name": "c", "force": 3e-3})
    return Sample(**(values | change))


def test_the_declarations_give_the_keys_in_order_and_their_units_are_known():
    assert keys(Sample) == ("title", "H_mm", "count", "ok", "M_z_A_per_m", "pair_x_mm",
                            "pair_y_mm", "parts", "loop_mN", "named", "extra", "note",
                            "shape_mm")
    check_declarations(Sample)

    @dataclass
    class Typo:
        x: float = entry(unit="milimetre")

    with pytest.raises(KeyError, match="milimetre"):
        check_declarations(Typo)


def test_a_record_is_written_in_user_units_and_read_back_in_si():
    s = _sample()
    doc = to_json(s)
    assert doc == {"title": "Sample", "H_mm": 3.0, "count": 4, "ok": True,
                   "M_z_A_per_m": 1.1e6, "pair_x_mm": 1.0, "pair_y_mm": 2.0,
                   "parts": [{"name": "a", "force_mN": 1.0}, {"name": "b", "force_mN": None}],
                   "loop_mN": [0.0, 2.0], "named": {"gain_N_per_T": [1.0, 2.0],
                                                    "cal_r_mN": [1.0, 2.0]},
                   "extra": {"name": "c", "force_mN": 3.0}}
    back = from_json(Sample, json.loads(json.dumps(doc)))
    assert back.H == 3e-3 and back.pair == (1e-3, 2e-3) and back.M_z == 1.1e6
    assert back.parts[0] == Part("a", 1e-3) and math.isnan(back.parts[1].force)
    np.testing.assert_array_equal(back.loop, [0.0, 2e-3])
    assert back.named == {"gain": (1.0, 2.0), "cal_r": (1e-3, 2e-3)}
    assert back.extra == {"name": "c", "force": 3e-3} and back.note == {}
    assert back.shape is None


def test_none_and_empty_values_are_written_as_declared():
    doc = to_json(_sample(M_z=None, pair=None, extra={}, note={"a": [1]}, shape=(1e-3, 1e-3)))
    assert doc["M_z_A_per_m"] is None and doc["pair_x_mm"] is None and doc["extra"] == {}
    assert doc["note"] == {"a": [1]} and doc["shape_mm"] == {"pair_x_mm": 1.0,
                                                            "pair_y_mm": 1.0}
    back = from_json(Sample, doc)
    assert back.M_z is None and back.pair is None and back.extra == {}
    assert back.note == {"a": [1]} and back.shape == (1e-3, 1e-3)


UNITS = ("mm", "mN", "kPa", "uT", "mT", "pct", "pct_per_K", "um", "A_per_m", "rad")
#: Numbers of a physical record: finite, none below 1e-200 in size but zero (a subnormal's
#: conversion loses digits that no file can give back).
finite = st.floats(allow_nan=False, allow_infinity=False, min_value=-1e12,
                   max_value=1e12).filter(lambda x: x == 0 or abs(x) > 1e-200)


@settings(max_examples=300, deadline=None)
@given(si=finite, unit=st.sampled_from(UNITS))
def test_a_number_written_and_read_writes_the_same_number_again(si, unit):
    user = user_value(si, unit)
    assert user == from_si(si, unit)  # the writer is the units module's conversion
    back = si_value(user, unit)
    assert user_value(back, unit) == user  # the file read and written again is the same
    assert back == si or abs(back - si) <= 2 * math.ulp(si)


@settings(max_examples=300, deadline=None)
@given(user=finite, unit=st.sampled_from(UNITS))
def test_a_file_number_reads_as_the_si_value_nearest_to_the_units_module(user, unit):
    si = si_value(user, unit)
    assert abs(si - to_si(user, unit)) <= 2 * math.ulp(to_si(user, unit))
    if from_si(to_si(user, unit), unit) == user:
        assert si == to_si(user, unit)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(H=finite, parts=st.lists(st.tuples(st.text(max_size=5), finite), max_size=4))
def test_a_written_record_reads_back_and_writes_the_same_document(H, parts):
    s = _sample(H=H, parts=tuple(Part(n, f) for n, f in parts))
    text = json.dumps(to_json(s))
    again = json.dumps(to_json(from_json(Sample, json.loads(text))))
    assert again == text


# ---- hostile documents ------------------------------------------------------------------------
def _doc() -> dict:
    return json.loads(json.dumps(to_json(_sample())))


@pytest.mark.parametrize(("change", "message"), [
    (lambda d: d.pop("H_mm"), "sample.json: the document: missing key 'H_mm' (Sample)"),
    (lambda d: d.update(H_mm="3"), "sample.json: H_mm: expected a number (mm), got '3'"),
    (lambda d: d.update(H_mm=True), "sample.json: H_mm: expected a number (mm), got True"),
    (lambda d: d.update(count=4.0), "sample.json: count: expected an integer, got 4.0"),
    (lambda d: d.update(count=False), "sample.json: count: expected an integer, got False"),
    (lambda d: d.update(ok=1), "sample.json: ok: expected true or false, got 1"),
    (lambda d: d.pop("pair_y_mm"), "sample.json: the document: missing key 'pair_y_mm' (Pair)"),
    (lambda d: d.update(parts={}), "sample.json: parts: expected a JSON array, got {}"),
    (lambda d: d["parts"][1].pop("name"),
     "sample.json: parts[1]: missing key 'name' (Part)"),
    (lambda d: d["parts"].append(3), "sample.json: parts[2]: expected a JSON object (Part), "
                                     "got 3"),
    (lambda d: d["parts"][0].update(force_mN=[1]),
     "sample.json: parts[0].force_mN: expected a number (mN), got [1]"),
    (lambda d: d["named"].update(gain_N_per_T=[None]),
     "sample.json: named.gain_N_per_T[0]: expected a number (N_per_T), got None"),
    (lambda d: d.update(loop_mN=None), "sample.json: loop_mN: expected a JSON array, got None"),
    (lambda d: d.update(extra={"name": "c"}),
     "sample.json: extra: missing key 'force_mN' (Part)"),
])
def test_a_document_of_another_shape_is_refused_naming_the_key(change, message):
    doc = _doc()
    change(doc)
    with pytest.raises(RecordError) as info:
        from_json(Sample, doc, "sample.json")
    assert str(info.value) == message
    assert from_json_or_none(Sample, doc) is None


def test_without_a_file_the_message_names_the_record():
    with pytest.raises(RecordError, match=r"^Sample: the document: expected a JSON object "
                                          r"\(Sample\), got \[\]$"):
        from_json(Sample, [])


json_values = st.recursive(st.none() | st.booleans() | st.integers() | finite | st.text(),
                           lambda inner: st.lists(inner, max_size=3)
                           | st.dictionaries(st.text(max_size=8), inner, max_size=3),
                           max_leaves=10)


@settings(max_examples=150, deadline=None)
@given(key=st.sampled_from(keys(Sample)), value=json_values)
def test_a_hostile_value_reads_as_a_record_or_an_error_that_names_its_key(key, value):
    doc = _doc() | {key: value}
    try:
        s = from_json(Sample, doc, "sample.json")
    except RecordError as exc:
        assert str(exc).startswith("sample.json: ")
        assert key in str(exc) or "the document: missing key" in str(exc)
    else:
        assert isinstance(s, Sample)
        assume(key not in ("note", "title"))
        json.dumps(to_json(s))  # whatever was read writes a document again


@settings(max_examples=100, deadline=None)
@given(drop=st.sets(st.sampled_from(keys(Sample)), min_size=1))
def test_a_document_without_a_required_key_names_it(drop):
    doc = {k: v for k, v in _doc().items() if k not in drop}
    required = [k for k in keys(Sample) if k in drop and k not in ("title", "extra", "note",
                                                                   "shape_mm")]
    if not required:
        assert isinstance(from_json(Sample, doc), Sample)
        return
    with pytest.raises(RecordError, match="missing key") as info:
        from_json(Sample, doc, "sample.json")
    assert any(f"missing key {k!r}" in str(info.value) for k in required)


def test_the_sensor_is_written_with_its_chip_setting_and_read_back():
    from dataclasses import replace

    from magtact import Sensor
    from magtact.parts import ChipSetting
    from magtact.study import load_study

    sensor = replace(Sensor.of_study(load_study("magone"), 3e-3, 29.4e3),
                     setting=ChipSetting(7, 2, 2, 3), standoff=2.4e-3)
    doc = json.loads(json.dumps(sensor.to_json()))
    assert list(doc) == ["H_mm", "G_kPa", "R_mm", "silicone", "magnet_R_m_mm",
                         "magnet_H_m_mm", "magnet_grade", "M_z_A_per_m", "chip",
                         "chip_setting", "standoff_mm"]
    assert doc["chip_setting"] == {"gain_sel": 7, "res": 2, "osr": 2, "dig_filt": 3}
    assert doc["standoff_mm"] == from_si(2.4e-3, "mm") and doc["G_kPa"] == 29.4
    assert Sensor.from_json(doc) == sensor
    assert Sensor.from_json(doc | {"chip_setting": {"gain_sel": "7"}}) is None


# ---- lenient reading --------------------------------------------------------------------------
def test_a_lenient_read_takes_what_the_document_gives_and_defaults_for_the_rest():
    doc = _doc()
    doc.pop("count")
    doc |= {"H_mm": "3", "title": 4, "note": [1]}
    doc["parts"][1]["force_mN"] = "x"
    s = from_json_lenient(Sample, doc)
    assert s.count is None and s.H is None  # missing (no default) and of another type
    assert s.title == "Sample" and s.note == [1]  # the default, and any JSON as is
    assert s.ok is True and s.pair == (1e-3, 2e-3) and s.M_z == 1.1e6
    assert s.parts[0] == Part("a", 1e-3) and s.parts[1] == Part("b", None)
    with pytest.raises(RecordError, match="title: expected text"):
        from_json(Sample, doc)  # the strict reader refuses the same document


def test_a_lenient_read_of_an_inline_record_reads_its_keys_one_by_one():
    doc = _doc()
    doc.pop("pair_y_mm")
    assert from_json_lenient(Sample, doc).pair == (1e-3, None)
    doc["pair_x_mm"] = None
    assert from_json_lenient(Sample, doc).pair is None  # every key null or missing


@pytest.mark.parametrize("doc", [None, [], "x", 3.0])
def test_a_lenient_read_of_no_object_is_none(doc):
    assert from_json_lenient(Sample, doc) is None


@dataclass(frozen=True)
class WithOptional:
    a: float = entry(unit="mm")
    b: float | None = entry(unit="mm", optional=True, omit="none", default=None, kw_only=True)
    c: str = entry(kind=str)


@dataclass(frozen=True)
class Holder:
    inner: WithOptional = entry(kind=WithOptional, inline=True)
    d: int = entry(kind=int)


def test_an_inline_record_without_its_omitted_keys_reads_strictly():
    doc = to_json(Holder(WithOptional(1e-3, c="x"), 2))
    assert doc == {"a_mm": 1.0, "c": "x", "d": 2}
    assert from_json(Holder, doc) == Holder(WithOptional(1e-3, c="x"), 2)
    doc = to_json(Holder(WithOptional(1e-3, b=2e-3, c="x"), 2))
    assert doc == {"a_mm": 1.0, "b_mm": 2.0, "c": "x", "d": 2}
    assert from_json(Holder, doc).inner.b == 2e-3
    with pytest.raises(RecordError, match=r"missing key 'c' \(WithOptional\)"):
        from_json(Holder, {"a_mm": 1.0, "d": 2}, "holder.json")


@dataclass(frozen=True)
class Grouped:
    name: str = entry(kind=str)
    group: WithOptional | None = entry(kind=WithOptional, inline=True, omit="none",
                                       default=None)


def test_an_inline_record_left_out_reads_as_the_default():
    assert to_json(Grouped("g")) == {"name": "g"}
    assert from_json(Grouped, {"name": "g"}) == Grouped("g")
    doc = to_json(Grouped("g", WithOptional(1e-3, c="x")))
    assert doc == {"name": "g", "a_mm": 1.0, "c": "x"}
    assert from_json(Grouped, doc) == Grouped("g", WithOptional(1e-3, c="x"))
    with pytest.raises(RecordError, match=r"missing key 'c' \(WithOptional\)"):
        from_json(Grouped, {"name": "g", "a_mm": 1.0})  # a part of the group is no group


@dataclass(frozen=True)
class Table:
    rows: np.ndarray = entry(unit="mN", levels=("list", "list"), array=True)


def test_an_array_of_rows_reads_as_a_matrix_and_ragged_rows_are_refused():
    t = from_json(Table, {"rows_mN": [[1.0, 2.0], [3.0, 4.0]]})
    np.testing.assert_array_equal(t.rows, [[1e-3, 2e-3], [3e-3, 4e-3]])
    with pytest.raises(RecordError, match="table.json: rows_mN: expected an array of rows"):
        from_json(Table, {"rows_mN": [[1.0, 2.0], [3.0]]}, "table.json")


def test_a_table_row_keeps_its_numbers_that_are_not_finite():
    s = _sample(parts=(Part("b", math.nan),))
    assert to_json(s)["parts"] == [{"name": "b", "force_mN": None}]
    row = to_json(s, null_nan=False)["parts"][0]
    assert row["name"] == "b" and math.isnan(row["force_mN"])


@dataclass(frozen=True)
class Stage:
    name: str = entry(kind=str, fallback="unknown")
    status: str = entry(kind=str, default="pending", fallback="unknown")


@dataclass(frozen=True)
class Run:
    stages: tuple = entry(kind=Stage, levels=("list",))
    by_name: dict = entry(kind=Stage, levels=("map",), default_factory=dict)


def test_a_lenient_read_gives_the_fallback_and_keeps_the_items_that_read():
    doc = {"stages": [{"name": "a", "status": "ok"}, 3, {"status": 4}, None],
           "by_name": {"x": {"name": "x"}, "y": "no"}}
    run = from_json_lenient(Run, doc)
    assert run.stages == (Stage("a", "ok"), Stage("unknown", "unknown"))
    assert run.by_name == {"x": Stage("x", "unknown")}
    assert from_json(Stage, {"name": "b"}).status == "pending"  # a strict read: the default
    with pytest.raises(RecordError, match=r"stages\[1\]: expected a JSON object"):
        from_json(Run, doc)


@dataclass(frozen=True)
class Row:
    quantity: str = entry(kind=str)
    cells: dict = entry(kind=object, levels=("map",), inline=True)
    parts: dict = entry(kind=Part, levels=("map",), optional=True, default_factory=dict)


def test_a_map_inline_stands_in_the_object_and_null_items_read_as_none():
    r = Row("q", {"a/b": {"x": 1}, "c": 2}, {"p": None, "q": Part("n", 1e-3)})
    doc = to_json(r)
    assert doc == {"quantity": "q", "a/b": {"x": 1}, "c": 2,
                   "parts": {"p": None, "q": {"name": "n", "force_mN": 1.0}}}
    assert keys(Row) == ("quantity", "parts")
    assert from_json(Row, doc) == r
