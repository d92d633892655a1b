"""Reading the files a user hands in, and writing result files.

A user's file is read by :func:`read_bytes_capped` (or :func:`read_text_capped`,
:func:`read_json_capped` on top of it): a regular file only, at most a stated number of bytes,
every failure one :class:`UnreadableFile` with the reason.

Result files appear whole or not at all.
A file is written to a temporary sibling and renamed over the target (``os.replace`` is atomic
on one file system), so an interrupted run never leaves a half-written table, JSON or data set
that a later run or reader would take for a finished one.
"""

from __future__ import annotations

import csv
import errno
import io
import json
import os
import secrets
import stat
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def atomic_path(path: str | os.PathLike, fsync: bool = False) -> Iterator[Path]:
    """A temporary sibling of ``path`` to write; it replaces ``path`` when the block succeeds.

    On any exception the temporary file is removed and ``path`` is left as it was. With
    ``fsync`` the data reach the disk before the rename (for caches that must survive a crash
    of the machine, not only of the process).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = _new_file(path)
    try:
        yield Path(tmp)
        if fsync:
            with open(tmp, "rb") as fh:
                os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _new_file(path: Path) -> str:
    """Create an empty, unique temporary sibling of ``path`` and return its name.

    Unlike :func:`tempfile.mkstemp` (always mode 0600), the file is created with mode 0666 less
    the process's umask, as :func:`open` would create ``path`` itself, so that the renamed file
    has the permissions the user's umask asks for.
    """
    while True:
        tmp = path.parent / f".{path.name}.{secrets.token_hex(6)}.tmp"
        try:
            os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
        except FileExistsError:
            continue
        return str(tmp)


def write_bytes(path: str | os.PathLike, data: bytes, fsync: bool = False) -> Path:
    """Write ``data`` to ``path`` atomically; return the path."""
    with atomic_path(path, fsync=fsync) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def write_text(path: str | os.PathLike, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; return the path."""
    return write_bytes(path, text.encode("utf-8"))


def write_json(path: str | os.PathLike, data, **dumps) -> Path:
    """Write ``data`` as JSON (``json.dumps`` keywords, e.g. ``indent``) atomically."""
    return write_text(path, json.dumps(data, **dumps) + "\n")


def write_csv(path: str | os.PathLike, header: Sequence[str], rows: Iterable[Sequence],
              cell: Callable[[object], object] | None = None) -> Path:
    """Write a header and rows as CSV atomically; ``cell`` formats each value (default: str)."""
    buf = io.StringIO(newline="")
    w = csv.writer(buf)
    w.writerow(header)
    for row in rows:
        w.writerow(row if cell is None else [cell(v) for v in row])
    return write_text(path, buf.getvalue())


def significant(digits: int) -> Callable[[object], object]:
    """A ``cell`` formatter for :func:`write_csv`: floats to ``digits`` significant digits."""
    import numpy as np

    def cell(v):
        return f"{v:.{digits}g}" if isinstance(v, float | np.floating) else v
    return cell


def file_problem(path: str | os.PathLike, want: str = "file") -> str | None:
    """What ``path`` is when it is not a ``want`` (``"file"`` or ``"folder"``); None if it is one.

    ``"not found"``, or a phrase that reads after "it is": a broken symbolic link, a symbolic
    link loop, a folder, a file, a FIFO, a socket, a device, or unreadable with the system's
    reason (e.g. permission denied).
    """
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return ("a broken symbolic link (its target does not exist)" if os.path.islink(path)
                else "not found")
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return "a symbolic link loop (the link points, through links, back to itself)"
        return f"unreadable ({exc.strerror or exc})"
    if stat.S_ISDIR(mode):
        return None if want == "folder" else "a folder"
    if stat.S_ISREG(mode):
        return None if want == "file" else "a file"
    return ("a FIFO (named pipe)" if stat.S_ISFIFO(mode) else "a socket" if stat.S_ISSOCK(mode)
            else "a device" if stat.S_ISCHR(mode) or stat.S_ISBLK(mode)
            else "a special file")


class UnreadableFile(Exception):
    """A file :func:`read_text_capped` refuses; ``str(exc)`` is the reason, without the path
    (the caller names the file in its own error)."""


def read_bytes_capped(path: str | os.PathLike, max_bytes: int) -> bytes:
    """The bytes of the regular file ``path``, at most ``max_bytes`` of them.

    The file is opened without blocking (a FIFO never holds the reader) and checked on the open
    descriptor, so a path swapped between the check and the read still reads a regular file,
    and at most ``max_bytes + 1`` bytes are read whatever the file claims (a file growing while
    read, or a device reporting size 0).

    Raises
    ------
    UnreadableFile
        If ``path`` is not a regular file, is larger than ``max_bytes`` or cannot be read.
    """
    path = Path(path)
    problem = file_problem(path)
    if problem is not None:
        raise UnreadableFile("not found" if problem == "not found" else f"is {problem}")
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0)
                     | getattr(os, "O_NOCTTY", 0))
    except OSError as exc:
        raise UnreadableFile(f"cannot be read: {exc.strerror or exc}") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise UnreadableFile("is not a regular file (it changed while it was opened)")
        if st.st_size > max_bytes:
            raise UnreadableFile(f"has {st.st_size:,} bytes; at most {max_bytes:,} are read")
        chunks, total = [], 0
        while total <= max_bytes:
            chunk = os.read(fd, min(1 << 20, max_bytes + 1 - total))
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
        if total > max_bytes:
            raise UnreadableFile(f"has more than {max_bytes:,} bytes; at most {max_bytes:,} "
                                 "are read")
        return b"".join(chunks)
    except OSError as exc:
        raise UnreadableFile(f"cannot be read: {exc.strerror or exc}") from None
    finally:
        os.close(fd)


