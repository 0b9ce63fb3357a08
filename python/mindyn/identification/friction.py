"""The friction model of an identification: given, derived from the data, or chosen on held-out
data.

The friction models (:attr:`mindyn.Robot.friction_model`), per slot with velocity ``v``:
``coulomb`` ``Fv v + Fc sign(v)``; ``asymmetric`` ``Fv v + Fc sign(v) + Fa |sign(v)|``;
``smooth`` ``Fv v + Fc tanh(v / w)``; ``stribeck`` ``Fv v + Fc sign(v) + Fs sign(v)
exp(-(v / w)^2)``; and, beside the core's models, ``dahl`` ``Fv v + Fc z`` with the presliding
state ``z`` of the Dahl model, ``dz/dq = sigma (1 - z sign(v))``, ``z`` in ``[-1, 1]``
(:class:`DahlBase`): rate-independent, so ``z`` is a function of the slot's position path,
integrated exactly sample by sample (:func:`dahl_state`), 0 at a log's start. At rest ``z``
keeps the value it had when the joint stopped: the torque held by stiction, which no function
of the velocity gives. ``sigma`` is the inverse of the presliding displacement; given it, the
regressor is linear in ``Fv`` and ``Fc`` (the Coulomb column is ``z`` instead of
``sign(v)``). The state follows the positions the regressor is evaluated on: the low-pass
filtered ones on preprocessed data, so position noise above the cut-off does not move it; below
the cut-off, a step smaller than the presliding displacement moves ``z`` only part of the way.
Dynamic model only (its state needs the samples in order). The simulation integrates the state
with the plant (:func:`mindyn.control.simulate` and :func:`~mindyn.control.simulate_inverse`,
``dahl_sigma``); generated code, the momentum observer and robot descriptions have no friction
state and refuse an identification with it.

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
  velocity is not resolved by the data; the dynamic and integral models: at least their
  ``min_velocity``, below which they have no equation) to its largest speed, then a
  golden-section search on ``log w`` between the grid neighbours of the best point, all joints
  at once (one fit per step: each joint's velocity changes only its own equations' friction
  column), the objective of joint ``j`` its residual in the first (ordinary least-squares) fit.
  The energy model has one equation for all joints: there the joints are searched one after
  the other on the overall residual.
- ``dahl``: ``sigma_j`` is found by the same search (:func:`dahl_search`) on a log-spaced grid
  from ``2 / r_j``, ``r_j`` the joint's range of motion in the fit logs (a longer presliding
  displacement never saturates: a spring over the whole motion), to ``1 / (w_j dt)``, ``w_j``
  the smooth width above (the speed below which the data do not tell the direction) and ``dt``
  the logged sample interval (a shorter one is covered within one sample at that speed: ``z``
  is ``sign(v)`` on the samples, the Coulomb model).

On the motor side (:attr:`~mindyn.Robot.drive_side`) each motor is a slot and its velocity
scale, ``sigma`` and the speeds above are in the motor's units (``v = t_k . dq``): its largest
speed is its own, a joint's noise level and ``min_velocity`` become the motor's through the
largest ``|T_kj|`` of its row (:func:`_in_slot_units`; ``|r|`` times the joint's for a motor that
drives one joint), and a width given is the motor's.
- ``auto``: the five models are fitted (the smooth width and the Stribeck velocities derived
  and searched on all fit logs as above) and each scored by cross-validation over contiguous
  time blocks of the fit logs (:func:`~mindyn.identification.prior.block_triangles`: each
  block's residual predicted by the estimate fitted on the other blocks, summed, every model
  weighted with the same per-joint weights, those of the Coulomb fit; every sample of a block
  scored, also those the dynamic and integral models leave out of the fit as slower than
  ``min_velocity``; each fold's fit decides its parameters as the fit does, by rank and RSD
  pruning, see :func:`held_out_residual`);
  the simplest model (in the order coulomb, smooth, asymmetric, stribeck, dahl: the stateful
  model last) whose summed held-out residual exceeds the smallest by at most one standard error
  of that excess wins (the one-standard-error rule on paired differences: the error from the
  spread of the model's block-by-block differences from the best model, since all models are
  scored on the same blocks and how hard a block is cancels). A model the data cannot
  identify (e.g. ``asymmetric`` with torque offsets, whose ``Fa`` is a constant torque whenever
  the joint moves) is reported and left out, and so is one whose fitted friction is not
  friction: a friction torque is dissipative, ``f(v) v >= 0`` at every speed, and a fit whose
  ``f(v) sign(v)`` is significantly negative at some speed (:func:`active_friction`, e.g. a
  Stribeck term ``Fs`` below ``-Fc``: friction pushing the joint along as it starts) fits
  something other than friction there (when every model's fit is such, none is left out: each
  is reported so, and the choice warned of).

The fit of a model given or the default is checked by the same rule
(:func:`dissipation_check`): the identification workflow records and warns of a fitted
friction that is not dissipative.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .. import _args
from ..base import BaseParameters
from ..robot import FRICTION_KINDS, Robot
from .errors import IdentificationError

#: The friction models, simplest first (a tie in the held-out residual goes to the simpler).
KINDS = ("coulomb", "smooth", "asymmetric", "stribeck", "dahl")

#: What ``--friction-model`` accepts.
CHOICES = (*FRICTION_KINDS, "dahl", "auto")


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


def _slots(robot: Robot) -> tuple[np.ndarray, str]:
    """The rows ``t_k`` of the friction slots (the transmission's ``T`` on the motor side, the
    identity otherwise; :attr:`~mindyn.Robot.drive_matrix`) and what a slot is ("joint",
    "motor")."""
    return np.asarray(robot.drive_matrix, float), (
        "motor" if robot.drive_side == "motor" else "joint"
    )


def _speeds(robot: Robot, logs) -> np.ndarray:
    """Each slot's largest speed in ``logs``: ``|t_k . dq|`` (the motor's on the motor side)."""
    return np.max(np.vstack([np.abs(robot.slot_velocities(d.dq)) for d in logs]), axis=0)


def _in_slot_units(robot: Robot, speed: np.ndarray) -> np.ndarray:
    """A per-joint speed (n,) as each slot's: ``max_j |T_kj| speed_j`` on the motor side (exact
    for a motor that drives one joint, ``|r| speed_j``; for a motor turning with several joints
    the largest of its joints' shares), ``speed`` itself otherwise. The friction models'
    velocity scales are in the slot's units: the motor's on the motor side."""
    T, _ = _slots(robot)
    return np.max(np.abs(T) * np.asarray(speed, float), axis=1)


def _never_moving(robot: Robot, speed: np.ndarray) -> str:
    """The slots (named "joint(s) 1, 3" or "motor(s) 'm2'") whose ``speed`` is not positive."""
    _, slot = _slots(robot)
    still = np.flatnonzero(~(speed > 0))
    if slot == "motor" and robot.transmission is not None:
        return "motor(s) " + ", ".join(f"'{robot.transmission.motors[k]}'" for k in still)
    return "joint(s) " + ", ".join(str(k + 1) for k in still)


def _noise_width(robot: Robot, logs) -> tuple[np.ndarray, str]:
    """Per slot, the speed below which the sign of its velocity is not determined by the data:
    the moving threshold of the error measures
    (:func:`~mindyn.identification.validation.moving_threshold`: 3 x the noise level of the
    joint's velocity as the fit uses it, at least 0.001 x the joint's largest speed), the
    largest over ``logs``, in the slot's units (:func:`_in_slot_units`); and the rule in
    words."""
    from .validation import logged_samples, moving_threshold

    # the logged samples carry the data path's noise level of the filtered velocity
    rules = [moving_threshold(logged_samples(d) or d) for d in logs]
    w = _in_slot_units(robot, np.max([w for w, _ in rules], axis=0))
    rule = rules[0][1]
    if _slots(robot)[1] == "motor":
        rule += "; a motor's: the largest |T_kj| times its joints' (the motor's units)"
    return w, rule


def _unresolved(robot: Robot, logs, width: np.ndarray) -> str:
    """Words on the slots whose given tanh ``width`` lies below the speed at which the data
    resolve the sign of their velocity (:func:`_noise_width`, the derived width), or ''."""
    floor = _noise_width(robot, logs)[0]
    low = np.flatnonzero(width < floor)
    if not low.size:
        return ""
    _, slot = _slots(robot)
    names = (
        [robot.transmission.motors[k] for k in low]
        if slot == "motor" and robot.transmission is not None
        else [str(k + 1) for k in low]
    )
    return (
        f"; below the speed at which the data resolve the sign for {slot}(s) "
        f"{', '.join(names)} ({' '.join(f'{floor[k]:.3g}' for k in low)}): tanh(v / w) is "
        "sign(v) there, the Coulomb model"
        + (" (a motor's width is in its units: |r| times a joint's)" if slot == "motor" else "")
    )


def smooth_width(robot: Robot, logs) -> tuple[np.ndarray, str]:
    """The smooth model's tanh width per slot of ``robot`` (the joints, or the motors on the
    motor side, in their units) from the velocities of ``logs`` (see the module
    documentation), and the rule in words."""
    w, rule = _noise_width(robot, logs)
    if not np.all(w > 0):
        raise IdentificationError(
            f"smooth friction: {_never_moving(robot, w)} never move in the fit data; their tanh "
            "width cannot be derived (give friction_width=, or leave out friction=True)"
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
    robot = base.robot
    top = _speeds(robot, logs)
    if not np.all(top > 0):
        raise IdentificationError(
            f"Stribeck friction: {_never_moving(robot, top)} never move in the fit data; their "
            "Stribeck velocity cannot be searched (leave out friction=True, or move them)"
        )
    # Below the velocity's noise level (the smooth width) the data do not resolve the velocity,
    # and the dynamic and integral models have no equation below their min_velocity (a joint
    # speed: in the slot's units as the noise level).
    floor = _noise_width(robot, logs)[0]
    if fit.get("model", "dynamic") in ("dynamic", "integral"):
        least = fit.get("min_velocity", _default("min_velocity"))
        floor = np.maximum(floor, _in_slot_units(robot, np.full(robot.n, least)))
    lo = np.log(np.minimum(floor, 0.5 * top))
    hi = np.log(top)
    x, record = _log_search(robot, lambda w: base.with_friction_velocity(w), lo, hi, logs, fit)
    record["search"] = (
        f"log-spaced grid of {GRID_POINTS} velocities from each joint's (on the motor side each "
        "motor's) velocity noise level "
        "(the smooth width rule; the dynamic and integral models: at least their min_velocity) "
        "to its "
        f"largest speed, then {GOLDEN_STEPS} golden-section steps on log velocity, "
        + record["search"]
    )
    return x, record


#: Most passes over the slots of a group acting on a joint in common (coordinate search).
SEARCH_PASSES = 3


def _groups(acts: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
    """The search's rounds and each slot's joints: ``acts`` (slots, joints) is True where slot
    k acts on joint j; slots acting on a joint in common, directly or through others, form a
    group. Round r holds the r-th slot of each group (so that the slots of a round act on
    disjoint joints), and row k of the second result marks the joints of slot k's group."""
    n = acts.shape[0]
    group = list(range(n))  # union-find over slots sharing a joint

    def root(k: int) -> int:
        while group[k] != k:
            k = group[k]
        return k

    for k in range(n):
        for m in range(k):
            if np.any(acts[k] & acts[m]):
                group[root(k)] = root(m)
    members: dict[int, list[int]] = {}
    for k in range(n):
        members.setdefault(root(k), []).append(k)
    depth = max(len(v) for v in members.values())
    rounds = [np.array([v[r] for v in members.values() if len(v) > r]) for r in range(depth)]
    joints = np.array([np.any(acts[members[root(k)]], axis=0) for k in range(n)])
    return rounds, joints


