"""Inverse kinematics through the Jacobian.

- :func:`velocity_ik`: ``dq = J^+ dx`` for a tool twist ``dx``, with damped least squares near
  singularities and optional null-space motion for redundant arms;
- :func:`resolved_rate`: online velocity control along a Cartesian path, ``q`` read back every
  cycle (the textbook's scheme), with feedback on the pose error;
- :func:`ik` / :func:`ik_solve`: position IK by iterating the velocity solution (damped least
  squares / Levenberg-Marquardt in C++), inside the joint limits, with seeded random restarts.

Twists and Jacobians follow :meth:`mindyn.Robot.jacobian`: ``(vx, vy, vz, wx, wy, wz)`` in the base
frame, the linear part the velocity of the tool-frame origin. Pose errors are the twist that moves
a frame onto another in unit time: ``(p_d - p, rotation vector of R_d R^T)``.

``mindyn.ik`` is the function :func:`ik`; the other names are imported from this module,
``mindyn.inverse_kinematics``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from . import _args, _core
from ._args import ArgumentError
from .robot import Robot

__all__ = [
    "IkResult",
    "circle_path",
    "damped_pinv",
    "ik",
    "ik_solve",
    "limits_gradient",
    "line_path",
    "pose_error",
    "pose_from_xyz_rpy",
    "pose_rank",
    "resolved_rate",
    "velocity_ik",
]

TASKS = {"pose": [0, 1, 2, 3, 4, 5], "position": [0, 1, 2], "orientation": [3, 4, 5]}
#: The default weight [m/rad] of :func:`ik_solve`'s orientation error against its position error
IK_ORIENTATION_WEIGHT = 0.3


# ---------------------------------------------------------------------------------------------
# Poses
# ---------------------------------------------------------------------------------------------
def pose_error(T: np.ndarray, T_desired: np.ndarray) -> np.ndarray:
    """Twist ``(p_d - p, log(R_d R^T))``, shape (6,), taking pose ``T`` onto ``T_desired`` (4x4
    each, base frame)."""
    return _core.pose_error(_pose(T, "T"), _pose(T_desired, "T_desired"))


def pose_from_xyz_rpy(xyz, rpy) -> np.ndarray:
    """4x4 pose from a position and roll-pitch-yaw angles (URDF convention, fixed axes:
    ``R = Rz(yaw) Ry(pitch) Rx(roll)``)."""
    from scipy.spatial.transform import Rotation

    xyz = _args.array(xyz, "xyz", (3,))
    rpy = _args.array(rpy, "rpy", (3,))
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("xyz", rpy).as_matrix()  # extrinsic x, then y, then z
    T[:3, 3] = xyz
    return T


def _pose(T, name: str) -> np.ndarray:
    T = _args.array(T, name, (4, 4))
    R = T[:3, :3]
    # a rotation's entries are at most 1: larger ones are refused before R^T R (which could
    # overflow)
    if np.abs(R).max() > 1.0 + 1e-6 or np.abs(R.T @ R - np.eye(3)).max() > 1e-6:
        raise ArgumentError(f"{name}: the upper-left 3x3 block is not a rotation matrix")
    if np.linalg.det(R) < 0:
        raise ArgumentError(f"{name}: the upper-left 3x3 block is not a rotation matrix")
    if np.any(T[3] != [0.0, 0.0, 0.0, 1.0]):
        raise ArgumentError(f"{name}: the last row must be (0, 0, 0, 1)")
    return T


# ---------------------------------------------------------------------------------------------
# Velocity IK
# ---------------------------------------------------------------------------------------------
def damped_pinv(J, *, damping: float = 0.05, threshold: float = 0.02) -> np.ndarray:
    """Damped pseudo-inverse ``V diag(s / (s^2 + lambda^2)) U^T`` of ``J`` (m x n).

    ``lambda^2 = damping^2 (1 - (s_min / threshold)^2)`` when the smallest singular value
    ``s_min`` is below ``threshold`` and 0 otherwise: the exact pseudo-inverse away from
    singularities, bounded joint speeds near them."""
    J = _args.array(J, "J", (None, None))
    damping = _args.number(damping, "damping", minimum=0.0)
    threshold = _args.number(threshold, "threshold", minimum=0.0)
    U, s, Vt = np.linalg.svd(J, full_matrices=False)
    smin = s[-1] if s.size else 0.0
    lam2 = 0.0
    if threshold > 0 and smin < threshold:
        lam2 = damping**2 * (1.0 - (smin / threshold) ** 2)
    if lam2 == 0.0:
        keep = s > s[0] * 1e-12 if s.size else s
        inv = np.zeros_like(s)
        inv[keep] = 1.0 / s[keep]
    else:
        inv = s / (s**2 + lam2)
    return (Vt.T * inv) @ U.T


def _task_rows(task) -> list[int]:
    if isinstance(task, str):
        if task not in TASKS:
            raise ArgumentError(f"task must be one of {', '.join(TASKS)} or a list of rows 0..5")
        return TASKS[task]
    if not isinstance(task, (list, tuple, np.ndarray)):
        raise _args.fail("task", f"is {task!r}; expected one of {', '.join(TASKS)} or rows 0..5")
    if any(isinstance(r, (bool, np.bool_)) or not isinstance(r, (int, np.integer)) for r in task):
        raise _args.fail("task", "rows must be distinct integers in 0..5")
    rows = [int(r) for r in task]
    if not rows or any(r < 0 or r > 5 for r in rows) or len(set(rows)) != len(rows):
        raise ArgumentError("task rows must be distinct integers in 0..5")
    return rows


def limits_gradient(robot: Robot, q) -> np.ndarray:
    """A null-space motion that moves joints towards the middle of their limits:
    ``-(q - q_mid) / half_range^2`` (zero for joints without limits)."""
    _args.instance(robot, "robot", Robot)
    lim = robot.limits
    lo, hi = lim["lower"], lim["upper"]
    ok = np.isfinite(lo) & np.isfinite(hi) & (hi > lo)
    q = _args.array(q, "q", (robot.n,), unit="joint")
    z = np.zeros(robot.n)
    mid = 0.5 * (lo + hi)
    half = 0.5 * (hi - lo)
    z[ok] = -(q[ok] - mid[ok]) / half[ok] ** 2
    return z


def velocity_ik(
    robot: Robot,
    q,
    twist,
    *,
    task="pose",
    damping: float = 0.05,
    threshold: float = 0.02,
    nullspace=None,
) -> np.ndarray:
    """Joint velocities for a commanded tool twist.

    ``dq = J^+ dx + (I - J^+ J) z`` with ``J`` the rows ``task`` of the tool Jacobian at ``q``
    and ``J^+`` :func:`damped_pinv` (exact away from singularities).

    Parameters
    ----------
    robot : Robot
    q : array (n,)
        Current joint positions (the sensor reading in online control).
    twist : array (len(rows),)
        Commanded ``(vx, vy, vz, wx, wy, wz)`` restricted to the task rows.
    task : "pose", "position", "orientation" or a list of rows of the 6-row Jacobian
    damping, threshold : float
        Damped least squares near singularities (see :func:`damped_pinv`).
    nullspace : None, array (n,), callable ``q -> (n,)`` or "limits"
        Secondary joint motion ``z`` projected on the null space of the task (redundant arms);
        ``"limits"`` uses :func:`limits_gradient`.

    Returns
    -------
    dq : ndarray (n,)
    """
    _args.instance(robot, "robot", Robot)
    robot._require_serial("inverse kinematics (velocity_ik)")
    robot._require_single_dof("inverse kinematics (velocity_ik)")
    q = _args.array(q, "q", (robot.n,), unit="joint")
    rows = _task_rows(task)
    x = _args.array(twist, "twist", (len(rows),))
    J = robot.jacobian(q)[rows]
    Jp = damped_pinv(J, damping=damping, threshold=threshold)
    dq = Jp @ x
    if nullspace is not None:
        if isinstance(nullspace, str):
            if nullspace != "limits":
                raise ArgumentError("nullspace must be None, an array, a callable or 'limits'")
            z = limits_gradient(robot, q)
        elif callable(nullspace):
            z = np.asarray(nullspace(q), dtype=float)
        else:
            z = nullspace
        z = _args.array(z, "nullspace", (robot.n,), unit="joint")
        dq = dq + z - Jp @ (J @ z)
    return dq


# ---------------------------------------------------------------------------------------------
# Cartesian paths: callables t -> (T_d (4, 4), twist_d (6,))
# ---------------------------------------------------------------------------------------------
def circle_path(T0, radius: float, period: float, *, normal=(0.0, 0.0, 1.0)):
    """A circle through the position of ``T0`` at constant orientation: centre
    ``p0 - radius u``, ``p(t) = c + radius (cos(w t) u + sin(w t) v)``, ``(u, v, normal)``
    right-handed, ``w = 2 pi / period``."""
    T0 = _pose(T0, "T0")
    radius = _args.number(radius, "radius", positive=True)
    period = _args.number(period, "period", positive=True)
    nrm = _args.array(normal, "normal", (3,))
    if not np.linalg.norm(nrm) > 0:
        raise _args.fail("normal", "is the zero vector; expected a direction")
    nrm = nrm / np.linalg.norm(nrm)
    u = np.cross(nrm, [1.0, 0.0, 0.0])
    if np.linalg.norm(u) < 1e-6:
        u = np.cross(nrm, [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(nrm, u)
    c = T0[:3, 3] - radius * u
    w = 2 * np.pi / period

    def path(t: float):
        T = T0.copy()
        T[:3, 3] = c + radius * (np.cos(w * t) * u + np.sin(w * t) * v)
        vel = radius * w * (-np.sin(w * t) * u + np.cos(w * t) * v)
        return T, np.concatenate([vel, np.zeros(3)])

    return path


def line_path(T0, T1, duration: float):
    """A straight line with the orientation turning about a fixed axis, both with the quintic
    time scaling ``s(t)`` (zero speed and acceleration at both ends)."""
    T0 = _pose(T0, "T0")
    T1 = _pose(T1, "T1")
    duration = _args.number(duration, "duration", positive=True)
    dp = T1[:3, 3] - T0[:3, 3]
    rv = _core.pose_error(T0, T1)[3:]

    def path(t: float):
        from scipy.spatial.transform import Rotation

        x = min(max(t / duration, 0.0), 1.0)
        s = 10 * x**3 - 15 * x**4 + 6 * x**5
        ds = (30 * x**2 - 60 * x**3 + 30 * x**4) / duration if 0 < t < duration else 0.0
        T = np.eye(4)
        T[:3, 3] = T0[:3, 3] + s * dp
        T[:3, :3] = Rotation.from_rotvec(s * rv).as_matrix() @ T0[:3, :3]
        return T, np.concatenate([ds * dp, ds * rv])

    return path


@dataclass
class RateResult:
    """Resolved-rate run: ``t`` (K,), ``q`` and ``dq`` (K, n), ``error`` (K, 6) pose error of
    the tool against the path at each cycle (before the update)."""

    t: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    error: np.ndarray

    @property
    def max_position_error(self) -> float:
        return float(np.linalg.norm(self.error[:, :3], axis=1).max())

    @property
    def max_orientation_error(self) -> float:
        return float(np.linalg.norm(self.error[:, 3:], axis=1).max())


def resolved_rate(
    robot: Robot,
    q0,
    path: Callable[[float], tuple],
    duration: float,
    *,
    dt: float = 0.004,
    gain: float = 10.0,
    **velocity_options,
) -> RateResult:
    """Online velocity control along ``path``: every cycle read ``q``, command
    ``dx = twist_d + gain * pose_error(fk(q), T_d)`` (pose task) and integrate
    ``dq = velocity_ik(q, dx)`` over ``dt`` (the joints are assumed to follow the commanded
    velocity). ``velocity_options`` go to :func:`velocity_ik` (``nullspace``, ``damping``, ...).
    """
    _args.instance(robot, "robot", Robot)
    robot._require_serial("inverse kinematics (resolved_rate)")
    robot._require_single_dof("inverse kinematics (resolved_rate)")
    _args.function(path, "path")
    duration = _args.number(duration, "duration", positive=True)
    dt = _args.number(dt, "dt", positive=True)
    gain = _args.number(gain, "gain", minimum=0.0)
    q = _args.array(q0, "q0", (robot.n,), unit="joint").copy()
    K = int(round(duration / dt)) + 1
    t = np.arange(K) * dt
    Q, DQ, E = np.zeros((K, robot.n)), np.zeros((K, robot.n)), np.zeros((K, 6))
    for i in range(K):
        Td, twist = path(t[i])
        e = pose_error(robot.fk(q), Td)
        dq = velocity_ik(robot, q, np.asarray(twist) + gain * e, **velocity_options)
        Q[i], DQ[i], E[i] = q, dq, e
        q = q + dt * dq
    return RateResult(t, Q, DQ, E)


# ---------------------------------------------------------------------------------------------
# Position IK
# ---------------------------------------------------------------------------------------------
@dataclass
class IkResult:
    """Outcome of :func:`ik_solve`.

    status: ``"converged"`` (pose error within tolerance, inside the limits), ``"not converged"``
    (all attempts used: unreachable or too hard), ``"timeout"`` (budget used up).
    ``q`` is the solution, or the best point found; ``error`` its pose error
    ``|log6(T_target^-1 T(q))|``, the norm of a twist whose translation is in metres and rotation
    in radians, unweighted (as Pinocchio's ``pin.log6(oMdes.actInv(oMq)).vector`` norm; the
    solver's tolerance applies to it); ``position_error`` [m] the distance of the tool frame's
    origin from the target's and ``orientation_error`` [rad] the angle of the rotation between
    their orientations, each in its own unit. ``position_only`` (``orientation_weight=0``): the
    orientation was free, and ``error`` is ``position_error``."""

    q: np.ndarray
    success: bool
    status: str
    error: float
    iterations: int
    attempts: int
    position_error: float = math.nan
    orientation_error: float = math.nan
    position_only: bool = False

    def error_text(self) -> str:
        """The errors in words, each with its unit: position [m], orientation [rad, deg], and
        the pose error the tolerance applies to (position only: that the orientation was
        free)."""
        orientation = (
            f"orientation error {self.orientation_error:.3g} rad "
            f"({math.degrees(self.orientation_error):.3g} deg)"
        )
        if self.position_only:
            return (
                f"position error {self.position_error:.3g} m (position only: the tolerance "
                f"applies to it; the orientation free, {orientation} from the target's)"
            )
        return (
            f"position error {self.position_error:.3g} m, {orientation}; "
            f"pose error |log6| {self.error:.3g} (m and rad together, unweighted)"
        )


def ik_solve(
    robot: Robot,
    T_target,
    q0=None,
    *,
    tolerance: float = 1e-5,
    max_time: float = 0.1,
    max_attempts: int = 100,
    max_iterations: int = 100,
    orientation_weight: float = IK_ORIENTATION_WEIGHT,
    seed: int = 42,
) -> IkResult:
    """Joint positions inside the limits that put the tool frame at ``T_target`` (4x4, base
    frame), by damped least squares with random restarts (C++). Once the pose error is within
    ``tolerance``, Newton steps continue (at most ten, the best point kept) until it is at
    rounding level: a converged answer is as precise as the arithmetic allows (about 1e-15)
    unless a joint limit stops it.

    Parameters
    ----------
    q0 : array (n,), optional
        Start (default: the middle of the limits); values outside the limits are brought inside.
    tolerance : float
        Largest accepted pose error ``|log6(T_target^-1 T(q))|`` (m, rad); position only: the
        largest position error [m].
    max_time : float
        CPU-time budget in seconds (0: none); ``max_attempts`` bounds the restarts.
    orientation_weight : float
        Weight [m/rad] of the orientation error against the position error in the steps; 0:
        position only (the orientation free; for a tool whose pose moves in fewer than six
        independent directions, :func:`pose_rank`, which reaches most positions in few
        orientations only).
    seed : int
        Seed of the restart points (same seed, same answer).
    """
    _args.instance(robot, "robot", Robot)
    robot._require_serial("inverse kinematics (ik_solve)")
    T = _pose(T_target, "T_target")
    if q0 is not None:
        q0 = _args.array(q0, "q0", (robot.n,), unit="joint")
    solver_options = dict(
        tolerance=_args.number(tolerance, "tolerance", positive=True),
        max_iterations=_args.integer(max_iterations, "max_iterations", minimum=1),
        max_attempts=_args.integer(max_attempts, "max_attempts", minimum=1),
        max_time=_args.number(max_time, "max_time", minimum=0.0),
        orientation_weight=_args.number(orientation_weight, "orientation_weight", minimum=0.0),
        seed=_args.integer(seed, "seed", minimum=0),
    )
    solver = _core.IkSolver(robot._m, **solver_options)
    given = q0
    if q0 is None:
        q0 = 0.5 * (solver.lower + solver.upper)
    r = solver.solve(T, q0)
    q = np.asarray(r["q"])
    # (p_target - p, rotation vector of R_target R^T); a target so far that the errors
    # overflow (|p| near 1e308) is refused below, not warned about by numpy
    with np.errstate(over="ignore", invalid="ignore"):
        e = pose_error(robot.fk(q), T)
        errors = [float(r["error"]), float(np.linalg.norm(e[:3])), float(np.linalg.norm(e[3:]))]
    if not np.isfinite(errors).all():
        inputs = {"T_target's position": T[:3, 3]}  # its rotation's entries are at most 1
        if given is not None:
            inputs["q0"] = given
        raise _args.overflow("ik_solve", **inputs)
    return IkResult(
        q=q,
        success=bool(r["success"]),
        status=r["status"],
        error=errors[0],
        iterations=int(r["iterations"]),
        attempts=int(r["attempts"]),
        position_error=errors[1],
        orientation_error=errors[2],
        position_only=solver_options["orientation_weight"] == 0,
    )


#: Configurations :func:`pose_rank` samples, and the span it samples a joint without limits in
#: (rad for a revolute joint, m for a prismatic one)
POSE_RANK_SAMPLES = 8
POSE_RANK_UNLIMITED = math.pi


def pose_rank(robot: Robot, *, samples: int = POSE_RANK_SAMPLES, seed: int = 0):
    """How many independent directions the tool frame's pose moves in: the rank of the tool
    frame's Jacobian (:meth:`~mindyn.Robot.jacobian`) over the joints that move it, the
    largest at ``samples`` random configurations within the limits (a joint without limits:
    within +-:data:`POSE_RANK_UNLIMITED`; a singular configuration has a lower rank, random
    ones the robot's). Returns ``(rank, joints)``, ``joints`` the 0-based joints whose columns
    are not zero anywhere. Below 6, most poses are out of reach whatever the joint count: a
    five-joint arm, a planar one, a wrist joint coaxial with the one before it, a joint on
    another branch of a tree than the tool's."""
    _args.instance(robot, "robot", Robot)
    samples = _args.integer(samples, "samples", minimum=1)
    seed = _args.integer(seed, "seed", minimum=0)
    if not robot.single_dof:
        raise _core.ModelError(
            f"pose_rank takes revolute and prismatic joints only; robot '{robot.name}' has "
            "joints of several degrees of freedom"
        )
    lower = np.asarray(robot.limits["lower"], dtype=float)
    upper = np.asarray(robot.limits["upper"], dtype=float)
    bounded = np.isfinite(lower) & np.isfinite(upper)
    lower = np.where(bounded, lower, -POSE_RANK_UNLIMITED)
    upper = np.where(bounded, upper, POSE_RANK_UNLIMITED)
    rng = np.random.default_rng(seed)
    rank, moving = 0, np.zeros(robot.n, dtype=bool)
    for _ in range(samples):
        J = robot.jacobian(rng.uniform(lower, upper))
        scale = np.abs(J).max()
        moving |= np.abs(J).max(axis=0) > 1e-12 * max(scale, 1e-300)
        rank = max(rank, int(np.linalg.matrix_rank(J[:, moving])) if moving.any() else 0)
    return rank, [int(j) for j in np.flatnonzero(moving)]


def ik(robot: Robot, T_target, q0=None, **options) -> tuple[np.ndarray, bool]:
    """``(q, success)`` of :func:`ik_solve` (same options)."""
    r = ik_solve(robot, T_target, q0, **options)
    return r.q, r.success
