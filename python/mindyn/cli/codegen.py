"""``mindyn codegen``: generated inverse-dynamics code and controller steps in C99 or Structured
Text, optionally packed as a PLCopen XML project."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from .._core import ModelError
from ..base import base_parameters
from ..codegen import CONTROLLERS, generate, generate_controller, generate_observer, plcopen_project
from ..robot import load
from .args import (
    add_command,
    add_joint_terms,
    add_offset,
    add_robot,
    controller_period,
    drive_side,
    joint_terms,
    joint_values,
    joint_vector,
    output_file,
)
from .method import base_method

#: The --what of the momentum-observer step.
OBSERVER = "momentum-observer"


def register(subparsers) -> None:
    p = add_command(
        subparsers,
        "codegen",
        description="Generate the Newton-Euler recursion customised to the robot, in its base "
        "parameters, as C99 (header + source) or IEC 61131-3 Structured Text, and print its "
        "operation counts beside those of the classical-parameter recursion generated the "
        "same way. Constants of the geometry within 1e-9 of 0 (or of +-1, for rotation "
        "entries alone in their row and column) are taken as exact; how many (beyond "
        "round-off) is printed and stated in the generated header. With --what adaptive-pd, "
        "computed-torque or gravity-compensation: one controller step instead (C: a state "
        "struct, init and step; ST: one FUNCTION_BLOCK) and its operation counts.",
    )
    add_robot(p)
    p.add_argument("--lang", choices=["c", "st"], required=True, help="C99 or Structured Text")
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
    p.add_argument(
        "--params",
        metavar="FILE",
        help="base-parameter values: the JSON that 'mindyn identify --json' writes (the "
        "parameters it pruned for a high relative standard deviation are taken as zero, and "
        "the output says how many; the friction model it records, friction_model: {kind, "
        "velocity}, is the generated code's, else Coulomb), a JSON mapping, or 'NAME value' "
        "lines; default: the robot's own values",
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
    controller_period(c, default=0.004, help="controller period [s]")
    joint_vector(
        c,
        "--observer-gain",
        metavar="K_O",
        help=f"--what {OBSERVER}: gain K_O [1/s], one or one per joint, each below 2 / period "
        "(default 1 / (10 period), a time constant of ten periods)",
    )
    c.add_argument(
        "--torque-limit",
        metavar="effort|NM",
        help="saturate the torque at the robot's effort limits or at +-NM on every joint",
    )
    c.add_argument(
        "--box",
        type=float,
        metavar="F",
        help="keep each estimate within F |p0| of its initial value p0 (default: unbounded)",
    )
    p.add_argument(
        "--plcopen",
        metavar="XML",
        type=output_file,
        help="also write a PLCopen XML (TC6 v2.01) project with the Structured Text function "
        "blocks (the controller, inverse dynamics, gravity, regressor and the momentum "
        "observer) for CODESYS",
    )
    p.add_argument("--name", help="prefix of the generated identifiers (default: robot name)")
    p.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="FILE",
        type=output_file,
        help="C: FILE.c and FILE.h; ST: FILE",
    )
    p.set_defaults(func=cmd_codegen, outputs=_outputs)


def _output_base(args: argparse.Namespace) -> Path:
    """``-o``'s path without the ``.c``/``.h`` a C output may be given with."""
    out = Path(args.output)
    return out.with_suffix("") if args.lang == "c" and out.suffix in (".c", ".h") else out


def _outputs(args: argparse.Namespace) -> list[tuple[str, Path, bool]]:
    """The files codegen writes (C: NAME.c and NAME.h; ST: the file; the PLCopen XML), for the
    command line's one rule on outputs."""
    out = _output_base(args)
    files = (
        [
            ("--output", out.with_suffix(".c"), False),
            ("--output", out.parent / (out.name + ".h"), False),
        ]
        if args.lang == "c"
        else [("--output", out, False)]
    )
    if args.plcopen:
        files.append(("--plcopen", Path(args.plcopen), False))
    return files


