"""The error budget: false forces ΔF = J ΔB against independent computations, the neighbours'
superposed field against magpylib, the Monte Carlo against linear propagation, the figure and
the report against the JSON, and bad input."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from conftest import G_ORIGINAL, H_ORIGINAL, spec_hall_field
from magtact.budget import (
    budget_card_rows,
    budget_json,
    error_budget,
    linearised,
    magnets_field,
    monte_carlo,
    neighbour_offsets,
    percentiles,
    responses,
    unit_context,
    worst_false_force,
    write_budgets,
)
from magtact.optimise import per_design
from magtact.sensitivity import dF_dB, gamma
from magtact.study import StudyError, load_study, study_from_dict

H0, G0 = H_ORIGINAL, G_ORIGINAL
NOISE = (1e-6, 1.5e-6)


@pytest.fixture(scope="module")
def study():
    return load_study("magone")


@pytest.fixture(scope="module")
def design(models, study):
    """The original design's extrema (a small GA start: its box is the whole path range)."""
    quick = replace(study, optimise=replace(study.optimise, population=40, ga_generations=4))
    return per_design(models, H0, G0, quick)


@pytest.fixture(scope="module")
def budget(models, study, design):
    return error_budget(models, study, H0, G0, label="original", design=design, noise=NOISE,
                        samples=400)


def _row(budget, start, component):
    rows = [r for r in budget.rows if r.name.startswith(start) and r.component == component]
    assert len(rows) == 1, [r.name for r in budget.rows]
    return rows[0]


# ---- temperature and stray fields: ΔF = J ΔB, computed here without the budget's code ---------


def test_temperature_rows_are_the_jacobian_times_alpha_B_at_rest(models, study, budget):
    env = study.environment
    B = np.array([v[0] for v in spec_hall_field([0.0], [0.0], [H0])])  # magpylib, method.md §1
    J = dF_dB(models, 0.0, 0.0, H0, G0)
    for start, coefficient in (("temperature: magnet remanence", env.remanence_tc),
                               ("temperature: remanence after", env.remanence_tc_tolerance)):
        expected = np.abs(J @ (coefficient * env.delta_T * B))
        got = [_row(budget, start, c).at_rest for c in ("F_r", "F_z")]
        np.testing.assert_allclose(got[1], expected[1], rtol=1e-8)
        assert got[0] == 0.0 and expected[0] < 1e-12 * expected[1]  # B_r = 0, J_rz = 0 at rest
    # about 36 mT × 0.12 %/K × 117 N/T ≈ 5 mN per kelvin at rest
    assert 4e-3 < _row(budget, "temperature: magnet remanence", "F_z").at_rest / 10 < 6e-3


def test_temperature_worst_is_the_largest_on_the_stable_region(models, study, budget, design):
    """A 9 × 9 grid of the stable region (a subset of the budget's 41 × 41), computed here."""
    t, th = (a.ravel() for a in np.meshgrid(np.linspace(0, design.t_m, 9),
                                            np.linspace(0, design.theta_m, 9), indexing="ij"))
    a = study.environment.remanence_tc * study.environment.delta_T
    B = np.stack(spec_hall_field(t, th, H0), axis=-1)
    F = np.abs(np.einsum("nij,nj->ni", dF_dB(models, t, th, H0, G0), a * B)).max(axis=0)
    for k, c in enumerate(("F_r", "F_z")):
        worst = _row(budget, "temperature: magnet remanence", c).worst
        assert F[k] * (1 - 1e-8) <= worst <= 1.1 * F[k]


def test_stray_rows_are_the_largest_J_b_over_directions(models, study, budget, design):
    b = study.environment.earth_field
    phi = np.linspace(0.0, 2 * np.pi, 200_001)
    field = b * np.stack([np.cos(phi), np.sin(phi)])  # every direction in the plane of shear
    J = dF_dB(models, 0.0, 0.0, H0, G0)
    largest = np.abs(J @ field).max(axis=1)
    for k, c in enumerate(("F_r", "F_z")):
        row = _row(budget, "Earth's field, worst", c)
        np.testing.assert_allclose(row.at_rest, largest[k], rtol=1e-8)
        turn = _row(budget, "Earth's field, sensor turned", c)
        assert turn.at_rest == pytest.approx(2 * row.at_rest, rel=1e-12)
    worst = (design.Gamma_r_max, design.Gamma_z_max)
    for k, c in enumerate(("F_r", "F_z")):
        assert _row(budget, "Earth's field, worst", c).worst == pytest.approx(b * worst[k])
    g0 = gamma(models, 0.0, 0.0, H0, G0)
    assert _row(budget, "Earth's field, worst", "F_z").at_rest == pytest.approx(b * float(g0[1]))


