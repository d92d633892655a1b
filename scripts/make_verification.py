"""Write docs/verification.md from the benchmark results in bench/results/*.json.

Every number in the document is read from those files (or computed from numbers read there);
the text around them says what was measured and how to read it. Rerun after a benchmark::

    python scripts/make_verification.py [--results bench/results] [--out docs/verification.md]
"""

from __future__ import annotations

import argparse
import json
import re
import statistics
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def pct(x: float, digits: int = 1) -> str:
    """A fraction as a percentage with a sign only where it is negative."""
    return f"{100 * x:.{digits}f} %"


def spct(x: float, digits: int = 1) -> str:
    """A relative change as a signed percentage."""
    return f"{100 * x:+.{digits}f} %"


def rel(a: float, b: float) -> float:
    """Relative change (a − b) / |b|."""
    return (a - b) / abs(b)


def table(header: list[str], rows: list[list[str]]) -> list[str]:
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return out + [""]


class Results:
    """The JSON files of a results folder, by stem."""

    def __init__(self, folder: Path):
        self.folder = folder
        self.files = {p.stem: json.loads(p.read_text("utf-8"))
                      for p in sorted(folder.glob("*.json"))}

    def __getitem__(self, stem: str) -> dict:
        return self.files[stem]

    def source(self, stem: str) -> str:
        return f"`bench/results/{stem}.json`"


def field_section(r: Results) -> list[str]:
    f = r["field"]
    ex, fe = f["exact_vs_magpylib_max_rel"], f["fe_vs_exact_max_rel"]
    mesh = f["fe_mesh"]
    out = ["## Magnetic field", "",
           f"Source: {r.source('field')} (`bench/bench_field.py`), docs/method.md §2.", "",
           "**Exact field against magpylib.** Largest relative difference of the closed-form "
           f"cylinder field: {ex['below']:.1e} below the magnet, {ex['above']:.1e} above, "
           f"{ex['beside']:.1e} beside (round-off).", "",
           f"**Finite elements against the exact field** (default mesh: {mesh['triangles']:,} "
           f"triangles, {mesh['dofs_P2']:,} P2 unknowns; mesh and solve in "
           f"{f['fe_timing']['median_total_s']:.1f} s, median of "
           f"{len(f['fe_timing']['runs'])} runs): largest relative difference "
           f"{pct(fe['below'], 2)} below the magnet, {pct(fe['above'], 2)} above, "
           f"{pct(fe['beside'], 2)} beside, and {pct(f['fe_vs_exact_hall_points_max_rel'], 2)} "
           "over the Hall points of the DOE.", "",
           "**Convergence** on uniformly refined meshes below the magnet, for two far boxes "
           "(the far boundary does not limit the accuracy):", ""]
    rows = [[f"{c['far_r']:g} R_m × ±{c['far_z']:g} H_m", f"{c['size_factor']:g}",
             f"{c['triangles']:,}", pct(c["max_rel"], 3), pct(c["rms_rel"], 3),
             f"{c['rms_rate']:.2f}" if "rms_rate" in c else "–"]
            for c in f["refinement_below_magnet"]]
    out += table(["far box", "element size factor", "triangles", "max rel. error",
                  "rms rel. error", "rms rate"], rows)
    return out


def _case(path: dict) -> dict:
    return path


def mechanics_section(r: Results) -> list[str]:
    out = ["## Structural mechanics", "",
           "Sources: `bench/results/mechanics_*.json` (`bench/bench_mechanics.py`), "
           "docs/method.md §3. All paths at θ = θ_max, the hardest case; forces at t = 1 and "
           "the minimum of F_r along the path.", ""]
    cases = [r[f"mechanics_convergence_H{H}"]["cases"][0] for H in (3, 7)]
    met = all(c["below_2_percent"] for c in cases)
    out += ["### Default mesh against the `fine` mesh", "",
            "`fine` has twice the default's cells in every direction. The target of a change "
            f"below 2 % is {'met' if met else '**not** met'} by the default mesh:", ""]
    rows = []
    for c in cases:
        d, f = c["default"], c["fine"]
        rows.append([f"{c['H_mm']:g}", f"{d['n_dofs']:,} / {f['n_dofs']:,}",
                     f"{d['wall_time_s']:.0f} / {f['wall_time_s']:.0f}",
                     f"{d['F_z_t1_N']:.3f} / {f['F_z_t1_N']:.3f}", pct(c["change_F_z_t1"]),
                     f"{d['F_r_min_N']:.4f} / {f['F_r_min_N']:.4f}", pct(c["change_F_r_min"]),
                     "yes" if c["below_2_percent"] else "no"])
    out += table(["H [mm]", "DOFs default / fine", "time per path [s]", "F_z(t=1) [N]",
                  "change", "min F_r [N]", "change", "< 2 %"], rows)

    out += ["### Where the discretisation error sits", "",
            "Doubling the default's cells in one direction at a time: change of F_z(t = 1) "
            "and of min F_r against the default mesh (negative: the doubled mesh gives less).",
            ""]
    rows = []
    for H in (3, 7):
        default = r[f"mechanics_convergence_H{H}"]["cases"][0]["default"]
        for c in r[f"mechanics_directions_H{H}"]["cases"]:
            rows.append([f"{c['H_mm']:g}", c["doubled"].replace("_", " "), f"{c['n_dofs']:,}",
                         spct(rel(c["F_z_t1_N"], default["F_z_t1_N"]), 2),
                         spct(rel(abs(c["F_r_min_N"]), abs(default["F_r_min_N"])), 2)])
    out += table(["H [mm]", "cells doubled", "DOFs", "F_z(t=1)", "magnitude of min F_r"], rows)

    out += ["### Meshes between default and fine", "",
            "`accurate` (twice the default's cells in z and radially) and a mesh with 1.5 times "
            "the default's cells per direction, against `fine`:", ""]
    rows = []
    for c in r["mechanics_accurate"]["cases"]:
        rows.append([f"{c['H_mm']:g}", c["mesh"].replace("_", " "), f"{c['n_dofs']:,}",
                     f"{c['wall_time_s']:.0f}", pct(c["change_vs_fine_F_z_t1"], 2),
                     pct(c["change_vs_fine_F_r_min"], 2)])
    for c in r["mechanics_order"]["cases"]:
        rows.append([f"{c['H_mm']:g}", c["mesh"].replace("_", " "), f"{c['n_dofs']:,}",
                     f"{c['wall_time_s']:.0f}", pct(c["change_vs_fine_F_z_t1"], 2),
                     pct(c["change_vs_fine_F_r_min"], 2)])
    out += table(["H [mm]", "mesh", "DOFs", "time per path [s]", "F_z(t=1) vs fine",
                  "min F_r vs fine"], rows)
    orders = []
    for c in r["mechanics_order"]["cases"]:
        o = c["order"]["F_z_t1_nominal"]
        orders.append(f"H = {c['H_mm']:g} mm: order {o['order']:.2f}, predicted change of the "
                      f"default against its doubled mesh {pct(o['predicted_change_default_vs_x2'])}"
                      f", cells per direction for 2 %: {o['k_min_for_0.02']:.2f} × the default's")
    out += ["**Order of convergence** of F_z(t = 1) from the three meshes (refinements 1 : 1.5 : 2 "
            "taken as nominal; with the cube roots of the cell counts no order fits): "
            + "; ".join(orders) + ". min F_r is not in the asymptotic range.", ""]

    g = r["mechanics_grid"]["summary"]
    s = r["mechanics_solver"]
    out += ["### The 25 DOE paths and the linear solver", "",
            f"Default mesh ({r.source('mechanics_grid')}): {g['completed']} of {g['total']} paths "
            f"completed, {g['wall_time_s']['mean']:.0f} s per path on average (largest "
            f"{g['wall_time_s']['max']:.0f} s), {g['newton_iterations_mean']:.0f} Newton "
            f"iterations per path on average, {g['cutbacks_total']} step cut-backs in all. Time "
            f"split: factorisation {pct(g['time_share']['factorization'], 0)}, solid assembly "
            f"{pct(g['time_share']['solid'], 0)}, solves {pct(g['time_share']['solve'], 0)}, "
            f"contact {pct(g['time_share']['contact'], 0)}.", "",
            f"Factorisation of one tangent ({s['n']:,} unknowns, {s['nnz']:,} non-zeros; "
            f"{r.source('mechanics_solver')}): PARDISO "
            f"{statistics.median(s['pardiso']['factorize_s']):.2f} s, SciPy SuperLU "
            f"{statistics.median(s['superlu']['factorize_s']):.2f} s (medians of "
            f"{len(s['pardiso']['factorize_s'])}).", ""]
    return out


