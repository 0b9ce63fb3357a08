"""Writing identified classical parameters back into a robot description.

:func:`write_urdf` rewrites the URDF a robot was loaded from with new inertials and joint
friction (and a sidecar YAML for what URDF has no place for: rotor inertia, torque offsets);
:func:`write_yaml` rewrites a YAML DH/MDH table. Both take the classical parameters as a mapping
from their names (``XX1 .. M1``, optionally ``Ia1``, ``Fv1 Fc1`` and ``Off1`` per joint, all
joints alike) to values, or as a vector in a classical layout, and write numbers with ``repr``
precision, so that ``mindyn.load`` of the result gives back the same parameters.
"""

from __future__ import annotations

import io
import math
import numbers
import re
import xml.etree.ElementTree as ET
import xml.parsers.expat
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from . import _args, _sidecar
from ._args import ArgumentError
from ._core import OFFSET_PREFIX as _OFF
from ._core import ModelError, RobotFileNotFoundError
from .robot import Robot, _direct_drives, _reflected

__all__ = [
    "Export",
    "JointTerms",
    "classical_terms",
    "read_joint_terms",
    "write_urdf",
    "write_yaml",
]

_TERMS = _sidecar.TERMS


@dataclass
class JointTerms:
    """Validated classical parameters: ``inertial`` (10 n) and, per joint, the optional terms
    (``None`` when absent); ``third`` the friction model's third term, named ``third_name``
    (``Fa`` or ``Fs``)."""

    inertial: np.ndarray
    rotor: np.ndarray | None = None
    viscous: np.ndarray | None = None
    coulomb: np.ndarray | None = None
    offset: np.ndarray | None = None
    third: np.ndarray | None = None
    third_name: str = ""

    def joint_terms(self) -> dict[str, np.ndarray]:
        """The per-joint terms present, by their name prefix (``Ia``, ``Fv``, ``Fc``, ``Fa`` or
        ``Fs``, ``Off``)."""
        out = {"Ia": self.rotor, "Fv": self.viscous, "Fc": self.coulomb}
        if self.third is not None:
            out[self.third_name] = self.third
        out[_OFF] = self.offset
        return {k: v for k, v in out.items() if v is not None}


@dataclass
class Export:
    """What an export wrote: the description, the sidecar YAML (``None`` if none) and notes on
    values that needed a choice (zero masses, inertias that are not physical, ...)."""

    path: Path
    sidecar: Path | None = None
    notes: list[str] = field(default_factory=list)


# -- the classical parameters -----------------------------------------------------------------
def classical_terms(robot: Robot, classical, *, what: str = "classical parameters") -> JointTerms:
    """Checks ``classical`` against ``robot`` and splits it.

    ``classical`` is a mapping ``{name: value}`` holding exactly the names of one classical
    layout of the robot (``robot.parameter_names(rotor, friction)``, the friction columns those
    of its friction model), optionally with ``Off1 .. OffN``, or a vector in a classical layout
    (per joint 10, 11 with rotor inertia, 10 + c with friction of ``c`` columns, 11 + c with
    both); anything else (names missing or unknown, a value that is not a finite number) is an
    :class:`~mindyn.ArgumentError`; a negative rotor inertia or friction value (``Ia``, ``Fv``,
    ``Fc``) a :class:`~mindyn.ModelError`. ``what`` names the input in error messages."""
    _args.instance(robot, "robot", Robot)
    _args.text(what, "what")
    if isinstance(classical, Mapping):
        terms = _from_mapping(robot, classical, what)
    else:
        terms = _from_vector(robot, classical, what)
    for key, values in (("Ia", terms.rotor), ("Fv", terms.viscous), ("Fc", terms.coulomb)):
        if values is None or not np.any(values < 0):
            continue
        k = int(np.flatnonzero(values < 0)[0])
        raise ModelError(
            f"{what}: {key}{k + 1} = {values[k]:.6g} is negative; a robot description's rotor "
            "inertia and friction are >= 0 (the physically consistent estimate, "
            "consistent=True, keeps them so)"
        )
    return terms


def _from_vector(robot: Robot, classical, what: str) -> JointTerms:
    n = robot.n
    c = _friction_columns(robot)
    p = _args.params(classical, what, n, (10, 11, 10 + c, 11 + c), allow_none=False)
    per = p.size // n
    rotor = per in (11, 11 + c)
    friction = per in (10 + c, 11 + c)
    rows = p.reshape(n, per)
    out = JointTerms(inertial=rows[:, :10].reshape(-1).copy())
    if rotor:
        out.rotor = rows[:, 10].copy()
    if friction:
        f = 11 if rotor else 10
        out.viscous = rows[:, f].copy()
        out.coulomb = rows[:, f + 1].copy()
        if c == 3:
            out.third, out.third_name = rows[:, f + 2].copy(), _third_name(robot)
    return out


def _friction_columns(robot: Robot) -> int:
    """The number of friction terms of the robot's friction model (2 or 3)."""
    return 3 if _third_name(robot) else 2


def _third_name(robot: Robot) -> str:
    """The name prefix of the third friction term of the robot's friction model, or ''."""
    third = _sidecar.FRICTION_MODELS[robot.friction_model["kind"]][0]
    return third or ""


