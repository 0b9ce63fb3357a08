"""Numbers in a URDF: each one the model takes from a link or a joint is read or refused with one
line naming the file, line, link or joint, element, attribute and value as written; none becomes
a zero. urdfdom logs most of these (a mass of "3.7.0", an inertia of "nan", a missing <inertia>)
and keeps the link with mass and inertia 0; a misspelt attribute (ixxx, xzy, lowr) it takes as
absent, i.e. as its default. A link without <inertial> stays allowed and is named in the notes.
The valid URDFs of example-robot-data all load, with Pinocchio's moving masses."""

from __future__ import annotations

import subprocess
import sys

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import ROBOTS_DIR
from mindyn.cli import main

INERTIAL = (
    '<inertial><origin xyz="0.1 0 0" rpy="0 0 0"/><mass value="2"/>'
    '<inertia ixx="0.1" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.3"/></inertial>'
)
ORIGIN = '<origin xyz="0 0 0.5" rpy="0 0 0"/>'
AXIS = '<axis xyz="0 0 1"/>'
LIMIT = '<limit lower="-1" upper="1" effort="10" velocity="2"/>'
DYNAMICS = '<dynamics damping="0.1" friction="0.2"/>'
MIMIC = ""  # joint j2's mimic element, none in the good file


def text(**parts: str) -> str:
    """A two-joint URDF; `parts` replace INERTIAL (of link l1), ORIGIN, AXIS, LIMIT, DYNAMICS
    (of joint j1) and MIMIC (of joint j2)."""
    p = dict(
        INERTIAL=INERTIAL, ORIGIN=ORIGIN, AXIS=AXIS, LIMIT=LIMIT, DYNAMICS=DYNAMICS, MIMIC=MIMIC
    )
    p.update(parts)
    return (
        '<?xml version="1.0"?>\n'
        '<robot name="typo">\n'
        '  <link name="base"/>\n'
        f'  <link name="l1">{p["INERTIAL"]}</link>\n'
        f'  <link name="l2">{INERTIAL}</link>\n'
        '  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>\n'
        f"    {p['ORIGIN']}{p['AXIS']}{p['LIMIT']}{p['DYNAMICS']}\n"
        "  </joint>\n"
        '  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>\n'
        f"    {ORIGIN}{AXIS}{LIMIT}{p['MIMIC']}\n"
        "  </joint>\n"
        "</robot>\n"
    )


L1, J1, J2 = ("link 'l1'", 4), ("joint 'j1'", 7), ("joint 'j2'", 10)


def inertial(mass='value="2"', inertia=None, origin='xyz="0.1 0 0" rpy="0 0 0"', extra=""):
    inertia = inertia or 'ixx="0.1" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.3"'
    return f"<inertial><origin {origin}/><mass {mass}/><inertia {inertia}/>{extra}</inertial>"


def with_ixx(value: str) -> str:
    return inertial(inertia=f'ixx="{value}" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.3"')


NOT_A_NUMBER = ": not a number"
BOUND = "exceeds the bound 1e+16 on the magnitude of a description value"

