"""MuJoCo MJCF out and in, checked against MuJoCo's own inverse dynamics (``mj_inverse``) and
Pinocchio's ``rnea``.

How MuJoCo's joint terms are compared: ``armature`` (MuJoCo adds it to the diagonal of the
joint-space inertia) and ``damping`` (a passive force ``-damping * dq``) are in ``mj_inverse``'s
``qfrc_inverse`` exactly as ``Ia ddq`` and ``Fv dq``. ``frictionloss`` is a soft dry-friction
constraint, not a force ``Fc sign(dq)``: the comparisons disable it (``mjDSBL_FRICTIONLOSS``)
and add ``Fc sign(dq)`` on the reference side; a separate check keeps it enabled at moving
states and asserts MuJoCo's constraint is saturated there (``efc_state`` linear), where its
force is exactly ``Fc sign(dq)``. Joint limits and contacts are disabled (they are not
dynamics of the model).
"""

from __future__ import annotations

import math
import re
import sys
import warnings

import mindyn
import numpy as np
import pinocchio as pin
import pytest
import yaml
from conftest import (
    ROBOTS_DIR,
    URDFS,
    assert_close,
    body_inertia,
    cli,
    load_urdf_pair,
    pinocchio_model,
    set_pinocchio_params,
)
from mindyn.mjcf import write_mjcf

mujoco = pytest.importorskip("mujoco", reason="the 'mujoco' wheel is not installed")

REPO_UR5 = __import__("pathlib").Path(__file__).parent.parent / "examples/urdf/ur5.urdf"
BAXTER = ROBOTS_DIR / "baxter_description/urdf/baxter.urdf"
# MuJoCo before 3.14 diagonalises a fullinertia only to about 1e-6 relative (from 3.14 on, to
# round-off): the dynamics and the round trip then agree to that, not to the target.
_OLD = tuple(int(x) for x in mujoco.__version__.split(".")[:2]) < (3, 14)
TOL = 1e-5 if _OLD else 1e-9
ROUND_TRIP = 1e-6 if _OLD else 1e-12
OFF = (
    mujoco.mjtDisableBit.mjDSBL_FRICTIONLOSS
    | mujoco.mjtDisableBit.mjDSBL_LIMIT
    | mujoco.mjtDisableBit.mjDSBL_CONTACT
)


# -- references ---------------------------------------------------------------------------------
def physical_params(robot, rng, drive: bool = True) -> np.ndarray:
    """Random physically consistent classical parameters (13 per joint with ``drive``): masses
    in [0.5, 5] kg, centres of mass within 0.2 m, inertias of a body (principal moments
    a+b, b+c, a+c) in random axes; Ia, Fv, Fc in [0.1, 1]."""
    rows = []
    for _ in range(robot.n):
        a = rng.uniform(0.01, 0.1, 3)
        Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        inertia = Q @ np.diag([a[0] + a[1], a[1] + a[2], a[0] + a[2]]) @ Q.T
        p = mindyn.inertial_from_com(rng.uniform(0.5, 5), rng.uniform(-0.2, 0.2, 3), inertia)
        rows.append(np.concatenate([p, rng.uniform(0.1, 1.0, 3)]) if drive else p)
    return np.concatenate(rows)


def split(robot, p):
    rows = np.asarray(p).reshape(robot.n, 13)
    return rows[:, :10].ravel(), rows[:, 10], rows[:, 11], rows[:, 12]


def mj_inverse(m, names, q, dq, ddq, disable=OFF):
    """MuJoCo's qfrc_inverse at each state, in the order of joint ``names``; and MuJoCo's
    data of the last one."""
    m.opt.disableflags = int(disable)
    d = mujoco.MjData(m)
    adr = [int(m.jnt_qposadr[m.joint(n).id]) for n in names]
    dof = [int(m.jnt_dofadr[m.joint(n).id]) for n in names]
    out = []
    for qi, dqi, ddqi in zip(np.atleast_2d(q), np.atleast_2d(dq), np.atleast_2d(ddq)):
        d.qpos[adr], d.qvel[dof], d.qacc[dof] = qi, dqi, ddqi
        mujoco.mj_inverse(m, d)
        out.append(d.qfrc_inverse[dof].copy())
    return np.array(out), d


def pin_rnea(model, q, dq, ddq):
    data = model.createData()
    return np.array([pin.rnea(model, data, a, b, c) for a, b, c in zip(q, dq, ddq)])


def states(robot, rng, m: int = 4, speed=(-2.0, 2.0)):
    lim = robot.limits
    lo = np.where(np.isfinite(lim["lower"]), lim["lower"], -np.pi)
    hi = np.where(np.isfinite(lim["upper"]), lim["upper"], np.pi)
    q = rng.uniform(lo, hi, (m, robot.n))
    dq = rng.uniform(*speed, (m, robot.n)) * rng.choice([-1, 1], (m, robot.n))
    return q, dq, rng.uniform(-2.0, 2.0, (m, robot.n))


def arm(case):
    """(mindyn Robot, Pinocchio model with the same geometry) for a case: Pinocchio's own URDF
    parser for the example-robot-data arms, else the model conftest builds from the geometry."""
    if case in ("ur5", "panda"):
        return load_urdf_pair(case)
    if case == "baxter_arm":
        robot = mindyn.load(BAXTER, tip="left_hand_link")
        return robot, pinocchio_model(robot)
    robot = mindyn.load(REPO_UR5 if case == "ur5_example" else case)
    return robot, (None if case == "ur5_example" else pinocchio_model(robot))


CASES = ["puma560", "stanford", "zcr07s", "planar3", "ur5_example", "ur5", "panda", "baxter_arm"]


# -- MJCF out -----------------------------------------------------------------------------------
def joint_side(robot):
    """``robot`` with its rotor inertia and friction on the joints (UR5 and Baxter declare
    ros_control transmissions: theirs are on the motors by default)."""
    return robot if robot.transmission is None else robot.with_drive_side("joint")


@pytest.mark.parametrize("case", CASES)
def test_exported_mjcf_inverse_dynamics_is_pinocchio_plus_the_joint_terms(case, tmp_path):
    robot, model = arm(case)
    robot = joint_side(robot)
    if model is None:  # the repository's UR5: Pinocchio's URDF parser
        model = pin.buildModelFromUrdf(str(REPO_UR5))
    rng = np.random.default_rng(11)
    p = physical_params(robot, rng)
    inertial, ia, fv, fc = split(robot, p)
    out = write_mjcf(robot, p, tmp_path / "arm.xml").path
    if case in ("ur5", "panda", "ur5_example"):
        set_pinocchio_params(model, robot, inertial)
    else:
        model = pinocchio_model(robot, inertial)
    q, dq, ddq = states(robot, rng)
    ref = pin_rnea(model, q, dq, ddq) + ia * ddq + fv * dq + fc * np.sign(dq)
    m = mujoco.MjModel.from_xml_path(str(out))
    got, _ = mj_inverse(m, robot.joint_names, q, dq, ddq)
    assert_close(got + fc * np.sign(dq), ref, TOL, "MJCF mj_inverse vs Pinocchio + Ia, Fv, Fc")
    assert_close(robot.inverse_dynamics(q, dq, ddq, p), ref, TOL, "mindyn vs Pinocchio + terms")
    # frictionloss enabled, at moving states: where MuJoCo's dry-friction constraint is
    # saturated its force is Fc sign(dq), and mj_inverse gives the whole model
    q, dq, ddq = states(robot, rng, m=2, speed=(1.0, 2.0))
    got, d = mj_inverse(m, robot.joint_names, q, dq, ddq, disable=_no_limits())
    friction = d.efc_type[: d.nefc] == mujoco.mjtConstraint.mjCNSTR_FRICTION_DOF
    linear = (mujoco.mjtConstraintState.mjCNSTRSTATE_LINEARNEG,
              mujoco.mjtConstraintState.mjCNSTRSTATE_LINEARPOS)  # fmt: skip
    assert friction.sum() == robot.n and np.isin(d.efc_state[: d.nefc][friction], linear).all()
    ref = robot.inverse_dynamics(q, dq, ddq, p)
    assert_close(got[-1], ref[-1], TOL, "MJCF mj_inverse with frictionloss, moving")


def _no_limits():
    return mujoco.mjtDisableBit.mjDSBL_LIMIT | mujoco.mjtDisableBit.mjDSBL_CONTACT


@pytest.mark.parametrize("case", ["ur5", "ur5_joint_side", "panda"])
def test_mjcf_round_trip_keeps_every_parameter(case, tmp_path):
    """URDF -> mindyn -> MJCF -> mindyn: inertial parameters, Ia, Fv, Fc, gravity, axes and
    limits to 1e-12. UR5's motors (ratio 1) carry the drive terms by default: on the joints of
    the MJCF, they come back as the same joint terms."""
    name = case.split("_")[0]
    robot = mindyn.load(URDFS[name], tip="panda_hand" if name == "panda" else None)
    if case == "ur5_joint_side":
        robot = robot.with_drive_side("joint")
    assert robot.drive_side == ("motor" if case == "ur5" else "joint")
    p = physical_params(robot, np.random.default_rng(3))
    out = write_mjcf(robot, p, tmp_path / f"{name}.xml").path
    again = mindyn.load(out)
    assert again.joint_names == robot.joint_names and again.joint_types == robot.joint_types
    assert again.transmission is None and again.drive_side == "joint"
    np.testing.assert_allclose(
        again.parameters(rotor=True, friction=True), p, rtol=0, atol=ROUND_TRIP
    )
    np.testing.assert_allclose(again.gravity, robot.gravity, rtol=0, atol=1e-15)
    np.testing.assert_allclose(again.axes, robot.axes, rtol=0, atol=ROUND_TRIP)
    # the effort limits too (the joints' actuatorfrcrange), and the velocity limits (custom
    # numerics, MJCF having no element for them)
    for key in ("lower", "upper", "effort", "velocity"):
        np.testing.assert_allclose(again.limits[key], robot.limits[key], atol=1e-12)


