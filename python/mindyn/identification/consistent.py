"""Physically consistent estimation of the classical parameters, and payload identification.

Consistent estimate (:func:`identify_consistent`, :func:`consistent_estimate`): the classical
parameters ``pi`` (per link ``XX XY XZ YY YZ ZZ MX MY MZ M`` about the link-frame origin, then
``Ia``, ``Fv``, ``Fc`` per joint and ``Off`` per joint as the base set has them) minimising the
residual of the unconstrained estimate's own least-squares problem -- same model, same equations,
same row weights -- through the base parameters ``p_b = Y pi``, subject to

- every link's pseudo-inertia ``J = [[tr(I)/2 1 - I, h], [h^T, m]]`` positive semidefinite (mass
  ``m >= 0``, inertia about the centre of mass positive semidefinite and the triangle
  inequalities of its principal moments);
- ``Ia >= 0``, ``Fv >= 0``, ``Fc >= 0`` (offsets are free), and the friction dissipative under
  the robot's friction model (``f(v) v >= 0`` at every speed): ``Fc + Fs >= 0`` (Stribeck:
  the breakaway torque), ``Fc - Fa >= 0`` and ``Fc + Fa >= 0`` (asymmetric: the Coulomb torque
  each way). These joint-term constraints are the rows of ``B e >= 0`` (:class:`_Layout`).

The residual is taken from the ``c x c`` triangle the estimation reduced the (weighted) system to,
``|A p_b - b|^2 = |R p_b - z|^2 + rho``, so the convex problem is small whatever the length of
the log. Without a prior it is solved with cvxpy (Clarabel; SCS if Clarabel fails, reported);
with the description's log-det prior, whose weight is chosen from the data by default
(:mod:`~mindyn.identification.prior`), by a damped Newton descent (the cone solver as
fallback). The fit term is measured in units of the noise variance ``s^2``: the residual
variance of the unconstrained fit with all base parameters times the factor that accounts for
the correlation of filtered samples (the estimate's standard deviations carry the same,
``settings.std_correlation``), ``|R p_b - z|^2 / s^2``: it grows by about 1 per standard
deviation that the base parameters move along any one direction of the estimate's
uncertainty.

Payload (:func:`identify_payload`): the 10 inertial parameters of a body fixed to the last link,
from ``tau - tau_arm(q, dq, ddq) = W_last(q, dq, ddq) phi`` with the identified arm's torques
``tau_arm`` and the last link's 10 classical regressor columns ``W_last``.
"""

from __future__ import annotations

import contextlib
import inspect
import math
import numbers
import re
import time
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

import numpy as np
import scipy.linalg as sla

from .. import _args
from .._core import ModelError
from ..base import BaseParameters
from ..robot import Robot, load, pseudo_inertia
from .data import DataError, read_json
from .document import (
    check_identified_model,
    check_identified_robot,
    identified_base,
    names_difference,
    read_identification,
)
from .errors import IdentificationError
from .estimation import (
    IdentificationResult,
    _logs,
    _Reduced,
    correlation_factor,
    identify,
    joint_weights,
    noise_variance_factor,
    predicted_torques,
    regressor_rows,
)
from .joint_data import JointData
from .models import moving_equations, require_torque

__all__ = [
    "ConsistentResult",
    "PayloadResult",
    "consistent_estimate",
    "identify_consistent",
    "identify_payload",
    "inertial_from_pseudo",
    "pseudo_inertia",
]

#: Smallest eigenvalue of a link's pseudo-inertia accepted as positive semidefinite, in kg (its
#: entries in kg, kg m and kg m^2, lengths in metres).
EIG_TOL = 1e-9

#: Without a prior, the classical parameters the data do not determine (the null space of the
#: regrouping ``Y``) are chosen nearest the description (Euclidean norm, masses in units of the
#: description's mean link mass). When the unconstrained optimum has no consistent realisation,
#: the constrained optimum may only be approached as some masses grow without bound (a larger
#: mass lets the link carry larger first moments; the fit gains ever less): so the estimate is the
#: one nearest the description among those whose fit term is within this many noise variances of
#: the optimum (statistically indistinguishable from it: a tenth of a standard deviation along
#: any one direction would cost 0.01). A first solve finds the optimum, carrying the same
#: distance with weight :data:`NULL_SPACE_WEIGHT` to keep it bounded; a second one the estimate.
TIE_BREAK_SLACK = 1.0
NULL_SPACE_WEIGHT = 1e-6

#: A description link whose pseudo-inertia ``J0`` has an eigenvalue below this fraction of the
#: mean link mass ``eps`` (kg; singular, nearly singular or indefinite) enters the log-det prior as
#: its projection onto the positive semidefinite matrices plus ``eps`` times the identity (noted
#: in the result).
PRIOR_REGULARISATION = 1e-3

#: Largest prior weight accepted: the prior then counts a million times the fit, which leaves
#: the description's values; beyond it the conic solvers fail or return inaccurate answers
#: (Clarabel panics at 1e200, SCS returned a mass of 2e5 kg at 1e9).
MAX_PRIOR_WEIGHT = 1e6

INERTIAL = ("XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M")
_NAME = re.compile(r"([A-Za-z]+?)([0-9]+)")


def _name_kind(name: str) -> str:
    """The kind of a classical parameter name: ``Ia`` of ``Ia3``."""
    m = _NAME.fullmatch(name)
    assert m is not None, name  # a kind and a joint number
    return m.group(1)


# ---------------------------------------------------------------------------------------------
# Pseudo-inertia
# ---------------------------------------------------------------------------------------------
def inertial_from_pseudo(J) -> np.ndarray:
    """The 10 inertial parameters of a pseudo-inertia (inverse of :func:`pseudo_inertia`):
    ``I = tr(S) 1 - S`` for its upper-left block ``S``."""
    J = _args.array(J, "J", (4, 4))
    J = 0.5 * (np.asarray(J, dtype=float) + np.asarray(J, dtype=float).T)
    inertia = np.trace(J[:3, :3]) * np.eye(3) - J[:3, :3]
    return np.array(
        [
            inertia[0, 0],
            inertia[0, 1],
            inertia[0, 2],
            inertia[1, 1],
            inertia[1, 2],
            inertia[2, 2],
            J[0, 3],
            J[1, 3],
            J[2, 3],
            J[3, 3],
        ]
    )


def _pseudo_map() -> np.ndarray:
    """``G`` (10, 16) with ``inertial_from_pseudo(J) = G @ J.ravel()`` for symmetric ``J``
    (symmetric pairs of entries weighted half each)."""
    G = np.zeros((10, 16))
    for k in range(16):
        E = np.zeros(16)
        E[k] = 1.0
        G[:, k] = inertial_from_pseudo(E.reshape(4, 4))
    return G


def body_quantities(p) -> dict:
    """Mass, centre of mass and inertia about it (``XX XY XZ YY YZ ZZ``) of 10 inertial
    parameters about a frame's origin: ``I_O = I_C + m (|c|^2 1 - c c^T)``."""
    p = np.asarray(p, dtype=float)
    m = p[9]
    c = p[6:9] / m if m != 0 else np.full(3, np.nan)
    S = pseudo_inertia(p)[:3, :3]
    inertia_o = np.trace(S) * np.eye(3) - S
    ic = inertia_o - m * (c @ c * np.eye(3) - np.outer(c, c))
    return {"mass": m, "com": c, "inertia_com": ic[np.triu_indices(3)]}


