"""The silicone's relaxation in time: hysteresis, creep and the error against the press rate of
a design, from a Prony series and the metamodels' elastic forces (docs/method.md §15)."""

from ._design import (
    SiliconeSweep,
    TimePress,
    TimeRecord,
    TimeResponse,
    design_forces,
    implied_ratio,
    relaxation_of,
    time_json,
    time_response,
    unknown_time_json,
)
from ._prony import Prony, held_force, hereditary_force
from ._sensor import (
    CALIBRATIONS,
    MEASURED_HYSTERESIS,
    MEASURED_SOURCE,
    Creep,
    Loop,
    RateSweep,
    calibration_modulus,
    press_and_hold,
    press_cycle,
    press_times_around,
    rate_sweep,
)

__all__ = [
    "CALIBRATIONS", "MEASURED_HYSTERESIS", "MEASURED_SOURCE", "Creep", "Loop", "Prony",
    "RateSweep", "SiliconeSweep", "TimePress", "TimeRecord", "TimeResponse",
    "calibration_modulus", "design_forces", "held_force", "hereditary_force", "implied_ratio",
    "press_and_hold", "press_cycle", "press_times_around", "rate_sweep", "relaxation_of",
    "time_json", "time_response", "unknown_time_json",
]
