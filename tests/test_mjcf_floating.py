"""MuJoCo MJCF in and out for a floating base (a free joint on the root body) and ball joints.

MuJoCo's free joint and mindyn's floating joint (Pinocchio's free-flyer) have other
coordinates. The map is written here from MuJoCo's definitions, not taken from the library, and
checked on its own against finite differences of ``mj_integratePos``:

- ``qpos = (p, w, x, y, z)``, mindyn's ``q = (p, x, y, z, w)``: the body's position and
  orientation in the world;
- ``qvel = (R v, w)`` for mindyn's ``v = (v, w)``: MuJoCo's linear velocity is the body
  origin's in the world axes, mindyn's in the body's; the angular velocity is in the body's
  axes in both;
- so ``qacc = (R (a + w x v), dw)`` (the derivative of ``R v``) and the generalised forces,
  dual to the velocities, ``qfrc = (R f, t)``;
- a ball joint: ``qpos = (w, x, y, z)``, mindyn's ``q = (x, y, z, w)``; the velocity is the
  angular velocity in the body's axes in both (Pinocchio's spherical joint's).

The references: MuJoCo's ``mj_inverse`` (no contacts, no limits, gravity on), Pinocchio's
``rnea`` on a free-flyer (whose coordinates are mindyn's) and the base regressor ``W_b`` times
the base parameters.
"""

from __future__ import annotations

import re
import warnings

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import ROBOTS_DIR, assert_close, cli, set_pinocchio_params
from mindyn.mjcf import write_mjcf
from test_mjcf import REPO_UR5, ROUND_TRIP, TOL, full_mass_matrix, physical_params
from test_multibody import pin_q, random_state

mujoco = pytest.importorskip("mujoco", reason="the 'mujoco' wheel is not installed")

SOLO = ROBOTS_DIR / "solo_description/robots/solo12.urdf"
NO_CONTACT = mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_LIMIT
FLOATING = {"solo12": SOLO, "ur5_example": REPO_UR5}


# -- the two conventions, from MuJoCo's definitions ---------------------------------------------
def rotation(quat_wxyz) -> np.ndarray:
    out = np.zeros(9)
    mujoco.mju_quat2Mat(out, np.asarray(quat_wxyz, dtype=float))
    return out.reshape(3, 3)


def to_mujoco(m, robot, q, v, a):
    """MuJoCo's ``qpos, qvel, qacc`` of mindyn's ``q, v, a`` (joints matched by name)."""
    qpos, qvel, qacc = np.zeros(m.nq), np.zeros(m.nv), np.zeros(m.nv)
    iq = iv = 0
    for kind, name in zip(robot.joint_types, robot.joint_names, strict=True):
        j = m.joint(name).id
        adr, dof = int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j])
        if kind == "floating":
            assert int(m.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_FREE)
            p, (x, y, z, w) = q[iq : iq + 3], q[iq + 3 : iq + 7]
            R = rotation([w, x, y, z])
            lin, ang = v[iv : iv + 3], v[iv + 3 : iv + 6]
            qpos[adr : adr + 7] = [*p, w, x, y, z]
            qvel[dof : dof + 6] = [*(R @ lin), *ang]
            qacc[dof : dof + 6] = [
                *(R @ (a[iv : iv + 3] + np.cross(ang, lin))),
                *a[iv + 3 : iv + 6],
            ]
            iq, iv = iq + 7, iv + 6
        elif kind == "spherical":
            assert int(m.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_BALL)
            x, y, z, w = q[iq : iq + 4]
            qpos[adr : adr + 4] = [w, x, y, z]
            qvel[dof : dof + 3], qacc[dof : dof + 3] = v[iv : iv + 3], a[iv : iv + 3]
            iq, iv = iq + 4, iv + 3
        else:
            assert robot.joint_types.count("floating") <= 1 and kind in ("revolute", "prismatic")
            qpos[adr], qvel[dof], qacc[dof] = q[iq], v[iv], a[iv]
            iq, iv = iq + 1, iv + 1
    return qpos, qvel, qacc


