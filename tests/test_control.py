"""Controllers and the closed-loop simulator: the adaptive PD sign convention (feedforward against
Pinocchio's rnea, feedback and update terms by their formulas), tracking that improves while the
estimate adapts, against plain PD, the closed loop against energy conservation and scipy's
integrator, reference trajectories, gains files and the ``track`` command."""

from __future__ import annotations

import json
import re

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import assert_close, pinocchio_model
from mindyn import control
from mindyn.cli import main
from mindyn.control import CsvTrajectory, SensorNoise, SumOfSines, simulate, summary


def _at(ref, t):
    """The reference at one time: three (n,) arrays."""
    return tuple(x[0] for x in ref.evaluate(t))


def _state_on(ref, t):
    qd, dqd, ddqd = _at(ref, t)
    return qd.copy(), dqd.copy(), (qd, dqd, ddqd)


def _run(robot, ctl, ref, duration, **kw):
    """The tracking run of ``mindyn track``: the robot with rotor inertia and friction, the
    controller's periods over [0, duration)."""
    kw = {"rotor": True, "friction": True, **kw}
    return simulate(robot, ref, ctl, duration=duration, endpoint=False, **kw)


# --------------------------------------------------------------------------------------------
# Sign convention
# --------------------------------------------------------------------------------------------
def test_adaptive_pd_on_the_reference_with_true_parameters_is_inverse_dynamics():
    """e = 0, p_hat = p: tau = A ddq_d + C dq_d + c + Fv dq + Fc sign(dq) (Pinocchio rnea)."""
    robot = mindyn.load("zcr07s")
    base = mindyn.base_parameters(robot, friction=True)
    p = base.values(robot.parameters(friction=True))
    ctl = control.AdaptivePD(base, kd=50.0, lam=5.0, gamma=1.0, p0=p)
    ref = SumOfSines(robot, period=3.0)
    model = pinocchio_model(robot)
    data = model.createData()
    for t in (0.3, 1.1, 2.4):
        q, dq, r = _state_on(ref, t)
        tau = ctl(t, q, dq, *r)
        expected = pin.rnea(model, data, *r) + robot.viscous * dq + robot.coulomb * np.sign(dq)
        assert_close(tau, expected, 1e-10, "adaptive PD feedforward vs pin rnea")
        assert np.allclose(ctl.p_hat, p)  # s = 0: no adaptation


def test_adaptive_pd_feedback_and_update_signs(rng):
    """p_hat = 0 leaves tau = -K_D s with s = de + Lambda e, e = q - q_d; the estimate moves by
    -T Gamma Y^T s with Y = Y(q, dq, dq_d - Lambda e, ddq_d - Lambda de)."""
    robot = mindyn.load("puma560")
    base = mindyn.base_parameters(robot)
    kd = rng.uniform(1, 5, 6)
    lam = rng.uniform(2, 8, 6)
    gamma = rng.uniform(0.5, 2.0, base.n)
    ctl = control.AdaptivePD(base, kd, lam, gamma, np.zeros(base.n), period=0.01)
    qd, dqd, ddqd = rng.uniform(-1, 1, (3, 6))
    e = np.zeros(6)
    e[2] = 1e-3  # joint 3 ahead of the reference
    tau = ctl(0.0, qd + e, dqd, qd, dqd, ddqd)
    assert tau[2] == pytest.approx(-kd[2] * lam[2] * 1e-3, rel=1e-12)
    assert np.all(tau[[0, 1, 3, 4, 5]] == 0)
    s = lam * e
    Y = mindyn.slotine_li_regressor(base, qd + e, dqd, dqd - lam * e, ddqd)
    assert_close(ctl.p_hat, -0.01 * gamma * (Y.T @ s), 1e-12, "adaptation step -T Gamma Y^T s")
    normalised = control.AdaptivePD(base, kd, lam, gamma, np.zeros(base.n), nu=0.05, period=0.01)
    normalised(0.0, qd + e, dqd, qd, dqd, ddqd)
    step = -0.01 * gamma * (Y.T @ s) / (1 + 0.05 * np.sum(Y**2))
    assert_close(normalised.p_hat, step, 1e-12, "normalised step -T Gamma Y^T s / (1 + nu |Y|^2)")
    with pytest.raises(ValueError, match="nu must be"):
        control.AdaptivePD(base, kd, lam, gamma, np.zeros(base.n), nu=-1.0)


