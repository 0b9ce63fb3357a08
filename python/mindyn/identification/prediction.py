"""Torques an identified model predicts on any log, so that anyone can score the model their
own way: the model ``W_b(q, dq, ddq) @ p_b`` of an identification (its JSON, or a result) on the
motion identify would read from that log, at the log's own samples."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import _args
from .._args import ArgumentError
from ..base import BaseParameters
from ..robot import Robot, load
from .data import DataError
from .document import (
    check_identified_model,
    check_identified_robot,
    identified_base,
    names_difference,
    read_identification,
)
from .estimation import CHUNK_SAMPLES
from .joint_data import JointData
from .models import require_torque
from .validation import logged_samples

__all__ = ["Prediction", "identified_model", "predict"]


@dataclass
class Prediction:
    """Predicted joint torques at the samples of a log.

    Attributes
    ----------
    t : ndarray (m,)
        The log's time stamps (between the filter edges on low-pass filtered data).
    q, dq, ddq : ndarray (m, n)
        The motion the model was evaluated on (filtered, at those stamps).
    tau_hat : ndarray (m, n)
        Predicted torques ``W_b(q, dq, ddq) @ values``.
    tau : ndarray (m, n) or None
        The torques as logged at those samples (N m), when the log has them.
    values : ndarray (nb,)
        The base-parameter values used, in the order of ``base.names``.
    info : dict
        Where the values came from and how the log was read.
    """

    t: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    ddq: np.ndarray
    tau_hat: np.ndarray
    tau: np.ndarray | None
    base: BaseParameters
    values: np.ndarray
    info: dict = field(default_factory=dict)

    def write_csv(self, path) -> Path:
        """``t, q1..qn, dq1..dqn, ddq1..ddqn, tau_hat1..tau_hatn[, tau1..taun]`` with 17
        significant digits (the motion as evaluated, so that other code can be run on the same
        states)."""
        n = self.q.shape[1]
        cols = [self.t[:, None], self.q, self.dq, self.ddq, self.tau_hat]
        names = ["t"] + [f"{k}{j + 1}" for k in ("q", "dq", "ddq", "tau_hat") for j in range(n)]
        if self.tau is not None:
            cols.append(self.tau)
            names += [f"tau{j + 1}" for j in range(n)]
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savetxt(
            path, np.hstack(cols), delimiter=",", header=",".join(names), comments="", fmt="%.17g"
        )
        return path


def identified_model(
    identification, robot: Robot | str | None = None, *, estimate: str = "unconstrained"
) -> tuple[BaseParameters, np.ndarray, dict]:
    """The base parameters and their values of an identification: a result of
    :func:`~mindyn.identification.identify` or :func:`~mindyn.identification.consistent.
    consistent_estimate` (``robot`` unused), or the JSON of ``mindyn identify --json`` (a path or
    its dict; ``robot`` is then required, loaded with the JSON's ``tip``, the base parameters formed
    with its ``rotor``, ``friction`` and ``offset`` and checked against its ``base_names`` and
    ``model_check``). ``estimate``: ``unconstrained`` (``base_values``) or ``consistent``
    (``consistent_estimate.base_values``). Returns ``(base, values, doc)`` (``doc`` empty for a
    result)."""
    _args.choice(estimate, "estimate", ("unconstrained", "consistent"))
    _args.optional(
        _args.instance, robot, "robot", (Robot, str, Path), "a Robot, a robot name or a path"
    )
    if not (hasattr(identification, "base") and hasattr(identification, "full")):
        _args.instance(
            identification,
            "identification",
            (dict, str, Path),
            "an identification (a result, or its JSON as a dict or path)",
        )
    if hasattr(identification, "base") and hasattr(identification, "full"):
        if estimate == "consistent" and not hasattr(identification, "classical"):
            raise ArgumentError("estimate 'consistent' needs a consistent result")
        return identification.base, np.asarray(identification.full, dtype=float), {}
    where = str(identification) if not isinstance(identification, dict) else "identification"
    doc = read_identification(identification, need=("base_names", "base_values"), what=where)
    if robot is None:
        raise _args.fail("robot", "is None; the robot is needed with an identification JSON")
    if not isinstance(robot, Robot):
        robot = load(robot, tip=doc.get("tip"))
    check_identified_robot(doc, robot, where)
    base = identified_base(doc, robot, where)
    robot = base.robot
    check_identified_model(doc, base, where)
    src: dict = doc
    if estimate == "consistent":
        consistent = doc.get("consistent_estimate")
        if not isinstance(consistent, dict) or "base_values" not in consistent:
            raise DataError(
                f"{where}: holds no consistent estimate (identify with consistent=True)"
            )
        src = consistent
    names = src["base_names"] if "base_names" in src else doc["base_names"]
    values = src["base_values"]
    if not (isinstance(names, list) and isinstance(values, list)):
        raise DataError(
            f"{where}: the consistent estimate's base_names and base_values must be lists"
        )
    if names != list(base.names):
        raise DataError(
            f"{where}: its base parameters are not those of '{robot.name}' with its "
            f"rotor/friction/offset settings ({names_difference(names, base.names)})"
        )
    try:
        values = np.array([float(v) for v in values])
    except (TypeError, ValueError):
        raise DataError(f"{where}: base_values must be numbers") from None
    if values.shape != (base.n,) or not np.all(np.isfinite(values)):
        raise DataError(f"{where}: base_values must be {base.n} finite numbers")
    return base, values, doc


def predict(
    identification,
    data: JointData | Sequence[JointData],
    *,
    robot: Robot | str | None = None,
    estimate: str = "unconstrained",
) -> Prediction:
    """The torques the model of ``identification`` (see :func:`identified_model`) predicts on
    ``data``: one log or its segments, read as identify reads them. On data of
    :func:`~mindyn.identification.preprocess.preprocess` the model is evaluated on the filtered
    motion at each logged time stamp between the dropped filter edges (``data.logged``: no
    decimation, no filtering of the prediction); otherwise on the samples as given. Segments
    are stacked in order."""
    from .estimation import _logs

    base, values, doc = identified_model(identification, robot, estimate=estimate)
    logs = _logs(data, robot=base.robot)
    if not logs:
        raise DataError("predict: no data")
    parts = []
    for d in logs:
        if d.n != base.robot.n:
            raise DataError(f"{d.source or 'data'} has {d.n} joints; expected {base.robot.n}")
        s = logged_samples(d)
        if s is None:
            raise DataError(
                f"{d.source or 'data'}: low-pass filtered without its logged samples; give the "
                "log as read, or as preprocess() returns it"
            )
        parts.append(s)
    t = np.concatenate([s.t for s in parts])
    q, dq, ddq = (np.vstack([getattr(s, k) for s in parts]) for k in ("q", "dq", "ddq"))
    tau_hat = np.empty_like(q)
    for a in range(0, t.size, CHUNK_SAMPLES):
        b = min(t.size, a + CHUNK_SAMPLES)
        tau_hat[a:b] = base.regressor(q[a:b], dq[a:b], ddq[a:b]) @ values
    has_tau = all(s.tau is not None for s in parts)
    info = {
        "estimate": estimate,
        "robot": base.robot.name,
        "base_names": list(base.names),
        "sources": [d.source for d in logs],
        "samples": int(t.size),
        "motion": (
            "filtered, at the logged time stamps between the filter edges"
            if any(d.logged is not None for d in logs)
            else "as read"
        ),
    }
    return Prediction(
        t,
        q,
        dq,
        ddq,
        tau_hat,
        np.vstack([require_torque(s) for s in parts]) if has_tau else None,
        base,
        values,
        info,
    )