def cmd_codegen(args: argparse.Namespace) -> int:
    robot = load(args.robot, tip=args.tip)
    robot, friction_note = _with_friction_model(robot, args)
    robot, drive_note = drive_side(robot, args)
    out = _output_base(args)
    header = out.name + ".h"
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
    if method != "projection" and args.method is None:
        print(f"base parameters by the {method} method: {why}")
    base = base_parameters(
        robot, rotor=args.rotor, friction=args.friction, offset=args.offset, method=method
    )
    for note in (drive_note, friction_note):
        if note:
            print(note)
    params, pruned, threshold = (
        _identified_params(args.params, robot, base, args) if args.params else (None, [], "")
    )
    if args.what.strip() in CONTROLLERS + (OBSERVER,):
        note = _params_note(base.n, args.params, pruned, threshold) if params is not None else None
        given = params if params is not None else args.params
        if args.what.strip() == OBSERVER:
            return _observer(args, robot, base, out, given, note)
        if args.observer_gain is not None:
            raise ModelError(f"--observer-gain applies to --what {OBSERVER} only")
        return _controller(args, robot, base, out, given, note)
    if args.observer_gain is not None:
        raise ModelError(f"--observer-gain applies to --what {OBSERVER} only")
    for opt in ("gains", "torque_limit", "box"):
        if getattr(args, opt) is not None:
            raise ModelError(f"--{opt.replace('_', '-')} applies to controller steps only")
    if any(w.strip() in CONTROLLERS + (OBSERVER,) for w in args.what.split(",")):
        raise ModelError("--what: a controller step is generated alone, not with other functions")
    code = generate(
        robot,
        params=params if params is not None else args.params,
        name=args.name,
        header_name=header,
        trig=args.trig,
        base=base,
        **same,
    )
    # the classical-parameter recursion generated the same way, for its operation counts
    classical = generate(robot, name=code.name, base=False, **same)
    written = code.write(out.with_suffix(".c") if args.lang == "c" else out)
    extras = joint_terms(args)
    print(
        f"{robot.name}: {len(code.names)} base parameters"
        + (f" ({', '.join(extras)})" if extras else "")
        + (", values baked in" if args.numeric else "")
        + f"; {len(classical.names)} classical"
    )
    if params is not None:
        print(_params_note(len(code.names), args.params, pruned, threshold))
    if args.plcopen:
        st = (
            code
            if args.lang == "st"
            else generate(robot, base=base, name=code.name, **dict(same, lang="st"))
        )
        assert st.text is not None  # Structured Text
        Path(args.plcopen).write_bytes(plcopen_project([st.text], code.name))
        written.append(Path(args.plcopen))
    print("wrote " + ", ".join(str(w) for w in written))
    snap = code.geometry_snap
    if snap["count"]:
        print(
            f"geometry: {snap['count']} constants within {snap['tolerance']:g} of 0 or +-1 "
            f"taken as exact (largest change {snap['largest']:.2g})"
        )
    print()
    print("\n".join(operation_table(code, classical)))
    return 0


def operation_table(code, classical) -> list[str]:
    """The lines of the operation counts of each function of ``code`` (base parameters) beside
    those of ``classical`` (the classical-parameter recursion generated the same way)."""
    lines = [
        f"{'function':<18}{'base parameters':>22}    {'classical parameters':>22}",
        f"{'':<18}{'mul':>8}{'add':>7}{'trig':>7}    {'mul':>8}{'add':>7}{'trig':>7}",
    ]
    for f, c in code.counts.items():
        k = classical.counts[f]
        lines.append(
            f"{f:<18}{c['mul']:>8}{c['add']:>7}{c['trig']:>7}    "
            f"{k['mul']:>8}{k['add']:>7}{k['trig']:>7}"
        )
    return lines


def _params_note(n: int, path: str, pruned: list[str], threshold: str) -> str:
    """The line saying which identified values the generated code takes."""
    return (
        f"parameters: {n - len(pruned)} identified values from {path}; "
        f"{len(pruned)} pruned in identification (relative standard deviation above "
        f"{threshold}) taken as zero" + (f": {', '.join(pruned)}" if pruned else "")
    )


def _observer(args, robot, base, out: Path, params, note: str | None = None) -> int:
    """``--what momentum-observer``; ``note`` says where the values came from."""
    from ..control import default_observer_gain

    for opt in ("gains", "torque_limit", "box"):
        if getattr(args, opt) is not None:
            raise ModelError(f"--{opt.replace('_', '-')} applies to controller steps only")
    if args.numeric:
        raise ModelError(f"--numeric does not apply to the {OBSERVER} step")
    gains = (
        joint_values(args.observer_gain, robot.n, "--observer-gain", broadcast=True)
        if args.observer_gain
        else None
    )
    same = dict(base=base, params=params, period=args.period, gains=gains, name=args.name)
    code = generate_observer(robot, args.lang, header_name=out.name + ".h", trig=args.trig, **same)
    written = code.write(out.with_suffix(".c") if args.lang == "c" else out)
    if args.plcopen:
        st = code if args.lang == "st" else generate_observer(robot, "st", **same)
        assert st.text is not None  # Structured Text
        Path(args.plcopen).write_bytes(plcopen_project([st.text], code.name))
        written.append(Path(args.plcopen))
    _say_step(robot, "momentum observer", code, args)
    if note:
        print(note)
    how = "given" if gains else f"default 1 / (10 T) = {default_observer_gain(args.period):.4g}"
    print("gains K_O [1/s] (" + how + "): " + ", ".join(f"{k:.4g}" for k in code.gains))
    print("wrote " + ", ".join(str(w) for w in written))
    for label, c in (
        ("momentum pass:", code.counts["momentum"]),
        ("whole step:", code.counts["step"]),
    ):
        calls = "".join(f", {c[f]} {f}" for f in ("sign", "tanh", "exp") if c[f])
        print(f"{label:<15}{c['mul']} mul, {c['add']} add, {c['trig']} sin/cos{calls}")
    return 0


