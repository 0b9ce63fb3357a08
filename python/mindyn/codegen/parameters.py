"""Parameter values for generated code from a file (:func:`read_parameter_file`)."""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .. import _args, _core

__all__ = ["read_identified_parameters", "read_parameter_file"]

_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


def _names(names) -> list[str]:
    """``names`` checked: a list of distinct non-empty parameter names."""
    if isinstance(names, (str, bytes)) or not isinstance(names, Sequence):
        raise _args.fail("names", "must be a list of parameter names")
    names = list(names)
    if not names or not all(isinstance(k, str) and k for k in names):
        raise _args.fail("names", "must be a non-empty list of non-empty strings")
    twice = sorted({k for k in names if names.count(k) > 1})
    if twice:
        raise _args.fail("names", f"gives {', '.join(twice[:5])} more than once")
    return names


def _is_json(path: Path, text: str) -> bool:
    """Whether a parameter file is meant as JSON (its suffix, or its first character), not as
    ``NAME value`` lines."""
    return path.suffix.lower() == ".json" or text.lstrip().startswith(("{", "["))


def read_parameter_file(path: str | Path, names: Sequence[str]) -> np.ndarray:
    """Parameter values from a file, in the order of ``names``.

    Accepted: JSON, either a mapping ``{"NAME": value}`` or ``{"names": [...], "values": [...]}``
    or a plain list in order; or text with one ``NAME value`` (or ``NAME = value``) per line,
    ``#`` comments allowed. Every name must be given exactly once; unknown names are an error.
    """
    from ..identification.data import DataError, decode_text, read_json

    path = Path(_args.path(path, "path"))
    names = _names(names)
    if not path.is_file():
        raise _core.RobotFileNotFoundError(f"parameter file '{path}' does not exist")
    text = decode_text(path)
    mapping: dict[str, float] = {}
    if _is_json(path, text):
        data = read_json(path, what="parameter file")
        if isinstance(data, list):
            if len(data) != len(names):
                raise DataError(f"{path}: {len(data)} values; expected {len(names)}")
            mapping = dict(zip(names, data))
        elif isinstance(data, dict) and "names" in data and "values" in data:
            idents, values = data["names"], data["values"]
            if not (isinstance(idents, list) and isinstance(values, list)):
                raise DataError(f"{path}: 'names' and 'values' must be lists")
            if not all(isinstance(k, str) for k in idents):
                raise DataError(f"{path}: 'names' must list parameter names (strings)")
            if len(idents) != len(values):
                raise DataError(f"{path}: 'names' and 'values' differ in length")
            mapping = dict(zip(data["names"], data["values"]))
        elif isinstance(data, dict):
            mapping = data
        else:
            raise DataError(f"{path}: expected a JSON mapping or list")
    else:
        for lineno, line in enumerate(text.splitlines(), 1):
            line = line.split("#", 1)[0].strip()
            if not line:
                continue
            m = re.fullmatch(r"([A-Za-z_][A-Za-z0-9_]*)\s*(?:=|:|\s)\s*(" + _NUMBER + r")", line)
            if not m:
                raise DataError(f"{path}:{lineno}: expected 'NAME value', got '{line}'")
            if m.group(1) in mapping:
                raise DataError(f"{path}:{lineno}: '{m.group(1)}' given twice")
            mapping[m.group(1)] = float(m.group(2))
    unknown = [k for k in mapping if k not in names]
    if unknown:
        raise DataError(
            f"{path}: unknown parameter(s) {', '.join(unknown[:5])}; expected {', '.join(names)}"
        )
    missing = [k for k in names if k not in mapping]
    if missing:
        raise DataError(f"{path}: missing parameter(s) {', '.join(missing[:8])}")
    values = np.empty(len(names))
    for i, k in enumerate(names):
        try:
            values[i] = float(mapping[k])
        except (TypeError, ValueError):
            raise DataError(f"{path}: value of '{k}' is not a number") from None
        if not math.isfinite(values[i]):
            raise DataError(f"{path}: value of '{k}' is not finite")
    return values


