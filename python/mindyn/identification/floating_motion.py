"""Velocities and accelerations of a floating-base log from its configurations alone, by the
differentiation rules of the fixed-base logs (:func:`~mindyn.identification.data.differentiate`:
``butter``, ``savgol`` or ``none``; velocities from the filtered configuration, accelerations
from the filtered velocities, as :func:`~mindyn.identification.data.fill_derivatives` does),
with each joint's velocity in its own convention (Pinocchio's):

- a free-flyer ``(p, x, y, z, w)``: the quaternion's sign made continuous, position and
  quaternion filtered and differentiated, the quaternion renormalised (its derivative projected
  on the tangent space); the velocity is ``(R^T p', w_b)``, linear then angular in the body's
  axes, ``(0, w_b) = 2 conj(Q) (x) Q'`` (``Q' = Q (x) (0, w_b) / 2``, Hamilton product);
- a spherical joint ``(x, y, z, w)``: ``w_b`` as above;
- a planar joint ``(x, y, cos th, sin th)``: ``th`` unwrapped, then ``(R(th)^T (x', y'), th')``;
- every other joint: the derivative of its coordinates.

The accelerations are the time derivatives of these velocity coordinates (Pinocchio's ``a`` of
a free-flyer: the derivative of its body-axis twist). The samples at each end where the
derivatives are not those of the motion (one-sided differences; a filter's start-up) are
counted in ``edge_samples`` of the settings: 2 for ``none``, the half window for ``savgol`` and
``2 / cutoff`` seconds for ``butter`` (the fixed-base data path's filter edge) per derivation
(two when the velocities are derived too), each plus 2;
:func:`~mindyn.identification.floating.read_floating_csv` drops them."""

from __future__ import annotations

import numpy as np

from .. import _args
from ..robot import Robot
from .data import DataError, differentiate, filter_edge

__all__ = ["configuration_derivatives"]

_NQ = {"spherical": 4, "planar": 4, "floating": 7, "universal": 2, "cylindrical": 2}
_FILTERS = ("butter", "savgol", "none")


def _rotation(Q: np.ndarray) -> np.ndarray:
    """Rotation matrices (m, 3, 3) of unit quaternions (m, 4) in the order x, y, z, w."""
    x, y, z, w = Q.T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=1,
    )


def _continuous(Q: np.ndarray) -> np.ndarray:
    """Quaternions (m, 4) with the sign of each chosen to follow the previous sample's (q and -q
    are the same rotation)."""
    Q = Q.copy()
    for i in range(1, len(Q)):
        if Q[i] @ Q[i - 1] < 0:
            Q[i] = -Q[i]
    return Q


