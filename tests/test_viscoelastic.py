"""The silicone's relaxation in time: the hereditary integral against closed forms and an
independent quadrature, the loop's limits in rate, creep against the closed-form retardation,
the budget's time rows and card, the figure against the JSON, and bad input."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import G_ORIGINAL, H_ORIGINAL
from magtact import MagtactError
from magtact.budget import budget_card_rows, budget_json, error_budget
from magtact.optimise import per_design
from magtact.study import StudyError, load_study
from magtact.viscoelastic import (
    MEASURED_HYSTERESIS,
    Prony,
    design_forces,
    held_force,
    hereditary_force,
    implied_ratio,
    press_and_hold,
    press_cycle,
    rate_sweep,
    relaxation_of,
)

# ---- the hereditary integral ----------------------------------------------------------------


def _ramp_hold(G_inf, G1, tau, rate, T, t):
    """F(t) of f = rate·t up to T, then held: G_∞ f + G_1 rate τ (1 − e^{−t/τ}) (e^{−(t−T)/τ})."""
    ramp = t <= T
    up = G_inf * rate * t + G1 * rate * tau * -np.expm1(-t / tau)
    hold = (G_inf * rate * T
            + G1 * rate * tau * -np.expm1(-T / tau) * np.exp(-np.maximum(t - T, 0.0) / tau))
    return np.where(ramp, up, hold)


@pytest.mark.parametrize("G_inf, G1, tau, rate, T", [
    (29.4e3, 14.7e3, 0.5, 2e-4, 1.0), (1.0, 3.0, 2.0, 0.7, 3.0), (5e5, 1e3, 1e-3, 1.0, 10.0)])
def test_single_exponential_ramp_and_hold_is_the_closed_form(G_inf, G1, tau, rate, T):
    t = np.concatenate([np.linspace(0.0, T, 13), T + np.geomspace(1e-3, 20 * tau, 40)])
    f = np.where(t <= T, rate * t, rate * T)
    F = hereditary_force(Prony(G_inf, (G1,), (tau,)), t, f)
    exact = _ramp_hold(G_inf, G1, tau, rate, T, t)
    np.testing.assert_allclose(F[1:], exact[1:], rtol=1e-9)
    assert F[0] == 0.0


def test_zero_relaxation_gives_the_elastic_force_exactly():
    rng = np.random.default_rng(1)
    t = np.cumsum(rng.uniform(0.01, 1.0, 50))
    f = rng.normal(size=(50, 2))
    for p in (Prony(29.4e3), Prony(29.4e3, (0.0, 0.0), (1.0, 5.0))):
        np.testing.assert_array_equal(hereditary_force(p, t, f), 29.4e3 * f)


def test_a_nonlinear_history_agrees_with_an_independent_quadrature():
    """F(t_end) = ∫ G(t_end − s) f'(s) ds by the trapezoidal rule on 2·10⁵ points against the
    recursion on 2000 samples (f not linear in time: the recursion's error is O(Δ²))."""
    p = Prony(2.0, (1.0, 0.5), (0.3, 4.0))
    fun = lambda s: np.sin(1.3 * s) ** 2 + 0.2 * s  # noqa: E731
    dfun = lambda s: 1.3 * np.sin(2.6 * s) + 0.2  # noqa: E731
    t_end = 5.0
    s = np.linspace(0.0, t_end, 200_001)
    reference = np.trapezoid(p.relaxation(t_end - s) * dfun(s), s)
    t = np.linspace(0.0, t_end, 2001)
    got = hereditary_force(p, t, fun(t))[-1]
    assert got == pytest.approx(reference, rel=1e-6)


def test_creep_under_a_step_force_is_the_closed_form_retardation():
    """A force F_0 applied at once and held: f(t) = F_0/G_∞ − F_0 (1/G_∞ − 1/G_0)
    exp(−t G_∞ / (G_0 τ)) for one term (the retardation time τ G_0 / G_∞)."""
    G_inf, G1, tau, F0 = 1.0, 0.5, 2.0, 3.0
    p = Prony(G_inf, (G1,), (tau,))
    G0 = G_inf + G1
    t = np.concatenate([[0.0], np.geomspace(1e-5, 40.0, 4000)])
    f = np.full(len(t), F0 / G0)
    F, f_held = held_force(p, t, f, 0)
    np.testing.assert_array_equal(F, np.full(len(t), F0 / G0 * G0))
    exact = F0 / G_inf - F0 * (1 / G_inf - 1 / G0) * np.exp(-t * G_inf / (G0 * tau))
    np.testing.assert_allclose(f_held, exact, rtol=2e-6)


# ---- the loop in rate ------------------------------------------------------------------------


@settings(max_examples=12, deadline=None)
@given(g=st.floats(0.05, 3.0), tau=st.floats(1e-2, 1e2), curve=st.floats(0.0, 2.0))
def test_loop_area_vanishes_at_both_rate_limits_and_peaks_near_one_over_tau(g, tau, curve):
    p = Prony(1.0, (g,), (tau,))
    f = lambda load: load + curve * load**2  # noqa: E731  (a stiffening body)
    sweep = rate_sweep(p, f, 1.0, tau * np.geomspace(1e-5, 1e5, 41), n=200)
    area = sweep.area[:, 0]
    assert area.max() > 0
    assert area[0] < 1e-3 * area.max() and area[-1] < 1e-3 * area.max()
    best = sweep.press_times[int(np.argmax(area))]
    assert tau / 10 <= best <= 10 * tau
    for k in (0, -1):  # no hysteresis at either limit either
        assert sweep.gap[k, 0] < 1e-3 * sweep.gap[:, 0].max()


def test_the_largest_error_goes_from_zero_to_the_modulus_ratio_with_rate():
    """Calibrated on G_∞: a slow press reads true; an instant one reads G_∞/G_0 of the truth.
    Calibrated on G_0 the other way round."""
    p = Prony(1.0, (0.5,), (1.0,))
    f = lambda load: load  # noqa: E731
    slow, fast = (press_cycle(p, f, 1.0, T) for T in (1e5, 1e-6))
    assert slow.error[0] < 1e-4 and fast.error[0] == pytest.approx(0.5, rel=1e-5)
    slow, fast = (press_cycle(p, f, 1.0, T, calibrated_on="short") for T in (1e5, 1e-6))
    assert slow.error[0] == pytest.approx(0.5, rel=1e-4) and fast.error[0] < 1e-5


def test_creep_of_a_long_hold_reaches_the_long_time_reading():
    p = Prony(1.0, (0.5,), (1.0,))
    c = press_and_hold(p, lambda load: load, 1.0, 1e-3, 200.0)
    F_held = c.F_true[-1, 0]
    assert c.F_read[-1, 0] == pytest.approx(F_held, rel=1e-6)  # read on G_∞ = true at rest
    assert c.creep[0] == pytest.approx(F_held * (1 - 1 / 1.5), rel=2e-3)


def test_the_implied_single_term_reaches_the_target_hysteresis():
    f = lambda load: load + 0.5 * load**2  # noqa: E731
    g, tau = implied_ratio(f, 1.0, 1.0, MEASURED_HYSTERESIS)
    lp = press_cycle(Prony(1.0, (g,), (tau,)), f, 1.0, 1.0, n=100)
    assert lp.gap[0] / lp.peak[0] == pytest.approx(MEASURED_HYSTERESIS, rel=1e-3)
    assert 0 < g < 1


# ---- the budget and the card ----------------------------------------------------------------


@pytest.fixture(scope="module")
def original(models):
    s = load_study("magone")
    quick = replace(s, optimise=replace(s.optimise, population=40, ga_generations=4))
    design = per_design(models, H_ORIGINAL, G_ORIGINAL, quick)
    plain = error_budget(models, s, H_ORIGINAL, G_ORIGINAL, label="original", design=design,
                         noise=(1e-6, 1.5e-6), samples=200)
    given_s = _with_series(s)
    timed = error_budget(models, given_s, H_ORIGINAL, G_ORIGINAL, label="original",
                         design=design, noise=(1e-6, 1.5e-6), samples=200)
    return s, given_s, design, plain, timed


def _with_series(s):
    return replace(s, material=replace(s.material, relaxation_g1=0.3, relaxation_tau1=0.5,
                                       relaxation_g2=0.2, relaxation_tau2=20.0))


def test_without_relaxation_data_the_budget_says_so_and_keeps_its_rows(original):
    _, _, _, plain, timed = original
    assert not any(r.group == "time" for r in plain.rows)
    note = [n for n in plain.not_modelled if n.startswith("the silicone's relaxation")]
    assert len(note) == 1 and "no relaxation data for Ecoflex 00-30" in note[0]
    rows = budget_card_rows([plain])
    assert any(r[0] == "error budget: time (hysteresis, creep)" and r[1].startswith(
        "not known: no relaxation data for Ecoflex 00-30") for r in rows)
    # the other rows are those of the budget with time rows, number for number
    other = [(r.name, r.component, r.at_rest, r.worst) for r in timed.rows if r.group != "time"]
    assert other == [(r.name, r.component, r.at_rest, r.worst) for r in plain.rows]
    m = budget_json(plain)["time"]["measured"]
    assert m["hysteresis_pct"] == pytest.approx(3.4) and 0 < m["single_term_g_min"] < 1


def test_time_rows_are_the_loops_of_the_design_in_mN_with_their_source(original, models):
    s, given_s, design, _, timed = original
    prony, source = relaxation_of(given_s, G_ORIGINAL)
    assert "given by the study" in source and prony.ratios == pytest.approx((0.3, 0.2))
    assert prony.G_inf == G_ORIGINAL
    hyst = [r for r in timed.rows if r.name.startswith("time: hysteresis")]
    creep = [r for r in timed.rows if r.name.startswith("time: creep")]
    assert [r.component for r in hyst] == ["F_r", "F_z"] and len(creep) == 2
    assert all(source in r.assumptions for r in hyst + creep)
    # the F_z row is the worse of the normal and the sheared press, computed here
    gaps = [press_cycle(prony, design_forces(models, H_ORIGINAL, th), design.t_m, 1.0).gap[1]
            for th in (0.0, design.theta_m)]
    assert hyst[1].worst == pytest.approx(max(gaps), rel=1e-12)
    doc = budget_json(timed)
    rows = {(r["name"], r["component"]): r for r in doc["rows"]}
    assert rows[(hyst[1].name, "F_z")]["worst_mN"] == pytest.approx(1e3 * hyst[1].worst)
    assert doc["time"]["measured"]["predicted_pct"] > 0
    card = budget_card_rows([timed])
    names = " ".join(r[0] for r in card)
    assert "time: hysteresis" in names and "time: creep" in names and source in names


def test_a_catalogue_relaxation_serves_where_the_study_gives_none(original, models,
                                                                  monkeypatch):
    """A silicone given a cited series in the catalogue: its ratios and times at the design's
    G, its source on the rows, and its sweep in budget.json and the figure."""
    from magtact.parts import SILICONES, Relaxation
    from magtact.report import draw_time

    s, _, design, _, _ = original
    cited = Relaxation((0.4,), (2.0,), "a cited test")
    monkeypatch.setitem(SILICONES, "Ecoflex 00-30",
                        replace(SILICONES["Ecoflex 00-30"], relaxation=cited))
    prony, source = relaxation_of(s, G_ORIGINAL)
    assert source == "Ecoflex 00-30: a cited test"
    assert prony.G == pytest.approx((0.4 * G_ORIGINAL,)) and prony.tau == (2.0,)
    b = error_budget(models, s, H_ORIGINAL, G_ORIGINAL, label="original", design=design,
                     noise=(1e-6, 1.5e-6), samples=200)
    assert all("Ecoflex 00-30: a cited test" in r.assumptions for r in b.rows
               if r.group == "time")
    doc = {"budgets": [budget_json(b)]}
    sweep = doc["budgets"][0]["time"]["silicones"]["Ecoflex 00-30"]
    f = design_forces(models, H_ORIGINAL, 0.0)
    T = sweep["press_time_s"][5]
    lp = press_cycle(prony, f, design.t_m, T, n=200)
    assert sweep["hysteresis_pct"][5] == pytest.approx(100 * lp.gap[1] / lp.peak[1], rel=1e-12)
    ax_h = draw_time(doc).axes[1]
    (line,) = [ln for ln in ax_h.lines if ln.get_gid() == "silicone:Ecoflex 00-30"]
    np.testing.assert_allclose(line.get_ydata(), sweep["hysteresis_pct"])


def test_the_study_refuses_a_bad_relaxation_naming_the_key():
    with pytest.raises(StudyError, match=r"material\.relaxation_g1.*at least 0"):
        _load({"material": {"relaxation_g1": -0.1}})
    with pytest.raises(StudyError, match=r"material\.relaxation_tau2_s.*positive"):
        _load({"material": {"relaxation_tau2_s": 0.0}})
    with pytest.raises(StudyError, match=r"environment\.press_time_s.*positive"):
        _load({"environment": {"press_time_s": -1.0}})
    with pytest.raises(StudyError, match=r"environment\.calibrated_on.*'long', 'short'"):
        _load({"environment": {"calibrated_on": "medium"}})


def _load(sections):
    import magtact

    return magtact.load("magone", **sections)


# ---- the figure ------------------------------------------------------------------------------


def test_the_figure_draws_the_loop_and_the_sweep_of_the_json(original):
    from magtact.report import draw_time

    _, _, _, plain, timed = original
    assert draw_time({"budgets": [budget_json(plain)]}) is None
    doc = {"budgets": [budget_json(timed)]}
    fig = draw_time(doc)
    ax_l, ax_h = fig.axes[:2]
    press = doc["budgets"][0]["time"]["presses"][0]
    (loop,) = [ln for ln in ax_l.lines if ln.get_gid() == "loop"]
    np.testing.assert_array_equal(loop.get_xdata(), np.asarray(press["loop"]["F_true_mN"])[:, 1])
    np.testing.assert_array_equal(loop.get_ydata(), np.asarray(press["loop"]["F_read_mN"])[:, 1])
    (sweep,) = [ln for ln in ax_h.lines if ln.get_gid() == "sweep:0"]
    sw = press["rate_sweep"]
    expected = 100 * np.asarray(sw["hysteresis_mN"])[:, 1] / np.asarray(sw["peak_mN"])[:, 1]
    np.testing.assert_allclose(sweep.get_ydata(), expected)


# ---- bad input -------------------------------------------------------------------------------


@pytest.mark.parametrize("args, message", [
    ((1.0, (-1.0,), (1.0,)), r"^Prony series: G_1 = -1 Pa is negative"),
    ((1.0, (0.5, -2.0), (1.0, 2.0)), r"^Prony series: G_2 = -2 Pa is negative"),
    ((-5.0, (), ()), r"^Prony series: G_inf = -5 Pa must be positive"),
    ((0.0, (), ()), r"^Prony series: G_inf = 0 Pa must be positive"),
    ((1.0, (1.0,), (0.0,)), r"^Prony series: tau_1 = 0 s must be positive"),
    ((1.0, (1.0, 1.0), (1.0, -3.0)), r"^Prony series: tau_2 = -3 s must be positive"),
    ((1.0, (math.nan,), (1.0,)), r"^Prony series: G_1 = nan is not finite"),
    ((1.0, (1.0,), (math.inf,)), r"^Prony series: tau_1 = inf is not finite"),
    ((1.0, (1.0, 2.0), (1.0,)), r"^Prony series: 2 moduli G_i but 1 times tau_i"),
])
def test_a_bad_prony_series_is_refused_naming_it(args, message):
    with pytest.raises(MagtactError, match=message) as err:
        Prony(*args)
    assert "\n" not in str(err.value)


@settings(max_examples=30, deadline=None)
@given(n=st.integers(2, 30), data=st.data())
def test_a_history_with_nan_is_refused_naming_the_sample(n, data):
    k = data.draw(st.integers(0, n - 1))
    which = data.draw(st.sampled_from(["f", "time"]))
    t, f = np.linspace(0.0, 1.0, n), np.linspace(0.0, 2.0, n)
    (f if which == "f" else t)[k] = np.nan
    with pytest.raises(MagtactError, match=rf"^history: {which}\[{k}\] = nan is not finite") \
            as err:
        hereditary_force(Prony(1.0, (1.0,), (1.0,)), t, f)
    assert "\n" not in str(err.value)


def test_times_that_do_not_increase_and_bad_press_times_are_refused():
    p = Prony(1.0, (1.0,), (1.0,))
    with pytest.raises(MagtactError, match=r"^history: time\[2\] = 0.5 s does not follow"):
        hereditary_force(p, [0.0, 0.5, 0.5], [0.0, 1.0, 2.0])
    with pytest.raises(MagtactError, match=r"^press_time = 0 s must be a positive"):
        press_cycle(p, lambda x: x, 1.0, 0)
    with pytest.raises(MagtactError, match=r"^hold = -1 s must be a positive"):
        press_and_hold(p, lambda x: x, 1.0, 1.0, -1)
    with pytest.raises(MagtactError, match=r"^calibrated_on must be one of long, short"):
        press_cycle(p, lambda x: x, 1.0, 1.0, calibrated_on="medium")


# ---- against a finite-strain viscoelastic FE path (-m long) ---------------------------------


@pytest.mark.long
def test_the_quasi_linear_force_follows_a_finite_strain_viscoelastic_fe_path():
    """bench/bench_viscoelastic.py with 40 levels per half cycle: the normal press of the
    MagOne body (H = 3 mm, coarse mesh) to t = 0.5 in 1 s and back, g = 0.5, τ = 1 s. The
    quasi-linear force from the elastic FE path is within 2 % of the peak of the
    viscoelastic FE path while loading (the explicit inelastic update is first order in the
    step: about 1 % at τ/40), and the two hysteresis gaps agree within 20 %."""
    pytest.importorskip("tensortrax")
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
    import bench_viscoelastic as bv

    s = load_study("magone")
    prony = Prony.from_ratios(s.material.G_ref, (0.5,), (1.0,))
    elastic = bv.fe_path(s, 3e-3, 0.5, 1.0, 40, "coarse", None)
    visco = bv.fe_path(s, 3e-3, 0.5, 1.0, 40, "coarse", prony)
    t = np.asarray(elastic["time_s"])
    qlv = hereditary_force(prony, t, np.asarray(elastic["F_z_N"]) / s.material.G_ref)
    fe = np.asarray(visco["F_z_N"])
    half, peak = len(t) // 2, np.max(np.abs(fe))
    assert np.max(np.abs(qlv[: half + 1] - fe[: half + 1])) < 0.02 * peak
    gap_fe = np.max(np.abs(fe[: half + 1] - fe[half:][::-1]))
    gap_qlv = np.max(np.abs(qlv[: half + 1] - qlv[half:][::-1]))
    assert gap_qlv == pytest.approx(gap_fe, rel=0.2)


def test_equal_steps_as_one_filter_are_the_step_by_step_recursion():
    """On equal time steps the hereditary integrals run as one linear filter; they equal the
    step-by-step recursion (:class:`_State`) to round-off, for one and for two force columns."""
    from magtact.viscoelastic._prony import Prony, _State, hereditary_force

    p = Prony(G_inf=10e3, G=(5e3, 2e3), tau=(0.05, 1.3))
    t = np.linspace(0.0, 2.0, 401)
    f = np.column_stack([np.sin(3 * t) + 0.2, t**2])
    st = _State(p, f[0], t[0])
    slow = np.empty_like(f)
    slow[0] = st.force()
    for k in range(1, len(t)):
        slow[k] = st.to_f(t[k], f[k])
    np.testing.assert_allclose(hereditary_force(p, t, f), slow, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(hereditary_force(p, t, f[:, 0]), slow[:, 0], rtol=1e-12,
                               atol=1e-12)
