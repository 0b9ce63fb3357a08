"""The generalised-momentum observer against external torques injected in simulation.

Reference: with the true model, no noise and the external torque ``e`` held over each period,
the discrete residual is the first-order recursion ``r_k = a r_{k-1} + c T e_{k-1}``, ``a = (1 -
K T/2) / (1 + K T/2)``, ``c = K / (1 + K T/2)`` (the bilinear image of ``K / (s + K)``), computed
here from the injected profile alone; the observer sees only the logged motion and the
controller's torque."""

from __future__ import annotations

import mindyn
import numpy as np
import pytest
from mindyn.control import (
    ContactWrench,
    MomentumObserver,
    SumOfSines,
    TorqueProfile,
    alarm_intervals,
    calibrate_thresholds,
    simulate,
)
from random_tree import random_tree_urdf


def filter_prediction(ext, gains, period):
    h = 0.5 * gains * period
    a, c = (1 - h) / (1 + h), gains / (1 + h)
    r = np.zeros_like(ext)
    for k in range(1, ext.shape[0]):
        r[k] = a * r[k - 1] + c * period * ext[k - 1]
    return r


def plant_params(robot):
    """Rotor inertia and viscous friction (no Coulomb step, which the trapezoid does not
    integrate exactly at a velocity reversal)."""
    p = robot.parameters(rotor=True, friction=True).reshape(robot.n, 13).copy()
    p[:, 12] = 0.0
    return p.reshape(-1)


def run(robot, ext, rate=2000.0, duration=0.4):
    params = plant_params(robot)
    res = simulate(
        robot,
        SumOfSines(robot, period=2.0, fraction=0.3, seed=3),
        rate=rate,
        duration=duration,
        substeps=4,
        params=params,
        external=ext,
    )
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    obs = MomentumObserver(base, base.values(params), period=1.0 / rate)
    return res, obs, obs.run(res.q, res.dq, res.tau)


@pytest.mark.parametrize("which", ["puma560", "tree"])
def test_residual_is_the_discrete_filter_of_the_external_torque(which, tmp_path):
    if which == "tree":
        robot = mindyn.load(random_tree_urdf(tmp_path / "tree.urdf", 5, seed=4))
    else:
        robot = mindyn.load(which)
    n = robot.n
    torque = np.linspace(3.0, -2.0, n) + 0.5  # every joint, different values
    ext = TorqueProfile(torque, start=0.1, stop=0.3)
    res, obs, r = run(robot, ext)  # 2 kHz: the trapezoid's error on beta, O(T^2), is 4e-7
    assert np.abs(res.tau_ext).max() > 0 and np.abs(res.tau_ext[-1]).max() == 0
    want = filter_prediction(res.tau_ext, obs.gains, obs.period)
    err = np.abs(r - want).max() / np.abs(torque).max()
    assert err <= 1e-6, f"{which}: residual off the filter by {err:.2e} (relative)"
    # and without the external torque the residual stays at round-off / trapezoid level
    assert np.abs(r[:100]).max() <= 1e-6 * np.abs(torque).max()


def test_residual_converges_to_the_continuous_filter():
    """As T -> 0 the discrete residual of a held step tends to ``e (1 - exp(-K t))``, the
    continuous form's answer; the bilinear image differs by O((K T)^2)."""
    robot = mindyn.load("puma560")
    errs = []
    for rate in (500.0, 2000.0):
        K = 40.0
        res = simulate(
            robot,
            SumOfSines(robot, period=2.0, fraction=0.3, seed=3),
            rate=rate,
            duration=0.2,
            params=plant_params(robot),
            external=TorqueProfile(np.full(robot.n, 5.0), start=0.0),
        )
        base = mindyn.base_parameters(robot, rotor=True, friction=True)
        obs = MomentumObserver(base, base.values(plant_params(robot)), period=1 / rate, gains=K)
        r = obs.run(res.q, res.dq, res.tau)
        # the held step acts from t = 0: r_k = e (1 - a^k), a^k = exp(-K t_k) (1 + O((K T)^2))
        cont = 5.0 * (1 - np.exp(-K * res.t))
        errs.append(np.abs(r[1:] - cont[1:, None]).max() / 5.0)
    assert errs[1] < errs[0] / 10  # second order: 16 times smaller at 4 times the rate
    assert errs[1] < 1e-3


def test_held_and_sampled_torque_and_offsets():
    """A constant torque offset in the model and none in the plant: the model needs ``off`` more
    than the motion shows, which the residual reads as an external torque ``off`` (the filter
    of a constant from sample 0)."""
    robot = mindyn.load("puma560")
    params = plant_params(robot)
    res = simulate(
        robot,
        SumOfSines(robot, period=2.0, fraction=0.3, seed=1),
        rate=1000.0,
        duration=0.3,
        params=params,
    )
    base = mindyn.base_parameters(robot, rotor=True, friction=True, offset=True)
    off = np.linspace(-1.0, 1.0, robot.n)
    values = np.concatenate([base.values(params)[: base.n - robot.n], off])
    r = MomentumObserver(base, values, period=1e-3).run(res.q, res.dq, res.tau)
    want = filter_prediction(np.tile(off, (r.shape[0], 1)), np.full(robot.n, 100.0), 1e-3)
    assert np.abs(r - want).max() <= 3e-5  # the trapezoid's O(T^2) error on beta at 1 kHz


