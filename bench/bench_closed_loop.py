"""The closed-loop table with default settings over full reference periods: gains, margins,
tracking errors and run times.

    .venv/bin/python bench/bench_closed_loop.py [--periods 2 10] [--cycles 1] [--rate 250]
        [--robots puma560 zcr07s planar3 examples/urdf/ur5.urdf ...] [--urdf-arms]

For each robot, controller (PD, computed torque, adaptive PD), reference period (a sum of sines
within the limits) and rotor inertia on/off: ``simulate(robot, SumOfSines(robot, period),
make_controller(kind, robot, default_gains(robot, period=T)), duration=cycles * period,
rotor=rotor)``, each run's outcome (max tracking error in degrees, or the error that stopped
it), the gain margins of the default gains and the seconds taken. ``--urdf-arms`` adds the
example-robot-data UR5 and Panda (tip panda_link8) found under the environment's
``cmeel.prefix``. Exits 1 when any run diverged.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import mindyn
import numpy as np
from mindyn import control


def urdf_arms() -> list[tuple[str, str | None]]:
    hits = sorted(
        Path(sys.prefix).glob(
            "lib/python*/site-packages/cmeel.prefix/share/example-robot-data/robots"
        )
    )
    if not hits:
        print("example-robot-data not found: --urdf-arms skipped", file=sys.stderr)
        return []
    root = hits[0]
    return [
        (str(root / "ur_description/urdf/ur5_robot.urdf"), None),
        (str(root / "panda_description/urdf/panda.urdf"), "panda_link8"),
    ]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--robots", nargs="+", default=["puma560", "zcr07s", "planar3", "examples/urdf/ur5.urdf"]
    )
    ap.add_argument("--urdf-arms", action="store_true")
    ap.add_argument("--periods", nargs="+", type=float, default=[2.0, 10.0])
    ap.add_argument("--cycles", type=float, default=1.0, help="simulated reference periods")
    ap.add_argument("--rate", type=float, default=250.0, help="controller rate [Hz]")
    args = ap.parse_args()
    T = 1.0 / args.rate
    robots = [(r, None) for r in args.robots] + (urdf_arms() if args.urdf_arms else [])
    failed = runs = 0
    print(f"{'robot':<14}{'controller':<17}{'period':>7}{'rotor':>7}{'s':>7}{'max err [deg]':>15}")
    for path, tip in robots:
        robot = mindyn.load(path, tip=tip)
        t0 = time.perf_counter()
        gains = control.default_gains(robot, period=T)
        print(f"{robot.name}: default gains in {time.perf_counter() - t0:.2f} s: {gains.note}")
        for kind in control.CONTROLLERS:
            ctl = control.make_controller(kind, robot, gains, period=T)
            for period in args.periods:
                ref = control.SumOfSines(robot, period=period)
                for rotor in (True, False):
                    runs += 1
                    t0 = time.perf_counter()
                    try:
                        r = control.simulate(
                            robot,
                            ref,
                            ctl,
                            rate=args.rate,
                            duration=args.cycles * period,
                            rotor=rotor,
                        )
                        what = f"{np.degrees(np.abs(r.error).max()):15.4g}"
                    except control.UnstableLoopError as e:
                        failed += 1
                        what = f"  DIVERGED: {e}"
                    dt = time.perf_counter() - t0
                    print(
                        f"{robot.name:<14}{kind:<17}{period:7g}{'on' if rotor else 'off':>7}"
                        f"{dt:7.2f}{what}"
                    )
    print(f"{runs} runs, {failed} diverged")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
