"""Catenary and pantograph presets: recorded values, provenance tags, and validation on load (docs/model.md,
'Data and sources').

Values and tags are those of docs/model.md, 'Data and sources'; a failure here means a preset file drifted
from it.
"""

from __future__ import annotations

import dataclasses
import re
import shutil
from pathlib import Path
from typing import Any

import pytest

from catenary_env.model.definition import CatenaryDefinition, DefinitionError, PantographDefinition
from catenary_env.model.presets import (
    catenary_names,
    load_catenary,
    load_pantograph,
    pantograph_names,
    preset_path,
)

# ---------------------------------------------------------------------------------------------------------
# Helpers


def _copy_with(tmp_path: Path, kind: str, name: str, *edits: tuple[str, str], filename: str = "") -> Path:
    """Copy a preset file to ``tmp_path``, replacing in order each ``old`` text (found once) by ``new``."""
    text = preset_path(kind, name).read_text(encoding="utf-8")
    for old, new in edits:
        assert text.count(old) == 1, f"edit target {old!r} must occur once in {name}.toml"
        text = text.replace(old, new)
    target = tmp_path / (filename or f"my-{name}.toml")
    target.write_text(text, encoding="utf-8")
    return target


def _leaf_fields(record: Any, prefix: str = "") -> list[str]:
    """Dotted names of the figures of a record (nested records walked; name, provenance, None skipped, and
    the modelling choices, which are not figures: docs/model.md, 'Modelling choices')."""
    names: list[str] = []
    for f in dataclasses.fields(record):
        value = getattr(record, f.name)
        if f.name in ("name", "provenance", "modelling") or value is None:
            continue
        if dataclasses.is_dataclass(value):
            names += _leaf_fields(value, prefix + f.name + ".")
        else:
            names.append(prefix + f.name)
    return names


def _comment(text: str, dotted: str) -> str:
    """The TOML comment on the line that sets ``dotted``; for a key left out, the comment lines naming it."""
    table, _, key = dotted.rpartition(".")
    current = ""
    for line in text.splitlines():
        header = re.fullmatch(r"\[(\w+)\]\s*", line)
        if header:
            current = header.group(1)
        elif current == table and re.match(rf"{key}\s*=", line):
            return line.partition("#")[2]
    return "\n".join(line for line in text.splitlines() if line.startswith("#") and key in line)


# ---------------------------------------------------------------------------------------------------------
# Recorded values (docs/model.md, 'Data and sources')

CATENARIES = ["benchmark", "en50318-2002", "stitched"]
PANTOGRAPHS = ["benchmark", "en50318-2002"]


def test_names_list_the_shipped_presets() -> None:
    assert catenary_names() == CATENARIES
    assert pantograph_names() == PANTOGRAPHS


@pytest.mark.parametrize("name", CATENARIES)
def test_every_catenary_preset_loads_with_its_name_and_pantograph(name: str) -> None:
    catenary = load_catenary(name)
    assert isinstance(catenary, CatenaryDefinition)
    assert catenary.name == name
    assert catenary.pantograph in PANTOGRAPHS
    assert load_catenary(preset_path("catenary", name)) == catenary  # by path as by name


@pytest.mark.parametrize("name", PANTOGRAPHS)
def test_every_pantograph_preset_loads_with_its_name(name: str) -> None:
    pantograph = load_pantograph(name)
    assert isinstance(pantograph, PantographDefinition)
    assert pantograph.name == name


def test_en50318_2002_values() -> None:
    c = load_catenary("en50318-2002")
    assert c.span_length == 60.0
    assert c.dropper_positions == (5.0, 10.5, 17.0, 23.5, 30.0, 36.5, 43.0, 49.5, 55.0)
    assert (c.system_height, c.contact_wire_height) == (1.2, 5.3)
    cw = c.contact_wire
    assert (cw.linear_mass, cw.tension, cw.bending_stiffness) == (1.35, 2e4, 195.0)
    assert (c.messenger_wire.linear_mass, c.messenger_wire.tension) == (1.07, 1.6e4)
    assert (c.contact_wire.axial_stiffness, c.messenger_wire.axial_stiffness) == (1.8e7, 1.2e7)
    assert c.dropper.stiffness == 1e5 and c.dropper.axial_stiffness is None
    assert (c.dropper.clamp_mass_messenger, c.dropper.clamp_mass_contact) == (0.195, 0.165)
    assert c.supports == type(c.supports)(5e4, 0.0, 300.0, 0.0)
    assert (c.damping.alpha, c.damping.beta, c.contact_stiffness) == (0.0125, 1e-4, 5e4)
    assert (c.n_spans, c.analysis_spans, c.stitch_wire) == (10, 2, None)
    p = load_pantograph("en50318-2002")
    assert p.masses == (15.0, 7.2)
    assert p.stiffnesses == (50.0, 4200.0)
    assert p.dampings == (90.0, 10.0)
    assert p.uplift_force == 117.5


