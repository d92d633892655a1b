"""Field at the Hall point: the geometry of docs/method.md §1 written out by hand, checked with
magpylib."""

from dataclasses import replace

import numpy as np
import pytest

from conftest import rel_diff, spec_hall_field
from magtact.magnetics import hall_field, magnet_field
from magtact.study import StudyError, load_study


def grid(study):
    return np.meshgrid(study.t_levels, study.theta_levels, study.H_levels, indexing="ij")


@pytest.mark.parametrize("placement", ["covered", "flush"])
def test_exact_hall_field_matches_spec_geometry(placement):
    s = load_study()
    s = replace(s, magnet=replace(s.magnet, placement=placement))
    t, theta, H = grid(s)
    B = hall_field(s, t, theta, H, solver="exact")
    assert rel_diff(B, spec_hall_field(t, theta, H, placement)).max() <= 1e-9


def test_fe_hall_field_matches_spec_geometry():
    s = load_study()
    t, theta, H = grid(s)
    B = hall_field(s, t, theta, H)  # the study's default solver: FE
    assert s.magnetics.solver == "fe"
    assert rel_diff(B, spec_hall_field(t, theta, H)).max() <= 2e-3


def test_sign_conventions():
    s = load_study()
    B_r, B_z = hall_field(s, np.array([0.5, 1.0, 1.0]), np.array([0.0, 0.2, 0.4]), 3e-3, "exact")
    assert B_r[0] == 0.0            # no shear: Hall point on the axis
    assert np.all(B_r[1:] > 0.0)    # shear along +x: B_r > 0 (the Hall point is at x < 0)
    assert np.all(B_z > 0.0)        # below a +z magnetised magnet: B_z up
    # a mirrored shear (θ < 0) mirrors B_r only
    mirrored = hall_field(s, 1.0, -0.4, 3e-3, "exact")
    assert mirrored[0] == pytest.approx(-B_r[2], rel=1e-14)
    assert mirrored[1] == pytest.approx(B_z[2], rel=1e-14)


def test_broadcasting_and_magnet_frame_symmetry():
    s = load_study()
    B_r, B_z = hall_field(s, np.linspace(0, 1, 4)[:, None], 0.3, np.array([3e-3, 5e-3]), "exact")
    assert B_r.shape == B_z.shape == (4, 2)
    x = np.array([-2e-3, 2e-3])
    B_x, B_zz = magnet_field(s, x, -4e-3, "exact")
    assert B_x[0] == -B_x[1] and B_zz[0] == B_zz[1]


def test_unknown_solver_is_refused():
    with pytest.raises(ValueError, match="solver must be one of"):
        hall_field(load_study(), 0.5, 0.1, 3e-3, solver="bem")


def test_hall_point_beyond_the_fine_zone_names_the_key():
    s = load_study()
    s = replace(s, magnetics=replace(s.magnetics, near=3e-3))
    with pytest.raises(StudyError, match=r"magnetics\.near_mm"):
        hall_field(s, 0.0, 0.0, 7e-3, solver="fe")
