"""Catenary and pantograph presets: TOML data files a user can copy and edit (docs/model.md, 'Data and
sources').

A preset is a TOML file whose keys and tables mirror the fields of
:class:`~catenary_env.model.definition.CatenaryDefinition` (tables ``[contact_wire]``, ``[messenger_wire]``,
``[stitch_wire]``, ``[dropper]``, ``[supports]``, ``[damping]``) or of
:class:`~catenary_env.model.definition.PantographDefinition`. Every file also carries a ``[provenance]`` table
that maps dotted field names to source tags (docs/model.md, 'Data and sources')::

    [provenance]
    "contact_wire.axial_stiffness" = "A: 150 mm² copper alloy, not found in a source"

Tags start with ``S`` (two independent sources), ``S?`` (one source) or ``A`` (an assumption of this
project), optionally followed by ``": note"``.

Loading checks the file's structure here (unknown or missing fields, wrong types, provenance keys that
name no field) and leaves every numeric range to the records' own validation, so each check lives in one
place. Every error is a :class:`~catenary_env.model.definition.DefinitionError` that names the file and the
dotted field, before any solve.

Examples
--------
>>> from catenary_env.model.presets import load_catenary, load_pantograph
>>> catenary = load_catenary("benchmark")
>>> catenary.contact_wire.tension
22000.0
>>> load_pantograph(catenary.pantograph).masses
(6.0, 9.0, 7.5)
"""

from __future__ import annotations

import dataclasses
import difflib
import functools
import os
import re
import tomllib
import types
import typing
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any, TypeVar

from ..acceptance_limits import AcceptanceLimits
from ..definition import CatenaryDefinition, DefinitionError, PantographDefinition

__all__ = [
    "acceptance_names",
    "catenary_names",
    "load_acceptance",
    "load_catenary",
    "load_pantograph",
    "pantograph_names",
    "preset_path",
]

_ROOT = Path(__file__).parent
_FOLDERS = {"catenary": "catenaries", "pantograph": "pantographs", "acceptance": "acceptance"}
_TAG = re.compile(r"(S\?|S|A)(:.*)?", re.DOTALL)
_KEY_PART = re.compile(r"(\w+)(?:\[(\d+)\])?")

_Record = TypeVar("_Record", CatenaryDefinition, PantographDefinition, AcceptanceLimits)


# ---------------------------------------------------------------------------------------------------------
# Public API


def catenary_names() -> list[str]:
    """Names of the catenary presets shipped with the package, sorted."""
    return _names("catenary")


def pantograph_names() -> list[str]:
    """Names of the pantograph presets shipped with the package, sorted."""
    return _names("pantograph")


def acceptance_names() -> list[str]:
    """Names of the acceptance-limit presets shipped with the package (docs/acceptance.md), sorted."""
    return _names("acceptance")


def load_acceptance(name_or_path: str | os.PathLike[str] = "en50367-ac") -> AcceptanceLimits:
    """Load and validate acceptance limits (EN 50367 criteria; docs/acceptance.md).

    Parameters
    ----------
    name_or_path : str or path-like
        A preset name (see :func:`acceptance_names`) or the path of a ``.toml`` file.

    Raises
    ------
    DefinitionError
        As :func:`load_catenary`.

    Examples
    --------
    >>> load_acceptance().max_std_over_mean
    0.3
    """
    path = _locate("acceptance", name_or_path)
    table = _read(path)
    with _naming(path):
        return _build_record(AcceptanceLimits, table)


def preset_path(kind: str, name: str) -> Path:
    """Path of a preset's TOML file, e.g. for a user to copy and edit.

    Parameters
    ----------
    kind : {"catenary", "pantograph", "acceptance"}
    name : str
        Preset name, e.g. ``"benchmark"``.

    Returns
    -------
    pathlib.Path
        The file inside the installed package (treat it as read-only; copy it to edit).

    Raises
    ------
    DefinitionError
        For an unknown kind or name; the message lists the available ones.

    Examples
    --------
    >>> preset_path("catenary", "benchmark").name
    'benchmark.toml'
    """
    names = _names(kind)
    if name not in names:
        raise DefinitionError(f"unknown {kind} preset {name!r}; available: {', '.join(names)}")
    return _ROOT / _FOLDERS[kind] / f"{name}.toml"


def load_catenary(name_or_path: str | os.PathLike[str]) -> CatenaryDefinition:
    """Load and validate a catenary definition.

    Parameters
    ----------
    name_or_path : str or path-like
        A preset name (see :func:`catenary_names`), or the path of a ``.toml`` file. A string is read
        as a path when it ends in ``.toml`` or contains a path separator.

    Returns
    -------
    CatenaryDefinition
        With ``provenance`` holding the file's ``[provenance]`` table. A relative ``pantograph`` path in
        the file is resolved against the file's folder.

    Raises
    ------
    DefinitionError
        Naming the file and the dotted field: unknown, missing or mistyped fields, a value outside its
        allowed range, an unknown preset name or pantograph reference.

    Examples
    --------
    >>> load_catenary("stitched").stitch_wire.length
    18.0
    """
    path = _locate("catenary", name_or_path)
    table = _read(path)
    with _naming(path):
        table = _resolve_pantograph(table, path)
        return _build_record(CatenaryDefinition, table)