def _from_mapping(robot: Robot, classical: Mapping, what: str) -> JointTerms:
    n = robot.n
    keys = list(classical)
    bad = [k for k in keys if not isinstance(k, str)]
    if bad:
        raise ArgumentError(f"{what}: the names must be text, got {bad[0]!r}")
    has = {p: any(k.startswith(p) and k[len(p) :].isdigit() for k in keys) for p in _TERMS}
    rotor, friction = has["Ia"], has["Fv"] or has["Fc"] or has["Fa"] or has["Fs"]
    expected = robot.parameter_names(rotor=rotor, friction=friction, offset=has[_OFF])
    missing = [k for k in expected if k not in classical]
    unknown = [k for k in keys if k not in set(expected)]
    if missing or unknown:
        parts = []
        if unknown:
            parts.append(f"unknown {_few(unknown)}")
        if missing:
            parts.append(f"missing {_few(missing)}")
        third = _third_name(robot)
        words = "Fv, Fc" + (f", {third}" if third else "")
        extras = [t for t, on in (("Ia", rotor), (words, friction), (_OFF, has[_OFF])) if on]
        layout = "XX..M" + "".join(f", {t}" for t in extras)
        raise ArgumentError(
            f"{what}: {'; '.join(parts)} (robot '{robot.name}' has {n} joints: expected "
            f"{layout} for joints 1..{n}, {len(expected)} names)"
        )
    values = {}
    for k in expected:
        v = classical[k]
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real):
            raise ArgumentError(f"{what}: '{k}' is {v!r}; expected a number")
        try:
            x = float(v)
        except OverflowError:  # an integer beyond a double
            raise ArgumentError(
                f"{what}: '{k}' is an integer of {len(str(abs(math.trunc(v))))} digits, too large "
                "for a double"
            ) from None
        if not math.isfinite(x):
            raise ArgumentError(f"{what}: '{k}' is {x}; expected a finite number")
        values[k] = x

    def column(prefix: str) -> np.ndarray:
        return np.array([values[f"{prefix}{k + 1}"] for k in range(n)])

    out = JointTerms(inertial=np.array([values[k] for k in robot.param_names]))
    if rotor:
        out.rotor = column("Ia")
    if friction:
        out.viscous, out.coulomb = column("Fv"), column("Fc")
        if _third_name(robot):
            out.third_name = _third_name(robot)
            out.third = column(out.third_name)
    if has[_OFF]:
        out.offset = column(_OFF)
    return out


def _joint_side_terms(
    robot: Robot, terms: JointTerms, kept: str = "in the joint-terms file"
) -> tuple[JointTerms, list[str]]:
    """The terms as a description's per-joint rotor inertia and friction can carry them (URDF
    ``<dynamics damping friction>``, a YAML table's ``rotor_inertia`` and ``friction``), and
    notes. On the joint side, the terms as they are. On the motor side (slot k is motor k,
    acting as ``t_k^T (Ia_k t_k . ddq + Fv_k v_k + Fc_k sign v_k)``, ``v_k = t_k . dq``): a joint
    driven by a motor of its own alone (row ``k`` of ``T`` is ``r e_j``) gets its motor's terms as
    they act on the joint, ``r^2 Ia_k``, ``r^2 Fv_k``, ``|r| Fc_k``, exactly (what the loader
    divides back); a joint whose motor turns with other joints (or that several motors drive)
    cannot carry them per joint: 0 there, said in a note (the sidecar has the motor values)."""
    if robot.drive_side != "motor" or (terms.rotor is None and terms.viscous is None):
        return terms, []
    assert robot.transmission is not None  # the motor side has one
    T = robot.transmission.T
    zeros = np.zeros(robot.n)
    out = JointTerms(
        terms.inertial,
        None if terms.rotor is None else zeros.copy(),
        None if terms.viscous is None else zeros.copy(),
        None if terms.coulomb is None else zeros.copy(),
        terms.offset,
        None if terms.third is None else zeros.copy(),
        terms.third_name,
    )
    coupled = []
    for j, direct in enumerate(_direct_drives(T)):
        if direct is None:
            coupled.append(j)
            continue
        k, r = direct
        if terms.rotor is not None and out.rotor is not None:
            out.rotor[j] = _reflected("rotor", r) * terms.rotor[k]
        if terms.viscous is not None and out.viscous is not None:
            assert terms.coulomb is not None and out.coulomb is not None  # given with viscous
            out.viscous[j] = _reflected("viscous", r) * terms.viscous[k]
            out.coulomb[j] = _reflected("coulomb", r) * terms.coulomb[k]
            if terms.third is not None and out.third is not None:  # as the loader divides
                out.third[j] = _reflected(terms.third_name, r) * terms.third[k]
    notes = [
        "rotor inertia and friction on the motors: each directly driven joint carries its "
        "motor's as they act on the joint (r^2 Ia, r^2 Fv, |r| Fc, r the reduction)"
    ]
    if coupled:
        notes.append(_coupled_note(robot, coupled, kept))
    return out, notes


