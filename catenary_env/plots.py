"""Plots a catenary engineer expects (README.md, 'Command line'): geometry, contact force, stiffness, dropper
forces.

matplotlib is optional: it is imported where used, with the install command in the error.
Every function draws on a given Axes and returns it, so figures can be composed.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from .errors import MissingDependency
from .fem.layout import CONTACT, MESSENGER, STITCH
from .statics.shape_finding import StaticSolution

if TYPE_CHECKING:
    from .analysis.static_analysis import StiffnessProfile
    from .pipeline import Simulation


def pyplot() -> Any:
    """matplotlib.pyplot with a non-interactive backend, or an error with the install command."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:  # pragma: no cover - depends on the environment
        raise MissingDependency("plotting needs matplotlib: pip install 'catenary-env[plot]'") from None
    return plt


def span_geometry(static: StaticSolution, ax: Any, span: int | None = None) -> Any:
    """Contact wire, messenger, stitch wire and droppers of one span (the central one by default)."""
    lay = static.layout
    span = lay.n_spans // 2 if span is None else span
    x0 = span * lay.span_length
    X = static.positions
    inside = (lay.node_x >= x0 - 1e-9) & (lay.node_x <= x0 + lay.span_length + 1e-9)
    for kind, label, style in (
        (CONTACT, "contact wire", "C0-"),
        (MESSENGER, "messenger wire", "C1-"),
        (STITCH, "stitch wire", "C2o-"),
    ):
        nodes = np.flatnonzero(inside & (lay.node_kind == kind))
        if nodes.size:
            ax.plot(lay.node_x[nodes] - x0, X[lay.node_dof[nodes] + 1], style, lw=1.2, ms=3, label=label)
    drop = lay.dropper_bars[lay.dropper_span == span]
    for top, bottom in lay.bar_nodes[drop]:
        xs = X[lay.node_dof[[top, bottom]]] - x0
        zs = X[lay.node_dof[[top, bottom]] + 1]
        ax.plot(xs, zs, "k-", lw=0.8)
    ax.set_xlabel("position in span (m)")
    ax.set_ylabel("height (m)")
    ax.legend(loc="upper center", fontsize=8)
    return ax


def contact_wire_height(static: StaticSolution, ax: Any, span: int | None = None) -> Any:
    """Contact-wire height along a span in mm relative to the supports, with the dropper points."""
    lay = static.layout
    span = lay.n_spans // 2 if span is None else span
    x0 = span * lay.span_length
    nodes = np.flatnonzero(
        (lay.node_kind == CONTACT) & (lay.node_x >= x0 - 1e-9) & (lay.node_x <= x0 + lay.span_length + 1e-9)
    )
    base = lay.catenary.contact_wire_height
    ax.plot(lay.node_x[nodes] - x0, 1e3 * (static.positions[lay.node_dof[nodes] + 1] - base), "C0-")
    drop = lay.bar_nodes[lay.dropper_bars[lay.dropper_span == span], 1]
    ax.plot(lay.node_x[drop] - x0, 1e3 * (static.positions[lay.node_dof[drop] + 1] - base), "ko", ms=4)
    ax.set_xlabel("position in span (m)")
    ax.set_ylabel("contact-wire height (mm)")
    return ax


def contact_force(simulation: Simulation, ax: Any) -> Any:
    """Raw and 20 Hz filtered contact force along the track, with the analysis section shaded."""
    tr = simulation.trajectory
    ax.plot(tr.position, tr.contact_force, color="0.7", lw=0.6, label="raw")
    ax.plot(tr.position, simulation.filtered_force, "C0-", lw=1.0, label="filtered 20 Hz")
    ax.axvspan(*simulation.window, color="C2", alpha=0.08, label="analysis section")
    s = simulation.statistics
    ax.axhline(s.mean, color="C3", lw=0.8, ls="--", label=f"Fm = {s.mean:.1f} N, σ = {s.std:.1f} N")
    for x in tr.support_x:
        ax.axvline(x, color="0.85", lw=0.5, zorder=0)
    ax.set_xlabel("position along the track (m)")
    ax.set_ylabel("contact force (N)")
    ax.legend(loc="upper right", fontsize=8)
    return ax


def stiffness(profiles: list[StiffnessProfile], ax: Any) -> Any:
    """Static stiffness along the span for one or more load levels."""
    for p in profiles:
        ax.plot(
            p.positions, p.stiffness / 1e3, "o-", ms=3, label=f"F = {p.force:.0f} N, α = {p.variability:.3f}"
        )
    ax.set_xlabel("position in span (m)")
    ax.set_ylabel("stiffness (kN/m)")
    ax.legend(fontsize=8)
    return ax


def dropper_forces(static: StaticSolution, ax: Any, span: int | None = None) -> Any:
    """Static dropper forces of one span."""
    lay = static.layout
    span = lay.n_spans // 2 if span is None else span
    pick = lay.dropper_span == span
    x = np.asarray(lay.design.dropper_positions)
    ax.bar(x, static.dropper_forces[pick], width=1.2)
    ax.set_xlabel("dropper position (m)")
    ax.set_ylabel("static dropper force (N)")
    return ax
