"""Identified classical parameters written as a MuJoCo MJCF.

How MuJoCo's terms relate to the model's (``tau = W(q, dq, ddq) p + Ia ddq + Fv dq + Fc sign(dq)``):

- a body's ``<inertial>``: ``mass`` = ``M``, ``pos`` = centre of mass ``(MX, MY, MZ) / M`` and
  ``fullinertia`` = the inertia about it, in the body frame;
- a joint's ``armature`` = ``Ia``: MuJoCo adds it to the diagonal of the joint-space inertia
  (``tau += Ia ddq``, exactly the model's rotor term);
- a joint's ``damping`` = ``Fv``: a passive force ``-Fv dq`` (exactly the model's viscous term);
- a joint's ``frictionloss`` = ``Fc``: not a force ``Fc sign(dq)`` but a dry-friction
  constraint, solved with the other constraints: its force is at most ``Fc`` in magnitude and
  opposes the motion, and is smaller (soft, set by ``solreffriction``/``solimpfriction``) near
  zero velocity. ``mj_inverse`` includes the constraint force the soft model gives for the
  state and acceleration: where the constraint is saturated (the joint moves, MuJoCo's
  ``efc_state`` linear) that is exactly ``Fc sign(dq)``; with the frictionloss constraint
  disabled (``mjDSBL_FRICTIONLOSS``) ``mj_inverse`` leaves it out and ``Fc sign(dq)`` is added by
  hand;
- a floating root (a free-flyer, ``root_joint="floating"``) is a ``<freejoint>`` on its body,
  which hangs from the world (MuJoCo's free joint moves such a body only, and the model's
  floating base carries every other joint: :func:`check_joints`), without armature, damping or
  frictionloss (the model's floating base has none). The coordinates differ: MuJoCo's ``qpos``
  = the body's position and quaternion ``(w, x, y, z)`` in the world, mindyn's q = the same
  position and quaternion ``(x, y, z, w)``; MuJoCo's ``qvel`` = ``(R v, w)`` for mindyn's v =
  ``(v, w)``: the linear velocity of the body origin in the world axes against the body's
  (``R`` the body's rotation), the angular velocity in the body's axes in both; so MuJoCo's
  ``qacc`` = ``(R (a + w x v), dw)`` and its generalised force ``(R f, t)`` for mindyn's ``(f,
  t)``. A spherical joint is a ball joint (``qpos`` its quaternion ``(w, x, y, z)``, mindyn's q
  ``(x, y, z, w)``; the angular velocity in the body's axes in both), without motor, limits or
  drive terms. Other joints of several degrees of freedom (planar, universal, cylindrical) are
  refused by name;
- torque offsets ``Off`` have no place in MJCF (a comment lists them);
- the joints' effort limits are their ``actuatorfrcrange``; their velocity limits, which MJCF has
  no element for, custom numerics ``<numeric name="velocity_limit:JOINT" data="V"/>`` (data that
  MuJoCo keeps and ignores, read back by :func:`mindyn.load`).

With transmissions (``q_m = T q + c``, ``tau = T^T tau_m``), motor by motor (row ``i`` of ``T``):

- a motor whose row has one non-zero entry ``r`` on joint ``k`` (a simple transmission of ratio
  ``r``, the common case) is a ``<motor>`` actuator on joint ``k`` with ``gear`` = ``r`` (MuJoCo's
  own form of a gear ratio: joint torque ``r tau_m``). With the drive terms on the motors
  (``drive_side="motor"``: slot ``i`` of ``Ia``, ``Fv``, ``Fc`` is motor ``i``'s, ``tau +=
  T^T (Ia T ddq + Fv T dq + Fc sign(T dq))``) they are folded exactly onto joint ``k``:
  ``armature`` = ``r^2 Ia``, ``damping`` = ``r^2 Fv``, ``frictionloss`` = ``|r| Fc`` (summed when
  several such motors drive one joint);
- a motor coupling several joints is a fixed tendon whose coefficients are its row of ``T``
  (which ``gear`` on a joint actuator cannot express), driven by a ``<motor>`` on the tendon with
  ``gear`` 1; with the drive terms on the motors they go on the tendon (its ``armature``,
  ``damping``, ``frictionloss``: ``T_i^T Ia T_i ddq`` and so on; MuJoCo 3.4 and later), but for
  the rotor inertia of a motor coupling joints on different branches of the tree, refused:
  MuJoCo adds a tendon's armature to its mass matrix only between joints of one branch;
- with the drive terms on the joints they are the joints' ``armature``, ``damping``,
  ``frictionloss`` as without transmissions; the motor offsets ``c`` are not written (they do
  not change the dynamics).

Read back (:mod:`mindyn._mujoco`), such a file gives a robot with the same dynamics: a
motor-side robot's simple motors come back as the joint terms above (``r^2 Ia`` ..., the same
parameters when ``r`` = 1); fixed tendons over several joints carrying terms come back as a
transmission (``robot.transmission.format`` ``mjcf``) of one motor per tendon, its row of ``T``
the tendon's coefficients and its ``Ia``, ``Fv``, ``Fc`` the tendon's terms, every other joint
driven directly (ratio 1) with its joint's terms, the drive terms on the motors. A robot read so
is written back with each coupling motor's terms on its tendon and each direct motor's on its
joint.
"""

from __future__ import annotations

import os
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from . import _args, _mujoco
from ._core import OFFSET_PREFIX as _OFF
from ._core import ModelError, RobotFileNotFoundError
from .export import (
    Export,
    JointTerms,
    XmlDocument,
    centroidal,
    classical_terms,
    unread_transmission_notes,
)
from .robot import Robot, load

__all__ = ["check_joints", "write_mjcf"]


