"""The progress of an optimisation run on stderr: simulations spent, evaluations, best σ, time and rate.

On a terminal, one line refreshed as the evaluations complete; elsewhere (a log file, ``nohup``, a
pipe), a plain line every ``interval`` seconds and one at the end, so that a logged run shows it is
alive. ``quiet`` silences both; notes (e.g. that a run is resumed) are shown unless quiet.
"""

from __future__ import annotations

import sys
import time
from typing import TextIO

__all__ = ["LOG_INTERVAL", "ProgressDisplay"]

LOG_INTERVAL = 30.0
"""Seconds between two progress lines when stderr is not a terminal."""


class ProgressDisplay:
    """Show ``label [#####.....] spent/budget simulations, best σ`` as the run goes.

    Parameters
    ----------
    label : str
        What runs, e.g. ``"ga on B1"``.
    budget : int
        Simulations allowed.
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
    >>> display = ProgressDisplay("ga on B1", 200, stream=log, interval=0.0)
    >>> display.update(40, 52, 21.5)
    >>> log.getvalue().split(", best")[0]
    'ga on B1: 40/200 simulations, 52 evaluations'
    """

    def __init__(
        self,
        label: str,
        budget: int,
        quiet: bool = False,
        stream: TextIO | None = None,
        interval: float = LOG_INTERVAL,
    ) -> None:
        self.stream = sys.stderr if stream is None else stream
        self.quiet = quiet
        self.terminal = self.stream.isatty()
        self.label = label
        self.budget = budget
        self.interval = interval
        self.start = time.perf_counter()
        self._last_write = self.start if not self.terminal else 0.0
        self._line_open = False

    def update(
        self, n_simulations: int, n_evaluations: int, best_sigma: float | None, force: bool = False
    ) -> None:
        """Show the state: on a terminal at most 10 times a second, else every ``interval`` (or ``force``)."""
        if self.quiet:
            return
        now = time.perf_counter()
        if not force and now - self._last_write < (0.1 if self.terminal else self.interval):
            return
        self._last_write = now
        elapsed = now - self.start
        best = "none feasible yet" if best_sigma is None else f"best sigma {best_sigma:.3f} N"
        counts = f"{n_simulations}/{self.budget} simulations, {n_evaluations} evaluations"
        if self.terminal:
            width = 30
            filled = int(round(width * min(1.0, n_simulations / self.budget)))
            self.stream.write(
                f"\r{self.label} [{'#' * filled}{'.' * (width - filled)}] {counts}, {best}, {elapsed:.1f} s "
            )
            self._line_open = True
        else:
            rate = n_simulations / elapsed if elapsed > 0.0 else 0.0
            self.stream.write(
                f"{self.label}: {counts}, {best}, {elapsed:.1f} s elapsed, {rate:.2f} simulations/s\n"
            )
        self.stream.flush()

    def note(self, message: str) -> None:
        """Show a message on a line of its own (unless quiet)."""
        if self.quiet:
            return
        self.stream.write(f"{chr(10) if self._line_open else ''}{self.label}: {message}\n")
        self._line_open = False
        self.stream.flush()

    def finish(self, message: str) -> None:
        """End the display with a message."""
        self.note(message)