def _log_search(robot: Robot, make, lo, hi, logs, fit: dict) -> tuple[np.ndarray, dict]:
    """The scale per slot of ``robot`` (joint, or motor on the motor side) between ``exp(lo)``
    and ``exp(hi)`` (n,) minimising the fit's residual of the base set ``make(scale)``: a
    log-spaced grid of :data:`GRID_POINTS`, then :data:`GOLDEN_STEPS` golden-section steps
    between the grid neighbours of the best point; every slot at once, each on the residuals
    of the joints it acts on (the sum of their logarithms: a slot's scale changes only those
    joints' equations), except that slots acting on a joint in common (motors of a coupled
    wrist or a differential) are searched one after the other on their joints' residuals, the
    others held, in up to :data:`SEARCH_PASSES` passes (until a pass moves none by 1e-4 in log
    scale); or (the energy model) one slot at a time on the overall residual.
    ``(scale, record)``."""
    n = lo.shape[0]
    grid = np.linspace(lo, hi, GRID_POINTS)  # (G, n), log scales
    per_joint = fit.get("model", "dynamic") != "energy"
    evaluations = 0
    rounds, joints = _groups(np.abs(_slots(robot)[0]) > 0)
    passes = 0

    def f(logw: np.ndarray) -> np.ndarray:
        nonlocal evaluations
        evaluations += 1
        residual = _objective(make(np.exp(logw)), logs, fit, per_joint)
        if not per_joint:
            return residual
        return joints @ np.log(np.maximum(residual, 1e-300))  # per slot, its group's joints'

    if per_joint:
        x = grid[GRID_POINTS // 2].copy()
        while passes < (1 if len(rounds) == 1 else SEARCH_PASSES):
            passes += 1
            before = x.copy()
            for slots in rounds:
                values = []
                for g in grid:
                    y = x.copy()
                    y[slots] = g[slots]
                    values.append(f(y))
                best = np.zeros(n, dtype=int)
                best[slots] = np.argmin(np.array(values)[:, slots], axis=0)
                x[slots] = _golden(f, grid, best, slots, start=x)[slots]
            if np.max(np.abs(x - before)) < 1e-4:
                break
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
            "all slots at once, each on the residuals of the joints it acts on (first OLS fit)"
            + (
                ", slots acting on a joint in common one after the other on their joints' "
                f"residuals ({passes} passes)"
                if len(rounds) > 1
                else ""
            )
            if per_joint
            else "one slot at a time on the overall residual"
        ),
        "fits": evaluations,
        "range": [[float(a), float(b)] for a, b in zip(np.exp(lo), np.exp(hi))],
        "at_range_end": [
            bool(abs(v - a) < 1e-3 or abs(v - b) < 1e-3) for v, a, b in zip(x, lo, hi)
        ],
    }
    return np.exp(x), record


