"""The magnet-size design space: its DOE, and surrogates across magnet sizes checked on sizes
they never saw.

``bench/magtact_sizes.toml``: the MagOne body over H 2-10 mm (4 levels) with magnets of
diameter 3, 4, 5, 6 mm and height 1, 2, 3 mm (12 sizes), 3 theta levels of structural paths,
default mesh, G by its exact scaling: 144 paths. It shares the job cache of the broad study
(``bench/results/broad_cache``, committed), so the four corner sizes are not solved again and an
interrupted DOE resumes where it stopped.

Steps (each writes its part of ``bench/results/sizes.json``)::

    nohup python bench/bench_sizes.py doe --workers 1 --first 5x2,4x1,4x2 > sizes_doe.log 2>&1 &
    python bench/bench_sizes.py status       # paths cached of the 144, their solver time
    python bench/bench_sizes.py ship 3x2     # a finished size's data set and fit, shipped
    python bench/bench_sizes.py surrogate    # models across sizes, held-out sizes measured
    python bench/bench_sizes.py surrogate --cached --models rbf,kriging   # before the DOE ends

The 2 mm-high sizes over H 2-10 mm at 7 levels instead of 4 (``bench/magtact_sizes_fine_h.toml``,
the same cache: only the 3 new levels are solved), fitted but not shipped, and their blend for
the 5 x 2 mm magnet measured on the MagOne data::

    nohup python bench/bench_sizes.py fine-h-doe 4x2,6x2,3x2 > fine_h_doe.log 2>&1 &
    python bench/bench_sizes.py fine-h 4x2,6x2,3x2   # data and fits, bench/results/sizes_fine_h
    python bench/bench_sizes.py fine-h-blend
    python bench/bench_sizes.py fine-h-ship 4x2,6x2,3x2   # into the package, replacing 4 heights
    nohup python bench/bench_sizes.py fine-h-doe 4x2,6x2,3x2 --angles 5 > fine_ht.log 2>&1 &

``doe --first`` solves the named sizes' paths first (one sub-DOE each, through the same cache),
then runs ``magtact doe`` on the whole study, which finds them cached.

``surrogate`` fits f_z = F_z / G and f_r = F_r / G over (t, theta, H, R_m, H_m) on every size but
the held-out ones (the MagOne 5 x 2 mm magnet and a 4 x 3 mm magnet) and measures each model on
(a) the held-out sizes' paths of this DOE and (b) the bundled MagOne data set (5 x 2 mm, H 3-7 mm
at 5 levels and 5 theta levels: an independent DOE at other H and theta levels). The error is the
largest |error| over the points of a size as a fraction of that size's force range. Models:

- ``kriging``: SMT's ordinary kriging (squared-exponential correlation, constant trend) in the
  features (p, q, H, R_m, H_m) = (t, t tan theta, ...) scaled to [0, 1]; f_r (odd in theta) as
  q times a kriging of f_r / q over (p, q^2, H, R_m, H_m);
- ``rbf``: SciPy's thin-plate-spline radial basis interpolation in the same scaled features
  (the simplest interpolator, a floor any model must beat);
- ``gp``: magtact's genetic-programming fit (:func:`magtact.metamodel` ``fit_response``) with
  the same training points and anchoring transforms as a shipped fit, and a reduced budget.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RESULTS = HERE / "results"
STUDY = HERE / "magtact_sizes.toml"
#: FE paths of a 4 x 1.5 mm magnet (``magtact doe bench/magtact_4x1p5.toml --out
#: bench/results/size_check/doe --cache bench/results/size_check/cache``), a height between the
#: shipped sizes': the check of the blend along the height.
HEIGHT_CHECK = RESULTS / "size_check" / "doe" / "doe.nc"
DOE_DIR = RESULTS / "sizes_doe"
CACHE = RESULTS / "broad_cache"
OUT = RESULTS / "sizes.json"
#: Magnet sizes held out of every fit: (radius, height) [m].
HELD_OUT = ((2.5e-3, 2.0e-3), (2.0e-3, 3.0e-3))


def _update(section: str, values: dict, key: str | None = None) -> None:
    """Set ``section`` of the record to ``values`` (with ``key``: only that entry of the
    section), the file read and written under a lock: steps of this bench run side by side
    (a fit of one size while another's DOE runs), and each keeps the others' entries."""
    import fcntl

    with open(OUT.with_suffix(".lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        out = json.loads(OUT.read_text()) if OUT.is_file() else {}
        out.update({"benchmark": "the magnet-size design space",
                    "study": str(STUDY.relative_to(ROOT)),
                    "machine": {"cpus": os.cpu_count(), "platform": platform.platform(),
                                "python": platform.python_version()}})
        if key is None:
            out[section] = values
        else:
            out.setdefault(section, {})[key] = values
        OUT.write_text(json.dumps(out, indent=1) + "\n")


def _label(R_m: float, H_m: float) -> str:
    return f"{2e3 * R_m:g} x {1e3 * H_m:g} mm"


def _doe_file() -> Path:
    full = DOE_DIR / "doe.nc"
    return full if full.is_file() else DOE_DIR / "doe_partial.nc"


def _cache_paths() -> int:
    return len(list((CACHE / "path").glob("*.mtc")))


def _size(text: str) -> dict[str, float]:
    """``"5x2"`` (diameter x height [mm]) as the study's geometric variables [m]."""
    d, h = (float(v) for v in text.lower().split("x"))
    return {"R_m": d / 2e3, "H_m": h / 1e3}


def status() -> dict:
    """How many of the study's paths the cache holds, per magnet size, and their solver time."""
    import itertools

    from magtact import study as mstudy
    from magtact.doe._cache import JobCache
    from magtact.doe._jobs import plan
    from magtact.magnetics import hall_field
    from magtact.mechanics import simulate_path

    study = mstudy.load_study(STUDY)
    cache = JobCache(CACHE)
    levels = study.geometry_levels
    sizes, total, cached, wall = {}, 0, 0, 0.0
    for values in itertools.product(*levels.values()):
        geometry = dict(zip(levels, (float(v) for v in values), strict=True))
        _, jobs = plan(study.at(**geometry), simulate_path, hall_field)
        entries = [cache.get("path", j.key) for j in jobs]
        done = [e for e in entries if e is not None]
        sizes[_label(geometry["R_m"], geometry["H_m"])] = f"{len(done)}/{len(jobs)}"
        total += len(jobs)
        cached += len(done)
        wall += sum(float(e.meta["job_wall_time"]) for e in done)
    out = {"command": "python bench/bench_sizes.py status", "paths_total": total,
           "paths_cached": cached, "path_job_wall_time_s_sum": wall,
           "path_job_wall_time_s_mean": wall / max(cached, 1), "per_size": sizes}
    _update("status", out)
    print(json.dumps(out, indent=1))
    return out


def doe(workers: int, first: list[str]) -> None:
    """Run (or resume) the DOE through the committed job cache and record its cost."""
    import xarray as xr

    from magtact import study as mstudy
    from magtact.doe import run_doe
    from magtact.doe._run import DOEFailed

    before = _cache_paths()
    study = mstudy.load_study(STUDY)
    record = json.loads(OUT.read_text()).get("doe_runs", []) if OUT.is_file() else []
    run = {"started": time.strftime("%Y-%m-%d %H:%M:%S"), "workers": workers,
           "cache_paths_at_start": before, "sizes": {}}
    record.append(run)
    for text in first:
        start = time.perf_counter()
        try:
            ds = run_doe(study.at(**_size(text)), cache=CACHE, workers=workers)
            failed = 0
        except DOEFailed as exc:  # stalled paths are retried by the whole run below
            ds, failed = exc.dataset, len(exc.failures)
        # what an interrupted run left is found in the cache: cached paths are not solved again
        run["sizes"][text] = {"paths_cached": int(ds.attrs["run_paths_cached"]),
                              "paths_computed": int(ds.attrs["run_paths_computed"]),
                              "paths_failed": failed,
                              "wall_time_s": time.perf_counter() - start,
                              "load_average_at_end": os.getloadavg()}
        _update("doe_runs", record)
        print(f"{text}: {run['sizes'][text]}", flush=True)
    cmd = [sys.executable, "-m", "magtact", "doe", str(STUDY), "--out", str(DOE_DIR),
           "--workers", str(workers), "--cache", str(CACHE)]
    load = os.getloadavg()
    start = time.perf_counter()
    proc = subprocess.run(cmd, cwd=ROOT)
    wall = time.perf_counter() - start
    data = _doe_file()
    if not data.is_file():
        raise SystemExit(f"magtact doe failed (exit {proc.returncode}) and left no data set")
    with xr.open_dataset(data) as ds:
        attrs = dict(ds.attrs)
    jobs = [j for j in json.loads(attrs["jobs"]) if "job_wall_time" in j]
    _update("doe", {
        "command": f"python bench/bench_sizes.py doe --workers {workers}",
        "workers": workers, "wall_time_s": wall, "load_average_at_start": load,
        "load_average_at_end": os.getloadavg(),
        "paths_total": int(attrs["run_paths_total"]),
        "paths_computed": int(attrs["run_paths_computed"]),
        "paths_cached": int(attrs["run_paths_cached"]),
        "cache_paths_before": before, "cache_paths_after": _cache_paths(),
        "path_job_wall_time_s_sum": sum(j["job_wall_time"] for j in jobs),
        "failed_jobs": [j for j in attrs.get("failed_jobs", "").splitlines() if j],
        "complete": int(attrs.get("complete", 0)),
        "dataset": str(data.relative_to(ROOT)),
    })
    print(f"DOE: {wall:.0f} s -> {data}")


# ---- the data as points ------------------------------------------------------------------------
def _points(ds, dims: tuple[str, ...]) -> dict[str, np.ndarray]:
    """Every grid point of ``ds`` over ``dims`` [SI] with f_r, f_z = F / G [N/Pa] (mean over
    the G levels: the forces are exactly proportional to G)."""
    grids = np.meshgrid(*(ds[d].values.astype(float) for d in dims), indexing="ij")
    out = {d: g.ravel() for d, g in zip(dims, grids, strict=True)}
    G = ds["G"].values.astype(float)
    for k in ("r", "z"):
        F = ds[f"F_{k}"].transpose(*dims, "G").values.astype(float)
        out[f"f_{k}"] = (F / G).mean(axis=-1).ravel()
    return out


def sizes_table(ds) -> dict[str, np.ndarray]:
    """Every finite point of the sizes DOE: t, theta, H, R_m, H_m [SI] and f_r, f_z [N/Pa]."""
    out = _points(ds, ("t", "theta", "H", "R_m", "H_m"))
    keep = np.isfinite(out["f_r"]) & np.isfinite(out["f_z"])
    return {k: v[keep] for k, v in out.items()}


def magone_table() -> dict[str, np.ndarray]:
    """The bundled MagOne data set (5 x 2 mm magnet) as points of the same form."""
    import xarray as xr

    from magtact.doe import bundled_path

    with xr.open_dataset(bundled_path()) as ds:
        out = _points(ds, ("t", "theta", "H"))
    out["R_m"] = np.full_like(out["t"], 2.5e-3)
    out["H_m"] = np.full_like(out["t"], 2.0e-3)
    return out


def _features(table: dict) -> np.ndarray:
    t, th = table["t"], table["theta"]
    return np.column_stack([t, t * np.tan(th), table["H"], table["R_m"], table["H_m"]])


class Scaled:
    """Scale the feature columns to [0, 1] over the training data's box."""

    def __init__(self, X: np.ndarray):
        self.lo, self.hi = X.min(axis=0), X.max(axis=0)

    def __call__(self, X: np.ndarray) -> np.ndarray:
        return (X - self.lo) / np.where(self.hi > self.lo, self.hi - self.lo, 1.0)


def _mirror(X: np.ndarray, y: np.ndarray, name: str) -> tuple[np.ndarray, np.ndarray]:
    """f_r is odd in q (θ → −θ): add the mirrored points so an interpolator vanishes on the
    axis; f_z is even: its mirror adds nothing the (q >= 0) queries use."""
    if name != "f_r":
        return X, y
    Xm = X.copy()
    Xm[:, 1] = -Xm[:, 1]
    off = X[:, 1] > 0
    return np.vstack([X, Xm[off]]), np.concatenate([y, -y[off]])


def _unique(X: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One point per feature vector (every θ gives p = q = 0 at t = 0): an interpolator's
    system is singular with repeated points."""
    Xu, inverse = np.unique(X, axis=0, return_inverse=True)
    return Xu, np.bincount(inverse.ravel(), weights=y) / np.bincount(inverse.ravel())


def fit_kriging(X, y, name):
    """SMT's ordinary kriging. f_r is odd in q: it is kriged as f_r / q over (p, q², H, R_m,
    H_m) on the points with q > 0 and predicted as q times that (zero on the axis, exactly),
    which keeps the system as small as f_z's (mirroring the points would double it and cost
    eight times the time)."""
    from smt.surrogate_models import KRG

    odd = name == "f_r"

    def features(Z):
        return np.column_stack([Z[:, 0], Z[:, 1] ** 2, Z[:, 2:]]) if odd else Z

    if odd:
        keep = X[:, 1] > 0
        X, y = X[keep], y[keep] / X[keep, 1]
    X, y = _unique(features(X), y)
    scale = Scaled(X)
    model = KRG(print_global=False, corr="squar_exp", poly="constant", n_start=1, seed=0,
                nugget=1e-10)
    model.set_training_values(scale(X), y)
    model.train()

    def predict(Z):
        g = model.predict_values(scale(features(Z))).ravel()
        return Z[:, 1] * g if odd else g
    return predict


def fit_rbf(X, y, name):
    from scipy.interpolate import RBFInterpolator

    X, y = _unique(*_mirror(X, y, name))
    scale = Scaled(X)
    rbf = RBFInterpolator(scale(X), y, kernel="thin_plate_spline", degree=1)
    return lambda Z: rbf(scale(Z))


def fit_gp(train: dict, name: str):
    """magtact's GP fit of one force response over (t, θ, H, R_m, H_m) on ``train``."""
    import dataclasses

    from magtact import study as mstudy
    from magtact.metamodel._fit import fit_response

    study = mstudy.load_study(STUDY)
    settings = dataclasses.replace(study.metamodel, generations=100, population=500,
                                   max_length=60)
    table = dict(train)
    for k in ("B_r", "B_z"):
        table[k] = np.ones_like(table["t"])
    model, _report = fit_response(name, table, np.zeros(table["t"].shape, bool), study,
                                  settings=settings)

    def predict(tab):
        return np.asarray(model.value(tab["t"], tab["theta"], tab["H"], R_m=tab["R_m"],
                                      H_m=tab["H_m"]), dtype=float)
    return predict


