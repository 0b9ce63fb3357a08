"""Patterns of published MJCF files (MuJoCo Menagerie's arms and humanoids), each reproduced in
a small file written here: effort limits given by the actuators (``forcerange`` and ``gear``,
or a motor's ``ctrlrange``), a floating-base model written back by an identification that has
no rotor inertia or friction, and files that ``<include>`` files with assets written to
another folder.

The references are MuJoCo's own: the actuator force it applies on each joint with the
controls at their extremes (``qfrc_actuator``), its compiled model and the file it compiles.
"""

from __future__ import annotations

import mindyn
import numpy as np
import pytest
from mindyn.mjcf import write_mjcf

mujoco = pytest.importorskip("mujoco", reason="the 'mujoco' wheel is not installed")


def _chain(joints: str, actuators: str, tendons: str = "", compiler: str = "") -> str:
    """An MJCF of hinges j1.. on a chain, one per ``<joint .../>`` line of ``joints``."""
    lines = [line.strip() for line in joints.strip().splitlines()]
    body = ""
    for k, joint in enumerate(lines, start=1):
        named = joint.replace("<joint ", f'<joint name="j{k}" ')
        body += (
            f'<body name="l{k}" pos="0 0 0.1"><inertial mass="1" pos="0.05 0 0" '
            f'diaginertia="0.01 0.02 0.03"/>{named}'
        )
    body += "</body>" * len(lines)
    return (
        f'<mujoco model="arm"><compiler angle="radian" {compiler}/>'
        f"<worldbody>{body}</worldbody>{tendons}<actuator>{actuators}</actuator></mujoco>"
    )


EFFORTS = _chain(
    """
    <joint axis="0 0 1"/>
    <joint axis="0 1 0" actuatorfrcrange="-120 120"/>
    <joint axis="0 1 0"/>
    <joint axis="1 0 0"/>
    <joint axis="0 1 0" actuatorfrcrange="-20 25"/>
    <joint axis="0 0 1"/>
    <joint axis="0 0 1" actuatorfrcrange="-30 50"/>
    <joint axis="0 1 0"/>
    """,
    # j1: forcerange (autolimits) times gear, asymmetric: the bound reached both ways
    '<general joint="j1" gear="2" forcerange="-80 100" gainprm="1" biastype="none"/>'
    # j2: a position actuator's forcerange with a negative gear, and the joint's own range
    '<position joint="j2" kp="100" gear="-3" forcerange="-50 50"/>'
    # j3: a position actuator without forcerange: no bound
    '<position joint="j3" kp="100"/>'
    # j4: a motor bounded by its ctrlrange (force = ctrl)
    '<motor joint="j4" gear="10" ctrlrange="-2 2.5"/>'
    # j5: two motors whose forces add, clamped by the joint's actuatorfrcrange
    '<motor joint="j5" gear="1" forcerange="-10 10"/>'
    '<motor joint="j5" gear="2" ctrlrange="-9 9" forcerange="-12 12"/>'
    # j6: a joint motor and a tendon actuator over it: no per-joint bound from them
    '<motor joint="j6" forcerange="-5 5"/>'
    '<motor tendon="t" forcerange="-5 5"/>',
    # j7: no actuator, its own asymmetric actuatorfrcrange; j8: none at all
    tendons='<tendon><fixed name="t"><joint joint="j6" coef="1"/><joint joint="j8" coef="0.5"/>'
    "</fixed></tendon>",
    compiler='autolimits="true"',
)


def _mujoco_efforts(m) -> np.ndarray:
    """The actuator force MuJoCo applies on each joint with every control at its extreme, the
    smaller of the two directions (a huge value where nothing bounds it): ``qfrc_actuator``
    at q = 0 with each actuator's control at +-1e9 times the sign of its gear."""
    d = mujoco.MjData(m)
    reached = []
    for sign in (1.0, -1.0):
        d.qpos[:] = 0
        d.ctrl[:] = sign * 1e9 * np.sign(np.asarray(m.actuator_gear)[:, 0])
        mujoco.mj_forward(m, d)
        reached.append(np.abs(np.asarray(d.qfrc_actuator)))
    return np.minimum(*reached)[np.asarray(m.jnt_dofadr)]


