"""Running a design of experiments: plan, look up the cache, compute the rest, assemble."""

from __future__ import annotations

import functools
import itertools
import json
import os
import subprocess
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import xarray as xr
from rich.console import Console

from .._errors import MagtactError
from ..study import Study, from_si
from ._cache import JobCache
from ._dataset import GEOMETRY_NAMES, assemble
from ._discretisation import FINER_MESH, attach_discretisation_error, error_points
from ._executor import Task, default_workers, execute
from ._jobs import (
    FIELD_MODEL,
    PATH_MODEL,
    plan,
    run_field,
    run_path,
    solver_identity,
    verify_entry,
)
from ._progress import Display


@dataclass(frozen=True)
class JobFailure:
    """A job that could not be completed: its label, error message and worker traceback."""

    label: str
    error: str
    detail: str = ""


class DOEFailed(RuntimeError):
    """Some jobs failed; every other job finished and is cached.

    Attributes
    ----------
    failures : list of JobFailure
    dataset : xarray.Dataset
        The incomplete data set (NaN where a job failed; ``attrs["complete"] == 0``).
    """

    def __init__(self, failures: list[JobFailure], dataset: xr.Dataset):
        self.failures = failures
        self.dataset = dataset
        lines = "\n".join(f"  {f.label}: {f.error}" for f in failures)
        super().__init__(f"{len(failures)} DOE job(s) failed (the others are cached; re-run to "
                         f"retry only these):\n{lines}")


@dataclass
class RunStats:
    """Counters of one run (also written to the data set's ``run_*`` attributes)."""

    paths_total: int = 0
    paths_cached: int = 0
    paths_computed: int = 0
    fields_computed: int = 0
    cache_corrupt: int = 0
    failures: list[JobFailure] = field(default_factory=list)


def run_doe(study: Study, *, cache: str | os.PathLike | None = None, workers: int | None = None,
            scheduler: str | None = None, console: Console | None = None,
            path_solver=None, field_solver=None, error_paths: int = 0) -> xr.Dataset:
    """Compute the full-factorial design of experiments of ``study`` (docs/method.md §4).

    Parameters
    ----------
    study : Study
    cache : path, optional
        Job cache folder. Jobs found there (and verified) are not recomputed; every computed job
        is written there as soon as it finishes, so an interrupted run resumes. ``None``: no cache.
    workers : int, optional
        Local worker processes (default: the number of cores; 0: compute in this process).
    scheduler : str, optional
        Address of a dask.distributed scheduler; the jobs then run on its workers.
    console : rich.console.Console, optional
        Draw a live per-job status table and progress bar with ETA there.
    path_solver, field_solver : callable, optional
        The structural path solver (default :func:`magtact.mechanics.simulate_path`) and the
        field solver (default :func:`magtact.magnetics.hall_field`); their source code is part
        of the cache keys.
    error_paths : int
        Also solve this many (θ, H) paths on the next finer mesh (:data:`FINER_MESH`, chosen by
        :func:`error_points`) and record every path's discretisation-error estimate
        (:func:`attach_discretisation_error`). 0: no estimate.

    Returns
    -------
    xarray.Dataset
        dims ``t, theta, H, G``; ``u_r, u_z, B_r, B_z`` (t, theta, H), ``F_r, F_z``
        (t, theta, H, G) in SI, with units and provenance attributes. The ``run_*`` attributes
        count this run's work: ``run_paths_computed`` structural solves, ``run_paths_cached``
        paths read from the cache, ``run_cache_corrupt`` corrupt entries recomputed.

    Raises
    ------
    DOEFailed
        If any job failed, after all other jobs finished (they are cached).
    """
    if path_solver is None:
        from ..mechanics import simulate_path as path_solver
    if field_solver is None:
        from ..magnetics import hall_field as field_solver
    if study.geometric_variables:
        return _run_geometry(study, cache=cache, workers=workers, scheduler=scheduler,
                             console=console, path_solver=path_solver, field_solver=field_solver,
                             error_paths=error_paths)
    run = functools.partial(_run, cache=cache, workers=workers, scheduler=scheduler,
                            console=console, path_solver=path_solver, field_solver=field_solver)
    mesh = study.mechanics.mesh
    if error_paths > 0 and mesh not in FINER_MESH:
        raise MagtactError(f"mechanics.mesh = {mesh!r} has no finer mesh to estimate its "
                           "discretisation error against (those that have: "
                           f"{sorted(FINER_MESH)})")
    ds = run(study)
    if error_paths <= 0:
        return ds
    finer = replace(study, mechanics=replace(study.mechanics, mesh=FINER_MESH[mesh]))
    points = error_points(study.theta_levels, study.H_levels, error_paths)
    return attach_discretisation_error(ds, run(finer, only=points))


