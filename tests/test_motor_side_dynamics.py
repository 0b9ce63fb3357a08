"""Rotor inertia and friction on the motors of coupled transmissions: inverse dynamics,
regressor, mass matrix, forward dynamics, energies and momentum of a 6R arm with a four-bar
wrist (motor 6 turns with q5 + q6) and of a WAM-like 7R arm (differentials on joints 2-3 and
5-6), against Pinocchio's rnea / crba / kinetic energy plus the motor terms written out here
(T^T (Ia T ddq + Fv T dq + Fc sign(T dq))), and finite differences of the energies."""

from __future__ import annotations

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from coupled_arms import coupled_wrist_urdf, motor_terms, motor_values, wam_like_urdf

ARMS = {"wrist6": coupled_wrist_urdf, "wam7": wam_like_urdf}


@pytest.fixture(params=sorted(ARMS))
def arm(request, tmp_path):
    path, T = ARMS[request.param](tmp_path / f"{request.param}.urdf")
    robot = mindyn.load(path)
    model = pin.buildModelFromUrdf(str(path))
    n = robot.n
    Ia, Fv, Fc = motor_values(n, seed=n)
    params = robot.parameters(rotor=True, friction=True).copy()
    per = 13
    for k in range(n):
        params[k * per + 10 : k * per + 13] = Ia[k], Fv[k], Fc[k]
    return robot, model, T, params, (Ia, Fv, Fc)


def states(n, count=5, seed=0):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        yield rng.uniform(-2, 2, n), rng.uniform(-2, 2, n), rng.uniform(-3, 3, n)


def rel(a, b):
    return np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300)


def test_the_loaded_transmission_is_the_one_written(arm):
    robot, _, T, _, _ = arm
    assert robot.drive_side == "motor"
    np.testing.assert_array_equal(robot.transmission.T, T)


def test_inverse_dynamics_and_regressor_add_the_motor_terms_through_T(arm):
    robot, model, T, params, (Ia, Fv, Fc) = arm
    data = model.createData()
    for q, dq, ddq in states(robot.n):
        ref = pin.rnea(model, data, q, dq, ddq) + motor_terms(T, Ia, Fv, Fc, dq, ddq)
        assert rel(robot.inverse_dynamics(q, dq, ddq, params), ref) <= 1e-12
        W = robot.regressor(q, dq, ddq, rotor=True, friction=True)
        assert rel(W @ params, ref) <= 1e-12


def test_mass_matrix_and_forward_dynamics_include_T_transpose_Ia_T(arm):
    robot, model, T, params, (Ia, Fv, Fc) = arm
    data = model.createData()
    for q, dq, ddq in states(robot.n, seed=1):
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        Mref = M + T.T @ np.diag(Ia) @ T
        assert rel(robot.mass_matrix(q, params), Mref) <= 1e-12
        tau = pin.rnea(model, data, q, dq, ddq) + motor_terms(T, Ia, Fv, Fc, dq, ddq)
        assert rel(robot.forward_dynamics(q, dq, tau, params), ddq) <= 1e-9


def test_kinetic_energy_has_the_motor_rotor_energy(arm):
    robot, model, T, params, (Ia, _, _) = arm
    data = model.createData()
    for q, dq, _ in states(robot.n, seed=2):
        ref = pin.computeKineticEnergy(model, data, q, dq) + 0.5 * np.sum(Ia * (T @ dq) ** 2)
        assert abs(robot.kinetic_energy(q, dq, params) - ref) <= 1e-12 * abs(ref)
        wk, wp = robot.energy_regressors(q, dq, rotor=True, friction=True)
        assert abs(wk @ params - ref) <= 1e-12 * abs(ref)


def test_momentum_is_the_velocity_gradient_of_the_kinetic_energy(arm):
    """p = dK/d(dq) and Wl pi = -dL/dq, by central differences of the energies."""
    robot, _, T, params, (Ia, _, _) = arm
    h = 1e-6
    for q, dq, _ in states(robot.n, count=3, seed=3):
        Wp, Wl = robot.momentum_regressors(q, dq, rotor=True, friction=True)
        p = Wp @ params
        fd_p = np.array(
            [
                (
                    robot.kinetic_energy(q, dq + h * e, params)
                    - robot.kinetic_energy(q, dq - h * e, params)
                )
                / (2 * h)
                for e in np.eye(robot.n)
            ]
        )
        assert rel(p, fd_p) <= 1e-7

        def lag(x, dq=dq):
            return robot.kinetic_energy(x, dq, params) - robot.potential_energy(x, params)

        fd_l = np.array([-(lag(q + h * e) - lag(q - h * e)) / (2 * h) for e in np.eye(robot.n)])
        assert rel(Wl @ params, fd_l) <= 1e-6
        # The rotor's share of the momentum, by hand.
        Wp0, _ = robot.with_drive_side("joint").momentum_regressors(
            q, dq, rotor=True, friction=True
        )
        params0 = params.copy()
        params0[10::13] = 0.0
        assert rel(p - Wp0 @ params0, T.T @ (Ia * (T @ dq))) <= 1e-12


def test_joint_side_keeps_the_terms_on_the_joints(arm):
    """With the drive side 'joint', slot k acts on joint k as without transmissions."""
    robot, model, _, params, (Ia, Fv, Fc) = arm
    joint = robot.with_drive_side("joint")
    data = model.createData()
    eye = np.eye(robot.n)
    for q, dq, ddq in states(robot.n, count=2, seed=4):
        ref = pin.rnea(model, data, q, dq, ddq) + motor_terms(eye, Ia, Fv, Fc, dq, ddq)
        assert rel(joint.inverse_dynamics(q, dq, ddq, params), ref) <= 1e-12


def test_the_simulation_plant_applies_the_motor_friction_through_T(arm):
    """The integrator's forward dynamics (Coulomb torque taken out of the parameters and applied
    at each motor's velocity, sign or tanh) inverts the reference torques."""
    robot, model, T, params, (Ia, Fv, Fc) = arm
    data = model.createData()
    eps = 0.05
    exact = mindyn._core.Integrator(robot._m, params, 0.0)
    smooth = mindyn._core.Integrator(robot._m, params, eps)
    for q, dq, ddq in states(robot.n, count=3, seed=5):
        rigid = pin.rnea(model, data, q, dq, ddq)
        tau = rigid + motor_terms(T, Ia, Fv, Fc, dq, ddq)
        assert rel(exact.acceleration(q, dq, tau), ddq) <= 1e-9
        vm = T @ dq
        tau_s = rigid + T.T @ (Ia * (T @ ddq) + Fv * vm + Fc * np.tanh(vm / eps))
        assert rel(smooth.acceleration(q, dq, tau_s), ddq) <= 1e-9