def from_mujoco_force(m, robot, q, qfrc) -> np.ndarray:
    """mindyn's generalised force (order of v) of MuJoCo's ``qfrc`` at mindyn's ``q``."""
    out, iq = [], 0
    for kind, name in zip(robot.joint_types, robot.joint_names, strict=True):
        dof = int(m.jnt_dofadr[m.joint(name).id])
        if kind == "floating":
            x, y, z, w = q[iq + 3 : iq + 7]
            R = rotation([w, x, y, z])
            out += [*(R.T @ qfrc[dof : dof + 3]), *qfrc[dof + 3 : dof + 6]]
            iq += 7
        elif kind == "spherical":
            out += list(qfrc[dof : dof + 3])
            iq += 4
        else:
            out.append(qfrc[dof])
            iq += 1
    return np.array(out)


def mj_inverse(m, robot, q, v, a) -> np.ndarray:
    """MuJoCo's inverse dynamics (contacts and limits off, gravity on) in mindyn's terms."""
    m.opt.disableflags = int(NO_CONTACT)
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:], d.qacc[:] = to_mujoco(m, robot, q, v, a)
    mujoco.mj_inverse(m, d)
    return from_mujoco_force(m, robot, q, d.qfrc_inverse)


def written(name, tmp_path, seed=3):
    """(robot on a free-flyer, random physically consistent parameters, the MJCF written)."""
    robot = mindyn.load(FLOATING[name], root_joint="floating")
    p = physical_params(robot, np.random.default_rng(seed), drive=False)
    res = write_mjcf(robot, p, tmp_path / f"{name}.xml")
    return robot, p, res


# -- MJCF out, read back, against MuJoCo, Pinocchio and the base parameters ---------------------
def test_free_joint_coordinates_are_checked_by_finite_differences(tmp_path):
    """The map above, checked on MuJoCo itself: at mindyn's q the free body's pose (MuJoCo's
    xpos, xmat) and every other body's are mindyn's link poses; stepping MuJoCo's qpos along
    qvel (mj_integratePos, central differences) moves the body origin by R v in the world and
    turns its axes by w in its own axes."""
    robot, _, res = written("ur5_example", tmp_path)
    m = mujoco.MjModel.from_xml_path(str(res.path))
    d = mujoco.MjData(m)
    rng = np.random.default_rng(7)
    h = 1e-6
    for _ in range(3):
        q, v, a = random_state(robot, rng)
        qpos, qvel, _ = to_mujoco(m, robot, q, v, a)
        d.qpos[:] = qpos
        mujoco.mj_kinematics(m, d)
        poses = robot.link_poses(q)
        for k, link in enumerate(robot.link_names[1:]):
            b = m.body(link).id
            assert_close(d.xpos[b], poses[k][:3, 3], 1e-12, f"position of {link}")
            assert_close(d.xmat[b].reshape(3, 3), poses[k][:3, :3], 1e-12, f"axes of {link}")
        ends = []
        for step in (h, -h):
            x = qpos.copy()
            mujoco.mj_integratePos(m, x, qvel, step)
            ends.append(x)
        R = rotation(qpos[3:7])
        dp = (ends[0][:3] - ends[1][:3]) / (2 * h)
        dR = (rotation(ends[0][3:7]) - rotation(ends[1][3:7])) / (2 * h)
        body = R.T @ dR  # [w]x in the body's axes
        assert_close(dp, R @ v[:3], 1e-7, "d/dt position = R v")
        assert_close([body[2, 1], body[0, 2], body[1, 0]], v[3:6], 1e-7, "body angular velocity")
        assert_close((ends[0][7:] - ends[1][7:]) / (2 * h), v[6:], 1e-8, "the hinges' rates")


