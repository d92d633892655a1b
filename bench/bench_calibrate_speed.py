"""``magtact calibrate --out X`` against ``magtact run`` on the built-in study, as whole processes.

Usage::

    python bench/bench_calibrate_speed.py [--pairs 3]

Runs the two commands in turn (run, calibrate, run, calibrate ...: pairing keeps the ratio
meaningful when the machine's speed drifts), each a fresh process from start to exit, and
records per run the wall time, the CPU time (user + system of the process and the processes it
waited for) and the load averages before and after. Writes ``bench/results/calibrate_speed.json``
with the medians and the ratio calibrate / run of the medians and of each pair; the target is a
ratio of at most 0.5. Both commands compute their answer (the answers cache off). Each pair is
followed by the designer's order, ``magtact run`` then ``magtact calibrate`` with one answers
cache, whose calibrate is recorded as ``calibrate_after_run``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
OUT = HERE / "results" / "calibrate_speed.json"
TARGET = 0.5


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def timed(args: list[str], folder: Path, cache: str = "off") -> dict:
    """Wall and CPU seconds of one process, its exit status and the load around it; ``cache``:
    the answers cache folder (``"off"``: the command computes its answer)."""
    shutil.rmtree(folder, ignore_errors=True)
    load_before = os.getloadavg()
    cpu0, t0 = _cpu(), time.perf_counter()
    proc = subprocess.run([*args, "--out", str(folder)], capture_output=True, text=True,
                          env=dict(os.environ, MAGTACT_CACHE_DIR=cache))
    wall, cpu = time.perf_counter() - t0, _cpu() - cpu0
    return {"wall_s": wall, "cpu_s": cpu, "exit_status": proc.returncode,
            "load_average_before": list(load_before), "load_average_after": list(os.getloadavg()),
            "stderr_tail": proc.stderr[-400:] if proc.returncode else ""}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--pairs", type=int, default=3)
    opts = parser.parse_args()
    exe = shutil.which("magtact") or sys.exit("magtact is not on PATH")
    commands = {"run": [exe, "run"], "calibrate": [exe, "calibrate"]}
    runs: dict[str, list[dict]] = {k: [] for k in commands}
    after: list[dict] = []  # the designer's order: run, then calibrate, one answers cache
    with tempfile.TemporaryDirectory(prefix="magtact-bench-calibrate-") as tmp:
        for k in range(opts.pairs):
            for name, args in commands.items():
                r = timed(args, Path(tmp) / f"{name}{k}")
                runs[name].append(r)
                print(f"{name} {k + 1}/{opts.pairs}: {r['wall_s']:.1f} s wall, "
                      f"{r['cpu_s']:.1f} s CPU, exit {r['exit_status']}, load "
                      f"{r['load_average_before'][0]:.2f}", flush=True)
            cache = str(Path(tmp) / f"answers{k}")
            first = timed(commands["run"], Path(tmp) / f"run_cached{k}", cache)
            r = timed(commands["calibrate"], Path(tmp) / f"calibrate_after{k}", cache)
            after.append(r | {"run_before_exit_status": first["exit_status"]})
            print(f"calibrate after run {k + 1}/{opts.pairs}: {r['wall_s']:.1f} s wall",
                  flush=True)
    median = {name: {key: statistics.median(r[key] for r in rs) for key in ("wall_s", "cpu_s")}
              for name, rs in runs.items()}
    pairs = [{key: c[key] / r[key] for key in ("wall_s", "cpu_s")}
             for r, c in zip(runs["run"], runs["calibrate"], strict=True)]
    ratio = {key: median["calibrate"][key] / median["run"][key] for key in ("wall_s", "cpu_s")}
    commit = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True,
                            cwd=HERE).stdout.strip()
    doc = {
        "machine": {"cpus": os.cpu_count(), "platform": platform.platform(),
                    "python": platform.python_version()},
        "commit": commit,
        "commands": {name: " ".join(["magtact", *args[1:], "--out", "DIR"])
                     for name, args in commands.items()},
        "runs": runs, "median": median, "ratio_of_medians": ratio,
        "calibrate_after_run": {
            "what": "magtact calibrate right after magtact run with one answers cache "
                    "(MAGTACT_CACHE_DIR): the run's answer is kept, the calibration computed",
            "runs": after,
            "median_wall_s": statistics.median(r["wall_s"] for r in after),
            "ratio_to_run_median_wall": statistics.median(r["wall_s"] for r in after)
            / median["run"]["wall_s"]},
        "ratio_per_pair": pairs, "target_ratio": TARGET,
        "target_met": {key: v <= TARGET for key, v in ratio.items()},
        "all_exit_0": all(r["exit_status"] == 0 for rs in runs.values() for r in rs),
    }
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
    print(f"calibrate / run: {ratio['wall_s']:.2f} (wall), {ratio['cpu_s']:.2f} (CPU) -> {OUT}")


if __name__ == "__main__":
    main()
