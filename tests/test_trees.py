"""Fixed-base trees loaded whole from URDF, checked against Pinocchio's own URDF parser: Baxter
(example-robot-data: head, both arms and a finger of each gripper) and random trees
(tests/random_tree.py: arbitrary axes, revolute, continuous and prismatic joints, fixed joints,
branches).

Pinocchio parses the file itself, so joint order, merged fixed links and inertial values are
checked along with the dynamics. Pinocchio models a continuous joint by (cos q, sin q); its
configuration is built from ours below. Baxter's second finger joints mimic the first: mindyn
locks them at q = 0 clamped into their limits and merges them; Pinocchio, which models them as
independent joints, gets the same joints locked at the same values (buildReducedModel).
"""

from __future__ import annotations

import json

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import ROBOTS_DIR, assert_close, random_state
from mindyn import cli
from mindyn.export import write_urdf
from random_tree import random_tree_urdf

BAXTER = ROBOTS_DIR / "baxter_description/urdf/baxter.urdf"

# (n moving joints, seed) of the random trees
RANDOM = [(4, 1), (7, 2), (10, 3), (14, 4)]
CASES = ["baxter"] + [f"tree{n}_{seed}" for n, seed in RANDOM]

# Tolerances: rnea and our Newton-Euler both sum O(n) products of O(1) quantities in double
# precision (errors ~1e-15 relative); 1e-10 leaves five orders of magnitude of margin. The base
# parameters' target is the project's 1e-9 relative.
TOL = 1e-10
BASE_TOL = 1e-9


BAXTER_MIMIC = ["l_gripper_r_finger_joint", "r_gripper_r_finger_joint"]


def _pair(case: str, tmp_path_factory):
    if case == "baxter":
        path = BAXTER
    else:
        n, seed = (int(x) for x in case[4:].split("_"))
        path = random_tree_urdf(tmp_path_factory.mktemp(case) / f"{case}.urdf", n, seed)
    model = pin.buildModelFromUrdf(str(path))
    if case == "baxter":
        model = lock(model, BAXTER_MIMIC)
    return mindyn.load(path), model, path


def lock(model: pin.Model, names: list[str]) -> pin.Model:
    """`model` with the joints `names` locked at 0 clamped into their limits."""
    q = pin.neutral(model)
    ids = [model.getJointId(name) for name in names]
    for i in ids:
        k = model.joints[i].idx_q
        q[k] = np.clip(0.0, model.lowerPositionLimit[k], model.upperPositionLimit[k])
    return pin.buildReducedModel(model, ids, q)


@pytest.fixture(scope="module", params=CASES)
def pair(request, tmp_path_factory):
    return _pair(request.param, tmp_path_factory)


def pin_q(model: pin.Model, q: np.ndarray) -> np.ndarray:
    """Pinocchio's configuration for our joint values (cos, sin for an unbounded joint)."""
    out = np.zeros(model.nq)
    for i in range(1, model.njoints):
        j = model.joints[i]
        v = q[j.idx_v]
        if j.nq == 2:
            out[j.idx_q : j.idx_q + 2] = np.cos(v), np.sin(v)
        else:
            out[j.idx_q] = v
    return out


def states(robot, seed: int, m: int = 4):
    rng = np.random.default_rng(seed)
    return [random_state(robot, rng) for _ in range(m)]


def test_random_trees_branch_and_mix_joint_kinds(tmp_path):
    """The generator gives what the other tests rely on: trees, every joint kind, axes off the
    coordinate axes, fixed joints, names out of document order."""
    kinds = set()
    for n, seed in RANDOM:
        path = random_tree_urdf(tmp_path / f"t{seed}.urdf", n, seed)
        robot = mindyn.load(path)
        assert robot.n == n and not robot.is_serial
        text = path.read_text()
        kinds |= {k for k in ("revolute", "continuous", "prismatic", "fixed") if k in text}
        axes = np.abs(robot.axes)
        assert np.any((axes > 1e-3) & (axes < 1 - 1e-3))
        written = [line.split('"')[1] for line in text.splitlines() if "<joint name" in line]
        assert written != sorted(written)
    assert kinds == {"revolute", "continuous", "prismatic", "fixed"}


def test_joint_order_names_and_parents_equal_pinocchio(pair):
    robot, model, _ = pair
    assert robot.joint_names == list(model.names[1:])
    assert robot.parents == [int(p) - 1 for p in model.parents[1:]]
    assert not robot.is_serial
    # branches: Pinocchio's joints with no child joint (its subtree holds only itself)
    assert robot.branches == sum(len(model.subtrees[j]) == 1 for j in range(1, model.njoints))
    prismatic = [model.joints[k + 1].shortname().startswith("JointModelP") for k in range(robot.n)]
    assert robot.joint_types == ["prismatic" if p else "revolute" for p in prismatic]
    np.testing.assert_array_equal(robot.tool, np.eye(4))