def test_round_trip_of_the_model_own_parameters_and_gravity(tmp_path):
    robot = mindyn.load(URDFS["ur5"], gravity=[0.5, -1.0, -9.7])
    out = write_mjcf(robot, robot.params, tmp_path / "ur5.xml").path
    text = out.read_text()
    assert 'gravity="0.5 -1.0 -9.7"' in text and "frictionloss" in text
    again = mindyn.load(out)
    scale = np.abs(robot.params).max()
    np.testing.assert_allclose(again.params, robot.params, rtol=0, atol=1e-12 * scale)
    np.testing.assert_array_equal(again.gravity, robot.gravity)
    assert not again.rotor_inertia.any() and not again.coulomb.any()


# -- drive terms on the motors of simple transmissions ------------------------------------------
GEARS = [101.0, -101.0, 80.5, 50.0, -50.0, 30.0]


def geared_ur5(tmp_path):
    """example-robot-data's UR5 with its six SimpleTransmissions given these reductions
    (the file declares 1)."""
    text = URDFS["ur5"].read_text()
    assert text.count("<mechanicalReduction>1</mechanicalReduction>") == 6
    ratios = iter(GEARS)
    text = re.sub(
        r"<mechanicalReduction>1</mechanicalReduction>",
        lambda _: f"<mechanicalReduction>{next(ratios)!r}</mechanicalReduction>",
        text,
    )
    path = tmp_path / "ur5_geared.urdf"
    path.write_text(text, encoding="utf-8")
    return path


def baxter_rnea(robot, inertial, q, dq, ddq):
    """Pinocchio's rnea of Baxter whole (its own URDF parser, the mimic fingers locked) with
    ``inertial``, in the order of ``robot``'s joints."""
    model = pin.buildModelFromUrdf(str(BAXTER))
    locked = [j for j in model.names[1:] if j not in robot.joint_names]  # mimic fingers
    model = pin.buildReducedModel(model, [model.getJointId(j) for j in locked], pin.neutral(model))
    assert model.nq == model.nv == robot.n
    for k, name in enumerate(robot.joint_names):
        model.inertias[model.getJointId(name)] = body_inertia(
            inertial[10 * k : 10 * k + 10], robot.joint_post(k)
        )
    idx = [model.idx_qs[model.getJointId(n)] for n in robot.joint_names]
    out = np.zeros_like(q)
    data = model.createData()
    for i in range(len(q)):
        x, v, a = (np.zeros(model.nq) for _ in range(3))
        x[idx], v[idx], a[idx] = q[i], dq[i], ddq[i]
        out[i] = pin.rnea(model, data, x, v, a)[idx]
    return out


def motor_side_case(case, tmp_path):
    """(motor-side robot, rnea(inertial, q, dq, ddq) of Pinocchio on the same URDF)."""
    if case == "baxter":
        robot = mindyn.load(BAXTER)
        return robot, lambda p, q, dq, ddq: baxter_rnea(robot, p, q, dq, ddq)
    path = URDFS["ur5"] if case == "ur5" else geared_ur5(tmp_path)
    robot, model = mindyn.load(path), pin.buildModelFromUrdf(str(path))

    def rnea(p, q, dq, ddq):
        set_pinocchio_params(model, robot, p)
        return pin_rnea(model, q, dq, ddq)

    return robot, rnea


@pytest.mark.parametrize("case", ["ur5", "ur5_geared", "baxter"])
def test_motor_side_mjcf_is_the_motor_formula_and_reads_back_as_joint_terms(case, tmp_path):
    """UR5 (ratio 1), UR5 with gear ratios (some negative) and Baxter whole (its grippers'
    transmissions first: T permutes the joints) with the drive terms on the motors: mj_inverse
    of the MJCF is rnea + T^T (Ia T ddq + Fv T dq + Fc sign(T dq)), written here; the motors
    act through T^T; read back, the joints carry r^2 Ia, r^2 Fv, |r| Fc with the same
    dynamics."""
    robot, rnea = motor_side_case(case, tmp_path)
    assert robot.drive_side == "motor"
    T = robot.transmission.T
    assert (np.count_nonzero(T, axis=1) == 1).all()  # simple transmissions
    rng = np.random.default_rng(12)
    p = physical_params(robot, rng)
    inertial, ia, fv, fc = split(robot, p)  # slot i: motor i
    out = write_mjcf(robot, p, tmp_path / "motors.xml").path
    text = out.read_text()
    assert "<tendon" not in text and text.count("<motor ") == robot.n
    m = mujoco.MjModel.from_xml_path(str(out))
    q, dq, ddq = states(robot, rng, m=3)
    friction = (fc * np.sign(dq @ T.T)) @ T
    ref = rnea(inertial, q, dq, ddq) + (ia * (ddq @ T.T) + fv * (dq @ T.T)) @ T + friction
    got, _ = mj_inverse(m, robot.joint_names, q, dq, ddq)
    assert_close(got + friction, ref, TOL, "motor-side MJCF vs rnea + T^T (motor terms)")
    # frictionloss enabled, at moving states: saturated, so mj_inverse is the whole formula
    q, dq, ddq = states(robot, rng, m=2, speed=(1.0, 2.0))
    friction = (fc * np.sign(dq @ T.T)) @ T
    ref = rnea(inertial, q, dq, ddq) + (ia * (ddq @ T.T) + fv * (dq @ T.T)) @ T + friction
    got, d = mj_inverse(m, robot.joint_names, q, dq, ddq, disable=_no_limits())
    on_dofs = d.efc_type[: d.nefc] == mujoco.mjtConstraint.mjCNSTR_FRICTION_DOF
    linear = (mujoco.mjtConstraintState.mjCNSTRSTATE_LINEARNEG,
              mujoco.mjtConstraintState.mjCNSTRSTATE_LINEARPOS)  # fmt: skip
    assert on_dofs.sum() == d.nefc == robot.n
    assert np.isin(d.efc_state[: d.nefc], linear).all()
    assert_close(got[-1], ref[-1], TOL, "motor-side MJCF with frictionloss, moving")
    # the motors drive the joints through T^T (actuators on the joints, gear r)
    d = mujoco.MjData(m)
    tau_m = rng.normal(size=robot.n)
    effort = robot.limits["effort"]
    tau_m *= min(1.0, 0.5 * np.min(effort / np.abs(T.T @ tau_m)))  # within the effort limits
    ids = [m.actuator(name).id for name in robot.transmission.motors]
    d.ctrl[ids] = tau_m
    mujoco.mj_forward(m, d)
    dof = [int(m.jnt_dofadr[m.joint(n).id]) for n in robot.joint_names]
    np.testing.assert_allclose(d.qfrc_actuator[dof], T.T @ tau_m, rtol=1e-15, atol=0)
    # beyond them, the joint's torque is its effort limit (the joints' actuatorfrcrange)
    d.ctrl[ids] = 4 * tau_m / np.min(np.abs(T.T @ tau_m) / effort)
    mujoco.mj_forward(m, d)
    np.testing.assert_allclose(np.abs(d.qfrc_actuator[dof]), effort, rtol=1e-15)
    # read back: a joint-side robot without transmissions, with the motors' terms folded
    again = mindyn.load(out)
    assert again.transmission is None and again.drive_side == "joint"
    assert again.joint_names == robot.joint_names
    folded = np.column_stack(
        [inertial.reshape(robot.n, 10), (T**2).T @ ia, (T**2).T @ fv, np.abs(T).T @ fc]
    ).ravel()
    np.testing.assert_allclose(
        again.parameters(rotor=True, friction=True), folded, rtol=ROUND_TRIP, atol=ROUND_TRIP
    )
    if not np.any(np.abs(T) != (T != 0)):  # ratios 1: the same numbers
        np.testing.assert_array_equal(
            again.parameters(rotor=True, friction=True)[10::13], folded[10::13]
        )
    got = again.inverse_dynamics(q, dq, ddq, again.parameters(rotor=True, friction=True))
    assert_close(got, ref, ROUND_TRIP, "motor-side MJCF read back vs the motor formula")
    got, _ = mj_inverse(m, again.joint_names, q, dq, ddq, disable=_no_limits())
    p_again = again.parameters(rotor=True, friction=True)
    assert_close(got, again.inverse_dynamics(q, dq, ddq, p_again),
                 ROUND_TRIP, "motor-side MJCF: mj_inverse vs the robot read back")  # fmt: skip


# -- transmissions ------------------------------------------------------------------------------
def dh6(tmp_path, transmissions) -> mindyn.Robot:
    """A 6R arm (DH) with ``transmissions`` (YAML form)."""
    rows = [(0.0, np.pi / 2, 0.4), (0.5, 0.0, 0.0), (0.1, np.pi / 2, 0.0),
            (0.0, -np.pi / 2, 0.45), (0.0, np.pi / 2, 0.0), (0.0, 0.0, 0.1)]  # fmt: skip
    doc = {
        "name": "wrist6",
        "convention": "dh",
        "joints": [
            {
                "name": f"j{k + 1}",
                "a": a,
                "alpha": al,
                "d": d,
                "theta": 0.0,
                "inertial": {
                    "mass": 1.0,
                    "com": [0.05, 0, 0],
                    "inertia": {"xx": 0.01, "yy": 0.02, "zz": 0.02},
                },
            }
            for k, (a, al, d) in enumerate(rows)
        ],  # fmt: skip
        "transmissions": transmissions,
    }
    path = tmp_path / "wrist6.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False), encoding="utf-8")
    return mindyn.load(path)


COUPLED_WRIST = np.diag([100.0, 100.0, 80.0, 50.0, 50.0, 50.0])
COUPLED_WRIST[5, 4] = 50.0  # motor 6 turns with q5 + q6
DIFFERENTIAL = np.diag([100.0, 100.0, 80.0, 1.0, 1.0, 50.0])
DIFFERENTIAL[3:5, 3:5] = [[40.0, 40.0], [40.0, -40.0]]  # motors 4, 5: q4 + q5 and q4 - q5


