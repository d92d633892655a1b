"""The error–cost frontier of the structural forces: discretisations measured against each other.

For θ = θ_max and H = 3 and 7 mm, every route gives F_z(t = 1) and min F_r over t on a sequence
of meshes; a point of the frontier is one mesh of one route: its wall time per path (one core)
and the relative change of its forces against the next finer mesh of the same route.

Routes:

- ``hex8``: trilinear Q1/P0 hexahedra (the default) on the ``coarse``, ``default``,
  ``default_x1.5`` and ``fine`` meshes (refinement 2, 1.5 and 2 per direction from ``coarse``).
  The ``default``, ``default_x1.5`` and ``fine`` paths are those of
  ``bench/bench_mechanics.py --part convergence`` and ``--part order``; ``coarse`` runs here.
- ``hex27``: triquadratic Q2/P0 hexahedra (``mechanics.element = "hex27"``) on
  ``coarse_x0.67``, ``coarse`` and ``coarse_x1.5`` (refinement 1.5 per direction; the two
  densities exist only in this benchmark).
- ``hex20``: 20-node serendipity Q2s/P0 hexahedra (``mechanics.element = "hex20"``) on the same
  three meshes.
- ``richardson``: hex8 forces extrapolated from a pair of meshes with the observed order 1,
  F ≈ (r F(h/r) − F(h)) / (r − 1); its cost is that of both meshes, its change is against the
  extrapolation of the next finer pair.
- ``multi-fidelity``: the 25 default-mesh DOE paths corrected by a relation to a finer mesh
  fitted on 5 of them (corners and centre of the (θ, H) grid; bilinear in θ and H at every t),
  checked on the other 20 against the finer mesh (``bench/results/doe_accurate.nc``); its
  cost is the default path plus a fifth of a finer path.

    python bench/bench_frontier.py run --route hex27 --mesh coarse --H 3   # one path (minutes)
    python bench/bench_frontier.py assemble                               # JSON and figure

``run`` adds its record to ``bench/results/frontier_runs.json``; ``assemble`` writes
``bench/results/frontier.json`` and ``frontier.png``.
"""

from __future__ import annotations

import os

# one core per path: no BLAS threads (numpy's einsum calls BLAS; on a shared machine its
# threads make the tangent assembly many times slower), as in the DOE's workers
for _var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from magtact.geometry._body_mesh import _GRADING, DENSITIES  # noqa: E402

RESULTS = Path(__file__).parent / "results"
RUNS = RESULTS / "frontier_runs.json"
SUPERSEDED = RESULTS / "frontier_runs_superseded.json"
#: Densities of this benchmark only: the coarse mesh with 2/3 and 1.5 times its cells per
#: direction (counts rounded).
DENSITIES.setdefault("coarse_x0.67", {"m": 2, "radial": (1, 2, 1), "h_z": 1.8e-3,
                                      "n_corner": 1} | _GRADING)
DENSITIES.setdefault("coarse_x1.5", {"m": 5, "radial": (3, 5, 3), "h_z": 0.8e-3,
                                     "n_corner": 3} | _GRADING)
#: The coarse mesh with 2 instead of 3 cells along a quarter of the half circle (the direction
#: in which the hex8 error was smallest at H = 3 mm).
DENSITIES.setdefault("coarse_m2", DENSITIES["coarse"] | {"m": 2})
#: ... and one cell across the rounded top edge instead of 2.
DENSITIES.setdefault("coarse_m2_c1", DENSITIES["coarse"] | {"m": 2, "n_corner": 1})
#: Observed orders taken as clean enough to extrapolate with.
CLEAN_ORDER = (0.5, 4.0)
#: Mesh sequence of each route, coarse to fine, with the refinement to the next mesh.
SEQUENCES = {
    "hex8": [("coarse", 2.0), ("default", 2.0), ("fine", None)],
    "hex27": [("coarse_x0.67", 1.5), ("coarse", 1.5), ("coarse_x1.5", None)],
    "hex20": [("coarse_x0.67", 1.5), ("coarse", 1.5), ("coarse_x1.5", None)],
    "hex20-faces": [("coarse_x0.67", 1.5), ("coarse", 1.5), ("coarse_x1.5", None)],
    "hex27-faces": [("coarse_x0.67", 1.5), ("coarse", 1.5), ("coarse_x1.5", None)],
}
#: Routes: the element, and "-faces" for contact integrated at the faces' Gauss points
#: (``mechanics.contact = "faces"``; node-wise otherwise).
ROUTES = ("hex8", "hex20", "hex27", "hex8-faces", "hex20-faces", "hex27-faces")


