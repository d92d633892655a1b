"""The Hall chip as part of a sensor design: the settings a design chooses from, what the chip
reads of a design over the loads it must read, where it leaves its range, and its force noise
(docs/method.md §10)."""

from ._options import ChipOption, chip_options
from ._reading import (
    N_T,
    N_THETA,
    SensorGrid,
    exact_field_models,
    sensor_grid,
    unit_magnet,
)

__all__ = ["N_T", "N_THETA", "ChipOption", "SensorGrid", "chip_options", "exact_field_models",
           "sensor_grid", "unit_magnet"]
