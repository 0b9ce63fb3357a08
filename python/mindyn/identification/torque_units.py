"""The unit and sign of a log's torques, checked against the robot's description: torques in
mN m (1000 times too large) or of the opposite sign were identified without a word (inertias
1000 times too large, or negative). :func:`check_torque_units` is run where the other unit
checks of :mod:`~mindyn.identification.data` run, once per log."""

from __future__ import annotations

import numpy as np

from .data import EDGE_PERIODS, DataError, differentiate, filter_edge

# no public names: the readers and the checks of a JointData run it (as the other unit checks
# of the data module)
__all__: list[str] = []

#: A joint whose logged torque and the description's correlate at least this much (in
#: magnitude) is judged; the least-squares ratio of the two must lie within these bounds (a
#: description's generic inertials can be off by 2 to 3 times; mN m give 1000, a negated
#: column -1).
TORQUE_CHECK_CORRELATION = 0.9
TORQUE_RATIO_BOUNDS = (0.1, 10.0)
#: A joint whose description torque or logged torque varies (RMS about its mean) by at most
#: this fraction of the RMS of all joints' torques is not judged: its variation is round-off
VARIATION_FLOOR = 1e-9
#: At most this many evenly spaced samples are compared
TORQUE_CHECK_SAMPLES = 2000
#: Fewest samples for the comparison to judge (as the velocity check's)
TORQUE_CHECK_MIN_SAMPLES = 20
#: The low-pass [Hz] applied alike to the logged torques and the motion the description's
#: torques are computed on (at least 4 edge periods over the log's span)
TORQUE_CHECK_CUTOFF = 2.0
#: A ratio above the bounds is refused only where it is beyond doubt: the joint's torques peak
#: beyond this many times its effort limit, or, for a joint without one, the ratio exceeds this
#: (a description's placeholder friction or inertials can be far too small; mN m give 1000)
EFFORT_EXCEEDED = 2.0
UNLIMITED_RATIO = 100.0
#: Without a judged joint: torques whose peak exceeds this many times the effort limit on most
#: joints that have one are refused
EFFORT_FACTOR = 20.0


def _description_ratios(t, q, dq, tau, robot):
    """Per joint, the correlation of the logged torques with the description's inverse dynamics
    (gravity, inertia, velocity terms, its rotor inertia and friction) on the logged motion, and
    the slope of the least-squares line ``tau ~ k tau_desc + c`` (an offset allowed: logged
    torques often carry one); None when the description carries no masses. Both signals are
    low-passed alike and the accelerations are the derivative of the low-passed velocities."""
    if not np.any(np.asarray(robot.params)[9::10] != 0):
        return None
    m = t.size
    span = float(t[-1] - t[0])
    rate = (m - 1) / span
    fc = max(TORQUE_CHECK_CUTOFF, 4.0 * EDGE_PERIODS / span)
    x = np.hstack([q, dq, tau])
    n = q.shape[1]
    got = None
    with np.errstate(all="ignore"):
        if fc < rate / 4:
            try:
                xf, dx, info = differentiate(t, x, filter="butter", cutoff=fc)
                got = (xf, dx, filter_edge(info))
            except (DataError, ValueError, np.linalg.LinAlgError):
                got = None
        # a log too slow or too short to low-pass: its signals as they are
        xf, dx, edge = got if got is not None else (x, np.gradient(x, t, axis=0), 0)
    if m - 2 * edge < TORQUE_CHECK_MIN_SAMPLES:
        return None
    idx = np.unique(np.linspace(edge, m - edge - 1, min(TORQUE_CHECK_SAMPLES, m - 2 * edge)))
    idx = idx.astype(int)
    qf, dqf, ddqf, tf = xf[idx, :n], xf[idx, n : 2 * n], dx[idx, n : 2 * n], xf[idx, 2 * n :]
    if not (np.isfinite(qf).all() and np.isfinite(dqf).all() and np.isfinite(ddqf).all()):
        return None
    try:
        desc = robot.inverse_dynamics(qf, dqf, ddqf, robot.parameters(rotor=True, friction=True))
    except (ValueError, ArithmeticError):
        return None
    with np.errstate(all="ignore"):
        d0, m0 = desc - desc.mean(axis=0), tf - tf.mean(axis=0)
        corr = (d0 * m0).sum(axis=0) / np.sqrt((d0**2).sum(axis=0) * (m0**2).sum(axis=0))
        k = (d0 * m0).sum(axis=0) / (d0**2).sum(axis=0)
        # a signal that does not vary beyond the round-off of the torques' scale (a joint whose
        # gravity torque is zero held still, a constant logged torque) has no shape to compare:
        # its correlation and ratio are those of the round-off
        flat = (np.sqrt((d0**2).mean(axis=0)) <= VARIATION_FLOOR * np.sqrt((desc**2).mean())) | (
            np.sqrt((m0**2).mean(axis=0)) <= VARIATION_FLOOR * np.sqrt((tf**2).mean())
        )
    corr, k = np.where(flat, np.nan, corr), np.where(flat, np.nan, k)
    return corr, k


def _causes(k: float) -> str:
    if k < 0:
        return (
            "the torque column negated, a drive whose sign convention is opposite to the joint's "
            "axis, or a description whose gravity is not the robot's (mounted upside down)"
        )
    if k > 1:
        return (
            "torques in mN m (1000) or in another unit (per mille or percent of the rated torque)"
        )
    return "torques in another unit (kN m, motor currents in A read as N m, a share of a torque)"


