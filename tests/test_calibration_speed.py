"""What keeps ``magtact calibrate`` quick: the calibration figure's frontier panel labelled in
plain text and without a comb of minor ticks, and the figure drawn by a second process
(``FigureProcess``) that the command starts before its design, with the same files as one
drawn in the command's own process; the firmware sweep's shared work (the basis built at once,
the two-stage candidates' samples and force fits shared, the tables' Newton in the mirror plane
in two features, the table's rows inverted once for the file and the builds, the builds
compiled at once), each giving what the work done apart gives; the command's exit left to the
system."""

from __future__ import annotations

import atexit
import csv
import gc
import pickle
import shutil
import sys
from dataclasses import dataclass, fields, replace
from types import SimpleNamespace

import numpy as np
import pytest
from matplotlib.figure import Figure
from numpy.polynomial.chebyshev import chebvander
from PIL import Image

from magtact.calibration import SensorMap, sensor_map
from magtact.calibration._firmware import (
    BUILDS,
    _basis,
    _FeatureSamples,
    _samples,
    basis_terms,
    c_source,
    fit_features,
    fit_poly,
    fit_table,
    region_polygon,
    run_header,
    run_headers,
    table_readings,
    write_table_csv,
)
from magtact.calibration._map import _newton_step
from magtact.cli._calibrate import FigureProcess, freeze_at_exit
from magtact.optimise import per_design
from magtact.report import MINOR_TICK_DECADES, calibration_figures, draw_calibration
from magtact.study import load_study

SUPERSCRIPT = str.maketrans("⁰¹²³⁴⁵⁶⁷⁸⁹⁻", "0123456789-")


# a calibration as the figure reads it, small and picklable (the figure's process gets it so)
@dataclass(frozen=True)
class Point:
    kind: str
    bytes: int
    error_over_sigma: float
    on_frontier: bool


@dataclass(frozen=True)
class Chosen:
    kind: str
    bytes: int
    err_r: float
    err_z: float


@dataclass(frozen=True)
class Firmware:
    chosen: Chosen
    points: tuple
    reached: bool

    def frontier_points(self) -> list:
        return list(self.points)


@dataclass(frozen=True)
class Cal:
    grid: dict
    firmware: Firmware
    sigma_F: tuple
    noise: tuple
    map: SimpleNamespace


def stand_in(decades: int = 9, lowest: int = -6) -> Cal:
    """Errors over σ_F from 10^lowest up ``decades`` decades, sizes over about three decades."""
    t, theta = np.meshgrid(np.linspace(0.0, 1.0, 9), np.linspace(0.0, 0.42, 9), indexing="ij")
    errors = np.logspace(lowest, lowest + decades, 12)
    sizes = np.geomspace(300, 5e5, 12).round().astype(int)
    kinds = ("features", "poly", "table")
    points = tuple(Point(kinds[k % 3], int(b), float(e), k % 2 == 0)
                   for k, (b, e) in enumerate(zip(sizes, errors[::-1], strict=True)))
    chosen = Chosen("features", 580, 0.46e-3, 0.75e-3)
    return Cal({"t": t, "theta": theta, "err_r": t * theta * 1e-3, "err_z": (t + theta) * 1e-3},
               Firmware(chosen, points, True), (0.48e-3, 1.48e-3), (2.25e-6, 3.45e-6),
               SimpleNamespace(H=3.08e-3, G=34.2e3))


def drawn(cal: Cal) -> list:
    fig = Figure(figsize=(10.0, 3.4))
    axes = draw_calibration(fig, cal)
    fig.draw_without_rendering()  # ticks and their labels as the files show them
    return axes


def power_of_ten(label: str) -> float:
    """The value of a plain-text label ``10⁻⁶`` or ``2×10³``."""
    coefficient, _, power = label.replace("\N{MINUS SIGN}", "-").rpartition("10")
    return float(coefficient.rstrip("×") or 1) * 10.0 ** int(power.translate(SUPERSCRIPT))


# ---- the frontier panel ----------------------------------------------------------------------
def test_the_frontier_panel_shows_every_candidate_and_the_chosen_one():
    cal = stand_in()
    ax = drawn(cal)[2]
    shown = {(float(x), float(y)) for ln in ax.lines[:-2]
             for x, y in zip(ln.get_xdata(), ln.get_ydata(), strict=True)}
    assert shown == {(p.bytes, p.error_over_sigma) for p in cal.firmware.points}
    star = ax.lines[-2]
    a = cal.firmware.chosen
    assert star.get_label() == "chosen" and list(star.get_xdata()) == [a.bytes]
    assert star.get_ydata()[0] == pytest.approx(max(a.err_r / cal.sigma_F[0],
                                                    a.err_z / cal.sigma_F[1]))
    assert list(ax.lines[-1].get_ydata()) == [1.0, 1.0]  # the target
    assert [t.get_text() for t in ax.get_legend().get_texts()] == [
        "features (frontier)", "features", "poly (frontier)", "poly", "table (frontier)",
        "table", "chosen"]


