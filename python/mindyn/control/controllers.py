"""Joint-space tracking controllers and their regressors.

Each controller satisfies :class:`mindyn.control.Controller`: ``tau = ctl(t, q, dq, q_d, dq_d,
ddq_d)`` once per period on the measured state, the torque held until the next call;
:func:`mindyn.control.simulate` runs them in closed loop.

- :class:`AdaptivePD`: the Slotine-Li adaptive controller on the base parameters.
  Sign convention (the one used everywhere here)::

      e = q - q_d                 s = dq - dq_r = de + Lambda e
      dq_r = dq_d - Lambda e      ddq_r = ddq_d - Lambda de
      tau = Y(q, dq, dq_r, ddq_r) p_hat - K_D s
      dp_hat/dt = -Gamma Y^T s / (1 + nu |Y|^2)     (explicit Euler over one period,
                                                     then p_hat clipped to [p_min, p_max])

  with ``Y p = A(q) ddq_r + C(q, dq) dq_r + c(q) (+ Fv dq + Fc sign dq)`` the Slotine-Li regressor
  (:func:`slotine_li_regressor`); ``K_P = Lambda K_D``. ``nu = 0`` is the Slotine-Li law; ``nu > 0``
  normalises the step by the squared Frobenius norm of ``Y`` (normalised gradient), which bounds
  the change of the estimate per period by ``T Gamma |s| / (nu |Y|)`` and keeps large adaptation
  gains usable at a slow controller rate (plain Euler steps diverge there): the sampled update
  needs ``T lambda_max(K_D^-1/2 Y Gamma Y^T K_D^-1/2) / (1 + nu |Y|^2) < 1``
  (:func:`~mindyn.control.stability.adaptation_step_ratio`). The box (parameter projection,
  :func:`estimate_box` by default in :func:`make_controller`) keeps the estimate where the
  linearised sampled loop stays stable.
- :class:`ComputedTorque`: ``tau = W_b(q, dq, ddq_d - K_D de - K_P e) p_hat`` with fixed
  parameters (Coulomb friction on the measured or, :func:`default_controller`, on the reference
  velocity).
- :class:`PD`: ``tau = -K_P e - K_D de``.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Hashable
from pathlib import Path

import numpy as np

from .. import _args, _core
from ..base import BaseParameters, base_parameters
from ..robot import Robot

__all__ = [
    "ControllerSettingError",
    "AdaptivePD",
    "CONTROLLERS",
    "ComputedTorque",
    "PD",
    "ZCR07S_STUDY_GAINS",
    "consistent_perturbation",
    "coriolis_matrix",
    "default_controller",
    "Gains",
    "check_gains",
    "check_period",
    "check_sampled_gains",
    "controller_check",
    "coulomb_friction",
    "default_gains",
    "estimate_box",
    "friction_bound",
    "friction_shortfall",
    "load_gains",
    "make_controller",
    "model_friction_shortfall",
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
@_args.finite_results("q", "dq", "dqr", "ddqr")
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
    _args.instance(base, "base", BaseParameters)
    q, dq, dqr, ddqr = _args.batch(base.robot.n, q=q, dq=dq, dqr=dqr, ddqr=ddqr)
    return _core.slotine_li_regressor(base._b, q, dq, dqr, ddqr)


@_args.finite_results("q", "dq", "dqr", "ddqr")
def slotine_li_regressor_classical(
    robot: Robot, q, dq, dqr, ddqr, *, rotor: bool = False, friction: bool = False
) -> np.ndarray:
    """Slotine-Li regressor in the classical layout, shape (n, P) or (m, n, P) (multi-DOF
    joints: (nv, 10 n), q of nq entries, the others of nv, no rotor inertia or friction)."""
    _args.instance(robot, "robot", Robot)
    if not robot.single_dof:
        robot._refuse_drive_terms(rotor, friction)
        return robot._multibody(
            _core.multibody_slotine_li_regressor, q=q, dq=dq, dqr=dqr, ddqr=ddqr
        )
    q, dq, dqr, ddqr = _args.batch(robot.n, q=q, dq=dq, dqr=dqr, ddqr=ddqr)
    rotor, friction = _args.flag(rotor, "rotor"), _args.flag(friction, "friction")
    return _core.slotine_li_regressor_classical(
        robot._m, q, dq, dqr, ddqr, rotor=rotor, friction=friction
    )


@_args.finite_results("q", "dq", "params")
def coriolis_matrix(robot: Robot, q, dq, params=None) -> np.ndarray:
    """Coriolis matrix ``C(q, dq)`` of the Christoffel symbols, shape (n, n) or (m, n, n):
    ``C dq`` is the velocity-product torque and ``dA/dt - 2 C`` is skew-symmetric. ``params``: any
    classical layout (default the model's inertial parameters; multi-DOF joints: (nv, nv), the
    inertial parameters only)."""
    _args.instance(robot, "robot", Robot)
    if not robot.single_dof:
        return robot._multibody(_core.multibody_coriolis_matrix, q=q, dq=dq, params=params)
    q, dq = _args.batch(robot.n, q=q, dq=dq)
    return _core.coriolis_matrix(robot._m, q, dq, robot._params(params))


# ---------------------------------------------------------------------------------------------
# Controllers
# ---------------------------------------------------------------------------------------------
class ControllerSettingError(_args.ArgumentError):
    """A gain, period or other controller setting that cannot be used: not a finite number of
    the right shape, or outside what a sampled loop at the period can take."""


#: Largest gain accepted (kd, kp, lambda, gamma, nu): the bound every number of a description
#: keeps, which keeps one controller step's arithmetic finite (1e308 gave infinite torques).
MAX_GAIN = 1e16


def _diag(x, n: int, name: str) -> np.ndarray:
    if isinstance(x, (bool, np.bool_)) or (
        isinstance(x, (list, tuple)) and any(isinstance(v, (bool, np.bool_)) for v in x)
    ):
        raise ControllerSettingError(f"gain '{name}' must be numbers, got a boolean ({x!r})")
    a = np.array(x, dtype=float)  # a copy: the caller's array may change after
    if a.ndim == 0:
        a = np.full(n, float(a))
    if a.shape != (n,):
        raise ControllerSettingError(
            f"gain '{name}' must be a scalar or {n} values, got shape {a.shape}"
        )
    if not np.all(np.isfinite(a)) or np.any(a < 0) or np.any(a > MAX_GAIN):
        raise ControllerSettingError(
            f"gain '{name}' must be a number in [0, {MAX_GAIN:g}], got {a.tolist()}"
        )
    return a


#: Shortest and longest controller period [s] accepted: a microsecond (joint controllers run
#: at 1-32 kHz) and 1000 s (the longest of ``mindyn simulate --period``).
MIN_PERIOD, MAX_PERIOD = 1e-6, 1e3


def check_period(period, *, what: str = "period") -> float:
    """``period`` as a float; raises ControllerSettingError (an ArgumentError) unless it is a
    number of seconds in [:data:`MIN_PERIOD`, :data:`MAX_PERIOD`]."""
    _args.text(what, "what")
    if isinstance(period, (bool, np.bool_, str, bytes)):
        raise ControllerSettingError(f"{what} must be a number of seconds, got {period!r}")
    try:
        T = float(period)
    except (TypeError, ValueError):
        raise ControllerSettingError(
            f"{what} must be a number of seconds, got {period!r}"
        ) from None
    if not (MIN_PERIOD <= T <= MAX_PERIOD):
        raise ControllerSettingError(
            f"{what} must be a number of seconds in [{MIN_PERIOD:g}, {MAX_PERIOD:g}], got {T:g}"
        )
    return T


def check_sampled_gains(kind: str, kp, kd, lam, period: float) -> None:
    """Raises ValueError unless the gains of ``kind`` (``pd``, ``computed-torque``,
    ``adaptive-pd``; diagonals) meet the conditions of a sampled loop at ``period`` that hold
    whatever the robot (one joint of any inertia ``m``: ``K_P T < 2 K_D`` for PD; with an exact
    model ``K_D T < 2`` and ``K_P T < 2 K_D`` for computed torque; ``Lambda T < 2`` for adaptive
    PD, :func:`check_lambda`). The robot's part, ``T M^-1 K_D,eff < 2``, is :func:`check_gains`."""
    _args.choice(kind, "kind", CONTROLLERS)
    T = check_period(period)
    kp, kd, lam = (  # the values are checked below, with the gains' own messages
        _args.array(x, name, (None,) * min(np.ndim(x), 1), finite=False)
        for x, name in ((kp, "kp"), (kd, "kd"), (lam, "lam"))
    )
    for name, x in (("lambda", lam), ("kd", kd), ("kp", kp)):
        if not np.all(np.isfinite(x)) or np.any(x < 0) or np.any(x > MAX_GAIN):
            raise ControllerSettingError(
                f"gain '{name}' must be a number in [0, {MAX_GAIN:g}], got {x.tolist()}"
            )
    if kind == "adaptive-pd":
        check_lambda(lam, T)
        return
    rules = [("K_P T < 2 K_D", kp * T, 2 * kd)]
    if kind == "computed-torque":
        rules.append(("K_D T < 2", kd * T, np.full_like(kd, 2.0)))
    for rule, left, right in rules:
        bad = np.flatnonzero(~(left < right))
        if bad.size:
            k = int(bad[0])
            raise ControllerSettingError(
                f"{kind} gains on joint {k + 1} (kp {kp[k]:g}, kd {kd[k]:g}) with the controller "
                f"period {T:g} s: a sampled loop needs {rule} (here {left[k]:.4g} against "
                f"{right[k]:.4g})"
            )


