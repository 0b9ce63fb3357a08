"""The library as a Python user meets it: documents and objects that do not change under their
users, the tip an identification records, and inputs refused in one line instead of a silent
wrong number (controller estimates, inertia tensors, rotations)."""

import json

import mindyn
import numpy as np
import pytest
from mindyn import control
from mindyn import identification as ident
from mindyn.control.controllers import ControllerSettingError

#: a three-joint chain with a fixed flange after its last moving link, written for these tests
URDF = """<?xml version="1.0"?>
<robot name="chain3">
  <link name="base"/>
  <link name="a"><inertial><origin xyz="0.1 0 0.02"/><mass value="2.0"/>
    <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.025"/></inertial></link>
  <link name="b"><inertial><origin xyz="0.15 0.01 0"/><mass value="1.5"/>
    <inertia ixx="0.01" ixy="0.001" ixz="0" iyy="0.02" iyz="0" izz="0.015"/></inertial></link>
  <link name="c"><inertial><origin xyz="0.05 0 0.01"/><mass value="0.7"/>
    <inertia ixx="0.004" ixy="0" ixz="0" iyy="0.005" iyz="0" izz="0.003"/></inertial></link>
  <link name="flange"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/>
    <origin xyz="0 0 0.2"/><axis xyz="0 0 1"/>
    <limit lower="-2.5" upper="2.5" effort="60" velocity="2"/></joint>
  <joint name="j2" type="revolute"><parent link="a"/><child link="b"/>
    <origin xyz="0.3 0 0" rpy="1.5707963267948966 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-2.5" upper="2.5" effort="40" velocity="2"/></joint>
  <joint name="j3" type="revolute"><parent link="b"/><child link="c"/>
    <origin xyz="0.3 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-2.5" upper="2.5" effort="20" velocity="2"/></joint>
  <joint name="fix" type="fixed"><parent link="c"/><child link="flange"/>
    <origin xyz="0.1 0 0"/></joint>
</robot>
"""


@pytest.fixture(scope="module")
def chain(tmp_path_factory):
    path = tmp_path_factory.mktemp("chain") / "chain3.urdf"
    path.write_text(URDF)
    return path


@pytest.fixture(scope="module")
def fitted(chain):
    """A simulated log of the chain (inverse dynamics with friction, torque noise) and its
    identification."""
    robot = mindyn.load(chain, tip="flange")
    ref = control.SumOfSines(robot, period=8.0, seed=2)
    noise = control.SensorNoise(torque=0.01)
    sim = control.simulate_inverse(robot, ref, rate=250.0, friction=True, noise=noise, seed=1)
    data = ident.JointData(t=sim.t, q=sim.q, dq=sim.dq, ddq=sim.ddq_true, tau=sim.tau)
    return robot, data, sim


def test_report_document_is_a_new_one_each_time(fitted):
    robot, data, _ = fitted
    report = ident.run(robot, [data], friction=True, tip="flange")
    first = report.to_dict()
    expected = json.dumps(first, sort_keys=True, default=str)
    first["names"].append("XX9")  # edits of nested lists and dicts of the document
    first["settings"].clear()
    first["model_check"].clear()
    first["fit"]["rms"][0] = -1.0
    again = report.to_dict()
    assert json.dumps(again, sort_keys=True, default=str) == expected
    assert list(report.result.names) == again["names"]


def test_run_loads_a_description_with_its_tip_and_records_it(chain, fitted):
    robot, data, sim = fitted
    report = ident.run(str(chain), [data], friction=True, tip="flange")
    assert report.robot.joint_names == ["j1", "j2", "j3"]
    assert report.to_dict()["tip"] == "flange"
    # the estimate predicts the simulated torques (noise of 0.01 N m)
    rms = np.sqrt(np.mean((report.result.predict(data) - sim.tau_true) ** 2))
    assert rms < 0.01


def test_run_refuses_a_tip_that_is_not_the_robots_chain(chain, fitted):
    robot, data, _ = fitted
    with pytest.raises(mindyn.ArgumentError, match=r"^tip is 'b', whose chain .* j1, j2; robot"):
        ident.run(robot, [data], friction=True, tip="b")
    with pytest.raises(mindyn.ArgumentError, match=r"^tip does not apply .* 'nope'"):
        ident.run(robot, [data], friction=True, tip="nope")
    with pytest.raises(mindyn.ArgumentError, match=r"^tip does not apply to robot 'puma560'"):
        ident.run(mindyn.load("puma560"), [data], tip="link6")


def test_result_predict_names_a_wrong_argument(fitted):
    robot, data, _ = fitted
    res = ident.identify(robot, data, friction=True)
    with pytest.raises(mindyn.ArgumentError, match=r"^data is a str 'abc'; expected a JointData"):
        res.predict("abc")


def _controller_setup():
    robot = mindyn.load("planar3")
    base = mindyn.base_parameters(robot)
    return robot, base, base.values(robot.params)