def _unit(Q: np.ndarray, dQ: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The filtered quaternions renormalised, and their derivatives on the unit sphere."""
    norm = np.linalg.norm(Q, axis=1, keepdims=True)
    Qn = Q / norm
    return Qn, (dQ - Qn * np.sum(Qn * dQ, axis=1, keepdims=True)) / norm


def _body_rate(Q: np.ndarray, dQ: np.ndarray) -> np.ndarray:
    """The body angular velocity ``w_b`` (m, 3) of unit quaternions Q and their derivatives:
    the vector part of ``2 conj(Q) (x) Q'``."""
    u, w = Q[:, :3], Q[:, 3:]
    du, dw = dQ[:, :3], dQ[:, 3:]
    return 2.0 * (w * du - dw * u - np.cross(u, du))


def edge_samples(info: dict, *, derivations: int = 1) -> int:
    """The samples at each end of a log whose derivatives by the settings ``info`` of
    :func:`~mindyn.identification.data.differentiate` are not the motion's: the filter's edge
    (:func:`~mindyn.identification.data.filter_edge`: ``savgol``, half its window; ``butter``,
    ``2 / cutoff`` seconds) of each of the ``derivations`` taken (accelerations from derived
    velocities filter the velocities' edge error again, as
    :func:`~mindyn.identification.data.fill_derivatives` counts) and the two one-sided
    differences of velocity and acceleration."""
    _args.mapping(info, "info")
    derivations = _args.integer(derivations, "derivations", 1, maximum=2)
    return derivations * filter_edge(info) + 2


def configuration_derivatives(robot: Robot, t, q, *, filter: str = "butter", cutoff=None):
    """The filtered configurations ``q`` (m, nq), velocities ``dq`` and accelerations ``ddq``
    (m, nv) of a log of configurations ``q`` (m, nq) at times ``t`` (m,), and the settings of
    the differentiation (a dict, for the report): see the module's docstring.

    ``filter``, ``cutoff``: as :func:`~mindyn.identification.data.differentiate` (``butter``:
    zero-phase Butterworth, default cut-off ``min(10 Hz, rate / 10)``; ``savgol``; ``none``:
    central differences of the logged values). Raises DataError for a log too short for the
    filter or a cut-off out of range."""
    _args.instance(robot, "robot", Robot)
    t = _args.array(t, "t", (None,))
    q = _args.array(q, "q", (len(t), robot.nq))
    _args.choice(filter, "filter", _FILTERS)
    cutoff = _args.optional(_args.number, cutoff, "cutoff", positive=True)
    if len(t) < 3:
        raise DataError(f"{len(t)} samples are too few to differentiate (at least 3)")
    if np.any(np.diff(t) <= 0):
        raise DataError("the time stamps t must increase from sample to sample")
    # the smooth coordinates: every configuration entry, a continuous quaternion, an unwrapped
    # planar angle in place of its (cos, sin)
    kinds: list[str] = []
    starts: list[int] = []
    cols: list[np.ndarray] = []
    i = 0
    for kind in robot.joint_types:
        nq = _NQ.get(kind, 1)
        block = q[:, i : i + nq]
        if kind == "floating":
            block = np.hstack([block[:, :3], _continuous(block[:, 3:])])
        elif kind == "spherical":
            block = _continuous(block)
        elif kind == "planar":
            block = np.column_stack([block[:, :2], np.unwrap(np.arctan2(block[:, 3], block[:, 2]))])
        kinds.append(kind)
        starts.append(sum(c.shape[1] for c in cols))
        cols.append(block)
        i += nq
    X = np.hstack(cols)
    Xf, dX, info = differentiate(t, X, filter=filter, cutoff=cutoff)
    qf, dq = [], []
    for kind, s, block in zip(kinds, starts, cols, strict=True):
        x, dx = Xf[:, s : s + block.shape[1]], dX[:, s : s + block.shape[1]]
        if kind == "floating":
            Q, dQ = _unit(x[:, 3:], dx[:, 3:])
            v = np.einsum("mji,mj->mi", _rotation(Q), dx[:, :3])  # R^T p'
            qf.append(np.hstack([x[:, :3], Q]))
            dq.append(np.hstack([v, _body_rate(Q, dQ)]))
        elif kind == "spherical":
            Q, dQ = _unit(x, dx)
            qf.append(Q)
            dq.append(_body_rate(Q, dQ))
        elif kind == "planar":
            th, c, s_ = x[:, 2], np.cos(x[:, 2]), np.sin(x[:, 2])
            vx = c * dx[:, 0] + s_ * dx[:, 1]
            vy = -s_ * dx[:, 0] + c * dx[:, 1]
            qf.append(np.column_stack([x[:, :2], np.cos(th), np.sin(th)]))
            dq.append(np.column_stack([vx, vy, dx[:, 2]]))
        else:
            qf.append(x)
            dq.append(dx)
    dq_all = np.hstack(dq)
    _, ddq, _ = differentiate(t, dq_all, filter=filter, cutoff=cutoff)
    info = {
        **info,
        "edge_samples": edge_samples(info, derivations=2),
        "velocity": "differentiated configurations (body-axis velocities of the free-flyer, "
        "spherical and planar joints)",
        "acceleration": "differentiated velocities",
    }
    return np.hstack(qf), dq_all, ddq, info
