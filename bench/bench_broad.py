"""The broad design space shipped with magtact.

``bench/magtact_broad_full.toml``: the MagOne body with H in [2, 10] mm at 4 levels and four
magnets, diameter 3 or 6 mm (R_m 1.5, 3 mm) × height 1 or 3 mm, 3 theta levels, default mesh,
G by its exact scaling: 48 structural paths in 4 sub-DOEs. Seven paths of the tall magnets stall
before t = 1 and keep the levels they reached. magtact ships one (t, theta, H) data set and fit
per magnet size (``src/magtact/doe/data/broad_<D>x<H>_doe.nc``, ``metamodel/data/broad_<D>x<H>``):
a single fit over the four sizes (``fit --study full``) does not interpolate between them (the
``magone`` step measures it against the MagOne data of a 5 x 2 mm magnet).

Steps (each writes its part of ``bench/results/broad.json``)::

    nohup python bench/bench_broad.py doe --study full --workers 2 > broad_doe.log 2>&1 &
    python bench/bench_broad.py split        # per size: its data set and magtact fit
    python bench/bench_broad.py ship_sizes   # copy data sets and fits into the package
    python bench/bench_broad.py fit --study full   # one fit over the four sizes, for the check
    python bench/bench_broad.py magone       # that fit against the MagOne data
    python bench/bench_broad.py whatif       # what-ifs answered from the shipped data, timed
    python bench/bench_broad.py mesh         # the mesh correction, measured (no FE solve)
    python bench/bench_broad.py runs         # magtact run of the first what-ifs, timed
    python bench/bench_broad.py quick        # one design's answer from the broad data, timed

``doe`` runs ``magtact doe`` through the job cache ``bench/results/broad_cache`` (committed: a
rerun reuses every finished path and computes the stalled ones again).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RESULTS = HERE / "results"
STUDIES = {"full": HERE / "magtact_broad_full.toml"}
DOE_DIRS = {k: RESULTS / f"broad_{k}_doe" for k in STUDIES}
FIT_DIRS = {k: RESULTS / f"broad_{k}_fit" for k in STUDIES}
CACHE = RESULTS / "broad_cache"
OUT = RESULTS / "broad.json"
SHIP_DATA = ROOT / "src" / "magtact" / "doe" / "data"
SHIP_FIT = ROOT / "src" / "magtact" / "metamodel" / "data"



def _command(cmd: list[str]) -> str:
    """The magtact command line of ``cmd`` with paths relative to the repository (the record
    must not depend on where the checkout lies)."""
    return " ".join(["magtact", *(a.replace(str(ROOT) + "/", "") for a in cmd[3:])])

def _update(section: str, values: dict) -> None:
    out = json.loads(OUT.read_text()) if OUT.is_file() else {}
    out.update({"benchmark": "the broad bundled design space",
                "studies": {k: str(v.relative_to(ROOT)) for k, v in STUDIES.items()},
                "machine": {"cpus": os.cpu_count(), "platform": platform.platform(),
                            "python": platform.python_version()}})
    out[section] = values
    RESULTS.mkdir(exist_ok=True)
    OUT.write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")


def _magtact(*args: str) -> list[str]:
    return [sys.executable, "-m", "magtact", *args]


def _cache_cost() -> dict:
    """The cached paths' solver wall times and the span of their completion times."""
    from magtact.doe import JobCache

    cache = JobCache(CACHE)
    keys = cache.keys("path")
    walls = [float(cache.get("path", k).meta["job_wall_time"]) for k in keys]
    stamps = sorted(cache.path("path", k).stat().st_mtime for k in keys)
    return {"paths_cached": len(keys), "path_job_wall_time_s_sum": sum(walls),
            "path_job_wall_time_s_min": min(walls, default=None),
            "path_job_wall_time_s_max": max(walls, default=None),
            "first_to_last_completion_s": stamps[-1] - stamps[0] if stamps else None}


