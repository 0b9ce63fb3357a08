"""PR2's older URDF transmissions (pr2_mechanism_model): <transmission type="..."> with a
SimpleTransmission's direct <mechanicalReduction> and the WristTransmission's <rightActuator>,
<leftActuator>, <flexJoint>, <rollJoint>. The matrix T of q_m = T q is checked against the map
written out here from pr2_mechanism_model's equations (WristTransmission's joint -> actuator
map, and its actuator -> joint map with the values its own tests publish), the export round
trip, the wrist's motor-side rotor inertia against Pinocchio plus T^T Ia T ddq written out and
against ros_control's DifferentialTransmission of the same T, the types that are no linear map
(belt compensator, gripper) left out with the note, and malformed PR2 transmissions refused."""

from __future__ import annotations

import warnings

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from mindyn.export import write_urdf
from test_transmissions import arm_urdf, pair, simple

PR2 = "pr2_mechanism_model/"


def pr2_simple(name, joint, motor, reduction, form="attribute") -> str:
    """PR2's SimpleTransmission: the type in the attribute (``form`` 'attribute', or 'bare':
    without the package, as older PR2 files write it) or in a <type> element ('element'), the
    reduction a child of <transmission>."""
    kind = "SimpleTransmission"
    head, body = _type(kind, form)
    return (
        f"<transmission name='{name}'{head}>{body}<actuator name='{motor}'/>"
        f"<joint name='{joint}'/><mechanicalReduction>{reduction}</mechanicalReduction>"
        "</transmission>"
    )


def pr2_wrist(name, flex, roll, right, left, a, j, form="attribute") -> str:
    """PR2's WristTransmission: a = (right, left) actuator reductions, j = (flex, roll) joint
    reductions, each the mechanicalReduction attribute of its element."""
    head, body = _type("WristTransmission", form)
    return (
        f"<transmission name='{name}'{head}>{body}"
        f"<rightActuator name='{right}' mechanicalReduction='{a[0]}'/>"
        f"<leftActuator name='{left}' mechanicalReduction='{a[1]}'/>"
        f"<flexJoint name='{flex}' mechanicalReduction='{j[0]}'/>"
        f"<rollJoint name='{roll}' mechanicalReduction='{j[1]}'/></transmission>"
    )


def _type(kind, form):
    if form == "element":
        return "", f"<type>{PR2}{kind}</type>"
    return f" type='{'' if form == 'bare' else PR2}{kind}'", ""


def load_text(tmp_path, text, name="arm.urdf"):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    with warnings.catch_warnings():
        warnings.simplefilter("error", mindyn.DriveTrainWarning)  # everything is read
        return mindyn.load(p)


# ---- T by hand, from pr2_mechanism_model's equations ----------------------------------------


def wrist_T(a, j):
    """WristTransmission's joint -> actuator positions (propagatePositionBackwards), x the joint
    positions less their calibration reference (0 here):
    right = a_r (j_f x_flex - j_r x_roll), left = a_l (-j_f x_flex - j_r x_roll)."""
    return np.array([[a[0] * j[0], -a[0] * j[1]], [-a[1] * j[0], -a[1] * j[1]]])


def wrist_joint_positions(motors, a, j):
    """WristTransmission's actuator -> joint positions (propagatePosition):
    flex = (right/a_r - left/a_l) / (2 j_f), roll = (-right/a_r - left/a_l) / (2 j_r)."""
    r, left = motors[0] / a[0], motors[1] / a[1]
    return np.array([(r - left) / (2 * j[0]), (-r - left) / (2 * j[1])])


def wrist_joint_efforts(efforts, a, j):
    """WristTransmission's actuator -> joint efforts (propagateEffortBackwards):
    flex = j_f (a_r e_right - a_l e_left), roll = j_r (-a_r e_right - a_l e_left)."""
    er, el = efforts
    return np.array([j[0] * (a[0] * er - a[1] * el), j[1] * (-a[0] * er - a[1] * el)])


A, J = (60.17, 45.5), (-1.0, 1.5)  # PR2's flex joint reduction is -1; here the rest differ