def test_bad_gains_and_values_are_refused():
    robot = mindyn.load("puma560")
    base = mindyn.base_parameters(robot)
    v = base.values(robot.parameters())
    with pytest.raises(mindyn.Error, match="observer gain K_O of joint 1"):
        MomentumObserver(base, v, period=1e-3, gains=2000.0)
    with pytest.raises(mindyn.Error, match="values has"):
        MomentumObserver(base, v[:-1], period=1e-3)
    obs = MomentumObserver(base, v, period=1e-3)
    with pytest.raises(mindyn.Error, match="NaN"):
        obs.run(np.full((3, 6), np.nan), np.zeros((3, 6)), np.zeros((3, 6)))


def test_thresholds_and_alarm_intervals():
    t = np.arange(10) * 0.1
    r = np.zeros((10, 2))
    r[3:5, 1] = [2.0, -3.0]
    r[8, 0] = 1.5
    got = alarm_intervals(t, r, np.array([1.0, 1.0]))
    assert [(d["joint"], d["start"], d["end"], d["peak"]) for d in got] == [
        (2, 0.30000000000000004, 0.4, -3.0),
        (1, 0.8, 0.8, 1.5),
    ]
    thr = calibrate_thresholds(np.array([[0.0, 1.0], [0.0, -2.0]]), margin=1.5)
    assert thr[1] == 3.0 and 0 < thr[0] < 1e-8


def test_identified_model_with_noise_detects_steps_without_false_alarms():
    """puma560 (rotor inertia, viscous and Coulomb friction) at 1 kHz, the logged torque with
    white noise of 1 % of each joint's peak torque: the base parameters identified (integral
    model) from a 5 s run; thresholds calibrated on one 2 s collision-free run; no alarm on five
    other 1 s runs (other references, other noise); then 10 N m held on each joint in turn (60 ms
    each, 150 ms apart) is detected within 20 ms of its onset. The full figures with longer runs:
    bench/bench_collision_detection.py."""
    from mindyn.identification import JointData, identify

    robot = mindyn.load("puma560")
    n, T = robot.n, 1e-3

    def run(seed, duration, sd=0.0, external=None):
        return simulate(
            robot,
            SumOfSines(robot, period=2.0, fraction=0.5, seed=seed),
            rate=1 / T,
            duration=duration,
            rotor=True,
            friction=True,
            noise=mindyn.control.SensorNoise(torque=sd),
            seed=seed + 1000,
            external=external,
        )

    sd = 0.01 * np.abs(run(100, 5.0).tau).max(0)
    ex = run(100, 5.0, sd)
    fit = identify(
        robot,
        JointData(ex.t, ex.q, ex.dq, np.zeros_like(ex.q), ex.tau),
        model="integral",
        rotor=True,
        friction=True,
    )
    truth = fit.base.values(ex.params)
    assert np.linalg.norm(fit.full - truth) > 1e-3 * np.linalg.norm(truth)  # not the true model

    def residual(res):
        obs = MomentumObserver(fit.base, fit.full, period=T)
        return obs.run(res.q, res.dq, res.tau)

    thr = calibrate_thresholds(residual(run(0, 2.0, sd)))
    for seed in range(1, 6):
        res = run(seed, 1.0, sd)
        assert alarm_intervals(res.t, residual(res), thr) == [], f"false alarm, run {seed}"

    starts = 0.1 + 0.15 * np.arange(n)

    def steps(t, q, dq):
        on = (t >= starts - 1e-9) & (t < starts + 0.06 - 1e-9)
        return np.where(on, 10.0, 0.0)

    res = run(7, 0.1 + 0.15 * n, sd, steps)
    r = residual(res)
    for j in range(n):
        i0 = int(np.flatnonzero(res.tau_ext[:, j])[0])
        above = np.flatnonzero(np.abs(r[i0:, j]) > thr[j])
        assert above.size and above[0] * T <= 0.020, f"joint {j + 1}: not detected in 20 ms"


