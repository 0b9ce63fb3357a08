"""The one simulation stack: its integrator against the earlier step-by-step RK4 and scipy, every
kind of reference through the one reference protocol, a controller with internal state through the
one controller protocol, and ``mindyn simulate`` and ``mindyn track`` as two uses of it."""

from __future__ import annotations

import json

import mindyn
import numpy as np
import pytest
from mindyn import _core, control
from mindyn.cli import main
from mindyn.control import CsvTrajectory, SumOfSines, load_reference, simulate
from mindyn.identification.data import read_csv, write_csv, write_trajectory_csv
from mindyn.identification.excitation import FourierTrajectory, random_trajectory
from scipy.integrate import solve_ivp
from test_cli_workflow import cli


def save_like_excite(traj, csv_path):
    """The CSV (sampled at 250 Hz) and the JSON (coefficients) of ``mindyn excite``."""
    write_trajectory_csv(csv_path, *traj.sample(rate=250.0))
    csv_path.with_suffix(".json").write_text(json.dumps(traj.to_dict()))


# --------------------------------------------------------------------------------------------
# Integrator
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("eps", [0.0, 0.05])
def test_integrator_is_the_rk4_of_the_forward_dynamics_with_coulomb_as_a_torque(eps, rng):
    """The RK4 written out here on Robot.forward_dynamics (Coulomb friction taken out of the
    parameters and applied as Fc sign(dq) or Fc tanh(dq / eps), the simulator's earlier
    Python loop) and the C++ integrator take the same steps: equal to round-off."""
    robot = mindyn.load("zcr07s")
    n = robot.n
    p = robot.parameters(rotor=True, friction=True)
    fc = p.reshape(n, 13)[:, 12].copy()
    p0 = p.reshape(n, 13).copy()
    p0[:, 12] = 0.0
    p0 = p0.reshape(-1)

    def f(q, dq, tau):
        s = np.tanh(dq / eps) if eps > 0 else np.sign(dq)
        return robot.forward_dynamics(q, dq, tau - fc * s, p0)

    plant = _core.Integrator(robot._m, p, eps)
    q, dq, tau = rng.uniform(-1, 1, (3, n))
    tau *= 20
    h, steps = 0.001, 4
    x, v = q.copy(), dq.copy()
    for _ in range(steps):
        k1 = f(x, v, tau)
        v2 = v + 0.5 * h * k1
        k2 = f(x + 0.5 * h * v, v2, tau)
        v3 = v + 0.5 * h * k2
        k3 = f(x + 0.5 * h * v2, v3, tau)
        v4 = v + h * k3
        k4 = f(x + h * v3, v4, tau)
        x, v = x + h / 6 * (v + 2 * v2 + 2 * v3 + v4), v + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    qn, dqn = plant.step(q, dq, tau, h * steps, steps)
    # the same arithmetic in another order: round-off, ~1e-15 of the state
    assert np.allclose(qn, x, rtol=0, atol=1e-12)
    assert np.allclose(dqn, v, rtol=0, atol=1e-10)
    assert np.allclose(plant.acceleration(q, dq, tau), f(q, dq, tau), rtol=1e-12, atol=1e-9)


def test_integrator_against_scipy_and_errors():
    robot = mindyn.load("planar2")
    p = robot.parameters(rotor=True, friction=True)
    plant = _core.Integrator(robot._m, p)
    q, dq, tau = np.array([0.3, -0.4]), np.array([0.5, 1.0]), np.array([2.0, -1.0])

    def f(_, x):
        return np.concatenate([x[2:], robot.forward_dynamics(x[:2], x[2:], tau, p)])

    sol = solve_ivp(f, (0, 0.1), np.concatenate([q, dq]), rtol=1e-12, atol=1e-13)
    qn, dqn = plant.step(q, dq, tau, 0.1, 100)
    # RK4 at h = 1 ms: ~1e-12 of the state; scipy at rtol 1e-12: 1e-9 covers both
    assert np.allclose(qn, sol.y[:2, -1], rtol=0, atol=1e-9)
    assert np.allclose(dqn, sol.y[2:, -1], rtol=0, atol=1e-9)
    # the binding guards the sizes; the settings are checked by simulate, first
    with pytest.raises(mindyn.ArgumentError, match="^tau has 3 entries"):
        plant.step(q, dq, np.zeros(3), 0.1, 1)
    ref = SumOfSines(robot, period=1.0)
    with pytest.raises(mindyn.ArgumentError, match="^substeps is 0; expected an integer >= 1"):
        simulate(robot, ref, substeps=0, duration=0.1)
    with pytest.raises(mindyn.ArgumentError, match="^coulomb_smoothing is -1.0; expected"):
        simulate(robot, ref, coulomb_smoothing=-1.0, duration=0.1)
    with pytest.raises(mindyn.ArgumentError, match="^rate is 0.0; expected a positive number"):
        simulate(robot, ref, rate=0.0, duration=0.1)


