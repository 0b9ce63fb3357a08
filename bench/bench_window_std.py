"""Standard deviations of the window models (integral and energy) on the data path against the
scatter of their estimates over noise realisations.

    .venv/bin/python bench/bench_window_std.py [--robot puma560_3] [--duration 40]
        [--rate 250] [--cutoff 5] [--noise 0.02] [--realisations 20] [--batches 5]
        [--no-friction] [--models integral energy dynamic]

A log of DURATION seconds at RATE Hz along a random 5-harmonic Fourier motion of ROBOT, its
torques from the description's inverse dynamics (plus viscous and Coulomb friction unless
``--no-friction``), gets white torque noise of NOISE x each joint's largest torque, goes through
:func:`~mindyn.identification.preprocess.preprocess` (cut-off CUTOFF Hz, decimated to 10 x the
cut-off, or not) and is identified by each model without pruning. Over REALISATIONS noise draws
the ratio of the scatter of the estimates to their reported standard deviations is the RMS of
``(estimate - mean) / std`` over the parameters and draws (the mean's degree of freedom taken
out). Printed per model and decimation: the variance factor the fit reports
(``settings.std_correlation``), the ratio with it, and the ratio the standard deviations give
without it (times the square root of the factor); mean and standard deviation over BATCHES
batches of draws (the spread of the ratio a test of REALISATIONS draws sees). Energy model:
the torque-noise level of its window weights (``joint_sigma``) over the simulated one, per
joint.
"""

from __future__ import annotations

import argparse
import math
import time

import mindyn
import numpy as np
from mindyn.identification import JointData, identify
from mindyn.identification.excitation import random_trajectory
from mindyn.identification.preprocess import preprocess


def simulated_log(robot, duration: float, rate: float, friction: bool):
    """Times, motion and noise-free torques of a random Fourier motion of ``robot``."""
    t = np.arange(0.0, duration, 1.0 / rate)
    q, dq, ddq = random_trajectory(robot, harmonics=5, freq=0.1, seed=3).evaluate(t)
    p = robot.parameters(rotor=True, friction=True).reshape(robot.n, 13).copy()
    p[:, 10:] = 0.0
    tau = robot.inverse_dynamics(q, dq, ddq, p.reshape(-1))
    if friction:
        tau = tau + (0.5 + 0.1 * np.arange(robot.n)) * dq
        tau = tau + (1.0 + 0.2 * np.arange(robot.n)) * np.sign(dq)
    return t, q, dq, ddq, tau


def scatter_ratio(robot, base, log, *, model, decimate, cutoff, noise, seeds):
    """``(ratio, variance factor, noise level)`` over the noise draws ``seeds``, the noise level
    that of the energy model's weights (``joint_sigma``) over the simulated one per joint (the
    last draw's; None for the other models)."""
    t, q, dq, ddq, tau = log
    sd = noise * np.abs(tau).max(axis=0)
    est, std, factor, level = [], [], 1.0, None
    for s in seeds:
        noisy = tau + sd * np.random.default_rng(s).standard_normal(tau.shape)
        d = preprocess(
            JointData(t, q, dq, ddq, noisy, source="mc"), cutoff=cutoff, decimate=decimate
        )
        res = identify(robot, d, base=base, model=model, rsd_threshold=None)
        est.append(res.full)
        std.append(res.std)
        factor = res.settings["std_correlation"]["variance_factor"]
        if model == "energy" and res.joint_sigma is not None:
            level = res.joint_sigma / sd
    z = (np.array(est) - np.mean(est, axis=0)) / np.array(std)
    return math.sqrt(np.sum(z**2) / (z.size - z.shape[1])), factor, level


def shown(x) -> str:
    return " ".join(f"{v:.3g}" for v in x)


def log_arguments(description: str) -> argparse.ArgumentParser:
    """The options of the simulated log and its data path shared by the window-model studies:
    ``--robot``, ``--duration``, ``--rate``, ``--cutoff``, ``--noise``."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--robot", default="puma560_3")
    ap.add_argument("--duration", type=float, default=40.0)
    ap.add_argument("--rate", type=float, default=250.0)
    ap.add_argument("--cutoff", type=float, default=5.0)
    ap.add_argument("--noise", type=float, default=0.02)
    return ap


def main() -> None:
    ap = log_arguments(__doc__.split("\n\n")[0])
    ap.add_argument("--realisations", type=int, default=20)
    ap.add_argument("--batches", type=int, default=5)
    ap.add_argument("--no-friction", action="store_true")
    ap.add_argument("--models", nargs="+", default=["integral", "energy"])
    a = ap.parse_args()
    robot = mindyn.load(a.robot)
    friction = not a.no_friction
    base = mindyn.base_parameters(robot, friction=friction)
    log = simulated_log(robot, a.duration, a.rate, friction)
    print(
        f"{a.robot}, {a.duration:g} s at {a.rate:g} Hz, cut-off {a.cutoff:g} Hz, torque noise "
        f"{a.noise:g} x the largest torque, friction {friction}, {base.n} base parameters; "
        f"{a.batches} batches of {a.realisations} draws"
    )
    for model in a.models:
        for decimate in (True, False):
            t0 = time.perf_counter()
            got, bare = [], []
            for b in range(a.batches):
                seeds = range(b * a.realisations, (b + 1) * a.realisations)
                r, f, level = scatter_ratio(
                    robot,
                    base,
                    log,
                    model=model,
                    decimate=decimate,
                    cutoff=a.cutoff,
                    noise=a.noise,
                    seeds=seeds,
                )
                got.append(r)
                bare.append(r * math.sqrt(f))
            spread = np.std(got, ddof=1) if len(got) > 1 else float("nan")
            print(
                f"  {model:8s} decimate={decimate!s:5s}: variance factor {f:.4g}; scatter / std "
                f"{np.mean(got):.3f} (sd {spread:.3f}, range {min(got):.3f}-{max(got):.3f}); "
                f"without the factor {np.mean(bare):.3f}"
                + ("" if level is None else "; weights' torque noise / simulated " + shown(level))
                + f"  [{time.perf_counter() - t0:.1f} s]",
                flush=True,
            )


if __name__ == "__main__":
    main()
