"""Kinematics of robots with multi-DOF joints: Robot.fk, Robot.jacobian of any link in world or
local axes and the frame Jacobian of a link (identification.floating.contact_jacobian) against
Pinocchio's framesForwardKinematics and getFrameJacobian (LOCAL_WORLD_ALIGNED and LOCAL) on Solo12
with a free-flyer root, TIAGo with a planar root, random trees of every joint kind with a tool
frame and single-DOF chains and trees; then against central
differences of the link poses along each velocity coordinate, the configuration moved by each
joint's own motion (unit quaternions turned by the exponential of the angular velocity), which
uses no Jacobian code of mindyn or Pinocchio."""

from __future__ import annotations

import mindyn
import numpy as np
import pinocchio as pin
import pytest
import yaml
from conftest import assert_close, load_urdf_pair, se3
from mindyn import inverse_kinematics
from mindyn.control import slotine_li_regressor_classical
from mindyn.identification.floating import contact_jacobian
from random_tree import random_multidof_tree_yaml, random_tree_urdf
from test_multibody import geometry_pair, pin_q, random_state, urdf_pair

TOL = 1e-12
FRAMES = (("world", pin.LOCAL_WORLD_ALIGNED), ("local", pin.LOCAL))


def tree_with_tool(tmp_path, seed: int) -> mindyn.Robot:
    """A random tree of every joint kind (serial for odd seeds) with a tool frame on its last
    link."""
    path = random_multidof_tree_yaml(tmp_path / "tree.yaml", n=9, seed=seed, serial=seed % 2 == 1)
    doc = yaml.safe_load(path.read_text())
    rng = np.random.default_rng(seed)
    doc["tool"] = {"xyz": rng.uniform(-0.2, 0.2, 3).tolist(), "rpy": rng.uniform(-3, 3, 3).tolist()}
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return mindyn.load(path)


# robots of revolute and prismatic joints only: DH with a tool, DH with a prismatic joint, a
# URDF chain with a fixed tip, a random URDF tree (branches, prismatic and continuous joints)
SINGLE_DOF = ("puma560", "stanford", "panda", "urdftree")


def single_dof_robot(tmp_path, name: str) -> mindyn.Robot:
    if name == "panda":
        return load_urdf_pair("panda", tip="panda_hand")[0]
    if name == "urdftree":
        robot = mindyn.load(random_tree_urdf(tmp_path / "tree.urdf", 7, 2))
        assert not robot.is_serial
        return robot
    return mindyn.load(name)


def kinematic_pair(tmp_path, name: str):
    """(robot, pin.Model with a frame per link and one for the tool, frame ids, tool frame id,
    Pinocchio's q of mindyn's)."""
    if name.startswith("tree") or name in SINGLE_DOF:
        robot = tree_with_tool(tmp_path, int(name[4:])) if name.startswith("tree") else None
        robot = robot or single_dof_robot(tmp_path, name)
        model, bodies = geometry_pair(robot)
        to_pin = np.asarray
    else:
        robot, cached = urdf_pair(name)
        model, bodies = pin.Model(cached), [k + 1 for k in range(robot.n)]

        def to_pin(q):
            return pin_q(robot, model, q)

    ids = []
    for k in range(robot.n):
        frame = pin.Frame(f"link{k}", bodies[k], se3(robot.joint_post(k)), pin.FrameType.OP_FRAME)
        ids.append(model.addFrame(frame))
    last = robot.n - 1
    tool = pin.Frame("tool", bodies[last], se3(robot.joint_post(last) @ robot.tool), pin.OP_FRAME)
    return robot, model, ids, model.addFrame(tool), to_pin


