"""Regression systems of the identification models, over the equations-of-motion base set of
:func:`mindyn.base_parameters`.

``dynamic``
    ``W_b(q_i, dq_i, ddq_i) p_b = tau_i`` for every sample ``i``, stacked (``m n`` rows).
``energy``
    The integral form of the energy theorem over consecutive windows ``[t_a, t_b]`` of
    ``window`` samples: ``(w_H(t_b) - w_H(t_a)) p_b + sum_i F_i,k int v_k phi_i(v_k) dt
    + Off_k (q_k(t_b) - q_k(t_a)) = int dq^T tau dt``, ``phi_i`` the friction columns of the
    robot's friction model (:meth:`~mindyn.Robot.friction_shapes`; ``Fv_k int v_k^2 dt + Fc_k
    int |v_k| dt`` for viscous and Coulomb friction) at the velocity ``v_k`` of friction slot
    ``k`` (``dq_k``, or motor ``k``'s ``t_k . dq`` on the motor side); no accelerations are
    needed. The
    dissipated-energy columns of the friction parameters (and the work of the torque offsets)
    replace their (zero) energy columns; the integrals use the trapezoid or Simpson rule on the
    samples, or for the power the zero-order hold (``sum tau_k^T (q_k+1 - q_k)``, exact for a
    torque held over each sample period).
``integral``
    Each joint's equation of motion in momentum form, ``tau = d/dt p - dL/dq + friction``
    (``p = A(q) dq``, ``L = K - P``), integrated over windows ``[t_a, t_b]`` of ``window``
    sample intervals (:func:`integral_system`): ``n`` equations per window, no accelerations.
"""

from __future__ import annotations

import math
import re

import numpy as np
from scipy import integrate

from .. import _args
from .._args import ArgumentError
from ..base import BaseParameters
from .data import DataError, check_units
from .errors import IdentificationError
from .joint_data import JointData

MODELS = ("dynamic", "energy", "integral")

#: A sample interval longer than this many times the median one is a gap in the log: no
#: integral-model window spans it.
GAP_FACTOR = 2.0

#: Samples whose momentum regressors are evaluated at once by the integral model.
CHUNK_SAMPLES = 8192


# ---------------------------------------------------------------------------------------------
def moving_equations(base: BaseParameters, dq, min_velocity: float) -> np.ndarray | None:
    """Which equations of the dynamic model to keep with ``min_velocity``: ``(m, n)`` booleans,
    or None to keep all (no friction, or ``min_velocity`` 0). Joint ``j``'s equation at a sample
    is left out when a slot whose friction acts on it moves slower than ``min_velocity``: on the
    joints, joint ``j`` itself; on the motors, each motor ``k`` with ``T[k, j] != 0``, its speed
    taken in joint units (divided by its largest ``|T[k, :]|``, a direct drive's ratio)."""
    if not (min_velocity > 0 and base.friction):
        return None
    robot = base.robot
    dq = np.asarray(dq, dtype=float)
    if robot.drive_side != "motor":
        return np.abs(dq) >= min_velocity
    T = robot.drive_matrix
    slow = np.abs(robot.slot_velocities(dq)) < min_velocity * np.max(np.abs(T), axis=1)
    return ~(slow.astype(float) @ (T != 0).astype(float) > 0)


def moving_windows(
    base: BaseParameters, data: JointData, window: int, min_velocity: float
) -> np.ndarray | None:
    """Which equations of the integral model to keep with ``min_velocity``: ``(w, n)`` booleans
    for the windows of :func:`windows`, or None to keep all (no friction, or ``min_velocity``
    0). Joint ``j``'s equation of a window is left out when :func:`moving_equations` leaves out
    joint ``j``'s equation at any sample of the window (joint ``j``, or on the motor side a
    motor acting on it, slower than ``min_velocity``): the Coulomb term integrated over the
    window takes the sign of the velocity there, which the data do not determine (velocity
    noise; a rest, where the drive holds the joint without friction). Keeping windows slow at
    up to a quarter or half of their samples changed the estimates' bias little on simulated
    logs (bench/bench_window_rests.py); with any slow sample, as in the dynamic model, no kept
    equation carries an undetermined sign.

    The energy model needs no such rule: a slow joint's friction power, its torque times its
    velocity, is small whatever the sign (on the same logs its estimates stayed within 0.7
    standard deviations of the truth without it)."""
    keep = moving_equations(base, data.dq, min_velocity)
    if keep is None:
        return None
    a, b = windows(data, window)
    slow = np.vstack([np.zeros((1, data.n)), np.cumsum(~keep, axis=0)])  # slow samples before
    return slow[b + 1] - slow[a] == 0


