"""``mindyn codegen``: generated inverse-dynamics code and controller steps in C99 or Structured
Text, optionally packed as a PLCopen XML project (the steps: :mod:`.codegen_steps`; the output
files: :mod:`.codegen_output`; the parameter values: :mod:`.codegen_params`)."""

from __future__ import annotations

import argparse

from ..base import base_parameters
from ..codegen import CONTROLLERS, FUNCTIONS, generate
from .args import UsageError, add_command
from .closed_loop import add_tolerance_arg, torque_limit
from .codegen_output import (
    DEFAULT_FOLDER,
    OBSERVER,
    _output_base,
    _outputs,
    _stem,
    _write,
    _write_plcopen,
)
from .codegen_params import (
    _identified_layout,
    _identified_params,
    _identified_snap,
    _on_identified_drive_side,
    _params_note,
    _with_friction_model,
)
from .codegen_steps import _controller, _observer, refuse_controller_options
from .method import base_method
from .number_options import controller_period, joint_vector
from .outputs import output_file
from .robot_options import (
    add_joint_terms,
    add_offset,
    add_robot,
    add_snap,
    drive_side,
    joint_terms,
    load_robot,
    require_single_dof,
    snap_keyword,
    snap_lines,
)

#: The default controller period [s] of the generated controller and observer steps
PERIOD = 0.004


def register(subparsers) -> None:
    p = add_command(
        subparsers,
        "codegen",
        description="Generate the Newton-Euler recursion customised to the robot, in its base "
        "parameters, as C99 (header + source) or IEC 61131-3 Structured Text, and print its "
        "operation counts beside those of the classical-parameter recursion generated the "
        "same way (by default for robots of single-DOF joints only: on a floating base the "
        "second generation takes several times as long as the first). Constants of the "
        "geometry within 1e-9 of 0 (or of +-1, for rotation entries alone in their row and "
        "column) are taken as exact; how many (beyond round-off) is printed and stated in the "
        "generated header. With --what adaptive-pd, computed-torque or gravity-compensation: "
        "one controller step instead (C: a state struct, init and step; ST: one "
        "FUNCTION_BLOCK) and its operation counts.",
    )
    add_robot(p)
    p.add_argument(
        "--lang",
        choices=["c", "st"],
        help="C99 or Structured Text (needed with -o unless its FILE ends in .c, .h or .st; "
        "--plcopen alone generates Structured Text)",
    )
    p.add_argument(
        "--what",
        default="id,gravity,regressor",
        help="functions, comma-separated: id (inverse dynamics), gravity, regressor "
        "(default: all three); or one controller step: adaptive-pd (Slotine-Li, as "
        "mindyn.control.AdaptivePD, with its regressor products generated from the recursion "
        "customised to the robot), computed-torque, gravity-compensation; or the "
        f"{OBSERVER} step (the generalised-momentum residual of mindyn.control."
        "MomentumObserver, with the torque held over the period, to run beside a controller "
        "step)",
    )
    add_joint_terms(p)
    add_offset(p)
    add_snap(p)
    p.add_argument(
        "--contact",
        nargs="+",
        metavar="LINK",
        help="floating-base robot, C inverse dynamics: the links in contact, whose wrenches "
        "(force, then moment about the link's origin) the function takes after the parameters, "
        "6 per link in this order, and returns tau = rnea - sum J_c^T f_c (default: none)",
    )
    p.add_argument(
        "--wrench-frame",
        choices=("world", "local"),
        default=None,
        help="with --contact: the axes of the contact wrenches, world (the default) or local, "
        "the link's own axes",
    )
    p.add_argument(
        "--classical-counts",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="also generate the classical-parameter recursion the same way and print its "
        "operation counts beside the base-parameter ones (a second generation, which takes "
        "longer than the first: on a humanoid on a free-flyer several times as long); "
        "default: on for a robot of single-DOF joints, off with joints of several DOF",
    )
    p.add_argument(
        "--params",
        metavar="FILE",
        help="base-parameter values: the JSON that 'mindyn identify --json' writes (the "
        "parameters it pruned for a high relative standard deviation are taken as zero, and "
        "the output says how many; the friction model it records, friction_model: {kind, "
        "velocity}, is the generated code's, else Coulomb; its rotor inertia, friction and "
        "offset too when none of --rotor, --friction, --offset is given), a JSON mapping, or "
        "'NAME value' lines; default: the robot's own values",
    )
    p.add_argument(
        "--consistent",
        action="store_true",
        help="with --params an identification JSON: its consistent estimate (identify "
        "--consistent; every base parameter, none pruned) instead of the unconstrained one",
    )
    method_help = (
        "how the base parameters are found, as 'mindyn base --method': the exact projection "
        "method, the exact recursive method, or the numerical method (sampled regressor + QR); "
        "default: the projection method, or the recursive one (the same base set) where the "
        "projection method's limits or cost estimate refuse the robot, as mindyn base chooses"
    )
    methods = ["projection", "recursive", "numerical"]
    p.add_argument("--method", choices=methods, help=method_help)
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
    c = p.add_argument_group(
        "controller steps (--what adaptive-pd, computed-torque, gravity-compensation)"
    )
    c.add_argument(
        "--gains",
        metavar="FILE",
        help="YAML with kd, lambda, gamma, nu, kp (as 'mindyn track --gains' reads it; default: "
        "the robot's default gains, as 'mindyn track' uses them); --params gives the initial "
        "estimate",
    )
    controller_period(
        c,
        low=1e-6,  # the library's least period (mindyn.control.MIN_PERIOD), checked again below
        help=f"controller period [s] of the controller and observer steps (default {PERIOD:g})",
    )
    add_tolerance_arg(c)
    joint_vector(
        c,
        "--observer-gain",
        metavar="K_O",
        help=f"--what {OBSERVER}: gain K_O [1/s], one or one per joint, each below 2 / period "
        "(default 1 / (10 period), a time constant of ten periods)",
    )
    c.add_argument(
        "--torque-limit",
        type=torque_limit,
        metavar="effort|none|NM",
        help="saturate the torque at the robot's effort limits or at +-NM [N m, N] on every "
        "joint; none: no limit (the default), as track and simulate take it",
    )
    c.add_argument(
        "--box",
        type=float,
        metavar="F",
        help="keep each estimate within F |p0| of its initial value p0 (default, base "
        "parameters: the box of 'mindyn track' about the description's values, p0 projected "
        "onto it; stated in the output)",
    )
    p.add_argument(
        "--plcopen",
        metavar="XML",
        type=output_file,
        nargs="?",
        const=True,  # --plcopen alone: the default path
        help="write a PLCopen XML (TC6 v2.01) project with the Structured Text function "
        "blocks (the controller, inverse dynamics, gravity, regressor and the momentum "
        f"observer) for CODESYS; without XML: {DEFAULT_FOLDER}/NAME.xml (a folder: NAME.xml "
        "inside it), the path written is printed",
    )
    p.add_argument("--name", help="prefix of the generated identifiers (default: robot name)")
    p.add_argument(
        "-o",
        "--output",
        metavar="FILE",
        type=output_file,
        help="C: FILE.c and FILE.h (FILE: the path without a .c, .h or .st suffix; any other "
        "suffix is kept in both names); ST: FILE; a folder: NAME.c and NAME.h, or NAME.st, inside "
        "it (NAME: --name, or the robot's name, with the controller or observer step's); "
        "-o, --plcopen or both",
    )
    p.set_defaults(func=cmd_codegen, outputs=_outputs)


