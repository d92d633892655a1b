"""Magnetic field of the magnet: exact closed form, axisymmetric FE, field at the Hall point."""

from ._exact import cel, cylinder_field
from ._fe import FieldSolution, solve_fe, solve_field
from ._hall import SOLVERS, hall_field, magnet_field
from ._outputs import CSV_COLUMNS, field_grid, write_field_csv, write_field_outputs

__all__ = [
    "CSV_COLUMNS", "SOLVERS", "FieldSolution", "cel", "cylinder_field", "field_grid", "hall_field",
    "magnet_field", "solve_fe", "solve_field", "write_field_csv", "write_field_outputs",
]