def blend_sizes(ds, name: str, R_m: float, H_m: float, exclude=HELD_OUT) -> np.ndarray:
    """f on the DOE's (t, θ, H) grid for a magnet (R_m, H_m) [m]: at each grid point a
    quadratic in (R_m, H_m) fitted by least squares over the data's sizes (those not in
    ``exclude`` and finite there). Linear in the data: the same weights blend per-size models
    (values and derivatives alike)."""
    G = ds["G"].values.astype(float)
    F = ds[f"F_{name[-1]}"].transpose("t", "theta", "H", "R_m", "H_m", "G").values.astype(float)
    f = (F / G).mean(axis=-1)
    Rs, Hs = ds["R_m"].values.astype(float), ds["H_m"].values.astype(float)
    r0, h0 = Rs.mean(), Hs.mean()
    def basis(r, h):
        x, y = (r - r0) / r0, (h - h0) / h0
        return np.array([1.0, x, y, x * x, x * y, y * y])
    out = np.full(f.shape[:3], np.nan)
    for idx in np.ndindex(*f.shape[:3]):
        rows, vals = [], []
        for i, r in enumerate(Rs):
            for j, h in enumerate(Hs):
                if any(np.isclose(r, a) and np.isclose(h, b) for a, b in exclude):
                    continue
                if np.isfinite(f[idx + (i, j)]):
                    rows.append(basis(r, h))
                    vals.append(f[idx + (i, j)])
        if len(rows) >= 6:
            coef, *_ = np.linalg.lstsq(np.array(rows), np.array(vals), rcond=None)
            out[idx] = basis(R_m, H_m) @ coef
    return out


