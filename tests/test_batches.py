"""Every per-sample function on batches of m = 0, 1 and 3 samples: shape (m, ...) and each row
equal to the single-sample call on that sample. An empty batch gives an empty result. The
bindings are called directly as well, without the Python argument checks in front of them."""

from __future__ import annotations

import mindyn
import numpy as np
import pytest
from mindyn import _core
from mindyn.codegen import BaseDynamics
from mindyn.control import coriolis_matrix, slotine_li_regressor, slotine_li_regressor_classical

ROBOT = mindyn.load("puma560")
BASE = mindyn.base_parameters(ROBOT, rotor=True, friction=True)
BD = BaseDynamics(BASE)
P13 = ROBOT.parameters(rotor=True, friction=True)

# name -> (number of per-sample arguments, function of them)
FUNCTIONS = {
    "inverse_dynamics": (3, lambda *a: ROBOT.inverse_dynamics(*a)),
    "inverse_dynamics params": (3, lambda *a: ROBOT.inverse_dynamics(*a, P13)),
    "regressor": (3, lambda *a: ROBOT.regressor(*a, rotor=True, friction=True)),
    "gravity_torque": (1, lambda q: ROBOT.gravity_torque(q)),
    "mass_matrix": (1, lambda q: ROBOT.mass_matrix(q)),
    "forward_dynamics": (3, lambda *a: ROBOT.forward_dynamics(*a)),
    "kinetic_energy": (2, lambda *a: ROBOT.kinetic_energy(*a)),
    "potential_energy": (1, lambda q: ROBOT.potential_energy(q)),
    "energy": (2, lambda *a: ROBOT.energy(*a)),
    "energy_regressors": (2, lambda *a: np.stack(ROBOT.energy_regressors(*a), axis=-1)),
    "energy_regressor": (2, lambda *a: ROBOT.energy_regressor(*a)),
    "lagrangian_regressor": (2, lambda *a: ROBOT.lagrangian_regressor(*a)),
    "BaseParameters.regressor": (3, lambda *a: BASE.regressor(*a)),
    "BaseParameters.energy_regressor": (2, lambda *a: BASE.energy_regressor(*a)),
    "slotine_li_regressor": (4, lambda *a: slotine_li_regressor(BASE, *a)),
    "slotine_li_regressor_classical": (4, lambda *a: slotine_li_regressor_classical(ROBOT, *a)),
    "coriolis_matrix": (2, lambda *a: coriolis_matrix(ROBOT, *a)),
    "BaseDynamics.inverse_dynamics": (3, lambda *a: BD.inverse_dynamics(*a)),
    "BaseDynamics.gravity": (1, lambda q: BD.gravity(q)),
    "BaseDynamics.regressor": (3, lambda *a: BD.regressor(*a)),
    # the bindings themselves
    "_core inverse_dynamics": (3, lambda *a: ROBOT._m.inverse_dynamics(*a, None)),
    "_core gravity_torque": (1, lambda q: ROBOT._m.gravity_torque(q, None)),
    "_core forward_dynamics": (3, lambda *a: ROBOT._m.forward_dynamics(*a, None)),
    "_core regressor": (3, lambda *a: ROBOT._m.regressor(*a, True, False)),
    "_core mass_matrix": (1, lambda q: ROBOT._m.mass_matrix(q, None)),
    "_core energies": (2, lambda *a: np.stack(ROBOT._m.energies(*a, None), axis=-1)),
    "_core energy_regressors": (
        2,
        lambda *a: np.stack(ROBOT._m.energy_regressors(*a, False, True), axis=-1),
    ),
    "_core base regressor": (3, lambda *a: BASE._b.regressor(*a)),
    "_core base energy_regressor": (2, lambda *a: BASE._b.energy_regressor(*a)),
    "_core slotine_li_regressor": (4, lambda *a: _core.slotine_li_regressor(BASE._b, *a)),
    "_core slotine_li_regressor_classical": (
        4,
        lambda *a: _core.slotine_li_regressor_classical(ROBOT._m, *a, True, True),
    ),
    "_core coriolis_matrix": (2, lambda *a: _core.coriolis_matrix(ROBOT._m, *a, None)),
    "_core BaseDynamics.inverse_dynamics": (
        3,
        lambda *a: BD._d.inverse_dynamics(*a, BD._values(None)),
    ),
    "_core BaseDynamics.gravity": (1, lambda q: BD._d.gravity(q, BD._values(None))),
    "_core BaseDynamics.regressor": (3, lambda *a: BD._d.regressor(*a)),
}


@pytest.mark.parametrize("name", sorted(FUNCTIONS))
@pytest.mark.parametrize("m", [0, 1, 3])
def test_batch_matches_single_samples(name, m):
    count, f = FUNCTIONS[name]
    rng = np.random.default_rng(5)
    args = [rng.uniform(-1.5, 1.5, (m, 6)) for _ in range(count)]
    single = np.asarray(f(*[a[0] for a in rng.uniform(-1, 1, (count, 1, 6))]))
    out = np.asarray(f(*args))
    assert out.shape == (m, *single.shape)
    for i in range(m):
        np.testing.assert_array_equal(out[i], np.asarray(f(*[a[i] for a in args])))


def test_empty_batch_at_a_page_end():
    """An empty batch whose (empty) data sits at the end of an allocation is not read."""
    big = np.zeros((1024, 6))
    e = big[1024:]
    assert e.shape == (0, 6)
    assert ROBOT.inverse_dynamics(e, e, e).shape == (0, 6)
    assert ROBOT._m.inverse_dynamics(e, e, e, None).shape == (0, 6)
