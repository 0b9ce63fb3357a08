"""Energies and their regressors: consistency with the energies, with the power balance
dH/dt = dq . tau (finite differences and quadrature along a smooth trajectory), and with the
Euler-Lagrange equations (finite differences of the Lagrangian regressor give the torque one)."""

from __future__ import annotations

import mindyn
import numpy as np
import pytest
from conftest import URDFS, assert_close, load_urdf_pair, random_state

NAMES = ["puma560", "stanford", "zcr07s", "planar3", "ur5"]


def fresh(name: str) -> mindyn.Robot:
    return load_urdf_pair(name)[0] if name in URDFS else mindyn.load(name)


def with_drives(robot: mindyn.Robot, rng) -> mindyn.Robot:
    """Gives every joint nonzero rotor inertia and friction (the URDFs have none)."""
    robot.rotor_inertia = rng.uniform(0.1, 1.0, robot.n)
    robot.viscous = rng.uniform(0.1, 2.0, robot.n)
    robot.coulomb = rng.uniform(0.1, 2.0, robot.n)
    return robot


class Trajectory:
    """q(t) = q0 + a t + b t^2 + c sin(w t): smooth, with exact derivatives."""

    def __init__(self, robot: mindyn.Robot, rng):
        n = robot.n
        self.q0, _, _ = random_state(robot, rng)
        self.a, self.b, self.c = rng.uniform(-1, 1, (3, n))
        self.w = rng.uniform(1.0, 3.0, n)

    def __call__(self, t):
        t = np.asarray(t, dtype=float)[..., None]
        q = self.q0 + self.a * t + self.b * t**2 + self.c * np.sin(self.w * t)
        dq = self.a + 2 * self.b * t + self.c * self.w * np.cos(self.w * t)
        ddq = 2 * self.b - self.c * self.w**2 * np.sin(self.w * t)
        return q, dq, ddq


@pytest.mark.parametrize("name", NAMES)
def test_energy_regressors_times_params(name, rng):
    robot = with_drives(fresh(name), rng)
    n = robot.n
    for _ in range(3):
        q, dq, _ = random_state(robot, rng)
        for rotor, friction in [(False, False), (True, False), (False, True), (True, True)]:
            p = robot.parameters(rotor=rotor, friction=friction)
            wk, wp = robot.energy_regressors(q, dq, rotor=rotor, friction=friction)
            assert wk.shape == wp.shape == (len(p),)
            K = robot.kinetic_energy(q, dq, p)
            P = robot.potential_energy(q, p)
            assert_close(wk @ p, K, 1e-12, "wK @ params == K")
            assert_close(wp @ p, P, 1e-12, "wP @ params == P")
            wh = robot.energy_regressor(q, dq, rotor=rotor, friction=friction)
            assert_close(wh, wk + wp, 0.0, "wH == wK + wP")
            assert_close(wh @ p, robot.energy(q, dq, p), 1e-12, "wH @ params == H")
            wl = robot.lagrangian_regressor(q, dq, rotor=rotor, friction=friction)
            assert_close(wl, wk - wp, 0.0, "wL == wK - wP")
            assert_close(wl @ p, K - P, 1e-12, "wL @ params == K - P")
            names = robot.parameter_names(rotor=rotor, friction=friction)
            for k in range(n):
                if rotor:
                    i = names.index(f"Ia{k + 1}")
                    assert wk[i] == pytest.approx(0.5 * dq[k] ** 2, rel=1e-15)
                    assert wp[i] == 0.0
                if friction:
                    for f in ("Fv", "Fc"):
                        i = names.index(f"{f}{k + 1}")
                        assert wk[i] == 0.0 and wp[i] == 0.0
        # the kinetic energy is the quadratic form of the mass matrix
        p = robot.parameters(rotor=True)
        assert_close(
            robot.kinetic_energy(q, dq, p),
            0.5 * dq @ robot.mass_matrix(q, p) @ dq,
            1e-12,
            "K == dq M dq / 2",
        )
        # at rest K = 0; P has no inertia-tensor columns and does not depend on dq
        wk0, wp0 = robot.energy_regressors(q, np.zeros(n))
        wk1, wp1 = robot.energy_regressors(q, dq)
        assert not np.any(wk0)
        np.testing.assert_array_equal(wp0, wp1)
        assert not np.any(wp0.reshape(n, 10)[:, :6])


