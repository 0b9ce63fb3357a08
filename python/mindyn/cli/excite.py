"""CLI: ``mindyn excite``, an optimised excitation trajectory."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from .._core import ArgumentError
from .args import ZCR07S_STUDY, UsageError, add_command, deprecated
from .number_options import check_radians, joint_values, joint_vector, number, seed
from .outputs import output_file
from .robot_options import (
    add_drive_side,
    add_robot,
    add_snap,
    load_robot,
    snap_keyword,
    snap_lines,
    with_drive_side,
)


def cmd_excite(args: argparse.Namespace) -> int:
    from ..base import base_parameters
    from ..identification.excitation import EFFORT_SHARE, check_sampling, optimize_excitation

    if Path(args.output).suffix.lower() in (".json", ".png"):
        raise UsageError(
            f"-o {args.output}: the trajectory CSV needs another suffix than "
            f"{Path(args.output).suffix} (the coefficients and the plot are written beside it as "
            ".json and .png)"
        )
    try:  # before the optimisation, not after it
        check_sampling(args.harmonics, args.freq, args.rate)
    except ArgumentError as e:  # the library's check; a bare ValueError stays a defect
        raise UsageError(f"--rate {args.rate:g}: {e}") from None
    if not args.samples > 2 * args.harmonics:
        raise UsageError(
            f"--samples {args.samples}: expected more than 2 x --harmonics = "
            f"{2 * args.harmonics}, so that the highest harmonic is sampled"
        )
    robot = with_drive_side(load_robot(args, command="excite"), args)
    start = None
    if args.start:
        start = np.array(joint_values(args.start, robot.n, "--start", broadcast=True))
        if args.degrees:
            rev = np.array([t == "revolute" for t in robot.joint_types])
            start = np.where(rev, np.radians(start), start)
        else:
            check_radians(start, "--start", "--deg", robot)
    acc = np.asarray(robot.limits["acceleration"], dtype=float)
    if args.effort_share is not None and np.all(np.isfinite(acc) & (acc > 0)):
        raise UsageError(
            f"--effort-share: applies where the description gives no acceleration limit; "
            f"{robot.name} gives one for every joint (lower those to lower the torques)"
        )
    base = base_parameters(robot, rotor=args.rotor, friction=args.friction, snap=snap_keyword(args))
    res = optimize_excitation(
        robot,
        base=base,
        harmonics=args.harmonics,
        freq=args.freq,
        criterion=args.criterion,
        starts=args.starts,
        seed=args.seed,
        rotor=args.rotor,
        friction=args.friction,
        samples=args.samples,
        maxiter=args.maxiter,
        margin=args.margin,
        effort_share=EFFORT_SHARE if args.effort_share is None else args.effort_share,
        start=start,
        progress=not args.quiet,
    )
    paths = res.save(args.output, rate=args.rate)
    shown = {"cond": "condition number", "logdet": "log det(W^T W / rows)"}.get(
        res.criterion, "log Hadamard ratio"
    )
    print(
        f"{robot.name}: {res.trajectory.harmonics} harmonics at {res.trajectory.freq:g} Hz "
        f"(period {res.trajectory.period:g} s), {len(res.base_names)} base parameters"
    )
    print(f"  {shown}: {res.value:.6g} (initial guess {res.initial_value:.6g})")
    for line in snap_lines(base, "  base set: ", detail=False):
        print(line)
    for note in res.notes:
        if note.startswith("acceleration limits"):
            print(f"  {note}")
    print(f"  {res.peak_torque['line']}")
    for warning in res.warnings:
        print(f"  WARNING: {warning}")
    print(f"  limits respected on a fine grid (largest relative excess {res.max_violation:.2g})")
    print(f"  wrote {paths['csv']} ({args.rate:g} Hz), {paths['json']}, {paths['png']}")
    return 0


def register(sub) -> None:
    """Adds ``excite`` to the ``mindyn`` subcommands."""
    from ..identification.excitation import MAX_TRAJECTORY_ROWS

    p = add_command(
        sub,
        "excite",
        description="Finite Fourier series per joint, zero velocity and acceleration at start and "
        "end, optimised (SLSQP, several random starts) for a conditioning criterion of the "
        "stacked base regressor under the robot's position, velocity and acceleration limits. "
        "Writes the sampled trajectory (CSV), the coefficients (JSON, same name) and a plot (PNG).",
    )
    add_robot(p)
    number(
        p,
        "--harmonics",
        low=2,
        high=30,
        integer=True,
        default=5,
        help="harmonics N (the limits are imposed on max(100, 20 N) points per period, each "
        "a constraint of the optimisation)",
    )
    number(p, "--freq", low=0, high=1000, low_open=True, default=0.1, help="base frequency [Hz]")
    p.add_argument(
        "--criterion",
        choices=["cond", "logdet", "hadamard"],
        default="cond",
        help="condition number (default), D-optimality, or the Hadamard-bound ratio of "
        + ZCR07S_STUDY,
    )
    number(p, "--starts", low=1, high=100, integer=True, default=3, help="random starting guesses")
    seed(p, "--seed")
    number(
        p,
        "--maxiter",
        low=1,
        high=10000,
        integer=True,
        default=100,
        help="SLSQP iterations per start (the work is about --starts x --maxiter iterations)",
    )
    number(
        p,
        "--samples",
        low=1,
        high=10000,
        integer=True,
        default=100,
        help="regressor samples per period (more than 2 N: the highest harmonic is sampled)",
    )
    number(
        p,
        "--margin",
        low=0,
        high=0.5,
        high_open=True,
        default=0.05,
        help="fraction the limits are tightened by",
    )
    number(
        p,
        "--effort-share",
        low=0,
        high=1,
        low_open=True,
        default_when_unset=0.8,  # identification.excitation.EFFORT_SHARE
        help="where the description gives no acceleration limit (URDF never does), each joint's "
        "is derived so that the inverse-dynamics torque (gravity, velocity terms at the velocity "
        "limits, the mass matrix with the other joints' accelerations at their limits, over 64 "
        "sampled configurations) stays within this share of its effort limit; without an effort "
        "limit the fixed 6 rad/s^2 (2 m/s^2) is used. Both are stated, and the trajectory's peak "
        "torques are reported against the effort limits",
    )
    p.add_argument("--rotor", action="store_true", help="base parameters with rotor inertia")
    p.add_argument("--friction", action="store_true", help="base parameters with friction")
    add_drive_side(p)
    add_snap(p)
    joint_vector(
        p, "--start", help="prescribed start position [rad, m] (or one value for all joints)"
    )
    deg = p.add_argument(
        "--deg",
        dest="degrees",
        action="store_true",
        help="the revolute joints of --start in degrees",
    )
    deprecated(p, "--degrees", deg)
    number(
        p,
        "--rate",
        low=0,
        high=1e6,
        low_open=True,
        default=250.0,
        help="CSV sample rate [Hz], above 2 N freq (the highest harmonic is sampled) and at most "
        f"{MAX_TRAJECTORY_ROWS:,} rows per period",
    )
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="CSV",
        type=output_file,
        help="trajectory CSV to write (and its .json and .png beside it)",
    )
    p.set_defaults(func=cmd_excite, implied=_implied)


def _implied(args: argparse.Namespace) -> list[tuple[str, str, str, Path, str]]:
    """The files excite writes beside the trajectory CSV: its coefficients (.json) and plot
    (.png)."""
    out, remedy = Path(args.output), "give --output another file name"
    return [
        ("--output", str(out), what, out.with_suffix(suffix), remedy)
        for what, suffix in (("coefficients file", ".json"), ("plot", ".png"))
    ]
