"""Identification of a floating-base robot (a free-flyer or planar root joint) from logs with
measured contact wrenches, or in free flight.

The equations of motion with contacts are ``W(q, dq, ddq) params = S^T tau + sum_c J_c^T f_c``:
``W`` the classical regressor (``Robot.regressor``, nv rows), ``S^T tau`` the joint torques in the
rows of the actuated coordinates and zero in the root joint's (6 for a free-flyer, 3 for a planar
root: nothing drives the base), ``f_c`` the wrench the environment applies on contact link ``c``
and ``J_c`` that link's Jacobian (:func:`contact_jacobian`). Two models come from them:

- ``"full"``: every row; needs the joint torques (with no contact, free flight);
- ``"base"`` (the base-link model): the root joint's rows only, whose left side is zero: needs no
  joint torques, only the motion and the wrenches.

The parameters are estimated as the numerical method's base parameters of the robot
(:func:`mindyn.base_parameters`) by weighted least squares, one noise level per coordinate
(:func:`identify_floating`); the base-link model may identify fewer combinations of them (its
``rank``), and gives the minimum-norm solution in their span.

Log format (CSV, one header line, one row per sample, comma-separated, as
:mod:`~mindyn.identification.data` reads its cells)::

    [t], q1..q<nq>, [dq1..dq<nv>], [ddq1..ddq<nv>], [tau1..tau<na>], [<link>.fx .. <link>.tz]

``t`` (s) is needed only when ``dq`` or ``ddq`` is not logged (they are then derived: see
:func:`read_floating_csv`); ``q`` is the robot's
configuration in its nq convention (a free-flyer's position, then its unit quaternion x, y, z,
w); ``dq``, ``ddq`` its nv velocities and accelerations (a free-flyer's linear
then angular velocity in its body's axes, as Pinocchio); ``tau1..tau<na>`` the generalized forces
of the actuated coordinates (nv minus the root's, in that order); for each contact link, six
columns ``<link>.fx, <link>.fy, <link>.fz, <link>.tx, <link>.ty, <link>.tz``: the force (N) and
the moment (N m) the environment applies on the link, about the link's origin, in world axes
(``wrench_frame="world"``, Pinocchio's LOCAL_WORLD_ALIGNED) or in the link's own axes
(``"local"``, as a force/torque sensor fixed to the link measures it). Columns may come in any
order; each once.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import _args
from .._threads import single_threaded_blas
from ..base import BaseParameters, base_parameters
from ..robot import Robot
from .data import (
    DataError,
    DataFileNotFoundError,
    check_time_units,
    decode_text,
    differentiate,
    parse_cell,
)
from .errors import IdentificationError
from .estimation import _triangle

__all__ = [
    "FloatingLog",
    "FloatingResult",
    "contact_jacobian",
    "floating_system",
    "identify_floating",
    "read_floating_csv",
]

WRENCH_AXES = ("fx", "fy", "fz", "tx", "ty", "tz")
_FRAMES = ("world", "local")
_MODELS = ("full", "base")


def _root_dofs(robot: Robot) -> int:
    """The unactuated coordinates of the root joint: 6 (free-flyer) or 3 (planar); refuses a
    robot whose root is another joint."""
    kind = robot.joint_types[0] if robot.n else ""
    if kind == "floating":
        return 6
    if kind == "planar":
        return 3
    raise IdentificationError(
        f"floating-base identification needs a free-flyer or planar root joint; robot "
        f"'{robot.name}' has the {kind or 'no'} joint '{robot.joint_names[0] if robot.n else ''}' "
        "at its root (load it with root_joint='floating' or 'planar')"
    )


def _link_index(robot: Robot, link: str | int) -> int:
    names = robot.link_names[1:]
    if isinstance(link, (int, np.integer)) and not isinstance(link, bool):
        if 0 <= link < robot.n:
            return int(link)
        raise _args.fail("link", f"is {link}; expected a joint index in 0..{robot.n - 1}")
    _args.instance(link, "link", (str, int), "a link name or a joint index")
    if link in names:
        return names.index(link)
    raise _args.fail(
        "link",
        f"is {link!r}, no moving link of robot '{robot.name}' ({', '.join(names)})"
        + robot._fixed_link_hint(link),
    )


def contact_jacobian(robot: Robot, q, link: str | int, *, frame: str = "world") -> np.ndarray:
    """The Jacobian of a link's origin, shape (6, nv): ``[v; w] = J dq`` with ``v`` the velocity
    of the link's origin and ``w`` the link's angular velocity, in world axes (``frame="world"``,
    Pinocchio's ``getFrameJacobian`` with LOCAL_WORLD_ALIGNED) or in the link's axes
    (``"local"``, Pinocchio's LOCAL). A wrench ``f = (force, moment about the origin)`` in the
    same axes acting on the link gives the generalized force ``J^T f``.

    ``link`` is a name of ``robot.link_names`` (not the fixed world) or a joint index k (the link
    joint k moves): :meth:`mindyn.Robot.jacobian` of that link."""
    _args.instance(robot, "robot", Robot)
    return robot.jacobian(q, link=_link_index(robot, link), frame=frame)


@dataclass
class FloatingLog:
    """A floating-base log: ``q`` (m, nq), ``dq`` and ``ddq`` (m, nv), ``tau`` (m, na) of the
    actuated coordinates or None, ``wrenches`` per contact link name (m, 6) (force then moment
    about the link's origin, in ``wrench_frame`` axes: ``"world"`` or ``"local"``)."""

    q: np.ndarray
    dq: np.ndarray
    ddq: np.ndarray
    tau: np.ndarray | None = None
    wrenches: dict[str, np.ndarray] = field(default_factory=dict)
    wrench_frame: str = "world"
    source: str = "<memory>"
    processing: dict = field(default_factory=dict)  # how dq and ddq were obtained

    @property
    def m(self) -> int:
        return len(self.q)


def _check_log(robot: Robot, log: FloatingLog) -> tuple[int, list[int]]:
    _args.instance(robot, "robot", Robot)
    _args.instance(log, "log", FloatingLog)
    r = _root_dofs(robot)
    m = len(np.asarray(log.q))
    for name, a, width in (
        ("q", log.q, robot.nq),
        ("dq", log.dq, robot.nv),
        ("ddq", log.ddq, robot.nv),
    ):
        if np.shape(a) != (m, width):
            raise IdentificationError(
                f"{log.source}: {name} has shape {np.shape(a)}, expected ({m}, {width})"
            )
    if log.tau is not None and np.shape(log.tau) != (m, robot.nv - r):
        raise IdentificationError(
            f"{log.source}: tau has shape {np.shape(log.tau)}, expected ({m}, {robot.nv - r}) "
            "(the actuated coordinates)"
        )
    if log.wrench_frame not in _FRAMES:
        raise IdentificationError(
            f"wrench_frame must be 'world' or 'local', not {log.wrench_frame!r}"
        )
    links = []
    names = robot.link_names[1:]
    for name, w in log.wrenches.items():
        if name not in names:
            raise IdentificationError(
                f"{log.source}: a wrench on {name!r}, no moving link of robot '{robot.name}' "
                f"({', '.join(names)})" + robot._fixed_link_hint(name)
            )
        links.append(names.index(name))
        if np.shape(w) != (m, 6):
            raise IdentificationError(
                f"{log.source}: the wrench of link {name!r} has shape {np.shape(w)}, "
                f"expected ({m}, 6)"
            )
    blocks = [("q", log.q), ("dq", log.dq), ("ddq", log.ddq), ("tau", log.tau)]
    blocks += [(f"the wrench of link {k!r}", w) for k, w in log.wrenches.items()]
    for name, a in blocks:
        if a is None:
            continue
        bad = np.flatnonzero(~np.isfinite(np.asarray(a, dtype=float)))
        if len(bad):
            row = int(bad[0]) // int(np.shape(a)[1])
            raise IdentificationError(f"{log.source}: {name} has a non-finite value (sample {row})")
    if m == 0:
        raise IdentificationError(f"{log.source}: the log has no sample")
    return r, links


def floating_system(robot: Robot, log: FloatingLog, *, model: str = "full"):
    """The stacked system ``(W, b)`` of a floating-base log: ``W`` the classical regressor rows
    (m * rows, 10 n), ``b`` the measured generalized forces ``S^T tau + sum_c J_c^T f_c``
    (``model="full"``: all nv rows per sample, needs ``tau``) or ``sum_c J_c^T f_c`` in the root
    joint's rows (``model="base"``: needs no torques)."""
    _args.choice(model, "model", _MODELS)
    r, links = _check_log(robot, log)
    if model == "full" and log.tau is None:
        raise IdentificationError(
            f"{log.source}: the full model needs the joint torques (tau columns); the base-link "
            "model (model='base') needs none"
        )
    rows = robot.nv if model == "full" else r
    W = np.asarray(robot.regressor(log.q, log.dq, log.ddq))[:, :rows, :]
    b = np.zeros((log.m, rows))
    if model == "full":
        b[:, r:] = log.tau
    for (_, f), k in zip(log.wrenches.items(), links, strict=True):
        for i in range(log.m):
            J = contact_jacobian(robot, log.q[i], k, frame=log.wrench_frame)
            b[i] += (J.T @ f[i])[:rows]
    return W.reshape(-1, W.shape[-1]), b.reshape(-1)


@dataclass
class FloatingResult:
    """A floating-base identification: ``values`` the estimated base values of ``base`` (the
    minimum-norm solution when the model's ``rank`` is below ``base.n``), ``span`` (rank, n_b):
    an orthonormal basis of the combinations of base values the data identified, ``model``
    ("full" or "base"), ``rms`` the fit's residual (generalized-force units, unweighted),
    ``rows`` the equations fitted.

    ``weighted``: weighted least squares (the default of :func:`identify_floating`), each
    coordinate's equations (each of the root's, each actuated joint's) weighted by
    ``1 / coordinate_sigma``: the noise's standard deviation in that coordinate, estimated from
    its residual (generalized-force units, one per row of a sample, in the rows' order; None
    for ordinary least squares); ``weighting`` says how in words (and why not, when the weights
    could not be estimated). ``sigma`` is the standard deviation of the final fit's (weighted)
    residual ``sqrt(RSS_w / (rows - rank))``: dimensionless and about 1 when weighted, in
    generalized-force units for ordinary least squares.
    ``std`` the standard deviation of each value: ``sigma`` through the (weighted)
    least-squares covariance ``sigma^2 V diag(1/s^2) V^T`` of the identified span, NaN for a
    value the data do not determine alone (outside ``span``: only combinations of it are
    identified)."""

    base: BaseParameters
    values: np.ndarray
    rank: int
    span: np.ndarray
    model: str
    rms: float
    std: np.ndarray
    sigma: float
    rows: int
    weighted: bool = False
    coordinate_sigma: np.ndarray | None = None
    weighting: str = "none (ordinary least squares)"

    def residual(self, log: FloatingLog) -> np.ndarray:
        """Predicted minus measured generalized forces of ``log`` in this result's model, shape
        (m * rows,)."""
        predicted, measured = self.forces(log)
        return (predicted - measured).reshape(-1)

    def forces(self, log: FloatingLog) -> tuple[np.ndarray, np.ndarray]:
        """The generalized forces of ``log`` in this result's model, predicted by the estimate
        and measured (``S^T tau + sum_c J_c^T f_c``; the base-link model: the root's rows), each
        of shape (m, rows)."""
        W, b = floating_system(self.base.robot, log, model=self.model)
        shape = (log.m, len(b) // max(log.m, 1))
        return (W[:, _pivots(self.base)] @ self.values).reshape(shape), b.reshape(shape)


def _pivots(base: BaseParameters) -> np.ndarray:
    """The classical columns of the base set: ``W[:, pivots] @ values(p) == W @ p``."""
    e = base.embed(np.arange(1.0, base.n + 1))
    order = np.argsort(e)[-base.n :]
    return order[np.argsort(e[order])]


@single_threaded_blas  # a QR of a few thousand rows: one BLAS thread is faster on a loaded machine
def identify_floating(
    robot: Robot,
    logs,
    *,
    model: str = "full",
    base: BaseParameters | None = None,
    tolerance: float | None = None,
    weighted: bool = True,
) -> FloatingResult:
    """Base parameters of a floating-base robot from one or more :class:`FloatingLog` (see the
    module's docstring for the equations and the CSV format, :func:`read_floating_csv`).

    ``model``: ``"full"`` (joint torques and wrenches; free flight is the case with no wrench)
    or ``"base"`` (the root joint's rows: wrenches and motion only). ``base`` defaults to the
    numerical method's base parameters of ``robot``. ``tolerance`` (relative to the largest
    singular value of the base regressor; default ``max(rows, n_b) * eps``) decides the rank:
    a rank below ``n_b`` is stated in ``rank`` and ``span``, and the full model refuses it.

    ``weighted`` (default): weighted least squares, its weights from the residuals as the
    fixed-base identification's, per coordinate: each of the root joint's (a free-flyer's fx,
    fy, fz, tx, ty, tz in its body's axes; a planar root's fx, fy, tz) and each actuated
    joint's, since each carries the noise of other sensors (contact force/torque sensors through
    the contact Jacobians, joint torque sensors) through other lever arms: one per axis rather
    than one per force and one per moment, because a root moment mixes the force noise through
    the lever arms of the contacts, which differ per axis. A first ordinary fit gives each
    coordinate's noise ``sigma_g = sqrt(rss_g / (m_g - h_g))`` (its residual sum of squares
    over its equations less its leverage ``h_g``, the degrees of freedom the fit takes from
    it); the next fit weights its equations by ``1 / sigma_g``, and its residuals give the
    ``sigma_g`` again, until none changes by more than 1 % (at most 20 fits): one weighted fit
    after an ordinary one is not enough when the noise levels differ much, since the ordinary
    fit's error then inflates the residual of the precise coordinates. The last fit gives the
    values and their standard deviations. A ``sigma_g`` below 1e-9 of the largest (a
    coordinate fitted to round-off) is raised to that floor, which bounds the weights' ratio;
    when the ordinary fit's residual is itself round-off (below 1.5e-8 of the measured forces:
    noise-free data) or no equation is left beyond the parameters, the fit stays ordinary. Each
    is stated in ``weighting``. ``weighted=False``: ordinary least squares, one noise level for
    every equation.

    The stacked system is reduced chunk by chunk (bounded memory on long logs) to one triangle
    per coordinate, ``S_g^T S_g = [W_g y_g]^T [W_g y_g]``, (n_b + 1)^2 each: every fit and each
    coordinate's residual come from these triangles, without a second pass over the logs."""
    _args.instance(robot, "robot", Robot)
    _args.choice(model, "model", _MODELS)
    if isinstance(logs, FloatingLog):
        logs = [logs]
    elif not (
        isinstance(logs, (list, tuple)) and logs and all(isinstance(x, FloatingLog) for x in logs)
    ):
        raise _args.fail("logs", "is not a FloatingLog or a non-empty list of them")
    _args.optional(_args.instance, base, "base", BaseParameters)
    if base is not None and (
        base.robot.nv != robot.nv
        or base.robot.param_names != robot.param_names
        or len(base.embed(np.zeros(base.n))) != 10 * robot.n
    ):
        raise _args.fail(
            "base", "is not a set of the robot's 10 n inertial parameters (another robot?)"
        )
    _args.optional(_args.number, tolerance, "tolerance", positive=True, below=1.0)
    weighted = _args.flag(weighted, "weighted")
    if model == "base" and not any(log.wrenches for log in logs):
        raise IdentificationError(
            "the base-link model needs contact wrenches: in free flight its equations are "
            "homogeneous (W_base p = 0) and give the parameters only up to a scale; use "
            "model='full' with the joint torques"
        )
    if base is None:
        base = base_parameters(robot, method="numerical")
    nb = base.n
    S, rows = _coordinate_triangles(robot, logs, model, base)
    k = len(S)
    U, s, Vt, z = _reduce(S, np.ones(k))
    # the first (ordinary) fit decides the rank: row weights change neither the regressor's row
    # space nor, therefore, the combinations the data identify
    tol = (max(rows, nb) * np.finfo(float).eps if tolerance is None else tolerance) * s[0]
    rank = int(np.sum(s > tol))
    if model == "full" and rank < nb:
        raise IdentificationError(
            f"the logs identify {rank} of the {nb} base parameters (singular values below "
            f"{tol:.3g}); excite more motion or add logs"
        )
    x, rss = _solve(S, U, s, Vt, z, rank)
    weights, coordinate_sigma, weighting = np.ones(k), None, "none (ordinary least squares)"
    exact = float(rss.sum()) <= _ROUND_OFF**2 * float(np.sum(S[:, :, -1] ** 2))
    if weighted and rows <= rank:
        weighting = "none: no equation is left beyond the parameters to measure the noise with"
    elif weighted and exact:
        weighting = (
            "none: the ordinary fit's residual is at round-off (below "
            f"{_ROUND_OFF:.2g} of the measured forces): no noise to weight by"
        )
    elif weighted:
        weights, coordinate_sigma, weighting, (x, s, Vt, rss) = _weights(
            S, s, Vt, rss, rank, rows // k
        )
    rms = float(np.sqrt(rss.sum() / rows))
    wrss = float(weights**2 @ rss)
    sigma = float(np.sqrt(wrss / (rows - rank))) if rows > rank else float("nan")
    V = Vt[:rank].T
    std = sigma * np.sqrt(np.einsum("ij,j,ij->i", V, 1.0 / s[:rank] ** 2, V))
    # a value is determined alone when its unit vector lies in the identified span
    std[np.einsum("ij,ij->i", V, V) < 1.0 - _IN_SPAN] = np.nan
    return FloatingResult(
        base,
        x,
        rank,
        Vt[:rank],
        model,
        rms,
        std,
        sigma,
        rows,
        coordinate_sigma is not None,
        coordinate_sigma,
        weighting,
    )


def _coordinate_triangles(
    robot: Robot, logs: Sequence[FloatingLog], model: str, base: BaseParameters
) -> tuple[np.ndarray, int]:
    """The stacked system of ``logs`` reduced per coordinate (the rows of one coordinate of every
    sample): triangles ``S`` (k, n_b + 1, n_b + 1) with ``S_g^T S_g = [W_g y_g]^T [W_g y_g]``
    (``W_g`` the base regressor's rows), merged chunk by chunk by QR; and the equation count."""
    cols = _pivots(base)
    k = robot.nv if model == "full" else _root_dofs(robot)
    S = np.zeros((k, base.n + 1, base.n + 1))
    rows = 0
    for log in logs:
        _check_log(robot, log)
        for a in range(0, len(log.q), _CHUNK):
            W, y = floating_system(robot, _samples(log, a, a + _CHUNK), model=model)
            A = np.column_stack([W[:, cols], y]).reshape(-1, k, base.n + 1)
            for g in range(k):
                S[g] = _triangle(np.vstack([S[g], A[:, g]]))
            rows += len(y)
    return S, rows


def _reduce(S: np.ndarray, weights: np.ndarray):
    """The coordinates' triangles ``S`` weighted by ``weights`` and stacked, reduced to the SVD
    ``U diag(s) Vt`` of the weighted base regressor and ``z``, the weighted measurements
    projected on its column space (``W_w = Q R``, ``z = Q^T y_w``)."""
    nb = S.shape[1] - 1
    T = _triangle(np.vstack(list(weights[:, None, None] * S)))
    U, s, Vt = np.linalg.svd(T[:nb, :nb])
    return U, s, Vt, T[:nb, nb]


def _solve(S, U, s, Vt, z, rank: int) -> tuple[np.ndarray, np.ndarray]:
    """The minimum-norm least-squares solution in the first ``rank`` singular directions of a
    reduced system (:func:`_reduce`), and each coordinate's unweighted residual sum of
    squares, ``|y_g - W_g x|^2 = |S_g [x; -1]|^2``."""
    x = Vt[:rank].T @ ((U[:, :rank].T @ z) / s[:rank])
    return x, np.sum((S @ np.append(x, -1.0)) ** 2, axis=1)


def _weights(S, s, Vt, rss, rank: int, m_g: int):
    """The weights of the coordinates (``1 / sigma_g``), their ``sigma_g``, the weighting in
    words and the weighted fit ``(x, s, Vt, rss)`` (:func:`_solve`), from the ordinary fit
    (``s``, ``Vt``, each coordinate's ``rss``): each coordinate's noise from its residual and
    the degrees of freedom the fit leaves it (:func:`_coordinate_sigma`), then from the weighted
    fit's residual, again, until no ``sigma_g`` changes by more than :data:`_SETTLED` (at most
    :data:`_MAX_REWEIGHTS` weighted fits); a ``sigma_g`` below :data:`_SIGMA_FLOOR` of the
    largest is raised to it (a coordinate fitted to round-off would otherwise take an unbounded
    weight)."""
    new = _coordinate_sigma(S, np.ones(len(S)), s, Vt, rss, rank, m_g)
    fits = 0
    while True:
        fits += 1
        floor = float(new.max()) * _SIGMA_FLOOR
        low = np.flatnonzero(new < floor)
        sigma = np.maximum(new, floor)
        weights = 1.0 / sigma
        U, s, Vt, z = _reduce(S, weights)
        x, rss = _solve(S, U, s, Vt, z, rank)
        new = _coordinate_sigma(S, weights, s, Vt, rss, rank, m_g)
        change = float(np.max(np.abs(np.maximum(new, floor) / sigma - 1.0)))
        if change <= _SETTLED or fits == _MAX_REWEIGHTS:
            break
    plural = "" if fits == 1 else "s"
    words = "per coordinate, 1 / sigma of its residual: a first ordinary fit, then " + (
        f"the weighted fit's until the sigmas settled within {_SETTLED:.0%} ({fits} weighted "
        f"fit{plural})"
        if change <= _SETTLED
        else f"{fits} weighted fits, the sigmas still changing by {change:.1%} in the last"
    )
    if len(low):
        words += (
            f"; {len(low)} coordinate(s) (rows {', '.join(str(g + 1) for g in low)} of each "
            f"sample) fitted to round-off: their sigma raised to {_SIGMA_FLOOR:g} of the largest"
        )
    return weights, sigma, words, (x, s, Vt, rss)


def _coordinate_sigma(S, weights, s, Vt, rss, rank: int, m_g: int) -> np.ndarray:
    """Each coordinate's residual standard deviation ``sqrt(rss_g / (m_g - h_g))``: ``m_g`` its
    equations, ``h_g`` its leverage in the weighted fit (the trace of its block of the hat
    matrix, ``|w_g W_g V_r diag(1/s_r)|_F^2``, the residual's degrees of freedom it takes; at
    least one is left)."""
    M = Vt[:rank].T / s[:rank]
    h = weights**2 * np.sum((S[:, :, :-1] @ M) ** 2, axis=(1, 2))
    return np.sqrt(rss / np.maximum(m_g - h, 1.0))


_ROUND_OFF = 1.5e-8  # sqrt(eps): a smaller relative residual is round-off, not noise
_SIGMA_FLOOR = 1e-9  # a coordinate's residual sigma is at least this fraction of the largest
_SETTLED = 1e-2  # the weights have settled when no coordinate's sigma changes by more
_MAX_REWEIGHTS = 20  # weighted fits at most
_IN_SPAN = 1e-9  # a unit vector whose projection on the span falls short by more is outside it


_CHUNK = 256  # samples per block of the stacked system (bounded memory on long logs)


def _samples(log: FloatingLog, a: int, b: int) -> FloatingLog:
    """Samples a..b-1 of a log."""
    return FloatingLog(
        np.asarray(log.q)[a:b],
        np.asarray(log.dq)[a:b],
        np.asarray(log.ddq)[a:b],
        None if log.tau is None else np.asarray(log.tau)[a:b],
        {k: np.asarray(w)[a:b] for k, w in log.wrenches.items()},
        log.wrench_frame,
        log.source,
        log.processing,
    )


def read_floating_csv(
    path,
    robot: Robot,
    *,
    wrench_frame: str = "world",
    filter: str = "butter",
    cutoff: float | None = None,
) -> FloatingLog:
    """A floating-base log from CSV (the format of the module's docstring): the contact links are
    the ``<link>.fx``-style column groups of the header; ``tau`` columns are optional (all of
    them or none). Strict: a missing, repeated or unknown column, an incomplete wrench group, a
    row of another length, a cell that is not a number, a quaternion (or planar (cos, sin)
    pair) whose norm is not 1 within 1e-6 raise DataError naming the file, line and column.

    A log without the ``dq`` columns (or the ``ddq`` columns) gets them derived from its ``t``
    and ``q`` columns (or its ``dq``) by ``filter`` and ``cutoff``
    (:func:`~mindyn.identification.floating_motion.configuration_derivatives`: the rules of
    the fixed-base logs, with the body-axis velocities of the free-flyer, spherical and planar
    joints); torques and wrenches are used as logged. ``processing`` of the log says which."""
    path = Path(_args.path(path, "path"))
    _args.instance(robot, "robot", Robot)
    wrench_frame = _args.choice(wrench_frame, "wrench_frame", _FRAMES)
    _args.choice(filter, "filter", ("butter", "savgol", "none"))
    cutoff = _args.optional(_args.number, cutoff, "cutoff", positive=True)
    if not path.is_file():
        raise DataFileNotFoundError(f"{path}: no such file")
    reader = csv.reader(io.StringIO(decode_text(path)))
    try:
        rows = [row for row in reader if any(c.strip() for c in row)]
    except csv.Error as e:  # a field past the csv module's size limit
        raise DataError(f"{path}, line {reader.line_num}: not readable as CSV ({e})") from None
    if not rows:
        raise DataError(f"{path}: empty file (expected a header line)")
    header = [c.strip() for c in rows[0]]
    r = _root_dofs(robot)
    groups = {
        "q": [f"q{i + 1}" for i in range(robot.nq)],
        "dq": [f"dq{i + 1}" for i in range(robot.nv)],
        "ddq": [f"ddq{i + 1}" for i in range(robot.nv)],
        "tau": [f"tau{i + 1}" for i in range(robot.nv - r)],
    }
    index: dict[str, int] = {}
    for j, name in enumerate(header):
        if name in index:
            raise DataError(f"{path}:1: column {name!r} appears twice")
        index[name] = j
    known = {"t", *(c for g in groups.values() for c in g)}
    links: dict[str, list[str]] = {}
    for name in header:
        if name in known:
            continue
        link, dot, axis = name.rpartition(".")
        if not dot or axis not in WRENCH_AXES:
            raise DataError(
                f"{path}:1: unknown column {name!r} (expected t, q1..q{robot.nq}, "
                f"dq1..dq{robot.nv}, ddq1..ddq{robot.nv}, tau1..tau{robot.nv - r} and "
                "<link>.fx/.fy/.fz/.tx/.ty/.tz)"
            )
        _link_as_data_error(robot, link, path)
        links.setdefault(link, [])
    logged = {}
    for g in ("q", "dq", "ddq"):
        missing = [c for c in groups[g] if c not in index]
        logged[g] = not missing
        if missing and (g == "q" or len(missing) < len(groups[g])):
            raise DataError(f"{path}:1: missing column {missing[0]!r}")
    if not (logged["dq"] and logged["ddq"]) and "t" not in index:
        what = "dq and ddq" if not logged["dq"] else "ddq"
        raise DataError(
            f"{path}:1: no {what} columns and no time column 't' to derive them from (a "
            f"floating-base log carries t, or dq1..dq{robot.nv} and ddq1..ddq{robot.nv})"
        )
    has_tau = [c in index for c in groups["tau"]]
    if any(has_tau) and not all(has_tau):
        raise DataError(f"{path}:1: missing column {groups['tau'][has_tau.index(False)]!r}")
    for link in links:
        links[link] = [f"{link}.{a}" for a in WRENCH_AXES]
        missing = [c for c in links[link] if c not in index]
        if missing:
            raise DataError(f"{path}:1: missing column {missing[0]!r} of link {link!r}'s wrench")
    values = np.empty((len(rows) - 1, len(header)))
    for i, row in enumerate(rows[1:]):
        if len(row) != len(header):
            raise DataError(f"{path}:{i + 2}: {len(row)} cells, the header has {len(header)}")
        for j, cell in enumerate(row):
            values[i, j] = parse_cell(cell, f"{path}:{i + 2}: column {header[j]!r}")
    if len(values) == 0:
        raise DataError(f"{path}: no data row")

    def block(names: list[str]) -> np.ndarray:
        return values[:, [index[c] for c in names]]

    q = block(groups["q"])
    _check_norms(robot, q, path)
    dq = block(groups["dq"]) if logged["dq"] else None
    ddq = block(groups["ddq"]) if logged["ddq"] else None
    processing: dict = {"velocity": "logged", "acceleration": "logged"}
    keep = slice(None)
    if dq is None or ddq is None:
        from .floating_motion import configuration_derivatives, edge_samples

        t = values[:, index["t"]]
        check_time_units(
            t,
            str(path),
            "give t in s (it serves only to derive the missing dq or ddq, which a log this "
            "slow cannot give: log them)",
        )
        try:
            if dq is None:
                _, dq, derived, processing = configuration_derivatives(
                    robot, t, q, filter=filter, cutoff=cutoff
                )
                ddq = derived if ddq is None else ddq
            else:
                _, ddq, processing = differentiate(t, dq, filter=filter, cutoff=cutoff)
                processing = {
                    **processing,
                    "velocity": "logged",
                    "acceleration": "differentiated velocities",
                    "edge_samples": edge_samples(processing),
                }
        except DataError as e:
            raise DataError(f"{path}: {e}") from None
        edge = processing["edge_samples"]
        if len(q) <= 2 * edge:
            raise DataError(
                f"{path}: {len(q)} samples, no more than the {edge} at each end whose derivatives "
                f"by {filter} are not the motion's"
            )
        keep = slice(edge, len(q) - edge)
        values, q, dq, ddq = values[keep], q[keep], dq[keep], ddq[keep]
    return FloatingLog(
        q=q,
        dq=dq,
        ddq=ddq,
        tau=block(groups["tau"]) if all(has_tau) else None,
        wrenches={link: block(cols) for link, cols in links.items()},
        wrench_frame=wrench_frame,
        source=str(path),
        processing=processing,
    )


def _check_norms(robot: Robot, q: np.ndarray, path: Path) -> None:
    """Refuses a quaternion or planar (cos, sin) pair of the log whose norm is not 1, naming the
    line and the columns."""
    tolerance = _args.UNIT_NORM_TOLERANCE
    for start, size, what in robot._unit_blocks():
        norm = np.linalg.norm(q[:, start : start + size], axis=1)
        bad = np.flatnonzero(~(np.abs(norm - 1.0) <= tolerance))
        if len(bad):
            raise DataError(
                f"{path}:{bad[0] + 2}: the {what} (columns q{start + 1}..q{start + size}) has "
                f"norm {norm[bad[0]]:.9g}, not 1 (within {tolerance:g})"
            )


def _link_as_data_error(robot: Robot, link: str, path: Path) -> None:
    names = robot.link_names[1:]
    if link not in names:
        raise DataError(
            f"{path}:1: no moving link {link!r} in robot '{robot.name}' for the wrench columns "
            f"{link}.fx..{link}.tz (links: {', '.join(names)})" + robot._fixed_link_hint(link)
        )
