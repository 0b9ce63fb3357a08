"""Where physical consistency costs the fit (:func:`constraint_costs`): the least fit increase
any consistent estimate has over the unconstrained least-squares fit, and how much of it each
link's own constraint accounts for.

A consistent estimate that fits clearly worse than the unconstrained one says that the data,
read through the model, ask for inertial values no rigid body has, or for negative rotor inertia
or friction. Lifting one link's constraint (its pseudo-inertia any symmetric matrix, every other
constraint kept) and solving again shows where: a link whose release recovers most of the
increase is where the description's geometry or the model (friction, elasticity, cables,
sensor gains on its joints) disagrees with the log. Every solve is without a prior, on the
unconstrained estimate's own least-squares problem (the module
:mod:`~mindyn.identification.consistent`); fits are in its noise variances.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import scipy.linalg as sla

from ..base import BaseParameters
from .errors import IdentificationError

#: Below this least fit increase [noise variances] the constraints are statistically free (as
#: the no-prior tie-break's slack, :data:`~mindyn.identification.consistent.TIE_BREAK_SLACK`):
#: the per-link solves are skipped.
NEGLIGIBLE = 1.0

#: A link whose release recovers at least this share of the least increase is named as where
#: the constraints cost most.
MAJOR_SHARE = 0.5

RULE = (
    "the least fit increase of a consistent estimate over the unconstrained fit with all base "
    "parameters (no prior) [noise variances]; per link, how much of it lifting that link's "
    "constraint alone (its pseudo-inertia any symmetric matrix, the other constraints kept) "
    "recovers; joint terms: the same with Ia, Fv, Fc free of their bounds"
)


def constraint_costs(
    base: BaseParameters,
    M: np.ndarray,
    z: np.ndarray,
    s2: float,
    *,
    fit_ls: float | None = None,
    notes: list | None = None,
    progress: Callable[[str], None] | None = None,
) -> dict:
    """The cost of physical consistency for the least-squares problem ``|M pi - z|^2`` in the
    classical parameters ``pi`` of ``base`` (``M``: (c, P), ``z``: (c,), ``s2``: the noise
    variance, as :func:`~mindyn.identification.consistent.consistent_estimate` sets them up;
    ``fit_ls``: the unconstrained least-squares fit term ``min |M pi - z|^2``, computed when
    not given).

    Returns ``total``: the least fit increase of a consistent ``pi`` over the unconstrained
    least-squares fit [noise variances] (None: the solve failed, noted in ``notes``);
    ``links``: link name -> the part of ``total`` that lifting that link's constraint alone
    recovers (None when ``total`` is below :data:`NEGLIGIBLE`: not computed; a link's None: its
    solve failed, noted); ``joint_terms``: the same for the joint terms' constraints
    (``Ia, Fv, Fc >= 0``, the friction dissipative: ``Fc + Fs >= 0``, ``|Fa| <= Fc``; None
    without such terms or when not computed); ``major``: the links (and ``"joint terms"``)
    recovering at least :data:`MAJOR_SHARE` of ``total``, the largest first (recoveries do not
    add up: a link's parameters can stand in for another's they regroup with); ``rule``."""
    from .consistent import (
        _conic_map,
        _conic_variables,
        _Layout,
        _run,
        _stage,
        description_vector,
    )

    layout = _Layout(base)
    names = list(base.robot.link_names[1:])
    n = len(layout.links)
    if fit_ls is None:  # the unconstrained optimum: |M pi - z|^2 depends on Y pi only
        A = M @ np.linalg.pinv(base.Y)
        fit_ls = float(np.sum((A @ np.linalg.lstsq(A, z, rcond=None)[0] - z) ** 2))
    pi0 = description_vector(base)
    G, s, _ = _conic_map(base, layout, pi0)
    N = sla.null_space(base.Y * s)
    scale = 1.0 / math.sqrt(s2)
    said = notes if notes is not None else []

    def least(free_link: int | None = None, free_terms: bool = False) -> float:
        import cvxpy as cp

        _, e, u = _conic_variables(layout, free_link)
        r = cp.Variable(z.size)
        cons = [r == (M @ G) @ u * scale - z * scale]
        if e is not None and layout.B.shape[0] and not free_terms:
            cons.append(layout.B @ e >= 0)
        objective = cp.sum_squares(r)
        if N.size:  # keeps the undetermined parameters bounded; the fit is recomputed below
            objective = objective + 1e-6 * cp.sum_squares(N.T @ ((G @ u - pi0) / s))
        try:
            _run(cp.Problem(cp.Minimize(objective), cons), said, "cost of consistency: ")
        except IdentificationError as ex:
            lifted = (
                "every constraint kept"
                if free_link is None and not free_terms
                else f"{names[free_link]}'s constraint lifted"
                if free_link is not None
                else "the joint terms' bounds lifted"
            )
            said.append(f"cost of consistency, {lifted}: not measured ({ex})")
            return math.nan
        pi = np.asarray(G @ u.value, float)
        return max((float(np.sum((M @ pi - z) ** 2)) - fit_ls) / s2, 0.0)

    with _stage(progress, "cost of consistency: least fit of a consistent estimate"):
        total = least()
    out: dict = {
        "total": total,
        "links": None,
        "joint_terms": None,
        "major": [],
        "rule": RULE,
    }
    if not total >= NEGLIGIBLE:  # negligible, or not solved (noted)
        out["total"] = None if math.isnan(total) else total
        return out

    def recovered(**lifted) -> float | None:
        rest = least(**lifted)
        return None if math.isnan(rest) else max(total - rest, 0.0)

    with _stage(progress, f"cost of consistency: {n} links' constraints lifted one at a time"):
        out["links"] = {nm: recovered(free_link=j) for j, nm in enumerate(names)}
        if layout.B.shape[0]:
            out["joint_terms"] = recovered(free_terms=True)
    shares = dict(out["links"])
    if out["joint_terms"] is not None:
        shares["joint terms"] = out["joint_terms"]
    major = [(v, nm) for nm, v in shares.items() if v is not None and v >= MAJOR_SHARE * total]
    out["major"] = [nm for v, nm in sorted(major, key=lambda x: -x[0])]
    return out
