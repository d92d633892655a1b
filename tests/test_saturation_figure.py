"""One saturation figure: the normal force at which the chip leaves its setting's range, found
by root-finding along each loading path, stated the same in every file and display, and equal
to a bisection on the exact field computed here with magpylib (independent of magtact's field
code)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from magtact.chip import onset
from magtact.study import MU0


def magpylib_ratio(study, sensor, H, range_x, range_z):
    """max(|B_x| / range_x, |B_z| / range_z) at the chip for loads (t, θ), from docs/method.md
    §1 with magpylib: the magnet's centre Δz0 = H + H_g − H_m above the base ("covered"),
    moved by u_z = t (Δz_sat + H_m − H − H_g) and u_r = −u_z tan θ, the chip the sensor's
    standoff below the base, its magnet's M_z."""
    magpy = pytest.importorskip("magpylib")
    m, b = study.magnet, study.body
    assert m.placement == "covered"

    def ratio(t, theta):
        t, theta = np.broadcast_arrays(np.asarray(t, float), np.asarray(theta, float))
        u_z = t * (study.loading.dz_sat + m.H_m - H - b.H_g)
        u_r = -u_z * np.tan(theta)
        centre = H + b.H_g - m.H_m + u_z + sensor.standoff
        pos = np.stack([u_r.ravel(), np.zeros(t.size), centre.ravel()], axis=-1)
        magnet = magpy.magnet.Cylinder(dimension=(2 * m.R_m, m.H_m),
                                       polarization=(0, 0, MU0 * sensor.M_z), position=pos)
        B = np.atleast_2d(magnet.getB((0.0, 0.0, 0.0)))
        return np.maximum(np.abs(B[:, 0]) / range_x, np.abs(B[:, 2]) / range_z).reshape(t.shape)
    return ratio


def bisection_figure(models, a, n_theta=61):
    """The smallest normal force at which the chip leaves its range, over ``n_theta`` paths of
    the stable region: per path a scan of 401 levels, then 60 plain bisection steps."""
    d, study = a.design, a.study
    ratio = magpylib_ratio(study, a.sensor, d.H, a.chip.range_x, a.chip.range_z)
    th = np.linspace(0.0, d.theta_m, n_theta)
    t = np.linspace(0.0, d.t_m, 401)
    over = ratio(t[:, None] + 0 * th, th + 0 * t[:, None]) > 1
    hit = over.any(axis=0)  # the paths on which the chip leaves its range
    assert hit.any() and not over[0].any()
    th = th[hit]
    i = over[:, hit].argmax(axis=0)
    lo, hi = t[i - 1], t[i]
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        out = ratio(mid, th) > 1
        lo, hi = np.where(out, lo, mid), np.where(out, mid, hi)
    return float(np.min(models.forces(hi, th, d.H, d.G)[1]))


def test_the_saturation_figure_agrees_with_a_bisection_on_the_exact_field(
        magone_magnet_design):
    a = magone_magnet_design.chosen
    models, _, _ = magone_magnet_design.of(a)
    reference = bisection_figure(models, a)
    assert a.verdict.F_saturation == pytest.approx(reference, rel=5e-3)
    assert a.saturation.F_z == pytest.approx(a.verdict.F_saturation, rel=1e-9)


def test_every_file_and_display_states_the_same_saturation_figure(magone_magnet_design,
                                                                  tmp_path):
    import magtact
    from magtact import write_results_into

    r = magone_magnet_design
    budgets = magtact.error_budgets(r)
    figure = f"{r.chosen.verdict.F_saturation:.3g}"
    write_results_into(r, tmp_path, figures=False, budget=False, budgets=budgets)
    card = json.loads((tmp_path / "card.json").read_text())
    sensor = json.loads((tmp_path / "sensor.json").read_text())
    chosen = json.loads((tmp_path / "chosen.json").read_text())
    stated = {"card.json": card["answers"][0]["saturation_F_z_N"],
              "sensor.json": sensor["chosen"]["F_saturation_N"],
              "chosen.json": chosen["F_saturation_N"]}
    assert {k: f"{v:.3g}" for k, v in stated.items()} == dict.fromkeys(stated, figure)
    # the card's rows (the terminal's and the report's card) and the verdict's words
    shown = magtact.card(r, budgets)
    rows = " | ".join(" ; ".join(row) for row in shown["rows"])
    assert f"F_z = {figure} N" in rows and f"saturates at {figure} N" in rows
    assert f"saturates at {figure} N" in str(shown)
    assert f"saturates at {figure} N" in r.chosen.verdict["normal"].answer


def test_onset_finds_the_first_crossing_of_a_known_ratio():
    """ratio = 1 + (t − t0(θ)) crossing once, and a ratio that leaves and re-enters the range:
    the first crossing is found to the bisection's precision; paths that never cross are NaN."""
    th = np.array([0.0, 0.1, 0.2, 0.3])
    t0 = np.array([0.123456789, 0.5, 0.0, 2.0])  # the last never crosses on [0, 1]

    def ratio(t, theta):
        k = np.searchsorted(th, theta)
        return 1.0 + (t - t0[np.clip(k, 0, 3)])

    t = onset(ratio, th, 1.0)
    assert t[:2] == pytest.approx(t0[:2], abs=1e-12)
    assert t[2] == pytest.approx(0.0, abs=1e-12) and np.isnan(t[3])

    def bump(t, theta):  # over the range on (0.2, 0.3) and from 0.7 on
        return np.where(((t > 0.2) & (t < 0.3)) | (t > 0.7), 2.0, 0.5)

    assert onset(bump, np.zeros(1), 1.0)[0] == pytest.approx(0.2, abs=1e-12)


def test_the_saturation_of_another_modulus_is_the_forces_scaled_by_it(magone_magnet_design):
    """Where the chip leaves its range depends on the load path, not on G (the forces are G
    times the per-unit-G forces): a design of another G saturates at the same t and θ, at the
    forces scaled by the ratio of the moduli, and a kept figure equals a fresh search."""
    from magtact.chip import saturation
    from magtact.chip._range import _unit_saturation

    a = magone_magnet_design.chosen
    models, _, _ = magone_magnet_design.of(a)
    d, study = a.design, a.study
    place = {"M_z": a.sensor.M_z, "standoff": a.sensor.standoff}
    s1 = saturation(study, models, d.H, d.G, a.chip, d.t_m, d.theta_m, **place)
    s2 = saturation(study, models, d.H, 2.5 * d.G, a.chip, d.t_m, d.theta_m, **place)
    assert (s2.t, s2.theta, s2.axis) == (s1.t, s1.theta, s1.axis)
    assert s2.F_z == pytest.approx(2.5 * s1.F_z, rel=1e-14)
    assert s2.F_r == pytest.approx(2.5 * s1.F_r, rel=1e-14)
    _unit_saturation.cache_clear()
    fresh = saturation(study, models, d.H, 2.5 * d.G, a.chip, d.t_m, d.theta_m, **place)
    assert fresh == s2
    # against the models' own forces at G where the chip leaves its range
    F_r, F_z = models.forces(s2.t, s2.theta, d.H, 2.5 * d.G)
    assert (s2.F_r, s2.F_z) == (pytest.approx(float(F_r), rel=1e-14),
                                pytest.approx(float(F_z), rel=1e-14))