# --------------------------------------------------------------------------------------------
# References
# --------------------------------------------------------------------------------------------
def test_every_reference_kind_drives_the_same_simulator(tmp_path):
    """A Fourier series, its JSON and CSV as ``mindyn excite`` writes them, a sum of sines and a
    CSV of positions only: the robot under computed torque with the true parameters follows each
    to within the zero-order hold of the 4 ms period."""
    robot = mindyn.load("planar2")
    traj = random_trajectory(robot, seed=2)
    save_like_excite(traj, tmp_path / "traj.csv")
    t = np.arange(0, traj.period, 0.01)
    q_only = tmp_path / "q.csv"
    write_csv(q_only, t, traj.evaluate(t)[0], None)
    refs = {
        "fourier": traj,
        "excite json": load_reference(tmp_path / "traj.json", 2),
        "excite csv": load_reference(tmp_path / "traj.csv", 2),
        "positions csv": CsvTrajectory(q_only, 2),
        "sum of sines": SumOfSines(robot, period=2.0),
    }
    assert isinstance(refs["excite json"], FourierTrajectory)
    for name, ref in refs.items():
        r = simulate(robot, ref, duration=1.0)
        assert r.t.shape == (251,) and r.qd.shape == (251, 2), name
        assert np.allclose(r.qd, ref.evaluate(r.t)[0], rtol=0, atol=1e-12), name
        # tracking error of computed torque at K_P = 400: far below the reference's motion
        motion = np.ptp(r.qd, axis=0).max()
        assert np.abs(r.error).max() < 1e-2 * motion, name
    with pytest.raises(ValueError, match="2 joints; the robot has 3"):
        load_reference(tmp_path / "traj.json", 3)


# --------------------------------------------------------------------------------------------
# Controller protocol
# --------------------------------------------------------------------------------------------
class IntegralStep:
    """What a compiled step looks like from Python: ``u = step(t, q, dq, q_d, dq_d, ddq_d)``
    with internal state (here a PID's error integral), no other members."""

    def __init__(self, kp, kd, ki, period):
        self.kp, self.kd, self.ki, self.h = kp, kd, ki, period
        self.integral = 0.0
        self.calls = []

    def __call__(self, t, q, dq, q_d, dq_d, ddq_d):
        e = q_d - q
        self.integral = self.integral + self.h * e
        self.calls.append((t, q.copy(), dq.copy()))
        return self.kp * e + self.kd * (dq_d - dq) + self.ki * self.integral


def test_a_stateful_step_is_a_controller():
    robot = mindyn.load("planar2")
    ref = SumOfSines(robot, period=1.0)
    step = IntegralStep(400.0, 40.0, 1000.0, 0.004)
    r = simulate(robot, ref, step, duration=0.4)
    assert len(step.calls) == r.t.size == 101
    # called on the logged (here noise-free) state at each sample, its torque applied and logged
    for i, (t, q, dq) in enumerate(step.calls):
        assert t == r.t[i] and np.array_equal(q, r.q[i]) and np.array_equal(dq, r.dq[i])
    e = r.qd - r.q_true
    integral = 0.004 * np.cumsum(e, axis=0)
    expected = 400 * e + 40 * (r.dqd - r.dq_true) + 1000 * integral
    assert np.allclose(r.tau_true, expected, rtol=1e-12, atol=1e-12)
    assert np.isnan(r.tau_model).all() and r.p_hat is None


def test_controller_period_and_output_are_checked():
    robot = mindyn.load("planar2")
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    ref = SumOfSines(robot, period=1.0)
    gains = control.default_gains(robot)
    ada = control.make_controller("adaptive-pd", robot, gains, base=base, period=0.002)
    with pytest.raises(ValueError, match="made for a period of 0.002 s; the simulation runs at"):
        simulate(robot, ref, ada, duration=0.1)
    r = simulate(robot, ref, ada, rate=500.0, duration=0.1)
    assert r.p_hat.shape == (51, base.n)
    with pytest.raises(ValueError, match="returned shape \\(3,\\)"):
        simulate(robot, ref, lambda *a: np.zeros(3), duration=0.1)


