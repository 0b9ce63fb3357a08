"""The weight of the description's prior in the consistent estimate, chosen from the data, and
what the estimate owes to the data and to the prior, link by link.

The consistent estimate with a prior (:func:`~mindyn.identification.consistent
.consistent_estimate`) minimises ``f(pi) = |M pi - z|^2 / s^2 + W sum_links d(J, J0)``, with
``s^2`` the noise variance of the fit (corrected for the correlation of filtered samples) and
``d`` the log-det divergence of a link's pseudo-inertia ``J`` from the description's ``J0``. Half
of ``f`` is the negative log posterior of the parameters when the noise is Gaussian and each link's
pseudo-inertia has the prior density ``exp(-W d(J, J0) / 2)`` normalised: a Wishart density of
``W + 5`` degrees of freedom and scale ``J0 / W`` (its mode ``J0``, its mean ``(1 + 5 / W) J0``,
a diagonal entry's relative spread ``sqrt(2 / (W + 5))`` about the mean). So ``W`` says how far
the true links may lie from the description, and the data tell how far they do: its default is
the candidate of :data:`CANDIDATES` under which the data are most probable, the marginal
likelihood ``p(z | W)`` (type-II maximum likelihood, or empirical Bayes; MacKay, *Bayesian
interpolation*, Neural Computation 4, 1992), by Laplace's approximation at the estimate
(:func:`log_evidence`, :func:`choose_prior_weight`): a weight too small spreads the prior over
masses the data exclude (Occam's factor), one too large cannot reach the values the data demand.
Unlike a cross-validation over parts of the same log, the choice does not depend on how the log
is cut, and it costs one Newton descent per candidate.

The objective is smooth and strictly convex inside the cone of positive definite
pseudo-inertias (the log-det terms are barriers), so each of these solves is a damped Newton
descent (:func:`newton_prior`, warm-started from the neighbouring weight's answer), milliseconds
where the conic solver takes seconds; the non-negative rotor-inertia and friction parameters
enter through a log barrier driven to :data:`BARRIER_END`.

Per link (:func:`link_report`): with the objective's Hessian ``H`` at the estimate, the
estimate's covariance is ``C = 2 H^-1`` (the objective is twice a negative log posterior). How
fast it shrinks as the weight grows, ``-d ln C / d ln W``, is the share of the variance the
priors account for: 0 where the data alone fix a parameter, 1 where they leave it to the
priors (of this link or of the links whose parameters the data only see together with it);
below one half, the data determine it. The verdict is taken over the link's identifiable
directions. A link's mass alone is seldom identifiable, and the log-det prior is far from
quadratic (it also keeps the pseudo-inertia positive definite), so the mass has its own verdict
from the profile of the fit: the estimate recomputed with the mass held at the description's
(:func:`mass_profile`); when the fit is then worse by at least :data:`MASS_EVIDENCE` noise
variances (the likelihood ratio of two standard deviations), the data reject the description's
mass and determine it, with the standard deviation the data give it, ``|m - m0| / sqrt(increase)``;
when the fit is not, but the whole objective is (the log-det prior ties a link's mass to its
first and second moments: with those fixed by the data, the prior itself moves the mass away
from the description's), the mass is determined by the data through the prior
(``data+prior``); otherwise the mass is held by the priors: the description's mass is then within
two standard deviations of the estimate's.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sla

from .._threads import single_threaded_blas
from .errors import IdentificationError

#: Candidate prior weights (units: one divergence costs W noise variances of the fit): half
#: decades from a prior the data outweigh in every direction they see (its mean 500 times the
#: description's pseudo-inertia) to one that holds all but the best-determined directions (a
#: diagonal entry's relative spread 1.4 %).
CANDIDATES = tuple(float(f"{10.0 ** (k / 2):.3g}") for k in range(-4, 9))

#: The weights of the descent from the description to a weaker prior's minimiser (a weak
#: prior's minimiser lies near the cone's boundary, far from the description): a decade at a
#: time.
PATH = tuple(w for w in CANDIDATES if math.log10(w).is_integer())

#: Contiguous blocks each log is cut into for a cross-validation (that of ``auto`` friction).
FOLDS = 5

#: Barrier weight of the non-negative joint parameters at the end of the Newton descent, in
#: noise variances (the objective is then within ``count x BARRIER_END`` of its minimum).
BARRIER_END = 1e-9

#: A link direction counts as determined by the data when its posterior variance is below this
#: fraction of the prior's alone (the data carry more information along it than the prior).
DATA_SHARE = 0.5

#: A link's mass counts as determined by the data when holding it at the description's makes
#: the fit worse by at least this many noise variances (a likelihood ratio of two standard
#: deviations: the data reject the description's mass at about 95 %).
MASS_EVIDENCE = 4.0


def _basis() -> np.ndarray:
    """``E`` (10, 4, 4): the pseudo-inertia of each unit inertial parameter (the map is
    linear)."""
    from .consistent import pseudo_inertia

    return np.array([pseudo_inertia(np.eye(10)[a]) for a in range(10)])


class PriorProblem:
    """``|M pi - z|^2 / s2 + W sum_l (-log det J_l + tr(J0_l^-1 J_l))`` over the classical
    vector ``pi`` (layout of :class:`~mindyn.identification.consistent._Layout`), its joint
    terms' constraints ``B pi >= 0`` (``Ia, Fv, Fc >= 0``, ``Fc + Fs >= 0``, ``Fc -+ Fa >= 0``)
    kept strict by a log barrier."""

    def __init__(self, M, z, s2, layout, J0s):
        self.M, self.z, self.s2 = M, z, s2
        self.Q = 2.0 * (M.T @ M) / s2
        self.c = 2.0 * (M.T @ z) / s2
        self.links = layout.links
        self.nonneg = layout.extra[layout.nonneg]
        self.B = np.zeros((layout.B.shape[0], M.shape[1]))  # over the whole classical vector
        self.B[:, layout.extra] = layout.B
        self.J0s = [0.5 * (J0 + J0.T) for J0 in J0s]
        self.J0inv = [0.5 * (A + A.T) for A in (np.linalg.inv(J0) for J0 in self.J0s)]
        self.E = _basis()
        self._E16 = self.E.reshape(10, 16)
        self.tr0 = [np.einsum("ij,aji->a", Ji, self.E) for Ji in self.J0inv]

    def J(self, p) -> np.ndarray:
        """The pseudo-inertia of a link's 10 parameters."""
        return (p @ self._E16).reshape(4, 4)

    def feasible(self, pi) -> bool:
        if np.any(self.B @ pi <= 0):
            return False
        for ix in self.links:
            try:
                np.linalg.cholesky(self.J(pi[ix]))
            except np.linalg.LinAlgError:
                return False
        return True

    def fit(self, pi) -> float:
        r = self.M @ pi - self.z
        return float(r @ r) / self.s2

    def prior(self, pi, *, J0s=None) -> float:
        """``sum_l d(J_l, J0_l)`` (the log-det divergence, 0 at the description)."""
        out = 0.0
        for ix, Ji in zip(self.links, self.J0inv):
            A = Ji @ self.J(pi[ix])
            sign, logdet = np.linalg.slogdet(A)
            out += -logdet + float(np.trace(A)) - 4.0 if sign > 0 else math.inf
        return out

    def value(self, pi, W, mu) -> float:
        f = self.fit(pi)
        for ix, t0 in zip(self.links, self.tr0):
            sign, logdet = np.linalg.slogdet(self.J(pi[ix]))
            if sign <= 0:
                return math.inf
            f += W * (-logdet + float(t0 @ pi[ix]))
        if mu > 0 and self.B.shape[0]:
            v = self.B @ pi
            if np.any(v <= 0):
                return math.inf
            f -= mu * float(np.sum(np.log(v)))
        return f

    def derivatives(self, pi, W, mu, *, barrier=True):
        """Gradient and Hessian of :meth:`value` (without the barrier: ``barrier=False``)."""
        g = self.Q @ pi - self.c
        H = self.Q.copy()
        for ix, t0 in zip(self.links, self.tr0):
            Jinv = np.linalg.inv(self.J(pi[ix]))
            A = Jinv @ self.E  # (10, 4, 4)
            g[ix] += W * (t0 - np.einsum("aii->a", A))
            H[np.ix_(ix, ix)] += W * np.einsum("aij,bji->ab", A, A)
        if barrier and mu > 0 and self.B.shape[0]:
            v = self.B @ pi
            g -= self.B.T @ (mu / v)
            H += (self.B.T * (mu / v**2)) @ self.B
        return g, H