def check_torque_units(t, q, dq, tau, robot, source: str, remedy: str) -> None:
    """Refuses logged torques ``tau`` (samples x joints, in N m as read) that are in another
    unit or of the opposite sign, named ``source``, the message ending with ``remedy``.

    With the description's inertial parameters (some link mass non-zero): per joint whose
    logged torques and the description's inverse dynamics on the logged motion (at most
    :data:`TORQUE_CHECK_SAMPLES` evenly spaced samples; both low-passed alike at
    :data:`TORQUE_CHECK_CUTOFF` Hz, accelerations from the low-passed velocities ``dq``)
    correlate at least :data:`TORQUE_CHECK_CORRELATION` in magnitude, the slope ``k`` of the
    least-squares line ``tau ~ k tau_desc + offset`` must lie within
    :data:`TORQUE_RATIO_BOUNDS` (mN m: 1000, a negated column: -1; real logs: 0.7 to 1.4); a
    ratio above them is refused only where the joint's torques peak beyond
    :data:`EFFORT_EXCEEDED` times its effort limit or, without a limit, the ratio exceeds
    :data:`UNLIMITED_RATIO` (a description's placeholder friction or inertials can be far too
    small; that is not a wrong unit). Joints dominated by
    friction or with little gravity do not correlate and are not judged. When no joint is
    judged (no masses, none correlating): torques whose peak exceeds :data:`EFFORT_FACTOR`
    times the effort limit on most joints that have one are refused. Robots with joints of
    several degrees of freedom are not checked."""
    from ..robot import Robot

    if tau is None or not isinstance(robot, Robot) or not robot.single_dof:
        return
    t, q, dq, tau = (np.asarray(a, dtype=float) for a in (t, q, dq, tau))
    n = robot.n
    if t.ndim != 1 or t.size < TORQUE_CHECK_MIN_SAMPLES or t[-1] <= t[0]:
        return
    if any(a.shape != (t.size, n) for a in (q, dq, tau)):
        return
    with np.errstate(all="ignore"):
        peak = np.max(np.abs(tau), axis=0)
    effort = np.asarray(robot.limits["effort"], dtype=float)
    limited = np.isfinite(effort) & (effort > 0)
    got = _description_ratios(t, q, dq, tau, robot)
    judged = np.zeros(n, dtype=bool)
    if got is not None:
        corr, k = got
        judged = np.isfinite(corr) & np.isfinite(k) & (np.abs(corr) >= TORQUE_CHECK_CORRELATION)
        low, high = TORQUE_RATIO_BOUNDS
        beyond = np.where(
            limited, peak > EFFORT_EXCEEDED * np.where(limited, effort, 0.0), k > UNLIMITED_RATIO
        )
        bad = [j for j in np.flatnonzero(judged) if k[j] < low or (k[j] > high and beyond[j])]
        if bad:
            j = bad[0]
            others = [b + 1 for b in bad[1:]]
            also = f"; joint(s) {', '.join(map(str, others))} alike" if others else ""
            raise DataError(
                f"{source}: the torques of joint {j + 1} ('{robot.joint_names[j]}') are "
                f"{k[j]:.4g} times the description's inverse dynamics on the logged motion "
                f"(correlation {corr[j]:.3f}; expected about 1, from {low:g} to {high:g} for an "
                f"approximate description{also}): {_causes(float(k[j]))}; {remedy}"
            )
    if judged.any() or not limited.any():
        return
    far = limited & (peak > EFFORT_FACTOR * np.where(limited, effort, np.inf))
    if 2 * int(far.sum()) <= int(limited.sum()):
        return
    j = int(np.flatnonzero(far)[0])
    raise DataError(
        f"{source}: the torques of {int(far.sum())} of the {int(limited.sum())} joints with an "
        f"effort limit peak beyond {EFFORT_FACTOR:g} times it (joint {j + 1} "
        f"('{robot.joint_names[j]}'): {peak[j]:.4g} for a limit of {effort[j]:.4g}): "
        f"{_causes(peak[j] / effort[j])}; {remedy}"
    )


#: How a CSV log (read by ``read_csv``, ``identify``) states its torques' unit
CSV_TORQUE_REMEDY = (
    "give the torques in N m (N), positive along each joint's axis: convert the columns, or state "
    "their unit (torque_unit='permille' or 'current' with drive_gain=, a negative gain for a "
    "reversed drive; tau1[permille] or i1 in the header, tau[permille] or i in a column map); "
    "torques right as they are (a description far from the robot) are taken when their unit is "
    "stated as N m (torque_unit='Nm', tau1[Nm] in the header)"
)
#: How a ROS bag's efforts are given
BAG_TORQUE_REMEDY = (
    "record the efforts in N m (N), positive along each joint's axis, or state their unit "
    "(torque_unit='permille' or 'current' with drive_gain=, a negative gain for a reversed drive)"
)
#: How torques from a currents file are formed
CURRENTS_TORQUE_REMEDY = (
    "the currents are in A and times the drive gains give N m (N) along each joint's axis: check "
    "the gains (drive_gain=, a negative gain for a reversed drive)"
)
#: How a JointData built in Python gives its torques
JOINT_DATA_TORQUE_REMEDY = (
    "JointData.tau is in N m (N), positive along each joint's axis: convert it, or give "
    "JointData(..., units_checked=True) for torques that are right as they are"
)
