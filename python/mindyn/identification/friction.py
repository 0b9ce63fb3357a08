"""The friction model of an identification: given, derived from the data, or chosen on held-out
data.

The friction models (:attr:`mindyn.Robot.friction_model`), per slot with velocity ``v``:
``coulomb`` ``Fv v + Fc sign(v)``; ``asymmetric`` ``Fv v + Fc sign(v) + Fa |sign(v)|``;
``smooth`` ``Fv v + Fc tanh(v / w)``; ``stribeck`` ``Fv v + Fc sign(v) + Fs sign(v)
exp(-(v / w)^2)``.

- ``smooth``: the width ``w_j`` of joint ``j`` is given, or derived from the data
  (:func:`smooth_width`): the speed below which the data do not determine the sign of the
  velocity, the threshold of the error measures' moving samples
  (:func:`~mindyn.identification.validation.moving_threshold`: 3 times the noise level of the
  joint's velocity as the fit uses it, recorded by the data path for the filtered velocity or
  estimated from second differences, and at least 0.001 of the joint's largest speed), the
  largest over the fit logs.
- ``stribeck``: the Stribeck velocity ``w_j`` of each joint is found by a one-dimensional search
  on the fit's residual (:func:`stribeck_search`): a log-spaced grid of :data:`GRID_POINTS`
  velocities from the joint's velocity noise level (the smooth width above: a smaller Stribeck
  velocity is not resolved by the data; the dynamic model: at least its ``min_velocity``, below
  which it has no equation) to its largest speed, then a
  golden-section search on ``log w`` between the grid neighbours of the best point, all joints
  at once (one fit per step: each joint's velocity changes only its own equations' friction
  column), the objective of joint ``j`` its residual in the first (ordinary least-squares) fit.
  The energy model has one equation for all joints: there the joints are searched one after
  the other on the overall residual.
- ``auto``: the four models are fitted (the smooth width and the Stribeck velocities derived
  and searched on all fit logs as above) and each scored by cross-validation over contiguous
  time blocks of the fit logs (:func:`~mindyn.identification.prior.block_triangles`: each
  block's residual predicted by the estimate fitted on the other blocks, summed, every model
  weighted with the same per-joint weights, those of the Coulomb fit; every sample of a block
  scored, also those the dynamic model leaves out of the fit as slower than ``min_velocity``);
  the simplest model (in the order coulomb, smooth, asymmetric, stribeck) whose summed held-out
  residual is within one standard error of the smallest (the one-standard-error rule, as for
  the prior's weight, the error from the spread of the blocks) wins. A model the data cannot
  identify (e.g. ``asymmetric`` with torque offsets, whose ``Fa`` is a constant torque whenever
  the joint moves) is reported and left out.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from ..base import BaseParameters
from ..robot import FRICTION_KINDS, Robot
from .errors import IdentificationError

#: The friction models, simplest first (a tie in the held-out residual goes to the simpler).
KINDS = ("coulomb", "smooth", "asymmetric", "stribeck")

#: What ``--friction-model`` accepts.
CHOICES = (*FRICTION_KINDS, "auto")


#: Points of the Stribeck search's log-spaced grid, and golden-section steps after it.
GRID_POINTS = 13
GOLDEN_STEPS = 24

_GOLD = (math.sqrt(5.0) - 1.0) / 2.0


@dataclass
class FrictionChoice:
    """The robot with its friction model and the base set for it, and the record of the choice
    for the output (``kind``, ``velocity`` per slot or None, ``chosen_by``, and how)."""

    robot: Robot
    base: BaseParameters
    record: dict = field(default_factory=dict)


def _speeds(logs) -> np.ndarray:
    return np.max(np.vstack([np.abs(d.dq) for d in logs]), axis=0)


def _noise_width(logs) -> tuple[np.ndarray, str]:
    """Per joint, the speed below which the sign of the velocity is not determined by the data:
    the moving threshold of the error measures
    (:func:`~mindyn.identification.validation.moving_threshold`: 3 x the noise level of the
    velocity as the fit uses it, at least 0.001 x the joint's largest speed), the largest over
    ``logs``; and the rule in words."""
    from .validation import logged_samples, moving_threshold

    # the logged samples carry the data path's noise level of the filtered velocity
    rules = [moving_threshold(logged_samples(d) or d) for d in logs]
    return np.max([w for w, _ in rules], axis=0), rules[0][1]


def smooth_width(logs) -> tuple[np.ndarray, str]:
    """The smooth model's tanh width per joint from the velocities of ``logs`` (see the module
    documentation), and the rule in words."""
    w, rule = _noise_width(logs)
    if not np.all(w > 0):
        still = [str(j + 1) for j in np.flatnonzero(~(w > 0))]
        raise IdentificationError(
            f"smooth friction: joint(s) {', '.join(still)} never move in the fit data; their tanh "
            "width cannot be derived (give --friction-width, or leave out --friction)"
        )
    return w, rule.replace("|dq_j| >= ", "w_j = ")


def _default(option: str):
    """The default of an option of :func:`~mindyn.identification.identify`."""
    import inspect

    from .estimation import identify

    return inspect.signature(identify).parameters[option].default


def _fit(base: BaseParameters, logs, fit: dict):
    from .estimation import identify

    return identify(base.robot, logs, base=base, **fit)


def _objective(base: BaseParameters, logs, fit: dict, per_joint: bool) -> np.ndarray:
    """The fit's residual per joint (first OLS pass) or overall; inf where the fit fails."""
    from .errors import RankDeficientError

    n = base.robot.n
    try:
        res = _fit(base, logs, {**fit, "rsd_threshold": None, "weighted": True})
    except (RankDeficientError, np.linalg.LinAlgError):
        return np.full(n, np.inf)
    if per_joint and res.joint_sigma is not None:
        return np.asarray(res.joint_sigma, float)
    return np.full(n, res.sigma)


