"""Excitation trajectories for identification: finite Fourier series optimised for conditioning.

Joint ``i`` follows a finite Fourier series (as in the ZCR07S study)::

    q_i(t) = q_i0 + sum_{l=1..N} [ a_il / (w l) sin(w l t) - b_il / (w l) cos(w l t) ],  w = 2 pi f

so that ``dq_i = sum_l a_il cos(w l t) + b_il sin(w l t)`` and
``ddq_i = sum_l w l (-a_il sin(w l t) + b_il cos(w l t))``. The motion is periodic with period
``1 / f``. Zero velocity and acceleration at the start and end of each period hold *by
construction*: ``a_i1 = -sum_{l>=2} a_il`` and ``b_i1 = -sum_{l>=2} l b_il``, so the optimiser only
sees the free coefficients ``a_i2..a_iN``, ``b_i2..b_iN`` and the offset ``q_i0`` (or, with a
prescribed start position, only the ``a``, ``b``: ``q_i0`` then follows from ``q_i(0)``).

Positions, velocities and accelerations are linear in these coefficients, so the joint limits are
linear inequality constraints (imposed on a time grid and checked afterwards on a fine grid). The
criterion is evaluated on the stacked base regressor ``W_b`` (C++ core) along the trajectory:

``cond``      condition number of ``W_b`` (minimised through its logarithm);
``logdet``    D-optimality: ``-log det(W_b^T W_b / rows)``;
``hadamard``  the Hadamard-inequality bound of the ZCR07S study: ``det(G) <= prod diag(G)`` with
              ``G = W_b^T W_b``, minimised as ``log prod diag(G) - log det(G) >= 0`` (zero exactly
              when the columns of ``W_b`` are orthogonal).
"""

from __future__ import annotations

import json
import math
import re
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.optimize import minimize

from .. import _args
from .._args import ArgumentError
from .._threads import single_threaded_blas
from ..base import BaseParameters, base_parameters
from ..robot import Robot, as_robot, drive_train_record, load
from .errors import IdentificationError

__all__ = [
    "CRITERIA",
    "MAX_TRAJECTORY_ROWS",
    "check_sampling",
    "ExcitationResult",
    "FourierTrajectory",
    "criterion_value",
    "effort_acceleration_limits",
    "excitation_limits",
    "optimize_excitation",
    "peak_torques",
    "plot_trajectory",
    "random_trajectory",
]

CRITERIA = ("cond", "logdet", "hadamard")

#: Seconds between progress lines within a start when the progress stream is not a terminal
#: (on a terminal the line is redrawn twice a second).
PROGRESS_SECONDS = 10.0

#: Most rows a sampled trajectory may have (:meth:`FourierTrajectory.sample`): one period at
#: 1 kHz of a 0.001 Hz trajectory; about 160 bytes per row and joint in CSV text.
MAX_TRAJECTORY_ROWS = 1_000_000

# Used where a robot description gives no limit (NaN): revolute, prismatic.
FALLBACK = {
    "position": (math.pi, 0.5),  # half range about 0 [rad], [m]
    "velocity": (1.5, 0.5),  # [rad/s], [m/s]
    "acceleration": (6.0, 2.0),  # [rad/s^2], [m/s^2]
}


def check_sampling(harmonics: int, freq: float, rate: float, *, periods: float = 1.0) -> int:
    """Raises ValueError unless ``rate`` [Hz] samples ``periods`` periods of a trajectory of
    ``harmonics`` harmonics of ``freq`` [Hz]: a rate above ``2 N freq`` (each period of the
    highest harmonic sampled more than twice) and at most :data:`MAX_TRAJECTORY_ROWS` samples.
    Returns the number of samples."""
    harmonics = _args.integer(harmonics, "harmonics", 1)
    freq = _args.number(freq, "freq", positive=True)
    rate = _args.number(rate, "rate", positive=True)
    periods = _args.number(periods, "periods", positive=True)
    rate, periods, period = float(rate), float(periods), 1.0 / float(freq)
    top = harmonics * freq
    if not (math.isfinite(rate) and rate > 2 * top):
        raise ArgumentError(
            f"sample rate {rate:g} Hz does not sample the highest harmonic ({harmonics} x "
            f"{freq:g} Hz = {top:g} Hz); expected a rate above {2 * top:g} Hz"
        )
    if not (math.isfinite(periods) and periods > 0):
        raise ArgumentError(f"periods must be a positive number, got {periods:g}")
    rows = periods * period * rate + 1
    if rows > MAX_TRAJECTORY_ROWS:
        raise ArgumentError(
            f"{periods:g} period(s) of {period:g} s at {rate:g} Hz are {rows:.4g} rows; "
            f"at most {MAX_TRAJECTORY_ROWS:,} are written (lower the rate)"
        )
    return int(round(periods * period * rate)) + 1


