"""Joints of several degrees of freedom and floating bases against Pinocchio: inverse dynamics
(rnea), the mass matrix (crba), the joint-torque regressor, forward dynamics (aba) and the
energies, on example-robot-data's humanoid and quadrupeds with a free-flyer root (Pinocchio's
URDF parser with a JointModelFreeFlyer root), a mobile manipulator with a planar root, and
random trees of spherical, universal, cylindrical, planar and free-flyer joints (a pin.Model
built from the geometry a Robot exposes, with Pinocchio's own joint models).

Pinocchio's state conventions are mindyn's (quaternions (x, y, z, w), a free-flyer's velocity
linear first in its body's axes), so its q, v and a are passed unchanged, except URDF
continuous joints, which Pinocchio parametrises by (cos, sin)."""

from __future__ import annotations

import functools
from pathlib import Path

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import assert_close, body_inertia, se3
from mindyn import codegen
from mindyn.control import slotine_li_regressor_classical
from mindyn.identification import identify
from random_tree import random_multidof_tree_yaml, random_tree_urdf

TOL = 1e-12
ROBOTS = Path(pin.__file__).parents[4] / "share" / "example-robot-data" / "robots"
FLOATING = {
    "talos": ROBOTS / "talos_data" / "robots" / "talos_reduced.urdf",
    "solo12": ROBOTS / "solo_description" / "robots" / "solo12.urdf",
    "go1": ROBOTS / "go1_description" / "urdf" / "go1.urdf",
    "anymal": ROBOTS / "anymal_c_simple_description" / "urdf" / "anymal.urdf",
    "g1": ROBOTS / "g1_description" / "urdf" / "g1_29dof_rev_1_0.urdf",
}
PLANAR = {"tiago": ROBOTS / "tiago_description" / "robots" / "tiago_no_hand.urdf"}


@functools.cache
def urdf_pair(name: str):
    """(mindyn Robot, pin.Model) of one URDF with a free-flyer or planar root."""
    path = FLOATING.get(name) or PLANAR[name]
    kind = "floating" if name in FLOATING else "planar"
    root = pin.JointModelFreeFlyer() if kind == "floating" else pin.JointModelPlanar()
    model = pin.buildModelFromUrdf(str(path), root)
    robot = mindyn.load(path, root_joint=kind)
    return robot, model


def geometry_pair(robot: mindyn.Robot, params=None):
    """A pin.Model built from the Robot's joint kinds, axes, parents and pre/post transforms
    (joints in depth-first order, as Pinocchio's crba needs), and its body of each link."""
    p = robot.params if params is None else params
    model = pin.Model()
    ids = []
    for k, kind in enumerate(robot.joint_types):
        parent = robot.parents[k]
        placement = robot.joint_pre(k)
        if parent >= 0:
            placement = robot.joint_post(parent) @ placement
        axis = np.asarray(robot.axes[k], dtype=float)
        if kind == "revolute":
            joint = pin.JointModelRevoluteUnaligned(axis)
        elif kind == "prismatic":
            joint = pin.JointModelPrismaticUnaligned(axis)
        elif kind == "spherical":
            joint = pin.JointModelSpherical()
        elif kind == "universal":
            joint = pin.JointModelUniversal(axis, np.array([1.0, 0.0, 0.0]))
        elif kind == "cylindrical":
            joint = pin.JointModelComposite(pin.JointModelPrismaticUnaligned(axis))
            joint.addJoint(pin.JointModelRevoluteUnaligned(axis))
        elif kind == "planar":
            joint = pin.JointModelPlanar()
        else:
            assert kind == "floating"
            joint = pin.JointModelFreeFlyer()
        jid = model.addJoint(0 if parent < 0 else ids[parent], joint, se3(placement), f"j{k}")
        model.inertias[jid] = body_inertia(p[10 * k : 10 * k + 10], robot.joint_post(k))
        ids.append(jid)
    model.gravity = pin.Motion(np.asarray(robot.gravity, dtype=float), np.zeros(3))
    return model, ids


def unit(rng, size):
    x = rng.normal(size=size)
    return x / np.linalg.norm(x)


