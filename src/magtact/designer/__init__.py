"""The designer's answer: force resolution with a named Hall chip, measuring range, the chip's
limits, and the margin for the fabrication tolerance of G (docs/method.md §10)."""

from ..optimise import SettingChoice, best_setting, setting_for, with_setting
from ..study import HALL_PRESETS, HallChip, HallPreset, hall_chip
from ._answer import (
    DesignAnswer,
    Parts,
    Resolution,
    Saturation,
    answer,
    answer_json,
    check_rest_field,
    parts_of,
    resolution,
    saturation,
)
from ._verdict import N_FINE, Requirement, Verdict, verdict

__all__ = ["N_FINE", "Requirement", "Verdict", "verdict", "HALL_PRESETS", "DesignAnswer", "HallChip", "HallPreset", "Parts", "Resolution",
           "Saturation", "SettingChoice", "answer", "answer_json", "best_setting",
           "check_rest_field", "hall_chip", "parts_of", "resolution", "saturation",
           "setting_for", "with_setting"]
