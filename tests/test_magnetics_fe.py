"""Axisymmetric FE field vs the exact closed form; mesh refinement; bad settings."""

from dataclasses import replace

import numpy as np
import pytest

from conftest import H_M, M_Z, R_M, acceptance_points, rel_diff
from magtact.geometry import field_mesh
from magtact.magnetics import cylinder_field, solve_fe, solve_field
from magtact.study import StudyError, load_study


@pytest.fixture(scope="module")
def solution():
    return solve_fe(load_study())


@pytest.mark.parametrize("region", ["below", "above", "beside"])
def test_fe_matches_exact_on_acceptance_grid(solution, region):
    r, z = acceptance_points()[region]
    err = rel_diff(solution.B(r, z), cylinder_field(r, z, R_M, H_M, M_Z))
    assert err.max() <= 2e-3


def test_fe_inside_the_magnet_includes_M(solution):
    r, z = np.array([0.0, 1e-3, 2e-3]), np.array([0.0, 0.5e-3, -0.5e-3])
    B = solution.B(r, z)
    assert rel_diff(B, cylinder_field(r, z, R_M, H_M, M_Z)).max() <= 2e-3
    assert np.all(B[1] > 0.4)  # B_z inside ≈ μ0 (M + H_demag) > 0


def test_solution_is_cached_per_magnet_and_mesh(solution):
    s = load_study()
    assert solve_fe(s) is solution
    other = replace(s, magnetics=replace(s.magnetics, h_magnet=0.2e-3))
    assert solve_fe(replace(other, magnetics=replace(other.magnetics, solver="exact"))) \
        is solve_fe(other) is not solution


def test_second_order_elements_on_a_conforming_mesh(solution):
    # P2: one DOF per node and per edge; Euler for a simply connected triangulation gives
    # n_edges = n_nodes + n_triangles - 1.
    n_nodes, n_tri = solution.mesh.points.shape[1], solution.mesh.n_triangles
    assert solution.n_dofs == 2 * n_nodes + n_tri - 1
    in_magnet = solution.mesh.points[:, solution.mesh.triangles[:, solution.mesh.in_magnet]]
    assert in_magnet[0].max() <= R_M * (1 + 1e-12)
    assert np.abs(in_magnet[1]).max() <= H_M / 2 * (1 + 1e-12)


def test_error_falls_with_refinement_at_second_order():
    """All element sizes halved twice; a far box large enough that its n·B = 0 image field is
    far below the discretisation error, so the rate measured is that of the P2 elements."""
    r, gap = np.meshgrid(np.linspace(0, 3e-3, 7), np.linspace(2.97e-3, 12e-3, 10))
    r, z = r.ravel(), -H_M / 2 - gap.ravel()
    exact = cylinder_field(r, z, R_M, H_M, M_Z)
    errors = []
    for f in (1.0, 0.5, 0.25):
        mesh = field_mesh(R_M, H_M, h_magnet=0.4e-3 * f, growth_near=0.05 * f, near=13e-3,
                          growth=0.6 * f, far_r=400, far_z=500)
        e = rel_diff(solve_field(mesh, R_M, H_M, M_Z).B(r, z), exact)
        errors.append(np.sqrt(np.mean(e**2)))
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert errors[0] > errors[1] > errors[2]
    assert np.all(rates > 1.6), rates  # P2: gradient error O(h^2)


def test_point_outside_or_negative_radius_is_refused(solution):
    with pytest.raises(ValueError, match="outside the far box"):
        solution.B(0.0, 0.2)
    with pytest.raises(ValueError, match="r must be >= 0"):
        solution.B(-1e-3, 0.0)


@pytest.mark.parametrize("key, value, message", [
    ("growth_near", 0.5, "magnetics.growth_near"),
    ("far_r", 3.0, "magnetics.far_r"),
    ("far_z", 2.0, "magnetics.far_z"),
])
def test_inconsistent_mesh_settings_name_the_key(key, value, message):
    s = load_study()
    with pytest.raises(StudyError, match=message.replace(".", r"\.")):
        solve_fe(replace(s, magnetics=replace(s.magnetics, **{key: value})))


@pytest.mark.parametrize("kwargs, message", [
    (dict(h_magnet=0.0), "h_magnet must be positive"),
    (dict(growth_near=0.7), "growth_near < growth"),
    (dict(far_r=1.0), "must enclose the magnet"),
])
def test_field_mesh_bad_input(kwargs, message):
    args = dict(h_magnet=1e-4, growth_near=0.01, near=13e-3, growth=0.3, far_r=100, far_z=50)
    with pytest.raises(ValueError, match=message):
        field_mesh(R_M, H_M, **(args | kwargs))
