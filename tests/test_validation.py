"""Validation stage: statistics, ε, filter, model interface, shipped SYNTHETIC data."""

from __future__ import annotations

import math

import numpy as np
import pytest

from magtact.validation import (
    RESPONSES,
    DataError,
    FilterSettings,
    PathModel,
    bandpass,
    excluded_ranges,
    read_experiment,
    synthetic_files,
    validate,
)

HEADER = "u_z_mm,B_r_T,B_z_T,F_r_N,F_z_N"


def write(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def tiny(tmp_path):
    """Three repeats on the same 4-point grid (u_z = 0, −1, −2, −3 mm), θ = 0.2 rad."""
    # B_r is zero at the first point: its c_v and ε exclude that point.
    data = {
        "a": [(0, 0.0, 1.0, 1.0, -1.0), (-1, 1.0, 2.0, 2.0, -2.0), (-2, 2.0, 3.0, 3.0, -3.0),
              (-3, 3.0, 4.0, 4.0, -4.0)],
        "b": [(0, 0.0, 2.0, 1.0, -1.0), (-1, 2.0, 2.0, 2.0, -2.0), (-2, 2.0, 3.0, 3.0, -3.0),
              (-3, 3.0, 4.0, 4.0, -4.0)],
        "c": [(0, 0.0, 3.0, 1.0, -1.0), (-1, 3.0, 2.0, 2.0, -2.0), (-2, 2.0, 3.0, 3.0, -3.0),
              (-3, 3.0, 4.0, 4.0, -4.0)],
    }
    paths = []
    for k, (name, rows) in enumerate(data.items()):
        text = f"# theta_rad = 0.2\n# sensor = {name}\n# repeat = {k}\n{HEADER}\n"
        text += "".join(",".join(str(v) for v in row) + "\n" for row in rows)
        paths.append(write(tmp_path, f"{name}.csv", text))
    return paths


def model_tiny():
    # model: B_r = −u_z [mm], B_z = 2.5, F_r = −u_z + 1 (mm), F_z = 2 u_z − 1 (mm)
    return PathModel(lambda u: {"B_r": -u * 1e3, "B_z": np.full_like(u, 2.5),
                                "F_r": 1.0 - u * 1e3, "F_z": 2e3 * u - 1.0}, theta=0.2)


def test_statistics_and_eps_against_hand_computed_values(tmp_path):
    exp = read_experiment(tiny(tmp_path))
    v = validate(exp, model_tiny(), filter=FilterSettings(f_hi=None), n_grid=4, floor=0.05)
    assert np.allclose(v.u_z, [0.0, -1e-3, -2e-3, -3e-3])
    assert np.allclose(v.u_r, [0.0, 1e-3 * math.tan(0.2), 2e-3 * math.tan(0.2),
                               3e-3 * math.tan(0.2)])
    # B_r: values (0,0,0), (1,2,3), (2,2,2), (3,3,3): mean 0, 2, 2, 3; std (1/N) 0, sqrt(2/3), 0, 0
    s = v.stats["B_r"]
    assert np.allclose(s.mean, [0.0, 2.0, 2.0, 3.0])
    assert np.allclose(s.std, [0.0, math.sqrt(2.0 / 3.0), 0.0, 0.0])
    # c_v = max |σ/μ| without the point where μ = 0: sqrt(2/3)/2 at u_z = −1 mm
    assert s.c_v == pytest.approx(100 * math.sqrt(2.0 / 3.0) / 2.0)
    assert s.c_v_at == pytest.approx(-1e-3)
    assert s.cv_excluded.tolist() == [True, False, False, False]
    # ε against model (0, 1, 2, 3): point 0 excluded; |2−1|/1 = 100 % at −1 mm
    assert s.eps == pytest.approx(100.0)
    assert s.eps_at == pytest.approx(-1e-3)
    assert s.eps_excluded.tolist() == [True, False, False, False]
    # B_z: mean (2, 2, 3, 4), std (sqrt(2/3), 0, 0, 0); model 2.5 → ε = max(0.5, 0.5, 0.5, 1.5)/2.5
    s = v.stats["B_z"]
    assert s.c_v == pytest.approx(100 * math.sqrt(2.0 / 3.0) / 2.0)
    assert s.eps == pytest.approx(100 * 1.5 / 2.5)
    assert s.eps_at == pytest.approx(-3e-3)
    assert not s.eps_excluded.any()
    # F_r identical repeats (1, 2, 3, 4): c_v = 0; model (1, 2, 3, 4) → ε = 0
    assert v.stats["F_r"].c_v == 0.0 and v.stats["F_r"].eps == pytest.approx(0.0, abs=1e-12)
    # F_z (−1, −2, −3, −4) against model (−1, −3, −5, −7): ε = max(0, 1/3, 2/5, 3/7)
    assert v.stats["F_z"].eps == pytest.approx(100 * 3 / 7)
    rows = v.rows()
    assert [r["response"] for r in rows] == list(RESPONSES)
    assert rows[0]["c_v_excluded"].startswith("1 pts")


def test_vanishing_denominator_everywhere_gives_nan_and_says_so(tmp_path):
    exp = read_experiment(tiny(tmp_path))
    zero = PathModel(lambda u: {"B_r": 0 * u, "B_z": 0 * u + 1, "F_r": 0 * u + 1,
                                "F_z": 0 * u + 1}, theta=0.2)
    v = validate(exp, zero, filter=FilterSettings(f_hi=None), n_grid=4)
    assert math.isnan(v.stats["B_r"].eps) and v.stats["B_r"].eps_excluded.all()
    assert v.rows()[0]["eps_excluded"] == "all points (denominator vanishes)"
    # the summary file writes the ε that is not a number as null and reads back as its record
    import json

    from magtact._records import from_json
    from magtact.validation._outputs import ValidationSummary, write_outputs

    path = next(f for f in write_outputs(v, tmp_path / "out") if f.suffix == ".json")
    doc = json.loads(path.read_text(encoding="utf-8"))
    assert doc["rows"][0]["eps_percent"] is None and doc["filter_cycles_per_mm"][1] is None
    back = from_json(ValidationSummary, doc, path.name)
    assert math.isnan(back.rows[0].eps) and back.theta == v.theta
    assert back.rows[1].c_v_at_u_z == pytest.approx(v.stats["B_z"].c_v_at, rel=1e-15)


def test_filter_removes_high_frequency_sinusoid_and_keeps_slow_ramp():
    u = np.linspace(0.0, -4e-3, 401)  # 4 mm, spacing 10 µm
    dx = u[1] - u[0]
    ramp = 0.05 + 30.0 * (-u) + 2e3 * u ** 2  # slow, curved ramp: 0.05 → 0.202
    slow = 0.01 * np.sin(2 * np.pi * 250.0 * u + 0.3)  # 0.25 cycles/mm: must be kept
    fast = 0.02 * np.sin(2 * np.pi * 20000.0 * u + 0.7)  # 20 cycles/mm: must be removed
    err = bandpass(ramp + slow + fast, dx, FilterSettings(f_hi=2000.0)) - (ramp + slow)
    inner = slice(50, -50)  # beyond 0.5 mm (one cut-off wavelength) from either end
    assert np.max(np.abs(err[inner])) < 0.01 * 0.02  # fast sinusoid removed to < 1 %
    assert np.sqrt(np.mean(err ** 2)) < 0.02 * 0.02  # < 2 % rms over the whole curve
    assert np.max(np.abs(err)) < 0.15 * 0.02  # < 15 % even at the ends
    # the ramp alone is kept: exactly if straight, to 0.1 % of its smallest value if curved
    line = 0.05 + 30.0 * (-u)
    assert np.max(np.abs(bandpass(line, dx, FilterSettings()) - line)) < 1e-12
    assert np.max(np.abs(bandpass(ramp, dx, FilterSettings()) - ramp)) < 1e-3 * 0.05
    # a high-pass above the slow content removes ramp and slow sinusoid, keeps the fast one
    hp = bandpass(line + slow + fast, dx, FilterSettings(f_lo=5000.0, f_hi=None))
    assert np.max(np.abs(hp - fast)[inner]) < 0.05 * 0.02
    # no cut-off at all: the identity
    y = ramp + fast
    assert np.array_equal(bandpass(y, dx, FilterSettings(f_hi=None)), y)


def test_filter_settings_are_checked():
    with pytest.raises(ValueError, match="f_lo must be >= 0"):
        FilterSettings(f_lo=-1.0)
    with pytest.raises(ValueError, match="must exceed f_lo"):
        FilterSettings(f_lo=10.0, f_hi=5.0)


def test_noisy_repeats_of_a_model_recover_it(tmp_path):
    """8 repeats = model + independent noise: the filtered mean is within the noise of the model."""
    theta = 0.3
    rng = np.random.default_rng(1)
    model = PathModel(lambda u: {"B_r": -2.0 * u, "B_z": 0.04 + 20.0 * u ** 2,
                                 "F_r": 100.0 * u * (u + 2e-3), "F_z": 2000.0 * u},
                      theta=theta, u_z_range=(-3e-3, 0.0))
    u = np.linspace(0.0, -3e-3, 301)
    paths = []
    for k in range(8):
        clean = model(u)
        lines = [f"# theta_rad = {theta}", "sensor,repeat," + HEADER]
        noisy = {r: clean[r] + 1e-3 * np.abs(clean[r]).max() * rng.standard_normal(u.size)
                 for r in RESPONSES}
        lines += [f"S{k % 4},{k // 4},{u[i] * 1e3}," + ",".join(str(noisy[r][i]) for r in
                                                                  RESPONSES)
                  for i in range(u.size)]
        paths.append(write(tmp_path, f"t{k}.csv", "\n".join(lines)))
    v = validate(read_experiment(paths), model)
    assert v.n_tests == 8 and v.sensors == ("S0", "S1", "S2", "S3")
    for r in RESPONSES:
        s = v.stats[r]
        scale = np.abs(s.model).max()
        assert np.max(np.abs(s.mean - s.model)) < 2e-3 * scale, r


def test_model_at_another_shear_angle_is_refused(tmp_path):
    exp = read_experiment(tiny(tmp_path))
    other = PathModel(model_tiny().fn, theta=0.4)
    with pytest.raises(ValueError, match="model is at theta = 0.4"):
        validate(exp, other)


def test_grid_is_clipped_to_the_model_range_and_noted(tmp_path):
    exp = read_experiment(tiny(tmp_path))
    m = PathModel(model_tiny().fn, theta=0.2, u_z_range=(-2e-3, 0.0))
    v = validate(exp, m, filter=FilterSettings(f_hi=None), n_grid=3)
    assert np.allclose(v.u_z, [0.0, -1e-3, -2e-3])
    assert "clipped" in v.notes[0]


def test_from_samples_interpolates_a_cubic_exactly():
    u = np.linspace(-4e-3, 0.0, 9)
    cubic = {r: (k + 1) * 1e6 * u ** 3 + u for k, r in enumerate(RESPONSES)}
    m = PathModel.from_samples(u, cubic, theta=0.1)
    x = np.array([-3.3e-3, -0.7e-3])
    out = m(x)
    for k, r in enumerate(RESPONSES):
        assert np.allclose(out[r], (k + 1) * 1e6 * x ** 3 + x, rtol=1e-10, atol=1e-15)
    assert m.u_z_range == (-4e-3, 0.0)


def test_from_metamodels_maps_u_z_to_t_and_scales_forces_by_G():
    sympy = pytest.importorskip("sympy")
    from magtact.geometry import loading_path
    from magtact.metamodel import ModelSet
    from magtact.study import load_study

    study = load_study(None)
    t, th, H = sympy.symbols("t theta H")
    models = ModelSet.from_exprs({"B_r": t * th, "B_z": 1 + t, "f_r": -t * 1e-6,
                                  "f_z": -(t ** 2) * H})
    Hd, G, theta = 4e-3, 20e3, 0.3
    pm = PathModel.from_metamodels(models, study, Hd, G, theta)
    tt = np.array([0.0, 0.25, 1.0])
    u_z = loading_path(study, tt, theta, Hd)[1]
    out = pm(u_z)
    assert np.allclose(out["B_r"], tt * theta)
    assert np.allclose(out["B_z"], 1 + tt)
    assert np.allclose(out["F_r"], -tt * 1e-6 * G)
    assert np.allclose(out["F_z"], -(tt ** 2) * Hd * G)


def test_excluded_ranges_are_contiguous_runs():
    u = np.arange(6.0)
    mask = np.array([True, True, False, True, False, True])
    assert excluded_ranges(u, mask) == [(0.0, 1.0), (3.0, 3.0), (5.0, 5.0)]


def test_shipped_synthetic_data_is_labelled_and_readable():
    files = synthetic_files()
    assert len(files) == 8
    assert all(f.name.startswith("synthetic_") for f in files)
    exp = read_experiment(files)
    assert exp.synthetic and len(exp.sensors) == 4 and len(exp.curves) == 8
    assert exp.metadata["design_h_mm"] == "4.1" and exp.metadata["design_g_kpa"] == "29.4"
    assert exp.theta == pytest.approx(math.atan(0.45), abs=1e-9)
    model = PathModel.from_samples(
        np.linspace(-5e-3, 1e-3, 7), {r: np.ones(7) for r in RESPONSES}, theta=exp.theta,
        label="constant")
    v = validate(exp, model)
    assert "SYNTHETIC" in v.title
    assert all(row["data"] == "synthetic" for row in v.rows())


def test_read_long_table_groups_sensor_and_repeat(tmp_path):
    rows = [f"S{s},{r},{-k * 0.5},0,{k},{k},{-k},0.1" for s in (1, 2) for r in (1, 2)
            for k in range(5)]
    path = write(tmp_path, "long.csv", "sensor,repeat,u_z_mm,B_r_T,B_z_T,F_r_N,F_z_N,theta_deg\n"
                 + "\n".join(rows))
    exp = read_experiment(path)
    assert [(c.sensor, c.repeat) for c in exp.curves] == [("S1", "1"), ("S1", "2"),
                                                          ("S2", "1"), ("S2", "2")]
    assert exp.theta == pytest.approx(math.radians(0.1))
    assert np.allclose(exp.curves[0].u_z, [0, -0.5e-3, -1e-3, -1.5e-3, -2e-3])
    assert exp.curves[0].line == 2 and exp.curves[1].line == 7
    assert not exp.synthetic


def test_duplicate_test_across_files_names_both(tmp_path):
    text = f"# theta_rad = 0.2\n# sensor = A\n{HEADER}\n" + "".join(
        f"{-k},0,1,1,1\n" for k in range(4))
    a, b = write(tmp_path, "a.csv", text), write(tmp_path, "b.csv", text)
    with pytest.raises(DataError, match=r"b\.csv: line 4, columns 'sensor', 'repeat'.*a\.csv"):
        read_experiment([a, b])


def test_validate_command_with_metamodels_recovers_exact_data(tmp_path):
    """Data made from known metamodels, validated against the same metamodels: ε ≈ 0."""
    from typer.testing import CliRunner

    from magtact.cli._app import app
    from magtact.metamodel import H as Hs
    from magtact.metamodel import ModelSet, save_models, t, theta
    from magtact.study import load_study

    models = ModelSet.from_exprs({"B_r": 0.02 * t * theta, "B_z": 0.04 + 0.1 * t ** 2,
                                  "f_r": -1e-6 * t * theta * (1 - t), "f_z": 3e-4 * t * Hs})
    save_models(models, tmp_path / "models")
    study = load_study(None)
    H, G, th = 4e-3, 20e3, 0.3
    pm = PathModel.from_metamodels(models, study, H, G, th)
    u = np.linspace(0.0, pm.u_z_range[0], 81)
    paths = []
    for k in range(3):
        vals = pm(u)
        lines = [f"# theta_rad = {th}", f"# repeat = {k}", HEADER]
        lines += [f"{float(u[i]) * 1e3!r}," + ",".join(repr(float(vals[r][i])) for r in RESPONSES)
                  for i in range(u.size)]
        paths.append(write(tmp_path, f"r{k}.csv", "\n".join(lines)))
    out = tmp_path / "out"
    result = CliRunner().invoke(app, ["validate", *map(str, paths), "--H", "4", "--G", "20",
                                      "--models", str(tmp_path / "models"), "--out", str(out),
                                      "--f-hi", "0", "--n-grid", "81"])  # grid = the samples
    assert result.exit_code == 0, result.output
    import csv

    rows = list(csv.DictReader((out / "validation.csv").open()))
    assert [r["response"] for r in rows] == list(RESPONSES)
    for r in rows:
        assert float(r["c_v_percent"]) < 1e-9 and float(r["eps_percent"]) < 1e-6, r
        assert r["data"] == "experiment"
    assert (out / "validation.png").is_file() and (out / "validation.svg").is_file()
    assert "c_v" in result.output


def test_validate_command_without_design_names_the_option(tmp_path):
    from typer.testing import CliRunner

    from magtact.cli._app import app

    paths = tiny(tmp_path)
    result = CliRunner().invoke(app, ["validate", *map(str, paths), "--out", str(tmp_path)])
    assert result.exit_code != 0
    assert "--H" in str(result.exception)


def test_study_and_data_arguments_are_told_apart():
    from pathlib import Path

    from magtact.cli._validate import split_study_and_data

    assert split_study_and_data(["magone", "a.csv"]) == ("magone", [Path("a.csv")])
    assert split_study_and_data(["my.TOML", "a.csv", "b.csv"]) == ("my.TOML", [Path("a.csv"),
                                                                             Path("b.csv")])
    assert split_study_and_data(["a.csv"]) == (None, [Path("a.csv")])
    assert split_study_and_data([]) == (None, [])


def test_the_synthetic_example_simulates_the_fabricated_sensor():
    from magtact.publication import reference
    from magtact.validation import SYNTHETIC_H

    assert SYNTHETIC_H == reference.H_FABRICATED == pytest.approx(4.1e-3, rel=1e-12)
