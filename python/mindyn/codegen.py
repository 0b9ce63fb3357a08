"""Generated inverse-dynamics code (C99, IEC 61131-3 Structured Text) and the runtime
base-parameter dynamics.

The generator writes the Newton-Euler recursion of a robot into an expression graph, customised
to the model: exact zeros and ones of the geometry, the base parameters at their pivot positions
of the classical vector (every other entry exactly zero), constant folding, removal of
multiplications by 0 and +-1, common-subexpression elimination and dead-code removal. Three
functions can be generated: ``inverse_dynamics`` (tau from q, dq, ddq and p), ``gravity``
(tau from q and p) and ``regressor`` (W_b with tau = W_b p).

Controller steps (:func:`generate_controller`): the Slotine-Li adaptive PD of
:class:`mindyn.control.AdaptivePD` with ``Y p`` and ``Y^T s`` generated from the Slotine-Li
recursion customised the same way (the regressor's columns, or the adjoint pass of ``s^T Y p``,
whichever needs fewer operations), computed torque and PD with gravity compensation, as a C99 state
struct with init and step functions or one Structured Text FUNCTION_BLOCK holding the estimate;
:class:`CompiledController` runs the C step in :func:`mindyn.control.simulate`, and
:func:`plcopen_project` packs Structured Text function blocks into a PLCopen XML project.

The momentum observer (:func:`generate_observer`): the step of
:class:`mindyn.control.MomentumObserver` with ``p = A(q) dq`` and ``beta = -dL/dq + friction +
offset`` from one momentum pass customised to the robot, to run beside a controller step;
:class:`CompiledObserver` calls the C step.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from . import _args, _core
from .base import BaseParameters, base_parameters
from .robot import Robot, load

__all__ = [
    "CONTROLLERS",
    "FUNCTIONS",
    "BaseDynamics",
    "CompiledController",
    "CompiledObserver",
    "GeneratedCode",
    "GeneratedController",
    "GeneratedObserver",
    "generate",
    "generate_controller",
    "generate_observer",
    "plcopen_project",
    "read_parameter_file",
]

FUNCTIONS = ("inverse_dynamics", "gravity", "regressor")
_ALIASES = {"id": "inverse_dynamics"}


class GeneratedCode:
    """Generated code and its operation counts.

    Attributes
    ----------
    lang : {"c", "st"}
    name : str
        Prefix of the generated functions (``NAME_inverse_dynamics`` ...).
    header, source : str
        C only: the header and source texts.
    text : str
        Structured Text only: the FUNCTION_BLOCKs.
    counts : dict
        Per function: ``{"mul", "add", "neg", "trig", "sign"}`` operation counts.
    names : list of str
        The parameters ``p`` in order.
    values : ndarray, shape (np,)
        Their values (the robot's own, or those given; baked in when ``numeric``).
    geometry_snap : dict
        Constants of the geometry (joint transforms and axes, gravity) within ``tolerance``
        (1e-9) of 0 are taken as 0, and rotation or axis entries then alone in their row and
        column as +-1; ``count``: how many changed by more than round-off (e.g. cos
        1.57079632679 = 4.9e-12 from a URDF's truncated pi/2), ``largest``: the largest change.
        Also stated in the generated header comment.
    """

    def __init__(self, lang: str, name: str, out: dict, numeric: bool, header_name: str):
        self.lang = lang
        self.header_name = header_name
        self.name = name
        self.numeric = numeric
        self.header: str | None = out.get("header")  # C: the header and the source
        self.source: str | None = out.get("source")
        self.text: str | None = out.get("text")  # Structured Text
        self.counts = {k: dict(v) for k, v in out["counts"].items()}
        self.names = list(out["names"])
        self.values = np.asarray(out["values"], dtype=float)
        self.geometry_snap = dict(out["geometry_snap"])

    def write(self, path: str | Path) -> list[Path]:
        """Writes the code: C to ``path`` (``.c`` added when missing) and the header beside it
        under ``header_name`` (the name the source includes); ST to ``path``. Returns the paths
        written."""
        path = Path(path)
        if self.lang == "st":
            assert self.text is not None
            path.write_text(self.text)
            return [path]
        assert self.header is not None and self.source is not None
        src = path if path.suffix == ".c" else path.with_suffix(".c")
        hdr = src.parent / self.header_name
        hdr.write_text(self.header)
        src.write_text(self.source)
        return [hdr, src]

    def __repr__(self) -> str:
        c = ", ".join(f"{k}: {v['mul']} mul {v['add']} add" for k, v in self.counts.items())
        return f"GeneratedCode({self.lang!r}, {self.name!r}, {c})"


def _functions(what) -> list[str]:
    if isinstance(what, str):
        what = [w.strip() for w in what.split(",") if w.strip()]
    out = []
    for w in what:
        w = _ALIASES.get(w, w)
        if w not in FUNCTIONS:
            raise ValueError(f"unknown function '{w}' (choose from id, gravity, regressor)")
        if w not in out:
            out.append(w)
    if not out:
        raise ValueError("no function to generate")
    return out


def _check_lang(lang: str, trig: str | None) -> None:
    if lang not in ("c", "st"):
        raise ValueError(f"lang must be 'c' or 'st', got '{lang}'")
    if trig is not None and lang != "c":
        raise ValueError("trig applies to C only; Structured Text uses SIN and COS")
    if trig not in (None, "inline", "libm"):
        raise ValueError(f"trig must be 'inline' or 'libm', got '{trig}'")


def _identifier(name: str) -> str:
    s = re.sub(r"[^A-Za-z0-9]+", "_", name).strip("_")
    s = re.sub(r"_+", "_", s)
    if not s or not s[0].isalpha():
        s = "robot_" + s
    return s[:40].rstrip("_")


def generate(
    robot: Robot | str,
    lang: str = "c",
    what: Sequence[str] | str = FUNCTIONS,
    rotor: bool = False,
    friction: bool = False,
    params: str | Path | Sequence[float] | None = None,
    numeric: bool = False,
    name: str | None = None,
    base: bool | BaseParameters = True,
    header_name: str | None = None,
    minimise: str = "operations",
    trig: str | None = None,
    offset: bool = False,
) -> GeneratedCode:
    """Generates inverse-dynamics code for ``robot``.

    Parameters
    ----------
    robot : Robot or str
        Anything :func:`mindyn.load` accepts.
    lang : {"c", "st"}
        C99 (header and source) or IEC 61131-3 Structured Text.
    what : sequence of str or str
        Functions to generate: ``inverse_dynamics`` (alias ``id``), ``gravity``, ``regressor``;
        a comma-separated string is accepted.
    rotor, friction : bool
        Include rotor inertia ``Ia`` and viscous / Coulomb friction ``Fv, Fc`` per joint, or per
        motor when ``robot.drive_side`` is ``"motor"`` (a description with transmissions, unless
        :meth:`Robot.with_drive_side` put them on the joints): motor k's velocity ``t_k . dq``
        and acceleration ``t_k . ddq`` (``t_k`` row k of ``T``) formed once each, its torque
        taken back to the joints by ``t_k^T``. The friction terms follow
        ``robot.friction_model`` (Coulomb, direction-dependent, smooth with ``tanh``, Stribeck
        with ``exp``; its velocities baked in; a third column ``Fa``/``Fs`` per slot where the
        model has one); the header says which and where.
    params : path or array, optional
        Parameter values, shape (np,): an array, or a file read by
        :func:`read_parameter_file`. Default: the robot's own values (``p_b = Y pi``).
    numeric : bool
        Bake the values into inverse_dynamics and gravity (they then take no ``p``).
    name : str, optional
        Prefix of the generated identifiers (default: from the robot's name).
    base : bool or BaseParameters
        Base parameters (default: by the method :func:`mindyn.base_parameters` chooses), a
        given :class:`BaseParameters`, or ``False`` for all classical parameters (the classical
        recursion, for comparison). The header lists the base parameters with their formulas as
        ``BaseParameters.formulas`` writes them.
    header_name : str, optional
        C: the header file name the source includes (default ``NAME.h``).
    minimise : {"operations", "additions"}
        What the choice among exact formulations of the recursion minimises (where the
        along-axis translations go, and whether a link's wrench is formed in its own frame or
        in the joint frame before the joint motion): multiplications plus additions, ties to
        fewer additions (default), or additions first, ties to fewer multiplications.
    trig : {"inline", "libm"}, optional
        C only: how sines and cosines are evaluated. ``"inline"`` (default): one call per
        angle of a routine in the generated source gives both, without branches or library
        calls for ``|x| <= 1e6`` and within 2.2e-16 of the C library (which it calls beyond, and
        for NaN and infinities); ``"libm"``: ``sin`` and ``cos`` of ``math.h``. Structured Text
        always uses ``SIN`` and ``COS``.
    offset : bool
        A constant torque offset per joint, ``Off1 .. OffN``, after the other parameters: added
        to the inverse dynamics, a unit column of the regressor, not part of the gravity torque
        (taken from ``base`` when a :class:`BaseParameters` is given).
    """
    robot = load(robot) if not isinstance(robot, Robot) else robot
    rotor, friction = _args.flag(rotor, "rotor"), _args.flag(friction, "friction")
    numeric = _args.flag(numeric, "numeric")
    offset = _args.flag(offset, "offset")
    if not isinstance(base, BaseParameters):
        base = _args.flag(base, "base")
    _check_lang(lang, trig)
    fs = _functions(what)
    name = name if name is not None else _identifier(robot.name)
    if isinstance(base, BaseParameters):
        if base.rotor != rotor or base.friction != friction:
            rotor, friction = base.rotor, base.friction
        offset = base.offset
        bp_core = base._b
        names = base.names
        formulas = base.formulas[: bp_core.n]
    elif base:
        # the projection method, or the recursive one where the projection method refuses
        bp = base_parameters(robot, rotor=rotor, friction=friction)
        bp_core = bp._b
        names = bp.names + [f"Off{k + 1}" for k in range(robot.n) if offset]
        formulas = bp.formulas
    else:
        bp_core = formulas = None
        names = list(_core.classical_parameter_names(robot._m, rotor=rotor, friction=friction))
        names += [f"Off{k + 1}" for k in range(robot.n) if offset]
    values = None
    if params is not None:
        if isinstance(params, (str, Path)):
            values = read_parameter_file(params, names)
        else:
            values = _args.array(params, "params", (len(names),))
    out = _core.generate_code(
        robot._m,
        bp_core,  # type: ignore[arg-type]  # None: the classical parameters (the stub omits it)
        rotor=rotor,
        friction=friction,
        functions=fs,
        name=name,
        numeric=numeric,
        values=values,
        lang=lang,
        header_name=header_name or f"{name}.h",
        minimise=minimise,
        inline_trig=trig != "libm",
        offset=offset,
        formulas=formulas,  # as mindyn base prints them (BaseParameters.formulas)
    )
    return GeneratedCode(lang, name, out, numeric, header_name or f"{name}.h")


_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


def read_parameter_file(path: str | Path, names: Sequence[str]) -> np.ndarray:
    """Parameter values from a file, in the order of ``names``.

    Accepted: JSON, either a mapping ``{"NAME": value}`` or ``{"names": [...], "values": [...]}``
    or a plain list in order; or text with one ``NAME value`` (or ``NAME = value``) per line,
    ``#`` comments allowed. Every name must be given exactly once; unknown names are an error.
    """
    path = Path(path)
    if not path.is_file():
        raise _core.RobotFileNotFoundError(f"parameter file '{path}' does not exist")
    text = path.read_text()
    names = list(names)
    mapping: dict[str, float] = {}
    if path.suffix.lower() == ".json" or text.lstrip().startswith(("{", "[")):
        try:
            data = json.loads(text)
        except json.JSONDecodeError as e:
            raise ValueError(f"{path}:{e.lineno}: not valid JSON: {e.msg}") from None
        if isinstance(data, list):
            if len(data) != len(names):
                raise ValueError(f"{path}: {len(data)} values; expected {len(names)}")
            mapping = dict(zip(names, data))
        elif isinstance(data, dict) and "names" in data and "values" in data:
            if len(data["names"]) != len(data["values"]):
                raise ValueError(f"{path}: 'names' and 'values' differ in length")
            mapping = dict(zip(data["names"], data["values"]))
        elif isinstance(data, dict):
            mapping = data
        else:
            raise ValueError(f"{path}: expected a JSON mapping or list")
    else:
        for lineno, line in enumerate(text.splitlines(), 1):
            line = line.split("#", 1)[0].strip()
            if not line:
                continue
            m = re.fullmatch(r"([A-Za-z_][A-Za-z0-9_]*)\s*(?:=|:|\s)\s*(" + _NUMBER + r")", line)
            if not m:
                raise ValueError(f"{path}:{lineno}: expected 'NAME value', got '{line}'")
            if m.group(1) in mapping:
                raise ValueError(f"{path}:{lineno}: '{m.group(1)}' given twice")
            mapping[m.group(1)] = float(m.group(2))
    unknown = [k for k in mapping if k not in names]
    if unknown:
        raise ValueError(
            f"{path}: unknown parameter(s) {', '.join(unknown[:5])}; expected {', '.join(names)}"
        )
    missing = [k for k in names if k not in mapping]
    if missing:
        raise ValueError(f"{path}: missing parameter(s) {', '.join(missing[:8])}")
    values = np.empty(len(names))
    for i, k in enumerate(names):
        try:
            values[i] = float(mapping[k])
        except (TypeError, ValueError):
            raise ValueError(f"{path}: value of '{k}' is not a number") from None
        if not math.isfinite(values[i]):
            raise ValueError(f"{path}: value of '{k}' is not finite")
    return values


#: numpy's array type, for annotations in classes where ``np`` names an attribute
_Array = np.ndarray


class BaseDynamics:
    """Inverse dynamics, gravity torque and base regressor in the base parameters, by the
    customised Newton-Euler recursion flattened at construction (C++, allocation-free per call).

    Parameters
    ----------
    base : BaseParameters
        From :func:`mindyn.base_parameters` (its robot, rotor, friction and offset settings are
        used; offsets are added to the inverse dynamics, not to the gravity torque).

    Attributes
    ----------
    n, np : int
        Joints and base parameters.
    names : list of str
    counts : dict
        Operation counts per function.
    geometry_snap : dict
        Geometric constants taken as exactly 0 or +-1, as in :class:`GeneratedCode`.
    """

    def __init__(self, base: BaseParameters):
        self.base = base
        self._d = _core.BaseDynamics(base._b, offset=base.offset)

    n = property(lambda self: self._d.n)
    np = property(lambda self: self._d.np)
    names = property(lambda self: self._d.names)
    counts = property(lambda self: self._d.counts)
    geometry_snap = property(lambda self: self._d.geometry_snap)

    def inverse_dynamics(self, q, dq, ddq, p=None) -> _Array:
        """tau, shape (n,) or (m, n) for batches of q, dq, ddq; ``p`` shape (np,), default the
        robot's own base-parameter values."""
        q, dq, ddq = _args.batch(self.n, q=q, dq=dq, ddq=ddq)
        return self._d.inverse_dynamics(q, dq, ddq, self._values(p))

    def gravity(self, q, p=None) -> _Array:
        """Gravity torque, shape (n,) or (m, n)."""
        return self._d.gravity(_args.samples(q, "q", self.n), self._values(p))

    def regressor(self, q, dq, ddq) -> _Array:
        """W_b, shape (n, np) or (m, n, np): ``tau = W_b @ p``."""
        q, dq, ddq = _args.batch(self.n, q=q, dq=dq, ddq=ddq)
        return self._d.regressor(q, dq, ddq)

    def _values(self, p):
        if p is None:
            rob = self.base.robot
            return self.base.values(rob.parameters(self.base.rotor, self.base.friction))
        return _args.array(p, "p", (self.np,))

    def __repr__(self) -> str:
        return f"BaseDynamics(n={self.n}, np={self.np})"


# ---------------------------------------------------------------------------------------------
# Generated controllers
# ---------------------------------------------------------------------------------------------
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
        ``p_max``, ``tau_max``, ``nu``, ``period``; arrays).
    """

    def __init__(self, kind, lang, name, out, header_name, settings):
        super().__init__(lang, name, out, False, header_name)
        self.kind = kind
        self.function = f"{name}_{kind.replace('-', '_')}"
        self.variants = {k: dict(v) for k, v in out["variants"].items()}
        self.form = out["form"]
        self.settings = settings

    def __repr__(self) -> str:
        s = self.counts["step"]
        return f"GeneratedController({self.kind!r}, {self.lang!r}, {s['mul']} mul {s['add']} add)"


def _setting(value, size: int, name: str, default: float) -> np.ndarray:
    if value is None:
        return np.full(size, default)
    a = np.asarray(value, dtype=float)
    if a.ndim == 0:
        a = np.full(size, float(a))
    if a.shape != (size,):
        raise ValueError(f"setting '{name}' must be a scalar or {size} values, got shape {a.shape}")
    return a


def generate_controller(
    robot: Robot | str,
    kind: str = "adaptive-pd",
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
        acceleration ``t_k . ddq_r``, friction at the motor velocity ``t_k . dq``).
    gains : dict, optional
        ``kd``, ``lambda``, ``gamma``, ``nu``, ``kp`` as :func:`mindyn.control.default_gains`
        gives them (the default: for ``period``, the robot with its rotor inertia). Gains that
        no sampled loop at ``period`` tolerates are refused
        (:func:`mindyn.control.check_sampled_gains`). ``kp`` defaults to ``lambda**2`` for
        computed torque (with ``kd = 2 lambda``, as :func:`mindyn.control.make_controller`) and
        ``lambda kd`` for gravity compensation.
    params : path or array, optional
        The initial estimate ``p0`` (a file as :func:`read_parameter_file` reads it, e.g. the JSON
        of ``mindyn identify --json``); default the robot's own values.
    period : float
        Controller period [s] (adaptive PD: the adaptation step).
    p_min, p_max : scalar or array (np,), optional
        Box on the estimate (default unbounded).
    tau_max : None, "effort", scalar or array (n,)
        Torque limit (default none; ``"effort"``: the model's effort limits).
    """
    from . import control

    robot = load(robot) if not isinstance(robot, Robot) else robot
    if kind not in CONTROLLERS:
        raise ValueError(f"unknown controller '{kind}' (choose from {', '.join(CONTROLLERS)})")
    _check_lang(lang, trig)
    classical = base is False
    if base is None:
        base = base_parameters(robot, rotor=True, friction=True)
    bp = None if classical else base
    assert bp is None or isinstance(bp, BaseParameters)
    if bp is None:
        names = list(_core.classical_parameter_names(robot._m, rotor=True, friction=True))
    else:
        names = list(bp.names)
    n = robot.n
    g = dict(control.default_gains(robot, period=period, rotor=True) if gains is None else gains)
    lam = _setting(g.get("lambda"), n, "lambda", 10.0)
    s: dict[str, Any] = {"lambda": lam, "period": float(period), "nu": float(g.get("nu", 0.0))}
    if kind == "computed-torque":
        with np.errstate(over="ignore"):  # an infinite square is refused just below
            s["kp"] = _setting(g.get("kp"), n, "kp", 0.0) if "kp" in g else lam**2
        s["kd"] = _setting(g["kd"], n, "kd", 0.0) if "kp" in g else 2 * lam
    else:
        s["kd"] = _setting(g.get("kd"), n, "kd", 0.0)
        with np.errstate(over="ignore"):  # an infinite product is refused just below
            s["kp"] = _setting(g.get("kp"), n, "kp", 0.0) if "kp" in g else lam * s["kd"]
    s["gamma"] = _setting(g.get("gamma"), len(names), "gamma", 1.0)
    check = "pd" if kind == "gravity-compensation" else kind
    control.check_sampled_gains(check, s["kp"], s["kd"], lam, period)
    big = control.controllers.MAX_GAIN
    if not (np.all(s["gamma"] >= 0) and np.all(s["gamma"] <= big) and 0 <= s["nu"] <= big):
        raise control.ControllerSettingError(
            f"gains 'gamma' and 'nu' must be numbers in [0, {big:g}]"
        )
    if params is None and bp is None:
        s["p0"] = None  # the robot's classical values, as the generator reads them
    elif params is None:
        assert bp is not None
        s["p0"] = bp.values(robot.parameters(bp.rotor, bp.friction))
        if bp.offset:
            s["p0"] = np.concatenate([s["p0"], np.zeros(n)])[: len(names)]
    elif isinstance(params, (str, Path)):
        s["p0"] = read_parameter_file(params, names)
    else:
        s["p0"] = _args.array(params, "params", (len(names),))
    s["p_min"] = _setting(p_min, len(names), "p_min", -math.inf)
    s["p_max"] = _setting(p_max, len(names), "p_max", math.inf)
    if isinstance(tau_max, str):
        if tau_max != "effort":
            raise ValueError(f"tau_max must be None, 'effort' or {n} values, got '{tau_max}'")
        tau_max = robot.limits["effort"]
        if not np.all(np.isfinite(tau_max)):
            raise ValueError(f"robot '{robot.name}' does not give effort limits for all joints")
    s["tau_max"] = _setting(tau_max, n, "tau_max", math.inf)
    name = name if name is not None else _identifier(robot.name)
    fn = f"{name}_{kind.replace('-', '_')}"
    header_name = header_name or f"{fn}.h"
    out = _core.generate_controller(
        None if bp is None else bp._b,  # type: ignore[arg-type]  # None: the classical parameters
        False if bp is None else bp.offset,
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


def _compile_shared(code: GeneratedController | GeneratedObserver, what: str):
    """Compiles generated C into a shared library in a temporary folder with the system C
    compiler (``$CC``, else ``cc`` or ``gcc``); returns the folder (kept alive by its holder)
    and the loaded library."""
    import ctypes
    import os
    import shutil
    import subprocess
    import tempfile

    cc = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if not cc:
        raise _core.ModelError("no C compiler found (set CC, or install cc or gcc)")
    folder = tempfile.TemporaryDirectory(prefix=f"mindyn-{what}-")
    path = Path(folder.name)
    src, so = code.write(path / f"{code.function}.c")[1], path / f"{code.function}.so"
    cmd = [cc, "-std=c99", "-O2", "-shared", "-fPIC", "-o", str(so), str(src), "-lm"]
    res = subprocess.run(cmd, capture_output=True, text=True)
    if res.returncode != 0:
        first = (res.stderr.strip().splitlines() or ["no message"])[0]
        raise _core.ModelError(f"compiling the generated {what} with {cc} failed: {first}")
    return folder, ctypes.CDLL(str(so))


class CompiledController:
    """A generated C controller step compiled with the system C compiler (``$CC``, else ``cc``
    or ``gcc``) into a temporary folder and called through ctypes: a controller of
    :func:`mindyn.control.simulate` (:class:`mindyn.control.Controller`), ``tau =
    controller(t, q, dq, q_d, dq_d, ddq_d)``, with ``reset()`` and, for the adaptive step,
    ``period`` (the period it was generated for; a simulation at another period is refused).

    Parameters
    ----------
    code : GeneratedController
        C code from :func:`generate_controller`.
    base : BaseParameters, optional
        Reported to :func:`~mindyn.control.simulate` (the true base parameters in its result).

    Attributes
    ----------
    p_hat : ndarray
        The current estimate (a copy).
    """

    def __init__(self, code: GeneratedController, base: BaseParameters | None = None):
        import ctypes

        if not isinstance(code, GeneratedController) or code.lang != "c":
            raise ValueError("CompiledController needs the C code of generate_controller")
        self.code = code
        self.base = base
        self.name = code.kind
        self._dir, self._lib = _compile_shared(code, "controller")
        n, np_ = len(code.settings["kd"]), len(code.names)
        dbl = ctypes.c_double
        fields: list[tuple[str, Any]] = [("p", dbl * np_), ("p0", dbl * np_), ("kd", dbl * n)]
        if code.kind == "adaptive-pd":
            fields += [("lambda_", dbl * n), ("gamma", dbl * np_)]
            fields += [("p_min", dbl * np_), ("p_max", dbl * np_)]
        else:
            fields += [("kp", dbl * n)]
        fields += [("tau_max", dbl * n)]
        if code.kind == "adaptive-pd" and code.settings["nu"] > 0:
            fields += [("nu", dbl)]
        if code.kind == "adaptive-pd":
            fields += [("period", dbl)]
        self._State = type("State", (ctypes.Structure,), {"_fields_": fields})
        self._state = self._State()
        self._init = getattr(self._lib, f"{code.function}_init")
        self._step = getattr(self._lib, f"{code.function}_step")
        ptr = ctypes.POINTER(dbl)
        self._step.argtypes = [ctypes.POINTER(self._State)] + [ptr] * 6
        self._step.restype = None
        self._ptr = ptr
        self._n = n
        self.reset()

    def reset(self) -> None:
        import ctypes

        self._init(ctypes.byref(self._state))

    @property
    def p_hat(self) -> np.ndarray:
        return np.array(self._state.p[:], dtype=float)

    def __getattr__(self, name):
        # ``period`` exists for the adaptive step only (the others do not depend on it)
        if name == "period" and self.__dict__.get("code") is not None:
            if self.code.kind == "adaptive-pd":
                return float(self.code.settings["period"])
        raise AttributeError(name)

    def __call__(self, t, q, dq, q_d, dq_d, ddq_d):
        import ctypes

        args = [np.ascontiguousarray(a, dtype=float) for a in (q, dq, q_d, dq_d, ddq_d)]
        for a in args:
            if a.shape != (self._n,):
                raise ValueError(f"controller inputs must have shape ({self._n},), got {a.shape}")
        tau = np.zeros(self._n)
        ptrs = [a.ctypes.data_as(self._ptr) for a in args + [tau]]
        self._step(ctypes.byref(self._state), *ptrs)
        return tau


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
        ``K_O`` [1/s]; ``period`` [s]; ``held_torque``.
    """

    def __init__(self, lang, name, out, header_name, period, held_torque):
        super().__init__(lang, name, out, False, header_name)
        self.function = f"{name}_momentum_observer"
        self.gains = np.asarray(out["gains"], dtype=float)
        self.period = float(period)
        self.held_torque = bool(held_torque)

    def __repr__(self) -> str:
        s = self.counts["step"]
        return f"GeneratedObserver({self.lang!r}, {s['mul']} mul {s['add']} add)"


def generate_observer(
    robot: Robot | str,
    lang: str = "c",
    *,
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
        ``t_k Ia_k (t_k . dq)``, beta the friction ``t_k f(t_k . dq)``.
    params : path or array, optional
        The parameter values (a file as :func:`read_parameter_file` reads it, e.g. the JSON of
        ``mindyn identify --json``); default the robot's own values.
    period : float
        The controller period [s].
    gains : scalar or array (n,), optional
        ``K_O`` [1/s], each in ``(0, 2 / period)``; default
        :func:`mindyn.control.default_observer_gain`.
    held_torque : bool
        The step's torque is the command held over the period (True) or a sampled measurement.
    """
    from . import control

    robot = load(robot) if not isinstance(robot, Robot) else robot
    _check_lang(lang, trig)
    if base is None:
        base = base_parameters(robot, rotor=True, friction=True)
    n, names = robot.n, list(base.names)
    period = control.controllers.check_period(period)
    k = control.default_observer_gain(period) if gains is None else gains
    k = _setting(k, n, "gains", 0.0)
    if params is None:
        p = base.values(robot.parameters(base.rotor, base.friction))
        if base.offset:
            p = np.concatenate([p, np.zeros(n)])[: len(names)]
    elif isinstance(params, (str, Path)):
        p = read_parameter_file(params, names)
    else:
        p = _args.array(params, "params", (len(names),))
    name = name if name is not None else _identifier(robot.name)
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


class CompiledObserver:
    """A generated C observer step compiled with the system C compiler and called through
    ctypes: ``r = observer(q, dq, tau)`` per sample (the first call starts it, r = 0), with
    ``reset()``."""

    def __init__(self, code: GeneratedObserver):
        import ctypes

        if not isinstance(code, GeneratedObserver) or code.lang != "c":
            raise ValueError("CompiledObserver needs the C code of generate_observer")
        self.code = code
        self._dir, self._lib = _compile_shared(code, "observer")
        n, np_ = len(code.gains), len(code.names)
        dbl = ctypes.c_double
        fields = [("p", dbl * np_), ("ko", dbl * n), ("c", dbl * n), ("period", dbl)]
        fields += [("half", dbl), ("started", ctypes.c_int)]
        fields += [(f, dbl * n) for f in ("p_start", "integral", "r", "tau_prev", "beta_prev")]
        self._State = type("State", (ctypes.Structure,), {"_fields_": fields})
        self._state = self._State()
        self._init = getattr(self._lib, f"{code.function}_init")
        self._step = getattr(self._lib, f"{code.function}_step")
        self._ptr = ctypes.POINTER(dbl)
        self._step.argtypes = [ctypes.POINTER(self._State)] + [self._ptr] * 4
        self._step.restype = None
        self._n = n
        self.reset()

    def reset(self) -> None:
        import ctypes

        self._init(ctypes.byref(self._state))

    def __call__(self, q, dq, tau) -> np.ndarray:
        import ctypes

        args = [np.ascontiguousarray(a, dtype=float) for a in (q, dq, tau)]
        for a in args:
            if a.shape != (self._n,):
                raise ValueError(f"observer inputs must have shape ({self._n},), got {a.shape}")
        r = np.zeros(self._n)
        self._step(ctypes.byref(self._state), *[a.ctypes.data_as(self._ptr) for a in args + [r]])
        return r


# ---------------------------------------------------------------------------------------------
# PLCopen XML (IEC 61131-10 / TC6 XML v2.01)
# ---------------------------------------------------------------------------------------------
PLCOPEN_NS = "http://www.plcopen.org/xml/tc6_0201"
_XHTML_NS = "http://www.w3.org/1999/xhtml"
_SECTIONS = {"VAR_INPUT": "inputVars", "VAR_OUTPUT": "outputVars", "VAR": "localVars"}
_DECL = re.compile(
    r"\s*(\w+)\s*:\s*(?:ARRAY\[([0-9., ]+)\]\s+OF\s+)?(LREAL|BOOL)\s*;\s*", re.IGNORECASE
)


def _function_blocks(text: str) -> list[dict]:
    """The FUNCTION_BLOCKs of generated Structured Text: name, variable sections, body, and the
    comment lines before the first block."""
    blocks = []
    for m in re.finditer(r"FUNCTION_BLOCK (\w+)\n(.*?)END_FUNCTION_BLOCK", text, re.DOTALL):
        name, inner = m.group(1), m.group(2)
        sections: list[tuple[str, list[tuple[str, list[tuple[int, int]], str]]]] = []
        lines = inner.split("\n")
        i = 0
        while i < len(lines) and lines[i].strip() in _SECTIONS:
            kind, decls = _SECTIONS[lines[i].strip()], []
            i += 1
            while lines[i].strip() != "END_VAR":
                d = _DECL.fullmatch(lines[i])
                if not d:
                    raise ValueError(f"FUNCTION_BLOCK {name}: unexpected declaration '{lines[i]}'")
                dims = []
                if d.group(2):
                    for r in d.group(2).split(","):
                        lo, hi = r.split("..")
                        dims.append((int(lo), int(hi)))
                decls.append((d.group(1), dims, d.group(3).upper()))
                i += 1
            sections.append((kind, decls))
            i += 1
        blocks.append({"name": name, "sections": sections, "body": "\n".join(lines[i:])})
    return blocks


def plcopen_project(texts: Sequence[str], project: str, comment: str = "") -> bytes:
    """A PLCopen XML (TC6 XML v2.01) project with the FUNCTION_BLOCKs of the given generated
    Structured Text texts as POUs (interface variables typed, bodies in ``<ST><xhtml:p>``), ready
    for import into CODESYS and other IEC 61131-3 tools. Returns UTF-8 XML bytes."""
    import datetime
    import xml.etree.ElementTree as ET

    ET.register_namespace("", PLCOPEN_NS)
    ET.register_namespace("xhtml", _XHTML_NS)

    def el(parent, tag, **attrs):
        return ET.SubElement(parent, f"{{{PLCOPEN_NS}}}{tag}", attrs)

    now = datetime.datetime.now(datetime.timezone.utc).replace(microsecond=0).isoformat()
    root = ET.Element(f"{{{PLCOPEN_NS}}}project")
    from ._version import __version__

    el(
        root,
        "fileHeader",
        companyName="mindyn",
        productName="mindyn",
        productVersion=str(__version__),
        creationDateTime=now,
        contentDescription="generated robot dynamics and controllers",
    )
    header = el(root, "contentHeader", name=project, modificationDateTime=now)
    if comment:
        el(header, "Comment").text = comment
    coord = el(header, "coordinateInfo")
    for lang in ("fbd", "ld", "sfc"):
        el(el(coord, lang), "scaling", x="1", y="1")
    types = el(root, "types")
    el(types, "dataTypes")
    pous = el(types, "pous")
    for text in texts:
        head = text.split("FUNCTION_BLOCK ", 1)[0]
        notes = "\n".join(re.findall(r"\(\*(.*?)\*\)", head, re.DOTALL)).strip()
        for fb in _function_blocks(text):
            pou = el(pous, "pou", name=fb["name"], pouType="functionBlock")
            interface = el(pou, "interface")
            for kind, decls in fb["sections"]:
                section = el(interface, kind)
                for var, dims, base in decls:
                    typ = el(el(section, "variable", name=var), "type")
                    if dims:
                        arr = el(typ, "array")
                        for lo, hi in dims:
                            el(arr, "dimension", lower=str(lo), upper=str(hi))
                        el(el(arr, "baseType"), base)
                    else:
                        el(typ, base)
            st = el(el(pou, "body"), "ST")
            ET.SubElement(st, f"{{{_XHTML_NS}}}p").text = fb["body"]
            if notes:
                doc = el(pou, "documentation")
                ET.SubElement(doc, f"{{{_XHTML_NS}}}p").text = notes
    el(el(root, "instances"), "configurations")
    ET.indent(root)
    return ET.tostring(root, encoding="utf-8", xml_declaration=True)
