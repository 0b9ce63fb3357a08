"""Calibration of the standard deviations ``mindyn identify`` reports on its default data path,
against the truth, by Monte Carlo.

    .venv/bin/python bench/bench_std_calibration.py [--robot zcr07s] [--seeds 20]
        [--model dynamic integral energy] [--noise white ar1] [--duration 20] [--rate 250]
        [--harmonics 5] [--level 0.01] [--correlation-time 0.05] [--no-friction]
        [--closed-loop] [--quantization 0]

Per seed, a random Fourier motion of ROBOT (HARMONICS harmonics, seed-dependent) is simulated
open loop (:func:`mindyn.control.simulate_inverse`; ``--closed-loop``: tracked under the
default controller, :func:`mindyn.control.simulate`, torques held over each sample period;
rotor inertia and viscous and Coulomb friction unless ``--no-friction``) for DURATION seconds
at RATE Hz, positions quantised to QUANTIZATION if given; torque noise of LEVEL x each joint's
effort limit is added, ``white`` (independent samples) or ``ar1`` (a first-order
autoregression of correlation time CORRELATION_TIME seconds, of the same variance: noise
correlated like model error). The log is written as a CSV and read as ``mindyn identify`` reads
it (:func:`~mindyn.identification.reading.load_logs` with the default reading options: the
low-pass at the cut-off derived from the log, edges dropped, the dynamic model's log decimated)
and each MODEL is fitted with every base parameter (``rsd_threshold=0``), the other options the
defaults. With the true base parameters ``p`` (the simulation's, regrouped) the normalised errors
``z = (estimate - p) / std`` should have an RMS of 1 over the parameters and seeds if the
standard deviations are calibrated.

Printed per model and noise: the RMS of ``z`` over the parameters and seeds with its standard
error (the spread of the per-seed mean squares, delta method), the share of ``|z| > 3`` (0.27 %
for normal errors), the mean variance factor the fit reports (``settings.std_correlation``) with
the data path's and the measured one (dynamic model) and the RMS of ``z`` the standard
deviations would give without the factor. ``--json PATH`` writes the figures.
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
import time
from pathlib import Path

import mindyn
import numpy as np
from mindyn.base import base_parameters
from mindyn.control import SensorNoise, simulate, simulate_inverse
from mindyn.identification import identify
from mindyn.identification.data import write_csv
from mindyn.identification.errors import RankDeficientError
from mindyn.identification.excitation import random_trajectory
from mindyn.identification.reading import load_logs
from mindyn.identification.validation import true_base_values


def torque_noise(shape, sd, kind: str, rate: float, tc: float, rng) -> np.ndarray:
    """Zero-mean torque noise of standard deviation ``sd`` per joint: white, or AR(1) with
    coefficient ``exp(-1 / (rate tc))`` started in its stationary distribution."""
    w = rng.standard_normal(shape)
    if kind == "white":
        return sd * w
    phi = math.exp(-1.0 / (rate * tc))
    e = np.empty(shape)
    e[0] = w[0]
    s = math.sqrt(1.0 - phi * phi)
    for k in range(1, shape[0]):
        e[k] = phi * e[k - 1] + s * w[k]
    return sd * e


def one_seed(robot, base, args, seed: int, kind: str, folder: Path) -> dict:
    """Per model: ``z``, the variance factors and the seconds of one simulated log."""
    traj = random_trajectory(robot, harmonics=args.harmonics, freq=0.1, seed=seed)
    friction = not args.no_friction
    sim = simulate if args.closed_loop else simulate_inverse
    log = sim(
        robot,
        traj,
        rate=args.rate,
        duration=args.duration,
        rotor=True,
        friction=friction,
        noise=SensorNoise(quantization=args.quantization),
        seed=seed,
    )
    truth = true_base_values(base, {"names": log.param_names, "values": log.params})
    sd = args.level * np.asarray(robot.limits["effort"], dtype=float)
    rng = np.random.default_rng(1000 + seed)
    tau = log.tau + torque_noise(log.tau.shape, sd, kind, args.rate, args.correlation_time, rng)
    path = write_csv(folder / f"log_{kind}_{seed}.csv", log.t, log.q, tau, dq=log.dq)
    out = {}
    for model in args.model:
        logs = load_logs(path, robot, model=model)
        t0 = time.perf_counter()
        res = identify(
            robot, list(logs.fit.logs), model=model, base=base, rsd_threshold=0, friction=friction
        )
        corr = res.settings["std_correlation"]
        z = (res.values - truth) / res.std
        out[model] = {
            "z": z,
            "error": res.values - truth,
            "std": res.std,
            "factor": corr["variance_factor"],
            "path": corr["data_path"],
            "measured": corr["residuals"],
            "seconds": time.perf_counter() - t0,
            "cutoff": logs.cutoff,
        }
    return out


def summary(runs: list[dict], model: str) -> dict:
    """RMS of z over parameters and seeds, its standard error, the share beyond 3, the factors."""
    Z = np.array([r[model]["z"] for r in runs])  # seeds x parameters
    ms = np.mean(Z**2, axis=1)  # per-seed mean square
    rms = math.sqrt(float(ms.mean()))
    se = float(ms.std(ddof=1)) / math.sqrt(len(ms)) / (2.0 * rms) if len(ms) > 1 else float("nan")
    f = np.array([r[model]["factor"] for r in runs])
    zf = Z * np.sqrt(f)[:, None]  # without the variance factor
    meas = [r[model]["measured"] for r in runs if r[model]["measured"] is not None]
    return {
        "rms_z": rms,
        "se": se,
        "beyond_3": float(np.mean(np.abs(Z) > 3.0)),
        "max_abs_z": float(np.abs(Z).max()),
        "mean_z": float(Z.mean()),
        "variance_factor": float(f.mean()),
        "data_path_factor": float(np.mean([r[model]["path"] for r in runs])),
        "measured_factor": float(np.mean(meas)) if meas else None,
        "rms_z_without_factor": math.sqrt(float(np.mean(zf**2))),
        "parameters": int(Z.shape[1]),
        "seeds": int(Z.shape[0]),
        "cutoff_Hz": float(np.mean([r[model]["cutoff"] for r in runs])),
        "fit_seconds": float(np.mean([r[model]["seconds"] for r in runs])),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robot", default="zcr07s")
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--model", nargs="+", default=["dynamic", "integral", "energy"])
    ap.add_argument("--noise", nargs="+", default=["white", "ar1"], choices=["white", "ar1"])
    ap.add_argument("--duration", type=float, default=20.0)
    ap.add_argument("--rate", type=float, default=250.0)
    ap.add_argument("--harmonics", type=int, default=5)
    ap.add_argument("--level", type=float, default=0.01, help="torque noise / effort limit")
    ap.add_argument("--correlation-time", type=float, default=0.05, help="AR(1) noise [s]")
    ap.add_argument("--no-friction", action="store_true")
    ap.add_argument("--quantization", type=float, default=0.0, help="encoder step [rad]")
    ap.add_argument(
        "--closed-loop",
        action="store_true",
        help="simulate the robot tracking the motion under the default controller (torques held "
        "over each sample period) instead of the motion's inverse dynamics",
    )
    ap.add_argument("--json", help="write the figures to this file")
    args = ap.parse_args()
    robot = mindyn.load(args.robot)
    base = base_parameters(robot, rotor=True, friction=not args.no_friction)
    print(
        f"{args.robot}: {base.n} base parameters, {args.seeds} seeds, {args.duration:g} s at "
        f"{args.rate:g} Hz, {args.harmonics} harmonics, torque noise {args.level:g} x effort "
        f"(ar1: correlation time {args.correlation_time:g} s), rsd_threshold=0"
    )
    print(
        f"{'model':9s} {'noise':6s} {'RMS z':>7s} {'+-se':>6s} {'|z|>3':>6s} {'max|z|':>7s} "
        f"{'factor':>7s} {'path':>7s} {'resid':>7s} {'RMS z no factor':>16s} {'cut-off':>8s}"
    )
    record = {"settings": vars(args), "results": {}}
    with tempfile.TemporaryDirectory() as tmp:
        for kind in args.noise:
            runs, seed, skipped = [], 0, 0
            while len(runs) < args.seeds:  # a motion that leaves a parameter unexcited: next
                try:
                    runs.append(one_seed(robot, base, args, seed, kind, Path(tmp)))
                except RankDeficientError:
                    skipped += 1
                seed += 1
            if skipped:
                print(f"({kind}: {skipped} motions rank deficient for some model, skipped)")
            for model in args.model:
                s = summary(runs, model)
                record["results"][f"{model}/{kind}"] = s
                meas = "-" if s["measured_factor"] is None else f"{s['measured_factor']:.3g}"
                print(
                    f"{model:9s} {kind:6s} {s['rms_z']:7.3f} {s['se']:6.3f} "
                    f"{100 * s['beyond_3']:5.1f}% {s['max_abs_z']:7.2f} "
                    f"{s['variance_factor']:7.3g} {s['data_path_factor']:7.3g} {meas:>7s} "
                    f"{s['rms_z_without_factor']:16.3f} {s['cutoff_Hz']:7.3g}Hz",
                    flush=True,
                )
    if args.json:
        Path(args.json).write_text(json.dumps(record, indent=2) + "\n")


if __name__ == "__main__":
    main()
