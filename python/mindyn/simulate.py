"""Simulation as the stand-in for a robot: what a joint controller would log along a reference.

Two modes:

``tracking`` (default)
    The robot (forward dynamics of the C++ core, true parameters, optionally with rotor inertia
    and friction) is integrated with fixed-step RK4 under a discrete-time controller that runs at
    the log rate (zero-order hold on the torque). The controller reads the *measured* joint state
    (quantised, noisy) and its torque is logged with torque-sensor noise added. The default
    controller is computed torque with PD on the reference (:class:`ComputedTorquePD`); any
    object with the :class:`Controller` call signature can be passed to
    :func:`simulate_tracking`.
``inverse``
    The reference itself is taken as the motion and the torques come from inverse dynamics
    along it (no controller, no integration); noise is added the same way.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

import numpy as np

from .identification.data import truth_path, write_csv
from .robot import Robot, load

__all__ = [
    "CONTROLLERS",
    "ComputedTorquePD",
    "Controller",
    "SensorNoise",
    "SimulationLog",
    "load_reference",
    "simulate",
    "simulate_inverse",
    "simulate_tracking",
]


class Controller(Protocol):
    """A discrete-time joint controller, called once per control period.

    ``q, dq`` are the measured joint state, ``q_d, dq_d, ddq_d`` the reference at time ``t``;
    all shape (n,). Returns the joint torque, shape (n,), held until the next call. A controller
    may keep and update internal state (e.g. parameter estimates) on each call."""

    def __call__(self, t: float, q, dq, q_d, dq_d, ddq_d) -> np.ndarray: ...


class ComputedTorquePD:
    """Computed torque with PD on the reference:
    ``tau = ID(q, dq, ddq_d + Kp (q_d - q) + Kd (dq_d - dq); params)``.

    ``params`` (any classical layout, default: the robot's with rotor inertia and friction) is the
    controller's model. Its Coulomb friction is compensated as a feedforward from the *reference*
    velocity, ``Fc sign(dq_d)`` (``Fc tanh(dq_d / coulomb_smoothing)`` when smoothing is set):
    switching on the measured velocity would chatter about zero speed. ``kp``, ``kd`` default to
    ``omega^2`` and ``2 omega`` per joint (critical damping at ``omega`` rad/s)."""

    name = "computed-torque"

    def __init__(
        self,
        robot: Robot,
        params=None,
        omega: float = 20.0,
        kp=None,
        kd=None,
        coulomb_smoothing: float = 0.0,
    ):
        self.robot = robot
        full = expand_params(robot.n, robot.parameters(True, True) if params is None else params)
        self.params, self.fc = split_coulomb(robot.n, full)
        self.eps = float(coulomb_smoothing)
        n = robot.n
        self.kp = np.broadcast_to(np.asarray(omega**2 if kp is None else kp, float), (n,))
        self.kd = np.broadcast_to(np.asarray(2 * omega if kd is None else kd, float), (n,))

    def __call__(self, t, q, dq, q_d, dq_d, ddq_d):
        v = ddq_d + self.kp * (q_d - q) + self.kd * (dq_d - dq)
        return self.robot.inverse_dynamics(q, dq, v, self.params) + coulomb(self.fc, dq_d, self.eps)


def split_coulomb(n: int, full: np.ndarray):
    """``(params with Fc = 0, Fc)`` from a 13 n vector."""
    p = full.reshape(n, 13).copy()
    fc = p[:, 12].copy()
    p[:, 12] = 0.0
    return p.reshape(-1), fc


def coulomb(fc: np.ndarray, dq: np.ndarray, eps: float) -> np.ndarray:
    """Coulomb friction torque ``Fc tanh(dq / eps)`` (``Fc sign(dq)`` for ``eps = 0``)."""
    return fc * (np.tanh(dq / eps) if eps > 0 else np.sign(dq))


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
            v = np.asarray(getattr(self, k), dtype=float)
            try:
                v = np.broadcast_to(v, (n,)).copy()
            except ValueError:
                raise ValueError(
                    f"{k} noise has shape {v.shape}; expected a scalar or ({n},)"
                ) from None
            if (v < 0).any() or not np.isfinite(v).all():
                raise ValueError(f"{k} noise must be finite and non-negative, got {v.tolist()}")
            out[k] = v
        return out

    def measure_q(self, q, rng, arr):
        step = arr["quantization"]
        qm = np.where(step > 0, np.round(q / np.where(step > 0, step, 1.0)) * step, q)
        return qm + arr["position"] * rng.standard_normal(q.shape)


@dataclass
class SimulationLog:
    """What was logged and what was true.

    ``t`` (m,); ``q, dq, tau``: logged (measured) values, (m, n) each; ``q_true, dq_true,
    ddq_true, tau_true``: the true motion and applied torque at the log instants; ``q_ref``:
    the reference; ``info``: settings and figures (mode, rate, noise, tracking error)."""

    t: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    tau: np.ndarray
    q_true: np.ndarray
    dq_true: np.ndarray
    ddq_true: np.ndarray
    tau_true: np.ndarray
    q_ref: np.ndarray
    info: dict = field(default_factory=dict)
    params: np.ndarray | None = None
    param_names: list = field(default_factory=list)

    def save(self, path, robot_name: str = "") -> Path:
        """Writes ``t, q, dq, tau`` (the logged values) to ``path`` and the true parameters and
        settings to the sidecar ``<stem>.truth.json``."""
        path = write_csv(path, self.t, self.q, self.tau, dq=self.dq)
        truth = {
            "robot": robot_name,
            "names": self.param_names,
            "values": [float(v) for v in self.params],
            "simulation": self.info,
        }
        truth_path(path).write_text(json.dumps(truth, indent=2) + "\n")
        return path


def load_reference(path):
    """A reference trajectory from the JSON of ``mindyn excite`` (exact Fourier series) or from a
    CSV ``t, q, [dq], [ddq]`` (interpolated by cubic splines; missing derivatives obtained from
    the positions)."""
    from .identification.data import read_csv
    from .identification.excitation import FourierTrajectory

    p = Path(path)
    if p.suffix.lower() == ".json":
        return FourierTrajectory.load(p)
    return read_csv(p, require_torque=False, filter="none")


def _true_params(robot: Robot, rotor: bool, friction: bool, params=None):
    names = robot.parameter_names(True, True)
    if params is None:
        p = robot.parameters(True, True).reshape(robot.n, 13).copy()
        if not rotor:
            p[:, 10] = 0.0
        if not friction:
            p[:, 11:] = 0.0
        params = p.reshape(-1)
    return names, expand_params(robot.n, params)


def expand_params(n: int, params) -> np.ndarray:
    """A classical vector of any layout (10 n, 11 n with Ia, 12 n with Fv Fc, 13 n with all)
    in the full 13 n layout, absent entries zero."""
    p = np.asarray(params, dtype=float).reshape(-1)
    per = p.shape[0] // n if n else 0
    if per * n != p.shape[0] or per not in (10, 11, 12, 13):
        raise ValueError(
            f"params has {p.shape[0]} entries; expected {10 * n}, {11 * n}, {12 * n} or {13 * n}"
        )
    if not np.isfinite(p).all():
        raise ValueError("params contains NaN or infinite values")
    blocks = p.reshape(n, per)
    out = np.zeros((n, 13))
    out[:, :10] = blocks[:, :10]
    if per in (11, 13):
        out[:, 10] = blocks[:, 10]
    if per in (12, 13):
        out[:, 11:] = blocks[:, -2:]
    return out.reshape(-1)


#: Most samples (control periods) one simulation may have: the logs are held in memory, about
#: 60 bytes per sample and joint (tracking) before they are written.
MAX_SAMPLES = 1_000_000
#: Most integration steps (samples x substeps) one simulation may take: about two minutes of
#: RK4 with the controller on a 6-joint robot (3 s per 100,000 steps measured).
MAX_STEPS = 4_000_000


def check_steps(duration: float, rate: float, substeps: int = 1) -> int:
    """Number of samples of a simulation of ``duration`` s at ``rate`` Hz with ``substeps``
    integration steps each; raises ValueError unless all are finite and positive and within
    :data:`MAX_SAMPLES` and :data:`MAX_STEPS` (the message gives the counts and the limits)."""
    duration, rate = float(duration), float(rate)
    if not (math.isfinite(duration) and duration > 0):
        raise ValueError(f"duration must be a positive number of seconds, got {duration:g}")
    if not (math.isfinite(rate) and rate > 0):
        raise ValueError(f"rate must be a positive number of Hz, got {rate:g}")
    if not substeps >= 1:
        raise ValueError(f"substeps must be at least 1, got {substeps}")
    samples = duration * rate
    if samples > MAX_SAMPLES or samples * substeps > MAX_STEPS:
        raise ValueError(
            f"{duration:g} s at {rate:g} Hz are {samples:.4g} samples"
            + (f" x {substeps} substeps = {samples * substeps:.4g} steps" if substeps > 1 else "")
            + f"; at most {MAX_SAMPLES:,} samples and {MAX_STEPS:,} integration steps are "
            "simulated (shorten the duration or lower the rate)"
        )
    return int(round(samples)) + 1


def _span(reference, duration):
    if duration is not None:
        return float(duration)
    for attr in ("period", "duration"):
        if hasattr(reference, attr):
            return float(getattr(reference, attr))
    raise ValueError("duration is needed for a reference without a period or duration")


def simulate_tracking(
    robot: Robot | str,
    reference,
    controller: Controller | None = None,
    rate: float = 250.0,
    duration: float | None = None,
    substeps: int = 4,
    rotor: bool = False,
    friction: bool = False,
    params=None,
    noise: SensorNoise | None = None,
    seed: int = 0,
    coulomb_smoothing: float = 0.0,
) -> SimulationLog:
    """Closed-loop simulation: the robot tracks ``reference`` under ``controller``.

    Parameters
    ----------
    robot : Robot or str
    reference
        Anything with ``evaluate(t) -> (q, dq, ddq)`` (each (m, n)) — a
        :class:`~mindyn.identification.excitation.FourierTrajectory` or
        :class:`~mindyn.identification.data.JointData`.
    controller : Controller, optional
        Default :class:`ComputedTorquePD` with the true parameters.
    rate : float
        Control and log rate [Hz] (default 250 Hz, a 4 ms period).
    duration : float, optional
        Default: the reference's period (or duration).
    substeps : int
        RK4 steps per control period.
    rotor, friction : bool
        Give the simulated robot its rotor inertia / friction (from the description).
    params : array, optional
        True classical parameters (any layout, e.g. 13 n with Ia, Fv, Fc per joint); overrides
        the above.
    noise : SensorNoise, optional
    seed : int
        Seed of the noise generator.
    coulomb_smoothing : float
        If positive, the simulated Coulomb friction is ``Fc tanh(dq / coulomb_smoothing)``
        [rad/s | m/s] instead of ``Fc sign(dq)`` (plant and default controller).
    """
    robot = load(robot)
    n = robot.n
    names, p_true = _true_params(robot, rotor, friction, params)
    if controller is None:
        controller = ComputedTorquePD(robot, p_true, coulomb_smoothing=coulomb_smoothing)
    noise = noise or SensorNoise()
    arr = noise.arrays(n)
    rng = np.random.default_rng(seed)
    T = _span(reference, duration)
    m = check_steps(T, rate, substeps)
    t = np.arange(m) / rate
    q_ref, dq_ref, ddq_ref = reference.evaluate(t)
    h = 1.0 / (rate * substeps)
    fd = robot._m.forward_dynamics
    p_plant, fc = split_coulomb(n, p_true)
    eps = float(coulomb_smoothing)

    def f(q, dq, tau):
        return fd(q, dq, tau - coulomb(fc, dq, eps), p_plant)

    q, dq = q_ref[0].copy(), dq_ref[0].copy()
    out = {k: np.empty((m, n)) for k in ("q", "dq", "ddq", "tau", "qm", "dqm", "taum")}
    t0 = time.perf_counter()
    for i in range(m):
        qm = noise.measure_q(q, rng, arr)
        dqm = dq + arr["velocity"] * rng.standard_normal(n)
        tau = np.asarray(controller(t[i], qm, dqm, q_ref[i], dq_ref[i], ddq_ref[i]), float)
        if tau.shape != (n,) or not np.isfinite(tau).all():
            raise ValueError(
                f"controller returned {tau!r} at t = {t[i]:g}; expected {n} finite torques"
            )
        ddq = f(q, dq, tau)
        out["q"][i], out["dq"][i], out["ddq"][i], out["tau"][i] = q, dq, ddq, tau
        out["qm"][i], out["dqm"][i] = qm, dqm
        out["taum"][i] = tau + arr["torque"] * rng.standard_normal(n)
        if i == m - 1:
            break
        for _ in range(substeps):  # RK4 with the torque held
            k1v = ddq
            k1q = dq
            q2, dq2 = q + 0.5 * h * k1q, dq + 0.5 * h * k1v
            k2v = f(q2, dq2, tau)
            q3, dq3 = q + 0.5 * h * dq2, dq + 0.5 * h * k2v
            k3v = f(q3, dq3, tau)
            q4, dq4 = q + h * dq3, dq + h * k3v
            k4v = f(q4, dq4, tau)
            q = q + h / 6.0 * (k1q + 2 * dq2 + 2 * dq3 + dq4)
            dq = dq + h / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v)
            ddq = f(q, dq, tau)
    err = out["q"] - q_ref
    info = {
        "mode": "tracking",
        "controller": getattr(controller, "name", type(controller).__name__),
        "rate_Hz": rate,
        "substeps": substeps,
        "integrator": "RK4, torque held over each control period",
        "duration_s": T,
        "rotor": rotor,
        "friction": friction,
        "coulomb_smoothing": eps,
        "noise": {k: v.tolist() for k, v in arr.items()},
        "seed": seed,
        "max_tracking_error": np.abs(err).max(0).tolist(),
        "seconds": time.perf_counter() - t0,
    }
    return SimulationLog(
        t,
        out["qm"],
        out["dqm"],
        out["taum"],
        out["q"],
        out["dq"],
        out["ddq"],
        out["tau"],
        q_ref,
        info,
        p_true,
        names,
    )


def simulate_inverse(
    robot: Robot | str,
    reference,
    rate: float = 250.0,
    duration: float | None = None,
    rotor: bool = False,
    friction: bool = False,
    params=None,
    noise: SensorNoise | None = None,
    seed: int = 0,
) -> SimulationLog:
    """Open-loop: the motion is the reference, torques by inverse dynamics along it (true
    parameters), then measurement noise. Arguments as :func:`simulate_tracking`."""
    robot = load(robot)
    n = robot.n
    names, p_true = _true_params(robot, rotor, friction, params)
    noise = noise or SensorNoise()
    arr = noise.arrays(n)
    rng = np.random.default_rng(seed)
    T = _span(reference, duration)
    m = check_steps(T, rate)
    t = np.arange(m) / rate
    t0 = time.perf_counter()
    q, dq, ddq = reference.evaluate(t)
    tau = robot.inverse_dynamics(q, dq, ddq, p_true)
    qm = noise.measure_q(q, rng, arr)
    dqm = dq + arr["velocity"] * rng.standard_normal(dq.shape)
    taum = tau + arr["torque"] * rng.standard_normal(tau.shape)
    info = {
        "mode": "inverse",
        "rate_Hz": rate,
        "duration_s": T,
        "rotor": rotor,
        "friction": friction,
        "noise": {k: v.tolist() for k, v in arr.items()},
        "seed": seed,
        "max_tracking_error": [0.0] * n,
        "seconds": time.perf_counter() - t0,
    }
    return SimulationLog(t, qm, dqm, taum, q, dq, ddq, tau, q, info, p_true, names)


# Tracking controllers selectable by name (``mindyn simulate --controller NAME``): a factory
# ``(robot, cli_args) -> Controller or None`` (None: the default computed-torque controller with
# the simulated robot's true parameters).
CONTROLLERS = {
    "computed-torque": lambda robot, args=None: None,
}


def simulate(robot, reference, mode: str = "tracking", **kwargs) -> SimulationLog:
    """:func:`simulate_tracking` (``mode="tracking"``) or :func:`simulate_inverse`."""
    if mode == "tracking":
        return simulate_tracking(robot, reference, **kwargs)
    if mode == "inverse":
        kwargs.pop("controller", None)
        kwargs.pop("substeps", None)
        return simulate_inverse(robot, reference, **kwargs)
    raise ValueError(f"unknown simulation mode '{mode}'; use tracking or inverse")


#: Largest noise levels :func:`noise_from_spec` accepts, per kind (SI units; torque noise in
#: percent at most 100 %): beyond them the "measurement" carries no information about the
#: motion or the torque.
NOISE_LIMITS = {"torque": 1e6, "position": 1.0, "velocity": 100.0, "quantization": 1.0}


def noise_from_spec(spec: str | None, robot: Robot, what: str, reference_torque=None) -> np.ndarray:
    """Parses a noise level: ``"0.5"`` (all joints), ``"0.5,0.5,0.2"`` (per joint) or ``"1%"``
    (torque only: percent of each joint's effort limit, or of the peak reference torque where
    the description gives no effort limit). Values must be finite, non-negative and at most
    :data:`NOISE_LIMITS` (percentages at most 100)."""
    n = robot.n
    opt = "--quantization" if what == "quantization" else f"--{what}-noise"
    if spec is None or spec == "":
        return np.zeros(n)
    s = spec.strip()
    if s.endswith("%"):
        if what != "torque":
            raise ValueError(f"{opt}: a percentage applies to torque noise only")
        try:
            pct = float(s[:-1])
        except ValueError:
            pct = math.nan
        if not (math.isfinite(pct) and 0 <= pct <= 100):
            raise ValueError(f"{opt}: expected a percentage in [0, 100], got '{spec}'")
        eff = np.array(robot.limits["effort"], dtype=float)
        if reference_torque is not None:
            peak = np.abs(np.asarray(reference_torque)).max(0)
            eff = np.where(np.isfinite(eff) & (eff > 0), eff, peak)
        if not np.isfinite(eff).all():
            raise ValueError("torque noise in %: the robot has no effort limits")
        return pct / 100.0 * eff
    try:
        vals = [float(v) for v in s.split(",")]
    except ValueError:
        raise ValueError(f"{opt}: '{spec}' is not a number or list of numbers") from None
    if len(vals) == 1:
        vals = vals * n
    if len(vals) != n:
        raise ValueError(f"{opt}: {len(vals)} values for {n} joints")
    top = NOISE_LIMITS[what]
    if any(not (math.isfinite(v) and 0 <= v <= top) for v in vals):
        raise ValueError(f"{opt}: expected finite values in [0, {top:g}], got '{spec}'")
    return np.array(vals)
