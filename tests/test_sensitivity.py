"""Sensitivity Γ: against finite differences of the same models, the limit at t = 0, the data."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import sympy as sp

from conftest import AREA, K_DIPOLE, synthetic_doe
from magtact.metamodel import ExactField, ModelSet, fit_models, hall_features
from magtact.metamodel import H as Hs
from magtact.metamodel import p as ps
from magtact.metamodel import q as qs
from magtact.sensitivity import Responses, compare_with_data, dF_dB, gamma, gamma_from_data
from magtact.study import load_study

STUDY = load_study(None)


def analytic_set() -> ModelSet:
    """The stand-in data's exact formulas (dipole field, smooth forces) as a ModelSet."""
    X, Z = (v / 1000 for v in hall_features(STUDY))
    r2 = X**2 + Z**2
    a = STUDY.loading.dz_sat + STUDY.magnet.H_m - Hs - STUDY.body.H_g
    u_r, u_z = -a * qs, a * ps
    e, s = -u_z / Hs, u_r / Hs
    return ModelSet.from_exprs({
        "B_r": K_DIPOLE * 3 * X * Z / r2 ** sp.Rational(5, 2),
        "B_z": K_DIPOLE * (3 * Z**2 - r2) / r2 ** sp.Rational(5, 2),
        "f_r": -AREA * s * (1 - 2 * e**2) * sp.Float(0.8),
        "f_z": AREA * e * (1 + sp.Float(1.5) * e) * (1 + sp.Float(0.2) * s**2),
    })


def fitted_set() -> ModelSet:
    cfg = replace(STUDY.metamodel, generations=6, population=60)
    return fit_models(synthetic_doe(STUDY, n_t=6), STUDY, settings=cfg).model_set()


def exact_B_set() -> ModelSet:
    m = analytic_set()
    return ModelSet(B_r=ExactField(STUDY, "B_r"), B_z=ExactField(STUDY, "B_z"),
                    f_r=m.f_r, f_z=m.f_z)


def gamma_fd(models: ModelSet, t, th, H, G, h=1e-6):
    """Γ from central differences of model values in (t, θ): ∂F/∂B = ∂F/∂x (∂B/∂x)⁻¹."""
    def d(m):
        return np.stack([(m.value(t + h, th, H) - m.value(t - h, th, H)) / (2 * h),
                         (m.value(t, th + h, H) - m.value(t, th - h, H)) / (2 * h)], axis=-1)
    J = np.stack([d(models.B_r), d(models.B_z)], axis=-2)
    S = np.asarray(G)[..., None, None] * np.stack([d(models.f_r), d(models.f_z)], axis=-2) \
        @ np.linalg.inv(J)
    return np.hypot(S[..., 0, 0], S[..., 0, 1]), np.hypot(S[..., 1, 0], S[..., 1, 1])


def random_points(n=40, seed=0):
    rng = np.random.default_rng(seed)
    return (rng.uniform(0.05, 1.0, n), rng.uniform(0.02, STUDY.loading.theta_max, n),
            rng.uniform(*STUDY.design.H, n), rng.uniform(*STUDY.design.G, n))


@pytest.mark.parametrize("make", [analytic_set, fitted_set, exact_B_set])
def test_gamma_matches_finite_differences_of_the_same_models(make):
    models = make()
    t, th, H, G = random_points()
    for a, b in zip(gamma(models, t, th, H, G), gamma_fd(models, t, th, H, G), strict=True):
        assert np.all(np.isfinite(a))
        assert np.allclose(a, b, rtol=1e-5, atol=0)


def test_gamma_scales_with_G_and_dF_dB_shape():
    models = analytic_set()
    S1, S2 = dF_dB(models, 0.5, 0.2, 4e-3, 1.0), dF_dB(models, 0.5, 0.2, 4e-3, 3e4)
    assert S1.shape == (2, 2) and np.allclose(S2, 3e4 * S1, rtol=1e-15)


@pytest.mark.parametrize("make", [analytic_set, fitted_set, exact_B_set])
def test_gamma_finite_at_t0_and_equal_to_its_limit(make):
    models = make()
    th = np.linspace(0.0, STUDY.loading.theta_max, 5)
    for H in STUDY.design.H:
        g0 = gamma(models, 0.0, th, H, 2e4)
        g_small = gamma(models, 1e-7, th, H, 2e4)
        scale = gamma(models, np.linspace(0, 1, 11)[:, None], th, H, 2e4)
        for a, b, s in zip(g0, g_small, scale, strict=True):
            assert np.all(np.isfinite(a))
            assert np.allclose(a, b, rtol=1e-5, atol=1e-6 * s.max())


