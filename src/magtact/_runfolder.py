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

The per-stage commands (``field``, ``doe``, ``fit``, ``optimise``, ...) follow the same rules
through one context manager, :func:`command_outputs`: the folder's lock; the command writes
into a staging folder, and its files are put in place one by one (journalled) only when each
file in the way is one magtact wrote there and nobody changed since; they are then recorded in
the stamp with the command that wrote them. A command never replaces a file of a run's results
(the run's record stays true), and a run never replaces a file a command wrote.
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
import uuid
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

from ._errors import MagtactError
from ._files import (
    MAX_BYTES,
    UnreadableFile,
    read_json_capped,
    write_json,
    write_text,
)
from ._records import entry, from_json_lenient, from_json_or_none, to_json

#: The lock file of a results folder.
LOCK = ".magtact-lock"
#: The identity stamp: every file the last run wrote into the folder, with its SHA-256.
OWNED = ".magtact-files.json"
#: Prefix of a run's staging folder (followed by its run id).
STAGING = ".magtact-staging-"
#: Prefix of the folder the replaced results are moved to during a swap (then deleted).
OLD = ".magtact-old-"
#: Prefix of a per-stage command's staging folder (followed by a random id).
WRITING = ".magtact-writing-"
#: Prefix of the folder that keeps a command's outputs it could not put in place.
REFUSED = "magtact-unplaced-"
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


def _read_json(path: Path):
    """A JSON file of the folder's bookkeeping through the bounded reader (a regular file of
    at most :data:`magtact._files.MAX_BYTES` ``["json"]``, nested at most
    :data:`magtact._files.MAX_JSON_DEPTH` deep); :class:`UnreadableFile` otherwise."""
    return read_json_capped(path, MAX_BYTES["json"])


# ---- the lock --------------------------------------------------------------------------------
def _now() -> str:
    return datetime.now(UTC).strftime("%Y-%m-%d %H:%M:%S UTC")


@dataclass(frozen=True)
class LockInfo:
    """What the lock file (:data:`LOCK`) says of its holder: process, host, start, command and
    the top-level entries of the folder it writes."""

    pid: int = entry(kind=int)
    host: str = entry(kind=str)
    started: str = entry(kind=str)
    command: str = entry(kind=str, default="")
    writes: tuple[str, ...] = entry(kind=str, levels=("list",), default=())


def _lock_info(path: Path) -> LockInfo | None:
    """The holder a lock file records; None where it is unreadable or not written yet."""
    try:
        return from_json_or_none(LockInfo, _read_json(path))
    except UnreadableFile:
        return None


def _holder_text(path: Path) -> str:
    """The holder recorded in a lock file, in words."""
    info = _lock_info(path)
    if info is None:
        return "another magtact process (its details are not written yet)"
    alive = _pid_alive(info.pid) if info.host == platform.node() else None
    state = "" if alive is not False else ", no longer running: a worker it started still holds"
    cmd = f" ({info.command})" if info.command else ""
    return f"process {info.pid} on {info.host}, started {info.started}{cmd}{state}"


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
                 patience_s: float | None = None, writes: Iterable[str] = ()):
        self.path = Path(folder) / LOCK
        self.command = command
        self.writes = sorted(set(writes))
        self.patience_s = LOCK_PATIENCE_S if patience_s is None else patience_s
        self.fd: int | None = None
        self.nested = False

    def __enter__(self) -> RunLock:
        key = os.path.realpath(self.path)
        if _HELD.get(key, (None, 0))[0] == os.getpid():  # this process holds it already
            pid, depth = _HELD[key]
            _HELD[key] = (pid, depth + 1)
            self.nested = True
            return self
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
        info = LockInfo(os.getpid(), platform.node(), _now(), self.command, tuple(self.writes))
        os.ftruncate(fd, 0)
        os.lseek(fd, 0, os.SEEK_SET)
        os.write(fd, (json.dumps(to_json(info)) + "\n").encode())
        _HELD[key] = (os.getpid(), 1)
        return self

    def __exit__(self, *exc) -> None:
        key = os.path.realpath(self.path)
        if self.nested:
            pid, depth = _HELD[key]
            _HELD[key] = (pid, depth - 1)
            self.nested = False
            return
        _HELD.pop(key, None)
        if self.fd is not None:
            with contextlib.suppress(OSError):
                self.path.unlink()
            os.close(self.fd)  # closing releases the lock
            self.fd = None


