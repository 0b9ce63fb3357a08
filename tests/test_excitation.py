"""Excitation trajectories: Fourier series, boundary conditions, limits, criteria, CLI."""

from __future__ import annotations

import json
import math

import mindyn
import numpy as np
import pytest
from conftest import ROBOTS_DIR
from mindyn import cli
from mindyn.identification.data import read_csv
from mindyn.identification.excitation import (
    FourierTrajectory,
    criterion_value,
    excitation_limits,
    optimize_excitation,
    random_trajectory,
)

KINOVA = ROBOTS_DIR / "kinova_description/robots/kinova.urdf"


def seed_formula(a, b, q0, f, t):
    """The Fourier series of the ZCR07S study, written out term by term."""
    w = 2 * math.pi * f
    n, N = a.shape
    q = np.tile(q0, (t.size, 1)).astype(float)
    for i in range(n):
        for ell in range(1, N + 1):
            q[:, i] += a[i, ell - 1] / (w * ell) * np.sin(w * ell * t)
            q[:, i] -= b[i, ell - 1] / (w * ell) * np.cos(w * ell * t)
    return q


def test_fourier_series_matches_the_seed_formula_and_its_derivatives():
    rng = np.random.default_rng(3)
    a, b, q0 = rng.normal(size=(2, 4)), rng.normal(size=(2, 4)), rng.normal(size=2)
    traj = FourierTrajectory(a, b, q0, 0.2)
    t = np.linspace(0, 5, 501)
    q, dq, ddq = traj.evaluate(t)
    np.testing.assert_allclose(q, seed_formula(a, b, q0, 0.2, t), rtol=1e-13, atol=1e-13)
    h = 1e-5  # central differences of the series formula
    fd = (seed_formula(a, b, q0, 0.2, t + h) - seed_formula(a, b, q0, 0.2, t - h)) / (2 * h)
    np.testing.assert_allclose(dq, fd, atol=1e-8)
    fdd = (seed_formula(a, b, q0, 0.2, t + h) - 2 * q + seed_formula(a, b, q0, 0.2, t - h)) / h**2
    np.testing.assert_allclose(ddq, fdd, atol=2e-4)


def _assert_boundary(traj, start=None):
    T = traj.period
    q, dq, ddq = traj.evaluate(np.array([0.0, T]))
    np.testing.assert_allclose(dq, 0, atol=1e-12)
    np.testing.assert_allclose(ddq, 0, atol=1e-11)
    np.testing.assert_allclose(q[0], q[1], atol=1e-12)
    if start is not None:
        np.testing.assert_allclose(q[0], start, atol=1e-12)


def _assert_within_robot_limits(robot, traj, margin=0.0):
    """Checked on a fine grid against the robot description's own limits."""
    lim = robot.limits
    t = np.linspace(0, traj.period, 20001)
    q, dq, ddq = traj.evaluate(t)
    tol = 1e-9
    assert (q >= lim["lower"] - tol).all() and (q <= lim["upper"] + tol).all()
    assert (np.abs(dq) <= lim["velocity"] * (1 - margin) + tol).all()
    assert (np.abs(ddq) <= lim["acceleration"] * (1 - margin) + tol).all()
    return np.abs(dq).max(0) / lim["velocity"], np.abs(ddq).max(0) / lim["acceleration"]


def test_random_trajectory_meets_boundary_conditions_and_limits():
    robot = mindyn.load("zcr07s")
    for seed in range(3):
        traj = random_trajectory(robot, seed=seed)
        _assert_boundary(traj)
        _assert_within_robot_limits(robot, traj)


@pytest.fixture(scope="module")
def zcr_result():
    return optimize_excitation("zcr07s", starts=2, maxiter=20, seed=4, progress=False)


