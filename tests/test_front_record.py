"""``magtact.Result`` is a plain record: what is made of it are functions that take it first
(``magtact.error_budget``, ``error_budgets``, ``calibrate``, ``card``, ``figures``,
``write_results``, ``write_results_into``); the error budgets of a results folder are computed
once, for its card and its ``budget.json``."""

from __future__ import annotations

import json

import pytest

import magtact

#: A small calibration (the function's defaults, not the firmware's accuracy).
SMALL_CALIBRATION = {"degrees": (4,), "table_sizes": (16,)}
FUNCTIONS = ("error_budget", "error_budgets", "calibrate", "card", "figures", "write_results",
             "write_results_into")


@pytest.fixture(scope="module")
def result(magone_design):
    return magone_design


def _doc(obj) -> str:
    return json.dumps(obj.to_json(), sort_keys=True)


def test_the_functions_are_public_and_shadow_no_sub_package():
    import magtact.budget
    import magtact.calibration

    for name in FUNCTIONS:
        assert name in magtact.__all__ and callable(getattr(magtact, name)), name
        assert getattr(magtact, name).__doc__.count("Parameters\n    ----------") == 1, name
    # the sub-packages keep their names: the budget's function is not called ``budget``
    assert magtact.budget.__name__ == "magtact.budget"
    assert magtact.calibration.__name__ == "magtact.calibration"
    # one way to each: the record has no member doing the functions' work
    members = {"budget", "budgets", "calibrate", "card", "figures", "write", "write_into"}
    assert not members & set(dir(magtact.Result))


def test_the_budgets_are_the_budget_function_of_both_designs(result, magone_budgets):
    chosen, original = magone_budgets
    assert (chosen.label, original.label) == ("chosen", "original")
    # the default design is the chosen one
    assert _doc(magtact.error_budget(result, dataset=result.dataset)) == _doc(chosen)
    given = magtact.error_budget(result, result.original, noise=(1e-6, 1.5e-6))
    assert given.label == "original" and given.noise_source.startswith("given as")


def test_the_calibrate_function_calibrates_the_chosen_design(result):
    cal = magtact.calibrate(result, **SMALL_CALIBRATION)
    assert cal.map.H == result.chosen.H and cal.map.G == result.chosen.G


def test_the_calibrate_function_refuses_a_geometry_range(result):
    from dataclasses import replace

    study = result.study
    wide = replace(study, design=replace(study.design, R=(6e-3, 8e-3)))
    assert wide.geometric_variables == {"R": (6e-3, 8e-3)}
    with pytest.raises(magtact.MagtactError, match="one geometry"):
        magtact.calibrate(replace(result, study=wide))


def _files(files, root) -> dict[str, bytes]:
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in files}


def test_a_results_folder_computes_its_budgets_once(result, magone_budgets, tmp_path,
                                                  monkeypatch):
    """Without ``budgets=``, writing a folder computes the two budgets once for the card and
    ``budget.json``, and writes what a caller's budgets give; the card is ``magtact.card``."""
    import magtact._outputs as outputs

    calls = []
    real = outputs.error_budget
    monkeypatch.setattr(outputs, "error_budget", lambda *a, **k: calls.append(a) or real(*a, **k))
    a, b = tmp_path / "computed", tmp_path / "given"
    computed = _files(magtact.write_results(result, a, figures=False), a)
    assert len(calls) == 2
    given = _files(magtact.write_results(result, b, figures=False, budgets=magone_budgets), b)
    assert len(calls) == 2
    assert {"card.json", "budget.json", "design.json", "chosen.json"} <= computed.keys()
    assert computed == given
    card = json.loads(computed["card.json"])
    assert card["rows"] == magtact.card(result, magone_budgets)["rows"]
    # into a folder already held: the same files, budget.json only where asked
    c = tmp_path / "into"
    c.mkdir()
    into = _files(magtact.write_results_into(result, c, figures=False, budget=False,
                                             budgets=magone_budgets), c)
    assert len(calls) == 2
    assert "budget.json" not in into and into == {k: v for k, v in given.items()
                                                  if k in into}
