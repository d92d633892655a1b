"""Wrong values that used to be accepted, messages that misled, exits that said nothing, and
file modes: each class on instances of its own.

* every ordered pair of settings and every number reader;
* every reader of a file the user names says what a path is when it is not a file;
* every non-zero exit of the command line says why.
"""

from __future__ import annotations

import json
import os
import signal
import stat
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from magtact._errors import MagtactError
from magtact._files import write_csv, write_json, write_text
from magtact._numbers import parse_float, parse_int
from magtact.study import StudyError, load_study, study_from_dict
from magtact.validation import DataError, PathModel, read_experiment, validate

HEADER = "u_z_mm,B_r_T,B_z_T,F_r_N,F_z_N"


def table(tmp_path, name, u_z_mm, repeat=1, cell=None):
    rows = [f"{u!r},0.001,0.04,0.01,-0.5" for u in u_z_mm]
    if cell is not None:
        rows[1] = rows[1].replace("0.04", cell, 1)
    path = tmp_path / name
    path.write_text("\n".join(["# theta_rad = 0.3", f"# repeat = {repeat}", HEADER, *rows])
                    + "\n", encoding="utf-8")
    return path


# ---- ordered pairs of settings ---------------------------------------------------------------
#: (smaller key, larger key): a study must keep smaller <= larger (strictly below for growth).
PAIRS = [("mechanics.dt_min", "mechanics.dt_max"), ("mechanics.dt_initial", "mechanics.dt_max"),
         ("mechanics.dt_min", "mechanics.dt_initial"),
         ("magnetics.growth_near", "magnetics.growth")]


@settings(max_examples=30, deadline=None)
@given(pair=st.sampled_from(PAIRS), low=st.floats(0.011, 0.9), ratio=st.floats(1.01, 10.0))
def test_every_ordered_pair_of_settings_is_checked(pair, low, ratio):
    """Any values with the pair out of order (the others at their defaults) are refused, naming
    a key of the pair."""
    doc: dict = {}
    for key, value in zip(pair, (min(low * ratio, 1.0), low), strict=True):
        section, name = key.split(".")
        doc.setdefault(section, {})[name] = value
    with pytest.raises(StudyError) as err:
        study_from_dict(doc)
    assert any(f"[{k}]" in str(err.value) for k in pair), str(err.value)


def test_holdout_larger_than_the_study_doe_is_refused_before_any_work(tmp_path):
    from magtact import pipeline

    s = study_from_dict({"doe": {"n_theta": 3, "n_H": 4}, "metamodel": {"holdout_paths": 3}})
    with pytest.raises(StudyError, match=r"\[metamodel.holdout_paths\] 3 held-out paths, but "
                                         r"the DOE's 3 × 4 .* allow at most 2"):
        pipeline.run_study(s, tmp_path / "R", log=lambda m: None)
    assert not (tmp_path / "R").exists()  # refused before the folder was made


def test_holdout_larger_than_the_data_set_names_file_and_setting():
    from magtact.study import check_holdout

    check_holdout(load_study(None), 2, 6, "ok.nc", "s.toml")  # 8 interior paths: 4 can go
    with pytest.raises(StudyError, match=r"s.toml: \[metamodel.holdout_paths\] 4 held-out "
                                         r"paths, but the data set small.nc has 3 × 3 \(θ, H\) "
                                         r"paths allow at most 1"):
        check_holdout(load_study(None), 3, 3, "small.nc", "s.toml")


@pytest.mark.long
def test_holdout_larger_than_the_data_file_names_file_and_setting(refused, tmp_path):
    import magtact.doe
    from conftest import synthetic_doe

    ds = synthetic_doe(study_from_dict({"doe": {"n_theta": 3, "n_H": 3}}), n_t=4)
    magtact.doe.save_dataset(ds, tmp_path / "small.nc")
    refused(["fit", "--data", str(tmp_path / "small.nc"), "--out", str(tmp_path / "f")],
            "[metamodel.holdout_paths] 4 held-out paths, but the data set",
            "small.nc has 3 × 3 (θ, H) paths allow at most 1")


# ---- validation tables sharing too little displacement ---------------------------------------
@pytest.mark.parametrize(("offset_mm", "fragment"), [
    (-2.0 + 5e-4, "share only 0.0005 mm"),  # half a micrometre
    (-2.0 + 0.06, "share only 0.06 mm"),  # 3 % of the shortest test's 2 mm
])
def test_tests_sharing_a_sliver_of_displacement_are_refused(tmp_path, offset_mm, fragment):
    a = table(tmp_path, "a.csv", [-0.5 * k for k in range(5)])
    b = table(tmp_path, "b.csv", [offset_mm - 0.5 * k for k in range(5)], repeat=2)
    model = PathModel(lambda u: {r: 1.0 + 0 * u for r in ("B_r", "B_z", "F_r", "F_z")}, 0.3)
    with pytest.raises(DataError, match="b.csv, line 4") as err:
        validate(read_experiment([a, b]), model)
    assert fragment in str(err.value)
    c = table(tmp_path, "c.csv", [-0.2 - 0.5 * k for k in range(5)], repeat=3)
    validate(read_experiment([a, c]), model)  # 90 % shared: accepted


