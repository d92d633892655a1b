"""Installed versions of packages: for provenance records, and for the DOE job cache keys.

Cache-key policy (docs/usage.md, "Design of experiments"): a cached field or path is reused
as long as nothing that computes it changed. The key holds magtact's model versions
(``MODEL_VERSION`` of ``magtact.magnetics`` and ``magtact.mechanics``, bumped by hand when a
change of the code changes results) and the *major.minor* versions of the packages that compute
the job (:data:`FIELD`, :data:`MECHANICS`). A patch release (numpy 2.4.5 → 2.4.6) keeps the
cache; a minor or major release, or a package installed or removed among these, renews it.
Packages that compute nothing of the job (magpylib, a test-only reference; the storage and
scheduling packages) are not part of it.
"""

from __future__ import annotations

import re
from importlib import metadata

#: Packages a field job's result depends on (their minor versions are part of its cache key).
FIELD = ("numpy", "scipy", "scikit-fem", "gmsh")
#: Packages a structural path's result depends on (minor versions part of its cache key).
MECHANICS = ("numpy", "scipy", "felupe", "gmsh", "pypardiso")
#: Packages recorded in a DOE data set's provenance: the computing ones and the storage.
DOE = tuple(dict.fromkeys(("magtact", *FIELD, *MECHANICS, "magpylib", "xarray", "h5netcdf",
                           "dask", "distributed")))
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


def minor_version(version: str) -> str:
    """``major.minor`` of a version string (``"2.4.6"`` → ``"2.4"``, ``"2026.8.0"`` →
    ``"2026.8"``); a string without a dotted numeric prefix (``"absent"``) is kept whole."""
    m = re.match(r"(\d+)\.(\d+)", version)
    return f"{m.group(1)}.{m.group(2)}" if m else version


def key_versions(names) -> dict[str, str]:
    """The ``major.minor`` versions of the named distributions, for a cache key."""
    return {name: minor_version(v) for name, v in package_versions(names).items()}
