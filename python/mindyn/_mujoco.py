"""MuJoCo MJCF descriptions read through the ``mujoco`` package's own compiler.

``mujoco`` is an optional dependency (``pip install "mindyn[mujoco]"``), imported only when an
MJCF is read or written. MuJoCo compiles the file (``<default>`` classes, ``<include>``, angle
units, Euler sequences, inertia from geoms ...); the compiled model is then written as a URDF in
memory, which the core's URDF parser turns into the model (the one model builder), with each
joint's ``armature`` as its rotor inertia ``Ia``, ``damping`` as ``Fv`` and ``frictionloss`` as
``Fc``, and MuJoCo's gravity.

Tendons: a fixed tendon over one joint with coefficient ``c`` (length ``c q``) is folded onto
that joint, exactly as MuJoCo applies it: its ``armature`` adds ``c^2 armature`` to the joint's
``Ia``, its ``damping`` ``c^2 damping`` to ``Fv`` and its ``frictionloss`` ``|c| frictionloss``
to ``Fc``. Fixed tendons over several joints carrying armature, damping or frictionloss are
motors (:func:`motor_tendons`, :func:`_with_tendon_motors`): MuJoCo applies a tendon's armature
as ``armature J^T J`` in the mass matrix, its damping as the force ``-damping J^T (J dq)`` and
its frictionloss as a dry friction of at most ``frictionloss`` on the tendon velocity ``J dq``,
``J`` the tendon's coefficients: the motor-side model's ``T_k^T (Ia_k T_k ddq + Fv_k T_k dq +
Fc_k sign(T_k dq))`` with ``T_k = J``. The model read then has a transmission (format
``mjcf``): a motor per such tendon and a direct motor (ratio 1, the joint's terms) per other
joint, the drive terms on the motors. A spatial tendon carrying such terms is refused by name,
as is tendon stiffness, tendons that are not one motor per joint they turn, and armature on a
tendon turning joints on different branches of the tree (MuJoCo adds it to its mass matrix
only between joints of one branch: :func:`_one_branch`). Tendons
without such terms (outside a differential's), and actuators, do not enter the dynamics and are
not read (but for the effort limits).

Limits: a joint's ``range``; its effort limit from its ``actuatorfrcrange`` and the actuators
driving it through a joint transmission, ``|gear|`` times each one's force bound
(:func:`effort_limits`); its velocity limit, which MJCF lacks, from a custom numeric
``velocity_limit:JOINT`` (:data:`VELOCITY_LIMIT`), as :func:`mindyn.mjcf.write_mjcf` writes it.

A link frame of the model is the MuJoCo body frame moved to the anchor (``pos``) of the body's
last joint, with the body's axes; a body with several joints gets one massless link per joint
before its last one (``BODY__JOINT``; a body of that name is refused by name, as are unnamed
bodies and joints, named by number, whose name another has). Jointless bodies are merged into
the link they hang from.

A free joint (:func:`free_joint`: one, on a body hanging from the world, with every other joint
below that body) is the model's floating joint (Pinocchio's free-flyer) from the world to the
body frame, with no placement: MuJoCo's ``qpos`` of it is the body's pose in the world (the
body's ``pos`` and ``quat`` give only the initial ``qpos0``). The coordinates, checked in the
tests by finite differences of ``mj_integratePos``: MuJoCo's ``qpos`` = ``(p, w, x, y, z)``
and the model's q = ``(p, x, y, z, w)`` (the same position and quaternion); MuJoCo's ``qvel`` =
``(R v, w)`` where the model's v = ``(v, w)``, ``R`` the body's rotation: MuJoCo's linear
velocity is the body origin's in the world axes, the model's in the body's, the angular
velocity in the body's axes in both. The generalised forces are dual: MuJoCo's force is ``R f``
for the model's ``f``, the torque (about the body origin, body axes) the same.

A ball joint is the model's spherical joint at its anchor (written into the URDF text as a
floating joint, which :meth:`Model.with_spherical` then makes spherical: URDF has no ball
joint): MuJoCo's ``qpos`` of it is the quaternion ``(w, x, y, z)``, the model's q ``(x, y, z,
w)``, and the velocity is the angular velocity in the body's axes in both. Free and ball joints
carry no armature, damping, frictionloss or velocity limit (refused by name: the model's joints
of several degrees of freedom have none); a ball joint's cone ``range`` is not read (a warning
names it). A model with a free or ball joint has no rotor inertia or friction in its dynamics:
its hinges' and slides' armature, damping and frictionloss are read as their ``Ia``, ``Fv``,
``Fc`` (and written back), but its mass matrix and inverse dynamics are MuJoCo's without them,
which :func:`mindyn.load` warns, naming them.
"""

from __future__ import annotations

import contextlib
import math
import warnings
import xml.parsers.expat
from pathlib import Path

import numpy as np

from . import _core

#: How to install the optional dependency, for error messages.
INSTALL = 'pip install "mindyn[mujoco]"'
#: The name of a custom numeric (``<custom><numeric name="velocity_limit:JOINT" data="V"/>``)
#: holding a joint's velocity limit [rad/s, m/s], which MJCF has no element for: written by
#: :func:`mindyn.mjcf.write_mjcf`, read back here (MuJoCo keeps it as data, unused).
VELOCITY_LIMIT = "velocity_limit:"


def require(what: str):
    """The ``mujoco`` module, or a one-line error saying that ``what`` needs it."""
    try:
        import mujoco
    except ImportError:
        raise _core.ModelError(f"{what} needs the 'mujoco' package: {INSTALL}") from None
    return mujoco


def root_tag(path) -> str | None:
    """The name of the root element of the XML file ``path`` (``None`` if it cannot be read or
    is not XML): ``mujoco`` for an MJCF, ``robot`` for a URDF."""
    found: list[str] = []
    p = xml.parsers.expat.ParserCreate()

    def first(name, attrs):
        found.append(name)
        raise StopIteration

    p.StartElementHandler = first
    try:
        with open(path, "rb") as f:
            p.ParseFile(f)
    except StopIteration:
        pass
    except (OSError, xml.parsers.expat.ExpatError):
        return None
    return found[0] if found else None