def _coupled_note(robot: Robot, coupled: list[int], kept: str) -> str:
    """The note on the joints whose terms cannot be written per joint, saying why of each of
    their motors: it turns with several joints, or it drives one joint that other motors drive
    too (a coupled wrist's first motor)."""
    assert robot.transmission is not None  # the motor side has one
    T, motors = robot.transmission.T, robot.transmission.motors
    via = sorted({int(k) for j in coupled for k in np.flatnonzero(T[:, j])})
    several = [k for k in via if np.count_nonzero(T[k]) > 1]
    shared = [k for k in via if k not in several]
    reasons = []
    if several:
        verb = "turns" if len(several) == 1 else "turn"
        reasons.append(f"{', '.join(repr(motors[k]) for k in several)} {verb} with several joints")
    if shared:
        alone = ", ".join(
            f"{motors[k]!r} drives {robot.joint_names[int(np.flatnonzero(T[k])[0])]!r}"
            for k in shared
        )
        reasons.append(f"{alone}, which other motors drive too")
    names = ", ".join(f"'{robot.joint_names[j]}'" for j in coupled)
    return (
        f"joints {names}: the rotor inertia and friction of motors "
        f"{', '.join(repr(motors[k]) for k in via)} cannot be written per joint "
        f"({'; '.join(reasons)}): 0 there; the motor values are {kept}"
    )


def unread_transmission_notes(robot: Robot, written: str) -> list[str]:
    """A note per transmission of a type the loader does not read that drives joints of the
    model (:attr:`~mindyn.Robot.unread_transmissions`): ``written`` says what the output does
    with it; its joints' terms are written as those of directly driven joints."""
    return [
        f"transmission '{t['name']}' ({t['type']}) was not read: {written}; joint(s) "
        + ", ".join(f"'{j}'" for j in t["modelled_directly"])
        + " written as directly driven (ratio 1)"
        for t in robot.unread_transmissions
        if t["modelled_directly"]
    ]


def _few(names: list[str], most: int = 6) -> str:
    shown = ", ".join(f"'{k}'" for k in names[:most])
    return shown + (f" and {len(names) - most} more" if len(names) > most else "")


def _num(x: float) -> str:
    """The shortest text that reads back as exactly ``x`` (``repr``), for XML attributes."""
    return repr(float(x))


# -- URDF -------------------------------------------------------------------------------------
def write_urdf(
    robot: Robot,
    classical,
    path,
    *,
    source=None,
    sidecar=None,
) -> Export:
    """Writes the URDF ``robot`` was loaded from with ``classical`` as its dynamics.

    Parameters
    ----------
    robot : Robot
        Loaded from a URDF (with the ``tip`` the parameters were identified for). A floating or
        planar root joint the loader added (``root_joint=``) is not written, as the source does
        not hold it (a note says so): load the written file with the same ``root_joint``.
    classical : mapping or array_like
        Classical parameters, see :func:`classical_terms`: about each link-frame origin, in link
        axes; a link frame is the URDF frame of the link that the moving joint moves.
    path : str or Path
        The URDF to write (its folder is created when missing).
    source : str or Path, optional
        The URDF to start from; default ``robot.source``.
    sidecar : str or Path, optional
        The YAML for the joint terms (default ``<path stem>.joints.yaml`` beside ``path``, written
        only when ``classical`` has joint terms).

    Returns
    -------
    Export
        The files written and notes.

    Each moving link of the model (a chain or a tree) gets one ``<inertial>``: mass ``M``,
    centre of mass ``(MX, MY, MZ) / M`` and the inertia about it, in link axes (``rpy="0 0
    0"``); comments inside a replaced ``<inertial>`` go with it. The links merged into a moving
    link when the robot was loaded (children on fixed joints, and moving joints locked at
    ``q = 0`` clamped into their limits: off a chain, or mimic joints) lose their
    ``<inertial>``, which a comment replaces, so that the total is the identified one. Links
    before the first moving joint and off the model are kept as they were, as is everything
    else in the file (comments included). A link of zero mass and
    zero first moment gets mass 0 and its rotational inertia at the link origin (a zero
    inertial if it has none); the notes say so. ``Fv`` and ``Fc`` go into the joint's
    ``<dynamics damping= friction=>``; when the parameters have no friction, the model joints'
    damping and friction are set to 0, so that the file describes the identified model (a note
    names the joints whose non-zero values that replaces). ``Ia``,
    ``Fv``, ``Fc`` and ``Off`` are also written to the sidecar YAML, with their meaning and unit
    (:func:`read_joint_terms` reads it back). With rotor inertia and friction on the motors
    (:attr:`~mindyn.Robot.drive_side`), a directly driven joint's ``<dynamics>`` is its motor's
    friction as it acts on the joint (``r^2 Fv``, ``|r| Fc``), a joint of a motor that turns
    with several joints gets 0 (a note says so), and the sidecar has the motor values
    (``drive_side: motor``, each row naming its motor). A transmission of a type the loader does
    not read (:attr:`~mindyn.Robot.unread_transmissions`) stays in the file as written; a note
    says that its joints were written as directly driven.

    Raises
    ------
    ModelError
        ``classical`` does not fit the robot, a mass is negative (or zero with a first moment),
        the robot is not from a URDF, or ``source`` does not hold the robot's joints.
    """
    _args.instance(robot, "robot", Robot)
    _args.path(path, "path")
    _args.optional(_args.path, source, "source")
    _args.optional(_args.path, sidecar, "sidecar")
    if robot.convention != "urdf":
        raise ModelError(
            f"robot '{robot.name}' is a {robot.convention} table, not a URDF"
            + (": export it with write_yaml" if robot.convention in ("dh", "mdh") else "")
        )
    terms = classical_terms(robot, classical)
    src = Path(robot.source if source is None else source)
    doc = _UrdfDocument(src)
    joint_side, reflected = _joint_side_terms(robot, terms)
    notes = doc.set_chain(robot, joint_side) + reflected
    notes += unread_transmission_notes(robot, "kept in the file as the source writes it")
    out = Path(path)
    side = _sidecar_path(sidecar, out) if terms.joint_terms() or sidecar is not None else None
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(doc.text(), encoding="utf-8")
    written = Export(out, notes=notes)
    if side is not None:
        _write_sidecar(side, robot, terms, out, urdf=True)
        written.sidecar = side
        written.notes += _shape_note(robot, terms, side, "the joints' <dynamics> hold")
    return written


