"""Installed versions of packages, for provenance records."""

from __future__ import annotations

from importlib import metadata


def package_versions(names) -> dict[str, str]:
    """Installed versions of the named distributions (``"absent"`` when not installed)."""
    out = {}
    for name in names:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "absent"
    return out
