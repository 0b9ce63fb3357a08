"""The ``mindyn`` command line. A command's module is imported, and its options declared, only
when that command runs or shows its help: ``mindyn --help`` and the light commands start without
the libraries that only identification, plots or convex fits need."""

from __future__ import annotations

import argparse
import importlib
import json
import math
import os
import sys
from pathlib import Path

import numpy as np

from .._core import ModelError, RobotFileNotFoundError
from .._threads import reuse_freed_memory
from ..base import base_parameters
from ..robot import load
from .args import (
    COMMANDS,
    Parser,
    UsageError,
    add_command,
    add_joint_terms,
    add_offset,
    add_robot,
    deprecated,
    joint_terms,
    number,
    output_file,
    prepare_outputs,
    print_deprecation_notes,
    with_drive_side,
)
from .method import base_method
from .quiet import warnings_after_success


def _fmt(x: float, width: int = 10) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-".rjust(width)
    return f"{x:{width}.4g}"


def _transmission_lines(robot) -> list[str]:
    """The motors of the robot's transmissions, each with its row of ``q_m = T q + offset``."""
    tr = robot.transmission
    if tr is None:
        return []
    form = {"ros1": "URDF, ROS 1 form", "ros2": "URDF, ROS 2 form"}.get(tr.format, tr.format)
    out = [
        "",
        f"transmissions ({form}): motor positions q_m = T q + offset, joint torques "
        "tau = T^T tau_m (not used by the dynamics)",
    ]
    w = max([5] + [len(m) for m in tr.motors]) + 1
    wt = max([4] + [len(t) for t in tr.types]) + 1
    out.append(f"{'#':<3} {'motor':<{w}}{'type':<{wt}}q_m")
    for i, motor in enumerate(tr.motors):
        terms = [
            f"{tr.T[i, k]:+.6g} {robot.joint_names[k]}" for k in range(robot.n) if tr.T[i, k] != 0.0
        ]
        if tr.offset[i] != 0.0:
            terms.append(f"{tr.offset[i]:+.6g}")
        out.append(f"{'m' + str(i + 1):<3} {motor:<{w}}{tr.types[i]:<{wt}}{' '.join(terms)}")
    return out


def cmd_info(args: argparse.Namespace) -> int:
    robot = load(args.robot, tip=args.tip)
    n = robot.n
    out = []
    tree = not robot.is_serial
    shape = f", a tree of {robot.branches} branches" if tree else ""
    out.append(f"robot      {robot.name}  ({n} joints, {robot.convention}{shape})")
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
    w = max([13] + [len(j) for j in robot.joint_names]) + 1  # joint-name column
    # a tree: the link each joint hangs from (the base link, or the link of its parent joint)
    hang = [robot.link_names[p + 1] for p in robot.parents] if tree else []
    wp = max([12] + [len(h) for h in hang]) + 1 if tree else 0
    parent_head = f"{'parent link':<{wp}}" if tree else ""
    if robot.convention in ("dh", "mdh") and len(dh):
        if robot.convention == "dh":
            head = f"{'a [m]':>9} {'alpha[deg]':>10} {'d [m]':>9} {'theta[deg]':>10}"
        else:
            head = f"{'d [m]':>9} {'alpha[deg]':>10} {'r [m]':>9} {'theta[deg]':>10}"
    else:
        head = f"{'axis (joint frame)':>30}"
    out.append(
        f"{'#':>2} {'joint':<{w}}{parent_head}{'type':<10}{head} {'lower':>9} {'upper':>9} "
        f"{'vel':>9} {'effort':>9} {'rated':>7} {'gear':>7}"
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
            f"{k + 1:>2} {robot.joint_names[k]:<{w}}{hang[k] if tree else '':<{wp}}{t:<10}{geo} "
            f"{_fmt(lim['lower'][k] * s, 9)} {_fmt(lim['upper'][k] * s, 9)} "
            f"{_fmt(lim['velocity'][k] * s, 9)} "
            f"{_fmt(lim['effort'][k], 9)} {_fmt(drv['rated_torque'][k], 7)} "
            f"{_fmt(drv['gear_ratio'][k], 7)}"
        )
    out.extend(_transmission_lines(robot))
    out.append("")
    out.append("classical parameters about each link-frame origin (SI)")
    names = ["XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M", "Ia", "Fv", "Fc"]
    wl = max([10] + [len(x) + 1 for x in robot.link_names[1:]])  # link-name column
    out.append(f"{'link':<{wl}}" + "".join(f"{c:>11}" for c in names))
    p = robot.params.reshape(n, 10)
    extra = np.column_stack([robot.rotor_inertia, robot.viscous, robot.coulomb])
    for k in range(n):
        row = list(p[k]) + list(extra[k])
        out.append(f"{robot.link_names[k + 1]:<{wl}}" + "".join(f"{v:11.4g}" for v in row))
    out.append(f"total moving mass {p[:, 9].sum():.4g} kg")
    print("\n".join(out))
    return 0


