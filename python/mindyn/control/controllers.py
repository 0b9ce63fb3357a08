"""Joint-space tracking controllers and their regressors.

Each controller satisfies :class:`mindyn.control.Controller`: ``tau = ctl(t, q, dq, q_d, dq_d,
ddq_d)`` once per period on the measured state, the torque held until the next call;
:func:`mindyn.control.simulate` runs them in closed loop.

- :class:`AdaptivePD`: the Slotine-Li adaptive controller on the base parameters.
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
  parameters (Coulomb friction on the measured or, :func:`default_controller`, on the reference
  velocity).
- :class:`PD`: ``tau = -K_P e - K_D de``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .. import _args, _core
from ..base import BaseParameters, base_parameters
from ..robot import Robot

__all__ = [
    "AdaptivePD",
    "CONTROLLERS",
    "ComputedTorque",
    "PD",
    "ZCR07S_STUDY_GAINS",
    "coriolis_matrix",
    "default_controller",
    "default_gains",
    "load_gains",
    "make_controller",
    "perturbed_parameters",
    "slotine_li_regressor",
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

    def __call__(self, t, q, dq, q_d, dq_d, ddq_d):
        return -self.kp * (q - q_d) - self.kd * (dq - dq_d)


class ComputedTorque:
    """Computed torque with fixed base parameters ``p_hat``:
    ``tau = W_b(q, dq, v) p_hat`` with ``v = ddq_d - K_D (dq - dq_d) - K_P (q - q_d)``.

    ``coulomb``: where the Coulomb friction of the model (when ``base`` has friction) takes its
    sign: ``"measured"`` (``Fc sign(dq)``, as ``W_b`` has it) or ``"reference"`` (a feedforward
    ``Fc sign(dq_d)``, ``Fc tanh(dq_d / coulomb_smoothing)`` when smoothing is set: switching on
    the measured velocity chatters about zero speed)."""

    name = "computed-torque"

    def __init__(
        self,
        base: BaseParameters,
        p_hat,
        kp,
        kd,
        coulomb: str = "measured",
        coulomb_smoothing: float = 0.0,
    ):
        n = base.robot.n
        self.base = base
        self.p_hat = np.asarray(p_hat, dtype=float).copy()
        if self.p_hat.shape != (base.n,):
            raise ValueError(f"p_hat has shape {self.p_hat.shape}; expected ({base.n},)")
        self.kp = _diag(kp, n, "kp")
        self.kd = _diag(kd, n, "kd")
        if coulomb not in ("measured", "reference"):
            raise ValueError(f"coulomb must be 'measured' or 'reference', got '{coulomb}'")
        self.eps = float(coulomb_smoothing)
        if not (math.isfinite(self.eps) and self.eps >= 0):
            raise ValueError(f"coulomb_smoothing must be a finite number >= 0, got {self.eps}")
        self._p = self.p_hat
        self._fc = np.zeros(n)
        if coulomb == "reference":
            self._p = self.p_hat.copy()
            for i, name in enumerate(base.names):
                if name.startswith("Fc") and name[2:].isdigit():
                    self._fc[int(name[2:]) - 1] = self._p[i]
                    self._p[i] = 0.0

    def __call__(self, t, q, dq, q_d, dq_d, ddq_d):
        v = ddq_d - self.kd * (dq - dq_d) - self.kp * (q - q_d)
        self.model_torque = self.base.regressor(q, dq, v) @ self._p
        if self._fc.any():
            s = np.tanh(dq_d / self.eps) if self.eps > 0 else np.sign(dq_d)
            self.model_torque = self.model_torque + self._fc * s
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
    period : float
        Controller period [s]: the explicit Euler step of the adaptation law.
    """

    name = "adaptive-pd"

    def __init__(
        self,
        base: BaseParameters,
        kd,
        lam,
        gamma,
        p0,
        adapt: bool = True,
        nu: float = 0.0,
        period: float = 0.004,
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
        self.period = float(period)
        if not (math.isfinite(self.period) and self.period > 0):
            raise ValueError(f"period must be a positive number of seconds, got {period}")
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

    def __call__(self, t, q, dq, q_d, dq_d, ddq_d):
        _, s, dqr, ddqr = self.terms(q, dq, (q_d, dq_d, ddq_d))
        Y = slotine_li_regressor(self.base, q, dq, dqr, ddqr)
        self.Y = Y
        self.model_torque = Y @ self.p_hat
        tau = self.model_torque - self.kd * s
        if self.adapt:
            step = self.period * self.gamma * (Y.T @ s)
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
        from .._core import RobotFileNotFoundError

        raise RobotFileNotFoundError(f"gains file '{path}' does not exist")
    from ..identification.data import decode_text

    try:
        data = yaml.safe_load(decode_text(path))
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


#: The controllers :func:`make_controller` makes, by name (``--controller`` on the command line).
CONTROLLERS = ("adaptive-pd", "computed-torque", "pd")


def make_controller(
    kind: str,
    robot: Robot,
    gains: dict,
    p_hat=None,
    base: BaseParameters | None = None,
    period: float = 0.004,
):
    """A controller by name (:data:`CONTROLLERS`) with ``gains`` as from :func:`default_gains` /
    :func:`load_gains`, for the controller ``period`` [s]. ``base`` defaults to the base
    parameters with rotor inertia and friction; ``p_hat`` (base parameters) to the true ones."""
    if kind not in CONTROLLERS:
        raise ValueError(f"unknown controller '{kind}'; use {', '.join(CONTROLLERS)}")
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
    return AdaptivePD(
        base, kd, lam, gains.get("gamma", 1.0), p_hat, nu=gains.get("nu", 0.0), period=period
    )


def default_controller(robot: Robot, params, omega: float = 20.0, coulomb_smoothing: float = 0.0):
    """The controller of the simulated logs: computed torque with the true parameters ``params``
    (classical, 13 per joint), Coulomb friction as a feedforward on the reference velocity, and
    ``K_P = omega^2``, ``K_D = 2 omega`` (critical damping at ``omega`` rad/s)."""
    base = base_parameters(robot, rotor=True, friction=True)
    return ComputedTorque(
        base,
        base.values(params),
        omega**2,
        2 * omega,
        coulomb="reference",
        coulomb_smoothing=coulomb_smoothing,
    )
