"""`magtact doe`: compute a study's design of experiments (parallel, cached, resumable)."""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import Annotated

import typer

from ._app import CacheOpt, OutOpt, StudyArg, WorkersOpt, app, console, get_study, outputs


@app.command("doe")
def doe_command(
    study: StudyArg = None,
    out: OutOpt = Path("doe"),
    workers: WorkersOpt = None,
    scheduler: Annotated[str | None, typer.Option(
        "--scheduler", help="Address of a dask.distributed scheduler (tcp://host:8786); the "
                            "jobs run on its workers instead of local processes.")] = None,
    cache: CacheOpt = Path(".magtact-cache"),
    no_cache: Annotated[bool, typer.Option("--no-cache", help="Compute every job afresh.")]
    = False,
    error_paths: Annotated[int, typer.Option(
        "--error-paths", min=0, help="Also solve this many (θ, H) paths on the next finer mesh "
                                     "and record every path's discretisation-error estimate "
                                     "(err_F_z, err_F_r; 5 is enough for a bilinear model and "
                                     "its check).")] = 0,
) -> None:
    """Run STUDY's full-factorial DOE; write OUT/doe.nc (netCDF) and OUT/doe.csv (user units).

    If jobs fail, the others stay cached and OUT/doe_partial.nc holds what finished (NaN on the
    failed paths, a stalled path's levels before the stall kept); magtact fit accepts it.
    """
    from .._files import write_text
    from ..doe import DOEFailed, run_doe, save_dataset, write_csv
    from ..metamodel import MAX_OMITTED

    s = get_study(study)
    start = time.perf_counter()
    failed = None
    with outputs("doe", out, "doe.nc", "doe.csv") as o:
        try:
            ds = run_doe(s, cache=None if no_cache else cache, workers=workers,
                         scheduler=scheduler, console=console, error_paths=error_paths)
        except DOEFailed as exc:
            failed = exc.failures
            report = o.final(write_text(o.folder / "doe_failures.json", json.dumps(
                [{"job": f.label, "error": f.error, "traceback": f.detail} for f in failed],
                indent=1)))
            # the finished jobs as a data set of its own name (NaN on the failed paths,
            # complete = 0): magtact fit leaves a few failed paths out and records them
            if exc.dataset is not None:
                o.final(save_dataset(exc.dataset, o.folder / "doe_partial.nc"))
        else:
            nc = o.final(save_dataset(ds, o.folder / "doe.nc"))
            csv = o.final(write_csv(ds, o.folder / "doe.csv"))
    if failed is not None:
        console.print(f"[bold red]{len(failed)} job(s) failed[/] (tracebacks in {report}); "
                      "the other jobs are cached: re-run to retry only the failed ones. "
                      "The data set of the finished jobs (NaN on the failed paths) is in "
                      f"{out / 'doe_partial.nc'}: magtact fit leaves out up to "
                      f"{MAX_OMITTED:.0%} of its points and records them.")
        for f in failed:
            console.print(f"  [red]{f.label}[/]: {f.error}", highlight=False)
        sys.exit(1)
    a = ds.attrs
    console.print(f"{a['run_paths_total']} structural paths: {a['run_paths_computed']} computed, "
                  f"{a['run_paths_cached']} from the cache"
                  + (f" ({a['run_cache_corrupt']} corrupt entries recomputed)"
                     if a["run_cache_corrupt"] else "")
                  + f"; field {'computed' if a['run_fields_computed'] else 'from the cache'}."
                  + (f"\ndiscretisation error against the {a['discretisation_finer_mesh']} mesh "
                     f"({a['discretisation_paths_measured']} paths measured): F_z(t=1) "
                     f"{100 * float(ds['err_F_z'].min()):+.2f} to "
                     f"{100 * float(ds['err_F_z'].max()):+.2f} %" if "err_F_z" in ds else "")
                  + f"\nwrote {nc} and {csv} ({ds['F_r'].size:,} rows) in "
                  f"{time.perf_counter() - start:.1f} s", highlight=False)
