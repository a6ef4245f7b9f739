"""``catenary presets``: list the catenary and pantograph presets, or copy one to edit."""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

from ..errors import UsageError, UserFileError
from ..model.presets import catenary_names, pantograph_names, preset_path
from .paths import check_output_path


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``presets`` to the sub-commands of ``catenary``."""
    p = sub.add_parser("presets", help="list the presets, or copy one to edit")
    p.add_argument(
        "--copy", nargs=2, metavar=("NAME", "DEST"), help="copy a catenary preset's TOML file to DEST"
    )
    p.add_argument("--pantograph", action="store_true", help="with --copy: copy the pantograph preset NAME")
    p.add_argument("--force", action="store_true", help="with --copy: overwrite DEST if it exists")


def run(args: argparse.Namespace) -> int:
    """List the presets, or copy one; 0."""
    if args.copy:
        return _copy(*args.copy, pantograph=args.pantograph, force=args.force)
    if args.pantograph or args.force:
        raise UsageError("--pantograph and --force go with --copy NAME DEST")
    print("catenaries: " + ", ".join(catenary_names()))
    print("pantographs: " + ", ".join(pantograph_names()))
    return 0


def _copy(name: str, dest: str, pantograph: bool, force: bool) -> int:
    kind = "pantograph" if pantograph else "catenary"
    names = pantograph_names() if pantograph else catenary_names()
    if name not in names:
        other = "" if pantograph else " (for a pantograph preset add --pantograph)"
        raise UsageError(f"--copy {name}: unknown {kind} preset; available: {', '.join(names)}{other}")
    check_output_path(dest, "--copy")
    if Path(dest).exists() and not force:
        raise UsageError(f"--copy {name} {dest}: the file exists; add --force to overwrite it")
    try:
        shutil.copyfile(preset_path(kind, name), dest)
    except OSError as error:
        raise UserFileError.from_os_error(error, "--copy") from error
    print(f"copied the {kind} preset '{name}' to {dest}: edit it and pass the path instead of the name")
    return 0