def test_default_controller_is_computed_torque_on_the_true_model():
    """Computed torque with the true parameters and Coulomb friction on the reference velocity:
    on the reference (e = 0) its torque is the inverse dynamics with Fc sign(dq_d)."""
    robot = mindyn.load("zcr07s")
    p = robot.parameters(rotor=True, friction=True)
    ctl = control.default_controller(robot, p)
    traj = random_trajectory(robot, seed=1)
    q, dq, ddq = (x[0] for x in traj.evaluate(0.37))
    tau = ctl(0.37, q, dq, q, dq, ddq)
    assert np.allclose(tau, robot.inverse_dynamics(q, dq, ddq, p), rtol=1e-9, atol=1e-9)
    assert np.all(robot.coulomb > 0) and np.all(dq != 0)
    dq_m = -dq  # a measured velocity of the other sign: the Coulomb term keeps the reference's
    v = ddq - 40 * (dq_m - dq)
    p0 = p.reshape(6, 13).copy()
    p0[:, 12] = 0
    expected = robot.inverse_dynamics(q, dq_m, v, p0.reshape(-1)) + robot.coulomb * np.sign(dq)
    assert np.allclose(ctl(0.37, q, dq_m, q, dq, ddq), expected, rtol=1e-9, atol=1e-9)


# --------------------------------------------------------------------------------------------
# simulate and track on the command line
# --------------------------------------------------------------------------------------------
def test_simulate_and_track_run_the_same_closed_loop(tmp_path):
    """``track`` (the robot with rotor inertia and friction) and ``simulate --rotor --friction``
    with the same controller give the same log over the controller periods they share."""
    a, b = tmp_path / "track.csv", tmp_path / "sim.csv"
    out = cli("track", "planar2", "--controller", "pd", "--duration", 0.4, "-o", a)
    assert f"log: {a} (100 samples" in out
    out = cli("simulate", "planar2", "--controller", "pd", "--rotor", "--friction",
              "--duration", 0.4, "-o", b)  # fmt: skip
    assert f"wrote {b}" in out
    robot = mindyn.load("planar2")
    da, db = read_csv(a, robot, filter="none"), read_csv(b, robot, filter="none")
    assert (da.m, db.m) == (100, 101)
    assert np.array_equal(da.q, db.q[:100]) and np.array_equal(da.tau, db.tau[:100])
    truth = json.loads(b.with_name("sim.truth.json").read_text())
    assert truth["values"] == robot.parameters(rotor=True, friction=True).tolist()


def test_simulate_with_feedback_controllers_and_rotor(tmp_path):
    """``simulate --controller adaptive-pd|pd`` is simulate's own closed loop (no hand-over to
    track): its log, the rotor inertia of --rotor in the truth, the controller named."""
    robot = mindyn.load("planar2")
    for kind in ("adaptive-pd", "pd"):
        log = tmp_path / f"{kind}.csv"
        out = cli("simulate", "planar2", "--controller", kind, "--rotor", "--duration", 0.2,
                  "-o", log)  # fmt: skip
        assert f"controller {kind}" in out and f"wrote {log}" in out
        truth = json.loads(log.with_name(f"{kind}.truth.json").read_text())
        p = np.array(truth["values"]).reshape(2, 13)
        assert np.array_equal(p[:, 10], robot.rotor_inertia) and not p[:, 11:].any()
        assert read_csv(log, robot, filter="none").m == 51


def test_track_reads_the_excite_json(tmp_path, capsys):
    robot = mindyn.load("planar2")
    traj = random_trajectory(robot, seed=3)
    save_like_excite(traj, tmp_path / "traj.csv")
    out = cli("track", "planar2", "--controller", "computed-torque", "--trajectory",
              tmp_path / "traj.json", "--duration", 1.0, "--report", tmp_path / "rep")  # fmt: skip
    assert f"trajectory {tmp_path / 'traj.json'} ({traj.period:g} s)" in out
    log = np.loadtxt(tmp_path / "rep" / "log.csv", delimiter=",", skiprows=1)
    qd = traj.evaluate(log[:, 0])[0]
    assert np.allclose(log[:, 3:5], qd, rtol=0, atol=1e-12)  # the reference logged is the JSON's
    assert main(["track", "planar2", "--trajectory", str(tmp_path / "none.json")]) == 2
    assert "none.json" in capsys.readouterr().err


def test_tracking_errors_of_a_prismatic_joint_are_in_millimetres(tmp_path):
    """The tracking figures were degrees for every joint: a prismatic joint's error in metres
    went through np.degrees (the Stanford arm's d3 shown 57.3 times its metres, labelled deg).
    Each figure is checked against the report's own log (q, qd): degrees on revolute joints,
    millimetres on the prismatic one, and the heading says both."""
    robot = mindyn.load("stanford")
    assert robot.joint_types[2] == "prismatic"
    report = tmp_path / "rep"
    out = cli("track", "stanford", "--controller", "pd", "--duration", 0.4, "--report", report)
    log = np.loadtxt(report / "log.csv", delimiter=",", skiprows=1)
    n = robot.n
    err = np.abs(log[:, 1 : 1 + n] - log[:, 1 + n : 1 + 2 * n]).max(axis=0)
    expected = np.where(np.array(robot.joint_types) == "prismatic", 1e3, 180 / np.pi) * err
    s = json.loads((report / "summary.json").read_text())
    np.testing.assert_allclose(s["max_error_deg"], expected, rtol=1e-12)
    assert s["error_unit"] == "deg | mm"
    row = next(line for line in out.splitlines() if line.startswith("max |q - q_d|"))
    assert row.startswith("max |q - q_d| [deg | mm]"), row
    np.testing.assert_allclose([float(v) for v in row.split("]")[1].split()], expected, atol=1e-4)
    out = cli("simulate", "stanford", "--duration", 0.4, "-o", tmp_path / "s.csv")
    assert "max tracking error per joint [deg | mm]" in out


