"""Least-squares estimation of the base parameters from a regression system of
:mod:`mindyn.identification.models`.

Estimation is ordinary least squares, or weighted least squares with per-joint weights
``1 / sigma_j`` from the residuals of a first OLS pass (dynamic model). Statistics as in the
ZCR07S study:
``sigma^2 = |y - W p|^2 / (r - c)``, ``cov = sigma^2 (W^T W)^-1``,
``RSD = 100 sqrt(cov_bb) / |p_b|``; parameters whose RSD exceeds a threshold are removed one at a
time (largest first) and the rest re-estimated. On low-passed logs the covariance is
multiplied by :func:`correlation_factor` (the filtered noise is correlated between the samples
fitted, and within and between the windows of the integral and energy models)."""

from __future__ import annotations

import math
import re
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import cast

import numpy as np
import scipy.linalg as sla
from scipy import integrate

from .. import _args, _core
from .._core import OFFSET_PREFIX as OFF
from .._threads import evaluated_ahead, single_threaded_blas
from ..base import BaseParameters, base_parameters
from ..robot import Robot, as_robot, drive_train_record
from .data import DataError
from .document import identified_robot_record, model_record
from .errors import IdentificationError, RankDeficientError
from .joint_data import JointData
from .models import (
    MODELS,
    energy_row_noise,
    energy_system,
    integral_chunks,
    logged_torques,
    moving_equations,
    moving_windows,
    require_torque,
    torque_noise,
    windows,
)
from .options import DEFAULT_MIN_VELOCITY, DEFAULT_RSD_THRESHOLD, INTEGRATIONS

#: Least equations per base parameter (and degrees of freedom of the noise estimate) that
#: :func:`identify` accepts. Dynamic model: 10 equations per parameter; fewer, and a log too
#: short to move every joint through its range gives estimates (after pruning) far from the
#: truth with small RSDs. Energy model: 4 windows per parameter (one window integrates the
#: power of all joints over ``window`` samples). Integral model: 4 equations per parameter (one
#: per joint and window, each integrating ``window`` samples). All: at least 30 degrees of
#: freedom, so that the noise variance behind the RSDs is known within about 25 %.
MIN_EQUATIONS_PER_PARAMETER = {"dynamic": 10, "energy": 4, "integral": 4}
MIN_NOISE_DOF = 30

#: Samples whose regressor is evaluated at once by the dynamic model (memory: samples x joints x
#: base parameters x 8 bytes, 15 MB for 6 joints and 40 parameters).
CHUNK_SAMPLES = 8192


@dataclass
class IdentificationResult:
    """Estimated base parameters with their statistics.

    Attributes
    ----------
    model : str
        ``dynamic``, ``energy`` or ``integral``.
    names, values, std, rsd : tuple of str, ndarray (k,), ndarray (k,), ndarray (k,)
        The parameters kept after pruning, their estimates, standard deviations and relative
        standard deviations in percent.
    removed : tuple of (name, rsd) tuples
        Parameters removed for an RSD above the threshold, in order of removal (their RSD at
        that moment).
    full : ndarray, shape (nb,)
        All base parameters in the order of ``base.names``, removed ones set to zero: the vector
        to use with ``base.regressor`` (see :meth:`predict`).
    sigma : float
        Residual standard deviation of the (weighted) final fit.
    joint_sigma : ndarray (n,), optional
        Dynamic and integral models: per-joint residual standard deviations of the first OLS
        pass, the weights' inverse (WLS).
    cond : float
        Condition number of the stacked regressor (unweighted, equations left out by
        ``min_velocity`` excluded) with its columns scaled to unit norm.
    initial : dict
        Estimates, std and RSD of all base parameters before pruning.

    The arrays (``values``, ``std``, ``rsd``, ``full``, ``joint_sigma`` and those of
    ``initial``) are read-only copies: assigning to an entry raises ``ValueError``; ``names``
    and ``removed`` are tuples (``to_dict()`` writes them as lists).
    """

    model: str
    base: BaseParameters
    names: tuple[str, ...]
    values: np.ndarray
    std: np.ndarray
    rsd: np.ndarray
    removed: tuple[tuple[str, float], ...]
    full: np.ndarray
    sigma: float
    rows: int
    weighted: bool
    joint_sigma: np.ndarray | None = None
    cond: float = float("nan")
    rsd_threshold: float = DEFAULT_RSD_THRESHOLD
    initial: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)
    seconds: float = 0.0
    #: The final (weighted) least-squares problem reduced to its triangle, for estimates under
    #: constraints on the same residual (:mod:`~mindyn.identification.consistent`).
    reduced: _Reduced | None = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        # the arrays read-only copies (as a Robot's): an entry assigned raises, instead of
        # making values disagree with full, which predict() uses
        for name in ("values", "std", "rsd", "full", "joint_sigma"):
            if getattr(self, name) is not None:
                setattr(self, name, _args.readonly(getattr(self, name)))
        self.initial = {
            k: _args.readonly(v) if isinstance(v, np.ndarray) else v
            for k, v in self.initial.items()
        }
        # and the kept and removed parameters tuples: a list edited would change them too
        self.names = tuple(self.names)
        self.removed = tuple((n, r) for n, r in self.removed)

    def predict(self, data: JointData) -> np.ndarray:
        """Joint torques ``W_b(q, dq, ddq) @ full`` on ``data``, shape (m, n)
        (:func:`predicted_torques`)."""
        _args.instance(data, "data", JointData)
        return predicted_torques(self.base, self.full, data)

    def prediction_std(self, data: JointData) -> np.ndarray:
        """Standard deviation of each torque the estimate predicts on ``data``, shape (m, n):
        ``sqrt(diag(Y Sigma Y^T))`` per sample, ``Y`` the base regressor rows of the sample
        (as :meth:`predict` evaluates them) and ``Sigma`` the covariance of all base
        parameters before pruning (the ``initial`` estimate, its variance multiplied by the
        factor for correlated equations, :func:`noise_variance_factor`). Pruning sets the
        parameters the data determine least to zero, and the covariance of the kept ones alone
        would count the torques of those zeros as known exactly; the full covariance keeps
        their uncertainty. On a simulated energy fit that left torques undetermined, the kept
        parameters' covariance gave a fifth of the scatter of the pruned estimate's torques
        over noise realisations, the full one half of it or more.

        For a model that fits the torques themselves (dynamic), the mean of the squares over
        the fit's equations is ``p / N_eff`` times the residual variance (``p`` parameters,
        ``N_eff`` independent equations); a model fitted on other equations (energy: the power
        ``dq . tau``; integral: integrated torques) can leave it far larger
        (:func:`~mindyn.identification.validation.prediction_check`)."""
        if self.reduced is None:
            raise IdentificationError("prediction_std: the result carries no least-squares system")
        nb = self.base.n
        root = self.reduced.covariance_root(list(range(nb)), inflation=noise_variance_factor(self))
        out = np.empty((data.m, data.n))
        for a in range(0, data.m, CHUNK_SAMPLES):
            b = min(data.m, a + CHUNK_SAMPLES)
            out[a:b] = np.linalg.norm(regressor_rows(self.base, data, a, b) @ root, axis=2)
        return out

    def initial_covariance(self) -> list | None:
        """The covariance of all base parameters before pruning (the ``initial`` estimate), its
        variance multiplied by the factor for correlated equations
        (:func:`noise_variance_factor`), as :meth:`prediction_std` takes it: a list of
        ``base.n`` rows, or None without a least-squares system. The identification JSON keeps
        it (``initial.covariance``) for what carries the estimate's uncertainty on
        (:func:`~mindyn.identification.consistent.identify_payload`)."""
        if self.reduced is None:
            return None
        nb = self.base.n
        root = self.reduced.covariance_root(list(range(nb)), inflation=noise_variance_factor(self))
        C = root @ root.T
        if not np.all(np.isfinite(C)):
            return None
        return [[float(v) for v in row] for row in 0.5 * (C + C.T)]

    def to_dict(self) -> dict:
        return {
            "model": self.model,
            **identified_robot_record(self.base.robot),  # robot, joints, description
            "rotor": self.base.rotor,
            "friction": self.base.friction,
            "offset": self.base.offset,
            # where Ia/Fv/Fc act: "motor" (slot k is motor k's, through the transmission) or
            # "joint"
            "drive_side": self.base.robot.drive_side,
            "names": list(self.names),
            "values": [float(v) for v in self.values],
            "std": [float(v) for v in self.std],
            "rsd": [_json_float(v) for v in self.rsd],
            "removed": [{"name": n, "rsd": _json_float(r)} for n, r in self.removed],
            "rsd_threshold": self.rsd_threshold,
            "base_names": list(self.base.names),
            "base_values": [float(v) for v in self.full],
            # the regrouping and regressor columns of the base set: what the readers compare
            "model_check": model_record(self.base),
            "sigma": self.sigma,
            "rows": self.rows,
            "weighted": self.weighted,
            "joint_sigma": None if self.joint_sigma is None else self.joint_sigma.tolist(),
            "cond": _json_float(self.cond),
            "condition_number_scaled": _json_float(self.cond),
            "initial": {
                "names": list(self.base.names),
                "values": [float(v) for v in self.initial.get("values", [])],
                "std": [_json_float(v) for v in self.initial.get("std", [])],
                "rsd": [_json_float(v) for v in self.initial.get("rsd", [])],
                "covariance": self.initial_covariance(),
            },
            "settings": self.settings,
            "seconds": self.seconds,
            **drive_train_record(self.base.robot),
        }


