"""The jobs of a design of experiments, their cache keys, and the functions workers run.

Two kinds of job (docs/method.md §4):

* a **path** job: one structural loading path at (θ, H) through every t level, solved at the
  reference modulus ``G_ref`` and scaled to each G level (or, with
  ``mechanics.scale_in_G = false``, one job per (θ, H, G));
* the **field** job: the Hall reading B over the whole (t, θ, H) grid (the field does not depend
  on the deformation, so it is one cheap job).

A job's key is the SHA-256 of a canonical JSON text of every input that can change its result:
the study settings it reads (in SI), its own levels, the solver's name and model version
(``magtact.mechanics.MODEL_VERSION``, ``magtact.magnetics.MODEL_VERSION``, bumped by hand when a
change alters results; editing a comment does not invalidate the cache) and the major.minor
versions of the numerical libraries that compute the job (policy: :mod:`magtact._versions`).
Settings a job does not read (the other levels, the design ranges, the
constraints, ``theta_max`` and, for path jobs, the G levels) are left out, so changing them reuses
the cached jobs.

The functions :func:`run_path` and :func:`run_field` run in the workers (local processes or
dask); they never raise for a failed solve but return a :class:`Outcome` holding the error.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import time
import traceback
from dataclasses import dataclass

import numpy as np

from .._versions import FIELD, MECHANICS, key_versions
from ..study import Study, kpa, mm
from ._cache import Entry

#: Arrays a path result must provide, each of shape (n_t,): SI units.
PATH_ARRAYS = ("t", "u_r", "u_z", "F_r", "F_z")
#: Scalars a path result must provide (beyond the arrays).
PATH_SCALARS = ("G", "newton_iterations", "cutbacks", "wall_time", "n_dofs", "n_cells")
#: magtact sub-package whose MODEL_VERSION is part of a path (resp. field) job's key.
PATH_MODEL = "mechanics"
FIELD_MODEL = "magnetics"


@dataclass(frozen=True)
class PathJob:
    """One structural path: (θ, H) [rad, m] through the levels ``t``; ``G`` [Pa] or ``None``.

    ``G = None`` means solved at ``study.material.G_ref`` and scaled to every G level.
    """

    study: Study
    theta: float
    H: float
    G: float | None
    t: tuple[float, ...]
    key: str

    kind = "path"

    @property
    def label(self) -> str:
        """Short human-readable name, in user units."""
        g = "" if self.G is None else f", G={kpa(self.G):.4g} kPa"
        return f"path θ={self.theta:.4f} rad, H={mm(self.H):.4g} mm{g}"


@dataclass(frozen=True)
class FieldJob:
    """The Hall reading over the grid ``t`` × ``theta`` × ``H`` with the named field solver."""

    study: Study
    t: tuple[float, ...]
    theta: tuple[float, ...]
    H: tuple[float, ...]
    solver: str
    key: str

    kind = "field"

    @property
    def label(self) -> str:
        """Short human-readable name."""
        return f"field B ({self.solver}, {len(self.t)}×{len(self.theta)}×{len(self.H)} points)"


@dataclass(frozen=True)
class Outcome:
    """What a worker returns: a cache entry, or the error that stopped the job."""

    entry: Entry | None
    error: str | None = None
    detail: str = ""
    wall_time: float = 0.0
    #: a failed path's levels before the failure (NaN beyond): data, never cached
    partial: Entry | None = None


# ---- keys ---------------------------------------------------------------------------------------
def solver_identity(func, package: str) -> dict:
    """Name and model version of a solver function.

    The version is the function's own ``model_version`` attribute if it has one, else the
    ``MODEL_VERSION`` of the magtact sub-package ``package`` when the function belongs to it;
    a solver from elsewhere is identified by its name (and ``model_version`` if it sets one).
    """
    import importlib

    name = f"{func.__module__}.{func.__qualname__}"
    version = getattr(func, "model_version", None)
    if version is None and func.__module__.startswith(f"magtact.{package}"):
        version = importlib.import_module(f"magtact.{package}").MODEL_VERSION
    return {"name": name, "model_version": version}


def digest(payload: dict) -> str:
    """The cache key of a canonical JSON payload (floats written exactly)."""
    text = json.dumps(payload, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:40]


#: Material settings the quasi-static structural path does not read (the viscoelastic budget's).
RELAXATION_FIELDS = ("relaxation_g1", "relaxation_tau1", "relaxation_g2", "relaxation_tau2")


def _section(study: Study, name: str, drop: tuple[str, ...] = ()) -> dict:
    d = dataclasses.asdict(getattr(study, name))
    return {k: v for k, v in d.items() if k not in drop}


def path_key_inputs(study: Study, solver: dict) -> dict:
    """Everything except the job's own levels that a path job's result depends on."""
    return {
        "kind": "path",
        "solver": solver,
        "versions": key_versions(MECHANICS),
        "body": _section(study, "body"),
        "magnet": _section(study, "magnet"),
        "loading": _section(study, "loading", drop=("theta_max",)),
        # the quasi-static path reads the long-term (relaxed) material: the relaxation's
        # Prony terms change no path, so they do not invalidate the cached paths
        "material": _section(study, "material", drop=RELAXATION_FIELDS),
        "mechanics": _section(study, "mechanics"),
    }


def field_key_inputs(study: Study, solver: dict) -> dict:
    """Everything except the grid that the field job's result depends on."""
    return {
        "kind": "field",
        "solver": solver,
        "versions": key_versions(FIELD),
        "body": _section(study, "body"),
        "magnet": _section(study, "magnet"),
        "loading": _section(study, "loading", drop=("theta_max", "mu_f")),
        "magnetics": _section(study, "magnetics"),
    }


