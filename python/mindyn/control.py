"""Joint-space tracking control in closed-loop simulation.

Controllers (all sampled at their own period, torque held in between):

- :class:`AdaptivePD`: the Slotine-Li adaptive controller on the base parameters (method.md §7).
  Sign convention (the one used everywhere here)::

      e = q - q_d                 s = dq - dq_r = de + Lambda e
      dq_r = dq_d - Lambda e      ddq_r = ddq_d - Lambda de
      tau = Y(q, dq, dq_r, ddq_r) p_hat - K_D s
      dp_hat/dt = -Gamma Y^T s / (1 + nu |Y|^2)     (explicit Euler over one period)

  with ``Y p = A(q) ddq_r + C(q, dq) dq_r + c(q) (+ Fv dq + Fc sign dq)`` the Slotine-Li regressor
  (:func:`slotine_li_regressor`); ``K_P = Lambda K_D``. ``nu = 0`` is the Slotine-Li law; ``nu > 0``
  normalises the step by the squared Frobenius norm of ``Y`` (normalised gradient), which bounds
  the change of the estimate per period by ``T Gamma |s| / (nu |Y|)`` and keeps large adaptation
  gains usable at a slow controller rate (plain Euler steps diverge there).
- :class:`ComputedTorque`: ``tau = W_b(q, dq, ddq_d - K_D de - K_P e) p_hat`` with fixed
  parameters.
- :class:`PD`: ``tau = -K_P e - K_D de``.

:func:`simulate` integrates the true robot (classical parameters with rotor inertia and friction)
with fixed Runge-Kutta steps (C++) or scipy's adaptive ``solve_ivp`` and runs the controller every
``period`` seconds with zero-order hold, optional sensor noise and torque limits.
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from . import _args, _core
from .base import BaseParameters, base_parameters
from .robot import Robot

__all__ = [
    "AdaptivePD",
    "ComputedTorque",
    "CsvTrajectory",
    "PD",
    "ZCR07S_STUDY_GAINS",
    "SimulationResult",
    "SumOfSines",
    "coriolis_matrix",
    "default_gains",
    "load_gains",
    "perturbed_parameters",
    "simulate",
    "slotine_li_regressor",
    "write_report",
]

#: The ZCR07S study's gains for the ZCR07S (joints 1-6), adaptation gains 1, period 4 ms.
ZCR07S_STUDY_GAINS = {
    "kd": [400.0, 350.0, 130.0, 22.0, 9.0, 2.0],
    "lambda": [10.0, 10.0, 10.0, 30.0, 30.0, 25.0],
    "gamma": 1.0,
}


# ---------------------------------------------------------------------------------------------
# Regressors
# ---------------------------------------------------------------------------------------------
def slotine_li_regressor(base: BaseParameters, q, dq, dqr, ddqr) -> np.ndarray:
    """Slotine-Li regressor in base parameters.

    ``Y_b(q, dq, dqr, ddqr) @ p_b = A(q) ddqr + C(q, dq) dqr + c(q)`` (plus ``Fv dq + Fc sign(dq)``
    when ``base`` includes friction), where ``C`` is the Coriolis matrix of the Christoffel symbols
    (``dA/dt - 2 C`` skew-symmetric) and ``p_b = base.values(params)``. With ``dqr = dq`` and
    ``ddqr = ddq`` it is the base regressor ``base.regressor(q, dq, ddq)``.

    Parameters
    ----------
    base : BaseParameters
        From :func:`mindyn.base_parameters`; its layout (rotor inertia, friction) is used.
    q, dq, dqr, ddqr : array_like, shape (n,) or (m, n)

    Returns
    -------
    ndarray, shape (n, base.n) or (m, n, base.n)
    """
    q, dq, dqr, ddqr = _args.batch(base.robot.n, q=q, dq=dq, dqr=dqr, ddqr=ddqr)
    return _core.slotine_li_regressor(base._b, q, dq, dqr, ddqr)


def slotine_li_regressor_classical(
    robot: Robot, q, dq, dqr, ddqr, rotor: bool = False, friction: bool = False
) -> np.ndarray:
    """Slotine-Li regressor in the classical layout, shape (n, P) or (m, n, P)."""
    q, dq, dqr, ddqr = _args.batch(robot.n, q=q, dq=dq, dqr=dqr, ddqr=ddqr)
    rotor, friction = _args.flag(rotor, "rotor"), _args.flag(friction, "friction")
    return _core.slotine_li_regressor_classical(robot._m, q, dq, dqr, ddqr, rotor, friction)


def coriolis_matrix(robot: Robot, q, dq, params=None) -> np.ndarray:
    """Coriolis matrix ``C(q, dq)`` of the Christoffel symbols, shape (n, n) or (m, n, n):
    ``C dq`` is the velocity-product torque and ``dA/dt - 2 C`` is skew-symmetric. ``params``: any
    classical layout (default the model's inertial parameters)."""
    q, dq = _args.batch(robot.n, q=q, dq=dq)
    return _core.coriolis_matrix(robot._m, q, dq, _args.params(params, "params", robot.n))


# ---------------------------------------------------------------------------------------------
# Reference trajectories: callables t -> (q_d, dq_d, ddq_d), each shape (n,)
# ---------------------------------------------------------------------------------------------
class SumOfSines:
    """A smooth periodic reference inside the joint limits:
    ``q_d,i(t) = c_i + a_i (sin(w t + phi_i) + 0.5 sin(2 w t + 2 phi_i) + 0.25 sin(3 w t))``
    with ``w = 2 pi / period``, ``c`` the middle of the limits and the amplitude ``a_i`` the
    largest that keeps ``q_d`` within ``fraction`` of the half range and ``|dq_d|`` within
    ``fraction`` of the velocity limit (joints without limits: half range pi/2, 1 rad/s)."""

    def __init__(self, robot: Robot, period: float = 10.0, fraction: float = 0.5, seed: int = 0):
        if not period > 0:
            raise ValueError(f"period must be positive, got {period}")
        if not 0 < fraction <= 1:
            raise ValueError(f"fraction must be in (0, 1], got {fraction}")
        lim = robot.limits
        lo = np.where(np.isfinite(lim["lower"]), lim["lower"], -np.pi / 2)
        hi = np.where(np.isfinite(lim["upper"]), lim["upper"], np.pi / 2)
        vmax = np.where(np.isfinite(lim["velocity"]), lim["velocity"], 1.0)
        self.n = robot.n
        self.period = float(period)
        self.w = 2 * np.pi / self.period
        self.center = 0.5 * (lo + hi)
        self.phase = np.random.default_rng(seed).uniform(0, 2 * np.pi, robot.n)
        # bounds of the unit shape: |sum| <= 1.75, |d/dt| <= w (1 + 1 + 0.75)
        amp_q = fraction * 0.5 * (hi - lo) / 1.75
        amp_v = fraction * vmax / (2.75 * self.w)
        self.amplitude = np.minimum(amp_q, amp_v)

    def __call__(self, t: float):
        w, p, a = self.w, self.phase, self.amplitude
        th = w * t
        s = np.sin(th + p) + 0.5 * np.sin(2 * th + 2 * p) + 0.25 * np.sin(3 * th)
        ds = w * (np.cos(th + p) + np.cos(2 * th + 2 * p) + 0.75 * np.cos(3 * th))
        dds = -(w**2) * (np.sin(th + p) + 2 * np.sin(2 * th + 2 * p) + 2.25 * np.sin(3 * th))
        return self.center + a * s, a * ds, a * dds


class CsvTrajectory:
    """A reference from a CSV file with columns ``t, q1..qN`` and optionally ``dq1..dqN`` and
    ``ddq1..ddqN`` (a header line is allowed). Positions are interpolated by cubic splines;
    missing velocities and accelerations are the spline's derivatives. After the last sample the
    reference holds the last position at rest."""

    def __init__(self, path: str | Path, n: int):
        from scipy.interpolate import CubicSpline

        path = Path(path)
        if not path.is_file():
            from . import RobotFileNotFoundError

            raise RobotFileNotFoundError(f"trajectory file '{path}' does not exist")
        rows: list[list[float]] = []
        with path.open(newline="") as f:
            for lineno, row in enumerate(csv.reader(f), 1):
                if not row or all(not c.strip() for c in row):
                    continue
                try:
                    rows.append([float(c) for c in row])
                except ValueError:
                    if rows or lineno > 1:
                        raise ValueError(
                            f"{path}:{lineno}: non-numeric value in a data line"
                        ) from None
                    continue  # header
        if len({len(r) for r in rows}) > 1:
            raise ValueError(f"{path}: rows have different numbers of columns")
        if len(rows) < 4:
            raise ValueError(f"{path}: need at least 4 samples, found {len(rows)}")
        data = np.array(rows, dtype=float)
        cols = data.shape[1]
        if cols not in (1 + n, 1 + 2 * n, 1 + 3 * n):
            raise ValueError(
                f"{path}: {cols} columns; expected t and q1..q{n} ({1 + n}), plus dq "
                f"({1 + 2 * n}) and ddq ({1 + 3 * n})"
            )
        if not np.all(np.isfinite(data)):
            raise ValueError(f"{path}: contains NaN or infinite values")
        t = data[:, 0]
        if np.any(np.diff(t) <= 0):
            raise ValueError(f"{path}: time column must be strictly increasing")
        self.n = n
        self.t0, self.t1 = float(t[0]), float(t[-1])
        self.duration = self.t1 - self.t0
        self._q = CubicSpline(t, data[:, 1 : 1 + n])
        self._dq = CubicSpline(t, data[:, 1 + n : 1 + 2 * n]) if cols >= 1 + 2 * n else None
        self._ddq = CubicSpline(t, data[:, 1 + 2 * n :]) if cols == 1 + 3 * n else None
        self._qend = data[-1, 1 : 1 + n]

    def __call__(self, t: float):
        t = self.t0 + t
        if t >= self.t1:
            return self._qend.copy(), np.zeros(self.n), np.zeros(self.n)
        q = self._q(t)
        dq = self._dq(t) if self._dq is not None else self._q(t, 1)
        ddq = self._ddq(t) if self._ddq is not None else self._q(t, 2)
        return q, dq, ddq


# ---------------------------------------------------------------------------------------------
# Controllers
# ---------------------------------------------------------------------------------------------
def _diag(x, n: int, name: str) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.ndim == 0:
        a = np.full(n, float(a))
    if a.shape != (n,):
        raise ValueError(f"gain '{name}' must be a scalar or {n} values, got shape {a.shape}")
    if not np.all(np.isfinite(a)) or np.any(a < 0):
        raise ValueError(f"gain '{name}' must be finite and non-negative")
    return a


class PD:
    """Plain PD: ``tau = -K_P e - K_D de`` (no model)."""

    name = "pd"

    def __init__(self, n: int, kp, kd):
        self.kp = _diag(kp, n, "kp")
        self.kd = _diag(kd, n, "kd")

    def reset(self) -> None:
        pass

    def __call__(self, t, q, dq, ref, dt):
        qd, dqd, _ = ref
        return -self.kp * (q - qd) - self.kd * (dq - dqd)


class ComputedTorque:
    """Computed torque with fixed base parameters ``p_hat``:
    ``tau = W_b(q, dq, ddq_d - K_D de - K_P e) p_hat``."""

    name = "computed-torque"

    def __init__(self, base: BaseParameters, p_hat, kp, kd):
        n = base.robot.n
        self.base = base
        self.p_hat = np.asarray(p_hat, dtype=float).copy()
        if self.p_hat.shape != (base.n,):
            raise ValueError(f"p_hat has shape {self.p_hat.shape}; expected ({base.n},)")
        self.kp = _diag(kp, n, "kp")
        self.kd = _diag(kd, n, "kd")

    def reset(self) -> None:
        pass

    def __call__(self, t, q, dq, ref, dt):
        qd, dqd, ddqd = ref
        v = ddqd - self.kd * (dq - dqd) - self.kp * (q - qd)
        self.model_torque = self.base.regressor(q, dq, v) @ self.p_hat
        return self.model_torque


class AdaptivePD:
    """Slotine-Li adaptive controller on the base parameters (sign convention in the module
    docstring).

    Parameters
    ----------
    base : BaseParameters
        The parameter set adapted (its layout decides whether rotor inertia and friction are).
    kd, lam : scalar or array of shape (n,)
        ``K_D`` and ``Lambda`` (diagonal).
    gamma : scalar or array of shape (base.n,)
        Adaptation gains (diagonal of ``Gamma``).
    p0 : array of shape (base.n,)
        Initial estimate.
    adapt : bool
        False freezes the estimate (the controller is then a PD plus model feedforward).
    nu : float
        Normalisation of the adaptation step (>= 0; 0: the plain Slotine-Li law).
    """

    name = "adaptive-pd"

    def __init__(
        self, base: BaseParameters, kd, lam, gamma, p0, adapt: bool = True, nu: float = 0.0
    ):
        n = base.robot.n
        self.base = base
        self.kd = _diag(kd, n, "kd")
        self.lam = _diag(lam, n, "lambda")
        self.gamma = _diag(gamma, base.n, "gamma")
        self.p0 = np.asarray(p0, dtype=float).copy()
        if self.p0.shape != (base.n,):
            raise ValueError(f"p0 has shape {self.p0.shape}; expected ({base.n},)")
        self.adapt = adapt
        self.nu = float(nu)
        if not (math.isfinite(self.nu) and self.nu >= 0):
            raise ValueError(f"nu must be a finite number >= 0, got {nu}")
        self.reset()

    def reset(self) -> None:
        self.p_hat = self.p0.copy()

    def terms(self, q, dq, ref):
        """``(e, s, dq_r, ddq_r)`` of the sign convention."""
        qd, dqd, ddqd = ref
        e = q - qd
        de = dq - dqd
        dqr = dqd - self.lam * e
        ddqr = ddqd - self.lam * de
        s = de + self.lam * e
        return e, s, dqr, ddqr

    def __call__(self, t, q, dq, ref, dt):
        _, s, dqr, ddqr = self.terms(q, dq, ref)
        Y = slotine_li_regressor(self.base, q, dq, dqr, ddqr)
        self.Y = Y
        self.model_torque = Y @ self.p_hat
        tau = self.model_torque - self.kd * s
        if self.adapt:
            step = dt * self.gamma * (Y.T @ s)
            if self.nu:
                step /= 1.0 + self.nu * float(np.sum(Y * Y))
            self.p_hat = self.p_hat - step
        return tau


# ---------------------------------------------------------------------------------------------
# Gains
# ---------------------------------------------------------------------------------------------
def default_gains(robot: Robot) -> dict:
    """The ZCR07S study's gains for ``zcr07s``; otherwise ``Lambda = 10``,
    ``K_D = 40 diag(A(q_mid))`` (``A`` with rotor inertia), adaptation gains 1. ``kp`` for PD is
    ``Lambda K_D``; computed torque uses ``K_P = Lambda^2``, ``K_D = 2 Lambda``."""
    if robot.name == "zcr07s" and robot.n == 6:
        g = {k: (list(v) if isinstance(v, list) else v) for k, v in ZCR07S_STUDY_GAINS.items()}
    else:
        lim = robot.limits
        lo = np.where(np.isfinite(lim["lower"]), lim["lower"], 0.0)
        hi = np.where(np.isfinite(lim["upper"]), lim["upper"], 0.0)
        A = robot.mass_matrix(0.5 * (lo + hi), robot.parameters(rotor=True))
        g = {"kd": list(40.0 * np.maximum(np.diag(A), 1e-3)), "lambda": [10.0] * robot.n}
        g["gamma"] = 1.0
    return g


def load_gains(path: str | Path, robot: Robot) -> dict:
    """Gains from a YAML file with keys ``kd``, ``lambda``, ``gamma``, ``nu`` (adaptation-step
    normalisation, a scalar), ``kp`` (scalars or lists; missing keys take :func:`default_gains`)."""
    import yaml

    path = Path(path)
    if not path.is_file():
        from . import RobotFileNotFoundError

        raise RobotFileNotFoundError(f"gains file '{path}' does not exist")
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as e:
        raise ValueError(f"{path}: not valid YAML ({e})") from None
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ValueError(f"{path}: expected a mapping with keys kd, lambda, gamma, nu, kp")
    unknown = set(data) - {"kd", "lambda", "gamma", "nu", "kp"}
    if unknown:
        raise ValueError(
            f"{path}: unknown key(s) {', '.join(sorted(unknown))}; "
            "expected kd, lambda, gamma, nu, kp"
        )
    gains = default_gains(robot)
    for key, value in data.items():
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"{path}: '{key}' must be a number or a list of numbers") from None
        if key == "nu" and (arr.ndim != 0 or not arr >= 0):
            raise ValueError(f"{path}: 'nu' must be one number >= 0")
        gains[key] = arr.tolist()
    return gains


