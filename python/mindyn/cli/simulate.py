"""CLI: ``mindyn simulate``, a simulated joint log (a stand-in for a robot)."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from .args import UsageError, add_command, given_options, remember_flags
from .number_options import controller_period, number, seed
from .outputs import output_file
from .robot_options import add_drive_side, add_robot, drive_side_words, load_robot, with_drive_side

#: The options of the closed loop, which --mode inverse (no controller) does not take
TRACKING_ONLY = (
    "controller",
    "gains",
    "param_error",
    "substeps",
    "integrator",
    "torque_limit",
    "tracking_tolerance",
)


def _check_mode(args: argparse.Namespace) -> None:
    """--mode inverse refuses the closed loop's options instead of ignoring them."""
    given = given_options(args, *TRACKING_ONLY) if args.mode == "inverse" else []
    if given:
        raise UsageError(
            f"{given[0]}: an option of the closed loop (--mode tracking); --mode inverse has no "
            "controller (the torques of the inverse dynamics along the reference)"
        )


def cmd_simulate(args: argparse.Namespace) -> int:
    from ..control.simulation import (
        SensorNoise,
        error_unit,
        noise_from_spec,
        simulate,
        simulate_inverse,
        write_tracking_report,
    )
    from ..identification.data import convert_torque, write_csv
    from .closed_loop import applied_limit, check_controller_options, reference_and_controller

    _check_mode(args)
    check_controller_options(args)
    robot = with_drive_side(load_robot(args, command="simulate"), args)
    rate = 1.0 / args.period if args.period else args.rate
    args.period = 1.0 / rate
    ref, ref_text, duration, cycle, controller, _ = reference_and_controller(
        args, robot, lambda r: r.duration
    )
    ref_tau = None
    if args.torque_noise and args.torque_noise.strip().endswith("%"):
        t = np.linspace(0, ref.duration, 200)
        ref_tau = robot.inverse_dynamics(*ref.evaluate(t))
    noise = SensorNoise(
        torque=noise_from_spec(args.torque_noise, robot, "torque", reference_torque=ref_tau),
        position=noise_from_spec(args.position_noise, robot, "position"),
        velocity=noise_from_spec(args.velocity_noise, robot, "velocity"),
        quantization=noise_from_spec(args.quantization, robot, "quantization"),
    )
    kwargs = dict(
        rate=rate,
        duration=duration,
        rotor=args.rotor,
        friction=args.friction,
        noise=noise,
        seed=args.seed,
    )
    if args.mode == "tracking":
        limit = applied_limit(args.torque_limit, robot.n)
        log = simulate(
            robot,
            ref,
            controller,
            substeps=args.substeps,
            integrator=args.integrator,
            torque_limit=limit,
            **kwargs,
        )
    else:
        log = simulate_inverse(robot, ref, **kwargs)
    from ..identification.data import link_frames

    path = log.save(
        args.output,
        robot_name=robot.name,
        joint_names=robot.joint_names,
        link_frames=link_frames(robot),
    )
    if args.torque_unit == "permille":
        scale, _ = convert_torque(np.ones((1, robot.n)), "permille", robot)
        write_csv(path, log.t, log.q, log.tau / scale, dq=log.dq, torque_unit="permille")
    info = log.info
    given = robot.drive_terms_given()
    none = " (zero in the description: no effect)"
    rotor = f"on{'' if 'Ia' in given else none}" if args.rotor else "off"
    friction = f"on{'' if set(given) - {'Ia'} else none}" if args.friction else "off"
    print(
        f"{robot.name}: {info['mode']} simulation, {log.t.shape[0]} samples at {rate:g} Hz "
        f"({info['duration_s']:g} s), rotor inertia {rotor}, friction {friction}"
        + (f", {side}" if (side := drive_side_words(robot, args)) else "")
    )
    print(f"  reference: {ref_text}")
    if info["mode"] == "tracking":
        err = log.max_error_deg()
        print(
            f"  controller {info['controller']}; max tracking error per joint "
            f"[{error_unit(robot.joint_types)}]: " + " ".join(f"{e:.3g}" for e in err)
        )
        shortfall = ""
        if controller is None and args.friction:  # the simulator's default computed torque
            from ..control.controllers import friction_shortfall
            from .closed_loop import joint_tolerance

            tolerance = joint_tolerance(robot, args.tracking_tolerance)
            shortfall = friction_shortfall(robot, rotor=args.rotor, tolerance=tolerance)
            if shortfall:  # the command's way to the default gains
                shortfall = shortfall.replace(
                    "(the gains of default_gains hold it or are refused)",
                    "(--param-error 0 takes the default gains, which hold it or are refused)",
                )
        for note in (
            gains.note_for(args.controller)
            if (gains := getattr(controller, "gains", None))
            else "",
            info.get("stability"),
            shortfall,
        ):
            if note:
                print(f"  {note}")
        print(f"  integration: {info['integrator']}")
    nz = info["noise"]
    print(
        "  torque noise sd per joint: "
        + " ".join(f"{v:.3g}" for v in nz["torque"])
        + _noise_basis(args.torque_noise, robot, ref_tau)
    )
    if any(nz["quantization"]) or any(nz["position"]) or any(nz["velocity"]):
        print(
            f"  encoder step {max(nz['quantization']):.3g}, position noise "
            f"{max(nz['position']):.3g}, velocity noise {max(nz['velocity']):.3g}"
        )
    unit = " (torques in permille of rated torque)" if args.torque_unit == "permille" else ""
    print(f"  wrote {path}{unit} and {path.with_name(path.stem + '.truth.json')}")
    if args.report:
        header = {"robot": robot.name, "reference": ref_text, "seed": args.seed}
        write_tracking_report(log, args.report, cycle=cycle, header=header)
        print(f"  report: {args.report}/ (summary.json, log.csv, plots)")
    return 0