def write_mjcf(
    robot: Robot, classical, path, *, source=None, drive_side=None, new: bool = False
) -> Export:
    """Writes ``classical`` as the dynamics of ``robot`` in a MuJoCo MJCF.

    Parameters
    ----------
    robot : Robot
        A robot of revolute, prismatic and spherical joints on a fixed or floating base
        (:func:`check_joints`); one loaded from an MJCF has that file rewritten.
    classical : mapping or array_like
        Classical parameters, see :func:`mindyn.export.classical_terms`.
    path : str or Path
        The MJCF to write (its folder is created when missing).
    source : str or Path, optional
        The description to start from; default ``robot.source``. An MJCF is written back with
        only its moving bodies' ``<inertial>`` and its joints' ``armature``, ``damping`` and
        ``frictionloss`` changed (of these, those ``classical`` holds: the file keeps its own
        of the others, as a note says; comments and everything else kept; bodies merged into a
        moving link get a zero ``<inertial>``), then compiled by MuJoCo and checked to give
        the parameters written. Any other robot gets a new MJCF: one body per link, its frame
        the joint frame (a hinge's or slide's link without inertia and with one child hinge,
        slide or ball joint, not turned from it, shares that joint's body: MuJoCo has no
        massless moving body), with
        ``<inertial>``, a hinge or slide joint (axis, range, the effort
        limit as ``actuatorfrcrange``, ``armature``, ``damping``, ``frictionloss``: 0 for a
        term ``classical`` lacks, as a note says when the description has some), a ball
        joint for a spherical joint or, for a floating root, a ``<freejoint>`` (see the
        module's docstring), the
        velocity limits as custom numerics ``velocity_limit:<joint>`` (MJCF has none; MuJoCo
        keeps them as data, :func:`mindyn.load` reads them back), gravity, a ``tool`` site for
        a chain, and a ``<motor>``
        per joint, or with transmissions per motor: on its joint with ``gear`` = its ratio, or
        on a fixed tendon for a motor coupling joints (see the module's docstring).
    drive_side : {"joint", "motor"}, optional
        Where ``Ia``, ``Fv``, ``Fc`` act with transmissions; default the robot's
        ``drive_side`` (``"joint"`` when it has none).
    new : bool
        Write a new MJCF even for a robot loaded from one (``source`` is then not read).

    Returns
    -------
    Export
        The file written and notes.

    Raises
    ------
    RobotFileNotFoundError
        ``source`` is given and does not exist.
    ModelError
        ``classical`` does not fit the robot, a mass is negative (or zero with a first
        moment), friction of a friction model other than Coulomb's (MJCF has no place for
        its shape), the MJCF to rewrite does not hold the robot's bodies and joints by name,
        ``mujoco`` is missing where it is needed, MuJoCo compiles the written file to other
        parameters, or the robot has joints MJCF out cannot write (:func:`check_joints`).
    """
    _args.instance(robot, "robot", Robot)
    check_joints(robot)
    _args.path(path, "path")
    _args.optional(_args.path, source, "source")
    terms = classical_terms(robot, classical)
    kind = robot.friction_model["kind"] if robot.single_dof else "coulomb"
    if kind != "coulomb" and terms.coulomb is not None:
        raise ModelError(
            f"robot '{robot.name}' has the {kind} friction model; MJCF holds viscous friction "
            "(damping) and dry friction (frictionloss) only: write a URDF or YAML table, whose "
            "joint-terms file keeps the model, or identify with friction_model='coulomb'"
        )
    side = drive_side if drive_side is not None else getattr(robot, "drive_side", "joint")
    _args.choice(side, "drive_side", ("joint", "motor"))
    new = _args.flag(new, "new")
    if source is not None and not new and not Path(source).is_file():
        raise RobotFileNotFoundError(f"source: description file '{source}' does not exist")
    src = Path(robot.source if source is None else source)
    out = Path(path)
    if not new and _mujoco.is_mjcf(src):
        return _rewrite(robot, terms, src, out)
    return _generate(robot, terms, out, side)


def check_joints(robot: Robot) -> None:
    """Refuses, in one line naming the joint, a robot whose joints an MJCF cannot hold as the
    model has them: any joint of several degrees of freedom but a spherical joint (a ball
    joint) and a floating root (a free-flyer on the base carrying every other joint, written as
    MuJoCo's free joint, which moves a body hanging from the world only)."""
    _args.instance(robot, "robot", Robot)
    roots = [k for k in range(robot.n) if robot.parents[k] < 0]
    for k, kind in enumerate(robot.joint_types):
        if kind in _SINGLE_DOF or kind == "spherical":
            continue
        name = robot.joint_names[k]
        if kind != "floating":
            raise ModelError(
                f"write_mjcf writes revolute, prismatic and spherical joints and a floating root "
                f"(a free joint); robot '{robot.name}' has the {kind} joint '{name}', which MJCF "
                "out does not write"
            )
        if robot.parents[k] >= 0:
            raise ModelError(
                f"robot '{robot.name}' has the floating joint '{name}' below link "
                f"'{robot.link_names[robot.parents[k] + 1]}': MuJoCo's free joint moves a body "
                "hanging from the world only"
            )
        if len(roots) > 1:
            other = robot.joint_names[next(i for i in roots if i != k)]
            raise ModelError(
                f"robot '{robot.name}' has the joint '{other}' on its base beside the floating "
                f"joint '{name}': a floating base written as MuJoCo's free joint carries every "
                "joint"
            )


_SINGLE_DOF = ("revolute", "prismatic")


def _unwritten_limits_and_drives(robot: Robot) -> list[str]:
    """A note naming what the description gives and a new MJCF has no place for: acceleration
    limits, the drive table (rated torques, gear ratios, torque constants)."""
    accel = robot.limits["acceleration"]
    lost = ["the acceleration limits"] if np.any(np.isfinite(accel) & (accel > 0)) else []
    drives = robot.drives
    table = [
        label
        for key, label in (
            ("rated_torque", "rated torques"),
            ("gear_ratio", "gear ratios"),
            ("torque_constant", "torque constants"),
        )
        if np.any(np.isfinite(drives[key]))
    ]
    if table:
        lost.append(f"the drive table ({', '.join(table)})")
    if not lost:
        return []
    return [
        f"{' and '.join(lost)} of the description, which MJCF has no place for, are not written:"
        " the file read back has none (torques logged in permille of the rated torque or as"
        " currents need the description, or drive_gain= for currents)"
    ]