def is_mjcf(path) -> bool:
    """True when ``path`` is an existing XML file whose root element is ``<mujoco>``."""
    return Path(str(path)).is_file() and root_tag(path) == "mujoco"


@contextlib.contextmanager
def warnings_caught(mujoco):
    """MuJoCo's warnings within the block, collected in the list it yields, one text each,
    instead of MuJoCo's own handling (printed, and appended to a file MUJOCO_LOG.TXT in the
    current folder); the handler set before is restored after."""
    said: list[str] = []
    before = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda text: said.append(" ".join(str(text).split())))
    try:
        yield said
    finally:
        mujoco.set_mju_user_warning(before)


def compile_model(path):
    """MuJoCo's compiled model of the MJCF ``path``, or a one-line ModelError with MuJoCo's
    reason. MuJoCo's warnings on the file (a deprecated attribute ...) are Python warnings
    naming it."""
    mujoco = require(f"reading the MJCF '{path}'")
    with warnings_caught(mujoco) as said:
        try:
            model = mujoco.MjModel.from_xml_path(str(path))
        except ValueError as e:
            why = "; ".join(s.strip() for s in str(e).splitlines() if s.strip())
            raise _core.ModelError(f"{path}: MuJoCo cannot compile it: {why}") from None
    for text in said:
        warnings.warn(f"{path}: MuJoCo warns: {text}", stacklevel=2)
    return model


def _name(m, kind, i: int, fallback: str) -> str:
    mujoco = require("reading an MJCF")
    return mujoco.mj_id2name(m, kind, i) or fallback


def body_name(m, b: int) -> str:
    mujoco = require("reading an MJCF")
    return _name(m, mujoco.mjtObj.mjOBJ_BODY, b, "world" if b == 0 else f"body{b}")


def joint_name(m, j: int) -> str:
    mujoco = require("reading an MJCF")
    return _name(m, mujoco.mjtObj.mjOBJ_JOINT, j, f"joint{j}")


def body_joints(m, b: int) -> list[int]:
    start = int(m.body_jntadr[b])
    return list(range(start, start + int(m.body_jntnum[b]))) if start >= 0 else []


def link_name(m, b: int, j: int) -> str:
    """The model's name of the link that joint ``j`` of body ``b`` moves."""
    joints = body_joints(m, b)
    name = body_name(m, b)
    return name if j == joints[-1] else f"{name}__{joint_name(m, j)}"


def last_anchor(m, b: int) -> np.ndarray:
    """Where the link frame of body ``b`` sits in the body frame: its last joint's ``pos``."""
    joints = body_joints(m, b)
    return np.array(m.jnt_pos[joints[-1]], dtype=float) if joints else np.zeros(3)


def check(m, path, joints: set[int] | None = None) -> None:
    """Refuses, in one line naming the element, what the model cannot represent. ``joints``:
    the ids of the joints the model has (a chain to a tip link), default all; what acts only
    on the others, which the chain holds locked at q = 0 clamped into their range (springs,
    equality constraints and tendons over them, gravity compensation of bodies they alone
    move, the terms of ball joints), is not refused; a reference (``ref``) is, on any joint:
    the position it is locked at is in the model's q."""
    require("reading an MJCF")
    chain = set(range(m.njnt)) if joints is None else set(joints)
    if joints is None:
        free_joint(m, path)  # a chain holds at most one free joint, at its root
    _distinct_names(m, path)
    for j in range(m.njnt):
        name, body = joint_name(m, j), body_name(m, int(m.jnt_bodyid[j]))
        where = f"{path}: joint '{name}' (body '{body}')"
        if j not in chain:
            _no_reference(m, j, where)
            continue
        if m.jnt_stiffness[j] != 0:
            raise _core.ModelError(
                f"{where} has a spring (stiffness {float(m.jnt_stiffness[j])!r}); joint "
                "springs are not in the model"
                + (
                    ""
                    if joints is not None
                    else "; a chain to a tip link (tip=) without it locks it"
                )
            )
        dof = int(m.jnt_dofadr[j])
        for key in ("armature", "damping", "frictionloss"):
            value = float(getattr(m, "dof_" + key)[dof])
            if value < 0:
                raise _core.ModelError(
                    f"{where} has {key}={value!r}; rotor inertia and friction are >= 0"
                )
        kind = _multi_dof_kinds().get(int(m.jnt_type[j]))
        if kind:
            _no_drive_terms(m, j, path, kind)
            continue  # its qpos0 is the body's initial pose or the identity, not a reference
        _no_reference(m, j, where)
        b = int(m.jnt_bodyid[j])
        while b != 0:
            if m.body_mocapid[b] >= 0:
                raise _core.ModelError(
                    f"{where} hangs from the mocap body '{body_name(m, b)}', which MuJoCo moves: "
                    "the joints must be on a tree rooted at the fixed world"
                )
            b = int(m.body_parentid[b])
    for e in range(m.neq):
        moved = _equality_joints(m, e)
        if moved is None or moved & chain:
            hint = (
                "; a chain to a tip link (tip=) leaves out the joints off it"
                if joints is None and len(chain - (moved or chain)) > 0
                else ""
            )
            raise _core.ModelError(
                f"{path}: {_equality_label(m, e)}: closed chains and coupled joints are not in "
                f"the model{hint}"
            )
    for t in range(m.ntendon):
        if not _tendon_moved_by(m, t) & chain:
            continue  # over joints the chain holds locked
        terms = tendon_terms(m, t)
        for key, value in terms.items():
            if key in ("armature", "damping", "frictionloss") and value < 0:
                raise _core.ModelError(
                    f"{path}: tendon '{tendon_name(m, t)}' has {key}={float(value)!r}; rotor "
                    "inertia and friction are >= 0"
                )
        given = [f"{k} {float(v)!r}" for k, v in terms.items() if v != 0]
        if not given:
            continue
        where = f"{path}: tendon '{tendon_name(m, t)}'"
        if m.tendon_stiffness[t] != 0:
            raise _core.ModelError(
                f"{where} has a spring (stiffness {float(m.tendon_stiffness[t])!r}); tendon "
                "springs are not in the model"
            )
        if tendon_joints(m, t) is None:
            raise _core.ModelError(
                f"{where} is a spatial tendon and has {', '.join(given)}: only the terms of "
                "fixed tendons are read (over one joint folded onto it, over several a motor)"
            )
    for b in range(1, m.nbody):
        if m.body_gravcomp[b] != 0 and _ancestor_joints(m, b) & chain:
            raise _core.ModelError(
                f"{path}: body '{body_name(m, b)}' has gravcomp={float(m.body_gravcomp[b])!r}; "
                "gravity compensation is not in the model"
            )
    if m.opt.density != 0 or m.opt.viscosity != 0:
        raise _core.ModelError(
            f"{path}: <option density={float(m.opt.density)!r} "
            f"viscosity={float(m.opt.viscosity)!r}>: fluid forces are not in the model"
        )
    if m.nv == 0:
        raise _core.ModelError(f"{path}: no hinge, slide or free joint")