def cmd_base(args: argparse.Namespace) -> int:
    robot = with_drive_side(load(args.robot, tip=args.tip), args)
    order = [s.strip() for s in args.order.split(",")] if args.order else None
    method, why = base_method(robot, args.rotor, args.method, args.friction)
    bp = base_parameters(
        robot,
        rotor=args.rotor,
        friction=args.friction,
        offset=args.offset,
        method=method,
        order=order,
        tolerance=args.tolerance,
        snap=args.snap,
    )
    tree = {} if robot.is_serial else {"parents": robot.parents}  # 0-based, -1 the base
    if args.format == "json" or args.json:
        doc = {**bp.to_dict(symbolic=args.symbolic), "method_reason": why, **tree}
        text = json.dumps(doc, indent=2)
        if args.json:
            Path(args.json).write_text(text + "\n")
        if args.format == "json":
            print(text)
            return 0
    if args.format == "latex":
        print(bp.latex(symbolic=args.symbolic))
        return 0
    extras = joint_terms(args, robot)
    counts = {k: s["n"] for k, s in bp.sets.items()}
    m = bp.margin
    lines = [
        f"{robot.name}: base parameters by the {bp.method} method"
        + (f" ({', '.join(extras)})" if extras else ""),
        f"  method         {bp.method}: {why}",
        f"  sets           Lagrangian {counts['lagrangian']}, total energy {counts['energy']}, "
        f"equations of motion {counts['eom']}",
        f"  coincide       Lagrangian = energy: {'yes' if bp.lagrangian_equals_energy else 'no'}; "
        f"Lagrangian = equations of motion: {'yes' if bp.lagrangian_equals_eom else 'no'}",
        "  used           the equations-of-motion set, for inverse dynamics, the base regressor "
        "and the identification models",
        f"  rank margin    smallest kept pivot {m['smallest_kept']:.3g}, largest dropped "
        f"{m['largest_dropped']:.3g} (relative tolerance {m['tolerance']:.3g}); weakest kept "
        f"column against its kind {m['weakest_kept_for_its_kind']:.3g}",
    ]
    if tree:
        # joint numbers as in the parameter names (XX3 belongs to joint 3's link)
        parents = ", ".join("-" if p < 0 else str(p + 1) for p in robot.parents)
        lines.insert(
            2,
            f"  tree           {robot.n} joints, {robot.branches} branches; parent joint of "
            f"joints 1..{robot.n} (- the base): {parents}",
        )
    if m["largest_zeroed"] > 0:
        lines.append(
            f"  zero columns   treated as zero below {m['zero_threshold']:.1g} of the largest; "
            f"the largest such column is {m['largest_zeroed']:.3g}"
        )
    if m["near_degenerate"]:
        lines.append(
            f"  WARNING        near-degenerate geometry: {counts['eom']} base parameters at "
            f"tolerance {m['tolerance']:.3g}, decided by pivots within the band (smallest kept "
            f"{m['smallest_kept']:.3g}, largest regrouped {m['largest_dropped']:.3g}); "
            f"{m['rank_at_looser_tolerance']} at {m['looser_tolerance']:.3g}, "
            f"{m['rank_at_tighter_tolerance']} at {m['tighter_tolerance']:.3g}; the regrouping "
            f"is checked: W_b Y reproduces the dynamics to {m['consistency']:.2g}"
            + (
                f" (--snap would round {len(bp.snappable)} rotation(s) or axes that are within "
                "1e-3 of right angles)"
                if bp.snappable
                else ""
            )
        )
    if bp.offset:
        lines.append(
            f"  offsets        Off1..Off{robot.n} after the equations-of-motion set, one base "
            f"parameter each ({bp.n} in all)"
        )
    for s in bp.snapped:
        lines.append(f"  snapped        {s}")
    if bp.no_effect:
        lines.append(f"  no effect      {' '.join(bp.no_effect)}")
    what = {
        "projection": "non-zero basis functions",
        "recursive": "rows spanning the identifiable space",
    }.get(bp.method, "stacked regressor rows")
    lines.append(f"  computed       {bp.basis_rows} {what}, {bp.seconds * 1e3:.2f} ms")
    formulas = bp.formulas
    if args.symbolic:
        sym = bp.symbolic()
        values = ", ".join(f"{k} = {v:g}" for k, v in sym.symbols.items()) or "none"
        lines.append(f"  symbols        {values} (lengths in m)")
        lines.append(
            f"  checked        against the numeric formulas at {sym.checked} geometries, "
            f"largest difference {sym.largest_difference:.2g}"
        )
        formulas = sym.text
    lines.append("")
    width = max(len(n) for n in bp.names) if bp.names else 4
    for i, f in enumerate(formulas, 1):
        name, rhs = f.split(" = ", 1)
        lines.append(f"{i:>3}  {name:<{width}}  = {rhs}")
    print("\n".join(lines))
    return 0


