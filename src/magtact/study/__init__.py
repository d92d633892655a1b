"""Study settings: typed, immutable, loaded from TOML in user units, SI inside."""

from ._hall import (
    HALL_PRESETS,
    HallChip,
    HallPreset,
    candidate_settings,
    hall_chip,
    setting_figures,
)
from ._load import (
    PRESETS,
    StudyError,
    load_study,
    magone,
    magone_printed,
    study_from_dict,
)
from ._model import (
    ARRAY_LAYOUTS,
    DOE,
    MESH_DENSITIES,
    Array,
    Body,
    Constraints,
    Design,
    Environment,
    Loading,
    Magnet,
    Magnetics,
    Material,
    Mechanics,
    Requirements,
    Sensitivity,
    Study,
    Tolerances,
    holdout_limit,
)
from ._rules import ROOM_C, check_field_mesh, check_holdout, check_parts, check_study
from ._units import LABEL, MU0, PHYSICAL, check_si, checked_si, from_si, kpa, mm, mt, to_si

__all__ = [
    "PRESETS", "HallChip", "Study", "StudyError", "check_study", "checked_si", "from_si",
    "hall_chip", "load_study", "study_from_dict", "to_si",
]