# (id, parts of the file, (owner, line), what the message says)
CASES = [
    # <mass value=...>
    (
        "mass 3.7.0",
        {"INERTIAL": inertial('value="3.7.0"')},
        L1,
        '<mass value="3.7.0">: not a number',
    ),
    ("mass 3,7", {"INERTIAL": inertial('value="3,7"')}, L1, '<mass value="3,7">: not a number'),
    ("mass abc", {"INERTIAL": inertial('value="abc"')}, L1, '<mass value="abc">: not a number'),
    (
        "mass empty",
        {"INERTIAL": inertial('value=""')},
        L1,
        'value="">: expected one number, got none',
    ),
    ("mass nan", {"INERTIAL": inertial('value="nan"')}, L1, 'value="nan">: not a finite number'),
    ("mass inf", {"INERTIAL": inertial('value="inf"')}, L1, 'value="inf">: not a finite number'),
    (
        "mass -Infinity",
        {"INERTIAL": inertial('value="-Infinity"')},
        L1,
        'value="-Infinity">: not a finite number',
    ),
    ("mass 1e400", {"INERTIAL": inertial('value="1e400"')}, L1, f'value="1e400">: {BOUND}'),
    ("mass 1e17", {"INERTIAL": inertial('value="1e17"')}, L1, f'value="1e17">: {BOUND}'),
    (
        "mass two numbers",
        {"INERTIAL": inertial('value="3 7"')},
        L1,
        'value="3 7">: expected one number, got 2',
    ),
    ("mass hex", {"INERTIAL": inertial('value="0x10"')}, L1, '<mass value="0x10">: not a number'),
    (
        "mass negative",
        {"INERTIAL": inertial('value="-2"')},
        L1,
        '<mass value="-2">: a mass cannot be',
    ),
    ("mass misspelt", {"INERTIAL": inertial('valeu="2"')}, L1, 'valeu="2", which URDF does not'),
    (
        "mass without value",
        {"INERTIAL": inertial("")},
        L1,
        "<inertial><mass> has no attribute value",
    ),
    ("no mass", {"INERTIAL": INERTIAL.replace('<mass value="2"/>', "")}, L1, "has no <mass"),
    # <inertia ixx=... >
    ("ixx nan", {"INERTIAL": with_ixx("nan")}, L1, '<inertia ixx="nan">: not a finite number'),
    ("ixx abc", {"INERTIAL": with_ixx("abc")}, L1, '<inertia ixx="abc">: not a number'),
    ("ixx 3.7.0", {"INERTIAL": with_ixx("3.7.0")}, L1, '<inertia ixx="3.7.0">: not a number'),
    ("ixx empty", {"INERTIAL": with_ixx("")}, L1, 'ixx="">: expected one number, got none'),
    ("ixx 1e400", {"INERTIAL": with_ixx("1e400")}, L1, f'<inertia ixx="1e400">: {BOUND}'),
    ("ixx 1,5", {"INERTIAL": with_ixx("1,5")}, L1, '<inertia ixx="1,5">: not a number'),
    (
        "ixxx misspelt",
        {"INERTIAL": inertial(inertia='ixxx="0.1" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.3"')},
        L1,
        'attribute ixxx="0.1", which URDF does not define there; is it ixx?',
    ),
    (
        "iyy missing",
        {"INERTIAL": inertial(inertia='ixx="0.1" ixy="0" ixz="0" iyz="0" izz="0.3"')},
        L1,
        "<inertial><inertia> has no attribute iyy",
    ),
    (
        "inertia on <inertial>",
        {
            "INERTIAL": '<inertial ixx="0.1" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.3">'
            '<mass value="2"/></inertial>'
        },
        L1,
        '<inertial> has an attribute ixx="0.1", which URDF does not define',
    ),
    (
        "no inertia",
        {"INERTIAL": '<inertial><mass value="2"/></inertial>'},
        L1,
        "<inertial> has no <inertia",
    ),
    (
        "inertia misspelt element",
        {"INERTIAL": INERTIAL.replace("<inertia ", "<intertia ")},
        L1,
        "<inertial> holds an element <intertia>, which URDF does not define",
    ),
    # <inertial> and its <origin>
    (
        "com two numbers",
        {"INERTIAL": inertial(origin='xyz="0.1 0"')},
        L1,
        '<inertial><origin xyz="0.1 0">: expected 3 numbers, got 2',
    ),
    (
        "com rpy nan",
        {"INERTIAL": inertial(origin='rpy="0 nan 0"')},
        L1,
        '<inertial><origin rpy="0 nan 0">: "nan" is not a finite number',
    ),
    ("com misspelt", {"INERTIAL": inertial(origin='xyx="0 0 0"')}, L1, 'xyx="0 0 0", which'),
    (
        "inertial misspelt",
        {"INERTIAL": INERTIAL.replace("inertial>", "inertal>")},
        L1,
        "<link> holds an element <inertal>, which URDF does not define; is it <inertial>?",
    ),
    # the joint's <origin>, <axis>, <limit>, <dynamics>, <mimic>
    (
        "origin abc",
        {"ORIGIN": '<origin xyz="0 0 abc"/>'},
        J1,
        '<origin xyz="0 0 abc">: "abc" is not',
    ),
    (
        "origin commas",
        {"ORIGIN": '<origin rpy="0,0,0"/>'},
        J1,
        'rpy="0,0,0">: expected 3 numbers, got 1',
    ),
    ("origin 1e400", {"ORIGIN": '<origin xyz="1e400 0 0"/>'}, J1, f'"1e400" {BOUND}'),
    ("origin misspelt", {"ORIGIN": '<origin xyz="0 0 0.5" ryp="0 0 0"/>'}, J1, "is it rpy?"),
    ("axis 1.0.0", {"AXIS": '<axis xyz="0 0 1.0.0"/>'}, J1, '<axis xyz="0 0 1.0.0">: "1.0.0" is'),
    ("axis misspelt", {"AXIS": '<axis xzy="0 0 1"/>'}, J1, 'xzy="0 0 1", which URDF does not'),
    ("axis without xyz", {"AXIS": "<axis/>"}, J1, "<axis> has no attribute xyz"),
    (
        "axis element misspelt",
        {"AXIS": '<axsi xyz="0 0 1"/>'},
        J1,
        "<joint> holds an element <axsi>, which URDF does not define; is it <axis>?",
    ),
    (
        "lower 3.7.0",
        {"LIMIT": LIMIT.replace('"-1"', '"3.7.0"')},
        J1,
        '<limit lower="3.7.0">: not a number',
    ),
    (
        "upper nan",
        {"LIMIT": LIMIT.replace('upper="1"', 'upper="nan"')},
        J1,
        '<limit upper="nan">: not a finite number',
    ),
    ("lower misspelt", {"LIMIT": LIMIT.replace("lower", "lowr")}, J1, "is it lower?"),
    (
        "velocity misspelt",
        {"LIMIT": LIMIT.replace("velocity", "velocty")},
        J1,
        'velocty="2", which URDF does not define there; is it velocity?',
    ),
    (
        "effort negative",
        {"LIMIT": LIMIT.replace('"10"', '"-10"')},
        J1,
        '<limit effort="-10">: a limit on the magnitude cannot',
    ),
    (
        "effort 1e400",
        {"LIMIT": LIMIT.replace('"10"', '"1e400"')},
        J1,
        f'<limit effort="1e400">: {BOUND}',
    ),
    (
        "no velocity",
        {"LIMIT": LIMIT.replace(' velocity="2"', "")},
        J1,
        "<limit> has no attribute velocity (it needs effort and velocity)",
    ),
    ("limits element", {"LIMIT": LIMIT.replace("<limit", "<limits")}, J1, "is it <limit>?"),
    (
        "damping abc",
        {"DYNAMICS": DYNAMICS.replace('"0.1"', '"abc"')},
        J1,
        '<dynamics damping="abc">: not a number',
    ),
    (
        "damping misspelt",
        {"DYNAMICS": DYNAMICS.replace("damping", "dampng")},
        J1,
        'dampng="0.1", which URDF does not define there; is it damping?',
    ),
    (
        "mimic abc",
        {"MIMIC": '<mimic joint="j1" multiplier="abc"/>'},
        J2,
        '<mimic multiplier="abc">: not a number',
    ),
]