def _run_geometry(study: Study, **kw) -> xr.Dataset:
    """The DOE over the geometric design variables besides H: one sub-DOE (its field solve and
    structural paths) per point of their grid, joined along one dimension per variable."""
    levels = study.geometry_levels
    parts, failures = [], []
    for values in itertools.product(*levels.values()):
        geometry = dict(zip(levels, (float(v) for v in values), strict=True))
        try:
            part = run_doe(study.at(**geometry), **kw)
        except DOEFailed as exc:
            where = ", ".join(f"{k}={from_si(v, 'mm'):.4g} mm" for k, v in geometry.items())
            failures += [replace(f, label=f"{f.label}, {where}") for f in exc.failures]
            part = exc.dataset
        # one new dimension per geometric variable, after the DOE's own (any number of them)
        parts.append(part.expand_dims({k: [v] for k, v in geometry.items()})
                     .transpose(..., *geometry))
    ds = xr.combine_by_coords(parts, combine_attrs="drop_conflicts")
    for k in levels:
        ds[k].attrs.update(units="m", long_name=GEOMETRY_NAMES[k])
    jobs = [dict(j, **{k: float(p[k].values[0]) for k in levels})
            for p in parts for j in json.loads(p.attrs["jobs"])]
    ds.attrs.update({
        "study_name": study.name, "study_toml": study.to_toml(),
        "title": f"magtact design of experiments: {study.name}",
        "jobs": json.dumps(jobs),
        "geometric_variables": ", ".join(levels),
        "complete": int(not failures),
        "failed_jobs": "\n".join(f"{f.label}: {f.error}" for f in failures),
        **{key: sum(int(p.attrs[key]) for p in parts)
           for key in ("run_paths_total", "run_paths_computed", "run_paths_cached",
                       "run_fields_computed", "run_cache_corrupt")},
        "run_wall_time_s": sum(float(p.attrs["run_wall_time_s"]) for p in parts),
    })
    if failures:
        raise DOEFailed(failures, ds)
    return ds


def _run(study: Study, *, cache, workers, scheduler, console, path_solver, field_solver,
         only: list[tuple[float, float]] | None = None) -> xr.Dataset:
    """One DOE run; ``only``: solve just these (θ, H) paths and no field (NaN elsewhere)."""
    start = time.perf_counter()
    code = _code_attrs(path_solver, field_solver)  # the sources as they are when the run starts
    store = JobCache(cache) if cache is not None else None
    field_job, path_jobs = plan(study, path_solver, field_solver)
    if only is not None:
        path_jobs = [j for j in path_jobs if (j.theta, j.H) in set(only)]
    stats = RunStats(paths_total=len(path_jobs))
    results, field_entry, tasks = {}, None, []
    display = Display([*([field_job] if only is None else []), *path_jobs], console)
    for job in (*([field_job] if only is None else []), *path_jobs):
        entry = (store.get(job.kind, job.key, verify=functools.partial(verify_entry, job))
                 if store is not None else None)
        if entry is None:
            is_field = job is field_job
            tasks.append(Task(job, run_field if is_field else run_path,
                              (field_solver if is_field else path_solver,)))
            continue
        display.cached(job)
        if job is field_job:
            field_entry = entry
        else:
            results[job.key] = entry
            stats.paths_cached += 1
    stats.cache_corrupt = store.corrupt if store is not None else 0
    display.queue(len(tasks))
    with display:
        for job, outcome in execute(tasks, workers=workers, scheduler=scheduler,
                                    on_start=display.start):
            display.finish(job, outcome)
            if outcome.entry is None:
                error = outcome.error or ""
                if outcome.partial is not None:  # its levels before the failure are data
                    results[job.key] = outcome.partial
                    error += f" (its levels up to t = {outcome.partial.meta['t_reached']:.4g} kept)"
                stats.failures.append(JobFailure(job.label, error, outcome.detail))
                continue
            if store is not None:
                store.put(job.kind, job.key, outcome.entry)
            if job is field_job:
                field_entry = outcome.entry
                stats.fields_computed += 1
            else:
                results[job.key] = outcome.entry
                stats.paths_computed += 1
    attrs = {
        "complete": int(not stats.failures),
        "failed_jobs": "\n".join(f"{f.label}: {f.error}" for f in stats.failures),
        "run_paths_total": stats.paths_total,
        "run_paths_computed": stats.paths_computed,
        "run_paths_cached": stats.paths_cached,
        "run_fields_computed": stats.fields_computed,
        "run_cache_corrupt": stats.cache_corrupt,
        "run_wall_time_s": time.perf_counter() - start,
        "run_executor": _executor_name(workers, scheduler),
        **code,
    }
    ds = assemble(study, field_job, field_entry, path_jobs, results, attrs)
    if stats.failures:
        raise DOEFailed(stats.failures, ds)
    return ds


def _executor_name(workers: int | None, scheduler: str | None) -> str:
    if scheduler is not None:
        return f"dask.distributed scheduler {scheduler}"
    if workers == 0:
        return "in process"
    return f"{workers or default_workers()} local worker processes"


def _code_attrs(path_solver, field_solver) -> dict:
    """Solver names, the model versions that enter the cache keys, and the source revision."""
    path = solver_identity(path_solver, PATH_MODEL)
    field = solver_identity(field_solver, FIELD_MODEL)
    try:
        rev = subprocess.run(["git", "describe", "--always", "--dirty", "--abbrev=12"],
                             cwd=Path(__file__).parent, capture_output=True, text=True,
                             timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        rev = ""
    return {"path_solver_function": path["name"],
            "path_model_version": str(path["model_version"]),
            "field_solver_function": field["name"],
            "field_model_version": str(field["model_version"]),
            "source_revision": rev or "unknown (not a git checkout)"}
