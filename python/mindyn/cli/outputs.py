"""The command line's one rule for the files and folders it writes: the validated types of the
output options (:func:`output_file`, :func:`output_dir`), the path a default name takes
(:func:`output_path`), the checks and folders made before a command runs
(:func:`prepare_outputs`), and the robot-description outputs (:func:`add_description_outputs`)
with the check that one fits the robot before any work is done (:func:`check_description_kind`)."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from .._mujoco import is_mjcf
from .args import UsageError


def _nearest_existing(path: Path) -> Path:
    path = path.absolute()
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def _check_parent(path: Path, text: str) -> None:
    anc = _nearest_existing(path.parent)
    if not anc.is_dir():
        raise argparse.ArgumentTypeError(f"'{text}': '{anc}' is a file, not a folder")
    if not os.access(anc, os.W_OK | os.X_OK):
        raise argparse.ArgumentTypeError(f"'{text}': the folder '{anc}' is not writable")


class OutputPath(str):
    """An output option's value (a ``str``), marked as a file or a folder to write, so that
    :func:`prepare_outputs` finds every output of a command line; ``into_folder``: a file
    option given an existing folder (or a path ending in ``/``), which :func:`output_path`
    turns into the command's default file name inside it."""

    folder = False
    into_folder = False


class OutputFolder(OutputPath):
    folder = True


def output_file(text: str) -> str:
    """An argparse ``type``: a file to write, by the rule of :func:`output_path` (a folder
    means the command's default file name inside it; the missing folders are created by
    :func:`prepare_outputs`)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a file name to write, got an empty string")
    path = Path(text)
    if path.is_dir() or text.endswith(("/", os.sep)):
        if path.is_dir() and not os.access(path, os.W_OK | os.X_OK):
            raise argparse.ArgumentTypeError(f"the folder '{text}' is not writable")
        if not path.exists():
            _check_parent(path, text)
        value = OutputPath(text)
        value.into_folder = True
        return value
    if path.exists() and not os.access(path, os.W_OK):
        raise argparse.ArgumentTypeError(f"'{text}' exists and is not writable")
    _check_parent(path, text)
    return OutputPath(text)


def output_path(value: str | None, default: str) -> Path:
    """The one rule for the file an output option of any command names: a path naming a folder
    (an existing one, or any path ending in ``/``) means ``default``'s file name inside that
    folder; no value means ``default`` itself (relative to the current folder); any other path
    is the file. The missing folders of the file are created. Commands state the path they
    wrote ("wrote PATH", unless standard output carries a JSON document)."""
    if value is None:
        path = Path(default)
    elif getattr(value, "into_folder", False) or Path(value).is_dir():
        path = Path(value) / Path(default).name
    else:
        path = Path(value)
    path.parent.mkdir(parents=True, exist_ok=True)
    return path


output_file.__name__ = "file name"


def output_dir(text: str) -> str:
    """An argparse ``type``: a folder to write into (created when missing)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a folder to write into, got an empty string")
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"'{text}' is a file; expected a folder to write into")
    if path.is_dir() and not os.access(path, os.W_OK | os.X_OK):
        raise argparse.ArgumentTypeError(f"the folder '{text}' is not writable")
    if not path.exists():
        _check_parent(path, text)
    return OutputFolder(text)


output_dir.__name__ = "folder"


#: The extension of an output option's default file name (:func:`default_file_name`), by the
#: option's destination; CSV for ``-o``.
_EXTENSIONS = {
    "json": ".json",
    "calibrate": ".json",
    "urdf": ".urdf",
    "yaml": ".yaml",
    "mjcf": ".xml",
    "sidecar": ".joints.yaml",
    "plot": ".png",
    "output": ".csv",
}


def default_file_name(args: argparse.Namespace, dest: str) -> str:
    """The file an output option writes when given a folder: ROBOT_COMMAND.EXT, ROBOT the
    robot argument (a bundled name, or its description file's name without extension)."""
    robot = Path(str(getattr(args, "robot", "") or "mindyn")).stem or "mindyn"
    return f"{robot}_{getattr(args, 'command', 'mindyn')}{_EXTENSIONS.get(dest, '')}"


def _into_folders(args: argparse.Namespace) -> None:
    """Every file option given a folder names :func:`default_file_name` inside it
    (:func:`output_path`), for the commands that write what their options name."""
    for dest, value in vars(args).items():
        if isinstance(value, OutputPath) and value.into_folder:
            path = output_path(value, default_file_name(args, dest))
            setattr(args, dest, OutputPath(str(path)))