def dahl_search(base: DahlBase, logs, *, fit: dict) -> tuple[np.ndarray, dict]:
    """The Dahl ``sigma`` per joint minimising the fit's residual (see the module
    documentation): ``(sigma, record)``; ``base`` is a Dahl base set (its sigma is replaced)."""
    from .validation import logged_samples

    robot = base.robot
    T, _ = _slots(robot)
    span = np.max([np.ptp(d.q @ T.T, axis=0) for d in logs], axis=0)  # slot positions
    if not np.all(span > 0):
        raise IdentificationError(
            f"Dahl friction: {_never_moving(robot, span)} never move in the fit data; their "
            "presliding displacement cannot be searched (leave out friction=True, or move them)"
        )
    # The presliding displacement 1/sigma lies between the distance a joint travels in one
    # sample at the speed below which the data do not tell its direction (shorter: the state
    # is sign(dq) on the samples, the Coulomb model) and half its range of motion (longer: the
    # state never saturates, a spring over the whole motion).
    width = _noise_width(robot, logs)[0]  # in slot units
    dt = np.median(np.concatenate([np.diff((logged_samples(d) or d).t) for d in logs]))
    hi = np.log(1.0 / np.maximum(width * dt, 1e-300))
    lo = np.log(2.0 / span)
    hi = np.maximum(hi, lo + math.log(10.0))
    sigma, record = _log_search(robot, base.with_sigma, lo, hi, logs, fit)
    record["search"] = (
        f"log-spaced grid of {GRID_POINTS} values of sigma from 2 / each joint's (on the motor "
        "side each motor's) range of motion "
        "to 1 / (its velocity noise level (the smooth width rule) x the logged sample interval), "
        f"then {GOLDEN_STEPS} golden-section steps on log sigma, " + record["search"]
    )
    return sigma, record


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
    *,
    kind: str = "coulomb",
    rotor: bool = False,
    offset: bool = False,
    width=None,
    fit: dict | None = None,
    folds: int | None = None,
    progress=None,
    snap="auto",
) -> FrictionChoice:
    """The robot with the friction model ``kind`` (:data:`CHOICES`) for identifying it from
    ``logs`` with the :func:`~mindyn.identification.identify` options ``fit``, and the base set
    with friction (and ``rotor``, ``offset``) for it; see the module documentation for how
    the smooth width (unless ``width`` is given, one value or one per joint), the Stribeck
    velocities and ``auto`` are decided. ``snap``: as in :func:`mindyn.base_parameters`."""
    from ..base import base_parameters
    from .estimation import _logs
    from .prior import FOLDS

    _args.instance(robot, "robot", Robot)
    logs = _logs(logs, "logs", robot)
    _args.choice(kind, "kind", CHOICES)
    rotor, offset = _args.flag(rotor, "rotor"), _args.flag(offset, "offset")
    _args.optional(_args.mapping, fit, "fit")
    folds = _args.optional(_args.integer, folds, "folds", 2)
    _args.optional(_args.function, progress, "progress")
    fit = dict(fit or {})
    n = robot.n
    given_width = None
    if width is not None:
        if np.ndim(width) == 0:
            given_width = np.full(n, _args.number(width, "width", positive=True))
        else:
            given_width = _args.array(width, "width", (n,))
        if kind not in ("smooth", "auto"):
            raise _args.fail(
                "width",
                f"applies only with friction_model='smooth' or friction_model='auto' (kind "
                f"{kind!r})",
            )

    def make(k: str, velocity=None):
        r = robot.with_friction_model(k, velocity=velocity)
        return r, base_parameters(r, rotor=rotor, friction=True, offset=offset, snap=snap)

    def one(k: str) -> FrictionChoice:
        rec: dict = {"kind": k, "velocity": None}
        if k == "smooth":
            if given_width is not None:
                w, rule = given_width, "given" + _unresolved(robot, logs, given_width)
            else:
                w, rule = smooth_width(robot, logs)
            rec.update(velocity=[float(v) for v in w], velocity_rule=rule)
            r, b = make(k, w)
        elif k == "stribeck":
            r, b = make(k, _speeds(robot, logs).clip(min=1e-300))
            if progress is not None:
                progress("friction: searching the Stribeck velocities")
            w, search = stribeck_search(b, logs, fit=fit)
            b = b.with_friction_velocity(w)
            r = b.robot
            rec.update(
                velocity=[float(v) for v in w], velocity_rule=search["search"], search=search
            )
        elif k == "dahl":
            r, b = make("coulomb")
            if fit.get("model", "dynamic") != "dynamic":
                raise IdentificationError(
                    f"Dahl friction: only with the dynamic model (its state follows the "
                    f"positions sample by sample), not the {fit['model']} model"
                )
            b = dahl_base(b, 1.0)
            if progress is not None:
                progress("friction: searching the Dahl sigma (inverse presliding displacement)")
            sigma, search = dahl_search(b, logs, fit=fit)
            b = b.with_sigma(sigma)
            rec.update(sigma=[float(v) for v in sigma], sigma_rule=search["search"], search=search)
        else:
            r, b = make(k)
        return FrictionChoice(r, b, rec)

    if kind != "auto":
        out = one(kind)
        out.record["chosen_by"] = "default" if kind == "coulomb" else "given"
        return out
    folds = FOLDS if folds is None else folds
    choices, scores, per_fold, refused, active_fits = {}, {}, {}, {}, {}
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
        scores[k], per_fold[k] = held_out_residual(
            res, logs, folds=folds, joint_sigma=common, rank_tolerance=fit.get("rank_tolerance")
        )
        choices[k] = c
        active = active_friction(res, logs)
        if active:
            active_fits[k] = active
        if progress is not None:
            progress(f"friction: {k} held-out residual {scores[k]:.4g}")
    if len(active_fits) < len(scores):  # a fit that is not friction competes only with such
        for k in active_fits:
            del scores[k]
    if not scores:
        by_reason: dict[str, list[str]] = {}  # one reason once, with the models it refused
        for k, m in refused.items():
            by_reason.setdefault(m, []).append(k)
        if len(by_reason) == 1 and len(refused) > 1:
            why = f"every candidate, {', '.join(refused)}: {next(iter(by_reason))}"
        else:
            why = "; ".join(f"{', '.join(ks)}: {m}" for m, ks in by_reason.items())
        raise IdentificationError(
            f"friction model auto: no friction model can be identified from this data ({why})"
        )
    chosen, best, se = simplest_within_one_error(scores, per_fold)
    out = choices[chosen]
    out.record.update(
        chosen_by="held-out data",
        rule=(
            f"{folds}-fold cross-validation over contiguous time blocks of the fit logs (each "
            "block's residual predicted by the estimate fitted on the other blocks, summed, "
            "with the Coulomb fit's per-joint weights): the simplest model (coulomb, smooth, "
            "asymmetric, stribeck, dahl) whose excess over the smallest is within one standard "
            "error of that excess (from its fold-by-fold differences), among those whose fitted "
            "friction is dissipative"
        ),
        smallest=best,
        standard_error={k: se[k] for k in scores},
        candidates={k: float(v) for k, v in scores.items()},
        candidates_per_fold={k: [float(x) for x in v] for k, v in per_fold.items()},
        candidates_unit="weighted residual per equation",
        not_identifiable=refused,
        not_dissipative=active_fits,
        warning=None,  # the chosen fit is checked as a given model's (dissipation_check)
    )
    return out


