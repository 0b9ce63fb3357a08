"""Identification of a 6R arm with a coupled wrist: ``mindyn identify`` against a careful
least-squares script that models the coupling, and against mindyn without the transmissions.

The arm is Stäubli-TX90-like (published kinematics order: shoulder height 0.478 m, shoulder
offset 0.05 m, upper arm 0.425 m, elbow offset 0.05 m, forearm 0.425 m, flange 0.1 m; axes z y y
z y z; link masses 28 / 22 / 10 / 6 / 2 / 2 kg with a tool, inertias of boxes of the links'
size, centres of mass off the axes and inertia frames turned, so that products of inertia
appear). Its wrist is coupled as in the Stäubli arms: motor 6 sits in the forearm and drives
joint 6 through joint 5's axis (bevel gears), so when joint 5 turns with motor 6 held, joint 6
turns with it relative to link 5. The motor positions are

    q_m5 = r5 q5,        q_m6 = r6 (q6 + c q5)      (c = 1 here: motor 6 turns with q5 + q6)

and motor 6's rotor inertia and friction act on joints 5 and 6 both: tau += T^T (J_m T ddq +
f(T dq)). The description writes this as a real integrator would, with ros_control's
``FourBarLinkageTransmission`` on joints 5 and 6, whose documented joint -> actuator map is

    x_a1 = n_a1 n_j1 x_j1,     x_a2 = n_a2 (x_j1 + n_j2 x_j2)

(actuator reductions n_a1 = r5, n_a2 = r6 c, joint reductions n_j1 = 1, n_j2 = 1 / c: with
c = 1 simply n_a = (r5, r6), n_j = (1, 1)), and ``SimpleTransmission`` (x_a = n_a x_j) on joints
1-4. Both forms are written: ROS 1 (``<type>``, ``<role>``, ``<mechanicalReduction>``) and ROS 2
(inside ``<ros2_control>``, ``<plugin>``, ``role=``, ``<mechanical_reduction>``); the ROS 2 form
is identified on the first case and must give the ROS 1 form's figures.

The logs are simulated to stress the tool as a real controller log does:

- fit: a 5-harmonic Fourier excitation (0.1 Hz, 30 s); validation on two other motions (20 s
  each, both given to one ``--validate``): another Fourier excitation (4 harmonics, 0.12 Hz)
  and point-to-point quintic moves between random configurations with dwells;
- 250 Hz controller with sampling jitter (standard deviation 40 us); the stamps are the sample
  instants; positions from motor encoders (2^16 counts per motor turn) mapped through T^-1,
  velocities the controller's backward difference of them over the nominal period (so jitter
  and quantisation make their noise, as an encoder-differentiated velocity's);
- motor-side friction that is not the model's: Coulomb with a Stribeck hump (+50 % at rest,
  Stribeck speed 15 rad/s on the motor), smoothed through zero (tanh, 0.5 rad/s), viscous, and a
  position ripple of 6 % of the Coulomb level once per motor turn; rotor inertias of industrial
  motors (reflected J_m r^2 of the wrist motors 0.02-0.08 kg m^2, above the wrist links');
- motor currents i = tau_m / K_t + offset + white noise (``--noise`` levels, fractions of each
  motor's RMS current) and the logged torques T^T (K_t,nominal i), the nominal torque constants
  off the true ones by up to ``--gain-error`` (3 %) per axis.

Each case (seed, noise level) runs:

1. ``mindyn identify ARM.urdf FIT.csv --validate FOURIER.csv PTP.csv --rotor --friction
   --offset --json OUT.json`` (defaults otherwise) on the URDF with transmissions (torques in
   N m), and on the logs of currents (``i1..i6``) with ``--drive-gain`` the nominal K_t (the
   same figures expected); on the first case also the ROS 2 form (the same figures expected);
2. the same on the URDF without transmissions (joint-side rotor inertia and friction), and on
   the URDF with transmissions with ``--rsd-threshold 0`` (every base parameter kept, as the
   script keeps them: the row ``all kept`` shows what the default pruning costs or gains);
3. the careful script (this file, independent of mindyn: numpy, scipy, Pinocchio): linear
   resampling of the jittered stamps onto a uniform grid, zero-phase Butterworth (order 4) of
   positions, velocities and torques at mindyn's reported cut-off (so that the filtered
   measure is the same one), accelerations by differentiating the filtered velocity,
   Pinocchio's ``computeJointTorqueRegressor`` plus per-motor columns T^T e_k (e_k^T T ddq),
   T^T e_k (e_k^T T dq), T^T e_k sign(e_k^T T dq) and an offset per joint, the regressor
   filtered as the torques (parallel filtering), two periods of the cut-off dropped at each
   end, equations of joints slower than 0.01 rad/s left out of the fit (as mindyn's default),
   columns scaled to unit norm, the independent set by QR with column pivoting (tolerance
   1e-9 of the largest pivot), then weighted least squares with per-joint noise from the
   ordinary fit's residuals (reweighted twice).

Measures (as the JSON's, per validation log: ``validation.logs[k]``): the overall relative
error |tau - tau_hat| / |tau| against the low-pass filtered torques (``overall_relative``; the
script: its prediction against the torques it filtered, at the same cut-off, edges dropped) and
against the torques as logged (``raw.overall_relative``; the script: its prediction
at the logged samples: its smooth part interpolated, the Coulomb signs from the velocity there).
The table gives fit and both validations for the four
runs, the ratio mindyn coupled / script on validation (target <= 1.05, the acceptance figure of
the real-log test, whose careful script got 9.35 % and a joint-side model 15.3 %) and the
per-joint validation errors (filtered) of mindyn coupled, the script and mindyn joint-side,
joint 5 especially. The point-to-point log's error is dominated, for every model, by the
Coulomb step where a move starts or stops (the low-pass smears it over about 1 / cut-off).

Measured (seeds 0 1 2, current noise 1 % and 4 %), pruning at RSD > 70.7 % (``--rsd-threshold
70.7``, the default before ``auto``; on standard deviations that count the low-passed noise's
correlation): mindyn with the
transmissions against the script on the Fourier validation log 0.96 to 1.06 (filtered; raw
0.98 to 1.05), above 1.05 on seed 1 only (1.059 and 1.052 filtered), on the point-to-point log
1.00 to 1.02; every base parameter kept (``--rsd-threshold 0``), 1.00 to 1.03 on both; with the
ZCR07S study's RSD > 30 % on those standard deviations, 0.92 to 1.00 (which pruned too much on
the Panda's real log, see docs/benchmarks.md). The joint-side model: 4.6 to 8.0 % against 4.0 to
5.6 % on the Fourier log, joint 5 30 to 50 % against 10 to 17 %, joint 6 90 to 114 % against 9
to 14 %. The ROS 2 form and the current logs with ``--drive-gain`` give the ROS 1 form's
figures; a four-bar of ratio c = 0.75 (``--coupling 0.75``) is read as the script's T.

With the default ``--rsd-threshold auto`` (the pruning decided on held-out blocks of the fit
log; each case prints the decision): every base parameter kept on seeds 0 and 1, the pruning on
seed 2; 0.96 to 1.03 on the Fourier log, 1.00 on the point-to-point log.

Run: ``.venv/bin/python bench/bench_coupled_wrist.py [--seeds 0 1] [--noise 0.01 0.04]
[--gain-error 0.03] [--coupling C] [--keep DIR] [--rsd-threshold PERCENT]`` (with the defaults,
4 cases: 28 s on an idle 2-core machine, up to 4 minutes when it is shared).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pinocchio as pin
from scipy import signal
from scipy.linalg import qr

RATE = 250.0  # Hz, the controller's
JITTER = 40e-6  # s, standard deviation of the sample instants
COUNTS = 2**16  # encoder counts per motor turn
R = np.array([-120.0, 150.0, -100.0, 70.0, 60.0, 45.0])  # reductions (sign: motor direction)
COUPLING = 1.0  # c: q_m6 = r6 (q6 + c q5)
JM = np.array([2.5e-4, 2.5e-4, 1.2e-4, 4.0e-5, 1.5e-5, 1.2e-5])  # rotor inertia [kg m^2]
FC = np.array([0.20, 0.25, 0.15, 0.06, 0.05, 0.04])  # Coulomb [N m] at the motor
FV = np.array([6e-4, 6e-4, 4e-4, 1.5e-4, 1.2e-4, 1.2e-4])  # viscous [N m s/rad] at the motor
KT = np.array([1.1, 1.1, 0.8, 0.5, 0.4, 0.4])  # torque constants [N m/A]
I_OFF = np.array([0.03, -0.05, 0.04, 0.02, -0.03, 0.025])  # current offsets [A]
STRIBECK = 0.5  # the hump at rest over the Coulomb level
V_STRIBECK = 15.0  # rad/s at the motor
V_SMOOTH = 0.5  # rad/s at the motor: the friction's slope through zero
RIPPLE = 0.06  # of the Coulomb level, once per motor turn

# (name, parent xyz, axis, mass, com, box size (x, y, z) for the inertia, inertia frame rpy)
LINKS = [
    ("shoulder", "0 0 0.478", "0 0 1", 28.0, (0.02, 0.0, -0.08), (0.30, 0.30, 0.35), (0.1, 0, 0)),
    ("arm", "0.05 0 0", "0 1 0", 22.0, (0.0, 0.12, 0.2), (0.16, 0.2, 0.55), (0, 0.05, 0)),
    ("elbow", "0 0.05 0.425", "0 1 0", 10.0, (0.0, -0.03, 0.06), (0.16, 0.18, 0.22), (0, 0, 0.2)),
    ("forearm", "0 0 0.2", "0 0 1", 6.0, (0.0, 0.01, 0.12), (0.12, 0.12, 0.3), (0.05, 0, 0)),
    ("wrist", "0 0 0.225", "0 1 0", 2.0, (0.0, 0.0, 0.03), (0.08, 0.1, 0.1), (0, 0, 0.1)),
    ("flange", "0 0 0.1", "0 0 1", 2.0, (0.01, 0.0, 0.06), (0.1, 0.1, 0.12), (0.1, 0.1, 0)),
]
LIMITS = [(-3.1, 3.1, 318), (-2.2, 2.5, 166), (-2.5, 2.5, 76), (-4.7, 4.7, 34), (-2.0, 2.4, 29),
          (-4.7, 4.7, 11)]  # fmt: skip
PREFIX = "transmission_interface/"


def transmission_matrix() -> np.ndarray:
    """T of q_m = T q: simple transmissions and the coupled wrist."""
    T = np.diag(R)
    T[5, 4] = R[5] * COUPLING
    return T


def urdf_text(form: str | None) -> str:
    """The arm's URDF; form "ros1", "ros2" or None (no transmissions)."""
    parts = ["<robot name='tx90_like'><link name='base_link'/>"]
    parent = "base_link"
    for k, (name, xyz, axis, m, com, box, rpy) in enumerate(LINKS, start=1):
        x, y, z = box
        ixx, iyy, izz = m * (y * y + z * z) / 12, m * (x * x + z * z) / 12, m * (x * x + y * y) / 12
        parts.append(
            f"<link name='{name}'><inertial><origin xyz='{com[0]} {com[1]} {com[2]}' "
            f"rpy='{rpy[0]} {rpy[1]} {rpy[2]}'/><mass value='{m}'/><inertia ixx='{ixx:.6g}' "
            f"ixy='0' ixz='0' iyy='{iyy:.6g}' iyz='0' izz='{izz:.6g}'/></inertial></link>"
        )
        lo, hi, eff = LIMITS[k - 1]
        parts.append(
            f"<joint name='joint_{k}' type='revolute'><parent link='{parent}'/>"
            f"<child link='{name}'/><origin xyz='{xyz}' rpy='0 0 0'/><axis xyz='{axis}'/>"
            f"<limit lower='{lo}' upper='{hi}' effort='{eff}' velocity='3'/></joint>"
        )
        parent = name
    if form is not None:
        tr = "".join(_simple(k, form) for k in range(1, 5)) + _four_bar(form)
        if form == "ros2":
            tr = (
                "<ros2_control name='tx90' type='system'><hardware><plugin>cs8/Hardware</plugin>"
                f"</hardware>{tr}</ros2_control>"
            )
        parts.append(tr)
    parts.append("</robot>")
    return "\n".join(parts)


