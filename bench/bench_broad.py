"""The broad design space shipped with magtact.

``bench/magtact_broad_full.toml`` is the space aimed at: H in [2, 10] mm at 4 levels, the
magnet's radius R_m in [1.5, 3] mm and height H_m in [1, 3] mm at 2 levels each (diameters 3 and
6 mm), 3 theta levels, default mesh, G by its exact scaling: 48 structural paths in 4 sub-DOEs.
On the shared 2-core machine (load average 6-9 from other work) its paths took 3.3 min each,
so only its first two sub-DOEs (the 3 mm magnet, heights 1 and 3 mm) completed in the time there
was; they are ``bench/magtact_broad.toml``, the data set and fit shipped with magtact.

Steps (each writes its part of ``bench/results/broad.json``)::

    nohup nice -n 5 python bench/bench_broad.py doe --study full > broad_doe.log 2>&1 &
    python bench/bench_broad.py assemble   # the shipped study's data set from the job cache
    python bench/bench_broad.py fit        # magtact fit over it; held-out error
    python bench/bench_broad.py ship       # copy data and fit into the package
    python bench/bench_broad.py whatif     # what-ifs answered from the shipped data, timed
    python bench/bench_broad.py mesh       # the mesh correction, measured (no FE solve)
    python bench/bench_broad.py runs       # magtact run of the first what-ifs, timed
    python bench/bench_broad.py quick      # one design's answer from the broad data, timed

``doe`` and ``assemble`` run ``magtact doe`` with one worker through the job cache
``bench/results/broad_cache`` (a rerun reuses every finished path). The cache keys hash the
study's sections as the code of the run reads them, so a resume needs the same code: the cached
paths were computed by the source of commit d951cd0 (give its ``src`` folder in the environment
variable ``MAGTACT_BROAD_SRC``, e.g. ``git archive d951cd0 src | tar -x -C /tmp/old``).
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
STUDIES = {"3x1": HERE / "magtact_broad_3x1.toml", "H_m": HERE / "magtact_broad.toml",
           "full": HERE / "magtact_broad_full.toml"}
DOE_DIRS = {k: RESULTS / f"broad_{k}_doe" for k in STUDIES}
FIT_DIRS = {k: RESULTS / f"broad_{k}_fit" for k in STUDIES}
CACHE = RESULTS / "broad_cache"
OUT = RESULTS / "broad.json"
SHIP_DATA = ROOT / "src" / "magtact" / "doe" / "data" / "broad_doe.nc"
SHIP_FIT = ROOT / "src" / "magtact" / "metamodel" / "data" / "broad"



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


def _env() -> dict:
    env = dict(os.environ)
    src = os.environ.get("MAGTACT_BROAD_SRC")
    if src:
        env["PYTHONPATH"] = src
    return env


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


def doe(which: str, workers: int, section: str = "doe") -> None:
    import xarray as xr

    out = DOE_DIRS[which]
    cmd = _magtact("doe", str(STUDIES[which]), "--out", str(out), "--workers", str(workers),
                   "--cache", str(CACHE))
    load_start = os.getloadavg()
    start = time.perf_counter()
    subprocess.run(cmd, check=True, cwd=ROOT, env=_env())
    wall = time.perf_counter() - start
    with xr.open_dataset(out / "doe.nc") as ds:
        attrs = dict(ds.attrs)
        sizes = {k: int(v) for k, v in ds.sizes.items()}
    jobs = [j for j in json.loads(attrs["jobs"]) if "job_wall_time" in j]
    _update(section, {
        "command": f"python bench/bench_broad.py {section} --study {which}",
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
        "dataset": str((out / "doe.nc").relative_to(ROOT)),
        "cache": _cache_cost(),
    })
    print(f"DOE: {wall:.0f} s -> {out / 'doe.nc'}")


def fit(which: str) -> None:
    FIT_DIR = FIT_DIRS[which]
    cmd = _magtact("fit", str(STUDIES[which]), "--data",
                   str(DOE_DIRS[which] / "doe.nc"), "--out", str(FIT_DIR))
    load_start = os.getloadavg()
    start = time.perf_counter()
    subprocess.run(cmd, check=True, cwd=ROOT)
    wall = time.perf_counter() - start
    held = {}
    for name in ("f_r", "f_z"):
        info = json.loads((FIT_DIR / f"{name}.json").read_text())["info"]
        held[name] = info["accuracy"]
    from magtact.study import load_study

    _update("fit", {"command": f"python bench/bench_broad.py fit --study {which}",
                    "study": str(STUDIES[which].relative_to(ROOT)),
                    "magtact_command": _command(cmd),
                    "settings": dict(vars(load_study(STUDIES[which]).metamodel)),
                    "wall_time_s": wall, "load_average_at_start": load_start,
                    "load_average_at_end": os.getloadavg(), "accuracy": held})
    print(json.dumps(held, indent=1))


def ship(which: str) -> None:
    shutil.copy2(DOE_DIRS[which] / "doe.nc", SHIP_DATA)
    SHIP_FIT.mkdir(parents=True, exist_ok=True)
    for src in sorted(FIT_DIRS[which].iterdir()):
        if src.suffix in (".json", ".md", ".png", ".svg") and not src.name.startswith("."):
            shutil.copy2(src, SHIP_FIT / src.name)
    sizes = {"data_bytes": SHIP_DATA.stat().st_size,
             "fit_bytes": sum(p.stat().st_size for p in SHIP_FIT.iterdir())}
    _update("ship", {"command": f"python bench/bench_broad.py ship --study {which}",
                     "study": str(STUDIES[which].relative_to(ROOT)),
                     "data": str(SHIP_DATA.relative_to(ROOT)),
                     "fit": str(SHIP_FIT.relative_to(ROOT)), **sizes})
    print(sizes)


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
                      "F_z_max_N": r.chosen.design.F_z_max}
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
                "stderr_tail": proc.stderr[-600:]}
            print(label, f"{wall:.0f} s", proc.returncode, manifest.get("doe_source"))
    _update("runs", {"command": "python bench/bench_broad.py runs", "cases": out})


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("step", choices=("doe", "assemble", "fit", "ship", "whatif", "mesh", "runs",
                                    "quick"))
    p.add_argument("--study", choices=tuple(STUDIES), default="full")
    p.add_argument("--workers", type=int, default=1)
    a = p.parse_args()
    if a.step == "doe":
        doe(a.study, a.workers)
    elif a.step == "assemble":
        doe(a.study, a.workers, section="assemble")
    elif a.step in ("fit", "ship"):
        {"fit": fit, "ship": ship}[a.step](a.study)
    else:
        {"whatif": whatif, "mesh": mesh, "runs": runs, "quick": quick}[a.step]()


if __name__ == "__main__":
    main()
