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
    "uplift_definition": ("nominal-height", "static-contact"),
    "messenger_support": ("hinge", "continuous"),
    "axial_restraint": ("every-support", "section-ends"),
    "linearisation": ("extensible", "transverse-only"),
    "dropper_geometric_stiffness": ("excluded", "included"),
    "clamp_masses": ("point", "distributed"),
    "rayleigh_damping_scope": ("whole-system", "wires-only"),
}
"""The allowed values of every choice."""


@dataclass(frozen=True)
class ModellingOptions:
    """The modelling choices of a catenary model (docs/model.md, 'Modelling choices').

    Attributes
    ----------
    slack_dropper_damping : {"none", "stiffness-proportional"}
        What a slack dropper transmits: ``"none"``, nothing (its spring and its share β k of the Rayleigh
        damping both drop out); ``"stiffness-proportional"``, its damping β k Δl̇ stays while its spring force
        drops out (the damping matrix is that of the taut catenary).
    uplift_definition : {"nominal-height", "static-contact"}
        What the static uplift force F₀ means: ``"nominal-height"``, a force on the frame whose spring
        is relaxed at the contact wire's nominal height h₀, so the frame spring takes part of F₀ as the
        pantograph rises; ``"static-contact"``, the static contact force: the frame spring is relaxed where
        the pantograph stands at static equilibrium on the wire, so the static contact force averaged over
        a span equals F₀.
    messenger_support : {"hinge", "continuous"}
        The messenger's node at an interior support: ``"hinge"``, one position and a separate slope on each
        side; ``"continuous"``, one slope (a C¹ wire across the support).
    axial_restraint : {"every-support", "section-ends"}
        Where the messenger is held along the track in the dynamics: at every support, or only at the ends of
        the section (the supports are then vertical springs only). The wires' ends are held either way.
    linearisation : {"extensible", "transverse-only"}
        ``"extensible"``: the wires keep their axial coordinates and axial stiffness EA in the linearised
        dynamics; ``"transverse-only"``: the wires (and stitch wires) move vertically only, at their static
        axial force (tensioned beams): no axial coordinate, no EA. The statics are extensible either way.
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
    uplift_definition: str = "nominal-height"
    messenger_support: str = "hinge"
    axial_restraint: str = "every-support"
    linearisation: str = "extensible"
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
