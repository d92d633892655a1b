"""DOE machinery with analytic stand-in solvers: cache, keys, executor, data set, CSV, errors.

The stand-ins have known closed forms, so every number of the assembled data set is checked
against its formula; the real solvers are exercised in ``test_doe_acceptance.py``.
"""

import csv
import json
import os
from dataclasses import replace

import numpy as np
import pytest
import xarray as xr

from conftest import fake_field, fake_forces, fake_path, run, tiny
from magtact.doe import (
    CacheCorruptWarning,
    DOEFailed,
    JobCache,
    load_dataset,
    run_doe,
    save_dataset,
    write_csv,
)
from magtact.doe._cache import Entry
from magtact.doe._dataset import BUNDLED_NAMES, _read_h5, bundled_path
from magtact.geometry import loading_path
from magtact.study import from_si


def nan_path(study, H, theta, *, G=None, mesh=None, t=None, vtu=None):
    res = fake_path(study, H, theta, G=G, t=t)
    return replace(res, F_z=res.F_z * np.nan)


# ---- the data set ------------------------------------------------------------------------------
def test_dataset_layout_units_and_values_match_the_formulas():
    s = tiny()
    ds = run(s)
    assert dict(ds.sizes) == {"t": 4, "theta": 2, "H": 2, "G": 3}
    for name, units in {"u_r": "m", "u_z": "m", "B_r": "T", "B_z": "T", "F_r": "N",
                        "F_z": "N"}.items():
        assert ds[name].attrs["units"] == units
    assert ds["F_r"].dims == ("t", "theta", "H", "G") and ds["B_z"].dims == ("t", "theta", "H")
    np.testing.assert_array_equal(ds.G.values, s.G_levels)
    T, TH, HH, GG = np.meshgrid(s.t_levels, s.theta_levels, s.H_levels, s.G_levels,
                                indexing="ij")
    F_r, F_z = fake_forces(T, TH, HH, GG)
    np.testing.assert_allclose(ds.F_r.values, F_r, rtol=1e-13, atol=0)
    np.testing.assert_allclose(ds.F_z.values, F_z, rtol=1e-13, atol=0)
    u_r, u_z = loading_path(s, T[..., 0], TH[..., 0], HH[..., 0])
    np.testing.assert_array_equal(ds.u_z.values, u_z)
    np.testing.assert_array_equal(ds.B_r.values, 1e3 * u_r)
    assert ds.attrs["complete"] == 1 and ds.attrs["run_paths_computed"] == 4
    assert "[doe]" in ds.attrs["study_toml"] and "felupe" in ds.attrs["versions"]


def test_netcdf_round_trip_and_csv_export(tmp_path):
    s = tiny()
    ds = run(s)
    back = load_dataset(save_dataset(ds, tmp_path / "d.nc"))
    xr.testing.assert_identical(back, ds)
    path = write_csv(ds, tmp_path / "d.csv")
    with path.open() as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["t", "theta_rad", "H_mm", "G_kPa", "u_r_mm", "u_z_mm", "B_r_T", "B_z_T",
                       "F_r_N", "F_z_N"]
    assert len(rows) - 1 == 4 * 2 * 2 * 3
    # last row: the last level of every dimension (G fastest), in user units, exact doubles
    last = [float(x) for x in rows[-1]]
    sel = ds.isel(t=-1, theta=-1, H=-1, G=-1)
    assert last[:4] == [1.0, s.theta_levels[-1], from_si(s.H_levels[-1], "mm"),
                        from_si(s.G_levels[-1], "kPa")]
    assert last[5] == from_si(float(sel.u_z), "mm") and last[9] == float(sel.F_z)
    second = [float(x) for x in rows[2]]  # t=0, theta=0, H=H_0, G=G_1
    assert second[3] == from_si(s.G_levels[1], "kPa") and second[0] == 0.0


