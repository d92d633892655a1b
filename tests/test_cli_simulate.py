"""`magtact simulate`: files written, forces.csv against the loading path, bad input."""

import re
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
    (root / "stdout.txt").write_text(result.output)
    return out


def test_the_summary_names_the_discretisation(run):
    text = " ".join((run.parent / "stdout.txt").read_text().split())
    assert re.search(r"\d+ DOFs \(coarse mesh, hex8 cells, contact node by node\)", text), text


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


def test_vtu_holds_the_deformed_half_body(run):
    """The VTU: the deformed coarse half body with its displacement; undeformed, it is the body
    of the study (y ≥ 0, radius 6 mm, height H + H_g); the clamped base does not move and the
    nodes of the magnet's cavity moved rigidly with the magnet by (0, 0, −H) = (0, 0, −4 mm)."""
    mesh = meshio.read(run / "deformed_t1.vtu")
    assert [c.type for c in mesh.cells] == ["hexahedron"] and len(mesh.cells[0].data) > 100
    u = mesh.point_data["displacement"]
    np.testing.assert_allclose(mesh.point_data["displacement_magnitude"],
                               np.linalg.norm(u, axis=1))
    x0 = mesh.points - u  # undeformed
    assert x0[:, 1].min() >= -1e-12  # the half body y ≥ 0
    # radius 6 mm (the coarse mesh's outer nodes within 1 % of it)
    assert np.hypot(x0[:, 0], x0[:, 1]).max() == pytest.approx(6e-3, rel=0.01)
    assert x0[:, 2].min() == pytest.approx(0.0, abs=1e-12)
    assert x0[:, 2].max() == pytest.approx(4e-3 + 4.97e-3, rel=1e-9)
    base = x0[:, 2] < 1e-9
    assert base.sum() > 10 and np.abs(u[base]).max() == 0.0
    magnet = np.all(np.abs(u - [0.0, 0.0, -4e-3]) < 1e-12, axis=1)
    assert magnet.sum() > 10
    # the cavity: within the magnet (R_m = 2.5 mm, centre at H + H_g − H_m = 6.97 mm, H_m = 2 mm)
    assert np.hypot(x0[magnet, 0], x0[magnet, 1]).max() <= 1.01 * 2.5e-3
    assert x0[magnet, 2].min() >= 5.97e-3 - 1e-9 and x0[magnet, 2].max() <= 7.97e-3 + 1e-9


def test_figure_shows_the_runs_body_and_numbers(run):
    """The figure's text (matplotlib writes each text of an SVG as a comment): the panels and
    their axes, the colour scale up to the largest displacement, the run's forces."""
    svg = (run / "deformed_body.svg").read_text("utf-8")
    texts = re.findall(r"<!-- (.*?) -->", svg)
    for label in ("half body y ≥ 0, deformed", "section y = 0 (undeformed dashed)", "x [mm]",
                  "y [mm]", "z [mm]", "|u| [mm]"):
        assert label in texts, label
    title = next(t for t in texts if t.startswith("H = 4 mm, θ = 0.000 rad, t = 1"))
    F_z = np.loadtxt(run / "forces.csv", delimiter=",", skiprows=1)[-1, 4]
    assert f"F_z = {F_z:.3g} N (G = 20 kPa)" in title
    # colour scale: the ticks between the section's title and "|u| [mm]" reach max |u| = 4 mm
    ticks = texts[texts.index("section y = 0 (undeformed dashed)") + 1:texts.index("|u| [mm]")]
    ticks = [float(t.replace("−", "-")) for t in ticks]
    u_max = 1e3 * meshio.read(run / "deformed_t1.vtu").point_data["displacement_magnitude"].max()
    step = ticks[1] - ticks[0]
    assert ticks[0] == 0 and 0 <= u_max - ticks[-1] < step and u_max == pytest.approx(4, rel=0.01)
    assert (run / "deformed_body.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_bad_height_is_a_clean_error(tmp_path):
    res = subprocess.run([sys.executable, "-m", "magtact", "simulate", "--H", "-1", "--theta",
                          "0.1", "--out", str(tmp_path / "o")],
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 2
    assert "--H must be between 0.001 and 1000 mm" in res.stderr and "Traceback" not in res.stderr


def test_the_figure_draws_quadratic_cells_by_their_corners(tmp_path):
    """20- and 27-node cells (``mechanics.element``) give the picture of their 8 corners: the
    same pixels as the same points with the corner hexahedra only."""
    from matplotlib.image import imread

    from magtact.geometry import body_mesh
    from magtact.report import fig_deformed_body
    from magtact.study import load_study

    study = load_study(None)
    for i, kw in enumerate(({"order": 2, "serendipity": True}, {"order": 2})):
        m = body_mesh(study, 3e-3, "coarse", **kw)
        u = 0.1 * m.points * [1.0, 0.0, -1.0]
        pictures = []
        for j, cells in enumerate((m.cells, m.cells[:, :8])):
            files = fig_deformed_body(m.points, cells, u, tmp_path / f"body{i}{j}")
            pictures.append(imread(next(f for f in files if f.suffix == ".png")))
        np.testing.assert_array_equal(pictures[0], pictures[1])


@pytest.mark.long
def test_simulate_with_20_node_cells_writes_its_files(tmp_path):
    """``mechanics.element = "hex20"`` with contact over the faces: the VTU holds 20-node cells
    and the figure is drawn (the command read 8-node cells only)."""
    study = tmp_path / "hex20.toml"
    study.write_text(SMALL + 'element = "hex20"\ncontact = "faces"\n')
    out = tmp_path / "out"
    result = CliRunner().invoke(app, ["simulate", str(study), "--H", "4", "--theta", "0",
                                      "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "hex20 cells, contact over the faces" in " ".join(result.output.split())
    mesh = meshio.read(out / "deformed_t1.vtu")
    assert [c.type for c in mesh.cells] == ["hexahedron20"]
    assert (out / "deformed_body.png").stat().st_size > 10_000
