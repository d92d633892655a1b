"""The results folder of ``magtact run``: nothing of the user's lost, no two runs mixed.

Three rules, each with its mechanism (docs/method.md §14):

* **One run at a time.** A run holds an exclusive lock on ``<folder>/.magtact-lock`` (an
  advisory ``flock``, which the system releases when the process ends in any way, so a crashed
  or killed run leaves no stuck lock). The file names the holder: process id, host, start time
  and command. A second run into the folder is refused with those details.
* **The previous results stay until the new ones are complete.** A run writes everything into a
  staging folder ``<folder>/.magtact-staging-<run id>/`` and, once its report is built, moves
  its files into place: the names to move are first recorded in a journal
  (``.magtact-swap.json``), so that a swap cut short by a kill is completed by the next
  ``magtact run`` or ``magtact report`` on the folder. A run stopped before the swap leaves the
  previous results untouched and its staging folder behind; :func:`interrupted_runs` finds it,
  and the report names it as interrupted.
* **No output replaces a file magtact did not write.** Each run records every file it wrote,
  with its SHA-256, in ``.magtact-files.json`` (the run's identity stamp). A file or folder in
  the way of an output is replaced only when the stamp lists it (every file of a folder) with
  the same content; anything else — the user's own ``study.toml``, a file they added to a stage
  folder or edited — makes the run refuse before it starts, naming the files.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import platform
import shutil
import signal
import time
from collections.abc import Iterable, Iterator
from datetime import UTC, datetime
from pathlib import Path

from ._errors import MagtactError
from ._files import write_json, write_text

#: The lock file of a results folder.
LOCK = ".magtact-lock"
#: The identity stamp: every file the last run wrote into the folder, with its SHA-256.
OWNED = ".magtact-files.json"
#: Prefix of a run's staging folder (followed by its run id).
STAGING = ".magtact-staging-"
#: Prefix of the folder the replaced results are moved to during a swap (then deleted).
OLD = ".magtact-old-"
#: The journal of a swap in progress.
JOURNAL = ".magtact-swap.json"
#: Seconds a run tries for the lock before refusing (covers a report's brief look).
LOCK_PATIENCE_S = 2.0
#: Start of every report magtact writes (a report.html older than the stamp is known by it).
REPORT_HEAD = '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>magtact report'

_replace = os.replace  # one name for every move of the swap


class FolderInUse(MagtactError):
    """Another process is writing the results folder."""


class NotMagtactsFile(MagtactError):
    """A file or folder in the way of an output was not written by magtact (or was changed)."""


# ---- the lock --------------------------------------------------------------------------------
def _now() -> str:
    return datetime.now(UTC).strftime("%Y-%m-%d %H:%M:%S UTC")


def _holder_text(path: Path) -> str:
    """The holder recorded in a lock file, in words."""
    try:
        info = json.loads(path.read_text(encoding="utf-8"))
        pid, host = int(info["pid"]), str(info["host"])
        started, command = str(info["started"]), str(info.get("command", ""))
    except (OSError, ValueError, KeyError, TypeError):
        return "another magtact process (its details are not written yet)"
    alive = _pid_alive(pid) if host == platform.node() else None
    state = "" if alive is not False else ", no longer running: a worker it started still holds"
    cmd = f" ({command})" if command else ""
    return f"process {pid} on {host}, started {started}{cmd}{state}"


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True
    return True


class RunLock:
    """The exclusive lock of a results folder, as a context manager.

    Parameters
    ----------
    folder : path
        The results folder (must exist).
    command : str
        What holds the lock (recorded for the message of a refused run).
    patience_s : float, optional
        Seconds to keep trying before refusing (default :data:`LOCK_PATIENCE_S`).

    Raises
    ------
    FolderInUse
        On entry, if another process holds the lock; the message names it.
    """

    def __init__(self, folder: str | os.PathLike, command: str = "",
                 patience_s: float | None = None):
        self.path = Path(folder) / LOCK
        self.command = command
        self.patience_s = LOCK_PATIENCE_S if patience_s is None else patience_s
        self.fd: int | None = None

    def __enter__(self) -> RunLock:
        deadline = time.monotonic() + self.patience_s
        while True:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o666)
            if _try_lock(fd):
                try:  # the file may have been removed by its last holder meanwhile
                    same = os.fstat(fd).st_ino == os.stat(self.path).st_ino
                except FileNotFoundError:
                    same = False
                if same:
                    break
            os.close(fd)
            if time.monotonic() > deadline:
                raise FolderInUse(f"{self.path.parent} is in use by another magtact run: "
                                  f"{_holder_text(self.path)}. Wait until it ends, or give "
                                  "another --out")
            time.sleep(0.1)
        self.fd = fd
        info = {"pid": os.getpid(), "host": platform.node(), "started": _now(),
                "command": self.command}
        os.ftruncate(fd, 0)
        os.lseek(fd, 0, os.SEEK_SET)
        os.write(fd, (json.dumps(info) + "\n").encode())
        return self

    def __exit__(self, *exc) -> None:
        if self.fd is not None:
            with contextlib.suppress(OSError):
                self.path.unlink()
            os.close(self.fd)  # closing releases the lock
            self.fd = None


def _try_lock(fd: int) -> bool:
    try:
        import fcntl
    except ImportError:  # Windows: a byte-range lock, released when the process ends
        import msvcrt

        try:
            msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
        except OSError:
            return False
        return True
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        return False
    return True


def in_use(folder: str | os.PathLike) -> str | None:
    """The process writing ``folder`` (in words), or None if no process holds its lock."""
    path = Path(folder) / LOCK
    try:
        fd = os.open(path, os.O_RDWR)
    except OSError:
        return None
    try:
        if _try_lock(fd):
            return None
        return _holder_text(path)
    finally:
        os.close(fd)


# ---- the identity stamp ------------------------------------------------------------------------
def sha256(path: Path) -> str:
    """SHA-256 of a file (hex)."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _files(root: Path) -> Iterator[Path]:
    """Every entry below ``root`` that is not a folder (symbolic links included, not followed)."""
    for top, dirs, names in os.walk(root):
        for name in names + [d for d in dirs if Path(top, d).is_symlink()]:
            yield Path(top, name)


