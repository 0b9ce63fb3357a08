"""Generated controller steps (:func:`generate_controller`: adaptive PD, computed torque, PD
with gravity compensation) and the momentum-observer step (:func:`generate_observer`), in C99 or
Structured Text."""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from pathlib import Path
from typing import Any, cast

import numpy as np

from .. import _args, _core
from ..base import BaseParameters, base_parameters
from ..robot import Robot, load
from .generation import (
    GeneratedCode,
    _check_lang,
    _check_options,
    _parameter_values,
    check_base_robot,
    identifier,
)

__all__ = [
    "CONTROLLERS",
    "GeneratedController",
    "GeneratedObserver",
    "generate_controller",
    "generate_observer",
]

CONTROLLERS = ("adaptive-pd", "computed-torque", "gravity-compensation")


class GeneratedController(GeneratedCode):
    """A generated controller step (see :func:`generate_controller`).

    Attributes (beyond :class:`GeneratedCode`)
    ------------------------------------------
    kind : str
        ``adaptive-pd``, ``computed-torque`` or ``gravity-compensation``.
    function : str
        The C / ST name of the step: ``NAME_adaptive_pd`` (C: ``NAME_adaptive_pd_t``,
        ``NAME_adaptive_pd_init``, ``NAME_adaptive_pd_step``; ST: the FUNCTION_BLOCK).
    counts : dict
        ``{"slotine_li" | "inverse_dynamics" | "gravity": counts of the dynamics part,
        "step": counts of the whole step (with ``div``)}``.
    variants : dict
        Adaptive PD: the counts of each way of forming ``Y p`` and ``Y^T s`` (``form``: the one
        used, the fewest multiplications plus additions).
    settings : dict
        The settings the step starts with (``kd``, ``lambda``, ``gamma``, ``kp``, ``p_min``,
        ``p_max``, ``tau_max``, ``nu``, ``period``; arrays, read-only: they describe the code
        written).
    """

    def __init__(self, kind, lang, name, out, header_name, settings):
        super().__init__(lang, name, out, False, header_name)
        self.kind = kind
        self.function = f"{name}_{kind.replace('-', '_')}"
        self.variants = {k: dict(v) for k, v in out["variants"].items()}
        self.form = out["form"]
        self.settings: dict[str, Any] = {
            k: _args.readonly(v) if isinstance(v, np.ndarray) else v for k, v in settings.items()
        }

    def __repr__(self) -> str:
        s = self.counts["step"]
        return f"GeneratedController({self.kind!r}, {self.lang!r}, {s['mul']} mul {s['add']} add)"


def _setting(value, size: int, name: str, default: float, *, infinite: bool = False):
    """A setting as ``size`` values: None (``default``), a number or an array of ``size``
    numbers; NaN refused, infinities too unless ``infinite`` (a bound that may be absent)."""
    if value is None:
        return np.full(size, default)
    if isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_)):
        a = np.full(size, float(value))
    else:
        a = _args.array(value, name, (size,), finite=False)
    if np.isnan(a).any() or not (infinite or np.isfinite(a).all()):
        raise _args.fail(
            name,
            f"contains {'NaN' if np.isnan(a).any() else 'infinity'}; expected "
            f"{'numbers' if infinite else 'finite numbers'} (a scalar or {size} values)",
        )
    return a


_GAINS = ("kd", "lambda", "gamma", "nu", "kp")


def _gains(gains) -> dict:
    """The gains mapping: known keys only, each a number or an array (checked where used)."""
    g = dict(_args.mapping(gains, "gains"))
    unknown = [k for k in g if k not in _GAINS]
    if unknown:
        raise _args.fail(
            "gains",
            f"has unknown key(s) {', '.join(map(repr, unknown))}; expected {', '.join(_GAINS)}",
        )
    return g