def perturbed_parameters(p, fraction: float, seed: int = 0) -> np.ndarray:
    """``p * (1 + fraction * u)``, ``u`` uniform in [-1, 1] per entry (seeded)."""
    p = np.asarray(p, dtype=float)
    u = np.random.default_rng(seed).uniform(-1.0, 1.0, p.shape)
    return p * (1.0 + fraction * u)


# ---------------------------------------------------------------------------------------------
# Simulation
# ---------------------------------------------------------------------------------------------
@dataclass
class SimulationResult:
    """Time series at the controller samples (``K`` samples, ``n`` joints, ``nb`` base
    parameters).

    Attributes
    ----------
    t : (K,)  q, dq, qd, dqd, ddqd : (K, n) actual and reference motion (true, not noisy)
    tau : (K, n) applied torque (after limits)   tau_model : (K, n) model part of the controller
    (``Y p_hat`` or ``W_b p_hat``; NaN for PD)   tau_true_model : (K, n) the same with the true
    parameters (adaptive PD only)   p_hat : (K, nb) estimates (adaptive PD only)
    p_true : (nb,) true base parameters   saturated : (K, n) bool
    """

    controller: str
    period: float
    t: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    qd: np.ndarray
    dqd: np.ndarray
    ddqd: np.ndarray
    tau: np.ndarray
    tau_model: np.ndarray
    tau_true_model: np.ndarray | None = None
    p_hat: np.ndarray | None = None
    p_true: np.ndarray | None = None
    param_names: list[str] = field(default_factory=list)
    saturated: np.ndarray | None = None

    @property
    def error(self) -> np.ndarray:
        """Position error ``q - q_d``, shape (K, n), rad."""
        return self.q - self.qd

    def max_error_deg(self, t_from: float = 0.0) -> np.ndarray:
        """Largest ``|q - q_d|`` per joint in degrees, from ``t_from`` on."""
        sel = self.t >= t_from
        return np.degrees(np.abs(self.error[sel]).max(axis=0))

    def rms_error_deg(self, t0: float, t1: float) -> np.ndarray:
        """RMS position error per joint in degrees over ``t0 <= t < t1``."""
        sel = (self.t >= t0) & (self.t < t1)
        if not np.any(sel):
            raise ValueError(f"no samples in [{t0}, {t1})")
        return np.degrees(np.sqrt(np.mean(self.error[sel] ** 2, axis=0)))

    def final_error_deg(self) -> np.ndarray:
        """``q - q_d`` at the last sample, degrees."""
        return np.degrees(self.error[-1])