def test_benchmark_values() -> None:
    c = load_catenary("benchmark")
    assert c.span_length == 55.0
    assert c.dropper_positions == (4.5, 10.25, 16.0, 21.75, 27.5, 33.25, 39.0, 44.75, 50.5)
    assert c.contact_wire.tension == 22000.0
    assert (c.messenger_wire.linear_mass, c.messenger_wire.tension, c.messenger_wire.bending_stiffness) == (
        1.08,
        16000.0,
        131.7,
    )
    assert c.dropper.axial_stiffness == 2e5 and c.dropper.stiffness is None
    assert c.dropper.linear_mass == 0.117
    assert c.supports == type(c.supports)(5e5, 0.0, 2673.58, 1.0)
    assert (c.contact_stiffness, c.n_spans, c.analysis_spans, c.stitch_wire) == (5e4, 20, 10, None)
    p = load_pantograph("benchmark")
    assert p.masses == (6.0, 9.0, 7.5)
    assert p.stiffnesses == (160.0, 15500.0, 7000.0)
    assert p.dampings == (100.0, 0.0, 0.0)
    assert p.uplift_force is None  # set by the study (docs/model.md, 'Pantograph and contact')


def test_stitched_values() -> None:
    c = load_catenary("stitched")
    assert c.span_length == 65.0
    assert c.dropper_positions == (4.5, 14.0, 23.25, 32.5, 41.75, 51.0, 60.5)
    assert c.stitch_wire is not None
    assert (
        c.stitch_wire.length,
        c.stitch_wire.linear_mass,
        c.stitch_wire.tension,
        c.stitch_wire.axial_stiffness,
    ) == (18.0, 0.31, 3500.0, 3.5e6)
    assert (c.contact_wire.tension, c.messenger_wire.tension) == (27e3, 21e3)
    assert c.messenger_wire.linear_mass == 1.07
    assert c.system_height == 1.6
    assert c.pantograph == "benchmark"


def test_stitched_shares_the_benchmark_droppers_supports_damping_and_contact() -> None:
    stitched, benchmark = load_catenary("stitched"), load_catenary("benchmark")
    for name in ("dropper", "supports", "damping", "contact_stiffness", "contact_wire_height"):
        assert getattr(stitched, name) == getattr(benchmark, name), name


# ---------------------------------------------------------------------------------------------------------
# Provenance

# Every figure tagged [A] in docs/model.md, 'Data and sources', by preset (a study setting is tagged A as
# well, and so is a figure models.md does not give, set to zero).
ASSUMED = {
    ("catenary", "en50318-2002"): [
        "contact_wire.axial_stiffness",
        "messenger_wire.axial_stiffness",
        "dropper.linear_mass",
        "dropper.clamp_mass_messenger",
        "dropper.clamp_mass_contact",
        "system_height",
        "contact_wire_height",
        "analysis_spans",
        "supports.messenger_mass",
        "supports.steady_arm_mass",
    ],
    ("pantograph", "en50318-2002"): ["uplift_force"],
    ("catenary", "benchmark"): [
        "contact_wire_height",
        "contact_wire.axial_stiffness",
        "messenger_wire.axial_stiffness",
        "supports.steady_arm_mass",
        "supports.messenger_mass",
        "damping.alpha",
        "damping.beta",
        "contact_stiffness",
        "n_spans",
        "analysis_spans",
    ],
    ("pantograph", "benchmark"): ["dampings", "uplift_force"],
    ("catenary", "stitched"): [
        "span_length",
        "dropper_positions",
        "system_height",
        "contact_wire_height",
        "contact_stiffness",
        "n_spans",
        "analysis_spans",
        "pantograph",
        *(
            f"{wire}.{f}"
            for wire in ("contact_wire", "messenger_wire")
            for f in ("linear_mass", "tension", "bending_stiffness", "axial_stiffness")
        ),
        *(f"stitch_wire.{f}" for f in ("length", "linear_mass", "tension", "axial_stiffness")),
        *(
            f"dropper.{f}"
            for f in ("axial_stiffness", "linear_mass", "clamp_mass_messenger", "clamp_mass_contact")
        ),
        *(
            f"supports.{f}"
            for f in ("messenger_stiffness", "messenger_mass", "steady_arm_stiffness", "steady_arm_mass")
        ),
        "damping.alpha",
        "damping.beta",
    ],
}