def fit_section(r: Results) -> list[str]:
    out = ["## Metamodels", "",
           f"Sources: {r.source('fit')} (bundled DOE) and {r.source('fit_accurate')} (the DOE "
           "on the `accurate` mesh), `bench/bench_fit.py`; docs/method.md §5. Held-out: whole "
           "(θ, H) paths never seen by the fit.", ""]
    rows = []
    for stem, label in (("fit", "bundled (default mesh)"), ("fit_accurate", "accurate mesh")):
        for name, m in r[stem]["models"].items():
            te = m["test"]
            rows.append([label, name, f"{te['r2']:.6f}", pct(te["max_abs_err_over_range"], 2),
                         pct(te["max_rel_err"], 1), pct(m["limit_max_abs_err_over_range"], 0),
                         f"{m['fit_time_s']:.0f}"])
    out += table(["data", "model", "held-out R²", "max error / range", "max rel. error",
                  "limit (error / range)", "fit time [s]"], rows)
    rough = [[label, *(pct(r[stem]["data_roughness_per_path_poly6"][k], 2)
                       for k in ("B_r", "B_z", "f_r", "f_z"))]
             for stem, label in (("fit", "bundled (default mesh)"),
                                 ("fit_accurate", "accurate mesh"))]
    out += ["**Roughness of the data** along each path (largest residual of a degree-6 "
            "polynomial in t, over the range of the response): the FE forces are not smooth "
            "(contact events), which bounds what any smooth fit can reproduce.", ""]
    out += table(["data", "B_r", "B_z", "f_r", "f_z"], rough)
    return out


def gamma_section(r: Results) -> list[str]:
    out = ["## Γ against the data", "",
           "The models' Γ against Γ from finite differences of the DOE data alone "
           "(docs/method.md §6), at t ≥ 0.2 and where Γ exceeds 5 % of its maximum:", ""]
    rows = []
    for stem, label in (("fit", "bundled (default mesh)"), ("fit_accurate", "accurate mesh")):
        for name in ("gamma_r", "gamma_z"):
            g = r[stem]["gamma_vs_data_fd"][name]
            rows.append([label, name.replace("gamma_", "Γ_"), f"{g['n_points_above_floor']}",
                         pct(g["within_5_percent_above_floor"]), pct(g["median_above_floor"], 2),
                         pct(g["p95_above_floor"], 1), pct(g["max_above_floor"], 0),
                         pct(g["max_abs_over_max"], 1)])
    out += table(["data", "Γ", "points", "within 5 %", "median difference", "95th percentile",
                  "largest", "largest / max Γ"], rows)
    b = r["fit"]["gamma_vs_data_fd"]["gamma_r"]["within_5_percent_above_floor"]
    a = r["fit_accurate"]["gamma_vs_data_fd"]["gamma_r"]["within_5_percent_above_floor"]
    out += [f"Γ_r agrees within 5 % at {pct(b)} of the points on the bundled data and at "
            f"{pct(a)} on the data of the `accurate` mesh, whose f_r is smoother (table above): "
            "Γ_r depends on small differences of F_r, where the roughness of the structural "
            "data matters.", ""]
    return out


def mesh_effect_section(r: Results) -> list[str]:
    m = r["mesh_effect"]
    c = m["change_default_vs_finer"]
    d, f, ch = (m["chosen_design"]["default"], m["chosen_design"]["finer"],
                m["chosen_design_change"])
    out = ["## What the mesh error does to the answer", "",
           f"Source: {r.source('mesh_effect')} (`bench/bench_mesh_effect.py`): the whole DOE on "
           f"the `{m['mesh']['finer']}` mesh against the bundled DOE on the "
           f"`{m['mesh']['default']}` mesh, each fitted and optimised with the default settings.",
           "",
           f"The default mesh's F_z(t = 1) is {pct(c['F_z_t1_range'][0])} to "
           f"{pct(c['F_z_t1_range'][1])} higher on every path; its min F_r differs by "
           f"{spct(c['F_r_min_theta_gt_0_range'][0])} to {spct(c['F_r_min_theta_gt_0_range'][1])}"
           " in magnitude (θ > 0). The chosen design:", ""]
    rows = [["H [mm]", f"{d['H_mm']:.3f}", f"{f['H_mm']:.3f}", spct(ch["H_mm"])],
            ["G [kPa]", f"{d['G_kPa']:.2f}", f"{f['G_kPa']:.2f}", spct(ch["G_kPa"])],
            ["Γ_r,max [N/T]", f"{d['Gamma_r_max_N_per_T']:.2f}",
             f"{f['Gamma_r_max_N_per_T']:.2f}", spct(ch["Gamma_r_max_N_per_T"])],
            ["Γ_z,max [N/T]", f"{d['Gamma_z_max_N_per_T']:.2f}",
             f"{f['Gamma_z_max_N_per_T']:.2f}", spct(ch["Gamma_z_max_N_per_T"])],
            ["F_z,max [N]", f"{d['F_z_max_N']:.3f}", f"{f['F_z_max_N']:.3f}",
             spct(ch["F_z_max_N"])]]
    out += table(["", m["mesh"]["default"], m["mesh"]["finer"], "change"], rows)
    return out


LABEL = {"F_z_t1_N": "F_z(t = 1)", "F_r_min_N": "min F_r"}


def _load(p: dict) -> str:
    load = p.get("load_1min")
    return "—" if load is None else f"{load:.1f}"


def frontier_section(r: Results) -> list[str]:
    if "frontier" not in r.files:
        return []
    f = r["frontier"]
    tgt = f["target"]
    out = ["## Error–cost frontier of the structural forces", "",
           f"Source: {r.source('frontier')} (`bench/bench_frontier.py`), figure "
           "`bench/results/frontier.png`. θ = θ_max; each row is one mesh of one route: its "
           "wall time per path on one core and the change of its forces against the next finer "
           "mesh of the same route (refinement per direction in the last column). Target: "
           f"{pct(tgt['change_F_z_t1'], 0)} in F_z(t = 1), {pct(tgt['change_F_r_min'], 0)} in "
           f"min F_r, at most {tgt['seconds_per_path']:.0f} s per path (25 paths on 2 workers "
           f"in {tgt['doe_minutes_2_workers']} min).", ""]
    out += ["Wall times were measured on the shared 2-core machine; the column *load* gives the "
            "1-minute load average when the path started (— where the benchmark did not record "
            "it). Above a load of 2 the paths share the cores with other work, so the times "
            "are upper bounds of the cost on one idle core; the paths run by this benchmark "
            "since it sets one BLAS thread (`blas_threads` in the records) ran at loads of 1 "
            "to 3.", ""]
    rows = []
    for p in f["points"]:
        H = f"{p['H_mm']:g}" if isinstance(p["H_mm"], float) else p["H_mm"]
        rows.append([p["route"], p["mesh"], H, f"{p['wall_time_s']:.0f}", _load(p),
                     pct(p["change_F_z_t1"], 2), pct(p["change_F_r_min"], 2),
                     f"{p['next']} ({p['refinement']:g})" if "refinement" in p else p["next"]])
    out += table(["route", "mesh", "H [mm]", "s per path", "load", "ΔF_z(t=1)", "Δ min F_r",
                  "against"], rows)
    for o in f["orders"]:
        if "order_F_z_t1" in o:
            oz, orr = o["order_F_z_t1"], o["order_F_r_min"]
            out.append(f"Observed order, {o['route']}, H = {o['H_mm']:g} mm "
                       f"({' → '.join(o['meshes'])}): F_z(t = 1) "
                       f"{'none' if oz is None else f'{oz:.2f}'}, min F_r "
                       f"{'none' if orr is None else f'{orr:.2f}'}.")
            out.append("")
    limits = [o for o in f["orders"] if "vs_limit" in o]
    if limits:
        out += ["Against the converged value: the hex8 forces extrapolated with order 1 from the "
                "`default` and `fine` meshes, F = 2 F_fine − F_default (the `default` and "
                "`default_x1.5` pair gives the same limit within "
                + ", ".join(pct(abs(o["limit_from_default_x1.5"]["F_z_t1_N"]
                                    / o["limit_from_default_fine"]["F_z_t1_N"] - 1), 2)
                            + f" at H = {o['H_mm']:g} mm" for o in limits)
                + " in F_z(t = 1)):", ""]
        def own(p, k, digits):
            v = p.get(f"change_{k}_vs_observed_order")
            return "—" if v is None else pct(v, digits)

        rows = [[p["route"], p["mesh"], f"{o['H_mm']:g}", f"{p['wall_time_s']:.0f}", _load(p),
                 pct(p["change_F_z_t1"], 3), pct(p["change_F_r_min"], 2),
                 own(p, "F_z_t1", 3), own(p, "F_r_min", 2)]
                for o in limits for p in sorted(o["vs_limit"], key=lambda p: p["wall_time_s"])]
        out += ["The last two columns compare with the hex8 limit extrapolated with the hex8 "
                "route's own observed order (table above) from the `default` and `fine` meshes, "
                "F = F_fine + (F_fine − F_default) / (2^p − 1), where that order is clean "
                "(0.5 ≤ p ≤ 4; — where it is not): "
                + "; ".join(f"H = {o['H_mm']:g} mm: "
                            + (", ".join(f"{LABEL[k]} = {v:.4f} N"
                                         for k, v in o["limit_observed_order"].items())
                               or "none")
                            for o in limits) + ".", ""]
        out += table(["route", "mesh", "H [mm]", "s per path", "load", "ΔF_z(t=1)",
                      "Δ min F_r", "ΔF_z(t=1), order p", "Δ min F_r, order p"], rows)
    for H, best in f.get("cheapest_within_target", {}).items():
        h = H.removeprefix("H_").removesuffix("_mm")
        words = [f"{label}: " + (f"{b['route']} `{b['mesh']}`, {b['wall_time_s']:.0f} s per path"
                                 if b else "no measured route")
                 for label, b in (("F_z(t = 1) alone", best["F_z_t1"]),
                                  ("with min F_r too", best["F_z_t1_and_F_r_min"]),
                                  ("with min F_r too, against the observed-order limits where "
                                   "clean", best.get("F_z_t1_and_F_r_min_observed_order")))]
        out += [f"Cheapest within the target of the converged value at H = {h} mm: "
                + "; ".join(words) + ".", ""]
    if limits:  # a DOE needs one discretisation for every H
        def within(p):
            return all(p.get(f"change_{k}_vs_observed_order", p[f"change_{k}"])
                       <= tgt[f"change_{k}"] for k in ("F_z_t1", "F_r_min"))

        ok = [{(p["route"], p["mesh"]) for p in o["vs_limit"] if within(p)} for o in limits]
        both = sorted(set.intersection(*ok)) if ok else []
        out += ["Within the target at every height measured (the same route and mesh; against "
                "the observed-order limits where clean): "
                + (", ".join(f"{r} `{m}`" for r, m in both) if both else "none") + ".", ""]
        out += _other_height(limits, f["failed_runs"], within)
    if limits:  # the same element and mesh with contact over the faces and node by node
        pairs = [(o["H_mm"], p, q) for o in limits for p in o["vs_limit"]
                 for q in o["vs_limit"] if p["route"].endswith("-faces")
                 and q["route"] == p["route"].removesuffix("-faces") and q["mesh"] == p["mesh"]]
        if pairs:
            out += ["Contact over the faces against contact node by node (the same element and "
                    "mesh; differences from the hex8 limit of the table above, where clean):", ""]
            out += table(["element", "mesh", "H [mm]", "ΔF_z(t=1), nodes", "ΔF_z(t=1), faces",
                          "Δ min F_r, nodes", "Δ min F_r, faces"],
                         [[q["route"], q["mesh"], f"{H:g}", own(q, "F_z_t1", 2),
                           own(p, "F_z_t1", 2), own(q, "F_r_min", 2), own(p, "F_r_min", 2)]
                          for H, p, q in pairs])
    for run in f["failed_runs"]:
        variant = f" ({run['variant']})" if run.get("variant") else ""
        out += [f"Not completed: {run['route']}{variant} on `{run['mesh']}` at "
                f"H = {run['H_mm']:g} mm ({run['error']}).", ""]
    return out + quadratic_section(r)