def read_identified_parameters(
    path: str | Path,
    names: Sequence[str],
    *,
    robot,
    rotor: bool = False,
    friction: bool = False,
    offset: bool = False,
) -> tuple[np.ndarray, list[str], str] | None:
    """The values of the JSON that ``mindyn identify --json`` writes
    (:func:`mindyn.identification.run`'s report) in the order of the base parameters ``names``, with
    the parameters the identification pruned (its ``removed``) as zero.

    Returns ``(values, pruned, threshold)``: the pruned names in the order of ``names`` and the
    pruning threshold as text; None when ``path`` is not such a JSON (it has no ``names``,
    ``values`` and ``removed``: :func:`read_parameter_file` reads it), and for the JSON of a
    floating-base identification (``floating_base``: its ``names`` and ``values``, nothing
    pruned, are read_parameter_file's), once its robot and model are checked
    (:func:`~mindyn.identification.document.check_floating_identification`). Refused with a
    :class:`mindyn.ModelError` naming the file: a JSON identified for another robot than ``robot``
    (its name, joints, or the model its ``model_check`` records), with other joint terms than
    ``rotor``, ``friction`` and ``offset``, or, with ``friction``, with another friction model than
    the robot's (then ``robot.with_friction_model(kind, velocity=...)`` with the JSON's
    ``friction_model`` is the robot it was identified for) or, with ``rotor`` or ``friction``, with
    them on the other side (``drive_side``) than the robot's (then ``robot.with_drive_side(side)``
    is the robot it was identified for). Refused with a
    :class:`~mindyn.identification.data.DataError` naming the file (and, for a syntax error, its
    line and column): a file meant as JSON (its suffix or first character) that is not JSON; fields
    of the wrong type; the Dahl model, which generated code has no state for; names unknown,
    missing, or both identified and pruned; values that are not finite numbers."""
    from ..identification.data import DataError, read_json
    from ..robot import Robot

    path = Path(_args.path(path, "path"))
    names = _names(names)
    _args.instance(robot, "robot", Robot)
    flags = {
        "rotor": _args.flag(rotor, "rotor"),
        "friction": _args.flag(friction, "friction"),
        "offset": _args.flag(offset, "offset"),
    }
    try:
        doc = read_json(path)
    except FileNotFoundError:
        return None  # read_parameter_file says so
    except DataError:
        from ..identification.data import decode_text

        if _is_json(path, decode_text(path)):
            raise  # where the JSON breaks, not "not the JSON of identify" further on
        return None  # NAME value lines
    if isinstance(doc, dict) and doc.get("floating_base") is True:
        from ..identification.document import check_floating_identification

        # its names and values (nothing pruned) are read_parameter_file's, once checked
        check_floating_identification(doc, robot, f"{path}: parameters", error=_core.ModelError)
        return None
    if not (isinstance(doc, dict) and {"names", "values", "removed"} <= doc.keys()):
        return None
    from ..identification.document import check_identified_geometry, check_identified_robot

    check_identified_robot(doc, robot, f"{path}: parameters", error=_core.ModelError)
    differ = [k for k, on in flags.items() if k in doc and bool(doc[k]) != on]
    if differ:
        said = " ".join(f"{k}=True" for k in flags if doc.get(k))
        raise _core.ModelError(
            f"{path}: identified "
            f"{'with ' + said if said else 'without rotor=True, friction=True and offset=True'}; "
            "generate with the same rotor=, friction= (and offset=) as the identification"
        )
    if flags["friction"]:
        _same_friction_model(doc, path, robot)
    if flags["rotor"] or flags["friction"]:
        _same_drive_side(doc, path, robot)
    check_identified_geometry(doc, robot, f"{path}: parameters", error=_core.ModelError)
    idents, values = doc["names"], doc["values"]
    try:
        pruned = [r["name"] if isinstance(r, dict) else str(r) for r in doc["removed"]]
        pruned = [k if isinstance(k, str) else str(k) for k in pruned]
    except (KeyError, TypeError):
        raise DataError(f"{path}: 'removed' must list the pruned parameters by name") from None
    if not (isinstance(idents, list) and isinstance(values, list) and len(idents) == len(values)):
        raise DataError(f"{path}: 'names' and 'values' must be lists of the same length")
    odd = next((k for k in idents if not isinstance(k, str)), None)
    if odd is not None:
        raise DataError(f"{path}: 'names' must list parameter names (strings), got {odd!r}")
    known = set(names)
    unknown = [k for k in idents + pruned if k not in known]
    if unknown:
        raise DataError(
            f"{path}: unknown parameter(s) {', '.join(unknown[:5])}; expected {', '.join(names)}"
        )
    given = dict(zip(idents, values))
    both = [k for k in pruned if k in given]
    if both:
        raise DataError(f"{path}: {', '.join(both[:5])} both identified and pruned")
    missing = [k for k in names if k not in given and k not in pruned]
    if missing:
        raise DataError(f"{path}: missing parameter(s) {', '.join(missing[:8])}")
    out = np.zeros(len(names))
    for i, k in enumerate(names):
        if k in given:
            v = given[k]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise DataError(f"{path}: value of '{k}' is not a finite number")
            out[i] = v
    threshold = doc.get("rsd_threshold")
    said = f"{threshold:g} %" if isinstance(threshold, (int, float)) else "the threshold"
    return out, [k for k in names if k in pruned], said


