"""``mindyn codegen --what adaptive-pd | computed-torque | gravity-compensation |
momentum-observer``: one generated controller or observer step, its report and its PLCopen
project."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from .._core import ArgumentError
from ..codegen import generate, generate_controller, generate_observer
from .args import UsageError
from .codegen_output import OBSERVER, _stem, _write, _write_plcopen
from .number_options import joint_values
from .robot_options import joint_terms


def refuse_controller_options(args) -> None:
    """Refuses (UsageError) the options of the controller steps alone, given for another step or
    function (which would not use them)."""
    for opt in ("gains", "torque_limit", "box", "tracking_tolerance"):
        if getattr(args, opt) is not None:
            raise UsageError(f"--{opt.replace('_', '-')}: applies to controller steps only")


def _observer(args, robot, base, out: Path | None, params, note: str | None = None) -> int:
    """``--what momentum-observer``; ``note`` says where the values came from."""
    from ..control import default_observer_gain

    refuse_controller_options(args)
    if args.numeric:
        raise UsageError(f"--numeric: does not apply to the {OBSERVER} step")
    gains = (
        joint_values(args.observer_gain, robot.n, "--observer-gain", broadcast=True)
        if args.observer_gain
        else None
    )
    same = dict(base=base, params=params, period=args.period, gains=gains, name=args.name)
    header = (out.name if out is not None else _stem(args, robot)) + ".h"
    try:
        code = generate_observer(robot, lang=args.lang, header_name=header, trig=args.trig, **same)
    except ArgumentError as e:  # the library's keyword gains is --observer-gain here
        key, sep, rest = str(e).partition(" ")
        if key == "gains":
            raise UsageError(f"--observer-gain{sep}{rest}") from None
        raise
    written = _write(code, out, args.lang)
    if args.plcopen is not None:
        st = code if args.lang == "st" else generate_observer(robot, lang="st", **same)
        written.append(_write_plcopen(args, [st], code.name, code.function))
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


def _controller(args, robot, base, out: Path | None, params, note: str | None = None) -> int:
    """``--what adaptive-pd | computed-torque | gravity-compensation``; ``note`` says where the
    initial estimate comes from."""
    from .. import control

    kind = args.what.strip()
    if args.numeric:
        raise UsageError("--numeric: does not apply to controller steps (p is their state)")
    from .closed_loop import joint_tolerance

    tolerance = joint_tolerance(robot, args.tracking_tolerance)
    if args.gains:
        gains = control.load_gains(
            args.gains, robot, period=args.period, rotor=True, tolerance=tolerance
        )
    else:
        gains = control.default_gains(robot, period=args.period, rotor=True, tolerance=tolerance)
    limit = None if args.torque_limit == "none" else args.torque_limit
    same = dict(base=base, gains=gains, params=params, period=args.period, name=args.name)
    same.update(tau_max=limit)
    if args.box is not None:
        if kind != "adaptive-pd":
            raise UsageError("--box: applies to --what adaptive-pd only (a box on the estimate)")
        if not (math.isfinite(args.box) and args.box >= 0):
            raise UsageError(f"--box: expected a finite number >= 0, got {args.box:g}")
        p0 = generate_controller(robot, kind, lang="st", **same).settings["p0"]
        same.update(p_min=p0 - args.box * np.abs(p0), p_max=p0 + args.box * np.abs(p0))
    header = (out.name if out is not None else _stem(args, robot)) + ".h"
    code = generate_controller(
        robot, kind, lang=args.lang, header_name=header, trig=args.trig, **same
    )
    written = _write(code, out, args.lang)
    if args.plcopen is not None:
        st = code if args.lang == "st" else generate_controller(robot, kind, lang="st", **same)
        dyn = generate(robot, lang="st", base=base, name=st.name, offset=base.offset)
        # the momentum observer of the same model, to run beside the controller
        obs = generate_observer(
            robot, lang="st", base=base, params=st.settings["p0"], period=args.period, name=st.name
        )
        written.append(_write_plcopen(args, [st, dyn, obs], st.name, st.function))
    _say_step(robot, f"{kind} step", code, args)
    if note:
        print(note)
    note = gains.note_for("pd" if kind == "gravity-compensation" else kind)  # PD + gravity
    if note:
        print(note)
    if kind == "adaptive-pd":
        box = code.settings["box"]
        print(box if box.startswith("estimate box") else f"estimate box: {box}")
    _check_model(robot, code, base, args, tolerance)
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


def _check_model(robot, code, base, args, tolerance) -> None:
    """The sampled loop of the step as generated, its own model (``base``, the initial estimate)
    and gains, against the robot with its rotor inertia and friction, which the default gains
    assume (:func:`mindyn.control.controllers.controller_check`): printed when the model is not
    the description's whole one (no rotor inertia or friction in it, or ``--params``), a warning
    on stderr when unstable; computed torque, whose gains act through its model's inertia: a
    warning naming the joints where that inertia leaves the error that Coulomb friction causes
    beyond the whole tracking tolerance
    (:func:`mindyn.control.controllers.model_friction_shortfall`; the default gains hold it
    within half, an identified model's inertia a little smaller still within the whole)."""
    from ..control import controllers

    class Step:  # what controller_check reads of a compiled generated step
        def __init__(self):
            self.name, self.code, self.base = code.kind, code, base

        def __call__(self, *args):  # pragma: no cover - never run, the check reads settings
            raise NotImplementedError

    kind, s = code.kind, code.settings
    plant = robot.parameters(rotor=True, friction=True)
    check = controllers.controller_check(robot, Step(), plant, args.period)
    left = [t for t, on in (("rotor inertia", base.rotor), ("friction", base.friction)) if not on]
    names = robot.parameter_names(rotor=True, friction=False)
    values = robot.parameters(rotor=True, friction=False)
    rotors = any(v != 0 for k, v in zip(names, values) if k.startswith("Ia"))
    model = "its model without " + " and ".join(left) if left else "its model from --params"
    if check is not None and (left or args.params):
        print(
            f"generated step ({model}) against the robot with rotor inertia and friction: "
            + check.text()
        )
    if check is not None and not check.stable:
        print(
            f"mindyn: warning: the gains baked in are not stable: the {check.text()}",
            file=sys.stderr,
        )
    if kind == "computed-torque":
        short = controllers.model_friction_shortfall(  # beyond the whole tolerance
            robot, base, s["p0"], s["kp"], tolerance=tolerance, share=1.0
        )
        if short:
            hint = (
                "; --rotor puts the robot's rotor inertia into the model"
                if not base.rotor and rotors
                else ""
            )
            print(f"mindyn: warning: the generated {short}{hint}", file=sys.stderr)


def _say_step(robot, what: str, code, args) -> None:
    """The first line of a generated step's report: what, in how many base parameters with which
    joint terms, at which period."""
    extras = joint_terms(args)
    print(
        f"{robot.name}: {what} in {len(code.names)} base parameters"
        + (f" ({', '.join(extras)})" if extras else "")
        + f", period {args.period:g} s"
    )