@pytest.mark.parametrize("axis", ["x", "y"])
def test_log_labels_are_plain_text_at_their_powers_of_ten(axis):
    ax = drawn(stand_in())[2]
    ticks = getattr(ax, f"get_{axis}ticklabels")()
    labelled = [(t.get_position()[axis == "y"], t.get_text()) for t in ticks if t.get_text()]
    lo, hi = getattr(ax, f"get_{axis}lim")()
    inside = [(v, s) for v, s in labelled if lo <= v <= hi]
    assert len(inside) >= 3
    for value, text in inside:
        assert "$" not in text  # no mathtext to parse at each draw
        assert power_of_ten(text) == pytest.approx(value)


def test_minor_ticks_only_on_a_log_axis_of_few_decades():
    ax = drawn(stand_in(decades=9))[2]
    assert np.log10(np.divide(*ax.get_ylim()[::-1])) > MINOR_TICK_DECADES
    assert len(ax.yaxis.get_minorticklocs()) == 0
    assert np.log10(np.divide(*ax.get_xlim()[::-1])) < MINOR_TICK_DECADES
    assert len(ax.xaxis.get_minorticklocs()) > 10
    narrow = drawn(stand_in(decades=3, lowest=-2))[2]
    assert len(narrow.yaxis.get_minorticklocs()) > 10


def test_the_figure_pickles_for_a_background_writer():
    fig = Figure(figsize=(10.0, 3.4))
    draw_calibration(fig, stand_in())
    back = pickle.loads(pickle.dumps(fig))
    ax = back.axes[2]
    assert ax.yaxis.get_major_formatter()(1e-3) == "10⁻³"
    assert ax.xaxis.get_minor_formatter()(2e3) in ("", "2×10³")


# ---- the figure's process --------------------------------------------------------------------
def pixels(path) -> np.ndarray:
    return np.asarray(Image.open(path))


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="a process by fork")
def test_the_figure_process_writes_the_figure_of_the_command_process(tmp_path):
    cal = stand_in()
    here = calibration_figures(cal, tmp_path / "here")
    with FigureProcess() as figure:
        assert figure._proc.is_alive()
        (tmp_path / "there").mkdir()
        figure.draw(cal, tmp_path / "there")
        figure.wait()
        assert (tmp_path / "there" / "calibration.svg").stat().st_size > 0
    assert figure._proc is None
    np.testing.assert_array_equal(pixels(tmp_path / "there" / "calibration.png"),
                                  pixels(here[0]))


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="a process by fork")
def test_a_failed_figure_names_why(tmp_path):
    (tmp_path / "file").write_text("a file where the figure's folder would be")
    with FigureProcess() as figure:
        figure.draw(stand_in(), tmp_path / "file" / "sub")
        with pytest.raises(RuntimeError, match="calibration figure not written: "):
            figure.wait()


def test_a_calibration_that_does_not_pickle_is_drawn_here(tmp_path):
    cal = stand_in()
    unpicklable = SimpleNamespace(**vars(cal) | {"firmware": SimpleNamespace(
        chosen=cal.firmware.chosen, reached=True,
        frontier_points=lambda: list(cal.firmware.points))})
    with FigureProcess() as figure:
        figure.draw(unpicklable, tmp_path)
        figure.wait()
    np.testing.assert_array_equal(pixels(tmp_path / "calibration.png"),
                                  pixels(calibration_figures(cal, tmp_path / "ref")[0]))


def test_a_command_that_stops_before_its_figure_ends_the_process():
    with pytest.raises(KeyError), FigureProcess() as figure:
        proc = figure._proc
        raise KeyError("the design failed")
    if proc is not None:
        assert not proc.is_alive()


# ---- the firmware sweep's shared work --------------------------------------------------------
@pytest.fixture(scope="module")
def smap(models):
    study = load_study(None)
    H, G = 3e-3, 22.57e3
    return sensor_map(models, study, H, G, design=per_design(models, H, G, study))


def test_the_basis_is_the_products_of_the_polynomials_in_c_order():
    xi, eta = np.random.default_rng(1).uniform(-1.0, 1.0, (2, 40, 3))
    Tx, Ty = chebvander(xi, 6), chebvander(eta, 6)
    A = _basis(xi, eta, 6)
    np.testing.assert_array_equal(
        A, np.stack([Tx[..., i] * Ty[..., j] for i, j in basis_terms(6)], axis=-1))
    assert A.flags.c_contiguous  # the layout its products with the coefficients are made in


