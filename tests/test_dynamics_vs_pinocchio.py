"""Dynamics against Pinocchio: RNEA, CRBA, ABA, energies, gravity, regressors.

Bundled DH/MDH robots are compared with a pin.Model built from their geometry by
conftest.pinocchio_model(); the example-robot-data arms with pin.buildModelFromUrdf (Panda reduced
to its 7 arm joints with the fingers locked at 0).
"""

from __future__ import annotations

import functools

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import (
    BUNDLED,
    URDFS,
    assert_close,
    body_inertia,
    load_urdf_pair,
    pinocchio_model,
    random_state,
    set_pinocchio_params,
)

ALL = BUNDLED + list(URDFS)
TOL = 1e-10
N_STATES = 4


@functools.cache
def _robot(name: str) -> mindyn.Robot:
    if name in URDFS:
        return load_urdf_pair(name)[0]
    return mindyn.load(name)


def make_pair(name: str):
    """A fresh (mindyn Robot, pin.Model, pin.Data) for `name`."""
    robot = _robot(name)
    if name in URDFS:
        model = load_urdf_pair(name)[1]
    else:
        model = pinocchio_model(robot)
    return robot, model, model.createData()


def random_params(robot: mindyn.Robot, rng: np.random.Generator, positive_mass=False) -> np.ndarray:
    """Physically meaningless classical parameters with |m| >= 0.2 (Pinocchio needs m != 0).

    positive_mass: for Pinocchio algorithms that add inertias (CRBA's composite bodies), whose
    Inertia addition divides by max(total mass, eps) and so fails for negative totals."""
    p = rng.uniform(-1.0, 1.0, 10 * robot.n)
    m = p[9::10]
    p[9::10] = (1.0 if positive_mass else np.sign(m)) * (0.2 + np.abs(m))
    return p


def links_coincide(robot: mindyn.Robot) -> bool:
    """True when every link frame is its joint frame (URDF and MDH: post = I)."""
    return all(np.array_equal(robot.joint_post(k), np.eye(4)) for k in range(robot.n))


def param_map(robot: mindyn.Robot) -> np.ndarray:
    """Matrix A with pinocchio_dynamic_params(joint frames) = A @ classical params (link frames).

    Built from conftest.body_inertia (Pinocchio's se3Action), using that the change of frame is
    linear in the parameters: columns are differences around a unit-mass reference body.
    """
    n = robot.n
    A = np.zeros((10 * n, 10 * n))
    for k in range(n):
        post = robot.joint_post(k)
        ref = np.zeros(10)
        ref[[0, 3, 5, 9]] = 1.0
        base = body_inertia(ref, post).toDynamicParameters()
        for j in range(10):
            e = ref.copy()
            e[j] += 1.0
            A[10 * k : 10 * k + 10, 10 * k + j] = body_inertia(e, post).toDynamicParameters() - base
    return A


# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ALL)
def test_inverse_dynamics_matches_rnea(name, rng):
    robot, model, data = make_pair(name)
    for _ in range(N_STATES):
        q, dq, ddq = random_state(robot, rng)
        tau = robot.inverse_dynamics(q, dq, ddq)
        assert_close(tau, pin.rnea(model, data, q, dq, ddq), TOL, "inverse_dynamics vs pin.rnea")
        # params default to the inertial parameters only: equal to passing them explicitly
        assert_close(tau, robot.inverse_dynamics(q, dq, ddq, robot.params), 0.0, "default params")


@pytest.mark.parametrize("name", ALL)
def test_inverse_dynamics_random_params(name, rng):
    robot, model, data = make_pair(name)
    for _ in range(N_STATES):
        p = random_params(robot, rng)
        set_pinocchio_params(model, robot, p)
        q, dq, ddq = random_state(robot, rng)
        assert_close(
            robot.inverse_dynamics(q, dq, ddq, p),
            pin.rnea(model, data, q, dq, ddq),
            TOL,
            "inverse_dynamics(random params) vs pin.rnea",
        )
        assert_close(
            robot.gravity_torque(q, p),
            pin.computeGeneralizedGravity(model, data, q),
            TOL,
            "gravity_torque(random params) vs pin",
        )
        p = random_params(robot, rng, positive_mass=True)
        set_pinocchio_params(model, robot, p)
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        assert_close(robot.mass_matrix(q, p), M, TOL, "mass_matrix(random params) vs pin.crba")
        tau = pin.rnea(model, data, q, dq, ddq)
        assert_close(
            robot.inverse_dynamics(q, dq, ddq, p),
            tau,
            TOL,
            "inverse_dynamics(random params) vs pin.rnea",
        )


