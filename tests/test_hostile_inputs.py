"""What a designer types or hands in: each class refused in one line naming the key or option
and why, on instances of its own.

1. unbounded reads: every file input (``--seed-study`` included) through one size-capped reader of
   regular files;
2. press files checked like validation tables, and a unit fit whose memory grows linearly with
   the presses;
3. options that cannot take effect, and one form of ``--noise-uT``;
4. pairs of settings no physical sensor has; CSV cells with an open quote; numbers given as
   text;
5. unit mistakes, and messages that blame the key the user wrote;
6. ``magtact study`` applies the rules the commands apply.
"""

from __future__ import annotations

import os
import tracemalloc

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from magtact._errors import MagtactError
from magtact._files import UnreadableFile, read_bytes_capped, read_json_capped
from magtact.study import StudyError, check_study, checked_si, load_study, study_from_dict
from magtact.study._units import NEIGHBOURS, PLAUSIBLE, unit_mistake
from magtact.validation import DataError

PRESS_HEADER = "B_x_T,B_y_T,B_z_T,F_x_N,F_y_N,F_z_N"


def study_refused(data, key, *fragments) -> str:
    with pytest.raises(StudyError) as info:
        study_from_dict(data)
    assert info.value.key == key, str(info.value)
    for f in fragments:
        assert f in str(info.value), (f, str(info.value))
    assert "\n" not in str(info.value)
    return str(info.value)


# ---- 1. unbounded reads ------------------------------------------------------------------------
def test_seeds_from_a_device_a_fifo_and_a_large_file_are_refused(tmp_path, refused):
    fifo = tmp_path / "seeds.fifo"
    os.mkfifo(fifo)
    big = tmp_path / "big.json"
    with big.open("wb") as fh:  # sparse: 20 MB claimed, nothing written
        fh.truncate(20_000_000)
    link = tmp_path / "random.json"
    link.symlink_to("/dev/urandom")
    base = ["budget", "--H", "3", "--G", "22.57", "--seed-study"]
    refused([*base, "/dev/urandom"], "--seed-study /dev/urandom: is a device")
    refused([*base, str(fifo)], "is a FIFO")
    refused([*base, str(link)], "is a device")
    refused([*base, str(big)], "has 20,000,000 bytes; at most 10,000,000 are read")


def test_seeds_that_are_not_a_seed_study_are_refused(tmp_path, refused):
    path = tmp_path / "p.json"
    base = ["budget", "--H", "3", "--G", "22.57", "--seed-study", str(path)]
    for text, fragment in [
        ('{"spread": {"jacobian": {"acc_f_r": {"max": NaN}}}}', "NaN is not a JSON number"),
        ('{"spread": {"jacobian": {"acc_f_r": {"max": "0.1"}}}}',
         "spread.jacobian.acc_f_r.max must be a relative error"),
        ('{"spread": {"jacobian": [1, 2]}}', "spread.jacobian must be a table"),
        ('{"spread": {"jacobian": {"acc_f_z": {"max": 0.1, "n": -3}}}}', "count of seeds"),
        ("[" * 100_000, "nests arrays or objects more than 64 deep"),
        ('{"spread": 3}', "not a seed study"),
    ]:
        path.write_text(text, encoding="utf-8")
        refused(base, f"--seed-study {path}", fragment)


def test_study_write_does_not_read_a_large_file_it_would_not_replace(tmp_path, refused,
                                                                     monkeypatch):
    """``magtact study --write FILE`` compares an existing FILE with the study through the
    capped reader: a 5 GB (sparse) file is refused unread."""
    import magtact._files as files

    big = tmp_path / "big.toml"
    with big.open("wb") as fh:
        fh.truncate(5_000_000_000)
    reads = []
    real = files.os.read
    monkeypatch.setattr(files.os, "read", lambda fd, n: reads.append(n) or real(fd, n))
    refused(["study", "--write", str(big)], "the file exists and magtact does not replace it")
    assert not reads


