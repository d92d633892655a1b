"""Parts a designer can buy: the Hall chip's settings against the datasheet's own relations,
the chip setting as a design choice, magnets and silicones, and bad input."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import G_ORIGINAL, H_ORIGINAL
from magtact.parts import GRADES, SILICONES, ChipSetting, SettingError, chip_table
from magtact.study import MU0, StudyError, load_study, study_from_dict

H0, G0 = H_ORIGINAL, G_ORIGINAL
MLX = chip_table("MLX90393")


@pytest.fixture(scope="module")
def study():
    return load_study("magone")


def _hall(study, **kw):
    return replace(study, hall=replace(study.hall, **kw))


def _rate(study, rate: float):
    return replace(study, requirements=replace(study.requirements, rate=rate))


# ---- the MLX90393's tables against the datasheet's own relations --------------------------------
def test_each_res_step_doubles_the_lsb():
    """Table 17: RES r + 1 has twice the µT/LSB of RES r (3 decimals as printed)."""
    for table in ("xy_uT_per_LSB", "z_uT_per_LSB"):
        s = np.array(MLX.data["sensitivity"][table])
        assert s.shape == (8, 4)
        np.testing.assert_allclose(s[:, 1:], 2 * s[:, :-1], atol=1.5e-3, rtol=0)
        assert (np.diff(s[:, 0]) < 0).all()  # a higher gain, a finer LSB
    # the one cell printed otherwise, and Table 18 (35 °C) keeping the doubling there
    assert MLX.data["sensitivity"]["printed_differently"] == [["xy", 1, 3, 4.840, 4.806]]
    assert 5.034 == pytest.approx(2 * 2.517, abs=1e-12)


def test_range_is_the_output_limit_times_the_lsb_below_the_saturation_onset():
    f = MLX.figures(ChipSetting(7, 0, 0, 2))
    assert f.range_x == pytest.approx(2**15 * 0.150e-6, rel=1e-12)  # ±4.9 mT
    assert f.range_z == pytest.approx(2**15 * 0.242e-6, rel=1e-12)  # ±7.9 mT
    assert f.range_x >= 4.8e-3  # Table 9, note 8: the highest gain reads at least ±4.8 mT
    f = MLX.figures(ChipSetting(0, 3, 3, 7))  # 11000 LSB × 6.009 µT = 66 mT > B_SAT
    assert (f.range_x, f.range_z) == (50e-3, 50e-3)
    f = MLX.figures(ChipSetting(2, 2, 1, 4))
    assert f.range_x == pytest.approx(22000 * 1.803e-6) and f.range_z == 50e-3


def test_conversion_time_formula_against_table_19():
    """Table 19 (TXYZ, OSR2 = 0) is three axes of T = 67 + 64·2^OSR·(2 + 2^DIG_FILT) µs, the
    temperature conversion 67 + 192 µs and one constant overhead, to its printed 0.01 ms."""
    t19 = np.array(MLX.data["conversion"]["T_txyz_ms"]) * 1e-3
    axis = np.array([[MLX.axis_time(o, d) for o in range(4)] for d in range(8)])
    assert MLX.axis_time(0, 0) == pytest.approx(259e-6) and MLX.axis_time(3, 7) == pytest.approx(
        66627e-6)  # Table 8's minimum and maximum
    overhead = t19 - 3 * axis - 259e-6
    assert np.ptp(overhead) <= 0.011e-3
    assert 0 < overhead.mean() < 0.5e-3


def test_noise_interval_contains_the_gain7_figure_and_collapses_at_gain_7():
    for s in MLX.settings():
        n7 = MLX.gain7_noise(s.osr, s.dig_filt)
        if np.isnan(n7[0]):
            continue
        f = MLX.figures(s)
        for (lo, hi), n, lsb, (slo, shi) in ((f.noise_x, n7[0], f.lsb_x, f.sigma_x),
                                              (f.noise_z, n7[1], f.lsb_z, f.sigma_z)):
            assert lo <= n <= hi
            assert (lo == hi == n) if s.gain_sel == 7 else lo < hi
            assert slo == pytest.approx(math.sqrt(lo**2 + lsb**2 / 12), rel=1e-12)
            assert shi == pytest.approx(math.sqrt(hi**2 + lsb**2 / 12), rel=1e-12)
        assert f.interval == (s.gain_sel != 7)
    assert MLX.gain7_noise(0, 0) == pytest.approx((5.08e-6, 7.68e-6))  # the plot's first point


def test_a_setting_that_is_not_permitted_is_refused():
    with pytest.raises(SettingError, match=r"\[dig_filt\] OSR 0 with DIG_FILT 1 is not permitted"):
        MLX.figures(ChipSetting(7, 0, 0, 1))
    assert len(list(MLX.settings())) == 8 * 4 * (32 - 3)
    with pytest.raises(StudyError, match=r"\[hall.dig_filt\] OSR 1 with DIG_FILT 0 is not "
                                         r"permitted with HALLCONF = 0xC"):
        study_from_dict({"hall": {"osr": 1, "dig_filt": 0}})


# ---- σ_F with the setting's noise --------------------------------------------------------------
@pytest.fixture(scope="module")
def fast_answer(models, study):
    """The original design's answer at GAIN_SEL 7, RES 0, OSR 0, DIG_FILT 2."""
    from magtact import Sensor
    from magtact.designer import answer

    fast = _hall(study, gain_sel=7, res=0, osr=0, dig_filt=2)
    return answer(models, fast, Sensor.of_study(fast, H0, G0), "original")


