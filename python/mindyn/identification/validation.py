"""Validation of an identification: torque prediction on other data, and the base values of a
known truth."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np

from .. import _args
from ..base import BaseParameters
from .data import DataError
from .estimation import IdentificationResult, _logs, correlation_factor, noise_variance_factor
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


def uncertainty_measures(tau: np.ndarray, std: np.ndarray) -> dict:
    """How well an estimate determines the torques it predicts, from the standard deviation
    ``std`` (m, n) of each predicted torque
    (:meth:`~mindyn.identification.estimation.IdentificationResult.prediction_std`) beside the
    torques ``tau`` (m, n), as :func:`error_measures` measures the error: ``rms``, the per-joint
    RMS of ``std`` [N m | N] (n,); ``relative``, that over the joint's RMS torque (n,; NaN for
    zero torques); ``overall_relative``, ``|std| / |tau|`` over all joints and samples stacked
    (Frobenius norms): the torques the estimate predicts are determined to +- that fraction.
    ``std`` itself is kept under that key."""
    tau = _args.array(tau, "tau", (None, None))
    std = _args.array(std, "std", tau.shape)
    m = max(tau.shape[0], 1)
    norms = norm(tau, axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(norms > 0, norm(std, axis=0) / norms, np.nan)
    total = float(norm(tau))
    return {
        "rms": norm(std, axis=0) / np.sqrt(m),
        "relative": rel,
        "overall_relative": float(norm(std)) / total if total > 0 else float("nan"),
        "std": std,
    }


#: :func:`prediction_check` warns when the squared prediction uncertainty averaged over the
#: fit's samples, each joint's over its mean squared torque residual, exceeds this share on
#: average over the joints ...
UNCERTAINTY_SHARE = 0.5
#: ... or when on a joint the RMS prediction uncertainty is at least this fraction of its RMS
#: torque (the torque is then not determined even in size).
UNCERTAINTY_RELATIVE = 1.0
#: ... and only when the predicted torques' uncertainty over all joints stacked is above this
#: fraction of ``|tau|``: below it the residual and the uncertainty it scales are the round-off
#: of a noise-free log fitted exactly (1e-14 of the torques on a simulated 6R arm), whose ratio
#: says nothing about the excitation.
UNCERTAINTY_ROUND_OFF = 1e-9


def prediction_check(result: IdentificationResult, fit: dict, data) -> dict:
    """Whether ``result`` determines the torques it predicts, from the measures ``fit`` of
    :func:`validate` on the logs ``data`` it was fitted on (with ``prediction_uncertainty``).

    Per joint ``j``, ``share_j = mean u_j^2 / r_j^2``: the squared prediction uncertainty
    ``u`` (:func:`uncertainty_measures`) averaged over the fit's samples over the fit's mean
    squared torque residual ``r_j^2``; ``mean_share`` is their mean over the joints, the mean
    of ``(u / r_j)^2`` over all the fit's torque equations. For an honest covariance of a
    model that fits the torques themselves (dynamic), the sum of ``u^2`` over the equations,
    each weighted by its inverse residual variance, is ``p`` residual variances times the
    factor for correlated equations: ``mean_share`` is ``p / N_eff`` (``reference``; ``p`` base
    parameters, ``N_eff`` independent torque equations: samples times joints over the factor
    for correlated equations, the dynamic model's own
    (:func:`~mindyn.identification.estimation.noise_variance_factor`), else the data path's for
    samples, :func:`~mindyn.identification.estimation.correlation_factor`); a single joint's share
    differs from it as its equations carry more or less of the parameters' leverage. A model
    fitted on other equations (energy: the power ``dq . tau`` only; integral: torques
    integrated over windows) can leave torque directions its equations hardly see, and ``u``
    far larger: ``excess = mean_share / reference`` is that ratio, about 1 for a fit of the
    torques. As such a model's prediction error is not fitted away, its residual is about
    ``r^2 = s^2 + u^2`` (``s^2``: noise and model error), so ``excess`` is bounded by about
    ``N_eff / p`` however badly the torques are determined; the warning therefore compares
    ``u`` with the residual directly: ``mean_share > 1/2`` (:data:`UNCERTAINTY_SHARE`) means
    ``u > s`` on average over the joints: the estimate's own uncertainty is most of the torque
    residual, and the fit's error figures describe the estimate's indeterminacy rather than the
    robot; not when ``u`` over all joints stacked is at most :data:`UNCERTAINTY_ROUND_OFF` of
    the torques (a noise-free log fitted to round-off, where both are round-off). A fit of the
    torques reaches it only with fewer than ``3 p`` independent equations
    (``mean_share = (p / N_eff) / (1 - p / N_eff)``). On data where model error dominates the
    residual (real logs fitted with the energy model) the share stays small while a joint's
    torque can still be undetermined: the check also warns when a joint's RMS uncertainty is at
    least its RMS torque (:data:`UNCERTAINTY_RELATIVE`: the predicted torque is then within one
    standard deviation of zero; a fit of the torques reaches it only on a joint whose residual
    is several times its torque). The joints named are those whose uncertainty reaches their
    torque and, when the mean share is the reason, those whose own share exceeds 1/2. A share
    above 1 is possible: the error of one fit along an undetermined direction is one draw, and
    can fall below its standard deviation. No torque noise is estimated (on logs whose torques
    a controller smoothed it means nothing): the fit is compared with itself and its torques.

    Returns ``{"share" (n,), "mean_share", "reference", "excess", "threshold",
    "relative_threshold", "joints" (1-based), "warning" (one line, or None), "rule"}``."""
    _args.instance(result, "result", IdentificationResult)
    unc = fit.get("prediction_uncertainty") if isinstance(fit, dict) else None
    if unc is None:
        raise _args.fail("fit", "has no prediction_uncertainty (validate an IdentificationResult)")
    logs = _logs(data, robot=result.base.robot)
    rows = sum(d.m * d.n for d in logs)
    # the factor of the covariance a fit of the torques has: the dynamic model's own (the data
    # path's or its residuals', the larger); else the data path's for samples
    factor = (
        noise_variance_factor(result)
        if result.model == "dynamic"
        else correlation_factor(logs, [d.m * d.n for d in logs], None)[0]
    )
    p = result.base.n
    reference = p * factor / max(rows, 1)
    rms = np.asarray(fit["rms"], dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.where(rms > 0, (np.asarray(unc["rms"]) / rms) ** 2, np.nan)
    mean = float(np.mean(share[np.isfinite(share)])) if np.any(np.isfinite(share)) else 0.0
    rel = np.asarray(unc["relative"], dtype=float)
    large = rel >= UNCERTAINTY_RELATIVE
    # a noise-free log fitted to round-off: u and r are both round-off, their ratio no warning
    material = not float(unc["overall_relative"]) <= UNCERTAINTY_ROUND_OFF
    by_share = material and mean > UNCERTAINTY_SHARE
    named = large | ((share > UNCERTAINTY_SHARE) & by_share)
    joints = [int(j) + 1 for j in np.flatnonzero(named)]
    reasons = []
    if by_share:
        reasons.append(
            f"it is most of the fit's torque residual (mean share {mean:.2g} > "
            f"{UNCERTAINTY_SHARE:g}; a fit of the torques leaves p / N_eff = {reference:.2g})"
        )
    if np.any(large):
        reasons.append(
            "on joint(s) "
            + ", ".join(str(j + 1) for j in np.flatnonzero(large))
            + " it reaches the RMS torque"
        )
    warning = None
    if reasons:
        remedy = {
            "energy": "its equations see only the power dq . tau: use the dynamic model or a "
            "richer excitation",
            "integral": "use the dynamic model or a richer excitation",
        }.get(result.model, "use a longer or richer excitation")
        warning = (
            f"the {result.model} model's estimate does not determine the torques it predicts, "
            f"+-{100 * unc['overall_relative']:.3g} % of |tau| (joint(s) "
            + ", ".join(f"{j} +-{100 * rel[j - 1]:.3g} %" for j in joints)
            + "): "
            + "; ".join(reasons)
            + "; "
            + remedy
        )
    return {
        "share": share,
        "mean_share": mean,
        "reference": reference,
        "excess": mean / reference,
        "threshold": UNCERTAINTY_SHARE,
        "relative_threshold": UNCERTAINTY_RELATIVE,
        "joints": joints if warning else [],
        "warning": warning,
        "rule": (
            f"warned when the mean over the joints of mean u_j^2 / r_j^2 on the fit exceeds "
            f"{UNCERTAINTY_SHARE:g} (u: prediction uncertainty, r: torque residual; a fit of "
            f"the torques leaves p / N_eff = {p} / {rows / factor:.4g} = {reference:.2g}) and "
            f"the predicted torques are determined to more than {UNCERTAINTY_ROUND_OFF:g} of "
            f"|tau| (below: a noise-free log fitted to round-off), or a joint's RMS u reaches "
            f"{UNCERTAINTY_RELATIVE:g} x its RMS torque"
        ),
    }


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

    Each entry of ``logs`` has its own ``raw`` and ``moving``. For an
    :class:`~mindyn.identification.estimation.IdentificationResult` (not a consistent one), the
    stacked measures and each log's also have ``prediction_uncertainty``
    (:func:`uncertainty_measures` of its
    :meth:`~mindyn.identification.estimation.IdentificationResult.prediction_std`); on the logs
    it was fitted on, :func:`prediction_check` judges it."""
    from .consistent import ConsistentResult

    _args.instance(result, "result", (IdentificationResult, ConsistentResult))
    robot = result.base.robot
    logs = _logs(data, robot=robot)
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
        if isinstance(result, IdentificationResult) and result.reduced is not None:
            per[-1]["prediction_uncertainty"] = uncertainty_measures(tau, result.prediction_std(d))
    out = error_measures(
        np.vstack([require_torque(d) for d in logs]),
        np.vstack([p["tau_hat"] for p in per]),
        effort=effort,
    )
    if all("prediction_uncertainty" in p for p in per):
        out["prediction_uncertainty"] = uncertainty_measures(
            np.vstack([require_torque(d) for d in logs]),
            np.vstack([p["prediction_uncertainty"]["std"] for p in per]),
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
    against = RAW_AGAINST
    if any("held" in d.processing.get("torque", {}) for d in logs):
        against += (
            " (read as held: the command held over each period taken at the samples, the "
            "interpolation between the middles of the periods)"
        )
    raw.update({"samples": int(tau.shape[0]), "against": against, "tau_hat": hats[0]})
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
            "against": against,
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