def _simple(k: int, form: str) -> str:
    if form == "ros2":
        return (
            f"<transmission name='trans_{k}'><plugin>{PREFIX}SimpleTransmission</plugin>"
            f"<actuator name='motor_{k}' role='actuator1'/><joint name='joint_{k}' "
            f"role='joint1'><mechanical_reduction>{R[k - 1]}</mechanical_reduction></joint>"
            "</transmission>"
        )
    return (
        f"<transmission name='trans_{k}'><type>{PREFIX}SimpleTransmission</type>"
        f"<joint name='joint_{k}'><hardwareInterface>hardware_interface/EffortJointInterface"
        f"</hardwareInterface></joint><actuator name='motor_{k}'>"
        f"<mechanicalReduction>{R[k - 1]}</mechanicalReduction></actuator></transmission>"
    )


def _four_bar(form: str) -> str:
    """Joints 5-6: actuator reductions (r5, r6 c), joint reductions (1, 1 / c)."""
    act, jnt = (R[4], R[5] * COUPLING), (1.0, 1.0 / COUPLING)
    kind = f"{PREFIX}FourBarLinkageTransmission"
    if form == "ros2":
        red = "mechanical_reduction"
        body = "".join(
            f"<actuator name='motor_{5 + r}' role='actuator{r + 1}'><{red}>{act[r]}</{red}>"
            "</actuator>"
            for r in range(2)
        ) + "".join(
            f"<joint name='joint_{5 + r}' role='joint{r + 1}'><{red}>{jnt[r]}</{red}></joint>"
            for r in range(2)
        )
        return f"<transmission name='wrist'><plugin>{kind}</plugin>{body}</transmission>"
    red = "mechanicalReduction"
    body = "".join(
        f"<actuator name='motor_{5 + r}'><role>actuator{r + 1}</role><{red}>{act[r]}</{red}>"
        "</actuator>"
        for r in range(2)
    ) + "".join(
        f"<joint name='joint_{5 + r}'><role>joint{r + 1}</role><{red}>{jnt[r]}</{red}>"
        "<hardwareInterface>hardware_interface/EffortJointInterface</hardwareInterface></joint>"
        for r in range(2)
    )
    return f"<transmission name='wrist'><type>{kind}</type>{body}</transmission>"


