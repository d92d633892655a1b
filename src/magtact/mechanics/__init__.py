"""Structural mechanics of the sensor body: FElupe half model, loading paths, reaction forces."""

#: Version of the structural model as the DOE cache keys see it. Bump it when a change makes a
#: path give other forces: the mesh, the material law, the contact, the geometry of the body or
#: magnet (magtact.geometry), tolerances or load stepping. Comments, refactoring and speed-ups
#: that give the same forces leave it alone, so cached paths stay valid.
MODEL_VERSION = 2

from ._model import SOLVERS, HalfBodyModel, Stepping  # noqa: E402
from ._result import PathFailed, PathResult  # noqa: E402
from ._simulate import build_model, simulate_path  # noqa: E402
from ._vtu import write_vtu  # noqa: E402

__all__ = [
    "MODEL_VERSION", "HalfBodyModel", "PathFailed", "PathResult", "build_model", "simulate_path",
]
