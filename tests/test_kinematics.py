"""Forward kinematics and the tool Jacobian (KDL inside mindyn) against products of the joint
transforms, Rodrigues' formula, Pinocchio, finite differences and the planar closed form."""

from __future__ import annotations

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import BUNDLED, assert_close, load_urdf_pair, pinocchio_model, random_state

LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


def joint_motion(axis, kind, q) -> np.ndarray:
    """4x4 motion of a joint: Rodrigues' rotation or a translation along the axis."""
    T = np.eye(4)
    a = np.asarray(axis, dtype=float)
    if kind == "revolute":
        K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
        T[:3, :3] = np.eye(3) + np.sin(q) * K + (1 - np.cos(q)) * K @ K
    else:
        T[:3, 3] = q * a
    return T


def chain(robot: mindyn.Robot, q, upto: int | None = None) -> np.ndarray:
    T = np.eye(4)
    for k in range(robot.n if upto is None else upto + 1):
        T = T @ robot.joint_transform(k, q[k])
    return T


def fk_jacobian(robot, q, h=1e-6) -> np.ndarray:
    """Geometric Jacobian of the tool frame by central differences of fk."""
    J = np.zeros((6, robot.n))
    for k in range(robot.n):
        dq = np.zeros(robot.n)
        dq[k] = h
        Tp, Tm = robot.fk(q + dq), robot.fk(q - dq)
        J[:3, k] = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
        J[3:, k] = pin.log3(Tp[:3, :3] @ Tm[:3, :3].T) / (2 * h)  # world-frame rotation
    return J


def urdf_case(name):
    """(robot, model, frame name of mindyn's tool frame) for URDF robots."""
    if name == "ur5":  # mindyn's chain ends at wrist_3_link (tool0 is merged, tool = I)
        robot, model = load_urdf_pair("ur5")
        return robot, model, "wrist_3_link"
    if name == "ur5-tool0":  # a fixed tip: tool = the fixed transform wrist_3_link -> tool0
        robot, model = load_urdf_pair("ur5", tip="tool0")
        return robot, model, "tool0"
    if name == "panda-hand":
        robot, model = load_urdf_pair("panda", tip="panda_hand")
        return robot, model, "panda_hand"
    robot, model = load_urdf_pair("panda", tip="panda_link8")
    return robot, model, "panda_link8"


URDF_CASES = ["ur5", "ur5-tool0", "panda-hand", "panda-link8"]


# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", BUNDLED + ["ur5", "panda"])
def test_joint_transform_is_pre_motion_post(name, rng):
    robot = load_urdf_pair(name)[0] if name in ("ur5", "panda") else mindyn.load(name)
    for k in range(robot.n):
        q = rng.uniform(-2, 2)
        T = (
            robot.joint_pre(k)
            @ joint_motion(robot.axes[k], robot.joint_types[k], q)
            @ robot.joint_post(k)
        )
        assert_close(robot.joint_transform(k, q), T, 1e-14, "joint_transform == pre J post")
        assert np.linalg.norm(robot.axes[k]) == pytest.approx(1.0, abs=1e-12)
    with pytest.raises(mindyn.ArgumentError, match="^k is "):
        robot.joint_transform(robot.n, 0.0)


@pytest.mark.parametrize("name", BUNDLED + ["ur5", "panda"])
def test_fk_is_product_of_joint_transforms(name, rng):
    robot = load_urdf_pair(name)[0] if name in ("ur5", "panda") else mindyn.load(name)
    for _ in range(3):
        q, _, _ = random_state(robot, rng)
        assert_close(robot.fk(q), chain(robot, q) @ robot.tool, 1e-12, "fk == prod T_k @ tool")
        assert_close(robot.fk(q, link=-1), robot.fk(q), 0.0, "fk(link=-1) == tool")
        for k in range(robot.n):
            assert_close(robot.fk(q, link=k), chain(robot, q, k), 1e-12, "fk(link k) == prod T")
    with pytest.raises(mindyn.ArgumentError, match="^link is "):
        robot.fk(q, link=robot.n)