class XmlDocument:
    """An XML description (``kind``: URDF, MJCF) parsed with its comments, to be edited and
    written back with everything else as it was."""

    def __init__(self, path: Path, kind: str):
        if not path.is_file():
            raise RobotFileNotFoundError(f"{kind} file '{path}' does not exist")
        self.path = path
        raw = path.read_bytes()
        try:
            raw.decode("utf-8")
        except UnicodeDecodeError as e:
            raise ModelError(f"{path}: not UTF-8 text (byte at offset {e.start})") from None
        builder = ET.TreeBuilder(insert_comments=True, insert_pis=True)
        parser = ET.XMLParser(target=builder)
        try:
            parser.feed(raw)
            self.root = parser.close()
        except ET.ParseError as e:
            line, col = e.position
            raise ModelError(f"{path}:{line}:{col + 1}: not valid XML: {e}") from None
        self.prolog = self._prolog(raw)
        self._names_as_written(raw)

    def _names_as_written(self, raw: bytes) -> None:
        """Turns ElementTree's ``{uri}name`` back into ``prefix:name`` (``name`` for the default
        namespace, as urdfdom reads it) and declares the namespaces on the root again, so that
        the file is written with the names and declarations it had."""
        declared: dict[str, str] = {}
        for _, (prefix, uri) in ET.iterparse(io.BytesIO(raw), events=("start-ns",)):
            declared.setdefault(prefix, uri)
        if not declared:
            return
        prefix_of: dict[str, str] = {}
        for prefix, uri in declared.items():
            prefix_of.setdefault(uri, prefix)

        def plain(name: str) -> str:
            if not name.startswith("{"):
                return name
            uri, local = name[1:].split("}", 1)
            prefix = prefix_of.get(uri, "")
            return f"{prefix}:{local}" if prefix else local

        for e in self.root.iter():
            if isinstance(e.tag, str):
                e.tag = plain(e.tag)
            if any(k.startswith("{") for k in e.attrib):
                attrib = {plain(k): v for k, v in e.attrib.items()}
                e.attrib.clear()
                e.attrib.update(attrib)
        for prefix, uri in declared.items():
            self.root.set(f"xmlns:{prefix}" if prefix else "xmlns", uri)

    @staticmethod
    def _prolog(raw: bytes) -> str:
        """The text before the root element (XML declaration, comments), kept verbatim."""
        start = []
        p = xml.parsers.expat.ParserCreate()

        def first(name, attrs):
            start.append(p.CurrentByteIndex)
            raise StopIteration

        p.StartElementHandler = first
        try:
            p.Parse(raw, True)
        except StopIteration:
            pass
        return raw[: start[0]].decode("utf-8") if start else ""

    def text(self) -> str:
        body = ET.tostring(self.root, encoding="unicode")
        # ElementTree closes empty elements with " />"; URDFs mostly write "/>". Outside comments
        # and processing instructions, whose text is written as it is, every ">" of the output
        # ends a tag (ElementTree escapes it in text and attribute values).
        parts = re.split(r"(<!--.*?-->|<\?.*?\?>)", body, flags=re.DOTALL)
        for i in range(0, len(parts), 2):
            parts[i] = parts[i].replace(" />", "/>")
        return self.prolog + "".join(parts) + "\n"