def _controller(args, robot, base, out: Path, params, note: str | None = None) -> int:
    """``--what adaptive-pd | computed-torque | gravity-compensation``; ``note`` says where the
    initial estimate comes from."""
    from .. import control

    kind = args.what.strip()
    if args.numeric:
        raise ModelError("--numeric does not apply to controller steps (p is their state)")
    if not (math.isfinite(args.period) and args.period > 0):
        raise ModelError(
            f"--controller-period must be a positive number of seconds, got {args.period:g}"
        )
    if args.gains:
        gains = control.load_gains(args.gains, robot, period=args.period, rotor=True)
    else:
        gains = control.default_gains(robot, period=args.period, rotor=True)
    limit = args.torque_limit
    if limit is not None and limit != "effort":
        try:
            limit = float(limit)
        except ValueError:
            raise ModelError(
                f"--torque-limit: expected 'effort' or a number, got '{limit}'"
            ) from None
        if not (math.isfinite(limit) and limit > 0):
            raise ModelError(f"--torque-limit must be positive, got {limit:g}")
    same = dict(base=base, gains=gains, params=params, period=args.period, name=args.name)
    same.update(tau_max=limit)
    if args.box is not None:
        if kind != "adaptive-pd":
            raise ModelError("--box (a box on the estimate) applies to --what adaptive-pd only")
        if not (math.isfinite(args.box) and args.box >= 0):
            raise ModelError(f"--box must be a number >= 0, got {args.box:g}")
        p0 = generate_controller(robot, kind, lang="st", **same).settings["p0"]
        same.update(p_min=p0 - args.box * np.abs(p0), p_max=p0 + args.box * np.abs(p0))
    code = generate_controller(
        robot, kind, lang=args.lang, header_name=out.name + ".h", trig=args.trig, **same
    )
    written = code.write(out.with_suffix(".c") if args.lang == "c" else out)
    if args.plcopen:
        st = code if args.lang == "st" else generate_controller(robot, kind, lang="st", **same)
        dyn = generate(robot, lang="st", base=base, name=st.name, offset=base.offset)
        # the momentum observer of the same model, to run beside the controller
        obs = generate_observer(
            robot, "st", base=base, params=st.settings["p0"], period=args.period, name=st.name
        )
        assert st.text is not None and dyn.text is not None and obs.text is not None  # ST
        texts = [st.text, dyn.text, obs.text]
        Path(args.plcopen).write_bytes(plcopen_project(texts, st.name))
        written.append(Path(args.plcopen))
    _say_step(robot, f"{kind} step", code, args)
    if note:
        print(note)
    if gains.note:
        print(gains.note)
    _warn_unstable(robot, gains, kind, args.period)
    print("wrote " + ", ".join(str(w) for w in written))
    print()
    print(f"{'':<34}{'mul':>8}{'add':>7}{'trig':>7}{'sign':>7}{'div':>7}")
    for f, c in code.counts.items():
        label = "whole step" if f == "step" else f
        print(
            f"{label:<34}{c['mul']:>8}{c['add']:>7}{c['trig']:>7}{c['sign']:>7}{c.get('div', 0):>7}"
        )
    if code.variants:
        print()
        print("forms of Y p and Y^T s (* used: the fewest multiplications plus additions):")
        for form, c in code.variants.items():
            mark = "*" if form == code.form else " "
            print(f" {mark} {form:<52}{c['mul']:>6} mul{c['add']:>6} add")
    return 0


def _warn_unstable(robot, gains, kind: str, period: float) -> None:
    """Warns on stderr when the sampled loop of the gains baked in is unstable at ``period``
    (the robot with its rotor inertia; :func:`mindyn.control.check_gains`)."""
    from .. import control

    check = control.check_gains(
        robot, gains, "pd" if kind == "gravity-compensation" else kind, period=period, rotor=True
    )
    if not check.stable:
        print(
            f"mindyn: warning: the gains baked in are not stable: the {check.text()}",
            file=sys.stderr,
        )