SIZE_DIR = RESULTS / "sizes"


def _cut_and_fit(sub, text: str, folder: Path) -> dict:
    """A size's data set read from the cache (a path not cached: refused, nothing is solved)
    into ``folder`` with its study, and its ``magtact fit`` in ``folder/fit``; the fit's wall
    time, the load and the models' accuracy."""
    from magtact.doe import run_doe, save_dataset
    from magtact.doe._cache import JobCache
    from magtact.doe._jobs import plan
    from magtact.magnetics import hall_field
    from magtact.mechanics import simulate_path

    _, jobs = plan(sub, simulate_path, hall_field)
    missing = [j.label for j in jobs if JobCache(CACHE).get("path", j.key) is None]
    if missing:
        raise SystemExit(f"{text}: {len(missing)} path(s) not cached yet ({missing[0]} ...)")
    ds = run_doe(sub, cache=CACHE, workers=0)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "study.toml").write_text(sub.to_toml(), encoding="utf-8")
    save_dataset(ds, folder / "doe.nc")
    cmd = [sys.executable, "-m", "magtact", "fit", str(folder / "study.toml"), "--data",
           str(folder / "doe.nc"), "--out", str(folder / "fit")]
    start = time.perf_counter()
    subprocess.run(cmd, check=True, cwd=ROOT)
    return {"fit_wall_time_s": time.perf_counter() - start, "load_average": os.getloadavg(),
            "accuracy": {k: json.loads((folder / "fit" / f"{k}.json").read_text())["info"]
                         ["accuracy"] for k in ("f_r", "f_z")}}


