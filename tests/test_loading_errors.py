"""Bad input gets a precise ValueError / FileNotFoundError (subclass) in Python and a one-line
message with a non-zero exit status from the CLI."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import URDFS
from mindyn.identification.data import DataError, read_csv

GOOD_YAML = """\
name: two
convention: dh
joints:
  - {name: a, a: 0.4, alpha: 0, d: 0, theta: 0, inertial: {mass: 1.0, com: [-0.2, 0, 0]}}
  - {name: b, a: 0.3, alpha: 0, d: 0, theta: 0, inertial: {mass: 0.5, com: [-0.15, 0, 0]}}
"""


def write(tmp_path: Path, name: str, text: str) -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def urdf(joints: str, links: str = "") -> str:
    head = '<?xml version="1.0"?>\n<robot name="t">\n<link name="base"/>\n'
    return f"{head}{links}\n{joints}\n</robot>\n"


def link(name: str, mass: float = 1.0) -> str:
    return (
        f'<link name="{name}"><inertial><mass value="{mass}"/>'
        '<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>'
    )


def joint(name: str, parent: str, child: str, kind: str = "revolute", extra: str = "") -> str:
    lim = '<limit lower="-1" upper="1" effort="1" velocity="1"/>' if kind != "fixed" else ""
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f'<axis xyz="0 0 1"/>{lim}{extra}</joint>'
    )


# --------------------------------------------------------------------------------------------
# files
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["missing.urdf", "missing.yaml", "missing.yml", "missing.xml"])
def test_missing_file(tmp_path, name):
    path = tmp_path / name
    with pytest.raises(FileNotFoundError, match=str(path)) as info:
        mindyn.load(path)
    assert isinstance(info.value, mindyn.RobotFileNotFoundError)
    with pytest.raises(mindyn.RobotFileNotFoundError):
        mindyn.load(str(path))


def test_missing_path_without_suffix(tmp_path):
    path = tmp_path / "nowhere" / "robot"
    with pytest.raises(FileNotFoundError, match="robot"):
        mindyn.load(path)


def test_paths_that_are_no_description_say_what_a_robot_is(tmp_path, monkeypatch):
    """A folder, an existing file of another kind and a missing MJCF are refused naming every
    form a robot takes (MJCF among them), a folder that has a bundled robot's name does not hide
    it."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "arm").mkdir()
    (tmp_path / "puma560").mkdir()
    write(tmp_path, "log.csv", "t,q1,tau1\n0,0,0\n")
    forms = "a .urdf file, a MuJoCo MJCF .xml file or a YAML DH/MDH table"
    with pytest.raises(mindyn.RobotFileNotFoundError, match=f"'arm' is a folder.*{forms}"):
        mindyn.load("arm")
    with pytest.raises(mindyn.ModelError, match=f"'log.csv' is not a robot description.*{forms}"):
        mindyn.load("log.csv")
    with pytest.raises(mindyn.RobotFileNotFoundError, match="robot file 'arm.xml' does not exist"):
        mindyn.load("arm.xml")
    with pytest.raises(mindyn.ModelError, match=f"unknown robot 'puma999'.*{forms}"):
        mindyn.load("puma999")
    assert mindyn.load("puma560").n == 6


def test_unknown_bundled_name():
    with pytest.raises(ValueError, match="unknown robot 'puma999'.*puma560") as info:
        mindyn.load("puma999")
    assert isinstance(info.value, mindyn.ModelError)


def test_bundled_names_load():
    for name in ["puma560", "puma560_3", "zcr07s", "stanford", "planar1", "planar5h"]:
        robot = mindyn.load(name)
        assert robot.n >= 1
        assert len(robot.params) == 10 * robot.n
    assert "puma560" in mindyn.bundled_robots()
    with pytest.raises(ValueError, match="at least one joint"):
        mindyn.load("planar0")


def test_malformed_urdf(tmp_path):
    path = write(tmp_path, "bad.urdf", '<robot name="x"><link name="a"/><joint name="j"')
    with pytest.raises(ValueError, match=r"bad\.urdf.*not a valid URDF") as info:
        mindyn.load(path)
    assert isinstance(info.value, mindyn.ModelError)
    # a joint naming a link that does not exist is urdfdom's complaint, passed on
    path = write(tmp_path, "dangling.urdf", urdf(joint("j1", "base", "nolink")))
    with pytest.raises(ValueError, match=r"dangling\.urdf.*not a valid URDF"):
        mindyn.load(path)


def test_urdf_floating_and_planar_joints_load_as_multi_dof_joints(tmp_path):
    """Formerly refused; now a free-flyer (nq 7, nv 6) and a planar joint (nq 4, nv 3)."""
    path = write(tmp_path, "float.urdf", urdf(joint("free", "base", "l1", "floating"), link("l1")))
    robot = mindyn.load(path)
    assert (robot.joint_types, robot.nq, robot.nv) == (["floating"], 7, 6)
    path = write(tmp_path, "planar.urdf", urdf(joint("pl", "base", "l1", "planar"), link("l1")))
    robot = mindyn.load(path)
    assert (robot.joint_types, robot.nq, robot.nv) == (["planar"], 4, 3)


def test_urdf_without_moving_joint(tmp_path):
    path = write(tmp_path, "rigid.urdf", urdf(joint("f", "base", "l1", "fixed"), link("l1")))
    with pytest.raises(ValueError, match="no moving joint"):
        mindyn.load(path)


