"""Stability of the sampled closed loop: the linearised check against the closed form of one
joint (the Jury conditions of the sampled PD loop) and against simulated runs; default gains
that keep every loop of the closed-loop table stable at the controller period; unstable loops
refused or stopped with the figures that explain them (library, ``track``, ``simulate``); the
warning of ``codegen`` on unstable gains; absurd settings and gains files refused."""

from __future__ import annotations

import math
import re

import mindyn
import numpy as np
import pytest
from conftest import ROBOTS_DIR, URDFS
from mindyn import control
from mindyn.cli import main
from mindyn.codegen import generate_controller
from mindyn.control import SumOfSines, simulate
from mindyn.control import simulation as simulation_module

EXAMPLE_UR5 = "examples/urdf/ur5.urdf"


def one_joint_urdf(path, izz: float) -> str:
    """A single revolute joint about the vertical axis (no gravity torque), its link's mass at
    the axis: the inertia about the joint is ``izz`` exactly."""
    path.write_text(
        f"""<robot name="one">
  <link name="base"/>
  <link name="arm"><inertial><origin xyz="0 0 0"/><mass value="2.0"/>
    <inertia ixx="0.1" iyy="0.1" izz="{izz!r}" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="100" velocity="5"/></joint>
</robot>
"""
    )
    return str(path)


def jury_stable(m: float, kp: float, kd: float, T: float) -> bool:
    """One joint ``m dde = u``, ``u = -kp e - kd de`` held over ``T``: characteristic polynomial
    ``z^2 - (2 - a - b/2) z + (1 - a + b/2)`` with ``a = kd T / m``, ``b = kp T^2 / m``; by the
    Jury conditions stable iff ``b > 0``, ``a < 2`` and ``b < 2 a``."""
    a, b = kd * T / m, kp * T * T / m
    return b > 0 and a < 2 and b < 2 * a


# --------------------------------------------------------------------------------------------
# The check against independent references
# --------------------------------------------------------------------------------------------
def test_loop_matrix_is_one_period_of_the_double_integrator(rng):
    """Phi against scipy's matrix exponential of the held-input double integrator."""
    from mindyn.control.stability import loop_matrix
    from scipy.linalg import expm

    n, T = 3, 0.004
    a = rng.standard_normal((n, n))
    M = a @ a.T + n * np.eye(n)
    kp, kd = rng.uniform(1, 50, n), rng.uniform(1, 20, n)
    minv = np.linalg.inv(M)
    # x = (e, de, u), u constant: d/dt (e, de) = (de, M^-1 u)
    A = np.zeros((3 * n, 3 * n))
    A[:n, n : 2 * n] = np.eye(n)
    A[n : 2 * n, 2 * n :] = minv
    step = expm(A * T)[: 2 * n]
    feedback = np.vstack([np.eye(2 * n), np.hstack([-np.diag(kp), -np.diag(kd)])])
    assert np.allclose(loop_matrix(kp, kd, minv, T), step @ feedback, atol=1e-14)


@pytest.mark.parametrize("T", [0.001, 0.004, 0.02])
def test_one_joint_check_is_the_jury_closed_form(tmp_path, T):
    """On a one-joint robot of inertia m, the check's verdict is the closed form's for PD and
    adaptive PD (K_P,eff = K_D Lambda, K_D,eff = K_D + m Lambda) over gains on both sides of the
    limits, its gain/period ratio is K_D T / m, and PD's gain margin is 2 m / (K_D T)."""
    m = 0.37
    robot = mindyn.load(one_joint_urdf(tmp_path / "one.urdf", m))
    rng = np.random.default_rng(7)
    seen, qs = set(), [[0.0]]  # one joint about the vertical: M does not depend on q
    for _ in range(40):
        kd = m / T * rng.uniform(0.05, 3.0)  # a = K_D T / m in (0.05, 3)
        lam = rng.uniform(0.05, 3.0) / T
        lam = lam if rng.uniform() < 0.5 else min(lam, 1.9 / T)
        gains = {"kd": kd, "lambda": lam}
        pd = control.check_gains(robot, gains, kind="pd", period=T, rotor=False, qs=qs)
        assert pd.stable == jury_stable(m, lam * kd, kd, T)
        assert math.isclose(pd.ratio, kd * T / m, rel_tol=1e-9)
        if pd.stable:
            assert math.isclose(pd.gain_margin, 2 * m / (kd * T), rel_tol=1e-3)
        ada = control.check_gains(robot, gains, kind="adaptive-pd", period=T, rotor=False, qs=qs)
        assert ada.stable == jury_stable(m, kd * lam, kd + m * lam, T)
        seen |= {pd.stable, ada.stable}
    assert seen == {True, False}


