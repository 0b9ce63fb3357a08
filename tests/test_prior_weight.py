"""The prior's weight of the consistent estimate chosen from the data, and the per-link report.

References: logs simulated by inverse dynamics with known parameters (seeded noise), the known
masses, the regrouping of the known parameters with the unconstrained estimate's standard
deviations, Laplace's approximation of the marginal likelihood written out here (classical
regressor, each penalised fit solved by scipy over Cholesky factors of the pseudo-inertias, the
Wishart density written out, no Newton descent and no base parameters involved), and the scatter
of estimates over noise realisations.
"""

from __future__ import annotations

import json

import mindyn
import numpy as np
import pytest
from mindyn import cli
from mindyn.control import SensorNoise, simulate_inverse
from mindyn.identification import identify
from mindyn.identification.consistent import (
    _Layout,
    _prior_matrices,
    consistent_estimate,
    description_vector,
    inertial_from_pseudo,
    pseudo_inertia,
)
from mindyn.identification.data import JointData, write_csv
from mindyn.identification.estimation import residual_correlation
from mindyn.identification.excitation import excitation_limits, random_trajectory
from mindyn.identification.prior import (
    MASS_EVIDENCE,
    PriorProblem,
    block_triangles,
    choose_prior_weight,
    feasible_start,
    mass_profile,
    newton_prior,
)
from scipy.optimize import minimize
from scipy.special import multigammaln

ROBOT = "zcr07s"  # every link of its description physically consistent
FACTORS = [1.3, 0.8, 1.2, 0.7, 1.25, 0.9]  # the truth: each link's parameters scaled


def _log(robot, truth, *, slow=1.0, noise=0.02, coulomb=0.0, rate=100.0, seed=1):
    """Inverse-dynamics log along a random trajectory whose last half of the joints move with
    ``slow`` times the velocity and acceleration limits; white torque noise of ``noise`` times
    each joint's RMS torque; ``coulomb``: a smooth Coulomb friction of that many RMS torques that
    the identified model leaves out (a drive effect, as on real arms)."""
    lim, _ = excitation_limits(robot, margin=0.05)
    lim = dict(lim)
    k = robot.n // 2
    for key in ("velocity", "acceleration"):
        v = np.array(lim[key], float)
        v[k:] *= slow
        lim[key] = v
    traj = random_trajectory(robot, seed=3, limits=lim)
    clean = simulate_inverse(robot, traj, rate=rate, params=truth)
    rms = np.sqrt(np.mean(clean.tau**2, axis=0))
    log = simulate_inverse(
        robot, traj, rate=rate, params=truth, noise=SensorNoise(torque=noise * rms), seed=seed
    )
    tau = log.tau + coulomb * rms * np.tanh(log.dq / 0.05)
    return JointData(log.t, log.q, log.dq, log.ddq_true, tau, "sim")


def _truth(robot):
    return (robot.params.reshape(robot.n, 10) * np.array(FACTORS)[:, None]).reshape(-1)


def _masses(c):
    return np.array([c.classical[ix[9]] for ix in _Layout(c.base).links])


def test_default_weight_gives_plausible_masses_where_links_are_poorly_excited():
    """Wrist joints moving at a twentieth of their limits, and a friction the model leaves out:
    without a prior the consistent estimate puts some link's mass more than 3 times off the
    truth; with the weight chosen from the data every mass is within a factor 1.6 of it."""
    robot = mindyn.load(ROBOT)
    truth = _truth(robot)
    data = _log(robot, truth, slow=0.05, coulomb=0.1)
    res = identify(robot, data, rsd_threshold=None)
    m_true = truth.reshape(robot.n, 10)[:, 9]
    bare = consistent_estimate(res, prior_weight=0.0)
    ratio = _masses(bare) / m_true
    assert np.any((ratio > 3) | (ratio < 1 / 3)), ratio
    auto = consistent_estimate(res)
    assert auto.weight_choice is not None and auto.prior_weight == auto.weight_choice["chosen"]
    ratio = _masses(auto) / m_true
    assert np.all((ratio < 1.6) & (ratio > 1 / 1.6)), ratio
    assert np.all(auto.min_eig >= -1e-9)


