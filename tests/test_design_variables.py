"""The magnetisation M_z as a design variable: exact scaling, no new simulation, the optimisation
over (H, G, M_z) against its closed form, and bad input."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from conftest import G_ORIGINAL, H_ORIGINAL
from magtact.metamodel import ExactField, ModelSet
from magtact.optimise import (
    as_responses,
    best_magnetisation,
    chip_margin,
    choose,
    exact_reduction,
    force_constraints,
    front_gap,
    pareto_nsga2,
    per_design,
    sweep,
)
from magtact.sensitivity import gamma
from magtact.study import StudyError, load_study, study_from_dict

H0, G0 = H_ORIGINAL, G_ORIGINAL


@pytest.fixture(scope="module")
def study():
    s = load_study("magone")
    return replace(s, design=replace(s.design, M_z=(0.9e6, 1.3e6)),
                   optimise=replace(s.optimise, sweep_n=201, population=60,
                                    nsga2_generations=40))


def _exact(models, study, M_z):
    """The models with the exact field of a magnet of magnetisation M_z."""
    s = replace(study, magnet=replace(study.magnet, M_z=M_z))
    return ModelSet(ExactField(s, "B_r"), ExactField(s, "B_z"), models.f_r, models.f_z)


def test_gamma_scales_as_G_over_M_z(models, study):
    """Γ from the exact field of a 1.3 MA/m magnet is Γ of the 1.2 MA/m magnet × 1.2 / 1.3."""
    t, th = np.meshgrid(np.linspace(0, 1, 9), np.linspace(0, 0.4, 5), indexing="ij")
    M0, M1 = study.magnet.M_z, 1.3e6
    ref, strong = _exact(models, study, M0), _exact(models, study, M1)
    for a, b in zip(gamma(strong, t, th, H0, 2 * G0), gamma(ref, t, th, H0, G0), strict=True):
        np.testing.assert_allclose(a, b * 2 * M0 / M1, rtol=1e-12, atol=0)
    d0, d1 = per_design(ref, H0, G0, study), per_design(ref, H0, G0, study, M1)
    assert d1.Gamma_r_max == pytest.approx(d0.Gamma_r_max * M0 / M1, rel=1e-12)
    assert d1.Gamma_z_max == pytest.approx(d0.Gamma_z_max * M0 / M1, rel=1e-12)
    assert (d1.F_r_min, d1.F_z_max) == (d0.F_r_min, d0.F_z_max)  # forces do not see M_z


def test_M_z_adds_no_structural_path_and_keeps_the_bundled_data(study):
    from magtact.doe import load_bundled, matches_study
    from magtact.doe._jobs import plan
    from magtact.magnetics import hall_field
    from magtact.mechanics import simulate_path

    fixed = load_study("magone")
    f0, p0 = plan(fixed, simulate_path, hall_field)
    f1, p1 = plan(study, simulate_path, hall_field)
    assert [j.key for j in p1] == [j.key for j in p0] and f1.key == f0.key
    assert matches_study(load_bundled(), study)


def test_without_the_chip_the_strongest_magnet_wins(models, study):
    R = as_responses(models)
    table = sweep(R, study)
    c = force_constraints(R, study)
    red = exact_reduction(R, study, c, table)
    np.testing.assert_array_equal(red.M_z_star, 1.3e6)
    fixed = exact_reduction(R, load_study("magone"), c, table)
    np.testing.assert_allclose(red.Gamma_r, fixed.Gamma_r * 1.2 / 1.3, rtol=1e-12)


def test_with_the_chip_the_reduction_is_the_closed_form_and_nsga2_agrees(models, study):
    """M_z*(H) = min(M_hi, M_0 / (1 + m_0(H))): the field exactly fills the chip's range."""
    s = replace(study, constraints=replace(study.constraints, chip_range=True))
    R = as_responses(models)
    table = sweep(R, s)
    c = force_constraints(R, s)
    red = exact_reduction(R, s, c, table)
    m0 = chip_margin(s, table.H, table.t_m, table.theta_m)
    expect = np.minimum(1.3e6, 1.2e6 / (1 + m0))
    ok = expect >= 0.9e6
    np.testing.assert_allclose(red.M_z_star[ok], expect[ok], rtol=1e-12)
    assert np.isnan(best_magnetisation(s, table)[~ok]).all() and (~ok).any()
    # where the cap binds, the chosen magnet's field touches the range: margin 0
    k = np.flatnonzero(ok & (expect < 1.3e6))[0]
    strong = replace(s, magnet=replace(s.magnet, M_z=float(red.M_z_star[k])))
    assert abs(chip_margin(strong, table.H[k], table.t_m[k], table.theta_m[k])[0]) < 1e-9
    pareto = pareto_nsga2(R, s, c, table)
    assert front_gap(pareto, red) < 0.01
    ch = choose(R, s, red)
    assert ch.design.M_z == pytest.approx(red.M_z_star[ch.index])


