"""MuJoCo simulating an exported MJCF along a logged trajectory under computed torque.

Usage: python bench/bench_mjcf_tracking.py ROBOT.xml LOG.csv [--kp 100] [--kd 20]
       [--timestep 0.001] [--frictionloss]

The log's positions (columns q1..qN, time t) are interpolated by a cubic spline into the desired
q_d, dq_d, ddq_d. Each step the controller asks MuJoCo's own inverse dynamics of the file
(``mj_inverse`` at the measured state with the commanded acceleration ddq_d + kp e + kd de) for
the torque and applies it; MuJoCo integrates. Printed: the largest tracking error per joint and
over the whole run, and the time it took. A stable run keeps the error bounded and small; an
unstable model (an inertia that is not a body's, a negative armature) diverges.
"""

from __future__ import annotations

import argparse
import csv
import time

import numpy as np
from scipy.interpolate import CubicSpline


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mjcf")
    ap.add_argument("log")
    ap.add_argument("--kp", type=float, default=100.0, help="position gain [1/s^2]")
    ap.add_argument("--kd", type=float, default=20.0, help="velocity gain [1/s]")
    ap.add_argument("--timestep", type=float, default=0.001, help="MuJoCo's time step [s]")
    ap.add_argument(
        "--frictionloss",
        action="store_true",
        help="keep MuJoCo's frictionloss constraint (default: disabled in the plant and in the "
        "controller's model alike)",
    )
    args = ap.parse_args()

    import mindyn
    import mujoco

    robot = mindyn.load(args.mjcf)
    with open(args.log, newline="") as f:
        rows = list(csv.DictReader(f))
    t = np.array([float(r["t"]) for r in rows])
    q = np.array([[float(r[f"q{k + 1}"]) for k in range(robot.n)] for r in rows])
    spline = CubicSpline(t, q)
    m = mujoco.MjModel.from_xml_path(args.mjcf)
    m.opt.timestep = args.timestep
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    if not args.frictionloss:
        m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_FRICTIONLOSS)
    plant, ctl = mujoco.MjData(m), mujoco.MjData(m)
    adr = [int(m.jnt_qposadr[m.joint(n).id]) for n in robot.joint_names]
    dof = [int(m.jnt_dofadr[m.joint(n).id]) for n in robot.joint_names]
    plant.qpos[adr] = spline(t[0])
    plant.qvel[dof] = spline(t[0], 1)
    worst = np.zeros(robot.n)
    steps = int((t[-1] - t[0]) / args.timestep)
    start = time.perf_counter()
    for i in range(steps):
        s = t[0] + i * args.timestep
        qd, dqd, ddqd = spline(s), spline(s, 1), spline(s, 2)
        e, de = qd - plant.qpos[adr], dqd - plant.qvel[dof]
        worst = np.maximum(worst, np.abs(e))
        if not np.all(np.isfinite(e)) or np.max(np.abs(e)) > 10.0:
            print(f"diverged at t = {s:.3f} s (error {np.max(np.abs(e)):.3g})")
            return
        ctl.qpos[:], ctl.qvel[:] = plant.qpos, plant.qvel
        ctl.qacc[dof] = ddqd + args.kp * e + args.kd * de
        mujoco.mj_inverse(m, ctl)
        plant.qfrc_applied[:] = ctl.qfrc_inverse
        mujoco.mj_step(m, plant)
    took = time.perf_counter() - start
    print(f"{robot.name}: {steps} steps of {args.timestep} s ({t[-1] - t[0]:.1f} s), {took:.2f} s")
    print("largest tracking error per joint [rad | m]: " + " ".join(f"{x:.3g}" for x in worst))
    print(f"largest over the run: {worst.max():.3g}")


if __name__ == "__main__":
    main()