def _other_height(limits: list[dict], failed: list[dict], within) -> list[str]:
    """The cost of the target at both heights: each route and mesh within it at the lowest
    height, cheapest first, with what the same route and mesh gave at the others."""
    by_h = {o["H_mm"]: {(p["route"], p["mesh"]): p for p in o["vs_limit"]} for o in limits}
    stalls = {(r["route"] + (f" ({r['variant']})" if r.get("variant") else ""), r["mesh"],
               r["H_mm"]): r["error"] for r in failed}
    low, *others = sorted(by_h)
    rows = []
    for key, p in sorted(by_h[low].items(), key=lambda kv: kv[1]["wall_time_s"]):
        if not within(p):
            continue
        row = [key[0], key[1], f"{p['wall_time_s']:.0f}"]
        for H in others:
            q = by_h[H].get(key)
            if q is not None:
                changes = ", ".join(
                    pct(q.get(f"change_{k}_vs_observed_order", q[f"change_{k}"]), 2)
                    for k in ("F_z_t1", "F_r_min"))
                row.append(f"{q['wall_time_s']:.0f} s, " + ("within" if within(q) else "outside")
                           + f" ({changes})")
            elif (err := stalls.get((*key, H))) is not None:
                t = float(err.split("failed at t = ")[1].split(" ")[0])
                row.append(f"stalls at t = {t:.3f}")
            else:
                row.append("not run")
        rows.append(row)
    if not rows:
        return []
    return ([f"The target at both heights: each route and mesh within it at H = {low:g} mm "
             "(cheapest first) and what the same route and mesh gave at the other height "
             "(ΔF_z(t = 1), Δ min F_r as in the table above):", ""]
            + table(["route", "mesh", f"s per path, H = {low:g} mm"]
                    + [f"H = {H:g} mm" for H in others], rows))


def quadratic_section(r: Results) -> list[str]:
    if "quadratic" not in r.files:
        return []
    q = r["quadratic"]
    out = ["### The quadratic routes: where their time goes, why their Newton iterations "
           "stalled", "",
           f"Source: {r.source('quadratic')} (`bench/bench_quadratic.py`), docs/method.md §3.",
           ""]
    if "tangent" in q:
        t = q["tangent"]
        out += ["**Tangent integration and factorisation** (H = 3 mm, minimum of repeated "
                f"calls; load average {t['load_average_at_start'][0]:.1f} at the start, BLAS "
                f"threads: {t.get('blas_threads', 'library default')}): FElupe's einsum of the "
                "solid's tangent against batched matrix products per cell (the same numbers), "
                "the whole tangent assembly with each, and one PARDISO factorisation of the "
                "free-free block. On the idle machine the two integrations take the same "
                "time; under load (3 to 11) FElupe's einsum, with its BLAS threads, took up to "
                "23 times as long, so the frontier's paths now run with one BLAS thread (those "
                "before did not).",
                ""]
        rows = [[c["element"], c["mesh"], f"{c['n_dofs']:,}", f"{c['nnz']:,}",
                 f"{c['felupe_einsum_s']:.3f}", f"{c['batched_s']:.3f}",
                 *(f"{c[k]:.3f}" if k in c else "—"
                   for k in ("tangent_assembly_stock_s", "tangent_assembly_batched_s")),
                 f"{c['max_relative_difference']:.0e}", f"{c['factorisation_s']:.2f}"]
                for c in t["cases"]]
        out += table(["element", "mesh", "DOFs", "non-zeros", "einsum [s]", "batched [s]",
                      "tangent, einsum [s]", "tangent, batched [s]", "max rel. diff.",
                      "factorisation [s]"], rows)
    if "penalty_scale" in q:
        out += ["**Contact penalty against the surface's stiffness** (upper plate, H = 3 mm, "
                "reference configuration): the normal multiplier λ_n = penalty × the mean "
                "diagonal stiffness of the contact nodes, which the volumetric term dominates, "
                "against the same mean of a shear-only solid:", ""]
        rows = [[c["element"], c["mesh"], f"{c['penalty']:g}",
                 f"{c['mean_diagonal_over_G_m'] / c['mean_shear_diagonal_over_G_m']:.0f}",
                 f"{c['lambda_n_over_mean_shear_diagonal']:.0f}"]
                for c in q["penalty_scale"]["cases"]]
        out += table(["element", "mesh", "penalty", "diagonal / shear diagonal",
                      "λ_n / shear diagonal"], rows)
    if "uniaxial_hex20" in q:
        out += ["**20-node cells against the uniaxial closed form** F = G A₀ (λ⁻² − λ) (a plain "
                "cylinder, R = h = 6 mm, between frictionless plates): a serendipity face's "
                "consistent nodal forces under a uniform pressure are negative at its corners, "
                "so with contact node by node its corners lift off the plate; contact "
                "integrated over the faces gives them (gaps of the top face's nodes at the end; "
                "negative: off the plate).", ""]
        rows = [[c.get("contact", "nodes"), f"`{c['density']}`", f"{c['lambda']:g}",
                 f"{c['n_dofs']:,}",
                 spct(c["relative_error"], 2) if c["completed"]
                 else f"failed at t = {c['failed_at_t']:.3f}",
                 "{min:.1f} to {max:.1f}".format(**c["top_corner_gap_um"]),
                 "{min:.3f} to {max:.3f}".format(**c["top_mid_edge_gap_um"]),
                 f"{c['wall_time_s']:.0f}"]
                for c in q["uniaxial_hex20"]["cases"]]
        out += table(["contact", "mesh", "λ", "DOFs", "F vs closed form", "corner gaps [µm]",
                      "mid-edge gaps [µm]", "s"], rows)
    runs = {k: v for k, v in q.items()
            if k.startswith("newton_") or k.startswith("hex20_newton_")}
    if runs:
        out += ["**Newton iterations logged along one path** (θ_max, the study's 21 "
                "load levels):", ""]
        rows = []
        for v in runs.values():
            tail = next((s for s in reversed(v["steps"]) if not s["converged"]), None)
            rows.append([v.get("element", "hex27"), f"`{v['mesh']}`", f"{v['H_mm']:g}",
                         f"{v['tol_cycling']:g}",
                         f"{v['contact_penalty']:g}",
                         "completed" if v["status"] == "completed" else "failed: " + v["status"],
                         f"{v['F_z_t1_N']:.4f}" if "F_z_t1_N" in v else "—",
                         str(v["newton_iterations"]), f"{v['wall_time_s']:.0f}",
                         f"{v['load_average_at_start'][0]:.1f}",
                         "—" if tail is None else
                         f"{len([s for s in v['steps'] if not s['converged']])}"])
        out += table(["element", "mesh", "H [mm]", "tol_cycling", "penalty", "status",
                      "F_z(t=1) [N]",
                      "iterations", "s", "load", "failed steps"], rows)
        for v in runs.values():
            if v["status"] == "completed":
                continue
            last = v["steps"][-1]
            res = ", ".join(f"{i['residual']:.1e}" for i in last["iterations"])
            moved = [i for i in last["iterations"] if "lower_changed" in i]
            gaps = sorted({g for i in moved for g in i.get("lower_changed_gaps_um", [])})
            worst = last["iterations"][0]["largest_residual_nodes"][0]
            kinds = {tuple(sorted((k, n) for k, n in i["lower_changed"].items() if n))
                     for i in moved}
            which = (f"always one {worst['class']} node (node {worst['node']}, the largest "
                     "residual when in contact)"
                     if kinds == {((worst["class"], 1),)} else f"nodes changed: {sorted(kinds)}")
            largest = [i["largest_residual_nodes"][0]["class"] for i in last["iterations"]]
            head = (f"Last step tried with {v.get('element', 'hex27')} on `{v['mesh']}` at "
                    f"H = {v['H_mm']:g} mm (t = {last['t'][0]:.5f} → {last['t'][1]:.5f}): "
                    f"residuals {res}.")
            if moved:
                body = (f" The lower plate's contact set changes in {len(moved)} of "
                        f"{len(last['iterations'])} iterations, {which}, at gaps of "
                        f"{', '.join(f'{g:g}' for g in gaps)} µm;")
            else:
                body = " The contact sets do not change;"
                for plate in ("lower", "upper"):
                    key = f"{plate}_slip_changed_nodes"
                    slips = [i for i in last["iterations"] if key in i]
                    if slips:
                        nodes = sorted({n for i in slips for n in i[key]})
                        body += (f" on the {plate} plate {'node' if len(nodes) == 1 else 'nodes'}"
                                 f" {', '.join(str(n) for n in nodes)} switch"
                                 f"{'es' if len(nodes) == 1 else ''} between sticking and "
                                 f"sliding in {len(slips)} of {len(last['iterations'])} "
                                 "iterations;")
            out += [head + body + " the largest residual sits at a node of class "
                    f"{', '.join(largest)} in successive iterations.", ""]
    return out