def test_card_names_the_magnetisation(models, study):
    from magtact import Sensor
    from magtact.designer import answer
    from magtact.report import card_rows

    a = answer(models, study, Sensor.of_study(study, H0, G0, 1.3e6), "chosen", 1.3e6)
    b = answer(models, study, Sensor.of_study(study, H0, G0), "original")
    rows = {r[0]: r[1:] for r in card_rows([a, b])[1]}
    assert rows["magnetisation M_z (magnet grade)"] == ["1.3 MA/m", "the magnet's own"]
    # the stronger magnet's field reaches the chip's range sooner
    assert a.saturation.t < b.saturation.t


@pytest.mark.parametrize(("design", "message"), [
    ({"M_z_A_per_m": [1.3e6, 0.9e6]}, r"\[design.M_z_A_per_m\] range out of order"),
    ({"M_z_A_per_m": [0, 1.3e6]}, r"\[design.M_z_A_per_m\] must be \[0, 0\]"),
    ({"M_z_A_per_m": [-1.0, 1.3e6]}, r"\[design.M_z_A_per_m\] must be at least 0"),
    ({"M_z_A_per_m": [1e6, 1e9]}, r"\[design.M_z_A_per_m\] must be 0 or between"),
    ({"R_m_mm": [1.5, 3.5]}, r"\[design.R_m_mm\] geometric design variables need the exact "
                             r"field \(metamodel.b_model = 'exact'\)"),
    ({"M_mm": [1.0, 2.0]}, r"\[design.M_mm\] unknown key"),
])
def test_bad_design_variables_name_the_key(design, message):
    with pytest.raises(StudyError, match=message):
        study_from_dict({"design": design})


EXACT = {"metamodel": {"b_model": "exact"}}


@pytest.mark.parametrize(("design", "message"), [
    ({"R_m_mm": [3.5, 1.5]}, r"\[design.R_m_mm\] range out of order: low 3.5"),
    ({"R_m_mm": [0, 3.5]}, r"\[design.R_m_mm\] must be \[0, 0\] \(fixed at magnet.R_m_mm\)"),
    ({"R_m_mm": [3.0, 4.0]}, r"\[magnet.R_m_mm\] 2.5 mm \(the original design's\) lies outside "
                             r"design.R_m_mm = \[3, 4\]"),
    ({"R_m_mm": [1.5, 6.5]}, r"\[design.R_m_mm\] cannot be built at the corner R_m = 6.5 mm "
                             r"of the design ranges: \[magnet.R_m_mm\] the magnet \(6.5 mm "
                             r"radius\) must be narrower than the body"),
    ({"R_m_mm": [1.5, 3.5], "H_m_mm": [1.0, 4.0]},
     r"\[design.R_m_mm, design.H_m_mm\] cannot be built at the corner R_m = 1.5 mm, H_m = 4 mm"
     r".*\[magnet.H_m_mm\] the covered magnet needs 6 mm"),
    ({"R_m_mm": [2.0, 3.5], "R_mm": [4.2, 8.0]},
     r"corner R_m = 3.5 mm, R = 4.2 mm .*\[body.R_h_mm\] edge radius 1 mm"),
])
def test_geometric_ranges_that_cannot_be_built_name_keys_and_corner(design, message):
    with pytest.raises(StudyError, match=message):
        study_from_dict({"design": design} | EXACT)


def test_a_geometric_sub_study_fixes_the_value_and_clears_the_range():
    s = study_from_dict({"design": {"R_m_mm": [1.5, 3.5], "R_mm": [5.0, 7.0]}} | EXACT)
    assert list(s.geometric_variables) == ["R_m", "R"]
    np.testing.assert_allclose(s.geometry_levels["R_m"], [1.5e-3, 2.5e-3, 3.5e-3])
    sub = s.at(R_m=2e-3, R=6.5e-3)
    assert sub.magnet.R_m == 2e-3 and sub.body.R == sub.body.R_g == 6.5e-3
    assert sub.geometric_variables == {} and sub.design.H == s.design.H
    assert s.geometry() == {"R_m": 2.5e-3, "R": 6e-3}
    with pytest.raises(ValueError, match=r"not geometric design variables: \['G'\]"):
        s.at(G=1.0)