# --------------------------------------------------------------------------------------------
# Closed loop
# --------------------------------------------------------------------------------------------
def _per_cycle_rms(result, cycle):
    s = summary(result, cycle=cycle)
    return np.array([np.sqrt(np.mean(np.square(r))) for r in s["rms_error_deg_per_cycle"]]), s


def test_adaptive_pd_learns_the_model_from_zero():
    """Two-link vertical arm, estimate starting at zero: the error shrinks cycle after cycle, the
    torque prediction error too, and plain PD with the same gains stays far worse."""
    robot = mindyn.load("planar2")
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    gains = control.default_gains(robot)
    ref = SumOfSines(robot, period=2.0)
    ada = control.make_controller("adaptive-pd", robot, gains, np.zeros(base.n), base=base)
    r = _run(robot, ada, ref, 10.0)
    rms, s = _per_cycle_rms(r, 2.0)
    assert np.all(np.diff(rms) < 0), rms
    assert rms[-1] < 0.2 * rms[0]
    tp = [np.sqrt(np.mean(np.square(x))) for x in s["torque_prediction_rms_per_cycle"]]
    assert tp[-1] < 0.2 * tp[0]
    pd = control.make_controller("pd", robot, gains)
    rp = _run(robot, pd, ref, 10.0)
    assert np.all(rp.max_error_deg(t_from=8.0) > 5 * r.max_error_deg(t_from=8.0))


def test_zcr07s_setting_tracks_better_than_pd_and_improves():
    """ZCR07S with the study's gains (adaptation gains 1, 4 ms), estimate off by up to +-30 %:
    tracking error and torque prediction error decrease from the first to the last cycle;
    PD and the same controller with the estimate frozen are worse."""
    robot = mindyn.load("zcr07s")
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    p = base.values(robot.parameters(rotor=True, friction=True))
    p0 = control.perturbed_parameters(p, 0.3, seed=0)
    gains = control.default_gains(robot, rotor=True)
    assert gains["kd"] == [400, 350, 130, 22, 9, 2] and gains["gamma"] == 1
    ref = SumOfSines(robot, period=2.5)
    ada = control.make_controller("adaptive-pd", robot, gains, p0, base=base)
    r = _run(robot, ada, ref, 7.5)
    rms, s = _per_cycle_rms(r, 2.5)
    assert rms[-1] < rms[0]
    tp = [np.sqrt(np.mean(np.square(x))) for x in s["torque_prediction_rms_per_cycle"]]
    assert np.all(np.diff(tp) < 0), tp
    assert s["parameter_error_norm"][-1] < s["parameter_error_norm"][0]
    frozen = control.make_controller("adaptive-pd", robot, dict(gains, gamma=0.0), p0, base=base)
    rf = _run(robot, frozen, ref, 7.5)
    assert _per_cycle_rms(rf, 2.5)[0][-1] > rms[-1]
    pd = control.make_controller("pd", robot, gains)
    rp = _run(robot, pd, ref, 7.5)
    assert np.all(rp.max_error_deg() > r.max_error_deg())


def test_normalised_adaptation_keeps_large_gains_stable_at_4ms():
    """At the study's 4 ms period the plain law with adaptation gains 5 (and no box on the
    estimate) diverges; normalised by 1 + nu |Y|^2 the same gains track within the plain law's
    accuracy at gains 1 and improve the estimate, cycle by cycle."""
    robot = mindyn.load("zcr07s")
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    p = base.values(robot.parameters(rotor=True, friction=True))
    p0 = control.perturbed_parameters(p, 0.3, seed=0)
    gains = control.default_gains(robot, rotor=True)
    ref = SumOfSines(robot, period=2.5)
    plain = control.make_controller(
        "adaptive-pd", robot, dict(gains, gamma=5.0), p0, base=base, box=False
    )
    with pytest.raises(ValueError, match="diverged"):
        _run(robot, plain, ref, 7.5)
    slow = control.make_controller("adaptive-pd", robot, gains, p0, base=base)
    r1 = _run(robot, slow, ref, 7.5)
    fast = control.make_controller(
        "adaptive-pd", robot, dict(gains, gamma=5.0, nu=0.01), p0, base=base
    )
    r5 = _run(robot, fast, ref, 7.5)
    assert np.all(r5.max_error_deg(t_from=5.0) < 1.5 * r1.max_error_deg(t_from=5.0))
    rms, s = _per_cycle_rms(r5, 2.5)
    assert rms[-1] < rms[0]
    assert s["parameter_error_norm"][-1] < s["parameter_error_norm"][0]


