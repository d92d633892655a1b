"""Deformed mesh output for ParaView (VTU via meshio)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..geometry import BodyMesh


def write_vtu(path: str | Path, bmesh: BodyMesh, displacement: np.ndarray) -> Path:
    """Write the deformed half mesh as VTU.

    Parameters
    ----------
    path : path
        Output file (``.vtu``); parent folders are created.
    bmesh : BodyMesh
        Undeformed mesh [m].
    displacement : (n_points, 3) ndarray
        Nodal displacement [m].

    Returns
    -------
    Path
        The written file. Point data: ``displacement`` [m] and ``displacement_magnitude`` [m];
        the points are the deformed positions [m].
    """
    import meshio

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    u = np.asarray(displacement, dtype=float)
    if u.shape != bmesh.points.shape:
        raise ValueError(f"displacement must have shape {bmesh.points.shape}, got {u.shape}")
    cell_type = {8: "hexahedron", 20: "hexahedron20", 27: "hexahedron27"}[bmesh.cells.shape[1]]
    meshio.Mesh(
        bmesh.points + u, [(cell_type, bmesh.cells)],
        point_data={"displacement": u, "displacement_magnitude": np.linalg.norm(u, axis=1)},
    ).write(path)
    return path