@pytest.mark.parametrize("name", BUNDLED)
def test_fk_and_jacobian_match_pinocchio_bundled(name, rng):
    robot = mindyn.load(name)
    model = pinocchio_model(robot)
    data = model.createData()
    fid = model.getFrameId("tool")
    for _ in range(3):
        q, _, _ = random_state(robot, rng)
        pin.framesForwardKinematics(model, data, q)
        assert_close(robot.fk(q), data.oMf[fid].homogeneous, 1e-12, "fk vs pin oMf (tool)")
        for k in range(robot.n):
            # Pinocchio's joint frame k moved by post_k is mindyn's link frame k
            ref = data.oMi[k + 1].homogeneous @ robot.joint_post(k)
            assert_close(robot.fk(q, link=k), ref, 1e-12, "fk(link) vs pin oMi")
        J = pin.computeFrameJacobian(model, data, q, fid, LWA)
        assert_close(robot.jacobian(q), J, 1e-12, "jacobian vs pin (LOCAL_WORLD_ALIGNED)")
        assert_close(
            robot.jacobian(q), fk_jacobian(robot, q), 1e-8, "jacobian vs finite differences"
        )


@pytest.mark.parametrize("case", URDF_CASES)
def test_fk_and_jacobian_match_pinocchio_urdf(case, rng):
    robot, model, frame = urdf_case(case)
    data = model.createData()
    fid = model.getFrameId(frame)
    last = model.frames[fid].parentJoint
    assert last == robot.n
    for _ in range(3):
        q, _, _ = random_state(robot, rng)
        pin.framesForwardKinematics(model, data, q)
        assert_close(robot.fk(q), data.oMf[fid].homogeneous, 1e-12, "fk vs pin oMf (URDF tip)")
        # URDF link frames are the joint frames: link k == oMi[k + 1]
        for k in range(robot.n):
            assert_close(
                robot.fk(q, link=k), data.oMi[k + 1].homogeneous, 1e-12, "fk(link) vs pin oMi"
            )
        # the tool is the fixed transform from the last joint frame to the tip frame
        assert_close(
            robot.tool,
            model.frames[fid].placement.homogeneous,
            1e-12,
            "tool vs pin frame placement",
        )
        J = pin.computeFrameJacobian(model, data, q, fid, LWA)
        assert_close(robot.jacobian(q), J, 1e-12, "jacobian vs pin (LOCAL_WORLD_ALIGNED)")
        # the joint Jacobian of the last joint agrees when the tool is that joint frame
        if np.array_equal(robot.tool, np.eye(4)):
            Jj = pin.computeJointJacobian(model, data, q, robot.n)  # LOCAL
            R = data.oMi[robot.n].rotation
            assert_close(
                robot.jacobian(q),
                np.vstack([R @ Jj[:3], R @ Jj[3:]]),
                1e-12,
                "jacobian vs pin joint Jacobian",
            )
        assert_close(
            robot.jacobian(q), fk_jacobian(robot, q), 1e-8, "jacobian vs finite differences"
        )


def test_ur5_tool0_offset():
    """UR5's tool0 sits 0.0823 m along y of wrist_3_link, rotated -pi/2 about x (URDF text)."""
    robot = load_urdf_pair("ur5", tip="tool0")[0]
    T = np.eye(4)
    T[:3, :3] = pin.rpy.rpyToMatrix(-1.57079632679, 0, 0)
    T[1, 3] = 0.0823
    assert_close(robot.tool, T, 1e-12, "UR5 tool0 from the URDF text")
    base = load_urdf_pair("ur5")[0]
    q = np.array([0.1, -0.5, 0.9, 0.3, -1.2, 2.0])
    assert_close(robot.fk(q), base.fk(q) @ T, 1e-12, "UR5 tool0 = wrist_3_link @ offset")


