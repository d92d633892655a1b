"""Benchmark of the metamodel stage on the default MagOne DOE (accuracy, Γ check).

Fits B_r, B_z, f_r, f_z with the study's [metamodel] settings, records the time of each fit and
the held-out accuracy (whole (θ, H) paths), and compares Γ of the models with Γ from finite
differences of the DOE data. Writes ``bench/results/fit.json``.

    python bench/bench_fit.py [--data DOE.nc] [--out bench/results/fit.json] [--models-out DIR]

Without ``--data`` the bundled data set is used (``magtact.doe.load_bundled``). The fit runs
through :func:`magtact.metamodel.write_fit_outputs`, as ``magtact fit`` does; ``--models-out
src/magtact/metamodel/data/magone`` keeps its files as the fit shipped with magtact.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import tempfile
import time
from dataclasses import asdict
from pathlib import Path

import numpy as np

from magtact.doe import load_bundled, load_dataset
from magtact.metamodel import write_fit_outputs
from magtact.report import fit_figures
from magtact.sensitivity import compare_with_data
from magtact.study import load_study

LIMITS = {"B_r": 0.01, "B_z": 0.01, "f_r": 0.02, "f_z": 0.02}
TIME_LIMIT_S = 120.0


def roughness(ds, degree: int = 6) -> dict[str, float]:
    """Max residual / range of a degree-``degree`` polynomial in t fitted to each (θ, H) path
    separately: a floor for any smooth model's error (FE contact events make F rough)."""
    G = ds["G"].values
    t = ds["t"].values
    out = {}
    for name, arr in (("B_r", ds["B_r"].values), ("B_z", ds["B_z"].values),
                      ("f_r", (ds["F_r"].values / G).mean(-1)),
                      ("f_z", (ds["F_z"].values / G).mean(-1))):
        worst = 0.0
        for i in range(arr.shape[1]):
            for j in range(arr.shape[2]):
                c = np.polyfit(t, arr[:, i, j], degree)
                worst = max(worst, float(np.abs(np.polyval(c, t) - arr[:, i, j]).max()))
        out[name] = worst / float(np.ptp(arr))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=None)
    ap.add_argument("--out", type=Path, default=Path(__file__).parent / "results" / "fit.json")
    ap.add_argument("--models-out", type=Path, default=None,
                    help="keep the model files, report and figures there (default: discarded)")
    args = ap.parse_args()
    study = load_study(None)
    ds = load_dataset(args.data) if args.data else load_bundled()
    with tempfile.TemporaryDirectory(prefix="magtact-bench-fit-") as tmp:
        t0 = time.perf_counter()
        res, _ = write_fit_outputs(study, ds, args.models_out or tmp, log=print,
                                   gamma_check=compare_with_data, figures=fit_figures)
        total = time.perf_counter() - t0
    models = res.model_set(study)
    rows = {}
    for k, rep in res.reports.items():
        rows[k] = {
            "fit_time_s": rep.fit_time_s, "tries": rep.tries, "seed": rep.seed,
            "transform": rep.transform, "rejected": list(rep.rejected),
            "test": asdict(rep.test), "train": asdict(rep.train),
            "limit_max_abs_err_over_range": LIMITS[k],
            "pass_accuracy": rep.test.max_abs_err_over_range <= LIMITS[k],
            "pass_time": rep.fit_time_s <= TIME_LIMIT_S,
            "expression": str(models[k].expr),
        }
        print(f"{k}: held-out R² {rep.test.r2:.6f}, max err/range "
              f"{rep.test.max_abs_err_over_range:.4g} (limit {LIMITS[k]}), max rel err "
              f"{rep.test.max_rel_err:.4g}, {rep.fit_time_s:.1f} s")
    check = compare_with_data(models, ds, t_min=0.2)
    print("Γ vs finite differences of the data:", json.dumps(check, indent=1))
    out = {
        "data": str(args.data) if args.data else "bundled",
        "data_hash": res.data_hash,
        "data_synthetic": bool(ds.attrs.get("synthetic", False)),
        "settings": asdict(study.metamodel),
        "holdout_theta_H": [list(h) for h in res.holdout],
        "models": rows,
        "gamma_vs_data_fd": check,
        "data_roughness_per_path_poly6": roughness(ds),
        "total_time_s": total,
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                    "platform": platform.platform()},
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(out, indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
