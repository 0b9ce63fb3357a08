"""Patterns of published MJCF arm files, each reproduced in a small file written here: an arm
whose gripper has what the model cannot hold (a joint equality coupling the fingers, a finger
spring, a tendon with damping) loaded as the chain to a tip link, and an
MJCF with meshes and textures in folders written back to another folder.

The references are MuJoCo's own ``mj_inverse`` and ``mj_fullM`` on the same file, with the
joints off the chain held where the model locks them (q = 0 clamped into their range) and the
constraints, limits and contacts disabled (no dynamics of the model).
"""

from __future__ import annotations

import struct
import zlib

import mindyn
import numpy as np
import pytest
from conftest import assert_close
from mindyn.mjcf import write_mjcf

mujoco = pytest.importorskip("mujoco", reason="the 'mujoco' wheel is not installed")

_OLD = tuple(int(x) for x in mujoco.__version__.split(".")[:2]) < (3, 14)
TOL = 1e-5 if _OLD else 1e-9
OFF = (
    mujoco.mjtDisableBit.mjDSBL_FRICTIONLOSS
    | mujoco.mjtDisableBit.mjDSBL_LIMIT
    | mujoco.mjtDisableBit.mjDSBL_CONTACT
    | mujoco.mjtDisableBit.mjDSBL_EQUALITY
)

# a three-joint arm with a two-finger gripper as published arm files have it: the fingers
# coupled by a joint equality, one with a spring, a tendon with damping over both, the fingers'
# range not holding 0
GRIPPER_ARM = """<mujoco model="gripper_arm">
  <compiler angle="radian" autolimits="true"/>
  <default>
    <joint armature="0.1" damping="0.5" frictionloss="0.2"/>
    <default class="finger"><joint type="slide" axis="0 1 0" armature="0.01"/></default>
  </default>
  <worldbody>
    <body name="base">
      <inertial mass="2" pos="0 0 0.05" diaginertia="0.01 0.01 0.01"/>
      <body name="upper" pos="0 0 0.2">
        <inertial mass="1.5" pos="0.01 0.02 0.1" fullinertia="0.03 0.03 0.02 0.001 0.002 0.003"/>
        <joint name="j1" axis="0 0 1" range="-3 3"/>
        <body name="fore" pos="0 0.05 0.3" quat="0.9 0.3 0.1 0.2">
          <inertial mass="1.2" pos="0.1 0 0.02" diaginertia="0.01 0.02 0.015"/>
          <joint name="j2" axis="0 1 0" pos="0.01 0 0" range="-2 2"/>
          <body name="palm" pos="0.25 0 0">
            <inertial mass="0.6" pos="0.03 0.01 0" diaginertia="0.002 0.003 0.004"/>
            <joint name="j3" axis="1 0 0" range="-3 3"/>
            <body name="left" pos="0.08 0 0">
              <inertial mass="0.05" pos="0.01 0 0" diaginertia="1e-5 2e-5 3e-5"/>
              <joint name="f1" class="finger" range="0.01 0.04" stiffness="20"/>
            </body>
            <body name="right" pos="0.08 0 0">
              <inertial mass="0.07" pos="0.01 0.002 0" diaginertia="2e-5 2e-5 3e-5"/>
              <joint name="f2" class="finger" range="-0.04 -0.01"/>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <tendon>
    <fixed name="split" damping="3">
      <joint joint="f1" coef="0.5"/><joint joint="f2" coef="-0.5"/>
    </fixed>
  </tendon>
  <equality>
    <joint name="fingers" joint1="f1" joint2="f2" polycoef="0 -1 0 0 0"/>
  </equality>
</mujoco>
"""


def full_mass_matrix(m, d) -> np.ndarray:
    full = np.zeros((m.nv, m.nv))
    if hasattr(d, "qM"):  # MuJoCo 3
        mujoco.mj_fullM(m, full, d.qM)
    else:  # MuJoCo 4: mj_fullM(m, d, dst)
        mujoco.mj_fullM(m, d, full)
    return full


def locked_qpos(m) -> np.ndarray:
    """MuJoCo's qpos with every hinge and slide at 0 clamped into its range: where the model
    of a chain locks the joints off it."""
    qpos = np.array(m.qpos0)
    for j in range(m.njnt):
        if m.jnt_limited[j]:
            a = int(m.jnt_qposadr[j])
            qpos[a] = min(max(qpos[a], m.jnt_range[j][0]), m.jnt_range[j][1])
    return qpos


