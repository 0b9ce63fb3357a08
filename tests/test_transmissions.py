"""Transmissions read from URDF (ros_control's ROS 1 and ROS 2 forms) and YAML: the matrix T of
q_m = T q + c against T written out here from ros_control's documented maps, export round
trips, refusals of malformed transmissions, and motor currents converted through T."""

from __future__ import annotations

from pathlib import Path

import mindyn
import numpy as np
import pytest
import yaml
from mindyn import cli
from mindyn.export import write_urdf, write_yaml
from mindyn.identification.currents import attach_currents
from mindyn.identification.data import read_csv, write_csv

PREFIX = "transmission_interface/"


def arm_urdf(n: int, transmissions: str = "", ros2: bool = False, branch: bool = False) -> str:
    """A chain of n revolute joints j1..jn (alternating z / y axes) with unit-ish inertia; with
    `branch`, a finger joint 'f1' hangs off link n (off the chain when tip = 'l{n}')."""
    links = ["<link name='base'/>"]
    joints = []
    for k in range(1, n + 1):
        links.append(
            f"<link name='l{k}'><inertial><origin xyz='0.1 0.02 0.05'/><mass value='{2.0 / k}'/>"
            "<inertia ixx='0.02' ixy='0' ixz='0' iyy='0.03' iyz='0' izz='0.01'/></inertial></link>"
        )
        axis = "0 0 1" if k % 2 else "0 1 0"
        parent = "base" if k == 1 else f"l{k - 1}"
        joints.append(
            f"<joint name='j{k}' type='revolute'><parent link='{parent}'/>"
            f"<child link='l{k}'/><origin xyz='0 0 0.3'/><axis xyz='{axis}'/>"
            "<limit lower='-3' upper='3' effort='100' velocity='3'/></joint>"
        )
    if branch:
        links.append(
            "<link name='finger'><inertial><mass value='0.1'/>"
            "<inertia ixx='1e-4' ixy='0' ixz='0' iyy='1e-4' iyz='0' izz='1e-4'/></inertial></link>"
        )
        joints.append(
            f"<joint name='f1' type='prismatic'><parent link='l{n}'/><child link='finger'/>"
            "<axis xyz='1 0 0'/><limit lower='0.01' upper='0.04' effort='10' velocity='1'/></joint>"
        )
    if ros2:
        transmissions = (
            "<ros2_control name='arm' type='system'><hardware><plugin>fake/Hw</plugin>"
            f"</hardware>{transmissions}</ros2_control>"
        )
    return "<robot name='arm'>" + "".join(links + joints) + transmissions + "</robot>"


# ---- ros_control's transmissions written in each form --------------------------------------


def simple(name, joint, motor, reduction, offset=None, ros2=False) -> str:
    off = "" if offset is None else f"<offset>{offset}</offset>"
    if ros2:
        return (
            f"<transmission name='{name}'><plugin>{PREFIX}SimpleTransmission</plugin>"
            f"<actuator name='{motor}' role='actuator1'/>"
            f"<joint name='{joint}' role='joint1'>{off}"
            f"<mechanical_reduction>{reduction}</mechanical_reduction></joint></transmission>"
        )
    return (
        f"<transmission name='{name}'><type>{PREFIX}SimpleTransmission</type>"
        f"<joint name='{joint}'><hardwareInterface>x</hardwareInterface>{off}</joint>"
        f"<actuator name='{motor}'><mechanicalReduction>{reduction}</mechanicalReduction>"
        "</actuator></transmission>"
    )


def pair(kind, name, joints, motors, a, j, offsets=(None, None), ros2=False, swap=False) -> str:
    """A two-joint transmission (Differential or FourBarLinkage); `swap` writes the role-2
    elements first (the roles, not the order, decide)."""
    red = "mechanical_reduction" if ros2 else "mechanicalReduction"
    js, acts = [], []
    for r in range(2):
        off = "" if offsets[r] is None else f"<offset>{offsets[r]}</offset>"
        if ros2:
            js.append(
                f"<joint name='{joints[r]}' role='joint{r + 1}'>{off}<{red}>{j[r]}</{red}></joint>"
            )
            acts.append(
                f"<actuator name='{motors[r]}' role='actuator{r + 1}'><{red}>{a[r]}</{red}>"
                "</actuator>"
            )
        else:
            js.append(
                f"<joint name='{joints[r]}'><role>joint{r + 1}</role>{off}<{red}>{j[r]}</{red}>"
                "</joint>"
            )
            acts.append(
                f"<actuator name='{motors[r]}'><role>actuator{r + 1}</role><{red}>{a[r]}</{red}>"
                "</actuator>"
            )
    if swap:
        js.reverse()
        acts.reverse()
    tag = "plugin" if ros2 else "type"
    return (
        f"<transmission name='{name}'><{tag}>{PREFIX}{kind}</{tag}>"
        + "".join(acts + js)
        + "</transmission>"
    )


def load_text(tmp_path, text: str, name: str = "arm.urdf", tip=None):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return mindyn.load(p, tip=tip)


# ---- T by hand, from ros_control's documented joint -> actuator position maps ---------------


def simple_T(a):  # x_a = a (x_j - off)
    return np.array([[a]])


def differential_T(a, j):  # x_a1 = a1 (j1 x1 + j2 x2), x_a2 = a2 (j1 x1 - j2 x2)
    return np.array([[a[0] * j[0], a[0] * j[1]], [a[1] * j[0], -a[1] * j[1]]])


def four_bar_T(a, j):  # x_a1 = a1 j1 x1, x_a2 = a2 (x1 + j2 x2): motor 2 turns with both joints
    return np.array([[a[0] * j[0], 0.0], [a[1], a[1] * j[1]]])


def four_bar_joint_positions(xa, a, j, off):
    """ros_control's documented actuator -> joint map of the four-bar linkage."""
    x1 = xa[0] / (j[0] * a[0]) + off[0]
    x2 = (xa[1] / a[1] - xa[0] / (j[0] * a[0])) / j[1] + off[1]
    return np.array([x1, x2])


def differential_joint_positions(xa, a, j, off):
    """ros_control's documented actuator -> joint map of the differential."""
    x1 = (xa[0] / a[0] + xa[1] / a[1]) / (2 * j[0]) + off[0]
    x2 = (xa[0] / a[0] - xa[1] / a[1]) / (2 * j[1]) + off[1]
    return np.array([x1, x2])