def min_eigenvalues(pi: np.ndarray, layout: _Layout) -> np.ndarray:
    """Smallest eigenvalue of each link's pseudo-inertia, shape (n,) [kg]."""
    return np.array([np.linalg.eigvalsh(pseudo_inertia(pi[ix]))[0] for ix in layout.links])


class _Layout:
    """Indices of a base set's classical vector: the 10 inertial parameters of each link, and
    the rotor, friction and offset parameters (``extra``, the joint terms ``e = pi[extra]``),
    with their constraints ``B e >= 0`` (``B`` (c, len(extra))): ``Ia, Fv, Fc >= 0`` (the rows
    of ``nonneg``), ``Fc + Fs >= 0`` and ``Fc -+ Fa >= 0`` (the friction dissipative)."""

    def __init__(self, base: BaseParameters):
        names = base.classical_names
        self.names = names
        n = base.robot.n
        where = {nm: i for i, nm in enumerate(names)}
        self.links = [np.array([where[f"{k}{j + 1}"] for k in INERTIAL]) for j in range(n)]
        inertial = set(np.concatenate(self.links).tolist())
        self.extra = np.array([i for i in range(len(names)) if i not in inertial], dtype=int)
        kinds = [_name_kind(names[i]) for i in self.extra]
        self.nonneg = np.array([k in ("Ia", "Fv", "Fc") for k in kinds], dtype=bool)
        rows = [np.eye(len(kinds))[i] for i in np.flatnonzero(self.nonneg)]
        at = {names[i]: a for a, i in enumerate(self.extra)}
        #: (kind, index of Fc, index of the third term) in pi: each third friction term
        self.pairs = [
            (_name_kind(name), int(self.extra[at["Fc" + name[2:]]]), int(self.extra[a]))
            for name, a in at.items()
            if _name_kind(name) in ("Fs", "Fa") and "Fc" + name[2:] in at
        ]
        inside = {int(i): a for a, i in enumerate(self.extra)}
        for kind, fc, third in self.pairs:
            for sign in (1.0,) if kind == "Fs" else (1.0, -1.0):
                row = np.zeros(len(kinds))
                row[inside[fc]], row[inside[third]] = 1.0, sign
                rows.append(row)
        self.B = np.array(rows, dtype=float).reshape(len(rows), len(kinds))
        self.robot_params = len(names) - (n if base.offset else 0)

    def satisfied(self, pi: np.ndarray, tol: float = 0.0) -> bool:
        """Whether the joint terms of ``pi`` meet ``B e >= -tol``."""
        return bool(np.all(self.B @ pi[self.extra] >= -tol))

    def project(self, pi: np.ndarray) -> None:
        """Moves the joint terms of ``pi`` (in place) onto their constraints: ``Ia, Fv, Fc``
        clipped at zero, then ``Fs`` raised to ``-Fc`` and ``Fa`` clipped to ``[-Fc, Fc]``
        (solver tolerance)."""
        nonneg = self.extra[self.nonneg]
        pi[nonneg] = np.maximum(pi[nonneg], 0.0)
        for kind, fc, third in self.pairs:
            lo, hi = -pi[fc], (np.inf if kind == "Fs" else pi[fc])
            pi[third] = min(max(pi[third], lo), hi)


# ---------------------------------------------------------------------------------------------
# Consistent estimate
# ---------------------------------------------------------------------------------------------
@dataclass
class ConsistentResult:
    """A physically consistent estimate beside the unconstrained one it was computed from.

    Attributes
    ----------
    base : BaseParameters
    classical : ndarray, shape (P,)
        The classical parameters, names ``classical_names`` (``base.classical_names``).
    full : ndarray, shape (nb,)
        Their base parameters ``Y @ classical`` (use with ``base.regressor``, :meth:`predict`).
    unconstrained : IdentificationResult
    min_eig, unconstrained_min_eig : ndarray (n,)
        Smallest eigenvalue of each link's pseudo-inertia [kg] of this estimate, and of a
        classical realisation of the unconstrained estimate: a consistent one when it has one
        (found without a prior, the estimate then being that realisation), else the one nearest
        to the description (``pi0 + Y^+ (p_b - Y pi0)``, least change in the Euclidean norm).
    solver, status : str
        ``CLARABEL`` or ``SCS`` (``none`` when the unconstrained optimum is itself consistent and
        is returned as it is), and the solver's status.
    fit_increase : float
        ``(|R p_b - z|^2 - |R p_b_ls - z|^2) / s^2``: how much worse the consistent estimate fits
        than the unconstrained one with all base parameters, in units of the noise variance.
    links : tuple of mappings, optional
        With a prior, per link: its mass, the mass's standard deviation, and whether the data or
        the prior determine it (:func:`~mindyn.identification.prior.link_report`); else None.
    notes : tuple of str
        What the estimate's computation took or met, one line each.

    The arrays (``classical``, ``full``, ``min_eig``, ``unconstrained_min_eig``) are read-only
    copies, as an :class:`IdentificationResult`'s: assigning to an entry raises ``ValueError``;
    ``links`` (each link's record a read-only view) and ``notes`` are tuples (``to_dict()``
    writes them as lists and dicts).
    """

    model: str
    base: BaseParameters
    classical: np.ndarray
    full: np.ndarray
    unconstrained: IdentificationResult
    min_eig: np.ndarray
    unconstrained_min_eig: np.ndarray
    prior_weight: float
    solver: str
    status: str
    fit_increase: float
    prior_divergence: float | None = None
    #: How the prior's weight was chosen (None: given): see
    #: :func:`~mindyn.identification.prior.choose_prior_weight`.
    weight_choice: dict | None = None
    #: Per link (with a prior): mass, its standard deviation, and whether the data or the prior
    #: determine it (:func:`~mindyn.identification.prior.link_report`).
    links: tuple[Mapping, ...] | None = None
    #: Where consistency costs the fit: the least increase of any consistent estimate and the
    #: part each link's constraint accounts for
    #: (:func:`~mindyn.identification.constraint_cost.constraint_costs`).
    constraint_cost: dict | None = None
    #: The fit term's noise variance as a factor on the residual variance (:func:`noise_scale`).
    noise: dict = field(default_factory=dict)
    #: Without a prior, when the estimate was taken nearest the description among those within
    #: :data:`TIE_BREAK_SLACK` noise variances of the optimum's fit: ``slack`` and the optimum's
    #: own ``optimum_fit_increase`` (its ``fit_increase`` then lies between the two sums);
    #: None when that path was not taken.
    tie_break: dict | None = None
    notes: tuple[str, ...] = ()
    seconds: float = 0.0

    def __post_init__(self):
        # as an IdentificationResult's: the arrays read-only copies and the lists tuples (an
        # entry assigned, or a note added, would change the estimate under its other users)
        for name in ("classical", "full", "min_eig", "unconstrained_min_eig"):
            setattr(self, name, _args.readonly(getattr(self, name)))
        if self.links is not None:
            self.links = tuple(MappingProxyType(dict(lk)) for lk in self.links)
        self.notes = tuple(self.notes)

    @property
    def classical_names(self) -> list[str]:
        return list(self.base.classical_names)

    @property
    def link_names(self) -> list[str]:
        return list(self.base.robot.link_names[1:])

    @property
    def robot_params(self) -> np.ndarray:
        """The classical vector without offsets, in the layout ``Robot`` methods take."""
        return _args.readonly(self.classical[: _Layout(self.base).robot_params])

    @property
    def total_mass(self) -> float:
        return float(sum(self.classical[ix[9]] for ix in _Layout(self.base).links))

    def violating_links(self, *, unconstrained: bool = True) -> list[str]:
        eig = self.unconstrained_min_eig if unconstrained else self.min_eig
        return [nm for nm, e in zip(self.link_names, eig) if e < -EIG_TOL]

    def predict(self, data: JointData) -> np.ndarray:
        """Joint torques of the consistent estimate on ``data``, shape (m, n)
        (:func:`~mindyn.identification.estimation.predicted_torques`)."""
        return predicted_torques(self.base, self.full, data)

    def mass_matrix_min_eig(self, data) -> float:
        """Smallest eigenvalue of the joint-space inertia ``A(q)`` of the identified classical
        parameters over every sample of ``data`` (one log or several)."""
        robot = self.base.robot
        low = math.inf
        for d in _logs(data):
            for a in range(0, d.m, 8192):
                A = robot.mass_matrix(d.q[a : a + 8192], self.robot_params)
                low = min(low, float(np.linalg.eigvalsh(A)[:, 0].min()))
        return low

    def to_dict(self) -> dict:
        """The JSON fields of a consistent estimate (``classical`` and ``pseudo_inertia_min_eig``
        as name -> value maps)."""
        return {
            "consistent": True,
            "classical": {nm: float(v) for nm, v in zip(self.classical_names, self.classical)},
            "pseudo_inertia_min_eig": {
                nm: float(v) for nm, v in zip(self.link_names, self.min_eig)
            },
            "total_mass": self.total_mass,
            "consistent_estimate": {
                "solver": self.solver,
                "status": self.status,
                "seconds": self.seconds,
                "prior_weight": self.prior_weight,
                "prior_weight_choice": self.weight_choice,
                "prior_divergence": self.prior_divergence,
                "links": None if self.links is None else [dict(lk) for lk in self.links],
                "fit_increase_noise_variances": self.fit_increase,
                "constraint_cost": self.constraint_cost,
                "tie_break": self.tie_break,
                "noise_variance_factor": self.noise,
                "eig_tolerance": EIG_TOL,
                "base_names": list(self.base.names),
                "base_values": [float(v) for v in self.full],
                "unconstrained_pseudo_inertia_min_eig": {
                    nm: float(v) for nm, v in zip(self.link_names, self.unconstrained_min_eig)
                },
                "unconstrained_violating_links": self.violating_links(unconstrained=True),
                "notes": list(self.notes),
            },
        }


