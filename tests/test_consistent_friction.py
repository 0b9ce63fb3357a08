"""The consistent estimate keeps the friction dissipative under the robot's friction model:
``Fc + Fs >= 0`` (Stribeck) and ``|Fa| <= Fc`` (asymmetric), besides ``Ia, Fv, Fc >= 0``. On
logs this module generates whose joint-2 friction pushes the joint along at low speed (a
Stribeck ``Fs`` below ``-Fc``, an asymmetric ``Fa`` beyond ``Fc``: what a torque sensor's
drift or an unmodelled effect can leave in a fit), the unconstrained estimate violates the
constraint by many standard deviations, and the consistent one, with and without the prior,
holds it, at its boundary, where the least-squares problem restricted to that boundary (solved
here independently with numpy) has its optimum."""

from __future__ import annotations

import mindyn
import numpy as np
import pytest
from mindyn.identification import identify, select_friction_model
from mindyn.identification.consistent import consistent_estimate
from random_arm import random_arm_yaml
from test_friction_models import FC, FV, make_log


@pytest.fixture(scope="module")
def arm(tmp_path_factory):
    return mindyn.load(random_arm_yaml(tmp_path_factory.mktemp("arm") / "arm.yaml", n=3, seed=4))


CASES = {
    # Fc2 + Fs2 = -0.6 Fc2: below zero; the others dissipative
    "stribeck": (np.array([0.15, 0.25, 0.1]), np.array([1.0, -1.6, 0.5]), "Fs", (1.0,)),
    # Fc2 - Fa2 = -0.5 Fc2: the Coulomb torque backwards negative
    "asymmetric": (None, np.array([0.3, 1.5, -0.2]), "Fa", (1.0, -1.0)),
}


def fitted(arm, kind):
    w, f3, _, _ = CASES[kind]
    third = f3 * FC
    log = make_log(arm, kind, w, FV, FC, third, noise=0.01, seed=8)
    choice = select_friction_model(arm, [log], kind=kind, fit={"min_velocity": 0.0})
    res = identify(choice.robot, log, base=choice.base, rsd_threshold=None, min_velocity=0.0)
    return res


def value(names, values, name):
    return float(values[list(names).index(name)])


@pytest.mark.parametrize("kind", sorted(CASES))
@pytest.mark.parametrize("prior_weight", [0.0, "auto"])
def test_the_consistent_friction_is_dissipative(arm, kind, prior_weight):
    _, _, third, signs = CASES[kind]
    res = fitted(arm, kind)
    names = list(res.base.names)
    std = dict(zip(res.names, res.std))
    # the unconstrained estimate: joint 2's friction pushes, by many standard deviations
    fc2, t2 = value(names, res.full, "Fc2"), value(names, res.full, f"{third}2")
    worst = min(fc2 + s * t2 for s in signs)
    assert worst < -10 * np.hypot(std["Fc2"], std[f"{third}2"]), (fc2, t2)
    con = consistent_estimate(res, prior_weight=prior_weight)
    cn = list(res.base.classical_names)
    for k in (1, 2, 3):
        fc, t = value(cn, con.classical, f"Fc{k}"), value(cn, con.classical, f"{third}{k}")
        for s in signs:
            assert fc + s * t >= -1e-9 * abs(fc), (kind, k, fc, t)
    # joint 2 at the boundary: Fs2 = -Fc2, or Fa2 = Fc2 (its violated side)
    fc, t = value(cn, con.classical, "Fc2"), value(cn, con.classical, f"{third}2")
    edge = min(fc + s * t for s in signs)
    assert edge <= (1e-6 if prior_weight == 0.0 else 2e-2) * abs(fc), (fc, t)


def test_without_prior_the_boundary_optimum_is_the_least_squares_one(arm):
    """Stribeck, no prior: on the boundary Fs2 = -Fc2 the problem is linear least squares in
    the other base parameters (Fs2's column folded into Fc2's); solved here with numpy on the
    estimate's own system and row weights, its torques on the fit log are the consistent
    estimate's to 5 % of the constraint's effect (the estimate is taken within one noise
    variance of the optimum's fit, nearest the description)."""
    res = fitted(arm, "stribeck")
    con = consistent_estimate(res, prior_weight=0.0)
    names = list(res.base.names)
    w, f3, _, _ = CASES["stribeck"]
    data = make_log(arm, "stribeck", w, FV, FC, f3 * FC, noise=0.01, seed=8)
    Wb = res.base.regressor(data.q, data.dq, data.ddq).reshape(-1, len(names))
    i, j = names.index("Fc2"), names.index("Fs2")
    Wr = np.delete(Wb, j, axis=1)
    Wr[:, i if i < j else i - 1] -= Wb[:, j]  # Fs2 = -Fc2
    tau = data.tau.reshape(-1)
    sigma = np.asarray(res.joint_sigma)  # the fit's per-joint weights
    wts = np.tile(1.0 / sigma, data.m)
    sol = np.linalg.lstsq(Wr * wts[:, None], tau * wts, rcond=None)[0]
    want = Wr @ sol
    got = Wb @ con.full
    free = Wb @ res.full  # the unconstrained estimate's
    # the constraint moves the torques by |free - want|; the consistent estimate lies within 5 %
    # of that of the boundary optimum (it is taken within one noise variance of the optimum's
    # fit, nearest the description: TIE_BREAK_SLACK)
    assert np.abs(got - want).max() <= 0.05 * np.abs(free - want).max()