# ---- motions ---------------------------------------------------------------------------------


def fourier(rng, t, harmonics=5, f0=0.1):
    """q, dq, ddq of a Fourier excitation (zero velocity at the start), scaled to 60 % of each
    joint's range about its middle and to a peak speed of 1.6 rad/s."""
    n = len(LIMITS)
    q, dq, ddq = (np.zeros((t.size, n)) for _ in range(3))
    for j, (lo, hi, _) in enumerate(LIMITS):
        a, b = rng.normal(size=(2, harmonics))
        w = 2 * np.pi * f0 * np.arange(1, harmonics + 1)
        s, c = np.sin(np.outer(t, w)), np.cos(np.outer(t, w))
        p = (a / w) @ s.T - (b / w) @ (c.T - 1)
        v = a @ c.T + b @ s.T
        acc = (-a * w) @ s.T + (b * w) @ c.T
        k = min(0.3 * (hi - lo) / np.abs(p).max(), 1.6 / np.abs(v).max())
        mid = 0.5 * (lo + hi)
        q[:, j], dq[:, j], ddq[:, j] = mid + k * p, k * v, k * acc
    return q, dq, ddq


def point_to_point(rng, t):
    """Quintic moves between random configurations (1-2.5 s each, all joints together) with
    dwells of 0.2-0.8 s."""
    lo = np.array([x[0] for x in LIMITS]) * 0.6
    hi = np.array([x[1] for x in LIMITS]) * 0.6
    n = lo.size
    q, dq, ddq = (np.zeros((t.size, n)) for _ in range(3))
    start, p0 = 0.0, 0.5 * (lo + hi)
    q[:] = p0
    while start < t[-1]:
        p1 = rng.uniform(lo, hi)
        dur = rng.uniform(1.0, 2.5)
        dur = max(dur, 1.875 * np.abs(p1 - p0).max() / 1.6)  # peak speed <= 1.6 rad/s
        sel = (t >= start) & (t < start + dur)
        s = (t[sel] - start) / dur
        d = p1 - p0
        q[sel] = p0 + np.outer(10 * s**3 - 15 * s**4 + 6 * s**5, d)
        dq[sel] = np.outer((30 * s**2 - 60 * s**3 + 30 * s**4) / dur, d)
        ddq[sel] = np.outer((60 * s - 180 * s**2 + 120 * s**3) / dur**2, d)
        after = t >= start + dur
        q[after], dq[after], ddq[after] = p1, 0.0, 0.0
        start, p0 = start + dur + rng.uniform(0.2, 0.8), p1
    return q, dq, ddq


