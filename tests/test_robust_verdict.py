"""The robust verdict: the tolerance box with its cited sources, the yield by quasi-Monte Carlo
against exact cases (only the remanence varies: the yield is the probability that it lies
below the threshold where the chip saturates at the required force), the worst corner against
every sampled unit, and the built units of the default design against an independent field."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

import magtact
from magtact.parts import grade
from magtact.study import StudyError
from magtact.tolerance import (
    INPUTS,
    Tolerance,
    ToleranceBox,
    corners,
    design_context,
    robust_verdict,
    tolerance_box,
    unit_figures,
)


@pytest.fixture(scope="module")
def chosen(magone_design):
    a = magone_design.chosen
    return magone_design.of(a)[0], a


def only_remanence(box: ToleranceBox) -> ToleranceBox:
    """``box`` with every input but the remanence fixed at its nominal value."""
    fixed = tuple(t if t.name == "B_r" else replace(t, low=t.nominal, high=t.nominal)
                  for t in box.inputs)
    return replace(box, inputs=fixed)


def at_threshold(models, a, box, share=0.4):
    """The answer with the required normal force where the unit whose remanence factor is k0
    (``share`` of the way from nominal to the box's high end) saturates; the saturation
    figure falls as the remanence grows, so the units that read it are those below k0."""
    ctx = design_context(models, a, box)
    b = box.inputs[box.index("B_r")]
    k0 = b.nominal + share * (b.high - b.nominal)
    x = box.nominal.copy()
    x[box.index("B_r")] = k0
    F_z = float(unit_figures(ctx, box, x[None, :])["F_sat"][0])
    study = replace(a.study, requirements=replace(a.study.requirements, F_z=F_z))
    return replace(a, study=study), k0


def test_the_yield_of_a_uniform_remanence_is_its_probability_below_the_threshold(chosen):
    models, a = chosen
    box = only_remanence(tolerance_box(a.study, a.sensor.grade))
    b = box.inputs[0]
    g = grade(a.parts.grade)  # the grade's catalogue range, e.g. N40: 1.25-1.28 T
    assert b.distribution == "uniform" and (b.low, b.high) == pytest.approx(
        (g.B_r_min / g.B_r, g.B_r_max / g.B_r))
    answer, k = at_threshold(models, a, box)
    exact = (k - b.low) / (b.high - b.low)  # reads where B_r lies below the threshold
    r = robust_verdict(models, answer, box)["normal"]
    lo, hi = r.interval
    assert lo <= exact <= hi and hi - lo < 0.05, (exact, r.yield_fraction, r.interval)
    assert r.limited_by == "B_r" and not r.met  # the strongest magnet saturates below F_z


def test_the_yield_of_a_normal_remanence_is_its_probability_below_the_threshold(chosen):
    models, a = chosen
    custom = replace(a, sensor=replace(a.sensor, grade="custom"))  # a magnet of no grade
    tol = a.study.tolerances
    box = only_remanence(tolerance_box(a.study, "custom"))
    b = box.inputs[0]
    assert b.distribution == "normal" and b.sigma == tol.remanence
    answer, k = at_threshold(models, custom, box)
    c = tol.coverage  # truncated at ± c σ
    z = (k - 1.0) / b.sigma
    exact = (stats.norm.cdf(z) - stats.norm.cdf(-c)) / (stats.norm.cdf(c) - stats.norm.cdf(-c))
    r = robust_verdict(models, answer, box)["normal"]
    assert r.interval[0] <= exact <= r.interval[1], (exact, r.yield_fraction, r.interval)


def test_the_nominal_unit_is_the_nominal_verdict(chosen):
    models, a = chosen
    box = tolerance_box(a.study, a.sensor.grade)
    fig = unit_figures(design_context(models, a, box), box, box.nominal[None, :])
    v = a.verdict
    assert fig["F_sat"][0] == pytest.approx(v.F_saturation, rel=1e-3)
    assert fig["shear_read"][0] == pytest.approx(v.shear_read, rel=1e-3)
    assert fig["F_z_max"][0] == pytest.approx(a.design.F_z_max, rel=1e-9)
    assert fig["shear_stable"][0] == pytest.approx(-a.design.F_r_min, rel=1e-9)


def test_no_sampled_unit_is_worse_than_the_worst_corner(chosen):
    models, a = chosen
    r = robust_verdict(models, a)
    assert r.corner_bounds_samples
    assert r.samples == a.study.tolerances.robust_samples
    for q in r.requirements:  # the worst corner is no better than the nominal unit
        assert q.worst <= q.nominal * (1 + 1e-9)
        assert q.limited_by in INPUTS
        assert q.answer.startswith(("yes at the worst case; ", "no at the worst case; "))
        assert q.answer.startswith("yes" if q.met else "no")
    assert r.sigma_worst >= r.sigma_nominal


def test_the_box_cites_its_sources_and_refuses_a_reversed_temperature_range(chosen):
    _, a = chosen
    box = tolerance_box(a.study, a.sensor.grade)
    assert box.names == INPUTS
    chip = box.inputs[box.index("chip_sensitivity")]
    assert chip.high == pytest.approx(0.03) and "Table 9" in chip.source  # MLX90393 SENSTHD
    assert box.offset == pytest.approx((150e-6, 242e-6))  # 1000 LSB at GAIN_SEL 7, RES 0
    assert box.inputs[box.index("fe_bias")].high == pytest.approx(0.05)
    assert corners(box).shape == (128, len(INPUTS))
    bad = replace(a.study, tolerances=replace(a.study.tolerances, temperature_C=(40.0, 10.0)))
    with pytest.raises(StudyError, match=r"tolerances\.temperature_C.*lowest temperature"):
        tolerance_box(bad)


def test_a_tolerance_of_zero_width_is_its_nominal_value():
    t = Tolerance("G", 0.0, 0.0, 0.0, "normal", 0.0, "none")
    assert np.all(t.ppf(np.linspace(0, 1, 5)) == 0.0)


def test_the_chosen_sensor_is_designed_for_its_worst_corner():
    """``[tolerances] design_for = "worst"`` (the default): where a sensor of the catalogue's
    parts meets the requirements at the worst corner of its tolerances (the built-in study
    with its own magnet asking 0.22 N of shear; at its 0.25 N no catalogue silicone reaches a
    G that carries it in every unit), the chosen sensor's worst corner reads the required normal force and
    carries and reads the required shear on the load envelope, its robust verdict comes with
    the answer and its JSON, and σ_F is stated nominal and worst."""
    from magtact.designer import answer_json

    magone_design = magtact.design(magtact.load("magone", requirements={"F_r_N": 0.22},
                                                design={"magnet_sizes": []}))
    magone_budgets = magtact.error_budgets(magone_design)
    a = magone_design.chosen
    assert magone_design.study.tolerances.design_for == "worst"
    r = a.robust
    req = a.study.requirements
    assert r["normal"].met and r["normal"].worst > req.F_z
    assert r["shear"].met and r["shear"].worst >= req.F_r * (1 - 1e-6)
    assert r.met and r["normal"].yield_fraction == r["shear"].yield_fraction == 1.0
    # the card states it under the verdict: the yield over every requirement, the worst corner
    from magtact import card

    rows = {row[0]: row[1:] for row in card(magone_design, magone_budgets)["rows"]}
    lo, hi = r.interval
    assert rows["units built that meet every requirement"][0] == (
        f"{100 * r.yield_fraction:.3g} % (95 % CI {100 * lo:.3g}–{100 * hi:.3g} %); "
        "the worst corner meets all")
    doc = answer_json(a)["robust_verdict"]
    assert doc["requirements"][0]["requirement"] == "normal"
    assert doc["sigma_F_worst_N"] >= doc["sigma_F_nominal_N"] > 0


def test_the_yield_factors_ask_more_of_the_nominal_parts_for_a_higher_yield(chosen):
    """``[tolerances] yield_target``: the chip must read F_z,req over the (1 − y)-quantile of
    the units' saturation force relative to the nominal unit's, so that a fraction y of the
    units reads it; a higher yield asks the nominal parts for more."""
    from magtact.tolerance import yield_factors

    models, a = chosen
    half, most = (yield_factors(models, a, y) for y in (0.5, 0.99))
    assert 1.0 <= half.read <= most.read and most.force <= half.force <= 1.0
    assert half.field == most.field == 1.0


def test_the_corners_alone_give_the_full_verdicts_decisions(chosen):
    """Without samples the verdict keeps what a solve decides on (met, worst and nominal
    figures, what limits each requirement), equal to the full verdict's, and no yield."""
    models, a = chosen
    full, quick = robust_verdict(models, a), robust_verdict(models, a, samples=False)
    for f, q in zip(full.requirements, quick.requirements, strict=True):
        assert (q.key, q.met, q.worst, q.nominal, q.limited_by) == \
            (f.key, f.met, f.worst, f.nominal, f.limited_by)
        assert np.isnan(q.yield_fraction) and np.isnan(q.interval).all()
    assert quick.samples == 0 and np.isnan(quick.yield_fraction)
    assert (quick.sigma_nominal, quick.sigma_worst) == (full.sigma_nominal, full.sigma_worst)
    target = replace(a, study=replace(a.study, tolerances=replace(a.study.tolerances,
                                                                   yield_target=0.9)))
    with pytest.raises(ValueError, match="yield target is judged on the samples"):
        robust_verdict(models, target, samples=False)