def check_lambda(lam, period: float, *, what: str = "lambda") -> None:
    """Raises ValueError unless ``Lambda T < 2`` on every joint: the adaptive PD's feedforward
    ``M ddq_r`` with ``ddq_r = ddq_d - Lambda de`` is a velocity feedback of gain ``M Lambda``,
    and a sampled loop needs ``T M^-1 K_D,eff`` below 2 (one joint: ``(K_D / m + Lambda) T < 2``),
    whatever the robot."""
    lam = np.asarray(lam, dtype=float)
    bad = np.flatnonzero(~(lam * period < 2.0))
    if bad.size:
        k = int(bad[0])
        raise ControllerSettingError(
            f"{what} {lam[k]:g} on joint {k + 1} with the controller period {period:g} s: a "
            f"sampled loop needs Lambda T < 2 (here {lam[k] * period:.3g}), so Lambda < "
            f"{2.0 / period:.4g} at this period"
        )


def _estimate(x, base: BaseParameters, name: str) -> np.ndarray:
    """A vector of base-parameter values (an estimate), a copy: ``base.n`` finite numbers."""
    try:
        a = np.array(x, dtype=float)  # a copy: the caller's array may change after
    except (TypeError, ValueError):
        raise ControllerSettingError(f"{name} must be {base.n} numbers, got {x!r}") from None
    if a.shape != (base.n,):
        raise ControllerSettingError(f"{name} has shape {a.shape}; expected ({base.n},)")
    bad = np.flatnonzero(~np.isfinite(a))
    if bad.size:
        k = int(bad[0])
        raise ControllerSettingError(
            f"{name} has {a[k]} at '{base.names[k]}' (entry {k + 1}); expected finite values"
        )
    return a


def _bound(x, size: int, name: str, fill: float) -> np.ndarray:
    """A side of the box on the estimate: None (``fill``, open), a number or ``size`` numbers
    (infinities allowed, NaN not)."""
    if x is None:
        return np.full(size, fill)
    try:
        a = np.array(x, dtype=float)
    except (TypeError, ValueError):
        raise ControllerSettingError(f"{name} must be numbers, got {x!r}") from None
    a = np.full(size, float(a)) if a.ndim == 0 else a
    if a.shape != (size,) or np.isnan(a).any():
        raise ControllerSettingError(
            f"{name} must be a number or {size} numbers (no NaN), got shape {a.shape}"
        )
    return a


def _joint_vectors(n: int, **arrays) -> list[np.ndarray]:
    """A controller step's per-joint inputs, each of shape (n,) and finite, or an ArgumentError
    naming it (:func:`mindyn._args.array`). A float64 array of that shape passes as it is, not
    copied (the step runs every controller period); anything else is converted."""
    out = []
    for name, x in arrays.items():
        if not (
            type(x) is np.ndarray
            and x.shape == (n,)
            and x.dtype == np.float64
            and np.isfinite(x).all()
        ):
            x = _args.array(x, name, (n,), unit="joint")
        out.append(x)
    return out


class PD:
    """Plain PD: ``tau = -K_P e - K_D de`` (no model). ``q``, ``dq`` and the reference are
    arrays of shape (n,), finite (else an ArgumentError names the argument)."""

    name = "pd"

    def __init__(self, n: int, kp, kd):
        self.n = n = _args.integer(n, "n", 1)
        self.kp = _diag(kp, n, "kp")
        self.kd = _diag(kd, n, "kd")

    def __call__(self, t, q, dq, q_d, dq_d, ddq_d):
        q, dq, q_d, dq_d, _ = _joint_vectors(self.n, q=q, dq=dq, q_d=q_d, dq_d=dq_d, ddq_d=ddq_d)
        return -self.kp * (q - q_d) - self.kd * (dq - dq_d)