# ---- the plant -------------------------------------------------------------------------------


def motor_friction(vm, qm):
    """Stribeck + viscous + position ripple, smoothed through zero: not the model's form."""
    sgn = np.tanh(vm / V_SMOOTH)
    hump = 1.0 + STRIBECK * np.exp(-((vm / V_STRIBECK) ** 2))
    ripple = RIPPLE * FC * np.sin(qm + 0.7) * np.abs(sgn)
    return FC * hump * sgn + FV * vm + ripple


def simulate(model, kind, seed, duration, noise, gain):
    """One log: (t, q, dq, tau [N m], currents [A]) as the controller records them."""
    rng = np.random.default_rng(seed)
    m = int(duration * RATE)
    t = np.arange(m) / RATE + rng.normal(0, JITTER, m)
    t[0] = 0.0
    t = np.sort(t)
    if kind == "fit":
        q, dq, ddq = fourier(rng, t)
    elif kind == "fourier":  # another excitation: fewer, slower harmonics
        q, dq, ddq = fourier(rng, t, harmonics=4, f0=0.12)
    else:
        q, dq, ddq = point_to_point(rng, t)
    T = transmission_matrix()
    data = model.createData()
    tau_links = np.array([pin.rnea(model, data, q[i], dq[i], ddq[i]) for i in range(m)])
    qm, vm, am = q @ T.T, dq @ T.T, ddq @ T.T
    tau_m = np.linalg.solve(T.T, tau_links.T).T + JM * am + motor_friction(vm, qm)
    current = tau_m / KT + I_OFF
    current += rng.normal(0, 1, current.shape) * noise * np.sqrt(np.mean(current**2, axis=0))
    # encoders on the motors; the controller's joint positions and velocities from them
    qm_enc = np.round(qm / (2 * np.pi) * COUNTS) * (2 * np.pi) / COUNTS
    q_log = np.linalg.solve(T, qm_enc.T).T
    dq_log = np.vstack([np.zeros(6), np.diff(q_log, axis=0) * RATE])
    tau_log = (current * KT * gain) @ T  # T^T (K_t,nominal i), row by row
    return t, q_log, dq_log, tau_log, current