def _no_reference(m, j: int, where: str) -> None:
    """Refuses a hinge or slide joint ``j`` with a reference position (``ref``, MuJoCo's
    ``qpos0``): the model's q is MuJoCo's qpos only without one."""
    mujoco = require("reading an MJCF")
    if _multi_dof_kinds().get(int(m.jnt_type[j])):
        return  # its qpos0 is the body's initial pose or the identity, not a reference
    if m.qpos0[m.jnt_qposadr[j]] != 0:
        hinge = int(m.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_HINGE)
        unit = "rad (an angle of the file in degrees, the default unit, is compiled to it)"
        raise _core.ModelError(
            f"{where} has ref={float(m.qpos0[m.jnt_qposadr[j]])!r} {unit if hinge else 'm'}; "
            "the model's q is MuJoCo's qpos only with ref=0"
        )


def _ancestor_joints(m, b: int) -> set[int]:
    """The joints moving body ``b``: its own and those of the bodies it hangs from."""
    out: set[int] = set()
    while b > 0:
        out.update(body_joints(m, b))
        b = int(m.body_parentid[b])
    return out


def _joints_between(m, bodies: list[int]) -> set[int]:
    """The joints that move the ``bodies`` relative to each other (on the tree's paths
    between them; the world is body 0)."""
    if not bodies:
        return set()
    first = _ancestor_joints(m, bodies[0])
    out: set[int] = set()
    for b in bodies[1:]:
        out |= first ^ _ancestor_joints(m, b)
    return out


def _tendon_moved_by(m, t: int) -> set[int]:
    """The joints that change the length of tendon ``t``: a fixed tendon's joints, or those
    moving the bodies of a spatial tendon's sites and wrapping geoms relative to each other."""
    mujoco = require("reading an MJCF")
    adr, num = int(m.tendon_adr[t]), int(m.tendon_num[t])
    joints, bodies = set(), []
    for w in range(adr, adr + num):
        kind, obj = int(m.wrap_type[w]), int(m.wrap_objid[w])
        if kind == int(mujoco.mjtWrap.mjWRAP_JOINT):
            joints.add(obj)
        elif kind == int(mujoco.mjtWrap.mjWRAP_SITE):
            bodies.append(int(m.site_bodyid[obj]))
        elif obj >= 0:  # a wrapping sphere or cylinder
            bodies.append(int(m.geom_bodyid[obj]))
    return joints | _joints_between(m, bodies)


def _equality_joints(m, e: int) -> set[int] | None:
    """The joints equality constraint ``e`` acts on (its joints, its tendons' joints, or those
    moving its two bodies or sites relative to each other); ``None`` for other kinds."""
    mujoco = require("reading an MJCF")
    kind, a, b = int(m.eq_type[e]), int(m.eq_obj1id[e]), int(m.eq_obj2id[e])
    eq = mujoco.mjtEq
    if kind == int(eq.mjEQ_JOINT):
        return {j for j in (a, b) if j >= 0}
    if kind == int(eq.mjEQ_TENDON):
        return set().union(*(_tendon_moved_by(m, t) for t in (a, b) if t >= 0))
    if kind in (int(eq.mjEQ_CONNECT), int(eq.mjEQ_WELD)):
        sites = int(getattr(m, "eq_objtype", [0] * m.neq)[e]) == int(mujoco.mjtObj.mjOBJ_SITE)
        bodies = [int(m.site_bodyid[x]) if sites else x for x in (a, b) if x >= 0]
        return _joints_between(m, bodies + [0] * (len(bodies) < 2))
    return None


def _equality_label(m, e: int) -> str:
    """Equality constraint ``e`` as the file writes it: its name or number, its kind and the
    elements it ties (``equality 0 <joint joint1="a" joint2="b">``)."""
    mujoco = require("reading an MJCF")
    kind = int(m.eq_type[e])
    tag = mujoco.mjtEq(kind).name[len("mjEQ_") :].lower()
    objects = {
        int(mujoco.mjtEq.mjEQ_JOINT): (mujoco.mjtObj.mjOBJ_JOINT, "joint"),
        int(mujoco.mjtEq.mjEQ_TENDON): (mujoco.mjtObj.mjOBJ_TENDON, "tendon"),
    }
    if kind in objects:
        obj, key = objects[kind]
    elif int(getattr(m, "eq_objtype", [0] * m.neq)[e]) == int(mujoco.mjtObj.mjOBJ_SITE):
        obj, key = mujoco.mjtObj.mjOBJ_SITE, "site"
    else:
        obj, key = mujoco.mjtObj.mjOBJ_BODY, "body"
    attrs = []
    for i, x in enumerate((int(m.eq_obj1id[e]), int(m.eq_obj2id[e])), start=1):
        if x >= 0:
            attrs.append(f'{key}{i}="{mujoco.mj_id2name(m, obj, x) or f"{key}{x}"}"')
    name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_EQUALITY, e)
    return f"equality {repr(name) if name else e} <{tag} {' '.join(attrs)}>"