class ComputedTorque:
    """Computed torque with fixed base parameters ``p_hat``:
    ``tau = W_b(q, dq, v) p_hat`` with ``v = ddq_d - K_D (dq - dq_d) - K_P (q - q_d)``.

    ``coulomb``: where the Coulomb friction of the model (when ``base`` has friction) takes its
    sign: ``"measured"`` (``Fc sign(dq)``, as ``W_b`` has it) or ``"reference"`` (a feedforward
    ``Fc sign(dq_d)``, ``Fc tanh(dq_d / coulomb_smoothing)`` when smoothing is set: switching on
    the measured velocity chatters about zero speed)."""

    name = "computed-torque"
    #: set by :func:`make_controller`: ``p_hat`` is the simulated robot's own parameters
    true_model: bool = False

    def __init__(
        self,
        base: BaseParameters,
        p_hat,
        kp,
        kd,
        *,
        coulomb: str = "measured",
        coulomb_smoothing: float = 0.0,
    ):
        _args.instance(base, "base", BaseParameters)
        n = base.robot.n
        self.base = base
        self.p_hat = _estimate(p_hat, base, "p_hat")
        self.kp = _diag(kp, n, "kp")
        self.kd = _diag(kd, n, "kd")
        if coulomb not in ("measured", "reference"):
            raise ControllerSettingError(
                f"coulomb must be 'measured' or 'reference', got '{coulomb}'"
            )
        self._coulomb = coulomb
        self.eps = _args.number(coulomb_smoothing, "coulomb_smoothing", minimum=0.0)
        if not (math.isfinite(self.eps) and self.eps >= 0):
            raise ControllerSettingError(
                f"coulomb_smoothing must be a finite number >= 0, got {self.eps}"
            )
        self._p = self.p_hat
        self._fc = np.zeros(n)
        if coulomb == "reference":
            self._p = self.p_hat.copy()
            for i, name in enumerate(base.names):
                if name.startswith("Fc") and name[2:].isdigit():
                    self._fc[int(name[2:]) - 1] = self._p[i]
                    self._p[i] = 0.0

    def use_parameters(self, p_hat) -> None:
        """Takes ``p_hat`` (base parameters) as the fixed model."""
        ComputedTorque.__init__(
            self,
            self.base,
            p_hat,
            self.kp,
            self.kd,
            coulomb=self._coulomb,
            coulomb_smoothing=self.eps,
        )

    def __call__(self, t, q, dq, q_d, dq_d, ddq_d):
        q, dq, q_d, dq_d, ddq_d = _joint_vectors(
            self.base.robot.n, q=q, dq=dq, q_d=q_d, dq_d=dq_d, ddq_d=ddq_d
        )
        v = ddq_d - self.kd * (dq - dq_d) - self.kp * (q - q_d)
        self.model_torque = self.base.regressor(q, dq, v) @ self._p
        if self._fc.any():  # slot k's Coulomb torque at its reference velocity, through t_k
            robot = self.base.robot
            v_d = robot.slot_velocities(dq_d)
            s = np.tanh(v_d / self.eps) if self.eps > 0 else np.sign(v_d)
            f = self._fc * s
            self.model_torque = self.model_torque + (
                f if robot.drive_side != "motor" else robot.drive_matrix.T @ f
            )
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
    p_min, p_max : array of shape (base.n,), optional
        Box on the estimate (parameter projection: ``p0`` and ``p_hat`` after each step are
        clipped to it;
        ``-inf`` / ``inf`` entries leave a side open; default unbounded).
        :func:`estimate_box` derives one from the linearised check of the sampled loop
        (:func:`make_controller` uses it by default).
    """

    name = "adaptive-pd"
    #: set by :func:`make_controller`: ``p0`` is the simulated robot's own parameters
    true_model: bool = False

    def __init__(
        self,
        base: BaseParameters,
        kd,
        lam,
        gamma,
        p0,
        *,
        adapt: bool = True,
        nu: float = 0.0,
        period: float = 0.004,
        p_min=None,
        p_max=None,
    ):
        _args.instance(base, "base", BaseParameters)
        n = base.robot.n
        self.base = base
        self.kd = _diag(kd, n, "kd")
        self.lam = _diag(lam, n, "lambda")
        self.p_min, self.p_max = (
            _bound(x, base.n, name, fill)
            for x, name, fill in ((p_min, "p_min", -math.inf), (p_max, "p_max", math.inf))
        )
        if np.any(self.p_min > self.p_max):
            k = int(np.argmax(self.p_min > self.p_max))
            raise ControllerSettingError(
                f"p_min exceeds p_max at '{base.names[k]}' ({self.p_min[k]:g} > {self.p_max[k]:g})"
            )
        self.gamma = _diag(gamma, base.n, "gamma")
        self.p0 = _estimate(p0, base, "p0")
        self.adapt = _args.flag(adapt, "adapt")
        self.nu = float(nu)
        if not (0 <= self.nu <= MAX_GAIN):
            raise ControllerSettingError(f"nu must be a number in [0, {MAX_GAIN:g}], got {nu}")
        self.period = check_period(period)
        check_lambda(self.lam, self.period)
        self.reset()

    def reset(self) -> None:
        """The estimate back to ``p0``, projected onto the box (as the generated step's initial
        estimate is)."""
        self.p_hat = np.clip(self.p0, self.p_min, self.p_max)

    #: how the box was set: "derived" (:meth:`derive_box`), "given" or "none"
    box = "none"
    box_note = ""

    def derive_box(self, params=None, *, rotor: bool = True, friction: bool = True) -> None:
        """Sets the box on the estimate to :func:`estimate_box` of this controller's gains and
        period about the description's values (``rotor``, ``friction``) or the classical
        parameters ``params`` (full layout: a simulated robot's), and projects the estimate
        onto it (:meth:`reset`)."""
        robot = self.base.robot
        gains = {"kd": self.kd, "lambda": self.lam}
        self.p_min, self.p_max, self.box_note = estimate_box(
            robot,
            self.base,
            gains,
            period=self.period,
            rotor=rotor,
            friction=friction,
            params=params,
        )
        self.box = "derived"
        self.reset()

    def use_parameters(self, p0) -> None:
        """Takes ``p0`` (base parameters) as the initial estimate, and resets."""
        self.p0 = _estimate(p0, self.base, "p0")
        self.reset()

    def terms(self, q, dq, ref):
        """``(e, s, dq_r, ddq_r)`` of the sign convention; ``ref`` is ``(q_d, dq_d, ddq_d)``.
        Every array is of shape (n,) and finite, else an ArgumentError names it."""
        if not (isinstance(ref, (tuple, list)) and len(ref) == 3):
            raise _args.fail("ref", "must be the three arrays (q_d, dq_d, ddq_d)")
        return self._terms(
            *_joint_vectors(self.base.robot.n, q=q, dq=dq, q_d=ref[0], dq_d=ref[1], ddq_d=ref[2])
        )

    def _terms(self, q, dq, qd, dqd, ddqd):
        e = q - qd
        de = dq - dqd
        dqr = dqd - self.lam * e
        ddqr = ddqd - self.lam * de
        s = de + self.lam * e
        return e, s, dqr, ddqr

    def __call__(self, t, q, dq, q_d, dq_d, ddq_d):
        q, dq, q_d, dq_d, ddq_d = _joint_vectors(
            self.base.robot.n, q=q, dq=dq, q_d=q_d, dq_d=dq_d, ddq_d=ddq_d
        )
        _, s, dqr, ddqr = self._terms(q, dq, q_d, dq_d, ddq_d)
        Y = slotine_li_regressor(self.base, q, dq, dqr, ddqr)
        self.Y = Y
        self.model_torque = Y @ self.p_hat
        tau = self.model_torque - self.kd * s
        if self.adapt:
            step = self.period * self.gamma * (Y.T @ s)
            if self.nu:
                step /= 1.0 + self.nu * float(np.sum(Y * Y))
            self.p_hat = np.clip(self.p_hat - step, self.p_min, self.p_max)
        return tau


# ---------------------------------------------------------------------------------------------
# Gains
# ---------------------------------------------------------------------------------------------
class Gains(dict):
    """Gains as :func:`default_gains` and :func:`load_gains` give them (``kd``, ``lambda``,
    ``gamma`` and optionally ``nu``, ``kp``), with ``note``: how they were chosen and the check
    of their sampled loops at the period, for every controller (text, empty when nothing is to
    be said); :meth:`note_for`: the part of it that concerns one controller (plain PD uses no
    adaptation gain, computed torque no K_D); and ``conflicts``: for each controller whose
    sampled loop cannot hold the friction bound at the period (:func:`default_gains`), the
    one-line reason; :func:`make_controller` refuses it."""

    conflicts: dict = {}  # replaced, never mutated, per instance
    #: the keys a gains file left to the defaults (:func:`load_gains`; empty otherwise)
    defaulted: frozenset = frozenset()
    # the note's clauses: (the views that show it, text); a view is a controller or None (the
    # note of every controller)
    _clauses: tuple = ()

    @property
    def note(self) -> str:
        return self.note_for(None)

    @note.setter
    def note(self, text: str) -> None:
        self._clauses = ()
        if text:
            self.add_note(text)

    def note_for(self, controller: str | None) -> str:
        """The note's clauses that concern ``controller`` (one of :data:`CONTROLLERS`; None:
        every controller's, :attr:`note`), joined by '; '."""
        if controller is not None:
            _args.choice(controller, "controller", CONTROLLERS)
        return "; ".join(text for views, text in self._clauses if controller in views)

    def add_note(self, text: str, controllers=None, *, general: bool = True) -> None:
        """Appends a clause to the note, shown for ``controllers`` (a sequence of names; None:
        every one) and, when ``general``, in :attr:`note` (every controller's)."""
        views = set(CONTROLLERS if controllers is None else controllers)
        self._clauses = (*self._clauses, (frozenset(views | ({None} if general else set())), text))


def plant_parameters(robot: Robot, rotor: bool, *, friction: bool = True) -> np.ndarray:
    """The description's parameters in the full layout (rotor inertia and the friction model's
    columns, ``robot.layout_sizes[3]`` per joint), rotor inertia and friction zero unless asked
    for (the simulated robot of :func:`mindyn.control.simulate`)."""
    p = robot.parameters(rotor=True, friction=True).reshape(robot.n, -1).copy()
    if not rotor:
        p[:, 10] = 0.0
    if not friction:
        p[:, 11:] = 0.0
    return p.reshape(-1)


def base_values(base: BaseParameters, params) -> np.ndarray:
    """The base-parameter values of classical parameters ``params`` in the full layout (with
    rotor inertia and friction, :func:`plant_parameters`), whatever the layout of ``base``."""
    n = base.robot.n
    full = np.asarray(params, dtype=float).reshape(n, base.robot.layout_sizes[3])
    cols = list(range(10)) + [10] * base.rotor + list(range(11, full.shape[1])) * base.friction
    values = base.values(full[:, cols].reshape(-1))
    if base.offset:
        values = np.concatenate([values, np.zeros(n)])[: len(base.names)]
    return values


def _rotor_cases(rotor) -> list[bool]:
    if rotor is None:
        return [True, False]
    return [_args.flag(rotor, "rotor")]


def _gain_arrays(kind: str, gains: dict, n: int):
    """``(kp, kd, lam)`` diagonals as :func:`make_controller` uses them for ``kind``."""
    kd = _diag(gains["kd"], n, "kd")
    lam = _diag(gains["lambda"], n, "lambda")
    if kind == "pd":
        return _diag(gains.get("kp", lam * kd), n, "kp"), kd, lam
    if kind == "computed-torque":
        if "kp" in gains:
            kp = _diag(gains["kp"], n, "kp")
            return kp, computed_torque_kd(kp, kd, getattr(gains, "defaulted", ())), lam
        return lam**2, 2 * lam, lam
    return lam * kd, kd, lam


def computed_torque_kd(kp, kd, defaulted) -> np.ndarray:
    """Computed torque's ``K_D`` beside the gains' own ``kp``: ``kd`` when the gains give it,
    else (``"kd"`` in ``defaulted``, the keys a gains file left to the defaults: the default kd
    is a torque gain of the other controllers) critically damped, ``2 sqrt(K_P)`` [1/s]."""
    if "kd" in defaulted:
        return 2.0 * np.sqrt(np.maximum(kp, 0.0))
    return kd


def check_gains(
    robot: Robot,
    gains: dict,
    *,
    kind: str = "adaptive-pd",
    period: float = 0.004,
    rotor: bool | None = None,
    qs=None,
):
    """The linearised check of the sampled loop (:mod:`mindyn.control.stability`) of the
    controller ``kind`` that :func:`make_controller` makes from ``gains``, at ``period`` [s].

    The robot's mass matrix is sampled over the workspace
    (:func:`~mindyn.control.stability.workspace_samples`, or ``qs``); the simulated robot has
    rotor inertia (``rotor=True``), has none (``False``) or either (``None``: both checked), and
    the controller's model is the simulated robot's own (the true parameters, the default of
    :func:`make_controller` in :func:`~mindyn.control.simulate`). Returns a
    :class:`~mindyn.control.stability.LoopCheck`."""
    _args.instance(robot, "robot", Robot)
    _args.mapping(gains, "gains")
    _args.choice(kind, "kind", CONTROLLERS)
    _args.optional(_args.flag, rotor, "rotor")
    from .stability import check_loop, workspace_samples

    if kind not in CONTROLLERS:
        raise ControllerSettingError(f"unknown controller '{kind}'; use {', '.join(CONTROLLERS)}")
    T = check_period(period)
    kp, kd, lam = _gain_arrays(kind, gains, robot.n)
    qs = workspace_samples(robot) if qs is None else np.atleast_2d(np.asarray(qs, dtype=float))
    plants, models, damping, cases = [], [], [], []
    for r in _rotor_cases(rotor):
        p = plant_parameters(robot, r)
        m = robot.mass_matrix(qs, p)
        plants.append(np.linalg.inv(m))
        models.append(m)
        damping.append(plant_damping(robot, p, qs))
        cases.append(f"robot {'with' if r else 'without'} rotor inertia")
    cases.append(f"{len(qs)} configurations, the controller's model the robot's own")
    return check_loop(
        kind,
        kp,
        kd,
        lam,
        T,
        plants,
        models,
        qs,
        cases,
        plant_damping=damping,
        model_damping=damping,
    )


def plant_damping(robot: Robot, params, qs) -> np.ndarray:
    """The viscous friction's ``d tau / d dq`` of the robot of classical ``params`` (full
    layout) at ``qs`` (:func:`~mindyn.control.stability.viscous_damping`), (m, n, n)."""
    from .stability import viscous_damping

    def regressor(q, dq, ddq):
        return robot.regressor(q, dq, ddq, rotor=True, friction=True)

    names = robot.parameter_names(rotor=True, friction=True)
    return viscous_damping(regressor, names, params, qs)


def _generated_base(robot: Robot, code) -> BaseParameters | None:
    """The base parameters of ``robot`` whose names are those of a generated step ``code``
    (with or without rotor inertia and friction, as :func:`mindyn.base_parameters` gives
    them), or None when none is: the model of a compiled step given no ``base``."""
    names = list(getattr(code, "names", ()))
    for rotor, friction in ((True, True), (False, False), (True, False), (False, True)):
        base = base_parameters(robot, rotor=rotor, friction=friction)
        if list(base.names) == names:
            return base
    return None


def controller_check(robot: Robot, controller, params, period: float):
    """The linearised check of a controller of this module or of a compiled generated step
    (:class:`mindyn.codegen.CompiledController`; given no ``base``, the robot's base set whose
    names are the step's; ``None`` for other controllers) against the
    simulated robot of classical parameters ``params`` (13 per joint) at ``period`` [s]: the
    controller's own model (``base`` and ``p0`` / ``p_hat``) at the sampled configurations."""
    _args.instance(robot, "robot", Robot)
    _args.function(controller, "controller")
    params = _args.array(params, "params", (None,))
    period = _args.number(period, "period", positive=True)
    from .simulation import expand_params
    from .stability import check_loop, viscous_damping, workspace_samples

    n = robot.n
    kind = getattr(controller, "name", None)
    settings = getattr(getattr(controller, "code", None), "settings", None)
    if isinstance(settings, dict) and {"kd", "kp", "lambda", "p0"} <= settings.keys():
        kind = "pd" if kind == "gravity-compensation" else kind
        kd, kp, lam, p_hat = (settings[k] for k in ("kd", "kp", "lambda", "p0"))
    elif kind in CONTROLLERS and hasattr(controller, "kd"):
        kd, lam = controller.kd, getattr(controller, "lam", np.zeros(n))
        kp = getattr(controller, "kp", lam * controller.kd)
        p_hat = getattr(controller, "p0", None)
        p_hat = getattr(controller, "p_hat", None) if p_hat is None else p_hat
        if p_hat is not None and hasattr(controller, "p_min"):  # the estimate starts in its box
            p_hat = np.clip(p_hat, controller.p_min, controller.p_max)
    else:
        return None
    base = getattr(controller, "base", None)
    if base is None and isinstance(settings, dict):  # a compiled step given no base
        base = _generated_base(robot, controller.code)
    if kind not in CONTROLLERS or (kind != "pd" and (base is None or p_hat is None)):
        return None
    qs = workspace_samples(robot)
    m = robot.mass_matrix(qs, params)
    models, fed = [m], None
    if kind != "pd":
        assert base is not None and p_hat is not None
        k = len(qs)
        eye = np.broadcast_to(np.eye(n), (k, n, n)).reshape(k * n, n)
        qq = np.repeat(qs, n, axis=0)
        cols = base.regressor(qq, np.zeros_like(qq), eye) @ p_hat
        grav = base.regressor(qs, np.zeros_like(qs), np.zeros_like(qs)) @ p_hat
        models = [cols.reshape(k, n, n).transpose(0, 2, 1) - grav[:, :, None]]
        fed = [viscous_damping(base.regressor, base.names, p_hat, qs)]
    full = expand_params(n, params, sizes=robot.layout_sizes)
    cases = ["the controller's model", f"{len(qs)} configurations"]
    return check_loop(
        kind,
        kp,
        kd,
        lam,
        period,
        [np.linalg.inv(m)],
        models,
        qs,
        cases,
        plant_damping=[plant_damping(robot, full, qs)],
        model_damping=fed,
    )


#: Reference samples at which :func:`adaptation_check` evaluates the step condition.
STEP_SAMPLES = 400


def adaptation_check(controller, q_d, dq_d, ddq_d, period: float) -> str | None:
    """The step condition of an adaptive PD's sampled update along the reference (one text
    line; None for other controllers): the largest ``T lambda_max(K_D^-1/2 Y Gamma Y^T
    K_D^-1/2) / (1 + nu |Y|^2)`` over up to :data:`STEP_SAMPLES` samples of the reference
    (``Y`` on the reference, where ``s = 0``), which the update needs below 1
    (:func:`~mindyn.control.stability.adaptation_step_ratio`), and the largest factor on
    ``Gamma`` that keeps it so; with the box on the estimate when the controller has one.
    ``controller``: an :class:`AdaptivePD` or a compiled generated adaptive-PD step given its
    ``base``."""
    from .stability import adaptation_step_ratio

    settings = getattr(getattr(controller, "code", None), "settings", None)
    base = getattr(controller, "base", None)
    if getattr(controller, "name", None) != "adaptive-pd" or base is None:
        return None
    if isinstance(settings, dict):
        kd, gamma, nu = settings["kd"], settings["gamma"], settings["nu"]
        lo, hi = settings.get("p_min"), settings.get("p_max")
        adapt = True
    else:
        kd, gamma, nu = controller.kd, controller.gamma, controller.nu
        lo, hi = controller.p_min, controller.p_max
        adapt = controller.adapt
    if not adapt:
        return "adaptation off"
    m, n = np.shape(q_d)
    pick = np.unique(np.linspace(0, m - 1, min(m, STEP_SAMPLES)).round().astype(int))
    Y = slotine_li_regressor(base, q_d[pick], dq_d[pick], dq_d[pick], ddq_d[pick])
    if np.size(gamma) == base.n + n:  # a generated step with a torque offset per joint
        Y = np.concatenate([Y, np.broadcast_to(np.eye(n), (len(pick), n, n))], axis=-1)
    ratio = float(np.max(adaptation_step_ratio(Y, kd, gamma, nu, period)))
    text = (
        f"adaptation step condition along the reference: T lambda_max(K_D^-1/2 Y Gamma Y^T "
        f"K_D^-1/2) / (1 + nu |Y|^2) at most {ratio:.3g} (the sampled update needs it below 1"
        + (
            "; NOT MET: the update is unstable where the reference holds it above 1, and "
            "diverges if it stays there long"
            if ratio >= 1
            else ""
        )
        + (f"; Gamma could grow {1.0 / ratio:.3g} times, nu fixed" if ratio > 0 else "")
        + f"; {len(pick)} samples)"
    )
    if lo is not None and hi is not None:
        bounded = int(np.sum(np.isfinite(lo) | np.isfinite(hi)))
        text += f"; estimate projected onto a box ({bounded} of {len(lo)} parameters bounded"
        p0 = getattr(controller, "p0", None)
        moved = 0 if p0 is None else int(np.sum((p0 < lo) | (p0 > hi)))
        text += f", the initial estimate moved into it on {moved})" if moved else ")"
    return text


#: Configurations at which :func:`estimate_box` checks each parameter's change (the cost is a
#: loop check per parameter and bisection step).
BOX_SAMPLES = 8


def estimate_box(
    robot: Robot,
    base: BaseParameters,
    gains: dict,
    *,
    period: float = 0.004,
    rotor: bool = True,
    friction: bool = True,
    params=None,
    center=None,
    qs=None,
) -> tuple[np.ndarray, np.ndarray, str]:
    """The default box on adaptive PD's estimate (parameter projection), ``(p_min, p_max,
    note)``, about ``center`` (base parameters; default the description's values): a part of
    the region where the linearised sampled loop of adaptive PD with ``gains`` at ``period``
    stays stable that holds with the parameters moving together.

    For the robot of the description (its rotor inertia and friction as ``rotor`` and
    ``friction`` say; ``params``: classical parameters in the full layout instead, a simulated
    robot's) and the model ``center``, ``d_j`` is the change of parameter ``j`` alone (down or
    up) that makes the loop unstable (:func:`~mindyn.control.stability.deviation_bounds`, mass
    matrix and viscous friction at :data:`BOX_SAMPLES` configurations of
    :func:`~mindyn.control.stability.workspace_samples`); ``f`` the largest common fraction of
    them at which the box's corners and random points keep the loop stable
    (:func:`~mindyn.control.stability.box_fraction`: 1, 1/2, 1/4, ..., at least ``1 / N``,
    where every point of the box lies in the convex hull of the single-parameter limits). Each
    side is a third (:data:`~mindyn.control.stability.GAIN_MARGIN`) of ``f d_j``. Estimate
    drift (the gradient follows what the model cannot represent: the torque held over a
    period, Coulomb friction, noise) then cannot take the model where the sampled loop
    diverges: an inertia estimate that drops until ``K_D + M_hat Lambda`` no longer damps, a
    viscous friction estimate that grows past the robot's where the friction is fast beside
    the period. Parameters that the linearised loop does not see (Coulomb friction,
    gravity-only combinations) get no bound (infinite sides). The note states the figures."""
    _args.instance(robot, "robot", Robot)
    _args.instance(base, "base", BaseParameters)
    _args.mapping(gains, "gains")
    rotor, friction = _args.flag(rotor, "rotor"), _args.flag(friction, "friction")
    from .stability import (
        BOX_POINTS,
        GAIN_MARGIN,
        box_fraction,
        deviation_bounds,
        workspace_samples,
    )

    params = _args.optional(_args.array, params, "params", (robot.layout_sizes[3] * robot.n,))
    center = _args.optional(_args.array, center, "center", (base.n,))
    qs = _args.optional(_args.array, qs, "qs", (None, robot.n))
    if base.robot.n != robot.n:
        raise _args.fail("base", f"is of a robot of {base.robot.n} joints; expected {robot.n}")
    T = check_period(period)
    n, nb = robot.n, base.n
    _, kd, lam = _gain_arrays("adaptive-pd", gains, n)
    full = plant_parameters(robot, rotor, friction=friction) if params is None else params
    p_d = base_values(base, full)
    p_c = p_d if center is None else center
    if qs is None:
        qs = workspace_samples(robot, count=BOX_SAMPLES)
    k = len(qs)
    zero = np.zeros_like(qs)
    eye = np.broadcast_to(np.eye(n), (k, n, n)).reshape(k * n, n)
    qq = np.repeat(qs, n, axis=0)
    grav = base.regressor(qs, zero, zero)  # (k, n, nb)
    cols = base.regressor(qq, np.zeros_like(qq), eye).reshape(k, n, n, nb)  # [k, c, i, j]
    inertia = (cols - grav[:, None]).transpose(3, 0, 2, 1)  # [j, k, i, c]
    viscous = np.array([str(x).startswith("Fv") for x in base.names])
    vel = base.regressor(qq, eye, np.zeros_like(qq)).reshape(k, n, n, nb) - grav[:, None]
    fric = np.where(viscous, vel, 0.0).transpose(3, 0, 2, 1)
    minv = np.linalg.inv(robot.mass_matrix(qs, full))
    m_hat = np.einsum("jkic,j->kic", inertia, p_c)
    fed = np.einsum("jkic,j->kic", fric, p_c)
    damping = plant_damping(robot, full, qs)
    loop = (kd, lam, T, minv, m_hat, damping, fed, inertia, fric)
    down, up = deviation_bounds(*loop)
    seen = np.isfinite(down) | np.isfinite(up)
    fraction = box_fraction(*loop, down, up)
    share = GAIN_MARGIN / fraction
    lo, hi = p_c - down / share, p_c + up / share
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.minimum(down, up) / share / np.abs(p_c)
    tight = [i for i in np.argsort(rel) if seen[i] and np.isfinite(rel[i])][:2]
    where = "the description's values" if center is None else "the initial estimate"
    note = (
        f"estimate box about {where}: {int(seen.sum())} of {nb} base parameters bounded, each "
        f"to 1/{share:.4g} of the change that alone makes the linearised sampled loop at "
        f"{T:g} s unstable (a third of the largest common fraction, {fraction:.4g}, at which "
        f"the box's corners and {BOX_POINTS} random points keep it stable; {len(qs)} "
        f"configurations; {nb - int(seen.sum())} the loop does not see, such as Coulomb "
        "friction, unbounded)"
        + (
            "; tightest "
            + ", ".join(
                f"{base.names[i]} {p_c[i]:.4g} in [{lo[i]:.4g}, {hi[i]:.4g}]" for i in tight
            )
            if tight
            else ""
        )
    )
    return lo, hi, note


#: Bandwidth of the derived default gains where the period allows it [rad/s]: ``Lambda``
#: (position error) and ``K_D`` per unit of effective inertia.
DEFAULT_LAMBDA, DEFAULT_KD_PER_INERTIA = 10.0, 40.0
#: The tracking tolerance the default gains hold against Coulomb friction (revolute [rad],
#: prismatic [m]): 2 degrees, 2 mm.
DEFAULT_TOLERANCE = (math.radians(2.0), 0.002)
#: The share of the tolerance left to Coulomb friction's steady error ``2 Fc / K_P``; the rest
#: is for what the feedback leaves of the dynamics (the lag of the sampled loop, model error).
FRICTION_SHARE = 0.5


def coulomb_friction(robot: Robot, params) -> np.ndarray:
    """The largest Coulomb friction torque (force) on each joint, (n,), of the robot of
    classical ``params`` (full layout, :func:`plant_parameters`): its ``Fc`` per joint, or,
    friction on the motors, ``sum_k |t_ki| Fc_k`` through the drive matrix."""
    _args.instance(robot, "robot", Robot)
    size = robot.layout_sizes[3]
    params = _args.array(params, "params", (size * robot.n,))
    names = robot.parameter_names(rotor=True, friction=True)
    cols = [k for k in range(size) if names[k].startswith("Fc")]
    p = np.asarray(params, dtype=float).reshape(robot.n, size)
    fc = np.abs(p[:, cols]).sum(axis=1) if cols else np.zeros(robot.n)
    T = robot.drive_matrix
    # the slots are the motors' only with one motor per joint (Robot.parameters), else the joints'
    return np.abs(T).T @ fc if robot.drive_side == "motor" and T.shape[0] == robot.n else fc


def friction_bound(robot: Robot, *, tolerance=None) -> tuple[np.ndarray, np.ndarray]:
    """``(kp_min, tolerance)`` (n,) each: the smallest position gain ``K_P`` [N m/rad | N/m]
    that holds each joint within ``tolerance`` (a number or n, in the joint's unit; default
    :data:`DEFAULT_TOLERANCE`) against its Coulomb friction (:func:`coulomb_friction` of the
    description): ``K_P >= 2 Fc / (s tolerance)``, the friction's share ``s``
    (:data:`FRICTION_SHARE`) of the tolerance.

    At a velocity reversal the model's Coulomb term (on the reference velocity, or left out)
    and the robot's (on its own velocity) differ by up to ``2 Fc``, a torque the feedback
    alone must hold: a PD loop ``-K_P e - K_D de`` settles where ``K_P |e| = 2 Fc`` (and the
    velocity loop keeps ``|de|`` within ``Fc / K_D``), so ``|e| <= 2 Fc / K_P``; below the bound
    the error that friction leaves is larger than the tolerance, and a joint whose friction
    exceeds its gains by far wanders (the loop never corrects an error of less than
    ``Fc / K_P``)."""
    _args.instance(robot, "robot", Robot)
    rev = np.array([t != "prismatic" for t in robot.joint_types])
    if tolerance is None:
        tol = np.where(rev, *DEFAULT_TOLERANCE)
    else:
        tol = (
            np.full(robot.n, _args.number(tolerance, "tolerance", positive=True))
            if np.ndim(tolerance) == 0
            else _args.array(tolerance, "tolerance", (robot.n,))
        )
        if not np.all(np.isfinite(tol) & (tol > 0)):
            raise _args.fail(
                "tolerance", f"must be positive and finite, got {np.asarray(tolerance).tolist()}"
            )
    fc = coulomb_friction(robot, plant_parameters(robot, True))
    return 2.0 * fc / (FRICTION_SHARE * tol), np.array(tol, dtype=float)


def _unit(robot: Robot, i: int, value: float, what: str) -> str:
    """``value`` of joint ``i`` in degrees / mm (``what`` "angle") or N m/rad / N/m ("gain")."""
    prismatic = robot.joint_types[i] == "prismatic"
    if what == "angle":
        return f"{value * 1e3:.3g} mm" if prismatic else f"{math.degrees(value):.3g} deg"
    return f"{value:.3g} N/m" if prismatic else f"{value:.3g} N m/rad"


def default_gains(
    robot: Robot, *, period: float = 0.004, rotor: bool | None = None, tolerance=None
) -> Gains:
    """Default gains, stable at the controller ``period`` [s] for the simulated robot with
    rotor inertia (``rotor=True``), without (``False``) or either (``None``), and holding each
    joint within ``tolerance`` (a number or n; default :data:`DEFAULT_TOLERANCE`) against its
    Coulomb friction.

    ``zcr07s``: the ZCR07S study's gains when their sampled loops are stable at ``period``
    (otherwise the note says so and the derived gains follow). Derived gains, from the mass
    matrix sampled over the workspace (:func:`~mindyn.control.stability.workspace_samples`):
    ``K_D,i = 40 m_i`` with ``m_i = 1 / max_q (M^-1(q))_ii`` the smallest effective inertia of
    joint ``i`` (the other joints free; ``M`` with and without rotor inertia as ``rotor`` says)
    and ``Lambda = 10``, lowered where the period requires (``K_D,i`` to ``2 m_i / (3 T)``,
    ``Lambda`` to ``1 / (3 T)``, then all gains by one factor) until the sampled loops of PD,
    computed torque and adaptive PD with the true model (:func:`check_gains`) keep a gain
    margin of :data:`~mindyn.control.stability.GAIN_MARGIN`.

    The lower bound: each joint's position gain must reach ``kp_min = 2 Fc / tolerance``
    (:func:`friction_bound`): ``Lambda_i`` is raised (up to ``1 / (3 T)``) until the computed
    torque's ``min_q M_ii Lambda_i^2`` reaches it, then ``K_D,i`` until ``Lambda_i K_D,i``
    (PD, adaptive PD) does; the lowering for the period stops at these floors. Where a
    controller's loop cannot have both at ``period`` (its gain margin below
    :data:`~mindyn.control.stability.GAIN_MARGIN` at the floors, or, computed torque,
    ``Lambda_i`` above ``1 / (3 T)``), ``conflicts[kind]`` holds a one-line message naming
    the joint and a period that allows both (found by halving the period), and
    :func:`make_controller` refuses that controller with these gains. With ``rotor=None``
    and a conflict on either plant, the gains are derived without the lower bound and the note
    says so (the friction of a geared robot's description belongs to its drives: without their
    rotor inertia a wrist is far lighter than the robot's).

    Adaptation gains 1 with the step normalised by ``nu = 3 Gamma T / min K_D`` (the sampled
    update is an integral action on ``s`` of gain ``K_I = T Y Gamma Y^T / (1 + nu |Y|^2)`` per
    period, stable for ``lambda_max(K_D^-1/2 K_I K_D^-1/2) < 1``,
    :func:`~mindyn.control.stability.adaptation_step_ratio`; this ``nu`` keeps it below a third
    for any ``Y``). ``kp`` for PD is ``Lambda K_D``; computed torque uses ``K_P = Lambda^2``,
    ``K_D = 2 Lambda``. The result's ``note`` states the choice, the friction bound and the
    margins; ``note_for(controller)`` what of it concerns one controller (its own margin, the
    adaptation gains for adaptive PD only)."""
    _args.instance(robot, "robot", Robot)
    _args.optional(_args.flag, rotor, "rotor")
    T = check_period(period)
    kp_min, tol = friction_bound(robot, tolerance=tolerance)
    g = _default_gains(robot, T, rotor, kp_min, tol)
    if rotor is None and g.conflicts:  # no gains hold the friction on both plants: unbound
        which = ", ".join(g.conflicts)
        g = _default_gains(robot, T, rotor, np.zeros(robot.n), tol)
        g.add_note(
            f"NOT held against Coulomb friction ({which} cannot hold K_P >= 2 Fc / "
            f"({FRICTION_SHARE:g} tolerance) on the robot both with and without rotor inertia "
            f"at {T:g} s): the error friction leaves is up to 2 Fc / K_P; derive the gains for "
            "one of them (rotor True or False)"
        )
        return g
    for kind in list(g.conflicts):
        shorter = T
        for _ in range(12):  # down to T / 4096
            shorter /= 2.0
            if shorter < MIN_PERIOD:
                shorter = 0.0
                break
            if kind not in _default_gains(robot, shorter, rotor, kp_min, tol).conflicts:
                break
        else:
            shorter = 0.0
        g.conflicts[kind] += (
            f" at a period of {T:g} s"
            + (f"; a period of {shorter:.3g} s allows both" if shorter else "; no period does")
            + " (or give gains, or a larger tracking tolerance)"
        )
        g.add_note(f"{kind} REFUSED with these gains: {g.conflicts[kind]}", [kind])
    return g


def _default_gains(robot: Robot, T: float, rotor, kp_min, tol) -> Gains:
    """:func:`default_gains` at ``T`` with the friction floors ``kp_min`` (of ``tol``), the
    conflicts without the period that resolves them."""
    from .stability import GAIN_MARGIN, workspace_samples

    qs = workspace_samples(robot)

    def checks(g):
        return [check_gains(robot, g, kind=k, period=T, rotor=rotor, qs=qs) for k in CONTROLLERS]

    def margin_text(cs):
        return ", ".join(f"{c.kind} {c.gain_margin:.3g}" for c in cs)

    def add_margins(g, cs):  # every loop's in the note, each controller's own in its view
        g.add_note(f"gain margins of the sampled loops at {T:g} s: {margin_text(cs)}", [])
        for c in cs:
            text = f"gain margin of the sampled {c.kind} loop at {T:g} s: {c.gain_margin:.3g}"
            g.add_note(text, [c.kind], general=False)

    where = {None: "with or without rotor inertia", True: "with rotor inertia"}.get(
        rotor, "without rotor inertia"
    )
    prefix = ""
    if robot.name == "zcr07s" and robot.n == 6:
        g = Gains(
            {k: (list(v) if isinstance(v, list) else v) for k, v in ZCR07S_STUDY_GAINS.items()}
        )
        g.conflicts = {}
        lam_ok = np.all(np.asarray(g["lambda"]) * T < 2.0)
        cs = checks(g) if lam_ok else []
        if lam_ok and all(c.stable for c in cs):
            g.note = (
                f"gains: the ZCR07S study's (K_D {g['kd']}, Lambda {g['lambda']}), stable at "
                f"{T:g} s for the robot {where}"
            )
            add_margins(g, cs)
            return g
        why = next((c.text() for c in cs if not c.stable), f"Lambda T >= 2 at {T:g} s")
        prefix = f"the ZCR07S study's gains are NOT stable at this period ({why}); instead "
    masses = [robot.mass_matrix(qs, plant_parameters(robot, r)) for r in _rotor_cases(rotor)]
    inv = [np.linalg.inv(m) for m in masses]
    m_eff = 1.0 / np.max([np.diagonal(m, axis1=1, axis2=2).max(0) for m in inv], axis=0)
    m_diag = np.min([np.diagonal(m, axis1=1, axis2=2).min(0) for m in masses], axis=0)
    lam_max = 1.0 / (GAIN_MARGIN * T)
    lam = np.full(robot.n, min(DEFAULT_LAMBDA, lam_max))
    kd = np.minimum(DEFAULT_KD_PER_INERTIA, 2.0 / (GAIN_MARGIN * T)) * m_eff
    # the friction floors: computed torque's M_ii Lambda^2, then PD's Lambda K_D
    lam_ct = np.sqrt(kp_min / m_diag)
    lam_floor = np.minimum(lam_ct, lam_max)
    lam = np.maximum(lam, lam_floor)
    # where computed torque cannot reach the floor anyway (refused below), Lambda up to
    # 2 / (3 T) (Lambda T < 2 with the margin) before K_D: a joint whose viscous friction is
    # fast beside the period tolerates K_P, not K_D
    up = (lam_ct > lam_max) & (kp_min > lam * kd)
    lam_floor = np.where(up, 2.0 * lam_max, lam_floor)
    lam = np.maximum(lam, lam_floor)
    kd = np.maximum(kd, kp_min / lam)
    conflicts = {}
    short = np.flatnonzero(lam_ct > lam_max * (1 + 1e-12))
    if short.size:
        i = int(short[np.argmax(lam_ct[short] / lam_max)])
        conflicts["computed-torque"] = (
            f"joint {i + 1}: its Coulomb friction needs K_P >= {_unit(robot, i, kp_min[i], 'gain')}"
            f" (2 Fc / {FRICTION_SHARE:g} of a tolerance of {_unit(robot, i, tol[i], 'angle')}),"
            " computed torque "
            f"Lambda >= {lam_ct[i]:.4g} on its inertia {m_diag[i]:.3g}, and a sampled loop "
            f"with a gain margin of {GAIN_MARGIN:g} needs Lambda <= 1 / ({GAIN_MARGIN:g} T)"
        )
    scale = 1.0
    for _ in range(40):
        lam_s = np.maximum(scale * lam, lam_floor)
        kd_s = np.maximum(scale * kd, kp_min / lam_s)
        g = Gains(kd=kd_s.tolist(), **{"lambda": lam_s.tolist()}, gamma=1.0)
        g["nu"] = GAIN_MARGIN * g["gamma"] * T / min(g["kd"])
        cs = checks(g)
        low = [c for c in cs if c.gain_margin < GAIN_MARGIN and c.kind not in conflicts]
        if not low:
            break
        floored = np.all(kd_s <= kp_min / lam_s * (1 + 1e-9))
        if floored and scale * lam.max() <= lam_floor.min():
            break
        worst = min(c.gain_margin for c in low)
        scale *= max(0.1, min(0.9, worst / GAIN_MARGIN))
    if low and np.all(kp_min == 0):
        raise ControllerSettingError(
            f"no default gains keep a gain margin of {GAIN_MARGIN:g} at a period of {T:g} s "
            f"for '{robot.name}' (margins {margin_text(cs)}): give gains"
        )
    held = kp_min > 0
    for c in low:
        at_floor = np.flatnonzero(held & (kd_s <= kp_min / lam_s * (1 + 1e-9)))
        # the joint whose floor is hardest on the sampled loop: largest K_P T^2 / m
        stiff = kp_min * T * T / m_eff
        i = int(at_floor[np.argmax(stiff[at_floor])]) if at_floor.size else int(np.argmax(stiff))
        conflicts[c.kind] = (
            f"joint {i + 1}: its Coulomb friction needs K_P >= {_unit(robot, i, kp_min[i], 'gain')}"
            f" (2 Fc / {FRICTION_SHARE:g} of a tolerance of {_unit(robot, i, tol[i], 'angle')}),"
            " and the sampled "
            f"{c.kind} loop with it keeps a gain margin of {c.gain_margin:.3g}, below "
            f"{GAIN_MARGIN:g}"
        )
    g.conflicts = conflicts
    lowered = scale < 1.0 or np.any(lam < DEFAULT_LAMBDA)
    raised = np.flatnonzero(
        held & (kd_s * lam_s > (DEFAULT_LAMBDA * DEFAULT_KD_PER_INERTIA * m_eff) * (1 + 1e-9))
    )
    bound = (
        f"; held against Coulomb friction: K_P >= 2 Fc / ({FRICTION_SHARE:g} tolerance) (joint "
        + ", ".join(
            f"{i + 1} {_unit(robot, i, kp_min[i], 'gain')}" for i in np.flatnonzero(held).tolist()
        )
        + "; tolerance "
        + ", ".join(sorted({_unit(robot, i, t, "angle") for i, t in enumerate(tol)}))
        + (
            f"; Lambda and K_D raised to it on joint(s) {', '.join(str(i + 1) for i in raised)}"
            if raised.size
            else ""
        )
        + ")"
        if held.any()
        else "; no Coulomb friction to hold"
    )
    lowered_text = f", lowered for the period {T:g} s" if lowered else ""
    kd_text = f"K_D = {DEFAULT_KD_PER_INERTIA:g} x the smallest effective inertia of each joint"
    lam_text = f"Lambda = {DEFAULT_LAMBDA:g}"
    # the values themselves, which a controller elsewhere takes (what --gains reads)
    kd_values = f"K_D {_gain_text(g['kd'])}"
    lam_values = f"Lambda {_gain_text(g['lambda'])}"
    g.note = ""
    g.add_note(
        f"{prefix}gains: {kd_text}, {lam_text}{lowered_text}: {kd_values}, {lam_values}",
        ["adaptive-pd"],
    )
    pd_head = (
        f"{prefix}gains: {kd_text}, {lam_text} (K_P = Lambda K_D){lowered_text}: {kd_values}, "
        f"{lam_values}"
    )
    g.add_note(pd_head, ["pd"], general=False)
    ct_head = (
        f"{prefix}gains: {lam_text} (K_P = Lambda^2, K_D = 2 Lambda){lowered_text}: {lam_values}"
    )
    g.add_note(ct_head, ["computed-torque"], general=False)
    g.add_note(
        bound.removeprefix("; ") + f" (mass matrix sampled at {len(qs)} configurations, "
        f"robot {where})"
    )
    g.add_note(
        f"adaptation gains 1 normalised by nu = {g['nu']:.3g} (= {GAIN_MARGIN:g} Gamma T / min "
        "K_D: the sampled update's step condition, T lambda_max(K_D^-1/2 Y Gamma Y^T "
        "K_D^-1/2) / (1 + nu |Y|^2) < 1, kept below a third for any Y)",
        ["adaptive-pd"],
    )
    add_margins(g, cs)
    return g


def _reject_duplicate_keys(path: Path):
    """A YAML safe loader that refuses a mapping with a key twice (PyYAML keeps the last)."""
    import yaml

    from .._yaml import SafeLoader

    class Loader(SafeLoader):
        pass

    def mapping(loader, node, deep=False):
        seen = set()
        for key_node, _ in node.value:
            key = loader.construct_object(key_node, deep=deep)
            if not isinstance(key, Hashable):
                break  # a list or a mapping as a key: construct_mapping refuses it, with where
            if key in seen:
                mark = key_node.start_mark
                raise ControllerSettingError(
                    f"{path}:{mark.line + 1}:{mark.column + 1}: key '{key}' appears twice"
                )
            seen.add(key)
        return loader.construct_mapping(node, deep=deep)

    Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, mapping)
    return Loader


