"""The closed loop shared by ``mindyn track`` and ``mindyn simulate``: its options (reference,
controller, gains, parameter error, torque limit, integration) and the reference and controller
they give."""

from __future__ import annotations

import argparse
from pathlib import Path

from .._core import ArgumentError
from ..base import base_parameters
from .args import UsageError
from .number_options import number
from .outputs import output_dir


def check_controller_options(args: argparse.Namespace) -> None:
    """--param-error sets a model's estimate: PD has none (it was ignored)."""
    if getattr(args, "estimate_box", None) is not None and args.controller != "adaptive-pd":
        raise UsageError(
            f"--estimate-box: a box on the estimate of adaptive-pd (--controller is "
            f"{args.controller})"
        )
    if args.controller == "pd" and args.param_error is not None:
        raise UsageError(
            "--param-error: --controller pd has no model (the error is that of the estimate of "
            "adaptive-pd and computed-torque)"
        )


def torque_limit(text: str):
    """``--torque-limit`` (track, simulate and codegen alike): ``effort`` (each joint's effort
    limit), ``none`` or a positive number [N m | N] on every joint."""
    import math

    word = text.strip()
    if word in ("effort", "none"):
        return word
    try:
        value = float(word)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected effort, none or a positive number [N m], got '{text}'"
        ) from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be positive and finite, got {text}")
    return value


def applied_limit(limit, n: int):
    """The ``torque_limit`` of :func:`mindyn.control.simulate` for ``--torque-limit``: None,
    ``"effort"`` or the number on each of the ``n`` joints."""
    import numpy as np

    if limit is None or limit == "none":
        return None
    return limit if limit == "effort" else np.full(n, float(limit))


def limit_words(limit) -> str:
    """``--torque-limit`` in words: effort, or +-N on every joint."""
    return "effort" if limit == "effort" else f"+-{float(limit):g} N m on every joint"


def joint_tolerance(robot, degrees):
    """``--tracking-tolerance`` (degrees on revolute joints, millimetres on prismatic ones) as the
    per-joint tolerance of :func:`mindyn.control.default_gains` [rad | m]; None for None."""
    if degrees is None:
        return None
    import math

    return [
        degrees * 1e-3 if t == "prismatic" else math.radians(degrees) for t in robot.joint_types
    ]


def add_tolerance_arg(p) -> None:
    """``--tracking-tolerance``: what the default gains hold against Coulomb friction."""
    number(
        p,
        "--tracking-tolerance",
        metavar="DEG",
        low=0,
        high=360,
        low_open=True,
        help="tracking tolerance the default gains hold against each joint's Coulomb friction "
        "[deg; mm on prismatic joints] (default 2): K_P >= 2 Fc / (tolerance / 2), the "
        "friction's steady error taking half of it; where the sampled loop at the controller "
        "period cannot also keep its gain margin, the controller is refused in one line naming "
        "the joint and a period that allows both",
    )


def reference_and_controller(args: argparse.Namespace, robot, default_duration):
    """The reference, its text, the simulated time, the per-cycle span and the controller of
    ``mindyn track`` and ``mindyn simulate`` (``--trajectory``, ``--cycle``, ``--controller``,
    ``--gains``, ``--param-error``, ``--seed``); ``default_duration(reference)`` gives the
    simulated time when ``--duration`` is not given. Returns also the base parameters of the
    estimate (None for PD)."""
    from .. import control
    from ..control.simulation import SumOfSines, load_reference

    n = robot.n
    period = args.period
    if args.cycle is not None and args.cycle < 20 * period:
        raise UsageError(
            f"--cycle {args.cycle:g} s: expected at least 20 controller periods "
            f"(--controller-period {period:g} s), so that the reference's third harmonic is "
            "sampled about 7 times per oscillation"
        )
    if args.trajectory:
        reference = load_reference(args.trajectory, n, robot=robot)
        ref_text = f"trajectory {args.trajectory} ({reference.duration:g} s)"
        duration = args.duration or reference.duration
        cycle = args.cycle or duration
    else:
        reference = SumOfSines(robot, period=args.cycle or 10.0, seed=args.seed)
        ref_text = f"sum of sines within the limits, {reference.period:g} s cycle"
        duration = args.duration or default_duration(reference)
        cycle = reference.period
    from ..control.simulation import MIN_SUBSTEPS, check_steps

    try:  # before any set-up work
        check_steps(
            duration,
            1.0 / period,
            substeps=(args.substeps or MIN_SUBSTEPS) if args.integrator == "rk4" else 1,
        )
    except ArgumentError as e:  # the library's check; a bare ValueError stays a defect
        raise UsageError(
            f"--duration {duration:g} with --controller-period {period:g}: {e}"
            + (" (the duration is two cycles unless given)" if args.duration is None else "")
        ) from None
    if duration < period:
        raise UsageError(
            f"--duration {duration:g} s is shorter than one --controller-period {period:g} s"
        )
    if args.controller == "computed-torque" and args.gains is None and args.param_error is None:
        return reference, ref_text, duration, cycle, None, None  # the simulator's default
    # the simulated robot: track's has rotor inertia and friction, simulate's as its flags say
    rotor, friction = getattr(args, "rotor", True), getattr(args, "friction", True)
    tolerance = joint_tolerance(robot, getattr(args, "tracking_tolerance", None))
    if args.gains:
        gains = control.load_gains(
            args.gains, robot, period=period, rotor=rotor, tolerance=tolerance
        )
    else:
        gains = control.default_gains(robot, period=period, rotor=rotor, tolerance=tolerance)
    base = p_hat = None
    if args.controller != "pd":
        from ..control.controllers import base_values, plant_parameters

        base = base_parameters(robot, rotor=True, friction=True)
        error = 0.3 if args.param_error is None else args.param_error
        p_hat = base_values(
            base,
            control.consistent_perturbation(
                robot, plant_parameters(robot, rotor, friction=friction), error, seed=args.seed
            ),
        )
    box = getattr(args, "estimate_box", None) != "none"
    controller = control.make_controller(
        args.controller,
        robot,
        gains,
        p_hat,
        base=base,
        period=period,
        rotor=rotor,
        friction=friction,
        box=box,
    )
    if getattr(controller, "box_note", ""):
        gains.add_note(controller.box_note, [args.controller])
    controller.gains = gains
    return reference, ref_text, duration, cycle, controller, base


