"""A job cache on disk: one verified file per job, written atomically.

Each entry is ``<root>/<kind>/<key>.mtc``: one header line
``MAGTACT-CACHE 1 <kind> <key> <sha256 of payload> <payload size>`` followed by the payload, a
NumPy ``.npz`` archive (read with ``allow_pickle=False``) holding the job's arrays and a JSON
string of its scalar metadata. An entry is written to a temporary file in the same folder and
renamed over the target (``os.replace`` is atomic on one file system), so a reader never sees a
half-written entry; an entry that fails any check on read (header, size, checksum, key, archive)
is reported with a :class:`CacheCorruptWarning` and treated as missing, so the job is recomputed;
so is an entry that passes those checks but fails the caller's ``verify`` (an array missing,
misshapen or not finite). Something that is not a file in an entry's place (a folder), or an
entry that cannot be read, is a :class:`CacheError` naming it: the cache is not this run's to
delete.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._errors import MagtactError
from .._files import write_bytes

MAGIC = b"MAGTACT-CACHE"
FORMAT = 1
SUFFIX = ".mtc"


class CacheError(MagtactError):
    """An entry's place in the cache holds something magtact cannot read or replace."""


class CacheCorruptWarning(UserWarning):
    """A cache entry could not be verified; the job it holds is recomputed."""


@dataclass(frozen=True)
class Entry:
    """The content of one cache entry: named arrays and JSON-safe metadata."""

    arrays: dict[str, np.ndarray]
    meta: dict


class JobCache:
    """Job results on disk under ``root``, keyed by ``(kind, key)``.

    Parameters
    ----------
    root : path
        Cache folder (created on first write). Safe to share between runs and processes: entries
        are immutable once written and every write is atomic.
    """

    def __init__(self, root: str | os.PathLike):
        self.root = Path(root)
        #: Number of entries found corrupt (and discarded) by :meth:`get` so far.
        self.corrupt = 0

    def path(self, kind: str, key: str) -> Path:
        """File of the entry ``(kind, key)``."""
        _check_name(kind, "kind")
        _check_name(key, "key")
        return self.root / kind / f"{key}{SUFFIX}"

    def get(self, kind: str, key: str, verify=None) -> Entry | None:
        """The verified entry, or ``None`` if it is missing or corrupt (with a warning).

        ``verify(entry)``, if given, checks the content and raises ValueError when the entry
        does not hold what the job produces (the entry is then treated as corrupt).

        Raises
        ------
        CacheError
            If the entry's place holds a folder or another non-file, or cannot be read.
        """
        path = self.path(kind, key)
        try:
            data = path.read_bytes()
        except FileNotFoundError:
            return None
        except OSError as exc:
            what = "a folder" if path.is_dir() else "unreadable"
            raise CacheError(f"cache entry {path} is {what} ({exc.strerror or exc}); remove it "
                             "or give another cache folder") from None
        try:
            entry = _decode(data, kind, key)
            if verify is not None:
                verify(entry)
            return entry
        except ValueError as exc:
            self.corrupt += 1
            warnings.warn(f"cache entry {path} is corrupt ({exc}); the job is recomputed",
                          CacheCorruptWarning, stacklevel=2)
            return None

    def put(self, kind: str, key: str, entry: Entry) -> Path:
        """Write ``entry`` atomically (temporary file + rename); return its path."""
        return write_bytes(self.path(kind, key), _encode(entry, kind, key), fsync=True)

    def keys(self, kind: str) -> list[str]:
        """Keys of the entries of one kind present on disk (not verified)."""
        folder = self.root / kind
        if not folder.is_dir():
            return []
        return sorted(p.stem for p in folder.glob(f"*{SUFFIX}"))


def _check_name(name: str, what: str) -> None:
    if not name or not all(c.isalnum() or c in "-_" for c in name):
        raise ValueError(f"cache {what} must be letters, digits, '-' or '_', got {name!r}")


def _encode(entry: Entry, kind: str, key: str) -> bytes:
    buf = io.BytesIO()
    arrays = {name: np.asarray(a) for name, a in entry.arrays.items()}
    if "__meta__" in arrays:
        raise ValueError("'__meta__' is reserved in cache entries")
    for name, a in arrays.items():
        if a.dtype == object:
            raise ValueError(f"cache array {name!r} has dtype object; only plain arrays are stored")
    np.savez(buf, __meta__=np.array(json.dumps(entry.meta, sort_keys=True)), **arrays)
    payload = buf.getvalue()
    digest = hashlib.sha256(payload).hexdigest()
    header = b" ".join([MAGIC, str(FORMAT).encode(), kind.encode(), key.encode(),
                        digest.encode(), str(len(payload)).encode()])
    return header + b"\n" + payload


def _decode(data: bytes, kind: str, key: str) -> Entry:
    head, sep, payload = data.partition(b"\n")
    if not sep:
        raise ValueError("no header line")
    parts = head.split(b" ")
    if len(parts) != 6 or parts[0] != MAGIC:
        raise ValueError("not a magtact cache entry")
    if parts[1] != str(FORMAT).encode():
        raise ValueError(f"cache format {parts[1].decode(errors='replace')}, expected {FORMAT}")
    if parts[2].decode(errors="replace") != kind or parts[3].decode(errors="replace") != key:
        raise ValueError("the header names another job")
    try:
        size = int(parts[5])
    except ValueError:
        raise ValueError("bad payload size in header") from None
    if len(payload) != size:
        raise ValueError(f"payload has {len(payload)} bytes, header says {size} (truncated?)")
    if hashlib.sha256(payload).hexdigest().encode() != parts[4]:
        raise ValueError("checksum mismatch")
    try:
        with np.load(io.BytesIO(payload), allow_pickle=False) as npz:
            arrays = {name: npz[name] for name in npz.files}
        meta = json.loads(str(arrays.pop("__meta__")))
    except Exception as exc:  # a payload that passed the checksum but is not a valid archive
        raise ValueError(f"unreadable payload: {exc}") from None
    if not isinstance(meta, dict):
        raise ValueError("the metadata is not a JSON object")
    return Entry(arrays=arrays, meta=meta)
