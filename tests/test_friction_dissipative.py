"""The dissipativity check of ``friction_model='auto'`` (:func:`active_friction`) weighs a
pruned fit's friction with the standard deviations of the fit with every base parameter.

A pruned fit's standard deviations assume the removed parameters zero and come out smaller
than the estimate's spread with them free: on a simulated Kinova arm without friction the
Coulomb, smooth and Stribeck fits were left out as "driving the motion" for a viscous
estimate of -1.6e-6 at 3.9 of its pruned standard deviations and 1.7 of the other, and the
most complex model won by elimination. The check is a t-statistic: these cases give it in
closed form."""

from __future__ import annotations

import dataclasses

import mindyn
import numpy as np
import pytest
from mindyn.control.simulation import SensorNoise, simulate_inverse
from mindyn.identification import JointData, identify
from mindyn.identification.excitation import random_trajectory
from mindyn.identification.friction import ACTIVE_SIGMAS, active_friction


@pytest.fixture(scope="module")
def fit():
    robot = mindyn.load("planar2")
    base = mindyn.base_parameters(robot, friction=True)
    log = simulate_inverse(
        robot, random_trajectory(robot, seed=1), noise=SensorNoise(torque=0.01), seed=2
    )
    data = JointData(log.t, log.q, log.dq, log.ddq_true, log.tau, "sim", {})
    return identify(robot, data, base=base, rsd_threshold=0), data


def _with_viscous(res, t_pruned: float, ratio: float):
    """``res`` with slot 1's friction only its viscous term, at ``t_pruned`` of its pruned
    standard deviation (1e-3), and the standard deviation with every base parameter free
    ``ratio`` times that."""
    names = list(res.base.names)
    friction = {n for n in names if n[:2] in ("Fv", "Fc")}
    kept = [n for n in res.names if n not in friction or n == "Fv1"]
    std = {n: s for n, s in zip(res.names, res.std)}
    std["Fv1"] = 1e-3
    full = np.array(res.full, float)
    for n in friction:
        full[names.index(n)] = 0.0
    full[names.index("Fv1")] = t_pruned * 1e-3
    free = np.array(res.initial["std"], float)
    free[names.index("Fv1")] = ratio * 1e-3
    return dataclasses.replace(
        res,
        names=kept,
        std=np.array([std[n] for n in kept]),
        full=full,
        initial={**res.initial, "std": free},
    )


def test_a_viscous_term_negative_beyond_both_spreads_is_not_friction(fit):
    res, data = fit
    why = active_friction(_with_viscous(res, -3.0, 1.0), [data])
    assert why is not None and why.startswith("the fitted friction drives the motion")
    assert "joint 1 at" in why


def test_a_viscous_term_negative_only_against_the_pruned_spread_is_friction(fit):
    """-3 pruned standard deviations, -1.5 of the spread with the removed parameters free:
    within ACTIVE_SIGMAS of zero, friction."""
    res, data = fit
    assert 3.0 / 2.0 < ACTIVE_SIGMAS < 3.0
    assert active_friction(_with_viscous(res, -3.0, 2.0), [data]) is None


def test_the_fit_itself_is_friction(fit):
    res, data = fit
    assert active_friction(res, [data]) is None