def simplest_within_one_error(scores: dict, per_fold: dict) -> tuple[str, str, dict]:
    """The one-standard-error rule on paired differences
    (:func:`~mindyn.identification.held_out.within_one_error`) over the friction models, the
    simplest first (order of :data:`KINDS`): ``scores`` (model -> summed held-out residual)
    and ``per_fold`` (model -> its residual per block, the same blocks for every model).
    Returns ``(chosen, best, se)``."""
    from .held_out import within_one_error

    return within_one_error(scores, per_fold, order=KINDS)


#: A fitted friction torque counts as pushing a slot along its motion when ``f(v) sign(v)`` is
#: below zero by more than this many of its standard deviations (about 98 % one-sided).
ACTIVE_SIGMAS = 2.0


#: The default and given friction models' fits are warned of (:func:`dissipation_check`) only
#: where the friction that drives the motion is material: on some joint at least this share of
#: that joint's RMS torque in the fit logs (a slot whose fitted friction is close to zero, e.g.
#: a motor's behind a joint torque sensor, crosses zero by a few standard deviations, which
#: changes no torque the model predicts).
MATERIAL_SHARE = 0.01


def active_friction(
    res, logs, *, material: float | None = None, sigmas: float = ACTIVE_SIGMAS
) -> str | None:
    """Why the friction fitted in ``res`` is not friction, or None: a friction torque is
    dissipative, ``f(v) v >= 0`` at every speed; the slots whose fitted ``f(v) sign(v)`` is
    below zero by more than :data:`ACTIVE_SIGMAS` standard deviations (the parameters' standard
    deviations of the fit, taken as independent; of a pruned fit each the larger of the pruned
    one and that of the fit with every base parameter, ``res.initial["std"]``, since the pruned
    one assumes the removed parameters zero) at some speed from just above zero to the
    largest of ``logs``, either way (the steady friction of the Dahl model: ``sign(v)`` for
    its state). The slots are named as the joints or, on the motor side, the motors they are,
    each with the first speed found and its value. ``sigmas``: that many standard deviations
    instead of :data:`ACTIVE_SIGMAS`. ``material``: a slot counts only where its
    most negative such value, as it acts on the joints (``T^T`` on the motor side), is at least
    this share of some joint's RMS torque in ``logs``."""
    base = res.base
    if not base.friction:
        return None
    robot = base.robot
    names = list(base.names)
    std = dict(zip(res.names, np.asarray(res.std, float)))
    free = dict(zip(names, np.asarray(res.initial.get("std", []), float)))
    std = {nm: max(s, free.get(nm, 0.0)) for nm, s in std.items()}
    classical = robot.parameter_names(rotor=False, friction=True)[10 : robot.layout_sizes[2]]
    kinds = [nm.rstrip("0123456789") for nm in classical]
    top = np.max(np.vstack([np.abs(robot.slot_velocities(d.dq)) for d in logs]), axis=0)
    speeds = np.geomspace(1e-9, 1.0, 40)[:, None] * np.maximum(top, 1e-300)  # (S, n)
    phis = {sgn: robot.friction_shapes(sgn * speeds) for sgn in (1.0, -1.0)}  # (S, n, c)
    slot = "motor" if robot.drive_side == "motor" else "joint"
    if material is not None:
        acts = (
            np.abs(np.asarray(robot.transmission.T, float))
            if robot.drive_side == "motor" and robot.transmission is not None
            else np.eye(robot.n)
        )
        rms = np.sqrt(np.mean(np.vstack([d.tau for d in logs]) ** 2, axis=0))
    bad = []
    for k in range(robot.n):
        for sgn, phi in phis.items():
            value = np.zeros(speeds.shape[0])
            var = np.zeros(speeds.shape[0])
            for i, kind in enumerate(kinds):
                nm = f"{kind}{k + 1}"
                if nm in names:
                    col = sgn * phi[:, k, i]
                    value += col * res.full[names.index(nm)]
                    var += (col * std.get(nm, 0.0)) ** 2
            low = value < -sigmas * np.sqrt(var)
            if np.any(low) and material is not None:
                worst = -float(value[low].min())  # the most negative value found
                if not np.any(worst * acts[k] >= material * rms):
                    continue  # immaterial: changes no torque the model predicts
            if np.any(low):
                at = int(np.argmax(low))
                bad.append(
                    f"{slot} {k + 1} at v = {sgn * speeds[at, k]:.3g}: f(v) sign(v) = "
                    f"{value[at]:.3g} +- {math.sqrt(var[at]):.2g}"
                )
                break
    if not bad:
        return None
    return (
        "the fitted friction drives the motion (f(v) v < 0 beyond "
        f"{sigmas:.3g} standard deviations): " + "; ".join(bad)
    )


