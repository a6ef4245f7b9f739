"""The Gymnasium environment of a catenary design problem: one action is one whole design (docs/problems.md,
'Environments')."""

from __future__ import annotations

import functools
import math
from collections import OrderedDict
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import ArrayLike, NDArray

from ..analysis.statistics import ContactStatistics
from ..calibration_cache import quiet_calibrations
from ..model.buildability import BuildabilityLimits, buildability_named
from ..model.definition import CatenaryDefinition
from ..model.design import Design, check_speed, physical_warnings
from ..pipeline import CONSTRAINTS, Evaluation, Fidelity, analysis_window, en50367_mean_force
from ..problems import DesignProblem, get_problem, resolve_fidelity
from ..problems.design_problem import TENSION_FRACTIONS
from ..problems.speeds import SpeedsEvaluation, evaluate_over_speeds
from ..problems.tolerance import RobustObjective
from ..train import SINGLE, Train
from .vector_options import VECTOR_KWARGS

OBJECTIVES = ("sigma", "mean_sigma_over_speeds", "worst_sigma_over_speeds", "robust")
"""Objective names: σ at one speed, the mean of σ over ``speeds_kmh``, the largest σ over ``speeds_kmh``,
the mean (or a quantile) of σ at one speed over seeded installation-tolerance draws (``robust``)."""

SINGLE_SPEED = ("sigma", "robust")
"""The objectives at one speed (``speed_kmh`` or ``speed_range``)."""

INFEASIBLE_SIGMA_OVER_MEAN = 1.0
"""An infeasible design scores as if σ equalled the EN 50367 mean force Fm (σ / Fm = 1).

That is more than three times the EN 50367 quality limit σ / Fm < 0.3, and out of reach in practice of a
design that keeps contact (the only feasible kind): its statistical minimum Fm - 3σ would be -2 Fm.
"""

MEMO_SIZE = 1024
"""Evaluations an env keeps, keyed by design on its grid, speed and tension: a repeated design is not
re-simulated."""

TENSION_STEP = 100.0
"""The grid of contact-wire tensions ``reset`` draws from a ``contact_wire_tension_range``, N."""

_STATISTICS = tuple(ContactStatistics.__dataclass_fields__)