def test_force_noise_is_J_sigma_J_with_the_settings_noise_and_quantisation(models, fast_answer):
    from magtact.report import card_rows
    from magtact.sensitivity import dF_dB

    a = fast_answer
    # datasheet figures typed here: Fig. 2/3 at OSR 0, DIG_FILT 2; Table 17 GAIN_SEL 7, RES 0
    sx = math.hypot(3.04e-6, 0.150e-6 / math.sqrt(12))
    sz = math.hypot(4.63e-6, 0.242e-6 / math.sqrt(12))
    J = dF_dB(models, 0.0, 0.0, H0, G0)
    assert a.resolution.sigma_r_0 == pytest.approx(math.hypot(J[0, 0] * sx, J[0, 1] * sz),
                                                   rel=1e-12)
    assert a.resolution.sigma_z_0 == pytest.approx(math.hypot(J[1, 0] * sx, J[1, 1] * sz),
                                                   rel=1e-12)
    assert a.resolution_low is None and a.figures.rate == 493.0
    # ±7.9 mT is below the field at rest (36 mT): saturated at t = 0
    assert a.saturation.saturates and a.saturation.t == 0.0
    text = " ".join(" ".join(r) for r in card_rows([a])[1])
    assert "GAIN_SEL 7, RES 0, OSR 0, DIG_FILT 2; 493 Hz" in text and "mN" in text
    assert "±4.92 / 7.93 mT: saturates (normal axis) at t = 0.00" in text


def test_min_rate_trades_force_noise_for_speed(models, study, fast_answer):
    from magtact.designer import setting_for

    design = fast_answer.design  # the design's extrema do not depend on the chip
    slow = setting_for(models, _rate(study, 0.0), design)
    fast = setting_for(models, _rate(study, 200.0), design)
    assert slow.figures.rate < 200 <= fast.figures.rate
    assert slow.setting != fast.setting
    assert fast.sigma_r_worst > slow.sigma_r_worst and fast.sigma_z_worst > slow.sigma_z_worst
    # no setting holds MagOne's 171 mT: both saturate where the widest range does
    assert not slow.holds and slow.B_max_z > 0.17
    assert slow.figures.range_z == fast.figures.range_z == 50e-3
    # asked to read only the first fifth of the loads, a setting holds the field there
    # (|B_z| reaches 50 mT at t = 0.24 of the original design)
    publication = load_study("magone-publication")  # read_fraction: the publication's problem
    part = setting_for(models, _hall(publication, read_fraction=0.2), design)
    assert part.holds and part.figures.range_z >= 0.036  # above the field at rest


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(st.floats(0, 1e6) | st.just(float("nan")),
                          st.floats(0, 1e6) | st.just(float("nan"))), min_size=1, max_size=40),
       st.floats(0, 1e3), st.floats(0, 1e3))
def test_the_worst_noise_over_the_undominated_points_is_the_worst_over_all(points, a, b):
    """A non-negatively weighted sum is largest at a point no other exceeds in both columns;
    NaN points are left out as ``nanmax`` leaves them out."""
    from magtact.chip._setting import _maximal

    P = np.array(points, float)
    M = _maximal(P)
    whole = P[:, 0] * a + P[:, 1] * b
    if np.isnan(whole).all():
        assert len(M) == 0
        return
    assert np.max(M[:, 0] * a + M[:, 1] * b) == np.nanmax(whole)
    # each kept point is one of the given ones
    assert all(any(np.array_equal(m, p) for p in P) for m in M)