def optimise_section(r: Results) -> list[str]:
    o = r["optimise"]
    d, ref = o["default_constraints"], o["reference_constraints"]
    bf = o["brute_force"]
    out = ["## Optimisation", "",
           f"Source: {r.source('optimise')} (`bench/bench_optimise.py`), with the shipped "
           "metamodels; docs/method.md §7.", "",
           f"**Default constraints** (F_r,c = {d['constraints']['F_r_c_N']:g} N, "
           f"F_z,c = {d['constraints']['F_z_c_N']:g} N): chosen H = {d['H_mm']:.3f} mm, "
           f"G = {d['G_kPa']:.2f} kPa, Γ_r,max = {d['Gamma_r_max_N_per_T']:.2f} N/T, "
           f"Γ_z,max = {d['Gamma_z_max_N_per_T']:.2f} N/T, active: "
           f"{', '.join(d['active_constraints']) or 'none'}. The exact reduction chooses "
           f"G = {d['exact_reduction_choice']['G_kPa']:.2f} kPa; NSGA-II's set lies within "
           f"{d['gap_to_exact_front']:.1e} (relative) of the exact front.", "",
           f"**Constraints of the original design** (H = {ref['reference_design']['H_mm']:g} mm,"
           f" G = {ref['reference_design']['G_kPa']:g} kPa): chosen H = {ref['H_mm']:.3f} mm, "
           f"G = {ref['G_kPa']:.2f} kPa, gap to the exact front "
           f"{ref['gap_to_exact_front']:.1e}.", "",
           f"**Against brute force** on a {bf['grid'][0]} × {bf['grid'][1]} grid of (t, θ) at "
           f"{len(bf['heights'])} heights: largest relative difference of the per-design "
           f"extrema {bf['max_rel_diff']:.1e}; the optimiser is never worse than the grid: "
           f"{'yes' if bf['optimiser_never_worse'] else 'no'}.", ""]
    return out


def _design_row(label: str, d: dict) -> list[str]:
    return [label, f"{d['H_mm']:.3f}", f"{d['G_kPa']:.2f}", f"{d['R_m_mm']:.3f}",
            f"{d['Gamma_r_max_N_per_T']:.2f}", f"{d['Gamma_z_max_N_per_T']:.2f}",
            f"{d['F_r_min_N']:.3f}", f"{d['F_z_max_N']:.2f}"]


def geometry_section(r: Results) -> list[str]:
    if "optimise" not in r.files.get("geometry", {}):
        return []
    g = r["geometry"]
    d, o = g["doe"], g["optimise"]
    out = ["## The magnet radius as a design variable", "",
           f"Source: {r.source('geometry')} (`bench/bench_geometry.py`, study "
           f"`{g['study']}`); docs/method.md §7.2. The DOE: {d['paths_total']} structural paths "
           f"and {d['fields_computed']} field solves on the `{d['mesh']}` mesh with "
           f"{d['workers']} workers in {d['wall_time_s'] / 60:.0f} min (data set "
           f"`{d['dataset']}`); the force fit {o['fit_wall_time_s']:.0f} s, the optimisation "
           f"{o['optimise_wall_time_s']:.0f} s. NSGA-II's {o['nsga2_evaluations']} evaluations "
           f"end within {pct(o['gap_to_exact_front'], 2)} of the refined exact front.", ""]
    out += table(["design", "H [mm]", "G [kPa]", "R_m [mm]", "Γ_r,max [N/T]", "Γ_z,max [N/T]",
                  "F_r,min [N]", "F_z,max [N]"],
                 [_design_row("chosen (H, G, R_m)", o["chosen"]),
                  _design_row("exact reduction (H, G, R_m)", o["chosen_by_exact_reduction"]),
                  _design_row("(H, G) at R_m = 2.5 mm, same models",
                              o["HG_optimum_same_models_R_m_2p5"]),
                  _design_row("(H, G), shipped models", o["HG_optimum_shipped_models"])])
    return out