def dynamic_system(base: BaseParameters, data: JointData, *, min_velocity: float = 0.0):
    """Stacked dynamic model: ``W`` (r, nb), ``y`` (r,) and the joint of each row (r,).

    With ``min_velocity > 0`` and Coulomb friction in the model, the equation of joint ``j`` at a
    sample where ``|dq_j| < min_velocity`` is left out: there the sign of the velocity, and so
    the Coulomb term, is not determined by the data (a torque held over a sample period, stiction,
    velocity noise). ``r = m n`` minus those equations."""
    _args.instance(base, "base", BaseParameters)
    _args.instance(data, "data", JointData)
    check_units(data, base.robot, "data")  # a log built in Python: once
    min_velocity = _args.number(min_velocity, "min_velocity", minimum=0.0)
    require_torque(data)
    assert data.tau is not None
    if data.regressor_filter is not None:  # preprocessed: columns filtered like the torques
        W = data.regressor_filter.regressor(base)
    else:
        W = base.regressor(data.q, data.dq, data.ddq)  # (m, n, nb)
    m, n, nb = W.shape
    W, y, joint = W.reshape(m * n, nb), data.tau.reshape(m * n), np.tile(np.arange(n), m)
    keep = moving_equations(base, data.dq, min_velocity)
    if keep is not None:
        keep = keep.reshape(m * n)
        W, y, joint = W[keep], y[keep], joint[keep]
    return W, y, joint


def friction_columns(base: BaseParameters, dq: np.ndarray) -> dict[int, tuple[int, np.ndarray]]:
    """The friction parameters among the base parameters: base column -> (slot, its friction
    column at the joint velocities ``dq`` (m, n), shape (m,)), the column ``i`` of the robot's
    friction model (:meth:`~mindyn.Robot.friction_shapes`; ``Fv``, ``Fc``, then ``Fa`` or
    ``Fs``) at the slot's velocity (:meth:`~mindyn.Robot.slot_velocities`: the joint's, or its
    motor's on the motor side)."""
    if not base.friction:
        return {}
    names = list(base.names)
    # joint 1's friction names (Fv1, Fc1, then Fa1 or Fs1)
    classical = base.robot.parameter_names(rotor=False, friction=True)[
        10 : base.robot.layout_sizes[2]
    ]
    kinds = [re.sub(r"\d+$", "", nm) for nm in classical]
    phi = base.robot.friction_shapes(base.robot.slot_velocities(dq))  # (m, n, c)
    out = {}
    for k in range(dq.shape[1]):
        for i, kind in enumerate(kinds):
            if f"{kind}{k + 1}" in names:
                out[names.index(f"{kind}{k + 1}")] = (k, phi[:, k, i])
    return out


def data_friction_columns(
    base: BaseParameters, data: JointData
) -> dict[int, tuple[int, np.ndarray]]:
    """:func:`friction_columns` at the velocities of ``data``; on preprocessed data whose
    regressor columns are filtered like the torques (``data.regressor_filter``), each column is
    evaluated on the filtered full-rate motion and low-passed like the torques: the torques
    carry the Coulomb step filtered, not a step at the filtered velocity's sign change, and the
    windows of the energy and integral models that cut through a reversal would otherwise see
    the difference as noise (a bias on the Coulomb and viscous estimates)."""
    cols = friction_columns(base, data.dq)
    if not cols or data.regressor_filter is None:
        return cols
    order = list(cols)

    def shapes(q, dq, ddq):
        at = friction_columns(base, dq)
        return np.column_stack([at[c][1] for c in order])

    filtered = data.regressor_filter.signals(shapes)
    return {c: (cols[c][0], filtered[:, i]) for i, c in enumerate(order)}


