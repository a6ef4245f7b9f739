"""The project's own errors: what a user can get wrong (README.md, 'Command line').

Every failure a user can cause and correct (a catenary or pantograph file, a design, an option value, an
input or output path, a run store, a policy file) raises a subclass of :class:`CatenaryError`, whose message
names the culprit and what to do. The command line prints such an error on one line and exits with status
2; any other exception is a bug in catenary-env and keeps its traceback (``catenary_env/cli/``).

A library user can catch :class:`CatenaryError` for all of them. The subclasses that replace a
``ValueError`` (a definition, a design, a usage error) are also ``ValueError``, so that code written
against the older types keeps working.
"""

from __future__ import annotations

__all__ = ["CatenaryError", "MissingDependency", "UnknownNameError", "UsageError", "UserFileError"]


class CatenaryError(Exception):
    """A failure the user caused and can correct; the message names the culprit and the allowed values."""


class UsageError(CatenaryError, ValueError):
    """A value the user can correct: an option, a combination of options, an argument of a function."""


class UserFileError(CatenaryError, OSError):
    """A file or folder the user named cannot be read or written (missing, a folder, no permission).

    Raised where the file is opened, from the ``OSError`` there, so that a missing input is a user error
    while an ``OSError`` of the program's own files stays a bug.
    """

    @classmethod
    def from_os_error(cls, error: OSError, what: str = "") -> UserFileError:
        """The user error for ``error``, naming its file (and ``what`` it is, e.g. ``"--store"``)."""
        filename = error.filename if error.filename is not None else ""
        reason = error.strerror or str(error) or type(error).__name__
        prefix = " ".join(part for part in (what, str(filename)) if part)
        return cls(f"{prefix}: {reason}" if prefix else reason)


class MissingDependency(CatenaryError, ImportError):
    """An optional package that a feature needs is not installed; the message gives the install command."""


class UnknownNameError(CatenaryError, KeyError):
    """A name that is not in a table (a design problem, an optimiser); the message lists the names there."""

    def __str__(self) -> str:
        # KeyError's own str() would quote the message.
        return str(self.args[0]) if self.args else ""
