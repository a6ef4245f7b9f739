"""Plausible ranges of the physical fields of catenary and pantograph definitions (docs/model.md,
'Plausible ranges').

A value outside its field's plausible range is refused before any solve, and where the value times a unit
factor falls inside it, the message names the unit it looks like (``system_height = 1200`` "looks like
millimetres"; a tension of ``27.0`` "looks like kN"). A value inside the range but outside the usual one is
only warned about. The ranges are wide on purpose: they catch slips of units, not unusual designs.

Examples
--------
>>> implausibility("catenary 'x'", "system_height", 1200.0)
"catenary 'x'.system_height = 1200.0 m: looks like millimetres (1.2 m?); must lie in [0.1, 4] m"
>>> plausibility_warning("catenary 'x'", "system_height", 3.5)
"catenary 'x'.system_height = 3.5 m is unusual (usual: 0.3 to 3 m); check the value"
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, NamedTuple


class PlausibleRange(NamedTuple):
    """A field's refused-outside range, usual range and unit (SI)."""

    low: float
    high: float
    usual_low: float
    usual_high: float
    unit: str


_LENGTH_SLIPS = ((1e-3, "millimetres"), (1e-2, "centimetres"))
_SLIPS = {
    "m": _LENGTH_SLIPS,
    "N": ((1e3, "kN"), (1e6, "MN")),
    "N/m": ((1e3, "kN/m"), (1e6, "MN/m")),
    "kg/m": ((1e-3, "g/m"),),
    "kg": ((1e-3, "grams"),),
    "N·m²": (),
    "N·s/m": ((1e3, "kN·s/m"),),
    "1/s": (),
    "s": ((1e-3, "milliseconds"),),
}
"""Unit factors tried on an implausible value: ``value * factor`` inside the range names the unit."""

RANGES: dict[str, PlausibleRange] = {
    # the catenary
    "span_length": PlausibleRange(10.0, 500.0, 30.0, 80.0, "m"),
    "system_height": PlausibleRange(0.1, 4.0, 0.3, 3.0, "m"),
    "contact_wire_height": PlausibleRange(3.5, 8.0, 4.5, 6.5, "m"),
    "contact_stiffness": PlausibleRange(1e3, math.inf, 1e4, 5e5, "N/m"),
    # wires
    "linear_mass": PlausibleRange(0.05, 5.0, 0.1, 2.5, "kg/m"),
    "tension": PlausibleRange(500.0, 80000.0, 1000.0, 40000.0, "N"),
    "axial_stiffness": PlausibleRange(1e4, 1e9, 1e5, 5e7, "N"),
    "bending_stiffness": PlausibleRange(0.0, 5000.0, 0.0, 1000.0, "N·m²"),
    "length": PlausibleRange(2.0, 60.0, 5.0, 30.0, "m"),
    # droppers and supports
    "stiffness": PlausibleRange(1e3, math.inf, 1e4, 1e7, "N/m"),
    "clamp_mass_messenger": PlausibleRange(0.0, 5.0, 0.0, 1.0, "kg"),
    "clamp_mass_contact": PlausibleRange(0.0, 5.0, 0.0, 1.0, "kg"),
    "messenger_stiffness": PlausibleRange(1e3, math.inf, 1e4, 1e8, "N/m"),
    "messenger_mass": PlausibleRange(0.0, 50.0, 0.0, 20.0, "kg"),
    "steady_arm_stiffness": PlausibleRange(50.0, math.inf, 100.0, 1e5, "N/m"),
    "steady_arm_mass": PlausibleRange(0.0, 30.0, 0.0, 10.0, "kg"),
    "alpha": PlausibleRange(0.0, 10.0, 0.0, 2.0, "1/s"),
    "beta": PlausibleRange(0.0, 0.01, 0.0, 1e-3, "s"),
    # the pantograph
    "masses": PlausibleRange(0.5, 100.0, 2.0, 40.0, "kg"),
    "stiffnesses": PlausibleRange(0.0, 1e6, 0.0, 1e5, "N/m"),
    "dampings": PlausibleRange(0.0, 1e4, 0.0, 1e3, "N·s/m"),
}
"""Plausible (refused outside) and usual (warned outside) range of each physical field, by field name.

A spring has no upper bound: a rigid support (a very stiff spring) is a legitimate idealisation, and the slip
of a unit there (kN/m typed for N/m) makes a value too small, which is refused.

The same name means the same range in every record where it stands (a wire's ``tension``, the stitch wire's
too; a dropper's ``linear_mass`` like a wire's), except the ones in :data:`RECORD_RANGES`."""

