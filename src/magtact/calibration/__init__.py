"""The sensor's own product: its field-to-force map, the firmware export and the calibration of a
built unit from a few presses (docs/method.md §13)."""

from ._fe import FEForces, PathHoldout, fe_forces, has_height, path_holdout
from ._firmware import (
    Approximation,
    FirmwareChoice,
    FrontierPoint,
    approximation_json,
    c_header,
    firmware_approximation,
    load_approximation,
    region_polygon,
    write_table_csv,
)
from ._map import (
    FLAG_NAMES,
    FORCE_SOURCES,
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
    SUMMARY_FORMAT,
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
    TOLERANCE,
    Presses,
    UnitCalibration,
    calibrate_unit,
    fe_readings,
    read_presses,
    write_presses,
)

__all__ = [
    "DEFAULT_FIT", "FLAG_NAMES", "FORCE_SOURCES", "FEForces", "PathHoldout", "fe_forces",
    "force_model_error", "force_source_for", "has_height", "path_holdout", "NOT_UNIQUE",
    "NO_INVERSE", "OK", "OUTSIDE", "PARAMETERS",
    "PRESS_COLUMNS", "SUMMARY_FORMAT", "TOLERANCE", "Approximation", "Calibration",
    "CalibrationSummary", "FirmwareChoice", "ForceError", "FrontierPoint", "Presses",
    "Reading", "SensorMap", "UnitCalibration", "UnitParameters", "approximation_json",
    "c_header", "calibrate", "calibrate_unit", "error_grid", "fe_readings",
    "firmware_approximation", "load_approximation", "read_presses", "region_polygon",
    "round_trip_error", "sensor_map", "write_calibration_outputs", "write_presses",
    "write_table_csv",
]