def _newton_step(g, H) -> np.ndarray:
    """``-H^-1 g`` with ``H`` scaled to a unit diagonal (its entries span many decades); a
    singular ``H`` (a joint parameter no equation of this data involves) by least squares."""
    d = np.sqrt(np.maximum(np.diag(H), 1e-300))
    Hs = H / np.outer(d, d)
    gs = g / d
    try:
        step = sla.cho_solve(sla.cho_factor(Hs), -gs)
    except (np.linalg.LinAlgError, ValueError):
        step = np.linalg.lstsq(Hs, -gs, rcond=1e-13)[0]
    return step / d


def newton_prior(
    problem: PriorProblem, W: float, start, *, max_iter: int = 400, fixed=None, barrier=1e-2
):
    """The minimiser of ``problem`` at weight ``W > 0`` from the strictly feasible ``start``:
    damped Newton steps (backtracking keeps every pseudo-inertia positive definite and the
    non-negative parameters positive), the barrier weight of the non-negative parameters
    lowered tenfold from ``barrier`` to :data:`BARRIER_END` noise variances. ``fixed``: indices
    held at their values in ``start`` (the minimiser over the others). Returns ``(pi,
    converged, iterations)``."""
    pi = np.array(start, dtype=float)
    if not problem.feasible(pi):
        raise IdentificationError("consistent estimate: infeasible start of the Newton descent")
    free = np.setdiff1d(np.arange(pi.size), [] if fixed is None else fixed)
    mu = max(barrier, BARRIER_END) if problem.B.shape[0] else 0.0
    it = 0
    converged = False
    while True:
        f = problem.value(pi, W, mu)
        stage_done = False
        while it < max_iter:
            it += 1
            g, H = problem.derivatives(pi, W, mu)
            step = np.zeros_like(pi)
            step[free] = _newton_step(g[free], H[np.ix_(free, free)])
            dec = -float(g @ step)  # Newton decrement squared
            if not math.isfinite(dec) or dec <= 1e-10:
                stage_done = True
                break
            alpha = 1.0
            while alpha > 1e-12:
                trial = pi + alpha * step
                ft = problem.value(trial, W, mu) if problem.feasible(trial) else math.inf
                if ft <= f - 0.25 * alpha * dec:
                    break
                alpha *= 0.5
            else:  # no decrease within round-off: at the minimum to machine precision
                stage_done = True
                break
            pi, f = trial, ft
            if dec < 1e-8:
                stage_done = True
                break
        if not stage_done:
            break
        if mu <= BARRIER_END:
            converged = True
            break
        mu = max(mu * 0.1, BARRIER_END) if mu > BARRIER_END else 0.0
    return pi, converged, it


