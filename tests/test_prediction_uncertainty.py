"""How well an identification determines the torques it predicts: the standard deviation of each
predicted torque from the estimate's covariance (``fit.prediction_uncertainty``), checked
against numpy's covariance of the same least squares and against the scatter of the predicted
torques over noise realisations of a simulated log (Monte Carlo, independent of the
covariance), and the warning of a fit whose own uncertainty is most of its torque residual.

The logs are simulated here: a small arm (the three-joint Puma) along a three-harmonic random
excitation with rotor inertia, friction and white torque noise, read through the data path of
``mindyn identify`` (low-pass, edges, decimation for the dynamic model), as the manual's
tutorial reads its log. The energy model sees the power ``dq . tau`` only and leaves torque
directions of this excitation nearly undetermined; the dynamic model fits the torques
themselves."""

from __future__ import annotations

import mindyn
import numpy as np
import pytest
from mindyn.control import SensorNoise, simulate_inverse
from mindyn.identification import identify, load_logs, run, true_base_values
from mindyn.identification.data import JointData, fill_derivatives, write_csv
from mindyn.identification.estimation import predicted_torques
from mindyn.identification.excitation import random_trajectory
from mindyn.identification.validation import (
    UNCERTAINTY_RELATIVE,
    UNCERTAINTY_SHARE,
    prediction_check,
)

REALISATIONS = 8


@pytest.fixture(scope="module")
def arm():
    """The arm, its excitation and the torque noise: 1 % of each joint's peak torque."""
    robot = mindyn.load("puma560_3")
    traj = random_trajectory(robot, harmonics=3, freq=0.1, seed=3)
    clean = simulate_inverse(robot, traj, rotor=True, friction=True)
    return robot, traj, 0.01 * np.abs(clean.tau).max(axis=0)


def _log(arm, seed):
    robot, traj, sd = arm
    return simulate_inverse(
        robot, traj, rotor=True, friction=True, noise=SensorNoise(torque=sd), seed=seed
    )


def _monte_carlo(arm, tmp_path, model):
    """The first realisation's report (validated on the second realisation, the same motion),
    and per joint: the RMS over the samples of the predicted torques' standard deviation over
    the realisations (the scatter), the RMS error of the predictions against the true torques,
    and the reported prediction uncertainty averaged over the realisations."""
    robot = arm[0]
    paths = []
    for k in range(REALISATIONS):
        log = _log(arm, 10 + k)
        paths.append(write_csv(tmp_path / f"{model}{k}.csv", log.t, log.q, log.tau, dq=log.dq))
    first = None
    preds, reported = [], []
    for k, path in enumerate(paths):
        logs = load_logs([path], robot, validate=[paths[1]] if k == 0 else (), model=model)
        report = run(robot, logs, model=model, rotor=True, friction=True)
        if first is None:
            first, data = report, logs.fit.logs[0]
            truth = true_base_values(report.base, {"names": log.param_names, "values": log.params})
            exact = predicted_torques(report.base, truth, data)
        preds.append(report.result.predict(data))  # on the same (noise-free) filtered motion
        reported.append(report.fit["prediction_uncertainty"]["rms"])
    P = np.array(preds)
    scatter = np.sqrt(np.mean(P.var(axis=0, ddof=1), axis=0))
    error = np.sqrt(np.mean((P - exact) ** 2, axis=(0, 1)))
    return first, scatter, error, np.mean(reported, axis=0)


def test_an_energy_fit_that_leaves_the_torques_undetermined_is_warned_of(arm, tmp_path):
    """The energy model along three harmonics: the torques it predicts scatter over noise
    realisations by several times the noise that remains after the low-pass, and the reported
    uncertainty is that scatter within a factor 2 (and the error against the true torques); it
    is most of the fit's own torque residual, and the fit warns, naming the model and the
    remedy, in the text and in the JSON."""
    report, scatter, error, reported = _monte_carlo(arm, tmp_path, "energy")
    print(f"\nenergy: reported {reported}, Monte Carlo scatter {scatter}, error {error}")
    assert np.all(reported < 2.0 * scatter) and np.all(reported > 0.5 * scatter)
    assert np.all(reported < 2.0 * error) and np.all(reported > 0.5 * error)
    check = report.fit["prediction_uncertainty"]
    assert check["mean_share"] > UNCERTAINTY_SHARE
    # for a fit of the torques the mean share is p / N_eff: this one is far beyond it
    assert check["excess"] > 3.0
    line = check["warning"]
    assert line and "energy model" in line and "dynamic model" in line and "\n" not in line
    assert check["joints"] == [j + 1 for j in range(3) if check["share"][j] > UNCERTAINTY_SHARE]
    assert f"WARNING: {line}" in report.format()
    doc = report.to_dict()
    assert doc["fit"]["prediction_uncertainty"]["warning"] == line
    assert doc["fit"]["prediction_uncertainty"]["overall_relative"] == pytest.approx(
        check["overall_relative"]
    )
    # the validation log follows the same motion: the same uncertainty, the same estimate
    val = doc["validation"]["prediction_uncertainty"]
    np.testing.assert_allclose(val["rms"], check["rms"], rtol=1e-9)
    assert "warning" not in val


