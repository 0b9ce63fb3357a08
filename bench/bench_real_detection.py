"""Collision detection on real robot logs (all collision-free): thresholds calibrated on each
robot's identification log, false alarms on its validation log, and the smallest external torque
per joint that would be detected.

    .venv/bin/python bench/bench_real_detection.py DIR [--margin 1.5] [--model-sigma K]

``DIR`` is laid out as for bench/bench_real_identification.py (panda/, kuka_lwr4/, ur10e/; the
logs' torques in N m). Per robot: ``mindyn identify ROBOT FIT --friction --offset [--rotor]
--json ID.json`` (the same command lines as bench_real_identification.py, UR10e from its
currents), then ``mindyn detect ROBOT ID.json FIT --calibrate THR.json`` (the residual of the
logged torque, sampled, at the log's time stamps; default gain, the largest step permitting) and
``mindyn detect ROBOT ID.json VAL --thresholds THR.json``. Printed per joint: the threshold,
which is the smallest constant external torque the residual reaches above it (in steady state,
the residual otherwise at zero), the largest |r| on the validation log over the threshold, and
the alarms there (false alarms: the logs are collision-free).
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

UR10E_DRIVE_GAINS = (10.0, 10.6956, 8.4566, 9.0029, 9.48, 10.1232)

CASES = [
    (
        "Panda",
        "panda/panda_gaz2019.yaml",
        "panda/panda_gaz2019_traj1_fit_period1.csv",
        "panda/panda_gaz2019_traj1_val_repeat.csv",
        [],
    ),
    (
        "KUKA LWR4+",
        "kuka_lwr4/kuka_lwr4.urdf",
        "kuka_lwr4/lwr4_meas3_trajB.csv",
        "kuka_lwr4/lwr4_meas1_trajA_run1.csv",
        [],
    ),
    (
        "UR10e",
        "ur10e/ur10e.urdf",
        "ur10e/ur10e_fit_30sec_12harm.csv",
        "ur10e/ur10e_val_ptp_10_points.csv",
        [
            "--rotor",
            "--currents",
            "{dir}/ur10e/ur10e_fit_30sec_12harm_raw_currents.csv",
            "--drive-gain",
            ",".join(map(str, UR10E_DRIVE_GAINS)),
        ],
    ),
]


def mindyn(*args) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mindyn", *args], capture_output=True, text=True)


def residual_lines(out: str) -> list[float]:
    """The largest |r| per joint of detect's output."""
    return [float(m.group(1)) for m in re.finditer(r"^\s+\d+: ([0-9.e+-]+) /", out, re.M)]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dir", type=Path, help="folder with panda/, kuka_lwr4/, ur10e/")
    ap.add_argument("--margin", type=float, default=1.5, help="thresholds: margin x max |r|")
    ap.add_argument(
        "--model-sigma", type=float, default=0.0, help="as detect --model-sigma (0: off)"
    )
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for k, (name, robot, fit, val, extra) in enumerate(CASES):
            ident = Path(tmp) / f"id{k}.json"
            thr = Path(tmp) / f"thr{k}.json"
            robot_path = str(args.dir / robot)
            cmd = [
                "identify",
                robot_path,
                str(args.dir / fit),
                "--friction",
                "--offset",
                *[x.format(dir=args.dir) for x in extra],
                "--json",
                str(ident),
            ]
            print(f"{name}\n  $ mindyn {' '.join(cmd)}", flush=True)
            run = mindyn(*cmd)
            if run.returncode != 0:
                print("  identify refused: " + (run.stderr.strip().splitlines() or ["?"])[-1])
                continue
            cal = [
                "detect",
                robot_path,
                str(ident),
                str(args.dir / fit),
                "--calibrate",
                str(thr),
                "--margin",
                str(args.margin),
                "--model-sigma",
                str(args.model_sigma),
            ]
            print(f"  $ mindyn {' '.join(cal)}", flush=True)
            run = mindyn(*cal)
            if run.returncode != 0:
                print("  detect refused: " + (run.stderr.strip().splitlines() or ["?"])[-1])
                continue
            gains = [ln for ln in run.stdout.splitlines() if "gains K_O" in ln]
            print("  " + (gains[0].strip() if gains else ""))
            thresholds = json.loads(thr.read_text())["thresholds"]
            run = mindyn(
                "detect", robot_path, str(ident), str(args.dir / val), "--thresholds", str(thr)
            )
            if run.returncode not in (0, 1):
                print("  detect refused: " + (run.stderr.strip().splitlines() or ["?"])[-1])
                continue
            rmax = residual_lines(run.stdout)
            alarms = [
                ln.strip() for ln in run.stdout.splitlines() if ln.strip().startswith("joint ")
            ]
            print(f"  validation {val}: {len(alarms)} false alarm interval(s)")
            print(f"  {'joint':>7}{'threshold [N m]':>17}{'max |r| val / thr':>19}{'alarms':>8}")
            for j, t in enumerate(thresholds):
                count = sum(1 for a in alarms if a.startswith(f"joint {j + 1}:"))
                ratio = rmax[j] / t if j < len(rmax) else float("nan")
                print(f"  {j + 1:>7}{t:>17.3g}{ratio:>19.2f}{count:>8}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
