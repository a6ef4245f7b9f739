"""The buildability verdict of a static state (docs/acceptance.md, 'Buildability limits'): the first limit of
:class:`~catenary_env.model.buildability.BuildabilityLimits` a solved design violates, named, or nothing.

It runs with the static verdict (compression, negative length), before any dynamics.
"""

from __future__ import annotations

import numpy as np

from ..model.buildability import BuildabilityLimits
from ..statics.shape_finding import StaticSolution


def buildability_violation(static: StaticSolution, limits: BuildabilityLimits) -> str:
    """Why ``static`` cannot be built under ``limits``, starting ``"buildability:"``; empty when it can.

    Every span counts (spans differ under installation tolerances).
    """
    if not limits.binding:
        return ""
    lay = static.layout
    lengths, forces = static.dropper_lengths, static.dropper_forces
    i = int(np.argmin(lengths))
    if lengths[i] < limits.min_dropper_length:
        return (
            f"buildability: dropper {lay.dropper_index[i] + 1} of span {lay.dropper_span[i] + 1} is "
            f"{lengths[i]:.3f} m long, below buildability.min_dropper_length = "
            f"{limits.min_dropper_length:g} m"
        )
    i = int(np.argmin(forces))
    if forces[i] < limits.min_dropper_force:
        return (
            f"buildability: dropper {lay.dropper_index[i] + 1} of span {lay.dropper_span[i] + 1} carries "
            f"{forces[i]:.1f} N, below buildability.min_dropper_force = {limits.min_dropper_force:g} N"
        )
    x = lay.node_x[lay.bar_nodes[lay.dropper_bars, 1]]
    same_span = lay.dropper_span[1:] == lay.dropper_span[:-1]
    gaps = np.where(same_span, np.diff(x), 0.0)
    i = int(np.argmax(gaps)) if gaps.size else 0
    if gaps.size and gaps[i] > limits.max_dropper_spacing:
        return (
            f"buildability: droppers {lay.dropper_index[i] + 1} and {lay.dropper_index[i] + 2} of span "
            f"{lay.dropper_span[i] + 1} stand {gaps[i]:.2f} m apart, above "
            f"buildability.max_dropper_spacing = {limits.max_dropper_spacing:g} m"
        )
    return ""