class _UrdfDocument(XmlDocument):
    """A URDF file parsed with its comments, to be edited and written back."""

    def __init__(self, path: Path):
        super().__init__(path, "URDF")
        if self.root.tag != "robot":
            raise ModelError(f"{path}: the root element is <{self.root.tag}>, not <robot>")
        self.links = {e.get("name"): e for e in self.root if e.tag == "link" and e.get("name")}
        self.joints = [e for e in self.root if e.tag == "joint"]
        self.entering = {}  # child link -> joint element
        self.children: dict[str, list] = {}  # parent link -> joint elements
        for j in self.joints:
            child, parent = self._end(j, "child"), self._end(j, "parent")
            self.entering[child] = j
            self.children.setdefault(parent, []).append(j)

    def _end(self, joint, which: str) -> str:
        e = joint.find(which)
        return e.get("link", "") if e is not None else ""

    def added_root(self, robot: Robot) -> bool:
        """Whether the robot's first joint is the free-flyer or planar ``root_joint`` the loader
        put above the file's root link (``load(..., root_joint=...)``), not a joint of the file:
        the file's root link, entered by no joint, is the robot's first body, below ``world``."""
        bodies = robot.link_names[1:]
        return (
            bool(bodies)
            and robot.link_names[0] == "world"
            and robot.joint_names[0] == "root_joint"
            and robot.joint_types[0] in ("floating", "planar")
            and bodies[0] in self.links
            and bodies[0] not in self.entering
        )

    def set_chain(self, robot: Robot, terms: JointTerms) -> list[str]:
        bodies = robot.link_names[1:]
        added = self.added_root(robot)
        for k, name in enumerate(bodies):
            j = self.entering.get(name)
            if added and k == 0:
                continue
            if name not in self.links or j is None or j.get("name") != robot.joint_names[k]:
                raise ModelError(
                    f"{self.path}: has no joint '{robot.joint_names[k]}' moving link '{name}': "
                    f"it is not the URDF robot '{robot.name}' was loaded from"
                )
        notes = []
        if added:  # a URDF holds it as a joint of the file, which the same loading would double
            kind = robot.joint_types[0]
            notes.append(
                f"the {kind} root joint 'root_joint' was added by the loader above the root link "
                f"'{bodies[0]}' and is not written: load the file with root_joint='{kind}' for the "
                "same robot"
            )
        body_set = set(bodies)
        for k, name in enumerate(bodies):
            merged = [
                m
                for m in self._merged_below(name, body_set)
                if self._drop_inertial(self.links[m], name)
            ]
            p = terms.inertial[10 * k : 10 * k + 10]
            notes += self._set_inertial(self.links[name], p, k + 1, name)
            if merged:
                notes.append(
                    f"link '{name}' holds the identified inertia of the links merged into it, "
                    f"whose <inertial> was removed: {', '.join(merged)}"
                )
        zeroed = []
        for k, name in enumerate(bodies):
            if added and k == 0:
                continue
            joint = self.entering[name]
            if terms.viscous is None and self._has_friction(joint):
                zeroed.append(joint.get("name", "?"))
            fv = 0.0 if terms.viscous is None else terms.viscous[k]
            fc = 0.0 if terms.coulomb is None else terms.coulomb[k]
            self._set_dynamics(joint, fv, fc)
        if zeroed:
            notes.append(
                "the parameters have no friction: the <dynamics> damping and friction of joints "
                f"{', '.join(repr(j) for j in zeroed)}, non-zero in the description, written as 0"
            )
        return notes

    @staticmethod
    def _has_friction(joint) -> bool:
        """Whether `joint`'s <dynamics> gives a non-zero damping or friction."""
        dyn = joint.find("dynamics")
        if dyn is None:
            return False
        for key in ("damping", "friction"):
            try:
                if float(dyn.get(key, "0")) != 0.0:
                    return True
            except ValueError:
                return True  # not a number: replaced all the same
        return False

    def _merged_below(self, body: str, bodies: set) -> list[str]:
        """The links merged into `body` by the loader: all below it, up to the next body."""
        out, stack = [], [body]
        while stack:  # depth first, in the file's order
            link = stack.pop()
            if link != body:
                out.append(link)
            kids = [self._end(j, "child") for j in self.children.get(link, [])]
            stack += [c for c in reversed(kids) if c not in bodies]
        return [m for m in out if m in self.links]

    def _element(self, parent, tag: str, indent: str, attrib=None):
        """A new last child of `parent` (whose own line starts with `indent`), indented one
        level deeper than `parent`, or like its other children."""
        e = ET.Element(tag, attrib or {})
        kids = list(parent)
        if not kids:
            parent.text = "\n" + indent + "  "
            e.tail = "\n" + indent
        else:
            e.tail = kids[-1].tail
            kids[-1].tail = _child_ws(parent, indent)
        parent.append(e)
        return e

    def _set_inertial(self, link, p: np.ndarray, index: int, name: str) -> list[str]:
        m, com, Ic, notes = centroidal(p, index, name)
        old = [e for e in link if e.tag == "inertial"]
        if old:
            where = list(link).index(old[0])
            tail = old[0].tail
            for e in old:
                link.remove(e)
            new = ET.Element("inertial")
            new.tail = tail
            link.insert(where, new)
        else:
            new = self._element(link, "inertial", self._indent(link))
        level = _child_ws(link, self._indent(link)).rsplit("\n", 1)[1]
        xyz = " ".join(_num(v) for v in com)
        self._element(new, "origin", level, {"xyz": xyz, "rpy": "0 0 0"})
        self._element(new, "mass", level, {"value": _num(m)})
        names = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
        values = (Ic[0, 0], Ic[0, 1], Ic[0, 2], Ic[1, 1], Ic[1, 2], Ic[2, 2])
        self._element(new, "inertia", level, {k: _num(v) for k, v in zip(names, values)})
        return notes

    def _indent(self, element) -> str:
        """The indentation of the line of `element`, a child of the root."""
        kids = list(self.root)
        i = kids.index(element)
        ws = (self.root.text if i == 0 else kids[i - 1].tail) or ""
        return ws.rsplit("\n", 1)[1] if "\n" in ws and not ws.strip() else ""

    def _drop_inertial(self, link, body: str) -> bool:
        """Replaces `link`'s <inertial> by a comment; False if it had none."""
        found = False
        for i, e in enumerate(list(link)):
            if e.tag != "inertial":
                continue
            c = ET.Comment(f" inertial merged into link '{body}' by mindyn export ")
            c.tail = e.tail
            link.remove(e)
            link.insert(i, c)
            found = True
        return found

    def _set_dynamics(self, joint, viscous: float, coulomb: float) -> None:
        dyn = joint.find("dynamics")
        if dyn is None:
            if viscous == 0 and coulomb == 0:
                return
            dyn = self._element(joint, "dynamics", self._indent(joint))
        dyn.set("damping", _num(viscous))
        dyn.set("friction", _num(coulomb))