def _remedy(kind: str) -> str:
    """What to try when the fitted friction of the model ``kind`` is not dissipative."""
    if kind == "stribeck":
        return "friction_model='auto' leaves out a model whose fitted friction is not friction"
    return (
        "for a Stribeck-shaped friction (breakaway above the Coulomb level) try "
        "friction_model='stribeck' or 'auto'"
    )


def dissipation_check(res, logs, *, kind: str, auto: bool = False) -> dict:
    """The fit ``res`` of a friction model given or the default (``kind``; ``auto`` checks each
    of its candidates itself) checked by :func:`active_friction` on its fit logs ``logs``, where
    material (:data:`MATERIAL_SHARE` of a joint's RMS torque) and beyond the standard
    deviations that hold the chance of a false warning over all ``2 n`` slots and directions
    to that of one :data:`ACTIVE_SIGMAS` test (Bonferroni: 2.94 for 7 slots):
    ``{"not_dissipative": {kind: why} (empty when dissipative), "warning": one line or
    None}``, the warning naming the joints or motors, the speed and value found, and what to
    try. ``auto``: ``kind`` is the model ``friction_model='auto'`` chose (which it left in as
    every candidate's fit drives the motion): ``{"warning": ...}`` alone."""
    from scipy.stats import norm

    # one test per slot and direction: each at the level of one ACTIVE_SIGMAS test over all
    n = res.base.robot.n
    sigmas = float(norm.isf(norm.sf(ACTIVE_SIGMAS) / (2 * n)))
    why = active_friction(res, logs, material=MATERIAL_SHARE, sigmas=sigmas)
    if auto:  # the candidates were checked at ACTIVE_SIGMAS: their record stays
        return {
            "warning": None
            if why is None
            else f"friction model auto, {kind}: {why} (every candidate's fit drives the motion "
            f"beyond {ACTIVE_SIGMAS:g} standard deviations: none was left out)"
        }
    if why is None:
        return {"not_dissipative": {}, "warning": None}
    return {
        "not_dissipative": {kind: why},
        "warning": f"friction model {kind}: {why}; {_remedy(kind)}",
    }


