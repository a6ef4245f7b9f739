"""The one progress display of every long command (a passage, a validation, an optimisation run).

On a terminal, one line refreshed as the work goes; elsewhere (a log file, ``nohup``, a pipe), a plain line
every ``interval`` seconds (and the forced ones, e.g. at the end of a run), so that a logged command shows it
is alive. ``quiet`` silences both; notes (e.g. that a run is resumed) are shown unless quiet.
"""

from __future__ import annotations

import sys
import time
from typing import TextIO

__all__ = ["LOG_INTERVAL", "ProgressDisplay"]

LOG_INTERVAL = 30.0
"""Seconds between two progress lines when stderr is not a terminal."""

TERMINAL_INTERVAL = 0.1
"""Seconds between two refreshes of the terminal line."""

BAR_WIDTH = 30


class ProgressDisplay:
    """Show ``label [#####.....] done/total unit, detail`` as the work goes.

    Parameters
    ----------
    label : str
        What runs, e.g. ``"ga on B1"`` or ``"simulate"``.
    total : float
        The work to do, in ``unit``.
    unit : str
        What is counted, e.g. ``"simulations"``; ``"%"`` shows the fraction of ``total`` done in per cent (a
        passage's progress, reported as a fraction of 1).
    quiet : bool
        Show nothing.
    stream : file, optional
        Where to write (default: stderr): a refreshed line if it is a terminal, else plain lines.
    interval : float
        Seconds between two plain lines when the stream is not a terminal (default :data:`LOG_INTERVAL`).

    Examples
    --------
    >>> import io
    >>> log = io.StringIO()
    >>> display = ProgressDisplay("ga on B1", 200, "simulations", stream=log, interval=0.0)
    >>> display.update(40, "52 evaluations")
    >>> log.getvalue().split(", 0.")[0]
    'ga on B1: 40/200 simulations, 52 evaluations'
    """

    def __init__(
        self,
        label: str,
        total: float,
        unit: str = "%",
        quiet: bool = False,
        stream: TextIO | None = None,
        interval: float = LOG_INTERVAL,
    ) -> None:
        self.stream = sys.stderr if stream is None else stream
        self.quiet = quiet
        self.terminal = self.stream.isatty()
        self.label = label
        self.total = total
        self.unit = unit
        self.interval = interval
        self.start = time.perf_counter()
        self._last_write = self.start if not self.terminal else 0.0
        self._line_open = False

    def update(self, done: float, detail: str = "", force: bool = False) -> None:
        """Show ``done`` (in the display's unit) and a ``detail``: on a terminal at most 10 times a second,
        else every ``interval`` seconds (or when ``force``)."""
        if self.quiet:
            return
        now = time.perf_counter()
        if not force and now - self._last_write < (TERMINAL_INTERVAL if self.terminal else self.interval):
            return
        self._last_write = now
        elapsed = now - self.start
        fraction = min(1.0, done / self.total) if self.total > 0 else 1.0
        counts = (
            f"{100.0 * fraction:5.1f} %"
            if self.unit == "%"
            else f"{_count(done)}/{_count(self.total)} {self.unit}"
        )
        counts += f", {detail}" if detail else ""
        if self.terminal:
            filled = int(round(BAR_WIDTH * fraction))
            bar = "#" * filled + "." * (BAR_WIDTH - filled)
            self.stream.write(f"\r{self.label} [{bar}] {counts}, {elapsed:.1f} s ")
            self._line_open = True
        else:
            rate = (
                "" if self.unit == "%" else f", {done / elapsed if elapsed > 0.0 else 0.0:.2f} {self.unit}/s"
            )
            self.stream.write(f"{self.label}: {counts}, {elapsed:.1f} s elapsed{rate}\n")
        self.stream.flush()

    def fraction(self, fraction: float) -> None:
        """Show the fraction of the work done (the progress callback of a passage, 0 to 1)."""
        self.update(fraction * self.total)

    def note(self, message: str) -> None:
        """Show a message on a line of its own (unless quiet)."""
        if self.quiet:
            return
        self.stream.write(f"{chr(10) if self._line_open else ''}{self.label}: {message}\n")
        self._line_open = False
        self.stream.flush()

    def finish(self, message: str = "") -> None:
        """End the display: close the terminal line, with a message if one is given."""
        if message:
            self.note(message)
        elif self._line_open and not self.quiet:
            self.stream.write("\n")
            self._line_open = False
            self.stream.flush()


def _count(value: float) -> str:
    """A count as written: a whole number without a decimal point."""
    return f"{value:.0f}" if float(value).is_integer() else f"{value:g}"