def test_the_capped_reader_reads_at_most_its_cap(tmp_path):
    """A regular file is read whole up to the cap; one byte more is refused, and a device that
    claims size 0 is refused before a byte is read."""
    path = tmp_path / "f"
    path.write_bytes(b"x" * 1000)
    assert read_bytes_capped(path, 1000) == b"x" * 1000
    with pytest.raises(UnreadableFile, match="has 1,000 bytes; at most 999"):
        read_bytes_capped(path, 999)
    with pytest.raises(UnreadableFile, match="is a device"):
        read_bytes_capped("/dev/zero", 10)
    path.write_text('{"a": Infinity}')
    with pytest.raises(UnreadableFile, match="Infinity is not a JSON number"):
        read_json_capped(path, 100)


# ---- 2. press files ----------------------------------------------------------------------------
def _press_file(tmp_path, rows, meta=""):
    path = tmp_path / "presses.csv"
    path.write_text(meta + PRESS_HEADER + "\n" + "\n".join(rows) + "\n", encoding="utf-8")
    return path


@pytest.mark.parametrize(("row", "fragment"), [
    ("0,-3e5,0.03,0,0,1", "column 'B_y_T': -3e5 is outside ±2 T"),
    ("0,0,35,0,0,1", "column 'B_z_T': 35 is outside ±2 T; did you give mT?"),
    ("0,0,0.03,0,0,2500", "column 'F_z_N': 2500 is outside ±1000 N; did you give mN?"),
    ("0,0,0.03,0,0,-1e300", "column 'F_z_N': -1e300 is outside ±1000 N"),
    ('0,0,"0.03,0,0,1', "not a CSV row"),
    ('0,0,"0.03"x,0,0,1', "not a CSV row"),
])
def test_press_cells_are_checked_like_validation_tables(tmp_path, row, fragment):
    from magtact.calibration import read_presses

    path = _press_file(tmp_path, ["0,0,0.03,0,0,0", row])
    with pytest.raises(DataError) as info:
        read_presses(path)
    assert "line 3" in str(info.value) and fragment in str(info.value), str(info.value)


def test_press_noise_metadata_is_bounded(tmp_path):
    from magtact.calibration import read_presses

    path = _press_file(tmp_path, ["0,0,0.03,0,0,0"], "# sigma_B_uT = 1e9\n")
    with pytest.raises(DataError, match=r"line 1: sigma_b_ut = '1e9' must be between 0.001 and "
                                        "10000"):
        read_presses(path)


def test_press_row_limit(tmp_path):
    from magtact.calibration import read_presses
    from magtact.calibration._unit import MAX_PRESSES

    path = _press_file(tmp_path, ["0,0,0.03,0,0,0"] * (MAX_PRESSES + 1))
    with pytest.raises(DataError, match=f"line {MAX_PRESSES + 2}: more than "
                                        f"{MAX_PRESSES:,} presses"):
        read_presses(path)


@pytest.fixture(scope="module")
def smap(models):
    from magtact.calibration import sensor_map
    from magtact.optimise import per_design

    study = load_study(None)
    return sensor_map(models, study, 3e-3, 22.57e3,
                      design=per_design(models, 3e-3, 22.57e3, study))


def _problem(smap, n, seed=0):
    from dataclasses import replace

    from magtact.calibration import Presses, UnitParameters
    from magtact.calibration._unit import _SCALE, DEFAULT_FIT, PARAMETERS, _Problem

    L = smap.region_samples(n, seed=seed)
    unit = replace(smap, field_source="exact")
    B, F = unit.at_load(0.9 * L[:, 0], 0.9 * L[:, 1], L[:, 2])
    free = np.array([p in DEFAULT_FIT for p in PARAMETERS])
    theta0 = UnitParameters().vector()
    prob = _Problem(unit, Presses(B, F), free, theta0)
    w = unit.features(0.9 * L[:, 0], 0.9 * L[:, 1], L[:, 2])
    x = np.concatenate([theta0[free] / _SCALE[free], w.ravel()])
    return prob, x


