"""Benchmark of the field stage: accuracy, convergence and time of the FE field.

Measures, for the built-in MagOne study: the exact kernel against magpylib; the FE mesh and
solve times, element and DOF counts (fresh solves, not the per-process cache) and the FE error
against the exact field on the acceptance grid and at every Hall point of the DOE; the error
under uniform mesh refinement. Writes ``bench/results/field.json``. Target: mesh + solve ≤ 5 s.

    nice -n 10 /work/venv/bin/python bench/bench_field.py
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import numpy as np

from magtact.geometry import field_mesh
from magtact.magnetics import cylinder_field, hall_field, solve_field
from magtact.study import MU0, load_study

TARGET_S = 5.0
HERE = Path(__file__).resolve().parent


def acceptance_points(R_m, H_m):
    """Below / above the magnet (r 0..3 mm, 2.97..12 mm from the face) and beside it."""
    r = np.linspace(0.0, 3e-3, 13)
    gap = np.linspace(2.97e-3, 12e-3, 20)
    rr, gg = np.meshgrid(r, gap)
    rb, zb = np.meshgrid(R_m + gap, np.linspace(-H_m / 2 - 2e-3, H_m / 2 + 2e-3, 9))
    return {"below": (rr.ravel(), -H_m / 2 - gg.ravel()),
            "above": (rr.ravel(), H_m / 2 + gg.ravel()),
            "beside": (rb.ravel(), zb.ravel())}


def rel(B, ref):
    return np.linalg.norm(np.subtract(B, ref), axis=0) / np.linalg.norm(ref, axis=0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--json", default=str(HERE / "results" / "field.json"))
    args = parser.parse_args()
    s = load_study()
    m, f = s.magnet, s.magnetics
    points = acceptance_points(m.R_m, m.H_m)
    exact = {k: cylinder_field(r, z, m.R_m, m.H_m, m.M_z) for k, (r, z) in points.items()}
    result: dict = {"study": s.name, "target_mesh_plus_solve_s": TARGET_S,
                    "load_average_at_start": os.getloadavg(),
                    "settings": {"h_magnet_mm": f.h_magnet * 1e3, "growth_near": f.growth_near,
                                 "near_mm": f.near * 1e3, "growth": f.growth, "far_r": f.far_r,
                                 "far_z": f.far_z}}

    try:
        import magpylib as magpy
    except ImportError:  # magpylib is a test-only dependency
        result["exact_vs_magpylib"] = "magpylib not installed"
    else:
        cyl = magpy.magnet.Cylinder(dimension=(2 * m.R_m, m.H_m), polarization=(0, 0, MU0 * m.M_z))
        worst = {}
        for k, (r, z) in points.items():
            B = cyl.getB(np.column_stack([r, 0 * r, z]))
            worst[k] = float(rel(exact[k], (B[:, 0], B[:, 2])).max())
        result["exact_vs_magpylib_max_rel"] = worst

    # warm-up on a coarse mesh: one-off imports (gmsh, scikit-fem) are not part of the timing
    solve_field(field_mesh(m.R_m, m.H_m, h_magnet=1e-3, growth_near=0.1, near=f.near,
                           growth=0.6, far_r=f.far_r, far_z=f.far_z), m.R_m, m.H_m, m.M_z)
    runs = []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        mesh = field_mesh(m.R_m, m.H_m, h_magnet=f.h_magnet, growth_near=f.growth_near,
                          near=f.near, growth=f.growth, far_r=f.far_r, far_z=f.far_z)
        t1 = time.perf_counter()
        sol = solve_field(mesh, m.R_m, m.H_m, m.M_z)
        t2 = time.perf_counter()
        runs.append({"mesh_s": t1 - t0, "solve_s": t2 - t1, "total_s": t2 - t0})
    result["fe_timing"] = {"runs": runs,
                           "median_total_s": float(np.median([r["total_s"] for r in runs])),
                           "max_total_s": float(max(r["total_s"] for r in runs))}
    result["fe_mesh"] = {"triangles": sol.mesh.n_triangles, "nodes": sol.mesh.points.shape[1],
                         "dofs_P2": sol.n_dofs,
                         "triangles_in_magnet": int(sol.mesh.in_magnet.sum())}
    result["fe_vs_exact_max_rel"] = {k: float(rel(sol.B(*points[k]), exact[k]).max())
                                     for k in points}
    t, th, H = np.meshgrid(s.t_levels, s.theta_levels, s.H_levels, indexing="ij")
    result["fe_vs_exact_hall_points_max_rel"] = float(
        rel(hall_field(s, t, th, H, "fe"), hall_field(s, t, th, H, "exact")).max())

    refinement = []
    r, z = points["below"]
    for far_r, far_z in ((f.far_r, f.far_z), (400.0, 500.0)):
        for factor in (1.0, 0.5, 0.25):
            mesh = field_mesh(m.R_m, m.H_m, h_magnet=0.4e-3 * factor, growth_near=0.05 * factor,
                              near=f.near, growth=0.6 * factor, far_r=far_r, far_z=far_z)
            e = rel(solve_field(mesh, m.R_m, m.H_m, m.M_z).B(r, z), exact["below"])
            refinement.append({"far_r": far_r, "far_z": far_z, "size_factor": factor,
                               "triangles": mesh.n_triangles, "max_rel": float(e.max()),
                               "rms_rel": float(np.sqrt(np.mean(e**2)))})
    for i in range(len(refinement)):
        if refinement[i]["size_factor"] < 1.0:
            prev, cur = refinement[i - 1], refinement[i]
            cur["rms_rate"] = float(np.log2(prev["rms_rel"] / cur["rms_rel"]))
    result["refinement_below_magnet"] = refinement
    result["machine"] = {"cpus": os.cpu_count(), "load_average_1_5_15min": os.getloadavg(),
                         "platform": platform.platform()}
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(json.dumps(result, indent=1), encoding="utf-8")
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