@pytest.mark.long
def test_sigma_objective_is_the_force_noise_and_nsga2_meets_the_exact_reduction(models, study):
    from magtact.optimise import exact_reduction, force_constraints, front_gap, pareto_nsga2, sweep
    from magtact.optimise._setting import sigma_objective
    from magtact.sensitivity import force_noise

    s = replace(study, optimise=replace(study.optimise, sweep_n=201, population=60,
                                        nsga2_generations=40, objective="sigma_F"))
    obj = sigma_objective(models, s)
    t, th = np.meshgrid(np.linspace(0, 1, 5), np.linspace(0, 0.4, 3), indexing="ij")
    got = [G0 * obj.responses.at(H0).value(k, t, th) for k in ("gamma_r", "gamma_z")]
    want = force_noise(models, t, th, H0, G0, obj.noise)
    np.testing.assert_allclose(got, want, rtol=1e-10)
    R = obj.responses
    table = sweep(R, s)
    c = force_constraints(R, s)
    red = exact_reduction(R, s, c, table)
    pareto = pareto_nsga2(R, s, c, table)
    assert front_gap(pareto, red) < 0.01


# ---- magnets and silicones -------------------------------------------------------------------
def test_grade_and_size_set_the_magnet_and_conflicts_are_refused():
    s = study_from_dict({"magnet": {"grade": "N52", "size": "3x3", "placement": "flush"}})
    assert s.magnet.M_z == pytest.approx(0.5 * (1.42 + 1.46) / MU0, rel=1e-12)
    assert (s.magnet.R_m, s.magnet.H_m) == (1.5e-3, 3e-3)
    with pytest.raises(StudyError, match=r"\[magnet.M_z_A_per_m\] 1e\+06 conflicts with "
                                         r"magnet.grade = 'N52'"):
        study_from_dict({"magnet": {"grade": "N52", "M_z_A_per_m": 1.0e6}})
    again = study_from_dict(__import__("tomllib").loads(s.to_toml()))
    assert again == s  # the written study names both and they agree
    assert [g for g in GRADES] == ["N35", "N38", "N40", "N42", "N45", "N48", "N50", "N52"]
    for g in GRADES.values():
        assert 1.1 < g.B_r_min < g.B_r < g.B_r_max < 1.5


#: The sizes inside the broad data set's magnet space that vendor listings were found for.
BROAD_SIZES = {"3x1", "3x2", "3x3", "4x1", "4x2", "4x3", "5x1", "6x1", "6x2", "6x3"}


def test_every_catalogue_size_has_its_dimensions_and_a_source():
    """Each size is '<D>x<H>' with D_mm, H_mm > 0 and a source; the broad space (D 3–6 mm,
    H 1–3 mm) holds at least the sizes cited from vendor listings."""
    import tomllib
    from importlib import resources

    from magtact.parts import SIZES

    raw = tomllib.loads(resources.files("magtact.parts").joinpath("data", "magnets.toml")
                        .read_text("utf-8"))["sizes"]
    assert set(raw) == set(SIZES)
    for name, v in raw.items():
        assert v["D_mm"] > 0 and v["H_mm"] > 0, name
        assert isinstance(v["source"], str) and v["source"].strip(), name
        assert name == f"{v['D_mm']:g}x{v['H_mm']:g}"
        s = SIZES[name]
        assert (s.R_m, s.H_m) == pytest.approx((0.5e-3 * v["D_mm"], 1e-3 * v["H_mm"]))
        assert s.source == v["source"]
    broad = {k for k, v in raw.items() if 3 <= v["D_mm"] <= 6 and 1 <= v["H_mm"] <= 3}
    assert broad >= BROAD_SIZES


@pytest.mark.parametrize(("table", "key", "listed"), [
    ({"magnet": {"grade": "N60"}}, "magnet.grade", "N52"),
    ({"magnet": {"size": "4x4"}}, "magnet.size", "5x2"),
    ({"material": {"silicone": "Ecoflex 00-40"}}, "material.silicone", "Ecoflex 00-30"),
])
def test_unknown_parts_are_refused_with_the_known_names(table, key, listed):
    with pytest.raises(StudyError, match=rf"\[{key}\] expected one of .*'{listed}'"):
        study_from_dict(table)


def test_silicones_name_their_sources_and_ranges():
    eco = SILICONES["Ecoflex 00-30"]
    assert eco.G_range == pytest.approx((16.8e3, 10 * 6894.757293168 / 3))
    assert eco.contains(22.6e3) and not eco.contains(29.4e3)
    assert all(src and how for s in SILICONES.values() for _, src, how in s.figures)