def broad_section(r: Results) -> list[str]:
    if "broad" not in r.files:
        return []
    b = r["broad"]
    out = ["## The broad design space", "",
           f"Source: {r.source('broad')} (`bench/bench_broad.py`). The space, "
           f"`{b['studies']['full']}`: the MagOne body with H over 2–10 mm (4 levels), the "
           "magnet's diameter 3 and 6 mm and its height 1 and 3 mm (the corners of the "
           "catalogue's sizes), 3 θ levels: 48 structural paths and 4 field solves, default "
           "mesh, G by its exact scaling. magtact ships it as one data set and one fit per "
           "magnet size.", ""]
    d = b.get("doe_full")
    if d:
        c = d["cache"]
        failed = d.get("partial_paths", [])
        out += [f"**Its DOE** (`{d['magtact_command']}`): {d['paths_total']} paths, "
                f"{c['paths_cached']} finished in the job cache "
                f"({c['path_job_wall_time_s_sum'] / 60:.0f} min of solver time, "
                f"{c['path_job_wall_time_s_min']:.0f}–{c['path_job_wall_time_s_max']:.0f} s per "
                "path, computed over two sessions with one and two workers beside other work: "
                "a 1-minute load average of 2 to 9), and "
                f"{len(failed)} that stall before t = 1 (no progress of the Newton iterations, "
                "as in §3 of the method): each keeps the load levels it reached, NaN beyond, and "
                "the fit leaves the missing levels out:", ""]
        stalled_s = d["path_job_wall_time_s_sum"] - c["path_job_wall_time_s_sum"]
        out += [f"Those {len(failed)} paths took {stalled_s / 60:.0f} min more, and the whole "
                f"run {d['wall_time_s'] / 60:.0f} min with {d['workers']} workers (every "
                "finished path from the cache).", ""]
        out += table(["magnet [mm]", "θ [rad]", "H [mm]", "last level kept"],
                     [[f"{f['D_mm']:.3g} × {f['H_m_mm']:.3g}", f"{f['theta_rad']:.3g}",
                       f"{f['H_mm']:.3g}", f"t = {f['t_reached']:.3g}"] for f in failed])
    sz = b.get("sizes")
    if sz:
        st = sz["settings"]
        rows = []
        for name, v in sz["sizes"].items():
            for k in ("f_r", "f_z"):
                x = v["accuracy"][k]["test"]
                rows.append([name.replace("x", " × "), k, f"{x['r2']:.4f}",
                             pct(x["max_abs_err_over_range"], 2), str(x["n_points"]),
                             str(v["points_missing"]), f"{v['wall_time_s']:.0f}"])
        out += ["**Metamodels, one per magnet size** (`python bench/bench_broad.py split`: "
                f"`magtact fit` of each size's data set, {st['generations']} GP generations × "
                f"{st['population']}, up to {st['retries'] + 1} seeds; the field is the exact "
                "one; held out: whole (θ, H) paths, the same two for every size):", ""]
        out += table(["magnet [mm]", "model", "held-out R²", "held-out error / range",
                      "held-out points", "points missing", "fit [s]"], rows)
        from magtact.metamodel import POOR_OVER_RANGE, POOR_R2

        poor = [f"{name.replace('x', ' × ')} mm {k} (R² {x['r2']:.4f})"
                for name, v in sz["sizes"].items() for k in ("f_r", "f_z")
                if (x := v["accuracy"][k]["test"])["r2"] < POOR_R2
                or x["max_abs_err_over_range"] > POOR_OVER_RANGE]
        if poor:
            out += [f"Below the poor-fit thresholds (held-out R² ≥ {POOR_R2}, error ≤ "
                    f"{pct(POOR_OVER_RANGE)} of the range): {', '.join(poor)}; every answer "
                    "from that fit says it rests on a poor fit (card, stage, `magtact fit`).",
                    ""]
    sh = b.get("ship")
    if sh and "sizes" in sh:
        total = sum(v["data_bytes"] + v["fit_bytes"] for v in sh["sizes"].values())
        out += ["Shipped (`python bench/bench_broad.py ship_sizes`): "
                + ", ".join(f"`{v['data']}` ({v['data_bytes'] / 1e3:.0f} kB) and `{v['fit']}` "
                            f"({v['fit_bytes'] / 1e3:.0f} kB)" for v in sh["sizes"].values())
                + f"; {total / 1e6:.1f} MB in all.", "",
                "![parity of the 3 × 1 mm fit]"
                "(../src/magtact/metamodel/data/broad_3x1/parity.png)", ""]
    ff, mg = b.get("fit_full"), b.get("magone")
    if ff and mg:
        dd = mg["data"]
        acc = ff["accuracy"]
        out += ["**Why the sizes are not interpolated.** One fit over the four sizes "
                f"(`{ff['magtact_command']}`, {ff['settings']['generations']} GP generations × "
                f"{ff['settings']['population']}, {ff['wall_time_s'] / 60:.0f} min) reaches "
                f"held-out f_z within {pct(acc['f_z']['test']['max_abs_err_over_range'], 2)} of "
                f"the range and f_r within {pct(acc['f_r']['test']['max_abs_err_over_range'], 2)}"
                f" (R² {acc['f_r']['test']['r2']:.3f}) on the four sizes; against the MagOne "
                "data set, which it never saw (a 5 × 2 mm magnet, between those sizes, at "
                "H 3–7 mm; the same body, loading and mesh: `python bench/bench_broad.py "
                "magone`):", ""]
        out += table(["force per unit G", "R²", "largest error / range", "points"],
                     [[k, f"{v['r2']:.3f}", pct(v["max_abs_err_over_range"], 1),
                       str(v["n_points"])] for k, v in dd.items() if isinstance(v, dict)])
        out += [f"F_z(t = 1) of the MagOne paths is off by up to "
                f"{pct(dd['F_z_t1_max_rel_err'], 0)} and min F_r by up to "
                f"{pct(dd['F_r_min_max_rel_err'], 0)}: two levels per magnet dimension do not "
                "resolve the forces between them, so magtact answers the four sizes of the "
                "data only, each from its own fit, and refuses a size between them.", "",
                "![MagOne data against the fit over the sizes]"
                "(../bench/results/broad_magone.png)", ""]
    w = b.get("whatif")
    if w:
        out += ["**What-ifs answered from it** (`magtact.design`, no DOE; 1-minute load "
                f"average {w['load_average'][0]:.1f}; the chosen sensor of each):", ""]

        def sensor_row(v):
            d = (v.get("sensor") or {}).get("chosen")
            if not d:
                return ["—"] * 5
            met = {True: "met", False: "not met", None: "—"}[v.get("verdict_met")]
            return [d["magnet_grade"], f"{d['standoff_mm']:.2g}", f"{d['sigma_Fr_mN']:.3g}",
                    f"{d['sigma_Fz_mN']:.3g}", met]

        out += table(["study edit", "s", "H [mm]", "G [kPa]", "grade", "standoff [mm]",
                      "σ_F,r [mN]", "σ_F,z [mN]", "requirements"],
                     [[k, f"{v['wall_time_s']:.1f}", f"{v['chosen']['H_mm']:.3g}",
                       f"{v['chosen']['G_kPa']:.3g}", *sensor_row(v)]
                      for k, v in w["cases"].items()])
    q = b.get("quick")
    if q:
        out += [f"**One design's what-if** (`python bench/bench_broad.py quick`: a 3 × 1 mm N52 "
                f"magnet at H = 9 mm, G = 30 kPa, in a fresh process): {q['wall_time_s']:.1f} s "
                f"in all at a 1-minute load average of {q['load_average_at_start'][0]:.1f} "
                f"(imports {q['import_s']:.1f} s, the models from `{q['data']}` "
                f"{q['models_s']:.2f} s, the designer's answer {q['answer_s']:.1f} s).", ""]
    runs = b.get("runs")
    if runs:
        rows = []
        for k, v in runs["cases"].items():
            st = v["stages"]
            rows.append([k, f"{v['wall_time_s']:.0f}", str(v["exit_status"]),
                         f"{v['load_average_at_start'][0]:.1f}",
                         *(f"{st[s]['wall_time_s']:.1f}" if s in st else "—"
                           for s in ("doe", "metamodel", "optimise")),
                         ", ".join(f"{s}: {x['status']}" for s, x in st.items()
                                   if x["status"] != "ok") or "all ok",
                         *((f"{c['H_mm']:.3g}", f"{c['G_kPa']:.3g}")
                           if (c := v.get("chosen")) else ("—", "—"))])
        out += ["**`magtact run` of the first what-ifs** (`python bench/bench_broad.py runs`; "
                "no DOE computed in any of them):", ""]
        out += table(["study edit", "total [s]", "exit", "load", "DOE [s]", "metamodels [s]",
                      "optimisation [s]", "stages not ok", "H [mm]", "G [kPa]"], rows)
    m = b.get("mesh_correction")
    if m:
        rows = []
        for h in ("H_3_mm", "H_7_mm"):
            for key, label in (("F_z_t1_N", "F_z(t = 1)"), ("F_r_min_N", "min F_r")):
                x = m[h][key]
                rows.append([h[2:-3], label, f"{x['limit']:.4g}", spct(x["default_vs_limit"], 2),
                             spct(x["corrected_vs_limit"], 2),
                             spct(x["richardson_of_the_path_vs_limit"], 2)])
        out += ["**A mesh correction of the bundled forces** (`python bench/bench_broad.py "
                "mesh`): a multiplicative bridge c(θ, H), linear, fitted to the order-1 "
                "Richardson values 2 F_accurate − F_default of 5 DOE paths (θ > 0, not the two "
                "below), applied to the default mesh's forces of the held-out paths θ_max at "
                "H = 3 and 7 mm and compared with the frontier's limits there (extrapolated from "
                "`default` and `fine`, θ_max, G = 29.4 kPa):", ""]
        out += table(["H [mm]", "force", "limit [N]", "default", "corrected",
                      "Richardson of the path itself"], rows)
        verdict = "adopted" if m["adopted"] else "not adopted: the bundled data stay uncorrected"
        out += [f"Threshold for adopting it: F_z(t = 1) within {pct(m['adopt_if_F_z_t1_within'])}"
                f" at both heights; worst {pct(m['worst_corrected_F_z_t1'], 2)}, so {verdict}. "
                "Even each held-out path's own Richardson value from `default` and "
                "`accurate` lies outside 1.5 % at 7 mm (last column), so no bridge fitted to "
                "such values can reach it there.", ""]
    return out


def _spread_rows(p: dict) -> list[list[str]]:
    rows = []
    for d, figs in p["spread"].items():
        for f in figs.values():
            if "min" in f and f.get("min") is not None and f.get("n", 1) > 0:  # measured
                mm = f.get("max_over_min")
                rows.append([d, f["label"], f["unit"], f"{f['min']:.4g}", f"{f['max']:.4g}",
                             "∞" if mm is None or mm == float("inf") else f"{mm:.3g}"])
    return rows


