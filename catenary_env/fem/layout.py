"""Layout of a catenary section: nodes, elements, droppers and supports for ``n_spans`` equal spans.

Nodes of the contact wire (CW) and messenger wire (MW) are ANCF nodes with four coordinates
(x, z, x', z'); stitch-wire nodes are bar nodes with two (x, z). Nodes stand at the supports and
dropper points and, between them, at equal intervals no longer than the fidelity's element length.
Nodes are numbered in order of x so that the matrices are banded.

The messenger passes over each interior support as over a saddle: the support's reaction (about a
kilonewton) bends it, by a few hundredths of a radian, over the bending length sqrt(EI/T) ≈ 0.1 m. It is
one continuous wire there (``messenger_support = "continuous"``, the default; docs/model.md, 'Modelling
choices'), and a cubic (C¹) element cannot bend that sharply across one node of a 1 m mesh: it would spread
the bend over the adjacent elements, whose spurious axial-strain swing shifts the dropper lengths by
millimetres. So the messenger gets nodes at 0.5, 1, 2 and 4 bending lengths on each side of each interior
support, which brings the dropper lengths within a few tenths of a millimetre of a uniform 5 cm mesh. The
choice ``"hinge"`` models the sharp-kink limit instead: one position and a separate position gradient for
each side (6 coordinates), which puts the messenger's chord some 4 mm lower at the supports.

Dropper clamps and steady arms are point masses at their nodes, or, with ``clamp_masses = "distributed"``,
spread along the wire they sit on: each span's clamps and one steady arm add their mass per metre of span to
the contact wire and the messenger.

Stitch wires hang at the interior supports only; at the two end supports of the section the first
dropper hangs from the messenger. Only the end spans, outside the analysis section, see this.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model.definition import CatenaryDefinition
from ..model.design import Design
from ..model.tolerances import SectionDeviations

BENDING_LAYER = (0.5, 1.0, 2.0, 4.0)
"""Distances from an interior support, in bending lengths √(EI/T), of the nodes that resolve a continuous
messenger's bend over the support."""

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

    def topology(self) -> tuple[np.ndarray, ...]:
        """What the sparsity of the section's matrices follows from: its coordinates, its elements' nodes
        and its stitch bars (the same for every design of a problem, whatever the heights)."""
        n_dofs = np.array([self.n_dofs])
        return (n_dofs, self.node_dof, self.cable_dof_table, self.bar_nodes, self.stitch_bars)

    def node_size(self, nodes: np.ndarray) -> np.ndarray:
        """Coordinates per node: 2 (stitch), 4 (wire), 6 (messenger hinge at a support)."""
        ends = np.r_[self.node_dof, self.n_dofs]
        nodes = np.asarray(nodes)
        return ends[nodes + 1] - ends[nodes]

    def bar_dofs(self) -> np.ndarray:
        """Global indices of the positions (x, z) of both ends of each bar; shape (Eb, 4)."""
        start = self.node_dof[self.bar_nodes]
        return (start[:, :, None] + np.arange(2)[None, None, :]).reshape(-1, 4)

    def axial_coordinates(self) -> np.ndarray:
        """Mask (n_dofs,) of the coordinates along the track: x and each x' of a wire node, x of a stitch one.

        A node's coordinates alternate x-like and z-like: (x, z), (x, z, x', z') or, at a hinge,
        (x, z, x', z', x', z').
        """
        nodes = np.arange(self.node_x.size)
        node = np.repeat(nodes, self.node_size(nodes))
        return (np.arange(self.n_dofs) - self.node_dof[node]) % 2 == 0

    def x_dof(self, nodes: np.ndarray) -> np.ndarray:
        return self.node_dof[nodes]

    def z_dof(self, nodes: np.ndarray) -> np.ndarray:
        return self.node_dof[nodes] + 1


def _subdivide(keys: np.ndarray, max_length: float) -> np.ndarray:
    """Key positions plus equally spaced points so that no interval exceeds ``max_length``, m; sorted."""
    keys = np.unique(np.round(keys, 9))
    a, b = keys[:-1], keys[1:]
    n = np.maximum(1, np.ceil((b - a) / max_length - 1e-9)).astype(int)
    interval = np.repeat(np.arange(a.size), n)
    i = np.arange(1, interval.size + 1) - np.repeat(np.cumsum(n) - n, n)  # 1..n within each interval
    return np.r_[keys[0], a[interval] + (b - a)[interval] * i / n[interval]]


