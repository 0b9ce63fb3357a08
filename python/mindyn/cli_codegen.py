"""``mindyn codegen``: generated inverse-dynamics code in C99 or Structured Text."""

from __future__ import annotations

import argparse
from pathlib import Path

from . import ModelError, load
from .cli_args import add_joint_terms, add_robot
from .codegen import generate


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "codegen",
        help="generate inverse dynamics, gravity torque and base regressor in C or ST",
        description="Generate the Newton-Euler recursion customised to the robot, in its base "
        "parameters, as C99 (header + source) or IEC 61131-3 Structured Text, and print its "
        "operation counts beside those of the classical-parameter recursion generated the "
        "same way. Constants of the geometry within 1e-9 of 0 (or of +-1, for rotation "
        "entries alone in their row and column) are taken as exact; how many (beyond "
        "round-off) is printed and stated in the generated header.",
    )
    add_robot(p)
    p.add_argument("--lang", choices=["c", "st"], required=True, help="C99 or Structured Text")
    p.add_argument(
        "--what",
        default="id,gravity,regressor",
        help="functions, comma-separated: id (inverse dynamics), gravity, regressor "
        "(default: all three)",
    )
    add_joint_terms(p)
    p.add_argument(
        "--params",
        metavar="FILE",
        help="base-parameter values (JSON mapping or 'NAME value' lines); default: the "
        "robot's own values",
    )
    p.add_argument(
        "--numeric",
        action="store_true",
        help="bake the parameter values in (inverse dynamics and gravity then take no p)",
    )
    p.add_argument(
        "--minimise",
        choices=["operations", "additions"],
        default="operations",
        help="what the choice among exact formulations minimises: multiplications plus "
        "additions (default; ties to fewer additions) or additions first",
    )
    p.add_argument(
        "--trig",
        choices=["inline", "libm"],
        help="C: sines and cosines from a branch-free routine in the generated source (default; "
        "within 2.2e-16 of math.h, math.h beyond |q| > 1e6) or from math.h's sin and cos; "
        "Structured Text always uses SIN and COS",
    )
    p.add_argument("--name", help="prefix of the generated identifiers (default: robot name)")
    p.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="FILE",
        help="C: FILE.c and FILE.h; ST: FILE",
    )
    p.set_defaults(func=cmd_codegen)


def cmd_codegen(args: argparse.Namespace) -> int:
    robot = load(args.robot, tip=args.tip)
    out = Path(args.output)
    if not out.parent.is_dir():
        raise ModelError(f"output folder '{out.parent}' does not exist")
    if args.lang == "c" and out.suffix in (".c", ".h"):
        out = out.with_suffix("")
    header = out.name + ".h"
    same = dict(
        lang=args.lang,
        what=args.what,
        rotor=args.rotor,
        friction=args.friction,
        numeric=args.numeric,
        minimise=args.minimise,
    )
    code = generate(
        robot, params=args.params, name=args.name, header_name=header, trig=args.trig, **same
    )
    # the classical-parameter recursion generated the same way, for its operation counts
    classical = generate(robot, name=code.name, base=False, **same)
    written = code.write(out.with_suffix(".c") if args.lang == "c" else out)
    extras = [x for x, on in (("rotor inertia", args.rotor), ("friction", args.friction)) if on]
    print(
        f"{robot.name}: {len(code.names)} base parameters"
        + (f" ({', '.join(extras)})" if extras else "")
        + (", values baked in" if args.numeric else "")
        + f"; {len(classical.names)} classical"
    )
    print("wrote " + ", ".join(str(w) for w in written))
    snap = code.geometry_snap
    if snap["count"]:
        print(
            f"geometry: {snap['count']} constants within {snap['tolerance']:g} of 0 or +-1 "
            f"taken as exact (largest change {snap['largest']:.2g})"
        )
    print()
    print(f"{'function':<18}{'base parameters':>22}    {'classical parameters':>22}")
    print(f"{'':<18}{'mul':>8}{'add':>7}{'trig':>7}    {'mul':>8}{'add':>7}{'trig':>7}")
    for f, c in code.counts.items():
        k = classical.counts[f]
        print(
            f"{f:<18}{c['mul']:>8}{c['add']:>7}{c['trig']:>7}    "
            f"{k['mul']:>8}{k['add']:>7}{k['trig']:>7}"
        )
    return 0