@pytest.mark.parametrize("name", [*SINGLE_DOF, "solo12", "tiago", "tree0", "tree1", "tree2"])
def test_fk_and_jacobians_agree_with_pinocchio(tmp_path, name):
    """Robot.fk and Robot.jacobian(q, link=k, frame=...) of every link and of the tool frame
    (link=-1) against Pinocchio's oMf and getFrameJacobian of a frame at the link's origin,
    LOCAL_WORLD_ALIGNED ("world") and LOCAL ("local"): single-DOF chains (DH, URDF) and a
    single-DOF tree, robots with a free-flyer or planar root and random trees of every joint
    kind; contact_jacobian is the same Jacobian."""
    robot, model, ids, tool, to_pin = kinematic_pair(tmp_path, name)
    assert robot.single_dof == (name in SINGLE_DOF)
    if name.startswith("tree"):
        assert not np.allclose(robot.tool, np.eye(4))
    data = model.createData()
    rng = np.random.default_rng(3)
    for _ in range(3):
        q = random_state(robot, rng)[0]
        pin.framesForwardKinematics(model, data, to_pin(q))
        pin.computeJointJacobians(model, data, to_pin(q))
        for k, fid in [*enumerate(ids), (-1, tool)]:
            assert_close(robot.fk(q, link=k), data.oMf[fid].homogeneous, TOL, "fk")
            for frame, ref in FRAMES:
                J = robot.jacobian(q, link=k, frame=frame)
                assert J.shape == (6, robot.nv)
                expected = pin.getFrameJacobian(model, data, fid, ref)
                assert_close(J, expected, TOL, f"jacobian(link=k, frame={frame!r})")
                if k >= 0:
                    assert np.array_equal(contact_jacobian(robot, q, k, frame=frame), J)
        expected = pin.getFrameJacobian(model, data, tool, pin.LOCAL_WORLD_ALIGNED)
        assert_close(robot.jacobian(q), expected, TOL, "jacobian (default: tool, world)")


def test_jacobian_checks_link_and_frame():
    """A link out of range or not an integer, a frame not 'world' or 'local': ArgumentError
    naming the argument."""
    for robot in (mindyn.load("puma560"), urdf_pair("solo12")[0]):
        q = random_state(robot, np.random.default_rng(0))[0]
        for link in (robot.n, -2, 1.0, True, "1"):
            with pytest.raises(mindyn.ArgumentError, match=r"^link is "):
                robot.jacobian(q, link=link)
        for frame in ("base", "LOCAL", None, 1):
            with pytest.raises(mindyn.ArgumentError, match=r"^frame is .*'world', 'local'"):
                robot.jacobian(q, frame=frame)
    with pytest.raises(mindyn.ArgumentError, match=r"^frame is "):
        contact_jacobian(robot, q, 0, frame="base")


def exp_quaternion(quat, w):
    """The unit quaternion (x, y, z, w) turned by the rotation vector w in its own axes."""
    angle = np.linalg.norm(w)
    axis = w / angle if angle > 0 else np.zeros(3)
    dx, dw = np.sin(angle / 2) * axis, np.cos(angle / 2)
    x, s = np.asarray(quat[:3]), quat[3]
    return np.concatenate([s * dx + dw * x + np.cross(x, dx), [s * dw - x @ dx]])


def rotation(quat):
    x, y, z, w = quat
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def integrate(robot: mindyn.Robot, q, v):
    """The configuration reached from q moving each joint with its velocity v for unit time:
    a quaternion turned by the exponential of its body angular velocity, a free-flyer's and a
    planar joint's position along their body-axis velocity, the others along their rates."""
    out, i, j = [], 0, 0
    for kind in robot.joint_types:
        if kind == "spherical":
            out += list(exp_quaternion(q[i : i + 4], v[j : j + 3]))
            i, j = i + 4, j + 3
        elif kind == "floating":
            quat = q[i + 3 : i + 7]
            out += list(q[i : i + 3] + rotation(quat) @ v[j : j + 3])
            out += list(exp_quaternion(quat, v[j + 3 : j + 6]))
            i, j = i + 7, j + 6
        elif kind == "planar":
            c, s = q[i + 2], q[i + 3]
            t = np.arctan2(s, c) + v[j + 2]
            out += [q[i] + c * v[j] - s * v[j + 1], q[i + 1] + s * v[j] + c * v[j + 1]]
            out += [np.cos(t), np.sin(t)]
            i, j = i + 4, j + 3
        else:
            m = 2 if kind in ("universal", "cylindrical") else 1
            out += list(q[i : i + m] + v[j : j + m])
            i, j = i + m, j + m
    assert (i, j) == (robot.nq, robot.nv)
    return np.array(out)


def vee(S):
    return np.array([S[2, 1], S[0, 2], S[1, 0]])


