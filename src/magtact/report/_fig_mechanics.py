"""Figures of the structural stage: the deformed sensor body coloured by displacement."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib import cm, colors
from matplotlib.figure import Figure
from matplotlib.tri import Triangulation

from ..study import mm
from ._style import CMAP_SEQ, colormap, save, style

_FACES = np.array([[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6],
                   [3, 0, 4, 7]])


def _boundary_faces(cells: np.ndarray) -> np.ndarray:
    faces = cells[:, _FACES].reshape(-1, 4)
    _, inverse, counts = np.unique(np.sort(faces, axis=1), axis=0, return_inverse=True,
                                   return_counts=True)
    return faces[counts[inverse.ravel()] == 1]


def fig_deformed_body(points: np.ndarray, cells: np.ndarray, displacement: np.ndarray,
                      path: str | Path, *, title: str = "", elev: float = 22.0,
                      azim: float = -62.0) -> list[Path]:
    """The deformed half body y ≥ 0 coloured by the displacement magnitude (PNG + SVG).

    Left: a 3D view of the half body's surface, cut face y = 0 included. Right: the section
    y = 0 (the plane of shear), with the undeformed outline dashed.

    Parameters
    ----------
    points : (n_points, 3) ndarray
        Undeformed node coordinates [m].
    cells : (n_cells, 8 | 20 | 27) ndarray of int
        Hexahedra (VTK order, corners first); quadratic cells are drawn by their corners.
    displacement : (n_points, 3) ndarray
        Nodal displacement [m].
    path : path
        Output path without or with suffix; ``.png`` and ``.svg`` are written.
    title : str
        Figure title.
    elev, azim : float
        View angles of the 3D panel [degrees].

    Returns
    -------
    list of Path
        The written files.
    """
    x = mm(points + displacement)
    mag = mm(np.linalg.norm(displacement, axis=1))
    norm = colors.Normalize(vmin=0.0, vmax=max(float(mag.max()), 1e-12))
    cmap = colormap(CMAP_SEQ)
    faces = _boundary_faces(cells)
    tol = 1e-9 * np.ptp(points[:, 2])
    on_sym = np.all(np.abs(points[faces, 1]) < tol, axis=1)

    with style():
        fig = Figure(figsize=(6.8, 3.1))
        ax3 = fig.add_subplot(1, 2, 1, projection="3d")
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection

        polys = Poly3DCollection(x[faces], facecolors=cmap(norm(mag[faces].mean(axis=1))),
                                 edgecolors=(0, 0, 0, 0.25), linewidths=0.15)
        ax3.add_collection3d(polys)
        lo, hi = x.min(axis=0), x.max(axis=0)
        ax3.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]),
                xlabel="x [mm]", ylabel="y [mm]")
        ax3.set_title("half body y ≥ 0, deformed")
        ax3.set_box_aspect(hi - lo)
        ax3.view_init(elev=elev, azim=azim)
        ax3.tick_params(labelsize=6, pad=0)
        for axis in (ax3.xaxis, ax3.yaxis, ax3.zaxis):
            axis.labelpad = -2

        ax2 = fig.add_subplot(1, 2, 2)
        sec = faces[on_sym]
        tri = np.concatenate([sec[:, [0, 1, 2]], sec[:, [0, 2, 3]]])
        triang = Triangulation(x[:, 0], x[:, 2], tri)
        ax2.tripcolor(triang, mag, shading="gouraud", cmap=cmap, norm=norm)
        # undeformed outline: the edges used by one section face only
        edges = np.concatenate([sec[:, [0, 1]], sec[:, [1, 2]], sec[:, [2, 3]], sec[:, [3, 0]]])
        key, counts = np.unique(np.sort(edges, axis=1), axis=0, return_counts=True)
        outline = key[counts == 1]
        p0 = mm(points)
        for a, b in outline:
            ax2.plot(p0[[a, b], 0], p0[[a, b], 2], "k--", lw=0.5, dashes=(2, 2))
        ax2.set(xlabel="x [mm]", ylabel="z [mm]", aspect="equal")
        ax2.set_title("section y = 0 (undeformed dashed)")
        fig.colorbar(cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax2,
                     label="|u| [mm]", shrink=0.85)
        if title:
            fig.suptitle(title)
        return save(fig, Path(path))
