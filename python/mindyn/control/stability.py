"""Stability of the sampled joint loops: the controller reads the state every period ``T`` and
holds its torque (zero-order hold), so gains that a continuous loop tolerates can make the
sampled loop diverge.

The check linearises the closed loop about rest at configurations sampled over the workspace.
The robot is ``M(q) dde + D(q) de = u`` over one period, ``D`` the viscous friction's
``d tau / d dq`` (on the motors ``T^T diag(Fv) T``). Each controller is a PD law on
``e = q - q_d`` with effective gains, plus the viscous friction its model feeds back on the
measured velocity, ``D_hat de`` (none for PD):

- PD: ``u = -K_P e - K_D de``;
- computed torque: ``u = M_hat (-K_P e - K_D de) + D_hat de`` (``M_hat``, ``D_hat``: the
  controller's model);
- adaptive PD: ``u = M_hat ddq_r - K_D s + D_hat de = -(K_D Lambda) e - (K_D + M_hat Lambda -
  D_hat) de`` (the feedforward ``Y p_hat`` holds ``M_hat ddq_r + D_hat dq`` with
  ``ddq_r = ddq_d - Lambda de``).

One period of the linear plant with ``u`` held is exactly ``x_{k+1} = A_d x_k + B_d u_k``,
``x = (e, de)``, from the matrix exponential of ``[[0, I, 0], [0, -B D, B], [0, 0, 0]] T``
(``B = M^-1``); without friction it is the closed form::

    Phi = [[I - T^2/2 B K_P,  T I - T^2/2 B K_D],
           [   -T B K_P,          I - T B K_D   ]]

and the loop is stable when the spectral radius of ``Phi = A_d - B_d [K_P  K_D - D_hat]`` is
below 1 at every sampled configuration. For one joint of inertia ``m`` without friction this is
``0 < K_D T / m < 2`` and ``K_P T < 2 K_D`` (the Jury conditions of its characteristic
polynomial). Viscous friction matters where it is fast beside the period: a light link with a
large friction (``Fv T / m`` of 60 on the xArm7's wrist at 4 ms) reaches its friction-limited
speed within a period, so that a model that feeds back more viscous friction than the robot has
(``D_hat > D``) makes the sampled loop diverge unless ``K_D`` outweighs the excess (more gain,
not less). The figures reported are the
spectral radius, the *gain margin* (the factor by which the gains ``K_P``, ``K_D`` could grow,
the model's ``D_hat`` fixed, before the loop goes unstable), the *viscous-friction margin of the
model* (the factor by which ``D_hat`` could grow, the gains fixed; with the true friction it is
barely above 1 where the friction is fast: an adaptive estimate that grows past it diverges)
and the *gain/period ratio* ``max |eig(T M^-1 K_D,eff)|``, which a sampled loop without
friction needs below 2.

Not covered (:data:`COVERED`, stated with each verdict): gravity and the velocity terms (slow
beside the feedback at the periods of joint controllers), Coulomb friction (a relay: it has no
linear part) and the adaptation of adaptive PD (the estimate is taken as it is when checked).
For the adaptation, two conditions of its own, reported beside the verdict by
:func:`mindyn.control.simulate`: the step condition of the sampled update
(:func:`adaptation_step_ratio`, below 1 along the reference), and the box on the estimate
(:func:`deviation_bounds`, :func:`box_fraction`, :func:`mindyn.control.estimate_box`), which
gives each parameter the loop sees a third of a common fraction of the change that alone makes
this check's loop unstable, the fraction one at which the parameters moving together keep it
stable: the gradient, fed
by what the model cannot represent (the torque held over a period, Coulomb friction, noise),
otherwise drifts the estimate there (on the xArm7 at 4 ms, the wrist's viscous friction above
the robot's and its inertia below: the loop diverged after 2.5 s).
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
    "adaptation_step_ratio",
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
#: What the linearised check covers (said with its verdict).
COVERED = (
    "linearised at rest: inertia and viscous friction of the robot and of the controller's "
    "model; not gravity, Coulomb friction or adaptation"
)
#: Largest gain margin searched (a margin above it is reported as at least this).
_MARGIN_CAP = 1e3


class UnstableLoopError(Error, ValueError):
    """The sampled closed loop is unstable (by the linearised check or because the simulated
    tracking error grew without bound)."""


def loop_matrix(kp, kd, minv, period: float, *, damping=None) -> np.ndarray:
    """``Phi`` of one period of ``M dde + D de = u``, ``u = -kp e - kd de`` held (module
    docstring); ``kp``, ``kd``: (n, n) or (n,) (diagonal) effective gains, ``minv``: ``M^-1``
    (n, n), ``damping``: ``D`` (n, n) (default none); or stacks of them, (k, n, n), giving
    (k, 2n, 2n)."""
    kp = _args.array(kp, "kp", (None,) * np.ndim(kp))
    kd = _args.array(kd, "kd", (None,) * np.ndim(kd))
    minv = _args.array(minv, "minv", (None,) * np.ndim(minv))
    period = _args.number(period, "period", positive=True)
    damping = _args.optional(_args.array, damping, "damping", (None,) * np.ndim(damping))
    minv = minv if minv.ndim >= 2 else np.atleast_2d(minv)
    kp, kd = (np.diag(k) if np.ndim(k) == 1 else k for k in (kp, kd))
    return _closed(*plant_step(minv, float(period), damping), kp, kd)


def plant_step(minv, T: float, damping=None) -> tuple[np.ndarray, np.ndarray]:
    """``(A_d, B_d)``, stacks (k, 2n, 2n) and (k, 2n, n): one period ``T`` of
    ``M dde + D de = u`` with ``u`` held, ``x = (e, de)`` (module docstring); the closed form
    without ``damping`` ``D``, else the matrix exponential."""
    n = minv.shape[-1]
    eye = np.broadcast_to(np.eye(n), minv.shape)
    zero = np.zeros(minv.shape)
    if damping is None:
        ad = np.concatenate(
            [np.concatenate([eye, T * eye], -1), np.concatenate([zero, eye], -1)], -2
        )
        return ad, np.concatenate([0.5 * T * T * minv, T * minv], axis=-2)
    from scipy.linalg import expm

    rows = [
        np.concatenate([zero, eye, zero], -1),
        np.concatenate([zero, -minv @ np.broadcast_to(damping, minv.shape), minv], -1),
        np.concatenate([zero, zero, zero], -1),
    ]
    step = expm(np.concatenate(rows, -2) * T)
    return step[..., : 2 * n, : 2 * n], step[..., : 2 * n, 2 * n :]


def _closed(ad, bd, kp, kd) -> np.ndarray:
    """``A_d - B_d [kp kd]``: the sampled loop of the feedback ``u = -kp e - kd de``."""
    return ad - bd @ np.concatenate([kp, kd], axis=-1)


def _radius(ad, bd, kp, kd) -> np.ndarray:
    """Spectral radius of each loop of a stack."""
    return np.max(np.abs(np.linalg.eigvals(_closed(ad, bd, kp, kd))), axis=-1)


#: Spectral radius above which a loop counts as unstable: 1 plus round-off (a loop with no
#: position gain has an eigenvalue at exactly 1: it drifts but does not diverge).
_UNSTABLE = 1.0 + 1e-9


def _scaled_gains(g, ad, bd, kp, kd, fed) -> np.ndarray:
    """Spectral radii of the loops with the gains times ``g``, the model's friction fixed."""
    return _radius(ad, bd, g * kp, g * kd - fed)


