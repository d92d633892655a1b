"""The designer's answer: force resolution with a named Hall chip, measuring range, the chip's
limits, and the margin for the fabrication tolerance of G (docs/method.md §10)."""

from ..study import HALL_PRESETS, HallChip, HallPreset, hall_chip
from ._answer import (
    DesignAnswer,
    Resolution,
    Saturation,
    answer,
    answer_json,
    check_rest_field,
    resolution,
    saturation,
)

__all__ = ["HALL_PRESETS", "DesignAnswer", "HallChip", "HallPreset", "Resolution", "Saturation",
           "answer", "answer_json", "check_rest_field", "hall_chip", "resolution", "saturation"]
