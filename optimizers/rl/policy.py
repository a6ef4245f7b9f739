"""A design policy: the env it was trained on (:class:`EnvSpec`), how it saw the observations, and the
design it gives for a speed (and a contact-wire tension)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..problem import GridProblem, GridSpace


@dataclass(frozen=True)
class EnvSpec:
    """How to make the design env (picklable; recorded with the run).

    Attributes
    ----------
    env_id : str
        Registered Gymnasium id, e.g. ``"Catenary-B1-v0"``.
    speed_kmh : float or None
        Train speed, km/h; None with ``speed_range``.
    speed_range : (float, float) or None
        Lowest and highest speed, km/h, drawn at each reset: a speed-conditioned policy.
    fidelity : str
        ``"study"`` or ``"test"``.
    excluded_speeds : tuple of (float, float)
        With ``speed_range``: bands of speeds, km/h, never drawn in training (held out, to evaluate the
        policy where it has not been trained; the env's ``excluded_speeds``).
    contact_wire_tension_range : (float, float) or None
        Lowest and highest contact-wire tension, N, drawn at each reset: a policy conditioned on the
        tension as well (the env's ``contact_wire_tension_range``); None: the preset's tension.
    excluded_tensions : tuple of (float, float)
        With ``contact_wire_tension_range``: bands of tensions, N, never drawn in training.
    """

    env_id: str
    speed_kmh: float | None = 300.0
    speed_range: tuple[float, float] | None = None
    fidelity: str = "study"
    excluded_speeds: tuple[tuple[float, float], ...] = ()
    contact_wire_tension_range: tuple[float, float] | None = None
    excluded_tensions: tuple[tuple[float, float], ...] = ()

    def as_dict(self) -> dict[str, Any]:
        """The spec as JSON values, part of a run's identity and of its steps' key in the store; without
        the held-out bands and the tension range where there are none, as before they existed, so that a
        store's earlier runs and steps still match."""
        data = dataclasses.asdict(self)
        for name in ("excluded_speeds", "contact_wire_tension_range", "excluded_tensions"):
            if not data[name]:
                del data[name]
        return data

    def make(self) -> Any:
        """Build the env with ``gymnasium.make``."""
        import gymnasium

        kwargs: dict[str, Any] = {"fidelity": self.fidelity}
        if self.speed_range is not None:
            kwargs["speed_range"] = tuple(self.speed_range)
            if self.excluded_speeds:
                kwargs["excluded_speeds"] = tuple(map(tuple, self.excluded_speeds))
        else:
            kwargs["speed_kmh"] = self.speed_kmh
        if self.contact_wire_tension_range is not None:
            kwargs["contact_wire_tension_range"] = tuple(self.contact_wire_tension_range)
            if self.excluded_tensions:
                kwargs["excluded_tensions"] = tuple(map(tuple, self.excluded_tensions))
        return gymnasium.make(self.env_id, **kwargs)

    @property
    def conditions(self) -> str:
        """The speeds (and tensions) trained on, in words."""
        if self.speed_range is None:
            text = f"{self.speed_kmh:g} km/h"
        else:
            text = f"{self.speed_range[0]:g}-{self.speed_range[1]:g} km/h{_except(self.excluded_speeds, 1.0)}"
        if self.contact_wire_tension_range is not None:
            lo, hi = self.contact_wire_tension_range
            held_out = _except(self.excluded_tensions, 1000.0)
            text += f", contact wire at {lo / 1000:g}-{hi / 1000:g} kN{held_out}"
        return text


def _except(bands: Any, unit: float) -> str:
    """The words " except a-b and c-d" of held-out bands, in ``unit`` (none without bands)."""
    if not bands:
        return ""
    return " except " + " and ".join(f"{a / unit:g}-{b / unit:g}" for a, b in bands)


class ObservationScaling(NamedTuple):
    """SB3 ``VecNormalize``'s observation standardisation, frozen at the end of training.

    Attributes
    ----------
    mean, var : ndarray
        Running mean and variance of the observations.
    epsilon : float
        Added to the variance.
    clip : float
        Standardised observations are clipped to ``[-clip, clip]``.
    """

    mean: NDArray[np.float64]
    var: NDArray[np.float64]
    epsilon: float
    clip: float

    def apply(self, observation: NDArray[np.float32]) -> NDArray[np.float32]:
        """The observation as the policy saw it in training."""
        scaled = (np.asarray(observation) - self.mean) / np.sqrt(self.var + self.epsilon)
        return np.clip(scaled, -self.clip, self.clip).astype(np.float32)


@dataclass(frozen=True)
class DesignPolicy:
    """A trained design policy: the learner's model and the env it was trained on.

    Attributes
    ----------
    model : stable_baselines3.PPO or stable_baselines3.SAC
        The trained model.
    env_spec : EnvSpec
        The env (its observations are what the policy reads).
    observation_scaling : ObservationScaling or None
        How observations were standardised in training (None: not at all).
    """

    model: Any
    env_spec: EnvSpec
    observation_scaling: ObservationScaling | None = None


def design_for_speed(
    policy: DesignPolicy, problem: GridProblem, speed_kmh: float, contact_wire_tension: float | None = None
) -> NDArray[np.float64]:
    """The design the policy gives for a speed (and a contact-wire tension): its deterministic action,
    mapped onto the grid.

    Parameters
    ----------
    policy : DesignPolicy
        A trained policy.
    problem : GridProblem
        Its problem (bounds and grid).
    speed_kmh : float
        Train speed, km/h (within the training range for a meaningful answer).
    contact_wire_tension : float, optional
        The contact wire's tension, N, for a policy trained over a tension range (required there, refused
        otherwise).

    Returns
    -------
    ndarray, shape (n_variables,)
        The design's variables, m, on the grid.
    """
    trained = policy.env_spec.conditions
    if policy.env_spec.contact_wire_tension_range is not None and contact_wire_tension is None:
        raise ValueError(f"contact_wire_tension: give the tension, N: the policy was trained on {trained}")
    if policy.env_spec.contact_wire_tension_range is None and contact_wire_tension is not None:
        raise ValueError(
            f"contact_wire_tension = {contact_wire_tension!r}: the policy knows none ({trained})"
        )
    options = {"speed_kmh": float(speed_kmh)}
    if contact_wire_tension is not None:
        options["contact_wire_tension"] = float(contact_wire_tension)
    env = policy.env_spec.make()
    try:
        observation, _ = env.reset(seed=0, options=options)
    finally:
        env.close()
    if policy.observation_scaling is not None:
        observation = policy.observation_scaling.apply(observation)
    action, _ = policy.model.predict(observation, deterministic=True)
    return GridSpace.from_problem(problem).from_action(np.asarray(action).reshape(-1))