def doe(which: str, workers: int) -> None:
    import xarray as xr

    section = f"doe_{which}"
    out = DOE_DIRS[which]
    cmd = _magtact("doe", str(STUDIES[which]), "--out", str(out), "--workers", str(workers),
                   "--cache", str(CACHE))
    load_start = os.getloadavg()
    start = time.perf_counter()
    proc = subprocess.run(cmd, cwd=ROOT)
    wall = time.perf_counter() - start
    data = _doe_file(which)
    if proc.returncode and data.name != "doe_partial.nc":
        raise SystemExit(f"magtact doe failed (exit {proc.returncode}) and left no data set")
    with xr.open_dataset(data) as ds:
        attrs = dict(ds.attrs)
        sizes = {k: int(v) for k, v in ds.sizes.items()}
    jobs = [j for j in json.loads(attrs["jobs"]) if "job_wall_time" in j]
    _update(section, {
        "command": f"python bench/bench_broad.py doe --study {which} --workers {workers}",
        "magtact_command": _command(cmd),
        "study": str(STUDIES[which].relative_to(ROOT)),
        "workers": workers, "wall_time_s": wall, "load_average_at_start": load_start,
        "load_average_at_end": os.getloadavg(), "sizes": sizes,
        "paths_total": int(attrs["run_paths_total"]),
        "paths_computed": int(attrs["run_paths_computed"]),
        "paths_cached": int(attrs["run_paths_cached"]),
        "fields_computed": int(attrs["run_fields_computed"]),
        "path_job_wall_time_s_sum": sum(j["job_wall_time"] for j in jobs),
        "complete": int(attrs.get("complete", 0)), "mesh": attrs.get("mesh"),
        "source_revision": attrs.get("source_revision"),
        "failed_jobs": [j for j in attrs.get("failed_jobs", "").splitlines() if j],
        "partial_paths": partial_paths(attrs),
        "dataset": str(data.relative_to(ROOT)),
        "cache": _cache_cost(),
    })
    print(f"DOE: {wall:.0f} s -> {data}")


def partial_paths(attrs: dict) -> list[dict]:
    """The paths that stalled before t = 1, from a data set's job records: where (θ [rad],
    H [mm] and the magnet's diameter and height [mm]) and the last load level kept."""
    out = []
    for j in json.loads(attrs.get("jobs", "[]")):
        if "t_reached" in j:
            out.append({"theta_rad": j["theta"], "H_mm": j["H"] * 1e3,
                        "D_mm": 2e3 * j["R_m"] if "R_m" in j else None,
                        "H_m_mm": j["H_m"] * 1e3 if "H_m" in j else None,
                        "t_reached": j["t_reached"]})
    return out


def _doe_file(which: str) -> Path:
    """The DOE's data set: doe.nc, or doe_partial.nc when some jobs failed (the fit leaves
    their paths out)."""
    full = DOE_DIRS[which] / "doe.nc"
    return full if full.is_file() else DOE_DIRS[which] / "doe_partial.nc"


def fit(which: str) -> None:
    FIT_DIR = FIT_DIRS[which]
    cmd = _magtact("fit", str(STUDIES[which]), "--data", str(_doe_file(which)),
                   "--out", str(FIT_DIR))
    load_start = os.getloadavg()
    start = time.perf_counter()
    subprocess.run(cmd, check=True, cwd=ROOT)
    wall = time.perf_counter() - start
    held = {}
    for name in ("f_r", "f_z"):
        info = json.loads((FIT_DIR / f"{name}.json").read_text())["info"]
        held[name] = info["accuracy"]
    from magtact.study import load_study

    _update("fit" if which != "full" else "fit_full",
            {"command": f"python bench/bench_broad.py fit --study {which}",
                    "study": str(STUDIES[which].relative_to(ROOT)),
                    "magtact_command": _command(cmd),
                    "settings": dict(vars(load_study(STUDIES[which]).metamodel)),
                    "wall_time_s": wall, "load_average_at_start": load_start,
                    "load_average_at_end": os.getloadavg(), "accuracy": held})
    print(json.dumps(held, indent=1))