def held_out_residual(
    res, logs, *, folds: int, joint_sigma=None, rank_tolerance: float | None = None
) -> tuple[float, np.ndarray]:
    """The summed held-out residual per equation of the fit ``res`` over ``folds`` contiguous
    blocks of ``logs`` and each block's share, ``(total, per block)``, each fold's fit pruned
    at the fit's own threshold: :func:`~mindyn.identification.held_out.held_out_residuals`
    (which see) with that one threshold."""
    from .held_out import held_out_residuals

    return held_out_residuals(
        res,
        logs,
        folds=folds,
        thresholds=[res.settings.get("rsd_threshold")],
        joint_sigma=joint_sigma,
        rank_tolerance=rank_tolerance,
        what="friction model auto",
    )[0]


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
        if record.get("kind") == "dahl":  # the core's coulomb model, its Coulomb column z
            out["kind"] = "dahl"
    return out


def friction_lines(robot: Robot, *, record: dict | None = None) -> list[str]:
    """The output lines that state the friction model and how it was chosen."""
    rec = friction_record(robot, record=record)
    formula = {
        "coulomb": "Fv v + Fc sign(v)",
        "asymmetric": "Fv v + Fc sign(v) + Fa |sign(v)|",
        "smooth": "Fv v + Fc tanh(v / w)",
        "stribeck": "Fv v + Fc sign(v) + Fs sign(v) exp(-(v / w)^2)",
        "dahl": "Fv v + Fc z, dz/dq = sigma (1 - z sign(v)), z = 0 at a log's start",
    }[rec["kind"]]
    how = {"default": "the default", "given": "given"}.get(rec["chosen_by"], rec["chosen_by"])
    slot = _slots(robot)[1]
    lines = [f"  friction model {rec['kind']}: {formula} per {slot} ({how})"]
    if rec["velocity"] is not None:
        what = "tanh width" if rec["kind"] == "smooth" else "Stribeck velocity"
        unit = "[rad/s | m/s of the motor]" if slot == "motor" else "[rad/s | m/s]"
        lines.append(
            f"    {what} w {unit}: "
            + " ".join(f"{v:.4g}" for v in rec["velocity"])
            + (f" ({rec['velocity_rule']})" if rec.get("velocity_rule") else "")
        )
    if rec.get("sigma") is not None:
        lines.append(
            "    Dahl sigma [1/rad | 1/m of the slot's position, the motor's on the motor side] "
            "(1 / presliding displacement): "
            + " ".join(f"{v:.4g}" for v in rec["sigma"])
            + f" ({rec['sigma_rule']}; the state follows the low-pass filtered positions)"
        )
    if rec.get("candidates"):
        lines.append(
            "    held-out residual per equation (weighted): "
            + ", ".join(f"{k} {v:.5g}" for k, v in rec["candidates"].items())
            + "; "
            + rec["rule"]
        )
        se, best = rec.get("standard_error"), rec.get("smallest")
        if se and best in rec["candidates"] and len(rec["candidates"]) > 1:
            top = rec["candidates"][best]
            lines.append(
                f"    excess over the smallest ({best}) and its standard error: "
                + ", ".join(
                    f"{k} {v - top:.3g} (se {se[k]:.3g})"
                    for k, v in rec["candidates"].items()
                    if k != best and k in se
                )
            )
    for k, why in (rec.get("not_identifiable") or {}).items():
        lines.append(f"    {k}: not identifiable here ({why})")
    if rec["chosen_by"] == "held-out data":
        for k, why in (rec.get("not_dissipative") or {}).items():
            kept = k in rec["candidates"]
            how = "not left out (every candidate's fit is such)" if kept else "left out"
            lines.append(f"    {k}: {how}, not friction here ({why})")
    if rec.get("warning"):
        lines.append(f"  WARNING: {rec['warning']}")
    return lines