def _json_float(x):
    x = float(x)
    return x if math.isfinite(x) else None


# ---------------------------------------------------------------------------------------------
# Least squares with statistics
# ---------------------------------------------------------------------------------------------
class _Reduced:
    """A least-squares problem ``min |y - W p|`` reduced once by QR of the column-scaled
    ``[W y]`` to a ``c x c`` triangle, so that any subset of columns is solved (with statistics)
    from the small triangle: ``W`` (r, c), ``y`` (r,)."""

    def __init__(self, W: np.ndarray, y: np.ndarray):
        self._set(_triangle(np.column_stack([W, y])), W.shape[0])

    @classmethod
    def from_triangle(cls, S: np.ndarray, rows: int) -> _Reduced:
        """From the triangular factor ``S`` ((c+1) x (c+1)) of the unscaled ``[W y]`` of
        ``rows`` rows: ``S^T S = [W y]^T [W y]``."""
        self = cls.__new__(cls)
        self._set(S, rows)
        return self

    def _set(self, S: np.ndarray, rows: int) -> None:
        # Column scaling commutes with QR: the factor of [W / norms, y] is S with its first c
        # columns divided by the norms, which are the norms of the columns of S.
        self.r, c = rows, S.shape[1] - 1
        self.c = c
        norms = np.linalg.norm(S[:, :c], axis=0)
        self.zero = norms <= 1e-300
        self.norms = np.where(self.zero, 1.0, norms)
        R = S / np.append(self.norms, 1.0)
        self.R = R[:c, :c]
        self.z = R[:c, c]
        self.rho = float(R[c, c] ** 2)

    def rank(self, tol: float):
        """``(rank, pivot order, condition number)`` of the column-scaled regressor (columns
        of unit norm); the condition number is the ratio of the extreme singular values, those
        of the triangle ``R``."""
        _, Rp, piv = sla.qr(self.R, pivoting=True)
        d = np.abs(np.diag(Rp))
        rank = int(np.sum(d > tol * d[0])) if d.size and d[0] > 0 else 0
        sv = np.linalg.svd(self.R, compute_uv=False)
        cond = float(sv[0] / sv[-1]) if sv.size and sv[-1] > 0 else float("inf")
        return rank, piv, cond

    def solve(self, keep: list[int], *, inflation: float = 1.0):
        """Estimate of the columns ``keep``: ``(p, std, sigma2)``, the variances multiplied by
        ``inflation`` (the factor for correlated equations, :func:`correlation_factor`)."""
        ps, root, sigma2 = self._solved(keep, inflation)
        return ps, np.sqrt(np.einsum("ij,ij->i", root, root)), sigma2

    def covariance_root(self, keep: list[int], *, inflation: float = 1.0) -> np.ndarray:
        """``G`` (k, k) with ``G G^T`` the covariance of the estimate of the columns ``keep``
        (:meth:`solve`'s standard deviations are the norms of its rows)."""
        return self._solved(keep, inflation)[1]

    def _solved(self, keep: list[int], inflation: float):
        k = len(keep)
        T = _r_factor(np.column_stack([self.R[:, keep], self.z]))
        rss = self.rho + (float(T[k, k] ** 2) if T.shape[0] > k else 0.0)
        Rk = T[:k, :k]
        ps = sla.solve_triangular(Rk, T[:k, k])
        scale = self.norms[keep]
        sigma2 = rss / (self.r - k) if self.r > k else float("nan")
        Rinv = sla.solve_triangular(Rk, np.eye(k))
        root = Rinv * (math.sqrt(inflation * sigma2) if sigma2 >= 0 else math.nan)
        return ps / scale, root / scale[:, None], sigma2


def _r_factor(A: np.ndarray) -> np.ndarray:
    """``numpy.linalg.qr(A, mode="r")``: the array R (typed by numpy as its tuple result)."""
    return cast(np.ndarray, np.linalg.qr(A, mode="r"))


def _triangle(A: np.ndarray) -> np.ndarray:
    """The upper triangular R of ``A = Q R``, padded with zero rows to square ``(k, k)``."""
    k = A.shape[1]
    R = _r_factor(A)
    if R.shape[0] < k:
        R = np.vstack([R, np.zeros((k - R.shape[0], k))])
    return R


