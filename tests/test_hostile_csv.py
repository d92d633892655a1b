"""Hostile validation CSV files and options: an experiment within its physical ranges, or one
DataError (or a ValueError of an option) naming the file, line and column.

The property tests generate CSV tables (known and junk columns, hostile cells, metadata lines)
and raw text, and check that :func:`magtact.validation.read_experiment` returns an experiment
that satisfies every documented rule, or raises :class:`DataError`; nothing else may escape.
"""

from __future__ import annotations

import csv
import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import deny_open
from magtact.validation import DataError, read_experiment
from magtact.validation._io import MAX_MESSAGE, MIN_SAMPLES, PHYSICAL_RANGE

HEADER = "u_z_mm,B_r_T,B_z_T,F_r_N,F_z_N"
ROWS = [f"{-0.5 * k},0.001,0.04,0.01,-0.5" for k in range(5)]


def write(folder: Path, name: str, lines: list[str] | bytes) -> Path:
    path = folder / name
    if isinstance(lines, bytes):
        path.write_bytes(lines)
    else:
        path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def good(folder: Path, name: str, repeat: int) -> Path:
    return write(folder, name, ["# theta_rad = 0.3", f"# repeat = {repeat}", HEADER, *ROWS])


def refused(paths, *fragments: str) -> str:
    with pytest.raises(DataError) as info:
        read_experiment(paths)
    message = str(info.value)
    for fragment in fragments:
        assert fragment in message, (fragment, message)
    assert "\n" not in message and len(message) <= MAX_MESSAGE + 40
    return message


# ---- one file, each class of damage ------------------------------------------------------------
def test_giant_cell_is_a_data_error_naming_the_line(tmp_path):
    rows = list(ROWS)
    rows[2] = '-1.0,"' + "9" * 200_000 + '",0.04,0.01,-0.5'
    bad = write(tmp_path, "bad.csv", ["# theta_rad = 0.3", HEADER, *rows])
    msg = refused([good(tmp_path, "a.csv", 1), bad], "bad.csv: line 5: not a CSV row",
                  "field larger than field limit")
    assert len(msg) < MAX_MESSAGE + 40


def test_giant_label_is_clipped_in_the_message(tmp_path):
    path = write(tmp_path, "one.csv", ["# theta_rad = 0.3", "# repeat = " + "r" * 100_000,
                                       HEADER, *ROWS])
    msg = refused(path, "one.csv", "only one test")
    assert len(msg) <= MAX_MESSAGE + 40


def test_values_outside_the_physical_range(tmp_path):
    rows = list(ROWS)
    rows[1] = "-0.5,0.001,1e300,0.01,-0.5"
    bad = write(tmp_path, "bad.csv", ["# theta_rad = 0.3", HEADER, *rows])
    refused([good(tmp_path, "a.csv", 1), bad], "bad.csv: line 4, column 'B_z_T'",
            "outside the physical range [-100, 100] T")
    rows[1] = "-5e6,0.001,0.04,0.01,-0.5"
    bad = write(tmp_path, "bad.csv", ["# theta_rad = 0.3", HEADER, *rows])
    refused([good(tmp_path, "a.csv", 1), bad], "column 'u_z_mm'", "[-1, 1] m")
    bad = write(tmp_path, "bad.csv", ["# theta_rad = nan", HEADER, *ROWS])
    refused([good(tmp_path, "a.csv", 1), bad], "bad.csv: line 1, metadata 'theta_rad'",
            "outside [0, π/2] rad")


def test_folder_and_unreadable_files(tmp_path, monkeypatch):
    refused([good(tmp_path, "a.csv", 1), tmp_path], f"{tmp_path}: not a file: it is a folder")
    locked = good(tmp_path, "locked.csv", 2)

    deny_open(monkeypatch, locked)
    refused([locked], "locked.csv: cannot be read: Permission denied")