# ---------------------------------------------------------------------------------------------
# The Dahl model: a presliding state per joint that follows the positions.


def dahl_state(q, sigma, *, z0=None) -> np.ndarray:
    """The Dahl state ``z`` (m, n) of the position path ``q`` (m, n): ``dz/dq_j = sigma_j (1 -
    z_j sign(dq_j))``, ``z(0) = z0`` (default 0), integrated exactly between consecutive
    samples with the joint moving one way: over a run of steps of sign ``s``,
    ``z = s + (z_a - s) exp(-sigma sum |dq|)`` from the run's first state ``z_a`` (a step that
    does not move keeps ``z``). Rate-independent: ``z`` is a function of the path only; it
    stays in ``[-1, 1]`` from a start in it."""
    q = np.asarray(q, dtype=float)
    if q.ndim == 1:
        q = q[None, :]
    m, n = q.shape
    sigma = np.broadcast_to(np.asarray(sigma, float), (n,))
    start = np.zeros(n) if z0 is None else np.broadcast_to(np.asarray(z0, float), (n,))
    z = np.empty_like(q)
    if m == 0:
        return z
    z[0] = start
    step = np.diff(q, axis=0)
    for j in range(n):
        s = np.sign(step[:, j])
        # a step that does not move takes the sign of the last that did (its factor is 1)
        last = np.maximum.accumulate(np.where(s != 0, np.arange(s.size), 0))
        run = s[last] if s.size else s
        run = np.where(run == 0, 1.0, run)
        travel = sigma[j] * np.abs(step[:, j])
        cuts = np.flatnonzero(np.diff(run)) + 1
        zc = start[j]
        for a, b in zip(np.r_[0, cuts], np.r_[cuts, s.size]):
            seg = run[a] + (zc - run[a]) * np.exp(-np.cumsum(travel[a:b]))
            z[a + 1 : b + 1, j] = seg
            zc = seg[-1]
    return z