def _git_commit() -> str:
    import subprocess

    try:
        out = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                             text=True, cwd=Path(__file__).parent, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--", "../src"],
                               capture_output=True, text=True, cwd=Path(__file__).parent,
                               check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return out + ("+modified" if dirty else "")


def _key(rec: dict) -> tuple:
    return rec["route"], rec["mesh"], rec["H_mm"], rec.get("variant", "")


def _load_runs() -> list[dict]:
    return json.loads(RUNS.read_text()) if RUNS.is_file() else []


def _save(path: Path, data) -> None:
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(data, indent=1))
    os.replace(tmp, path)


def run(route: str, mesh: str, H_mm: float, reuse_ratio: float = 0.0,
        penalty_per_class: bool = False, tol_cycling: float | None = None,
        elastic_slip_mm: float | None = None, contact_penalty: float | None = None) -> dict:
    """Solve one path at θ_max and add its record to ``frontier_runs.json``.

    ``reuse_ratio`` > 0 runs the Newton iterations with tangents kept while they contract the
    residual by that factor (``Stepping.reuse_ratio``); the record is then a variant of the
    route (``"variant": "reuse_<ratio>"``), kept beside the plain one; so is
    ``penalty_per_class`` (``HalfBodyModel(penalty_per_node_class=True)``) and
    ``tol_cycling`` (``Stepping.tol_cycling`` instead of its default), ``elastic_slip_mm``
    (``mechanics.elastic_slip_mm`` instead of the study's) and ``contact_penalty``
    (``mechanics.contact_penalty`` instead of the study's).
    """
    from dataclasses import replace

    from magtact.mechanics import PathFailed, _simulate, simulate_path
    from magtact.study import load_study

    study = load_study("magone")
    element, _, contact = route.partition("-")
    study = replace(study, mechanics=replace(study.mechanics, element=element,
                                             contact=contact or "nodes", threads=1))
    variant = f"reuse_{reuse_ratio:g}" if reuse_ratio > 0 else ""
    if elastic_slip_mm is not None:
        variant = "+".join(v for v in (variant, f"elastic_slip_{elastic_slip_mm:g}mm") if v)
        study = replace(study, mechanics=replace(study.mechanics,
                                                 elastic_slip=elastic_slip_mm * 1e-3))
    if contact_penalty is not None:
        variant = "+".join(v for v in (variant, f"penalty_{contact_penalty:g}") if v)
        study = replace(study, mechanics=replace(study.mechanics,
                                                 contact_penalty=contact_penalty))
    if reuse_ratio > 0:
        plain = _simulate.stepping_of
        _simulate.stepping_of = lambda s: replace(plain(s), reuse_ratio=reuse_ratio)
    if tol_cycling is not None:
        variant = "+".join(v for v in (variant, f"tol_cycling_{tol_cycling:g}") if v)
        plain_stepping = _simulate.stepping_of
        _simulate.stepping_of = lambda s: replace(plain_stepping(s), tol_cycling=tol_cycling)
    if penalty_per_class:
        from functools import partial

        variant = "+".join(v for v in (variant, "penalty_per_class") if v)
        _simulate.HalfBodyModel = partial(_simulate.HalfBodyModel, penalty_per_node_class=True)
    rec = {"route": route, "mesh": mesh, "H_mm": H_mm, "variant": variant,
           "theta_rad": study.loading.theta_max,
           "machine": {"platform": platform.platform(), "cpus": os.cpu_count(),
                       "load_average_at_start": os.getloadavg()},
           "code": _git_commit(),
           "blas_threads": os.environ.get("OPENBLAS_NUM_THREADS")}
    t0 = time.perf_counter()
    try:
        r = simulate_path(study, H_mm * 1e-3, study.loading.theta_max, mesh=mesh)
        rec |= {"completed": True, "wall_time_s": round(r.wall_time, 2), "n_dofs": r.n_dofs,
                "n_cells": r.n_cells, "steps": r.steps, "jacobians": r.jacobians,
                "newton_iterations": r.newton_iterations,
                "timings_s": {k: round(v, 2) for k, v in r.timings.items()},
                "F_z_t1_N": float(r.F_z[-1]), "F_r_min_N": float(np.min(r.F_r)),
                "t": r.t.tolist(), "F_z_N": r.F_z.tolist(), "F_r_N": r.F_r.tolist()}
    except PathFailed as exc:
        rec |= {"completed": False, "error": str(exc),
                "wall_time_s": round(time.perf_counter() - t0, 2)}
    # the wall time is measured on a shared machine: the load beside it says how shared
    rec["machine"]["load_average_at_end"] = os.getloadavg()
    old = _load_runs()
    key = (route, mesh, H_mm, variant)
    replaced = [r for r in old if _key(r) == key]
    if replaced:  # earlier records of the same path (older code) are kept aside
        _save(SUPERSEDED, (json.loads(SUPERSEDED.read_text()) if SUPERSEDED.is_file() else [])
              + replaced)
    _save(RUNS, [r for r in old if _key(r) != key] + [rec])
    return rec


