"""Validation of an identification: torque prediction on other data, and the base values of a
known truth."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np

from .. import _args
from ..base import BaseParameters
from .data import DataError
from .estimation import IdentificationResult, _logs
from .joint_data import JointData
from .models import require_torque, torque_noise

#: A joint's sample counts as moving when its speed is at least this many times the noise level
#: of its velocity (:func:`moving_threshold`): below it the direction, hence the Coulomb sign, is
#: not known, and a joint resting there is held by stiction, which the model does not describe.
MOVING_NOISE_FACTOR = 3.0
#: ... and at least this fraction of the joint's largest speed in the log (noise-free velocities
#: have no noise level; the filter's ringing about a rest is of this order).
MOVING_PEAK_FRACTION = 1e-3


def error_measures(tau: np.ndarray, tau_hat: np.ndarray, *, effort=None, mask=None) -> dict:
    """The usual torque-error measures of an identified model, from measured ``tau`` and
    predicted ``tau_hat`` (m, n):

    - ``overall_relative``: ``|tau - tau_hat| / |tau|`` over all joints and samples stacked
      (Frobenius norms; a fraction, NaN for zero torques);
    - ``relative``: the same per joint, shape (n,);
    - ``rms``: per-joint RMS of ``tau - tau_hat`` [N m | N], shape (n,);
    - ``nrms``: ``rms`` over the joint's torque limit ``effort`` (n,) (a fraction), NaN where
      the limit is missing (not finite or not positive); ``nrms_missing`` lists those joints
      (1-based).

    ``mask`` (m, n) of bool, optional: only the samples it marks count, joint by joint (the
    RMS of a joint with none is NaN); ``counted`` then gives each joint's count.
    """
    tau = _args.array(tau, "tau", (None, None))
    err = tau - _args.array(tau_hat, "tau_hat", tau.shape)
    if effort is not None:
        effort = _args.array(effort, "effort", (tau.shape[1],), finite=False)
    if mask is not None:
        mask = _args.array(mask, "mask", tau.shape) != 0
        tau, err = np.where(mask, tau, 0.0), np.where(mask, err, 0.0)
        count = mask.sum(axis=0)
    else:
        count = np.full(tau.shape[1], tau.shape[0])
    with np.errstate(divide="ignore", invalid="ignore"):
        rms = np.where(count > 0, norm(err, axis=0) / np.sqrt(np.maximum(count, 1)), np.nan)
    norms = norm(tau, axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(norms > 0, norm(err, axis=0) / norms, np.nan)
    total = float(norm(tau))
    overall = float(norm(err)) / total if total > 0 else float("nan")
    lim = np.full(tau.shape[1], np.nan) if effort is None else np.asarray(effort, dtype=float)
    has = np.isfinite(lim) & (lim > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        nrms = np.where(has, rms / np.where(has, lim, 1.0), np.nan)
    out = {
        "overall_relative": overall,
        "relative": rel,
        "rms": rms,
        "nrms": nrms,
        "nrms_missing": [int(k) + 1 for k in np.flatnonzero(~has)],
    }
    if mask is not None:
        out["counted"] = count
    return out


def norm(x: np.ndarray, axis: int | None = None) -> np.ndarray | float:
    """``np.linalg.norm(x, axis=axis)`` (2-norm of the entries) of finite ``x`` without
    overflow: the squares of entries beyond 1e154 overflow, those of ``x`` over its largest
    magnitude do not."""
    x = np.asarray(x, dtype=float)
    if not x.size:
        return np.asarray(np.linalg.norm(x, axis=axis))
    scale = np.abs(x).max(axis=axis, keepdims=True)
    scale = np.where(scale > 0, scale, 1.0)
    out = np.linalg.norm(x / scale, axis=axis, keepdims=True) * scale
    return float(out.item()) if axis is None else np.squeeze(out, axis=axis)


def logged_samples(data: JointData) -> JointData | None:
    """The samples of ``data`` as logged, with the motion the model is evaluated on: those
    :func:`~mindyn.identification.preprocess.preprocess` kept (``data.logged``), ``data``
    itself when its torques were not low-pass filtered, None when they were but the logged
    samples are not known."""
    if data.logged is not None:
        return data.logged
    if "preprocess" in data.processing or data.regressor_filter is not None:
        return None
    return data


def moving_threshold(data: JointData) -> tuple[np.ndarray, str]:
    """Per joint, the speed [rad/s | m/s] at or above which a sample of ``data`` (as given by
    :func:`logged_samples`) counts as moving: :data:`MOVING_NOISE_FACTOR` times the noise level
    of the velocity it carries (recorded by the data path for the filtered velocity, else
    estimated from second differences of ``data.dq``), and at least
    :data:`MOVING_PEAK_FRACTION` of the joint's largest speed. Returns ``(threshold, rule)``,
    the rule in words."""
    noise = data.processing.get("velocity_noise")
    if noise is not None:
        sd = np.asarray(noise["filtered"], dtype=float)
        what = f"the noise level of the filtered velocity ({noise['source']} through the low-pass)"
    else:
        sd = (
            torque_noise([data.dq[p] for p in data.log_slices()])
            if data.m > 2
            else np.zeros(data.n)
        )
        what = "the noise level of the velocity (second differences)"
    peak = np.max(np.abs(data.dq), axis=0) if data.m else np.zeros(data.n)
    thr = np.maximum(MOVING_NOISE_FACTOR * sd, MOVING_PEAK_FRACTION * peak)
    rule = (
        f"|dq_j| >= max({MOVING_NOISE_FACTOR:g} x {what}, {MOVING_PEAK_FRACTION:g} x the "
        "joint's largest speed)"
    )
    return thr, rule


RAW_AGAINST = "the torques as logged, at the logged samples (no low-pass), edges excluded"


class Predictor(Protocol):
    """What :func:`validate` uses of a result (an :class:`IdentificationResult`, a consistent
    one): its base parameters and its torques predicted on a log."""

    @property
    def base(self) -> BaseParameters: ...

    def predict(self, data: JointData) -> np.ndarray: ...


def validate(result: Predictor, data: JointData | Sequence[JointData]) -> dict:
    """Torque prediction on ``data`` (one log or several), with the measures of
    :func:`error_measures` over all logs stacked (``overall_relative``, ``relative``, ``rms``,
    ``nrms`` against the robot's effort limits, ``nrms_missing``), the predicted torques
    ``tau_hat`` ((m, n), a list of them for several logs) and ``logs``: the same measures per
    log, each with its ``source``, ``samples`` and ``tau_hat``.

    These compare with the torques the fit saw (on preprocessed data: low-pass filtered,
    decimated). Beside them:

    - ``raw``: the same measures against the torques as logged, at the logged samples
      (:func:`logged_samples`: the model evaluated on the filtered motion at each logged time
      stamp between the dropped filter edges), with its ``samples``; None when the logged
      samples are not known;
    - ``moving``: ``raw`` on the moving samples only, joint by joint (:func:`moving_threshold`),
      with ``threshold`` (n,) (the largest over the logs; each log's in its own ``moving``),
      ``rule``, and ``fraction``: the share of each joint's samples counted.

    Each entry of ``logs`` has its own ``raw`` and ``moving``."""
    from .consistent import ConsistentResult

    _args.instance(result, "result", (IdentificationResult, ConsistentResult))
    logs = _logs(data)
    robot = result.base.robot
    effort = robot.limits["effort"]
    per = []
    for d in logs:
        tau = require_torque(d)
        if d.n != robot.n:
            raise DataError(f"{d.source or 'data'} has {d.n} joints; expected {robot.n}")
        pred = result.predict(d)
        per.append(
            {
                **error_measures(tau, pred, effort=effort),
                "source": d.source,
                "samples": d.m,
                "tau_hat": pred,
                **_raw_and_moving(result, [d], effort),
            }
        )
    out = error_measures(
        np.vstack([require_torque(d) for d in logs]),
        np.vstack([p["tau_hat"] for p in per]),
        effort=effort,
    )
    out["tau_hat"] = (
        per[0]["tau_hat"] if isinstance(data, JointData) else [p["tau_hat"] for p in per]
    )
    out["source"] = ", ".join(d.source for d in logs)
    out["samples"] = sum(d.m for d in logs)
    out.update(_raw_and_moving(result, logs, effort, [p["raw"] for p in per]))
    out["logs"] = per
    return out


def _raw_and_moving(result, logs: list, effort, known=None) -> dict:
    """``raw`` and ``moving`` of :func:`validate` over ``logs`` stacked (``known``: their
    ``raw`` entries computed already, whose ``tau_hat`` is reused)."""
    found = [logged_samples(d) for d in logs]
    raws = [r for r in found if r is not None and r.tau is not None]
    if len(raws) < len(found):
        return {"raw": None, "moving": None}
    hats = [k["tau_hat"] for k in known] if known is not None else [result.predict(r) for r in raws]
    tau = np.vstack([require_torque(r) for r in raws])
    hat = np.vstack(hats)
    raw = error_measures(tau, hat, effort=effort)
    raw.update({"samples": int(tau.shape[0]), "against": RAW_AGAINST, "tau_hat": hats[0]})
    if len(logs) > 1:
        raw["tau_hat"] = hats
    thr = [moving_threshold(r) for r in raws]
    mask = np.vstack([np.abs(r.dq) >= t for r, (t, _) in zip(raws, thr)])
    moving = error_measures(tau, hat, effort=effort, mask=mask)
    moving.update(
        {
            "samples": int(tau.shape[0]),
            "threshold": np.max([t for t, _ in thr], axis=0),
            "rule": thr[0][1],
            "fraction": moving["counted"] / max(tau.shape[0], 1),
            "against": RAW_AGAINST,
        }
    )
    return {"raw": raw, "moving": moving}


def true_base_values(base: BaseParameters, truth: dict) -> np.ndarray:
    """Base-parameter values of a truth sidecar (classical names/values, any layout) in the layout
    of ``base``; classical parameters absent from the truth count as zero."""
    _args.instance(base, "base", BaseParameters)
    _args.mapping(truth, "truth")
    if not {"names", "values"} <= truth.keys():
        raise _args.fail("truth", "must have 'names' and 'values' (a truth sidecar)")
    lookup = dict(zip(truth["names"], truth["values"]))
    pi = np.array([float(lookup.get(nm, 0.0)) for nm in base.classical_names])
    return base.values(pi)
