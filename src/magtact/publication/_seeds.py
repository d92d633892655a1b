"""The seed study: how much of each answer belongs to the sensor and how much to the GP's seed.

For each sensitivity definition and each seed, the force models are refitted (field models
fixed), and the figures the publication reports are recomputed: held-out accuracy, the worst
sensitivities of the original design, the chosen design under the default constraints and under
the constraints of the original design (exact reduction and decision rule), the number of
branches of the Pareto set, and Γ_z along the path at the tallest height and θ_max. Fits run in
worker processes, one (definition, seed) each.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
import tomllib
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import replace
from pathlib import Path

import numpy as np

from .._errors import MagtactError
from .._files import write_json
from ..study import Study, from_si, study_from_dict
from . import _reference as published
from ._file import (
    ChosenRow,
    Conditioning,
    DesignRow,
    FitAccuracy,
    GammaZCurve,
    Resolution,
    SeedRecord,
    Sweep,
)

#: Sensitivity definitions compared.
DEFINITIONS = ("jacobian", "published")
#: Points along t of the Γ_z curve at the tallest height.
N_T_CURVE = 41


def seed_study(study: Study, ds, models_dir: str | Path, *, seeds: Sequence[int],
               definitions: Sequence[str] = DEFINITIONS, workers: int | None = None,
               data_path: str | Path | None = None, sweep_n: int = 201,
               cache: str | Path | None = None,
               log: Callable[[str], None] | None = None) -> list[dict]:
    """Refit the force models with every seed under every definition and measure each fit.

    Parameters
    ----------
    study : Study
    ds : xarray.Dataset
        The DOE data set (used in this process only to check it; workers read ``data_path``).
    models_dir : path
        Folder of a model set whose field models (``B_r.json``, ``B_z.json``) every fit uses.
    seeds : sequence of int
        GP seeds (each fit uses one seed, no retries, so that seeds are independent samples).
    definitions : sequence of {"jacobian", "published"}
    workers : int, optional
        Worker processes (default: the number of cores); each GP runs on one thread.
    data_path : path, optional
        The data set file the workers load; None: the bundled MagOne data set.
    sweep_n : int
        Heights of the exact reduction's sweep per fit.
    cache : path, optional
        Folder where each finished record is kept (keyed by the study, data, field models and
        settings), so that an interrupted study resumes and a repeated one is instant.
    log : callable, optional
        Progress messages (one per finished fit).

    Returns
    -------
    list of dict
        One record per (definition, seed), in that order; see :func:`_measure` for the keys.

    Raises
    ------
    ValueError
        For an empty seed list or an unknown definition.
    """
    seeds = [int(s) for s in seeds]
    if not seeds:
        raise MagtactError("--seeds must be at least 1")
    for d in definitions:
        if d not in DEFINITIONS:
            raise MagtactError(f"[sensitivity] definition must be one of {list(DEFINITIONS)}, "
                             f"got {d!r}")
    jobs = [(d, s) for d in definitions for s in seeds]
    args = dict(study_toml=study.to_toml(), models_dir=str(models_dir),
                data_path=None if data_path is None else str(data_path), sweep_n=sweep_n)
    key = _key(args, ds, models_dir)
    records: dict[tuple[str, int], dict] = {}
    for d, s in jobs:  # records of an earlier, possibly interrupted, run of the same study
        rec = _cached(cache, key, d, s)
        if rec is not None:
            records[(d, s)] = rec
    todo = [j for j in jobs if j not in records]
    if log and records:
        log(f"{len(records)} of {len(jobs)} fits from {cache}")

    def done(job, rec):
        records[job] = rec
        _store(cache, key, *job, rec)
        if log:
            log(_line(rec, len(records), len(jobs)))

    workers = max(1, min(workers or os.cpu_count() or 1, max(len(todo), 1)))
    if workers == 1:
        for d, s in todo:
            done((d, s), _measure(definition=d, seed=s, **args))
    elif todo:
        with ProcessPoolExecutor(max_workers=workers) as pool:
            futures = {pool.submit(_measure, definition=d, seed=s, **args): (d, s)
                       for d, s in todo}
            for fut in as_completed(futures):
                done(futures[fut], fut.result())
    return [records[j] for j in jobs]


#: Version of a seed-study record; bump it when what a record holds or how it is measured
#: changes, so that cached records of the old kind are not reused.
RECORD_VERSION = 2


def _key(args: dict, ds, models_dir) -> str:
    """Hash of everything a record depends on: study, data, field models, settings."""
    from ..metamodel import data_hash

    h = hashlib.sha256()
    h.update(json.dumps({k: v for k, v in args.items() if k != "models_dir"},
                        sort_keys=True).encode())
    h.update(data_hash(ds).encode())
    for name in ("B_r.json", "B_z.json"):
        h.update((Path(models_dir) / name).read_bytes())
    h.update(str(RECORD_VERSION).encode())
    return h.hexdigest()[:16]


def _cache_file(cache, key: str, definition: str, seed: int) -> Path:
    return Path(cache) / f"{definition}-{seed}-{key}.json"


def _cached(cache, key, definition, seed) -> dict | None:
    if cache is None:
        return None
    path = _cache_file(cache, key, definition, seed)
    try:
        rec = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    r = SeedRecord.from_json(rec)
    return rec if r is not None and (r.definition, r.seed) == (definition, seed) else None


def _store(cache, key, definition, seed, rec) -> None:
    if cache is None:
        return
    write_json(_cache_file(cache, key, definition, seed), rec, allow_nan=True)


def _line(doc: dict, done: int, total: int) -> str:
    rec = SeedRecord.from_json(doc)
    head = f"[{done}/{total}] {rec.definition} seed {rec.seed}"
    if not rec.ok:
        return f"{head}: {rec.message}"
    return (f"{head}: fit {rec.fit_time_s:.0f} s; original design Γ_r,max "
            f"{rec.original.Gamma_r_max:.3g}, Γ_z,max {rec.original.Gamma_z_max:.3g}"
            f" N/T; H* {from_si(rec.chosen.H, 'mm'):.3g} mm")


def _measure(*, study_toml: str, models_dir: str, data_path: str | None, definition: str,
             seed: int, sweep_n: int) -> dict:
    """Fit the forces with one seed under one definition and measure the figures (a worker).

    Returns the document of a :class:`magtact.publication.SeedRecord`: held-out accuracy of
    f_r, f_z, the original and fabricated designs, the chosen design under the default
    constraints and under those of the original design (or why none; under the default ones
    with σ_F with the study's Hall chip where its noise is known), the Pareto branches of the
    exact reduction, Γ_z along t at the largest H, θ_max, G of the original design and its
    trend, the per-unit-G extrema over H and the stable-shear bound's conditioning.
    """
    from ..doe import load_bundled, load_dataset
    from ..metamodel import fit_models, load_field_models
    from ..optimise import (
        ForceConstraints,
        InfeasibleError,
        decision_index,
        exact_reduction,
        force_constraints,
        heights_batch,
        shear_bound_conditioning,
        sweep,
    )
    from ..sensitivity import Responses, gamma

    study = study_from_dict(tomllib.loads(study_toml))
    study = replace(study,
                    metamodel=replace(study.metamodel, seed=seed, retries=0, threads=1),
                    sensitivity=replace(study.sensitivity, definition=definition),
                    optimise=replace(study.optimise, sweep_n=sweep_n,
                                     sweep_coarse=min(study.optimise.sweep_coarse, sweep_n)))
    ds = load_dataset(data_path) if data_path else load_bundled()
    field_models = load_field_models(models_dir)
    t0 = time.perf_counter()
    try:
        fit = fit_models(ds, study, definition=definition, field_models=field_models)
    except RuntimeError as exc:  # every try failed the guard rails
        return SeedRecord(definition, seed, False,
                          f"no model passed the guard rails: {exc}").to_json()
    fit_time = time.perf_counter() - t0
    accuracy = {k: FitAccuracy(r.test.max_abs_err_over_range, r.test.r2) if r.test else None
                for k, r in fit.reports.items()}
    models = fit.model_set(study)
    R = Responses(models)
    d = study.design
    # batched per-height extrema (projected Newton, checked against an evolution + trust-region
    # method in the tests): the seed study needs many designs, not the last digit of each
    H_fab = min(max(published.H_FABRICATED, d.H[0]), d.H[1])  # within the study's bounds
    designs = heights_batch(R, [d.H_original, H_fab], study)
    original = _row(designs, 0, d.G_original)
    table = sweep(R, study)
    reference = ForceConstraints(original.F_r_min, original.F_z_max, "reference")
    chosen, branches = [], []
    for c in (force_constraints(R, study), reference):
        try:
            red = exact_reduction(R, study, c, table)
        except InfeasibleError as exc:
            chosen.append(ChosenRow(infeasible=str(exc)))
            branches.append(0)
            continue
        idx = np.flatnonzero(red.front)
        k = int(idx[decision_index(np.stack([red.Gamma_r[idx], red.Gamma_z[idx]], axis=1))])
        row = _row(table, k, red.G_star[k])
        g_r, g_z = c.margins(row.F_r_min, row.F_z_max)
        rtol = study.optimise.active_rtol
        active = tuple(n for n, g, lim in (("F_r", g_r, c.F_r_c), ("F_z", g_z, c.F_z_c))
                       if abs(g) <= rtol * abs(lim))
        sigma = _resolution(models, study, table.H[k], red.G_star[k]) if not chosen else None
        chosen.append(ChosenRow(**vars(row), active=active, F_r_c=c.F_r_c, F_z_c=c.F_z_c,
                                resolution=sigma))
        branches.append(count_branches(red.front))
    cond = shear_bound_conditioning(R, study, np.linspace(*d.H, 21))
    tt = np.linspace(0.0, 1.0, N_T_CURVE)
    gz = gamma(models, tt, study.loading.theta_max, d.H[1], d.G_original)[1]
    return SeedRecord(
        definition, seed, True, "", fit_time, accuracy, original,
        _row(designs, 1, d.G_original),
        Sweep(table.H, table.gamma_r_max, table.gamma_z_max, table.f_r_min, table.f_z_max,
              table.t_m),
        chosen[0], branches[0], chosen[1], branches[1],
        Conditioning(cond.H, cond.tol, cond.t_m, cond.t_tol, cond.dF_z_rel),
        GammaZCurve(tt, np.asarray(gz), d.H[1], study.loading.theta_max),
        trend(gz)).to_json()


def _resolution(models, study: Study, H: float, G: float) -> Resolution | None:
    """σ_F of design (H, G) with the study's chip, or None if its noise is not known."""
    from ..designer import resolution
    from ..optimise import per_design
    from ..study import hall_chip

    chip = hall_chip(study)
    if chip.noise is None:
        return None
    r = resolution(models, study, per_design(models, float(H), float(G), study), chip)
    return Resolution(r.sigma_r_0, r.sigma_r_worst, r.sigma_z_0, r.sigma_z_worst)


def _row(table, k: int, G: float) -> DesignRow:
    """Design k of a per-height table at shear modulus G [Pa]."""
    return DesignRow(float(table.H[k]), float(G), float(G * table.gamma_r_max[k]),
                     float(G * table.gamma_z_max[k]), float(G * table.f_r_min[k]),
                     float(G * table.f_z_max[k]), float(table.t_m[k]),
                     float(table.theta_m[k]))


def count_branches(front: np.ndarray) -> int:
    """Number of maximal runs of consecutive True in ``front`` (branches of a Pareto set
    sampled on a sweep)."""
    f = np.asarray(front, dtype=bool).astype(int)
    return int(np.sum(np.diff(np.concatenate([[0], f])) == 1))


def trend(y, rtol: float = 1e-9) -> str:
    """``"increasing"``, ``"decreasing"``, ``"constant"`` or ``"mixed"`` for a sampled curve."""
    d = np.diff(np.asarray(y, dtype=float))
    tol = rtol * max(float(np.max(np.abs(y))), 1e-300)
    up, down = np.any(d > tol), np.any(d < -tol)
    return "mixed" if up and down else "increasing" if up else "decreasing" if down \
        else "constant"