def test_a_well_excited_dynamic_fit_is_not_warned_of(arm, tmp_path):
    """The dynamic model on the same logs: its reported uncertainty is the Monte Carlo scatter
    of its predicted torques within a factor 1.5, its mean share of the torque residual is
    about p / N_eff (the value for an honest covariance of a fit of the torques), and no
    warning."""
    report, scatter, error, reported = _monte_carlo(arm, tmp_path, "dynamic")
    print(f"\ndynamic: reported {reported}, Monte Carlo scatter {scatter}, error {error}")
    assert np.all(reported < 1.5 * scatter) and np.all(reported > scatter / 1.5)
    check = report.fit["prediction_uncertainty"]
    assert 0.5 < check["excess"] < 2.0, check
    assert check["warning"] is None and check["joints"] == []
    assert "WARNING" not in report.format()
    # the same fit with joint 2's uncertainty at its RMS torque (its share still small) is
    # warned of, naming that joint: the torque is not determined even in size
    fit = dict(report.fit)
    unc = dict(check, relative=np.array(check["relative"], dtype=float))
    unc["relative"][1] = UNCERTAINTY_RELATIVE
    fit["prediction_uncertainty"] = unc
    data = report.logs.fit.logs
    again = prediction_check(report.result, fit, data)
    assert again["mean_share"] == pytest.approx(check["mean_share"])
    assert again["joints"] == [2] and "joint(s) 2 it reaches the RMS torque" in again["warning"]
    assert "dynamic model's estimate" in again["warning"]


def test_prediction_std_is_the_covariance_of_the_least_squares(arm):
    """Ordinary least squares on a log without low-pass: ``sqrt(diag(Y Sigma Y^T))`` with
    numpy's ``Sigma = s^2 (W^T W)^-1`` of the stacked dynamic system, all base parameters
    (pruning does not change it)."""
    robot = arm[0]
    log = _log(arm, 1)
    dq, ddq, info = fill_derivatives(log.t, log.q, log.dq, None)
    data = JointData(log.t, log.q, dq, ddq, log.tau, "sim", info)
    res = identify(robot, data, rotor=True, friction=True, weighted=False, min_velocity=0)
    assert res.removed  # pruned: the covariance is still that of every base parameter
    W = res.base.regressor(data.q, data.dq, data.ddq)
    A, y = W.reshape(-1, res.base.n), data.tau.reshape(-1)
    p, *_ = np.linalg.lstsq(A, y, rcond=None)
    s2 = np.sum((y - A @ p) ** 2) / (A.shape[0] - A.shape[1])
    cov = s2 * np.linalg.inv(A.T @ A)
    want = np.sqrt(np.einsum("mjb,bc,mjc->mj", W, cov, W))
    np.testing.assert_allclose(res.prediction_std(data), want, rtol=1e-6)


def test_a_noise_free_log_fitted_to_round_off_is_not_warned_of(arm, tmp_path):
    """A log without noise, with its exact accelerations and no filter, is fitted to round-off:
    the estimates are the true base values, and the residual and the prediction uncertainty
    are both round-off, whose ratio (any size) is no sign of a poor excitation."""
    robot, traj, _ = arm
    t = np.arange(0.0, traj.period, 0.004)
    q, dq, ddq = traj.evaluate(t)
    W = robot.regressor(q, dq, ddq, rotor=True, friction=True)
    tau = W @ robot.parameters(rotor=True, friction=True)  # the classical model's torques
    path = write_csv(tmp_path / "clean.csv", t, q, tau, dq=dq, ddq=ddq)
    logs = load_logs([path], robot, filter="none")
    report = run(robot, logs, rotor=True, friction=True, rsd_threshold=0)
    res = report.result
    truth = mindyn.base_parameters(robot, rotor=True, friction=True)
    np.testing.assert_allclose(
        res.values, truth.Y @ robot.parameters(rotor=True, friction=True), rtol=1e-9, atol=1e-10
    )
    unc = report.fit["prediction_uncertainty"]
    assert unc["overall_relative"] < 1e-12
    assert unc["warning"] is None and unc["joints"] == []
    assert "WARNING" not in report.format()
    # round-off over round-off can be any ratio (0.8 to 1.6 on a 6R arm's wrist): at a share
    # of 0.9 on every joint the fit is still not warned of, while the same share with torques
    # determined to 0.1 % is
    fit = dict(report.fit)
    fit["prediction_uncertainty"] = dict(unc, rms=np.sqrt(0.9) * np.asarray(fit["rms"]))
    data = report.logs.fit.logs
    check = prediction_check(res, fit, data)
    assert check["mean_share"] == pytest.approx(0.9) and check["warning"] is None
    fit["prediction_uncertainty"]["overall_relative"] = 1e-3
    check = prediction_check(res, fit, data)
    assert "it is most of the fit's torque residual" in check["warning"]