def _distinct_names(m, path) -> None:
    """Refuses, naming them, two links of the model with one name: a body named as the link of
    one of another body's several joints (``BODY__JOINT``), or an unnamed body or joint whose
    name by number (``body3``, ``joint2``) another has."""
    mujoco = require("reading an MJCF")
    seen: dict[str, str] = {}
    for b in range(1, m.nbody):
        for j in body_joints(m, b)[:-1] + [None]:
            name = body_name(m, b) if j is None else link_name(m, b, j)
            if j is not None:
                what = f"the link of joint '{joint_name(m, j)}' of body '{body_name(m, b)}'"
            else:
                what = f"body '{name}'" if _named_body(m, b) else f"unnamed body {b}"
            if name in seen:
                raise _core.ModelError(
                    f"{path}: {seen[name]} and {what} are both '{name}' in the model (a body of "
                    "several joints has a link per joint before its last, named BODY__JOINT; "
                    "an unnamed body or joint is named by its number): rename one"
                )
            seen[name] = what
    joints: dict[str, int] = {}
    for j in range(m.njnt):
        name = joint_name(m, j)
        if name in joints:
            unnamed = joints[name] if mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) else j
            raise _core.ModelError(
                f"{path}: joint '{name}' and unnamed joint {unnamed} "
                f"are both '{name}' in the model (an unnamed joint is named by its number): "
                "name it"
            )
        joints[name] = j


def _named_body(m, b: int) -> bool:
    mujoco = require("reading an MJCF")
    return bool(mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b))


def free_joint(m, path) -> int | None:
    """The id of the model's free joint (None if none), checked to be what the model's floating
    base is: one free joint, on a body hanging from the world, every other joint below that
    body, with no armature, damping or frictionloss (refused by name otherwise)."""
    mujoco = require("reading an MJCF")
    free = [j for j in range(m.njnt) if int(m.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_FREE)]
    if not free:
        return None

    def where(j: int) -> str:
        return f"joint '{joint_name(m, j)}' (body '{body_name(m, int(m.jnt_bodyid[j]))}')"

    if len(free) > 1:
        raise _core.ModelError(
            f"{path}: {where(free[0])} and {where(free[1])} are both free joints: one floating "
            "base is read, not several free bodies"
        )
    j = free[0]
    b = int(m.jnt_bodyid[j])
    if int(m.body_parentid[b]) != 0:
        raise _core.ModelError(
            f"{path}: free {where(j)} is below body '{body_name(m, int(m.body_parentid[b]))}': "
            "a floating base is a free joint on a body hanging from the world"
        )
    for other in range(m.njnt):
        a = int(m.jnt_bodyid[other])
        while a not in (0, b):
            a = int(m.body_parentid[a])
        if a != b:
            raise _core.ModelError(
                f"{path}: {where(other)} is not below the free body '{body_name(m, b)}': a "
                "floating base carries every joint (none may hang from the world beside it)"
            )
    return j


def _no_drive_terms(m, j: int, path, kind: str) -> None:
    """Refuses armature, damping or frictionloss on the free or ball joint ``j``: the model's
    joints of several degrees of freedom have no rotor inertia or friction."""
    start = int(m.jnt_dofadr[j])
    dofs = slice(start, start + (6 if kind == "free" else 3))
    for key in ("armature", "damping", "frictionloss"):
        values = np.asarray(getattr(m, f"dof_{key}")[dofs], dtype=float)
        if np.any(values != 0):
            raise _core.ModelError(
                f"{path}: {kind} joint '{joint_name(m, j)}' (body "
                f"'{body_name(m, int(m.jnt_bodyid[j]))}') has {key} "
                f"{float(values[values != 0][0])!r}: the model's {kind} joints have no rotor "
                "inertia or friction"
            )


def _multi_dof_kinds() -> dict[int, str]:
    mujoco = require("reading an MJCF")
    return {int(mujoco.mjtJoint.mjJNT_FREE): "free", int(mujoco.mjtJoint.mjJNT_BALL): "ball"}


def read(path, tip: str | None) -> _core.Model:
    """The core model of the MJCF ``path`` (``tip`` as for a URDF)."""
    mujoco = require(f"reading the MJCF '{path}'")
    m = compile_model(path)
    if tip:
        _distinct_names(m, path)  # the links of the URDF text below, checked before it
    else:
        check(m, path)
    disabled = int(m.opt.disableflags)
    flags = mujoco.mjtDisableBit
    damper = getattr(flags, "mjDSBL_DAMPER", None) or flags.mjDSBL_PASSIVE
    frictionloss = int(flags.mjDSBL_FRICTIONLOSS) | int(flags.mjDSBL_CONSTRAINT)
    armature, damping, friction = joint_terms(m)
    if disabled & int(damper):
        damping[:] = 0.0
    if disabled & frictionloss:
        friction[:] = 0.0
    urdf = _urdf(m, _model_name(m, path), damping, friction, velocity_limits(m, path))
    core = _core.parse_urdf(urdf, tip or "", str(path))
    if tip:  # the chain's joints; those off it are held at the file's pose
        ids = {joint_name(m, j): j for j in range(m.njnt)}
        check(m, path, {ids[name] for name in core.joint_names})
    ball = int(mujoco.mjtJoint.mjJNT_BALL)
    balls = {joint_name(m, j) for j in range(m.njnt) if int(m.jnt_type[j]) == ball}
    if balls & set(core.joint_names):  # written as floating joints: URDF has no ball joint
        core = core.with_spherical(sorted(balls & set(core.joint_names)))
    gravity = np.zeros(3) if disabled & int(flags.mjDSBL_GRAVITY) else np.array(m.opt.gravity)
    core = core.with_gravity(gravity)
    by_name = {joint_name(m, j): float(armature[j]) for j in range(m.njnt)}
    core.rotor_inertia = np.array([by_name[name] for name in core.joint_names])
    if not core.single_dof:
        _ball_ranges(m, core, path)
    scale = (1.0, 0.0 if disabled & int(damper) else 1.0, 0.0 if disabled & frictionloss else 1.0)
    return _with_tendon_motors(m, core, path, (armature, damping, friction), scale)