@pytest.mark.parametrize("vertical", [True, False])
def test_planar2_closed_form(vertical, rng):
    """x = l1 c1 + l2 c12, y = l1 s1 + l2 s12 in the arm's plane (l1 = l2 = 0.5 m)."""
    robot = mindyn.load("planar2" if vertical else "planar2h")
    l1 = l2 = 0.5
    zero = np.zeros(2)
    o = robot.fk(zero, link=0)[:3, 3]  # joint 1 origin
    e1 = (robot.fk(zero)[:3, 3] - o) / (l1 + l2)  # x axis of the plane: the arm at q = 0
    e2 = (robot.fk(np.array([np.pi / 2, 0.0]))[:3, 3] - o) / (l1 + l2)  # q1 = 90 deg
    z = robot.fk(zero, link=0)[:3, 2]  # the joint axis
    assert np.linalg.norm(e1) == pytest.approx(1.0, abs=1e-12)
    assert np.linalg.norm(e2) == pytest.approx(1.0, abs=1e-12)
    assert e1 @ e2 == pytest.approx(0.0, abs=1e-12)
    assert_close(np.cross(z, e1), e2, 1e-12, "planar2 plane orientation")  # positive rotation
    g = robot.gravity / np.linalg.norm(robot.gravity)
    if vertical:  # gravity lies in the plane
        assert abs(g @ z) < 1e-12
    else:  # gravity along the joint axes
        assert abs(abs(g @ z) - 1.0) < 1e-12
    for _ in range(5):
        q1, q2 = q = rng.uniform(-np.pi, np.pi, 2)
        x = l1 * np.cos(q1) + l2 * np.cos(q1 + q2)
        y = l1 * np.sin(q1) + l2 * np.sin(q1 + q2)
        T = robot.fk(q)
        assert_close(T[:3, 3], o + x * e1 + y * e2, 1e-12, "planar2 closed form")
        # tool x axis along the second link; all joint axes stay z
        assert_close(
            T[:3, 0], np.cos(q1 + q2) * e1 + np.sin(q1 + q2) * e2, 1e-12, "planar2 closed form"
        )
        assert_close(T[:3, 2], z, 1e-12, "planar2 closed form")
        # Jacobian: d(x, y)/dq in the plane, angular velocity along z
        Jxy = np.array([[-y, -l2 * np.sin(q1 + q2)], [x, l2 * np.cos(q1 + q2)]])
        J = robot.jacobian(q)
        assert_close(
            J[:3], np.outer(e1, Jxy[0]) + np.outer(e2, Jxy[1]), 1e-12, "planar2 closed form"
        )
        assert_close(J[3:], np.outer(z, [1.0, 1.0]), 1e-12, "planar2 closed form")


def test_kinematics_input_validation():
    robot = mindyn.load("puma560")
    with pytest.raises(ValueError, match=r"q has shape \(5,\)"):
        robot.fk(np.zeros(5))
    with pytest.raises(ValueError, match=r"q has shape \(2, 6\)"):
        robot.jacobian(np.zeros((2, 6)))
    with pytest.raises(ValueError, match="q contains NaN at joint 4"):
        robot.fk([0, 0, 0, np.nan, 0, 0])
    with pytest.raises(ValueError, match="q contains an infinite value at joint 1"):
        robot.jacobian([np.inf, 0, 0, 0, 0, 0])


def _rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def _rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def _tr(x, y, z):
    T = np.eye(4)
    T[:3, 3] = x, y, z
    return T


@pytest.mark.parametrize("name", ["puma560", "puma560_3", "stanford", "zcr07s"])
def test_bundled_tables_follow_textbook_dh(name, rng):
    """Each joint transform from the YAML text (read with PyYAML, not our parser) through the
    textbook formulas: DH  Rz(theta) Tz(d) Tx(a) Rx(alpha);  MDH (Khalil-Kleinfinger)
    Rx(alpha) Tx(d) Rz(theta) Tz(r); the joint variable adds to theta or to d / r."""
    yaml = pytest.importorskip("yaml")
    from importlib import resources

    text = (resources.files("mindyn") / "robots" / f"{name}.yaml").read_text()
    desc = yaml.safe_load(text)
    unit = np.pi / 180 if desc.get("angle_unit", "rad") == "deg" else 1.0
    robot = mindyn.load(name)
    assert robot.n == len(desc["joints"])
    for k, j in enumerate(desc["joints"]):
        prismatic = j.get("type", "revolute") == "prismatic"
        assert robot.joint_types[k] == ("prismatic" if prismatic else "revolute")
        alpha, theta = j.get("alpha", 0) * unit, j.get("theta", 0) * unit
        for q in rng.uniform(-1.0, 1.0, 3):
            if desc["convention"] == "dh":
                a, d = j.get("a", 0), j.get("d", 0)
                T = _rz(theta + (0 if prismatic else q)) @ _tr(0, 0, d + (q if prismatic else 0))
                T = T @ _tr(a, 0, 0) @ _rx(alpha)
            else:
                dj, r = j.get("d", 0), j.get("r", 0)
                T = _rx(alpha) @ _tr(dj, 0, 0) @ _rz(theta + (0 if prismatic else q))
                T = T @ _tr(0, 0, r + (q if prismatic else 0))
            assert_close(robot.joint_transform(k, q), T, 1e-14, "joint_transform vs DH/MDH formula")


def test_puma560_flange_at_zero():
    """Corke's PUMA 560 at q = 0: flange at (a2 + a3, -d3, d1 + d4), with the published
    a2 = 0.4318, a3 = 0.0203, d3 = 0.15005, d4 = 0.4318 and the base offset d1 = 0.67183 m."""
    T = mindyn.load("puma560").fk(np.zeros(6))
    assert_close(T[:3, 3], [0.4318 + 0.0203, -0.15005, 0.67183 + 0.4318], 1e-12, "PUMA flange")