def test_gamma_exact_for_models_linear_in_u():
    """B = J u and F = G K u: ∂F/∂B = G K J⁻¹ everywhere, t = 0 included."""
    a = -4e-3  # u per unit t at H = 4 mm (a = Δz_sat − Δz0 = −H with the defaults)
    J = np.array([[30.0, 2.0], [1.0, -20.0]])  # [T/m], rows B, columns (u_r, u_z)
    K = np.array([[-400.0, 10.0], [5.0, -900.0]])  # [N/(Pa m)]
    u_r, u_z = -a * qs, a * ps
    models = ModelSet.from_exprs({
        "B_r": J[0, 0] * u_r + J[0, 1] * u_z, "B_z": 0.05 + J[1, 0] * u_r + J[1, 1] * u_z,
        "f_r": K[0, 0] * u_r + K[0, 1] * u_z, "f_z": K[1, 0] * u_r + K[1, 1] * u_z})
    S = 2e4 * K @ np.linalg.inv(J)
    t = np.array([0.0, 0.0, 0.5, 1.0])
    th = np.array([0.0, 0.3, 0.1, 0.4])
    gr, gz = gamma(models, t, th, 4e-3, 2e4)
    assert np.allclose(gr, np.hypot(*S[0]), rtol=1e-13)
    assert np.allclose(gz, np.hypot(*S[1]), rtol=1e-13)


@pytest.mark.parametrize("make", [analytic_set, exact_B_set])
def test_responses_derivatives_match_finite_differences(make):
    models = make()
    at = Responses(models).at(4.5e-3)
    t = np.array([0.0, 0.2, 0.6, 0.95])
    th = np.array([0.1, 0.0, 0.25, 0.4])
    h = 1e-6
    for name in ("f_r", "f_z", "gamma_r", "gamma_z"):
        v, g, H2 = at.value(name, t, th), at.grad(name, t, th), at.hess(name, t, th)
        assert v.shape == (4,) and g.shape == (4, 2) and H2.shape == (4, 2, 2)
        gfd = np.stack([(at.value(name, t + h, th) - at.value(name, t - h, th)) / (2 * h),
                        (at.value(name, t, th + h) - at.value(name, t, th - h)) / (2 * h)], -1)
        hfd = np.stack([(at.grad(name, t + h, th) - at.grad(name, t - h, th)) / (2 * h),
                        (at.grad(name, t, th + h) - at.grad(name, t, th - h)) / (2 * h)], -2)
        scale_g, scale_h = np.abs(g).max(), np.abs(H2).max()
        assert np.allclose(g, gfd, rtol=1e-5, atol=1e-6 * scale_g), name
        assert np.allclose(H2, hfd, rtol=1e-4, atol=1e-5 * scale_h), name
        assert np.allclose(H2, np.swapaxes(H2, -1, -2), rtol=1e-10, atol=1e-12 * scale_h)
    gr, gz = gamma(models, t, th, 4.5e-3, 1.0)
    assert np.allclose(at.value("gamma_r", t, th), gr, rtol=1e-14)
    assert np.allclose(at.value("gamma_z", t, th), gz, rtol=1e-14)
    assert np.allclose(at.value("f_r", t, th), models.f_r.value(t, th, 4.5e-3), rtol=1e-15)


def test_responses_broadcast_over_heights():
    models = analytic_set()
    H = np.array([3e-3, 5e-3, 7e-3])[:, None]
    t, th = np.array([0.0, 0.3, 0.9]), np.array([0.1, 0.2, 0.4])
    many = Responses(models).at(H)
    for name in ("f_z", "gamma_r"):
        v, g, h = many.value(name, t, th), many.grad(name, t, th), many.hess(name, t, th)
        assert v.shape == (3, 3) and g.shape == (3, 3, 2) and h.shape == (3, 3, 2, 2)
        for i, Hi in enumerate(H[:, 0]):
            one = Responses(models).at(Hi)
            assert np.allclose(v[i], one.value(name, t, th), rtol=1e-14)
            assert np.allclose(g[i], one.grad(name, t, th), rtol=1e-13)
            assert np.allclose(h[i], one.hess(name, t, th), rtol=1e-12)


def test_responses_unknown_name():
    with pytest.raises(ValueError, match="unknown response 'F_r'"):
        Responses(analytic_set()).at(4e-3).value("F_r", 0.1, 0.1)