@pytest.mark.parametrize("name", BUNDLED_NAMES)
def test_direct_reading_equals_xarrays_for_every_bundled_file(name):
    """The bundled files are read through HDF5 directly (the magnet-size screen reads one per
    size): the same data set as xarray's reading, attributes and types included."""
    path = bundled_path(name)
    direct = _read_h5(path)
    assert direct is not None
    with xr.open_dataset(path, engine="h5netcdf") as ds:
        reference = ds.load()
    xr.testing.assert_identical(direct, reference)
    for k in reference.variables:
        assert direct[k].dtype == reference[k].dtype and direct[k].attrs == reference[k].attrs
    assert {k: type(v) for k, v in direct.attrs.items()} == \
        {k: type(v) for k, v in reference.attrs.items()}


def test_files_of_another_layout_are_read_by_xarray(tmp_path):
    """A NaN written and read back, and files the direct reading does not describe (CF
    scaling, a float fill value that is not NaN) are read as xarray reads them."""
    ds = run(tiny())
    ds["F_z"][0, 0, 0, 0] = np.nan
    path = save_dataset(ds, tmp_path / "d.nc")
    assert _read_h5(path) is not None
    xr.testing.assert_identical(load_dataset(path), ds)
    for encoding in ({"F_z": {"scale_factor": 0.5}}, {"F_z": {"_FillValue": -1.0}}):
        ds.to_netcdf(tmp_path / "e.nc", engine="h5netcdf", encoding=encoding)
        assert _read_h5(tmp_path / "e.nc") is None
        with xr.open_dataset(tmp_path / "e.nc", engine="h5netcdf") as ref:
            xr.testing.assert_identical(load_dataset(tmp_path / "e.nc"), ref.load())


def test_load_dataset_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="DOE data set not found"):
        load_dataset(tmp_path / "missing.nc")
    xr.Dataset({"x": ("t", [1.0])}).to_netcdf(tmp_path / "other.nc", engine="h5netcdf")
    with pytest.raises(ValueError, match="not a DOE data set"):
        load_dataset(tmp_path / "other.nc")


# ---- cache -------------------------------------------------------------------------------------
def test_cache_round_trip_and_corruption_is_detected(tmp_path):
    cache = JobCache(tmp_path)
    entry = Entry({"a": np.arange(5.0)}, {"n": 3, "name": "x"})
    path = cache.put("path", "k1", entry)
    got = cache.get("path", "k1")
    np.testing.assert_array_equal(got.arrays["a"], entry.arrays["a"])
    assert got.meta == entry.meta and cache.get("path", "absent") is None
    assert not list(tmp_path.rglob("*.tmp"))  # the temporary file was renamed
    good = path.read_bytes()
    for bad, reason in [(good[:-7], "truncated"), (good[:-3] + b"xyz", "checksum"),
                        (b"garbage\nmore", "not a magtact cache entry"), (b"garbage", "no header"),
                        (good.replace(b" k1 ", b" k2 ", 1), "names another job")]:
        path.write_bytes(bad)
        with pytest.warns(CacheCorruptWarning, match=reason):
            assert cache.get("path", "k1") is None
    assert cache.corrupt == 5


def test_cache_rejects_bad_names_and_object_arrays(tmp_path):
    cache = JobCache(tmp_path)
    with pytest.raises(ValueError, match="cache key must be letters"):
        cache.path("path", "../escape")
    with pytest.raises(ValueError, match="dtype object"):
        cache.put("path", "k", Entry({"a": np.array([None])}, {}))


def test_rerun_uses_cache_and_G_levels_trigger_no_solve(tmp_path):
    s = tiny()
    first = run(s, tmp_path)
    again = run(s, tmp_path)
    assert again.attrs["run_paths_computed"] == 0 and again.attrs["run_fields_computed"] == 0
    xr.testing.assert_equal(first, again)
    s2 = replace(s, design=replace(s.design, G=(15e3, 45e3)), doe=replace(s.doe, n_G=4))
    moved = run(s2, tmp_path)
    assert moved.attrs["run_paths_computed"] == 0 and moved.attrs["run_fields_computed"] == 0
    np.testing.assert_allclose(moved.F_z.isel(G=0), first.F_z.isel(G=0) * 15 / 10, rtol=1e-13)