#: The magnet sizes of the full DOE, each shipped as its own (t, θ, H) data set and fit.
SIZE_DIR = RESULTS / "broad_sizes"


def _size_name(R_m: float, H_m: float) -> str:
    return f"{2e3 * R_m:.3g}x{1e3 * H_m:.3g}"


def split() -> None:
    """The full DOE's data set per magnet size: a (t, θ, H) data set each (the values as
    computed, the study of that size, the jobs and stalls of that size), then ``magtact fit``
    of each with a larger GP budget than the default (the field exact, 2 held-out paths)."""
    from dataclasses import replace

    from magtact.doe import load_dataset, save_dataset
    from magtact.study import load_study, magone

    full = load_dataset(_doe_file("full"))
    study = load_study(STUDIES["full"])
    # twice the default GP budget and up to five seeds: a (t, θ, H) fit per size as in the
    # MagOne fit, where the sizes with a tall magnet need more search to reach its thresholds
    fit_settings = replace(magone().metamodel, b_model="exact", holdout_paths=2,
                           generations=200, population=1000, retries=4)
    jobs = json.loads(full.attrs["jobs"])
    record = {}
    for R_m in full["R_m"].values:
        for H_m in full["H_m"].values:
            name = _size_name(R_m, H_m)
            sub = replace(study.at(R_m=float(R_m), H_m=float(H_m)), metamodel=fit_settings,
                          name=f"MagOne body, {name} mm magnet, H 2-10 mm")
            ds = full.sel(R_m=R_m, H_m=H_m).drop_vars(["R_m", "H_m"])
            mine = [j for j in jobs if j["R_m"] == R_m and j["H_m"] == H_m]
            stalled = [j for j in mine if "t_reached" in j]
            attrs = {k: v for k, v in full.attrs.items() if k != "geometric_variables"}
            attrs.update({
                "study_name": sub.name, "study_toml": sub.to_toml(),
                "title": f"magtact design of experiments: {sub.name}",
                "jobs": json.dumps(mine), "complete": int(not stalled),
                "failed_jobs": "\n".join(
                    f"path θ={j['theta']:.4f} rad, H={1e3 * j['H']:.4g} mm: stalled, its levels "
                    f"up to t = {j['t_reached']:.4g} kept" for j in stalled),
                "split_from": f"{full.attrs['study_name']} at R_m = {1e3 * R_m:.4g} mm, "
                              f"H_m = {1e3 * H_m:.4g} mm (bench/bench_broad.py split)"})
            ds.attrs = attrs
            folder = SIZE_DIR / name
            folder.mkdir(parents=True, exist_ok=True)
            (folder / "study.toml").write_text(sub.to_toml(), encoding="utf-8")
            save_dataset(ds, folder / "doe.nc")
            cmd = _magtact("fit", str(folder / "study.toml"), "--data", str(folder / "doe.nc"),
                           "--out", str(folder / "fit"))
            start = time.perf_counter()
            subprocess.run(cmd, check=True, cwd=ROOT)
            wall = time.perf_counter() - start
            record[name] = {
                "magtact_command": _command(cmd), "wall_time_s": wall,
                "paths_stalled": len(stalled),
                "points_missing": int(ds["F_z"].isel(G=0).isnull().sum()),
                "accuracy": {k: json.loads((folder / "fit" / f"{k}.json").read_text())["info"]
                             ["accuracy"] for k in ("f_r", "f_z")}}
            print(name, f"{wall:.0f} s", {k: v["test"]["max_abs_err_over_range"]
                                          for k, v in record[name]["accuracy"].items()})
    _update("sizes", {"command": "python bench/bench_broad.py split",
                      "settings": dict(vars(fit_settings)), "sizes": record})