def description_vector(base: BaseParameters) -> np.ndarray:
    """The description's classical parameters in the layout of ``base`` (offsets zero)."""
    robot = base.robot
    p = robot.parameters(rotor=base.rotor, friction=base.friction)
    return np.concatenate([p, np.zeros(robot.n if base.offset else 0)])


def nearest_realisation(base: BaseParameters, values) -> np.ndarray:
    """The classical vector with base parameters ``values`` nearest to the description
    (Euclidean norm): ``pi0 + Y^+ (values - Y pi0)``."""
    pi0 = description_vector(base)
    Y = base.Y
    return pi0 + np.linalg.lstsq(Y, np.asarray(values, float) - Y @ pi0, rcond=None)[0]


def noise_scale(res: IdentificationResult) -> dict:
    """The noise variance of the consistent estimate's fit term as a factor on the residual
    variance of ``res`` (which counts its rows as independent): the factor of its standard
    deviations, ``settings.std_correlation`` (:func:`~mindyn.identification.identify`), the
    larger of the data path's (:func:`~mindyn.identification.estimation.correlation_factor`:
    filtered noise) and the one its residuals show
    (:func:`~mindyn.identification.estimation.residual_correlation`: model error; dynamic
    and integral models). Returns ``factor``, ``data_path``, ``residuals`` (None: not
    measured, the energy model) and ``residuals_rule``."""
    record = res.settings.get("std_correlation") or {}
    path = float(record.get("data_path", noise_variance_factor(res)))
    measured = record.get("residuals")
    return {
        "factor": max(path, measured or 0.0, 1.0),
        "data_path": path,
        "residuals": measured,
        "residuals_rule": str(record.get("residuals_rule", "not measured")),
    }


def identify_consistent(
    robot, data, *, prior_weight: float | str = "auto", **kwargs
) -> ConsistentResult:
    """:func:`~mindyn.identification.identify` (same arguments in ``kwargs``), then
    :func:`consistent_estimate` on its least-squares problem (the prior's weight chosen from
    the data by default)."""
    accepted = [
        name
        for name, p in inspect.signature(identify).parameters.items()
        if p.kind is p.KEYWORD_ONLY
    ]
    _args.unknown_keywords("identify_consistent", kwargs, ["prior_weight", *accepted])
    _weight(prior_weight)
    return consistent_estimate(identify(robot, data, **kwargs), prior_weight=prior_weight)


def _weight(prior_weight) -> float | None:
    if prior_weight is None or (isinstance(prior_weight, str) and prior_weight == "auto"):
        return None
    if isinstance(prior_weight, str) or not isinstance(prior_weight, numbers.Real):
        raise _args.fail(
            "prior_weight",
            f"is {prior_weight!r}; expected 'auto' or a number from 0 to {MAX_PRIOR_WEIGHT:g}",
        )
    w = _args.number(prior_weight, "prior_weight", minimum=0.0)
    if not (0 <= w <= MAX_PRIOR_WEIGHT):
        raise _args.ArgumentError(
            f"prior_weight is {w:g}; expected a number from 0 to {MAX_PRIOR_WEIGHT:g} (at "
            f"{MAX_PRIOR_WEIGHT:g} the prior already outweighs the fit by that factor, and the "
            "convex solvers lose accuracy beyond it)"
        )
    return w