def _convergence_records() -> list[dict]:
    """The hex8 paths of the mechanics benchmark (default, default_x1.5, fine)."""
    out = []
    for h in (3, 7):
        f = RESULTS / f"mechanics_convergence_H{h}.json"
        if f.is_file():
            for mesh in ("default", "fine"):
                rec = json.loads(f.read_text())["cases"][0].get(mesh)
                if rec and rec.get("completed"):
                    out.append(rec | {"route": "hex8"})
    f = RESULTS / "mechanics_order.json"
    if f.is_file():
        out += [c | {"route": "hex8"} for c in json.loads(f.read_text())["cases"]
                if c.get("completed")]
    return out


def _load(rec: dict) -> float | None:
    """1-minute load average at the start of a run (None where the record has none)."""
    load = rec.get("machine", {}).get("load_average_at_start")
    return None if load is None else round(float(load[0]), 2)


def _change(a: float, b: float) -> float:
    return abs(a / b - 1)


def _mesh_points(records: list[dict]) -> tuple[list[dict], list[dict]]:
    """Frontier points of the mesh routes and of Richardson extrapolation, and observed orders
    (of a route's variants too where all three of its meshes completed)."""
    by = {(r["route"], r["mesh"], r["H_mm"]): r for r in records
          if r.get("completed") and not r.get("variant")}
    done = {_key(r): r for r in records if r.get("completed")}
    points, orders = [], []
    for route, seq in SEQUENCES.items():
        for H in (3.0, 7.0):
            for (mesh, ratio), (finer, _) in zip(seq[:-1], seq[1:], strict=True):
                a, b = by.get((route, mesh, H)), by.get((route, finer, H))
                if a and b:
                    points.append({
                        "route": route, "mesh": mesh, "next": finer, "refinement": ratio,
                        "H_mm": H, "wall_time_s": a["wall_time_s"], "n_dofs": a["n_dofs"],
                        "load_1min": _load(a),
                        "F_z_t1_N": a["F_z_t1_N"], "F_r_min_N": a["F_r_min_N"],
                        "change_F_z_t1": _change(a["F_z_t1_N"], b["F_z_t1_N"]),
                        "change_F_r_min": _change(a["F_r_min_N"], b["F_r_min_N"])})
            for variant in sorted({k[3] for k in done if k[0] == route}):
                trio = [done.get((route, m, H, variant)) for m, _ in seq]
                if not all(trio):
                    continue
                r = seq[0][1]
                rec = {"route": route + (f" ({variant})" if variant else ""), "H_mm": H,
                       "meshes": [m for m, _ in seq]}
                for key in ("F_z_t1_N", "F_r_min_N"):
                    f1, f2, f3 = (t[key] for t in trio)
                    q = (f1 - f2) / (f2 - f3)
                    p = float(np.log(q) / np.log(r)) if q > 0 else None
                    rec[f"order_{key[:-2]}"] = p
                    if p is not None and CLEAN_ORDER[0] <= p <= CLEAN_ORDER[1]:
                        # the route's own limit: extrapolation of its two finest meshes
                        rec[f"limit_{key}"] = f3 + (f3 - f2) / (seq[1][1] ** p - 1)
                orders.append(rec)
    # Richardson (order 1) on consecutive hex8 pairs of the same refinement
    for H in (3.0, 7.0):
        pairs = [("coarse", "default", 2.0), ("default", "fine", 2.0),
                 ("default", "default_x1.5", 1.5)]
        ext = {}
        for lo, hi, r in pairs:
            a, b = by.get(("hex8", lo, H)), by.get(("hex8", hi, H))
            if a and b:
                ext[(lo, hi)] = {k: (r * b[k] - a[k]) / (r - 1) for k in ("F_z_t1_N", "F_r_min_N")}
                ext[(lo, hi)]["wall_time_s"] = a["wall_time_s"] + b["wall_time_s"]
        for coarse_pair, fine_pair in ((("coarse", "default"), ("default", "fine")),):
            if coarse_pair in ext and fine_pair in ext:
                e, f = ext[coarse_pair], ext[fine_pair]
                points.append({
                    "route": "richardson", "mesh": "+".join(coarse_pair),
                    "next": "+".join(fine_pair), "refinement": 2.0, "H_mm": H,
                    "wall_time_s": e["wall_time_s"], "F_z_t1_N": e["F_z_t1_N"],
                    "F_r_min_N": e["F_r_min_N"],
                    "change_F_z_t1": _change(e["F_z_t1_N"], f["F_z_t1_N"]),
                    "change_F_r_min": _change(e["F_r_min_N"], f["F_r_min_N"])})
        if ("default", "fine") in ext and ("default", "default_x1.5") in ext:
            limit = ext[("default", "fine")]
            rec = {"route": "richardson", "H_mm": H, "limit_from_default_fine": limit,
                   "limit_from_default_x1.5": ext[("default", "default_x1.5")]}
            candidates = [(r, m, by[(r, m, h)]) for (r, m, h) in by if h == H]
            candidates += [(f"{r['route']} ({r['variant']})", r["mesh"], r) for r in records
                           if r.get("variant") and r.get("completed") and r["H_mm"] == H]
            candidates += [("richardson", f"{lo}+{hi}", ext[(lo, hi)]) for lo, hi in ext
                           if (lo, hi) != ("default", "fine")]
            own = next((o for o in orders if o["route"] == "hex8" and o["H_mm"] == H
                        and "meshes" in o), {})
            rec["limit_observed_order"] = {k: own[f"limit_{k}"] for k in ("F_z_t1_N", "F_r_min_N")
                                           if f"limit_{k}" in own}
            for route, mesh, a in candidates:  # each against the extrapolated hex8 limit
                if mesh == "fine" and route == "hex8":
                    continue  # one of the two meshes that define the limit
                rec.setdefault("vs_limit", []).append(
                    {"route": route, "mesh": mesh, "wall_time_s": a["wall_time_s"],
                     "load_1min": _load(a)}
                    | {f"change_{k[:-2]}": abs(a[k] / limit[k] - 1)
                       for k in ("F_z_t1_N", "F_r_min_N")}
                    | {f"change_{k[:-2]}_vs_observed_order": abs(a[k] / v - 1)
                       for k, v in rec["limit_observed_order"].items()})
            orders.append(rec)
    return points, orders


