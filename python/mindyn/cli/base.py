"""CLI: ``mindyn base``, the base inertial parameters of a robot."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from ..base import AUTO_PROJECTION_TERMS, MAX_TOLERANCE, base_parameters
from .args import add_command, deprecated
from .method import base_method, projection_limits_text
from .number_options import number
from .outputs import output_file
from .robot_options import (
    add_joint_terms,
    add_offset,
    add_robot,
    add_snap,
    joint_terms,
    load_robot,
    snap_keyword,
    snap_lines,
    with_drive_side,
)


def cmd_base(args: argparse.Namespace) -> int:
    robot = with_drive_side(load_robot(args), args)
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
        snap=snap_keyword(args),
    )
    tree = {} if robot.is_serial else {"parents": robot.parents}  # 0-based, -1 the base
    if args.format == "json" or args.json:
        doc = {**bp.to_dict(symbolic=args.symbolic), "method_reason": why, **tree}
        text = json.dumps(doc, indent=2)
        if args.json:
            Path(args.json).write_text(text + "\n")
            if args.format != "json":  # standard output carries the document otherwise
                print(f"wrote {args.json}")
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
            f"{m['rank_at_tighter_tolerance']} at {m['tighter_tolerance']:.3g}"
            + (
                f"; the tolerance decides {' '.join(m['decided_by_tolerance'])}"
                if m["decided_by_tolerance"]
                else ""
            )
            + f"; the regrouping is checked: W_b Y reproduces the dynamics to "
            f"{m['consistency']:.2g}"
            + (
                f" (--snap would round {len(bp.snappable)} rotation(s) or axes that are within "
                "1e-3 of right angles)"
                if bp.snappable
                else ""
            )
        )
    if bp.offset:
        lines.append(
            f"  offsets        {bp.names[-robot.n]}..{bp.names[-1]} after the "
            f"equations-of-motion set, one base parameter each ({bp.n} in all)"
        )
    lines += snap_lines(bp)
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
    """Adds ``base`` to the ``mindyn`` subcommands."""
    p = add_command(
        sub,
        "base",
        description="Base inertial parameters by the projection method (exact; the default), "
        "the recursive method (exact, the same base set, cost linear in the number of joints) "
        "or the numerical method (sampled regressor + QR), on chains and trees. Without "
        "--method, a robot whose projection cost estimate is over its budget or over "
        f"{AUTO_PROJECTION_TERMS:.0e} terms (about a second), or beyond the projection method's "
        f"limits (more than {projection_limits_text()}), is computed by the recursive method, "
        "and the output says so; joints of several degrees of freedom (--root-joint, the "
        "multi-DOF joints of a YAML table) are taken by the exact methods as chains of "
        "single-DOF joints through massless links, except a floating root, which the "
        "projection method takes as it is.",
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
        f"method's limits ({projection_limits_text(parameters=False)}) or its cost estimate "
        "refuse the robot",
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
        high=MAX_TOLERANCE,
        low_open=True,
        high_open=True,
        default=1e-9,
        help="relative pivot size below which a column is dependent (the rank decision)",
    )
    deprecated(p, "--tolerance", rank_tolerance)
    add_snap(p)
    p.set_defaults(func=cmd_base)