def write_log(path, t, q, dq, cols, name):
    n = q.shape[1]
    head = ["t"] + [f"q{j}" for j in range(1, n + 1)] + [f"dq{j}" for j in range(1, n + 1)]
    head += [f"{name}{j}" for j in range(1, n + 1)]
    np.savetxt(path, np.column_stack([t, q, dq, cols]), delimiter=",", header=",".join(head),
               comments="", fmt="%.9g")  # fmt: skip


# ---- the careful script ----------------------------------------------------------------------


class Script:
    """Least squares with the coupled motor terms, written from the textbook (see module
    docstring); independent of mindyn."""

    MIN_VELOCITY = 0.01  # rad/s: joint equations slower than this are left out

    def __init__(self, model, T, cutoff):
        self.model, self.data, self.T, self.cutoff = model, model.createData(), T, cutoff
        self.edge = 2.0 / cutoff  # s dropped at each end after filtering

    def prepare(self, t, q, dq, tau):
        """Uniform grid, filters, regressor; returns the filtered regressor and torques and
        the moving mask on the kept samples, what :meth:`predict_raw` needs, and the logged
        torques at the kept logged samples."""
        dt = np.median(np.diff(t))
        grid = np.arange(t[0], t[-1], dt)
        res = [np.column_stack([np.interp(grid, t, x[:, j]) for j in range(x.shape[1])])
               for x in (q, dq, tau)]  # fmt: skip
        sos = signal.butter(4, self.cutoff, fs=1 / dt, output="sos")

        def filt(x):
            return signal.sosfiltfilt(sos, x, axis=0)

        qf, dqf, tauf = (filt(x) for x in res)
        ddqf = np.gradient(dqf, dt, axis=0)
        W = self.regressor(qf, dqf, ddqf)
        Wf = filt(W.reshape(W.shape[0], -1)).reshape(W.shape)  # parallel filtering
        keep = (grid >= grid[0] + self.edge) & (grid <= grid[-1] - self.edge)
        moving = np.abs(dqf[keep]) >= self.MIN_VELOCITY
        # raw: the model on the filtered motion, interpolated to the logged samples, against
        # the logged torques
        lk = (t >= grid[0] + self.edge) & (t <= grid[-1] - self.edge)
        dq_at = np.column_stack([np.interp(t[lk], grid, x) for x in dqf.T])
        return Wf[keep], tauf[keep], moving, (grid, W, t[lk], dq_at), tau[lk]

    def predict_raw(self, raw):
        """The prediction at the logged stamps: its smooth part interpolated from the grid,
        the Coulomb terms from the motors' velocity there (a sign is not interpolated)."""
        grid, W, t, dq = raw
        n = dq.shape[1]
        coulomb = 10 * n + 3 * np.arange(n) + 2
        smooth = W.copy()
        smooth[:, :, coulomb] = 0.0
        hat = self.predict(smooth)
        hat = np.column_stack([np.interp(t, grid, hat[:, j]) for j in range(n)])
        signs = np.zeros((t.size, n, W.shape[2]))
        signs[:, :, coulomb] = self.regressor_coulomb(dq)
        return hat + self.predict(signs)

    def regressor_coulomb(self, dq):
        """The Coulomb columns of :meth:`regressor`, (m, n, n)."""
        sgn = np.sign(dq @ self.T.T)
        return np.einsum("mk,kj->mjk", sgn, self.T)

    def regressor(self, q, dq, ddq):
        m, n = q.shape
        T = self.T
        W = np.zeros((m, n, 10 * n + 3 * n + n))
        vm, am = dq @ T.T, ddq @ T.T
        sgn = np.sign(vm)
        for i in range(m):
            W[i, :, : 10 * n] = pin.computeJointTorqueRegressor(
                self.model, self.data, q[i], dq[i], ddq[i]
            )
        for k in range(n):
            col = T[k]  # T^T e_k
            W[:, :, 10 * n + 3 * k] = np.outer(am[:, k], col)
            W[:, :, 10 * n + 3 * k + 1] = np.outer(vm[:, k], col)
            W[:, :, 10 * n + 3 * k + 2] = np.outer(sgn[:, k], col)
        W[:, :, 13 * n :] = np.eye(n)
        return W

    def fit(self, W, y, mask):
        n = y.shape[1]
        A = W.reshape(-1, W.shape[2])
        b = y.reshape(-1)
        rows = mask.reshape(-1)
        A, b, joint = A[rows], b[rows], np.tile(np.arange(n), y.shape[0])[rows]
        scale = np.linalg.norm(A, axis=0)
        scale[scale == 0] = 1.0
        _, Rr, piv = qr(A / scale, mode="economic", pivoting=True)
        d = np.abs(np.diag(Rr))
        self.cols = np.sort(piv[: int(np.sum(d > 1e-9 * d[0]))])
        As = A[:, self.cols] / scale[self.cols]
        w = np.ones(b.size)
        for _ in range(3):  # ordinary, then twice reweighted per joint
            x, *_ = np.linalg.lstsq(As * w[:, None], b * w, rcond=None)
            r = b - As @ x
            sigma = np.array(
                [np.sqrt(np.mean(r[joint == j] ** 2)) for j in range(n)]
            )  # per-joint noise
            w = 1.0 / np.maximum(sigma[joint], 1e-12 * sigma.max())
        self.p = x / scale[self.cols]
        return self

    def predict(self, W):
        return W[:, :, self.cols] @ self.p


