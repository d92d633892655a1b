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
    CHIP_FILES,
    MLX_FIELDS,
    ChipSetting,
    ChipTable,
    SettingError,
    SettingFigures,
    chip_table,
    widest,
)

__all__ = ["CHIP_FILES", "GRADES", "MLX_FIELDS", "SILICONES", "SIZES", "ChipSetting",
           "ChipTable", "Grade", "Relaxation", "SettingError", "SettingFigures", "Silicone", "Size",
           "chip_table", "grade", "silicones_around", "size", "widest"]