def declared_outputs(args: argparse.Namespace) -> list[tuple[str, Path, bool]]:
    """The outputs a command line names: ``(option, path, is_folder)`` for every value of an
    option typed :func:`output_file` or :func:`output_dir`."""
    found = []
    for dest, value in vars(args).items():
        for v in value if isinstance(value, list) else [value]:
            if isinstance(v, OutputPath):
                found.append(("--" + dest.replace("_", "-"), Path(v), v.folder or v.into_folder))
    return found


#: The arguments that name files a command reads, by destination, with their name in a message
#: (positional ones by their metavar): no output may be one of them.
INPUTS = {
    "robot": "ROBOT",
    "data": "LOG",
    "log": "LOG",
    "identification": "ID.json",
    "params": "the identification JSON",
    "validate": "--validate",
    "currents": "--currents",
    "validate_currents": "--validate-currents",
    "trajectory": "--trajectory",
    "gains": "--gains",
    "thresholds": "--thresholds",
    "joint_terms": "--joint-terms",
}


def _inputs(args: argparse.Namespace) -> dict[Path, tuple[str, str]]:
    """The existing files the command line names as inputs (:data:`INPUTS`), by resolved path:
    the argument's name and the path as given."""
    found: dict[Path, tuple[str, str]] = {}
    for dest, name in INPUTS.items():
        value = getattr(args, dest, None)
        for v in value if isinstance(value, list) else [value]:
            if isinstance(v, (str, os.PathLike)) and not isinstance(v, OutputPath):
                if Path(v).is_file():
                    found.setdefault(Path(v).resolve(), (name, str(v)))
    return found


def implied_outputs(args: argparse.Namespace) -> list[tuple[str, str, str, Path, str]]:
    """The files a command writes beside the outputs its options name: ``(option, value,
    what, path, remedy)`` for each: the option and its value, what the file is, its path, and
    how to write it elsewhere. The joint-terms file beside ``--urdf`` / ``--yaml`` (without
    ``--sidecar``), and those the command's ``implied(args)`` (a parser default) lists, such as
    the coefficients and plot ``excite -o X.csv`` writes as X.json and X.png."""
    found = []
    if getattr(args, "sidecar", None) is None:  # the joint-terms file beside --urdf / --yaml
        from ..export import default_sidecar

        for dest in ("urdf", "yaml"):
            value = getattr(args, dest, None)
            side = default_sidecar(value) if isinstance(value, OutputPath) else None
            if side is not None:
                remedy = "give --sidecar another file"
                found.append((f"--{dest}", str(value), "joint-terms file", side, remedy))
    if callable(getattr(args, "implied", None)):
        found += args.implied(args)
    return found


def is_output(args: argparse.Namespace, filename: object) -> bool:
    """Whether ``filename`` (an OSError's) is a file the command line's outputs name or imply,
    a folder on the way to one, or lies in a folder an output names: an error on it is the
    output's, not the input's."""
    if not isinstance(filename, (str, os.PathLike)):
        return False
    try:
        key = Path(filename).resolve()
        named = [(path, folder) for _, path, folder in declared_outputs(args)]
        named += [(path, False) for *_, path, _ in implied_outputs(args)]
        return any(
            key == path.resolve()
            or key in path.resolve().parents
            or (folder and path.resolve() in key.parents)
            for path, folder in named
        )
    except (OSError, ValueError, RuntimeError):
        return False


