"""How the answer reads: the last screen of ``magtact run`` in an 80 × 24 pseudo-terminal, and
every object a user gets printed in at most 25 lines of at most 100 characters and shown in a
notebook (``_repr_html_``), with its verdict where it has one."""

from __future__ import annotations

import math
import os
import re
import struct
import subprocess
import sys
import textwrap

import pytest

from magtact._display import MAX_LINES, MAX_WIDTH

#: What a terminal's escape sequences look like (colour, bold, cursor).
ANSI = re.compile(r"\x1b\[[0-?]*[ -/]*[@-~]|\x1b\][^\x07]*\x07")


# ---- every object a user gets ------------------------------------------------------------------
@pytest.fixture(scope="module")
def objects(magone_design, magone_budgets, tmp_path_factory):
    """Every public object of an answer, by name: the result and what it holds, an evaluation,
    a budget, a calibration, the sensor map, the study, a run's result and the answer to a
    specification no design meets."""
    import magtact
    from magtact._runfolder import StageRecord
    from magtact.designer import Infeasible, Relaxation, Requirement
    from magtact.pipeline import RunResult

    r = magone_design
    folder = tmp_path_factory.mktemp("run")
    card = magtact.card(r, magone_budgets)
    run = RunResult(folder, folder / "report.html",
                    (StageRecord(key="field", title="Magnetic field", status="ok",
                                 message="3 files " + "x" * 200, wall_time_s=5.4),),
                    44.2, answer=dict(card))
    infeasible = Infeasible(
        (Requirement("normal", False, "reads 0–3 N normal without saturating",
                     "no: up to 9.05 N alone, not with 0.5 N shear", math.nan, "N"),
         Requirement("shear", False, "carries and reads 0–0.5 N shear",
                     "no: up to 0.323 N with 3 N normal", -0.177, "N")),
        "shear", Relaxation("shear", 0.5, 0.323, "N", "requirements.F_r_N"), "why", "tiny")
    return {"result": r, "study": r.study, "chosen": r.chosen, "original": r.original,
            "parts": r.chosen.parts, "verdict": r.chosen.verdict,
            "evaluation": r.evaluate(H_mm=4.0, G_kPa=30.0), "card": card,
            "budget": magone_budgets[0], "sensor": r.sensor, "force_map": magtact.force_map(r),
            "calibration": magtact.calibrate(r, degrees=(8,), table_sizes=(16,)), "run": run,
            "infeasible": infeasible}


NAMES = ("result", "study", "chosen", "original", "parts", "verdict", "evaluation", "card",
         "budget", "sensor", "force_map", "calibration", "run", "infeasible")


@pytest.mark.parametrize("name", NAMES)
def test_every_object_prints_in_25_lines_of_100_characters(objects, name):
    obj = objects[name]
    text = str(obj)
    lines = text.splitlines()
    assert 2 <= len(lines) <= MAX_LINES, (name, text)
    assert max(len(line) for line in lines) <= MAX_WIDTH, (name, text)
    assert "e+" not in text and "`" not in text, (name, text)
    assert not re.search(r"\d\.\d{5,}", text), (name, text)  # no 17-digit floats
    assert "custom" not in text and "design design" not in text, (name, text)
    html = obj._repr_html_()
    assert html.startswith("<table>") and "<caption" in html, name


@pytest.mark.parametrize("name", ["result", "chosen", "verdict", "evaluation", "card", "run",
                                  "infeasible"])
def test_an_object_with_a_verdict_shows_each_requirement_and_its_margin(objects, name):
    obj = objects[name]
    if name == "infeasible":
        items = obj.to_json()["verdict"]
    elif name == "card":
        items = obj["verdict"]
    elif name == "run":
        items = obj.answer["verdict"]
    elif name == "verdict":
        items = obj.to_json()
    else:
        items = obj.chosen.verdict.to_json() if name == "result" else obj.verdict.to_json()
    from magtact._display import margin_text

    text, html = str(obj), obj._repr_html_()
    flat = " ".join(text.split())  # a wrapped value reads whole again
    for v in items:
        mark = "✓" if v["met"] else "✗"
        line = next(x for x in text.splitlines() if v["statement"][:30] in x)
        assert mark in line, (name, line)
        if v["margin"] is not None:
            assert margin_text(v["margin"], v["unit"]) in flat, (name, text)
        assert v["statement"] in html and mark in html


def test_the_parts_print_the_magnet_size_in_mm(objects):
    p, study = objects["parts"], objects["study"]
    text = str(p)
    size = f"⌀{2e3 * study.magnet.R_m:g} × {1e3 * study.magnet.H_m:g} mm"
    assert size in text or f"{study.magnet.size} mm" in text, text