def test_computed_torque_is_the_closed_form_and_refuses_nan_estimates():
    robot, base, p = _controller_setup()
    q, dq = np.array([0.1, -0.3, 0.5]), np.array([0.2, 0.1, -0.4])
    qd, dqd, ddqd = np.array([0.2, -0.2, 0.4]), np.zeros(3), np.array([0.5, -0.1, 0.3])
    kp, kd = np.array([100.0, 80.0, 60.0]), np.array([20.0, 15.0, 10.0])
    given = p.copy()
    ctl = control.ComputedTorque(base, given, kp, kd)
    given[:] = 0.0  # the controller keeps its own copy
    v = ddqd - kd * (dq - dqd) - kp * (q - qd)
    expected = robot.inverse_dynamics(q, dq, v)  # W_b(q, dq, v) p_b is the classical torque
    assert np.allclose(ctl(0.0, q, dq, qd, dqd, ddqd), expected, rtol=1e-12, atol=1e-12)
    bad = p.copy()
    bad[1] = np.nan
    with pytest.raises(ControllerSettingError, match=rf"^p_hat has nan at '{base.names[1]}'"):
        control.ComputedTorque(base, bad, kp, kd)
    with pytest.raises(ControllerSettingError, match=r"^p_hat must be \d+ numbers, got 'x'"):
        control.ComputedTorque(base, "x", kp, kd)
    with pytest.raises(mindyn.ArgumentError, match=r"^coulomb_smoothing is nan"):
        control.ComputedTorque(base, p, kp, kd, coulomb_smoothing=float("nan"))
    with pytest.raises(mindyn.ArgumentError, match=r"^base is a str 'planar3'"):
        control.ComputedTorque("planar3", p, kp, kd)


def test_adaptive_pd_refuses_nan_estimates_and_a_non_boolean_adapt():
    robot, base, p = _controller_setup()
    bad = np.full(base.n, np.inf)
    with pytest.raises(ControllerSettingError, match=r"^p0 has inf at "):
        control.AdaptivePD(base, 10.0, 5.0, 0.1, bad)
    ctl = control.AdaptivePD(base, 10.0, 5.0, 0.1, p)
    with pytest.raises(ControllerSettingError, match=r"^p0 has nan at "):
        ctl.use_parameters(np.full(base.n, np.nan))
    assert np.array_equal(ctl.p_hat, p)  # unchanged by the refused call
    with pytest.raises(mindyn.ArgumentError, match=r"^adapt is a str 'no'; expected True or"):
        control.AdaptivePD(base, 10.0, 5.0, 0.1, p, adapt="no")
    # frozen, the controller is PD plus the model: the classical torque at the reference terms
    frozen = control.AdaptivePD(base, 10.0, 5.0, 0.1, p, adapt=False)
    q, dq = np.array([0.1, 0.2, 0.3]), np.array([0.0, 0.1, 0.0])
    qd, dqd, ddqd = np.zeros(3), np.zeros(3), np.zeros(3)
    e, s = q - qd, dq - dqd + 5.0 * (q - qd)
    dqr, ddqr = dqd - 5.0 * e, ddqd - 5.0 * (dq - dqd)
    C = mindyn.coriolis_matrix(robot, q, dq)
    model = robot.mass_matrix(q) @ ddqr + C @ dqr + robot.gravity_torque(q)
    tau = frozen(0.0, q, dq, qd, dqd, ddqd)
    assert np.allclose(tau, model - 10.0 * s, rtol=1e-10, atol=1e-10)


def test_inertial_from_com_is_the_parallel_axis_theorem_and_refuses_asymmetric_tensors():
    m, c = 1.7, np.array([0.1, -0.2, 0.05])
    Ic = np.array([[0.03, 0.002, -0.001], [0.002, 0.04, 0.003], [-0.001, 0.003, 0.05]])
    Io = Ic + m * (c @ c * np.eye(3) - np.outer(c, c))
    expected = [Io[0, 0], Io[0, 1], Io[0, 2], Io[1, 1], Io[1, 2], Io[2, 2], *(m * c), m]
    assert np.allclose(mindyn.inertial_from_com(m, c, Ic), expected, rtol=1e-14, atol=1e-16)
    skew = Ic.copy()
    skew[0, 1] += 0.01  # the two triangles would give two products of inertia
    with pytest.raises(mindyn.ArgumentError, match=r"^inertia is not symmetric: entry \(0, 1\)"):
        mindyn.inertial_from_com(m, c, skew)
    with pytest.raises(mindyn.ArgumentError, match=r"^inertia is not symmetric"):
        mindyn.inertial_from_urdf(m, c, np.eye(3), skew)


def test_inertial_from_urdf_turns_the_tensor_and_refuses_what_is_no_rotation():
    m, c = 0.9, np.array([0.02, 0.0, 0.1])
    Ic = np.diag([0.01, 0.02, 0.03])
    a = 0.7
    R = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    expected = mindyn.inertial_from_com(m, c, R @ Ic @ R.T)
    assert np.allclose(mindyn.inertial_from_urdf(m, c, R, Ic), expected, rtol=1e-13, atol=1e-16)
    with pytest.raises(mindyn.ArgumentError, match=r"^rotation is not a rotation matrix \(R\^T"):
        mindyn.inertial_from_urdf(m, c, 2.0 * np.eye(3), Ic)
    with pytest.raises(mindyn.ArgumentError, match=r"^rotation is not a rotation matrix \(a ref"):
        mindyn.inertial_from_urdf(m, c, np.diag([1.0, 1.0, -1.0]), Ic)
