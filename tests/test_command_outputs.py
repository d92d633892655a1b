"""The outputs of the per-stage commands (field, doe, fit, optimise, validate, simulate,
reproduce, budget, calibrate): no output replaces a file magtact did not write, a run's results
stay the run's, two writers never mix, and a command stopped while putting its files in place is
completed by the next one (docs/method.md §14).

The commands run through :func:`magtact.cli.main`, the entry point of the ``magtact`` command
line (arguments in ``sys.argv``, exit status and message as a user sees them). A refusal comes
before the command's work, so that every command is tested here, however long its work.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import signal
import stat
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from magtact import _runfolder
from magtact.report._html import build_report
from test_runfolder import consistent, files, run

#: Each command with arguments that make it quick to refuse, and the files it always writes
#: into --out (the names its documentation gives).
COMMANDS = {
    "field": (["--solver", "exact"], ["field.csv"]),
    "doe": (["--no-cache", "--workers", "0"], ["doe.nc", "doe.csv"]),
    "fit": ([], ["metamodels.md"]),
    "optimise": ([], ["design.json", "pareto.csv", "reduction.csv", "maps.csv", "card.json",
                      "chosen.json"]),
    "validate": ([], ["validation_synthetic.csv", "validation_synthetic.json"]),
    "simulate": (["--H", "3", "--theta", "0.1", "--mesh", "coarse"],
                 ["forces.csv", "deformed_t1.vtu"]),
    "reproduce": (["--seeds", "1"], ["publication/publication.json", "publication/seeds.csv",
                                     "publication/spread.csv", "publication/comparison.csv"]),
    "budget": (["--H", "3", "--G", "30"], ["budget.json"]),
    "calibrate": ([], ["force.h", "force_map.json", "force_table.csv", "calibration.json"]),
}


def cli(*args: str) -> tuple[int, str]:
    """Exit status and output (stdout and stderr, whitespace folded) of ``magtact ARGS``."""
    from magtact.cli import main

    out = io.StringIO()
    handler = signal.getsignal(signal.SIGTERM)
    saved = sys.argv
    sys.argv = ["magtact", *map(str, args)]
    try:
        with contextlib.redirect_stderr(out), contextlib.redirect_stdout(out):
            main()
        code = 0
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    finally:
        sys.argv = saved
        signal.signal(signal.SIGTERM, handler)
    return code, " ".join(out.getvalue().split())


def plant(folder: Path, names) -> dict[str, bytes]:
    """The user's own files under the given names; return the folder's files."""
    for name in names:
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_bytes(f"the user's own {name}\n".encode())
    return files(folder)


def placed(folder: Path) -> dict[str, bytes]:
    """The folder's files, less the outputs a refused command kept aside."""
    return {k: v for k, v in files(folder).items() if not k.startswith(_runfolder.REFUSED)}


def no_leftovers(folder: Path) -> None:
    """No staging folder, journal or lock left (the stamp stays)."""
    r = _runfolder
    left = [p.name for p in folder.rglob(".magtact-*")
            if p.name.startswith((r.STAGING, r.WRITING, r.OLD, r.JOURNAL, r.LOCK))]
    assert left == [], left


# ---- class 1: the user's files ---------------------------------------------------------------
@pytest.mark.parametrize("command", list(COMMANDS))
def test_a_users_file_with_an_outputs_name_is_kept_and_named(tmp_path, command):
    args, names = COMMANDS[command]
    out = tmp_path / "o"
    name = names[-1]  # another name than the first of each command
    before = plant(out, [name])
    code, text = cli(command, *args, "--out", out)
    assert code == 2, text
    assert f"error: {out / name} is not magtact's" in text, text
    assert text.count("error:") == 1
    assert "Move it away, or give another --out" in text
    assert files(out) == before
    no_leftovers(out)


@settings(max_examples=12, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.sampled_from(["optimise", "calibrate", "reproduce"]).flatmap(
    lambda c: st.tuples(st.just(c), st.sets(st.sampled_from(COMMANDS[c][1]), min_size=1))))
def test_any_set_of_the_users_files_is_kept_and_each_named(case):
    command, names = case
    args, _ = COMMANDS[command]
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "o"
        before = plant(out, sorted(names))
        code, text = cli(command, *args, "--out", out)
        assert code == 2, text
        assert text.count("error:") == 1
        for name in names:
            assert str(out / name) in text
        for name in set(COMMANDS[command][1]) - names:
            assert str(out / name) not in text
        assert files(out) == before


