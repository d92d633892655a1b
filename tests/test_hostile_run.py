"""Runs into a folder that holds another run: the report shows only this run's results.

The stages are replaced by stand-ins that write one file named after the study, so that the
report's text tells which run each shown file came from.
"""

from __future__ import annotations

import json
from dataclasses import replace

import pytest

from magtact import pipeline
from magtact.report._html import build_report
from magtact.study import magone


def stand_in_stages(skip_from: str | None = None, interrupt_at: str | None = None):
    """Stages that write ``<key>/<study name>.csv`` (and the chosen design); from ``skip_from``
    on they are skipped, at ``interrupt_at`` the user presses Ctrl-C."""
    keys = [key for key, _, _ in pipeline.STAGES]

    def stage(key):
        def fn(ctx, rec):
            if interrupt_at == key:
                (ctx.folder / key).mkdir(exist_ok=True)
                (ctx.folder / key / "partial.csv").write_text("half,done\n1,2\n")
                raise KeyboardInterrupt
            if skip_from is not None and keys.index(key) >= keys.index(skip_from):
                raise pipeline.StageSkipped("needs an earlier stage, which is missing")
            folder = ctx.folder / key
            folder.mkdir(exist_ok=True)
            name = ctx.study.name
            (folder / f"{name}.csv").write_text(f"study,value\n{name},1\n", encoding="utf-8")
            if key == "optimise":
                (folder / "chosen.json").write_text(json.dumps({"study": name, "H_mm": 3.0}))
            return f"done for {name}"
        return fn

    return tuple((key, title, stage(key)) for key, title, _ in pipeline.STAGES)


def run(tmp_path, name, monkeypatch, **kw):
    monkeypatch.setattr(pipeline, "STAGES", stand_in_stages(**kw))
    return pipeline.run_study(replace(magone(), name=name), tmp_path / "R", log=lambda m: None)


def test_second_study_into_the_same_folder_shows_only_its_results(tmp_path, monkeypatch):
    run(tmp_path, "FirstStudy", monkeypatch)
    first_id = json.loads((tmp_path / "R" / "run.json").read_text())["run_id"]
    html = (tmp_path / "R" / "report.html").read_text()
    assert html.count("<td>FirstStudy</td>") == 5  # a table per tabled stage
    result = run(tmp_path, "SecondStudy", monkeypatch, skip_from="metamodel")
    manifest = json.loads((tmp_path / "R" / "run.json").read_text())
    assert manifest["run_id"] != first_id and manifest["study"] == "SecondStudy"
    html = result.report.read_text()
    assert "FirstStudy" not in html  # no design, table or caption of the first run
    assert "No chosen design" in html
    assert html.count("<td>SecondStudy</td>") == 2  # field and doe
    for key in ("metamodel", "optimise", "validation"):
        assert not (tmp_path / "R" / key).exists()  # the first run's stamped folders are gone
    assert (tmp_path / "R" / "field" / pipeline.RUN_STAMP).read_text() == manifest["run_id"]


def test_interrupted_run_keeps_the_previous_results_and_is_named(tmp_path, monkeypatch):
    run(tmp_path, "FirstStudy", monkeypatch)
    folder = tmp_path / "R"
    before = (folder / "report.html").read_text()
    with pytest.raises(KeyboardInterrupt):
        run(tmp_path, "SecondStudy", monkeypatch, interrupt_at="metamodel")
    assert (folder / "report.html").read_text() == before  # the finished run's report stays
    assert json.loads((folder / "run.json").read_text())["study"] == "FirstStudy"
    html = build_report(folder).read_text()
    assert html.count("<td>FirstStudy</td>") == 5 and "SecondStudy" not in html
    assert "partial.csv" not in html and "half,done" not in html
    assert "<b>Interrupted run.</b>" in html
    assert "interrupted during the stage <i>Metamodels</i> (KeyboardInterrupt)" in html
    assert "finished stages: Magnetic field (ok), Design of experiments (ok)" in html
    run(tmp_path, "ThirdStudy", monkeypatch)  # a complete run replaces both
    html = (folder / "report.html").read_text()
    assert html.count("<td>ThirdStudy</td>") == 5 and "Interrupted run" not in html
    assert not list(folder.glob(".magtact-*-*"))  # no staging folder left


def test_first_run_interrupted_says_there_is_no_complete_run(tmp_path, monkeypatch):
    with pytest.raises(KeyboardInterrupt):
        run(tmp_path, "OnlyStudy", monkeypatch, interrupt_at="field")
    html = build_report(tmp_path / "R").read_text()
    assert "interrupted during the stage <i>Magnetic field</i>" in html
    assert "This folder holds no complete run." in html
    assert "OnlyStudy" not in html


@pytest.mark.parametrize("text", [
    "[1, 2]", "[" * 100_000, '{"stages": [1, "x", null]}', '{"stages": 3}', "\xff",
    '{"stages": [{"key": "doe", "status": 3, "wall_time_s": "x", "notes": 5}], "versions": 3, '
    '"run_id": 7, "wall_time_s": "long"}'])
def test_report_of_a_forged_run_json_is_built(tmp_path, text):
    folder = tmp_path / "R"
    folder.mkdir()
    (folder / "run.json").write_text(text, encoding="utf-8", errors="surrogateescape")
    html = build_report(folder).read_text()
    assert "magtact report" in html and "Run summary" in html
