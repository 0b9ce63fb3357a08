"""Generated inverse-dynamics code: the Newton-Euler recursion of a robot customised to its
model and base parameters, as C99 or IEC 61131-3 Structured Text (:func:`generate`), and the
generated-code object the controller and observer steps extend (:class:`GeneratedCode`)."""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .. import _args, _core
from ..base import BaseParameters, base_parameters
from ..robot import Robot, load
from .parameters import read_identified_parameters, read_parameter_file

__all__ = ["FUNCTIONS", "GeneratedCode", "generate", "identifier"]

FUNCTIONS = ("inverse_dynamics", "gravity", "regressor")
_ALIASES = {"id": "inverse_dynamics"}


class GeneratedCode:
    """Generated code and its operation counts.

    Attributes
    ----------
    lang : {"c", "st"}
    name : str
        Prefix of the generated functions (``NAME_inverse_dynamics`` ...).
    header, source : str
        C only: the header and source texts.
    text : str
        Structured Text only: the FUNCTION_BLOCKs.
    program : mindyn._core.STProgram
        Structured Text only: the same program as blocks (``comments``; ``blocks``, each with
        ``name``, typed ``inputs``, ``outputs``, ``locals``, a ``note`` and the ``body``), from
        which the C++ core wrote ``text`` (``program.text() == text``) and
        :func:`plcopen_project` writes the PLCopen XML.
    counts : dict
        Per function: ``{"mul", "add", "neg", "trig", "sign"}`` operation counts.
    names : list of str
        The parameters ``p`` in order.
    values : ndarray, shape (np,)
        Their values (the robot's own, or those given; baked in when ``numeric``), read-only:
        they describe the code written.
    geometry_snap : dict
        Constants of the geometry (joint transforms and axes, gravity) within ``tolerance``
        (1e-9) of 0 are taken as 0, and rotation or axis entries then alone in their row and
        column as +-1; ``count``: how many changed by more than round-off (e.g. cos
        1.57079632679 = 4.9e-12 from a URDF's truncated pi/2), ``largest``: the largest change.
        Also stated in the generated header comment.
    contacts : list of str
        The contact links whose wrenches the inverse dynamics takes (``f``, 6 per link, in this
        order), empty for none.
    wrench_frame : {"world", "local"}
        The axes of the contact wrenches.
    """

    def __init__(
        self,
        lang: str,
        name: str,
        out: dict,
        numeric: bool,
        header_name: str,
        contacts: Sequence[str] = (),
        wrench_frame: str = "world",
    ):
        self.lang = lang
        self.header_name = header_name
        self.name = name
        self.numeric = numeric
        self.header = out.get("header")
        self.source = out.get("source")
        self.text = out.get("text")
        self.program = out.get("program")
        self.counts = {k: dict(v) for k, v in out["counts"].items()}
        self.names = list(out["names"])
        self.values = _args.readonly(np.asarray(out["values"], dtype=float))
        self.geometry_snap = dict(out["geometry_snap"])
        self.contacts = list(contacts)
        self.wrench_frame = wrench_frame

    def write(self, path: str | Path) -> list[Path]:
        """Writes the code: C to ``path`` (``.c`` added when it does not end so: ``arm.v2`` is
        written as ``arm.v2.c``) and the header beside it
        under ``header_name`` (the name the source includes); ST to ``path``. Returns the paths
        written."""
        path = Path(_args.path(path, "path"))
        if self.lang == "st":
            assert self.text is not None
            path.write_text(self.text)
            return [path]
        src = path if path.suffix == ".c" else path.parent / (path.name + ".c")
        hdr = src.parent / self.header_name
        assert self.header is not None and self.source is not None
        hdr.write_text(self.header)
        src.write_text(self.source)
        return [hdr, src]

    def __repr__(self) -> str:
        c = ", ".join(f"{k}: {v['mul']} mul {v['add']} add" for k, v in self.counts.items())
        return f"GeneratedCode({self.lang!r}, {self.name!r}, {c})"


def _functions(what) -> list[str]:
    if isinstance(what, str):
        what = [w.strip() for w in what.split(",") if w.strip()]
    elif not isinstance(what, (list, tuple)) or not all(isinstance(w, str) for w in what):
        raise _args.fail("what", "must be a string or a list of strings (id, gravity, regressor)")
    out = []
    for w in what:
        w = _ALIASES.get(w, w)
        if w not in FUNCTIONS:
            raise _args.fail(
                "what",
                f"names an unknown function '{w}'; expected inverse_dynamics (id), gravity, "
                "regressor",
            )
        if w not in out:
            out.append(w)
    if not out:
        raise _args.fail(
            "what", "names no function; expected inverse_dynamics (id), gravity, regressor"
        )
    return out