def _path(q: np.ndarray) -> tuple[np.ndarray, int]:
    """The whole position path a block of rows ``q`` was cut from (a view of rows of a 2-D
    array, as the data path evaluates the regressor block by block) and the block's first row in
    it; ``(q, 0)`` when ``q`` is not such a view."""
    parent = q.base
    if (
        isinstance(parent, np.ndarray)
        and parent.ndim == 2
        and parent.shape[1] == q.shape[1]
        and parent.flags.c_contiguous
        and q.strides == parent.strides
    ):
        offset = q.__array_interface__["data"][0] - parent.__array_interface__["data"][0]
        row, rest = divmod(offset, parent.strides[0])
        if rest == 0 and 0 <= row and row + q.shape[0] <= parent.shape[0]:
            return parent, int(row)
    return q, 0


class DahlBase(BaseParameters):
    """A base set with viscous and Coulomb friction whose Coulomb column is the Dahl state
    instead of ``sign(v_k)``: slot ``k``'s friction is ``Fv_k v_k + Fc_k z_k`` with ``z_k``
    the :func:`dahl_state` of its position path (the joint's, or on the motor side motor
    ``k``'s ``t_k . q``) at ``sigma_k`` (the inverse presliding displacement [1/rad | 1/m] of
    the slot's position); on the motor side it reaches joint ``j`` times ``T[k, j]``. The
    regressor of a block of samples takes ``z`` from the whole path the block belongs to (a
    view of a larger array: the data path's blocks), else from the block's own path, starting
    at rest (``z = 0``) at its first sample."""

    def __init__(self, base: BaseParameters, sigma):
        super().__init__(base._b, base.robot, base.offset, base.options)
        self.method_reason = base.method_reason
        # the same base set, snapped the same way: the JSON records it, predict forms it again
        self._snap_decision = base._snap_decision
        n = base.robot.n
        self.sigma = np.broadcast_to(np.asarray(sigma, dtype=float), (n,)).copy()
        if not np.all(np.isfinite(self.sigma) & (self.sigma > 0)):
            raise IdentificationError("Dahl friction: sigma must be positive per joint")
        names = list(base.names)
        self._fc = [(j, names.index(f"Fc{j + 1}")) for j in range(n) if f"Fc{j + 1}" in names]
        self._paths: dict = {}
        # the Dahl sets of one base set differ in their Coulomb columns only
        root = base._family[0] if base._family and base._family[1] == "dahl" else base
        self._family = (root, "dahl")

    def _varied(self) -> list[tuple[int, int, int]]:
        """The Coulomb columns, the Dahl states: ``(base column, slot, 1)`` each."""
        return [(c, k, 1) for k, c in self._fc]

    def _varied_regressor(self, q, dq, ddq) -> np.ndarray:
        """The Coulomb columns of :meth:`regressor` alone (the Dahl state of each slot times
        its row of the drive matrix)."""
        q = np.asarray(q, dtype=float)
        z = self.state(q)
        T = self.robot.drive_matrix
        out = np.empty((q.shape[0], self.robot.n, len(self._fc)))
        for c, (k, _) in enumerate(self._fc):
            out[:, :, c] = z[:, k, None] * T[k]
        return out

    def with_sigma(self, sigma) -> DahlBase:
        """The same base set at another ``sigma`` (n,)."""
        return DahlBase(self, sigma)

    def state(self, q) -> np.ndarray:
        """The Dahl state of each slot at the joint positions ``q`` (m, n) (see the class
        documentation)."""
        path, row = _path(q)
        key = id(path)
        hit = self._paths.get(key)
        if hit is None or hit[0] is not path or hit[1].shape[0] != path.shape[0]:
            robot = self.robot
            slots = path if robot.drive_side != "motor" else path @ robot.drive_matrix.T
            hit = (path, dahl_state(slots, self.sigma))
            self._paths = {key: hit}  # the last path only: the data path goes block by block
        return hit[1][row : row + q.shape[0]]

    def regressor(self, q, dq, ddq) -> np.ndarray:
        if np.ndim(q) == 1:
            raise IdentificationError(
                "Dahl friction: its state follows the positions of a path, shape (m, n); one "
                "sample has none (a controller or observer step keeps no Dahl state)"
            )
        W = super().regressor(q, dq, ddq)
        q = np.asarray(q, dtype=float)
        T = self.robot.drive_matrix  # slot k's Coulomb torque reaches joint j times T[k, j]
        z = self.state(q)
        for k, c in self._fc:
            W[:, :, c] = z[:, k, None] * T[k]
        return W


def dahl_base(base: BaseParameters, sigma) -> DahlBase:
    """The Dahl base set of ``base`` (viscous and Coulomb friction on the joints) at ``sigma``
    (n,); IdentificationError for a base set it cannot be (no friction, another friction
    model)."""
    if not base.friction:
        raise IdentificationError(
            "Dahl friction: expected a base set with friction (friction=True)"
        )
    if base.robot.friction_model["kind"] != "coulomb":
        raise IdentificationError(
            "Dahl friction replaces the Coulomb column of the coulomb model; "
            f"not of the {base.robot.friction_model['kind']} model"
        )
    return DahlBase(base, sigma)
