"""The sampled adaptation of adaptive PD: its step condition (the largest stable adaptation gain
of the discrete update) against the update's own behaviour in closed loop, the box on the
estimate against the linearised check it comes from, and the xArm7 at 4 ms, whose estimate
drifted until the loop diverged, tracking with the default gains and box."""

from __future__ import annotations

import re

import mindyn
import numpy as np
import pytest
from conftest import ROBOTS_DIR
from mindyn import codegen, control
from mindyn.cli import main
from mindyn.control.controllers import controller_check, estimate_box, plant_parameters
from mindyn.control.stability import adaptation_step_ratio, workspace_samples

XARM7 = ROBOTS_DIR / "xarm_description/urdf/xarm7.urdf"


class Ramp:
    """A constant acceleration ``a`` from ``q = -2`` at rest: the Slotine-Li regressor of a
    single inertia is the constant ``a`` along it."""

    n = 1

    def __init__(self, a: float, duration: float):
        self.a, self.duration = a, duration

    def evaluate(self, t):
        t = np.atleast_1d(np.asarray(t, dtype=float))[:, None]
        return 0.5 * self.a * t * t - 2.0, self.a * t, np.full_like(t, self.a)


@pytest.mark.parametrize("nu", [0.0, 3.0])
def test_step_condition_is_the_largest_stable_adaptation_gain(nu):
    """One inertia (planar1h: no gravity, the base parameter ZZ1) on a constant-acceleration
    reference, its estimate 20 % off: the step condition gives Gamma* = K_D (1 + nu a^2) /
    (T a^2) (the closed form of the one-joint derivation); the library's AdaptivePD in closed
    loop converges at 0.8 Gamma* (the error never grows, ends below 2 %) and not at
    1.25 Gamma* (nu = 0: the loop diverges; nu > 0 bounds each step, and the estimate error
    grows tenfold to a limit cycle); the simulator's report says so."""
    robot = mindyn.load("planar1h")
    base = mindyn.base_parameters(robot)
    p = base.values(robot.parameters())
    T, a, kd, lam, duration = 0.004, 0.5, 2.0, 5.0, 4.0
    ref = Ramp(a, duration)
    qd, dqd, ddqd = ref.evaluate(np.arange(0.0, duration, T))
    Y = control.slotine_li_regressor(base, qd, dqd, dqd, ddqd)
    g_star = 1.0 / adaptation_step_ratio(Y, [kd], 1.0, nu, T).max()
    assert g_star == pytest.approx(kd * (1 + nu * a * a) / (T * a * a), rel=1e-9)
    run = dict(rate=1.0 / T, duration=duration)

    ctl = control.AdaptivePD(base, kd, lam, 0.8 * g_star, 1.2 * p, nu=nu, period=T)
    r = control.simulate(robot, ref, ctl, **run)
    err = np.abs(r.p_hat[:, 0] - p[0])
    assert err.max() <= err[0] * (1 + 1e-9) and err[-1] < 0.02 * err[0]
    assert "at most 0.8 (" in r.info["stability"] and "NOT MET" not in r.info["stability"]

    ctl = control.AdaptivePD(base, kd, lam, 1.25 * g_star, 1.2 * p, nu=nu, period=T)
    if nu == 0:
        with pytest.raises(
            control.UnstableLoopError, match=r"(?s)diverged.*at most 1.25 \(.{0,50}NOT MET"
        ):
            control.simulate(robot, ref, ctl, **run)
    else:  # the normalisation bounds each step: the estimate error grows to a limit cycle
        r = control.simulate(robot, ref, ctl, **run)
        err = np.abs(r.p_hat[:, 0] - p[0])
        assert err.max() > 10.0 * err[0] and err[-1] > err[0]
        assert "at most 1.25 (" in r.info["stability"] and "NOT MET" in r.info["stability"]


def test_default_nu_keeps_the_step_condition_for_any_regressor(rng):
    """nu = 3 Gamma T / min K_D of the default gains: the step condition at most 1/3 for
    regressors of any size (random, scaled over twelve decades), and 1/3 for a large one on the
    joint of the smallest K_D."""
    robot = mindyn.load("puma560")
    gains = control.default_gains(robot, rotor=True)
    nb = mindyn.base_parameters(robot, rotor=True, friction=True).n
    Y = rng.standard_normal((60, robot.n, nb)) * np.logspace(-6, 6, 60)[:, None, None]
    ratio = adaptation_step_ratio(Y, gains["kd"], gains["gamma"], gains["nu"], 0.004)
    assert ratio.max() <= 1.0 / 3.0 + 1e-12
    # a large regressor acting on the joint of the smallest K_D alone reaches it (not slack)
    weak = np.zeros((robot.n, nb))
    weak[int(np.argmin(gains["kd"]))] = 1e6 * rng.standard_normal(nb)
    ratio = adaptation_step_ratio(weak, gains["kd"], gains["gamma"], gains["nu"], 0.004)
    assert ratio[0] == pytest.approx(1.0 / 3.0, rel=1e-6)