def test_computed_torque_with_exact_parameters_tracks_closely():
    robot = mindyn.load("puma560_3")
    gains = {"kd": [0, 0, 0], "lambda": [20.0] * 3}
    ct = control.make_controller("computed-torque", robot, gains)
    ref = SumOfSines(robot, period=2.0)
    r = _run(robot, ct, ref, 2.0, substeps=8)
    # only the zero-order hold of the 4 ms period separates it from exact tracking
    assert r.max_error_deg().max() < 0.02


# --------------------------------------------------------------------------------------------
# Simulator
# --------------------------------------------------------------------------------------------
def test_free_motion_conserves_energy():
    """No torque, no friction: the RK4 integrator keeps the total energy (Robot.energy)."""
    robot = mindyn.load("puma560")

    class Zero:
        name = "zero"

        def __call__(self, t, q, dq, q_d, dq_d, ddq_d):
            return np.zeros(6)

    class Start:  # the start state at every time: the robot starts there
        n, duration = 6, 1.0

        def evaluate(self, t):
            m = np.size(t)
            q0, dq0 = [0.2, -0.5, 0.3, 0.1, 0.4, -0.2], [1, -1, 0.5, 2, -1, 1.0]
            return np.tile(q0, (m, 1)), np.tile(dq0, (m, 1)), np.zeros((m, 6))

    r = simulate(robot, Start(), Zero(), params=robot.params, substeps=4)
    H = robot.energy(r.q_true, r.dq_true)
    assert np.abs(H - H[0]).max() < 1e-6 * max(1.0, abs(H[0]))
    assert np.abs(r.q_true[-1] - r.q_true[0]).max() > 0.1  # it did move


def test_rk4_and_scipy_integrators_agree():
    robot = mindyn.load("planar2")
    gains = control.default_gains(robot)
    ref = SumOfSines(robot, period=1.0)
    runs = []
    for integrator in ("rk4", "scipy"):
        ctl = control.make_controller("pd", robot, gains)
        runs.append(_run(robot, ctl, ref, 0.4, integrator=integrator, substeps=8))
    assert np.abs(runs[0].q_true - runs[1].q_true).max() < 1e-7


def test_noise_and_torque_limits():
    robot = mindyn.load("zcr07s")
    gains = control.default_gains(robot)
    ref = SumOfSines(robot, period=1.0, fraction=1.0)
    ctl = control.make_controller("pd", robot, dict(gains, kd=[4000] * 6))
    noisy = {"torque_limit": "effort", "noise": SensorNoise(position=1e-4, velocity=1e-3)}
    r = _run(robot, ctl, ref, 0.5, seed=3, **noisy)
    effort = robot.limits["effort"]
    assert np.all(np.abs(r.tau_true) <= effort + 1e-12)
    assert r.saturated.any()
    assert np.allclose(
        np.abs(r.tau_true[r.saturated]), np.broadcast_to(effort, r.tau.shape)[r.saturated]
    )
    # same seed, same run; the noise changes the torques
    r2 = _run(robot, ctl, ref, 0.5, seed=3, **noisy)
    assert np.array_equal(r.tau_true, r2.tau_true)
    r3 = _run(robot, ctl, ref, 0.5, torque_limit="effort")
    assert not np.allclose(r.tau_true, r3.tau_true)


def test_simulate_input_errors():
    robot = mindyn.load("planar2")
    ctl = control.PD(2, 1.0, 1.0)
    ref = SumOfSines(robot)
    with pytest.raises(ValueError, match="shorter than one period"):
        _run(robot, ctl, ref, 0.001)
    with pytest.raises(ValueError, match="integrator"):
        _run(robot, ctl, ref, 0.1, integrator="euler")
    with pytest.raises(ValueError, match="torque_limit"):
        _run(robot, ctl, ref, 0.1, torque_limit="max")
    with pytest.raises(ValueError, match="gain 'kd'"):
        control.PD(2, 1.0, [1.0, -1.0])