def plan(study: Study, path_solver, field_solver) -> tuple[FieldJob, list[PathJob]]:
    """The field job and the path jobs of ``study`` (θ-major, then H, then G), with their keys."""
    t = tuple(float(x) for x in study.t_levels)
    thetas = tuple(float(x) for x in study.theta_levels)
    Hs = tuple(float(x) for x in study.H_levels)
    p_inputs = path_key_inputs(study, solver_identity(path_solver, PATH_MODEL))
    Gs: tuple[float | None, ...] = (
        (None,) if study.mechanics.scale_in_G else tuple(float(x) for x in study.G_levels))
    paths = []
    for theta in thetas:
        for H in Hs:
            for G in Gs:
                key = digest({**p_inputs, "theta": theta, "H": H, "G": G, "t": t})
                paths.append(PathJob(study, theta, H, G, t, key))
    solver = study.magnetics.solver
    f_inputs = field_key_inputs(study, solver_identity(field_solver, FIELD_MODEL))
    fkey = digest({**f_inputs, "solver_name": solver, "t": t, "theta": thetas, "H": Hs})
    return FieldJob(study, t, thetas, Hs, solver, fkey), paths


# ---- worker functions ---------------------------------------------------------------------------
def _plain(value):
    """A JSON-safe copy of a scalar or array metadata value."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


def path_entry(job: PathJob, result) -> Entry:
    """Check a path solver's result against the job and turn it into a cache entry.

    Raises ``ValueError`` if an array is missing, has the wrong shape, is not finite, or if the
    result is for other levels than the job's.
    """
    n = len(job.t)
    arrays = {}
    for name in PATH_ARRAYS:
        a = np.asarray(getattr(result, name), dtype=float)
        if a.shape != (n,):
            raise ValueError(f"path result {name!r} has shape {a.shape}, expected ({n},)")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"path result {name!r} is not finite")
        arrays[name] = a
    if not np.allclose(arrays["t"], job.t, rtol=0, atol=1e-12):
        raise ValueError("path result is at other t levels than requested")
    meta = {name: _plain(getattr(result, name)) for name in PATH_SCALARS}
    meta["mesh"] = str(getattr(result, "mesh", ""))
    if not (np.isfinite(meta["G"]) and meta["G"] > 0):
        raise ValueError(f"path result has G = {meta['G']!r}, expected a positive modulus")
    return Entry(arrays=arrays, meta=meta)


def partial_entry(job: PathJob, result) -> Entry:
    """The entry of a path that failed after reaching the first levels of ``job.t``: those
    levels' values, NaN beyond (checked as :func:`path_entry` checks a whole path)."""
    k = len(result.t)
    if not 0 < k < len(job.t):
        raise ValueError(f"a partial path has {k} levels, expected 1 to {len(job.t) - 1}")
    short = PathJob(job.study, job.theta, job.H, job.G, job.t[:k], job.key)
    entry = path_entry(short, result)
    pad = np.full(len(job.t) - k, np.nan)
    arrays = {name: np.concatenate([a, pad]) for name, a in entry.arrays.items()}
    arrays["t"] = np.asarray(job.t, dtype=float)
    return Entry(arrays=arrays, meta={**entry.meta, "t_reached": float(job.t[k - 1])})