class CatenaryDesignEnv(gym.Env[NDArray[np.float32], NDArray[np.float32]]):
    """
    ## Description

    The design of a railway catenary (overhead contact line) for fast, smooth current collection, posed as one
    decision: the action is the whole geometry of a span (contact-wire heights at the droppers, or dropper
    positions, or both), the catenary is built and a pantograph runs under it in a finite-element simulation,
    and the reward is minus the standard deviation σ of the 20 Hz filtered contact force over the central
    spans (docs/problems.md, 'The eight problems'). Each problem has its own env, `Catenary-<problem>-v0`;
    every span is equal and symmetric, so one variable sets a dropper and its mirror. The pantograph's uplift
    force is set once per speed, on the problem's reference design (the level contact wire on the preset's
    droppers), so that its mean contact force equals the EN 50367 target (157.3 N at 300 km/h); every design
    is simulated with that force.

    ## Action Space

    A `ndarray` of shape `(n_variables,)`, dtype float32, in `[-1, 1]`: action `a_i` maps affinely to
    variable `x_i = lower_i + (a_i + 1) / 2 (upper_i - lower_i)`, which is then rounded to the problem's
    grid (heights 1 mm, positions 1 cm; ties round up). `a = -1` is the lower bound, `a = 1` the upper.
    Values outside `[-1, 1]` are clipped and `info["clipped"]` says so; NaN, infinite values or a wrong
    shape raise `ValueError`. `s`: pre-sag at mid-span (positive = lower); `dh_i`: contact-wire height
    change at dropper i (negative = lower); `d_i`: position of dropper i from the span's first support;
    dropper 1 is next to the support.

    The variables and bounds of each problem: docs/problems.md, 'The eight problems' (the table
    :func:`~catenary_env.problems.table.problem_table` writes from the problems).

    ## Observation Space

    A `ndarray` of shape `(2,)`, dtype float32: the speeds the design is for, as fractions of the
    contact wire's wave speed c = sqrt(T / ρA) (459.6 km/h on the benchmark catenary, 509.1 km/h on the
    stitched one, at their presets' tensions). This ratio governs the dynamics (a catenary is run at
    v / c ≤ 0.7). The observation is constant within an episode; with `speed_range` it changes from
    episode to episode, so a policy can be conditioned on the speed. With `contact_wire_tension_range`
    it has shape `(3,)`: the third entry is the episode's contact-wire tension over the preset's, and c
    is the episode's.

    | Num | Observation                                        | Min | Max |
    |-----|----------------------------------------------------|-----|-----|
    | 0   | lowest speed of the objective / c                  | 0   | 1   |
    | 1   | highest speed of the objective / c                 | 0   | 1   |
    | 2   | contact-wire tension / preset's (with a range)     | 0.7 | 1.3 |

    With `objective="sigma"` both entries are the episode's speed.

    ## Rewards

    *r = -σ* in newtons, σ the standard deviation of the filtered contact force at the episode's speed;
    with `objective="mean_sigma_over_speeds"` *r = -mean(σ(v))*, with `"worst_sigma_over_speeds"`
    *r = -max(σ(v))* over `speeds_kmh`. With `normalize_reward=True` the reward is divided by the same
    objective of the reference design (so the reference scores -1 and a 30 % reduction scores -0.7).
    An infeasible design (a slack dropper at equilibrium, contact loss, or a geometry the catenary
    cannot build) scores *r = -Fm* (normalised likewise), Fm the EN 50367 mean force (157.3 N at
    300 km/h; over several speeds, aggregated like σ): worse than any feasible design.

    ## Starting State

    Nothing is random but the speed: with `speed_range=(lo, hi)` it is drawn at `reset` from
    `self.np_random`, uniformly on the whole km/h values in `[lo, hi]` (a 1 km/h grid, so that the
    pantograph calibration of each speed is reused) outside the `excluded_speeds` bands.
    `reset(options={"speed_kmh": v})` sets it, in an excluded band too (to evaluate a policy there).
    With `contact_wire_tension_range=(lo, hi)` the contact wire's tension is drawn as well, after the
    speed, on a 100 N grid outside the `excluded_tensions` bands; `reset(options={"contact_wire_tension":
    t})` sets it. The reset's info gives `speed_kmh`, and `contact_wire_tension` (N) with a tension range.

    ## Episode End

    Every episode is one step: `terminated=True` after it, `truncated=False`. Vector envs should use
    `autoreset_mode=gymnasium.vector.AutoresetMode.SAME_STEP`, so that no step is spent on a reset:
    `gymnasium.make_vec("Catenary-B1-v0", n)` gives it, with `vectorization_mode="async"` too.

    ## Info

    After `step`: `feasible` (bool), `reason` (str, empty when feasible), `variables` (dict of the
    variables on their grid, m), `design` (the full :class:`~catenary_env.model.design.Design`),
    `speed_kmh`, `contact_wire_tension` (N), `objective` (the σ value behind the reward, N, before
    normalisation; the penalty when infeasible), every field of
    :class:`~catenary_env.analysis.statistics.ContactStatistics` (`mean`, `std`, `std_over_mean`,
    `statistical_max`, `statistical_min`, `actual_max`, `actual_min` in N, `contact_loss_percent` in %,
    `max_support_uplift` in m; absent when the design was not simulated dynamically),
    `acceptance` (the EN 50367 acceptance block, :class:`~catenary_env.analysis.acceptance.Acceptance`:
    each criterion's limit, value, verdict and source tag; docs/acceptance.md) and `acceptance_passed` (bool;
    both absent where the statistics are), `uplift_force` (N), `constraints` (the values of
    `catenary_env.pipeline.CONSTRAINTS` by name: the largest dropper compression in N, the largest
    dropper-length shortfall in m and the contact-loss share in %; feasible when all are <= 0; a value not
    computed is absent, e.g. the contact loss of a design that failed the static check; arrays over the speeds
    with a multi-speed objective, NaN where not computed), `pantograph_statistics` (a dict of those statistics
    per pantograph, the leading one first; per speed with a multi-speed objective), `dropper_lengths` (m) and
    `dropper_forces` (N) of a central span,
    `wall_time` (s, of the simulations behind the result) and `clipped` (bool). With a multi-speed
    objective, `speed_kmh`, the statistics and `uplift_force` are arrays over `speeds_kmh`; a design is
    not simulated at the speeds after the first at which it is infeasible (the statistics are then absent,
    `uplift_force` NaN there), as in the studies' mean-σ problem (`catenary_env.problems.speeds`).
    A design an env has already simulated (the last 1024, on the grid, at the same speed) is not
    simulated again: the step returns the stored result, `wall_time` included.

    ## Arguments

    - `problem`: problem name, one of docs/problems.md's table (set by the registered ID).
    - `speed_kmh=None`: train speed, km/h (default 300; not with a multi-speed objective or `speed_range`).
    - `speed_range=None`: `(lo, hi)` km/h to draw the speed from at each reset. A speed (or range) above
      0.9 of the wave speed is warned about, as on the command line: the wave-speed singularity dominates
      the contact force there.
    - `excluded_speeds=()`: with `speed_range`, bands `((a, b), ...)` km/h, each within the range and
      apart from the others, whose speeds (a and b included) are never drawn: speeds held out of
      training. Refused if no whole km/h speed is left to draw.
    - `contact_wire_tension=None`: the contact wire's tension, N, within 70–130 % of the preset's (default
      the preset's; docs/problems.md, 'Contact-wire tension'). Every tension is simulated under the
      preset's uplift force at the speed: the pantograph is set once per catenary, not per tension.
    - `contact_wire_tension_range=None`: `(lo, hi)` N, drawn at each reset (not with
      `contact_wire_tension`): a policy conditioned on the tension as well.
    - `excluded_tensions=()`: with `contact_wire_tension_range`, bands `((a, b), ...)` N never drawn, as
      `excluded_speeds` are for the speeds.
    - `n_spans=None`: spans in the section, overriding the fidelity's (the analysis section shrinks to
      `n_spans - 2` spans if needed).
    - `fidelity="study"`: `"study"` (20 spans, statistics on 10, Δt = 1 ms), `"test"` (5 spans, coarse
      mesh; for tests only) or a :class:`~catenary_env.pipeline.Fidelity`.
    - `objective="sigma"`: or `"mean_sigma_over_speeds"`, `"worst_sigma_over_speeds"` with `speeds_kmh`.
    - `speeds_kmh=None`: speeds of a multi-speed objective, km/h.
    - `normalize_reward=False`: divide the reward by the reference design's objective.
    - `buildability=None`: limits a design must meet at equilibrium, before any dynamics (docs/acceptance.md,
      'Buildability limits'): `None` or `"none"` (the reference study's setting), `"default"` (dropper force
      >= 30 N, dropper length >= 0.5 m, dropper spacing <= 11 m) or a
      :class:`~catenary_env.model.buildability.BuildabilityLimits`. A design violating one is infeasible,
      with `info["reason"]` starting `"buildability:"`.
    - `robust=None`: with `objective="robust"`, a :class:`~catenary_env.problems.tolerance.RobustObjective`
      (default: 8 draws of seed 0 of the practice tolerances, their mean σ). The same draws serve every
      design of the env; the statistics in `info` are each statistic's mean (or quantile) over the draws,
      and a design is infeasible where any draw is. `normalize_reward` divides by the reference design's
      σ as drawn.
    - `render_mode=None`: or `"rgb_array"`, a picture of the last design (the reference design before
      the first step) with its statistics.
    - `vector_kwargs`: registered for `gymnasium.make_vec` (same-step autoreset), which reads it;
      `gymnasium.make` passes it on, and the env refuses any other value.
    - `train=SINGLE`: a :class:`~catenary_env.train.Train`, pantographs behind the leading one and which
      of them the objective's σ is (`"leading"`, `"trailing"`, `"worst"`, `"mean"`); feasibility covers
      every pantograph (docs/model.md, 'Several pantographs'). Default: one pantograph.

    ```python
    >>> import gymnasium as gym
    >>> from catenary_env.envs import register_envs
    >>> register_envs()
    >>> env = gym.make("Catenary-B1-v0", speed_kmh=280.0, fidelity="test")
    >>> env.action_space
    Box(-1.0, 1.0, (5,), float32)

    ```

    ## Version History

    * v0: Initial version.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 1}

    def __init__(
        self,
        problem: str,
        speed_kmh: float | None = None,
        speed_range: tuple[float, float] | None = None,
        excluded_speeds: tuple[tuple[float, float], ...] = (),
        n_spans: int | None = None,
        fidelity: str | Fidelity = "study",
        objective: str = "sigma",
        speeds_kmh: tuple[float, ...] | None = None,
        normalize_reward: bool = False,
        render_mode: str | None = None,
        vector_kwargs: dict[str, Any] | None = None,
        buildability: str | BuildabilityLimits | None = None,
        robust: RobustObjective | None = None,
        train: Train = SINGLE,
        contact_wire_tension: float | None = None,
        contact_wire_tension_range: tuple[float, float] | None = None,
        excluded_tensions: tuple[tuple[float, float], ...] = (),
    ) -> None:
        if vector_kwargs is not None and vector_kwargs != VECTOR_KWARGS:
            raise ValueError(
                f"vector_kwargs = {vector_kwargs!r}: an option of gymnasium.make_vec, registered as "
                f"{VECTOR_KWARGS!r}; a design env takes no other"
            )
        base = _with_options(get_problem(problem), objective, buildability, robust)
        self._tension_range = _tension_range(base, contact_wire_tension, contact_wire_tension_range)
        self._tension_choices = _drawn_values(
            self._tension_range, excluded_tensions, TENSION_STEP, "contact_wire_tension_range",
            "excluded_tensions", "N", "tension",
        )  # fmt: skip
        first_tension = contact_wire_tension if self._tension_choices is None else self._tension_choices[0]
        self.problem: DesignProblem = base.with_contact_wire_tension(first_tension)
        """The problem of the episode: its catenary has the episode's contact-wire tension."""
        self._preset_tension = get_problem(problem).catenary_definition.contact_wire.tension
        self.fidelity: Fidelity = resolve_fidelity(fidelity, n_spans)
        if not isinstance(train, Train):
            raise ValueError(f"train = {train!r}: a catenary_env.train.Train")
        catenary = self.problem.catenary_definition
        train.check(catenary, self.fidelity.n_spans, analysis_window(catenary, self.fidelity)[1])
        self.train = train
        self.objective = objective
        self.normalize_reward = bool(normalize_reward)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode = {render_mode!r}: must be None or one of {self.metadata['render_modes']}"
            )
        self.render_mode = render_mode
        self._speeds, self._speed_range = _speed_setting(
            self.problem.catenary_definition, speed_kmh, speed_range, objective, speeds_kmh
        )  # the lowest tension's wave speed: a speed it allows, every tension drawn allows
        self._speed_choices = _drawn_values(
            self._speed_range, excluded_speeds, 1.0, "speed_range", "excluded_speeds", "km/h", "speed"
        )
        n = self.problem.n_variables
        self.action_space = spaces.Box(-1.0, 1.0, (n,), np.float32)
        if self._tension_range is None:
            self.observation_space = spaces.Box(0.0, 1.0, (2,), np.float32)
        else:
            high = np.array([1.0, 1.0, TENSION_FRACTIONS[1]], dtype=np.float32)
            self.observation_space = spaces.Box(np.zeros(3, np.float32), high, (3,), np.float32)
        self.evaluation_count = 0
        """Designs simulated by this env (memo hits, calibrations and reference runs not counted)."""
        self._memo: OrderedDict[tuple[tuple[float, ...], float, float | None], Evaluation] = OrderedDict()
        self._reset_done = False
        self._last: tuple[Design, str, list[str]] | None = None
        self._last_trace: tuple[tuple[float, ...], tuple[float, ...]] = ((), ())

    # -- Gymnasium API ------------------------------------------------------------------------------------

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        super().reset(seed=seed)
        options = options or {}
        speeds, problem = self._speeds, self.problem
        if "speed_kmh" in options:
            if self.objective not in SINGLE_SPEED:
                raise ValueError("options['speed_kmh'] is only for objective='sigma' or 'robust'")
            speeds = (float(options["speed_kmh"]),)
        elif self._speed_choices is not None:
            speeds = (float(self._speed_choices[self.np_random.integers(len(self._speed_choices))]),)
        if "contact_wire_tension" in options:
            if self._tension_range is None:
                raise ValueError(
                    "options['contact_wire_tension'] is only for an env with a contact_wire_tension_range"
                )
            problem = problem.with_contact_wire_tension(float(options["contact_wire_tension"]))
        elif self._tension_choices is not None:  # after the speed: a speed-only env draws as it always did
            tension = self._tension_choices[self.np_random.integers(len(self._tension_choices))]
            problem = problem.with_contact_wire_tension(float(tension))
        if options:  # drawn speeds and tensions were checked with the ranges
            for v in speeds:
                _check_speed(problem.catenary_definition, v)
        self._speeds, self.problem = speeds, problem
        self._reset_done = True
        info: dict[str, Any] = {"speed_kmh": self._speed_info()}
        if self._tension_range is not None:
            info["contact_wire_tension"] = self._tension
        return self._observation(), info

    def step(self, action: ArrayLike) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        if (self._speed_range is not None or self._tension_range is not None) and not self._reset_done:
            raise gym.error.ResetNeeded(
                "call reset() first: it draws the speed and the tension from their ranges"
            )
        values = self.problem.grid.check_vector(action, "action")
        clipped = bool(np.any(values < -1.0) or np.any(values > 1.0))
        x = self.action_to_x(values)
        with quiet_calibrations():  # a training loop meets many speeds: no two lines on stderr for each
            result = self._evaluate(x)
            objective = self._objective(result)
            reward = -objective / self._reference_objective() if self.normalize_reward else -objective
        design = self.problem.design(x)
        info = self._info(x, design, result, objective, clipped)
        self._last = (design, f"{self.problem.name} design at {self._condition_text()}", self._summary(info))
        first = result.evaluations[0]
        self._last_trace = (first.trace_position, first.trace_force)
        return self._observation(), float(reward), True, False, info

    def render(self) -> NDArray[np.uint8] | None:
        if self.render_mode is None:
            gym.logger.warn("render() without a render_mode: make the env with render_mode='rgb_array'")
            return None
        from .rendering import render_design

        if self._last is None:
            design, title = (
                self.problem.reference_design(),
                f"{self.problem.name} reference design (level wire)",
            )
            return render_design(self.problem.catenary_definition, design, title, ["not simulated"])
        design, title, lines = self._last
        return render_design(self.problem.catenary_definition, design, title, lines, self._last_trace)

    # -- mapping ------------------------------------------------------------------------------------------

    def action_to_x(self, action: ArrayLike) -> NDArray[np.float64]:
        """The problem's variables (m, on the grid) of an action (clipped to [-1, 1])."""
        return self.problem.grid.from_action(action)

    def x_to_action(self, x: ArrayLike) -> NDArray[np.float32]:
        """The action of variables ``x`` (m, within the bounds): :meth:`action_to_x`'s inverse on the grid."""
        return self.problem.grid.to_action(self.problem.check_variables(x)).astype(np.float32)

    # -- helpers ------------------------------------------------------------------------------------------

    def _evaluate(self, x: NDArray[np.float64]) -> SpeedsEvaluation:
        """The design at the env's speeds: those it has met before from the memo, the rest in one
        :meth:`~catenary_env.problems.DesignProblem.evaluate_speeds` (one statics for all of them)."""
        design_key = tuple(x.tolist())
        evaluations: list[Evaluation] = []
        tension = self.problem.contact_wire_tension
        for i, speed in enumerate(self._speeds):
            key = (design_key, speed, tension)
            if key not in self._memo:
                rest = self.problem.evaluate_speeds(x, self._speeds[i:], self.fidelity, train=self.train)
                self.evaluation_count += len(rest.evaluations)
                for v, evaluation in zip(self._speeds[i:], rest.evaluations, strict=False):
                    self._memo[design_key, v, tension] = evaluation
                while len(self._memo) > MEMO_SIZE:
                    self._memo.popitem(last=False)
                evaluations.extend(rest.evaluations)
                break
            self._memo.move_to_end(key)
            evaluations.append(self._memo[key])
            if not evaluations[-1].feasible:
                break
        return SpeedsEvaluation(self._speeds, tuple(evaluations))

    def _objective(self, result: SpeedsEvaluation) -> float:
        worst = self.objective == "worst_sigma_over_speeds"
        sigma = result.sigma(worst)
        if sigma is not None:
            return sigma
        penalty = [INFEASIBLE_SIGMA_OVER_MEAN * en50367_mean_force(v / 3.6) for v in self._speeds]
        return float(np.max(penalty) if worst else np.mean(penalty))

    def _reference_objective(self) -> float:
        reference = evaluate_over_speeds(
            functools.partial(self.problem.reference_evaluation, fidelity=self.fidelity, train=self.train),
            self._speeds,
        )
        sigma = reference.sigma(self.objective == "worst_sigma_over_speeds")
        if sigma is None:
            raise RuntimeError(
                f"reward normalisation: the reference design of {self.problem.name} is infeasible "
                f"({reference.reason})"
            )
        return sigma

    def _info(
        self,
        x: NDArray[np.float64],
        design: Design,
        result: SpeedsEvaluation,
        objective: float,
        clipped: bool,
    ) -> dict[str, Any]:
        single = len(self._speeds) == 1
        evaluations = result.evaluations
        info: dict[str, Any] = {
            "feasible": result.feasible,
            "reason": result.reason,
            "variables": dict(zip(self.problem.variables, x.tolist(), strict=True)),
            "design": design,
            "speed_kmh": self._speed_info(),
            "contact_wire_tension": self._tension,
            "objective": objective,
        }
        stats = [e.statistics for e in evaluations]
        if len(stats) == len(self._speeds) and all(s is not None for s in stats):
            for name in _STATISTICS:
                column = [float(getattr(s, name)) for s in stats]
                info[name] = column[0] if single else np.array(column)
        uplift = [e.uplift_force for e in evaluations]
        info["uplift_force"] = (
            uplift[0] if single else np.array(uplift + [math.nan] * (len(self._speeds) - len(uplift)))
        )
        acceptance = [e.acceptance for e in evaluations]
        if len(acceptance) == len(self._speeds) and all(a is not None for a in acceptance):
            info["acceptance"] = acceptance[0] if single else tuple(acceptance)
            passed = [a.passed for a in acceptance if a is not None]
            info["acceptance_passed"] = passed[0] if single else np.array(passed)
        info["constraints"] = _constraint_info(evaluations, len(self._speeds))
        per_pantograph = [tuple(s.as_dict() for s in e.pantograph_statistics) for e in evaluations]
        info["pantograph_statistics"] = per_pantograph[0] if single else tuple(per_pantograph)
        info["dropper_lengths"] = tuple(evaluations[0].dropper_lengths)
        info["dropper_forces"] = tuple(evaluations[0].dropper_forces)
        info["wall_time"] = result.wall_time
        info["clipped"] = clipped
        return info

    def _summary(self, info: dict[str, Any]) -> list[str]:
        lines = [f"feasible: {info['feasible']}" + (f" ({info['reason']})" if info["reason"] else "")]
        lines.append("variables (m): " + ", ".join(f"{k} = {v:.3f}" for k, v in info["variables"].items()))
        if "std" in info:
            lines.append(
                f"sigma = {np.round(info['std'], 2)} N, Fm = {np.round(info['mean'], 2)} N, "
                f"contact loss = {np.round(info['contact_loss_percent'], 2)} %"
            )
        return lines

    def _observation(self) -> NDArray[np.float32]:
        # In single precision throughout, as it always was: a stored policy run replays its actions.
        wave_speed_kmh = np.float32(self.problem.catenary_definition.wave_speed * 3.6)
        speeds = np.array([min(self._speeds), max(self._speeds)], dtype=np.float32) / wave_speed_kmh
        if self._tension_range is None:
            return speeds
        return np.append(speeds, np.float32(self._tension / self._preset_tension))

    @property
    def _tension(self) -> float:
        """The episode's contact-wire tension, N."""
        return float(self.problem.catenary_definition.contact_wire.tension)

    def _speed_info(self) -> float | NDArray[np.float64]:
        return self._speeds[0] if len(self._speeds) == 1 else np.array(self._speeds)

    def _condition_text(self) -> str:
        speeds = ", ".join(f"{v:g}" for v in self._speeds) + " km/h"
        if self._tension_range is None and self.problem.contact_wire_tension is None:
            return speeds
        return f"{speeds}, contact wire at {self._tension / 1000:g} kN"