def test_effort_limits_come_from_the_actuators_as_mujoco_applies_them(tmp_path):
    """A joint's effort limit is the force its actuators through a joint transmission can
    apply in both directions (|gear| times the bound of ``forcerange``, or of a motor's
    ``ctrlrange``; summed over several actuators), clamped by the joint's own
    ``actuatorfrcrange``: what MuJoCo's ``qfrc_actuator`` reaches with the controls at their
    extremes. A joint something leaves unbounded (a position actuator without ``forcerange``,
    a tendon actuator over it) or without actuators and ``actuatorfrcrange`` has none."""
    path = tmp_path / "arm.xml"
    path.write_text(EFFORTS, encoding="utf-8")
    m = mujoco.MjModel.from_xml_path(str(path))
    robot = mindyn.load(path)
    effort = np.asarray(robot.limits["effort"], dtype=float)
    # the compiled numbers, by the rule
    gear = np.abs(np.asarray(m.actuator_gear)[:, 0])
    force = np.asarray(m.actuator_forcerange)
    assert bool(m.actuator_forcelimited[0]) and not m.actuator_forcelimited[2]
    assert effort[0] == pytest.approx(gear[0] * min(-force[0, 0], force[0, 1]))  # 2 * 80
    assert effort[1] == pytest.approx(min(gear[1] * force[1, 1], m.jnt_actfrcrange[1, 1]))  # 120
    assert effort[3] == pytest.approx(gear[3] * 2.0)  # the ctrlrange's smaller side
    assert effort[4] == pytest.approx(20.0)  # 10 + 2 * 9, clamped by the joint's -20 .. 25
    assert effort[6] == pytest.approx(30.0)
    assert np.all(np.isnan(effort[[2, 5, 7]]))  # no effort limit
    np.testing.assert_allclose(effort, [160, 120, np.nan, 20, 20, np.nan, 30, np.nan])
    # MuJoCo's own forces at the extremes: the same on the joints bounded by actuators (j7,
    # without any, reaches none)
    reached = _mujoco_efforts(m)
    bounded = np.isfinite(effort) & (np.arange(8) != 6)
    np.testing.assert_allclose(effort[bounded], reached[bounded], rtol=1e-12)
    # j5 without the joint's clamp: the sum of its two actuators
    assert reached[4] == pytest.approx(20.0)
    unclamped = EFFORTS.replace('actuatorfrcrange="-20 25"', "")
    path.write_text(unclamped, encoding="utf-8")
    m = mujoco.MjModel.from_xml_path(str(path))
    assert mindyn.load(path).limits["effort"][4] == pytest.approx(_mujoco_efforts(m)[4]) == 28.0
    # the position actuator without forcerange really is unbounded in MuJoCo
    assert reached[2] > 1e6


# a humanoid's pattern: a floating pelvis, hinges whose armature comes from a default class,
# damping and frictionloss on some, a fixed tendon over one joint carrying damping
FLOATING = """<mujoco model="biped">
  <compiler angle="radian" autolimits="true"/>
  <default><joint armature="0.01" damping="0.2"/></default>
  <worldbody>
    <body name="pelvis" pos="0 0 0.8">
      <freejoint name="root"/>
      <inertial mass="5" pos="0 0 0" diaginertia="0.05 0.04 0.03"/>
      <body name="thigh" pos="0 0.1 -0.1">
        <joint name="hip" axis="0 1 0" range="-2 2" frictionloss="0.3"/>
        <inertial mass="2" pos="0 0 -0.15" diaginertia="0.02 0.02 0.005"/>
        <body name="shin" pos="0 0 -0.3">
          <joint name="knee" axis="0 1 0" range="0 2.5" armature="0.02"/>
          <inertial mass="1.5" pos="0 0 -0.15" diaginertia="0.015 0.015 0.003"/>
        </body>
      </body>
    </body>
  </worldbody>
  <tendon><fixed name="knee_damper" damping="0.5"><joint joint="knee" coef="2"/></fixed></tendon>
</mujoco>
"""


