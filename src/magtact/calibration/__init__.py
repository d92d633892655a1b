"""The sensor's own product: its field-to-force map, the firmware export and the calibration of a
built unit from a few presses (docs/method.md §13)."""

from ._fe import FEForces, PathHoldout, fe_forces, path_holdout
from ._firmware import (
    Approximation,
    FirmwareChoice,
    FrontierPoint,
    c_header,
    firmware_approximation,
    load_approximation,
    write_table_csv,
)
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
from ._outputs import (
    Calibration,
    CalibrationSummary,
    ForceError,
    calibrate,
    error_grid,
    force_model_error,
    force_source_for,
    round_trip_error,
    write_calibration_outputs,
)
from ._unit import (
    DEFAULT_FIT,
    PARAMETERS,
    PRESS_COLUMNS,
    Presses,
    UnitCalibration,
    calibrate_unit,
    fe_readings,
    read_presses,
    write_presses,
)

__all__ = [
    "Approximation", "Calibration", "Presses", "SensorMap", "UnitCalibration", "calibrate",
    "calibrate_unit", "firmware_approximation", "load_approximation", "path_holdout",
    "read_presses", "sensor_map", "write_calibration_outputs",
]
