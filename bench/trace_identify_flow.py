"""The modules one ``mindyn identify`` run enters, call by call, and how often it comes back.

    .venv/bin/python bench/trace_identify_flow.py [--robot examples/urdf/ur5.urdf] [--rate 50]
        [--no-consistent] [--no-validate] [--no-urdf] [--show]

Generates a fit log and a validation log (inverse dynamics along random Fourier trajectories
with torque noise, in a temporary folder), then runs, in this process,

    mindyn identify ROBOT fit.csv --validate val.csv --consistent --urdf out.urdf --json id.json

under ``sys.setprofile``. Every Python call whose code lies in the ``mindyn`` package is
recorded by the file of its code; consecutive calls in one file are one visit. Printed: the
number of distinct files entered, the number of re-entries (a visit to a file the flow had
already left: a call back into it after calls into other files), and the re-entries per file.
Module bodies run by imports are left out (they are loading, not the flow); returns are not
calls, so coming back to a caller is not counted, only calling into it again. ``--show``
prints the visits in order.
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import io
import sys
import tempfile
from pathlib import Path

import mindyn

PACKAGE = Path(mindyn.__file__).resolve().parent
REPO = Path(__file__).resolve().parents[1]


# Modules every concern calls into (the robot, base parameters, argument checks, threads, the
# command line's argument helpers): their re-entries are reported apart.
UTILITY = {
    "_args.py",
    "_mujoco.py",
    "_threads.py",
    "_version.py",
    "base.py",
    "robot.py",
    "cli/args.py",
    "cli/quiet.py",
}


def reentries(visits: list[str]) -> tuple[set[str], collections.Counter]:
    """The files visited and, per file, the visits after the first."""
    seen: set[str] = set()
    again: collections.Counter = collections.Counter()
    for v in visits:
        if v in seen:
            again[v] += 1
        seen.add(v)
    return seen, again


def make_logs(robot_path: str, folder: Path, rate: float) -> tuple[Path, Path]:
    from mindyn.control import SensorNoise, simulate_inverse
    from mindyn.identification.data import write_csv
    from mindyn.identification.excitation import random_trajectory

    robot = mindyn.load(robot_path)
    paths = []
    for name, seed in (("fit", 3), ("val", 4)):
        traj = random_trajectory(robot, seed=seed)
        log = simulate_inverse(robot, traj, rate=rate, noise=SensorNoise(torque=0.05), seed=seed)
        path = folder / f"{name}.csv"
        write_csv(path, log.t, log.q, log.tau, dq=log.dq)
        paths.append(path)
    return paths[0], paths[1]


def trace(argv: list[str]) -> tuple[list[str], int]:
    """The visits (files relative to the package, in order) and the exit status."""
    from mindyn.cli import main

    visits: list[str] = []
    names: dict[str, str | None] = {}  # file of a code object -> its name in the package

    def package_name(filename: str) -> str | None:
        path = Path(filename).resolve()
        return str(path.relative_to(PACKAGE)) if path.is_relative_to(PACKAGE) else None

    def profile(frame, event, arg):
        if event != "call":
            return
        code = frame.f_code
        if code.co_name == "<module>":
            return
        name = names.get(code.co_filename, "")
        if name == "":
            name = names[code.co_filename] = package_name(code.co_filename)
        if name is not None and (not visits or visits[-1] != name):
            visits.append(name)

    out = io.StringIO()
    sys.setprofile(profile)
    try:
        with contextlib.redirect_stdout(out):
            status = main(argv)
    finally:
        sys.setprofile(None)
    return visits, status


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robot", default=str(REPO / "examples/urdf/ur5.urdf"))
    ap.add_argument("--rate", type=float, default=50.0, help="log rate [Hz]")
    ap.add_argument("--no-consistent", action="store_true")
    ap.add_argument("--no-validate", action="store_true")
    ap.add_argument("--no-urdf", action="store_true")
    ap.add_argument("--show", action="store_true", help="print the visits in order")
    opts = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        fit, val = make_logs(opts.robot, folder, opts.rate)
        argv = ["identify", opts.robot, str(fit), "--json", str(folder / "id.json")]
        if not opts.no_validate:
            argv += ["--validate", str(val)]
        if not opts.no_consistent:
            argv += ["--consistent"]
            if not opts.no_urdf:
                argv += ["--urdf", str(folder / "out.urdf")]
        visits, status = trace(argv)
    if status != 0:
        print(f"identify failed with status {status}", file=sys.stderr)
        return 1
    seen, again = reentries(visits)
    # the same with the utility and core modules transparent: a call into one of them does not
    # end its caller's visit
    flow = [v for v in visits if v not in UTILITY]
    flow = [v for k, v in enumerate(flow) if k == 0 or flow[k - 1] != v]
    fseen, fagain = reentries(flow)
    print("mindyn identify ROBOT fit.csv " + " ".join(argv[3:]).replace(tmp, "."))
    print(f"  files entered: {len(seen)}")
    print(f"  visits: {len(visits)}; re-entries (into a file already left): {sum(again.values())}")
    for name in sorted(seen):
        print(f"    {name:<40} re-entered {again[name]:4d} times")
    print(f"  without the utility and core modules ({', '.join(sorted(UTILITY))}):")
    print(f"  files entered: {len(fseen)}; visits: {len(flow)}; re-entries: {sum(fagain.values())}")
    for name in sorted(fseen):
        print(f"    {name:<40} re-entered {fagain[name]:4d} times")
    if opts.show:
        print("  visits in order:")
        for v in visits:
            print(f"    {v}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
