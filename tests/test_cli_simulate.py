"""`magtact simulate`: files written, forces.csv against the loading path, bad input."""

import subprocess
import sys

import meshio
import numpy as np
import pytest
from typer.testing import CliRunner

from magtact.cli import app

SMALL = 'base = "magone"\n[doe]\nn_t = 3\n[mechanics]\nmesh = "coarse"\n'


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    root = tmp_path_factory.mktemp("simulate")
    study = root / "small.toml"
    study.write_text(SMALL)
    out = root / "out"
    result = CliRunner().invoke(app, ["simulate", str(study), "--H", "4", "--theta", "0",
                                      "--G", "20", "--out", str(out)])
    assert result.exit_code == 0, result.output
    return out


def test_forces_csv(run):
    lines = (run / "forces.csv").read_text().splitlines()
    assert lines[0] == "t,u_r_mm,u_z_mm,F_r_N,F_z_N"
    t, u_r, u_z, F_r, F_z = np.loadtxt(run / "forces.csv", delimiter=",", skiprows=1).T
    np.testing.assert_allclose(t, [0, 0.5, 1])
    # docs/method.md §1 with the default body: u_z = t (Δz_sat + H_m − H − H_g) = −t·H, u_r = 0
    np.testing.assert_allclose(u_z, [0.0, -2.0, -4.0], atol=1e-9)
    np.testing.assert_array_equal(u_r, 0.0)
    assert F_z[0] == 0 and np.all(np.diff(F_z) > 0)
    assert np.all(np.abs(F_r) <= 1e-6 * F_z[-1])


def test_vtu_and_figure(run):
    mesh = meshio.read(run / "deformed_t1.vtu")
    u = mesh.point_data["displacement"]
    np.testing.assert_allclose(mesh.point_data["displacement_magnitude"],
                               np.linalg.norm(u, axis=1))
    # the magnet (and with it the largest displacement) moved by |u| = H = 4 mm
    assert mesh.point_data["displacement_magnitude"].max() == pytest.approx(4e-3, rel=0.05)
    for suffix in ("png", "svg"):
        assert (run / f"deformed_body.{suffix}").stat().st_size > 10_000


def test_bad_height_is_a_clean_error(tmp_path):
    res = subprocess.run([sys.executable, "-m", "magtact", "simulate", "--H", "-1", "--theta",
                          "0.1", "--out", str(tmp_path / "o")],
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 2
    assert "--H must be between 0.001 and 1000 mm" in res.stderr and "Traceback" not in res.stderr
