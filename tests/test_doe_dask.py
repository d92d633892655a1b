"""The DOE on a dask.distributed cluster: ``magtact doe --scheduler ADDR`` on a ``LocalCluster``.

The cluster is one worker process (two threads) of a ``LocalCluster`` on this machine, reached
through its TCP address exactly as a remote scheduler would be. The structural and field
solvers are the analytic stand-ins of ``conftest.py`` (the worker process imports them by name),
so every job takes milliseconds; the real solvers on a cluster are exercised in
``test_doe_acceptance.py``.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import socket
import subprocess
import sys
import threading
import time

import pytest
import xarray as xr

from conftest import fake_field, fake_path, run, tiny
from magtact.doe import JobCache, load_dataset, run_doe
from magtact.study import load_study

STUDY = """\
name = "tiny-dask"
[doe]
n_t = 4
n_theta = 2
n_H = 3
n_G = 2
"""
N_PATHS = 2 * 3  # one structural path per (θ, H)


def magtact(*args: str) -> subprocess.CompletedProcess:
    """``magtact ARGS`` in this process (the console script's entry point), output captured."""
    from magtact.cli import main

    out, err = io.StringIO(), io.StringIO()
    argv, columns = sys.argv, os.environ.get("COLUMNS")
    sys.argv = ["magtact", *args]
    os.environ["COLUMNS"] = "1000"  # one message on one line
    code = 0
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            main()
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    finally:
        sys.argv = argv
        if columns is None:
            os.environ.pop("COLUMNS", None)
        else:
            os.environ["COLUMNS"] = columns
    return subprocess.CompletedProcess(args, code, out.getvalue(), err.getvalue())


def stand_in_solvers(monkeypatch) -> None:
    """Make ``magtact doe`` use the analytic stand-in solvers, every other argument as given."""
    def run_stand_in(study, **kw):
        return run_doe(study, path_solver=fake_path, field_solver=fake_field, **kw)

    monkeypatch.setattr("magtact.doe.run_doe", run_stand_in)


#: Global attributes that describe one run, not its data: counters, times, executor, date.
RUN_ATTRS = ("run_", "field_wall_time_s", "created_utc")


def comparable(ds: xr.Dataset) -> xr.Dataset:
    """The data set without what differs between two runs of the same DOE: the run's counters,
    wall times, executor and date (and each path's ``job_wall_time`` in ``jobs``)."""
    out = ds.copy()
    out.attrs = {k: v for k, v in ds.attrs.items() if not k.startswith(RUN_ATTRS)}
    out.attrs["jobs"] = json.dumps([{k: v for k, v in job.items() if k != "job_wall_time"}
                                    for job in json.loads(ds.attrs["jobs"])])
    return out


@pytest.fixture(scope="module")
def cluster():
    """A dask cluster on this machine: one worker process with two threads, and a client that
    watches its tasks."""
    import distributed

    with (distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=True,
                                   dashboard_address=None) as local,
          distributed.Client(local) as client):
        yield local.scheduler_address, client