def test_tree_urdf_without_tip_loads_whole(tmp_path):
    # Panda: the arm and one finger; the mirrored finger mimics it and is locked and merged
    robot = mindyn.load(URDFS["panda"])
    assert robot.n == 8 and robot.is_serial
    assert robot.joint_names[-1] == "panda_finger_joint1"
    assert "'panda_finger_joint2'" in robot.notes
    # a small tree of our own loads whole; tip= still selects a chain
    joints = joint("j1", "base", "l1") + joint("j2", "l1", "l2") + joint("j3", "l1", "l3")
    path = write(tmp_path, "tree.urdf", urdf(joints, link("l1") + link("l2") + link("l3")))
    tree = mindyn.load(path)
    assert tree.n == 3 and tree.parents == [-1, 0, 0] and not tree.is_serial
    assert mindyn.load(path, tip="l2").n == 2
    robot = mindyn.load(path, tip="l1")  # the branch locked and merged
    assert robot.n == 1
    assert robot.params[9] == pytest.approx(3.0)


def test_unknown_tip(tmp_path):
    with pytest.raises(ValueError, match="tip link 'hand' is not in robot 'panda'.*panda_link0"):
        mindyn.load(URDFS["panda"], tip="hand")


def test_mimic_joint_in_chain():
    with pytest.raises(ValueError, match="'panda_finger_joint2' mimics"):
        mindyn.load(URDFS["panda"], tip="panda_rightfinger")


def test_malformed_yaml(tmp_path):
    path = write(tmp_path, "bad.yaml", "name: x\nconvention: dh\njoints:\n  - {a: 1, alpha: 0\n")
    with pytest.raises(ValueError, match=r"bad\.yaml:5:1: not valid YAML") as info:
        mindyn.load(path)
    assert isinstance(info.value, mindyn.ModelError)


def test_yaml_unknown_key_typo(tmp_path):
    text = GOOD_YAML.replace("a: 0.3, alpha: 0", "a: 0.3, alpah: 0")
    path = write(tmp_path, "typo.yaml", text)
    column = text.splitlines()[4].index("alpah") + 1  # the key at fault
    with pytest.raises(
        ValueError, match=rf"typo\.yaml:5:{column}: joint 2 \('b'\): unknown key 'alpah'.*alpha"
    ):
        mindyn.load(path)
    path = write(tmp_path, "top.yaml", GOOD_YAML.replace("convention", "conventoin"))
    with pytest.raises(ValueError, match="unknown key 'conventoin'"):
        mindyn.load(path)


@pytest.mark.parametrize(
    "change, match",
    [
        (("convention: dh", "convention: xyz"), "'convention' must be 'dh' or 'mdh'"),
        (("name: a, a: 0.4", "name: a, type: ball, a: 0.4"), "joint type 'ball'"),
        (("a: 0.3", "a: abc"), "'a' must be a number"),
        (("mass: 1.0", "mass: -1.0"), "mass is negative"),
        (("com: [-0.2, 0, 0]", "com: [-0.2, 0]"), "'com' must be a list of 3 numbers"),
    ],
)
def test_yaml_bad_values(tmp_path, change, match):
    path = write(tmp_path, "r.yaml", GOOD_YAML.replace(*change))
    with pytest.raises(ValueError, match=match):
        mindyn.load(path)


def test_yaml_classical_inertial_with_a_negative_mass_is_refused(tmp_path):
    """A table's inertial in the loader's classical form (XX..M, as export writes it) took a
    negative M without a word (a -2 kg link, total moving mass -2 kg), where the mass/com form
    and a URDF refuse it."""
    text = (
        "name: neg\nconvention: dh\njoints:\n"
        "  - {type: revolute, a: 0.5, alpha: 0, d: 0, theta: 0,\n"
        "     inertial: {XX: 0.1, YY: 0.1, ZZ: 0.1, MX: 0.2, M: -2}}\n"
    )
    column = text.splitlines()[4].index("-2") + 1  # the value at fault
    with pytest.raises(mindyn.ModelError, match=rf"neg\.yaml:5:{column}: joint 1 .*mass M is neg"):
        mindyn.load(write(tmp_path, "neg.yaml", text))
    robot = mindyn.load(write(tmp_path, "pos.yaml", text.replace("M: -2", "M: 2")))
    assert robot.params[9] == 2.0


def test_good_yaml_loads(tmp_path):
    robot = mindyn.load(write(tmp_path, "r.yaml", GOOD_YAML))
    assert robot.n == 2
    assert robot.joint_names == ["a", "b"]
    assert robot.params[9::10].tolist() == [1.0, 0.5]


def test_tip_rejected_for_yaml_and_bundled(tmp_path):
    path = write(tmp_path, "r.yaml", GOOD_YAML)
    with pytest.raises(ValueError, match="tip= applies to URDF"):
        mindyn.load(path, tip="link2")
    with pytest.raises(ValueError, match="tip= applies to URDF"):
        mindyn.load("puma560", tip="link6")


# --------------------------------------------------------------------------------------------
# arrays
# --------------------------------------------------------------------------------------------
def test_wrong_array_shapes():
    robot = mindyn.load("puma560")
    z = np.zeros(6)
    with pytest.raises(ValueError, match=r"q has shape \(5,\); expected \(6,\)"):
        robot.inverse_dynamics(np.zeros(5), z, z)
    with pytest.raises(ValueError, match=r"ddq has shape \(7,\)"):
        robot.inverse_dynamics(z, z, np.zeros(7))
    with pytest.raises(ValueError, match=r"q has shape \(2, 3\); expected \(m, 6\)"):
        robot.mass_matrix(np.zeros((2, 3)))
    with pytest.raises(ValueError, match="q must be 1-D .* or 2-D .*got 3-D"):
        robot.regressor(np.zeros((2, 6, 1)), z, z)
    with pytest.raises(ValueError, match="batches of equal length"):
        robot.inverse_dynamics(np.zeros((3, 6)), np.zeros((2, 6)), np.zeros((3, 6)))
    with pytest.raises(ValueError, match="batches of equal length"):
        robot.inverse_dynamics(np.zeros((3, 6)), z, z)
    with pytest.raises(ValueError, match=r"dq has shape \(7,\)"):
        robot.kinetic_energy(z, np.zeros(7))
    with pytest.raises(ValueError, match=r"tau has shape \(5,\)"):
        robot.forward_dynamics(z, z, np.zeros(5))
    with pytest.raises(ValueError, match=r"q has shape \(5,\)"):
        robot.gravity_torque(np.zeros(5))
    with pytest.raises(ValueError, match=r"q has shape \(7,\)"):
        robot.energy_regressors(np.zeros(7), np.zeros(7))


