"""The one chain from a study to its answer: ``magtact.design``, ``magtact optimise`` and the
pipeline's optimisation stage give the same chosen design, for (H, G), with the magnetisation
and with a geometric design variable; the result object evaluates any design; NSGA-II applies
every constraint the exact reduction applies (the chip's range included, over the geometry)."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from typer.testing import CliRunner

import magtact
from magtact.cli._app import app
from magtact.metamodel import prefitted_dir, save_models
from magtact.study import load_study, study_from_dict
from test_geometry_batch import SMALL, radius_models

#: Small optimiser budgets: the chain, not the optimiser's accuracy, is under test here.
pytestmark = pytest.mark.filterwarnings("ignore::magtact.optimise.FrontGapWarning")

FAST = {"population": 24, "nsga2_generations": 12, "grid_n": 2, "sweep_n": 61,
        "sweep_coarse": 9}


def _chosen_json(folder):
    return json.loads((folder / "design.json").read_text())["chosen"]


def _same_design(result, chosen: dict):
    for key, value in result.chosen_design.items():
        assert value == pytest.approx(chosen[key], rel=1e-9), key


def test_the_chain_has_one_definition():
    """Every caller reaches the optimiser through ``solve``: no other module calls
    ``optimise`` or ``optimise_geometry`` (commands that answer for one named design call
    ``designer.answer`` directly)."""
    import ast
    from pathlib import Path

    src = Path(magtact.__file__).parent
    callers = {}
    for path in src.rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.Call):
                f = node.func
                name = f.id if isinstance(f, ast.Name) else getattr(f, "attr", None)
                if name in ("optimise", "optimise_geometry"):
                    callers.setdefault(name, set()).add(path.relative_to(src).as_posix())
    assert callers["optimise"] == {"_front.py"}
    assert callers["optimise_geometry"] == {"_front.py"}


@pytest.fixture(scope="module")
def magone(tmp_path_factory):
    """The publication's problem on MagOne with small optimiser budgets, through the front
    door (the sensor problem: tests/test_sensor.py)."""
    s = load_study("magone-publication")
    s = replace(s, optimise=replace(s.optimise, **FAST))
    path = tmp_path_factory.mktemp("magone") / "study.toml"
    path.write_text(s.to_toml(), encoding="utf-8")
    return path, magtact.design(path, models=prefitted_dir())


@pytest.fixture(scope="module")
def chain_budgets(magone):
    """The error budgets of ``magone``'s result, computed once for the module's cards."""
    return magtact.error_budgets(magone[1])


@pytest.mark.long  # over a minute: the sensor problem solved again with M_z as a variable
def test_design_with_the_magnetisation_as_a_design_variable(tmp_path, magone):
    path, hg = magone
    s = load_study(path)
    s = replace(s, design=replace(s.design, M_z=(0.9e6, 1.3e6)))
    result = magtact.design(s, models=prefitted_dir())
    assert set(result.chosen_design) == {"H_mm", "G_kPa", "M_z_A_per_m"}
    M = result.variables["M_z"]
    assert 0.9e6 <= M <= 1.3e6 and result.chosen.design.M_z == M
    # Γ ∝ G / M_z: the chosen design at its own magnetisation, evaluated again
    again = result.evaluate(H_mm=result.chosen_design["H_mm"],
                            G_kPa=result.chosen_design["G_kPa"], M_z_A_per_m=M)
    assert again.design.Gamma_z_max == pytest.approx(result.chosen.design.Gamma_z_max,
                                                     rel=1e-12)
    budgets = magtact.error_budgets(result)
    assert any(row[0].startswith("magnetisation")
               for row in magtact.card(result, budgets)["rows"])
    assert result.original.design.Gamma_z_max == pytest.approx(
        hg.original.design.Gamma_z_max, rel=1e-12)  # the original keeps the magnet's own M_z
    magtact.write_results(result, tmp_path / "design", budgets=budgets)
    assert _chosen_json(tmp_path / "design")["M_z_A_per_m"] == pytest.approx(M, rel=1e-12)
    # the run's optimisation stage on the same models chooses the same design
    from magtact import pipeline

    ctx = pipeline._Context(study=s, folder=tmp_path / "run", recompute=False, refit=False,
                            data=None, cache=None, workers=None, log=lambda m: None,
                            models=result.models)
    pipeline._stage_optimise(ctx, pipeline.StageRecord("optimise", "Optimisation"))
    assert ctx.result.variables == result.variables


def test_optimise_command_equals_design(tmp_path, magone, chain_budgets):
    path, result = magone
    run = CliRunner().invoke(app, ["optimise", str(path), "--models", str(prefitted_dir()),
                                   "--out", str(tmp_path)])
    assert run.exit_code == 0, run.output
    _same_design(result, _chosen_json(tmp_path))
    shown = magtact.card(result, chain_budgets)["rows"]
    assert json.loads((tmp_path / "card.json").read_text())["rows"] == shown


def _geo_study(tmp_path, **constraints):
    data = {"design": {"R_m_mm": [2.0, 3.0]}, "metamodel": {"b_model": "exact"},
            "optimise": SMALL | {"population": 12, "nsga2_generations": 6, "geometry_n": 3,
                                 "sweep_n": 5, "sweep_coarse": 3, "start_t": 5,
                                 "start_theta": 3, "tol": 1e-7},
            "constraints": {"source": "values", "F_r_c_N": -0.02, "F_z_c_N": 0.2}
            | constraints}
    s = study_from_dict(data)
    path = tmp_path / "geo.toml"
    path.write_text(s.to_toml(), encoding="utf-8")
    folder = tmp_path / "models"
    save_models(radius_models(s), folder)
    return s, path, folder


def test_geometric_design_equals_the_pipeline_and_reads_within_the_chip(tmp_path):
    """A geometric study with ``chip_range`` and a chip range that the strongest-field designs
    exceed: the front door (models read back from their files) and the pipeline choose the
    same design, and every design of NSGA-II's set reads within the range over its stable
    region, as the exact front does."""
    from magtact import Sensor, pipeline
    from magtact.designer import answer
    from magtact.optimise import chip_margin, per_design

    s, _, folder = _geo_study(tmp_path, chip_range=True)
    models = radius_models(s)
    R_hi, H_lo = 3e-3, s.design.H[0]  # the widest magnet, closest to the chip
    at = s.at(R_m=R_hi)
    strong = answer(models.at(R_m=R_hi), at, Sensor.of_study(at, H_lo, 20e3)).saturation
    limit = 0.8 * max(strong.B_max_x, strong.B_max_z)
    s = replace(s, hall=replace(s.hall, range_x=limit, range_z=limit))
    assert chip_margin(s.at(R_m=R_hi), [H_lo], [1.0], [s.loading.theta_max])[0] > 0

    result = magtact.design(s, models=folder)
    assert set(result.chosen_design) == {"H_mm", "G_kPa", "R_m_mm"}
    ctx = pipeline._Context(study=s, folder=tmp_path / "run", recompute=False, refit=False,
                            data=None, cache=None, workers=None, log=lambda m: None,
                            models=models)
    pipeline._stage_optimise(ctx, pipeline.StageRecord("optimise", "Optimisation"))
    assert ctx.result.variables == result.variables
    choice = json.loads((tmp_path / "run" / "optimise" / "geometry.json").read_text())["choice"]
    assert choice["design"] == magtact.optimise.describe(result.optimisation.choice.values)
    assert choice["Gamma_r_max_N_per_T"] == result.chosen.design.Gamma_r_max

    p = result.pareto
    assert len(p) > 0
    for i in range(len(p)):
        v = p.design(i)
        sub = s.at(R_m=v["R_m"])
        d = per_design(models.at(R_m=v["R_m"]), v["H"], v["G"], sub)
        assert chip_margin(sub, d.H, d.t_m, d.theta_m)[0] <= 1e-9
    assert result.chosen.saturation.region_margin <= 1e-9
    assert np.isfinite(result.optimisation.gap)
    # the answer at the chosen geometry is the answer of the sub-study at that geometry
    again = result.evaluate(H_mm=result.chosen_design["H_mm"],
                            G_kPa=result.chosen_design["G_kPa"],
                            R_m_mm=result.chosen_design["R_m_mm"])
    assert again.design.Gamma_r_max == pytest.approx(result.chosen.design.Gamma_r_max,
                                                     rel=1e-9)


def test_every_model_kind_is_a_response(models):
    """The fitted models, the exact field and a composed force share one interface."""
    from magtact.metamodel import ExactField, Response

    s = load_study("magone")
    kinds = [models.B_r, models.f_z, ExactField(s, "B_z"),
             radius_models(study_from_dict({"design": {"R_m_mm": [2.0, 3.0]},
                                            "metamodel": {"b_model": "exact"}})).f_r]
    for m in kinds:
        assert isinstance(m, Response), type(m)
        v = m.value(0.5, 0.2, 3e-3, **({"R_m": 2.5e-3} if getattr(m, "geometry", ()) else {}))
        jet = m.jet(0.5, 0.2, 3e-3, 1, **({"R_m": 2.5e-3} if getattr(m, "geometry", ()) else {}))
        assert np.isfinite(v) and jet[0] == pytest.approx(v, rel=1e-12)
    assert not isinstance(object(), Response)


def test_the_result_budgets_its_designs(magone):
    """The result's budget is the budget of its design (same rows as the budget package's
    function on the same models and design); a noise given replaces the chip's own."""
    from magtact.budget import error_budget, noise_given

    _, result = magone
    b = magtact.error_budget(result, result.original, noise=(1e-6, 1e-6))
    a = result.original
    ref = error_budget(result.models, result.study, a.H, a.G, label="original",
                       chip=noise_given(a.chip, (1e-6, 1e-6))[0])
    assert b.noise_source.startswith("given as 1, 1 µT (x, z), in place of")
    assert b.label == "original" and [r.name for r in b.rows] == [r.name for r in ref.rows]
    np.testing.assert_allclose([r.worst for r in b.rows], [r.worst for r in ref.rows],
                               rtol=1e-12)


