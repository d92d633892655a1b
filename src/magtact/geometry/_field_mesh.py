"""Triangle mesh of the axisymmetric (r, z) half-plane around the magnet, for the field solve.

The magnet's centre is the origin; r ≥ 0, z up. Lengths in metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._gmsh import initialize as initialize_gmsh


@dataclass(frozen=True)
class FieldMesh:
    """A conforming triangle mesh of the far box r ∈ [0, r_far], z ∈ [−z_far, z_far].

    Attributes
    ----------
    points : numpy.ndarray
        Node coordinates (r, z) [m], shape (2, n_nodes).
    triangles : numpy.ndarray
        Node indices of each triangle (counter-clockwise), shape (3, n_triangles).
    in_magnet : numpy.ndarray
        True for the triangles inside the magnet, shape (n_triangles,).
    r_far, z_far : float
        Extent of the far box [m].
    """

    points: np.ndarray
    triangles: np.ndarray
    in_magnet: np.ndarray
    r_far: float
    z_far: float

    @property
    def n_triangles(self) -> int:
        """Number of triangles."""
        return self.triangles.shape[1]


def field_mesh(R_m: float, H_m: float, *, h_magnet: float, growth_near: float, near: float,
               growth: float, far_r: float, far_z: float) -> FieldMesh:
    """Mesh the (r, z) half-plane box around a cylindrical magnet with gmsh, graded outward.

    Parameters
    ----------
    R_m, H_m : float
        Magnet radius and height [m]; the magnet is r ≤ R_m, |z| ≤ H_m / 2.
    h_magnet : float
        Element size on the magnet's surface and inside it [m].
    growth_near : float
        Size growth per unit distance within ``near`` of the magnet's surface (≥ 0).
    near : float
        Thickness of that finely graded zone [m]; it should hold every point where the field
        is sampled.
    growth : float
        Size growth per unit distance beyond ``near`` (> ``growth_near``).
    far_r, far_z : float
        Far boundary at r = far_r · R_m and z = ±far_z · H_m.

    Returns
    -------
    FieldMesh
        Straight-sided triangles; the magnet's boundary is resolved by element edges.

    Raises
    ------
    ValueError
        If a size is not positive, ``growth <= growth_near``, or the far box does not
        enclose the magnet.

    Notes
    -----
    With d the distance from the magnet's faces and mantle, the target element size is

    .. math::

        h(d) = \\max\\left(h_m + g_n d,\\; h_m + g_n d_n + g (d - d_n)\\right),

    i.e. slow linear growth g_n up to d = d_n (``near``) and fast growth g beyond.
    """
    for name, value in (("R_m", R_m), ("H_m", H_m), ("h_magnet", h_magnet), ("near", near),
                        ("growth", growth)):
        if not value > 0:
            raise ValueError(f"field_mesh: {name} must be positive, got {value}")
    if not 0 <= growth_near < growth:
        raise ValueError(f"field_mesh: expected 0 <= growth_near < growth, got growth_near="
                         f"{growth_near}, growth={growth}")
    if not (far_r > 1 and far_z > 0.5):
        raise ValueError(f"field_mesh: the far box (far_r={far_r}, far_z={far_z}) must enclose "
                         "the magnet (far_r > 1, far_z > 0.5)")
    import gmsh

    # Mesh in units of R_m (well-scaled numbers for gmsh's tolerances), scale back at the end.
    s = float(R_m)
    rf, zf, hz = far_r, far_z * H_m / s, 0.5 * H_m / s
    own = not gmsh.isInitialized()
    if own:
        initialize_gmsh()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("magtact_field")
        occ = gmsh.model.occ
        box = occ.addRectangle(0.0, -zf, 0.0, rf, 2 * zf)
        mag = occ.addRectangle(0.0, -hz, 0.0, 1.0, 2 * hz)
        _, parts = occ.fragment([(2, box)], [(2, mag)])
        occ.synchronize()
        magnet_tags = [tag for _, tag in parts[1]]
        air_tags = [tag for _, tag in parts[0] if tag not in magnet_tags]
        surface_curves = []  # the magnet's faces and mantle (not its segment of the axis)
        for _, c in gmsh.model.getBoundary([(2, t) for t in magnet_tags], oriented=False):
            xmax = gmsh.model.getBoundingBox(1, c)[3]
            if xmax > 1e-3:
                surface_curves.append(c)
        fld = gmsh.model.mesh.field
        dist = fld.add("Distance")
        fld.setNumbers(dist, "CurvesList", surface_curves)
        fld.setNumber(dist, "Sampling", 100)
        size = fld.add("MathEval")
        h0, dn = h_magnet / s, near / s
        hn = h0 + growth_near * dn
        expr = f"Max({h0!r} + {growth_near!r} * F{dist}, {hn!r} + {growth!r} * (F{dist} - {dn!r}))"
        fld.setString(size, "F", expr)
        fld.setAsBackgroundMesh(size)
        for opt, val in (("Mesh.MeshSizeExtendFromBoundary", 0), ("Mesh.MeshSizeFromPoints", 0),
                         ("Mesh.MeshSizeFromCurvature", 0), ("Mesh.Algorithm", 6),
                         ("General.NumThreads", 1)):
            gmsh.option.setNumber(opt, val)
        gmsh.model.mesh.generate(2)
        tags, coords, _ = gmsh.model.mesh.getNodes()
        index = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
        index[tags.astype(np.int64)] = np.arange(tags.size)
        points = coords.reshape(-1, 3)[:, :2].T * s
        tri, flag = [], []
        for group, is_magnet in ((magnet_tags, True), (air_tags, False)):
            for tag in group:
                _, nodes = gmsh.model.mesh.getElementsByType(2, tag)
                t = index[nodes.astype(np.int64)].reshape(-1, 3)
                tri.append(t)
                flag.append(np.full(len(t), is_magnet))
    finally:
        gmsh.model.remove()
        if own:
            gmsh.finalize()
    triangles = np.ascontiguousarray(np.concatenate(tri).T)
    # orient counter-clockwise
    p = points[:, triangles]
    area2 = ((p[0, 1] - p[0, 0]) * (p[1, 2] - p[1, 0]) - (p[0, 2] - p[0, 0]) * (p[1, 1] - p[1, 0]))
    triangles[[1, 2]] = np.where(area2 < 0, triangles[[2, 1]], triangles[[1, 2]])
    used = np.unique(triangles)
    if used.size != points.shape[1]:  # drop geometry-only nodes, renumber
        remap = np.full(points.shape[1], -1, dtype=np.int64)
        remap[used] = np.arange(used.size)
        points, triangles = points[:, used], remap[triangles]
    return FieldMesh(points=np.ascontiguousarray(points), triangles=np.ascontiguousarray(triangles),
                     in_magnet=np.concatenate(flag), r_far=far_r * R_m, z_far=far_z * H_m)