def _check_lang(lang, trig) -> None:
    _args.choice(lang, "lang", ("c", "st"))
    _args.optional(_args.choice, trig, "trig", ("inline", "libm"))
    if trig is not None and lang != "c":
        raise _args.fail("trig", "applies to C only; Structured Text uses SIN and COS")


# as the C++ generator requires (Structured Text forbids double and trailing underscores)
_IDENTIFIER = re.compile(r"[A-Za-z](?:_?[A-Za-z0-9])*")
_HEADER = re.compile(r"[A-Za-z0-9_.+-]+\.h")


def _check_options(name, header_name, params) -> None:
    """Checks the parameter values (None, a file, or a vector; its length is checked once the
    parameters are known), the prefix of generated identifiers (letters, digits and single
    underscores, first a letter, at most 40 characters, as the generator requires) and the
    header file name (a plain file name ending in ``.h``), when given."""
    if params is not None and not isinstance(params, (str, Path)):
        _args.array(params, "params", (None,))
    ok = name is None or _IDENTIFIER.fullmatch(_args.text(name, "name"))
    if not ok or (name is not None and len(name) > 40):
        raise _args.fail(
            "name",
            f"'{name}' is not an identifier (letters, digits and single underscores, starting "
            "with a letter, at most 40 characters)",
        )
    if header_name is not None and not _HEADER.fullmatch(_args.text(header_name, "header_name")):
        raise _args.fail(
            "header_name", f"is '{header_name}'; expected a file name ending in '.h' (no folder)"
        )


def check_base_robot(base: BaseParameters, robot: Robot) -> None:
    """Refuses (an ArgumentError naming ``base``) base parameters of a robot other than
    ``robot``: the code is generated from ``robot``'s geometry and ``base``'s set, which must
    be computed for that geometry (its joints, axes, placements and gravity; the parameter
    values, friction model and drive side may differ)."""
    other = base.robot
    if other is robot:
        return
    expected = f"expected base parameters of robot '{robot.name}' (base_parameters(robot, ...))"

    def refuse(what: str):
        return _args.fail("base", f"is of robot '{other.name}', whose {what}; {expected}")

    if other.n != robot.n:
        raise refuse(f"{other.n} joints differ from the {robot.n} of robot '{robot.name}'")
    for k in range(robot.n):
        joint = f"joint {k + 1} ('{other.joint_names[k]}')"
        if other.joint_types[k] != robot.joint_types[k] or other.parents[k] != robot.parents[k]:
            raise refuse(f"{joint} differs in its type or parent")
        for what, a, b in (
            ("axis", other.axes[k], robot.axes[k]),
            ("placement", other.joint_pre(k), robot.joint_pre(k)),
            ("placement", other.joint_post(k), robot.joint_post(k)),
        ):
            if not np.allclose(a, b, rtol=1e-12, atol=1e-12):
                raise refuse(f"{joint} differs in its {what}")
    if not np.allclose(other.gravity, robot.gravity, rtol=1e-12, atol=1e-12):
        raise refuse(f"gravity {other.gravity.tolist()} differs from {robot.gravity.tolist()}")


def _parameter_values(
    params, names: Sequence[str], robot: Robot, *, rotor: bool, friction: bool, offset: bool
):
    """``params`` (None, the JSON of ``mindyn identify --json`` for
    :func:`read_identified_parameters`, another file for :func:`read_parameter_file`, or an
    array) as values of ``names``, base parameters of ``robot`` with those joint terms; None
    stays None."""
    if params is None:
        return None
    if isinstance(params, (str, Path)):
        identified = read_identified_parameters(
            params, names, robot=robot, rotor=rotor, friction=friction, offset=offset
        )
        return identified[0] if identified is not None else read_parameter_file(params, names)
    return _args.array(params, "params", (len(names),))