def test_an_arm_is_read_to_a_tip_link_without_its_grippers_coupling(tmp_path):
    """The whole file is refused in one line naming the first element the model cannot hold
    and saying that a chain to a tip link leaves the joints off it out; loaded to the palm,
    the arm's inverse dynamics and mass matrix (armature in) are MuJoCo's on the same file,
    the fingers held where the model locks them (0 clamped into their range: 0.01 and
    -0.01 m), whose spring, equality and tendon then act on nothing that moves."""
    path = tmp_path / "arm.xml"
    path.write_text(GRIPPER_ARM, encoding="utf-8")
    with pytest.raises(mindyn.ModelError) as e:
        mindyn.load(path)
    said = str(e.value)
    assert "\n" not in said
    assert "joint 'f1' (body 'left') has a spring (stiffness 20.0)" in said
    assert "tip=" in said
    # without the spring, the equality is what stops the whole file: named as written
    path.write_text(GRIPPER_ARM.replace(' stiffness="20"', ""), encoding="utf-8")
    with pytest.raises(mindyn.ModelError) as e:
        mindyn.load(path)
    assert 'equality \'fingers\' <joint joint1="f1" joint2="f2">' in str(e.value)
    path.write_text(GRIPPER_ARM, encoding="utf-8")
    robot = mindyn.load(path, tip="palm")
    assert robot.joint_names == ["j1", "j2", "j3"] and robot.transmission is None
    assert robot.rotor_inertia.tolist() == [0.1] * 3
    m = mujoco.MjModel.from_xml_path(str(path))
    m.opt.disableflags = int(OFF)
    d = mujoco.MjData(m)
    dof = [int(m.jnt_dofadr[m.joint(n).id]) for n in robot.joint_names]
    adr = [int(m.jnt_qposadr[m.joint(n).id]) for n in robot.joint_names]
    params = robot.parameters(rotor=True, friction=True)
    fc = robot.coulomb
    rng = np.random.default_rng(4)
    for _ in range(4):
        q, dq, ddq = rng.uniform(-2, 2, (3, 3))
        d.qpos[:], d.qvel[:], d.qacc[:] = locked_qpos(m), 0.0, 0.0
        d.qpos[adr], d.qvel[dof], d.qacc[dof] = q, dq, ddq
        mujoco.mj_inverse(m, d)
        got = robot.inverse_dynamics(q, dq, ddq, params)
        assert_close(got, d.qfrc_inverse[dof] + fc * np.sign(dq), TOL, "arm to a tip vs mj_inverse")
        mujoco.mj_forward(m, d)
        full = full_mass_matrix(m, d)[np.ix_(dof, dof)]
        mass = robot.mass_matrix(q) + np.diag(robot.rotor_inertia)
        assert_close(mass, full, TOL, "arm to a tip vs mj_fullM")


_EQUALITY = '<joint name="fingers" joint1="f1" joint2="f2" polycoef="0 -1 0 0 0"/>'
_SPRING = 'range="0.01 0.04" stiffness="20"'


@pytest.mark.parametrize(
    "old, new, said",
    [
        # a coupling that moves a joint of the chain is refused with a tip too, named
        (
            _EQUALITY,
            _EQUALITY + '\n    <connect body1="palm" anchor="0 0 0"/>',
            'equality 1 <connect body1="palm" body2="world">: closed chains',
        ),
        # a reference position of a joint off the chain changes where it is locked
        (_SPRING, _SPRING + ' ref="0.02"', "joint 'f1' (body 'left') has ref=0.02 m"),
        # gravity compensation of a finger acts on the palm it is locked to
        (
            '<body name="right" pos="0.08 0 0">',
            '<body name="right" pos="0.08 0 0" gravcomp="1">',
            "body 'right' has gravcomp=1.0",
        ),
    ],
    ids=["connect_to_world", "reference_off_the_chain", "gravcomp_off_the_chain"],
)
def test_what_reaches_the_chain_is_still_refused_by_name(old, new, said, tmp_path):
    path = tmp_path / "arm.xml"
    path.write_text(GRIPPER_ARM.replace(old, new), encoding="utf-8")
    with pytest.raises(mindyn.ModelError) as e:
        mindyn.load(path, tip="palm")
    assert said in str(e.value) and "\n" not in str(e.value)