def verify_entry(job: PathJob | FieldJob, entry: Entry) -> None:
    """Check that a cache entry holds what ``job`` produces: every array with the job's shape,
    finite, and (for a path) its scalars with a positive modulus.

    Raises
    ------
    ValueError
        Naming the first array or scalar that is missing, misshapen or not finite.
    """
    if isinstance(job, FieldJob):
        shape = (len(job.t), len(job.theta), len(job.H))
        names = ("B_r", "B_z")
    else:
        shape = (len(job.t),)
        names = PATH_ARRAYS
    for name in names:
        if name not in entry.arrays:
            raise ValueError(f"array {name!r} is missing")
        a = entry.arrays[name]
        if a.shape != shape or a.dtype.kind not in "fi":
            raise ValueError(f"array {name!r} has shape {a.shape} and type {a.dtype}, expected "
                             f"numbers of shape {shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"array {name!r} holds non-finite values")
    if isinstance(job, PathJob):
        if not np.allclose(entry.arrays["t"], job.t, rtol=0, atol=1e-12):
            raise ValueError("the entry is at other t levels than the job")
        for name in PATH_SCALARS:
            value = entry.meta.get(name)
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ValueError(f"scalar {name!r} is missing or not a number")
            if not np.isfinite(value):
                raise ValueError(f"scalar {name!r} is not finite")
        if not entry.meta["G"] > 0:
            raise ValueError(f"scalar 'G' is {entry.meta['G']!r}, expected a positive modulus")


def run_path(job: PathJob, path_solver) -> Outcome:
    """Solve one path job (in a worker); errors are returned, not raised."""
    start = time.perf_counter()
    try:
        result = path_solver(job.study, job.H, job.theta, G=job.G, t=np.asarray(job.t))
        entry = path_entry(job, result)
    except Exception as exc:
        wall = time.perf_counter() - start
        partial = None
        if getattr(exc, "partial", None) is not None:  # a path that stopped part of the way
            try:
                partial = partial_entry(job, exc.partial)
                partial.meta["job_wall_time"] = wall
            except Exception:  # a malformed partial result: the failure alone is reported
                partial = None
        return Outcome(None, f"{type(exc).__name__}: {exc}", traceback.format_exc(), wall,
                       partial)
    wall = time.perf_counter() - start
    entry.meta["job_wall_time"] = wall
    return Outcome(entry, wall_time=wall)


def run_field(job: FieldJob, field_solver) -> Outcome:
    """Compute the field job (in a worker); errors are returned, not raised."""
    start = time.perf_counter()
    try:
        T, TH, HH = np.meshgrid(job.t, job.theta, job.H, indexing="ij")
        B_r, B_z = (np.asarray(b, dtype=float)
                    for b in field_solver(job.study, T, TH, HH, solver=job.solver))
        for name, b in (("B_r", B_r), ("B_z", B_z)):
            if b.shape != T.shape:
                raise ValueError(f"field {name} has shape {b.shape}, expected {T.shape}")
            if not np.all(np.isfinite(b)):
                raise ValueError(f"field {name} is not finite")
    except Exception as exc:
        return Outcome(None, f"{type(exc).__name__}: {exc}", traceback.format_exc(),
                       time.perf_counter() - start)
    wall = time.perf_counter() - start
    return Outcome(Entry({"B_r": B_r, "B_z": B_z}, {"job_wall_time": wall}), wall_time=wall)
