"""One set of rules for a study and for a design evaluated in Python, and `magtact study`
refusing what `magtact run` refuses: the data's coverage, implausible requirements; with the
small messages around them."""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import pytest

from magtact import Result
from magtact.calibration import read_presses
from magtact.parts import grade
from magtact.study import MU0, StudyError, check_study, load_study, study_from_dict
from magtact.study._rules import MAX_LOAD_FACTOR, check_parts, check_requirements
from magtact.validation import DataError


def evaluated(study, **kw):
    """``Result.evaluate`` up to its first use of the models: the rules it applies to its
    arguments (a stand-in result holding only the study)."""
    return Result.evaluate(SimpleNamespace(study=study, dataset=None), **kw)


@pytest.mark.parametrize("name, M_z", [("N42", 9.0e5), ("N52", 1.05e6), ("N38", 1.3e6)])
def test_grade_with_another_magnetisation_is_refused_alike_in_the_file_and_in_python(name, M_z):
    with pytest.raises(StudyError) as in_file:
        study_from_dict({"magnet": {"grade": name, "M_z_A_per_m": M_z}})
    with pytest.raises(StudyError) as in_python:
        evaluated(load_study(None), H_mm=4.2, G_kPa=27, grade=name, M_z_A_per_m=M_z)
    # the same rule and words; each names the keys as its caller writes them
    assert in_python.value.reason == in_file.value.reason.replace("magnet.grade", "grade")
    assert in_file.value.key == "magnet.M_z_A_per_m" and in_python.value.key == "M_z_A_per_m"
    assert f"conflicts with grade = {name!r}" in str(in_python.value)
    assert "give one of the two" in str(in_python.value)
    # the study's own grade and an M_z given alone: the same conflict
    graded = study_from_dict({"magnet": {"grade": name}})
    with pytest.raises(StudyError, match="conflicts with grade"):
        evaluated(graded, H_mm=4.2, G_kPa=27, M_z_A_per_m=M_z)


def test_grade_with_its_own_magnetisation_passes_the_rule():
    M_z = grade("N45").M_z(MU0)[0]
    assert check_parts("N45", "custom", {"M_z": M_z * (1 + 1e-12)},
                       {"M_z": "M_z_A_per_m", "grade": "grade"})["M_z"] == M_z
    with pytest.raises(StudyError, match=r"\[magnet.R_m_mm\] 2 conflicts with magnet.size"):
        study_from_dict({"magnet": {"size": "5x2", "R_m_mm": 2.0}})


@pytest.mark.parametrize("key, value, hint", [
    ("F_z_N", 600.0, True), ("F_r_N", 120.0, True), ("F_z_N", 950.0, True)])
def test_implausible_requirements_are_refused_with_the_likely_unit(key, value, hint):
    s = study_from_dict({"requirements": {key: value}})
    with pytest.raises(StudyError, match=rf"\[requirements.{key}\] = {value:g} N is more than"
                       ) as exc:
        check_study(s)
    assert ("did you give mN?" in str(exc.value)) == hint


def test_requirements_a_body_can_carry_pass():
    s = load_study(None)
    limit = MAX_LOAD_FACTOR * s.design.G[1] * 3.141592653589793 * s.body.R ** 2
    check_requirements(replace(s, requirements=replace(s.requirements, F_z=0.99 * limit)))
    with pytest.raises(StudyError, match="F_z_N"):
        check_requirements(replace(s, requirements=replace(s.requirements, F_z=1.01 * limit)))
    for preset in ("magone", "magone-printed", "magone-publication"):
        check_study(load_study(preset))


def test_study_command_refuses_what_run_refuses_and_shows_the_digits(tmp_path, refused):
    path = tmp_path / "s.toml"
    path.write_text("[magnet]\nH_m_mm = 2.0000003\n", encoding="utf-8")
    refused(["study", str(path)], "magtact run would refuse this study",
            "H_m_mm = 2.0000003 (the data set's: 2)", "--recompute")
    path.write_text("[requirements]\nF_z_N = 2500\n", encoding="utf-8")
    refused(["study", str(path), "--recompute"], "[requirements.F_z_N]", "did you give mN?")


def test_study_command_with_recompute_accepts_a_study_for_its_own_doe(tmp_path, capsys):
    import sys

    from magtact.cli import main

    path = tmp_path / "s.toml"
    path.write_text("[magnet]\nH_m_mm = 2.0000003\n", encoding="utf-8")
    saved = sys.argv
    sys.argv = ["magtact", "study", str(path), "--recompute"]
    try:
        main()
    except SystemExit as exc:
        assert exc.code in (0, None), capsys.readouterr()
    finally:
        sys.argv = saved
    assert "H_m_mm = 2.0000003" in capsys.readouterr().out


def test_unknown_key_message_separates_the_list():
    with pytest.raises(StudyError) as exc:
        study_from_dict({"magnet": {"zzz_mm": 1.0}})
    assert "unknown key (expected one of: " in str(exc.value)
    with pytest.raises(StudyError) as exc:
        study_from_dict({"magnet": {"R_mm": 1.0}})
    assert "did you mean" in str(exc.value) and "? (expected one of: " in str(exc.value)


@pytest.mark.parametrize("key", ["sigma_B_uT", "SIGMA_F_mN"])
def test_a_metadata_key_given_twice_is_refused(tmp_path, key):
    path = tmp_path / "p.csv"
    path.write_text(f"# {key} = 2\n# note = x\n# {key.lower()} = 3\n"
                    "B_x_T,B_y_T,B_z_T,F_x_N,F_y_N,F_z_N\n0,0,0.03,0,0,0\n", encoding="utf-8")
    with pytest.raises(DataError, match=rf"line 3: {key.lower()} is given twice \(also on line "
                                        r"1\); keep one"):
        read_presses(path)