def test_the_result_carries_the_chosen_designs_sensor_map(magone):
    """``magtact.force_map(result)`` maps the chosen design's field readings to forces and
    back; the calibration uses the chip at the chosen design's setting."""
    _, result = magone
    F = np.array([[0.1, 0.0, 2.0], [0.0, -0.05, 1.0], [0.0, 0.0, 0.5]])
    smap = magtact.force_map(result)
    B, flags = smap.field(F)
    assert not flags.any()
    back = smap.force(B)
    np.testing.assert_allclose(back.F, F, atol=1e-9 * np.abs(F).max())
    assert (smap.H, smap.G) == (result.chosen.H, result.chosen.G)


def test_result_write_keeps_the_users_files_and_replaces_its_own(tmp_path, magone,
                                                                  chain_budgets):
    """``magtact.write_results`` follows the results folder's rules: its own files are written
    again, a user's file of an output's name is kept byte for byte and named in the refusal."""
    _, result = magone

    def write():
        return magtact.write_results(result, folder, figures=False, budget=False,
                                     budgets=chain_budgets)

    folder = tmp_path / "design"
    files = write()
    assert {p.parent for p in files} == {folder} and all(p.is_file() for p in files)
    card = folder / "card.json"
    assert json.loads(card.read_text())["rows"]
    assert write()  # its own files: replaced
    card.write_text("my notes\n")
    with pytest.raises(magtact.MagtactError, match=r"card\.json"):
        write()
    assert card.read_text() == "my notes\n"
