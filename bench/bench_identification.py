"""Identification and excitation benchmarks.

1. Identification of a 6-DOF robot (ZCR07S, 52 base parameters with rotor inertia and
   friction) from 10 s of data at 250 Hz, end to end: load the robot, base parameters, read the
   CSV (filtering and differentiation), stacked regressor, weighted least squares, statistics
   and RSD pruning; target <= 1 s. The stacked-regressor stage is timed beside Pinocchio's
   ``computeJointTorqueRegressor`` over the same samples (from Python, one call per sample).
2. Excitation optimisation for 6 DOF, N = 5 harmonics (ZCR07S, 52 base parameters, default
   settings: 3 starts, up to 100 SLSQP iterations each); target <= 60 s.

Run: ``.venv/bin/python bench/bench_identification.py`` (BLAS pinned to one thread, as on a
controller PC and to keep timings stable on a shared machine).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import statistics  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import mindyn  # noqa: E402
import numpy as np  # noqa: E402
from mindyn.control import SensorNoise, simulate  # noqa: E402
from mindyn.identification import dynamic_system, identify, validate  # noqa: E402
from mindyn.identification.data import read_csv  # noqa: E402
from mindyn.identification.excitation import optimize_excitation, random_trajectory  # noqa: E402


def median_time(f, repeat=5):
    times = []
    out = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def bench_identification(tmp: Path) -> None:
    robot = mindyn.load("zcr07s")
    traj = random_trajectory(robot, seed=1)
    noise = SensorNoise(torque=0.01 * robot.limits["effort"], quantization=2 * np.pi / 2**20)
    log = simulate(robot, traj, rotor=True, friction=True, noise=noise, seed=1)
    csv = log.save(tmp / "zcr07s.csv", robot_name=robot.name)
    print(f"identification: zcr07s, {log.t.size} samples (10 s at 250 Hz), 52 base parameters")

    stages = {}

    def end_to_end(model="dynamic"):
        t0 = time.perf_counter()
        r = mindyn.load("zcr07s")
        base = mindyn.base_parameters(r, rotor=True, friction=True)
        t1 = time.perf_counter()
        data = read_csv(csv, r)
        t2 = time.perf_counter()
        res = identify(r, data, model=model, base=base)
        t3 = time.perf_counter()
        stages.setdefault(model, []).append((t1 - t0, t2 - t1, t3 - t2))
        return res, data

    for model in ("dynamic", "energy"):
        total, (res, data) = median_time(lambda m=model: end_to_end(m))
        s = np.median(np.array(stages[model]), axis=0)
        v = validate(res, data)
        print(
            f"  {model:7s} model end to end {total * 1e3:7.1f} ms (median of 5; target <= 1000): "
            f"load + base parameters {s[0] * 1e3:.1f} ms, read CSV + filter {s[1] * 1e3:.1f} ms, "
            f"regressor + WLS + statistics + pruning {s[2] * 1e3:.1f} ms; {len(res.names)} of "
            f"52 kept; fit RMS {np.round(v['rms'], 2)}"
        )

    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    t_ours, _ = median_time(lambda: dynamic_system(base, data))
    try:
        import pinocchio as pin

        sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
        from conftest import pinocchio_model

        model = pinocchio_model(robot)
        pdata = model.createData()

        def pin_stack():
            q, dq, ddq = data.q, data.dq, data.ddq
            reg = pin.computeJointTorqueRegressor
            return np.vstack([reg(model, pdata, q[i], dq[i], ddq[i]) for i in range(data.m)])

        t_pin, _ = median_time(pin_stack)
        print(
            f"  stacked regressor ({data.m} x 6 rows): mindyn base regressor {t_ours * 1e3:.1f} ms "
            f"(dynamic_system: {base.n} columns, friction columns included), Pinocchio "
            f"computeJointTorqueRegressor from Python {t_pin * 1e3:.1f} ms ({model.nv * 10} "
            f"columns); ratio Pinocchio / mindyn {t_pin / t_ours:.2f}"
        )
    except ImportError:
        print(f"  stacked regressor: mindyn {t_ours * 1e3:.1f} ms (Pinocchio not installed)")


def bench_excitation() -> None:
    robot = mindyn.load("zcr07s")
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    t0 = time.perf_counter()
    res = optimize_excitation(robot, base=base, harmonics=5, freq=0.1, seed=0, progress=False)
    dt = time.perf_counter() - t0
    its = sum(s["iterations"] for s in res.starts)
    print(
        f"excitation: zcr07s, 6 DOF, N = 5, 52 base parameters, {len(res.starts)} starts, "
        f"{its} SLSQP iterations in all: {dt:.1f} s (target <= 60); condition number "
        f"{res.initial_value:.4g} -> {res.value:.4g}"
    )
    for i, s in enumerate(res.starts, 1):
        print(
            f"  start {i}: {s['initial']:.4g} -> {s['final']:.4g}, {s['iterations']} iterations, "
            f"{s['seconds']:.1f} s ({s['message']})"
        )
    q, dq, ddq = res.trajectory.evaluate(np.arange(100) * 0.1)
    t_eval, _ = median_time(lambda: base.regressor(q, dq, ddq), repeat=20)
    print(
        f"  one criterion evaluation: base regressor at 100 samples {t_eval * 1e3:.2f} ms "
        f"({t_eval / 100 * 1e6:.1f} us per sample)"
    )


if __name__ == "__main__":
    with tempfile.TemporaryDirectory() as d:
        bench_identification(Path(d))
    bench_excitation()