def load_pantograph(name_or_path: str | os.PathLike[str]) -> PantographDefinition:
    """Load and validate a pantograph definition.

    Parameters
    ----------
    name_or_path : str or path-like
        A preset name (see :func:`pantograph_names`), or the path of a ``.toml`` file.

    Returns
    -------
    PantographDefinition

    Raises
    ------
    DefinitionError
        As :func:`load_catenary`.

    Examples
    --------
    >>> load_pantograph("en50318-2002").uplift_force
    117.5
    """
    path = _locate("pantograph", name_or_path)
    table = _read(path)
    with _naming(path):
        return _build_record(PantographDefinition, table)


# ---------------------------------------------------------------------------------------------------------
# Files


def _names(kind: str) -> list[str]:
    if kind not in _FOLDERS:
        raise DefinitionError(f"unknown preset kind {kind!r}; allowed: {', '.join(_FOLDERS)}")
    return sorted(p.stem for p in (_ROOT / _FOLDERS[kind]).glob("*.toml"))


def _locate(kind: str, name_or_path: str | os.PathLike[str]) -> Path:
    """The file to read: a preset's file, or the given path."""
    if isinstance(name_or_path, str) and not _looks_like_path(name_or_path):
        return preset_path(kind, name_or_path)
    if not isinstance(name_or_path, str | os.PathLike):
        raise TypeError(f"expected a {kind} preset name or a path, got {type(name_or_path).__name__}")
    path = Path(name_or_path)
    if not path.is_file():
        raise DefinitionError(f"{kind} file '{path}' not found")
    return path


def _looks_like_path(text: str) -> bool:
    return text.endswith(".toml") or "/" in text or os.sep in text


def _read(path: Path) -> dict[str, Any]:
    try:
        with path.open("rb") as file:
            return tomllib.load(file)
    except tomllib.TOMLDecodeError as error:
        raise DefinitionError(f"{path}: not valid TOML: {error}") from None
    except (OSError, UnicodeDecodeError) as error:
        raise DefinitionError(f"{path}: cannot read: {error}") from None


@contextmanager
def _naming(path: Path) -> Iterator[None]:
    """Prefix every DefinitionError raised inside with the file it comes from."""
    try:
        yield
    except DefinitionError as error:
        raise DefinitionError(f"{path}: {error}") from None


def _resolve_pantograph(table: dict[str, Any], path: Path) -> dict[str, Any]:
    """Check the catenary's default pantograph: a preset name, or a ``.toml`` path relative to the file."""
    reference = table.get("pantograph")
    if not isinstance(reference, str) or reference == "":
        return table  # absent, empty (no default) or mistyped: the type check reports the last
    if not _looks_like_path(reference):
        names = pantograph_names()
        if reference not in names:
            raise DefinitionError(
                f"pantograph = {reference!r}: unknown pantograph preset; available: {', '.join(names)} "
                f"(or the path of a .toml file, relative to this file)"
            )
        return table
    target = path.parent / reference  # an absolute reference stays as it is
    if not target.is_file():
        raise DefinitionError(f"pantograph = {reference!r}: file '{target}' not found")
    return {**table, "pantograph": str(target.resolve())}


# ---------------------------------------------------------------------------------------------------------
# Tables -> records


def _build_record(cls: type[_Record], table: dict[str, Any]) -> _Record:
    """Build a top-level record (its own validation runs in ``__post_init__``)."""
    provenance = _provenance(cls, table.get("provenance", {}), table)
    return cls(**_arguments(cls, table, prefix=""), provenance=provenance)


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def _without_none(hint: Any) -> tuple[Any, bool]:
    """``X | None`` -> ``(X, True)``; ``X`` -> ``(X, False)``."""
    if isinstance(hint, types.UnionType) or typing.get_origin(hint) is typing.Union:
        args = [a for a in typing.get_args(hint) if a is not type(None)]
        if len(args) == 1:
            return args[0], True
    return hint, False


def _arguments(cls: type, table: Mapping[str, Any], prefix: str) -> dict[str, Any]:
    """Constructor arguments of a dataclass from a TOML table, with structure and type checks."""
    fields = [f for f in dataclasses.fields(cls) if f.name != "provenance"]
    allowed = [f.name for f in dataclasses.fields(cls)]
    for key in table:
        if key not in allowed:
            raise _unknown_field(prefix + key, key, allowed)
    arguments: dict[str, Any] = {}
    for f in fields:
        hint, optional = _without_none(_hints(cls)[f.name])
        dotted = prefix + f.name
        if f.name in table:
            arguments[f.name] = _convert(table[f.name], hint, dotted)
        elif optional and not _has_default(f):
            arguments[f.name] = None
        elif not _has_default(f):
            what = f"table [{dotted}]" if dataclasses.is_dataclass(hint) else "field"
            raise DefinitionError(f"{dotted}: missing required {what}")
    return arguments


