"""NSGA-II and the exact reduction must agree: a disagreement is an error naming both designs."""

from __future__ import annotations

from dataclasses import replace

import pytest

import magtact.optimise._run as run_module
from magtact.optimise import optimise
from magtact.sensitivity import Responses
from magtact.study import load_study
from test_optimise import synthetic_models


def test_disagreement_between_nsga2_and_exact_reduction_is_an_error(monkeypatch):
    s = load_study(None)
    s = replace(s, optimise=replace(s.optimise, population=24, ga_generations=3,
                                    nsga2_generations=10, grid_n=4, sweep_n=101))
    monkeypatch.setattr(run_module, "front_gap", lambda pareto, reduction: 0.3)
    with pytest.raises(ValueError, match=r"NSGA-II's Pareto set lies 0.3 \(relative\) from "
                                         r"the exact reduction's front, more than 0.05: its "
                                         r"choice H = .* mm, G = .* kPa disagrees with the exact "
                                         r"reduction's H = .* mm, G = .* kPa"):
        optimise(Responses(synthetic_models()), s)