def publication_section(r: Results) -> list[str]:
    if "reproduce" not in r.files:
        return []
    p = r["reproduce"]
    out = ["## The seed study against the publication", "",
           f"Source: {r.source('reproduce')} (`bench/bench_reproduce.py`, "
           "`magtact reproduce`); docs/method.md §6. The force models refitted with "
           f"{len(p['seeds'])} GP seeds under each definition of Γ on the bundled DOE, "
           f"{p.get('gp', {}).get('generations', '?')} GP generations per fit (the seed "
           f"study's default), {p['workers']} workers, {p['wall_time_s']:.0f} s.", "",
           "Spread across seeds (max / min):", ""]
    out += table(["definition", "figure", "unit", "min", "max", "max / min"], _spread_rows(p))
    out += ["Beside the publication (median [min, max] over seeds; G as magone reads it):", ""]
    cols = [k for k in p["comparison"][0] if k.endswith("/study")]
    out += table(["quantity", "unit", "scale-free", "publication", *cols],
                 [[c["quantity"], c["unit"], "yes" if c["scale_free"] else "no",
                   c["publication"], *(c[k] for k in cols)] for c in p["comparison"]])
    for stem in sorted(k for k in r.files if k.startswith("reproduce_g")):
        q = r[stem]
        g, g0 = q["gp"]["generations"], p.get("gp", {}).get("generations", 0)
        out += [f"**A {'larger' if g > g0 else 'smaller'} GP budget** ({r.source(stem)}: "
                f"{g} generations per fit instead of {g0}, {q['wall_time_s']:.0f} s):", ""]
        out += table(["definition", "figure", "unit", "min", "max", "max / min"],
                     _spread_rows(q))
    return out


def timing_section(r: Results) -> list[str]:
    d, run = r["doe"], r["run"]
    p = d["path_job_wall_time_s"]
    out = ["## Timings", "",
           f"On the {d['machine']['cpus']}-core development machine "
           "(other work on the machine shows in the load averages the files record).", "",
           f"**Full DOE from an empty cache** ({r.source('doe')}): {d['n_paths']} structural "
           f"paths with {d['workers']} workers in {d['wall_time_s']:.0f} s (parallel efficiency "
           f"{pct(d['parallel_efficiency'], 0)}); per path {p['min']:.0f}–{p['max']:.0f} s, "
           f"{p['mean']:.0f} s on average; field job {d['field_job_wall_time_s']:.1f} s.", "",
           f"**`magtact run`** ({r.source('run')}):", ""]
    rows = []
    for key, label in (("bundled", "bundled data"), ("recompute", "--recompute --refit")):
        s = run[key]
        rows.append([label, f"{s['wall_time_s']:.0f}",
                     *(f"{s['stages'][k]['wall_time_s']:.1f}"
                       for k in ("field", "doe", "metamodel", "optimise", "validation"))])
    out += table(["run", "total [s]", "field", "DOE", "metamodels", "optimisation",
                  "validation"], rows)
    return out


def speed_section(r: Results) -> list[str]:
    if "speed" not in r.files:
        return []
    sp = r["speed"]
    out = ["## Speed", "",
           f"Source: {r.source('speed')} (`bench/bench_speed.py`). Whole processes of the "
           f"baseline commit {sp['baseline'][:7]} and of {sp['head'][:7]}, timed in turn in one "
           "call on the 2-core development machine, shared with other work: the load averages "
           "below say how much. Wall time counts the waiting for a core; CPU time (user + "
           "system) counts the work, and is the figure to compare across machines. Speed-up: "
           "baseline median / new median.", ""]
    rows = []
    for rec in sp["rows"].values():
        w, c = rec["median_wall_s"], rec["median_cpu_s"]
        load = rec["load_average_start"][0], rec["load_average_end"][0]
        rows.append([rec["what"], f"×{rec['speed_up_cpu']:.2f}", f"{c['baseline']:.1f}",
                     f"{c['head']:.1f}", f"×{rec['speed_up_wall']:.2f}", f"{w['baseline']:.0f}",
                     f"{w['head']:.0f}", str(rec.get("runs_done", rec["repeat"])),
                     f"{load[0]:.1f}–{load[1]:.1f}", "yes" if rec["all_ok"] else "no"])
    out += table(["what", "speed-up (CPU)", "CPU before [s]", "CPU now [s]", "speed-up (wall)",
                  "wall before [s]", "wall now [s]", "runs (median of)", "load (1 min)",
                  "every run exit 0"], rows)
    if "speed_vectorised_only" in r.files:
        v = r["speed_vectorised_only"]
        for rec in v["rows"].values():
            c, w = rec["median_cpu_s"], rec["median_wall_s"]
            out += [f"The new commit also does more than the baseline (the sensor problem "
                    "solved again at the worst corner of the tolerances, the robust verdict). "
                    f"The baseline with the vectorised design problem alone ({v['head'][:7]}, "
                    f"{r.source('speed_vectorised_only')}): {rec['what']} CPU "
                    f"{c['baseline']:.1f} → {c['head']:.1f} s (×{rec['speed_up_cpu']:.2f}), "
                    f"wall {w['baseline']:.0f} → {w['head']:.0f} s (×{rec['speed_up_wall']:.2f}), "
                    f"{rec.get('runs_done', rec['repeat'])} run each, load "
                    f"{rec['load_average_start'][0]:.1f}–{rec['load_average_end'][0]:.1f}."]
        out += [""]
    out += ["A row whose runs did not all exit 0 times a failed run: its ratio is no speed-up "
            "(the runs' `stderr_tail` in the file says why)."]
    return out + [""]


def robust_section(r: Results) -> list[str]:
    if "robust" not in r.files:
        return []
    out = ["## Designing for every unit built", "",
           "Sources: " + ", ".join(r.source(k) for k in ("robust", "robust_light")
                                   if k in r.files)
           + " (`bench/bench_robust.py`), docs/method.md §16: the sensor problem solved at the "
           "nominal parts and at the worst corner of the parts' tolerances, each timed after a "
           "warm-up run.", ""]
    rows = []
    for stem in ("robust", "robust_light"):
        if stem not in r.files:
            continue
        d = r[stem]
        for key in ("nominal", "robust"):
            c = d[key]
            rows.append([stem.replace("robust_light", "light specification")
                         .replace("robust", "built-in study"), key,
                         f"{c['saturation_F_z_N']:.3g}", f"{c['sigma_F_nominal_mN']:.3g}",
                         f"{c['sigma_F_worst_mN']:.3g}", f"{c['wall_time_s']:.0f}"])
        rows[-1][-1] += f" (×{d['robust_over_nominal_time']:.2f})"
    out += table(["study", "design for", "saturates at [N] (nominal unit)",
                  "σ_F,z nominal [mN]", "σ_F,z worst [mN]", "solve [s]"], rows)
    if "calibrate_speed" in r.files:
        c = r["calibrate_speed"]
        m = c["median"]
        out += ["", "**`magtact calibrate` against `magtact run`** "
                f"({r.source('calibrate_speed')}, "
                f"`bench/bench_calibrate_speed.py`, commit {c['commit'][:7]}, whole processes in "
                f"turn, medians): run {m['run']['wall_s']:.0f} s wall / {m['run']['cpu_s']:.0f} s "
                f"CPU, calibrate {m['calibrate']['wall_s']:.0f} s / {m['calibrate']['cpu_s']:.0f} "
                f"s: ratio {c['ratio_of_medians']['wall_s']:.2f} (wall), "
                f"{c['ratio_of_medians']['cpu_s']:.2f} (CPU); both pay the same design solve."]
        a = c.get("calibrate_after_run")
        if a:
            out[-1] += (f" In the designer's order (`magtact run`, then `magtact calibrate` with "
                        f"one answers cache: the run's answer kept) calibrate takes "
                        f"{a['median_wall_s']:.1f} s, ratio {a['ratio_to_run_median_wall']:.2f}.")
    return out + [""]


