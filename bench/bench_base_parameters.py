"""Base parameters: the projection, recursive and numerical methods, in the same run.

    .venv/bin/python bench/bench_base_parameters.py [--quick] [--repeats N] [--callgrind]

For each robot the methods run alternately; the table gives the median over the repeats of the
computation time the library reports (``bp.seconds``) per method, the wall time of the Python
call of the recursive method, the ratios numerical / recursive and projection / recursive (of
the library times), the number of base parameters found by each method and whether the
recursive method's base set and ``Y`` equal the projection's (``same``). The projection method
refuses the 20-joint chains (more than 18 joints): ``-`` in its columns. The last case is a
tree (Baxter, both arms and the head). ``--quick`` leaves out the 12-link chain (several
seconds per projection call). ``--callgrind`` adds instruction
counts of one call of each method (valgrind's callgrind, counting only inside
``mindyn::computeBaseParameters``), which do not depend on the load of the machine.
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


def skewed_chain(directory: Path, n: int, seed: int) -> mindyn.Robot:
    """An n-joint arm in standard DH with no parallel or perpendicular consecutive axes, mounted
    tilted against gravity (n = 6, seed 6: the skewed 6R of robots.md, 38 base parameters)."""
    rng = np.random.default_rng(seed)
    lines = [
        f"name: skewed{n}r",
        "convention: dh",
        "gravity: [1.5, -2.0, -9.5]",
        "joints:",
    ]
    for k in range(n):
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
    path = directory / f"skewed{n}r.yaml"
    path.write_text("\n".join(lines) + "\n")
    return mindyn.load(path)


def example_robot(path: str, tip: str | None = None) -> mindyn.Robot | None:
    """A URDF of example-robot-data (installed with the test requirements), or None."""
    hits = sorted(
        Path(sys.prefix).glob(
            f"lib/python*/site-packages/cmeel.prefix/share/example-robot-data/robots/{path}"
        )
    )
    return mindyn.load(hits[0], tip=tip) if hits else None


METHODS = ("projection", "recursive", "numerical")


def measure(robot: mindyn.Robot, options: dict, methods, repeats: int) -> dict:
    runs: dict[str, dict[str, list]] = {m: {"seconds": [], "wall": [], "bp": []} for m in methods}
    for _ in range(repeats):
        for method in methods:
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
        ("panda", example_robot("panda_description/urdf/panda.urdf", "panda_hand"), {}),
        ("skewed 6R", skewed_chain(directory, 6, 6), {}),
    ]
    sizes = [6, 8, 10] if quick else [6, 8, 10, 12]
    out += [(f"planar{n}", mindyn.load(f"planar{n}"), {}) for n in sizes]
    return out + [
        ("planar20", mindyn.load("planar20"), {}),
        ("skewed 20R", skewed_chain(directory, 20, 20), {}),
        # a tree: head and two 7-joint arms with a gripper finger each, 17 joints
        ("baxter (tree)", example_robot("baxter_description/urdf/baxter.urdf"), {}),
    ]


def timing_table(all_cases, repeats: int) -> None:
    head = (
        f"{'robot':<17}{'n_b proj/rec/num':>17}{'same':>6}{'proj ms':>10}{'rec ms':>9}"
        f"{'(wall)':>9}{'num ms':>9}{'num/rec':>9}{'proj/rec':>10}"
    )
    print(head)
    print("-" * len(head))
    for label, robot, options in all_cases:
        if robot is None:
            print(f"{label:<17}  skipped: example-robot-data is not installed")
            continue
        methods = METHODS if robot.n <= 18 else ("recursive", "numerical")
        # one untimed call of each, then fewer repeats for the slow chains
        first = max(mindyn.base_parameters(robot, method=m, **options).seconds for m in methods)
        r = measure(robot, options, methods, repeats if first < 0.5 else max(1, min(repeats, 3)))
        rec, num, proj = r["recursive"], r["numerical"], r.get("projection")
        if proj:
            same = proj["bp"].names == rec["bp"].names and np.allclose(
                proj["bp"].Y, rec["bp"].Y, rtol=0, atol=1e-10
            )
            pn, pms, pr = (
                f"{proj['bp'].n}",
                f"{proj['ms']:>10.3f}",
                f"{proj['ms'] / rec['ms']:>10.0f}",
            )
        else:
            same, pn, pms, pr = "-", "-", f"{'-':>10}", f"{'-':>10}"
        counts = f"{pn}/{rec['bp'].n}/{num['bp'].n}"
        print(
            f"{label:<17}{counts:>17}{str(same)[:1] if same != '-' else '-':>6}{pms}"
            f"{rec['ms']:>9.3f}{rec['wall_ms']:>9.3f}{num['ms']:>9.2f}"
            f"{num['ms'] / rec['ms']:>9.1f}{pr}",
            flush=True,
        )
    print(
        "\nms: median time reported by the library (bp.seconds); (wall): median of the Python "
        "call of the recursive method; num/rec, proj/rec: ratios of the library times; same: "
        "the recursive base set and Y (to 1e-10) equal the projection's (T). Targets: recursive "
        "faster than numerical on every arm (goal 5x), a 6-DOF arm <= 0.1 ms, planar20 and the "
        "skewed 20R <= 5 ms (recursive); a 6-DOF arm <= 1 ms, planar10 <= 100 ms (projection)."
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
    print(
        f"\n{'robot':<17}" + "".join(f"{m[:4] + ' instr':>15}" for m in METHODS) + "   (callgrind)"
    )
    for label, robot, _ in all_cases:
        if robot is None or label == "planar12":  # planar12: minutes under valgrind
            continue
        methods = METHODS if robot.n <= 18 else METHODS[1:]
        counts = {m: instructions(label, m, quick) for m in methods}
        print(
            f"{label:<17}"
            + "".join(f"{counts[m]:>15,}" if m in counts else f"{'-':>15}" for m in METHODS),
            flush=True,
        )


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