def _yaml_number(v):
    """A YAML value as a float: numbers, and strings that are numbers (YAML 1.1 reads ``1e3``
    as a string); None for anything else (booleans, words, lists, mappings)."""
    if isinstance(v, bool):
        return None  # true/false, yes/no, on/off
    if isinstance(v, (int, float)):
        return float(v)
    if isinstance(v, str):
        try:
            return float(v)
        except ValueError:
            return None
    return None


def _gain_text(value) -> str:
    """A gain (a number or a list of numbers) in a note, 4 significant digits."""
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(f"{float(v):.4g}" for v in value) + "]"
    return f"{float(value):.4g}"


def load_gains(
    path: str | Path, robot: Robot, *, period: float = 0.004, rotor=None, tolerance=None
) -> Gains:
    """Gains from a YAML file with keys ``kd``, ``lambda``, ``gamma``, ``nu`` (adaptation-step
    normalisation, a scalar), ``kp`` (numbers or lists of numbers; a key given twice, a boolean
    or a string is refused; missing keys take :func:`default_gains` at ``period`` for
    ``rotor`` and ``tolerance``)."""
    _args.path(path, "path")
    _args.instance(robot, "robot", Robot)
    _args.optional(_args.flag, rotor, "rotor")
    path = Path(path)
    if not path.is_file():
        from .._core import RobotFileNotFoundError

        raise RobotFileNotFoundError(f"gains file '{path}' does not exist")
    from .. import _yaml
    from ..identification.data import decode_text

    data = _yaml.load(
        decode_text(path), path, ControllerSettingError, loader=_reject_duplicate_keys(path)
    )
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ControllerSettingError(
            f"{path}: expected a mapping with keys kd, lambda, gamma, nu, kp"
        )
    unknown = {str(k) for k in data} - {"kd", "lambda", "gamma", "nu", "kp"}
    if unknown:
        raise ControllerSettingError(
            f"{path}: unknown key(s) {', '.join(sorted(unknown))}; "
            "expected kd, lambda, gamma, nu, kp"
        )
    gains = default_gains(robot, period=period, rotor=rotor, tolerance=tolerance)
    given = []
    for key, value in data.items():
        items = value if isinstance(value, list) else [value]
        numbers = [_yaml_number(v) for v in items]
        bad = [v for v, x in zip(items, numbers) if x is None]
        if bad or not items:
            what = f"{bad[0]!r}" if bad else "an empty list"
            if bad and isinstance(bad[0], bool):
                what = f"the boolean {str(bad[0]).lower()} (YAML reads true/false/yes/no/on/off so)"
            raise ControllerSettingError(
                f"{path}: '{key}' must be a number or a list of numbers, got {what}"
            )
        arr = np.asarray(numbers if isinstance(value, list) else numbers[0], dtype=float)
        if key == "nu" and (arr.ndim != 0 or not arr >= 0):
            raise ControllerSettingError(f"{path}: 'nu' must be one number >= 0")
        if key in ("kd", "lambda", "kp"):  # per joint (gamma: per base parameter, checked there)
            try:
                _diag(arr, robot.n, key)
            except ControllerSettingError as e:
                raise ControllerSettingError(f"{path}: {e}") from None
        gains[key] = arr.tolist()
        given.append(key)
    if given:
        gains.conflicts = {}  # the file's gains are the caller's choice
        gains.defaulted = frozenset(k for k in ("kd", "lambda", "gamma", "nu") if k not in given)
        gains.note = f"gains: {', '.join(given)} from {path}"
        rest = [k for k in ("kd", "lambda", "gamma", "nu") if k in gains.defaulted]

        def defaults(keys) -> str:  # the defaults' values; their margins were checked for them
            return ", ".join(
                f"{k} {_gain_text(gains[k])}" if k in gains else f"{k} 0 (no normalisation)"
                for k in keys
            )

        if rest:  # every controller's note lists them all; each controller's, those it uses
            gains.add_note("the rest by default: " + defaults(rest), ())
            uses = {
                "pd": ("kd",) if "kp" in given else ("kd", "lambda"),
                "computed-torque": () if "kp" in given else ("lambda",),
                "adaptive-pd": ("kd", "lambda", "gamma", "nu"),
            }
            for controller, keys in uses.items():
                used = [k for k in rest if k in keys]
                if used:
                    gains.add_note(
                        "the rest by default: " + defaults(used), [controller], general=False
                    )
        lam = "the file's Lambda" if "lambda" in given else "the default Lambda"
        gains.add_note(
            "PD: K_P = " + ("the file's kp" if "kp" in given else f"{lam} x K_D"),
            ["pd"],
            general=False,
        )
        if "kp" in given:
            ct = "computed torque: the file's kp as K_P, K_D = " + (
                "the file's kd [1/s]" if "kd" in given else "2 sqrt(K_P) [1/s] (critical damping)"
            )
        else:
            ct = f"computed torque: K_P = Lambda^2, K_D = 2 Lambda [1/s] with {lam}" + (
                f" (the file's kd, a torque gain of PD and adaptive PD, is not used; give kp "
                f"and kd together in {path} to set computed torque's own)"
                if "kd" in given
                else ""
            )
        gains.add_note(ct, ["computed-torque"], general=False)
        if "kp" in given:  # Slotine-Li's position gain is Lambda K_D
            gains.add_note(
                "adaptive PD: the file's kp is not used (its position gain is Lambda K_D)",
                ["adaptive-pd"],
                general=False,
            )
    return gains