def _drive_terms(m) -> np.ndarray:
    """MuJoCo's armature, damping and frictionloss per dof, with the tendon's."""
    return np.array(
        [m.dof_armature, m.dof_damping, m.dof_frictionloss, [m.tendon_damping[0]] * m.nv]
    )


@pytest.mark.filterwarnings("ignore:.*floating.*:UserWarning")
def test_a_floating_base_written_back_keeps_the_files_own_armature_and_friction(tmp_path):
    """An identification of a floating-base robot has no rotor inertia or friction (its
    dynamics have none): written back, the file keeps its own ``armature``, ``damping`` and
    ``frictionloss`` (from default classes, the joints and the tendon over one joint), as
    MuJoCo compiles both files, and a note says so; the inertias are the ones identified.
    With the terms given, they are written."""
    src = tmp_path / "biped.xml"
    src.write_text(FLOATING, encoding="utf-8")
    robot = mindyn.load(src)
    p = robot.parameters()  # inertial only
    p[10:20] *= 1.2  # the thigh identified heavier
    out = tmp_path / "out" / "biped_id.xml"
    res = write_mjcf(robot, p, out)
    a, b = mujoco.MjModel.from_xml_path(str(src)), mujoco.MjModel.from_xml_path(str(out))
    np.testing.assert_array_equal(_drive_terms(b), _drive_terms(a))
    assert b.dof_armature[6] == 0.01 and b.dof_frictionloss[6] == 0.3  # the hip's, kept
    for key in ("armature", "damping", "frictionloss"):
        assert any(f"file's own {key} is kept" in n for n in res.notes), (key, res.notes)
    assert b.body_mass[2] == pytest.approx(1.2 * a.body_mass[2], rel=1e-12)
    # with the rotor inertia identified: written on the hinges, the friction still kept
    q = dict(zip(robot.parameter_names(rotor=True), robot.parameters(rotor=True)))
    q.update(Ia1=0.0, Ia2=0.05, Ia3=0.07)  # the free joint's none, then hip and knee
    res = write_mjcf(robot, q, out)
    b = mujoco.MjModel.from_xml_path(str(out))
    np.testing.assert_array_equal(b.dof_armature[6:], [0.05, 0.07])
    np.testing.assert_array_equal(_drive_terms(b)[1:], _drive_terms(a)[1:])
    assert not any("armature is kept" in n for n in res.notes), res.notes


def test_a_new_mjcf_says_it_writes_zero_where_the_description_has_friction(tmp_path):
    """A new MJCF (from a URDF) of parameters without friction writes ``damping`` and
    ``frictionloss`` 0, and says so when the description has friction."""
    urdf = tmp_path / "one.urdf"
    urdf.write_text(
        '<robot name="one"><link name="base"/><link name="arm"><inertial><origin xyz="0.1 0 0"/>'
        '<mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.03"/>'
        '</inertial></link><joint name="j" type="revolute"><parent link="base"/>'
        '<child link="arm"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="5" '
        'velocity="2"/><dynamics damping="0.4" friction="0.1"/></joint></robot>',
        encoding="utf-8",
    )
    robot = mindyn.load(urdf)
    out = tmp_path / "one.xml"
    res = write_mjcf(robot, robot.parameters(), out)
    m = mujoco.MjModel.from_xml_path(str(out))
    assert (m.dof_damping[0], m.dof_frictionloss[0]) == (0.0, 0.0)
    said = [n for n in res.notes if "0 is written on every joint" in n]
    assert [n.split(":")[1].split()[0] for n in said] == ["damping", "frictionloss"], res.notes
    res = write_mjcf(robot, robot.parameters(friction=True), out)
    assert not any("0 is written" in n for n in res.notes)
    assert mujoco.MjModel.from_xml_path(str(out)).dof_damping[0] == 0.4


