"""The designer's answer: force resolution with a named Hall chip, measuring range, the chip's
limits, and the margin for the fabrication tolerance of G (docs/method.md §10)."""

from ..chip import (
    Saturation,
    SettingChoice,
    check_rest_field,
    saturation,
    setting_for,
    with_setting,
)
from ..optimise import best_setting
from ..study import HALL_PRESETS, HallChip, HallPreset, hall_chip
from ._answer import (
    DesignAnswer,
    Parts,
    Resolution,
    answer,
    answer_json,
    parts_of,
    resolution,
)
from ._infeasible import (
    Infeasible,
    InfeasibleSpecification,
    Relaxation,
    infeasibility,
)
from ._verdict import N_FINE, Requirement, Verdict, verdict

__all__ = ["HALL_PRESETS", "N_FINE", "DesignAnswer", "HallChip", "HallPreset", "Infeasible",
           "InfeasibleSpecification", "Parts", "Relaxation", "Requirement", "Resolution",
           "Saturation", "SettingChoice", "Verdict", "answer", "answer_json", "best_setting",
           "check_rest_field", "hall_chip", "infeasibility", "parts_of", "resolution",
           "saturation", "setting_for", "verdict", "with_setting"]