def test_verdict_agrees_with_a_simulated_run(tmp_path):
    """PD on the one-joint robot just below and just above K_D T / m = 2: the simulation (RK4 of
    the true dynamics, a controller the check does not know) stays bounded below and diverges
    above, as the check says."""
    m, T = 0.37, 0.004
    robot = mindyn.load(one_joint_urdf(tmp_path / "one.urdf", m))
    ref = SumOfSines(robot, period=2.0)
    for a, stable in ((1.8, True), (2.2, False)):
        kd = a * m / T
        gains = {"kd": kd, "lambda": 1.0}
        assert control.check_gains(robot, gains, kind="pd", period=T, rotor=False).stable == stable
        pd = control.make_controller("pd", robot, gains)

        def opaque(*args, pd=pd):
            return pd(*args)

        if stable:
            r = simulate(robot, ref, opaque, duration=2.0)
            assert np.degrees(np.abs(r.error).max()) < 5.0
        else:
            with pytest.raises(control.UnstableLoopError, match="diverged"):
                simulate(robot, ref, opaque, duration=2.0)


def damped_joint_urdf(path, izz: float, damping: float) -> str:
    """``one_joint_urdf`` with viscous friction ``damping`` [N m s/rad] and no Coulomb
    friction."""
    one_joint_urdf(path, izz)
    text = path.read_text().replace(
        "</joint>", f'<dynamics damping="{damping!r}" friction="0"/></joint>'
    )
    path.write_text(text)
    return str(path)


def held_damped_step(m: float, d: float, T: float) -> np.ndarray:
    """``[[e], [de]]`` after ``T`` of ``m dde + d de = u`` from ``(e, de, u)``, u held: the closed
    form (``a = d / m``: ``de(T) = de e^(-aT) + u / d (1 - e^(-aT))``, ``e`` its integral), as
    the 2x3 matrix acting on ``(e, de, u)``."""
    a = d / m
    decay = math.exp(-a * T)
    rise = (1.0 - decay) / a
    return np.array([[1.0, rise, (T - rise) / d], [0.0, decay, (1.0 - decay) / d]])


@pytest.mark.parametrize("model_friction, stable", [(1.3, False), (0.7, True)])
def test_viscous_friction_fed_back_by_the_model_is_checked(tmp_path, model_friction, stable):
    """A light joint with a large viscous friction (``Fv T / m`` = 4 at 4 ms) under computed
    torque whose model has ``model_friction`` times the robot's ``Fv``: the frictionless loop
    (the sampled double integrator alone) is stable either way, but a model feeding back more
    friction than the robot has diverges. The verdict against the closed form of the held
    damped joint (its 2x2 loop's eigenvalues) and a simulated run of a controller the check
    does not know (RK4 of the true dynamics); the controller itself is refused before the run,
    the message naming the model's friction."""
    from mindyn.control.controllers import base_values, controller_check, plant_parameters
    from mindyn.control.stability import loop_matrix

    m, d, T = 1e-3, 1.0, 0.004
    robot = mindyn.load(damped_joint_urdf(tmp_path / "damped.urdf", m, d))
    kp, kd = 100.0, 20.0  # computed torque: K_P,eff = m kp, K_D,eff = m kd
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    truth = plant_parameters(robot, True, friction=True)
    p_hat = base_values(base, truth)
    p_hat[base.names.index("Fv1")] *= model_friction
    gains = {"kd": kd, "kp": kp, "lambda": kp / kd}
    ctl = control.make_controller("computed-torque", robot, gains, p_hat, base=base, period=T)
    # what the check said before it took friction in: the sampled double integrator, stable
    frictionless = loop_matrix([m * kp], [m * kd], [[1.0 / m]], T)
    assert np.max(np.abs(np.linalg.eigvals(frictionless))) < 0.99

    def closed_form(d_hat: float) -> float:
        """Spectral radius of the held damped joint under u = -m kp e - (m kd - d_hat) de."""
        feedback = np.array([[1.0, 0.0], [0.0, 1.0], [-m * kp, -(m * kd - d_hat)]])
        return np.max(np.abs(np.linalg.eigvals(held_damped_step(m, d, T) @ feedback)))

    assert (closed_form(model_friction * d) < 1.0) == stable
    check = controller_check(robot, ctl, truth, T)
    assert check.stable == stable
    assert math.isclose(check.spectral_radius, closed_form(model_friction * d), rel_tol=1e-9)
    assert "viscous friction" in check.text()
    # the model's friction could grow by friction_margin: the closed form's boundary
    if stable:
        grown = model_friction * d * check.friction_margin
        assert closed_form(0.999 * grown) < 1.0 < closed_form(1.001 * grown)
    else:
        assert check.friction_margin == 0.0

    def opaque(*args):
        return ctl(*args)

    ref = SumOfSines(robot, period=2.0)
    run = {"rotor": True, "friction": True, "duration": 1.0, "rate": 1.0 / T}
    if stable:  # bounded: the under-compensated friction lags, by far less than a turn
        r = simulate(robot, ref, opaque, **run)
        assert np.degrees(np.abs(r.error).max()) < 45.0
        simulate(robot, ref, ctl, **run)
    else:
        with pytest.raises(control.UnstableLoopError, match="diverged"):
            simulate(robot, ref, opaque, **run)
        with pytest.raises(control.UnstableLoopError, match="UNSTABLE.*controller's model"):
            simulate(robot, ref, ctl, **run)


