"""Running jobs: in this process, in local worker processes, or on a dask.distributed cluster.

The same job functions run everywhere; results come back to the calling process as they finish
(the caller caches each one at once, so an interruption loses only the jobs in flight).
Local workers are ``spawn``-ed processes that exit by themselves if the calling process dies
(a watchdog thread compares their parent id), so a killed study leaves no orphan solving on.
A dask worker process runs one job at a time whatever its number of threads: the meshes are
made by gmsh, whose state is global to a process and which is not thread-safe.
"""

from __future__ import annotations

import os
import queue
import threading
import time
import uuid
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass
from multiprocessing import get_context

from .._errors import MagtactError
from ._jobs import Outcome

#: Environment variables that bound the threads of BLAS / MKL (PARDISO) in each worker.
THREAD_VARS = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")
#: How long to try to reach a dask scheduler.
CONNECT_TIMEOUT = "10s"
#: Held by the job that runs in a dask worker process (its other threads wait).
_JOB_LOCK = threading.Lock()


@dataclass(frozen=True)
class Task:
    """One job to run: ``func(job, *args)`` returns an :class:`Outcome`."""

    job: object
    func: Callable[..., Outcome]
    args: tuple = ()


def default_workers() -> int:
    """Number of local worker processes by default: the CPU cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def execute(tasks: list[Task], *, workers: int | None = None, scheduler: str | None = None,
            on_start: Callable[[object], None] = lambda job: None,
            ) -> Iterator[tuple[object, Outcome]]:
    """Run ``tasks``; yield ``(job, outcome)`` in order of completion.

    Parameters
    ----------
    tasks : list of Task
    workers : int, optional
        Local worker processes (default: the number of cores); ``0`` runs the jobs one after the
        other in this process. Ignored when ``scheduler`` is given.
    scheduler : str, optional
        Address of a dask.distributed scheduler (``"tcp://host:8786"``): the jobs run on its
        workers instead, one job at a time in each worker process (start the workers with
        ``--nthreads 1``, one process per core: ``dask worker ADDR --nworkers N --nthreads 1``).
    on_start : callable
        Called with a job when it is known to be running (in this process or a local worker).

    Infrastructure errors (a dead worker process, a lost dask worker) are returned as failed
    outcomes for the jobs they hit; the other jobs still finish.
    """
    if not tasks:
        return
    if scheduler is not None:
        yield from _dask(tasks, scheduler)
        return
    workers = default_workers() if workers is None else workers
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 0:
        raise ValueError(f"workers must be a whole number >= 0 (0: run in this process), "
                         f"got {workers!r}")
    if workers == 0:
        for task in tasks:
            on_start(task.job)
            yield task.job, task.func(task.job, *task.args)
        return
    yield from _local(tasks, min(workers, len(tasks)), on_start)


def _watch_parent(parent: int) -> None:
    """Worker initialiser: exit as soon as the process that started us is gone."""
    def watch():
        while os.getppid() == parent:
            time.sleep(0.2)
        os._exit(3)

    threading.Thread(target=watch, name="magtact-parent-watch", daemon=True).start()


@contextmanager
def _thread_limits(workers: int):
    """Give each spawned worker an equal share of the cores (unless the user set a limit)."""
    share = str(max(1, default_workers() // workers))
    added = [v for v in THREAD_VARS if v not in os.environ]
    for var in added:
        os.environ[var] = share
    try:
        yield
    finally:
        for var in added:
            os.environ.pop(var, None)


def _local(tasks: list[Task], workers: int, on_start) -> Iterator[tuple[object, Outcome]]:
    done: queue.Queue = queue.Queue()
    with _thread_limits(workers):
        pool = ProcessPoolExecutor(max_workers=workers, mp_context=get_context("spawn"),
                                   initializer=_watch_parent, initargs=(os.getpid(),))
        try:
            futures = {}
            for task in tasks:
                fut = pool.submit(task.func, task.job, *task.args)
                futures[fut] = task.job
                fut.add_done_callback(done.put)
            started: set = set()
            for _ in range(len(futures)):
                while True:
                    for fut, job in futures.items():
                        if fut not in started and fut.running():
                            started.add(fut)
                            on_start(job)
                    try:
                        fut = done.get(timeout=0.25)
                        break
                    except queue.Empty:
                        continue
                yield futures[fut], _outcome(fut)
        finally:
            pool.shutdown(wait=True, cancel_futures=True)


def _dask(tasks: list[Task], scheduler: str) -> Iterator[tuple[object, Outcome]]:
    from distributed import Client

    done: queue.Queue = queue.Queue()
    try:
        client = Client(scheduler, timeout=CONNECT_TIMEOUT)
    except (OSError, ValueError, TypeError) as exc:
        raise MagtactError(f"cannot use the dask scheduler {scheduler!r} (--scheduler): "
                           f"{exc}") from None
    with client:
        futures = {}
        for task in tasks:
            fut = client.submit(_one_at_a_time, task.func, task.job, *task.args, pure=False,
                                key=f"{task.func.__name__}-{uuid.uuid4()}")
            futures[fut.key] = (fut, task.job)
            fut.add_done_callback(lambda f: done.put(f.key))
        for _ in range(len(futures)):
            fut, job = futures[done.get()]
            yield job, _outcome(fut)


def _one_at_a_time(func: Callable[..., Outcome], job: object, *args) -> Outcome:
    """``func(job, *args)`` in a dask worker, never beside another job of the same process.

    A worker with several threads would otherwise run several jobs at once in one process, and
    two meshes made by gmsh at the same time in one process come out empty or mixed up.
    """
    with _JOB_LOCK:
        return func(job, *args)


def _outcome(fut) -> Outcome:
    """The outcome of a finished future; an exception of the executor becomes a failure."""
    try:
        return fut.result()
    except Exception as exc:  # e.g. BrokenProcessPool, KilledWorker, CancelledError
        return Outcome(None, f"{type(exc).__name__}: {exc} (the job's worker failed)")
