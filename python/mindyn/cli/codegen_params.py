"""The parameter values ``mindyn codegen --params`` takes: the JSON of ``mindyn identify
--json`` (pruned parameters as zero, its friction model and drive side) or any file that
:func:`mindyn.codegen.read_parameter_file` reads."""

from __future__ import annotations

import numpy as np

from .._core import ArgumentError, ModelError
from .args import UsageError


def _params_note(n: int, path: str, pruned: list[str], threshold: str | None) -> str:
    """The line saying which identified values the generated code takes (``threshold`` None:
    the consistent estimate, which prunes nothing)."""
    if threshold is None:
        return f"parameters: the consistent estimate of {path}, all {n} base values"
    return (
        f"parameters: {n - len(pruned)} identified values from {path}; "
        f"{len(pruned)} pruned in identification (relative standard deviation above "
        f"{threshold}) taken as zero" + (f": {', '.join(pruned)}" if pruned else "")
    ) + (
        " (the unconstrained estimate; the file's consistent estimate: --consistent)"
        if _has_consistent(path)
        else ""
    )


def _has_consistent(path: str) -> bool:
    """Whether the identification JSON ``path`` holds a consistent estimate."""
    from ..identification.data import read_json

    doc = read_json(path)
    return isinstance(doc, dict) and isinstance(doc.get("consistent_estimate"), dict)


def _identified_layout(args) -> str:
    """Sets ``--rotor``, ``--friction`` and ``--offset`` from the ``--params`` JSON of ``mindyn
    identify`` (its ``rotor``, ``friction`` and ``offset``) when none of the three is given, as
    ``predict`` and ``detect`` take them from it; the line saying so, or "" (no such JSON, a flag
    given: a layout other than the JSON's is then refused, naming it)."""
    from ..identification.data import DataError, read_json

    if not args.params or args.rotor or args.friction or args.offset:
        return ""
    try:
        doc = read_json(args.params)
    except (DataError, FileNotFoundError):
        return ""  # not an identification JSON: read_parameter_file reads it, or says why
    if not (isinstance(doc, dict) and {"names", "values", "removed"} <= doc.keys()):
        return ""
    taken = [k for k in ("rotor", "friction", "offset") if doc.get(k) is True]
    for k in taken:
        setattr(args, k, True)
    if not taken:
        return ""
    return f"{', '.join('--' + k for k in taken)}: as identified in {args.params}"


def _with_friction_model(robot, args):
    """``robot`` with the friction model a ``--params`` JSON records (``friction_model: {kind,
    velocity}``), else as it is (Coulomb); and the line saying which, when ``--friction``."""
    from ..identification.data import DataError, read_json

    recorded = None
    if args.params:
        try:
            doc = read_json(args.params)
        except (DataError, FileNotFoundError):
            doc = None
        if isinstance(doc, dict) and doc.get("friction_model") is not None:
            from ..identification.document import refuse_state

            refuse_state(doc, "generated code", str(args.params))
            recorded = doc["friction_model"]
            if not (isinstance(recorded, dict) and isinstance(recorded.get("kind"), str)):
                raise DataError(
                    f"{args.params}: 'friction_model' must be {{kind, velocity}}, got {recorded!r}"
                )
            velocity = recorded.get("velocity")
            if velocity is not None and not (
                isinstance(velocity, list)
                and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in velocity)
            ):
                raise DataError(f"{args.params}: friction_model velocity must be a list of numbers")
            try:
                robot = robot.with_friction_model(recorded["kind"], velocity=velocity or None)
            except ArgumentError as e:  # the JSON's values, not the command's arguments
                raise ModelError(f"{args.params}: friction_model: {e}") from None
    if not args.friction:
        return robot, ""
    model = robot.friction_model
    scale = {"smooth": "tanh widths", "stribeck": "Stribeck velocities"}.get(model["kind"])
    words = f"friction model: {model['kind']}"
    if scale:
        words += f" ({scale} " + ", ".join(f"{v:g}" for v in model["velocity"]) + ")"
    return robot, words + (f", from {args.params}" if recorded else " (the default)")


def _on_identified_drive_side(robot, args):
    """``robot`` with the rotor inertia and friction on the side (``drive_side``) where the
    ``--params`` JSON of ``mindyn identify`` has them, when ``--rotor`` or ``--friction`` asks
    for them and ``--drive-side`` is not given (a ``--drive-side`` that differs is refused);
    and that JSON's path when it decided, else None."""
    from ..identification.data import DataError, read_json
    from ..identification.document import robot_on_drive_side

    if not args.params or not (args.rotor or args.friction):
        return robot, None
    try:
        doc = read_json(args.params)
    except (DataError, FileNotFoundError):
        return robot, None  # not an identification JSON: read_parameter_file reads it
    if not (isinstance(doc, dict) and {"names", "values", "removed"} <= doc.keys()):
        return robot, None
    side = doc.get("drive_side", "joint")
    given = getattr(args, "drive_side", None)
    if given is not None and side in ("motor", "joint") and given != side:
        raise UsageError(
            f"--drive-side {given}: {args.params} was identified with the rotor inertia and "
            f"friction on the {side}s; give --drive-side {side} or leave it out"
        )
    if given is not None or side == robot.drive_side:
        return robot, None
    return robot_on_drive_side(robot, doc, where=str(args.params)), str(args.params)


def _identified_snap(args):
    """The ``snap=`` the ``--params`` JSON of ``mindyn identify`` was identified with (its base
    set's names follow it), "auto" without such a JSON."""
    from ..identification.data import DataError, read_json
    from ..identification.document import identified_snap

    if not args.params:
        return "auto"
    try:
        doc = read_json(args.params)
    except (DataError, FileNotFoundError):
        return "auto"
    if not (isinstance(doc, dict) and {"names", "values", "removed"} <= doc.keys()):
        return "auto"
    return identified_snap(doc, where=str(args.params))


def _identified_params(path: str, robot, base, args):
    """The values of a ``mindyn identify --json`` file in the order of ``base.names``, with the
    parameters it pruned (``removed``) as zero, and the pruned names; ``(None, [], "")`` for any
    other parameter file (read by :func:`mindyn.codegen.read_parameter_file`); and the pruning
    threshold as text (:func:`mindyn.codegen.read_identified_parameters`)."""
    from ..codegen import read_identified_parameters

    identified = read_identified_parameters(
        path, base.names, robot=robot, rotor=args.rotor, friction=args.friction, offset=args.offset
    )
    if not args.consistent:
        return identified if identified is not None else (None, [], "")
    if identified is None:
        raise ArgumentError(f"--consistent: {path} is not the JSON of 'mindyn identify --json'")
    from ..identification.prediction import identified_model

    own, values, _ = identified_model(path, robot, estimate="consistent")
    by_name = dict(zip(own.names, values))
    missing = [k for k in base.names if k not in by_name]
    if missing:
        raise ModelError(
            f"--consistent: the base set of this command ({', '.join(missing[:5])}) is not the "
            f"one {path} was identified in; generate with the identification's --method"
        )
    return np.array([by_name[k] for k in base.names]), [], None
