"""CLI: ``mindyn identify`` on a floating-base robot (a free-flyer or planar root joint), the
workflow of :mod:`mindyn.identification.floating_workflow` on the command line: its options
(declared with identify's others in :mod:`mindyn.cli.identify_args`), the refusal of the options
that do not apply to it, and the run."""

from __future__ import annotations

import argparse

from .args import UsageError, given_options
from .identify_args import FLOATING_MODELS

#: The options of ``identify`` a floating-base log takes: ROBOT, LOG, --tip, --root-joint,
#: --model, --validate, --json, --ols and those below. Every other option given is refused.
_APPLY = {"robot", "data", "tip", "root_joint", "model", "validate", "json", "ols", "contact"}
_APPLY |= {"wrench_frame", "filter", "cutoff", "func", "command"}


def _refuse_fixed_base_options(args: argparse.Namespace) -> None:
    """Refuses, naming the first, an option of ``identify`` given on the command line that a
    floating-base log does not take (joint terms, the fixed-base reading and pre-processing, the
    consistent estimate, descriptions, reports, currents, bags)."""
    given = given_options(args, *(d for d in args._flags if d not in _APPLY))
    if given:
        raise UsageError(
            f"{given[0]}: does not apply to a floating-base robot (its logs carry q, dq, "
            "ddq, joint torques and contact wrenches, fitted by weighted least squares; "
            "options: --model full|base, --contact, --wrench-frame, --validate, --json, "
            "--ols, and --filter butter|savgol|none, --cutoff for a log without dq or ddq)"
        )


def cmd_identify_floating(args: argparse.Namespace, robot) -> int:
    """``mindyn identify`` on ``robot``, a floating-base robot."""
    from ..identification.floating_workflow import load_floating_logs, run_floating
    from .identify import write_json

    if robot.joint_types[0] not in ("floating", "planar"):
        k = next(k for k, t in enumerate(robot.joint_types) if t not in ("revolute", "prismatic"))
        raise UsageError(
            f"identify: robot '{robot.name}' has the {robot.joint_types[k]} joint "
            f"'{robot.joint_names[k]}' and no floating or planar root joint: the fixed-base "
            "identification takes revolute and prismatic joints only, the floating-base one a "
            "free-flyer or planar root (--root-joint floating|planar with a URDF)"
        )
    _refuse_fixed_base_options(args)
    model = args.model or "full"
    if model not in FLOATING_MODELS:
        raise UsageError(
            f"--model {model}: a floating-base robot is identified by the full model (joint "
            "torques and contact wrenches) or the base-link model (--model base: the root's "
            f"equations, no joint torques), not the {model} model"
        )
    logs = load_floating_logs(
        args.data,
        robot,
        validate=args.validate or (),
        wrench_frame=args.wrench_frame or "world",
        contacts=args.contact,
        filter="butter" if args.filter == "lowpass" else args.filter,
        cutoff=args.cutoff,
    )
    report = run_floating(robot, logs, model=model, weighted=not args.ols)
    print(report.format())
    if args.json:
        write_json(args.json, report.to_dict())
    return 0