def test_rerun_replaces_its_own_outputs_and_an_edited_one_is_the_users(tmp_path):
    out = tmp_path / "f"
    (out / "notes").mkdir(parents=True)
    (out / "notes" / "mine.txt").write_text("keep me")
    assert cli("field", "--solver", "exact", "--out", out)[0] == 0
    first = files(out)
    stamp = json.loads((out / _runfolder.OWNED).read_text())
    assert set(stamp["files"]) == {"field.csv", "field_maps.png", "field_maps.svg"}
    assert set(stamp["commands"].values()) == {f"magtact field --out {out}"}
    code, text = cli("field", "--solver", "exact", "--out", out)
    assert code == 0, text
    # the place of the file, not the staging one
    assert f"wrote {out / 'field.csv'}" in text and ".magtact-" not in text
    assert files(out)["notes/mine.txt"] == b"keep me"
    assert first["field.csv"] == files(out)["field.csv"]
    # the user edits a figure magtact wrote: it is theirs now (a name not checked before the
    # work: the command's outputs are kept aside, complete, and named)
    with open(out / "field_maps.svg", "a") as fh:
        fh.write("<!-- my note -->")
    before = files(out)
    code, text = cli("field", "--solver", "exact", "--out", out)
    assert code == 2
    assert f"{out / 'field_maps.svg'} is not magtact's" in text
    kept = next(out.glob(f"{_runfolder.REFUSED}*"))
    assert f"This command's outputs are in {kept}" in text
    assert {p.name for p in kept.iterdir()} == {"field.csv", "field_maps.png", "field_maps.svg"}
    assert placed(out) == before
    no_leftovers(out)


@pytest.mark.long
@pytest.mark.parametrize("command", ["simulate", "budget", "optimise"])
def test_a_command_run_again_replaces_its_own_outputs(tmp_path, command):
    args, names = COMMANDS[command]
    out = tmp_path / "o"
    plant(out, ["mine.csv"])
    assert cli(command, *args, "--out", out)[0] == 0
    stamp = json.loads((out / _runfolder.OWNED).read_text())
    assert set(names) <= set(stamp["files"]) and "mine.csv" not in stamp["files"]
    code, text = cli(command, *args, "--out", out)
    assert code == 0, text
    assert (out / "mine.csv").read_bytes() == b"the user's own mine.csv\n"
    assert json.loads((out / _runfolder.OWNED).read_text())["files"].keys() == stamp[
        "files"].keys()
    no_leftovers(out)


class _Reproduction:
    """Stands in for the result of :func:`magtact.publication.reproduce`."""

    comparison = [{"quantity": "Γ_z,max", "unit": "N/T", "scale_free": False,
                   "publication": 1.0, "jacobian / magtact": {"text": "1.1"}}]
    wall_time_s, workers = 0.0, 1

    def write(self, folder):
        from magtact._files import write_text

        return [write_text(Path(folder) / n, f"{n}\n") for n in (
            "publication.json", "seeds.csv", "spread.csv", "comparison.csv")]


def test_reproduce_puts_its_section_in_place_and_rebuilds_the_report(tmp_path, monkeypatch):
    """``reproduce`` writes ``publication/`` like any command, then rebuilds ``report.html``
    holding the folder's lock; run again, it replaces both."""
    import magtact.publication as publication
    import magtact.report as report

    monkeypatch.setattr(publication, "reproduce", lambda *a, **kw: _Reproduction())
    monkeypatch.setattr(report, "publication_figures", lambda folder: [])
    out = tmp_path / "R"
    for _ in range(2):
        code, text = cli("reproduce", "--seeds", "1", "--out", out)
        assert code == 0, text
        stamp = json.loads((out / _runfolder.OWNED).read_text())
        assert {k for k in stamp["commands"]} == {f"publication/{n}" for n in (
            "publication.json", "seeds.csv", "spread.csv", "comparison.csv")}
        assert "report.html" in stamp["files"] and "report.html" not in stamp["commands"]
        assert (out / "report.html").read_text().startswith(_runfolder.REPORT_HEAD)
        no_leftovers(out)