def ship_size(folder: Path, name: str) -> dict:
    """Copy one size's data set (``folder/doe.nc``) and fit (``folder/fit``: models,
    metamodels.md, PNG figures) into the package as ``broad_<name>``; their paths and sizes."""
    data = SHIP_DATA / f"broad_{name}_doe.nc"
    shutil.copy2(folder / "doe.nc", data)
    fit_dir = SHIP_FIT / f"broad_{name}"
    if fit_dir.exists():
        shutil.rmtree(fit_dir)
    fit_dir.mkdir(parents=True)
    for src in sorted((folder / "fit").iterdir()):
        if src.suffix in (".json", ".md", ".png") and not src.name.startswith("."):
            shutil.copy2(src, fit_dir / src.name)
    return {"data": str(data.relative_to(ROOT)), "fit": str(fit_dir.relative_to(ROOT)),
            "data_bytes": data.stat().st_size,
            "fit_bytes": sum(p.stat().st_size for p in fit_dir.iterdir())}


def ship_sizes() -> None:
    """Copy each size's data set and fit (models, metamodels.md, PNG figures) into the package."""
    sizes = {folder.name: ship_size(folder, folder.name)
             for folder in sorted(p for p in SIZE_DIR.iterdir() if (p / "doe.nc").is_file())}
    _update("ship", {"command": "python bench/bench_broad.py ship_sizes", "sizes": sizes})
    print(json.dumps(sizes, indent=1))


def whatif() -> None:
    """What-ifs inside the shipped space, answered without a DOE: magtact.design timed."""
    import magtact
    from magtact.study import study_from_dict

    cases = {
        "3 x 1 mm magnet": {"magnet": {"R_m_mm": 1.5, "H_m_mm": 1.0}},
        "3 x 1 mm magnet, H in [3, 9] mm": {"magnet": {"R_m_mm": 1.5, "H_m_mm": 1.0},
                                             "design": {"H_mm": [3.0, 9.0]}},
        "3 x 1 mm N52 magnet, H in [2, 10] mm": {"magnet": {"R_m_mm": 1.5, "H_m_mm": 1.0,
                                                            "grade": "N52"},
                                                 "design": {"H_mm": [2.0, 10.0]}},
        "6 x 1 mm magnet, H in [2, 10] mm": {"magnet": {"R_m_mm": 3.0, "H_m_mm": 1.0},
                                             "design": {"H_mm": [2.0, 10.0]}},
        "3 x 3 mm magnet, H in [3, 9] mm": {"magnet": {"R_m_mm": 1.5, "H_m_mm": 3.0},
                                            "design": {"H_mm": [3.0, 9.0]}},
    }
    out = {}
    for label, edit in cases.items():
        study = study_from_dict({"base": "magone", **edit})
        start = time.perf_counter()
        r = magtact.design(study)
        wall = time.perf_counter() - start
        out[label] = {"edit": edit, "wall_time_s": wall, "models_source": r.models_source,
                      "chosen": r.chosen_design,
                      "Gamma_r_max_N_per_T": r.chosen.design.Gamma_r_max,
                      "Gamma_z_max_N_per_T": r.chosen.design.Gamma_z_max,
                      "F_r_min_N": r.chosen.design.F_r_min,
                      "F_z_max_N": r.chosen.design.F_z_max,
                      "sensor": (r.sensor_design.to_json() if r.sensor_design is not None
                                 else None),
                      "verdict_met": r.chosen.verdict.met if r.chosen.verdict else None}
        print(label, f"{wall:.1f} s", r.chosen_design)
    _update("whatif", {"command": "python bench/bench_broad.py whatif",
                       "load_average": os.getloadavg(), "cases": out})


#: The (theta index, H index) paths of the bundled MagOne DOE the bridge is fitted on: five paths
#: spread over theta > 0 and H, none of the two held-out paths (theta_max, 3 mm), (theta_max, 7 mm).
BRIDGE_PATHS = ((1, 1), (2, 2), (3, 3), (4, 2), (2, 4))
#: The issue's threshold for adopting the correction: F_z(t = 1) within 1.5 % of the limit.
ADOPT_F_Z = 0.015


