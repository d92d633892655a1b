"""Benchmark of the structural stage: mesh convergence, the 25 DOE paths, solvers.

Writes ``bench/results/mechanics_<part>.json`` (after every path, so a long run can be inspected
while it runs; ``"complete": true`` once the part has finished). The parts can run in parallel.

    nice -n 10 python bench/bench_mechanics.py                # all parts
    nice -n 10 python bench/bench_mechanics.py --part grid    # one part
    python bench/bench_mechanics.py --part convergence --H 7  # one height: ..._H7.json

Parts:
- ``solver``: time to factorise the tangent of the default mesh (H = 7 mm, t = 0) with PARDISO
  and SuperLU, and the accuracy of both solutions.
- ``convergence``: θ = θ_max, H = 3 and 7 mm on the default and the fine mesh (twice the
  default's cells in every direction): F_z(t = 1) and min F_r and their relative change
  (target < 2 %).
  ``--reuse-fine`` keeps the fine paths of the existing JSON when nothing they depend on changed;
  ``--t-max 0.6`` follows the paths only to t = 0.6 (min F_r of the paths whose fine version
  fails near t = 1).
- ``grid``: every (θ, H) of the default DOE grid on the default mesh: completion, wall time,
  Newton iterations, Jacobians, cut-backs, and where the time goes.
- ``directions``: θ = θ_max on the default mesh with one of its parameters doubled at a time
  (cells in z, radially, around the circle, across the rounded edge; radially also one ring at
  a time): which direction and which ring carries the discretisation error, against the fine
  mesh of the ``convergence`` part if it was run.
- ``order``: θ = θ_max on the default mesh with 1.5 times its cells in every direction; with the
  default and fine paths of the ``convergence`` part (1 and 2 times), the observed order p of
  F_z(t = 1) and min F_r in the cell size (F = F_∞ + C h^p), and from it the predicted change
  between a mesh k times the default and its doubled mesh, and the smallest k with < 2 %; with
  the nominal refinement (1.5, 2) and with the cube root of the cell counts (the 1.5 mesh rounds
  its counts up, so it is 1.5 in z and 1.5–1.67 in the other directions).
- ``accurate``: θ = θ_max on the ``accurate`` mesh (the default refined in z and radially), as
  it is and with the other grading of the layer under the magnet (``grade_magnet_face``
  switched), against the fine mesh of the ``convergence`` part if it was run.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from functools import partial
from pathlib import Path

import numpy as np

from magtact.geometry._body_mesh import DENSITIES
from magtact.mechanics import PathFailed, build_model, simulate_path
from magtact.study import load_study

RESULTS = Path(__file__).parent / "results"


def _path_record(r) -> dict:
    """JSON record of a path; the forces at its last level are keyed ``*_t1_N`` when that level
    is t = 1, else ``*_t_end_N``."""
    i = int(np.argmin(r.F_r))
    end = "t1" if r.t[-1] == 1 else "t_end"
    return {
        "H_mm": r.H * 1e3, "theta_rad": r.theta, "mesh": r.mesh, "n_dofs": r.n_dofs,
        "n_cells": r.n_cells, "completed": True, "wall_time_s": round(r.wall_time, 2),
        "newton_iterations": r.newton_iterations, "jacobians": r.jacobians,
        "cutbacks": r.cutbacks, "steps": r.steps,
        "timings_s": {k: round(v, 2) for k, v in r.timings.items()},
        f"F_z_{end}_N": float(r.F_z[-1]), f"F_r_{end}_N": float(r.F_r[-1]),
        "F_r_min_N": float(r.F_r[i]), "t_at_F_r_min": float(r.t[i]),
        "F_z_N": r.F_z.tolist(), "F_r_N": r.F_r.tolist(),
    }


def _save(data: dict) -> None:
    RESULTS.mkdir(parents=True, exist_ok=True)
    target = RESULTS / f"mechanics_{data['part']}.json"
    tmp = target.with_suffix(".tmp")
    tmp.write_text(json.dumps(data, indent=1))
    os.replace(tmp, target)


def _header(study, part: str) -> dict:
    import felupe as fem

    return {
        "part": part, "complete": False,
        "machine": {"platform": platform.platform(), "cpus": os.cpu_count(),
                    "load_average_at_start": os.getloadavg(), "felupe": fem.__version__,
                    "note": "2 cores; other work on the machine shows in the load average"},
        "settings": {k: getattr(study.mechanics, k) for k in study.mechanics.__dataclass_fields__},
        "densities": {k: {kk: list(vv) if isinstance(vv, tuple) else vv for kk, vv in v.items()}
                      for k, v in DENSITIES.items()},
    }


def part_solver(study) -> None:
    data = _header(study, "solver")
    model = build_model(study, 7e-3, mesh="default")
    K = model.items[0].assemble.matrix()
    for c in model.contacts:
        K = K + c.assemble.matrix()
    A = K.tocsr()[model.dof1][:, model.dof1].tocsr()
    b = np.random.default_rng(0).normal(size=A.shape[0])
    out = {"n": int(A.shape[0]), "nnz": int(A.nnz)}
    from magtact.mechanics._model import _linear_solver

    for name in ("pardiso", "superlu"):
        solver = _linear_solver(name, study.mechanics.threads)
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            solver.factorize(A)
            times.append(time.perf_counter() - t0)
        x = solver.solve(b)
        out[name] = {"factorize_s": [round(t, 3) for t in times],
                     "relative_residual": float(np.linalg.norm(A @ x - b) / np.linalg.norm(b))}
        solver.free()
    data |= out
    data["complete"] = True
    _save(data)


def _previous_fine(data: dict) -> dict:
    """Fine-mesh records {H_mm: record} of an earlier run of this part with the same solver
    settings and the same fine mesh (a run that did not record the densities is taken to have
    used the current fine mesh), each marked as reused."""
    path = RESULTS / f"mechanics_{data['part']}.json"
    old = json.loads(path.read_text()) if path.is_file() else {}
    if old.get("settings") != data["settings"] or (
            "densities" in old and old["densities"]["fine"] != data["densities"]["fine"]):
        return {}
    note = {"reused_from_run_with_load_average": old["machine"]["load_average_at_start"]}
    return {c["H_mm"]: c["fine"] | note for c in old.get("cases", []) if "fine" in c}


def part_convergence(study, heights_mm: list[float], reuse_fine: bool = False,
                     t_max: float = 1.0) -> None:
    theta = study.loading.theta_max
    t = study.t_levels[study.t_levels <= t_max + 1e-12]
    name = "convergence" + _suffix(heights_mm) + ("" if t_max >= 1 else f"_to{t_max:g}")
    data = _header(study, name) | {"cases": [], "t_max": float(t[-1])}
    previous = _previous_fine(data) if reuse_fine else {}
    cases = {h * 1e-3: {"H_mm": h, "theta_rad": theta} for h in heights_mm}
    data["cases"] = list(cases.values())
    for mesh in ("default", "fine"):  # both default paths first: the fine ones are long
        for H, case in cases.items():
            if mesh == "fine" and case["H_mm"] in previous:
                case[mesh] = previous[case["H_mm"]]
            else:
                try:
                    case[mesh] = _path_record(simulate_path(study, H, theta, mesh=mesh, t=t))
                except PathFailed as exc:
                    case[mesh] = {"mesh": mesh, "completed": False, "error": str(exc)}
            if mesh == "fine" and case["default"]["completed"] and case["fine"]["completed"]:
                d, f = case["default"], case["fine"]
                # on a shortened path (t_max < 1) only min F_r over t ≤ t_max is compared
                if t_max >= 1:
                    case["change_F_z_t1"] = abs(d["F_z_t1_N"] / f["F_z_t1_N"] - 1)
                case["change_F_r_min"] = abs(d["F_r_min_N"] / f["F_r_min_N"] - 1)
                case["below_2_percent"] = bool(
                    max(case.get("change_F_z_t1", 0.0), case["change_F_r_min"]) < 0.02)
            _save(data)
    data["complete"] = True
    _save(data)


def _convergence_record(h: float, mesh: str) -> dict | None:
    """The completed ``mesh`` ("default" or "fine") record of the ``convergence`` part at
    H = h mm, if it was run."""
    conv = RESULTS / f"mechanics_convergence_H{h:g}.json"
    rec = json.loads(conv.read_text())["cases"][0].get(mesh) if conv.is_file() else None
    return rec if rec and rec["completed"] else None


def _observed_order(f: tuple[float, float, float], k: tuple[float, float],
                    target: float = 0.02) -> dict:
    """Fit F(k) = F_∞ + C k^(−p) to the values ``f`` at 1, k[0] and k[1] times the default's cells
    per direction; then the predicted relative change between k and 2k times the default and
    the smallest such k with a change below ``target`` (order None where no p in (0.05, 8)
    fits)."""
    from scipy.optimize import brentq

    f1, f15, f2 = f
    a, b = 1 / k[0], 1 / k[1]
    ratio = (f1 - f15) / (f15 - f2) if f15 != f2 else np.inf
    g = lambda p: (1 - a**p) / (a**p - b**p) - ratio  # noqa: E731 (increasing in p)
    out = {"refinement": list(k), "ratio_of_differences": ratio, "order": None}
    if not (g(0.05) < 0 < g(8.0)):
        return out
    p = brentq(g, 0.05, 8.0)
    C = (f1 - f15) / (1 - a**p)
    f_inf = f1 - C

    def change(k):
        return abs(C * k**-p * (1 - 2**-p)) / abs(f_inf + C * k**-p)

    k_min = brentq(lambda k: change(k) - target, 1.0, 1e6) if change(1.0) > target else 1.0
    return out | {"order": p, "extrapolated": f_inf, "error_of_default": abs(C / f_inf),
                  "predicted_change_default_vs_x2": change(1.0),
                  f"k_min_for_{target:g}": k_min}


def part_order(study, heights_mm: list[float]) -> None:
    base = DENSITIES["default"]

    def up(n):
        return int(1.5 * n + 0.5)

    DENSITIES["default_x1.5"] = base | {
        "m": up(base["m"]), "radial": tuple(map(up, base["radial"])), "h_z": base["h_z"] / 1.5,
        "n_corner": up(base["n_corner"])}
    data = _header(study, "order" + _suffix(heights_mm)) | {"cases": []}
    for h in heights_mm:
        d, f = _convergence_record(h, "default"), _convergence_record(h, "fine")
        rec = _theta_max_path(study, h, "default_x1.5", f)
        if d and f and rec["completed"]:
            # two measures of the refinement: the nominal one (exact in z, where most of the
            # error is) and the cube root of the cell counts (the counts round up)
            cells = [(r["n_cells"] / d["n_cells"]) ** (1 / 3) for r in (rec, f)]
            rec["order"] = {
                f"{q}_{basis}": _observed_order((d[key], rec[key], f[key]), k)
                for q, key in (("F_z_t1", "F_z_t1_N"), ("F_r_min", "F_r_min_N"))
                for basis, k in (("nominal", (1.5, 2.0)), ("cells", tuple(cells)))}
            rec["values_x1_x1.5_x2"] = {key: [d[key], rec[key], f[key]]
                                        for key in ("F_z_t1_N", "F_r_min_N")}
            rec["n_dofs_x1_x2"] = [d["n_dofs"], f["n_dofs"]]
        data["cases"].append(rec)
        print(f"H = {h:g} mm: {rec.get('error') or rec.get('order')}", flush=True)
        _save(data)
    data["complete"] = True
    _save(data)


def _versus_fine(rec: dict, fine: dict | None) -> dict:
    if fine is None:
        return rec
    return rec | {"change_vs_fine_F_z_t1": abs(rec["F_z_t1_N"] / fine["F_z_t1_N"] - 1),
                  "change_vs_fine_F_r_min": abs(rec["F_r_min_N"] / fine["F_r_min_N"] - 1)}


def _suffix(heights_mm: list[float]) -> str:
    return "" if heights_mm == [3.0, 7.0] else "_H" + "_".join(f"{h:g}" for h in heights_mm)


def _theta_max_path(study, h: float, mesh: str, fine: dict | None) -> dict:
    """Record of the θ_max path at H = h mm on ``mesh``, compared with ``fine``; a failed path
    is recorded with its error."""
    theta = study.loading.theta_max
    try:
        return _versus_fine(_path_record(simulate_path(study, h * 1e-3, theta, mesh=mesh)), fine)
    except PathFailed as exc:
        return {"H_mm": h, "theta_rad": theta, "mesh": mesh, "completed": False,
                "error": str(exc)}


def part_accurate(study, heights_mm: list[float]) -> None:
    base = DENSITIES["accurate"]
    flipped = not base["grade_magnet_face"]
    other = "accurate_" + ("graded_face" if flipped else "graded_base_only")
    DENSITIES[other] = base | {"grade_magnet_face": flipped}
    data = _header(study, "accurate" + _suffix(heights_mm)) | {"cases": []}
    for h in heights_mm:
        fine = _convergence_record(h, "fine")
        for mesh in ("accurate", other):
            rec = _theta_max_path(study, h, mesh, fine)
            data["cases"].append(rec | {"grade_magnet_face": DENSITIES[mesh]["grade_magnet_face"]})
            print(f"H = {h:g} mm, {mesh}: {rec.get('error') or rec['F_z_t1_N']}", flush=True)
            _save(data)
    data["complete"] = True
    _save(data)


def part_directions(study, heights_mm: list[float]) -> None:
    base = DENSITIES["default"]
    variants = {"z": {"h_z": base["h_z"] / 2},
                "radial": {"radial": tuple(2 * n for n in base["radial"])},
                "circumferential": {"m": 2 * base["m"]},
                "corner": {"n_corner": 2 * base["n_corner"]}}
    # the radial doubling split by ring: under the magnet, magnet's edge to the rounded edge,
    # rounded edge to the side
    for i, ring in enumerate(("radial_under_magnet", "radial_beside_magnet", "radial_outer")):
        variants[ring] = {"radial": tuple(2 * n if j == i else n
                                          for j, n in enumerate(base["radial"]))}
    data = _header(study, "directions" + _suffix(heights_mm)) | {"cases": []}
    for h in heights_mm:
        fine = _convergence_record(h, "fine")
        for direction, change in variants.items():
            DENSITIES[f"default_x2_{direction}"] = base | change
            rec = _theta_max_path(study, h, f"default_x2_{direction}", fine)
            data["cases"].append(rec | {"doubled": direction})
            print(f"H = {h:g} mm, doubled {direction}: "
                  f"{rec.get('error') or rec['F_z_t1_N']}", flush=True)
            _save(data)
    data["complete"] = True
    _save(data)


def part_grid(study) -> None:
    data = _header(study, "grid") | {"paths": []}
    for H in study.H_levels:
        for theta in study.theta_levels:
            try:
                rec = _path_record(simulate_path(study, float(H), float(theta)))
            except PathFailed as exc:
                rec = {"H_mm": float(H) * 1e3, "theta_rad": float(theta), "completed": False,
                       "error": str(exc), "mesh": study.mechanics.mesh}
            data["paths"].append(rec)
            print(f"H = {H * 1e3:.0f} mm, theta = {theta:.3f}: "
                  f"{rec.get('wall_time_s', 'failed')} s", flush=True)
            _save(data)
    ok = [p for p in data["paths"] if p["completed"]]
    walls = [p["wall_time_s"] for p in ok]
    data["summary"] = {
        "completed": len(ok), "total": len(data["paths"]),
        "wall_time_s": {"mean": float(np.mean(walls)), "max": float(np.max(walls))} if ok else None,
        "newton_iterations_mean": (float(np.mean([p["newton_iterations"] for p in ok]))
                                   if ok else None),
        "cutbacks_total": int(sum(p["cutbacks"] for p in ok)),
        "time_share": {k: float(sum(p["timings_s"][k] for p in ok) / sum(walls))
                       for k in ok[0]["timings_s"]} if ok else None,
    }
    data["complete"] = True
    _save(data)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--part", default="all", choices=("all", "solver", "convergence", "grid",
                                                      "directions", "accurate", "order"))
    ap.add_argument("--H", type=float, nargs="+", default=[3.0, 7.0],
                    help="base heights [mm] of the convergence, directions, accurate and order "
                         "parts (default 3 7); otherwise the JSON is named ..._H<..>.json")
    ap.add_argument("--reuse-fine", action="store_true",
                    help="convergence: keep the fine-mesh paths of the part's existing JSON if "
                         "its solver settings and fine mesh are the current ones (they take "
                         "10–45 min each); the default paths are always recomputed")
    ap.add_argument("--t-max", type=float, default=1.0,
                    help="convergence: follow the paths only to this load level (then only "
                         "min F_r up to it is compared; JSON ..._to<t_max>.json)")
    args = ap.parse_args()
    study = load_study(None)
    parts = (("solver", "convergence", "directions", "accurate", "order", "grid")
             if args.part == "all"
             else (args.part,))
    by_height = {"convergence": partial(part_convergence, reuse_fine=args.reuse_fine,
                                        t_max=args.t_max),
                 "directions": part_directions, "accurate": part_accurate, "order": part_order}
    for part in parts:
        if part in by_height:
            by_height[part](study, args.H)
        else:
            {"solver": part_solver, "grid": part_grid}[part](study)


if __name__ == "__main__":
    main()