def _noise_basis(spec: str | None, robot, reference_torque) -> str:
    """The unit of the torque noise and, given in percent, what it was taken of per joint."""
    from ..control.simulation import torque_noise_scale

    if not spec:
        return ""
    if not spec.strip().endswith("%"):
        return " [N m | N]"
    pct = spec.strip()[:-1].strip()
    return f" [N m | N], {pct} % of {torque_noise_scale(robot, reference_torque)[2]}"


def register(sub) -> None:
    """Adds ``simulate`` to the ``mindyn`` subcommands."""
    from ..control.simulation import EFFORT_PLACEHOLDER_ABOVE as ABOVE
    from ..control.simulation import EFFORT_PLACEHOLDER_BELOW as BELOW
    from ..control.simulation import MAX_SAMPLES, MAX_STEPS
    from .closed_loop import add_closed_loop_args

    p = add_command(
        sub,
        "simulate",
        description="Produces what a joint controller would log (t, q, dq, tau): the robot with "
        "its true parameters integrated (RK4) under a tracking controller, or torques from "
        "inverse dynamics along the reference (--mode inverse); optional sensor noise and "
        "encoder quantisation. Also writes <output>.truth.json with the true parameters. "
        "The controller and the reference are those of 'mindyn track' (default: computed torque "
        "with the true parameters and Coulomb friction on the reference velocity, K_P = 400, "
        "K_D = 40; a sum of sines within the limits when no --trajectory is given).",
    )
    add_robot(p)
    p.add_argument(
        "--mode",
        choices=["tracking", "inverse"],
        default="tracking",
        help="tracking: the robot integrated under the controller (default); inverse: torques "
        "from inverse dynamics along the reference, no controller (the closed loop's options "
        "--controller, --gains, --param-error, --substeps, --integrator, --torque-limit are "
        "refused)",
    )
    add_closed_loop_args(p, "computed-torque")
    remember_flags(p)
    g = p.add_mutually_exclusive_group()
    number(
        g, "--rate", low=0, high=1e6, low_open=True, default=250.0, help="control and log rate [Hz]"
    )
    controller_period(g, low=1e-6, high=1e3, help="control and log period [s] (1 / rate)")
    number(
        p,
        "--duration",
        low=0,
        high=1e6,
        low_open=True,
        help=f"seconds (default: one period of the reference); at most {MAX_SAMPLES:,} samples "
        f"(duration x rate) and {MAX_STEPS:,} integration steps (x substeps)",
    )
    p.add_argument("--rotor", action="store_true", help="true robot with rotor inertia")
    p.add_argument("--friction", action="store_true", help="true robot with friction")
    add_drive_side(p)
    p.add_argument(
        "--torque-noise",
        metavar="SD",
        help="torque noise sd: one value, one per joint (comma-separated), or P%% of each "
        "joint's effort limit (of its peak torque along the reference where the description "
        f"gives none or a placeholder: over {ABOVE:g} x the largest peak torque of any joint, "
        f"or under {BELOW:g} x the joint's own; the output says which); in [0, 1e6] N m or "
        "[0, 100] %%",
    )
    p.add_argument(
        "--position-noise", metavar="SD", help="position noise sd (rad, m), each in [0, 1]"
    )
    p.add_argument(
        "--velocity-noise", metavar="SD", help="velocity noise sd (rad/s, m/s), each in [0, 100]"
    )
    p.add_argument("--quantization", metavar="STEP", help="encoder step (rad, m), each in [0, 1]")
    seed(p, "--seed", help="noise seed")
    p.add_argument(
        "--torque-unit",
        choices=["Nm", "permille"],
        default="Nm",
        help="write torques in N m (the default) or in permille of rated torque (drive table; "
        "the header then says tau1[permille]...)",
    )
    p.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="CSV",
        type=output_file,
        help="log to write (and its .truth.json beside it)",
    )
    p.set_defaults(func=cmd_simulate, implied=_implied)


def _implied(args: argparse.Namespace) -> list[tuple[str, str, str, Path, str]]:
    """The files simulate writes beside its outputs: the truth file beside the log, the
    tracking report's files."""
    from ..identification.data import truth_path
    from .closed_loop import report_outputs

    truth = truth_path(args.output)
    remedy = "give --output another file name"
    return [("--output", str(args.output), "truth file", truth, remedy), *report_outputs(args)]