def test_unit_fit_jacobian_and_deviations_equal_the_dense_reference(smap):
    """The block Jacobian equals column-by-column central differences of the residuals, and
    the deviations from the Schur complement equal sqrt(diag((JᵀJ)⁻¹)) of the dense J."""
    from magtact.calibration._unit import _std

    prob, x = _problem(smap, 7)
    J = prob.jac(x).toarray()
    h = 1e-6 * np.maximum(1.0, np.abs(x))
    dense = np.stack([(prob(x + h[j] * np.eye(x.size)[j]) - prob(x - h[j] * np.eye(x.size)[j]))
                      / (2 * h[j]) for j in range(x.size)], axis=1)
    np.testing.assert_allclose(J, dense, rtol=1e-12, atol=1e-12 * np.abs(dense).max())
    reference = np.sqrt(np.diag(np.linalg.inv(dense.T @ dense))[:prob.k])
    np.testing.assert_allclose(_std(*prob.blocks(x)), reference, rtol=1e-6)


def test_unit_fit_memory_grows_linearly_with_the_presses(smap):
    """3,000 presses: the Jacobian blocks and the deviations within 60 MB (the dense Jacobian
    alone would be 6n × (3n + 5) doubles, 1.3 GB, its perturbation matrix 648 MB)."""
    from magtact.calibration._unit import _std

    prob, x = _problem(smap, 3000, seed=1)
    tracemalloc.start()
    try:
        blocks = prob.blocks(x)
        prob.sparse(*blocks)
        _std(*blocks)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 60e6, peak


def test_presses_of_something_else_are_refused_not_fitted(smap):
    """Readings of no unit of this design (uniform at random; a real unit's readings with the
    chip's x and z columns swapped) leave residuals far above the noise: refused, saying so,
    instead of a calibration."""
    from dataclasses import replace

    from magtact.calibration import Presses, calibrate_unit

    rng = np.random.default_rng(4)
    B, F = rng.uniform(-0.04, 0.04, (12, 3)), rng.uniform(-4.0, 4.0, (12, 3))
    with pytest.raises(MagtactError, match="presses do not fit a unit of this design"):
        calibrate_unit(smap, Presses(B, F))
    L = smap.region_samples(12, seed=5)
    B, F = replace(smap, field_source="exact").at_load(0.9 * L[:, 0], 0.9 * L[:, 1], L[:, 2])
    with pytest.raises(MagtactError, match=r"do not fit a unit of this design: .* times their "
                                           r"noise \(RMS"):
        calibrate_unit(smap, Presses(B[:, ::-1], F))


# ---- 3. options that cannot take effect --------------------------------------------------------
@pytest.mark.parametrize(("args", "fragments"), [
    (["--fit", " , "], ["--fit cannot take effect without --presses"]),
    (["--fit", "B_scale"], ["--fit cannot take effect without --presses"]),
    (["--model-error", "0.02"], ["--model-error cannot take effect without --presses"]),
    (["--noise-uT", "1,2,3"], ["--noise-uT must be 'X,Z' or one number"]),
    (["--noise-uT", "0"], ["--noise-uT must be between"]),
])
def test_calibrate_refuses_options_that_cannot_take_effect(tmp_path, refused, args, fragments):
    refused(["calibrate", "--out", str(tmp_path / "o"), "--H", "3", "--G", "22.57", *args],
            *fragments)
    assert not (tmp_path / "o").exists()


def test_calibrate_fit_names_are_checked_with_presses(tmp_path, refused):
    presses = _press_file(tmp_path, ["0,0,0.03,0,0,0", "0.001,0,0.035,-0.1,0,1"])
    base = ["calibrate", "--out", str(tmp_path / "o"), "--H", "3", "--G", "22.57",
            "--presses", str(presses)]
    refused([*base, "--fit", ","], "--fit names no parameter")
    refused([*base, "--fit", "G_scale,,B_scale"], "--fit: an empty name between commas")
    refused([*base, "--fit", "G_scale,G_scale"], "--fit names 'G_scale' twice")
    refused([*base, "--fit", "stiffness"], "--fit: unknown 'stiffness'")


