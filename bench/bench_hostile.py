"""Benchmark: thousands of hostile inputs through the three readers of user files, and the
user's data against the results folder, the command line and the value checks.

Generates study documents (TOML, and raw text/bytes), validation tables (CSV pairs, and raw
text/bytes) and model expressions with the Hypothesis strategies of ``tests/test_hostile_*.py``
and hands each case to a worker process that reads it with magtact
(:func:`magtact.study.load_study`, :func:`magtact.validation.read_experiment`,
:func:`magtact.metamodel.parse_expression`). Further kinds (:func:`safety_cases`): the user's
files in a results folder, runs killed at each point by SIGTERM and SIGKILL, two runs at once,
ordered settings, held-out paths, numbers outside the usual grammar (CSV cells and every number
option of every command), tests sharing little displacement, model files with huge integers,
paths that are not files, broken pipes in each command, file modes; and the per-stage commands
over the user's files (each command with the user's file under each name it always writes; the
outputs' mechanism with generated sets of the user's files), into a folder in use, and into a
finished run's stage folder. Each case ends in one of:

``clean``             refused with the project's error (StudyError, DataError, ValueError) whose
                      message is one line;
``accepted``          read, and the result satisfies every documented rule (the tests' oracles);
``wrongly_accepted``  read, but the result breaks a rule (a number out of bounds, a NaN...);
``traceback``         any other exception, or a refusal whose message is not one line;
``hang``              no answer within ``--timeout`` seconds (the worker is killed and restarted).

The designer's own inputs (:func:`designer_cases`): seed studies of ``magtact budget --seed-study``
(devices, a FIFO, a large file, generated JSON), press files (generated cells, 10,001 and 10⁶
rows) and unit fits (random readings, 10,000 presses of a real unit), options that cannot take
effect and the one form of ``--noise-uT``, the temperature change against the remanence
coefficient, quoted CSV cells, numbers of other types, unit mistakes in study keys, the study
check against the commands' rules, and any reading through the compiled ``force.h``.
Results folders forged or damaged (:func:`_forged_results`: deep JSON, huge arrays, FIFOs,
devices, sparse files, symbolic link loops, wrong types, generated JSON in place of each record)
through ``magtact report``, and press files in each sign convention (:func:`_press_sign`)
through the unit fit, each family in a fresh worker whose peak resident memory must stay below
1 GB.

Writes the counts per reader to ``bench/results/hostile.json``, with the peak resident memory
of the worker and of the processes it started (no process may exceed 2 GB); all but ``clean``
and ``accepted`` should be zero.

    nice -n 10 python bench/bench_hostile.py            # ~6 min on the 2-core machine
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import platform
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

OUTCOMES = ("clean", "accepted", "wrongly_accepted", "traceback", "hang")
#: No process of the benchmark may hold more resident memory than this [MB].
RSS_LIMIT_MB = 2048


# ---- generating the cases ---------------------------------------------------------------------
def generate(strategy, n: int, seed: int) -> list:
    """``n`` examples of a Hypothesis strategy (generation phase only, reproducible)."""
    from hypothesis import HealthCheck, Phase, given, settings
    from hypothesis import seed as hseed

    out = []

    @hseed(seed)
    @settings(max_examples=n, phases=[Phase.generate], deadline=None, database=None,
              suppress_health_check=list(HealthCheck))
    @given(strategy)
    def collect(example):
        out.append(example)

    collect()
    return out


def cases(n: int) -> dict[str, list]:
    from hypothesis import strategies as st

    import test_hostile_csv as hc
    import test_hostile_expressions as he
    import test_hostile_study as hs

    raw = n // 4
    return {
        "study_toml": generate(hs.documents(), n, 1),
        "study_raw": generate(st.one_of(st.lists(hs.TOML_TOKENS, max_size=40).map("".join),
                                        st.binary(max_size=200)), raw, 2),
        "csv_tables": generate(st.tuples(hc.tables(), hc.tables()), n, 3),
        "csv_raw": generate(st.one_of(st.binary(max_size=300), st.text(max_size=300)), raw, 4),
        "expressions": generate(st.one_of(he.trees(), he.SOUP), n, 5),
        "expressions_large": generate(large_expressions(), max(n // 50, 10), 6),
    } | safety_cases(n)


def safety_cases(n: int) -> dict[str, list]:
    """The kinds of the results folder, the command line and the value checks."""
    from hypothesis import strategies as st

    import test_command_outputs as tc
    import test_hostile_values as hv

    small = max(n // 10, 20)
    digits = "0123456789_.eE+- \tx١٣"
    return {
        "user_files": [(plant, after) for plant in range(5) for after in (False, True)],
        "killed_runs": [(sig, pause) for sig in ("TERM", "KILL") for pause in KILL_POINTS],
        "concurrent_runs": list(range(3)),
        "ordered_settings": generate(st.tuples(st.sampled_from(hv.PAIRS), st.floats(0.011, 0.9),
                                               st.floats(1.01, 10.0)), small, 7),
        "holdout_paths": generate(st.tuples(st.integers(1, 9), st.integers(1, 9),
                                            st.integers(0, 90)), small, 8),
        "csv_numbers": generate(st.text(alphabet=digits, min_size=1, max_size=10), small, 9),
        "shared_range": generate(st.floats(-2.5, 0.0), small, 10),
        "option_numbers": option_cases(),
        "option_messages": MESSAGE_CASES,
        "model_files": [(where, ndigits) for where in range(3) for ndigits in (4301, 5000, 20000)],
        "not_a_file": [(reader, kind) for reader in range(4) for kind in PATH_KINDS],
        "broken_pipe": [c for c in COMMANDS],
        "file_modes": [0o022, 0o077, 0o002, 0o027],
        "command_user_files": [(c, name) for c, (_, names) in tc.COMMANDS.items()
                               for name in names],
        "command_outputs": generate(st.tuples(st.sets(st.sampled_from(tc.NAMES)),
                                              st.sets(st.sampled_from(tc.NAMES)),
                                              st.booleans()), small, 11),
        "command_in_use": list(tc.COMMANDS),
        "command_in_run": list(tc.COMMANDS),
    } | designer_cases(n)


#: Kinds whose cases start a process of their own (a run to kill, a run holding the lock): their
#: time limit is this multiple of ``--timeout``.
SLOW = {"killed_runs": 6, "concurrent_runs": 6, "user_files": 3, "file_modes": 3,
        "command_user_files": 3, "command_in_use": 6, "command_in_run": 3, "press_fits": 18,
        "option_effect": 6, "press_files": 3, "firmware_readings": 3, "forged_results": 3,
        "press_sign": 3}
#: Kinds run in a fresh worker, so that its peak resident memory is theirs alone.
FRESH = ("forged_results", "press_sign")
#: The most resident memory a process of a FRESH kind may reach [MB].
FRESH_RSS_LIMIT_MB = 1024
KILL_POINTS = ["stage:field", "stage:doe", "stage:optimise", "swap", "move:1", "move:4",
               "move:9", "move:18"]
PATH_KINDS = ("loop", "fifo", "folder", "broken-link")
COMMANDS = ["field", "doe", "fit", "optimise", "run", "validate", "simulate", "reproduce",
            "study"]
#: (arguments, fragment the one-line message must hold).
MESSAGE_CASES = [
    (["validate", "--f-lo", "4", "--f-hi", "0.5"], "cycles per mm"),
    (["validate", "--f-lo", "1", "--f-hi", "1"], "--f-hi (1 cycles per mm) must be above"),
    (["validate", "--n-grid", "0"], "'--n-grid'"),
    (["validate", "--n-grid", "1000000"], "'--n-grid'"),
    (["validate", "--floor", "1.5"], "--floor must be in [0, 1)"),
    (["validate", "--floor", "-1"], "--floor must be in [0, 1)"),
    (["study", "magone_printed"], "no preset has that name (presets: magone, "),
    (["study", "MagOne"], "no preset has that name (presets: magone, "),
    (["fit", "--out", "x", "--generations", "0"], "'--generations'"),
    (["validate", "--mesh", "huge"],
     "'huge' is not one of 'coarse', 'default', 'accurate', 'fine'"),
    (["validate", "--solver", "fem"], "'fem' is not one of 'fe', 'exact'"),
    (["doe", "--workers", "-3", "--out", "x"], "'--workers'"),
    (["run", "--workers", "-1", "--out", "x"], "'--workers'"),
    (["reproduce", "--workers", "-1", "--out", "x"], "'--workers'"),
    (["doe", "--scheduler", "nohost", "--out", "{tmp}"], "(--scheduler)"),
]


def option_cases() -> list[tuple[list[str], str]]:
    """Every number option of every command with values outside the usual grammar."""
    import typer.main

    from magtact.cli._app import app

    group = typer.main.get_command(app)
    out = []
    for name, command in sorted(group.commands.items()):
        for param in command.params:
            kind = getattr(getattr(param, "type_descriptor", None), "annotation", None)
            if kind in (float, int) and param.opts and param.opts[0].startswith("--"):
                has_out = any("--out" in p.opts for p in command.params)
                for bad in ("1_0", "٣", "0x10", "1e1_0", "１"):
                    out.append(([name, param.opts[0], bad, *(["--out", "unused"] if has_out
                                                             else [])], param.opts[0]))
    return out


def balanced(leaves: list[str], ops: list[str]) -> str:
    """A balanced tree of ``leaves`` joined by ``ops`` in turn (shallow, however many leaves)."""
    if len(leaves) == 1:
        return leaves[0]
    m = len(leaves) // 2
    return (f"({balanced(leaves[:m], ops)}{ops[len(leaves) % len(ops)]}"
            f"{balanced(leaves[m:], ops)})")


def large_expressions():
    """Valid-looking expressions up to the reader's size bounds (shapes that are costly for
    SymPy to build: sums, quotients and powers of transcendental terms)."""
    from hypothesis import strategies as st

    leaf = st.sampled_from(["exp(0.37*t)*tanh(theta*1.3+H)", "(0.5+t)/(H-0.002)",
                            "sqrt(t+0.1)", "log(1+p)*q", "atan(q/p)", "t**theta"])
    ops = st.sampled_from([["+", "*", "-", "/"], ["/"], ["+", "/"], ["**"], ["*"]])
    return st.builds(balanced, st.lists(leaf, min_size=20, max_size=400), ops)


# ---- reading one case (in the worker) ---------------------------------------------------------
def one_line(message: str) -> bool:
    return "\n" not in message and 0 < len(message) < 2100


def run_case(kind: str, case) -> tuple[str, str]:
    """Read one case; return (outcome, detail)."""
    import tomli_w

    import test_hostile_csv as hc
    import test_hostile_expressions as he
    import test_hostile_study as hs
    from magtact.metamodel import parse_expression
    from magtact.study import StudyError, load_study
    from magtact.validation import DataError, read_experiment

    if kind in SAFETY:
        with tempfile.TemporaryDirectory() as tmp:
            try:
                return SAFETY[kind](Path(tmp), case)
            except AssertionError as exc:
                return "wrongly_accepted", f"{exc!r}"[:300]
            except Exception as exc:  # noqa: BLE001 - counting every other exception is the point
                return "traceback", f"{type(exc).__name__}: {exc}"[:300]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        try:
            if kind.startswith("study"):
                if kind == "study_toml":
                    try:
                        data = tomli_w.dumps(case).encode("utf-8")
                    except (TypeError, ValueError, OverflowError):
                        return "skip", ""
                else:
                    data = case.encode("utf-8") if isinstance(case, str) else case
                path = folder / "s.toml"
                path.write_bytes(data)
                try:
                    s = load_study(path)
                except StudyError as exc:
                    return ("clean" if one_line(str(exc)) else "traceback"), str(exc)[:200]
                hs.assert_within_bounds(s)
                return "accepted", ""
            if kind.startswith("csv"):
                if kind == "csv_tables":
                    paths = []
                    for k, table in enumerate(case):
                        paths.append(folder / f"t{k}.csv")
                        paths[-1].write_bytes(hc.render(*table).encode("utf-8"))
                else:
                    paths = [folder / "raw.csv"]
                    paths[0].write_bytes(case if isinstance(case, bytes)
                                         else case.encode("utf-8", "surrogatepass"))
                try:
                    read_experiment(paths)
                except DataError as exc:
                    return ("clean" if one_line(str(exc)) else "traceback"), str(exc)[:200]
                hc.read_or_refuse(paths)  # the oracle (raises AssertionError if a rule fails)
                return "accepted", ""
            try:
                expr = parse_expression(case)
            except ValueError as exc:
                return ("clean" if one_line(str(exc)) else "traceback"), str(exc)[:200]
            he.assert_accepted(expr)
            return "accepted", ""
        except AssertionError as exc:
            return "wrongly_accepted", f"{exc!r}"[:300]
        except Exception as exc:  # noqa: BLE001 - counting every other exception is the point
            return "traceback", f"{type(exc).__name__}: {exc}"[:300]


# ---- the results folder, the command line and the value checks (in the worker) -----------------
def _refusal(exc: Exception, *fragments: str) -> tuple[str, str]:
    text = str(exc)
    if not one_line(text):
        return "traceback", text[:200]
    assert all(f in text for f in fragments), (fragments, text[:300])
    return "clean", text[:200]


def _main(args: list[str]) -> tuple[int, str]:
    """Exit status and output of the command line's entry point (in this process)."""
    from test_command_outputs import cli

    return cli(*args)