@pytest.mark.parametrize("name", ["puma560", "urdftree", "solo12", "tiago", "tree0", "tree1"])
def test_jacobians_are_the_derivatives_of_the_link_poses(tmp_path, name):
    """Column i of the Jacobians of a link and of the tool frame: the central difference of the
    pose (Robot.fk) along the unit velocity e_i, the translation's derivative the origin's
    velocity, dR R^T the angular one (world axes), both turned by R^T (local axes)."""
    if name.startswith("tree"):
        robot = tree_with_tool(tmp_path, int(name[4:]))
    elif name in SINGLE_DOF:
        robot = single_dof_robot(tmp_path, name)
    else:
        robot = urdf_pair(name)[0]
    rng = np.random.default_rng(5)
    h = 1e-6
    q = random_state(robot, rng)[0]
    links = [robot.n - 1, int(rng.integers(robot.n)), -1]
    J = {k: np.zeros((6, robot.nv)) for k in links}
    for i in range(robot.nv):
        e = np.zeros(robot.nv)
        e[i] = h
        plus, minus = integrate(robot, q, e), integrate(robot, q, -e)
        for k in links:
            Tp, Tm, T = robot.fk(plus, link=k), robot.fk(minus, link=k), robot.fk(q, link=k)
            J[k][:3, i] = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
            J[k][3:, i] = vee((Tp[:3, :3] - Tm[:3, :3]) / (2 * h) @ T[:3, :3].T)
    for k in links:
        R = robot.fk(q, link=k)[:3, :3]
        local = np.vstack([R.T @ J[k][:3], R.T @ J[k][3:]])
        world_j = robot.jacobian(q, link=k)
        assert_close(world_j, J[k], 1e-7, "jacobian against differences")
        local_j = robot.jacobian(q, link=k, frame="local")
        assert_close(local_j, local, 1e-7, "jacobian against differences")
        if k >= 0:
            assert np.array_equal(contact_jacobian(robot, q, k, frame="world"), world_j)
            assert np.array_equal(contact_jacobian(robot, q, k, frame="local"), local_j)
        else:
            assert np.array_equal(robot.jacobian(q), world_j)


def test_kinematics_of_multidof_robots_check_their_arguments():
    """NaN, a wrong shape or a batch of the wrong length: ArgumentError naming the argument,
    on every multi-DOF path (before, a NaN reached the core: ModelError 'v has a value that is
    not finite'; fk and jacobian refused the robot)."""
    robot, _ = urdf_pair("solo12")
    q, v, a = random_state(robot, np.random.default_rng(0))
    bad = v.copy()
    bad[4] = np.nan
    calls = {
        "dq": lambda: robot.inverse_dynamics(q, bad, a),
        "ddq": lambda: robot.regressor(q, v, bad),
        "tau": lambda: robot.forward_dynamics(q, v, bad),
    }
    for name, call in calls.items():
        with pytest.raises(mindyn.ArgumentError, match=rf"^{name} contains NaN at coordinate 5"):
            call()
    nan_q = q.copy()
    nan_q[2] = np.nan
    for call in (
        lambda: robot.fk(nan_q),
        lambda: robot.jacobian(nan_q),
        lambda: robot.mass_matrix(nan_q),
        lambda: robot.potential_energy(nan_q),
        lambda: mindyn.coriolis_matrix(robot, nan_q, v),
    ):
        with pytest.raises(mindyn.ArgumentError, match=r"^q contains NaN at coordinate 3"):
            call()
    with pytest.raises(mindyn.ArgumentError, match=r"^q has shape \(18,\); expected \(19,\)"):
        robot.jacobian(q[:-1])
    with pytest.raises(mindyn.ArgumentError, match=r"^params has shape \(3,\)"):
        robot.mass_matrix(q, params=np.ones(3))
    with pytest.raises(mindyn.ArgumentError, match=r"^q contains NaN at sample 1, coordinate 3"):
        robot.kinetic_energy(np.vstack([q, nan_q]), np.vstack([v, v]))


