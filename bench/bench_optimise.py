"""Optimisation stage on real metamodels: wall time, brute-force check, chosen designs.

Usage::

    nice -n 10 python bench/bench_optimise.py [--models DIR] [--repeats 2]

Models: the metamodel files in DIR (``magtact fit --out DIR``), else fitted to the bundled DOE
data set. Measures, and writes ``bench/results/optimise.json``:

- wall time of the whole optimisation (maps + sweep/exact reduction + NSGA-II + decision) for
  the default constraints, best of ``--repeats`` runs, against the 30 s target;
- per-design extrema (GA + trust region) against a brute-force 2001 × 401 grid over (t, θ) on
  the same models at five heights: relative differences and location distances;
- NSGA-II's distance from the exact reduction's front (relative, target ≤ 1 %);
- the chosen design and active constraints for the default constraints and for constraints
  taken from the original design (H = 3 mm, G = 29.4 kPa).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import numpy as np

from magtact.optimise import (
    as_responses,
    force_constraints,
    optimise,
    per_height,
)
from magtact.study import from_si, load_study

RESULTS = Path(__file__).resolve().parent / "results" / "optimise.json"
TARGET_S = 30.0
GRID = (2001, 401)


def load_models(folder: str | None, study):
    from magtact.metamodel import fit_models, load_models

    if folder:
        return load_models(folder), f"metamodel files in {folder}"
    from magtact.doe import load_bundled

    return fit_models(load_bundled(), study).model_set(study), "fitted to the bundled DOE"


def brute_force(models, study, H: float) -> dict:
    """Per-height extrema vs the best point of a dense grid on the same box."""
    R = as_responses(models).at(H)
    r = per_height(models, H, study)
    out = {"H_mm": from_si(H, "mm"), "degenerate": r.degenerate}
    boxes = {"f_r_min": (1.0, study.loading.theta_max, -1.0)}
    for name in ("f_z_max", "gamma_r_max", "gamma_z_max"):
        boxes[name] = (r.t_m, r.theta_m, 1.0)
    for key, (t_hi, th_hi, sign) in boxes.items():
        name = key.rsplit("_", 1)[0]
        T, TH = np.meshgrid(np.linspace(0, t_hi, GRID[0]), np.linspace(0, th_hi, GRID[1]),
                            indexing="ij")
        V = sign * R.value(name, T, TH)
        k = int(np.argmax(V))
        opt = getattr(r, key)
        v_grid = sign * V.flat[k]
        out[key] = {
            "optimiser": opt.value, "grid": float(v_grid),
            "rel_diff": float(abs(opt.value - v_grid) / abs(v_grid)) if v_grid else 0.0,
            "optimiser_not_worse": bool(sign * opt.value >= sign * v_grid - 1e-15 * abs(v_grid)),
            "location_optimiser": [opt.t, opt.theta],
            "location_grid": [float(T.flat[k]), float(TH.flat[k])],
            "grid_step": [t_hi / (GRID[0] - 1), th_hi / (GRID[1] - 1)],
            "kkt": opt.kkt, "active": list(opt.active),
        }
    return out


def chosen(result) -> dict:
    c = result.choice
    d = c.design
    return {"H_mm": from_si(d.H, "mm"), "G_kPa": from_si(d.G, "kPa"),
            "Gamma_r_max_N_per_T": d.Gamma_r_max, "Gamma_z_max_N_per_T": d.Gamma_z_max,
            "F_r_min_N": d.F_r_min, "F_z_max_N": d.F_z_max, "g_r_N": c.g_r, "g_z_N": c.g_z,
            "active_constraints": list(c.active), "degenerate": d.degenerate,
            "constraints": {"F_r_c_N": result.constraints.F_r_c,
                            "F_z_c_N": result.constraints.F_z_c,
                            "source": result.constraints.source},
            "exact_reduction_choice": {
                "H_mm": from_si(result.reduction_choice.design.H, "mm"),
                "G_kPa": from_si(result.reduction_choice.design.G, "kPa"),
                "Gamma_r_max_N_per_T": result.reduction_choice.design.Gamma_r_max,
                "Gamma_z_max_N_per_T": result.reduction_choice.design.Gamma_z_max,
                "active_constraints": list(result.reduction_choice.active)},
            "pareto_points": int(result.pareto.H.size), "gap_to_exact_front": result.gap,
            "timings_s": {"constraints": result.timings.constraints,
                          "sweep_and_reduction": result.timings.sweep,
                          "nsga2": result.timings.nsga2, "decision": result.timings.decision,
                          "maps": result.timings.maps, "total": result.timings.total}}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--models", default=None, help="folder of metamodel files")
    parser.add_argument("--repeats", type=int, default=2, help="timed runs (best is kept)")
    args = parser.parse_args(argv)
    study = load_study(None)
    models, source = load_models(args.models, study)
    R = as_responses(models)
    doc = {"machine": {"cpus": os.cpu_count(), "platform": platform.platform(),
                       "python": platform.python_version(),
                       "load_average_1min_at_start": os.getloadavg()[0]},
           "models": source, "target_s": TARGET_S, "settings": vars(study.optimise)}

    walls, result = [], None
    for _ in range(args.repeats):
        start = time.perf_counter()
        result = optimise(R, study)
        walls.append(time.perf_counter() - start)
    doc["default_constraints"] = chosen(result)
    doc["wall_time_s"] = {"runs": walls, "best": min(walls), "meets_target": min(walls) <= TARGET_S}
    print(f"default constraints: {min(walls):.1f} s, gap {result.gap:.2e}")

    ref = force_constraints(R, study, reference=(study.design.H_original,
                                                  study.design.G_original))
    result_ref = optimise(R, study, ref)
    doc["reference_constraints"] = chosen(result_ref)
    doc["reference_constraints"]["reference_design"] = {
        "H_mm": from_si(study.design.H_original, "mm"),
        "G_kPa": from_si(study.design.G_original, "kPa")}

    checks = [brute_force(R, study, H) for H in np.linspace(*study.design.H, 5)]
    doc["brute_force"] = {"grid": list(GRID), "heights": checks,
                          "max_rel_diff": max(c[k]["rel_diff"] for c in checks
                                              for k in ("f_r_min", "f_z_max", "gamma_r_max",
                                                        "gamma_z_max")),
                          "optimiser_never_worse": all(
                              c[k]["optimiser_not_worse"] for c in checks
                              for k in ("f_r_min", "f_z_max", "gamma_r_max", "gamma_z_max"))}
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(doc, indent=1, default=float) + "\n")
    print(json.dumps({k: doc[k] for k in ("wall_time_s", "default_constraints",
                                          "reference_constraints")}, indent=1, default=float))
    print(f"brute force: max rel diff {doc['brute_force']['max_rel_diff']:.2e}")


if __name__ == "__main__":
    main()