@pytest.mark.parametrize(
    "call",
    [
        lambda r, q, z: r.inverse_dynamics(q, z, z),
        lambda r, q, z: r.regressor(q, z, z),
        lambda r, q, z: r.mass_matrix(q),
        lambda r, q, z: r.gravity_torque(q),
        lambda r, q, z: r.forward_dynamics(q, z, z),
        lambda r, q, z: r.kinetic_energy(q, z),
        lambda r, q, z: r.potential_energy(q),
        lambda r, q, z: r.energy_regressors(q, z),
        lambda r, q, z: r.fk(q),
        lambda r, q, z: r.jacobian(q),
    ],
)
def test_nan_in_q_names_q_and_joint(call):
    robot = mindyn.load("puma560")
    q = np.zeros(6)
    q[2] = np.nan
    with pytest.raises(ValueError, match="q contains NaN at joint 3"):
        call(robot, q, np.zeros(6))


def test_nan_in_batches_and_other_arguments():
    robot = mindyn.load("puma560")
    Q = np.zeros((4, 6))
    Q[2, 4] = np.nan
    with pytest.raises(ValueError, match="q contains NaN at sample 2, joint 5"):
        robot.inverse_dynamics(Q, Q * 0, Q * 0)
    dq = np.zeros(6)
    dq[0] = np.inf
    with pytest.raises(ValueError, match="dq contains an infinite value at joint 1"):
        robot.inverse_dynamics(np.zeros(6), dq, np.zeros(6))
    p = robot.params.copy()
    p[3] = np.nan
    with pytest.raises(ValueError, match="params contains NaN"):
        robot.inverse_dynamics(np.zeros(6), np.zeros(6), np.zeros(6), p)


def test_wrong_params_length():
    robot = mindyn.load("puma560")
    z = np.zeros(6)
    with pytest.raises(ValueError, match="59 entries fits no layout for 6 joints.*60.*66.*72.*78"):
        robot.inverse_dynamics(z, z, z, np.zeros(59))
    with pytest.raises(ValueError, match="fits no layout"):
        robot.mass_matrix(z, np.zeros(10))
    with pytest.raises(ValueError, match="params must be 1-D"):
        robot.gravity_torque(z, np.zeros((6, 10)))


def test_forward_dynamics_singular():
    robot = mindyn.load("planar3")
    z = np.zeros(3)
    with pytest.raises(ValueError, match="not positive definite"):
        robot.forward_dynamics(z, z, z, np.zeros(30))


def test_gravity_validation():
    robot = mindyn.load("planar2")
    with pytest.raises(ValueError, match="gravity contains NaN at entry 2"):
        robot.with_gravity([0.0, np.nan, -9.81])
    with pytest.raises(ValueError):
        robot.with_gravity([0.0, -9.81])
    with pytest.raises(ValueError, match="gravity contains NaN at entry 2"):
        mindyn.load("planar2", gravity=[0.0, np.nan, -9.81])
    with pytest.raises(AttributeError, match="with_gravity"):
        robot.gravity = [0.0, 0.0, -9.81]


# --------------------------------------------------------------------------------------------
# command line
# --------------------------------------------------------------------------------------------
def run_cli(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "mindyn", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=cwd,
    )


def assert_one_line_error(result):
    assert result.returncode != 0
    assert result.stdout == ""
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("mindyn: error: ")
    assert "Traceback" not in result.stderr


def test_cli_info_bundled():
    r = run_cli("info", "puma560")
    assert r.returncode == 0, r.stderr
    assert r.stderr == ""
    out = r.stdout
    assert "robot      puma560  (6 joints, dh)" in out
    rows = [line.split() for line in out.splitlines() if line[:2].strip().isdigit()]
    assert [row[:3] for row in rows] == [[str(k), f"j{k}", "revolute"] for k in range(1, 7)]
    # the PUMA's published link masses (Armstrong-Khatib-Burdick): 17.4 + 4.8 + 0.82 + 0.34 + 0.09
    assert "total moving mass 23.45 kg" in out
    assert "XX" in out and "Ia" in out and "Fc" in out


def test_cli_info_urdf():
    r = run_cli("info", URDFS["ur5"])
    assert r.returncode == 0, r.stderr
    model = pin.buildModelFromUrdf(str(URDFS["ur5"]))
    mass = sum(model.inertias[k].mass for k in range(1, model.njoints))
    assert f"total moving mass {mass:.4g} kg" in r.stdout
    rows = [line.split() for line in r.stdout.splitlines() if line[:2].strip().isdigit()]
    names = [model.names[k] for k in range(1, model.njoints)]
    assert [row[1] for row in rows] == names  # long names do not run into the type column
    assert all(row[2] == "revolute" for row in rows)