def random_state(robot: mindyn.Robot, rng: np.random.Generator):
    """mindyn's q (unit quaternions and (cos, sin) pairs), v and a."""
    q = []
    for kind in robot.joint_types:
        if kind in ("revolute", "prismatic"):
            q += list(rng.uniform(-1.5, 1.5, 1))
        elif kind == "spherical":
            q += list(unit(rng, 4))
        elif kind in ("universal", "cylindrical"):
            q += list(rng.uniform(-1.5, 1.5, 2))
        elif kind == "planar":
            t = rng.uniform(-np.pi, np.pi)
            q += [*rng.uniform(-1, 1, 2), np.cos(t), np.sin(t)]
        else:
            q += [*rng.uniform(-1, 1, 3), *unit(rng, 4)]
    q = np.array(q)
    assert len(q) == robot.nq
    return q, rng.uniform(-2, 2, robot.nv), rng.uniform(-2, 2, robot.nv)


def pin_q(robot: mindyn.Robot, model: pin.Model, q):
    """Pinocchio's configuration of mindyn's: (cos, sin) of a continuous joint's angle."""
    out, i = [], 0
    for k, jm in enumerate(model.joints[1:]):
        kind = robot.joint_types[k]
        size = {"spherical": 4, "universal": 2, "cylindrical": 2, "planar": 4, "floating": 7}
        m = size.get(kind, 1)
        if jm.nq == 2 and jm.nv == 1:  # continuous
            out += [np.cos(q[i]), np.sin(q[i])]
        else:
            assert jm.nq == m
            out += list(q[i : i + m])
        i += m
    return np.array(out)