def prepare_outputs(args: argparse.Namespace) -> None:
    """The one rule for the outputs of every command, applied before the command writes
    anything: a file option given a folder names its default file inside it
    (:func:`output_path`, :func:`default_file_name`), no two outputs may be the same file
    (compared as resolved paths), none may be a file the command reads (:data:`INPUTS`: the
    robot's description, a log, ...), and the missing folders of each are created. The outputs are
    :func:`declared_outputs`, or those that the command's ``outputs(args)`` (a parser default)
    lists when it writes files the options only imply (``codegen -o NAME``: NAME.c and
    NAME.h). The files written beside an output (:func:`implied_outputs`: ``excite -o X.csv``
    writes X.json and X.png, ``simulate -o X.csv`` X.truth.json, ``--urdf`` its joint-terms
    file) may not be a file the command reads either, nor another output. The commands state the
    paths they wrote (on standard output, unless it carries the JSON document of ``--format
    json``)."""
    if callable(getattr(args, "outputs", None)):
        outputs = args.outputs(args)  # the command names the files in a folder given
    else:
        _into_folders(args)
        outputs = declared_outputs(args)
    seen: dict[Path, tuple[str, Path]] = {}
    folders = {path.resolve(): (option, path) for option, path, folder in outputs if folder}
    inputs = _inputs(args)
    declared = {path.resolve(): (option, path) for option, path, folder in outputs if not folder}
    for option, value, what, path, remedy in implied_outputs(args):
        key = path.resolve()
        if key in inputs:
            name, given = inputs[key]
            raise UsageError(
                f"{option} '{value}': its {what} '{path}' is also the file the command reads as "
                f"{name} ('{given}'): writing it would overwrite that input; {remedy}"
            )
        if key in declared and declared[key][0] != option:
            other, first = declared[key]
            raise UsageError(
                f"{option} '{value}': its {what} '{path}' is also the file {other} writes "
                f"('{first}'): {remedy}"
            )
    for option, path, folder in outputs:
        if folder:  # files inside it are named by the command (output_path)
            continue
        key = path.resolve()
        if key in inputs:
            name, given = inputs[key]
            raise UsageError(
                f"{option} '{path}' is also the file the command reads as {name} ('{given}'): "
                "writing it would overwrite that input; give the output its own file"
            )
        if key in folders:
            other, first = folders[key]
            raise UsageError(
                f"{option} '{path}' is also the folder {other} writes into ('{first}'): give "
                "each output its own path"
            )
        if key in seen:
            other, first = seen[key]
            raise UsageError(
                f"{option} '{path}' is also the file {other} writes ('{first}'): give each "
                "output its own file"
            )
        seen[key] = (option, path)
    for _, path, folder in outputs:
        (path if folder else path.parent).mkdir(parents=True, exist_ok=True)


def add_description_outputs(p, what: str) -> None:
    """``--urdf FILE``, ``--yaml FILE`` (one of them) and ``--sidecar FILE`` on parser ``p``."""
    out = p.add_mutually_exclusive_group(required=what == "export")
    suffix = "" if what == "export" else " with the consistent estimate (needs --consistent)"
    out.add_argument("--urdf", metavar="FILE", type=output_file, help="URDF to write" + suffix)
    out.add_argument(
        "--yaml", metavar="FILE", type=output_file, help="YAML DH/MDH table to write" + suffix
    )
    multi_dof = ", a floating root and spherical joints as free and ball joints"
    out.add_argument(
        "--mjcf",
        metavar="FILE",
        type=output_file,
        help="MuJoCo MJCF to write" + suffix + ": inertials, joint armature (Ia), damping (Fv) "
        "and frictionloss (Fc), the effort limits (actuatorfrcrange) and velocity limits "
        "(custom numerics velocity_limit:JOINT, read back on loading), transmissions as "
        f"tendons{multi_dof if what == 'export' else ''}; a robot read from an MJCF has that "
        "file written back",
    )
    p.add_argument(
        "--sidecar",
        metavar="FILE",
        type=output_file,
        help="YAML for the joint terms (rotor inertia, friction, offsets); default: "
        "<FILE stem>.joints.yaml beside FILE, written when there are joint terms (URDF) or "
        "torque offsets (YAML table)",
    )


def check_description_kind(robot, source: str, urdf: bool, mjcf=None) -> None:
    """Refuse (UsageError) ``--urdf`` for a robot from a YAML table or an MJCF, ``--yaml`` for
    one from a URDF or an MJCF; ``--mjcf`` takes any robot."""
    if mjcf is not None:
        return
    if is_mjcf(robot.source):
        want = "--urdf needs a robot from a URDF" if urdf else "--yaml needs a YAML DH/MDH table"
        raise UsageError(f"{want}: '{source}' is an MJCF; use --mjcf")
    if urdf != (robot.convention == "urdf"):
        want = "--urdf needs a robot from a URDF" if urdf else "--yaml needs a YAML DH/MDH table"
        kind = "a URDF" if robot.convention == "urdf" else f"a {robot.convention.upper()} table"
        raise UsageError(f"{want}: '{source}' is {kind}; use {'--yaml' if urdf else '--urdf'}")