# A sample of the [S] and [S?] figures.
SOURCED = {
    ("catenary", "en50318-2002"): {
        "span_length": "S",
        "dropper.stiffness": "S",
        "contact_wire.tension": "S",
        "supports.steady_arm_stiffness": "S",
        "damping.alpha": "S",
        "n_spans": "S",
    },
    ("pantograph", "en50318-2002"): {"masses": "S?", "stiffnesses": "S?", "dampings": "S?"},
    ("catenary", "benchmark"): {
        "span_length": "S?",
        "dropper_positions": "S?",
        "system_height": "S?",
        "dropper.axial_stiffness": "S?",
        "supports.steady_arm_stiffness": "S?",
        "messenger_wire.linear_mass": "S?",
    },
    ("pantograph", "benchmark"): {"masses": "S?", "stiffnesses": "S?"},
}


def _load(kind: str, name: str) -> CatenaryDefinition | PantographDefinition:
    return load_catenary(name) if kind == "catenary" else load_pantograph(name)


def _tag(note: str) -> str:
    return note.partition(":")[0]


@pytest.mark.parametrize(("kind", "name"), list(ASSUMED))
def test_every_assumed_figure_is_tagged_a_in_provenance_and_in_a_comment(kind: str, name: str) -> None:
    record = _load(kind, name)
    text = preset_path(kind, name).read_text(encoding="utf-8")
    for dotted in ASSUMED[(kind, name)]:
        note = record.provenance.get(dotted, "")
        assert _tag(note) == "A", f"{name}: {dotted} needs an 'A: ...' provenance entry"
        assert len(note) > len("A: "), f"{name}: {dotted} needs a note"
        assert "[A]" in _comment(text, dotted), f"{name}.toml: the line of {dotted} needs an [A] comment"


@pytest.mark.parametrize(("kind", "name"), list(SOURCED))
def test_sourced_figures_carry_their_tag(kind: str, name: str) -> None:
    record = _load(kind, name)
    text = preset_path(kind, name).read_text(encoding="utf-8")
    for dotted, tag in SOURCED[(kind, name)].items():
        assert _tag(record.provenance[dotted]) == tag, dotted
        assert f"[{tag}]" in _comment(text, dotted), dotted


@pytest.mark.parametrize(("kind", "name"), list(ASSUMED))
def test_every_figure_of_a_preset_has_a_provenance_entry(kind: str, name: str) -> None:
    record = _load(kind, name)
    assert set(_leaf_fields(record)) <= set(record.provenance)
    assert all(_tag(note) in ("S", "S?", "A") for note in record.provenance.values())


def test_provenance_key_that_names_no_field_is_refused(tmp_path: Path) -> None:
    path = _copy_with(
        tmp_path, "catenary", "benchmark", ('"contact_wire.tension" =', '"contact_wire.tensoin" =')
    )
    with pytest.raises(DefinitionError, match=r'provenance\."contact_wire\.tensoin": names no field'):
        load_catenary(path)


def test_provenance_tag_must_start_with_s_s_or_a(tmp_path: Path) -> None:
    path = _copy_with(
        tmp_path, "pantograph", "benchmark", ('"masses" = "S?: single source"', '"masses" = "measured"')
    )
    with pytest.raises(DefinitionError, match=r'provenance\."masses" = \'measured\''):
        load_pantograph(path)


def test_provenance_accepts_indexed_and_unquoted_dotted_keys(tmp_path: Path) -> None:
    path = _copy_with(tmp_path, "pantograph", "benchmark", ('"dampings" = "A:', '"dampings[0]" = "A:'))
    assert _tag(load_pantograph(path).provenance["dampings[0]"]) == "A"
    path = _copy_with(tmp_path, "catenary", "benchmark", ('"damping.beta" =', "damping.beta ="))
    assert _tag(load_catenary(path).provenance["damping.beta"]) == "A"
    path = _copy_with(tmp_path, "pantograph", "benchmark", ('"dampings" = "A:', '"dampings[3]" = "A:'))
    with pytest.raises(DefinitionError, match=r'"dampings\[3\]": index out of range'):
        load_pantograph(path)