def overall(tau, hat):
    return float(np.linalg.norm(tau - hat) / np.linalg.norm(tau))


def per_joint(tau, hat):
    return np.linalg.norm(tau - hat, axis=0) / np.linalg.norm(tau, axis=0)


# ---- the cases -------------------------------------------------------------------------------


#: Flags of every mindyn run before its own (``--rsd-threshold``: the last given counts).
DEFAULT_FLAGS: list[str] = []


def run_mindyn(urdf, fit, val, tmp, tag, extra=()):
    out = tmp / f"{tag}.json"
    cmd = [sys.executable, "-m", "mindyn", "identify", str(urdf), str(fit), "--validate"]
    cmd += [*map(str, val), "--rotor", "--friction", "--offset", "--json", str(out)]
    cmd += [*DEFAULT_FLAGS, *extra]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"{tag}: mindyn failed: {proc.stderr.strip() or proc.stdout[-400:]}")
    doc = json.loads(out.read_text())
    return doc


VALIDATIONS = ("fourier", "ptp")


def _threshold_words(threshold) -> str:
    return "all kept" if threshold is None else f"RSD > {threshold:g} %"


def pruning_said(doc):
    """The fit's pruning (``settings.pruning_choice`` with ``--rsd-threshold auto``: the
    candidates' held-out residuals) in one line."""
    c = doc["settings"].get("pruning_choice")
    if not c:
        thr = doc["settings"].get("rsd_threshold")
        return f"  pruning: {_threshold_words(thr)} (given), {len(doc['removed'])} removed"
    held = ", ".join(
        f"{_threshold_words(d['rsd_threshold'])} {d['held_out']:.5g} (se {d['standard_error']:.2g})"
        for d in c.get("candidates", [])
    )
    return (
        f"  pruning: {_threshold_words(c.get('rsd_threshold'))} "
        f"({c.get('chosen_by')}{'; held-out ' + held if held else ''}), "
        f"{len(doc['removed'])} removed"
    )


