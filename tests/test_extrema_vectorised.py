"""The per-design extrema of all designs at once, against a brute-force grid, the single-problem
differential evolution + trust-region method and per-design evaluations; the sensor grid over
many standoffs at once against one standoff at a time; the field's derivatives from the curl-
and divergence-free identities against finite differences."""

from __future__ import annotations

import numpy as np
import pytest

from magtact.chip import sensor_grid
from magtact.metamodel import ExactField
from magtact.optimise import box_optimum, per_heights
from magtact.optimise._box import grid_local_optima, multistart_optimum
from magtact.sensitivity import Responses
from magtact.study import magone

STUDY = magone()


@pytest.fixture(scope="module")
def responses(shipped_models):
    return Responses(shipped_models)


def _brute(R, h, name, t_hi, theta_hi, maximise, n=(1001, 201)):
    """Best value of ``name`` on a dense uniform grid over [0, t_hi] × [0, θ_hi]."""
    T, TH = np.meshgrid(np.linspace(0, t_hi, n[0]), np.linspace(0, theta_hi, n[1]),
                        indexing="ij")
    V = R.at(h).value(name, T, TH)
    return float(V.max() if maximise else V.min())


def test_vectorised_extrema_match_a_brute_force_grid_on_20_random_designs(responses):
    rng = np.random.default_rng(7)
    H = np.sort(rng.uniform(*STUDY.design.H, 20))
    res = per_heights(responses, H, STUDY)
    theta_max = STUDY.loading.theta_max
    for h, r in zip(H, res, strict=True):
        brute = _brute(responses, h, "f_r", 1.0, theta_max, False)
        assert r.f_r_min.value <= brute * (1 - 1e-12)  # never worse than the grid
        assert abs(r.f_r_min.value - brute) <= 1e-4 * abs(brute)
        for name, opt in (("f_z", r.f_z_max), ("gamma_r", r.gamma_r_max),
                          ("gamma_z", r.gamma_z_max)):
            brute = _brute(responses, h, name, r.t_m, r.theta_m, True)
            assert opt.value >= brute * (1 - 1e-12), (h, name)
            assert abs(opt.value - brute) <= 1e-4 * abs(brute), (h, name)
            assert 0 <= opt.t <= r.t_m and 0 <= opt.theta <= r.theta_m


def test_vectorised_extrema_equal_the_evolution_and_trust_region_method(responses):
    o = STUDY.optimise
    H = np.array([3.0e-3, 4.7e-3, 6.6e-3])
    res = per_heights(responses, H, STUDY)
    kw = {"population": o.population, "generations": o.ga_generations, "seed": o.seed,
          "tol": o.tol}
    for h, r in zip(H, res, strict=True):
        R = responses.at(h)

        def funcs(name, R=R):
            return (lambda x: R.value(name, x[:, 0], x[:, 1]),
                    lambda x: R.grad(name, x[:, 0], x[:, 1]),
                    lambda x: R.hess(name, x[:, 0], x[:, 1]))

        ref = box_optimum(*funcs("f_r"), [0, 0], [1, STUDY.loading.theta_max],
                          maximise=False, **kw)
        assert r.f_r_min.value == pytest.approx(ref.value, rel=1e-9)
        assert (r.t_m, r.theta_m) == pytest.approx((ref.t, ref.theta), abs=1e-7)
        for name, opt in (("f_z", r.f_z_max), ("gamma_z", r.gamma_z_max)):
            ref = box_optimum(*funcs(name), [0, 0], [r.t_m, r.theta_m], maximise=True, **kw)
            assert opt.value == pytest.approx(ref.value, rel=1e-9), (h, name)


def test_each_height_alone_gives_the_same_extrema(responses):
    H = np.array([3.3e-3, 5.0e-3, 6.9e-3])
    together = per_heights(responses, H, STUDY)
    for h, r in zip(H, together, strict=True):
        alone = per_heights(responses, [h], STUDY)[0]
        for name in ("f_r_min", "f_z_max", "gamma_r_max", "gamma_z_max"):
            assert getattr(alone, name).value == pytest.approx(getattr(r, name).value,
                                                               rel=1e-12)


