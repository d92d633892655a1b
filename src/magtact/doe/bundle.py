"""Rebuild the bundled data set: the default MagOne study's DOE with the default mesh.

Usage::

    python -m magtact.doe.bundle [--workers N] [--cache DIR] [--out FILE]
    python -m magtact.doe.bundle --error-from FINER.nc     # attach the discretisation error only

By default the result replaces ``magtact/doe/data/magone_doe.nc`` in the package (in a source
checkout: ``src/magtact/doe/data/``) and the job cache ``.magtact-cache`` is used, so an
interrupted rebuild resumes. See ``magtact/doe/data/README.md``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import xarray as xr
from rich.console import Console

from ..study import magone
from ._dataset import bundled_path, load_bundled, load_dataset, save_dataset
from ._discretisation import attach_discretisation_error
from ._run import run_doe


def build_bundle(*, workers: int | None = 2, cache: str | Path | None = ".magtact-cache",
                 out: str | Path | None = None, console: Console | None = None,
                 ) -> tuple[xr.Dataset, Path]:
    """Compute the default MagOne DOE and write it to ``out`` (default: the bundled file).

    Returns the data set and the path written.
    """
    ds = run_doe(magone(), cache=cache, workers=workers, console=console)
    return ds, save_dataset(ds, bundled_path() if out is None else out)


def attach_error(finer: str | Path, *, out: str | Path | None = None) -> tuple[xr.Dataset, Path]:
    """Add the per-path discretisation-error estimate against the finer-mesh DOE ``finer`` to
    the bundled data set (its forces unchanged) and write it to ``out`` (default: in place)."""
    ds = attach_discretisation_error(load_bundled(), load_dataset(finer))
    return ds, save_dataset(ds, bundled_path() if out is None else out)


def main(argv: list[str] | None = None) -> None:
    """Command-line entry point (``python -m magtact.doe.bundle``)."""
    parser = argparse.ArgumentParser(prog="python -m magtact.doe.bundle", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--workers", type=int, default=2, help="local worker processes (2)")
    parser.add_argument("--cache", default=".magtact-cache", help="job cache folder")
    parser.add_argument("--out", default=None, help="output file (default: the bundled file)")
    parser.add_argument("--error-from", default=None, metavar="FINER.nc",
                        help="only attach the discretisation-error estimate against this DOE "
                             "of the same study on a finer mesh")
    args = parser.parse_args(argv)
    console = Console(stderr=True)
    if args.error_from is not None:
        ds, path = attach_error(args.error_from, out=args.out)
        console.print(f"wrote {path}: discretisation error of {ds.attrs['discretisation_mesh']} "
                      f"against {ds.attrs['discretisation_finer_mesh']}, "
                      f"{ds.attrs['discretisation_paths_measured']} paths measured")
        return
    ds, path = build_bundle(workers=args.workers, cache=args.cache, out=args.out,
                            console=console)
    console.print(f"wrote {path}: {ds.attrs['run_paths_computed']} paths computed, "
                  f"{ds.attrs['run_paths_cached']} from the cache")


if __name__ == "__main__":
    main()