def _with_friction_model(robot, args):
    """``robot`` with the friction model a ``--params`` JSON records (``friction_model: {kind,
    velocity}``), else as it is (Coulomb); and the line saying which, when ``--friction``."""
    from ..identification.data import DataError, read_json

    recorded = None
    if args.params:
        try:
            doc = read_json(args.params)
        except (DataError, FileNotFoundError):
            doc = None
        if isinstance(doc, dict) and doc.get("friction_model") is not None:
            recorded = doc["friction_model"]
            if not (isinstance(recorded, dict) and isinstance(recorded.get("kind"), str)):
                raise ModelError(
                    f"{args.params}: 'friction_model' must be {{kind, velocity}}, got {recorded!r}"
                )
            velocity = recorded.get("velocity")
            if velocity is not None and not (
                isinstance(velocity, list)
                and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in velocity)
            ):
                raise ModelError(
                    f"{args.params}: friction_model velocity must be a list of numbers"
                )
            robot = robot.with_friction_model(recorded["kind"], velocity=velocity or None)
    if not args.friction:
        return robot, ""
    model = robot.friction_model
    scale = {"smooth": "tanh widths", "stribeck": "Stribeck velocities"}.get(model["kind"])
    words = f"friction model: {model['kind']}"
    if scale:
        words += f" ({scale} " + ", ".join(f"{v:g}" for v in model["velocity"]) + ")"
    return robot, words + (f", from {args.params}" if recorded else " (the default)")


def _identified_params(path: str, robot, base, args):
    """The values of a ``mindyn identify --json`` file in the order of ``base.names``, with the
    parameters it pruned (``removed``) as zero, and the pruned names; ``(None, [], "")`` for any
    other parameter file (read by :func:`mindyn.codegen.read_parameter_file`); and the pruning
    threshold as text."""
    from ..identification.data import DataError, read_json

    try:
        doc = read_json(path)
    except (DataError, FileNotFoundError):
        return None, [], ""
    if not (isinstance(doc, dict) and {"names", "values", "removed"} <= doc.keys()):
        return None, [], ""
    if doc.get("robot") not in (None, robot.name):
        raise ModelError(
            f"{path}: parameters identified for robot '{doc['robot']}', not '{robot.name}'"
        )
    flags = {"rotor": args.rotor, "friction": args.friction, "offset": args.offset}
    differ = [k for k, on in flags.items() if k in doc and bool(doc[k]) != on]
    if differ:
        said = " ".join(f"--{k}" for k in flags if doc.get(k))
        raise ModelError(
            f"{path}: identified "
            f"{'with ' + said if said else 'without --rotor, --friction and --offset'}; "
            "give codegen the same --rotor and --friction (and --offset) as identify"
        )
    names, values = doc["names"], doc["values"]
    try:
        pruned = [r["name"] if isinstance(r, dict) else str(r) for r in doc["removed"]]
    except (KeyError, TypeError):
        raise ModelError(f"{path}: 'removed' must list the pruned parameters by name") from None
    if not (isinstance(names, list) and isinstance(values, list) and len(names) == len(values)):
        raise ModelError(f"{path}: 'names' and 'values' must be lists of the same length")
    known = set(base.names)
    unknown = [k for k in names + pruned if k not in known]
    if unknown:
        raise ModelError(
            f"{path}: unknown parameter(s) {', '.join(unknown[:5])}; expected "
            f"{', '.join(base.names)}"
        )
    given = dict(zip(names, values))
    both = [k for k in pruned if k in given]
    if both:
        raise ModelError(f"{path}: {', '.join(both[:5])} both identified and pruned")
    missing = [k for k in base.names if k not in given and k not in pruned]
    if missing:
        raise ModelError(f"{path}: missing parameter(s) {', '.join(missing[:8])}")
    out = np.zeros(len(base.names))
    for i, k in enumerate(base.names):
        if k in given:
            v = given[k]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ModelError(f"{path}: value of '{k}' is not a finite number")
            out[i] = v
    threshold = doc.get("rsd_threshold")
    said = f"{threshold:g} %" if isinstance(threshold, (int, float)) else "the threshold"
    return out, [k for k in base.names if k in pruned], said


def _say_step(robot, what: str, code, args) -> None:
    """The first line of a generated step's report: what, in how many base parameters with which
    joint terms, at which period."""
    extras = joint_terms(args)
    print(
        f"{robot.name}: {what} in {len(code.names)} base parameters"
        + (f" ({', '.join(extras)})" if extras else "")
        + f", period {args.period:g} s"
    )