@pytest.mark.parametrize("name", ALL)
def test_mass_matrix_matches_crba(name, rng):
    robot, model, data = make_pair(name)
    for _ in range(N_STATES):
        q, _, _ = random_state(robot, rng)
        A = robot.mass_matrix(q)
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T  # crba fills the upper triangle
        assert_close(A, M, TOL, "mass_matrix vs pin.crba")
        np.testing.assert_array_equal(A, A.T)
        assert np.all(np.linalg.eigvalsh(A) > 0.0)


@pytest.mark.parametrize("name", ALL)
def test_forward_dynamics_matches_aba(name, rng):
    robot, model, data = make_pair(name)
    for _ in range(N_STATES):
        q, dq, _ = random_state(robot, rng)
        tau = rng.uniform(-20.0, 20.0, robot.n)
        ddq = robot.forward_dynamics(q, dq, tau)
        # ABA is a different algorithm (no mass matrix); the error scales with cond(A).
        tol = TOL * max(1.0, np.linalg.cond(robot.mass_matrix(q)) / 1e3)
        assert_close(ddq, pin.aba(model, data, q, dq, tau), tol, "forward_dynamics vs pin.aba")
        # and it inverts the inverse dynamics
        assert_close(robot.inverse_dynamics(q, dq, ddq), tau, tol, "inverse(forward) == tau")


@pytest.mark.parametrize("name", ALL)
def test_energies_match_pinocchio(name, rng):
    robot, model, data = make_pair(name)
    states = [random_state(robot, rng) for _ in range(N_STATES)]
    pots = []
    for q, dq, _ in states:
        assert_close(
            robot.kinetic_energy(q, dq),
            pin.computeKineticEnergy(model, data, q, dq),
            TOL,
            "kinetic_energy vs pin",
        )
        # Pinocchio's potential energy is -sum_i m_i g . c_i over the moving bodies (joint 1..n;
        # the fixed base body, inertias[0], is left out), with c_i the COM in the world frame
        # and the world origin as zero level: the same convention as mindyn, so there is no
        # constant offset and the values compare directly. The differences between two
        # configurations are compared as well, which would hold under any constant offset.
        P_pin = pin.computePotentialEnergy(model, data, q)
        P = robot.potential_energy(q)
        assert_close(P, P_pin, TOL, "potential_energy vs pin")
        H_pin = P_pin + pin.computeKineticEnergy(model, data, q, dq)
        assert_close(robot.energy(q, dq), H_pin, TOL, "energy vs pin")
        pots.append((P, P_pin))
    P, P_pin = np.array(pots).T
    assert_close(np.diff(P), np.diff(P_pin), TOL, "potential_energy differences vs pin")


@pytest.mark.parametrize("name", ALL)
def test_gravity_torque_matches_pinocchio(name, rng):
    robot, model, data = make_pair(name)
    for _ in range(N_STATES):
        q, _, _ = random_state(robot, rng)
        g = robot.gravity_torque(q)
        assert_close(g, pin.computeGeneralizedGravity(model, data, q), TOL, "gravity_torque vs pin")
        zero = np.zeros(robot.n)
        assert_close(g, robot.inverse_dynamics(q, zero, zero), 1e-14, "gravity == ID(q, 0, 0)")


@pytest.mark.parametrize("name", ["puma560", "stanford", "ur5"])
def test_other_gravity_matches_pinocchio(name, rng):
    if name in URDFS:
        robot, model = load_urdf_pair(name)
    else:
        robot = mindyn.load(name)
        model = pinocchio_model(robot)
    robot = robot.with_gravity([1.0, -2.0, -9.0])
    np.testing.assert_array_equal(robot.gravity, [1.0, -2.0, -9.0])
    model.gravity = pin.Motion(np.array([1.0, -2.0, -9.0]), np.zeros(3))
    data = model.createData()
    q, dq, ddq = random_state(robot, rng)
    what = "with_gravity vs pin"
    assert_close(robot.inverse_dynamics(q, dq, ddq), pin.rnea(model, data, q, dq, ddq), TOL, what)
    assert_close(robot.potential_energy(q), pin.computePotentialEnergy(model, data, q), TOL, what)