def consistent_estimate(
    res: IdentificationResult,
    *,
    prior_weight: float | str = "auto",
    progress=None,
) -> ConsistentResult:
    """The physically consistent classical parameters for the least-squares problem of ``res``
    (see the module documentation).

    ``prior_weight`` ``W >= 0`` adds ``W * sum_links d(J, J0)``, the log-det (Bregman)
    divergence ``d(J, J0) = -log det(J0^-1 J) + tr(J0^-1 J) - 4`` of each link's pseudo-inertia
    from the description's, to the fit term (which is in units of the noise variance, see the
    module): at ``W = 1`` a divergence of 1 costs as much as moving the base parameters one
    standard deviation along one direction. ``"auto"`` (default): ``W`` the candidate under
    which the data are most probable (the marginal likelihood; see
    :mod:`~mindyn.identification.prior`), recorded in ``weight_choice``. With a prior, the
    estimate is the minimiser found by a damped Newton descent (:func:`~mindyn.identification
    .prior.newton_prior`; the conic solver and a smooth refinement if it does not converge), and
    ``links`` says per link whether the data or the prior determine its parameters. ``W = 0``:
    no prior; the classical parameters the data leave undetermined are then taken nearest the
    description. Without a prior, when the unconstrained optimum (all base parameters, no
    pruning) has a consistent classical realisation, that is the answer (its base parameters
    equal the least-squares estimate): its realisation nearest the description when that is
    consistent (no solver runs), else the consistent one nearest the description (one convex
    solve with ``Y pi = p_b`` imposed). Otherwise the optimum is on the boundary of the
    consistent set; see :data:`TIE_BREAK_SLACK` for how it is taken. With a prior, when the
    Newton descent does not converge, the conic solver's answer is refined by a smooth descent
    of the same objective (:func:`_refine_with_prior`; noted with the gain). After a solve,
    pseudo-inertias with eigenvalues below zero by solver tolerance are projected onto the
    positive semidefinite matrices (negative eigenvalues set to zero) and the joint terms moved
    onto their constraints (``Ia, Fv, Fc`` clipped at zero, ``Fs >= -Fc``, ``|Fa| <= Fc``), so
    every smallest eigenvalue is at least ``-EIG_TOL``.

    The fit term's noise variance is the residual variance of ``res`` times
    :func:`noise_scale`'s factor, that of its standard deviations: it also accounts for the
    correlation of the residuals that model error leaves (recorded in ``noise``).

    ``constraint_cost`` says where consistency costs the fit (without a prior, one solve with
    every constraint and, when that costs at least one noise variance, one per link with its
    constraint lifted: :func:`~mindyn.identification.constraint_cost.constraint_costs`).

    ``progress``, a callable taking a line of text, is told each solve and refinement as it
    starts and ends (they can take seconds each)."""
    t0 = time.perf_counter()
    _args.instance(res, "res", IdentificationResult)
    W = _weight(prior_weight)
    _args.optional(_args.function, progress, "progress")
    base = res.base
    ls = res.reduced
    if ls is None:
        raise IdentificationError("the identification result carries no least-squares problem")
    layout = _Layout(base)
    nb = base.n
    Y = base.Y
    M = (ls.R * ls.norms) @ Y  # residual |M pi - z|^2 + rho
    z = ls.z
    beta_ls, _, _ = ls.solve(list(range(nb)))
    s2 = ls.rho / (ls.r - nb) if ls.r > nb else 0.0
    floor = 1e-10 * (float(z @ z) + ls.rho)  # noise-free data: |z| / s at most 1e5
    noise = noise_scale(res)
    s2 = max(s2 * noise["factor"], floor, 1e-300)
    fit_ls = float(np.sum((ls.R @ (beta_ls * ls.norms) - z) ** 2))
    notes: list[str] = []

    def fit_increase(pi):
        return (float(np.sum((M @ pi - z) ** 2)) - fit_ls) / s2

    pi0 = description_vector(base)
    pi_n = nearest_realisation(base, beta_ls)
    ok_n = np.all(min_eigenvalues(pi_n, layout) >= 0) and layout.satisfied(pi_n)
    pi_un = nearest_realisation(base, res.full)
    choice, links, start = None, None, None
    tie_break: dict = {}  # filled when the no-prior estimate is taken by the tie-break
    if W != 0:
        from .prior import PATH, PriorProblem, choose_prior_weight, feasible_start, newton_prior

        J0s = _prior_matrices(base, layout, pi0, notes)
        problem = PriorProblem(M, z, s2, layout, J0s)
        if W is None:
            with _stage(progress, "prior weight by the marginal likelihood"):
                W, choice, start = choose_prior_weight(
                    problem, feasible_start(problem, J0s, layout, pi0), progress=progress
                )
    if W == 0 and ok_n:
        pi, solver, status = pi_n, "none", "optimal"
        notes.append("the unconstrained optimum is consistent: returned as it is")
    elif W > 0:
        with _stage(progress, "Newton descent"):
            if start is None or not problem.feasible(start):
                # from the description down a decade at a time to W (a weak prior's minimiser
                # lies near the cone's boundary, far from the description)
                start = feasible_start(problem, J0s, layout, pi0)
                for w in sorted((c for c in PATH if c > W), reverse=True):
                    start = newton_prior(problem, w, start)[0]
            pi, converged, iters = newton_prior(problem, W, start)
        solver, status = "Newton", f"converged in {iters} steps"
        if not converged:
            pi, solver, status = _solve(base, layout, M, z, s2, pi0, W, [], beta_ls, progress)
            with _stage(progress, "refinement of the solver's answer (L-BFGS-B)"):
                pi, gain = _refine_with_prior(M, z, s2, pi, layout, J0s, W)
            notes.append(
                f"the Newton descent did not converge in {iters} steps: the cone solver's "
                f"answer instead, refined by a smooth descent of the same objective (L-BFGS-B "
                f"over Cholesky factors of the pseudo-inertias; lower by {gain:.3g})"
            )
        else:
            from .prior import link_report

            with _stage(progress, "per link, the fit with its mass held at the description's"):
                links = link_report(
                    problem,
                    pi,
                    W,
                    base.robot.link_names[1:],
                    pi0,
                    Y,
                    start=feasible_start(problem, J0s, layout, pi0),
                )
    else:
        pi, solver, status = _solve(
            base, layout, M, z, s2, pi0, W, notes, beta_ls, progress, tie_break
        )
        if tie_break:  # the optimum's fit term, from the residual variable: in noise variances
            tie_break["optimum_fit_increase"] = tie_break.pop("optimum_fit") - fit_ls / s2
    realised = W == 0 and (ok_n or any(n.startswith("the unconstrained optimum") for n in notes))
    # Enforce the constraints exactly (solver tolerance): PSD projection, clipping.
    for ix in layout.links:
        J = pseudo_inertia(pi[ix])
        lam, V = np.linalg.eigh(J)
        if lam[0] < 0:
            pi[ix] = inertial_from_pseudo((V * np.maximum(lam, 0.0)) @ V.T)
    layout.project(pi)
    eig = min_eigenvalues(pi, layout)
    if eig.min() < -EIG_TOL:  # pragma: no cover - guarded by the projection above
        raise IdentificationError(
            f"consistent estimate: smallest pseudo-inertia eigenvalue {eig.min():.3g} kg"
        )
    if ok_n:  # the unconstrained optimum is consistent: consistency costs nothing
        from .constraint_cost import RULE

        cost: dict = {"total": 0.0, "links": None, "joint_terms": None, "major": [], "rule": RULE}
    else:
        from .constraint_cost import constraint_costs

        cost = constraint_costs(base, M, z, s2, fit_ls=fit_ls, notes=notes, progress=progress)
    prior = None
    if W > 0:
        prior = float(
            sum(
                _divergence(pseudo_inertia(pi[ix]), J0)
                for ix, J0 in zip(layout.links, _prior_matrices(base, layout, pi0, None))
            )
        )
    return ConsistentResult(
        model=res.model,
        base=base,
        classical=pi,
        full=Y @ pi,
        unconstrained=res,
        min_eig=eig,
        unconstrained_min_eig=min_eigenvalues(
            pi if realised and np.array_equal(res.full, beta_ls) else pi_un, layout
        ),
        prior_weight=W,
        weight_choice=choice,
        links=None if links is None else tuple(links),
        solver=solver,
        status=status,
        fit_increase=fit_increase(pi),
        constraint_cost=cost,
        tie_break=tie_break or None,
        prior_divergence=prior,
        noise=noise,
        notes=tuple(notes),
        seconds=time.perf_counter() - t0,
    )


