"""Pieces of HTML shared by the report's sections: escaping, an embedded figure, and the files of
a results folder read through the bounded reader.

Every file the report reads goes through :func:`magtact._files.read_result` (a regular file
only, at most the size of its kind, JSON at most :data:`magtact._files.MAX_JSON_DEPTH` deep).
A file that is present but damaged (too large, a FIFO or a device, a symbolic link loop, not
UTF-8, not JSON, of the wrong shape) is left out and noted: :func:`collecting` gathers the
notes, one line per file naming it and what is wrong, and the report shows them above its
sections, which render from the files that are whole.
"""

from __future__ import annotations

import base64
import html
import os
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path

from .._files import UnreadableFile, read_result

#: The notes of the report being built: (results folder, {file shown: what is wrong}).
_NOTES: ContextVar[tuple[Path, dict[str, str]] | None] = ContextVar("report_notes",
                                                                     default=None)


def escape(x) -> str:
    """``str(x)`` HTML-escaped, quotes included."""
    return html.escape(str(x), quote=True)


@contextmanager
def collecting(folder: Path) -> Iterator[dict[str, str]]:
    """Gather the damaged files of the report of ``folder`` while the block runs: a dict of
    the file (relative to ``folder`` where it lies inside) to what is wrong with it."""
    notes: dict[str, str] = {}
    token = _NOTES.set((Path(folder), notes))
    try:
        yield notes
    finally:
        _NOTES.reset(token)


def note(path: Path, problem: str) -> None:
    """Record that ``path`` is left out of the report because of ``problem``."""
    state = _NOTES.get()
    if state is None:
        return
    root, notes = state
    try:
        shown = Path(os.path.relpath(path, root)).as_posix()
    except ValueError:
        shown = str(path)
    shown = str(path) if shown.startswith("..") else shown
    notes.setdefault(shown, problem)


def read(path: Path, kind: str):
    """The content of ``path`` read as ``kind`` (:func:`magtact._files.read_result`), or None:
    silently where the file is missing, with a note where it is present and damaged."""
    try:
        return read_result(path, kind)
    except UnreadableFile as exc:
        if str(exc) != "not found":
            note(path, str(exc))
        return None


def load_json(path: Path, check: Callable[[object], str | None] | None = None):
    """The JSON content of ``path``, or None if it is missing or damaged (noted).

    ``check`` returns what is wrong with the document's shape (e.g. an array longer than the
    record that reads it allows), or None where it is whole; a document it refuses is noted
    and not returned.
    """
    data = read(path, "json")
    if data is not None and check is not None:
        problem = check(data)
        if problem is not None:
            note(path, problem)
            return None
    return data


def load_record(path: Path, record, what: str):
    """``record.from_json`` of the JSON file ``path`` (the type that writes it), or None; a
    file that is JSON but not such a record is noted as not being ``what``."""
    data = load_json(path)
    out = record.from_json(data)
    if data is not None and out is None:
        note(path, f"is not {what}")
    return out


def load_captions(path: Path) -> dict[str, str]:
    """``captions.json`` of a stage folder: file stem → caption (text only; empty where the
    file is missing or damaged)."""
    def check(data):
        if not isinstance(data, dict) or not all(isinstance(v, str) for v in data.values()):
            return "is not a table of captions (file name → text)"
        return None

    return load_json(path, check) or {}


def read_text(path: Path, kind: str = "text") -> str | None:
    """The text of ``path`` (notes, TXT, TEX, a stamp, a table, the study), or None (noted
    where it is present and damaged)."""
    return read(path, kind)


def figure(path: Path, caption: str | None) -> str:
    """A PNG file as a ``<figure>`` with the image embedded (base64) and its caption; nothing
    (noted) where the file is above the figure cap or is not a PNG."""
    data = read(path, "figure")
    if data is None:
        return ""
    if not data.startswith(b"\x89PNG\r\n\x1a\n"):
        note(path, "is not a PNG image")
        return ""
    encoded = base64.b64encode(data).decode("ascii")
    cap = caption or path.stem.replace("_", " ")
    return (f'<figure><img src="data:image/png;base64,{encoded}" alt="{escape(cap)}">'
            f"<figcaption>{escape(cap)} <small>({escape(path.name)})</small></figcaption>"
            "</figure>")


def damaged_section(notes: dict[str, str]) -> str:
    """The banner listing the damaged files (one line each), or nothing."""
    if not notes:
        return ""
    items = "".join(f"<li><code>{escape(k)}</code>: {escape(v)}</li>"
                    for k, v in sorted(notes.items()))
    return ('<div class="missing" id="damaged"><b>Files left out of this report</b> (the '
            "sections below are built from the other files):<ul>" + items + "</ul></div>")
