"""Momentum-form regressors against Pinocchio and finite differences.

``Robot.momentum_regressors`` gives ``p = A(q) dq = W_p @ params`` and
``-dL/dq = W_l @ params``. References: Pinocchio's CRBA (``p = M dq``), its Coriolis matrix
(``dK/dq = C^T dq`` since ``dA/dt = C + C^T``) and gravity (``dP/dq``), and central finite
differences of ``Robot.kinetic_energy``/``potential_energy``.
"""

from __future__ import annotations

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import BUNDLED, URDFS, assert_close, load_urdf_pair, pinocchio_model, random_state

ALL = BUNDLED + ["ur5", "panda", "skewed6r"]
TOL = 1e-10


def _pair(name, tmp_path_factory=None):
    if name in URDFS:
        return load_urdf_pair(name)
    if name == "skewed6r":  # random joint origins, rotations and axes (test_codegen.py)
        from test_codegen import skewed_urdf

        path = tmp_path_factory.mktemp("skewed") / "skewed6r.urdf"
        path.write_text(skewed_urdf(np.random.default_rng(7)))
        return mindyn.load(path), pin.buildModelFromUrdf(str(path))
    robot = mindyn.load(name)
    return robot, pinocchio_model(robot)


@pytest.mark.parametrize("name", ALL)
def test_momentum_regressors_match_pinocchio(name, rng, tmp_path_factory):
    robot, model = _pair(name, tmp_path_factory)
    data = model.createData()
    p = robot.params
    for _ in range(4):
        q, dq, _ = random_state(robot, rng)
        Wp, Wl = robot.momentum_regressors(q, dq)
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        assert_close(Wp @ p, M @ dq, TOL, "momentum vs pin.crba M dq")
        C = pin.computeCoriolisMatrix(model, data, q, dq)
        g = pin.computeGeneralizedGravity(model, data, q)
        assert_close(Wl @ p, g - C.T @ dq, TOL, "-dL/dq vs pin g - C^T dq")


@pytest.mark.parametrize("name", ["puma560", "stanford", "zcr07s", "panda", "skewed6r"])
def test_lagrangian_gradient_matches_finite_differences(name, rng, tmp_path_factory):
    # Central differences, step 1e-6: truncation ~1e-12 x third derivatives, rounding
    # ~1e-16 |K| / 1e-6 ~ 1e-10 |K|; 1e-7 relative leaves a margin of about 1000.
    robot, _ = _pair(name, tmp_path_factory)
    p = robot.parameters(rotor=True)
    p[10::11] = rng.uniform(0.1, 1.0, robot.n)  # rotor inertia: must not contribute to dK/dq
    h = 1e-6
    for _ in range(3):
        q, dq, _ = random_state(robot, rng)
        _, Wl = robot.momentum_regressors(q, dq, rotor=True)
        fd = np.empty(robot.n)
        for j in range(robot.n):
            e = np.zeros(robot.n)
            e[j] = h
            lp = robot.kinetic_energy(q + e, dq, p) - robot.potential_energy(q + e, p)
            lm = robot.kinetic_energy(q - e, dq, p) - robot.potential_energy(q - e, p)
            fd[j] = -(lp - lm) / (2 * h)
        assert_close(Wl @ p, fd, 1e-7, "-dL/dq vs finite differences of K - P")


def test_rotor_friction_columns_and_batches(rng):
    robot = mindyn.load("zcr07s")
    n = robot.n
    q, dq, _ = random_state(robot, rng, m=5)
    Wp, Wl = robot.momentum_regressors(q, dq, rotor=True, friction=True)
    assert Wp.shape == Wl.shape == (5, n, 13 * n)
    for i in range(5):
        a, b = robot.momentum_regressors(q[i], dq[i], rotor=True, friction=True)
        np.testing.assert_array_equal(a, Wp[i])
        np.testing.assert_array_equal(b, Wl[i])
    # rotor column of W_p is dq on its own joint; friction columns are zero in both
    for k in range(n):
        np.testing.assert_array_equal(Wp[:, k, 13 * k + 10], dq[:, k])
        assert not Wl[:, :, 13 * k + 10].any()
        assert not Wp[:, :, 13 * k + 11 : 13 * k + 13].any()
        assert not Wl[:, :, 13 * k + 11 : 13 * k + 13].any()
    e = np.zeros((0, n))
    a, b = robot.momentum_regressors(e, e)
    assert a.shape == b.shape == (0, n, 10 * n)
    with pytest.raises(ValueError, match="dq"):
        robot.momentum_regressors(q, dq[:3])


@pytest.mark.parametrize("name", ["puma560", "stanford"])
def test_momentum_identity_along_a_trajectory(name):
    # tau - friction = dp/dt - dL/dq along q(t) = q0 + a sin(w t) + b cos(2 w t), dp/dt by a
    # fourth-order central difference (h = 1e-3 s: error ~1e-13 x fifth derivatives ~ 1e2).
    robot = mindyn.load(name)
    robot.rotor_inertia = np.linspace(0.1, 0.6, robot.n)
    robot.viscous = np.full(robot.n, 0.5)
    robot.coulomb = np.full(robot.n, 0.3)
    p = robot.parameters(rotor=True, friction=True)
    r = np.random.default_rng(5)
    q0, a, b = r.uniform(-1, 1, (3, robot.n))
    w, h = 2.0, 1e-3

    def state(t):
        t = np.atleast_1d(t)[:, None]
        q = q0 + a * np.sin(w * t) + b * np.cos(2 * w * t)
        dq = a * w * np.cos(w * t) - 2 * w * b * np.sin(2 * w * t)
        ddq = -a * w**2 * np.sin(w * t) - 4 * w**2 * b * np.cos(2 * w * t)
        return q, dq, ddq

    def momentum(t):
        q, dq, _ = state(t)
        return robot.momentum_regressors(q, dq, rotor=True, friction=True)[0] @ p

    t = np.array([0.1, 0.7, 1.9])
    dp = -momentum(t + 2 * h) + 8 * momentum(t + h) - 8 * momentum(t - h) + momentum(t - 2 * h)
    dp /= 12 * h
    q, dq, ddq = state(t)
    _, Wl = robot.momentum_regressors(q, dq, rotor=True, friction=True)
    tau = robot.inverse_dynamics(q, dq, ddq, p) - 0.5 * dq - 0.3 * np.sign(dq)
    assert_close(dp + Wl @ p, tau, 1e-8, "dp/dt - dL/dq vs inverse dynamics")


def test_base_momentum_regressors():
    robot = mindyn.load("puma560")
    robot.rotor_inertia = np.linspace(0.1, 0.6, robot.n)
    bp = mindyn.base_parameters(robot, rotor=True, friction=True)
    r = np.random.default_rng(7)
    q, dq = r.uniform(-2, 2, (2, 4, robot.n))
    Wpb, Wlb = bp.momentum_regressors(q, dq)
    Wp, Wl = robot.momentum_regressors(q, dq, rotor=True, friction=True)
    pi = robot.parameters(rotor=True, friction=True)
    assert_close(Wpb @ bp.values(pi), Wp @ pi, 1e-10, "base momentum vs classical")
    assert_close(Wlb @ bp.values(pi), Wl @ pi, 1e-10, "base -dL/dq vs classical")
