"""The design grid: bounds, grid steps, snapping, actions in [-1, 1] and the cache key of a design.

Every search over designs happens on one grid (docs/problems.md, 'Design variables and grid'): heights on a 1
mm grid, dropper positions on a 1 cm grid, from the lower bound to the upper, both on the grid. The design
problems, the environments, the optimisers and the RL wrapper all map through this one module, so a design is
the same float wherever it was made.

Examples
--------
>>> grid = DesignGrid("demo", ("dh_1", "d_1"), [-0.02, 0.1], [0.02, 7.4], [0.001, 0.01])
>>> grid.n_levels.tolist()
[41, 731]
>>> grid.snap([0.0105, 9.0]).tolist()  # a tie rounds up; a value outside is clipped
[0.011, 7.4]
>>> grid.from_action([-1.0, 1.0]).tolist()
[-0.02, 7.4]
>>> grid.design_key([0.011, 7.4])
(11, 740)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["HEIGHT_STEP", "POSITION_STEP", "DesignGrid"]

HEIGHT_STEP = 0.001
"""Grid step of heights (pre-sag, Δh), m: 1 mm (docs/problems.md, 'Design variables and grid')."""

POSITION_STEP = 0.01
"""Grid step of dropper positions, m: 1 cm (docs/problems.md, 'Design variables and grid')."""

DECIMALS = 9
"""Grid values are rounded to this many decimals (1 nm) so that equal grid points are equal floats.

The grid points of every problem are the same floats rounded to 9 or to 12 decimals (they were rounded
to 9 by the problems and to 12 by the optimisers before this module owned the grid)."""

BOUND_TOLERANCE = 1e-9
"""m; a value this close to a bound counts as on it (floating-point noise, not a design change)."""

TIE_TOLERANCE = 1e-9
"""Grid steps; a value this close below a half step counts as the tie, which rounds up."""


@dataclass(frozen=True, eq=False)
class DesignGrid:
    """The grid ``x = lower + k * step``, ``0 <= k < n_levels``, of a problem's variables.

    Attributes
    ----------
    name : str
        Problem id, for messages.
    variable_names : tuple of str
        One name per variable.
    lower, upper : ndarray, shape (n_variables,)
        Bounds, physical units (m), on the grid. Read-only.
    step : ndarray, shape (n_variables,)
        Grid step of each variable. Read-only.
    """

    name: str
    variable_names: tuple[str, ...]
    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    step: NDArray[np.float64]

    def __post_init__(self) -> None:
        n = len(self.variable_names)
        object.__setattr__(self, "variable_names", tuple(self.variable_names))
        for field_name in ("lower", "upper", "step"):
            array = np.array(getattr(self, field_name), dtype=np.float64)
            if array.shape != (n,):
                raise ValueError(
                    f"problem {self.name!r}: {field_name} must have {n} values, one per variable"
                )
            array.setflags(write=False)  # frozen record: the bounds must not change under a user's feet
            object.__setattr__(self, field_name, array)
        if not (np.all(self.step > 0.0) and np.all(self.lower < self.upper)):
            raise ValueError(f"problem {self.name!r}: need step > 0 and lower < upper")
        for bound in (self.lower, self.upper):
            if not np.allclose(bound / self.step, np.round(bound / self.step), rtol=0.0, atol=1e-6):
                raise ValueError(f"problem {self.name!r}: bounds must lie on the grid")

    @property
    def n_variables(self) -> int:
        return len(self.variable_names)

    @property
    def n_levels(self) -> NDArray[np.int64]:
        """Grid points of each variable, bounds included."""
        return np.round((self.upper - self.lower) / self.step).astype(np.int64) + 1

    def check_vector(self, values: ArrayLike, what: str = "x") -> NDArray[np.float64]:
        """``values`` as one finite number per variable (a design ``x`` in m, or an env's action), or a
        ValueError naming ``what``, the problem and its variables.

        The one check of a design input: the problems' ``x`` and the environments' actions pass it.
        """
        names = ", ".join(self.variable_names)
        try:
            array = np.asarray(values, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(
                f"problem {self.name}: {what} must be {self.n_variables} numbers ({names}), got {values!r}"
            ) from None
        if array.shape != (self.n_variables,):
            raise ValueError(
                f"problem {self.name}: {what} must have shape ({self.n_variables},) ({names}), "
                f"got shape {array.shape}"
            )
        if not np.all(np.isfinite(array)):
            raise ValueError(f"problem {self.name}: {what} must be finite (no NaN or inf): {array.tolist()}")
        return array

    def to_index(self, x: ArrayLike) -> NDArray[np.int64]:
        """Integer grid coordinates of ``x``: clipped to the bounds, rounded to the nearest point.

        A value half-way between two points rounds up, towards the upper bound.
        """
        values = np.clip(np.asarray(x, dtype=np.float64), self.lower, self.upper)
        index = np.floor((values - self.lower) / self.step + 0.5 + TIE_TOLERANCE).astype(np.int64)
        return np.minimum(index, self.n_levels - 1)

    def from_index(self, k: ArrayLike) -> NDArray[np.float64]:
        """Variables of integer grid coordinates ``k`` (shape (..., n_variables)), unchecked."""
        x = self.lower + np.asarray(k, dtype=np.int64) * self.step
        return np.asarray(np.round(np.minimum(x, self.upper), DECIMALS), dtype=np.float64)

    def snap(self, x: ArrayLike) -> NDArray[np.float64]:
        """``x`` clipped to the bounds and rounded to the grid; equal grid points are equal floats."""
        return self.from_index(self.to_index(x))

    def out_of_bounds(self, x: ArrayLike) -> tuple[str, ...]:
        """Names of the variables of ``x`` outside the bounds (what :meth:`snap` would clip)."""
        values = np.asarray(x, dtype=np.float64)
        outside = (values < self.lower - BOUND_TOLERANCE) | (values > self.upper + BOUND_TOLERANCE)
        return tuple(name for name, out in zip(self.variable_names, outside, strict=True) if out)

    def from_action(self, action: ArrayLike) -> NDArray[np.float64]:
        """The design of an action in [-1, 1] (clipped): affine onto the bounds, then onto the grid."""
        a = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)
        return self.snap(self.lower + 0.5 * (a + 1.0) * (self.upper - self.lower))

    def to_action(self, x: ArrayLike) -> NDArray[np.float64]:
        """The action in [-1, 1] of variables ``x`` on the grid: :meth:`from_action`'s inverse."""
        return 2.0 * (np.asarray(x, dtype=np.float64) - self.lower) / (self.upper - self.lower) - 1.0

    def design_key(self, x: ArrayLike) -> tuple[int, ...]:
        """The cache key of a design on the grid: ``round(x / step)``, integers independent of the bounds."""
        return tuple(int(v) for v in np.round(np.asarray(x, dtype=np.float64) / self.step))