def test_multistart_finds_the_deeper_of_two_basins():
    # two wells on the unit box: the deeper one is not the one nearest the grid's best
    # point on a coarse grid, and every start is refined to its own minimum
    centres = np.array([[0.2, 0.3], [0.8, 0.75]])
    depth = np.array([1.0, 1.2])
    width = np.array([0.05, 0.01])

    def parts(t, th):
        d = [(t - c[0]) ** 2 + (th - c[1]) ** 2 for c in centres]
        return [-a * np.exp(-di / w) for a, di, w in zip(depth, d, width, strict=True)]

    def fun(r, t, th):
        return sum(parts(t, th))

    def jac(r, t, th):
        out = 0
        for p, c, w in zip(parts(t, th), centres, width, strict=True):
            out = out + p[..., None] * np.stack([-2 * (t - c[0]) / w, -2 * (th - c[1]) / w],
                                                axis=-1)
        return out

    def hess(r, t, th):
        out = 0
        for p, c, w in zip(parts(t, th), centres, width, strict=True):
            g = np.stack([-2 * (t - c[0]) / w, -2 * (th - c[1]) / w], axis=-1)
            out = out + p[..., None, None] * (g[..., :, None] * g[..., None, :]
                                              - 2 / w * np.eye(2))
        return out

    lo, hi = np.zeros((1, 2)), np.ones((1, 2))
    res = multistart_optimum(fun, jac, hess, lo, hi, maximise=False, grid=(6, 6), tol=1e-12,
                             starts=4)
    assert (res.t[0], res.theta[0]) == pytest.approx((0.8, 0.75), abs=1e-4)
    assert res.value[0] == pytest.approx(-1.2, rel=1e-4)


def test_grid_local_optima_lists_the_best_local_minima_first():
    V = np.array([[3.1, 2.0, 3.2, 3.3, 0.5],
                  [3.4, 3.5, 3.6, 3.7, 3.8],
                  [1.0, 3.9, 4.0, 4.1, 4.2]])[None]
    k = grid_local_optima(V, 4)
    assert k.shape == (1, 4)
    assert list(V.reshape(1, -1)[0, k[0, :3]]) == [0.5, 1.0, 2.0]
    assert k[0, 3] == k[0, 0]  # fewer minima than starts: the best repeated


def test_sensor_grid_over_many_standoffs_equals_one_standoff_at_a_time(shipped_models):
    rng = np.random.default_rng(3)
    n = 12
    H = rng.uniform(3e-3, 7e-3, n)
    t_m, theta_m = rng.uniform(0.3, 1.0, n), rng.uniform(0.05, 0.4, n)
    standoff = rng.choice(np.arange(0, 31) * 1e-4, n)
    together = sensor_grid(shipped_models, STUDY, H, t_m, theta_m, standoff)
    for i in range(n):
        one = sensor_grid(shipped_models, STUDY, H[i:i + 1], t_m[i:i + 1], theta_m[i:i + 1],
                          float(standoff[i]))
        for name in ("f_r", "f_z", "b_x", "b_z", "j"):
            np.testing.assert_allclose(getattr(together, name)[i], getattr(one, name)[0],
                                       rtol=1e-9, atol=1e-11 * np.abs(getattr(one, name)).max())


def test_field_derivatives_from_the_identities_match_finite_differences():
    rng = np.random.default_rng(5)
    t = np.concatenate([[0.0, 0.5], rng.uniform(0, 1, 30)])
    th = np.concatenate([[0.2, 0.0], rng.uniform(0, 0.42, 30)])
    H = rng.uniform(3e-3, 7e-3, t.size)
    for name in ("B_r", "B_z"):
        f = ExactField(STUDY, name)
        g = f.grad(t, th, H)
        scale = np.abs(g).max(axis=0)
        for i, step in enumerate((1e-6, 1e-6, 1e-9)):
            d = np.zeros((3, t.size))
            d[i] = step
            x = np.stack([t, th, H])
            lo = np.clip(x - d, 0, None)
            fd = (f.value(*(x + d)) - f.value(*lo)) / (x + d - lo)[i]
            np.testing.assert_allclose(g[:, i], fd, rtol=1e-5, atol=1e-6 * scale[i])


def test_the_force_extrema_are_those_of_the_whole_per_height_problem(shipped_models):
    """The stable box and the force range without the sensitivities' maxima: the same solves,
    so the same numbers to the last bit."""
    from magtact.optimise import force_extrema

    H = np.array([3.0e-3, 4.4e-3, 7.0e-3])
    whole = per_heights(shipped_models, H, STUDY)
    got = force_extrema(shipped_models, H, STUDY)
    want = [[h.t_m for h in whole], [h.theta_m for h in whole],
            [h.f_r_min.value for h in whole], [h.f_z_max.value for h in whole]]
    for a, b in zip(got, want, strict=True):
        assert np.array_equal(a, np.array(b))
