"""Modelling choices: how the catenary's data become a model (docs/model.md, 'Modelling choices').

A catenary definition fixes the physical data; :class:`ModellingOptions` fixes the modelling choices that
the data leave open: how a slack dropper behaves, what the pantograph's uplift force means, how the messenger
passes its supports, which axial motions the wires have, and where masses and damping sit. Every choice is an
enumerated string, so that it reads the same in a TOML file (an optional ``[modelling]`` table of a catenary
preset) and in Python. The record is part of the catenary definition, and so of the model fingerprint.

The choices act on what both dynamic models (the exact passage and the span-mode model) consume: the layout,
the matrices M, K and C, the dropper data and the force applied to the pantograph. Two choices give a damping
that is not C = αM + βK with slack droppers dropping their whole force; only the straightforward exact loop
integrates such a model (see :attr:`ModellingOptions.rayleigh_only`).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

CHOICES: dict[str, tuple[str, ...]] = {
    "slack_dropper_damping": ("none", "stiffness-proportional"),
    "uplift_definition": ("static-contact", "nominal-height"),
    "messenger_support": ("continuous", "hinge"),
    "axial_restraint": ("section-ends", "every-support"),
    "linearisation": ("transverse-only", "extensible"),
    "dropper_geometric_stiffness": ("excluded", "included"),
    "clamp_masses": ("point", "distributed"),
    "rayleigh_damping_scope": ("whole-system", "wires-only"),
}
"""The allowed values of every choice, the default first (docs/model.md, 'Modelling choices', argues each
default from the EN 50318:2002 reference model's definition and the physics)."""

FORMER_DEFAULTS = {
    "uplift_definition": "nominal-height",
    "messenger_support": "hinge",
    "axial_restraint": "every-support",
    "linearisation": "extensible",
}
"""The choices whose default changed with physics revision 3 (docs/model.md, 'Model revisions'), and
their former default: ``ModellingOptions(**FORMER_DEFAULTS)`` is the model of revision 2."""


@dataclass(frozen=True)
class ModellingOptions:
    """The modelling choices of a catenary model (docs/model.md, 'Modelling choices').

    Attributes
    ----------
    slack_dropper_damping : {"none", "stiffness-proportional"}
        What a slack dropper transmits: ``"none"``, nothing (its spring and its share β k of the Rayleigh
        damping both drop out); ``"stiffness-proportional"``, its damping β k Δl̇ stays while its spring force
        drops out (the damping matrix is that of the taut catenary).
    uplift_definition : {"static-contact", "nominal-height"}
        What the static uplift force F₀ means: ``"static-contact"``, the static contact force: the frame
        spring is relaxed where the pantograph stands at static equilibrium on the wire, so the static
        contact force averaged over a span equals F₀; ``"nominal-height"``, a force on the frame whose spring
        is relaxed at the contact wire's nominal height h₀, so the frame spring takes part of F₀ as the
        pantograph rises.
    messenger_support : {"continuous", "hinge"}
        The messenger's node at an interior support: ``"continuous"``, one slope (a C¹ wire across the
        support, its bend resolved by the layout); ``"hinge"``, one position and a slope on each side.
    axial_restraint : {"section-ends", "every-support"}
        Where the messenger is held along the track, in the dynamics and the static analysis: only at the
        ends of the section (the supports are vertical springs only), or at every support. The wires' ends
        are held either way.
    linearisation : {"transverse-only", "extensible"}
        ``"transverse-only"``: the wires (and stitch wires) move vertically only, at their static axial force
        (tensioned beams): no axial coordinate, no EA; ``"extensible"``: the wires keep their axial
        coordinates and axial stiffness EA in the linearised dynamics. The statics are extensible either way.
    dropper_geometric_stiffness : {"excluded", "included"}
        Whether the droppers' geometric stiffness N/l (across the dropper, i.e. along the track) enters K.
        Included, it stays when the dropper goes slack; only the axial spring switches off.
    clamp_masses : {"point", "distributed"}
        The dropper clamps and the steady arms: point masses at their nodes, or spread uniformly along the
        wire they sit on, span by span (same mass and weight per span).
    rayleigh_damping_scope : {"whole-system", "wires-only"}
        C = αM + βK over the whole catenary, or over the wires only (their mass and tangent stiffness, the
        stitch wires included): no damping from droppers, support springs, steady arms and point masses.
    """

    slack_dropper_damping: str = "none"
    uplift_definition: str = "static-contact"
    messenger_support: str = "continuous"
    axial_restraint: str = "section-ends"
    linearisation: str = "transverse-only"
    dropper_geometric_stiffness: str = "excluded"
    clamp_masses: str = "point"
    rayleigh_damping_scope: str = "whole-system"

    def invalid(self) -> tuple[str, str] | None:
        """The first field whose value is not one of :data:`CHOICES`, and its value; None if all are valid."""
        for f in fields(self):
            value = getattr(self, f.name)
            if value not in CHOICES[f.name]:
                return f.name, value
        return None

    @property
    def rayleigh_only(self) -> bool:
        """True when C = αM + βK and a slack dropper drops its whole force: what the fast loops integrate."""
        return self.slack_dropper_damping == "none" and self.rayleigh_damping_scope == "whole-system"

    def changed(self) -> dict[str, str]:
        """The choices that differ from the defaults, by field name."""
        default = ModellingOptions()
        return {
            f.name: getattr(self, f.name)
            for f in fields(self)
            if getattr(self, f.name) != getattr(default, f.name)
        }
