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
    MEASURED_HYSTERESIS,
    Creep,
    Loop,
    RateSweep,
    press_and_hold,
    press_cycle,
    rate_sweep,
)

__all__ = [
    "Creep", "Loop", "Prony", "RateSweep", "TimeResponse", "hereditary_force", "press_and_hold",
    "press_cycle", "rate_sweep", "relaxation_of", "time_response",
]