def ship(texts: list[str]) -> None:
    """Each finished size's (t, θ, H) data set, read from the cache (a size with a path not
    cached is refused: nothing is solved here), its ``magtact fit`` with the broad sizes'
    settings (twice the default GP budget, up to five seeds, the field exact, 2 held-out
    paths) and both copied into the package as ``broad_<D>x<H>``."""
    from dataclasses import replace

    from bench_broad import ship_size

    from magtact import study as mstudy

    study = mstudy.load_study(STUDY)
    settings = replace(mstudy.magone().metamodel, b_model="exact", holdout_paths=2,
                       generations=200, population=1000, retries=4)
    record = json.loads(OUT.read_text()).get("ship", {}) if OUT.is_file() else {}
    for text in texts:
        size = _size(text)
        sub = replace(study.at(**size), metamodel=settings,
                      name=f"MagOne body, {text} mm magnet, H 2-10 mm")
        folder = SIZE_DIR / text
        fitted = _cut_and_fit(sub, text, folder)
        wall = fitted["fit_wall_time_s"]
        record[text] = {**fitted, **ship_size(folder, text)}
        _update("ship", record)
        print(text, f"fit {wall:.0f} s", {k: v["test"]["max_abs_err_over_range"]
                                          for k, v in record[text]["accuracy"].items()})


#: The 2 mm-high magnets over H 2-10 mm at 7 levels (:data:`FINE_H_STUDY`): their data and fits,
#: not shipped (``fine-h`` and ``fine-h-blend``).
FINE_H_STUDY = HERE / "magtact_sizes_fine_h.toml"
FINE_H_DIR = RESULTS / "sizes_fine_h"
#: The same sizes at 5 θ levels too (``fine-h-doe --angles 5``).
FINE_HT_STUDY = HERE / "magtact_sizes_fine_ht.toml"


def fine_h_doe(texts: list[str], workers: int, study_file: Path = FINE_H_STUDY) -> None:
    """The named 2 mm-high sizes' paths over H 2-10 mm at 7 levels (:data:`FINE_H_STUDY`, or
    ``study_file``: also at 5 θ levels, :data:`FINE_HT_STUDY`), through the committed job
    cache: the levels already solved are found there, the new ones solved (resumable: a path
    finished is never solved again)."""
    from magtact import study as mstudy
    from magtact.doe import run_doe
    from magtact.doe._run import DOEFailed

    study = mstudy.load_study(study_file)
    for text in texts:
        start = time.perf_counter()
        try:
            ds = run_doe(study.at(**_size(text)), cache=CACHE, workers=workers)
            print(text, "complete:", ds.attrs["run_paths_computed"], "paths solved",
                  f"{time.perf_counter() - start:.0f} s", flush=True)
        except DOEFailed as exc:
            print(text, f"{len(exc.failures)} path(s) failed", flush=True)