def test_baxter_has_head_arms_and_grippers():
    robot = mindyn.load(BAXTER)
    assert robot.n == 17
    names = robot.joint_names
    assert names[0] == "head_pan" and robot.parents[0] == -1
    for side in ("left", "right"):
        arm = [names.index(f"{side}_{j}") for j in ("s0", "s1", "e0", "e1", "w0", "w1", "w2")]
        assert robot.parents[arm[0]] == -1
        assert [robot.parents[k] for k in arm[1:]] == arm[:-1]
        k = names.index(f"{side[0]}_gripper_l_finger_joint")
        assert robot.parents[k] == arm[-1]
    assert all(name in robot.notes for name in BAXTER_MIMIC), robot.notes
    # Pinocchio's own joint order, with the mimic joints taken out
    full = pin.buildModelFromUrdf(str(BAXTER))
    assert names == [n for n in full.names[1:] if n not in BAXTER_MIMIC]


def test_panda_whole_is_a_chain_with_its_mimic_finger_locked(robots_dir):
    path = robots_dir / "panda_description/urdf/panda.urdf"
    robot = mindyn.load(path)
    model = lock(pin.buildModelFromUrdf(str(path)), ["panda_finger_joint2"])
    assert robot.is_serial and robot.joint_names == list(model.names[1:])
    for k in range(robot.n):
        ours = np.asarray(mindyn.to_pinocchio_order(robot.params[10 * k : 10 * k + 10]))
        assert_close(ours, model.inertias[k + 1].toDynamicParameters(), TOL, "tree inertias")


def test_inertial_parameters_equal_pinocchio(pair):
    """Our classical parameters about each link origin (fixed links merged) equal Pinocchio's
    body inertias, which its parser merged the same way."""
    robot, model, _ = pair
    for k in range(robot.n):
        ours = np.asarray(mindyn.to_pinocchio_order(robot.params[10 * k : 10 * k + 10]))
        assert_close(ours, model.inertias[k + 1].toDynamicParameters(), TOL, "tree inertias")


def test_joint_transforms_equal_pinocchio(pair):
    """Geometry as loaded: each joint's transform from its parent's link frame at random q
    equals Pinocchio's liMi (fixed joints folded into the origins, axes normalised)."""
    robot, model, _ = pair
    data = model.createData()
    for q, _, _ in states(robot, 10, 3):
        pin.forwardKinematics(model, data, pin_q(model, q))
        for k in range(robot.n):
            got = robot.joint_transform(k, q[k])
            assert_close(got, data.liMi[k + 1].homogeneous, TOL, "tree joint transforms")