def _user_files(tmp: Path, case) -> tuple[str, str]:
    import test_runfolder as tr
    from magtact import _runfolder

    plants = [tr._user_study_beside, tr._user_file_in_stage_folder, tr._edited_output,
              tr._user_folder, tr._link_in_place]
    plant, after = plants[case[0]], case[1]
    folder = tmp / "R"
    folder.mkdir()
    mp_ = _Patch()
    if after or case[0] in (1, 2):
        tr.run(folder, "First", mp_)
    name = plant(folder)
    before = tr.files(folder)
    try:
        tr.run(folder, "Second", mp_)
    except _runfolder.NotMagtactsFile as exc:
        assert tr.files(folder) == before, "a refused run changed the folder"
        return _refusal(exc, str(folder / name))
    finally:
        mp_.undo()
    raise AssertionError(f"a run replaced {name}")


class _Patch:
    """The part of pytest's monkeypatch that the tests' helpers use."""

    def __init__(self):
        self.saved = []

    def setattr(self, obj, name, value):
        self.saved.append((obj, name, getattr(obj, name)))
        setattr(obj, name, value)

    def undo(self):
        for obj, name, value in reversed(self.saved):
            setattr(obj, name, value)
        self.saved.clear()


def _killed_runs(tmp: Path, case) -> tuple[str, str]:
    import signal

    import test_runfolder as tr
    from magtact.report._html import build_report

    sig, pause = getattr(signal, "SIG" + case[0]), case[1]
    folder = tmp / "R"
    folder.mkdir()
    mp_ = _Patch()
    try:
        tr.run(folder, "First", mp_)
    finally:
        mp_.undo()
    proc = tr.start(tmp, "Second", pause, folder)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == (143 if sig == signal.SIGTERM else -signal.SIGKILL), err[-300:]
    if sig == signal.SIGTERM:
        assert b"terminated by a signal (SIGTERM)" in err
    in_place = pause.startswith("move:")
    if not in_place:
        assert tr.consistent(folder) == "First"
    html = build_report(folder).read_text()
    assert tr.consistent(folder) == ("Second" if in_place else "First")
    assert ("<b>Interrupted run.</b>" in html) is not in_place
    return "clean", ""