@contextlib.contextmanager
def _stage(progress, what: str):
    """Tells ``progress`` (a callable taking a line, or None) that ``what`` starts, and when it
    ends with its duration (or that it failed)."""
    if progress is None:
        yield
        return
    progress(f"consistent estimate: {what} ...")
    t0 = time.perf_counter()
    ok = False
    try:
        yield
        ok = True
    finally:
        progress(
            f"consistent estimate: {what}: {'done' if ok else 'failed'} in "
            f"{time.perf_counter() - t0:.1f} s"
        )


def _refine_with_prior(M, z, s2, pi, layout: _Layout, J0s, W: float) -> tuple[np.ndarray, float]:
    """With a prior the objective ``|M pi - z|^2 / s2 + W sum d(J, J0)`` is smooth and strictly
    convex inside the cone, and its minimiser is interior (the log-det term): a conic solver
    stops at a relative duality gap of about 1e-5 when the fit term is large, which leaves the
    parameters the prior decides visibly off (or on the boundary). This descends from its
    answer over ``J = L L^T`` per link (``L`` lower triangular, so every iterate is consistent)
    and the non-negative joint terms as bounds, with the exact gradient; returns the better of
    the two and how much lower the objective is (0: the solver's answer kept)."""
    from scipy.optimize import minimize

    G10 = _pseudo_map()
    tril = np.tril_indices(4)
    J0inv = [0.5 * (A + A.T) for A in (np.linalg.inv(J0) for J0 in J0s)]
    links, extra = layout.links, layout.extra
    nl = len(links)

    def unpack(x):
        p = np.array(pi, dtype=float)
        Js = []
        for j, ix in enumerate(links):
            L = np.zeros((4, 4))
            L[tril] = x[10 * j : 10 * j + 10]
            J = L @ L.T
            p[ix] = G10 @ J.ravel()
            Js.append((L, J))
        p[extra] = x[10 * nl :]
        return p, Js

    def fun(x):
        p, Js = unpack(x)
        r = M @ p - z
        f = float(r @ r) / s2
        gp = 2.0 * (M.T @ r) / s2
        grad = np.zeros_like(x)
        for j, (ix, (L, J)) in enumerate(zip(links, Js)):
            sign, logdet = np.linalg.slogdet(J)
            if sign <= 0:
                return math.inf, grad
            Jinv = np.linalg.inv(J)
            f += W * (-logdet + float(np.sum(J0inv[j] * J)))
            D = (G10.T @ gp[ix]).reshape(4, 4) + W * (J0inv[j] - Jinv)
            grad[10 * j : 10 * j + 10] = ((D + D.T) @ L)[tril]
        grad[10 * nl :] = gp[extra]
        return f, grad

    x0 = []
    for ix in links:
        J = pseudo_inertia(pi[ix])
        lam, V = np.linalg.eigh(J)
        floor = 1e-9 * max(1.0, float(lam[-1]))  # a factor of a singular answer: just inside
        root = V * np.sqrt(np.maximum(lam, floor))
        R = np.asarray(np.linalg.qr(root.T, mode="r"))  # numpy types it as the tuple result
        x0.extend((R.T * np.where(np.diag(R) < 0, -1.0, 1.0))[tril])
    nonneg = set(extra[layout.nonneg].tolist())
    start = [max(v, 0.0) if i in nonneg else v for v, i in zip(np.asarray(pi, float)[extra], extra)]
    x0 = np.concatenate([x0, start])
    f0 = fun(x0)[0]
    bounds = [(None, None)] * (10 * nl) + [
        (0.0, None) if i in nonneg else (None, None) for i in extra
    ]
    out = minimize(
        fun,
        x0,
        jac=True,
        method="L-BFGS-B",
        bounds=bounds,
        options={"maxiter": 5000, "ftol": 1e-15, "gtol": 1e-10},
    )
    refined = unpack(out.x)[0]
    # its bounds are the non-negative terms' alone: a refinement that leaves the friction's
    # other constraints (Fs >= -Fc, |Fa| <= Fc) beyond round-off is not taken
    scale = max(float(np.max(np.abs(refined[extra]), initial=0.0)), 1e-300)
    if not (math.isfinite(out.fun) and out.fun < f0 and layout.satisfied(refined, 1e-9 * scale)):
        return pi, 0.0
    return refined, float(f0 - out.fun)


def _mean_mass(base: BaseParameters, layout: _Layout, pi0: np.ndarray) -> float:
    masses = np.array([pi0[ix[9]] for ix in layout.links])
    pos = masses[masses > 0]
    return float(pos.mean()) if pos.size else 1.0


def _prior_matrices(base, layout, pi0, notes) -> list[np.ndarray]:
    """The description's pseudo-inertias, each made positive definite when it is not (see
    :data:`PRIOR_REGULARISATION`)."""
    eps = PRIOR_REGULARISATION * _mean_mass(base, layout, pi0)
    out = []
    for name, ix in zip(base.robot.link_names[1:], layout.links):
        J0 = pseudo_inertia(pi0[ix])
        lam, V = np.linalg.eigh(J0)
        if lam[0] < eps:
            J0 = (V * np.maximum(lam, 0.0)) @ V.T + eps * np.eye(4)
            if notes is not None:
                notes.append(
                    f"prior: the description's pseudo-inertia of {name} has its smallest "
                    f"eigenvalue {lam[0]:.3g} kg, below {eps:.3g} kg (singular or nearly so); "
                    f"regularised to its PSD part + {eps:.3g} kg x identity"
                )
        out.append(J0)
    return out


def _divergence(J, J0) -> float:
    A = np.linalg.solve(J0, J)
    sign, logdet = np.linalg.slogdet(A)
    return float(-logdet + np.trace(A) - 4) if sign > 0 else math.inf


def _conic_map(base, layout, pi0) -> tuple[np.ndarray, np.ndarray, float]:
    """The conic problems' variables: ``pi = G u``, ``u = [vec(J'_1) .. vec(J'_n), extras]``
    with each link's pseudo-inertia ``J = mbar J'`` (variables of order 1; ``mbar`` the mean
    link mass); ``s`` (P,): each parameter's scale (``mbar`` on a link's, 1 on the joint
    terms'). Returns ``(G, s, mbar)``."""
    mbar = _mean_mass(base, layout, pi0)
    G10 = _pseudo_map()
    n, P, k = len(layout.links), len(layout.names), layout.extra.size
    G = np.zeros((P, 16 * n + k))
    s = np.ones(P)
    for j, ix in enumerate(layout.links):
        G[ix, 16 * j : 16 * (j + 1)] = mbar * G10
        s[ix] = mbar
    G[layout.extra, 16 * n + np.arange(k)] = 1.0
    return G, s, mbar


def _conic_variables(layout, free_link: int | None = None):
    """The variables of :func:`_conic_map`: ``(Js, e, u)``, the links' scaled pseudo-inertias
    (positive semidefinite; link ``free_link``'s only symmetric), the joint terms (None without
    them) and their stack ``u``."""
    import cvxpy as cp

    Js = [
        cp.Variable((4, 4), symmetric=True) if j == free_link else cp.Variable((4, 4), PSD=True)
        for j in range(len(layout.links))
    ]
    parts = [cp.vec(J, order="C") for J in Js]
    k = layout.extra.size
    e = cp.Variable(k) if k else None
    if e is not None:
        parts.append(e)
    return Js, e, cp.hstack(parts)