def mesh() -> None:
    """A multiplicative bridge from the default mesh towards the converged forces, fitted on a
    few paths and checked on held-out ones against the frontier's limits.

    On each path with both meshes (the bundled DOE on ``default``, ``bench/results/
    doe_accurate.nc`` on ``accurate``: twice the cells in z and radially) the order-1
    Richardson value 2 F_accurate - F_default estimates the limit; the bridge c = F_R / F_default
    is fitted linear in (theta, H) on :data:`BRIDGE_PATHS` and applied to the held-out paths
    (theta_max, 3 mm) and (theta_max, 7 mm), whose limits the frontier extrapolated from
    ``default`` and ``fine`` (``bench/results/frontier.json``). No FE solve is run.
    """
    import numpy as np

    from magtact.doe import load_bundled, load_dataset

    d, a = load_bundled(), load_dataset(RESULTS / "doe_accurate.nc")
    fr = json.loads((RESULTS / "frontier.json").read_text())
    limit = {o["H_mm"]: o["limit_from_default_fine"] for o in fr["orders"]
             if o["route"] == "richardson"}

    def forces(ds):  # at G_ref = 29.4 kPa, as the frontier's paths (forces are exact in G)
        k = 29.4e3 / float(ds["G"][0])
        return {"F_z_t1_N": ds["F_z"].isel(G=0).sel(t=1.0).transpose("theta", "H").values * k,
                "F_r_min_N": ds["F_r"].isel(G=0).min("t").transpose("theta", "H").values * k}

    fd, fa = forces(d), forces(a)
    theta, H = d["theta"].values, d["H"].values
    X = np.array([[1.0, theta[i], H[j] * 1e3] for i, j in BRIDGE_PATHS])
    rows = {}
    for key in ("F_z_t1_N", "F_r_min_N"):
        ratio = (2 * fa[key] - fd[key]) / fd[key]
        coef = np.linalg.lstsq(X, np.array([ratio[i, j] for i, j in BRIDGE_PATHS]),
                               rcond=None)[0]
        for j, H_mm in ((0, 3.0), (len(H) - 1, 7.0)):
            i = len(theta) - 1
            F = fd[key][i, j]
            corrected = F * float(coef @ [1.0, theta[i], H[j] * 1e3])
            L = limit[H_mm][key]
            rows.setdefault(f"H_{H_mm:g}_mm", {})[key] = {
                "limit": L, "default": F, "corrected": corrected,
                "default_vs_limit": F / L - 1, "corrected_vs_limit": corrected / L - 1,
                "richardson_of_the_path_vs_limit": (2 * fa[key][i, j] - fd[key][i, j]) / L - 1}
        rows.setdefault("bridge_coefficients", {})[key] = coef.tolist()
    worst = max(abs(rows[h]["F_z_t1_N"]["corrected_vs_limit"]) for h in ("H_3_mm", "H_7_mm"))
    _update("mesh_correction", {
        "command": "python bench/bench_broad.py mesh", "fit_paths_theta_H_index": BRIDGE_PATHS,
        "held_out": "theta_max at H = 3 and 7 mm", "adopt_if_F_z_t1_within": ADOPT_F_Z,
        "adopted": bool(worst <= ADOPT_F_Z), "worst_corrected_F_z_t1": worst, **rows})
    print(json.dumps(rows, indent=1), "adopted:", worst <= ADOPT_F_Z)