def test_noise_option_has_one_form_and_says_what_it_replaces(capsys):
    from magtact.budget import noise_given
    from magtact.cli._budget import noise_override, parse_noise
    from magtact.study import hall_chip

    assert parse_noise("2") == pytest.approx((2e-6, 2e-6))
    assert parse_noise(" 1.5 ,2.5") == pytest.approx((1.5e-6, 2.5e-6))
    chip = hall_chip(load_study(None))
    assert chip.noise is not None or chip.picked
    # the API replaces the chip's figure and says so (the budget's noise_source) ...
    replaced, said = noise_given(chip, (3e-6, 4e-6))
    assert replaced.noise == pytest.approx((3e-6, 4e-6))
    assert replaced.name == chip.name and replaced.noise != chip.noise
    assert "in place of the chip's own figure" in said and chip.name in said
    # ... and the commands say on stderr what --noise-uT replaces
    noise_override((3e-6, 4e-6))
    captured = capsys.readouterr()
    err = " ".join(captured.err.split())
    assert "--noise-uT 3, 4 µT" in err and "in place of the chip's own figure" in err
    assert "--noise-uT" not in captured.out


# ---- 4. pairs no sensor has, open quotes, numbers as text --------------------------------------
@pytest.mark.parametrize(("env", "grade", "fragment"), [
    ({"delta_T_K": 100.0, "remanence_tc_pct_per_K": -0.6}, "custom",
     "changes the remanence by -60 %"),
    ({"delta_T_K": 65.0}, "N52", "beyond its working temperature of 80 °C"),
])
def test_temperature_span_and_coefficient_beyond_the_magnet(env, grade, fragment):
    study_refused({"environment": env, "magnet": {"grade": grade}}, "environment.delta_T_K",
                  fragment)


def test_temperature_within_the_grade_is_accepted():
    s = study_from_dict({"environment": {"delta_T_K": 55.0}, "magnet": {"grade": "N52"}})
    assert s.environment.delta_T == 55.0
    # a custom magnet weaker than any NdFeB grade (a ferrite's 0.4 T): its limit is not known
    s = study_from_dict({"environment": {"delta_T_K": 100.0},
                         "magnet": {"M_z_A_per_m": 0.4 / 1.257e-6}})
    assert s.environment.delta_T == 100.0


@settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.floats(1e-3, 200.0), st.floats(-1.0, 1.0))
def test_remanence_change_oracle(delta_T, tc_pct):
    """Refused exactly when |α ΔT| exceeds 50 % or ΔT takes the MagOne magnet (custom, μ0 M_z
    = 1.51 T: sintered NdFeB) beyond the N series' 80 °C from 20 °C, the message naming the
    key."""
    data = {"environment": {"delta_T_K": delta_T, "remanence_tc_pct_per_K": tc_pct}}
    if abs(delta_T * tc_pct / 100) > 0.5:
        study_refused(data, "environment.delta_T_K", "changes the remanence by")
    elif delta_T > 60.0:
        study_refused(data, "environment.delta_T_K", "sintered NdFeB", "at most 60 K")
    else:
        assert study_from_dict(data).environment.delta_T == pytest.approx(delta_T)


def test_validation_cell_with_an_open_quote_is_refused(tmp_path):
    from magtact.validation import read_experiment

    path = tmp_path / "t.csv"
    rows = [f"{-0.1 * k:.2f},0.001,0.04,0.01,-0.5" for k in range(1, 6)]
    rows[2] = '-0.30,0.001,0.04,"0.01,-0.5'
    path.write_text("# theta_rad = 0.3\nu_z_mm,B_r_T,B_z_T,F_r_N,F_z_N\n" + "\n".join(rows)
                    + "\n", encoding="utf-8")
    with pytest.raises(DataError, match=r"t.csv: line 5: not a CSV row \(unexpected end of "
                                        r"data; a quoted cell must close its quote"):
        read_experiment([path])