def _concurrent_runs(tmp: Path, case) -> tuple[str, str]:
    import signal

    import test_runfolder as tr
    from magtact import _runfolder

    folder = tmp / "R"
    folder.mkdir()
    mp_ = _Patch()
    proc = tr.start(tmp, "Busy", ["stage:field", "stage:metamodel", "swap"][case], folder)
    try:
        mp_.setattr(_runfolder, "LOCK_PATIENCE_S", 0.2)
        try:
            tr.run(folder, "Other", mp_)
        except _runfolder.FolderInUse as exc:
            return _refusal(exc, f"process {proc.pid} on ")
        raise AssertionError("a second run into a folder in use was accepted")
    finally:
        mp_.undo()
        proc.send_signal(signal.SIGTERM)
        proc.communicate(timeout=60)


def _ordered_settings(tmp: Path, case) -> tuple[str, str]:
    from magtact.study import StudyError, study_from_dict

    pair, low, ratio = case
    doc: dict = {}
    for key, value in zip(pair, (min(low * ratio, 1.0), low), strict=True):
        section, name = key.split(".")
        doc.setdefault(section, {})[name] = value
    try:
        study_from_dict(doc)
    except StudyError as exc:
        return _refusal(exc)
    raise AssertionError(f"accepted {doc}")


def _holdout(tmp: Path, case) -> tuple[str, str]:
    from magtact.metamodel import holdout_paths
    from magtact.study import StudyError, check_holdout, study_from_dict

    n_theta, n_H, n = case
    try:
        s = study_from_dict({"doe": {"n_theta": n_theta, "n_H": n_H},
                             "metamodel": {"holdout_paths": n}})
    except StudyError as exc:
        return _refusal(exc)  # another setting's bound
    try:
        check_holdout(s)
    except StudyError as exc:
        try:
            holdout_paths(range(n_theta), range(n_H), n)
        except ValueError:
            return _refusal(exc, "holdout_paths")
        raise AssertionError(f"refused {case}, which the fit accepts") from None
    holdout_paths(range(n_theta), range(n_H), n)  # the fit accepts what the check accepts
    return "accepted", ""


def _csv_numbers(tmp: Path, case) -> tuple[str, str]:
    import math
    import re

    import test_hostile_values as hv
    from magtact.validation import DataError, read_experiment

    paths = [hv.table(tmp, "ok.csv", [-0.5 * k for k in range(5)], 2),
             hv.table(tmp, "bad.csv", [-0.5 * k for k in range(5)], cell=case)]
    valid = re.fullmatch(r"[+-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][+-]?[0-9]+)?", case.strip())
    try:
        exp = read_experiment(paths)
    except DataError as exc:
        assert not (valid and math.isfinite(float(case)) and 0 < abs(float(case)) <= 10
                    ), f"refused {case!r}"
        return _refusal(exc, "bad.csv")
    assert valid, f"accepted {case!r}"
    assert float(case) in exp.curves[1].values["B_z"]
    return "accepted", ""


def _shared_range(tmp: Path, offset) -> tuple[str, str]:
    import test_hostile_values as hv
    from magtact.validation import DataError, PathModel, read_experiment, validate

    a = hv.table(tmp, "a.csv", [-0.5 * k for k in range(5)])
    b = hv.table(tmp, "b.csv", [offset - 0.5 * k for k in range(5)], repeat=2)
    shared = 2.0 + min(offset, 0.0) if offset > -2.0 else 0.0
    model = PathModel(lambda u: {r: 1.0 + 0 * u for r in ("B_r", "B_z", "F_r", "F_z")}, 0.3)
    try:
        validate(read_experiment([a, b]), model)
    except DataError as exc:
        assert shared < max(1e-3, 0.05 * 2.0) + 1e-9, f"refused a shared {shared} mm"
        return _refusal(exc, "b.csv")
    assert shared >= max(1e-3, 0.05 * 2.0) - 1e-9, f"accepted a shared {shared} mm"
    return "accepted", ""


def _option_numbers(tmp: Path, case) -> tuple[str, str]:
    args, option = case
    code, text = _main(args)
    assert code != 0, f"{args} accepted"
    if code != 2 or "Traceback" in text or option not in text:
        return "traceback", text[:200]
    return "clean", text[:200]


def _option_messages(tmp: Path, case) -> tuple[str, str]:
    args, fragment = case
    args = [str(tmp / "o") if a == "{tmp}" else a for a in args]
    code, text = _main(args + (["--out", str(tmp / "v")] if args[0] == "validate" else []))
    assert code != 0, f"{args} accepted"
    if code != 2 or "Traceback" in text:
        return "traceback", text[:200]
    assert fragment in text and "1/m" not in text and "n_grid" not in text, text[:300]
    return "clean", text[:200]


def _model_files(tmp: Path, case) -> tuple[str, str]:
    from magtact._errors import MagtactError
    from magtact.metamodel import load_model, prefitted_dir

    where, ndigits = case
    doc = json.loads((prefitted_dir() / "f_z.json").read_text())
    place = "__BIG__"
    if where == 0:
        doc["info"] = {"n": place, **doc.get("info", {})}
    elif where == 1:
        doc["variables"] = [place, *doc["variables"]]
    else:
        doc["extra"] = [[[place]]]
    text = json.dumps(doc).replace(f'"{place}"', ("-" if where == 1 else "") + "9" * ndigits)
    path = tmp / "m.json"
    path.write_text(text)
    try:
        load_model(path)
    except MagtactError as exc:
        return _refusal(exc, "m.json")
    raise AssertionError("a model file with a huge integer was read")


