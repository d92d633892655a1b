"""What keeps ``magtact calibrate`` quick: the calibration figure's frontier panel labelled in
plain text and without a comb of minor ticks, and the figure drawn by a second process
(``FigureProcess``) that the command starts before its design, with the same files as one
drawn in the command's own process."""

from __future__ import annotations

import pickle
import sys
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np
import pytest
from matplotlib.figure import Figure
from PIL import Image

from magtact.cli._calibrate import FigureProcess
from magtact.report import MINOR_TICK_DECADES, calibration_figures, draw_calibration

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