@pytest.mark.parametrize("form", ["attribute", "bare", "element"])
def test_pr2_simple_and_wrist_give_the_map_written_from_pr2_mechanism_model(tmp_path, form):
    parts = (
        simple("t1", "j1", "m1", 42.0)  # ros_control's ROS 1 form in the same file
        + pr2_simple("t2", "j2", "m2", -79.2380952381, form)
        + pr2_simple("t3", "j3", "m3", 63.16, form)
        + pr2_wrist("wrist", "j4", "j5", "r_motor", "l_motor", A, J, form)
    )
    robot = load_text(tmp_path, arm_urdf(5, parts))
    tr = robot.transmission
    expected = np.zeros((5, 5))
    expected[0, 0], expected[1, 1], expected[2, 2] = 42.0, -79.2380952381, 63.16
    expected[3:, 3:] = wrist_T(A, J)
    np.testing.assert_array_equal(tr.T, expected)
    np.testing.assert_array_equal(tr.offset, np.zeros(5))
    assert tr.motors == ("m1", "m2", "m3", "r_motor", "l_motor")
    assert tr.types[1:3] == (PR2 + "SimpleTransmission",) * 2
    assert tr.types[3:] == (PR2 + "WristTransmission",) * 2
    assert tr.format == "ros1" and robot.drive_side == "motor"
    # the actuator -> joint map inverts T on the wrist, and its effort map is T^T (virtual work)
    rng = np.random.default_rng(0)
    q = rng.uniform(-1, 1, 5)
    np.testing.assert_allclose(wrist_joint_positions(tr.T[3:] @ q, A, J), q[3:], atol=1e-12)
    tau_m = rng.uniform(-1, 1, 5)
    np.testing.assert_allclose((tr.T.T @ tau_m)[3:], wrist_joint_efforts(tau_m[3:], A, J))
    wrist = tr.groups[-1]
    assert wrist["joints"] == ["j4", "j5"] and wrist["actuators"] == ["r_motor", "l_motor"]
    assert wrist["actuator_reduction"] == list(A) and wrist["joint_reduction"] == list(J)


@pytest.mark.parametrize(
    ("motors", "joints"),
    [((100.0, 0.0), (5.0, -5.0)), ((0.0, 100.0), (-0.5, -0.5))],
)
def test_wrist_positions_match_the_values_pr2_mechanism_model_publishes(tmp_path, motors, joints):
    """pr2_mechanism_model's wrist tests (actuator reductions 10 and 100, joint reductions 1):
    the joint positions of given actuator positions; T q must give those actuator positions."""
    parts = pr2_wrist("w", "j1", "j2", "r", "l", (10.0, 100.0), (1.0, 1.0))
    tr = load_text(tmp_path, arm_urdf(2, parts)).transmission
    np.testing.assert_allclose(tr.T @ np.array(joints), motors, rtol=0, atol=1e-12)


def test_pr2_form_beside_ros2_control_is_read_with_it(tmp_path):
    """A file ported to ROS 2 that keeps PR2's transmissions: both are read (a file mixing
    ros_control's ROS 1 and ROS 2 forms stays refused)."""
    ros2 = simple("t1", "j1", "m1", 7.5, ros2=True)
    text = arm_urdf(3, ros2, ros2=True).replace(
        "</robot>", pr2_wrist("w", "j2", "j3", "r", "l", A, J) + "</robot>"
    )
    tr = load_text(tmp_path, text).transmission
    expected = np.zeros((3, 3))
    expected[0, 0] = 7.5
    expected[1:, 1:] = wrist_T(A, J)
    np.testing.assert_array_equal(tr.T, expected)
    assert tr.format == "ros2" and tr.motors == ("m1", "r", "l")
    mixed = text.replace("</robot>", simple("t9", "j9", "m9", 3.0) + "</robot>")
    with pytest.raises(mindyn.ModelError, match="both the ROS 1 form"):
        load_text(tmp_path, mixed, "mixed.urdf")


def test_pr2_wrist_is_the_ros_differential_with_negated_reductions(tmp_path):
    """The wrist is ros_control's DifferentialTransmission with actuator1 = right (a_r),
    actuator2 = left (-a_l), joint1 = flex (j_f), joint2 = roll (-j_r): the same T."""
    wrist = load_text(tmp_path, arm_urdf(2, pr2_wrist("w", "j1", "j2", "r", "l", A, J)), "a.urdf")
    diff = pair(
        "DifferentialTransmission", "w", ("j1", "j2"), ("r", "l"), (A[0], -A[1]), (J[0], -J[1])
    )
    ros = load_text(tmp_path, arm_urdf(2, diff), "b.urdf")
    np.testing.assert_array_equal(wrist.transmission.T, ros.transmission.T)
    np.testing.assert_array_equal(wrist.transmission.T, wrist_T(A, J))


