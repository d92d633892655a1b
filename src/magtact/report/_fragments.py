"""Pieces of HTML shared by the report's sections: escaping, an embedded figure, a JSON file
read without failing."""

from __future__ import annotations

import base64
import html
import json
from pathlib import Path


def escape(x) -> str:
    """``str(x)`` HTML-escaped, quotes included."""
    return html.escape(str(x), quote=True)


def figure(path: Path, caption: str | None) -> str:
    """A PNG file as a ``<figure>`` with the image embedded (base64) and its caption."""
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    cap = caption or path.stem.replace("_", " ")
    return (f'<figure><img src="data:image/png;base64,{data}" alt="{escape(cap)}">'
            f"<figcaption>{escape(cap)} <small>({escape(path.name)})</small></figcaption>"
            "</figure>")


def load_json(path: Path):
    """The JSON content of ``path``, or None if it is missing or unreadable."""
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return None