def _solve(base, layout, M, z, s2, pi0, W, notes, beta=None, progress=None, tie_break=None):
    """The conic solve; when the tie-break is taken (no prior), ``tie_break`` (a dict) gets
    ``slack`` and ``optimum_fit``, the optimum's fit term [noise variances]."""
    import cvxpy as cp

    P = len(layout.names)
    G, s, mbar = _conic_map(base, layout, pi0)
    Js, e, u = _conic_variables(layout)
    pi = G @ u
    scale = 1.0 / math.sqrt(s2)
    # The residual as its own variable: the objective's quadratic form is then the identity
    # rather than the (squared, ill-conditioned) normal matrix.
    r = cp.Variable(z.size)
    fit = cp.sum_squares(r)
    objective = fit
    N = np.zeros((P, 0))
    cons = [r == (M @ G) @ u * scale - z * scale]
    if e is not None and layout.B.shape[0]:
        cons.append(layout.B @ e >= 0)
    if W > 0:
        J0s = _prior_matrices(base, layout, pi0, notes)
        for J, J0 in zip(Js, J0s):
            inv = np.linalg.inv(J0 / mbar)
            inv = 0.5 * (inv + inv.T)
            objective = objective + W * (-cp.log_det(J) + cp.trace(inv @ J))
    else:
        N = sla.null_space(base.Y * s)
        if N.size:
            w = cp.Variable(N.shape[1])
            cons.append(w == N.T @ ((pi - pi0) / s))
            tie = cp.sum_squares(w)
            objective = objective + NULL_SPACE_WEIGHT * tie
    if W == 0 and beta is not None:
        # Does the unconstrained optimum have a consistent realisation? Then it is the answer,
        # the undetermined parameters nearest the description.
        A = base.Y @ G
        rn = np.maximum(np.linalg.norm(A, axis=1), 1e-300)
        feas = cons[1:] + [(A / rn[:, None]) @ u == beta / rn]
        prob = cp.Problem(cp.Minimize(tie if N.size else 0), feas)
        solver, status = _run(prob, notes, "realisation ", True, progress)
        if status in ("optimal", "optimal_inaccurate"):
            pi_f = np.asarray(G @ u.value, float)
            pi_f += np.linalg.lstsq(base.Y, beta - base.Y @ pi_f, rcond=None)[0]
            notes.append("the unconstrained optimum has a consistent realisation: returned")
            return pi_f, solver, status
    solver, status = _run(cp.Problem(cp.Minimize(objective), cons), notes, "", False, progress)
    if W == 0 and N.size:
        # second solve: the undetermined parameters nearest the description among the optima
        best = float(fit.value)
        prob = cp.Problem(
            cp.Minimize(tie), cons + [cp.norm(r) <= math.sqrt(best + TIE_BREAK_SLACK)]
        )
        solver2, status2 = _run(prob, notes, "tie-break ", False, progress)
        if tie_break is not None:
            tie_break.update(slack=TIE_BREAK_SLACK, optimum_fit=best)
        solver = solver if solver2 == solver else f"{solver}+{solver2}"
        status = status if status2 == status else f"{status}+{status2}"
    return np.asarray(G @ u.value, float), solver, status


def _run(
    prob, notes: list, what: str, accept_infeasible: bool = False, progress=None
) -> tuple[str, str]:
    """Solves ``prob`` with Clarabel, else SCS (noted); raises IdentificationError when neither
    gives a solution (with ``accept_infeasible``, Clarabel's verdict of infeasibility is
    returned as the status)."""

    tried = []
    for solver in ("CLARABEL", "SCS"):
        # an inaccurate solution is reported in the status (optimal_inaccurate), not warned
        options = (
            {"eps": 1e-9, "max_iters": 20000}
            if solver == "SCS"
            else {"chordal_decomposition_enable": False}
        )
        try:
            with warnings.catch_warnings(), np.errstate(all="ignore"):
                warnings.filterwarnings("ignore", "Solution may be inaccurate", UserWarning)
                warnings.filterwarnings("ignore", category=RuntimeWarning)
                size = sum(v.size for v in prob.variables())
                with _stage(
                    progress, f"{what or 'main '}solve, {solver.capitalize()}, {size} variables"
                ):
                    prob.solve(solver=solver, **options)
        except (KeyboardInterrupt, SystemExit, MemoryError):
            raise
        except BaseException as ex:  # noqa: BLE001 - Clarabel's PanicException is a BaseException
            text = str(ex).splitlines()[0] if str(ex).strip() else type(ex).__name__
            tried.append(f"{solver.capitalize()} failed ({text})")
            continue
        if accept_infeasible and solver == "CLARABEL" and prob.status == "infeasible":
            return solver, prob.status
        if prob.status in ("optimal", "optimal_inaccurate") and all(
            v.value is not None for v in prob.variables()
        ):
            if tried:
                notes.append(f"{what}fallback to SCS after " + "; ".join(tried))
            return solver, prob.status
        tried.append(f"{solver.capitalize()} ended with status '{prob.status}'")
    raise IdentificationError(
        f"consistent estimate: the convex {what}problem (least squares under positive "
        "semidefinite pseudo-inertias) was not solved: " + "; ".join(tried) + "; the data may "
        "be badly scaled (a longer or richer log, or a smaller prior_weight=, may help)"
    )


# ---------------------------------------------------------------------------------------------
# Payload
# ---------------------------------------------------------------------------------------------
@dataclass
class PayloadResult:
    """Inertial parameters of a payload fixed to the last link, about the last link frame's
    origin and in its frame (``XX XY XZ YY YZ ZZ MX MY MZ M``).

    ``values``, ``std``: the unconstrained (weighted) least-squares estimate and its standard
    deviations (``f s^2 (A^T A)^-1`` of the weighted rows, ``s^2`` their residual variance, ``f``
    the correlation factor of low-passed logs; ``std_rule`` says which); ``covariance``
    (10, 10); ``sigma`` the first OLS pass's residual standard deviation, ``joint_sigma`` per
    joint. ``consistent``:
    the estimate with the payload's pseudo-inertia positive semidefinite (or None). ``derived`` /
    ``consistent_derived``: mass, centre of mass, inertia about the centre of mass, with standard
    deviations by first-order propagation for the unconstrained one."""

    names: list
    values: np.ndarray
    std: np.ndarray
    covariance: np.ndarray
    sigma: float
    rows: int
    rank: int
    cond: float
    consistent: np.ndarray | None
    min_eig: float
    consistent_min_eig: float | None
    arm_values: str
    solver: str | None = None
    status: str | None = None
    seconds: float = 0.0
    #: The per-joint residual standard deviations of the first OLS pass (n,), whose inverses
    #: weight the joints' equations, and how the standard deviations were formed.
    joint_sigma: np.ndarray | None = None
    std_rule: str = ""
    #: ``H`` (10, nb): the estimate moves by ``-H e`` for an error ``e`` of the arm's base
    #: values; ``arm_covariance`` ``H Sigma_arm H^T`` (10, 10), the part of ``covariance`` the
    #: arm estimate's uncertainty brings (None when its JSON has no covariance).
    arm_sensitivity: np.ndarray | None = None
    arm_covariance: np.ndarray | None = None

    def derived(self, *, consistent: bool = False) -> dict:
        if consistent:
            return body_quantities(self.consistent)
        p = self.values
        out = body_quantities(p)
        # first-order propagation: central differences of the derived quantities
        f0 = _flat(out)
        Jac = np.zeros((f0.size, 10))
        for k in range(10):
            h = 1e-6 * max(1.0, abs(p[k]))
            dp = np.zeros(10)
            dp[k] = h
            Jac[:, k] = (_flat(body_quantities(p + dp)) - _flat(body_quantities(p - dp))) / (2 * h)
        sd = np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", Jac, self.covariance, Jac), 0.0))
        out["mass_std"], out["com_std"], out["inertia_com_std"] = sd[0], sd[1:4], sd[4:]
        return out

    def to_dict(self) -> dict:
        def plain(d):
            return {
                k: (v.tolist() if isinstance(v, np.ndarray) else float(v)) for k, v in d.items()
            }

        return {
            "frame": "last link frame, parameters about its origin",
            "names": list(self.names),
            "values": self.values.tolist(),
            "std": self.std.tolist(),
            "std_rule": self.std_rule,
            "sigma": self.sigma,
            "joint_sigma": None if self.joint_sigma is None else self.joint_sigma.tolist(),
            "rows": self.rows,
            "rank": self.rank,
            "condition_number_scaled": self.cond,
            "pseudo_inertia_min_eig": self.min_eig,
            "unconstrained": plain(self.derived()),
            "consistent": None
            if self.consistent is None
            else {
                "values": self.consistent.tolist(),
                "pseudo_inertia_min_eig": self.consistent_min_eig,
                "solver": self.solver,
                "status": self.status,
                **plain(self.derived(consistent=True)),
            },
            "arm_values": self.arm_values,
            "seconds": self.seconds,
        }