def wrist_arm(tmp_path, kind: str):
    """A 6R arm (random inertia, tests/coupled_arms.py) whose joints 1-4 have PR2's simple
    transmissions and whose wrist joints 5-6 PR2's WristTransmission ('pr2') or the equivalent
    ros_control DifferentialTransmission ('ros'); returns the robot and T written by hand."""
    from coupled_arms import coupled_wrist_urdf

    path, _ = coupled_wrist_urdf(tmp_path / f"{kind}.urdf")
    text = path.read_text(encoding="utf-8")
    body = text[: text.index("<transmission")]
    red = [100.0, -80.0, 60.0, 50.0]
    a, j = (40.0, 32.0), (-1.0, 1.25)
    if kind == "pr2":
        tr = [pr2_simple(f"t{k}", f"j{k}", f"m{k}", red[k - 1]) for k in range(1, 5)]
        tr.append(pr2_wrist("wrist", "j5", "j6", "m5", "m6", a, j))
    else:
        tr = [simple(f"t{k}", f"j{k}", f"m{k}", red[k - 1]) for k in range(1, 5)]
        tr.append(
            pair(
                "DifferentialTransmission",
                "wrist",
                ("j5", "j6"),
                ("m5", "m6"),
                (a[0], -a[1]),
                (j[0], -j[1]),
            )  # fmt: skip
        )
    path.write_text(body + "".join(tr) + "</robot>", encoding="utf-8")
    T = np.zeros((6, 6))
    for k in range(4):
        T[k, k] = red[k]
    T[4:, 4:] = wrist_T(a, j)
    return load_text(tmp_path, path.read_text(encoding="utf-8"), path.name), T


def test_pr2_wrist_rotor_inertia_acts_through_T_and_regroups_as_the_ros_differential(tmp_path):
    """With motor-side rotor inertia and friction, the PR2 arm's torques are Pinocchio's rigid
    bodies plus T^T (Ia T ddq + Fv T dq + Fc sign(T dq)) with T from the PR2 equations, and its
    base parameters (count, names, regressor, values) are those of the arm whose wrist is the
    equivalent ros_control differential: the same T, the same base parameters."""
    from coupled_arms import motor_terms

    pr2, T = wrist_arm(tmp_path, "pr2")
    ros, _ = wrist_arm(tmp_path, "ros")
    model = pin.buildModelFromUrdf(pr2.source)
    data = model.createData()
    rng = np.random.default_rng(3)
    pi = pr2.parameters(rotor=True, friction=True).reshape(6, 13).copy()
    pi[:, 10:13] = rng.uniform(0.1, 1.0, (6, 3)) * [1e-4, 1e-3, 0.05]
    pi = pi.reshape(-1)
    bp = mindyn.base_parameters(pr2, rotor=True, friction=True)
    br = mindyn.base_parameters(ros, rotor=True, friction=True)
    assert bp.n == br.n and list(bp.names) == list(br.names)
    for _ in range(3):
        q, dq, ddq = rng.uniform(-2, 2, (3, 6))
        ref = pin.rnea(model, data, q, dq, ddq) + motor_terms(
            T, pi[10::13], pi[11::13], pi[12::13], dq, ddq
        )
        tau = pr2.inverse_dynamics(q, dq, ddq, pi)
        assert np.max(np.abs(tau - ref)) <= 1e-9 * np.max(np.abs(ref))
        np.testing.assert_allclose(
            ros.inverse_dynamics(q, dq, ddq, pi), tau, rtol=1e-12, atol=1e-12
        )
        np.testing.assert_allclose(bp.regressor(q, dq, ddq), br.regressor(q, dq, ddq), atol=1e-12)
    np.testing.assert_allclose(bp.values(pi), br.values(pi), rtol=1e-12, atol=1e-15)


# ---- export round trip ---------------------------------------------------------------------