# --------------------------------------------------------------------------------------------
# Default gains: the closed-loop table
# --------------------------------------------------------------------------------------------
_GAINS: dict = {}


def _default(name):
    if name not in _GAINS:
        robot = mindyn.load(name)
        _GAINS[name] = (robot, control.default_gains(robot))
    return _GAINS[name]


@pytest.mark.parametrize("rotor", [True, False])
@pytest.mark.parametrize("period", [2.0, 10.0])
@pytest.mark.parametrize("kind", control.CONTROLLERS)
@pytest.mark.parametrize("name", ["puma560", "zcr07s", "planar3"])
def test_closed_loop_table_runs_with_default_settings(name, kind, period, rotor):
    """``simulate(robot, SumOfSines(robot, period), make_controller(kind, robot,
    default_gains(robot)), rotor=rotor)``: no divergence (the first second; the full spans are
    bench/bench_closed_loop.py's), and the controllers with the true model track within a
    degree."""
    robot, gains = _default(name)
    assert gains.note
    ctl = control.make_controller(kind, robot, gains)
    r = simulate(robot, SumOfSines(robot, period=period), ctl, duration=1.0, rotor=rotor)
    err = np.degrees(np.abs(r.error).max())
    assert np.isfinite(err) and err < (1.0 if kind != "pd" else 180.0)
    assert "stable" in r.info["stability"] and "UNSTABLE" not in r.info["stability"]


@pytest.mark.parametrize("kind", ["adaptive-pd", "pd"])
@pytest.mark.parametrize(
    "robot",
    [
        [EXAMPLE_UR5],
        [str(URDFS["ur5"])],
        [str(URDFS["panda"]), "--tip", "panda_link8"],
        ["planar3"],
        [str(ROBOTS_DIR / "kinova_description/robots/kinova.urdf")],
    ],
    ids=["example-ur5", "erd-ur5", "panda", "planar3", "kinova"],
)
def test_track_urdf_arms_with_default_settings(robot, kind, capsys):
    """``mindyn track`` on the URDF arms, with the default estimate error and without: runs,
    states the gains and their margins, and tracks within a few degrees (PD, without a model
    and sagging under gravity: within a quarter turn)."""
    for error in ("0.3", "0") if kind != "pd" else ("",):  # PD has no estimate to err
        args = ["track", *robot, "--controller", kind, "--duration", "1"]
        args += ["--param-error", error] if error else []
        assert main(args) == 0
        out = capsys.readouterr().out
        assert f"gain margin of the sampled {kind} loop" in out, out
        assert "stable (spectral radius" in out
        row = next(line for line in out.splitlines() if line.startswith("max |q - q_d|"))
        errors = [float(v) for v in row.split()[5:]]
        assert max(errors) < (10.0 if kind == "adaptive-pd" else 90.0), row


KINOVA = ROBOTS_DIR / "kinova_description/robots/kinova.urdf"


def test_the_default_estimate_error_keeps_a_physical_robot():
    """On the Kinova arm, base parameters each off by up to 30 % give a model whose mass matrix
    is not positive definite for most seeds (no controller can use it: the default track was
    refused as unstable); the perturbation of the classical parameters keeps every link's
    pseudo-inertia positive semidefinite, each mass within the fraction, and the mass matrix
    positive definite, for every seed; a fraction of 0 changes nothing."""
    from mindyn.control.controllers import base_values, plant_parameters
    from mindyn.control.stability import workspace_samples
    from mindyn.identification.consistent import pseudo_inertia

    robot = mindyn.load(KINOVA)
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    full = plant_parameters(robot, True)
    qs = workspace_samples(robot)
    n = robot.n
    cols = np.repeat(qs, n, axis=0), np.tile(np.eye(n), (len(qs), 1))

    def smallest(p_base):  # the model's mass matrix from its base regressor, as a controller's
        tau = base.regressor(cols[0], np.zeros_like(cols[0]), cols[1]) @ p_base
        grav = base.regressor(qs, np.zeros_like(qs), np.zeros_like(qs)) @ p_base
        m = tau.reshape(len(qs), n, n).transpose(0, 2, 1) - grav[:, :, None]
        return np.linalg.eigvalsh(0.5 * (m + m.transpose(0, 2, 1))).min()

    p_true = base_values(base, full)
    indefinite = sum(
        smallest(control.perturbed_parameters(p_true, 0.3, seed=s)) <= 0 for s in range(10)
    )
    assert indefinite >= 3  # the base-parameter perturbation is not a physical robot
    m0 = full.reshape(n, -1)[:, 9]
    for s in range(10):
        p = control.consistent_perturbation(robot, full, 0.3, seed=s)
        links = p.reshape(n, -1)
        assert np.all(np.abs(links[:, 9] / m0 - 1) <= 0.3 + 1e-12)
        for link in links:
            J = pseudo_inertia(link[:10])
            assert np.linalg.eigvalsh(J).min() >= -1e-12 * np.abs(J).max()
        assert smallest(base_values(base, p)) > 0
        assert np.linalg.eigvalsh(robot.mass_matrix(qs, p)).min() > 0
    same = control.consistent_perturbation(robot, full, 0.0, seed=3)
    assert np.allclose(same, full, rtol=1e-14, atol=1e-15 * np.abs(full).max())