def register(sub) -> None:
    """Adds ``info`` and ``base`` to the ``mindyn`` subcommands."""
    p = add_command(sub, "info")
    add_robot(p)
    p.set_defaults(func=cmd_info)

    p = add_command(
        sub,
        "base",
        description="Base inertial parameters by the projection method (exact; the default), "
        "the recursive method (exact, the same base set, cost linear in the number of joints) "
        "or the numerical method (sampled regressor + QR), on chains and trees. Without "
        "--method, a robot whose projection cost estimate is over its budget (or beyond the "
        "projection method's limits: more than 18 joints on a chain, 44 on a tree or 16 on one "
        "of its root paths, more than 256 parameters) is computed by the recursive method, and "
        "the output says so.",
    )
    add_robot(p)
    add_joint_terms(p)
    add_offset(p)
    p.add_argument(
        "--order",
        help="column priority: every classical parameter once, comma-separated "
        "(default: Khalil's order, link by link with YY, MZ, M last)",
    )
    p.add_argument(
        "--method",
        choices=["projection", "recursive", "numerical"],
        default=None,
        help="default: projection, or recursive (the same base set) where the projection "
        "method's limits (18 joints on a chain; 44 on a tree, 16 on a root path) or its cost "
        "estimate refuse the robot",
    )
    p.add_argument(
        "--format",
        choices=["table", "json", "latex"],
        default="table",
        help="what is printed: the summary and formulas (table, the default), the JSON document, "
        "or the formulas as LaTeX",
    )
    p.add_argument(
        "--json",
        metavar="FILE",
        type=output_file,
        help="also write the JSON document (as --format json prints it) to FILE",
    )
    p.add_argument(
        "--symbolic",
        action="store_true",
        help="formulas in the description's lengths (DH a_j, d_j; MDH d_j, r_j; URDF joint "
        "origins x_j, y_j, z_j) instead of numbers",
    )
    rank_tolerance = number(
        p,
        "--rank-tolerance",
        dest="tolerance",
        low=0,
        high=0.01,
        low_open=True,
        high_open=True,
        default=1e-9,
        help="relative pivot size below which a column is dependent (the rank decision)",
    )
    deprecated(p, "--tolerance", rank_tolerance)
    number(
        p,
        "--snap",
        low=0,
        high=0.1,
        nargs="?",
        const=1e-3,
        default=None,
        metavar="RAD",
        help="round joint rotations within RAD (1e-3 when given alone) of multiples of pi/2",
    )
    p.set_defaults(func=cmd_base)


