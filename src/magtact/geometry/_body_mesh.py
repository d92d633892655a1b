"""Hexahedral mesh of the half sensor body (y ≥ 0) for the structural model (docs/method.md §3).

The mesh is built in two parts:

1. gmsh meshes the half disc y ≥ 0 of the body's cross-section with structured (transfinite)
   quadrilateral blocks: an O-grid of a half square core and three rings of blocks, whose block
   edges lie on the circles r = R_m (the magnet's edge) and r = R − R_h (start of the rounded
   top edge) and r = R, and extrudes it along z in layers (``recombine``: hexahedra).
2. numpy then rounds the top outer edge: nodes in the corner square
   [R − R_h, R] × [z_top − R_h, z_top] of the (r, z) plane are mapped onto the quarter disc of
   radius R_h with the elliptical square-to-disc map, and the cells of the magnet (the cavity)
   are removed.

The cross-section polygon is scaled so that its area equals that of the circle (equal-area
polygon), hence the cross-section area and the magnet's cross-section are exact for any number
of segments around the half circle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..study import Study
from ._gmsh import initialize as initialize_gmsh
from ._path import magnet_span

#: Named mesh densities. ``m``: cells along a quarter of the half circle (the half circle has
#: 4 m segments); ``radial``: cells between the core and R_m, R_m and R − R_h, R − R_h and R;
#: ``h_z``: mean cell height [m] in z; ``n_corner``: cells across the rounded edge in z.
#: Grading: ``progression`` (gmsh) of the cells from the core to the magnet's edge, ``bump``
#: (gmsh, < 1 refines both ends) from the magnet's edge to the body's side, ``z_grading`` ∈ [0, 1]
#: towards the base, the magnet's faces and the top (:func:`_graded`); with
#: ``grade_magnet_face`` false, the layer between the base and the magnet is graded towards the
#: base only, so the cells under the magnet's face are not the thinnest. Near t = 1 at θ_max the
#: cell under the magnet's rounded edge is squeezed almost flat; with a 0.3 mm edge radius,
#: meshes refined there stalled at H = 7 mm. With the 0.6 mm radius of the MagOne study, face
#: grading completes on the ``accurate`` mesh, with 0.5–0.8 % lower F_z(t = 1)
#: (bench/results/mechanics_accurate.json), and on the default mesh (with weight 0.7: 0.7 % and
#: 1.8 % lower F_z(t = 1) at θ_max for H = 3 and 7 mm, all 25 DOE paths, 35 s per path on
#: average), but the ``fine`` mesh graded that way stalled at t = 0.9988 at H = 7 mm. With
#: weight 0.5 it completes, and the default is as far from it as with base-only grading (3.9 %
#: in F_z(t = 1) at H = 7 mm, 2.5 % at H = 3 mm), so the base-only grading stays.
#: Doubling the cells in one direction at a time (bench/results/mechanics_directions_H*.json)
#: showed the error mostly in z and radially (in the rings under and beside the magnet), little
#: around the circle at H = 3 mm (as much as radially at H = 7 mm) and none across the rounded
#: edge, so the default has few segments around the circle (the equal-area polygon keeps the
#: cross-section exact). ``fine`` has twice the default's cells in every direction (the
#: reference of the convergence benchmark); ``accurate`` twice the default's cells in z and
#: radially.
_GRADING = {"progression": 0.9, "bump": 0.6, "z_grading": 0.3, "grade_magnet_face": False}
_DEFAULT = {"m": 3, "radial": (4, 7, 3), "h_z": 0.6e-3, "n_corner": 3}
DENSITIES: dict[str, dict] = {
    "coarse": {"m": 3, "radial": (2, 3, 2), "h_z": 1.2e-3, "n_corner": 2} | _GRADING,
    "default": _DEFAULT | _GRADING,
    "accurate": _DEFAULT | {"radial": (8, 14, 6), "h_z": 0.3e-3} | _GRADING,
    "fine": {"m": 6, "radial": (8, 14, 6), "h_z": 0.3e-3, "n_corner": 6} | _GRADING,
}


@dataclass(frozen=True)
class BodyMesh:
    """A hexahedral mesh of the half body y ≥ 0 with its named node sets.

    Attributes
    ----------
    points : (n_points, 3) ndarray
        Node coordinates [m]; base at z = 0, axis x = y = 0.
    cells : (n_cells, 8), (n_cells, 20) or (n_cells, 27) ndarray of int
        Hexahedra, VTK node order, positive volume: trilinear (8 nodes), serendipity quadratic
        (20 nodes: corners and mid-edge nodes) or triquadratic (27 nodes: also mid-face and
        mid-cell nodes); the corner nodes are numbered before the others, so the first
        ``n_corners`` points carry a trilinear field of the same cells.
    base, symmetry, cavity, surface : ndarray of int
        Node indices on the base z = 0; on the symmetry plane y = 0; on the magnet's cavity
        surface (empty without a magnet); on the free outer surface (side, rounded edge and top
        face, without base and cavity nodes), i.e. the nodes that can touch a plate.
    z_top : float
        Height of the top face [m].
    name : str
        Name of the mesh density.
    """

    points: np.ndarray
    cells: np.ndarray
    base: np.ndarray
    symmetry: np.ndarray
    cavity: np.ndarray
    surface: np.ndarray
    z_top: float
    name: str

    @property
    def order(self) -> int:
        """Polynomial order of the cells: 1 (8 nodes) or 2 (20 or 27 nodes)."""
        return 1 if self.cells.shape[1] == 8 else 2

    @property
    def n_corners(self) -> int:
        """Number of cell-corner nodes (numbered first)."""
        return int(self.cells[:, :8].max()) + 1

    @property
    def n_points(self) -> int:
        """Number of nodes."""
        return len(self.points)

    @property
    def n_cells(self) -> int:
        """Number of hexahedra."""
        return len(self.cells)

    def volume(self) -> float:
        """Volume of the half body [m³] (sum of the trilinear cell volumes)."""
        return float(np.sum(_cell_volumes(self.points, self.cells[:, :8])))


def body_mesh(study: Study, H: float, mesh: str | None = None, order: int = 1,
              serendipity: bool = False) -> BodyMesh:
    """Hexahedral mesh of the half sensor body y ≥ 0 for the base height ``H`` [m].

    Parameters
    ----------
    study : Study
        Body and magnet dimensions (docs/method.md §1).
    H : float
        Base height [m]; the body is a cylinder of radius R and height H + H_g.
    mesh : {"coarse", "default", "accurate", "fine"} or None
        Mesh density; ``None`` takes ``study.mechanics.mesh``.
    order : {1, 2}
        Trilinear (8-node) or quadratic hexahedra on the same cells.
    serendipity : bool
        With ``order=2``: 20-node (serendipity) instead of 27-node (triquadratic) hexahedra.

    Returns
    -------
    BodyMesh
        The mesh with the magnet's cavity removed (placement per ``study.magnet.placement``),
        its lower edge rounded by ``study.mechanics.magnet_edge_radius``.
    """
    name = study.mechanics.mesh if mesh is None else mesh
    z_low, z_high = (float(v) for v in magnet_span(study, H))
    return half_cylinder_mesh(
        R=study.body.R,
        height=H + study.body.H_g,
        R_h=study.body.R_h,
        cavity=(study.magnet.R_m, z_low, z_high),
        density=name,
        edge_radius=study.mechanics.magnet_edge_radius,
        order=order,
        serendipity=serendipity,
    )


def half_cylinder_mesh(
    R: float,
    height: float,
    *,
    R_h: float = 0.0,
    cavity: tuple[float, float, float] | None = None,
    density: str = "default",
    r_ring: float | None = None,
    edge_radius: float = 0.0,
    order: int = 1,
    serendipity: bool = False,
) -> BodyMesh:
    """Hexahedral mesh of a half cylinder y ≥ 0 with a rounded top edge and an optional cavity.

    Parameters
    ----------
    R, height : float
        Radius and height of the cylinder [m]; the base is at z = 0.
    R_h : float
        Radius of the rounded top outer edge [m] (0: a sharp edge).
    cavity : (R_m, z_low, z_high) or None
        Cylindrical cavity on the axis of radius R_m between the heights z_low and z_high [m]
        (the magnet), or None for a plain body.
    density : {"coarse", "default", "accurate", "fine"}
        Named mesh density (:data:`DENSITIES`).
    r_ring : float or None
        Radius of the inner ring of block edges [m]; defaults to the cavity radius (without a
        cavity: R / 2).
    edge_radius : float
        Radius [m] of the rounded lower edge of the cavity (0: sharp). The cavity nodes within
        ``edge_radius`` of the edge are projected onto the quarter circle of that radius.
    order : {1, 2}
        1: trilinear hexahedra; 2: triquadratic (27-node) hexahedra with the same corners.
        The mid-edge, mid-face and mid-cell nodes are added to the straight extruded blocks
        and then go through the same maps as the corners (rounded edges), so they lie on the
        curved surfaces.
    serendipity : bool
        With ``order=2``: 20-node hexahedra (corners and mid-edge nodes only) instead of
        27-node ones.

    Returns
    -------
    BodyMesh
    """
    if order not in (1, 2):
        raise ValueError(f"order must be 1 or 2, got {order!r}")
    if density not in DENSITIES:
        raise ValueError(f"unknown mesh density {density!r}; choose one of {sorted(DENSITIES)}")
    if not (R > 0 and height > 0):
        raise ValueError(f"the body needs R > 0 and height > 0, got R={R}, height={height}")
    if not 0 <= R_h < min(R, height):
        raise ValueError(f"the edge radius R_h={R_h} must be in [0, min(R, height))")
    dens = DENSITIES[density]
    if cavity is not None:
        R_m, z_low, z_high = cavity
        if not 0 <= edge_radius < min(R_m, z_high - z_low):
            raise ValueError(f"the magnet's edge radius {edge_radius} must be in "
                             f"[0, min(R_m, H_m)) = [0, {min(R_m, z_high - z_low)})")
        if not (0 < R_m < R - R_h and 0 < z_low < z_high <= height):
            raise ValueError(
                f"the magnet (R_m={R_m}, z in [{z_low}, {z_high}]) must lie inside the body "
                f"(R - R_h = {R - R_h}, height = {height}) above the base"
            )
        r1 = R_m
    else:
        r1 = R / 2 if r_ring is None else r_ring
    radii = [r1, R - R_h, R] if R_h > 0 else [r1, R]
    n_radial = list(dens["radial"]) if R_h > 0 else [dens["radial"][0], sum(dens["radial"][1:])]

    xy, quads = _half_disc(radii, n_radial, dens)
    z_levels = _z_levels(height, R_h, cavity, dens)
    points, cells = _extrude(xy, quads, z_levels)
    if order == 2:
        points, cells = _quadratic(points, cells, serendipity)

    # round the top outer edge: elliptical map of the corner square onto the quarter disc
    if R_h > 0:
        rho = np.hypot(points[:, 0], points[:, 1])
        xi = np.clip((rho - (R - R_h)) / R_h, 0.0, 1.0)
        eta = np.clip((points[:, 2] - (height - R_h)) / R_h, 0.0, 1.0)
        corner = (xi > 0) & (eta > 0)
        rho_new = R - R_h + R_h * xi * np.sqrt(1 - eta**2 / 2)
        z_new = height - R_h + R_h * eta * np.sqrt(1 - xi**2 / 2)
        scale = np.where(corner, rho_new / np.where(rho > 0, rho, 1.0), 1.0)
        points[:, :2] *= scale[:, None]
        points[corner, 2] = z_new[corner]

    # equal-area polygon: the 4 m segments of each circle enclose the circle's area
    alpha = math.pi / (4 * dens["m"])
    points[:, :2] *= math.sqrt(alpha / math.sin(alpha))

    # remove the magnet's cells
    tol = 1e-9 * height
    if cavity is not None:
        centre = points[cells[:, :8]].mean(axis=1)
        rho_c = np.hypot(centre[:, 0], centre[:, 1])
        inside = (rho_c < r1) & (centre[:, 2] > z_low) & (centre[:, 2] < z_high)
        cells = cells[~inside]
        corners, used = np.unique(cells[:, :8]), np.unique(cells)
        used = np.concatenate([corners, np.setdiff1d(used, corners)])  # corners first
        renumber = np.full(len(points), -1)
        renumber[used] = np.arange(len(used))
        points, cells = points[used], renumber[cells]

    base = np.flatnonzero(np.abs(points[:, 2]) < tol)
    symmetry = np.flatnonzero(np.abs(points[:, 1]) < tol)
    if cavity is not None:
        rho = np.hypot(points[:, 0], points[:, 1])
        r_cav = r1 * math.sqrt(alpha / math.sin(alpha))
        z = points[:, 2]
        cavity_nodes = np.flatnonzero((rho < r_cav * (1 + 1e-9)) & (z > z_low - tol)
                                      & (z < z_high + tol))
        if edge_radius > 0:
            _round_edge(points, cavity_nodes, r_cav, z_low, edge_radius)
    else:
        cavity_nodes = np.array([], dtype=int)
    surface = _outer_surface(points, cells, tol, exclude=np.union1d(base, cavity_nodes))
    return BodyMesh(points=points, cells=cells, base=base, symmetry=symmetry, cavity=cavity_nodes,
                    surface=surface, z_top=float(height), name=density)


def _round_edge(points: np.ndarray, nodes: np.ndarray, r_cav: float, z_low: float,
                radius: float) -> None:
    """Round the cavity's lower edge in place: the cavity nodes within ``radius`` of the edge
    (r = r_cav, z = z_low) are projected from the fillet's centre line
    (r = r_cav − radius, z = z_low + radius) onto the circle of that radius."""
    p = points[nodes]
    rho = np.hypot(p[:, 0], p[:, 1])
    c_r, c_z = r_cav - radius, z_low + radius
    near = (rho > c_r) & (p[:, 2] < c_z)
    d = np.column_stack([rho[near] - c_r, p[near, 2] - c_z])
    d *= radius / np.linalg.norm(d, axis=1)[:, None]
    idx = nodes[near]
    points[idx, :2] *= ((c_r + d[:, 0]) / rho[near])[:, None]
    points[idx, 2] = c_z + d[:, 1]


def _half_disc(radii: list[float], n_radial: list[int],
               dens: dict) -> tuple[np.ndarray, np.ndarray]:
    """Quadrilateral O-grid of the half disc y ≥ 0 by gmsh transfinite blocks.

    Returns the node coordinates (n, 2) [m] and the quads (n_quads, 4), counter-clockwise.
    """
    import gmsh

    m = dens["m"]
    a = 0.45 * radii[0]  # half width of the core square
    angles = (0.0, 0.25 * math.pi, 0.75 * math.pi, math.pi)
    n_arc = (m, 2 * m, m)
    initialised = gmsh.isInitialized()
    if not initialised:
        initialize_gmsh()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("half_disc")
    try:
        geo = gmsh.model.geo
        centre = geo.addPoint(0, 0, 0)
        core = [geo.addPoint(a, 0, 0), geo.addPoint(a, a, 0), geo.addPoint(-a, a, 0),
                geo.addPoint(-a, 0, 0)]
        rings = [core] + [[geo.addPoint(r * math.cos(p), r * math.sin(p), 0) for p in angles]
                          for r in radii]
        # curves along each ring (core square edges, then circle arcs) and radial lines
        along = []
        for j, pts in enumerate(rings):
            if j == 0:
                along.append([geo.addLine(pts[q], pts[q + 1]) for q in range(3)])
            else:
                along.append([geo.addCircleArc(pts[q], centre, pts[q + 1]) for q in range(3)])
            for q in range(3):
                geo.mesh.setTransfiniteCurve(along[j][q], n_arc[q] + 1)
        bottom = geo.addLine(core[3], core[0])
        geo.mesh.setTransfiniteCurve(bottom, 2 * m + 1)
        surfaces = [geo.addPlaneSurface([geo.addCurveLoop([bottom] + along[0])])]
        geo.mesh.setTransfiniteSurface(surfaces[0], cornerTags=core)
        for j in range(1, len(rings)):
            radial = [geo.addLine(rings[j - 1][q], rings[j][q]) for q in range(4)]
            for line in radial:
                # ring 1 (core → magnet edge) graded towards the magnet edge, the others
                # towards both ends (the magnet edge, the body corners)
                if j == 1:
                    geo.mesh.setTransfiniteCurve(line, n_radial[0] + 1, "Progression",
                                                 dens["progression"])
                else:
                    geo.mesh.setTransfiniteCurve(line, n_radial[j - 1] + 1, "Bump",
                                                 dens["bump"])
            for q in range(3):
                loop = geo.addCurveLoop([radial[q], along[j][q], -radial[q + 1], -along[j - 1][q]])
                s = geo.addPlaneSurface([loop])
                corners = [rings[j - 1][q], rings[j][q], rings[j][q + 1], rings[j - 1][q + 1]]
                geo.mesh.setTransfiniteSurface(s, cornerTags=corners)
                surfaces.append(s)
        for s in surfaces:
            geo.mesh.setRecombine(2, s)
        geo.synchronize()
        gmsh.model.mesh.generate(2)
        tags, coords, _ = gmsh.model.mesh.getNodes()
        _, quad_nodes = gmsh.model.mesh.getElementsByType(3)
    finally:
        gmsh.model.remove()
        if not initialised:
            gmsh.finalize()
    index = np.full(int(tags.max()) + 1, -1)
    index[tags.astype(int)] = np.arange(len(tags))
    xy = coords.reshape(-1, 3)[:, :2].copy()
    quads = index[quad_nodes.astype(int)].reshape(-1, 4)
    used = np.unique(quads)  # drop the centre point of the arcs
    renumber = np.full(len(xy), -1)
    renumber[used] = np.arange(len(used))
    xy, quads = xy[used], renumber[quads]
    # counter-clockwise orientation (positive area) for every quad
    p = xy[quads]
    d1, d2 = p[:, 2] - p[:, 0], p[:, 3] - p[:, 1]
    area = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    quads[area < 0] = quads[area < 0][:, ::-1]
    return xy, quads


def _graded(a: float, b: float, n: int, weight: float, both: bool = True) -> np.ndarray:
    """n + 1 levels from a to b, refined towards both ends (``both``) or towards a only: a blend
    with weight ``weight`` ∈ [0, 1] of uniform and cosine (Chebyshev) spacing."""
    s = np.linspace(0.0, 1.0, n + 1)
    cosine = 0.5 * (1 - np.cos(np.pi * s)) if both else 1 - np.cos(0.5 * np.pi * s)
    s = (1 - weight) * s + weight * cosine
    return a + (b - a) * s


def _z_levels(height: float, R_h: float, cavity, dens: dict) -> np.ndarray:
    """Heights of the layers [m], graded towards the base, the magnet's faces and the top."""
    breaks = [0.0, height]
    if R_h > 0:
        breaks.append(height - R_h)
    if cavity is not None:
        breaks += [cavity[1], cavity[2]]
    breaks = np.unique(np.round(np.asarray(breaks) / height, 9)) * height
    levels = [np.array([0.0])]
    for lo, hi in zip(breaks[:-1], breaks[1:], strict=True):
        if R_h > 0 and hi >= height - 1e-9 * height and lo >= height - R_h - 1e-9 * height:
            n = dens["n_corner"] if math.isclose(hi - lo, R_h) else max(1, round(
                dens["n_corner"] * (hi - lo) / R_h))
            levels.append(_graded(lo, hi, n, 0.0)[1:])
        else:
            n = max(2, math.ceil((hi - lo) / dens["h_z"]))
            under_magnet = cavity is not None and math.isclose(hi, cavity[1])
            both = dens["grade_magnet_face"] or not under_magnet
            levels.append(_graded(lo, hi, n, dens["z_grading"], both)[1:])
    return np.concatenate(levels)