def _with_options(
    problem: DesignProblem,
    objective: str,
    buildability: str | BuildabilityLimits | None,
    robust: RobustObjective | None,
) -> DesignProblem:
    """The env's problem: with its buildability limits, and the robust objective where asked."""
    if robust is not None and objective != "robust":
        raise ValueError(f"robust = {robust!r}: only with objective='robust'")
    if robust is not None and not isinstance(robust, RobustObjective):
        raise ValueError(f"robust = {robust!r}: must be a RobustObjective")
    limits = (
        buildability_named(buildability or "none")
        if not isinstance(buildability, BuildabilityLimits)
        else buildability
    )
    if objective == "robust":
        return problem.with_options(limits, robust or RobustObjective())
    return problem.with_options(limits)


DEFAULT_SPEED_KMH = 300.0
"""The train speed of an env given no speed, km/h."""


def _speed_setting(
    catenary: CatenaryDefinition,
    speed_kmh: float | None,
    speed_range: tuple[float, float] | None,
    objective: str,
    speeds_kmh: tuple[float, ...] | None,
) -> tuple[tuple[float, ...], tuple[float, float] | None]:
    """Check the speed arguments; return the speeds of the first episode (km/h) and the range, if any."""
    if objective not in OBJECTIVES:
        raise ValueError(f"objective = {objective!r}: must be one of {', '.join(OBJECTIVES)}")
    if speed_kmh is not None and speed_range is not None:
        raise ValueError(
            f"speed_kmh = {speed_kmh!r} and speed_range = {speed_range!r}: give one, the speed or the range "
            "drawn from at each reset"
        )
    if objective not in SINGLE_SPEED:
        if speed_range is not None:
            raise ValueError(f"speed_range cannot be combined with objective={objective!r}; give speeds_kmh")
        if speed_kmh is not None:
            raise ValueError(f"speed_kmh cannot be combined with objective={objective!r}; give speeds_kmh")
        if not speeds_kmh:
            raise ValueError(f"objective={objective!r} needs speeds_kmh, a tuple of speeds in km/h")
        speeds = tuple(float(v) for v in speeds_kmh)
        checked: tuple[float, ...] = speeds
        bounds: tuple[float, float] | None = None
    elif speeds_kmh is not None:
        raise ValueError("speeds_kmh is for the multi-speed objectives; use speed_kmh or speed_range")
    elif speed_range is None:
        speeds = checked = (DEFAULT_SPEED_KMH if speed_kmh is None else float(speed_kmh),)
        bounds = None
    else:
        lo, hi = (float(v) for v in speed_range)
        if not (lo <= hi and math.floor(hi) >= math.ceil(lo)):
            raise ValueError(f"speed_range = {speed_range!r}: need lo <= hi with a whole km/h value between")
        bounds = (lo, hi)
        checked, speeds = bounds, (float(math.ceil(lo)),)  # reset() draws the episode's speed
    for v in checked:
        _check_speed(catenary, v)
    return speeds, bounds