def test_optimised_excitation_respects_limits_and_improves_conditioning(zcr_result):
    res = zcr_result
    robot = mindyn.load("zcr07s")
    _assert_boundary(res.trajectory)
    v, a = _assert_within_robot_limits(robot, res.trajectory, margin=0.05)
    print(f"\nzcr07s excitation: peak |dq|/limit {np.round(v, 2)}, |ddq|/limit {np.round(a, 2)}")
    # Condition numbers recomputed with numpy from the stacked base regressor.
    base = mindyn.base_parameters(robot)
    t = np.arange(100) * (res.trajectory.period / 100)

    def cond(traj):
        W = base.regressor(*traj.evaluate(t)).reshape(-1, base.n)
        return np.linalg.cond(W)

    final, initial = cond(res.trajectory), cond(res.initial_trajectory)
    print(f"zcr07s excitation: condition number {initial:.4g} -> {final:.4g}")
    assert final == pytest.approx(res.value, rel=1e-6)
    assert initial == pytest.approx(res.initial_value, rel=1e-6)
    assert final < 0.5 * initial
    assert len(res.starts) == 2 and all(s["final"] <= s["initial"] for s in res.starts)


@pytest.mark.parametrize("criterion", ["logdet", "hadamard"])
def test_other_criteria_improve_over_the_initial_guess(criterion):
    robot = mindyn.load("planar2")
    res = optimize_excitation(
        robot,
        criterion=criterion,
        starts=1,
        maxiter=30,
        seed=1,
        progress=False,
        limits={"lower": -2.0, "upper": 2.0},
    )
    base = mindyn.base_parameters(robot)
    t = np.arange(100) * (res.trajectory.period / 100)

    def crit(traj):
        W = base.regressor(*traj.evaluate(t)).reshape(-1, base.n)
        G = W.T @ W
        _, logdet = np.linalg.slogdet(G / W.shape[0])
        if criterion == "logdet":
            return logdet  # larger is better
        return -(np.sum(np.log(np.diag(G) / W.shape[0])) - logdet)  # larger is better

    assert crit(res.trajectory) > crit(res.initial_trajectory)
    # Reported form: log det (larger is better) for logdet, the log Hadamard ratio (smaller is
    # better) for hadamard; value and initial_value (and each start's) share it. The objective
    # is evaluated on the same 100 samples as above (rel 1e-6: summation order only).
    sign = 1.0 if criterion == "logdet" else -1.0
    expect = sign * crit(res.trajectory)
    assert res.value == pytest.approx(expect, rel=1e-9, abs=1e-12)
    assert res.initial_value == pytest.approx(sign * crit(res.initial_trajectory), rel=1e-6)
    assert sign * res.value > sign * res.initial_value
    (run,) = res.starts
    assert sign * run["final"] >= sign * run["initial"]
    assert run["initial"] == pytest.approx(res.initial_value, rel=1e-12)
    _assert_boundary(res.trajectory)


def test_prescribed_start_and_missing_limits():
    robot = mindyn.load("puma560_3")  # no limits at all in its description
    start = np.array([-np.pi, 0.0, np.pi / 2])
    res = optimize_excitation(
        robot,
        starts=1,
        maxiter=15,
        start=start,
        progress=False,
        limits={"lower": start - 1.5, "upper": start + 1.5},
    )
    _assert_boundary(res.trajectory, start)
    assert any("no velocity limit given; using 1.5 rad/s" in n for n in res.notes)
    q, dq, ddq = res.trajectory.evaluate(np.linspace(0, 10, 5001))
    assert np.abs(dq).max() <= 1.5 * 0.95 + 1e-9 and np.abs(ddq).max() <= 6.0 * 0.95 + 1e-9
    assert (q >= start - 1.5).all() and (q <= start + 1.5).all()


def test_excitation_limits_fallbacks():
    lim, notes = excitation_limits(mindyn.load("stanford"), margin=0.0)
    assert np.isfinite(lim["velocity"]).all() and np.isfinite(lim["acceleration"]).all()
    lim2, _ = excitation_limits(mindyn.load("zcr07s"), margin=0.1)
    full = mindyn.load("zcr07s").limits
    np.testing.assert_allclose(lim2["velocity"], 0.9 * full["velocity"])
    np.testing.assert_allclose(lim2["upper"] - lim2["lower"], 0.9 * (full["upper"] - full["lower"]))