def pin_regressor_columns(n: int, bodies=None) -> np.ndarray:
    """cols with W_mindyn = W_pinocchio[:, cols] (the parameter orders of the two; link k is
    Pinocchio's body bodies[k], default k + 1)."""
    src = np.asarray(mindyn.to_pinocchio_order(np.arange(10.0 * n)), dtype=int)
    cols = np.empty(10 * n, dtype=int)
    cols[src] = np.arange(10 * n)
    if bodies is not None:
        cols = np.array([10 * (bodies[c // 10] - 1) + c % 10 for c in cols])
    return cols


def compare(robot: mindyn.Robot, model: pin.Model, rng, states: int = 3, bodies=None) -> dict:
    """Asserts the agreement; `bodies` (Pinocchio's body of each link) for a model built by
    geometry_pair, whose q is mindyn's."""
    data = model.createData()
    if bodies is None:
        assert list(model.names[1:]) == robot.joint_names
    cols = pin_regressor_columns(robot.n, bodies)
    worst = {}
    for _ in range(states):
        q, v, a = random_state(robot, rng)
        qp = q if bodies is not None else pin_q(robot, model, q)
        tau = robot.inverse_dynamics(q, v, a)
        worst["rnea"] = max(
            worst.get("rnea", 0), assert_close(tau, pin.rnea(model, data, qp, v, a), TOL, "rnea")
        )
        M = pin.crba(model, data, qp)
        M = np.triu(M) + np.triu(M, 1).T
        assert_close(robot.mass_matrix(q), M, TOL, "crba")
        Wp = pin.computeJointTorqueRegressor(model, data, qp, v, a)
        W = robot.regressor(q, v, a)
        assert_close(W, Wp[:, cols], TOL, "joint torque regressor")
        assert_close(W @ robot.params, tau, TOL, "regressor times params")
        tau2 = rng.uniform(-5, 5, robot.nv)
        assert_close(
            robot.forward_dynamics(q, v, tau2), pin.aba(model, data, qp, v, tau2), 1e-10, "aba"
        )
        assert_close(
            robot.kinetic_energy(q, v),
            pin.computeKineticEnergy(model, data, qp, v),
            TOL,
            "kinetic energy",
        )
        assert_close(
            robot.potential_energy(q),
            pin.computePotentialEnergy(model, data, qp),
            TOL,
            "potential energy",
        )
    return worst


@pytest.mark.parametrize("name", [*FLOATING, *PLANAR])
def test_floating_and_planar_base_robots_agree_with_pinocchio(name):
    robot, model = urdf_pair(name)
    assert robot.joint_types[0] == ("floating" if name in FLOATING else "planar")
    assert robot.nv == model.nv and robot.n == model.njoints - 1
    assert robot.nq == model.nq - sum(1 for j in model.joints if j.nq == 2 and j.nv == 1)
    # the bodies Pinocchio's parser forms (fixed links merged, the root link the base body)
    pinp = np.concatenate(
        [model.inertias[i].toDynamicParameters() for i in range(1, model.njoints)]
    )
    assert_close(mindyn.to_pinocchio_order(robot.params), pinp, TOL, "urdf inertial parameters")
    compare(robot, model, np.random.default_rng(1))


@pytest.mark.parametrize("seed", range(4))
def test_random_multidof_trees_agree_with_pinocchio(tmp_path, seed):
    robot = mindyn.load(random_multidof_tree_yaml(tmp_path / "tree.yaml", n=9, seed=seed))
    assert set(robot.joint_types) == {
        "revolute",
        "prismatic",
        "spherical",
        "universal",
        "cylindrical",
        "planar",
        "floating",
    }
    model, bodies = geometry_pair(robot)
    compare(robot, model, np.random.default_rng(seed), bodies=bodies)


def pinocchio_rank(robot, model, rng, states: int, bodies=None) -> tuple[int, np.ndarray]:
    """The rank of Pinocchio's joint-torque regressors stacked at random states (mindyn's
    column order; columns scaled to unit norm, singular values relative to the largest), and
    the stack. `bodies`: those of a geometry-built model (geometry_pair), None for a URDF's."""
    data = model.createData()
    cols = pin_regressor_columns(robot.n, bodies)
    rows = []
    for _ in range(states):
        q, v, a = random_state(robot, rng)
        qp = q if bodies is not None else pin_q(robot, model, q)
        rows.append(pin.computeJointTorqueRegressor(model, data, qp, v, a)[:, cols])
    W = np.vstack(rows)
    s = np.linalg.svd(W / np.linalg.norm(W, axis=0).clip(1e-300), compute_uv=False)
    return int(np.sum(s > 1e-9 * s[0])), W


def in_row_space(Y: np.ndarray, t: np.ndarray) -> float:
    """Relative residual of t projected off the row space of Y (0: t is a combination of the
    base parameters, i.e. identifiable)."""
    c, *_ = np.linalg.lstsq(Y.T, t, rcond=None)
    return float(np.linalg.norm(Y.T @ c - t) / np.linalg.norm(t))


@pytest.mark.parametrize("name", ["solo12", "tiago"])
def test_numerical_base_parameters_of_floating_and_planar_bases(name):
    robot, model = urdf_pair(name)
    bp = mindyn.base_parameters(robot, method="numerical")
    rank, _ = pinocchio_rank(robot, model, np.random.default_rng(7), states=12)
    assert bp.n == rank
    # W_b (Y pi) = W pi at random states for a random pi
    rng = np.random.default_rng(8)
    pi = rng.uniform(-1, 1, 10 * robot.n)
    for _ in range(3):
        q, v, a = random_state(robot, rng)
        W = robot.regressor(q, v, a)
        assert_close(W[:, bp.pivots] @ (bp.Y @ pi), W @ pi, 1e-9, "base regressor times Y pi")


def test_multidof_models_are_refused_where_unsupported(tmp_path):
    robot, _ = urdf_pair("solo12")
    with pytest.raises(mindyn.ModelError, match="rotor inertia and friction"):
        mindyn.base_parameters(robot, rotor=True)
    q, v, a = random_state(robot, np.random.default_rng(0))
    for call in (
        lambda: robot.momentum_regressors(q, v),
        lambda: robot.energy_regressors(q, v),
        lambda: mindyn.base_parameters(robot).energy_regressor(q, v),
        lambda: mindyn.base_parameters(robot).momentum_regressors(q, v),
    ):
        with pytest.raises(mindyn.ModelError, match="has the floating joint 'root_joint'"):
            call()
    with pytest.raises(mindyn.ModelError, match="joint 0 \\('root_joint'\\) is floating"):
        robot.joint_transform(0, 0.1)
    with pytest.raises(mindyn.ModelError, match="identify takes revolute.*identify_floating"):
        identify(robot, None)
    with pytest.raises(mindyn.ModelError, match="Structured Text is generated for a fixed base"):
        codegen.generate(robot, base=False, lang="st")
    assert_close(robot.gravity_torque(q), robot.inverse_dynamics(q, 0 * v, 0 * a), 0, "gravity")
    q[3:7] *= 2
    with pytest.raises(mindyn.ArgumentError, match="quaternion of the floating joint 'root_joint'"):
        robot.inverse_dynamics(q, v, a)
    with pytest.raises(mindyn.ArgumentError, match=r"^dq has shape \(17,\); expected \(18,\)"):
        robot.inverse_dynamics(random_state(robot, np.random.default_rng(0))[0], v[:-1], a)
    with pytest.raises(mindyn.ModelError, match="root_joint= applies to URDF files only"):
        mindyn.load("puma560", root_joint="floating")
    with pytest.raises(mindyn.ModelError, match="must be 'floating' or 'planar'"):
        mindyn.load(FLOATING["solo12"], root_joint="spherical")


@pytest.mark.parametrize("seed", range(2))
def test_urdf_floating_and_planar_joints_in_a_tree_agree_with_pinocchio(tmp_path, seed):
    path = random_tree_urdf(
        tmp_path / "tree.urdf",
        n=8,
        seed=seed,
        moving=("revolute", "continuous", "prismatic", "floating", "planar"),
    )
    robot = mindyn.load(path)
    assert {"floating", "planar"} & set(robot.joint_types)
    model = pin.buildModelFromUrdf(str(path))
    compare(robot, model, np.random.default_rng(seed))


@pytest.mark.parametrize("seed", range(2))
def test_numerical_base_parameters_of_random_multidof_trees(tmp_path, seed):
    robot = mindyn.load(random_multidof_tree_yaml(tmp_path / "tree.yaml", n=9, seed=seed))
    model, bodies = geometry_pair(robot)
    rank, _ = pinocchio_rank(robot, model, np.random.default_rng(5), 12, bodies)
    assert mindyn.base_parameters(robot, method="numerical").n == rank


def test_batches_of_states_give_the_single_states():
    robot, _ = urdf_pair("solo12")
    rng = np.random.default_rng(4)
    states = [random_state(robot, rng) for _ in range(3)]
    q, v, a = (np.array(x) for x in zip(*states, strict=True))
    tau = robot.inverse_dynamics(q, v, a)
    assert tau.shape == (3, robot.nv)
    for i, (qi, vi, ai) in enumerate(states):
        assert_close(tau[i], robot.inverse_dynamics(qi, vi, ai), 0, "batch")
        assert_close(robot.mass_matrix(q)[i], robot.mass_matrix(qi), 0, "batch")
        assert_close(robot.kinetic_energy(q, v)[i], robot.kinetic_energy(qi, vi), 0, "batch")
    with pytest.raises(mindyn.ArgumentError, match="^dq has shape .*batches of equal length"):
        robot.inverse_dynamics(q, v[:2], a)


@pytest.mark.parametrize("name", ["solo12", "tiago", "tree"])
def test_slotine_li_regressor_and_coriolis_matrix_agree_with_pinocchio(tmp_path, name):
    """The Coriolis matrix C(q, v) gives Pinocchio's velocity-product torque (rnea with a = 0 minus
    its gravity), dM/dt - 2 C is skew-symmetric with dM/dt by central differences of Pinocchio's
    crba along pin.integrate, and C is Pinocchio's computeCoriolisMatrix where the model has no
    universal joint (Pinocchio 4's misses the turning of the universal joint's subspace: its C v
    is not its own velocity product there); then Y(q, v, vr, ar) pi = M ar + C vr + g with
    Pinocchio's M and g."""
    if name == "tree":
        robot = mindyn.load(random_multidof_tree_yaml(tmp_path / "tree.yaml", n=9, seed=5))
        model, bodies = geometry_pair(robot)
    else:
        (robot, model), bodies = urdf_pair(name), None
    data = model.createData()
    rng = np.random.default_rng(2)

    def pin_m(qp):
        M = pin.crba(model, data, qp)
        return np.triu(M) + np.triu(M, 1).T

    for _ in range(2):
        q, v, a = random_state(robot, rng)
        vr, ar = rng.uniform(-2, 2, (2, robot.nv))
        qp = q if bodies is not None else pin_q(robot, model, q)
        g = pin.computeGeneralizedGravity(model, data, qp).copy()
        b = pin.rnea(model, data, qp, v, 0 * v) - g
        C = mindyn.coriolis_matrix(robot, q, v)
        assert_close(C @ v, b, TOL, "coriolis matrix times v")
        h = 1e-6
        dM = (pin_m(pin.integrate(model, qp, h * v)) - pin_m(pin.integrate(model, qp, -h * v))) / (
            2 * h
        )
        N = dM - 2 * C
        assert_close(N + N.T, 0 * N, 1e-7 * np.linalg.norm(dM), "dM/dt - 2 C skew")
        if "universal" not in robot.joint_types:
            Cp = pin.computeCoriolisMatrix(model, data, qp, v).copy()  # a view of data.C
            assert_close(C, Cp, TOL, "coriolis matrix")
        Y = slotine_li_regressor_classical(robot, q, v, vr, ar)
        assert_close(Y @ robot.params, pin_m(qp) @ ar + C @ vr + g, TOL, "slotine-li regressor")


@pytest.mark.parametrize("name", ["talos", "tiago", "tree"])
def test_link_poses_and_momentum_agree_with_pinocchio(tmp_path, name):
    """Link poses against Pinocchio's forwardKinematics (oMi, times the link offset post of a
    geometry-built model), the momentum against computeCentroidalMomentum moved from the centre
    of mass to the base origin."""
    if name == "tree":
        robot = mindyn.load(random_multidof_tree_yaml(tmp_path / "tree.yaml", n=9, seed=6))
        model, bodies = geometry_pair(robot)
    else:
        (robot, model), bodies = urdf_pair(name), None
    data = model.createData()
    rng = np.random.default_rng(9)
    for _ in range(2):
        q, v, _ = random_state(robot, rng)
        qp = q if bodies is not None else pin_q(robot, model, q)
        pin.forwardKinematics(model, data, qp)
        poses = robot.link_poses(q)
        for k in range(robot.n):
            expected = data.oMi[k + 1 if bodies is None else bodies[k]].homogeneous
            if bodies is not None:
                expected = expected @ robot.joint_post(k)
            assert_close(poses[k], expected, TOL, "link poses")
        hg = pin.computeCentroidalMomentum(model, data, qp, v)
        com = data.com[0]
        expected = np.concatenate([hg.linear, hg.angular + np.cross(com, hg.linear)])
        assert_close(robot.momentum(q, v), expected, TOL, "momentum")


def test_a_floating_chain_to_a_tip_agrees_with_pinocchio_locking_the_other_joints():
    """TALOS's left arm on its floating base (tip given): the joints off the chain locked at 0
    clamped into their limits and merged, as Pinocchio's buildReducedModel locks them."""
    robot = mindyn.load(FLOATING["talos"], tip="arm_left_7_link", root_joint="floating")
    assert robot.joint_types[0] == "floating" and robot.n == 10
    full = pin.buildModelFromUrdf(str(FLOATING["talos"]), pin.JointModelFreeFlyer())
    lock = [full.getJointId(n) for n in full.names[1:] if n not in robot.joint_names]
    q0 = pin.neutral(full)
    for jid in lock:
        i = full.joints[jid].idx_q
        q0[i] = min(max(0.0, full.lowerPositionLimit[i]), full.upperPositionLimit[i])
    compare(robot, pin.buildReducedModel(full, lock, q0), np.random.default_rng(1))


def _planar_urdf(path: Path, planar_rpy, axis, below_xyz, below_rpy, com, com_rpy) -> Path:
    """base -j1 (revolute)- l1 -j2 (planar, `axis`)- l2 -j3 (revolute)- l3."""
    inertia = '<inertia ixx="0.01" ixy="0.001" ixz="0" iyy="0.02" iyz="0.002" izz="0.03"/>'

    def link(name, xyz="0.1 0.02 -0.03", rpy="0.1 0.2 0.3"):
        return (
            f'<link name="{name}"><inertial><origin xyz="{xyz}" rpy="{rpy}"/>'
            f'<mass value="0.8"/>{inertia}</inertial></link>'
        )

    def joint(name, kind, parent, child, xyz, rpy, ax):
        limit = '<limit lower="-2" upper="2" effort="10" velocity="3"/>' if kind != "planar" else ""
        return (
            f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="{ax}"/>{limit}</joint>'
        )

    def v(x):
        return " ".join(repr(float(c)) for c in x)

    path.write_text(
        '<robot name="planar_axis">'
        + link("base")
        + link("l1")
        + link("l2", v(com), v(com_rpy))
        + link("l3")
        + joint("j1", "revolute", "base", "l1", "0 0 0.1", "0 0 0", "0 1 0")
        + joint("j2", "planar", "l1", "l2", "0.05 0 0.2", v(planar_rpy), v(axis))
        + joint("j3", "revolute", "l2", "l3", v(below_xyz), v(below_rpy), "1 0 0")
        + "</robot>"
    )
    return path


def test_a_urdf_planar_joint_moves_in_the_plane_normal_to_its_axis(tmp_path):
    """URDF's planar joint moves in the plane normal to its <axis> (Pinocchio's URDF parser takes
    the joint frame's xy plane whatever the axis). With the axis a = (0.6, 0, 0.8): the joint's
    translations move the link normal to a and its rotation turns it about a (the Jacobian's
    columns, world axes), and the robot is Pinocchio's of the same URDF rewritten with the axis z
    and the joint frame turned by the shortest rotation A taking z onto a (the joint origin's
    rotation times A, what hangs below it by A^T): x and y of q along A's x and y axes (inverse
    and forward dynamics, mass matrix)."""
    a = np.array([0.6, 0.0, 0.8])
    z = np.array([0.0, 0.0, 1.0])
    k = np.cross(z, a) / np.linalg.norm(np.cross(z, a))  # Rodrigues: about k by acos(z . a)
    A = pin.AngleAxis(np.arccos(z @ a), k).matrix()
    R0 = pin.rpy.rpyToMatrix(0.3, 0.0, 0.2)
    below_xyz, below_R = np.array([0.2, 0.05, -0.1]), pin.rpy.rpyToMatrix(0.1, -0.4, 0.5)
    com, com_R = np.array([0.1, 0.02, -0.03]), pin.rpy.rpyToMatrix(0.1, 0.2, 0.3)
    rpy = pin.rpy.matrixToRpy
    robot = mindyn.load(
        _planar_urdf(tmp_path / "a.urdf", rpy(R0), a, below_xyz, rpy(below_R), com, rpy(com_R))
    )
    assert robot.joint_types == ["revolute", "planar", "revolute"]
    rng = np.random.default_rng(3)
    for _ in range(3):
        q, _, _ = random_state(robot, rng)
        J = robot.jacobian(q, link=1)  # link l2, about its origin, world axes
        a_world = robot.fk(q, link=0)[:3, :3] @ R0 @ a
        assert_close(J[:3, 1:3].T @ a_world, np.zeros(2), 1e-12, "translations normal to a")
        assert_close(J[3:, 1:3], np.zeros((3, 2)), 1e-12, "translations do not turn")
        assert_close(J[3:, 3], a_world, 1e-12, "the rotation is about a")
    turned = _planar_urdf(
        tmp_path / "z.urdf",
        rpy(R0 @ A),
        z,
        A.T @ below_xyz,
        rpy(A.T @ below_R),
        A.T @ com,
        rpy(A.T @ com_R),
    )
    model = pin.buildModelFromUrdf(str(turned))
    data = model.createData()
    assert list(model.names[1:]) == robot.joint_names
    for _ in range(3):  # (the regressors differ: link l2's frame is turned by A in one of them)
        q, v, acc = random_state(robot, rng)
        tau = rng.uniform(-5, 5, robot.nv)
        assert_close(
            robot.inverse_dynamics(q, v, acc), pin.rnea(model, data, q, v, acc), TOL, "rnea"
        )
        M = pin.crba(model, data, q)
        assert_close(robot.mass_matrix(q), np.triu(M) + np.triu(M, 1).T, TOL, "crba")
        assert_close(
            robot.forward_dynamics(q, v, tau), pin.aba(model, data, q, v, tau), 1e-10, "aba"
        )


def test_joint_friction_of_a_floating_urdf_is_named_as_not_in_the_dynamics():
    """TIAGo on a planar root: its URDF gives joint damping (the torso lift 1000 N s/m), which
    the model of a robot with joints of several degrees of freedom leaves out of its dynamics,
    as Pinocchio's rnea does: it was kept in the robot silently. A warning names the joints
    with the URDF's values, and the inverse dynamics are Pinocchio's (without them)."""
    import xml.etree.ElementTree as ET

    path = PLANAR["tiago"]
    with pytest.warns(UserWarning, match="of its revolute and prismatic joints") as caught:
        robot = mindyn.load(path, root_joint="planar")
    said = next(str(w.message) for w in caught if "not in the dynamics" in str(w.message))
    damping = {
        j.get("name"): float(j.find("dynamics").get("damping", 0))
        for j in ET.parse(path).getroot().iter("joint")
        if j.find("dynamics") is not None
    }
    damped = [k for k in robot.joint_names[1:] if damping.get(k, 0) != 0]
    listed = ", ".join(f"{k} {damping[k]:g}" for k in damped[:4])
    assert f"viscous friction ({listed} and {len(damped) - 4} more)" in said, said
    model = pin.buildModelFromUrdf(str(path), pin.JointModelPlanar())
    compare(robot, model, np.random.default_rng(2), states=1)