def test_changed_settings_recompute_only_what_they_touch(tmp_path):
    s = tiny()
    run(s, tmp_path)
    more_theta = run(replace(s, doe=replace(s.doe, n_theta=3)), tmp_path)  # adds θmax/2
    assert more_theta.attrs["run_paths_computed"] == 2  # 1 new θ × 2 H
    stiffer = run(replace(s, material=replace(s.material, bulk_ratio=8000.0)), tmp_path)
    assert stiffer.attrs["run_paths_computed"] == 4 and stiffer.attrs["run_fields_computed"] == 0
    field = run(replace(s, magnetics=replace(s.magnetics, solver="exact")), tmp_path)
    assert field.attrs["run_paths_computed"] == 0 and field.attrs["run_fields_computed"] == 1


def test_per_G_solves_when_scaling_is_off(tmp_path):
    s = tiny()
    s = replace(s, mechanics=replace(s.mechanics, scale_in_G=False))
    ds = run(s, tmp_path)
    assert ds.attrs["run_paths_computed"] == 2 * 2 * 3 and ds.attrs["forces_scaled_in_G"] == 0
    np.testing.assert_allclose(ds.F_r.values, run(tiny()).F_r.values, rtol=1e-13)


# ---- failures and executors --------------------------------------------------------------------
def test_failed_jobs_are_reported_and_others_finish(tmp_path, monkeypatch):
    s = tiny()
    monkeypatch.setenv("MAGTACT_TEST_FAIL", "1")
    with pytest.raises(DOEFailed, match=r"1 DOE job\(s\) failed") as info:
        run(s, tmp_path)
    (fail,) = info.value.failures
    assert "no convergence at theta=0.423" in fail.error and "H=7" in fail.label
    partial = info.value.dataset
    assert partial.attrs["complete"] == 0 and partial.attrs["run_paths_computed"] == 3
    assert np.isnan(partial.F_r.isel(theta=1, H=1)).all()
    assert not np.isnan(partial.F_r.isel(theta=0)).any()
    monkeypatch.delenv("MAGTACT_TEST_FAIL")
    retry = run(s, tmp_path)  # only the failed path is computed again
    assert retry.attrs["run_paths_computed"] == 1


def stalling_path(study, H, theta, *, G=None, mesh=None, t=None, vtu=None):
    """The fake path, failing after its first two levels at the sheared, tallest path."""
    from magtact.mechanics import PathFailed

    res = fake_path(study, H, theta, G=G, t=t)
    if theta > 0 and H == study.H_levels[-1]:
        part = replace(res, **{k: getattr(res, k)[:2] for k in ("t", "u_r", "u_z", "F_r", "F_z")})
        raise PathFailed(0.5, theta, H, float(res.t[1]), "no progress", part)
    return res


def test_a_failed_path_keeps_its_levels_before_the_failure(tmp_path):
    s = tiny()
    with pytest.raises(DOEFailed, match="levels up to t = 0.3333 kept") as info:
        run(s, tmp_path, path_solver=stalling_path)
    ds = info.value.dataset
    whole = run(s)
    assert ds.attrs["complete"] == 0 and "kept" in ds.attrs["failed_jobs"]
    kept = ds.F_z.isel(theta=1, H=1)
    xr.testing.assert_equal(kept.isel(t=slice(0, 2)), whole.F_z.isel(theta=1, H=1, t=slice(0, 2)))
    assert np.isnan(kept.isel(t=slice(2, None))).all()
    job = next(j for j in json.loads(ds.attrs["jobs"]) if "t_reached" in j)
    assert job["t_reached"] == pytest.approx(1 / 3)
    with pytest.raises(DOEFailed):  # a partial path is not cached: the next run tries again
        run(s, tmp_path, path_solver=stalling_path)


