"""The controllers, the momentum observer and the external-torque profile keep their own copies
of the arrays they are given: a caller who edits an array after handing it over (or edits what a
call returned) leaves them computing what they computed before. The answers are closed forms:
a PD torque ``-K_P e - K_D de``, the observer's filter ``a = (1 - K T/2) / (1 + K T/2)``,
``c = K / (1 + K T/2)`` and a held step profile."""

from __future__ import annotations

import mindyn
import numpy as np
import pytest
from mindyn import ArgumentError, control

ROBOT = mindyn.load("puma560")
BASE = mindyn.base_parameters(ROBOT)
T = 0.004


def test_pd_and_adaptive_pd_gains_do_not_follow_the_callers_arrays():
    kp, kd = np.full(6, 100.0), np.full(6, 20.0)
    pd = control.PD(6, kp, kd)
    kp[:] = 0.0
    kd[:] = 0.0
    e, de = np.linspace(0.1, 0.6, 6), np.linspace(-1, 1, 6)
    zero = np.zeros(6)
    np.testing.assert_allclose(pd(0.0, e, de, zero, zero, zero), -100.0 * e - 20.0 * de)

    gains = control.default_gains(ROBOT, period=T)
    kd, lam = np.array(gains["kd"]), np.array(gains["lambda"])
    gamma = np.ones(BASE.n)
    adaptive = control.AdaptivePD(
        BASE, kd, lam, gamma, BASE.values(ROBOT.params), period=T, nu=gains["nu"]
    )
    kd[:], lam[:], gamma[:] = 0.0, 0.0, 0.0
    np.testing.assert_array_equal(adaptive.kd, gains["kd"])
    np.testing.assert_array_equal(adaptive.lam, gains["lambda"])
    np.testing.assert_array_equal(adaptive.gamma, np.ones(BASE.n))


def test_pd_refuses_a_joint_count_that_is_not_an_integer():
    with pytest.raises(ArgumentError, match=r"^n is a Robot; expected an integer$"):
        control.PD(ROBOT, 1.0, 1.0)


def test_a_period_given_as_text_is_refused():
    with pytest.raises(ArgumentError, match="period must be a number of seconds, got '0.004'"):
        control.MomentumObserver(BASE, BASE.values(ROBOT.params), period="0.004")


def test_the_observer_keeps_its_values_and_gains():
    values = BASE.values(ROBOT.params).copy()
    gains = np.linspace(5.0, 30.0, 6)
    observer = control.MomentumObserver(BASE, values, period=T, gains=gains)
    fresh = control.MomentumObserver(BASE, values.copy(), period=T, gains=gains.copy())
    values[:] = 0.0
    gains[:] = 400.0
    h = 0.5 * np.linspace(5.0, 30.0, 6) * T
    a, c = observer.filter_coefficients()
    np.testing.assert_allclose(a, (1 - h) / (1 + h), rtol=1e-15)
    np.testing.assert_allclose(c, np.linspace(5.0, 30.0, 6) / (1 + h), rtol=1e-15)
    for name in ("values", "gains"):
        with pytest.raises(ValueError, match="read-only"):
            getattr(observer, name)[0] = 1.0
    rng = np.random.default_rng(3)
    q, dq, tau = rng.uniform(-1, 1, (3, 50, 6))
    np.testing.assert_array_equal(observer.run(q, dq, tau), fresh.run(q, dq, tau))
    # the residual's spread from the parameters' uncertainty uses the observer's gains
    std = np.full(BASE.n, 1e-3)
    np.testing.assert_array_equal(
        control.residual_uncertainty(observer, std, q, dq),
        control.residual_uncertainty(fresh, std, q, dq),
    )


