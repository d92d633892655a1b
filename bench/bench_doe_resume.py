"""The DOE interrupted and resumed: what an interruption costs, and that nothing is lost or
solved twice.

Usage::

    python bench/bench_doe_resume.py [--workers 1] [--signal INT]

A small real study (coarse mesh, a short loading path, the exact field: a few seconds a path,
:data:`STUDY`) runs three times as whole ``python -m magtact doe`` processes, each with
``--workers``:

1. **uninterrupted**, into a fresh job cache: the reference data set and wall time;
2. **interrupted**, into a second fresh cache: as soon as the cache holds a structural path the
   process group gets ``--signal`` (``INT``: what Ctrl-C in a terminal sends); if it has not ended
   after :data:`GRACE_S` seconds it gets SIGTERM, then SIGKILL;
3. **resumed**: the same command again on the second cache.

Recorded in ``bench/results/doe_resume.json``: the paths in the cache when the signal was sent and
when the interrupted process had ended, the signals it took and its exit status, whether a
process of its group outlived it; the paths the resumed run solved, counted three ways (its
message ``N computed, M from the cache``, its data set's ``run_paths_computed`` and the cache
entries it added) and checked to be exactly the ones the interruption left missing (by cache
key); the wall times interrupted + resumed against the uninterrupted run; and whether the
resumed data set equals the uninterrupted one (``xarray`` ``identical`` on the data, and the
largest relative difference). With the commit, the machine and the load averages.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import xarray as xr

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "bench" / "results" / "doe_resume.json"

#: The study: 2 θ × 3 H = 6 structural paths on the coarse mesh, a short loading path
#: (Δz_sat = 5.7 mm) in steps of at most 0.5, 3 levels of t and 2 of G, the exact field.
STUDY = """\
name = "resume-bench"
[doe]
n_t = 3
n_theta = 2
n_H = 3
n_G = 2
[loading]
dz_sat_mm = 5.7
[mechanics]
mesh = "coarse"
dt_initial = 0.25
dt_max = 0.5
[magnetics]
solver = "exact"
"""
#: Seconds the interrupted process is given to end after each signal before the next one.
GRACE_S = 30.0
#: Run attributes that differ between two runs of the same DOE (not data).
RUN_ATTRS = ("run_", "field_wall_time_s", "created_utc")
#: Fields of a path's record in the ``jobs`` attribute that time it (the solver's and the job's).
JOB_TIMES = ("wall_time", "job_wall_time")
#: The summary line of ``magtact doe``.
SUMMARY = re.compile(r"(\d+) structural paths: (\d+) computed, (\d+) from the cache")


def _keys(cache: Path, kind: str = "path") -> set[str]:
    """The job keys of ``kind`` in a job cache (empty if it does not exist yet)."""
    from magtact.doe import JobCache

    return set(JobCache(cache).keys(kind)) if cache.is_dir() else set()


def _command(study: Path, out: Path, cache: Path, workers: int) -> list[str]:
    return [sys.executable, "-m", "magtact", "doe", str(study), "--out", str(out),
            "--cache", str(cache), "--workers", str(workers)]


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def _group(pgid: int) -> list[int]:
    """The processes of a process group still there (zombies not counted)."""
    pids = subprocess.run(["pgrep", "-g", str(pgid)], capture_output=True,
                          text=True).stdout.split()
    alive = []
    for pid in map(int, pids):
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:
            continue
        if state != "Z":
            alive.append(pid)
    return alive


def _summary(text: str) -> dict:
    """The counts of ``magtact doe``'s summary line."""
    m = SUMMARY.search(" ".join(text.split()))
    if m is None:
        raise SystemExit(f"no summary line in the output of magtact doe:\n{text[-2000:]}")
    total, computed, cached = map(int, m.groups())
    return {"paths_total": total, "paths_computed": computed, "paths_cached": cached}