def _drawn_values(
    value_range: tuple[float, float] | None,
    excluded: tuple[tuple[float, float], ...],
    step: float,
    range_field: str,
    excluded_field: str,
    unit: str,
    what: str,
) -> NDArray[np.float64] | None:
    """The values on a grid of ``step`` that ``reset`` draws from: those of the range outside the excluded
    bands (None without a range); ValueError naming ``excluded_field`` for a band that is reversed, reaches
    outside the range or overlaps another, or bands that leave no value."""
    bands = [(float(a), float(b)) for a, b in excluded]
    if value_range is None:
        if bands:
            raise ValueError(
                f"{excluded_field} = {excluded!r}: only with {range_field}, the values drawn from"
            )
        return None
    lo, hi = value_range
    for a, b in bands:
        if not (lo <= a <= b <= hi):
            raise ValueError(
                f"{excluded_field}: band ({a:g}, {b:g}) {unit} must have a <= b within {range_field} "
                f"({lo:g}, {hi:g}) {unit}"
            )
    for (a, b), (c, d) in zip(sorted(bands), sorted(bands)[1:], strict=False):
        if c <= b:
            raise ValueError(f"{excluded_field}: bands ({a:g}, {b:g}) and ({c:g}, {d:g}) {unit} overlap")
    values = step * np.arange(math.ceil(lo / step), math.floor(hi / step) + 1, dtype=np.float64)
    held_out = np.zeros(values.shape, dtype=bool)
    for a, b in bands:
        held_out |= (values >= a) & (values <= b)
    kept = values[~held_out]
    if kept.size == 0:
        raise ValueError(
            f"{excluded_field} = {excluded!r}: no {what} of ({lo:g}, {hi:g}) {unit} on the {step:g} {unit} "
            "grid is left to draw"
        )
    return kept