def _same_drive_side(doc: dict, path, robot) -> None:
    """Refuses an identification JSON whose rotor inertia and friction act on the other side
    (``drive_side``; absent: the joints) than ``robot``'s: a motor's values are in motor units,
    a joint's are those through the gear ratio squared (rotor inertia, viscous friction)."""
    side = doc.get("drive_side", "joint")
    if side not in ("motor", "joint"):
        raise _core.ModelError(f"{path}: 'drive_side' is {side!r}; expected 'motor' or 'joint'")
    if side != robot.drive_side:
        raise _core.ModelError(
            f"{path}: identified with the rotor inertia and friction on the {side}s; robot "
            f"'{robot.name}' has them on the {robot.drive_side}s: generate for "
            f"robot.with_drive_side('{side}')"
        )


def _same_friction_model(doc: dict, path, robot) -> None:
    """Refuses an identification JSON whose friction model (``friction_model: {kind,
    velocity}``) is not ``robot``'s: its friction parameters are another model's."""
    from ..identification.data import DataError
    from ..identification.document import refuse_state

    refuse_state(doc, "generated code", str(path))
    recorded = doc.get("friction_model")
    if recorded is None:
        return
    if not (isinstance(recorded, dict) and isinstance(recorded.get("kind"), str)):
        raise DataError(f"{path}: 'friction_model' must be {{kind, velocity}}, got {recorded!r}")
    kind, velocity = recorded["kind"], recorded.get("velocity") or []
    if not isinstance(velocity, list):
        raise DataError(
            f"{path}: friction_model velocity must be a list of numbers, got {velocity!r}"
        )
    own = robot.friction_model
    same = kind == own["kind"] and len(velocity) == len(own["velocity"])
    if same and velocity:
        try:
            same = bool(np.array_equal(np.asarray(velocity, dtype=float), own["velocity"]))
        except (TypeError, ValueError):
            raise DataError(f"{path}: friction_model velocity must be a list of numbers") from None
    if not same:
        scales = f", velocity={list(velocity)!r}" if velocity else ""
        raise _core.ModelError(
            f"{path}: identified with the {kind} friction model; robot '{robot.name}' has the "
            f"{own['kind']} one: generate for robot.with_friction_model('{kind}'{scales})"
        )