def perturbed_parameters(p, fraction: float, *, seed: int = 0) -> np.ndarray:
    """``p * (1 + fraction * u)``, ``u`` uniform in [-1, 1] per entry (seeded). On base
    parameters the result need not be a physical robot's: combinations that nearly cancel (a
    light wrist's) can give an estimate whose mass matrix is not positive definite;
    :func:`consistent_perturbation` perturbs the classical parameters instead."""
    p = _args.array(p, "p", (None,))
    fraction = _args.number(fraction, "fraction", minimum=0.0)
    seed = _args.integer(seed, "seed", 0)
    p = np.asarray(p, dtype=float)
    u = np.random.default_rng(seed).uniform(-1.0, 1.0, p.shape)
    return p * (1.0 + fraction * u)


def consistent_perturbation(robot: Robot, params, fraction: float, *, seed: int = 0) -> np.ndarray:
    """Classical parameters ``params`` (the full layout, :func:`plant_parameters`) of ``robot``
    perturbed the way a physical robot can be (seeded): each link's 4x4 pseudo-inertia ``J``
    becomes ``D J D`` with ``D = diag(sqrt(|1 + fraction u|))``, ``u`` uniform in [-1, 1] (four
    per link), so that its mass and its second moments along the link frame's axes are off by
    up to ``fraction`` (its first moments by the geometric mean of the two factors) and ``J``
    stays positive semidefinite; each rotor inertia and friction coefficient is multiplied by
    ``|1 + fraction u|``. The mass matrix of the result is positive definite wherever that of
    ``params`` is, which :func:`perturbed_parameters` on base parameters does not keep."""
    from ..identification.consistent import inertial_from_pseudo, pseudo_inertia

    _args.instance(robot, "robot", Robot)
    size = robot.layout_sizes[3]
    params = _args.array(params, "params", (size * robot.n,))
    fraction = _args.number(fraction, "fraction", minimum=0.0)
    seed = _args.integer(seed, "seed", 0)
    full = np.array(params, dtype=float).reshape(robot.n, size)
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1.0, 1.0, (robot.n, 4))
    v = rng.uniform(-1.0, 1.0, (robot.n, size - 10))
    for link, d in enumerate(np.sqrt(np.abs(1.0 + fraction * u))):
        full[link, :10] = inertial_from_pseudo(d[:, None] * pseudo_inertia(full[link, :10]) * d)
    full[:, 10:] *= np.abs(1.0 + fraction * v)
    return full.reshape(-1)