def generate_controller(
    robot: Robot | str,
    kind: str = "adaptive-pd",
    *,
    lang: str = "c",
    base: BaseParameters | bool | None = None,
    gains: dict | None = None,
    params: str | Path | Sequence[float] | None = None,
    period: float = 0.004,
    p_min=None,
    p_max=None,
    tau_max=None,
    name: str | None = None,
    header_name: str | None = None,
    trig: str | None = None,
) -> GeneratedController:
    """Generates one controller step as C99 or Structured Text.

    ``adaptive-pd`` is :class:`mindyn.control.AdaptivePD` (same sign convention, same
    adaptation step, ``nu`` normalisation when ``gains["nu"] > 0``) with the products ``Y p``
    and ``Y^T s`` of the Slotine-Li regressor generated from its recursion customised to the
    robot, then a torque limit and a box on the estimate; ``computed-torque`` is
    :class:`mindyn.control.ComputedTorque`, ``gravity-compensation`` is PD plus the gravity
    torque ``g(q) p``.

    Parameters
    ----------
    robot : Robot or str
    kind : {"adaptive-pd", "computed-torque", "gravity-compensation"}
    lang : {"c", "st"}
    base : BaseParameters or False, optional
        The parameter set (default: base parameters with rotor inertia and friction; ``False``:
        all classical parameters with rotor inertia and friction); a base set's offset setting
        adds a torque offset per joint. Its robot decides where rotor inertia and friction act
        and the friction model, as in :func:`generate` (rotor inertia through the reference
        acceleration ``t_k . ddq_r``, friction at the motor velocity ``t_k . dq``). It must
        be of ``robot``'s geometry: another robot's is an ArgumentError.
    gains : dict, optional
        ``kd``, ``lambda``, ``gamma``, ``nu``, ``kp`` as :func:`mindyn.control.default_gains`
        gives them (the default: for ``period``, the robot with its rotor inertia). Gains that
        no sampled loop at ``period`` tolerates are refused
        (:func:`mindyn.control.check_sampled_gains`), and so are default gains whose
        ``conflicts`` name the controller (they cannot hold its Coulomb friction at
        ``period``). ``kp`` defaults to ``lambda**2`` for computed torque (with ``kd = 2
        lambda``, as :func:`mindyn.control.make_controller`; with a gains file's ``kp`` and no
        ``kd`` of its own, critically damped ``kd = 2 sqrt(kp)``, as that too) and ``lambda
        kd`` for gravity compensation.
    params : path or array, optional
        The initial estimate ``p0`` (the JSON of ``mindyn identify --json``, read by
        :func:`read_identified_parameters`, or another file :func:`read_parameter_file` reads);
        default the robot's own values.
    period : float
        Controller period [s] (adaptive PD: the adaptation step).
    p_min, p_max : scalar or array (np,), optional
        Box on the estimate (``-inf`` / ``inf``: a side open; an initial estimate outside it is
        refused). Default, adaptive PD on base parameters: :func:`mindyn.control.estimate_box`
        about the description's values, the box :func:`mindyn.control.make_controller` gives
        the library's controller, the initial estimate projected onto it (the note in
        ``settings["box"]`` says on how many parameters); otherwise unbounded.
    tau_max : None, "effort", scalar or array (n,)
        Torque limit (default none; ``"effort"``: the model's effort limits).
    """
    from .. import control

    robot = load(robot) if not isinstance(robot, Robot) else robot
    _args.choice(kind, "kind", CONTROLLERS)
    _check_lang(lang, trig)
    _check_options(name, header_name, params)
    if base is not None and base is not False:
        _args.instance(base, "base", BaseParameters, "a BaseParameters, False or None")
        check_base_robot(cast(BaseParameters, base), robot)
    period = _args.number(period, "period", positive=True)
    conflicts = getattr(gains, "conflicts", {})
    defaulted = getattr(gains, "defaulted", ())  # the keys a gains file left to the defaults
    gains = None if gains is None else _gains(gains)
    if isinstance(tau_max, str) and tau_max != "effort":
        raise _args.fail("tau_max", f"is '{tau_max}'; expected None, 'effort' or {robot.n} values")
    classical = base is False
    if base is None:
        base = base_parameters(robot, rotor=True, friction=True)
    bp = cast(BaseParameters, base)  # unless classical
    if classical:
        names = list(_core.classical_parameter_names(robot._m, rotor=True, friction=True))
    else:
        names = list(bp.names)
    n = robot.n
    check = "pd" if kind == "gravity-compensation" else kind
    if gains is None:
        gains = control.default_gains(robot, period=period, rotor=True)
        conflicts = gains.conflicts
    if conflicts.get(check):  # default gains that cannot hold the friction: as make_controller
        raise control.ControllerSettingError(f"default gains for {check}: {conflicts[check]}")
    g = dict(gains)
    lam = _setting(g.get("lambda"), n, "lambda", 10.0)
    s: dict[str, Any] = {"lambda": lam, "period": float(period), "nu": float(g.get("nu", 0.0))}
    if kind == "computed-torque":
        with np.errstate(over="ignore"):  # an infinite square is refused just below
            s["kp"] = _setting(g.get("kp"), n, "kp", 0.0) if "kp" in g else lam**2
        s["kd"] = (
            control.controllers.computed_torque_kd(
                s["kp"], _setting(g["kd"], n, "kd", 0.0), defaulted
            )
            if "kp" in g
            else 2 * lam
        )
    else:
        s["kd"] = _setting(g.get("kd"), n, "kd", 0.0)
        with np.errstate(over="ignore"):  # an infinite product is refused just below
            s["kp"] = _setting(g.get("kp"), n, "kp", 0.0) if "kp" in g else lam * s["kd"]
    s["gamma"] = _setting(g.get("gamma"), len(names), "gamma", 1.0)
    control.check_sampled_gains(check, s["kp"], s["kd"], lam, period)
    big = control.controllers.MAX_GAIN
    if not (np.all(s["gamma"] >= 0) and np.all(s["gamma"] <= big) and 0 <= s["nu"] <= big):
        raise control.ControllerSettingError(
            f"gains 'gamma' and 'nu' must be numbers in [0, {big:g}]"
        )
    if params is None and classical:
        s["p0"] = None  # the robot's classical values, as the generator reads them
    elif params is None:
        # the robot's torque offsets (0 unless a joint-terms file gave them)
        s["p0"] = bp.values(
            robot.parameters(rotor=bp.rotor, friction=bp.friction, offset=bool(bp.offset))
        )
    else:
        s["p0"] = _parameter_values(
            params,
            names,
            robot,
            rotor=True if classical else bp.rotor,
            friction=True if classical else bp.friction,
            offset=False if classical else bp.offset,
        )
    s["box"] = "given" if p_min is not None or p_max is not None else "none"
    if kind == "adaptive-pd" and p_min is None and p_max is None and not classical:
        # the library's default box (make_controller): about the description's values
        p_min, p_max, s["box"] = control.estimate_box(
            robot, bp, {"kd": s["kd"], "lambda": lam}, period=period
        )
    s["p_min"] = _setting(p_min, len(names), "p_min", -math.inf, infinite=True)
    s["p_max"] = _setting(p_max, len(names), "p_max", math.inf, infinite=True)
    if np.any(s["p_min"] > s["p_max"]):
        i = int(np.argmax(s["p_min"] > s["p_max"]))
        raise _args.fail(
            "p_min", f"exceeds p_max at '{names[i]}' ({s['p_min'][i]:g} > {s['p_max'][i]:g})"
        )
    if s["p0"] is not None and s["box"].startswith("estimate box"):
        # the derived box: the initial estimate projected onto it, as the library's (a given
        # box refuses an estimate outside it)
        out_of = (s["p0"] < s["p_min"]) | (s["p0"] > s["p_max"])
        if out_of.any():
            s["p0"] = np.clip(s["p0"], s["p_min"], s["p_max"])
            s["box"] += f"; the initial estimate moved into it on {int(out_of.sum())}"
    if isinstance(tau_max, str):
        from ..control.simulation import effort_limits

        tau_max = effort_limits(robot, "tau_max='effort'")
    s["tau_max"] = _setting(tau_max, n, "tau_max", math.inf, infinite=True)
    if not np.all(s["tau_max"] > 0):
        raise _args.fail("tau_max", "must be positive")
    name = name if name is not None else identifier(robot.name)
    fn = f"{name}_{kind.replace('-', '_')}"
    header_name = header_name or f"{fn}.h"
    out = _core.generate_controller(
        None if classical else bp._b,  # type: ignore[arg-type]  # None: classical parameters
        False if classical else bp.offset,
        kind,
        name,
        s,
        lang=lang,
        header_name=header_name,
        inline_trig=trig != "libm",
        model=robot._m if classical else None,
    )
    s["p0"] = np.asarray(out["values"], dtype=float)
    return GeneratedController(kind, lang, name, out, header_name, s)