def test_contact_wrench_at_the_tool_is_jacobian_transpose_and_observed():
    """A force at the tool of puma560: the simulator applies J(q)^T w, checked against finite
    differences of the tool position (virtual work: tau_j = f . d p_tool / d q_j); the residual
    of the true model then follows it as the discrete filter predicts."""
    robot = mindyn.load("puma560")
    force = np.array([30.0, -20.0, 10.0])
    contact = ContactWrench(np.concatenate([force, np.zeros(3)]), start=0.05, robot=robot)
    q = np.array([0.3, -0.5, 0.8, 0.2, -0.4, 0.6])
    h = 1e-6
    fd = [
        force @ (robot.fk(q + h * e)[:3, 3] - robot.fk(q - h * e)[:3, 3]) / (2 * h)
        for e in np.eye(robot.n)
    ]
    np.testing.assert_allclose(contact(0.1, q, 0 * q), fd, rtol=1e-6, atol=1e-6)
    assert np.all(contact(0.0, q, 0 * q) == 0)
    res, obs, r = run(robot, contact, duration=0.2)
    want = filter_prediction(res.tau_ext, obs.gains, obs.period)
    assert np.abs(res.tau_ext).max() > 1.0
    assert np.abs(r - want).max() <= 1e-6 * np.abs(res.tau_ext).max()


def test_residual_uncertainty_is_the_residual_of_a_parameter_error():
    """The residual is linear in the parameter values: an error s in one base parameter changes
    it by exactly the sensitivity residual_uncertainty gives for a standard deviation s there;
    for two parameters the deviations add in quadrature."""
    from mindyn.control import residual_uncertainty

    robot = mindyn.load("puma560")
    params = plant_params(robot)
    res = simulate(
        robot,
        SumOfSines(robot, period=2.0, fraction=0.3, seed=2),
        rate=1000.0,
        duration=0.3,
        params=params,
    )
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    v = base.values(params)
    obs = MomentumObserver(base, v, period=1e-3)
    r0 = obs.run(res.q, res.dq, res.tau)
    diffs = []
    for i, s in ((3, 0.02), (17, 0.05)):
        std = np.zeros(base.n)
        std[i] = s
        dv = v.copy()
        dv[i] += s
        diff = MomentumObserver(base, dv, period=1e-3).run(res.q, res.dq, res.tau) - r0
        got = residual_uncertainty(obs, std, res.q, res.dq)
        assert np.abs(diff).max() > 1e-4
        np.testing.assert_allclose(got, np.abs(diff), rtol=1e-9, atol=1e-12)
        diffs.append(diff)
    std = np.zeros(base.n)
    std[[3, 17]] = [0.02, 0.05]
    both = residual_uncertainty(obs, std, res.q, res.dq)
    np.testing.assert_allclose(both, np.hypot(*diffs), rtol=1e-9, atol=1e-12)


def test_a_collision_in_a_log_that_pinocchio_integrates_is_the_filter_of_its_torque():
    """An observer independent of the simulator: Pinocchio integrates the UR5 of
    example-robot-data (RK4 on its ``aba``, 4 steps per 1 ms period) under a PD with gravity
    compensation from its ``rnea``, the command and a 5 N m external torque on joint 3 held
    over each period; the residual of the true base values is the discrete filter of that
    torque on joint 3 and stays at the integration's level on the others, and thresholds
    calibrated on the log before the collision flag joint 3 alone, one period after it."""
    pin = pytest.importorskip("pinocchio")
    from conftest import load_urdf_pair

    robot, model = load_urdf_pair("ur5")
    data = model.createData()
    n, period, steps = robot.n, 1e-3, 600
    q = np.array([0.2, -1.0, 1.2, -0.5, 0.8, 0.3])
    dq = np.zeros(n)
    hold = q + 0.3
    ext = np.zeros((steps, n))
    ext[300:400, 2] = 5.0
    log_q, log_dq, log_tau = (np.zeros((steps, n)) for _ in range(3))

    def accel(q, dq, u):
        return pin.aba(model, data, q, dq, u)

    for k in range(steps):
        tau = pin.computeGeneralizedGravity(model, data, q) + 50.0 * (hold - q) - 5.0 * dq
        log_q[k], log_dq[k], log_tau[k] = q, dq, tau
        u, h = tau + ext[k], period / 4
        for _ in range(4):
            k1 = dq, accel(q, dq, u)
            k2 = dq + h / 2 * k1[1], accel(q + h / 2 * k1[0], dq + h / 2 * k1[1], u)
            k3 = dq + h / 2 * k2[1], accel(q + h / 2 * k2[0], dq + h / 2 * k2[1], u)
            k4 = dq + h * k3[1], accel(q + h * k3[0], dq + h * k3[1], u)
            q = q + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            dq = dq + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
    base = mindyn.base_parameters(robot)
    obs = MomentumObserver(base, base.values(robot.params), period=period)
    r = obs.run(log_q, log_dq, log_tau)
    want = filter_prediction(ext, obs.gains, period)
    assert np.abs(r - want).max() <= 1e-5 * 5.0
    thr = calibrate_thresholds(r[:300], margin=1.5)
    t = np.arange(steps) * period
    alarms = alarm_intervals(t, r, np.maximum(thr, 0.05))  # 1 % of the step: the floor
    assert [a["joint"] for a in alarms] == [3]
    # from the first sample after the step to its decay below the floor after the release
    assert alarms[0]["start"] == pytest.approx(0.301)
    assert 0.4 < alarms[0]["end"] < 0.5