@pytest.mark.parametrize("seed", range(40))
def test_many_random_trees_load_as_pinocchio(seed, tmp_path):
    """A bounded sweep (40 URDFs, a few ms each): order, parents, body inertias and joint
    transforms equal Pinocchio's. branches=False lets some draws be chains (3 of the 40 here,
    1 to 12 joints), loaded with empty parents as before."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 13))
    branches = n >= 2 and seed % 4 != 0
    path = random_tree_urdf(tmp_path / "t.urdf", n, 100 + seed, branches=branches)
    robot = mindyn.load(path)
    model = pin.buildModelFromUrdf(str(path))
    assert robot.joint_names == list(model.names[1:])
    assert robot.parents == [int(p) - 1 for p in model.parents[1:]]
    assert robot.is_serial == all(p == k for k, p in enumerate(model.parents[1:]))
    data = model.createData()
    q = random_state(robot, rng)[0]
    pin.forwardKinematics(model, data, pin_q(model, q))
    for k in range(robot.n):
        ours = np.asarray(mindyn.to_pinocchio_order(robot.params[10 * k : 10 * k + 10]))
        assert_close(ours, model.inertias[k + 1].toDynamicParameters(), TOL, "tree inertias")
        got = robot.joint_transform(k, q[k])
        assert_close(got, data.liMi[k + 1].homogeneous, TOL, "tree joint transforms")


def test_inverse_dynamics_regressor_and_mass_matrix_equal_pinocchio(pair):
    robot, model, _ = pair
    data = model.createData()
    for q, dq, ddq in states(robot, 11):
        qp = pin_q(model, q)
        ref = pin.rnea(model, data, qp, dq, ddq)
        assert_close(robot.inverse_dynamics(q, dq, ddq), ref, TOL, "tree rnea")
        assert_close(robot.regressor(q, dq, ddq) @ robot.params, ref, TOL, "tree W pi vs rnea")
        M = pin.crba(model, data, qp)
        M = np.triu(M) + np.triu(M, 1).T
        assert_close(robot.mass_matrix(q), M, TOL, "tree mass matrix vs crba")
        g = pin.computeGeneralizedGravity(model, data, qp)
        assert_close(robot.gravity_torque(q), g, TOL, "tree gravity vs pinocchio")


def test_forward_kinematics_of_every_link_equals_pinocchio(pair):
    robot, model, _ = pair
    data = model.createData()
    for q, _, _ in states(robot, 12, 2):
        pin.forwardKinematics(model, data, pin_q(model, q))
        for k in range(robot.n):
            assert_close(robot.fk(q, link=k), data.oMi[k + 1].homogeneous, TOL, "tree fk")


def test_jacobian_is_the_last_links_with_zero_columns_off_its_branch(pair):
    robot, model, _ = pair
    data = model.createData()
    last = robot.n
    q = states(robot, 13, 1)[0][0]
    pin.computeJointJacobians(model, data, pin_q(model, q))
    # base axes, reference point the link origin
    ref = pin.getJointJacobian(model, data, last, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
    assert_close(robot.jacobian(q), ref, TOL, "tree jacobian")
    supports = {last - 1}
    while (p := robot.parents[min(supports)]) >= 0:
        supports.add(p)
    off = [k for k in range(robot.n) if k not in supports]
    assert off and not np.any(robot.jacobian(q)[:, off])


def test_numerical_base_parameters_reproduce_rnea(pair):
    robot, model, _ = pair
    data = model.createData()
    bp = mindyn.base_parameters(robot, method="numerical")
    pb = bp.values(robot.params)
    for q, dq, ddq in states(robot, 14):
        ref = pin.rnea(model, data, pin_q(model, q), dq, ddq)
        assert_close(bp.regressor(q, dq, ddq) @ pb, ref, BASE_TOL, "tree W_b (Y pi) vs rnea")


@pytest.mark.parametrize("method", ["projection", "recursive"])
def test_exact_methods_on_trees(pair, method):
    """The exact methods give the numerical method's count and reproduce rnea."""
    robot, model, _ = pair
    bp = mindyn.base_parameters(robot, method=method)
    data = model.createData()
    numerical = mindyn.base_parameters(robot, method="numerical")
    assert bp.n == numerical.n
    pb = bp.values(robot.params)
    for q, dq, ddq in states(robot, 15, 2):
        ref = pin.rnea(model, data, pin_q(model, q), dq, ddq)
        assert_close(bp.regressor(q, dq, ddq) @ pb, ref, BASE_TOL, f"tree {method} vs rnea")


@pytest.mark.parametrize("extras", [False, True])
def test_recursive_gives_the_projection_set_and_y_on_trees(pair, extras):
    """The recursive method's base set, names and Y are the projection method's, with and
    without rotor inertia and friction (Y to 1e-10: both computed to rounding)."""
    robot = pair[0]
    proj = mindyn.base_parameters(robot, rotor=extras, friction=extras, method="projection")
    rec = mindyn.base_parameters(robot, rotor=extras, friction=extras, method="recursive")
    assert rec.names == proj.names
    assert np.abs(rec.Y - proj.Y).max() <= 1e-10 * max(1.0, np.abs(proj.Y).max())


def test_tip_still_selects_a_chain():
    robot = mindyn.load(BAXTER, tip="left_gripper")
    assert robot.is_serial and robot.n == 7 and robot.parents == list(range(-1, 6))
    assert robot.joint_names == ["left_s0", "left_s1", "left_e0", "left_e1", "left_w0"] + [
        "left_w1",
        "left_w2",
    ]
    assert "l_gripper_l_finger_joint" in robot.notes  # locked and merged
    assert not np.allclose(robot.tool, np.eye(4))  # the fixed joints after left_w2


def test_export_round_trip_of_a_tree(pair, tmp_path):
    """write_urdf on a tree: we and Pinocchio read the written file back with the parameters
    written (here the model's own, scaled per link) as every body's inertia."""
    robot, _, _ = pair
    scale = np.repeat(np.linspace(0.5, 1.5, robot.n), 10)
    params = robot.params * scale
    out = write_urdf(robot, params, tmp_path / "out.urdf").path
    again = mindyn.load(out)
    assert again.joint_names == robot.joint_names and again.parents == robot.parents
    assert_close(again.params, params, 1e-12, "tree export round trip")
    model = pin.buildModelFromUrdf(str(out))
    if robot.name == "baxter":
        model = lock(model, BAXTER_MIMIC)
    for k in range(robot.n):
        ours = np.asarray(mindyn.to_pinocchio_order(params[10 * k : 10 * k + 10]))
        got = model.inertias[k + 1].toDynamicParameters()
        assert_close(got, ours, 1e-12, "tree export read by Pinocchio")


