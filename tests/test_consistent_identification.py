"""Physically consistent identification and payload identification.

References: data simulated by inverse dynamics with known parameters (noise-free or with seeded
noise), the regrouping of those known parameters, and an independent solve of the same small
problems by scipy.optimize over a Cholesky factorisation of each pseudo-inertia (``J = L L^T``,
positive semidefinite by construction, no cone solver involved).
"""

from __future__ import annotations

import contextlib
import io
import json

import mindyn
import numpy as np
import pytest
from mindyn import cli
from mindyn.control import SensorNoise, simulate, simulate_inverse
from mindyn.identification import identify
from mindyn.identification.consistent import (
    EIG_TOL,
    consistent_estimate,
    identify_consistent,
    identify_payload,
    inertial_from_pseudo,
    pseudo_inertia,
)
from mindyn.identification.data import JointData
from mindyn.identification.excitation import random_trajectory
from scipy.optimize import least_squares, minimize

ROBOT = "zcr07s"  # a description whose every link is physically consistent
SMALL = "planar2"  # for the independent solves by scipy (20 unknowns)


def make_log(robot, params, seed=1, noise=0.0, rate=50.0, traj_seed=1):
    """Inverse-dynamics log along a random trajectory; torques with white noise of ``noise``
    times each joint's RMS torque; accelerations as simulated (no differentiation error)."""
    traj = random_trajectory(robot, seed=traj_seed)
    clean = simulate_inverse(robot, traj, rate=rate, params=params)
    sd = noise * np.sqrt(np.mean(clean.tau**2, axis=0))
    log = simulate_inverse(
        robot, traj, rate=rate, params=params, noise=SensorNoise(torque=sd), seed=seed
    )
    return JointData(log.t, log.q, log.dq, log.ddq_true, log.tau, f"sim{seed}")


def scaled_links(robot, factors):
    """The description with each link's 10 inertial parameters scaled (a positive factor keeps
    a pseudo-inertia positive semidefinite)."""
    p = robot.params.reshape(robot.n, 10) * np.asarray(factors)[:, None]
    return p.reshape(-1)


def test_pseudo_inertia_round_trip_and_meaning():
    # a point mass m at c: J = m [c; 1][c; 1]^T, rank 1
    m, c = 2.0, np.array([0.1, -0.2, 0.3])
    inertia = m * (c @ c * np.eye(3) - np.outer(c, c))
    p = np.concatenate([inertia[np.triu_indices(3)], m * c, [m]])
    v = np.append(c, 1.0)
    np.testing.assert_allclose(pseudo_inertia(p), m * np.outer(v, v), atol=1e-15)
    np.testing.assert_allclose(inertial_from_pseudo(pseudo_inertia(p)), p, atol=1e-15)


def test_consistent_optimum_equals_unconstrained_when_it_is_consistent():
    """(a) noise-free data of a physical robot: the constrained optimum is the unconstrained
    one; its base parameters equal the least-squares estimate and the truth's."""
    robot = mindyn.load(ROBOT)
    truth = scaled_links(robot, [1.1, 0.9, 1.2, 0.8, 1.05, 0.95])  # differs from the description
    data = make_log(robot, truth)
    res = identify(robot, data, rsd_threshold=None)
    cons = consistent_estimate(res, prior_weight=0.0)
    beta_true = res.base.values(truth)
    scale = np.linalg.norm(beta_true)
    # tolerance: noise-free data, the least-squares solve is exact to ~1e-12 relative
    assert np.linalg.norm(cons.full - res.full) / scale < 1e-9
    assert np.linalg.norm(cons.full - beta_true) / scale < 1e-8
    assert np.all(cons.min_eig >= -EIG_TOL)
    assert cons.violating_links() == []


def _residual_problem(res):
    ls = res.reduced
    M = (ls.R * ls.norms) @ res.base.Y
    nb = res.base.n
    s2 = ls.rho / (ls.r - nb)
    return M, ls.z, s2


def _cholesky_pi(x, n, P, links, extra, nonneg):
    """Classical vector from per-link lower-triangular factors (10 entries each) and the other
    parameters (squared where they must be >= 0)."""
    pi = np.zeros(P)
    tril = np.tril_indices(4)
    for j, ix in enumerate(links):
        L = np.zeros((4, 4))
        L[tril] = x[10 * j : 10 * j + 10]
        pi[ix] = inertial_from_pseudo(L @ L.T)
    e = x[10 * n :]
    pi[extra] = np.where(nonneg, e**2, e)
    return pi


def _cholesky_start(pi0, n, links, extra, nonneg, eps=1e-6):
    """Lower-triangular factors L (J = L L^T) of each link's pseudo-inertia J + eps I (eps = 0:
    of J itself, also when singular: L^T is the R of a QR of a square root of J)."""
    x = []
    for ix in links:
        J = pseudo_inertia(pi0[ix]) + eps * np.eye(4)
        lam, V = np.linalg.eigh(J)
        r = np.linalg.qr((V * np.sqrt(np.clip(lam, 0, None))).T, mode="r")
        L = r.T * np.where(np.diag(r) < 0, -1.0, 1.0)  # J = L L^T, diagonal >= 0
        x.extend(L[np.tril_indices(4)])
    e = pi0[extra]
    x.extend(np.where(nonneg, np.sqrt(np.abs(e)), e))
    return np.array(x)


