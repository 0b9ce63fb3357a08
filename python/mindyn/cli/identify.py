"""CLI: ``mindyn identify`` and ``mindyn identify-payload``, the identification workflow of
:mod:`mindyn.identification.workflow` on the command line: arguments -> options -> logs ->
run -> text and files (the arguments are declared in :mod:`mindyn.cli.identify_args`)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ..robot import drive_train_record
from .args import UsageError
from .export import write_description
from .flags import library_options_as_flags
from .identify_args import FLOATING_MODELS
from .identify_floating import cmd_identify_floating
from .number_options import joint_values
from .outputs import check_description_kind
from .robot_options import load_robot, snap_keyword, with_drive_side


def _progress():
    """Progress lines on stderr when it is a terminal (``identify --consistent`` solves for
    seconds); None otherwise, so that a log or a pipe gets the result and errors only."""
    if not sys.stderr.isatty():
        return None
    return lambda line: print(f"identify: {line}", file=sys.stderr, flush=True)


def reading_options(args: argparse.Namespace):
    """The :class:`~mindyn.identification.options.ReadingOptions` of the command line (the drive
    gains as given, as the JSON records them)."""
    from ..identification.options import ReadingOptions

    return ReadingOptions(
        filter=args.filter,
        cutoff=args.cutoff,
        periods=args.periods,
        period=args.period,
        edge=args.edge,
        decimate=False if args.no_decimate else None,
        torque_unit=args.torque_unit,
        drive_gain=args.drive_gain,
        topic=args.topic,
        columns=args.columns,
        torque=args.torque,
    )


def identify_options(args: argparse.Namespace, robot):
    """The :class:`~mindyn.identification.options.IdentifyOptions` of the command line."""
    from ..identification.options import IdentifyOptions

    width = args.friction_width
    if width is not None and args.friction_model is not None:
        width = tuple(joint_values(width, robot.n, "--friction-width", broadcast=True))
    return IdentifyOptions(
        model=args.model or "dynamic",  # None: the default (full on a floating base)
        rotor=args.rotor,
        friction=args.friction,
        offset=args.offset,
        weighted=not args.ols,
        rsd_threshold=args.rsd_threshold,
        energy_window=args.energy_window,
        integration=args.integration,
        integral_window=args.integral_window,
        min_velocity=args.min_velocity,
        friction_model=args.friction_model,
        friction_width=width,
        consistent=args.consistent,
        prior_weight=args.prior_weight,
        snap=snap_keyword(args),
    )


def _check_outputs(args: argparse.Namespace, robot) -> None:
    """The robot-description outputs need the consistent estimate, a description of the same
    kind and a friction model it can hold (MJCF: Coulomb's; no description: Dahl's)."""
    described = args.urdf or args.yaml or args.mjcf
    if (described or args.sidecar) and not args.consistent:
        given = "urdf" if args.urdf else "yaml" if args.yaml else "mjcf" if args.mjcf else "sidecar"
        raise UsageError(
            f"--{given}: expected "
            "--consistent as well (only a physically consistent estimate can be written as a robot "
            "description)"
        )
    if args.mjcf and args.friction_model not in (None, "coulomb", "auto"):
        raise UsageError(
            "--mjcf: MJCF holds viscous and dry friction only, not the "
            f"{args.friction_model} friction model (--urdf and --yaml keep it in their "
            "joint-terms file)"
        )
    if described and args.friction_model == "dahl":
        given = "urdf" if args.urdf else "yaml"
        raise UsageError(
            f"--{given}: the Dahl friction model's state follows the motion; no robot "
            "description holds it"
        )
    if args.sidecar and not (args.urdf or args.yaml):
        raise UsageError("--sidecar: expected --urdf or --yaml (the description it goes with)")
    if described:
        check_description_kind(robot, args.robot, args.urdf is not None, args.mjcf)


def _write_report(folder: str, report, doc: dict, text: str) -> None:
    """The plots of ``--report`` (of the consistent estimate when there is one), the JSON and
    the text."""
    from ..identification.excitation import excitation_limits
    from ..identification.report import write_report

    lim, _ = excitation_limits(report.robot, margin=0.0)
    logs, vlogs = report.logs.fit.logs, report.logs.validation.logs
    if report.consistent is None:
        paths = write_report(
            folder, report.result, logs, validation_data=vlogs, validation=report.validation,
            fit=report.fit, trajectory_limits=lim,
        )  # fmt: skip
    else:  # the headline estimate, named in each plot's title
        paths = write_report(
            folder, report.consistent, logs, validation_data=vlogs,
            validation=report.consistent_validation, fit=report.consistent_fit,
            trajectory_limits=lim, estimate="consistent",
        )  # fmt: skip
    for name, content in (("identification.json", json.dumps(doc, indent=2)), ("table.txt", text)):
        (Path(folder) / name).write_text(content + "\n")
        paths.append(Path(folder) / name)
    print(f"wrote report to {Path(folder)}/: " + ", ".join(p.name for p in paths))


def write_json(path: str, doc: dict) -> None:
    """Writes the JSON document of an identification to ``path`` and says so."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Path(path).write_text(json.dumps(doc, indent=2) + "\n")
    print(f"wrote {path}")