@dataclass
class FourierTrajectory:
    """A periodic joint trajectory given by finite Fourier series.

    Attributes
    ----------
    a, b : ndarray, shape (n, N)
        Coefficients per joint and harmonic (velocity amplitudes, rad/s or m/s).
    q0 : ndarray, shape (n,)
        Offsets.
    freq : float
        Base frequency [Hz]; the period is ``1 / freq``.
    """

    a: np.ndarray
    b: np.ndarray
    q0: np.ndarray
    freq: float

    def __post_init__(self):
        self.a = np.atleast_2d(np.asarray(self.a, dtype=float))
        self.b = np.atleast_2d(np.asarray(self.b, dtype=float))
        self.q0 = np.asarray(self.q0, dtype=float).reshape(-1)
        if self.a.shape != self.b.shape or self.a.shape[0] != self.q0.shape[0]:
            raise ArgumentError(
                f"Fourier coefficients a {self.a.shape}, b {self.b.shape} and offsets q0 "
                f"{self.q0.shape} do not fit together; expected (n, N), (n, N), (n,)"
            )
        if not self.freq > 0:
            raise ArgumentError(f"base frequency must be positive, got {self.freq}")

    @property
    def n(self) -> int:
        return self.a.shape[0]

    @property
    def harmonics(self) -> int:
        return self.a.shape[1]

    @property
    def period(self) -> float:
        return 1.0 / self.freq

    @property
    def duration(self) -> float:
        """One period [s]: the span of a simulation along the trajectory unless told otherwise
        (the reference protocol of :mod:`mindyn.control.simulation`)."""
        return self.period

    def evaluate(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions, velocities, accelerations at times ``t`` (shape (m,)): three (m, n) arrays."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        bq, bd, bdd = _basis(t, self.harmonics, self.freq)
        c = np.hstack([self.a, self.b, self.q0[:, None]])  # (n, 2N+1)
        return bq @ c.T, bd @ c.T, bdd @ c.T

    def sample(self, *, rate: float = 250.0, periods: float = 1.0):
        """``(t, q, dq, ddq)`` sampled at ``rate`` Hz over ``periods`` periods, both ends
        included; ``t`` shape (m,), the others (m, n).

        The rate must be above twice the highest harmonic's frequency (``2 N freq``: each of its
        periods is then sampled more than twice), and the samples at most
        :data:`MAX_TRAJECTORY_ROWS`."""
        check_sampling(self.harmonics, self.freq, rate, periods=periods)
        m = int(round(periods * self.period * rate)) + 1
        t = np.arange(m) / rate
        return (t, *self.evaluate(t))

    def to_dict(self) -> dict:
        return {
            "type": "fourier",
            "freq": self.freq,
            "period": self.period,
            "harmonics": self.harmonics,
            "a": self.a.tolist(),
            "b": self.b.tolist(),
            "q0": self.q0.tolist(),
        }

    @classmethod
    def from_dict(cls, d: dict, *, source: str = "Fourier trajectory") -> FourierTrajectory:
        """The trajectory of :meth:`to_dict`'s mapping ``d``; DataError naming ``source`` (and the
        entry) when an entry is missing or is not a finite number or array of the right shape."""
        from .data import DataError

        if not isinstance(d, dict):
            raise DataError(f"{source}: expected a mapping of the Fourier coefficients")
        missing = [k for k in ("a", "b", "q0", "freq") if k not in d]
        if missing:
            raise DataError(
                f"{source}: missing entr{'y' if len(missing) == 1 else 'ies'} "
                + ", ".join(repr(k) for k in missing)
                + " (an excitation's coefficients: a, b, q0 and freq, as mindyn excite writes)"
            )
        shapes = {"a": 2, "b": 2, "q0": 1, "freq": 0}
        got = {}
        for key, ndim in shapes.items():
            value = d[key]
            x = None
            if not (isinstance(value, (bool, str)) or value is None):
                try:
                    x = np.asarray(value, dtype=float)
                except (TypeError, ValueError):
                    pass
            if x is None or x.ndim != ndim or (ndim and x.size == 0):
                what = ("a number", "a list of numbers", "a list of lists of numbers")[ndim]
                raise DataError(f"{source}: entry '{key}' is not {what}")
            if not np.isfinite(x).all():
                raise DataError(f"{source}: entry '{key}' holds NaN or infinite values")
            got[key] = x
        try:
            return cls(got["a"], got["b"], got["q0"], float(got["freq"]))
        except ArgumentError as e:
            raise DataError(f"{source}: {e}") from None

    @classmethod
    def load(cls, path) -> FourierTrajectory:
        """Reads the JSON written by :meth:`ExcitationResult.save` (or :meth:`to_dict`);
        DataError naming the file when it holds no such trajectory."""
        from .data import DataError, read_json

        path = Path(path)
        d = read_json(path, what="trajectory file")
        if not isinstance(d, dict):
            raise DataError(f"{path}: expected a JSON object (the excitation's coefficients)")
        if "trajectory" not in d and not {"a", "b", "q0", "freq"} & set(d):
            kind = next((k for key, k in _OTHER_JSON if key in d), "a JSON document")
            raise DataError(
                f"{path}: {kind}, not an excitation's coefficients (the JSON that mindyn excite "
                "writes beside its CSV)"
            )
        return cls.from_dict(d.get("trajectory", d), source=str(path))


#: Entries by which the other JSON files of the commands are recognised, and what they are
_OTHER_JSON = (
    ("thresholds", "a collision-detection thresholds file"),
    ("simulation", "the truth file of a simulated log"),
    ("base_names", "the JSON of an identification"),
    ("n_base", "the JSON of mindyn base"),
)


def _basis(t: np.ndarray, N: int, freq: float):
    """Matrices mapping full per-joint coefficients ``[a_1..a_N, b_1..b_N, q0]`` to q, dq, ddq at
    times ``t``: three arrays of shape (m, 2N+1)."""
    w = 2.0 * math.pi * freq
    ell = np.arange(1, N + 1)
    arg = np.outer(t, w * ell)
    s, c = np.sin(arg), np.cos(arg)
    m = t.shape[0]
    one, zero = np.ones((m, 1)), np.zeros((m, 1))
    bq = np.hstack([s / (w * ell), -c / (w * ell), one])
    bd = np.hstack([c, s, zero])
    bdd = np.hstack([-s * (w * ell), c * (w * ell), zero])
    return bq, bd, bdd


def _reduction(N: int, freq: float, start: float | None):
    """Affine map from free to full per-joint coefficients, ``full = R @ free + r``.

    Free coefficients: ``a_2..a_N, b_2..b_N`` and, without a prescribed start, ``q0``. With
    ``start`` the offset ``q0`` follows from ``q(0) = q0 - sum_l b_l / (w l) = start``."""
    nf = 2 * (N - 1) + (0 if start is not None else 1)
    R = np.zeros((2 * N + 1, nf))
    r = np.zeros(2 * N + 1)
    ell = np.arange(2, N + 1)
    for j in range(N - 1):
        R[1 + j, j] = 1.0  # a_l
        R[0, j] = -1.0  # a_1 = -sum a_l
        R[N + 1 + j, N - 1 + j] = 1.0  # b_l
        R[N, N - 1 + j] = -float(ell[j])  # b_1 = -sum l b_l
    if start is None:
        R[2 * N, nf - 1] = 1.0
    else:
        w = 2.0 * math.pi * freq
        # q0 = start + sum_{l>=1} b_l / (w l), with b_1 expressed through the free b's.
        for j in range(N - 1):
            R[2 * N, N - 1 + j] = 1.0 / (w * ell[j]) - ell[j] / w
        r[2 * N] = start
    return R, r


#: Share of each joint's effort limit that the acceleration limits derived from it leave to the
#: inverse-dynamics torque (:func:`effort_acceleration_limits`).
EFFORT_SHARE = 0.8

#: Configurations sampled within the position limits by :func:`effort_acceleration_limits`.
EFFORT_CONFIGURATIONS = 64


def _drive_torques(robot: Robot, q, dq, ddq, *, rotor: bool, friction: bool) -> np.ndarray:
    """Inverse-dynamics torques, shape (m, n), with the robot's rotor inertia and friction when
    asked (on its :attr:`~mindyn.robot.Robot.drive_side`)."""
    p = robot.parameters(rotor=rotor, friction=friction)
    q, dq, ddq = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (q, dq, ddq))
    step = max(1, 2_000_000 // (robot.n * p.size))  # rows per block: at most ~16 MB of W
    blocks = [
        robot.regressor(
            q[i : i + step], dq[i : i + step], ddq[i : i + step], rotor=rotor, friction=friction
        )
        @ p
        for i in range(0, q.shape[0], step)
    ]
    return np.concatenate(blocks)


def _mass_matrices(robot: Robot, q: np.ndarray, *, rotor: bool) -> np.ndarray:
    """``M(q)``, shape (m, n, n), with the rotor inertia ``sum_k Ia_k t_k^T t_k`` when asked
    (``t_k`` the rows of :attr:`~mindyn.robot.Robot.drive_matrix`)."""
    M = robot.mass_matrix(q)
    if rotor:
        names = robot.parameter_names(rotor=True)
        p = robot.parameters(rotor=True)
        D = np.asarray(robot.drive_matrix, dtype=float)
        ia = np.zeros(D.shape[0])
        for i, name in enumerate(names):
            m = re.fullmatch(r"Ia(\d+)", name)
            if m and int(m[1]) <= D.shape[0]:
                ia[int(m[1]) - 1] = p[i]
        M = M + (D.T * ia) @ D
    return M


def effort_acceleration_limits(
    robot: Robot,
    *,
    lower,
    upper,
    velocity,
    fixed,
    fallback,
    reach=None,
    share: float = EFFORT_SHARE,
    rotor: bool = False,
    friction: bool = False,
    configurations: int = EFFORT_CONFIGURATIONS,
    seed: int = 0,
) -> dict:
    """Acceleration limits derived from the robot's effort limits ``E`` and its dynamics.

    At ``configurations`` positions ``q_s`` drawn uniformly within ``[lower, upper]`` (seeded
    by ``seed``), each with velocities ``v_s`` at ``+-velocity`` (random signs), joint ``k``'s
    limit is the largest ``A_k`` with

        ``|h_k(q_s, v_s)| + M_kk(q_s) A_k + sum_{j != k} |M_kj(q_s)| U_j <= share E_k``

    at every sample (``h``: gravity, velocity terms and, when asked, friction; ``M``: the mass
    matrix, with the rotor inertia when asked). ``U_j`` bounds the other joints' accelerations:
    ``fixed[j]`` where given (limits of the description or the fallback), else joint ``j``'s
    own limit with no coupling, ``min_s (share E_j - |h_j|) / M_jj`` where positive, else
    ``fallback[j]`` (the limit the joint will get) — all capped at
    ``reach[j]`` when given (the largest acceleration the trajectory can reach). Each ``U_j`` is
    at least the acceleration joint ``j`` will have, so every joint's torque stays within
    ``share E_k`` at the samples with all joints accelerating at once, worst signs included.

    ``fixed``: (n,) limits already known (NaN where one is to be derived). Returns a dict:
    ``acceleration`` (n,) (NaN where none can be derived: a ``fixed`` joint, no positive effort
    limit, or ``|h_k|`` plus the coupling reaching ``share E_k``), ``isolated`` (n,), ``bound``
    (the ``U``), ``share``, ``effort``, ``q`` and ``dq`` (the samples, (S, n)) and
    ``saturated`` (joints whose ``|h_k|`` alone reaches ``share E_k``) with ``held``, the
    largest ``|h_k| / E_k`` and ``gravity``, the largest ``|g_k(q_s)| / E_k`` per joint."""
    _args.instance(robot, "robot", Robot)
    n = robot.n
    lower = _args.array(lower, "lower", (n,))
    upper = _args.array(upper, "upper", (n,))
    velocity = _args.array(velocity, "velocity", (n,))
    fixed = _args.array(fixed, "fixed", (n,), finite=False)
    fallback = _args.array(fallback, "fallback", (n,))
    reach = np.full(n, np.inf) if reach is None else _args.array(reach, "reach", (n,))
    for name, v in (
        ("velocity", velocity),
        ("fixed", fixed),
        ("fallback", fallback),
        ("reach", reach),
    ):
        bad = np.flatnonzero(v <= 0)
        if bad.size:
            raise ArgumentError(
                f"{name} of joint {bad[0] + 1} is {v[bad[0]]:g}; expected a positive limit"
            )
    bad = np.flatnonzero(lower >= upper)
    if bad.size:
        k = int(bad[0])
        raise ArgumentError(f"lower {lower[k]:g} of joint {k + 1} is not below upper {upper[k]:g}")
    share = _args.number(share, "share", positive=True, maximum=1.0)
    rotor, friction = _args.flag(rotor, "rotor"), _args.flag(friction, "friction")
    configurations = _args.integer(configurations, "configurations", 1)
    seed = _args.integer(seed, "seed", 0)
    effort = np.array(robot.limits["effort"], dtype=float)
    rng = np.random.default_rng(seed)
    S = configurations
    q = lower + (upper - lower) * rng.uniform(size=(S, n))
    dq = velocity * rng.choice([-1.0, 1.0], size=(S, n))
    h = _drive_torques(robot, q, dq, np.zeros_like(q), rotor=rotor, friction=friction)
    M = _mass_matrices(robot, q, rotor=rotor)  # M[s, k, j]
    diag = np.einsum("skk->sk", M)
    budget = share * effort - np.abs(h)  # (S, n)
    ok = np.isfinite(effort) & (effort > 0) & ~np.isfinite(fixed)
    saturated = [k for k in range(n) if ok[k] and budget[:, k].min() <= 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        isolated = np.where(ok, np.min(budget / diag, axis=0), np.nan)
    ok &= np.isfinite(isolated) & (isolated > 0)  # (a joint moving no mass has no bound)
    bound = np.where(ok, isolated, fallback)
    bound = np.minimum(np.where(np.isfinite(fixed), fixed, bound), reach)
    coupling = (np.abs(M) * ~np.eye(n, dtype=bool)) @ bound  # sum_{j != k} |M_kj| U_j, (S, n)
    with np.errstate(divide="ignore", invalid="ignore"):
        acc = np.min((budget - coupling) / diag, axis=0)
    ok &= np.isfinite(acc) & (acc > 0)
    return {
        "acceleration": np.where(ok, acc, np.nan),
        "isolated": isolated,
        "bound": bound,
        "share": share,
        "effort": effort,
        "q": q,
        "dq": dq,
        "saturated": saturated,
        "held": np.max(np.abs(h), axis=0) / effort,
        "gravity": np.max(np.abs(robot.gravity_torque(q)), axis=0) / effort,
    }


def excitation_limits(
    robot: Robot,
    *,
    margin: float = 0.05,
    overrides: dict | None = None,
    effort_share: float = EFFORT_SHARE,
    rotor: bool = False,
    friction: bool = False,
    harmonics: int = 5,
    freq: float = 0.1,
):
    """Limits used for the excitation: arrays ``lower``, ``upper``, ``velocity``,
    ``acceleration`` of shape (n,), ``acceleration_source`` (per joint ``"description"``,
    ``"override"``, ``"effort"`` or ``"fallback"``) and ``acceleration_rule`` (a dict: the
    rule's numbers, :func:`effort_acceleration_limits`), and a list of notes for every
    fallback taken and rule applied.

    The robot's limits are shrunk by ``margin`` (a fraction: positions towards the middle of
    their range, velocities and accelerations in magnitude). Where the description gives no
    position or velocity limit (NaN) a fallback is used (``FALLBACK``) and noted. Where it gives
    no acceleration limit (URDF never does), the limit is derived from the joint's effort limit
    and the robot's dynamics (with its rotor inertia and friction when asked) so that the
    inverse-dynamics torque stays within ``effort_share`` of the effort limits
    (:func:`effort_acceleration_limits`, on the limits after the margin, the other joints'
    accelerations bounded by what a trajectory of ``harmonics`` harmonics of ``freq`` [Hz] can
    reach); only without a usable effort limit is the fixed fallback used. ``overrides`` may
    give any of the four arrays (or scalars) to replace the robot's values."""
    _args.instance(robot, "robot", Robot)
    margin = _args.number(margin, "margin", minimum=0.0, below=0.5)
    _args.optional(_args.mapping, overrides, "overrides")
    effort_share = _args.number(effort_share, "effort_share", positive=True, maximum=1.0)
    rotor, friction = _args.flag(rotor, "rotor"), _args.flag(friction, "friction")
    harmonics = _args.integer(harmonics, "harmonics", 1)
    freq = _args.number(freq, "freq", positive=True)
    lim = robot.limits
    n = robot.n
    overrides = overrides or {}
    prism = np.array([t == "prismatic" for t in robot.joint_types])
    out: dict = {}
    notes: list[str] = []
    source = np.array(["description"] * n, dtype=object)
    for key in ("lower", "upper", "velocity", "acceleration"):
        v = np.array(lim[key], dtype=float)
        if key in overrides and overrides[key] is not None:
            v = np.broadcast_to(np.asarray(overrides[key], dtype=float), (n,)).copy()
            if key == "acceleration":
                source[:] = "override"
        out[key] = v
    for k in range(n):
        unit = "m" if prism[k] else "rad"
        if not np.isfinite(out["velocity"][k]) or out["velocity"][k] <= 0:
            fb = FALLBACK["velocity"][1 if prism[k] else 0]
            out["velocity"][k] = fb
            notes.append(f"joint {k + 1}: no velocity limit given; using {fb:g} {unit}/s")
        for key, sign in (("lower", -1.0), ("upper", 1.0)):
            if not np.isfinite(out[key][k]):
                fb = FALLBACK["position"][1 if prism[k] else 0]
                out[key][k] = sign * fb
                notes.append(
                    f"joint {k + 1}: no {key} position limit given; using {sign * fb:g} {unit}"
                )
        if out["lower"][k] >= out["upper"][k]:
            raise ArgumentError(
                f"joint {k + 1}: lower position limit {out['lower'][k]:g} is not below the "
                f"upper limit {out['upper'][k]:g}"
            )
    mid = 0.5 * (out["lower"] + out["upper"])
    half = 0.5 * (out["upper"] - out["lower"]) * (1 - margin)
    out["lower"], out["upper"] = mid - half, mid + half
    out["velocity"] = out["velocity"] * (1 - margin)
    acc = out["acceleration"]
    given = np.isfinite(acc) & (acc > 0)
    acc = np.where(given, acc * (1 - margin), np.nan)
    fallback = (1 - margin) * np.where(
        prism, FALLBACK["acceleration"][1], FALLBACK["acceleration"][0]
    )
    record: dict = {"share": effort_share, "configurations": 0}
    if given.any():
        notes.append(
            f"acceleration limits of joints {_joint_list(given)} from the "
            f"{'overrides' if source[0] == 'override' else 'description'} less the "
            f"{100 * margin:g} % margin: {_values(acc[given])}"
        )
    if not given.all() and robot.single_dof:
        # Bernstein's inequality: a Fourier series of N harmonics of f whose velocity stays
        # within V has accelerations within 2 pi f N V.
        reach = 2.0 * math.pi * freq * harmonics * out["velocity"]
        rule = effort_acceleration_limits(
            robot,
            lower=out["lower"],
            upper=out["upper"],
            velocity=out["velocity"],
            fixed=np.where(given, acc, np.where(robot.limits["effort"] > 0, np.nan, fallback)),
            fallback=fallback,
            reach=reach,
            share=effort_share,
            rotor=rotor,
            friction=friction,
        )
        derived = np.isfinite(rule["acceleration"])
        acc = np.where(derived, rule["acceleration"], acc)
        source[derived] = "effort"
        record.update(
            configurations=EFFORT_CONFIGURATIONS,
            isolated=[float(v) if np.isfinite(v) else None for v in rule["isolated"]],
            coupling_bound=rule["bound"].tolist(),
        )
        if derived.any():
            notes.append(
                f"acceleration limits of joints {_joint_list(derived)} from their effort limits: "
                f"{_values(acc[derived])} (the largest for which |gravity + velocity terms| + "
                f"M_kk a_k + sum |M_kj| a_j of the other joints at their limits or their reach "
                f"2 pi f N v_max stays within {100 * effort_share:g} % of the effort limit at "
                f"{EFFORT_CONFIGURATIONS} configurations within the position limits, "
                "velocities at their limits)"
            )
        for k in np.flatnonzero(~derived & ~given & (rule["effort"] > 0)):
            if k in rule["saturated"]:
                why = (
                    f"gravity and velocity terms alone reach {100 * rule['held'][k]:.0f} % of "
                    f"its effort limit {rule['effort'][k]:g} (gravity alone "
                    f"{100 * rule['gravity'][k]:.0f} %)"
                )
            else:
                why = (
                    "gravity, velocity terms and the other joints' accelerations leave no "
                    f"torque within {100 * effort_share:g} % of its effort limit "
                    f"{rule['effort'][k]:g}"
                )
            notes.append(
                f"joint {k + 1}: {why} at a sampled configuration; no acceleration limit can "
                "be derived from it"
            )
    missing = ~np.isfinite(acc)
    if missing.any():
        acc = np.where(missing, fallback, acc)
        source[missing] = "fallback"
        notes.append(
            f"acceleration limits of joints {_joint_list(missing)}: the fixed fallback "
            f"{FALLBACK['acceleration'][0]:g} rad/s^2 ({FALLBACK['acceleration'][1]:g} m/s^2) "
            f"less the {100 * margin:g} % margin, {_values(acc[missing])} (no effort limit "
            "to derive them from, or one the rule above cannot use)"
        )
    out["acceleration"] = acc
    out["acceleration_source"] = source.astype(str)
    record["source"] = out["acceleration_source"].tolist()
    out["acceleration_rule"] = record
    return out, notes


def _joint_list(mask: np.ndarray) -> str:
    """``1-3, 5`` for the joints where ``mask`` holds."""
    ks = [int(k) + 1 for k in np.flatnonzero(mask)]
    parts, i = [], 0
    while i < len(ks):
        j = i
        while j + 1 < len(ks) and ks[j + 1] == ks[j] + 1:
            j += 1
        parts.append(f"{ks[i]}" if i == j else f"{ks[i]}-{ks[j]}")
        i = j + 1
    return ", ".join(parts)


def _values(v: np.ndarray) -> str:
    return ", ".join(f"{x:.3g}" for x in v)


def _criterion(G: np.ndarray, rows: int, criterion: str) -> float:
    """Criterion value from ``G = W^T W`` (the quantity minimised)."""
    if criterion == "cond":
        ev = np.linalg.eigvalsh(G)
        if ev[0] <= ev[-1] * 1e-30 or ev[-1] <= 0:
            return 70.0  # log of a condition number beyond double precision
        return 0.5 * math.log(ev[-1] / ev[0])
    sign, logdet = np.linalg.slogdet(G / rows)
    if sign <= 0:
        return 1e3
    if criterion == "logdet":
        return -logdet
    d = np.diag(G) / rows
    return float(np.sum(np.log(d)) - logdet)


def _joint_units(base: BaseParameters) -> np.ndarray:
    """Per base parameter, the factor on its regressor column that gives it in joint units: 1,
    except, when the robot's rotor inertia and friction act on its motors (``drive_side``
    "motor"), for a base parameter that is motor ``k``'s own ``Ia``, ``Fv`` (``1 / |t_k|^2``)
    or Coulomb-type friction (``1 / |t_k|_1``), ``t_k`` its row of ``T``: in motor units their
    columns are ``r^2`` or ``|r|`` times a joint-side one, and a gear ratio of 160 made the
    condition number that of the ratio, not of the motion. The criteria are evaluated on
    ``W * _joint_units(base)``: on a robot whose motors each drive one joint they equal those of
    the same robot with the terms on the joints."""
    robot = base.robot
    scale = np.ones(base.n)
    tr = robot.transmission
    if tr is None or robot.drive_side != "motor":
        return scale
    T = np.asarray(tr.T, dtype=float)
    for i, name in enumerate(base.names):
        m = re.fullmatch(r"(Ia|Fv|Fc|Fa|Fs)R?(\d+)", name)
        if m and int(m[2]) <= T.shape[0]:
            row = T[int(m[2]) - 1]
            size = np.sum(row**2) if m[1] in ("Ia", "Fv") else np.sum(np.abs(row))
            scale[i] = 1.0 / size if size > 0 else 1.0
    return scale


def criterion_value(base: BaseParameters, q, dq, ddq, *, criterion: str = "cond") -> float:
    """The criterion in its reported form on samples ``q, dq, ddq`` (each (m, n)): the condition
    number for ``cond``, ``log det(W^T W / rows)`` for ``logdet`` and the log Hadamard ratio
    ``log prod diag(G) - log det(G)`` for ``hadamard``, ``W`` the stacked base regressor with
    its columns in joint units (:func:`_joint_units`)."""
    _args.instance(base, "base", BaseParameters)
    q, dq, ddq = _args.batch(base.robot.n, q=q, dq=dq, ddq=ddq)
    _args.choice(criterion, "criterion", CRITERIA)
    if criterion not in CRITERIA:
        raise ArgumentError(f"unknown criterion '{criterion}'; choose one of {', '.join(CRITERIA)}")
    W = base.regressor(q, dq, ddq).reshape(-1, base.n) * _joint_units(base)
    with np.errstate(over="ignore", invalid="ignore"):  # checked on the next line
        gram = W.T @ W
    if not np.isfinite(gram).all():
        raise _args.overflow("criterion_value", q=q, dq=dq, ddq=ddq)
    J = _criterion(gram, W.shape[0], criterion)
    if criterion == "cond":
        return math.exp(J)
    if criterion == "logdet":
        return -J
    return J


@dataclass
class ExcitationResult:
    """An optimised excitation trajectory with what it took to get it.

    ``value`` / ``initial_value`` are in the reported form of :func:`criterion_value` (the
    latter for ``initial_trajectory``, the starting guess of the best start); ``starts`` lists
    per random start its initial and final value, iterations, seconds, the optimiser's
    message, whether it converged and whether it improved on the start, in the same form;
    ``warnings`` says when the optimiser failed without improving on any start (the trajectory
    is then a random one). That form is smaller-is-better for
    ``cond`` and ``hadamard`` and larger-is-better for ``logdet`` (``log det(W^T W / rows)``,
    maximised)."""

    robot: str
    trajectory: FourierTrajectory
    criterion: str
    value: float
    initial_value: float
    limits: dict
    notes: list = field(default_factory=list)
    starts: list = field(default_factory=list)
    seconds: float = 0.0
    base_names: list = field(default_factory=list)
    rotor: bool = False
    friction: bool = False
    seed: int = 0
    max_violation: float = 0.0
    initial_trajectory: FourierTrajectory | None = None
    warnings: list = field(default_factory=list)
    #: The robot's transmissions of a type not read (:func:`mindyn.robot.drive_train_record`).
    drive_train: dict = field(default_factory=dict)
    #: The trajectory's peak torque per joint against its effort limit (:func:`peak_torques`).
    peak_torque: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {
            "robot": self.robot,
            "criterion": self.criterion,
            "value": self.value,
            "initial_value": self.initial_value,
            "rotor": self.rotor,
            "friction": self.friction,
            "base_parameters": len(self.base_names),
            "seed": self.seed,
            "seconds": self.seconds,
            "max_limit_violation": self.max_violation,
            "limits": {
                k: np.asarray(v).tolist()
                for k, v in self.limits.items()
                if k != "acceleration_rule"
            },
            "acceleration_rule": self.limits.get("acceleration_rule", {}),
            "peak_torque": {k: v for k, v in self.peak_torque.items() if k != "line"},
            "notes": self.notes,
            "warnings": self.warnings,
            "starts": self.starts,
            "trajectory": self.trajectory.to_dict(),
            **self.drive_train,
        }

    def save(self, csv_path, *, rate: float = 250.0, periods: float = 1.0) -> dict:
        """Writes ``<stem>.csv`` (``t, q1..qn, dq1..dqn, ddq1..ddqn`` sampled at ``rate`` Hz),
        ``<stem>.json`` (coefficients, criterion, limits) and ``<stem>.png`` (plot). Returns the
        three paths."""
        from .data import write_trajectory_csv

        csv_path = Path(csv_path)
        csv_path.parent.mkdir(parents=True, exist_ok=True)
        t, q, dq, ddq = self.trajectory.sample(rate=rate, periods=periods)
        write_trajectory_csv(csv_path, t, q, dq, ddq)
        json_path = csv_path.with_suffix(".json")
        json_path.write_text(json.dumps(self.to_dict(), indent=2) + "\n")
        png_path = csv_path.with_suffix(".png")
        plot_trajectory(
            png_path,
            t,
            q,
            dq,
            ddq,
            limits=self.limits,
            title=f"{self.robot}: excitation trajectory",
        )
        return {"csv": csv_path, "json": json_path, "png": png_path}


class _Problem:
    """The optimisation problem in free coefficients, all joints stacked joint by joint."""

    def __init__(self, base, n, N, freq, limits, criterion, samples, grid, start):
        self.base, self.n, self.N, self.freq = base, n, N, freq
        self.units = _joint_units(base)
        self.criterion = criterion
        self.start = None if start is None else np.asarray(start, dtype=float)
        T = 1.0 / freq
        t_obj = np.arange(samples) * (T / samples)
        t_con = np.arange(grid) * (T / grid)
        self.bq, self.bd, self.bdd = _basis(t_obj, N, freq)
        cq, cd, cdd = _basis(t_con, N, freq)
        self.R, self.r = [], []
        for k in range(n):
            R, r = _reduction(N, freq, None if self.start is None else self.start[k])
            self.R.append(R)
            self.r.append(r)
        self.nf = self.R[0].shape[1]
        # Linear constraints A x <= ub for all joints, block diagonal.
        rows, ub = [], []
        for k in range(n):
            R, r = self.R[k], self.r[k]
            for B, lo, hi in (
                (cq, limits["lower"][k], limits["upper"][k]),
                (cd, -limits["velocity"][k], limits["velocity"][k]),
                (cdd, -limits["acceleration"][k], limits["acceleration"][k]),
            ):
                if B is cq or np.isfinite(hi):
                    M = B @ R
                    off = B @ r
                    blk = np.zeros((2 * M.shape[0], n * self.nf))
                    blk[: M.shape[0], k * self.nf : (k + 1) * self.nf] = M
                    blk[M.shape[0] :, k * self.nf : (k + 1) * self.nf] = -M
                    rows.append(blk)
                    ub.append(np.concatenate([hi - off, -(lo - off)]))
        self.A = np.vstack(rows)
        self.ub = np.concatenate(ub)
        self.evals = 0
        self.best = math.inf

    def full(self, x: np.ndarray) -> np.ndarray:
        """Full coefficients (n, 2N+1)."""
        X = x.reshape(self.n, self.nf)
        return np.stack([self.R[k] @ X[k] + self.r[k] for k in range(self.n)])

    def trajectory(self, x: np.ndarray) -> FourierTrajectory:
        C = self.full(x)
        N = self.N
        return FourierTrajectory(C[:, :N], C[:, N : 2 * N], C[:, 2 * N], self.freq)

    def objective(self, x: np.ndarray) -> float:
        self.evals += 1
        C = self.full(x)
        q, dq, ddq = self.bq @ C.T, self.bd @ C.T, self.bdd @ C.T
        W = self.base.regressor(q, dq, ddq).reshape(-1, self.base.n) * self.units
        J = _criterion(W.T @ W, W.shape[0], self.criterion)
        if J < self.best and self.violation(x) <= 1e-9:
            self.best = J
        return J

    def violation(self, x: np.ndarray) -> float:
        return float(np.max(self.A @ x - self.ub, initial=0.0))


def _scale_into_limits(traj: FourierTrajectory, limits: dict, grid: int, fixed_q0: bool):
    """Shrinks the motion until the trajectory respects ``limits`` on a grid; returns a copy.

    The motion is scaled about its start position ``q(0)`` when that is prescribed
    (``fixed_q0``; ``q(t) - q(0)`` is linear in the coefficients, so the start stays put), and
    otherwise about its offsets, which are first moved into range."""
    t = np.arange(grid) * (traj.period / grid)
    q, dq, ddq = traj.evaluate(t)
    lo, hi = limits["lower"], limits["upper"]
    if fixed_q0:
        anchor = q[0].copy()
        q0 = traj.q0
    else:
        q0 = np.clip(traj.q0, lo, hi)
        anchor = q0
        q = q - traj.q0 + q0
    dev = q - anchor
    with np.errstate(divide="ignore", invalid="ignore"):
        up = np.where(dev.max(0) > 0, (hi - anchor) / dev.max(0), np.inf)
        dn = np.where(dev.min(0) < 0, (lo - anchor) / dev.min(0), np.inf)
        sv = limits["velocity"] / np.abs(dq).max(0)
        sa = limits["acceleration"] / np.abs(ddq).max(0)
    s = np.minimum.reduce([np.ones(traj.n), up, dn, sv, sa])
    s = np.where(np.isfinite(s), np.maximum(s, 0.0), 1.0)
    # q0 - q(0) is linear in the coefficients too: it scales with them.
    q0 = anchor + s * (q0 - anchor) if fixed_q0 else q0
    return FourierTrajectory(traj.a * s[:, None], traj.b * s[:, None], q0, traj.freq)


def random_trajectory(
    robot: Robot | str,
    *,
    harmonics: int = 5,
    freq: float = 0.1,
    seed: int = 0,
    limits: dict | None = None,
    start=None,
    fill: float = 0.8,
    margin: float = 0.05,
) -> FourierTrajectory:
    """A random Fourier trajectory within the limits (zero velocity and acceleration at both ends),
    scaled to use ``fill`` of the tightest limit per joint. Used as starting guess and as
    validation trajectory. ``limits``: all four arrays as returned by
    :func:`excitation_limits`, or some of them as overrides of the robot's (then ``margin``
    applies)."""
    robot = as_robot(robot)
    harmonics = _args.integer(harmonics, "harmonics", 1)
    freq = _args.number(freq, "freq", positive=True)
    seed = _args.integer(seed, "seed", 0)
    _args.optional(_args.mapping, limits, "limits")
    start = _args.optional(_args.array, start, "start", (robot.n,))
    fill = _args.number(fill, "fill", positive=True, maximum=1.0)
    margin = _args.number(margin, "margin", minimum=0.0, below=0.5)
    robot = load(robot)
    keys = ("lower", "upper", "velocity", "acceleration")
    if limits is None or not all(k in limits for k in keys):
        limits, _ = excitation_limits(
            robot, margin=margin, overrides=limits, harmonics=harmonics, freq=freq
        )
    rng = np.random.default_rng(seed)
    n, N = robot.n, harmonics
    rows = []
    for k in range(n):
        R, r = _reduction(N, freq, None if start is None else float(np.asarray(start)[k]))
        # Velocity amplitudes falling off with the harmonic number.
        ell = np.arange(2, N + 1, dtype=float)
        xk = rng.normal(size=2 * (N - 1)) / np.concatenate([ell, ell])
        if start is None:
            mid = 0.5 * (limits["lower"][k] + limits["upper"][k])
            half = 0.5 * (limits["upper"][k] - limits["lower"][k])
            xk = np.concatenate([xk, [mid + 0.3 * half * rng.uniform(-1, 1)]])
        rows.append(R @ xk + r)
    C = np.stack(rows)
    traj = FourierTrajectory(C[:, :N], C[:, N : 2 * N], C[:, 2 * N], freq)
    grid = max(400, 40 * N)
    shrunk = {
        "lower": traj.q0 + fill * (limits["lower"] - traj.q0) if start is None else limits["lower"],
        "upper": traj.q0 + fill * (limits["upper"] - traj.q0) if start is None else limits["upper"],
        "velocity": fill * limits["velocity"],
        "acceleration": fill * limits["acceleration"],
    }
    shrunk["lower"] = np.minimum(shrunk["lower"], traj.q0)
    shrunk["upper"] = np.maximum(shrunk["upper"], traj.q0)
    return _scale_into_limits(traj, shrunk, grid, fixed_q0=start is not None)


@single_threaded_blas
def optimize_excitation(
    robot: Robot | str,
    *,
    harmonics: int = 5,
    freq: float = 0.1,
    criterion: str = "cond",
    starts: int = 3,
    seed: int = 0,
    rotor: bool = False,
    friction: bool = False,
    base: BaseParameters | None = None,
    samples: int = 100,
    grid: int | None = None,
    maxiter: int = 100,
    margin: float = 0.05,
    effort_share: float = EFFORT_SHARE,
    limits: dict | None = None,
    start=None,
    progress: bool = True,
    stream=None,
) -> ExcitationResult:
    """Optimise a Fourier excitation trajectory for the base regressor of ``robot``.

    Parameters
    ----------
    robot : Robot or str
    harmonics, freq : int, float
        Number of harmonics ``N`` and base frequency [Hz] (period ``1 / freq``).
    criterion : {"cond", "logdet", "hadamard"}
    starts, seed : int
        Number of random starting guesses and the seed of their generator.
    rotor, friction : bool
        Base parameters with rotor inertia / friction (ignored when ``base`` is given).
    samples : int
        Regressor samples per period for the criterion.
    grid : int, optional
        Time samples per period on which the limits are imposed (default ``max(100, 20 N)``);
        the result is checked on a grid ten times finer and shrunk if needed.
    maxiter : int
        SLSQP iterations per start.
    margin : float
        Fraction by which the robot's limits are tightened (see :func:`excitation_limits`).
    effort_share : float
        Share of each effort limit that the acceleration limits derived from it leave to the
        inverse-dynamics torque, where the description gives no acceleration limit (see
        :func:`excitation_limits`). The trajectory's peak torques are reported against the
        effort limits either way (``peak_torque``; a warning beyond them).
    limits : dict, optional
        Overrides for ``lower``, ``upper``, ``velocity``, ``acceleration`` (arrays (n,) or
        scalars).
    start : array (n,), optional
        Prescribed position at ``t = 0`` (and at the end of each period).
    progress : bool
        Print progress to ``stream`` (default stderr): a line per start, redrawn during it on a
        terminal, else a line every :data:`PROGRESS_SECONDS` within a start.
    """
    robot = as_robot(robot)
    harmonics = _args.integer(harmonics, "harmonics", 2)
    freq = _args.number(freq, "freq", positive=True)
    _args.choice(criterion, "criterion", CRITERIA)
    starts = _args.integer(starts, "starts", 1)
    seed = _args.integer(seed, "seed", 0)
    rotor, friction = _args.flag(rotor, "rotor"), _args.flag(friction, "friction")
    _args.optional(_args.instance, base, "base", BaseParameters)
    samples = _args.integer(samples, "samples", 1)
    grid = _args.optional(_args.integer, grid, "grid", 1)
    maxiter = _args.integer(maxiter, "maxiter", 1)
    margin = _args.number(margin, "margin", minimum=0.0, below=0.5)
    effort_share = _args.number(effort_share, "effort_share", positive=True, maximum=1.0)
    _args.optional(_args.mapping, limits, "limits")
    start = _args.optional(_args.array, start, "start", (robot.n,))
    progress = _args.flag(progress, "progress")
    if criterion not in CRITERIA:
        raise ArgumentError(f"unknown criterion '{criterion}'; choose one of {', '.join(CRITERIA)}")
    if harmonics < 2:
        raise ArgumentError(
            f"harmonics must be at least 2 (one is spent on zero start/end velocity and "
            f"acceleration), got {harmonics}"
        )
    if not freq > 0:
        raise ArgumentError(f"base frequency must be positive, got {freq}")
    if starts < 1:
        raise ArgumentError(f"starts must be at least 1, got {starts}")
    if not samples > 2 * harmonics:
        raise ArgumentError(
            f"{samples} regressor samples per period do not sample the highest of {harmonics} "
            f"harmonics; expected more than {2 * harmonics}"
        )
    robot = load(robot)
    stream = stream or sys.stderr
    t_begin = time.perf_counter()
    if base is None:
        base = base_parameters(robot, rotor=rotor, friction=friction)
    lim, notes = excitation_limits(
        robot,
        margin=margin,
        overrides=limits,
        effort_share=effort_share,
        rotor=base.rotor,
        friction=base.friction,
        harmonics=harmonics,
        freq=freq,
    )
    if start is not None:
        start = np.asarray(start, dtype=float).reshape(-1)
        if start.shape != (robot.n,):
            raise ArgumentError(f"start has shape {start.shape}; expected ({robot.n},)")
        bad = np.flatnonzero((start < lim["lower"]) | (start > lim["upper"]))
        if bad.size:
            k = int(bad[0])
            raise ArgumentError(
                f"start position of joint {k + 1} ({start[k]:g}) is outside its limits "
                f"[{lim['lower'][k]:g}, {lim['upper'][k]:g}] (after the {margin:g} margin)"
            )
    if samples * robot.n < base.n:
        raise ArgumentError(
            f"{samples} samples x {robot.n} joints = {samples * robot.n} regressor rows are "
            f"fewer than the {base.n} base parameters; raise samples"
        )
    grid = grid or max(100, 20 * harmonics)
    prob = _Problem(base, robot.n, harmonics, freq, lim, criterion, samples, grid, start)

    def say(msg: str, end: str = "\n") -> None:
        if progress:
            print(msg, end=end, file=stream, flush=True)

    for note in notes:
        say(f"excite: {note}")
    say(
        f"excite: {robot.name}, {base.n} base parameters, criterion {criterion}, "
        f"N={harmonics}, f={freq:g} Hz, {prob.n * prob.nf} free coefficients, "
        f"{starts} start(s), {prob.A.shape[0]} limit constraints"
    )
    shown = {"cond": "cond", "logdet": "logdet", "hadamard": "log hadamard ratio"}[criterion]

    def report(J: float) -> float:
        """The objective ``J`` (minimised) in the reported form of :func:`criterion_value`."""
        if criterion == "cond":
            return math.exp(J)
        return -J if criterion == "logdet" else J

    best = None
    runs = []
    rng = np.random.default_rng(seed)
    for s in range(starts):
        t0 = time.perf_counter()
        guess = random_trajectory(
            robot,
            harmonics=harmonics,
            freq=freq,
            seed=int(rng.integers(2**31)),
            limits=lim,
            start=start,
            fill=0.7,
        )
        x0 = _free_from(prob, guess)
        J0 = prob.objective(x0)
        it = {"k": 0, "last": time.perf_counter()}

        prob.best = J0

        live = bool(getattr(stream, "isatty", lambda: False)())  # redraw on a terminal only

        def callback(*_, it=it, s=s, live=live, t0=t0):
            it["k"] += 1
            now = time.perf_counter()
            if now - it["last"] > (0.5 if live else PROGRESS_SECONDS):
                it["last"] = now
                text = (
                    f"  start {s + 1}/{starts}: iteration {it['k']:>3}, "
                    f"best {shown} so far {report(prob.best):.6g}"
                )
                if live:  # redrawn in place
                    say(f"\r{text}   ", end="")
                else:  # a log or a pipe: a line now and then
                    say(f"{text} ({now - t0:.0f} s)")

        cons = [
            {
                "type": "ineq",
                "fun": lambda x: prob.ub - prob.A @ x,
                "jac": lambda x: -prob.A,
            }
        ]
        res = minimize(
            prob.objective,
            x0,
            method="SLSQP",
            constraints=cons,
            callback=callback,
            options={"maxiter": maxiter, "ftol": 1e-7},
        )
        x = res.x
        viol = prob.violation(x)
        if viol > 1e-6:  # infeasible end point: fall back to the feasible start
            traj = _scale_into_limits(prob.trajectory(x), lim, grid, start is not None)
            x = _free_from(prob, traj)
        J = prob.objective(x)
        if J > J0:
            x, J = x0, J0
        dt = time.perf_counter() - t0
        runs.append(
            {
                "initial": report(J0),
                "final": report(J),
                "iterations": int(res.nit),
                "seconds": dt,
                "message": str(res.message),
                "improved": bool(J < J0),
                "converged": bool(res.success),
            }
        )
        say(
            ("\r" if live else "")
            + f"  start {s + 1}/{starts}: {shown} {report(J0):.6g} -> {report(J):.6g} "
            f"({res.nit} iterations, {dt:.1f} s)          "
        )
        if best is None or J < best[1]:
            best = (x, J, J0, guess)
    assert best is not None  # starts >= 1
    x, J, J0, guess = best
    warnings = []
    if not any(r["improved"] or r["converged"] for r in runs):  # a random guess: say so
        why = "; ".join(sorted({str(r["message"]) for r in runs}))
        warnings.append(
            f"the optimiser (SLSQP) failed on all {starts} start(s) without improving on any "
            f"({why}): the trajectory is the best random start's, {shown} {report(J0):.6g}"
        )
        say(f"excite: WARNING: {warnings[-1]}")
    if J >= 60.0:  # no start found a trajectory with a full-rank regressor
        raise IdentificationError(
            f"no excitation found that excites all {base.n} base parameters of {robot.name} "
            "within the limits; widen the limits or add harmonics"
        )
    traj = prob.trajectory(x)
    # The optimiser saw the limits on a coarse grid only. Shrink against limits tightened by
    # 1e-3 on a grid 20 times finer: between its points (>= 200 per period of the highest
    # harmonic) a peak can exceed the sampled maximum by at most 1 - cos(pi / 200) ~ 1.2e-4.
    fine = 20 * grid
    t = np.arange(fine + 1) * (traj.period / fine)
    q, dq, ddq = traj.evaluate(t)
    rel = _relative_violation(q, dq, ddq, _tighten(lim, 1e-3))
    if rel > 0:
        if rel > 1e-3:
            say(f"excite: limits exceeded by {100 * rel:.3g} % between grid points; motion shrunk")
        traj = _scale_into_limits(traj, _tighten(lim, 1e-3), fine, start is not None)
        q, dq, ddq = traj.evaluate(t)
    peak = peak_torques(robot, q, dq, ddq, rotor=base.rotor, friction=base.friction)
    say(f"excite: {peak['line']}")
    over = np.flatnonzero(np.nan_to_num(np.array(peak["share"], dtype=float)) > 1.0)
    if over.size:  # what is left of the effort limit with the joints at rest along the path
        still = np.abs(_drive_torques(robot, q, 0 * dq, 0 * ddq, rotor=False, friction=False))
    for k in over:
        what = (
            f"joint {k + 1}: the trajectory's peak inverse-dynamics torque "
            f"{peak['torque'][k]:.4g} is {100 * peak['share'][k]:.0f} % of its effort limit "
            f"{peak['effort'][k]:g}"
        )
        gravity = still[:, k].max() / peak["effort"][k]
        derived = lim["acceleration_source"] == "effort"
        if gravity > 1.0:
            why = (
                f"gravity alone along it reaches {100 * gravity:.0f} %: no acceleration limit "
                "keeps it within; narrow the joints' position limits (or check the effort limit "
                "and the masses)"
            )
        elif derived.any():
            why = (
                f"the acceleration limits of joints {_joint_list(derived)} come "
                "from the effort limits: lower the effort share (or give acceleration limits)"
            )
        else:
            why = (
                "the acceleration limits are the "
                + (
                    "given ones"
                    if (lim["acceleration_source"] == "override").any()
                    else "description's"
                )
                + f" (gravity alone reaches {100 * gravity:.0f} %): lower them (the effort share "
                "applies only where no acceleration limit is given)"
            )
        warnings.append(f"{what}; {why}")
        say(f"excite: WARNING: {warnings[-1]}")
    tm = np.arange(samples) * (traj.period / samples)
    qm, dqm, ddqm = traj.evaluate(tm)
    value = criterion_value(base, qm, dqm, ddqm, criterion=criterion)
    elapsed = time.perf_counter() - t_begin
    say(f"excite: best {shown} {value:.6g} (initial guess {report(J0):.6g}), {elapsed:.1f} s")
    return ExcitationResult(
        robot=robot.name,
        trajectory=traj,
        criterion=criterion,
        value=value,
        initial_value=report(J0),
        limits=lim,
        notes=notes,
        starts=runs,
        seconds=elapsed,
        base_names=list(base.names),
        rotor=base.rotor,
        friction=base.friction,
        drive_train=drive_train_record(robot),
        seed=seed,
        max_violation=_relative_violation(q, dq, ddq, lim),
        initial_trajectory=guess,
        warnings=warnings,
        peak_torque=peak,
    )


def peak_torques(robot: Robot, q, dq, ddq, *, rotor: bool = False, friction: bool = False):
    """The largest inverse-dynamics torque magnitude per joint along samples ``q, dq, ddq``
    (each (m, n)), with the robot's rotor inertia and friction when asked, and its share of the
    joint's effort limit: a dict of lists ``torque``, ``effort`` and ``share`` (None where the
    description gives no effort limit) and ``line``, the statement printed."""
    _args.instance(robot, "robot", Robot)
    q, dq, ddq = _args.batch(robot.n, q=q, dq=dq, ddq=ddq)
    rotor, friction = _args.flag(rotor, "rotor"), _args.flag(friction, "friction")
    tau = _drive_torques(robot, q, dq, ddq, rotor=rotor, friction=friction)
    top = np.abs(tau).max(0)
    effort = np.array(robot.limits["effort"], dtype=float)
    has = np.isfinite(effort) & (effort > 0)
    share = np.where(has, top / np.where(has, effort, 1.0), np.nan)
    shown = ", ".join(f"{100 * v:.0f} %" if np.isfinite(v) else "-" for v in share)
    extra = " with rotor inertia" if rotor else ""
    extra += (" and friction" if rotor else " with friction") if friction else ""
    return {
        "torque": top.tolist(),
        "effort": [float(e) if h else None for e, h in zip(effort, has)],
        "share": [float(v) if np.isfinite(v) else None for v in share],
        "line": f"peak inverse-dynamics torque{extra} / effort limit per joint: {shown}",
    }


def _tighten(lim: dict, frac: float) -> dict:
    mid = 0.5 * (lim["lower"] + lim["upper"])
    half = 0.5 * (lim["upper"] - lim["lower"]) * (1 - frac)
    return {
        "lower": mid - half,
        "upper": mid + half,
        "velocity": lim["velocity"] * (1 - frac),
        "acceleration": lim["acceleration"] * (1 - frac),
    }


def _relative_violation(q, dq, ddq, lim) -> float:
    """Largest limit excess relative to the limit's size (0 when all limits hold)."""
    span = lim["upper"] - lim["lower"]
    v = [
        np.max((q - lim["upper"]) / span, initial=0.0),
        np.max((lim["lower"] - q) / span, initial=0.0),
        np.max(np.abs(dq) / lim["velocity"] - 1.0, initial=0.0),
        np.max(np.abs(ddq) / lim["acceleration"] - 1.0, initial=0.0),
    ]
    return float(max(v))


def _free_from(prob: _Problem, traj: FourierTrajectory) -> np.ndarray:
    """Free coefficients of ``traj`` (which must satisfy the boundary conditions)."""
    N = prob.N
    x = []
    for k in range(prob.n):
        xk = np.concatenate([traj.a[k, 1:], traj.b[k, 1:]])
        if prob.start is None:
            xk = np.concatenate([xk, [traj.q0[k]]])
        x.append(xk)
    assert len(x[0]) == prob.nf, (len(x[0]), prob.nf, N)
    return np.concatenate(x)


def plot_trajectory(path, t, q, dq, ddq, *, limits: dict | None = None, title: str = "") -> Path:
    """PNG of positions, velocities and accelerations per joint (limits dashed)."""
    _args.path(path, "path")
    t = _args.array(t, "t", (None,))
    q = _args.array(q, "q", (t.shape[0], None))
    dq = _args.array(dq, "dq", q.shape)
    ddq = _args.array(ddq, "ddq", q.shape)
    _args.optional(_args.mapping, limits, "limits")
    _args.text(title, "title", empty=True)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = q.shape[1]
    fig, axes = plt.subplots(3, 1, figsize=(9, 8), sharex=True)
    for ax, y, label, keys in (
        (axes[0], q, "position [rad | m]", ("lower", "upper")),
        (axes[1], dq, "velocity [/s]", ("velocity",)),
        (axes[2], ddq, "acceleration [/s^2]", ("acceleration",)),
    ):
        for k in range(n):
            (line,) = ax.plot(t, y[:, k], lw=1.0, label=f"joint {k + 1}")
            if limits is not None:
                for key in keys:
                    v = np.asarray(limits[key])[k]
                    ax.axhline(v, color=line.get_color(), ls="--", lw=0.6)
                    if key in ("velocity", "acceleration"):
                        ax.axhline(-v, color=line.get_color(), ls="--", lw=0.6)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(ncol=min(n, 6), fontsize=7, loc="upper right")
    axes[-1].set_xlabel("t [s]")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