def stribeck_search(base: BaseParameters, logs, *, fit: dict) -> tuple[np.ndarray, dict]:
    """The Stribeck velocity per joint minimising the fit's residual (see the module
    documentation): ``(velocity, record)``; ``base`` is a Stribeck base set (its velocities are
    replaced)."""
    n = base.robot.n
    top = _speeds(logs)
    if not np.all(top > 0):
        still = [str(j + 1) for j in np.flatnonzero(~(top > 0))]
        raise IdentificationError(
            f"Stribeck friction: joint(s) {', '.join(still)} never move in the fit data; their "
            "Stribeck velocity cannot be searched (leave out --friction, or move them)"
        )
    # Below the velocity's noise level (the smooth width) the data do not resolve the velocity,
    # and the dynamic model has no equation below its min_velocity.
    floor = _noise_width(logs)[0]
    if fit.get("model", "dynamic") == "dynamic":
        floor = np.maximum(floor, fit.get("min_velocity", _default("min_velocity")))
    lo = np.log(np.minimum(floor, 0.5 * top))
    hi = np.log(top)
    grid = np.linspace(lo, hi, GRID_POINTS)  # (G, n), log velocities
    per_joint = fit.get("model", "dynamic") != "energy"
    evaluations = 0

    def f(logw: np.ndarray) -> np.ndarray:
        nonlocal evaluations
        evaluations += 1
        return _objective(base.with_friction_velocity(np.exp(logw)), logs, fit, per_joint)

    if per_joint:
        values = np.array([f(g) for g in grid])  # (G, n)
        best = np.argmin(values, axis=0)
        x = _golden(f, grid, best, np.arange(n))
    else:  # one joint at a time on the overall residual
        x = grid[GRID_POINTS // 2].copy()
        for j in range(n):
            vals = []
            for g in grid[:, j]:
                y = x.copy()
                y[j] = g
                vals.append(f(y)[0])
            best = np.zeros(n, dtype=int)
            best[j] = int(np.argmin(vals))
            x[j] = _golden(f, grid, best, np.array([j]), start=x)[j]
    record = {
        "search": (
            f"log-spaced grid of {GRID_POINTS} velocities from the joint's velocity noise level "
            "(the smooth width rule; the dynamic model: at least its min_velocity) to its "
            f"largest speed, then {GOLDEN_STEPS} golden-section steps on log velocity, "
            + (
                "all joints at once, each on its own residual (first OLS fit)"
                if per_joint
                else "one joint at a time on the overall residual"
            )
        ),
        "fits": evaluations,
        "range": [[float(a), float(b)] for a, b in zip(np.exp(lo), np.exp(hi))],
        "at_range_end": [
            bool(abs(v - a) < 1e-3 or abs(v - b) < 1e-3) for v, a, b in zip(x, lo, hi)
        ],
    }
    return np.exp(x), record


def _golden(f, grid, best, joints, start=None) -> np.ndarray:
    """Golden-section search on log velocity of ``joints``, each between the grid neighbours of
    its best grid point, the others held at ``start`` (default: their best grid points)."""
    G, n = grid.shape
    cols = np.arange(n)
    x = grid[best, cols].copy() if start is None else start.copy()
    a = grid[np.maximum(best - 1, 0), cols]
    b = grid[np.minimum(best + 1, G - 1), cols]
    c = b - _GOLD * (b - a)
    d = a + _GOLD * (b - a)

    def at(points):
        y = x.copy()
        y[joints] = points[joints]
        return f(y)

    fc, fd = at(c), at(d)
    for _ in range(GOLDEN_STEPS):
        left = fc <= fd  # the minimum is in [a, d]
        b = np.where(left, d, b)
        a = np.where(left, a, c)
        new_c = np.where(left, b - _GOLD * (b - a), d)
        new_d = np.where(left, c, a + _GOLD * (b - a))
        c, d = new_c, new_d
        trial = np.where(left, c, d)
        ft = at(trial)
        fc, fd = np.where(left, ft, fd), np.where(left, fc, ft)
    x[joints] = 0.5 * (a + b)[joints]
    return x


def select_friction_model(
    robot: Robot,
    logs,
    kind: str = "coulomb",
    *,
    rotor: bool = False,
    offset: bool = False,
    width=None,
    fit: dict | None = None,
    folds: int | None = None,
    progress=None,
) -> FrictionChoice:
    """The robot with the friction model ``kind`` (:data:`CHOICES`) for identifying it from
    ``logs`` with the :func:`~mindyn.identification.identify` options ``fit``, and the base set
    with friction (and ``rotor``, ``offset``) for it; see the module documentation for how
    the smooth width (unless ``width`` is given, one value or one per joint), the Stribeck
    velocities and ``auto`` are decided."""
    from ..base import base_parameters
    from .prior import FOLDS

    if kind not in CHOICES:
        raise IdentificationError(
            f"friction model must be {', '.join(CHOICES[:-1])} or auto, not {kind!r}"
        )
    fit = dict(fit or {})
    n = robot.n
    given_width = None
    if width is not None:
        given_width = np.broadcast_to(np.asarray(width, float), (n,)).copy()
        if kind not in ("smooth", "auto"):
            raise IdentificationError("--friction-width: only with --friction-model smooth or auto")

    def make(k: str, velocity=None):
        r = robot.with_friction_model(k, velocity=velocity)
        return r, base_parameters(r, rotor=rotor, friction=True, offset=offset)

    def one(k: str) -> FrictionChoice:
        rec: dict = {"kind": k, "velocity": None}
        if k == "smooth":
            if given_width is not None:
                w, rule = given_width, "given (--friction-width)"
            else:
                w, rule = smooth_width(logs)
            rec.update(velocity=[float(v) for v in w], velocity_rule=rule)
            r, b = make(k, w)
        elif k == "stribeck":
            r, b = make(k, _speeds(logs).clip(min=1e-300))
            if progress is not None:
                progress("friction: searching the Stribeck velocities")
            w, search = stribeck_search(b, logs, fit=fit)
            b = b.with_friction_velocity(w)
            r = b.robot
            rec.update(
                velocity=[float(v) for v in w], velocity_rule=search["search"], search=search
            )
        else:
            r, b = make(k)
        return FrictionChoice(r, b, rec)

    if kind != "auto":
        out = one(kind)
        out.record["chosen_by"] = "default" if kind == "coulomb" else "given"
        return out
    folds = FOLDS if folds is None else folds
    choices, scores, per_fold, refused = {}, {}, {}, {}
    common = None
    for k in KINDS:
        try:
            c = one(k)
            res = _fit(c.base, logs, fit)
        except (IdentificationError, np.linalg.LinAlgError) as e:
            refused[k] = str(e)
            continue
        if common is None:  # the Coulomb fit's weights for every model
            common = res.joint_sigma
        scores[k], per_fold[k] = held_out_residual(res, logs, folds=folds, joint_sigma=common)
        choices[k] = c
        if progress is not None:
            progress(f"friction: {k} held-out residual {scores[k]:.4g}")
    if not scores:
        raise IdentificationError(
            "friction model auto: no friction model can be identified from this data ("
            + "; ".join(f"{k}: {m}" for k, m in refused.items())
            + ")"
        )
    best = min(scores, key=lambda k: (scores[k], KINDS.index(k)))
    # one standard error of the best model's summed held-out residual, from its folds' spread
    err = per_fold[best]
    se = float(np.std(err, ddof=1) * math.sqrt(err.size)) if err.size > 1 else 0.0
    chosen = next(k for k in KINDS if k in scores and scores[k] <= scores[best] + se)
    out = choices[chosen]
    out.record.update(
        chosen_by="held-out data",
        rule=(
            f"{folds}-fold cross-validation over contiguous time blocks of the fit logs (each "
            "block's residual predicted by the estimate fitted on the other blocks, summed, "
            "with the Coulomb fit's per-joint weights): the simplest model (coulomb, smooth, "
            "asymmetric, stribeck) within one standard error of the smallest"
        ),
        smallest=best,
        standard_error=se,
        candidates={k: float(v) for k, v in scores.items()},
        candidates_per_fold={k: [float(x) for x in v] for k, v in per_fold.items()},
        candidates_unit="weighted residual per equation",
        not_identifiable=refused,
    )
    return out


def held_out_residual(res, logs, *, folds: int, joint_sigma=None) -> tuple[float, np.ndarray]:
    """The summed held-out residual per equation of the fit ``res`` over ``folds`` contiguous
    blocks of ``logs`` (:func:`~mindyn.identification.prior.block_triangles`), each block
    predicted by the least-squares estimate of all base parameters on the other blocks (fitted
    on the fit's equations, scored on every sample, those the dynamic model leaves out as slower
    than ``min_velocity`` included), and each block's share: ``(total, per block)``; rows
    weighted with ``joint_sigma`` when given (else the fit's own weights)."""
    from .estimation import _triangle
    from .prior import block_triangles

    if joint_sigma is not None and res.model != "energy":
        res = dataclasses.replace(res, joint_sigma=np.asarray(joint_sigma), weighted=True)
    S = block_triangles(res, logs, folds)
    # a block is predicted at every sample, also where the fit leaves the equations of slow
    # joints out (min_velocity): a model's switching at rest counts against it
    held = S
    if res.settings.get("min_velocity", 0.0) > 0:
        every = dataclasses.replace(res, settings={**res.settings, "min_velocity": 0.0})
        held = block_triangles(every, logs, folds)
    nb = res.base.n
    used = [k for k in range(folds) if np.any(S[k])]
    if len(used) < 2:
        raise IdentificationError("friction model auto: the data give fewer than 2 blocks")
    err = []
    for k in used:
        T = _triangle(np.vstack([S[i] for i in used if i != k]))
        p = np.linalg.lstsq(T[:nb, :nb], T[:nb, nb], rcond=None)[0]
        r = held[k] @ np.append(p, -1.0)
        err.append(float(r @ r) / max(res.rows, 1))
    err = np.array(err)
    return float(err.sum()), err


def friction_record(robot: Robot, *, record: dict | None = None) -> dict:
    """The JSON record of an identification's friction model: ``kind``, ``velocity`` (per slot,
    or None), ``chosen_by`` (``default``, ``given`` or ``held-out data``) and how (``record`` of
    :func:`select_friction_model`; None: the robot's own model, viscous and Coulomb by default)."""
    fm = robot.friction_model
    out = {
        "kind": fm["kind"],
        "velocity": [float(v) for v in fm["velocity"]] or None,
        "chosen_by": "default",
    }
    if record:
        out.update({k: v for k, v in record.items() if k not in out or k == "chosen_by"})
    return out


def friction_lines(robot: Robot, *, record: dict | None = None) -> list[str]:
    """The output lines that state the friction model and how it was chosen."""
    rec = friction_record(robot, record=record)
    formula = {
        "coulomb": "Fv v + Fc sign(v)",
        "asymmetric": "Fv v + Fc sign(v) + Fa |sign(v)|",
        "smooth": "Fv v + Fc tanh(v / w)",
        "stribeck": "Fv v + Fc sign(v) + Fs sign(v) exp(-(v / w)^2)",
    }[rec["kind"]]
    how = {"default": "the default", "given": "given"}.get(rec["chosen_by"], rec["chosen_by"])
    lines = [f"  friction model {rec['kind']}: {formula} per joint ({how})"]
    if rec["velocity"] is not None:
        what = "tanh width" if rec["kind"] == "smooth" else "Stribeck velocity"
        lines.append(
            f"    {what} w [rad/s | m/s]: "
            + " ".join(f"{v:.4g}" for v in rec["velocity"])
            + (f" ({rec['velocity_rule']})" if rec.get("velocity_rule") else "")
        )
    if rec.get("candidates"):
        lines.append(
            "    held-out residual per equation (weighted): "
            + ", ".join(f"{k} {v:.5g}" for k, v in rec["candidates"].items())
            + "; "
            + rec["rule"]
        )
    for k, why in (rec.get("not_identifiable") or {}).items():
        lines.append(f"    {k}: not identifiable here ({why})")
    return lines