def test_design_metadata_is_checked_in_si(tmp_path):
    lines = ["# theta_rad = 0.3", "# design_H_mm = 1e6", "# design_G_kPa = nan", HEADER, *ROWS]
    a = write(tmp_path, "a.csv", [*lines[:1], "# repeat = 1", *lines[1:]])
    b = write(tmp_path, "b.csv", [*lines[:1], "# repeat = 2", *lines[1:]])
    experiment = read_experiment([a, b])
    with pytest.raises(ValueError, match=r"a.csv: metadata 'design_h_mm' must be between 0.001 "
                                         r"and 1000 mm .* got 1000000.0"):
        experiment.design()
    with pytest.raises(ValueError, match=r"a.csv: metadata 'design_g_kpa' must be between"):
        experiment.design(H=4e-3)


@pytest.mark.parametrize("option, value, fragment", [
    ("--G", "nan", "--G must be between 0.001 and 1e+06 kPa"),
    ("--H", "1e6", "--H must be between 0.001 and 1000 mm"),
    ("--H", "-4", "--H must be between 0.001 and 1000 mm"),
    ("--f-hi", "-1", "--f-hi must be between 0 and 1e+06 cycles per mm"),
    ("--f-lo", "inf", "--f-lo must be between 0"),
])
def test_validate_options_are_refused_with_their_bounds(tmp_path, option, value, fragment):
    from test_command_outputs import cli  # the command line's entry point, in this process

    code, text = cli("validate", option, value, "--out", tmp_path / "v")
    assert code == 2, text
    assert fragment in text and "Traceback" not in text, text
    assert not (tmp_path / "v").exists()


def test_validate_n_grid_is_bounded(tmp_path):
    from magtact.validation import PathModel, synthetic_files, validate

    experiment = read_experiment(synthetic_files())
    model = PathModel(fn=lambda u: {r: np.ones_like(u) for r in ("B_r", "B_z", "F_r", "F_z")},
                      theta=experiment.theta)
    with pytest.raises(ValueError, match="n_grid must be between 2 and 100,001, got 10000000"):
        validate(experiment, model, n_grid=10**7)


def test_non_finite_model_stops_validation_naming_response(tmp_path):
    from magtact.validation import PathModel, synthetic_files, validate

    experiment = read_experiment(synthetic_files())

    def fn(u):
        out = {r: np.ones_like(u) for r in ("B_r", "B_z", "F_r", "F_z")}
        out["F_z"] = np.where(u < -1e-3, np.nan, 1.0)
        return out

    model = PathModel(fn=fn, theta=experiment.theta, label="broken")
    with pytest.raises(ValueError, match=r"model 'broken' gives a non-finite F_z \(nan\) at u_z"):
        validate(experiment, model)


# ---- property-based: generated tables ------------------------------------------------------------
COLUMNS = ["u_z_mm", "u_z_m", "u_r_mm", "B_r_T", "B_z_T", "F_r_N", "F_z_N", "theta_rad",
           "theta_deg", "sensor", "repeat", "time_s", "", "B_r_T"]
CELLS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.floats(min_value=-5, max_value=5).map(lambda v: f"{v:.3g}"),
    st.integers(-(10**30), 10**30).map(str),
    st.sampled_from(["", "nan", "inf", "-inf", "1e309", "1_0", "0x1", " 1 ", "a", "1,2",
                     '"3"', "s1", "r1", "r2", "0.3", "17.2", "1e-320"]),
    st.text(max_size=8),
)
META = st.one_of(
    st.sampled_from(["# theta_rad = 0.3", "# theta_deg = 17.2", "# theta_rad = nan",
                     "# theta_rad = 1e308", "# repeat = 2", "# sensor = s", "# synthetic = true",
                     "# design_H_mm = 4", "#", "# just words", "# theta_rad: 0.3"]),
    st.text(max_size=20).map(lambda s: "# " + s),
)