def _flat(d: dict) -> np.ndarray:
    return np.concatenate([[d["mass"]], d["com"], d["inertia_com"]])


class _LastLink:
    """The last link's 10 classical regressor columns, in the interface of a base set that the
    preprocessing's parallel filter takes (``n``, ``regressor``)."""

    def __init__(self, robot: Robot):
        self.robot = robot
        self.n = 10
        self.cols = np.arange(10 * (robot.n - 1), 10 * robot.n)

    def regressor(self, q, dq, ddq):
        return self.robot.regressor(q, dq, ddq)[..., self.cols]


def read_arm(
    robot: Robot, arm, *, where: str = "arm"
) -> tuple[BaseParameters, np.ndarray, str, np.ndarray | None]:
    """The base set and base values of an identified arm: the JSON of ``mindyn identify``
    (a dict or a path), checked by :func:`~mindyn.identification.document.read_identification`.
    Uses ``classical`` when present (the consistent estimate), else ``base_values``; with them
    which it used and the covariance of the least-squares estimate's base parameters
    (``initial.covariance``; None in a JSON without it)."""
    if isinstance(arm, (str, Path)):
        where = str(arm)
        try:
            arm = read_json(arm, what="identification JSON")
        except DataError as ex:
            raise ModelError(f"{where}: not a JSON file of mindyn identify ({ex})") from None
    need = ("robot", "base_names", "base_values", "rotor", "friction", "offset")
    arm = read_identification(arm, need=need, what=where)
    check_identified_robot(arm, robot, where, error=ModelError)
    base = identified_base(arm, robot, where)
    robot = base.robot
    if arm["base_names"] != list(base.names):
        tip = arm.get("tip")
        raise ModelError(
            f"{where}: its base parameters ({len(arm['base_names'])}) are not those of robot "
            f"'{robot.name}' ({base.n}, {robot.n} joints: "
            f"{names_difference(arm['base_names'], base.names)}); "
            + (
                f"it was identified on the chain ending at tip='{tip}': load the robot with "
                "that tip"
                if tip
                else "identified with another description or another tip=?"
            )
        )
    check_identified_model(arm, base, where, error=ModelError)
    classical = arm.get("classical")
    if classical is not None:
        missing = [nm for nm in base.classical_names if nm not in classical]
        if missing:
            raise ModelError(f"{where}: 'classical' lacks {', '.join(missing[:5])}")
        pi = np.array([classical[nm] for nm in base.classical_names])
        values, used = base.values(pi), "classical (consistent estimate)"
    else:
        values, used = np.array(arm["base_values"]), "base values"
    if values.shape != (base.n,) or not np.all(np.isfinite(values)):
        raise ModelError(f"{where}: expected {base.n} finite base values")
    cov = (arm.get("initial") or {}).get("covariance")
    if cov is not None:
        try:
            cov = np.array(cov, dtype=float)
        except (TypeError, ValueError):
            cov = None
        if cov is None or cov.shape != (base.n, base.n) or not np.all(np.isfinite(cov)):
            raise ModelError(
                f"{where}: 'initial.covariance' is not a {base.n} x {base.n} matrix of finite "
                "numbers"
            )
    return base, values, used, cov


def arm_tip(arm, robot) -> str | None:
    """The ``tip`` an identification JSON (a path or a dict) was identified with, when the
    ``robot`` argument is a URDF file (a tip applies to nothing else; :func:`read_arm` then
    refuses the robot by name), else None: what :func:`identify_payload` loads a robot named by
    a string with."""
    if Path(str(robot)).suffix.lower() not in (".urdf", ".xml"):
        return None
    if isinstance(arm, (str, Path)):
        try:
            arm = read_json(arm, what="identification JSON")
        except DataError:
            return None  # read_arm names the problem
    tip = arm.get("tip") if isinstance(arm, dict) else None
    return tip if isinstance(tip, str) else None


#: The default ``min_velocity`` of :func:`identify_payload` [rad/s, m/s] (as identify's).
PAYLOAD_MIN_VELOCITY = 0.01