RECORD_RANGES: dict[tuple[str, str], PlausibleRange] = {
    ("dropper", "axial_stiffness"): PlausibleRange(1e3, 1e8, 1e4, 1e7, "N"),
    ("dropper", "linear_mass"): PlausibleRange(0.0, 2.0, 0.0, 0.5, "kg/m"),
    ("stitch_wire", "tension"): PlausibleRange(100.0, 30000.0, 500.0, 10000.0, "N"),
}
"""Ranges of fields whose name means something else in one record: ``(record, field)``."""


def plausible_range(where: str, name: str) -> PlausibleRange | None:
    """The range of field ``name`` in the record named last in ``where`` (``"catenary 'x'.dropper"``)."""
    record = where.rsplit(".", 1)[-1] if "." in where else ""
    base = name.split("[", 1)[0]
    return RECORD_RANGES.get((record, base), RANGES.get(base))


def implausibility(where: str, name: str, value: float) -> str | None:
    """Why a value lies outside its field's plausible range, naming the unit it looks like; None when inside.

    The message reads ``"<where>.<name> = <value> <unit>: looks like <unit> (<converted>?); must lie in
    [low, high] <unit>"`` (the definitions raise it as a DefinitionError).
    """
    r = plausible_range(where, name)
    if r is None or r.low <= value <= r.high:
        return None
    slip = ""
    for factor, unit in _SLIPS[r.unit]:
        converted = value * factor
        if r.usual_low <= converted <= r.usual_high and converted > 0.0:
            slip = f"looks like {unit} ({converted:g} {r.unit}?); "
            break
    return f"{where}.{name} = {value!r} {r.unit}: {slip}must lie in [{r.low:g}, {r.high:g}] {r.unit}"


def plausibility_warning(where: str, name: str, value: float) -> str | None:
    """A warning for a plausible value outside the usual range, or None."""
    r = plausible_range(where, name)
    if r is None or r.usual_low <= value <= r.usual_high:
        return None
    return (
        f"{where}.{name} = {value!r} {r.unit} is unusual (usual: {r.usual_low:g} to {r.usual_high:g} "
        f"{r.unit}); check the value"
    )


def physical_fields(where: str, record: Any) -> list[tuple[str, str, float]]:
    """Every (where, name, value) of a definition record's numeric fields with a range, nested records
    included (``where`` of a nested one: ``"<where>.<field>"``), array entries as ``name[i]``."""
    found = []
    for f in dataclasses.fields(record):
        value = getattr(record, f.name)
        if dataclasses.is_dataclass(value) and not isinstance(value, type):
            found += physical_fields(f"{where}.{f.name}", value)
        elif isinstance(value, tuple) and plausible_range(where, f.name) is not None:
            found += [(where, f"{f.name}[{i}]", float(v)) for i, v in enumerate(value)]
        elif isinstance(value, float) and plausible_range(where, f.name) is not None:
            found.append((where, f.name, value))
    return found


def definition_warnings(where: str, record: Any) -> list[str]:
    """Warnings for every field of a definition that is plausible but outside its usual range."""
    found = (plausibility_warning(w, name, value) for w, name, value in physical_fields(where, record))
    return [w for w in found if w is not None]
