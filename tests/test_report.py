"""HTML report built from a results folder, and the run orchestration's bookkeeping."""

from __future__ import annotations

import base64
import html
import json
import re

import matplotlib.pyplot as plt
import pytest
from typer.testing import CliRunner

from magtact import pipeline
from magtact.cli._app import app
from magtact.report import save
from magtact.report._html import MAX_ROWS, build_report
from magtact.study import load_study


def png(path):
    fig, ax = plt.subplots(figsize=(2, 1.5))
    ax.plot([0, 1], [0, 1])
    return save(fig, path, formats=("png",))[0]


def results_folder(tmp_path):
    """A folder as a run leaves it: doe ok with a figure and a table, optimise failed."""
    folder = tmp_path / "res"
    (folder / "doe").mkdir(parents=True)
    png(folder / "doe" / "forces")
    rows = "\n".join(f"{k},{k * 0.5}" for k in range(MAX_ROWS + 5))
    (folder / "doe" / "table.csv").write_text("a,b\n" + rows + "\n", encoding="utf-8")
    (folder / "doe" / "captions.json").write_text(json.dumps({"forces": "F over <t>"}))
    (folder / "study.toml").write_text('name = "MagOne"\n', encoding="utf-8")
    manifest = {"study": "MagOne", "command": "magtact run", "started": "now", "wall_time_s": 3.0,
                "versions": {"numpy": "9.9"},
                "stages": [{"key": "doe", "title": "DOE", "status": "ok", "wall_time_s": 1.5,
                            "message": "done", "notes": []},
                           {"key": "optimise", "title": "Optimisation", "status": "failed",
                            "wall_time_s": 0.1, "message": "RuntimeError: boom", "notes": []}]}
    (folder / "run.json").write_text(json.dumps(manifest), encoding="utf-8")
    return folder


def test_report_embeds_figures_and_reports_absent_and_failed_stages(tmp_path):
    folder = results_folder(tmp_path)
    text = build_report(folder).read_text(encoding="utf-8")
    imgs = re.findall(r'<img src="(data:image/png[^"]+)"', text)  # the method's drawing is SVG
    assert len(imgs) == 1 and imgs[0].startswith("data:image/png;base64,")
    decoded = base64.b64decode(imgs[0].split(",", 1)[1])
    assert decoded == (folder / "doe" / "forces.png").read_bytes()
    assert "F over &lt;t&gt;" in text  # caption from captions.json, escaped
    assert "5 more rows in table.csv" in text
    assert "RuntimeError: boom" in text and 'class="l failed"' in text
    # field, metamodel, optimise, calibration, validation (the budget says so in its own words)
    assert text.count("No results for this stage") == 5 and "No error budget" in text
    assert "No chosen design" in text and "No benchmark results" in text
    assert "numpy" in text
    assert '<td class="l"><code>name</code></td><td class="l">MagOne</td>' in text
    assert "SYNTHETIC" not in text


def test_report_labels_synthetic_validation(tmp_path):
    folder = results_folder(tmp_path)
    (folder / "validation").mkdir()
    (folder / "validation" / "validation_synthetic.csv").write_text("data,response\n"
                                                                    "synthetic,B_r\n")
    text = build_report(folder).read_text(encoding="utf-8")
    assert "SYNTHETIC validation data" in text
    assert "validation synthetic (SYNTHETIC data)" in text


def test_report_of_missing_folder_is_an_error(tmp_path):
    with pytest.raises(FileNotFoundError, match="nothere"):
        build_report(tmp_path / "nothere")


def test_report_command_rebuilds_html(tmp_path):
    folder = results_folder(tmp_path)
    result = CliRunner().invoke(app, ["report", str(folder)])
    assert result.exit_code == 0, result.output
    assert (folder / "report.html").is_file()


def test_run_records_ok_failed_and_skipped_stages(tmp_path, monkeypatch):
    """The orchestration never hides a failure: statuses, messages and tracebacks are kept."""

    def ok(ctx, rec):
        png(ctx.folder / "field" / "map")
        ctx.dataset = "data"
        return "one map"

    def boom(ctx, rec):
        raise RuntimeError("solver diverged at t = 0.4")

    def needs(ctx, rec):
        if ctx.models is None:
            raise pipeline.StageSkipped("needs the metamodels, which are missing")
        return "unreachable"

    monkeypatch.setattr(pipeline, "STAGES", (("field", "Field", ok),
                                             ("metamodel", "Metamodels", boom),
                                             ("optimise", "Optimisation", needs)))
    result = pipeline.run_study(load_study(None), tmp_path / "out", log=lambda m: None)
    assert [s.status for s in result.stages] == ["ok", "failed", "skipped"]
    assert not result.ok
    manifest = json.loads((tmp_path / "out" / "run.json").read_text())
    assert [s["status"] for s in manifest["stages"]] == ["ok", "failed", "skipped"]
    assert manifest["stages"][1]["message"] == "RuntimeError: solver diverged at t = 0.4"
    assert "solver diverged" in (tmp_path / "out" / "logs" / "metamodel.traceback.txt").read_text()
    assert load_study(tmp_path / "out" / "study.toml") == load_study(None)
    text = result.report.read_text(encoding="utf-8")
    assert "solver diverged at t = 0.4" in text and "needs the metamodels" in text
    assert text.count('<img src="data:image/png') == 1  # the stage's figure (not the method's)