#: The locks this process holds (real path of the lock file -> (pid, depth)): a command that
#: holds its folder's lock may call another part that takes it (``magtact reproduce`` builds the
#: report), without waiting for itself.
_HELD: dict[str, tuple[int, int]] = {}


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


@dataclass
class Stamp:
    """The stamp of a results folder (:data:`OWNED`): the run that wrote it, the files it
    holds (relative path -> SHA-256) and the per-stage commands that wrote some of them
    (relative path -> command; the other files are a run's or its report's; left out of the
    file where there are none)."""

    run_id: str | None = entry(kind=str, optional=True, default=None)
    files: dict[str, str] = entry(kind=str, levels=("map",), default_factory=dict)
    commands: dict[str, str] = entry(kind=str, levels=("map",), omit="empty",
                                     default_factory=dict)


def write_stamp(folder: Path, run_id: str) -> Path:
    """Record every file in ``folder`` (a staging folder) with its SHA-256 in the stamp."""
    files = {p.relative_to(folder).as_posix(): sha256(p) for p in sorted(_files(folder))
             if p.name != OWNED}
    return _write_stamp_doc(folder, Stamp(run_id, files))


def _stamp_doc(folder: Path) -> Stamp:
    """The stamp of ``folder``, read field by field (empty tables where there is none or it is
    unreadable)."""
    try:
        data = _read_json(folder / OWNED)
    except UnreadableFile:
        return Stamp()
    return from_json_lenient(Stamp, data) or Stamp()


def _stamp(folder: Path) -> dict[str, str]:
    """The files the stamp of ``folder`` records (empty if none or unreadable)."""
    return _stamp_doc(folder).files


def _is_magtacts(folder: Path, name: str, owned: dict[str, str],
                 commands: dict[str, str] | None = None) -> bool:
    """True if ``folder/name`` holds only what a run (or its report) wrote there, unchanged;
    a file a per-stage command wrote (in ``commands``) is not a run's to replace."""
    path = folder / name
    commands = commands or {}
    if path.is_symlink() or not (path.is_file() or path.is_dir()):
        return False
    if path.is_file():
        if name in commands:
            return False
        if owned.get(name) == sha256(path):
            return True
        return name == "report.html" and _starts_with(path, REPORT_HEAD)
    for p in _files(path):
        rel = p.relative_to(folder).as_posix()
        if (p.is_symlink() or not p.is_file() or rel in commands
                or owned.get(rel) != sha256(p)):
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
    doc = _stamp_doc(folder)
    owned, commands = doc.files, doc.commands
    bad = [n for n in names if n != OWNED and os.path.lexists(folder / n)
           and not _is_magtacts(folder, n, owned, commands)]
    if bad:
        one = len(bad) == 1
        listed = ", ".join(str(folder / n) for n in bad)
        by = sorted({commands[k] for k in commands if k.split("/", 1)[0] in bad})
        raise NotMagtactsFile(
            f"{listed} {'is' if one else 'are'} not magtact's: not written by an earlier run "
            f"into {folder}, or changed since"
            + (f", or {'it holds' if one else 'they hold'} the output of {', '.join(by)}"
               if by else "")
            + f", and {'it' if one else 'they'} would be replaced "
            f"by this run's output. Give another --out (e.g. {folder / 'results'}), or move "
            f"{'it' if one else 'them'} away")


def claim(folder: Path, name: str, text: str) -> Path:
    """Write ``folder/name`` (if it is absent or magtact's) and record it in the stamp."""
    check_replaceable(folder, [name])
    path = write_text(folder / name, text)
    data = _stamp_doc(folder)
    data.files[name] = sha256(path)
    data.commands.pop(name, None)
    _write_stamp_doc(folder, data)
    return path