def simulate(
    robot: Robot,
    controller,
    reference: Callable[[float], tuple],
    duration: float,
    period: float = 0.004,
    *,
    true_params=None,
    substeps: int = 4,
    integrator: str = "rk4",
    noise: tuple[float, float] = (0.0, 0.0),
    torque_limit=None,
    seed: int = 0,
    base: BaseParameters | None = None,
) -> SimulationResult:
    """Closed-loop simulation of ``robot`` under ``controller`` following ``reference``.

    Parameters
    ----------
    robot : Robot
    controller : PD, ComputedTorque or AdaptivePD (any callable
        ``(t, q, dq, (q_d, dq_d, ddq_d), period) -> tau`` with ``reset()``)
    reference : callable ``t -> (q_d, dq_d, ddq_d)``, each shape (n,)
    duration, period : float
        Simulated time and controller period [s]; the robot starts on the reference at t = 0.
    true_params : array, optional
        Classical parameters of the simulated robot in any layout (default: the model's with
        rotor inertia and friction, ``robot.parameters(True, True)``).
    substeps : int
        RK4 steps per controller period (``integrator="rk4"``).
    integrator : {"rk4", "scipy"}
        Fixed-step RK4 (C++) or scipy's adaptive RK45 per period (rtol 1e-8).
    noise : (sigma_q, sigma_dq)
        Standard deviations of white Gaussian noise on the measured q [rad] and dq [rad/s].
    torque_limit : None, "effort" or array (n,)
        Saturation of the applied torque (``"effort"``: the model's effort limits).
    base : BaseParameters, optional
        Used to report the true base parameters and the true model torque next to the estimates
        (default: the controller's).
    """
    if not (math.isfinite(duration) and duration > 0 and math.isfinite(period) and period > 0):
        raise ValueError(
            f"duration and period must be positive numbers of seconds, got {duration:g} and "
            f"{period:g}"
        )
    if duration < period:
        raise ValueError(f"duration {duration} s is shorter than one period {period} s")
    if integrator not in ("rk4", "scipy"):
        raise ValueError(f"integrator must be 'rk4' or 'scipy', got '{integrator}'")
    if substeps < 1:
        raise ValueError("substeps must be at least 1")
    from .simulate import check_steps

    check_steps(duration, 1.0 / period, substeps if integrator == "rk4" else 1)
    n = robot.n
    p_true = robot.parameters(True, True) if true_params is None else np.asarray(true_params)
    limit = None
    if isinstance(torque_limit, str):
        if torque_limit != "effort":
            raise ValueError(f"torque_limit must be None, 'effort' or {n} values")
        limit = robot.limits["effort"]
        if not np.all(np.isfinite(limit)):
            raise ValueError(f"robot '{robot.name}' does not give effort limits for all joints")
    elif torque_limit is not None:
        limit = _diag(torque_limit, n, "torque_limit")
    sq, sdq = (float(x) for x in noise)
    rng = np.random.default_rng(seed)
    base = base if base is not None else getattr(controller, "base", None)
    pb_true = None
    if base is not None and len(p_true) == len(base.classical_names):
        pb_true = base.values(p_true)

    K = int(round(duration / period))
    t = np.arange(K) * period
    Q, DQ, QD, DQD, DDQD, TAU, TAUM = (np.zeros((K, n)) for _ in range(7))
    TAUT = np.full((K, n), np.nan)
    SAT = np.zeros((K, n), dtype=bool)
    adaptive = isinstance(controller, AdaptivePD)
    PH = np.zeros((K, controller.base.n)) if adaptive else None

    controller.reset()
    q, dq, _ = reference(0.0)
    q, dq = np.array(q, dtype=float), np.array(dq, dtype=float)
    # A diverging loop shows as a non-finite torque, reported as such (not as warnings).
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        for i in range(K):
            ref = reference(t[i])
            qm = q + (rng.normal(0.0, sq, n) if sq > 0 else 0.0)
            dqm = dq + (rng.normal(0.0, sdq, n) if sdq > 0 else 0.0)
            tau = np.asarray(controller(t[i], qm, dqm, ref, period), dtype=float)
            if not np.all(np.isfinite(tau)):
                raise ValueError(
                    f"the controller returned a non-finite torque at t = {t[i]:.4f} s: the "
                    "closed loop diverged (gains, controller period or reference speed)"
                )
            if limit is not None:
                SAT[i] = np.abs(tau) > limit
                tau = np.clip(tau, -limit, limit)
            Q[i], DQ[i] = q, dq
            QD[i], DQD[i], DDQD[i] = ref
            TAU[i] = tau
            TAUM[i] = getattr(controller, "model_torque", np.full(n, np.nan))
            if adaptive:
                PH[i] = controller.p_hat
                if pb_true is not None:
                    TAUT[i] = controller.Y @ pb_true
            q, dq = _advance(robot, q, dq, tau, period, substeps, integrator, p_true)
    return SimulationResult(
        controller=getattr(controller, "name", type(controller).__name__),
        period=period,
        t=t,
        q=Q,
        dq=DQ,
        qd=QD,
        dqd=DQD,
        ddqd=DDQD,
        tau=TAU,
        tau_model=TAUM,
        tau_true_model=TAUT if adaptive and pb_true is not None else None,
        p_hat=PH,
        p_true=pb_true,
        param_names=list(base.names) if base is not None else [],
        saturated=SAT,
    )


