"""A motor on a prismatic joint through a very large reduction (a lead screw: PR2's torso lift
is driven at -52143 motor radians per metre), its rotor inertia and friction on the motor side:
the rotor enters the torques as T^T Ia T ddq, so its column is r^2 (2.7e9 at PR2's reduction)
times a joint-side rotor's. The projection method measured it against the joint-side columns of
its rows at that size and dropped them (3 base parameters instead of 18 at r = 5e4, a refusal
of its regrouping), the numerical method lost one at r = 1e6. Every method must give the rank
of a regressor formed here independently, and its base regressor must reproduce the dynamics.

The reference: Pinocchio's joint-torque regressor of the URDF (inertial columns) beside the
motor columns T^T e_k (T_k ddq), T^T e_k (T_k dq), T^T e_k sign(T_k dq) written out, stacked at
random states, each column scaled to unit norm (which takes the reduction's size out of the
columns, as it takes out the lengths' powers; an inertial column at the rounding of the rigid
torques counts as zero), its rank by numpy's SVD at the default tolerance relative to the
largest singular value; the test requires a clear gap around the tolerance."""

from __future__ import annotations

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from test_transmissions import arm_urdf, simple

TOLERANCE = 1e-9  # the default rank tolerance
METHODS = ("projection", "recursive", "numerical")
ARM_REDUCTIONS = (-50.0, 30.0)  # the two revolute joints' motors


def screw_arm(path, reduction):
    """A vertical prismatic joint (travel +-0.2 m) under two revolute ones, each driven by a
    ROS 1 SimpleTransmission; the first of `reduction` motor radians per metre."""
    reductions = (reduction, *ARM_REDUCTIONS)
    text = arm_urdf(
        3, "".join(simple(f"t{k}", f"j{k}", f"m{k}", r) for k, r in enumerate(reductions, 1))
    )
    text = text.replace("type='revolute'", "type='prismatic'", 1)
    text = text.replace("lower='-3' upper='3'", "lower='-0.2' upper='0.2'", 1)
    path.write_text(text, encoding="utf-8")
    return np.diag(reductions)


def random_state(pin_model, rng):
    """Joint positions within the limits (+-pi where there are none), as Pinocchio's
    configuration (a continuous joint's as cos, sin), rates in [-2, 2]."""
    q = []
    for joint in pin_model.joints[1:]:
        i = joint.idx_q
        lo = max(pin_model.lowerPositionLimit[i], -np.pi)
        hi = min(pin_model.upperPositionLimit[i], np.pi)
        x = rng.uniform(lo, hi) if joint.nq == 1 else rng.uniform(-np.pi, np.pi)
        q += [x] if joint.nq == 1 else [np.cos(x), np.sin(x)]
    n = pin_model.nv
    return np.array(q), rng.uniform(-2, 2, n), rng.uniform(-2, 2, n)


def motor_columns(T, dq, ddq):
    """The torques of unit Ia_k, Fv_k, Fc_k of each motor k, as columns (n, 3 n_motors)."""
    cols = []
    for k in range(T.shape[0]):
        t = T[k]
        cols += [t * (t @ ddq), t * (t @ dq), t * np.sign(t @ dq)]
    return np.array(cols).T.reshape(len(dq), len(cols))


def reference_ratios(pin_model, T, states=40, seed=5):
    """sigma_i / sigma_1 of the stacked regressor, its columns at unit norm."""
    data = pin_model.createData()
    rng = np.random.default_rng(seed)
    rows = []
    for _ in range(states):
        q, dq, ddq = random_state(pin_model, rng)
        W = pin.computeJointTorqueRegressor(pin_model, data, q, dq, ddq)
        rows.append(np.hstack([W, motor_columns(T, dq, ddq)]))
    A = np.vstack(rows)
    norms = np.linalg.norm(A, axis=0)
    # an inertial column that is zero for the exact geometry is the rounding of the rigid
    # bodies' torques (PR2's MY3: 3e-15 of them), which unit norm would make a direction
    rigid = 10 * (pin_model.njoints - 1)  # Pinocchio's inertial columns
    keep = norms > 0
    keep[:rigid] = norms[:rigid] > 1e-12 * norms[:rigid].max()
    A = A[:, keep] / norms[keep]
    s = np.linalg.svd(A, compute_uv=False)
    return s / s[0]