@pytest.mark.parametrize("value", ["3", b"3", True, None, [3.0], "nan"])
def test_numbers_given_as_anything_but_a_number_are_refused(value):
    with pytest.raises(MagtactError, match=f"G_kPa must be a number, got {value!r}"[:24]):
        checked_si(value, "kPa", "G_kPa")


@pytest.mark.parametrize(("kwargs", "fragment"), [
    ({"H_mm": "3", "G_kPa": 22.57}, "H_mm must be a number, got '3'"),
    ({"H_mm": 3.0, "G_kPa": True}, "G_kPa must be a number, got True"),
    ({"H_mm": 3.0, "G_kPa": 22.57, "M_z_A_per_m": "1.2e6"}, "M_z_A_per_m must be a number"),
    ({"H_mm": 3.0, "G_kPa": 22570.0}, "did you give pascals?"),
])
def test_result_evaluate_refuses_text_and_unit_mistakes(kwargs, fragment):
    """The designer's answer for a design: the numbers are checked before anything else."""
    from dataclasses import fields, replace

    from magtact import Result

    result = replace(Result(**{f.name: None for f in fields(Result)}), study=load_study(None))
    with pytest.raises(MagtactError) as info:
        result.evaluate(**kwargs)
    assert fragment in str(info.value)


def test_numpy_numbers_are_numbers():
    assert checked_si(np.float32(3.0), "mm", "H_mm") == pytest.approx(3e-3)
    assert checked_si(np.int64(22), "kPa", "G_kPa") == 22e3


# ---- 5. unit mistakes and whom a message blames ------------------------------------------------
@pytest.mark.parametrize(("data", "key", "unit"), [
    ({"body": {"R_mm": 0.006}}, "body.R_mm", "did you give metres?"),
    ({"magnet": {"H_m_mm": 800.0}}, "magnet.H_m_mm", "did you give micrometres?"),
    ({"magnet": {"H_m_mm": 2000.0}}, "magnet.H_m_mm", "did you give micrometres?"),
    ({"design": {"G_kPa": [0.01, 0.05]}}, "design.G_kPa", "did you give MPa?"),
    ({"material": {"G_ref_kPa": 18000.0}}, "material.G_ref_kPa", "did you give pascals?"),
    ({"magnet": {"M_z_A_per_m": 1.45}}, "magnet.M_z_A_per_m", "remanence B_r in tesla"),
    ({"magnet": {"M_z_A_per_m": 1450.0}}, "magnet.M_z_A_per_m", "remanence B_r in mT"),
    ({"constraints": {"source": "values", "F_r_c_N": -2500.0}}, "constraints.F_r_c_N",
     "did you give mN?"),
])
def test_unit_mistakes_name_the_key_and_the_likely_unit(data, key, unit):
    study_refused(data, key, unit, "plausible:")


@pytest.mark.parametrize(("args", "fragment"), [
    (["--H", "0.003", "--G", "22.57"], "--H = 0.003: 3 µm is not a dimension"),
    (["--H", "3", "--G", "22570"], "--G = 22570.0: 22.6 MPa is not an elastomer's shear "
                                   "modulus"),
])
def test_command_numbers_in_the_wrong_unit(refused, args, fragment):
    refused(["budget", *args], fragment, "did you give")


@settings(max_examples=80, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.sampled_from(["kPa", "mm", "A_per_m", "N"]), st.floats(0.0, 1.0), st.data())
def test_a_plausible_value_in_a_neighbouring_unit_is_named(unit, where, data):
    """A plausible value given in a neighbouring unit is refused naming that unit whenever the
    written number is implausible in the key's own unit; a plausible value never is."""
    from magtact.study._units import to_si

    _, lo, hi = PLAUSIBLE[unit]
    si = lo * (hi / lo) ** where
    value = si / to_si(1.0, unit)
    assert unit_mistake(unit, value, si) is None
    name, factor = data.draw(st.sampled_from(NEIGHBOURS[unit]))
    written = value / factor
    written_si = to_si(written, unit)
    hint = unit_mistake(unit, written, written_si)
    if lo <= abs(written_si) <= hi:
        assert hint is None
    else:
        assert hint is not None and name in hint