def test_bad_requests_are_errors():
    with pytest.raises(ValueError, match="harmonics is 1; expected an integer >= 2"):
        optimize_excitation("planar2", harmonics=1, progress=False)
    with pytest.raises(ValueError, match="^criterion is a str 'rank'; expected one of"):
        optimize_excitation("planar2", criterion="rank", progress=False)
    with pytest.raises(ValueError, match="start position of joint 2"):
        optimize_excitation("zcr07s", start=[0, 3.0, 0, 0, 0, 0], progress=False)
    with pytest.raises(ValueError, match="^criterion is a str"):
        criterion_value(
            mindyn.base_parameters("planar2"),
            np.zeros((3, 2)),
            np.zeros((3, 2)),
            np.zeros((3, 2)),
            criterion="rank",
        )
    with pytest.raises(ValueError, match="do not fit together"):
        FourierTrajectory(np.zeros((2, 3)), np.zeros((2, 4)), np.zeros(2), 0.1)


def test_cli_excite_writes_csv_json_png(tmp_path, capsys):
    out = tmp_path / "traj.csv"
    rc = cli.main(
        [
            "excite",
            "planar3",
            "--harmonics",
            "4",
            "--starts",
            "1",
            "--maxiter",
            "10",
            "--seed",
            "2",
            "-o",
            str(out),
        ]
    )
    assert rc == 0
    captured = capsys.readouterr()
    assert "condition number" in captured.out and "start 1/1" in captured.err
    doc = json.loads(out.with_suffix(".json").read_text())
    assert out.with_suffix(".png").stat().st_size > 10_000
    traj = FourierTrajectory.load(out.with_suffix(".json"))
    d = read_csv(out, n=3, require_torque=False)
    assert d.tau is None and d.processing["acceleration"]["source"] == "logged"
    assert d.t[-1] == pytest.approx(10.0) and d.rate == pytest.approx(250.0)
    q, dq, ddq = traj.evaluate(d.t)
    np.testing.assert_allclose(d.q, q, atol=1e-10)
    np.testing.assert_allclose(d.ddq, ddq, atol=1e-9)
    assert doc["criterion"] == "cond" and doc["value"] < doc["initial_value"]


def test_the_criterion_takes_motor_terms_in_joint_units():
    """Kinova's motors drive their joints with a ratio of 160: with the rotor inertia and
    friction on the motors, their base columns are 160^2 (Ia, Fv) and 160 (Fc) times the
    joint-side ones, and the condition number was that of the gear ratio (4e5 where the joint
    side gives 1e2: the optimiser failed on every start). Each criterion now equals the one of
    the same robot with the terms on the joints, on the same samples."""
    robot = mindyn.load(KINOVA)
    assert robot.drive_side == "motor" and np.allclose(np.abs(np.diag(robot.transmission.T)), 160)
    motor = mindyn.base_parameters(robot, rotor=True, friction=True)
    joint = mindyn.base_parameters(robot.with_drive_side("joint"), rotor=True, friction=True)
    assert motor.names == joint.names
    rng = np.random.default_rng(4)
    q, dq, ddq = rng.uniform(-1, 1, (3, 200, robot.n))
    for criterion in ("cond", "logdet", "hadamard"):
        a = criterion_value(motor, q, dq, ddq, criterion=criterion)
        b = criterion_value(joint, q, dq, ddq, criterion=criterion)
        assert a == pytest.approx(b, rel=1e-9, abs=1e-9), criterion
    # the joint side's own value, from numpy on the regressor the test forms
    W = joint.regressor(q, dq, ddq).reshape(-1, joint.n)
    assert criterion_value(motor, q, dq, ddq) == pytest.approx(np.linalg.cond(W), rel=1e-6)