@pytest.fixture(params=CASES, ids=[c[0] for c in CASES])
def typo(request, tmp_path):
    name, parts, (owner, line), says = request.param
    path = tmp_path / "typo.urdf"
    path.write_text(text(**parts))
    return path, f"typo.urdf:{line}: {owner}: ", says


def test_the_good_file_loads_with_its_values(tmp_path):
    path = tmp_path / "good.urdf"
    path.write_text(text())
    robot = mindyn.load(path)
    # l1: 2 kg at x = 0.1 in its frame, inertia diag(0.1, 0.2, 0.3) about the COM
    expect = [0.1, 0, 0, 0.2 + 2 * 0.01, 0, 0.3 + 2 * 0.01, 0.2, 0, 0, 2]
    assert np.allclose(robot.parameters()[:10], expect, rtol=0, atol=1e-15)
    assert np.allclose(robot.limits["effort"], 10) and robot.notes == ""


def test_a_typo_is_refused_by_load_naming_where(typo):
    path, where, says = typo
    with pytest.raises(mindyn.ModelError) as e:
        mindyn.load(path)
    msg = str(e.value)
    assert where in msg and says in msg and "\n" not in msg, msg


def test_a_typo_is_one_error_line_from_info(typo, capfd):
    path, where, says = typo
    assert main(["info", str(path)]) == 2
    out, err = capfd.readouterr()  # file descriptors: urdfdom's console output would show here
    assert out == "" and err.startswith("mindyn: error: ") and err.count("\n") == 1, err
    assert where in err and says in err, err