def test_zcr07s_study_gains_kept_where_stable_and_said_where_not():
    """The study's gains at 4 ms on the robot with its rotor inertia (stable: kept); at 30 ms the
    check finds them unstable, the note says so, and a run with them diverges (simulated); the
    derived PD gains at 30 ms cannot hold the wrist's Coulomb friction within the default
    tolerance (refused), and run with a wider one."""
    robot = mindyn.load("zcr07s")
    study = control.controllers.ZCR07S_STUDY_GAINS
    kept = control.default_gains(robot, period=0.004, rotor=True)
    assert kept["kd"] == study["kd"] and kept["lambda"] == study["lambda"]
    assert "the ZCR07S study's" in kept.note and "NOT" not in kept.note
    other = control.default_gains(robot, period=0.03, rotor=True)
    assert "the ZCR07S study's gains are NOT stable at this period" in other.note
    assert other["kd"] != study["kd"]
    ref = SumOfSines(robot, period=10.0)
    pd = control.make_controller("pd", robot, study, period=0.03)
    with pytest.raises(control.UnstableLoopError, match="diverged"):
        simulate(robot, ref, lambda *a: pd(*a), rate=1 / 0.03, duration=3.0, rotor=True)
    # at 30 ms no PD gains both hold 2 degrees against the wrist's Coulomb friction and keep
    # the sampled loop's margin: refused; with a wider tolerance the derived gains run
    with pytest.raises(control.ControllerSettingError, match="joint 6.*a period of"):
        control.make_controller("pd", robot, other, period=0.03)
    wide = control.default_gains(robot, period=0.03, rotor=True, tolerance=math.radians(20.0))
    ok = control.make_controller("pd", robot, wide, period=0.03)
    simulate(robot, ref, lambda *a: ok(*a), rate=1 / 0.03, duration=3.0, rotor=True)


# --------------------------------------------------------------------------------------------
# Unstable loops: errors, no logs
# --------------------------------------------------------------------------------------------
def test_unstable_gain_period_is_a_clear_error():
    """Gains ten times the sampling limit on planar3: refused before the run, with the ratio
    max |eig(T M^-1 K_D)| that the check computes, here against numpy on the robot's mass
    matrix at the middle of the limits (a lower bound of the worst over the workspace)."""
    robot = mindyn.load("planar3")
    T = 0.004
    lim = robot.limits
    M = robot.mass_matrix(0.5 * (lim["lower"] + lim["upper"]))
    kd = 10 * 2.0 / (T * np.max(np.diag(np.linalg.inv(M))))
    gains = {"kd": kd, "lambda": 5.0}
    ctl = control.make_controller("pd", robot, gains)
    with pytest.raises(control.UnstableLoopError) as info:
        simulate(robot, SumOfSines(robot, period=10.0), ctl, duration=1.0)
    msg = str(info.value)
    assert "UNSTABLE" in msg and "a sampled loop needs it below 2" in msg
    ratio = float(msg.split("T M^-1 K_D,eff ")[1].split(",")[0])
    at_mid = np.max(np.abs(np.linalg.eigvals(T * np.linalg.inv(M) * kd)))
    assert ratio >= at_mid * (1 - 1e-3) and ratio > 2


def test_simulate_command_exits_non_zero_and_writes_no_log(tmp_path, capsys):
    """An unstable loop: exit 2, one line, no log; the UR5 example's default PD: a bounded run
    (it once wrote errors of 1460 deg with exit 0)."""
    gains = tmp_path / "g.yaml"
    gains.write_text("kd: 4000\n")
    out = tmp_path / "x.csv"
    args = ["simulate", "planar3", "--controller", "pd", "--gains", str(gains), "-o", str(out)]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "UNSTABLE" in err and len(err.strip().splitlines()) == 1
    assert not out.exists() and not out.with_name("x.truth.json").exists()
    args = ["simulate", EXAMPLE_UR5, "--controller", "pd", "--duration", "2", "-o", str(out)]
    assert main(args) == 0
    text = capsys.readouterr().out
    row = next(line for line in text.splitlines() if "max tracking error" in line)
    assert max(float(v) for v in row.split(":")[1].split()) < 90.0
    assert "gain margin of the sampled pd loop" in text