# ---- numbers ---------------------------------------------------------------------------------
PYTHON_ONLY = ["1_0.0", "0.0_4", "٣.٥", "１.５", "0x10", "1e1_0", "+-1", "1.5j"]


@pytest.mark.parametrize("cell", PYTHON_ONLY)
def test_csv_numbers_follow_the_usual_grammar(tmp_path, cell):
    bad = table(tmp_path, "bad.csv", [-0.5 * k for k in range(5)], cell=cell)
    with pytest.raises(DataError, match=r"bad.csv: line 5, column 'B_z_T': not a number"):
        read_experiment([table(tmp_path, "ok.csv", [-0.5 * k for k in range(5)], 2), bad])


@pytest.mark.parametrize("meta", ["# design_H_mm = 3_0\n# design_G_kPa = 20",
                                  "# design_H_mm = 3\n# design_G_kPa = ٢٠"])
def test_csv_metadata_numbers_follow_the_usual_grammar(tmp_path, meta):
    path = table(tmp_path, "m.csv", [-0.5 * k for k in range(5)])
    path.write_text(meta + "\n" + path.read_text())
    with pytest.raises(MagtactError, match="is not a number"):
        read_experiment([path, table(tmp_path, "n.csv", [-0.5 * k for k in range(5)], 2)]).design()


@settings(max_examples=300, deadline=None)
@given(st.text(alphabet="0123456789_.eE+- \tx١٣", max_size=12))
def test_parse_float_is_float_on_the_grammar_and_refuses_the_rest(text):
    import re

    grammar = re.fullmatch(r"[ \t]*[+-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][+-]?[0-9]+)?[ \t]*",
                           text)
    if grammar:
        assert parse_float(text) == float(text)
    else:
        with pytest.raises(ValueError, match="not a number"):
            parse_float(text)
    if re.fullmatch(r"[ \t]*[+-]?[0-9]+[ \t]*", text):
        assert parse_int(text) == int(text)
    else:
        with pytest.raises(ValueError, match="not an integer"):
            parse_int(text)


@pytest.mark.parametrize(("args", "option"), [
    (["validate", "--H", "3_0"], "'--H'"), (["validate", "--n-grid", "4_0"], "'--n-grid'"),
    (["doe", "--out", "x", "--workers", "٢"], "'--workers'"),
])
def test_number_options_follow_the_usual_grammar(refused, args, option):
    refused(args, f"Invalid value for {option}", "not a")


def test_model_file_with_a_huge_integer_is_one_line(tmp_path):
    from magtact.metamodel import load_model, prefitted_dir

    good = json.loads((prefitted_dir() / "f_z.json").read_text())
    for n, doc in enumerate([good | {"variables": ["t", "-" + "9" * 6000]},
                             good | {"info": {"nested": [[{"n": "1" * 4400}]]}}]):
        path = tmp_path / f"m{n}.json"
        path.write_text(json.dumps(doc).replace('"-999', "-999").replace('999"', "999")
                        .replace('"1111', "1111").replace('1111"', "1111"))
        with pytest.raises(MagtactError, match=rf"m{n}.json: not a model file \(a number it "
                                               "holds cannot be read"):
            load_model(path)


# ---- messages --------------------------------------------------------------------------------
def test_study_the_bundled_data_do_not_describe_names_the_settings():
    from magtact.doe import bundled_for

    s = study_from_dict({"doe": {"n_G": 3}, "body": {"R_h_mm": 0.8}})
    with pytest.raises(MagtactError) as err:
        bundled_for(s)
    text = str(err.value)
    # the DOE's levels only say how a new DOE would sample: the body needs new mechanics
    assert "needs new mechanics: [body] R_h_mm = 0.8 (the data set's: 1)" in text
    assert "n_G" not in text
    assert "as its data" not in text and "--models MODELS" in text


@pytest.mark.parametrize(("args", "fragment"), [
    (["validate", "--f-lo", "3", "--f-hi", "2"],
     "--f-hi (2 cycles per mm) must be above --f-lo (3 cycles per mm)"),
    (["validate", "--f-lo", "2", "--f-hi", "2"], "--f-hi (2 cycles per mm) must be above"),
    (["validate", "--n-grid", "1"], "Invalid value for '--n-grid'"),
    (["validate", "--floor", "-0.5"], "--floor must be in [0, 1), got -0.5"),
    (["validate", "--floor", "2"], "--floor must be in [0, 1), got 2.0"),
    (["study", "magone-printd"], "no preset has that name (presets: magone, "),
    (["validate", "--mesh", "huge"],  # a typer choice: the option named, then its choices
     ("Invalid value for '--mesh'", "'huge' is not one of 'coarse', 'default', 'accurate', "
                                    "'fine'")),
    (["doe", "--workers", "-3", "--out", "unused"], "Invalid value for '--workers'"),
])
def test_option_messages_name_the_option_in_its_units(refused, tmp_path, args, fragment):
    text = refused([*args, *(["--out", str(tmp_path / "v")] if args[0] == "validate" else [])],
                   *(fragment if isinstance(fragment, tuple) else (fragment,)))
    assert "1/m" not in text and "n_grid" not in text


