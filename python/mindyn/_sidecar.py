"""The joint-terms file (``OUT.joints.yaml``) that :mod:`mindyn.export` writes beside a
description for what it has no place for (rotor inertia, friction, torque offsets): what each
term is, reading the file (:func:`read`) and mapping its rows onto a robot's joints and motors
(:func:`slots`), which :func:`mindyn.load` (``joint_terms=``) uses."""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import _args, _yaml
from ._core import OFFSET_PREFIX as OFF
from ._core import ModelError, RobotFileNotFoundError

#: What each joint term of a sidecar file is, and its unit for a revolute / prismatic joint.
TERMS = {
    "Ia": (
        "rotor (armature) inertia reflected to the joint side: tau += Ia * ddq",
        "kg m^2",
        "kg",
    ),
    "Fv": ("viscous friction: tau += Fv * dq", "N m s/rad", "N s/m"),
    "Fc": ("Coulomb friction: tau += Fc * sign(dq)", "N m", "N"),
    "Fa": (
        "direction-dependent Coulomb friction (friction_model asymmetric): tau += Fa * "
        "|sign(dq)|, the Coulomb torque Fc + Fa moving forward and Fc - Fa backward",
        "N m",
        "N",
    ),
    "Fs": (
        "Stribeck friction (friction_model stribeck): tau += Fs * sign(dq) * exp(-(dq / "
        "velocity)^2), velocity the row's Stribeck velocity",
        "N m",
        "N",
    ),
    OFF: (f"constant torque offset: tau += {OFF}", "N m", "N"),
}
#: What a term of a row is on the motor side (``drive_side: motor``): the motor's it names, in
#: the motor's velocity ``dq_m`` (row k of ``T dq``) and torque ``tau_m`` (``tau += T^T tau_m``).
MOTOR_TERMS = {
    "Ia": "rotor inertia of the row's motor: tau_m += Ia * ddq_m",
    "Fv": "viscous friction of the row's motor: tau_m += Fv * dq_m",
    "Fc": "Coulomb friction of the row's motor: tau_m += Fc * sign(dq_m)",
    "Fa": (
        "direction-dependent Coulomb friction of the row's motor (friction_model asymmetric): "
        "tau_m += Fa * |sign(dq_m)|"
    ),
    "Fs": (
        "Stribeck friction of the row's motor (friction_model stribeck): tau_m += Fs * "
        "sign(dq_m) * exp(-(dq_m / velocity)^2)"
    ),
}
#: The entries of a row besides the terms.
_ROW_KEYS = ("name", "index", "type", "motor", "units", "velocity")
#: The terms that are never negative, in words.
_NONNEGATIVE = {"Ia": "rotor inertia", "Fv": "viscous friction", "Fc": "Coulomb friction"}
#: The friction models a file may name (``friction_model``), with the third term each has and
#: whether its rows give a ``velocity`` (the tanh width of ``smooth``: ``tau += Fc *
#: tanh(dq / velocity)`` in place of ``Fc * sign(dq)``; the Stribeck velocity).
FRICTION_MODELS = {
    "coulomb": (None, False),
    "asymmetric": ("Fa", False),
    "smooth": (None, True),
    "stribeck": ("Fs", True),
}


@dataclass(frozen=True)
class Sidecar:
    """A joint-terms file as read: its rows (mappings, the terms checked as numbers),
    ``drive_side`` (``"motor"``: each row's Ia, Fv, Fc are the motor's it names; else
    ``"joint"``), ``friction_model`` (a key of :data:`FRICTION_MODELS`) and the file name of
    the ``description`` it was written beside (None if not recorded)."""

    path: Path
    rows: list
    drive_side: str
    friction_model: str = "coulomb"
    description: str | None = None


def read_yaml(path: Path, what: str):
    """The document of the YAML file ``path`` (a joint-terms file, a description to rewrite),
    or an error naming it as ``what``."""
    if not path.is_file():
        raise RobotFileNotFoundError(f"{what} '{path}' does not exist")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as e:
        raise ModelError(f"{path}: not a YAML file: {' '.join(str(e).split())}") from None
    return _yaml.load(text, path, ModelError)


def description_name(robot) -> str | None:
    """The file name of the description ``robot`` was loaded from (what a joint-terms file and
    the JSON of ``mindyn identify`` record as ``description``), None for a generated robot."""
    source = Path(robot.source)
    return source.name if source.is_file() else None


def warn_other_description(recorded, robot, where: str) -> None:
    """A warning when the ``description`` file name a document records (for ``robot``, whose
    joints it matches) is not the one ``robot`` was loaded from: files get renamed and moved,
    so it is not refused."""
    own = description_name(robot)
    if isinstance(recorded, str) and own is not None and recorded != own:
        warnings.warn(
            f"{where}: made for the description '{recorded}'; robot '{robot.name}' was loaded "
            f"from '{own}' (same joint names: taken as the same robot)",
            stacklevel=3,
        )