def cmd_codegen(args: argparse.Namespace) -> int:
    robot = load_robot(args)  # a floating base: C inverse dynamics, gravity, regressor only
    if args.wrench_frame is not None and not args.contact:
        raise UsageError("--wrench-frame: applies with --contact (the contact wrenches' axes)")
    if args.contact and robot.single_dof:
        raise UsageError(
            "--contact: applies to a floating-base robot (--root-joint floating|planar, or a "
            "floating or planar joint at the root of the description)"
        )
    layout_note = _identified_layout(args)
    robot, friction_note = _with_friction_model(robot, args)
    robot, source = _on_identified_drive_side(robot, args)
    robot, drive_note = drive_side(robot, args, source=source)
    args.lang = args.lang or "st"  # --plcopen alone
    out = _output_base(args, robot)
    header = (out.name if out is not None else _stem(args, robot)) + ".h"
    same = dict(
        lang=args.lang,
        what=args.what,
        rotor=args.rotor,
        friction=args.friction,
        numeric=args.numeric,
        minimise=args.minimise,
        offset=args.offset,
    )
    method, why = base_method(robot, args.rotor, args.method, args.friction)
    base = base_parameters(
        robot,
        rotor=args.rotor,
        friction=args.friction,
        offset=args.offset,
        method=method,
        snap=_identified_snap(args) if args.snap == "auto" else snap_keyword(args),
    )
    if method != "projection" and args.method is None:  # said once the method ran
        print(f"base parameters by the {method} method: {why}")
    for note in (layout_note, drive_note, friction_note):
        if note:
            print(note)
    if args.consistent and not args.params:
        raise UsageError("--consistent: takes the consistent estimate of --params FILE: give it")
    params, pruned, threshold = (
        _identified_params(args.params, robot, base, args) if args.params else (None, [], "")
    )
    if args.what.strip() in CONTROLLERS + (OBSERVER,):
        require_single_dof(robot, f"codegen --what {args.what.strip()}")
        if args.classical_counts:  # given (None: the default)
            raise UsageError(
                "--classical-counts: applies to the inverse dynamics, gravity and regressor, "
                "not to a controller or observer step"
            )
        from ..control.controllers import check_period

        # the library's range, said with this command's flag (the library's keyword period is
        # identify's --excitation-period)
        args.period = check_period(
            PERIOD if args.period is None else args.period, what="--controller-period"
        )
        note = _params_note(base.n, args.params, pruned, threshold) if params is not None else None
        given = params if params is not None else args.params
        if args.what.strip() == OBSERVER:
            return _observer(args, robot, base, out, given, note)
        if args.observer_gain is not None:
            raise UsageError(f"--observer-gain: applies to --what {OBSERVER} only")
        return _controller(args, robot, base, out, given, note)
    if args.observer_gain is not None:
        raise UsageError(f"--observer-gain: applies to --what {OBSERVER} only")
    refuse_controller_options(args)
    if args.period is not None:  # the functions of q have no period
        raise UsageError(f"--controller-period: applies to controller and {OBSERVER} steps only")
    if args.numeric and not {w.strip() for w in args.what.split(",")} & {"id", *FUNCTIONS[:2]}:
        raise UsageError(
            "--numeric: applies to the inverse dynamics and gravity (the regressor takes no "
            "parameter values)"
        )
    if any(w.strip() in CONTROLLERS + (OBSERVER,) for w in args.what.split(",")):
        raise UsageError("--what: a controller step is generated alone, not with other functions")
    contacts: dict = {"contacts": args.contact or [], "wrench_frame": args.wrench_frame or "world"}
    code = generate(
        robot,
        **contacts,
        params=params if params is not None else args.params,
        name=args.name,
        header_name=header,
        trig=args.trig,
        base=base,
        **same,
    )
    # the classical-parameter recursion generated the same way, for its operation counts only:
    # on request (a second generation)
    classical = None
    if args.classical_counts or (args.classical_counts is None and robot.single_dof):
        classical = generate(robot, name=code.name, base=False, **contacts, **same)
    written = _write(code, out, args.lang)
    extras = joint_terms(args)
    layout = dict(rotor=args.rotor, friction=args.friction, offset=args.offset)
    print(
        f"{robot.name}: {len(code.names)} base parameters"
        + (f" ({', '.join(extras)})" if extras else "")
        + (", values baked in" if args.numeric else "")
        + f"; {len(robot.parameter_names(**layout))} classical"
        + f"; base set by the {method} method"
        + (" (the default)" if args.method is None and method == "projection" else "")
    )
    if params is not None:
        print(_params_note(len(code.names), args.params, pruned, threshold))
    if args.plcopen is not None:
        st = (
            code
            if args.lang == "st"
            else generate(robot, base=base, name=code.name, **dict(same, lang="st"))
        )
        written.append(_write_plcopen(args, [st], code.name, code.name))
    print("wrote " + ", ".join(str(w) for w in written))
    snap = code.geometry_snap
    if snap["count"]:
        print(
            f"geometry: {snap['count']} constants within {snap['tolerance']:g} of 0 or +-1 "
            f"taken as exact (largest change {snap['largest']:.2g})"
        )
    for line in snap_lines(base, "base set: ", detail=False):
        print(line)
    print()
    if classical is None:
        print(
            "operation counts of the base-parameter recursion (--classical-counts: beside "
            "those of the classical-parameter one, generated too"
            + ("" if args.classical_counts is False else "; off by default with multi-DOF joints")
            + ")"
        )
    print("\n".join(operation_table(code, classical)))
    return 0


def operation_table(code, classical=None) -> list[str]:
    """The lines of the operation counts of each function of ``code`` (base parameters) beside
    those of ``classical`` (the classical-parameter recursion generated the same way), if
    given."""
    beside = classical is not None
    lines = [
        f"{'function':<18}{'base parameters':>22}"
        + (f"    {'classical parameters':>22}" if beside else ""),
        f"{'':<18}{'mul':>8}{'add':>7}{'trig':>7}"
        + (f"    {'mul':>8}{'add':>7}{'trig':>7}" if beside else ""),
    ]
    for f, c in code.counts.items():
        line = f"{f:<18}{c['mul']:>8}{c['add']:>7}{c['trig']:>7}"
        if beside:
            k = classical.counts[f]
            line += f"    {k['mul']:>8}{k['add']:>7}{k['trig']:>7}"
        lines.append(line)
    return lines
