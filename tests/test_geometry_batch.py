"""Designs of different geometries evaluated together: the exact field over per-point magnet
dimensions, batched per-design extrema and sweeps, against the same quantities computed one
geometry at a time (sub-studies)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from magtact.magnetics import cylinder_field
from magtact.metamodel import ExactField, Metamodel, ModelSet
from magtact.metamodel._symbols import H, R_m, p, q
from magtact.optimise import heights_batch, sweep
from magtact.optimise._design import _bracket, _groups
from magtact.study import study_from_dict

SMALL = {"start_t": 9, "start_theta": 5, "sweep_n": 9, "sweep_coarse": 5, "tol": 1e-9,
         "geometry_n": 5}


def geo_study(**design):
    return study_from_dict({"design": design or {"R_m_mm": [2.0, 3.0]},
                            "metamodel": {"b_model": "exact"}, "optimise": SMALL})


def radius_models(study) -> ModelSet:
    """The exact field and smooth forces of the displacement that stiffen with the radius."""
    a = -(study.loading.dz_sat + study.magnet.H_m - H - study.body.H_g)  # −u_z per unit t
    e, s = a * p / H, -a * q / H
    area = sp.pi * 36e-6 * (1 + 0.3 * (R_m / 2.5e-3) ** 2)
    f_z = area * e * (1 + 1.5 * e) * (1 + 0.2 * s**2)
    f_r = -area * s * (1 - 2.0 * e**2) * 0.8
    return ModelSet(ExactField(study, "B_r"), ExactField(study, "B_z"),
                    Metamodel.from_expr("f_r", f_r, "N/Pa"),
                    Metamodel.from_expr("f_z", f_z, "N/Pa"))


def test_cylinder_field_broadcasts_over_the_magnet():
    r, z = np.array([0.0, 1e-3, 2.5e-3, 4e-3]), np.array([-3e-3, -4e-3, -2e-3, 1e-3])
    R, Hm = np.array([1.5e-3, 2e-3, 2.5e-3, 3.5e-3]), np.array([1e-3, 2e-3, 3e-3, 2e-3])
    batch = cylinder_field(r, z, R, Hm, 1.2e6)
    one = np.array([cylinder_field(*v, 1.2e6) for v in zip(r, z, R, Hm, strict=True)]).T
    np.testing.assert_allclose(batch, one, rtol=1e-14, atol=0)  # AGM iterations
    with pytest.raises(ValueError, match="R_m and H_m must be positive"):
        cylinder_field(r, z, np.array([1e-3, 0.0, 1e-3, 1e-3]), 2e-3, 1.2e6)


def test_exact_field_at_given_magnet_dimensions_is_the_sub_studys():
    """Values per point equal the field of the sub-study at that point's magnet, to the
    rounding of the position's affine coefficients (amplified by 1/h³ in third derivatives)."""
    s = geo_study(R_m_mm=[2.0, 3.0], H_m_mm=[1.5, 2.5])
    t, th, h = np.array([0.0, 0.3, 0.8]), np.array([0.1, 0.0, 0.35]), np.array([3e-3, 5e-3, 7e-3])
    geo = {"R_m": np.array([2e-3, 2.4e-3, 3e-3]), "H_m": np.array([2.5e-3, 1.5e-3, 2e-3])}
    for name in ("B_r", "B_z"):
        field = ExactField(s, name)
        assert field.geometry == ("R_m", "H_m")
        for i in range(3):
            sub = ExactField(s.at(R_m=geo["R_m"][i], H_m=geo["H_m"][i]), name)
            bound = field.bind(R_m=geo["R_m"][i], H_m=geo["H_m"][i])
            for f in (sub, bound):
                np.testing.assert_allclose(field.value(t, th, h, **geo)[i],
                                           f.value(t[i], th[i], h[i]), rtol=1e-13, atol=1e-16)
                np.testing.assert_allclose(field.hess(t, th, h, **geo)[i],
                                           f.hess(t[i], th[i], h[i]), rtol=1e-9, atol=1e-9)
                for a, b in zip(field.jet(t, th, h, 3, **geo), f.jet(t[i], th[i], h[i], 3),
                                strict=True):
                    np.testing.assert_allclose(a[i], b, rtol=1e-8, atol=1e-8 * np.abs(b).max())


def test_exact_field_of_a_geometric_study_needs_the_values():
    field = ExactField(geo_study(), "B_z")
    with pytest.raises(ValueError, match=r"model B_z depends on \['R_m'\]: give their values"):
        field.value(0.5, 0.1, 4e-3)
    assert ExactField(study_from_dict({}), "B_z").geometry == ()


def test_batched_extrema_equal_one_geometry_at_a_time():
    s = geo_study()
    models = radius_models(s)
    H_, R_ = np.array([3e-3, 6e-3, 4.5e-3]), np.array([2e-3, 3e-3, 2.6e-3])
    tab = heights_batch(models, H_, s, geometry={"R_m": R_})
    np.testing.assert_array_equal(tab.geometry["R_m"], R_)
    for i in range(3):
        one = heights_batch(models.at(R_m=R_[i]), [H_[i]], s.at(R_m=R_[i]))
        for name in ("f_r_min", "f_z_max", "gamma_r_max", "gamma_z_max"):
            np.testing.assert_allclose(getattr(tab, name)[i], getattr(one, name)[0], rtol=1e-7)