def nodes_at(node_x: np.ndarray, nodes: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The node among ``nodes`` (in order of x) that stands at each ``x``, to a micrometre."""
    at = node_x[nodes]
    i = np.clip(np.searchsorted(at, np.asarray(x) - 1e-6), 0, at.size - 1)
    if np.any(np.abs(at[i] - x) > 1e-6):
        raise ValueError("layout: no node at a key position")  # a bug, never a user error
    return nodes[i]


def _bending_layer(supports: np.ndarray, catenary: CatenaryDefinition, room: float) -> np.ndarray:
    """Messenger node positions of :data:`BENDING_LAYER` around each support, those within half of
    ``room`` (m, the distance to the nearest dropper) only."""
    wire = catenary.messenger_wire
    offsets = math.sqrt(wire.bending_stiffness / wire.tension) * np.array(BENDING_LAYER)
    offsets = offsets[(offsets > 0.0) & (offsets < 0.5 * room)]
    return (supports[:, None] + np.r_[-offsets, offsets]).ravel()


def build_layout(
    catenary: CatenaryDefinition,
    design: Design,
    n_spans: int,
    contact_wire_element: float,
    messenger_wire_element: float,
    deviations: SectionDeviations | None = None,
) -> Layout:
    """Discretise ``n_spans`` spans of ``catenary`` carrying ``design`` (see module docstring).

    ``deviations`` (installation tolerances, per span and dropper) move each dropper and its contact-wire
    height; the spans are then no longer equal.
    """
    c = catenary
    L = c.span_length
    stitch = c.stitch_wire
    half = 0.5 * stitch.length if stitch is not None else 0.0
    support_x = np.arange(n_spans + 1) * L
    d = np.asarray(design.dropper_positions)
    n_d = d.size
    shift = np.zeros((n_spans, d.size)) if deviations is None else deviations.position
    dropper_x = (support_x[:-1, None] + d[None, :] + shift).ravel()
    dropper_span = np.repeat(np.arange(n_spans), n_d)
    dropper_index = np.tile(np.arange(n_d), n_spans)
    # A dropper hangs from the stitch wire when it is the first one after (or the last one before)
    # an interior support.
    on_stitch = np.zeros(dropper_x.size, dtype=bool)
    if stitch is not None:
        on_stitch = ((dropper_index == 0) & (dropper_span > 0)) | (
            (dropper_index == n_d - 1) & (dropper_span < n_spans - 1)
        )

    interior = support_x[1:-1]
    cw_points = _subdivide(np.r_[support_x, dropper_x], contact_wire_element)
    mw_keys = np.r_[support_x, dropper_x[~on_stitch]]
    if c.modelling.messenger_support == "continuous":
        room = min(d[0], L - d[-1]) - np.max(np.abs(shift), initial=0.0) if d.size else L
        mw_keys = np.r_[mw_keys, _bending_layer(interior, c, room)]
    if stitch is not None:
        mw_keys = np.r_[mw_keys, (interior[:, None] + [-half, half]).ravel()]
    mw_points = _subdivide(mw_keys, messenger_wire_element)
    st_points = np.sort(np.round(dropper_x[on_stitch], 9))

    # Number nodes in order of x (CW, MW, stitch at the same x) for a banded matrix.
    all_x = np.r_[cw_points, mw_points, st_points]
    all_kind = np.r_[
        np.full(cw_points.size, CONTACT), np.full(mw_points.size, MESSENGER), np.full(st_points.size, STITCH)
    ]
    order = np.lexsort((all_kind, all_x))
    node_x, node_kind = all_x[order], all_kind[order]
    cw_nodes, mw_nodes, st_nodes = (
        np.flatnonzero(node_kind == kind) for kind in (CONTACT, MESSENGER, STITCH)
    )
    options = c.modelling
    hinged = options.messenger_support == "hinge"
    hinges = nodes_at(node_x, mw_nodes, interior) if hinged else np.zeros(0, int)
    sizes = np.where(node_kind == STITCH, 2, 4)
    sizes[hinges] = 6
    node_dof = np.concatenate([[0], np.cumsum(sizes)[:-1]])

    cable_nodes = np.vstack([np.c_[cw_nodes[:-1], cw_nodes[1:]], np.c_[mw_nodes[:-1], mw_nodes[1:]]])
    cable_wire = np.r_[np.full(cw_nodes.size - 1, CONTACT), np.full(mw_nodes.size - 1, MESSENGER)]

    def per_cable(attr: str) -> np.ndarray:
        return np.where(
            cable_wire == CONTACT, float(getattr(c.contact_wire, attr)), getattr(c.messenger_wire, attr)
        )

    cable_linear_mass = per_cable("linear_mass")
    distributed = options.clamp_masses == "distributed"
    if distributed:  # a span's clamps, and one steady arm, per metre of span
        cable_linear_mass += np.where(
            cable_wire == CONTACT,
            (n_d * c.dropper.clamp_mass_contact + c.supports.steady_arm_mass) / L,
            n_d * c.dropper.clamp_mass_messenger / L,
        )

    # Bars: the droppers (top, bottom) in dropper order, then three bars per stitch wire.
    top = np.empty(dropper_x.size, dtype=int)
    top[on_stitch] = nodes_at(node_x, st_nodes, dropper_x[on_stitch])
    top[~on_stitch] = nodes_at(node_x, mw_nodes, dropper_x[~on_stitch])
    dropper_nodes = np.c_[top, nodes_at(node_x, cw_nodes, dropper_x)]
    n_drop = dropper_x.size
    stitch_nodes = np.zeros((0, 2), dtype=int)
    stitch_ea = stitch_rho = math.nan
    if stitch is not None:
        chain = np.c_[
            nodes_at(node_x, mw_nodes, interior - half),
            nodes_at(node_x, st_nodes, dropper_x.reshape(n_spans, n_d)[:-1, -1]),
            nodes_at(node_x, st_nodes, dropper_x.reshape(n_spans, n_d)[1:, 0]),
            nodes_at(node_x, mw_nodes, interior + half),
        ]
        stitch_nodes = np.stack([chain[:, :-1], chain[:, 1:]], axis=2).reshape(-1, 2)
        stitch_ea, stitch_rho = stitch.axial_stiffness, stitch.linear_mass
    n_stitch = stitch_nodes.shape[0]
    bars = np.vstack([dropper_nodes, stitch_nodes]).astype(int)
    drop = np.arange(n_drop)
    stitch_bars = (n_drop + np.arange(n_stitch)).reshape(-1, 3)
    bar_kind = np.r_[np.full(n_drop, DROPPER), np.full(n_stitch, STITCH_BAR)]
    k_d = c.dropper.stiffness if c.dropper.stiffness is not None else math.nan
    ea_d = c.dropper.axial_stiffness if c.dropper.axial_stiffness is not None else math.nan
    bar_k = np.r_[np.full(n_drop, k_d, dtype=float), np.full(n_stitch, math.nan)]
    bar_ea = np.r_[np.full(n_drop, ea_d, dtype=float), np.full(n_stitch, stitch_ea, dtype=float)]
    bar_rho = np.r_[
        np.full(n_drop, c.dropper.linear_mass, dtype=float), np.full(n_stitch, stitch_rho, dtype=float)
    ]

    # An element's end at a hinge uses the gradient of its own side: (+2, +3) left of it, (+4, +5) right.
    start = node_dof[cable_nodes]
    right_side = np.where(np.isin(cable_nodes[:, 0], hinges), 4, 2)
    cable_dof_table = np.hstack(
        [start[:, :1] + [0, 1], (start[:, 0] + right_side)[:, None] + [0, 1], start[:, 1:] + [0, 1, 2, 3]]
    )
    mw_supports = nodes_at(node_x, mw_nodes, support_x)
    cw_supports = nodes_at(node_x, cw_nodes, support_x)
    mass_nodes = np.r_[bars[drop, 0], bars[drop, 1], cw_supports, mw_supports]
    point = 0.0 if distributed else 1.0  # distributed clamps and steady arms are in the wires' mass
    mass_values = np.r_[
        np.full(drop.size, point * c.dropper.clamp_mass_messenger),
        np.full(drop.size, point * c.dropper.clamp_mass_contact),
        np.full(cw_supports.size, point * c.supports.steady_arm_mass),
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
        cable_linear_mass=cable_linear_mass,
        bar_nodes=bars,
        bar_kind=bar_kind,
        bar_stiffness=bar_k,
        bar_axial_stiffness=bar_ea,
        bar_linear_mass=bar_rho,
        dropper_bars=drop,
        dropper_span=dropper_span,
        dropper_index=dropper_index,
        dropper_height=c.contact_wire_height
        + np.tile(np.asarray(design.contact_wire_offsets), n_spans)
        + (0.0 if deviations is None else deviations.height.ravel()),
        stitch_bars=stitch_bars,
        support_x=support_x,
        messenger_supports=mw_supports,
        contact_supports=cw_supports,
        wire_ends=np.array([[cw_nodes[0], cw_nodes[-1]], [mw_nodes[0], mw_nodes[-1]]]),
        mass_nodes=mass_nodes,
        mass_values=mass_values,
        cable_dof_table=cable_dof_table,
    )