def _advance(robot, q, dq, tau, period, substeps, integrator, params):
    if integrator == "rk4":
        return _core.integrate_rk4(robot._m, q, dq, tau, period, substeps, params)
    from scipy.integrate import solve_ivp

    n = robot.n

    def f(_t, x):
        return np.concatenate([x[n:], robot.forward_dynamics(x[:n], x[n:], tau, params)])

    sol = solve_ivp(f, (0.0, period), np.concatenate([q, dq]), rtol=1e-8, atol=1e-10)
    if not sol.success:
        raise ValueError(f"the integrator failed: {sol.message}")
    x = sol.y[:, -1]
    return x[:n], x[n:]


# ---------------------------------------------------------------------------------------------
# Report
# ---------------------------------------------------------------------------------------------
def summary(result: SimulationResult, cycle: float | None = None) -> dict:
    """Figures of a run: max / final / RMS-per-cycle position errors (deg), and for adaptive runs
    the torque prediction error ``Y (p_hat - p)`` and the parameter error per cycle."""
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
        "rms_error_deg_per_cycle": [
            result.rms_error_deg(a, b).tolist() for a, b in zip(edges[:-1], edges[1:])
        ],
        "max_error_deg_per_cycle": [
            np.degrees(np.abs(result.error[(result.t >= a) & (result.t < b)]).max(axis=0)).tolist()
            for a, b in zip(edges[:-1], edges[1:])
        ],
        "saturated_fraction": float(result.saturated.mean()) if result.saturated is not None else 0,
    }
    if result.tau_true_model is not None:
        d = result.tau_model - result.tau_true_model
        out["torque_prediction_rms_per_cycle"] = [
            np.sqrt(np.mean(d[(result.t >= a) & (result.t < b)] ** 2, axis=0)).tolist()
            for a, b in zip(edges[:-1], edges[1:])
        ]
    if result.p_hat is not None and result.p_true is not None:
        err = result.p_hat - result.p_true
        scale = np.maximum(np.abs(result.p_true), 1e-9)
        idx = [min(int(round(b / result.period)), len(result.t) - 1) for b in edges]
        out["parameter_error_norm"] = [float(np.linalg.norm(err[i])) for i in idx]
        out["parameter_error_at_s"] = [float(result.t[i]) for i in idx]
        out["final_parameter_relative_error"] = dict(
            zip(result.param_names, (err[-1] / scale).tolist())
        )
    return out