def test_a_non_finite_result_is_a_failure_not_data():
    with pytest.raises(DOEFailed, match="'F_z' is not finite"):
        run(tiny(), path_solver=nan_path)


def test_local_processes_give_the_in_process_result(tmp_path):
    s = tiny()
    pooled = run(s, tmp_path / "a", workers=2)
    xr.testing.assert_equal(pooled, run(s))
    assert pooled.attrs["run_executor"] == "2 local worker processes"


def test_bad_worker_count_is_refused():
    with pytest.raises(ValueError, match="workers must be a whole number >= 0"):
        run(tiny(), workers=-1)


def test_cli_doe_writes_netcdf_and_csv(tmp_path, monkeypatch):
    from typer.testing import CliRunner

    from magtact.cli import app

    def fake_run(study, **kw):
        return run_doe(study, cache=kw["cache"], workers=0, path_solver=fake_path,
                       field_solver=fake_field)

    monkeypatch.setattr("magtact.doe.run_doe", fake_run)
    study = tmp_path / "tiny.toml"
    study.write_text("[doe]\nn_t = 3\nn_theta = 1\nn_H = 1\nn_G = 2\n")
    res = CliRunner().invoke(app, ["doe", str(study), "--out", str(tmp_path / "o"),
                                   "--cache", str(tmp_path / "c")])
    assert res.exit_code == 0, res.output
    assert load_dataset(tmp_path / "o" / "doe.nc").sizes["G"] == 2
    assert len((tmp_path / "o" / "doe.csv").read_text().splitlines()) == 1 + 3 * 2
    assert "1 computed" in res.output
    assert os.listdir(tmp_path / "c")


def test_doe_figure_is_written(tmp_path):
    from magtact.report import fig_doe

    files = fig_doe(run(tiny()), tmp_path / "doe")
    assert [f.suffix for f in files] == [".png", ".svg"]
    assert all(f.stat().st_size > 1000 for f in files)


def test_unreachable_scheduler_is_a_user_error(monkeypatch):
    monkeypatch.setattr("magtact.doe._executor.CONNECT_TIMEOUT", "1s")
    with pytest.raises(ValueError, match="cannot use the dask scheduler 'tcp://127.0.0.1:9'"):
        run(tiny(), scheduler="tcp://127.0.0.1:9")


def test_cli_doe_reports_failed_jobs(tmp_path, monkeypatch):
    import json

    from typer.testing import CliRunner

    from magtact.cli import app

    def fake_run(study, **kw):
        return run_doe(study, cache=kw["cache"], workers=0, path_solver=fake_path,
                       field_solver=fake_field)

    monkeypatch.setattr("magtact.doe.run_doe", fake_run)
    monkeypatch.setenv("MAGTACT_TEST_FAIL", "1")
    study = tmp_path / "tiny.toml"
    study.write_text("[doe]\nn_t = 3\nn_theta = 2\nn_H = 2\nn_G = 2\n")
    res = CliRunner().invoke(app, ["doe", str(study), "--out", str(tmp_path / "o"),
                                   "--no-cache"])
    assert res.exit_code == 1
    assert "1 job(s) failed" in res.output and "no convergence at theta=0.423" in res.output
    (fail,) = json.loads((tmp_path / "o" / "doe_failures.json").read_text())
    assert "H=7 mm" in fail["job"] and "RuntimeError" in fail["traceback"]
    assert not (tmp_path / "o" / "doe.nc").exists()
    partial = load_dataset(tmp_path / "o" / "doe_partial.nc")  # the finished jobs, NaN elsewhere
    assert partial.attrs["complete"] == 0 and "H=7 mm" in partial.attrs["failed_jobs"]
    assert np.isnan(partial.F_r.isel(theta=1, H=1)).all()
    assert "doe_partial.nc: magtact fit leaves out up to 10%" in " ".join(res.output.split())