def _contact_links(robot: Robot, contacts) -> list[int]:
    """The joint indices of the contact links ``contacts`` (names of moving links of a robot with
    a floating base)."""
    if isinstance(contacts, (str, bytes)) or not isinstance(contacts, Sequence):
        raise _args.fail("contacts", "must be a sequence of link names")
    names = robot.link_names[1:]
    links = []
    for c in contacts:
        if not isinstance(c, str) or c not in names:
            raise _args.fail(
                "contacts",
                f"names {c!r}, no moving link of robot '{robot.name}' ({', '.join(names)})"
                + robot._fixed_link_hint(c),
            )
        if names.index(c) in links:
            raise _args.fail("contacts", f"names the link {c!r} twice")
        links.append(names.index(c))
    if links and not any(kind in ("floating", "planar") for kind in robot.joint_types):
        raise _args.fail(
            "contacts",
            f"apply to a floating base (a free-flyer or planar root joint); robot "
            f"'{robot.name}' has a fixed base (load it with root_joint='floating')",
        )
    return links


def identifier(name: str) -> str:
    """The default prefix of generated identifiers: ``name`` in letters, digits and single
    underscores, starting with a letter, at most 40 characters."""
    _args.text(name, "name")
    s = re.sub(r"[^A-Za-z0-9]+", "_", name).strip("_")
    s = re.sub(r"_+", "_", s)
    if not s or not s[0].isalpha():
        s = "robot_" + s
    return s[:40].rstrip("_")