def _write_stamp_doc(folder: Path, doc: Stamp) -> Path:
    return write_json(folder / OWNED, to_json(doc), indent=1)


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
    doc = _stamp_doc(folder)
    owned, commands = doc.files, doc.commands
    earlier = sorted({k.split("/", 1)[0] for k in owned} - set(names) - {OWNED})
    remove = [n for n in earlier
              if os.path.lexists(folder / n) and _is_magtacts(folder, n, owned, commands)]
    gone = set(names) | set(remove)
    kept = {k: v for k, v in owned.items()
            if k.split("/", 1)[0] not in gone and os.path.lexists(folder / k)}
    if kept:  # what the folder keeps (a command's outputs) stays recorded
        new = _stamp_doc(stage)
        new.files = kept | new.files
        new.commands = {k: c for k, c in commands.items() if k in kept} | new.commands
        _write_stamp_doc(stage, new)
    journal = SwapJournal(stage.name, f"{OLD}{run_id}", tuple(names), tuple(remove),
                          run_id=run_id)
    write_json(folder / JOURNAL, to_json(journal), indent=1)
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


@dataclass(frozen=True)
class SwapJournal:
    """The journal of a swap (:data:`JOURNAL`): the run, its staging folder, the folder the
    previous entries go to, the entries put in place and the previous ones removed."""

    run_id: str | None = entry(kind=str, optional=True, default=None, kw_only=True)
    staging: str = entry(kind=str)
    old: str = entry(kind=str)
    names: tuple[str, ...] = entry(kind=str, levels=("list",))
    remove: tuple[str, ...] = entry(kind=str, levels=("list",))


def _roll_forward(folder: Path, journal: SwapJournal) -> None:
    """Carry out (or finish) the swap a journal describes; idempotent."""
    stage, old = folder / journal.staging, folder / journal.old
    old.mkdir(exist_ok=True)
    for name in journal.remove:
        if os.path.lexists(folder / name):
            _replace(folder / name, old / name)
    for name in journal.names:
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
    """Finish a swap that a killed run, or the placing of outputs that a killed command, left
    half done (call with the lock held); True if one was finished."""
    try:
        if not os.path.lexists(folder / JOURNAL):
            return False
        doc = _read_json(folder / JOURNAL)
        if isinstance(doc, dict) and doc.get("kind") == "place":
            return _recover_place(folder, doc)
        journal = from_json_or_none(SwapJournal, doc)
    except UnreadableFile:
        journal = None
    if journal is None or not _plain_names([journal.staging, journal.old, *journal.names,
                                            *journal.remove]):
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
        if p.name.startswith((STAGING, OLD, WRITING)) and p != keep:
            _remove(p)


@dataclass
class StageRecord:
    """What happened to one stage of a run (an entry of ``run.json``'s ``stages``).

    Attributes
    ----------
    key, title : str
        Folder name and human title.
    status : str
        ``"ok"``, ``"warning"``, ``"failed"`` or ``"skipped"``.
    wall_time_s : float or None
        Wall time [s] (None where a file read back does not give it as a number).
    message : str
        One line: what was produced, or why it failed / was skipped.
    notes : list of str
        Further remarks (shown in the report).
    """

    key: str | None = entry(kind=str)
    title: str = entry(kind=str, fallback="")
    status: str = entry(kind=str, default="pending", fallback="unknown")
    wall_time_s: float | None = entry(optional=True, default=0.0, fallback=None)
    message: str = entry(kind=str, default="")
    notes: list[str] = entry(kind=str, levels=("list",), default_factory=list)

    def __post_init__(self):
        self.notes = list(self.notes)  # a list to add to, also where read from a file

    def to_json(self) -> dict:
        return to_json(self)

    @classmethod
    def from_json(cls, data) -> StageRecord | None:
        """The record :meth:`to_json` wrote, read field by field (None for anything but a
        JSON object; the key as the file gives it, None where missing or not text; a status
        the file does not give is ``"unknown"``)."""
        return from_json_lenient(cls, data)