def test_torque_limit_effort_names_the_joints_without_one(tmp_path, capsys):
    """--torque-limit effort on a robot whose description lacks some effort limits said 'does
    not give effort limits for all joints' (which?) in the library's keywords. The joints
    the URDF leaves without one (here the first and third, written as effort="0", read as
    none) are named, in the command's flag, for simulate and codegen alike."""
    import itertools
    import re
    from pathlib import Path

    example = Path(__file__).resolve().parents[1] / "examples/urdf/ur5.urdf"
    names = mindyn.load(example).joint_names
    count = itertools.count(1)
    text = re.sub(
        r'effort="[^"]+"',
        lambda m: 'effort="0"' if next(count) in (1, 3) else m.group(0),
        example.read_text(),
    )
    urdf = tmp_path / "ur5.urdf"
    urdf.write_text(text)
    limits = mindyn.load(urdf).limits["effort"]
    assert np.isnan(limits[[0, 2]]).all() and np.isfinite(limits[[1, 3, 4, 5]]).all()
    for argv in (
        ["simulate", urdf, "--torque-limit", "effort", "--duration", 0.1, "-o", tmp_path / "s.csv"],
        [
            "codegen",
            urdf,
            "--what",
            "gravity-compensation",
            "--lang",
            "c",
            "--torque-limit",
            "effort",
            "-o",
            tmp_path / "g",
        ],  # fmt: skip
    ):
        assert main([str(a) for a in argv]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith("mindyn: error: --torque-limit"), err
        assert f"joint(s) 1 ('{names[0]}'), 3 ('{names[2]}');" in err, err


def test_torque_headings_say_newtons_for_a_prismatic_joint():
    """The adaptive run's torque-prediction row was headed [Nm] whatever the joints: the
    Stanford arm's prismatic joint 3 carries a force. The heading gives both units there, and
    N m alone on an arm of revolute joints."""
    out = cli("track", "stanford", "--controller", "adaptive-pd", "--duration", 0.4)
    row = next(line for line in out.splitlines() if line.startswith("|Y (p_hat - p)|"))
    assert row.startswith("|Y (p_hat - p)| RMS, first [N m | N]"), row
    out = cli("track", "planar2", "--controller", "adaptive-pd", "--duration", 0.4)
    row = next(line for line in out.splitlines() if line.startswith("|Y (p_hat - p)|"))
    assert row.startswith("|Y (p_hat - p)| RMS, first [N m] "), row


def test_torque_limit_takes_the_same_words_in_simulate_track_and_codegen(tmp_path, capsys):
    """codegen --torque-limit took effort or a number and refused none; simulate and track took
    effort or none and refused a number. All three take effort, none and NM now: the
    simulated log's torques stay within +-NM and reach it, the generated step saturates at it,
    and none is no limit."""
    log = tmp_path / "s.csv"
    argv = ["simulate", "planar2", "--torque-limit", "2", "--duration", "0.5", "-o", str(log)]
    assert main(argv) == 0
    capsys.readouterr()
    data = np.genfromtxt(log, delimiter=",", names=True)
    tau = np.column_stack([data["tau1"], data["tau2"]])
    assert np.abs(tau).max() == pytest.approx(2.0, abs=1e-12)  # saturated, never beyond
    track = ["track", "planar2", "--cycle", "0.2", "--duration", "0.2", "--torque-limit", "2"]
    assert main(track) == 0
    assert "torque limits: +-2 N m on every joint, saturated" in capsys.readouterr().out
    code = ["codegen", "planar2", "--what", "computed-torque", "--lang", "c"]
    assert main([*code, "--torque-limit", "2.5", "-o", str(tmp_path / "a")]) == 0
    assert "c->tau_max[1] = 2.5;" in (tmp_path / "a.c").read_text()
    assert main([*code, "--torque-limit", "none", "-o", str(tmp_path / "b")]) == 0
    assert "c->tau_max[1] = 1.0e+300;" in (tmp_path / "b.c").read_text()
    capsys.readouterr()
    for command in (argv[:2] + ["-o", str(log)], track[:2], code + ["-o", str(tmp_path / "c")]):
        assert main([*command, "--torque-limit", "-1"]) == 2
        err = capsys.readouterr().err
        assert "--torque-limit: must be positive and finite, got -1" in err, err
