"""Optimisation stage (docs/method.md §7) on metamodels given as known formulas.

The model set (``synthetic_models`` of ``conftest.py``) has a stable-shear minimum f_r,min known
in closed form: with c = 0.4 + 100 H, f_r = k_r [(p − c)² − c² + 4 (q − 0.12)² − 0.0576] (p = t,
q = t tan θ) is smallest at p = c, q = 0.12 while c ≤ 1 (interior: t_m = c, θ_m = atan(0.12 / c))
and on the edge t = 1 beyond (H > 6 mm: t_m = 1, θ_m = atan(0.12)). f_z grows with p and q, so
its maximum is the corner (t_m, θ_m). Γ has no closed form: it is checked against a dense
brute-force grid.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import sympy as sp

from conftest import K_Z, synthetic_models
from magtact.metamodel import p, q
from magtact.optimise import (
    ForceConstraints,
    InfeasibleError,
    box_optimum,
    compare,
    decision_index,
    exact_reduction,
    feasible_G,
    force_constraints,
    front_gap,
    heights_batch,
    nondominated,
    pareto_nsga2,
    per_design,
    per_height,
    sweep,
)
from magtact.sensitivity import Responses
from magtact.study import load_study


def k_r(h):
    return 6e-5 * (3e-3 / h)


def c_of(h):
    return 0.4 + 100 * h


@pytest.fixture(scope="module")
def models():
    return Responses(synthetic_models())


@pytest.fixture(scope="module")
def study():
    return load_study(None)


def f_z_exact(t, theta):
    pq = t * math.tan(theta)
    return K_Z * (t**2 + t / 2 + 0.3 * pq**2)


def brute_max(R, name, t_m, theta_m, n=(2001, 401)):
    """Largest value of ``name`` on a dense grid over [0, t_m] × [0, θ_m] and its location."""
    T, TH = np.meshgrid(np.linspace(0, t_m, n[0]), np.linspace(0, theta_m, n[1]), indexing="ij")
    V = R.value(name, T, TH)
    k = np.argmax(V)
    return V.flat[k], T.flat[k], TH.flat[k]


@pytest.mark.parametrize("h, interior", [(4e-3, True), (7e-3, False)])
def test_per_design_against_exact_and_brute_force(models, study, h, interior):
    G = 25e3
    d = per_design(models, h, G, study)
    # stable shear bounds: exact minimum of f_r
    c = c_of(h)
    t_m, theta_m = (c, math.atan(0.12 / c)) if interior else (1.0, math.atan(0.12))
    f_min = k_r(h) * ((t_m - c) ** 2 - c**2 - 0.0576)
    assert d.t_m == pytest.approx(t_m, rel=1e-9, abs=1e-12)
    assert d.theta_m == pytest.approx(theta_m, rel=1e-9)
    assert d.F_r_min == pytest.approx(G * f_min, rel=1e-12)
    assert ("t_upper" in d.height.f_r_min.active) is not interior
    assert d.height.f_r_min.kkt <= 1e-9
    # F_z,max at the corner (t_m, θ_m): a boundary optimum on both bounds
    assert d.F_z_max == pytest.approx(G * f_z_exact(t_m, theta_m), rel=1e-9)
    assert set(d.height.f_z_max.active) == {"t_upper", "theta_upper"}
    # Γ: brute force on the same box with a 2001 × 401 grid
    R = models.at(h)
    dt, dth = t_m / 2000, theta_m / 400
    for name, opt in (("gamma_r", d.height.gamma_r_max), ("gamma_z", d.height.gamma_z_max)):
        v, tb, thb = brute_max(R, name, d.t_m, d.theta_m)
        assert opt.value >= v * (1 - 1e-12)  # never worse than the grid
        assert (opt.value - v) / v <= 1e-6  # and within the grid's resolution
        assert abs(opt.t - tb) <= dt + 1e-12
        if opt.t > 0:  # at t = 0 every θ gives the same Γ (p = q = 0)
            assert abs(opt.theta - thb) <= dth + 1e-12
    assert d.Gamma_r_max == pytest.approx(G * d.height.gamma_r_max.value, rel=1e-15)


def test_batched_heights_agree_with_per_height(models, study):
    hs = np.array([3e-3, 4e-3, 5.5e-3, 7e-3])
    tab = heights_batch(models, hs, study)
    assert tab.converged.all()
    for i, h in enumerate(hs):
        r = per_height(models, h, study)
        for name in ("f_r_min", "f_z_max", "gamma_r_max", "gamma_z_max"):
            assert getattr(tab, name)[i] == pytest.approx(getattr(r, name).value, rel=1e-9)
        assert tab.t_m[i] == pytest.approx(r.t_m, abs=1e-9)
        assert tab.theta_m[i] == pytest.approx(r.theta_m, abs=1e-9)


def test_degenerate_boxes_are_handled_and_reported(study):
    # f_r ≥ 0 everywhere, zero on the edge t = 0 (any θ: there p = q = 0): t_m = 0
    edge = Responses(synthetic_models(f_r=1e-5 * (p + q)))
    r = per_height(edge, 5e-3, study)
    assert r.t_m == 0.0
    assert r.degenerate in ("t_m = 0", "t_m = theta_m = 0")
    assert r.f_z_max.value == 0.0 and r.f_z_max.t == 0.0
    gamma_0 = edge.at(5e-3).value("gamma_z", 0.0, 0.0)
    assert r.gamma_z_max.value == pytest.approx(gamma_0, rel=1e-14)
    # f_r = k((p − 1/2)² − 1/4 + q): minimum at t = 1/2 on θ = 0, so the box is a segment
    seg = Responses(synthetic_models(f_r=1e-5 * ((p - sp.Rational(1, 2)) ** 2
                                                  - sp.Rational(1, 4) + q)))
    r = per_height(seg, 5e-3, study)
    assert r.theta_m == 0.0 and r.t_m == pytest.approx(0.5, abs=1e-12)
    assert r.degenerate == "theta_m = 0"
    assert r.f_z_max.value == pytest.approx(K_Z * 0.5, rel=1e-12)
    assert r.f_z_max.theta == 0.0
    tab = heights_batch(seg, [5e-3], study)
    assert tab.f_z_max[0] == pytest.approx(K_Z * 0.5, rel=1e-12)


def test_feasible_G_covers_every_sign():
    c = ForceConstraints(F_r_c=-0.25, F_z_c=5.0)
    lo, hi = feasible_G([-1e-5, -1e-5, 1e-5, -1e-5], [2e-4, 1e-4, 2e-4, 0.0], c, (10e3, 50e3))
    # G ≥ 0.25 / 1e-5 = 25 kPa and G ≥ 5 / 2e-4 = 25 kPa
    assert lo[0] == pytest.approx(25e3) and hi[0] == 50e3
    assert lo[1] == pytest.approx(50e3)  # F_z needs G ≥ 50 kPa: just feasible
    assert lo[2] > hi[2]  # f_r,min > 0 can never reach a negative F_r,c
    assert lo[3] > hi[3]  # f_z,max = 0 can never reach F_z,c > 0
    # a positive F_r,c with positive f_r,min bounds G from above
    lo, hi = feasible_G([1e-5], [2e-4], ForceConstraints(0.3, 5.0), (10e3, 50e3))
    assert hi[0] == pytest.approx(30e3) and lo[0] == pytest.approx(25e3)


def test_nondominated_and_decision_rule():
    obj = np.array([[1.0, 5.0], [2.0, 2.0], [3.0, 1.0], [2.5, 2.5], [1.0, 6.0]])
    assert nondominated(obj).tolist() == [True, True, True, False, False]
    # normalised sums over the set: 0 + 1, 0.5 + 0.25, 1 + 0 → the middle one
    assert decision_index(obj[:3]) == 1
    assert decision_index(np.array([[1.0, 3.0], [1.0, 2.0]])) == 1  # constant objective


@pytest.fixture(scope="module")
def runs(models, study):
    C = force_constraints(models, study)
    table = sweep(models, study)
    red = exact_reduction(models, study, C, table)
    first = pareto_nsga2(models, study, C, table)
    second = pareto_nsga2(models, study, C, table)
    return C, red, first, second


def test_exact_reduction_is_the_smallest_feasible_G(models, study, runs):
    C, red, _, _ = runs
    t = red.table
    expected = np.maximum.reduce([np.full(t.H.shape, study.design.G[0]), C.F_r_c / t.f_r_min,
                                  C.F_z_c / t.f_z_max])
    ok = expected <= study.design.G[1]
    assert np.array_equal(red.feasible, ok)
    np.testing.assert_allclose(red.G_star[ok], expected[ok], rtol=1e-14)
    assert red.front.sum() > 100  # a real trade-off curve, not a single point
    # every front point meets the binding constraint with equality
    f = red.front
    g_r, g_z = C.margins(red.G_star[f] * t.f_r_min[f], red.G_star[f] * t.f_z_max[f])
    assert np.all(np.minimum(np.abs(g_r), np.abs(g_z)) <= 1e-12 * C.F_z_c)


def test_nsga2_front_within_one_percent_of_exact(runs):
    C, red, pareto, _ = runs
    assert pareto.H.size > 20
    g_r, g_z = C.margins(pareto.F_r_min, pareto.F_z_max)
    assert np.all(g_r <= 0) and np.all(g_z <= 0)
    assert front_gap(pareto, red) <= 0.01


def test_same_seed_same_pareto_set_and_choice(models, study, runs):
    from magtact.optimise import choose

    _, _, a, b = runs
    for name in ("H", "G", "Gamma_r_max", "Gamma_z_max"):
        assert np.array_equal(getattr(a, name), getattr(b, name))
    ca, cb = choose(models, study, a), choose(models, study, b)
    assert (ca.design.H, ca.design.G, ca.active) == (cb.design.H, cb.design.G, cb.active)


def test_infeasible_constraints_give_best_reachable_values(models, study):
    C = ForceConstraints(F_r_c=-0.25, F_z_c=100.0)
    table = sweep(models, study)
    with pytest.raises(InfeasibleError) as err:
        exact_reduction(models, study, C, table)
    best_z = study.design.G[1] * table.f_z_max.max()
    best_r = study.design.G[1] * table.f_r_min.min()
    msg = str(err.value)
    assert "no design with H in [3, 7] mm and G in [10, 50] kPa satisfies" in msg
    assert f"F_z,max = {best_z:.4g} N" in msg and f"F_r,min = {best_r:.4g} N" in msg
    with pytest.raises(InfeasibleError, match="Best reachable"):
        pareto_nsga2(models, dataclasses.replace(
            study, optimise=dataclasses.replace(study.optimise, nsga2_generations=2)), C, table)


def test_constraints_from_reference_design(models, study):
    C = force_constraints(models, study, reference=(3e-3, 29.4e3))
    d = per_design(models, 3e-3, 29.4e3, study)
    assert (C.F_r_c, C.F_z_c, C.source) == (d.F_r_min, d.F_z_max, "reference")
    ref_study = dataclasses.replace(
        study, constraints=dataclasses.replace(study.constraints, source="reference"))
    assert force_constraints(models, ref_study).F_z_c == d.F_z_max
    assert force_constraints(models, study, F_z_c=3.0).F_z_c == 3.0
    with pytest.raises(ValueError, match="not both"):
        force_constraints(models, study, F_r_c=-1.0, reference=(3e-3, 29.4e3))


def test_compare_percentages(models, study):
    d1 = per_design(models, 4e-3, 20e3, study)
    d2 = per_design(models, 4e-3, 30e3, study)
    cmp = compare(d1, d2)
    for _, _, v1, v2, pct in cmp.rows:
        assert v2 == pytest.approx(1.5 * v1, rel=1e-12)
        assert pct == pytest.approx(50.0, rel=1e-9)


def test_bad_inputs_have_clear_messages(models, study):
    with pytest.raises(ValueError, match="G must be positive"):
        per_design(models, 4e-3, 0.0, study)
    with pytest.raises(TypeError, match="expected Responses or ModelSet, got dict"):
        per_height({}, 4e-3, study)
    with pytest.raises(ValueError, match="lo <= hi"):
        box_optimum(None, None, None, [0, 1], [1, 0], maximise=True, population=10,
                    generations=1, seed=0, tol=1e-12)