def read_text_capped(path: str | os.PathLike, max_bytes: int) -> str:
    """The text of the file ``path``: UTF-8 with or without a byte-order mark, at most
    ``max_bytes`` bytes (read by :func:`read_bytes_capped`).

    Raises
    ------
    UnreadableFile
        If ``path`` is not a regular file, is larger than ``max_bytes``, cannot be read, or is
        not UTF-8 text (the message gives the first offending byte and its offset).
    """
    data = read_bytes_capped(path, max_bytes)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise UnreadableFile(f"is not UTF-8 text (byte {data[exc.start]:#04x} at offset "
                             f"{exc.start}); save it as UTF-8") from None


#: Deepest nesting of arrays and objects in a JSON file magtact reads (its own files nest a
#: few levels; a forged one of thousands would exhaust the parser's recursion).
MAX_JSON_DEPTH = 64

#: Largest file of each kind that magtact reads back, its own outputs included [bytes]: JSON
#: records and summaries, figures (PNG, embedded in the report), text (TXT, TEX, a stage's
#: stamp), notes (Markdown, rendered: ten times the metamodels' notes of 12 kB; the renderer's
#: time grows faster than the text's length on nested brackets), tables (CSV) and the study
#: file of a results folder.
MAX_BYTES = {"json": 8 << 20, "figure": 8 << 20, "text": 1 << 20, "notes": 128 << 10,
             "table": 8 << 20, "stamp": 4096, "toml": 1 << 20}


def json_depth(doc) -> int:
    """The nesting depth of a parsed JSON document (a number or a string: 0), counted without
    recursion."""
    depth, stack = 0, [(doc, 1)]
    while stack:
        node, level = stack.pop()
        if isinstance(node, dict):
            node = list(node.values())
        elif not isinstance(node, list):
            continue
        depth = max(depth, level)
        stack.extend((child, level + 1) for child in node if isinstance(child, (dict, list)))
    return depth


def read_json_capped(path: str | os.PathLike, max_bytes: int,
                     max_depth: int = MAX_JSON_DEPTH):
    """The JSON document of the file ``path`` (read by :func:`read_text_capped`); constants
    such as ``NaN`` and ``Infinity``, which are not JSON, are refused, and so is nesting deeper
    than ``max_depth``.

    Raises
    ------
    UnreadableFile
        If the file is unreadable (as :func:`read_text_capped`), is not JSON (the message
        gives the line and column) or nests too deeply.
    """
    text = read_text_capped(path, max_bytes)

    def constant(name):
        raise ValueError(f"{name} is not a JSON number")

    try:
        doc = json.loads(text, parse_constant=constant)
    except json.JSONDecodeError as exc:
        raise UnreadableFile(f"is not JSON: {exc.msg} at line {exc.lineno}, column "
                             f"{exc.colno}") from None
    except RecursionError:
        raise UnreadableFile(f"nests arrays or objects more than {max_depth} deep") from None
    except ValueError as exc:
        raise UnreadableFile(f"is not JSON: {exc}") from None
    if json_depth(doc) > max_depth:
        raise UnreadableFile(f"nests arrays or objects more than {max_depth} deep")
    return doc


def read_result(path: str | os.PathLike, kind: str):
    """A file magtact reads back (its own outputs included) through :func:`read_bytes_capped`,
    capped at :data:`MAX_BYTES` of ``kind``: ``"json"`` → the document (at most
    :data:`MAX_JSON_DEPTH` deep), ``"figure"`` → bytes, ``"text"``, ``"notes"``, ``"stamp"``,
    ``"table"``, ``"toml"`` → text (UTF-8).

    Raises
    ------
    UnreadableFile
        With the reason (not found, not a regular file, too large, not UTF-8, not JSON).
    """
    cap = MAX_BYTES[kind]
    if kind == "json":
        return read_json_capped(path, cap)
    if kind == "figure":
        return read_bytes_capped(path, cap)
    return read_text_capped(path, cap)


# ---- a result file read back: each value of the type its writer gives it, else nothing ----
def json_number(value) -> float | None:
    """``value`` as a float if it is a JSON number (not a boolean), else None."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value)
    return None


def json_text(value, default: str = "") -> str:
    """``value`` as text: a JSON string as is, None as ``default``, anything else as
    ``str(value)`` (a forged file's number where words belong is shown, not refused)."""
    return default if value is None else value if isinstance(value, str) else str(value)


def json_dict(value) -> dict:
    """``value`` if it is a JSON object, else an empty one."""
    return value if isinstance(value, dict) else {}


def json_list(value) -> list:
    """``value`` if it is a JSON array, else an empty one."""
    return value if isinstance(value, list) else []