def complete_run(study: Path, out: Path, cache: Path, workers: int) -> dict:
    """``magtact doe`` to its end: wall time, load, its summary and data set attributes."""
    load = os.getloadavg()
    start = time.perf_counter()
    proc = subprocess.run(_command(study, out, cache, workers), capture_output=True, text=True,
                          cwd=ROOT)
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        raise SystemExit(f"magtact doe failed (exit {proc.returncode}):\n{proc.stderr[-3000:]}")
    with xr.open_dataset(out / "doe.nc") as ds:
        attrs = ds.attrs
        run = {k: int(attrs[k]) for k in ("run_paths_total", "run_paths_computed",
                                          "run_paths_cached", "run_fields_computed")}
        revision = str(attrs["source_revision"])
    return {"wall_time_s": wall, "load_average_at_start": list(load),
            "load_average_at_end": list(os.getloadavg()),
            "message": _summary(proc.stdout + proc.stderr), "dataset_attrs": run,
            "source_revision": revision}


def interrupted_run(study: Path, out: Path, cache: Path, workers: int, first: str) -> dict:
    """``magtact doe`` stopped by signals as soon as its cache holds a structural path."""
    load = os.getloadavg()
    start = time.perf_counter()
    log = out.parent / f"{out.name}.log"  # a file, not a pipe: nothing blocks the process
    with log.open("w") as sink:
        proc = subprocess.Popen(_command(study, out, cache, workers), stdout=sink,
                                stderr=subprocess.STDOUT, cwd=ROOT, start_new_session=True)
    pgid = proc.pid  # its own session and process group
    while not _keys(cache):
        if proc.poll() is not None:
            raise SystemExit("the DOE ended before a path was cached:\n" + log.read_text())
        time.sleep(0.05)
    at_signal = _keys(cache)
    signalled_after = time.perf_counter() - start
    sent = []
    for name in (first, "TERM", "KILL"):
        if name in sent:
            continue
        os.killpg(pgid, getattr(signal, f"SIG{name}"))
        sent.append(name)
        try:
            proc.wait(timeout=GRACE_S)
            break
        except subprocess.TimeoutExpired:
            continue
    proc.wait()
    ended = time.perf_counter() - start
    output = log.read_text()
    # the group's other processes (the local workers) end by themselves; give them GRACE_S
    deadline = time.monotonic() + GRACE_S
    while _group(pgid) and time.monotonic() < deadline:
        time.sleep(0.1)
    survivors = _group(pgid)
    for pid in survivors:
        os.kill(pid, signal.SIGKILL)
    after = _keys(cache)
    return {
        "wall_time_s": ended, "signal_sent_after_s": signalled_after,
        "exit_after_signal_s": ended - signalled_after,
        "load_average_at_start": list(load), "load_average_at_end": list(os.getloadavg()),
        "signals": [f"SIG{s}" for s in sent], "exit_status": proc.returncode,
        "output_tail": output[-600:],
        "paths_cached_at_signal": len(at_signal), "paths_cached_at_exit": len(after),
        "fields_cached_at_exit": len(_keys(cache, "field")),
        "processes_left_in_its_group": len(survivors),
        "doe_nc_written": (out / "doe.nc").exists(),
        "_keys_at_exit": sorted(after),
    }


def _comparable(ds: xr.Dataset) -> xr.Dataset:
    """The data set without what differs between two runs of one DOE: the run's counters and
    date, and the wall times (the run's, the field job's and each path's)."""
    out = ds.copy()
    out.attrs = {k: v for k, v in ds.attrs.items() if not k.startswith(RUN_ATTRS)}
    out.attrs["jobs"] = json.dumps([{k: v for k, v in j.items() if k not in JOB_TIMES}
                                    for j in json.loads(ds.attrs["jobs"])])
    return out