def test_candidates_from_shared_samples_are_those_fitted_alone(smap):
    samples = _FeatureSamples(smap, 0)
    for degree, transform in ((4, "B_z"), (6, "1/B_z"), (6, "B_z^(-1/3)")):
        shared = fit_features(smap, degree, transform, 0, samples)
        alone = fit_features(smap, degree, transform, 0)
        assert shared.limits == alone.limits
        for a, b in ((shared.coef_r, alone.coef_r), (shared.coef_z, alone.coef_z),
                     *((getattr(shared.stage, f.name), getattr(alone.stage, f.name))
                       for f in fields(alone.stage))):
            np.testing.assert_array_equal(a, b)
    assert sorted(samples._force_fits) == [4, 6]  # one force fit per degree


def test_forces_are_those_of_the_evaluation(smap):
    polygon = region_polygon(smap)
    B, _ = _samples(smap, 300, 7)
    for a in (fit_features(smap, 6, "B_z", 0),
              fit_poly(smap, 6, "1/B_z", _samples(smap, 400, 1), polygon),
              fit_table(smap, 16, polygon)):
        F, inside = a.evaluate(B)
        np.testing.assert_array_equal(a.forces(B), F)
        assert inside.any()


def test_the_newton_step_in_the_mirror_plane_is_the_full_step(smap):
    # features and readings with q_y = 0 and b_y = 0 (a table's nodes): the 2 x 2 system's
    # step is the 3 x 3 system's, whose q_y step vanishes
    t = np.linspace(0.1, 0.9, 12)
    w = smap.features(t, 0.2)
    target, _ = smap.at_load(t * 1.03, 0.22)
    res = smap.B_of(w) - target
    assert not res[:, 1].any()
    full = _newton_step(smap.B_of, w, res, planar=False)
    plane = _newton_step(smap.B_of, w, res, planar=True)
    assert not plane[:, 2].any() and np.abs(full[:, 2]).max() <= 1e-15
    np.testing.assert_allclose(plane[:, :2], full[:, :2], rtol=1e-12, atol=0.0)
    # the inversion of such readings lands in the plane, on the loads they come from
    r = smap.force(target)
    assert not r.phi.any()
    np.testing.assert_allclose(r.t, t * 1.03, atol=1e-9)


def test_the_table_rows_are_inverted_once_for_the_file_and_the_builds(smap, tmp_path,
                                                                      monkeypatch):
    fresh = replace(smap)  # a map without rows kept
    inverted = []
    force = SensorMap.force
    monkeypatch.setattr(SensorMap, "force",
                        lambda self, B: inverted.append(np.shape(B)) or force(self, B))
    write_table_csv(fresh, tmp_path / "table.csv", n=16)
    B, F = table_readings(fresh, n=16)
    assert inverted == [(16, 16, 3)]
    with (tmp_path / "table.csv").open() as fh:
        rows = [r for r in csv.DictReader(fh) if r["inside"] == "1"]
    assert len(rows) == len(B) > 0
    np.testing.assert_array_equal(F[:, 0], [float(r["F_r_N"]) for r in rows])


@pytest.mark.skipif(shutil.which("cc") is None and shutil.which("gcc") is None,
                    reason="no C compiler on this machine")
def test_builds_compiled_at_once_read_as_each_alone(smap):
    a = fit_features(smap, 6, "B_z", 0)
    header = c_source(a, smap)
    B, _ = table_readings(smap, n=16)
    together = run_headers(header, B, [(real, acc) for _, real, acc in BUILDS])
    assert len(together) == len(BUILDS)
    for (_, real, acc), (rc, out) in zip(BUILDS, together, strict=True):
        alone = run_header(header, B, real, acc)
        np.testing.assert_array_equal(rc, alone[0])
        np.testing.assert_array_equal(out, alone[1])
    assert not np.array_equal(together[0][1], together[-1][1])  # double and float differ


@pytest.mark.skipif(shutil.which("cc") is None and shutil.which("gcc") is None,
                    reason="no C compiler on this machine")
def test_a_build_that_does_not_compile_says_so(smap):
    import subprocess

    header = c_source(fit_features(smap, 4, "B_z", 0), smap) + "\nnot C;\n"
    with pytest.raises(subprocess.CalledProcessError):
        run_headers(header, np.zeros((1, 3)), [(real, acc) for _, real, acc in BUILDS])


def test_the_exit_is_left_to_the_system_once(monkeypatch):
    registered = []
    monkeypatch.setattr(atexit, "register", registered.append)
    freeze_at_exit.cache_clear()
    try:
        freeze_at_exit()
        freeze_at_exit()
    finally:
        freeze_at_exit.cache_clear()
    assert registered == [gc.freeze]
