"""When ``mindyn ik`` fails on a pose, it suggests ``--position-only`` for a tool whose pose
moves in fewer than six independent directions: the rank of the tool frame's Jacobian over the
joints that move it (``pose_rank``), not the joint count. A six-joint robot that cannot reach
a full pose (a planar arm, a five-joint arm with a last joint coaxial with the one before) got
no hint. The rank is checked against the rank of the tool pose's derivatives by central
differences of the forward kinematics, and with Pinocchio's frame Jacobian."""

from __future__ import annotations

import mindyn
import numpy as np
import pytest
from mindyn.cli import main
from mindyn.inverse_kinematics import pose_rank

HINT = "--position-only leaves the orientation free"

#: A five-joint arm: pan, lift, elbow, wrist flex, wrist roll (name, parent, child, xyz, axis)
ARM = [
    ("pan", "base", "shoulder", "0 0 0.1", "0 0 1"),
    ("lift", "shoulder", "upper", "0 0 0.1", "0 1 0"),
    ("elbow", "upper", "lower", "0 0 0.3", "0 1 0"),
    ("flex", "lower", "wrist", "0 0 0.3", "0 1 0"),
    ("roll", "wrist", "hand", "0 0 0.1", "0 0 1"),
]


def urdf(name: str, joints) -> str:
    """A URDF of revolute ``joints`` (limits +-2 rad), a 1-kg body on each link."""
    links = {"base"} | {j[1] for j in joints} | {j[2] for j in joints}
    inertial = (
        '<inertial><mass value="1"/><origin xyz="0 0 0.05"/>'
        '<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>'
    )
    out = [f'<robot name="{name}">'] + [
        f'<link name="{k}">{inertial}</link>' for k in sorted(links)
    ]
    for joint, parent, child, xyz, axis in joints:
        out.append(
            f'<joint name="{joint}" type="revolute"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin xyz="{xyz}"/><axis xyz="{axis}"/>'
            '<limit lower="-2" upper="2" effort="10" velocity="2"/></joint>'
        )
    return "\n".join([*out, "</robot>"])


def fd_rank(robot, samples: int = 8, seed: int = 1, h: float = 1e-6) -> int:
    """The largest rank of the tool pose's derivatives over the joints, by central differences
    of the forward kinematics (translation, and the rotation's R' R^T), at random
    configurations within the limits."""
    rng = np.random.default_rng(seed)
    best = 0
    for _ in range(samples):
        q = rng.uniform(robot.limits["lower"], robot.limits["upper"])
        R = robot.fk(q)[:3, :3]
        cols = []
        for j in range(robot.n):
            e = np.zeros(robot.n)
            e[j] = h
            d = (robot.fk(q + e) - robot.fk(q - e)) / (2 * h)
            W = d[:3, :3] @ R.T  # skew: the angular velocity of a unit joint velocity
            cols.append(np.concatenate([d[:3, 3], [W[2, 1], W[0, 2], W[1, 0]]]))
        s = np.linalg.svd(np.array(cols).T, compute_uv=False)
        best = max(best, int((s > 1e-6 * s[0]).sum()))
    return best


@pytest.fixture(scope="module")
def robots(tmp_path_factory):
    d = tmp_path_factory.mktemp("ik_hint")
    gripper = ("gripper", "wrist", "jaw", "0.02 0 0.05", "1 0 0")
    files = {
        # a five-joint arm and a gripper joint on a branch of its own off the wrist
        "tree": urdf("tree", [*ARM, gripper]),
        # the arm and a sixth joint turning about the roll axis (coaxial with it)
        "coaxial": urdf("coaxial", [*ARM, ("spin", "hand", "tip", "0 0 0.05", "0 0 1")]),
        # the arm and its gripper's jaw as the last link, as a URDF of a so101 loads
        "jaw": urdf("jaw", [*ARM, ("gripper", "hand", "jaw", "0.02 0 0.05", "1 0 0")]),
    }
    for name, text in files.items():
        (d / f"{name}.urdf").write_text(text)
    return {name: str(d / f"{name}.urdf") for name in files}


def test_pose_rank_is_the_rank_of_the_tool_pose_derivatives(robots):
    cases = {
        "puma560": (6, 6),
        "planar6": (3, 6),
        robots["coaxial"]: (5, 6),
        robots["jaw"]: (6, 6),
    }
    for source, (rank, n) in cases.items():
        robot = mindyn.load(source)
        assert robot.n == n and pose_rank(robot) == (rank, list(range(n))), source
        assert fd_rank(robot) == rank, source


def test_a_joint_off_the_tools_chain_does_not_count(robots):
    """The gripper joint of the tree moves its jaw, not the tool (the hand): its Jacobian
    column is zero, and the tool's pose has the five directions of the arm."""
    robot = mindyn.load(robots["tree"])
    assert not robot.is_serial and robot.n == 6 and robot.link_names[-1] == "hand"
    gripper = robot.joint_names.index("gripper")
    rank, moving = pose_rank(robot)
    assert rank == 5 and moving == [j for j in range(6) if j != gripper]
    q = np.random.default_rng(2).uniform(-1, 1, robot.n)
    e = np.zeros(robot.n)
    e[gripper] = 0.3
    np.testing.assert_allclose(robot.fk(q + e), robot.fk(q), atol=1e-15)  # off the chain
    # the chain to the hand: the five joints, whose pose ik then solves for
    arm = mindyn.load(robots["tree"], tip="hand")
    assert arm.n == 5 and pose_rank(arm) == (5, list(range(5))) and fd_rank(arm) == 5


def test_pose_rank_agrees_with_pinocchio(robots):
    pin = pytest.importorskip("pinocchio")
    from conftest import pinocchio_model

    for source in ("puma560", "planar6", robots["coaxial"]):
        robot = mindyn.load(source)
        model = pinocchio_model(robot)
        data = model.createData()
        fid = model.getFrameId("tool")
        rng = np.random.default_rng(3)
        best = 0
        for _ in range(8):
            q = rng.uniform(robot.limits["lower"], robot.limits["upper"])
            J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
            best = max(best, int(np.linalg.matrix_rank(J)))
        assert pose_rank(robot)[0] == best, source


@pytest.mark.parametrize(
    "source, hinted",
    [
        ("puma560", False),
        ("planar6", True),
        ("coaxial", True),
        ("tree:hand", True),
        ("jaw", False),
    ],
)
def test_the_hint_follows_the_rank_not_the_joint_count(robots, source, hinted, capsys):
    """An unreachable pose (20 m above the base): the hint, with the rank and the joints that
    move the tool, exactly when the rank is below 6."""
    name, _, tip = source.partition(":")
    robot_arg = robots.get(name, name)
    argv = ["ik", robot_arg, "--xyz", "0.1", "0.1", "20", "--timeout", "0.05"]
    argv += ["--tip", tip] if tip else []
    robot = mindyn.load(robot_arg, tip=tip or None)
    rank, moving = pose_rank(robot)
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("mindyn: error: no joint solution"), err
    assert (HINT in err) == hinted, err
    if hinted:
        assert f"Jacobian has rank {rank} over the {len(moving)} joint(s)" in err, err
    # position only: no hint, whatever the rank
    assert main([*argv, "--position-only"]) == 1
    assert HINT not in capsys.readouterr().err