def _unwritten():
    """A field of a manifest that the run has not reached yet: None, and not written."""
    return entry(kind=str, optional=True, omit="none", default=None)


@dataclass
class RunManifest:
    """``run.json``: what a run is (its id, study, command, start) and, as it goes, each
    stage's record, the data set's source, and at its end its finish or interruption and
    total wall time [s]. A field the run has not reached yet is None and not written."""

    run_id: str | None = entry(kind=str, optional=True)
    study: str = entry(kind=str, fallback="unknown study")
    command: str = entry(kind=str, fallback="")
    started: str | None = entry(kind=str, optional=True)
    recompute: bool = entry(kind=bool, default=False)
    refit: bool = entry(kind=bool, default=False)
    versions: dict[str, str] = entry(kind=str, levels=("map",), default_factory=dict)
    stages: list[StageRecord] = entry(kind=StageRecord, levels=("list",),
                                      default_factory=list)
    doe_source: str | None = _unwritten()
    wall_time_s: float | None = entry(optional=True, omit="none", default=None)
    interrupted: str | None = _unwritten()
    finished: str | None = _unwritten()

    def __post_init__(self):
        self.stages = list(self.stages)  # a list to add to, also where read from a file

    def to_json(self) -> dict:
        return to_json(self)

    @classmethod
    def from_json(cls, data) -> RunManifest | None:
        """The manifest :meth:`to_json` wrote, read field by field; None for anything but a
        non-empty JSON object (a forged file's value of the wrong type reads as none, a stage
        that is no record is left out)."""
        if not isinstance(data, dict) or not data:
            return None
        return from_json_lenient(cls, data)

    def write(self, folder: str | os.PathLike) -> Path:
        """Write ``folder/run.json``."""
        return write_json(Path(folder) / MANIFEST, self.to_json(), indent=1, ensure_ascii=False)


#: The manifest of a run, in its results folder.
MANIFEST = "run.json"


def interrupted_runs(folder: str | os.PathLike, held: bool = False) -> list[dict]:
    """The runs that stopped before their results were put in place.

    Returns
    -------
    list of dict
        Per staging folder left by a run no longer running: ``staging`` (its name) and the
        ``run.json`` it holds (``manifest``, a :class:`RunManifest`, None if none). Empty
        while another process holds the lock (its staging folder is in use); ``held``: this
        process holds it.
    """
    folder = Path(folder)
    if not folder.is_dir() or (not held and in_use(folder)):
        return []
    out = []
    for p in sorted(folder.glob(f"{STAGING}*")):
        try:
            manifest = _read_json(p / MANIFEST)
        except UnreadableFile:
            manifest = None
        out.append({"staging": p.name, "manifest": RunManifest.from_json(manifest)})
    return out


# ---- the outputs of a per-stage command ------------------------------------------------------
def results_root(out: str | os.PathLike) -> Path:
    """The folder whose lock and stamp govern what a command writes into ``out``.

    ``out`` itself, unless ``out`` lies inside a folder whose stamp records files in the
    same sub-folder (a stage folder of a finished run, e.g. ``R/optimise`` or
    ``R/optimise/x``), or inside a folder that
    a running process is writing and that process writes where ``out`` is (a stage folder of
    a run in progress); then that folder.
    """
    given = Path(out)
    out = Path(os.path.abspath(out))
    root = next((parent for parent in out.parents
                 if _governs(parent, out.relative_to(parent).as_posix())), None)
    if root is None:
        return given
    # the folder as the user would name it: the given path less the levels below the root
    below = len(out.relative_to(root).parts)
    if ".." in given.parts or len(given.parts) < below:
        return root
    return Path(*given.parts[:len(given.parts) - below]) if len(given.parts) > below else Path()