def test_prior_optimum_matches_independent_scipy_solve():
    """(b) data of an inconsistent parameter vector (a two-link arm, link 2 with a negative
    moment of inertia about its joint axis), prior weight 1: the cone solver's minimiser of
    fit + W * log-det divergence equals scipy's over Cholesky factors (the objective is strictly
    convex in the pseudo-inertias: one minimiser)."""
    robot = mindyn.load(SMALL)
    bad = robot.params.reshape(robot.n, 10).copy()
    bad[1, 5] = -bad[1, 5]  # negative ZZ2
    data = make_log(robot, bad.reshape(-1), noise=0.01)
    res = identify(robot, data, rsd_threshold=None)
    W = 1.0
    cons = consistent_estimate(res, prior_weight=W)
    assert cons.violating_links() != []  # the unconstrained estimate is inconsistent
    assert np.all(cons.min_eig >= -EIG_TOL)  # (c)

    from mindyn.identification.consistent import _Layout, _prior_matrices, description_vector

    layout = _Layout(res.base)
    n, P = robot.n, len(layout.names)
    M, z, s2 = _residual_problem(res)
    pi0 = description_vector(res.base)
    J0inv = [np.linalg.inv(J0) for J0 in _prior_matrices(res.base, layout, pi0, None)]

    def objective(x):
        return objective_pi(_cholesky_pi(x, n, P, layout.links, layout.extra, layout.nonneg))

    def objective_pi(pi):
        f = np.sum((M @ pi - z) ** 2) / s2
        for ix, Ji in zip(layout.links, J0inv):
            A = Ji @ pseudo_inertia(pi[ix])
            sign, logdet = np.linalg.slogdet(A)
            if sign <= 0:
                return 1e30
            f += W * (-logdet + np.trace(A) - 4)
        return f

    bfgs = {"maxiter": 20000, "gtol": 1e-8}
    x0 = _cholesky_start(pi0, n, layout.links, layout.extra, layout.nonneg)
    opt = minimize(objective, x0, method="BFGS", options=bfgs)
    ours = objective_pi(cons.classical)
    x_ours = _cholesky_start(cons.classical, n, layout.links, layout.extra, layout.nonneg, 0.0)
    assert abs(objective(x_ours) - ours) <= 1e-9 * abs(ours)  # the factors reproduce ours
    # The conic solver alone stops at a relative duality gap of about 2e-5 here (the fit, ~66 000
    # noise variances of an inconsistent robot, dwarfs the log-det terms); the estimate refines
    # its answer by a smooth descent, so its value is the minimum to REL = 1e-7 (of which BFGS's
    # own stopping takes most). Ours is at least as low as scipy's own minimisation from the
    # description (BFGS may stop above the minimum, never below it) ...
    REL = 1e-7
    assert ours <= opt.fun + REL * abs(opt.fun)
    # ... and scipy started at ours finds nothing lower beyond REL: the objective is strictly
    # convex in the pseudo-inertias, so there is one minimiser
    polish = minimize(objective, x_ours, method="BFGS", options=bfgs)
    gap = ours - polish.fun
    assert gap <= REL * abs(ours)
    # the minimisers agree: the objective rises quadratically in the whitened base parameters
    # (units of one noise standard deviation), so a value gap `gap` allows a distance of about
    # sqrt(gap)
    pi_ref = _cholesky_pi(polish.x, n, P, layout.links, layout.extra, layout.nonneg)
    Lw = (res.reduced.R * res.reduced.norms) / np.sqrt(s2)  # whitened: units of one std
    dist = np.linalg.norm(Lw @ (cons.full - res.base.Y @ pi_ref))
    assert dist <= 2.0 * np.sqrt(max(gap, 0.0)) + 0.05, (dist, gap)


def boundary_fit():
    """A log of the robot with a negative viscous friction on joint 2 (1 % noise) and its
    unconstrained fit with friction: the consistent optimum without a prior sits on the
    boundary Fv2 = 0."""
    robot = mindyn.load(ROBOT)
    p = robot.parameters(rotor=False, friction=True).reshape(robot.n, 12)
    p[:, 10] = [0.5, -0.4, 0.3, 0.2, 0.1, 0.1]  # Fv, one negative
    p[:, 11] = [0.8, 0.6, 0.5, 0.3, 0.2, 0.2]  # Fc
    data = make_log(robot, p.reshape(-1), noise=0.01)
    return data, identify(robot, data, friction=True, rsd_threshold=None, min_velocity=0.0)


