"""Stability of the sampled joint loops: the controller reads the state every period ``T`` and
holds its torque (zero-order hold), so gains that a continuous loop tolerates can make the
sampled loop diverge.

The check linearises the closed loop about rest at configurations sampled over the workspace:
the robot is ``M(q) dde = u`` over one period (gravity and velocity terms are slow beside the
feedback), and each controller is a PD law on ``e = q - q_d`` with effective gains

- PD: ``u = -K_P e - K_D de``;
- computed torque: ``u = M_hat (-K_P e - K_D de)`` (``M_hat``: the controller's model);
- adaptive PD: ``u = M_hat ddq_r - K_D s = -(K_D Lambda) e - (K_D + M_hat Lambda) de`` (the
  feedforward ``Y p_hat`` holds ``M_hat ddq_r`` with ``ddq_r = ddq_d - Lambda de``).

One period of ``M dde = u`` with ``u`` held is exactly ``x_{k+1} = Phi x_k``, ``x = (e, de)``::

    Phi = [[I - T^2/2 B K_P,  T I - T^2/2 B K_D],
           [   -T B K_P,          I - T B K_D   ]]      B = M^-1

and the loop is stable when the spectral radius of ``Phi`` is below 1 at every sampled
configuration. For one joint of inertia ``m`` this is ``0 < K_D T / m < 2`` and
``K_P T < 2 K_D`` (the Jury conditions of its characteristic polynomial). The figures reported
are the spectral radius, the *gain margin* (the factor by which all gains could grow before the
loop goes unstable) and the *gain/period ratio* ``max |eig(T M^-1 K_D,eff)|``, which a sampled
loop needs below 2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .. import _args
from .._core import Error
from ..robot import Robot

__all__ = [
    "GAIN_MARGIN",
    "LoopCheck",
    "UnstableLoopError",
    "check_loop",
    "loop_matrix",
    "workspace_samples",
]

#: The gain margin the default gains keep at every sampled configuration: the gains could be
#: this many times larger (or the inertia this many times smaller, the period this many times
#: longer, about) before the sampled loop goes unstable.
GAIN_MARGIN = 3.0
#: Configurations at which the mass matrix is sampled (the middle of the limits and random ones).
SAMPLES = 24
#: Largest gain margin searched (a margin above it is reported as at least this).
_MARGIN_CAP = 1e3


class UnstableLoopError(Error, ValueError):
    """The sampled closed loop is unstable (by the linearised check or because the simulated
    tracking error grew without bound)."""


def loop_matrix(kp, kd, minv, period: float) -> np.ndarray:
    """``Phi`` of one period of ``M dde = u``, ``u = -kp e - kd de`` held (module docstring);
    ``kp``, ``kd``: (n, n) or (n,) (diagonal) effective gains, ``minv``: ``M^-1`` (n, n); or
    stacks of them, (k, n, n), giving (k, 2n, 2n)."""
    kp = _args.array(kp, "kp", (None,) * np.ndim(kp))
    kd = _args.array(kd, "kd", (None,) * np.ndim(kd))
    minv = _args.array(minv, "minv", (None,) * np.ndim(minv))
    period = _args.number(period, "period", positive=True)
    minv = np.asarray(minv, dtype=float)
    minv = minv if minv.ndim >= 2 else np.atleast_2d(minv)
    n = minv.shape[-1]
    kp, kd = (np.diag(k) if np.ndim(k) == 1 else np.asarray(k, dtype=float) for k in (kp, kd))
    T = float(period)
    bp, bd = minv @ kp, minv @ kd
    eye = np.broadcast_to(np.eye(n), bp.shape)
    top = np.concatenate([eye - 0.5 * T * T * bp, T * eye - 0.5 * T * T * bd], axis=-1)
    bottom = np.concatenate([-T * bp, eye - T * bd], axis=-1)
    return np.concatenate([top, bottom], axis=-2)


def _radius(kp, kd, minv, T) -> np.ndarray:
    """Spectral radius of each loop of a stack."""
    return np.max(np.abs(np.linalg.eigvals(loop_matrix(kp, kd, minv, T))), axis=-1)


#: Spectral radius above which a loop counts as unstable: 1 plus round-off (a loop with no
#: position gain has an eigenvalue at exactly 1: it drifts but does not diverge).
_UNSTABLE = 1.0 + 1e-9


def _margin(kp, kd, minv, T) -> np.ndarray:
    """For each loop of a stack, the largest factor g (up to ``_MARGIN_CAP``) with the loop of
    ``g kp, g kd`` stable; 0 where the loop is unstable already (bisection on log g, all loops
    at once; the stable set of g is an interval from 0 for the loops here)."""
    stable = _radius(kp, kd, minv, T) <= _UNSTABLE
    capped = _radius(_MARGIN_CAP * kp, _MARGIN_CAP * kd, minv, T) <= _UNSTABLE
    lo = np.zeros(stable.shape)
    hi = np.full(stable.shape, math.log(_MARGIN_CAP))
    for _ in range(14):  # log g to 4e-4: the margin to 0.05 %
        mid = 0.5 * (lo + hi)
        g = np.exp(mid)[:, None, None]
        ok = _radius(g * kp, g * kd, minv, T) <= _UNSTABLE
        lo, hi = np.where(ok, mid, lo), np.where(ok, hi, mid)
    return np.where(~stable, 0.0, np.where(capped, _MARGIN_CAP, np.exp(lo)))


def workspace_samples(robot: Robot, *, count: int | None = None, seed: int = 0) -> np.ndarray:
    """``count`` configurations, shape (count, n): the middle of the limits, then uniform ones
    inside them (joints without limits: revolute in [-pi, pi], prismatic in [-1, 1] m). By
    default :data:`SAMPLES`, fewer beyond 12 joints (``SAMPLES * 12 / n``, at least 6: the check
    costs ``n^3`` per configuration)."""
    _args.instance(robot, "robot", Robot)
    count = _args.optional(_args.integer, count, "count", 1)
    seed = _args.integer(seed, "seed", 0)
    if count is None:
        count = max(6, min(SAMPLES, SAMPLES * 12 // max(robot.n, 1)))
    lim = robot.limits
    rev = np.array([t != "prismatic" for t in robot.joint_types])
    wide = np.where(rev, np.pi, 1.0)
    lo = np.where(np.isfinite(lim["lower"]), lim["lower"], -wide)
    hi = np.where(np.isfinite(lim["upper"]), lim["upper"], wide)
    u = np.random.default_rng(seed).uniform(0.0, 1.0, (max(count, 1) - 1, robot.n))
    return np.vstack([0.5 * (lo + hi), lo + u * (hi - lo)])


def effective_gains(kind: str, kp, kd, lam, m_hat):
    """``(K_P,eff, K_D,eff)`` (..., n, n) of a controller (module docstring); ``kp``, ``kd``,
    ``lam`` diagonals (n,) as the controller holds them, ``m_hat`` the controller's mass matrix
    (n, n) or a stack of them."""
    if kind == "pd":
        return np.diag(kp), np.diag(kd)
    if kind == "computed-torque":
        return m_hat * kp, m_hat * kd  # M_hat @ diag(k)
    return np.diag(kd * lam), np.diag(kd) + m_hat * lam


@dataclass
class LoopCheck:
    """The linearised check of one controller at one period (:func:`check_loop`).

    ``stable``: every sampled loop has spectral radius at most 1; ``gain_margin``: the smallest
    over the samples (0 when unstable); ``spectral_radius`` the largest; ``ratio`` the largest
    ``|eig(T M^-1 K_D,eff)|`` (a sampled loop needs it below 2); ``q`` the configuration of the
    smallest margin; ``cases`` the plant/model pairs checked (text)."""

    kind: str
    period: float
    stable: bool
    gain_margin: float
    spectral_radius: float
    ratio: float
    q: np.ndarray
    cases: list = field(default_factory=list)

    def text(self) -> str:
        """One line: the verdict and the figures that explain it."""
        margin = (
            f"gain margin {self.gain_margin:.3g}"
            if self.gain_margin < _MARGIN_CAP
            else f"gain margin above {_MARGIN_CAP:g}"
        )
        verdict = "stable" if self.stable else "UNSTABLE"
        return (
            f"sampled {self.kind} loop at a period of {self.period:g} s: {verdict} "
            f"(spectral radius {self.spectral_radius:.6g}, {margin}; largest eigenvalue of "
            f"T M^-1 K_D,eff {self.ratio:.3g}, a sampled loop needs it below 2; "
            f"{len(self.q) and 'checked on ' + ', '.join(self.cases)})"
        )

    def error(self, *, what: str = "") -> UnstableLoopError:
        """The error that refuses this loop, ``what`` naming the gains."""
        fix = "lower the gains or the controller period"
        return UnstableLoopError(
            f"{what + ': ' if what else ''}the {self.text()}; {fix}"
            if not self.stable
            else self.text()
        )


def check_loop(
    kind: str,
    kp,
    kd,
    lam,
    period: float,
    plant_inverses,
    models,
    qs: np.ndarray,
    cases: list,
) -> LoopCheck:
    """The check of one controller: ``plant_inverses`` and ``models`` lists of (m, n, n) stacks
    of ``M^-1`` and ``M_hat`` at the configurations ``qs`` (m, n), each plant checked with the
    model beside it; ``cases`` names them."""
    _args.text(kind, "kind")
    kp = _args.array(kp, "kp", (None,) * np.ndim(kp))
    kd = _args.array(kd, "kd", (None,) * np.ndim(kd))
    lam = _args.array(lam, "lam", (None,) * np.ndim(lam))
    period = _args.number(period, "period", positive=True)
    _args.instance(plant_inverses, "plant_inverses", (list, tuple), "a list of arrays")
    _args.instance(models, "models", (list, tuple), "a list of arrays")
    qs = _args.array(qs, "qs", (None, None))
    _args.instance(cases, "cases", (list, tuple), "a list of names")
    T = float(period)
    worst = (math.inf, 0.0, 0.0, None)  # margin, radius, ratio, q
    rho_max, ratio_max = 0.0, 0.0
    for minv, m_hat in zip(plant_inverses, models):
        kpe, kde = effective_gains(kind, kp, kd, lam, m_hat)
        kpe, kde = np.broadcast_to(kpe, minv.shape), np.broadcast_to(kde, minv.shape)
        rho = _radius(kpe, kde, minv, T)
        ratio = np.max(np.abs(np.linalg.eigvals(T * minv @ kde)), axis=-1)
        margin = _margin(kpe, kde, minv, T)
        rho_max, ratio_max = max(rho_max, float(rho.max())), max(ratio_max, float(ratio.max()))
        i = int(np.argmin(margin))
        if margin[i] < worst[0]:
            worst = (float(margin[i]), float(rho[i]), float(ratio[i]), qs[i])
    return LoopCheck(
        kind,
        T,
        worst[0] > 0,
        worst[0],
        rho_max,
        ratio_max,
        np.asarray(worst[3]),
        list(cases),
    )