# ---- the mechanism, on names of any kind ------------------------------------------------------
NAMES = ["a.csv", "b.json", "figs/c.png", "figs/d.svg", "deep/er/e.txt"]


def write_all(folder: Path, tag: str) -> None:
    for name in NAMES:
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_text(f"{tag} {name}\n")


@settings(max_examples=40, deadline=None)
@given(users=st.sets(st.sampled_from(NAMES)), expect=st.sets(st.sampled_from(NAMES)),
       earlier=st.booleans())
def test_outputs_never_replace_the_users_files(users, expect, earlier):
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        if earlier:  # an earlier output of the command, then the user's files over some
            with _runfolder.command_outputs(out, "cmd") as o:
                write_all(o.folder, "old")
        before = plant(out, sorted(users))
        try:
            with _runfolder.command_outputs(out, "cmd", expect) as o:
                write_all(o.folder, "new")
        except _runfolder.NotMagtactsFile as exc:
            assert users, "refused with nothing of the user's in the way"
            named = users & expect or users  # before the work, the expected names
            assert all(str(out / n) in str(exc) for n in named), str(exc)
            assert placed(out) == before
        else:
            assert not users
            assert all((out / n).read_text() == f"new {n}\n" for n in NAMES)
            assert set(json.loads((out / _runfolder.OWNED).read_text())["files"]) == set(NAMES)
        no_leftovers(out)


@pytest.mark.parametrize("way", ["symlink", "folder", "file-for-folder"])
def test_what_is_not_a_file_of_magtacts_is_refused(tmp_path, way):
    out = tmp_path / "o"
    out.mkdir()
    elsewhere = tmp_path / "elsewhere.csv"
    elsewhere.write_text("precious")
    if way == "symlink":
        (out / "a.csv").symlink_to(elsewhere)
        named = out / "a.csv"
    elif way == "folder":
        (out / "a.csv").mkdir()
        named = out / "a.csv"
    else:
        (out / "figs").write_text("a file where the command makes a folder")
        named = out / "figs"
    before = files(out)
    with pytest.raises(_runfolder.NotMagtactsFile, match=f"{named} is not magtact's"):
        with _runfolder.command_outputs(out, "cmd") as o:
            write_all(o.folder, "new")
    assert placed(out) == before
    assert elsewhere.read_text() == "precious"


# ---- a run's results -------------------------------------------------------------------------
def test_a_command_keeps_a_finished_run_as_it_was(tmp_path, monkeypatch):
    folder = tmp_path / "R"
    run(folder, "First", monkeypatch)
    before = files(folder)
    # a stage folder of the run holds the run's files alone; nor are the run's files at the
    # top of the folder a command's to replace
    for into, stage in (("optimise", "optimise"), ("doe", "doe"), ("doe/mine", "doe")):
        code, text = cli("field", "--solver", "exact", "--out", folder / into)
        assert code == 2
        assert (f"error: {folder / stage} belongs to the results of the magtact run in {folder}, "
                "which a command does not change") in text, text
    assert not (folder / "doe" / "mine").exists()  # the folder made for --out is removed
    with pytest.raises(_runfolder.NotMagtactsFile, match="run.json belongs to the results"):
        with _runfolder.command_outputs(folder, "cmd") as o:
            (o.folder / "run.json").write_text("{}")
    assert placed(folder) == before
    # beside the run: the command's files are added, the run is as it was and its report builds
    field_beside(folder)
    assert consistent(folder) == "First"
    build_report(folder)
    assert consistent(folder) == "First"
    field = (folder / "field.csv").read_bytes()
    # the next run replaces its own results and keeps the command's, still recorded
    run(folder, "Second", monkeypatch)
    assert consistent(folder) == "Second"
    assert (folder / "field.csv").read_bytes() == field
    field_beside(folder, expect=["field.csv"])  # still recorded as the command's
    no_leftovers(folder)


def test_the_folder_that_governs_a_stage_folder_is_named_as_the_user_names_it(tmp_path,
                                                                              monkeypatch):
    run(tmp_path / "R", "First", monkeypatch)
    monkeypatch.chdir(tmp_path)
    root = _runfolder.results_root
    assert root(Path("R/optimise")) == Path("R")
    assert root(Path("R/optimise/sub")) == Path("R")
    assert root(Path("R/other")) == Path("R/other")  # the run records nothing there
    assert root(tmp_path / "R" / "doe") == tmp_path / "R"
    assert root(Path("x/../R/doe")) == tmp_path / "R"
    monkeypatch.chdir(tmp_path / "R")
    assert root(Path("optimise")) == Path(".")