def reference_count(pin_model, T):
    ratios = reference_ratios(pin_model, T)
    # a clear decision: nothing within three orders of magnitude of the tolerance
    assert all(r > 1e3 * TOLERANCE or r < 1e-3 * TOLERANCE for r in ratios), ratios
    return int(np.sum(ratios > TOLERANCE))


def check_reproduces(robot, pin_model, T, base, rng):
    """W_b (Y pi) = Pinocchio's inverse dynamics of the URDF's inertia plus
    T^T (Ia T ddq + Fv T dq + Fc sign(T dq)), the drive parameters each of the size it takes
    in the torques (a reflected inertia r^2 Ia of 0.1 .. 1)."""
    data = pin_model.createData()
    pi = robot.parameters(rotor=True, friction=True)
    r = np.abs(np.diag(T))
    Ia, Fv, Fc = (rng.uniform(0.1, 1, len(r)) / r**p for p in (2, 2, 1))
    pi[10::13], pi[11::13], pi[12::13] = Ia, Fv, Fc
    for _ in range(5):
        q, dq, ddq = random_state(pin_model, rng)
        ref = pin.rnea(pin_model, data, q, dq, ddq) + T.T @ (
            Ia * (T @ ddq) + Fv * (T @ dq) + Fc * np.sign(T @ dq)
        )
        tb = base.regressor(q, dq, ddq) @ base.values(pi)
        err = np.max(np.abs(tb - ref)) / np.max(np.abs(ref))
        assert err <= 1e-9, (base.method, err)


@pytest.mark.parametrize("reduction", [1.0, 1e2, 1e4, 5e4, 1e6])
def test_a_large_reduction_on_a_prismatic_joint(tmp_path, reduction):
    path = tmp_path / "screw.urdf"
    T = screw_arm(path, reduction)
    robot = mindyn.load(path)
    assert robot.drive_side == "motor" and list(robot.joint_types)[0] == "prismatic"
    np.testing.assert_array_equal(robot.transmission.T, T)  # q_m = r q, as the file writes it
    pin_model = pin.buildModelFromUrdf(str(path))
    count = reference_count(pin_model, T)
    rng = np.random.default_rng(7)
    for method in METHODS:
        base = mindyn.base_parameters(robot, rotor=True, friction=True, method=method)
        assert base.n == count, (method, reduction, base.names)
        assert not base.margin["near_degenerate"], (method, base.margin)
        check_reproduces(robot, pin_model, T, base, rng)


def test_pr2_right_arm_with_its_torso_screw(robots_dir):
    """example-robot-data's PR2 from the base to r_wrist_roll_link: the torso lift joint's
    motor turns -52143.33 rad per metre. Every method gives the reference's count, 66 (the joint
    side's too), against the regressor of Pinocchio's model with the joints off the chain
    locked (their links then move with the chain's, which changes values, not ranks)."""
    path = robots_dir / "pr2_description/urdf/pr2.urdf"
    robot = mindyn.load(path, tip="r_wrist_roll_link")
    T = robot.transmission.T
    assert T[0, 0] == -52143.33  # the file's torso_lift_motor
    full = pin.buildModelFromUrdf(str(path))
    chain = set(robot.joint_names)
    locked = [full.getJointId(name) for name in full.names[1:] if name not in chain]
    pin_model = pin.buildReducedModel(full, locked, pin.neutral(full))
    assert list(pin_model.names[1:]) == list(robot.joint_names)
    count = reference_count(pin_model, T)
    assert count == 66
    for method in METHODS:
        for side in ("motor", "joint"):
            base = mindyn.base_parameters(
                robot.with_drive_side(side), rotor=True, friction=True, method=method
            )
            assert base.n == count, (method, side, base.names)
