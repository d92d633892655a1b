"""The exceptions magtact raises for errors a user can fix.

:class:`MagtactError` marks a problem with what the user gave: a study that does not validate,
a data file that is missing or malformed, force constraints that no design meets. The command
line prints such an error as one line; any other exception is a fault of magtact (or of a
library it calls) and keeps its traceback. Both subclass :class:`ValueError`, so code that
catches ``ValueError`` keeps working.
"""

from __future__ import annotations


class MagtactError(ValueError):
    """An error in the user's input: a bad study, bad data, infeasible constraints."""


class MissingFileError(MagtactError, FileNotFoundError):
    """A file or folder the user named does not exist."""