def test_inverse_kinematics_refuses_multidof_chains_naming_the_joint(tmp_path):
    """fk and jacobian take a serial chain of multi-DOF joints; the inverse kinematics does not
    (its steps add dq to q), in one line naming the first multi-DOF joint."""
    robot = tree_with_tool(tmp_path, 1)
    assert robot.is_serial
    q = random_state(robot, np.random.default_rng(0))[0]
    kind = next(t for t in robot.joint_types if t not in ("revolute", "prismatic"))
    path = inverse_kinematics.line_path(robot.fk(q), robot.fk(q), 0.1)
    for call in (
        lambda: inverse_kinematics.velocity_ik(robot, q, np.zeros(6)),
        lambda: inverse_kinematics.resolved_rate(robot, q, path, 0.1),
        lambda: mindyn.ik(robot, robot.fk(q)),
    ):
        with pytest.raises(mindyn.ModelError, match=f"has the {kind} joint"):
            call()


@pytest.mark.parametrize("name", ["solo12", "tiago", "tree0"])
def test_a_configuration_whose_quaternion_is_not_unit_is_an_argument_error(tmp_path, name):
    """A quaternion or planar (cos, sin) pair of q off norm 1 by more than 1e-6 is a bad
    argument at every public entry taking q of a multi-DOF robot: ArgumentError naming q, the
    joint, its coordinates (1-based), the norm (computed here) and the tolerance; within the
    tolerance it is accepted (nothing is normalised). It was the core's ModelError."""
    robot = tree_with_tool(tmp_path, 0) if name == "tree0" else urdf_pair(name)[0]
    q, v, a = random_state(robot, np.random.default_rng(2))
    kinds = {"floating": (3, 4, 7), "spherical": (0, 4, 4), "planar": (2, 2, 4)}
    starts, i = [], 0  # the unit blocks, from the joint kinds and Pinocchio's nq of each
    for kind, joint in zip(robot.joint_types, robot.joint_names, strict=True):
        start, size, nq = kinds.get(kind, (0, 0, 2 if kind in ("universal", "cylindrical") else 1))
        if size:
            starts.append((i + start, size, kind, joint))
        i += nq
    assert i == robot.nq and starts
    start, size, kind, joint = starts[-1]
    bad = q.copy()
    bad[start : start + size] *= 1.0 + 3e-5
    norm = np.linalg.norm(bad[start : start + size])
    base = mindyn.base_parameters(robot, method="numerical")
    calls = {
        "inverse_dynamics": lambda x: robot.inverse_dynamics(x, v, a),
        "regressor": lambda x: robot.regressor(x, v, a),
        "mass_matrix": lambda x: robot.mass_matrix(x),
        "forward_dynamics": lambda x: robot.forward_dynamics(x, v, a),
        "gravity_torque": lambda x: robot.gravity_torque(x),
        "energy": lambda x: robot.energy(x, v),
        "kinetic_energy": lambda x: robot.kinetic_energy(x, v),
        "potential_energy": lambda x: robot.potential_energy(x),
        "momentum": lambda x: robot.momentum(x, v),
        "link_poses": lambda x: robot.link_poses(x),
        "fk": lambda x: robot.fk(x, link=0),
        "jacobian": lambda x: robot.jacobian(x, frame="local"),
        "contact_jacobian": lambda x: contact_jacobian(robot, x, 0),
        "coriolis_matrix": lambda x: mindyn.coriolis_matrix(robot, x, v),
        "slotine_li_regressor_classical": lambda x: slotine_li_regressor_classical(
            robot, x, v, v, a
        ),
        "BaseParameters.regressor": lambda x: base.regressor(x, v, a),
    }
    what = "quaternion" if size == 4 else r"\(cos, sin\) pair"
    message = (
        rf"^q has the {what} of the {kind} joint '{joint}' \(coordinates {start + 1} to "
        rf"{start + size}\) of norm {norm:.9g}; expected norm 1 within 1e-06"
    )
    near = q.copy()
    near[start : start + size] *= 1.0 + 1e-8  # within the tolerance: accepted as given
    for label, call in calls.items():
        with pytest.raises(mindyn.ArgumentError, match=message):
            call(bad)
        assert np.all(np.isfinite(call(near))), label
    with pytest.raises(mindyn.ArgumentError, match=rf"^q has the {what} .*\(sample 1, coord"):
        robot.mass_matrix(np.vstack([q, bad]))
