"""A specification no design meets is an answer: each requirement with the best figure a design
of the study's ranges reaches, the requirement that binds, and the smallest change of one
requirement that makes it feasible, checked here by solving the exact reduction again with that
change."""

from __future__ import annotations

import math

import pytest

import magtact
from conftest import TINY_STUDY as TINY
from magtact.designer import InfeasibleSpecification


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    path = tmp_path_factory.mktemp("study") / "tiny.toml"
    path.write_text(TINY, encoding="utf-8")
    study = magtact.load(path)
    models, source, dataset = magtact.models_for(study)
    with pytest.raises(InfeasibleSpecification) as caught:
        magtact.solve(models, study, models_source=source, dataset=dataset)
    return path, study, models, source, dataset, caught.value


def test_the_answer_names_what_binds_and_the_best_figures(tiny):
    _, study, *_, exc = tiny
    answer = exc.answer
    assert not answer.met and answer.binding == "shear"
    shear = next(r for r in answer.requirements if r.key == "shear")
    normal = next(r for r in answer.requirements if r.key == "normal")
    assert shear.met is False and shear.margin < 0
    # the best shear reached within the normal range: at most the stable region's best, that
    # of the optimiser's message (its best reachable F_r,min)
    best = float(str(exc).split("F_r,min = ")[1].split(" N")[0])
    assert 0 < shear.margin + 0.5 <= -best * (1 + 2e-3)
    assert normal.met is False and math.isnan(normal.margin)  # not reached with 0.5 N shear
    text = str(answer)
    assert "binds" in text and "requirements.F_r_N = " in text
    assert "no design meets the requirements" in answer._repr_html_()


def test_the_relaxation_makes_the_specification_feasible(tiny):
    path, study, models, _, _, exc = tiny
    relax = exc.answer.relaxation
    assert relax.key == "shear" and relax.relaxed < relax.required
    assert relax.setting == "requirements.F_r_N"

    def study_with(F_r: float):  # the study file with the one change a user makes
        changed = path.with_name(f"relaxed_{F_r:.6g}.toml")
        changed.write_text(TINY.replace("F_r_N = 0.5", f"F_r_N = {F_r!r}"), encoding="utf-8")
        return magtact.load(changed)

    from magtact.chip import exact_field_models
    from magtact.designer import answer
    from magtact.optimise import exact_sensor_reduction, force_constraints, sensor_space, sweep

    def reduced(study):  # the sensor problem's exact reduction (NSGA-II only goes below it)
        space = sensor_space(models, study, table, force_constraints(models, study))
        return space, exact_sensor_reduction(models, study, space)[0]

    # solved again with the change, the chosen sensor meets every requirement as its verdict
    # reads them (the shear root-found along the paths within the normal range)
    relaxed = study_with(relax.relaxed)
    table = sweep(models, relaxed)  # the geometry is the same for every F_r
    _, red = reduced(relaxed)
    sensor = red.sensor(relaxed)
    verdict = answer(exact_field_models(models, relaxed, sensor.standoff, sensor.M_z), relaxed,
                     sensor).verdict
    assert verdict.met, str(verdict)
    assert verdict["shear"].margin >= 0
    # and it is the smallest change (to 3 significant figures): 1 % beyond it no sensor's
    # loads within 3 N normal include the shear
    space, red = reduced(study_with(relax.relaxed * 1.01))
    assert space.F_r == pytest.approx(relax.relaxed * 1.01)
    assert red.F_r_within < space.F_r