def field_beside(folder: Path, expect=()) -> None:
    """What ``magtact field --out FOLDER`` does with its files (without its work)."""
    with _runfolder.command_outputs(folder, f"magtact field --out {folder}", expect) as o:
        (o.folder / "field.csv").write_text("t,theta_rad,H_mm,B_r_T,B_z_T\n")


def test_a_run_does_not_replace_what_a_command_wrote_in_its_place(tmp_path, monkeypatch):
    folder = tmp_path / "R"
    (folder / "validation").mkdir(parents=True)
    field_beside(folder / "validation")
    before = files(folder)
    with pytest.raises(_runfolder.NotMagtactsFile, match=f"{folder / 'validation'} is not"):
        run(folder, "First", monkeypatch)
    assert files(folder) == before


# ---- class 3: two writers at once ------------------------------------------------------------
HOLDER = textwrap.dedent('''
    import sys, time
    from pathlib import Path
    from magtact import _runfolder
    with _runfolder.RunLock(sys.argv[1], "magtact run --out R", writes=sys.argv[3:]):
        Path(sys.argv[2]).write_text("ready")
        time.sleep(60)
''')


@pytest.mark.parametrize("into", [".", "optimise"])
def test_a_command_into_a_folder_in_use_is_refused_naming_the_process(tmp_path, monkeypatch,
                                                                      into):
    folder = tmp_path / "R"
    folder.mkdir()
    ready = tmp_path / "ready"
    proc = subprocess.Popen([sys.executable, "-c", HOLDER, str(folder), str(ready), "optimise"],
                            env=os.environ | {"PYTHONPATH": os.pathsep.join(sys.path)})
    try:
        deadline = time.monotonic() + 60
        while not ready.exists():
            assert time.monotonic() < deadline and proc.poll() is None
            time.sleep(0.05)
        monkeypatch.setattr(_runfolder, "LOCK_PATIENCE_S", 0.2)
        out = folder / into
        code, text = cli("optimise", "--out", out)
        assert code == 2
        assert f"{folder} is in use by another magtact run: process {proc.pid} on " in text, text
        assert "(magtact run --out R)" in text
        assert [p.name for p in folder.iterdir()] == [".magtact-lock"]  # nothing else made
    finally:
        proc.kill()
        proc.wait()


def test_a_command_within_a_command_takes_the_lock_again(tmp_path):
    """``magtact reproduce`` builds the report of its folder while it holds the folder's lock."""
    with _runfolder.command_outputs(tmp_path, "cmd") as o:
        (o.folder / "a.csv").write_text("1")
        o.place()
        report = build_report(tmp_path)
    assert report.read_text().startswith(_runfolder.REPORT_HEAD)
    assert not (tmp_path / _runfolder.LOCK).exists()


# ---- class 2: stopped part way ---------------------------------------------------------------
def test_a_failed_command_leaves_the_earlier_outputs(tmp_path):
    with _runfolder.command_outputs(tmp_path, "cmd") as o:
        write_all(o.folder, "old")
    before = files(tmp_path)
    with pytest.raises(KeyboardInterrupt), _runfolder.command_outputs(tmp_path, "cmd") as o:
        (o.folder / "a.csv").write_text("half")
        raise KeyboardInterrupt
    assert files(tmp_path) == before
    no_leftovers(tmp_path)


def test_placing_cut_short_is_completed_by_the_next_command(tmp_path, monkeypatch):
    real, moves = _runfolder._replace, []

    def killed_after_two(src, dst):
        if len(moves) == 2:
            raise SystemExit("killed")
        real(src, dst)
        moves.append(dst)

    with _runfolder.command_outputs(tmp_path, "cmd") as o:
        write_all(o.folder, "old")
    monkeypatch.setattr(_runfolder, "_replace", killed_after_two)
    with pytest.raises(SystemExit), _runfolder.command_outputs(tmp_path, "cmd") as o:
        write_all(o.folder, "new")
    assert (tmp_path / _runfolder.JOURNAL).exists()
    monkeypatch.setattr(_runfolder, "_replace", real)
    with _runfolder.command_outputs(tmp_path, "other", ["a.csv"]):
        pass  # entering finishes the placing: every file new, and recorded as such
    assert all((tmp_path / n).read_text() == f"new {n}\n" for n in NAMES)
    with _runfolder.command_outputs(tmp_path, "cmd", NAMES) as o:  # all magtact's
        write_all(o.folder, "third")
    no_leftovers(tmp_path)


