"""Command-line subcommands of the control side: ``track`` (closed-loop tracking simulation) and
``ik`` (position inverse kinematics)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from .args import ZCR07S_STUDY, UsageError, add_command, deprecated
from .closed_loop import (
    add_closed_loop_args,
    applied_limit,
    check_controller_options,
    limit_words,
    reference_and_controller,
)
from .number_options import (
    Number,
    check_radians,
    controller_period,
    item,
    joint_values,
    joint_vector,
    number,
    seed,
)
from .outputs import output_file
from .robot_options import add_drive_side, add_robot, drive_side_words, load_robot, with_drive_side

#: The ZCR07S study's maximum position errors on the real ZCR07S, joints 1-6 [deg].
ZCR07S_STUDY_MAX_ERROR_DEG = [0.06, 0.22, 0.34, 0.29, 0.45, 0.85]


def _row(label: str, values, fmt: str = "{:9.4f}") -> str:
    return f"{label:<28}" + "".join(fmt.format(v) for v in values)


def cmd_track(args: argparse.Namespace) -> int:
    from ..control.simulation import (
        SensorNoise,
        simulate,
        summary,
        torque_unit,
        write_tracking_report,
    )

    check_controller_options(args)
    robot = with_drive_side(load_robot(args, command="track"), args)
    n = robot.n
    if args.param_error is None:
        args.param_error = 0.3
    reference, ref_text, duration, cycle, controller, base = reference_and_controller(
        args, robot, lambda ref: 2 * ref.period
    )
    gains = controller.gains
    limit = applied_limit(args.torque_limit, n)
    result = simulate(
        robot,
        reference,
        controller,
        rate=1.0 / args.period,
        duration=duration,
        substeps=args.substeps,
        integrator=args.integrator,
        rotor=True,
        friction=True,
        noise=SensorNoise(position=args.noise[0], velocity=args.noise[1]),
        torque_limit=limit,
        seed=args.seed,
        endpoint=False,
    )
    s = summary(result, cycle=cycle)
    lines = [
        f"{robot.name}: {args.controller}, period {args.period * 1e3:g} ms, {duration:g} s, "
        f"{ref_text}"
        + (
            f"; rotor inertia and friction {drive_side_words(robot, args)}"
            if drive_side_words(robot, args)
            else ""
        ),
    ]
    if args.controller != "pd":
        lines.append(
            f"  initial estimate: the base parameters of the robot with each link's mass and "
            f"second moments and each rotor inertia and friction coefficient x "
            f"|1 + {args.param_error:g} u|, u uniform in [-1, 1] (seed {args.seed}), every link "
            f"kept physically consistent; {base.n} base parameters with rotor inertia and friction"
        )
    if args.noise[0] > 0 or args.noise[1] > 0:
        lines.append(
            f"  sensor noise: sigma_q {args.noise[0]:g} rad, sigma_dq {args.noise[1]:g} rad/s"
        )
    if limit is not None:
        lines.append(
            f"  torque limits: {limit_words(args.torque_limit)}, saturated "
            f"{100 * s['saturated_fraction']:.2f} %"
        )
    if gains is not None and gains.note_for(args.controller):
        lines.append(f"  {gains.note_for(args.controller)}")
    if "stability" in result.info:
        lines.append(f"  {result.info['stability']}")
    lines.append(f"  integration: {result.info['integrator']}")
    lines.append("")
    lines.append(_row("joint", range(1, n + 1), "{:>9d}"))
    lines.append(_row(f"max |q - q_d| [{s['error_unit']}]", s["max_error_deg"]))
    if robot.name == "zcr07s" and args.controller == "adaptive-pd" and n == 6:
        lines.append(_row("  the ZCR07S study (real robot)", ZCR07S_STUDY_MAX_ERROR_DEG, "{:9.2f}"))
    lines.append(_row(f"final q - q_d [{s['error_unit']}]", s["final_error_deg"]))
    rms = s["rms_error_deg_per_cycle"]
    lines.append(_row("RMS error, first cycle", rms[0]))
    if len(rms) > 1:
        lines.append(_row(f"RMS error, cycle {len(rms)}", rms[-1]))
    if "torque_prediction_rms_per_cycle" in s:
        tp = s["torque_prediction_rms_per_cycle"]
        unit = torque_unit(robot.joint_types)
        lines.append(_row(f"|Y (p_hat - p)| RMS, first [{unit}]", tp[0]))
        if len(tp) > 1:
            lines.append(_row(f"|Y (p_hat - p)| RMS, cycle {len(tp)}", tp[-1]))
    if "parameter_error_norm" in s:
        pe = s["parameter_error_norm"]
        lines.append(f"parameter error |p_hat - p|: {pe[0]:.4g} at t = 0, {pe[-1]:.4g} at the end")
    if args.output:
        from ..identification.data import link_frames, truth_path

        path = result.save(args.output, robot_name=robot.name, link_frames=link_frames(robot))
        lines.append(
            f"log: {path} ({result.t.size} samples: t, q, dq, tau in N m) and {truth_path(path)}"
        )
    if args.report:
        header = {
            "robot": robot.name,
            "reference": ref_text,
            "gains": {k: np.asarray(v).tolist() for k, v in gains.items()},
            "param_error": args.param_error,
            "seed": args.seed,
            "noise": list(args.noise),
            "torque_limit": args.torque_limit,
            "integrator": result.info["integrator"],
        }
        if robot.name == "zcr07s" and args.controller == "adaptive-pd":
            header["zcr07s_max_error_deg"] = ZCR07S_STUDY_MAX_ERROR_DEG
        write_tracking_report(result, args.report, cycle=cycle, header=header)
        lines.append(f"report: {args.report}/ (summary.json, log.csv, plots)")
    print("\n".join(lines))
    return 0


def cmd_ik(args: argparse.Namespace) -> int:
    from ..inverse_kinematics import IK_ORIENTATION_WEIGHT, ik_solve, pose_from_xyz_rpy

    robot = load_robot(args, command="ik")
    if args.position_only and args.rpy is not None:
        raise UsageError("--rpy: --position-only leaves the orientation free; give one of them")
    rpy = [0.0, 0.0, 0.0] if args.rpy is None else args.rpy
    scale = np.pi / 180.0 if args.deg else 1.0
    if not args.deg:
        check_radians(rpy, "--rpy", "--deg")
    T = pose_from_xyz_rpy(args.xyz, np.asarray(rpy, dtype=float) * scale)
    q0 = None
    if args.q0 is not None:
        revolute = np.array([t == "revolute" for t in robot.joint_types])
        q0 = np.asarray(joint_values(args.q0, robot.n, "--q0"), dtype=float)
        if not args.deg:
            check_radians(q0, "--q0", "--deg", robot)
        q0 = np.where(revolute, q0 * scale, q0)
    r = ik_solve(
        robot,
        T,
        q0,
        tolerance=args.tolerance,
        max_time=args.timeout,
        seed=args.seed,
        orientation_weight=0.0 if args.position_only else IK_ORIENTATION_WEIGHT,
    )
    frame = _tool_frame_words(robot)
    doc = {
        "robot": robot.name,
        "frame": frame,
        "success": r.success,
        "status": r.status,
        "q": r.q.tolist(),
        "pose_error": r.error,
        "position_only": r.position_only,
        "pose_error_definition": "|p_target - p(q)| [m]: the position alone, the orientation "
        "free (the tolerance applies to it)"
        if r.position_only
        else "|log6(T_target^-1 T(q))|: metres and radians together, unweighted (the tolerance "
        "applies to it)",
        "position_error_m": r.position_error,
        "orientation_error_rad": r.orientation_error,
        "iterations": r.iterations,
        "attempts": r.attempts,
    }
    if args.json:
        Path(args.json).write_text(json.dumps(doc, indent=2) + "\n")
        if args.format != "json":  # standard output carries the document otherwise
            print(f"wrote {args.json}")
    if args.format == "json":
        print(json.dumps(doc, indent=2))
    else:
        print(
            f"{robot.name}: {r.status} ({r.error_text()}; {r.iterations} iterations, "
            f"{r.attempts} attempt{'s' if r.attempts != 1 else ''})"
        )
        print(f"  frame: {frame}")
        width = max([16, *map(len, robot.joint_names)])
        for k in range(robot.n):
            unit = "rad" if robot.joint_types[k] == "revolute" else "m  "
            extra = f"  {np.degrees(r.q[k]):10.4f} deg" if unit == "rad" else ""
            print(f"  {robot.joint_names[k]:<{width}} {r.q[k]:12.6f} {unit}{extra}".rstrip())
    if not r.success:
        hint = ""
        if not r.position_only:
            from ..inverse_kinematics import POSE_RANK_SAMPLES, pose_rank

            rank, moving = pose_rank(robot)
            if rank < 6:
                hint = (
                    f"; the tool frame's Jacobian has rank {rank} over the {len(moving)} "
                    f"joint(s) that move it (at most, at {POSE_RANK_SAMPLES} configurations "
                    "within the limits): its pose moves in fewer than 6 directions, so most "
                    "positions are reached in few orientations only: --position-only leaves "
                    "the orientation free"
                )
        print(
            f"mindyn: error: no joint solution inside the limits reached the "
            f"{'position' if r.position_only else 'pose'} ({r.status}; best point: "
            f"{r.error_text()}){hint}",
            file=sys.stderr,
        )
        return 1
    return 0


def _tool_frame_words(robot) -> str:
    """The frame whose pose ``ik`` solves for, in words: the last link's frame moved by the
    description's tool offset (a URDF's fixed links after the last moving one are not part of
    it unless the chain is loaded to one of them with ``--tip``)."""
    from scipy.spatial.transform import Rotation

    last = robot.link_names[-1]
    tool = np.asarray(robot.tool)
    if np.allclose(tool, np.eye(4), rtol=0.0, atol=0.0):
        where = f"the frame of link '{last}', the last moving link"
    else:
        offset = "xyz " + " ".join(f"{v:.6g}" for v in tool[:3, 3]) + " m"
        if not np.array_equal(tool[:3, :3], np.eye(3)):  # as --rpy takes it (fixed axes x, y, z)
            rpy = Rotation.from_matrix(tool[:3, :3]).as_euler("xyz")
            offset += ", rpy " + " ".join(f"{v:.6g}" for v in rpy) + " rad"
        where = f"the tool frame: link '{last}' moved by the tool offset ({offset})"
    if robot.convention == "urdf" and where.startswith("the frame"):
        where += " (a fixed link after it: --tip LINK)"
    return where


def register(sub) -> None:
    """Adds ``track`` and ``ik`` to the ``mindyn`` subcommands."""
    p = add_command(
        sub,
        "track",
        description="Simulates the robot (true parameters with rotor inertia and friction, RK4) "
        "under a controller sampled every --controller-period seconds with zero-order hold. "
        "Adaptive PD is the Slotine-Li controller on the base parameters: tau = Y p_hat - K_D s, "
        "dp_hat/dt = -Gamma Y^T s / (1 + nu |Y|^2), s = de + Lambda e, e = q - q_d. Default gains: "
        f"those of {ZCR07S_STUDY} "
        "for zcr07s (K_D = diag(400, 350, 130, 22, 9, 2), Lambda = diag(10, 10, 10, 30, 30, 25), "
        "Gamma = 1) when their sampled loops are stable at --controller-period, otherwise "
        "derived from the mass matrix sampled over the workspace and the period: Lambda = 10 and "
        "K_D = 40 x the "
        "smallest effective inertia of each joint, raised per joint until K_P >= 2 Fc / "
        "(--tracking-tolerance / 2) holds its Coulomb friction Fc, and lowered (not below "
        "that) until the sampled loops keep a gain margin of 3 (a controller that cannot have "
        "both at the period is refused, naming the joint and a period that allows it), Gamma = 1 "
        "normalised by nu = 3 Gamma T / min K_D (the sampled update's "
        "step condition T lambda_max(K_D^-1/2 Y Gamma Y^T K_D^-1/2) / (1 + nu |Y|^2) < 1 kept "
        "below a third); the estimate is kept in a box about the description's values where "
        "the linearised sampled loop stays stable with the parameters moving together "
        "(--estimate-box none: no box); the output states the choice and the "
        "step condition along the reference. A loop that the linearised check finds unstable "
        "is refused, one that diverges is stopped, each with the figures that explain it "
        "(exit status 2).",
    )
    add_robot(p)
    add_drive_side(p)
    add_closed_loop_args(p, "adaptive-pd")
    from ..control.simulation import MAX_STEPS

    controller_period(
        p,
        default=0.004,
        help=f"controller period [s]; duration / period x substeps at most {MAX_STEPS:,}",
    )
    number(
        p,
        "--duration",
        low=0,
        high=1e6,
        low_open=True,
        help="simulated time [s] (default: two cycles, or the CSV's)",
    )
    seed(p, "--seed", help="seed of the estimate error and noise")
    for index, (flag, unit) in enumerate(
        [("--position-noise", "rad, m"), ("--velocity-noise", "rad/s, m/s")]
    ):
        kind = flag[2:].split("-")[0]
        item(
            p,
            flag,
            dest="noise",
            index=index,
            low=0,
            high=10,
            default=[0.0, 0.0],
            metavar="SD",
            help=f"{kind} sensor noise standard deviation [{unit}]",
        )
    deprecated(
        p,
        "--noise",
        new="--position-noise SD --velocity-noise SD",
        dest="noise",
        nargs=2,
        type=Number(0, 10),
    )
    p.add_argument(
        "-o",
        "--output",
        metavar="CSV",
        type=output_file,
        help="write the log as 'mindyn identify' reads it: t, q1..qN, dq1..dqN, tau1..tauN "
        "(the measured motion and the applied torque, N m) at the controller samples; the true "
        "parameters in <name>.truth.json beside it",
    )
    p.set_defaults(func=cmd_track)

    p = add_command(
        sub,
        "ik",
        description="Damped least squares (Levenberg-Marquardt) with random restarts inside the "
        "limits. Exit status 1 when no solution is found.",
    )
    add_robot(p)
    number(p, "--xyz", nargs=3, required=True, metavar=("X", "Y", "Z"), help="tool position [m]")
    number(
        p,
        "--rpy",
        nargs=3,
        metavar=("R", "P", "Y"),
        help="roll, pitch, yaw about the fixed base axes x, y, z (URDF convention); default 0 0 0",
    )
    p.add_argument(
        "--position-only",
        action="store_true",
        help="solve for the position alone, the orientation free (a tool whose Jacobian has "
        "rank below 6, such as a five-joint arm's, reaches most positions in few orientations "
        "only; a failed pose says so); the tolerance is then the position error's [m]",
    )
    joint_vector(p, "--q0", help="start [rad, m] (default: the middle of the limits)")
    p.add_argument(
        "--deg",
        action="store_true",
        help="--rpy and the revolute joints of --q0 in degrees; without it they are in radians, "
        "and values outside [-2pi, 2pi] are refused",
    )
    tolerance = number(
        p,
        "--pose-tolerance",
        dest="tolerance",
        low=0,
        high=1,
        low_open=True,
        default=1e-5,
        help="largest pose error |log6(T_target^-1 T)| of a solution [m, rad] (--position-only: "
        "largest position error [m])",
    )
    deprecated(p, "--tolerance", tolerance)
    number(p, "--timeout", low=0, high=3600, low_open=True, default=0.5, help="CPU-time budget [s]")
    seed(p, "--seed", default=42, help="seed of the restart points")
    p.add_argument(
        "--format",
        choices=["table", "json"],
        default="table",
        help="what is printed: the joint values (table, the default) or the JSON document",
    )
    p.add_argument(
        "--json",
        metavar="FILE",
        type=output_file,
        help="also write the JSON document (as --format json prints it) to FILE",
    )
    p.set_defaults(func=cmd_ik)