def _cumulative(f: np.ndarray, t: np.ndarray, rule: str) -> np.ndarray:
    """Cumulative integral of the samples ``f`` (m, ...) over ``t`` (m,), starting at 0."""
    if rule == "trapezoid":
        return integrate.cumulative_trapezoid(f, t, axis=0, initial=0)
    if rule == "simpson":
        if hasattr(integrate, "cumulative_simpson"):
            return integrate.cumulative_simpson(f, x=t, axis=0, initial=0)
        raise ArgumentError("Simpson integration needs scipy >= 1.12; use trapezoid")
    raise ArgumentError(f"unknown integration rule '{rule}'; use trapezoid or simpson")


def energy_system(
    base: BaseParameters, data: JointData, *, window: int = 1, integration: str = "simpson"
):
    """Energy model over non-overlapping windows of ``window`` sample intervals
    (:func:`windows`; none spans the join of two logs): ``W`` (r, nb) and ``y`` (r,),
    ``r = (m - 1) // window`` for a log not joined."""
    _args.instance(base, "base", BaseParameters)
    _args.instance(data, "data", JointData)
    check_units(data, base.robot, "data")  # a log built in Python: once
    window = _args.integer(window, "window", 1)
    _args.choice(integration, "integration", ("simpson", "trapezoid", "zoh"))
    require_torque(data)
    assert data.tau is not None
    if window < 1:
        raise ArgumentError(f"energy window must be at least 1 sample interval, got {window}")
    t, dq = data.t, data.dq
    a, b = windows(data, window, gaps=False)
    if a.size == 0:
        raise IdentificationError(
            f"{data.m} samples give no complete energy window of {window} intervals"
        )
    at = np.unique(np.concatenate([a, b]))  # the energy regressor only at window ends
    H = base.energy_regressor(data.q[at], dq[at])
    W = H[np.searchsorted(at, b)] - H[np.searchsorted(at, a)]
    power = np.einsum("ij,ij->i", dq, data.tau)
    v = base.robot.slot_velocities(dq)  # friction power of slot k: its friction torque times v_k
    cols = {c: v[:, k] * f for c, (k, f) in data_friction_columns(base, data).items()}
    F = np.column_stack([power] + list(cols.values())) if cols else power[:, None]
    cum = np.zeros_like(F)
    for p in data.log_slices():  # each joined log's integrals on its own samples
        if p.stop - p.start < 2:
            continue
        cum[p] = _cumulative(F[p], t[p], "simpson" if integration == "zoh" else integration)
        if integration == "zoh":
            # Torque held over each sample interval: int dq^T tau dt = sum tau_k^T (q_k+1 - q_k).
            held = np.einsum("ij,ij->i", np.diff(data.q[p], axis=0), data.tau[p][:-1])
            cum[p, 0] = np.concatenate([[0.0], np.cumsum(held)])
    dI = cum[b] - cum[a]
    y = dI[:, 0]
    # an offset's work Off_k (q_k(t_b) - q_k(t_a)) is exact in W: its energy column is q_k
    for j, c in enumerate(cols):
        W[:, c] = dI[:, j + 1]
    return W, y