RED = [100.0, -120.0, 80.0, 60.0]


def six_r_four_bar(ros2: bool, a=(50.0, 40.0), j=(1.0, 1.0), offsets=(None, None)) -> str:
    parts = [simple(f"t{k}", f"j{k}", f"m{k}", RED[k - 1], ros2=ros2) for k in range(1, 5)]
    parts.append(
        pair("FourBarLinkageTransmission", "wrist", ("j5", "j6"), ("m5", "m6"), a, j, offsets, ros2)
    )
    return arm_urdf(6, "".join(parts), ros2)


def wam_like(ros2: bool, swap: bool = False) -> str:
    a23, j23, a56, j56 = (30.0, -30.0), (1.0, 1.5), (20.0, 20.0), (0.8, 1.0)
    diff = "DifferentialTransmission"
    parts = [
        simple("t1", "j1", "m1", 42.0, ros2=ros2),
        pair(diff, "shoulder", ("j2", "j3"), ("m2", "m3"), a23, j23, ros2=ros2, swap=swap),
        simple("t4", "j4", "m4", 18.0, ros2=ros2),
        pair(diff, "wrist", ("j5", "j6"), ("m5", "m6"), a56, j56, ros2=ros2, swap=swap),
        simple("t7", "j7", "m7", 10.0, ros2=ros2),
    ]
    T = np.zeros((7, 7))
    T[0, 0], T[3, 3], T[6, 6] = 42.0, 18.0, 10.0
    T[1:3, 1:3] = differential_T(a23, j23)
    T[4:6, 4:6] = differential_T(a56, j56)
    return arm_urdf(7, "".join(parts), ros2), T


@pytest.mark.parametrize("ros2", [False, True], ids=["ros1", "ros2"])
def test_six_r_arm_with_a_four_bar_wrist_gives_the_documented_T(tmp_path, ros2):
    a, j = (50.0, 40.0), (1.2, 0.9)
    robot = load_text(tmp_path, six_r_four_bar(ros2, a, j))
    tr = robot.transmission
    expected = np.zeros((6, 6))
    for k in range(4):
        expected[k, k] = RED[k]
    expected[4:, 4:] = four_bar_T(a, j)
    assert tr.T.shape == (6, 6)
    np.testing.assert_allclose(tr.T, expected, rtol=0, atol=1e-12)
    assert tr.motors == ("m1", "m2", "m3", "m4", "m5", "m6")
    assert tr.types[4:] == ("FourBarLinkageTransmission",) * 2
    assert tr.format == ("ros2" if ros2 else "ros1")
    assert not tr.T.flags.writeable
    # motor 6 turns with joints 5 and 6; motor 5 with joint 5 only
    assert tr.T[5, 4] != 0 and tr.T[5, 5] != 0 and tr.T[4, 5] == 0


@pytest.mark.parametrize("ros2", [False, True], ids=["ros1", "ros2"])
def test_joint_offsets_give_motor_offsets_and_invert_as_ros_control_documents(tmp_path, ros2):
    a, j, off = (50.0, 40.0), (1.2, 0.9), (0.1, -0.25)
    robot = load_text(tmp_path, six_r_four_bar(ros2, a, j, off))
    tr = robot.transmission
    q = np.random.default_rng(0).uniform(-1, 1, 6)
    qm = tr.T @ q + tr.offset
    # ros_control's actuator -> joint map recovers the joint positions from the motors'
    np.testing.assert_allclose(four_bar_joint_positions(qm[4:], a, j, off), q[4:], atol=1e-12)
    np.testing.assert_allclose(tr.offset[:4], 0.0, atol=0)


@pytest.mark.parametrize("ros2", [False, True], ids=["ros1", "ros2"])
@pytest.mark.parametrize("swap", [False, True], ids=["in-order", "roles-swapped"])
def test_wam_like_arm_with_two_differentials_gives_the_documented_T(tmp_path, ros2, swap):
    text, expected = wam_like(ros2, swap)
    robot = load_text(tmp_path, text)
    np.testing.assert_allclose(robot.transmission.T, expected, rtol=0, atol=1e-12)
    # ros_control's documented actuator -> joint map inverts T on each differential
    q = np.random.default_rng(1).uniform(-1, 1, 7)
    qm = robot.transmission.T @ q
    back = differential_joint_positions(qm[4:6], (20.0, 20.0), (0.8, 1.0), (0.0, 0.0))
    np.testing.assert_allclose(back, q[4:6], atol=1e-12)


def test_simple_transmission_offset_and_ros2_reduction_from_the_joint(tmp_path):
    parts = simple("t1", "j1", "m1", 7.5, offset=0.2, ros2=True) + simple(
        "t2", "j2", "m2", -3.0, ros2=True
    )
    robot = load_text(tmp_path, arm_urdf(2, parts, ros2=True))
    tr = robot.transmission
    np.testing.assert_allclose(tr.T, np.diag([7.5, -3.0]), atol=0)
    np.testing.assert_allclose(tr.offset, [-7.5 * 0.2, 0.0], atol=1e-15)  # x_a = a (x - off)


def test_reductions_of_very_different_sizes_are_not_a_rank_deficiency(tmp_path):
    """Motors of reductions 1e-6 and 1e9 and a four-bar wrist of 1e4 x 1e4: T is block diagonal
    with invertible blocks (determinants 1e-6, 1e9 and a1 j1 a2 j2), so the motors determine
    every joint; the spread of its singular values (1e-15) is one of units. Two motors whose
    rows are multiples of each other stay refused, whatever their sizes."""
    parts = simple("t1", "j1", "m1", 1e-6) + simple("t2", "j2", "m2", 1e9)
    parts += pair("FourBarLinkageTransmission", "w", ("j3", "j4"), ("m3", "m4"), (1e4, 30.0),
                  (1e4, 1.0))  # fmt: skip
    robot = load_text(tmp_path, arm_urdf(4, parts))
    expected = np.zeros((4, 4))
    expected[0, 0], expected[1, 1] = 1e-6, 1e9
    expected[2:, 2:] = four_bar_T((1e4, 30.0), (1e4, 1.0))
    np.testing.assert_array_equal(robot.transmission.T, expected)
    rows = [[1e-6, 2e-6, 0.0], [1e9, 2e9, 0.0], [0.0, 0.0, 50.0]]
    with pytest.raises(mindyn.ModelError, match="rank deficient") as e:
        arm_yaml(tmp_path / "bad.yaml", {"matrix": rows})
    assert "\n" not in str(e.value)