def centroidal(p: np.ndarray, index: int, name: str, *, kind: str = "a URDF"):
    """``(mass, centre of mass, inertia about it, notes)`` of link ``index`` (1-based, named
    ``name``) from its ten classical parameters ``p``; a zero mass gives the rotational inertia
    at the link origin. Raises ModelError for a negative mass, or a zero one with a first
    moment, which no inertial of ``kind`` holds."""
    notes = []
    m = float(p[9])
    h = np.array(p[6:9], dtype=float)
    Io = np.array([[p[0], p[1], p[2]], [p[1], p[3], p[4]], [p[2], p[4], p[5]]], dtype=float)
    if m < 0:
        raise ModelError(
            f"M{index} = {m!r} (link '{name}') is negative; {kind} mass must be >= 0 "
            "(export physically consistent parameters)"
        )
    if m == 0:
        if np.any(h != 0):
            raise ModelError(
                f"M{index} = 0 (link '{name}') with a first moment (MX{index}, MY{index}, "
                f"MZ{index}) = ({', '.join(repr(float(x)) for x in h)}): no {kind[2:]} "
                "inertial has that"
            )
        notes.append(
            f"link '{name}': M{index} = 0, no centre of mass; "
            + (
                "zero inertial written"
                if not np.any(Io)
                else "its rotational inertia is written at the link origin"
            )
        )
        return m, np.zeros(3), Io, notes
    com = h / m
    Ic = Io - (np.dot(h, h) * np.eye(3) - np.outer(h, h)) / m
    ev = np.linalg.eigvalsh(Ic)
    if ev[0] < 0 or 2 * ev.max() > ev.sum() * (1 + 1e-12):
        notes.append(
            f"link '{name}': the inertia about its centre of mass (principal moments "
            f"{', '.join(f'{v:.4g}' for v in ev)}) is not that of a physical body"
        )
    return m, com, Ic, notes


def _child_ws(parent, indent: str) -> str:
    """The whitespace before `parent`'s children: as its first child has it, or one level (two
    spaces) deeper than `indent`."""
    text = parent.text or ""
    if len(parent) and "\n" in text and not text.strip():
        return "\n" + text.rsplit("\n", 1)[1]
    return "\n" + indent + "  "


# -- sidecar ----------------------------------------------------------------------------------
def default_sidecar(description) -> Path:
    """The joint-terms file written beside a description file when no other is named:
    ``OUT.joints.yaml`` beside ``OUT.urdf`` (or ``OUT.yaml``)."""
    out = Path(description)
    return out.with_name(out.stem + ".joints.yaml")


def _sidecar_path(sidecar, out: Path) -> Path:
    side = Path(sidecar) if sidecar is not None else default_sidecar(out)
    if side.absolute() == out.absolute():
        raise ModelError(f"the sidecar file '{side}' is the description file itself")
    return side


def _shape_note(robot: Robot, terms: JointTerms, side: Path, holds: str) -> list[str]:
    """The note that the description holds only viscous and Coulomb friction of a robot whose
    friction model has a shape (smooth, asymmetric, Stribeck), which the sidecar ``side``
    keeps; ``holds`` says where the description has them."""
    kind = robot.friction_model["kind"]
    if kind == "coulomb" or terms.coulomb is None:
        return []
    extra = [t for t in (terms.third_name,) if t]
    if _sidecar.FRICTION_MODELS[kind][1]:
        extra.append("velocity")
    return [
        f"friction model {kind}: {holds} Fv and Fc only; the model and its "
        f"{' and '.join(extra)} are in {side} (read back with joint_terms=)"
    ]