def _tension_range(
    problem: DesignProblem,
    contact_wire_tension: float | None,
    contact_wire_tension_range: tuple[float, float] | None,
) -> tuple[float, float] | None:
    """Check the tension arguments (ValueError naming the field and the allowed range); return the range."""
    if contact_wire_tension_range is None:
        problem.with_contact_wire_tension(contact_wire_tension)
        return None
    if contact_wire_tension is not None:
        raise ValueError(
            f"contact_wire_tension = {contact_wire_tension!r} and contact_wire_tension_range = "
            f"{contact_wire_tension_range!r}: give one, the tension or the range drawn from at each reset"
        )
    lo, hi = (float(v) for v in contact_wire_tension_range)
    if not (lo <= hi and math.floor(hi / TENSION_STEP) >= math.ceil(lo / TENSION_STEP)):
        raise ValueError(
            f"contact_wire_tension_range = {contact_wire_tension_range!r}: need lo <= hi with a value on the "
            f"{TENSION_STEP:g} N grid between"
        )
    for tension in (lo, hi):
        try:
            problem.with_contact_wire_tension(tension)
        except ValueError as error:  # an end outside the allowed tensions: name the range given
            named = f"contact_wire_tension_range = {contact_wire_tension_range!r}: {error}"
            raise type(error)(named) from None
    return lo, hi


def _check_speed(catenary: CatenaryDefinition, speed_kmh: float) -> None:
    """Refuse a speed outside (0, wave speed) (a DesignError, a ValueError, naming the allowed range); warn
    about one near the wave speed, as the command line does."""
    check_speed(catenary, speed_kmh / 3.6)
    for warning in physical_warnings(catenary, speed_kmh / 3.6, None):
        gym.logger.warn(warning)


def _constraint_info(evaluations: Sequence[Evaluation], n_speeds: int) -> dict[str, Any]:
    """``info["constraints"]``: each of :data:`~catenary_env.pipeline.CONSTRAINTS` by name (feasible when
    <= 0), a float at one speed (absent where not computed), else an array over the speeds (NaN where not
    computed)."""
    values = [tuple(e.constraints) or (math.nan,) * len(CONSTRAINTS) for e in evaluations]
    values += [(math.nan,) * len(CONSTRAINTS)] * (n_speeds - len(values))
    if n_speeds == 1:  # a value not computed is absent, as the statistics of a design not simulated are
        return {name: float(v) for name, v in zip(CONSTRAINTS, values[0], strict=True) if not math.isnan(v)}
    return {name: np.array([v[i] for v in values]) for i, name in enumerate(CONSTRAINTS)}