def test_well_excited_log_lets_the_data_dominate():
    """Every joint excited, 1 % noise, no model error, the truth far from the description
    (links scaled by 0.5 to 2): the estimate with the chosen weight has every base parameter
    within 4 standard deviations of the truth's and every mass within 4 of its reported standard
    deviations; every link with parameter combinations of its own that the base parameters
    determine (the row space of the regrouping within its coordinates, counted here) is
    reported as determined by the data, the first link (none: its only inertia about the
    vertical axis is regrouped with the others') as held by the prior."""
    robot = mindyn.load("stanford")
    truth = robot.params.reshape(6, 10) * np.array([2.0, 0.5, 1.8, 0.5, 2.0, 0.6])[:, None]
    truth = truth.reshape(-1)
    data = _log(robot, truth, noise=0.01)
    res = identify(robot, data, rsd_threshold=None)
    c = consistent_estimate(res)
    beta = res.base.values(truth)
    assert np.all(np.abs(c.full - beta) <= 4 * res.std), (c.full - beta) / res.std
    layout = _Layout(res.base)
    Y = res.base.Y
    P = np.linalg.pinv(Y) @ Y  # projector onto the row space
    m_true = truth.reshape(robot.n, 10)[:, 9]
    for ix, lk, m in zip(layout.links, c.links, m_true):
        E = np.zeros((Y.shape[1], 10))
        E[ix, np.arange(10)] = 1.0
        own = 10 - np.linalg.matrix_rank(E - P @ E, tol=1e-8)
        assert lk["identifiable_directions"] == own, lk
        assert lk["verdict"] == ("data" if own else "prior"), lk
        assert abs(lk["mass"] - m) <= 4 * lk["mass_std"], lk
    assert c.links[0]["identifiable_directions"] == 0


@pytest.mark.parametrize(
    "model, friction", [("dynamic", True), ("integral", True), ("energy", False)]
)
def test_held_out_blocks_add_up_to_the_fit(model, friction):
    """The blocks of the cross-validation carry the fit's own rows and weights: their summed
    normal matrices equal the fit's (rows left out below min_velocity, per-joint weights of the
    weighted fit, per-window weights of the energy model)."""
    robot = mindyn.load("puma560_3")
    data = _log(robot, robot.params, noise=0.02, coulomb=0.05 if friction else 0.0)
    res = identify(
        robot, data, model=model, friction=friction, rsd_threshold=None, integral_window=10
    )
    S = block_triangles(res, data, folds=4)
    G = sum(Sk.T @ Sk for Sk in S)
    ls = res.reduced
    F = np.zeros((ls.c + 1, ls.c + 1))
    F[: ls.c, : ls.c] = ls.R
    F[: ls.c, ls.c] = ls.z
    F[ls.c, ls.c] = np.sqrt(ls.rho)
    F[:, : ls.c] *= ls.norms  # back to the unscaled columns
    ref = F.T @ F
    assert np.allclose(G, ref, rtol=1e-8, atol=1e-10 * np.abs(ref).max())
    assert all(np.any(Sk) for Sk in S)


