"""Where ``mindyn codegen`` writes: ``-o`` (C: NAME.c and NAME.h, NAME the path without a
.c, .h or .st suffix, any other kept; ST: the file) and the PLCopen
XML of ``--plcopen``, by the command line's one output rule
(:func:`~mindyn.cli.outputs.output_path`: a folder means the default name inside it;
``--plcopen`` alone: :data:`DEFAULT_FOLDER`)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..codegen import CONTROLLERS, plcopen_project
from ..codegen.generation import identifier
from .args import UsageError
from .outputs import output_path

#: The --what of the momentum-observer step.
OBSERVER = "momentum-observer"

#: Where ``--plcopen`` without a path writes (NAME.xml), relative to the current folder.
DEFAULT_FOLDER = "mindyn-codegen"


def _stem(args: argparse.Namespace, robot) -> str:
    """The default file name (without extension) of what codegen writes: the generated
    identifiers' prefix, with the controller or observer step's name."""
    name = args.name if args.name is not None else identifier(robot.name)
    what = args.what.strip()
    return f"{name}_{what.replace('-', '_')}" if what in CONTROLLERS + (OBSERVER,) else name


#: The suffixes a C output's -o may end with: taken off before .c and .h are added (any other
#: suffix is part of the name: -o arm.v2 writes arm.v2.c and arm.v2.h).
C_SUFFIXES = (".c", ".h", ".st")


def c_base(out: Path) -> Path:
    """The C output ``out`` without a suffix of :data:`C_SUFFIXES`: FILE of FILE.c and FILE.h."""
    return out.with_suffix("") if out.suffix in C_SUFFIXES else out


def c_files(base: Path) -> tuple[Path, Path]:
    """The source and header of the C output ``base`` (:func:`c_base`): ``base`` + .c, + .h."""
    return base.parent / (base.name + ".c"), base.parent / (base.name + ".h")


def _output_base(args: argparse.Namespace, robot) -> Path | None:
    """``-o``'s path, for C without a suffix of :data:`C_SUFFIXES` (a folder: the default name
    inside it, by :func:`~mindyn.cli.outputs.output_path`), or None without -o."""
    if args.output is None:
        return None
    ext = ".st" if args.lang == "st" else ""
    out = output_path(args.output, _stem(args, robot) + ext)
    return c_base(out) if args.lang == "c" else out


def _plcopen_path(args: argparse.Namespace, name: str) -> Path:
    """Where the PLCopen XML goes: ``--plcopen``'s path, or NAME.xml in its folder or in
    :data:`DEFAULT_FOLDER` (created)."""
    given = args.plcopen if isinstance(args.plcopen, str) else None
    return output_path(given, f"{DEFAULT_FOLDER}/{name}.xml")


def _outputs(args: argparse.Namespace) -> list[tuple[str, Path, bool]]:
    """The files codegen writes (C: NAME.c and NAME.h; ST: the file; the PLCopen XML), for the
    command line's one rule on outputs (a folder given: the files inside it are named later)."""
    if args.output is not None and args.lang is None and not args.output.into_folder:
        # the language of a file name that says it
        args.lang = {".c": "c", ".h": "c", ".st": "st"}.get(Path(args.output).suffix.lower())
    if args.output is not None and args.lang is None:
        raise UsageError("--lang is required with -o (c or st) unless FILE ends in .c, .h or .st")
    if args.output is None and args.plcopen is None:
        raise UsageError("nothing to write: give -o FILE (with --lang), --plcopen [XML] or both")
    files = []
    if args.output is not None and args.output.into_folder:
        files.append(("--output", Path(args.output), True))
    elif args.output is not None:
        out = Path(args.output)
        names = c_files(c_base(out)) if args.lang == "c" else (out,)
        files += [("--output", f, False) for f in names]
    if isinstance(args.plcopen, str):
        files.append(("--plcopen", Path(args.plcopen), getattr(args.plcopen, "into_folder", False)))
    return files


def _write(code, out: Path | None, lang: str) -> list[Path]:
    """Writes ``code`` to ``-o``'s path (C: .c and .h), or nothing without -o."""
    if out is None:
        return []
    return code.write(c_files(out)[0] if lang == "c" else out)


def _write_plcopen(args: argparse.Namespace, codes: list, project: str, name: str) -> Path:
    """Writes the PLCopen XML project ``project`` of ``codes`` (Structured Text), by default as
    NAME.xml; returns its path."""
    path = _plcopen_path(args, name)
    path.write_bytes(plcopen_project(codes, project))
    return path
