"""Identification from one long log: time per stage and end to end, fast CSV reading checked
against the strict one.

    .venv/bin/python bench/bench_long_log.py [ROWS] [--robot zcr07s] [--log FILE] [--no-strict]

A log of ROWS samples at 1 kHz (default 1 000 000, ten minutes is 600 000) is simulated with
``mindyn simulate ROBOT --mode inverse --rotor --friction`` (torque noise, encoder steps) unless
``--log`` gives one. Then, in this process, the stages of ``mindyn identify ROBOT LOG --rotor
--friction`` are timed one by one: reading the CSV, the data path (low-pass, edges,
decimation), base parameters, the fit (parallel-filtered regressor, weighted least squares,
statistics, pruning) and the validation on the fit data; then the command itself is timed
end to end in a new process. Unless ``--no-strict``, the log is read again through the strict
cell-by-cell path alone and identified again: the arrays read and the estimates must be the
same bit for bit (the script exits non-zero otherwise). Wall-clock times on a shared machine
grow with its load while the CPU times stay: both are printed, and the load average.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def simulate(robot: str, rows: int, path: Path) -> None:
    argv = [sys.executable, "-m", "mindyn", "simulate", robot, "--mode", "inverse"]
    argv += ["--rate", "1000", "--duration", f"{(rows - 1) / 1000:.3f}", "--rotor", "--friction"]
    argv += ["--torque-noise", "0.5", "--quantization", "1e-6", "--seed", "1", "-o", str(path)]
    subprocess.run(argv, check=True, stdout=subprocess.DEVNULL)


def identify_stages(robot_name: str, path: Path, strict: bool = False):
    """The stages of ``mindyn identify ROBOT LOG --rotor --friction`` timed; returns the times,
    the raw data read and the result."""
    import mindyn
    from mindyn._threads import reuse_freed_memory
    from mindyn.identification import data as D
    from mindyn.identification import identify, validate
    from mindyn.identification.preprocess import preprocess, split_at_gaps

    times = {}
    clock = [time.perf_counter(), time.process_time()]

    def lap(stage):
        now = [time.perf_counter(), time.process_time()]
        times[stage] = (now[0] - clock[0], now[1] - clock[1])
        clock[:] = now

    reuse_freed_memory()  # as the command line does for its process
    robot = mindyn.load(robot_name)
    lap("load robot")
    fast = getattr(D, "_fast_values", None)  # absent from a reader without the fast path
    if strict and fast is not None:
        D._fast_values = lambda *a: None
    try:
        clock[:] = [time.perf_counter(), time.process_time()]
        raw = D.read_csv(path, robot=robot, filter="none")
        lap("read CSV")
    finally:
        if fast is not None:
            D._fast_values = fast
    logs = [preprocess(seg) for seg in split_at_gaps(raw)]
    lap("data path (filter, edges, decimation)")
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    lap("base parameters")
    res = identify(robot, logs, model="dynamic", base=base)
    lap("fit (parallel-filtered regressor, WLS, pruning)")
    validate(res, logs)
    lap("validation on the fit data")
    return times, raw, res


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("rows", type=int, nargs="?", default=1_000_000, help="samples of the log")
    ap.add_argument("--robot", default="zcr07s", help="robot to simulate and identify")
    ap.add_argument("--log", type=Path, help="an existing log of ROBOT instead of a simulated one")
    ap.add_argument("--no-strict", action="store_true", help="skip the strict-reader check")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = args.log
        if path is None:
            path = Path(tmp) / "long.csv"
            print(f"simulating {args.rows} samples of {args.robot} at 1 kHz ...", flush=True)
            simulate(args.robot, args.rows, path)
        size = path.stat().st_size
        print(f"log {path}: {size / 2**20:.1f} MiB")
        print(f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
        times, raw, res = identify_stages(args.robot, path)
        print(f"{raw.m} samples, {raw.n} joints; {len(res.names)} parameters kept")
        print(f"  {'stage':<50} {'wall [s]':>9} {'CPU [s]':>9}")
        for stage, (wall, cpu) in times.items():
            print(f"  {stage:<50} {wall:9.2f} {cpu:9.2f}")
        wall, cpu = (sum(w[k] for w in times.values()) for k in (0, 1))
        print(f"  {'total of the stages':<50} {wall:9.2f} {cpu:9.2f}")
        argv = [sys.executable, "-m", "mindyn", "identify", args.robot, str(path)]
        argv += ["--rotor", "--friction", "--json", str(Path(tmp) / "id.json")]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run(argv, check=True, stdout=subprocess.DEVNULL)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = sum(getattr(after, k) - getattr(before, k) for k in ("ru_utime", "ru_stime"))
        print(f"  {'mindyn identify, end to end (new process)':<50} {wall:9.2f} {cpu:9.2f}")
        print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
        if args.no_strict:
            return 0
        s_times, s_raw, s_res = identify_stages(args.robot, path, strict=True)
        wall, cpu = s_times["read CSV"]
        print(f"strict cell-by-cell reading: {wall:.2f} s wall, {cpu:.2f} s CPU")
        same_data = all(
            getattr(raw, k).tobytes() == getattr(s_raw, k).tobytes()
            for k in ("t", "q", "dq", "ddq", "tau")
        )
        same_est = res.names == s_res.names and np.array_equal(res.values, s_res.values)
        print(f"same arrays as the strict reader: {same_data}; same estimates: {same_est}")
        return 0 if same_data and same_est else 1


if __name__ == "__main__":
    sys.exit(main())