# -- a new MJCF -------------------------------------------------------------------------------
def _generate(robot: Robot, terms: JointTerms, out: Path, side: str) -> Export:
    notes = unread_transmission_notes(robot, "not written (MJCF has no place for it)")
    tr = robot.transmission
    on_motors = side == "motor" and tr is not None
    motors = _motor_rows(robot, tr)
    coupled = [i for i, (_, row) in enumerate(motors) if len(row) > 1]
    if on_motors:
        _check_motor_side(robot, tr, bool(coupled))
        for i in coupled:
            _one_branch(robot, motors[i], _slot(terms, i, f"motor '{motors[i][0]}'")[0])
    drive = _joint_drive(robot, terms, motors, on_motors)
    notes += _zero_terms(robot, terms)
    root = ET.Element("mujoco", {"model": robot.name})
    root.append(_comment(_mapping_comment(robot, on_motors, tr is not None)))
    ET.SubElement(root, "compiler", {"angle": "radian", "inertiafromgeom": "false"})
    ET.SubElement(root, "option", {"gravity": _vec(robot.gravity)})
    world = ET.SubElement(root, "worldbody")
    parents = robot.parents
    bodies: list[ET.Element] = []
    # where each joint frame sits in its body's frame: the identity, or for a joint sharing the
    # body of a massless link before it, a translation
    offsets: list[np.ndarray] = []
    lim = robot.limits
    speeds: list[tuple[str, float]] = []
    for k in range(robot.n):
        place = robot.joint_pre(k)
        if parents[k] >= 0:
            place = robot.joint_post(parents[k]) @ place
        if _shares_body(robot, terms, k):  # MuJoCo has no massless moving body
            body = bodies[parents[k]]
            offset = offsets[parents[k]] @ place
            massless = robot.link_names[parents[k] + 1]
            body.set("name", robot.link_names[k + 1])
            body.remove(next(e for e in body if e.tag == "inertial"))  # the massless link's
            notes = [x for x in notes if not x.startswith(f"link '{massless}': M")]
            notes.append(
                f"link '{massless}' (no mass) shares the body of link "
                f"'{robot.link_names[k + 1]}': its joint '{robot.joint_names[parents[k]]}' "
                f"then '{robot.joint_names[k]}' (MuJoCo has no moving body without mass)"
            )
        elif _turned_massless(robot, terms, k):
            raise ModelError(
                f"link '{robot.link_names[parents[k] + 1]}' has no mass, and MuJoCo refuses a "
                f"moving body without one: it can share the body of its one child joint "
                f"'{robot.joint_names[k]}' only when that joint's frame is not turned from it "
                f"(here turned by {_turn_degrees(robot, k):.4g} deg); give the link a mass, or "
                "write a URDF"
            )
        else:
            parent = world if parents[k] < 0 else bodies[parents[k]]
            if parents[k] >= 0:
                place = offsets[parents[k]] @ place
            body = ET.SubElement(parent, "body", {"name": robot.link_names[k + 1], **_pose(place)})
            offset = np.eye(4)
        bodies.append(body)
        offsets.append(offset)
        mass, com, inertia, more = centroidal(
            terms.inertial[10 * k : 10 * k + 10], k + 1, robot.link_names[k + 1], kind="an MJCF"
        )
        notes += more
        post = offset @ robot.joint_post(k)
        com = post[:3, :3] @ com + post[:3, 3]
        inertia = post[:3, :3] @ inertia @ post[:3, :3].T
        ET.SubElement(body, "inertial", _inertial(mass, com, inertia))
        if robot.joint_types[k] == "floating":  # the root (check_joints)
            _no_drive_terms(robot, k, drive[k])
            ET.SubElement(body, "freejoint", {"name": robot.joint_names[k]})
            notes += _free_notes(robot, k, place)
            continue
        if robot.joint_types[k] == "spherical":
            _no_drive_terms(robot, k, drive[k])
            ball = {"name": robot.joint_names[k], "type": "ball"}
            if np.any(offset[:3, 3] != 0):  # a joint after others in its body: its anchor
                ball["pos"] = _vec(offset[:3, 3])
            ET.SubElement(body, "joint", ball)
            continue
        joint = {
            "name": robot.joint_names[k],
            "type": "hinge" if robot.joint_types[k] == "revolute" else "slide",
            "axis": _vec(robot.axes[k]),
        }
        if np.any(offset[:3, 3] != 0):  # a joint after others in its body: its anchor
            joint["pos"] = _vec(offset[:3, 3])
        lo, hi = lim["lower"][k], lim["upper"][k]
        if np.isfinite(lo) and np.isfinite(hi):
            joint.update(limited="true", range=_vec((lo, hi)))
        else:
            joint["limited"] = "false"
        effort = lim["effort"][k]
        if np.isfinite(effort) and effort > 0:  # read back as the joint's effort limit
            joint.update(actuatorfrclimited="true", actuatorfrcrange=_vec((-effort, effort)))
        joint.update(_attrs(drive[k]))
        ET.SubElement(body, "joint", joint)
        speed = lim["velocity"][k]
        if np.isfinite(speed) and speed > 0:  # MJCF has none: a custom numeric, read back
            speeds.append((robot.joint_names[k], speed))
    balls = [name for name, t in zip(robot.joint_names, robot.joint_types) if t == "spherical"]
    if balls:
        notes.append(
            f"the spherical joints ({', '.join(repr(b) for b in balls)}) are ball joints: "
            "MuJoCo's qpos holds their quaternions as (w, x, y, z), mindyn's q as (x, y, z, w) "
            "(the velocity, the angular velocity in the body's axes, is the same)"
        )
    if robot.is_serial:
        tool = offsets[-1] @ robot.joint_post(robot.n - 1) @ robot.tool
        ET.SubElement(bodies[-1], "site", {"name": "tool", **_pose(tool)})
    if coupled:
        tendons = ET.SubElement(root, "tendon")
        for i in coupled:
            motor, row = motors[i]
            fixed = ET.SubElement(tendons, "fixed", {"name": motor})
            if on_motors:
                fixed.attrib.update(_attrs(_slot(terms, i, f"motor '{motor}'")))
            for k, c in row:
                ET.SubElement(fixed, "joint", {"joint": robot.joint_names[k], "coef": _num(c)})
    if speeds:
        custom = ET.SubElement(root, "custom")
        for name, speed in speeds:
            numeric = {"name": _mujoco.VELOCITY_LIMIT + name, "data": repr(float(speed))}
            ET.SubElement(custom, "numeric", numeric)
        notes.append(
            "the velocity limits, which MJCF lacks, are custom numerics "
            f"'{_mujoco.VELOCITY_LIMIT}<joint>' (MuJoCo ignores them; mindyn reads them back)"
        )
    notes += _unwritten_limits_and_drives(robot)
    actuators = ET.SubElement(root, "actuator")
    for motor, row in motors:
        if tr is None and robot.joint_types[row[0][0]] not in _SINGLE_DOF:
            continue  # no motor: a free or ball joint has no drive
        if len(row) == 1:
            ((k, r),) = row
            on = {"joint": robot.joint_names[k], "gear": _num(r)}
        else:
            on = {"tendon": motor, "gear": "1.0"}
        ET.SubElement(actuators, "motor", {"name": motor, **on})
    if on_motors and len(coupled) < len(motors):
        notes.append(
            "the rotor inertia and friction of each motor driving one joint with ratio r are "
            "written on that joint as armature r^2 Ia, damping r^2 Fv, frictionloss |r| Fc"
        )
    if tr is not None and np.any(tr.offset != 0):
        notes.append(
            "the motor offsets of the transmissions do not change the dynamics: not written"
        )
    if terms.offset is not None:
        root.append(_comment(_offsets_comment(robot, terms)))
        notes.append("torque offsets have no place in MJCF: listed in a comment of the file")
    ET.indent(root, space="  ")
    text = '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, "unicode") + "\n"
    _compiles(text, robot, notes)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text, encoding="utf-8")
    return Export(out, notes=notes)