def figures(doc):
    """Fit and per-validation-log measures of a JSON."""
    f = doc["fit"]
    out = {"fit": f["overall_relative"], "fit_raw": f["raw"]["overall_relative"]}
    for kind, v in zip(VALIDATIONS, doc["validation"]["logs"], strict=True):
        out[kind] = {
            "val": v["overall_relative"],
            "val_raw": v["raw"]["overall_relative"],
            "joints": np.asarray(v["relative"]),
        }
    return out


def case(seed, noise, gain_error, tmp, ros2_check):
    rng = np.random.default_rng(1000 + seed)
    gain = 1.0 + rng.uniform(-gain_error, gain_error, 6)
    urdfs = {form: tmp / f"arm_{form}.urdf" for form in ("ros1", "ros2", "plain")}
    for form, path in urdfs.items():
        path.write_text(urdf_text(None if form == "plain" else form))
    model = pin.buildModelFromUrdf(str(urdfs["plain"]))
    logs = {}
    for k, (kind, dur) in enumerate((("fit", 30.0), ("fourier", 20.0), ("ptp", 20.0))):
        t, q, dq, tau, cur = simulate(model, kind, 7919 * (3 * seed + k) + 17, dur, noise, gain)
        write_log(tmp / f"{kind}.csv", t, q, dq, tau, "tau")
        write_log(tmp / f"{kind}_i.csv", t, q, dq, cur, "i")
        logs[kind] = (t, q, dq, tau)
    fit, val = tmp / "fit.csv", [str(tmp / f"{kind}.csv") for kind in VALIDATIONS]
    out = {}
    t0 = time.perf_counter()
    doc = run_mindyn(urdfs["ros1"], fit, val, tmp, "coupled")
    out["mindyn coupled"] = figures(doc)
    print(pruning_said(doc))
    fm = doc["friction_model"]
    if fm["kind"] != "coulomb" or fm.get("chosen_by") != "default":
        scales = " ".join(f"{v:.3g}" for v in fm["velocity"] or [])
        print(f"  friction model {fm['kind']} ({fm['chosen_by']})"
              + (f", velocity scales per motor {scales} rad/s" if scales else ""))  # fmt: skip
    cutoff = doc["settings"]["preprocessing"]["filter"]["cutoff_Hz"]
    kt = ",".join(f"{k:.9g}" for k in KT * gain)
    val_i = [str(tmp / f"{kind}_i.csv") for kind in VALIDATIONS]
    doc = run_mindyn(urdfs["ros1"], tmp / "fit_i.csv", val_i, tmp, "currents", ["--drive-gain", kt])
    out["mindyn currents"] = figures(doc)
    if ros2_check:
        r2 = figures(run_mindyn(urdfs["ros2"], fit, val, tmp, "ros2"))
        same = all(
            abs(r2[k]["val"] - out["mindyn coupled"][k]["val"]) <= 1e-12 for k in VALIDATIONS
        )
        print(f"  ROS 2 form: {'the same figures' if same else 'DIFFERENT figures'}")
    out["mindyn joint-side"] = figures(run_mindyn(urdfs["plain"], fit, val, tmp, "plain"))
    doc = run_mindyn(urdfs["ros1"], fit, val, tmp, "all", ["--rsd-threshold", "0"])
    out["mindyn coupled, all kept"] = figures(doc)
    t1 = time.perf_counter()
    script = Script(model, transmission_matrix(), cutoff)
    Wf, yf, mask, Wr, yr = script.prepare(*logs["fit"])
    script.fit(Wf, yf, mask)
    res = {"fit": overall(yf, script.predict(Wf)), "fit_raw": overall(yr, script.predict_raw(Wr))}
    for kind in VALIDATIONS:
        Wv, yv, _, Wvr, yvr = script.prepare(*logs[kind])
        res[kind] = {
            "val": overall(yv, script.predict(Wv)),
            "val_raw": overall(yvr, script.predict_raw(Wvr)),
            "joints": per_joint(yv, script.predict(Wv)),
        }
    out["script"] = res
    t2 = time.perf_counter()
    print(f"  cut-off {cutoff:.3g} Hz; mindyn runs {t1 - t0:.1f} s, script {t2 - t1:.1f} s")
    return out


NAMES = [
    "mindyn coupled",
    "mindyn currents",
    "script",
    "mindyn joint-side",
    "mindyn coupled, all kept",
]


