"""How long a designer waits: whole processes of a baseline commit and of this checkout's commit,
timed side by side in one run.

Usage::

    python bench/bench_speed.py [--baseline 6151215] [--head HEAD] [--repeat 3]
                                [--rows run,design,whatif,whatif_6x3,calibrate,explorer]

Each row is one command in a fresh Python process (start-up, the models' compilation and the
whole computation included), run ``--repeat`` times for each commit in turn (baseline, head,
baseline, head, ...: a drift of the machine's speed falls on both alike). Both commits run from
their own git worktree (``PYTHONPATH=<worktree>/src``), so uncommitted changes of the checkout
take no part. For each run the wall time and the CPU time (user + system, of the child processes)
are recorded; each row gives the medians and the speed-up ``baseline / head`` of each, with the
load averages at its start and end (a shared machine runs slower in wall time; its CPU time
moves less). Writes ``bench/results/speed.json``.

The rows: ``magtact run`` on the built-in study; ``magtact.design("magone")``; a what-if (grade
N52, G in 10-60 kPa); the 6 x 3 mm N42 magnet's what-if through ``magtact.design`` (the study edit
of ``bench/bench_broad.py``); ``magtact calibrate``; the explorer's grid of the built-in study's
result (``magtact.report.explorer_data``, after its ``magtact.design``).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "results" / "speed.json"

#: The what-ifs, as study edits of the built-in study.
WHATIF = {"magnet": {"grade": "N52"}, "design": {"G_kPa": [10.0, 60.0]}}
WHATIF_6X3 = {"magnet": {"R_m_mm": 3.0, "H_m_mm": 3.0, "grade": "N42"},
              "design": {"H_mm": [4.0, 10.0], "H_original_mm": 5.0}}

_DESIGN = "import magtact; magtact.design({study})"
ROWS = {
    "run": ("magtact run --out OUT", ["-c", "from magtact.cli import main; main()", "run",
                                      "--out", "{out}"]),
    "design": ('magtact.design("magone")', ["-c", _DESIGN.format(study="'magone'")]),
    "whatif": ("magtact.design: grade N52, G in 10-60 kPa",
               ["-c", "from magtact.study import study_from_dict; "
                + _DESIGN.format(study=f"study_from_dict({{'base': 'magone', **{WHATIF!r}}})")]),
    "whatif_6x3": ("magtact.design: 6 x 3 mm N42 magnet, H in 4-10 mm",
                   ["-c", "from magtact.study import study_from_dict; "
                    + _DESIGN.format(study="study_from_dict({'base': 'magone', "
                                           f"**{WHATIF_6X3!r}}})")]),
    "calibrate": ("magtact calibrate --out OUT", ["-c", "from magtact.cli import main; main()",
                                                  "calibrate", "--out", "{out}"]),
    "explorer": ("the explorer's grid (magtact.design, then explorer_data)",
                 ["-c", "import magtact; from magtact.report import explorer_data; "
                        "explorer_data(magtact.design('magone'))"]),
}


def worktree(commit: str, where: Path) -> tuple[Path, str]:
    """A detached worktree of ``commit`` at ``where``; returns it and the full hash."""
    full = subprocess.run(["git", "-C", str(ROOT), "rev-parse", commit], check=True,
                          capture_output=True, text=True).stdout.strip()
    subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(where), full],
                   check=True, capture_output=True)
    return where, full


def timed(src: Path, args: list[str], out: Path) -> dict:
    """One run of ``python ARGS`` with ``src`` first on the path: wall and CPU seconds."""
    # the computation is timed, not an answer kept by an earlier run (magtact._answers)
    env = dict(os.environ, PYTHONPATH=str(src), MPLBACKEND="Agg", MAGTACT_CACHE_DIR="off")
    cmd = [sys.executable, *(a.replace("{out}", str(out)) for a in args)]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False,
                          cwd=out.parent)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall_s": wall, "cpu_s": cpu, "exit_status": proc.returncode,
            "stderr_tail": proc.stderr[-800:] if proc.returncode else ""}


def _record(label: str, repeat: int, load_start, runs: dict) -> dict:
    """A row's record: its runs, the medians of wall and CPU time and the speed-ups."""
    rec = {"what": label, "repeat": repeat, "runs_done": len(runs["head"]),
           "load_average_start": load_start, "load_average_end": os.getloadavg(), "runs": runs}
    for k in ("wall_s", "cpu_s"):
        med = {n: statistics.median(r[k] for r in runs[n]) for n in runs}
        rec[f"median_{k}"] = med
        rec[f"speed_up_{k.removesuffix('_s')}"] = med["baseline"] / med["head"]
    rec["all_ok"] = all(r["exit_status"] == 0 for n in runs for r in runs[n])
    return rec