# ---------------------------------------------------------------------------------------------------------
# A user's edited copy


def test_an_edited_copy_loads_with_the_new_value(tmp_path: Path) -> None:
    path = _copy_with(
        tmp_path,
        "catenary",
        "benchmark",
        ("tension = 22000.0", "tension = 25000.0"),
        ('name = "benchmark"', 'name = "my-benchmark"'),
    )
    catenary = load_catenary(str(path))
    assert catenary.name == "my-benchmark"
    assert catenary.contact_wire.tension == 25000.0
    assert catenary.messenger_wire == load_catenary("benchmark").messenger_wire


def test_an_edited_pantograph_copy_loads_with_the_new_value(tmp_path: Path) -> None:
    path = _copy_with(
        tmp_path,
        "pantograph",
        "benchmark",
        ("# To fix it instead, add:  uplift_force = <N>", "uplift_force = 160.0"),
    )
    assert load_pantograph(path).uplift_force == 160.0


def test_a_relative_pantograph_path_resolves_next_to_the_catenary_file(tmp_path: Path) -> None:
    shutil.copy(preset_path("pantograph", "benchmark"), tmp_path / "my-pantograph.toml")
    path = _copy_with(
        tmp_path, "catenary", "benchmark", ('pantograph = "benchmark"', 'pantograph = "my-pantograph.toml"')
    )
    catenary = load_catenary(path)
    assert Path(catenary.pantograph) == (tmp_path / "my-pantograph.toml").resolve()
    assert load_pantograph(catenary.pantograph) == load_pantograph("benchmark")


# ---------------------------------------------------------------------------------------------------------
# Invalid definitions: each error names the file and the field (docs/model.md, 'Data and sources')


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        (("tension = 22000.0", "tension = -22000.0"), r"contact_wire\.tension = -22000\.0: must be .*> 0"),
        (("linear_mass = 1.08", "linear_mass = -1.08"), r"messenger_wire\.linear_mass = -1\.08"),
        (("clamp_mass_contact = 0.165", "clamp_mass_contact = -0.165"), r"dropper\.clamp_mass_contact"),
        (("steady_arm_mass = 1.0", "steady_arm_mass = -1.0"), r"supports\.steady_arm_mass = -1\.0"),
        (("[4.5, 10.25", "[-1.0, 10.25"), r"dropper_positions\[0\] = -1\.0: must lie in \(0, 55\.0\)"),
        (("44.75, 50.5]", "44.75, 56.0]"), r"dropper_positions\[8\] = 56\.0: must lie in \(0, 55\.0\)"),
        (("10.25, 16.0,", "16.0, 10.25,"), r"dropper_positions\[2\] = 10\.25: droppers must not cross"),
        (
            ("tension = 22000.0", "tensoin = 22000.0"),
            r"contact_wire\.tensoin: unknown field \(did you mean 'tension'\?\); allowed: axial_stiffness, ",
        ),
        (("[supports]", "[suports]"), r"suports: unknown field"),
        (("tension = 22000.0 ", "# tension = 22000.0 "), r"contact_wire\.tension: missing required field"),
        (('name = "benchmark"\n', ""), r"name: missing required field"),
        (
            ("tension = 22000.0", 'tension = "22 kN"'),
            r"contact_wire\.tension = '22 kN': expected a number, got a string",
        ),
        (("n_spans = 20", "n_spans = 20.0"), r"n_spans = 20\.0: expected an integer, got a float"),
        (("n_spans = 20", "n_spans = true"), r"n_spans = True: expected an integer, got a boolean"),
        (("n_spans = 20", "n_spans = 2"), r"n_spans = 2: must be an integer in \[3, 200\]"),
        (("[4.5, 10.25", '["4.5", 10.25'), r"dropper_positions\[0\] = '4\.5': expected a number"),
        (
            ("axial_stiffness = 2.0e5", "stiffness = 2.0e5\naxial_stiffness = 2.0e5"),
            r"dropper: give exactly one of 'stiffness'",
        ),
        (
            ('pantograph = "benchmark"', 'pantograph = "pantograph-x"'),
            r"pantograph = 'pantograph-x': unknown pantograph preset; available: benchmark, en50318-2002",
        ),
        (
            ("span_length = 55.0", "span_length = [55.0]"),
            r"span_length = \[55\.0\]: expected a number, got an array",
        ),
    ],
)
def test_invalid_catenary_is_refused_naming_the_file_and_field(
    tmp_path: Path, edit: tuple[str, str], field: str
) -> None:
    path = _copy_with(tmp_path, "catenary", "benchmark", edit)
    with pytest.raises(DefinitionError, match=field) as error:
        load_catenary(path)
    assert str(path) in str(error.value)


