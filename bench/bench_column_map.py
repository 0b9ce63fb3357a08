"""Reading a log through a column map: time of the three parsers on an RTDE-like log.

    .venv/bin/python bench/bench_column_map.py [--rows 60000] [--extra 42] [--no-text]

A 6-joint log of ROWS samples at 500 Hz under Universal Robots RTDE names (``timestamp`` in ms,
``actual_q_*``, ``actual_qd_*``, ``target_moment_*``) with EXTRA further numeric columns and,
unless ``--no-text``, a text column (a robot mode) is written to a temporary folder and read by
``read_csv(columns=...)``: as the reader chooses (all columns at once when every cell is a
number, else the rows cut down to the mapped columns), and by the strict cell-by-cell reading
alone. The arrays must be the same bit for bit (the script exits non-zero otherwise). Wall-clock
and CPU times are printed, with the load average (the machine may be shared).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

MAP = {
    "t[ms]": "timestamp",
    "q": "actual_q_{j0}",
    "dq": "actual_qd_{j0}",
    "tau": "target_moment_{j0}",
}


def write_log(path: Path, rows: int, extra: int, text: bool) -> None:
    rng = np.random.default_rng(0)
    names = ["timestamp"] + [
        f"{kind}_{j}" for kind in ("actual_q", "actual_qd", "target_moment") for j in range(6)
    ]
    names += [f"other_{k}" for k in range(extra)] + (["robot_mode"] if text else [])
    x = np.cumsum(rng.normal(size=(rows, 18 + extra)) * 1e-4, axis=0)
    with path.open("w") as f:
        f.write(",".join(names) + "\n")
        end = ",RUNNING\n" if text else "\n"
        for k in range(rows):
            f.write(f"{2 * k}," + ",".join(f"{v:.9g}" for v in x[k]) + end)


def timed(read):
    clock = (time.perf_counter(), time.process_time())
    data = read()
    return data, time.perf_counter() - clock[0], time.process_time() - clock[1]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rows", type=int, default=60000)
    ap.add_argument("--extra", type=int, default=42, help="further numeric columns")
    ap.add_argument("--no-text", action="store_true", help="no text column")
    a = ap.parse_args()

    import mindyn
    from mindyn.identification import data as D

    robot = mindyn.load("zcr07s")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "rtde.csv"
        write_log(path, a.rows, a.extra, not a.no_text)
        read = lambda: D.read_csv(path, robot, columns=MAP, filter="none")  # noqa: E731
        got, wall, cpu = timed(read)
        fast, projected = D._fast_values, D._projected_values
        D._fast_values = D._projected_values = lambda *args: None  # the strict reading alone
        try:
            strict, s_wall, s_cpu = timed(read)
        finally:
            D._fast_values, D._projected_values = fast, projected
    width = 19 + a.extra + (0 if a.no_text else 1)
    print(f"{a.rows} rows x {width} columns ({'no ' if a.no_text else 'a '}text column)")
    print(f"  as read:        {wall:6.2f} s wall, {cpu:6.2f} s CPU")
    print(f"  strict reading: {s_wall:6.2f} s wall, {s_cpu:6.2f} s CPU")
    print(f"  load average {os.getloadavg()[0]:.2f}")
    same = all(np.array_equal(getattr(got, k), getattr(strict, k)) for k in ("t", "q", "dq", "tau"))
    print("  arrays the same bit for bit" if same else "  ARRAYS DIFFER")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