@pytest.mark.parametrize("T", [COUPLED_WRIST, DIFFERENTIAL], ids=["coupled_wrist", "differential"])
def test_tendon_mjcf_is_the_motor_side_formula(T, tmp_path):
    robot = dh6(tmp_path, {"matrix": T.tolist(), "motors": [f"m{k + 1}" for k in range(6)]})
    rng = np.random.default_rng(7)
    p = physical_params(robot, rng)
    inertial, ia, fv, fc = split(robot, p)
    ia, fv, fc = ia * 1e-4, fv * 1e-3, fc * 1e-2  # motor-side magnitudes
    p = np.column_stack([inertial.reshape(6, 10), ia, fv, fc]).ravel()
    out = write_mjcf(robot, p, tmp_path / "motor.xml", drive_side="motor").path
    text = out.read_text()
    # the motors coupling joints on tendons, the others on their joint with their ratio
    coupled = [k for k in range(6) if np.count_nonzero(T[k]) > 1]
    assert text.count("<fixed ") == len(coupled) and 'joint="j1" gear="100.0"' in text
    assert all(f'<motor name="m{k + 1}" tendon="m{k + 1}"' in text for k in coupled)
    m = mujoco.MjModel.from_xml_path(str(out))
    q, dq, ddq = states(robot, rng)
    rnea = pin_rnea(pinocchio_model(robot, inertial), q, dq, ddq)
    # written here: tau = rnea + T^T (Ia T ddq + Fv T dq + Fc sign(T dq))
    ref = rnea + ((ia * (ddq @ T.T) + fv * (dq @ T.T)) @ T + (fc * np.sign(dq @ T.T)) @ T)
    got, _ = mj_inverse(m, robot.joint_names, q, dq, ddq)
    friction = (fc * np.sign(dq @ T.T)) @ T
    assert_close(got + friction, ref, TOL, "tendon MJCF vs motor-side formula")
    # the motors drive the joints through T^T: a motor torque tau_m gives joint torques T^T tau_m
    d = mujoco.MjData(m)
    tau_m = rng.normal(size=6)
    d.ctrl[[m.actuator(f"m{k + 1}").id for k in range(6)]] = tau_m
    mujoco.mj_forward(m, d)
    dof = [int(m.jnt_dofadr[m.joint(n).id]) for n in robot.joint_names]
    np.testing.assert_allclose(d.qfrc_actuator[dof], T.T @ tau_m, rtol=1e-12, atol=1e-12)
    # read back: each tendon a motor whose row of T is its coefficients and whose Ia, Fv, Fc
    # are its armature, damping, frictionloss; every other joint (and one with terms of its own,
    # as the four-bar linkage's first) a direct motor of ratio 1 with its joint's terms
    again = mindyn.load(out)
    tr = again.transmission
    assert again.drive_side == "motor" and tr.format == "mjcf"
    slots = again.parameters(rotor=True, friction=True).reshape(6, 13)[:, 10:]
    for k in coupled:
        i = tr.motors.index(f"m{k + 1}")
        np.testing.assert_array_equal(tr.T[i], T[k])
        np.testing.assert_allclose(slots[i], [ia[k], fv[k], fc[k]], rtol=1e-15)
    assert sorted(tr.types) == sorted(["tendon"] * len(coupled) + ["direct"] * (6 - len(coupled)))
    got = again.inverse_dynamics(q, dq, ddq, again.parameters(rotor=True, friction=True))
    assert_close(got, ref, ROUND_TRIP, "tendon MJCF read back vs motor-side formula")
    # written back from the robot read: the same file's dynamics
    back = write_mjcf(again, again.parameters(rotor=True, friction=True), tmp_path / "back.xml")
    got, _ = mj_inverse(mujoco.MjModel.from_xml_path(str(back.path)), robot.joint_names, q, dq, ddq)
    assert_close(got + friction, ref, TOL, "tendon MJCF written back vs motor-side formula")
    # joint-side terms with the same transmissions: on the joints; read back exactly (tendons
    # without terms, and actuators, are not dynamics: the robot read has no transmissions)
    joint = write_mjcf(robot, p, tmp_path / "joint.xml", drive_side="joint").path
    assert "<fixed " in joint.read_text()
    got, _ = mj_inverse(mujoco.MjModel.from_xml_path(str(joint)), robot.joint_names, q, dq, ddq)
    assert_close(got + fc * np.sign(dq), rnea + ia * ddq + fv * dq + fc * np.sign(dq), TOL,
                 "tendon MJCF, joint-side terms")  # fmt: skip
    again = mindyn.load(joint)  # link frames = joint frames, not the DH frames: same dynamics
    assert again.transmission is None
    drive = again.parameters(rotor=True, friction=True).reshape(6, 13)[:, 10:]
    np.testing.assert_allclose(drive, np.column_stack([ia, fv, fc]), rtol=0, atol=ROUND_TRIP)
    got = again.inverse_dynamics(q, dq, ddq, again.parameters(rotor=True, friction=True))
    assert_close(got, rnea + ia * ddq + fv * dq + fc * np.sign(dq), ROUND_TRIP,
                 "tendon MJCF, joint-side terms read back")  # fmt: skip


def test_motor_side_needs_one_motor_per_joint(tmp_path):
    T = 50.0 * np.vstack([np.eye(6), np.ones((1, 6))])  # a seventh, redundant motor
    robot = dh6(tmp_path, {"matrix": T.tolist(), "motors": [f"m{k + 1}" for k in range(7)]})
    with pytest.raises(mindyn.ModelError, match="7 motors for 6 joints"):
        write_mjcf(robot, robot.params, tmp_path / "x.xml", drive_side="motor")


# -- MJCF in ------------------------------------------------------------------------------------
ARM7 = """<mujoco model="arm7">
  <!-- seven revolute joints; defaults by class -->
  <compiler angle="degree" eulerseq="zyx"/>
  <option gravity="0.3 -0.2 -9.7"/>
  <default>
    <joint armature="0.12" damping="0.6" frictionloss="0.25"/>
    <geom density="800"/>
    <default class="wrist">
      <joint armature="0.015" damping="0.1" frictionloss="0.05" range="-120 120"/>
    </default>
  </default>
  <worldbody>
    <body name="base" pos="0 0 0.1">
      <geom type="cylinder" size="0.1 0.05"/>
      <body name="l1" pos="0 0 0.08" euler="30 0 0">
        <joint name="j1" axis="0 0 1"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.3" size="0.05"/>
        <body name="l2" pos="0 0 0.3" euler="10 20 30">
          <joint name="j2" axis="0 1 0" pos="0 0 0.02" range="-90 90"/>
          <inertial pos="0.1 0.02 0.01" mass="2" fullinertia="0.03 0.025 0.02 0.001 0.002 0.003"/>
          <body name="l3" pos="0.3 0 0" quat="0.9 0.1 0.2 0.3">
            <joint name="j3" axis="1 0 0"/>
            <geom type="box" size="0.15 0.04 0.03" pos="0.15 0 0"/>
            <body name="l4" pos="0.3 0 0" euler="0 -90 0">
              <joint name="j4" axis="0 0 1" pos="0.01 0.02 0"/>
              <geom type="capsule" fromto="0 0 0 0.25 0 0" size="0.04"/>
              <body name="l5" pos="0.25 0 0">
                <joint name="j5" class="wrist" axis="1 0 0"/>
                <geom type="sphere" size="0.05"/>
                <body name="l6" pos="0.05 0 0" euler="0 0 45">
                  <joint name="j6" class="wrist" axis="0 1 0"/>
                  <geom type="box" size="0.03 0.03 0.03"/>
                  <body name="l7" pos="0.06 0 0">
                    <joint name="j7" class="wrist" axis="1 0 0"/>
                    <geom type="cylinder" size="0.03 0.02" euler="0 90 0"/>
                    <body name="tool" pos="0.05 0 0"><geom type="sphere" size="0.02"/></body>
                  </body>
                </body>
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""

TREE = """<mujoco model="tree">
  <default><joint armature="0.05" damping="0.3"/></default>
  <worldbody>
    <body name="torso" pos="0 0 0.5">
      <joint name="waist" axis="0 0 1" frictionloss="0.4"/>
      <geom type="box" size="0.1 0.2 0.3"/>
      <body name="left" pos="0 0.25 0.2" axisangle="1 0 0 0.3">
        <joint name="left1" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.04"/>
        <body name="left2" pos="0.3 0 0">
          <joint name="left2" type="slide" axis="1 0 0" damping="2"/>
          <joint name="left3" axis="0 0 1" pos="0.02 0 0"/>
          <geom type="sphere" size="0.05" pos="0.1 0 0"/>
        </body>
      </body>
      <body name="right" pos="0 -0.25 0.2">
        <joint name="right1" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.04"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def full_mass_matrix(m, qpos) -> np.ndarray:
    """MuJoCo's joint-space inertia (armature included) at ``qpos``."""
    d = mujoco.MjData(m)
    d.qpos[:] = qpos
    mujoco.mj_forward(m, d)
    full = np.zeros((m.nv, m.nv))
    if hasattr(d, "qM"):  # MuJoCo 3
        mujoco.mj_fullM(m, full, d.qM)
    else:  # MuJoCo 4: mj_fullM(m, d, dst)
        mujoco.mj_fullM(m, d, full)
    return full


