"""The Hall chip as part of a sensor design (docs/method.md §10): the settings a design
chooses from and the choice of one (:func:`setting_for`), the chip's range over a design's
stable region (:func:`chip_margin`), along its paths (:func:`saturation`) and at rest
(:func:`check_rest_field`), what it reads over the loads it must read and its force noise
there (:func:`sensor_grid`), and the check that its noise is known (:func:`require_noise`).
The chips' datasheet tables are :mod:`magtact.parts` data; the study's ``[hall]`` chip is
:func:`magtact.study.hall_chip`."""

from ._options import ChipOption, chip_options, require_noise
from ._range import (
    Saturation,
    check_rest_field,
    chip_margin,
    field_ratio,
    onset,
    saturation,
    saturation_force,
)
from ._reading import (
    SensorGrid,
    exact_field_models,
    sensor_grid,
)
from ._setting import SettingChoice, setting_for

__all__ = [
    "ChipOption", "Saturation", "SensorGrid", "SettingChoice", "chip_options", "onset",
    "saturation", "sensor_grid", "setting_for",
]