def test_track_command_refuses_an_unstable_period(tmp_path, capsys):
    """At a 40 ms period: Lambda = 60 (Lambda T = 2.4) and K_D of the 4 ms defaults are refused
    with the figures; the defaults derived for 40 ms run, lowered and saying so."""
    path = tmp_path / "g.yaml"
    path.write_text("lambda: 60\n")
    args = ["track", "planar3", "--period", "0.04", "--duration", "4"]
    assert main([*args, "--gains", str(path)]) == 2
    assert "a sampled loop needs Lambda T < 2 (here 2.4)" in capsys.readouterr().err
    fast = control.default_gains(mindyn.load("planar3"), period=0.004, rotor=True)
    path.write_text(f"kd: {fast['kd']}\nlambda: 5\n")
    assert main([*args, "--gains", str(path), "--controller", "pd"]) == 2
    assert "UNSTABLE" in capsys.readouterr().err
    assert main(args) == 0
    assert "lowered for the period 0.04 s" in capsys.readouterr().out


def test_scipy_integrator_is_bounded(monkeypatch):
    """scipy's RK45 stops with a precise error when one period needs too many evaluations, and
    every run stops at its wall-time bound."""
    robot = mindyn.load("planar3")
    ref = SumOfSines(robot, period=2.0)
    monkeypatch.setattr(simulation_module, "SCIPY_MAX_EVALUATIONS", 3)
    with pytest.raises(ValueError, match="more than 3 evaluations within one controller period"):
        simulate(robot, ref, integrator="scipy", duration=0.1)
    monkeypatch.undo()
    with pytest.raises(control.SimulationTimeoutError, match="wall-time bound of 1e-09 s"):
        simulate(robot, ref, integrator="scipy", duration=0.1, max_seconds=1e-9)
    with pytest.raises(ValueError, match="max_seconds"):
        simulate(robot, ref, duration=0.1, max_seconds=-1)


def test_a_simulation_past_its_wall_time_bound_exits_1(tmp_path, monkeypatch, capsys):
    """A simulation past its wall-time bound is a limit of the machine, as memory is (exit
    status 1, as docs/errors.md says), not an error in the input (2); it writes no log."""
    monkeypatch.setattr(simulation_module, "MAX_SECONDS", 1e-9)  # the command line's bound
    log = tmp_path / "log.csv"
    argv = ["simulate", "planar2", "--mode", "tracking", "--duration", "0.1", "-o", str(log)]
    assert main(argv) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mindyn: error: "), err
    assert "exceeded its wall-time bound of 1e-09 s" in err[0], err
    assert not log.exists()


# --------------------------------------------------------------------------------------------
# codegen, absurd settings, gains files
# --------------------------------------------------------------------------------------------
def test_codegen_warns_when_the_gains_are_not_stable(tmp_path, capsys):
    gains = tmp_path / "g.yaml"
    gains.write_text("kd: 4000\n")
    base = ["codegen", "planar3", "--lang", "c", "--what", "adaptive-pd"]
    assert main([*base, "-o", str(tmp_path / "a"), "--gains", str(gains)]) == 0
    err = capsys.readouterr().err
    assert "warning: the gains baked in are not stable" in err and "UNSTABLE" in err
    assert main([*base, "-o", str(tmp_path / "b")]) == 0
    captured = capsys.readouterr()
    assert "warning" not in captured.err
    assert "gain margin of the sampled adaptive-pd loop" in captured.out


@pytest.mark.parametrize(
    "settings, message",
    [
        ({"lambda": 1e200}, r"gain 'lambda' must be a number in \[0, 1e\+16\]"),
        ({"lambda": 1e3}, "a sampled loop needs Lambda T < 2"),
        ({"period": 1e308}, "period must be a number of seconds in"),
        ({"period": 0.5}, "a sampled loop needs Lambda T < 2"),
        ({"kp": 1e9}, "a sampled loop needs K_P T < 2 K_D"),
        ({"kd": 1e308}, r"gain 'kd' must be a number in \[0, 1e\+16\]"),
        ({"kd": 1e308, "kp": 1.0}, r"gain 'kd' must be a number in \[0, 1e\+16\]"),
        ({"gamma": 1e308}, r"'gamma' .*must be a number|'gamma' and 'nu' must be numbers"),
        ({"nu": float("nan")}, r"nu must be a number in|'gamma' and 'nu' must be numbers"),
    ],
)
def test_absurd_settings_are_refused_by_library_and_codegen(settings, message):
    """The library's controllers and the generated code refuse the same settings (they once
    gave NaN / -inf torques in the library and -1e300 in C)."""
    robot = mindyn.load("planar3")
    gains = dict(control.default_gains(robot, rotor=True))
    period = settings.get("period", 0.004)
    gains.update({k: v for k, v in settings.items() if k != "period"})
    kind = "computed-torque" if "kp" in settings else "adaptive-pd"
    with pytest.raises(control.ControllerSettingError, match=message):
        control.make_controller(kind, robot, gains, period=period)
    with pytest.raises(control.ControllerSettingError, match=message):
        generate_controller(robot, kind, gains=gains, period=period)