def sizes_section(r: Results) -> list[str]:
    if "sizes" not in r.files:
        return []
    d = r["sizes"]
    out = ["## The magnet-size design space", "",
           f"Source: {r.source('sizes')} (`bench/bench_sizes.py`, study `{d['study']}`): the "
           "MagOne body over H 2–10 mm (4 levels) with magnets of diameter 3, 4, 5, 6 mm and "
           "height 1, 2, 3 mm, 3 θ levels: 144 structural paths through the job cache it shares "
           "with the broad study (`bench/results/broad_cache`, committed as it grows).", ""]
    st = d.get("status")
    if st:
        out += [f"**Progress.** {st['paths_cached']} of {st['paths_total']} paths cached; their "
                f"solver time {st['path_job_wall_time_s_sum'] / 3600:.1f} h in all, "
                f"{st['path_job_wall_time_s_mean']:.0f} s a path on average (one worker, the "
                "machine shared with other work). Per size (diameter × height): "
                + ", ".join(f"{k} {v}" for k, v in st["per_size"].items()) + ".", ""]
    runs = d.get("doe_runs", [])
    if runs:
        out += ["**Resumption.** The DOE was killed twice while a path was being solved and "
                "started again (to solve the sizes the checks need first); the runs recorded "
                "since, per size, with the paths they found finished in the cache and the paths "
                "they solved:", ""]
        rows = [[run["started"], k, str(v["paths_cached"]), str(v["paths_computed"]),
                 str(v["paths_failed"]), f"{v['wall_time_s']:.0f}"]
                for run in runs for k, v in run["sizes"].items()]
        out += table(["run started", "size", "paths found cached", "paths solved",
                      "paths failed", "wall [s]"], rows)
    ship = d.get("ship", {})
    if ship:
        rows = [[k, f"{pct(v['accuracy']['f_z']['test']['max_abs_err_over_range'], 2)}",
                 f"{pct(v['accuracy']['f_r']['test']['max_abs_err_over_range'], 2)}",
                 "—" if v.get("fit_wall_time_s") is None else f"{v['fit_wall_time_s']:.0f}",
                 f"`{v['data']}`" if v.get("shipped", True) else f"not shipped: {v['why_not']}"]
                for k, v in ship.items()]
        out += ["**Shipped sizes** (`python bench/bench_sizes.py ship SIZE`: the size's data set "
                "from the cache and its own (t, θ, H) fit, held-out paths):", ""]
        out += table(["size [mm]", "f_z held-out max error / range",
                      "f_r held-out max error / range", "fit [s]", "shipped data set"], rows)
    sg = d.get("surrogate")
    if not sg:
        out += ["The surrogate across sizes (`bench_sizes.py surrogate`: kriging, radial basis "
                "and the GP fit over (t, θ, H, R_m, H_m), measured on held-out sizes and on the "
                "bundled MagOne data) waits for the DOE's interior sizes."]
        return out + [""]
    data = sg.get("data", "the DOE's data set")
    out += [f"**Surrogates across sizes** (`{sg['command']}`), fitted on "
            f"{sg['training_points']} points of {len(sg['training_sizes'])} sizes ("
            + ", ".join(sg["training_sizes"]) + f"; data: {data}) and measured on sizes "
            "they never saw: largest |error| over a size's points as a fraction of its force "
            "range (the targets: 2 % for f_z, 5 % for f_r).", ""]
    rows = []

    def cell(entry, name, check):
        e = entry.get(name, {}).get(check)
        return pct(e["max_error_of_range"], 2) if e else "not measured"

    for model, entry in sg["models"].items():
        checks = list(dict.fromkeys(k for name in ("f_z", "f_r") for k, v in
                                    entry.get(name, {}).items() if isinstance(v, dict)))
        fit = " + ".join(f"{entry[n]['fit_s']:.0f}" for n in ("f_z", "f_r") if n in entry)
        for check in checks:
            rows.append([model, check, cell(entry, "f_z", check), cell(entry, "f_r", check),
                         fit])
    out += table(["model", "held-out data", "f_z max error / range", "f_r max error / range",
                  "fit f_z + f_r [s]"], rows)
    return out + [""] + _interpolation_rows(d) + _blend_rows(d) + _robust_size_rows(d)


def _robust_size_rows(d: dict) -> list[str]:
    rb = d.get("robust")
    if not rb:
        return []
    out = [f"**The size chosen on the nominal parts against the units built** "
           f"(`{rb['command']}`): every size that carries the built-in specification solved "
           "whole, its worst corner and robust verdict included. The size chosen on the "
           f"nominal parts is {rb['chosen_size']} mm; the size whose units meet every "
           f"requirement most often is {rb['best_yield_size']} mm.", ""]
    rows = [[name, f"{v['nominal_sigma_mN']:.3g}", f"{v['sigma_Fr_mN']:.3g} / "
             f"{v['sigma_Fz_mN']:.3g}", pct(v["yield"], 1),
             ", ".join(f"{k} {'yes' if q['met_worst_case'] else 'no'} "
                       f"({pct(q['yield'], 1)})" for k, q in v["requirements"].items())]
            for name, v in rb["sizes"].items()]
    out += table(["size [mm]", "nominal σ_F [mN]", "σ_F,r / σ_F,z designed [mN]",
                  "units meeting every requirement", "worst case met (units)"], rows)
    return out + [""]


def _interpolation_rows(d: dict) -> list[str]:
    ip = d.get("interpolation")
    if not ip:
        return []
    out = [f"**The data across sizes, without a model** (`{ip['command']}`): each size of the "
           "DOE predicted from the others at the same (t, θ, H) points, along the radius by the "
           "quadratic through the three other radii at its height, along the height by the "
           "line through the two other heights at its radius (the middle height only); "
           "largest |error| / the size's range.", ""]
    rows = []
    for name, e in ip["sizes"].items():
        def cell(key):
            return pct(e[key]["max_error_of_range"], 2) if key in e else "–"
        rows.append([name, cell("f_z along the radius (quadratic)"),
                     cell("f_r along the radius (quadratic)"),
                     cell("f_z along the height (line)"), cell("f_r along the height (line)")])
    out += table(["size", "f_z, radius", "f_r, radius", "f_z, height", "f_r, height"], rows)
    return out + [""]


def _blend_rows(d: dict) -> list[str]:
    bl = d.get("blend")
    if not bl:
        return []
    out = [f"**The shipped blend across sizes, on sizes it never saw** (`{bl['command']}`): "
           "the shipped per-size fits of the sizes around a magnet blended along its radius "
           "(three sizes of its height), or along its height and radius (the 4 × 1.5 mm "
           "magnet: the quadratic through the heights 1, 2 and 3 mm), what `magtact` answers "
           "for a magnet between the bundled sizes; a held-out size is left out of the sizes it "
           "may blend. Largest |error| / the size's force range, over every point, over the "
           "stable region (each path up to its shear force's extreme: what the sensor problem "
           "reads) and over t ≤ 0.5 (the targets: 2 % for f_z, 5 % for f_r).", ""]
    rows = []
    for label, e in bl["checks"].items():
        parts = ", ".join(f"{n} × {w:.3g}" for n, w in e["blended_from"].items())
        rows.append([label, parts] + [pct(e[k]["max_error_of_range"], 2) if k in e else "–"
                                      for k in ("f_z", "f_r", "f_z, stable", "f_r, stable",
                                                "f_z, t <= 0.5", "f_r, t <= 0.5")])
    out += table(["held-out data", "blend of", "f_z", "f_r", "f_z, stable", "f_r, stable",
                  "f_z, t ≤ 0.5", "f_r, t ≤ 0.5"], rows)
    worst = [f"{label}: t = {w['t']:.3g}, θ = {w['theta_rad']:.3g} rad, H = {w['H_mm']:.3g} mm"
             for label, e in bl["checks"].items()
             if (w := e["f_r"].get("stable_worst_at")) is not None]
    if worst:
        out += ["", "Where the largest f_r error over the stable region lies: " + "; ".join(worst)
                + "."]
    return out + [""]


#: A failed path of ``magtact doe`` as its data set records it (``failed_jobs``).
FAILED_PATH = re.compile(
    r"path θ=(?P<theta>[\d.]+) rad, H=(?P<H>[\d.]+) mm, R_m=(?P<R_m>[\d.]+) mm, "
    r"H_m=(?P<H_m>[\d.]+) mm: (?P<error>\w+): structural path failed at t = (?P<t>[\d.]+)"
    r".*?: (?P<why>[^(]+?) \(residual (?P<residual>[^)]+)\)"
    r"(?: \(its levels up to t = (?P<kept>[\d.]+) kept\))?$")


def _failed_rows(failed: list[str]) -> list[list[str]]:
    """One row per failed path: the magnet, H, θ, where it stopped, why, the levels kept."""
    rows = []
    for text in failed:
        m = FAILED_PATH.match(text)
        if m is None:
            rows.append([text, "", "", "", "", ""])
            continue
        g = m.groupdict()
        rows.append([f"{2 * float(g['R_m']):g} × {float(g['H_m']):g}", f"{float(g['H']):g}",
                     f"{float(g['theta']):.4f}", g["t"],
                     f"{g['error']}: {g['why']} (residual {g['residual']})",
                     g["kept"] or "none"])
    return rows


def _attributes_differing(names: list[str], a: dict, b: dict, same_keys: bool) -> str:
    """The global attributes two runs of one DOE differ in, said in words."""
    if not names:
        return "none differ"
    text = ", ".join(f"`{k}`" for k in names) + (" differs" if len(names) == 1 else " differ")
    if "source_revision" in names and "source_revision" in a:
        text += (f" (the checkout's revision: {a['source_revision']} for the uninterrupted run, "
                 f"{b['source_revision']} for the resumed one, other work being committed "
                 "meanwhile" + ("; the two caches hold the same keys, which include the model "
                                "versions)" if same_keys else ")"))
    return text