class _Version(argparse.Action):
    """``--version``: the package version (read when asked, from the installed package's
    metadata, which pyproject.toml writes)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, **kwargs):
        kwargs.setdefault("help", "print mindyn's version and exit")
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        from .._version import __version__

        print(f"mindyn {__version__}")
        parser.exit()


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The ``mindyn`` parser. ``command``: declare that command's options only (with those of
    the commands defined in the same module) and give the others their name and summary alone,
    so that their modules are not imported; an unknown name declares none. Default: every
    command."""
    parser = Parser(
        prog="mindyn",
        description="Minimal dynamic models of manipulators.",
    )
    parser.add_argument("--version", action=_Version)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    wanted = COMMANDS[command][0] if command in COMMANDS else None
    registered = set()
    for name, (module, summary) in COMMANDS.items():
        if command is not None and module != wanted:
            sub.add_parser(name, help=summary)
        elif module not in registered:
            # "": this module (info, base); else a module of this package
            home = (
                importlib.import_module(f"{__name__}.{module}") if module else sys.modules[__name__]
            )
            home.register(sub)
            registered.add(module)
    return parser


def _command(argv: list[str]) -> str:
    """The command named on a command line: its first word that is not an option ("" if none)."""
    return next((a for a in argv if not a.startswith("-")), "")


def _one_line(text: object) -> str:
    return "; ".join(line.strip() for line in str(text).splitlines() if line.strip())


def _error(text: object) -> None:
    print(f"mindyn: error: {_one_line(text)}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    """Runs the command line; returns the exit status. Every failure ends in one line on stderr,
    ``mindyn: error: ...``, and a non-zero status."""
    try:
        argv = list(sys.argv[1:] if argv is None else argv)
        args = build_parser(_command(argv)).parse_args(argv)
    except UsageError as e:
        _error(e)
        return 2
    except SystemExit as e:  # --help
        return e.code if isinstance(e.code, int) else 0
    try:
        reuse_freed_memory()  # long logs: large temporaries reused, not mapped anew each time
        prepare_outputs(args)
        status = warnings_after_success(args.func)(args)  # an error stays one line
        sys.stdout.flush()  # a closed pipe shows here, not at exit
        if status == 0:  # an error stays one line
            print_deprecation_notes(args)
        return status
    except UsageError as e:
        _error(e)
        return 2
    except (RobotFileNotFoundError, FileNotFoundError) as e:
        _error(e)
        return 2
    except (ModelError, ValueError, IndexError) as e:
        _error(e)
        return 2
    except KeyboardInterrupt:
        print("mindyn: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # The reader of stdout went away (e.g. `mindyn base ROBOT | head`): stop quietly, and
        # keep the interpreter from reporting the same error again when it flushes stdout.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 141
    except OSError as e:  # writing an output: permissions, a full disk, a folder in the way
        where = f"'{e.filename}': " if e.filename else ""
        _error(f"{where}{e.strerror or e}")
        return 1
    except MemoryError:
        _error("out of memory: the input asks for more memory than this machine has")
        return 1
    except Exception as e:  # last resort: a defect in mindyn, not in the input
        _error(
            f"unexpected {type(e).__name__}: {e} (a defect in mindyn; please report it with "
            "the command line)"
        )
        return 70


if __name__ == "__main__":
    raise SystemExit(main())
