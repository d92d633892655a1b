"""Contact integrated at the faces' Gauss points: exact nodal forces, the Coulomb limit, and the
tangent against finite differences of the residual (one cell; milliseconds)."""

from __future__ import annotations

import felupe as fem
import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from magtact.mechanics._face_contact import FaceContactRigidPlane


def _cell(nodes: int):
    """One unit cube cell of 8, 20 or 27 nodes plus a plate point at its top, z = 1."""
    mesh = fem.Cube(n=2)
    if nodes > 8:
        mesh = fem.mesh.convert(mesh, order=2, calc_midfaces=nodes == 27,
                                calc_midvolumes=nodes == 27)
    mesh.update(points=np.vstack([mesh.points, [[0.0, 0.0, 1.0]]]))
    region = {8: fem.RegionHexahedron, 20: fem.RegionQuadraticHexahedron,
              27: fem.RegionTriQuadraticHexahedron}[nodes](mesh)
    field = fem.FieldContainer([fem.Field(region, dim=3)])
    solid = fem.SolidBodyNearlyIncompressible(fem.NeoHooke(mu=1.0), field, bulk=50.0)
    top = np.isclose(mesh.points[:, 2], 1.0)
    top[-1] = False
    return mesh, field, solid, top


def _contact(field, solid, top, **kw):
    n = field.region.mesh.npoints
    return FaceContactRigidPlane(field, top, None, n - 1, [0, 0, -1.0], solid=solid, **kw)


def _residual(c) -> np.ndarray:
    return np.asarray(c.assemble.vector().todense()).ravel()


@pytest.mark.parametrize(("nodes", "corner", "edge", "middle"),
                         [(8, 1 / 4, None, None), (20, -1 / 12, 1 / 3, None),
                          (27, 1 / 36, 1 / 9, 4 / 9)])
def test_a_uniform_penetration_gives_the_faces_consistent_nodal_forces(nodes, corner, edge,
                                                                       middle):
    """The plate 1 µm into the top face: the face's consistent loads of a uniform pressure
    (the 20-node face's corners pull, −1/12), ε (g − δ/2) A in all (the C¹ penalty), the
    plate's reaction opposite."""
    mesh, field, solid, top = _cell(nodes)
    c = _contact(field, solid, top)
    field[0].values[-1, 2] = -1e-6
    f = _residual(c).reshape(-1, 3)
    total = c._eps * (1e-6 - c.smoothing / 2) * 1.0  # ε (g − δ/2) A, the face's area is 1
    assert f[top, 2].sum() == pytest.approx(total, rel=1e-9)
    assert f[-1, 2] == pytest.approx(-total, rel=1e-9)
    assert np.abs(f[:, :2]).max() < 1e-12 * total  # frictionless: no tangential force
    xy = mesh.points[top, :2]
    at_corner = np.all(np.isclose(xy, 0) | np.isclose(xy, 1), axis=1)
    at_middle = np.all(np.isclose(xy, 0.5), axis=1)
    share = f[top, 2] / total
    np.testing.assert_allclose(share[at_corner], corner, rtol=1e-9)
    if edge is not None:
        np.testing.assert_allclose(share[~at_corner & ~at_middle], edge, rtol=1e-9)
    if middle is not None:
        np.testing.assert_allclose(share[at_middle], middle, rtol=1e-9)


def test_a_face_off_the_plate_feels_nothing():
    mesh, field, solid, top = _cell(20)
    c = _contact(field, solid, top, friction=0.5)
    field[0].values[-1, 2] = 1e-6
    assert not np.any(_residual(c))
    assert c.assemble.matrix().nnz == 0


def _state(nodes: int, slide: float, seed: int, start: float = -1e-6):
    """The plate ``start`` above the cell's top face (the converged state: negative, pressed
    into it), then 1 µm into it, moved sideways by ``slide`` × the elastic slip, and the nodes
    perturbed (the trial state); a point that was off the plate touches it within the
    increment."""
    mesh, field, solid, top = _cell(nodes)
    gamma = 1e-6
    c = _contact(field, solid, top, friction=0.3, elastic_slip=gamma)
    u = field[0].values
    u[-1, 2] = start
    c.assemble.vector()
    c.results.update_statevars()
    rng = np.random.default_rng(seed)
    u[-1] = [slide * gamma, 0.5 * slide * gamma, -1e-6]
    u[:-1] += 2e-7 * rng.standard_normal(u[:-1].shape)
    return c, u


@pytest.mark.parametrize("slide", [0.3, 5.0])
def test_sliding_points_carry_mu_times_their_normal_force(slide):
    """Below the elastic slip every point sticks; beyond it every point slides with
    |f_t| = μ f_n, the Coulomb limit, and the plate is dragged along."""
    c, u = _state(20, slide, 0)
    idx, force, _ = c._evaluate()
    fn = -force @ c.normal
    ft = np.linalg.norm(force - np.outer(force @ c.normal, c.normal), axis=1)
    if slide < 1:
        assert np.all(ft < 0.3 * fn)
    else:
        np.testing.assert_allclose(ft, 0.3 * fn, rtol=1e-9)
    assert np.all(fn > 0)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(nodes=st.sampled_from([8, 20, 27]), slide=st.floats(0.0, 4.0),
       seed=st.integers(0, 2**16), start=st.sampled_from([-1e-6, 5e-7]))
def test_the_tangent_is_the_derivative_of_the_residual(nodes, slide, seed, start):
    """K d equals the central difference of the residual along a random direction d, with
    sticking, sliding and newly touching points (the contact state the same on both sides)."""
    c, u = _state(nodes, slide, seed, start)
    u0 = u.copy()
    K = c.assemble.matrix()
    d = np.random.default_rng(seed + 1).standard_normal(u.shape) * 1e-10
    states = []
    r = []
    for sign in (1, -1):
        u[:] = u0 + sign * d
        r.append(_residual(c))
        states.append((c._trial["active"].copy(), c.results.slip.copy()))
    u[:] = u0
    idx0 = c._evaluate()[0]
    assume(all(np.array_equal(a, c._trial["active"]) and np.array_equal(s, c.results.slip)
               for a, s in states))
    fd = (r[0] - r[1]) / 2
    scale = np.linalg.norm(fd)
    assume(idx0.size > 0 and scale > 0)
    assert np.linalg.norm(K @ d.ravel() - fd) <= 1e-5 * scale


def test_an_unknown_contact_is_refused_naming_the_choices():
    from magtact.geometry import half_cylinder_mesh
    from magtact.mechanics import HalfBodyModel

    with pytest.raises(ValueError, match=r"contact must be one of \('nodes', 'faces'\), "
                                         r"got 'edges'"):
        HalfBodyModel(half_cylinder_mesh(6e-3, 6e-3, density="coarse"), 10e3, 5000.0, 0.0,
                      contact="edges")


def test_the_study_refuses_an_unknown_contact_naming_the_key():
    from magtact.study import StudyError, study_from_dict

    with pytest.raises(StudyError, match=r"mechanics\.contact.*'nodes', 'faces'"):
        study_from_dict({"mechanics": {"contact": "edges"}}, "test")