def test_urdfs_without_transmissions_have_none(tmp_path):
    robot = load_text(tmp_path, arm_urdf(3))
    assert robot.transmission is None
    assert mindyn.load("puma560").transmission is None


def test_a_joint_without_transmission_is_driven_directly_and_noted(tmp_path):
    robot = load_text(tmp_path, arm_urdf(3, simple("t2", "j2", "m2", 9.0)))
    expected = [[0.0, 9.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]  # rows: m2, then j1, j3
    np.testing.assert_allclose(robot.transmission.T, expected, atol=0)
    assert robot.transmission.motors == ("m2", "j1", "j3")
    assert robot.transmission.types == ("SimpleTransmission", "direct", "direct")
    assert "driven directly" in robot.notes and "'j1'" in robot.notes


def test_transmission_of_a_locked_joint_is_dropped_or_held_constant(tmp_path):
    # the finger joint f1 is off the chain ending at l3: locked at 0 clamped into [0.01, 0.04]
    parts = "".join(simple(f"t{k}", f"j{k}", f"m{k}", 10.0 * k) for k in (1, 2))
    parts += pair("DifferentialTransmission", "mix", ("j3", "f1"), ("m3", "m4"), (5.0, 6.0),
                  (1.0, 2.0))  # fmt: skip
    parts += simple("tf", "f1x", "mf", 3.0)  # names no joint of the file: left out
    robot = load_text(tmp_path, arm_urdf(3, parts, branch=True), tip="l3")
    tr = robot.transmission
    assert robot.n == 3 and tr.T.shape == (4, 3)
    np.testing.assert_allclose(tr.T[:, 2], [0, 0, 5.0, 6.0], atol=0)
    # the locked joint's column times its locked position 0.01 is a constant of motors 3, 4
    np.testing.assert_allclose(tr.offset, [0, 0, 5.0 * 2.0 * 0.01, -6.0 * 2.0 * 0.01], atol=1e-15)
    assert "locked" in robot.notes and "'f1'" in robot.notes and "'tf'" in robot.notes


def test_other_transmission_types_are_left_out_and_noted(tmp_path):
    other = (
        "<transmission name='pr2' type='pr2_mechanism_model/PR2BeltCompensatorTransmission'>"
        "<actuator name='x'/><joint name='j1'/><mechanicalReduction>1</mechanicalReduction>"
        "</transmission>"
    )
    with pytest.warns(mindyn.DriveTrainWarning, match="'pr2'"):
        robot = load_text(tmp_path, arm_urdf(2, other))
    assert robot.transmission is None
    assert [t["name"] for t in robot.unread_transmissions] == ["pr2"]


# ---- export round trips --------------------------------------------------------------------


@pytest.mark.parametrize("ros2", [False, True], ids=["ros1", "ros2"])
def test_export_writes_the_transmissions_back_and_they_load_again(tmp_path, ros2):
    robot = load_text(tmp_path, six_r_four_bar(ros2, offsets=(0.1, 0.2)))
    out = tmp_path / "out.urdf"
    write_urdf(robot, robot.params * 1.1, out)
    text = out.read_text(encoding="utf-8")
    assert ("<ros2_control" in text) == ros2 and "FourBarLinkageTransmission" in text
    again = mindyn.load(out)
    np.testing.assert_array_equal(again.transmission.T, robot.transmission.T)
    np.testing.assert_array_equal(again.transmission.offset, robot.transmission.offset)
    assert again.transmission.motors == robot.transmission.motors
    assert again.transmission.format == robot.transmission.format


def arm_yaml(path, transmissions) -> mindyn.Robot:
    doc = {
        "name": "y",
        "convention": "dh",
        "joints": [
            {
                "name": f"j{k}",
                "a": 0.3,
                "alpha": 0.0,
                "d": 0.0,
                "theta": 0.0,
                "inertial": {
                    "mass": 1.0,
                    "com": [0.1, 0, 0],
                    "inertia": {"xx": 0.01, "yy": 0.01, "zz": 0.01},
                },
            }
            for k in (1, 2, 3)
        ],  # fmt: skip
    }
    if transmissions is not None:
        doc["transmissions"] = transmissions
    path.write_text(yaml.safe_dump(doc, sort_keys=False), encoding="utf-8")
    return mindyn.load(path)


def test_yaml_matrix_and_per_motor_forms_give_the_same_T_and_round_trip(tmp_path):
    T = [[100.0, 0.0, 0.0], [0.0, 50.0, 0.0], [0.0, 50.0, 50.0]]
    a = arm_yaml(
        tmp_path / "a.yaml",
        {"matrix": T, "motors": ["ma", "mb", "mc"], "torque_constant": [0.1, 0.2, 0.3]},
    )
    b = arm_yaml(
        tmp_path / "b.yaml",
        [
            {"name": "ma", "joints": {"j1": 100.0}, "torque_constant": 0.1},
            {"name": "mb", "joints": {"j2": 50.0}, "torque_constant": 0.2},
            {"name": "mc", "joints": {"j2": 50.0, "j3": 50.0}, "offset": 0.5},
        ],
    )
    np.testing.assert_array_equal(a.transmission.T, np.array(T))
    np.testing.assert_array_equal(b.transmission.T, np.array(T))
    np.testing.assert_array_equal(a.transmission.torque_constant, [0.1, 0.2, 0.3])
    assert np.isnan(b.transmission.torque_constant[2]) and b.transmission.offset[2] == 0.5
    assert a.transmission.motors == ("ma", "mb", "mc") and a.transmission.types[0] == "matrix"
    out = tmp_path / "out.yaml"
    write_yaml(b, b.params, out)
    again = mindyn.load(out)
    np.testing.assert_array_equal(again.transmission.T, b.transmission.T)
    np.testing.assert_array_equal(again.transmission.offset, b.transmission.offset)


@pytest.mark.parametrize(
    "transmissions, message",
    [
        ({"matrix": [[1, 0, 0], [0, 1, 1], [0, 2, 2]]}, "rank deficient"),
        ({"matrix": [[1, 0, 0], [0, 1, 0], [0, 1, 0.0]], "motors": ["a", "a", "b"]}, "unique"),
        ({"matrix": [[1, 0, 0], [0, 1, 0], [0, 0, 0]]}, "no motor drives joint 'j3' .its column"),
        ({"matrix": [[1, 0], [0, 1], [0, 0]]}, "'matrix' must be a list of 3 numbers"),
        ({"matrix": [[1, 0, 0], [0, 1, 0], [0, 0, "x"]]}, "'matrix' must be a number"),
        ([{"name": "m", "joints": {"j9": 1.0}}], "joint 'j9' is not a joint"),
        ([{"name": "m", "joints": {"j1": 1.0}}], "joints 'j2' and 'j3' .their columns of"),
        ({"matrix": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "torque_constant": [1, 0, 1]}, "torque"),
        ({"rows": [[1]]}, "unknown key 'rows'"),
        # the forms named with every key they take
        ("m1", r"offset, torque_constant, rotor_inertia, viscous, coulomb\} or a list"),
        ([], r"coefficient\}, offset, torque_constant, rotor_inertia, viscous, coulomb\}"),
    ],
)
def test_yaml_transmissions_malformed_are_refused_in_one_line(tmp_path, transmissions, message):
    with pytest.raises(mindyn.ModelError, match=message) as e:
        arm_yaml(tmp_path / "bad.yaml", transmissions)
    assert "\n" not in str(e.value) and "bad.yaml" in str(e.value)


# ---- malformed URDF transmissions ----------------------------------------------------------

GOOD_SIMPLE = (
    "<transmission name='t1'><type>transmission_interface/SimpleTransmission</type>"
    "<joint name='j1'/><actuator name='m1'><mechanicalReduction>10</mechanicalReduction>"
    "</actuator></transmission>"
)
GOOD_DIFF = pair("DifferentialTransmission", "d", ("j1", "j2"), ("m1", "m2"), (2, 3), (1, 1))


@pytest.mark.parametrize(
    "text, message",
    [
        (GOOD_SIMPLE.replace("<type>transmission_interface/SimpleTransmission</type>", ""),
         "transmission 't1': <transmission> has no <type>"),
        (GOOD_SIMPLE.replace("SimpleTransmission<", "SimpleTransmision<"),
         "is it transmission_interface/SimpleTransmission"),
        (GOOD_SIMPLE.replace(" name='t1'", ""), "has no name attribute"),
        (GOOD_SIMPLE.replace("<joint name='j1'/>", ""), "needs 1 <joint> element, found 0"),
        (GOOD_SIMPLE.replace("<joint name='j1'/>", "<joint/>"), "<joint> has no name"),
        (GOOD_SIMPLE.replace(">10<", ">1O<"), "<mechanicalReduction>1O</mechanicalReduction>: "
         "not a number"),
        (GOOD_SIMPLE.replace(">10<", "><"), "expected a number, got none"),
        (GOOD_SIMPLE.replace(">10<", ">0<"), "a reduction cannot be zero"),
        (GOOD_SIMPLE.replace(">10<", ">1e400<"), "exceeds the bound"),
        (GOOD_SIMPLE.replace("mechanicalReduction>", "mechanicalReducton>"),
         "is it <mechanicalReduction>"),
        (GOOD_DIFF.replace("'j2'", "'j9'"), "joint 'j9' is not a joint of the robot"),
        (GOOD_SIMPLE + GOOD_SIMPLE.replace("'m1'", "'m9'"), "declared twice"),
        (GOOD_SIMPLE + GOOD_SIMPLE.replace("'t1'", "'t2'").replace("'m1'", "'m2'"),
         "joint 'j1' is driven by transmission 't1' too"),
        (GOOD_SIMPLE + GOOD_SIMPLE.replace("'t1'", "'t2'").replace("'j1'", "'j2'"),
         "actuator 'm1' belongs to another transmission"),
        (GOOD_DIFF.replace("<role>joint2</role>", ""),
         "<joint name=\"j2\"> has no <role> (joint1 or joint2)"),
        (GOOD_DIFF.replace("<role>joint1</role>", "").replace("<role>joint2</role>", ""),
         "has no <role> (joint1 or joint2)"),
        (GOOD_DIFF.replace("<role>actuator2</role>", "<role>actuator1</role>"),
         "two <actuator> elements have the role actuator1"),
        (GOOD_DIFF.replace("<role>joint2</role>", "<role>joint3</role>"),
         "role 'joint3' is not joint1 or joint2"),
        (GOOD_DIFF.replace("<joint name='j2'><role>joint2</role><mechanicalReduction>1"
                           "</mechanicalReduction></joint>", ""),
         "needs 2 <joint> elements, found 1"),
        (GOOD_DIFF.replace("'j2'", "'j1'"), "both <joint> elements name 'j1'"),
        (GOOD_DIFF.replace("<role>joint1</role>", "<role>joint1</role><offset>a</offset>"),
         "<offset>a</offset>: not a number"),
    ],
)  # fmt: skip
def test_malformed_ros1_transmissions_are_refused_in_one_line(tmp_path, text, message):
    with pytest.raises(mindyn.ModelError) as e:
        load_text(tmp_path, arm_urdf(2, text), name="bad.urdf")
    msg = str(e.value)
    assert message in msg, msg
    assert "\n" not in msg and "bad.urdf:1:" in msg


@pytest.mark.parametrize(
    "text, message",
    [
        (simple("t1", "j1", "m1", 4, ros2=True).replace(
            "<plugin>transmission_interface/SimpleTransmission</plugin>", ""),
         "<transmission> has no <plugin>"),
        (simple("t1", "j1", "m1", 4, ros2=True).replace(
            "role='actuator1'/>", "role='actuator1'><mechanical_reduction>3"
            "</mechanical_reduction></actuator>"),
         "ros2_control's SimpleTransmission reads it from <joint>"),  # in both: which one?
        (pair("FourBarLinkageTransmission", "w", ("j1", "j2"), ("m1", "m2"), (1, 2), (1, 1),
              ros2=True).replace("role='joint2'", "role='joint1'"),
         "two <joint> elements have the role joint1"),
        (pair("FourBarLinkageTransmission", "w", ("j1", "j2"), ("m1", "m2"), (1, 2), (1, 1),
              ros2=True).replace(">2<", ">two<"),
         "<mechanical_reduction>two</mechanical_reduction>: not a number"),
        (pair("DifferentialTransmission", "w", ("j1", "j2"), ("m1", "m2"), (1, 2), (1, 1),
              ros2=True).replace(" role='actuator2'", ""),
         "<actuator> has no role while the other has one"),
    ],
)  # fmt: skip
def test_malformed_ros2_transmissions_are_refused_in_one_line(tmp_path, text, message):
    with pytest.raises(mindyn.ModelError) as e:
        load_text(tmp_path, arm_urdf(2, text, ros2=True), name="bad.urdf")
    msg = str(e.value)
    assert message in msg, msg
    assert "\n" not in msg and "bad.urdf:1:" in msg


def test_mixed_forms_are_refused(tmp_path):
    text = arm_urdf(2, simple("t2", "j2", "m2", 3, ros2=True), ros2=True)
    text = text.replace("</robot>", simple("t1", "j1", "m1", 3) + "</robot>")
    with pytest.raises(mindyn.ModelError, match="both the ROS 1 form"):
        load_text(tmp_path, text)


def test_cli_info_lists_the_motors(tmp_path, capsys):
    p = tmp_path / "arm.urdf"
    p.write_text(six_r_four_bar(False), encoding="utf-8")
    from mindyn.cli import main

    assert main(["info", str(p)]) == 0
    out = capsys.readouterr().out
    assert "transmissions (URDF, ROS 1 form)" in out
    line = next(x for x in out.splitlines() if x.startswith("m6 "))
    assert "FourBarLinkageTransmission" in line and "+40 j5 +40 j6" in line


def redundant_drive(tmp_path) -> Path:
    """The PUMA's links 1-3 driven by 4 motors through a YAML matrix (a redundant drive)."""
    table = yaml.safe_load(
        (Path(mindyn.__file__).parent / "robots" / "puma560_3.yaml").read_text(encoding="utf-8")
    )
    table["transmissions"] = {"matrix": [[1, 0, 0], [0, 2, 0], [0, 0, 3], [1, 1, 1]]}
    for joint, coulomb in zip(table["joints"], (2.0, 1.5, 1.0)):
        joint["friction"] = {"viscous": 0.5, "coulomb": coulomb}
    path = tmp_path / "redundant.yaml"
    path.write_text(yaml.safe_dump(table), encoding="utf-8")
    return path


def test_more_motors_than_joints_put_the_drive_terms_on_the_joints_by_default(tmp_path, capsys):
    """A YAML matrix of 4 motors for 3 joints (a redundant drive): a motor's rotor inertia and
    friction have no joint slot, so they act on the joints by default (a motor side refused
    --rotor and --friction until --drive-side joint was given); the rotor columns are then the
    joints' accelerations and the friction columns their velocities and signs (the closed
    form), info lists the 4 motors and says where the terms act, and asking for the motor side
    is refused in one line (library and description alike)."""
    from mindyn.cli import main

    path = redundant_drive(tmp_path)
    robot = mindyn.load(path)
    assert robot.transmission.n_motors == 4 and robot.n == 3
    assert robot.drive_side == "joint"
    rng = np.random.default_rng(3)
    q, dq, ddq = (rng.standard_normal(3) for _ in range(3))
    W = robot.regressor(q, dq, ddq, rotor=True, friction=True).reshape(3, 3, 13)
    np.testing.assert_array_equal(W[:, :, 10], np.diag(ddq))
    np.testing.assert_array_equal(W[:, :, 11], np.diag(dq))
    np.testing.assert_array_equal(W[:, :, 12], np.diag(np.sign(dq)))
    with pytest.raises(mindyn.ModelError, match="4 motors for 3 joints") as e:
        robot.with_drive_side("motor")
    assert "\n" not in str(e.value)
    table = yaml.safe_load(path.read_text(encoding="utf-8"))
    table["drive_side"] = "motor"
    (tmp_path / "motor.yaml").write_text(yaml.safe_dump(table), encoding="utf-8")
    with pytest.raises(mindyn.ModelError, match="needs one motor per joint.*4 motors for 3"):
        mindyn.load(tmp_path / "motor.yaml")
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "m4 " in out and "+1 j1 +1 j2 +1 j3" in out.replace("  ", " ")
    assert "rotor inertia and friction: on the joints (the values above): 4 motors for 3" in out


def test_default_gains_of_more_motors_than_joints_take_the_joints_friction(tmp_path, capsys):
    """The friction bound of the default gains takes the joints' Coulomb friction (4 motors for
    3 joints: K_P >= 2 Fc / (0.5 x 2 deg) per joint, from the description's values), with the
    rotors too, and `track` runs with them; a numpy shape error (T is 4 x 3) came out of
    both, and of `track`."""
    from mindyn import control
    from mindyn.cli import main

    path = redundant_drive(tmp_path)
    robot = mindyn.load(path)
    fc = robot.coulomb  # the description's joint values
    assert fc.tolist() == [2.0, 1.5, 1.0]
    kp, tol = control.controllers.friction_bound(robot)
    np.testing.assert_allclose(kp, 2 * fc / (0.5 * np.radians(2.0)), rtol=1e-12)
    gains = control.default_gains(robot, period=0.004, rotor=True)
    assert np.asarray(gains["kd"]).shape == (3,) and np.all(np.asarray(gains["kd"]) > 0)
    assert main(["track", str(path), "--duration", "0.2"]) == 0, capsys.readouterr().err


# ---- motor currents through T --------------------------------------------------------------


def test_currents_of_a_coupled_wrist_convert_through_T_not_per_joint(tmp_path):
    """A generated log of the 6R arm with a four-bar wrist: the motors' currents come from the
    inverse dynamics and tau_m = T^-T tau; tau = T^T K_t i recovers the joint torques, while
    the per-joint conversion (i x K_t x gear ratio of each joint) is measurably wrong."""
    robot = load_text(tmp_path, six_r_four_bar(False, a=(50.0, 40.0), j=(1.0, 1.0)))
    T = np.zeros((6, 6))
    for k in range(4):
        T[k, k] = RED[k]
    T[4:, 4:] = four_bar_T((50.0, 40.0), (1.0, 1.0))
    t = np.arange(400) * 0.005
    w = np.arange(1, 7)
    q = 0.5 * np.sin(0.7 * w * t[:, None])
    dq = 0.35 * w * np.cos(0.7 * w * t[:, None])
    ddq = -0.245 * w**2 * np.sin(0.7 * w * t[:, None])
    tau = robot.inverse_dynamics(q, dq, ddq)
    Kt = np.array([0.11, 0.12, 0.09, 0.07, 0.05, 0.04])
    i = np.linalg.solve(T.T, tau.T).T / Kt  # motor currents
    log = write_csv(tmp_path / "log.csv", t, q, i, dq=dq, ddq=ddq, torque_unit="current")
    data = read_csv(log, robot=robot, drive_gain=Kt)
    np.testing.assert_allclose(data.tau, tau, rtol=1e-9, atol=1e-9 * np.abs(tau).max())
    assert data.processing["torque"]["transmission_T"] == T.tolist()
    # the diagonal conversion that ignores the coupling misses joint 5's share of motor 6
    diagonal = i * Kt * np.diag(T)
    err5 = np.sqrt(np.mean((diagonal[:, 4] - tau[:, 4]) ** 2) / np.mean(tau[:, 4] ** 2))
    assert err5 > 0.5
    # the same through a currents file of its own
    cur = tmp_path / "cur.csv"
    cur.write_text(
        "t," + ",".join(f"i{k}" for k in range(1, 7)) + "\n"
        + "\n".join(",".join(repr(float(v)) for v in [t[s], *i[s]]) for s in range(t.size)),
        encoding="utf-8",
    )  # fmt: skip
    joined = attach_currents(data, cur, robot, drive_gain=Kt)
    np.testing.assert_allclose(joined.tau, tau, rtol=1e-9, atol=1e-9 * np.abs(tau).max())


def test_currents_need_the_motor_torque_constants(tmp_path):
    robot = load_text(tmp_path, six_r_four_bar(False))
    t = np.arange(10) * 0.01
    log = write_csv(tmp_path / "log.csv", t, np.zeros((10, 6)), np.ones((10, 6)),
                    torque_unit="current")  # fmt: skip
    with pytest.raises(mindyn.Error, match="no usable torque constant for motor.*m1"):
        read_csv(log, robot=robot)
    with pytest.raises(mindyn.Error, match="3 values for 6 motors"):
        read_csv(log, robot=robot, drive_gain=[1.0, 2.0, 3.0])
    # a zero given is named as given, not as a constant missing from the description
    with pytest.raises(mindyn.Error) as err:
        read_csv(log, robot=robot, drive_gain=[1.0, 0.0, 1.0, 1.0, 1.0, 0.0])
    message = str(err.value)
    assert "constants given are zero or not finite for m2 = 0, m6 = 0" in message, message
    assert "not given" not in message and "m1" not in message


def test_drive_side_is_the_motors_with_transmissions_and_switches_without_changing_the_robot(
    tmp_path,
):
    robot = load_text(tmp_path, six_r_four_bar(False))
    assert robot.drive_side == "motor"
    joint = robot.with_drive_side("joint")
    assert joint.drive_side == "joint" and robot.drive_side == "motor"
    assert joint.with_drive_side("motor").drive_side == "motor"
    plain = load_text(tmp_path, arm_urdf(3), name="plain.urdf")
    assert plain.drive_side == "joint"
    with pytest.raises(mindyn.ModelError, match="declares no transmissions"):
        plain.with_drive_side("motor")
    with pytest.raises(mindyn.ArgumentError, match="^side is .*'motor', 'joint'"):
        robot.with_drive_side("motors")


def test_friction_model_is_chosen_on_a_new_robot_and_checked(tmp_path):
    robot = load_text(tmp_path, arm_urdf(3), name="plain.urdf")
    assert robot.friction_model["kind"] == "coulomb"
    smooth = robot.with_friction_model("smooth", velocity=[0.01, 0.02, 0.03])
    assert smooth.friction_model["kind"] == "smooth" and robot.friction_model["kind"] == "coulomb"
    np.testing.assert_array_equal(smooth.friction_model["velocity"], [0.01, 0.02, 0.03])
    assert robot.with_friction_model("asymmetric").friction_model["kind"] == "asymmetric"
    with pytest.raises(mindyn.ArgumentError, match="'coulomb', 'asymmetric', 'smooth', 'stribeck'"):
        robot.with_friction_model("lugre")
    with pytest.raises(mindyn.ArgumentError, match="^velocity has 0 at entry 2"):
        robot.with_friction_model("stribeck", velocity=[0.1, 0.0, 0.1])
    with pytest.raises(mindyn.ModelError, match="needs a velocity per joint"):
        robot.with_friction_model("smooth")
    with pytest.raises(mindyn.ModelError, match="takes no velocity"):
        robot.with_friction_model("coulomb", velocity=[1.0, 1.0, 1.0])


@pytest.mark.parametrize("kind", ["coulomb", "asymmetric", "stribeck"])
def test_direct_drives_from_joint_values_have_the_joint_side_dynamics(tmp_path, kind):
    """A motor that alone drives one joint with ratio r, its values derived from the joint's
    (r^2 Ia, r^2 Fv, |r| Fc and the third friction term written out here), gives the joint-side
    dynamics exactly, with the friction velocity scales in motor units (|r| w)."""
    ratios = (-3.0, 7.0)
    parts = "".join(simple(f"t{k}", f"j{k}", f"m{k}", r) for k, r in zip((1, 2), ratios))
    robot = load_text(tmp_path, arm_urdf(2, parts))
    rng = np.random.default_rng(3)
    robot.rotor_inertia, robot.viscous = rng.uniform(0.1, 1.0, 2), rng.uniform(0.1, 1.0, 2)
    robot.coulomb, robot.third_friction = rng.uniform(0.1, 1.0, 2), rng.uniform(0.1, 1.0, 2)
    w = np.array([0.3, 0.5])
    joint = robot.with_drive_side("joint")
    motor = robot.with_drive_side("motor")
    if kind == "stribeck":
        joint = joint.with_friction_model(kind, velocity=w)
        motor = motor.with_friction_model(kind, velocity=np.abs(ratios) * w)
    elif kind == "asymmetric":
        joint, motor = joint.with_friction_model(kind), motor.with_friction_model(kind)
    r = np.array(ratios)
    pm = motor.parameters(rotor=True, friction=True).reshape(2, -1)
    np.testing.assert_allclose(pm[:, 10], robot.rotor_inertia / r**2, rtol=1e-15)
    np.testing.assert_allclose(pm[:, 11], robot.viscous / r**2, rtol=1e-15)
    np.testing.assert_allclose(pm[:, 12], robot.coulomb / np.abs(r), rtol=1e-15)
    if kind != "coulomb":  # r Fa |sign(r dq)| = (r Fa) |sign dq|; r Fs sign(r dq) = |r| Fs sign dq
        third = robot.third_friction / (r if kind == "asymmetric" else np.abs(r))
        np.testing.assert_allclose(pm[:, 13], third, rtol=1e-15)
    q, dq, ddq = rng.uniform(-1, 1, (3, 20, 2))
    tj = joint.inverse_dynamics(q, dq, ddq, joint.parameters(rotor=True, friction=True))
    tm = motor.inverse_dynamics(q, dq, ddq, motor.parameters(rotor=True, friction=True))
    np.testing.assert_allclose(tm, tj, rtol=1e-12, atol=1e-12 * np.abs(tj).max())


# ---- a floating or planar base: a joint of several degrees of freedom has no motor ----------


def declared_rows(path) -> dict[str, dict[str, float]]:
    """Each actuator's row of T, {joint: coefficient}, from the ROS 1 <transmission> elements of
    the URDF at `path` read with ElementTree, by ros_control's documented position maps (a
    joint's mechanicalReduction 1 unless given; roles by <role>, else the order)."""
    import xml.etree.ElementTree as ET

    def reduction(e) -> float:
        r = e.find("mechanicalReduction")
        return 1.0 if r is None else float(r.text)

    def by_role(es, kind):
        return sorted(es, key=lambda e: e.findtext("role") or f"{kind}{es.index(e) + 1}")

    rows = {}
    for t in ET.parse(path).getroot().iter("transmission"):
        kind = t.findtext("type").rsplit("/", 1)[-1]
        acts = by_role(t.findall("actuator"), "actuator")
        js = by_role(t.findall("joint"), "joint")
        a = [reduction(e) for e in acts]
        j = [reduction(e) for e in js]
        names = [e.get("name") for e in js]
        if kind == "SimpleTransmission":
            rows[acts[0].get("name")] = {names[0]: a[0] * j[0]}
        else:  # DifferentialTransmission: a1 (j1 x1 + j2 x2), a2 (j1 x1 - j2 x2)
            assert kind == "DifferentialTransmission"
            rows[acts[0].get("name")] = {names[0]: a[0] * j[0], names[1]: a[0] * j[1]}
            rows[acts[1].get("name")] = {names[0]: a[1] * j[0], names[1]: -a[1] * j[1]}
    return rows


def assert_declared(robot, rows, base: str, direct=()) -> None:
    """The base joint has a zero column and no motor; each declared motor has its declared row,
    each joint of `direct` a motor of its name with ratio 1, and there are no other motors."""
    tr = robot.transmission
    k = robot.joint_names.index(base)
    assert base not in tr.motors and not np.any(tr.T[:, k]), (tr.motors, tr.T[:, k])
    expected = dict(rows) | {d: {d: 1.0} for d in direct}
    assert sorted(tr.motors) == sorted(expected)
    for i, motor in enumerate(tr.motors):
        want = np.zeros(robot.n)
        for joint, c in expected[motor].items():
            want[robot.joint_names.index(joint)] = c
        np.testing.assert_array_equal(tr.T[i], want, err_msg=motor)
    assert tr.types.count("direct") == len(direct)
    said = [s for s in robot.notes.split(";") if "driven directly" in s]
    assert not any(f"'{base}'" in s for s in said), said


TIAGO = "tiago_description/robots/tiago_no_hand.urdf"


def test_a_planar_mobile_base_has_no_motor_and_the_arm_s_motors_are_as_declared(robots_dir):
    """TIAGo on a planar root: its 12 declared motors (one a differential wrist with a negative
    reduction), none for the planar joint, whose column of T is zero; `mindyn info` lists no
    motor of the root joint."""
    path = robots_dir / TIAGO
    robot = mindyn.load(path, root_joint="planar")
    rows = declared_rows(path)
    assert len(rows) == 12 and robot.n == 13
    assert_declared(robot, rows, "root_joint")
    assert robot.transmission.T.shape == (12, 13)
    from conftest import cli

    text = cli("info", path, "--root-joint", "planar")
    motors = [s for s in text.splitlines() if s.startswith("m") and s.split()[0][1:].isdigit()]
    assert len(motors) == 12 and not any("root_joint" in s for s in motors)
    assert "driven directly" not in text
    # what the motors' terms do, as the robot takes them: not at all with a planar base, through
    # T on the motor side without it
    assert "rotor inertia and friction are not modelled with joints of several" in text
    fixed = cli("info", path)
    assert mindyn.load(path).drive_side == "motor"
    assert "the motors' rotor inertia and friction act through T" in fixed


FLOATING_FILE = (
    "<link name='world'/><link name='base'><inertial><mass value='3'/><inertia ixx='0.1' "
    "ixy='0' ixz='0' iyy='0.2' iyz='0' izz='0.3'/></inertial></link>"
    "<joint name='float' type='floating'><parent link='world'/><child link='base'/></joint>"
)


def floating_arm(tmp_path, root: str, extra: str = "") -> tuple:
    """The 4R arm with a simple transmission on j1 and a differential on j2, j3 (j4 has none) on
    a floating or planar root joint, or under a floating joint of its own file ('file');
    returns (path, robot, the base joint's name)."""
    parts = simple("t1", "j1", "m1", 50.0)
    parts += pair("DifferentialTransmission", "w", ("j2", "j3"), ("m2", "m3"), (20.0, -30.0),
                  (1.5, 2.0))  # fmt: skip
    text = arm_urdf(4, parts + extra)
    if root == "file":
        text = text.replace("<link name='base'/>", FLOATING_FILE)
    path = tmp_path / "arm.urdf"
    path.write_text(text, encoding="utf-8")
    if root == "file":
        return path, mindyn.load(path), "float"
    return path, mindyn.load(path, root_joint=root), "root_joint"


@pytest.mark.parametrize("root", ["floating", "planar", "file"])
def test_a_floating_or_planar_root_has_no_motor_and_a_zero_column(tmp_path, root):
    path, robot, base = floating_arm(tmp_path, root)
    assert not robot.single_dof
    assert_declared(robot, declared_rows(path), base, direct=("j4",))
    assert "several degrees of freedom" in robot.notes and f"'{base}'" in robot.notes


@pytest.mark.parametrize("root", ["floating", "planar", "file"])
def test_a_multidof_robot_reports_no_drive_term_on_the_motors(tmp_path, root, capsys):
    """A robot with a joint of several degrees of freedom has no rotor inertia or friction
    terms (refused), so none acts on a motor: drive_side is "joint" although its file declares
    transmissions (read here with ElementTree), while the same arm on a fixed base reports
    "motor"; the motor side is refused in one line naming the joint (library and --drive-side);
    `mindyn info` says the terms are not modelled."""
    path, robot, base = floating_arm(tmp_path, root)
    assert len(declared_rows(path)) == 3 and robot.transmission is not None
    assert robot.drive_side == "joint"
    assert robot.with_drive_side("joint").drive_side == "joint"
    kind = "planar" if root == "planar" else "floating"
    with pytest.raises(mindyn.ModelError, match=f"has the {kind} joint '{base}'"):
        robot.with_drive_side("motor")
    q = np.r_[np.zeros(robot.nq - 4), 0.1, 0.2, 0.3, 0.4]
    q[3 if kind == "floating" else 2] = 1.0  # a unit quaternion (x, y, z, w), a (cos, sin)
    with pytest.raises(mindyn.ModelError, match="defined for revolute and prismatic joints"):
        robot.regressor(q, np.zeros(robot.nv), np.zeros(robot.nv), rotor=True)
    if root != "file":
        assert mindyn.load(path).drive_side == "motor"  # the arm on a fixed base
    from conftest import cli
    from mindyn.cli import main

    given = [] if root == "file" else ["--root-joint", root]
    text = cli("info", path, *given)
    assert "rotor inertia and friction are not modelled with joints of several" in text
    assert "act through T" not in text and "drive side: motor" not in text
    assert main(["base", str(path), *given, "--drive-side", "motor"]) != 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"has the {kind} joint '{base}'" in err, err


def test_export_of_a_floating_robot_writes_the_transmissions_back_unchanged(tmp_path):
    path, robot, base = floating_arm(tmp_path, "file")
    out = tmp_path / "out.urdf"
    write_urdf(robot, robot.params * 1.1, out)
    again = mindyn.load(out)
    np.testing.assert_array_equal(again.transmission.T, robot.transmission.T)
    assert again.transmission.motors == robot.transmission.motors
    assert_declared(again, declared_rows(out), base, direct=("j4",))


@pytest.mark.parametrize("root", ["floating", "planar", "file"])
def test_a_transmission_naming_a_floating_or_planar_joint_is_refused_in_one_line(
    tmp_path, root, capsys
):
    joint = "float" if root == "file" else "root_joint"
    kind = "planar" if root == "planar" else "floating"
    extra = simple("tb", joint, "mb", 2.0)
    with pytest.raises(mindyn.ModelError) as e:
        floating_arm(tmp_path, root, extra)
    message = str(e.value)
    assert "\n" not in message
    assert f"transmission 'tb': joint '{joint}' is a {kind} joint of several degrees" in message
    from mindyn.cli import main

    argv = ["info", str(tmp_path / "arm.urdf")] + ([] if root == "file" else ["--root-joint", root])
    assert main(argv) != 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"joint '{joint}' is a {kind} joint" in err


def test_currents_of_joints_without_a_transmission_beside_geared_ones_are_said(tmp_path, capsys):
    """A URDF that declares the transmission of joint 2 only: joints 1 and 3 are driven
    directly, so their currents become their torques at ratio 1. A wrist left out of the
    description by mistake gave torques 50 to 80 times too small that the unit check, blind to
    friction-dominated joints, took silently; the conversion now says which joints it took as
    driven directly."""
    robot = load_text(tmp_path, arm_urdf(3, simple("t2", "j2", "m2", 9.0)))
    t = np.arange(300) * 0.01
    w = np.arange(1, 4)
    q = 0.5 * np.sin(0.7 * w * t[:, None])
    dq = 0.35 * w * np.cos(0.7 * w * t[:, None])
    i = np.column_stack([np.sin(t), np.cos(2 * t), np.sin(3 * t + 1)])  # motors m2, j1, j3
    Kt = np.array([0.2, 3.0, 4.0])
    log = write_csv(tmp_path / "log.csv", t, q, i, dq=dq, torque_unit="current")
    data = read_csv(log, robot=robot, drive_gain=Kt)
    expected = np.column_stack([3.0 * i[:, 1], 9.0 * 0.2 * i[:, 0], 4.0 * i[:, 2]])  # by hand
    rows = np.searchsorted(t, data.t)
    np.testing.assert_allclose(data.tau, expected[rows], rtol=1e-9, atol=1e-9)  # 12 digits
    assert data.processing["torque"]["direct"] == ["j1", "j3"]
    argv = ["identify", str(tmp_path / "arm.urdf"), str(log), "--drive-gain", "0.2,3,4"]
    assert cli.main(argv + ["--rsd-threshold", "0"]) == 0, capsys.readouterr().err
    out = capsys.readouterr().out
    assert "joint(s) j1, j3 without a transmission in the description: driven directly" in out
    # every motor declared: nothing to say
    both = simple("t1", "j1", "m1", 5.0) + simple("t2", "j2", "m2", 9.0)
    both += simple("t3", "j3", "m3", 7.0)
    robot = load_text(tmp_path, arm_urdf(3, both), name="all.urdf")
    assert read_csv(log, robot=robot, drive_gain=Kt).processing["torque"]["direct"] == []