def test_boundary_optimum_without_prior_matches_bounded_least_squares():
    """(b, c) prior weight 0, data of a robot with a negative viscous friction on joint 2: the
    optimum sits on the boundary Fv2 = 0. Independent route: scipy's bounded linear least
    squares of the same weighted problem in the base parameters with Fv, Fc >= 0 (the inertial
    part of the optimum is inside the consistent set, so only the bounds are active)."""
    from scipy.optimize import lsq_linear

    data, res = boundary_fit()
    cons = consistent_estimate(res, prior_weight=0.0)
    assert np.all(cons.min_eig >= -EIG_TOL)
    names = res.base.names
    lo = np.array([0.0 if nm[:2] in ("Fv", "Fc") else -np.inf for nm in names])
    ls = res.reduced
    ref = lsq_linear(ls.R, ls.z, bounds=(lo / ls.norms, np.inf), tol=1e-14, method="bvls")
    beta_ref = ref.x / ls.norms
    assert beta_ref[names.index("Fv2")] == 0.0  # the bound is active
    assert cons.full[names.index("Fv2")] >= 0.0
    # The same minimiser up to the tie-break: the estimate's fit is within TIE_BREAK_SLACK noise
    # variances of the optimum's; for this strongly convex quadratic that bounds its whitened
    # distance from the minimiser by sqrt(TIE_BREAK_SLACK) (1 % margin for solver tolerance).
    from mindyn.identification.consistent import TIE_BREAK_SLACK

    M, z, s2 = _residual_problem(res)
    Lw = (ls.R * ls.norms) / np.sqrt(s2)
    f_ref = float(np.sum((Lw @ beta_ref - z / np.sqrt(s2)) ** 2))
    f_ours = float(np.sum((Lw @ cons.full - z / np.sqrt(s2)) ** 2))
    assert f_ours <= f_ref + TIE_BREAK_SLACK * 1.01
    assert np.linalg.norm(Lw @ (cons.full - beta_ref)) <= np.sqrt(TIE_BREAK_SLACK) * 1.01
    assert cons.fit_increase > 1.0  # the constraint is active: the optimum is on the boundary


def test_prior_weight_pulls_toward_description_monotonically():
    """(e) the summed log-det divergence from the description falls as W grows, and the fit
    worsens."""
    robot = mindyn.load(ROBOT)
    truth = scaled_links(robot, [1.3, 0.7, 1.4, 0.6, 1.2, 0.8])
    data = make_log(robot, truth, noise=0.01)
    res = identify(robot, data, rsd_threshold=None)
    div, fit = [], []
    for W in (0.01, 1.0, 100.0):
        c = consistent_estimate(res, prior_weight=W)
        div.append(c.prior_divergence)
        fit.append(c.fit_increase)
    assert div[0] > div[1] > div[2]
    assert fit[0] < fit[1] < fit[2]


def test_identify_consistent_api_and_mass_matrix():
    robot = mindyn.load(ROBOT)
    data = make_log(robot, robot.params, noise=0.01)
    c = identify_consistent(robot, data, friction=False, rsd_threshold=None)
    doc = c.to_dict()
    assert doc["consistent"] is True
    assert list(doc["classical"]) == robot.parameter_names()
    assert list(doc["pseudo_inertia_min_eig"]) == robot.link_names[1:]
    assert doc["total_mass"] == pytest.approx(sum(robot.params.reshape(6, 10)[:, 9]), rel=0.2)
    assert c.mass_matrix_min_eig(data) > 0
    with pytest.raises(ValueError, match="prior_weight"):
        consistent_estimate(c.unconstrained, prior_weight=-1)


def test_consistent_model_simulates_stably_along_the_trajectory():
    """4: the identified consistent model, driven by computed torque with the same model along
    the fit trajectory, stays on it (a mass matrix not positive definite would stop the
    integration with an error)."""
    robot = mindyn.load(ROBOT)
    data = make_log(robot, robot.params, noise=0.01)
    c = identify_consistent(robot, data, rsd_threshold=None)
    log = simulate(
        robot, data, rate=data.rate, duration=data.t[-1] - data.t[0], params=c.robot_params
    )
    assert np.all(np.isfinite(log.q))
    # computed torque with its own model: what remains is the torque held over each 20 ms
    # control period (a few mrad); an unstable model would diverge from the ~1 rad motion
    assert np.max(log.info["max_tracking_error"]) < 0.01


# ---------------------------------------------------------------------------------------------
# Payload
# ---------------------------------------------------------------------------------------------
def _payload():
    m, c = 1.5, np.array([0.02, -0.01, 0.05])
    ic = np.array([[0.004, 0.0003, -0.0002], [0.0003, 0.005, 0.0001], [-0.0002, 0.0001, 0.003]])
    io = ic + m * (c @ c * np.eye(3) - np.outer(c, c))
    return np.concatenate([io[np.triu_indices(3)], m * c, [m]]), m, c, ic


def _arm_doc(robot):
    base = mindyn.base_parameters(robot)
    return {
        "robot": robot.name,
        "base_names": base.names,
        "base_values": base.values(robot.params).tolist(),
        "rotor": False,
        "friction": False,
        "offset": False,
    }


