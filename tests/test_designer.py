"""The designer's answer: force noise from field noise, the chip's range, the tolerance of G."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from conftest import G_ORIGINAL, H_ORIGINAL
from magtact import Sensor
from magtact.designer import answer, hall_chip
from magtact.sensitivity import dF_dB, force_noise, gamma
from magtact.study import StudyError, load_study, study_from_dict

H0, G0 = H_ORIGINAL, G_ORIGINAL


@pytest.fixture(scope="module")
def study():
    return load_study("magone")


def _hall(study, **kw):
    return replace(study, hall=replace(study.hall, **kw))


def test_isotropic_noise_gives_gamma_times_sigma(models):
    t, th = np.meshgrid(np.linspace(0, 1, 7), np.linspace(0, 0.4, 5), indexing="ij")
    sigma = 3e-6
    s_r, s_z = force_noise(models, t, th, H0, G0, (sigma, sigma))
    g_r, g_z = gamma(models, t, th, H0, G0)
    np.testing.assert_allclose(s_r, g_r * sigma, rtol=1e-12, atol=0)
    np.testing.assert_allclose(s_z, g_z * sigma, rtol=1e-12, atol=0)


def test_force_noise_matches_monte_carlo_through_the_inverse_map(models):
    """10⁵ noisy fields B + δ mapped back to the displacement (p, q) by Newton's method on the
    field models, then to the force: the spread of F equals σ_F of the linear formula."""
    t0, th0 = 0.5, 0.2
    sigma = np.array([20e-6, 35e-6])
    rng = np.random.default_rng(1)
    n = 100_000
    p0, q0 = t0, t0 * np.tan(th0)
    B0 = np.array([models["B_r"].value(t0, th0, H0), models["B_z"].value(t0, th0, H0)])
    target = B0[:, None] + sigma[:, None] * rng.standard_normal((2, n))
    p, q = np.full(n, p0), np.full(n, q0)
    for _ in range(8):  # Newton in the features, where the models are smooth
        t, th = p, np.arctan2(q, p)
        jr, jz = (models[k].jet(t, th, H0, 1) for k in ("B_r", "B_z"))
        res = np.stack([jr[0] - target[0], jz[0] - target[1]])
        J = np.stack([jr[1], jz[1]], axis=-2)  # (n, 2 [B], 2 [p, q])
        step = np.linalg.solve(J, res.T[..., None])[..., 0]
        p, q = p - step[:, 0], q - step[:, 1]
    assert np.max(np.abs(res)) < 1e-12
    F_r, F_z = models.forces(p, np.arctan2(q, p), H0, G0)
    s_r, s_z = force_noise(models, t0, th0, H0, G0, sigma)
    assert np.std(F_r) == pytest.approx(float(s_r), rel=0.02)
    assert np.std(F_z) == pytest.approx(float(s_z), rel=0.02)
    # and a full covariance is taken as such
    cov = np.diag(sigma**2)
    np.testing.assert_allclose(force_noise(models, t0, th0, H0, G0, cov), (s_r, s_z))
    assert dF_dB(models, t0, th0, H0, G0).shape == (2, 2)


def test_tolerant_design_is_the_closed_form(models, study):
    """With δ, the force constraints hold at G (1 − δ): G*_δ = G* / (1 − δ), same H*."""
    from magtact.optimise import as_responses, choose, exact_reduction, force_constraints, sweep

    R = as_responses(models)
    table = sweep(R, study)
    tolerant = replace(study, constraints=replace(study.constraints, G_tolerance=0.1))
    c0, c1 = force_constraints(R, study), force_constraints(R, tolerant)
    assert (c1.F_r_c, c1.F_z_c) == pytest.approx((c0.F_r_c / 0.9, c0.F_z_c / 0.9), rel=1e-15)
    ch0 = choose(R, study, exact_reduction(R, study, c0, table))
    ch1 = choose(R, tolerant, exact_reduction(R, tolerant, c1, table))
    assert ch0.active  # the closed form holds where a force constraint is active
    assert ch1.design.H == ch0.design.H
    assert ch1.design.G == pytest.approx(ch0.design.G / 0.9, rel=1e-9)
    # the softest body of the tolerance band still meets the constraint
    assert 0.9 * ch1.design.F_r_min <= c0.F_r_c + 1e-9 * abs(c0.F_r_c)


def test_resolution_and_range_of_a_design(models, study):
    s = _hall(study, noise_x=1e-6, noise_z=2e-6)
    a = answer(models, s, Sensor.of_study(s, H0, G0), "original")
    r = a.resolution
    J0 = dF_dB(models, 0.0, 0.0, H0, G0)
    assert r.sigma_r_0 == pytest.approx(np.hypot(J0[0, 0] * 1e-6, J0[0, 1] * 2e-6), rel=1e-12)
    assert r.sigma_z_worst >= r.sigma_z_0 and r.sigma_r_worst >= r.sigma_r_0
    t, th = r.where_z
    assert 0 <= t <= a.design.t_m and 0 <= th <= a.design.theta_m
    assert a.design.F_z_max > 0 > a.design.F_r_min


def test_a_strong_field_saturates_the_chip_with_t_and_force_named(models, study):
    from magtact.metamodel import ExactField

    strong = _hall(study, chip="custom", noise_x=1e-6, noise_z=1e-6, range_x=0.08,
                   range_z=0.08)
    a = answer(models, strong, Sensor.of_study(strong, H0, G0))
    s = a.saturation
    assert s.saturates and 0 < s.t < 1 and s.axis == "z"
    bz = abs(float(ExactField(strong, "B_z").value(s.t, s.theta, H0)))
    assert bz > 0.08  # saturated where it says
    assert abs(float(ExactField(strong, "B_z").value(s.t - 1 / 200, s.theta, H0))) <= 0.08
    assert s.F_z == pytest.approx(float(models.forces(s.t, s.theta, H0, G0)[1]))
    wide = _hall(strong, range_x=1.0, range_z=1.0)
    assert not answer(models, wide, Sensor.of_study(wide, H0, G0)).saturation.saturates


def test_card_asks_for_the_noise_the_preset_lacks(models, study):
    from magtact.report import card_rows

    tle = _hall(study, chip="TLE493D")  # the TLE493D's sources state no noise
    a = answer(models, tle, Sensor.of_study(tle, H0, G0), "original")
    assert a.resolution is None and hall_chip(tle).missing == ("hall.noise_x_uT",
                                                               "hall.noise_z_uT")
    header, rows = card_rows([a])
    text = " ".join(" ".join(r) for r in rows)
    assert "give hall.noise_x_uT and hall.noise_z_uT" in text
    assert "None" not in text and "Gamma_" not in text


@pytest.mark.parametrize(("table", "key"), [
    ({"hall": {"noise_x_uT": -1.0}}, "hall.noise_x_uT"),
    ({"hall": {"chip": "HMC5883"}}, "hall.chip"),
    ({"constraints": {"G_tolerance": 0.5}}, "constraints.G_tolerance"),
    ({"constraints": {"G_tolerance": -0.1}}, "constraints.G_tolerance"),
    ({"constraints": {"chip_range": "yes"}}, "constraints.chip_range"),
])
def test_bad_hall_and_tolerance_settings_name_the_key(table, key):
    with pytest.raises(StudyError, match=rf"\[{key}\]"):
        study_from_dict(table)


def test_a_range_below_the_field_at_rest(models, study):
    """Below this design's rest field: saturated at t = 0; below every design's: refused."""
    from magtact.designer import check_rest_field

    low = _hall(study, chip="custom", noise_x=1e-6, noise_z=1e-6, range_x=0.1, range_z=0.03)
    s = answer(models, low, Sensor.of_study(low, H0, G0)).saturation
    assert s.saturates and s.t == 0.0 and s.axis == "z"
    check_rest_field(low)  # the tallest designs still read below 30 mT at rest
    tiny = _hall(low, range_z=1e-3)
    with pytest.raises(StudyError, match=r"\[hall.range_z_mT\] 1 mT is below the field at rest"):
        check_rest_field(tiny)


def test_cli_refuses_a_useless_chip_in_one_line_before_the_work(tmp_path):
    from test_command_outputs import cli  # the command line's entry point, in this process

    study = tmp_path / "s.toml"
    study.write_text("[hall]\nchip = 'custom'\nnoise_x_uT = 1.0\nnoise_z_uT = 1.0\n"
                     "range_x_mT = 0.5\nrange_z_mT = 0.5\n")
    code, text = cli("optimise", study, "--out", tmp_path / "o")
    assert code == 2
    assert "[hall.range_z_mT]" in text and "Traceback" not in text, text
    assert not (tmp_path / "o" / "design.json").exists()


def test_chip_range_as_a_constraint_moves_the_design_to_where_the_chip_reads(models, study):
    """With ``chip_range`` the exact reduction keeps exactly the force-feasible heights whose
    stable region the chip reads, and NSGA-II agrees with it."""
    from magtact.optimise import (
        as_responses,
        chip_margin,
        choose,
        exact_reduction,
        feasible_G,
        force_constraints,
        front_gap,
        pareto_nsga2,
        sweep,
    )

    R = as_responses(models)
    s = replace(study, constraints=replace(study.constraints, chip_range=True),
                optimise=replace(study.optimise, sweep_n=201, population=60,
                                 nsga2_generations=40))
    table = sweep(R, s)
    c = force_constraints(R, s)
    m = chip_margin(s, table.H, table.t_m, table.theta_m)
    low, high = feasible_G(table.f_r_min, table.f_z_max, c, s.design.G)
    red = exact_reduction(R, s, c, table)
    np.testing.assert_array_equal(red.feasible, (low <= high) & (m <= 0))
    assert (m > 0).any() and (m <= 0).any()  # the MLX90393's ±50 mT bites on MagOne
    free = choose(R, study, exact_reduction(R, study, c, table)).design
    bound = choose(R, s, red).design
    assert chip_margin(s, free.H, free.t_m, free.theta_m)[0] > 0 >= chip_margin(
        s, bound.H, bound.t_m, bound.theta_m)[0] - 1e-3
    # the card's saturation scan says the same of the chosen design's stable region
    a = answer(models, s, Sensor.of_study(s, bound.H, bound.G))
    assert not a.saturation.in_region
    assert answer(models, s, Sensor.of_study(s, free.H, free.G)).saturation.in_region
    pareto = pareto_nsga2(R, s, c, table)
    assert front_gap(pareto, red) < 0.01
    assert (np.interp(pareto.H, table.H, m) <= 0).all()


def test_a_chip_that_reads_no_stable_region_is_an_error_naming_the_keys(models, study):
    from magtact.optimise import InfeasibleError, optimise

    s = replace(_hall(study, chip="custom", noise_x=1e-6, noise_z=1e-6, range_x=0.02,
                      range_z=0.02),
                constraints=replace(study.constraints, chip_range=True))
    with pytest.raises(InfeasibleError, match=r"saturates inside the stable region of every "
                                              r"feasible height.*constraints.chip_range"):
        optimise(models, s)


def test_seed_records_hold_the_chosen_designs_force_noise(models, study):
    """Isotropic noise σ: the worst σ_F of a design is its worst Γ times σ."""
    from magtact.optimise import per_design
    from magtact.publication._seeds import _resolution

    sigma = 2e-6
    # the noise of a setting picked per design is not the study's
    assert _resolution(models, study, H0, G0) is None
    rec = _resolution(models, _hall(study, noise_x=sigma, noise_z=sigma), H0, G0)
    d = per_design(models, H0, G0, study)
    assert rec.sigma_Fr_worst == pytest.approx(d.Gamma_r_max * sigma, rel=1e-6)
    assert rec.sigma_Fz_worst == pytest.approx(d.Gamma_z_max * sigma, rel=1e-6)


def test_card_shows_the_seed_spread_of_a_reproduce_run_of_the_same_study(tmp_path, models,
                                                                         study):
    import json

    from magtact.publication import spread
    from magtact.publication._run import _finite
    from magtact.report import read_card, write_card

    sensor = Sensor.of_study(study, H0, G0)
    answers = [answer(models, study, sensor, "chosen"), answer(models, study, sensor, "orig")]
    write_card(answers, tmp_path / "optimise", study=study)
    rows = read_card(tmp_path / "optimise")["rows"]
    assert rows[-1][0] == "seed spread of the answer" and "magtact reproduce" in rows[-1][1]
    records = [{"definition": "jacobian", "seed": k, "ok": True,
                "chosen": {"H_mm": h, "G_kPa": g},
                "original": {"Gamma_r_max": 10.0 + k, "Gamma_z_max": 20.0}}
               for k, (h, g) in enumerate([(3.0, 22.5), (3.2, 24.0), (3.1, 23.0)])]
    pub = tmp_path / "publication"
    pub.mkdir()
    doc = {"study": study.name, "spread": spread(records)}
    # written as Reproduction.write writes it (NaN and inf as null: the reader refuses NaN)
    (pub / "publication.json").write_text(json.dumps(_finite(doc), allow_nan=False))
    text = {r[0]: r[1:] for r in read_card(tmp_path / "optimise")["rows"]}
    assert text["height H over 3 GP seeds (min – max)"] == ["3 – 3.2 mm", "(fixed)"]
    assert text["shear modulus G over 3 GP seeds (min – max)"][0] == "22.5 – 24 kPa"
    assert not any("seed spread of the answer" in k for k in text)
    doc["study"] = "another"  # a seed study of another study is not this answer's spread
    (pub / "publication.json").write_text(json.dumps(_finite(doc), allow_nan=False))
    assert read_card(tmp_path / "optimise")["rows"][-1][0] == "seed spread of the answer"
