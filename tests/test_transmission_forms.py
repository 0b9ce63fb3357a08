"""URDF transmissions in forms descriptions in use write and ros_control's loaders do not take
as written (a missing actuator reduction, a reduction on the other element or in a <param>, a
transmission repeated per hardware interface): T checked against ros_control's maps written
out here, the note, the lines of later messages, and the export round trip."""

from __future__ import annotations

import warnings

import mindyn
import numpy as np
import pytest
from mindyn.export import write_urdf

SIMPLE = "transmission_interface/SimpleTransmission"
DIFF = "transmission_interface/DifferentialTransmission"


def arm(transmissions: str, ros2: bool = False) -> str:
    """Two revolute joints j1 (z) and j2 (y), one link each; the transmissions go on their own
    lines after the links and joints (line 3 on)."""
    links, joints = ["<link name='base'/>"], []
    for k, axis in ((1, "0 0 1"), (2, "0 1 0")):
        links.append(
            f"<link name='l{k}'><inertial><origin xyz='0.1 0.02 0.05'/><mass value='{3 - k}'/>"
            "<inertia ixx='0.02' ixy='0' ixz='0' iyy='0.03' iyz='0' izz='0.01'/></inertial></link>"
        )
        joints.append(
            f"<joint name='j{k}' type='revolute'><parent link='{'base' if k == 1 else 'l1'}'/>"
            f"<child link='l{k}'/><origin xyz='0 0 0.3'/><axis xyz='{axis}'/>"
            "<limit lower='-3' upper='3' effort='100' velocity='3'/></joint>"
        )
    if ros2:
        transmissions = (
            "<ros2_control name='arm' type='system'>\n<hardware><plugin>fake/Hw</plugin>"
            f"</hardware>{transmissions}</ros2_control>"
        )
    return "<robot name='arm'>\n" + "".join(links + joints) + "\n" + transmissions + "\n</robot>\n"


def load(tmp_path, text: str, name: str = "arm.urdf"):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = mindyn.load(p)
    notes = [str(w.message) for w in caught if "ros_control does not take" in str(w.message)]
    return robot, notes


def ros1_simple(name, joint, motor, actuator="", joint_body="", hw="EffortJointInterface"):
    return (
        f"<transmission name='{name}'><type>{SIMPLE}</type>"
        f"<joint name='{joint}'><hardwareInterface>hardware_interface/{hw}</hardwareInterface>"
        f"{joint_body}</joint><actuator name='{motor}'>{actuator}</actuator></transmission>\n"
    )


def T_of(robot):
    tr = robot.transmission
    return {m: tr.T[i] for i, m in enumerate(tr.motors)}, dict(zip(tr.motors, tr.offset))


def test_franka_form_missing_reduction_and_repeats_per_interface(tmp_path):
    """Franka's Gazebo form: no <mechanicalReduction>, each transmission written three times
    (Position, Velocity, Effort interfaces): one motor per joint at ratio 1 (x_a = 1 x_j)."""
    text = "".join(
        ros1_simple(f"t{k}", f"j{k}", f"m{k}", hw=hw)
        for hw in ("PositionJointInterface", "VelocityJointInterface", "EffortJointInterface")
        for k in (1, 2)
    )
    robot, notes = load(tmp_path, arm(text))
    assert robot.transmission.motors == ("m1", "m2")
    np.testing.assert_array_equal(robot.transmission.T, np.eye(2))
    assert len(notes) == 1 and "\n" not in notes[0]
    assert "read once: 't1' (line 5), 't2' (line 6), 't1' (line 7)" in notes[0]
    assert "without <mechanicalReduction> has reduction 1 (" in notes[0]
    assert "ratio 1): 't1' (line 3), 't2' (line 4)" in notes[0]
    # the repeats are dropped, not the actuators of the first ones: m1 is one motor
    assert robot.drive_side == "motor"


def test_ros1_reduction_in_joint_or_transmission_is_the_actuator_one(tmp_path):
    """ros_control: x_a = n (x_j - off) with n the actuator's reduction; here n is written in the
    <joint> (t1) or in <transmission> as PR2 writes it (t2); the offset stays the joint's."""
    t1 = ros1_simple(
        "t1",
        "j1",
        "m1",
        joint_body="<offset>0.25</offset><mechanicalReduction>-40</mechanicalReduction>",
    )
    t2 = (
        f"<transmission name='t2'><type>{SIMPLE}</type><joint name='j2'/><actuator name='m2'/>"
        "<mechanicalReduction>12.5</mechanicalReduction></transmission>\n"
    )
    robot, notes = load(tmp_path, arm(t1 + t2))
    T, off = T_of(robot)
    np.testing.assert_allclose(T["m1"], [-40.0, 0.0])
    np.testing.assert_allclose(T["m2"], [0.0, 12.5])
    assert off["m1"] == pytest.approx(-40.0 * -0.25) and off["m2"] == 0.0
    assert (
        "written in its <joint> alone is its reduction" in notes[0] and "'t1' (line 3)" in notes[0]
    )
    assert "written in <transmission> (PR2's place)" in notes[0] and "'t2' (line 4)" in notes[0]