@pytest.mark.parametrize(("data", "key", "fragment"), [
    ({"design": {"H_mm": [10.0, 20.0]}}, "design.H_mm", "design.H_original_mm from the base"),
    ({"body": {"R_mm": 2.0}}, "body.R_mm", "magnet.R_m_mm from the base"),
    ({"magnet": {"H_m_mm": 0.5}}, "magnet.H_m_mm", "mechanics.magnet_edge_radius_mm from"),
])
def test_messages_blame_the_key_the_file_gives(data, key, fragment):
    study_refused(data, key, fragment)


def test_the_key_the_file_gives_itself_is_named_as_before():
    study_refused({"design": {"H_mm": [10.0, 20.0], "H_original_mm": 3.0}},
                  "design.H_original_mm", "lies outside the design range")


# ---- 6. magtact study applies the commands' rules ----------------------------------------------
@pytest.mark.parametrize(("toml", "key", "fragment"), [
    ("[doe]\nn_theta = 4\nn_H = 3\n[metamodel]\nholdout_paths = 3\n",
     "[metamodel.holdout_paths]", "allow at most 2"),
    ("[magnetics]\nfar_z = 2.0\n", "[magnetics.far_z]", "must lie beyond the near zone"),
])
def test_study_check_refuses_what_the_commands_refuse(tmp_path, refused, toml, key, fragment):
    path = tmp_path / "s.toml"
    path.write_text(toml, encoding="utf-8")
    refused(["study", str(path)], key, fragment)
    with pytest.raises(StudyError, match="must lie beyond|allow at most"):
        check_study(load_study(path))


@pytest.mark.parametrize("data", [
    {}, {"magnet": {"placement": "flush"}}, {"hall": {"standoff_mm": 2.5}},
    {"design": {"H_mm": [2.0, 9.0]}, "loading": {"theta_max_rad": 0.2}},
])
def test_near_zone_reach_is_the_field_solvers(data):
    """The reach :func:`check_study` holds near_mm to equals the Hall point's distance from the
    magnet computed by the geometry's loading path, as the field solver measures it."""
    from magtact.geometry import hall_from_magnet_centre, loading_path
    from magtact.study._rules import near_zone_reach

    s = study_from_dict(data)
    T, TH, HH = np.meshgrid(s.t_levels, s.theta_levels, s.H_levels, indexing="ij")
    x, z = hall_from_magnet_centre(s, *loading_path(s, T, TH, HH), HH)
    m = s.magnet
    gap = np.hypot(np.maximum(np.abs(x) - m.R_m, 0.0), np.maximum(np.abs(z) - m.H_m / 2, 0.0))
    assert near_zone_reach(s) == pytest.approx(float(gap.max()), rel=1e-12)
    ok = study_from_dict({**data, "magnetics": {"near_mm": 1e3 * gap.max() * 1.01}})
    check_study(ok)
    short = study_from_dict({**data, "magnetics": {"near_mm": 1e3 * gap.max() * 0.99}})
    with pytest.raises(StudyError, match=r"\[magnetics.near_mm\] the Hall point reaches"):
        check_study(short)


def test_study_check_accepts_the_presets():
    for name in ("magone", "magone-printed"):
        check_study(load_study(name))


def test_run_applies_the_same_rules(tmp_path):
    from magtact import run

    s = load_study(None)
    bad = study_from_dict({"magnetics": {"far_r": 2.0}})
    with pytest.raises(StudyError, match=r"\[magnetics.far_r\]"):
        run(bad, tmp_path / "out")
    assert s.magnetics.far_r * s.magnet.R_m > s.magnet.R_m + s.magnetics.near
    assert not (tmp_path / "out" / "doe").exists()
