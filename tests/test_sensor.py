"""The sensor problem: the whole sensor (H, G, magnet grade, chip standoff and setting) that
meets the study's requirements. The chosen sensor's field at the required loads is checked
against magpylib (an independent field code), NSGA-II against the exact reduction, the verdict
against designs that break a requirement."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import magtact
from magtact.chip import SensorGrid
from magtact.metamodel import prefitted_dir
from magtact.study import MU0, StudyError, load_study

pytestmark = pytest.mark.filterwarnings("ignore::magtact.optimise.FrontGapWarning")

#: Small optimiser budgets for the publication's part of the chain (the sensor is under test).
FAST = {"population": 24, "nsga2_generations": 12, "grid_n": 2, "sweep_n": 201,
        "sweep_coarse": 21}


def _study(**sections):
    s = magtact.load("magone", **sections)
    return replace(s, optimise=replace(s.optimise, **FAST))


@pytest.fixture(scope="module")
def result(magone_magnet_design):
    """The built-in study's design with its own magnet, the MagOne ⌀5 × 2 mm (the session's:
    solved once for every test that asks)."""
    return magone_magnet_design


def field_magpylib(study, sensor, H, t, theta):
    """(B_x, B_z) [T] at the chip from docs/method.md §1 with magpylib: the magnet's centre
    Δz0 = H + H_g − H_m above the body's base, moved by u_z = t (Δz_sat + H_m − H − H_g) and
    u_r = −u_z tan θ; the chip the sensor's standoff below the base, its magnet's M_z."""
    magpy = pytest.importorskip("magpylib")
    m, b = study.magnet, study.body
    u_z = t * (study.loading.dz_sat + m.H_m - H - b.H_g)
    u_r = -u_z * np.tan(theta)
    centre = H + b.H_g - m.H_m + u_z + sensor.standoff
    out = np.empty((2, t.size))
    for i in range(t.size):
        magnet = magpy.magnet.Cylinder(dimension=(2 * m.R_m, m.H_m),
                                       polarization=(0, 0, MU0 * sensor.M_z),
                                       position=(u_r[i], 0.0, centre[i]))
        B = magnet.getB((0.0, 0.0, 0.0))
        out[:, i] = B[0], B[2]
    return out


def assert_reads_required_loads(result, n=(60, 15)):
    """The chosen sensor's field at every load up to the required normal force, from
    magpylib, lies inside the range of its chip setting."""
    a = result.chosen
    study = a.study
    d = a.design
    T, TH = (v.ravel() for v in np.meshgrid(np.linspace(0, d.t_m, n[0]),
                                            np.linspace(0, d.theta_m, n[1]), indexing="ij"))
    _, F_z = result.models.forces(T, TH, d.H, d.G)
    keep = F_z <= study.requirements.F_z
    assert keep.sum() > 0.3 * keep.size  # the required loads are a good part of the region
    B = field_magpylib(study, a.sensor, d.H, T[keep], TH[keep])
    assert np.abs(B[0]).max() <= a.chip.range_x and np.abs(B[1]).max() <= a.chip.range_z
    return B


def assert_shear_line_holds_on_the_chip(result, n=(201, 41)):
    """The verdict's shear line against the loads on the paths (the models' forces) and the
    chip's field from magpylib: the largest shear within the required normal force up to where
    the chip leaves its range on each path is the verdict's figure, and the line says yes
    exactly when it reaches the required shear (and the body is stable up to it)."""
    a = result.chosen
    study, d = a.study, a.design
    req = study.requirements
    th = np.linspace(0.0, d.theta_m, n[1])
    t = np.linspace(0.0, d.t_m, n[0])
    T, TH = (v.ravel() for v in np.meshgrid(t, th, indexing="ij"))
    F_r, F_z = (np.asarray(f).reshape(n) for f in result.models.forces(T, TH, d.H, d.G))
    B = field_magpylib(study, a.sensor, d.H, T, TH).reshape(2, *n)
    out = (np.abs(B[0]) > a.chip.range_x) | (np.abs(B[1]) > a.chip.range_z)
    before = np.cumsum(out, axis=0) == 0  # the loads before the chip leaves its range
    read = np.abs(F_r[before & (F_z <= req.F_z)]).max()
    # a grid of 201 levels: within a level's shear of the root-found figure
    assert a.verdict.shear_read == pytest.approx(read, abs=0.01 * req.F_r)
    line = a.verdict["shear"]
    assert line.met is bool(read >= req.F_r and -d.F_r_min >= req.F_r)
    if not line.met and -d.F_r_min >= req.F_r:
        assert f"{a.verdict.shear_read:.3g} N" in line.answer, line.answer


#: The MLX90393's offset band over temperature, 1000 LSB at GAIN_SEL 7, RES 0 (datasheet rev.
#: 011, Table 9 OFFSTHD; Table 17: 0.150 µT/LSB xy, 0.242 µT/LSB z) [T].
MLX_OFFSET = (150e-6, 242e-6)


def assert_worst_corner_reads(result, n_t=401):
    """At the worst corner of the chosen sensor's tolerances (the robust verdict's), the chip
    reads the required normal force on every DOE path: the unit's field from magpylib (its
    remanence at its temperature, magnet size, body height and standoff, read with its gain
    and offset), its normal force from the bundled DOE's FE forces (linear in t, and in H
    between the two nearest levels; times its G over G and over 1 + the FE bias)."""
    from magtact.doe import bundled_for
    from magtact.parts import grade

    magpy = pytest.importorskip("magpylib")
    a = result.chosen
    study, d = a.study, a.design
    req = study.requirements
    w = a.robust["normal"]
    assert w.met, w.text
    c = w.corner
    m, b = study.magnet, study.body
    alpha = grade(a.parts.grade).alpha
    M = a.sensor.M_z * c["B_r"] * (1 + alpha * (c["temperature"] - 20.0))
    H = d.H + c["H"]
    standoff = max(a.sensor.standoff + c["standoff"], 0.0)
    gain, off = 1 + c["chip_sensitivity"], c["chip_offset"] * np.array(MLX_OFFSET)
    ds = bundled_for(study)
    Hs = ds["H"].values
    k = int(np.clip(np.searchsorted(Hs, H) - 1, 0, Hs.size - 2))
    wH = (H - Hs[k]) / (Hs[k + 1] - Hs[k])
    G_ref = float(ds["G"].values[-1])
    F_z_doe = ds["F_z"].sel(G=G_ref).values  # (t, θ, H)
    scale = d.G * (1 + c["G"]) / (1 + c["fe_bias"]) / G_ref
    t = np.linspace(0.0, 1.0, n_t)
    checked = 0
    for j, theta in enumerate(ds["theta"].values):
        if theta > d.theta_m * (1 + 1e-9):
            continue
        F = scale * ((1 - wH) * np.interp(t, ds["t"].values, F_z_doe[:, j, k])
                     + wH * np.interp(t, ds["t"].values, F_z_doe[:, j, k + 1]))
        tt = t[(F <= req.F_z) & (t <= d.t_m)]
        u_z = tt * (study.loading.dz_sat + m.H_m - H - b.H_g)
        pos = np.stack([-u_z * np.tan(theta), 0 * tt, H + b.H_g - m.H_m + u_z + standoff], -1)
        magnet = magpy.magnet.Cylinder(dimension=(2 * (m.R_m + c["R_m"]), m.H_m + c["H_m"]),
                                       polarization=(0, 0, MU0 * M), position=pos)
        B = np.atleast_2d(magnet.getB((0.0, 0.0, 0.0)))
        assert np.all(np.abs(gain * B[:, 0] + off[0]) <= a.chip.range_x)
        assert np.all(np.abs(gain * B[:, 2] + off[1]) <= a.chip.range_z), (theta, tt.max())
        checked += 1
    assert checked >= 3


def test_the_default_sensor_reads_the_required_loads_and_its_verdict_leads_the_card(
        result):
    B = assert_reads_required_loads(result)
    a = result.chosen
    assert np.abs(B[1]).max() > 0.5 * a.chip.range_z  # it uses its range
    rows = magtact.card(result)["rows"]
    req = [r.statement for r in a.verdict.requirements]
    assert [r[0] for r in rows[:len(req)]] == req
    assert req[0] == "reads 0–5 N normal without saturating"
    assert a.verdict["normal"].met
    assert rows[0][1].startswith("yes, saturates at" if np.isfinite(a.verdict.F_saturation)
                                 else "yes, never saturates")
    # the shear requirement at the loads where it occurs within the normal range: this body
    # carries 0.25 N of shear stably only beyond 5 N normal, and the verdict says so
    assert_shear_line_holds_on_the_chip(result)
    assert_worst_corner_reads(result)
    # the original MagOne design fails the range requirement, and the card says so
    o = result.original.verdict
    assert not o["normal"].met and o["normal"].margin < 0
    assert rows[0][2].startswith("no: the chip saturates at")
    # the parts: a catalogue grade, a standoff in its levels, a setting fast enough
    s = result.sensor_design.choice
    assert s.grade in result.study.design.grades and a.parts.grade == s.grade
    assert a.sensor.M_z == pytest.approx(
        magtact.parts.grade(s.grade).M_z(MU0)[0], rel=1e-12)
    assert 0 <= s.standoff <= 3e-3 + 1e-12 and a.standoff == s.standoff
    assert a.chip.figures.rate >= 100 and s.feasible
    # the design's noise over the required loads is the sensor problem's objective
    assert a.verdict.sigma_r == pytest.approx(s.sigma_r, rel=0.05)
    assert a.verdict.sigma_z == pytest.approx(s.sigma_z, rel=0.05)


def test_a_light_specification_gets_its_rate_and_range(result):
    study = _study(requirements={"F_z_N": 2.0, "rate_Hz": 100.0})
    r = magtact.design(study, models=prefitted_dir())
    a = r.chosen
    assert a.chip.figures.rate >= 100 and a.verdict["normal"].met
    assert a.design.F_z_max >= 2.0 and a.verdict["normal"].margin > 0
    assert_reads_required_loads(r)
    assert_shear_line_holds_on_the_chip(r)
    assert_worst_corner_reads(r)
    # a lighter specification buys a lower noise than the 5 N one
    assert r.sensor_design.choice.sigma < result.sensor_design.choice.sigma


def test_an_impossible_specification_names_the_requirement_and_the_best_reached():
    with pytest.raises(magtact.MagtactError,
                       match=r"requirements\.F_z_N = 50 N.*Best reachable: .*F_z,max = "):
        magtact.design(_study(requirements={"F_z_N": 50.0}), models=prefitted_dir())
    with pytest.raises(StudyError, match=r"\[requirements\.rate_Hz\] 2000 Hz is above"):
        load_study_with(requirements={"rate_Hz": 2000.0})


def load_study_with(**sections):
    return magtact.load("magone", **sections)


def test_a_force_constraint_that_would_not_take_effect_is_refused():
    with pytest.raises(StudyError, match=r"\[constraints\.F_z_c_N\] 4 N would not take effect.*"
                                         r"requirements\.F_z_N"):
        magtact.load("magone", constraints={"F_z_c_N": 4.0})
    s = magtact.load("magone", constraints={"F_z_c_N": 4.0, "source": "values"})
    assert s.constraints.F_z_c == 4.0
    s = magtact.load("magone", requirements={"F_z_N": 3.0, "F_r_N": 0.1})
    assert (s.constraints.F_z_c, s.constraints.F_r_c) == (3.0, -0.1)


def test_evaluate_reports_each_requirement_with_its_margin(result):
    # a taller, stiffer body: shear turns unstable below 0.25 N
    a = result.evaluate(H_mm=4.11, G_kPa=29.4)
    assert not a.verdict["shear"].met and a.verdict["shear"].margin < 0
    assert a.verdict["shear"].margin == pytest.approx(
        min(-a.design.F_r_min, a.verdict.shear_read) - 0.25, rel=1e-12)
    # the answer names what limits the shear: the body's stability first, then the loads
    # within the normal force, then the chip's reading
    answer = a.verdict["shear"].answer
    if -a.design.F_r_min < 0.25:
        assert answer.startswith("no: shear turns unstable at")
    else:
        assert answer.startswith(("no: the body carries at most", "no: reads shear up to"))
    # the original design: the chip saturates long before 5 N
    o = result.evaluate(H_mm=3.0, G_kPa=29.4, standoff_mm=0.0)
    assert not o.verdict["normal"].met and o.verdict.F_saturation < 2.0
    assert f"saturates at {o.verdict.F_saturation:.3g} N" in o.verdict["normal"].answer
    # a weaker magnet farther away reads more of the load
    far = result.evaluate(H_mm=3.0, G_kPa=29.4, grade="N35", standoff_mm=2.5)
    assert far.verdict.F_saturation > o.verdict.F_saturation
    assert far.parts.grade == "N35" and far.standoff == pytest.approx(2.5e-3)
    with pytest.raises(magtact.MagtactError, match="grade"):
        result.evaluate(H_mm=3.0, G_kPa=29.4, grade="N99")


def test_a_design_on_the_constraint_boundary_meets_it(result):
    """G chosen where F_z,max just reaches the required force: met to G's precision, not
    below it by a round-off (which would print "no: the body carries 5 N stably")."""
    from magtact.designer import verdict

    a = result.chosen
    study = result.study
    place = {"M_z": a.sensor.M_z, "standoff": a.sensor.standoff}
    req = study.requirements
    chip = a.chip
    class At:  # the chosen design with one force replaced
        def __init__(self, **forces):
            self.forces = forces

        def __getattr__(self, name):
            return self.forces[name] if name in self.forces else getattr(a.design, name)

    for F_z_max, met in ((req.F_z * (1 - 1e-8), True), (req.F_z * (1 - 1e-3), False)):
        v = verdict(result.models, study, At(F_z_max=F_z_max), chip, **place)
        assert v["normal"].met is met, v["normal"].text
    for F_r_min, stable in ((-req.F_r * (1 - 1e-8), True), (-req.F_r * (1 - 1e-3), False)):
        v = verdict(result.models, study, At(F_r_min=F_r_min), chip, **place)
        assert ("turns unstable" not in v["shear"].answer) is stable, v["shear"].text


def test_nsga2_meets_the_exact_reduction_and_is_seeded():
    from magtact.optimise import (
        WARN_GAP_SENSOR,
        exact_sensor_reduction,
        sensor_nsga2,
        sensor_space,
        sweep,
    )

    study = _study(design={"grades": ["N35", "N42", "N52"], "standoff_mm": [0.0, 1.5]})
    models = magtact.models_for(study, models=prefitted_dir())[0]
    space = sensor_space(models, study, sweep(models, study))
    red, combos = exact_sensor_reduction(models, study, space)
    assert combos == 16 * 3 * len(space.options) * len(space.silicones) and red.feasible
    first = sensor_nsga2(models, study, space)
    best = np.hypot(first.sigma_r, first.sigma_z).min()
    assert abs(best - red.sigma) / red.sigma <= WARN_GAP_SENSOR
    again = sensor_nsga2(models, study, space)
    for name in ("H", "G", "standoff", "grade", "option", "sigma_r", "sigma_z"):
        np.testing.assert_array_equal(getattr(first, name), getattr(again, name))


def test_the_reduction_is_exact_in_G_on_its_grid():
    """On a grid of one height, the least σ over G from the breakpoints equals a brute-force
    scan of G; G_range is the smallest G whose required loads avoid every saturated point."""
    from magtact.optimise._sensor import _Noise, _Within

    rng = np.random.default_rng(1)
    shape = (1, 6, 3)
    f_z = np.sort(rng.uniform(0, 1e-4, shape), axis=1)
    f_z[:, 0] = 0.0
    b = np.linspace(0.01, 0.06, 6)[None, :, None] * np.ones(shape) / 1e6  # per unit M_z
    j = rng.uniform(1, 3, shape + (2, 2))
    grid = SensorGrid(np.zeros(shape), np.zeros(shape), -f_z, f_z, 0.2 * b, b, j)
    M_z, F_z = 1e6, 2.0
    G_range = float(grid.G_range(M_z, 1.0, 0.035, F_z)[0])
    sat = M_z * b > 0.035
    before = np.concatenate([np.zeros((1, 1, 3)), f_z[:, :-1]], axis=1)
    assert G_range == pytest.approx(1.02 * (F_z / before[sat]).max(), rel=1e-12)
    G_low = np.array([G_range])
    value, G_best = _Noise(_Within(grid), (1e-6, 2e-6)).least(M_z, G_low, 1e6, F_z)
    scan = np.geomspace(G_range, 1e6, 200_001)
    s_r, s_z = grid.sigma(scan, np.full(scan.size, M_z), np.full(scan.size, 1e-6),
                          np.full(scan.size, 2e-6), F_z)
    brute = np.hypot(s_r, s_z).min()
    assert value[0] <= brute * (1 + 1e-6) and value[0] >= brute * (1 - 1e-3)
    s_r, s_z = grid.sigma(G_best, [M_z], [1e-6], [2e-6], F_z)
    assert np.hypot(s_r, s_z)[0] == pytest.approx(value[0], rel=1e-9)
    # with a shear the loads within F_z must include: the same scan, kept where they do
    within = scan[:, None] * f_z.reshape(1, -1) <= F_z
    shear = scan * np.where(within, f_z.reshape(1, -1), 0.0).max(axis=1)  # |f_r| = f_z here
    sigma = np.hypot(*grid.sigma(scan, np.full(scan.size, M_z), np.full(scan.size, 1e-6),
                                 np.full(scan.size, 2e-6), F_z))
    noise = _Noise(_Within(grid), (1e-6, 2e-6))
    for F_r in (0.5 * shear.max(), 0.9 * shear.max()):
        value, G_best = noise.least(M_z, G_low, 1e6, F_z, F_r)
        brute = sigma[shear >= F_r].min()
        assert value[0] <= brute * (1 + 1e-6) and value[0] >= brute * (1 - 1e-3)
        assert G_best[0] * f_z[0][f_z[0] * G_best[0] <= F_z].max() >= F_r * (1 - 1e-12)
    value, _ = noise.least(M_z, G_low, 1e6, F_z, 1.01 * shear.max())
    assert np.isinf(value[0])  # no G's loads include that shear
    # the largest shear the loads include over G (what the relaxation of a specification asks)
    most, G_most = _Within(grid).most_shear(G_low, 1e6, F_z)
    assert shear.max() <= most[0] * (1 + 1e-12) and most[0] <= shear.max() * (1 + 1e-3)
    assert G_most[0] * f_z[0][f_z[0] * G_most[0] <= F_z].max() == pytest.approx(most[0],
                                                                                rel=1e-12)


def test_the_publication_preset_keeps_the_publications_problem():
    p = load_study("magone-publication")
    assert p.optimise.problem == "publication" and p.optimise.objective == "gamma"
    assert not p.constraints.chip_range and p.design.grades == () and p.design.standoff[1] == 0
    assert load_study("magone-printed").optimise.problem == "publication"
    s = load_study("magone")
    assert s.optimise.problem == "sensor" and s.requirements.F_z == 5.0


def test_a_standoff_with_fitted_field_models_is_refused_in_the_publications_problem():
    with pytest.raises(StudyError, match=r"\[hall\.standoff_mm\] .*b_model = 'exact'"):
        magtact.load("magone-publication", hall={"standoff_mm": 1.0})
    s = magtact.load("magone-publication", hall={"standoff_mm": 1.0},
                     metamodel={"b_model": "exact"})
    assert s.hall.standoff == pytest.approx(1e-3)
    assert magtact.load("magone", hall={"standoff_mm": 1.0}).hall.standoff == pytest.approx(1e-3)


def test_a_chip_without_a_noise_figure_is_refused_before_the_work(monkeypatch):
    from magtact import _front

    def no_work(*args, **kwargs):
        raise AssertionError("the optimisation ran")

    monkeypatch.setattr("magtact.optimise.optimise", no_work)
    study = magtact.load("magone", hall={"chip": "TLE493D"})
    with pytest.raises(StudyError, match=r"\[hall\.noise_x_uT\] the sensor problem needs"):
        _front.solve(magtact.models_for(study, models=prefitted_dir())[0], study)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.sampled_from([3e-3, 3.5e-3, 4e-3]), st.integers(0, 2),
                          st.integers(0, 1)), min_size=1, max_size=25),
       st.lists(st.tuples(st.sampled_from([3e-3, 4e-3]), st.integers(0, 2), st.integers(0, 1)),
                max_size=8))
def test_the_hashed_duplicate_elimination_marks_what_pymoos_pairwise_one_marks(designs, others):
    from pymoo.core.mixed import MixedVariableDuplicateElimination
    from pymoo.core.population import Population

    from magtact.optimise._sensor import same_designs

    def population(rows):
        return Population.new(X=np.array([{"H": h, "standoff": s, "grade": g}
                                          for h, s, g in rows], dtype=object))

    pop, other = population(designs), population(others)
    for args in ((None,), (other,)):
        if args[0] is not None and len(others) == 0:
            continue
        want = MixedVariableDuplicateElimination()._do(pop, *args, np.full(len(pop), False))
        got = same_designs()._do(pop, *args, np.full(len(pop), False))
        np.testing.assert_array_equal(got, want)
