"""The simulation stack: a simulated robot under a discrete-time joint controller along a
reference trajectory, standing in for a real robot (identification logs) and for a control
experiment (tracking reports).

- One reference protocol, :class:`Reference`: ``n`` joints, a ``duration`` and
  ``evaluate(t) -> (q_d, dq_d, ddq_d)`` for times ``t`` of shape (m,), each (m, n). The Fourier
  series of ``mindyn excite`` (:class:`~mindyn.identification.excitation.FourierTrajectory`, its
  JSON read by :func:`load_reference`), a CSV (:class:`CsvTrajectory`), a sum of sines within the
  limits (:class:`SumOfSines`) and a joint log (:class:`~mindyn.identification.data.JointData`)
  satisfy it.
- One controller protocol, :class:`Controller`: ``u = step(t, q, dq, q_d, dq_d, ddq_d)`` once
  per period on the measured state, the torque held until the next call; the controllers of
  :mod:`mindyn.control` and a compiled step with internal state alike.
- One integrator, the C++ ``mindyn::Integrator``: classical Runge-Kutta (RK4) of the forward
  dynamics of the true robot with the torque held over each controller period, ``substeps``
  steps per period (or scipy's adaptive RK45, ``integrator="scipy"``).
- One result, :class:`SimulationResult`: what was logged (measured, noisy), what was true, the
  reference and the controller's model terms; :meth:`SimulationResult.save` writes the log of
  ``mindyn identify``, :func:`write_tracking_report` the tracking report of ``mindyn track``.

:func:`simulate` runs the closed loop; :func:`simulate_inverse` is the open-loop alternative
(the motion is the reference, the torques by inverse dynamics, no controller).
"""

from __future__ import annotations

import csv
import json
import math
import re
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from .. import _args, _core
from .._args import ArgumentError
from ..base import BaseParameters
from ..robot import Robot, as_robot, drive_train_record, load

__all__ = [
    "Controller",
    "CsvTrajectory",
    "Reference",
    "SensorNoise",
    "SimulationResult",
    "SimulationTimeoutError",
    "SumOfSines",
    "TorqueProfile",
    "ContactWrench",
    "load_reference",
    "simulate",
    "simulate_inverse",
    "summary",
    "write_tracking_report",
]


class Controller(Protocol):
    """A discrete-time joint controller, called once per control period.

    ``q, dq`` are the measured joint state, ``q_d, dq_d, ddq_d`` the reference at time ``t``;
    all shape (n,). Returns the joint torque, shape (n,), held until the next call. A controller
    may keep and update internal state (e.g. parameter estimates) on each call; a compiled step
    ``u = step(t, q, dq, q_d, dq_d, ddq_d)`` wrapped as a Python callable satisfies the protocol.

    Optional members, used when present: ``reset()`` (called once before a run: back to the
    initial state), ``period`` (the period the controller was made for, in s: a run at another
    period is refused), and, read after each call for the report, ``model_torque`` (the model
    part of the torque, shape (n,)), ``p_hat`` (the current parameter estimate) and ``Y`` (the
    regressor with ``model_torque = Y p_hat``), ``base`` (the
    :class:`~mindyn.base.BaseParameters` that ``p_hat`` is in). The controllers of
    :func:`~mindyn.control.make_controller` made with the true parameters have ``true_model``
    True and take the simulated robot's (``use_parameters``); their sampled loop is checked
    before the run (:func:`~mindyn.control.controllers.controller_check`)."""

    def __call__(self, t: float, q, dq, q_d, dq_d, ddq_d) -> np.ndarray: ...