def _cli(capsys, *argv) -> str:
    assert cli.main([str(a) for a in argv]) == 0
    return capsys.readouterr().out


def test_cli_info_shows_the_tree(capsys):
    out = _cli(capsys, "info", BAXTER)
    assert "(17 joints, urdf, a tree of 3 branches)" in out
    table = [line.split() for line in out.splitlines() if line[:2].strip().isdigit()]
    rows = {cells[1]: cells[2] for cells in table}
    assert rows["head_pan"] == "base" and rows["left_s0"] == "base"
    assert rows["left_e0"] == "left_lower_shoulder"
    assert rows["r_gripper_l_finger_joint"] == "right_wrist"
    assert "l_gripper_r_finger_joint" in out  # the notes name the locked mimic joints
    chain = _cli(capsys, "info", BAXTER, "--tip", "right_gripper")
    assert "(7 joints, urdf)" in chain and "parent link" not in chain


@pytest.mark.parametrize("method", ["numerical", "projection", "recursive", None])
def test_cli_base_on_a_tree(capsys, tmp_path, method):
    """``mindyn base`` on a tree by each method and by the default (projection): the numerical
    method's count, the parent joints in the text and in the JSON."""
    path = random_tree_urdf(tmp_path / "t.urdf", 6, 7)
    robot = mindyn.load(path)
    extra = ["--method", method] if method else []
    numerical = mindyn.base_parameters(robot, method="numerical")
    out = _cli(capsys, "base", path, *extra)
    assert f"equations of motion {numerical.n}" in out
    parents = ", ".join("-" if p < 0 else str(p + 1) for p in robot.parents)
    assert f"(- the base): {parents}\n" in out
    doc = json.loads(_cli(capsys, "base", path, *extra, "--format", "json"))
    assert doc["parents"] == robot.parents and len(doc["names"]) == numerical.n


def test_chain_only_operations_refuse_a_tree():
    """Inverse kinematics and payload identification need one end link: on a tree they refuse
    with one line that names the robot and the way out (tip=)."""
    from mindyn.identification import identify_payload
    from mindyn.inverse_kinematics import ik_solve, resolved_rate, velocity_ik

    robot = mindyn.load(BAXTER)
    z = np.zeros(robot.n)
    calls = {
        "ik_solve": lambda: ik_solve(robot, np.eye(4)),
        "velocity_ik": lambda: velocity_ik(robot, z, np.zeros(6)),
        "resolved_rate": lambda: resolved_rate(robot, z, lambda t: (np.eye(4), np.zeros(6)), 1.0),
        "payload identification": lambda: identify_payload(robot, {}, []),
    }
    for what, call in calls.items():
        with pytest.raises(mindyn.ModelError) as info:
            call()
        msg = str(info.value)
        assert what in msg.split(" needs ")[0] and "\n" not in msg, msg
        assert "robot 'baxter' is a tree (17 joints, 3 branches)" in msg and "tip=" in msg, msg


@pytest.mark.parametrize("model", ["dynamic", "energy"])
def test_identification_on_a_tree_recovers_the_base_parameters(tmp_path, model):
    """A tree's noise-free inverse-dynamics log (torques of the tree's Newton-Euler recursion,
    checked against rnea above) identified with rotor inertia and friction: the dynamic model
    with the logged accelerations gives the true base values to rounding (1e-9 relative), the
    energy model, which needs no acceleration but integrates power over windows, to 1e-3 (as for
    chains in test_identification)."""
    from mindyn.control import simulate_inverse
    from mindyn.identification import identify, true_base_values
    from mindyn.identification.data import JointData
    from mindyn.identification.excitation import random_trajectory

    robot = mindyn.load(random_tree_urdf(tmp_path / "t.urdf", 5, 11))
    assert not robot.is_serial
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    log = simulate_inverse(robot, random_trajectory(robot, seed=3), rotor=True, friction=True)
    truth = true_base_values(base, {"names": log.param_names, "values": log.params})
    data = JointData(log.t, log.q, log.dq, log.ddq_true, log.tau, "sim", {})
    slow = {} if model == "energy" else {"min_velocity": 0}  # energy: every sample anyway
    res = identify(robot, data, model=model, base=base, rsd_threshold=None, **slow)
    rel = np.abs(res.full - truth) / np.maximum(np.abs(truth), 1e-3 * np.abs(truth).max())
    assert rel.max() < (1e-9 if model == "dynamic" else 1e-3), rel.max()