def _after_massless(robot: Robot, terms: JointTerms, k: int) -> bool:
    """Whether hinge, slide or ball joint ``k`` is the one child of a link without inertia
    (MuJoCo refuses a moving body without mass) of a hinge or slide joint: such a joint shares
    that link's body when its frame is not turned from the link's (:func:`_shares_body`), and
    is refused by name when it is (:func:`_turned_massless`)."""
    parent = robot.parents[k]
    kinds = (*_SINGLE_DOF, "spherical")  # MuJoCo refuses a ball joint followed by another
    return (
        parent >= 0
        and robot.joint_types[k] in kinds
        and robot.joint_types[parent] in _SINGLE_DOF
        and robot.parents.count(parent) == 1
        and not np.any(terms.inertial[10 * parent : 10 * parent + 10] != 0)
    )


def _shares_body(robot: Robot, terms: JointTerms, k: int) -> bool:
    """Whether joint ``k`` goes into the body of its massless parent link
    (:func:`_after_massless`), its frame that link's moved without rotation: MuJoCo's joints of
    one body act one after the other, each about its axis through its anchor (``pos``) in the
    body's axes, as the chain of the massless link does (mindyn reads such a body back as
    that)."""
    return _after_massless(robot, terms, k) and _turn_degrees(robot, k) == 0


def _turned_massless(robot: Robot, terms: JointTerms, k: int) -> bool:
    """Whether joint ``k`` would share the body of its massless parent link
    (:func:`_shares_body`) but for its frame being turned from that link's."""
    return _after_massless(robot, terms, k) and _turn_degrees(robot, k) != 0


def _turn_degrees(robot: Robot, k: int) -> float:
    """The angle [deg] by which joint ``k``'s frame is turned from its parent link's."""
    R = (robot.joint_post(robot.parents[k]) @ robot.joint_pre(k))[:3, :3]
    if np.array_equal(R, np.eye(3)):
        return 0.0
    c = np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0)
    return float(np.degrees(np.arccos(c))) or float(np.finfo(float).eps)


def _no_drive_terms(robot: Robot, k: int, drive) -> None:
    """Refuses armature, damping or frictionloss on the floating or spherical joint ``k``:
    MuJoCo would apply them to each of its velocities, the model has none on such a joint."""
    for key, x in zip(_DRIVE, drive):
        if x != 0:
            raise ModelError(
                f"{key} of the {robot.joint_types[k]} joint '{robot.joint_names[k]}' would be "
                f"{float(x)!r}: the model's joints of several degrees of freedom have no rotor "
                "inertia or friction (give 0)"
            )


def _free_notes(robot: Robot, k: int, place) -> list[str]:
    """What a reader of the MJCF needs to know of the free joint written for the floating joint
    ``k``, whose placement from the world is ``place``."""
    name, body = robot.joint_names[k], robot.link_names[k + 1]
    notes = [
        f"the floating joint '{name}' is the free joint of body '{body}': MuJoCo's qpos holds "
        "its quaternion as (w, x, y, z), mindyn's q as (x, y, z, w), and MuJoCo's qvel its "
        "linear velocity in the world axes, mindyn's v in the body's (the angular velocity is "
        "in the body's axes in both)"
    ]
    if not np.array_equal(np.asarray(place, dtype=float), np.eye(4)):
        notes.append(
            f"the floating joint '{name}' has a placement from the world, written as the "
            f"initial pose of body '{body}' (pos, quat: MuJoCo's qpos0): MuJoCo's qpos is the "
            "body's pose in the world, the placement times mindyn's q (v is the same); read "
            "back, the free joint has no placement"
        )
    return notes


