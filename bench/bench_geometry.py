"""The magnet radius as a design variable on the MagOne study (``bench/magone_geometry.toml``):
H in [3, 7] mm and R_m in [1.5, 3.5] mm at 5 x 5 levels, 5 theta levels, default mesh, G by its
exact scaling.

Two steps, so that the long one runs once and the rest can be repeated::

    nohup python bench/bench_geometry.py doe > bench/results/geometry_doe.log 2>&1 &
    python bench/bench_geometry.py optimise

``doe`` runs the 125 structural paths and 5 field solves with 2 worker processes through a job
cache (resumable: a rerun reuses every finished path) and keeps the data set in
``bench/results/geometry_doe.nc``. ``optimise`` fits the force metamodels over
(t, theta, H, R_m), optimises over (H, G, R_m) with NSGA-II and the generalised exact reduction,
and compares the chosen design with the (H, G) optimum of the same constraints (the magnet
radius fixed at 2.5 mm, on the same metamodels, and on the shipped (H, G) metamodels). Both
write ``bench/results/geometry.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
STUDY = HERE / "magone_geometry.toml"
DATA = RESULTS / "geometry_doe.nc"
OUT = RESULTS / "geometry.json"
CACHE = Path(os.environ.get("MAGTACT_BENCH_CACHE", Path.home() / ".cache" / "magtact-geometry"))


def _update(section: str, values: dict) -> None:
    out = json.loads(OUT.read_text()) if OUT.is_file() else {}
    out.update({"benchmark": "MagOne with the magnet radius as a design variable",
                "study": str(STUDY.relative_to(HERE.parent)),
                "machine": {"cpus": os.cpu_count(), "platform": platform.platform(),
                            "python": platform.python_version()}})
    out[section] = values
    RESULTS.mkdir(exist_ok=True)
    OUT.write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")


def doe(workers: int) -> None:
    from rich.console import Console

    from magtact.doe import run_doe, save_dataset
    from magtact.study import load_study

    study = load_study(STUDY)
    load_start = os.getloadavg()
    start = time.perf_counter()
    ds = run_doe(study, cache=CACHE, workers=workers, console=Console(stderr=True))
    wall = time.perf_counter() - start
    save_dataset(ds, DATA)
    jobs = [j for j in json.loads(ds.attrs["jobs"]) if "job_wall_time" in j]
    _update("doe", {
        "command": "python bench/bench_geometry.py doe", "workers": workers,
        "wall_time_s": wall, "load_average_at_start": load_start,
        "load_average_at_end": os.getloadavg(),
        "paths_total": int(ds.attrs["run_paths_total"]),
        "paths_computed": int(ds.attrs["run_paths_computed"]),
        "fields_computed": int(ds.attrs["run_fields_computed"]),
        "path_job_wall_time_s_sum": sum(j["job_wall_time"] for j in jobs),
        "mesh": study.mechanics.mesh, "dataset": str(DATA.relative_to(HERE.parent)),
    })
    print(f"DOE: {wall:.0f} s, {ds.attrs['run_paths_computed']} paths computed -> {DATA}")


def _row(values: dict, d) -> dict:
    from magtact.study import from_si

    row = {f"{k}_{u}": from_si(values[k], u)
           for k, u in (("H", "mm"), ("G", "kPa"), ("R_m", "mm")) if k in values}
    row.update(Gamma_r_max_N_per_T=d.Gamma_r_max, Gamma_z_max_N_per_T=d.Gamma_z_max,
               F_r_min_N=d.F_r_min, F_z_max_N=d.F_z_max)
    return row


def optimise() -> None:
    from magtact.doe import load_dataset
    from magtact.metamodel import fit_models, load_models, prefitted_dir
    from magtact.optimise import optimise as optimise_hg
    from magtact.optimise import optimise_geometry
    from magtact.study import load_study

    study = load_study(STUDY)
    ds = load_dataset(DATA)
    t0 = time.perf_counter()
    fit = fit_models(ds, study, log=print)
    t_fit = time.perf_counter() - t0
    models = fit.model_set(study)
    t0 = time.perf_counter()
    r = optimise_geometry(models, study)
    t_opt = time.perf_counter() - t0
    # the (H, G) optimum of the same constraints: R_m fixed at the original 2.5 mm
    original = study.magnet.R_m
    fixed = study.at(R_m=original)
    hg_same = optimise_hg(models.at(R_m=original), fixed)
    hg_shipped = optimise_hg(load_models(prefitted_dir()), load_study("magone"))
    choice = r.choice
    _update("optimise", {
        "command": "python bench/bench_geometry.py optimise",
        "fit_wall_time_s": t_fit, "optimise_wall_time_s": t_opt,
        "fit_test_max_rel_err": {k: (v.test.max_rel_err if v.test is not None else None)
                                 for k, v in fit.reports.items()},
        "nsga2_evaluations": r.evaluations, "gap_to_exact_front": r.gap,
        "chosen": _row(choice.values, choice.design),
        "chosen_by_exact_reduction": _row(r.exact_choice.values, r.exact_choice.design),
        "HG_optimum_same_models_R_m_2p5": _row({"H": hg_same.choice.design.H,
                                                "G": hg_same.choice.design.G, "R_m": original},
                                               hg_same.choice.design),
        "HG_optimum_shipped_models": _row({"H": hg_shipped.choice.design.H,
                                           "G": hg_shipped.choice.design.G, "R_m": original},
                                          hg_shipped.choice.design),
    })
    print(json.dumps(json.loads(OUT.read_text())["optimise"], indent=1))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("step", choices=("doe", "optimise"))
    p.add_argument("--workers", type=int, default=2)
    a = p.parse_args()
    doe(a.workers) if a.step == "doe" else optimise()


if __name__ == "__main__":
    main()
