"""The recursive base-parameter method on a large random tree: time and peak memory.

    .venv/bin/python bench/bench_recursive_tree.py [--joints 1000] [--seed 0] [--plain]

Builds a random fixed-base tree of ``--joints`` moving joints (tests/random_tree.py: each joint
hangs from a random earlier link, axes anywhere, revolute, prismatic and fixed joints) and
measures, each in a fresh process so that the peak resident memory is that run's own:

- ``load``: loading the URDF only (the baseline of the Python process);
- ``core``: loading it and the C++ call of the recursive method (``mindyn._core.base_parameters``),
  with the library's own time (``seconds``) and the wall time of the call;
- ``library``: ``mindyn.base_parameters(..., method="recursive")`` and its readable formulas
  (the Python API end to end);
- ``mindyn base``: the command line end to end (``mindyn base FILE --rotor --friction``), its
  output discarded.

With rotor inertia and friction (``Ia, Fv, Fc`` per joint) unless ``--plain``. Peak memory is
the maximum resident set size of the process (``wait4``), load and interpreter included. The
target is 5 s and 1 GB for 1000 joints with rotor inertia and friction.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

_CHILD = """
import sys, time
sys.path.insert(0, {tests!r})
import mindyn
from mindyn import _core
robot = mindyn.load({path!r})
what, rotor, friction = {what!r}, {rotor!r}, {friction!r}
t0 = time.perf_counter()
if what == "core":
    b = _core.base_parameters(robot._m, rotor=rotor, friction=friction, method="recursive")
    print(b.n, b.seconds, time.perf_counter() - t0)
elif what == "library":
    bp = mindyn.base_parameters(robot, rotor=rotor, friction=friction, method="recursive")
    n = len(bp.formulas)
    print(bp.n, bp.seconds, time.perf_counter() - t0)
else:
    print(0, 0.0, time.perf_counter() - t0)
"""


def run(cmd: list[str]) -> tuple[str, float, float, float]:
    """Output, wall seconds, CPU seconds (user + system) and peak resident memory (bytes) of
    one process."""
    t0 = time.perf_counter()
    with tempfile.TemporaryFile() as out:
        proc = subprocess.Popen(cmd, stdout=out, stderr=subprocess.PIPE, cwd=ROOT)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        err = proc.stderr.read().decode() if proc.stderr else ""
        if os.waitstatus_to_exitcode(status) != 0:
            raise SystemExit(f"{' '.join(cmd[:3])}...: failed: {err.strip()[-400:]}")
        out.seek(0)
        text = out.read().decode()
    return text, wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss * 1024.0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--joints", type=int, default=1000, help="moving joints (default 1000)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the random tree")
    parser.add_argument("--plain", action="store_true", help="without rotor inertia and friction")
    args = parser.parse_args(argv)
    sys.path.insert(0, str(ROOT / "tests"))
    from random_tree import random_tree_urdf

    rotor = friction = not args.plain
    with tempfile.TemporaryDirectory() as tmp:
        path = str(random_tree_urdf(Path(tmp) / "tree.urdf", n=args.joints, seed=args.seed))
        print(
            f"random tree: {args.joints} joints, seed {args.seed}, "
            + ("rotor inertia and friction" if rotor else "rigid bodies only")
        )
        head = ("what", "n_base", "library s", "call s", "process s", "cpu s", "peak MB")
        widths = (8, 11, 9, 11, 8, 9)
        print(f"{head[0]:<12}" + "".join(f"{h:>{w}}" for h, w in zip(head[1:], widths)))
        for what in ("load", "core", "library"):
            code = _CHILD.format(
                tests=str(ROOT / "tests"), path=path, what=what, rotor=rotor, friction=friction
            )
            text, wall, cpu, rss = run([sys.executable, "-c", code])
            nb, seconds, call = text.split()
            lib = f"{float(seconds):>11.2f}" if what != "load" else f"{'-':>11}"
            count = nb if what != "load" else "-"
            print(
                f"{what:<12}{count:>8}{lib}{float(call):>9.2f}{wall:>11.2f}{cpu:>8.2f}"
                f"{rss / 1e6:>9.0f}",
                flush=True,
            )
        cli = [sys.executable, "-m", "mindyn", "base", path]
        cli += ["--rotor", "--friction"] if rotor else []
        text, wall, cpu, rss = run(cli)
        print(
            f"{'mindyn base':<12}{'-':>8}{'-':>11}{'-':>9}{wall:>11.2f}{cpu:>8.2f}{rss / 1e6:>9.0f}"
        )
        first = next((line for line in text.splitlines() if "method" in line), "")
        print(f"\nmindyn base: {first.strip()}")
    print(
        "process s: wall time of the process; cpu s: its user + system CPU time (the wall time "
        "exceeds it on a loaded machine)\n"
        "target (1000 joints, rotor inertia and friction): <= 5 s and <= 1 GB (1000 MB)"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