OBJ = "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
INCLUDING = """<mujoco model="including">
  <include file="parts/meshes.xml"/>
  <include file="parts/outer.xml"/>
  <include file="parts/colours.xml"/>
  <worldbody>
    <body name="link">
      <inertial mass="1" pos="0 0 0.05" diaginertia="0.01 0.01 0.01"/>
      <joint name="j" axis="0 0 1"/>
      <geom type="mesh" mesh="shell" material="blue" contype="0" conaffinity="0"/>
      <geom type="mesh" mesh="lid" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
</mujoco>
"""


def test_included_files_with_assets_are_written_into_a_file_moved_to_another_folder(tmp_path):
    """MuJoCo reads the relative paths inside an included file from the main file's folder:
    written to another folder with only its ``<include>`` paths rewritten, a file including
    files with assets no longer compiles (shown first). Written back elsewhere, the included
    files holding paths (one naming a mesh, one including another that does) are written into
    the file with those paths rewritten, and MuJoCo compiles it to the same meshes; an
    included file without paths stays an include."""
    src = tmp_path / "robot"
    (src / "parts").mkdir(parents=True)
    (src / "meshes").mkdir()
    (src / "meshes" / "shell.obj").write_text(OBJ)
    (src / "meshes" / "lid.obj").write_text(OBJ.replace("0.1", "0.2"))
    (src / "parts" / "meshes.xml").write_text(
        '<mujoco><asset><mesh name="shell" file="meshes/shell.obj"/></asset></mujoco>'
    )
    (src / "parts" / "outer.xml").write_text('<mujoco><include file="parts/inner.xml"/></mujoco>')
    (src / "parts" / "inner.xml").write_text(
        '<mujoco><asset><mesh name="lid" file="meshes/lid.obj"/></asset></mujoco>'
    )
    (src / "parts" / "colours.xml").write_text(
        '<mujoco><asset><material name="blue" rgba="0 0 1 1"/></asset></mujoco>'
    )
    path = src / "robot.xml"
    path.write_text(INCLUDING, encoding="utf-8")
    a = mujoco.MjModel.from_xml_path(str(path))
    out = tmp_path / "out" / "robot_id.xml"
    out.parent.mkdir()
    # the includes alone moved: MuJoCo looks for the nested include and meshes from there
    out.write_text(INCLUDING.replace('file="parts/', 'file="../robot/parts/'), encoding="utf-8")
    with pytest.raises(ValueError, match=r"Error opening file .*(inner\.xml|shell\.obj)"):
        mujoco.MjModel.from_xml_path(str(out))
    robot = mindyn.load(path)
    res = write_mjcf(robot, robot.parameters(), out)
    b = mujoco.MjModel.from_xml_path(str(out))
    assert (b.nmesh, b.nmat) == (a.nmesh, a.nmat) == (2, 1)
    np.testing.assert_array_equal(b.mesh_vert, a.mesh_vert)
    text = out.read_text()
    assert 'file="../robot/meshes/shell.obj"' in text and 'file="../robot/meshes/lid.obj"' in text
    assert '<include file="../robot/parts/colours.xml"' in text
    assert "parts/meshes.xml" not in text.replace('<include file="parts/meshes.xml">', "")
    said = [n for n in res.notes if "written into the file" in n]
    assert said and all(f"'parts/{x}.xml'" in said[0] for x in ("meshes", "outer", "inner"))
    # written into its own folder, nothing moves
    res = write_mjcf(robot, robot.parameters(), src / "robot_id.xml")
    assert '<include file="parts/meshes.xml"/>' in (src / "robot_id.xml").read_text()
    assert not any("written into the file" in n for n in res.notes)