def _motor_rows(robot: Robot, tr) -> list[tuple[str, list[tuple[int, float]]]]:
    """Each motor's name and the joints its row of ``T`` drives, with the ratios; without
    transmissions, one motor per joint named after it, ratio 1."""
    if tr is None:
        return [(name, [(k, 1.0)]) for k, name in enumerate(robot.joint_names)]
    return [
        (name, [(k, float(c)) for k, c in enumerate(tr.T[i]) if c != 0])
        for i, name in enumerate(tr.motors)
    ]


def _joint_drive(robot: Robot, terms: JointTerms, motors, on_motors: bool) -> np.ndarray:
    """Armature, damping, frictionloss of each joint (n x 3): the joint terms, or with the
    terms on the motors those of the motors driving the joint alone, folded onto it."""
    if not on_motors:
        return np.array(
            [_slot(terms, k, f"joint '{name}'") for k, name in enumerate(robot.joint_names)]
        )
    drive = np.zeros((robot.n, 3))
    for i, (motor, row) in enumerate(motors):
        ia, fv, fc = _slot(terms, i, f"motor '{motor}'")
        if len(row) == 1:
            ((k, r),) = row
            drive[k] += (r * r * ia, r * r * fv, abs(r) * fc)
    return drive


def _compiles(text: str, robot: Robot, notes: list[str]) -> None:
    """Has MuJoCo compile the MJCF ``text`` (when installed): its refusal (an inertia that is
    not physical, a body without mass ...) becomes a one-line ModelError, its warnings notes."""
    try:
        import mujoco
    except ImportError:
        notes.append(f"not compiled by MuJoCo (the 'mujoco' package is missing: {_mujoco.INSTALL})")
        return
    with _mujoco.warnings_caught(mujoco) as said:
        try:
            mujoco.MjModel.from_xml_string(text)
        except ValueError as e:
            why = "; ".join(s.strip() for s in str(e).splitlines() if s.strip())
            raise ModelError(
                f"MuJoCo refuses the MJCF of robot '{robot.name}' with these parameters: {why} "
                "(export physically consistent parameters, with positive masses)"
            ) from None
    notes += [f"MuJoCo warns on the file written: {w}" for w in said]


def _check_motor_side(robot: Robot, tr, coupled: bool) -> None:
    if tr.n_motors != robot.n:
        raise ModelError(
            f"drive terms on the motors need as many motors as joints: robot '{robot.name}' has "
            f"{tr.n_motors} motors for {robot.n} joints"
        )
    if not coupled:
        return  # every motor's terms go on its joint
    try:
        import mujoco
    except ImportError:
        return  # the file is written all the same, for MuJoCo 3.4 and later
    # tendon armature came with 3.3.1, and enters MuJoCo's dynamics as T^T Ia T from 3.4 on
    # (the tests compare mj_inverse with the motor-side formula)
    if tuple(int(x) for x in re.findall(r"\d+", mujoco.__version__)[:2]) < (3, 4):
        raise ModelError(
            f"drive terms on motors coupling several joints go on tendons, whose armature "
            f"MuJoCo {mujoco.__version__} does not take as the motors' inertia (3.4 and later do)"
        )


def _one_branch(robot: Robot, motor: tuple[str, list[tuple[int, float]]], ia: float) -> None:
    """Refuses the rotor inertia ``ia`` of a motor coupling joints on different branches of the
    tree (neither moves the other): MuJoCo adds a tendon's armature to its mass matrix only
    between joints of one branch, so the MJCF would not have the motor's inertia
    ``T_i^T Ia T_i`` (its terms between the branches dropped)."""
    if ia == 0:
        return
    parents = robot.parents

    def chain(k: int) -> set[int]:  # joint k and the joints moving it
        out = set()
        while k >= 0:
            out.add(k)
            k = parents[k]
        return out

    joints = [k for k, _ in motor[1]]
    for a in joints:
        for b in joints:
            if a < b and a not in chain(b) and b not in chain(a):
                raise ModelError(
                    f"motor '{motor[0]}' has rotor inertia {ia!r} and couples joints "
                    f"'{robot.joint_names[a]}' and '{robot.joint_names[b]}', on different "
                    "branches of the tree: MuJoCo adds a tendon's armature to its mass matrix "
                    "only between joints of one branch, not as the motor inertia T^T Ia T "
                    "(write the drive terms on the joints: drive_side='joint')"
                )


_DRIVE = ("armature", "damping", "frictionloss")


def _slot(terms: JointTerms, k: int, what: str) -> tuple[float, float, float]:
    """Slot ``k`` of ``Ia``, ``Fv``, ``Fc`` (zero where ``terms`` has none), checked
    non-negative; ``what`` names it in the error."""
    out = []
    for key, v in zip(_DRIVE, (terms.rotor, terms.viscous, terms.coulomb)):
        x = 0.0 if v is None else float(v[k])
        if x < 0:
            raise ModelError(
                f"{key} of {what} would be {x!r}; MuJoCo takes no negative {key} "
                "(export physically consistent parameters)"
            )
        out.append(x)
    return out[0], out[1], out[2]


def _attrs(values, given=_DRIVE) -> dict[str, str]:
    """``armature``, ``damping``, ``frictionloss`` of ``values``, those named in ``given``."""
    return {key: _num(x) for key, x in zip(_DRIVE, values) if key in given}


def _given(terms: JointTerms) -> tuple[str, ...]:
    """The MJCF terms of which ``terms`` holds values: ``armature`` with ``Ia``, ``damping``
    and ``frictionloss`` with ``Fv`` and ``Fc``."""
    values = (terms.rotor, terms.viscous, terms.coulomb)
    return tuple(key for key, v in zip(_DRIVE, values) if v is not None)


#: what each MJCF term holds, and its name among the model's parameters
_TERM_NAMES = {
    "armature": ("rotor inertia", "Ia"),
    "damping": ("viscous friction", "Fv"),
    "frictionloss": ("Coulomb friction", "Fc"),
}


