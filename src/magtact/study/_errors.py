"""The study's own error: an invalid setting, named by its key."""

from __future__ import annotations

from .._errors import MagtactError


class StudyError(MagtactError):
    """A study file is invalid. ``key`` names the offending TOML key (``section.key``)."""

    def __init__(self, key: str, message: str, source: str | None = None):
        self.key, self.reason = key, message
        where = f"{source}: " if source else ""
        super().__init__(one_line(f"{where}[{key}] {message}"))


def one_line(text: str) -> str:
    """``text`` with line breaks and other unprintable characters escaped (keys and values
    quoted from a file may hold any character)."""
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)