def _with_payload(robot, phi):
    p = robot.params.copy()
    p[-10:] += phi
    return p


def test_payload_recovered_exactly_from_noise_free_data():
    """(d) noise-free: the 10 parameters within 1e-6 relative (the arm's torques are exact)."""
    robot = mindyn.load(ROBOT)
    phi, m, c, ic = _payload()
    data = make_log(robot, _with_payload(robot, phi))
    res = identify_payload(robot, _arm_doc(robot), data)
    assert res.rank == 10
    assert np.linalg.norm(res.values - phi) / np.linalg.norm(phi) <= 1e-6
    d = res.derived()
    assert abs(d["mass"] - m) / m <= 1e-6
    np.testing.assert_allclose(d["com"], c, atol=1e-6)
    np.testing.assert_allclose(d["inertia_com"], ic[np.triu_indices(3)], atol=1e-6)
    assert np.linalg.norm(res.consistent - phi) / np.linalg.norm(phi) <= 1e-6


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_payload_mass_within_two_percent_at_one_percent_noise(seed):
    """(d) 1 % torque noise (of each joint's RMS torque), 20 s at 100 Hz: the payload's
    standard deviation of mass is about 0.3 %, so 2 % is more than 5 sigma."""
    robot = mindyn.load(ROBOT)
    phi, m, _, _ = _payload()
    data = make_log(robot, _with_payload(robot, phi), seed=seed, noise=0.01, rate=100.0)
    res = identify_payload(robot, _arm_doc(robot), data)
    assert abs(res.derived()["mass"] - m) / m <= 0.02
    assert abs(res.derived(consistent=True)["mass"] - m) / m <= 0.02
    # the reported sigma explains the error (within 5 sigma)
    assert abs(res.values[9] - m) <= 5 * res.std[9]


def test_payload_standard_deviation_matches_the_scatter_over_noise_realisations():
    """A low-passed, decimated log (the data path of identify-payload) with white torque noise
    of 1 % of each joint's RMS torque: over 16 noise realisations the payload mass scatters as
    its reported standard deviation says (the ratio is 1.2 here; without the factor for the
    filtered noise's correlation and with unweighted joints it was 4). Reference: the
    realisations' own sample standard deviation."""
    from mindyn.identification.preprocess import preprocess

    robot = mindyn.load(ROBOT)
    phi, m, _, _ = _payload()
    masses, stds = [], []
    for seed in range(16):
        data = make_log(robot, _with_payload(robot, phi), seed=seed, noise=0.01, rate=250.0)
        res = identify_payload(robot, _arm_doc(robot), preprocess(data), consistent=False)
        masses.append(res.values[9])
        stds.append(res.std[9])
    ratio = np.std(masses, ddof=1) / np.mean(stds)
    assert 0.6 <= ratio <= 1.8, (ratio, np.std(masses, ddof=1), np.mean(stds))
    assert abs(np.mean(masses) - m) <= 4 * np.std(masses, ddof=1) / np.sqrt(len(masses))
    assert "low-passed noise's correlation" in res.std_rule, res.std_rule


def test_payload_arm_sensitivity_is_the_weighted_least_squares_map():
    """The payload estimate moves by ``-H e`` for an error ``e`` of the arm's base values (at the
    fit's joint weights): ``H`` equals the weighted least-squares solution of the arm's base
    regressor on the last link's classical regressor columns, both formed here with the
    robot's and the base set's public regressors, and ``arm_covariance`` is ``H Sigma H^T`` of
    the covariance the arm's JSON holds."""
    robot = mindyn.load(ROBOT)
    phi, _, _, _ = _payload()
    data = make_log(robot, _with_payload(robot, phi), noise=0.01)
    doc = _arm_doc(robot)
    base = mindyn.base_parameters(robot)
    rng = np.random.default_rng(5)
    L = rng.standard_normal((base.n, base.n)) * 1e-3
    doc["initial"] = {"covariance": (L @ L.T).tolist()}
    res = identify_payload(robot, doc, data, consistent=False)
    w = np.tile(1.0 / res.joint_sigma, data.m)[:, None]  # equations sample by sample
    A = robot.regressor(data.q, data.dq, data.ddq)[..., -10:].reshape(-1, 10) * w
    B = base.regressor(data.q, data.dq, data.ddq).reshape(-1, base.n) * w
    H = np.linalg.lstsq(A, B, rcond=None)[0]
    np.testing.assert_allclose(res.arm_sensitivity, H, rtol=1e-8, atol=1e-10 * np.abs(H).max())
    np.testing.assert_allclose(res.arm_covariance, H @ L @ L.T @ H.T, rtol=1e-7, atol=1e-14)
    own = identify_payload(robot, _arm_doc(robot), data, consistent=False)
    assert own.arm_covariance is None and "not counted" in own.std_rule
    np.testing.assert_allclose(res.covariance, own.covariance + res.arm_covariance, rtol=1e-9)