# --------------------------------------------------------------------------------------------
# References and gains
# --------------------------------------------------------------------------------------------
def test_sum_of_sines_respects_limits_and_differentiates(rng):
    robot = mindyn.load("zcr07s")
    ref = SumOfSines(robot, period=4.0, fraction=0.9)
    lim = robot.limits
    ts = np.linspace(0, 4, 2001)
    Q, DQ, _ = ref.evaluate(ts)
    assert np.all(Q >= lim["lower"]) and np.all(Q <= lim["upper"])
    assert np.all(np.abs(DQ) <= lim["velocity"])
    h = 1e-6
    for t in rng.uniform(0, 4, 5):
        q, dq, ddq = _at(ref, t)
        plus, minus = _at(ref, t + h), _at(ref, t - h)
        assert_close((plus[0] - minus[0]) / (2 * h), dq, 1e-7, "reference dq by FD")
        assert_close((plus[1] - minus[1]) / (2 * h), ddq, 1e-7, "reference ddq by FD")


def test_csv_trajectory(tmp_path):
    t = np.linspace(0, 2, 201)
    q = np.column_stack([np.sin(2 * t), 0.5 * np.cos(t)])
    path = tmp_path / "traj.csv"
    np.savetxt(path, np.column_stack([t, q]), delimiter=",", header="t,q1,q2", comments="")
    ref = CsvTrajectory(path, 2)
    for s in (0.3047, 1.1731):
        qd, dqd, ddqd = _at(ref, s)
        assert_close(qd, [np.sin(2 * s), 0.5 * np.cos(s)], 1e-7, "CSV spline q")
        assert_close(dqd, [2 * np.cos(2 * s), -0.5 * np.sin(s)], 1e-4, "CSV spline dq")
        assert_close(ddqd, [-4 * np.sin(2 * s), -0.5 * np.cos(s)], 1e-2, "CSV spline ddq")
    qd, dqd, _ = _at(ref, 5.0)  # after the end: hold
    assert_close(qd, q[-1], 0.0, "CSV hold")
    assert not dqd.any()
    bad = tmp_path / "bad.csv"
    bad.write_text("0,1,2\n1,2,3\n2,3\n3,4,5\n")
    with pytest.raises(ValueError, match="different numbers of columns"):
        CsvTrajectory(bad, 2)
    bad.write_text("0,1\n1,2\n2,3\n3,4\n")
    with pytest.raises(ValueError, match="2 columns; expected t and q1..q2"):
        CsvTrajectory(bad, 2)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        CsvTrajectory(tmp_path / "none.csv", 2)


def test_csv_trajectory_columns_are_taken_by_their_header_names(tmp_path):
    """A log given as a trajectory (t, q, dq, tau) had its torques read as the reference's
    accelerations, by count. With a header the columns are taken by name, in any order, the
    others left out; a motion column with a unit or a group given in part is refused."""
    t = np.linspace(0, 2, 201)
    q = np.column_stack([np.sin(2 * t), 0.5 * np.cos(t)])
    dq = np.column_stack([2 * np.cos(2 * t), -0.5 * np.sin(t)])
    tau = np.column_stack([40 + t, -30 - t])  # far from any acceleration of this motion
    log = tmp_path / "log.csv"
    np.savetxt(log, np.column_stack([t, q, dq, tau]), delimiter=",", comments="",
               header="t,q1,q2,dq1,dq2,tau1,tau2")  # fmt: skip
    shuffled = tmp_path / "shuffled.csv"
    np.savetxt(shuffled, np.column_stack([t, tau[:, 0], dq[:, 1], q[:, 1], dq[:, 0], q[:, 0]]),
               delimiter=",", comments="", header="t,tau1,dq2,q2,dq1,q1")  # fmt: skip
    for path in (log, shuffled):
        ref = CsvTrajectory(path, 2)
        for s in (0.3047, 1.1731):
            qd, dqd, ddqd = _at(ref, s)
            assert_close(qd, [np.sin(2 * s), 0.5 * np.cos(s)], 1e-7, "q by name")
            assert_close(ddqd, [-4 * np.sin(2 * s), -0.5 * np.cos(s)], 1e-2, "ddq, not tau")
    cases = {
        "t,q1[deg],q2": "column 'q1\\[deg\\]' gives a unit",
        "t,q1,tau2": "has no column q2",
        "t,q1,q2,dq1": "has no column dq2",
        "t,q1,q2,q2": "column 'q2' is given twice",
        "t,q1,q2,q3": "column.s. q3 beyond the robot's 2 joints",
    }
    for header, message in cases.items():
        bad = tmp_path / "bad.csv"
        k = header.count(",")
        np.savetxt(bad, np.column_stack([t] + [q[:, 0]] * k), delimiter=",", header=header,
                   comments="")  # fmt: skip
        with pytest.raises(mindyn.Error, match=message):
            CsvTrajectory(bad, 2)