def _zero_terms(robot: Robot, terms: JointTerms) -> list[str]:
    """A note per MJCF term that ``terms`` has no values of and that the robot's description
    gives some joint: a new MJCF has 0 there."""
    notes = []
    for key, given in zip(_DRIVE, (robot.rotor_inertia, robot.viscous, robot.coulomb)):
        if key not in _given(terms) and np.any(np.asarray(given) != 0):
            notes.append(
                f"the parameters written have no {_TERM_NAMES[key][0]} "
                f"({_TERM_NAMES[key][1]}): {key} 0 is written on every joint (the "
                f"description's {_TERM_NAMES[key][0]} is not)"
            )
    return notes


def _kept_terms(m, terms: JointTerms) -> list[str]:
    """A note per MJCF term that ``terms`` has no values of (an identification without rotor
    inertia or friction, as every one of a floating base is) and that the file written back
    (compiled as ``m``) gives some joint or tendon: the file's own values are kept."""
    dofs = [
        int(m.jnt_dofadr[j])
        for j in range(m.njnt)
        if not _mujoco._multi_dof_kinds().get(int(m.jnt_type[j]))
    ]
    notes = []
    for key in _DRIVE:
        if key in _given(terms):
            continue
        joints = sum(1 for d in dofs if getattr(m, f"dof_{key}")[d] != 0)
        tendons = sum(1 for t in range(m.ntendon) if _mujoco.tendon_terms(m, t)[key] != 0)
        if not joints and not tendons:
            continue
        where = [
            f"{n} {w}{'s' if n > 1 else ''}"
            for n, w in ((joints, "joint"), (tendons, "tendon"))
            if n
        ]
        notes.append(
            f"the parameters written have no {_TERM_NAMES[key][0]} ({_TERM_NAMES[key][1]}): "
            f"the file's own {key} is kept "
            f"({' and '.join(where)} carry it)"
        )
    return notes


def _comment(text: str):
    """An XML comment of ``text`` (``--`` may not appear in one: spaced out)."""
    while "--" in text:
        text = text.replace("--", "- -")
    return ET.Comment(text)


def _mapping_comment(robot: Robot, on_motors: bool, transmissions: bool) -> str:
    text = (
        f" Written by mindyn export for robot '{robot.name}' ({robot.source}). Bodies: mass, "
        "centre of mass and inertia about it (fullinertia, body frame = joint frame). On each "
        "joint: armature = rotor inertia Ia (tau += Ia ddq), damping = viscous friction Fv "
        "(tau += Fv dq), frictionloss = Coulomb friction Fc, which MuJoCo applies as a dry-"
        "friction constraint (at most Fc, opposing the motion, soft near zero velocity), not "
        "as Fc sign(dq). "
    )
    if robot.joint_types[0] == "floating":
        text += (
            f"The floating base is the free joint '{robot.joint_names[0]}' of body "
            f"'{robot.link_names[1]}': qpos = its position and quaternion (w, x, y, z) in the "
            "world (mindyn's q: (x, y, z, w)), qvel = the linear velocity of its origin in the "
            "world axes and its angular velocity in its own axes (mindyn's v: both in its own "
            "axes). "
        )
    if "spherical" in robot.joint_types:
        text += (
            "Ball joints: qpos = the quaternion (w, x, y, z) (mindyn's q: (x, y, z, w)), qvel = "
            "the angular velocity in the body's axes (as mindyn's v). "
        )
    if transmissions:
        text += (
            "Motors (q_m = T q, tau = T^T tau_m): one driving one joint with ratio r is an "
            "actuator on the joint with gear r; one coupling joints is a fixed tendon with its "
            "row of T as coefficients, actuated with gear 1. "
        )
    if on_motors:
        text += (
            "The rotor inertia and friction are the motors' (tau += T^T (Ia T ddq + Fv T dq + "
            "Fc sign(T dq))): a motor's on its one joint as armature r^2 Ia, damping r^2 Fv, "
            "frictionloss |r| Fc; a coupling motor's on its tendon. "
        )
    return text


def _offsets_comment(robot: Robot, terms: JointTerms) -> str:
    assert terms.offset is not None  # called when there are offsets
    values = ", ".join(f"{name} {float(v)!r}" for name, v in zip(robot.joint_names, terms.offset))
    return (
        f" Torque offsets {_OFF} (tau += {_OFF}) have no place in MJCF; identified values, per "
        f"joint: {values} "
    )


def _inertial(mass: float, com, inertia) -> dict[str, str]:
    if mass == 0 and not np.any(inertia):  # MuJoCo takes a zero inertia as diagonal only
        return {"pos": _vec(com), "mass": "0.0", "diaginertia": "0.0 0.0 0.0"}
    full = (inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[0, 2],
            inertia[1, 2])  # fmt: skip
    return {"pos": _vec(com), "mass": _num(mass), "fullinertia": _vec(full)}


def _pose(T) -> dict[str, str]:
    T = np.asarray(T, dtype=float)
    return {"pos": _vec(T[:3, 3]), "quat": _vec(_mujoco.quaternion(T[:3, :3]))}


def _num(x) -> str:
    return repr(float(x))


def _vec(v) -> str:
    return " ".join(_num(x) for x in v)