@pytest.mark.parametrize("name", sorted(FLOATING))
def test_floating_mjcf_round_trip_and_inverse_dynamics(name, tmp_path):
    """Solo12 (a tree) and the example UR5 (a chain) on a free-flyer, random physically
    consistent parameters written as an MJCF: the file has a <freejoint> on the root body and
    no motor on it; read back, the robot has the same joints, links, tree, gravity, link frames
    and parameters; at random states MuJoCo's mj_inverse on the file (coordinates converted as
    in the module's docstring) is mindyn's floating-base inverse dynamics (of the robot and of
    the file read back), Pinocchio's rnea on the URDF with a JointModelFreeFlyer root and the
    base regressor W_b times the base parameters Y p."""
    robot, p, res = written(name, tmp_path)
    text = res.path.read_text()
    assert len(re.findall(r'<freejoint name="root_joint"\s*/>', text)) == 1
    assert '<motor name="root_joint"' not in text and "velocity_limit:root_joint" not in text
    said = [n for n in res.notes if "free joint of body" in n]
    assert len(said) == 1 and "(w, x, y, z)" in said[0] and "world axes" in said[0]
    again = mindyn.load(res.path)
    assert again.joint_names == robot.joint_names
    assert again.joint_types == robot.joint_types
    assert again.link_names == robot.link_names and again.parents == robot.parents
    np.testing.assert_array_equal(again.gravity, robot.gravity)
    for k in range(robot.n):
        assert_close(again.joint_pre(k), robot.joint_pre(k), 1e-12, f"placement of joint {k}")
    scale = np.abs(p).max()
    np.testing.assert_allclose(again.params, p, rtol=0, atol=ROUND_TRIP * scale)

    m = mujoco.MjModel.from_xml_path(str(res.path))
    model = pin.buildModelFromUrdf(str(FLOATING[name]), pin.JointModelFreeFlyer())
    assert list(model.names[1:]) == robot.joint_names
    set_pinocchio_params(model, robot, p)
    data = model.createData()
    bp = mindyn.base_parameters(robot)
    values = bp.values(p)
    rng = np.random.default_rng(11)
    for _ in range(4):
        q, v, a = random_state(robot, rng)
        ref = mj_inverse(m, robot, q, v, a)
        assert np.abs(ref[:6]).max() > 1.0  # the base's equations carry the motion and weight
        assert_close(robot.inverse_dynamics(q, v, a, params=p), ref, TOL, "mindyn vs MuJoCo")
        assert_close(again.inverse_dynamics(q, v, a), ref, TOL, "file read back vs MuJoCo")
        rnea = pin.rnea(model, data, pin_q(robot, model, q), v, a)
        assert_close(rnea, ref, TOL, "Pinocchio free-flyer rnea vs MuJoCo")
        assert_close(bp.regressor(q, v, a) @ values, ref, TOL, "W_b Y p vs MuJoCo")


def test_floating_mjcf_written_back_keeps_the_free_joint(tmp_path):
    """A floating robot read from an MJCF is written back into that file: the free joint and
    the rest kept, only the inertials changed, and the file read back holds the new values."""
    robot, _, res = written("solo12", tmp_path)
    again = mindyn.load(res.path)
    p2 = physical_params(again, np.random.default_rng(8), drive=False)
    back = write_mjcf(again, p2, tmp_path / "back.xml")
    text = back.path.read_text()
    assert len(re.findall(r'<freejoint name="root_joint"\s*/>', text)) == 1
    assert text.count("<inertial") == res.path.read_text().count("<inertial")
    third = mindyn.load(back.path)
    assert third.joint_types == robot.joint_types
    np.testing.assert_allclose(third.params, p2, rtol=0, atol=ROUND_TRIP * np.abs(p2).max())
    with pytest.raises(mindyn.ModelError, match="armature of the floating joint 'root_joint'"):
        rows = np.c_[p2.reshape(again.n, 10), np.r_[0.5, np.zeros(again.n - 1)]]
        write_mjcf(again, rows.ravel(), tmp_path / "bad.xml")


def test_cli_export_mjcf_of_a_floating_robot(tmp_path):
    """`mindyn export URDF --root-joint floating ID.json --mjcf OUT` writes the library's file
    and prints how the free joint's coordinates differ from mindyn's."""
    import json

    robot, p, res = written("solo12", tmp_path)
    ident = tmp_path / "id.json"
    ident.write_text(json.dumps({"classical": dict(zip(robot.param_names, p.tolist()))}))
    out = tmp_path / "cli.xml"
    text = cli("export", SOLO, "--root-joint", "floating", ident, "--mjcf", out)
    assert out.read_text() == res.path.read_text()
    assert "note: the floating joint 'root_joint' is the free joint of body" in text


