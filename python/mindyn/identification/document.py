"""The JSON document of ``mindyn identify --json`` read back: one check of the fields that
``identify-payload``, ``export``, ``predict``, ``detect`` and ``codegen --params`` take
from it.

A field is checked for its JSON type (``rotor: "no"`` is not a boolean, ``base_names: 7`` not a
list), numbers for being finite and within a double (a 400-digit integer is not), and the lists
for matching lengths; each failure is one :class:`~mindyn.identification.data.DataError` naming
the file and the field.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .. import _args, _sidecar
from .data import DataError, check_joint_names, read_json

if TYPE_CHECKING:
    from ..base import BaseParameters
    from ..robot import Robot

__all__ = ["FLAGS", "read_identification", "robot_on_drive_side", "with_identified_friction"]

#: The boolean fields: JSON ``true`` / ``false`` only.
FLAGS = ("rotor", "friction", "offset", "consistent")


def read_identification(
    source, *, need=(), what: str = "identification JSON", finite: bool = False
) -> dict:
    """The checked document of ``mindyn identify --json``: ``source`` a path or an already read
    mapping. ``need`` names the fields that must be present (``robot``, ``base_names``,
    ``base_values``, ``classical``, one of :data:`FLAGS`...); the others are checked when
    present; with ``finite`` a file holding NaN or Infinity anywhere is refused. Returns the
    document with ``base_values`` as floats and ``classical`` (when
    present) as a name -> float mapping.

    Raises
    ------
    DataError
        Not a JSON object, a needed field missing, or a field of the wrong type or range."""
    _args.instance(source, "source", (dict, str, Path), "an identification JSON (a dict or a path)")
    _args.instance(need, "need", (tuple, list), "a tuple of field names")
    _args.text(what, "what")
    finite = _args.flag(finite, "finite")
    if isinstance(source, (str, Path)):
        where = str(source)
        doc = read_json(source, what=what, finite=finite)
    else:
        where, doc = what, source
    obj = doc if isinstance(doc, dict) else {}
    missing = [k for k in need if obj.get(k) is None]
    if "classical" in missing:
        raise DataError(
            f"{where} has no 'classical' map of classical parameter values (it is written by "
            "an identification with consistent=True)"
        )
    if not isinstance(doc, dict):
        raise DataError(f"{where}: expected a JSON object (the JSON of mindyn identify)")
    if missing:
        raise DataError(
            f"{where}: lacks {', '.join(repr(k) for k in missing)} (the JSON of mindyn "
            "identify has them)"
        )
    out = dict(doc)
    for key in ("robot", "tip", "description"):
        v = doc.get(key)
        if key in doc and not isinstance(v, str) and not (key != "robot" and v is None):
            raise DataError(f"{where}: '{key}' is {_kind(v)}; expected text")
    for key in FLAGS:
        if key in doc and not isinstance(doc[key], bool):
            raise DataError(f"{where}: '{key}' is {_kind(doc[key])}; expected true or false")
    joints = doc.get("joints")
    if joints is not None and not (
        isinstance(joints, list) and all(isinstance(x, str) for x in joints)
    ):
        raise DataError(f"{where}: 'joints' is {_kind(joints)}; expected a list of joint names")
    if "base_names" in doc:
        names = doc["base_names"]
        if not isinstance(names, list) or not all(isinstance(x, str) for x in names):
            raise DataError(f"{where}: 'base_names' is {_kind(names)}; expected a list of names")
    if "base_values" in doc:
        values = doc["base_values"]
        if not isinstance(values, list):
            raise DataError(
                f"{where}: 'base_values' is {_kind(values)}; expected a list of numbers"
            )
        out["base_values"] = [
            _number(v, f"{where}: 'base_values' item {i + 1}") for i, v in enumerate(values)
        ]
        names = doc.get("base_names")
        if isinstance(names, list) and len(names) != len(values):
            raise DataError(f"{where}: {len(values)} 'base_values' for {len(names)} 'base_names'")
    side = doc.get("drive_side")
    if "drive_side" in doc and side not in ("motor", "joint"):
        raise DataError(f'{where}: \'drive_side\' is {_kind(side)}; expected "motor" or "joint"')
    fm = doc.get("friction_model")
    if fm is not None:
        out["friction_model"] = _friction_model(fm, where)
    if doc.get("reading") is not None:
        out["reading"] = _reading(doc["reading"], where)
    classical = doc.get("classical")
    if classical is not None:
        if not isinstance(classical, dict) or not classical:
            raise DataError(
                f"{where}: 'classical' is {_kind(classical)}; expected a map of classical "
                "parameter names to numbers"
            )
        out["classical"] = {
            k: _number(v, f"{where}: 'classical' {k!r}") for k, v in classical.items()
        }
    return out


def check_identified_robot(
    doc: dict, robot: Robot, where: str, *, error: type[Exception] = DataError
) -> None:
    """Refuses (``error``, naming ``where``) an identification JSON ``doc`` made for another
    robot than ``robot``: another ``robot`` name, or other ``joints`` (their count, or the
    joints whose names differ); a warning when the ``description`` file name it records is not
    the one ``robot`` was loaded from. A field the document does not record is not checked
    (JSON of earlier versions has no ``joints`` and ``description``)."""
    name = doc.get("robot")
    if name is not None and name != robot.name:
        raise error(f"{where}: identified for robot '{name}', not '{robot.name}'")
    tip = doc.get("tip")
    hint = (
        f" (identified on the chain ending at tip='{tip}': load the robot with that tip)"
        if isinstance(tip, str)
        else " (identified with another tip=?)"
    )
    check_joint_names(doc.get("joints"), robot, where, error=error, hint=hint)
    _sidecar.warn_other_description(doc.get("description"), robot, where)


#: The states of :func:`model_record`: how many, and the tolerance of its comparison: relative
#: to each number, plus a floor relative to the largest of its list (a number that round-off
#: leaves near zero: a gear ratio's 1e4 beside a length's 0.1 in one list). Far above the
#: round-off of another machine's arithmetic and the record's 12 digits, far below what a
#: length changed by a tenth of a millimetre does to a regrouping or a regressor column.
MODEL_STATES = 2
MODEL_TOLERANCE = 1e-7
MODEL_FLOOR = 1e-11


def model_record(base: BaseParameters) -> dict:
    """What identifies the model of an identification's base set ``base`` in its JSON
    (``model_check``), for :func:`check_identified_model`: ``regrouping``, the base values of
    a fixed classical vector (one number per base parameter: the numeric regrouping, which the
    lengths, axes and gear ratios set), and ``regressor``, per fixed state (positions,
    velocities and accelerations) the base regressor's rows summed with fixed weights (one
    number per base parameter: its torque column, which the geometry, gravity, transmissions
    and friction model set). Numbers at 12 significant digits."""
    regrouping, regressor = _model_numbers(base)
    return {
        "version": 1,
        "regrouping": [float(f"{x:.12g}") for x in regrouping],
        "regressor": [[float(f"{x:.12g}") for x in row] for row in regressor],
    }


def _model_numbers(base: BaseParameters) -> tuple[np.ndarray, np.ndarray]:
    """The numbers of :func:`model_record` at full precision."""
    from ..base import BaseParameters

    robot = base.robot
    P = len(base.classical_names)
    regrouping = base.values(1.0 + 0.17 * np.sin(1.1 * np.arange(1, P + 1)))
    rows = []
    for s in range(MODEL_STATES):
        q = 0.4 + 0.9 * np.sin(1.7 * np.arange(1, robot.nq + 1) + 2.3 * s)
        for start, size, _ in robot._unit_blocks():
            q[start : start + size] /= np.linalg.norm(q[start : start + size])
        v = np.arange(1, robot.nv + 1)
        dq = 0.6 + 0.8 * np.cos(1.3 * v + 0.9 * s)
        ddq = -0.5 + 1.1 * np.sin(0.7 * v + 1.9 * s)
        # the set's own columns: a Dahl set's Coulomb column is a state along a path
        W = BaseParameters.regressor(base, q, dq, ddq)
        rows.append((1.0 + 0.31 * np.arange(W.shape[0])) @ W)
    return regrouping, np.array(rows)


def check_identified_model(
    doc: dict, base: BaseParameters, where: str, *, error: type[Exception] = DataError
) -> None:
    """Refuses (``error``, one line naming ``where`` and the base parameters concerned) an
    identification JSON ``doc`` whose ``model_check`` (:func:`model_record`) is not that of
    ``base``, the base set formed for the robot given with the document's settings: another
    geometry, gravity, transmission or friction model under the same robot and joint names. A
    document without the record (written by earlier versions) is not checked."""
    record = doc.get("model_check")
    if record is None:
        return
    n = base.n
    try:
        regrouping = np.asarray(record["regrouping"], dtype=float)
        regressor = np.asarray(record["regressor"], dtype=float)
        ok = regrouping.shape == (n,) and regressor.shape == (MODEL_STATES, n)
    except (KeyError, TypeError, ValueError):
        ok = False
    if not ok or record.get("version") != 1:
        raise DataError(
            f"{where}: 'model_check' is not a record of {n} base parameters at "
            f"{MODEL_STATES} states (the JSON of mindyn identify writes it)"
        )
    own_regrouping, own_regressor = _model_numbers(base)
    names = list(base.names)
    regrouped = [names[i] for i in np.flatnonzero(_differ(regrouping, own_regrouping))]
    columns = sorted(
        set().union(*(np.flatnonzero(_differ(a, b)) for a, b in zip(regressor, own_regressor)))
    )
    if not regrouped and not columns:
        return
    parts = []
    if regrouped:
        parts.append(f"the regrouping of {_some(regrouped)}")
    if columns:
        parts.append(f"the torque columns of {_some([names[i] for i in columns])}")
    source = base.robot.source
    raise error(
        f"{where}: identified on another model than robot '{base.robot.name}'"
        + (f" loaded from '{source}'" if Path(source).is_file() else "")
        + f": {' and '.join(parts)} differ (its lengths, axes, gravity, gear ratios or friction "
        "model are not those identified)"
    )


def check_identified_geometry(
    doc: dict, robot: Robot, where: str, *, error: type[Exception] = DataError
) -> None:
    """:func:`check_identified_model` for a reader that forms no base set of its own: the base
    set of ``robot`` with the settings the document records (drive side, friction model,
    ``rotor``, ``friction``, ``offset``, snap), formed only when it has a ``model_check``."""
    if doc.get("model_check") is None:
        return
    check_identified_model(doc, identified_base(doc, robot, where), where, error=error)


def check_floating_identification(
    doc: dict, robot: Robot, where: str, *, error: type[Exception] = DataError
) -> None:
    """For the JSON of a floating-base identification (``floating_base``), what
    :func:`check_identified_robot` and :func:`check_identified_geometry` are for a fixed-base
    one: refuses (``error``, one line naming ``where``) a document made for another robot
    (name, joints) or another model (its ``model_check`` against the base set it was fitted
    with, the ``base_method``'s of ``robot``: another geometry or gravity under the same names).
    A document without ``model_check`` (earlier versions) has its robot checked only."""
    from ..base import base_parameters

    check_identified_robot(doc, robot, where, error=error)
    if doc.get("model_check") is None:
        return
    method = doc.get("base_method", "numerical")
    if method not in ("projection", "recursive", "numerical"):
        raise DataError(f"{where}: 'base_method' is {_kind(method)}; expected the method's name")
    check_identified_model(doc, base_parameters(robot, method=method), where, error=error)


def identified_base(doc: dict, robot: Robot, where: str) -> BaseParameters:
    """The base set an identification JSON ``doc`` was fitted with, formed for ``robot`` (checked
    against the document by :func:`check_identified_robot`): its drive side, friction model,
    ``rotor``, ``friction``, ``offset`` and snap (the Dahl set for the Dahl model)."""
    from ..base import base_parameters

    robot = with_identified_friction(robot_on_drive_side(robot, doc, where=where), doc, where=where)
    base = base_parameters(
        robot,
        rotor=bool(doc.get("rotor")),
        friction=bool(doc.get("friction")),
        offset=bool(doc.get("offset")),
        snap=identified_snap(doc, where=where),
    )
    return with_identified_state(base, doc, where)


def _differ(recorded: np.ndarray, own: np.ndarray) -> np.ndarray:
    """Where the numbers ``own`` differ from the ``recorded`` ones beyond
    :data:`MODEL_TOLERANCE` (and :data:`MODEL_FLOOR`)."""
    floor = MODEL_FLOOR * max(float(np.max(np.abs(own), initial=0.0)), 1e-300)
    return np.abs(recorded - own) > MODEL_TOLERANCE * np.abs(own) + floor


def _some(names: list[str]) -> str:
    """Up to five names, and how many more."""
    more = f" and {len(names) - 5} more" if len(names) > 5 else ""
    return ", ".join(names[:5]) + more


def identified_robot_record(robot: Robot) -> dict:
    """What the JSON of an identification records of its robot, for
    :func:`check_identified_robot`: ``robot`` (its name), ``joints`` (the joint names) and
    ``description`` (the file name it was loaded from; None for a generated robot)."""
    return {
        "robot": robot.name,
        "joints": list(robot.joint_names),
        "description": _sidecar.description_name(robot),
    }


def identified_snap(doc: dict, *, where: str = "identification JSON"):
    """The ``snap=`` of :func:`mindyn.base_parameters` that the identification ``doc`` had
    (``base_snap``: ``mode`` auto, off or given with its ``tolerance``): "auto", False or the
    tolerance; "auto" for a document that does not record it."""
    _args.mapping(doc, "doc")
    record = doc.get("base_snap")
    if record is None:
        return "auto"
    mode = record.get("mode") if isinstance(record, dict) else None
    if mode not in ("auto", "off", "given"):
        raise DataError(
            f"{where}: 'base_snap' is {_kind(record)}; expected {{mode: auto, off or given, ...}}"
        )
    if mode == "given":
        tol = record.get("tolerance")
        if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not 0 < tol < 1:
            raise DataError(f"{where}: 'base_snap' tolerance is {_kind(tol)}; expected (0, 1)")
        return float(tol)
    return "auto" if mode == "auto" else False


def robot_on_drive_side(robot: Robot, doc: dict, *, where: str = "identification JSON") -> Robot:
    """``robot`` with rotor inertia and friction where the identification ``doc`` had them
    (``drive_side``; a document without it was identified with them on the joints)."""
    from ..robot import Robot

    _args.instance(robot, "robot", Robot)
    _args.mapping(doc, "doc")
    _args.text(where, "where")
    side = doc.get("drive_side", "joint")
    if robot.drive_side == side:
        return robot
    if side == "motor" and robot.transmission is None:
        raise DataError(
            f"{where}: identified with rotor inertia and friction on the motors, but "
            f"'{robot.name}' declares no transmissions"
        )
    return robot.with_drive_side(side)


def _friction_model(fm, where: str) -> dict:
    """The checked ``friction_model`` field: ``{kind, velocity (per slot, or null), chosen_by}``."""
    from ..robot import FRICTION_KINDS

    kinds = (*FRICTION_KINDS, "dahl")
    if not isinstance(fm, dict) or fm.get("kind") not in kinds:
        kind = fm.get("kind") if isinstance(fm, dict) else fm
        raise DataError(
            f"{where}: 'friction_model' kind is {_kind(kind)}; expected one of " + ", ".join(kinds)
        )
    out = dict(fm)
    if fm["kind"] == "dahl":
        sigma = fm.get("sigma")
        if not isinstance(sigma, list):
            raise DataError(
                f"{where}: 'friction_model' dahl: 'sigma' is {_kind(sigma)}; expected a list"
            )
        out["sigma"] = [
            _number(x, f"{where}: 'friction_model' sigma item {i + 1}") for i, x in enumerate(sigma)
        ]
        if not all(x > 0 for x in out["sigma"]):
            raise DataError(f"{where}: 'friction_model' sigma: every value must be positive")
    v = fm.get("velocity")
    if v is not None:
        if not isinstance(v, list):
            raise DataError(f"{where}: 'friction_model' velocity is {_kind(v)}; expected a list")
        out["velocity"] = [
            _number(x, f"{where}: 'friction_model' velocity item {i + 1}") for i, x in enumerate(v)
        ]
    return out


def _reading(rec, where: str) -> dict:
    """The checked ``reading`` field, how identify read its logs: ``filter`` one of the filters,
    ``cutoff_Hz`` and ``edge_s`` numbers, ``torque_unit`` and ``topic`` text, ``drive_gain`` a
    list of numbers, ``columns`` a column map, ``torque`` sampled or held; each may be null or
    absent."""
    from .options import FILTERS, TORQUE_READINGS

    if not isinstance(rec, dict):
        raise DataError(
            f"{where}: 'reading' is {_kind(rec)}; expected an object (how identify read its logs)"
        )
    out = dict(rec)
    filt = rec.get("filter")
    if filt is not None and filt not in FILTERS:
        raise DataError(
            f"{where}: 'reading' filter is {_kind(filt)}; expected one of {', '.join(FILTERS)}"
        )
    for key in ("cutoff_Hz", "edge_s"):
        if rec.get(key) is not None:
            out[key] = _number(rec[key], f"{where}: 'reading' {key}")
    for key in ("torque_unit", "topic"):
        if rec.get(key) is not None and not isinstance(rec[key], str):
            raise DataError(f"{where}: 'reading' {key} is {_kind(rec[key])}; expected text")
    if rec.get("torque") is not None and rec["torque"] not in TORQUE_READINGS:
        raise DataError(
            f"{where}: 'reading' torque is {_kind(rec['torque'])}; expected one of "
            f"{', '.join(TORQUE_READINGS)}"
        )
    if rec.get("columns") is not None:
        from .._core import ArgumentError
        from .columns import column_map

        try:
            column_map(rec["columns"])
        except ArgumentError as e:
            raise DataError(f"{where}: 'reading' {e}") from None
    gain = rec.get("drive_gain")
    if gain is not None:
        if not isinstance(gain, list):
            raise DataError(
                f"{where}: 'reading' drive_gain is {_kind(gain)}; expected a list of numbers"
            )
        out["drive_gain"] = [
            _number(g, f"{where}: 'reading' drive_gain item {i + 1}") for i, g in enumerate(gain)
        ]
    return out


def with_identified_friction(
    robot: Robot, doc: dict, *, where: str = "identification JSON"
) -> Robot:
    """``robot`` with the friction model an identification JSON records (``friction_model``;
    unchanged without one: viscous and Coulomb friction). DataError when the record does not fit
    the robot."""
    from ..robot import Robot

    _args.instance(robot, "robot", Robot)
    _args.mapping(doc, "doc")
    _args.text(where, "where")
    fm = doc.get("friction_model")
    if fm is None:
        return robot
    fm = _friction_model(fm, where)
    if fm["kind"] == "dahl":  # the core's coulomb model; its Coulomb column is the Dahl state
        fm = {"kind": "coulomb"}
    try:
        return robot.with_friction_model(fm["kind"], velocity=fm.get("velocity"))
    except Exception as e:  # a ModelError of the core, in the terms of this file
        raise DataError(f"{where}: 'friction_model' does not fit '{robot.name}': {e}") from None


def with_identified_state(base, doc: dict, where: str = "identification JSON"):
    """``base`` (formed for the robot of :func:`with_identified_friction`) as the Dahl base set
    when the identification JSON records the Dahl friction model, else ``base``."""
    fm = doc.get("friction_model")
    if fm is None or fm.get("kind") != "dahl":
        return base
    from .friction import dahl_base

    sigma = _friction_model(fm, where)["sigma"]
    if len(sigma) != base.robot.n:
        raise DataError(
            f"{where}: 'friction_model' sigma has {len(sigma)} values; expected {base.robot.n}"
        )
    return dahl_base(base, sigma)


def names_difference(
    given, expected, *, given_as: str = "the file", expected_as: str = "here"
) -> str:
    """Which names of the list ``given`` differ from ``expected``, in words: those only in one
    of them (up to 6 each, with the count), or, for the same names in another order, the first
    position where they differ; empty when the lists are equal."""
    given, expected = [str(k) for k in given], [str(k) for k in expected]
    if given == expected:
        return ""

    def listed(names: list[str]) -> str:
        more = f" and {len(names) - 6} more" if len(names) > 6 else ""
        return ", ".join(names[:6]) + more

    only_given = [k for k in given if k not in set(expected)]
    only_expected = [k for k in expected if k not in set(given)]
    parts = []
    if only_given:
        parts.append(f"only in {given_as}: {listed(only_given)}")
    if only_expected:
        parts.append(f"only {expected_as}: {listed(only_expected)}")
    if not parts:
        i = next(i for i, (a, b) in enumerate(zip(given, expected)) if a != b)
        parts.append(
            f"the same names in another order, first at position {i + 1}: {given[i]} in "
            f"{given_as}, {expected[i]} {expected_as}"
        )
    return "; ".join(parts)


def refuse_state(doc, what: str, where: str = "identification JSON") -> None:
    """DataError when the identification JSON ``doc`` records the Dahl friction model: ``what``
    (generated code, a description, ...) has no friction state per joint."""
    fm = doc.get("friction_model") if isinstance(doc, dict) else None
    if isinstance(fm, dict) and fm.get("kind") == "dahl":
        raise DataError(
            f"{where}: identified with the Dahl friction model, whose torque depends on a "
            f"presliding state integrated along the positions; {what} has no such state (identify "
            "with friction_model='coulomb', 'smooth', 'asymmetric' or 'stribeck')"
        )


def _number(v, where: str) -> float:
    """A JSON number as a finite double, or DataError."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise DataError(f"{where} is {_kind(v)}; expected a number")
    try:
        x = float(v)
    except OverflowError:
        raise DataError(
            f"{where}: an integer of {len(str(abs(v)))} digits is too large for a double"
        ) from None
    if not math.isfinite(x):
        raise DataError(f"{where} is not a finite number")
    return x


def _kind(v) -> str:
    """What a JSON value is, for a message (its text when short)."""
    if v is None:
        return "null"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return repr(v) if len(v) <= 40 else "a text"
    if isinstance(v, (int, float)):
        text = repr(v)
        return text if len(text) <= 24 else f"a number of {len(text)} digits"
    return "a list" if isinstance(v, list) else "an object"
