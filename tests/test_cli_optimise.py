"""`magtact optimise` and `magtact compare` with metamodels from known formulas."""

from __future__ import annotations

import csv
import json

import pytest
from typer.testing import CliRunner

from conftest import synthetic_models
from magtact.cli import app, main
from magtact.metamodel import save_models
from magtact.optimise import per_design
from magtact.study import load_study

SMALL = """
base = "magone"
[optimise]
grid_n = 2
sweep_n = 201
nsga2_generations = 30
population = 40
ga_generations = 5
sensor_population = 20
sensor_generations = 10
[tolerances]
robust_samples = 256
design_for = "nominal"
"""
#: The publication's (H, G) problem of the same study (no sensor problem).
SMALL_PUBLICATION = SMALL.replace("[tolerances]", 'problem = "publication"\n[tolerances]', 1)


@pytest.fixture(scope="module")
def model_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("models")
    save_models(synthetic_models(), folder)
    return folder


@pytest.fixture(scope="module")
def small_study(tmp_path_factory):
    path = tmp_path_factory.mktemp("study") / "small.toml"
    path.write_text(SMALL)
    return path


def test_optimise_writes_design_tables_and_figures(tmp_path, model_dir, small_study):
    out = tmp_path / "opt"
    result = CliRunner().invoke(app, ["optimise", str(small_study), "--models", str(model_dir),
                                      "--Frc", "-0.3", "--Fzc", "4", "--out", str(out)])
    assert result.exit_code == 0, result.output
    doc = json.loads((out / "design.json").read_text())
    assert doc["constraints"] == {"F_r_c_N": -0.3, "F_z_c_N": 4.0, "source": "values",
                                  "reference": None}
    chosen = doc["chosen"]
    assert 3 <= chosen["H_mm"] <= 7 and 10 <= chosen["G_kPa"] <= 50
    assert chosen["F_r_min_N"] <= -0.3 and chosen["F_z_max_N"] >= 4.0
    assert set(chosen["active_constraints"]) <= {"F_r", "F_z"}
    with (out / "maps.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 4  # 2 × 2 grid
    # the map row of (3 mm, 10 kPa) is the per-design result there
    d = per_design(synthetic_models(), 3e-3, 10e3, load_study(small_study))
    assert float(rows[0]["F_r_min_N"]) == pytest.approx(d.F_r_min, rel=1e-9)
    for name in ("pareto.csv", "reduction.csv", "pareto_set.png", "maps_objectives.svg",
                 "maps_constraints.png"):
        assert (out / name).is_file()
    # the sensor problem (the default) reads the constraints' forces as its requirements
    assert "Chosen sensor" in result.output and "0–4 N normal" in result.output
    sensor = json.loads((out / "sensor.json").read_text())["chosen"]
    assert 3 <= sensor["H_mm"] <= 7 and sensor["G_kPa"] >= sensor["G_force_kPa"]


def test_constraints_from_a_reference_design(tmp_path, model_dir, small_study):
    out = tmp_path / "ref"
    study = small_study.with_name("publication.toml")
    study.write_text(SMALL_PUBLICATION)
    result = CliRunner().invoke(app, ["optimise", str(study), "--models", str(model_dir),
                                      "--constraints-from", "3,29.4", "--out", str(out)])
    assert result.exit_code == 0, result.output
    c = json.loads((out / "design.json").read_text())["constraints"]
    d = per_design(synthetic_models(), 3e-3, 29.4e3, load_study(small_study))
    assert c["source"] == "reference"
    assert c["F_z_c_N"] == pytest.approx(d.F_z_max, rel=1e-12)
    assert c["reference"]["H_mm"] == 3.0


@pytest.mark.parametrize("args, message", [
    (["--constraints-from", "3"], "--constraints-from must be 'H_MM,G_KPA'"),
    (["--constraints-from", "3,-1"], "H and G must be positive"),
    (["--Frc", "-1", "--constraints-from", "3,29.4"], "not both"),
])
def test_optimise_user_errors(tmp_path, model_dir, small_study, monkeypatch, capsys, args,
                              message):
    monkeypatch.setattr("sys.argv", ["magtact", "optimise", str(small_study), "--models",
                                     str(model_dir), "--out", str(tmp_path), *args])
    with pytest.raises(SystemExit) as exc:
        main()
    assert exc.value.code == 2
    assert message in " ".join(capsys.readouterr().err.split())


def test_an_infeasible_constraint_is_an_answer_with_exit_status_3(tmp_path, model_dir,
                                                                  small_study, monkeypatch,
                                                                  capsys):
    monkeypatch.setattr("sys.argv", ["magtact", "optimise", str(small_study), "--models",
                                     str(model_dir), "--out", str(tmp_path), "--Fzc", "1000"])
    with pytest.raises(SystemExit) as exc:
        main()
    assert exc.value.code == 3
    out = " ".join(capsys.readouterr().out.split())
    assert out.split(": ", 1)[1].startswith("no design meets the requirements ✗"), out
    assert "binds: reads 0–1000 N normal" in out
    assert "relax: the normal force constraint F_z,c [N] = " in out and "(from 1000 N)" in out


def test_compare_prints_percentages(model_dir):
    result = CliRunner().invoke(app, ["compare", "4,20", "4,30", "--models", str(model_dir)])
    assert result.exit_code == 0, result.output
    assert result.output.count("+50.00") == 8  # every quantity scales with G, σ_F too
    bad = CliRunner().invoke(app, ["compare", "4", "4,30", "--models", str(model_dir)])
    assert "first design must be 'H_MM,G_KPA'" in str(bad.exception)


def test_write_optimise_outputs_for_the_report(tmp_path, small_study):
    from magtact.optimise import optimise, write_optimise_outputs

    result = optimise(synthetic_models(), load_study(small_study))
    files = write_optimise_outputs(result, synthetic_models(), tmp_path)
    assert sorted(files) == sorted(p for p in tmp_path.iterdir() if p.is_file())
    choice = result.choice
    chosen = json.loads((tmp_path / "chosen.json").read_text())
    assert chosen["H_mm"] == pytest.approx(choice.design.H * 1e3, rel=1e-12)
    assert chosen["active_constraints"] == (", ".join(choice.active) or "none")
    captions = json.loads((tmp_path / "captions.json").read_text())
    stems = {p.stem for p in tmp_path.iterdir() if p.suffix in (".png", ".csv")}
    assert stems <= set(captions)  # every figure and table has its caption