def test_noise_row_is_the_designers_resolution(models, study, design, budget):
    from magtact.designer import hall_chip, resolution

    chip = replace(hall_chip(study), noise_x=NOISE[0], noise_z=NOISE[1])
    r = resolution(models, study, design, chip)
    assert _row(budget, "noise", "F_z").worst == r.sigma_z_worst
    assert _row(budget, "noise", "F_r").at_rest == r.sigma_r_0
    assert "given to the budget" in budget.noise_source


# ---- neighbours -------------------------------------------------------------------------------


@pytest.mark.parametrize(("layout", "rings", "count"), [("square", 1, 8), ("square", 2, 24),
                                                         ("hexagonal", 1, 6),
                                                         ("hexagonal", 2, 18)])
def test_neighbour_layouts(layout, rings, count):
    xy = neighbour_offsets(layout, rings, 10e-3)
    assert xy.shape == (count, 2)
    d = np.hypot(*xy.T)
    assert d.min() == pytest.approx(10e-3) and np.sum(np.isclose(d, 10e-3)) == (
        4 if layout == "square" else 6)
    np.testing.assert_allclose(xy.sum(axis=0), 0.0, atol=1e-15)  # symmetric about the taxel


def test_superposed_neighbour_field_equals_magpylibs(study):
    magpy = pytest.importorskip("magpylib")
    from magtact.study import MU0

    m = study.magnet
    rng = np.random.default_rng(7)
    for layout, rings in (("square", 2), ("hexagonal", 1)):
        xy = neighbour_offsets(layout, rings, 12e-3) + rng.uniform(-2e-3, 2e-3, (1, 2))
        centres = np.column_stack([xy, rng.uniform(3e-3, 7e-3, len(xy))])
        ours = magnets_field(study, centres)
        magnets = magpy.Collection(*(magpy.magnet.Cylinder(
            dimension=(2 * m.R_m, m.H_m), polarization=(0, 0, MU0 * m.M_z), position=c)
            for c in centres))
        ref = magnets.getB((0.0, 0.0, 0.0))
        assert np.linalg.norm(ours - ref) <= 1e-9 * np.linalg.norm(ref)


def test_worst_false_force_is_the_largest_over_orientations():
    rng = np.random.default_rng(2)
    J = rng.normal(size=(30, 2, 2))
    dB = rng.normal(size=(200, 3))
    got = worst_false_force(J, dB)
    # brute force: this taxel's shear direction at every angle ψ, both signs of x
    psi = np.linspace(0, 2 * np.pi, 721)
    bx = np.cos(psi)[:, None] * dB[None, :, 0] + np.sin(psi)[:, None] * dB[None, :, 1]
    for k in range(2):
        F = np.abs(J[:, None, None, k, 0] * bx[None]
                   + J[:, None, None, k, 1] * dB[None, None, :, 2])
        assert F.max() <= got[k] * (1 + 1e-12)
        assert F.max() >= got[k] * (1 - 1e-4)


def test_crosstalk_falls_with_pitch_and_the_smallest_pitch_meets_the_resolution(models, study,
                                                                                budget,
                                                                                design):
    from magtact.budget import crosstalk

    J = dF_dB(models, 0.0, 0.0, H0, G0)
    near = crosstalk(study, H0, design.t_m, design.theta_m, J, 12e-3, "square", 1)["worst"]
    far = crosstalk(study, H0, design.t_m, design.theta_m, J, 24e-3, "square", 1)["worst"]
    assert np.all(far < near / 8)  # a dipole's field gradient falls at least as 1/d⁴
    p = budget.array["smallest_pitch"]
    limit = np.array(budget.resolution[2:])
    grid = dF_dB(models, *np.meshgrid(np.linspace(0, design.t_m, 41),
                                      np.linspace(0, design.theta_m, 41), indexing="ij"), H0, G0)
    at = crosstalk(study, H0, design.t_m, design.theta_m, grid, p, "square", 1)["worst"]
    below = crosstalk(study, H0, design.t_m, design.theta_m, grid, 0.99 * p, "square", 1)["worst"]
    assert np.all(at <= limit) and np.any(below > limit)


# ---- fabrication -------------------------------------------------------------------------------


