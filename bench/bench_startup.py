"""Start-up time of the command line: median wall-clock and CPU time of commands run afresh.

    .venv/bin/python bench/bench_startup.py [--runs 10] [--python .venv/bin/python]

Each command (``python -c "import mindyn"``; ``mindyn --help``, ``mindyn --version``,
``mindyn base puma560``, through ``python -m mindyn`` and through the installed ``mindyn``
script beside the interpreter) runs ``--runs`` times in a new process; the median wall-clock
time and the median CPU time (user + system of the child) are printed. On a machine shared with
other work the wall-clock time grows with the load while the CPU time stays: both are printed,
and the load average beside them. The targets on a quiet machine: a median wall-clock time of at
most 0.4 s for the import, 0.3 s for ``mindyn --help``.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

COMMANDS = [["--help"], ["--version"], ["base", "puma560"]]


def timed(argv: list[str]) -> tuple[float, float]:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(argv, stdout=subprocess.DEVNULL, check=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=10, help="runs of each command (default 10)")
    ap.add_argument("--python", default=sys.executable, help="the interpreter with mindyn")
    args = ap.parse_args()
    script = Path(args.python).with_name("mindyn")
    launchers = [("python -m mindyn", [args.python, "-m", "mindyn"])]
    if script.exists():
        launchers.append(("mindyn", [str(script)]))
    rows = [("python -c 'import mindyn'", [args.python, "-c", "import mindyn"])]
    rows += [
        (f"{label} {' '.join(c)}", launcher + c) for label, launcher in launchers for c in COMMANDS
    ]
    print(f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print(f"{'command':<32} {'median wall [s]':>16} {'median CPU [s]':>15}")
    for label, argv in rows:
        runs = [timed(argv) for _ in range(args.runs)]
        wall = statistics.median(w for w, _ in runs)
        cpu = statistics.median(c for _, c in runs)
        print(f"{label:<32} {wall:16.3f} {cpu:15.3f}")
    print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