def _interruption_cost(overhead: float) -> str:
    """What the interrupted and resumed runs cost beyond the uninterrupted one, in words."""
    lost = ("An interruption loses the work on the paths in flight and costs a second start-up"
            f"; interrupted and resumed together took {pct(abs(overhead))} "
            f"{'less' if overhead < 0 else 'more'} wall time than the uninterrupted run")
    if overhead < 0:
        return (lost + ", because on this machine, shared with other work, the wall time "
                "of a run varies with the other work more than an interruption costs (each "
                "run's load averages are in the file).")
    return lost + " (each run's load averages are in the file)."


def doe_cost_section(r: Results) -> list[str]:
    if "sizes" not in r.files and "doe_resume" not in r.files:
        return []
    out = ["## What a DOE costs, and its resumption", ""]
    d = r.files.get("sizes", {})
    st, final, runs = d.get("status"), d.get("doe"), d.get("doe_runs", [])
    if st and final:
        cpus = d["machine"]["cpus"]
        out += [f"**The magnet-size DOE** ({r.source('sizes')}, `bench/bench_sizes.py`, the "
                f"{cpus}-core development machine shared with other work): "
                f"{st['paths_total']} structural paths on the default mesh; the cache held "
                f"{st['paths_cached']} finished paths (`{st['command']}`), "
                f"{st['path_job_wall_time_s_sum']:,.0f} s of solver time "
                f"({st['path_job_wall_time_s_sum'] / 3600:.1f} h), "
                f"{st['path_job_wall_time_s_mean']:.0f} s a path on average."]
        if runs:
            solved = sum(v["paths_computed"] for run in runs for v in run["sizes"].values())
            failed = sum(v["paths_failed"] for run in runs for v in run["sizes"].values())
            wall = sum(v["wall_time_s"] for run in runs for v in run["sizes"].values())
            workers = sorted({run["workers"] for run in runs})
            out[-1] += (f" The {len(runs)} runs recorded ({' or '.join(map(str, workers))} "
                        f"worker{'s' if workers != [1] else ''}; per size under \"The "
                        f"magnet-size design space\") solved {solved} paths and failed {failed} "
                        f"in {wall:,.0f} s ({wall / 3600:.1f} h) of wall time: "
                        f"{wall / max(solved, 1):.0f} s per solved path, failed attempts "
                        "included.")
        n_failed = len(final["failed_jobs"])
        out[-1] += (f" The last whole `magtact doe` run ({final['workers']} worker"
                    f"{'s' if final['workers'] != 1 else ''}, `{final['command']}`) found "
                    f"{final['paths_cached']} of {final['paths_total']} paths in the cache, "
                    f"solved {final['paths_computed']} and tried the {n_failed} missing ones "
                    f"again in {final['wall_time_s']:,.0f} s (load "
                    f"{final['load_average_at_start'][0]:.1f} at its start, "
                    f"{final['load_average_at_end'][0]:.1f} at its end); its data set "
                    f"(`{final['dataset']}`, complete = {final['complete']}) records "
                    f"{final['path_job_wall_time_s_sum']:,.0f} s of solver time, the finished "
                    "paths' and this run's failed attempts'.")
        if n_failed:
            parsed = [m.groupdict() for m in map(FAILED_PATH.match, final["failed_jobs"]) if m]
            where = ""
            if len(parsed) == n_failed:
                heights = sorted({float(g["H_m"]) for g in parsed})
                bases = sorted({float(g["H"]) for g in parsed})
                where = (f" (magnets {' or '.join(f'{h:g}' for h in heights)} mm high, bases "
                         f"H = {' and '.join(f'{h:g}' for h in bases)} mm)")
            out += ["", f"The {n_failed} paths that fail{where} stop before full compression; "
                    "the levels of t each reached are kept in the data set (NaN beyond):", ""]
            out += table(["magnet [mm]", "H [mm]", "θ [rad]", "failed at t", "why",
                          "levels kept up to t"], _failed_rows(final["failed_jobs"]))
        else:
            out += [""]
    if "doe_resume" in r.files:
        e = r["doe_resume"]
        ref, stop, res = e["uninterrupted"], e["interrupted"], e["resumed"]
        same = e["resumed_equals_uninterrupted"]
        diff = max(same["max_relative_difference"].values())
        msg = res["message"]
        out += [f"**Resumption after an interruption** ({r.source('doe_resume')}, "
                f"`bench/bench_doe_resume.py`, commit {e['commit'][:7]}, "
                f"{e['machine']['cpus']} cores, load {e['load_average_at_start'][0]:.1f} at the "
                f"start and {e['load_average_at_end'][0]:.1f} at the end). A small real study "
                f"({e['paths_total']} structural paths on the coarse mesh) runs as "
                f"`{e['magtact_doe']}` three times: to its end in a fresh cache "
                f"({ref['wall_time_s']:.1f} s); in a second fresh cache, stopped "
                f"{stop['signal_sent_after_s']:.1f} s in, as soon as the cache held "
                f"{stop['paths_cached_at_signal']} path"
                f"{'s' if stop['paths_cached_at_signal'] != 1 else ''}, "
                f"by {' then '.join(stop['signals'])} to its process group"
                f"{' (what Ctrl-C in a terminal sends)' if stop['signals'][0] == 'SIGINT' else ''}"
                f", which ended it in {stop['exit_after_signal_s']:.1f} s with exit "
                f"status {stop['exit_status']}, {stop['paths_cached_at_exit']} path"
                f"{'s' if stop['paths_cached_at_exit'] != 1 else ''} cached, no data set "
                f"written{'' if not stop['doe_nc_written'] else ' (yet a doe.nc was written)'} "
                f"and {stop['processes_left_in_its_group'] or 'none'} of its processes left"
                "; then the "
                f"same command again on that cache.", ""]
        rows = [["uninterrupted, fresh cache", f"{ref['wall_time_s']:.1f}",
                 str(ref["message"]["paths_computed"]), str(ref["message"]["paths_cached"])],
                ["interrupted", f"{stop['wall_time_s']:.1f}",
                 f"{stop['paths_cached_at_exit']} (cached by the signal's end)", "0"],
                ["resumed", f"{res['wall_time_s']:.1f}", str(msg["paths_computed"]),
                 str(msg["paths_cached"])],
                ["interrupted + resumed", f"{e['interrupted_plus_resumed_wall_time_s']:.1f} "
                 f"({spct(e['overhead_over_uninterrupted'])} against the uninterrupted run)",
                 "", ""]]
        out += table(["run", "wall [s]", "paths solved", "paths from the cache"], rows)
        counts = {msg["paths_computed"], res["dataset_attrs"]["run_paths_computed"],
                  res["paths_added_to_the_cache"]}
        out += [f"The resumed run solved {' / '.join(str(c) for c in sorted(counts))} "
                f"path{'s' if counts != {1} else ''} by its message, its data set's "
                "`run_paths_computed` and the entries it added to the cache"
                + (" (all three agree)" if len(counts) == 1 else " (they disagree)")
                + ": " + ("exactly the paths the interruption left missing, by cache key"
                          if res["solved_exactly_the_missing_paths"]
                          else "not exactly the paths the interruption left missing")
                + f". Its data set is {'identical' if same['data_identical'] else 'not identical'}"
                " to the uninterrupted one (`xarray` `identical`: the variables and coordinates "
                "with their attributes; largest relative difference of a variable "
                + (f"{diff:.1e}" if diff else "0: every number the same to the bit") + "); "
                "of the global attributes, besides those that describe a run (its counters, "
                "times and date), "
                + _attributes_differing(same["attributes_differing"], ref, res,
                                        res["solved_exactly_the_missing_paths"])
                + ". " + _interruption_cost(e["overhead_over_uninterrupted"]), ""]
    return out


def document(folder: Path) -> str:
    r = Results(folder)
    lines = ["# Verification of magtact", "",
             "<!-- Generated by scripts/make_verification.py from bench/results/*.json; "
             "do not edit by hand. -->", "",
             "What the benchmarks in `bench/` measured: accuracy of the field, convergence of "
             "the structural model, accuracy of the metamodels, Γ against the data, the effect "
             "of the mesh on the chosen design, the optimiser against brute force, and timings. "
             "The method is in [method.md](method.md). Every number below is read from "
             "`bench/results`; rerun a benchmark, then `python scripts/make_verification.py`.",
             ""]
    for section in (field_section, mechanics_section, fit_section, gamma_section,
                    mesh_effect_section, frontier_section, optimise_section, geometry_section,
                    broad_section, sizes_section, robust_section, publication_section,
                    timing_section, doe_cost_section,
                    speed_section):
        lines += section(r)
    return "\n".join(lines).rstrip() + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--results", type=Path, default=ROOT / "bench" / "results")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "verification.md")
    args = ap.parse_args()
    args.out.write_text(document(args.results), encoding="utf-8")
    print(args.out)


if __name__ == "__main__":
    main()