def _fine(angles: int) -> tuple[Path, Path, str]:
    """The study file, the results folder and the record's name of the 2 mm-high sizes over 7
    heights at 3 or 5 θ levels."""
    if angles == 3:
        return FINE_H_STUDY, FINE_H_DIR, "fine_h"
    return FINE_HT_STUDY, RESULTS / "sizes_fine_ht", "fine_ht"


def fine_h(texts: list[str], angles: int = 3) -> None:
    """Each named 2 mm-high size's data set over H 2-10 mm at 7 levels (and 3 or 5 θ levels),
    read from the cache (a path not cached: refused), and its ``magtact fit`` with the shipped
    sizes' settings, in :data:`FINE_H_DIR` (``sizes_fine_ht`` at 5 θ levels; nothing is copied
    into the package)."""
    from dataclasses import replace

    from magtact import study as mstudy

    study_file, results, name = _fine(angles)
    study = mstudy.load_study(study_file)
    settings = replace(mstudy.magone().metamodel, b_model="exact", holdout_paths=2,
                       generations=200, population=1000, retries=4)
    for text in texts:
        sub = replace(study.at(**_size(text)), metamodel=settings,
                      name=f"MagOne body, {text} mm magnet, H 2-10 mm at 7 levels")
        entry = _cut_and_fit(sub, text, results / text)
        _update(name, entry, key=text)
        print(text, f"fit {entry['fit_wall_time_s']:.0f} s", flush=True)


def fine_h_ship(texts: list[str], angles: int = 3) -> None:
    """Copy the named sizes' data sets and fits over 7 heights (:func:`fine_h`) into the
    package as ``broad_<D>x<H>``, replacing those over 4 heights; their records in ``ship``."""
    from bench_broad import ship_size

    _, results, name = _fine(angles)
    record = json.loads(OUT.read_text()).get("ship", {}) if OUT.is_file() else {}
    fits = json.loads(OUT.read_text()).get(name, {}) if OUT.is_file() else {}
    for text in texts:
        folder = results / text
        record[text] = {"from": f"python bench/bench_sizes.py fine-h --angles {angles} (H 2-10 "
                                f"mm at 7 levels, {angles} theta levels)",
                        **fits.get(text, {}), **ship_size(folder, text)}
        print(text, record[text]["data"], record[text]["fit"], flush=True)
    _update("ship", record)


def fine_h_blend(angles: int = 3) -> None:
    """The 5 x 2 mm magnet's blend along the radius (4 x 2 mm x 1, 6 x 2 mm x 1/3, 3 x 2 mm x
    -1/3, :func:`magtact.doe.lagrange_weights`) of the fits over 7 heights (:func:`fine_h`)
    against the bundled MagOne data set, as ``blend`` measures the shipped fits."""
    from magtact import study as mstudy
    from magtact.doe import lagrange_weights
    from magtact.metamodel import load_models

    names = ("4x2", "6x2", "3x2")
    w = lagrange_weights([_size(n)["R_m"] for n in names], 2.5e-3)
    study = mstudy.magone()
    _, results, name = _fine(angles)
    models = [load_models(results / n / "fit", definition=study.sensitivity.definition)
              for n in names]
    tab = magone_table()
    stable = _stable(tab)
    entry = {"blended_from": dict(zip(names, map(float, w), strict=True))}
    for resp in ("f_z", "f_r"):
        pred = sum(wk * np.asarray(m[resp].value(tab["t"], tab["theta"], tab["H"]), float)
                   for wk, m in zip(w, models, strict=True))
        entry[resp] = _errors(pred, tab, resp)
        entry[f"{resp}, stable"] = _errors(pred[stable], {k: v[stable] for k, v in tab.items()},
                                           resp)
    _update(f"{name}_blend", {"command": f"python bench/bench_sizes.py fine-h-blend --angles "
                                         f"{angles}", "the bundled MagOne data set": entry})
    print({k: round(v["max_error_of_range"], 4) for k, v in entry.items()
           if k != "blended_from"})


def _errors(pred: np.ndarray, table: dict, name: str) -> dict:
    y = table[name]
    span = float(y.max() - y.min())
    err = np.abs(pred - y)
    return {"max_error_of_range": float(err.max() / span),
            "rms_error_of_range": float(np.sqrt(np.mean(err ** 2)) / span),
            "range": span, "points": int(y.size)}