#: The controllers :func:`make_controller` makes, by name (``--controller`` on the command line).
CONTROLLERS = ("adaptive-pd", "computed-torque", "pd")


def make_controller(
    kind: str,
    robot: Robot,
    gains: dict,
    p_hat=None,
    *,
    base: BaseParameters | None = None,
    period: float = 0.004,
    rotor: bool = True,
    friction: bool = True,
    box=True,
):
    """A controller by name (:data:`CONTROLLERS`) with ``gains`` as from :func:`default_gains` /
    :func:`load_gains`, for the controller ``period`` [s]. ``base`` defaults to the base
    parameters with rotor inertia and friction; ``p_hat`` (base parameters) to the true ones:
    those of the description (its rotor inertia and friction unless ``rotor`` / ``friction`` is
    False), and in :func:`mindyn.control.simulate` those of the simulated robot (its ``rotor``,
    ``friction`` and ``params``: the controller's ``true_model`` is then True).

    ``box`` (adaptive PD): the box on the estimate: True, :func:`estimate_box` about the
    description's values as ``rotor`` and ``friction`` say, ``p_hat`` projected onto it (its
    note is the controller's ``box_note``; :func:`mindyn.control.simulate` derives it again
    for the simulated robot when ``p_hat`` is its own); False, none; or ``(p_min, p_max)``."""
    _args.choice(kind, "kind", CONTROLLERS)
    _args.instance(robot, "robot", Robot)
    _args.mapping(gains, "gains")
    _args.optional(_args.instance, base, "base", BaseParameters)
    rotor, friction = _args.flag(rotor, "rotor"), _args.flag(friction, "friction")
    if kind not in CONTROLLERS:
        raise ControllerSettingError(f"unknown controller '{kind}'; use {', '.join(CONTROLLERS)}")
    n = robot.n
    period = check_period(period)
    conflict = getattr(gains, "conflicts", {}).get(kind)
    if conflict:
        raise ControllerSettingError(f"default gains for {kind}: {conflict}")
    kp, kd, lam = _gain_arrays(kind, gains, n)
    check_sampled_gains(kind, kp, kd, lam, period)
    if kind == "pd":
        return PD(n, kp, kd)
    base = base if base is not None else base_parameters(robot, rotor=True, friction=True)
    true = p_hat is None
    if true:
        p_hat = base_values(base, plant_parameters(robot, rotor, friction=friction))
    if kind == "computed-torque":
        ctl = ComputedTorque(base, p_hat, kp, kd)
    else:
        lo = hi = None
        if box is not True and box is not False and box is not None:
            if not (isinstance(box, (tuple, list)) and len(box) == 2):
                raise ControllerSettingError("box must be True, False or (p_min, p_max)")
            lo, hi = box
        ctl = AdaptivePD(
            base,
            kd,
            lam,
            gains.get("gamma", 1.0),
            p_hat,
            nu=gains.get("nu", 0.0),
            period=period,
            p_min=lo,
            p_max=hi,
        )
        if box is True:
            ctl.derive_box(rotor=rotor, friction=friction)
        elif lo is not None:
            ctl.box, ctl.box_note = "given", "estimate box: given"
        else:
            ctl.box_note = "estimate box: none"
    ctl.true_model = true
    return ctl


