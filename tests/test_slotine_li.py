"""The Slotine-Li regressor and Coriolis matrix against Pinocchio (crba, computeCoriolisMatrix,
computeGeneralizedGravity, rnea), finite differences of Pinocchio's mass matrix (skew-symmetry of
dA/dt - 2C) and the base regressor."""

from __future__ import annotations

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import BUNDLED, assert_close, load_urdf_pair, pinocchio_model, random_state
from mindyn.control import slotine_li_regressor_classical


def case(name):
    if name in ("ur5", "panda"):
        return load_urdf_pair(name)
    robot = mindyn.load(name)
    return robot, pinocchio_model(robot)


def pin_terms(model, data, q, dq):
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    C = pin.computeCoriolisMatrix(model, data, q, dq)
    g = pin.computeGeneralizedGravity(model, data, q)
    return M, C, g


@pytest.mark.parametrize("name", BUNDLED + ["ur5", "panda"])
def test_slotine_li_is_mass_coriolis_gravity_of_pinocchio(name, rng):
    robot, model = case(name)
    data = model.createData()
    base = mindyn.base_parameters(robot)
    pb = base.values(robot.params)
    for _ in range(4):
        q, dq, _ = random_state(robot, rng)
        dqr, ddqr = rng.uniform(-2, 2, (2, robot.n))
        M, C, g = pin_terms(model, data, q, dq)
        expected = M @ ddqr + C @ dqr + g
        Y = slotine_li_regressor_classical(robot, q, dq, dqr, ddqr)
        assert_close(Y @ robot.params, expected, 1e-10, "Slotine-Li Y p vs pin A ddqr + C dqr + g")
        Yb = mindyn.slotine_li_regressor(base, q, dq, dqr, ddqr)
        assert_close(Yb @ pb, expected, 1e-9, "Slotine-Li Y_b p_b vs pin")
        assert_close(mindyn.coriolis_matrix(robot, q, dq), C, 1e-10, "C vs pin Coriolis matrix")


@pytest.mark.parametrize("name", ["zcr07s", "puma560", "ur5"])
def test_reference_equal_to_motion_gives_the_base_regressor(name, rng):
    robot, _ = case(name)
    for rotor, friction in [(False, False), (True, True)]:
        base = mindyn.base_parameters(robot, rotor=rotor, friction=friction)
        q, dq, ddq = random_state(robot, rng, 5)
        Yb = mindyn.slotine_li_regressor(base, q, dq, dq, ddq)
        assert Yb.shape == (5, robot.n, base.n)
        assert_close(Yb, base.regressor(q, dq, ddq), 1e-12, "Slotine-Li(dq, ddq) == W_b")


def test_friction_and_rotor_columns(rng):
    """Rotor inertia enters through ddqr, friction through the actual dq (not dqr)."""
    robot = mindyn.load("zcr07s")
    model = pinocchio_model(robot)
    data = model.createData()
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    pb = base.values(robot.parameters(rotor=True, friction=True))
    q, dq, _ = random_state(robot, rng)
    dqr, ddqr = rng.uniform(-2, 2, (2, robot.n))
    M, C, g = pin_terms(model, data, q, dq)
    expected = (
        (M + np.diag(robot.rotor_inertia)) @ ddqr
        + C @ dqr
        + g
        + robot.viscous * dq
        + robot.coulomb * np.sign(dq)
    )
    Yb = mindyn.slotine_li_regressor(base, q, dq, dqr, ddqr)
    assert_close(Yb @ pb, expected, 1e-10, "Slotine-Li with Ia, Fv, Fc vs pin + closed form")


@pytest.mark.parametrize("name", ["puma560", "stanford", "panda"])
def test_mass_matrix_derivative_minus_two_coriolis_is_skew(name, rng):
    """dA/dt = sum_k dA/dq_k dq_k by central differences of Pinocchio's crba."""
    robot, model = case(name)
    data = model.createData()
    h = 1e-6
    for _ in range(3):
        q, dq, _ = random_state(robot, rng)
        Adot = np.zeros((robot.n, robot.n))
        for k in range(robot.n):
            e = np.zeros(robot.n)
            e[k] = h
            Ap = pin_terms(model, data, q + e, dq)[0]
            Am = pin_terms(model, data, q - e, dq)[0]
            Adot += (Ap - Am) / (2 * h) * dq[k]
        N = Adot - 2 * mindyn.coriolis_matrix(robot, q, dq)
        assert np.linalg.norm(N + N.T) <= 1e-7 * max(1.0, np.linalg.norm(Adot))
        assert np.linalg.norm(N) > 1e-3  # the property is not trivially met


def test_input_errors():
    robot = mindyn.load("puma560")
    base = mindyn.base_parameters(robot)
    z = np.zeros(6)
    with pytest.raises(ValueError, match=r"dqr has shape \(5,\)"):
        mindyn.slotine_li_regressor(base, z, z, np.zeros(5), z)
    with pytest.raises(ValueError, match="ddqr contains NaN at joint 2"):
        mindyn.slotine_li_regressor(base, z, z, z, [0, np.nan, 0, 0, 0, 0])
    with pytest.raises(ValueError, match="batches of equal length"):
        mindyn.slotine_li_regressor(base, np.zeros((2, 6)), z, z, z)
    with pytest.raises(ValueError, match="fits no layout"):
        mindyn.coriolis_matrix(robot, z, z, np.zeros(7))