def terms_of(sidecar: Sidecar) -> list[str]:
    """The terms the file's rows have (those of its first row), in the order of :data:`TERMS`."""
    return [k for k in TERMS if sidecar.rows and k in sidecar.rows[0]]


def read(path) -> Sidecar:
    """The joint-terms file ``path``: a YAML mapping with a ``joints`` list of mappings whose
    terms (``Ia``, ``Fv``, ``Fc``, ``Off``) are finite numbers within 1e16; ModelError (one line
    naming the file) otherwise, RobotFileNotFoundError when it does not exist."""
    _args.path(path, "path")
    p = Path(path)
    doc = read_yaml(p, "joint-terms file")
    rows = doc.get("joints") if isinstance(doc, dict) else None
    if not isinstance(rows, list) or not all(isinstance(r, dict) for r in rows):
        raise ModelError(f"{p}: expected a 'joints' list of mappings (a mindyn joint-terms file)")
    for i, row in enumerate(rows, 1):
        for key in TERMS:
            if key in row:
                v = row[key]
                if isinstance(v, bool) or not isinstance(v, (int, float)):
                    raise ModelError(f"{p}: joint {i}: '{key}' is {v!r}; expected a number")
                if not abs(v) <= 1e16:  # as a description's numbers; not inf, nan or 400 digits
                    said = "an integer beyond 1e16" if isinstance(v, int) else repr(v)
                    raise ModelError(
                        f"{p}: joint {i}: '{key}' is {said}; expected a finite number within 1e16"
                    )
        if "velocity" in row:
            v = row["velocity"]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 < v <= 1e16:
                raise ModelError(
                    f"{p}: joint {i}: 'velocity' is {v!r}; expected a positive number [rad/s | m/s]"
                )
    side = doc.get("drive_side", "joint")
    if side not in ("motor", "joint"):
        raise ModelError(f"{p}: 'drive_side' is {side!r}; expected 'motor' or 'joint'")
    model = doc.get("friction_model", "coulomb")
    if model not in FRICTION_MODELS:
        hint = (
            " (the Dahl model's state follows the motion: no joint term holds it)"
            if model == "dahl"
            else ""
        )
        raise ModelError(
            f"{p}: 'friction_model' is {model!r}; expected one of "
            f"{', '.join(FRICTION_MODELS)}{hint}"
        )
    description = doc.get("description")
    return Sidecar(p, rows, side, model, description if isinstance(description, str) else None)