def refuse_floating_options(args: argparse.Namespace) -> None:
    """Refuses ``--contact``, ``--wrench-frame`` and ``--model full|base`` on a robot that has
    no floating or planar root."""
    given = [
        flag
        for flag, on in (
            ("--contact", args.contact is not None),
            ("--wrench-frame", args.wrench_frame is not None),
            (f"--model {args.model}", args.model in FLOATING_MODELS),
        )
        if on
    ]
    if given:
        raise UsageError(
            f"{given[0]}: applies to a floating-base robot (a free-flyer or planar root joint: "
            "--root-joint floating|planar with a URDF, or the root joint of a YAML table); "
            "the models of a fixed-base robot are dynamic, integral and energy"
        )


def read_logs(args: argparse.Namespace, robot, options):
    """The identification and validation logs of the command line, read for the regression
    model of ``options`` (its :class:`~mindyn.identification.options.IdentifyOptions`)."""
    from ..identification.workflow import load_logs

    return load_logs(
        args.data,
        robot,
        validate=args.validate or (),
        currents=args.currents,
        validate_currents=args.validate_currents,
        model=options.model,
        options=reading_options(args),
    )


def cmd_identify(args: argparse.Namespace) -> int:
    from ..identification.workflow import run

    if args.validate_currents and not args.validate:
        raise UsageError("--validate-currents: expected --validate with the logs they belong to")
    robot = load_robot(args)
    if not robot.single_dof:  # a floating-base robot: its own workflow
        return cmd_identify_floating(args, robot)
    refuse_floating_options(args)
    robot = with_drive_side(robot, args)
    _check_outputs(args, robot)
    options = identify_options(args, robot)
    logs = read_logs(args, robot, options)
    report = run(robot, logs, options=options, tip=args.tip, progress=_progress())
    doc = report.to_dict()
    text = library_options_as_flags(report.format())  # the report names keywords
    print(text)
    if args.json:
        write_json(args.json, doc)
    if args.urdf or args.yaml or args.mjcf:
        from ..identification.document import refuse_state

        refuse_state(doc, "a robot description", "the consistent estimate")
        write_description(
            report.robot,
            doc["classical"],
            "the consistent estimate",
            args.robot,
            args.urdf,
            args.yaml,
            args.sidecar,
            mjcf=args.mjcf,
        )
    if args.report:
        _write_report(args.report, report, doc, text)
    return 0


def cmd_identify_payload(args: argparse.Namespace) -> int:
    from ..identification.consistent import arm_tip, identify_payload, read_arm
    from ..identification.summary import plain
    from ..identification.terminal import format_payload
    from ..identification.workflow import load_logs

    tip = arm_tip(args.identification, args.robot)
    if args.tip is not None and tip is not None and args.tip != tip:
        raise UsageError(
            f"--tip {args.tip}: {args.identification} was identified on the chain ending at "
            f"--tip {tip}; the payload sits on that chain's last link"
        )
    robot = load_robot(args, tip=tip, command="identify-payload")
    read_arm(robot, args.identification)  # its errors before reading the logs
    logs = load_logs(
        args.data,
        robot,
        currents=args.currents,
        options=reading_options(args),
        what="the payload data",
    )
    res = identify_payload(
        robot,
        args.identification,
        list(logs),
        consistent=not args.no_consistent,
        min_velocity=args.min_velocity,
    )
    files = logs.fit.files
    note = f", chain to --tip {tip} as identified" if tip and not args.tip else ""
    print(format_payload(res, robot, files, args.identification, note))
    if args.json:
        doc = {"robot": robot.name, "files": files, **res.to_dict(), **drive_train_record(robot)}
        write_json(args.json, plain(doc))
    return 0