def cached_table() -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """The points of every path the cache holds, size by size (nothing is solved: a path not
    cached yet is left out), as :func:`sizes_table`; and the paths held per size."""
    import itertools

    from magtact import study as mstudy
    from magtact.doe._cache import JobCache
    from magtact.doe._dataset import assemble
    from magtact.doe._jobs import plan
    from magtact.magnetics import hall_field
    from magtact.mechanics import simulate_path

    study = mstudy.load_study(STUDY)
    cache = JobCache(CACHE)
    levels = study.geometry_levels
    parts, held = [], {}
    for values in itertools.product(*levels.values()):
        geometry = dict(zip(levels, (float(v) for v in values), strict=True))
        sub = study.at(**geometry)
        field_job, jobs = plan(sub, simulate_path, hall_field)
        found = {j.key: e for j in jobs if (e := cache.get("path", j.key)) is not None}
        held[_label(geometry["R_m"], geometry["H_m"])] = f"{len(found)}/{len(jobs)}"
        if not found:
            continue
        ds = assemble(sub, field_job, None, jobs, found, {})
        points = _points(ds, ("t", "theta", "H"))
        points["R_m"] = np.full_like(points["t"], geometry["R_m"])
        points["H_m"] = np.full_like(points["t"], geometry["H_m"])
        parts.append(points)
    table = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    keep = np.isfinite(table["f_r"]) & np.isfinite(table["f_z"])
    return {k: v[keep] for k, v in table.items()}, held


def surrogate(models: list[str], cached: bool = False,
              responses: tuple[str, ...] = ("f_z", "f_r")) -> None:
    """Fit each model on every size but :data:`HELD_OUT` and measure it on those (``cached``:
    on the paths the cache holds now, before the DOE's data set exists)."""
    import xarray as xr

    held_paths = None
    if cached:
        table, held_paths = cached_table()
    else:
        with xr.open_dataset(_doe_file()) as ds:
            table = sizes_table(ds.load())
    held = np.zeros(table["t"].shape, bool)
    for R_m, H_m in HELD_OUT:
        held |= np.isclose(table["R_m"], R_m) & np.isclose(table["H_m"], H_m)
    train = {k: v[~held] for k, v in table.items()}
    sizes = sorted({(float(a), float(b)) for a, b in zip(train["R_m"], train["H_m"], strict=True)})
    checks = {f"{_label(*s)} (held out, this DOE)":
              {k: v[np.isclose(table["R_m"], s[0]) & np.isclose(table["H_m"], s[1])]
               for k, v in table.items()} for s in HELD_OUT}
    checks["5 x 2 mm, the bundled MagOne data (held out)"] = magone_table()
    result = {"command": "python bench/bench_sizes.py surrogate",
              "training_sizes": [_label(*s) for s in sizes],
              "training_points": int(train["t"].size),
              "held_out_sizes": [_label(*s) for s in HELD_OUT],
              "error_measure": "largest |error| over a size's points / that size's range "
                               "(and the root-mean-square error / range)",
              "data": ("the paths the job cache held (per size)" if cached
                       else str(_doe_file().relative_to(ROOT))),
              "paths_per_size": held_paths,
              "models": {}}
    before = json.loads(OUT.read_text()).get("surrogate", {}) if OUT.is_file() else {}
    if all(before.get(k) == result[k] for k in ("training_sizes", "training_points", "data")):
        result["models"] = before.get("models", {})  # other models and responses measured before
    X = _features(train)
    for model_name in models:
        entry = result["models"].get(model_name, {})
        for name in responses:
            start = time.perf_counter()
            if model_name == "gp":
                fitted = fit_gp(train, name)
                predict = fitted
            else:
                fit = {"kriging": fit_kriging, "rbf": fit_rbf}[model_name]
                f = fit(X, train[name], name)
                predict = lambda tab, f=f: f(_features(tab))  # noqa: E731
            fit_s = time.perf_counter() - start
            entry[name] = {"fit_s": fit_s,
                           **{label: _errors(predict(tab), tab, name)
                              for label, tab in checks.items()}}
            print(model_name, name, {k: round(v["max_error_of_range"], 4)
                                     for k, v in entry[name].items() if isinstance(v, dict)},
                  f"{fit_s:.1f} s", flush=True)
            # each response as it is measured (a kriging fit takes tens of minutes), merged
            # with what another process measured meanwhile on the same data
            now = json.loads(OUT.read_text()).get("surrogate", {}) if OUT.is_file() else {}
            if all(now.get(k) == result[k] for k in ("training_sizes", "training_points",
                                                     "data")):
                for m, e in now.get("models", {}).items():
                    result["models"].setdefault(m, {})
                    for r, v in e.items():
                        result["models"][m].setdefault(r, v)
            result["models"].setdefault(model_name, {}).update(entry)
            _update("surrogate", result)


