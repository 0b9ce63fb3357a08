"""Validation of an identification: torque prediction on other data, and the base values of a
known truth."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..base import BaseParameters
from .data import DataError, JointData
from .estimation import IdentificationResult
from .models import require_torque


def error_measures(tau: np.ndarray, tau_hat: np.ndarray, effort=None) -> dict:
    """The usual torque-error measures of an identified model, from measured ``tau`` and
    predicted ``tau_hat`` (m, n):

    - ``overall_relative``: ``|tau - tau_hat| / |tau|`` over all joints and samples stacked
      (Frobenius norms; a fraction, NaN for zero torques);
    - ``relative``: the same per joint, shape (n,);
    - ``rms``: per-joint RMS of ``tau - tau_hat`` [N m | N], shape (n,);
    - ``nrms``: ``rms`` over the joint's torque limit ``effort`` (n,) (a fraction), NaN where
      the limit is missing (not finite or not positive); ``nrms_missing`` lists those joints
      (1-based).
    """
    tau = np.asarray(tau, dtype=float)
    err = tau - np.asarray(tau_hat, dtype=float)
    rms = np.sqrt(np.mean(err**2, axis=0))
    norm = np.linalg.norm(tau, axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(norm > 0, np.linalg.norm(err, axis=0) / norm, np.nan)
    total = float(np.linalg.norm(tau))
    overall = float(np.linalg.norm(err)) / total if total > 0 else float("nan")
    lim = np.full(tau.shape[1], np.nan) if effort is None else np.asarray(effort, dtype=float)
    has = np.isfinite(lim) & (lim > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        nrms = np.where(has, rms / np.where(has, lim, 1.0), np.nan)
    return {
        "overall_relative": overall,
        "relative": rel,
        "rms": rms,
        "nrms": nrms,
        "nrms_missing": [int(k) + 1 for k in np.flatnonzero(~has)],
    }


def validate(result: IdentificationResult, data: JointData | Sequence[JointData]) -> dict:
    """Torque prediction on ``data`` (one log or several), with the measures of
    :func:`error_measures` over all logs stacked (``overall_relative``, ``relative``, ``rms``,
    ``nrms`` against the robot's effort limits, ``nrms_missing``), the predicted torques
    ``tau_hat`` ((m, n), a list of them for several logs) and ``logs``: the same measures per
    log, each with its ``source``, ``samples`` and ``tau_hat``."""
    logs = [data] if isinstance(data, JointData) else list(data)
    if not logs:
        raise DataError("validate: no data")
    robot = result.base.robot
    effort = robot.limits["effort"]
    per = []
    for d in logs:
        require_torque(d)
        if d.n != robot.n:
            raise DataError(f"{d.source or 'data'} has {d.n} joints; expected {robot.n}")
        pred = result.predict(d)
        per.append(
            {
                **error_measures(d.tau, pred, effort),
                "source": d.source,
                "samples": d.m,
                "tau_hat": pred,
            }
        )
    out = error_measures(
        np.vstack([d.tau for d in logs]), np.vstack([p["tau_hat"] for p in per]), effort
    )
    out["tau_hat"] = (
        per[0]["tau_hat"] if isinstance(data, JointData) else [p["tau_hat"] for p in per]
    )
    out["source"] = ", ".join(d.source for d in logs)
    out["samples"] = sum(d.m for d in logs)
    out["logs"] = per
    return out


def true_base_values(base: BaseParameters, truth: dict) -> np.ndarray:
    """Base-parameter values of a truth sidecar (classical names/values, any layout) in the layout
    of ``base``; classical parameters absent from the truth count as zero."""
    lookup = dict(zip(truth["names"], truth["values"]))
    pi = np.array([float(lookup.get(nm, 0.0)) for nm in base.classical_names])
    return base.values(pi)
