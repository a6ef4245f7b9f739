"""How a command ends: the one error policy of the command line (README.md, 'Command line').

- A user error (:class:`~catenary_env.errors.CatenaryError`: a bad file, field, option value, path, run store
  or policy file) is one line on stderr, ``catenary COMMAND: error: ...``, naming the culprit and what to do;
  exit status 2 (:data:`EXIT_USAGE`, argparse's own for a bad option). ``catenary --debug`` shows its
  traceback instead.
- Any other exception is a bug of catenary-env: its traceback, then one line asking to report it; exit
  status 70 (:data:`EXIT_BUG`).
- Ctrl-C and SIGTERM (:class:`Terminated`) unwind the command, so that worker pools and stores are closed, and
  it says how it ended: exit status 130 or 143.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import signal
import sys
import traceback
from collections.abc import Callable
from types import FrameType

from ..errors import CatenaryError

__all__ = [
    "EXIT_BUG",
    "EXIT_USAGE",
    "Terminated",
    "interruption",
    "one_line",
    "print_error",
    "raise_on_sigterm",
    "report_bug",
    "run_command",
]

EXIT_USAGE = 2
"""Exit status of a command refused for its input (argparse's own status for a bad option)."""

EXIT_BUG = 70
"""Exit status of a command ended by a bug (``EX_SOFTWARE`` of sysexits.h)."""

REPORT_LINE = (
    "this is a bug in catenary-env, not a problem with your input: please report it on the project's issue "
    "tracker, with the command and the traceback above"
)
"""The line after the traceback of an internal error."""


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
    """The message of an error on one line."""
    return " ".join((str(error) or type(error).__name__).split())


def print_error(command: str, error: CatenaryError) -> int:
    """Print ``COMMAND: error: ...`` on one line (``command``: as typed, e.g. ``"catenary simulate"``);
    return :data:`EXIT_USAGE`."""
    print(f"{command}: error: {one_line(error)}", file=sys.stderr)
    return EXIT_USAGE


def report_bug(command: str, error: BaseException) -> int:
    """Print the traceback of ``error`` and the line asking to report it; return :data:`EXIT_BUG`."""
    traceback.print_exception(error, file=sys.stderr)
    print(f"{command}: {REPORT_LINE}", file=sys.stderr)
    return EXIT_BUG


def run_command(
    command: str,
    handler: Callable[[argparse.Namespace], int],
    args: argparse.Namespace,
    interrupted_note: str = "",
) -> int:
    """Run a command's handler under the error policy; its exit status.

    A :class:`~catenary_env.errors.CatenaryError` ends in one line and :data:`EXIT_USAGE`; Ctrl-C or SIGTERM
    say how the command ended (130 or 143), followed by ``interrupted_note``; any other exception is a bug:
    its traceback and the line asking to report it, :data:`EXIT_BUG`. With ``args.debug`` an error is raised
    as it is, for a debugger. ``command`` is the command as typed (``"catenary simulate"``), for the messages.
    """
    try:
        return handler(args)
    except BrokenPipeError:  # the reader went away (``catenary ... | head``): nothing left to say
        _silence_stdout()
        return 0
    except CatenaryError as error:
        if getattr(args, "debug", False):
            raise
        return print_error(command, error)
    except KeyboardInterrupt as error:
        how, status = interruption(error)
        print(f"\n{command}: {how}{interrupted_note}", file=sys.stderr)
        return status
    except Exception as error:  # a bug: nothing the user can correct
        if getattr(args, "debug", False):
            raise
        return report_bug(command, error)


def _silence_stdout() -> None:
    """Point stdout at the null device, so that the interpreter's final flush finds no closed pipe."""
    with contextlib.suppress(OSError, ValueError):
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