@pytest.mark.parametrize("name", NAMES)
def test_power_balance_finite_differences(name, rng):
    """dH/dt == dq . (tau - friction) along q(t) (central differences of H in time)."""
    robot = with_drives(fresh(name), rng)
    p = robot.parameters(rotor=True, friction=True)
    traj = Trajectory(robot, rng)
    ts = np.linspace(0.0, 1.0, 5)
    h = 1e-4
    for t in ts:
        # fourth-order central difference of H(t)
        Qs, DQs, _ = traj(t + h * np.array([-2.0, -1.0, 1.0, 2.0]))
        H = robot.energy(Qs, DQs, p)
        dH = (H[0] - 8 * H[1] + 8 * H[2] - H[3]) / (12 * h)
        q, dq, ddq = traj(t)
        tau = robot.inverse_dynamics(q, dq, ddq, p)
        friction = robot.viscous * dq + robot.coulomb * np.sign(dq)
        power = dq @ (tau - friction)
        scale = np.abs(dq) @ np.abs(tau) + 1.0
        err = abs(dH - power) / scale
        assert err < 1e-9, f"dH/dt {dH} vs dq.tau {power} at t={t}"


@pytest.mark.parametrize("name", NAMES)
def test_power_balance_integral(name, rng):
    """H(T) - H(0) == integral of dq . tau dt (Gauss-Legendre; no friction)."""
    robot = with_drives(fresh(name), rng)
    p = robot.parameters(rotor=True)
    traj = Trajectory(robot, rng)
    T = 1.5
    x, w = np.polynomial.legendre.leggauss(40)
    t = 0.5 * T * (x + 1.0)
    Q, DQ, DDQ = traj(t)
    tau = robot.inverse_dynamics(Q, DQ, DDQ, p)
    work = 0.5 * T * np.sum(w * np.einsum("ij,ij->i", DQ, tau))
    (q0, dq0, _), (q1, dq1, _) = traj(0.0), traj(T)
    dH = robot.energy(q1, dq1, p) - robot.energy(q0, dq0, p)
    scale = 0.5 * T * np.sum(w * np.abs(DQ * tau).sum(1)) + 1.0
    assert abs(dH - work) / scale < 1e-11, f"H(T) - H(0) = {dH}, work = {work}"


@pytest.mark.parametrize("name", ["puma560", "stanford", "ur5"])
def test_euler_lagrange_from_lagrangian_regressor(name, rng):
    """W(q, dq, ddq) == d/dt dwL/d(dq) - dwL/dq, by finite differences of the energy regressor."""
    robot = fresh(name)
    n = robot.n
    traj = Trajectory(robot, rng)
    t0 = 0.4
    q, dq, ddq = traj(t0)
    W = robot.regressor(q, dq, ddq, rotor=True)
    E = np.eye(n)

    def dL_ddq(qq, dqq, h=1e-3):
        # wL is quadratic in dq: the central difference is exact up to rounding
        plus = robot.lagrangian_regressor(np.tile(qq, (n, 1)), dqq + h * E, rotor=True)
        minus = robot.lagrangian_regressor(np.tile(qq, (n, 1)), dqq - h * E, rotor=True)
        return (plus - minus) / (2 * h)  # (n, P): row i = d wL / d dq_i

    ht = 1e-4
    (qa, dqa, _), (qb, dqb, _) = traj(t0 - ht), traj(t0 + ht)
    ddt = (dL_ddq(qb, dqb) - dL_ddq(qa, dqa)) / (2 * ht)
    hq = 1e-6
    dL_dq = (
        robot.lagrangian_regressor(q + hq * E, np.tile(dq, (n, 1)), rotor=True)
        - robot.lagrangian_regressor(q - hq * E, np.tile(dq, (n, 1)), rotor=True)
    ) / (2 * hq)
    assert_close(ddt - dL_dq, W, 1e-6, "Euler-Lagrange from wL (finite differences)")


@pytest.mark.parametrize("name", NAMES)
def test_gravity_is_potential_gradient(name, rng):
    robot = fresh(name)
    n = robot.n
    q, _, _ = random_state(robot, rng)
    h = 1e-6
    E = np.eye(n)
    P = robot.potential_energy(np.vstack([q + h * E, q - h * E]))
    grad = (P[:n] - P[n:]) / (2 * h)
    assert_close(robot.gravity_torque(q), grad, 1e-7, "gravity == dP/dq (finite differences)")
