"""The results folder: the user's files are never replaced, the previous results stay until the
new ones are complete (also when the run is killed), and two runs never mix.

The runs use stand-in stages that write one file named after the study, so that every file
tells which run wrote it; the kills are real: a separate process runs ``magtact run`` (the
command-line entry point) and waits at a chosen point until it is sent SIGTERM or SIGKILL.
"""

from __future__ import annotations

import json
import os
import signal
import stat
import subprocess
import sys
import textwrap
import time
from dataclasses import replace
from pathlib import Path

import pytest

from magtact import _runfolder, pipeline
from magtact.report._html import build_report
from magtact.study import magone

# A run in a separate process: stand-in stages, paused at a point given on the command line.
SCRIPT = textwrap.dedent('''
    import json, os, sys, time
    from pathlib import Path
    from magtact import _runfolder, pipeline
    from magtact.study import magone

    name, pause, ready = sys.argv[1], sys.argv[2], Path(sys.argv[3])

    def wait_here(seconds=120):
        ready.write_text(str(os.getpid()))
        time.sleep(seconds)

    def stage(key):
        def fn(ctx, rec):
            if pause == "stage:" + key:
                (ctx.folder / key).mkdir(exist_ok=True)
                (ctx.folder / key / "partial.csv").write_text("half,done\\n")
                wait_here()
            folder = ctx.folder / key
            folder.mkdir(exist_ok=True)
            (folder / (name + ".csv")).write_text("study,value\\n" + name + ",1\\n")
            if key == "optimise":
                (folder / "chosen.json").write_text(json.dumps({"study": name, "H_mm": 3.0}))
            return "done for " + name
        return fn

    pipeline.STAGES = tuple((k, t, stage(k)) for k, t, _ in pipeline.STAGES)
    if pause.startswith("move:"):  # stop after the k-th move of the swap
        moves, real = [0], _runfolder._replace

        def counted(src, dst):
            real(src, dst)
            moves[0] += 1
            if moves[0] == int(pause[5:]):
                wait_here(0.5)  # SIGTERM is held during the swap: it takes effect after it
        _runfolder._replace = counted
    if pause == "swap":  # the new results complete in the staging folder, not yet in place
        real_swap = pipeline.swap

        def late_swap(*args):
            wait_here()
            real_swap(*args)
        pipeline.swap = late_swap
    from dataclasses import replace
    import magtact.cli._app as app
    app.load_study = lambda source=None: replace(magone(), name=name)
    sys.argv = ["magtact", "run", "--out", sys.argv[4]]
    from magtact.cli import main
    main()
''')


def stand_in_stages(name: str, interrupt_at: str | None = None):
    def stage(key):
        def fn(ctx, rec):
            if key == interrupt_at:
                raise KeyboardInterrupt
            folder = ctx.folder / key
            folder.mkdir(exist_ok=True)
            (folder / f"{name}.csv").write_text(f"study,value\n{name},1\n", encoding="utf-8")
            if key == "optimise":
                (folder / "chosen.json").write_text(json.dumps({"study": name, "H_mm": 3.0}))
            return f"done for {name}"
        return fn
    return tuple((key, title, stage(key)) for key, title, _ in pipeline.STAGES)


def run(folder: Path, name: str, monkeypatch, **kw):
    monkeypatch.setattr(pipeline, "STAGES", stand_in_stages(name, **kw))
    return pipeline.run_study(replace(magone(), name=name), folder, log=lambda m: None)


def consistent(folder: Path) -> str:
    """The one study whose results the folder holds (every part agrees), checked."""
    manifest = json.loads((folder / "run.json").read_text())
    name = manifest["study"]
    for key, _, _ in pipeline.STAGES:
        assert (folder / key / pipeline.RUN_STAMP).read_text() == manifest["run_id"]
        assert [p.name for p in (folder / key).glob("*.csv")] == [f"{name}.csv"]
    html = (folder / "report.html").read_text()
    assert html.count(f"<td>{name}</td>") == 5  # a table per tabled stage
    return name


