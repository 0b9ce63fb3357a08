"""Bias of the window models (integral and energy) with Coulomb friction on a joint that rests:
the estimates against the simulation's true values, in their standard deviations.

    .venv/bin/python bench/bench_window_rests.py [--robot puma560_3] [--duration 40]
        [--rate 250] [--cutoff 5] [--joint 2] [--period 4] [--noise 0.02]
        [--velocity-noise 0.005] [--draws 20] [--models dynamic integral energy]
        [--min-velocity 0.01]

A random 5-harmonic Fourier motion of ROBOT in which joint JOINT (1-based) follows its own path
through a time warp that stops it half of every PERIOD seconds (its path's speed times
``max(0, sin(2 pi t / PERIOD))^3``: it creeps into and out of each rest, lingering near zero
velocity), torques from the description's inverse dynamics plus viscous and Coulomb friction
(none at rest: the drive holds the joint), white torque noise of NOISE x each joint's largest
torque and white velocity noise of VELOCITY_NOISE rad/s on the logged velocities,
goes through :func:`~mindyn.identification.preprocess.preprocess` (cut-off CUTOFF Hz;
decimated for the dynamic model only, as ``identify`` does) and is identified by
each model with friction, without pruning, over DRAWS noise draws. Printed per model: the
bias of each estimate (mean over the draws minus the true value) over its mean reported
standard deviation, the largest and the resting joint's friction parameters, and the scatter
over the standard deviation (RMS of (estimate - mean) / std, the mean's degree of freedom
taken out); the bias's own sampling spread is about 1 / sqrt(DRAWS) standard deviations.
"""

from __future__ import annotations

import math
import time

import mindyn
import numpy as np
from bench_window_std import log_arguments
from mindyn.identification import JointData, identify, true_base_values
from mindyn.identification.excitation import random_trajectory
from mindyn.identification.preprocess import preprocess
from scipy import integrate


def resting_log(robot, duration: float, rate: float, joint: int, period: float):
    """Times, motion, noise-free torques and the truth sidecar of a motion whose joint
    ``joint`` (0-based) rests half of every ``period``."""
    t = np.arange(0.0, duration, 1.0 / rate)
    traj = random_trajectory(robot, harmonics=5, freq=0.1, seed=3)
    q, dq, ddq = traj.evaluate(t)
    s = np.sin(2 * np.pi * t / period)
    w = np.maximum(s, 0.0) ** 3  # the warp's speed: 0 at rest, C2 into and out of it
    dw = 3 * np.maximum(s, 0.0) ** 2 * np.cos(2 * np.pi * t / period) * 2 * np.pi / period
    fine = np.linspace(0.0, duration, 40 * t.size + 1)
    u_fine = integrate.cumulative_simpson(
        np.maximum(np.sin(2 * np.pi * fine / period), 0.0) ** 3, x=fine, initial=0.0
    )
    u = np.interp(t, fine, u_fine)
    qu, dqu, ddqu = traj.evaluate(u)
    q[:, joint] = qu[:, joint]
    dq[:, joint] = dqu[:, joint] * w
    ddq[:, joint] = ddqu[:, joint] * w**2 + dqu[:, joint] * dw
    p = robot.parameters(rotor=True, friction=True).reshape(robot.n, 13).copy()
    p[:, 10:] = 0.0
    fv, fc = 0.5 + 0.1 * np.arange(robot.n), 1.0 + 0.2 * np.arange(robot.n)
    tau = robot.inverse_dynamics(q, dq, ddq, p.reshape(-1)) + fv * dq + fc * np.sign(dq)
    p[:, 11], p[:, 12] = fv, fc
    names = robot.parameter_names(rotor=True, friction=True)
    return t, q, dq, ddq, tau, {"names": names, "values": p.reshape(-1)}


def main() -> None:
    ap = log_arguments(__doc__.split("\n\n")[0])
    ap.add_argument("--joint", type=int, default=2)
    ap.add_argument("--period", type=float, default=4.0)
    ap.add_argument("--velocity-noise", type=float, default=0.005)
    ap.add_argument("--draws", type=int, default=20)
    ap.add_argument("--models", nargs="+", default=["dynamic", "integral", "energy"])
    ap.add_argument("--min-velocity", type=float, default=0.01)
    a = ap.parse_args()
    robot = mindyn.load(a.robot)
    j = a.joint - 1
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    t, q, dq, ddq, tau, truth = resting_log(robot, a.duration, a.rate, j, a.period)
    true = true_base_values(base, truth)
    slow = np.mean(np.abs(dq[:, j]) < a.min_velocity)
    print(
        f"{a.robot}, {a.duration:g} s at {a.rate:g} Hz, cut-off {a.cutoff:g} Hz, joint {a.joint} "
        f"resting half of every {a.period:g} s ({100 * slow:.0f} % of the samples slower than "
        f"{a.min_velocity:g}), torque noise {a.noise:g} x the largest torque, velocity noise "
        f"{a.velocity_noise:g}, {base.n} base parameters, {a.draws} draws"
    )
    names = list(base.names)
    sd = a.noise * np.abs(tau).max(axis=0)
    for model in a.models:
        t0 = time.perf_counter()
        est, std = [], []
        for s in range(a.draws):
            rng = np.random.default_rng(s)
            log = JointData(
                t,
                q,
                dq + a.velocity_noise * rng.standard_normal(dq.shape),
                ddq,
                tau + sd * rng.standard_normal(tau.shape),
                source="rests",
            )
            d = preprocess(log, cutoff=a.cutoff, decimate=model == "dynamic")
            rule = {} if model == "energy" else {"min_velocity": a.min_velocity}
            res = identify(robot, d, base=base, model=model, rsd_threshold=None, **rule)
            est.append(res.full)
            std.append(res.std)
        est, std = np.array(est), np.array(std)
        sigma = std.mean(axis=0)
        bias = (est.mean(axis=0) - true) / sigma
        z = (est - est.mean(axis=0)) / std
        scatter = math.sqrt(np.sum(z**2) / (z.size - z.shape[1]))
        k = int(np.argmax(np.abs(bias)))
        own = [i for i, nm in enumerate(names) if nm in (f"Fv{a.joint}", f"Fc{a.joint}")]
        print(
            f"  {model:8s}: largest |bias| / std {abs(bias[k]):.2f} ({names[k]}); "
            + ", ".join(f"{names[i]} {bias[i]:+.2f}" for i in own)
            + f"; {np.sum(np.abs(bias) > 3)} of {base.n} beyond 3; scatter / std {scatter:.2f}"
            + f"  [{time.perf_counter() - t0:.1f} s]",
            flush=True,
        )


if __name__ == "__main__":
    main()