def dynamic_triangles(
    base: BaseParameters, data: JointData, *, min_velocity: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """The dynamic model of :func:`dynamic_system` reduced per joint without forming it: for
    each joint ``j``, the triangle ``S_j`` ((nb+1) x (nb+1)) with ``S_j^T S_j = [W_j y_j]^T
    [W_j y_j]`` over that joint's equations, and the equation count of each joint. The
    regressor is evaluated :data:`CHUNK_SAMPLES` samples at a time and each chunk merged by a
    QR factorisation (not by normal equations, which would square the condition number), so
    the memory does not grow with the length of the log. Returns ``(S, rows)``, shapes
    (n, nb+1, nb+1) and (n,)."""
    require_torque(data)
    n, nb = data.n, base.n
    S = np.zeros((n, nb + 1, nb + 1))
    rows = np.zeros(n, dtype=int)
    keep = moving_equations(base, data.dq, min_velocity)
    assert data.tau is not None  # require_torque
    for a in range(0, data.m, CHUNK_SAMPLES):
        b = min(data.m, a + CHUNK_SAMPLES)
        W = regressor_rows(base, data, a, b)  # (k, n, nb)
        for j in range(n):
            A = np.column_stack([W[:, j, :], data.tau[a:b, j]])
            if keep is not None:
                A = A[keep[a:b, j]]
            rows[j] += A.shape[0]
            S[j] = _triangle(np.vstack([S[j], A]))
    return S, rows


def predicted_torques(base: BaseParameters, full: np.ndarray, data: JointData) -> np.ndarray:
    """Joint torques ``W_b(q, dq, ddq) @ full`` of the base-parameter values ``full`` on
    ``data``, shape (m, n). On preprocessed data whose torques were low-pass filtered: from the
    regressor columns filtered alike (parallel filtering, computed once), :data:`CHUNK_SAMPLES`
    samples at a time. Otherwise by Newton-Euler with the classical vector that carries
    ``full`` (:meth:`~mindyn.BaseParameters.embed`; the torque offsets added joint by joint):
    the same torques to round-off, without forming the regressor (a fraction of its cost on a
    long log). A base set of its own kind (the Dahl model's, whose friction column is a state
    along the positions) is always evaluated through its regressor."""
    own_regressor = type(base) is not BaseParameters
    if data.regressor_filter is not None or data.m == 0 or own_regressor:
        out = np.empty((data.m, data.n))
        for a in range(0, data.m, CHUNK_SAMPLES):
            b = min(data.m, a + CHUNK_SAMPLES)
            out[a:b] = regressor_rows(base, data, a, b) @ full
        return out
    robot = base.robot
    pi = base.embed(full)
    P = len(robot.parameter_names(rotor=base.rotor, friction=base.friction))
    classical = pi[:P]

    def torques(a, b):
        return robot.inverse_dynamics(data.q[a:b], data.dq[a:b], data.ddq[a:b], classical)

    out = np.empty((data.m, data.n))
    step = 8 * CHUNK_SAMPLES
    bounds = [(a, min(data.m, a + step)) for a in range(0, data.m, step)]
    for (a, b), tau in zip(bounds, evaluated_ahead(torques, bounds)):  # on threads
        out[a:b] = tau.reshape(b - a, data.n)
    return out + pi[P:] if pi.size > P else out


def regressor_rows(base: BaseParameters, data: JointData, a: int, b: int) -> np.ndarray:
    """The base regressor of samples ``a:b`` of ``data``, (b - a, n, nb): evaluated on the
    samples, or, when ``data`` carries a ``regressor_filter`` (preprocessed data), the
    regressor columns filtered like its torques."""
    if data.regressor_filter is not None:
        return data.regressor_filter.regressor(base)[a:b]
    return base.regressor(data.q[a:b], data.dq[a:b], data.ddq[a:b])


def _check_rank(
    ls: _Reduced, names: list[str], what: str, tol: float, logs=(), speed=0.0, robot=None
):
    """Raises RankDeficientError when the columns of the regressor are dependent, naming the
    parameters in the dependence and, from the motion of ``logs`` (joint speeds at or above
    ``speed``), the option that would lift it (:func:`_rank_remedies`); returns the condition
    number of the column-scaled regressor."""
    rank, piv, cond = ls.rank(tol)
    if rank < ls.c:
        zero = [names[j] for j in np.flatnonzero(ls.zero)]
        dropped = [names[j] for j in piv[rank:]]
        # the parameters in the dependence: those with weight in the null space of the
        # column-scaled regressor (its last right singular vectors)
        _, _, vt = np.linalg.svd(ls.R)
        null = np.abs(vt[rank:]).max(axis=0)
        concerned = [names[j] for j in np.flatnonzero(null > 0.05) if names[j] not in zero]
        parts = []
        if zero:
            parts.append(f"no effect on this data: {', '.join(zero)}")
        if concerned:
            parts.append(f"dependent on each other in this data: {', '.join(concerned)}")
        remedies = _rank_remedies(zero + concerned, logs, speed, robot)
        raise RankDeficientError(
            f"{what}: the stacked regressor has rank {rank} for {ls.c} base parameters; "
            f"this trajectory cannot identify {len(dropped)} of them ({'; '.join(parts)}). "
            + (
                " ".join(remedies)
                if remedies
                else "Use a richer excitation trajectory or fewer parameters."
            ),
            dropped,
            rank,
        )
    return cond


def _rank_remedies(concerned: list[str], logs, speed: float, robot=None) -> list[str]:
    """What would lift a rank deficiency in ``concerned`` (base-parameter names), from the motion
    of ``logs``: a joint that never moves (no speed at or above ``speed``) leaves its friction
    (``friction=True``) and rotor inertia (``rotor=True``) without effect; a joint that never
    reverses makes its Coulomb friction a constant, inseparable from its torque offset
    (``offset=True``). Options are named as the library's keywords (the CLI names its flags).
    With rotor inertia and friction on the motors (``robot``'s drive side), ``Ia``, ``Fv`` and
    ``Fc`` of slot k follow motor k's motion (its speed in joint units, divided by its largest
    ratio) and are named after the motor; ``Off`` stays the joint's."""
    logs = list(logs)
    if not logs:
        return []
    dq = np.vstack([d.dq for d in logs])
    kinds: dict[int, set] = {}
    for nm in concerned:
        hit = re.fullmatch(rf"(Fv|Fc|Fa|Fs|{OFF}|Ia)(\d+)", nm)
        if hit:
            kinds.setdefault(int(hit.group(2)), set()).add(hit.group(1))
    if robot is None or robot.drive_side != "motor":
        return _remedies(kinds, dq, speed, "Joint(s) " + "{}")
    T = robot.drive_matrix
    vm = robot.slot_velocities(dq) / np.max(np.abs(T), axis=1)
    drive = {k: v - {OFF} for k, v in kinds.items() if v - {OFF}}
    offsets = {k: {OFF} for k, v in kinds.items() if OFF in v}
    motors = robot.transmission.motors
    names = [f"'{m}'" for m in motors]
    # the joints' offsets span every constant joint torque, so a motor's direction-dependent
    # Coulomb term (a constant T^T column whenever the motor moves) is inseparable from them
    return (
        _remedies(drive, vm, speed, "Motor(s) {}", names, offsets=bool(offsets))
        + _left_out(drive, vm, T, speed, names)
        + _remedies(offsets, dq, speed, "Joint(s) {}")
    )


def _left_out(kinds: dict, vm: np.ndarray, T: np.ndarray, speed: float, names) -> list[str]:
    """The remedy for motors of ``kinds`` (1-based) that move but whose joints have no equation
    left: a joint's equation is left out where a motor acting on it is slower than ``speed``
    (:func:`~mindyn.identification.models.moving_equations`; ``vm`` the motors' speeds in joint
    units), so a motor turning with a joint whose other motor never moves has no effect."""
    if not speed > 0 or not vm.size:
        return []
    slow = np.abs(vm) < speed
    empty = np.all((slow.astype(float) @ (T != 0).astype(float)) > 0, axis=0)  # per joint
    moving = ~np.all(slow, axis=0)
    hidden = [k for k in sorted(kinds) if moving[k - 1] and np.all(empty[T[k - 1] != 0])]
    if not hidden:
        return []
    culprits = [k for k in range(T.shape[0]) if not moving[k] and np.any(T[k, empty] != 0)]
    return [
        f"Motor(s) {', '.join(names[k - 1] for k in hidden)} move, but every equation of the "
        "joints they act on is left out: "
        + (
            f"motor(s) {', '.join(names[k] for k in culprits)} acting on those joints never reach"
            if culprits
            else "at every sample a motor acting on those joints is below"
        )
        + f" min_velocity ({speed:g} rad/s | m/s), below which an equation is left out; "
        "lower min_velocity, or move them."
    ]


def _remedies(
    kinds: dict, v: np.ndarray, speed: float, label: str, names=None, *, offsets: bool = False
) -> list[str]:
    """The remedies of :func:`_rank_remedies` for the slots ``kinds`` (1-based index -> kinds of
    parameter) moving at ``v`` (m, n), ``label`` formatted with their names (their indices
    unless ``names``); ``offsets``: torque offsets of the joints are among the dependent
    parameters, listed apart (motor slots)."""
    floor = max(speed, 1e-12 * float(np.max(np.abs(v), initial=0.0)))
    up = np.any(v >= floor, axis=0) if v.size else np.zeros(v.shape[1], bool)
    down = np.any(v <= -floor, axis=0) if v.size else np.zeros(v.shape[1], bool)
    coulomb = {"Fc", "Fa", "Fs"}  # the friction terms that are constant while a joint moves one way
    still = [j for j in sorted(kinds) if not (up[j - 1] or down[j - 1])]
    one_way = [
        j for j in sorted(kinds) if (up[j - 1] != down[j - 1]) and ({OFF} | coulomb) & kinds[j]
    ]
    # the direction-dependent Coulomb term is constant whenever the joint moves, either way
    level = [
        j
        for j in sorted(kinds)
        if j not in still + one_way and "Fa" in kinds[j] and (offsets or OFF in kinds[j])
    ]

    def named(js):
        return label.format(", ".join(str(j) if names is None else names[j - 1] for j in js))

    out = []
    speed_txt = f" (speed {speed:g} rad/s | m/s or more)" if speed > 0 else ""
    if still:
        opts = sorted(
            {"friction=True" for j in still if ({"Fv"} | coulomb) & kinds[j]}
            | {"rotor=True" for j in still if "Ia" in kinds[j]}
            | {"offset=True" for j in still if OFF in kinds[j] and not coulomb & kinds[j]}
        )
        out.append(
            f"{named(still)} never move{speed_txt} in this data: "
            + (f"leave out {' and '.join(opts)}, or " if opts else "")
            + "move them."
        )
    if one_way:
        out.append(
            f"{named(one_way)} never reverse direction in this data: "
            "their Coulomb friction is a constant torque there, inseparable from a torque offset: "
            "leave out offset=True (or friction=True), or reverse them."
        )
    if level:
        out.append(
            f"{named(level)}: the direction-dependent Coulomb term Fa is "
            f"a constant torque whenever the {'motor' if offsets else 'joint'} moves, "
            "inseparable from a torque offset: leave out offset=True, or use another "
            "friction_model=."
        )
    return out


#: A revolute position is refused when the rounding of a double at its magnitude loses more
#: than half of the digits of an angle within one turn (the regressor sees it only through
#: sin and cos; its velocities and accelerations are differences of it): |q| > pi 2^26.
ANGLE_DIGITS_KEPT = 0.5


def check_magnitudes(robot: Robot, logs: list) -> None:
    """Raises DataError naming the log, column and magnitude of a value beyond what the double
    arithmetic of the least-squares problem can carry, with the rule: each equation's terms are
    summed as squares over all ``E`` equations of the logs (``E`` = samples x joints), so a
    torque must stay below ``sqrt(DBL_MAX / E)``; velocities (their products, the centripetal
    and Coriolis terms), accelerations and prismatic positions (products with each other in
    the regressor) below ``(DBL_MAX / E)^(1/4)``; a revolute position within ``pi 2^26`` (see
    :data:`ANGLE_DIGITS_KEPT`: beyond, its rounding, ``|q| 2^-52``, leaves fewer than half of
    the 16 digits of an angle)."""
    big = np.finfo(float).max
    equations = max(sum(d.m for d in logs) * robot.n, 1)
    linear, product = math.sqrt(big / equations), (big / equations) ** 0.25
    digits = -math.log10(np.finfo(float).eps)  # of an angle within one turn, about 15.7
    for d in logs:
        src = d.source or "data"
        for kind, a, limit, units in (
            ("tau", d.tau, linear, ("N m", "N")),
            ("ddq", d.ddq, product, ("rad/s^2", "m/s^2")),
            ("dq", d.dq, product, ("rad/s", "m/s")),
        ):
            if a is None or not a.size:
                continue
            peak = np.abs(a).max(axis=0)
            j = int(np.argmax(peak))
            if peak[j] > limit:
                unit = units[robot.joint_types[j] != "revolute"]
                raise DataError(
                    f"{src}: {kind}{j + 1} reaches {peak[j]:.3g} {unit}, beyond what the "
                    f"double arithmetic of the fit can carry: its terms are summed as "
                    f"{'squares' if kind == 'tau' else 'squares of products'} over the "
                    f"{equations} equations, so the values must stay below {limit:.3g} "
                    f"((1.8e308 / {equations})^{'1/2' if kind == 'tau' else '1/4'}); "
                    "are the values in the right unit?"
                )
        peak = np.abs(d.q).max(axis=0)
        for j in range(robot.n):
            if robot.joint_types[j] != "revolute":
                if peak[j] > product:
                    raise DataError(
                        f"{src}: q{j + 1} (prismatic) reaches {peak[j]:.3g} m, beyond what the "
                        f"double arithmetic of the fit can carry: its products with the "
                        f"accelerations are summed as squares over the {equations} equations, "
                        f"so it must stay below {product:.3g} ((1.8e308 / {equations})^1/4)"
                    )
                continue
            lost = math.log10(peak[j] / math.pi) if peak[j] > math.pi else 0.0
            if lost > (1.0 - ANGLE_DIGITS_KEPT) * digits:
                raise DataError(
                    f"{src}: q{j + 1} reaches {peak[j]:.3g} rad: the rounding unit of a double "
                    f"of that magnitude is {float(np.spacing(peak[j])):.2g} rad, which loses "
                    f"{lost:.1f} of the {digits:.1f} digits of an angle within one turn (the "
                    "regressor takes its sine and cosine; velocities and accelerations are its "
                    "differences), more than half; reduce the positions to within a turn "
                    "(subtract a multiple of 2 pi)"
                )


def _enough(
    model: str, rows: int, nb: int, logs: list[JointData], settings: dict, window: int = 1
) -> None:
    """Refuses too few equations for ``nb`` parameters (:data:`MIN_EQUATIONS_PER_PARAMETER`,
    :data:`MIN_NOISE_DOF`) over all ``logs``; records the rule in ``settings``."""
    k = MIN_EQUATIONS_PER_PARAMETER[model]
    need = max(k * nb, nb + MIN_NOISE_DOF)
    settings["min_equations"] = need
    if rows >= need:
        return
    src = _sources(logs)
    m, n = sum(d.m for d in logs), logs[0].n
    if model == "dynamic":
        got = f"{m} samples x {n} joints = {rows} equations"
        if settings.get("equations_left_out"):
            got += f" ({settings['equations_left_out']} left out as slower than min_velocity)"
        more = _as_logged(logs, math.ceil(need * m / max(rows, 1)))
    elif model == "integral":
        got = f"{m} samples give {rows} integral equations ({n} per window of {window} intervals)"
        if settings.get("equations_left_out"):
            got += f" ({settings['equations_left_out']} left out as slower than min_velocity)"
        more = _as_logged(logs, math.ceil(need / n) * window + 1) + ", or a shorter window"
    else:
        got = f"{m} samples give {rows} energy windows of {window} intervals"
        more = _as_logged(logs, need * window + 1) + ", or a shorter window"
    raise IdentificationError(
        f"{src}: {got} for {nb} base parameters; at least {need} are needed ({k} per "
        f"parameter and {MIN_NOISE_DOF} degrees of freedom for the noise estimate): fewer give "
        f"estimates whose RSD does not show their error. Use a longer log ({more})"
    )


def _as_logged(logs: list[JointData], needed: int) -> str:
    """``needed`` samples after the data path as the rows a log must have: the data path drops
    the filter edges of each log (or segment) and keeps every ``decimation``-th sample, so the
    samples it leaves are fewer than the log's rows."""
    edges, step, cutoffs = 0, 1, set()
    for d in logs:
        pre = d.processing.get("preprocess") or {}
        edges += int(pre.get("edge_samples_dropped", 0))
        edges += 2 * int((d.processing.get("derivative_edges") or {}).get("samples", 0))
        step = max(step, int(pre.get("decimation", 1)))
        if "filter" in pre:
            cutoffs.add(float(pre["filter"]["cutoff_Hz"]))
    if not edges and step == 1:
        return f"at least {needed} samples"
    rows = edges + (needed - 1) * step + 1
    at = f" of its {cutoffs.pop():.4g} Hz cut-off" if len(cutoffs) == 1 else ""
    kept = f"{edges} at the filter edges{at}" + (f", then every {step}th kept" if step > 1 else "")
    return f"at least {rows} samples as logged, {needed} after the data path ({kept})"


def _sources(logs: list[JointData]) -> str:
    """The logs by name, the segments of a log cut at its breaks counted, not listed."""
    out: list[list] = []
    for d in logs:
        seg = d.processing.get("segment")
        name = (d.source or "data").rsplit(" [", 1)[0] if seg else d.source or "data"
        if seg and out and out[-1][0] == name and out[-1][1]:
            out[-1][1] += 1
        else:
            out.append([name, 1 if seg else 0])
    return " + ".join(n if k == 0 else f"{n} ({k} segments)" for n, k in out)


def _logs(data, name: str = "data", robot: Robot | None = None) -> list[JointData]:
    """One log or a sequence of logs as a non-empty list of :class:`JointData`; given the
    ``robot`` they are for, each whose units are not checked yet (a log built in Python) is
    checked, named ``name[k]`` (``name`` for one log given alone): the one place the logs of
    the library's identification entry points are checked
    (:func:`~mindyn.identification.data.check_units`)."""
    if isinstance(data, JointData):
        logs = [data]
    else:
        logs = list(data) if isinstance(data, (list, tuple)) else []
        if not logs or not all(isinstance(d, JointData) for d in logs):
            raise _args.fail(name, "must be a JointData or a non-empty list of JointData")
    if robot is not None:
        from .data import check_units

        for k, d in enumerate(logs):
            if not d.units_checked and d.n == robot.n:  # other joint counts: refused by each
                check_units(d, robot, name if isinstance(data, JointData) else f"{name}[{k}]")
    return logs


def distinct_logs(logs: list[JointData], name: str = "data") -> list[JointData]:
    """``logs`` when no log is given twice (the same object): a log fitted twice counts its
    samples twice (other estimates, smaller standard deviations); ArgumentError naming both
    places otherwise. (Logs read from files: :func:`~mindyn.identification.data.
    check_distinct_logs` compares the files.)"""
    seen: dict[int, int] = {}
    for k, d in enumerate(logs):
        first = seen.setdefault(id(d), k)
        if first != k:
            said = f" ({d.source})" if d.source else ""
            raise _args.fail(
                name,
                f"gives log {first + 1}{said} again as log {k + 1}: its samples would be "
                "fitted twice",
            )
    return logs


def noise_bandwidth(cutoff: float, order: int) -> float:
    """Equivalent noise bandwidth [Hz] of the data path's zero-phase Butterworth low-pass of
    ``order`` at ``cutoff``: ``int_0^inf |H(f)|^4 df`` with ``|H|^2 = 1 / (1 + (f/fc)^(2n))``
    (the filter applied forwards and backwards), ``fc (1 - 1/(2n)) (pi/(2n)) / sin(pi/(2n))``
    (0.898 fc at order 4)."""
    a = math.pi / (2 * order)
    return cutoff * (1.0 - 1.0 / (2 * order)) * a / math.sin(a)


def row_weights(res: IdentificationResult) -> np.ndarray:
    """Each joint's equations' weight in the fit of ``res``, shape (n,): ``1 / sigma_j`` of the
    weighted fit (:func:`joint_weights`), ones for ordinary least squares."""
    js = res.joint_sigma
    if res.weighted and js is not None:
        return joint_weights(js)
    return np.ones(res.base.robot.n)


def joint_weights(joint_sigma: np.ndarray) -> np.ndarray:
    """``1 / sigma_j`` per joint, a joint without residual floored at 1e-9 of the largest."""
    return 1.0 / np.maximum(joint_sigma, max(float(joint_sigma.max()) * 1e-9, 1e-300))


def noise_variance_factor(res: IdentificationResult) -> float:
    """How many times the residual variance of ``res`` (rows counted as independent) its
    noise's variance per independent equation is: ``settings.std_correlation``'s
    ``variance_factor`` (:func:`correlation_factor`), 1 where no correction applies."""
    corr = res.settings.get("std_correlation") or {}
    return float(corr.get("variance_factor", 1.0))


@single_threaded_blas
def residual_correlation(res: IdentificationResult, data) -> tuple[float | None, str]:
    """The factor on the variance of the estimates that the correlation of the fit's own
    residuals calls for, measured (not derived from the data path as :func:`correlation_factor`
    is), and the rule in words: model error (friction or drive effects the model leaves out)
    leaves residuals correlated over many samples, which the residual variance, counting the
    samples as independent, does not see.

    Dynamic and integral models, with ``data`` the logs ``res`` was fitted on: the Newey-West
    estimate of the covariance of the scores ``g_t = sum_j a_tj r_tj`` (per sample ``t`` of the
    dynamic model, per window of the integral model; ``a_tj`` the weighted regressor row of
    joint ``j``, ``r_tj`` its weighted residual with all base parameters), Bartlett weights up
    to the lag :func:`newey_west_lag` chooses per log from its scores' own correlation (Newey &
    West, *Automatic lag selection in covariance matrix estimation*, Review of Economic Studies
    61, 1994; the parts of a log joined by
    :func:`~mindyn.identification.preprocess.concatenate` each a log), against the covariance
    that independent residuals would give, ``s^2 A^T A``: the mean of its eigenvalues relative
    to that, ``tr(S (s^2 A^T A)^-1) / nb``, the mean inflation of a parameter direction's
    variance. About 1 for white residuals, the data path's factor for filtered noise, more for
    model error. Energy model: None (its windows are weighted by noise estimates of their own;
    not measured), as without residuals."""
    if res.model == "energy" or res.reduced is None:
        return None, "not measured (the dynamic and integral models only)"
    window = res.settings.get("integral_window") if res.model == "integral" else None
    return _score_correlation(
        res.base,
        res.reduced,
        row_weights(res),
        _logs(data),
        res.settings.get("min_velocity", 0.0),
        window=window,
        integration=res.settings.get("integration", "simpson"),
    )


def _equation_rows(
    base: BaseParameters,
    d: JointData,
    min_velocity: float,
    window: int | None,
    integration: str,
):
    """The equations of log ``d`` as :func:`_score_correlation` takes them: ``(count, edges,
    keep, chunks)``, ``count`` the samples (dynamic model, ``window`` None) or windows
    (integral model), ``edges`` the indices where the logs joined in ``d`` start (and
    ``count``), ``keep`` the equations fitted (``(count, n)`` booleans, None: all) and
    ``chunks`` an iterator of consecutive ``(W (k, n, nb), y (k, n))``."""
    if window is None:
        tau = require_torque(d)
        keep = moving_equations(base, d.dq, min_velocity)
        chunks = (
            (regressor_rows(base, d, c0, min(d.m, c0 + 8192)), tau[c0 : c0 + 8192])
            for c0 in range(0, d.m, 8192)
        )
        return d.m, [*(d.starts or (0,)), d.m], keep, chunks
    a, _ = windows(d, window)
    keep = moving_windows(base, d, window, min_velocity)
    chunks = integral_chunks(base, d, window=window, integration=integration)
    starts = np.searchsorted(a, np.asarray(d.starts or (0,)))
    return a.size, [*(int(x) for x in starts), a.size], keep, chunks


def _score_correlation(
    base: BaseParameters,
    ls: _Reduced,
    w: np.ndarray,
    logs: list[JointData],
    min_velocity: float,
    *,
    window: int | None = None,
    integration: str = "simpson",
) -> tuple[float | None, str]:
    """:func:`residual_correlation` of the reduced problem ``ls`` (rows weighted by ``w`` per
    joint) fitted on ``logs``: the dynamic model's (``window`` None) or the integral model's
    (windows of ``window`` sample intervals, integrated by ``integration``)."""
    nb = base.n
    beta, _, _ = ls.solve(list(range(nb)))
    s2 = ls.rho / (ls.r - nb) if ls.r > nb else 0.0
    A = np.zeros((nb, nb))
    S = np.zeros((nb, nb))
    lags = []
    for d in logs:
        count, edges, keep, chunks = _equation_rows(base, d, min_velocity, window, integration)
        G = np.zeros((count, nb))
        i0 = 0
        for Wr, y in chunks:
            i1 = i0 + Wr.shape[0]
            r = (y - Wr @ beta) * w[None, :]
            Wr = Wr * w[None, :, None]
            if keep is not None:
                Wr = Wr * keep[i0:i1, :, None]
                r = r * keep[i0:i1]
            G[i0:i1] = np.einsum("tjb,tj->tb", Wr, r)
            A += np.einsum("tjb,tjc->bc", Wr, Wr)
            i0 = i1
        # no lag spans the join of two logs
        for g in (G[a:b] for a, b in zip(edges[:-1], edges[1:]) if b > a):
            L = newey_west_lag(g)
            S += g.T @ g
            for k in range(1, L + 1):
                C = g[:-k].T @ g[k:]
                S += (1.0 - k / (L + 1.0)) * (C + C.T)
            lags.append(L)
    if not s2 > 0 or not np.any(A):
        return None, "not measured (no residual)"
    d = np.sqrt(np.maximum(np.diag(A), 1e-300))
    Ad = A / np.outer(d, d)
    try:
        X = sla.cho_solve(sla.cho_factor(Ad), S / np.outer(d, d))
    except (np.linalg.LinAlgError, ValueError):
        X = np.linalg.lstsq(Ad, S / np.outer(d, d), rcond=1e-13)[0]
    factor = float(np.trace(X)) / (nb * s2)
    rule = (
        "Newey-West covariance of the fit's scores (Bartlett weights up to lag "
        + ", ".join(map(str, lags))
        + (" samples" if window is None else " windows")
        + ", chosen from the scores' correlation by Newey and West's automatic rule) "
        "over that of independent residuals, mean over the parameter directions"
    )
    return factor, rule


def newey_west_lag(g: np.ndarray) -> int:
    """The Bartlett lag of the Newey-West covariance of the scores ``g`` (shape (m, k), one row
    per sample), by Newey & West's automatic selection (Review of Economic Studies 61, 1994), so
    that residuals correlated over many samples (model error) are covered: the preliminary lag
    alone, fixed by the number of samples, sees under half of the variance of an estimate
    under first-order autoregressive noise of coefficient 0.9 (19 times that of independent
    noise):
    ``L = floor(1.1447 (s1 / s0)^(2/3) m^(1/3))``, with ``s0 = sum_|j|<=n c_j`` and
    ``s1 = sum_|j|<=n |j| c_j`` from the autocovariances ``c_j`` (summed over the columns,
    each scaled to unit variance) up to the preliminary lag ``n = floor(4 (m / 100)^(2/9))``;
    ``n`` where ``s1 / s0`` is not positive. At most ``m - 1``."""
    m = len(g)
    n = min(int(4.0 * (m / 100.0) ** (2.0 / 9.0)), m - 1)
    sd = g.std(axis=0)
    u = g[:, sd > 0] / sd[sd > 0]
    if n < 1 or u.shape[1] == 0:
        return max(n, 0)
    c = np.array([float(np.sum(u[: m - j] * u[j:])) for j in range(n + 1)]) / m
    j = np.arange(1, n + 1)
    s0 = c[0] + 2.0 * float(c[1:].sum())
    s1 = 2.0 * float(j @ c[1:])
    if not (s0 > 0 and s1 > 0):
        return n
    return min(int(1.1447 * (s1 / s0) ** (2.0 / 3.0) * m ** (1.0 / 3.0)), m - 1)


def window_variance_factor(cutoff: float, order: int, duration: float) -> float:
    """The factor on the variance of estimates from equations that each integrate low-passed
    white noise over one of consecutive windows of ``duration`` seconds, the filter that of
    :func:`noise_bandwidth`. Such a window's noise has the variance ``S0 V(T)``,
    ``V(T) = int_-T^T (T - |tau|) rho(tau) dtau`` (``S0`` the white noise's spectral density,
    ``rho`` the inverse Fourier transform of ``|H|^4``, of unit integral), while the estimates,
    from regressor columns that change little over the filter's correlation time, see the
    noise's spectral density at zero frequency, ``S0 T`` per window: the variance of windows
    taken as independent is ``T / V(T)`` times too small. That is ``1 / (2 B T)`` for a window
    much shorter than the noise's correlation time ``1 / (2 B)`` (``B``:
    :func:`noise_bandwidth`; the windows then share their noise like samples do), tending to 1
    for long windows (a window shares only the noise near its ends with its neighbours).
    ``rho`` is evaluated from ``|H|^4`` by the trapezoid rule (cut-off 1: frequencies up to 40,
    correlation lags up to 20, where it has decayed below 1e-8 for orders 1 to 10)."""
    x = cutoff * duration  # the window in periods of the cut-off
    f = np.linspace(0.0, 40.0, 5121)
    h4 = (1.0 + f ** (2 * order)) ** -2
    u = np.linspace(0.0, min(x, 20.0), 257)
    w = np.full(f.size, f[1])
    w[[0, -1]] *= 0.5
    rho = 2.0 * np.cos(2.0 * np.pi * np.outer(u, f)) @ (w * h4)  # rho at cut-off 1
    var = 2.0 * float(integrate.trapezoid((x - u) * rho, u))  # V(T) fc
    return max(1.0, x / var)


def _variance_factor_record(
    path: float, path_rule: str, measured: float | None, measured_rule: str
) -> dict:
    """``settings.std_correlation``: the factor on the variance of the estimates, the larger of
    the data path's (:func:`correlation_factor`) and the one the fit's residuals show
    (:func:`residual_correlation`, None: not measured), with both and the rule in words."""
    factor = max(path, measured or 0.0)
    if measured is not None and measured > path:
        rule = (
            f"variance x {factor:.3g} for the correlation the fit's residuals show ({measured_rule}"
            f"; model error leaves residuals correlated), above the data path's {path:.3g} ("
            + path_rule
            + ")"
        )
    else:
        rule = path_rule + (
            f"; the fit's residuals show {measured:.3g} ({measured_rule}), not more"
            if measured is not None
            else ""
        )
    return {
        "variance_factor": factor,
        "rule": rule,
        "data_path": path,
        "residuals": measured,
        "residuals_rule": measured_rule,
    }


def correlation_factor(
    logs: Sequence[JointData], rows: Sequence[int], window: int | None = None
) -> tuple[float, str]:
    """The factor on the variance of the estimates for the correlation of the equations'
    noise, and the rule in words. The data path low-passes a log before it is decimated to at
    least 10 x the cut-off, so white noise on the logged torques (or velocities) is correlated
    between the samples fitted.

    Dynamic model (``window`` None): over ``m`` samples at rate ``fs`` the noise carries the
    information of ``m 2 B / fs`` independent ones (``B``: :func:`noise_bandwidth`), and the
    variance ``sigma^2 (W^T W)^-1`` of samples taken as independent is ``fs / (2 B)`` times too
    small (white noise has a flat spectrum; the regressor columns, within the band of the
    motion, change little over the noise's correlation time); per log ``max(1, fs / (2 B))``.
    Integral and energy models (equations integrating over consecutive windows of ``window``
    sample intervals): per log :func:`window_variance_factor` of the windows' duration
    ``window / fs``. A log not low-passed: 1. Averaged over the logs by their equations
    ``rows``, and over the parts of a log joined by
    :func:`~mindyn.identification.preprocess.concatenate` by their samples."""
    factors, rates = [], []

    def factor(pre: dict | None) -> float:
        pre = pre or {}
        filt = pre.get("filter")
        if filt is None:
            return 1.0
        fs, cutoff, order = float(pre["rate_Hz"]), float(filt["cutoff_Hz"]), int(filt["order"])
        band = noise_bandwidth(cutoff, order)
        rates.append((fs, band))
        if window is None:
            return max(1.0, fs / (2.0 * band))
        return window_variance_factor(cutoff, order, window / fs)

    for d in logs:
        pre = d.processing.get("preprocess")
        parts = (pre or {}).get("logs")
        if parts and len(parts) == len(d.starts or (0,)) > 1:
            # logs joined by concatenate: each part's own data path, by its samples
            edges = [*d.starts, d.m]
            sizes = np.diff(edges)
            factors.append(float(sizes @ [factor(p) for p in parts]) / max(d.m, 1))
        else:
            factors.append(factor(pre))
    total = sum(rows)
    f = sum(r * x for r, x in zip(rows, factors)) / total if total > 0 else 1.0
    if not rates:
        what = "samples" if window is None else "windows"
        return 1.0, f"{what} taken as independent (no low-pass)"
    fs, band = rates[0]
    if window is None:
        rule = (
            f"variance x {f:.3g} for the low-passed noise's correlation between samples (rate "
            f"{fs:.4g} Hz / (2 x its noise bandwidth {band:.4g} Hz))"
        )
    else:
        rule = (
            f"variance x {f:.3g} for the low-passed noise's correlation within and between "
            f"windows (windows of {window / fs:.4g} s against its correlation time "
            f"1 / (2 x its noise bandwidth {band:.4g} Hz) = {1 / (2 * band):.3g} s)"
        )
    return f, rule + (
        ", averaged over the logs" if len(rates) > 1 or len(rates) < len(logs) else ""
    )


#: Ratio of a kept estimate's standard deviation in the fit with all base parameters to its
#: standard deviation after pruning, above which the parameter is listed as one whose
#: standard deviation the pruning understates (see :func:`pruning_std_record`).
PRUNING_STD_LISTED = 3.0


def pruning_std_record(names: list, std: np.ndarray, std_all: np.ndarray, *, removed: int) -> dict:
    """How much the pruning narrows the kept estimates' standard deviations.

    A kept estimate after pruning is ``p_k + A p_r`` of the fit with all base parameters
    (``A`` the regression of the removed columns on the kept ones): it estimates its base
    parameter plus what the removed ones contribute through it. Its standard deviation after
    pruning assumes the removed parameters are zero; the fit with all of them gives the same
    estimate's spread with them free, ``cov_all = cov_pruned + A cov_rr A^T`` (the
    least-squares identity). Each kept parameter's ratio ``std_all / std`` says how much its
    standard deviation understates its error as an estimate of the base parameter when the
    removed parameters are not in fact zero (on simulated logs a tenth of an excitation period
    long with exact accelerations: median ratios of 24-37, and 14-32 of 33-37 kept estimates
    more than 3 of their standard deviations off, up to 8-190; all within 3 ``std_all``).

    Returns ``{"median", "largest": [[name, ratio], ...] (ratio above PRUNING_STD_LISTED,
    largest first, at most 10), "warn"}``; ``warn`` when more than half of the kept estimates
    are understated by that factor or more (the median ratio above it)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(std > 0, std_all / std, 1.0)
    ratio = np.where(np.isfinite(ratio), ratio, np.inf)
    order = np.argsort(-ratio)
    listed = [[names[i], _json_float(ratio[i])] for i in order if ratio[i] > PRUNING_STD_LISTED]
    median = float(np.median(ratio)) if ratio.size else 1.0
    return {
        "rule": (
            "std_all / std per kept parameter: its standard deviation in the fit with all base "
            "parameters over that after pruning; listed above "
            f"{PRUNING_STD_LISTED:g}, warned when the median is above it"
        ),
        "median": median,
        "largest": listed[:10],
        "listed": len(listed),
        "warn": bool(removed and median > PRUNING_STD_LISTED),
    }


def _rsd(p: np.ndarray, std: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(p != 0, 100.0 * std / np.abs(p), np.inf)


def pruned(solve, keep: list[int], threshold: float | None):
    """Backward elimination by relative standard deviation, the pruning of :func:`identify`:
    from the columns ``keep``, the parameter of largest RSD [%] (:func:`_rsd`) removed while it
    is above ``threshold`` (None: none removed), re-estimated after each removal by ``solve``
    (columns -> ``(p, std, sigma2)``). Returns ``(keep, p, std, sigma2, removed)``, ``removed``
    the columns left out with their RSD at that moment, in order."""
    keep = list(keep)
    p, std, s2 = solve(keep)
    removed = []
    while threshold is not None and len(keep) > 1:
        rsd = _rsd(p, std)
        j = int(np.argmax(np.where(np.isnan(rsd), np.inf, rsd)))
        if not rsd[j] > threshold:
            break
        removed.append((keep[j], float(rsd[j])))
        del keep[j]
        p, std, s2 = solve(keep)
    return keep, p, std, s2, removed


def _energy_row_sd(
    logs: list[JointData], used: list[JointData], window: int
) -> tuple[np.ndarray, np.ndarray | None]:
    """The energy model's weighting: per-joint torque-noise levels of ``logs`` as logged and
    each window's standard deviation of the power integral from them (None: the noise is not
    measurable)."""
    joint_sigma = torque_noise([x for d in logs for x in logged_torques(d)])
    sd = np.concatenate(_energy_window_sd(used, window, joint_sigma))
    return joint_sigma, (sd if np.all(sd > 0) else None)


def _energy_window_sd(used: list[JointData], window: int, joint_sigma: np.ndarray) -> list:
    """Per log of ``used``, each energy window's standard deviation of the power integral from
    the per-joint torque-noise levels ``joint_sigma`` (n,), with a floor of a tenth of the
    median variance over all the windows: windows near rest would otherwise get unbounded
    weight, and their error is then dominated by what the noise model leaves out (velocity
    noise, model error). The energy model's row weights are their inverses."""
    var = [energy_row_noise(d, window) @ joint_sigma**2 for d in used]
    floor = 0.1 * np.median(np.concatenate(var))
    return [np.sqrt(v + floor) for v in var]