@pytest.mark.parametrize("form", ["attribute", "bare", "element"])
def test_export_writes_the_pr2_transmissions_back_and_they_load_again(tmp_path, form):
    parts = pr2_simple("t1", "j1", "m1", 63.16, form) + pr2_wrist(
        "wrist", "j2", "j3", "r", "l", A, J, form
    )
    robot = load_text(tmp_path, arm_urdf(3, parts))
    out = tmp_path / "out.urdf"
    params = robot.parameters(rotor=True, friction=True) * 1.1
    write_urdf(robot, params, out)
    text = out.read_text(encoding="utf-8")
    assert "<rightActuator" in text and "<flexJoint" in text
    again = load_text(tmp_path, text, "again.urdf")
    expected = np.zeros((3, 3))
    expected[0, 0] = 63.16
    expected[1:, 1:] = wrist_T(A, J)
    np.testing.assert_array_equal(again.transmission.T, expected)
    np.testing.assert_array_equal(again.transmission.offset, robot.transmission.offset)
    assert again.transmission.motors == robot.transmission.motors == ("m1", "r", "l")
    assert again.transmission.types == robot.transmission.types
    assert again.transmission.groups == robot.transmission.groups


# ---- PR2's types that are no linear map, and malformed PR2 transmissions ---------------------


def test_pr2_belt_compensator_gripper_and_simulated_screw_stay_unread_and_noted(tmp_path):
    """The belt compensator (a compliant belt with its own dynamics), the gripper (a nonlinear
    linkage through <gap_joint>) and a SimpleTransmission with a <simulated_actuated_joint>
    (its effort goes to that joint in PR2's simulator) are not read: their joints are driven
    directly, with the note naming them; the PR2 SimpleTransmission beside them is read."""
    parts = (
        f"<transmission name='belt' type='{PR2}PR2BeltCompensatorTransmission'>"
        "<actuator name='mb'/><joint name='j1'/><mechanicalReduction>-60</mechanicalReduction>"
        "<compensator k_belt='4000' kd_motor='10' lambda_combined='0' lambda_joint='60' "
        "lambda_motor='60' mass_motor='0.05'/></transmission>"
        f"<transmission name='grip' type='{PR2}PR2GripperTransmission'><actuator name='mg'/>"
        "<gap_joint name='j2' mechanical_reduction='1.0' screw_reduction='0.004'/>"
        "<passive_joint name='finger'/></transmission>"
        f"<transmission name='screw' type='{PR2}SimpleTransmission'><actuator name='ms'/>"
        "<joint name='j3'/><mechanicalReduction>10</mechanicalReduction>"
        "<simulated_actuated_joint name='screw_joint' simulated_reduction='3000'/>"
        "</transmission>" + pr2_simple("t4", "j4", "m4", 50.0)
    )
    path = tmp_path / "arm.urdf"
    path.write_text(arm_urdf(4, parts), encoding="utf-8")
    with pytest.warns(mindyn.DriveTrainWarning) as caught:
        robot = mindyn.load(path)
    (note,) = [str(w.message) for w in caught if w.category is mindyn.DriveTrainWarning]
    for name, joint in (("belt", "j1"), ("grip", "j2"), ("screw", "j3")):
        assert f"'{name}' of type '{PR2}" in note and f"'{joint}'" in note, note
    unread = {t["name"]: t for t in robot.unread_transmissions}
    assert unread["grip"]["joints"] == ["j2", "finger"]
    assert unread["screw"]["joints"] == ["j3", "screw_joint"]
    assert [unread[k]["modelled_directly"] for k in ("belt", "grip", "screw")] == [
        ["j1"],
        ["j2"],
        ["j3"],
    ]
    tr = robot.transmission
    assert tr.motors == ("m4", "j1", "j2", "j3")
    np.testing.assert_array_equal(tr.T, [[0, 0, 0, 50.0], [1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]])