def friction_shortfall(
    robot: Robot, *, rotor: bool = True, omega: float = 20.0, tolerance=None
) -> str:
    """For :func:`default_controller` (``K_P = omega^2`` on the mass matrix) on the robot with
    (``rotor``) or without its rotor inertia: one line naming the joints where its position gain
    ``omega^2 min_q M_ii`` (the mass matrix sampled over the workspace) leaves Coulomb friction an
    error ``2 Fc / K_P`` above the friction's share of ``tolerance`` (:func:`friction_bound`),
    with that error; empty when none does."""
    _args.instance(robot, "robot", Robot)
    rotor = _args.flag(rotor, "rotor")
    omega = _args.number(omega, "omega", positive=True)
    from .stability import workspace_samples

    kp_min, tol = friction_bound(robot, tolerance=tolerance)
    qs = workspace_samples(robot)
    m = np.diagonal(robot.mass_matrix(qs, plant_parameters(robot, rotor)), axis1=1, axis2=2)
    kp = omega**2 * m.min(axis=0)
    short = np.flatnonzero(kp < kp_min)
    if not short.size:
        return ""
    error = kp_min * FRICTION_SHARE * tol / kp  # 2 Fc / K_P
    return (
        f"the default computed torque (K_P = {omega:g}^2 M) leaves Coulomb friction an error "
        "2 Fc / K_P above half the tracking tolerance on joint(s) "
        + ", ".join(f"{i + 1} (up to {_unit(robot, i, error[i], 'angle')})" for i in short.tolist())
        + ": the joints may wander at velocity reversals (the gains of default_gains hold it "
        "or are refused)"
    )