#: The integration rules ``integration="auto"`` chooses between (see :func:`_energy_equations`).
AUTO_RULES = ("simpson", "zoh")


def _energy_equations(
    base: BaseParameters,
    used: list[JointData],
    window: int,
    integration: str,
    row_sd: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray, str, dict | None]:
    """The energy model's stacked ``W``, ``y``, the integration rule used and, for ``auto``,
    the record of its choice (else None).

    ``auto`` takes, of Simpson's rule (exact for a torque that is smooth between the samples)
    and the zero-order hold (exact for a torque held over each sample period, as a digital
    controller's command is), the one whose least-squares fit with every base parameter leaves
    the smaller residual (the windows weighted by ``row_sd`` when given): each rule is the
    other's model error, of about a half sample period's shift of the torque (a relative error
    of 1.2e-3 in the windows' work on a simulated geared 6R arm, both ways; 1e-6 and 2e-10 with
    the right rule). On the real Panda, KUKA LWR4+ and UR10e logs the hold leaves the smaller
    residual, and smaller torque errors."""
    rules = AUTO_RULES if integration == "auto" else (integration,)
    systems = {}
    for rule in rules:
        parts = [energy_system(base, d, window=window, integration=rule) for d in used]
        systems[rule] = (np.vstack([w for w, _ in parts]), np.concatenate([v for _, v in parts]))
    if len(rules) == 1:
        return (*systems[integration], integration, None)
    w = np.ones(systems[rules[0]][1].size) if row_sd is None else 1.0 / row_sd
    rss = {}
    for rule, (W, y) in systems.items():
        p = np.linalg.lstsq(W * w[:, None], y * w, rcond=None)[0]
        rss[rule] = float(np.sum(((W @ p - y) * w) ** 2))
    choice = _integration_choice(
        rss, f"{'weighted ' if row_sd is not None else ''}residual sum of squares"
    )
    return (*systems[choice["chosen"]], choice["chosen"], choice)


