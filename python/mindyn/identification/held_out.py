"""Held-out residuals of a fit over contiguous time blocks of its logs, and the
one-standard-error rule on them: how the friction model ``auto``
(:func:`~mindyn.identification.friction.select_friction_model`) and the default pruning
(:mod:`~mindyn.identification.pruning`) decide from the data."""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np

from .._threads import single_threaded_blas
from .errors import IdentificationError


@single_threaded_blas  # thousands of small triangles: one BLAS thread is faster
def held_out_residuals(
    res,
    logs,
    *,
    folds: int,
    thresholds,
    joint_sigma=None,
    rank_tolerance: float | None = None,
    what: str = "held-out residual",
) -> list[tuple[float, np.ndarray]]:
    """Per RSD threshold of ``thresholds`` (None: no pruning), the summed held-out residual
    per equation of the fit ``res`` over ``folds`` contiguous blocks of ``logs``
    (:func:`~mindyn.identification.prior.block_triangles`), each block predicted by the
    estimate fitted on the other blocks the way ``res`` was fitted (fitted on the fit's
    equations, scored on every sample or window, those the dynamic and integral models leave
    out as slower than ``min_velocity`` included), and each block's share: a list of
    ``(total, per block)``; rows weighted with ``joint_sigma`` when given (else the fit's own
    weights). The blocks' triangles are formed once for all thresholds.

    Each fold's fit decides as the fit itself: the base parameters its blocks determine
    (pivoted QR of the column-scaled regressor, pivots below ``rank_tolerance`` (default:
    :func:`~mindyn.identification.identify`'s) of the largest left out), then pruned by
    relative standard deviation at the threshold (:func:`~mindyn.identification.estimation.
    pruned`, with the fit's variance factor for correlated samples). A parameter that the
    other blocks do not determine (e.g. a Stribeck term whose column is non-zero on a few
    samples of the held-out block only) is thus left out instead of being fitted to noise and
    extrapolated: the score measures a prediction, not the conditioning. ``what`` names the
    caller in the error raised when the data give fewer than 2 blocks."""
    import inspect

    from .estimation import _Reduced, _triangle, identify, noise_variance_factor, pruned
    from .prior import block_triangles

    if joint_sigma is not None and res.model != "energy":
        res = dataclasses.replace(res, joint_sigma=np.asarray(joint_sigma), weighted=True)
    if rank_tolerance is None:
        rank_tolerance = inspect.signature(identify).parameters["rank_tolerance"].default
    S, rows = block_triangles(res, logs, folds=folds, counts=True)
    # a block is predicted at every sample, also where the fit leaves the equations of slow
    # joints out (min_velocity): a model's switching at rest counts against it
    held = S
    if res.settings.get("min_velocity", 0.0) > 0:
        every = dataclasses.replace(res, settings={**res.settings, "min_velocity": 0.0})
        held = block_triangles(every, logs, folds=folds)
    nb = res.base.n
    used = [k for k in range(folds) if np.any(S[k])]
    if len(used) < 2:
        raise IdentificationError(f"{what}: the data give fewer than 2 blocks")
    inflation = noise_variance_factor(res)

    err = np.zeros((len(thresholds), len(used)))
    for i, k in enumerate(used):
        others = [u for u in used if u != k]
        ls = _Reduced.from_triangle(
            _triangle(np.vstack([S[u] for u in others])), rows[others].sum()
        )
        rank, piv, _ = ls.rank(rank_tolerance)
        determined = sorted(int(c) for c in piv[:rank])
        solve = functools.partial(ls.solve, inflation=inflation)
        for t, threshold in enumerate(thresholds):
            keep, p, _, _, _ = pruned(solve, determined, threshold)
            full = np.zeros(nb)
            full[keep] = p
            r = held[k] @ np.append(full, -1.0)
            err[t, i] = float(r @ r) / max(res.rows, 1)
    return [(float(e.sum()), e) for e in err]


def within_one_error(scores: dict, per_fold: dict, *, order) -> tuple:
    """The one-standard-error rule on paired differences: ``scores`` (candidate -> summed
    held-out residual) and ``per_fold`` (candidate -> its residual per block, the same blocks
    for every candidate), ``order`` the candidates, the one a tie goes to first. Returns
    ``(chosen, best, se)``: the first candidate in ``order`` whose excess over the smallest,
    ``best``, is at most one standard error of that excess, ``se`` per candidate: ``sqrt(K)``
    times the standard deviation of its ``K`` block-by-block differences from ``best`` (how
    hard a block is to predict is common to every candidate and cancels)."""
    order = list(order)
    best = min(scores, key=lambda k: (scores[k], order.index(k)))
    se = {}
    for k in scores:
        diff = np.asarray(per_fold[k], float) - np.asarray(per_fold[best], float)
        se[k] = float(np.std(diff, ddof=1) * math.sqrt(diff.size)) if diff.size > 1 else 0.0
    chosen = next(k for k in order if k in scores and scores[k] <= scores[best] + se[k])
    return chosen, best, se