class Reference(Protocol):
    """A reference trajectory: ``n`` joints, a natural ``duration`` [s] (the default simulated
    time) and ``evaluate(t)``: positions, velocities and accelerations at times ``t`` (shape
    (m,), from 0), three (m, n) arrays."""

    @property
    def n(self) -> int: ...  # an attribute or a read-only property

    @property
    def duration(self) -> float: ...

    def evaluate(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...


# ---------------------------------------------------------------------------------------------
# References
# ---------------------------------------------------------------------------------------------
class SumOfSines:
    """A smooth periodic reference inside the joint limits:
    ``q_d,i(t) = c_i + a_i (sin(w t + phi_i) + 0.5 sin(2 w t + 2 phi_i) + 0.25 sin(3 w t))``
    with ``w = 2 pi / period``, ``c`` the middle of the limits and the amplitude ``a_i`` the
    largest that keeps ``q_d`` within ``fraction`` of the half range and ``|dq_d|`` within
    ``fraction`` of the velocity limit (joints without limits: half range pi/2, 1 rad/s).
    ``duration`` is one period."""

    def __init__(self, robot: Robot, *, period: float = 10.0, fraction: float = 0.5, seed: int = 0):
        _args.instance(robot, "robot", Robot)
        period = _args.number(period, "period", positive=True)
        fraction = _args.number(fraction, "fraction", positive=True, maximum=1.0)
        seed = _args.integer(seed, "seed", 0)
        if not period > 0:
            raise ArgumentError(f"period must be positive, got {period}")
        if not 0 < fraction <= 1:
            raise ArgumentError(f"fraction must be in (0, 1], got {fraction}")
        lim = robot.limits
        lo = np.where(np.isfinite(lim["lower"]), lim["lower"], -np.pi / 2)
        hi = np.where(np.isfinite(lim["upper"]), lim["upper"], np.pi / 2)
        vmax = np.where(np.isfinite(lim["velocity"]), lim["velocity"], 1.0)
        self.n = robot.n
        self.period = self.duration = float(period)
        self.w = 2 * np.pi / self.period
        self.center = 0.5 * (lo + hi)
        self.phase = np.random.default_rng(seed).uniform(0, 2 * np.pi, robot.n)
        # bounds of the unit shape: |sum| <= 1.75, |d/dt| <= w (1 + 1 + 0.75)
        amp_q = fraction * 0.5 * (hi - lo) / 1.75
        amp_v = fraction * vmax / (2.75 * self.w)
        self.amplitude = np.minimum(amp_q, amp_v)

    def evaluate(self, t):
        w, p, a = self.w, self.phase, self.amplitude
        th = w * np.atleast_1d(np.asarray(t, dtype=float))[:, None]
        s = np.sin(th + p) + 0.5 * np.sin(2 * th + 2 * p) + 0.25 * np.sin(3 * th)
        ds = w * (np.cos(th + p) + np.cos(2 * th + 2 * p) + 0.75 * np.cos(3 * th))
        dds = -(w**2) * (np.sin(th + p) + 2 * np.sin(2 * th + 2 * p) + 2.25 * np.sin(3 * th))
        return self.center + a * s, a * ds, a * dds


def _time_unit(name: str | None, path: Path) -> str | None:
    """The unit the header's first name ``name`` gives the time in (``t[ms]``), None for none;
    DataError for a unit of time it does not know."""
    from ..identification.columns import TIME_UNITS
    from ..identification.data import DataError

    m = re.fullmatch(r"t\s*\[([^\]]*)\]", name or "")
    if m is None:
        return None
    unit = m.group(1).strip()
    if unit not in TIME_UNITS:
        raise DataError(
            f"{path}: the header gives t in '{unit}'; the units of t are " + ", ".join(TIME_UNITS)
        )
    return unit


def _trajectory_columns(header: list[str], n: int, path: Path) -> list[int]:
    """The indices of a trajectory CSV's columns ``t, q1..qN[, dq1..dqN[, ddq1..ddqN]]`` by
    their names in ``header`` (any order after ``t``; other columns, such as a log's
    ``tau1..tauN``, left out); DataError for a missing or repeated one, a group given in part,
    or a motion column with a unit (the reference is in rad and m)."""
    from ..identification.data import DataError

    where: dict[str, int] = {}
    for j, name in enumerate(header[1:], 1):
        m = re.fullmatch(r"(q|dq|ddq)([1-9][0-9]*)\s*(\[.*\])?", name)
        if m is None:
            continue  # not a motion column: a log's torques or currents, a comment column
        if m.group(3):
            raise DataError(
                f"{path}: column '{name}' gives a unit; a trajectory's positions, velocities "
                "and accelerations are in rad (m), rad/s and rad/s^2: convert the column and "
                f"name it {m.group(1)}{m.group(2)}"
            )
        if name in where:
            raise DataError(f"{path}: column '{name}' is given twice")
        where[name] = j
    order = [0]
    for group in ("q", "dq", "ddq"):
        names = [f"{group}{k}" for k in range(1, n + 1)]
        have = [c for c in names if c in where]
        if group == "q" or have:
            missing = [c for c in names if c not in where]
            if missing:
                raise DataError(
                    f"{path}: the header has no column {', '.join(missing)}; a trajectory "
                    f"gives t, q1..q{n} and optionally dq1..dq{n} and ddq1..ddq{n}"
                )
            order += [where[c] for c in names]
        extra = [c for c in where if re.fullmatch(rf"{group}[0-9]+", c) and c not in names]
        if extra:
            raise DataError(f"{path}: column(s) {', '.join(extra)} beyond the robot's {n} joints")
    if "ddq1" in where and "dq1" not in where:
        raise DataError(f"{path}: ddq1..ddq{n} without dq1..dq{n}; give both or neither")
    return order


class CsvTrajectory:
    """A reference from a CSV file with columns ``t, q1..qN`` and optionally ``dq1..dqN`` and
    ``ddq1..ddqN`` (``mindyn excite`` writes such a file). With a header line the columns are
    taken by their names, in any order after ``t``, and others are left out (a log's
    ``tau1..tauN``: the motion of a log replays); without one, by their count in that order.
    Time in s, or in the unit the header's first name gives, ``t[ms]`` (``s``, ``ms``, ``us``,
    ``ns``, as a column map's ``t``; :attr:`time_unit` that unit, None when not given).
    Positions are interpolated by cubic splines; missing velocities and accelerations are the
    spline's derivatives. Times count from the first sample; after the last sample the
    reference holds the last position at rest."""

    def __init__(self, path: str | Path, n: int):
        from scipy.interpolate import CubicSpline

        from ..identification.data import DataError, decode_text, parse_cell

        path = Path(path)
        if not path.is_file():
            from .._core import RobotFileNotFoundError

            raise RobotFileNotFoundError(f"trajectory file '{path}' does not exist")
        rows: list[list[float]] = []
        header: list[str] = []
        # cells as a log's (identification.data.parse_cell): ASCII decimals, so that '1_000',
        # hex or non-ASCII digits are refused, not read as Python's float() reads them
        reader = csv.reader(decode_text(path).splitlines())
        try:
            for lineno, row in enumerate(reader, 1):
                if not row or all(not c.strip() for c in row):
                    continue
                if lineno == 1:
                    try:
                        parse_cell(row[0], "")
                    except DataError:
                        header = [c.strip() for c in row]  # a first line whose t is not a number
                        continue
                rows.append(
                    [
                        parse_cell(
                            c,
                            f"{path}, line {lineno}, column "
                            + (header[j] if j < len(header) else str(j + 1)),
                        )
                        for j, c in enumerate(row)
                    ]
                )
        except csv.Error as e:  # a field past the csv module's size limit
            raise DataError(f"{path}, line {reader.line_num}: not readable as CSV ({e})") from None
        if len({len(r) for r in rows}) > 1:
            raise DataError(f"{path}: rows have different numbers of columns")
        if len(rows) < 4:
            raise DataError(f"{path}: need at least 4 samples, found {len(rows)}")
        data = np.array(rows, dtype=float)
        if header:  # the columns by their names, in the order t, q, dq, ddq
            data = data[:, _trajectory_columns(header, n, path)]
        cols = data.shape[1]
        if cols not in (1 + n, 1 + 2 * n, 1 + 3 * n):
            raise DataError(
                f"{path}: {cols} columns; expected t and q1..q{n} ({1 + n}), plus dq "
                f"({1 + 2 * n}) and ddq ({1 + 3 * n})"
            )
        if not np.all(np.isfinite(data)):
            raise DataError(f"{path}: contains NaN or infinite values")
        self.time_unit = _time_unit(header[0] if header else None, path)
        if self.time_unit is not None:
            from ..identification.columns import TIME_UNITS

            data[:, 0] /= TIME_UNITS[self.time_unit]
        t = data[:, 0]
        if np.any(np.diff(t) <= 0):
            raise DataError(f"{path}: time column must be strictly increasing")
        self.n = n
        self.t0, self.t1 = float(t[0]), float(t[-1])
        self.duration = self.t1 - self.t0
        self._q = CubicSpline(t, data[:, 1 : 1 + n])
        self._dq = CubicSpline(t, data[:, 1 + n : 1 + 2 * n]) if cols >= 1 + 2 * n else None
        self._ddq = CubicSpline(t, data[:, 1 + 2 * n :]) if cols == 1 + 3 * n else None
        self._qend = data[-1, 1 : 1 + n]
        self._samples = data[:, 1 : 1 + n]  # the positions as the file gives them
        self._t = t
        self._dq_samples = data[:, 1 + n : 1 + 2 * n] if cols >= 1 + 2 * n else None

    def evaluate(self, t):
        t = self.t0 + np.atleast_1d(np.asarray(t, dtype=float))
        inside = np.minimum(t, self.t1)
        q = self._q(inside)
        dq = self._dq(inside) if self._dq is not None else self._q(inside, 1)
        ddq = self._ddq(inside) if self._ddq is not None else self._q(inside, 2)
        after = t >= self.t1
        q[after], dq[after], ddq[after] = self._qend, 0.0, 0.0
        return q, dq, ddq


def load_reference(path, n: int, *, robot: Robot | None = None):
    """A reference from the JSON of ``mindyn excite`` (its exact Fourier series) or from a CSV
    (:class:`CsvTrajectory`, e.g. the CSV ``mindyn excite`` writes) for a robot of ``n`` joints;
    raises ValueError when the file gives another number of joints, and, given ``robot``, when
    the JSON names another robot (whose limits the excitation kept) or the CSV's positions are
    in degrees or millimetres (:func:`~mindyn.identification.data.check_position_units`); a
    CSV whose velocities are not its positions' derivative is refused too
    (:func:`~mindyn.identification.data.check_velocity_units`), and so is one whose median
    interval between time stamps is 0.5 s or more unless its header states the time's unit
    (:func:`~mindyn.identification.data.check_time_units`: ``t[s]`` for a trajectory that
    slow)."""
    _args.path(path, "path")
    n = _args.integer(n, "n", 1)
    _args.optional(_args.instance, robot, "robot", Robot)
    from ..identification.data import DataError, read_json
    from ..identification.excitation import FourierTrajectory

    p = Path(path)
    if p.suffix.lower() == ".json":
        ref = FourierTrajectory.load(p)
        if ref.n != n:
            raise ArgumentError(f"{path} has {ref.n} joints; the robot has {n}")
        made_for = read_json(p, what="trajectory file").get("robot")
        if robot is not None and made_for not in (None, robot.name):
            raise DataError(
                f"{path}: an excitation of robot '{made_for}', not '{robot.name}' (it keeps the "
                "limits of the robot it was made for)"
            )
        return ref
    ref = CsvTrajectory(p, n)
    from ..identification.data import (
        check_position_units,
        check_time_units,
        check_velocity_units,
    )

    if ref.time_unit is None:
        check_time_units(
            ref._t,
            str(p),
            "give t in s, or state its unit as the header's first name: t[ms], t[us] or t[ns] "
            "(t[s] for a trajectory this slow)",
        )
    if ref._dq_samples is not None:
        check_velocity_units(ref._t, ref._samples, ref._dq_samples, str(p))
    if robot is not None:
        check_position_units(ref._samples, robot, str(p))
    return ref


@dataclass
class SensorNoise:
    """Measurement imperfections, per joint (scalars broadcast).

    ``torque``, ``position``, ``velocity``: standard deviations of white Gaussian noise
    [N m | N], [rad | m], [rad/s | m/s]. ``quantization``: encoder step [rad | m] applied to
    positions before the noise (0: none)."""

    torque: float | np.ndarray = 0.0
    position: float | np.ndarray = 0.0
    velocity: float | np.ndarray = 0.0
    quantization: float | np.ndarray = 0.0

    def arrays(self, n: int) -> dict[str, np.ndarray]:
        out = {}
        for k in ("torque", "position", "velocity", "quantization"):
            given = getattr(self, k)
            v = None
            if given is not None and not isinstance(given, (str, bytes)):
                try:
                    v = np.asarray(given, dtype=float)
                except (TypeError, ValueError):
                    v = None
            if v is None:
                raise ArgumentError(
                    f"{k} noise is {_args.describe(given)}; expected a scalar or ({n},) of "
                    "finite non-negative numbers"
                )
            try:
                v = np.broadcast_to(v, (n,)).copy()
            except ValueError:
                raise ArgumentError(
                    f"{k} noise has shape {v.shape}; expected a scalar or ({n},)"
                ) from None
            if (v < 0).any() or not np.isfinite(v).all():
                raise ArgumentError(f"{k} noise must be finite and non-negative, got {v.tolist()}")
            out[k] = v
        return out

    def measure_q(self, q, rng, arr):
        step = arr["quantization"]
        qm = np.where(step > 0, np.round(q / np.where(step > 0, step, 1.0)) * step, q)
        return qm + arr["position"] * rng.standard_normal(q.shape)


def _true_params(robot: Robot, rotor: bool, friction: bool, params=None):
    names = robot.parameter_names(rotor=True, friction=True)
    if params is None:
        p = robot.parameters(rotor=True, friction=True).reshape(robot.n, -1).copy()
        if not rotor:
            p[:, 10] = 0.0
        if not friction:
            p[:, 11:] = 0.0
        params = p.reshape(-1)
    return names, expand_params(robot.n, params, sizes=robot.layout_sizes)


#: RK4's step times the plant's fastest damping rate is kept below this (RK4 is stable on the
#: negative real axis up to 2.785); the default steps per period are at least MIN_SUBSTEPS.
RK4_STEP_RATE = 2.0
MIN_SUBSTEPS = 4


def _why(substeps: int, rate: float | None) -> str:
    """Why a simulation takes ``substeps`` RK4 steps per period (``rate``: the plant's fastest
    damping rate when the steps were derived from it, None when given)."""
    if rate is None:
        return ", as given"
    if substeps == MIN_SUBSTEPS:
        return f", the default; the plant's fastest damping rate {rate:.3g} 1/s needs no more"
    return (
        f", so that the step times the plant's fastest damping rate {rate:.3g} 1/s (viscous "
        f"friction on inertia) stays below {RK4_STEP_RATE:g}"
    )


def rk4_substeps(robot: Robot, params, period: float) -> tuple[int, float]:
    """The RK4 steps per controller ``period`` the plant needs, and its fastest damping rate
    ``lambda`` [1/s]: the largest eigenvalue of ``M(q)^-1 D`` over :func:`workspace_samples`,
    ``M`` the mass matrix and ``D`` the viscous friction's ``d tau / d dq`` of the classical
    ``params`` (rotor inertia and friction included; on the motors, ``T^T diag(Fv) T``).
    Explicit RK4 diverges once its step exceeds 2.785 / lambda (a light wrist link with a large
    damping, as in the xArm7 of example-robot-data: lambda = 1.4e4 1/s), so the steps are
    ``max(MIN_SUBSTEPS, ceil(period lambda / RK4_STEP_RATE))``."""
    from .controllers import plant_damping
    from .stability import workspace_samples

    names = robot.parameter_names(rotor=True, friction=True)
    p = expand_params(robot.n, params, sizes=robot.layout_sizes)
    viscous = np.where([name.startswith("Fv") for name in names], p, 0.0)
    rate = 0.0
    if np.any(viscous != 0.0):
        qs = workspace_samples(robot)
        damping = plant_damping(robot, viscous, qs)
        eig = np.linalg.eigvals(np.linalg.solve(robot.mass_matrix(qs, p), damping))
        rate = float(np.max(eig.real))
    return max(MIN_SUBSTEPS, math.ceil(period * rate / RK4_STEP_RATE)), rate


def expand_params(n: int, params, *, sizes=(10, 11, 12, 13)) -> np.ndarray:
    """A classical vector of any layout (``sizes`` per joint: 10, 11 with Ia, 10 + c with the c
    friction columns, 11 + c with all; ``Robot.layout_sizes``) in the full layout (the last),
    absent entries zero."""
    p = np.asarray(params, dtype=float).reshape(-1)
    per = p.shape[0] // n if n else 0
    if per * n != p.shape[0] or per not in sizes:
        raise ArgumentError(
            f"params has {p.shape[0]} entries; expected "
            + ", ".join(str(k * n) for k in sizes[:-1])
            + f" or {sizes[-1] * n}"
        )
    if not np.isfinite(p).all():
        raise ArgumentError("params contains NaN or infinite values")
    c = sizes[2] - 10
    blocks = p.reshape(n, per)
    out = np.zeros((n, sizes[3]))
    out[:, :10] = blocks[:, :10]
    if per in (sizes[1], sizes[3]):
        out[:, 10] = blocks[:, 10]
    if per in (sizes[2], sizes[3]):
        out[:, 11:] = blocks[:, -c:]
    return out.reshape(-1)


#: Most samples (control periods) one simulation may have: the logs are held in memory, about
#: 60 bytes per sample and joint (tracking) before they are written.
MAX_SAMPLES = 1_000_000
#: Most integration steps (samples x substeps) one simulation may take: about two minutes of
#: RK4 with the controller on a 6-joint robot (3 s per 100,000 steps measured).
MAX_STEPS = 4_000_000


def check_steps(duration: float, rate: float, *, substeps: int = 1) -> int:
    """Number of samples of a simulation of ``duration`` s at ``rate`` Hz with ``substeps``
    integration steps each; raises ValueError unless all are finite and positive and within
    :data:`MAX_SAMPLES` and :data:`MAX_STEPS` (the message gives the counts and the limits)."""
    duration, rate = float(duration), float(rate)
    if not (math.isfinite(duration) and duration > 0):
        raise ArgumentError(f"duration must be a positive number of seconds, got {duration:g}")
    if not (math.isfinite(rate) and rate > 0):
        raise ArgumentError(f"rate must be a positive number of Hz, got {rate:g}")
    if not substeps >= 1:
        raise ArgumentError(f"substeps must be at least 1, got {substeps}")
    samples = duration * rate
    if samples > MAX_SAMPLES or samples * substeps > MAX_STEPS:
        raise ArgumentError(
            f"{duration:g} s at {rate:g} Hz are {samples:.4g} samples"
            + (f" x {substeps} substeps = {samples * substeps:.4g} steps" if substeps > 1 else "")
            + f"; at most {MAX_SAMPLES:,} samples and {MAX_STEPS:,} integration steps are "
            "simulated (shorten the duration or lower the rate)"
        )
    return int(round(samples)) + 1


def _span(reference, duration):
    if duration is not None:
        return float(duration)
    if getattr(reference, "duration", None) is None:
        raise ArgumentError("duration is needed for a reference without a duration")
    return float(reference.duration)


# ---------------------------------------------------------------------------------------------
# Result
# ---------------------------------------------------------------------------------------------
@dataclass
class SimulationResult:
    """A simulation at the controller samples (``m`` samples, ``n`` joints).

    ``t`` (m,); ``q, dq, tau``: the logged (measured) values, (m, n) each (with sensor noise;
    the controller saw ``q`` and ``dq``); ``q_true, dq_true, ddq_true, tau_true``: the true
    motion and the applied torque (after limits); ``qd, dqd, ddqd``: the reference;
    ``tau_model``: the model part of the controller's torque (NaN when it has none);
    ``tau_true_model``: the same with the true parameters (adaptive controllers);
    ``p_hat`` (m, nb): the controller's estimate after each call, ``p_true`` (nb,) the true
    values, in the base parameters ``base_names``; ``saturated`` (m, n): torque limited;
    ``params``, ``param_names``: the simulated robot's classical parameters (the full layout:
    rotor inertia and its friction model's columns per joint);
    ``tau_ext`` (m, n): the external joint torque held over each period (None without one);
    ``friction_state`` (m, n): the plant's Dahl state at each sample (None without one);
    ``info``: settings and figures."""

    t: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    tau: np.ndarray
    q_true: np.ndarray
    dq_true: np.ndarray
    ddq_true: np.ndarray
    tau_true: np.ndarray
    qd: np.ndarray
    dqd: np.ndarray
    ddqd: np.ndarray
    info: dict = field(default_factory=dict)
    params: np.ndarray | None = None
    param_names: list = field(default_factory=list)
    tau_model: np.ndarray | None = None
    tau_true_model: np.ndarray | None = None
    p_hat: np.ndarray | None = None
    p_true: np.ndarray | None = None
    base_names: list = field(default_factory=list)
    saturated: np.ndarray | None = None
    tau_ext: np.ndarray | None = None
    friction_state: np.ndarray | None = None

    @property
    def controller(self) -> str:
        return self.info.get("controller", "")

    @property
    def period(self) -> float:
        return 1.0 / self.info["rate_Hz"]

    @property
    def error(self) -> np.ndarray:
        """True position error ``q_true - q_d``, shape (m, n), rad."""
        return _args.readonly(self.q_true - self.qd)

    @property
    def display_scale(self) -> np.ndarray:
        """Per joint, the factor from rad (m) to the unit of the ``*_deg`` figures: degrees for
        a revolute joint, millimetres for a prismatic one (:func:`display_scale`)."""
        return display_scale(self.info.get("joint_types") or ["revolute"] * self.q_true.shape[1])

    def max_error_deg(self, *, t_from: float = 0.0) -> np.ndarray:
        """Largest ``|q - q_d|`` per joint in degrees (mm on prismatic joints), from ``t_from``
        on."""
        sel = self.t >= t_from
        return self.display_scale * np.abs(self.error[sel]).max(axis=0)

    def rms_error_deg(self, t0: float, t1: float) -> np.ndarray:
        """RMS position error per joint in degrees (mm on prismatic joints) over
        ``t0 <= t < t1``."""
        sel = (self.t >= t0) & (self.t < t1)
        if not np.any(sel):
            raise ArgumentError(f"no samples in [{t0}, {t1})")
        return self.display_scale * np.sqrt(np.mean(self.error[sel] ** 2, axis=0))

    def final_error_deg(self) -> np.ndarray:
        """``q - q_d`` at the last sample, degrees (mm on prismatic joints)."""
        return self.display_scale * self.error[-1]

    def save(self, path, *, robot_name: str = "", joint_names=None, link_frames=None) -> Path:
        """Writes ``t, q, dq, tau`` (the logged values, torques in N m) to ``path`` as
        ``mindyn identify`` reads it and the true parameters and settings to the sidecar
        ``<stem>.truth.json``, with the robot's name and ``joint_names`` (when given), by which
        ``mindyn identify`` refuses the log for another robot, and ``link_frames``
        (:func:`mindyn.identification.data.link_frames`, when given), the frames the classical
        values are about, by which it compares them only with a description of those frames."""
        # imported here: the identification package (and scipy.signal) is not needed to simulate
        from ..identification.data import truth_path, write_csv

        assert self.params is not None  # a simulation's result has the plant's parameters
        path = write_csv(path, self.t, self.q, self.tau, dq=self.dq)
        truth = {
            "robot": robot_name,
            **({} if joint_names is None else {"joints": list(joint_names)}),
            **({} if link_frames is None else {"link_frames": link_frames}),
            "names": self.param_names,
            "values": [float(v) for v in self.params],
            "simulation": self.info,
        }
        if self.tau_ext is not None:
            truth["external"] = external_spans(self.t, self.tau_ext)
        truth_path(path).write_text(json.dumps(truth, indent=2) + "\n")
        return path


# ---------------------------------------------------------------------------------------------
# Closed loop
# ---------------------------------------------------------------------------------------------
def effort_limits(robot: Robot, what: str) -> np.ndarray:
    """The robot's effort limits, one per joint, for ``what`` (the option asking for them); a
    joint without one (missing, zero or infinite in the description) is refused, named."""
    limit = np.asarray(robot.limits["effort"], dtype=float)
    missing = [k for k in range(robot.n) if not np.isfinite(limit[k]) or limit[k] <= 0]
    if missing:
        names = ", ".join(f"{k + 1} ('{robot.joint_names[k]}')" for k in missing)
        raise ArgumentError(
            f"{what}: robot '{robot.name}' has no effort limits for joint(s) {names}; add them "
            "to its description or give other limits"
        )
    return limit


def _torque_limit(robot: Robot, torque_limit):
    if torque_limit is None:
        return None
    n = robot.n
    if isinstance(torque_limit, str):
        if torque_limit != "effort":
            raise ArgumentError(f"torque_limit must be None, 'effort' or {n} values")
        return effort_limits(robot, "torque_limit='effort'")
    if np.ndim(torque_limit) == 0:
        return np.full(n, _args.number(torque_limit, "torque_limit", minimum=0.0))
    limit = _args.array(torque_limit, "torque_limit", (n,))
    if np.any(limit < 0):
        raise _args.fail("torque_limit", f"must be None, 'effort' or {n} finite values >= 0")
    return limit


def simulate(
    robot: Robot | str,
    reference: Reference,
    controller: Controller | None = None,
    *,
    rate: float = 250.0,
    duration: float | None = None,
    substeps: int | None = None,
    integrator: str = "rk4",
    rotor: bool = False,
    friction: bool = False,
    params=None,
    noise: SensorNoise | None = None,
    torque_limit=None,
    seed: int = 0,
    coulomb_smoothing: float = 0.0,
    endpoint: bool = True,
    base=None,
    max_seconds: float | None = None,
    external=None,
    dahl_sigma=None,
) -> SimulationResult:
    """Closed-loop simulation: the robot tracks ``reference`` under ``controller``.

    Every ``1 / rate`` seconds the controller reads the measured state (quantised, noisy) and the
    reference and returns a torque; the torque (limited by ``torque_limit``) is held while the
    true robot moves for one period. The logged torque carries torque-sensor noise. The robot
    starts on the reference at t = 0.

    Parameters
    ----------
    robot : Robot or str
    reference : Reference
        E.g. :class:`SumOfSines`, :class:`CsvTrajectory`, a
        :class:`~mindyn.identification.excitation.FourierTrajectory` (:func:`load_reference`).
    controller : Controller, optional
        Default: computed torque with PD on the reference and the true parameters
        (:func:`mindyn.control.default_controller`).
    rate : float
        Controller and log rate [Hz] (default 250 Hz, a 4 ms period).
    duration : float, optional
        Simulated time [s]; default the reference's period (or duration).
    substeps : int, optional
        RK4 steps per control period. Default: :func:`rk4_substeps`, at least 4 and as many as
        the robot's viscous friction on its inertia needs for RK4 to stay stable (recorded in
        the result's ``info``).
    integrator : {"rk4", "scipy"}
        Fixed-step RK4 (C++ ``mindyn::Integrator``) or scipy's adaptive RK45 per period
        (rtol 1e-8).
    rotor, friction : bool
        Give the simulated robot its rotor inertia / friction (from the description).
    params : array, optional
        True classical parameters (any layout, e.g. 13 n with Ia, Fv, Fc per joint; the friction
        model's columns are those of ``robot.friction_model``); overrides
        ``rotor`` and ``friction``.
    noise : SensorNoise, optional
    torque_limit : None, "effort" or array (n,)
        Saturation of the applied torque (``"effort"``: the model's effort limits).
    seed : int
        Seed of the noise generator.
    coulomb_smoothing : float
        If positive, the simulated Coulomb friction is ``Fc tanh(dq / coulomb_smoothing)``
        [rad/s | m/s] instead of ``Fc sign(dq)`` (plant and default controller).
    endpoint : bool
        Samples at ``0, T, ..., duration`` (True: ``duration * rate + 1`` samples, a log of the
        whole span) or up to one period before ``duration`` (False: ``duration * rate``
        controller periods, as the tracking report counts them).
    base : BaseParameters, optional
        The base parameters in which the true values ``p_true`` and the true model torque are
        reported beside the controller's estimates (default: the controller's ``base``).
    max_seconds : float, optional
        Wall-time bound of the run (default :data:`MAX_SECONDS`); scipy's RK45 is also bounded
        to :data:`SCIPY_MAX_EVALUATIONS` evaluations per period.
    external : callable, optional
        An external joint torque acting on the robot (a contact, a collision): ``external(t, q,
        dq)`` gives the torque (n,) [N m | N] at the sample ``t`` and the true state there, held
        over the period like the controller's torque (:class:`TorqueProfile`, or
        :class:`ContactWrench` for a wrench at the tool); logged as ``tau_ext`` (and where it
        acted in the truth sidecar :meth:`SimulationResult.save` writes). The logged
        torque ``tau`` stays the controller's (a robot without joint torque sensors does not
        see it).

    dahl_sigma : array_like (n,), optional
        Dahl presliding friction in the plant (with ``friction``, the coulomb friction model,
        friction on the joints, the rk4 integrator): the true robot's Coulomb term
        ``Fc sign(dq)`` becomes ``Fc z``, the state ``z`` integrated with the plant's (RK4 on
        ``dz/dt = sigma (dq - z |dq|)``, ``z = 0`` at the start); ``sigma`` [1/rad | 1/m] the
        inverse presliding displacement. The controller's model keeps ``Fc sign(dq)`` (the Dahl
        model's steady state). Recorded in ``info["dahl"]`` with the state at each sample.

    Raises
    ------
    UnstableLoopError
        Before the run, when the linearised sampled loop of a controller of
        :mod:`mindyn.control.controllers` is unstable for the simulated robot
        (:func:`~mindyn.control.controllers.controller_check`; not with a ``torque_limit``,
        which bounds such a loop); during the run, when the
        tracking error grows past a full turn (revolute; a prismatic joint's range) and four
        times the reference's excursion, or the state or torque becomes non-finite.
    SimulationTimeoutError
        When the run exceeds ``max_seconds``.
    """
    robot = as_robot(robot)
    _args.protocol(reference, "reference", "evaluate", "a Reference (an object with evaluate(t))")
    _args.optional(_args.function, controller, "controller")
    rate = _args.number(rate, "rate", positive=True)
    duration = _args.optional(_args.number, duration, "duration", positive=True)
    substeps = _args.optional(_args.integer, substeps, "substeps", 1)
    _args.choice(integrator, "integrator", ("rk4", "scipy"))
    rotor, friction = _args.flag(rotor, "rotor"), _args.flag(friction, "friction")
    params = _args.optional(_args.array, params, "params", (None,))
    _args.optional(_args.instance, noise, "noise", SensorNoise)
    seed = _args.integer(seed, "seed", 0)
    coulomb_smoothing = _args.number(coulomb_smoothing, "coulomb_smoothing", minimum=0.0)
    endpoint = _args.flag(endpoint, "endpoint")
    _args.optional(_args.instance, base, "base", BaseParameters)
    max_seconds = _args.optional(_args.number, max_seconds, "max_seconds", positive=True)
    _args.optional(_args.function, external, "external")
    from .controllers import default_controller

    robot = load(robot)
    n = robot.n
    if integrator not in ("rk4", "scipy"):
        raise ArgumentError(f"integrator must be 'rk4' or 'scipy', got '{integrator}'")
    if substeps is not None and not (isinstance(substeps, (int, np.integer)) and substeps >= 1):
        raise ArgumentError(f"substeps must be an integer >= 1, got {substeps}")
    names, p_true = _true_params(robot, rotor, friction, params)
    damping_rate = None
    if substeps is None and integrator == "rk4":
        substeps, damping_rate = rk4_substeps(robot, p_true, 1.0 / rate)
    substeps = int(substeps or MIN_SUBSTEPS)  # (scipy's RK45 chooses its own steps)
    eps = float(coulomb_smoothing)
    dahl, p_plant = _dahl_plant(robot, friction, p_true, dahl_sigma)
    if dahl is not None and integrator != "rk4":
        raise _args.ArgumentError(
            "dahl_sigma: the rk4 integrator only (the state integrates with it)"
        )
    plant = _core.Integrator(robot._m, p_plant, eps)
    if controller is None:
        controller = default_controller(robot, p_true, coulomb_smoothing=eps)
    T = _span(reference, duration)
    m = check_steps(T, rate, substeps=substeps if integrator == "rk4" else 1)
    period = 1.0 / rate
    if not endpoint:
        m -= 1
    if m < 1:
        raise ArgumentError(f"duration {T:g} s is shorter than one period {period:g} s")
    own = getattr(controller, "period", None)
    if own is not None and not math.isclose(own, period, rel_tol=1e-9):
        raise ArgumentError(
            f"the controller was made for a period of {own:g} s; the simulation runs at "
            f"{period:g} s"
        )
    cycle = getattr(reference, "period", None)
    if isinstance(cycle, (int, float)) and not period * MIN_SAMPLES_PER_CYCLE <= cycle:
        raise ArgumentError(
            f"the controller period {period:g} s is not far below the reference's period "
            f"{cycle:g} s: at least {MIN_SAMPLES_PER_CYCLE} periods per cycle are needed"
        )
    from .controllers import base_values, controller_check

    limit = _torque_limit(robot, torque_limit)

    if getattr(controller, "true_model", False):  # the true parameters: the simulated robot's
        model: Any = controller  # a model-based controller: ComputedTorque, AdaptivePD
        model.use_parameters(base_values(model.base, p_true))
        if getattr(model, "box", None) == "derived":  # the box about the simulated robot
            model.derive_box(p_true)
    check = controller_check(robot, controller, p_true, period)
    if check is not None and not check.stable and limit is None:
        raise check.error(what="the controller")  # (a torque limit bounds an unstable linear loop)
    budget = _Budget(max_seconds)
    noise = noise or SensorNoise()
    arr = noise.arrays(n)
    rng = np.random.default_rng(seed)
    t = np.arange(m) * period
    qd, dqd, ddqd = (np.asarray(x, dtype=float) for x in reference.evaluate(t))
    if qd.shape != (m, n) or dqd.shape != (m, n) or ddqd.shape != (m, n):
        raise ArgumentError(f"the reference gives shape {qd.shape}; expected ({m}, {n}) joints")
    if check is not None:
        from .controllers import adaptation_check

        check.adaptation = adaptation_check(controller, qd, dqd, ddqd, period) or ""
    bound = _divergence_bound(robot, qd)
    base = base if base is not None else getattr(controller, "base", None)
    pb_true = None
    if base is not None and len(base.classical_names) == robot.layout_sizes[3] * n:
        pb_true = base.values(p_true)

    out = {k: np.empty((m, n)) for k in ("q", "dq", "ddq", "tau", "qm", "dqm", "taum", "taud")}
    out["taud"].fill(np.nan)
    ext = np.zeros((m, n)) if external is not None else None
    taut = np.full((m, n), np.nan)
    sat = np.zeros((m, n), dtype=bool)
    ph = None
    if hasattr(controller, "reset"):
        controller.reset()
    q, dq = qd[0].copy(), dqd[0].copy()
    z = np.zeros(n)  # the Dahl state (with dahl_sigma)
    states = np.zeros((m, n))  # the Dahl state per sample (with dahl_sigma)
    t0 = time.perf_counter()
    # A diverging loop shows as a non-finite torque, reported as such (not as warnings).
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        for i in range(m):
            qm = noise.measure_q(q, rng, arr)
            dqm = dq + arr["velocity"] * rng.standard_normal(n)
            tau = _controller_torque(controller(t[i], qm, dqm, qd[i], dqd[i], ddqd[i]), t[i], n)
            if tau.shape != (n,):
                raise ArgumentError(
                    f"the controller returned shape {tau.shape} at t = {t[i]:g} s; expected "
                    f"{n} torques"
                )
            if not np.all(np.isfinite(tau)):
                raise _diverged(
                    f"the controller returned a non-finite torque at t = {t[i]:.4f} s", check
                )
            if limit is not None:
                sat[i] = np.abs(tau) > limit
                tau = np.clip(tau, -limit, limit)
            out["q"][i], out["dq"][i], out["tau"][i] = q, dq, tau
            if ext is not None:
                ext[i] = _external_torque(external, t[i], q, dq)
            try:
                if dahl is None:
                    out["ddq"][i] = plant.acceleration(q, dq, tau)
                else:
                    states[i] = z
                    out["ddq"][i] = plant.acceleration(q, dq, tau - dahl[1] * z)
            except ValueError as e:  # the plant's own error, whatever its class
                raise _plant_error(e, t[i], q) from None
            out["qm"][i], out["dqm"][i] = qm, dqm
            out["taum"][i] = tau + arr["torque"] * rng.standard_normal(n)
            model_torque = getattr(controller, "model_torque", None)
            if model_torque is not None:
                out["taud"][i] = model_torque
            p_hat = getattr(controller, "p_hat", None)
            if p_hat is not None:
                if ph is None:
                    ph = np.zeros((m, len(p_hat)))
                ph[i] = p_hat
                Y = getattr(controller, "Y", None)
                if pb_true is not None and Y is not None:
                    taut[i] = Y @ pb_true
            if i < m - 1 or not endpoint:
                budget.t = t[i]
                try:
                    acting = tau if ext is None else tau + ext[i]
                    if dahl is None:
                        q, dq = _advance(plant, q, dq, acting, period, substeps, integrator, budget)
                    else:
                        budget.check("integration")
                        q, dq, z = _advance_dahl(plant, q, dq, z, acting, period, substeps, *dahl)
                except ValueError as e:  # the plant's own error, whatever its class
                    if "the integration diverged" not in str(e):
                        raise _plant_error(e, t[i], q) from None
                    raise _diverged(
                        f"the state became non-finite after t = {t[i]:.4f} s", check
                    ) from None
                if i + 1 < m:
                    over = np.flatnonzero(~(np.abs(q - qd[i + 1]) <= bound))
                    if over.size:
                        k = int(over[0])
                        raise _diverged(
                            f"the tracking error of joint {k + 1} reached "
                            f"{_amount(robot, k, q[k] - qd[i + 1, k])} at t = {t[i + 1]:.4f} s, "
                            f"beyond {_amount(robot, k, bound[k])}",
                            check,
                        )
    err = out["q"] - qd
    info = {
        "mode": "tracking",
        "torque": "held",  # the command, held over each period (identify reads it so)
        "controller": getattr(controller, "name", type(controller).__name__),
        "rate_Hz": rate,
        "substeps": substeps,
        "integrator": f"RK4 ({substeps} steps per period{_why(substeps, damping_rate)}), torque "
        "held over each period"
        if integrator == "rk4"
        else "scipy RK45, torque held over each period",
        "duration_s": T,
        "rotor": rotor,
        "friction": friction,
        "drive_side": robot.drive_side,
        **drive_train_record(robot),
        "coulomb_smoothing": eps,
        "noise": {k: v.tolist() for k, v in arr.items()},
        "seed": seed,
        "max_tracking_error": np.abs(err).max(0).tolist(),
        "joint_types": list(robot.joint_types),
        "seconds": time.perf_counter() - t0,
    }
    if check is not None:
        info["stability"] = check.text()
    if dahl is not None:
        info["dahl"] = {"sigma": dahl[0].tolist(), "state": "friction_state, 0 at the start"}
    adaptive = ph is not None and pb_true is not None
    return SimulationResult(
        t,
        out["qm"],
        out["dqm"],
        out["taum"],
        out["q"],
        out["dq"],
        out["ddq"],
        out["tau"],
        qd,
        dqd,
        ddqd,
        info,
        p_true,
        names,
        tau_model=out["taud"],
        # a controller with a fixed model and no regressor of its own (computed torque) has
        # no true-model torque to compare with
        tau_true_model=taut if adaptive and np.all(np.isfinite(taut)) else None,
        p_hat=ph,
        p_true=pb_true,
        base_names=list(base.names) if base is not None else [],
        saturated=sat,
        tau_ext=ext,
        friction_state=states if dahl is not None else None,
    )


#: At most this many spans of an external torque are written to a truth sidecar
MAX_EXTERNAL_SPANS = 1000


def external_spans(t: np.ndarray, tau_ext: np.ndarray) -> dict:
    """Where an external torque ``tau_ext`` (m, n), held over each period from the samples
    ``t`` (m,), acted: ``spans``, per run of samples with a non-zero torque, ``start_s`` (its
    first sample), ``stop_s`` (the sample after its last: the hold's end; the log's last
    sample plus one period for a run to the end) and ``peak`` (n,): each joint's torque of the
    largest magnitude in the run [N m | N] (at most :data:`MAX_EXTERNAL_SPANS` runs, the count
    of all in ``count``), for the truth sidecar of a simulated log (``external``)."""
    t = np.asarray(t, dtype=float)
    on = np.any(tau_ext != 0, axis=1).astype(np.int8)
    edges = np.diff(np.concatenate([[0], on, [0]]))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    period = float(t[-1] - t[-2]) if t.size > 1 else 0.0
    spans = []
    for a, b in zip(starts[:MAX_EXTERNAL_SPANS], stops[:MAX_EXTERNAL_SPANS]):
        block = tau_ext[a:b]
        k = np.argmax(np.abs(block), axis=0)
        spans.append(
            {
                "start_s": float(t[a]),
                "stop_s": float(t[b]) if b < t.size else float(t[-1] + period),
                "peak": [float(block[i, j]) for j, i in enumerate(k)],
            }
        )
    return {
        "what": "the external torque the simulation applied (held over each period): its runs",
        "count": int(starts.size),
        "spans": spans,
    }


def _external_torque(external, t: float, q, dq) -> np.ndarray:
    n = q.shape[0]
    value = np.asarray(external(t, q.copy(), dq.copy()), dtype=float)
    if value.shape != (n,) or not np.all(np.isfinite(value)):
        raise ArgumentError(
            f"the external torque at t = {t:g} s has shape {value.shape} or is not finite; "
            f"expected {n} finite torques"
        )
    return value


@dataclass
class TorqueProfile:
    """An external joint torque: ``torque`` (n,) [N m | N] acting from ``start`` to ``stop``
    [s] (``stop`` None: to the end), zero elsewhere; a callable ``external`` of
    :func:`simulate` (sampled at the controller samples, held over each period)."""

    torque: np.ndarray
    start: float = 0.0
    stop: float | None = None

    def __post_init__(self):
        # a read-only copy: neither the caller's array nor a returned torque can change it
        self.torque = _args.readonly(_args.array(self.torque, "torque", (None,)))
        self.start = _args.number(self.start, "start")
        if self.stop is not None:
            self.stop = _args.number(self.stop, "stop")
            if not self.stop > self.start:
                raise _args.fail(
                    "stop", f"is {self.stop:g}; expected a time after start ({self.start:g} s)"
                )

    def active(self, t: float) -> bool:
        return t >= self.start and (self.stop is None or t < self.stop)

    def __call__(self, t: float, q=None, dq=None) -> np.ndarray:
        return self.torque.copy() if self.active(t) else np.zeros_like(self.torque)


@dataclass
class ContactWrench(TorqueProfile):
    """An external wrench at the tool frame's origin, ``torque`` read as ``(fx, fy, fz, mx,
    my, mz)`` [N, N m] in the base frame, acting from ``start`` to ``stop``: the joint torque
    ``J(q)^T w`` of the tool Jacobian (:meth:`~mindyn.Robot.jacobian`) at each sample; needs
    ``robot``."""

    robot: Robot | None = None

    def __post_init__(self):
        super().__post_init__()
        if self.torque.shape != (6,):
            raise ArgumentError(f"a wrench has 6 entries (force, moment), got {self.torque.shape}")
        if not isinstance(self.robot, Robot):
            raise ArgumentError("ContactWrench needs the robot (robot=...)")

    def __call__(self, t: float, q=None, dq=None) -> np.ndarray:
        assert self.robot is not None  # __post_init__ requires it
        n = self.robot.n
        if not self.active(t):
            return np.zeros(n)
        J = self.robot.jacobian(q)  # rows vx vy vz wx wy wz
        return J.T @ self.torque


#: Fewest controller periods per cycle of a periodic reference (its third harmonic sampled
#: about 7 times per oscillation).
MIN_SAMPLES_PER_CYCLE = 20
#: Most right-hand-side evaluations scipy's RK45 may take within one controller period (a
#: smooth motion needs a few dozen; more means a stiff or diverging loop).
SCIPY_MAX_EVALUATIONS = 20_000
#: Default wall-time bound of one simulation [s].
MAX_SECONDS = 600.0


class SimulationTimeoutError(_core.Error, TimeoutError):
    """A simulation ran past its wall-time bound (``max_seconds`` of :func:`simulate`)."""


class _Budget:
    """The wall-time bound of one simulation (checked every period and, with scipy, every
    evaluation)."""

    def __init__(self, max_seconds):
        limit = MAX_SECONDS if max_seconds is None else float(max_seconds)
        if not (math.isfinite(limit) and limit > 0):
            raise ArgumentError(f"max_seconds must be a positive number, got {max_seconds}")
        self.limit = limit
        self.deadline = time.perf_counter() + limit
        self.t = 0.0  # simulated time of the period being integrated

    def check(self, where: str) -> None:
        if time.perf_counter() > self.deadline:
            raise SimulationTimeoutError(
                f"the simulation exceeded its wall-time bound of {self.limit:g} s ({where}); "
                "shorten the duration or raise max_seconds"
            )


class _TooManySteps(_core.Error):
    """scipy's RK45 reached :data:`SCIPY_MAX_EVALUATIONS` within one period (raised inside the
    right-hand side, caught by ``_advance`` and reported there as a diverging loop)."""


def _dahl_plant(robot: Robot, friction: bool, p_true, dahl_sigma):
    """``((sigma, Fc), plant parameters)`` of a plant with Dahl friction (its Coulomb column
    zero: the Dahl term ``Fc z`` replaces it), or ``(None, p_true)`` without ``dahl_sigma``."""
    if dahl_sigma is None:
        return None, p_true
    n = robot.n
    if not friction:
        raise _args.ArgumentError(
            "dahl_sigma: expected friction=True (the plant's Coulomb friction)"
        )
    if robot.friction_model["kind"] != "coulomb" or robot.drive_side == "motor":
        raise _args.ArgumentError(
            "dahl_sigma: the Dahl state replaces Coulomb friction on the joints; this robot has "
            f"the {robot.friction_model['kind']} friction model on its {robot.drive_side}s"
        )
    sigma = _args.array(dahl_sigma, "dahl_sigma", (None,) * np.ndim(dahl_sigma))
    sigma = np.array(np.broadcast_to(sigma, (n,))) if sigma.size in (1, n) else sigma
    if sigma.shape != (n,) or not np.all(sigma > 0):
        raise _args.ArgumentError("dahl_sigma: expected positive finite values, one per joint")
    p = np.array(p_true, dtype=float).reshape(n, -1)
    fc = p[:, 12].copy()  # per joint: 10 inertial, Ia, Fv, Fc
    p[:, 12] = 0.0
    return (sigma, fc), p.reshape(-1)


def _advance_dahl(plant, q, dq, z, tau, period, substeps, sigma, fc):
    """One period of the plant with Dahl friction: classical RK4, ``substeps`` steps, of
    ``(q, dq, z)`` with ``ddq = FD(q, dq, tau - Fc z)``, ``dz/dt = sigma (dq - z |dq|)``."""
    h = period / substeps

    def f(x):
        q, dq, z = x
        return (dq, plant.acceleration(q, dq, tau - fc * z), sigma * (dq - z * np.abs(dq)))

    x = (q, dq, z)
    for _ in range(substeps):
        k1 = f(x)
        k2 = f(tuple(a + h / 2 * b for a, b in zip(x, k1)))
        k3 = f(tuple(a + h / 2 * b for a, b in zip(x, k2)))
        k4 = f(tuple(a + h * b for a, b in zip(x, k3)))
        x = tuple(a + h / 6 * (b + 2 * c + 2 * d + e) for a, b, c, d, e in zip(x, k1, k2, k3, k4))
    if not all(np.all(np.isfinite(a)) for a in x):
        from .stability import UnstableLoopError

        raise UnstableLoopError("the integration diverged (non-finite state)")
    return x


def _advance(plant, q, dq, tau, period, substeps, integrator, budget=None):
    if budget is not None:
        budget.check("integration")
    if integrator == "rk4":
        return plant.step(q, dq, tau, period, substeps)
    from scipy.integrate import solve_ivp

    from .stability import UnstableLoopError

    n = q.shape[0]
    calls = [0]

    def f(_t, x):
        calls[0] += 1
        if calls[0] > SCIPY_MAX_EVALUATIONS:
            raise _TooManySteps
        if budget is not None and calls[0] % 256 == 0:
            budget.check("scipy RK45")
        return np.concatenate([x[n:], plant.acceleration(x[:n], x[n:], tau)])

    try:
        sol = solve_ivp(
            f, (0.0, period), np.concatenate([q, dq]), rtol=1e-8, atol=1e-10, t_eval=[period]
        )
    except _TooManySteps:
        raise UnstableLoopError(
            f"scipy RK45 needed more than {SCIPY_MAX_EVALUATIONS:,} evaluations within one "
            f"controller period of {period:g} s at t = {budget.t if budget else 0:.4f} s: the "
            "motion is stiff or the closed loop unstable (the rk4 integrator takes fixed steps)"
        ) from None
    if not sol.success:
        raise UnstableLoopError(f"the integrator failed: {sol.message}")
    x = sol.y[:, -1]
    if not np.all(np.isfinite(x)):
        raise UnstableLoopError("the integration diverged (non-finite state)")
    return x[:n], x[n:]


def _divergence_bound(robot: Robot, qd) -> np.ndarray:
    """The tracking error past which a loop counts as diverged, per joint: a full turn for a
    revolute joint, else the joint's range or 1 m, and at least four times the reference's
    own excursion."""
    lim = robot.limits
    span = np.where(np.isfinite(lim["upper"] - lim["lower"]), lim["upper"] - lim["lower"], 1.0)
    rev = np.array([t != "prismatic" for t in robot.joint_types])
    return np.maximum(np.where(rev, 2 * np.pi, span), 4.0 * np.ptp(qd, axis=0))


def _amount(robot: Robot, k: int, value: float) -> str:
    if robot.joint_types[k] == "prismatic":
        return f"{value:.4g} m"
    return f"{math.degrees(value):.4g} deg"


def _diverged(what: str, check):
    from .stability import UnstableLoopError

    if check is None:
        return UnstableLoopError(
            f"the closed loop diverged: {what}; lower the gains or the controller period"
        )
    return UnstableLoopError(f"the closed loop diverged: {what} ({check.text()}); {check.advice()}")


def _controller_torque(value, t: float, n: int) -> np.ndarray:
    """What a controller returned, as a float array (its shape checked by the caller)."""
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ArgumentError(
            f"the controller returned {_args.describe(value)} at t = {t:g} s; expected {n} torques"
        ) from None


def _plant_error(error: ValueError, t: float, q) -> Exception:
    """The simulated robot's error at ``t``: a mass matrix that is not positive definite is the
    true parameters' (an ArgumentError naming ``params``); any other is returned as it is."""
    if "not positive definite" not in str(error):
        return error
    return ArgumentError(
        f"params: the simulated robot's mass matrix is not positive definite at t = {t:g} s "
        f"(q = {np.round(q, 6).tolist()}); expected physically consistent parameters (positive "
        "masses, rotor inertias and link inertias)"
    )


def simulate_inverse(
    robot: Robot | str,
    reference,
    *,
    rate: float = 250.0,
    duration: float | None = None,
    rotor: bool = False,
    friction: bool = False,
    params=None,
    noise: SensorNoise | None = None,
    seed: int = 0,
    dahl_sigma=None,
) -> SimulationResult:
    """Open-loop: the motion is the reference, torques by inverse dynamics along it (true
    parameters), then measurement noise. Arguments as :func:`simulate`; with ``dahl_sigma`` the
    Dahl state follows the reference's positions sample by sample
    (:func:`~mindyn.identification.friction.dahl_state`, exact for a path straight between
    samples)."""
    robot = as_robot(robot)
    _args.protocol(reference, "reference", "evaluate", "a Reference (an object with evaluate(t))")
    rate = _args.number(rate, "rate", positive=True)
    duration = _args.optional(_args.number, duration, "duration", positive=True)
    rotor, friction = _args.flag(rotor, "rotor"), _args.flag(friction, "friction")
    params = _args.optional(_args.array, params, "params", (None,))
    _args.optional(_args.instance, noise, "noise", SensorNoise)
    seed = _args.integer(seed, "seed", 0)
    robot = load(robot)
    n = robot.n
    names, p_true = _true_params(robot, rotor, friction, params)
    dahl, p_plant = _dahl_plant(robot, friction, p_true, dahl_sigma)
    noise = noise or SensorNoise()
    arr = noise.arrays(n)
    rng = np.random.default_rng(seed)
    T = _span(reference, duration)
    m = check_steps(T, rate)
    t = np.arange(m) / rate
    t0 = time.perf_counter()
    q, dq, ddq = reference.evaluate(t)
    tau = robot.inverse_dynamics(q, dq, ddq, p_plant)
    states = None
    if dahl is not None:
        from ..identification.friction import dahl_state

        states = dahl_state(q, dahl[0])
        tau = tau + dahl[1] * states
    qm = noise.measure_q(q, rng, arr)
    dqm = dq + arr["velocity"] * rng.standard_normal(dq.shape)
    taum = tau + arr["torque"] * rng.standard_normal(tau.shape)
    info = {
        "mode": "inverse",
        "torque": "sampled",  # inverse dynamics at the samples
        "rate_Hz": rate,
        "duration_s": T,
        "rotor": rotor,
        "friction": friction,
        "drive_side": robot.drive_side,
        **drive_train_record(robot),
        "noise": {k: v.tolist() for k, v in arr.items()},
        "seed": seed,
        "max_tracking_error": [0.0] * n,
        "joint_types": list(robot.joint_types),
        "seconds": time.perf_counter() - t0,
    }
    if dahl is not None:
        info["dahl"] = {"sigma": dahl[0].tolist(), "state": "friction_state, 0 at the start"}
    return SimulationResult(
        t, qm, dqm, taum, q, dq, ddq, tau, q, dq, ddq, info, p_true, names, friction_state=states
    )


#: Largest noise levels :func:`noise_from_spec` accepts, per kind (SI units; torque noise in
#: percent at most 100 %): beyond them the "measurement" carries no information about the
#: motion or the torque.
NOISE_LIMITS = {"torque": 1e6, "position": 1.0, "velocity": 100.0, "quantization": 1.0}


#: An effort limit more than this many times the largest peak torque of any joint along the
#: reference is a placeholder (no joint of the robot comes near it: 1000 N m on a 2 kg leg)
EFFORT_PLACEHOLDER_ABOVE = 100.0
#: An effort limit below this fraction of its joint's own peak torque along the reference is a
#: placeholder too (the reference needs ten times the limit)
EFFORT_PLACEHOLDER_BELOW = 0.1


def torque_noise_scale(robot: Robot, reference_torque) -> tuple[np.ndarray, np.ndarray, str]:
    """Per joint, the torque a percentage of torque noise is taken of: the effort limit, or the
    peak of ``|reference_torque|`` (shape (m, n), the torques along the reference) where the
    description gives none (missing, zero, infinite) or a placeholder, one that no torque along
    the reference makes sense of: above :data:`EFFORT_PLACEHOLDER_ABOVE` x the largest peak
    torque of any joint, or below :data:`EFFORT_PLACEHOLDER_BELOW` x the joint's own. Returns the
    torques, per joint whether it is the effort limit, and what they are in words (``"P % of "``
    + words: ``"each joint's effort limit"``, or which joints take the peak torque and why)."""
    eff = np.array(robot.limits["effort"], dtype=float)
    tau = np.asarray(reference_torque, dtype=float)
    if tau.ndim != 2 or tau.shape[1] != robot.n or tau.shape[0] == 0:
        raise ArgumentError(f"reference_torque: expected shape (m, {robot.n}), got {tau.shape}")
    peak = np.abs(tau).max(0)
    top = float(peak.max())
    given = np.isfinite(eff) & (eff > 0)
    above = given & (eff > EFFORT_PLACEHOLDER_ABOVE * top)
    below = given & ~above & (eff < EFFORT_PLACEHOLDER_BELOW * peak)
    limited = given & ~above & ~below
    if limited.all():
        return eff, limited, "each joint's effort limit"
    reasons = []
    for mask, why in (
        (~given, "no effort limit"),
        (
            above,
            f"an effort limit over {EFFORT_PLACEHOLDER_ABOVE:g} x the largest peak torque, "
            f"{top:.3g} N m | N: a placeholder",
        ),
        (
            below,
            f"an effort limit under {EFFORT_PLACEHOLDER_BELOW:g} x its peak torque: a placeholder",
        ),
    ):
        if mask.all():
            reasons.append(f"every joint ({why})")
        elif mask.any():
            reasons.append(
                f"joint(s) {', '.join(str(j + 1) for j in np.flatnonzero(mask))} ({why})"
            )
    words = "the peak torque along the reference for " + ", ".join(reasons)
    if limited.any():
        words = f"the effort limit, and of {words}"
    return np.where(limited, eff, peak), limited, words


def _at_least_zero(what: str) -> str:
    if what == "quantization":
        return "an encoder step is a size, at least 0"
    return "a noise level is a standard deviation, at least 0"


def noise_from_spec(
    spec: str | None, robot: Robot, what: str, *, reference_torque=None
) -> np.ndarray:
    """Parses a noise level: ``"0.5"`` (all joints), ``"0.5,0.5,0.2"`` (per joint) or ``"1%"``
    (torque only: percent of each joint's effort limit, or of its peak torque along the
    reference where the description gives none or a placeholder, :func:`torque_noise_scale`;
    ``reference_torque`` (m, n), the torques along the reference, is then needed). Values must
    be finite, non-negative and at most :data:`NOISE_LIMITS` (percentages at most 100); a
    joint left with nothing to take a percentage of (no usable limit, no torque) is refused."""
    n = robot.n
    opt = "quantization=" if what == "quantization" else f"{what}_noise="
    if spec is None:
        return np.zeros(n)
    s = spec.strip()
    if s.endswith("%"):
        if what != "torque":
            raise ArgumentError(f"{opt}: a percentage applies to torque noise only")
        try:
            pct = float(s[:-1])
        except ValueError:
            pct = math.nan
        if pct < 0:
            raise ArgumentError(f"{opt}: {s} is negative; {_at_least_zero(what)}")
        if not (math.isfinite(pct) and 0 <= pct <= 100):
            raise ArgumentError(f"{opt}: expected a percentage in [0, 100], got '{spec}'")
        if reference_torque is None:
            raise ArgumentError(
                "reference_torque: needed with torque noise in % (the effort limits are checked "
                "against the torques along the reference, which stand in for missing ones)",
            )
        scale, _, words = torque_noise_scale(robot, reference_torque)
        # a peak torque at the round-off of the largest one is no torque
        top = float(np.abs(np.asarray(reference_torque, dtype=float)).max())
        empty = ~(np.isfinite(scale) & (scale > 1e-12 * top))
        if empty.any():
            none = ", ".join(str(j + 1) for j in np.flatnonzero(empty))
            raise ArgumentError(
                f"{opt}: {s} of nothing for joint(s) {none}, which have no usable effort limit "
                f"and no torque along the reference ({s} of {words}); give the noise in N m "
                "instead, one value or one per joint"
            )
        return pct / 100.0 * scale
    parts = s.split(",")
    try:  # an empty value or entry is no level (never read as 0)
        vals = [float(v) for v in parts] if all(v.strip() for v in parts) else None
    except ValueError:
        vals = None
    if vals is None:
        raise ArgumentError(
            f"{opt}: expected a number, or one per joint separated by commas"
            + (", or a percentage P%" if what == "torque" else "")
            + f"; got '{spec}'"
        ) from None
    negative = [k for k, v in enumerate(vals) if v < 0]
    if negative:
        k = negative[0]
        where = f" (joint {k + 1})" if len(vals) > 1 else ""
        raise ArgumentError(f"{opt}: {parts[k].strip()}{where} is negative; {_at_least_zero(what)}")
    if len(vals) == 1:
        vals = vals * n
    if len(vals) != n:
        raise ArgumentError(f"{opt}: {len(vals)} values for {n} joints")
    top = NOISE_LIMITS[what]
    if any(not (math.isfinite(v) and 0 <= v <= top) for v in vals):
        raise ArgumentError(f"{opt}: expected finite values in [0, {top:g}], got '{spec}'")
    return np.array(vals)


# ---------------------------------------------------------------------------------------------
# Report
# ---------------------------------------------------------------------------------------------
def display_scale(joint_types) -> np.ndarray:
    """Per joint, the factor from rad (m) to the unit position errors are shown in: degrees on
    revolute joints, millimetres on prismatic ones (as ``--tracking-tolerance`` takes them)."""
    return np.array([1e3 if t == "prismatic" else 180.0 / np.pi for t in joint_types])


def error_unit(joint_types) -> str:
    """The unit of :func:`display_scale`'s figures in a heading: ``deg``, ``deg | mm`` or
    ``mm``."""
    kinds = {"mm" if t == "prismatic" else "deg" for t in joint_types}
    return " | ".join(u for u in ("deg", "mm") if u in kinds)


def torque_unit(joint_types) -> str:
    """The unit of joint torques (forces on prismatic joints) in a heading: ``N m``,
    ``N m | N`` or ``N``."""
    kinds = {"N" if t == "prismatic" else "N m" for t in joint_types}
    return " | ".join(u for u in ("N m", "N") if u in kinds)


def summary(result: SimulationResult, *, cycle: float | None = None) -> dict:
    """Figures of a run: max / final / RMS-per-cycle position errors (deg; mm on prismatic
    joints, ``error_unit``), and for adaptive runs
    the torque prediction error ``Y (p_hat - p)`` and the parameter error per cycle, and each
    base parameter's final relative error ``(p_hat - p) / |p|`` (None where ``p`` is zero)."""
    _args.instance(result, "result", SimulationResult)
    cycle = _args.optional(_args.number, cycle, "cycle", positive=True)
    T = result.t[-1] + result.period
    cycle = cycle if cycle else T
    edges = np.arange(0.0, T + 1e-9, cycle)
    if edges[-1] < T - 1e-9:
        edges = np.append(edges, T)
    out = {
        "controller": result.controller,
        "period_s": result.period,
        "duration_s": float(T),
        "max_error_deg": result.max_error_deg().tolist(),
        "final_error_deg": result.final_error_deg().tolist(),
        "cycle_s": cycle,
        "error_unit": error_unit(result.info.get("joint_types") or ["revolute"]),
        "rms_error_deg_per_cycle": [
            result.rms_error_deg(a, b).tolist() for a, b in zip(edges[:-1], edges[1:])
        ],
        "max_error_deg_per_cycle": [
            (
                result.display_scale
                * np.abs(result.error[(result.t >= a) & (result.t < b)]).max(axis=0)
            ).tolist()
            for a, b in zip(edges[:-1], edges[1:])
        ],
        "saturated_fraction": float(result.saturated.mean()) if result.saturated is not None else 0,
    }
    if "unread_transmissions" in result.info:  # the simulated robot's drive train as assumed
        out["unread_transmissions"] = result.info["unread_transmissions"]
    if result.tau_true_model is not None:
        d = result.tau_model - result.tau_true_model
        out["torque_prediction_rms_per_cycle"] = [
            np.sqrt(np.mean(d[(result.t >= a) & (result.t < b)] ** 2, axis=0)).tolist()
            for a, b in zip(edges[:-1], edges[1:])
        ]
    if result.p_hat is not None and result.p_true is not None:
        err = result.p_hat - result.p_true
        # a true value of zero (friction of a robot without it) has no relative error: None
        zero = np.abs(result.p_true) <= 1e-12 * max(float(np.abs(result.p_true).max()), 1e-300)
        relative = np.where(zero, np.nan, err[-1] / np.where(zero, 1.0, np.abs(result.p_true)))
        idx = [min(int(round(b / result.period)), len(result.t) - 1) for b in edges]
        out["parameter_error_norm"] = [float(np.linalg.norm(err[i])) for i in idx]
        out["parameter_error_at_s"] = [float(result.t[i]) for i in idx]
        out["final_parameter_relative_error"] = dict(
            zip(result.base_names, [None if zero[i] else float(v) for i, v in enumerate(relative)])
        )
    return out


def write_tracking_report(
    result: SimulationResult,
    folder: str | Path,
    *,
    cycle: float | None = None,
    header: dict | None = None,
) -> dict:
    """Writes ``summary.json``, ``log.csv`` and plots (``tracking_error.png``, ``torque.png``,
    and for adaptive runs ``parameters.png``: the estimates' errors, the adapted model's torque
    prediction error and both per cycle) into ``folder``. Returns the summary."""
    _args.instance(result, "result", SimulationResult)
    _args.path(folder, "folder")
    cycle = _args.optional(_args.number, cycle, "cycle", positive=True)
    _args.optional(_args.mapping, header, "header")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    s = dict(header or {})
    s.update(summary(result, cycle=cycle))
    (folder / "summary.json").write_text(json.dumps(s, indent=2) + "\n")

    n = result.q.shape[1]
    cols = ["t"] + [f"{p}{k + 1}" for p in ("q", "qd", "tau") for k in range(n)]
    data = np.column_stack([result.t, result.q_true, result.qd, result.tau_true])
    np.savetxt(folder / "log.csv", data, delimiter=",", header=",".join(cols), comments="")

    def per_joint(draw, title: str, name: str, legend: bool = False) -> None:
        rows = math.ceil(n / 2)
        fig, axes = plt.subplots(rows, 2, figsize=(11, 2.4 * rows), sharex=True, squeeze=False)
        for k in range(n):
            ax = axes[k // 2][k % 2]
            draw(ax, k)
            ax.grid(alpha=0.3)
        if legend:
            axes[0][0].legend(fontsize=7)
        for ax in axes[-1]:
            ax.set_xlabel("t [s]")
        fig.suptitle(f"{result.controller}: {title}")
        fig.tight_layout()
        fig.savefig(folder / name, dpi=110)
        plt.close(fig)

    scale = result.display_scale

    def error(ax, k):
        ax.plot(result.t, scale[k] * result.error[:, k], lw=0.8)
        ax.set_ylabel(f"e{k + 1} [{'mm' if scale[k] == 1e3 else 'deg'}]")

    def torque(ax, k):
        ax.plot(result.t, result.tau_true[:, k], lw=0.8, label="applied")
        if result.tau_model is not None and np.all(np.isfinite(result.tau_model[:, k])):
            ax.plot(result.t, result.tau_model[:, k], lw=0.8, label="model (estimate)")
        if result.tau_true_model is not None:
            ax.plot(result.t, result.tau_true_model[:, k], lw=0.8, ls="--", label="model (true)")
        ax.set_ylabel(f"tau{k + 1} [N m]")

    per_joint(error, "position error q - q_d", "tracking_error.png")
    per_joint(torque, "joint torques", "torque.png", legend=True)

    # an adaptive run's estimates (a fixed model, computed torque's, has no history to plot)
    if result.p_hat is not None and result.p_true is not None and result.tau_true_model is not None:
        fig, ax = plt.subplots(3, 1, figsize=(10, 10))
        scale = np.maximum(np.abs(result.p_true), 1e-2 * np.abs(result.p_true).max())
        ax[0].plot(result.t, (result.p_hat - result.p_true) / scale, lw=0.6)
        ax[0].set_ylabel("(p_hat - p) / max(|p|, 1% max|p|)")
        ax[0].set_title("base-parameter estimates: error, one line per parameter")
        ax[0].grid(alpha=0.3)
        d = result.tau_model - result.tau_true_model
        for k in range(n):
            ax[1].plot(result.t, d[:, k], lw=0.6, label=f"joint {k + 1}")
        ax[1].set_ylabel("Y (p_hat - p) [N m]")
        ax[1].set_title("torque prediction error of the adapted model")
        ax[1].legend(fontsize=7, ncol=3)
        ax[1].grid(alpha=0.3)
        ax[1].set_xlabel("t [s]")
        k = np.arange(1, len(s["rms_error_deg_per_cycle"]) + 1)
        rms_e = [np.sqrt(np.mean(np.square(x))) for x in s["rms_error_deg_per_cycle"]]
        rms_t = [np.sqrt(np.mean(np.square(x))) for x in s["torque_prediction_rms_per_cycle"]]
        ax[2].plot(k, rms_e, "o-", label=f"tracking error [{s['error_unit']}]")
        ax[2].set_ylabel(f"RMS tracking error [{s['error_unit']}]")
        ax[2].set_xlabel(f"cycle ({s['cycle_s']:g} s each)")
        tw = ax[2].twinx()
        tw.plot(k, rms_t, "s--", color="C3", label="torque prediction error [N m]")
        tw.set_ylabel("RMS |Y (p_hat - p)| [N m]")
        ax[2].set_title("per cycle, all joints")
        ax[2].grid(alpha=0.3)
        h1, l1 = ax[2].get_legend_handles_labels()
        h2, l2 = tw.get_legend_handles_labels()
        ax[2].legend(h1 + h2, l1 + l2, fontsize=8)
        ax[2].set_xticks(k)
        fig.tight_layout()
        fig.savefig(folder / "parameters.png", dpi=110)
        plt.close(fig)
    return s