def _integration_choice(score: dict[str, float], what: str) -> dict:
    """``settings["integration_choice"]``: the rule of the smallest ``score`` (its ``what``)."""
    return {
        "rule": f"auto: the rule whose fit with every base parameter leaves the smaller {what}",
        "rss": score,
        "chosen": min(score, key=lambda r: score[r]),
    }


def _integral_triangles(
    base: BaseParameters, logs: list[JointData], keeps: list, window: int, rule: str
) -> np.ndarray:
    """Per joint, the R factor of the integral model's ``[W_j, y_j]`` over ``logs`` (windows
    within each log, the equations ``keeps`` leaves out dropped), merged by QR: (n, nb+1, nb+1)."""
    n, nb = base.robot.n, base.n
    S = np.zeros((n, nb + 1, nb + 1))
    for d, keep in zip(logs, keeps):
        i0 = 0
        for Wi, yi in integral_chunks(base, d, window=window, integration=rule):
            sel = None if keep is None else keep[i0 : i0 + Wi.shape[0]]
            i0 += Wi.shape[0]
            for j in range(n):
                A = np.column_stack([Wi[:, j], yi[:, j]])
                S[j] = _triangle(np.vstack([S[j], A if sel is None else A[sel[:, j]]]))
    return S


def _integral_equations(
    base: BaseParameters, logs: list[JointData], keeps: list, window: int, integration: str
) -> tuple[np.ndarray, str, dict | None]:
    """The integral model's per-joint triangles (:func:`_integral_triangles`), the integration
    rule used and, for ``auto``, the record of its choice (else None): of :data:`AUTO_RULES`,
    the rule whose least-squares fit with every base parameter leaves the smaller residual,
    each joint's residual sum of squares taken relative to Simpson's (the joints' torques
    differ in scale), summed over the joints."""
    rules = AUTO_RULES if integration == "auto" else (integration,)
    tri = {rule: _integral_triangles(base, logs, keeps, window, rule) for rule in rules}
    if len(rules) == 1:
        return tri[integration], integration, None
    rss = {}
    for rule, S in tri.items():
        stacked = np.vstack(list(S))
        p = np.linalg.lstsq(stacked[:, :-1], stacked[:, -1], rcond=None)[0]
        rss[rule] = np.array([float(np.sum((Sj @ np.append(p, -1.0)) ** 2)) for Sj in S])
    ref = np.where(rss[rules[0]] > 0, rss[rules[0]], 1.0)
    score = {rule: float(np.sum(r / ref)) for rule, r in rss.items()}
    choice = _integration_choice(
        score, f"residual sum of squares, per joint relative to {rules[0]}'s, summed over joints"
    )
    return tri[choice["chosen"]], choice["chosen"], choice


