"""The command line's one error path: what a user can get wrong ends in one line and exit status 2.

Every ``catenary`` command (and the commands the packages above plug in) reports a failure the user can
cause (a bad file, field, option value, output path or run store) as one line on stderr naming the
culprit and what to do, and exits with status 2; ``catenary --debug ...`` shows the traceback instead.
Anything else is a bug and keeps its traceback. SIGTERM unwinds like Ctrl-C (:class:`Terminated`), so
that worker pools and stores are closed and the command says how it ended.
"""

from __future__ import annotations

import os
import signal
import sys
from pathlib import Path
from types import FrameType

__all__ = [
    "EXIT_USAGE",
    "Terminated",
    "UsageError",
    "check_output_path",
    "interruption",
    "one_line",
    "print_error",
    "raise_on_sigterm",
]

EXIT_USAGE = 2
"""Exit status of a command refused for its input (argparse's own status for a bad option)."""


class UsageError(ValueError):
    """A command-line value the user can correct: an option, an output path, a combination of options."""


class Terminated(KeyboardInterrupt):
    """SIGTERM arrived (a scheduler, ``timeout``, ``docker stop``): unwinds like Ctrl-C does."""


def _raise_terminated(signum: int, frame: FrameType | None) -> None:
    raise Terminated(signum)


def raise_on_sigterm() -> None:
    """Make SIGTERM raise :class:`Terminated` in the main thread (the default would kill at once, and
    leave the workers of a run and a half-written figure behind)."""
    signal.signal(signal.SIGTERM, _raise_terminated)


def interruption(error: KeyboardInterrupt) -> tuple[str, int]:
    """What ended a command (``"interrupted"`` or ``"terminated (SIGTERM)"``) and its exit status."""
    if isinstance(error, Terminated):
        return "terminated (SIGTERM)", 128 + signal.SIGTERM
    return "interrupted", 128 + signal.SIGINT


def one_line(error: BaseException) -> str:
    """The message of an error on one line (an OSError names its file)."""
    if isinstance(error, OSError) and error.filename is not None:
        message = f"{error.filename}: {error.strerror or error}"
    elif isinstance(error, KeyError) and error.args:
        message = str(error.args[0])
    else:
        message = str(error) or type(error).__name__
    return " ".join(message.split())


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


def print_error(command: str, error: BaseException) -> int:
    """Print ``catenary COMMAND: error: ...`` on one line; return :data:`EXIT_USAGE`."""
    print(f"catenary {command}: error: {one_line(error)}", file=sys.stderr)
    return EXIT_USAGE
