"""Collision detection by the momentum observer in simulation: detection delay per joint and
false alarms, with an identified (not the true) model and torque noise.

    .venv/bin/python bench/bench_collision_detection.py [--robot puma560] [--rate 1000]
        [--noise 1%] [--step 10] [--runs 5] [--duration 2] [--excitation 10]

1. Identification: the robot (rotor inertia, viscous and Coulomb friction) tracks a sum of sines
   for ``--excitation`` s under the default computed-torque controller, its logged torque with
   white noise of ``--noise`` (percent of each joint's effort limit, or where the description
   gives none of the joint's peak torque in that run without noise; or N m); the base
   parameters are identified from that log by the integral (momentum) model.
2. Calibration: one collision-free run (another sum of sines, other noise), thresholds = 1.5 x
   the largest |r_j| (the defaults of ``mindyn detect --calibrate``).
3. False alarms: ``--runs`` further collision-free runs (other references and noise).
4. Detection: per joint, a run with a ``--step`` N m external torque on that joint from the
   middle of the run on; the delay is the time from its onset to the first sample where any
   |r_j| exceeds its threshold (the torque held over the period acts from the onset sample, the
   residual sees it at the next sample: one period at least).

The observer: ``mindyn.control.MomentumObserver`` of the identified values at the controller
period with the default gain 1 / (10 T) (or ``--observer-gain``), the logged (noisy) torque
held over each period.
"""

from __future__ import annotations

import argparse
import time

import mindyn
import numpy as np
from mindyn import control
from mindyn.control.simulation import noise_from_spec
from mindyn.identification import JointData, identify


def run(robot, seed, args, external=None, duration=None, sd=0.0):
    noise = control.SensorNoise(torque=sd)
    return control.simulate(
        robot,
        control.SumOfSines(robot, period=2.0, fraction=0.5, seed=seed),
        rate=args.rate,
        duration=duration or args.duration,
        rotor=True,
        friction=True,
        noise=noise,
        seed=seed + 1000,
        external=external,
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--robot", default="puma560")
    ap.add_argument("--rate", type=float, default=1000.0, help="controller rate [Hz]")
    ap.add_argument("--noise", default="1%", help="torque noise: percent of effort, or N m")
    ap.add_argument("--step", type=float, default=10.0, help="external torque step [N m]")
    ap.add_argument("--runs", type=int, default=5, help="collision-free runs checked")
    ap.add_argument("--duration", type=float, default=2.0, help="each run [s]")
    ap.add_argument("--excitation", type=float, default=10.0, help="identification run [s]")
    ap.add_argument(
        "--observer-gain", type=float, help="observer gain K_O [1/s] (default: the library's)"
    )
    ap.add_argument("--margin", type=float, default=1.5, help="threshold margin on max |r|")
    args = ap.parse_args()
    robot = mindyn.load(args.robot)
    n, T = robot.n, 1.0 / args.rate
    t0 = time.perf_counter()
    clean = run(robot, 100, args, duration=args.excitation)
    sd = noise_from_spec(args.noise, robot, "torque", reference_torque=clean.tau)
    ex = run(robot, 100, args, duration=args.excitation, sd=sd)
    data = JointData(ex.t, ex.q, ex.dq, np.zeros_like(ex.q), ex.tau, source="excitation")
    result = identify(robot, data, model="integral", rotor=True, friction=True)
    base, values = result.base, np.asarray(result.full)
    truth = base.values(ex.params)
    err = np.linalg.norm(values - truth) / np.linalg.norm(truth)
    print(
        f"{robot.name}: {n} joints, {args.rate:g} Hz, torque noise {args.noise} "
        f"(sd {', '.join(f'{x:.3g}' for x in sd)} N m)"
    )
    print(
        f"identified {base.n} base parameters (integral model) from {args.excitation:g} s: "
        f"relative distance to the true values {err:.3g}"
    )

    def residual(res):
        obs = control.MomentumObserver(base, values, period=T, gains=gain)
        return obs.run(res.q, res.dq, res.tau)

    gain = args.observer_gain or control.default_observer_gain(T)
    cal = residual(run(robot, 0, args, sd=sd))
    thr = control.calibrate_thresholds(cal, margin=args.margin)
    print(f"gain K_O = {gain:.4g} 1/s on every joint; thresholds {args.margin:g} x max |r|")
    print("thresholds [N m]: " + ", ".join(f"{x:.3g}" for x in thr))
    false = []
    for k in range(args.runs):
        res = run(robot, k + 1, args, sd=sd)
        r = residual(res)
        alarms = control.alarm_intervals(res.t, r, thr)
        ratio = np.abs(r).max(0) / thr
        false.append(len(alarms))
        print(
            f"collision-free run {k + 1}: {len(alarms)} false alarm(s); largest |r| / threshold "
            f"per joint {', '.join(f'{x:.2f}' for x in ratio)}"
        )
    print("detection of a step of " + f"{args.step:g} N m from t = {args.duration / 2:g} s:")
    delays = []
    for j in range(n):
        torque = np.zeros(n)
        torque[j] = args.step
        step = control.TorqueProfile(torque, start=args.duration / 2)
        res = run(robot, 50 + j, args, step, sd=sd)
        r = residual(res)
        i0 = int(np.flatnonzero(res.tau_ext[:, j] != 0)[0])
        before = np.any(np.abs(r[:i0]) > thr)
        after = np.flatnonzero(np.any(np.abs(r[i0:]) > thr, axis=1))
        delay = (after[0] * T) if after.size else np.inf
        first = int(np.argmax(np.abs(r[i0 + after[0]]) / thr)) + 1 if after.size else 0
        delays.append(delay)
        print(
            f"  joint {j + 1}: detected after {delay * 1e3:.3g} ms (first on joint {first})"
            + ("; an alarm before the step" if before else "")
        )
    worst = max(delays)
    print(
        f"summary: false alarms {sum(false)} over {args.runs} runs; worst delay "
        f"{worst * 1e3:.3g} ms; {time.perf_counter() - t0:.1f} s"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
