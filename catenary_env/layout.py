"""Layout of a catenary section: nodes, elements, droppers and supports for ``n_spans`` equal spans.

Nodes of the contact wire (CW) and messenger wire (MW) are ANCF nodes with four coordinates
(x, z, x', z'); stitch-wire nodes are bar nodes with two (x, z). Nodes stand at the supports and
dropper points and, between them, at equal intervals no longer than the fidelity's element length.
Nodes are numbered in order of x so that the matrices are banded.

The messenger passes over each interior support as over a saddle: the support's reaction (about a
kilonewton) kinks it, by a few hundredths of a radian, over the bending length sqrt(EI/T) ≈ 0.1 m. A
cubic (C¹) element cannot bend that sharply across one node; it spreads the kink over the adjacent
elements, which then carry a spurious axial-strain swing and shift the dropper lengths by millimetres
at a 1 m mesh. So the messenger's node at an interior support is a hinge: one position, and a
separate position gradient for each side (6 coordinates).

Stitch wires hang at the interior supports only; at the two end supports of the section the first
dropper hangs from the messenger. Only the end spans, outside the analysis section, see this.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .definition import CatenaryDefinition
from .design import Design

CONTACT, MESSENGER, STITCH = 0, 1, 2
"""Node kinds."""

DROPPER, STITCH_BAR = 0, 1
"""Bar kinds."""


@dataclass(frozen=True)
class Layout:
    """The discretised section (no solution yet). Arrays are indexed by node, element or dropper.

    Attributes
    ----------
    n_spans : int
    span_length : float
        m.
    node_x : ndarray (N,)
        Design x of each node, m.
    node_kind : ndarray (N,)
        CONTACT, MESSENGER or STITCH.
    node_dof : ndarray (N,)
        Index of the node's first coordinate; ANCF nodes have 4, stitch nodes 2.
    n_dofs : int
    cable_nodes : ndarray (Ec, 2)
        Nodes of each ANCF element, in order of x.
    cable_wire : ndarray (Ec,)
        CONTACT or MESSENGER.
    cable_axial_stiffness, cable_bending_stiffness, cable_linear_mass : ndarray (Ec,)
    bar_nodes : ndarray (Eb, 2)
        Bar ends; for droppers (top, bottom).
    bar_kind : ndarray (Eb,)
        DROPPER or STITCH_BAR.
    bar_stiffness : ndarray (Eb,)
        Constant spring rate, N/m, or NaN where it is EA / L.
    bar_axial_stiffness, bar_linear_mass : ndarray (Eb,)
    dropper_bars : ndarray (D,)
        Bar index of each dropper, span by span.
    dropper_span, dropper_index : ndarray (D,)
        Span (0-based) and position in the span of each dropper.
    dropper_height : ndarray (D,)
        Design contact-wire height at each dropper, m.
    stitch_bars : ndarray (S, 3)
        The three bars of each stitch wire.
    support_x : ndarray (n_spans + 1,)
    messenger_supports, contact_supports : ndarray (n_spans + 1,)
        Wire nodes at the supports.
    wire_ends : ndarray (2, 2)
        First and last node of the CW (row 0) and the MW (row 1).
    mass_nodes, mass_values : ndarray
        Point masses (clamps, steady arms, supports): node and kg.
    """

    catenary: CatenaryDefinition
    design: Design
    n_spans: int
    span_length: float
    node_x: np.ndarray
    node_kind: np.ndarray
    node_dof: np.ndarray
    n_dofs: int
    cable_nodes: np.ndarray
    cable_wire: np.ndarray
    cable_axial_stiffness: np.ndarray
    cable_bending_stiffness: np.ndarray
    cable_linear_mass: np.ndarray
    bar_nodes: np.ndarray
    bar_kind: np.ndarray
    bar_stiffness: np.ndarray
    bar_axial_stiffness: np.ndarray
    bar_linear_mass: np.ndarray
    dropper_bars: np.ndarray
    dropper_span: np.ndarray
    dropper_index: np.ndarray
    dropper_height: np.ndarray
    stitch_bars: np.ndarray
    support_x: np.ndarray
    messenger_supports: np.ndarray
    contact_supports: np.ndarray
    wire_ends: np.ndarray
    mass_nodes: np.ndarray
    mass_values: np.ndarray
    cable_dof_table: np.ndarray

    @property
    def n_droppers(self) -> int:
        return int(self.dropper_bars.size)

    def cable_dofs(self) -> np.ndarray:
        """Global indices of the 8 coordinates of each cable element; shape (Ec, 8)."""
        return self.cable_dof_table

    def node_size(self, nodes: np.ndarray) -> np.ndarray:
        """Coordinates per node: 2 (stitch), 4 (wire), 6 (messenger hinge at a support)."""
        ends = np.r_[self.node_dof, self.n_dofs]
        nodes = np.asarray(nodes)
        return ends[nodes + 1] - ends[nodes]

    def bar_dofs(self) -> np.ndarray:
        """Global indices of the positions (x, z) of both ends of each bar; shape (Eb, 4)."""
        start = self.node_dof[self.bar_nodes]
        return (start[:, :, None] + np.arange(2)[None, None, :]).reshape(-1, 4)

    def x_dof(self, nodes: np.ndarray) -> np.ndarray:
        return self.node_dof[nodes]

    def z_dof(self, nodes: np.ndarray) -> np.ndarray:
        return self.node_dof[nodes] + 1


def _subdivide(keys: list[float], max_length: float) -> list[float]:
    """Key positions plus equally spaced points so that no interval exceeds ``max_length``."""
    keys = sorted(set(round(k, 9) for k in keys))
    points = [keys[0]]
    for a, b in zip(keys[:-1], keys[1:], strict=True):
        n = max(1, math.ceil((b - a) / max_length - 1e-9))
        points += [a + (b - a) * i / n for i in range(1, n + 1)]
    return points


def build_layout(
    catenary: CatenaryDefinition,
    design: Design,
    n_spans: int,
    contact_wire_element: float,
    messenger_wire_element: float,
) -> Layout:
    """Discretise ``n_spans`` spans of ``catenary`` carrying ``design`` (see module docstring)."""
    c = catenary
    L = c.span_length
    stitch = c.stitch_wire
    half = 0.5 * stitch.length if stitch is not None else 0.0
    support_x = np.arange(n_spans + 1) * L
    d = np.asarray(design.dropper_positions)
    n_d = d.size
    dropper_x = (support_x[:-1, None] + d[None, :]).ravel()
    dropper_span = np.repeat(np.arange(n_spans), n_d)
    dropper_index = np.tile(np.arange(n_d), n_spans)
    # A dropper hangs from the stitch wire when it is the first one after (or the last one before)
    # an interior support.
    on_stitch = np.zeros(dropper_x.size, dtype=bool)
    if stitch is not None:
        on_stitch = ((dropper_index == 0) & (dropper_span > 0)) | (
            (dropper_index == n_d - 1) & (dropper_span < n_spans - 1)
        )

    cw_points = _subdivide(list(support_x) + list(dropper_x), contact_wire_element)
    mw_keys = list(support_x) + list(dropper_x[~on_stitch])
    if stitch is not None:
        mw_keys += [x + s for x in support_x[1:-1] for s in (-half, half)]
    mw_points = _subdivide(mw_keys, messenger_wire_element)
    st_points = sorted(round(x, 9) for x in dropper_x[on_stitch])

    # Number nodes in order of x (CW before stitch before MW at the same x) for a banded matrix.
    entries = sorted(
        [(x, CONTACT) for x in cw_points]
        + [(x, MESSENGER) for x in mw_points]
        + [(x, STITCH) for x in st_points]
    )
    node_x = np.array([e[0] for e in entries])
    node_kind = np.array([e[1] for e in entries])
    lookup = {(k, round(x, 6)): i for i, (x, k) in enumerate(entries)}
    hinges = {lookup[(MESSENGER, round(x, 6))] for x in support_x[1:-1]}
    sizes = np.where(node_kind == STITCH, 2, 4)
    sizes[list(hinges)] = 6
    node_dof = np.concatenate([[0], np.cumsum(sizes)[:-1]])

    def node(kind: int, x: float) -> int:
        return lookup[(kind, round(x, 6))]

    cw_nodes = np.array([node(CONTACT, x) for x in cw_points])
    mw_nodes = np.array([node(MESSENGER, x) for x in mw_points])
    cable_nodes = np.vstack([np.c_[cw_nodes[:-1], cw_nodes[1:]], np.c_[mw_nodes[:-1], mw_nodes[1:]]])
    cable_wire = np.r_[np.full(cw_nodes.size - 1, CONTACT), np.full(mw_nodes.size - 1, MESSENGER)]
    wires = (c.contact_wire, c.messenger_wire)

    def per_cable(attr: str) -> np.ndarray:
        return np.array([getattr(wires[w], attr) for w in cable_wire], dtype=float)

    bar_nodes, bar_kind, bar_k, bar_ea, bar_rho = [], [], [], [], []
    dropper_bars = []
    k_d = c.dropper.stiffness if c.dropper.stiffness is not None else math.nan
    ea_d = c.dropper.axial_stiffness if c.dropper.axial_stiffness is not None else math.nan
    for x, hanging in zip(dropper_x, on_stitch, strict=True):
        top = node(STITCH, x) if hanging else node(MESSENGER, x)
        dropper_bars.append(len(bar_nodes))
        bar_nodes.append((top, node(CONTACT, x)))
        bar_kind.append(DROPPER)
        bar_k.append(k_d)
        bar_ea.append(ea_d)
        bar_rho.append(c.dropper.linear_mass)
    stitch_bars = []
    if stitch is not None:
        for xs in support_x[1:-1]:
            chain = [
                node(MESSENGER, xs - half),
                node(STITCH, xs - L + d[-1]),
                node(STITCH, xs + d[0]),
                node(MESSENGER, xs + half),
            ]
            stitch_bars.append([len(bar_nodes) + i for i in range(3)])
            for a, b in zip(chain[:-1], chain[1:], strict=True):
                bar_nodes.append((a, b))
                bar_kind.append(STITCH_BAR)
                bar_k.append(math.nan)
                bar_ea.append(stitch.axial_stiffness)
                bar_rho.append(stitch.linear_mass)

    # An element's end at a hinge uses the gradient of its own side: (+2, +3) left of it, (+4, +5) right.
    start = node_dof[cable_nodes]
    right_side = np.array([4 if a in hinges else 2 for a in cable_nodes[:, 0]])
    cable_dof_table = np.hstack(
        [start[:, :1] + [0, 1], (start[:, 0] + right_side)[:, None] + [0, 1], start[:, 1:] + [0, 1, 2, 3]]
    )
    mw_supports = np.array([node(MESSENGER, x) for x in support_x])
    cw_supports = np.array([node(CONTACT, x) for x in support_x])
    bars = np.array(bar_nodes, dtype=int).reshape(-1, 2)
    drop = np.array(dropper_bars, dtype=int)
    mass_nodes = np.r_[bars[drop, 0], bars[drop, 1], cw_supports, mw_supports]
    mass_values = np.r_[
        np.full(drop.size, c.dropper.clamp_mass_messenger),
        np.full(drop.size, c.dropper.clamp_mass_contact),
        np.full(cw_supports.size, c.supports.steady_arm_mass),
        np.full(mw_supports.size, c.supports.messenger_mass),
    ]
    return Layout(
        catenary=c,
        design=design,
        n_spans=n_spans,
        span_length=L,
        node_x=node_x,
        node_kind=node_kind,
        node_dof=node_dof,
        n_dofs=int(sizes.sum()),
        cable_nodes=cable_nodes,
        cable_wire=cable_wire,
        cable_axial_stiffness=per_cable("axial_stiffness"),
        cable_bending_stiffness=per_cable("bending_stiffness"),
        cable_linear_mass=per_cable("linear_mass"),
        bar_nodes=bars,
        bar_kind=np.array(bar_kind, dtype=int),
        bar_stiffness=np.array(bar_k, dtype=float),
        bar_axial_stiffness=np.array(bar_ea, dtype=float),
        bar_linear_mass=np.array(bar_rho, dtype=float),
        dropper_bars=drop,
        dropper_span=dropper_span,
        dropper_index=dropper_index,
        dropper_height=c.contact_wire_height + np.tile(np.asarray(design.contact_wire_offsets), n_spans),
        stitch_bars=np.array(stitch_bars, dtype=int).reshape(-1, 3),
        support_x=support_x,
        messenger_supports=mw_supports,
        contact_supports=cw_supports,
        wire_ends=np.array([[cw_nodes[0], cw_nodes[-1]], [mw_nodes[0], mw_nodes[-1]]]),
        mass_nodes=mass_nodes,
        mass_values=mass_values,
        cable_dof_table=cable_dof_table,
    )
