"""Installed versions of packages, for provenance records: which packages each record names."""

from __future__ import annotations

from importlib import metadata

#: Packages a field job's result depends on (part of its cache key).
FIELD = ("numpy", "scipy", "scikit-fem", "gmsh", "magpylib")
#: Packages a structural path's result depends on (part of its cache key).
MECHANICS = ("numpy", "scipy", "felupe", "gmsh", "pypardiso")
#: Packages recorded in a DOE data set's provenance: the computing ones and the storage.
DOE = tuple(dict.fromkeys(("magtact", *FIELD, *MECHANICS, "xarray", "h5netcdf", "dask",
                           "distributed")))
#: Packages a run records and the report lists: everything a result passes through.
RUN = tuple(dict.fromkeys((*DOE, "pyoperon", "sympy", "pymoo", "scikit-learn", "matplotlib",
                           "typer", "rich")))


def package_versions(names) -> dict[str, str]:
    """Installed versions of the named distributions (``"absent"`` when not installed)."""
    out = {}
    for name in names:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "absent"
    return out