def _ball_ranges(m, core: _core.Model, path) -> None:
    """A warning naming the ball joints of the model with a ``range`` (MuJoCo's cone limit on
    the joint's rotation angle), which the model's spherical joints have no place for."""
    mujoco = require("reading an MJCF")
    ball = int(mujoco.mjtJoint.mjJNT_BALL)
    names = set(core.joint_names)
    limited = [
        f"'{joint_name(m, j)}' ({math.degrees(float(m.jnt_range[j][1])):.6g} deg)"
        for j in range(m.njnt)
        if int(m.jnt_type[j]) == ball and bool(m.jnt_limited[j]) and joint_name(m, j) in names
    ]
    if limited:
        warnings.warn(
            f"{path}: the range of ball joint(s) {', '.join(limited)}, a cone limit on the "
            "rotation angle, is not read: the model's spherical joints have no limits",
            stacklevel=2,
        )


def tendon_name(m, t: int) -> str:
    mujoco = require("reading an MJCF")
    return _name(m, mujoco.mjtObj.mjOBJ_TENDON, t, f"tendon{t}")


def tendon_joints(m, t: int) -> list[tuple[int, float]] | None:
    """The joints of fixed tendon ``t`` with their non-zero coefficients (its length is
    ``sum c q``), or ``None`` for a spatial tendon."""
    mujoco = require("reading an MJCF")
    adr, num = int(m.tendon_adr[t]), int(m.tendon_num[t])
    if any(int(m.wrap_type[w]) != int(mujoco.mjtWrap.mjWRAP_JOINT) for w in range(adr, adr + num)):
        return None
    return [
        (int(m.wrap_objid[w]), float(m.wrap_prm[w]))
        for w in range(adr, adr + num)
        if m.wrap_prm[w] != 0
    ]


def tendon_terms(m, t: int) -> dict[str, float]:
    armature = getattr(m, "tendon_armature", None)  # MuJoCo 3.3.1 and later
    return {
        "stiffness": float(m.tendon_stiffness[t]),
        "armature": 0.0 if armature is None else float(armature[t]),
        "damping": float(m.tendon_damping[t]),
        "frictionloss": float(m.tendon_frictionloss[t]),
    }


def motor_tendons(m) -> list[int]:
    """The fixed tendons over several joints read as motors: those carrying armature, damping
    or frictionloss, and the fixed tendons over several joints that share a joint with them (a
    differential's other motor, whose terms may be zero)."""
    multi = {t: tendon_joints(m, t) for t in range(m.ntendon)}
    over = {t: {j for j, _ in w} for t, w in multi.items() if w is not None and len(w) > 1}
    chosen = {t for t in over if any(v != 0 for v in tendon_terms(m, t).values())}
    joints = set().union(*(over[t] for t in chosen)) if chosen else set()
    grew = bool(chosen)
    while grew:
        grew = False
        for t, js in over.items():
            if t not in chosen and js & joints:
                chosen.add(t)
                joints |= js
                grew = True
    return sorted(chosen)


def _with_tendon_motors(m, core, path, terms: tuple[np.ndarray, np.ndarray, np.ndarray], scale):
    """``core`` with the transmission of the motor tendons (:func:`motor_tendons`): a motor per
    such tendon, its row of ``T`` the tendon's coefficients and its ``Ia``, ``Fv``, ``Fc`` the
    tendon's ``armature``, ``damping`` and ``frictionloss`` (times ``scale``: 0 for a term
    ``<option>`` disables), which MuJoCo applies as ``T_k^T armature T_k`` in the mass matrix,
    ``-damping T_k^T (T_k dq)`` and a dry friction of at most ``frictionloss`` on the tendon
    velocity: the motor-side model's terms exactly. A joint that no such tendon turns, or that
    has terms of its own (``terms``: armature, damping, frictionloss by joint id; a four-bar
    linkage's first motor), is driven directly by a motor named after it (ratio 1) with those
    terms; a tendon joint the rows leave undetermined gets such a motor without terms. Refused
    by name: a model with free or ball joints, a tendon joint outside the model, and motors
    that are not one per joint (or whose rows do not determine the joints)."""
    names = list(core.joint_names)
    # a tendon over joints off a chain (loaded with a tip), which it holds locked, moves nothing
    tendons = [
        t
        for t in motor_tendons(m)
        if any(joint_name(m, j) in names for j, _ in tendon_joints(m, t) or [])
    ]
    if not tendons:
        return core
    index = {name: k for k, name in enumerate(names)}
    n = len(names)
    first = f"{path}: tendon '{tendon_name(m, tendons[0])}'"
    if not core.single_dof:
        raise _core.ModelError(
            f"{first} couples joints and carries motor terms, but the model has free or ball "
            "joints, which no motor drives (their drive terms act on the joints): put the "
            "terms on the joints"
        )
    rows, motors, types, values = [], [], [], []
    covered: dict[str, str] = {}  # joint -> a tendon turning it
    for t in tendons:
        row = np.zeros(n)
        tname = tendon_name(m, t)
        for j, c in tendon_joints(m, t) or []:
            jname = joint_name(m, j)
            if jname not in index:
                raise _core.ModelError(
                    f"{path}: tendon '{tname}' turns joint '{jname}', which is not in the model "
                    "(loaded with a tip): its motor cannot be read"
                )
            row[index[jname]] = c
            covered.setdefault(jname, tname)
        tt = tendon_terms(m, t)
        if tt["armature"] != 0:
            _one_branch(m, t, path)
        rows.append(row)
        motors.append(tname)
        types.append("tendon")
        values.append([tt[k] * f for k, f in zip(("armature", "damping", "frictionloss"), scale)])
    ids = {joint_name(m, j): j for j in range(m.njnt)}

    def direct(k: int) -> None:
        row = np.zeros(n)
        row[k] = 1.0
        rows.append(row)
        motors.append(names[k])
        types.append("direct")
        values.append([float(v[ids[names[k]]]) for v in terms])

    # a joint with terms of its own, or turned by no motor tendon, is driven directly (ratio 1)
    for k, jname in enumerate(names):
        if jname not in covered or any(v[ids[jname]] != 0 for v in terms):
            direct(k)
    # a tendon joint the rows leave undetermined: a direct motor without terms (a four-bar
    # linkage's first motor whose terms are all zero), which changes no dynamics
    for k, jname in enumerate(names):
        if len(rows) < n and jname in covered and motors.count(jname) == 0:
            if np.linalg.matrix_rank(np.array(rows + [np.eye(n)[k]])) > np.linalg.matrix_rank(
                np.array(rows)
            ):
                direct(k)
                values[-1] = [0.0, 0.0, 0.0]
    extra = [x for x in motors[len(tendons) :] if x in covered]
    said = (
        f"{path}: tendons {', '.join(repr(x) for x in motors[: len(tendons)])} carry motor "
        f"terms: with the joints' own terms"
        + (f" (on {', '.join(repr(x) for x in extra)})" if extra else "")
    )
    if len(rows) != n:
        raise _core.ModelError(
            f"{said} that is {len(rows)} motors for {n} joints, and the model reads motors "
            "only one per joint (put the terms either on the tendons or on the joints)"
        )
    try:
        core = core.with_transmission(T=np.array(rows), motors=motors, types=types, format="mjcf")
    except _core.ModelError as e:  # rows that do not determine the joints
        raise _core.ModelError(
            f"{said} as motors, {e} (put the terms either on the tendons or on the joints)"
        ) from None
    values_ = np.array(values)
    return core.with_joint_terms(
        motor_rotor=values_[:, 0], motor_viscous=values_[:, 1], motor_coulomb=values_[:, 2]
    )