def _write_sidecar(path: Path, robot: Robot, terms: JointTerms, description: Path, urdf: bool):
    present = terms.joint_terms()
    motor_side = robot.drive_side == "motor" and any(k in present for k in ("Ia", "Fv", "Fc"))
    meaning = {}
    for key in present:
        text, rev, pri = _TERMS[key]
        if motor_side and key in _sidecar.MOTOR_TERMS:
            meaning[key] = f"{_sidecar.MOTOR_TERMS[key]} [{rev} for a rotary motor, {pri} linear]"
            continue
        if urdf and key == "Fv":
            text += "; also the URDF joint's <dynamics damping>"
        if urdf and key == "Fc":
            text += "; also the URDF joint's <dynamics friction>"
        meaning[key] = f"{text} [{rev} for a revolute joint, {pri} for a prismatic one]"
    model = robot.friction_model
    shaped = model["kind"] != "coulomb" and "Fc" in present
    widths = shaped and _sidecar.FRICTION_MODELS[model["kind"]][1]
    if widths:
        meaning["velocity"] = (
            "the friction model's velocity scale: "
            + ("the tanh width of Fc" if model["kind"] == "smooth" else "the Stribeck velocity")
            + " [rad/s for a revolute joint, m/s for a prismatic one; the motor's on the motor "
            "side]"
        )
    joints = []
    for k in range(robot.n):
        kind = robot.joint_types[k]
        unit = 1 if kind == "revolute" else 2
        row: dict[str, Any] = {"name": robot.joint_names[k], "index": k + 1, "type": kind}
        row.update({key: float(v[k]) for key, v in present.items()})
        units = {key: _TERMS[key][unit] for key in present}
        if widths:
            row["velocity"] = float(model["velocity"][k])
            units["velocity"] = ("rad/s", "m/s")[unit - 1]
        row["units"] = units
        joints.append(row)
    doc: dict[str, Any] = {"robot": robot.name, "description": description.name}
    if shaped:
        doc["friction_model"] = model["kind"]
    doc.update({"terms": meaning, "joints": joints})
    if motor_side:
        # row k's Ia, Fv, Fc are motor k's, in motor units, acting through row k of T
        doc["drive_side"] = "motor"
        assert robot.transmission is not None  # the motor side has one
        for k, row in enumerate(joints):
            row["motor"] = robot.transmission.motors[k]
        doc["terms"]["drive_side"] = (
            "motor: each row's Ia, Fv, Fc (and the friction model's terms) belong to the motor "
            "named in it (row k of the transmission T, q_m = T q): tau += T^T (Ia T ddq + "
            "f(T dq)), f the friction model's torque (Fv T dq + Fc sign(T dq) for Coulomb "
            f"friction), in motor units (kg m^2, N m s/rad, N m); {_OFF} stays the joint's"
        )
    head = (
        f"# Joint terms identified for robot '{robot.name}', written by mindyn export beside "
        f"{description.name}.\n# Per joint: the term's value in the unit given under 'units'.\n"
    )
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(head + yaml.safe_dump(doc, sort_keys=False, width=100), encoding="utf-8")


def read_joint_terms(path) -> dict[str, float]:
    """The joint terms of a sidecar YAML written by :func:`write_urdf` or :func:`write_yaml`, as
    ``{"Ia1": ..., "Fv1": ..., "Fc1": ..., "Off1": ..., ...}`` (the terms it holds, numbered by
    row). To load a robot with them: ``mindyn.load(path, joint_terms=...)``."""
    side = _sidecar.read(path)
    return {
        f"{key}{i}": float(row[key])
        for i, row in enumerate(side.rows, 1)
        for key in _TERMS
        if key in row
    }


class _TableDumper(yaml.SafeDumper):
    """Writes lists of numbers and short mappings of numbers on one line, as the bundled tables
    do (``gravity: [0, 0, -9.81]``, ``limits: {lower: -170, upper: 170}``)."""

    def represent_sequence(self, tag, sequence, flow_style=None):
        flat = all(isinstance(v, (int, float, str)) for v in sequence)
        return super().represent_sequence(tag, sequence, flow_style=flat or flow_style)

    def represent_mapping(self, tag, mapping, flow_style=None):
        items = mapping.values() if isinstance(mapping, dict) else []
        flat = len(mapping) <= 6 and all(isinstance(v, (int, float)) for v in items)
        return super().represent_mapping(tag, mapping, flow_style=flat or flow_style)


# -- YAML DH / MDH tables -----------------------------------------------------------------------
def _set_motor_terms(node, robot: Robot, terms: JointTerms, src: Path) -> None:
    """Writes each motor's own rotor inertia and friction into a table's ``transmissions`` (the
    matrix form's lists ``rotor_inertia``, ``viscous``, ``coulomb``, or the keys of each motor
    of the list form), in the order of its motors, on the motor side; removes them on the joint
    side (the joints' values then hold)."""
    motor = robot.drive_side == "motor"
    keys = (("rotor_inertia", terms.rotor), ("viscous", terms.viscous), ("coulomb", terms.coulomb))
    assert robot.transmission is not None  # a table with transmissions
    m = robot.transmission.n_motors
    if isinstance(node, dict):
        for key, v in keys:
            node.pop(key, None)
            if motor and v is not None:
                node[key] = [float(x) for x in v[:m]]
    elif isinstance(node, list) and len(node) == m and all(isinstance(e, dict) for e in node):
        for k, e in enumerate(node):
            for key, v in keys:
                e.pop(key, None)
                if motor and v is not None:
                    e[key] = float(v[k])
    else:
        raise ModelError(f"{src}: its 'transmissions' are not those robot '{robot.name}' has")


