"""Base parameters on odd geometry: every base set returned must regroup the inverse dynamics.

Generates robots whose geometry sits next to the special cases the rank decision has to see
(joint axes a little off a coordinate axis, right angles written rounded, lengths far from a
metre) and checks, for every base set any of the three methods returns, that

    W_b(q, dq, ddq) (Y pi) = tau(q, dq, ddq)

at random states, for the robot's own (physically consistent) parameters pi, with tau from the
classical inverse dynamics; a set that is refused must be refused with a one-line mindyn error.
The relative error is |W_b Y pi - tau| over the size of the terms tau sums, max_j sum_c
|W_jc pi_c| plus |g| sum_k |m_k c_k| (the gravity forces, which the inverse dynamics forms even
where their torques cancel): the rounding level of tau itself.

    .venv/bin/python fuzz/base_consistency.py COUNT SEED [--pinocchio K] [--tolerance T] [-v]

COUNT robots are drawn from SEED, each run through the projection, recursive and numerical
methods; the script prints the count of each outcome: ``consistent`` (returned, W_b Y pi = tau to
``--tolerance``, default 1e-9), ``refused`` (a mindyn error with its reason) and ``inconsistent``
(returned, and wrong) -- and, for the first K serial URDF robots (default 50), how far the
classical inverse dynamics is from Pinocchio's on the same file (robots whose links all weigh
more than 1e-9 kg: Pinocchio cannot hold smaller masses). Exit status 1 when any set is
inconsistent or any other exception escapes.
"""

from __future__ import annotations

import argparse
import collections
import re
import sys
import tempfile
import traceback
from pathlib import Path

import mindyn
import numpy as np

METHODS = ("projection", "recursive", "numerical")
# exact pi/2 and pi multiples, and the same written rounded as URDFs and DH tables write them
RIGHT = (0.0, np.pi / 2, np.pi, -np.pi / 2)
ROUNDED_RAD = (1.5708, 1.570796, 1.57, 3.14159, 3.1416, -1.5708, -3.14159)
ROUNDED_DEG = (89.99, 90.01, 89.9999, 179.99, -89.99, 45.0, 90.0, -90.0, 0.0)


def _f(x: float) -> str:
    return repr(float(x))


def _vec(v) -> str:
    return " ".join(_f(x) for x in v)


def odd_axis(rng: np.random.Generator) -> np.ndarray:
    """A coordinate axis (either sign), most often tilted by 1e-12 .. 1e-6 in one or two
    components."""
    a = np.zeros(3)
    i = int(rng.integers(3))
    a[i] = rng.choice([-1.0, 1.0])
    if rng.uniform() < 0.8:
        for j in rng.choice([k for k in range(3) if k != i], int(rng.integers(1, 3)), False):
            a[j] = rng.choice([-1.0, 1.0]) * 10 ** rng.uniform(-12, -6)
    return a  # written unnormalised, as a user would


def odd_angle(rng: np.random.Generator) -> float:
    """A rotation angle: exact right angle, rounded right angle, right angle + tiny, or any."""
    u = rng.uniform()
    if u < 0.35:
        return float(rng.choice(RIGHT))
    if u < 0.75:
        return float(rng.choice(ROUNDED_RAD))
    if u < 0.9:
        return float(rng.choice(RIGHT)) + rng.choice([-1, 1]) * 10 ** rng.uniform(-12, -6)
    return float(rng.uniform(-np.pi, np.pi))


