"""The DOE over geometric design variables besides H, with stand-in solvers of known form."""

from dataclasses import replace

import numpy as np

from conftest import fake_field, fake_path, forces, run
from magtact.doe import load_dataset, save_dataset, write_csv
from magtact.study import study_from_dict

R_M0 = 2.5e-3


def radius_path(study, H, theta, *, G=None, mesh=None, t=None, vtu=None):
    """Stand-in forces that grow with the magnet's radius as (R_m / R_m0)²."""
    res = fake_path(study, H, theta, G=G, t=t)
    k = (study.magnet.R_m / R_M0) ** 2
    return replace(res, F_r=res.F_r * k, F_z=res.F_z * k)


def smooth_radius_path(study, H, theta, *, G=None, mesh=None, t=None, vtu=None):
    """Smooth stand-in forces of the displacement (conftest.forces) times (R_m / R_m0)²."""
    res = fake_path(study, H, theta, G=G, t=t)
    f_r, f_z = forces(res.u_r, res.u_z, H)
    k = res.G * (study.magnet.R_m / R_M0) ** 2
    return replace(res, F_r=f_r * k, F_z=f_z * k)


def radius_field(study, t, theta, H, solver="fe"):
    B_r, B_z = fake_field(study, t, theta, H, solver)
    return B_r * study.magnet.R_m / R_M0, B_z * study.magnet.R_m / R_M0


def geometry_study():
    return study_from_dict({"doe": {"n_t": 3, "n_theta": 2, "n_H": 2, "n_G": 2, "n_R_m": 3},
                            "design": {"R_m_mm": [1.5, 3.5]},
                            "metamodel": {"b_model": "exact"}})


def test_one_sub_doe_per_magnet_geometry_joined_along_r_m(tmp_path):
    s = geometry_study()
    ds = run(s, tmp_path, path_solver=radius_path, field_solver=radius_field)
    assert ds["F_z"].dims == ("t", "theta", "H", "G", "R_m")
    assert ds["B_z"].dims == ("t", "theta", "H", "R_m")
    np.testing.assert_allclose(ds["R_m"].values, [1.5e-3, 2.5e-3, 3.5e-3])
    assert ds["R_m"].attrs["units"] == "m"
    assert ds.attrs["run_paths_total"] == 2 * 2 * 3 and ds.attrs["run_fields_computed"] == 3
    # each level holds the sub-study's own solution
    for k, R_m in enumerate(s.geometry_levels["R_m"]):
        sub = run(s.at(R_m=R_m), tmp_path, path_solver=radius_path, field_solver=radius_field)
        for name in ("F_z", "F_r", "B_z", "u_z"):
            np.testing.assert_array_equal(ds[name].isel(R_m=k).values, sub[name].values)
    assert s.to_toml() == ds.attrs["study_toml"]
    again = run(s, tmp_path, path_solver=radius_path, field_solver=radius_field)
    assert again.attrs["run_paths_computed"] == 0  # all from the cache
    back = load_dataset(save_dataset(ds, tmp_path / "g.nc"))
    np.testing.assert_array_equal(back["F_z"].values, ds["F_z"].values)


def test_csv_of_a_geometric_doe_has_the_variable_after_g(tmp_path):
    s = geometry_study()
    ds = run(s, tmp_path, path_solver=radius_path, field_solver=radius_field)
    lines = write_csv(ds, tmp_path / "g.csv").read_text().splitlines()
    assert lines[0].startswith("t,theta_rad,H_mm,G_kPa,R_m_mm,u_r_mm")
    assert len(lines) == 1 + ds["F_z"].size
    assert [float(r.split(",")[4]) for r in lines[1:4]] == [1.5, 2.5, 3.5]


def test_curve_gap_is_zero_on_the_front_and_relative_off_it():
    from magtact.optimise._pareto import curve_gap

    front = np.array([[1.0, 4.0], [2.0, 2.0], [4.0, 1.0]])
    assert curve_gap(front, front) == 0.0
    assert curve_gap(np.array([[1.5, 3.0]]), front) < 1e-12  # on a segment
    assert abs(curve_gap(np.array([[4.4, 1.0]]), front) - 0.1) < 1e-12


def test_geometry_figure_shows_both_sets_and_the_choice(tmp_path):
    from magtact.optimise import DesignSet, GeometricChoice, GeometryOptimisation
    from magtact.report import draw_geometry_pareto, fig_geometry_pareto

    def dset(k):
        v = {"H": np.array([3e-3, 4e-3]) * k, "G": np.array([1e4, 2e4]),
             "M_z": np.array([1.2e6, 1.2e6]), "R_m": np.array([2e-3, 2.5e-3])}
        return DesignSet(v, np.array([10.0, 20.0]) * k, np.array([30.0, 15.0]) * k)

    class Result:  # what the figure reads of a GeometryOptimisation
        variables = ("R_m",)
        pareto, exact = dset(1.0), dset(1.01)
        choice = GeometricChoice({"H": 3e-3, "R_m": 2e-3}, type(
            "D", (), {"Gamma_r_max": 10.0, "Gamma_z_max": 30.0})(), -1.0, -1.0)

    assert {"variables", "pareto", "exact", "choice"} <= set(GeometryOptimisation.__annotations__)
    fig = draw_geometry_pareto(Result())
    objectives, design = fig.axes
    assert objectives.get_xlabel() == r"$\Gamma_{r,\max}$ [N/T]"
    assert design.get_ylabel() == r"magnet radius $R_m$ [mm]"
    lines = {ln.get_label(): ln for ln in objectives.get_lines()}
    np.testing.assert_allclose(lines["NSGA-II"].get_xdata(), [10.0, 20.0])
    np.testing.assert_allclose(lines["exact reduction"].get_ydata(), [30.3, 15.15])
    np.testing.assert_allclose(design.get_lines()[0].get_ydata(), [2.0, 2.5])  # in mm
    files = fig_geometry_pareto(Result(), tmp_path)
    assert {f.suffix for f in files} == {".png", ".svg"}
