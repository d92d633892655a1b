"""NSGA-II and the exact reduction must agree: a disagreement is loud and names both designs."""

from __future__ import annotations

from dataclasses import replace

import pytest

import magtact.optimise._run as run_module
from conftest import synthetic_models
from magtact._errors import MagtactError
from magtact.optimise import optimise
from magtact.sensitivity import Responses
from magtact.study import load_study


def test_disagreement_between_nsga2_and_exact_reduction_is_loud(monkeypatch):
    """A gap above 5 % is a warning naming both chosen designs; a gap that is not a number
    (something broke) is an error."""
    s = load_study(None)
    s = replace(s, optimise=replace(s.optimise, population=24, ga_generations=3,
                                    nsga2_generations=10, grid_n=4, sweep_n=101))
    gaps = iter([0.3, float("nan")])
    monkeypatch.setattr(run_module, "front_gap", lambda pareto, reduction: next(gaps))
    pattern = (r"NSGA-II's Pareto set lies {} \(relative\) from the exact reduction's front, "
               r"more than 0.05: its choice H = .* mm, G = .* kPa disagrees with the exact "
               r"reduction's H = .* mm, G = .* kPa")
    with pytest.warns(run_module.FrontGapWarning, match=pattern.format("0.3")):
        optimise(Responses(synthetic_models()), s)
    with pytest.raises(MagtactError, match=pattern.format("nan")):
        optimise(Responses(synthetic_models()), s)


def test_pipeline_says_the_disagreement_in_the_report(monkeypatch, tmp_path):
    import warnings

    from magtact import pipeline

    class FakeResult:
        pass

    def fake_solve(models, study, constraints=None, models_source="", dataset=None):
        warnings.warn("NSGA-II's Pareto set lies 0.3 (relative) from the exact reduction's "
                      "front", run_module.FrontGapWarning, stacklevel=2)
        return FakeResult()

    monkeypatch.setattr(pipeline, "solve", fake_solve)
    monkeypatch.setattr(pipeline, "error_budgets", lambda result: None)
    monkeypatch.setattr(pipeline, "write_results_into", lambda result, folder, **kw: [])
    ctx = pipeline._Context(study=load_study(None), folder=tmp_path, recompute=False,
                            refit=False, data=None, cache=None, workers=None,
                            log=lambda m: None, models=object())
    rec = pipeline.StageRecord("optimise", "Optimisation")
    assert pipeline._stage_optimise(ctx, rec) == "design chosen"
    assert rec.notes == ["WARNING: NSGA-II's Pareto set lies 0.3 (relative) from the exact "
                         "reduction's front"]


def test_models_not_finite_on_the_domain_are_refused_before_optimising():
    """A model NaN on part of the domain would put NaN into the tables (reduction.csv)."""
    import sympy as sp

    from magtact.metamodel import Metamodel, ModelSet
    from magtact.metamodel._symbols import SYMBOLS

    ms = synthetic_models()
    bad = Metamodel.from_expr("f_z", ms.f_z.expr * sp.sqrt(SYMBOLS["t"] - sp.Rational(1, 3)),
                              "N/Pa")
    models = ModelSet(B_r=ms.B_r, B_z=ms.B_z, f_r=ms.f_r, f_z=bad)
    n_bad = 14 * 11 * 11  # the 14 levels t = 0, 0.025, ..., 0.325 below 1/3, every (θ, H)
    with pytest.raises(MagtactError, match=r"model f_z is not finite \(nan\) at t = 0, theta = 0 "
                                           rf"rad, H = 3 mm \({n_bad} of 4961 points"):
        optimise(Responses(models), load_study(None))