def write_stamp(folder: Path, run_id: str) -> Path:
    """Record every file in ``folder`` (a staging folder) with its SHA-256 in the stamp."""
    files = {p.relative_to(folder).as_posix(): sha256(p) for p in sorted(_files(folder))
             if p.name != OWNED}
    return write_json(folder / OWNED, {"run_id": run_id, "files": files}, indent=1)


def _stamp(folder: Path) -> dict[str, str]:
    """The files the stamp of ``folder`` records (empty if none or unreadable)."""
    try:
        data = json.loads((folder / OWNED).read_text(encoding="utf-8"))
        files = data["files"]
    except (OSError, ValueError, KeyError, TypeError):
        return {}
    return {str(k): str(v) for k, v in files.items()} if isinstance(files, dict) else {}


def _is_magtacts(folder: Path, name: str, owned: dict[str, str]) -> bool:
    """True if ``folder/name`` holds only what magtact wrote there, unchanged."""
    path = folder / name
    if path.is_symlink() or not (path.is_file() or path.is_dir()):
        return False
    if path.is_file():
        if owned.get(name) == sha256(path):
            return True
        return name == "report.html" and _starts_with(path, REPORT_HEAD)
    for p in _files(path):
        rel = p.relative_to(folder).as_posix()
        if p.is_symlink() or not p.is_file() or owned.get(rel) != sha256(p):
            return False
    return True  # an empty folder holds nothing to lose


def _starts_with(path: Path, head: str) -> bool:
    try:
        with open(path, "rb") as fh:
            return fh.read(len(head.encode())) == head.encode()
    except OSError:
        return False


def check_replaceable(folder: str | os.PathLike, names: Iterable[str]) -> None:
    """Refuse if any of ``folder/<name>`` exists and is not magtact's to replace.

    Raises
    ------
    NotMagtactsFile
        Naming every such file or folder.
    """
    folder = Path(folder)
    owned = _stamp(folder)
    bad = [n for n in names if n != OWNED and os.path.lexists(folder / n)
           and not _is_magtacts(folder, n, owned)]
    if bad:
        one = len(bad) == 1
        listed = ", ".join(str(folder / n) for n in bad)
        raise NotMagtactsFile(
            f"{listed} {'is' if one else 'are'} not magtact's: not written by an earlier run "
            f"into {folder}, or changed since, and {'it' if one else 'they'} would be replaced "
            f"by this run's output. Give another --out (e.g. {folder / 'results'}), or move "
            f"{'it' if one else 'them'} away")


def claim(folder: Path, name: str, text: str) -> Path:
    """Write ``folder/name`` (if it is absent or magtact's) and record it in the stamp."""
    check_replaceable(folder, [name])
    path = write_text(folder / name, text)
    data = {"run_id": None, "files": {}}
    with contextlib.suppress(OSError, ValueError):
        loaded = json.loads((folder / OWNED).read_text(encoding="utf-8"))
        if isinstance(loaded, dict) and isinstance(loaded.get("files"), dict):
            data = loaded
    data["files"][name] = sha256(path)
    write_json(folder / OWNED, data, indent=1)
    return path


# ---- staging and swap ------------------------------------------------------------------------
def staging(folder: Path, run_id: str) -> Path:
    """Create and return the staging folder of run ``run_id``."""
    path = folder / f"{STAGING}{run_id}"
    path.mkdir()
    return path