def test_gains_file(tmp_path):
    robot = mindyn.load("zcr07s")
    f = tmp_path / "g.yaml"
    f.write_text("kd: 100\nlambda: [1, 2, 3, 4, 5, 6]\n")
    g = control.load_gains(f, robot)
    assert g["kd"] == 100 and g["lambda"] == [1, 2, 3, 4, 5, 6] and g["gamma"] == 1
    f.write_text("kp: 1\nki: 2\n")
    with pytest.raises(ValueError, match="unknown key.*ki"):
        control.load_gains(f, robot)
    f.write_text("kd: [1, 2\n")
    with pytest.raises(ValueError, match="not valid YAML"):
        control.load_gains(f, robot)
    f.write_text("gamma: 5\nnu: 0.01\n")
    g = control.load_gains(f, robot)
    assert control.make_controller("adaptive-pd", robot, g).nu == 0.01
    f.write_text("nu: [0.1, 0.2]\n")
    with pytest.raises(ValueError, match="'nu' must be one number >= 0"):
        control.load_gains(f, robot)


@pytest.mark.parametrize(
    ("text", "said"),
    [
        ("lambda: [1, 2, 3]\n", "gain 'lambda' must be a scalar or 2 values, got shape (3,)"),
        ("kp: [1, -2]\n", "gain 'kp' must be a number in [0, 1e+16], got [1.0, -2.0]"),
    ],
)
def test_gains_file_wrong_joint_gains_are_refused_naming_the_file(tmp_path, text, said):
    """A per-joint gain of the wrong length or sign was taken by load_gains and refused later,
    without the file's name (codegen: 'lambda has shape (3,); expected (2,)'). load_gains
    refuses it naming the file; codegen says the same."""
    f = tmp_path / "g.yaml"
    f.write_text(text)
    with pytest.raises(ValueError) as e:
        control.load_gains(f, mindyn.load("planar2"))
    assert str(e.value) == f"{f}: {said}"
    rc = main(["codegen", "planar2", "--what", "adaptive-pd", "--gains", str(f), "--lang", "c"])
    assert rc == 2


def test_gains_file_kp_unused_by_adaptive_pd_is_said(tmp_path):
    """Slotine-Li adaptive PD's position gain is Lambda K_D: a file's kp changed nothing there
    and its note did not say so. Now its note does; PD's takes the kp (note and controller)."""
    robot = mindyn.load("planar2")
    f = tmp_path / "g.yaml"
    f.write_text("kp: 100\n")
    g = control.load_gains(f, robot)
    note = g.note_for("adaptive-pd")
    assert "adaptive PD: the file's kp is not used (its position gain is Lambda K_D)" in note
    np.testing.assert_allclose(
        control.controllers._gain_arrays("adaptive-pd", g, 2)[0], np.multiply(g["lambda"], g["kd"])
    )
    assert "kp is not used" not in g.note_for("pd") and "K_P = the file's kp" in g.note_for("pd")
    np.testing.assert_allclose(control.make_controller("pd", robot, g).kp, [100, 100])


def test_gains_file_over_defaults_without_nu(tmp_path):
    """The ZCR07S study's default gains (with rotor inertia, stable at 4 ms) have no adaptation
    normalisation: a gains file leaving nu out takes none, and the note says so (it raised a
    KeyError)."""
    robot = mindyn.load("zcr07s")
    assert "nu" not in control.default_gains(robot, rotor=True)
    f = tmp_path / "g.yaml"
    f.write_text("kd: [400, 350, 130, 22, 9, 2]\ngamma: 1\n")
    g = control.load_gains(f, robot, rotor=True)
    assert "nu 0 (no normalisation)" in g.note
    assert control.make_controller("adaptive-pd", robot, g).nu == 0


