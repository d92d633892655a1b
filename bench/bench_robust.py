"""The robust solve against the nominal one on the built-in study with its own magnet (the
MagOne ⌀5 × 2 mm, ``[design] magnet_sizes = []``): wall time of each (one run
each after an untimed warm-up run, the same machine, one after the other), the sensor each chooses, its force noise nominal and at
the worst corner, and its verdict over the built units (worst case, yield, what limits it).

Usage::

    python bench/bench_robust.py [--light]

Writes ``bench/results/robust.json`` (``robust_light.json`` with ``--light``: the specification
``[requirements] F_z_N = 2, rate_Hz = 100``).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import magtact

# the solves are timed, not answers kept by an earlier run (magtact._answers)
os.environ["MAGTACT_CACHE_DIR"] = "off"
RESULTS = Path(__file__).resolve().parent / "results"


def _one(design_for: str, requirements: dict) -> tuple[dict, float]:
    study = magtact.load("magone", tolerances={"design_for": design_for},
                         requirements=requirements, design={"magnet_sizes": []})
    t0 = time.perf_counter()
    r = magtact.design(study)
    wall = time.perf_counter() - t0
    a, c = r.chosen, r.sensor_design.choice
    rob = a.robust
    doc = {"wall_time_s": wall, "load_average_after": list(os.getloadavg()),
           "chosen": c.to_json(),
           "verdict": a.verdict.to_json(),
           "saturation_F_z_N": a.verdict.F_saturation,
           "sigma_F_nominal_mN": 1e3 * rob.sigma_nominal,
           "sigma_F_worst_mN": 1e3 * rob.sigma_worst,
           "robust_verdict": rob.to_json()}
    return doc, wall


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--light", action="store_true")
    args = parser.parse_args(argv)
    req = {"F_z_N": 2.0, "rate_Hz": 100.0} if args.light else {}
    doc = {"machine": {"cpus": os.cpu_count(), "platform": platform.platform(),
                       "load_average_at_start": list(os.getloadavg())},
           "requirements": req or "the study's"}
    _one("nominal", req)  # warm-up (imports, the shipped models, compiled expressions)
    doc["nominal"], t_nominal = _one("nominal", req)
    doc["robust"], t_robust = _one("worst", req)
    doc["robust_over_nominal_time"] = t_robust / t_nominal
    out = RESULTS / ("robust_light.json" if args.light else "robust.json")
    out.write_text(json.dumps(doc, indent=1, ensure_ascii=False) + "\n")
    print(f"nominal {t_nominal:.1f} s, robust {t_robust:.1f} s "
          f"({t_robust / t_nominal:.2f} x); wrote {out}")
    for k in ("nominal", "robust"):
        print(k, doc[k]["chosen"]["H_mm"], doc[k]["chosen"]["G_kPa"],
              doc[k]["chosen"]["magnet_grade"], doc[k]["chosen"]["standoff_mm"],
              doc[k]["chosen"]["chip_setting"])
        for line in doc[k]["robust_verdict"]["requirements"]:
            print("  ", line["text"])


if __name__ == "__main__":
    main()