def test_codegen_refusal_of_huge_gains_is_one_line(tmp_path, capfd):
    """kd = 1e308 overflowed in the gain products: numpy's RuntimeWarnings came before the
    error (and C clamped the infinite torques at 1e300 where the library gave inf)."""
    gains = tmp_path / "g.yaml"
    gains.write_text("kd: 1.0e+308\nnu: 1.0\n")
    argv = ["codegen", "planar3", "--what", "gravity-compensation", "--lang", "c"]
    assert main([*argv, "--gains", str(gains), "-o", str(tmp_path / "x")]) == 2
    out, err = capfd.readouterr()
    assert err.count("\n") == 1 and "gain 'kd' must be a number in [0, 1e+16]" in err, err


@pytest.mark.parametrize(
    "content, message",
    [
        ("kd: 10\nlambda: 5\nkd: 20\n", r"g.yaml:3:1: key 'kd' appears twice"),
        ("kd: true\n", "'kd' must be a number or a list of numbers, got the boolean true"),
        ("kd: [1, 2, yes]\n", "got the boolean true"),
        ("gamma: abc\n", "'gamma' must be a number or a list of numbers, got 'abc'"),
        ("lambda: []\n", "'lambda' must be a number or a list of numbers, got an empty list"),
    ],
)
def test_gains_file_refuses_duplicates_and_booleans(tmp_path, content, message):
    path = tmp_path / "g.yaml"
    path.write_text(content)
    with pytest.raises(ValueError, match=message):
        control.load_gains(path, mindyn.load("planar3"))


def test_gains_file_numbers_as_yaml_strings(tmp_path):
    """YAML 1.1 reads 1e3 as a string: still the number."""
    path = tmp_path / "g.yaml"
    path.write_text("kd: 1e1\nlambda: [2, 3, 4]\n")
    g = control.load_gains(path, mindyn.load("planar3"))
    assert g["kd"] == 10.0 and g["lambda"] == [2.0, 3.0, 4.0]
    assert "kd, lambda from" in g.note


def test_compiled_step_with_unstable_gains_is_refused_before_the_run():
    """The generated C step (compiled) with K_D forty times the default: the simulation refuses
    it with the figures, as it refuses the library's controller with the same gains; with the
    default gains both run and agree."""
    from mindyn import codegen
    from mindyn.control.controllers import base_values, plant_parameters

    robot = mindyn.load("planar2")
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    p0 = base_values(base, plant_parameters(robot, False, friction=False))  # simulate's robot
    ref = SumOfSines(robot, period=2.0)
    fine = control.default_gains(robot, rotor=False)
    bad = dict(fine, kd=[40.0 * k for k in fine["kd"]])
    for gains, stable in ((fine, True), (bad, False)):
        code = codegen.generate_controller(robot, "adaptive-pd", base=base, gains=gains, params=p0)
        compiled = codegen.CompiledController(code, base)
        library = control.make_controller("adaptive-pd", robot, gains, p0, base=base)
        if stable:
            a = simulate(robot, ref, compiled, duration=0.5)
            b = simulate(robot, ref, library, duration=0.5)
            assert np.allclose(a.q_true, b.q_true, atol=1e-9)
            assert "stable" in a.info["stability"]
            continue
        for ctl in (compiled, library):
            with pytest.raises(control.UnstableLoopError, match="UNSTABLE"):
                simulate(robot, ref, ctl, duration=0.5)


