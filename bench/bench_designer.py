"""The designer's answer for the original and the chosen MagOne design with the chip presets.

Usage::

    python bench/bench_designer.py

Writes ``bench/results/designer.json``: per chip preset and design, the chip's range, where the
field leaves it along the paths (t, angle, force), the force ranges, and σ_F per µT of RMS field
noise (the presets state no noise figure: σ_F for a chip setting is these numbers times its
noise in µT, per axis); the sensitivity of the answer to the tolerance of G (10 %); the design
chosen when the chip's range is a constraint (``[constraints] chip_range``, NSGA-II and the exact
reduction); and the time of one answer.
"""

from __future__ import annotations

import json
import os
import platform
import time
from dataclasses import replace
from pathlib import Path

from magtact.designer import HALL_PRESETS, answer, answer_json
from magtact.metamodel import load_models, prefitted_dir
from magtact.optimise import (
    InfeasibleError,
    as_responses,
    choose,
    exact_reduction,
    force_constraints,
    optimise,
    sweep,
)
from magtact.study import load_study

RESULTS = Path(__file__).resolve().parent / "results"
PER_UT = 1e-6  # 1 µT RMS on both axes


def main() -> None:
    study = load_study("magone")
    models = load_models(prefitted_dir())
    R = as_responses(models)
    table = sweep(R, study)
    designs = {"original": (study.design.H_original, study.design.G_original)}
    for delta in (0.0, 0.1):
        s = replace(study, constraints=replace(study.constraints, G_tolerance=delta))
        ch = choose(R, s, exact_reduction(R, s, force_constraints(R, s), table))
        designs[f"chosen (G tolerance {delta:.0%})"] = (ch.design.H, ch.design.G)
    out = {"machine": {"cpus": os.cpu_count(), "platform": platform.platform()},
           "noise_note": "sigma_* are per 1 µT RMS field noise on both axes (the presets "
                         "state no noise figure)", "chips": {}}
    for chip in HALL_PRESETS:
        s = replace(study, hall=replace(study.hall, chip=chip, noise_x=PER_UT, noise_z=PER_UT))
        rows = {}
        bound = replace(s, constraints=replace(s.constraints, chip_range=True))
        t0, extra = time.perf_counter(), {}
        try:
            o = optimise(models, bound)
        except InfeasibleError as exc:
            out.setdefault("chip_range", {})[chip] = {"infeasible": str(exc)}
        else:
            e = o.reduction_choice.design
            out.setdefault("chip_range", {})[chip] = {
                "nsga2_H_mm": o.choice.design.H * 1e3, "nsga2_G_kPa": o.choice.design.G / 1e3,
                "exact_H_mm": e.H * 1e3, "exact_G_kPa": e.G / 1e3, "front_gap": o.gap,
                "active": list(o.choice.active), "time_s": time.perf_counter() - t0}
            extra = {"chosen (chip range a constraint)": (o.choice.design.H, o.choice.design.G)}
        for label, (H, G) in (designs | extra).items():
            t0 = time.perf_counter()
            a = answer(models, s, H, G, label)
            rows[label] = answer_json(a) | {"answer_time_s": time.perf_counter() - t0}
        out["chips"][chip] = rows
    (RESULTS / "designer.json").write_text(json.dumps(out, indent=1, ensure_ascii=False) + "\n")
    print(json.dumps(out["chip_range"], indent=1))
    for chip, rows in out["chips"].items():
        for label, r in rows.items():
            print(f"{chip:9s} {label:28s} H {r['H_mm']:.3g} mm G {r['G_kPa']:.3g} kPa  "
                  f"σ_Fr {r['sigma_Fr_0_mN']:.3g}/{r['sigma_Fr_worst_mN']:.3g} mN  "
                  f"σ_Fz {r['sigma_Fz_0_mN']:.3g}/{r['sigma_Fz_worst_mN']:.3g} mN per µT; "
                  f"saturates {r['saturates']} t={r['saturation_t']} F_z={r['saturation_F_z_N']}")


if __name__ == "__main__":
    main()