def compare(a: Path, b: Path) -> dict:
    """Whether two data sets of one DOE are the same: ``identical`` on their data (variables,
    coordinates and their attributes), the global attributes that differ beyond those that
    describe a run, and the largest relative difference of each variable."""
    with xr.open_dataset(a) as x, xr.open_dataset(b) as y:
        x, y = x.load(), y.load()
    diff = {}
    for name in x.data_vars:
        u, v = x[name].values, y[name].values
        scale = np.max(np.abs(u)) or 1.0
        diff[name] = float(np.max(np.abs(u - v)) / scale)
    cx, cy = _comparable(x), _comparable(y)
    bare_x, bare_y = cx.copy(), cy.copy()
    bare_x.attrs, bare_y.attrs = {}, {}
    jobs = list(zip(json.loads(x.attrs["jobs"]), json.loads(y.attrs["jobs"]), strict=True))
    return {"data_identical": bool(bare_x.identical(bare_y)),
            "path_record_fields_differing": sorted({k for a, b in jobs for k in a | b
                                                    if k not in JOB_TIMES
                                                    and a.get(k) != b.get(k)}),
            "attributes_differing": sorted(k for k in set(cx.attrs) | set(cy.attrs)
                                           if str(cx.attrs.get(k)) != str(cy.attrs.get(k))),
            "allclose_rtol_1e-12": bool(all(np.allclose(x[n].values, y[n].values, rtol=1e-12,
                                                        atol=0) for n in x.data_vars)),
            "max_relative_difference": diff}


def _git(*args: str) -> str:
    return subprocess.run(["git", *args], capture_output=True, text=True,
                          cwd=ROOT).stdout.rstrip("\n")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--signal", default="INT", choices=["INT", "TERM"])
    args = ap.parse_args(argv)
    load = os.getloadavg()
    commit = _git("rev-parse", "HEAD")
    with tempfile.TemporaryDirectory(prefix="magtact-resume-") as tmp:
        tmp = Path(tmp)
        study = tmp / "study.toml"
        study.write_text(STUDY)
        ref = complete_run(study, tmp / "ref", tmp / "cache-ref", args.workers)
        print(f"uninterrupted: {ref['wall_time_s']:.1f} s", flush=True)
        cache = tmp / "cache"
        stop = interrupted_run(study, tmp / "run", cache, args.workers, args.signal)
        left = set(stop.pop("_keys_at_exit"))
        print(f"interrupted after {stop['signal_sent_after_s']:.1f} s with "
              f"{stop['paths_cached_at_signal']} path(s) cached ({', '.join(stop['signals'])}, "
              f"exit {stop['exit_status']})", flush=True)
        resumed = complete_run(study, tmp / "run", cache, args.workers)
        solved = _keys(cache) - left
        all_keys = _keys(tmp / "cache-ref")
        resumed["paths_added_to_the_cache"] = len(solved)
        resumed["solved_exactly_the_missing_paths"] = (
            solved == all_keys - left and _keys(cache) == all_keys)
        print(f"resumed: {resumed['wall_time_s']:.1f} s, {resumed['message']}", flush=True)
        same = compare(tmp / "ref" / "doe.nc", tmp / "run" / "doe.nc")
    total = stop["wall_time_s"] + resumed["wall_time_s"]
    record = {
        "benchmark": "the DOE interrupted and resumed",
        "command": "python bench/bench_doe_resume.py" + "".join(
            f" --{k} {v}" for k, v in (("workers", args.workers), ("signal", args.signal))),
        "commit": commit, "commit_at_end": _git("rev-parse", "HEAD"),
        "source_changes_uncommitted": [line[3:] for line in
                                       _git("status", "--porcelain", "--", "src").splitlines()],
        "machine": {"cpus": os.cpu_count(), "platform": platform.platform(),
                    "python": platform.python_version()},
        "load_average_at_start": list(load), "load_average_at_end": list(os.getloadavg()),
        "study_toml": STUDY, "workers": args.workers,
        "magtact_doe": " ".join(["python -m magtact doe STUDY --out DIR --cache DIR",
                                 f"--workers {args.workers}"]),
        "paths_total": len(all_keys),
        "uninterrupted": ref, "interrupted": stop, "resumed": resumed,
        "interrupted_plus_resumed_wall_time_s": total,
        "overhead_over_uninterrupted": total / ref["wall_time_s"] - 1,
        "resumed_equals_uninterrupted": same,
    }
    OUT.write_text(json.dumps(record, indent=1) + "\n")
    print(f"{OUT}: interrupted + resumed {total:.1f} s against {ref['wall_time_s']:.1f} s "
          f"uninterrupted; data identical: {same['data_identical']}, attributes that differ: "
          f"{same['attributes_differing'] or 'none'}")


if __name__ == "__main__":
    main()