def test_the_doe_on_a_cluster_equals_the_in_process_doe_and_fills_the_cache(
        cluster, tmp_path, monkeypatch):
    from distributed import get_task_stream

    address, client = cluster
    assert address.startswith("tcp://")
    stand_in_solvers(monkeypatch)
    study_file = tmp_path / "study.toml"
    study_file.write_text(STUDY)
    cache = tmp_path / "cache"

    with get_task_stream(client) as tasks:
        res = magtact("doe", str(study_file), "--out", str(tmp_path / "dask"),
                      "--cache", str(cache), "--scheduler", address)
    assert res.returncode == 0, res.stdout + res.stderr
    assert f"{N_PATHS} computed, 0 from the cache" in res.stderr  # the console's messages
    # every job ran on the cluster's worker: one field job and one task per path
    worker = next(iter(client.scheduler_info()["workers"]))
    ran = sorted(t["key"].split("-")[0] for t in tasks.data if t["worker"] == worker)
    assert ran == ["run_field"] + ["run_path"] * N_PATHS
    # the calling process wrote every job's result to its cache as it came back
    store = JobCache(cache)
    assert len(store.keys("path")) == N_PATHS and len(store.keys("field")) == 1

    on_cluster = load_dataset(tmp_path / "dask" / "doe.nc")
    assert on_cluster.attrs["run_executor"] == f"dask.distributed scheduler {address}"
    in_process = run(load_study(study_file), workers=0)  # no cache: computed afresh here
    assert in_process.attrs["run_paths_computed"] == N_PATHS
    xr.testing.assert_identical(comparable(on_cluster), comparable(in_process))

    # the same DOE again, on the cluster and in process: everything comes from the cache
    with get_task_stream(client) as again:
        rerun = magtact("doe", str(study_file), "--out", str(tmp_path / "again"),
                        "--cache", str(cache), "--scheduler", address)
    assert rerun.returncode == 0, rerun.stdout + rerun.stderr
    assert f"0 computed, {N_PATHS} from the cache" in rerun.stderr
    assert again.data == []
    cached = run(load_study(study_file), cache, workers=0)
    assert cached.attrs["run_paths_computed"] == 0 and cached.attrs["run_fields_computed"] == 0
    xr.testing.assert_identical(comparable(cached), comparable(in_process))


# ---- one job at a time in a worker process ------------------------------------------------------
_BUSY = threading.Lock()  # held while a stand-in job runs in this process


def _alone(solve, *args, **kw):
    """``solve(*args, **kw)``, failing if another job runs in this process at the same time."""
    if not _BUSY.acquire(blocking=False):
        raise RuntimeError("two jobs at once in one worker process")
    try:
        time.sleep(0.05)  # long enough for a second thread to start a job beside this one
        return solve(*args, **kw)
    finally:
        _BUSY.release()


def path_alone(study, H, theta, **kw):
    """The stand-in structural path, refused beside another job of the same process."""
    return _alone(fake_path, study, H, theta, **kw)


def field_alone(study, t, theta, H, **kw):
    """The stand-in field, refused beside another job of the same process."""
    return _alone(fake_field, study, t, theta, H, **kw)


def test_a_worker_with_two_threads_runs_one_job_at_a_time(cluster, tmp_path):
    """The FE meshes are made by gmsh, which is not thread-safe: a worker process whose two
    threads could take two jobs still solves one after the other."""
    address, client = cluster
    assert sum(w["nthreads"] for w in client.scheduler_info()["workers"].values()) == 2
    ds = run(tiny(n_H=3), tmp_path, scheduler=address, path_solver=path_alone,
             field_solver=field_alone)
    assert ds.attrs["complete"] == 1 and ds.attrs["run_paths_computed"] == N_PATHS


def _closed_port() -> int:
    """A TCP port of this machine that nothing listens on (just released by the system)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_an_unreachable_scheduler_is_one_clear_error(tmp_path, monkeypatch):
    monkeypatch.setattr("magtact.doe._executor.CONNECT_TIMEOUT", "1s")
    stand_in_solvers(monkeypatch)
    study_file = tmp_path / "study.toml"
    study_file.write_text(STUDY)
    address = f"tcp://127.0.0.1:{_closed_port()}"
    res = magtact("doe", str(study_file), "--out", str(tmp_path / "o"),
                  "--cache", str(tmp_path / "cache"), "--scheduler", address)
    assert res.returncode == 2, res.stdout + res.stderr
    text = " ".join((res.stdout + res.stderr).split())
    assert "Traceback" not in text
    assert f"error: cannot use the dask scheduler '{address}' (--scheduler):" in text
    assert "Timed out trying to connect" in text
    # nothing was computed or written: the cache holds no job and no data set was written
    assert not JobCache(tmp_path / "cache").keys("path")
    assert not (tmp_path / "o" / "doe.nc").exists()
