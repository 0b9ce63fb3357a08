"""Base parameters of floating-base and planar-base robots by the three methods: counts and
wall times.

    .venv/bin/python bench/bench_base_parameters_multidof.py [ROBOT ...] [--runs 5]
        [--no-projection]

Each ROBOT is a name of example-robot-data's robots below (default: all of them) or
``PATH.urdf[:floating|planar]`` (the root joint added above the URDF's root link, floating when
not given). For each, ``mindyn.base_parameters`` by the recursive, projection and numerical
methods: the number of base parameters (equations of motion), the median wall time of
``--runs`` calls (the Python API end to end: the C++ computation, its checks and the Python
object; the formulas are not written), and the numerical method's time over each exact
method's. The projection method runs where its limits (joints and memory estimate of the
model as it runs it: a floating root kept, other multi-DOF joints expanded) admit the robot;
otherwise its refusal is printed. The target on TALOS:
the recursive method at least 5 times faster than the numerical one.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import mindyn
from mindyn import _core


def _robots_dir() -> Path:
    hits = sorted(
        Path(sys.prefix).glob(
            "lib/python*/site-packages/cmeel.prefix/share/example-robot-data/robots"
        )
    )
    if not hits:
        raise SystemExit("example-robot-data not found: pip install example-robot-data")
    return hits[0]


# name -> (path under example-robot-data's robots, root joint)
ROBOTS = {
    "talos": ("talos_data/robots/talos_reduced.urdf", "floating"),
    "g1": ("g1_description/urdf/g1_29dof_rev_1_0.urdf", "floating"),
    "solo12": ("solo_description/robots/solo12.urdf", "floating"),
    "go1": ("go1_description/urdf/go1.urdf", "floating"),
    "anymal": ("anymal_c_simple_description/urdf/anymal.urdf", "floating"),
    "tiago": ("tiago_description/robots/tiago_no_hand.urdf", "planar"),
}


METHODS = ("recursive", "projection", "numerical")


def load(spec: str) -> mindyn.Robot:
    if spec in ROBOTS:
        rel, root = ROBOTS[spec]
        return mindyn.load(_robots_dir() / rel, root_joint=root)
    path, _, root = spec.partition(":")
    return mindyn.load(path, root_joint=root or "floating")


def timed(robot: mindyn.Robot, method: str, runs: int) -> tuple[int, float]:
    times, n = [], 0
    for _ in range(runs):
        t0 = time.perf_counter()
        n = mindyn.base_parameters(robot, method=method).n
        times.append(time.perf_counter() - t0)
    return n, statistics.median(times)


def _cell(counts: dict, seconds: dict, m: str) -> str:
    if m not in counts:
        return f"{'-':>16}"
    return f"{counts[m]:>4} {1e3 * seconds[m]:>9.2f} ms"


def _ratio(seconds: dict, m: str) -> str:
    """The numerical method's time over method m's."""
    return f"{seconds['numerical'] / seconds[m]:>8.3g}" if m in seconds else f"{'-':>8}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("robots", nargs="*", help=f"names ({', '.join(ROBOTS)}) or PATH[:root]")
    ap.add_argument("--runs", type=int, default=5, help="calls per method (median), default 5")
    ap.add_argument("--no-projection", action="store_true", help="skip the projection method")
    args = ap.parse_args(argv)
    if args.runs < 1:
        ap.error("--runs must be at least 1")
    print(
        f"{'robot':<10} {'joints':>6} {'nv':>4} {'P':>4}  {'recursive':>16} {'projection':>16} "
        f"{'numerical':>16}  {'num/rec':>8} {'num/proj':>8}"
    )
    for spec in args.robots or list(ROBOTS):
        robot = load(spec)
        counts, seconds = {}, {}
        for method in METHODS:
            if method == "projection":
                refused = _core.projection_refusal(robot._m)
                if args.no_projection or refused:
                    if refused:
                        print(f"  {spec}: {refused}")
                    continue
            counts[method], seconds[method] = timed(robot, method, args.runs)
        cells = " ".join(_cell(counts, seconds, m) for m in METHODS)
        ratios = " ".join(_ratio(seconds, m) for m in ("recursive", "projection"))
        print(f"{spec:<10} {robot.n:>6} {robot.nv:>4} {10 * robot.n:>4}  {cells}  {ratios}")
        if len(set(counts.values())) > 1:
            print(f"  {spec}: THE COUNTS DIFFER: {counts}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
