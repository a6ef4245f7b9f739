"""Paths the user names on the command line: an output file is checked before any computation."""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import UsageError

__all__ = ["check_output_folder", "check_output_path"]


def check_output_path(path: str | os.PathLike[str], option: str) -> None:
    """Refuse an output file that cannot be written, before any computation.

    Parameters
    ----------
    path : str or path-like
        The file to be written.
    option : str
        The option that named it (for the message), e.g. ``"--plot"``.

    Raises
    ------
    UsageError
        Its folder is missing or not writable, or the path is a folder.
    """
    target = Path(path)
    folder = target.parent if str(target.parent) else Path(".")
    if target.is_dir():
        raise UsageError(f"{option} {path}: is a folder; give a file name")
    if not folder.is_dir():
        raise UsageError(
            f"{option} {path}: the folder {folder} does not exist; create it or give another path"
        )
    if not os.access(folder, os.W_OK):
        raise UsageError(f"{option} {path}: the folder {folder} is not writable; give another path")
    if target.exists() and not os.access(target, os.W_OK):
        raise UsageError(f"{option} {path}: the file is not writable; give another path")


def check_output_folder(path: str | os.PathLike[str], option: str) -> None:
    """Refuse an output folder that cannot be made or written, before any computation.

    Parameters
    ----------
    path : str or path-like
        The folder to be written into (made if absent, with its parents).
    option : str
        The option that named it (for the message), e.g. ``"--out"``.

    Raises
    ------
    UsageError
        The path is a file, or the folder (or its nearest existing parent, where it is to be made) is not
        writable.
    """
    target = Path(path)
    existing = next((p for p in (target, *target.parents) if p.exists()), Path("."))
    if not existing.is_dir():
        raise UsageError(f"{option} {path}: {existing} is a file, not a folder; give another path")
    if not os.access(existing, os.W_OK):
        raise UsageError(f"{option} {path}: the folder {existing} is not writable; give another path")
