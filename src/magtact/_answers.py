"""Answers kept by content: a study solved once is read back, not solved again.

:func:`magtact.solve` is deterministic (seeded optimisers, closed-form models), and the same
study is solved again and again: ``magtact run``, then ``magtact calibrate`` and ``budget`` on
its chosen sensor, ``magtact.design`` in a notebook, the tests. Its answer (everything a
:class:`magtact.Result` holds but the models and the data set, which the caller has) is kept
under a key that is the SHA-256 of everything it depends on:

- magtact's own source code (every ``.py`` file of the package: any change is a new key),
- the installed versions of the packages that compute it (:data:`PACKAGES`),
- the models' expressions (only closed-form :class:`magtact.metamodel.Metamodel` responses are
  keyed; other models are solved every time),
- the study's settings and the force constraints, with floats written exactly.

The folder is ``$MAGTACT_CACHE_DIR``, else ``$XDG_CACHE_HOME/magtact``, else
``~/.cache/magtact``; ``MAGTACT_CACHE_DIR=off`` turns the keeping off. An entry is a header
(``MAGTACT-ANSWER 1 <key> <sha256 of payload> <size>``) and a pickle of plain data; an entry
that fails its checksum, its key or unpickling is solved again and replaced. Entries are only
read from this folder, which is the user's own. Warnings the solve gave are kept with the
answer and given again when it is read.
"""

from __future__ import annotations

import contextlib
import dataclasses
import fcntl
import functools
import hashlib
import json
import os
import pickle
import warnings
from pathlib import Path

import numpy as np

from ._files import write_bytes
from ._versions import package_versions

MAGIC = b"MAGTACT-ANSWER"
FORMAT = 1
#: Packages whose versions are part of the key (the ones the optimisation computes with).
PACKAGES = ("numpy", "scipy", "sympy", "pymoo", "magpylib")
#: Largest entry read back [bytes].
MAX_BYTES = 64 * 2**20


def folder() -> Path | None:
    """The cache folder, or None where ``MAGTACT_CACHE_DIR=off``."""
    env = os.environ.get("MAGTACT_CACHE_DIR")
    if env is not None:
        return None if env.strip().lower() in ("off", "") else Path(env) / "answers"
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "magtact" / "answers"


@functools.cache
def _code() -> str:
    """SHA-256 of magtact's source files (path and content) and the computing packages'
    versions."""
    h = hashlib.sha256()
    root = Path(__file__).resolve().parent
    for p in sorted(root.rglob("*.py")):
        h.update(p.relative_to(root).as_posix().encode() + b"\0" + p.read_bytes() + b"\0")
    h.update(json.dumps(package_versions(PACKAGES), sort_keys=True).encode())
    return h.hexdigest()


def _plain(x):
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    raise TypeError(f"not keyable: {type(x).__name__}")


def key(models, study, constraints) -> str | None:
    """The key of ``solve(models, study, constraints)``; None where the models are not all
    closed-form expressions (then nothing is kept)."""
    from .metamodel import Metamodel

    parts = []
    for name, m in models.items():
        if type(m) is not Metamodel:
            return None
        parts.append([name, m.units, *m.text])
    try:
        text = json.dumps([_code(), parts, dataclasses.asdict(study),
                           None if constraints is None else dataclasses.asdict(constraints)],
                          sort_keys=True, default=_plain)
    except TypeError:
        return None
    return hashlib.sha256(text.encode()).hexdigest()


def read(k: str | None) -> dict | None:
    """The kept answer of key ``k`` (its fields and warnings), or None."""
    where = folder()
    if k is None or where is None:
        return None
    path = where / f"{k}.answer"
    try:
        if not path.is_file() or path.stat().st_size > MAX_BYTES:
            return None
        data = path.read_bytes()
        head, _, payload = data.partition(b"\n")
        parts = head.split(b" ")
        if (len(parts) != 5 or parts[0] != MAGIC or parts[1] != str(FORMAT).encode()
                or parts[2] != k.encode() or int(parts[4]) != len(payload)
                or hashlib.sha256(payload).hexdigest().encode() != parts[3]):
            return None
        return pickle.loads(payload)
    except Exception:  # an unreadable or stale entry: solved again and replaced
        return None


def write(k: str | None, answer: dict) -> None:
    """Keep ``answer`` under key ``k`` (atomically); a folder that cannot be written is left
    alone (the answer is simply not kept)."""
    where = folder()
    if k is None or where is None:
        return
    payload = pickle.dumps(answer, protocol=pickle.HIGHEST_PROTOCOL)
    head = b" ".join([MAGIC, str(FORMAT).encode(), k.encode(),
                      hashlib.sha256(payload).hexdigest().encode(), str(len(payload)).encode()])
    try:
        where.mkdir(parents=True, exist_ok=True)
        write_bytes(where / f"{k}.answer", head + b"\n" + payload)
    except OSError:
        pass


@contextlib.contextmanager
def _lock(k: str | None):
    """Hold the key's lock file: a second process solving the same study waits for the first
    and reads its answer. Without a folder that can hold it, no lock."""
    where = folder()
    if k is None or where is None:
        yield
        return
    try:
        where.mkdir(parents=True, exist_ok=True)
        handle = open(where / f"{k}.lock", "a")
    except OSError:
        yield
        return
    with handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        yield


def kept(k: str | None, compute):
    """``compute()``'s dict of fields, read back when kept under ``k``; the warnings it gives
    are kept with it and given again on every read."""
    hit = read(k)
    if hit is None:
        with _lock(k):
            hit = read(k)
            if hit is None:
                with warnings.catch_warnings(record=True) as caught:
                    warnings.simplefilter("always")
                    fields = compute()
                hit = {"fields": fields,
                       "warnings": [(str(w.message), w.category) for w in caught]}
                write(k, hit)
    for message, category in hit["warnings"]:
        warnings.warn(message, category, stacklevel=3)
    return hit["fields"]