# --------------------------------------------------------------------------------------------
# Command line
# --------------------------------------------------------------------------------------------
def test_track_command(tmp_path, capsys):
    out = tmp_path / "rep"
    code = main(
        [
            "track",
            "planar2",
            "--controller",
            "adaptive-pd",
            "--duration",
            "1",
            "--cycle",
            "0.5",
            "--report",
            str(out),
        ]
    )
    text = capsys.readouterr().out
    assert code == 0
    assert "max |q - q_d| [deg]" in text and "RMS error, cycle 2" in text
    s = json.loads((out / "summary.json").read_text())
    assert s["controller"] == "adaptive-pd" and len(s["rms_error_deg_per_cycle"]) == 2
    for name in ("tracking_error.png", "torque.png", "parameters.png", "log.csv"):
        assert (out / name).stat().st_size > 0
    # the files the report's docstring names are the files an adaptive run writes (it named a
    # torque_prediction.png that was never written)
    named = set(re.findall(r"``(\w+\.\w+)``", control.write_tracking_report.__doc__))
    assert named == {f.name for f in out.iterdir()}
    log = np.loadtxt(out / "log.csv", delimiter=",", skiprows=1)
    assert log.shape == (250, 1 + 3 * 2)


def test_track_report_of_computed_torque(tmp_path, capsys):
    """Computed torque keeps a fixed estimate (p_hat) and has no true-model torque: its report
    ended in 'unexpected AssertionError' from the parameter plot, which is for adaptive runs.
    The report is written without that plot; the summary gives the fixed estimate's error."""
    out = tmp_path / "rep"
    argv = ["track", "planar2", "--controller", "computed-torque", "--duration", "1"]
    assert main([*argv, "--cycle", "0.5", "--report", str(out)]) == 0, capsys.readouterr().err
    for name in ("tracking_error.png", "torque.png", "log.csv"):
        assert (out / name).stat().st_size > 0
    assert not (out / "parameters.png").exists()
    s = json.loads((out / "summary.json").read_text())
    assert s["controller"] == "computed-torque" and len(s["parameter_error_norm"]) == 3
    assert "torque_prediction_rms_per_cycle" not in s


def test_track_command_errors(tmp_path, capsys):
    assert main(["track", "planar2", "--gains", str(tmp_path / "none.yaml")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mindyn: error: gains file") and err.count("\n") == 1
    f = tmp_path / "g.yaml"
    f.write_text("kd: [1, 2, 3]\n")
    assert main(["track", "planar2", "--gains", str(f), "--duration", "0.1"]) == 2
    assert "gain 'kd' must be a scalar or 2 values" in capsys.readouterr().err
    for opt, value in (("--duration", "0"), ("--cycle", "-1"), ("--duration", "nan")):
        assert main(["track", "planar2", opt, value]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"mindyn: error: argument {opt}: expected a finite number in (0,")
        assert err.count("\n") == 1


@pytest.mark.parametrize(
    "content, message",
    [
        (b"kd: 5\n\xff\xfe\n", r"line 2: not UTF-8 text \(byte 0xff at offset 6\)"),
        (b"- 1\n- 2\n", "expected a mapping"),
    ],
)
def test_gains_file_not_utf8_or_not_a_mapping(tmp_path, content, message):
    """A gains file that is not UTF-8 text, or not a mapping: one error naming the file."""
    f = tmp_path / "gains.yaml"
    f.write_bytes(content)
    with pytest.raises(ValueError, match=message) as err:
        control.load_gains(f, mindyn.load("planar2"))
    assert str(f) in str(err.value)


@pytest.mark.parametrize(
    "content, message",
    [
        (b'{"freq": 0.1,\xff}', r"line 1: not UTF-8 text \(byte 0xff at offset 13\)"),
        (b"[1, 2, 3]", "expected a JSON object"),
    ],
)
def test_trajectory_json_not_utf8_or_not_an_object(tmp_path, content, message):
    """An excitation JSON that is not UTF-8 text, or not an object: one error naming the file
    (it used to be a codec error without the file, or an AttributeError)."""
    from mindyn.identification.excitation import FourierTrajectory

    f = tmp_path / "traj.json"
    f.write_bytes(content)
    with pytest.raises(ValueError, match=message) as err:
        FourierTrajectory.load(f)
    assert str(f) in str(err.value)