@pytest.mark.parametrize("xml", [ARM7, TREE], ids=["arm7_defaults", "tree"])
def test_hand_written_mjcf_loads_with_the_dynamics_mujoco_computes(xml, tmp_path):
    path = tmp_path / "robot.xml"
    path.write_text(xml, encoding="utf-8")
    robot = mindyn.load(path)
    m = mujoco.MjModel.from_xml_path(str(path))
    assert sorted(robot.joint_names) == sorted(m.joint(j).name for j in range(m.njnt))
    # the terms the file gives (through its classes), read back
    by_class = {"j5": 0.015, "j6": 0.015, "j7": 0.015}
    for k, name in enumerate(robot.joint_names):
        if xml is ARM7:
            assert robot.rotor_inertia[k] == by_class.get(name, 0.12)
            assert robot.coulomb[k] == (0.05 if name in by_class else 0.25)
        elif name == "left2":
            assert robot.viscous[k] == 2.0 and robot.joint_types[k] == "prismatic"
    if xml is ARM7:
        np.testing.assert_array_equal(robot.gravity, [0.3, -0.2, -9.7])
        np.testing.assert_allclose(robot.limits["upper"][4:], np.radians(120), rtol=1e-15)
    else:
        assert not robot.is_serial
    rng = np.random.default_rng(5)
    q, dq, ddq = states(robot, rng)
    got = robot.inverse_dynamics(q, dq, ddq, robot.parameters(rotor=True, friction=True))
    ref, _ = mj_inverse(m, robot.joint_names, q, dq, ddq)
    assert_close(got, ref + robot.coulomb * np.sign(dq), TOL, "MJCF in vs mj_inverse")
    # the mass matrix with the armature, against MuJoCo's
    adr = [int(m.jnt_qposadr[m.joint(n).id]) for n in robot.joint_names]
    dof = [int(m.jnt_dofadr[m.joint(n).id]) for n in robot.joint_names]
    qpos = np.array(m.qpos0)
    qpos[adr] = q[0]
    full = full_mass_matrix(m, qpos)
    mass = robot.mass_matrix(q[0]) + np.diag(robot.rotor_inertia)
    assert_close(mass, full[np.ix_(dof, dof)], TOL, "MJCF in mass matrix vs mj_fullM")


def test_mjcf_written_back_keeps_the_file_and_changes_only_the_dynamics(tmp_path):
    src = tmp_path / "arm7.xml"
    src.write_text(ARM7, encoding="utf-8")
    robot = mindyn.load(src)
    # new parameters: the model's inertia scaled and moved, new joint terms
    rng = np.random.default_rng(2)
    p = physical_params(robot, rng)
    out = write_mjcf(robot, p, tmp_path / "identified.xml").path
    text = out.read_text()
    assert "<!-- seven revolute joints; defaults by class -->" in text
    assert '<compiler angle="degree" eulerseq="zyx"/>' in text
    assert '<body name="l3" pos="0.3 0 0" quat="0.9 0.1 0.2 0.3">' in text

    # the base (fixed to the world) keeps its geom-derived inertia; every other line is kept
    # but for the inertials and joints
    def rest(t):
        t = re.sub(r"\s*<inertial [^>]*/>", "", t)
        return re.sub(r' (armature|damping|frictionloss)="[^"]*"', "", t).strip()

    assert rest(text) == rest(ARM7)
    assert text.count("<inertial") == 8  # l1 .. l7 and the tool merged into l7 (zero)
    again = mindyn.load(out)
    assert again.joint_names == robot.joint_names
    np.testing.assert_allclose(
        again.parameters(rotor=True, friction=True), p, rtol=0, atol=ROUND_TRIP
    )
    # MuJoCo simulates the new parameters: its inverse dynamics is mindyn's with them
    q, dq, ddq = states(robot, rng)
    ref, _ = mj_inverse(mujoco.MjModel.from_xml_path(str(out)), robot.joint_names, q, dq, ddq)
    got = robot.inverse_dynamics(q, dq, ddq, p)
    assert_close(got, ref + split(robot, p)[3] * np.sign(dq), TOL, "MJCF written back")


GEARED = """<mujoco model="geared">
  <default><joint armature="0.02" damping="0.1" frictionloss="0.05"/></default>
  <worldbody>
    <body name="a" pos="0 0 0.2">
      <joint name="h1" axis="0 0 1"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.04"/>
      <body name="b" pos="0.3 0 0" euler="0.4 0 0">
        <joint name="h2" axis="0 1 0"/>
        <geom type="box" size="0.12 0.03 0.02" pos="0.12 0 0"/>
      </body>
    </body>
  </worldbody>
  <tendon>
    <fixed name="motor2" armature="3e-4" damping="2e-3" frictionloss="0.01">
      <joint joint="h2" coef="-40"/>
    </fixed>
  </tendon>
  <actuator><motor name="motor2" tendon="motor2"/></actuator>
</mujoco>
"""


def test_mjcf_tendon_over_one_joint_is_folded_onto_it(tmp_path):
    """A fixed tendon over one joint with coefficient c: its armature, damping, frictionloss
    act on the joint as c^2 armature, c^2 damping, |c| frictionloss; written back, they are
    on the joint and zero on the tendon."""
    path = tmp_path / "geared.xml"
    path.write_text(GEARED, encoding="utf-8")
    robot = mindyn.load(path)
    assert robot.joint_names == ["h1", "h2"]
    np.testing.assert_allclose(robot.rotor_inertia, [0.02, 0.02 + 1600 * 3e-4], rtol=1e-15)
    np.testing.assert_allclose(robot.viscous, [0.1, 0.1 + 1600 * 2e-3], rtol=1e-15)
    np.testing.assert_allclose(robot.coulomb, [0.05, 0.05 + 40 * 0.01], rtol=1e-15)
    m = mujoco.MjModel.from_xml_path(str(path))
    rng = np.random.default_rng(6)
    q, dq, ddq = states(robot, rng)
    got = robot.inverse_dynamics(q, dq, ddq, robot.parameters(rotor=True, friction=True))
    ref, _ = mj_inverse(m, robot.joint_names, q, dq, ddq)
    assert_close(got, ref + robot.coulomb * np.sign(dq), TOL, "MJCF tendon folded vs mj_inverse")
    # with frictionloss, moving: MuJoCo's joint and tendon dry friction, both saturated
    q, dq, ddq = states(robot, rng, m=1, speed=(1.0, 2.0))
    ref, d = mj_inverse(m, robot.joint_names, q, dq, ddq, disable=_no_limits())
    assert d.nefc == 3 and (d.efc_type == mujoco.mjtConstraint.mjCNSTR_FRICTION_TENDON).sum() == 1
    got = robot.inverse_dynamics(q, dq, ddq, robot.parameters(rotor=True, friction=True))
    assert_close(got, ref, TOL, "MJCF tendon folded, frictionloss moving")
    # written back: the new terms on the joints, none left on the tendon
    p = physical_params(robot, rng)
    out = write_mjcf(robot, p, tmp_path / "back.xml")
    assert any("tendon 'motor2'" in n for n in out.notes)
    text = out.path.read_text()
    assert '<fixed name="motor2" armature="0.0" damping="0.0" frictionloss="0.0">' in text
    again = mindyn.load(out.path)
    np.testing.assert_allclose(
        again.parameters(rotor=True, friction=True), p, rtol=0, atol=ROUND_TRIP
    )
    ref, _ = mj_inverse(mujoco.MjModel.from_xml_path(str(out.path)), robot.joint_names, q, dq, ddq)
    got = robot.inverse_dynamics(q, dq, ddq, p)
    assert_close(got, ref + split(robot, p)[3] * np.sign(dq), TOL, "MJCF tendon written back")


def test_mjcf_tendon_terms_the_model_cannot_hold_are_refused_by_name(tmp_path):
    body = (
        '<worldbody><site name="s0"/><body name="a"><joint name="h1" axis="0 0 1"/>'
        '<geom size="0.1"/><site name="s1" pos="0.1 0 0"/><body name="b" pos="0.2 0 0">'
        '<joint name="h2" axis="0 0 1"/><geom size="0.1"/></body></body></worldbody>'
    )
    cases = {
        "redundant": (
            '<fixed name="d1" damping="0.2"><joint joint="h1" coef="1"/>'
            '<joint joint="h2" coef="1"/></fixed><fixed name="d2" armature="0.1">'
            '<joint joint="h1" coef="1"/><joint joint="h2" coef="-1"/></fixed>'
            '<fixed name="own" frictionloss="0.1"><joint joint="h1" coef="2"/></fixed>',
            "tendons 'd1', 'd2' carry motor terms: with the joints' own terms (on 'h1') that is "
            "3 motors for 2 joints",
        ),
        "spatial": (
            '<spatial name="cable" frictionloss="0.3"><site site="s0"/><site site="s1"/></spatial>',
            "tendon 'cable' is a spatial tendon and has frictionloss 0.3",
        ),
        "spring": (
            '<fixed name="k" stiffness="5"><joint joint="h1" coef="2"/></fixed>',
            "tendon 'k' has a spring (stiffness 5.0)",
        ),
    }
    path = tmp_path / "tendon.xml"
    for tendon, message in cases.values():
        path.write_text(f"<mujoco>{body}<tendon>{tendon}</tendon></mujoco>")
        with pytest.raises(mindyn.ModelError) as e:
            mindyn.load(path)
        assert message in str(e.value) and "\n" not in str(e.value), str(e.value)


DIFFERENTIAL_MJCF = """
<mujoco model="wrist">
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="a" pos="0 0 0.3">
      <joint name="h0" axis="0 0 1" armature="0.02" damping="0.1" frictionloss="0.2"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.04"/>
      <body name="b" pos="0.3 0 0">
        <joint name="h1" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0.25 0 0.05" size="0.03"/>
        <body name="c" pos="0.25 0 0.05">
          <joint name="h2" axis="1 0 0"/>
          <geom type="box" size="0.05 0.03 0.02" pos="0.05 0.01 0"/>
        </body>
      </body>
    </body>
  </worldbody>
  <tendon>
    <fixed name="ma" armature="0.004" damping="0.03" frictionloss="0.05">
      <joint joint="h1" coef="20"/><joint joint="h2" coef="20"/>
    </fixed>
    <fixed name="mb" armature="0.006" damping="0.02" frictionloss="0.04">
      <joint joint="h1" coef="15"/><joint joint="h2" coef="-15"/>
    </fixed>
  </tendon>
</mujoco>
"""