def test_monte_carlo_of_a_linear_response_matches_linear_propagation_and_its_seed():
    a = np.array([0.3, -0.1, 0.05, 0.2])

    def fn(eps):
        return {"y": 2.0 + eps @ a}

    y0, s = linearised(fn, 4)["y"]
    assert y0 == pytest.approx(2.0) and s == pytest.approx(np.linalg.norm(a), rel=1e-9)
    p = percentiles(monte_carlo(fn, 4, 20_000, seed=5))["y"]
    z = 1.6448536269514722  # the 95 % point of the standard normal
    assert p[2] - p[0] == pytest.approx(2 * z * s, rel=0.03)
    assert p[1] == pytest.approx(y0, abs=0.03 * s)
    again = monte_carlo(fn, 4, 20_000, seed=5)["y"]
    np.testing.assert_array_equal(again, monte_carlo(fn, 4, 20_000, seed=5)["y"])
    assert not np.array_equal(again, monte_carlo(fn, 4, 20_000, seed=6)["y"])


def test_fabrication_monte_carlo_matches_linear_propagation_for_small_tolerances(models, study,
                                                                                 design):
    t = study.tolerances
    small = replace(study, tolerances=replace(
        t, G=t.G / 10, remanence=t.remanence / 10, magnet_diameter=t.magnet_diameter / 10,
        magnet_height=t.magnet_height / 10, chip_lateral=t.chip_lateral / 10,
        chip_vertical=t.chip_vertical / 10, magnet_tilt=t.magnet_tilt / 10))
    unit = unit_context(models, small, H0, G0, small.magnet.M_z,
                        (design.F_r_min, design.F_z_max), NOISE)

    def fn(e):
        return responses(unit, e)

    lin = linearised(fn, 9)
    p = percentiles(monte_carlo(fn, 9, 20_000, seed=1))
    z = 1.6448536269514722
    for key in ("Gamma_z_0", "sigma_Fz_0", "F_z_max"):
        y0, s = lin[key]
        assert s > 0
        assert p[key][2] - p[key][0] == pytest.approx(2 * z * s, rel=0.03), key
        assert p[key][1] == pytest.approx(y0, abs=0.03 * s), key
    # the nominal unit is its own calibration: no error, no offset
    zero = responses(unit, np.zeros((1, 9)))
    assert zero["cal_z"][0] < 1e-9 and zero["offset_z"][0] < 1e-12
    assert zero["Gamma_z_0"][0] == pytest.approx(1.0, rel=1e-12)


# ---- files, card, figure, report -------------------------------------------------------------


def test_budget_json_has_units_in_keys_and_the_card_names_the_largest_rows(budget):
    doc = budget_json(budget)
    json.dumps(doc)  # plain JSON
    assert {"at_rest_mN", "worst_mN", "assumptions"} <= set(doc["rows"][0])
    assert doc["H_mm"] == pytest.approx(3.0) and doc["G_kPa"] == pytest.approx(29.4)
    largest = max(r["worst_mN"] for r in doc["rows"])
    rows = budget_card_rows([budget])
    assert (f"{largest:.3g} mN worst" in rows[0][1] if largest < 1e3
            else f"{largest / 1e3:.3g} N worst" in rows[0][1])
    assert any("smallest square array pitch" in r[0] for r in rows)


def test_figure_shows_the_rows_of_the_json(budget):
    from magtact.report import budget_labels, draw_budget

    entry = budget_json(budget)
    fig = draw_budget(entry)
    ax_r, ax_z = fig.axes[:2]
    names = budget_labels(entry)
    assert [t.get_text() for t in ax_r.get_yticklabels()] == names
    assert ax_z.get_xscale() == "log"
    for ax, comp in ((ax_r, "F_r"), (ax_z, "F_z")):
        for key in ("worst_mN", "at_rest_mN"):
            bars = [p for p in ax.patches if p.get_gid() == f"{comp}:{key}"]
            expected = [(names.index(r["name"]), r[key]) for r in entry["rows"]
                        if r["component"] == comp and r[key] and r[key] > 0]
            assert [b.get_width() for b in bars] == pytest.approx([v for _, v in expected])
            centre = [b.get_y() + b.get_height() / 2 for b in bars]
            assert [round(c) for c in centre] == [i for i, _ in expected]
        lines = [ln.get_xdata()[0] for ln in ax.lines]
        assert lines == pytest.approx([entry["resolution_mN"][f"{comp}_worst"]])