def write_report(
    result: SimulationResult,
    folder: str | Path,
    cycle: float | None = None,
    header: dict | None = None,
) -> dict:
    """Writes ``summary.json``, ``log.csv`` and plots (``tracking_error.png``, ``torque.png``,
    and for adaptive runs ``parameters.png``, ``torque_prediction.png``) into ``folder``.
    Returns the summary."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    s = dict(header or {})
    s.update(summary(result, cycle))
    (folder / "summary.json").write_text(json.dumps(s, indent=2) + "\n")

    n = result.q.shape[1]
    cols = ["t"] + [f"{p}{k + 1}" for p in ("q", "qd", "tau") for k in range(n)]
    data = np.column_stack([result.t, result.q, result.qd, result.tau])
    np.savetxt(folder / "log.csv", data, delimiter=",", header=",".join(cols), comments="")

    rows = math.ceil(n / 2)
    fig, axes = plt.subplots(rows, 2, figsize=(11, 2.4 * rows), sharex=True, squeeze=False)
    for k in range(n):
        ax = axes[k // 2][k % 2]
        ax.plot(result.t, np.degrees(result.error[:, k]), lw=0.8)
        ax.set_ylabel(f"e{k + 1} [deg]")
        ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    fig.suptitle(f"{result.controller}: position error q - q_d")
    fig.tight_layout()
    fig.savefig(folder / "tracking_error.png", dpi=110)
    plt.close(fig)

    fig, axes = plt.subplots(rows, 2, figsize=(11, 2.4 * rows), sharex=True, squeeze=False)
    for k in range(n):
        ax = axes[k // 2][k % 2]
        ax.plot(result.t, result.tau[:, k], lw=0.8, label="applied")
        if np.all(np.isfinite(result.tau_model[:, k])):
            ax.plot(result.t, result.tau_model[:, k], lw=0.8, label="model (estimate)")
        if result.tau_true_model is not None:
            ax.plot(result.t, result.tau_true_model[:, k], lw=0.8, ls="--", label="model (true)")
        ax.set_ylabel(f"tau{k + 1} [N m]")
        ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    fig.suptitle(f"{result.controller}: joint torques")
    fig.tight_layout()
    fig.savefig(folder / "torque.png", dpi=110)
    plt.close(fig)

    if result.p_hat is not None and result.p_true is not None:
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
        ax[2].plot(k, rms_e, "o-", label="tracking error [deg]")
        ax[2].set_ylabel("RMS tracking error [deg]")
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


def make_controller(
    kind: str,
    robot: Robot,
    gains: dict,
    p_hat=None,
    base: BaseParameters | None = None,
):
    """A controller by name (``adaptive-pd``, ``computed-torque``, ``pd``) with ``gains`` as from
    :func:`default_gains` / :func:`load_gains`. ``base`` defaults to the base parameters with
    rotor inertia and friction; ``p_hat`` (base parameters) to the true ones."""
    if kind not in ("adaptive-pd", "computed-torque", "pd"):
        raise ValueError(f"unknown controller '{kind}'; use adaptive-pd, computed-torque or pd")
    n = robot.n
    kd = _diag(gains["kd"], n, "kd")
    lam = _diag(gains["lambda"], n, "lambda")
    if kind == "pd":
        kp = gains.get("kp", lam * kd)
        return PD(n, kp, kd)
    base = base if base is not None else base_parameters(robot, rotor=True, friction=True)
    p_hat = base.values(robot.parameters(base.rotor, base.friction)) if p_hat is None else p_hat
    if kind == "computed-torque":
        kp = gains.get("kp", lam**2)
        return ComputedTorque(base, p_hat, kp, 2 * lam if "kp" not in gains else kd)
    return AdaptivePD(base, kd, lam, gains.get("gamma", 1.0), p_hat, nu=gains.get("nu", 0.0))