def test_box_sides_are_shares_of_where_the_loop_check_turns_unstable():
    """The xArm7 at 4 ms (a wrist whose viscous friction is fast beside the period): each side
    of the box on the estimate is the stated share 1/S of the change that alone makes the
    sampled loop unstable. controller_check (the assembled check of the simulator, on the same
    24 configurations) finds the model stable with the parameter moved 0.95 S times that side
    and unstable at 1.05 S, for the two tightest parameters; and stable at the corners with
    every parameter at its lower or its upper side and at random points of the box (the
    parameters moving together; other points than those the box was sized on)."""
    robot = mindyn.load(str(XARM7))
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    gains = control.default_gains(robot, rotor=True)
    qs = workspace_samples(robot)
    lo, hi, note = estimate_box(robot, base, gains, qs=qs)
    full = plant_parameters(robot, True)
    p_d = control.controllers.base_values(base, full)
    assert np.all(lo <= p_d) and np.all(p_d <= hi)
    share = float(re.search(r"each to 1/([0-9.]+) of the change", note).group(1))
    bounded = int(np.sum(np.isfinite(lo) | np.isfinite(hi)))
    assert 3.0 <= share <= 3.0 * bounded  # a third of a fraction in [1/N, 1]

    def stable(p) -> bool:
        ctl = control.make_controller(
            "adaptive-pd", robot, gains, p, base=base, period=0.004, box=False
        )
        return controller_check(robot, ctl, full, 0.004).stable

    side = np.concatenate([p_d - lo, hi - p_d])
    scale = np.concatenate([np.abs(p_d)] * 2)
    finite = np.flatnonzero(np.isfinite(side) & (scale > 0))
    picks = finite[np.argsort(side[finite] / scale[finite])[:2]]
    assert "Fv7" in [base.names[k % base.n] for k in picks]  # the wrist's friction
    for k in picks:
        j, sign = k % base.n, (1.0 if k >= base.n else -1.0)
        for factor, expected in ((0.95, True), (1.05, False)):
            p = p_d.copy()
            p[j] += sign * factor * share * side[k]
            assert stable(p) is expected, (base.names[j], sign, factor)
    low, high = np.where(np.isfinite(lo), lo, p_d), np.where(np.isfinite(hi), hi, p_d)
    rng = np.random.default_rng(12345)
    for p in [low, high] + [low + rng.uniform(size=base.n) * (high - low) for _ in range(3)]:
        assert stable(p)


def test_xarm7_at_4ms_tracks_with_the_default_box():
    """The defect: on the xArm7 at 4 ms with the default gains and the true parameters as the
    initial estimate, the estimate drifted (the wrist's viscous friction above the robot's,
    its inertia down) and the loop diverged at 2.49 s while the check found it stable. With
    the default box the estimate stays in it and, over 3 s, every joint tracks within 3 times
    the error of the same loop with the estimate frozen at the true values (an independent
    run)."""
    robot = mindyn.load(str(XARM7))
    T = 0.004
    gains = control.default_gains(robot, period=T, rotor=True)
    ref = control.SumOfSines(robot, period=10.0, seed=0)
    run = dict(rate=1.0 / T, duration=3.0, rotor=True, friction=True, endpoint=False)
    ctl = control.make_controller("adaptive-pd", robot, gains, period=T)
    r = control.simulate(robot, ref, ctl, **run)
    assert np.all((r.p_hat >= ctl.p_min) & (r.p_hat <= ctl.p_max))
    assert "adaptation step condition along the reference" in r.info["stability"]
    frozen = control.make_controller("adaptive-pd", robot, gains, period=T, box=False)
    frozen.adapt = False
    f = control.simulate(robot, ref, frozen, **run)
    assert np.all(r.max_error_deg() <= 3.0 * f.max_error_deg())


def test_generated_step_has_the_library_box():
    """generate_controller's default box on adaptive PD's estimate is make_controller's (the
    same law in the loop, tests/test_codegen_controller.py)."""
    robot = mindyn.load("puma560_3")
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    gains = control.default_gains(robot, rotor=True)
    ctl = control.make_controller("adaptive-pd", robot, gains, base=base)
    code = codegen.generate_controller(robot, base=base, gains=gains)
    assert np.array_equal(code.settings["p_min"], ctl.p_min)
    assert np.array_equal(code.settings["p_max"], ctl.p_max)
    assert np.isfinite(ctl.p_min).sum() > 0 and code.settings["box"] == ctl.box_note


def test_estimate_box_option_applies_to_adaptive_pd_only(capsys):
    """--estimate-box with another controller is refused in one line."""
    assert main(["track", "planar2", "--controller", "pd", "--estimate-box", "none"]) == 2
    err = capsys.readouterr().err
    assert "--estimate-box" in err and len(err.strip().splitlines()) == 1
