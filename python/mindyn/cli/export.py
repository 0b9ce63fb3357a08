"""``mindyn export``: identified classical parameters written back as a robot description."""

from __future__ import annotations

import argparse
import math

from .._core import ArgumentError, ModelError
from ..export import classical_terms, write_urdf, write_yaml
from .args import UsageError, add_command
from .flags import library_options_as_flags
from .outputs import add_description_outputs, check_description_kind
from .robot_options import add_robot, load_robot


def register(subparsers) -> None:
    p = add_command(
        subparsers,
        "export",
        description="Write the classical parameters of an identification JSON (its 'classical' "
        "map, from 'mindyn identify --consistent --json') into a copy of the robot's "
        "description: a URDF (inertials, joint damping and friction; rotor inertia, friction "
        "and torque offsets also in a sidecar YAML) or a YAML DH/MDH table, or as a MuJoCo MJCF.",
    )
    add_robot(p)
    p.add_argument("params", metavar="ID.json", help="identification JSON with a 'classical' map")
    add_description_outputs(p, "export")
    p.set_defaults(func=cmd_export)


def read_classical(path: str) -> tuple[dict, str | None, dict]:
    """The 'classical' map of an identification JSON, the robot it names (None if none) and the
    whole document, or a one-line error naming the file."""
    # here: not needed by the other commands
    from ..identification.document import read_identification

    doc = read_identification(path, need=("classical",), what="identification file", finite=True)
    return doc["classical"], doc.get("robot"), doc


def cmd_export(args: argparse.Namespace) -> int:
    from ..identification.document import (
        check_identified_geometry,
        check_identified_robot,
        refuse_state,
        robot_on_drive_side,
        with_identified_friction,
    )

    robot = load_robot(args)
    if args.mjcf is not None:  # MJCF: hinge and slide joints and a floating root
        from ..mjcf import check_joints  # here: not needed by the other outputs

        check_joints(robot)
    classical, _, doc = read_classical(args.params)
    refuse_state(doc, "a robot description", str(args.params))
    check_identified_robot(doc, robot, f"{args.params}: parameters", error=ModelError)
    check_identified_geometry(doc, robot, f"{args.params}: parameters", error=ModelError)
    robot = robot_on_drive_side(robot, doc, where=str(args.params))
    robot = with_identified_friction(robot, doc, where=str(args.params))
    write_description(
        robot,
        classical,
        f"{args.params}: 'classical'",
        args.robot,
        args.urdf,
        args.yaml,
        args.sidecar,
        mjcf=args.mjcf,
    )
    return 0


def write_description(
    robot, classical, what: str, source: str, urdf, yaml, sidecar, *, mjcf=None
) -> None:
    """Write ``classical`` into a copy of the robot's description (``urdf`` or ``yaml`` path) or
    an MJCF (``mjcf``) and say what was written; ``what`` names the values in errors, ``source``
    the robot argument."""
    check_description_kind(robot, source, urdf is not None, mjcf)
    kind = robot.friction_model["kind"]
    has_friction = any(k.startswith(("Fv", "Fc")) for k in classical)
    if mjcf is not None and kind != "coulomb" and has_friction:
        raise ModelError(
            f"{what}: identified with the {kind} friction model; MJCF holds viscous and dry "
            "friction only (write --urdf or --yaml, whose joint-terms file keeps the model, or "
            "identify with --friction-model coulomb)"
        )
    try:  # values read from a file: their errors are the data's
        terms = classical_terms(robot, classical, what=what)
    except ArgumentError as e:
        from ..identification.data import DataError

        raise DataError(str(e)) from None
    if mjcf is not None:
        if sidecar is not None:
            raise UsageError("--sidecar: goes with --urdf or --yaml, not --mjcf")
        from ..mjcf import write_mjcf  # here: not needed by the other outputs

        res = write_mjcf(robot, classical, mjcf)
    elif urdf is not None:
        res = write_urdf(robot, classical, urdf, sidecar=sidecar)
    else:
        res = write_yaml(robot, classical, yaml, sidecar=sidecar)
    total = math.fsum(terms.inertial[9::10])
    line = f"wrote {res.path} ({robot.name}, {robot.n} links, moving mass {total:.6g} kg)"
    if res.sidecar is not None:
        line += f" and {res.sidecar}"
    print(line)
    for note in res.notes:
        print(f"  note: {library_options_as_flags(note)}")