def _scaled_friction(g, ad, bd, kp, kd, fed) -> np.ndarray:
    """Spectral radii of the loops with the model's viscous friction times ``g``."""
    return _radius(ad, bd, kp, kd - g * fed)


def _largest_factor(radius, *loops) -> np.ndarray:
    """For each loop of a stack, the largest factor g (up to ``_MARGIN_CAP``) with the loop
    stable, ``radius(g, *loops)`` giving the spectral radii of the loops at factors ``g``
    (k, 1, 1) or (1, 1, 1); 0 where the loop is unstable at g = 1 (bisection on log g from 1,
    all loops at once)."""
    stable = radius(np.ones((1, 1, 1)), *loops) <= _UNSTABLE
    capped = radius(np.full((1, 1, 1), _MARGIN_CAP), *loops) <= _UNSTABLE
    lo = np.zeros(stable.shape)
    hi = np.full(stable.shape, math.log(_MARGIN_CAP))
    for _ in range(14):  # log g to 4e-4: the margin to 0.05 %
        mid = 0.5 * (lo + hi)
        ok = radius(np.exp(mid)[:, None, None], *loops) <= _UNSTABLE
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
    ``|eig(T M^-1 K_D,eff)|`` (a sampled loop without friction needs it below 2); ``q`` the
    configuration of the smallest margin; ``cases`` the plant/model pairs checked (text);
    ``friction_margin`` the factor by which the viscous friction the controller's model feeds
    back could grow, the gains fixed, before a loop goes unstable (the smallest; 0 when
    unstable; None when the model feeds back none): an estimate that adaptation moves past it
    makes the loop diverge. ``stable_gains``, for an unstable loop: the range ``(low, high)`` of
    factors on the gains (``K_P``, ``K_D``; the model's friction fixed) found stable on
    :data:`_GAIN_GRID` (the one nearest 1), None when none is: lowering or raising the gains is
    the next step only where it works (a model feeding back more viscous friction than the
    robot has needs ``K_D`` above the excess, more gain, not less)."""

    kind: str
    period: float
    stable: bool
    gain_margin: float
    spectral_radius: float
    ratio: float
    q: np.ndarray
    cases: list = field(default_factory=list)
    friction_margin: float | None = None
    stable_gains: tuple[float, float] | None = None
    #: adaptive PD along a reference: the adaptation's step condition and box (text, set by
    #: :func:`mindyn.control.simulate`; empty otherwise)
    adaptation: str = ""

    def text(self) -> str:
        """One line: the verdict and the figures that explain it."""
        margin = (
            f"gain margin {self.gain_margin:.3g}"
            if self.gain_margin < _MARGIN_CAP
            else f"gain margin above {_MARGIN_CAP:g}"
        )
        if self.friction_margin is not None:
            margin += (
                f", viscous-friction margin of the controller's model {self.friction_margin:.4g}"
                if self.friction_margin < _MARGIN_CAP
                else f", viscous-friction margin of the controller's model above {_MARGIN_CAP:g}"
            )
        verdict = "stable" if self.stable else "UNSTABLE"
        covered = COVERED  # the adaptation only where there is one
        if self.kind != "adaptive-pd":
            covered = covered.replace(
                "not gravity, Coulomb friction or adaptation", "not gravity or Coulomb friction"
            )
        return (
            f"sampled {self.kind} loop at a period of {self.period:g} s: {verdict} "
            f"(spectral radius {self.spectral_radius:.6g}, {margin}; largest eigenvalue of "
            f"T M^-1 K_D,eff {self.ratio:.3g}, a sampled loop needs it below 2; "
            f"{len(self.q) and 'checked on ' + ', '.join(self.cases) + '; '}{covered})"
            + (f"; {self.adaptation}" if self.adaptation else "")
        )

    def error(self, *, what: str = "") -> UnstableLoopError:
        """The error that refuses this loop, ``what`` naming the gains."""
        return UnstableLoopError(
            f"{what + ': ' if what else ''}the {self.text()}; {self.advice()}"
            if not self.stable
            else self.text()
        )

    def advice(self) -> str:
        """The next step for a loop this check found unstable (the gain factors found stable,
        or the period), or, for one it found stable that diverged all the same, what the check
        leaves out."""
        if self.stable:
            drift = (
                ", such as an adapted model whose viscous friction grew past the margin above"
                if self.friction_margin is not None
                else ""
            )
            return (
                "the check before the run found the loop stable: what it leaves out (gravity, "
                f"Coulomb friction, adaptation) made it diverge{drift}; try a shorter controller "
                "period, other gains or a controller without adaptation"
            )
        friction = (
            "the viscous friction of the controller's model (above the robot's, it makes the "
            "sampled loop diverge where the friction is fast beside the period unless K_D "
            "outweighs the excess)"
            if self.friction_margin is not None
            else ""
        )
        found = self.stable_gains
        if found is None:
            fix = (
                f"no factor on the gains from {_GAIN_GRID[0]:g} to {_GAIN_GRID[-1]:g} makes it "
                "stable: lower the controller period" + (f", or {friction}" if friction else "")
            )
        else:
            low, high = found
            fix = (
                f"{'raise' if low > 1 else 'lower'} the gains: the loop is stable with K_P and "
                f"K_D times {low:.3g} to {high:.3g} (factors from {_GAIN_GRID[0]:g} to "
                f"{_GAIN_GRID[-1]:g} tried)"
                + ("" if low > 1 else " or at a shorter controller period")
                + (f"; or lower {friction}" if friction else "")
            )
        return fix


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
    *,
    plant_damping=None,
    model_damping=None,
) -> LoopCheck:
    """The check of one controller: ``plant_inverses`` and ``models`` lists of (m, n, n) stacks
    of ``M^-1`` and ``M_hat`` at the configurations ``qs`` (m, n), each plant checked with the
    model beside it; ``cases`` names them. ``plant_damping`` and ``model_damping``: lists beside
    them of (m, n, n) stacks (:func:`viscous_damping`), the viscous friction of the plant and
    the one the controller's model feeds back (``None``, or a ``None`` entry: none; a PD
    controller has no model, its ``model_damping`` is ignored)."""
    _args.text(kind, "kind")
    kp = _args.array(kp, "kp", (None,) * np.ndim(kp))
    kd = _args.array(kd, "kd", (None,) * np.ndim(kd))
    lam = _args.array(lam, "lam", (None,) * np.ndim(lam))
    period = _args.number(period, "period", positive=True)
    _args.instance(plant_inverses, "plant_inverses", (list, tuple), "a list of arrays")
    _args.instance(models, "models", (list, tuple), "a list of arrays")
    qs = _args.array(qs, "qs", (None, None))
    _args.instance(cases, "cases", (list, tuple), "a list of names")
    plant_damping = _stacks(plant_damping, "plant_damping", len(plant_inverses))
    model_damping = _stacks(model_damping, "model_damping", len(plant_inverses))
    T = float(period)
    worst = (math.inf, 0.0, 0.0, None)  # margin, radius, ratio, q
    rho_max, ratio_max, friction = 0.0, 0.0, None
    stable_at = np.ones(len(_GAIN_GRID), dtype=bool)  # every loop, at each factor on the gains
    for minv, m_hat, damping, fed in zip(plant_inverses, models, plant_damping, model_damping):
        kpe, kde = effective_gains(kind, kp, kd, lam, m_hat)
        kpe, kde = np.broadcast_to(kpe, minv.shape), np.broadcast_to(kde, minv.shape)
        ad, bd = plant_step(minv, T, damping)
        fed = np.zeros(minv.shape) if fed is None or kind == "pd" else fed
        rho = _radius(ad, bd, kpe, kde - fed)
        ratio = np.max(np.abs(np.linalg.eigvals(T * minv @ kde)), axis=-1)
        margin = _largest_factor(_scaled_gains, ad, bd, kpe, kde, fed)
        if np.any(fed != 0.0):
            f = _largest_factor(_scaled_friction, ad, bd, kpe, kde, fed)
            friction = min(float(f.min()), math.inf if friction is None else friction)
        rho_max, ratio_max = max(rho_max, float(rho.max())), max(ratio_max, float(ratio.max()))
        if not np.all(margin > 0):  # unstable: which factors on the gains would do
            for k, g in enumerate(_GAIN_GRID):
                if stable_at[k]:
                    radii = _scaled_gains(np.full((1, 1, 1), g), ad, bd, kpe, kde, fed)
                    stable_at[k] = bool(np.all(radii <= _UNSTABLE))
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
        friction,
        None if worst[0] > 0 else _stable_range(stable_at),
    )


#: Factors on the gains tried when a loop is unstable (:attr:`LoopCheck.stable_gains`): a
#: quarter of a decade apart, from 1 / _MARGIN_CAP to _MARGIN_CAP.
_GAIN_GRID = np.logspace(-3, 3, 25)


def _stable_range(stable_at: np.ndarray) -> tuple[float, float] | None:
    """The run of consecutive factors of :data:`_GAIN_GRID` marked stable nearest to 1, as
    (smallest, largest), or None."""
    runs, k = [], 0
    while k < len(stable_at):
        if stable_at[k]:
            j = k
            while j + 1 < len(stable_at) and stable_at[j + 1]:
                j += 1
            runs.append((float(_GAIN_GRID[k]), float(_GAIN_GRID[j])))
            k = j
        k += 1
    if not runs:
        return None
    return min(runs, key=lambda r: abs(math.log(max(r[0], min(r[1], 1.0)))))


def _stacks(stacks, name: str, count: int) -> list:
    if stacks is None:
        return [None] * count
    _args.instance(stacks, name, (list, tuple), "a list of arrays or None")
    if len(stacks) != count:
        raise _args.fail(name, f"has {len(stacks)} entries; expected {count}, one per plant")
    return [None if d is None else _args.array(d, name, (None, None, None)) for d in stacks]


def viscous_damping(regressor, names, params, qs) -> np.ndarray:
    """``D``, a stack (m, n, n) at the configurations ``qs`` (m, n): the viscous friction's
    ``d tau / d dq`` of the model ``tau = regressor(q, dq, ddq) @ params`` (``names``: its
    columns; the columns ``Fv*``, linear in the velocity). Coulomb friction is left out (a
    relay: it has no linear part)."""
    qs = np.asarray(qs, dtype=float)
    viscous = np.where([str(x).startswith("Fv") for x in names], params, 0.0)
    m, n = qs.shape
    damping = np.zeros((m, n, n))
    if viscous.any():
        zero = np.zeros_like(qs)
        for j in range(n):
            unit = np.zeros_like(qs)
            unit[:, j] = 1.0
            damping[:, :, j] = regressor(qs, unit, zero) @ viscous
    return damping


def adaptation_step_ratio(Y, kd, gamma, nu: float, period: float) -> np.ndarray:
    """The step condition of the sampled adaptation law (one value per regressor of the stack
    ``Y``, (m, n, p) or (n, p)): ``T lambda_max(K_D^-1/2 Y Gamma Y^T K_D^-1/2) / (1 + nu |Y|^2)``,
    which the discrete update needs below 1.

    The update ``p_hat <- p_hat - T Gamma Y^T s / (1 + nu |Y|^2)``, applied from the next
    period, changes the model torque ``Y p_hat`` by ``-K_I s`` per period, ``K_I = T Y Gamma Y^T
    / (1 + nu |Y|^2)``: an integral action on ``s`` around the PD loop ``M ds/dt = -K_D s + Y
    p_tilde``. One joint, the torque held over a period: ``s+ = a s + b d``, ``d+ = d - k_I s``
    with ``a = exp(-K_D T / m)``, ``b = (1 - a) / K_D``; the characteristic polynomial
    ``z^2 - (1 + a) z + a + b k_I`` has its roots inside the unit circle exactly when
    ``a + b k_I < 1``, i.e. ``k_I < K_D`` (whatever the inertia, the period and ``a``; the
    full sampled loop with the position error flips within a few per cent of it). Several
    joints: ``lambda_max(K_D^-1/2 K_I K_D^-1/2) < 1``. Since ``lambda_max(...) <= T max(Gamma)
    |Y|_F^2 / min(K_D)``, ``nu >= c T max(Gamma) / min(K_D)`` keeps the ratio below ``1 / c``
    for any ``Y``."""
    if np.ndim(Y) not in (2, 3):
        raise _args.fail("Y", f"has {np.ndim(Y)} dimensions; expected (n, p) or (m, n, p)")
    Y = _args.array(Y, "Y", (None,) * np.ndim(Y))
    n, p = Y.shape[-2:]
    kd = _args.array(kd, "kd", (n,))
    gamma = _args.array(
        np.broadcast_to(gamma, (p,)) if np.ndim(gamma) == 0 else gamma, "gamma", (p,)
    )
    nu = _args.number(nu, "nu", minimum=0.0)
    period = _args.number(period, "period", positive=True)
    if not (np.all(kd > 0) and np.all(gamma >= 0)):
        raise _args.fail("kd", "and gamma must be positive (kd) and non-negative (gamma)")
    Y = Y[None] if Y.ndim == 2 else Y
    # scaled by the largest entry of each regressor: finite for regressors of any size
    big = np.abs(Y).max(axis=(-2, -1))
    big = np.where(big > 0, big, 1.0)
    Y = Y / big[:, None, None]
    Z = Y / np.sqrt(kd)[:, None] * np.sqrt(gamma)  # K_D^-1/2 Y Gamma^1/2, scaled
    top = np.linalg.eigvalsh(Z @ np.swapaxes(Z, -1, -2))[..., -1]
    with np.errstate(over="ignore"):
        return period * top / (1.0 / big**2 + nu * np.sum(Y * Y, axis=(-2, -1)))


def deviation_bounds(
    kd, lam, period: float, minv, m_hat, damping, fed, inertia, friction
) -> tuple[np.ndarray, np.ndarray]:
    """For each model parameter alone, the largest decrease and increase of its value that keep
    every sampled adaptive-PD loop stable (the linearised check of the module docstring), the
    other parameters at the model's values.

    ``minv``, ``m_hat``, ``damping``, ``fed``: (m, n, n) stacks of the robot's ``M^-1`` and
    ``D`` and the model's ``M_hat`` and ``D_hat`` at m configurations; ``inertia`` and
    ``friction``: (p, m, n, n), each parameter's part of ``M_hat`` and of ``D_hat`` (per unit
    value). A parameter moved by ``d`` changes ``K_D,eff - D_hat`` by ``d (M_j Lambda - D_j)``.
    Returns ``(down, up)`` (p,) each: ``inf`` where no finite change makes a loop unstable (a
    parameter the linearised loop does not see, or up to :data:`_MARGIN_CAP` times the change
    that doubles the loop's velocity gain), 0 where any change does."""
    kd, lam = np.asarray(kd, dtype=float), np.asarray(lam, dtype=float)
    kpe, kde = effective_gains("adaptive-pd", kd, kd, lam, m_hat)
    kde = np.broadcast_to(kde, minv.shape) - fed
    ad, bd = plant_step(minv, float(period), damping)
    sens = inertia * lam - friction  # (p, m, n, n)
    p = sens.shape[0]
    size = np.abs(sens).max(axis=(1, 2, 3))
    scale = np.where(size > 0, np.abs(kde).max() / np.where(size > 0, size, 1.0), np.inf)
    out = []
    for sign in (-1.0, 1.0):

        def radius(x, sign=sign):
            step = (sign * x * np.where(np.isfinite(scale), scale, 0.0))[:, None, None, None]
            moved = kde + step * sens
            return _radius(ad, bd, np.broadcast_to(kpe, moved.shape), moved).max(axis=1)

        lo = np.full(p, math.log(1e-6))
        hi = np.full(p, math.log(_MARGIN_CAP))
        small = radius(np.exp(lo)) <= _UNSTABLE
        capped = radius(np.exp(hi)) <= _UNSTABLE
        for _ in range(10):  # log x to 2 %: the bound to 2 %
            mid = 0.5 * (lo + hi)
            ok = radius(np.exp(mid)) <= _UNSTABLE
            lo, hi = np.where(ok, mid, lo), np.where(ok, hi, mid)
        bound = np.where(small, np.exp(lo) * scale, 0.0)
        out.append(np.where(capped | ~np.isfinite(scale), np.inf, bound))
    return out[0], out[1]


#: Random points of the box (besides its two uniform corners) at which :func:`box_fraction`
#: checks the parameters moving together.
BOX_POINTS = 32


def box_fraction(
    kd, lam, period: float, minv, m_hat, damping, fed, inertia, friction, down, up, *, seed=0
) -> float:
    """The largest common fraction ``f`` of the single-parameter limits ``down``, ``up``
    (:func:`deviation_bounds`) at which the box ``[-f down, f up]`` about the model keeps the
    sampled adaptive-PD loop stable with the parameters moving together, checked at its two
    uniform corners (every parameter down, every parameter up) and :data:`BOX_POINTS` random
    points (seeded): the largest of 1, 1/2, 1/4, ... that passes, and at least ``1 / N`` (``N``
    the parameters with a finite limit), where every point of the box has
    ``sum_j |d_j| / limit_j <= 1``, inside the convex hull of the single-parameter limits.
    Arguments as :func:`deviation_bounds`."""
    kd, lam = np.asarray(kd, dtype=float), np.asarray(lam, dtype=float)
    kpe, kde = effective_gains("adaptive-pd", kd, kd, lam, m_hat)
    kde = np.broadcast_to(kde, minv.shape) - fed
    ad, bd = plant_step(minv, float(period), damping)
    sens = inertia * lam - friction  # (p, m, n, n)
    lo = np.where(np.isfinite(down), down, 0.0)
    hi = np.where(np.isfinite(up), up, 0.0)
    seen = int(np.sum(np.isfinite(down) | np.isfinite(up)))
    u = np.random.default_rng(seed).uniform(-1.0, 1.0, (BOX_POINTS, len(lo)))
    unit = np.vstack([-lo, hi, np.where(u < 0, u * lo, u * hi)])  # (points, p)
    floor = 1.0 / max(seen, 1)
    f = 1.0
    while f > floor:
        moved = kde + np.einsum("ap,pmij->amij", f * unit, sens)
        radius = _radius(ad, bd, np.broadcast_to(kpe, moved.shape), moved)
        if np.all(radius <= _UNSTABLE):
            return f
        f *= 0.5
    return floor
