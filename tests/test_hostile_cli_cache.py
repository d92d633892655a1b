"""Hostile output folders, command options and DOE caches: one message, or a recomputation.

The DOE tests use the analytic stand-in solvers of ``conftest.py``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from conftest import fake_field, fake_path, run, tiny
from magtact.doe import CacheCorruptWarning, CacheError, JobCache
from magtact.doe._cache import Entry, _encode
from magtact.doe._jobs import plan


def magtact(*args: str) -> subprocess.CompletedProcess:
    """``magtact ARGS`` in this process (the console script's entry point), its output captured."""
    import contextlib
    import io

    from magtact.cli import main

    out, err = io.StringIO(), io.StringIO()
    argv, columns = sys.argv, os.environ.get("COLUMNS")
    sys.argv = ["magtact", *args]
    os.environ["COLUMNS"] = "1000"  # typer's error box must not break a long path mid-word
    code = 0
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            main()
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    finally:
        sys.argv = argv
        if columns is None:
            os.environ.pop("COLUMNS", None)
        else:
            os.environ["COLUMNS"] = columns
    return subprocess.CompletedProcess(args, code, out.getvalue(), err.getvalue())


def one_line_error(res: subprocess.CompletedProcess, *fragments: str) -> str:
    assert res.returncode == 2, (res.returncode, res.stderr)
    assert "Traceback" not in res.stderr + res.stdout, res.stderr
    for fragment in fragments:
        text = " ".join(res.stderr.replace("│", " ").split())  # typer boxes usage errors
        assert fragment in text, (fragment, res.stderr)
    return res.stderr


# ---- output folders and written files ---------------------------------------------------------
def test_out_an_existing_file_is_refused_before_any_work(tmp_path):
    target = tmp_path / "taken"
    target.write_text("keep me")
    for command in (["field", "--solver", "exact"], ["validate"], ["run"]):
        res = magtact(*command, "--out", str(target))
        one_line_error(res, "Invalid value for '--out'", "exists and is not a folder")
        assert target.read_text() == "keep me"
    res = magtact("field", "--solver", "exact", "--out", str(target / "sub"))
    one_line_error(res, f"{target} exists and is not a folder")


def test_out_a_folder_that_cannot_be_written(tmp_path, monkeypatch):
    from magtact.cli._app import out_dir

    def deny(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr("tempfile.NamedTemporaryFile", deny)
    with pytest.raises(ValueError, match=r"--out .*ro: cannot write there \(Permission denied"):
        out_dir(tmp_path / "ro")


def test_study_write_into_a_folder_is_one_line(tmp_path):
    res = magtact("study", "--write", str(tmp_path))
    one_line_error(res, f"{tmp_path}: Is a directory")


def test_other_design_options_are_checked(tmp_path):
    one_line_error(magtact("compare", "3,29.4", "3,1e300"),
                   "second design: G must be between 0.001 and 1e+06 kPa")
    one_line_error(magtact("simulate", "--H", "4", "--theta", "nan", "--out", str(tmp_path)),
                   "--theta must be in [0, π/2) rad, got nan")


# ---- the DOE cache -----------------------------------------------------------------------------
def forge(cache_dir: Path, study, edit) -> Path:
    """Replace the first path entry by an edited copy with a valid header and checksum."""
    cache = JobCache(cache_dir)
    _, jobs = plan(study, fake_path, fake_field)
    job = jobs[0]
    entry = cache.get(job.kind, job.key)
    arrays, meta = dict(entry.arrays), dict(entry.meta)
    edit(arrays, meta)
    path = cache.path(job.kind, job.key)
    path.write_bytes(_encode(Entry(arrays, meta), job.kind, job.key))
    return path


@pytest.mark.parametrize("edit, reason", [
    (lambda a, m: a.pop("F_z"), "array 'F_z' is missing"),
    (lambda a, m: a.update(F_r=a["F_r"] * np.nan), "array 'F_r' holds non-finite values"),
    (lambda a, m: a.update(u_z=a["u_z"][:2]), "array 'u_z' has shape (2,)"),
    (lambda a, m: a.update(t=np.array(["a"] * len(a["t"]))), "array 't' has shape"),
    (lambda a, m: m.pop("G"), "scalar 'G' is missing"),
    (lambda a, m: m.update(G=float("nan")), "scalar 'G' is not finite"),
    (lambda a, m: m.update(G=-1.0), "scalar 'G' is -1.0, expected a positive modulus"),
])
def test_forged_cache_entry_is_recomputed(tmp_path, edit, reason):
    study = tiny()
    clean = run(study, tmp_path / "cache")
    path = forge(tmp_path / "cache", study, edit)
    with pytest.warns(CacheCorruptWarning, match=r"is corrupt \(" + _escape(reason)):
        again = run(study, tmp_path / "cache")
    assert again.attrs["run_paths_computed"] == 1 and again.attrs["run_cache_corrupt"] == 1
    for name in ("F_r", "F_z", "u_r", "u_z", "B_r", "B_z"):
        np.testing.assert_array_equal(again[name].values, clean[name].values)
    assert JobCache(tmp_path / "cache").get("path", path.stem) is not None


def _escape(text: str) -> str:
    import re

    return re.escape(text)


def test_folder_in_place_of_an_entry_is_a_cache_error(tmp_path):
    study = tiny()
    run(study, tmp_path / "cache")
    cache = JobCache(tmp_path / "cache")
    _, jobs = plan(study, fake_path, fake_field)
    path = cache.path("path", jobs[0].key)
    path.unlink()
    path.mkdir()
    with pytest.raises(CacheError, match=r"cache entry .*\.mtc is a folder .*remove it or give "
                                         "another cache folder"):
        run(study, tmp_path / "cache")
    from magtact.cli import USER_ERRORS

    assert issubclass(CacheError, USER_ERRORS)  # the command line prints it in one line


@pytest.mark.parametrize("second", [
    pytest.param({"n_theta": 3, "n_H": 4}, id="same-study"),
    pytest.param({"n_theta": 2, "n_H": 5}, id="other-study", marks=pytest.mark.long)])
def test_two_processes_computing_the_same_cache(tmp_path, second):
    """Both processes compute (they start together and the stand-in is slowed down so that
    they overlap), on the same study or on two studies; each ends with its clean run's data and
    every entry verifies."""
    cache = tmp_path / "cache"
    script = textwrap.dedent(f"""
        import json, sys, time
        from pathlib import Path
        sys.path.insert(0, {str(Path(__file__).parent)!r})
        import conftest
        from magtact.doe import run_doe, save_dataset

        def slow_path(*args, **kwargs):
            time.sleep(0.15)
            return conftest.fake_path(*args, **kwargs)

        Path(sys.argv[1] + ".ready").touch()  # start together, once both have imported
        while len(list(Path({str(tmp_path)!r}).glob("*.ready"))) < 2:
            time.sleep(0.01)
        ds = run_doe(conftest.tiny(**json.loads(sys.argv[2])), cache={str(cache)!r}, workers=0,
                     path_solver=slow_path, field_solver=conftest.fake_field)
        save_dataset(ds, sys.argv[1])
        print(ds.attrs["run_paths_computed"], ds.attrs["run_cache_corrupt"])
        """)
    levels = [{"n_theta": 3, "n_H": 4}, second]
    procs = [subprocess.Popen([sys.executable, "-c", script, str(tmp_path / f"{k}.nc"),
                               json.dumps(lv)],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for k, lv in enumerate(levels)]
    outs = [p.communicate(timeout=300) for p in procs]
    assert all(p.returncode == 0 for p in procs), outs
    computed = [int(out.split()[0]) for out, _ in outs]
    assert all(out.split()[1] == "0" for out, _ in outs), outs
    assert min(computed) > 0, computed  # both computed paths
    if second == levels[0]:
        assert sum(computed) >= 12, computed

    for k, lv in enumerate(levels):
        clean = run(tiny(**lv))
        ds = xr.load_dataset(tmp_path / f"{k}.nc")
        for name in ("F_r", "F_z", "u_r", "u_z", "B_r", "B_z"):
            np.testing.assert_array_equal(ds[name].values, clean[name].values)
    store = JobCache(cache)
    with warnings.catch_warnings():
        warnings.simplefilter("error", CacheCorruptWarning)
        keys = store.keys("path")
        assert len(keys) >= 12 and all(store.get("path", k) is not None for k in keys)
    assert not list(cache.rglob("*.tmp"))


def test_hostile_input_errors_are_user_errors(tmp_path):
    """Every refusal of hostile input is a MagtactError (the command line's one-line errors)."""
    from magtact._errors import MagtactError
    from magtact.metamodel import load_model
    from magtact.study import StudyError, checked_si
    from magtact.validation import DataError

    for cls in (StudyError, DataError, CacheError):
        assert issubclass(cls, MagtactError)
    with pytest.raises(MagtactError, match="--H must be between"):
        checked_si(float("nan"), "mm", "--H")
    (tmp_path / "f_r.json").write_text('{"format": "magtact-metamodel/1", "name": "f_r", '
                                       '"units": "N/Pa", "expression": "9**9**9*t", '
                                       '"expression_pq": "p"}')
    with pytest.raises(MagtactError, match="f_r.json: model expression: exponent '387420489'"):
        load_model(tmp_path / "f_r.json")


def test_error_paths_on_a_mesh_without_a_finer_one_is_refused_before_any_work(tmp_path):
    study = tmp_path / "s.toml"
    study.write_text('base = "magone"\n[mechanics]\nmesh = "fine"\n')
    res = magtact("doe", str(study), "--out", str(tmp_path / "o"), "--error-paths", "3",
                  "--no-cache", "-j", "0")
    one_line_error(res, "mechanics.mesh = 'fine' has no finer mesh", "'default'")


def test_study_write_keeps_an_existing_file(tmp_path):
    mine = tmp_path / "study.toml"
    mine.write_text("# my notes\n[body]\nH_mm = 4\n")
    one_line_error(magtact("study", "--write", str(mine)),
                   f"--write {mine}: the file exists and magtact does not replace it")
    assert mine.read_text() == "# my notes\n[body]\nH_mm = 4\n"
    new = tmp_path / "full.toml"
    assert magtact("study", "--write", str(new)).returncode == 0
    assert magtact("study", "--write", str(new)).returncode == 0  # the same text again
    assert new.read_text().strip() in magtact("study").stdout
