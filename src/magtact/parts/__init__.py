"""Parts a designer can buy: Hall chips and their settings, NdFeB magnets, silicones
(docs/method.md §10). Every figure is data in ``magtact/parts/data`` with its source."""

from ._catalogue import (
    GRADES,
    SILICONES,
    SIZES,
    Grade,
    Relaxation,
    Silicone,
    Size,
    grade,
    silicones_around,
    size,
)
from ._chips import (
    MLX_FIELDS,
    PERMITTED_PAIR,
    ChipPart,
    ChipSetting,
    ChipTable,
    SettingError,
    SettingFigures,
    chip_part,
    chip_table,
)

__all__ = [
    "GRADES", "SILICONES", "SIZES", "ChipPart", "ChipSetting", "ChipTable", "Grade", "Silicone",
    "Size", "chip_part", "chip_table", "grade", "size",
]
