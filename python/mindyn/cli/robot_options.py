"""The robot argument of the commands (ROBOT, ``--tip``, ``--root-joint``, loaded by
:func:`load_robot`) and the options of the joint terms: rotor, friction, offsets and the side of
the transmissions they act on."""

from __future__ import annotations

import argparse
import re
import sys
import warnings

from .. import _sidecar
from ..robot import DriveTrainWarning, bundled_robots, load
from .args import UsageError
from .number_options import Number

#: The root joints ``--root-joint`` puts between the world and a URDF's root link
#: (``mindyn.load(..., root_joint=)``).
ROOT_JOINTS = ("floating", "planar")


def robot_help() -> str:
    return (
        "a bundled robot ("
        + ", ".join(bundled_robots())
        + "), a URDF file, a MuJoCo MJCF (.xml) or a YAML DH/MDH table"
    )


def robot_arg(text: str) -> str:
    """An argparse ``type`` for ROBOT: the name, file or ``planar<N>`` is checked by the loader;
    here only what cannot reach it (an empty name, a ``planar<N>`` whose N is no integer the
    model builder takes)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a robot name or file, got an empty string")
    m = re.fullmatch(r"planar(\d+)h?", text)
    if m and (len(m.group(1)) > 9 or int(m.group(1)) > 2**31 - 1):
        raise argparse.ArgumentTypeError(
            f"'{text}': planar<N> takes a joint count N, not {m.group(1)}"
        )
    return text


robot_arg.__name__ = "robot"


def add_robot(p: argparse.ArgumentParser) -> None:
    """The positional ROBOT, ``--tip`` (the last link of a URDF chain) and ``--root-joint`` (a
    free-flyer or planar joint above a URDF's root link); :func:`load_robot` loads them."""
    p.add_argument("robot", metavar="ROBOT", type=robot_arg, help=robot_help())
    p.add_argument(
        "--tip",
        help="URDF: the link that ends the chain root -> TIP (default: the whole URDF, a tree "
        "if it branches)",
    )
    p.add_argument(
        "--root-joint",
        choices=ROOT_JOINTS,
        default=None,
        help="URDF: a joint between the world and the root link, making a floating-base robot: "
        "floating (a free-flyer: q = position, unit quaternion x, y, z, w; 6 velocities, linear "
        "then angular in the base's axes) or planar (x, y, cos, sin of the yaw; 3 velocities), "
        "as Pinocchio's root joints (default: the root link fixed to the world)",
    )
    p.add_argument(
        "--joint-terms",
        metavar="FILE",
        help="a joint-terms file (OUT.joints.yaml, which identify and export write beside "
        "--urdf OUT.urdf): the robot's rotor inertia and friction are the file's (on the motors "
        "when it says drive_side: motor), and its torque offsets where the command takes "
        "--offset (info lists them); the output says so (default: the description's terms)",
    )


def load_robot(args: argparse.Namespace, *, tip: str | None = None, command: str = ""):
    """The robot of ``args``: ROBOT with ``--tip`` (else ``tip``) and ``--root-joint``
    (``mindyn.load``; its note on transmissions of a type not read, a
    :class:`~mindyn.DriveTrainWarning` printed once on stderr by the command, is silenced by
    ``--drive-side joint``). With ``command``, a command that takes revolute and prismatic joints
    only: a robot with joints of several degrees of freedom (a root joint, or spherical,
    universal, cylindrical, planar, floating joints of a YAML table) is refused in one line
    (:func:`require_single_dof`)."""
    given_tip = getattr(args, "tip", None)
    terms = getattr(args, "joint_terms", None)
    with warnings.catch_warnings():
        if getattr(args, "drive_side", None) == "joint":  # direct drive asked for: no note
            warnings.simplefilter("ignore", DriveTrainWarning)
        robot = load(
            args.robot,
            tip=given_tip if given_tip is not None else tip,
            root_joint=getattr(args, "root_joint", None),
            joint_terms=terms,
        )
    if command:
        require_single_dof(robot, command)
    if terms is not None:
        line = joint_terms_line(args, robot, _sidecar.read(terms))
        # beside a JSON document on standard output: on stderr
        print(line, file=sys.stderr if getattr(args, "format", None) == "json" else sys.stdout)
    return robot


def joint_terms_line(args: argparse.Namespace, robot, sidecar) -> str:
    """The output line of ``--joint-terms FILE``: which terms the robot took from the file and
    where they act, whether the command uses its torque offsets, or that the command takes
    every value from an identification file instead. Refuses (UsageError) a ``--drive-side``
    that contradicts the file's."""
    path, terms = sidecar.path, _sidecar.terms_of(sidecar)
    values = getattr(args, "identification", None) or getattr(args, "params", None)
    if values is not None:
        return (
            f"joint terms of {path}: not used (the parameter values, rotor inertia, friction "
            f"and offsets included, are those of {values})"
        )
    side = getattr(args, "drive_side", None)
    drives = [k for k in terms if k != _sidecar.OFF]  # rotor inertia and friction
    if drives and side is not None and side != robot.drive_side:
        raise UsageError(
            f"--drive-side {side}: the rotor inertia and friction of {path} act on the "
            f"{robot.drive_side}s (its drive_side); drop --drive-side"
        )
    words = []
    if drives:
        where = (
            f"of the {robot.n} motors (its drive_side: motor)"
            if robot.drive_side == "motor"
            else "on the joints"
        )
        words.append(f"{', '.join(drives)} {where}, replacing the description's")
        if "Fc" in drives and sidecar.friction_model != "coulomb":
            words.append(f"friction model {sidecar.friction_model}")
    off = _sidecar.OFF
    if off in terms:
        if getattr(args, "shows_offsets", False):
            words.append(f"torque offsets {off} shown")
        elif not hasattr(args, "offset"):
            words.append(f"torque offsets {off} not used (this command has none)")
        elif args.offset:
            words.append(f"torque offsets {off} used (--offset)")
        else:
            words.append(f"torque offsets {off} not used (without --offset)")
    return f"joint terms from {path}: " + ("; ".join(words) if words else "none in the file")


def require_single_dof(robot, command: str) -> None:
    """Refuses (UsageError) a robot with joints of several degrees of freedom in ``command``,
    which takes revolute and prismatic joints only, naming the first such joint and what the
    command line does with such a robot."""
    if robot.single_dof:
        return
    k = next(k for k, t in enumerate(robot.joint_types) if t not in ("revolute", "prismatic"))
    raise UsageError(
        f"{command} takes revolute and prismatic joints only; robot '{robot.name}' has the "
        f"{robot.joint_types[k]} joint '{robot.joint_names[k]}' (nq {robot.nq}, nv "
        f"{robot.nv}); for such a robot: info, base, export (--urdf, --yaml; --mjcf with a "
        "floating root and spherical joints), codegen (C "
        "inverse dynamics, gravity and regressor, with a floating or planar root) and, with such "
        "a root, identify"
    )


def add_joint_terms(p: argparse.ArgumentParser, verb: str = "include") -> None:
    """``--rotor``, ``--friction`` and ``--drive-side``; ``verb`` says what they do in this
    command."""
    p.add_argument(
        "--rotor", action="store_true", help=f"{verb} rotor inertia Ia per joint (or motor)"
    )
    p.add_argument("--friction", action="store_true", help=f"{verb} Fv, Fc per joint (or motor)")
    add_drive_side(p)


def add_drive_side(p: argparse.ArgumentParser) -> None:
    """``--drive-side``: where rotor inertia and friction act when the description declares
    transmissions."""
    p.add_argument(
        "--drive-side",
        choices=("motor", "joint"),
        default=None,
        help="where rotor inertia and friction act when the description declares transmissions: "
        "on the motors (the default then; Ia, Fv, Fc of slot k are motor k's, "
        "tau += T^T (Ia T ddq + Fv T dq + Fc sign(T dq))) or on the joints",
    )


def with_drive_side(robot, args):
    """The robot with the drive side of ``--drive-side`` (unchanged when not given); ``motor``
    on a robot without transmissions is refused (ModelError)."""
    side = getattr(args, "drive_side", None)
    return robot if side is None else robot.with_drive_side(side)


def drive_side_words(robot, args) -> str:
    """Where the rotor inertia and friction of this command act, in words for its first output
    line, when the robot has transmissions and they are asked for (a command without
    ``--rotor`` / ``--friction`` always has them); "" otherwise."""
    if robot.transmission is None or not (
        getattr(args, "rotor", True) or getattr(args, "friction", True)
    ):
        return ""
    if robot.drive_side == "motor":
        return "on the motors through the transmissions (--drive-side joint: on the joints)"
    return "on the joints (--drive-side joint)"


def drive_side(robot, args, *, source: str | None = None):
    """``robot`` with ``--drive-side`` applied (:func:`with_drive_side`), and the words saying
    where rotor inertia and friction act, for a command's output ("" when neither is asked
    for); ``source``: the file that put them there (an identification JSON), instead of an
    option or the default."""
    side = getattr(args, "drive_side", None)
    robot = with_drive_side(robot, args)
    if not (getattr(args, "rotor", False) or getattr(args, "friction", False)):
        return robot, ""
    if robot.drive_side == "motor":
        n = len(robot.transmission.motors)
        how = "--drive-side motor" if side else "the default with transmissions"
        how = f"as {source} has them" if source else how
        return robot, (
            f"rotor inertia and friction on the {n} motors (q_m = T q, tau = T^T tau_m; {how}"
            + ("" if side or source else "; --drive-side joint puts them on the joints")
            + ")"
        )
    why = "--drive-side joint" if side else "no transmissions declared"
    why = f"as {source} has them" if source else why
    return robot, f"rotor inertia and friction on the joints ({why})"


def add_offset(p: argparse.ArgumentParser, verb: str = "include") -> None:
    """``--offset``: a constant torque offset per joint (Off1 .. OffN)."""
    p.add_argument(
        "--offset",
        action="store_true",
        help=f"{verb} a constant torque offset per joint, Off1..OffN (tau_j = ... + Off_j)",
    )


def joint_terms(args, robot=None) -> list[str]:
    """The joint terms a command line asked for (``--rotor``, ``--friction``, ``--offset``), in
    words, for the first line of a command's output; with ``robot``, where the rotor inertia
    and friction act when it has transmissions (:func:`drive_side_words`)."""
    named = (
        ("rotor inertia", "rotor"),
        ("friction", "friction"),
        ("torque offsets", "offset"),
    )
    words = [words for words, flag in named if getattr(args, flag, False)]
    side = drive_side_words(robot, args) if robot is not None else ""
    if side:
        k = 1 + max(i for i, w in enumerate(words) if w in ("rotor inertia", "friction"))
        words[k - 1] += " " + side
    return words


def _snap_value(text: str):
    """``--snap``'s value: ``auto``, ``off`` or a tolerance in rad in (0, 0.1]."""
    s = text.strip().lower()
    if s in ("auto", "off"):
        return s
    try:
        return Number(0, 0.1, low_open=True)(text)
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(
            f"expected auto, off or a finite number in (0, 0.1] (rad), got '{text}'"
        ) from None


_snap_value.__name__ = "snap"  # argparse names the type by this


def add_snap(p: argparse.ArgumentParser) -> None:
    """``--snap [auto|off|RAD]``: which joint rotations near right angles are rounded to them
    before the base parameters are computed (``snap=`` of :func:`mindyn.base_parameters`)."""
    p.add_argument(
        "--snap",
        type=_snap_value,
        nargs="?",
        const=1e-3,
        default="auto",
        metavar="auto|off|RAD",
        help="round joint rotations to multiples of pi/2 before computing the base parameters: "
        "auto (the default) rounds the right angles and axes the description writes rounded "
        "(within 1e-5 rad, as CAD exports write them, 1.5707963; or with fewer decimals, "
        "1.5708), never a deliberate angle above that; off keeps the description as written; "
        "RAD (1e-3 when given alone) rounds every rotation and axis within RAD",
    )


def snap_keyword(args: argparse.Namespace):
    """The ``snap=`` keyword of ``--snap``: "auto", False (off) or the tolerance."""
    value = getattr(args, "snap", "auto")
    return False if value == "off" else value


def snap_lines(bp, label: str = "  snapped        ", *, detail: bool = True) -> list[str]:
    """What the base set's snap did (:meth:`mindyn.BaseParameters.snap_report`), one output line
    each under ``label``."""
    return [label + line for line in bp.snap_report(detail=detail)]