def test_a_torque_profile_is_its_own():
    torque = np.array([0.0, 0.0, 5.0, 0.0, 0.0, 0.0])
    profile = control.TorqueProfile(torque, 0.1, 0.2)
    torque[2] = -100.0
    first = profile(0.15)
    first[2] = 7.0  # the caller's own array
    np.testing.assert_array_equal(profile(0.15), [0, 0, 5.0, 0, 0, 0])
    np.testing.assert_array_equal(profile(0.2), np.zeros(6))  # stop is excluded
    np.testing.assert_array_equal(profile(0.05), np.zeros(6))


@pytest.mark.parametrize(
    "args, message",
    [
        (("x",), r"^torque is a str 'x'; expected an array of shape \(\*,\)$"),
        ((np.full(6, np.nan),), r"^torque contains NaN at entry 1; expected finite values$"),
        ((np.ones(6), "0"), r"^start is a str '0'; expected a number$"),
        ((np.ones(6), 2.0, 1.0), r"^stop is 1; expected a time after start \(2 s\)$"),
        ((np.ones(6), 0.0, np.inf), r"^stop is inf; expected a finite number$"),
    ],
)
def test_a_bad_torque_profile_is_refused_naming_the_keyword(args, message):
    with pytest.raises(ArgumentError, match=message):
        control.TorqueProfile(*args)


def test_alarm_intervals_of_a_known_residual():
    t = np.arange(8) * 0.5
    r = np.zeros((8, 2))
    r[2:4, 0] = [2.0, -3.0]
    r[6, 1] = 1.5
    alarms = control.alarm_intervals(t, r, [1.0, 1.0])
    assert [(a["joint"], a["start"], a["end"], a["peak"]) for a in alarms] == [
        (1, 1.0, 1.5, -3.0),
        (2, 3.0, 3.0, 1.5),
    ]


def test_alarm_intervals_refuse_thresholds_that_are_not_positive_and_unordered_times():
    t, r = np.arange(4.0), np.zeros((4, 2))
    with pytest.raises(ArgumentError, match=r"^thresholds has -1 for joint 2; expected positive"):
        control.alarm_intervals(t, r, [1.0, -1.0])
    with pytest.raises(ArgumentError, match=r"^thresholds has 0 for joint 1; expected positive"):
        control.alarm_intervals(t, r, [0.0, 1.0])
    with pytest.raises(ArgumentError, match=r"^t is not strictly increasing at sample 3$"):
        control.alarm_intervals(np.array([0.0, 1.0, 1.0, 2.0]), r, [1.0, 1.0])


def test_default_gains_state_their_values():
    gains = control.default_gains(ROBOT, period=T)
    for kind in ("adaptive-pd", "pd"):
        note = gains.note_for(kind)
        assert "K_D [" + ", ".join(f"{v:.4g}" for v in gains["kd"]) + "]" in note
        assert "Lambda [" + ", ".join(f"{v:.4g}" for v in gains["lambda"]) + "]" in note


def test_the_summary_gives_no_relative_error_for_a_parameter_whose_truth_is_zero():
    """The simulated robot has no friction while the controller's model has it: the friction
    parameters' true values are zero, their relative error undefined (was the error over 1e-9)."""
    robot = mindyn.load("planar2")
    gains = control.default_gains(robot, period=T)
    ctl = control.make_controller("adaptive-pd", robot, gains, period=T, rotor=False, box=False)
    res = control.simulate(robot, control.SumOfSines(robot, period=1.0), ctl, duration=0.5)
    out = control.summary(res)["final_parameter_relative_error"]
    names = list(ctl.base.names)
    truth = res.p_true[-1] if res.p_true.ndim == 2 else res.p_true
    for name, v, p in zip(names, res.p_hat[-1], truth, strict=True):
        if p == 0:
            assert out[name] is None, name
        else:
            assert out[name] == pytest.approx((v - p) / abs(p), rel=1e-12), name
    assert any(out[name] is None for name in names if name.startswith("F"))