@st.composite
def tables(draw):
    """Lines of a CSV file: metadata, a header, rows of cells. Half of the tables start as a
    valid test (plausible numbers, monotonic displacement) and then receive a few hostile cells
    or metadata lines; the other half mix known and junk columns freely."""
    if draw(st.booleans()):
        header = HEADER.split(",") + draw(st.sampled_from([[], ["repeat"], ["theta_rad"]]))
        n = draw(st.integers(MIN_SAMPLES, 10))
        plausible = st.floats(-5, 5).map(lambda v: f"{v:.4g}")
        rows = [[repr(-0.25 * k), *(draw(plausible) for _ in range(4))] for k in range(n)]
        for cells in rows:
            if "repeat" in header:
                cells.append(draw(st.sampled_from(["1", "2"])))
            elif "theta_rad" in header:
                cells.append("0.3")
        meta = ["# theta_rad = 0.3", f"# repeat = {draw(st.integers(1, 3))}"]
        for _ in range(draw(st.integers(0, 2))):  # a few hostile changes
            if draw(st.booleans()) and rows:
                i, j = draw(st.integers(0, n - 1)), draw(st.integers(0, len(header) - 1))
                rows[i][j] = draw(CELLS)
            else:
                meta[draw(st.integers(0, 1))] = draw(META)
        return meta, header, rows
    header = draw(st.lists(st.sampled_from(COLUMNS), min_size=1, max_size=9))
    n = draw(st.integers(0, 10))
    rows = []
    monotonic = draw(st.booleans())
    for k in range(n):
        cells = [draw(CELLS) for _ in header]
        if monotonic and "u_z_mm" in header:
            cells[header.index("u_z_mm")] = repr(-0.25 * k)
        if "repeat" in header and draw(st.booleans()):
            cells[header.index("repeat")] = str(k % 2)
        rows.append(cells)
    meta = draw(st.lists(META, max_size=4))
    return meta, header, rows


def render(meta, header, rows) -> str:
    lines = list(meta)
    for cells in [header, *rows]:
        buf = []
        writer = csv.writer(_Sink(buf), lineterminator="")
        writer.writerow(cells)
        lines.append("".join(buf))
    return "\n".join(lines) + "\n"


class _Sink:
    def __init__(self, buf):
        self.buf = buf

    def write(self, s):
        self.buf.append(s)


def read_or_refuse(paths):
    """Read ``paths``; return the experiment or None if refused with a DataError."""
    try:
        e = read_experiment(paths)
    except DataError as exc:
        message = str(exc)
        assert "\n" not in message and len(message) <= MAX_MESSAGE + 40, message
        return None
    # the oracle of an accepted experiment: every documented rule holds
    assert len(e.curves) >= 2
    assert 0.0 <= e.theta <= math.pi / 2
    assert len({(c.sensor, c.repeat) for c in e.curves}) == len(e.curves)
    lo, hi, _ = PHYSICAL_RANGE["length"]
    for c in e.curves:
        assert len(c.u_z) >= MIN_SAMPLES
        d = np.diff(c.u_z)
        assert np.all(d > 0) or np.all(d < 0)
        assert np.all(np.isfinite(c.u_z)) and np.all((lo <= c.u_z) & (c.u_z <= hi))
        for r, v in c.values.items():
            vlo, vhi, _ = PHYSICAL_RANGE["T" if r.startswith("B") else "N"]
            assert v.shape == c.u_z.shape and np.all(np.isfinite(v))
            assert np.all((vlo <= v) & (v <= vhi))
    return e


SETTINGS = settings(max_examples=300, deadline=2000, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


@SETTINGS
@given(tables(), tables())
def test_generated_tables_give_a_valid_experiment_or_a_data_error(first, second):
    with tempfile.TemporaryDirectory() as tmp:
        paths = [write(Path(tmp), f"t{k}.csv", render(*table).encode("utf-8"))
                 for k, table in enumerate((first, second))]
        read_or_refuse(paths)


@settings(max_examples=150, deadline=2000, derandomize=True)
@given(st.one_of(st.binary(max_size=300), st.text(max_size=300)))
def test_raw_bytes_give_an_experiment_or_a_data_error(raw):
    with tempfile.TemporaryDirectory() as tmp:
        data = raw if isinstance(raw, bytes) else raw.encode("utf-8", "surrogatepass")
        read_or_refuse([write(Path(tmp), "raw.csv", data)])