@pytest.mark.parametrize("name", ["puma560", "stanford", "planar3", "ur5", "panda"])
def test_batches_equal_single_calls(name, rng):
    robot = _robot(name)
    m = 7
    Q, DQ, DDQ = random_state(robot, rng, m)
    p = robot.parameters(rotor=True, friction=True)
    calls = {
        "inverse_dynamics": lambda q, dq, x: robot.inverse_dynamics(q, dq, x),
        "inverse_dynamics(p)": lambda q, dq, x: robot.inverse_dynamics(q, dq, x, p),
        "regressor": lambda q, dq, x: robot.regressor(q, dq, x, rotor=True, friction=True),
        "mass_matrix": lambda q, dq, x: robot.mass_matrix(q),
        "gravity_torque": lambda q, dq, x: robot.gravity_torque(q),
        "forward_dynamics": lambda q, dq, x: robot.forward_dynamics(q, dq, x),
        "kinetic_energy": lambda q, dq, x: robot.kinetic_energy(q, dq, p),
        "potential_energy": lambda q, dq, x: robot.potential_energy(q),
        "energy": lambda q, dq, x: robot.energy(q, dq),
        "energy_regressor": lambda q, dq, x: robot.energy_regressor(
            q, dq, rotor=True, friction=True
        ),
        "lagrangian_regressor": lambda q, dq, x: robot.lagrangian_regressor(q, dq),
    }
    for what, f in calls.items():
        batch = f(Q, DQ, DDQ)
        first = np.asarray(f(Q[0], DQ[0], DDQ[0]))
        assert batch.shape == (m, *first.shape), what
        for i in range(m):
            single = f(Q[i], DQ[i], DDQ[i])
            np.testing.assert_allclose(batch[i], single, rtol=1e-14, atol=1e-14, err_msg=what)
    wk, wp = robot.energy_regressors(Q, DQ)
    assert wk.shape == wp.shape == (m, 10 * robot.n)


@pytest.mark.parametrize("name", ALL)
def test_regressor_matches_pinocchio(name, rng):
    robot, model, data = make_pair(name)
    p = robot.params
    A = None if links_coincide(robot) else param_map(robot)
    for _ in range(N_STATES):
        q, dq, ddq = random_state(robot, rng)
        W = robot.regressor(q, dq, ddq)
        assert W.shape == (robot.n, 10 * robot.n)
        tau_pin = pin.rnea(model, data, q, dq, ddq)
        assert_close(W @ p, robot.inverse_dynamics(q, dq, ddq), 1e-12, "W @ params == ID")
        assert_close(W @ p, tau_pin, TOL, "regressor @ params vs pin.rnea")
        Wp = pin.computeJointTorqueRegressor(model, data, q, dq, ddq)
        if A is None:
            # same frames: W's columns are Pinocchio's, reordered per link.
            # W p = Wp to_pin(p) for every p, so each row of W is from_pin(row of Wp).
            expected = np.array([mindyn.from_pinocchio_order(row) for row in Wp])
            assert_close(W, expected, TOL, "regressor vs pin (reordered)")
            e = np.zeros(10 * robot.n)
            for j in range(10 * robot.n):
                e[:] = 0.0
                e[j] = 1.0
                assert_close(W[:, j], Wp @ mindyn.to_pinocchio_order(e), TOL, "regressor columns")
        else:
            # DH link frames differ from the joint frames: W = Wp @ A (A from Pinocchio's se3Action)
            assert_close(W, Wp @ A, TOL, "regressor vs pin (DH frames mapped)")


@pytest.mark.parametrize("name", ALL)
def test_energy_regressors_match_pinocchio(name, rng):
    robot, model, data = make_pair(name)
    A = None if links_coincide(robot) else param_map(robot)
    for _ in range(2):
        q, dq, _ = random_state(robot, rng)
        wk, wp = robot.energy_regressors(q, dq)
        wk_pin = pin.computeKineticEnergyRegressor(model, data, q, dq)
        wp_pin = pin.computePotentialEnergyRegressor(model, data, q)
        if A is None:
            wk_ref = mindyn.from_pinocchio_order(np.asarray(wk_pin).ravel())
            wp_ref = mindyn.from_pinocchio_order(np.asarray(wp_pin).ravel())
        else:
            wk_ref = np.asarray(wk_pin).ravel() @ A
            wp_ref = np.asarray(wp_pin).ravel() @ A
        assert_close(wk, wk_ref, TOL, "kinetic energy regressor vs pin")
        assert_close(wp, wp_ref, TOL, "potential energy regressor vs pin")