@pytest.mark.parametrize("seed", [1, 2])
def test_payload_standard_deviations_cover_the_arm_estimate_error(tmp_path, seed):
    """A description whose wrist is off (inertias x 2.5, first moments and masses x 1.4 in the
    simulated robot), 1 % torque noise: the payload's parameters through the arm's consistent
    estimate were up to 13.5 of their standard deviations off the truth (the arm's error was
    not counted; its least-squares estimate up to 8); with the arm estimate's covariance
    carried through, every one is within 3.5."""
    robot = mindyn.load(ROBOT)
    truth = scaled_links(robot, [1, 1, 1, 1, 1, 1]).reshape(6, 10)
    truth[3:, :6] *= 2.5
    truth[3:, 6:] *= 1.4
    truth = truth.reshape(-1)
    phi, _, _, _ = _payload()
    fit, pay = tmp_path / "fit.csv", tmp_path / "pay.csv"
    _write_log(fit, make_log(robot, truth, seed=seed, noise=0.01, rate=100.0))
    loaded = truth + _with_payload(robot, phi) - robot.params
    _write_log(pay, make_log(robot, loaded, seed=seed + 10, noise=0.01, rate=100.0, traj_seed=2))
    out, pj = tmp_path / "id.json", tmp_path / "payload.json"
    with contextlib.redirect_stdout(io.StringIO()):
        assert cli.main(["identify", ROBOT, str(fit), "--consistent", "--json", str(out)]) == 0
        argv = ["identify-payload", ROBOT, str(out), str(pay), "--no-consistent", "--json"]
        assert cli.main([*argv, str(pj)]) == 0
    doc = json.loads(pj.read_text())
    z = (np.array(doc["values"]) - phi) / np.array(doc["std"])
    assert np.all(np.abs(z) < 3.5), z
    assert "arm estimate's covariance" in doc["std_rule"]