def quick() -> None:
    """The what-if of one design inside the broad space, without the optimisation: the study's
    models from the bundled data (identity check, exact rescaling, shipped fit) and the
    designer's answer at H = 9 mm, G = 30 kPa with a 3 x 1 mm N52 magnet; each step timed in a
    fresh process (imports included)."""
    code = (
        "import time; t0 = time.perf_counter()\n"
        "import magtact\n"
        "from magtact.designer import answer\n"
        "from magtact.study import study_from_dict\n"
        "t1 = time.perf_counter()\n"
        "s = study_from_dict({'base': 'magone', 'magnet': {'R_m_mm': 1.5, 'H_m_mm': 1.0, "
        "'grade': 'N52'}, 'design': {'H_mm': [2.0, 10.0]}})\n"
        "m, source, ds = magtact.models_for(s)\n"
        "t2 = time.perf_counter()\n"
        "a = answer(m, s, 9e-3, 30e3)\n"
        "t3 = time.perf_counter()\n"
        "import json; print(json.dumps({'import_s': t1 - t0, 'models_s': t2 - t1, "
        "'answer_s': t3 - t2, 'total_s': t3 - t0, 'source': source, "
        "'data': ds.attrs.get('rescaled_from'), 'Gamma_r_max_N_per_T': a.design.Gamma_r_max, "
        "'F_z_max_N': a.design.F_z_max}))\n")
    load = os.getloadavg()
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                          text=True, check=True)
    wall = time.perf_counter() - start
    res = json.loads(proc.stdout.strip().splitlines()[-1])
    _update("quick", {"command": "python bench/bench_broad.py quick", "wall_time_s": wall,
                      "load_average_at_start": load, **res})
    print(f"{wall:.1f} s", res)


#: The what-ifs a designer first tried, as study edits of the built-in MagOne study.
RUNS = {
    "silicone Dragon Skin 10": {"material": {"silicone": "Dragon Skin 10"}},
    "grade N52": {"magnet": {"grade": "N52"}},
    "G range 10-60 kPa": {"design": {"G_kPa": [10.0, 60.0]}},
    "H range 3.5-6.5 mm": {"design": {"H_mm": [3.5, 6.5], "H_original_mm": 4.0}},
    "3 x 1 mm magnet, H range 3-9 mm": {"magnet": {"R_m_mm": 1.5, "H_m_mm": 1.0},
                                        "design": {"H_mm": [3.0, 9.0]}},
    "6 x 3 mm N42 magnet, H range 4-10 mm": {"magnet": {"R_m_mm": 3.0, "H_m_mm": 3.0,
                                                        "grade": "N42"},
                                             "design": {"H_mm": [4.0, 10.0],
                                                        "H_original_mm": 5.0}},
    "silicone, grade, G range, chip setting, constraints at once": {
        "material": {"silicone": "Dragon Skin 10"}, "magnet": {"grade": "N52"},
        "design": {"G_kPa": [10.0, 60.0]},
        "hall": {"gain_sel": 0, "res": 1, "osr": 1, "dig_filt": 2},
        "constraints": {"source": "values", "F_r_c_N": -0.3, "F_z_c_N": 4.0}},
}


def runs() -> None:
    """``magtact run`` of each what-if: its wall time, its stages and where its DOE came from."""
    import tempfile

    import tomli_w

    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        for n, (label, edit) in enumerate(RUNS.items()):
            study = Path(tmp) / f"s{n}.toml"
            study.write_text(tomli_w.dumps({"base": "magone", "name": label, **edit}))
            folder = Path(tmp) / f"r{n}"
            load = os.getloadavg()
            start = time.perf_counter()
            proc = subprocess.run(_magtact("run", str(study), "--out", str(folder)),
                                  cwd=ROOT, capture_output=True, text=True)
            wall = time.perf_counter() - start
            manifest = json.loads((folder / "run.json").read_text()) \
                if (folder / "run.json").is_file() else {}
            out[label] = {
                "edit": edit, "exit_status": proc.returncode, "wall_time_s": wall,
                "load_average_at_start": load, "doe_source": manifest.get("doe_source"),
                "stages": {s["key"]: {"status": s["status"], "wall_time_s": s["wall_time_s"],
                                      "message": s["message"][:300]}
                           for s in manifest.get("stages", [])},
                "stderr_tail": proc.stderr[-600:],
                "chosen": (json.loads((folder / "optimise" / "chosen.json").read_text())
                           if (folder / "optimise" / "chosen.json").is_file() else None)}
            print(label, f"{wall:.0f} s", proc.returncode, manifest.get("doe_source"))
    _update("runs", {"command": "python bench/bench_broad.py runs", "cases": out})