def test_a_floating_joint_with_a_placement_is_written_with_a_note(tmp_path):
    """A YAML table's floating joint with an MDH placement from the world: written as the free
    body's initial pose with a note; MuJoCo's qpos is then the placement times mindyn's q,
    and with that map MuJoCo's inverse dynamics is mindyn's (v, a, forces unchanged)."""
    path = tmp_path / "hop.yaml"
    path.write_text(YAML_FLOATING)
    robot = mindyn.load(path)
    pre = robot.joint_pre(0)
    assert not np.allclose(pre, np.eye(4))
    p = physical_params(robot, np.random.default_rng(2), drive=False)
    res = write_mjcf(robot, p, tmp_path / "hop.xml")
    assert any("has a placement from the world" in n for n in res.notes)
    again = mindyn.load(res.path)
    m = mujoco.MjModel.from_xml_path(str(res.path))
    rng = np.random.default_rng(9)
    for _ in range(3):
        q, v, a = random_state(robot, rng)
        pose = robot.link_poses(q)[0]  # the free body's pose: pre J(q), post identity
        w, x, y, z = mujoco_quat(pose[:3, :3])
        q_file = np.r_[pose[:3, 3], x, y, z, w, q[7:]]
        ref = mj_inverse(m, again, q_file, v, a)
        assert_close(robot.inverse_dynamics(q, v, a, params=p), ref, TOL, "placed base")
        assert_close(again.inverse_dynamics(q_file, v, a), ref, TOL, "read back")


def mujoco_quat(R) -> np.ndarray:
    out = np.zeros(4)
    mujoco.mju_mat2Quat(out, np.asarray(R, dtype=float).ravel())
    return out


YAML_FLOATING = """
name: hop
convention: mdh
joints:
  - {name: base, type: floating, alpha: 0.4, d: 0.1, theta: 0.2, r: 0.3,
     inertial: {mass: 5.0, com: [0, 0, 0.1], inertia: {xx: 0.1, yy: 0.1, zz: 0.05}}}
  - {name: j2, type: revolute, alpha: 1.5708, d: 0, theta: 0, r: 0,
     inertial: {mass: 0.5, com: [0.2, 0, 0], inertia: {xx: 0.001, yy: 0.01, zz: 0.01}}}
  - {name: j3, type: prismatic, alpha: 0.3, d: 0.2, theta: 0.1, r: 0, parent: 1,
     inertial: {mass: 0.5, com: [0.2, 0, 0], inertia: {xx: 0.001, yy: 0.01, zz: 0.01}}}
"""