def _one_branch(m, t: int, path) -> None:
    """Refuses the motor tendon ``t`` carrying armature when two of its joints are on different
    branches of the tree (neither moves the other): MuJoCo adds a tendon's armature to its
    joint-space inertia only where that matrix has entries, between joints of one branch, so
    its dynamics then have no ``J^T armature J``, the motor's inertia (they drop its terms
    between the branches)."""
    joints = [j for j, _ in tendon_joints(m, t) or []]

    def chain(j: int) -> set[int]:  # the dof of joint j and those of the joints moving it
        out, dof = set(), int(m.jnt_dofadr[j])
        while dof >= 0:
            out.add(dof)
            dof = int(m.dof_parentid[dof])
        return out

    for a in joints:
        for b in joints:
            if a < b and int(m.jnt_dofadr[a]) not in chain(b):
                if int(m.jnt_dofadr[b]) not in chain(a):
                    raise _core.ModelError(
                        f"{path}: tendon '{tendon_name(m, t)}' has armature "
                        f"{float(m.tendon_armature[t])!r} and turns joints '{joint_name(m, a)}' "
                        f"and '{joint_name(m, b)}', on different branches of the tree: MuJoCo "
                        "adds a tendon's armature to its mass matrix only between joints of "
                        "one branch, not as the motor inertia J^T armature J (put the armature "
                        "on the joints, or couple joints of one branch)"
                    )


def folded_tendons(m) -> list[int]:
    """The tendons whose armature, damping or frictionloss are folded onto their one joint."""
    out = []
    for t in range(m.ntendon):
        terms = tendon_terms(m, t)
        wraps = tendon_joints(m, t)
        if wraps is not None and len(wraps) == 1 and any(v != 0 for v in terms.values()):
            out.append(t)
    return out


