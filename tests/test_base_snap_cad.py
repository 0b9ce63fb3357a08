"""The default snap on descriptions exported from CAD: rotations and axes written with 7 or 8
significant digits or in single precision (``1.5707963``, ``1.57079637``, an axis
``(-1, 8.5e-11, 7e-8)``), off their right angles by 1e-11 .. a few 1e-6 rad. With no options
they give the base set of the exact geometry (their exact twin, written here with the right
angles exact: the numerical method's count and the rank of Pinocchio's regressor), and its
torques are Pinocchio's ``rnea`` on the exact twin; a deliberate tilt is never rounded."""

from __future__ import annotations

import math
import re

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import cli
from mindyn.identification import run
from test_base_snap_auto import simulated_log

HALF_PI = math.pi / 2
# (xyz, rpy exact, rpy as CAD writes it, axis exact, axis as CAD writes it) of a UR-like arm
ARM = [
    ("0 0 0.089", (0, 0, 0), "0 0 0", "0 0 1", "-8.5e-11 7e-08 1"),
    ("0 0.136 0", (0, HALF_PI, 0), "0 1.5707963 0", "0 1 0", "3.1e-08 1 -2.2e-08"),
    ("0 -0.12 0.425", (0, 0, 0), "0 0 0", "0 1 0", "0 1 0"),
    ("0 0 0.392", (0, HALF_PI, 0), "0 1.57079637 0", "0 1 0", "4.37e-08 1 0"),
    ("0 0.093 0", (0, 0, 0), "0 0 0", "0 0 1", "0 0 1"),
    ("0 0 0.095", (HALF_PI, 0, -HALF_PI), "1.5707964 0 -1.5707963", "-1 0 0", "-1 8.5e-11 7e-08"),
]
# a branch on the third link: a small tree
BRANCH = (
    "0.1 0.05 0.2",
    (math.pi, 0, HALF_PI),
    "3.1415927 0 1.5707963",
    "0 0 -1",
    "2e-08 -5e-08 -1",
)


def worse(text: str) -> str:
    """The same numbers written with 7 significant digits and tilts of up to 3e-6 rad."""
    return {
        "1.5707963": "1.570797",
        "1.57079637": "1.570796",
        "1.5707964": "1.570797",
        "3.1415927": "3.141594",
        "7e-08": "2.9e-06",
        "-5e-08": "-8e-07",
        "3.1e-08": "4e-07",
    }.get(text, text)


def inertial(k: int) -> str:
    """A full, off-centre inertial of link ``k`` (different per link)."""
    m, c = 1.0 + 0.3 * k, (0.02 * k - 0.05, 0.03 - 0.01 * k, 0.04 + 0.01 * k)
    return (
        f'<inertial><origin xyz="{c[0]} {c[1]} {c[2]}"/><mass value="{m}"/><inertia '
        f'ixx="{0.02 + 0.003 * k}" ixy="0.001" ixz="-0.002" iyy="{0.03 + 0.002 * k}" '
        f'iyz="0.0015" izz="{0.025 + 0.004 * k}"/></inertial>'
    )


def arm_urdf(*, cad: bool, tree: bool = False, write=str, tilt: float = 0.0) -> str:
    """The arm (with the branch when ``tree``): its rotations and axes as CAD writes them
    (through ``write``), or exact (the right angles as the doubles nearest them); with ``tilt``,
    the first joint's axis tilted by that many rad off the vertical in both."""
    joints = ARM + ([BRANCH] if tree else [])
    parents = [0, 1, 2, 3, 4, 5, 3][: len(joints)]
    out = []
    for k, ((xyz, rpy, rpy_cad, axis, axis_cad), parent) in enumerate(zip(joints, parents)):
        rpy_text = " ".join(write(x) for x in rpy_cad.split()) if cad else " ".join(map(repr, rpy))
        axis_text = " ".join(write(x) for x in axis_cad.split()) if cad else axis
        if k == 0 and tilt:
            axis_text = f"{math.sin(tilt)!r} 0 {math.cos(tilt)!r}"
        out.append((parent, "revolute", xyz, rpy_text, axis_text))
    return urdf(out)