def _cholesky_fit(Phi, tau, s2, J0inv, W, start, fixed=None):
    """The penalised fit ``|Phi pi - tau|^2 / s2 + W sum d(J, J0)`` by scipy over ``J = L L^T``
    per link (classical inertial parameters only); ``fixed=(link, mass)``: that link's mass held
    (its factor's last row scaled to norm ``sqrt(mass)``)."""
    n = len(J0inv)
    tril = np.tril_indices(4)

    def unpack(x):
        pi, Js = np.zeros(10 * n), []
        for j in range(n):
            L = np.zeros((4, 4))
            L[tril] = x[10 * j : 10 * j + 10]
            if fixed is not None and fixed[0] == j:
                L[3] *= np.sqrt(fixed[1]) / np.linalg.norm(L[3])
            J = L @ L.T
            S = J[:3, :3]
            inertia = np.trace(S) * np.eye(3) - S
            pi[10 * j : 10 * j + 10] = [
                *inertia[np.triu_indices(3)][[0, 1, 2, 3, 4, 5]],
                *J[:3, 3],
                J[3, 3],
            ]
            Js.append(J)
        return pi, Js

    def f(x):
        pi, Js = unpack(x)
        r = Phi @ pi - tau
        out = r @ r / s2
        for J, Ji in zip(Js, J0inv):
            A = Ji @ J
            sign, logdet = np.linalg.slogdet(A)
            if sign <= 0:
                return 1e30
            out += W * (-logdet + np.trace(A) - 4)
        return out

    x0 = np.concatenate(
        [np.linalg.cholesky(pseudo_inertia(start[10 * j : 10 * j + 10]))[tril] for j in range(n)]
    )
    opt = minimize(f, x0, method="BFGS", options={"gtol": 1e-9, "maxiter": 20000})
    if fixed is not None:  # polish: the scaled row makes the problem less well conditioned
        opt = minimize(f, opt.x, method="BFGS", options={"gtol": 1e-11})
    return unpack(opt.x)[0]


def _wishart_logpdf(J, W, J0):
    """log of the Wishart density of ``W + 5`` degrees of freedom and scale ``J0 / W`` at the
    4 x 4 ``J``, written out (Anderson, *An Introduction to Multivariate Statistical Analysis*,
    7.2)."""
    nu, p = W + 5.0, 4
    scale = J0 / W
    return (
        0.5 * (nu - p - 1) * np.linalg.slogdet(J)[1]
        - 0.5 * np.trace(np.linalg.solve(scale, J))
        - 0.5 * nu * p * np.log(2.0)
        - 0.5 * nu * np.linalg.slogdet(scale)[1]
        - multigammaln(0.5 * nu, p)
    )


def test_log_evidence_equals_a_laplace_approximation_written_out():
    """Two-link arm, ordinary least squares: the log marginal likelihood of each candidate
    weight, relative to the others, equals Laplace's approximation written out here on the
    classical regressor (negative log posterior ``|Phi pi - tau|^2 / (2 s^2)`` minus each link's
    Wishart log density, its minimiser by scipy over Cholesky factors, its Hessian by finite
    differences of the prior terms); the weight chosen is the largest of those."""
    robot = mindyn.load("planar2")
    truth = (robot.params.reshape(2, 10) * np.array([1.4, 0.6])[:, None]).reshape(-1)
    data = _log(robot, truth, noise=0.1, rate=20.0)
    res = identify(robot, data, weighted=False, rsd_threshold=None)
    layout = _Layout(res.base)
    pi0 = description_vector(res.base)
    J0s = _prior_matrices(res.base, layout, pi0, None)
    Phi = robot.regressor(data.q, data.dq, data.ddq)  # (m, n, 20)
    A, y = Phi.reshape(-1, 20), data.tau.reshape(-1)
    r = y - A @ np.linalg.lstsq(A, y, rcond=None)[0]
    s2 = r @ r / (y.size - np.linalg.matrix_rank(A))
    cands = (0.1, 3.16, 100.0)
    ls = res.reduced
    problem = PriorProblem((ls.R * ls.norms) @ res.base.Y, ls.z, s2, layout, J0s)
    W, record, _ = choose_prior_weight(
        problem, feasible_start(problem, J0s, layout, pi0), candidates=cands
    )
    J0inv = [np.linalg.inv(J) for J in J0s]

    def prior_terms(pi):
        return -sum(
            _wishart_logpdf(pseudo_inertia(pi[10 * j : 10 * j + 10]), w, J0s[j]) for j in range(2)
        )

    brute = []
    for w in cands:
        pi = _cholesky_fit(A, y, s2, J0inv, w, pi0)
        h = 1e-5 * np.maximum(np.abs(pi), 1e-2)
        Hp = np.zeros((20, 20))
        for a in range(20):
            for b in range(20):
                e_a, e_b = np.eye(20)[a] * h[a], np.eye(20)[b] * h[b]
                Hp[a, b] = (
                    prior_terms(pi + e_a + e_b)
                    - prior_terms(pi + e_a - e_b)
                    - prior_terms(pi - e_a + e_b)
                    + prior_terms(pi - e_a - e_b)
                ) / (4 * h[a] * h[b])
        H = A.T @ A / s2 + 0.5 * (Hp + Hp.T)
        rr = A @ pi - y
        brute.append(-0.5 * rr @ rr / s2 - prior_terms(pi) - 0.5 * np.linalg.slogdet(H)[1])
    brute = np.array(brute) - max(brute)
    assert record["candidates"] == list(cands)
    np.testing.assert_allclose(record["log_evidence"], brute, rtol=1e-3, atol=0.05)
    assert W == cands[int(np.argmax(brute))]
    assert np.sort(brute)[-2] < -1.0  # the choice is no near tie


