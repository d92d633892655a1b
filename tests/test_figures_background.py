"""Figures written by a worker process (``magtact.report.saved_in_background``): the files
exist and equal those written in the caller's process when the block ends, a failure names the
file, and a figure that cannot be pickled is written at once."""

from __future__ import annotations

import pytest
from matplotlib.ticker import FuncFormatter

from magtact.report import save, saved_in_background, style
from magtact.report._style import subplots


def _figure(pickles: bool = True):
    with style():
        fig, ax = subplots(1, 1, figsize=(3.0, 2.0))
        ax.plot([0, 1, 2], [0, 1, 4], label="x²")
        ax.set(xlabel="x", title="one")
        if not pickles:  # a lambda does not pickle
            ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    return fig


def test_a_figure_saved_in_the_background_equals_one_saved_at_once(tmp_path):
    here = save(_figure(), tmp_path / "here" / "a", formats=("png",))
    with saved_in_background() as saver:
        saver.tag = "stage"
        there = save(_figure(), tmp_path / "there" / "a", formats=("png",))
        assert saver.finish() == {}
    assert there[0].read_bytes() == here[0].read_bytes()


def test_a_figure_that_does_not_pickle_is_written_at_once(tmp_path):
    with saved_in_background():
        files = save(_figure(pickles=False), tmp_path / "b", formats=("png",))
        assert files[0].stat().st_size > 0  # before the block ends


def test_a_failed_figure_names_its_file_and_its_tag(tmp_path):
    (tmp_path / "c").write_text("a file where the figure would be a folder")
    with pytest.raises(RuntimeError, match=r"figures not written: d\.png: "):
        with saved_in_background() as saver:
            saver.tag = "field"
            target = tmp_path / "c" / "d"
            # the folder exists check happens here; make it pass, then fail in the worker
            saver.submit(_figure(), [target.with_suffix(".png")])
            failed = saver.finish()
            assert list(failed) == ["field"]
            saver.submit(_figure(), [target.with_suffix(".png")])
