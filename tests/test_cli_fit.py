"""``magtact fit``: files written, and user errors reported without a traceback."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from conftest import synthetic_doe
from magtact.cli import app
from magtact.doe import save_dataset
from magtact.metamodel import load_models
from magtact.study import load_study


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("fit")
    data = save_dataset(synthetic_doe(load_study(None), n_t=6), tmp / "doe.nc")
    out = tmp / "out"
    result = CliRunner().invoke(app, ["fit", "--data", str(data), "--out", str(out),
                                      "--generations", "3", "--H", "4", "--G", "20"])
    assert result.exit_code == 0, result.output
    return out


def test_fit_writes_models_report_and_figures(fitted):
    models = load_models(fitted)
    for name in ("B_r", "B_z", "f_r", "f_z"):
        data = json.loads((fitted / f"{name}.json").read_text())
        assert data["info"]["settings"]["generations"] == 3
        assert data["info"]["accuracy"]["test"]["n_points"] == 4 * 6
        assert models[name].name == name
    md = (fitted / "metamodels.md").read_text()
    assert "| model | transform | R² (held out)" in md and "## Sensitivity check" in md
    assert md.count("$$") == 8
    for fig in ("force_map", "gamma", "parity"):
        assert (fitted / f"{fig}.png").stat().st_size > 10_000
        assert (fitted / f"{fig}.svg").is_file()


@pytest.mark.parametrize("args, msg", [
    (["fit", "--data", "no/such/doe.nc", "--out", "x"], "DOE data set not found: no/such/doe.nc"),
    (["fit", "nosuchstudy.toml", "--out", "x"], "nosuchstudy.toml"),
])
def test_user_errors_reported_without_traceback(tmp_path, monkeypatch, args, msg):
    from test_command_outputs import cli  # the command line's entry point, in this process

    monkeypatch.chdir(tmp_path)
    code, text = cli(*args)
    assert code == 2
    assert msg in text and "Traceback" not in text, text


def test_generations_must_be_positive():
    result = CliRunner().invoke(app, ["fit", "--generations", "0", "--out", "x"])
    assert result.exit_code == 2 and "generations" in result.output
