"""The magnetisation as a design variable on the MagOne study: the chosen (H, G, M_z) with and
without the chip's range as a constraint, against the (H, G) optimum of the same constraints.

Usage::

    python bench/bench_design_variables.py

Writes ``bench/results/design_variables.json``: per case the chosen design of NSGA-II and of the
exact reduction, the front gap between them, the worst sensitivities and the wall time of the
whole optimisation (bundled DOE and shipped fit; no FE run: M_z needs no new simulation).
"""

from __future__ import annotations

import json
import os
import platform
import time
from dataclasses import replace
from pathlib import Path

from magtact.metamodel import load_models, prefitted_dir
from magtact.optimise import optimise
from magtact.study import from_si, load_study

RESULTS = Path(__file__).resolve().parent / "results"
M_Z_RANGE = (0.9e6, 1.3e6)  # A/m: N35 to N52 grades, roughly


def _design(d) -> dict:
    return {"H_mm": from_si(d.H, "mm"), "G_kPa": from_si(d.G, "kPa"),
            "M_z_MA_per_m": None if d.M_z is None else from_si(d.M_z, "MA_per_m"),
            "Gamma_r_max_N_per_T": d.Gamma_r_max, "Gamma_z_max_N_per_T": d.Gamma_z_max,
            "F_r_min_N": d.F_r_min, "F_z_max_N": d.F_z_max}


def main() -> None:
    base = load_study("magone")
    models = load_models(prefitted_dir())
    out = {"machine": {"cpus": os.cpu_count(), "platform": platform.platform()},
           "M_z_range_A_per_m": list(M_Z_RANGE), "chip": base.hall.chip, "cases": {}}
    for chip_range in (False, True):
        s0 = replace(base, constraints=replace(base.constraints, chip_range=chip_range))
        for variable in (False, True):
            s = replace(s0, design=replace(s0.design, M_z=M_Z_RANGE)) if variable else s0
            t0 = time.perf_counter()
            o = optimise(models, s)
            name = f"{'(H, G, M_z)' if variable else '(H, G)'}, chip_range={chip_range}"
            out["cases"][name] = {"nsga2": _design(o.choice.design),
                                  "exact_reduction": _design(o.reduction_choice.design),
                                  "front_gap": o.gap, "active": list(o.choice.active),
                                  "wall_time_s": time.perf_counter() - t0}
            c = out["cases"][name]
            print(f"{name:32s} H {c['nsga2']['H_mm']:.4g} mm  G {c['nsga2']['G_kPa']:.4g} kPa  "
                  f"M_z {c['nsga2']['M_z_MA_per_m']}  Γ_r {c['nsga2']['Gamma_r_max_N_per_T']:.4g}"
                  f"  gap {o.gap:.2g}  {c['wall_time_s']:.0f} s")
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "design_variables.json").write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