# ---- the terminal ------------------------------------------------------------------------------
#: Stands in for the stages of ``magtact run`` (they are not under test): the progress lines,
#: a warning, then the command's own ending, from the card of a computed design.
RUN_SCRIPT = textwrap.dedent("""
    import sys
    from pathlib import Path

    import magtact.pipeline as pipeline
    from magtact._runfolder import StageRecord
    from magtact.report import read_card

    folder = Path(sys.argv[1])

    def run_study(study, out, *, log, **options):
        records = []
        for n, (key, title, _) in enumerate(pipeline.STAGES, start=1):
            log(f"[{n}/{len(pipeline.STAGES)}] {title} ...")
            log(f"      ok (1.0 s) {'a long stage message ' * 8}")
            records.append(StageRecord(key=key, title=title, status="ok", message="done",
                                       wall_time_s=1.0))
        records[2].status = "warning"
        records[2].notes.append("WARNING: the fit of f_r is poor " + "(details) " * 10)
        return pipeline.RunResult(folder, folder / "report.html", tuple(records), 44.0,
                                  answer=read_card(folder / "optimise"))

    pipeline.run_study = run_study
    sys.argv = ["magtact", "run", "--out", str(folder)]
    from magtact.cli import main

    main()
""")


def screen_rows(text: str, columns: int = 80) -> list[str]:
    """The rows a terminal of ``columns`` shows for ``text`` (long lines wrap)."""
    rows = []
    for line in text.split("\n"):
        rows += [line[k:k + columns] for k in range(0, max(len(line), 1), columns)]
    return rows


def in_pty(args: list[str], columns: int = 80, lines: int = 24) -> tuple[str, int]:
    """Run ``args`` in a pseudo-terminal of ``columns`` × ``lines``; its output (stdout and
    stderr as the terminal shows them, escape sequences removed) and exit status."""
    import fcntl
    import pty
    import termios

    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", lines, columns, 0, 0))
    env = {k: v for k, v in os.environ.items() if k not in ("COLUMNS", "LINES", "NO_COLOR")}
    env["TERM"] = "xterm-256color"
    proc = subprocess.Popen(args, stdin=slave, stdout=slave, stderr=slave, env=env,
                            close_fds=True)
    os.close(slave)
    chunks = []
    while True:
        try:
            data = os.read(master, 65536)
        except OSError:  # the child closed the terminal
            break
        if not data:
            break
        chunks.append(data)
    os.close(master)
    status = proc.wait(timeout=120)
    text = ANSI.sub("", b"".join(chunks).decode("utf-8", "replace"))
    return text.replace("\r\n", "\n").replace("\r", "").rstrip("\n"), status


def test_the_last_screen_of_magtact_run_holds_the_verdict_with_margins_and_the_parts(
        magone_design, magone_budgets, tmp_path):
    from magtact import write_results_into
    from magtact.report import read_card

    write_results_into(magone_design, tmp_path / "optimise", figures=False, budget=False,
                       budgets=magone_budgets)
    card = read_card(tmp_path / "optimise")
    script = tmp_path / "run.py"
    script.write_text(RUN_SCRIPT, encoding="utf-8")
    text, status = in_pty([sys.executable, str(script), str(tmp_path)])
    assert status == 0, text
    last = screen_rows(text)[-24:]
    shown = "".join(last)  # a wrapped line reads whole again
    from magtact._display import margin_text, round_text

    assert card["verdict"]
    for v in card["verdict"]:
        assert v["statement"] in shown, (v, "\n".join(last))
        assert f"{v['answer']}; {margin_text(v['margin'], v['unit'])}" in shown, (
            v, "\n".join(last))
    for label, value in card["parts"]:
        assert f"{label}: {round_text(value)}" in shown, (label, "\n".join(last))
    # each requirement over the units built, under its nominal answer
    built = card["answers"][0]["robust_verdict"]["requirements"]
    assert built
    for r in built:
        line = "units built: " + round_text(r["answer"].replace(" of units", "", 1))
        assert line in shown, (r, "\n".join(last))
        assert shown.index(r["statement"]) < shown.index(line)
    # progress and warnings come first; the answer ends the output
    assert text.index("[7/7]") < text.index("WARNING: the fit") < text.index(card["verdict"][0][
        "statement"])
    assert "e+0" not in "\n".join(last) and "`" not in "\n".join(last)


@pytest.mark.parametrize("quiet", [False, True])
def test_quiet_leaves_out_the_progress_not_the_answer(magone_design, magone_budgets, tmp_path,
                                                      monkeypatch, quiet):
    from typer.testing import CliRunner

    import magtact.pipeline as pipeline
    from magtact import write_results_into
    from magtact.cli import app
    from magtact.report import read_card

    write_results_into(magone_design, tmp_path / "optimise", figures=False, budget=False,
                       budgets=magone_budgets)

    def run_study(study, out, *, log, **options):
        log("[1/7] Magnetic field ...")
        return pipeline.RunResult(tmp_path, tmp_path / "report.html", (), 1.0,
                                  answer=read_card(tmp_path / "optimise"))

    monkeypatch.setattr(pipeline, "run_study", run_study)
    r = CliRunner().invoke(app, ["run", "--out", str(tmp_path), *(["--quiet"] if quiet else [])])
    assert r.exit_code == 0, r.output
    assert ("[1/7]" in r.stderr) is not quiet
    assert "every requirement met" in r.stdout or "requirements not met" in r.stdout
    assert "report: " in r.stdout
