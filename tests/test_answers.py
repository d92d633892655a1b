"""Answers kept by content (magtact._answers): a study is solved once, read back equal, and
solved again whenever anything it depends on changes or the entry is damaged."""

from __future__ import annotations

import warnings
from dataclasses import replace

import pytest

import magtact
from conftest import known_set, synthetic_models
from magtact import _answers
from magtact.optimise import force_constraints

SMALL = {"problem": "publication", "population": 16, "nsga2_generations": 4,
         "ga_generations": 2, "grid_n": 2, "sweep_n": 51, "sweep_coarse": 11}


@pytest.fixture
def own_folder(tmp_path, monkeypatch):
    monkeypatch.setenv("MAGTACT_CACHE_DIR", str(tmp_path))
    return tmp_path / "answers"


def _study(**optimise):
    return magtact.load("magone", optimise=SMALL | optimise)


def test_the_key_follows_the_models_the_study_and_the_constraints():
    m, s = synthetic_models(), _study()
    c = force_constraints(m, s)
    k = _answers.key(m, s, c)
    assert k == _answers.key(synthetic_models(), _study(), force_constraints(m, s))
    assert _answers.key(m, _study(seed=1), c) != k
    assert _answers.key(m, s, replace(c, F_z_c=c.F_z_c * (1 + 1e-15))) != k
    assert _answers.key(known_set(), s, c) != k
    # a model that is not a closed-form expression is never keyed
    assert _answers.key(replace(m, B_r=object()), s, c) is None


@pytest.mark.filterwarnings("ignore:NSGA-II's Pareto set lies")  # a short NSGA-II, on purpose
def test_a_solve_is_kept_read_back_equal_and_its_warnings_given_again(own_folder):
    m, s = synthetic_models(), _study()
    first = magtact.solve(m, s)
    assert len(list(own_folder.glob("*.answer"))) == 1
    calls = []

    def compute():
        calls.append(1)
        return {}

    k = _answers.key(m, s, force_constraints(m, s))
    again = _answers.kept(k, compute)
    assert calls == []  # read, not solved
    assert again["chosen"] == first.chosen and again["variables"] == first.variables
    second = magtact.solve(m, s, models_source="elsewhere")
    assert second.models is m and second.models_source == "elsewhere"
    assert second.chosen_design == first.chosen_design

    def warns():
        warnings.warn("kept with the answer", UserWarning, stacklevel=1)
        return {"x": 1}

    with pytest.warns(UserWarning, match="kept with the answer"):
        _answers.kept("a" * 64, warns)
    with pytest.warns(UserWarning, match="kept with the answer"):
        assert _answers.kept("a" * 64, lambda: pytest.fail("solved again")) == {"x": 1}


@pytest.mark.parametrize("damage", [
    lambda b: b[:-10],                               # truncated
    lambda b: b.replace(b"MAGTACT-ANSWER", b"OTHER-THING", 1),
    lambda b: b[:-1] + bytes([b[-1] ^ 1]),           # one bit of the payload
    lambda b: b"",
])
def test_a_damaged_entry_is_solved_again_and_replaced(own_folder, damage):
    k = "b" * 64
    _answers.kept(k, lambda: {"value": 1})
    path = own_folder / f"{k}.answer"
    path.write_bytes(damage(path.read_bytes()))
    assert _answers.read(k) is None
    assert _answers.kept(k, lambda: {"value": 2}) == {"value": 2}
    assert _answers.read(k)["fields"] == {"value": 2}


def test_off_keeps_nothing(tmp_path, monkeypatch):
    monkeypatch.setenv("MAGTACT_CACHE_DIR", "off")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    calls = []
    for _ in range(2):
        _answers.kept("c" * 64, lambda: calls.append(1) or {})
    assert calls == [1, 1] and not any(tmp_path.iterdir())


def test_a_folder_that_cannot_be_written_only_costs_the_keeping(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("MAGTACT_CACHE_DIR", str(blocker))
    assert _answers.kept("d" * 64, lambda: {"value": 3}) == {"value": 3}
