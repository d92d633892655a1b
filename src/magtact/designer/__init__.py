"""The designer's answer: force resolution with a named Hall chip, measuring range, the chip's
limits, and the margin for the fabrication tolerance of G (docs/method.md §10)."""

from ..chip import (
    check_rest_field,
    setting_for,
)
from ..optimise import best_setting
from ..study import HALL_PRESETS, HallChip, hall_chip
from ._answer import (
    DesignAnswer,
    Parts,
    Resolution,
    answer,
    answer_json,
    resolution,
)
from ._infeasible import (
    Infeasible,
    InfeasibleSpecification,
    Relaxation,
    infeasibility,
)
from ._verdict import Requirement, Verdict, verdict

__all__ = [
    "DesignAnswer", "Infeasible", "InfeasibleSpecification", "Parts", "Resolution", "Verdict",
    "answer", "answer_json", "infeasibility", "verdict",
]