def feasible_start(problem: PriorProblem, J0s, layout, pi0) -> np.ndarray:
    """The description's (regularised) pseudo-inertias, and the joint parameters fitted to the
    data with the links held there (non-negative ones at least a thousandth of their typical
    size)."""
    from .consistent import inertial_from_pseudo

    pi = np.array(pi0, dtype=float)
    for ix, J0 in zip(layout.links, J0s):
        pi[ix] = inertial_from_pseudo(J0)
    ex = layout.extra
    if ex.size:
        links = np.setdiff1d(np.arange(pi.size), ex)
        rhs = problem.z - problem.M[:, links] @ pi[links]
        pi[ex] = np.linalg.lstsq(problem.M[:, ex], rhs, rcond=1e-12)[0]
        nn = problem.nonneg
        if nn.size:
            floor = 1e-3 * max(float(np.max(np.abs(pi[nn]))), 1e-6)
            pi[nn] = np.maximum(pi[nn], floor)
        # a third friction term strictly within its Coulomb term's bounds (Fs > -Fc, |Fa| < Fc)
        inside = np.array(pi)
        layout.project(inside)
        pi = np.where(inside != pi, 0.999 * inside, pi) if nn.size else pi
    return pi


# ---------------------------------------------------------------------------------------------
# Held-out blocks
# ---------------------------------------------------------------------------------------------
def _cut(count: int, folds: int) -> np.ndarray:
    """The block (0 .. folds-1) of each of ``count`` consecutive items, in contiguous runs."""
    return np.minimum((np.arange(count) * folds) // max(count, 1), folds - 1)


@single_threaded_blas
def block_triangles(res, data, *, folds: int = FOLDS, counts: bool = False):
    """The fit's weighted least-squares problem split into ``folds`` blocks of contiguous time
    (block ``k``: the ``k``-th of ``folds`` consecutive parts of every log): triangles ``S_k``,
    shape (folds, nb+1, nb+1), ``S_k^T S_k = [A_k b_k]^T [A_k b_k]`` over the block's rows with
    the fit's own row weights; with ``counts``, ``(S, rows)``, ``rows`` (folds,) each block's
    number of rows."""
    from .estimation import _energy_window_sd, _logs, _triangle, regressor_rows, row_weights
    from .models import (
        energy_system,
        integral_chunks,
        moving_equations,
        moving_windows,
        windows,
    )

    base = res.base
    nb = base.n
    logs = _logs(data)
    S = np.zeros((folds, nb + 1, nb + 1))
    rows = np.zeros(folds, dtype=int)

    def add(k, A):
        S[k] = _triangle(np.vstack([S[k], A]))
        rows[k] += A.shape[0]

    js = res.joint_sigma
    if res.model in ("dynamic", "integral"):
        w = row_weights(res)
        for d in logs:
            if res.model == "dynamic":
                assert d.tau is not None  # the fit's logs have torques
                block = _cut(d.m, folds)
                keep = moving_equations(base, d.dq, res.settings.get("min_velocity", 0.0))
                for k in range(folds):
                    a, b = np.flatnonzero(block == k)[[0, -1]] if np.any(block == k) else (0, -1)
                    if b < a:
                        continue
                    for c0 in range(a, b + 1, 8192):
                        c1 = min(b + 1, c0 + 8192)
                        Wr = regressor_rows(base, d, c0, c1)
                        for j in range(d.n):
                            A = w[j] * np.column_stack([Wr[:, j, :], d.tau[c0:c1, j]])
                            if keep is not None:
                                A = A[keep[c0:c1, j]]
                            add(k, A)
            else:
                window = res.settings["integral_window"]
                total = windows(d, window)[0].size
                moving = moving_windows(base, d, window, res.settings.get("min_velocity", 0.0))
                block = _cut(total, folds)
                i0 = 0
                for Wi, yi in integral_chunks(
                    base, d, window=window, integration=res.settings["integration"]
                ):
                    kk = block[i0 : i0 + Wi.shape[0]]
                    mv = None if moving is None else moving[i0 : i0 + Wi.shape[0]]
                    i0 += Wi.shape[0]
                    for k in np.unique(kk):
                        for j in range(d.n):
                            sel = kk == k if mv is None else (kk == k) & mv[:, j]
                            add(k, w[j] * np.column_stack([Wi[sel, j], yi[sel, j]]))
    elif res.model == "energy":
        window = res.settings["energy_window"]
        rule = res.settings["integration"]
        used = [d for d in logs if windows(d, window, gaps=False)[0].size > 0]
        sd = _energy_window_sd(used, window, js) if res.weighted and js is not None else None
        for i, d in enumerate(used):
            Wd, yd = energy_system(base, d, window=window, integration=rule)
            A = np.column_stack([Wd, yd])
            if sd is not None:
                A = A / sd[i][:, None]
            block = _cut(A.shape[0], folds)
            for k in range(folds):
                add(k, A[block == k])
    else:  # pragma: no cover - identify refuses other models
        raise IdentificationError(f"unknown model '{res.model}'")
    return (S, rows) if counts else S


# ---------------------------------------------------------------------------------------------
# Choice of the weight
# ---------------------------------------------------------------------------------------------
def log_evidence(problem: PriorProblem, pi, W: float) -> float:
    """``log p(z | W)`` up to a constant the same for every ``W``, by Laplace's approximation
    at ``pi``, the minimiser of ``problem`` at weight ``W > 0``: ``-fit / 2 + sum_links log
    p(J_l | W) - log det H / 2`` with ``p(J | W)`` the Wishart density of ``W + 5`` degrees of
    freedom and scale ``J0 / W`` (``exp(-W d(J, J0) / 2)`` normalised, see the module) and
    ``H`` the objective's Hessian at ``pi`` (twice the negative log posterior's; the joint
    parameters' flat priors and the factor 2 add the same constant at every weight)."""
    from scipy.stats import wishart

    value = -0.5 * problem.fit(pi)
    for ix, J0 in zip(problem.links, problem.J0s):
        J = problem.J(pi[ix])
        value += float(wishart.logpdf(0.5 * (J + J.T), df=W + 5.0, scale=J0 / W))
    _, H = problem.derivatives(pi, W, 0.0)
    d = np.sqrt(np.maximum(np.diag(H), 1e-300))
    lam = np.linalg.eigvalsh(H / np.outer(d, d))
    # a direction neither the data nor any prior constrain (a joint parameter no equation
    # involves) has the same zero curvature at every weight: left out alike
    lam = lam[lam > 1e-13 * lam[-1]]
    return value - 0.5 * (float(np.sum(np.log(lam))) + 2.0 * float(np.sum(np.log(d))))


def choose_prior_weight(
    problem: PriorProblem, start, *, candidates=CANDIDATES, progress=None
) -> tuple[float, dict, np.ndarray]:
    """The candidate weight of largest :func:`log_evidence`, the minimisers found by Newton
    descents from ``start`` (strictly feasible; the description's pseudo-inertias,
    :func:`feasible_start`) through the candidates from the strongest prior down, each warm from
    the last. Returns ``(W, record, pi)``: the record of the choice for the output (the rule,
    the candidates, their log marginal likelihoods relative to the largest, whether the choice
    is at the end of the candidates, how many descents stopped before converging) and the
    minimiser at ``W``."""
    cands = sorted({float(c) for c in candidates})[::-1]  # from the strongest prior down
    if not cands or cands[-1] <= 0:
        raise IdentificationError("consistent estimate: prior weight candidates must be > 0")
    pi = np.array(start, dtype=float)
    evidence, found, failed = [], [], 0
    for i, W in enumerate(cands):
        pi, ok, _ = newton_prior(problem, W, pi, barrier=1e-2 if i == 0 else BARRIER_END)
        failed += not ok
        evidence.append(log_evidence(problem, pi, W))
        found.append(pi)
        if progress is not None:
            progress(f"consistent estimate: prior weight {W:g}, {i + 1} of {len(cands)} done")
    best = int(np.argmax(evidence))
    top = evidence[best]
    W = cands[best]
    record = {
        "rule": (
            "largest marginal likelihood of the data (empirical Bayes: each link's "
            "pseudo-inertia Wishart-distributed about the description's, integrated by "
            "Laplace's approximation)"
        ),
        "candidates": cands[::-1],
        "log_evidence": [float(e - top) for e in evidence[::-1]],
        "log_evidence_unit": "natural log, relative to the largest",
        "chosen": W,
        "at_grid_end": best in (0, len(cands) - 1),
        "newton_not_converged": failed,
    }
    return W, record, found[best]


# ---------------------------------------------------------------------------------------------
# Data or prior, per link
# ---------------------------------------------------------------------------------------------
def mass_profile(problem: PriorProblem, pi, W: float, start) -> list[dict]:
    """Per link, the fit with its mass held at the description's: the minimiser of the same
    objective at weight ``W`` with that one parameter fixed, and how much worse it fits the
    data than ``pi`` [noise variances]. Reached as the estimate itself is: from ``start`` (the
    description's pseudo-inertias, which have that mass, see :func:`feasible_start`) by Newton
    descents at the weights of :data:`PATH` above ``W``, strongest first, then at ``W``;
    ``objective_increase``: how much higher the whole objective (fit and priors) is there;
    ``converged`` false when the last descent stopped at its iteration limit (the increase is
    then that of the point reached). ``fit_increase`` can be slightly negative: the descent
    minimises the whole objective, not the fit alone, so with the mass held the fit may come
    out better than the estimate's while the whole objective does not. The description's mass
    is that of the prior's pseudo-inertia (regularised when the description's is singular)."""
    f0, v0 = problem.fit(pi), problem.value(pi, W, 0.0)
    out = []
    for ix in problem.links:
        x, mu = np.array(start, dtype=float), 1e-2
        for w in sorted((c for c in PATH if c > W), reverse=True):
            x = newton_prior(problem, w, x, fixed=[ix[9]], barrier=mu)[0]
            mu = BARRIER_END  # warm: the barrier already at its final weight
        x, ok, _ = newton_prior(problem, W, x, fixed=[ix[9]], barrier=mu)
        out.append(
            {
                "mass": float(start[ix[9]]),
                "fit_increase": problem.fit(x) - f0,
                "objective_increase": problem.value(x, W, 0.0) - v0,
                "converged": ok,
            }
        )
    return out


def _relative_eigenvalues(A, B) -> np.ndarray:
    """The eigenvalues of ``A`` relative to the symmetric positive semidefinite ``B``
    (``A v = lambda B v``), over the directions where ``B`` is positive beyond round-off: ``B``
    of a covariance whose prior-held directions are ``1 / W`` times larger than the data's is
    positive definite in exact arithmetic but need not be in floating point, where a Cholesky
    factorisation of it fails."""
    A, B = 0.5 * (A + A.T), 0.5 * (B + B.T)
    lam, V = np.linalg.eigh(B)
    keep = lam > 1e-12 * max(float(lam[-1]), 1e-300)
    T = V[:, keep] / np.sqrt(lam[keep])
    return np.linalg.eigvalsh(T.T @ A @ T)


def link_report(problem: PriorProblem, pi, W: float, names, pi0, Y, *, start) -> list[dict]:
    """Per link, what the consistent estimate owes to the data and to the priors.

    With ``C = 2 H^-1`` (``H`` the objective's Hessian at ``pi``), the share of a parameter
    combination's variance that the priors account for is ``-d ln var / d ln W``, from
    ``W C H_p C / 2`` against ``C`` (``H_p`` the Hessian of the summed divergences): 0 when the
    data alone fix it, 1 when the priors do. Reported: the mass, its standard deviation
    ``sqrt(C_mm)`` and the priors' share of its variance (a link's mass alone is seldom
    identifiable: the data tie it to other links' parameters, whose priors then hold it); the
    link's identifiable directions (the combinations of its 10 parameters alone that the base
    parameters determine, ``Y``'s row space within the link's coordinates) and how many of them
    the data determine (share below :data:`DATA_SHARE`, generalised eigenvalues over that
    subspace) and their mean share; the verdict: ``data`` (mean share below
    :data:`DATA_SHARE`), ``partly`` (above, but some direction by the data), ``prior`` (none,
    or the link has none). The mass's own verdict (:func:`mass_profile`): ``data`` when
    holding it at the description's makes the fit worse by at least :data:`MASS_EVIDENCE`
    noise variances (``mass_fit_increase``), with the standard deviation the data give it,
    ``|m - m0| / sqrt(increase)`` (``mass_data_std``); ``data+prior`` when the fit alone does
    not reject the description's mass but the whole objective does, by at least as much
    (``mass_objective_increase``): the priors tie the mass to the link's other parameters,
    which the data fix, and so place it away from the description's (``mass_data_std`` from
    that increase); else ``prior``, the description's mass within the estimate's resolution;
    ``unknown`` when that fit stopped before it converged (``mass_profile_converged``).
    ``start``: the description's pseudo-inertias and fitted joint parameters
    (:func:`feasible_start`). ``pi0``: the description's classical vector (its masses
    beside)."""
    # the barrier at its final weight: a non-negative parameter at its bound is held there
    _, H = problem.derivatives(pi, W, BARRIER_END)
    _, Hfit = problem.derivatives(pi, 0.0, BARRIER_END)
    Hp = H - Hfit  # W x the priors' Hessian
    d = np.sqrt(np.maximum(np.diag(H), 1e-300))
    C = 2.0 * np.linalg.pinv(H / np.outer(d, d), rcond=1e-14, hermitian=True) / np.outer(d, d)
    Cp = 0.5 * C @ Hp @ C  # the priors' part of the covariance
    profile = mass_profile(problem, pi, W, start)  # constrained descents per link
    Ys = Y / np.maximum(np.linalg.norm(Y, axis=0), 1e-300)  # columns of unit norm
    _, sv, Vt = np.linalg.svd(Ys)
    rows = Vt[: int(np.sum(sv > 1e-9 * sv[0]))]  # orthonormal basis of the row space
    out: list[dict] = []
    for nm, ix in zip(names, problem.links):
        Cl, Pl = C[np.ix_(ix, ix)], Cp[np.ix_(ix, ix)]
        # directions v of the link alone in the row space: |(I - V^T V) e_ix v| = 0
        E = np.zeros((Y.shape[1], 10))
        E[ix, np.arange(10)] = 1.0
        Nl = sla.null_space(E - rows.T @ (rows @ E), rcond=1e-9)
        share = np.zeros(0)
        if Nl.size:
            A, B = Nl.T @ Pl @ Nl, Nl.T @ Cl @ Nl
            share = np.clip(_relative_eigenvalues(A, B), 0, 1)
        mass_share = float(np.clip(Pl[9, 9] / Cl[9, 9], 0.0, 1.0)) if Cl[9, 9] > 0 else 1.0
        held = profile[len(out)]
        rise, whole = held["fit_increase"], held["objective_increase"]
        m = float(pi[ix[9]])
        if rise >= MASS_EVIDENCE:
            mass_verdict, evidence = "data", rise
        elif whole >= MASS_EVIDENCE:
            mass_verdict, evidence = "data+prior", whole
        else:
            mass_verdict, evidence = "prior", 0.0
        by_data = int(np.sum(share < DATA_SHARE))
        mean = float(share.mean()) if share.size else 1.0
        verdict = "data" if mean < DATA_SHARE else ("partly" if by_data else "prior")
        out.append(
            {
                "link": nm,
                "mass": float(pi[ix[9]]),
                "description_mass": float(pi0[ix[9]]),
                "mass_std": float(math.sqrt(max(Cl[9, 9], 0.0))),
                "mass_prior_share": mass_share,
                "identifiable_directions": int(share.size),
                "directions_by_data": by_data,
                "directions_prior_share": mean,
                "verdict": verdict,
                "mass_verdict": mass_verdict if held["converged"] else "unknown",
                "mass_fit_increase": float(rise),
                "mass_objective_increase": float(whole),
                "mass_data_std": (
                    abs(m - held["mass"]) / math.sqrt(evidence) if evidence > 0 else None
                ),
                "mass_profile_converged": bool(held["converged"]),
            }
        )
    return out
