"""Validation against repeat indentation tests (docs/method.md §8).

Read tests from CSV (:func:`read_experiment`; the format is documented in ``_io``), compare them
with a :class:`PathModel` (metamodels, direct simulation, samples or any function) by
:func:`validate`, which filters, resamples and returns c_v and ε per response.
"""

from ._filter import FilterSettings, bandpass
from ._io import (
    RESPONSES,
    Curve,
    DataError,
    Experiment,
    read_cell,
    read_experiment,
    read_row,
    read_table_lines,
)
from ._model import PathModel
from ._outputs import output_stem, write_outputs
from ._stats import MAX_GRID, N_GRID, ResponseStats, Validation, excluded_ranges, validate
from ._synthetic import SYNTHETIC_H, synthetic_files

__all__ = [
    "DataError", "Experiment", "FilterSettings", "PathModel", "Validation", "read_experiment",
    "validate", "write_outputs",
]