def interpolate() -> None:
    """Each size of the DOE predicted from the others at the same (t, θ, H) points, without
    any model: (a) along the magnet's radius, the quadratic through the three other radii at
    the same height; (b) along its height, the line through the two other heights at the same
    radius (the middle height only: three levels leave nothing to check a quadratic with).
    The error of a size: the largest |error| over its finite points / its range."""
    import xarray as xr

    from magtact.doe import lagrange_weights  # the Lagrange weights magtact blends with

    with xr.open_dataset(_doe_file()) as ds:
        ds = ds.load()
    G = ds["G"].values.astype(float)
    f = {k: (ds[f"F_{k[-1]}"].transpose("t", "theta", "H", "R_m", "H_m", "G").values / G
             ).mean(axis=-1) for k in ("f_r", "f_z")}
    Rs, Hs = ds["R_m"].values.astype(float), ds["H_m"].values.astype(float)

    def error(pred, true):
        ok = np.isfinite(pred) & np.isfinite(true)
        span = float(np.nanmax(true) - np.nanmin(true))
        err = np.abs(pred - true)[ok]
        return {"max_error_of_range": float(err.max() / span),
                "rms_error_of_range": float(np.sqrt(np.mean(err ** 2)) / span),
                "points": int(ok.sum())}

    out = {}
    for i, R in enumerate(Rs):
        for j, h in enumerate(Hs):
            entry = {}
            others = [m for m in range(Rs.size) if m != i]
            w = lagrange_weights(Rs[others], R)
            for name, v in f.items():
                true = v[..., i, j]
                entry[f"{name} along the radius (quadratic)"] = error(
                    np.tensordot(v[..., others, j], w, axes=([-1], [0])), true)
                if 0 < j < Hs.size - 1:
                    wl = lagrange_weights(Hs[[j - 1, j + 1]], h)
                    entry[f"{name} along the height (line)"] = error(
                        v[..., i, j - 1] * wl[0] + v[..., i, j + 1] * wl[1], true)
            out[_label(R, h)] = entry
    for label, entry in out.items():
        print(label, {k: round(e["max_error_of_range"], 4) for k, e in entry.items()})
    _update("interpolation", {"command": "python bench/bench_sizes.py interpolate",
                              "data": str(_doe_file().relative_to(ROOT)),
                              "error_measure": "largest |error| over a size's finite points / "
                                               "that size's range (and rms / range)",
                              "sizes": out})


def _stable(tab: dict) -> np.ndarray:
    """The points of each path (θ, H) up to its shear force's extreme (the least f_r along
    the path: beyond it the body slips, outside the region the sensor problem reads)."""
    keep = np.zeros(tab["t"].shape, bool)
    for th, H in {(a, b) for a, b in zip(tab["theta"], tab["H"], strict=True)}:
        on = np.flatnonzero((tab["theta"] == th) & (tab["H"] == H))
        t_peak = tab["t"][on][np.argmin(tab["f_r"][on])] if th > 0 else np.inf
        keep[on] = tab["t"][on] <= t_peak
    return keep


def blend() -> None:
    """What magtact ships across sizes, measured on sizes it never saw: the shipped per-size
    fits of the sizes around a magnet blended along its radius, or its height and radius
    (:func:`magtact.doe.bundled_blend`, :func:`magtact.metamodel.blended_metamodels`), the
    held-out size left out of the sizes it may blend, against (a) that size's FE paths in
    this DOE, (b) for the 5 x 2 mm magnet, the bundled MagOne data set (another DOE: H 3-7
    mm at 5 levels, 5 theta levels) and (c) the FE paths of a 4 x 1.5 mm magnet
    (:data:`HEIGHT_CHECK`). Largest |error| / the size's force range, per response,
    over every point, over the points of t <= 0.5 and over the stable points (each path up to
    its shear force's extreme, :func:`_stable`)."""
    import xarray as xr

    import magtact
    from magtact.doe import BROAD_SIZES, bundled_blend
    from magtact.metamodel import blended_metamodels

    with xr.open_dataset(_doe_file()) as ds:
        table = sizes_table(ds.load())
    with xr.open_dataset(HEIGHT_CHECK) as ds:
        between = _points(ds.load(), ("t", "theta", "H"))
    checks = {}
    for target, H_range in (("5x2", (2.0, 10.0)), ("5x1", (2.0, 10.0)), ("4x1", (2.0, 10.0)),
                            ("4x1.5", (2.0, 10.0))):
        if target == "4x1.5":  # between the heights: every shipped size may blend
            study = magtact.load("magone", magnet={"R_m_mm": 2.0, "H_m_mm": 1.5},
                                 design={"H_mm": list(H_range), "magnet_sizes": []})
            ds, parts = bundled_blend(study)
            tabs = {"4 x 1.5 mm, its own FE paths (bench/magtact_4x1p5.toml)": between}
        else:
            size = _size(target)
            study = magtact.load("magone", design={"H_mm": list(H_range)}).sized(target)
            ds, parts = bundled_blend(study, tuple(s for s in BROAD_SIZES if s != target))
            own = {k: v[np.isclose(table["R_m"], size["R_m"])
                        & np.isclose(table["H_m"], size["H_m"])] for k, v in table.items()}
            name = f"{_label(size['R_m'], size['H_m'])}"
            tabs = {f"{name}, this DOE's FE paths": own}
            if target == "5x2":
                tabs[f"{name}, the bundled MagOne data set"] = magone_table()
        models = blended_metamodels(study, parts).models
        for label, tab in tabs.items():
            entry = {"blended_from": {n: w for n, w, _, _ in parts}}
            stable = _stable(tab)
            for resp in ("f_z", "f_r"):
                pred = np.asarray(models[resp].value(tab["t"], tab["theta"], tab["H"]), float)
                entry[resp] = _errors(pred, tab, resp)
                i = int(np.argmax(np.abs(pred - tab[resp]) * stable))
                entry[resp]["stable_worst_at"] = {"t": float(tab["t"][i]),
                                                  "theta_rad": float(tab["theta"][i]),
                                                  "H_mm": 1e3 * float(tab["H"][i])}
                for label_, keep in (("t <= 0.5", tab["t"] <= 0.5), ("stable", stable)):
                    entry[f"{resp}, {label_}"] = _errors(pred[keep], {k: v[keep] for k, v in
                                                                      tab.items()}, resp)
            checks[label] = entry
            print(label, {k: round(v["max_error_of_range"], 4) for k, v in entry.items()
                          if k != "blended_from"}, flush=True)
    _update("blend", {"command": "python bench/bench_sizes.py blend",
                      "shipped_sizes": list(BROAD_SIZES),
                      "error_measure": "largest |error| over the size's points / that size's "
                                       "range of the response (and rms / range)",
                      "checks": checks})