def files(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


# ---- the user's files ------------------------------------------------------------------------
def _user_study_beside(folder):
    (folder / "study.toml").write_text("# my study, with my comments\n[design]\n")
    return "study.toml"


def _user_file_in_stage_folder(folder):
    (folder / "optimise" / "my_notes.txt").write_text("keep me\n")
    return "optimise"


def _edited_output(folder):
    (folder / "run.json").write_text((folder / "run.json").read_text() + " ")
    return "run.json"


def _user_folder(folder):
    (folder / "logs").mkdir(exist_ok=True)
    (folder / "logs" / "lab.log").write_text("measured 3 N\n")
    return "logs"


def _link_in_place(folder):
    target = folder.parent / "elsewhere"
    target.mkdir()
    (target / "data.csv").write_text("a,b\n")
    (folder / "evidence").symlink_to(target)
    return "evidence"


@pytest.mark.parametrize("after_a_run", [False, True])
@pytest.mark.parametrize("plant", [_user_study_beside, _user_file_in_stage_folder,
                                   _edited_output, _user_folder, _link_in_place])
def test_no_output_replaces_a_file_magtact_did_not_write(tmp_path, monkeypatch, plant,
                                                         after_a_run):
    folder = tmp_path / "R"
    folder.mkdir()
    if after_a_run or plant in (_user_file_in_stage_folder, _edited_output):
        run(folder, "FirstStudy", monkeypatch)
    name = plant(folder)
    before = files(folder)
    with pytest.raises(_runfolder.NotMagtactsFile) as err:
        run(folder, "SecondStudy", monkeypatch)
    assert str(folder / name) in str(err.value) and "Give another --out" in str(err.value)
    assert files(folder) == before  # nothing written, nothing removed
    assert not list(folder.glob(".magtact-staging-*")) and not (folder / ".magtact-lock").exists()


def test_report_does_not_replace_a_users_report_html(tmp_path):
    folder = tmp_path / "R"
    folder.mkdir()
    (folder / "report.html").write_text("<html>my own notes</html>")
    with pytest.raises(_runfolder.NotMagtactsFile, match="report.html is not magtact's"):
        build_report(folder)
    assert (folder / "report.html").read_text() == "<html>my own notes</html>"


def test_rerun_replaces_what_magtact_wrote_and_keeps_other_files(tmp_path, monkeypatch):
    folder = tmp_path / "R"
    folder.mkdir()
    (folder / "notes.md").write_text("mine\n")  # a name no run writes: never touched
    run(folder, "FirstStudy", monkeypatch)
    build_report(folder)  # a rebuilt report stays magtact's
    run(folder, "SecondStudy", monkeypatch)
    assert consistent(folder) == "SecondStudy" and (folder / "notes.md").read_text() == "mine\n"


# ---- interrupted runs: real processes killed at several points -------------------------------
def start(tmp_path, name, pause, folder):
    ready = tmp_path / f"ready-{name}"
    script = tmp_path / "run_paused.py"
    script.write_text(SCRIPT)
    env = os.environ | {"PYTHONPATH": os.pathsep.join(sys.path)}
    proc = subprocess.Popen([sys.executable, str(script), name, pause, str(ready), str(folder)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    deadline = time.monotonic() + 60
    while not ready.exists():
        if proc.poll() is not None or time.monotonic() > deadline:
            proc.kill()
            raise AssertionError(proc.communicate()[1].decode())
        time.sleep(0.05)
    return proc


POINTS = ["stage:field", "stage:optimise", "swap", "move:1", "move:4", "move:9", "move:18"]
#: The points of the default suite (the others: -m long).
QUICK = {(signal.SIGKILL, "move:4"), (signal.SIGTERM, "stage:optimise")}


@pytest.mark.parametrize(("sig", "pause"), [
    pytest.param(sig, pause, id=f"{sig.name}-{pause}",
                 marks=() if (sig, pause) in QUICK else pytest.mark.long)
    for sig in (signal.SIGTERM, signal.SIGKILL) for pause in POINTS])
def test_killed_run_leaves_the_finished_run_or_the_new_complete_one(tmp_path, monkeypatch, sig,
                                                                    pause):
    """At each point the folder is the finished run's or the new one's, whole, once the next
    reader (here ``magtact report``) has finished a swap the kill cut short."""
    folder = tmp_path / "R"
    folder.mkdir()
    run(folder, "FirstStudy", monkeypatch)
    proc = start(tmp_path, "Second", pause, folder)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == (143 if sig == signal.SIGTERM else -signal.SIGKILL)
    if sig == signal.SIGTERM:  # said, and held during the swap: the new run is then in place
        assert "terminated by a signal (SIGTERM)" in err.decode()
    in_place = pause.startswith("move:")
    if not in_place:  # the finished run untouched, report included
        assert consistent(folder) == "FirstStudy", pause
    elif sig == signal.SIGTERM:
        assert consistent(folder) == "Second"
    html = build_report(folder).read_text()
    assert consistent(folder) == ("Second" if in_place else "FirstStudy"), pause
    assert ("<b>Interrupted run.</b>" in html) is not in_place, pause
    if pause.startswith("stage:"):
        title = dict((k, t) for k, t, _ in pipeline.STAGES)[pause[6:]]
        assert f"interrupted during the stage <i>{title}</i>" in html
    if pause == "swap":
        assert "after its last stage, before its results were put in place" in html
    assert "partial.csv" not in html


@pytest.mark.long
def test_killed_first_run_is_named_and_the_next_run_clears_it(tmp_path, monkeypatch):
    folder = tmp_path / "R"
    folder.mkdir()
    proc = start(tmp_path, "Lost", "stage:doe", folder)
    proc.kill()
    proc.wait(timeout=60)
    lock = json.loads((folder / _runfolder.LOCK).read_text())  # a dead process's lock is left
    assert lock["pid"] == proc.pid
    html = build_report(folder).read_text()
    assert "interrupted during the stage <i>Design of experiments</i>" in html
    assert "This folder holds no complete run" in html
    run(folder, "Next", monkeypatch)  # the stale lock is taken over
    assert consistent(folder) == "Next"
    assert not list(folder.glob(".magtact-staging-*"))


# ---- two runs at once ------------------------------------------------------------------------
def test_second_run_into_a_folder_in_use_is_refused_naming_the_first(tmp_path, monkeypatch):
    folder = tmp_path / "R"
    folder.mkdir()
    run(folder, "FirstStudy", monkeypatch)
    proc = start(tmp_path, "Busy", "stage:metamodel", folder)  # the barrier: it holds the lock
    try:
        monkeypatch.setattr(_runfolder, "LOCK_PATIENCE_S", 0.2)
        with pytest.raises(_runfolder.FolderInUse) as err:
            run(folder, "Other", monkeypatch)
        assert f"process {proc.pid} on " in str(err.value)
        assert "magtact run --out" in str(err.value)
        with pytest.raises(_runfolder.FolderInUse):
            build_report(folder)  # nor is the folder read half written
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.communicate(timeout=60)
    assert consistent(folder) == "FirstStudy"


def test_lock_file_of_a_dead_process_is_taken_over(tmp_path, monkeypatch):
    folder = tmp_path / "R"
    folder.mkdir()
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    (folder / _runfolder.LOCK).write_text(json.dumps(
        {"pid": int(dead.stdout), "host": os.uname().nodename, "started": "yesterday"}))
    run(folder, "Next", monkeypatch)
    assert consistent(folder) == "Next" and not (folder / _runfolder.LOCK).exists()


# ---- file modes ------------------------------------------------------------------------------
@pytest.mark.parametrize("umask", [0o022, 0o077, 0o002])
def test_outputs_follow_the_umask(tmp_path, monkeypatch, umask):
    old = os.umask(umask)
    try:
        run(tmp_path / "R", "Modes", monkeypatch)
    finally:
        os.umask(old)
    want = 0o666 & ~umask
    modes = {p.relative_to(tmp_path).as_posix(): stat.S_IMODE(p.stat().st_mode)
             for p in (tmp_path / "R").rglob("*") if p.is_file()}
    assert {"R/run.json", "R/report.html", "R/.magtact-files.json"} <= set(modes)
    assert modes == dict.fromkeys(modes, want)
