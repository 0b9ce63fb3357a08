"""The pruning of an identification decided on held-out data (``rsd_threshold="auto"``).

Pruning by relative standard deviation (:func:`~mindyn.identification.estimation.pruned`)
removes the parameters whose estimate is within ``sqrt(2)`` standard deviations of zero
(:data:`~mindyn.identification.options.DEFAULT_RSD_THRESHOLD`, Akaike's criterion for one
parameter): on average that lowers the prediction error when the removed parameters are in
fact negligible, and raises it when they are not (the kept estimates take up what the removed
ones contribute). Which of the two holds depends on the robot and the data; with
``rsd_threshold="auto"`` (:func:`~mindyn.identification.workflow.run`, ``mindyn identify
--rsd-threshold auto``) the data decide: both fits, with every base parameter and pruned at
the default threshold, are scored by cross-validation over contiguous time blocks of the fit
logs (:func:`~mindyn.identification.held_out.held_out_residuals`: each block predicted by the
estimate fitted on the other blocks, each fold's fit pruned as the candidate prunes), and the
pruning is kept unless keeping every base parameter gives a summed held-out residual below
the pruning's by more than one standard error of the difference (from the fold-by-fold paired
differences, :func:`~mindyn.identification.held_out.within_one_error`). This is the
one-standard-error rule of the friction model ``auto``: a tie goes to the simpler model, here
the pruned one with fewer parameters, since a difference within the noise of the held-out
estimate is no evidence for the parameters that the pruning removes. The dynamic, integral
and energy models alike (the energy model's blocks are blocks of its windows). The friction
model's own choice (``auto``) prunes its fits at the default threshold.

The blocks are parts of the fit's own motion: they measure the prediction of motions like it.
A motion that excites what the fit logs excite little can favour the other candidate (see
docs/benchmarks.md: on a real 7-joint arm, pruning predicted another trajectory better while
the blocks of the fit log favoured every parameter)."""

from __future__ import annotations

import numpy as np

from .errors import IdentificationError
from .options import DEFAULT_RSD_THRESHOLD

#: The candidates, the one a tie goes to first: pruned at the default threshold, every base
#: parameter kept (None).
CANDIDATES = (DEFAULT_RSD_THRESHOLD, None)

RULE = (
    "{folds}-fold cross-validation over contiguous time blocks of the fit logs (each block's "
    "residual predicted by the estimate fitted on the other blocks, each fold's fit pruned as "
    "the candidate prunes, summed): the pruning at RSD > {threshold:g} % is kept unless "
    "keeping every base parameter gives a held-out residual below the pruning's by more than "
    "one standard error of the difference (from its fold-by-fold differences); a tie goes to "
    "the pruning (fewer parameters)"
)


def _label(threshold) -> str:
    return "every base parameter" if threshold is None else f"RSD > {threshold:g} %"


def choose_pruning(robot, base, logs, *, fit: dict, folds: int | None = None, progress=None):
    """The fit of ``logs`` (:func:`~mindyn.identification.identify` of ``robot`` with the base
    set ``base`` and the keywords ``fit``, its ``rsd_threshold`` ignored) with the pruning the
    held-out data support (see the module documentation), its decision recorded in
    ``settings["pruning_choice"]``: ``chosen_by``, ``rsd_threshold`` (None: every base
    parameter kept), ``rule``, ``candidates`` (per candidate its ``rsd_threshold``, the
    parameters the whole fit removes, the summed held-out residual, per fold, and the standard
    error of its excess over the smallest) and ``smallest``. When the default threshold
    removes nothing there is nothing to decide (``chosen_by``: ``nothing to prune``)."""
    from .estimation import identify, repruned
    from .held_out import held_out_residuals, within_one_error
    from .prior import FOLDS

    folds = FOLDS if folds is None else folds
    fit = {k: v for k, v in fit.items() if k != "rsd_threshold"}
    threshold = CANDIDATES[0]
    res = identify(robot, logs, base=base, rsd_threshold=threshold, **fit)

    def unscored(how: str, why: str):
        res.settings["pruning_choice"] = {
            "chosen_by": how,
            "rsd_threshold": threshold,
            "rule": why,
            "candidates": [],
        }
        return res

    if not res.removed:
        return unscored("nothing to prune", f"no base parameter has an RSD above {threshold:g} %")
    try:
        scored = held_out_residuals(
            res,
            logs,
            folds=folds,
            thresholds=CANDIDATES,
            rank_tolerance=fit.get("rank_tolerance"),
            what="pruning choice",
        )
    except (IdentificationError, np.linalg.LinAlgError) as e:
        # too few blocks to score: the default threshold, said so
        return unscored("default (held-out data not scored)", f"not scored ({e})")
    scores = {t: s for t, (s, _) in zip(CANDIDATES, scored)}
    per_fold = {t: f for t, (_, f) in zip(CANDIDATES, scored)}
    chosen, best, se = within_one_error(scores, per_fold, order=CANDIDATES)
    if progress is not None:
        progress(
            "pruning: held-out residual "
            + ", ".join(f"{_label(t)} {s:.4g}" for t, s in scores.items())
        )
    removed = {threshold: len(res.removed), None: 0}
    if chosen is None:  # the same least-squares problem, every parameter kept
        res = repruned(res, None)
    res.settings["pruning_choice"] = {
        "chosen_by": "held-out data",
        "rsd_threshold": chosen,
        "rule": RULE.format(folds=folds, threshold=threshold),
        "smallest": best,
        "candidates": [
            {
                "rsd_threshold": t,
                "removed": removed[t],
                "held_out": float(scores[t]),
                "per_fold": [float(x) for x in per_fold[t]],
                "standard_error": se[t],
            }
            for t in CANDIDATES
        ],
        "unit": "weighted residual per equation",
    }
    return res


def pruning_line(choice: dict | None) -> str | None:
    """The output line that states the pruning decision of ``settings["pruning_choice"]``
    (None when nothing is recorded: a threshold given)."""
    if not choice:
        return None
    how = choice["chosen_by"]
    if not choice.get("candidates"):
        return f"  pruning at RSD > {choice['rsd_threshold']:g} % ({how}: {choice['rule']})"
    c = {d["rsd_threshold"]: d for d in choice["candidates"]}
    pruned, kept = (c[t] for t in CANDIDATES)
    gain = pruned["held_out"] - kept["held_out"]
    se = max(kept["standard_error"], pruned["standard_error"])
    figures = (
        f"held-out residual {kept['held_out']:.4g} with every base parameter, "
        f"{pruned['held_out']:.4g} pruned at RSD > {pruned['rsd_threshold']:g} % "
        f"(pruned minus all kept {gain:.3g}, standard error {se:.3g})"
    )
    if choice["rsd_threshold"] is None:
        return (
            f"  pruning: none, every base parameter kept, chosen on held-out data ({figures}: "
            "keeping them is better by more than one standard error; rsd_threshold= sets it)"
        )
    return (
        f"  pruning at RSD > {choice['rsd_threshold']:g} %, chosen on held-out data ({figures}: "
        "keeping every base parameter is not better by more than one standard error; "
        "rsd_threshold= sets it)"
    )