def visible(html_text: str) -> str:
    """The text a browser shows: tags stripped, entities decoded."""
    return html.unescape(re.sub(r"<[^>]+>", "", html_text))


def test_markdown_headings_tables_code_emphasis_links_lists_and_math():
    from magtact.report._markdown import render_markdown

    out = render_markdown("# Title\n\nsome `x<1` **bold** *it* [a link](https://x.org) text\n"
                          "continued\n\n- one\n- two\n\n| a | b |\n|---|---|\n| 1 | 2 |\n"
                          "\n$$\nB_{r} = t^2 * x_1\n$$\n```\ncode & more\n```\n"
                          "<script>x</script>\n")
    assert '<h3>Title</h3>' in out
    assert "<code>x&lt;1</code>" in out and "<strong>bold</strong>" in out
    assert "<em>it</em>" in out and '<a href="https://x.org">a link</a>' in out
    assert "<li>one</li>" in out and "<li>two</li>" in out
    assert re.search(r"<th>a</th>\s*<th>b</th>", out) and re.search(r"<td>1</td>\s*<td>2</td>", out)
    # math as MathML (the browser renders it, offline), no emphasis, no LaTeX source left
    assert '<math xmlns="http://www.w3.org/1998/Math/MathML" display="block">' in out
    assert "<msup><mi>t</mi><mn>2</mn></msup>" in out and "B_{r}" not in out
    assert "code &amp; more" in out
    assert "<script>" not in out  # raw HTML is escaped


def test_markdown_images_embedded_or_shown_as_text():
    from magtact.report._markdown import render_markdown

    out = render_markdown("![a drawing](d.svg) and ![gone](missing.png)",
                          images=lambda src: b"<svg/>" if src == "d.svg" else None)
    assert 'src="data:image/svg+xml;base64,PHN2Zy8+"' in out and 'alt="a drawing"' in out
    assert "[image: gone]" in visible(out) and "missing.png" not in out


def test_method_appendix_renders_markdown_images_and_internal_links():
    """The method document in the report: no Markdown syntax left in the visible text, the
    sensor drawing embedded, every internal link pointing at a heading of the appendix."""
    from magtact.report._html import _method

    out = _method()
    text = visible(out)
    for syntax in ("**", "![", "](#", "]("):
        assert syntax not in text, syntax
    svg = re.search(r'<img src="data:image/svg\+xml;base64,([^"]+)" alt="([^"]+)"', out)
    assert svg and svg.group(2) == "The sensor in the plane of shear"
    assert base64.b64decode(svg.group(1)).lstrip().startswith((b"<?xml", b"<svg"))
    assert "<strong>Coordinates.</strong>" in out and "<em>Figure: the cross-section" in out
    ids = set(re.findall(r'id="(method-[^"]+)"', out))
    links = re.findall(r'href="#([^"]+)"', out)
    assert len(links) >= 10 and set(links) <= ids
    assert "<table>" in out and "<math " in out and "\\frac" not in out


def test_evidence_json_with_a_convergence_study_becomes_a_table(tmp_path):
    folder = results_folder(tmp_path)
    bench = tmp_path / "bench"
    bench.mkdir()
    (bench / "conv.json").write_text(json.dumps({
        "study": "MagOne", "target": 0.02,
        "refinement": [{"h_mm": 0.5, "err": 0.1}, {"h_mm": 0.25, "err": 0.03, "rate": 1.7}]}))
    text = build_report(folder, evidence=bench).read_text(encoding="utf-8")
    assert "No benchmark results" not in text
    assert ("<tr><th>h [mm]</th><th>err</th><th>rate</th></tr><tr><td>0.500</td><td>0.100</td>"
            "<td></td></tr><tr><td>0.250</td><td>0.0300</td><td>1.70</td></tr>") in text


def test_force_map_draws_the_optimisers_stable_shear_box(monkeypatch):
    """The star sits at the optimiser's (t_m, θ_m) and the title quotes its F_r,min."""
    import numpy as np

    from magtact.metamodel import load_models, prefitted_dir
    from magtact.optimise import per_design
    from magtact.report import _fig_metamodel as fm

    study = load_study("magone")
    models = load_models(prefitted_dir())
    H, G = 3e-3, 29.4e3
    design = per_design(models, H, G, study)
    seen = {}
    monkeypatch.setattr(fm, "save", lambda fig, path: seen.setdefault("fig", fig) and [])
    fm.fig_force_map(models, study, H, G, "unused")
    ax = seen["fig"].axes[0]
    stars = [ln for ln in ax.get_lines() if ln.get_marker() == "*"]
    assert len(stars) == 1
    np.testing.assert_allclose([stars[0].get_xdata()[0], stars[0].get_ydata()[0]],
                               [design.t_m, np.degrees(design.theta_m)], rtol=1e-12)
    assert f"{design.F_r_min:.3g} N" in seen["fig"]._suptitle.get_text()
    assert ax.get_xlabel() == "load $t$ [-]"