WRIST = (
    f"<transmission name='w' type='{PR2}WristTransmission'>"
    "<rightActuator name='r' mechanicalReduction='60'/>"
    "<leftActuator name='l' mechanicalReduction='60'/>"
    "<flexJoint name='j1' mechanicalReduction='-1'/>"
    "<rollJoint name='j2' mechanicalReduction='1'/></transmission>"
)
SIMPLE = (
    f"<transmission name='s' type='{PR2}SimpleTransmission'><actuator name='m'/>"
    "<joint name='j1'/><mechanicalReduction>50</mechanicalReduction></transmission>"
)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (SIMPLE.replace("<mechanicalReduction>50</mechanicalReduction>", ""),
         "needs a <mechanicalReduction> in <transmission>"),
        (SIMPLE.replace("<actuator name='m'/>", "<actuator name='m'><mechanicalReduction>50"
                        "</mechanicalReduction></actuator>"),
         "<actuator> holds a <mechanicalReduction>; PR2's SimpleTransmission reads"),
        (SIMPLE.replace(">50<", ">5O<"),
         "<mechanicalReduction>5O</mechanicalReduction>: not a number"),
        (SIMPLE.replace(">50<", ">0<"), "a reduction cannot be zero"),
        (SIMPLE.replace("<joint name='j1'/>", ""), "needs a <joint name=...>"),
        (SIMPLE.replace("<joint name='j1'/>", "<joint name='j1'/><joint name='j2'/>"),
         "holds a second <joint>"),
        (SIMPLE.replace("<joint name='j1'/>", "<joint/>"), "<joint> has no name attribute"),
        (SIMPLE.replace("SimpleTransmission'", "SimpleTransmision'"),
         f"is it {PR2}SimpleTransmission?"),
        (WRIST.replace("<leftActuator name='l' mechanicalReduction='60'/>", ""),
         "needs a <leftActuator name=... mechanicalReduction=...>"),
        (WRIST.replace("name='j1' mechanicalReduction='-1'", "name='j1'"),
         "<flexJoint name=\"j1\"> has no mechanicalReduction attribute"),
        (WRIST.replace("mechanicalReduction='-1'", "mechanicalReduction='nan'"),
         "not a finite number"),
        (WRIST.replace("name='l'", "name='r'"), "both name 'r'"),
        (WRIST.replace("name='j2'", "name='j1'"), "both name 'j1'"),
        (WRIST.replace("<rollJoint", "<rolJoint"), "is it <rollJoint>?"),
        (WRIST.replace("WristTransmission'", "WristTransmision'"),
         f"is it {PR2}WristTransmission?"),
    ],
)  # fmt: skip
def test_malformed_pr2_transmissions_are_refused_in_one_line(tmp_path, text, message):
    path = tmp_path / "arm.urdf"
    path.write_text(arm_urdf(2, text), encoding="utf-8")
    with pytest.raises(mindyn.ModelError) as e:
        mindyn.load(path)
    text = str(e.value)
    assert message in text and f"{path}:" in text and "transmission '" in text, text
    assert "\n" not in text


def test_example_robot_data_pr2_right_arm_reads_the_file_s_reductions(robots_dir):
    """example-robot-data's pr2.urdf (bare PR2 type names in the attribute): the right arm's
    chain (torso and 7 joints) has T from the file's reductions, parsed here on their own, the
    wrist by pr2_mechanism_model's map, and no transmission is left unread on it."""
    import xml.etree.ElementTree as ET

    path = robots_dir / "pr2_description/urdf/pr2.urdf"
    with warnings.catch_warnings():
        warnings.simplefilter("error", mindyn.DriveTrainWarning)
        robot = mindyn.load(path, tip="r_wrist_roll_link")
    names = robot.joint_names
    expected = np.zeros((robot.n, robot.n))
    motors = []
    for t in ET.parse(path).getroot().iter("transmission"):
        if t.get("type") == "SimpleTransmission" and t.find("joint").get("name") in names:
            motors.append(t.find("actuator").get("name"))
            k = names.index(t.find("joint").get("name"))
            expected[len(motors) - 1, k] = float(t.find("mechanicalReduction").text)
        elif t.get("type") == "WristTransmission" and t.find("flexJoint").get("name") in names:
            red = {e.tag: float(e.get("mechanicalReduction")) for e in t}
            a = red["rightActuator"], red["leftActuator"]
            j = red["flexJoint"], red["rollJoint"]
            cols = [names.index(t.find(e).get("name")) for e in ("flexJoint", "rollJoint")]
            rows = [len(motors), len(motors) + 1]
            motors += [t.find(e).get("name") for e in ("rightActuator", "leftActuator")]
            expected[np.ix_(rows, cols)] = wrist_T(a, j)
    assert len(motors) == robot.n == 8
    assert robot.transmission.motors == tuple(motors)
    np.testing.assert_array_equal(robot.transmission.T, expected)
    assert robot.transmission.T[6, 6] == -60.1714285714  # the file's wrist: a_r 60.17, j_f -1