def _loop(tmp_path, name):
    path = tmp_path / name
    os.symlink(path.name + ".b", path)
    os.symlink(path.name, tmp_path / (name + ".b"))
    return path


def _fifo(tmp_path, name):
    path = tmp_path / name
    os.mkfifo(path)
    return path


@pytest.mark.parametrize("make", [_loop, _fifo], ids=["symlink-loop", "fifo"])
def test_every_reader_says_what_a_path_is(tmp_path, make):
    from magtact.doe import load_dataset
    from magtact.metamodel import load_models

    what = "symbolic link loop" if make is _loop else "FIFO (named pipe)"
    models = tmp_path / "models"
    models.mkdir()
    make(models, "B_r.json")
    readers = [(lambda: load_study(make(tmp_path, "s.toml")), "s.toml"),
               (lambda: read_experiment([make(tmp_path, "d.csv")]), "d.csv"),
               (lambda: load_dataset(make(tmp_path, "doe.nc")), "doe.nc"),
               (lambda: load_models(models), "B_r.json")]
    for read, name in readers:
        with pytest.raises(MagtactError) as err:
            read()
        assert name in str(err.value) and what in str(err.value), str(err.value)
        assert "not found" not in str(err.value)


# ---- exits -----------------------------------------------------------------------------------
def _cli(script: str, **popen):
    env = os.environ | {"PYTHONPATH": os.pathsep.join(sys.path)}
    return subprocess.Popen([sys.executable, "-c", textwrap.dedent(script)], env=env,
                            stderr=subprocess.PIPE, **popen)


def test_a_broken_pipe_in_a_command_is_a_fault_with_its_reason(monkeypatch, tmp_path):
    """In process: the command layer turns the broken pipe into a fault the interpreter prints
    (the next test runs the entry point in a process of its own)."""
    import magtact.cli._app as cli_app
    from magtact.cli import main
    from magtact.cli._app import BrokenPipeFault

    def broken(source=None):
        raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr(cli_app, "load_study", broken)
    monkeypatch.setattr(sys, "argv", ["magtact", "optimise", "--out", str(tmp_path / "o")])
    handler = signal.getsignal(signal.SIGTERM)
    try:
        with pytest.raises(BrokenPipeFault, match="a pipe to another process broke"):
            main()
    finally:
        signal.signal(signal.SIGTERM, handler)


def test_a_closed_reader_is_told_from_another_pipe(monkeypatch):
    from magtact.cli._app import standard_stream_closed

    read, write = os.pipe()
    with os.fdopen(write, "w") as out, os.fdopen(read) as inp:
        monkeypatch.setattr(sys, "stdout", out)
        assert not standard_stream_closed()
        inp.close()
        assert standard_stream_closed()


@pytest.mark.long
def test_a_broken_pipe_to_a_worker_exits_with_its_reason():
    """A pipe other than the terminal's output breaking (here: while the study is read, as a
    worker's would) is a fault with its traceback, not a silent exit 1."""
    proc = _cli("""
        import sys
        import magtact.cli._app as app

        def broken(source):
            raise BrokenPipeError(32, "Broken pipe")
        app.load_study = broken
        sys.argv = ["magtact", "field", "--out", "unused"]
        from magtact.cli import main
        main()
    """, stdout=subprocess.DEVNULL)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 1
    assert "BrokenPipeFault: a pipe to another process broke ([Errno 32] Broken pipe)" in \
        err.decode()


@pytest.mark.long
def test_closed_terminal_output_stays_a_quiet_exit():
    proc = _cli("""
        import sys
        sys.argv = ["magtact", "study", "magone"]
        from magtact.cli import main
        main()
    """, stdout=subprocess.PIPE)
    proc.stdout.close()  # the reader has gone before the study is printed (`| head -0`)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 1 and b"Traceback" not in err, err.decode()


# ---- file modes ------------------------------------------------------------------------------
@pytest.mark.parametrize("umask", [0o027, 0o002])
def test_atomic_writes_follow_the_umask(tmp_path, umask):
    old = os.umask(umask)
    try:
        paths = [write_text(tmp_path / "a.txt", "x"), write_json(tmp_path / "b.json", {}),
                 write_csv(tmp_path / "c.csv", ["a"], [[1]])]
    finally:
        os.umask(old)
    assert {stat.S_IMODE(p.stat().st_mode) for p in paths} == {0o666 & ~umask}
    assert np.all([not p.name.endswith(".tmp") for p in tmp_path.iterdir()])


def test_sigterm_reaches_python_after_gmsh_started():
    """gmsh replaces the SIGTERM handler at the C level; magtact puts Python's back, so that a
    run stopped after meshing still says so and releases its folder."""
    import gmsh

    from magtact.geometry._gmsh import initialize

    got = []
    old = signal.signal(signal.SIGTERM, lambda signum, frame: got.append(signum))
    try:
        initialize()
        gmsh.finalize()
        os.kill(os.getpid(), signal.SIGTERM)
        assert got == [signal.SIGTERM]
    finally:
        signal.signal(signal.SIGTERM, old)