def test_report_shows_the_budget_section(tmp_path, budget, study):
    from magtact._display import sig
    from magtact.report import build_report, draw_budget, save

    def png_only(doc, folder):
        save(draw_budget(doc["budgets"][0]), folder / "budget_original", formats=("png",))

    write_budgets([budget], study, tmp_path / "budget", figures=png_only)
    html = build_report(tmp_path).read_text(encoding="utf-8")
    assert '<h2 id="budget">Error budget</h2>' in html
    doc = json.loads((tmp_path / "budget" / "budget.json").read_text(encoding="utf-8"))
    row = doc["budgets"][0]["rows"][2]
    assert f"<td>{sig(row['worst_mN'])}</td>" in html
    assert "Error budget of the original design" in html and "data:image/png" in html
    sp = doc["budgets"][0]["array"]["smallest_pitch_mm"]
    assert f"<b>{sig(sp)} mm</b>" in html
    # in a run's folder: shown only if it names the run
    (tmp_path / "run.json").write_text('{"run_id": "abc", "stages": []}', encoding="utf-8")
    assert "is not of this run" in build_report(tmp_path).read_text(encoding="utf-8")
    doc["run_id"] = "abc"
    (tmp_path / "budget" / "budget.json").write_text(json.dumps(doc), encoding="utf-8")
    html = build_report(tmp_path).read_text(encoding="utf-8")
    assert "is not of this run" not in html and f"<td>{sig(row['worst_mN'])}</td>" in html
    (tmp_path / "budget" / "budget.json").unlink()
    assert "No error budget in this folder" in build_report(tmp_path).read_text(encoding="utf-8")


def test_no_noise_figure_leaves_the_noise_row_and_the_pitch_out(models, study, design):
    b = error_budget(models, study, H0, G0, design=design, samples=100)
    assert not any(r.group == "noise" for r in b.rows)
    assert b.array["smallest_pitch"] is None and "hall.noise_x_uT" in b.noise_source
    assert math.isfinite(_row(b, "neighbours", "F_z").worst)


# ---- bad input ---------------------------------------------------------------------------------


@pytest.mark.parametrize(("table", "key", "message"), [
    ({"tolerances": {"G_pct": -1.0}}, "tolerances.G_pct", "must be at least 0"),
    ({"tolerances": {"chip_lateral_mm": -0.1}}, "tolerances.chip_lateral_mm",
     "must be at least 0"),
    ({"tolerances": {"magnet_tilt_deg": -2}}, "tolerances.magnet_tilt_deg", "at least 0"),
    ({"environment": {"remanence_tc_tolerance_pct_per_K": -0.01}},
     "environment.remanence_tc_tolerance_pct_per_K", "at least 0"),
    ({"environment": {"earth_field_uT": -50}}, "environment.earth_field_uT", "at least 0"),
    ({"array": {"pitch_mm": 8.0}}, "array.pitch_mm", "smaller than the body"),
    ({"array": {"layout": "triangular"}}, "array.layout", "'square', 'hexagonal'"),
    ({"array": {"rings": 0}}, "array.rings", "at least 1"),
    ({"array": {"spacing_mm": 20}}, "array.spacing_mm", "unknown key"),
])
def test_bad_budget_settings_name_the_key(table, key, message):
    with pytest.raises(StudyError, match=rf"\[{key}\]") as exc:
        study_from_dict(table)
    assert message in str(exc.value)


def test_a_study_over_geometry_is_refused_by_name(models, study):
    from magtact import MagtactError

    geo = study_from_dict({"design": {"R_m_mm": [2.4, 2.5]}, "doe": {"n_R_m": 2},
                           "metamodel": {"b_model": "exact"}})
    with pytest.raises(MagtactError, match="fix the geometric design variables"):
        error_budget(models, geo, H0, G0)


def test_a_pitch_equal_to_the_body_is_accepted():
    assert study_from_dict({"array": {"pitch_mm": 12.0, "layout": "hexagonal"}}).array.pitch \
        == pytest.approx(12e-3)


@pytest.mark.parametrize(("args", "message"), [
    (["--noise-uT", "a,b"], "--noise-uT must be 'X,Z'"),
    (["--noise-uT", "1,2,3"], "--noise-uT must be 'X,Z'"),
    (["--noise-uT", "-1"], "--noise-uT must be between"),
    (["--H", "-3"], "--H must be between"),
])
def test_budget_command_refuses_bad_options_in_one_line(monkeypatch, capsys, args, message):
    from magtact.cli import main

    argv = ["magtact", "budget", "--H", "3", "--G", "29.4", *args]
    monkeypatch.setattr("sys.argv", argv)
    with pytest.raises(SystemExit) as exc:
        main()
    err = capsys.readouterr().err
    assert exc.value.code == 2 and message in " ".join(err.split())
    assert "Traceback" not in err


def test_budget_command_refuses_a_file_that_is_no_seed_study(tmp_path, monkeypatch, capsys):
    from magtact.cli import main

    bad = tmp_path / "seeds.json"
    bad.write_text('{"seeds": [1, 2]}', encoding="utf-8")
    monkeypatch.setattr("sys.argv", ["magtact", "budget", "--H", "3", "--G", "29.4", "--seed-study",
                                     str(bad)])
    with pytest.raises(SystemExit) as exc:
        main()
    assert exc.value.code == 2
    assert "not a seed study" in " ".join(capsys.readouterr().err.split())
