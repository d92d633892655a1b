"""Parametric geometry of the sensor: distances, loading path and meshes."""

from ._body_mesh import BodyMesh, body_mesh, half_cylinder_mesh  # noqa: F401  (mechanics stage)
from ._field_mesh import FieldMesh, field_mesh  # noqa: F401  (magnetics stage)
from ._path import dz0, hall_from_magnet_centre, loading_path, magnet_span, shear_displacement

__all__ = ["BodyMesh", "body_mesh", "hall_from_magnet_centre", "loading_path"]