def urdf(joints) -> str:
    """A URDF of the ``joints`` (parent link, type, xyz, rpy, axis), link k the child of joint
    k, every link with an inertial of its own."""
    links = [f'<link name="l{k}">{inertial(k)}</link>' for k in range(len(joints) + 1)]
    out = []
    for k, (parent, kind, xyz, rpy, axis) in enumerate(joints):
        limit = "" if kind == "continuous" else ' lower="-2" upper="2"'
        out.append(
            f'<joint name="j{k + 1}" type="{kind}"><origin xyz="{xyz}" rpy="{rpy}"/>'
            f'<parent link="l{parent}"/><child link="l{k + 1}"/><axis xyz="{axis}"/>'
            f'<limit{limit} effort="50" velocity="3"/></joint>'
        )
    return '<robot name="arm">\n' + "\n".join(links + out) + "\n</robot>\n"


def written(tmp_path, name: str, text: str):
    path = tmp_path / name
    path.write_text(text)
    return path


def pinocchio_rank(model: pin.Model, rng, states: int = 60) -> int:
    """Rank of Pinocchio's stacked joint-torque regressor at random states (relative singular
    value tolerance 1e-8)."""
    data = model.createData()
    rows = [
        pin.computeJointTorqueRegressor(model, data, *(rng.uniform(-2, 2, model.nv) for _ in "qva"))
        for _ in range(states)
    ]
    s = np.linalg.svd(np.vstack(rows), compute_uv=False)
    return int(np.sum(s > 1e-8 * s[0]))


def pinocchio_order(x: np.ndarray, idx: list[int]) -> np.ndarray:
    """``x`` (mindyn's joint order) in Pinocchio's: joint k at ``idx[k]``."""
    out = np.empty_like(x)
    out[idx] = x
    return out


CASES = [(False, str), (True, str), (False, worse), (True, worse)]
IDS = ["6R-8-digits", "tree-8-digits", "6R-7-digits", "tree-7-digits"]


@pytest.mark.parametrize("tree, write", CASES, ids=IDS)
def test_a_cad_rounded_arm_gives_the_exact_twins_base_set_by_default(tmp_path, rng, tree, write):
    exact_path = written(tmp_path, "exact.urdf", arm_urdf(cad=False, tree=tree))
    cad_path = written(tmp_path, "cad.urdf", arm_urdf(cad=True, tree=tree, write=write))
    model = pin.buildModelFromUrdf(str(exact_path))
    count = mindyn.base_parameters(exact_path, method="numerical", snap=False).n
    assert count == pinocchio_rank(model, rng)

    robot = mindyn.load(cad_path)
    # the description as written: the tilts are geometry to the rank decision (more
    # parameters, or a regrouping that misses the dynamics)
    try:
        assert mindyn.base_parameters(robot, method="numerical", snap=False).n > count
    except mindyn.ModelError as e:
        assert "does not reproduce the dynamics" in str(e)
    data = model.createData()
    idx = [model.joints[model.getJointId(name)].idx_v for name in robot.joint_names]
    for method in ("projection", "recursive", "numerical"):
        bp = mindyn.base_parameters(robot, method=method)
        d = bp.snap_decision
        assert bp.n == count, (method, d)
        assert d["applied"] and not d["real"] and not bp.margin["near_degenerate"]
        assert d["largest_rounding"] <= mindyn.base.SNAP_AUTO_BOUND
        # the safety check is stated with its bound: 100 times the largest rounding
        assert (
            d["check"] <= d["check_bound"] == pytest.approx(100 * d["largest_rounding"], rel=1e-3)
        )
        assert "reproduces the description's torques to" in bp.snap_report()[0]
        pb = bp.values(robot.params)
        for _ in range(3):
            q, dq, ddq = (rng.uniform(-2, 2, robot.n) for _ in range(3))
            tau = pin.rnea(model, data, *(pinocchio_order(x, idx) for x in (q, dq, ddq)))[idx]
            error = np.max(np.abs(bp.regressor(q, dq, ddq) @ pb - tau)) / np.max(np.abs(tau))
            # snapped to the exact geometry: round-off, far inside the stated check bound
            assert error <= min(1e-9, d["check_bound"]), (method, error)