def _write(doc: dict, row: str, rec: dict) -> None:
    """Write ``doc`` with the row ``row``; rows another call of this script wrote for the same
    commits (rows timed side by side in two processes) are kept."""
    doc["rows"][row] = rec
    now = json.loads(RESULTS.read_text()) if RESULTS.is_file() else {}
    if (now.get("baseline"), now.get("head")) == (doc["baseline"], doc["head"]):
        doc["rows"] = now.get("rows", {}) | {row: rec}
        doc["command"] = " ; ".join(dict.fromkeys(
            [*now.get("command", "").split(" ; "), doc["command"]]))
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")


def main(argv: list[str] | None = None) -> None:
    global RESULTS
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--baseline", default="6151215", help="baseline commit")
    parser.add_argument("--head", default="HEAD", help="commit to compare with the baseline")
    parser.add_argument("--repeat", type=int, default=3, help="runs per commit and row")
    parser.add_argument("--rows", default=",".join(ROWS), help="comma-separated rows")
    parser.add_argument("--results", type=Path, default=RESULTS, help="JSON file written")
    args = parser.parse_args(argv)
    rows = [r.strip() for r in args.rows.split(",") if r.strip()]
    unknown = [r for r in rows if r not in ROWS]
    if unknown:
        parser.error(f"unknown rows {unknown}; choose from {list(ROWS)}")
    RESULTS = args.results
    old = json.loads(RESULTS.read_text()) if RESULTS.is_file() else {}
    with tempfile.TemporaryDirectory(prefix="magtact-bench-speed-") as tmp:
        tmp = Path(tmp)
        trees = {}
        try:
            for name, commit in (("baseline", args.baseline), ("head", args.head)):
                trees[name] = worktree(commit, tmp / name)
            doc = {"command": "python bench/bench_speed.py " + " ".join(argv or sys.argv[1:]),
                   "machine": {"cpus": os.cpu_count(), "platform": platform.platform(),
                               "python": platform.python_version()},
                   "baseline": trees["baseline"][1], "head": trees["head"][1],
                   "repeat": args.repeat,
                   "note": "speed_up = baseline median / head median; wall and CPU (user + "
                           "system) seconds of whole processes; load averages (1, 5, 15 min) "
                           "at each row's start and end",
                   "rows": dict(old.get("rows", {})) if old.get("baseline") == args.baseline
                   else {}}
            for row in rows:
                label, cmd = ROWS[row]
                runs = {"baseline": [], "head": []}
                load_start = os.getloadavg()
                for i in range(args.repeat):
                    for name in ("baseline", "head"):
                        out = tmp / f"out-{row}-{name}-{i}"
                        r = timed(trees[name][0] / "src", cmd, out)
                        runs[name].append(r)
                        print(f"{row:11s} {name:8s} wall {r['wall_s']:7.1f} s  cpu "
                              f"{r['cpu_s']:7.1f} s  exit {r['exit_status']}", flush=True)
                        if runs["head"]:  # the row so far: an interrupted call keeps its runs
                            _write(doc, row, _record(label, args.repeat, load_start, runs))
        finally:
            for where, _ in trees.values():
                subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force",
                                str(where)], check=False, capture_output=True)
    print(f"wrote {RESULTS}")
    for row, rec in doc["rows"].items():
        print(f"{row:11s} wall {rec['median_wall_s']['baseline']:7.1f} -> "
              f"{rec['median_wall_s']['head']:6.1f} s (x{rec['speed_up_wall']:.2f}), cpu "
              f"{rec['median_cpu_s']['baseline']:7.1f} -> {rec['median_cpu_s']['head']:6.1f} s "
              f"(x{rec['speed_up_cpu']:.2f})")


if __name__ == "__main__":
    main()