def _not_a_file(tmp: Path, case) -> tuple[str, str]:
    import os

    from magtact._errors import MagtactError
    from magtact.doe import load_dataset
    from magtact.metamodel import load_models
    from magtact.study import load_study
    from magtact.validation import read_experiment

    reader, kind = case
    names = ["s.toml", "d.csv", "doe.nc", "B_r.json"]
    folder = tmp / "models" if reader == 3 else tmp
    folder.mkdir(exist_ok=True)
    path = folder / names[reader]
    if kind == "loop":
        os.symlink(path.name + ".b", path)
        os.symlink(path.name, folder / (path.name + ".b"))
    elif kind == "fifo":
        os.mkfifo(path)
    elif kind == "folder":
        path.mkdir()
    else:
        os.symlink("nowhere", path)
    read = [load_study, lambda p: read_experiment([p]), load_dataset,
            lambda p: load_models(p.parent)][reader]
    try:
        read(path)
    except MagtactError as exc:
        said = {"loop": "symbolic link loop", "fifo": "FIFO", "folder": "folder",
                "broken-link": "broken symbolic link"}[kind]
        return _refusal(exc, names[reader], said)
    raise AssertionError(f"{kind} read as a {names[reader]}")


def _broken_pipe(tmp: Path, command) -> tuple[str, str]:
    import magtact.cli._app as cli_app
    from magtact.cli._app import BrokenPipeFault

    def broken(source=None):
        raise BrokenPipeError(32, "Broken pipe")

    saved = cli_app.load_study
    cli_app.load_study = broken
    try:
        code, text = _main([command] + ([] if command == "study" else
                                        ["--out", str(tmp / "o")])
                           + (["--H", "3", "--theta", "0.2"] if command == "simulate" else []))
    except BrokenPipeFault as exc:  # a fault: the interpreter prints it with its traceback
        return ("clean" if "worker" in str(exc) else "traceback"), str(exc)[:200]
    finally:
        cli_app.load_study = saved
    raise AssertionError(f"exit {code} without saying why: {text[:200]!r}")


def _file_modes(tmp: Path, umask) -> tuple[str, str]:
    import os
    import stat

    import test_runfolder as tr

    old = os.umask(umask)
    mp_ = _Patch()
    try:
        tr.run(tmp / "R", "Modes", mp_)
    finally:
        os.umask(old)
        mp_.undo()
    modes = {stat.S_IMODE(p.stat().st_mode) for p in (tmp / "R").rglob("*") if p.is_file()}
    assert modes == {0o666 & ~umask}, (oct(umask), sorted(map(oct, modes)))
    return "clean", ""


def _command_result(code: int, text: str, before: dict, now: dict, *fragments: str
                    ) -> tuple[str, str]:
    if code == 1:
        return "traceback", text[-300:]
    assert code == 2, f"exit {code}: {text[-300:]}"
    assert now == before, "a refused command changed the folder"
    assert text.count("error:") == 1, text[-300:]
    return _refusal(Exception(text[text.index("error:"):]), *fragments)


def _command_user_files(tmp: Path, case) -> tuple[str, str]:
    import test_command_outputs as tc

    command, name = case
    out = tmp / "o"
    before = tc.plant(out, [name])
    code, text = _main([command, *tc.COMMANDS[command][0], "--out", str(out)])
    return _command_result(code, text, before, tc.placed(out), f"{out / name} is not magtact's")


def _command_outputs(tmp: Path, case) -> tuple[str, str]:
    import test_command_outputs as tc
    from magtact import _runfolder

    users, expect, earlier = case
    if earlier:
        with _runfolder.command_outputs(tmp, "cmd") as o:
            tc.write_all(o.folder, "old")
    before = tc.plant(tmp, sorted(users))
    try:
        with _runfolder.command_outputs(tmp, "cmd", expect) as o:
            tc.write_all(o.folder, "new")
    except _runfolder.NotMagtactsFile as exc:
        assert users, "refused with nothing of the user's in the way"
        assert tc.placed(tmp) == before, "a refused command changed the folder"
        return _refusal(exc, *(str(tmp / n) for n in (users & expect or users)))
    assert not users, f"the user's {sorted(users)} replaced"
    assert all((tmp / n).read_text() == f"new {n}\n" for n in tc.NAMES)
    return "accepted", ""


def _command_in_use(tmp: Path, command) -> tuple[str, str]:
    import os
    import subprocess
    import time

    import test_command_outputs as tc
    from magtact import _runfolder

    folder, ready = tmp / "R", tmp / "ready"
    folder.mkdir()
    proc = subprocess.Popen([sys.executable, "-c", tc.HOLDER, str(folder), str(ready)],
                            env=os.environ | {"PYTHONPATH": os.pathsep.join(sys.path)})
    mp_ = _Patch()
    try:
        while not ready.exists():
            assert proc.poll() is None, "the process holding the lock ended"
            time.sleep(0.05)
        mp_.setattr(_runfolder, "LOCK_PATIENCE_S", 0.2)
        before = tc.placed(folder)
        code, text = _main([command, *tc.COMMANDS[command][0], "--out", str(folder)])
        return _command_result(code, text, before, tc.placed(folder),
                               f"in use by another magtact run: process {proc.pid} on ")
    finally:
        mp_.undo()
        proc.kill()
        proc.wait()


def _command_in_run(tmp: Path, command) -> tuple[str, str]:
    import test_command_outputs as tc
    import test_runfolder as tr

    folder = tmp / "R"
    mp_ = _Patch()
    try:
        tr.run(folder, "First", mp_)
    finally:
        mp_.undo()
    before = tr.files(folder)
    code, text = _main([command, *tc.COMMANDS[command][0], "--out", str(folder / "optimise")])
    outcome = _command_result(code, text, before, tr.files(folder),
                              "belongs to the results of the magtact run")
    assert tr.consistent(folder) == "First"
    return outcome


