"""`magtact run` end to end on the bundled DOE data set (small GP and GA budgets)."""

from __future__ import annotations

import json
import re
from dataclasses import replace
from html import escape

import pytest
from typer.testing import CliRunner

from magtact.cli._app import app
from magtact.study import load_study


def fast_study(tmp_path, **sections):
    """The MagOne study with small metamodel, optimiser and Monte-Carlo budgets (the DOE
    sections unchanged, so the bundled data set applies)."""
    s = load_study(None)
    sections = {"metamodel": replace(s.metamodel, generations=5, population=400, max_length=40,
                                     retries=0, holdout_paths=2),
                "optimise": replace(s.optimise, population=24, ga_generations=3,
                                    nsga2_generations=10, grid_n=4, sweep_n=101),
                "tolerances": replace(s.tolerances, samples=400), **sections}
    s = replace(s, **sections)
    path = tmp_path / "fast.toml"
    path.write_text(s.to_toml(), encoding="utf-8")
    return path


def visible_text(html: str) -> str:
    """The prose a browser shows: styles, scripts, code (``<pre>``, ``<code>``: literal file
    keys and expressions) and tags removed, entities decoded."""
    import html as html_module

    html = re.sub(r"(?is)<(style|script|pre|code)\b.*?</\1>", " ", html)
    return html_module.unescape(re.sub(r"(?s)<[^>]+>", " ", html))


@pytest.fixture(autouse=True)
def small_firmware_sweep(monkeypatch):
    """The run's calibration measures two firmware candidates (the chain, not the sweep)."""
    from magtact import pipeline

    monkeypatch.setattr(pipeline, "RUN_CALIBRATION", {"degrees": (6,), "table_sizes": (32,)})


def check_run(tmp_path, study_file, may_warn=()):
    """Run the study; every stage ok (those of ``may_warn`` ok or warning), every figure
    embedded, report rebuilt from the folder."""
    out = tmp_path / "results"
    result = CliRunner().invoke(app, ["run", str(study_file), "--out", str(out)])
    manifest = json.loads((out / "run.json").read_text())
    statuses = {s["key"]: (s["status"], s["message"]) for s in manifest["stages"]}
    assert all(st == "ok" or (k in may_warn and st == "warning")
               for k, (st, _) in statuses.items()), statuses
    assert result.exit_code == 0, result.output
    html = (out / "report.html").read_text(encoding="utf-8")
    srcs = re.findall(r'<img src="([^"]+)"', html)
    pngs = sorted(out.glob("*/*.png"))
    # every figure of the folder (the designer's figures also lead the report, so some show
    # twice), and the method's drawing of the sensor (SVG)
    png = {s for s in srcs if s.startswith("data:image/png;base64,")}
    assert len(png) >= len(pngs) >= 5
    assert sum(s.startswith("data:image/svg+xml;base64,") for s in srcs) == 1
    assert "No chosen design" not in html and "SYNTHETIC" in html
    assert (out / "validation" / "validation_synthetic.csv").is_file()
    assert (out / "optimise" / "chosen.json").is_file()
    # the design card: at the top of the report, in the terminal, every number in card.json
    card = json.loads((out / "optimise" / "card.json").read_text())
    chosen = json.loads((out / "optimise" / "chosen.json").read_text())
    assert [a["label"] for a in card["answers"]] == ["chosen", "original"]
    assert card["answers"][0]["H_mm"] == pytest.approx(chosen["H_mm"])
    assert html.index('id="card"') < html.index('id="summary"')
    assert all(escape(c) in html for row in card["rows"] for c in row)
    # the terminal ends with the answer: each requirement with its margin, and the parts
    assert all(v["statement"] in result.stdout for v in card.get("verdict", []))
    assert all(f"{k}: " in result.stdout for k, _ in card.get("parts", []))
    assert "report: " in result.stdout
    # the prose a reader sees is in words and units: no file key, no Markdown syntax
    visible = visible_text(html)
    for raw in ("_N_per_T", "_kPa", "None", "**", "!["):
        assert raw not in visible, (raw, visible[max(0, visible.find(raw) - 200):][:400])
    # the report is rebuilt from the folder alone
    (out / "report.html").unlink()
    assert CliRunner().invoke(app, ["report", str(out)]).exit_code == 0
    assert len(re.findall(r"<img ", (out / "report.html").read_text())) == len(srcs)


# an end-to-end run of minutes: the default suite's one run is the browser tests' built run
@pytest.mark.long
def test_run_end_to_end_on_bundled_data(tmp_path):
    from magtact.doe import bundled_path

    if not bundled_path().is_file():
        pytest.skip("the bundled DOE data set is not built yet (python -m magtact.doe.bundle)")
    s = load_study(None)  # real FE data: the exact field for B, a modest GP budget for f
    study_file = fast_study(tmp_path, metamodel=replace(
        s.metamodel, b_model="exact", generations=20, population=400, max_length=40,
        retries=2, holdout_paths=2), optimise=replace(
        s.optimise, population=48, ga_generations=3, nsga2_generations=25, grid_n=4,
        sweep_n=101))  # NSGA-II within the front gap on a short fit
    check_run(tmp_path, study_file)
    # the front door on the run's models chooses what the run chose (one chain)
    import magtact

    out = tmp_path / "results"
    result = magtact.design(study_file, models=out / "metamodel")
    chosen = json.loads((out / "optimise" / "chosen.json").read_text())
    assert result.chosen_design == {
        k: pytest.approx(chosen[k], rel=1e-12) for k in ("H_mm", "G_kPa", "M_z_A_per_m",
                                                         "standoff_mm")}


# an end-to-end run of minutes: the default suite's one run is the browser tests' built run
@pytest.mark.long
def test_run_end_to_end_with_stand_in_doe(tmp_path, monkeypatch):
    """Every stage after the DOE on an analytic stand-in data set (the chain, not the numbers):
    its constraints are set so that the stand-in's forces can meet them."""
    import magtact.doe
    from conftest import synthetic_doe
    from magtact.study import Requirements

    study_file = fast_study(tmp_path, requirements=Requirements(F_r=0.05, F_z=1.0, rate=0.0))
    ds = synthetic_doe(load_study(study_file), n_t=6)
    monkeypatch.setattr(magtact.doe, "bundled_for", lambda study, advice=None: ds)
    # its 5-generation fit of the stand-in is a poor fit, and the stage says so
    check_run(tmp_path, study_file, may_warn=("metamodel",))
