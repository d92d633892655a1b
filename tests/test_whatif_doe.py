"""The DOE over two geometric design variables at once (the broad space: R_m and H_m), with
stand-in solvers of known form."""

from dataclasses import replace

import numpy as np

from conftest import fake_field, fake_path, run
from magtact.doe import load_dataset, save_dataset
from magtact.study import study_from_dict


def magnet_path(study, H, theta, *, G=None, mesh=None, t=None, vtu=None):
    """Stand-in forces scaled by R_m [mm] + 10 H_m [mm] (each geometry its own value)."""
    res = fake_path(study, H, theta, G=G, t=t)
    k = study.magnet.R_m * 1e3 + 10 * study.magnet.H_m * 1e3
    return replace(res, F_r=res.F_r * k, F_z=res.F_z * k)


def magnet_field(study, t, theta, H, solver="fe"):
    B_r, B_z = fake_field(study, t, theta, H, solver)
    k = study.magnet.R_m * 1e3 + 10 * study.magnet.H_m * 1e3
    return B_r * k, B_z * k


def test_two_geometric_variables_give_one_dimension_each(tmp_path):
    s = study_from_dict({"doe": {"n_t": 3, "n_theta": 2, "n_H": 2, "n_G": 2, "n_R_m": 2,
                                 "n_H_m": 2},
                         "design": {"R_m_mm": [1.5, 3.0], "H_m_mm": [1.0, 3.0]},
                         "metamodel": {"b_model": "exact"}})
    ds = run(s, tmp_path, path_solver=magnet_path, field_solver=magnet_field)
    assert ds["F_z"].dims == ("t", "theta", "H", "G", "R_m", "H_m")
    assert ds["B_z"].dims == ("t", "theta", "H", "R_m", "H_m")
    assert ds.attrs["run_paths_total"] == 2 * 2 * 4
    for i, R_m in enumerate(s.geometry_levels["R_m"]):
        for j, H_m in enumerate(s.geometry_levels["H_m"]):
            sub = run(s.at(R_m=R_m, H_m=H_m), tmp_path, path_solver=magnet_path,
                      field_solver=magnet_field)
            for name in ("F_z", "F_r", "B_z", "u_z"):
                np.testing.assert_array_equal(ds[name].isel(R_m=i, H_m=j).values,
                                              sub[name].values)
    back = load_dataset(save_dataset(ds, tmp_path / "g.nc"))
    np.testing.assert_array_equal(back["F_r"].values, ds["F_r"].values)


def test_a_failed_path_of_one_magnet_is_named_with_that_magnet(tmp_path, monkeypatch):
    import pytest

    from magtact.doe import DOEFailed

    s = study_from_dict({"doe": {"n_t": 3, "n_theta": 2, "n_H": 2, "n_G": 2, "n_R_m": 2},
                         "design": {"R_m_mm": [1.5, 3.0]}, "metamodel": {"b_model": "exact"}})
    monkeypatch.setenv("MAGTACT_TEST_FAIL", "1")  # the sheared path at the tallest H fails
    with pytest.raises(DOEFailed) as info:
        run(s, tmp_path, path_solver=magnet_path, field_solver=magnet_field)
    labels = [f.label for f in info.value.failures]
    assert len(labels) == 2 and labels[0].endswith("R_m=1.5 mm") and labels[1].endswith(
        "R_m=3 mm")
    assert "R_m=3 mm: RuntimeError" in info.value.dataset.attrs["failed_jobs"]


def test_the_outline_of_a_bundled_data_set_tells_what_it_describes_as_the_whole_one():
    """The bundled data sets are told apart by their coordinates and attributes alone (read
    without xarray's decoding); the differences are those of the data sets read whole."""
    from magtact.doe._dataset import (
        BUNDLED_NAMES,
        _outline,
        bundled_path,
        differences,
        load_bundled,
    )
    from magtact.study import load_study, study_from_dict

    studies = [load_study("magone"),
               study_from_dict({"base": "magone", "magnet": {"R_m_mm": 3.0, "H_m_mm": 3.0},
                                "design": {"H_mm": [4.0, 10.0], "H_original_mm": 5.0}})]
    names = [n for n in BUNDLED_NAMES if bundled_path(n).is_file()]
    assert len(names) >= 2
    for name in names:
        whole, outline = load_bundled(name), _outline(name)
        for study in studies:
            assert differences(outline, study) == differences(whole, study), name
