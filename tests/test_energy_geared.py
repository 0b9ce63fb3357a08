"""The energy model on a geared arm: the kept estimates against the truth of a log the test
simulates, in units of the standard deviations the fit reports.

Reference: the true parameters of the simulated log (`mindyn simulate` of an MDH table with
gear ratios of 50-153, rotor inertia and motor friction, torque noise of a known level). With
all base parameters free the energy fit's estimates lie within about 2 of their standard
deviations of the truth; pruning removes parameters whose estimates are not distinguishable
from zero, and the kept ones take up their contributions (rotor terms r^2 Ia of 10^4 Ia make a
removed product of inertia of 0.2 move a kept one by tens), which the pruned standard
deviations alone do not cover."""

from __future__ import annotations

import json

import mindyn
import numpy as np
from mindyn.base import base_parameters
from mindyn.cli import main
from mindyn.identification import identify, load_logs
from mindyn.identification.validation import true_base_values

ARM = """
name: geared6
convention: mdh
angle_unit: deg
joints:
  - {name: j1, type: revolute, alpha: 0, d: 0, theta: 0, r: 0.675,
     limits: {lower: -185, upper: 185, velocity: 156, acceleration: 300, effort: 1500},
     inertial: {mass: 70.0, com: [0.05, -0.02, -0.165],
                inertia: {xx: 2.1, yy: 2.4, zz: 1.9, xy: 0.05, xz: -0.12, yz: 0.03}}}
  - {name: j2, type: revolute, alpha: 90, d: 0.26, theta: 90, r: 0,
     limits: {lower: -155, upper: 35, velocity: 156, acceleration: 300, effort: 1800},
     inertial: {mass: 32.0, com: [0.33, -0.02, 0.12],
                inertia: {xx: 0.25, yy: 1.6, zz: 1.55, xy: -0.02, xz: -0.04, yz: -0.01}}}
  - {name: j3, type: revolute, alpha: 0, d: 0.68, theta: 0, r: 0,
     limits: {lower: -130, upper: 154, velocity: 170, acceleration: 300, effort: 900},
     inertial: {mass: 26.0, com: [0.08, -0.12, -0.01],
                inertia: {xx: 0.6, yy: 0.35, zz: 0.62, xy: 0.03, xz: 0, yz: -0.01}}}
  - {name: j4, type: revolute, alpha: 90, d: 0.035, theta: 0, r: 0.67,
     limits: {lower: -350, upper: 350, velocity: 340, acceleration: 600, effort: 300},
     inertial: {mass: 9.5, com: [0.01, 0, -0.15],
                inertia: {xx: 0.15, yy: 0.16, zz: 0.03, xy: 0, xz: 0.004, yz: -0.002}}}
  - {name: j5, type: revolute, alpha: -90, d: 0, theta: 0, r: 0,
     limits: {lower: -120, upper: 120, velocity: 340, acceleration: 600, effort: 300},
     inertial: {mass: 4.2, com: [0, -0.02, 0.01],
                inertia: {xx: 0.014, yy: 0.012, zz: 0.011, xy: 0, xz: 0, yz: -0.0005}}}
  - {name: j6, type: revolute, alpha: 90, d: 0, theta: -90, r: 0.09,
     limits: {lower: -350, upper: 350, velocity: 440, acceleration: 800, effort: 150},
     inertial: {mass: 0.6, com: [0, 0, -0.01], inertia: {xx: 0.0006, yy: 0.0006, zz: 0.001}}}
transmissions:
  - {name: m1, joints: {j1: 147}, rotor_inertia: 1.2e-3, viscous: 1.0e-3, coulomb: 0.15}
  - {name: m2, joints: {j2: -153}, rotor_inertia: 1.2e-3, viscous: 1.0e-3, coulomb: 0.18}
  - {name: m3, joints: {j3: 121}, rotor_inertia: 6.0e-4, viscous: 8.0e-4, coulomb: 0.12}
  - {name: m4, joints: {j4: 80}, rotor_inertia: 1.8e-4, viscous: 3.0e-4, coulomb: 0.05}
  - {name: m5, joints: {j5: 50, j6: 50}, rotor_inertia: 1.2e-4, viscous: 2.0e-4, coulomb: 0.03}
  - {name: m6, joints: {j5: 50, j6: -50}, rotor_inertia: 1.2e-4, viscous: 2.0e-4, coulomb: 0.03}
"""