def generate(
    robot: Robot | str,
    *,
    lang: str = "c",
    what: Sequence[str] | str = FUNCTIONS,
    rotor: bool = False,
    friction: bool = False,
    params: str | Path | Sequence[float] | None = None,
    numeric: bool = False,
    name: str | None = None,
    base: bool | BaseParameters = True,
    header_name: str | None = None,
    minimise: str = "operations",
    trig: str | None = None,
    offset: bool = False,
    contacts: Sequence[str] = (),
    wrench_frame: str = "world",
) -> GeneratedCode:
    """Generates inverse-dynamics code for ``robot``.

    A floating base (a robot loaded with ``root_joint="floating"`` or ``"planar"``, or any
    free-flyer or planar joint on the fixed base, revolute and prismatic joints below it): C
    only, the inertial parameters only (no ``rotor``, ``friction`` or ``offset``); ``q`` has
    ``robot.nq`` entries and ``dq``, ``ddq`` and ``tau`` ``robot.nv``, in Pinocchio's
    convention (a free-flyer's ``q``: position, then unit quaternion x, y, z, w, which the code
    requires of norm 1 and does not normalise; its ``dq``: linear, then angular velocity in the
    body's axes; ``ddq`` their derivative; its ``tau``: the force and moment on the body about
    its origin, in its axes). The inverse dynamics equals Pinocchio's ``rnea``, minus
    ``sum_c J_c^T f_c`` with ``contacts``; its first entries (the root joint's) are then the
    base wrench the contacts leave unexplained, zero when the motion agrees with them.

    Parameters
    ----------
    robot : Robot or str
        Anything :func:`mindyn.load` accepts.
    lang : {"c", "st"}
        C99 (header and source) or IEC 61131-3 Structured Text.
    what : sequence of str or str
        Functions to generate: ``inverse_dynamics`` (alias ``id``), ``gravity``, ``regressor``;
        a comma-separated string is accepted.
    rotor, friction : bool
        Include rotor inertia ``Ia`` and viscous / Coulomb friction ``Fv, Fc`` per joint, or per
        motor when ``robot.drive_side`` is ``"motor"`` (a description with transmissions, unless
        :meth:`Robot.with_drive_side` put them on the joints): motor k's velocity ``t_k . dq``
        and acceleration ``t_k . ddq`` (``t_k`` row k of ``T``) formed once each, its torque
        taken back to the joints by ``t_k^T``. The friction terms follow
        ``robot.friction_model`` (Coulomb, direction-dependent, smooth with ``tanh``, Stribeck
        with ``exp``; its velocities baked in; a third column ``Fa``/``Fs`` per slot where the
        model has one); the header says which and where.
    params : path or array, optional
        Parameter values, shape (np,): an array, the JSON of ``mindyn identify --json`` (read
        by :func:`read_identified_parameters`: its pruned parameters as zero) or another file
        read by :func:`read_parameter_file`. Default: the robot's own values (``p_b = Y pi``).
    numeric : bool
        Bake the values into inverse_dynamics and gravity (they then take no ``p``).
    name : str, optional
        Prefix of the generated identifiers (default: from the robot's name).
    base : bool or BaseParameters
        Base parameters (default: by the method :func:`mindyn.base_parameters` chooses), a
        given :class:`BaseParameters`, or ``False`` for all classical parameters (the classical
        recursion, for comparison). The header lists the base parameters with their formulas as
        ``BaseParameters.formulas`` writes them. A given set must be of ``robot``'s geometry
        (joints, axes, placements, gravity): another robot's is an ArgumentError.
    header_name : str, optional
        C: the header file name the source includes (default ``NAME.h``).
    minimise : {"operations", "additions"}
        What the choice among exact formulations of the recursion minimises (where the
        along-axis translations go, and whether a link's wrench is formed in its own frame or
        in the joint frame before the joint motion): multiplications plus additions, ties to
        fewer additions (default), or additions first, ties to fewer multiplications.
    trig : {"inline", "libm"}, optional
        C only: how sines and cosines are evaluated. ``"inline"`` (default): one call per
        angle of a routine in the generated source gives both, without branches or library
        calls for ``|x| <= 1e6`` and within 2.2e-16 of the C library (which it calls beyond, and
        for NaN and infinities); ``"libm"``: ``sin`` and ``cos`` of ``math.h``. Structured Text
        always uses ``SIN`` and ``COS``.
    offset : bool
        A constant torque offset per joint, ``Off1 .. OffN``, after the other parameters: added
        to the inverse dynamics, a unit column of the regressor, not part of the gravity torque
        (taken from ``base`` when a :class:`BaseParameters` is given).
    contacts : sequence of str
        A floating base only: links (names of ``robot.link_names``, not the fixed world) that
        receive a contact wrench; the inverse dynamics then takes ``f``, 6 entries per link in
        this order (force, then moment about the link's origin) after ``p``, and gives
        ``rnea(q, dq, ddq) - sum_c J_c^T f_c``, ``J_c`` the Jacobian of the link's origin (as
        :func:`mindyn.identification.floating.contact_jacobian`).
    wrench_frame : {"world", "local"}
        The axes of the contact wrenches: world axes (default; Pinocchio's LOCAL_WORLD_ALIGNED,
        as :class:`mindyn.identification.floating.FloatingLog`), or the link's own (a force/torque
        sensor's), which spares the rotations.
    """
    robot = load(robot) if not isinstance(robot, Robot) else robot
    rotor, friction = _args.flag(rotor, "rotor"), _args.flag(friction, "friction")
    numeric = _args.flag(numeric, "numeric")
    offset = _args.flag(offset, "offset")
    if not isinstance(base, BaseParameters):
        base = _args.flag(base, "base")
    _check_lang(lang, trig)
    fs = _functions(what)
    _check_options(name, header_name, params)
    _args.choice(minimise, "minimise", ("operations", "additions"))
    _args.choice(wrench_frame, "wrench_frame", ("world", "local"))
    links = _contact_links(robot, contacts)
    name = name if name is not None else identifier(robot.name)
    if isinstance(base, BaseParameters):
        check_base_robot(base, robot)
        if base.rotor != rotor or base.friction != friction:
            rotor, friction = base.rotor, base.friction
        offset = base.offset
        bp_core = base._b
        names = base.names
        formulas = base.formulas[: bp_core.n]
    elif base:
        # the projection method, or the recursive one where the projection method refuses
        bp = base_parameters(robot, rotor=rotor, friction=friction, offset=offset)
        bp_core = bp._b
        names = bp.names
        formulas = bp.formulas
    else:
        bp_core = formulas = None
        names = list(
            _core.classical_parameter_names(robot._m, rotor=rotor, friction=friction, offset=offset)
        )
    values = _parameter_values(
        params, names, robot, rotor=rotor, friction=friction, offset=bool(offset)
    )
    out = _core.generate_code(
        robot._m,
        bp_core,  # type: ignore[arg-type]  # None: the classical parameters (the binding takes it)
        rotor=rotor,
        friction=friction,
        functions=fs,
        name=name,
        numeric=numeric,
        values=values,
        lang=lang,
        header_name=header_name or f"{name}.h",
        minimise=minimise,
        inline_trig=trig != "libm",
        offset=offset,
        formulas=formulas,  # as mindyn base prints them (BaseParameters.formulas)
        contacts=links,
        world_wrenches=wrench_frame == "world",
    )
    return GeneratedCode(
        lang, name, out, numeric, header_name or f"{name}.h", list(contacts), wrench_frame
    )
