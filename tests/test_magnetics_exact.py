"""Exact field of an axially magnetised cylinder: magpylib, analytic limits, symmetries."""

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import ellipe, ellipk

from conftest import H_M, M_Z, R_M, acceptance_points, rel_diff
from magtact.magnetics import cel, cylinder_field
from magtact.study import MU0

magpy = pytest.importorskip("magpylib")

def magpylib_field(r, z, R_m=R_M, H_m=H_M, M_z=M_Z):
    """(B_r, B_z) of magpylib's cylinder with the same polarisation μ0 M_z (MU0 of magtact)."""
    magnet = magpy.magnet.Cylinder(dimension=(2 * R_m, H_m), polarization=(0, 0, MU0 * M_z))
    B = magnet.getB(np.column_stack([r, np.zeros_like(r), z]))
    return B[:, 0], B[:, 2]


@pytest.mark.parametrize("region", ["below", "above", "beside"])
def test_matches_magpylib_on_acceptance_grid(region):
    r, z = acceptance_points()[region]
    err = rel_diff(cylinder_field(r, z, R_M, H_M, M_Z), magpylib_field(r, z))
    assert err.max() <= 1e-9


def test_matches_magpylib_inside_on_mantle_line_and_faces():
    # inside the magnet (B = μ0 (H + M)), on the mantle's extension r = R_m, on the faces' planes
    r = np.array([0.0, 1e-3, 2.4e-3, R_M, R_M, R_M, 1e-3, 4e-3, 0.0])
    z = np.array([0.0, 0.3e-3, -0.9e-3, 1.5e-3, -4e-3, 0.5e-3, H_M / 2, -H_M / 2, 30e-3])
    err = rel_diff(cylinder_field(r, z, R_M, H_M, M_Z), magpylib_field(r, z))
    assert err.max() <= 1e-9


def test_other_aspect_ratios_match_magpylib():
    rng = np.random.default_rng(1)
    r, z = rng.uniform(0, 10e-3, 200), rng.uniform(-10e-3, 10e-3, 200)
    for R_m, H_m in ((1e-3, 8e-3), (6e-3, 0.5e-3)):
        err = rel_diff(cylinder_field(r, z, R_m, H_m, 8e5), magpylib_field(r, z, R_m, H_m, 8e5))
        assert err.max() <= 1e-9


def test_axis_closed_form():
    z = np.linspace(-20e-3, 20e-3, 81)
    B_r, B_z = cylinder_field(0.0, z, R_M, H_M, M_Z)
    zp, zm = z + H_M / 2, z - H_M / 2
    expected = MU0 * M_Z / 2 * (zp / np.hypot(zp, R_M) - zm / np.hypot(zm, R_M))
    assert np.all(B_r == 0.0)
    np.testing.assert_allclose(B_z, expected, rtol=1e-13)


def test_far_field_is_the_dipole():
    moment = M_Z * np.pi * R_M**2 * H_M
    d = 1.0  # 400 magnet radii away
    angle = np.linspace(0, np.pi, 7)
    r, z = d * np.sin(angle), d * np.cos(angle)
    B = np.array(cylinder_field(r, z, R_M, H_M, M_Z))
    dipole = MU0 * moment / (4 * np.pi * d**3) * np.array([3 * np.sin(angle) * np.cos(angle),
                                                           3 * np.cos(angle) ** 2 - 1])
    assert rel_diff(B, dipole).max() < 1e-4


def test_symmetry_about_the_mid_plane_and_linearity_in_M():
    r, z = np.meshgrid(np.linspace(0, 8e-3, 9), np.linspace(0.1e-3, 8e-3, 9))
    up, down = cylinder_field(r, z, R_M, H_M, M_Z), cylinder_field(r, -z, R_M, H_M, M_Z)
    np.testing.assert_allclose(down[0], -up[0], rtol=1e-12, atol=0)
    np.testing.assert_allclose(down[1], up[1], rtol=1e-12, atol=0)
    np.testing.assert_allclose(cylinder_field(r, z, R_M, H_M, 2 * M_Z)[1], 2 * up[1], rtol=1e-14)


def test_rim_is_nan_and_shapes_broadcast():
    B_r, B_z = cylinder_field(np.array([[R_M], [1e-3]]), np.array([H_M / 2, 0.0, -5e-3]),
                              R_M, H_M, M_Z)
    assert B_r.shape == B_z.shape == (2, 3)
    assert np.isnan(B_r[0, 0]) and np.isnan(B_z[0, 0])
    assert np.isfinite(B_r[1]).all() and np.isfinite(B_z[0, 1:]).all()


def test_cel_special_cases_and_quadrature():
    k = np.linspace(0.05, 0.95, 10)
    kc = np.sqrt(1 - k**2)
    np.testing.assert_allclose(cel(kc, 1.0, 1.0, 1.0), ellipk(k**2), rtol=1e-14)
    np.testing.assert_allclose(cel(kc, 1.0, 1.0, kc**2), ellipe(k**2), rtol=1e-14)
    for args in ((0.3, 0.0, 1.0, 0.0), (0.7, 0.25, 1.0, 0.5), (1.5, 3.0, -1.0, 2.0),
                 (0.01, 1.0, 1.0, -1.0)):
        kc_, p, c, s = args

        def f(phi, kc_=kc_, p=p, c=c, s=s):
            co, si = np.cos(phi) ** 2, np.sin(phi) ** 2
            return (c * co + s * si) / ((co + p * si) * np.sqrt(co + kc_**2 * si))

        assert cel(*args) == pytest.approx(quad(f, 0, np.pi / 2, epsabs=0, epsrel=1e-11)[0],
                                           rel=1e-10)


@pytest.mark.parametrize("call, message", [
    (lambda: cylinder_field(-1e-3, 0.0, R_M, H_M, M_Z), "r must be >= 0"),
    (lambda: cylinder_field(1e-3, 0.0, 0.0, H_M, M_Z), "R_m and H_m must be positive"),
    (lambda: cylinder_field(1e-3, 0.0, R_M, -H_M, M_Z), "R_m and H_m must be positive"),
    (lambda: cel(0.0, 1.0, 1.0, 1.0), "kc must be non-zero"),
    (lambda: cel(0.5, -1.0, 1.0, 1.0), "p must be >= 0"),
])
def test_bad_input_messages(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_scalar_input_gives_zero_dimensional_arrays():
    B_r, B_z = cylinder_field(1e-3, -4e-3, R_M, H_M, M_Z)
    assert np.shape(B_r) == np.shape(B_z) == ()
    assert np.isnan(cylinder_field(R_M, H_M / 2, R_M, H_M, M_Z)[0])
