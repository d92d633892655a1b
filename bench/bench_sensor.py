"""The sensor problem on the MagOne study: the chosen sensor, NSGA-II against the exact
reduction over seeds, and what the free variables (grade, standoff) and the rate cost or buy.

Usage::

    python bench/bench_sensor.py [--seeds 5]

Writes ``bench/results/sensor.json``: for the default study, each seed's NSGA-II choice, its
gap to the exact reduction and wall time; the chosen sensor; and the exact reduction's least
force noise for four problems: with and without the 100 Hz rate, with and without the free
grade and standoff (the study's magnet at the body's base: H, G and the setting only).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import magtact
from magtact.optimise import exact_sensor_reduction, optimise_sensor, sensor_space, sweep

RESULTS = Path(__file__).resolve().parent / "results" / "sensor.json"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=5)
    args = parser.parse_args(argv)
    study = magtact.load("magone")
    models = magtact.models_for(study)[0]
    table = sweep(models, study)
    doc = {"machine": {"cpus": os.cpu_count(), "platform": platform.platform(),
                       "load_average_at_start": list(os.getloadavg())},
           "seeds": []}
    for seed in range(args.seeds):
        s = magtact.load("magone", optimise={"seed": seed})
        t0 = time.perf_counter()
        r = optimise_sensor(models, s, table)
        doc["seeds"].append({"seed": seed, "gap_to_exact_reduction": r.gap,
                             "wall_time_s": time.perf_counter() - t0,
                             "chosen": r.choice.to_json()})
        if seed == 0:
            doc["chosen"] = r.to_json()
    variants = {
        "free grade and standoff, 100 Hz": {},
        "free grade and standoff, any rate": {"requirements": {"rate_Hz": 0.0}},
        "H, G and setting only, 100 Hz": {"design": {"grades": [], "standoff_mm": [0, 0]}},
        "H, G and setting only, any rate": {"design": {"grades": [], "standoff_mm": [0, 0]},
                                            "requirements": {"rate_Hz": 0.0}},
    }
    doc["exact_reduction"] = {}
    for name, sections in variants.items():
        s = magtact.load("magone", **sections)
        red, combos = exact_sensor_reduction(models, s, sensor_space(models, s, table))
        doc["exact_reduction"][name] = {"combinations": combos} | red.to_json()
    RESULTS.write_text(json.dumps(doc, indent=1) + "\n")
    gaps = [r["gap_to_exact_reduction"] for r in doc["seeds"]]
    print(f"wrote {RESULTS}: gaps {min(gaps):.3g} to {max(gaps):.3g}")
    for name, r in doc["exact_reduction"].items():
        print(f"  {name}: σ_F {r['sigma_Fr_mN']:.3g} / {r['sigma_Fz_mN']:.3g} mN "
              f"({r['magnet_grade']}, standoff {r['standoff_mm']:.3g} mm, H {r['H_mm']:.3g} mm, "
              f"G {r['G_kPa']:.3g} kPa, {r['chip_setting']})")


if __name__ == "__main__":
    main()
