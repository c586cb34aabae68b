"""Exceptions raised by pgvol: one base class carrying the kind and the path, and one subclass
per kind, each also a subclass of the matching built-in exception."""

from __future__ import annotations

from typing import Optional


class PgvolError(Exception):
    """A failed pgvol call.

    Attributes:
        message: the problem, in a sentence, without the path.
        kind: one of "input file", "output file", "bad parameter", "resource limit",
            "empty result", "cancelled", "internal".
        path: the file the error concerns, or None.
    """

    def __init__(self, message: str, kind: str = "internal", path: Optional[str] = None):
        super().__init__(message)
        self.message = message
        self.kind = kind
        self.path = path

    def __str__(self) -> str:
        if self.path:
            return f"{self.path}: {self.message}"
        return self.message

    def __reduce__(self):
        return (type(self), (self.message, self.kind, self.path))


class InputFileError(PgvolError):
    """An input file is missing, unreadable, malformed or describes something unusable."""


class MissingFileError(InputFileError, FileNotFoundError):
    """An input file does not exist (also a FileNotFoundError)."""

    def __init__(self, message: str, kind: str = "input file", path: Optional[str] = None):
        super().__init__(message, kind, path)
        self.filename = path


class OutputFileError(PgvolError):
    """An output file cannot be written, or its name asks for a format that does not exist."""


class ParameterError(PgvolError, ValueError):
    """A parameter is out of range, of the wrong type or shape, or contradicts another
    (also a ValueError)."""


class EmptyResultError(PgvolError, ValueError):
    """The result would be empty: nothing inside, or inside everywhere with no surface
    (also a ValueError)."""


class ResourceLimitError(PgvolError, MemoryError):
    """The job would exceed a size limit: grid nodes or memory (also a MemoryError)."""


class CancelledError(PgvolError):
    """The call was asked to stop."""


class InternalError(PgvolError, RuntimeError):
    """A stage failed on valid input: a defect in pgvol (also a RuntimeError)."""


class PgvolWarning(UserWarning):
    """Something to know about a result that is still produced (an open mesh hollowed, say)."""