def _multi_fidelity(n_fit_paths: int = 5) -> dict | None:
    """Correct the 25 default DOE paths with a relation fitted on 5 paths of the finer DOE."""
    from magtact.doe import load_bundled, load_dataset

    finer = RESULTS / "doe_accurate.nc"
    if not finer.is_file():
        return None
    lo, hi = load_bundled(), load_dataset(finer)

    def arr(ds, k):
        return ds[k].transpose("t", "theta", "H", "G").values[..., 0]

    th, H = lo.theta.values, lo.H.values
    grid = [(i, j) for i in range(len(th)) for j in range(len(H))]
    fit = [(0, 0), (0, len(H) - 1), (len(th) - 1, 0), (len(th) - 1, len(H) - 1),
           (len(th) // 2, len(H) // 2)][:n_fit_paths]
    check = [g for g in grid if g not in fit]

    def basis(ix):
        return np.array([[1.0, th[i], H[j], th[i] * H[j]] for i, j in ix])

    Fz_lo = arr(lo, "F_z")
    out = {"fit_paths": len(fit), "check_paths": len(check), "finer_mesh": "accurate"}
    for name in ("F_z", "F_r"):
        f_lo, f_hi = arr(lo, name), arr(hi, name)
        corrected = np.empty_like(f_lo)
        for k in range(f_lo.shape[0]):  # the change relative to |F_z|, bilinear in (θ, H)
            scale = np.maximum(np.abs(Fz_lo[k]), 1e-12)
            y = np.array([(f_hi[k, i, j] - f_lo[k, i, j]) / scale[i, j] for i, j in fit])
            c, *_ = np.linalg.lstsq(basis(fit), y, rcond=None)
            corrected[k] = f_lo[k] + (basis(grid) @ c).reshape(f_lo.shape[1:]) * scale
        if name == "F_z":
            raw = [_change(f_lo[-1, i, j], f_hi[-1, i, j]) for i, j in check]
            new = [_change(corrected[-1, i, j], f_hi[-1, i, j]) for i, j in check]
            key = "F_z_t1"
        else:
            sheared = [(i, j) for i, j in check if th[i] > 0]
            raw = [_change(f_lo[:, i, j].min(), f_hi[:, i, j].min()) for i, j in sheared]
            new = [_change(corrected[:, i, j].min(), f_hi[:, i, j].min()) for i, j in sheared]
            key = "F_r_min"
        out[f"change_{key}_uncorrected_max"] = float(max(raw))
        out[f"change_{key}_corrected_max"] = float(max(new))
        out[f"change_{key}_corrected_median"] = float(np.median(new))
    jobs = {k: json.loads(ds.attrs["jobs"]) for k, ds in (("default", lo), ("finer", hi))}
    t_lo = float(np.mean([j["wall_time"] for j in jobs["default"]]))
    t_hi = float(np.mean([j["wall_time"] for j in jobs["finer"]]))
    out |= {"wall_time_default_s": t_lo, "wall_time_finer_s": t_hi,
            "wall_time_s": t_lo + len(fit) / len(grid) * t_hi}
    return out


def _cheapest(orders: list[dict], target: dict) -> dict:
    """Per height, the cheapest measured route whose forces are within the target of the
    extrapolated limit: F_z(t = 1) alone, and F_z(t = 1) with min F_r."""
    out = {}
    for rec in orders:
        if "vs_limit" not in rec:
            continue
        fz = [p for p in rec["vs_limit"] if p["change_F_z_t1"] <= target["change_F_z_t1"]]
        both = [p for p in fz if p["change_F_r_min"] <= target["change_F_r_min"]]
        # against the observed-order limit where the hex8 order is clean, else order 1
        def change(p, k):
            return p.get(f"change_{k}_vs_observed_order", p[f"change_{k}"])

        both_own = [p for p in rec["vs_limit"]
                    if change(p, "F_z_t1") <= target["change_F_z_t1"]
                    and change(p, "F_r_min") <= target["change_F_r_min"]]
        out[f"H_{rec['H_mm']:g}_mm"] = {
            "F_z_t1": min(fz, key=lambda p: p["wall_time_s"]) if fz else None,
            "F_z_t1_and_F_r_min": min(both, key=lambda p: p["wall_time_s"]) if both else None,
            "F_z_t1_and_F_r_min_observed_order":
                min(both_own, key=lambda p: p["wall_time_s"]) if both_own else None,
            "observed_order_limits": sorted(rec["limit_observed_order"])}
    return out


def assemble() -> dict:
    runs = _load_runs()
    records = _convergence_records() + runs
    points, orders = _mesh_points(records)
    mf = _multi_fidelity()
    if mf is not None:
        points.append({"route": "multi-fidelity", "mesh": "default + 5 accurate paths",
                       "next": "accurate", "H_mm": "all 25 DOE paths",
                       "wall_time_s": mf["wall_time_s"],
                       "change_F_z_t1": mf["change_F_z_t1_corrected_max"],
                       "change_F_r_min": mf["change_F_r_min_corrected_max"]})
    data = {"points": points, "orders": orders, "multi_fidelity": mf,
            "failed_runs": [r for r in runs if not r.get("completed")],
            "target": {"change_F_z_t1": 0.01, "change_F_r_min": 0.02,
                       "doe_minutes_2_workers": 15, "seconds_per_path": 15 * 60 * 2 / 25}}
    data["cheapest_within_target"] = _cheapest(orders, data["target"])
    _save(RESULTS / "frontier.json", data)
    _figure(data, RESULTS / "frontier.png")
    return data


def _figure(data: dict, path: Path) -> None:
    """Top: change against the next finer mesh of the same route. Bottom: difference from the
    hex8 forces extrapolated from the default and fine meshes (order 1)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(10, 7.5), sharex=True)
    style = {"hex8": ("o", "C0"), "hex27": ("s", "C1"), "hex20": ("v", "C4"),
             "hex20-faces": ("P", "C5"), "hex27-faces": ("X", "C6"), "hex8-faces": ("*", "C7"),
             "richardson": ("^", "C2"), "multi-fidelity": ("D", "C3")}
    limits = {o["H_mm"]: o["vs_limit"] for o in data["orders"] if "vs_limit" in o}
    for col, (key, target) in enumerate((("change_F_z_t1", 0.01), ("change_F_r_min", 0.02))):
        for row in range(2):
            ax = axes[row, col]
            for route, (marker, colour) in style.items():
                for H, fill in ((3.0, colour), (7.0, "none"), ("all 25 DOE paths", colour)):
                    if row == 0:
                        sel = [p for p in data["points"]
                               if p["route"] == route and p["H_mm"] == H]
                    else:
                        sel = sorted((p for p in limits.get(H, []) if p["route"] == route),
                                     key=lambda p: p["wall_time_s"])
                    if sel:
                        ax.loglog([p["wall_time_s"] for p in sel],
                                  [max(100 * p[key], 1e-3) for p in sel], marker,
                                  color=colour, mfc=fill, linestyle="-",
                                  label=f"{route}, H = {H:g} mm" if H in (3.0, 7.0) else route)
            ax.axhline(100 * target, color="k", lw=0.8, ls="--")
            ax.axvline(data["target"]["seconds_per_path"], color="grey", lw=0.8, ls=":")
            name = "F_z(t = 1)" if key.endswith("t1") else "min F_r"
            ax.set_ylabel(f"{name}: change vs next finer mesh [%]" if row == 0
                          else f"{name}: difference from the limit [%]")
            if row == 1:
                ax.set_xlabel("wall time per path on one core [s]")
        axes[0, col].set_title("against the next finer mesh of the route" if col == 0 else "")
    axes[1, 0].set_title("against the hex8 limit extrapolated from default + fine")
    axes[0, 0].legend(fontsize=7)
    axes[1, 0].legend(fontsize=7)
    fig.suptitle("Error–cost frontier of the structural forces (θ = θ_max); dashed: target, "
                 "dotted: 72 s per path (25 paths, 2 workers, 15 min)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--route", choices=ROUTES, required=True)
    r.add_argument("--mesh", required=True)
    r.add_argument("--H", type=float, required=True, help="base height [mm]")
    r.add_argument("--reuse-ratio", type=float, default=0.0,
                   help="keep a tangent while it contracts the residual by this factor")
    r.add_argument("--penalty-per-class", action="store_true",
                   help="contact penalty per class of surface node (27-node cells)")
    r.add_argument("--elastic-slip-mm", type=float, default=None,
                   help="allowable elastic slip of sticking contact points [mm]")
    r.add_argument("--tol-cycling", type=float, default=None,
                   help="Newton tolerance once the contact state cycles (Stepping.tol_cycling)")
    r.add_argument("--contact-penalty", type=float, default=None,
                   help="contact penalty relative to the solid's nodal stiffness")
    sub.add_parser("assemble")
    args = ap.parse_args()
    if args.cmd == "run":
        print(json.dumps(run(args.route, args.mesh, args.H, args.reuse_ratio,
                             args.penalty_per_class, args.tol_cycling, args.elastic_slip_mm,
                             args.contact_penalty)))
    else:
        print(json.dumps(assemble(), indent=1)[:4000])


if __name__ == "__main__":
    main()