def test_the_truth_sidecar_says_where_the_external_torque_acted(tmp_path):
    """Two steps of a known torque on planar2 at 100 Hz (one from 0.3 to 0.5 s on joint 2, one
    from 0.8 s to the end on both joints): the sidecar's spans are those runs, each stopping
    where the hold ends, with the step's value as its peak."""
    import json

    from mindyn.control.simulation import SumOfSines, simulate

    robot = mindyn.load("planar2")
    first = control.TorqueProfile([0.0, -1.5], start=0.3, stop=0.5)
    second = control.TorqueProfile([2.0, 0.25], start=0.8)
    res = simulate(
        robot,
        SumOfSines(robot, period=2.0, fraction=0.2, seed=1),
        rate=100.0,
        duration=1.0,
        external=lambda t, q, dq: first(t) + second(t),
    )
    doc = json.loads(res.save(tmp_path / "log.csv").with_name("log.truth.json").read_text())
    ext = doc["external"]
    assert ext["count"] == 2
    (a, b) = ext["spans"]
    assert a["start_s"] == pytest.approx(0.3) and a["stop_s"] == pytest.approx(0.5)
    assert a["peak"] == [0.0, -1.5]
    assert b["start_s"] == pytest.approx(0.8) and b["stop_s"] == pytest.approx(1.01)
    assert b["peak"] == [2.0, 0.25]
    quiet = simulate(robot, SumOfSines(robot, period=2.0, fraction=0.2, seed=1), duration=0.1)
    doc = json.loads(quiet.save(tmp_path / "q.csv").with_name("q.truth.json").read_text())
    assert "external" not in doc


def test_the_observer_refuses_a_residual_that_overflows():
    """A finite state so large that the residual overflows (a velocity of 1e200, squared in
    the momentum's Coriolis terms) was returned as inf and NaN; it is an ArgumentError naming
    the step and the largest input, as for the other functions of the joint state. On good
    inputs after a reset the residual keeps its closed form: at rest under the gravity torque
    the momentum stays zero and beta equals the torque, so r = 0."""
    robot = mindyn.load("puma560")
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    values = base.values(robot.parameters(rotor=True, friction=True))
    observer = control.MomentumObserver(base, values, period=1e-3)
    q, zero = np.linspace(-0.5, 0.5, 6), np.zeros(6)
    observer.reset(q, zero, zero)
    with pytest.raises(ArgumentError, match=r"MomentumObserver.step: .*dq 1e\+200"):
        observer.step(q, np.full(6, 1e200), zero)
    with pytest.raises(ArgumentError, match=r"MomentumObserver.run: .*dq 1e\+200"):
        observer.run(np.tile(q, (3, 1)), np.full((3, 6), 1e200), np.zeros((3, 6)))
    g = robot.gravity_torque(q)
    observer.reset(q, zero, g)
    for _ in range(5):
        np.testing.assert_allclose(observer.step(q, zero, g), 0.0, atol=1e-12)


def test_generated_steps_keep_the_values_and_gains_they_were_written_with():
    """The values, gains and settings a generated step reports describe the code written:
    read-only, so that an edit cannot make them disagree with it."""
    from mindyn import codegen

    robot = mindyn.load("puma560")
    code = codegen.generate_observer(robot, period=1e-3, gains=np.linspace(10.0, 60.0, 6))
    values = code.values.copy()
    np.testing.assert_allclose(
        values, code_base_values(robot), rtol=1e-12, err_msg="the robot's own values"
    )
    for array in (code.values, code.gains):
        with pytest.raises(ValueError, match="read-only"):
            array[0] = 1.0
    np.testing.assert_array_equal(code.gains, np.linspace(10.0, 60.0, 6))
    ctl = codegen.generate_controller(robot, "computed-torque", period=T)
    with pytest.raises(ValueError, match="read-only"):
        ctl.settings["kd"][0] = 0.0


def code_base_values(robot):
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    return base.values(robot.parameters(rotor=True, friction=True))