def _extrude(xy: np.ndarray, quads: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Hexahedra from extruding the quads through the layers ``z`` (VTK node order)."""
    n, nz = len(xy), len(z)
    points = np.column_stack([np.tile(xy, (nz, 1)), np.repeat(z, n)])
    layer = np.arange(nz - 1)[:, None, None] * n
    bottom = quads[None, :, :] + layer
    cells = np.concatenate([bottom, bottom + n], axis=2).reshape(-1, 8)
    return points, cells


def _quadratic(points: np.ndarray, cells: np.ndarray,
               serendipity: bool) -> tuple[np.ndarray, np.ndarray]:
    """27-node, or with ``serendipity`` 20-node, hexahedra from trilinear ones (FElupe's
    conversion: new nodes appended)."""
    import felupe as fem

    points, cells, _ = fem.mesh.convert(points, cells, "hexahedron", order=2,
                                        calc_midfaces=not serendipity,
                                        calc_midvolumes=not serendipity)
    return np.asarray(points, dtype=float), np.asarray(cells)


def _cell_volumes(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Volumes of trilinear hexahedra by 2×2×2 Gauss quadrature [m³]."""
    g = 1 / math.sqrt(3)
    ref = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                    [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)
    x = points[cells]  # (c, 8, 3)
    vol = np.zeros(len(cells))
    for gp in ref * g:
        dN = np.empty((8, 3))
        for a in range(8):
            f = 1 + ref[a] * gp
            dN[a] = ref[a] * np.array([f[1] * f[2], f[0] * f[2], f[0] * f[1]]) / 8
        J = np.einsum("cai,aj->cij", x, dN)
        vol += np.linalg.det(J)
    return vol


def _face_nodes(n_nodes: int) -> np.ndarray:
    """Local node numbers of the 6 faces of an 8-, 20- or 27-node hexahedron (VTK order),
    corners first: the nodes whose reference coordinate along one axis is −1 or +1."""
    from felupe.element import Hexahedron, QuadraticHexahedron, TriQuadraticHexahedron

    ref = {8: Hexahedron, 20: QuadraticHexahedron, 27: TriQuadraticHexahedron}[n_nodes]().points
    faces = []
    for axis in range(3):
        for side in (-1.0, 1.0):
            on = np.flatnonzero(ref[:, axis] == side)
            faces.append(np.concatenate([on[on < 8], on[on >= 8]]))
    return np.array(faces)


def _outer_surface(points: np.ndarray, cells: np.ndarray, tol: float,
                   exclude: np.ndarray) -> np.ndarray:
    """Nodes of the boundary faces not on the symmetry plane y = 0, without ``exclude``."""
    local = _face_nodes(cells.shape[1])
    faces = cells[:, local].reshape(-1, local.shape[1])
    key = np.sort(faces[:, :4], axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    boundary = faces[counts[inverse.ravel()] == 1]
    on_symmetry = np.all(np.abs(points[boundary, 1]) < tol, axis=1)
    nodes = np.unique(boundary[~on_symmetry])
    return np.setdiff1d(nodes, exclude)
