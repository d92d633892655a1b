"""Closed-form metamodels of the study's responses by genetic programming (SPEC section 5)."""

from ._model import RESPONSES, Metamodel, ModelSet
from ._symbols import H, p, q, t, theta

__all__ = ["RESPONSES", "H", "Metamodel", "ModelSet", "p", "q", "t", "theta"]
