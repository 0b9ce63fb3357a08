"""The friction models' searches fit many base sets that differ in a few friction columns (the
Stribeck velocity, the smooth width, the Dahl sigma). The filtered regressor of such a set is
formed from the first set's with only its varied columns filtered again: it must equal the
whole regressor filtered, and the searches' cost must not grow with a cache of every set."""

from __future__ import annotations

import mindyn
import numpy as np
import pytest
from mindyn.control import simulate_inverse
from mindyn.identification.excitation import random_trajectory
from mindyn.identification.friction import dahl_base
from mindyn.identification.joint_data import JointData
from mindyn.identification.preprocess import KEPT_BASES, preprocess


@pytest.fixture(scope="module")
def logs():
    out = {}
    for side in ("joint", "motor"):
        robot = mindyn.load("puma560") if side == "joint" else coupled()
        log = simulate_inverse(robot, random_trajectory(robot, seed=2), rate=200.0, friction=True)
        data = JointData(log.t, log.q, log.dq, None, log.tau, units_checked=True)
        out[side] = (robot, preprocess(data))
    return out


def coupled():
    """The PUMA with a coupled wrist (motor 6 turns with joints 5 and 6) on the motor side."""
    import yaml

    doc = yaml.safe_load(open(mindyn.load("puma560").source).read())
    T = np.diag([50.0, 60.0, 40.0, 30.0, 30.0, 20.0])
    T[5, 4] = 20.0
    doc["transmissions"] = {"matrix": T.tolist()}
    import tempfile
    from pathlib import Path

    path = Path(tempfile.mkdtemp()) / "puma_coupled.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    robot = mindyn.load(path)
    assert robot.drive_side == "motor"
    return robot


@pytest.mark.parametrize("side", ["joint", "motor"])
@pytest.mark.parametrize("kind", ["stribeck", "smooth", "dahl"])
def test_a_family_member_equals_its_whole_regressor_filtered(logs, side, kind):
    robot, data = logs[side]
    pf = data.regressor_filter
    n = robot.n
    if kind == "dahl":
        first = dahl_base(mindyn.base_parameters(robot, friction=True), np.full(n, 300.0))
        others = [first.with_sigma(np.linspace(50.0, 900.0, n)), first.with_sigma(np.full(n, 2e3))]
    else:
        model = robot.with_friction_model(kind, velocity=np.full(n, 0.05))
        first = mindyn.base_parameters(model, friction=True)
        others = [
            first.with_friction_velocity(np.linspace(0.01, 0.4, n)),
            first.with_friction_velocity(np.full(n, 0.2)).with_friction_velocity(np.full(n, 1.0)),
        ]
    assert len(first._varied()) == n  # one varied column per slot
    pf.regressor(first)
    full = pf._full
    calls: list = []

    def counted(b):
        calls.append(b)
        return full(b)

    for base in others:
        pf._full = counted  # type: ignore[method-assign]
        got = pf.regressor(base)
        pf._full = full  # type: ignore[method-assign]
        assert calls == []  # from the first set's, its varied columns only
        want = pf._full(base)  # every column evaluated and filtered
        scale = np.abs(want).max(axis=(0, 1))
        assert np.all(np.abs(got - want) <= 1e-12 * np.maximum(scale, 1e-300))
        # the varied columns did change, the others are the first set's
        cols = [c for c, _, _ in base._varied()]
        assert not np.allclose(got[:, :, cols], pf._full(first)[:, :, cols])


def test_the_filter_keeps_a_bounded_number_of_regressors(logs):
    robot, data = logs["joint"]
    pf = data.regressor_filter
    model = robot.with_friction_model("stribeck", velocity=np.full(robot.n, 0.05))
    first = mindyn.base_parameters(model, friction=True)
    for w in np.linspace(0.02, 0.5, 3 * KEPT_BASES):
        pf.regressor(first.with_friction_velocity(np.full(robot.n, w)))
    assert len(pf._cache) <= KEPT_BASES