def inertial(rng: np.random.Generator, scale: float) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass, centre of mass and inertia about it (rotated principal moments meeting the
    triangle inequalities) of a body about ``scale`` metres in size."""
    # masses small enough for the loader's bound of 1e16 on inertia entries
    mass = float(rng.uniform(0.3, 4.0)) * min(1.0, 1e14 / scale**2)
    while True:
        mom = rng.uniform(0.2, 1.0, 3) * mass * scale**2 / 12
        if 2 * mom.max() < mom.sum():
            break
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    com = rng.uniform(-0.5, 0.5, 3) * scale
    if rng.uniform() < 0.3:  # a centre of mass on an axis
        com[rng.integers(3)] = 0.0
    return mass, com, Q @ np.diag(mom) @ Q.T


def link_scales(rng: np.random.Generator, n: int) -> np.ndarray:
    """Length scale per link: one scale for the robot (1e-9 .. 1e9 m, or 1e16 m now and
    then), sometimes a different one per link."""
    u = rng.uniform()
    if u < 0.08:
        return np.full(n, 1e16)
    base = 10 ** rng.uniform(-9, 9)
    if u < 0.25:
        return base * 10 ** rng.uniform(-2, 2, n)
    return np.full(n, base)


def urdf_robot(rng: np.random.Generator, n: int, tree: bool, name: str) -> str:
    scales = link_scales(rng, n)
    parents = [int(rng.integers(0, k + 1)) if tree else k for k in range(n)]  # 0: the base
    links, joints = ['  <link name="base"/>'], []
    for k in range(n):
        s = scales[k]
        mass, com, inertia = inertial(rng, s)
        i = inertia
        links.append(
            f'  <link name="l{k + 1}"><inertial><origin xyz="{_vec(com)}" rpy="0 0 0"/>'
            f'<mass value="{_f(mass)}"/><inertia ixx="{_f(i[0, 0])}" ixy="{_f(i[0, 1])}" '
            f'ixz="{_f(i[0, 2])}" iyy="{_f(i[1, 1])}" iyz="{_f(i[1, 2])}" izz="{_f(i[2, 2])}"/>'
            "</inertial></link>"
        )
        xyz = rng.uniform(-1, 1, 3) * s
        for c in range(3):
            if rng.uniform() < 0.5:
                xyz[c] = 0.0
        rpy = [odd_angle(rng) for _ in range(3)]
        prismatic = rng.uniform() < 0.2
        kind = "prismatic" if prismatic else rng.choice(["revolute", "continuous"])
        parent = "base" if parents[k] == 0 else f"l{parents[k]}"
        limit = (
            f'<limit lower="{_f(-s)}" upper="{_f(s)}" effort="1" velocity="1"/>'
            if prismatic
            else '<limit lower="-3" upper="3" effort="1" velocity="1"/>'
            if kind == "revolute"
            else ""
        )
        joints.append(
            f'  <joint name="j{k + 1}" type="{kind}"><parent link="{parent}"/>'
            f'<child link="l{k + 1}"/><origin xyz="{_vec(xyz)}" rpy="{_vec(rpy)}"/>'
            f'<axis xyz="{_vec(odd_axis(rng))}"/>{limit}</joint>'
        )
    body = "\n".join(links + joints)
    return f'<?xml version="1.0"?>\n<robot name="{name}">\n{body}\n</robot>\n'


def dh_robot(rng: np.random.Generator, n: int, name: str) -> str:
    """A DH or MDH table (degrees) with twists rounded near right angles and odd lengths."""
    scales = link_scales(rng, n)
    convention = str(rng.choice(["dh", "mdh"]))
    lines = [f"name: {name}", f"convention: {convention}", "angle_unit: deg", "joints:"]
    for k in range(n):
        s = scales[k]
        mass, com, i = inertial(rng, s)
        alpha = float(rng.choice(ROUNDED_DEG)) if rng.uniform() < 0.8 else rng.uniform(-180, 180)
        a, d = (float(rng.choice([0.0, rng.uniform(0.1, 1.0) * s])) for _ in range(2))
        theta = float(rng.choice([0.0, 90.0, 89.99, -90.0]))
        lengths = f"a: {_f(a)}, d: {_f(d)}" if convention == "dh" else f"d: {_f(a)}, r: {_f(d)}"
        kind = "prismatic" if rng.uniform() < 0.15 else "revolute"
        lines.append(
            f"  - {{name: j{k + 1}, type: {kind}, alpha: {_f(alpha)}, {lengths}, "
            f"theta: {_f(theta)}, inertial: {{mass: {_f(mass)}, com: [{', '.join(map(_f, com))}], "
            f"inertia: {{xx: {_f(i[0, 0])}, yy: {_f(i[1, 1])}, zz: {_f(i[2, 2])}, "
            f"xy: {_f(i[0, 1])}, xz: {_f(i[0, 2])}, yz: {_f(i[1, 2])}}}}}}}"
        )
    return "\n".join(lines) + "\n"


def draw(rng: np.random.Generator, index: int, folder: Path) -> tuple[Path, str]:
    """Writes one random odd robot into ``folder``; returns its path and kind."""
    n = int(rng.integers(1, 7))
    u = rng.uniform()
    if u < 0.3:
        path = folder / f"odd{index}.yaml"
        path.write_text(dh_robot(rng, n, f"odd{index}"))
        return path, "table"
    tree = u < 0.6 and n >= 3
    path = folder / f"odd{index}.urdf"
    path.write_text(urdf_robot(rng, n, tree, f"odd{index}"))
    return path, "tree" if tree else "chain"


def consistency_error(robot: mindyn.Robot, bp, rng: np.random.Generator, states: int = 4) -> float:
    """Largest |W_b Y pi - tau| / max_j sum_c |W_jc pi_c| over random states."""
    pi = robot.parameters(rotor=bp.rotor, friction=bp.friction)
    lim = robot.limits
    lo = np.where(np.isfinite(lim["lower"]), lim["lower"], -np.pi)
    hi = np.where(np.isfinite(lim["upper"]), lim["upper"], np.pi)
    worst = 0.0
    pb = bp.values(pi)
    for _ in range(states):
        q = rng.uniform(lo, hi)
        dq, ddq = rng.uniform(-2, 2, (2, robot.n))
        W = robot.regressor(q, dq, ddq, rotor=bp.rotor, friction=bp.friction)
        tau = robot.inverse_dynamics(q, dq, ddq)
        # the size of the terms tau sums; the gravity forces m g c enter the inverse dynamics
        # even where their torques cancel exactly, and round at their own size
        scale = np.max(np.abs(W) @ np.abs(pi)) + np.linalg.norm(robot.gravity) * np.sum(
            np.abs(robot.params.reshape(-1, 10)[:, 6:9])
        )
        if scale == 0.0:
            continue
        err = bp.regressor(q, dq, ddq) @ pb - tau
        worst = max(worst, float(np.max(np.abs(err)) / scale))
    return worst


def pinocchio_error(path: Path, robot: mindyn.Robot, rng: np.random.Generator) -> float | None:
    """Relative difference of the classical inverse dynamics from Pinocchio's, same URDF."""
    try:
        import pinocchio as pin
    except ImportError:
        return None
    model = pin.buildModelFromUrdf(str(path))
    if model.nq != robot.n:
        return None
    data = model.createData()
    idx = [model.joints[model.getJointId(j)].idx_q for j in robot.joint_names]
    worst = 0.0
    for _ in range(3):
        q, dq, ddq = rng.uniform(-2, 2, (3, robot.n))
        qp, dqp, ddqp = (np.zeros(model.nq) for _ in range(3))
        qp[idx], dqp[idx], ddqp[idx] = q, dq, ddq
        ref = pin.rnea(model, data, qp, dqp, ddqp)[idx]
        ours = robot.inverse_dynamics(q, dq, ddq)
        W = robot.regressor(q, dq, ddq)
        scale = np.max(np.abs(W) @ np.abs(robot.params))
        worst = max(worst, float(np.max(np.abs(ours - ref)) / scale))
    return worst


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("count", type=int, help="number of robots to draw")
    p.add_argument("seed", type=int, help="random seed")
    p.add_argument("--tolerance", type=float, default=1e-9, help="relative bound (1e-9)")
    p.add_argument("--pinocchio", type=int, default=50, help="serial URDFs checked (50)")
    p.add_argument("--keep", type=Path, help="folder to keep the robots in")
    p.add_argument("-v", "--verbose", action="store_true", help="one line per finding")
    args = p.parse_args(argv)
    folder = args.keep or Path(tempfile.mkdtemp(prefix="mindyn-odd-"))
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(args.seed)
    counts: collections.Counter = collections.Counter()
    by_method: dict = collections.defaultdict(collections.Counter)
    reasons: collections.Counter = collections.Counter()
    worst_ok, pin_worst, pin_checked, flagged = 0.0, 0.0, 0, 0
    for i in range(args.count):
        path, kind = draw(rng, i, folder)
        try:
            robot = mindyn.load(path)
        except mindyn.Error as e:
            counts["robot refused at load"] += 1
            reasons[str(e).split(":")[-1].strip()[:70]] += 1
            continue
        # Pinocchio divides first moments by max(mass, eps): masses below 1e-9 kg it cannot hold
        masses = robot.params[9::10]
        if kind == "chain" and pin_checked < args.pinocchio and masses.min() > 1e-9:
            err = pinocchio_error(path, robot, rng)
            if err is not None:
                pin_checked += 1
                pin_worst = max(pin_worst, err)
        for method in METHODS:
            rotor = friction = bool(rng.uniform() < 0.3)
            try:
                bp = mindyn.base_parameters(
                    robot, method=method, rotor=rotor, friction=friction, snap=False
                )
                err = consistency_error(robot, bp, rng)
            except mindyn.Error as e:
                msg = str(e)
                outcome = "refused" if msg and "\n" not in msg else "refused without one line"
                counts[outcome] += 1
                by_method[method][outcome] += 1
                reasons[re.sub(r"-?\d[\d.e+-]*", "#", msg)[:150]] += 1
                continue
            except Exception:  # noqa: BLE001 - a finding, counted and shown
                counts["exception"] += 1
                by_method[method]["exception"] += 1
                if args.verbose:
                    print(f"{path} {method}: {traceback.format_exc(limit=2)}")
                continue
            ok = err <= args.tolerance
            outcome = "consistent" if ok else "inconsistent"
            counts[outcome] += 1
            by_method[method][outcome] += 1
            flagged += bool(bp.margin["near_degenerate"])
            if ok:
                worst_ok = max(worst_ok, err)
            elif args.verbose:
                print(f"{path} {method} rotor={rotor}: inconsistent, {err:.3g} relative")
    print(f"{args.count} robots (seed {args.seed}), files in {folder}")
    for method in METHODS:
        print(
            f"  {method:<11} " + ", ".join(f"{k} {v}" for k, v in sorted(by_method[method].items()))
        )
    total = sum(counts.values())
    print(
        f"  all         {total} base sets: returned-consistent {counts['consistent']}, "
        f"refused-with-reason {counts['refused']}, inconsistent {counts['inconsistent']}"
        + "".join(
            f", {k} {v}"
            for k, v in counts.items()
            if k not in ("consistent", "refused", "inconsistent")
        )
    )
    print(f"  largest error of a consistent set {worst_ok:.3g}; flagged near-degenerate {flagged}")
    if reasons:
        print("  reasons for refusing:")
        for r, c in reasons.most_common(6):
            print(f"    {c:>5}  {r}")
    if pin_checked:
        print(
            f"  Pinocchio: {pin_checked} serial URDFs, largest relative difference {pin_worst:.3g}"
        )
    bad = counts["inconsistent"] + counts["exception"] + counts["refused without one line"]
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
