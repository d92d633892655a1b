"""Magnetic field of the magnet: exact closed form, axisymmetric FE, field at the Hall point."""

#: Version of the field model as the DOE cache keys see it. Bump it when a change makes the
#: field at the Hall point differ: the FE mesh or formulation, the exact kernel, the Hall point's
#: position (magtact.geometry). Comments, refactoring and speed-ups leave it alone.
MODEL_VERSION = 1

from ._exact import cel, cylinder_field, cylinder_field_dz  # noqa: E402
from ._fe import FieldSolution, solve_fe, solve_field  # noqa: E402
from ._hall import hall_field, magnet_field  # noqa: E402
from ._outputs import CSV_COLUMNS, write_field_outputs  # noqa: E402

__all__ = [
    "MODEL_VERSION", "FieldSolution", "cylinder_field", "hall_field", "solve_fe",
    "write_field_outputs",
]