def test_differential_without_actuator_reductions(tmp_path):
    """x_a1 = a1 (j1 x1 + j2 x2), x_a2 = a2 (j1 x1 - j2 x2) with a1 = a2 = 1, j = (2, 3)."""
    text = (
        f"<transmission name='d'><type>{DIFF}</type>"
        "<actuator name='m1'><role>actuator1</role></actuator>"
        "<actuator name='m2'><role>actuator2</role></actuator>"
        "<joint name='j1'><role>joint1</role><mechanicalReduction>2</mechanicalReduction></joint>"
        "<joint name='j2'><role>joint2</role><mechanicalReduction>3</mechanicalReduction></joint>"
        "</transmission>"
    )
    robot, notes = load(tmp_path, arm(text))
    np.testing.assert_allclose(robot.transmission.T, [[2.0, 3.0], [2.0, -3.0]])
    assert "'d' (line 3)" in notes[0]


def test_ros2_reduction_in_actuator_and_params(tmp_path):
    """ros2_control: x_a = n (x_j - off), n and off the joint's; here n sits in the <actuator>
    (t1), or both are <param>s of the joint (t2)."""
    t1 = (
        f"<transmission name='t1'><plugin>{SIMPLE}</plugin><actuator name='m1' role='actuator1'>"
        "<mechanical_reduction>50</mechanical_reduction></actuator>"
        "<joint name='j1' role='joint1'><offset>0.1</offset></joint></transmission>\n"
    )
    t2 = (
        f"<transmission name='t2'><plugin>{SIMPLE}</plugin><actuator name='m2' role='actuator1'/>"
        "<joint name='j2' role='joint1'><param name='mechanical_reduction'>-8</param>"
        "<param name='offset'>-0.5</param></joint></transmission>\n"
    )
    robot, notes = load(tmp_path, arm(t1 + t2, ros2=True))
    T, off = T_of(robot)
    np.testing.assert_allclose(T["m1"], [50.0, 0.0])
    np.testing.assert_allclose(T["m2"], [0.0, -8.0])
    assert off["m1"] == pytest.approx(-5.0) and off["m2"] == pytest.approx(-4.0)
    assert "in its <actuator>" in notes[0] and "'t1' (line 4)" in notes[0]
    assert '<param name="mechanical_reduction">' in notes[0] and "'t2' (line 5)" in notes[0]


def test_forms_taken_as_written_give_no_note_and_refusals_keep_their_lines(tmp_path):
    good = ros1_simple("t1", "j1", "m1", "<mechanicalReduction>7</mechanicalReduction>")
    robot, notes = load(tmp_path, arm(good))
    assert notes == [] and robot.transmission.T[0, 0] == 7.0
    # a rewritten file still names the lines of the file: the bad reduction is on line 4
    bad = ros1_simple("t2", "j2", "m2", "<mechanicalReduction>x</mechanicalReduction>")
    with pytest.raises(mindyn.ModelError, match=r"arm\.urdf:4: transmission 't2'"):
        load(tmp_path, arm(ros1_simple("t1", "j1", "m1") + bad))
    # repeats that differ in more than their interface are refused, as before
    other = ros1_simple("t1", "j1", "m1", "<mechanicalReduction>3</mechanicalReduction>")
    with pytest.raises(mindyn.ModelError, match="declared twice"):
        load(tmp_path, arm(good + other))


def test_export_round_trip_keeps_the_forms(tmp_path):
    text = arm(
        ros1_simple("t1", "j1", "m1") * 2
        + ros1_simple("t2", "j2", "m2", "", "<mechanicalReduction>9</mechanicalReduction>")
    )
    robot, _ = load(tmp_path, text)
    out = tmp_path / "again.urdf"
    write_urdf(robot, dict(zip(robot.param_names, robot.params)), out)
    again, notes = load(tmp_path, out.read_text(), name="again2.urdf")
    assert again.transmission.motors == robot.transmission.motors
    np.testing.assert_array_equal(again.transmission.T, robot.transmission.T)
    np.testing.assert_array_equal(again.transmission.T, np.diag([1.0, 9.0]))
    assert len(notes) == 1


def test_unread_interface_transmissions_leave_driven_joints_alone(tmp_path):
    """Franka's franka_hw/FrankaStateInterface 'transmission' names every joint: those a
    transmission read drives are not said to be driven directly."""
    text = (
        ros1_simple("t1", "j1", "m1", "<mechanicalReduction>5</mechanicalReduction>")
        + "<transmission name='state'><type>franka_hw/FrankaStateInterface</type>"
        "<joint name='j1'/><joint name='j2'/><actuator name='s'/></transmission>\n"
    )
    p = tmp_path / "arm.urdf"
    p.write_text(arm(text), encoding="utf-8")
    with pytest.warns(mindyn.DriveTrainWarning, match="driving joint\\(s\\) 'j2'\\. Assumed"):
        robot = mindyn.load(p)
    assert robot.unread_transmissions[0]["modelled_directly"] == ["j2"]