def swap(folder: Path, stage: Path, run_id: str) -> None:
    """Put the complete results of ``stage`` in place of the previous run's (journalled).

    Every entry of ``stage`` replaces the entry of that name in ``folder``; the previous run's
    entries that this run did not write are removed too, when the stamp shows them unchanged.
    Call with the folder's lock held.

    Raises
    ------
    NotMagtactsFile
        If a file or folder in the way is not magtact's (the new results then stay complete in
        ``stage``).
    """
    names = sorted(p.name for p in stage.iterdir())
    try:
        check_replaceable(folder, names)
    except NotMagtactsFile as exc:
        raise NotMagtactsFile(f"{exc}. This run's complete results are in {stage}") from None
    owned = _stamp(folder)
    earlier = sorted({k.split("/", 1)[0] for k in owned} - set(names) - {OWNED})
    remove = [n for n in earlier if os.path.lexists(folder / n) and _is_magtacts(folder, n, owned)]
    journal = {"run_id": run_id, "staging": stage.name, "old": f"{OLD}{run_id}",
               "names": names, "remove": remove}
    write_json(folder / JOURNAL, journal, indent=1)
    with _signals_held():
        _roll_forward(folder, journal)


@contextlib.contextmanager
def _signals_held():
    """Defer SIGINT and SIGTERM to the end of the block (when called in the main thread): the
    signal is recorded, and raised again once the previous handlers are back."""
    held: list[int] = []
    try:
        old = {sig: signal.signal(sig, lambda signum, frame: held.append(signum))
               for sig in (signal.SIGINT, signal.SIGTERM)}
    except ValueError:  # not the main thread: signals cannot be handled here anyway
        yield
        return
    try:
        yield
    finally:
        for sig, handler in old.items():
            signal.signal(sig, handler)
        for sig in dict.fromkeys(held):
            signal.raise_signal(sig)


def _roll_forward(folder: Path, journal: dict) -> None:
    """Carry out (or finish) the swap a journal describes; idempotent."""
    stage, old = folder / journal["staging"], folder / journal["old"]
    old.mkdir(exist_ok=True)
    for name in journal["remove"]:
        if os.path.lexists(folder / name):
            _replace(folder / name, old / name)
    for name in journal["names"]:
        if not os.path.lexists(stage / name):
            continue  # moved already
        if os.path.lexists(folder / name):
            _remove(old / name)
            _replace(folder / name, old / name)
        _replace(stage / name, folder / name)
    (folder / JOURNAL).unlink(missing_ok=True)
    _remove(old)
    _remove(stage)


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    elif os.path.lexists(path):
        path.unlink()


def recover(folder: Path) -> bool:
    """Finish a swap that a killed run left half done (call with the lock held); True if one
    was finished."""
    try:
        journal = json.loads((folder / JOURNAL).read_text(encoding="utf-8"))
        ok = all(isinstance(journal.get(k), str) for k in ("staging", "old")) and all(
            isinstance(journal.get(k), list) for k in ("names", "remove"))
    except FileNotFoundError:
        return False
    except (OSError, ValueError, AttributeError):
        ok = False
    if not ok or not _plain_names([journal["staging"], journal["old"], *journal["names"],
                                   *journal["remove"]]):
        raise MagtactError(f"{folder / JOURNAL}: not a swap journal magtact can finish; remove it "
                           "(and any .magtact-staging-* or .magtact-old-* folder) by hand")
    _roll_forward(folder, journal)
    return True


def _plain_names(names: list) -> bool:
    return all(isinstance(n, str) and n not in ("", ".", "..") and "/" not in n and "\\" not in n
               for n in names)


def remove_dead(folder: Path, keep: Path | None = None) -> None:
    """Remove the staging and swap leftovers of earlier runs (call with the lock held)."""
    for p in folder.iterdir():
        if p.name.startswith((STAGING, OLD)) and p != keep:
            _remove(p)


def interrupted_runs(folder: str | os.PathLike, held: bool = False) -> list[dict]:
    """The runs that stopped before their results were put in place.

    Returns
    -------
    list of dict
        Per staging folder left by a run no longer running: ``staging`` (its name) and the
        ``run.json`` it holds (``manifest``, empty if none). Empty while another process holds
        the lock (its staging folder is in use); ``held``: this process holds it.
    """
    folder = Path(folder)
    if not folder.is_dir() or (not held and in_use(folder)):
        return []
    out = []
    for p in sorted(folder.glob(f"{STAGING}*")):
        try:
            manifest = json.loads((p / "run.json").read_text(encoding="utf-8"))
        except (OSError, ValueError):
            manifest = {}
        out.append({"staging": p.name, "manifest": manifest if isinstance(manifest, dict)
                    else {}})
    return out
