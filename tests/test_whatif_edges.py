"""Honest edges: no answer outside the data's domain, and a poor fit is said on the stage, the
card and the command line."""

import math
from dataclasses import replace

import pytest
from typer.testing import CliRunner

from magtact import MagtactError
from magtact._front import Result
from magtact._outputs import _extra_rows
from magtact.cli import app
from magtact.doe import check_design, domain_of, load_bundled
from magtact.metamodel import (
    POOR_OVER_RANGE,
    POOR_R2,
    Selection,
    fit_models,
    fit_quality,
    fit_quality_rows,
    select_metamodels,
)
from magtact.study import magone

OUTSIDE = "lies outside the domain of the data its answer rests on (H ∈ [3, 7] mm"


@pytest.fixture(scope="module")
def ds():
    return load_bundled()


@pytest.fixture(scope="module")
def result(ds):
    """A result of the MagOne study on its shipped models (what evaluate needs)."""
    s = magone()
    return Result(s, select_metamodels(s, ds).models, "shipped", None, None, None, {},
                  dataset=ds)


@pytest.mark.parametrize("H_mm", [100.0, 12.0, 2.9, 7.01, math.nan])
def test_designs_outside_the_data_are_refused_naming_the_domain(ds, H_mm):
    with pytest.raises(MagtactError, match=r"the design's H = .* mm " + OUTSIDE.replace(
            "(", r"\(").replace("[", r"\[")):
        check_design(magone(), H_mm * 1e-3, ds)


@pytest.mark.parametrize("H_mm", [3.0, 5.0, 7.0, 7.0 * (1 + 1e-12)])
def test_designs_inside_the_data_pass(ds, H_mm):
    check_design(magone(), H_mm * 1e-3, ds)


def test_the_domain_is_the_design_range_within_the_data(ds):
    s = magone()
    narrow = replace(s, design=replace(s.design, H=(4e-3, 6e-3), H_original=4e-3))
    assert domain_of(narrow, ds).H == (4e-3, 6e-3)
    wide = replace(s, design=replace(s.design, H=(2e-3, 9e-3)))
    assert domain_of(wide, ds).H == (3e-3, 7e-3)  # the data's heights bound it
    assert domain_of(wide).H == (2e-3, 9e-3)


@pytest.mark.parametrize("H_mm", [100.0, 12.0])
def test_every_python_entry_point_refuses(result, ds, H_mm):
    from magtact import Sensor
    from magtact.budget import error_budget
    from magtact.calibration import calibrate, sensor_map
    from magtact.designer import answer
    from magtact.optimise import force_constraints

    H = H_mm * 1e-3
    calls = [lambda: result.evaluate(H_mm=H_mm, G_kPa=29.4),
             lambda: answer(result.models, result.study, Sensor.of_study(result.study, H, 29.4e3)),
             lambda: error_budget(result.models, result.study, H, 29.4e3, dataset=ds),
             lambda: sensor_map(result.models, result.study, H, 29.4e3),
             lambda: calibrate(result.models, result.study, H, 29.4e3, noise=(1e-7, 1e-7)),
             lambda: force_constraints(result.models, result.study, reference=(H, 29.4e3))]
    for call in calls:
        with pytest.raises(MagtactError, match=f"H = {H_mm:g} mm lies outside"):
            call()


@pytest.mark.parametrize("args", [
    ["budget", "--H", "100", "--G", "22.57"],
    ["budget", "--H", "12", "--G", "29.4"],
    ["compare", "12,29.4", "4,30"],
    ["compare", "4,29.4", "100,30"],
])
def test_the_commands_refuse(args):
    out = CliRunner().invoke(app, args)
    assert out.exit_code != 0
    text = " ".join((out.output + str(out.exception or "")).split())
    assert "lies outside the domain of the data" in text and "H ∈ [3, 7] mm" in text


def test_calibrate_command_refuses(tmp_path):
    out = CliRunner().invoke(app, ["calibrate", "--H", "12", "--G", "29.4", "--out",
                                   str(tmp_path / "cal"), "--noise-uT", "0.1"])
    assert out.exit_code != 0
    text = " ".join((out.output + str(out.exception or "")).split())
    assert "H = 12 mm lies outside the domain of the data" in text


@pytest.fixture(scope="module")
def short_fit(ds):
    """A deliberately short fit: one generation of 20 programs, no local search."""
    s = magone()
    s = replace(s, metamodel=replace(s.metamodel, generations=1, population=20, retries=0,
                                     local_iterations=0))
    return s, fit_models(ds, s)


def test_the_shipped_fit_is_not_poor(result):
    q = fit_quality(result.models)
    assert not q.is_poor and set(q.held_out) == {"B_r", "B_z", "f_r", "f_z"}
    assert fit_quality_rows(result.models, 2) == []


def test_a_short_fit_is_poor_on_the_selection_and_the_card(short_fit):
    s, fit = short_fit
    sel = Selection(fit.model_set(s), None, fit)
    assert sel.poor_fit
    for name in sel.quality.poor:  # each named model breaks a threshold
        r2, over, _ = sel.quality.held_out[name]
        assert r2 < POOR_R2 or over > POOR_OVER_RANGE
    assert "poor fit" in sel.source
    rows = fit_quality_rows(sel.models, 2)
    assert len(rows) == 1 and len(rows[0]) == 3 and rows[0][1].startswith("poor fit")
    # the card's rows after the answers' (magtact.card, card.json) carry it
    extra = _extra_rows(sel.models, None)
    assert extra == rows


def test_a_short_fit_turns_the_metamodel_stage_to_a_warning(ds, short_fit, tmp_path,
                                                            monkeypatch):
    from magtact import pipeline

    s, _ = short_fit
    ctx = pipeline._Context(study=s, folder=tmp_path, recompute=False, refit=True, data=None,
                            cache=None, workers=None, log=lambda m: None, dataset=ds)
    monkeypatch.setattr(pipeline, "STAGES", [("metamodel", "Metamodels",
                                              pipeline._stage_metamodel)])
    from magtact._runfolder import RunManifest

    manifest = RunManifest(run_id="test", study=s.name, command="test", started=None)
    (rec,) = pipeline._run_stages(ctx, "test", manifest, 0.0)
    assert rec.status == "warning"
    assert any(n.startswith("WARNING: the answer rests on a poor fit") for n in rec.notes)


def test_the_fit_command_says_a_short_fit_is_poor(tmp_path):
    study = tmp_path / "short.toml"
    study.write_text('base = "magone"\n[metamodel]\ngenerations = 1\npopulation = 20\n'
                     'retries = 0\nlocal_iterations = 0\n')
    out = CliRunner().invoke(app, ["fit", str(study), "--out", str(tmp_path / "fit")])
    assert out.exit_code == 0, out.output
    text = " ".join(out.output.split())
    assert "warning: the answer rests on a poor fit" in text
