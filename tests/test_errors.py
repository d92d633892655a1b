"""User errors reach the user as one line; anything else keeps its traceback."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

import magtact
from magtact._errors import MissingFileError
from magtact.doe import load_dataset
from magtact.optimise import InfeasibleError
from magtact.pipeline import run_study
from magtact.study import StudyError, magone
from magtact.validation import DataError


def _cli(code: str, *args: str, cwd) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True,
                          cwd=cwd, timeout=600)


def test_user_errors_are_magtact_errors_and_value_errors():
    for cls in (StudyError, InfeasibleError, DataError, MissingFileError):
        assert issubclass(cls, magtact.MagtactError)
    assert issubclass(magtact.MagtactError, ValueError)
    assert issubclass(MissingFileError, FileNotFoundError)
    assert "MagtactError" in magtact.__all__


def test_bad_study_is_one_line_and_exit_status_2(tmp_path):
    (tmp_path / "bad.toml").write_text("[magnet]\nR_m_mm = 7.0\n")
    r = _cli("from magtact.cli import main; main()", "study", "bad.toml", cwd=tmp_path)
    assert r.returncode == 2
    assert r.stderr.strip().splitlines() == [
        "error: bad.toml: [magnet.R_m_mm] the magnet (7 mm radius) must be narrower than the "
        "body (body.R_mm = 6)"]


def test_internal_error_in_the_optimiser_shows_its_traceback(tmp_path):
    """A LinAlgError raised inside the optimiser is a fault, not a user error."""
    code = textwrap.dedent("""
        import os
        os.environ["MAGTACT_CACHE_DIR"] = "off"  # solve, not read a kept answer
        import numpy as np
        import magtact.optimise._design as design

        def broken(*args, **kwargs):
            raise np.linalg.LinAlgError("Singular matrix")

        design._extrema = broken  # every sweep of the heights' extrema
        from magtact.cli import main
        main()
    """)
    r = _cli(code, "optimise", "--out", "out", cwd=tmp_path)
    assert r.returncode == 1
    assert "Traceback (most recent call last)" in r.stderr
    assert r.stderr.strip().splitlines()[-1] == "numpy.linalg.LinAlgError: Singular matrix"
    assert "error:" not in r.stderr


def test_a_plain_value_error_is_not_taken_for_a_user_error(tmp_path):
    code = textwrap.dedent("""
        import magtact.cli._study as study_command

        def broken(source):
            raise ValueError("an internal inconsistency")

        study_command.get_study = broken
        from magtact.cli import main
        main()
    """)
    r = _cli(code, "study", cwd=tmp_path)
    assert r.returncode == 1
    assert "Traceback (most recent call last)" in r.stderr
    assert r.stderr.strip().splitlines()[-1] == "ValueError: an internal inconsistency"


def test_missing_data_file_is_a_user_error(tmp_path):
    with pytest.raises(MissingFileError, match="DOE data set not found: nowhere.nc"):
        load_dataset("nowhere.nc")


def test_missing_evidence_folder_is_refused_before_any_stage(tmp_path):
    out = tmp_path / "results"
    with pytest.raises(MissingFileError, match="no such folder of benchmark results"):
        run_study(magone(), out, evidence=tmp_path / "no-bench", log=lambda m: None)
    assert not out.exists()