def test_missing_table_is_named(tmp_path: Path) -> None:
    text = preset_path("catenary", "benchmark").read_text(encoding="utf-8")
    damping = re.search(r"\[damping\]\n(.*\n)*?\n", text)
    assert damping is not None
    path = _copy_with(tmp_path, "catenary", "benchmark", (damping.group(0), ""))
    with pytest.raises(DefinitionError, match=r"damping: missing required table \[damping\]"):
        load_catenary(path)


def test_invalid_stitch_wire_is_refused(tmp_path: Path) -> None:
    path = _copy_with(tmp_path, "catenary", "stitched", ("tension = 3500.0", "tension = -3500.0"))
    with pytest.raises(DefinitionError, match=r"stitch_wire\.tension = -3500\.0"):
        load_catenary(path)
    path = _copy_with(tmp_path, "catenary", "stitched", ("length = 18.0", "length = 30.0"))
    with pytest.raises(DefinitionError, match=r"the first dropper must lie within the stitch wire"):
        load_catenary(path)


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        (("masses = [6.0, 9.0, 7.5]", "masses = [6.0]"), r"masses: 2 or 3 masses expected, got 1"),
        (("masses = [6.0, 9.0, 7.5]", "masses = [6.0, 9.0]"), r"stiffnesses: must have 2 values"),
        (("[160.0, 15500.0, 7000.0]", "[160.0, -15500.0, 7000.0]"), r"stiffnesses\[1\] = -15500\.0"),
        (("masses = [6.0, 9.0, 7.5]", "masses = [6.0, 9.0, -7.5]"), r"masses\[2\] = -7\.5"),
        (
            ("dampings = [100.0, 0.0, 0.0]", "damping = [100.0, 0.0, 0.0]"),
            r"damping: unknown field \(did you mean 'dampings'\?\)",
        ),
        (("# To fix it instead, add:  uplift_force = <N>", "uplift_force = -1.0"), r"uplift_force = -1\.0"),
    ],
)
def test_invalid_pantograph_is_refused_naming_the_file_and_field(
    tmp_path: Path, edit: tuple[str, str], field: str
) -> None:
    path = _copy_with(tmp_path, "pantograph", "benchmark", edit)
    with pytest.raises(DefinitionError, match=field) as error:
        load_pantograph(path)
    assert str(path) in str(error.value)


def test_unknown_preset_name_lists_the_available_ones() -> None:
    with pytest.raises(
        DefinitionError,
        match=r"unknown catenary preset 'benchmrk'; available: benchmark, "
        r"en50318-2002, stitched",
    ):
        load_catenary("benchmrk")
    with pytest.raises(DefinitionError, match=r"unknown pantograph preset 'x'; available: benchmark, en"):
        load_pantograph("x")
    with pytest.raises(DefinitionError, match=r"unknown preset kind 'catenaries'"):
        preset_path("catenaries", "benchmark")


def test_missing_file_and_bad_toml_are_named(tmp_path: Path) -> None:
    with pytest.raises(DefinitionError, match=r"catenary file '.*nope\.toml' not found"):
        load_catenary(tmp_path / "nope.toml")
    path = _copy_with(tmp_path, "catenary", "benchmark", ("span_length = 55.0", "span_length = = 55.0"))
    with pytest.raises(DefinitionError, match=r"my-benchmark\.toml: not valid TOML"):
        load_catenary(path)


def test_preset_path_points_at_the_shipped_file() -> None:
    path = preset_path("pantograph", "en50318-2002")
    assert path.is_file() and path.suffix == ".toml"
    assert path.parent.name == "pantographs"
