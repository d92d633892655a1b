"""``magtact.Result`` is a record: the error budget, the calibration and the writing are
functions over it (``magtact.error_budget``, ``calibrate``, ``write_results``,
``write_results_into``), and its methods of the same work give the same answers and files."""

from __future__ import annotations

import json

import numpy as np
import pytest

import magtact

#: A small calibration (the function against the method, not the firmware's accuracy).
SMALL_CALIBRATION = {"degrees": (4,), "table_sizes": (16,)}


@pytest.fixture(scope="module")
def result(magone_design):
    return magone_design


def _doc(obj) -> str:
    return json.dumps(obj.to_json(), sort_keys=True)


def test_the_functions_are_public_and_shadow_no_sub_package():
    import magtact.budget
    import magtact.calibration

    for name in ("error_budget", "calibrate", "write_results", "write_results_into"):
        assert name in magtact.__all__ and callable(getattr(magtact, name)), name
        assert getattr(magtact, name).__doc__.count("Parameters\n    ----------") == 1, name
    # the sub-packages keep their names: the budget's function is not called ``budget``
    assert magtact.budget.__name__ == "magtact.budget"
    assert magtact.calibration.__name__ == "magtact.calibration"
    for method, function in (("budget", "error_budget"), ("calibrate", "calibrate"),
                             ("write", "write_results"), ("write_into", "write_results_into")):
        assert f"magtact.{function}(self" in getattr(magtact.Result, method).__doc__, method


def test_the_budget_function_and_method_agree(result):
    kwargs = {"noise": (1e-6, 1.5e-6)}
    by_function = magtact.error_budget(result, result.original, **kwargs)
    by_method = result.budget(result.original, **kwargs)
    assert by_function.label == by_method.label == "original"
    assert _doc(by_function) == _doc(by_method)
    # the default design is the chosen one, and the cached budgets are the function's
    chosen = magtact.error_budget(result, dataset=result.dataset)
    assert chosen.label == "chosen"
    assert _doc(chosen) == _doc(result.budgets[0])


def test_the_calibrate_function_and_method_agree(result):
    by_function = magtact.calibrate(result, **SMALL_CALIBRATION)
    by_method = result.calibrate(**SMALL_CALIBRATION)
    assert _doc(by_function) == _doc(by_method)
    assert by_function.map.H == result.chosen.H and by_function.map.G == result.chosen.G
    for key in ("err_r", "err_z"):
        np.testing.assert_array_equal(by_function.grid[key], by_method.grid[key])
    assert by_function.firmware.chosen.to_json() == by_method.firmware.chosen.to_json()


def test_the_calibrate_function_refuses_a_geometry_range(result):
    from dataclasses import replace

    study = result.study
    wide = replace(study, design=replace(study.design, R=(6e-3, 8e-3)))
    assert wide.geometric_variables == {"R": (6e-3, 8e-3)}
    with pytest.raises(magtact.MagtactError, match="one geometry"):
        magtact.calibrate(replace(result, study=wide))


def _files(files, root) -> dict[str, bytes]:
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in files}


def test_write_function_and_method_write_the_same_files(result, tmp_path):
    a, b = tmp_path / "function", tmp_path / "method"
    by_function = _files(magtact.write_results(result, a, figures=False), a)
    by_method = _files(result.write(b, figures=False), b)
    assert by_function.keys() == by_method.keys()
    assert {"card.json", "budget.json", "design.json", "chosen.json"} <= by_function.keys()
    assert by_function == by_method
    # into a folder already held: the same files
    c, d = tmp_path / "into_function", tmp_path / "into_method"
    c.mkdir()
    d.mkdir()
    into_function = _files(magtact.write_results_into(result, c, figures=False,
                                                      budget=False), c)
    into_method = _files(result.write_into(d, figures=False, budget=False), d)
    assert into_function == into_method and "card.json" in into_function
    assert "budget.json" not in into_function
