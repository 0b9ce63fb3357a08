"""The torques of identified base-parameter values on a log as read (the raw and moving
validation measures, ``IdentificationResult.predict``): Newton-Euler with the classical vector
that carries the values gives ``W_b(q, dq, ddq) @ full``, the base regressor's product, to
round-off, whatever the model: rotor inertia, friction models, torque offsets, motors on the
motor side through a coupled transmission, a branching tree."""

from __future__ import annotations

import mindyn
import numpy as np
import pytest
from coupled_arms import coupled_wrist_urdf
from mindyn.identification import JointData
from mindyn.identification.estimation import predicted_torques
from random_tree import random_tree_urdf


def _robots(tmp_path):
    yield "puma560", mindyn.load("puma560"), {}
    zcr = mindyn.load("zcr07s")
    yield "zcr07s, all terms", zcr, dict(rotor=True, friction=True, offset=True)
    yield (
        "zcr07s, Stribeck",
        zcr.with_friction_model("stribeck", velocity=[0.05] * 6),
        dict(friction=True),
    )
    path, _ = coupled_wrist_urdf(tmp_path / "wrist.urdf")
    yield (
        "coupled wrist, motor side",
        mindyn.load(path).with_drive_side("motor"),
        dict(rotor=True, friction=True, offset=True),
    )
    yield (
        "tree",
        mindyn.load(random_tree_urdf(tmp_path / "tree.urdf", n=7, seed=2)),
        dict(rotor=True),
    )


def test_newton_euler_of_the_embedded_values_is_the_base_regressor_product(tmp_path):
    rng = np.random.default_rng(4)
    for label, robot, flags in _robots(tmp_path):
        base = mindyn.base_parameters(robot, **flags)
        m = 300
        q, dq, ddq = (rng.normal(size=(m, robot.n)) for _ in range(3))
        data = JointData(np.arange(m) * 1e-3, q, dq, ddq, np.zeros((m, robot.n)))
        full = rng.normal(size=base.n)
        want = base.regressor(q, dq, ddq) @ full
        got = predicted_torques(base, full, data)
        assert got.shape == (m, robot.n), label
        scale = np.max(np.abs(want))
        assert np.max(np.abs(got - want)) <= 1e-12 * scale, label


@pytest.mark.parametrize("m", [0, 1])
def test_short_logs(m):
    robot = mindyn.load("zcr07s")
    base = mindyn.base_parameters(robot, friction=True, offset=True)
    q = np.full((m, robot.n), 0.3)
    data = JointData(np.arange(m) * 1e-3, q, q, q, np.zeros((m, robot.n)))
    full = np.linspace(-1.0, 1.0, base.n)
    want = base.regressor(q, q, q).reshape(m, robot.n, base.n) @ full
    np.testing.assert_allclose(predicted_torques(base, full, data), want, rtol=1e-12, atol=1e-12)
