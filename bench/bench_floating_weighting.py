"""Floating-base identification, ordinary against weighted least squares: time, peak memory and
how well each fit's standard deviations describe its error.

    .venv/bin/python bench/bench_floating_weighting.py [--robot talos] [--samples 1000]
        [--logs 1] [--noise TAU FORCE MOMENT]

A log of SAMPLES random states of an example-robot-data robot on a free-flyer (talos on its two
feet, solo12 on its four) is simulated with mindyn: the generalized forces of the description's
parameters, the root's carried by the feet's wrenches (random, corrected by the least-norm wrench
that balances the root), the joints' torques the rest, then Gaussian noise of the standard
deviations TAU (joint torques), FORCE and MOMENT (the wrenches'). Each log is identified with
``identify_floating(..., weighted=False)`` and with the default weights; printed: the wall-clock
and CPU seconds, the peak of the memory numpy allocates during the fit (tracemalloc), the RMS of
``(estimate - truth) / std`` over the base values and the fraction within 3, pooled over the
LOGS logs, and the weighting the fit states.
"""

from __future__ import annotations

import argparse
import time
import tracemalloc
from pathlib import Path

import numpy as np

FEET = {
    "talos": ["leg_left_6_link", "leg_right_6_link"],
    "solo12": ["FL_LOWER_LEG", "FR_LOWER_LEG", "HL_LOWER_LEG", "HR_LOWER_LEG"],
}
URDF = {
    "talos": ("talos_data", "robots", "talos_reduced.urdf"),
    "solo12": ("solo_description", "robots", "solo12.urdf"),
}


def urdf(name: str) -> Path:
    import pinocchio

    robots = Path(pinocchio.__file__).parents[4] / "share" / "example-robot-data" / "robots"
    return robots.joinpath(*URDF[name])


def simulate(robot, feet, rng, m: int, noise: tuple[float, float, float]):
    from mindyn.identification.floating import FloatingLog, contact_jacobian

    r = 6
    q = np.empty((m, robot.nq))
    quat = rng.normal(size=(m, 4))
    q[:, :3] = rng.uniform(-1, 1, (m, 3))
    q[:, 3:7] = quat / np.linalg.norm(quat, axis=1)[:, None]
    q[:, 7:] = rng.uniform(-1.5, 1.5, (m, robot.nq - 7))
    dq, ddq = rng.uniform(-2, 2, (2, m, robot.nv))
    F = np.asarray(robot.inverse_dynamics(q, dq, ddq)).reshape(m, robot.nv)
    tau = np.empty((m, robot.nv - r))
    wrenches = {c: np.empty((m, 6)) for c in feet}
    scale = np.tile([noise[1]] * 3 + [noise[2]] * 3, len(feet))
    for i in range(m):
        A = np.hstack([contact_jacobian(robot, q[i], c).T for c in feet])
        f = rng.normal(0.0, 5.0, A.shape[1])
        f += np.linalg.pinv(A[:r]) @ (F[i, :r] - A[:r] @ f)
        tau[i] = (F[i] - A @ f)[r:] + rng.normal(0.0, noise[0], robot.nv - r)
        f = f + scale * rng.normal(size=f.shape)
        for k, c in enumerate(feet):
            wrenches[c][i] = f[6 * k : 6 * k + 6]
    return FloatingLog(q, dq, ddq, tau, wrenches)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robot", choices=sorted(FEET), default="talos")
    ap.add_argument("--samples", type=int, default=1000)
    ap.add_argument("--logs", type=int, default=1)
    ap.add_argument("--noise", type=float, nargs=3, default=(0.01, 1.0, 0.1))
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()

    import mindyn
    from mindyn.identification.floating import identify_floating

    robot = mindyn.load(urdf(args.robot), root_joint="floating")
    base = mindyn.base_parameters(robot, method="numerical")
    truth = base.values(robot.params)
    rng = np.random.default_rng(args.seed)
    print(
        f"{args.robot}: nv {robot.nv}, {base.n} base parameters, {args.logs} log(s) of "
        f"{args.samples} samples; noise: torques {args.noise[0]:g} N m, forces "
        f"{args.noise[1]:g} N, moments {args.noise[2]:g} N m"
    )
    z: dict[bool, list] = {False: [], True: []}
    for _ in range(args.logs):
        log = simulate(robot, FEET[args.robot], rng, args.samples, tuple(args.noise))
        for weighted in (False, True):
            tracemalloc.start()
            wall, cpu = time.perf_counter(), time.process_time()
            res = identify_floating(robot, log, base=base, weighted=weighted)
            wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
            peak = tracemalloc.get_traced_memory()[1] / 1e6
            tracemalloc.stop()
            z[weighted].append((res.values - truth) / res.std)
            print(
                f"  {'weighted' if weighted else 'ordinary'}: {wall:.2f} s wall, {cpu:.2f} s "
                f"CPU, peak {peak:.1f} MB; {res.weighting}"
            )
    for weighted in (False, True):
        zz = np.concatenate(z[weighted])
        print(
            f"{'weighted' if weighted else 'ordinary'}: RMS of (estimate - truth) / std "
            f"{np.sqrt(np.mean(zz**2)):.3f}, within 3: {np.mean(np.abs(zz) <= 3):.3f}"
        )


if __name__ == "__main__":
    main()