# -- an MJCF written back ---------------------------------------------------------------------
def _rewrite(robot: Robot, terms: JointTerms, src: Path, out: Path) -> Export:
    m = _mujoco.compile_model(src)
    doc = XmlDocument(src, "MJCF")
    if doc.root.tag != "mujoco":
        raise ModelError(f"{src}: the root element is <{doc.root.tag}>, not <mujoco>")
    if robot.n != m.njnt:
        raise ModelError(
            f"{src}: robot '{robot.name}' has {robot.n} of the file's {m.njnt} joints (loaded "
            "with a tip): an MJCF is written back for the whole model only"
        )
    bodies = {e.get("name"): e for e in doc.root.iter("body") if e.get("name")}
    joints = {e.get("name"): e for e in doc.root.iter("joint") if e.get("name")}
    link_index = {name: k for k, name in enumerate(robot.link_names[1:])}
    joint_index = {name: k for k, name in enumerate(robot.joint_names)}
    notes: list[str] = _kept_terms(m, terms)
    given = _given(terms)  # the terms identified; the file keeps its own of the others
    tendons = {e.get("name"): e for e in doc.root.iter("fixed") if e.get("name")}
    on_motors = robot.drive_side == "motor"
    if on_motors:  # the file's motor tendons (its transmission) and directly driven joints
        tr = robot.transmission
        assert tr is not None  # the motor side has one
        motors = _motor_rows(robot, tr)
        per_joint = _joint_drive(robot, terms, motors, True)
        for i, (motor, row) in enumerate(motors):
            if len(row) > 1:
                element = _named(tendons, motor, "fixed", src)
                element.attrib.update(_attrs(_slot(terms, i, f"motor '{motor}'"), given))
    for b in range(1, m.nbody):
        jnts = _mujoco.body_joints(m, b)
        bname = _mujoco.body_name(m, b)
        for j in jnts[:-1]:  # the massless links between a body's joints
            k = link_index[_mujoco.link_name(m, b, j)]
            if np.any(terms.inertial[10 * k : 10 * k + 10] != 0):
                raise ModelError(
                    f"link {k + 1} ('{robot.link_names[k + 1]}') between joints of body "
                    f"'{bname}' has identified inertia; MuJoCo has no body there"
                )
        if not jnts:
            if _moving_ancestor(m, b) and m.body_mass[b] > 0:
                element = _named(bodies, bname, "body", src)
                _set_inertial(element, 0.0, np.zeros(3), np.zeros((3, 3)))
                notes.append(f"body '{bname}' is merged into the link above it: zero <inertial>")
            continue
        k = link_index[bname]
        mass, com, inertia, more = centroidal(
            terms.inertial[10 * k : 10 * k + 10], k + 1, bname, kind="an MJCF"
        )
        notes += more
        com = com + _mujoco.last_anchor(m, b)
        _set_inertial(_named(bodies, bname, "body", src), mass, com, inertia)
        for j in jnts:
            name = _mujoco.joint_name(m, j)
            drive = (
                tuple(per_joint[joint_index[name]])
                if on_motors
                else _slot(terms, joint_index[name], f"joint '{name}'")
            )
            if robot.joint_types[joint_index[name]] not in _SINGLE_DOF:  # free or ball: none
                _no_drive_terms(robot, joint_index[name], drive)
                continue
            _named(joints, name, "joint", src).attrib.update(_attrs(drive, given))
    for t in _mujoco.folded_tendons(m):  # read as their joint's terms, now written there
        name = _mujoco.tendon_name(m, t)
        element = _named(tendons, name, "fixed", src)
        terms_t = _mujoco.tendon_terms(m, t)
        moved = [k for k in _DRIVE if terms_t[k] != 0 and k in given]
        if not moved:
            continue  # kept on the tendon, as the joint keeps its own
        element.attrib.update({k: "0.0" for k in moved})
        notes.append(
            f"the {', '.join(moved)} of tendon '{name}' (over one joint) "
            f"{'are' if len(moved) > 1 else 'is'} written on its joint: zero on the tendon"
        )
    if terms.offset is not None:
        comment = _comment(_offsets_comment(robot, terms))
        comment.tail = "\n"
        doc.root.insert(0, comment)
        notes.append("torque offsets have no place in MJCF: listed in a comment of the file")
    notes += _relocate(doc.root, src, out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(doc.text(), encoding="utf-8")
    _verify(robot, terms, out)
    return Export(out, notes=notes)


# the file attributes MuJoCo reads relative to meshdir (or assetdir), to texturedir (or
# assetdir), and relative to the model file's folder
_MESH_FILES = {"mesh": ("file",), "hfield": ("file",), "skin": ("file",)}
_TEXTURE_FILES = {
    "texture": ("file", "fileright", "fileleft", "fileup", "filedown", "filefront", "fileback")
}


def _relocate(root, src: Path, out: Path) -> list[str]:
    """Makes the relative paths of the MJCF ``root`` (read from ``src``) hold for a file written
    at ``out`` in another folder: MuJoCo reads ``<compiler>``'s ``meshdir``, ``texturedir`` and
    ``assetdir`` and an ``<include>``'s ``file`` relative to the model file's folder, and an
    asset's ``file`` relative to the folder those name (the model file's when unset), in an
    included file as in the model file (:func:`_inline_includes` writes such files into
    ``root``). Each such relative path is rewritten to the same place seen from ``out``'s
    folder; a note says how many."""
    old, new = src.resolve().parent, out.resolve().parent
    if old == new:
        return []
    notes = _inline_includes(root, old)
    changed = 0

    def move(element, key: str) -> None:
        nonlocal changed
        value = element.get(key)
        if value is None or value == "" or Path(value).is_absolute():
            return
        element.set(key, os.path.relpath(old / value, new).replace(os.sep, "/"))
        changed += 1

    compilers = [e for e in root.iter("compiler")]
    given = {key for e in compilers for key in ("meshdir", "texturedir", "assetdir") if e.get(key)}
    for e in compilers:
        for key in ("meshdir", "texturedir", "assetdir"):
            move(e, key)
    for e in root.iter("include"):
        move(e, "file")
    # an asset whose folder is the model file's (no folder given) is itself moved
    for kinds, folder in ((_MESH_FILES, "meshdir"), (_TEXTURE_FILES, "texturedir")):
        if given & {folder, "assetdir"}:
            continue
        for tag, keys in kinds.items():
            for e in root.iter(tag):
                for key in keys:
                    move(e, key)
    if not changed:
        return notes
    return notes + [
        f"{changed} relative path(s) of the file (asset folders, asset files, includes) "
        f"rewritten to hold from {out.parent}, the folder written to"
    ]


def _path_keys(element) -> tuple[str, ...]:
    """The attributes of ``element`` that MuJoCo reads as file or folder paths."""
    if element.tag == "compiler":
        return ("meshdir", "texturedir", "assetdir")
    if element.tag == "include":
        return ("file",)
    return {**_MESH_FILES, **_TEXTURE_FILES}.get(element.tag, ())


def _relative_paths(root) -> list[tuple[ET.Element, str]]:
    """The elements of ``root`` with a relative path, and the attribute holding it."""
    return [
        (e, key)
        for e in root.iter()
        for key in _path_keys(e)
        if e.get(key) and not Path(e.get(key, "")).is_absolute()
    ]


def _inline_includes(root, old: Path) -> list[str]:
    """Writes into ``root`` (an MJCF whose file was in the folder ``old``, to be written to
    another folder) the ``<include>``d files holding relative paths (asset folders, asset
    files, further includes), each in place of its ``<include>``, after a comment naming it:
    MuJoCo reads the paths of an included file relative to the main file's folder (or its
    ``meshdir`` ...), not the included file's, so from the new folder they would name other
    files; written into the file, :func:`_relocate` rewrites them as the file's own. MuJoCo 4
    falls back to the included file's own folder for a path not found from the main file's:
    such a path is first made relative to the main file's folder. An include holding no
    relative path stays an include (its ``file`` rewritten). A note names the files."""
    written: list[str] = []
    kept: set[int] = set()  # includes left as they are
    origin: dict[int, Path] = {}  # an include from an included file: that file's folder
    while True:
        found = next((e for e in root.iter("include") if id(e) not in kept), None)
        if found is None:
            break
        value = found.get("file") or ""
        here = origin.get(id(found), old)
        path = Path(value) if Path(value).is_absolute() else old / value
        if not path.is_file() and (here / value).is_file():
            path = here / value
        doc = XmlDocument(path, "MJCF")
        if not _relative_paths(doc.root):
            kept.add(id(found))
            continue
        if len(written) >= 1000:
            raise ModelError(f"{path}: more than 1000 <include>s (an include cycle?)")
        parent = next(p for p in root.iter() if found in list(p))
        at = list(parent).index(found)
        parent.remove(found)
        mark = _comment(f' from <include file="{value}"> ')
        mark.tail = found.tail
        parent.insert(at, mark)
        folder = path.resolve().parent
        for offset, kid in enumerate(list(doc.root), start=1):
            parent.insert(at + offset, kid)
            if folder != old:
                _main_relative(kid, old, folder, root)
                origin.update({id(e): folder for e in kid.iter("include")})
        if len(doc.root):
            doc.root[-1].tail = found.tail
        written.append(os.path.relpath(path, old).replace(os.sep, "/"))
    if not written:
        return []
    return [
        f"the included file(s) {', '.join(repr(x) for x in written)} are written into the "
        "file, in place of their <include>: MuJoCo reads the relative paths in an included "
        "file from the main file's folder"
    ]


def _main_relative(element, old: Path, folder: Path, root) -> None:
    """Rewrites each relative include or asset file of ``element`` (from an included file in
    ``folder``) that MuJoCo finds only in ``folder`` (its fallback) to the same file seen
    from the main file's folder ``old`` (the folder of the assets, when ``root``'s compiler
    names one)."""
    dirs = {
        key: e.get(key, "") for e in root.iter("compiler") for key in _path_keys(e) if e.get(key)
    }
    for e, key in _relative_paths(element):
        if e.tag == "compiler":
            continue
        value = e.get(key, "")
        kind = "texturedir" if e.tag in _TEXTURE_FILES else "meshdir"
        base = old if e.tag == "include" else old / dirs.get(kind, dirs.get("assetdir", ""))
        if not (base / value).exists() and (folder / value).exists():
            e.set(key, os.path.relpath(folder / value, base).replace(os.sep, "/"))


def _moving_ancestor(m, b: int) -> bool:
    b = int(m.body_parentid[b])
    while b != 0:
        if m.body_jntnum[b]:
            return True
        b = int(m.body_parentid[b])
    return False


def _named(elements: dict, name: str, kind: str, src: Path):
    if name not in elements:
        raise ModelError(
            f'{src}: no <{kind} name="{name}"> in the file itself (unnamed, or from an '
            "<include>d file): name it there to write the file back"
        )
    return elements[name]


def _set_inertial(body, mass: float, com, inertia) -> None:
    old = [e for e in body if e.tag == "inertial"]
    attrib = _inertial(mass, com, inertia)
    if old:
        old[0].attrib.clear()
        old[0].attrib.update(attrib)
        for e in old[1:]:
            body.remove(e)
        return
    new = ET.Element("inertial", attrib)
    new.tail = body.text  # the first child's indentation, kept for it
    body.insert(0, new)


def _verify(robot: Robot, terms: JointTerms, out: Path) -> None:
    """Compiles the written file and checks that it gives back the parameters written, to
    1e-5 relative per link: an overriding compiler option changes them far more; MuJoCo before
    3.14 diagonalises a ``fullinertia`` only to about 1e-6 (from 3.14 on, to round-off)."""
    again = load(out)
    names = dict(zip(again.link_names[1:], range(again.n)))
    for k, link in enumerate(robot.link_names[1:]):
        got = again.params[10 * names[link] : 10 * names[link] + 10]
        want = terms.inertial[10 * k : 10 * k + 10]
        if np.linalg.norm(got - want) > 1e-5 * max(float(np.linalg.norm(want)), 1e-300) + 1e-300:
            raise ModelError(
                f"{out}: MuJoCo compiles link '{link}' to other inertial parameters than "
                'written (a <compiler> option such as inertiafromgeom="true", fusestatic, '
                "boundmass, boundinertia or settotalmass overrides them)"
            )
