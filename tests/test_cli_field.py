"""`magtact field`: files written, field.csv against the geometry of docs/method.md §1, bad
input."""


import numpy as np
import pytest
from typer.testing import CliRunner

from conftest import rel_diff, spec_hall_field
from magtact.cli import app
from magtact.magnetics import CSV_COLUMNS


@pytest.fixture(scope="module")
def outputs(tmp_path_factory):
    root = tmp_path_factory.mktemp("field")
    runs = {}
    for solver in ("fe", "exact"):
        out = root / solver
        result = CliRunner().invoke(app, ["field", "--solver", solver, "--out", str(out)])
        assert result.exit_code == 0, result.output
        runs[solver] = out
    return runs


@pytest.mark.parametrize("solver, tol", [("fe", 2e-3), ("exact", 1e-9)])
def test_field_csv_matches_independent_computation(outputs, solver, tol):
    path = outputs[solver] / "field.csv"
    assert path.read_text().splitlines()[0] == ",".join(CSV_COLUMNS)
    table = np.loadtxt(path, delimiter=",", skiprows=1)
    assert table.shape == (21 * 5 * 5, 5)
    t, theta, H_mm, B_r, B_z = table.T
    # the default study's DOE grid, written out: t in [0, 1], θ in [0, atan 0.45], H in [3, 7] mm
    assert sorted(set(t)) == pytest.approx(np.linspace(0, 1, 21))
    assert sorted(set(theta)) == pytest.approx(np.linspace(0, np.arctan(0.45), 5))
    assert sorted(set(H_mm)) == pytest.approx([3, 4, 5, 6, 7])
    assert rel_diff((B_r, B_z), spec_hall_field(t, theta, H_mm * 1e-3)).max() <= tol


def test_field_figures_written(outputs):
    for suffix in ("png", "svg"):
        f = outputs["fe"] / f"field_maps.{suffix}"
        assert f.stat().st_size > 10_000


@pytest.mark.parametrize("toml, key", [
    ("[magnetics]\nh_magnet_mm = -0.1\n", "[magnetics.h_magnet_mm]"),
    ("[magnetics]\ngrowth_near = 0.5\n", "[magnetics.growth_near]"),
    ("[magnetics]\nnear_mm = 2.0\n", "[magnetics.near_mm]"),
])
def test_bad_study_message_names_key_without_traceback(tmp_path, toml, key):
    study = tmp_path / "bad.toml"
    study.write_text(toml)
    from test_command_outputs import cli  # the command line's entry point, in this process

    code, text = cli("field", study, "--out", tmp_path / "o")
    assert code != 0
    assert key in text and "Traceback" not in text, text
    assert not (tmp_path / "o" / "field.csv").exists()


def test_unknown_solver_option():
    result = CliRunner().invoke(app, ["field", "--solver", "bem", "--out", "unused"])
    assert result.exit_code == 2
    assert "--solver" in result.output