@pytest.mark.parametrize("name", ["puma560", "stanford", "zcr07s", "ur5", "panda"])
def test_rotor_inertia_and_friction(name, rng):
    _, model, data = make_pair(name)
    robot = load_urdf_pair(name)[0] if name in URDFS else mindyn.load(name)  # fresh, mutable
    n = robot.n
    Ia = rng.uniform(0.1, 2.0, n)
    Fv = rng.uniform(0.1, 5.0, n)
    Fc = rng.uniform(0.1, 5.0, n)
    robot.rotor_inertia, robot.viscous, robot.coulomb = Ia, Fv, Fc
    np.testing.assert_array_equal(robot.rotor_inertia, Ia)
    p = robot.parameters(rotor=True, friction=True)
    p_rotor = robot.parameters(rotor=True)
    p_fric = robot.parameters(friction=True)
    for i in range(N_STATES):
        q, dq, ddq = random_state(robot, rng)
        if i == 0:
            dq[0] = 0.0  # sign(0) = 0: no Coulomb torque at rest
        tau_rb = pin.rnea(model, data, q, dq, ddq)
        fric = Fv * dq + Fc * np.sign(dq)
        assert_close(
            robot.inverse_dynamics(q, dq, ddq, p),
            tau_rb + Ia * ddq + fric,
            TOL,
            "ID rotor+friction vs pin + terms",
        )
        assert_close(
            robot.inverse_dynamics(q, dq, ddq, p_rotor),
            tau_rb + Ia * ddq,
            TOL,
            "ID rotor vs pin + terms",
        )
        assert_close(
            robot.inverse_dynamics(q, dq, ddq, p_fric),
            tau_rb + fric,
            TOL,
            "ID friction vs pin + terms",
        )
        # the default parameters are the rigid-body ones only
        assert_close(robot.inverse_dynamics(q, dq, ddq), tau_rb, TOL, "ID default params vs pin")
        W = robot.regressor(q, dq, ddq, rotor=True, friction=True)
        assert_close(
            W @ p, tau_rb + Ia * ddq + fric, TOL, "regressor rotor+friction vs pin + terms"
        )
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        assert_close(
            robot.mass_matrix(q, p), M + np.diag(Ia), TOL, "mass_matrix rotor vs crba + Ia"
        )
        # gravity torque: neither rotor inertia nor friction contribute
        assert_close(
            robot.gravity_torque(q, p),
            pin.computeGeneralizedGravity(model, data, q),
            TOL,
            "gravity rotor+friction",
        )
        # kinetic energy gains 1/2 Ia dq^2
        K = pin.computeKineticEnergy(model, data, q, dq) + 0.5 * Ia @ dq**2
        assert_close(robot.kinetic_energy(q, dq, p), K, TOL, "kinetic energy rotor vs pin + terms")
        # forward dynamics: Pinocchio's ABA with armature = Ia on (tau - friction)
        tau = rng.uniform(-20, 20, n)
        model.armature = Ia
        ddq_pin = pin.aba(model, data, q, dq, tau - fric)
        model.armature = np.zeros(n)
        tol = TOL * max(1.0, np.linalg.cond(M + np.diag(Ia)) / 1e3)
        assert_close(
            robot.forward_dynamics(q, dq, tau, p),
            ddq_pin,
            tol,
            "forward_dynamics rotor+friction vs pin.aba",
        )


def test_planar2_closed_form():
    """Two uniform rods (0.5 m, 2 kg, radius 0.02 m, as described in planar2's notes)."""
    L, m, r, g = 0.5, 2.0, 0.02, 9.81
    Izz = m * (3 * r * r + L * L) / 12.0  # rod about a transverse axis through its centre
    a = L / 2
    for vertical in (True, False):
        robot = mindyn.load("planar2" if vertical else "planar2h")
        for q in ([0.3, -1.1], [2.0, 0.7], [-2.5, 2.9]):
            q1, q2 = q
            c2 = np.cos(q2)
            M11 = 2 * Izz + m * a * a + m * (L * L + a * a + 2 * L * a * c2)
            M12 = Izz + m * (a * a + L * a * c2)
            M22 = Izz + m * a * a
            assert_close(
                robot.mass_matrix(q), [[M11, M12], [M12, M22]], 1e-12, "planar2 closed form"
            )
            # angles measured from the horizontal x axis in the vertical case; gravity along -z
            G = np.zeros(2)
            if vertical:
                G[1] = m * g * a * np.cos(q1 + q2)
                G[0] = m * g * a * np.cos(q1) + m * g * (L * np.cos(q1) + a * np.cos(q1 + q2))
            assert_close(robot.gravity_torque(q), G, 1e-12, "planar2 closed form")
            dq = np.array([0.7, -1.3])
            h = -m * L * a * np.sin(q2)
            C = np.array([h * (2 * dq[0] * dq[1] + dq[1] ** 2), -h * dq[0] ** 2])
            zero = np.zeros(2)
            assert_close(robot.inverse_dynamics(q, dq, zero) - G, C, 1e-12, "planar2 closed form")