def _governs(parent: Path, rel: str) -> bool:
    """True if the stamp of ``parent`` records files in the folder of ``parent`` that holds
    ``rel``, or a process writing ``parent`` writes there."""
    top = rel.split("/", 1)[0]
    if os.path.lexists(parent / OWNED) and any(f.startswith(top + "/") for f in _stamp(parent)):
        return True
    if os.path.lexists(parent / LOCK) and in_use(parent):
        info = _lock_info(parent / LOCK)
        return info is not None and rel.split("/", 1)[0] in info.writes
    return False


class CommandOutputs:
    """Where a per-stage command writes (:func:`command_outputs`).

    Attributes
    ----------
    folder : Path
        The folder the command writes into: inside the staging folder.
    out : Path
        The folder the outputs are put in (the command's ``--out``).
    root : Path
        The folder whose lock and stamp govern ``out`` (:func:`results_root`).
    """

    def __init__(self, out: Path, root: Path, stage: Path, command: str):
        self.out, self.root, self.stage, self.command = out, root, stage, command
        self.folder = stage / Path(os.path.abspath(out)).relative_to(os.path.abspath(root))
        self.placed = False

    def final(self, path: str | os.PathLike) -> Path:
        """The place of a file written into :attr:`folder` once the outputs are in place."""
        return self.out / Path(path).relative_to(self.folder)

    def place(self) -> list[Path]:
        """Put the outputs written so far in place and record them (done at the end of the
        ``with`` block if not called before); return them, as :meth:`final` names them.

        Raises
        ------
        NotMagtactsFile
            If a file in the way is not one magtact wrote there, or is a run's; nothing is put
            in place then, and the outputs stay complete in a folder the message names.
        """
        if self.placed:
            return []
        self.placed = True
        files = sorted(p.relative_to(self.stage).as_posix() for p in _files(self.stage))
        try:
            check_placeable(self.root, files)
        except NotMagtactsFile as exc:
            kept = self.root / f"{REFUSED}{self.stage.name[len(WRITING):][:12]}"
            _replace(self.stage, kept)
            raise NotMagtactsFile(f"{exc}. This command's outputs are in {kept}") from None
        journal = {"kind": "place", "staging": self.stage.name, "command": self.command,
                   "files": {f: sha256(self.stage / f) for f in files}}
        write_json(self.root / JOURNAL, journal, indent=1)
        with _signals_held():
            _place_forward(self.root, journal)
        return [self.final(self.stage / f) for f in files]


@contextlib.contextmanager
def command_outputs(out: str | os.PathLike, command: str,
                    expect: Iterable[str] = ()) -> Iterator[CommandOutputs]:
    """The outputs of a per-stage command: nothing of the user's replaced, no two writers mixed.

    On entry: the lock of the folder (:func:`results_root` of ``out``; a run or another
    command writing it makes this refuse, naming the process), a swap or placing that a killed
    process left half done is finished, and the files ``expect`` (names in ``out`` the command
    will write) are checked (:func:`check_placeable`), so that the common refusals come before
    the work. The command writes into ``.folder`` (a staging folder); on normal exit every file
    written is checked again and put in place (journalled: a kill completes it at the next
    command, run or report on the folder), and recorded in the stamp with ``command``. On an
    exception the staging folder is removed and the outputs in ``out`` stay as they were.

    Parameters
    ----------
    out : path
        The command's output folder (must exist).
    command : str
        The command line, recorded with each file and in the lock.
    expect : iterable of str
        Names (relative to ``out``) of the files the command always writes.

    Raises
    ------
    FolderInUse
        If another process holds the lock.
    NotMagtactsFile
        If a file in the way is not magtact's to replace (see :func:`check_placeable`).
    """
    out = Path(out)
    root = results_root(out)
    rel = Path(os.path.abspath(out)).relative_to(os.path.abspath(root))
    expect = [(rel / e).as_posix() for e in expect]
    writes = {rel.parts[0]} if rel.parts else {e.split("/", 1)[0] for e in expect}
    with RunLock(root, command, writes=writes):
        recover(root)
        for p in root.iterdir():  # staging folders of commands that were killed
            if p.name.startswith(WRITING):
                _remove(p)
        check_placeable(root, expect)
        stage = root / f"{WRITING}{uuid.uuid4().hex}"
        stage.mkdir()
        outputs = CommandOutputs(out, root, stage, command)
        outputs.folder.mkdir(parents=True, exist_ok=True)
        try:
            yield outputs
        except BaseException:
            _remove(stage)
            raise
        outputs.place()