def test_a_sweep_over_many_geometries_is_each_geometrys_sweep():
    s = geo_study()
    s = replace(s, optimise=replace(s.optimise, sweep_n=5, sweep_coarse=3))
    models = radius_models(s)
    both = sweep(models, s, geometry={"R_m": [2e-3, 3e-3]})
    n = s.optimise.sweep_n
    assert both.H.size == 2 * n
    for j, r in ((1, 3e-3),):
        one = sweep(models.at(R_m=r), s.at(R_m=r))
        part = both.take(slice(j * n, (j + 1) * n))
        np.testing.assert_array_equal(part.H, one.H)
        np.testing.assert_array_equal(part.geometry["R_m"], np.full(n, r))
        for name in ("f_r_min", "f_z_max", "gamma_r_max", "gamma_z_max"):
            np.testing.assert_allclose(getattr(part, name), getattr(one, name), rtol=1e-7)


@settings(max_examples=60, deadline=None)
@given(groups=st.lists(st.integers(0, 3), min_size=1, max_size=30),
       data=st.data())
def test_bracket_stays_within_the_group(groups, data):
    """Each query is bracketed by two grid elements of its own geometry that enclose it."""
    n = len(groups)
    grid = np.array(data.draw(st.lists(st.floats(0, 1), min_size=n, max_size=n)))
    values = np.array(groups, float)
    queries = data.draw(st.lists(st.sampled_from(sorted(set(groups))), min_size=1, max_size=8))
    x = np.array(data.draw(st.lists(st.floats(0, 1), min_size=len(queries),
                                    max_size=len(queries))))
    gg, gx = _groups({"R_m": values}, {"R_m": np.array(queries, float)})
    lo, hi = _bracket(grid, x, gg, gx)
    for k, g in enumerate(queries):
        assert values[lo[k]] == values[hi[k]] == g
        own = np.sort(grid[values == g])
        if own.size > 1 and own[0] <= x[k] <= own[-1]:
            assert grid[lo[k]] <= x[k] <= grid[hi[k]]
    # without groups: the neighbours in the sorted grid, as for one geometry
    g = np.sort(grid)
    lo, hi = _bracket(g, x)
    if g.size > 1:
        np.testing.assert_array_equal(hi, np.clip(np.searchsorted(g, x), 1, g.size - 1))
        np.testing.assert_array_equal(lo, hi - 1)


@pytest.mark.parametrize("design, best", [
    ({"R_m_mm": [1.5, 3.5]}, {"R_m": 2.37e-3}),
    ({"R_m_mm": [2.0, 3.0], "H_m_mm": [1.5, 2.5]}, {"R_m": 2.37e-3, "H_m": 1.83e-3}),
])
def test_the_refined_grid_finds_an_optimum_between_its_first_levels(monkeypatch, design, best):
    """A stand-in front per geometry, one point with Γ_r = Γ_z = 1 + |g − g*|² (mm): the
    first 5-level grid misses g*, the refinement around the front approaches it until the
    front moves by less than the tolerance."""
    import magtact.optimise._geometry as geometry

    calls = []

    def fronts(models, study, constraints, names, points):
        calls.append(len(points))
        rows = []
        for p_ in points:
            gam = 1.0 + sum(((v - best[k]) / 1e-3) ** 2 for k, v in zip(names, p_, strict=True))
            rows.append([3e-3, 2e4, 1.2e6, *p_, gam, gam])
        return rows, None

    monkeypatch.setattr(geometry, "_fronts", fronts)
    s = geo_study(**design)
    exact, grid, step = geometry.exact_geometry(None, s, None)
    assert len(exact) == 1 and calls[0] == 5 ** len(best) and len(calls) > 2
    assert exact.Gamma_r_max[0] - 1.0 <= 2 * geometry.REFINE_TOL
    for k, v in best.items():
        np.testing.assert_allclose(grid[k], np.linspace(*s.geometric_variables[k], 5))
        assert abs(exact.values[k][0] - v) <= 0.1e-3
        assert step[k] < np.diff(grid[k])[0] / 2  # at least two halvings


def test_a_model_over_the_magnet_radius_round_trips_through_its_file(tmp_path):
    from magtact import MagtactError
    from magtact.metamodel import load_model, save_model

    s = geo_study()
    f = radius_models(s).f_z
    back = load_model(save_model(f, tmp_path / "f_z.json"))
    assert back.geometry == ("R_m",) and back.expr == f.expr
    x = (np.array([0.2, 1.0]), np.array([0.0, 0.3]), 4e-3)
    assert np.array_equal(back.value(*x, R_m=2.2e-3), f.value(*x, R_m=2.2e-3))
    bad = save_model(f, tmp_path / "bad.json")
    bad.write_text(bad.read_text().replace("R_m", "R_x"))
    with pytest.raises(MagtactError, match="name .R_x. is not allowed"):
        load_model(bad)