def _magone_figure(own, models, G: float) -> None:
    """F_z(t = 1) and min_t F_r over H: the MagOne data (points) and the broad fit (lines)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    H = np.linspace(float(own.H.min()), float(own.H.max()), 81)
    t = np.asarray(own.t.values, dtype=float)
    fig, (a, b) = plt.subplots(1, 2, figsize=(9, 3.6), layout="constrained")
    for i, th in enumerate(own.theta.values):
        c = f"C{i}"
        a.plot(own.H * 1e3, own.F_z.isel(G=0, t=-1, theta=i), "o", color=c)
        a.plot(H * 1e3, G * models.f_z.value(1.0, th, H), "-", color=c,
               label=f"θ = {np.degrees(th):.1f}°")
        if th > 0:
            b.plot(own.H * 1e3, own.F_r.isel(G=0, theta=i).min("t"), "o", color=c)
            fr = G * models.f_r.value(t[:, None], th, H[None, :])
            b.plot(H * 1e3, fr.min(axis=0), "-", color=c)
    a.set(xlabel="H [mm]", ylabel="F_z(t = 1) [N]",
          title="MagOne data (points), the fit over the four sizes (lines)")
    b.set(xlabel="H [mm]", ylabel="min over t of F_r [N]")
    a.legend(fontsize=7)
    fig.savefig(RESULTS / "broad_magone.png", dpi=110)
    plt.close(fig)


def magone() -> None:
    """The single fit over the four magnet sizes (``fit --study full``) against the MagOne data
    set it never saw: a 5 x 2 mm magnet, between its sizes, at H 3-7 mm, the same body, loading
    and mesh. This is why magtact does not interpolate between the broad sizes."""
    import numpy as np

    from magtact.doe import load_bundled
    from magtact.metamodel import load_models

    models = load_models(FIT_DIRS["full"]).at(R_m=2.5e-3, H_m=2e-3)
    own = load_bundled()
    t, th, H = np.meshgrid(own.t.values, own.theta.values, own.H.values, indexing="ij")
    G = float(own.G.values[0])
    data = {}
    for k in ("r", "z"):
        measured = own[f"F_{k}"].isel(G=0).transpose("t", "theta", "H").values / G
        model = np.asarray(getattr(models, f"f_{k}").value(t, th, H), dtype=float)
        err = np.abs(model - measured)
        data[f"f_{k}"] = {"max_abs_err_over_range": float(err.max() / np.ptp(measured)),
                          "r2": float(1 - np.sum(err**2) / np.sum((measured - measured.mean())**2)),
                          "n_points": int(err.size)}
    fz1 = own.F_z.isel(G=0, t=-1).transpose("theta", "H").values / G
    data["F_z_t1_max_rel_err"] = float(np.abs(models.f_z.value(1.0, th[-1], H[-1]) / fz1 - 1).max())
    fr = own.F_r.isel(G=0).min("t").transpose("theta", "H").values[1:] / G
    model_fr = np.asarray(models.f_r.value(t, th, H), dtype=float).min(axis=0)[1:]
    data["F_r_min_max_rel_err"] = float(np.abs(model_fr / fr - 1).max())
    _magone_figure(own, models, G)
    _update("magone", {"command": "python bench/bench_broad.py magone", "data": data})
    print(json.dumps(data, indent=1))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("step", choices=("doe", "fit", "whatif", "mesh", "runs", "quick", "magone",
                                    "split", "ship_sizes"))
    p.add_argument("--study", choices=tuple(STUDIES), default="full")
    p.add_argument("--workers", type=int, default=1)
    a = p.parse_args()
    if a.step == "doe":
        doe(a.study, a.workers)
    elif a.step == "fit":
        fit(a.study)
    else:
        {"whatif": whatif, "mesh": mesh, "runs": runs, "quick": quick,
         "magone": magone, "split": split, "ship_sizes": ship_sizes}[a.step]()


if __name__ == "__main__":
    main()