def test_payload_boundary_optimum_matches_scipy():
    """(b) a payload whose parameters break the triangle inequality: the consistent estimate is
    on the boundary (smallest eigenvalue 0) and equals scipy's least squares over a Cholesky
    factor of its pseudo-inertia (on the weighted equations the fit solves)."""
    robot = mindyn.load(ROBOT)
    phi, _, _, _ = _payload()
    phi = phi.copy()
    phi[0] += 3 * (phi[3] + phi[5])  # XX > YY + ZZ
    data = make_log(robot, _with_payload(robot, phi), noise=0.01)
    res = identify_payload(robot, _arm_doc(robot), data)
    assert res.min_eig < 0
    assert res.consistent_min_eig >= -EIG_TOL
    assert res.consistent_min_eig <= 1e-6  # on the boundary
    from mindyn.identification.estimation import _Reduced

    base = mindyn.base_parameters(robot)
    Wl = robot.regressor(data.q, data.dq, data.ddq)[..., -10:].reshape(-1, 10)
    y = (data.tau - base.regressor(data.q, data.dq, data.ddq) @ base.values(robot.params)).ravel()
    # the fit weights each joint's equations by 1 / its residual sd after a first OLS pass
    e = y - Wl @ np.linalg.lstsq(Wl, y, rcond=None)[0]
    sd = np.sqrt(np.mean(e.reshape(-1, robot.n) ** 2, axis=0) * len(y) / (len(y) - 10))
    w = np.tile(1.0 / sd, len(y) // robot.n)
    Wl, y = Wl * w[:, None], y * w
    ls = _Reduced(Wl, y)
    tril = np.tril_indices(4)

    Rs = ls.R * ls.norms  # |Wl phi - y|^2 = |Rs phi - z|^2 + rho: the same problem, small

    def resid(x):
        L = np.zeros((4, 4))
        L[tril] = x
        return Rs @ inertial_from_pseudo(L @ L.T) - ls.z

    x0 = np.linalg.cholesky(pseudo_inertia(_payload()[0]))[tril]
    ref = least_squares(resid, x0, xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=5000)
    L = np.zeros((4, 4))
    L[tril] = ref.x
    phi_ref = inertial_from_pseudo(L @ L.T)
    assert ls.r == Wl.shape[0]
    # same residual to 1e-6 relative and same parameters within 1e-3 relative (the boundary
    # optimum is unique: the regressor has full rank)
    f_ours = np.sum((Wl @ res.consistent - y) ** 2)
    assert f_ours <= (np.sum(ref.fun**2) + ls.rho) * (1 + 1e-6)
    assert np.linalg.norm(res.consistent - phi_ref) / np.linalg.norm(phi_ref) < 1e-3


def test_payload_refused_when_geometry_hides_parameters():
    """A planar arm's last link: only some of its 10 parameters act on the joints."""
    robot = mindyn.load("planar3")
    data = make_log(robot, robot.params)
    with pytest.raises(mindyn.identification.IdentificationError, match="rank [0-9] of 10"):
        identify_payload(robot, _arm_doc(robot), data)


# ---------------------------------------------------------------------------------------------
# CLI
# ---------------------------------------------------------------------------------------------
def _write_log(path, data):
    from mindyn.identification.data import write_csv

    write_csv(path, data.t, data.q, data.tau, dq=data.dq)


def test_cli_consistent_and_payload(tmp_path, capsys):
    robot = mindyn.load(ROBOT)
    fit = tmp_path / "fit.csv"
    _write_log(fit, make_log(robot, robot.params, noise=0.005, rate=100.0))
    out = tmp_path / "id.json"
    assert cli.main(["identify", ROBOT, str(fit), "--consistent", "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["consistent"] is True
    assert set(doc["classical"]) == set(robot.parameter_names())
    assert min(doc["pseudo_inertia_min_eig"].values()) >= -EIG_TOL
    assert doc["consistent_estimate"]["mass_matrix_min_eig"] > 0
    text = capsys.readouterr().out
    assert "Physically consistent estimate" in text
    phi, m, _, _ = _payload()
    pay = tmp_path / "payload.csv"
    _write_log(pay, make_log(robot, _with_payload(robot, phi), noise=0.005, rate=100.0))
    pj = tmp_path / "payload.json"
    assert cli.main(["identify-payload", ROBOT, str(out), str(pay), "--json", str(pj)]) == 0
    pdoc = json.loads(pj.read_text())
    # filtered derivatives and the arm's own estimation error: 5 % on the mass
    assert abs(pdoc["unconstrained"]["mass"] - m) / m < 0.05


@pytest.mark.parametrize(
    "argv, message",
    [
        (["identify", ROBOT, "{fit}", "--consistent", "--prior-weight", "-1"], "--prior-weight"),
        (["identify", ROBOT, "{fit}", "--prior-weight", "1"], "--prior-weight"),
        (["identify-payload", "puma560", "{json}", "{fit}"], "not 'puma560'"),
        (["identify-payload", ROBOT, "{missing}", "{fit}"], "does not exist"),
        (["identify-payload", ROBOT, "{fit}", "{fit}"], "not a JSON file"),
        (
            ["identify-payload", ROBOT, "{json}", "{fit}", "--min-velocity", "0"],
            "--min-velocity applies only to an arm identified with friction",
        ),
        (
            ["identify-payload", ROBOT, "{json}", "{fit}", "--min-velocity", "0.01"],
            "--min-velocity applies only to an arm identified with friction",
        ),
    ],
)
def test_cli_bad_input_one_line(tmp_path, capsys, argv, message):
    """(f) one-line errors naming the argument or file."""
    robot = mindyn.load(ROBOT)
    fit = tmp_path / "fit.csv"
    _write_log(fit, make_log(robot, robot.params, rate=20.0))
    js = tmp_path / "id.json"
    js.write_text(json.dumps(_arm_doc(robot)))
    args = [a.format(fit=fit, json=js, missing=tmp_path / "none.json") for a in argv]
    assert cli.main(args) != 0
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert message in err


def test_a_min_velocity_for_an_arm_without_friction_is_refused():
    """min_velocity leaves out the equations of slow joints for the arm's Coulomb friction: an
    arm identified without friction has none, and the option would be ignored."""
    robot = mindyn.load(ROBOT)
    data = make_log(robot, robot.params, rate=20.0)
    with pytest.raises(mindyn.ArgumentError, match="^min_velocity applies only to an arm"):
        identify_payload(robot, _arm_doc(robot), data, min_velocity=0.0, consistent=False)
    with pytest.raises(mindyn.ArgumentError, match="^min_velocity applies only to an arm"):
        identify_payload(robot, _arm_doc(robot), data, min_velocity=0.01, consistent=False)


def test_the_tie_break_slack_is_stated_with_the_fit_increase(tmp_path, capsys):
    """Without a prior on an optimum at the boundary (a negative viscous friction), the
    estimate is the one nearest the description within TIE_BREAK_SLACK noise variances of the
    optimum's fit: the fit increase printed read 1 noise variance more than the optimum's with
    no word of it. The result records the slack and the optimum's own increase (against scipy's
    bounded least squares of the same problem); the terminal line states both; with a prior
    (no tie-break) nothing of it is said."""
    from mindyn.identification.consistent import TIE_BREAK_SLACK
    from mindyn.identification.data import write_csv
    from scipy.optimize import lsq_linear

    data, res = boundary_fit()
    cons = consistent_estimate(res, prior_weight=0.0)
    names, ls = res.base.names, res.reduced
    lo = np.array([0.0 if nm[:2] in ("Fv", "Fc") else -np.inf for nm in names])
    ref = lsq_linear(ls.R, ls.z, bounds=(lo / ls.norms, np.inf), tol=1e-14, method="bvls")
    free = np.linalg.lstsq(ls.R, ls.z, rcond=None)[0]
    _, _, s2 = _residual_problem(res)
    optimum = (np.sum((ls.R @ ref.x - ls.z) ** 2) - np.sum((ls.R @ free - ls.z) ** 2)) / s2
    tie = cons.tie_break
    assert tie is not None and tie["slack"] == TIE_BREAK_SLACK
    assert abs(tie["optimum_fit_increase"] - optimum) <= 1e-3 * optimum + 1e-3, (tie, optimum)
    assert optimum - 1e-3 <= cons.fit_increase <= optimum + TIE_BREAK_SLACK * 1.01
    assert cons.to_dict()["consistent_estimate"]["tie_break"] == tie
    # the command line
    log, out = tmp_path / "log.csv", tmp_path / "id.json"
    write_csv(log, data.t, data.q, data.tau, dq=data.dq)
    argv = ["identify", ROBOT, str(log), "--friction", "--consistent", "--min-velocity", "0"]
    assert cli.main([*argv, "--prior-weight", "0", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    ce = json.loads(out.read_text())["consistent_estimate"]
    (line,) = [x for x in text.splitlines() if x.startswith("Physically consistent estimate")]
    assert f"fit {ce['fit_increase_noise_variances']:.4g} noise variances worse" in line
    opt = ce["tie_break"]["optimum_fit_increase"]
    assert f"(the optimum's {opt:.4g} plus at most 1 noise variance of designed slack" in line
    assert cli.main([*argv, "--prior-weight", "1e-3", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert json.loads(out.read_text())["consistent_estimate"]["tie_break"] is None
    assert "designed slack" not in text


def test_shares_of_a_link_at_a_vanishing_prior_weight(tmp_path):
    """At a prior weight of 1e-9 the covariance's prior-held directions are 1e9 times the
    data's: its block over a link's identifiable directions lost positive definiteness to
    round-off and the generalised eigenvalue solve failed with scipy's raw message. The
    relative eigenvalues equal scipy's where the matrix is positive definite, are finite where
    round-off made it indefinite, and the command runs."""
    from mindyn.identification.prior import _relative_eigenvalues
    from scipy.linalg import eigh

    rng = np.random.default_rng(0)
    X = rng.standard_normal((6, 6))
    A, B = X @ X.T, X.T @ X + np.eye(6)
    np.testing.assert_allclose(
        np.sort(_relative_eigenvalues(A, B)), eigh(A, B, eigvals_only=True), rtol=1e-10
    )
    V = np.linalg.qr(rng.standard_normal((6, 6)))[0]
    B = V @ np.diag([1e9, 1e3, 1.0, 1e-2, 1e-3, -1e-9]) @ V.T
    assert np.all(np.isfinite(_relative_eigenvalues(A, B)))
    data, _ = boundary_fit()
    fit = tmp_path / "fit.csv"
    _write_log(fit, data)
    argv = ["identify", ROBOT, str(fit), "--friction", "--consistent", "--min-velocity", "0"]
    assert cli.main([*argv, "--prior-weight", "1e-9"]) == 0


def _least_consistent_fit(res, free_link=None, n_starts=3):
    """The least fit increase of a consistent estimate [noise variances], independently: BFGS
    over Cholesky factors of the pseudo-inertias (no cone solver; link ``free_link``'s 10
    parameters free instead), from the description and from perturbed starts, the lowest kept
    (BFGS may stop above the minimum, never below)."""
    from mindyn.identification.consistent import _Layout, description_vector

    layout = _Layout(res.base)
    n, P = res.base.robot.n, len(layout.names)
    M, z, s2 = _residual_problem(res)
    ls = res.reduced
    beta = np.linalg.lstsq(ls.R * ls.norms, z, rcond=None)[0]
    fit_ls = float(np.sum((ls.R @ (beta * ls.norms) - z) ** 2))
    pi0 = description_vector(res.base)

    def objective(x):
        pi = _cholesky_pi(x, n, P, layout.links, layout.extra, layout.nonneg)
        if free_link is not None:
            pi[layout.links[free_link]] = x[10 * free_link : 10 * free_link + 10]
        return (float(np.sum((M @ pi - z) ** 2)) - fit_ls) / s2

    x0 = _cholesky_start(pi0, n, layout.links, layout.extra, layout.nonneg)
    if free_link is not None:
        x0[10 * free_link : 10 * free_link + 10] = pi0[layout.links[free_link]]
    rng = np.random.default_rng(0)
    best = np.inf
    for k in range(n_starts):
        x = x0 if k == 0 else x0 * (1 + 0.2 * rng.standard_normal(x0.size))
        best = min(best, minimize(objective, x, method="BFGS", options={"gtol": 1e-9}).fun)
    return best


def test_cost_of_consistency_is_at_the_link_whose_values_no_body_has():
    """A two-link arm whose link 2 has a negative moment of inertia about its joint axis (1 %
    noise): consistency costs the fit, the least increase equals an independent minimisation
    over Cholesky factors, lifting link 2's constraint recovers all of it, and lifting link 1's
    what the same minimisation with link 1's parameters free recovers (its mass regroups into
    link 1: a heavier link 2 takes a smaller moment of inertia, only partly)."""
    robot = mindyn.load(SMALL)
    bad = robot.params.reshape(robot.n, 10).copy()
    bad[1, 5] = -bad[1, 5]  # negative ZZ2
    data = make_log(robot, bad.reshape(-1), noise=0.01)
    res = identify(robot, data, rsd_threshold=None)
    cost = consistent_estimate(res, prior_weight=0.0).constraint_cost
    first, second = robot.link_names[1:]
    total = cost["total"]
    ref = _least_consistent_fit(res, n_starts=1)
    assert total > 100  # far from negligible: the data ask for a non-physical link 2
    # the cone solver's optimum and BFGS's agree to their stopping tolerances (1e-6 relative of
    # a fit term of ~1e5 noise variances plus its own size)
    assert abs(total - ref) <= 1e-4 * ref + 1.0, (total, ref)
    assert cost["links"][second] >= total - 1.0  # all of it recovered: the unconstrained fit
    # lifting link 1: its best fit is approached as link 2's mass grows without bound (held by
    # the solvers' tolerances), so BFGS stops visibly above it (0.5 % here): ours no worse,
    # and within 2 % of BFGS's
    ours, theirs = total - cost["links"][first], _least_consistent_fit(res, 0, n_starts=1)
    assert 0.05 * total < total - theirs < 0.95 * total  # partly: the case is not degenerate
    assert 0.98 * theirs <= ours <= theirs + 1.0, (ours, theirs)
    assert cost["major"][0] == second
    assert cost["joint_terms"] is None  # no friction or rotor terms


def test_cost_of_consistency_of_a_negative_friction_is_the_joint_terms(tmp_path):
    """The negative viscous friction on joint 2 of :func:`boundary_fit`: the joint terms' bounds
    account for the cost, which equals the bounded least-squares optimum's (scipy's bvls) fit
    increase; no link's constraint recovers any of it; a consistent robot's cost is zero."""
    from scipy.optimize import lsq_linear

    data, res = boundary_fit()
    cost = consistent_estimate(res, prior_weight=0.0).constraint_cost
    ls = res.reduced
    names = res.base.names
    lo = np.array([0.0 if nm[:2] in ("Fv", "Fc") else -np.inf for nm in names])
    ref = lsq_linear(ls.R, ls.z, bounds=(lo / ls.norms, np.inf), tol=1e-14, method="bvls")
    M, z, s2 = _residual_problem(res)
    free = lsq_linear(ls.R, ls.z, tol=1e-14)
    bound_cost = (
        float(np.sum((ls.R @ ref.x - z) ** 2)) - float(np.sum((ls.R @ free.x - z) ** 2))
    ) / s2
    assert bound_cost > 10
    assert abs(cost["total"] - bound_cost) <= 1e-4 * bound_cost + 0.05, (cost["total"], bound_cost)
    assert cost["joint_terms"] >= cost["total"] - 0.05
    assert max(cost["links"].values()) <= 0.05
    assert cost["major"] == ["joint terms"]
    fit = tmp_path / "fit.csv"
    _write_log(fit, data)
    argv = ["identify", ROBOT, str(fit), "--friction", "--consistent", "--min-velocity", "0"]
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert cli.main([*argv, "--prior-weight", "0", "--json", str(tmp_path / "id.json")]) == 0
    assert "most at joint terms (100 %)" in out.getvalue()
    doc = json.loads((tmp_path / "id.json").read_text())
    assert doc["consistent_estimate"]["constraint_cost"]["major"] == ["joint terms"]

    robot = mindyn.load(ROBOT)
    truth = scaled_links(robot, [1.1, 0.9, 1.2, 0.8, 1.05, 0.95])
    ok = identify(robot, make_log(robot, truth, noise=0.01), rsd_threshold=None)
    fine = consistent_estimate(ok, prior_weight=0.0).constraint_cost
    assert fine["total"] < 1.0 and fine["links"] is None and fine["major"] == []


def test_cost_of_consistency_reports_a_failed_solve(monkeypatch):
    """A solve of the cost that fails (both solvers) leaves its figure None and says so in the
    notes, while the consistent estimate itself is still returned."""
    from mindyn.identification import consistent as C
    from mindyn.identification.errors import IdentificationError

    data, res = boundary_fit()
    real = C._run

    def failing(prob, notes, what, *args, **kwargs):
        if what.startswith("cost of consistency"):
            raise IdentificationError("Clarabel failed (test); SCS failed (test)")
        return real(prob, notes, what, *args, **kwargs)

    monkeypatch.setattr(C, "_run", failing)
    cons = consistent_estimate(res, prior_weight=0.0)
    assert cons.constraint_cost["total"] is None and cons.constraint_cost["links"] is None
    assert any(
        n.startswith("cost of consistency, every constraint kept: not measured (Clarabel failed")
        for n in cons.notes
    ), cons.notes
    assert np.all(cons.min_eig >= -EIG_TOL)
