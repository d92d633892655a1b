"""The per-path discretisation-error estimate of a DOE, with stand-in solvers of known error."""

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from conftest import fake_path, run, tiny
from magtact.doe import FINER_MESH, attach_discretisation_error, error_points


def bilinear_change(theta, H):
    """The stand-in default mesh's relative excess over the finer one: bilinear in (θ, H)."""
    return 0.02 + 0.01 * theta + 3.0 * H + 20.0 * theta * H


def curved_change(theta, H):
    return 0.02 + 0.5 * theta**2 + 1e3 * H**2


def mesh_path(change):
    """A path solver whose forces on the default mesh exceed the finer mesh's by ``change``
    (F_r negative along the path, as the stable-shear bound sees it)."""
    def solve(study, H, theta, *, G=None, mesh=None, t=None, vtu=None):
        res = fake_path(study, H, theta, G=G, t=t)
        f = 1 + change(theta, H) if study.mechanics.mesh == "default" else 1.0
        return replace(res, F_r=-res.F_r * f, F_z=res.F_z * f, mesh=study.mechanics.mesh)
    return solve


def grid_study():
    return tiny(n_theta=4, n_H=3, n_G=2)


def test_every_path_records_the_exact_change_measured_or_modelled(tmp_path):
    s = grid_study()
    ds = run(s, tmp_path, path_solver=mesh_path(bilinear_change), error_paths=5)
    th, H = np.meshgrid(s.theta_levels, s.H_levels, indexing="ij")
    exact = bilinear_change(th, H)
    assert int(ds["err_measured"].sum()) == 5 == ds.attrs["discretisation_paths_measured"]
    # the bilinear model reproduces a bilinear change on the paths it did not measure
    np.testing.assert_allclose(ds["err_F_z"].values, exact, rtol=1e-10)
    sheared = s.theta_levels > 0
    np.testing.assert_allclose(ds["err_F_r"].values[sheared], exact[sheared], rtol=1e-10)
    assert np.isnan(ds["err_F_r"].values[~sheared]).all()  # F_r = 0 at θ = 0: no ratio
    assert ds.attrs["discretisation_loo_max_err_F_z"] < 1e-12
    assert ds.attrs["discretisation_finer_mesh"] == "accurate"  # FINER_MESH["default"]
    assert ds["err_F_z"].attrs["units"] == "1"
    assert "bilinear" in ds.attrs["discretisation_method"]
    # the forces themselves are those of the DOE's own mesh
    plain = run(s, tmp_path, path_solver=mesh_path(bilinear_change))
    np.testing.assert_array_equal(ds["F_z"].values, plain["F_z"].values)
    assert "err_F_z" not in plain


def test_a_curved_change_shows_in_the_leave_one_out_check(tmp_path):
    s = grid_study()
    ds = run(s, tmp_path, path_solver=mesh_path(curved_change), error_paths=6)
    th, H = np.meshgrid(s.theta_levels, s.H_levels, indexing="ij")
    exact = curved_change(th, H)
    measured = ds["err_measured"].values.astype(bool)
    np.testing.assert_allclose(ds["err_F_z"].values[measured], exact[measured], rtol=1e-12)
    loo = ds.attrs["discretisation_loo_max_err_F_z"]
    model_err = np.abs(ds["err_F_z"].values - exact)[~measured].max()
    assert 1e-4 < loo and model_err < 2 * loo  # the check sees the curvature it misses


def test_error_points_start_at_the_sheared_corners_and_are_distinct():
    theta, H = np.array([0.0, 0.1, 0.2, 0.3]), np.array([3e-3, 5e-3, 7e-3])
    pts = error_points(theta, H, 100)
    assert len(pts) == len(set(pts)) == 12
    assert set(pts[:4]) == {(0.1, 3e-3), (0.1, 7e-3), (0.3, 3e-3), (0.3, 7e-3)}
    assert pts[4] == (0.2, 5e-3)
    assert error_points(theta, H, 0) == []


def test_bad_input_is_refused_with_a_message(tmp_path):
    s = grid_study()
    with pytest.raises(ValueError, match="mechanics.mesh = 'fine' has no finer mesh"):
        run(s.__class__(**{**s.__dict__, "mechanics": replace(s.mechanics, mesh="fine")}),
            tmp_path, error_paths=2)
    ds = run(s, tmp_path)
    with pytest.raises(ValueError, match="other t levels"):
        attach_discretisation_error(ds, ds.isel(t=slice(1, None)))
    far = ds.assign_coords(H=ds["H"].values + 1.0)
    with pytest.raises(ValueError, match="no path of the DOE's"):
        attach_discretisation_error(ds, far)
    assert FINER_MESH["default"] == "accurate"


@given(st.integers(1, 6), st.integers(1, 6), st.integers(-2, 40))
def test_error_points_are_distinct_grid_points_for_any_grid(n_theta, n_H, n):
    theta, H = np.linspace(0, 0.4, n_theta), np.linspace(3e-3, 7e-3, n_H)
    pts = error_points(theta, H, n)
    assert len(pts) == len(set(pts)) == min(max(n, 0), n_theta * n_H)
    assert all(a in theta and b in H for a, b in pts)



def test_the_bundled_doe_records_its_measured_error_on_every_path():
    from magtact import metamodel
    from magtact.doe import load_bundled, load_dataset
    from magtact.metamodel import data_hash

    ds = load_bundled()
    assert ds["err_measured"].values.all() and ds.attrs["discretisation_paths_measured"] == 25
    assert ds.attrs["discretisation_finer_mesh"] == "accurate"
    assert np.isfinite(ds["err_F_z"].values).all()
    # a coarser mesh is stiffer: every path's F_z(t = 1) is a little too high
    assert (ds["err_F_z"].values > 0).all() and (ds["err_F_z"].values < 0.05).all()
    finer = Path(__file__).parents[1] / "bench" / "results" / "doe_accurate.nc"
    if finer.is_file():  # the stored values are the ratio of the two data sets' forces
        fine = load_dataset(finer)
        ratio = ds["F_z"].isel(t=-1, G=0) / fine["F_z"].isel(t=-1, G=0) - 1
        np.testing.assert_allclose(ds["err_F_z"].values, ratio.transpose("theta", "H").values,
                                   rtol=1e-12)
    # attaching the estimate left the forces (and so the shipped metamodels' data) unchanged
    shipped = Path(metamodel.__file__).parent / "data" / "magone" / "f_z.json"
    assert json.loads(shipped.read_text())["info"]["data_hash"] == data_hash(ds)