def test_mjcf_tendons_over_several_joints_are_motors_with_mujocos_dynamics(tmp_path):
    """MuJoCo applies a fixed tendon's armature as armature J^T J in the mass matrix, its damping
    as -damping J^T (J dq) and its frictionloss as a dry friction on J dq: the motor-side
    model's terms with J the motor's row of T. Read back as such, checked against mj_fullM and
    mj_inverse (frictionloss disabled, then enabled and saturated at moving states)."""
    path = tmp_path / "wrist.xml"
    path.write_text(DIFFERENTIAL_MJCF, encoding="utf-8")
    robot = mindyn.load(path)
    tr = robot.transmission
    assert robot.drive_side == "motor" and tr.motors == ("ma", "mb", "h0")
    assert tr.types == ("tendon", "tendon", "direct")
    T = np.array([[0, 20, 20], [0, 15, -15], [1, 0, 0]], dtype=float)
    np.testing.assert_array_equal(tr.T, T)
    ia, fv, fc = (
        np.array([0.004, 0.006, 0.02]),
        np.array([0.03, 0.02, 0.1]),
        np.array([0.05, 0.04, 0.2]),
    )
    p = robot.parameters(rotor=True, friction=True)
    np.testing.assert_array_equal(p.reshape(3, 13)[:, 10:], np.column_stack([ia, fv, fc]))
    m = mujoco.MjModel.from_xml_path(str(path))
    rng = np.random.default_rng(11)
    q, dq, ddq = states(robot, rng, m=5, speed=(0.3, 1.0))
    adr = [int(m.jnt_qposadr[m.joint(n).id]) for n in robot.joint_names]
    dof = [int(m.jnt_dofadr[m.joint(n).id]) for n in robot.joint_names]
    for qi in q:  # armature: T^T diag(Ia) T added to the mass matrix
        qpos = np.array(m.qpos0)
        qpos[adr] = qi
        full = full_mass_matrix(m, qpos)[np.ix_(dof, dof)]
        mass = robot.mass_matrix(qi) + T.T @ np.diag(ia) @ T
        assert_close(mass, full, TOL, "tendon armature vs mj_fullM")
    sign = np.sign(dq @ T.T)
    got = robot.inverse_dynamics(q, dq, ddq, p)
    ref, _ = mj_inverse(m, robot.joint_names, q, dq, ddq)  # damping in, frictionloss out
    assert_close(got, ref + (fc * sign) @ T, TOL, "tendon motors vs mj_inverse")
    # frictionloss on: MuJoCo's dry friction on each tendon velocity, saturated while it moves
    on = mujoco.mjtDisableBit.mjDSBL_LIMIT | mujoco.mjtDisableBit.mjDSBL_CONTACT
    linear = (mujoco.mjtConstraintState.mjCNSTRSTATE_LINEARNEG,
              mujoco.mjtConstraintState.mjCNSTRSTATE_LINEARPOS)  # fmt: skip
    for i in range(q.shape[0]):
        full, d = mj_inverse(m, robot.joint_names, q[i], dq[i], ddq[i], disable=on)
        kinds = d.efc_type[: d.nefc]
        assert (kinds == mujoco.mjtConstraint.mjCNSTR_FRICTION_TENDON).sum() == 2
        assert np.isin(d.efc_state[: d.nefc], linear).all()
        assert_close(got[i], full[0], TOL, "tendon motors vs mj_inverse with frictionloss")