#: The files the tracking report writes into ``--report``
#: (:func:`~mindyn.control.simulation.write_tracking_report`)
REPORT_FILES = ("summary.json", "log.csv", "tracking_error.png", "torque.png", "parameters.png")


def report_outputs(args: argparse.Namespace) -> list[tuple[str, str, str, Path, str]]:
    """The files of the tracking report in ``--report`` (none without it), for the command
    line's rule on outputs (:func:`~mindyn.cli.outputs.implied_outputs`)."""
    folder = getattr(args, "report", None)
    if folder is None:
        return []
    remedy = "give --report another folder"
    return [
        ("--report", str(folder), "report file", Path(folder) / name, remedy)
        for name in REPORT_FILES
    ]


def add_closed_loop_args(p, default: str) -> None:
    """The reference, controller and integration options shared by ``track`` and ``simulate``
    (``default``: the default controller)."""
    from ..control.controllers import CONTROLLERS

    p.add_argument(
        "--controller",
        choices=CONTROLLERS,
        default=default,
        help=f"tracking controller (default {default})",
    )
    p.add_argument(
        "--gains",
        metavar="FILE",
        help="YAML with kd, lambda, gamma, nu (adaptive PD) and optionally kp (PD: default "
        "Lambda K_D; computed torque: default Lambda^2 with K_D = 2 Lambda; with kp, the file's "
        "kd, else 2 sqrt(kp): a kd without kp is a torque gain, not computed torque's); keys "
        "left out take the defaults, stated in the output",
    )
    add_tolerance_arg(p)
    p.add_argument(
        "--estimate-box",
        choices=["derived", "none"],
        help="adaptive PD: derived (the default): project the estimate onto a box about the "
        "description's base parameters, each one the linearised sampled loop sees within a "
        "third of a common fraction (at which the parameters moving together keep the loop "
        "stable) of the change that alone makes that loop unstable (the others, such as "
        "Coulomb friction, unbounded; stated in the output); none: no box",
    )
    p.add_argument(
        "--trajectory",
        metavar="FILE",
        help="reference: the JSON of 'mindyn excite' (its Fourier series) or a CSV with columns "
        "t, q1..qN [, dq1..dqN, ddq1..ddqN], t in s (or as its header says: t[ms], t[s] for "
        "samples 0.5 s or more apart) (default: a sum of sines within the joint limits)",
    )
    number(
        p,
        "--cycle",
        low=0,
        high=1e6,
        low_open=True,
        help="period of the default reference and of the per-cycle figures [s], at least 20 "
        "controller periods (default 10)",
    )
    number(
        p,
        "--param-error",
        low=0,
        high=10,
        help="relative error of the initial estimate of adaptive PD and computed torque: each "
        "link's mass and second moments and each rotor inertia and friction coefficient off by "
        "up to this fraction, every link kept physically consistent (default 0.3: +-30 %); "
        "simulate's computed torque without --gains and --param-error has the true parameters",
    )
    number(
        p,
        "--substeps",
        low=1,
        high=1000,
        integer=True,
        help="RK4 steps per period (default: at least 4, more where the robot's viscous friction "
        "on its inertia needs them for RK4 to stay stable; stated in the output)",
    )
    p.add_argument(
        "--integrator",
        choices=["rk4", "scipy"],
        default="rk4",
        help="rk4: fixed-step Runge-Kutta, --substeps steps per controller period (default); "
        "scipy: scipy's adaptive RK45 between controller samples",
    )
    p.add_argument(
        "--torque-limit",
        type=torque_limit,
        default="none",
        metavar="effort|none|NM",
        help="effort: saturate each joint's torque at the robot's effort limit; NM: at +-NM "
        "[N m, N] on every joint; none: no limit (default)",
    )
    p.add_argument(
        "--report",
        metavar="DIR",
        type=output_dir,
        help="write the tracking report here: summary.json, log.csv and plots",
    )
    p.set_defaults(implied=report_outputs)