def test_info_command_exits_with_one_line(tmp_path):
    path = tmp_path / "typo.urdf"
    path.write_text(text(INERTIAL=inertial('value="3.7.0"')))
    r = subprocess.run(
        [sys.executable, "-m", "mindyn", "info", str(path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 2 and r.stdout == "", r
    assert r.stderr == (
        f"mindyn: error: {path}:4: link 'l1': <inertial><mass value=\"3.7.0\">: not a number\n"
    )


@pytest.mark.parametrize(
    "parts",
    [
        {"INERTIAL": inertial('value=" 2 "')},
        {"INERTIAL": inertial('value="\n\t2.0e0 "')},
        {"INERTIAL": inertial(origin='xyz=" 0.1\t0  0 " rpy="0  0 0"')},
        {"LIMIT": '<limit lower=" -1" upper="1 " effort=" 10 " velocity="2"/>'},
        {"AXIS": '<axis xyz=" 0\t0 1 "/>'},
    ],
)
def test_white_space_around_numbers_is_read_as_xml_schema_does(tmp_path, parts):
    # xs:double collapses white space; urdfdom refuses " 2 " (and logs, zeroing a mass)
    path = tmp_path / "spaces.urdf"
    path.write_text(text(**parts))
    robot = mindyn.load(path)
    expect = [0.1, 0, 0, 0.2 + 2 * 0.01, 0, 0.3 + 2 * 0.01, 0.2, 0, 0, 2]
    assert np.allclose(robot.parameters()[:10], expect, rtol=0, atol=1e-15)
    assert np.allclose(robot.limits["upper"], 1) and np.allclose(robot.limits["effort"], 10)
    assert np.allclose(robot.fk(np.zeros(2))[:3, 3], [0, 0, 1])  # axes along z, origins 0.5


def test_a_number_below_the_smallest_double_is_zero(tmp_path):
    path = tmp_path / "tiny.urdf"
    path.write_text(text(INERTIAL=with_ixx("1e-400")))
    expect = [0, 0, 0, 0.2 + 2 * 0.01, 0, 0.3 + 2 * 0.01, 0.2, 0, 0, 2]  # ixx = 0, the rest read
    assert np.allclose(mindyn.load(path).parameters()[:10], expect, rtol=0, atol=1e-15)


def test_a_link_without_inertial_loads_and_is_named_in_the_notes(tmp_path, capsys):
    path = tmp_path / "massless.urdf"
    path.write_text(text(INERTIAL=""))
    robot = mindyn.load(path)
    assert "links without <inertial>, taken as massless: 'l1'" in robot.notes, robot.notes
    assert np.array_equal(robot.parameters()[:10], np.zeros(10))
    assert main(["info", str(path)]) == 0
    assert "notes      links without <inertial>, taken as massless: 'l1'" in capsys.readouterr().out


@pytest.mark.parametrize(
    "parts, note",
    [
        ({"INERTIAL": inertial(extra='<mass value="3"/>')}, "link 'l1': a second <mass> (line 4)"),
        ({"INERTIAL": INERTIAL + INERTIAL.replace('"2"', '"5"')}, "a second <inertial> (line 4)"),
        ({"ORIGIN": ORIGIN + '<origin xyz="0 0 7"/>'}, "joint 'j1': a second <origin> (line 7)"),
    ],
)
def test_a_second_element_is_ignored_as_urdf_parsers_do_and_noted(tmp_path, parts, note):
    # urdfdom reads the first (a published KUKA LWR description has two <origin> in a joint),
    # so Pinocchio's model of the file is the reference
    path = tmp_path / "twice.urdf"
    path.write_text(text(**parts))
    robot = mindyn.load(path)
    assert "elements every URDF parser ignores (the first is read): " in robot.notes
    assert note in robot.notes, robot.notes
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    q = np.array([0.3, -0.7])
    pin.forwardKinematics(model, data, q)
    assert np.allclose(robot.fk(q)[:3, 3], data.oMi[2].translation, rtol=0, atol=1e-12)
    assert abs(robot.parameters()[9] - model.inertias[1].mass) <= 1e-15


# The example-robot-data URDFs that fail for reasons other than their numbers.
NOT_LOADED = {
    "hector_description/robots/quadrotor_base.urdf": "has no moving joint",
    "iris_description/robots/iris_simple.urdf": "has no moving joint",
    "ur_description/urdf/ur3.urdf": "No name given for the robot",
}


def test_the_urdfs_of_example_robot_data_load_with_pinocchios_masses():
    found = sorted(ROBOTS_DIR.rglob("*.urdf"))
    assert len(found) >= 60
    compared = 0
    for path in found:
        rel = str(path.relative_to(ROBOTS_DIR))
        if rel in NOT_LOADED:
            with pytest.raises(mindyn.ModelError, match=NOT_LOADED[rel]):
                mindyn.load(path)
            continue
        robot = mindyn.load(path)
        model = pin.buildModelFromUrdf(str(path))
        if model.nq != robot.n or robot.notes.startswith(("mimic", "joints off")):
            continue  # Pinocchio keeps the joints mindyn locks (mimic fingers), or has others
        # the moving mass: every number of every <mass> below the first moving joints was read
        ours = robot.parameters()[9::10].sum()
        theirs = sum(model.inertias[k].mass for k in range(1, model.njoints))
        assert ours == pytest.approx(theirs, rel=1e-12), rel
        compared += 1
    assert compared >= 40