BAD = {
    "spring": (
        '<joint name="s1" axis="0 0 1" stiffness="3"/>',
        "joint 's1' (body 'a') has a spring",
    ),
    "ref": ('<joint name="r1" axis="0 0 1" ref="0.2"/>', "joint 'r1' (body 'a') has ref=0.2"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_mjcf_joints_the_model_cannot_hold_are_refused_by_name(case, tmp_path):
    joint, message = BAD[case]
    path = tmp_path / "bad.xml"
    path.write_text(
        f'<mujoco><compiler angle="radian"/><worldbody><body name="a">{joint}'
        '<geom size="0.1"/></body></worldbody></mujoco>'
    )
    with pytest.raises(mindyn.ModelError) as e:
        mindyn.load(path)
    assert message in str(e.value) and "\n" not in str(e.value) and str(path) in str(e.value)


def test_a_joint_reference_is_refused_in_the_unit_it_is_shown_in(tmp_path):
    """MuJoCo compiles a hinge's ref from the file's unit (degrees by default) to radians: the
    refusal gives the compiled value with its unit, so that ref="0.2" (degrees) read as
    0.00349 rad does not look like another number than the file's."""
    path = tmp_path / "ref.xml"
    for compiler, joint, shown in (
        ("", 'axis="0 0 1" ref="0.2"', f"has ref={math.radians(0.2)!r} rad (an angle of"),
        ('<compiler angle="radian"/>', 'axis="0 0 1" ref="0.2"', "has ref=0.2 rad"),
        ("", 'type="slide" axis="0 0 1" ref="0.2"', "has ref=0.2 m;"),
    ):
        path.write_text(
            f'<mujoco>{compiler}<worldbody><body name="a"><joint name="r1" {joint}/>'
            '<geom size="0.1"/></body></worldbody></mujoco>'
        )
        with pytest.raises(mindyn.ModelError) as e:
            mindyn.load(path)
        assert shown in str(e.value) and "\n" not in str(e.value), str(e.value)


def test_mjcf_equality_and_mocap_are_refused(tmp_path):
    path = tmp_path / "eq.xml"
    path.write_text(
        '<mujoco><worldbody><body name="a"><joint name="h1" axis="0 0 1"/><geom size="0.1"/>'
        '<body name="b"><joint name="h2" axis="0 0 1"/><geom size="0.1"/></body></body>'
        '</worldbody><equality><joint name="couple" joint1="h1" joint2="h2"/></equality>'
        "</mujoco>"
    )
    with pytest.raises(mindyn.ModelError, match="equality 'couple' <joint joint1=\"h1\" joint2="):
        mindyn.load(path)
    path.write_text(
        '<mujoco><worldbody><body name="hand" mocap="true"><body name="f">'
        '<joint name="h1" axis="0 0 1"/><geom size="0.1"/></body></body></worldbody></mujoco>'
    )
    with pytest.raises(mindyn.ModelError, match="joint 'h1' .*mocap body 'hand'"):
        mindyn.load(path)


def test_without_mujoco_the_error_says_what_to_install(tmp_path, monkeypatch, capsys):
    path = tmp_path / "arm.xml"
    path.write_text(ARM7, encoding="utf-8")
    monkeypatch.setitem(sys.modules, "mujoco", None)  # import mujoco raises ImportError
    with pytest.raises(mindyn.ModelError) as e:
        mindyn.load(path)
    assert 'pip install "mindyn[mujoco]"' in str(e.value) and "\n" not in str(e.value)
    from mindyn.cli import main

    assert main(["info", str(path)]) != 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and 'pip install "mindyn[mujoco]"' in err, err


# -- command line -------------------------------------------------------------------------------
def test_cli_export_mjcf_and_urdf_refused_for_an_mjcf_robot(tmp_path):
    import json

    robot = mindyn.load(REPO_UR5)
    p = physical_params(robot, np.random.default_rng(4))
    ident = tmp_path / "id.json"
    names = robot.parameter_names(rotor=True, friction=True)
    ident.write_text(json.dumps({"robot": robot.name, "classical": dict(zip(names, p.tolist()))}))
    out = tmp_path / "ur5.xml"
    assert f"wrote {out}" in cli("export", REPO_UR5, ident, "--mjcf", out)
    again = mindyn.load(out)
    np.testing.assert_allclose(
        again.parameters(rotor=True, friction=True), p, rtol=0, atol=ROUND_TRIP
    )
    # and written back from the MJCF, where --urdf is refused
    back = tmp_path / "back.xml"
    cli("export", out, ident, "--mjcf", back)
    np.testing.assert_allclose(
        mindyn.load(back).parameters(rotor=True, friction=True), p, atol=ROUND_TRIP
    )
    from mindyn.cli import main

    for option in ("--urdf", "--yaml"):
        assert main(["export", str(out), str(ident), option, str(tmp_path / "x")]) == 2
    argv = ["export", str(REPO_UR5), str(ident), "--mjcf", str(back), "--sidecar", "s.yaml"]
    assert main(argv) == 2 and not (tmp_path / "s.yaml").exists()


def test_velocity_limits_survive_mjcf_export_and_load(tmp_path):
    """MJCF has no joint velocity limit: `export --mjcf` wrote none and the file read back had
    none. A URDF with a different velocity limit per joint (read from it here), exported and
    loaded again, gives the same limits, also once written back from the MJCF; MuJoCo still
    compiles the file, holding each limit as a custom numeric."""
    import json
    import xml.etree.ElementTree as ET

    speeds = iter([1.25, 2.5, 3.75, 0.625, 5.0, 7.125])
    text = re.sub(
        r'velocity="[^"]*"', lambda _: f'velocity="{next(speeds)!r}"', REPO_UR5.read_text()
    )
    urdf = tmp_path / "ur5_speeds.urdf"
    urdf.write_text(text)
    joints = {j.get("name"): j for j in ET.parse(urdf).getroot().findall("joint")}
    robot = mindyn.load(urdf)
    written = [float(joints[n].find("limit").get("velocity")) for n in robot.joint_names]
    assert sorted(written) == [0.625, 1.25, 2.5, 3.75, 5.0, 7.125]
    p = physical_params(robot, np.random.default_rng(5))
    ident = tmp_path / "id.json"
    names = robot.parameter_names(rotor=True, friction=True)
    ident.write_text(json.dumps({"robot": robot.name, "classical": dict(zip(names, p.tolist()))}))
    out = tmp_path / "ur5.xml"
    cli("export", urdf, ident, "--mjcf", out)
    np.testing.assert_array_equal(mindyn.load(out).limits["velocity"], written)
    m = mujoco.MjModel.from_xml_path(str(out))
    held = {
        mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_NUMERIC, i): float(
            m.numeric_data[m.numeric_adr[i]]
        )
        for i in range(m.nnumeric)
    }
    assert held == {f"velocity_limit:{n}": v for n, v in zip(robot.joint_names, written)}
    back = tmp_path / "back.xml"  # written back from the MJCF: the file's numerics kept
    cli("export", out, ident, "--mjcf", back)
    np.testing.assert_array_equal(mindyn.load(back).limits["velocity"], written)


@pytest.mark.parametrize(
    ("numeric", "said"),
    [
        ('name="velocity_limit:elbow" data="2"', "no joint 'elbow'"),
        ('name="velocity_limit:j1" data="-2"', "expected one positive velocity limit, got data -2"),
        (
            'name="velocity_limit:j1" data="1 2"',
            "expected one positive velocity limit, got data 1 2",
        ),
    ],
)
def test_a_velocity_limit_numeric_that_fits_no_joint_is_refused_by_name(numeric, said, tmp_path):
    path = tmp_path / "one.xml"
    path.write_text(
        '<mujoco><worldbody><body name="b"><joint name="j1" type="hinge"/>'
        '<inertial pos="0.1 0 0" mass="1" diaginertia="0.1 0.1 0.1"/></body></worldbody>'
        f"<custom><numeric {numeric}/></custom></mujoco>"
    )
    mujoco.MjModel.from_xml_path(str(path))  # MuJoCo takes it
    with pytest.raises(mindyn.ModelError, match=re.escape(said)):
        mindyn.load(path)


def test_mjcf_with_a_tip_loads_the_chain_and_is_written_back_whole_only(tmp_path):
    path = tmp_path / "arm7.xml"
    path.write_text(ARM7, encoding="utf-8")
    chain = mindyn.load(path, tip="l4")
    assert chain.joint_names == ["j1", "j2", "j3", "j4"]
    whole = mindyn.load(path)
    # the links beyond l4 are merged into it at q = 0: the whole model's gravity torque there
    assert_close(chain.gravity_torque(np.zeros(4)), whole.gravity_torque(np.zeros(7))[:4], 1e-12,
                 "MJCF tip vs whole model")  # fmt: skip
    with pytest.raises(mindyn.ModelError, match="4 of the file's 7 joints"):
        write_mjcf(chain, chain.params, tmp_path / "x.xml")


def test_cli_identify_consistent_mjcf(tmp_path):
    """``identify --consistent --mjcf``: MuJoCo's inverse dynamics of the written MJCF is the
    prediction of the JSON's classical parameters."""
    import json

    from mindyn.control import simulate_inverse
    from mindyn.identification.data import write_csv
    from mindyn.identification.excitation import random_trajectory

    robot = mindyn.load("planar3")
    log = simulate_inverse(robot, random_trajectory(robot, seed=3), rate=50.0, seed=2)
    fit = tmp_path / "fit.csv"
    write_csv(fit, log.t, log.q, log.tau, dq=log.dq)
    ident, out = tmp_path / "id.json", tmp_path / "planar3.xml"
    stdout = cli("identify", "planar3", fit, "--consistent", "--json", ident, "--mjcf", out)
    assert f"wrote {out}" in stdout
    classical = json.loads(ident.read_text())["classical"]
    p = np.array([classical[k] for k in robot.param_names])
    q, dq, ddq = states(robot, np.random.default_rng(1))
    got, _ = mj_inverse(mujoco.MjModel.from_xml_path(str(out)), robot.joint_names, q, dq, ddq)
    assert_close(got, robot.inverse_dynamics(q, dq, ddq, p), TOL, "identify --mjcf vs mindyn")
    assert re.search(r"frictionloss=\"0\.0\"", out.read_text())


def test_write_back_checked_by_compiling_and_mocap_markers_left_out(tmp_path):
    """A mocap marker (and what hangs from it) is not part of the robot; a compiler option that
    overrides the written inertials is caught by compiling the written file."""
    path = tmp_path / "m.xml"
    path.write_text(
        '<mujoco><worldbody><body name="target" mocap="true"><geom size="0.02"/>'
        '<body name="marker"><geom size="0.01"/></body></body>'
        '<body name="a"><joint name="h1" axis="0 0 1"/><geom size="0.1"/></body>'
        "</worldbody></mujoco>"
    )
    robot = mindyn.load(path)
    assert robot.link_names == ["world", "a"]
    # a sphere of radius 0.1 and density 1000: its mass
    assert robot.params[9] == pytest.approx(1000 * 4 / 3 * np.pi * 0.1**3, rel=1e-12)
    write_mjcf(robot, 2 * robot.params, tmp_path / "ok.xml")
    assert mindyn.load(tmp_path / "ok.xml").params[9] == pytest.approx(2 * robot.params[9])
    text = path.read_text().replace("<mujoco>", '<mujoco><compiler inertiafromgeom="true"/>')
    path.write_text(text)
    with pytest.raises(mindyn.ModelError, match="MuJoCo compiles link 'a' to other inertial"):
        write_mjcf(robot, 2 * robot.params, tmp_path / "bad.xml")


def test_exported_mjcf_of_a_tree_is_pinocchio_plus_the_joint_terms(tmp_path):
    """Baxter whole (head, both arms, grippers: a tree), its drive terms on the joints: the
    MJCF's bodies nest as the tree."""
    robot = joint_side(mindyn.load(BAXTER))
    assert not robot.is_serial
    rng = np.random.default_rng(8)
    p = physical_params(robot, rng)
    inertial, ia, fv, fc = split(robot, p)
    out = write_mjcf(robot, p, tmp_path / "baxter.xml").path
    q, dq, ddq = states(robot, rng, m=3)
    ref = baxter_rnea(robot, inertial, q, dq, ddq) + ia * ddq + fv * dq + fc * np.sign(dq)
    got, _ = mj_inverse(mujoco.MjModel.from_xml_path(str(out)), robot.joint_names, q, dq, ddq)
    assert_close(got + fc * np.sign(dq), ref, TOL, "MJCF of a tree vs Pinocchio + terms")


def test_mjcf_export_names_the_limits_and_drive_table_it_cannot_write(tmp_path):
    """A new MJCF has no place for acceleration limits or the drive table (rated torque, gear
    ratio) that a YAML table gives: export said nothing of them and the file read back had
    none. The note names them; a URDF without them gets no such note."""
    robot = mindyn.load("zcr07s")
    assert np.all(np.isfinite(robot.limits["acceleration"]))
    assert np.all(np.isfinite(robot.drives["rated_torque"]))
    out = write_mjcf(robot, robot.params, tmp_path / "zcr07s.xml")
    back = mindyn.load(out.path)
    assert np.all(np.isnan(back.limits["acceleration"]))
    assert np.all(np.isnan(back.drives["rated_torque"]))
    said = [n for n in out.notes if "which MJCF has no place for, are not written" in n]
    assert len(said) == 1
    assert "acceleration limits" in said[0] and "rated torques, gear ratios)" in said[0]
    assert "torque constants" not in said[0]  # the table gives none
    ur5 = mindyn.load(REPO_UR5)
    plain = write_mjcf(ur5, ur5.params, tmp_path / "ur5.xml")
    assert not [n for n in plain.notes if "no place for, are not written" in n]


def test_info_says_an_mjcf_is_an_mjcf(tmp_path):
    """`mindyn info` printed '(6 joints, urdf)' for a MuJoCo file: the frame convention it is
    read in (robot.convention), which reads as the file's format. It names the MJCF and the
    frames; a URDF keeps its line."""
    robot = mindyn.load(REPO_UR5)
    out = write_mjcf(robot, robot.params, tmp_path / "ur5.xml")
    assert mindyn.load(out.path).convention == "urdf"
    head = cli("info", out.path).splitlines()[0]
    assert "(6 joints, MJCF, link frames as a URDF's)" in head, head
    assert "(6 joints, urdf)" in cli("info", REPO_UR5).splitlines()[0]


def test_write_mjcf_refuses_none_without_offering_it(tmp_path):
    """write_mjcf needs parameters: None is refused saying what it takes, and a wrong length
    does not offer None among the shapes it expects."""
    from mindyn.mjcf import write_mjcf

    robot = mindyn.load("planar2")
    with pytest.raises(mindyn.ArgumentError, match=r"is None; expected a vector of shape \(20,\)"):
        write_mjcf(robot, None, tmp_path / "a.xml")
    with pytest.raises(mindyn.ArgumentError, match=r"7 entries") as e:
        write_mjcf(robot, np.zeros(7), tmp_path / "a.xml")
    assert "None" not in str(e.value)
    assert not list(tmp_path.iterdir())


BRANCHES_MJCF = """
<mujoco model="branches">
  <compiler angle="radian"/>
  <worldbody>
    <body name="torso" pos="0 0 0.5">
      <joint name="waist" axis="0 0 1"/>
      <geom type="box" size="0.1 0.2 0.3"/>
      <body name="left" pos="0 0.25 0.2">
        <joint name="left" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.04"/>
      </body>
      <body name="right" pos="0 -0.25 0.2" euler="0.3 0 0">
        <joint name="right" axis="1 0 0"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0.1" size="0.04"/>
      </body>
    </body>
  </worldbody>
  <tendon>
    <fixed name="both" {terms}>
      <joint joint="left" coef="20"/><joint joint="right" coef="-15"/>
    </fixed>
  </tendon>
</mujoco>
"""


def test_tendon_armature_across_branches_is_refused_by_name(tmp_path):
    """MuJoCo adds a tendon's armature to its joint-space inertia only where that sparse matrix
    has entries, between joints of one branch: a tendon over two sibling joints gets a * c^2
    on each diagonal but not the a * c1 * c2 between them that J^T a J has. Read as a motor,
    mindyn's model would have the whole J^T a J, not MuJoCo's dynamics (it was read so, 5 %
    off mj_inverse): refused naming the tendon and the joints. Its damping and frictionloss,
    forces through J, are MuJoCo's exactly and still read."""
    path = tmp_path / "branches.xml"
    path.write_text(BRANCHES_MJCF.format(terms='armature="0.01"'), encoding="utf-8")
    m = mujoco.MjModel.from_xml_path(str(path))
    bare = mujoco.MjModel.from_xml_path(str(path))
    bare.tendon_armature[:] = 0.0
    left, right = (int(m.jnt_dofadr[m.joint(n).id]) for n in ("left", "right"))
    added = full_mass_matrix(m, m.qpos0) - full_mass_matrix(bare, bare.qpos0)
    # MuJoCo's behaviour, pinned: the diagonal terms, nothing between the branches
    np.testing.assert_allclose(added[left, left], 0.01 * 400, rtol=1e-12)
    np.testing.assert_allclose(added[right, right], 0.01 * 225, rtol=1e-12)
    assert added[left, right] == 0.0
    with pytest.raises(mindyn.ModelError) as e:
        mindyn.load(path)
    said = str(e.value)
    assert str(path) in said and "\n" not in said
    assert "tendon 'both' has armature 0.01" in said and "'left' and 'right'" in said, said
    # without armature: the tendon's damping and frictionloss are read, MuJoCo's dynamics
    path.write_text(BRANCHES_MJCF.format(terms='damping="0.3" frictionloss="0.2"'))
    robot = mindyn.load(path)
    assert robot.transmission.motors[0] == "both"
    m = mujoco.MjModel.from_xml_path(str(path))
    q, dq, ddq = states(robot, np.random.default_rng(4), speed=(0.3, 1.0))
    coefs = {"waist": 0.0, "left": 20.0, "right": -15.0}
    J = np.array([coefs[name] for name in robot.joint_names])
    ref, _ = mj_inverse(m, robot.joint_names, q, dq, ddq)  # damping in, frictionloss out
    ref += np.outer(0.2 * np.sign(dq @ J), J)
    got = robot.inverse_dynamics(q, dq, ddq, robot.parameters(rotor=True, friction=True))
    assert_close(got, ref, TOL, "tendon across branches (damping, frictionloss) vs mj_inverse")


BRANCHES_URDF = """<robot name="branches">
  <link name="base"/>
  <link name="a"><inertial><mass value="1"/><origin xyz="0.1 0 0"/>
    <inertia ixx="0.01" iyy="0.02" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="b"><inertial><mass value="2"/><origin xyz="0 0.1 0"/>
    <inertia ixx="0.02" iyy="0.01" izz="0.03" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="ja" type="revolute"><parent link="base"/><child link="a"/>
    <origin xyz="0 0.2 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
  <joint name="jb" type="revolute"><parent link="base"/><child link="b"/>
    <origin xyz="0 -0.2 0"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
  <transmission name="diff"><type>transmission_interface/DifferentialTransmission</type>
    <actuator name="m1"><role>actuator1</role><mechanicalReduction>50</mechanicalReduction>
    </actuator>
    <actuator name="m2"><role>actuator2</role><mechanicalReduction>50</mechanicalReduction>
    </actuator>
    <joint name="ja"><role>joint1</role></joint>
    <joint name="jb"><role>joint2</role></joint>
  </transmission>
</robot>
"""


def test_mjcf_export_refuses_motor_inertia_coupling_two_branches(tmp_path):
    """The writer's side of the same: motors of a differential over two joints hanging from
    the base (two branches) with rotor inertia would be tendons whose armature MuJoCo applies
    without the terms between the branches; refused naming the motor and joints. Without rotor
    inertia, or with the terms on the joints, the file is written and MuJoCo's inverse
    dynamics is the motor-side formula."""
    path = tmp_path / "branches.urdf"
    path.write_text(BRANCHES_URDF)
    robot = mindyn.load(path)
    assert robot.drive_side == "motor" and not robot.is_serial
    p = physical_params(robot, np.random.default_rng(9))
    with pytest.raises(mindyn.ModelError) as e:
        write_mjcf(robot, p, tmp_path / "x.xml")
    said = str(e.value)
    assert "motor 'm1' has rotor inertia" in said and "'ja' and 'jb'" in said, said
    assert not (tmp_path / "x.xml").exists()
    inertial, ia, fv, fc = split(robot, p)
    p[10::13] = 0.0
    out = write_mjcf(robot, p, tmp_path / "ok.xml").path
    T = robot.transmission.T
    m = mujoco.MjModel.from_xml_path(str(out))
    q, dq, ddq = states(robot, np.random.default_rng(3))
    model = pin.buildModelFromUrdf(str(path))  # a tree: Pinocchio's own URDF parser
    set_pinocchio_params(model, robot, inertial)
    rnea = pin_rnea(model, q, dq, ddq)
    ref = rnea + (fv * (dq @ T.T)) @ T + (fc * np.sign(dq @ T.T)) @ T
    got, _ = mj_inverse(m, robot.joint_names, q, dq, ddq)
    assert_close(got + (fc * np.sign(dq @ T.T)) @ T, ref, TOL, "differential across branches")
    write_mjcf(robot, p, tmp_path / "joint.xml", drive_side="joint")


WRIST_URDF = """<robot name="wrist">
  <link name="base"/>
  <link name="arm"/>
  <link name="cross"/>
  <link name="hand"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="arm"/>
    <origin xyz="0 0 0.3" rpy="0.2 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
  <joint name="pitch" type="revolute"><parent link="arm"/><child link="cross"/>
    <origin xyz="0.4 0 0" rpy="0 0 0.4"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
  <joint name="yaw" type="revolute"><parent link="cross"/><child link="hand"/>
    <origin xyz="0.02 0 0.05" rpy="{rpy}"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
  <joint name="slide" type="prismatic"><parent link="hand"/><child link="tip"/>
    <origin xyz="0.1 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-0.1" upper="0.1" effort="10" velocity="2"/></joint>
  <link name="tip"/>
</robot>
"""


@pytest.mark.parametrize("rpy", ["0 0 0", "0 0.3 0"])
def test_mjcf_export_of_a_massless_link_between_two_joints(rpy, tmp_path):
    """A universal wrist: a massless link ('cross') between two revolute joints. MuJoCo refuses
    a moving body without mass, so export --mjcf failed for such a robot (and for a robot read
    from an MJCF body with two joints, written as a new file). Where the link's frame turns
    with its joint only (no rotation to the next joint), both joints go into one body, the
    second with its anchor: mj_inverse of the file is Pinocchio's rnea plus the joint terms,
    and the file reads back with the same dynamics; with a rotation between them the robot is
    refused before MuJoCo's compiler, in one line naming the link, its child joint and the
    turn."""
    path = tmp_path / "wrist.urdf"
    path.write_text(WRIST_URDF.replace("{rpy}", rpy))
    robot = mindyn.load(path)
    assert robot.joint_names == ["shoulder", "pitch", "yaw", "slide"]
    rng = np.random.default_rng(13)
    p = physical_params(robot, rng)
    p[13:23] = 0.0  # the cross link: no mass
    out = tmp_path / "wrist.xml"
    if rpy != "0 0 0":
        with pytest.raises(mindyn.ModelError) as e:
            write_mjcf(robot, p, out)
        msg = str(e.value)
        assert "\n" not in msg, msg
        # names the link, the joint and the turn between them (0.3 rad)
        assert msg.startswith("link 'cross' has no mass"), msg
        assert "child joint 'yaw'" in msg and f"turned by {np.degrees(0.3):.4g} deg" in msg, msg
        return
    written = write_mjcf(robot, p, out)
    # the massless link is said to share the body, not to have a zero inertial written
    assert not any(n.startswith("link 'cross': M") for n in written.notes), written.notes
    assert any("link 'cross' (no mass) shares the body of link 'hand'" in n for n in written.notes)
    m = mujoco.MjModel.from_xml_path(str(out))
    assert m.nbody == 4 and m.body("hand").jntnum == 2  # world, arm, hand (pitch, yaw), tip
    inertial, ia, fv, fc = split(robot, p)
    model = pin.buildModelFromUrdf(str(path))
    set_pinocchio_params(model, robot, inertial)
    q, dq, ddq = states(robot, rng)
    ref = pin_rnea(model, q, dq, ddq) + ia * ddq + fv * dq + fc * np.sign(dq)
    got, _ = mj_inverse(m, robot.joint_names, q, dq, ddq)
    assert_close(got + fc * np.sign(dq), ref, TOL, "massless link in one body vs Pinocchio")
    again = mindyn.load(out)
    assert again.joint_names == robot.joint_names
    got = again.inverse_dynamics(q, dq, ddq, again.parameters(rotor=True, friction=True))
    assert_close(got, ref, TOL, "massless link in one body read back vs Pinocchio")


def test_mjcf_tendon_motors_that_do_not_determine_the_joints_are_refused_by_name(tmp_path):
    """Two motor tendons and two joints with terms of their own, four motors for four joints,
    but the tendon over the two joints with terms is their sum: the rows do not determine the
    other tendon's joints. The refusal said 'the tendons as motors: mjcf: ... rank deficient'
    without naming a tendon; it names them and the joints with terms, in one line."""
    chain = "".join(
        f'<body name="b{k}" pos="0.2 0 0"><joint name="h{k}" axis="0 {k % 2} {1 - k % 2}"'
        + (' damping="0.3"' if k < 2 else "")
        + '/><inertial pos="0.1 0 0" mass="1" diaginertia="0.01 0.01 0.01"/>'
        for k in range(4)
    )
    path = tmp_path / "motors.xml"
    path.write_text(
        f"<mujoco><worldbody>{chain}{'</body>' * 4}</worldbody><tendon>"
        '<fixed name="m0" armature="0.1"><joint joint="h2" coef="2"/><joint joint="h3" coef="1"/>'
        '</fixed><fixed name="over_t" damping="0.1"><joint joint="h0" coef="1"/>'
        '<joint joint="h1" coef="1"/></fixed></tendon></mujoco>'
    )
    mujoco.MjModel.from_xml_path(str(path))  # MuJoCo takes it
    with pytest.raises(mindyn.ModelError) as e:
        mindyn.load(path)
    said = str(e.value)
    assert "\n" not in said and str(path) in said
    assert "tendons 'm0', 'over_t' carry motor terms" in said and "(on 'h0', 'h1')" in said
    assert "rank deficient" in said, said


def _named_chain(names) -> str:
    """A chain of bodies from ``names`` [(body name or None, joint names)], each with mass."""
    text = ""
    for body, joints in names:
        text += f'<body{"" if body is None else f" name={chr(34)}{body}{chr(34)}"} pos="0.2 0 0">'
        for k, joint in enumerate(joints):
            name = "" if joint is None else f' name="{joint}"'
            text += f'<joint{name} axis="{k % 2} 0 {1 - k % 2}" pos="0.0{k} 0 0"/>'
        text += '<inertial pos="0.1 0.02 0" mass="1" diaginertia="0.01 0.02 0.03"/>'
    return f"<mujoco><worldbody>{text}{'</body>' * len(names)}</worldbody></mujoco>"


def test_mjcf_names_that_clash_in_the_model_are_refused_by_name_or_kept_apart(tmp_path):
    """mindyn names the link of each joint but the last of a body BODY__JOINT, an unnamed body
    or joint by its number, and the fixed joint of a jointless body BODY__fixed. A body named
    as such a link was refused as 'not a valid URDF: link ... is not unique' (of an MJCF); it
    is refused naming both, as an unnamed joint whose number another's name is. A joint named
    BODY__fixed is kept apart from the merged body's joint: the file loads, with MuJoCo's
    dynamics."""
    path = tmp_path / "names.xml"
    for chain, said in (
        ([("b0", ["j1", "j2"]), ("b0__j1", ["j3"])],
         "the link of joint 'j1' of body 'b0' and body 'b0__j1' are both 'b0__j1'"),
        ([("b0", [None]), ("b1", ["joint0"])],
         "joint 'joint0' and unnamed joint 0 are both 'joint0'"),
        ([("b0", ["j0"]), (None, ["j1"]), ("body2", ["j2"])],
         "unnamed body 2 and body 'body2' are both 'body2'"),
    ):  # fmt: skip
        path.write_text(_named_chain(chain))
        mujoco.MjModel.from_xml_path(str(path))  # MuJoCo takes it
        with pytest.raises(mindyn.ModelError) as e:
            mindyn.load(path)
        assert said in str(e.value) and "\n" not in str(e.value), str(e.value)
    path.write_text(_named_chain([("b0", ["j0"]), ("b1", []), ("b2", ["b1__fixed"])]))
    robot = mindyn.load(path)
    assert robot.joint_names == ["j0", "b1__fixed"]
    m = mujoco.MjModel.from_xml_path(str(path))
    q, dq, ddq = states(robot, np.random.default_rng(2))
    ref, _ = mj_inverse(m, robot.joint_names, q, dq, ddq)
    assert_close(robot.inverse_dynamics(q, dq, ddq), ref, TOL, "joint named BODY__fixed")


TWO_JOINT_BODY = """<mujoco model="two">
  <worldbody>
    <body name="a" pos="0 0 0.3" euler="10 0 20">
      <joint name="h" axis="0 0 1"/>
      <inertial pos="0.1 0 0" mass="1.5" fullinertia="0.02 0.03 0.025 0.001 0 0.002"/>
      <body name="b" pos="0.4 0 0" xyaxes="0 1 0 -1 0 0">
        <joint name="first" axis="0 1 0" damping="0.2"/>
        <joint name="second" type="{kind}" pos="0.03 0.01 0" {axis}/>
        <inertial pos="0.1 0.02 0" mass="1" diaginertia="0.01 0.02 0.03" euler="5 10 15"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.mark.parametrize("kind", ["hinge", "slide", "ball"])
def test_a_body_with_two_joints_written_as_a_new_mjcf_has_mujocos_dynamics(kind, tmp_path):
    """A body with two joints is read with a massless link before its second joint; written as
    a new MJCF (from a description that is not the file) that link was a body without mass,
    which MuJoCo refuses. Its joints share a body again: MuJoCo's inverse dynamics of the new
    file is that of the original at the same qpos, qvel, qacc (joints by name)."""
    path = tmp_path / "two.xml"
    axis = "" if kind == "ball" else 'axis="1 0 0"'
    path.write_text(TWO_JOINT_BODY.replace("{kind}", kind).replace("{axis}", axis))
    if kind == "ball":  # the hinge's damping, outside the dynamics of a ball joint's robot
        with pytest.warns(UserWarning, match="are not in the dynamics"):
            robot = mindyn.load(path)
    else:
        robot = mindyn.load(path)
    assert robot.link_names[2:] == ["b__first", "b"]
    p = robot.parameters(rotor=True, friction=True)
    out = write_mjcf(robot, p, tmp_path / "new.xml", new=True).path
    old, new = (mujoco.MjModel.from_xml_path(str(f)) for f in (path, out))
    assert new.nbody == old.nbody and new.body("b").jntnum == 2
    rng = np.random.default_rng(1)
    for _ in range(3):
        state = rng.normal(size=old.nq), rng.normal(size=old.nv), rng.normal(size=old.nv)
        got = []
        for m in (old, new):
            m.opt.disableflags = int(OFF)
            d = mujoco.MjData(m)
            for name in ("h", "first", "second"):
                j = m.joint(name).id
                adr, dof = int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j])
                width = 4 if kind == "ball" and name == "second" else 1
                d.qpos[adr : adr + width] = state[0][adr : adr + width]
                d.qvel[dof : dof + width - (width > 1)] = state[1][dof : dof + width - (width > 1)]
                d.qacc[dof : dof + width - (width > 1)] = state[2][dof : dof + width - (width > 1)]
            mujoco.mj_normalizeQuat(m, d.qpos)
            mujoco.mj_inverse(m, d)
            got.append(d.qfrc_inverse.copy())
        assert_close(got[1], got[0], TOL, "two joints in a body, new MJCF vs the original")


def test_mujoco_warnings_on_a_file_read_are_python_warnings_and_write_no_log(tmp_path, monkeypatch):
    """MuJoCo's default warning handler printed the warning and appended it to MUJOCO_LOG.TXT in
    the current folder, a file the reader left beside the user's. The warning is now a Python
    warning naming the file, with MuJoCo's own text; the handler set before is restored."""
    (tmp_path / "arm.xml").write_text(
        """<mujoco model="arm">
  <statistic meaninertia="1"/>
  <worldbody>
    <body name="link1">
      <joint name="j1" type="hinge" axis="0 0 1"/>
      <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.05"/>
      <body name="link2" pos="0.5 0 0">
        <joint name="j2" type="hinge" axis="0 0 1"/>
        <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.04"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""
    )
    monkeypatch.chdir(tmp_path)
    own: list[str] = []

    def handler(text):  # the test's own handler: what MuJoCo says of the file
        own.append(text)

    before = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(handler)
    try:
        mujoco.MjModel.from_xml_path("arm.xml")
        said = list(own)
        own.clear()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            robot = mindyn.load("arm.xml")
        after = mujoco.get_mju_user_warning()
    finally:
        mujoco.set_mju_user_warning(before)
    assert own == [] and after is handler  # the reader's own, its handler then restored
    ours = [str(w.message) for w in caught if "MuJoCo" in str(w.message)]
    assert robot.n == 2 and list(robot.joint_names) == ["j1", "j2"]
    # MuJoCo deprecates 'meaninertia' from a 3.x release on (3.4 does not warn, 3.17 and 4.0 do)
    assert ours == [f"arm.xml: MuJoCo warns: {' '.join(w.split())}" for w in said]
    major, minor = (int(x) for x in mujoco.__version__.split(".")[:2])
    if (major, minor) >= (3, 17):
        assert len(said) == 1 and "'meaninertia' is deprecated" in said[0], said
    # with MuJoCo's default handler in place: no log file, the default restored
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mindyn.load("arm.xml")
    assert [str(w.message) for w in caught if "MuJoCo" in str(w.message)] == ours
    assert mujoco.get_mju_user_warning() is before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["arm.xml"]  # no MUJOCO_LOG.TXT


def test_a_source_that_does_not_exist_is_refused_and_new_writes_a_new_mjcf(tmp_path):
    """A ``source`` that does not exist gave a new MJCF without a word (the URDF and YAML
    writers refuse it); it is now refused, and ``new=True`` asks for a new MJCF of a robot
    loaded from one: a file of MuJoCo's own form whose inverse dynamics is the original's."""
    path = tmp_path / "arm7.xml"
    path.write_text(ARM7)
    robot = mindyn.load(path)
    p = robot.parameters(rotor=True, friction=True)
    with pytest.raises(mindyn.RobotFileNotFoundError, match="source: description file .*typo"):
        write_mjcf(robot, p, tmp_path / "out.xml", source=tmp_path / "typo.xml")
    with pytest.raises(mindyn.ArgumentError, match="new is a str"):
        write_mjcf(robot, p, tmp_path / "out.xml", new="yes")
    rewritten = write_mjcf(robot, p, tmp_path / "same.xml").path.read_text()
    written = write_mjcf(robot, p, tmp_path / "new.xml", new=True).path.read_text()
    assert 'class="wrist"' in rewritten  # the file rewritten keeps its default classes
    assert 'class="wrist"' not in written and "<inertial pos=" in written  # one per body
    old, new = (mujoco.MjModel.from_xml_path(str(f)) for f in (path, tmp_path / "new.xml"))
    rng = np.random.default_rng(2)
    for _ in range(3):
        qpos = rng.normal(size=old.nq)
        qvel, qacc = rng.normal(size=old.nv), rng.normal(size=old.nv)
        tau = []
        for m in (old, new):
            m.opt.disableflags = int(OFF)
            d = mujoco.MjData(m)
            d.qpos[:], d.qvel[:], d.qacc[:] = qpos, qvel, qacc
            mujoco.mj_inverse(m, d)
            tau.append(d.qfrc_inverse.copy())
        assert_close(tau[1], tau[0], TOL, "new=True, new MJCF vs the original")