def test_cli_info_panda_with_tip():
    r = run_cli("info", URDFS["panda"], "--tip", "panda_hand")
    assert r.returncode == 0, r.stderr
    assert "(7 joints, urdf)" in r.stdout


def test_cli_console_script():
    script = Path(sys.executable).with_name("mindyn")
    if not script.exists():
        pytest.skip("console script not installed next to the interpreter")
    r = subprocess.run([str(script), "info", "planar2"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    assert "total moving mass 4 kg" in r.stdout  # two 2 kg rods


@pytest.mark.parametrize(
    "args, match",
    [
        (("info", "missing.urdf"), "URDF file 'missing.urdf' does not exist"),
        (("info", "missing.yaml"), "missing.yaml"),
        (("info", "puma999"), "unknown robot 'puma999'"),
        (("info", "puma560", "--tip", "link6"), "--tip applies to URDF"),
        (("info", "GOOD.yaml", "--tip", "b"), "--tip applies to URDF"),
        (("info", "BAD.yaml"), "not valid YAML"),
        (("info", "BAD.urdf"), "not a valid URDF"),
        (("info", URDFS["panda"], "--tip", "panda_rightfinger"), "a tip link (--tip)"),
    ],
)
def test_cli_errors_are_one_line(tmp_path, args, match):
    write(tmp_path, "GOOD.yaml", GOOD_YAML)
    write(tmp_path, "BAD.yaml", "joints: [")
    write(tmp_path, "BAD.urdf", "<robot")
    r = run_cli(*args, cwd=tmp_path)
    assert_one_line_error(r)
    assert match in r.stderr


def test_cli_usage_errors():
    r = run_cli()
    assert r.returncode != 0
    assert "Traceback" not in r.stderr
    r = run_cli("info", "--help")
    assert r.returncode == 0
    assert "ROBOT" in r.stdout


def test_closed_stdout_ends_quietly():
    """A reader that goes away (`mindyn base ROBOT | head -1`) ends the command without a
    traceback: the pipe is closed before the command writes anything."""
    p = subprocess.Popen(
        [sys.executable, "-m", "mindyn", "base", "puma560"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    p.stdout.close()
    err = p.stderr.read()
    p.wait(timeout=60)
    assert "Traceback" not in err and "BrokenPipeError" not in err, err
    assert p.returncode == 141


# --------------------------------------------------------------------------------------------
# descriptions that are not trees, wrongly typed YAML, extreme values
# --------------------------------------------------------------------------------------------
def test_urdf_loops_and_self_parented_joints_are_named(tmp_path):
    links = link("a") + link("b") + link("c") + link("d")
    # a -> b -> c -> a next to the root chain base -> d: urdfdom accepts it, the chain walk used
    # to crash (SIGSEGV) or grow without bound with a tip
    loop = joint("j0", "base", "d") + joint("j1", "a", "b") + joint("j2", "b", "c")
    path = write(tmp_path, "loop.urdf", urdf(loop + joint("j3", "c", "a"), links))
    for tip in (None, "c", "d"):
        with pytest.raises(
            mindyn.ModelError,
            match=r"loop\.urdf: joints 'j1', 'j2', 'j3' form a loop through links 'b', 'c', 'a'",
        ):
            mindyn.load(path, tip=tip)
    # base -> a -> b -> a: a joint leads back to its parent's parent
    back = joint("j0", "base", "a") + joint("j1", "a", "b") + joint("j2", "b", "a")
    path = write(tmp_path, "back.urdf", urdf(back, link("a") + link("b")))
    for tip in (None, "b"):
        with pytest.raises(mindyn.ModelError, match=r"back\.urdf: link 'a' is the child of 2"):
            mindyn.load(path, tip=tip)
    # b -> b used to drop b silently and load a one-joint robot
    path = write(
        tmp_path,
        "self.urdf",
        urdf(joint("j0", "base", "a") + joint("j1", "b", "b"), link("a") + link("b")),
    )
    with pytest.raises(
        mindyn.ModelError, match=r"self\.urdf: joint 'j1' has link 'b' as both its parent"
    ):
        mindyn.load(path)
    r = run_cli("info", path)
    assert_one_line_error(r)
    assert "self.urdf" in r.stderr


@pytest.mark.parametrize(
    "change, at, match",
    [
        (("name: two", "name: [1, 2]"), "[1, 2]", r"r\.yaml:1:\d+: 'name' must be text, got a l"),
        (("convention: dh", "convention: {x: 1}"), "{x", r"r\.yaml:2:\d+: 'convention' must be"),
        (("name: a,", "name: [a],"), "[a]", r"r\.yaml:4:\d+: joint 1: 'name' must be text, got a"),
        (("a: 0.4", "a: [0.4]"), "[0.4]", r"r\.yaml:4:\d+: joint 1 \('a'\): 'a' must be a number"),
        (("com: [-0.2, 0, 0]", "com: {x: 1}"), "{x", r"r\.yaml:4:\d+: .*'com' must be a list of 3"),
        (("name: two", "name: !!python/object:os.system two"), "!!py", r"r\.yaml:1:\d+: YAML tag"),
        (("name: two", "name: !!binary AAAA"), "!!binary", r"r\.yaml:1:\d+: YAML tag '.*binary"),
        (("name: two", "name: two\nname: three"), "name: three", r"r\.yaml:2:\d+: key 'name' appe"),
        (("a: 0.4,", "a: 0.4, a: 0.5,"), "a: 0.5", r"r\.yaml:4:\d+: key 'a' appears twice"),
        (("name: two", "name: two\nsynthetic_inertia: [1]"), "[1]", r"r\.yaml:2:\d+: 'synthetic_"),
        (("name: two", "name: two\n[1, 2]: 3"), "[1, 2]: 3", r"r\.yaml:2:\d+: a key must be plain"),
        # numbers that cannot be read, or keys left without a value (were taken as 0)
        (("a: 0.4", "a: 3.7.0"), "3.7.0", r"r\.yaml:4:\d+: .*'a' must be a number, got '3.7.0'"),
        (("a: 0.4", "a: '3,7'"), "'3,7'", r"r\.yaml:4:\d+: .*'a' must be a number, got '3,7'"),
        (("a: 0.4", "a: 1e400"), "1e400", r"r\.yaml:4:\d+: .*'a' must be a number, got '1e400'"),
        (("a: 0.4", "a: ~"), "~", r"r\.yaml:4:\d+: joint 1 \('a'\): 'a' has no value; give a num"),
        (("mass: 1.0", "mass: 1.0, inertia: {xx: }"), "}, com", r"r\.yaml:4:\d+: .*'xx' has no"),
    ],
)
def test_yaml_type_errors_name_file_line_column_and_key(tmp_path, change, at, match):
    """The column is that of the entry at fault (where the value would be, for a key left
    without one), found here in the file's own text."""
    path = write(tmp_path, "r.yaml", GOOD_YAML.replace(*change))
    with pytest.raises(mindyn.ModelError, match=match) as e:
        mindyn.load(path)
    line, column = map(int, re.search(r"r\.yaml:(\d+):(\d+): ", str(e.value)).groups())
    assert path.read_text().splitlines()[line - 1][column - 1 :].startswith(at), e.value


# a quote left open outside a flow is refused where it opens, the place PyYAML names as the
# quoted text's start (its context); yaml-cpp took it as text running to the end of the file,
# and then said that 'convention' was missing
OPEN_QUOTES = [
    'name: "x\nconvention: dh\njoints:\n  - {a: 1, alpha: 0}\n',
    'name: "x\\"\nconvention: dh\njoints:\n  - {a: 1, alpha: 0}\n',  # the quote escaped
]


@pytest.mark.parametrize(
    "text",
    [
        "name: x\nconvention: dh\njoints:\n  - {a: 1, alpha: 0\n",  # a flow mapping not closed
        "name: x\n  bad: 1\n",  # a mapping value where none may be
        "joints: [\n",  # a flow sequence not closed
        "a: 1\n\tb: 2\n",  # a tab as indentation
        "name: x\nconvention: dh\njoints:\n  - {a: 1, alpha: 0]}\n",  # a stray flow end
        "name: x\nconvention: dh\njoints:\n  - a: 1\n   b: 2\n",  # indentation off by one
        "name: x\nconvention: dh\njoints:\n  - {name: 'j1, a: 1}\n",  # a quote left open in a flow
        *OPEN_QUOTES,
    ],
)
def test_yaml_syntax_errors_give_the_line_and_column_pyyaml_gives(tmp_path, text):
    """The description reader (yaml-cpp) named the line of a syntax error only; now the line
    and column, as the Python readers give them: the place PyYAML's parser reports (for a
    quote left open, where it opens)."""
    import yaml

    path = write(tmp_path, "s.yaml", text)
    with pytest.raises(yaml.YAMLError) as e:
        yaml.safe_load(text)
    mark = e.value.context_mark if text in OPEN_QUOTES else e.value.problem_mark
    with pytest.raises(mindyn.ModelError) as info:
        mindyn.load(path)
    want = f"{path}:{mark.line + 1}:{mark.column + 1}: not valid YAML: "
    assert str(info.value).startswith(want), (str(info.value), want)
    if text in OPEN_QUOTES:
        assert "the quoted text starting here is never closed" in str(info.value)


def test_yaml_closed_quotes_with_escapes_load(tmp_path):
    """Quotes closed after an escaped quote, a doubled single quote or a line break load, with
    the text PyYAML reads."""
    import yaml

    for name in ('"a\\"b"', "'it''s'", '"two\n  lines"'):
        text = f"name: {name}\nconvention: dh\njoints:\n  - {{a: 1, alpha: 0}}\n"
        path = write(tmp_path, "ok.yaml", text)
        assert mindyn.load(path).name == yaml.safe_load(text)["name"]


def test_yaml_several_documents_refused(tmp_path):
    path = write(tmp_path, "r.yaml", GOOD_YAML + "---\n" + GOOD_YAML)
    with pytest.raises(mindyn.ModelError, match=r"r\.yaml:6:1: a second YAML document starts here"):
        mindyn.load(path)
    # a stray flow end: yaml-cpp's own multi-document loader loops forever, allocating, on it
    path = write(tmp_path, "s.yaml", ", 0.1]}}\n")
    with pytest.raises(mindyn.ModelError, match=r"s\.yaml"):
        mindyn.load(path)


@pytest.mark.parametrize(
    "change, key",
    [
        (("a: 0.4", "a: 1e308"), "a"),
        (("mass: 1.0", "mass: 1e300"), "mass"),
        (("mass: 1.0", "mass: 1.0, inertia: {xx: 1e305}"), "xx"),
        (("name: a,", "name: a, limits: {lower: -1e308, upper: 1},"), "lower"),
        (("name: two", "name: two\ngravity: [0, 0, -1e200]"), "gravity"),
    ],
)
def test_yaml_extreme_values_refused_with_the_bound(tmp_path, change, key):
    path = write(tmp_path, "r.yaml", GOOD_YAML.replace(*change))
    with pytest.raises(
        mindyn.ModelError, match=rf"r\.yaml:\d+:\d+: .*'{key}' = .* exceeds the bound 1e\+16"
    ):
        mindyn.load(path)


def test_values_at_the_bound_give_finite_dynamics(tmp_path):
    """The bound is set so that the largest accepted values keep every result finite: a mass of
    1e16 kg on a 1e16 m link under 1e16 m/s^2 gravity at a moderate joint state."""
    text = GOOD_YAML.replace("a: 0.4", "a: 1e16").replace("mass: 1.0", "mass: 1e16")
    text = text.replace("name: two", "name: two\ngravity: [0, -1e16, 0]")
    robot = mindyn.load(write(tmp_path, "r.yaml", text))
    q = np.array([0.3, -0.2])
    tau = robot.inverse_dynamics(q, q, q)
    assert np.isfinite(tau).all()
    # gravity torque of joint 2 alone: its mass 0.5 at com -0.15 m of a 0.3 m link, known in
    # closed form, unaffected by the huge values upstream (relative 1e-9: rounding of the sums)
    g = robot.gravity_torque(q)
    assert np.isfinite(g).all()
    expect2 = -0.5 * 1e16 * (0.3 - 0.15) * np.cos(q[0] + q[1]) * -1
    assert g[1] == pytest.approx(expect2, rel=1e-9)


def test_urdf_extreme_values_refused_with_the_bound(tmp_path):
    path = write(tmp_path, "m.urdf", urdf(joint("j0", "base", "a"), link("a", mass=1e300)))
    bound = "exceeds the bound 1e[+]16 on the magnitude"
    with pytest.raises(
        mindyn.ModelError,
        match=rf"m\.urdf:4: link 'a': <inertial><mass value=\"1e[+]300\">: {bound}",
    ):
        mindyn.load(path)
    far = joint("j0", "base", "a", extra='<origin xyz="0 1e308 0"/>')
    path = write(tmp_path, "o.urdf", urdf(far, link("a")))
    with pytest.raises(
        mindyn.ModelError,
        match=rf"o\.urdf:5: joint 'j0': <origin xyz=\"0 1e308 0\">: \"1e308\" {bound}",
    ):
        mindyn.load(path)


def test_text_that_is_not_utf8_is_located(tmp_path):
    text = GOOD_YAML.replace("name: b", "name: b\xff").encode("latin-1")
    (tmp_path / "r.yaml").write_bytes(text)
    offset = text.index(b"\xff")
    with pytest.raises(
        mindyn.ModelError, match=rf"r\.yaml:5: not UTF-8 text \(byte 0xff at offset {offset}\)"
    ):
        mindyn.load(tmp_path / "r.yaml")
    text = urdf(joint("j\xe91", "base", "a"), link("a")).encode("latin-1")  # a Latin-1 name
    (tmp_path / "r.urdf").write_bytes(text)
    with pytest.raises(mindyn.ModelError, match=r"r\.urdf:\d+: not UTF-8 text \(byte 0xe9"):
        mindyn.load(tmp_path / "r.urdf")


def test_names_with_line_breaks_stay_on_one_line(tmp_path):
    path = write(tmp_path, "n.urdf", urdf(joint("j0", "base", "a\nb"), link("a")))
    with pytest.raises(mindyn.ModelError, match=r"n\.urdf: .*a\\nb") as info:
        mindyn.load(path)
    assert "\n" not in str(info.value)
    path = write(tmp_path, "n.yaml", GOOD_YAML.replace("a: 0.4", 'type: "x\\ny", a: 0.4'))
    column = path.read_text().splitlines()[3].index('"x') + 1
    with pytest.raises(mindyn.ModelError, match=rf"n\.yaml:4:{column}: .*type 'x\\ny'") as info:
        mindyn.load(path)
    assert "\n" not in str(info.value)


def test_yaml_parser_messages_reach_python_as_one_line(tmp_path):
    # NUL bytes make yaml-cpp quote a byte that is not UTF-8 in its message; the conversion to
    # Python used to fail with UnicodeDecodeError
    text = b"n" + b"\0" * 8 + b"ame: three\njoints:\n  - {alpha:, d: 0.1}\n  - {alpha: 0, d: }\n"
    (tmp_path / "z.yaml").write_bytes(text)
    with pytest.raises(mindyn.ModelError, match=r"z\.yaml:\d+:\d+: not valid YAML") as info:
        mindyn.load(tmp_path / "z.yaml")
    assert "\n" not in str(info.value)


def test_planar_arm_size_is_bounded():
    assert mindyn.load("planar1000").n == 1000  # the bound itself, as the core's
    for name in ("planar1001", "planar100000", "planar9999999999999999999999999"):
        with pytest.raises(mindyn.ModelError, match="a planar arm has at most 1000 joints"):
            mindyn.load(name)
    r = run_cli("info", "planar100000")  # (the command line refuses a count beyond an int itself)
    assert_one_line_error(r)
    assert "at most 1000 joints" in r.stderr
    with pytest.raises(mindyn.ModelError, match="unknown robot"):
        mindyn.load("planar\u0661")  # a non-ASCII digit is no number of joints


# --------------------------------------------------------------------------------------------
# property: every mutation of a valid file loads or fails with our error naming the file
# --------------------------------------------------------------------------------------------
GOOD_URDF = urdf(
    joint("j1", "base", "l1", extra='<origin xyz="0 0 0.1"/>')
    + joint("j2", "l1", "l2", "prismatic", extra='<origin xyz="0.4 0 0" rpy="1.5 0 0"/>')
    + joint("f", "l2", "tool", "fixed"),
    link("l1") + link("l2", 0.5) + '<link name="tool"/>',
)
GOOD_CSV = "t,q1,q2,tau1,tau2\n" + "".join(
    f"{0.004 * k:.3f},{0.1 * k:.2f},{-0.05 * k:.3f},{k % 3},{1 - k % 2}\n" for k in range(40)
)
EXTREMES = [
    "1e308", "-1e308", "1e400", "nan", ".nan", "inf", "-.inf", "1e16", "2e16", "0", "-0", "1_000",
    "0x10", "\uff11", "", " ", "[1, 2]", "{a: 1}", "!!python/object:os.system x", "~", "true",
    "'text'", "\xff", "\udcff", "\x00", "a", "&x 1", "*x", "-1", "1e-320",
]  # fmt: skip


def _mutate(text: str, data) -> str:
    """Drops, duplicates, retypes or breaks pieces of `text` as `data` (hypothesis) chooses."""
    from hypothesis import strategies as st

    for _ in range(data.draw(st.integers(1, 3))):
        lines = text.split("\n")
        k = data.draw(st.integers(0, len(lines) - 1))
        op = data.draw(st.sampled_from(["drop", "dup", "value", "key", "cut", "swap", "byte"]))
        if op == "drop":
            del lines[k]
        elif op == "dup":
            lines.insert(k, lines[k])
        elif op == "swap":
            j = data.draw(st.integers(0, len(lines) - 1))
            lines[k], lines[j] = lines[j], lines[k]
        elif op in ("value", "key"):
            # replace one token (a number, a quoted attribute, a word) by an extreme or a wrong type
            tokens = re.findall(r'"[^"]*"|[A-Za-z_]+|[-+0-9.eE]+', lines[k])
            if tokens:
                old = data.draw(st.sampled_from(tokens))
                new = data.draw(st.sampled_from(EXTREMES + ["name", "a", "base", "l1", "j1"]))
                if old.startswith('"'):
                    new = f'"{new}"'
                lines[k] = lines[k].replace(old, new, 1)
        elif op == "cut":
            i = data.draw(st.integers(0, len(lines[k])))
            lines[k] = lines[k][:i]
        else:
            i = data.draw(st.integers(0, len(lines[k])))
            ins = data.draw(st.sampled_from(["\udcff", "\x00", "<", '"', ","]))
            lines[k] = lines[k][:i] + ins + lines[k][i:]
        text = "\n".join(lines)
    return text


def _outcome_is_ours(path: Path, load) -> None:
    try:
        result = load(path)
    except (mindyn.ModelError, mindyn.RobotFileNotFoundError, DataError) as e:
        assert path.name in str(e) and "\n" not in str(e), str(e)
        return
    if isinstance(result, mindyn.Robot):
        q = np.full(result.n, 0.3)
        assert np.isfinite(result.inverse_dynamics(q, q, q)).all()
    else:
        assert all(np.isfinite(a).all() for a in (result.q, result.dq, result.ddq))


@pytest.mark.parametrize(
    "name, good, load",
    [
        ("m.urdf", GOOD_URDF, mindyn.load),
        ("m.yaml", GOOD_YAML, mindyn.load),
        ("m.csv", GOOD_CSV, lambda p: read_csv(p, filter="none")),
    ],
)
def test_mutated_files_load_or_fail_with_our_error(tmp_path, name, good, load):
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    path = tmp_path / name
    _outcome_is_ours(write(tmp_path, name, good), load)  # the unmutated file loads

    @settings(
        max_examples=150,
        deadline=2000,
        derandomize=True,
        database=None,
        suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
    )
    @given(st.data())
    def check(data):
        path.write_bytes(_mutate(good, data).encode("utf-8", "surrogateescape"))
        _outcome_is_ours(path, load)

    check()


# --------------------------------------------------------------------------------------------
# rotor inertia and friction are >= 0 wherever a robot gets them
# --------------------------------------------------------------------------------------------
NEGATIVE_TERMS = [
    ("r.yaml", ("{name: a,", "{name: a, rotor_inertia: -0.5,"), r"'rotor_inertia' is -0.5"),
    ("r.yaml", ("{name: b,", "{name: b, friction: {viscous: -1},"), r"'viscous' is -1"),
    ("r.yaml", ("{name: b,", "{name: b, friction: {coulomb: -0.2},"), r"'coulomb' is -0.2"),
    ("r.urdf", '<dynamics damping="-0.5"/>', r'damping="-0.5".*: friction cannot be negative'),
    ("r.urdf", '<dynamics friction="-0.1"/>', r'friction="-0.1".*: friction cannot be negative'),
    ("r.xml", 'damping="-1"', r"joint 'j1' \(body 'l1'\) has damping=-1.0"),
    ("r.xml", 'armature="-0.001"', r"joint 'j1' \(body 'l1'\) has armature=-0.001"),
    ("r.xml", 'frictionloss="-0.2"', r"joint 'j1' \(body 'l1'\) has frictionloss=-0.2"),
]


def _description(name: str, item: str) -> str:
    """A two-joint URDF or MJCF whose first joint carries ``item``."""
    if name.endswith(".urdf"):
        return urdf(
            joint("j1", "base", "l1", extra=item) + joint("j2", "l1", "l2"),
            link("l1") + link("l2"),
        )
    return (
        '<mujoco><worldbody><body name="l1"><joint name="j1" type="hinge" axis="0 0 1" '
        f'{item}/><geom type="sphere" size="0.1" mass="1"/><body name="l2" pos="0.3 0 0">'
        '<joint name="j2" type="hinge" axis="0 0 1"/><geom type="sphere" size="0.1" mass="1"/>'
        "</body></body></worldbody></mujoco>"
    )


@pytest.mark.parametrize("name, change, match", NEGATIVE_TERMS)
def test_negative_rotor_inertia_or_friction_in_a_description_is_refused(
    tmp_path, name, change, match
):
    """A negative damping, friction, armature or rotor inertia loaded silently from a URDF,
    YAML table or MJCF (MuJoCo compiles them too); joint-terms files and with_joint_terms
    refused them. Now every description refuses them in one line naming the file (and the
    entry); zero loads."""
    if name.endswith(".yaml"):
        text = GOOD_YAML.replace(*change)
        zero = GOOD_YAML.replace(change[0], re.sub(r"-[0-9.]+", "0", change[1]))
    else:
        negative = re.search(r"-[0-9.]+", change).group(0)
        text, zero = _description(name, change), _description(name, change.replace(negative, "0"))
    path = write(tmp_path, name, text)
    with pytest.raises(mindyn.ModelError, match=match) as e:
        mindyn.load(path)
    assert str(e.value).startswith(str(path)) and "\n" not in str(e.value)
    assert np.all(mindyn.load(write(tmp_path, "zero" + path.suffix, zero)).viscous == 0)


def test_yaml_negative_term_error_names_its_line_and_column(tmp_path):
    path = write(tmp_path, "r.yaml", GOOD_YAML.replace("{name: b,", "{name: b, rotor_inertia: -2,"))
    with pytest.raises(mindyn.ModelError) as e:
        mindyn.load(path)
    line, column = map(int, re.search(r"r\.yaml:(\d+):(\d+): ", str(e.value)).groups())
    assert path.read_text().splitlines()[line - 1][column - 1 :].startswith("-2,")
    assert "joint 2 ('b'): 'rotor_inertia' is -2; rotor inertia and friction are >= 0" in str(
        e.value
    )


@pytest.mark.parametrize("name", ["rotor_inertia", "viscous", "coulomb"])
def test_robot_drive_terms_refuse_negative_values(name):
    robot = mindyn.load("planar3")
    with pytest.raises(mindyn.ArgumentError, match=rf"{name} has -0.5 at entry 2; .* >= 0"):
        setattr(robot, name, [0.1, -0.5, 0.2])
    setattr(robot, name, [0.1, 0.0, 0.2])
    assert list(getattr(robot, name)) == [0.1, 0.0, 0.2]


def test_export_refuses_a_negative_friction_estimate(tmp_path):
    """An unconstrained estimate may hold a negative viscous friction; a URDF written with it
    would not load (a description's friction is >= 0): export refuses it, naming it."""
    from mindyn.export import write_urdf

    robot = mindyn.load(write(tmp_path, "r.urdf", GOOD_URDF))
    names = robot.parameter_names(friction=True)
    p = robot.parameters(friction=True).copy()
    p[names.index("Fv2")] = -0.05
    with pytest.raises(mindyn.ModelError, match=r"Fv2 = -0.05 is negative; .* consistent=True"):
        write_urdf(robot, p, tmp_path / "out.urdf")
    assert not (tmp_path / "out.urdf").exists()
    p[names.index("Fv2")] = 0.05
    write_urdf(robot, p, tmp_path / "out.urdf")
    assert mindyn.load(tmp_path / "out.urdf").viscous[1] == pytest.approx(0.05, rel=1e-15)


def test_yaml_joint_names_must_be_unique(tmp_path):
    """Two YAML joints of one name loaded (a URDF's are refused), and a transmission naming it
    then failed with a message that hid the cause."""
    path = write(tmp_path, "r.yaml", GOOD_YAML.replace("{name: b,", "{name: a,"))
    with pytest.raises(
        mindyn.ModelError,
        match=r"r\.yaml:5:12: joint 2: the name 'a' is joint 1's too; joint names must be unique",
    ):
        mindyn.load(path)


def _rigid(p) -> bool:
    """Whether 10 inertial parameters are a rigid body's, by its mass and principal moments
    about the centre of mass (each >= 0, each at most the sum of the other two)."""
    m, h = p[9], np.asarray(p[6:9])
    io = np.array([[p[0], p[1], p[2]], [p[1], p[3], p[4]], [p[2], p[4], p[5]]])
    if m < 0 or (m == 0 and np.any(h)):
        return False
    c = h / m if m > 0 else np.zeros(3)
    lam = np.linalg.eigvalsh(io - m * (c @ c * np.eye(3) - np.outer(c, c)))
    tol = 1e-9 * max(1.0, abs(lam).max())
    return bool(lam[0] >= -tol and 2 * lam.max() <= lam.sum() + tol)


@pytest.mark.parametrize("robot", ["puma560", "zcr07s", "stanford", "planar3", "r.urdf"])
def test_info_names_links_no_rigid_body_has(tmp_path, robot):
    """A link whose inertia breaks the triangle inequality loaded without a word; info now
    names every such link, the links a test of mass and principal moments finds."""
    if robot == "r.urdf":  # l2: izz beyond ixx + iyy
        good = link("l2", 0.5)
        text = GOOD_URDF.replace(good, good.replace('izz="0.01"', 'izz="0.5"'))
        robot = str(write(tmp_path, "r.urdf", text))
    r = mindyn.load(robot)
    expected = [
        r.link_names[k + 1] for k, p in enumerate(r.params.reshape(r.n, 10)) if not _rigid(p)
    ]
    out = run_cli("info", robot)
    assert out.returncode == 0, out.stderr
    lines = [ln for ln in out.stdout.splitlines() if "not a rigid body's" in ln]
    if robot.endswith("r.urdf"):
        assert expected == ["l2"]
    if expected:
        assert lines, out.stdout
        assert re.findall(r"'([^']+)'", lines[0].split(": ", 1)[1]) == expected
    else:
        assert not lines