@pytest.mark.parametrize("kind", ["raise", "lower"])
def test_an_unstable_loop_s_advice_is_the_gain_factors_that_make_it_stable(tmp_path, kind):
    """The held damped joint of the test above, unstable in two ways: under computed torque
    whose model feeds back 1.3 times the robot's viscous friction with K_D below the excess
    (more gain makes it stable, less does not), and under PD with gains past the sampling limit
    (less gain makes it stable). The range of factors on the gains the refusal names is stable
    by the closed form, the grid's factors just outside it are not, and the advice goes the way
    that works (it said "lower the gains" whatever the loop)."""
    from mindyn.control.controllers import base_values, controller_check, plant_parameters
    from mindyn.control.stability import _GAIN_GRID

    m, d, T = 1e-3, 1.0, 0.004
    robot = mindyn.load(damped_joint_urdf(tmp_path / "damped.urdf", m, d))
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    truth = plant_parameters(robot, True, friction=True)
    if kind == "raise":  # computed torque: K_P,eff = m kp, K_D,eff = m kd
        p_hat = base_values(base, truth)
        p_hat[base.names.index("Fv1")] *= 1.3
        gains = {"kd": 20.0, "kp": 100.0, "lambda": 5.0}
        ctl = control.make_controller("computed-torque", robot, gains, p_hat, base=base, period=T)
        kp_eff, kd_eff, d_hat = m * 100.0, m * 20.0, 1.3 * d
    else:  # PD: no model, K_P = Lambda K_D
        ctl = control.make_controller("pd", robot, {"kd": 5.0, "lambda": 10.0}, period=T)
        kp_eff, kd_eff, d_hat = 50.0, 5.0, 0.0

    def closed_form(g: float) -> float:
        """Spectral radius under u = -g kp_eff e - (g kd_eff - d_hat) de."""
        feedback = np.array([[1.0, 0.0], [0.0, 1.0], [-g * kp_eff, -(g * kd_eff - d_hat)]])
        return np.max(np.abs(np.linalg.eigvals(held_damped_step(m, d, T) @ feedback)))

    assert closed_form(1.0) > 1.0
    check = controller_check(robot, ctl, truth, T)
    assert not check.stable and check.stable_gains is not None
    low, high = check.stable_gains
    assert (low > 1.0) == (kind == "raise") and (high < 1.0) == (kind == "lower")
    inside = [g for g in _GAIN_GRID if low <= g <= high]
    assert inside and all(closed_form(g) <= 1.0 + 1e-9 for g in inside)
    for g in _GAIN_GRID:  # the grid's neighbours of the range
        if math.isclose(g, low / 10**0.25) or math.isclose(g, high * 10**0.25):
            assert closed_form(g) > 1.0, g
    run = {"rotor": True, "friction": True, "duration": 1.0, "rate": 1.0 / T}
    with pytest.raises(control.UnstableLoopError) as info:
        simulate(robot, SumOfSines(robot, period=2.0), ctl, **run)
    message = str(info.value)
    assert f"{kind} the gains: the loop is stable with K_P and K_D times {low:.3g}" in message
    assert message.count("\n") == 0


def test_a_diverged_loop_s_advice_follows_the_check_made_before_the_run(tmp_path):
    """A run that diverges where the check found the loop stable is told what the check leaves
    out (not to lower the gains, which the check found fine); where the check found it
    unstable, its own next step (here: lower the gains, as K_D T / m above 2 needs)."""
    from mindyn.control.simulation import _diverged

    T, m = 0.004, 0.05
    robot = mindyn.load(one_joint_urdf(tmp_path / "one.urdf", m))
    for a, stable in ((1.8, True), (2.2, False)):
        check = control.check_gains(
            robot, {"kd": a * m / T, "lambda": 1.0}, kind="pd", period=T, rotor=False
        )
        assert check.stable == stable
        text = str(_diverged("the state became non-finite after t = 1 s", check))
        assert text.startswith("the closed loop diverged: the state became non-finite")
        if stable:
            assert "what it leaves out (gravity, Coulomb friction, adaptation)" in text
            assert "lower the gains" not in text
        else:
            assert text.endswith(check.advice()) and "lower the gains" in check.advice()


# --------------------------------------------------------------------------------------------
# notes that concern the controller run
# --------------------------------------------------------------------------------------------
# what each controller uses of the default gains: plain PD K_P = Lambda K_D and no adaptation,
# computed torque K_P = Lambda^2 and K_D = 2 Lambda (not the K_D per inertia), adaptive PD the
# adaptation gains and the estimate box
USES = {
    "pd": ("K_P = Lambda K_D",),
    "computed-torque": ("K_P = Lambda^2, K_D = 2 Lambda",),
    "adaptive-pd": ("adaptation gains 1 normalised by nu", "estimate box"),
}
UNUSED = {
    "pd": ("adaptation", "nu =", "Gamma", "estimate box", "initial estimate"),
    "computed-torque": ("adaptation", "nu =", "Gamma", "estimate box", "x the smallest"),
    "adaptive-pd": ("K_P = Lambda",),
}


@pytest.mark.parametrize("command", ["track", "simulate"])
@pytest.mark.parametrize("kind", ["pd", "computed-torque", "adaptive-pd"])
def test_the_gains_note_speaks_of_the_controller_run_only(kind, command, tmp_path, capsys):
    """`track --controller pd` spoke of the adaptation gains and the margins of the other
    loops: each controller's output states what it uses of the gains and its own loop's gain
    margin, and nothing of what only the others use."""
    argv = [command, "planar2", "--controller", kind, "--duration", "0.2"]
    if command == "simulate":  # computed torque with an estimate: the library's, with gains
        argv += ["-o", str(tmp_path / "log.csv")]
        argv += ["--param-error", "0.3"] if kind == "computed-torque" else []
    assert main(argv) == 0
    out = capsys.readouterr().out
    (line,) = [s for s in out.splitlines() if s.strip().startswith("gains:")]
    for words in USES[kind]:
        assert words in line, (words, line)
    for words in UNUSED[kind]:
        assert words not in out, (words, out)
    assert f"gain margin of the sampled {kind} loop at 0.004 s:" in line, line
    others = [k for k in control.CONTROLLERS if k != kind]
    assert not any(re.search(rf"(?<![\w-]){k}(?![\w-])", line) for k in others), line
    # every figure printed is a number (computed torque printed a row of nan for the torque
    # prediction error of an estimate it does not adapt)
    assert "nan" not in out.lower(), out


