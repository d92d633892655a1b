"""Magnetic field of the magnet: exact closed form, axisymmetric FE, field at the Hall point."""

from ._exact import cel, cylinder_field
from ._fe import FieldSolution, solve_fe, solve_field
from ._hall import SOLVERS, hall_field

__all__ = ["SOLVERS", "FieldSolution", "cel", "cylinder_field", "hall_field", "solve_fe",
           "solve_field"]