def windows(data: JointData, window: int, *, gaps: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Sample indices ``(a, b)`` of the windows of the integral and energy models, ``b = a +
    window``.

    The log is split into continuous pieces at each join of logs (:attr:`JointData.starts`,
    :func:`~mindyn.identification.preprocess.concatenate`: a window across it would integrate
    two unrelated motions) and, with ``gaps`` (the integral model), at gaps (a sample interval
    longer than :data:`GAP_FACTOR` times the median one); each piece is covered by consecutive
    non-overlapping windows from its first sample (a window's last sample is the next one's
    first), the incomplete rest of a piece left out. No window spans a join or a gap."""
    if window < 1:
        raise ArgumentError(f"window must be at least 1 sample interval, got {window}")
    t = data.t
    first, last = [], []
    for piece in data.log_slices():
        f, e = piece.start, piece.stop - 1
        dt = np.diff(t[f : e + 1])
        cut = np.flatnonzero(dt > GAP_FACTOR * np.median(dt)) + f if gaps and dt.size else []
        first += [f, *(np.asarray(cut, dtype=int) + 1)]
        last += [*np.asarray(cut, dtype=int), e]
    starts = [np.arange(f, e - window + 1, window) for f, e in zip(first, last)]
    a = np.concatenate(starts).astype(int) if starts else np.zeros(0, dtype=int)
    return a, a + window


def _quadrature(t: np.ndarray, rule: str) -> np.ndarray:
    """Weights ``c`` with ``int f dt ~ c @ f(t)`` over the samples ``t`` of one window."""
    k = t.size
    if rule == "trapezoid":
        c = np.zeros(k)
        d = np.diff(t)
        c[:-1] += 0.5 * d
        c[1:] += 0.5 * d
        return c
    if rule == "simpson":
        return integrate.simpson(np.eye(k), x=t, axis=0)
    raise ArgumentError(f"unknown integration rule '{rule}'; use trapezoid, simpson or zoh")


def integral_system(
    base: BaseParameters, data: JointData, *, window: int = 40, integration: str = "simpson"
):
    """Integral model: ``W`` (w, n, nb), ``y`` (w, n) for ``w`` windows (:func:`windows`)
    (see :func:`integral_chunks`)."""
    _args.instance(base, "base", BaseParameters)
    _args.instance(data, "data", JointData)
    check_units(data, base.robot, "data")  # a log built in Python: once
    window = _args.integer(window, "window", 1)
    _args.choice(integration, "integration", ("simpson", "trapezoid", "zoh"))
    parts = list(integral_chunks(base, data, window=window, integration=integration))
    return np.concatenate([W for W, _ in parts]), np.concatenate([y for _, y in parts])


def integral_chunks(
    base: BaseParameters, data: JointData, *, window: int = 40, integration: str = "simpson"
):
    """The integral model's equations, :data:`CHUNK_SAMPLES` samples' worth of windows at a time:
    yields ``(W, y)``, shapes (k, n, nb) and (k, n), for consecutive runs of ``k`` windows.

    Joint ``j``, window ``[t_a, t_b]``:
    ``(W_p,j(t_b) - W_p,j(t_a) + int W_l,j dt) p_b + Fv_j (q_j(t_b) - q_j(t_a))
    + sum_i F_i,j int phi_i(dq_j) dt + Off_j (t_b - t_a) = int tau_j dt``, ``phi_i`` the friction
    columns of the robot's friction model after the viscous one (``Fc_j int sign(dq_j) dt``
    for Coulomb friction; :meth:`~mindyn.Robot.friction_shapes`; on the motor side, motor ``k``'s
    friction reaches joint ``j`` as ``T[k, j] (Fv_k t_k . (q(t_b) - q(t_a)) + sum_i F_i,k int
    phi_i(t_k . dq) dt)``), with the base momentum regressors
    ``p = W_p p_b``, ``-dL/dq + offsets = W_l p_b`` (:meth:`BaseParameters.momentum_regressors`:
    an offset's column of ``W_l`` is 1, its integral ``t_b - t_a``). The
    momentum is taken at the window's ends only; ``W_l``, the Coulomb term and the torque are
    integrated over the window's samples by Simpson's rule (``simpson``, exact for cubics; any
    number of intervals) or the trapezoid rule; ``zoh`` takes the logged torque as held over each
    sample interval (``int tau dt = sum tau_k (t_k+1 - t_k)``, exact for a command held by the
    drive) and integrates the rest by Simpson. The viscous term integrates exactly to the
    position difference, not through the (noisier) velocities. On preprocessed data the other
    friction columns are filtered like the torques (:func:`data_friction_columns`).

    Windows do not overlap (overlapping ones would repeat the same torque samples in several
    equations, correlating their errors without adding information); consecutive ones share
    their boundary sample, so noise at that sample enters both (with the momentum's sign
    opposite). On low-passed logs neighbouring windows also share the filtered torque noise
    near their common end: :func:`~mindyn.identification.estimation.correlation_factor` scales
    the variance of the estimates for it, as for the energy model's windows.

    Window length: the momentum at the two ends carries the velocity noise once per window
    (``A(q) delta dq``), while the torque integral's noise grows only as the square root of the
    window's length and its signal linearly; short windows therefore let velocity noise, an
    error in the regressor that least squares does not model, bias the estimate. The default of
    :func:`~mindyn.identification.identify` is 40 intervals (0.16 s at 250 Hz): on simulated
    6-joint log (ZCR07S, 20 s) with 0.005 rad/s velocity noise, 10 intervals left 14 % of the
    estimates outside three standard deviations and a validation error 16 % above that of the
    true parameters; 40 intervals, none outside and 2.5 % above.
    Longer windows give fewer equations (``n`` per window); a motion faster than the window
    is still integrated exactly up to the quadrature error."""
    require_torque(data)
    assert data.tau is not None
    a, b = windows(data, window)
    if a.size == 0:
        raise IdentificationError(
            f"{data.m} samples give no complete integral window of {window} intervals"
        )
    rule = "simpson" if integration == "zoh" else integration
    n, nb = data.n, base.n
    names = list(base.names)
    fv = {k: names.index(f"Fv{k + 1}") for k in range(n) if f"Fv{k + 1}" in names}
    shapes = {c: kf for c, kf in data_friction_columns(base, data).items() if c not in fv.values()}
    T = base.robot.drive_matrix
    per = max(1, CHUNK_SAMPLES // (window + 1))
    for c0 in range(0, a.size, per):
        wa, wb = a[c0 : c0 + per], b[c0 : c0 + per]
        idx = wa[:, None] + np.arange(window + 1)  # (k, window + 1) samples of each window
        Wp, Wl = base.momentum_regressors(data.q[idx.ravel()], data.dq[idx.ravel()])
        Wp = Wp.reshape(idx.shape + (n, nb))
        Wl = Wl.reshape(idx.shape + (n, nb))
        C = np.array([_quadrature(data.t[i], rule) for i in idx])  # (k, window + 1)
        # an offset's column of Wl is 1 in its joint's row: its integral is t_b - t_a
        W = Wp[:, -1] - Wp[:, 0] + np.einsum("ws,wsjp->wjp", C, Wl)
        tau = data.tau[idx]  # (k, window + 1, n)
        if integration == "zoh":
            y = np.einsum("ws,wsj->wj", np.diff(data.t[idx], axis=1), tau[:, :-1])
        else:
            y = np.einsum("ws,wsj->wj", C, tau)
        # Slot k's friction on joint j is T[k, j] (Fv_k v_k + Fc_k sign v_k), v = T dq: its
        # viscous integral T[k, j] Fv_k t_k . (q(t_b) - q(t_a)), exactly.
        dqw = data.q[wb] - data.q[wa]
        for k, col in fv.items():
            W[:, :, col] = np.outer(dqw @ T[k], T[k])
        for col, (k, f) in shapes.items():
            sk = np.einsum("ws,ws->w", C, f[idx])
            W[:, :, col] = np.outer(sk, T[k])
        yield W, y


def torque_noise(tau) -> np.ndarray:
    """Per-joint standard deviation of white noise on sampled torques, shape (n,), estimated
    from second differences (robust: median absolute deviation); the smooth part of a torque
    sampled much faster than it changes hardly contributes. ``tau`` (m, n), or a list of such
    logs: their second differences are pooled, none taken across the junction of two logs."""
    logs = tau if isinstance(tau, (list, tuple)) else [tau]
    d2 = np.vstack([np.diff(np.asarray(x), n=2, axis=0) for x in logs])
    mad = np.median(np.abs(d2 - np.median(d2, axis=0)), axis=0)
    return 1.4826 * mad / math.sqrt(6.0)


def logged_torques(data: JointData) -> list[np.ndarray]:
    """The torques whose white noise :func:`torque_noise` measures for the energy model's
    weights, one array per log joined (:meth:`JointData.log_slices`): on preprocessed data the
    torques as logged (``data.logged``), else ``data.tau``. The data path's low-pass leaves a
    fraction of the noise in ``data.tau``, and of that fraction's second differences little
    (at 250 Hz and a 5 Hz cut-off, 1e-3 of the logged noise, the torques' own curvature as
    much): per joint the level would be wrong by a factor that differs between joints."""
    src = data.logged if data.logged is not None and data.logged.tau is not None else data
    assert src.tau is not None
    return [src.tau[p] for p in src.log_slices()]


def _density_scale(data: JointData) -> list[float]:
    """Per log joined, the spectral density of the noise the windows integrate per unit
    variance of the noise :func:`torque_noise` measures on :func:`logged_torques`, over that of
    white noise on the samples of ``data``: ``fs / (P fs_logged)`` on preprocessed data (rate
    ``fs`` after decimation, ``fs_logged`` as logged, ``P`` periods averaged; the low-pass
    keeps the density at the frequencies of the motion), else 1."""
    pieces = data.log_slices()
    count = len(pieces)
    if data.logged is None:
        return [1.0] * count
    procs = data.processing.get("logs") or [data.processing]
    logged = data.logged.log_slices()
    whole = not len(procs) == len(logged) == count
    if whole:  # one scale for every log
        pieces, logged, procs = [slice(0, data.m)], [slice(0, data.logged.m)], procs[:1]
    out = []
    for p, lp, proc in zip(pieces, logged, procs):
        periods = ((proc.get("preprocess") or {}).get("averaging") or {}).get("periods", 1)
        t, lt = data.t[p], data.logged.t[lp]
        fs, fs_logged = (t.size - 1) / float(t[-1] - t[0]), (lt.size - 1) / float(lt[-1] - lt[0])
        out.append(fs / (periods * fs_logged))
    return out * count if whole else out


def energy_row_noise(data: JointData, window: int) -> np.ndarray:
    """Per window and joint, ``s sum_k (c_k dq_jk)^2`` with trapezoid weights ``c_k``: the
    variance of the window's power integral per unit variance of joint ``j``'s torque noise as
    logged (:func:`logged_torques`), over the energy model's windows (:func:`windows`); shape
    (rows, n). ``s`` is 1 on torques not low-passed; on preprocessed data the windows integrate
    the logged noise low-passed, whose spectral density at the frequencies of the motion is the
    logged one: ``s = fs / (P fs_logged)`` (decimated rate ``fs`` over the logged one, ``P``
    periods averaged). A row's noise variance is ``A @ sigma^2``."""
    dt = np.diff(data.t)
    scale = np.zeros(data.m)
    for p, s in zip(data.log_slices(), _density_scale(data)):
        scale[p] = s
    rows = []
    for a, b in zip(*windows(data, window, gaps=False)):
        c = np.zeros(b - a + 1)
        c[:-1] += 0.5 * dt[a:b]
        c[1:] += 0.5 * dt[a:b]
        rows.append(scale[a] * np.sum((c[:, None] * data.dq[a : b + 1]) ** 2, axis=0))
    return np.array(rows)


def require_torque(data: JointData) -> np.ndarray:
    """The torques of ``data``; a :class:`DataError` when it has none."""
    if data.tau is None:
        raise DataError(f"{data.source or 'data'}: no torque columns tau1..tau{data.n}")
    return data.tau