# A ``magtact field`` in a separate process that stops in its work (half its outputs written
# into the staging folder) or after the k-th move of the placing, until it is killed.
FIELD = textwrap.dedent('''
    import sys, time
    from pathlib import Path
    import magtact.magnetics as magnetics
    from magtact import _runfolder

    pause, ready, seconds = sys.argv[1], Path(sys.argv[2]), float(sys.argv[4])

    def wait_here():
        ready.write_text("ready")
        time.sleep(seconds)  # a SIGTERM held during the placing takes effect after it

    real = magnetics.write_field_outputs

    def paused(study, folder, **kw):
        files = real(study, folder, **kw)
        if pause == "work":
            (Path(folder) / "field.csv").write_text("half")
            wait_here()
        return files

    magnetics.write_field_outputs = paused
    if pause.startswith("move:"):
        moves, replace = [0], _runfolder._replace

        def counted(src, dst):
            replace(src, dst)
            moves[0] += 1
            if moves[0] == int(pause[5:]):
                wait_here()
        _runfolder._replace = counted
    sys.argv = ["magtact", "field", "--solver", "exact", "--out", sys.argv[3]]
    from magtact.cli import main
    main()
''')


@pytest.mark.parametrize(("sig", "pause"), [
    pytest.param(sig, pause, id=f"{sig.name}-{pause}",
                 marks=pytest.mark.long)
    for sig, pause in [(signal.SIGTERM, "work"), (signal.SIGKILL, "work"),
                       (signal.SIGKILL, "move:2"), (signal.SIGTERM, "move:1")]])
def test_a_killed_command_leaves_its_earlier_outputs_or_its_new_ones(tmp_path, sig, pause):
    """Killed in its work, a command leaves the earlier outputs; killed while putting its files
    in place, the next command on the folder completes the placing (SIGTERM is held until the
    placing is done)."""
    out = tmp_path / "f"
    out.mkdir()
    (out / "mine.txt").write_text("the user's")
    with _runfolder.command_outputs(out, "magtact field") as o:
        for name in ("field.csv", "field_maps.png", "field_maps.svg"):
            (o.folder / name).write_text(f"earlier {name}")
    before = files(out)
    ready = tmp_path / "ready"
    seconds = "1" if sig == signal.SIGTERM and pause != "work" else "60"
    proc = subprocess.Popen([sys.executable, "-c", FIELD, pause, str(ready), str(out), seconds],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            env=os.environ | {"PYTHONPATH": os.pathsep.join(sys.path)})
    deadline = time.monotonic() + 120
    while not ready.exists():
        if proc.poll() is not None or time.monotonic() > deadline:
            proc.kill()
            raise AssertionError(proc.communicate()[1].decode())
        time.sleep(0.05)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == (143 if sig == signal.SIGTERM else -signal.SIGKILL), err
    with _runfolder.command_outputs(out, "magtact report"):
        pass  # the next writer on the folder
    now = files(out)
    if pause == "work":
        assert now == before
    else:
        assert now["mine.txt"] == b"the user's"
        assert all(not now[n].startswith(b"earlier") for n in ("field.csv", "field_maps.png",
                                                                 "field_maps.svg"))
        assert now["field.csv"].startswith(b"t,theta_rad,H_mm,")
        with _runfolder.command_outputs(out, "again", ["field.csv", "field_maps.svg"]):
            pass  # every new file is recorded as magtact's
    no_leftovers(out)


# ---- file modes ------------------------------------------------------------------------------
@pytest.mark.parametrize("umask", [0o022, 0o077])
def test_placed_outputs_follow_the_umask(tmp_path, umask):
    from magtact._files import write_text

    old = os.umask(umask)
    try:
        with _runfolder.command_outputs(tmp_path, "cmd") as o:
            write_text(o.folder / "figs" / "a.csv", "1")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "figs" / "a.csv").stat().st_mode) == 0o666 & ~umask
    assert stat.S_IMODE((tmp_path / "figs").stat().st_mode) == 0o777 & ~umask
