"""The exceptions of mbgc, one class per kind of the library's error (``mbgc::Error``).

Every message is the one the ``mbgc`` command prints for the same input: it names the file (or
the label of in-memory data such as ``DataFrame``), the field and what was expected. The kinds
that say a value is wrong also derive from :class:`ValueError`, a file that cannot be read or
written from :class:`OSError`, so code that already catches those keeps working.
"""

from __future__ import annotations

from typing import Optional

__all__ = [
    "MbgcError",
    "InputError",
    "OutOfDomainError",
    "InvalidRequestError",
    "NoSolutionError",
    "InfeasibleError",
    "FileError",
    "ExtrapolationWarning",
]


class MbgcError(Exception):
    """Base class of every mbgc error.

    ``file``, ``field`` and ``expected`` repeat the parts of the message that name the input,
    where the error has them (``None`` otherwise).
    """

    def __init__(
        self,
        message: str,
        file: Optional[str] = None,
        field: Optional[str] = None,
        expected: Optional[str] = None,
    ) -> None:
        super().__init__(message)
        self.file = file
        self.field = field
        self.expected = expected


class InputError(MbgcError, ValueError):
    """Bad content in a file or in data given in memory (a TOML key, a CSV or DataFrame column)."""


class OutOfDomainError(MbgcError, ValueError):
    """A value lies outside the domain the metamodel was fitted on, where it would extrapolate."""


class InvalidRequestError(MbgcError, ValueError):
    """A request that cannot be honoured: a bad option or combination of options."""


class NoSolutionError(MbgcError, RuntimeError):
    """No start of the optimiser converged: the equations are not finite in the search box."""


class InfeasibleError(MbgcError, RuntimeError):
    """The material's constraints cannot be met inside the search box."""


class FileError(MbgcError, OSError):
    """A file could not be read or written; ``errno`` is the operating system's error number."""


class ExtrapolationWarning(UserWarning):
    """Predictions at points outside the model's valid domain, or not finite there."""