def test_the_command_line_runs_a_cad_rounded_arm_with_no_options(tmp_path):
    """``mindyn base ROBOT.urdf`` (no option) on the CAD-rounded arm: exit 0, the snap stated in
    the report's wording, no near-degenerate warning."""
    path = written(tmp_path, "cad.urdf", arm_urdf(cad=True, write=worse))
    out = cli("base", path)  # fails on a non-zero exit
    assert "right angle(s) written rounded" in out and "WARNING" not in out


def test_identification_of_a_cad_rounded_arm_runs_with_defaults_and_matches_the_truth(
    tmp_path, rng
):
    """Identification with no options on the CAD-rounded arm (7 significant digits) and a log
    it simulates (1 % torque noise): the base set of the exact twin, every estimate within 5
    sigma of the true base value (the snap moves the torques by about 1e-6, relatively: far
    below the noise), the snap stated in the header."""
    exact = mindyn.base_parameters(
        written(tmp_path, "exact.urdf", arm_urdf(cad=False)), method="numerical", snap=False
    )
    robot = mindyn.load(written(tmp_path, "cad.urdf", arm_urdf(cad=True, write=worse)))
    report = run(robot, simulated_log(robot, rng), rsd_threshold=0.0)
    base, res = report.base, report.result
    assert base.n == exact.n and base.snap_decision["applied"]
    truth = base.values(robot.params)
    est, std = np.asarray(res.values), np.asarray(res.std)
    assert np.all(np.abs(est - truth) <= 5 * std + 1e-9 * np.abs(truth).max())
    assert any("base set: " in x and "right angle(s)" in x for x in report.format().splitlines())


# Floating-base robots with CAD-rounded rotations and axes beside right angles written with
# three decimals (1.571, 2.04e-4 rad off): a rotation composed of such angles is read back off
# its right angles by sums of them, which no single decimal rounding matches.
FLOATING = {
    "tree": [  # three branches on the first link
        (0, "continuous", "0.1 -0.2 0.05", "1.7681 0.5532 2.1488", "0 0 1"),
        (1, "revolute", "0.2 0.1 -0.1", "1.57079633 0 0.7854", "0 0 1"),
        (1, "revolute", "-0.1 0.2 0.07", "1.57079633 3.14159 0.7854", "-0.5953 0.1572 0.1072"),
        (1, "revolute", "0 -0.15 -0.2", "1.571 0 1.57079633", "8.0615470097133e-09 1 -1.6e-07"),
    ],
    "chain": [
        (0, "continuous", "0.3 0.2 0", "1.8695 -1.0751 -2.8487", "-0.5493 0.0823 0.8308"),
        (1, "continuous", "0.4 0.3 0.2", "3.1416 3.1416 -3.14159", "0 0 1"),
        (2, "prismatic", "0.05 -0.2 0.3", "0 -1.5708 1.5708", "-0.1524 -0.0293 0.0450"),
        (3, "continuous", "0.1 0.4 -0.3", "1.571 1.571 1.571", "-1 0 1.0302886029988551e-08"),
        (4, "prismatic", "0.2 -0.1 0.05", "2.1423 2.6238 -2.3576", "1.7896711696575939e-09 1 0"),
        (5, "continuous", "0 0.12 0.3", "0.7854 1.57079633 1.5708", "6.09e-10 -1 -1.465e-09"),
        (6, "prismatic", "-0.2 0.1 0.3", "1.571 0.7854 -3.14159", "0 -7.701416862972695e-12 -1"),
    ],
}