@pytest.mark.parametrize(
    ("what", "view"), [("gravity-compensation", "pd"), ("computed-torque",) * 2]
)
def test_codegen_states_the_gains_its_step_uses(what, view, tmp_path, capsys):
    """The generated PD with gravity compensation (checked as the PD loop) and computed torque
    state no adaptation gain; the library's note for every controller still has them all."""
    argv = ["codegen", "planar2", "--lang", "c", "--what", what, "-o", str(tmp_path / "s")]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "adaptation" not in out and "nu =" not in out, out
    assert f"gain margin of the sampled {view} loop" in out, out
    gains = control.default_gains(mindyn.load("planar2"), rotor=True)
    assert "adaptation gains" in gains.note and "gain margins of the sampled loops" in gains.note
    assert gains.note_for(view) in out


def test_computed_torque_from_a_gains_file_states_and_uses_its_own_gains(tmp_path):
    """A gains file's kd is a torque gain of PD and adaptive PD: computed torque (gains in 1/s
    and 1/s^2) does not take it as its K_D; with the file's kp alone it is critically damped,
    K_D = 2 sqrt(K_P); with lambda alone K_P = Lambda^2, K_D = 2 Lambda of the file's Lambda.
    The note says which, and gives no default value for a key the file sets."""
    robot = mindyn.load("planar2")
    path = tmp_path / "g.yaml"
    cases = {
        "kd: [5, 7]\n": ([100.0, 100.0], [20.0, 20.0], "the file's kd, a torque gain"),
        "kp: [25, 64]\n": ([25.0, 64.0], [10.0, 16.0], "K_D = 2 sqrt(K_P)"),
        "lambda: [3, 4]\n": ([9.0, 16.0], [6.0, 8.0], "with the file's Lambda"),
        "kp: [25, 64]\nkd: [3, 4]\n": ([25.0, 64.0], [3.0, 4.0], "the file's kd [1/s]"),
    }
    for text, (kp, kd, words) in cases.items():
        path.write_text(text)
        g = control.load_gains(path, robot)
        ct = control.make_controller("computed-torque", robot, g)
        np.testing.assert_allclose(ct.kp, kp, rtol=1e-12)
        np.testing.assert_allclose(ct.kd, kd, rtol=1e-12)
        note = g.note_for("computed-torque")
        assert words in note, note
        rest = [c for c in g.note.split("; ") if c.startswith("the rest by default: ")]
        for key in (line.split(":")[0] for line in text.splitlines()):
            assert not any(f" {key} " in c for c in rest), (key, rest)
    path.write_text("lambda: [3, 4]\n")
    assert "Lambda = 10" not in control.load_gains(path, robot).note


def test_each_controller_lists_only_the_defaults_it_uses(tmp_path):
    """A gains file that leaves keys to the defaults: the note of computed torque listed the
    default gamma, nu and kd, which it does not use. Each controller's note lists the defaulted
    keys its law reads (computed torque: Lambda, none when kp is given; PD: K_D and Lambda, K_D
    alone when kp replaces Lambda K_D; adaptive PD: all four); the note of every controller
    still lists them all."""
    robot = mindyn.load("planar2")
    path = tmp_path / "g.yaml"
    reads = {  # (kp given?) -> the keys each law reads besides kp
        False: {"pd": {"kd", "lambda"}, "computed-torque": {"lambda"}},
        True: {"pd": {"kd"}, "computed-torque": set()},
    }
    for text in ("kd: [5, 7]\n", "gamma: 2\n", "kp: [25, 64]\n", "kp: [25, 64]\nkd: [3, 4]\n"):
        path.write_text(text)
        g = control.load_gains(path, robot)
        given = {line.split(":")[0] for line in text.splitlines()}
        defaulted = {"kd", "lambda", "gamma", "nu"} - given

        def listed(note: str) -> set:
            clauses = [c for c in note.split("; ") if c.startswith("the rest by default: ")]
            assert len(clauses) <= 1, note
            tail = clauses[0].removeprefix("the rest by default: ") if clauses else ""
            return set(re.findall(r"(?:^|, )(kd|lambda|gamma|nu) ", tail))

        assert listed(g.note) == defaulted, (text, g.note)
        laws = {**reads["kp" in given], "adaptive-pd": {"kd", "lambda", "gamma", "nu"}}
        for kind, keys in laws.items():
            assert listed(g.note_for(kind)) == keys & defaulted, (text, kind, g.note_for(kind))
