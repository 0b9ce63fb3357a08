"""Robot models: loading by name or path, and the linear-in-parameters dynamics.

Every per-sample method takes one sample, arrays of shape ``(n,)``, or a batch of ``m`` samples,
arrays of shape ``(m, n)``, and returns the matching shape. Parameter vectors follow the classical
layout ``[XX1 XY1 XZ1 YY1 YZ1 ZZ1 MX1 MY1 MZ1 M1 (Ia1) (Fv1 Fc1 (F31)) XX2 ...]``: inertial
parameters about each link-frame origin, optionally followed per joint by rotor inertia and the
friction parameters of the robot's friction model (:attr:`Robot.friction_model`: viscous and
Coulomb, and a third, ``Fa`` or ``Fs``, for the asymmetric and Stribeck models). A vector's
layout is recognised from its length (10n, 11n with ``Ia``, (10 + c) n with the ``c`` friction
columns, (11 + c) n with all).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from . import _args, _core, _mujoco, _sidecar, _urdf_forms

#: The friction models of :meth:`Robot.with_friction_model`.
FRICTION_KINDS = ("coulomb", "asymmetric", "smooth", "stribeck")

__all__ = ["DriveTrainWarning", "Robot", "Transmission", "as_robot", "load", "bundled_robots"]

_PLANAR = re.compile(r"planar([0-9]+)(h?)")
# Most joints of a model, as the core's kMaxModelJoints (a test keeps the two equal); checked here
# too so that a number too large for a C++ int gets the same message.
_MAX_JOINTS = 1000


_NO_PARAMS = object()  # a multibody function that takes no parameter vector
_SINGLE_DOF = ("revolute", "prismatic")
# (start, size, nq) of the unit-norm block of a joint's configuration; nq of the other kinds
_UNIT_BLOCKS = {"floating": (3, 4, 7), "spherical": (0, 4, 4), "planar": (2, 2, 4)}
_NQ = {"universal": 2, "cylindrical": 2}
_FRAMES = ("world", "local")  # the axes of a Jacobian's rows (Robot.jacobian)


def bundled_robots() -> list[str]:
    """Names accepted by :func:`load` besides file paths (``planar<N>`` for 1 <= N <= 1000)."""
    names = sorted(p.stem for p in _robot_dir().iterdir() if p.suffix == ".yaml")
    return names + ["planar<N>", "planar<N>h"]


def _robot_dir() -> Path:
    return Path(str(resources.files("mindyn") / "robots"))


def load(
    robot: Robot | str | Path,
    *,
    tip: str | None = None,
    gravity=None,
    root_joint: str | None = None,
    joint_terms=None,
) -> Robot:
    """Load a robot.

    Parameters
    ----------
    robot : str or Path
        A bundled name (``puma560``, ``puma560_3``, ``zcr07s``, ``stanford``, ``planar<N>`` for a
        vertical-plane N-link arm, ``planar<N>h`` for a horizontal one, 1 <= N <= 1000), a URDF
        file (``.urdf``, ``.xml``), a MuJoCo MJCF (``.xml`` whose root is ``<mujoco>``, compiled
        by the optional ``mujoco`` package: hinge and slide joints, ball joints as spherical
        joints and a free joint on the root body as the floating base, ``armature``,
        ``damping`` and ``frictionloss`` as ``Ia``, ``Fv``, ``Fc``, MuJoCo's gravity) or a
        YAML DH / MDH
        table (``.yaml``, ``.yml``).
    tip : str, optional
        URDF and MJCF only: the link that ends the serial chain root -> tip; moving joints off
        it are locked at ``q = 0`` (clamped into their limits) and merged. Without it the whole
        description is loaded: a tree when it branches (:attr:`Robot.parents`), its joints
        numbered depth-first from the root, the children of a link in the order of their joint
        names (Pinocchio's order). Mimic joints that end a branch are then locked and merged
        (see ``notes``).
    root_joint : {"floating", "planar"}, optional
        URDF only: a free-flyer (floating base) or planar joint ``root_joint`` between a base
        link ``world`` and the root link, which becomes the first moving body (Pinocchio's
        ``buildModel`` with a ``JointModelFreeFlyer`` or ``JointModelPlanar`` root). Such a
        robot and one with ``floating``, ``planar`` (URDF) or ``spherical``, ``universal``,
        ``cylindrical`` joints (YAML) has ``nq`` configuration and ``nv`` velocity entries
        (Pinocchio's conventions: quaternions ``(x, y, z, w)``, a free-flyer's velocity linear first
        in its body's axes; a quaternion or planar ``(cos, sin)`` of q off norm 1 by more than 1e-6
        raises ArgumentError, none is normalised); its dynamics (:meth:`Robot.inverse_dynamics`,
        :meth:`Robot.regressor`, :meth:`Robot.mass_matrix`, :meth:`Robot.forward_dynamics`,
        energies, :func:`mindyn.coriolis_matrix`, the classical Slotine-Li regressor), its
        kinematics (:meth:`Robot.link_poses`, :meth:`Robot.fk`, :meth:`Robot.jacobian`) and base
        parameters (every method, no rotor inertia or friction) are computed, other functions refuse
        it.
    gravity : array_like, shape (3,), optional
        Gravity in the base frame [m/s^2], instead of the description's (default
        ``(0, 0, -9.81)``). A robot's gravity is fixed once loaded; :meth:`Robot.with_gravity`
        gives a new robot with another.
    joint_terms : str or Path, optional
        A joint-terms file (``OUT.joints.yaml``, which ``mindyn identify --urdf OUT.urdf`` and
        :func:`mindyn.export.write_urdf` write beside the description): its rotor inertia,
        friction and torque offsets replace the description's (:meth:`Robot.with_joint_terms`;
        a term the file does not have stays the description's). Rows name the robot's joints
        (each once); with ``drive_side: motor`` each row's ``Ia``, ``Fv``, ``Fc`` are those of
        the motor it names, in motor units, and the robot's terms act on the motors, otherwise
        on the joints (:attr:`Robot.drive_side`). A file with friction gives the friction model
        too (``friction_model``, default coulomb; its third term ``Fa`` or ``Fs`` and the
        rows' ``velocity``, :attr:`Robot.friction_model`). A file that does not fit the robot
        (a joint or motor it does not have, a count that differs, a negative rotor inertia or
        friction, a term some rows lack, a friction model's term or velocity missing) is a
        ModelError naming the file and the entry.

    Raises
    ------
    FileNotFoundError
        The file does not exist (``mindyn.RobotFileNotFoundError``).
    ValueError
        Malformed description, unsupported joint, unknown name (``mindyn.ModelError``); a
        number that cannot be read, or a missing or misspelt URDF attribute (file, line, link or
        joint and attribute named). A URDF link without ``<inertial>`` is massless and named in
        ``notes``.

    Warns
    -----
    DriveTrainWarning
        A URDF transmission of a type not read drives joints of the model: they are modelled
        as driven directly (:attr:`Robot.unread_transmissions`).
    """
    _args.instance(robot, "robot", (Robot, str, Path), "a Robot, a bundled robot name or a path")
    _args.optional(_args.text, tip, "tip")
    _args.optional(_args.text, root_joint, "root_joint")
    if isinstance(robot, Robot) and (tip or root_joint):  # a loaded robot has its joints
        given = "tip=" if tip else "root_joint="
        raise _args.ArgumentError(
            f"{given} applies to a description file, not to the loaded Robot '{robot.name}' "
            f"(load its file with {given})"
        )
    _args.optional(_args.path, joint_terms, "joint_terms")
    out = _load(robot, tip, root_joint)
    if out is not robot:
        import warnings

        note = drive_train_note(out)
        if note:
            warnings.warn(note, DriveTrainWarning, stacklevel=2)
        note = unused_terms_note(out)
        if note:
            warnings.warn(note, UserWarning, stacklevel=2)
    if joint_terms is not None:
        terms = _sidecar.slots(_sidecar.read(joint_terms), out)
        model = terms.pop("friction_model")
        if model is not None:  # the file's friction: its model too
            out = out.with_friction_model(model["kind"], velocity=model["velocity"])
        out = out.with_joint_terms(**terms)
    return out if gravity is None else out.with_gravity(gravity)


class DriveTrainWarning(UserWarning):
    """A robot's drive train is modelled otherwise than its description writes it: a URDF
    ``<transmission>`` of a type not read (:attr:`Robot.unread_transmissions`), whose joints are
    modelled as driven directly. :func:`load` warns once per file; silence it with
    ``warnings.filterwarnings("ignore", category=mindyn.DriveTrainWarning)`` (the command line:
    ``--drive-side joint``, where a command has it, which the note names as
    ``drive_side='joint'``)."""


#: The transmission types read from a URDF: ros_control's (transmission_interface, named in a
#: ``<type>`` element or a ROS 2 ``<plugin>``) and PR2's older ones (pr2_mechanism_model, named
#: in the type attribute or a ``<type>`` element).
READ_TRANSMISSIONS = (
    "transmission_interface/SimpleTransmission",
    "transmission_interface/DifferentialTransmission",
    "transmission_interface/FourBarLinkageTransmission",
    "pr2_mechanism_model/SimpleTransmission",
    "pr2_mechanism_model/WristTransmission",
)


def unused_terms_note(robot: Robot) -> str:
    """The note on the rotor inertia and friction that the revolute and prismatic joints of a
    robot with joints of several degrees of freedom carry (as its description gives them), which
    its dynamics leave out (such a model has no rotor inertia or friction), one line; "" when
    there are none. What :func:`load` warns."""
    if robot.single_dof:
        return ""
    names = robot.joint_names
    given = []
    for words, values in (
        ("rotor inertia", robot.rotor_inertia),
        ("viscous friction", robot.viscous),
        ("Coulomb friction", robot.coulomb),
    ):
        at = [f"{names[k]} {values[k]:g}" for k in range(len(names)) if values[k] != 0]
        if at:
            more = f" and {len(at) - 4} more" if len(at) > 4 else ""
            given.append(f"{words} ({', '.join(at[:4])}{more})")
    if not given:
        return ""
    return (
        f"{robot.source}: the {'; '.join(given)} of its revolute and prismatic joints (a URDF's "
        "<dynamics damping, friction>, an MJCF's armature, damping, frictionloss) are not in the "
        "dynamics: with joints of several degrees of freedom the model has no rotor inertia or "
        "friction, so that its mass matrix and inverse dynamics leave them out (they stay the "
        "joints' Ia, Fv, Fc)"
    )


def drive_train_note(robot: Robot) -> str:
    """The note on the URDF transmissions of ``robot`` that are not read and drive joints of
    the model (:attr:`Robot.unread_transmissions`), one line; "" when there are none. What
    :func:`load` warns (:class:`DriveTrainWarning`) and the commands print."""
    unread = [t for t in robot.unread_transmissions if t["modelled_directly"]]
    if not unread:
        return ""
    each = "; ".join(
        f"'{t['name']}' of type '{t['type']}' (line {t['line']}) driving joint(s) "
        + ", ".join(f"'{j}'" for j in t["modelled_directly"])
        for t in unread
    )
    ros = [t for t in READ_TRANSMISSIONS if t.startswith("transmission_interface/")]
    pr2 = [t for t in READ_TRANSMISSIONS if t.startswith("pr2_mechanism_model/")]
    return (
        f"{robot.source}: transmission(s) of a type not read ({', '.join(ros)}, named so in a "
        f"<type> element or a ROS 2 <plugin>, and PR2's {', '.join(pr2)}, named so in the type "
        f"attribute or a <type> element, are): {each}. Assumed: those "
        "joints are driven directly (a motor of their own, ratio 1; rotor inertia and "
        "friction on the joint). Declare the transmission as one of the types read to model it;"
        " drive_side='joint' (where a command takes it: every joint's "
        "rotor inertia and friction on the joint) makes the direct drive explicit and "
        "silences this note"
    )


def drive_train_record(robot: Robot) -> dict:
    """``{"unread_transmissions": [...]}`` for a JSON output of a robot whose URDF has
    transmissions of a type not read that drive joints of the model (each: ``name``,
    ``type``, ``joints``, ``line``, ``modelled_directly``, ``assumed``), else ``{}``."""
    unread = [t for t in robot.unread_transmissions if t["modelled_directly"]]
    return {"unread_transmissions": unread} if unread else {}


def as_robot(robot, *, name: str = "robot") -> Robot:
    """``robot`` itself, or the robot :func:`load` gives for a bundled name or a path (the
    ``robot`` argument of the public functions); ArgumentError naming ``name`` otherwise."""
    if isinstance(robot, Robot):
        return robot
    _args.instance(robot, name, (Robot, str, Path), "a Robot, a bundled robot name or a path")
    return load(robot)


def _load(robot: Robot | str | Path, tip: str | None, root_joint: str | None = None) -> Robot:
    if isinstance(robot, Robot):
        return robot
    text = str(robot)
    path = Path(text)
    suffix = path.suffix.lower()
    if suffix in (".urdf", ".xml"):
        if not path.is_file():
            kind = "URDF" if suffix == ".urdf" else "robot"
            raise _core.RobotFileNotFoundError(f"{kind} file '{text}' does not exist")
        if suffix == ".xml" and _mujoco.is_mjcf(path):
            if root_joint:
                raise _core.ModelError("root_joint= applies to URDF files only, not to MJCF")
            return Robot(_mujoco.read(text, tip))
        if not root_joint:  # forms of transmissions read as ros_control's, on the same lines
            xml, note = _urdf_forms.normalise(path.read_bytes(), text)
            if note:
                import warnings

                warnings.warn(note, UserWarning, stacklevel=3)
                return Robot(_core.parse_urdf(xml, tip or "", text))
        return Robot(_core.load_urdf(text, tip or "", root_joint or ""))
    if root_joint:
        raise _core.ModelError(
            f"root_joint= applies to URDF files only, not to '{text}' "
            "(a YAML table writes a 'floating' or 'planar' joint instead)"
        )
    if suffix in (".yaml", ".yml"):
        if tip:
            raise _args.ArgumentError("tip= applies to URDF chains only, not to a DH/MDH table")
        if not path.is_file():
            raise _core.RobotFileNotFoundError(f"robot description '{text}' does not exist")
        return Robot(_core.load_yaml(text))
    if tip:
        raise _args.ArgumentError(
            f"tip= applies to URDF files only, not to the bundled robot '{text}'"
        )
    m = _PLANAR.fullmatch(text)
    if m:
        n = int(m.group(1))
        if n > _MAX_JOINTS:
            raise _core.ModelError(
                f"a planar arm has at most {_MAX_JOINTS} joints, got {m.group(1)} ('{text}')"
            )
        return Robot(_core.planar_arm(n, vertical=not m.group(2)))
    bundled = _robot_dir() / f"{text}.yaml"
    if "/" not in text and bundled.is_file():
        return Robot(_core.load_yaml(str(bundled)))
    if path.is_dir():
        raise _core.RobotFileNotFoundError(
            f"'{text}' is a folder, not a robot: give its description, {_FORMS}"
        )
    if path.is_file():
        raise _core.ModelError(
            f"'{text}' is not a robot description: expected a bundled robot or {_FORMS}"
        )
    if "/" in text or suffix:
        raise _core.RobotFileNotFoundError(
            f"'{text}' is neither an existing file nor a bundled robot (a robot is a bundled "
            f"name or {_FORMS})"
        )
    raise _core.ModelError(
        f"unknown robot '{text}'; bundled robots: {', '.join(bundled_robots())}, "
        f"or give the path of {_FORMS}"
    )


#: The description files a robot is read from (said when a path is none of them).
_FORMS = "a .urdf file, a MuJoCo MJCF .xml file or a YAML DH/MDH table (.yaml, .yml)"


def _readonly(a) -> np.ndarray:
    return _args.readonly(a)


@dataclass(frozen=True)
class Transmission:
    """Transmissions between the motors and the joints of a robot: motor positions, torque
    constants, and (on the motor side, :attr:`Robot.drive_side`) the rows through which the
    motors' rotor inertia and friction act.

    Attributes
    ----------
    T : ndarray, shape (n_m, n), read-only
        Motor positions ``q_m = T q + offset``; joint torques ``tau = T^T tau_m``. Row i is
        motor i, column k joint k; the gear ratios and coupling terms of ros_control's
        SimpleTransmission, DifferentialTransmission and FourBarLinkageTransmission and of PR2's
        SimpleTransmission and WristTransmission (pr2_mechanism_model). The column
        of a joint of several degrees of freedom (a floating or planar base) is zero: no motor.
    offset : ndarray, shape (n_m,), read-only
        Motor positions at ``q = 0``.
    motors : tuple of str
        Motor (actuator) names.
    types : tuple of str
        Each motor's transmission type (``SimpleTransmission``, ...,
        ``pr2_mechanism_model/WristTransmission``, ``direct`` for a revolute or prismatic joint
        a URDF gives no transmission while others have one, ``matrix`` for a YAML row).
    torque_constant : ndarray, shape (n_m,), read-only
        Motor torque constants [N m/A] the description gives (NaN where none).
    format : str
        ``ros1`` or ``ros2`` (the URDF form read; PR2's form alone is ``ros1``) or ``yaml``.
    groups : tuple of dict
        The transmissions as declared in a URDF: name, type, joints, actuators,
        actuator_reduction, joint_reduction, joint_offset.
    """

    T: np.ndarray
    offset: np.ndarray
    motors: tuple
    types: tuple
    torque_constant: np.ndarray
    format: str
    groups: tuple = field(default=())

    @property
    def n_motors(self) -> int:
        return len(self.motors)


class Robot:
    """A fixed-base manipulator: a serial chain, or a tree (:attr:`parents`, :attr:`is_serial`).

    Attributes
    ----------
    n : int
        Number of joints.
    param_names : list of str
        Names of the classical inertial parameters (``10 n``).
    params : ndarray, shape (10 n,)
        Their values (read-only; assign a whole vector to change the model).
    gravity : ndarray, shape (3,)
        Fixed once loaded (``mindyn.load(..., gravity=g)``, :meth:`with_gravity`): base
        parameter sets and the code generated from them depend on it.

    Notes
    -----
    The parameter values (``params``, ``rotor_inertia``, ``viscous``, ``coulomb``,
    ``third_friction``) can be
    assigned: what is derived from a robot depends on its geometry and gravity only (base
    parameter sets, base dynamics, inverse kinematics) or takes the values when it is made
    (generated code with baked-in values, simulators, controllers' default estimates), so
    an assignment never changes an object made before it.

    Several threads may use one robot at once: every computation makes its own workspace and
    runs with the GIL released, so batches on different threads run in parallel.
    """

    def __init__(self, core: _core.Model):
        self._m = core
        self._kin: _core.Kinematics | None = None

    # -- description ---------------------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of joints (and of moving links); the size of q and dq when every joint is
        revolute or prismatic (:attr:`nq`, :attr:`nv` otherwise)."""
        return self._m.n

    @property
    def nq(self) -> int:
        """Size of the configuration q (Pinocchio's nq: 4 per spherical, 7 per free-flyer, 4 per
        planar joint)."""
        return self._m.nq

    @property
    def nv(self) -> int:
        """Size of the velocity, acceleration and torque vectors (Pinocchio's nv)."""
        return self._m.nv

    @property
    def single_dof(self) -> bool:
        """True when every joint is revolute or prismatic (nq = nv = n)."""
        return self._m.single_dof

    def _multibody(self, fn, *, params=_NO_PARAMS, rows: bool = False, **arrays):
        """A multibody function of the core on one sample (1-D arrays) or a batch (2-D), its
        arguments checked (:mod:`._args`) under their names, in the order given: ``q`` of
        :attr:`nq` entries, the others of :attr:`nv`; ``params`` the 10 n inertial parameters
        or None (the model's)."""
        sizes = {name: self.nq if name == "q" else self.nv for name in arrays}
        checked = _args.batch(sizes, **arrays)
        if "q" in arrays:
            self._unit_norms(checked[list(arrays).index("q")])
        extra = ()
        if params is not _NO_PARAMS:
            extra = (_args.params(params, "params", self.n, (10,)),)
        if checked[0].ndim == 1:
            return fn(self._m, *checked, *extra)
        out = [fn(self._m, *x, *extra) for x in zip(*checked, strict=True)]
        return tuple(np.array(c) for c in zip(*out, strict=True)) if rows else np.array(out)

    def _configuration(self, q, name: str = "q") -> np.ndarray:
        """One configuration of :attr:`nq` entries, checked (:mod:`._args`): its quaternions and
        (cos, sin) pairs of norm 1."""
        return self._unit_norms(_args.array(q, name, (self.nq,), unit="coordinate"), name)

    def _unit_norms(self, q: np.ndarray, name: str = "q") -> np.ndarray:
        return _args.unit_norms(q, name, self._unit_blocks())

    def _unit_blocks(self) -> list[tuple[int, int, str]]:
        """The entries of a configuration q that must have norm 1 (none is normalised), as
        ``(start, size, what)``: the unit quaternion (x, y, z, w) of a spherical or free-flyer
        joint, the (cos t, sin t) of a planar joint, ``what`` naming it ("quaternion of the
        floating joint 'root_joint'"); empty for revolute and prismatic joints only."""
        out, i = [], 0
        for kind, joint in zip(self.joint_types, self.joint_names, strict=True):
            start, size, nq = _UNIT_BLOCKS.get(kind, (0, 0, _NQ.get(kind, 1)))
            if size:
                what = "quaternion" if size == 4 else "(cos, sin) pair"
                out.append((i + start, size, f"{what} of the {kind} joint '{joint}'"))
            i += nq
        return out

    @property
    def name(self) -> str:
        return self._m.name

    @property
    def source(self) -> str:
        return self._m.source

    @property
    def convention(self) -> str:
        """``urdf``, ``dh`` or ``mdh``: how the geometry was given."""
        return self._m.convention

    @property
    def notes(self) -> str:
        """Notes on the model: the YAML description's ``notes`` (a planar arm's geometry), or
        for a URDF the joints locked and merged and the links without ``<inertial>`` taken as
        massless."""
        return self._m.notes

    @property
    def unread_transmissions(self) -> list[dict]:
        """The URDF ``<transmission>`` elements of types not read (none of
        :data:`READ_TRANSMISSIONS`, e.g. ``my_pkg/HalfDifferentialTransmission`` or PR2's belt
        compensator and gripper),
        left out of :attr:`transmission`: each ``name``, ``type`` as written, the ``joints`` it
        names, its ``line``, ``modelled_directly`` (those of the model's joints that no
        transmission read drives, each modelled as driven by a motor of its own, ratio 1) and
        ``assumed`` (``"direct drive"``).
        :func:`load` warns of those driving joints of the model (:class:`DriveTrainWarning`)."""
        read = {j for g in self._m.transmission["groups"] for j in g["joints"]}
        names = set(self._m.joint_names) - read  # not those a transmission read drives
        return [
            {
                **t,
                "modelled_directly": [j for j in t["joints"] if j in names],
                "assumed": "direct drive",
            }
            for t in self._m.unread_transmissions
        ]

    @property
    def synthetic_inertia(self) -> bool:
        """True when the description says its inertial values are invented, not measured."""
        return self._m.synthetic_inertia

    @property
    def joint_names(self) -> list[str]:
        return self._m.joint_names

    @property
    def joint_types(self) -> list[str]:
        return self._m.joint_types

    @property
    def parents(self) -> list[int]:
        """Parent joint of each joint (0-based), -1 for the base: joint k moves link k+1 relative
        to the link of joint ``parents[k]``. A serial chain has ``parents == [-1, 0, 1, ...]``;
        a tree has parents before children (``parents[k] < k``)."""
        return self._m.parents

    @property
    def is_serial(self) -> bool:
        """True when every joint's parent is the joint before it (a serial chain)."""
        return all(p == k - 1 for k, p in enumerate(self._m.parents))

    @property
    def branches(self) -> int:
        """Number of branches: joints that no other joint hangs from (1 for a serial chain)."""
        return self.n - len(set(self.parents) - {-1})

    @property
    def link_names(self) -> list[str]:
        """``n + 1`` names: the base, then each moving link."""
        return self._m.link_names

    @property
    def axes(self) -> np.ndarray:
        """Joint axes, shape (n, 3), each in its joint frame."""
        return _readonly(self._m.axes)

    @property
    def dh(self) -> np.ndarray:
        """DH rows ``(a, alpha, d, theta)`` for ``dh``; MDH ``(d_j, alpha_j, r_j, theta_j)`` as
        ``(a, alpha, d, theta)`` for ``mdh``; empty for URDF. Shape (n, 4) or (0, 4)."""
        return _readonly(self._m.dh)

    @property
    def limits(self) -> dict[str, np.ndarray]:
        """Joint limits as arrays of shape (n,): lower, upper, velocity, acceleration, effort
        (NaN where the description gives none)."""
        rows = self._m.limits
        return {k: _readonly([r[k] for r in rows]) for k in rows[0]}

    @property
    def drives(self) -> dict[str, np.ndarray]:
        """Motor rated torque [N m], gear ratio and motor torque constant [N m/A] per joint
        (``rated_torque``, ``gear_ratio``, ``torque_constant``), shape (n,) each (NaN when
        unknown; URDF gives none)."""
        rows = self._m.drives
        return {k: _readonly([r[k] for r in rows]) for k in rows[0]}

    @property
    def transmission(self) -> Transmission | None:
        """The motors and their coupling to the joints, ``q_m = T q + offset`` and
        ``tau = T^T tau_m`` (:class:`Transmission`), or None when the description declares no
        transmissions (each joint driven directly)."""
        d = self._m.transmission
        if not d["motors"]:
            return None
        return Transmission(
            T=_readonly(d["T"]),
            offset=_readonly(d["offset"]),
            motors=tuple(d["motors"]),
            types=tuple(d["types"]),
            torque_constant=_readonly(d["torque_constant"]),
            format=d["format"],
            groups=tuple(d["groups"]),
        )

    @property
    def drive_side(self) -> str:
        """Where the rotor inertia and friction of a parameter vector act: ``"motor"`` when the
        description declares transmissions (slot k of ``Ia``/``Fv``/``Fc`` is then motor k's, in
        motor units: ``tau += T^T (Ia T ddq + Fv T dq + Fc sign(T dq))``), ``"joint"`` otherwise
        or after :meth:`with_drive_side`. Always ``"joint"`` for a robot with joints of several
        degrees of freedom (not :attr:`single_dof`): it has no rotor inertia or friction terms,
        so none acts on a motor, whatever transmissions it declares."""
        return self._m.drive_side if self._m.single_dof else "joint"

    def with_drive_side(self, side: str) -> Robot:
        """A new robot, the same as this one but with its rotor inertia and friction on the
        motors (``"motor"``, needs transmissions and revolute and prismatic joints only) or on
        the joints (``"joint"``); this robot is unchanged."""
        _args.choice(side, "side", ("motor", "joint"))
        if side == "motor":
            self._require_single_dof(
                "drive side 'motor' (rotor inertia and friction on the motors)"
            )
        return Robot(self._m.with_drive_side(side))

    def with_joint_terms(
        self,
        *,
        rotor=None,
        viscous=None,
        coulomb=None,
        third=None,
        offset=None,
        drive_side=None,
    ) -> Robot:
        """A new robot, the same as this one but for its rotor inertia, friction and torque
        offsets; this robot is unchanged. A term not given (``None``) stays as it is.

        Parameters
        ----------
        rotor, viscous, coulomb : array_like, shape (n,), optional
            ``Ia``, ``Fv``, ``Fc`` of each slot, each >= 0: joint k's on the joint side,
            motor k's (row k of ``transmission.T``, motor units) on the motor side. On the
            motor side the joint-side values (:attr:`rotor_inertia`, ...) become each directly
            driven joint's motor's as they act on it (``r^2 Ia``, ``r^2 Fv``, ``|r| Fc``), 0 for
            a joint of a motor that turns with several joints.
        third : array_like, shape (n,), optional
            The third parameter of the robot's friction model (:attr:`friction_model`: ``Fa``
            of the asymmetric, ``Fs`` of the Stribeck model) of each slot, as ``coulomb``
            (:attr:`third_friction`; on the motor side it acts on each directly driven joint as
            ``r Fa`` or ``|r| Fs``, and a motor that turns with several joints keeps its own).
        offset : array_like, shape (n,), optional
            A constant torque offset per joint (``Off1 .. OffN``, :attr:`torque_offset`), the
            values of the offset entries of :meth:`parameters`.
        drive_side : {"motor", "joint"}, optional
            Where ``rotor``, ``viscous`` and ``coulomb`` act (default: :attr:`drive_side`);
            the new robot has this drive side (:meth:`with_drive_side`).
        """
        self._require_single_dof("joint terms (rotor inertia, friction, torque offsets)")
        if drive_side is not None:
            _args.choice(drive_side, "drive_side", ("motor", "joint"))
        side = self.drive_side if drive_side is None else drive_side
        robot = self.with_drive_side(side) if side != self.drive_side else self
        given = {}
        for name, v in (("rotor", rotor), ("viscous", viscous), ("coulomb", coulomb)):
            if v is None:
                continue
            given[name] = _drive_vector(v, self.n, name)
        if third is not None:
            third = _vector(third, self.n, "third")
            kind = self.friction_model["kind"]
            if kind not in ("asymmetric", "stribeck"):
                raise _args.fail(
                    "third",
                    f"is given, but the friction model of robot '{self.name}' is {kind}, which "
                    "has two terms (a third for 'asymmetric' and 'stribeck': "
                    "robot.with_friction_model)",
                )
        kw = {}
        joint_third = third
        if side == "motor":
            direct = _direct_drives(robot.drive_matrix)
            if third is not None:  # the motors' own, and as they act on their joints
                kw["motor_third"] = third
                joint_third = np.zeros(self.n)
                third_name = "Fa" if kind == "asymmetric" else "Fs"
                for j, d in enumerate(direct):
                    if d is not None:
                        k, r = d
                        joint_third[j] = _reflected(third_name, r) * third[k]
            for name, v in given.items():
                kw["motor_" + name] = v
                reflected = np.zeros(self.n)
                for j, d in enumerate(direct):
                    if d is not None:
                        k, r = d
                        reflected[j] = _reflected(name, r) * v[k]
                kw[name] = reflected
        else:
            kw.update(given)
        if offset is not None:
            kw["offset"] = _vector(offset, self.n, "offset")
        core = robot._m.with_joint_terms(**kw)
        if joint_third is not None:
            core.third_friction = joint_third  # a new model: nobody uses it yet
        return Robot(core)

    @property
    def torque_offset(self) -> np.ndarray:
        """Constant torque offset per joint, shape (n,) (``Off1 .. OffN``): 0 unless given by
        :meth:`with_joint_terms` (a joint-terms file, ``mindyn.load(..., joint_terms=)``)."""
        return _readonly(self._m.torque_offset)

    @property
    def drive_matrix(self) -> np.ndarray:
        """The rows ``t_k`` through which slot ``k``'s rotor inertia and friction act, shape
        (n_m, n): the transmission's ``T`` on the motor side (:attr:`drive_side`; ``n_m`` motors,
        as many as joints unless the robot has joints of several degrees of freedom, which no
        motor drives), the identity (n, n) otherwise. Slot ``k`` adds
        ``t_k^T (Ia_k t_k . ddq + Fv_k v_k + Fc_k sign(v_k))`` to the joint torques,
        ``v_k = t_k . dq``."""
        if self.drive_side == "motor":
            return _readonly(np.array(self._m.transmission["T"], dtype=float))
        return _readonly(np.eye(self.n))

    @_args.finite_results("dq")
    def slot_velocities(self, dq) -> np.ndarray:
        """The velocity ``v_k = t_k . dq`` of each rotor/friction slot for joint velocities
        ``dq`` (n,) or (m, n): the motor velocities on the motor side, ``dq`` otherwise."""
        dq = _args.samples(dq, "dq", self.n)
        return dq if self.drive_side != "motor" else dq @ self.drive_matrix.T

    @property
    def friction_model(self) -> dict:
        """The shape of the friction terms: ``{"kind": "coulomb" | "asymmetric" | "smooth" |
        "stribeck", "velocity": array (n,) of tanh widths / Stribeck velocities [rad/s | m/s],
        one per slot (the motors' in their units on the motor side, :attr:`drive_side`), empty
        for the kinds without one}``."""
        d = self._m.friction_model
        return {"kind": d["kind"], "velocity": _readonly(d["velocity"])}

    def with_friction_model(self, kind: str, *, velocity=None) -> Robot:
        """A new robot, the same as this one but for its friction model (``kind`` coulomb,
        asymmetric, smooth or stribeck; ``velocity`` shape (n,), positive, for smooth and
        stribeck); this robot is unchanged."""
        _args.choice(kind, "kind", FRICTION_KINDS)
        v = np.zeros(0) if velocity is None else _args.array(velocity, "velocity", (self.n,))
        bad = np.flatnonzero(~(v > 0))
        if bad.size:
            k = int(bad[0])
            raise _args.fail(
                "velocity",
                f"has {v[k]:g} at entry {k + 1} (joint '{self.joint_names[k]}'); expected "
                "positive velocity scales, one per joint",
            )
        return Robot(self._m.with_friction_model(kind, v))

    @property
    def gravity(self) -> np.ndarray:
        """Gravity in the base frame, shape (3,); default (0, 0, -9.81)."""
        return _readonly(self._m.gravity)

    @gravity.setter
    def gravity(self, g) -> None:
        raise AttributeError(
            "a robot's gravity is fixed: use robot.with_gravity(g) for a new robot, or "
            "mindyn.load(..., gravity=g)"
        )

    def with_gravity(self, gravity) -> Robot:
        """A new robot, the same as this one but for ``gravity`` (shape (3,), base frame,
        m/s^2), with its own model: this robot, and base parameter sets, generated code or
        solvers made from it, are unchanged."""
        return Robot(self._m.with_gravity(_args.array(gravity, "gravity", (3,))))

    @property
    def tool(self) -> np.ndarray:
        """4x4 transform from the last link frame to the tool frame (the identity for a tree)."""
        return _readonly(self._m.tool)

    def _fixed_link_hint(self, name: object) -> str:
        """For a name that is no moving link: where a URDF fixes that link (``"; 'FL_foot' is
        fixed to the moving link 'FL_calf', merged into it"``), following its fixed joints up
        to a moving link; empty for any other name or description."""
        import xml.etree.ElementTree as ET

        if not isinstance(name, str) or self.convention != "urdf":
            return ""
        try:
            root = ET.parse(self.source).getroot()
        except (OSError, ET.ParseError):
            return ""
        if root.tag != "robot":  # an MJCF read as a URDF's link frames
            return ""
        parent: dict[str, str] = {}
        for joint in root.iter("joint"):
            child, up = joint.find("child"), joint.find("parent")
            if child is not None and up is not None and joint.get("type") == "fixed":
                parent[child.get("link", "")] = up.get("link", "")
        moving, link, seen = set(self.link_names[1:]), name, set()
        while link in parent and link not in moving and link not in seen:
            seen.add(link)
            link = parent[link]
        if link == name or link not in moving:
            return ""
        return f"; {name!r} is fixed to the moving link {link!r}, merged into it"

    def _require_serial(self, what: str) -> None:
        """Raises ModelError unless the robot is a serial chain; ``what`` names the operation."""
        if not self.is_serial:
            raise _core.ModelError(
                f"{what} needs a serial chain; robot '{self.name}' is a tree ({self.n} joints, "
                f"{self.branches} branches): load the chain to the link concerned, "
                "tip='<link>'"
            )

    @_args.finite_results("q")
    def joint_transform(self, k: int, q: float) -> np.ndarray:
        """4x4 transform from the link of joint ``parents[k]`` (the base when -1; ``k-1`` in a
        chain) to link ``k`` (0-based ``k``) at joint value ``q`` (a revolute or prismatic
        joint)."""
        self._check_joint(k)
        if self.joint_types[k] not in _SINGLE_DOF:
            raise _core.ModelError(
                f"joint_transform takes a revolute or prismatic joint; joint {k} "
                f"('{self.joint_names[k]}') is {self.joint_types[k]}"
            )
        return self._m.joint_transform(k, _args.number(q, "q"))

    def joint_pre(self, k: int) -> np.ndarray:
        self._check_joint(k)
        return self._m.joint_pre(k)

    def joint_post(self, k: int) -> np.ndarray:
        self._check_joint(k)
        return self._m.joint_post(k)

    def _check_joint(self, k: int) -> None:
        _args.integer(k, "k", 0, maximum=self.n - 1)

    # -- parameters ----------------------------------------------------------------------------
    @property
    def param_names(self) -> list[str]:
        return self._m.parameter_names(rotor=False, friction=False)

    @property
    def params(self) -> np.ndarray:
        return _readonly(self._m.inertial)

    @params.setter
    def params(self, value) -> None:
        self._m.inertial = _vector(value, 10 * self.n, "params", "entry")

    @property
    def rotor_inertia(self) -> np.ndarray:
        return _readonly(self._m.rotor_inertia)

    @rotor_inertia.setter
    def rotor_inertia(self, v) -> None:
        self._m.rotor_inertia = _drive_vector(v, self.n, "rotor_inertia")

    @property
    def viscous(self) -> np.ndarray:
        return _readonly(self._m.viscous)

    @viscous.setter
    def viscous(self, v) -> None:
        self._m.viscous = _drive_vector(v, self.n, "viscous")

    @property
    def coulomb(self) -> np.ndarray:
        return _readonly(self._m.coulomb)

    @coulomb.setter
    def coulomb(self, v) -> None:
        self._m.coulomb = _drive_vector(v, self.n, "coulomb")

    @property
    def third_friction(self) -> np.ndarray:
        """The third friction parameter per slot (``Fa`` of the asymmetric, ``Fs`` of the
        Stribeck friction model), shape (n,); zero unless assigned."""
        return _readonly(self._m.third_friction)

    @third_friction.setter
    def third_friction(self, v) -> None:
        self._m.third_friction = _vector(v, self.n, "third_friction")

    def drive_terms_given(self) -> list[str]:
        """The kinds of rotor inertia and friction terms that the description gives a non-zero
        value on some slot, in layout order (of ``Ia``, ``Fv``, ``Fc`` and the friction
        model's third, ``Fa`` or ``Fs``); empty for a robot with joints of several degrees of
        freedom, which has none."""
        if not self._m.single_dof:
            return []
        names = self.parameter_names(rotor=True, friction=True)
        values = self.parameters(rotor=True, friction=True)
        inertial = set(self.parameter_names())
        kinds = [
            nm.rstrip("0123456789") for nm, v in zip(names, values) if v and nm not in inertial
        ]
        return list(dict.fromkeys(kinds))

    def parameter_names(
        self, *, rotor: bool = False, friction: bool = False, offset: bool = False
    ) -> list[str]:
        """Classical parameter names in the layout with optional ``Ia`` and the friction
        model's columns (``Fv, Fc``, and ``Fa`` or ``Fs``): ``Ia6`` is slot 6's, joint 6's on
        the joint side, motor 6's (row 6 of ``transmission.T``) on the motor side
        (:attr:`drive_side`); with ``offset``, a torque offset per joint after all others
        (``Off6``: joint 6's on either side)."""
        return self._m.parameter_names(*self._layout(rotor, friction, offset))

    def parameters(
        self, *, rotor: bool = False, friction: bool = False, offset: bool = False
    ) -> np.ndarray:
        """Classical parameter values of the model in that layout. :attr:`rotor_inertia`,
        :attr:`viscous` and :attr:`coulomb` are the joints' (as descriptions give them); on the
        motor side slot k holds motor k's: its joint's divided by ``r^2``, ``r^2``, ``|r|`` for a
        motor that alone drives one joint, with ratio ``r``, 0 for a coupled motor, unless
        given (a YAML table's ``transmissions``, :meth:`with_joint_terms`). Torque offsets
        (``offset``) are :attr:`torque_offset`: 0 unless a joint-terms file gives them (a
        description gives none)."""
        return self._m.parameters(*self._layout(rotor, friction, offset))

    # -- dynamics ------------------------------------------------------------------------------
    @_args.finite_results("q", "dq", "ddq", "params")
    def inverse_dynamics(self, q, dq, ddq, params=None) -> np.ndarray:
        """Joint torques ``tau = W(q, dq, ddq) @ params`` by Newton-Euler.

        ``params`` defaults to the model's inertial parameters; any vector in a classical layout is
        accepted, physically meaningful or not. Returns shape (n,) or (m, n).

        With multi-DOF joints (not :attr:`single_dof`): q of :attr:`nq`, dq and ddq of
        :attr:`nv` entries, ``params`` the 10 n inertial ones, tau of :attr:`nv`."""
        if not self._m.single_dof:
            return self._multibody(
                _core.multibody_inverse_dynamics, q=q, dq=dq, ddq=ddq, params=params
            )
        q, dq, ddq = _args.batch(self.n, q=q, dq=dq, ddq=ddq)
        return self._m.inverse_dynamics(q, dq, ddq, self._params(params))

    @_args.finite_results("q", "dq", "ddq")
    def regressor(
        self, q, dq, ddq, *, rotor: bool = False, friction: bool = False, offset: bool = False
    ) -> np.ndarray:
        """Classical regressor ``W``, shape (n, P) or (m, n, P), with ``tau = W @ params``
        (an offset's column is 1 in its joint's row; multi-DOF joints: (nv, 10 n), no rotor
        inertia, friction or offsets)."""
        if not self._m.single_dof:
            self._refuse_drive_terms(rotor, friction, offset)
            return self._multibody(_core.multibody_regressor, q=q, dq=dq, ddq=ddq)
        q, dq, ddq = _args.batch(self.n, q=q, dq=dq, ddq=ddq)
        return self._m.regressor(q, dq, ddq, *self._layout(rotor, friction, offset))

    @_args.finite_results("q", "params")
    def gravity_torque(self, q, params=None) -> np.ndarray:
        """Gravity torque ``c(q)``, shape (n,) or (m, n) (multi-DOF joints: nv)."""
        if not self._m.single_dof:
            z = np.zeros(np.shape(q)[:-1] + (self.nv,))
            return self.inverse_dynamics(q, z, z, params)
        return self._m.gravity_torque(_args.samples(q, "q", self.n), self._params(params))

    @_args.finite_results("q", "params")
    def mass_matrix(self, q, params=None) -> np.ndarray:
        """Joint-space inertia ``A(q)``, shape (n, n) or (m, n, n) (multi-DOF joints: nv)."""
        if not self._m.single_dof:
            return self._multibody(_core.multibody_mass_matrix, q=q, params=params)
        return self._m.mass_matrix(_args.samples(q, "q", self.n), self._params(params))

    @_args.finite_results("q", "dq", "tau", "params")
    def forward_dynamics(self, q, dq, tau, params=None) -> np.ndarray:
        """Joint accelerations ``A(q)^-1 (tau - b - c - friction)``, shape (n,) or (m, n).

        Raises ValueError when ``A(q)`` is not positive definite for ``params``."""
        if not self._m.single_dof:
            return self._multibody(
                _core.multibody_forward_dynamics, q=q, dq=dq, tau=tau, params=params
            )
        q, dq, tau = _args.batch(self.n, q=q, dq=dq, tau=tau)
        return self._m.forward_dynamics(q, dq, tau, self._params(params))

    @_args.finite_results("q", "dq", "params")
    def kinetic_energy(self, q, dq, params=None):
        """Kinetic energy (rotor inertia included when ``params`` has it): float or shape (m,)."""
        return self._energies(q, dq, params)[0]

    @_args.finite_results("q", "params")
    def potential_energy(self, q, params=None):
        """Potential energy ``-sum g . (M_k p_k + R_k MS_k)``: float or shape (m,)."""
        if not self._m.single_dof:
            q = _args.samples(q, "q", self.nq, unit="coordinate")
            dq = np.zeros(q.shape[:-1] + (self.nv,))
            fn = _core.multibody_energies
            return self._multibody(fn, q=q, dq=dq, params=params, rows=True)[1]
        q = _args.samples(q, "q", self.n)
        return self._m.energies(q, np.zeros_like(q), self._params(params))[1]

    @_args.finite_results("q", "dq", "params")
    def energy(self, q, dq, params=None):
        """Total energy ``H = K + P``: float or shape (m,)."""
        k, p = self._energies(q, dq, params)
        return k + p

    @_args.finite_results("dq")
    def friction_shapes(self, dq) -> np.ndarray:
        """The friction columns of every slot at the slot velocities ``dq`` (:attr:`friction_model`:
        ``v, sign v`` (coulomb), ``v, sign v, |sign v|`` (asymmetric), ``v, tanh(v / w)``
        (smooth), ``v, sign v, sign v exp(-(v / w)^2)`` (stribeck)), shape (n, c) or (m, n, c):
        a slot's friction torque is its friction parameters dotted with its row."""
        (dq,) = _args.batch(self.n, dq=dq)
        return self._m.friction_shapes(dq)

    @_args.finite_results("q", "dq")
    def energy_regressors(
        self, q, dq, *, rotor: bool = False, friction: bool = False, offset: bool = False
    ):
        """``(w_K, w_P)`` with ``K = w_K @ params`` and ``P = w_P @ params``; shape (P,) or
        (m, P) each. An offset's column of ``w_P`` is its work ``q_j`` (``Off_j q_j``, not an
        energy), so that differences over a window are the energy model's columns."""
        return self._energy_regressors(q, dq, rotor, friction, offset)

    @_args.finite_results("q", "dq")
    def energy_regressor(self, q, dq, *, rotor: bool = False, friction: bool = False) -> np.ndarray:
        """Total-energy regressor ``w_H = w_K + w_P`` (``H = w_H @ params``)."""
        wk, wp = self._energy_regressors(q, dq, rotor, friction)
        return wk + wp

    @_args.finite_results("q", "dq")
    def lagrangian_regressor(self, q, dq, *, rotor: bool = False, friction: bool = False):
        """Lagrangian regressor ``w_L = w_K - w_P`` (``L = w_L @ params``)."""
        wk, wp = self._energy_regressors(q, dq, rotor, friction)
        return wk - wp

    @_args.finite_results("q", "dq")
    def momentum_regressors(
        self, q, dq, *, rotor: bool = False, friction: bool = False, offset: bool = False
    ):
        """``(W_p, W_l)``, shape (n, P) or (m, n, P) each, of the momentum form of the equations
        of motion ``tau = d/dt p - dL/dq + friction``: generalized momentum
        ``p = A(q) dq = W_p @ params`` and ``-dL/dq = W_l @ params`` (minus the gradient of the
        Lagrangian ``K - P``: the gravity torque minus ``dK/dq``). Neither needs an acceleration;
        their friction columns are zero, the rotor column of ``W_p`` is ``dq``. With ``offset``,
        ``W_l @ params`` is ``-dL/dq`` plus the offsets (an offset's column is 1 in its joint's
        row of ``W_l``, 0 in ``W_p``)."""
        self._require_single_dof("momentum_regressors")
        q, dq = _args.batch(self.n, q=q, dq=dq)
        return self._m.momentum_regressors(q, dq, *self._layout(rotor, friction, offset))

    def _energies(self, q, dq, params):
        if not self._m.single_dof:
            return self._multibody(_core.multibody_energies, q=q, dq=dq, params=params, rows=True)
        q, dq = _args.batch(self.n, q=q, dq=dq)
        return self._m.energies(q, dq, self._params(params))

    def _energy_regressors(self, q, dq, rotor, friction, offset=False):
        self._require_single_dof("the energy regressors")
        q, dq = _args.batch(self.n, q=q, dq=dq)
        return self._m.energy_regressors(q, dq, *self._layout(rotor, friction, offset))

    def _params(self, params, name: str = "params"):
        return _args.params(params, name, self.n, self.layout_sizes)

    @property
    def layout_sizes(self) -> tuple[int, int, int, int]:
        """Parameters per joint of the four classical layouts: 10, 11 with ``Ia``, ``10 + c``
        with the ``c`` friction columns of the friction model, ``11 + c`` with all."""
        c = len(self._m.parameter_names(rotor=False, friction=True)) // self.n - 10
        return 10, 11, 10 + c, 11 + c

    def _require_single_dof(self, what: str) -> None:
        """Refuses a robot with multi-DOF joints in one line naming the first."""
        if not self._m.single_dof:
            k = next(k for k, t in enumerate(self.joint_types) if t not in _SINGLE_DOF)
            raise _core.ModelError(
                f"{what} takes revolute and prismatic joints only; robot '{self.name}' has the "
                f"{self.joint_types[k]} joint '{self.joint_names[k]}' (multi-DOF joints have "
                "inverse dynamics, regressor, mass matrix, forward dynamics, energies, "
                "momentum, link poses, fk, jacobian, Slotine-Li regressor, Coriolis matrix, "
                "base parameters and the base regressor)"
            )

    @_args.finite_results("q")
    def link_poses(self, q) -> np.ndarray:
        """The pose of every link in the base frame at q (:attr:`nq` entries), shape (n, 4, 4);
        link k is the link joint k moves (any joint kinds)."""
        return np.array(_core.multibody_link_poses(self._m, self._configuration(q)))

    @_args.finite_results("q", "dq", "params")
    def momentum(self, q, dq, params=None) -> np.ndarray:
        """The momentum of the whole system at (q, dq) (:attr:`nq`, :attr:`nv` entries), shape
        (6,): linear momentum, then angular momentum about the base origin, both in base axes;
        ``params`` the 10 n inertial parameters (default the model's)."""
        q, dq = _args.array(q, "q", (self.nq,)), _args.array(dq, "dq", (self.nv,))
        return self._multibody(_core.multibody_momentum, q=q, dq=dq, params=params)

    def _refuse_drive_terms(self, rotor, friction, offset=False) -> None:
        if (
            _args.flag(rotor, "rotor")
            or _args.flag(friction, "friction")
            or _args.flag(offset, "offset")
        ):
            raise _core.ModelError(
                "rotor inertia, friction and offset columns are defined for revolute and prismatic "
                f"joints only; robot '{self.name}' has multi-DOF joints"
            )

    @staticmethod
    def _layout(rotor, friction, offset=False) -> tuple[bool, bool, bool]:
        return (
            _args.flag(rotor, "rotor"),
            _args.flag(friction, "friction"),
            _args.flag(offset, "offset"),
        )

    # -- kinematics (Orocos KDL) ---------------------------------------------------------------
    def _kinematics(self) -> _core.Kinematics:
        self._require_single_dof("the kinematics (KDL)")
        if self._kin is None:
            self._kin = _core.Kinematics(self._m)
        return self._kin

    @_args.finite_results("q")
    def fk(self, q, *, link: int = -1) -> np.ndarray:
        """4x4 pose in the base frame of link ``link`` (0-based: the link moved by joint
        ``link``) or of the tool frame (``-1``; for a tree the last link's frame). With
        multi-DOF joints (not :attr:`single_dof`) q has :attr:`nq` entries."""
        single = self._m.single_dof
        q = _vector(q, self.n, "q") if single else self._configuration(q)
        _args.integer(link, "link", -1, maximum=self.n - 1)
        if not single:
            pose = self.link_poses(q)[link]
            return pose @ self.tool if link < 0 else pose
        if not self.is_serial:
            pose = _core.link_poses(self._m, q)[link]
            return pose @ self.tool if link < 0 else pose
        return self._kinematics().pose(q, link)

    @_args.finite_results("q")
    def jacobian(self, q, *, link: int = -1, frame: str = "world") -> np.ndarray:
        """Geometric Jacobian of a link's frame, shape (6, n): ``[v; w] = J dq``, ``v`` the
        velocity of the frame's origin (its reference point) and ``w`` the frame's angular
        velocity.

        ``link`` is a link as :meth:`fk` takes it: 0-based, the link moved by joint ``link``,
        or ``-1`` (default) the tool frame (for a tree the last link's frame), with zero
        columns for the joints not on the link's path from the base. ``frame`` gives the rows'
        axes: ``"world"`` (default) the base frame's (Pinocchio's ``getFrameJacobian`` with
        LOCAL_WORLD_ALIGNED), ``"local"`` the frame's own (LOCAL); a wrench (force, moment about
        the frame's origin) in those axes acting on the link gives the joint torques ``J^T f``.

        With multi-DOF joints (not :attr:`single_dof`): q of :attr:`nq` entries, shape (6, nv),
        dq in the velocity convention of :attr:`nv` (a free-flyer's linear velocity first, in
        its body's axes)."""
        single = self._m.single_dof
        q = _vector(q, self.n, "q") if single else self._configuration(q)
        link = _args.integer(link, "link", -1, maximum=self.n - 1)
        local = _args.choice(frame, "frame", _FRAMES) == "local"
        if single and link < 0 and not local:
            return (
                self._kinematics().jacobian(q)
                if self.is_serial
                else _core.tool_jacobian(self._m, q)
            )
        k, placement = (self.n - 1, self.tool) if link < 0 else (link, np.eye(4))
        return _core.multibody_frame_jacobian(self._m, q, k, placement, local)

    def __repr__(self) -> str:
        return f"Robot(name={self.name!r}, n={self.n}, convention={self.convention!r})"


def _reflected(term: str, r: float) -> float:
    """The factor that carries a motor's drive term ``term`` (``rotor``, ``viscous``,
    ``coulomb``, or a third friction term ``Fa`` / ``Fs``) to the one joint it drives alone
    through the reduction ``r`` (``q_m = r q``, ``tau = r tau_m``): ``r^2`` for the rotor inertia
    and viscous friction, ``|r|`` for Coulomb and Stribeck levels, ``r`` for the asymmetric
    term, whose sign follows the direction of turning."""
    if term in ("rotor", "viscous"):
        return r * r
    if term == "Fa":
        return r
    assert term in ("coulomb", "Fs"), term
    return abs(r)


def _direct_drives(T: np.ndarray) -> list:
    """Per joint j, ``(k, r)`` when motor k alone drives it and drives it alone (row k of the
    transmission ``T`` is ``r e_j``; the core's ``sole_joints``, the one place this is
    decided), else None: the joints whose motor's rotor inertia and friction act on them as
    ``r^2 Ia``, ``r^2 Fv``, ``|r| Fc``, ``|r| Fs`` and ``r Fa``."""
    T = np.asarray(T, dtype=float)
    out: list = [None] * T.shape[1]
    for k, j in enumerate(_core.sole_joints(T)):
        if j >= 0:
            out[j] = (k, float(T[k, j]))
    return out


def _drive_vector(x, n: int, name: str) -> np.ndarray:
    """A rotor inertia or friction argument ``x`` as :func:`_vector` gives it, refused (naming
    ``name`` and the entry) where negative."""
    v = _vector(x, n, name)
    bad = np.flatnonzero(v < 0)
    if bad.size:
        k = int(bad[0])
        raise _args.fail(
            name, f"has {float(v[k])!r} at entry {k + 1}; rotor inertia and friction are >= 0"
        )
    return v


def _vector(x, n: int, name: str, unit: str = "joint") -> np.ndarray:
    """``x`` as a finite float array of shape (n,), or ModelError naming ``name``, the expected
    shape and what was given (the offending ``unit``, 1-based, for a non-finite value)."""
    return _args.array(x, name, (n,), unit=unit)


def pseudo_inertia(p) -> np.ndarray:
    """The 4x4 pseudo-inertia ``[[tr(I)/2 1 - I, h], [h^T, m]]`` of the 10 inertial parameters
    ``XX XY XZ YY YZ ZZ MX MY MZ M`` (about the link-frame origin, in its frame)."""
    p = _args.array(p, "p", (10,))
    xx, xy, xz, yy, yz, zz, mx, my, mz, m = np.asarray(p, dtype=float)
    inertia = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    J = np.empty((4, 4))
    J[:3, :3] = 0.5 * np.trace(inertia) * np.eye(3) - inertia
    J[:3, 3] = J[3, :3] = (mx, my, mz)
    J[3, 3] = m
    return J
