"""The modules one ``mindyn identify`` run enters, call by call, and how often it comes back.

    .venv/bin/python bench/trace_identify_flow.py [--robot examples/urdf/ur5.urdf] [--rate 50]
        [--no-consistent] [--no-validate] [--no-urdf] [--show]

Generates a fit log and a validation log (inverse dynamics along random Fourier trajectories
with torque noise, in a temporary folder), then runs, in this process,

    mindyn identify ROBOT fit.csv --validate val.csv --consistent --urdf out.urdf --json id.json

under ``sys.setprofile``. A call into a file of the ``mindyn`` package none of whose frames is
active enters that file; consecutive entries into one file are one visit. Printed: the number of
distinct files entered, the number of re-entries (a visit to a file the flow had already left:
every frame of it returned, then a call back into it after visits to other files), and the
re-entries per file. A file calling its own functions, or being returned to, does not re-enter it;
module bodies run by imports are left out (they are loading, not the flow). The counts are
printed three ways: every call; with the utility and core modules (robot, base parameters,
argument checks) left out, a call into one not ending its caller's visit; and the workflow's own
flow, the calls made by the command line's modules and the workflow modules (the code between
the command line and the algorithms; what the algorithms call in turn is left out). ``--show``
prints the visits of the last in order.
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


# Modules every concern calls into (the robot, base parameters, the log type, argument checks,
# threads, the command line's argument and output-file helpers): their re-entries are reported
# apart.
UTILITY = {
    "_args.py",
    "_mujoco.py",
    "_threads.py",
    "_version.py",
    "base.py",
    "robot.py",
    "identification/joint_data.py",
    "cli/args.py",
    "cli/flags.py",
    "cli/number_options.py",
    "cli/outputs.py",
    "cli/quiet.py",
    "cli/robot_options.py",
}


class _Workflow(set):
    """The command line's files and the workflow modules of the identification."""

    def __contains__(self, name) -> bool:
        return name.startswith("cli/") or super().__contains__(name)


WORKFLOW = _Workflow(
    {
        "cli/*.py",
        "identification/options.py",
        "identification/reading.py",
        "identification/summary.py",
        "identification/terminal.py",
        "identification/terminal_consistent.py",
        "identification/terminal_header.py",
        "identification/workflow.py",
    }
)


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


def trace(argv: list[str]) -> tuple[list[tuple[str, str | None]], int]:
    """The calls into the package's files, in order, each as (its file, its caller's file or
    None), consecutive repeats of a pair left out; and the exit status."""
    from mindyn.cli import main

    calls: list[tuple[str, str | None]] = []
    names: dict[str, str | None] = {}  # file of a code object -> its name in the package

    def package_name(filename: str) -> str | None:
        if filename not in names:
            path = Path(filename).resolve()
            names[filename] = (
                str(path.relative_to(PACKAGE)) if path.is_relative_to(PACKAGE) else None
            )
        return names[filename]

    stack: list[str | None] = []  # the package file of each active frame (None: outside)

    def caller(back) -> str | None:
        """The package file that made a call: the nearest frame in the package outside the
        utility modules (a call through a decorator or a helper is its caller's)."""
        while back is not None:
            name = package_name(back.f_code.co_filename)
            if name is not None and name not in UTILITY:
                return name
            back = back.f_back
        return None

    def profile(frame, event, arg):
        if event == "return":
            if stack:
                stack.pop()
            return
        if event != "call":
            return
        name = package_name(frame.f_code.co_filename)
        entered = name is not None and name not in stack and frame.f_code.co_name != "<module>"
        stack.append(name)
        if not entered:
            return
        pair = (name, caller(frame.f_back))
        if not calls or calls[-1] != pair:
            calls.append(pair)

    out = io.StringIO()
    sys.setprofile(profile)
    try:
        with contextlib.redirect_stdout(out):
            status = main(argv)
    finally:
        sys.setprofile(None)
    return calls, status


def collapsed(names: list[str]) -> list[str]:
    return [v for k, v in enumerate(names) if k == 0 or names[k - 1] != v]


def show(title: str, visits: list[str], listing: bool) -> None:
    seen, again = reentries(visits)
    print(title)
    print(
        f"  files entered: {len(seen)}; visits: {len(visits)}; re-entries (into a file already "
        f"left): {sum(again.values())}"
    )
    for name in sorted(seen):
        print(f"    {name:<40} re-entered {again[name]:4d} times")
    if listing:
        print("  visits in order: " + " > ".join(visits))


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
        calls, status = trace(argv)
    if status != 0:
        print(f"identify failed with status {status}", file=sys.stderr)
        return 1
    print("mindyn identify ROBOT fit.csv " + " ".join(argv[3:]).replace(tmp, "."))
    show("every call into the package:", collapsed([f for f, _ in calls]), False)
    useful = [(f, c) for f, c in calls if f not in UTILITY]
    show(
        f"the utility and core modules left out ({', '.join(sorted(UTILITY))}):",
        collapsed([f for f, _ in useful]),
        False,
    )
    layer = [(f, c) for f, c in useful if f in WORKFLOW or (c is not None and c in WORKFLOW)]
    show(
        "the workflow's own flow: the calls made by the command line and the workflow modules "
        f"({', '.join(sorted(WORKFLOW - {'cli/*.py'}))}, cli/*.py), utility and core modules "
        "left out:",
        collapsed([f for f, _ in layer]),
        opts.show,
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