def floating_urdf(joints, *, exact: bool) -> str:
    """The robot of ``joints`` (parent, type, xyz, rpy, axis); ``exact``: every rpy angle within
    1e-3 of a right angle written as that right angle, every axis component within 1e-3 of zero
    as 0."""

    def fix(text: str, angle: bool) -> str:
        def number(m: re.Match) -> str:
            x = float(m.group(0))
            k = round(x / HALF_PI) if angle else 0
            return repr(k * HALF_PI) if abs(x - k * HALF_PI) <= 1e-3 else m.group(0)

        return re.sub(r"-?[\d.]+(?:e-?\d+)?", number, text) if exact else text

    return urdf(
        [(p, kind, xyz, fix(rpy, True), fix(axis, False)) for p, kind, xyz, rpy, axis in joints]
    )


@pytest.mark.parametrize("kind", sorted(FLOATING))
def test_a_rounded_floating_base_robot_gives_the_exact_twins_count(tmp_path, kind):
    """On a free-flyer, the three methods with the default snap give the base count of the
    exact twin (the numerical method on it, nothing snapped), none near-degenerate, the snap
    checked against the description's multibody torques."""
    joints = FLOATING[kind]
    exact = written(tmp_path, "exact.urdf", floating_urdf(joints, exact=True))
    rounded = written(tmp_path, "rounded.urdf", floating_urdf(joints, exact=False))
    twin = mindyn.load(exact, root_joint="floating")
    count = mindyn.base_parameters(twin, method="numerical", snap=False).n
    robot = mindyn.load(rounded, root_joint="floating")
    for method in ("projection", "recursive", "numerical"):
        bp = mindyn.base_parameters(robot, method=method)
        d = bp.snap_decision
        assert bp.n == count, (method, d)
        assert d["applied"] and not bp.margin["near_degenerate"], (method, d)
        assert d["check"] is not None and d["check"] <= d["check_bound"]


@pytest.mark.parametrize("tilt", [1e-2, 1.5e-3])
def test_a_genuinely_tilted_axis_is_never_snapped(tmp_path, rng, tilt):
    """The CAD-rounded arm with its first axis tilted by ``tilt`` rad off the vertical, and
    right angles written 1.57 (8e-4 rad off: a description that coarse rounds everything within
    2.4e-3 rad of a right angle, up to 1e-3 rad): the tilt is kept, so the count is that of the
    exact arm with the same tilt, above the untilted one, and the snap lists nothing of that
    joint's axis (a snap tolerance of twice the 1.57's rounding, 1.6e-3, would have rounded a
    tilt of 1.5e-3 away)."""

    def coarse(text: str) -> str:
        return "1.57" if text == "1.5707963" else text

    tilted = written(tmp_path, "tilted.urdf", arm_urdf(cad=False, tilt=tilt))
    plain = written(tmp_path, "plain.urdf", arm_urdf(cad=False))
    cad = written(tmp_path, "cad.urdf", arm_urdf(cad=True, write=coarse, tilt=tilt))
    count = mindyn.base_parameters(tilted, method="numerical", snap=False).n
    assert count == pinocchio_rank(pin.buildModelFromUrdf(str(tilted)), rng)
    assert count > mindyn.base_parameters(plain, method="numerical", snap=False).n
    bp = mindyn.base_parameters(cad)
    d = bp.snap_decision
    assert d["applied"] and d["bound"] == pytest.approx(3 * (HALF_PI - 1.57), rel=1e-6)
    assert d["tolerance"] < tilt
    assert bp.n == count
    assert not any("j1' axis" in what for what, _ in d["rounded"] + d["real"])
    assert not any("joint 'j1' axis" in line for line in bp.snapped)
