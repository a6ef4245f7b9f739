"""Catenary and pantograph definitions: the physical data of a model, as typed frozen records.

A definition is pure data (SI units: m, kg, N, s). It is read from a TOML file by
:mod:`catenary_env.model.presets` and validated on construction: every record checks its own fields
and raises :class:`DefinitionError` naming the field and the allowed range, so a bad file fails
before any solve (README.md, 'Command line').

Positions along the track ``x`` are measured from the span's first support.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ..errors import CatenaryError
from .options import CHOICES, ModellingOptions
from .plausibility import implausibility, physical_fields


class DefinitionError(CatenaryError, ValueError):
    """An invalid catenary or pantograph definition; the message names the field and the allowed range."""


def check_plausible_fields(where: str, record: object) -> None:
    """Refuse the first numeric field of a definition outside its plausible range (docs/model.md, 'Plausible
    ranges'), naming the field and the unit the value looks like."""
    for w, name, value in physical_fields(where, record):
        problem = implausibility(w, name, value)
        if problem is not None:
            raise DefinitionError(problem)


def _check_positive(where: str, name: str, value: float, allow_zero: bool = False) -> None:
    ok = math.isfinite(value) and (value >= 0.0 if allow_zero else value > 0.0)
    if not ok:
        bound = ">= 0" if allow_zero else "> 0"
        raise DefinitionError(f"{where}.{name} = {value!r}: must be a finite number {bound}")


@dataclass(frozen=True)
class Wire:
    """A tensioned wire (contact wire or messenger wire), modelled with ANCF cable elements.

    Attributes
    ----------
    linear_mass : float
        Mass per unit (unstretched) length, kg/m.
    tension : float
        Tension applied by the tensioning device, N. The shape-finding imposes it as the horizontal
        component of the wire force, which is the same in every element of the wire.
    axial_stiffness : float
        EA, N.
    bending_stiffness : float
        EI, N·m².
    """

    linear_mass: float
    tension: float
    axial_stiffness: float
    bending_stiffness: float

    def validate(self, where: str) -> None:
        _check_positive(where, "linear_mass", self.linear_mass)
        _check_positive(where, "tension", self.tension)
        _check_positive(where, "axial_stiffness", self.axial_stiffness)
        _check_positive(where, "bending_stiffness", self.bending_stiffness, allow_zero=True)
        if self.tension >= 0.05 * self.axial_stiffness:
            raise DefinitionError(
                f"{where}.tension = {self.tension!r}: must be below 5 % of axial_stiffness "
                f"({0.05 * self.axial_stiffness:g} N); a larger strain is outside the model"
            )

    @property
    def wave_speed(self) -> float:
        """Transverse wave speed sqrt(T / rho A), m/s."""
        return math.sqrt(self.tension / self.linear_mass)


@dataclass(frozen=True)
class StitchWire:
    """A stitch wire centred on each support, hung from the messenger wire at both ends (bar elements).

    The first dropper on each side of a support hangs from the stitch wire instead of the messenger.

    Attributes
    ----------
    length : float
        Total length along the track, centred on the support, m.
    linear_mass : float
        kg/m.
    tension : float
        Horizontal tension, N.
    axial_stiffness : float
        EA, N.
    """

    length: float
    linear_mass: float
    tension: float
    axial_stiffness: float

    def validate(self, where: str) -> None:
        _check_positive(where, "length", self.length)
        _check_positive(where, "linear_mass", self.linear_mass)
        _check_positive(where, "tension", self.tension)
        _check_positive(where, "axial_stiffness", self.axial_stiffness)


@dataclass(frozen=True)
class Dropper:
    """Dropper data: a tension-only bar joining the messenger (or stitch wire) to the contact wire.

    Exactly one of ``stiffness`` (a spring rate independent of length, as in EN 50318:2002) and
    ``axial_stiffness`` (EA, so that the rate is EA / length) is given.

    Attributes
    ----------
    stiffness : float or None
        Spring rate in tension, N/m.
    axial_stiffness : float or None
        EA, N.
    linear_mass : float
        kg/m.
    clamp_mass_messenger : float
        Point mass of the clamp on the messenger (or stitch) wire, kg.
    clamp_mass_contact : float
        Point mass of the clamp on the contact wire, kg.
    """

    stiffness: float | None
    axial_stiffness: float | None
    linear_mass: float
    clamp_mass_messenger: float
    clamp_mass_contact: float

    def validate(self, where: str) -> None:
        if (self.stiffness is None) == (self.axial_stiffness is None):
            raise DefinitionError(f"{where}: give exactly one of 'stiffness' (N/m) and 'axial_stiffness' (N)")
        if self.stiffness is not None:
            _check_positive(where, "stiffness", self.stiffness)
        if self.axial_stiffness is not None:
            _check_positive(where, "axial_stiffness", self.axial_stiffness)
        _check_positive(where, "linear_mass", self.linear_mass, allow_zero=True)
        _check_positive(where, "clamp_mass_messenger", self.clamp_mass_messenger, allow_zero=True)
        _check_positive(where, "clamp_mass_contact", self.clamp_mass_contact, allow_zero=True)

    def spring_rate(self, length: float) -> float:
        """Axial spring rate in tension for an unstretched length, N/m."""
        if self.stiffness is not None:
            return self.stiffness
        assert self.axial_stiffness is not None
        return self.axial_stiffness / length


@dataclass(frozen=True)
class Supports:
    """Support data at every support (cantilever) of the section.

    Attributes
    ----------
    messenger_stiffness : float
        Vertical spring of the messenger-wire support, N/m. The horizontal position is held.
    messenger_mass : float
        Lumped mass at the messenger support point, kg.
    steady_arm_stiffness : float
        Vertical spring of the steady arm at the contact-wire support point, N/m.
    steady_arm_mass : float
        Lumped steady-arm mass at the contact-wire support point, kg.
    """

    messenger_stiffness: float
    messenger_mass: float
    steady_arm_stiffness: float
    steady_arm_mass: float

    def validate(self, where: str) -> None:
        _check_positive(where, "messenger_stiffness", self.messenger_stiffness)
        _check_positive(where, "messenger_mass", self.messenger_mass, allow_zero=True)
        _check_positive(where, "steady_arm_stiffness", self.steady_arm_stiffness)
        _check_positive(where, "steady_arm_mass", self.steady_arm_mass, allow_zero=True)


@dataclass(frozen=True)
class RayleighDamping:
    """Rayleigh damping C = alpha M + beta K.

    Attributes
    ----------
    alpha : float
        Mass-proportional coefficient, 1/s.
    beta : float
        Stiffness-proportional coefficient, s.
    """

    alpha: float
    beta: float

    def validate(self, where: str) -> None:
        _check_positive(where, "alpha", self.alpha, allow_zero=True)
        _check_positive(where, "beta", self.beta, allow_zero=True)


@dataclass(frozen=True)
class CatenaryDefinition:
    """A catenary: wires, droppers, supports, and the reference geometry of one span.

    All spans of a section are equal. Heights ``z`` are absolute (above rail level).

    Attributes
    ----------
    name : str
        Identifier, e.g. ``"benchmark"``.
    span_length : float
        Distance between supports, m.
    dropper_positions : tuple of float
        Reference dropper positions in a span, m from the span's first support, increasing.
    system_height : float
        Messenger-wire height above the contact wire at the supports, m.
    contact_wire_height : float
        Contact-wire height at the supports, m.
    contact_wire, messenger_wire : Wire
    stitch_wire : StitchWire or None
    dropper : Dropper
    supports : Supports
    damping : RayleighDamping
    contact_stiffness : float
        Penalty stiffness of the pantograph-contact wire contact, N/m.
    n_spans : int
        Default number of spans in a section.
    analysis_spans : int
        Default number of central spans over which statistics are taken.
    pantograph : str
        Name of the default pantograph preset.
    modelling : ModellingOptions
        The modelling choices (the optional ``[modelling]`` table of a preset; docs/model.md, 'Modelling
        choices').
    provenance : dict
        Source tag of figures, keyed by dotted field name (``"contact_wire.axial_stiffness"``):
        ``S`` standard data, ``S?`` single source, ``A`` assumption (see docs/model.md, 'Data and sources').
    """

    name: str
    span_length: float
    dropper_positions: tuple[float, ...]
    system_height: float
    contact_wire_height: float
    contact_wire: Wire
    messenger_wire: Wire
    stitch_wire: StitchWire | None
    dropper: Dropper
    supports: Supports
    damping: RayleighDamping
    contact_stiffness: float
    n_spans: int = 20
    analysis_spans: int = 10
    pantograph: str = ""
    modelling: ModellingOptions = field(default_factory=ModellingOptions)
    provenance: dict[str, str] = field(default_factory=dict, compare=False, hash=False)

    def __post_init__(self) -> None:
        where = f"catenary '{self.name}'"
        if not isinstance(self.modelling, ModellingOptions):
            raise DefinitionError(f"{where}.modelling: expected a ModellingOptions record")
        bad = self.modelling.invalid()
        if bad is not None:
            name, value = bad
            raise DefinitionError(
                f"{where}.modelling.{name} = {value!r}: must be one of {', '.join(map(repr, CHOICES[name]))}"
            )
        _check_positive(where, "span_length", self.span_length)
        _check_positive(where, "system_height", self.system_height)
        _check_positive(where, "contact_wire_height", self.contact_wire_height)
        _check_positive(where, "contact_stiffness", self.contact_stiffness)
        self.contact_wire.validate(f"{where}.contact_wire")
        self.messenger_wire.validate(f"{where}.messenger_wire")
        if self.stitch_wire is not None:
            self.stitch_wire.validate(f"{where}.stitch_wire")
        self.dropper.validate(f"{where}.dropper")
        self.supports.validate(f"{where}.supports")
        self.damping.validate(f"{where}.damping")
        # Before the droppers: a span typed in millimetres is named as such, not as droppers out of the span.
        check_plausible_fields(where, self)
        check_dropper_positions(self.dropper_positions, self.span_length, f"{where}.dropper_positions")
        if self.stitch_wire is not None:
            check_stitch_reach(self.dropper_positions, self.stitch_wire.length, self.span_length, where)
        if not (isinstance(self.n_spans, int) and 3 <= self.n_spans <= 200):
            raise DefinitionError(f"{where}.n_spans = {self.n_spans!r}: must be an integer in [3, 200]")
        if not (isinstance(self.analysis_spans, int) and 1 <= self.analysis_spans <= self.n_spans - 2):
            raise DefinitionError(
                f"{where}.analysis_spans = {self.analysis_spans!r}: must be an integer in [1, n_spans - 2]"
            )

    @property
    def messenger_height(self) -> float:
        """Messenger-wire height at the supports, m."""
        return self.contact_wire_height + self.system_height

    @property
    def wave_speed(self) -> float:
        """Transverse wave speed of the contact wire, m/s (the upper bound of the train speed)."""
        return self.contact_wire.wave_speed


def check_dropper_positions(positions: tuple[float, ...], span_length: float, where: str) -> None:
    """Check that dropper positions lie strictly inside the span, increase, and are mirror-symmetric.

    Raises
    ------
    DefinitionError
        Naming ``where`` and the allowed range.
    """
    if len(positions) < 1:
        raise DefinitionError(f"{where}: at least one dropper per span is needed")
    for i, x in enumerate(positions):
        if not (math.isfinite(x) and 0.0 < x < span_length):
            raise DefinitionError(f"{where}[{i}] = {x!r}: must lie in (0, {span_length}) m, inside the span")
        if i > 0 and x <= positions[i - 1] + 0.05:
            raise DefinitionError(
                f"{where}[{i}] = {x!r}: droppers must not cross; must exceed the previous dropper "
                f"({positions[i - 1]} m) by at least 0.05 m"
            )
    mirrored = [span_length - x for x in reversed(positions)]
    if max(abs(a - b) for a, b in zip(positions, mirrored, strict=True)) > 1e-6:
        raise DefinitionError(f"{where}: dropper positions must be symmetric about mid-span")


def check_stitch_reach(
    positions: tuple[float, ...], stitch_length: float, span_length: float, where: str
) -> None:
    """Check that the first dropper on each side of a support, and only it, hangs from the stitch wire."""
    half = 0.5 * stitch_length
    if not (half < 0.5 * span_length):
        raise DefinitionError(
            f"{where}.stitch_wire.length = {stitch_length!r}: must be below the span length"
        )
    if not (positions[0] < half) or (len(positions) > 1 and positions[1] <= half):
        raise DefinitionError(
            f"{where}.dropper_positions: the first dropper must lie within the stitch wire's half-length "
            f"({half} m) of the support, and the second beyond it; got {positions[:2]}"
        )


@dataclass(frozen=True)
class PantographDefinition:
    """A lumped-mass pantograph: a chain of masses from the frame (bottom) to the head (top).

    Spring ``i`` and damper ``i`` join mass ``i`` to the one below it (mass 0 to the ground).

    Attributes
    ----------
    name : str
    masses : tuple of float
        kg, bottom (frame) first, head last; 2 or 3 masses.
    stiffnesses : tuple of float
        N/m, same length as ``masses``.
    dampings : tuple of float
        N·s/m, same length as ``masses``.
    uplift_force : float or None
        Static uplift force on the bottom mass, N. ``None`` when a study sets it from a target mean
        contact force (docs/model.md, 'Pantograph and contact').
    provenance : dict
        Source tags, as in :class:`CatenaryDefinition`.
    """

    name: str
    masses: tuple[float, ...]
    stiffnesses: tuple[float, ...]
    dampings: tuple[float, ...]
    uplift_force: float | None = None
    provenance: dict[str, str] = field(default_factory=dict, compare=False, hash=False)

    def __post_init__(self) -> None:
        where = f"pantograph '{self.name}'"
        n = len(self.masses)
        if n not in (2, 3):
            raise DefinitionError(f"{where}.masses: 2 or 3 masses expected, got {n}")
        for name in ("stiffnesses", "dampings"):
            if len(getattr(self, name)) != n:
                raise DefinitionError(f"{where}.{name}: must have {n} values, one per mass")
        for i, m in enumerate(self.masses):
            _check_positive(where, f"masses[{i}]", m)
        for i, k in enumerate(self.stiffnesses):
            _check_positive(where, f"stiffnesses[{i}]", k, allow_zero=(i == 0))
        for i, c in enumerate(self.dampings):
            _check_positive(where, f"dampings[{i}]", c, allow_zero=True)
        if self.uplift_force is not None:
            _check_positive(where, "uplift_force", self.uplift_force)
        check_plausible_fields(where, self)