def joint_terms(m) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Armature, damping and frictionloss acting on each joint (by joint id): the joint's own
    plus ``c^2 armature``, ``c^2 damping``, ``|c| frictionloss`` of each fixed tendon over it
    alone with coefficient ``c`` (what MuJoCo applies through such a tendon)."""
    dof = np.asarray(m.jnt_dofadr, dtype=int)
    armature = np.array(m.dof_armature, dtype=float)[dof]
    damping = np.array(m.dof_damping, dtype=float)[dof]
    friction = np.array(m.dof_frictionloss, dtype=float)[dof]
    for t in folded_tendons(m):
        joints = tendon_joints(m, t)
        assert joints is not None  # a folded tendon is fixed
        ((j, c),) = joints
        terms = tendon_terms(m, t)
        armature[j] += c * c * terms["armature"]
        damping[j] += c * c * terms["damping"]
        friction[j] += abs(c) * terms["frictionloss"]
    return armature, damping, friction


def _model_name(m, path) -> str:
    """The ``model`` attribute of ``<mujoco>`` (MuJoCo's default name replaced by the file's
    stem)."""
    name = bytes(m.names).split(b"\0")[0].decode("utf-8", "replace")
    return name if name and name != "MuJoCo Model" else Path(str(path)).stem


def velocity_limits(m, path) -> np.ndarray:
    """Each joint's velocity limit (by joint id; 0: none) from the custom numerics
    ``velocity_limit:JOINT`` (:data:`VELOCITY_LIMIT`); one naming no joint, or whose data is
    not one positive finite number, is refused by name."""
    mujoco = require("reading an MJCF")
    out = np.zeros(m.njnt)
    joints = {joint_name(m, j): j for j in range(m.njnt)}
    for i in range(m.nnumeric):
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_NUMERIC, i) or ""
        if not name.startswith(VELOCITY_LIMIT):
            continue
        joint = name[len(VELOCITY_LIMIT) :]
        adr, size = int(m.numeric_adr[i]), int(m.numeric_size[i])
        data = [float(v) for v in m.numeric_data[adr : adr + size]]
        if joint not in joints:
            raise _core.ModelError(
                f"{path}: <numeric name=\"{name}\">: no joint '{joint}' (a velocity limit is "
                f"named {VELOCITY_LIMIT}<joint>)"
            )
        kind = _multi_dof_kinds().get(int(m.jnt_type[joints[joint]]))
        if kind:
            raise _core.ModelError(
                f"{path}: <numeric name=\"{name}\">: '{joint}' is a {kind} joint, which has no "
                "velocity limit in the model (hinge and slide joints have)"
            )
        if len(data) != 1 or not (math.isfinite(data[0]) and data[0] > 0):
            raise _core.ModelError(
                f'{path}: <numeric name="{name}">: expected one positive velocity limit, got '
                f"data {' '.join(f'{v:g}' for v in data) or '(none)'}"
            )
        out[joints[joint]] = data[0]
    return out


def _symmetric(lo: float, hi: float) -> float:
    """The bound ``E`` of a force range ``[lo, hi]`` as an effort limit, ``|tau| <= E``: the
    force reached in both directions, ``min(|lo|, |hi|)``; 0 (none) for a range that does not
    hold 0 strictly inside."""
    return min(-lo, hi) if lo < 0 < hi else 0.0


def _actuator_bound(m, a: int) -> float | None:
    """The largest force actuator ``a`` applies in both directions (:func:`_symmetric`), or
    ``None`` when it has no bound: its ``forcerange`` when force-limited and, for an actuator
    whose force is its control times a fixed gain (a ``<motor>``, a ``<general>`` without bias
    or activation dynamics), the gain times its ``ctrlrange`` when control-limited; the
    tighter of the two."""
    mujoco = require("reading an MJCF")
    bounds = []
    if m.actuator_forcelimited[a]:
        bounds.append(_symmetric(*(float(v) for v in m.actuator_forcerange[a])))
    plain = (
        int(m.actuator_gaintype[a]) == int(mujoco.mjtGain.mjGAIN_FIXED)
        and int(m.actuator_biastype[a]) == int(mujoco.mjtBias.mjBIAS_NONE)
        and int(m.actuator_dyntype[a]) == int(mujoco.mjtDyn.mjDYN_NONE)
    )
    if plain and m.actuator_ctrllimited[a]:
        gain = float(m.actuator_gainprm[a][0])
        lo, hi = sorted(gain * float(v) for v in m.actuator_ctrlrange[a])
        bounds.append(_symmetric(lo, hi))
    return min(bounds) if bounds else None


def effort_limits(m) -> np.ndarray:
    """Each joint's effort limit (by joint id; 0: none), ``|tau| <= E`` as a URDF's ``<limit
    effort>``: the tighter of its ``actuatorfrcrange`` (to which MuJoCo clamps the sum of the
    actuator forces on the joint) and the sum over the actuators driving it through a joint
    transmission (``joint=``) of ``|gear|`` times each one's bound (:func:`_actuator_bound`),
    each range taken as the force reached in both directions, ``min(|lo|, |hi|)``. The
    actuators give no limit to a joint one of them leaves unbounded, or that an actuator
    through a tendon over it also drives (its share of the tendon force is no joint limit);
    actuators through sites, bodies or a slider-crank are not read."""
    mujoco = require("reading an MJCF")
    direct = (int(mujoco.mjtTrn.mjTRN_JOINT), int(mujoco.mjtTrn.mjTRN_JOINTINPARENT))
    total = np.zeros(m.njnt)
    unbounded = np.zeros(m.njnt, dtype=bool)
    driven = np.zeros(m.njnt, dtype=bool)
    for a in range(m.nu):
        kind, target = int(m.actuator_trntype[a]), int(m.actuator_trnid[a][0])
        if kind in direct:
            bound = _actuator_bound(m, a)
            driven[target] = True
            if bound is None:
                unbounded[target] = True
            else:
                total[target] += abs(float(m.actuator_gear[a][0])) * bound
        elif kind == int(mujoco.mjtTrn.mjTRN_TENDON):
            for j, _ in tendon_joints(m, target) or []:
                unbounded[j] = True  # no per-joint bound
    out = np.where(driven & ~unbounded, total, 0.0)
    for j in range(m.njnt):
        if m.jnt_actfrclimited[j]:
            own = _symmetric(*(float(v) for v in m.jnt_actfrcrange[j]))
            if own > 0:
                out[j] = min(own, out[j]) if out[j] > 0 else own
    return out


def _urdf(m, name: str, damping: np.ndarray, friction: np.ndarray, speed: np.ndarray) -> str:
    """The compiled model ``m`` as URDF text (see the module's docstring), with the viscous and
    Coulomb friction and the velocity limit (0: none) of each joint (by joint id)."""
    mujoco = require("reading an MJCF")
    efforts = effort_limits(m)
    hinge = int(mujoco.mjtJoint.mjJNT_HINGE)
    parts = [f'<robot name="{_attr(name)}">', f'<link name="{_attr(body_name(m, 0))}"/>']
    link_of = {0: body_name(m, 0)}
    taken = {joint_name(m, j) for j in range(m.njnt)}  # a merged body's joint: a name of its own
    for b in range(1, m.nbody):
        p = int(m.body_parentid[b])
        if m.body_mocapid[b] >= 0 or p not in link_of:
            continue  # a mocap body and what hangs from it: no joint there (checked), not robot

        # from the parent's link frame
        pre = _translation(-last_anchor(m, p)) @ _pose(m.body_pos[b], m.body_quat[b])
        parent = link_of[p]
        joints = body_joints(m, b)
        if not joints:
            link = body_name(m, b)
            parts.append(_link(link, m, b, np.zeros(3)))
            fixed = f"{link}__fixed"
            while fixed in taken:
                fixed += "_"
            taken.add(fixed)
            parts.append(_joint(fixed, "fixed", parent, link, pre))
            link_of[b] = link
            continue
        previous = np.zeros(3)
        for j in joints:
            link = link_name(m, b, j)
            if int(m.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_FREE):  # the body's only joint
                # qpos is the body's pose in the world: no placement (pos, quat: qpos0 only)
                parts.append(_link(link, m, b, np.zeros(3)))
                parts.append(_joint(joint_name(m, j), "floating", parent, link, np.eye(4)))
                parent = link
                continue
            origin = (pre if j == joints[0] else np.eye(4)) @ _translation(m.jnt_pos[j] - previous)
            previous = np.array(m.jnt_pos[j], dtype=float)
            last = j == joints[-1]
            parts.append(_link(link, m, b if last else None, previous))
            if int(m.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_BALL):  # made spherical by read()
                parts.append(_joint(joint_name(m, j), "floating", parent, link, origin))
                parent = link
                continue
            lo, hi = (float(v) for v in m.jnt_range[j])
            limited = bool(m.jnt_limited[j])
            kind = "prismatic" if int(m.jnt_type[j]) != hinge else "revolute"
            if kind == "revolute" and not limited:
                kind = "continuous"
            limit = f'lower="{lo!r}" upper="{hi!r}" ' if limited else ""
            effort = float(efforts[j])
            extra = (
                f'<axis xyz="{_vec(m.jnt_axis[j])}"/>'
                f'<limit {limit}effort="{effort!r}" velocity="{float(speed[j])!r}"/>'
                f'<dynamics damping="{float(damping[j])!r}" friction="{float(friction[j])!r}"/>'
            )
            parts.append(_joint(joint_name(m, j), kind, parent, link, origin, extra))
            parent = link
        link_of[b] = parent
    parts.append("</robot>")
    return "\n".join(parts)


def _link(name: str, m, b: int | None, anchor: np.ndarray) -> str:
    """A URDF link holding body ``b``'s inertia (none: massless), its frame at ``anchor`` in the
    body frame."""
    if b is None:
        inertia, com, mass = np.zeros((3, 3)), np.zeros(3), 0.0
    else:
        R = _rotation(m.body_iquat[b])
        inertia = R @ np.diag(np.asarray(m.body_inertia[b], dtype=float)) @ R.T
        com = np.asarray(m.body_ipos[b], dtype=float) - anchor
        mass = float(m.body_mass[b])
    values = (inertia[0, 0], inertia[0, 1], inertia[0, 2], inertia[1, 1], inertia[1, 2])
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz")
    tensor = " ".join(f'{k}="{float(v)!r}"' for k, v in zip(keys, values))
    return (
        f'<link name="{_attr(name)}"><inertial><origin xyz="{_vec(com)}" rpy="0 0 0"/>'
        f'<mass value="{mass!r}"/>'
        f'<inertia {tensor} izz="{float(inertia[2, 2])!r}"/></inertial></link>'
    )


def _joint(name, kind, parent, child, origin, extra: str = "") -> str:
    return (
        f'<joint name="{_attr(name)}" type="{kind}"><parent link="{_attr(parent)}"/>'
        f'<child link="{_attr(child)}"/><origin xyz="{_vec(origin[:3, 3])}" '
        f'rpy="{_vec(rpy(origin[:3, :3]))}"/>{extra}</joint>'
    )


def _attr(text: str) -> str:
    return (
        text.replace("&", "&amp;").replace('"', "&quot;").replace("<", "&lt;").replace(">", "&gt;")
    )


def _vec(v) -> str:
    return " ".join(repr(float(x)) for x in v)


def _translation(p) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = p
    return T


def _pose(pos, quat) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = _rotation(quat)
    T[:3, 3] = pos
    return T


def _rotation(quat) -> np.ndarray:
    """The rotation matrix of a quaternion ``(w, x, y, z)`` (MuJoCo's order), normalised."""
    w, x, y, z = np.asarray(quat, dtype=float) / np.linalg.norm(quat)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def quaternion(R) -> np.ndarray:
    """The unit quaternion ``(w, x, y, z)`` of the rotation matrix ``R`` (Shepperd's method:
    from its largest component), with ``w >= 0``."""
    R = np.asarray(R, dtype=float)
    t = np.trace(R)
    cands = [t, R[0, 0], R[1, 1], R[2, 2]]
    i = int(np.argmax(cands))
    if i == 0:
        s = 2.0 * math.sqrt(1.0 + t)
        q = [s / 4, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s]
    elif i == 1:
        s = 2.0 * math.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2])
        q = [(R[2, 1] - R[1, 2]) / s, s / 4, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s]
    elif i == 2:
        s = 2.0 * math.sqrt(1.0 + R[1, 1] - R[0, 0] - R[2, 2])
        q = [(R[0, 2] - R[2, 0]) / s, (R[0, 1] + R[1, 0]) / s, s / 4, (R[1, 2] + R[2, 1]) / s]
    else:
        s = 2.0 * math.sqrt(1.0 + R[2, 2] - R[0, 0] - R[1, 1])
        q = [(R[1, 0] - R[0, 1]) / s, (R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, s / 4]
    q = np.array(q)
    return -q if q[0] < 0 else q


def rpy(R) -> np.ndarray:
    """URDF roll, pitch, yaw of ``R = Rz(yaw) Ry(pitch) Rx(roll)``: the yaw first, then pitch
    and roll from ``Rz(-yaw) R``, so that the angles give ``R`` back to round-off also at and
    near pitch = +-pi/2, where roll and yaw are ill-determined (only their sum or difference
    is)."""
    R = np.asarray(R, dtype=float)
    yaw = math.atan2(R[1, 0], R[0, 0])
    s, c = math.sin(yaw), math.cos(yaw)
    pitch = math.atan2(-R[2, 0], c * R[0, 0] + s * R[1, 0])
    roll = math.atan2(s * R[0, 2] - c * R[1, 2], c * R[1, 1] - s * R[0, 1])
    return np.array([roll, pitch, yaw])