# -- MJCF in ------------------------------------------------------------------------------------
FREE_TREE = """<mujoco model="walker">
  <compiler angle="radian"/>
  <option gravity="0.2 -0.1 -9.7"/>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="torso" pos="0.1 0.2 0.5" quat="0.9 0.1 0.2 0.3">
      <freejoint name="float"/>
      <inertial pos="0.01 0.02 0.03" mass="3" fullinertia="0.1 0.2 0.15 0.01 0.02 0.003"/>
      <body name="arm" pos="-0.1 0 0.1" euler="0.3 0 0.2">
        <joint name="z_shoulder" axis="1 0 0" pos="0 0.02 0"/>
        <inertial pos="0 0 0.1" mass="0.7" diaginertia="0.01 0.01 0.002"/>
      </body>
      <body name="leg" pos="0.1 0 -0.1">
        <joint name="a_hip" axis="0 1 0" pos="0 0 0.05"/>
        <inertial pos="0 0 -0.1" mass="1" diaginertia="0.01 0.01 0.002"/>
        <body name="shin" pos="0 0 -0.2">
          <joint name="b_knee" type="slide" axis="0 0.6 0.8"/>
          <inertial pos="0 0.01 -0.1" mass="0.5" diaginertia="0.01 0.012 0.005"/>
          <body name="foot" pos="0 0 -0.2"><geom type="sphere" size="0.03" mass="0.1"/></body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def test_hand_written_free_joint_loads_as_a_floating_base(tmp_path):
    """An MJCF whose root body has a free joint (the body placed off the origin, the hinges'
    order in the file not mindyn's by-name order, a jointless foot, gravity tilted) loads as a
    floating-base robot with the inverse dynamics MuJoCo computes, at random states with the
    coordinates converted as in the module's docstring; Pinocchio's rnea on the same geometry
    with a free-flyer root agrees."""
    path = tmp_path / "walker.xml"
    path.write_text(FREE_TREE)
    robot = mindyn.load(path)
    assert robot.joint_names == ["float", "a_hip", "b_knee", "z_shoulder"]
    assert robot.joint_types == ["floating", "revolute", "prismatic", "revolute"]
    assert (robot.nq, robot.nv, robot.parents) == (10, 9, [-1, 0, 1, 0])
    np.testing.assert_array_equal(robot.gravity, [0.2, -0.1, -9.7])
    m = mujoco.MjModel.from_xml_path(str(path))
    assert [m.joint(j).name for j in range(m.njnt)] != robot.joint_names
    assert_mujoco_agrees(robot, m, np.random.default_rng(4), "free joint in")


def assert_mujoco_agrees(robot, m, rng, what: str) -> None:
    """At random states mj_inverse of ``m`` is ``robot``'s inverse dynamics and Pinocchio's
    rnea of its geometry."""
    model = pinocchio_of(robot)
    data = model.createData()
    for _ in range(4):
        q, v, a = random_state(robot, rng)
        ref = mj_inverse(m, robot, q, v, a)
        assert_close(robot.inverse_dynamics(q, v, a), ref, TOL, f"{what}: mindyn vs MuJoCo")
        assert_close(pin.rnea(model, data, q, v, a), ref, TOL, f"{what}: Pinocchio vs MuJoCo")


def pinocchio_of(robot) -> pin.Model:
    """Pinocchio's model of ``robot``'s geometry (joint placements, axes, link inertias; link
    frames the joint frames) with a free-flyer and spherical joints for its own."""
    model = pin.Model()
    model.gravity.linear = robot.gravity
    ids = []
    for k, kind in enumerate(robot.joint_types):
        parent = 0 if robot.parents[k] < 0 else ids[robot.parents[k]]
        if kind == "floating":
            joint = pin.JointModelFreeFlyer()
        elif kind == "spherical":
            joint = pin.JointModelSpherical()
        elif kind == "revolute":
            joint = pin.JointModelRevoluteUnaligned(*robot.axes[k])
        else:
            joint = pin.JointModelPrismaticUnaligned(*robot.axes[k])
        pre = robot.joint_pre(k)
        placement = pin.SE3(pre[:3, :3], pre[:3, 3])
        ids.append(model.addJoint(parent, joint, placement, robot.joint_names[k]))
    set_pinocchio_params(model, robot, robot.params)
    return model


# -- what cannot be mapped: refused in one line naming the element -----------------------------
BODY = '<inertial pos="0 0 0" mass="1" diaginertia="0.1 0.1 0.1"/>'
REFUSED_IN = {
    "two_free_bodies": (
        f'<body name="a"><freejoint name="f1"/>{BODY}</body>'
        f'<body name="b"><freejoint name="f2"/>{BODY}</body>',
        "joint 'f1' (body 'a') and joint 'f2' (body 'b') are both free joints",
    ),
    "hinge_beside": (
        f'<body name="a"><freejoint name="f1"/>{BODY}</body>'
        f'<body name="c"><joint name="h" axis="0 0 1"/>{BODY}</body>',
        "joint 'h' (body 'c') is not below the free body 'a'",
    ),
    "free_below": (
        f'<body name="a"><joint name="h" axis="0 0 1"/>{BODY}'
        f'<body name="b"><freejoint name="f1"/>{BODY}</body></body>',
        "free joint can only be used on top level",
    ),
    "armature": (
        f'<body name="a"><joint name="f1" type="free" armature="0.2"/>{BODY}</body>',
        "free joint 'f1' (body 'a') has armature 0.2",
    ),
    "damping": (
        f'<body name="a"><joint name="f1" type="free" damping="0.3"/>{BODY}</body>',
        "free joint 'f1' (body 'a') has damping 0.3",
    ),
    "spring": (
        f'<body name="a"><joint name="f1" type="free" stiffness="3"/>{BODY}</body>',
        "joint 'f1' (body 'a') has a spring (stiffness 3.0)",
    ),
    "ball_damping": (
        f'<body name="a"><freejoint name="f1"/>{BODY}'
        f'<body name="b"><joint name="s" type="ball" damping="0.1"/>{BODY}</body></body>',
        "ball joint 's' (body 'b') has damping 0.1",
    ),
    "ball_velocity_limit": (
        f'<body name="a"><joint name="f1" type="ball"/>{BODY}</body>',
        "<numeric name=\"velocity_limit:f1\">: 'f1' is a ball joint",
    ),
    "velocity_limit": (
        f'<body name="a"><freejoint name="f1"/>{BODY}</body>',
        "<numeric name=\"velocity_limit:f1\">: 'f1' is a free joint",
    ),
}


@pytest.mark.parametrize("case", sorted(REFUSED_IN))
def test_free_joints_the_model_cannot_hold_are_refused_by_name(case, tmp_path):
    bodies, message = REFUSED_IN[case]
    custom = '<custom><numeric name="velocity_limit:f1" data="2"/></custom>'
    path = tmp_path / "bad.xml"
    path.write_text(
        f"<mujoco><worldbody>{bodies}</worldbody>{custom if 'velocity_limit' in case else ''}"
        "</mujoco>"
    )
    with pytest.raises(mindyn.ModelError) as e:
        mindyn.load(path)
    assert message in str(e.value) and "\n" not in str(e.value), str(e.value)


REFUSED_OUT = {
    "planar_root": ("planar", "has the planar joint 'root_joint', which MJCF out does not"),
    "cylindrical": (
        "  - {name: j2, type: cylindrical, alpha: 0, d: 0, theta: 0, r: 0.1, parent: 1,",
        "has the cylindrical joint 'j2', which MJCF out does not write",
    ),
    "floating_below": (
        "  - {name: j2, type: floating, alpha: 0, d: 0, theta: 0, r: 0.1, parent: 1,",
        "has the floating joint 'j2' below link 'link1': MuJoCo's free joint moves a body",
    ),
    "beside": (
        "  - {name: j2, type: revolute, alpha: 0, d: 0, theta: 0, r: 0.1, parent: 0,",
        "has the joint 'j2' on its base beside the floating joint 'j1'",
    ),
}


@pytest.mark.parametrize("case", sorted(REFUSED_OUT))
def test_joints_mjcf_out_cannot_write_are_refused_by_name(case, tmp_path):
    """write_mjcf and `export --mjcf` refuse, naming the joint, what a free or ball joint cannot
    be: a planar root, a joint of several degrees of freedom other than a spherical joint and
    the floating root, a floating joint below a link, a joint on the base beside the floating
    one."""
    second, message = REFUSED_OUT[case]
    if case == "planar_root":
        robot = mindyn.load(SOLO, root_joint="planar")
        args = [SOLO, "--root-joint", "planar"]
    else:
        first = "floating" if case == "beside" else "revolute"
        path = tmp_path / "r.yaml"
        path.write_text(
            "name: r\nconvention: mdh\njoints:\n"
            f"  - {{name: j1, type: {first}, alpha: 0, d: 0, theta: 0, r: 0,\n"
            "     inertial: {mass: 1.0, com: [0, 0, 0.1], inertia: {xx: 0.1, yy: 0.1, zz: 0.1}}}\n"
            f"{second}\n"
            "     inertial: {mass: 1.0, com: [0, 0, 0.1], inertia: {xx: 0.1, yy: 0.1, zz: 0.1}}}\n"
        )
        robot = mindyn.load(path)
        args = [path]
    with pytest.raises(mindyn.ModelError) as e:
        write_mjcf(robot, robot.params, tmp_path / "out.xml")
    assert message in str(e.value) and "\n" not in str(e.value), str(e.value)
    ident = tmp_path / "id.json"
    ident.write_text('{"classical": {}}')  # refused before it is read
    from test_floating_cli import refused

    refused("export", *args, ident, "--mjcf", tmp_path / "o.xml", match=message)
    assert not (tmp_path / "out.xml").exists() and not (tmp_path / "o.xml").exists()


# -- ball joints --------------------------------------------------------------------------------
BALLS = """<mujoco model="shoulder">
  <compiler angle="radian"/>
  <option gravity="0.3 0 -9.81"/>
  <worldbody>
    <body name="upper" pos="0 0 1" euler="0.2 0.1 0">
      <joint name="a_ball" type="ball" pos="0 0 0.05"/>
      <inertial pos="0.01 0 -0.15" mass="2" fullinertia="0.03 0.02 0.015 0.001 0.002 0.003"/>
      <body name="fore" pos="0 0 -0.3" quat="0.9 0 0.3 0.1">
        <joint name="b_elbow" axis="0 1 0"/>
        <inertial pos="0 0.01 -0.12" mass="1" diaginertia="0.01 0.012 0.004"/>
        <body name="hand" pos="0 0 -0.25">
          <joint name="c_wrist" axis="1 0 0" pos="0 0 0.02"/>
          <joint name="d_ball" type="ball" pos="0 0.01 0"/>
          <inertial pos="0.02 0 -0.05" mass="0.5" diaginertia="0.002 0.003 0.004"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def test_hand_written_ball_joints_load_as_spherical_joints(tmp_path):
    """Ball joints (one off its body's origin, one after a hinge in the same body) load as
    spherical joints at their anchors, with the inverse dynamics MuJoCo computes (quaternions
    reordered) and Pinocchio's rnea with JointModelSpherical on the same geometry."""
    path = tmp_path / "balls.xml"
    path.write_text(BALLS)
    robot = mindyn.load(path)
    assert robot.joint_names == ["a_ball", "b_elbow", "c_wrist", "d_ball"]
    assert robot.joint_types == ["spherical", "revolute", "revolute", "spherical"]
    assert (robot.nq, robot.nv) == (10, 8) and robot.link_names[3] == "hand__c_wrist"
    with pytest.raises(mindyn.ArgumentError, match="'b_elbow' is no floating joint of shoulder"):
        robot._m.with_spherical(["b_elbow"])  # what the reader uses on its floating joints
    m = mujoco.MjModel.from_xml_path(str(path))
    assert_mujoco_agrees(robot, m, np.random.default_rng(6), "ball joints in")


YAML_BALLS = """
name: critter
convention: mdh
joints:
  - {name: a_base, type: floating, alpha: 0, d: 0, theta: 0, r: 0,
     inertial: {mass: 4.0, com: [0.05, 0, 0.1], inertia: {xx: 0.1, yy: 0.08, zz: 0.05}}}
  - {name: b_hip, type: spherical, alpha: 0.3, d: 0.2, theta: 0.1, r: -0.05, parent: 1,
     inertial: {mass: 1.0, com: [0, 0.02, -0.2], inertia: {xx: 0.02, yy: 0.02, zz: 0.004}}}
  - {name: c_knee, type: revolute, alpha: 1.5708, d: 0, theta: 0, r: 0, parent: 2,
     inertial: {mass: 0.5, com: [0.2, 0, 0], inertia: {xx: 0.001, yy: 0.01, zz: 0.01}}}
  - {name: d_neck, type: spherical, alpha: -0.4, d: -0.1, theta: 0, r: 0.2, parent: 1,
     inertial: {mass: 0.8, com: [0, 0, 0.1], inertia: {xx: 0.01, yy: 0.01, zz: 0.003}}}
"""


def test_spherical_joints_are_written_as_ball_joints_and_read_back(tmp_path):
    """A YAML tree on a floating base with spherical joints, random physically consistent
    parameters: written with a ball joint per spherical joint (no motor, a note on the
    quaternion order), read back with the same joints and parameters, and MuJoCo's mj_inverse
    on the file is mindyn's inverse dynamics and Pinocchio's rnea of the robot read back."""
    path = tmp_path / "critter.yaml"
    path.write_text(YAML_BALLS)
    robot = mindyn.load(path)
    p = physical_params(robot, np.random.default_rng(12), drive=False)
    res = write_mjcf(robot, p, tmp_path / "critter.xml")
    text = res.path.read_text()
    assert len(re.findall(r'<joint name="(b_hip|d_neck)" type="ball"\s*/>', text)) == 2
    assert '<motor name="b_hip"' not in text
    assert any("('b_hip', 'd_neck') are ball joints" in n for n in res.notes)
    again = mindyn.load(res.path)
    assert again.joint_names == robot.joint_names and again.parents == robot.parents
    assert again.joint_types == robot.joint_types
    m = mujoco.MjModel.from_xml_path(str(res.path))
    assert_mujoco_agrees(again, m, np.random.default_rng(13), "ball joints read back")
    rng = np.random.default_rng(14)
    for _ in range(3):
        q, v, a = random_state(robot, rng)
        ref = mj_inverse(m, robot, q, v, a)
        assert_close(robot.inverse_dynamics(q, v, a, params=p), ref, TOL, "YAML balls vs MuJoCo")


# -- hinge terms and ball ranges the model of a floating base has no place for -----------------
ARMATURE = """<mujoco model="floatarm">
  <worldbody>
    <body name="base" pos="0 0 1">
      <freejoint name="root"/>
      <inertial pos="0.01 0.02 0" mass="3" diaginertia="0.1 0.2 0.15"/>
      <body name="l1" pos="0.1 0 0">
        <joint name="j1" axis="0 0 1" armature="0.3" damping="0.5" frictionloss="0.2"/>
        <inertial pos="0.2 0 0" mass="1.5" diaginertia="0.01 0.03 0.03"/>
        <body name="l2" pos="0.4 0 0">
          <joint name="j2" axis="0 1 0" armature="0.05"/>
          <inertial pos="0.1 0.01 0" mass="0.7" diaginertia="0.005 0.01 0.01"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def test_hinge_armature_under_a_free_joint_is_named_as_not_in_the_dynamics(tmp_path):
    """Armature, damping and frictionloss of hinges below a free joint: the model of a floating
    base has no rotor inertia or friction, and its dynamics left them out while the robot
    carried them, silently. Now a warning names them and says that the mass matrix and inverse
    dynamics are MuJoCo's without them, which they are: MuJoCo's mass matrix (in mindyn's
    velocities, ``S^T M S`` with ``S = diag(R, I)``) minus the armature on the hinges'
    diagonal, and ``mj_inverse`` of the model with the three terms set to zero. The robot
    keeps them as read (they are written back to an MJCF)."""
    path = tmp_path / "floatarm.xml"
    path.write_text(ARMATURE)
    said = r"rotor inertia \(j1 0.3, j2 0.05\); viscous friction \(j1 0.5\); Coulomb friction \("
    with pytest.warns(UserWarning, match=said + r"j1 0.2\) of its revolute and prismatic joints"):
        robot = mindyn.load(path)
    assert robot.joint_types == ["floating", "revolute", "revolute"]
    assert robot.rotor_inertia.tolist() == [0.0, 0.3, 0.05]
    assert (robot.viscous.tolist(), robot.coulomb.tolist()) == ([0, 0.5, 0], [0, 0.2, 0])
    m = mujoco.MjModel.from_xml_path(str(path))
    bare = mujoco.MjModel.from_xml_path(str(path))
    bare.dof_armature[:], bare.dof_damping[:], bare.dof_frictionloss[:] = 0.0, 0.0, 0.0
    armature = np.array(m.dof_armature)
    assert armature[6:].tolist() == [0.3, 0.05]
    rng = np.random.default_rng(8)
    for _ in range(3):
        q, v, a = random_state(robot, rng)
        qpos, _, _ = to_mujoco(m, robot, q, v, a)
        x, y, z, w = q[3:7]
        S = np.eye(m.nv)
        S[:3, :3] = rotation([w, x, y, z])
        full = S.T @ full_mass_matrix(m, qpos) @ S
        assert_close(robot.mass_matrix(q) + np.diag(armature), full, TOL, "A + armature vs MuJoCo")
        ref = mj_inverse(bare, robot, q, v, a)
        assert_close(robot.inverse_dynamics(q, v, a), ref, TOL, "mindyn vs MuJoCo without terms")


def test_a_ball_joint_range_is_named_as_not_read(tmp_path):
    """A ball joint's range (MuJoCo's cone limit on its rotation angle; 60 degrees here, in the
    file's degrees) has no place in the model's spherical joint: a warning names it."""
    path = tmp_path / "cone.xml"
    path.write_text(
        BALLS.replace('<compiler angle="radian"/>', "").replace(
            'name="a_ball" type="ball"', 'name="a_ball" type="ball" range="0 60"'
        )
    )
    with pytest.warns(UserWarning, match=r"range of ball joint\(s\) 'a_ball' \(60 deg\), a cone"):
        robot = mindyn.load(path)
    assert robot.joint_types[0] == "spherical"
    path.write_text(BALLS)  # no range: no warning
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mindyn.load(path)