def write_yaml(robot: Robot, classical, path, *, source=None, sidecar=None) -> Export:
    """Writes the YAML DH/MDH table ``robot`` was loaded from with ``classical`` as its dynamics.

    Each joint's ``inertial`` becomes ``{XX, XY, XZ, YY, YZ, ZZ, MX, MY, MZ, M}`` (about the
    link origin, link axes: the loader's own form), its ``rotor_inertia`` ``Ia`` and its
    ``friction`` ``{viscous: Fv, coulomb: Fc}``; a term that ``classical`` does not have is
    removed (zero), so that ``mindyn.load(path).parameters(True, True)`` is ``classical`` with
    zeros for the absent terms. The rest of the table is kept, in its order; the YAML comments
    of the source are not. Torque offsets ``Off`` have no place in a table: when present they
    go to a sidecar YAML (default ``<path stem>.joints.yaml``), as in :func:`write_urdf`.
    With transmissions, ``drive_side`` records where the terms act; on the motor side the
    motors' own values go under ``transmissions`` (``rotor_inertia``, ``viscous``,
    ``coulomb``, one per motor, which the loader puts in the motor slots), and each directly
    driven joint carries its motor's terms as they act on it (``r^2 Ia``, ``r^2 Fv``,
    ``|r| Fc``; a joint of a coupled motor 0, with a note).
    """
    _args.instance(robot, "robot", Robot)
    _args.path(path, "path")
    _args.optional(_args.path, source, "source")
    _args.optional(_args.path, sidecar, "sidecar")
    if robot.convention not in ("dh", "mdh"):
        raise ModelError(
            f"robot '{robot.name}' is not from a YAML DH/MDH table ({robot.convention}): "
            + ("export it with write_urdf" if robot.convention == "urdf" else "nothing to rewrite")
        )
    terms = classical_terms(robot, classical)
    if source is None and not Path(robot.source).is_file():
        raise ModelError(
            f"robot '{robot.name}' was not read from a description file (source "
            f"'{robot.source}'): there is no table to rewrite"
        )
    src = Path(robot.source if source is None else source)
    doc = _sidecar.read_yaml(src, "robot description")
    joints = doc.get("joints") if isinstance(doc, dict) else None
    if not isinstance(joints, list) or len(joints) != robot.n:
        raise ModelError(
            f"{src}: expected a 'joints' list of {robot.n} joints: it is not the table robot "
            f"'{robot.name}' was loaded from"
        )
    names = ("XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M")
    motor_terms = terms
    terms, reflected = _joint_side_terms(robot, terms, "under 'transmissions'")
    if robot.transmission is not None:
        _set_motor_terms(doc.get("transmissions"), robot, motor_terms, src)
    for k, jn in enumerate(joints):
        if not isinstance(jn, dict):
            raise ModelError(f"{src}: joint {k + 1} is not a mapping")
        p = terms.inertial[10 * k : 10 * k + 10]
        if p[9] != 0:  # a negative mass refused, an inertia no body has noted, as for a URDF
            reflected += centroidal(p, k + 1, robot.link_names[k + 1], kind="a YAML table")[3]
        jn["inertial"] = {key: float(v) for key, v in zip(names, p)}
        jn.pop("rotor_inertia", None)
        if terms.rotor is not None:
            jn["rotor_inertia"] = float(terms.rotor[k])
        jn.pop("friction", None)
        if terms.viscous is not None:
            assert terms.coulomb is not None  # given with viscous
            jn["friction"] = {
                "viscous": float(terms.viscous[k]),
                "coulomb": float(terms.coulomb[k]),
            }
    parts = ["inertial parameters"]
    parts += [
        t for t, v in (("rotor inertia", terms.rotor), ("friction", terms.viscous)) if v is not None
    ]
    what = ", ".join(parts[:-1]) + " and " + parts[-1] if len(parts) > 1 else parts[0]
    if robot.transmission is not None and (terms.rotor is not None or terms.viscous is not None):
        # the side they were identified on; on the motor side the joints carry their motors'
        # terms as they act on them (the loader divides them back)
        doc["drive_side"] = robot.drive_side
        what += (
            " ("
            + ("of the motors, per joint" if robot.drive_side == "motor" else "on the joints")
            + ")"
        )
    note = f"The {what} of this table are identified values written by mindyn export."
    old_notes = doc.get("notes")
    doc["notes"] = f"{old_notes.rstrip()} {note}" if isinstance(old_notes, str) else note
    out = Path(path)
    shaped = robot.friction_model["kind"] != "coulomb" and terms.coulomb is not None
    keep = terms.offset is not None or sidecar is not None or shaped
    side = _sidecar_path(sidecar, out) if keep else None
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(yaml.dump(doc, Dumper=_TableDumper, sort_keys=False, width=100), "utf-8")
    written = Export(out, notes=reflected)
    if side is not None:
        _write_sidecar(side, robot, motor_terms, out, urdf=False)
        written.sidecar = side
        if terms.offset is not None:
            written.notes.append(f"torque offsets have no place in a DH/MDH table: see {side}")
        written.notes += _shape_note(robot, motor_terms, side, "the table's 'friction' holds")
    return written