@single_threaded_blas
def identify(
    robot: Robot | str,
    data: JointData | Sequence[JointData],
    *,
    model: str = "dynamic",
    rotor: bool = False,
    friction: bool = False,
    base: BaseParameters | None = None,
    weighted: bool = True,
    rsd_threshold: float | None = DEFAULT_RSD_THRESHOLD,
    energy_window: int = 10,
    integration: str = "auto",
    integral_window: int = 40,
    min_velocity: float = DEFAULT_MIN_VELOCITY,
    rank_tolerance: float = 1e-9,
) -> IdentificationResult:
    """Estimate the base parameters of ``robot`` from ``data``.

    Parameters
    ----------
    robot : Robot or str
    data : JointData or sequence of JointData
        ``t, q, dq, ddq, tau`` (``ddq`` is used by the dynamic model only). Several logs are
        fitted together: each log's regression system is formed from its own samples (its
        derivatives were obtained on it alone, never across the junction between logs; energy
        and integral windows do not span two logs) and the systems are stacked; the per-joint
        noise weights are estimated over all of them. ``settings["logs"]`` gives each log's
        samples and equations.
    model : {"dynamic", "energy", "integral"}
    rotor, friction : bool
        Include rotor inertia / viscous and Coulomb friction (ignored when ``base`` is given).
    base : BaseParameters, optional
        Reuse a computed base-parameter set.
    weighted : bool
        Dynamic and integral models: weighted least squares with per-joint weights from a first
        OLS pass; energy model: per-window weights from per-joint torque-noise estimates on
        the torques as logged, before the data path's low-pass
        (:func:`~mindyn.identification.models.energy_row_noise`).
    rsd_threshold : float or None
        Remove parameters with an RSD above this many percent, largest first, re-estimating after
        each removal (None or <= 0: keep all). Default: 70.7, a t-statistic of sqrt(2)
        (:data:`~mindyn.identification.options.DEFAULT_RSD_THRESHOLD`).
    energy_window : int
        Energy model: sample intervals per window (one equation per window).
    integration : {"auto", "simpson", "trapezoid", "zoh"}
        Energy and integral models: rule for the integrals over a window (``zoh``: the logged
        torque is taken as held over each sample period, ``int dq^T tau dt = sum tau_k^T (q_k+1 -
        q_k)`` (energy), ``int tau dt = sum tau_k (t_k+1 - t_k)`` (integral), exact for a command
        held by the drive; the other integrals by Simpson). ``auto`` (the default): of
        ``simpson`` and ``zoh``, the one whose fit with every base parameter leaves the smaller
        residual (a torque held between the samples, or smooth; energy model: the weighted
        residual sum of squares, integral model: each joint's relative to Simpson's, summed;
        both systems are formed, twice the work of one rule); ``settings["integration_choice"]``
        records both.
    integral_window : int
        Integral model: sample intervals per window (one equation per joint and window; see
        :func:`~mindyn.identification.models.integral_system`).
    min_velocity : float
        Dynamic and integral models with friction: equations of joints slower than this
        [rad/s | m/s] are left out (see :func:`dynamic_system`; integral model: a joint's
        equation of a window where it is slower at any sample,
        :func:`~mindyn.identification.models.moving_windows`). Given (any value, 0.01 too) for
        a base without friction or with the energy model, refused; not given, 0.01
        (:data:`~mindyn.identification.options.DEFAULT_MIN_VELOCITY`).
    rank_tolerance : float
        Relative size of the pivots of the column-scaled regressor below which it counts as rank
        deficient.

    The dynamic model is reduced chunk by chunk (:func:`dynamic_triangles`): memory does not
    grow with the length of the log; nor does the integral model's (reduced per joint from
    :func:`~mindyn.identification.models.integral_chunks`, then weighted like the dynamic
    model's). More than half of the parameters removed by pruning is reported in
    ``settings["warnings"]``.

    Raises
    ------
    IdentificationError
        Fewer equations than :data:`MIN_EQUATIONS_PER_PARAMETER` per base parameter or than
        :data:`MIN_NOISE_DOF` beyond them, unknown model.
    RankDeficientError
        The data do not excite every base parameter (they are named).
    ArgumentError
        An argument of the wrong type or range, ``min_velocity`` given for a base without
        friction or with the energy model.
    """
    t0 = time.perf_counter()
    robot = as_robot(robot)
    if not robot.single_dof:
        raise _core.ModelError(
            f"identify takes revolute and prismatic joints only; robot '{robot.name}' has joints "
            "of several degrees of freedom: identify it with "
            "mindyn.identification.identify_floating (joint torques and contact wrenches, or "
            "free flight)"
        )
    logs = distinct_logs(_logs(data, robot=robot))
    _args.choice(model, "model", MODELS)
    rotor, friction = _args.flag(rotor, "rotor"), _args.flag(friction, "friction")
    _args.optional(_args.instance, base, "base", BaseParameters)
    weighted = _args.flag(weighted, "weighted")
    rsd_threshold = _args.optional(_args.number, rsd_threshold, "rsd_threshold")
    energy_window = _args.integer(energy_window, "energy_window", 1)
    _args.choice(integration, "integration", INTEGRATIONS)
    integral_window = _args.integer(integral_window, "integral_window", 1)
    given_velocity = min_velocity is not DEFAULT_MIN_VELOCITY
    min_velocity = _args.number(min_velocity, "min_velocity", minimum=0.0)
    rank_tolerance = _args.number(rank_tolerance, "rank_tolerance", positive=True)
    for d in logs:
        if d.n != robot.n:
            raise DataError(
                f"{d.source or 'data'} has {d.n} joints; robot '{robot.name}' has {robot.n}"
            )
    check_magnitudes(robot, logs)
    if base is None:
        base = base_parameters(robot, rotor=rotor, friction=friction)
    if given_velocity and model == "energy":
        raise _args.fail(
            "min_velocity",
            "applies only to the dynamic and integral models (it leaves out the equations of "
            "joints too slow for the sign of their Coulomb friction); the energy model's "
            "windows take every sample (model='dynamic' or 'integral', or leave out "
            "min_velocity)",
        )
    if given_velocity and not base.friction:
        raise _args.fail(
            "min_velocity",
            "applies only to a base with friction (it leaves out the equations of joints too "
            "slow for the sign of their Coulomb friction); this base has none (friction=True, "
            "or leave out min_velocity)",
        )
    names = list(base.names)
    nb = base.n
    settings: dict = {"model": model}
    equations = sum(d.m for d in logs) * robot.n
    pre = [d.processing["preprocess"] for d in logs if "preprocess" in d.processing]
    if pre:
        settings["preprocessing"] = pre[0] if len(logs) == 1 else pre
    if model == "dynamic":
        _enough(model, equations, nb, logs, settings)  # before any work
        S = np.zeros((robot.n, nb + 1, nb + 1))
        joint_rows = np.zeros(robot.n, dtype=int)
        log_rows = []
        for d in logs:  # each log's system on its own samples; per joint, merged by QR
            Sd, rd = dynamic_triangles(base, d, min_velocity=min_velocity)
            S = np.stack([_triangle(np.vstack([a, b])) for a, b in zip(S, Sd)])
            joint_rows += rd
            log_rows.append(int(rd.sum()))
        rows = int(joint_rows.sum())
        settings["min_velocity"] = min_velocity if base.friction else 0.0
        settings["equations_left_out"] = equations - rows
        _enough(model, rows, nb, logs, settings)
    elif model == "integral":
        keeps = [moving_windows(base, d, integral_window, min_velocity) for d in logs]
        counts = [
            np.full(robot.n, windows(d, integral_window)[0].size) if k is None else k.sum(axis=0)
            for d, k in zip(logs, keeps)
        ]
        log_rows = [int(c.sum()) for c in counts]
        rows = sum(log_rows)
        joint_rows = np.sum(counts, axis=0)
        settings["min_velocity"] = min_velocity if base.friction else 0.0
        settings["equations_left_out"] = (
            sum(windows(d, integral_window)[0].size * d.n for d in logs) - rows
        )
        _enough(model, rows, nb, logs, settings, integral_window)
        S, integration, choice = _integral_equations(
            base, logs, keeps, integral_window, integration
        )
        settings.update({"integral_window": integral_window, "integration": integration})
        if choice is not None:
            settings["integration_choice"] = choice
    else:
        log_rows = [windows(d, energy_window, gaps=False)[0].size for d in logs]
        rows = sum(log_rows)
        _enough(model, rows, nb, logs, settings, energy_window)
        used = [d for d, r in zip(logs, log_rows) if r > 0]  # logs with a whole window
        joint_sigma, row_sd = None, None
        if weighted:
            joint_sigma, row_sd = _energy_row_sd(logs, used, energy_window)
        W, y, integration, choice = _energy_equations(
            base, used, energy_window, integration, row_sd
        )
        settings.update({"energy_window": energy_window, "integration": integration})
        if choice is not None:
            settings["integration_choice"] = choice
    settings["logs"] = [
        {"source": d.source, "samples": d.m, "equations": r} for d, r in zip(logs, log_rows)
    ]
    what = f"{model} model on {_sources(logs)}"
    if model in ("dynamic", "integral"):
        ls = _Reduced.from_triangle(_triangle(np.vstack(list(S))), rows)
    else:
        ls = _Reduced(W, y)
    speed = min_velocity if base.friction and model in ("dynamic", "integral") else 0.0
    cond = _check_rank(ls, names, what, rank_tolerance, logs, speed, base.robot)

    if not any(np.any(np.asarray(d.tau)) for d in logs):  # not a singular regressor
        raise IdentificationError(
            f"{what}: every torque is zero at every sample: nothing to fit (were the torques, "
            "or currents, logged?)"
        )
    if model != "energy":
        joint_sigma = None
    if weighted and model == "energy":
        if row_sd is not None:
            w = 1.0 / row_sd
            ls = _Reduced(W * w[:, None], y * w)
            settings["weighting"] = (
                "per-window 1/sd of the power integral from per-joint torque-noise estimates "
                "(second differences of the torques as logged, before any low-pass)"
            )
        else:
            weighted = False
            settings["weighting"] = "none (torque noise not measurable)"
    elif weighted:
        p, _, _ = ls.solve(list(range(nb)))
        # |y_j - W_j p|^2 = |S_j [p; -1]|^2: each joint's residual from its triangle
        rss = np.array([float(np.sum((Sj @ np.append(p, -1.0)) ** 2)) for Sj in S])
        dof = (rows - nb) / rows
        mean = rss / np.maximum(joint_rows, 1)
        joint_sigma = np.sqrt(np.where(joint_rows > 0, mean, 0.0) / max(dof, 1e-12))
        w = joint_weights(joint_sigma)
        ls = _Reduced.from_triangle(_triangle(np.vstack([wj * Sj for wj, Sj in zip(w, S)])), rows)
        settings["weighting"] = "per-joint 1/sigma_j from a first OLS pass"
    else:
        settings["weighting"] = "none (ordinary least squares)"

    window = {"dynamic": None, "integral": integral_window, "energy": energy_window}[model]
    inflation, rule = correlation_factor(logs, log_rows, window)
    measured, measured_rule = None, "not measured (the dynamic and integral models only)"
    if model != "energy":
        w = joint_weights(joint_sigma) if weighted and joint_sigma is not None else np.ones(robot.n)
        measured, measured_rule = _score_correlation(
            base,
            ls,
            w,
            logs,
            settings.get("min_velocity", 0.0),
            window=window,
            integration=settings.get("integration", "simpson"),
        )
    settings["std_correlation"] = _variance_factor_record(inflation, rule, measured, measured_rule)
    inflation = settings["std_correlation"]["variance_factor"]

    return _pruned_result(
        model, base, ls, settings, inflation, rsd_threshold,
        weighted=weighted, joint_sigma=joint_sigma, cond=cond, t0=t0,
    )  # fmt: skip


