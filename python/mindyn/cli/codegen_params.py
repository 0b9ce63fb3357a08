"""The parameter values ``mindyn codegen --params`` takes: the JSON of ``mindyn identify
--json`` (pruned parameters as zero, its friction model) or any file that
:func:`mindyn.codegen.read_parameter_file` reads."""

from __future__ import annotations

import math

import numpy as np

from .._core import ModelError


def _params_note(n: int, path: str, pruned: list[str], threshold: str) -> str:
    """The line saying which identified values the generated code takes."""
    return (
        f"parameters: {n - len(pruned)} identified values from {path}; "
        f"{len(pruned)} pruned in identification (relative standard deviation above "
        f"{threshold}) taken as zero" + (f": {', '.join(pruned)}" if pruned else "")
    )


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
                raise ModelError(
                    f"{args.params}: 'friction_model' must be {{kind, velocity}}, got {recorded!r}"
                )
            velocity = recorded.get("velocity")
            if velocity is not None and not (
                isinstance(velocity, list)
                and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in velocity)
            ):
                raise ModelError(
                    f"{args.params}: friction_model velocity must be a list of numbers"
                )
            robot = robot.with_friction_model(recorded["kind"], velocity=velocity or None)
    if not args.friction:
        return robot, ""
    model = robot.friction_model
    scale = {"smooth": "tanh widths", "stribeck": "Stribeck velocities"}.get(model["kind"])
    words = f"friction model: {model['kind']}"
    if scale:
        words += f" ({scale} " + ", ".join(f"{v:g}" for v in model["velocity"]) + ")"
    return robot, words + (f", from {args.params}" if recorded else " (the default)")


def _identified_params(path: str, robot, base, args):
    """The values of a ``mindyn identify --json`` file in the order of ``base.names``, with the
    parameters it pruned (``removed``) as zero, and the pruned names; ``(None, [], "")`` for any
    other parameter file (read by :func:`mindyn.codegen.read_parameter_file`); and the pruning
    threshold as text."""
    from ..identification.data import DataError, read_json

    try:
        doc = read_json(path)
    except (DataError, FileNotFoundError):
        return None, [], ""
    if not (isinstance(doc, dict) and {"names", "values", "removed"} <= doc.keys()):
        return None, [], ""
    if doc.get("robot") not in (None, robot.name):
        raise ModelError(
            f"{path}: parameters identified for robot '{doc['robot']}', not '{robot.name}'"
        )
    flags = {"rotor": args.rotor, "friction": args.friction, "offset": args.offset}
    differ = [k for k, on in flags.items() if k in doc and bool(doc[k]) != on]
    if differ:
        said = " ".join(f"--{k}" for k in flags if doc.get(k))
        raise ModelError(
            f"{path}: identified "
            f"{'with ' + said if said else 'without --rotor, --friction and --offset'}; "
            "give codegen the same --rotor and --friction (and --offset) as identify"
        )
    names, values = doc["names"], doc["values"]
    try:
        pruned = [r["name"] if isinstance(r, dict) else str(r) for r in doc["removed"]]
    except (KeyError, TypeError):
        raise ModelError(f"{path}: 'removed' must list the pruned parameters by name") from None
    if not (isinstance(names, list) and isinstance(values, list) and len(names) == len(values)):
        raise ModelError(f"{path}: 'names' and 'values' must be lists of the same length")
    known = set(base.names)
    unknown = [k for k in names + pruned if k not in known]
    if unknown:
        raise ModelError(
            f"{path}: unknown parameter(s) {', '.join(unknown[:5])}; expected "
            f"{', '.join(base.names)}"
        )
    given = dict(zip(names, values))
    both = [k for k in pruned if k in given]
    if both:
        raise ModelError(f"{path}: {', '.join(both[:5])} both identified and pruned")
    missing = [k for k in base.names if k not in given and k not in pruned]
    if missing:
        raise ModelError(f"{path}: missing parameter(s) {', '.join(missing[:8])}")
    out = np.zeros(len(base.names))
    for i, k in enumerate(base.names):
        if k in given:
            v = given[k]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ModelError(f"{path}: value of '{k}' is not a finite number")
            out[i] = v
    threshold = doc.get("rsd_threshold")
    said = f"{threshold:g} %" if isinstance(threshold, (int, float)) else "the threshold"
    return out, [k for k in base.names if k in pruned], said