def model_friction_shortfall(
    robot: Robot,
    base: BaseParameters,
    p_hat,
    kp,
    *,
    tolerance=None,
    share: float = FRICTION_SHARE,
    qs=None,
) -> str:
    """For computed torque of model ``(base, p_hat)`` and acceleration gain ``kp`` [1/s²]:
    one line naming the joints where its position gain as a torque, ``K_P min_q M̂_ii`` (the
    model's mass matrix, sampled over the workspace or at ``qs``), is below the bound that
    holds the robot's Coulomb friction within ``share`` of ``tolerance`` (by default the share
    the default gains give it, :func:`friction_bound`; 1: the whole tolerance), with that
    torque gain and the error ``2 Fc / (K_P M̂_ii)``; empty when none is. The default gains
    raise ``Lambda`` for the robot's own inertia: a model with less inertia (no rotor inertia,
    where a geared joint's reflected rotor inertia dominates its link's) scales the torque
    gains down by the ratio."""
    from .stability import workspace_samples

    _args.instance(robot, "robot", Robot)
    _args.instance(base, "base", BaseParameters)
    if base.robot.n != robot.n:
        raise _args.fail("base", f"has {base.robot.n} joints; the robot has {robot.n}")
    n = robot.n
    p_hat = _estimate(p_hat, base, "p_hat")
    if isinstance(kp, numbers.Real) and not isinstance(kp, (bool, np.bool_)):
        kp = np.full(n, _args.number(kp, "kp", minimum=0.0))
    else:
        kp = _args.array(kp, "kp", (n,))
        if np.any(kp < 0):
            raise _args.fail("kp", f"must be >= 0, got {kp.tolist()}")
    share = _args.number(share, "share", positive=True)
    if share > 1:
        raise _args.fail("share", f"must be in (0, 1], got {share:g}")
    kp_min, tol = friction_bound(robot, tolerance=tolerance)
    kp_min = kp_min * FRICTION_SHARE / share
    qs = _args.optional(_args.array, qs, "qs", (None, n))
    qs = workspace_samples(robot) if qs is None else qs
    k = len(qs)
    eye = np.broadcast_to(np.eye(n), (k, n, n)).reshape(k * n, n)
    qq = np.repeat(qs, n, axis=0)
    grav = base.regressor(qs, np.zeros_like(qs), np.zeros_like(qs)) @ p_hat
    cols = (base.regressor(qq, np.zeros_like(qq), eye) @ p_hat).reshape(k, n, n)
    m_diag = np.min(np.diagonal(cols, axis1=1, axis2=2) - grav, axis=0)  # min_q M̂_ii
    gain = kp * m_diag
    short = np.flatnonzero(gain < kp_min * (1.0 - 1e-9))
    if not short.size:
        return ""
    error = kp_min * share * tol / np.maximum(gain, 1e-300)  # 2 Fc / (K_P M̂_ii)
    within = {1.0: "the whole", 0.5: "half the"}.get(share, f"{share:g} of the")
    return (
        "computed torque's model gives its position gain K_P M_ii (M_ii: the model's inertia, "
        "the smallest over the workspace) below the bound that holds Coulomb friction within "
        f"{within} tracking tolerance on joint(s) "
        + ", ".join(
            f"{i + 1} ({_unit(robot, i, gain[i], 'gain')} against "
            f"{_unit(robot, i, kp_min[i], 'gain')}: errors up to "
            f"{_unit(robot, i, error[i], 'angle')})"
            for i in short.tolist()
        )
    )


def default_controller(
    robot: Robot, params, *, omega: float = 20.0, coulomb_smoothing: float = 0.0
):
    """The controller of the simulated logs: computed torque with the true parameters ``params``
    (classical, 13 per joint), Coulomb friction as a feedforward on the reference velocity, and
    ``K_P = omega^2``, ``K_D = 2 omega`` (critical damping at ``omega`` rad/s)."""
    _args.instance(robot, "robot", Robot)
    params = _args.array(params, "params", (robot.layout_sizes[3] * robot.n,))
    omega = _args.number(omega, "omega", positive=True)
    coulomb_smoothing = _args.number(coulomb_smoothing, "coulomb_smoothing", minimum=0.0)
    base = base_parameters(robot, rotor=True, friction=True)
    return ComputedTorque(
        base,
        base.values(params),
        omega**2,
        2 * omega,
        coulomb="reference",
        coulomb_smoothing=coulomb_smoothing,
    )
