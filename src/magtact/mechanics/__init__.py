"""Structural mechanics of the sensor body: FElupe half model, loading paths, reaction forces."""

from ._model import HalfBodyModel, Stepping
from ._result import PathFailed, PathResult
from ._simulate import build_model, simulate_path
from ._vtu import write_vtu

__all__ = ["HalfBodyModel", "PathFailed", "PathResult", "Stepping", "build_model",
           "simulate_path", "write_vtu"]
