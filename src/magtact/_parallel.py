"""Independent solves spread over the machine's cores.

:func:`fork_map` runs a deterministic function on each of a few items in worker processes
started by fork (Linux), so that each worker starts with everything the caller has loaded
(models, data, imports) and nothing is pickled on the way in: the items travel as their
indices. Results come back in the order of the items; warnings a worker gave are given again
by the caller, in that order. Where no worker can be started by fork (other systems, one core,
a daemonic process, one item) or the pool breaks, the items are computed here, one after the
other, with the same results.

An item whose function raises in a worker is computed again here, so that the caller gets the
exception itself with its traceback (the function is deterministic).
"""

from __future__ import annotations

import os
import sys
import warnings
from collections.abc import Callable, Sequence
from typing import Any

#: The job of the workers being started: (function, items), read by the forked workers.
_JOB: tuple[Callable, Sequence] | None = None


def cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def _can_fork(n: int) -> bool:
    import multiprocessing

    return (n > 1 and sys.platform.startswith("linux") and cores() > 1
            and not multiprocessing.current_process().daemon)


def _run(i: int) -> tuple[str, Any, list]:
    """Item ``i`` of the job in a worker: ("ok", result, warnings) or ("raised", None, [])."""
    fn, items = _JOB
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            out = fn(items[i])
        except Exception:  # computed again by the caller, which raises it
            return "raised", None, []
    return "ok", out, [(str(w.message), w.category, w.filename, w.lineno) for w in caught]


def fork_map(fn: Callable, items: Sequence, workers: int | None = None, *,
             first: Callable[[Any], float] | None = None) -> list:
    """``[fn(x) for x in items]``, on up to ``workers`` (default: the cores) forked worker
    processes where that is possible (see the module notes); the same list either way.

    ``first``: the items of the smallest ``first(x)`` are handed to the workers first (the
    longest jobs, so that short ones fill the workers' last moments); the list returned is in
    the order of ``items`` all the same."""
    global _JOB

    items = list(items)
    workers = min(workers or cores(), len(items))
    if not _can_fork(workers):
        return [fn(x) for x in items]
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor
    from concurrent.futures.process import BrokenProcessPool

    _JOB = (fn, items)
    try:
        with warnings.catch_warnings():
            # Python 3.12+ warns of fork in a process with threads (a BLAS pool's, say): the
            # workers run only ``fn`` on their own data, as the figures' worker does
            warnings.filterwarnings("ignore", r"This process .* is multi-threaded",
                                    DeprecationWarning)
            with ProcessPoolExecutor(max_workers=workers,
                                     mp_context=multiprocessing.get_context("fork")) as pool:
                order = (range(len(items)) if first is None
                         else sorted(range(len(items)), key=lambda k: first(items[k])))
                done = dict(zip(order, pool.map(_run, order), strict=True))
                done = [done[k] for k in range(len(items))]
    except (BrokenProcessPool, OSError):  # no worker could run: here, one after the other
        return [fn(x) for x in items]
    finally:
        _JOB = None
    out = []
    for x, (status, result, caught) in zip(items, done, strict=True):
        if status != "ok":
            result = fn(x)  # raises what the worker raised
        for message, category, filename, lineno in caught:
            warnings.warn_explicit(message, category, filename, lineno)
        out.append(result)
    return out