def test_gamma_from_data_agrees_with_exact_formulas():
    """The data's finite-difference Γ converges to the exact Γ of the formulas behind the data."""
    study = replace(STUDY, doe=replace(STUDY.doe, n_theta=17))
    ds = synthetic_doe(study, n_t=41)
    check = compare_with_data(analytic_set(), ds, t_min=0.2)
    for v in check.values():  # second-order differences: ~(Δθ)² (one-sided at the edges)
        # interior: central in t and θ, θ = 0 included (continued to −θ by the mirror symmetry)
        assert v["n_points"] == 33 * 17 * 5 and v["n_points_interior"] == 32 * 16 * 5
        assert v["max"] < 0.025 and v["median"] < 0.002 and v["max_interior"] < 0.015
    coarse = compare_with_data(analytic_set(), synthetic_doe(
        replace(STUDY, doe=replace(STUDY.doe, n_theta=9)), n_t=41), t_min=0.2)
    assert coarse["gamma_r"]["max"] > 2 * check["gamma_r"]["max"]  # converges with refinement
    gr, gz = gamma_from_data(ds)
    assert np.all(np.isnan(gr[0])) and np.all(np.isfinite(gr[1:]))
    # the floor keeps the points where |γ_model| > floor · max |γ_model|, and only those
    gm = gamma(analytic_set(), *np.meshgrid(ds.t.values, ds.theta.values, ds.H.values,
                                             indexing="ij"), 1.0)
    keep = ds.t.values[:, None, None] >= 0.2
    for floor in (0.0, 0.5):
        above = compare_with_data(analytic_set(), ds, t_min=0.2, floor=floor)
        for v, g in zip(above.values(), gm, strict=True):
            g = np.where(keep, np.abs(g), np.nan)
            assert v["n_points_above_floor"] == np.sum(g > floor * np.nanmax(g))
            assert v["max_above_floor"] <= v["max"] and v["floor"] == floor
    # the share within 5 % (above the default floor) and the largest difference on Γ's scale
    for v, g, d in zip(check.values(), gm, (gr, gz), strict=True):
        g, d = np.abs(g[np.broadcast_to(keep, g.shape)]), d[np.broadcast_to(keep, d.shape)]
        above = g > 0.05 * g.max()
        assert v["within_5_percent_above_floor"] == np.mean(np.abs(g - d)[above] / g[above] <= 0.05)
        assert v["max_abs_over_max"] == pytest.approx(np.max(np.abs(g - d)) / g.max(), rel=1e-12)
    # the check is its record's document, and a floor above every point leaves that spread out
    from magtact._records import from_json, to_json
    from magtact.sensitivity._check import GammaCheck

    for v in check.values():
        assert to_json(from_json(GammaCheck, v)) == v
    empty = compare_with_data(analytic_set(), ds, t_min=0.2, floor=1.5)["gamma_z"]
    assert "median_above_floor" not in empty and "median_interior" in empty
    assert from_json(GammaCheck, empty).above_floor is None


def test_gamma_from_data_needs_three_levels():
    ds = synthetic_doe(replace(STUDY, doe=replace(STUDY.doe, n_theta=2)), n_t=5)
    with pytest.raises(ValueError, match="at least 3 levels of t and of theta"):
        gamma_from_data(ds)


def test_the_written_gamma_code_is_the_sympy_derivation():
    """``_phi_code.py`` (scripts/make_phi.py) gives what a fresh SymPy derivation of γ, its
    gradient and Hessian gives, at random points and at points near a singular Jacobian."""
    from magtact.sensitivity._gamma import _phi, _phi_functions

    rng = np.random.default_rng(3)
    v = rng.normal(size=(6, 200))
    v[2:, :5] = [[1.0], [2.0], [1.0], [2.0 + 1e-6]]  # det(∂B/∂x) near 0
    for written, derived in zip(_phi(), _phi_functions(), strict=True):
        a, b = (np.asarray(f(*v), float) for f in (written, derived))
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=0.0)


def test_the_closed_form_two_by_two_inverse_equals_a_solve():
    """∂F/∂B through the displacement, stacked 2 × 2 blocks in closed form, equals
    (∂F/∂x)(∂B/∂x)⁻¹ by LAPACK, also for a single row of F."""
    from magtact.sensitivity._gamma import through_displacement

    rng = np.random.default_rng(3)
    dB = rng.normal(size=(4, 5, 2, 2))
    for rows in (2, 1):
        dF = rng.normal(size=(4, 5, rows, 2))
        want = dF @ np.linalg.inv(dB)
        assert np.allclose(through_displacement(dF, dB), want, rtol=1e-12, atol=1e-12)
