"""The ``mindyn`` command line."""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from . import ModelError, RobotFileNotFoundError, bundled_robots, load

ROBOT_HELP = (
    "a bundled robot (" + ", ".join(bundled_robots()) + "), a URDF file or a YAML DH/MDH table"
)


def _fmt(x: float, width: int = 10) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-".rjust(width)
    return f"{x:{width}.4g}"


def cmd_info(args: argparse.Namespace) -> int:
    robot = load(args.robot, tip=args.tip)
    n = robot.n
    out = []
    out.append(f"robot      {robot.name}  ({n} joints, {robot.convention})")
    out.append(f"source     {robot.source}")
    g = robot.gravity
    out.append(f"gravity    [{g[0]:g}, {g[1]:g}, {g[2]:g}] m/s^2")
    if robot.synthetic_inertia:
        out.append("inertia    SYNTHETIC: the inertial values are invented, not measured")
    if robot.notes:
        out.append(f"notes      {robot.notes.strip()}")
    out.append("")
    lim = robot.limits
    drv = robot.drives
    deg = {"revolute": 180.0 / math.pi, "prismatic": 1.0}
    dh = robot.dh
    if robot.convention in ("dh", "mdh") and len(dh):
        if robot.convention == "dh":
            head = f"{'a [m]':>9} {'alpha[deg]':>10} {'d [m]':>9} {'theta[deg]':>10}"
        else:
            head = f"{'d [m]':>9} {'alpha[deg]':>10} {'r [m]':>9} {'theta[deg]':>10}"
    else:
        head = f"{'axis (joint frame)':>30}"
    out.append(
        f"{'#':>2} {'joint':<14}{'type':<10}{head} {'lower':>9} {'upper':>9} {'vel':>9} "
        f"{'effort':>9} {'rated':>7} {'gear':>7}"
    )
    out.append(
        "   (limits in deg, deg/s for revolute joints; m, m/s for prismatic; effort N m or N)"
    )
    for k in range(n):
        t = robot.joint_types[k]
        s = deg[t]
        if robot.convention in ("dh", "mdh") and len(dh):
            a, alpha, d, theta = dh[k]
            geo = f"{a:9.4f} {math.degrees(alpha):10.3f} {d:9.4f} {math.degrees(theta):10.3f}"
        else:
            ax = robot.axes[k]
            geo = f"[{ax[0]:8.4f} {ax[1]:8.4f} {ax[2]:8.4f}]".rjust(30)
        out.append(
            f"{k + 1:>2} {robot.joint_names[k]:<14}{t:<10}{geo} {_fmt(lim['lower'][k] * s, 9)} "
            f"{_fmt(lim['upper'][k] * s, 9)} {_fmt(lim['velocity'][k] * s, 9)} "
            f"{_fmt(lim['effort'][k], 9)} {_fmt(drv['rated_torque'][k], 7)} "
            f"{_fmt(drv['gear_ratio'][k], 7)}"
        )
    out.append("")
    out.append("classical parameters about each link-frame origin (SI)")
    names = ["XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M", "Ia", "Fv", "Fc"]
    out.append(f"{'link':<10}" + "".join(f"{c:>11}" for c in names))
    p = robot.params.reshape(n, 10)
    extra = np.column_stack([robot.rotor_inertia, robot.viscous, robot.coulomb])
    for k in range(n):
        row = list(p[k]) + list(extra[k])
        out.append(f"{robot.link_names[k + 1]:<10}" + "".join(f"{v:11.4g}" for v in row))
    out.append(f"total moving mass {p[:, 9].sum():.4g} kg")
    print("\n".join(out))
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="mindyn",
        description="Minimal dynamic models of manipulators.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    p = sub.add_parser("info", help="print a robot model: joints, geometry, limits, parameters")
    p.add_argument("robot", metavar="ROBOT", help=ROBOT_HELP)
    p.add_argument("--tip", help="URDF: the link that ends the chain")
    p.set_defaults(func=cmd_info)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except RobotFileNotFoundError as e:
        print(f"mindyn: error: {e}", file=sys.stderr)
        return 2
    except (ModelError, ValueError, IndexError) as e:
        print(f"mindyn: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("mindyn: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