# ---- what a designer types or flashes (in the worker) ------------------------------------------
def designer_cases(n: int) -> dict[str, list]:
    """Kinds of the designer's own inputs: seed studies, press files and their fit, options
    that cannot take effect, pairs of settings, quoted cells, numbers given as other types,
    unit mistakes, the study check, and readings fed to the firmware header."""
    from hypothesis import strategies as st

    small = max(n // 10, 20)
    json_leaf = st.one_of(st.none(), st.booleans(), st.integers(-10**30, 10**30),
                          st.floats(allow_nan=False, allow_infinity=False), st.text(max_size=8))
    json_doc = st.recursive(json_leaf, lambda c: st.one_of(
        st.lists(c, max_size=4), st.dictionaries(st.sampled_from(
            ["spread", "jacobian", "published", "acc_f_r", "acc_f_z", "max", "n", "x"]), c,
            max_size=4)), max_leaves=20)
    cell = st.one_of(st.floats(-1e3, 1e3).map(repr), st.floats().map(repr),
                     st.sampled_from(["1e308", "-1e308", "nan", "inf", "", "\"0.5", "0.5\"",
                                      "\"0.5\"", "1_0", "0x10", "35", "2500", "-3e5", "١"]),
                     st.text(alphabet="0123456789.eE+-\" ", max_size=8))
    plausible = sorted(PLAUSIBLE_KEY_UNITS)
    return {
        "seeds_files": [("device", "/dev/zero"), ("device", "/dev/urandom"), ("fifo", ""),
                        ("large", ""), ("link", "/dev/zero")]
                       + [("json", d) for d in generate(json_doc, small, 21)],
        "press_files": [("rows", n_rows) for n_rows in (10_001, 1_000_000)]
                       + [("cells", c) for c in generate(st.lists(cell, min_size=6,
                                                                   max_size=6), small, 22)],
        "press_fits": [("random", seed) for seed in range(10)] + [("large", 10_000)],
        "option_effect": OPTION_EFFECT_CASES,
        "physical_pairs": generate(st.tuples(st.floats(1e-3, 200.0), st.floats(-1.0, 1.0),
                                             st.sampled_from(["custom", "N35", "N52"])),
                                   small, 23),
        "csv_quotes": generate(st.text(alphabet="0.5\"', ", min_size=1, max_size=8), small, 24),
        "number_types": ["3", b"3", True, None, [3.0], 3 + 0j, "nan", float("nan"), 3, 3.0,
                         "٣", object()],
        "unit_mistakes": generate(st.tuples(st.sampled_from(plausible), st.floats(0.0, 1.0),
                                            st.integers(-1, 2)), small, 25),
        "study_check": generate(st.tuples(st.integers(1, 6), st.integers(1, 6),
                                          st.integers(0, 12), st.floats(1.5, 100.0),
                                          st.floats(1.0, 60.0), st.floats(5.0, 20.0)),
                                small, 26),
        "firmware_readings": generate(st.tuples(st.sampled_from(["any", "near rest"]), st.lists(
            st.one_of(st.floats(), st.floats(-0.1, 0.1),
                      st.sampled_from([0.0, -0.0, 1e-300, 1e300])),
            min_size=3, max_size=3)), small, 27),
        "forged_results": [(damage, target) for damage in FORGERIES for target in FORGED_FILES
                           if (damage, target) not in UNFIT]
                          + [("json", c) for c in generate(st.tuples(st.sampled_from(
                              ["optimise/card.json", "optimise/explorer.json", "run.json",
                               "budget/budget.json", "optimise/chosen.json"]), json_doc),
                              small, 28)],
        "press_sign": generate(st.tuples(st.floats(0.5, 2.0), st.floats(0.8, 1.2),
                                         st.floats(-2e-4, 2e-4), st.sampled_from(FLIPS),
                                         st.integers(0, 2**16)), small, 30),
    }


#: Damage planted in a results folder (:func:`_forged_results`), and the files it is planted in.
FORGERIES = ("deep", "huge_array", "fifo", "device", "sparse", "loop", "wrong_type", "not_png",
             "dev_zero")
FORGED_FILES = ("optimise/card.json", "optimise/explorer.json", "run.json",
                "budget/budget.json", "publication/publication.json", "doe/captions.json",
                "optimise/chosen.json", "study.toml", "doe/notes.md", "optimise/pareto_set.png",
                "doe/table.csv", ".magtact-staging-0/run.json")
#: Files of text (notes, a table): brackets or JSON in them are text, not damage.
TEXT_FILES = ("doe/notes.md", "doe/table.csv")
#: Records read field by field (a value of the wrong type is left out, the rest shown): an
#: object of wrong types is one of them with nothing in it.
LENIENT = ("run.json", "optimise/chosen.json", "publication/publication.json")
#: Pairs whose damage does not apply to the file (a PNG check of a JSON file).
UNFIT = {(d, t) for d in ("not_png",) for t in FORGED_FILES if not t.endswith(".png")}
#: Sign conventions of press files (:func:`_press_sign`): the map's (F_z > 0 in compression),
#: the load's (−F), only F_z flipped, the field flipped (magnet upside down).
FLIPS = ("none", "load", "z", "field")


#: The study keys of the unit-mistake check and the unit of each (section.setting -> unit).
PLAUSIBLE_KEY_UNITS = {
    "body.R": "mm", "body.H_g": "mm", "magnet.R_m": "mm", "magnet.H_m": "mm",
    "material.G_ref": "kPa", "magnet.M_z": "A_per_m", "design.G_original": "kPa",
    "design.H_original": "mm",
}
#: (arguments, fragment): options that cannot take effect or take one form in two commands.
OPTION_EFFECT_CASES = [
    (["calibrate", "--out", "{tmp}", "--H", "3", "--G", "22.57", "--fit", ""],
     "--fit cannot take effect without --presses"),
    (["calibrate", "--out", "{tmp}", "--H", "3", "--G", "22.57", "--fit", "G_scale"],
     "--fit cannot take effect without --presses"),
    (["calibrate", "--out", "{tmp}", "--H", "3", "--G", "22.57", "--model-error", "0.1"],
     "--model-error cannot take effect without --presses"),
    (["calibrate", "--out", "{tmp}", "--H", "3", "--G", "22.57", "--noise-uT", "1;2"],
     "--noise-uT must be 'X,Z' or one number"),
    (["budget", "--H", "3", "--G", "22.57", "--noise-uT", "1;2"],
     "--noise-uT must be 'X,Z' or one number"),
    (["calibrate", "--out", "{tmp}", "--H", "3", "--G", "22.57", "--noise-uT", "0.5,2e5"],
     "--noise-uT must be between"),
    (["budget", "--H", "3", "--G", "22.57", "--noise-uT", "0.5,2e5"],
     "--noise-uT must be between"),
    (["budget", "--H", "0.003", "--G", "22.57"], "did you give metres?"),
    (["calibrate", "--out", "{tmp}", "--H", "3", "--G", "22570"], "did you give pascals?"),
    (["budget", "--H", "3", "--G", "22.57", "--noise-uT", "2,3"], None),
]

_CACHE: dict = {}


def _seeds_files(tmp: Path, case) -> tuple[str, str]:
    import math
    import os

    from magtact._errors import MagtactError
    from magtact.cli._budget import _seeds

    kind, value = case
    if kind in ("device", "link"):
        path = Path(value)
        if kind == "link":
            path = tmp / "seeds.json"
            path.symlink_to(value)
        code, text = _main(["budget", "--H", "3", "--G", "22.57", "--seed-study", str(path)])
        if code != 2 or "Traceback" in text:
            return "traceback", text[:200]
        assert "is a device" in text, text[:300]
        return "clean", text[:200]
    path = tmp / "seeds.json"
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "large":
        with path.open("wb") as fh:
            fh.truncate(50_000_000)
    else:
        path.write_text(json.dumps(value), encoding="utf-8")
    try:
        data = _seeds(path)
    except MagtactError as exc:
        return _refusal(exc, "--seed-study")
    for entry in data["spread"].values():
        for acc in entry.values():
            assert math.isfinite(acc["max"]) and 0 <= acc["max"] <= 1e3, acc
    return "accepted", ""


def _press_files(tmp: Path, case) -> tuple[str, str]:
    import math

    from magtact.calibration import PRESS_COLUMNS, read_presses
    from magtact.calibration._unit import MAX_FIELD, MAX_FORCE, MAX_PRESSES
    from magtact.validation import DataError

    kind, value = case
    path = tmp / "presses.csv"
    with path.open("w", encoding="utf-8") as fh:
        fh.write(",".join(PRESS_COLUMNS) + "\n")
        if kind == "rows":
            fh.write("0,0,0.03,0,0,0\n" * value)
        else:
            fh.write(",".join(value) + "\n")
    try:
        p = read_presses(path)
    except DataError as exc:
        return _refusal(exc, "presses.csv")
    assert len(p) <= MAX_PRESSES, len(p)
    assert all(math.isfinite(v) for v in [*p.B.ravel(), *p.F.ravel()])
    assert abs(p.B).max() <= MAX_FIELD and abs(p.F).max() <= MAX_FORCE
    return "accepted", ""


def _design_map():
    if "smap" not in _CACHE:
        from magtact.calibration import sensor_map
        from magtact.metamodel import load_models, prefitted_dir
        from magtact.optimise import per_design
        from magtact.study import load_study

        s = load_study(None)
        ms = load_models(prefitted_dir())
        _CACHE["smap"] = sensor_map(ms, s, 3e-3, 22.57e3, design=per_design(ms, 3e-3, 22.57e3, s))
    return _CACHE["smap"]


def _press_fits(tmp: Path, case) -> tuple[str, str]:
    """Presses of a unit fitted: random readings (refused, or fitted to finite parameters),
    and 10,000 presses of a real unit (the largest file allowed: memory linear in the
    presses)."""
    from dataclasses import replace

    import numpy as np

    from magtact._errors import MagtactError
    from magtact.calibration import Presses, UnitParameters, calibrate_unit

    kind, value = case
    smap = _design_map()
    rng = np.random.default_rng(value)
    if kind == "random":
        n = int(rng.integers(2, 30))
        B = rng.uniform(-0.05, 0.05, (n, 3))
        F = rng.uniform(-5.0, 5.0, (n, 3))
    else:
        unit = replace(smap, field_source="exact").with_unit(UnitParameters(0.9, 1.02,
                                                                            (1e-4, 0, 0)))
        L = smap.region_samples(value, seed=1)
        B, F = unit.at_load(0.95 * L[:, 0], 0.95 * L[:, 1], L[:, 2])
        B = B + rng.normal(0, 1e-6, B.shape)
    try:
        cal = calibrate_unit(smap, Presses(B, F))
    except MagtactError as exc:
        return _refusal(exc, "presses")
    assert np.isfinite(cal.unit.vector()).all()
    if kind == "large":
        assert abs(cal.unit.G_scale - 0.9) < 1e-2 and abs(cal.unit.B_scale - 1.02) < 1e-2
    return "accepted", ""


def _option_effect(tmp: Path, case) -> tuple[str, str]:
    args, fragment = case
    code, text = _main([str(tmp / "o") if a == "{tmp}" else a for a in args])
    if fragment is None:  # the one form of --noise-uT, accepted, replacing the chip's figure
        assert code == 0, text[:300]
        assert "in place of the chip's own figure" in " ".join(text.split()), text[:300]
        return "accepted", ""
    assert code != 0, f"{args} accepted"
    if code != 2 or "Traceback" in text:
        return "traceback", text[:200]
    assert fragment in " ".join(text.split()), text[:300]
    return "clean", text[:200]


def _physical_pairs(tmp: Path, case) -> tuple[str, str]:
    from magtact.parts import grade
    from magtact.study import StudyError, study_from_dict

    delta_T, tc_pct, name = case
    data = {"environment": {"delta_T_K": delta_T, "remanence_tc_pct_per_K": tc_pct},
            "magnet": {"grade": name}}
    # the MagOne magnet (custom, μ0 M_z = 1.51 T) is sintered NdFeB: the N series' limit
    limit = grade("N35" if name == "custom" else name).max_temperature_C
    beyond = abs(delta_T * tc_pct / 100) > 0.5 or delta_T > limit - 20.0
    try:
        study_from_dict(data)
    except StudyError as exc:
        assert beyond, f"refused {case}: {exc}"
        return _refusal(exc, "[environment.delta_T_K]")
    assert not beyond, f"accepted {case}"
    return "accepted", ""


def _csv_quotes(tmp: Path, case) -> tuple[str, str]:
    import csv

    import test_hostile_values as hv
    from magtact.validation import DataError, read_experiment

    row = f"-0.5,0.001,{case},0.01,-0.5"
    try:
        cells = next(csv.reader([row], strict=True))
        strict_ok = True
    except csv.Error:
        strict_ok, cells = False, []
    paths = [hv.table(tmp, "ok.csv", [-0.5 * k for k in range(5)], 2),
             hv.table(tmp, "bad.csv", [-0.5 * k for k in range(5)])]
    lines = paths[1].read_text().splitlines()
    lines[4] = row  # the second sample (after two metadata lines and the header)
    paths[1].write_text("\n".join(lines) + "\n")
    try:
        read_experiment(paths)
    except DataError as exc:
        return _refusal(exc, "bad.csv")
    assert strict_ok and len(cells) == 5, f"accepted {row!r}"
    return "accepted", ""


def _number_types(tmp: Path, case) -> tuple[str, str]:
    import numbers

    from magtact._errors import MagtactError
    from magtact.study import checked_si

    try:
        si = checked_si(case, "mm", "H_mm")
    except MagtactError as exc:
        return _refusal(exc, "H_mm")
    assert isinstance(case, numbers.Real) and not isinstance(case, bool), repr(case)
    assert si == case / 1000
    return "accepted", ""


def _unit_mistakes(tmp: Path, case) -> tuple[str, str]:
    """A key's original value written as if in a neighbouring unit (power -1, 0, 1 or 2 of
    its factor): refused naming the key and the unit when implausible, never refused naming
    a key the file does not give."""
    from magtact.study import StudyError, load_study, study_from_dict, to_si
    from magtact.study._units import NEIGHBOURS, PLAUSIBLE

    name, pick, power = case
    section, setting = name.split(".")
    unit = PLAUSIBLE_KEY_UNITS[name]
    base = getattr(getattr(load_study(None), section), setting)
    label, factor = NEIGHBOURS[unit][int(pick * len(NEIGHBOURS[unit])) % len(NEIGHBOURS[unit])]
    written = base / to_si(1.0, unit) / factor ** power
    key = f"{section}.{setting}_{unit}"
    _, lo, hi = PLAUSIBLE[unit]
    mistaken = not lo <= abs(to_si(written, unit)) <= hi and power == 1
    try:
        study_from_dict({section: {key.split(".")[1]: written}})
    except StudyError as exc:
        text = str(exc)
        assert key in text, f"{key} not named: {text[:300]}"
        if mistaken:
            assert label in text, f"{label} not suggested: {text[:300]}"
        return _refusal(exc, key)
    assert not mistaken, f"accepted {key} = {written} ({label})"
    return "accepted", ""


def _study_check(tmp: Path, case) -> tuple[str, str]:
    import numpy as np

    from magtact.geometry import hall_from_magnet_centre, loading_path
    from magtact.study import StudyError, check_study, holdout_limit, load_study

    n_theta, n_H, holdout, far_r, far_z, near = case
    path = tmp / "s.toml"
    path.write_text(f"[doe]\nn_theta = {n_theta}\nn_H = {n_H}\n[metamodel]\nholdout_paths = "
                    f"{holdout}\n[magnetics]\nfar_r = {far_r!r}\nfar_z = {far_z!r}\n"
                    f"near_mm = {near!r}\n")
    try:
        s = load_study(path)
    except StudyError as exc:
        return _refusal(exc, "s.toml")
    m, f = s.magnet, s.magnetics
    # the Hall point's reach from the magnet, as the geometry and the field solver see it
    T, TH, HH = np.meshgrid(s.t_levels, s.theta_levels, s.H_levels, indexing="ij")
    x, z = hall_from_magnet_centre(s, *loading_path(s, T, TH, HH), HH)
    reach = np.hypot(np.maximum(np.abs(x) - m.R_m, 0), np.maximum(np.abs(z) - m.H_m / 2, 0))
    bad = (holdout > holdout_limit(n_theta, n_H) or far_r * m.R_m <= m.R_m + f.near
           or far_z * m.H_m <= m.H_m / 2 + f.near or reach.max() > f.near)
    code, text = _main(["study", str(path), "--recompute"])  # the rules, not the data's coverage
    try:
        check_study(s)
        checked = True
    except StudyError:
        checked = False
    assert checked == (code == 0) == (not bad), (case, code, text[:200])
    if bad:
        if code != 2 or "Traceback" in text:
            return "traceback", text[:200]
        return "clean", text[:200]
    return "accepted", ""


def _firmware_readings(tmp: Path, case) -> tuple[str, str]:
    """Readings of any value through the compiled header (double): rc 0, 1 or 2, every output
    finite, zero unless rc is 0."""
    import math
    import subprocess

    if "fw" not in _CACHE:
        from magtact.calibration import c_header, firmware_approximation

        smap = _design_map()
        choice = firmware_approximation(smap, (4.6e-5, 9.0e-5), degrees=(12,), table_sizes=(),
                                        n_test=2000)
        folder = Path(tempfile.mkdtemp())
        (folder / "force.h").write_text(c_header(choice.chosen, smap, choice,
                                                 noise=(1e-6, 1e-6)))
        (folder / "m.c").write_text(
            "#include <stdio.h>\n#include <stdlib.h>\n#include \"force.h\"\n"
            "int main(int argc, char **argv)\n{\n    MAGTACT_REAL o[3];\n    int rc;\n"
            "    (void)argc;\n    rc = magtact_force(strtod(argv[1], NULL), strtod(argv[2], "
            "NULL), strtod(argv[3], NULL), NULL, o);\n"
            "    printf(\"%d %.17g %.17g %.17g\\n\", rc, o[0], o[1], o[2]);\n    return 0;\n}\n")
        subprocess.run(["gcc", "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-o",
                        str(folder / "m"), str(folder / "m.c"), "-lm"], check=True)
        _CACHE["fw"] = folder / "m"
    mode, case = case
    if mode == "near rest":  # the rest field plus up to 5 µT (clipped) per axis
        from magtact.calibration._firmware import rest_field

        rest = rest_field(_design_map())
        case = [float(r + 5e-6 * max(-1.0, min(1.0, v / 0.1))) if math.isfinite(v) else v
                for r, v in zip(rest, case, strict=True)]
    run = subprocess.run([str(_CACHE["fw"]), *(repr(float(v)) for v in case)],
                         capture_output=True, text=True, check=True, timeout=10)
    rc, *out = run.stdout.split()
    out = [float(v) for v in out]
    assert rc in ("0", "1", "2"), run.stdout
    assert all(math.isfinite(v) for v in out), (case, run.stdout)
    assert rc == "0" or out == [0.0, 0.0, 0.0], (case, run.stdout)
    if any(not math.isfinite(v) for v in case) or not case[2] > 0:
        assert rc == "2", (case, run.stdout)
    return ("accepted" if rc == "0" else "clean"), run.stdout.strip()


def _forged_results(tmp: Path, case) -> tuple[str, str]:
    """A results folder with one file damaged or forged (:data:`FORGERIES`), or a generated
    JSON document in place of one of the report's records: the report names the damaged file
    on one line and renders the rest; no traceback, no hang, memory bounded."""
    import os
    import re

    import test_report_reads as tr
    from magtact.report import build_report

    folder = tr.folder_with(tmp)
    (folder / "run.json").write_text(json.dumps({"study": "S", "stages": []}))
    (folder / "budget").mkdir()
    (folder / "publication").mkdir()
    (folder / "study.toml").write_text('name = "S"\n')
    damage, target = case
    if damage == "json":
        target, doc = target
    path = folder / target
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.exists():
        path.unlink()
    if damage == "deep":
        path.write_text("[" * 200_000 + "]" * 200_000)
    elif damage == "huge_array":
        with path.open("w") as fh:
            fh.write('{"H_mm": [' + "1.0," * 3_000_000 + '1.0], "rows": []}')
    elif damage == "fifo":
        os.mkfifo(path)
    elif damage in ("device", "dev_zero"):
        path.symlink_to("/dev/zero" if damage == "dev_zero" else "/dev/urandom")
    elif damage == "sparse":
        with path.open("wb") as fh:
            fh.truncate(2 << 30)
    elif damage == "loop":
        path.symlink_to(path.name)
    elif damage == "wrong_type":
        path.write_text(json.dumps({"header": 3, "rows": {"a": 1}, "stages": "x", "grid": 7,
                                    "format": "magtact-explorer/1", "H_mm": "3"}))
    elif damage == "not_png":
        path.write_bytes(b"GIF89a" + b"\0" * 4096)
    else:
        path.write_text(json.dumps(doc))
    damaged: dict[str, str] = {}
    text = build_report(folder, damaged=damaged).read_text(encoding="utf-8")
    assert "Run summary" in text and "Study settings" in text, "the rest of the report is missing"
    if damage == "json":
        return ("clean" if target in damaged else "accepted"), str(damaged)[:200]
    staged = target.startswith(".magtact-staging")
    if staged:  # an interrupted run's manifest: the report is built, the run named as unknown
        assert "Interrupted run" in text, "the staging folder is not named"
        return "clean", ""
    if target in TEXT_FILES and damage in ("deep", "wrong_type"):  # text that is text
        note = damaged.get(target, "")  # left out only for its size
        assert not note or "at most" in note, damaged
        return ("clean", note) if note else ("accepted", "")
    if target in LENIENT and damage == "wrong_type" and target not in damaged:
        return "accepted", ""  # read field by field: what has its type is shown
    assert target in damaged, f"{target} ({damage}) not named: {damaged}"
    note = damaged[target]
    assert re.fullmatch(r"[^\n]{3,300}", note), note
    return "clean", f"{target}: {note}"[:200]


def _press_sign(tmp: Path, case) -> tuple[str, str]:
    """Presses of a unit (random stiffness, remanence and chip offset) in the map's sign
    convention, in the load's (−F), with only F_z flipped, or with the field flipped: the first
    fitted to its unit, the others refused on one line, never fitted to a negative scale."""
    import numpy as np

    from magtact._errors import MagtactError
    from magtact.calibration import Presses, UnitParameters, calibrate_unit

    g, b, dx, flip, seed = case
    smap = _design_map()
    truth = UnitParameters(g, b, (dx, 0.0, 0.0))
    rng = np.random.default_rng(seed)
    th = smap.theta_m
    loads = np.array([[t, th * k / 4, rng.uniform(-np.pi, np.pi)]
                      for t, k in [(0.0, 0), (0.3, 0), (0.7, 0), (1.0, 0), (0.5, 4), (0.9, 3),
                                   (0.6, 2), (1.0, 4)]])
    from dataclasses import replace

    B, F = replace(smap, field_source="exact").with_unit(truth).at_load(*loads.T)
    if flip == "load":
        F = -F
    elif flip == "z":
        F = F * np.array([1.0, 1.0, -1.0])
    elif flip == "field":
        B = -B
    try:
        cal = calibrate_unit(smap, Presses(B, F))
    except MagtactError as exc:
        # a unit in the map's convention may lack presses to identify a parameter, never be
        # called one in the load's sign
        assert flip != "none" or "negative scale" not in str(exc), (case, str(exc))
        if flip == "load":
            return _refusal(exc, "F_z must be positive in compression")
        return _refusal(exc, "presses")
    u = cal.unit
    assert u.G_scale > 0 and u.B_scale > 0, (case, u)
    assert flip == "none", f"{flip} accepted: {u}"
    assert abs(u.G_scale - g) <= 1e-2 * g and abs(u.B_scale - b) <= 1e-2 * b, (case, u)
    return "accepted", ""


SAFETY = {"user_files": _user_files, "killed_runs": _killed_runs,
          "concurrent_runs": _concurrent_runs, "ordered_settings": _ordered_settings,
          "holdout_paths": _holdout, "csv_numbers": _csv_numbers, "shared_range": _shared_range,
          "option_numbers": _option_numbers, "option_messages": _option_messages,
          "model_files": _model_files, "not_a_file": _not_a_file, "broken_pipe": _broken_pipe,
          "file_modes": _file_modes, "command_user_files": _command_user_files,
          "command_outputs": _command_outputs, "command_in_use": _command_in_use,
          "command_in_run": _command_in_run, "seeds_files": _seeds_files,
          "press_files": _press_files, "press_fits": _press_fits, "option_effect": _option_effect,
          "physical_pairs": _physical_pairs, "csv_quotes": _csv_quotes,
          "number_types": _number_types, "unit_mistakes": _unit_mistakes,
          "study_check": _study_check, "firmware_readings": _firmware_readings,
          "forged_results": _forged_results, "press_sign": _press_sign}


def worker(conn) -> None:
    while True:
        job = conn.recv()
        if job is None:
            return
        conn.send(peak_rss_mb() if job == "rss" else run_case(*job))


def peak_rss_mb() -> tuple[float, float]:
    """Peak resident memory [MB] of this process and of the largest of its finished children
    (the runs and compilers a case starts)."""
    import resource

    return (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
            resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024)


# ---- the driver ---------------------------------------------------------------------------------
class Pool:
    """One worker process fed case by case; killed and restarted when a case hangs."""

    def __init__(self):
        self.proc = None
        self.start()

    def start(self):
        self.conn, child = mp.Pipe()
        self.proc = mp.get_context("fork").Process(target=worker, args=(child,), daemon=True)
        self.proc.start()

    def run(self, kind, case, timeout: float):
        self.conn.send((kind, case))
        if self.conn.poll(timeout):
            return self.conn.recv()
        self.proc.kill()
        self.proc.join()
        self.start()
        return "hang", repr(case)[:200]

    def rss(self) -> tuple[float, float]:
        self.conn.send("rss")
        return self.conn.recv()

    def close(self):
        self.conn.send(None)
        self.proc.join(5)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--n", type=int, default=3000, help="cases per generated reader")
    parser.add_argument("--timeout", type=float, default=10.0, help="seconds before a hang")
    parser.add_argument("--json", default=str(HERE / "results" / "hostile.json"))
    parser.add_argument("--only", default="", help="comma-separated kinds (default: all)")
    args = parser.parse_args()
    start = time.perf_counter()
    generated = cases(args.n)
    if args.only:
        generated = {k: v for k, v in generated.items() if k in args.only.split(",")}
    gen_time = time.perf_counter() - start
    pool = Pool()
    pool.run("expressions", "t", args.timeout)  # imports, so that they do not count as a hang
    results = {}
    for kind, items in generated.items():
        if kind in FRESH:  # a new worker: its peak memory is this kind's alone
            pool.proc.kill()
            pool.proc.join()
            pool.start()
            pool.run("expressions", "t", args.timeout * 6)
        counts = dict.fromkeys(("cases", *OUTCOMES, "skipped"), 0)
        examples: dict[str, list[str]] = {o: [] for o in OUTCOMES if o not in ("clean",
                                                                                "accepted")}
        slowest = 0.0
        t0 = time.perf_counter()
        for case in items:
            c0 = time.perf_counter()
            outcome, detail = pool.run(kind, case, args.timeout * SLOW.get(kind, 1))
            slowest = max(slowest, time.perf_counter() - c0)
            if outcome == "skip":
                counts["skipped"] += 1
                continue
            counts["cases"] += 1
            counts[outcome] += 1
            if outcome in examples and len(examples[outcome]) < 5:
                examples[outcome].append(detail)
        worker_mb, children_mb = pool.rss()  # the worker's peak so far (restarted on a hang)
        results[kind] = {**counts, "slowest_case_s": round(slowest, 3),
                         "wall_time_s": round(time.perf_counter() - t0, 1),
                         "peak_rss_worker_MB": round(worker_mb, 1),
                         "peak_rss_children_MB": round(children_mb, 1),
                         "examples": {k: v for k, v in examples.items() if v}}
        if kind in FRESH:
            results[kind]["fresh_worker"] = True
            results[kind]["rss_limit_MB"] = FRESH_RSS_LIMIT_MB
            results[kind]["below_rss_limit"] = max(worker_mb, children_mb) < FRESH_RSS_LIMIT_MB
        print(kind, {k: v for k, v in results[kind].items() if k != "examples"}, flush=True)
    pool.close()
    total = {o: sum(r[o] for r in results.values()) for o in ("cases", *OUTCOMES)}
    peak = max([peak_rss_mb()[0], *(max(r["peak_rss_worker_MB"], r["peak_rss_children_MB"])
                                    for r in results.values())])
    total["peak_rss_MB"] = round(peak, 1)
    total["rss_limit_MB"] = RSS_LIMIT_MB
    total["every_process_below_limit"] = peak < RSS_LIMIT_MB
    fresh = [max(r["peak_rss_worker_MB"], r["peak_rss_children_MB"])
             for k, r in results.items() if k in FRESH]
    if fresh:
        total["forged_and_press_sign_peak_rss_MB"] = round(max(fresh), 1)
        total["forged_and_press_sign_below_1GB"] = max(fresh) < FRESH_RSS_LIMIT_MB
    report = {
        "benchmark": "hostile inputs through the study, CSV and expression readers; the user's "
                     "files, killed and concurrent runs, ordered settings, numbers, messages, "
                     "exits and file modes; the per-stage commands over the user's files, "
                     "folders in use and finished runs; seed studies, press files and their "
                     "fit, options that cannot take effect, pairs of settings, quoted cells, "
                     "numbers of other types, unit mistakes, the study check, readings "
                     "through the firmware header; forged results folders through the report "
                     "and press files in the load's sign convention through the unit fit",
        "cases_per_reader": args.n, "hang_timeout_s": args.timeout,
        "generation_time_s": round(gen_time, 1),
        "wall_time_s": round(time.perf_counter() - start, 1),
        "total": total, "readers": results,
        "machine": {"python": sys.version.split()[0], "platform": platform.platform()},
    }
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(json.dumps(report, indent=1) + "\n", encoding="utf-8")
    print("total", total)
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
