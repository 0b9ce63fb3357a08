"""Base parameters: the projection method against the numerical method, in the same run.

    .venv/bin/python bench/bench_base_parameters.py [--quick] [--repeats N] [--callgrind]

For each robot both methods run alternately; the table gives the median over the repeats of the
computation time the library reports (``bp.seconds``) and of the wall time of the Python call,
the ratio projection / numerical (wall), the number of base parameters found by each, the
non-zero basis functions of the projection (rows of Z) with the terms its recursion formed, and
the stacked regressor rows of the numerical method. ``--quick`` leaves out the 12-link chain
(several seconds per call). ``--callgrind`` adds instruction counts of one call of each
method (valgrind's callgrind, counting only inside ``mindyn::computeBaseParameters``), which do
not depend on the load of the machine.
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import mindyn
import numpy as np


def skewed_6r(directory: Path) -> mindyn.Robot:
    """A 6R arm in standard DH with no parallel or perpendicular consecutive axes, mounted tilted
    against gravity (robots.md: 38 base parameters)."""
    rng = np.random.default_rng(6)
    lines = [
        "name: skewed6r",
        "convention: dh",
        "gravity: [1.5, -2.0, -9.5]",
        "joints:",
    ]
    for k in range(6):
        alpha = float(rng.choice([-1, 1]) * rng.uniform(0.3, 1.2))
        a, d = (float(x) for x in rng.uniform(0.05, 0.4, 2))
        m = float(rng.uniform(1.0, 5.0))
        c = ", ".join(repr(float(x)) for x in rng.uniform(-0.1, 0.1, 3))
        ixx, iyy, izz = (float(x) for x in rng.uniform(0.02, 0.05, 3))
        lines.append(
            f"  - {{name: j{k + 1}, a: {a!r}, alpha: {alpha!r}, d: {d!r}, theta: 0, "
            f"inertial: {{mass: {m!r}, com: [{c}], "
            f"inertia: {{xx: {ixx!r}, yy: {iyy!r}, zz: {izz!r}}}}}}}"
        )
    path = directory / "skewed6r.yaml"
    path.write_text("\n".join(lines) + "\n")
    return mindyn.load(path)


def panda() -> mindyn.Robot | None:
    hits = sorted(
        Path(sys.prefix).glob(
            "lib/python*/site-packages/cmeel.prefix/share/example-robot-data/robots/"
            "panda_description/urdf/panda.urdf"
        )
    )
    return mindyn.load(hits[0], tip="panda_hand") if hits else None


def measure(robot: mindyn.Robot, options: dict, repeats: int) -> dict:
    runs: dict[str, dict[str, list]] = {
        m: {"seconds": [], "wall": [], "bp": []} for m in ("projection", "numerical")
    }
    for _ in range(repeats):
        for method in ("projection", "numerical"):
            t0 = time.perf_counter()
            bp = mindyn.base_parameters(robot, method=method, **options)
            wall = time.perf_counter() - t0
            runs[method]["seconds"].append(bp.seconds)
            runs[method]["wall"].append(wall)
            runs[method]["bp"] = bp
    return {
        m: {
            "ms": 1e3 * statistics.median(r["seconds"]),
            "wall_ms": 1e3 * statistics.median(r["wall"]),
            "bp": r["bp"],
        }
        for m, r in runs.items()
    }


def cases(directory: Path, quick: bool) -> list[tuple[str, mindyn.Robot | None, dict]]:
    out = [
        ("puma560", mindyn.load("puma560"), {}),
        ("zcr07s Ia+Fv+Fc", mindyn.load("zcr07s"), {"rotor": True, "friction": True}),
        ("panda", panda(), {}),
        ("skewed 6R", skewed_6r(directory), {}),
    ]
    sizes = [6, 8, 10] if quick else [6, 8, 10, 12]
    return out + [(f"planar{n}", mindyn.load(f"planar{n}"), {}) for n in sizes]


def timing_table(all_cases, repeats: int) -> None:
    head = (
        f"{'robot':<17}{'n_b proj/num':>13}{'basis rows':>12}{'terms':>10}{'num rows':>10}"
        f"{'proj ms':>10}{'(wall)':>10}{'num ms':>10}{'(wall)':>10}{'proj/num':>10}"
    )
    print(head)
    print("-" * len(head))
    for label, robot, options in all_cases:
        if robot is None:
            print(f"{label:<17}  skipped: example-robot-data is not installed")
            continue
        # one untimed call, then fewer repeats for the slow chains
        first = mindyn.base_parameters(robot, **options).seconds
        r = measure(robot, options, repeats if first < 0.5 else max(1, min(repeats, 3)))
        p, q = r["projection"], r["numerical"]
        print(
            f"{label:<17}{p['bp'].n:>7}/{q['bp'].n:<5}{p['bp'].basis_rows:>12}"
            f"{p['bp'].terms_formed:>10}{q['bp'].basis_rows:>10}"
            f"{p['ms']:>10.2f}{p['wall_ms']:>10.2f}{q['ms']:>10.2f}{q['wall_ms']:>10.2f}"
            f"{p['wall_ms'] / q['wall_ms']:>10.2f}",
            flush=True,
        )
    print(
        "\nms: median time reported by the library (bp.seconds); (wall): median of the Python "
        "call; proj/num: ratio of the wall times. Targets: a 6-DOF arm <= 1 ms, planar10 "
        "<= 100 ms (projection)."
    )


def instructions(label: str, method: str, quick: bool) -> int:
    """Instructions executed inside mindyn::computeBaseParameters for one call (callgrind)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "callgrind.out"
        cmd = [
            "valgrind",
            "--tool=callgrind",
            f"--callgrind-out-file={out}",
            "--collect-atstart=no",
            "--toggle-collect=mindyn::computeBaseParameters*",
            sys.executable,
            __file__,
            "--child",
            label,
            method,
        ] + (["--quick"] if quick else [])
        subprocess.run(cmd, check=True, capture_output=True)
        for line in out.read_text().splitlines():
            if line.startswith("summary:"):
                return int(line.split()[1])
    raise RuntimeError("callgrind wrote no summary")


def callgrind_table(all_cases, quick: bool) -> None:
    if shutil.which("valgrind") is None:
        print("callgrind: valgrind is not installed")
        return
    print(f"\n{'robot':<17}{'proj instr':>15}{'num instr':>15}{'proj/num':>10}   (callgrind)")
    for label, robot, _ in all_cases:
        if robot is None or label == "planar12":  # planar12: minutes under valgrind
            continue
        p = instructions(label, "projection", quick)
        q = instructions(label, "numerical", quick)
        print(f"{label:<17}{p:>15,}{q:>15,}{p / q:>10.2f}", flush=True)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="leave out the 12-link chain")
    parser.add_argument("--repeats", type=int, default=7, help="repeats per robot (default 7)")
    parser.add_argument(
        "--callgrind",
        action="store_true",
        help="also count instructions with valgrind's callgrind (about 10 s per robot and method)",
    )
    parser.add_argument("--child", nargs=2, metavar=("ROBOT", "METHOD"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)

    with tempfile.TemporaryDirectory() as tmp:
        all_cases = cases(Path(tmp), args.quick)
        if args.child:
            label, method = args.child
            robot, options = next((r, o) for lb, r, o in all_cases if lb == label)
            mindyn.base_parameters(robot, method=method, **options)
            return 0
        timing_table(all_cases, args.repeats)
        if args.callgrind:
            callgrind_table(all_cases, args.quick)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