def _pruned_result(
    model: str,
    base: BaseParameters,
    ls: _Reduced,
    settings: dict,
    inflation: float,
    rsd_threshold: float | None,
    *,
    weighted: bool,
    joint_sigma,
    cond: float,
    t0: float,
) -> IdentificationResult:
    """The estimate of the reduced problem ``ls`` (its variance times ``inflation``) pruned at
    ``rsd_threshold`` (None or <= 0: every base parameter kept), as :func:`identify` returns
    it; ``settings`` (the fit's, without the pruning's entries) gets the pruning's."""
    names, nb = list(base.names), base.n

    def solve(cols):
        return ls.solve(cols, inflation=inflation)

    p, std, s2 = solve(list(range(nb)))
    initial = {"values": p.copy(), "std": std.copy(), "rsd": _rsd(p, std)}
    thr = rsd_threshold if rsd_threshold is not None and rsd_threshold > 0 else None
    keep, p, std, s2, dropped = pruned(solve, list(range(nb)), thr)
    removed = tuple((names[j], r) for j, r in dropped)
    full = np.zeros(nb)
    full[keep] = p
    settings["rsd_threshold"] = thr
    warnings = []
    if 2 * len(removed) > nb:
        # The removed parameters are set to zero; what they contribute to the torques is taken
        # up by the kept ones, whose RSDs hold only if the removed ones are in fact negligible.
        warnings.append(
            f"{len(removed)} of {nb} base parameters removed for RSD > {thr:g} %: the data "
            "excite most parameters too little to tell them apart; the kept estimates take up "
            "what the removed ones contribute, and their RSDs assume those are zero. Use a "
            "longer or richer excitation"
        )
    settings["pruning_std"] = pruning_std_record(
        [names[k] for k in keep], std, initial["std"][keep], removed=len(removed)
    )
    if settings["pruning_std"]["warn"]:
        # The pruned standard deviations assume the removed parameters are zero, which data that
        # leave them this uncertain cannot confirm: each kept estimate is given the larger of
        # its two standard deviations (on a simulated geared arm, energy model: 79 % of the kept
        # estimates beyond 3 pruned ones from the truth, up to 22; none beyond 3 of these).
        std = np.maximum(std, initial["std"][keep])
        settings["pruning_std"]["widened"] = True
        r = settings["pruning_std"]
        warnings.append(
            f"the pruning leaves the kept estimates' standard deviations {r['median']:.3g} x "
            "smaller (median) than the fit with all base parameters gives them: they assume "
            f"the {len(removed)} removed parameters are zero, and as estimates of the base "
            "parameters they may be off by many of them (the removed parameters' contributions "
            "taken up); the standard deviations given are the larger ones, with the removed "
            "parameters free. Use a longer or richer excitation, or rsd_threshold=0 to keep "
            "every parameter with its own standard deviation"
        )
    if warnings:
        settings["warnings"] = warnings
    return IdentificationResult(
        model=model,
        base=base,
        names=tuple(names[k] for k in keep),
        values=p,
        std=std,
        rsd=_rsd(p, std),
        removed=removed,
        full=full,
        sigma=math.sqrt(s2) if math.isfinite(s2) else float("nan"),
        rows=ls.r,
        weighted=weighted,
        joint_sigma=joint_sigma,
        cond=cond,
        rsd_threshold=thr if thr is not None else float("nan"),
        initial=initial,
        settings=settings,
        seconds=time.perf_counter() - t0,
        reduced=ls,
    )


@single_threaded_blas
def repruned(res: IdentificationResult, rsd_threshold: float | None) -> IdentificationResult:
    """``res`` pruned at ``rsd_threshold`` instead (None or <= 0: every base parameter kept):
    what :func:`identify` returns for the same data and options with that threshold, from the
    least-squares problem ``res`` carries, without forming it again."""
    if res.reduced is None:
        raise IdentificationError("the identification result carries no least-squares problem")
    own = ("warnings", "pruning_std", "rsd_threshold")  # the pruning's entries
    settings = {k: v for k, v in res.settings.items() if k not in own}
    return _pruned_result(
        res.model, res.base, res.reduced, settings, noise_variance_factor(res), rsd_threshold,
        weighted=res.weighted, joint_sigma=res.joint_sigma, cond=res.cond,
        t0=time.perf_counter() - res.seconds,
    )  # fmt: skip