def _has_default(f: dataclasses.Field[Any]) -> bool:
    return f.default is not dataclasses.MISSING or f.default_factory is not dataclasses.MISSING


def _unknown_field(dotted: str, key: str, allowed: list[str]) -> DefinitionError:
    close = difflib.get_close_matches(key, allowed, n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    return DefinitionError(f"{dotted}: unknown field{hint}; allowed: {', '.join(sorted(allowed))}")


def _convert(value: Any, hint: Any, dotted: str) -> Any:
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        if not isinstance(value, dict):
            raise DefinitionError(f"{dotted} = {value!r}: expected a table [{dotted}], got {_kind(value)}")
        return hint(**_arguments(hint, value, prefix=dotted + "."))
    if typing.get_origin(hint) is tuple:
        if not isinstance(value, list):
            raise DefinitionError(f"{dotted} = {value!r}: expected an array of numbers, got {_kind(value)}")
        element = typing.get_args(hint)[0]
        return tuple(_scalar(v, element, f"{dotted}[{i}]") for i, v in enumerate(value))
    return _scalar(value, hint, dotted)


def _scalar(value: Any, hint: Any, dotted: str) -> Any:
    is_number = isinstance(value, int | float) and not isinstance(value, bool)
    if hint is float and is_number:
        return float(value)
    if hint is int and isinstance(value, int) and not isinstance(value, bool):
        return value
    if hint is str and isinstance(value, str):
        return value
    expected = {float: "a number", int: "an integer", str: "a string"}[hint]
    shown = "(a table)" if isinstance(value, dict) else repr(value)
    raise DefinitionError(f"{dotted} = {shown}: expected {expected}, got {_kind(value)}")


def _kind(value: Any) -> str:
    """The TOML name of a value's type, for error messages."""
    for python_type, name in (
        (bool, "a boolean"),
        (int, "an integer"),
        (float, "a float"),
        (str, "a string"),
        (list, "an array"),
        (dict, "a table"),
    ):
        if isinstance(value, python_type):
            return name
    return "a date/time"


# ---------------------------------------------------------------------------------------------------------
# Provenance


def _provenance(cls: type, raw: Any, table: Mapping[str, Any]) -> dict[str, str]:
    """Check a ``[provenance]`` table: every key names a field of ``cls``, every value starts with a tag.

    Unquoted dotted keys (``contact_wire.tension = "S"``) parse as nested tables in TOML; they are
    flattened back to dotted names.
    """
    if not isinstance(raw, dict):
        raise DefinitionError(f"provenance: expected a table [provenance], got {_kind(raw)}")
    provenance: dict[str, str] = {}
    for key, tag in _flatten(raw, prefix=""):
        _check_provenance_key(cls, key, table)
        if not (isinstance(tag, str) and _TAG.fullmatch(tag)):
            raise DefinitionError(
                f'provenance."{key}" = {tag!r}: must be a string starting with a source tag '
                f'"S", "S?" or "A", optionally followed by ": note"'
            )
        provenance[key] = tag
    return provenance


def _flatten(raw: Mapping[str, Any], prefix: str) -> Iterator[tuple[str, Any]]:
    for key, value in raw.items():
        if isinstance(value, dict):
            yield from _flatten(value, prefix + key + ".")
        else:
            yield prefix + key, value


def _check_provenance_key(cls: type, key: str, table: Mapping[str, Any]) -> None:
    """Walk a dotted key (``"dropper.stiffness"``, ``"masses[1]"``) through the record's fields."""
    current: Any = cls
    value: Any = table
    for part in key.split("."):
        match = _KEY_PART.fullmatch(part)
        names = [f.name for f in dataclasses.fields(current)] if dataclasses.is_dataclass(current) else []
        names = [n for n in names if n != "provenance"]
        if match is None or match.group(1) not in names:
            allowed = f"; allowed here: {', '.join(sorted(names))}" if names else ""
            raise DefinitionError(f'provenance."{key}": names no field{allowed}')
        name, index = match.group(1), match.group(2)
        hint, _ = _without_none(_hints(current)[name])
        value = value.get(name) if isinstance(value, dict) else None
        if index is not None:
            _check_index(key, hint, value, int(index))
            hint, value = None, None
        current = hint


def _check_index(key: str, hint: Any, value: Any, index: int) -> None:
    if typing.get_origin(hint) is not tuple:
        raise DefinitionError(f'provenance."{key}": names no field; only arrays take an index')
    if isinstance(value, list) and index >= len(value):
        raise DefinitionError(f'provenance."{key}": index out of range; the array has {len(value)} values')