def table(rows):
    """Prints the tables; returns the worst ratio mindyn coupled / script on validation."""
    print("\noverall relative error [%], filtered (raw): fit; validation on the Fourier log; on "
          "the point-to-point log" + (f" (mindyn: {' '.join(DEFAULT_FLAGS)})" if DEFAULT_FLAGS
                                      else ""))  # fmt: skip
    worst = 0.0
    for seed, noise, res in rows:
        print(f"seed {seed}, current noise {noise:.0%}:")
        for name in NAMES:
            r = res[name]
            cells = [f"fit {100 * r['fit']:5.2f} ({100 * r['fit_raw']:5.2f})"]
            cells += [
                f"{k} {100 * r[k]['val']:5.2f} ({100 * r[k]['val_raw']:5.2f})" for k in VALIDATIONS
            ]
            print(f"  {name:24s} " + "   ".join(cells))
        for who in ("mindyn coupled", "mindyn coupled, all kept"):
            ratios = [
                res[who][k][m] / res["script"][k][m]
                for k in VALIDATIONS
                for m in ("val", "val_raw")
            ]
            if who == "mindyn coupled":
                worst = max(worst, *ratios)
            cells = [
                f"{k} {ratios[2 * i]:5.3f} ({ratios[2 * i + 1]:5.3f})"
                for i, k in enumerate(VALIDATIONS)
            ]
            print(f"  ratio {who} / script: " + "   ".join(cells))
    for k in VALIDATIONS:
        print(f"\nvalidation error per joint [%] on the {k} log, filtered: "
              "mindyn coupled | script | mindyn joint-side")  # fmt: skip
        for seed, noise, res in rows:
            parts = [
                " ".join(f"{100 * x:5.1f}" for x in res[n][k]["joints"])
                for n in ("mindyn coupled", "script", "mindyn joint-side")
            ]
            print(f"{seed:>4} {noise:>5.0%}  " + " | ".join(parts))
    return worst


def main(argv=None):
    global COUPLING
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    ap.add_argument("--noise", type=float, nargs="+", default=[0.01, 0.04],
                    help="current noise, fractions of each motor's RMS current")  # fmt: skip
    ap.add_argument("--gain-error", type=float, default=0.03)
    ap.add_argument("--coupling", type=float, default=1.0,
                    help="c of q_m6 = r6 (q6 + c q5) (default 1), nonzero")  # fmt: skip
    ap.add_argument("--keep", type=Path, help="keep the files in this folder")
    ap.add_argument(
        "--rsd-threshold", help="mindyn's default runs with this --rsd-threshold (percent or auto)"
    )
    ap.add_argument(
        "--friction-model",
        help="mindyn's runs with this --friction-model (e.g. stribeck, auto; the plant's motor "
        "friction has a Stribeck hump); the script keeps viscous + Coulomb",
    )
    args = ap.parse_args(argv)
    if args.rsd_threshold is not None:
        DEFAULT_FLAGS[:] = ["--rsd-threshold", args.rsd_threshold]
    if args.friction_model is not None:
        DEFAULT_FLAGS.extend(["--friction-model", args.friction_model])
    if not (np.isfinite(args.coupling) and args.coupling != 0):
        ap.error("--coupling must be a finite nonzero number")
    COUPLING = args.coupling
    T = transmission_matrix()
    print("T (q_m = T q):\n" + np.array2string(T, precision=1))
    print(f"reflected rotor inertia diag(T^T J_m T): {np.round(np.diag(T.T @ np.diag(JM) @ T), 4)}")
    rows = []
    for seed in args.seeds:
        for k, noise in enumerate(args.noise):
            print(f"seed {seed}, current noise {noise:.0%}:")
            first = seed == args.seeds[0] and k == 0
            if args.keep:
                tmp = args.keep / f"seed{seed}_noise{noise:g}"
                tmp.mkdir(parents=True, exist_ok=True)
                rows.append((seed, noise, case(seed, noise, args.gain_error, tmp, first)))
            else:
                with tempfile.TemporaryDirectory() as d:
                    rows.append((seed, noise, case(seed, noise, args.gain_error, Path(d), first)))
    worst = table(rows)
    verdict = "met" if worst <= 1.05 else "MISSED"
    print(f"\nworst ratio mindyn coupled / script on validation: {worst:.3f} "
          f"(target <= 1.05: {verdict})")  # fmt: skip
    return 0


if __name__ == "__main__":
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    sys.exit(main())