def _ar1(rng, shape, sd, rho):
    """First-order autoregressive noise along axis 0, stationary, of standard deviation sd."""
    e = np.zeros(shape)
    white = rng.standard_normal(shape) * sd * np.sqrt(1 - rho**2)
    e[0] = rng.standard_normal(shape[1]) * sd
    for t in range(1, shape[0]):
        e[t] = rho * e[t - 1] + white[t]
    return e


def test_residual_correlation_matches_the_scatter_of_the_estimates():
    """The estimates' standard deviations count the correlation their residuals show. Torque
    noise correlated from sample to sample (first-order autoregressive, coefficient
    0.3, so the variance of a slowly varying regressor's estimate is about (1 + 0.3) / (1 - 0.3)
    = 1.86 times that of independent noise), and white noise: over 30 realisations, the mean
    variance inflation measured from each fit's residuals equals the one of the estimates'
    scatter, the trace of their covariance over that of ordinary least squares' formula
    (independent residuals), within 30 % (the truncated Bartlett weights see a little less
    than the 1.86)."""
    robot = mindyn.load(ROBOT)
    lim, _ = excitation_limits(robot, margin=0.05)
    traj = random_trajectory(robot, seed=3, limits=lim)
    clean = simulate_inverse(robot, traj, rate=100.0, params=robot.params)
    sd = 0.02 * np.sqrt(np.mean(clean.tau**2))  # the same on every joint (no weights needed)
    exact = JointData(clean.t, clean.q, clean.dq, clean.ddq_true, clean.tau, "sim")
    base = identify(robot, exact, weighted=False, rsd_threshold=None).base
    A = base.regressor(clean.q, clean.dq, clean.ddq_true).reshape(-1, base.n)
    rng = np.random.default_rng(5)
    for rho in (0.3, 0.0):
        est, measured, naive, var_reported = [], [], [], []
        for _ in range(30):
            e = _ar1(rng, clean.tau.shape, sd, rho)
            d = JointData(clean.t, clean.q, clean.dq, clean.ddq_true, clean.tau + e, "sim")
            res = identify(robot, d, weighted=False, rsd_threshold=None)
            measured.append(residual_correlation(res, d)[0])
            var_reported.append(res.std**2)
            beta, rss = np.linalg.lstsq(A, d.tau.reshape(-1), rcond=None)[:2]
            est.append(beta)
            naive.append(rss[0] / (A.shape[0] - base.n))
        C = np.cov(np.array(est).T)
        # the covariance against s^2 (A^T A)^-1, the formula for independent residuals
        scatter = np.trace(A.T @ A @ C) / np.mean(naive) / base.n
        assert 0.7 < np.mean(measured) / scatter < 1.3, (rho, np.mean(measured), scatter)
        # the estimates' reported variances carry the measured factor (the log is not
        # low-passed, so the data path's factor is 1): on the mean over the parameters, they
        # are the scatter's
        spread = np.mean(np.mean(var_reported, axis=0) / np.diag(C))
        assert 0.7 < spread < 1.3, (rho, spread)
        if rho:
            assert scatter > 1.5  # the correlation matters here