def identify_payload(
    robot: Robot | str,
    arm,
    data: JointData | list[JointData],
    *,
    consistent: bool = True,
    min_velocity: float | None = None,
    rank_tolerance: float = 1e-9,
) -> PayloadResult:
    """Inertial parameters of a payload rigidly fixed to the last link, from logs ``data`` with
    the payload and the identified ``arm`` (JSON of ``mindyn identify`` as a dict or path: its
    base values, or its ``classical`` map when present; friction, rotor inertia and offsets as
    identified; a ``robot`` given by name is loaded with the JSON's ``tip``). Least squares on
    ``tau - tau_arm = W_last phi``, weighted as identify's dynamic fit (per-joint ``1 / sigma_j``
    from a first OLS pass; the standard deviations inflated by
    :func:`~mindyn.identification.estimation.correlation_factor` for low-passed logs) (all
    joints' equations;
    with arm friction, equations of joints slower than ``min_velocity`` left out as in
    :func:`~mindyn.identification.identify`: :data:`PAYLOAD_MIN_VELOCITY` when not given;
    given to an arm without friction, refused), and with ``consistent`` the estimate under a
    positive semidefinite payload pseudo-inertia (cvxpy, Clarabel).

    Raises IdentificationError when the data (or the geometry: a last joint whose axis symmetry
    hides some parameters) do not determine all 10 parameters: the rank and the undetermined
    parameters and combinations are named."""
    t0 = time.perf_counter()
    _args.instance(robot, "robot", (Robot, str, Path), "a Robot, a bundled robot name or a path")
    _args.instance(arm, "arm", (dict, str, Path), "an identification (its JSON as a dict or path)")
    consistent = _args.flag(consistent, "consistent")
    given_velocity = min_velocity is not None
    min_velocity = _args.number(
        PAYLOAD_MIN_VELOCITY if min_velocity is None else min_velocity, "min_velocity", minimum=0.0
    )
    rank_tolerance = _args.number(rank_tolerance, "rank_tolerance", positive=True)
    robot = load(robot, tip=arm_tip(arm, robot) if isinstance(robot, (str, Path)) else None)
    robot._require_serial("payload identification (a payload on the last link)")
    base, beta, used, arm_cov = read_arm(robot, arm)
    if not base.friction and given_velocity:
        raise _args.fail(
            "min_velocity",
            "applies only to an arm identified with friction (it leaves out the equations of "
            "joints too slow for the sign of their Coulomb friction); this arm has none",
        )
    logs = _logs(data, robot=robot)
    last = _LastLink(robot)
    names = [f"{k}{robot.n}" for k in INERTIAL]
    rows_A, rows_y, rows_j, rows_B, log_rows = [], [], [], [], []
    for d in logs:
        tau = require_torque(d)
        if d.n != robot.n:
            raise ModelError(
                f"{d.source or 'data'} has {d.n} joints; robot '{robot.name}' has {robot.n}"
            )
        if d.regressor_filter is not None:
            Wl = d.regressor_filter.regressor(last)
        else:
            Wl = last.regressor(d.q, d.dq, d.ddq)
        # the arm's base regressor rows: its torques, and (with its covariance) how its
        # estimate's error reaches the payload's
        B = np.concatenate(
            [regressor_rows(base, d, a, min(d.m, a + 8192)) for a in range(0, d.m, 8192)]
        )
        B = B.reshape(-1, base.n)
        r = tau.reshape(-1) - B @ beta
        A = Wl.reshape(-1, 10)
        joint = np.tile(np.arange(robot.n), d.m)
        keep = moving_equations(base, d.dq, min_velocity)
        if keep is not None:
            keep = keep.reshape(-1)
            A, r, joint, B = A[keep], r[keep], joint[keep], B[keep]
        rows_B.append(B)
        rows_A.append(A)
        rows_y.append(r)
        rows_j.append(joint)
        log_rows.append(len(r))
    A, y, joint = np.vstack(rows_A), np.concatenate(rows_y), np.concatenate(rows_j)
    if A.shape[0] < 10 + 30:
        raise IdentificationError(
            f"{len(y)} equations for the 10 payload parameters; at least 40 are needed"
        )
    # weighted least squares as identify's dynamic fit: per-joint 1 / sigma_j from the
    # residuals of a first OLS pass (the joints' torque noise differs by orders of magnitude),
    # the variances inflated for the low-passed noise's correlation between samples
    p0, *_ = np.linalg.lstsq(A, y, rcond=None)
    e2 = (y - A @ p0) ** 2
    counts = np.bincount(joint, minlength=robot.n)
    dof = max((len(y) - 10) / len(y), 1e-12)
    joint_sigma = np.sqrt(np.bincount(joint, e2, robot.n) / np.maximum(counts, 1) / dof)
    w = joint_weights(joint_sigma)[joint]
    ls = _Reduced(A * w[:, None], y * w)
    inflation, inflation_rule = correlation_factor(logs, log_rows)
    rank, piv, cond = ls.rank(rank_tolerance)
    if rank < 10:
        N = sla.null_space(ls.R, rcond=rank_tolerance)  # scaled coordinates
        combos = []
        for v in N.T[: 10 - rank]:
            v = v / ls.norms
            v = v / v[np.argmax(np.abs(v))]
            combos.append(
                " ".join(f"{c:+.3g} {nm}" for c, nm in zip(v, names) if abs(c) > 1e-6).lstrip("+")
            )
        dropped = ", ".join(names[j] for j in piv[rank:])
        raise IdentificationError(
            f"payload: the last link's regressor has rank {rank} of 10 on this data; "
            f"{dropped} cannot be separated from the others (undetermined combinations: "
            + "; ".join(combos)
            + "); the joint axes' symmetry or the motion leaves them unobservable"
        )
    p, std, s2 = ls.solve(list(range(10)), inflation=inflation)
    Rinv = sla.solve_triangular(ls.R, np.eye(10))
    cov = s2 * inflation * (Rinv @ Rinv.T) / np.outer(ls.norms, ls.norms)
    # the estimate is linear in the arm's base values: p = G (tau - B beta), G the weighted
    # least-squares solution, so an error e of beta moves it by -H e, H = G B
    Bw = np.vstack(rows_B) * w[:, None]
    H = (Rinv @ Rinv.T) @ ((A * w[:, None] / ls.norms).T @ Bw) / ls.norms[:, None]
    arm_part = None
    if arm_cov is not None:
        arm_part = H @ arm_cov @ H.T
        cov = cov + arm_part
        std = np.sqrt(np.diag(cov))
        inflation_rule += (
            "; plus the arm estimate's covariance (its base parameters before pruning, "
            "initial.covariance of its JSON) carried through the arm's torques"
            + (
                ", that of its least-squares estimate for the consistent one used"
                if used.startswith("classical")
                else ""
            )
        )
    else:
        inflation_rule += (
            "; the arm estimate's own uncertainty is not counted (its JSON has no covariance)"
        )
    min_eig = float(np.linalg.eigvalsh(pseudo_inertia(p))[0])
    phi_c, solver, status, cmin = None, None, None, None
    if consistent:
        if min_eig >= 0:
            phi_c, solver, status = p.copy(), "none", "optimal"
        else:
            phi_c, solver, status = _solve_payload(ls, p)
        lam, V = np.linalg.eigh(pseudo_inertia(phi_c))
        if lam[0] < 0:
            phi_c = inertial_from_pseudo((V * np.maximum(lam, 0)) @ V.T)
        cmin = float(np.linalg.eigvalsh(pseudo_inertia(phi_c))[0])
    return PayloadResult(
        names=names,
        values=p,
        std=std,
        covariance=cov,
        sigma=math.sqrt(float(e2.sum()) / max(len(y) - 10, 1)),
        joint_sigma=joint_sigma,
        std_rule="weighted least squares, per-joint 1/sigma_j from a first OLS pass; "
        + inflation_rule,
        rows=ls.r,
        rank=rank,
        cond=cond,
        consistent=phi_c,
        min_eig=min_eig,
        consistent_min_eig=cmin,
        arm_values=used,
        arm_sensitivity=H,
        arm_covariance=arm_part,
        solver=solver,
        status=status,
        seconds=time.perf_counter() - t0,
    )


def _solve_payload(ls: _Reduced, p: np.ndarray):
    import cvxpy as cp

    ms = max(abs(p[9]), 1e-3)
    G = ms * _pseudo_map()
    J = cp.Variable((4, 4), PSD=True)
    Rs = ls.R * ls.norms
    scale = 1.0 / max(float(np.linalg.norm(ls.z)), 1e-300)
    r = cp.Variable(ls.z.size)
    cons = [r == (Rs @ G) @ cp.vec(J, order="C") * scale - ls.z * scale]
    prob = cp.Problem(cp.Minimize(cp.sum_squares(r)), cons)
    notes: list[str] = []
    solver, status = _run(prob, notes, "payload ")
    return G @ np.asarray(J.value).reshape(-1), solver, status