class GeneratedObserver(GeneratedCode):
    """A generated momentum-observer step (see :func:`generate_observer`).

    Attributes (beyond :class:`GeneratedCode`)
    ------------------------------------------
    function : str
        ``NAME_momentum_observer`` (C: ``_t``, ``_init``, ``_reset``, ``_step``; ST: the
        FUNCTION_BLOCK).
    counts : dict
        ``{"momentum": the momentum pass, "step": the whole step}``.
    gains : ndarray (n,)
        ``K_O`` [1/s] (read-only: they describe the code written); ``period`` [s];
        ``held_torque``.
    """

    def __init__(self, lang, name, out, header_name, period, held_torque):
        super().__init__(lang, name, out, False, header_name)
        self.function = f"{name}_momentum_observer"
        self.gains = _args.readonly(np.asarray(out["gains"], dtype=float))
        self.period = float(period)
        self.held_torque = bool(held_torque)

    def __repr__(self) -> str:
        s = self.counts["step"]
        return f"GeneratedObserver({self.lang!r}, {s['mul']} mul {s['add']} add)"


def generate_observer(
    robot: Robot | str,
    *,
    lang: str = "c",
    base: BaseParameters | None = None,
    params: str | Path | Sequence[float] | None = None,
    period: float = 0.004,
    gains=None,
    held_torque: bool = True,
    name: str | None = None,
    header_name: str | None = None,
    trig: str | None = None,
) -> GeneratedObserver:
    """Generates the momentum-observer step of :class:`mindyn.control.MomentumObserver` as C99
    or Structured Text.

    Parameters
    ----------
    robot : Robot or str
    lang : {"c", "st"}
    base : BaseParameters, optional
        The parameter set (default: base parameters with rotor inertia and friction); its
        offset setting adds a torque offset per joint. Its robot decides where rotor inertia
        and friction act and the friction model, as in :func:`generate`: the momentum gets
        ``t_k Ia_k (t_k . dq)``, beta the friction ``t_k f(t_k . dq)``. It must be of
        ``robot``'s geometry: another robot's is an ArgumentError.
    params : path or array, optional
        The parameter values (the JSON of ``mindyn identify --json``, read by
        :func:`read_identified_parameters`, or another file :func:`read_parameter_file` reads);
        default the robot's own values.
    period : float
        The controller period [s].
    gains : scalar or array (n,), optional
        ``K_O`` [1/s], each in ``(0, 2 / period)``; default
        :func:`mindyn.control.default_observer_gain`.
    held_torque : bool
        The step's torque is the command held over the period (True) or a sampled measurement.
    """
    from .. import control

    robot = load(robot) if not isinstance(robot, Robot) else robot
    _check_lang(lang, trig)
    _check_options(name, header_name, params)
    _args.optional(_args.instance, base, "base", BaseParameters)
    if base is not None:
        check_base_robot(base, robot)
    held_torque = _args.flag(held_torque, "held_torque")
    period = control.controllers.check_period(period)
    n = robot.n
    k = control.default_observer_gain(period) if gains is None else gains
    k = _setting(k, n, "gains", 0.0)
    bad = np.flatnonzero(~((k > 0) & (k < 2 / period)))
    if bad.size:
        raise _args.fail(
            "gains",
            f"gives observer gain K_O of joint {bad[0] + 1} as {k[bad[0]]:g} 1/s; expected "
            f"(0, 2 / period) = (0, {2 / period:g})",
        )
    if base is None:
        base = base_parameters(robot, rotor=True, friction=True)
    names = list(base.names)
    p = _parameter_values(
        params, names, robot, rotor=base.rotor, friction=base.friction, offset=base.offset
    )
    if p is None:
        p = base.values(
            robot.parameters(rotor=base.rotor, friction=base.friction, offset=bool(base.offset))
        )
    name = name if name is not None else identifier(robot.name)
    header_name = header_name or f"{name}_momentum_observer.h"
    out = _core.generate_observer(
        base._b,
        base.offset,
        name,
        p,
        k,
        period,
        held_torque=bool(held_torque),
        lang=lang,
        header_name=header_name,
        inline_trig=trig != "libm",
    )
    return GeneratedObserver(lang, name, out, header_name, period, held_torque)