def robust() -> None:
    """Whether the size the built-in study chooses on its nominal parts is also the best for
    the units built: each size that carries the specification solved whole (its worst corner,
    NSGA-II's cross-check: what the chosen size gets) and its robust verdict recorded."""
    import magtact
    from magtact._front import _sensor_result, models_for
    from magtact.optimise import force_constraints, optimise

    os.environ["MAGTACT_CACHE_DIR"] = "off"
    study = magtact.load("magone")
    chosen = magtact.design(study).sensor_design
    out = {}
    for name, d in zip(chosen.sizes, chosen.per_size, strict=True):
        if d is None:
            continue
        sub = study.sized(name)
        models = models_for(sub)[0]
        c = force_constraints(models, sub)
        start = time.perf_counter()
        r = _sensor_result(models, sub, optimise(models, sub, c), c, "given", None)
        rob, s = r.chosen.robust, r.sensor_design.choice
        out[name] = {"nominal_sigma_mN": 1e3 * d.sigma, "sigma_Fr_mN": 1e3 * s.sigma_r,
                     "sigma_Fz_mN": 1e3 * s.sigma_z, "yield": rob.yield_fraction,
                     "requirements": {q.key: {"met_worst_case": q.met,
                                              "yield": q.yield_fraction}
                                      for q in rob.requirements},
                     "wall_time_s": time.perf_counter() - start}
        print(name, round(1e3 * d.sigma, 4), round(rob.yield_fraction, 4), flush=True)
    best = max(out, key=lambda n: (out[n]["yield"], -out[n]["nominal_sigma_mN"]))
    _update("robust", {"command": "python bench/bench_sizes.py robust",
                       "chosen_size": chosen.size, "best_yield_size": best, "sizes": out})


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="step", required=True)
    d = sub.add_parser("doe")
    d.add_argument("--workers", type=int, default=1)
    d.add_argument("--first", default="", help="sizes to solve first, e.g. 5x2,4x1")
    sub.add_parser("status")
    sub.add_parser("interpolate")
    sub.add_parser("blend")
    sub.add_parser("robust")
    fd = sub.add_parser("fine-h-doe")
    fd.add_argument("sizes", nargs="?", default="4x2,6x2,3x2")
    fd.add_argument("--workers", type=int, default=1)
    fd.add_argument("--angles", type=int, choices=(3, 5), default=3,
                    help="theta levels: 3 (bench/magtact_sizes_fine_h.toml) or 5 "
                         "(bench/magtact_sizes_fine_ht.toml)")
    fh = sub.add_parser("fine-h")
    fh.add_argument("sizes", help="2 mm-high sizes whose 7 heights are cached, e.g. 4x2,6x2")
    fb = sub.add_parser("fine-h-blend")
    fs = sub.add_parser("fine-h-ship")
    fs.add_argument("sizes", help="sizes fitted over 7 heights, e.g. 4x2,6x2,3x2")
    for q in (fh, fb, fs):
        q.add_argument("--angles", type=int, choices=(3, 5), default=3)
    sh = sub.add_parser("ship")
    sh.add_argument("sizes", help="finished sizes to ship, e.g. 3x2,5x2")
    s = sub.add_parser("surrogate")
    s.add_argument("--models", default="rbf,kriging,gp")
    s.add_argument("--cached", action="store_true",
                   help="fit on the paths the cache holds now (before the DOE ends)")
    s.add_argument("--responses", default="f_z,f_r", help="responses to fit, e.g. f_z")
    args = ap.parse_args(argv)
    if args.step == "doe":
        doe(args.workers, [x for x in args.first.split(",") if x])
    elif args.step == "status":
        status()
    elif args.step == "interpolate":
        interpolate()
    elif args.step == "blend":
        blend()
    elif args.step == "robust":
        robust()
    elif args.step == "fine-h-doe":
        fine_h_doe([x for x in args.sizes.split(",") if x], args.workers,
                   FINE_H_STUDY if args.angles == 3 else FINE_HT_STUDY)
    elif args.step == "fine-h":
        fine_h([x for x in args.sizes.split(",") if x], args.angles)
    elif args.step == "fine-h-blend":
        fine_h_blend(args.angles)
    elif args.step == "fine-h-ship":
        fine_h_ship([x for x in args.sizes.split(",") if x], args.angles)
    elif args.step == "ship":
        ship(args.sizes.split(","))
    else:
        surrogate(args.models.split(","), cached=args.cached,
                  responses=tuple(args.responses.split(",")))


if __name__ == "__main__":
    main()