def check_placeable(root: str | os.PathLike, files: Iterable[str]) -> None:
    """Refuse if a command's file ``root/<file>`` would replace what is not its to replace.

    A file may be replaced only if the stamp of ``root`` records it, with the same content
    (a file the user edited after magtact wrote it is the user's), as written by a per-stage
    command. A run's results are not changed by a command: neither its files nor what its
    stage folders hold. A folder on the way that is a symbolic link or not a folder is
    refused too.

    Raises
    ------
    NotMagtactsFile
        Naming every such file and what to do.
    """
    root = Path(root)
    doc = _stamp_doc(root)
    owned, commands = doc.files, doc.commands
    run_folders = {k.split("/", 1)[0] for k in owned if "/" in k and k not in commands}
    bad, runs = [], []
    for rel in files:
        parts = Path(rel).parts
        if len(parts) > 1 and parts[0] in run_folders:  # a run's stage folder: the run's alone
            runs.append(root / parts[0])
            continue
        for k in range(1, len(parts)):
            parent = root.joinpath(*parts[:k])
            if os.path.lexists(parent) and (parent.is_symlink() or not parent.is_dir()):
                bad.append(parent)
                break
        else:
            path = root / rel
            if not os.path.lexists(path):
                continue
            if path.is_symlink() or not path.is_file() or owned.get(rel) != sha256(path):
                bad.append(path)
            elif rel not in commands:
                runs.append(path)
    msgs = []
    if bad:
        bad = list(dict.fromkeys(bad))
        one = len(bad) == 1
        msgs.append(f"{', '.join(map(str, bad))} {'is' if one else 'are'} not magtact's (not "
                    f"written by magtact into {root}, or changed since) and would be replaced by "
                    f"this command's output. Move {'it' if one else 'them'} away, or give "
                    "another --out")
    if runs:
        runs = list(dict.fromkeys(runs))
        one = len(runs) == 1
        msgs.append(f"{', '.join(map(str, runs))} {'belongs' if one else 'belong'} to the "
                    f"results of the magtact run in {root}, which a command does not change. "
                    "Give another --out, or rerun magtact run")
    if msgs:
        raise NotMagtactsFile("; ".join(msgs))


def _place_forward(root: Path, journal: dict) -> None:
    """Carry out (or finish) the placing a journal describes; idempotent."""
    stage = root / journal["staging"]
    for rel in journal["files"]:
        src = stage / rel
        if os.path.lexists(src):
            (root / rel).parent.mkdir(parents=True, exist_ok=True)
            _replace(src, root / rel)
    doc = _stamp_doc(root)
    doc.files.update(journal["files"])
    doc.commands.update(dict.fromkeys(journal["files"], journal["command"]))
    _write_stamp_doc(root, doc)
    (root / JOURNAL).unlink(missing_ok=True)
    _remove(stage)


def _recover_place(root: Path, journal: dict) -> bool:
    files = journal.get("files")
    ok = (isinstance(journal.get("staging"), str) and isinstance(journal.get("command"), str)
          and isinstance(files, dict) and _plain_names([journal["staging"]])
          and journal["staging"].startswith(WRITING)
          and all(isinstance(v, str) and _plain_relative(k) for k, v in files.items()))
    if not ok:
        raise MagtactError(f"{root / JOURNAL}: not a journal magtact can finish; remove it "
                           f"(and any {WRITING}* folder) by hand")
    _place_forward(root, journal)
    return True


def _plain_relative(rel: str) -> bool:
    return (isinstance(rel, str) and not rel.startswith("/") and "\\" not in rel
            and _plain_names(rel.split("/")))
