"""A one-line progress display of an optimisation run on stderr: simulations spent and best σ so far.

Silent when quiet or when stderr is not a terminal (a log file or a pipe gets nothing).
"""

from __future__ import annotations

import sys
import time
from typing import TextIO

__all__ = ["ProgressDisplay"]


class ProgressDisplay:
    """Show ``label [#####.....] spent/budget simulations, best σ`` on one refreshed line.

    Parameters
    ----------
    label : str
        What runs, e.g. ``"ga on B1"``.
    budget : int
        Simulations allowed.
    quiet : bool
        Show nothing.
    stream : file, optional
        Where to write (default: stderr); shown only if it is a terminal.
    """

    def __init__(self, label: str, budget: int, quiet: bool = False, stream: TextIO | None = None) -> None:
        self.stream = sys.stderr if stream is None else stream
        self.enabled = not quiet and self.stream.isatty()
        self.label = label
        self.budget = budget
        self.start = time.perf_counter()
        self._last_write = 0.0

    def update(
        self, n_simulations: int, n_evaluations: int, best_sigma: float | None, force: bool = False
    ) -> None:
        """Refresh the line (at most 10 times a second unless ``force``)."""
        if not self.enabled:
            return
        now = time.perf_counter()
        if not force and now - self._last_write < 0.1:
            return
        self._last_write = now
        width = 30
        filled = int(round(width * min(1.0, n_simulations / self.budget)))
        best = "none feasible yet" if best_sigma is None else f"best sigma {best_sigma:.3f} N"
        self.stream.write(
            f"\r{self.label} [{'#' * filled}{'.' * (width - filled)}] {n_simulations}/{self.budget} "
            f"simulations ({n_evaluations} evaluations), {best}, {now - self.start:.1f} s "
        )
        self.stream.flush()

    def finish(self, message: str) -> None:
        """End the line with a message."""
        if self.enabled:
            self.stream.write(f"\n{self.label}: {message}\n")
            self.stream.flush()
