"""A picture of one span's design for :meth:`CatenaryDesignEnv.render` (matplotlib, optional dependency).

Top panel: the span as built, to scale in metres: messenger wire (parabolic estimate, the same one
:func:`~catenary_env.model.design.check_design` uses), droppers, contact wire through the design heights.
Middle panel: the contact-wire height change Δh at the droppers in millimetres, where a few millimetres
are visible, with the simulation's statistics as text. Bottom panel (after a step): the filtered contact
force along the analysis section.
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ..model.definition import CatenaryDefinition
from ..model.design import Design, estimated_messenger_height

if TYPE_CHECKING:  # matplotlib is optional: imported for real only inside render_design
    from matplotlib.axes import Axes

INSTALL_HINT = "rendering needs matplotlib: pip install catenary-env[plot]"

WIDTH_PX, HEIGHT_PX, DPI = 800, 600, 100
TEXT_WIDTH = 100
"""Characters per line of the statistics text (monospace, 8 pt, fits 800 px)."""


def render_design(
    catenary: CatenaryDefinition,
    design: Design,
    title: str,
    lines: Sequence[str],
    trace: tuple[Sequence[float], Sequence[float]] = ((), ()),
) -> NDArray[np.uint8]:
    """Draw a span's design and return the image.

    Parameters
    ----------
    catenary : CatenaryDefinition
    design : Design
    title : str
        First line of the figure title.
    lines : sequence of str
        Text shown under the height plot (statistics, feasibility).
    trace : (positions, forces)
        Filtered contact force (N) along the analysis section (m); a third panel when not empty.

    Returns
    -------
    ndarray, shape (HEIGHT_PX, WIDTH_PX, 3), dtype uint8
        RGB image.
    """
    try:
        # Figure and the Agg canvas directly, not pyplot: no global state, no GUI backend, thread-safe.
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError as error:  # pragma: no cover - depends on the installation
        raise ImportError(INSTALL_HINT) from error

    figure = Figure(figsize=(WIDTH_PX / DPI, HEIGHT_PX / DPI), dpi=DPI)
    canvas = FigureCanvasAgg(figure)
    positions, forces = trace
    if len(forces):
        geometry, heights, force = figure.subplots(3, 1, gridspec_kw={"height_ratios": [3, 2, 2]})
        force.plot(positions, forces, color="tab:blue", linewidth=0.8)
        force.axhline(float(np.mean(forces)), color="tab:red", linewidth=0.8, linestyle="--")
        force.set_xlabel("position along the track (m)", fontsize=8)
        force.set_ylabel("contact force,\n20 Hz (N)", fontsize=8)
        force.tick_params(labelsize=7)
    else:
        geometry, heights = figure.subplots(2, 1, gridspec_kw={"height_ratios": [3, 2]})
    _draw_span(geometry, catenary, design)
    _draw_heights(heights, catenary, design)
    wrapped = [part for line in lines for part in textwrap.wrap(line, TEXT_WIDTH, subsequent_indent="  ")]
    figure.text(0.02, 0.01, "\n".join(wrapped), va="bottom", family="monospace", fontsize=8)
    geometry.set_title(title, fontsize=10)
    figure.subplots_adjust(
        left=0.09, right=0.98, top=0.93, bottom=0.04 + 0.017 * len(wrapped) + 0.06, hspace=0.45
    )
    canvas.draw()
    image = np.asarray(canvas.buffer_rgba())[:, :, :3]
    return np.array(image, dtype=np.uint8)  # a copy: the canvas's buffer dies with the figure


def _draw_span(axes: Axes, catenary: CatenaryDefinition, design: Design) -> None:
    length = catenary.span_length
    x = np.linspace(0.0, length, 201)
    positions = np.asarray(design.dropper_positions)
    contact = catenary.contact_wire_height + np.asarray(design.contact_wire_offsets)
    wire_x = np.concatenate([[0.0], positions, [length]])
    wire_z = np.concatenate([[catenary.contact_wire_height], contact, [catenary.contact_wire_height]])
    messenger = estimated_messenger_height(catenary, positions)
    axes.plot(x, estimated_messenger_height(catenary, x), color="tab:blue", label="messenger wire (estimate)")
    axes.vlines(positions, contact, messenger, color="tab:gray", label="droppers")
    axes.plot(wire_x, wire_z, color="tab:red", marker="o", markersize=3, label="contact wire")
    axes.vlines(
        [0.0, length],
        catenary.contact_wire_height - 0.3,
        catenary.messenger_height + 0.2,
        color="black",
        linewidth=3,
        label="supports",
    )
    if catenary.stitch_wire is not None:
        # The stitch wire's sag is only known after shape-finding: say where it is rather than guess it.
        axes.text(
            0.5,
            0.9,
            f"stitch wire ({catenary.stitch_wire.length:g} m, centred on each support; carries "
            "dropper 1) not drawn",
            transform=axes.transAxes,
            ha="center",
            fontsize=7,
            color="tab:gray",
        )
    axes.set_xlim(-0.02 * length, 1.02 * length)
    axes.set_ylabel("height (m)")
    axes.legend(loc="lower center", fontsize=7, ncol=4)


def _draw_heights(axes: Axes, catenary: CatenaryDefinition, design: Design) -> None:
    length = catenary.span_length
    positions = np.concatenate([[0.0], design.dropper_positions, [length]])
    offsets_mm = 1000.0 * np.concatenate([[0.0], design.contact_wire_offsets, [0.0]])
    axes.axhline(0.0, color="tab:gray", linewidth=0.8, linestyle="--")
    axes.plot(positions, offsets_mm, color="tab:red", marker="o", markersize=4)
    axes.set_xlim(-0.02 * length, 1.02 * length)
    limit = max(25.0, 1.1 * float(np.max(np.abs(offsets_mm))))
    axes.set_ylim(-limit, limit)
    axes.set_xlabel("position in the span (m)")
    axes.set_ylabel("Δh contact wire (mm)")
