"""Shape-finding of a section of equal spans, started from a short section's solution.

A section without installation deviations repeats one span; only the spans next to its anchors hang
differently, and their influence dies out span by span into the section (on the benchmark catenary the
middle span of three is 3.5e-5 off the interior one in slope, of five 3e-8; the stitched catenary's reaches
further: docs/performance.md, 'Speed'). So a short section of ``2k + 1`` spans holds, to that precision,
every span shape of the long one: its first ``k`` spans are the section's first ``k``, its last ``k`` the
section's last ``k`` and its middle span every span between. Newton then goes on from that start on the
whole section, to the same tolerance as from the parabolic start (:func:`~.shape_finding.find_shape`): the
same equilibrium, reached in zero or one Newton steps of the section instead of four (docs/performance.md,
'Shape-finding from a short section').
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..fem.layout import Layout, build_layout, nodes_at
from .shape_finding import ShapeFindingError, StaticSolution, find_shape

END_SPANS = 5
"""Spans at each end of the short section (``2 * END_SPANS + 1`` spans) taken as they are. A solver setting,
not an accuracy one: the solution is held to the same tolerance whatever it is. Five lands the stitched
catenary's start within Newton's tolerance on the presets' 20 spans (three does for the benchmark catenary,
not the stitched one: docs/performance.md, 'Shape-finding from a short section')."""


def find_equal_spans_shape(
    layout: Layout, contact_wire_element: float, messenger_wire_element: float
) -> StaticSolution:
    """:func:`~.shape_finding.find_shape` of ``layout`` (equal spans, built with these element lengths, m),
    started from the solution of ``2 * END_SPANS + 1`` of its spans where that section is the shorter by
    ``END_SPANS`` spans or more; from the parabolic start otherwise, and where the short section or the
    start fails (then the section's own Newton decides, with its own message)."""
    n_short = 2 * END_SPANS + 1
    if layout.n_spans >= n_short + END_SPANS:
        short = build_layout(
            layout.catenary, layout.design, n_short, contact_wire_element, messenger_wire_element
        )
        try:
            solution = find_shape(layout, start=replicated_start(layout, find_shape(short)))
        except ShapeFindingError:
            pass
        else:
            return dataclasses.replace(solution, start_spans=n_short)
    return find_shape(layout)


def replicated_start(section: Layout, short: StaticSolution) -> tuple[np.ndarray, np.ndarray]:
    """Coordinates and reference lengths (m) of ``section``, spans copied from ``short``, the solution of an
    odd number ``2k + 1`` of the same spans: its first and last ``k`` spans at the section's ends, its
    middle span everywhere else. Positions along the track move with the span they are copied to."""
    source = short.layout
    k, odd = divmod(source.n_spans, 2)
    if not odd or source.n_spans > section.n_spans:
        raise ValueError("replicated_start: an odd number of short spans needed, at most the section's")
    L = section.span_length
    last = section.n_spans - source.n_spans  # the shift, in spans, of the last k spans

    def shift(x: np.ndarray) -> np.ndarray:
        """m, from a point in the section to where it stands in the short one (continuous at both ends of
        the middle: the short section's middle span is its span ``k``)."""
        span = np.clip(np.floor(x / L).astype(int), 0, section.n_spans - 1)
        return L * np.clip(span - k, 0, last)

    def sources(nodes: np.ndarray, moved: np.ndarray) -> np.ndarray:
        """The short section's node of each node of ``nodes``, moved by ``moved`` (m) along the track."""
        x = section.node_x[nodes] - moved
        kind = section.node_kind[nodes]
        found = np.empty(nodes.shape, dtype=int)
        for wire in np.unique(kind):
            at = kind == wire
            found[at] = nodes_at(source.node_x, np.flatnonzero(source.node_kind == wire), x[at])
        return found

    # Coordinates, node by node; only a node's own position along the track moves (its gradients do not).
    nodes = np.arange(section.node_x.size)
    moved = shift(section.node_x)
    origin = sources(nodes, moved)
    size = section.node_size(nodes)
    if np.any(source.node_size(origin) != size):
        raise ValueError("replicated_start: a node copied from one of another size")  # a bug
    node_of = np.repeat(nodes, size)
    offset = np.arange(section.n_dofs) - section.node_dof[node_of]
    positions = short.positions[source.node_dof[origin[node_of]] + offset]
    positions[section.node_dof] += moved

    # Reference lengths, element by element (cables, then bars), each moved with the span of its midpoint.
    def ends(lay: Layout) -> np.ndarray:
        return np.r_[lay.cable_nodes, lay.bar_nodes]

    elements = ends(section)
    middle = section.node_x[elements].mean(axis=1)
    mapped = sources(elements, shift(middle)[:, None])
    n = source.node_x.size
    code = ends(source) @ np.array([n, 1])
    order = np.argsort(code)
    wanted = mapped @ np.array([n, 1])
    found = order[np.clip(np.searchsorted(code[order], wanted), 0, code.size - 1)]
    if np.any(code[found] != wanted):
        raise ValueError("replicated_start: an element with no counterpart in the short section")  # a bug
    return positions, short.lengths[found]
