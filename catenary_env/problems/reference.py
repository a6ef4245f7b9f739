"""The reference design's pantograph setting and evaluation.

Every design of a problem is simulated with the same pantograph uplift force: the one for which the problem's
reference design (the level contact wire on the preset's droppers) has the EN 50367 mean contact force at the
speed (docs/problems.md, 'Reference design and uplift'). It is calibrated once per model (catenary and
pantograph data), speed and fidelity and kept on disk for every later process and command
(:mod:`~catenary_env.calibration_cache`), and in this process's memory, as are the presets.
"""

from __future__ import annotations

import dataclasses
import functools

from .. import pipeline
from ..calibration_cache import cached_uplift
from ..model.definition import CatenaryDefinition, PantographDefinition
from ..model.design import Design, check_speed
from ..model.presets import load_catenary, load_pantograph
from ..pipeline import Evaluation, Fidelity
from ..train import SINGLE, Train

__all__ = [
    "calibrated_uplift",
    "clear_caches",
    "problem_catenary",
    "preset_catenary",
    "preset_pantograph",
    "reference_evaluation",
]


def clear_caches() -> None:
    """Forget the calibrated uplift forces and reference evaluations of this process (not the disk cache)."""
    calibrated_uplift.cache_clear()
    reference_evaluation.cache_clear()


@functools.lru_cache(maxsize=None)
def preset_catenary(name: str) -> CatenaryDefinition:
    return load_catenary(name)


@functools.lru_cache(maxsize=64)
def problem_catenary(name: str, contact_wire_tension: float | None = None) -> CatenaryDefinition:
    """The catenary preset ``name``, with its contact wire's tension set to ``contact_wire_tension`` (N)
    where given (docs/problems.md, 'Contact-wire tension'); checked as the data files are."""
    catenary = preset_catenary(name)
    if contact_wire_tension is None:
        return catenary
    wire = dataclasses.replace(catenary.contact_wire, tension=float(contact_wire_tension))
    return dataclasses.replace(catenary, contact_wire=wire)


@functools.lru_cache(maxsize=None)
def preset_pantograph(name: str) -> PantographDefinition:
    return load_pantograph(name)


@functools.lru_cache(maxsize=256)
def calibrated_uplift(catenary_name: str, reference: Design, speed_kmh: float, fidelity: Fidelity) -> float:
    # Keyed by the catenary and its reference design, not by the problem: the problems on one catenary
    # share the pantograph setting, so B1, B2, B3 calibrate once between them.
    catenary = preset_catenary(catenary_name)
    speed = speed_kmh / 3.6
    check_speed(catenary, speed)
    return cached_uplift(
        catenary,
        preset_pantograph(catenary.pantograph),
        reference,
        speed_kmh,
        fidelity,
        target_mean=pipeline.en50367_mean_force(speed),
    )


@functools.lru_cache(maxsize=256)
def reference_evaluation(
    catenary_name: str,
    reference: Design,
    speed_kmh: float,
    fidelity: Fidelity,
    train: Train = SINGLE,
    contact_wire_tension: float | None = None,
) -> Evaluation:
    """The reference design's evaluation, with the ``train``'s pantographs behind the calibrated one; on the
    preset with its contact wire at ``contact_wire_tension`` (N) where given, under the preset's uplift
    force (the pantograph is set once per catenary preset and speed, not per tension)."""
    catenary = problem_catenary(catenary_name, contact_wire_tension)
    force = calibrated_uplift(catenary_name, reference, speed_kmh, fidelity)
    return pipeline.evaluate(
        catenary,
        preset_pantograph(catenary.pantograph),
        reference,
        speed_kmh / 3.6,
        fidelity,
        uplift_force=force,
        train=train,
    )
