"""The sensor's own product: its field-to-force map, the firmware export and the calibration of a
built unit from a few presses (docs/method.md §12)."""

from ._map import (
    FLAG_NAMES,
    NO_INVERSE,
    NOT_UNIQUE,
    OK,
    OUTSIDE,
    Reading,
    SensorMap,
    UnitParameters,
    sensor_map,
)

__all__ = ["FLAG_NAMES", "NO_INVERSE", "NOT_UNIQUE", "OK", "OUTSIDE", "Reading", "SensorMap",
           "UnitParameters", "sensor_map"]