def slots(sidecar: Sidecar, robot) -> dict:
    """The terms of ``sidecar`` as the keywords of :meth:`mindyn.Robot.with_joint_terms` for
    ``robot``: ``rotor``, ``viscous``, ``coulomb`` and ``third`` (the friction model's ``Fa``
    or ``Fs``) by slot (motor k's on the motor side, the motor named in the row), ``offset``
    by joint (``None`` for a term the file does not have), ``drive_side`` and
    ``friction_model`` (``{"kind", "velocity"}``, velocity by slot or None; None without
    friction). Every row names a joint of the robot (``name``; ``index`` and
    ``type``, when given, as the robot has them), each joint once; every row has the same
    terms, ``Fv`` with ``Fc``, none of ``Ia``, ``Fv``, ``Fc`` negative. ModelError (one line
    naming the file and the entry) otherwise."""
    p, rows = sidecar.path, sidecar.rows
    if not robot.single_dof:
        raise ModelError(
            f"{p}: joint terms apply to revolute and prismatic joints; robot '{robot.name}' has "
            "joints of several degrees of freedom"
        )
    n, names = robot.n, list(robot.joint_names)
    joint_of: list[int] = []
    for i, row in enumerate(rows, 1):
        unknown = [k for k in row if k not in TERMS and k not in _ROW_KEYS]
        if unknown and isinstance(unknown[0], bool):  # YAML 1.1: a bare Off (On, No, ...)
            raise ModelError(
                f"{p}: joint {i}: a key YAML reads as {str(unknown[0]).lower()}: a bare Off, On, "
                f"No or Yes is a boolean in YAML; write the torque offset's key quoted, '{OFF}':"
            )
        if unknown:
            raise ModelError(
                f"{p}: joint {i}: unknown entry {str(unknown[0])!r} (a row has "
                f"{', '.join(_ROW_KEYS)} and the terms {', '.join(TERMS)})"
            )
        name = row.get("name")
        if not isinstance(name, str) or name not in names:
            raise ModelError(
                f"{p}: joint {i}: 'name' is {name!r}, not a joint of robot '{robot.name}' "
                f"({', '.join(names[:8])}{', ...' if n > 8 else ''})"
            )
        j = names.index(name)
        if j in joint_of:
            raise ModelError(f"{p}: joint {i}: '{name}' is also joint {joint_of.index(j) + 1}")
        joint_of.append(j)
        if "index" in row and (isinstance(row["index"], bool) or row["index"] != j + 1):
            raise ModelError(
                f"{p}: joint {i} ('{name}'): 'index' is {row['index']!r}; robot "
                f"'{robot.name}' numbers it {j + 1}"
            )
        if "type" in row and row["type"] != robot.joint_types[j]:
            raise ModelError(
                f"{p}: joint {i} ('{name}'): 'type' is {row['type']!r}; robot "
                f"'{robot.name}' has it {robot.joint_types[j]}"
            )
    if len(rows) != n:
        missing = [k for k in names if names.index(k) not in joint_of]
        raise ModelError(
            f"{p}: {len(rows)} joints; robot '{robot.name}' has {n} (missing: "
            f"{', '.join(repr(k) for k in missing[:6])})"
        )
    present = terms_of(sidecar)
    for i, row in enumerate(rows, 1):
        for key in TERMS:
            if (key in row) != (key in present):
                which = "has" if key in row else "has no"
                raise ModelError(
                    f"{p}: joint {i} ('{row['name']}') {which} '{key}', unlike joint 1: every "
                    "joint has the same terms"
                )
        for key, words in _NONNEGATIVE.items():
            if key in row and row[key] < 0:
                raise ModelError(
                    f"{p}: joint {i} ('{row['name']}'): '{key}' is {row[key]!r}; {words} is >= 0"
                )
    if ("Fv" in present) != ("Fc" in present):
        have = "Fv" if "Fv" in present else "Fc"
        raise ModelError(f"{p}: the joints have '{have}' alone; friction is Fv with Fc")
    third, velocity = FRICTION_MODELS[sidecar.friction_model]
    for key in ("Fa", "Fs"):
        if key in present and key != third:
            raise ModelError(
                f"{p}: the joints have '{key}', which the friction model "
                f"'{sidecar.friction_model}' has not (Fa: asymmetric, Fs: stribeck)"
            )
    if sidecar.friction_model != "coulomb" and "Fc" not in present:
        raise ModelError(
            f"{p}: 'friction_model' is '{sidecar.friction_model}' but the joints have no "
            "friction (Fv, Fc)"
        )
    if third is not None and third not in present:
        raise ModelError(
            f"{p}: the friction model '{sidecar.friction_model}' has a third term, '{third}', "
            "which the joints lack"
        )
    for i, row in enumerate(rows, 1):
        if ("velocity" in row) != (velocity and "Fc" in present):
            raise ModelError(
                f"{p}: joint {i} ('{row['name']}') "
                + (
                    f"has no 'velocity', which the friction model '{sidecar.friction_model}' needs"
                    if velocity
                    else f"has a 'velocity', which the friction model "
                    f"'{sidecar.friction_model}' has not (smooth and stribeck have one)"
                )
            )
    drives = any(k in present for k in _NONNEGATIVE)
    slot_of = _motor_slots(sidecar, robot) if drives and sidecar.drive_side == "motor" else joint_of
    # offsets alone: the robot's drive side stays (a file records where Ia, Fv, Fc act)
    out: dict = {"drive_side": sidecar.drive_side if drives else None}
    words = (("Ia", "rotor"), ("Fv", "viscous"), ("Fc", "coulomb"), (OFF, "offset"))
    for key, word in (*words, (third or "", "third"), ("velocity", "velocity")):
        if not (key in present or (key == "velocity" and velocity and "Fc" in present)):
            out[word] = None
            continue
        v = np.zeros(n)
        where = joint_of if key == OFF else slot_of
        for row, k in zip(rows, where):
            v[k] = float(row[key])
        assert all(math.isfinite(x) for x in v)  # read() checked them
        out[word] = v
    # the friction model's shape, by slot: with friction only (a file of offsets keeps the
    # robot's)
    by_slot = out.pop("velocity")
    out["friction_model"] = (
        {"kind": sidecar.friction_model, "velocity": by_slot} if "Fc" in present else None
    )
    warn_other_description(sidecar.description, robot, str(p))  # the file fits the robot
    return out


def _motor_slots(sidecar: Sidecar, robot) -> list[int]:
    """The slot (motor index) of each row of a motor-side file: the motor its ``motor`` entry
    names, each once."""
    p = sidecar.path
    tr = robot.transmission
    if tr is None or tr.n_motors != robot.n:
        has = "declares no transmissions" if tr is None else f"has {tr.n_motors} motors"
        raise ModelError(
            f"{p}: 'drive_side' is 'motor' (the rows' Ia, Fv, Fc are their motors'), but robot "
            f"'{robot.name}' {has} for its {robot.n} joints"
        )
    motors = list(tr.motors)
    out: list[int] = []
    for i, row in enumerate(sidecar.rows, 1):
        m = row.get("motor")
        if not isinstance(m, str) or m not in motors:
            raise ModelError(
                f"{p}: joint {i} ('{row['name']}'): 'motor' is {m!r}, not a motor of robot "
                f"'{robot.name}' ({', '.join(motors[:8])}{', ...' if len(motors) > 8 else ''})"
            )
        if motors.index(m) in out:
            raise ModelError(f"{p}: joint {i} ('{row['name']}'): motor '{m}' is named twice")
        out.append(motors.index(m))
    return out