def test_magone_keeps_its_magnet_and_the_new_keys_change_nothing(study):
    """The new keys in the built-in study are the defaults: leaving them out gives the same
    study."""
    assert study.magnet.M_z == 1.2e6 and study.magnet.grade == "custom"
    import tomllib

    from magtact.study import Study

    text = study.to_toml()
    data = tomllib.loads(text)
    for section, key in (("magnet", "grade"), ("magnet", "size"), ("material", "silicone"),
                         ("hall", "gain_sel"), ("hall", "res"), ("hall", "osr"),
                         ("hall", "dig_filt"), ("hall", "standoff_mm"),
                         ("optimise", "objective")):
        del data[section][key]
    data["base"] = "magone"
    assert study_from_dict(data) == study == replace(Study(), description=study.description)


# ---- bad input -----------------------------------------------------------------------------
@pytest.mark.parametrize(("table", "key", "message"), [
    ({"hall": {"noise_x_uT": -1.0}}, "hall.noise_x_uT", "must be at least 0"),
    ({"hall": {"chip": "custom", "range_x_mT": 50.0, "range_z_mT": 50.0, "noise_x_uT": 1.0}},
     "hall.noise_z_uT", "give the chip's RMS field noise"),
    ({"requirements": {"rate_Hz": 1000.0}}, "requirements.rate_Hz",
     "above the Melexis MLX90393's fastest permitted sample rate, 493 Hz"),
    ({"requirements": {"rate_Hz": 100.0}, "hall": {"osr": 3, "dig_filt": 7}},
     "requirements.rate_Hz",
     "above the fastest sample rate of the fixed setting fields, 4.5 Hz"),
    ({"hall": {"gain_sel": 8}}, "hall.gain_sel", "GAIN_SEL of the Melexis MLX90393 is 0 to 7"),
    ({"hall": {"res": -2}}, "hall.res", "must be at least -1"),
    ({"hall": {"chip": "TLE493D", "osr": 1}}, "hall.osr", "has no OSR setting"),
    ({"hall": {"chip": "TLV493D"}, "requirements": {"rate_Hz": 5000.0}},
     "requirements.rate_Hz", "3300 Hz"),
    ({"optimise": {"objective": "sigma_F"}, "sensitivity": {"definition": "published"}},
     "optimise.objective", "needs the Jacobian"),
])
def test_bad_chip_input_names_the_key(table, key, message):
    with pytest.raises(StudyError, match=rf"\[{key}\] .*{message}"):
        study_from_dict(table)


@pytest.mark.long
def test_cli_refuses_a_bad_setting_in_one_line(tmp_path):
    import subprocess
    import sys

    f = tmp_path / "s.toml"
    f.write_text("[hall]\nosr = 0\ndig_filt = 0\n")
    res = subprocess.run([sys.executable, "-m", "magtact", "optimise", str(f), "--out",
                          str(tmp_path / "o")], capture_output=True, text=True, timeout=120)
    out = res.stdout + res.stderr
    assert res.returncode == 2 and "[hall.dig_filt]" in out and "Traceback" not in out


def test_report_argues_where_the_chip_saturates():
    from magtact.report._publication import saturation_argument

    text = saturation_argument()
    for part in ("Δz_sat = 2.97 mm", "|B_z| = 171 mT there", "onset of 50 mT",
                 "t = 0.24 of the original design", "36 mT at rest", "chip of about 171 mT"):
        assert part in text


@settings(max_examples=40, deadline=None)
@given(chip=st.sampled_from(["MLX90393", "TLV493D", "TLE493D"]),
       fields=st.dictionaries(st.sampled_from(["gain_sel", "res", "osr", "dig_filt"]),
                              st.integers(-3, 300), max_size=4),
       rate=st.one_of(st.just(0.0), st.floats(0.0, 1e7, allow_nan=False)))
def test_any_hall_setting_loads_or_is_refused_naming_its_key(chip, fields, rate):
    table = {"hall": {"chip": chip, **fields}, "requirements": {"rate_Hz": rate}}
    try:
        s = study_from_dict(table)
    except StudyError as exc:
        assert exc.key.startswith(("hall.", "requirements.rate_Hz"))
        return
    if chip == "MLX90393":  # what loads has a permitted setting fast enough
        from magtact.study._hall import candidate_settings, setting_figures

        assert any(setting_figures(s, c).rate >= rate for c in candidate_settings(s))