def _png(width: int = 2, height: int = 2) -> bytes:
    """A small grey RGB PNG."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (
            struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
        )

    rows = b"".join(b"\0" + b"\x80" * (3 * width) for _ in range(height))
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(rows))
        + chunk(b"IEND", b"")
    )


MESHED = """<mujoco model="meshed">
  <compiler angle="radian" meshdir="assets" autolimits="true"/>
  <include file="parts/materials.xml"/>
  <asset>
    <mesh name="shell" file="shell.obj"/>
    <texture name="grey" type="2d" file="grey.png"/>
  </asset>
  <worldbody>
    <body name="link1" pos="0 0 0.1">
      <inertial mass="1.5" pos="0.01 0.02 0.1" diaginertia="0.02 0.03 0.01"/>
      <joint name="j1" axis="0 0 1" range="-3 3" armature="0.05"/>
      <geom type="mesh" mesh="shell" material="painted" contype="0" conaffinity="0"/>
      <body name="link2" pos="0.3 0 0">
        <inertial mass="0.8" pos="0.1 0 0" diaginertia="0.01 0.02 0.015"/>
        <joint name="j2" axis="0 1 0" range="-2 2"/>
        <geom type="mesh" mesh="shell" contype="0" conaffinity="0"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def test_an_mjcf_written_back_to_another_folder_finds_its_meshes_textures_and_includes(tmp_path):
    """A file whose meshes are in its ``meshdir``, whose texture is beside it (no
    ``texturedir``) and which includes a file by a relative path, written back elsewhere (as
    ``identify --mjcf out/...`` does): MuJoCo reads those paths relative to the model file's
    folder, so they are rewritten to the same files seen from the new folder (a note says
    so); MuJoCo compiles the file written with the same meshes and texture and the parameters
    written. Written into its own folder, the paths stay as they were."""
    src = tmp_path / "robot"
    (src / "assets").mkdir(parents=True)
    (src / "parts").mkdir()
    vertices = [(0, 0, 0), (0.1, 0, 0), (0, 0.1, 0), (0, 0, 0.1)]
    faces = [(1, 3, 2), (1, 2, 4), (1, 4, 3), (2, 3, 4)]
    (src / "assets" / "shell.obj").write_text(
        "".join(f"v {x} {y} {z}\n" for x, y, z in vertices)
        + "".join(f"f {a} {b} {c}\n" for a, b, c in faces)
    )
    (src / "grey.png").write_bytes(_png())
    (src / "parts" / "materials.xml").write_text(
        '<mujoco><asset><material name="painted" rgba="0.2 0.4 0.6 1"/></asset></mujoco>'
    )
    path = src / "robot.xml"
    path.write_text(MESHED, encoding="utf-8")
    robot = mindyn.load(path)
    p = robot.parameters(rotor=True, friction=True)
    p[:10] *= 1.1  # link 1 identified heavier
    out = tmp_path / "out" / "deeper" / "robot_id.xml"
    res = write_mjcf(robot, p, out)
    assert any("3 relative path(s)" in n and "rewritten" in n for n in res.notes), res.notes
    text = out.read_text()
    assert 'meshdir="../../robot/assets"' in text
    assert 'file="../../robot/parts/materials.xml"' in text
    assert 'file="../../robot/grey.png"' in text
    a, b = mujoco.MjModel.from_xml_path(str(path)), mujoco.MjModel.from_xml_path(str(out))
    assert (b.nmesh, b.ntex, b.nmat) == (a.nmesh, a.ntex, a.nmat) == (1, 1, 1)
    np.testing.assert_array_equal(b.mesh_vert, a.mesh_vert)
    again = mindyn.load(out)
    assert_close(again.parameters(rotor=True, friction=True), p, 1e-12, "meshed MJCF moved")
    # into its own folder: nothing to rewrite
    res = write_mjcf(robot, p, src / "robot_id.xml")
    assert not any("relative path" in n for n in res.notes)
    assert 'meshdir="assets"' in (src / "robot_id.xml").read_text()