NOISE = "15,18,9,3,3,1.5"  # torque noise [N m], about 1 % of each joint's effort limit
LOW_NOISE = "0.15,0.18,0.09,0.03,0.03,0.015"


def _log(tmp_path, *, model="energy", noise=NOISE, seed=0, mode="tracking", filter="lowpass"):
    """A 10-s log of the arm (``tracking``: the computed-torque controller's command, held over
    each sample period; ``inverse``: inverse dynamics at the samples, a smooth torque)."""
    arm = tmp_path / "geared6.yaml"
    arm.write_text(ARM)
    out = tmp_path / f"{mode}{seed}.csv"
    argv = ["simulate", str(arm), "--rotor", "--friction", "--duration", "10", "--seed", str(seed)]
    argv += ["--mode", mode, "--torque-noise", noise, "-o", str(out)]
    assert main(argv) == 0
    robot = mindyn.load(str(arm))
    base = base_parameters(robot, rotor=True, friction=True)
    truth = json.loads(out.with_name(f"{mode}{seed}.truth.json").read_text())
    logs = load_logs([out], robot, model=model, filter=filter).fit.logs
    return robot, base, logs, true_base_values(base, truth)


def test_energy_estimates_of_a_geared_arm_lie_within_their_standard_deviations(tmp_path):
    robot, base, logs, truth = _log(tmp_path)
    full = identify(robot, logs, model="energy", base=base, rsd_threshold=0)
    z_full = (full.values - truth) / full.std
    assert np.mean(np.abs(z_full) <= 3) >= 0.95  # the fit with all parameters is honest
    res = identify(robot, logs, model="energy", base=base)  # the default pruning
    assert res.removed
    kept = [base.names.index(n) for n in res.names]
    err = res.values - truth[kept]
    # the standard deviations that assume the removed parameters zero do not cover the error
    inflation = res.settings["std_correlation"]["variance_factor"]
    _, pruned_std, _ = res.reduced.solve(kept, inflation=inflation)
    assert np.mean(np.abs(err) / pruned_std > 3) > 0.3, "the case no longer shows the bias"
    # the reported ones do, and the fit says why they are wider
    assert np.mean(np.abs(err) / res.std <= 3) >= 0.95
    assert res.settings["pruning_std"]["widened"]
    assert any("the larger ones, with the removed" in w for w in res.settings["warnings"])


def test_held_torques_are_integrated_as_held(tmp_path):
    # The controller's command is held over each sample period: Simpson's rule, taking it as
    # smooth, shifts it by about half a period, which at low noise biased the integral model's
    # estimates (a quarter beyond 3 standard deviations, up to 11); the default rule is chosen
    # from the data and is then the hold.
    robot, base, logs, truth = _log(tmp_path, model="integral", noise=LOW_NOISE, seed=1)
    res = identify(robot, logs, model="integral", base=base, rsd_threshold=0)
    assert res.settings["integration"] == "zoh"
    rss = res.settings["integration_choice"]["rss"]
    assert rss["zoh"] < rss["simpson"]
    assert np.mean(np.abs(res.values - truth) / res.std <= 3) >= 0.95
    # the energy model on the log as logged chooses the hold too
    robot, base, logs, truth = _log(
        tmp_path, model="energy", noise=LOW_NOISE, seed=1, filter="none"
    )
    res = identify(robot, logs, model="energy", base=base, rsd_threshold=0)
    assert res.settings["integration"] == "zoh"
    assert np.mean(np.abs(res.values - truth) / res.std <= 3) >= 0.95


def test_smooth_torques_are_integrated_by_simpson(tmp_path):
    # inverse dynamics at the samples: a smooth torque, which the hold would shift
    for model in ("integral", "energy"):
        robot, base, logs, truth = _log(
            tmp_path, model=model, noise=LOW_NOISE, seed=1, mode="inverse"
        )
        res = identify(robot, logs, model=model, base=base, rsd_threshold=0)
        assert res.settings["integration"] == "simpson", model
        rss = res.settings["integration_choice"]["rss"]
        assert rss["simpson"] < rss["zoh"] / 2, model
        assert np.mean(np.abs(res.values - truth) / res.std <= 3) >= 0.95, model
