"""Benchmark: the full default MagOne DOE from an empty cache.

Runs ``magtact.doe.bundle.build_bundle`` with 2 local worker processes and a fresh, empty job
cache, writes the bundled data set (``src/magtact/doe/data/magone_doe.nc``) and the wall time
and per-path statistics to ``bench/results/doe.json``. Target: ≤ 15 min on the 2-core machine.

    nohup nice -n 10 /work/venv/bin/python bench/bench_doe.py > bench/results/doe.log 2>&1 &
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np
from rich.console import Console

from magtact.doe import DOEFailed
from magtact.doe.bundle import build_bundle

TARGET_S = 15 * 60
HERE = Path(__file__).resolve().parent


def _stats(values) -> dict:
    a = np.asarray(values, dtype=float)
    return {"min": float(a.min()), "median": float(np.median(a)), "mean": float(a.mean()),
            "max": float(a.max()), "sum": float(a.sum())}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--json", default=str(HERE / "results" / "doe.json"))
    parser.add_argument("--out", default=None,
                        help="data set file (default: the bundled data set in the package)")
    args = parser.parse_args()
    console = Console(stderr=True)
    load_start = os.getloadavg()
    with tempfile.TemporaryDirectory(prefix="magtact-doe-bench-") as cache:
        start = time.perf_counter()
        try:
            ds, path = build_bundle(workers=args.workers, cache=cache, out=args.out,
                                    console=console)
            failures = []
        except DOEFailed as exc:  # nothing is bundled; the statistics of the rest are kept
            ds, path = exc.dataset, None
            failures = [{"job": f.label, "error": f.error} for f in exc.failures]
        wall = time.perf_counter() - start
    jobs = json.loads(ds.attrs["jobs"])
    jobs = [j for j in jobs if "job_wall_time" in j]  # the completed paths
    per_path = [{"theta_rad": j["theta"], "H_mm": j["H"] * 1e3,
                 "job_wall_time_s": j["job_wall_time"], "solver_wall_time_s": j["wall_time"],
                 "newton_iterations": j["newton_iterations"], "cutbacks": j["cutbacks"],
                 "n_cells": j["n_cells"], "n_dofs": j["n_dofs"]} for j in jobs]
    result = {
        "benchmark": "full default MagOne DOE from an empty cache",
        "command": "python bench/bench_doe.py",
        "machine": {"cpus": os.cpu_count(), "platform": platform.platform(),
                    "python": platform.python_version(),
                    "load_average_at_start": load_start, "load_average_at_end": os.getloadavg(),
                    "note": "2 cores; other work on the machine shows in the load averages"},
        "workers": args.workers,
        "complete": not failures,
        "failures": failures,
        "n_paths": int(ds.attrs["run_paths_total"]),
        "n_points_F": int(ds["F_r"].size),
        "n_points_B": int(ds["B_r"].size),
        "mesh": ds.attrs["mesh"],
        "field_solver": ds.attrs["field_solver"],
        "wall_time_s": wall,
        "target_s": TARGET_S,
        "meets_target": bool(wall <= TARGET_S and not failures),
        "field_job_wall_time_s": ds.attrs["field_wall_time_s"],
        "paths_computed": int(ds.attrs["run_paths_computed"]),
        "path_job_wall_time_s": _stats([p["job_wall_time_s"] for p in per_path]),
        "path_newton_iterations": _stats([p["newton_iterations"] for p in per_path]),
        "path_cutbacks": _stats([p["cutbacks"] for p in per_path]),
        "path_n_cells": _stats([p["n_cells"] for p in per_path]),
        "parallel_efficiency": float(sum(p["job_wall_time_s"] for p in per_path)
                                     / (args.workers * wall)),
        "per_path": per_path,
        "dataset": str(path) if path else "not written (failed paths)",
        "versions": json.loads(ds.attrs["versions"]),
        "source_revision": ds.attrs["source_revision"],
        "path_model_version": ds.attrs.get("path_model_version"),
    }
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    console.print(f"full DOE: {wall:.0f} s (target {TARGET_S} s) -> {args.json}; data set {path}")


if __name__ == "__main__":
    main()