def test_cli_default_weight_reported(tmp_path, capsys):
    robot = mindyn.load(ROBOT)
    data = _log(robot, robot.params, noise=0.01)
    fit = tmp_path / "fit.csv"
    write_csv(fit, data.t, data.q, data.tau, dq=data.dq)
    out = tmp_path / "id.json"
    assert cli.main(["identify", ROBOT, str(fit), "--consistent", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    doc = json.loads(out.read_text())
    ce = doc["consistent_estimate"]
    choice = ce["prior_weight_choice"]
    assert ce["prior_weight"] == choice["chosen"] in choice["candidates"]
    assert len(choice["log_evidence"]) == len(choice["candidates"])
    assert max(choice["log_evidence"]) == 0.0
    assert choice["log_evidence"][choice["candidates"].index(choice["chosen"])] == 0.0
    assert [lk["link"] for lk in ce["links"]] == robot.link_names[1:]
    assert ce["fit"]["estimate"] == "consistent"
    assert doc["fit"]["estimate"] == "unconstrained least squares"
    assert f"prior weight {choice['chosen']:g} chosen by the largest marginal likelihood" in text
    noise = ce["noise_variance_factor"]
    assert noise["factor"] == max(noise["data_path"], noise["residuals"], 1.0)
    assert "one noise variance: the residual variance x" in text
    assert text.index("Headline, the physically consistent estimate") < text.index(
        "Unconstrained least-squares estimate"
    )
    assert "consistent estimate:" in text or "consistent estimate" in text


def test_mass_verdict_from_the_fit_with_the_mass_held_at_the_description():
    """Well-excited log, 1 % noise; the truth's third link is nearly a point mass three times
    the description's at the description's centre of mass (its pseudo-inertia at the
    description's mass would need three times the second moments the torques show): that mass
    is reported as determined by the data, the truth within 3 of its data's standard
    deviations. The first link's mass, which no torque depends on (its regressor column is zero
    here, vertical first axis), is reported as held by the priors, the fit no worse with it at
    the description's."""
    robot = mindyn.load(ROBOT)
    truth = robot.params.copy().reshape(robot.n, 10)
    J0 = pseudo_inertia(truth[2])
    m0, c = J0[3, 3], J0[:3, 3] / J0[3, 3]
    mt = 3.0 * m0
    Jt = np.zeros((4, 4))
    Jt[:3, :3] = mt * (np.outer(c, c) + 1e-4 * np.eye(3))  # radius of gyration 1 cm
    Jt[:3, 3] = Jt[3, :3] = mt * c
    Jt[3, 3] = mt
    truth[2] = inertial_from_pseudo(Jt)
    truth = truth.reshape(-1)
    data = _log(robot, truth, noise=0.01)
    Phi = robot.regressor(data.q, data.dq, data.ddq)
    assert np.all(Phi[..., 9] == 0.0)  # the first link's mass: no torque depends on it
    res = identify(robot, data, rsd_threshold=None)
    c = consistent_estimate(res)
    first, third = c.links[0], c.links[2]
    assert third["mass_verdict"] == "data", third
    assert third["mass_fit_increase"] >= MASS_EVIDENCE
    assert third["mass_data_std"] > 0
    assert abs(third["mass"] - mt) <= 3 * third["mass_data_std"], third
    assert third["mass"] > 2 * m0
    assert first["mass_verdict"] == "prior", first
    assert abs(first["mass_fit_increase"]) < 0.1 * MASS_EVIDENCE
    assert all(lk["mass_profile_converged"] for lk in c.links)


def test_a_mass_the_prior_moves_with_the_moments_the_data_fix_is_not_held_by_the_prior():
    """The truth's third link is the description's scaled by 0.2 (same centre of mass and radii
    of gyration, a fifth of the mass and moments). Its mass alone hardly changes the fit (held
    at the description's, the fit is not 4 noise variances worse), but the data fix its moments
    and the log-det prior ties the mass to them: the estimate sits far from the description's
    mass, nearer the truth, and is reported as determined by the data through the prior
    (``data+prior``: the whole objective is worse at the description's mass), not as held by
    the prior."""
    robot = mindyn.load(ROBOT)
    truth = robot.params.copy().reshape(robot.n, 10)
    truth[2] *= 0.2
    data = _log(robot, truth.reshape(-1), noise=0.01)
    c = consistent_estimate(identify(robot, data, rsd_threshold=None))
    third = c.links[2]
    m0, mt = third["description_mass"], truth[2, 9]
    assert third["mass_fit_increase"] < MASS_EVIDENCE, third
    assert third["mass_objective_increase"] >= MASS_EVIDENCE, third
    assert third["mass_verdict"] == "data+prior", third
    assert abs(third["mass"] - mt) < 0.5 * abs(third["mass"] - m0), third
    assert third["mass_data_std"] > 0
    # a link reported as held by the prior has the description's mass within the estimate's
    # resolution: the whole objective not 4 noise variances worse there
    for lk in c.links:
        if lk["mass_verdict"] == "prior":
            assert lk["mass_objective_increase"] < MASS_EVIDENCE, lk


def test_mass_profile_equals_a_brute_force_minimisation():
    """Two-link arm, the second link's truth nearly a point mass three times the description's:
    the fit with each mass held at the description's, from the Newton descent of the profile,
    equals a minimisation written out here (scipy over Cholesky factors of each pseudo-inertia,
    the held link's last row scaled to the fixed mass, so no constraint is needed)."""
    robot = mindyn.load("planar2")
    truth = robot.params.copy().reshape(2, 10)
    J0 = pseudo_inertia(truth[1])
    m0, c = J0[3, 3], J0[:3, 3] / J0[3, 3]
    Jt = np.zeros((4, 4))
    Jt[:3, :3] = 3 * m0 * (np.outer(c, c) + 1e-4 * np.eye(3))
    Jt[:3, 3] = Jt[3, :3] = 3 * m0 * c
    Jt[3, 3] = 3 * m0
    truth[1] = inertial_from_pseudo(Jt)
    data = _log(robot, truth.reshape(-1), noise=0.02, rate=20.0)
    res = identify(robot, data, weighted=False, rsd_threshold=None)
    layout = _Layout(res.base)
    pi0 = description_vector(res.base)
    J0s = _prior_matrices(res.base, layout, pi0, None)
    Phi = robot.regressor(data.q, data.dq, data.ddq).reshape(-1, 20)
    y = data.tau.reshape(-1)
    r = y - Phi @ np.linalg.lstsq(Phi, y, rcond=None)[0]
    s2 = r @ r / (y.size - np.linalg.matrix_rank(Phi))
    W = 1.0
    problem = PriorProblem(Phi, y, s2, layout, J0s)
    pi, ok, _ = newton_prior(problem, W, feasible_start(problem, J0s, layout, pi0))
    assert ok
    prof = mass_profile(problem, pi, W, feasible_start(problem, J0s, layout, pi0))
    J0inv = [np.linalg.inv(J) for J in J0s]
    ref_free = _cholesky_fit(Phi, y, s2, J0inv, W, pi0)
    f_free = _penalised(Phi, y, s2, J0inv, W, ref_free)
    f_newton = problem.fit(pi) + W * problem.prior(pi)
    assert abs(f_newton - f_free) <= 1e-6 * abs(f_free)  # the same minimum
    for link in range(2):
        m_fix = float(inertial_from_pseudo(J0s[link])[9])
        ref = _cholesky_fit(Phi, y, s2, J0inv, W, pi0, fixed=(link, m_fix))
        assert abs(ref[10 * link + 9] - m_fix) < 1e-12
        rise = (_residual(Phi, y, ref) - _residual(Phi, y, pi)) / s2
        assert prof[link]["converged"]
        assert abs(prof[link]["mass"] - m_fix) < 1e-12
        assert abs(prof[link]["fit_increase"] - rise) <= 1e-3 * max(1.0, abs(rise)), link
    assert prof[1]["fit_increase"] > MASS_EVIDENCE  # the point mass: rejected at m0


def _residual(Phi, y, pi):
    r = Phi @ pi - y
    return r @ r


def _penalised(Phi, y, s2, J0inv, W, pi):
    out = _residual(Phi, y, pi) / s2
    for j, Ji in enumerate(J0inv):
        A = Ji @ pseudo_inertia(pi[10 * j : 10 * j + 10])
        out += W * (-np.linalg.slogdet(A)[1] + np.trace(A) - 4)
    return out


def test_cli_report_plots_the_consistent_estimate(tmp_path, monkeypatch):
    """identify --consistent --report: the torque plots are the consistent estimate's (the
    headline), each title says so, and the relative error of the torques plotted (recomputed
    here from them) is the JSON's consistent_estimate.fit, not the unconstrained fit."""
    import mindyn.identification.report as report

    drawn = []

    def capture(path, t, tau, tau_hat, title="", unit="N m"):
        drawn.append((title, np.array(tau), np.array(tau_hat)))
        return path

    monkeypatch.setattr(report, "plot_torques", capture)
    robot = mindyn.load(ROBOT)
    data = _log(robot, _truth(robot), noise=0.01, coulomb=0.05)
    fit = tmp_path / "fit.csv"
    write_csv(fit, data.t, data.q, data.tau, dq=data.dq)
    out = tmp_path / "id.json"
    argv = ["identify", ROBOT, str(fit), "--consistent", "--prior-weight", "1e4"]
    assert cli.main([*argv, "--json", str(out), "--report", str(tmp_path / "rep")]) == 0
    doc = json.loads(out.read_text())
    title, tau, hat = drawn[0]
    assert "consistent estimate" in title
    rel = np.linalg.norm(tau - hat) / np.linalg.norm(tau)
    cons = doc["consistent_estimate"]["fit"]["overall_relative"]
    assert abs(rel - cons) <= 1e-9 * cons
    assert abs(rel - doc["fit"]["overall_relative"]) > 1e-3 * cons  # not the unconstrained one


def test_window_model_noise_factor_not_measured_is_not_reported_as_one(tmp_path, capsys):
    """The energy model's windows carry weights of their own: the residuals' own correlation
    factor is not measured. The JSON recorded it as 1.0 and the output as '(1: not measured
    ...)', a measurement it never made; now null, the output saying it is not measured, and
    the factor used is the data path's."""
    robot = mindyn.load(ROBOT)
    data = _log(robot, robot.params, noise=0.01)
    fit = tmp_path / "fit.csv"
    write_csv(fit, data.t, data.q, data.tau, dq=data.dq)
    out = tmp_path / "id.json"
    argv = ["identify", ROBOT, str(fit), "--model", "energy", "--energy-window", "4"]
    argv += ["--consistent", "--prior-weight"]
    assert cli.main([*argv, "1", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    noise = json.loads(out.read_text())["consistent_estimate"]["noise_variance_factor"]
    assert noise["residuals"] is None and noise["residuals_rule"].startswith("not measured")
    assert noise["factor"] == max(noise["data_path"], 1.0)
    line = next(t for t in text.splitlines() if "one noise variance" in t)
    assert "(1: not measured" not in line and "factor: not measured" in line


def test_a_negative_fit_increase_of_the_mass_profile_is_explained(tmp_path, capsys):
    """The per-link column 'fit worse with the mass held at the description's' read negative
    (-0.087 on a real log) without a word: the fit with the mass held minimises the whole
    objective (fit plus priors), not the fit alone. On a log whose light third link makes some
    of these values negative, every link's whole objective is no lower with its mass held (the
    estimate is its minimiser), and each negative value is named with that explanation."""
    robot = mindyn.load(ROBOT)
    truth = robot.params.copy().reshape(robot.n, 10)
    truth[2] *= 0.2
    data = _log(robot, truth.reshape(-1), noise=0.01)
    fit, out = tmp_path / "fit.csv", tmp_path / "id.json"
    write_csv(fit, data.t, data.q, data.tau, dq=data.dq)
    assert cli.main(["identify", ROBOT, str(fit), "--consistent", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    links = json.loads(out.read_text())["consistent_estimate"]["links"]
    better = [lk for lk in links if lk["mass_fit_increase"] < 0]
    assert better, links  # the case the explanation is for
    assert all(lk["mass_objective_increase"] >= -1e-6 for lk in links), links
    (line,) = [x for x in text.splitlines() if x.startswith("  (a negative fit increase, ")]
    for lk in better:
        assert f"{lk['link']} {lk['mass_fit_increase']:.3g} (whole objective" in line, line
    assert "minimises the whole objective, fit plus priors, not the fit alone" in line


def _ar1_z(rho: float, **fit) -> tuple[float, list]:
    """RMS of (estimate - truth) / std over 20 realisations of first-order autoregressive torque
    noise of coefficient ``rho`` (2 % of the RMS torque) on a log not low-passed, fitted with
    every base parameter and options ``fit``; the truth from the dynamic model on the exact
    accelerations, independent of any window. Also each fit's ``settings.std_correlation``."""
    robot = mindyn.load(ROBOT)
    lim, _ = excitation_limits(robot, margin=0.05)
    traj = random_trajectory(robot, seed=3, limits=lim)
    clean = simulate_inverse(robot, traj, rate=100.0, params=robot.params)
    sd = 0.02 * np.sqrt(np.mean(clean.tau**2))
    exact = JointData(clean.t, clean.q, clean.dq, clean.ddq_true, clean.tau, "sim")
    base = identify(robot, exact, weighted=False, rsd_threshold=None).base
    truth = identify(robot, exact, base=base, weighted=False, rsd_threshold=None).values
    rng, z, records = np.random.default_rng(7), [], []
    for _ in range(20):
        e = _ar1(rng, clean.tau.shape, sd, rho)
        d = JointData(clean.t, clean.q, clean.dq, clean.ddq_true, clean.tau + e, "sim")
        res = identify(robot, d, base=base, weighted=False, rsd_threshold=None, **fit)
        records.append(res.settings["std_correlation"])
        z.append((res.values - truth) / res.std)
    return float(np.sqrt(np.mean(np.square(z)))), records


def test_residual_correlation_follows_noise_correlated_over_many_samples():
    """Torque noise correlated over many samples (first-order autoregressive, coefficient 0.9:
    a slowly varying regressor's estimate has about (1 + 0.9) / (1 - 0.9) = 19 times the
    variance independent noise would give it) on a log not low-passed (the data path's factor
    is 1): the measured factor must carry most of it. The Bartlett lag is chosen from the
    residuals' own correlation (Newey & West's automatic selection, about 45 lags here): the
    RMS of (estimate - truth) / std over 20 realisations is about 1.45 (a lag fixed by the
    number of samples alone, 6 here, leaves about 2.0). The rest is the downward bias of a
    covariance measured from residuals over about 300 effectively independent samples for
    52 parameters, which the bound leaves room for."""
    rms, records = _ar1_z(0.9)
    assert all(r["data_path"] == 1.0 for r in records)  # not low-passed
    assert 0.75 < rms < 1.7, rms


def test_integral_model_residual_correlation_follows_noise_correlated_over_many_windows():
    """The integral model measures its residuals' correlation as the dynamic model does, over
    its windows: the same noise, in windows of 4 sample intervals (correlated over about 2.5
    windows). The RMS of (estimate - truth) / std is about 1.4 with the measured factor,
    about 2.3 with the windows taken as independent (the factor not measured)."""
    rms, records = _ar1_z(0.9, model="integral", integral_window=4)
    assert all(r["data_path"] == 1.0 and r["residuals"] is not None for r in records)
    assert all("windows" in r["residuals_rule"] for r in records)
    assert 0.75 < rms < 1.75, rms
