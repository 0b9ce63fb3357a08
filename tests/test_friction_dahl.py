"""The Dahl friction model (a presliding state per joint that follows the positions): its state
against an independent integration of its differential equation, identification from a log
this module generates with Dahl friction of known sigma and Fc (recovered; the static models
worse where the joints rest, where the true friction is the torque held since they stopped),
prediction from the JSON on another log, and the precise refusals of generated code and
descriptions."""

from __future__ import annotations

import json

import mindyn
import numpy as np
import pytest
from conftest import cli
from mindyn.identification import JointData, identify, select_friction_model, write_csv
from mindyn.identification.friction import dahl_state
from random_arm import random_arm_yaml

SIGMA = np.array([60.0, 25.0, 120.0])  # 1 / presliding displacement [1/rad]
FV, FC = np.array([0.8, 0.5, 0.3]), np.array([1.5, 1.0, 0.6])


@pytest.fixture(scope="module")
def arm(tmp_path_factory):
    return mindyn.load(random_arm_yaml(tmp_path_factory.mktemp("arm") / "arm.yaml", n=3, seed=4))


def motion(t, seed):
    """Analytic q, dq, ddq (m, 3): multi-sines of a phase that stops for part of every second
    (the joints rest there, and reverse between rests)."""
    rng = np.random.default_rng(seed)
    f = 1.0  # gate frequency [Hz]: phase rate om * max(0, sin(2 pi f t))^2
    g = np.maximum(0.0, np.sin(2 * np.pi * f * t))
    gate, dgate = g**2, 2 * g * 2 * np.pi * f * np.cos(2 * np.pi * f * t) * (g > 0)
    om = 2 * np.pi * 0.6
    # phase = om * int gate dt, in closed form over the positive half-periods
    c = np.floor(2 * f * t)  # half-periods passed
    tt = t - c / (2 * f)
    on = (c % 2) == 0
    half = 1 / (4 * f)  # int of sin^2 over one positive half-period
    done = np.floor(c / 2 + 0.5) * half  # whole positive half-periods before this one
    now = np.where(on, tt / 2 - np.sin(4 * np.pi * f * tt) / (8 * np.pi * f), 0.0)
    ph, dph, ddph = om * (done + now), om * gate, om * dgate
    q, dq, ddq = (np.zeros((t.size, 3)) for _ in range(3))
    for k in range(3):
        for h in (1, 2):
            a, p0 = rng.uniform(0.2, 0.4) / h, rng.uniform(0, 2 * np.pi)
            x = h * ph + p0
            q[:, k] += a * np.sin(x)
            dq[:, k] += a * h * np.cos(x) * dph
            ddq[:, k] += a * h * (np.cos(x) * ddph - h * np.sin(x) * dph**2)
    return q, dq, ddq


def dahl_integrated(t, dq_of, sigma, sub=10):
    """The Dahl state along the motion by classical Runge-Kutta (4th order) in time, ``sub``
    steps per sample interval, of ``dz/dt = sigma (dq - z |dq|)`` (continuous in dq) with the
    analytic velocity ``dq_of(t)`` (m, n), from rest: independent of the model's stepping in
    position."""
    h = (t[1] - t[0]) / sub
    tf = t[0] + h * np.arange(sub * (t.size - 1) + 1)
    v = dq_of(np.concatenate([tf, tf[:-1] + h / 2]))
    full, mid = v[: tf.size], v[tf.size :]

    def f(z, d):
        return sigma * (d - z * np.abs(d))

    z = np.zeros((t.size, sigma.size))
    zc = np.zeros(sigma.size)
    for i in range(tf.size - 1):
        k1 = f(zc, full[i])
        k2 = f(zc + h / 2 * k1, mid[i])
        k3 = f(zc + h / 2 * k2, mid[i])
        k4 = f(zc + h * k3, full[i + 1])
        zc = zc + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        if (i + 1) % sub == 0:
            z[(i + 1) // sub] = zc
    return z


def dahl_log(robot, *, seconds=4.0, rate=500.0, seed=1, noise=0.0):
    t = np.arange(0.0, seconds, 1 / rate)
    q, dq, ddq = motion(t, seed)
    z = dahl_integrated(t, lambda s: motion(s, seed)[1], SIGMA)
    tau = robot.inverse_dynamics(q, dq, ddq) + FV * dq + FC * z
    if noise:
        rng = np.random.default_rng(seed + 10)
        tau = tau + noise * tau.std(axis=0) * rng.standard_normal(tau.shape)
    return JointData(t, q, dq, ddq, tau, "dahl log"), z


def test_state_follows_the_closed_form_and_an_independent_integration():
    # one way from rest: z = 1 - exp(-sigma q) (closed form of dz/dq = sigma (1 - z))
    q = np.linspace(0, 0.1, 201)[:, None]
    np.testing.assert_allclose(dahl_state(q, [40.0])[:, 0], 1 - np.exp(-40 * q[:, 0]), atol=1e-12)
    # a sampled motion with rests and reversals against the Runge-Kutta integration
    t = np.arange(0.0, 2.0, 1e-3)
    q, _, _ = motion(t, 2)
    z = dahl_integrated(t, lambda s: motion(s, 2)[1], SIGMA, sub=4)
    got = dahl_state(q, SIGMA)
    assert np.max(np.abs(got - z)) < 1e-3
    assert np.all(np.abs(got) <= 1.0)
    # rate-independent: every other sample of the same path gives the same state there
    np.testing.assert_allclose(dahl_state(q[::2], SIGMA), got[::2], atol=5e-3)


def test_fit_recovers_sigma_and_fc_and_the_static_models_are_worse_at_rest(arm):
    log, _ = dahl_log(arm)
    fit = {"min_velocity": 0.0, "rsd_threshold": None}
    choice = select_friction_model(arm, [log], kind="dahl", fit=fit)
    rec = choice.record
    assert rec["kind"] == "dahl" and rec["chosen_by"] == "given"
    sigma = np.asarray(rec["sigma"])
    assert np.all(np.abs(sigma / SIGMA - 1) < 1e-3), sigma
    res = identify(choice.robot, log, base=choice.base, **fit)
    names = list(res.base.names)
    for k in range(3):
        for nm, v in (("Fc", FC), ("Fv", FV)):
            got = res.full[names.index(f"{nm}{k + 1}")]
            assert abs(got / v[k] - 1) < 1e-3, (nm, k, got, v[k])
    # where the joints rest the true friction is Fc z held since they stopped (known here): the
    # static models, a function of the velocity (zero at rest), miss it; Dahl does not
    rest = np.abs(log.dq) < 1e-9
    assert rest.mean(axis=0).min() > 0.2

    def at_rest(r):
        err = log.tau - r.predict(log)
        return np.sqrt(np.mean(err[rest] ** 2))

    dahl = at_rest(res)
    held = np.sqrt(np.mean((FC * dahl_state(log.q, SIGMA))[rest] ** 2))
    assert dahl < 1e-3 * held
    for kind in ("coulomb", "smooth", "stribeck"):
        c = select_friction_model(arm, [log], kind=kind, fit=fit)
        static = at_rest(identify(c.robot, log, base=c.base, **fit))
        assert static > 0.3 * held > 10 * dahl, (kind, static, held, dahl)


def test_cli_records_dahl_and_predict_follows_the_state_on_another_log(arm, tmp_path):
    log, _ = dahl_log(arm, noise=0.0)
    other, _ = dahl_log(arm, seconds=2.0, seed=7)
    robot_path = random_arm_yaml(tmp_path / "arm.yaml", n=3, seed=4)
    for name, d in (("fit.csv", log), ("other.csv", other)):
        write_csv(tmp_path / name, d.t, d.q, d.tau, d.dq, d.ddq)
    out = cli("identify", robot_path, tmp_path / "fit.csv", "--friction-model", "dahl", "--filter",
              "none", "--min-velocity", "0", "--json", tmp_path / "id.json")  # fmt: skip
    assert "friction model dahl" in out and "Dahl sigma" in out
    doc = json.loads((tmp_path / "id.json").read_text())
    fm = doc["friction_model"]
    assert fm["kind"] == "dahl" and np.all(np.abs(np.asarray(fm["sigma"]) / SIGMA - 1) < 0.02)
    cli("predict", robot_path, tmp_path / "id.json", tmp_path / "other.csv", "--filter", "none",
        "-o", tmp_path / "pred.csv")  # fmt: skip
    pred = np.genfromtxt(tmp_path / "pred.csv", delimiter=",", names=True)
    tau_hat = np.column_stack([pred[f"tau_hat{k + 1}"] for k in range(3)])
    np.testing.assert_allclose(tau_hat, other.tau, atol=0.01 * np.abs(other.tau).max())


SNAPPED = """<robot name="snapped4"><link name="base"/>
<link name="l1"><inertial><origin xyz="0 0 0.1"/><mass value="4"/>
<inertia ixx="0.03" iyy="0.03" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
<link name="l2"><inertial><origin xyz="0.15 0 0"/><mass value="3"/>
<inertia ixx="0.005" iyy="0.02" izz="0.02" ixy="0.001" ixz="0" iyz="0"/></inertial></link>
<link name="l3"><inertial><origin xyz="0.12 0 0.01"/><mass value="2"/>
<inertia ixx="0.003" iyy="0.012" izz="0.012" ixy="0" ixz="0.0005" iyz="0"/></inertial></link>
<link name="l4"><inertial><origin xyz="0 0.01 0.05"/><mass value="1"/>
<inertia ixx="0.002" iyy="0.002" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
<origin xyz="0 0 0.3"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="150" velocity="2"/>
</joint><joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
<origin xyz="0 0 0.2" rpy="1.5708 0 0"/><axis xyz="0 0 1"/>
<limit lower="-2" upper="2" effort="150" velocity="2"/></joint>
<joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>
<origin xyz="0.35 0 0"/><axis xyz="0 0 1"/>
<limit lower="-2.5" upper="2.5" effort="80" velocity="2"/></joint>
<joint name="j4" type="revolute"><parent link="l3"/><child link="l4"/>
<origin xyz="0.3 0 0" rpy="0 1.5708 0"/><axis xyz="0 0 1"/>
<limit lower="-3" upper="3" effort="30" velocity="3"/></joint></robot>"""


def test_dahl_identification_of_a_snapped_robot_predicts_with_its_base_set(tmp_path):
    """The Dahl base set keeps the snap of the base set it is made from (the origins' angles
    of 1.5708 rad snapped to pi/2): the JSON records it and predict forms the same set again
    (it formed it unsnapped, whose names differ, and refused the JSON)."""
    from mindyn.identification.friction import dahl_base

    path = tmp_path / "snapped4.urdf"
    path.write_text(SNAPPED)
    robot = mindyn.load(path)
    base = mindyn.base_parameters(robot, friction=True)
    assert base.snap_decision["applied"]
    sigma = np.r_[SIGMA, 40.0]
    assert dahl_base(base, 50.0).with_sigma(sigma).snap_decision == base.snap_decision
    unsnapped = mindyn.base_parameters(robot, friction=True, snap=False)
    assert list(unsnapped.names) != list(base.names)  # what made the JSON unreadable
    t = np.arange(0.0, 3.0, 1 / 500.0)

    def four(s):  # the three joints of motion() and a fourth from another of its seeds
        a, b = motion(s, 1), motion(s, 6)
        return tuple(np.hstack([x, y[:, :1]]) for x, y in zip(a, b))

    q, dq, ddq = four(t)
    z = dahl_integrated(t, lambda s: four(s)[1], sigma)
    tau = robot.inverse_dynamics(q, dq, ddq) + np.r_[FV, 0.4] * dq + np.r_[FC, 0.5] * z
    log = JointData(t, q, dq, ddq, tau, "dahl log")
    write_csv(tmp_path / "log.csv", log.t, log.q, log.tau, log.dq, log.ddq)
    cli("identify", path, tmp_path / "log.csv", "--friction-model", "dahl", "--filter", "none",
        "--min-velocity", "0", "--json", tmp_path / "id.json")  # fmt: skip
    doc = json.loads((tmp_path / "id.json").read_text())
    assert doc["base_snap"]["mode"] == "auto" and doc["base_names"] == list(base.names)
    cli("predict", path, tmp_path / "id.json", tmp_path / "log.csv", "--filter", "none",
        "-o", tmp_path / "pred.csv")  # fmt: skip
    pred = np.genfromtxt(tmp_path / "pred.csv", delimiter=",", names=True)
    tau_hat = np.column_stack([pred[f"tau_hat{k + 1}"] for k in range(4)])
    np.testing.assert_allclose(tau_hat, log.tau, atol=0.01 * np.abs(log.tau).max())


def test_base_names_that_differ_are_named(arm, tmp_path):
    """predict names the parameters that differ, never two equal truncated lists."""
    from mindyn.identification import DataError
    from mindyn.identification.document import names_difference
    from mindyn.identification.prediction import identified_model

    base = mindyn.base_parameters(arm, friction=True)
    names = list(base.names)
    doc = {"robot": arm.name, "friction": True, "rotor": False, "offset": False,
           "base_names": names[:-1] + ["Fx9"], "base_values": [1.0] * base.n}  # fmt: skip
    with pytest.raises(DataError) as e:
        identified_model(doc, arm)
    assert f"only in the file: Fx9; only here: {names[-1]}" in str(e.value), str(e.value)
    swapped = [names[1], names[0], *names[2:]]
    said = names_difference(swapped, names)
    assert said == (
        f"the same names in another order, first at position 1: {names[1]} in the file, "
        f"{names[0]} here"
    )


def test_generated_code_and_descriptions_refuse_the_dahl_state(arm, tmp_path, capsys):
    from mindyn.cli import main

    robot_path = random_arm_yaml(tmp_path / "arm.yaml", n=3, seed=4)
    base = mindyn.base_parameters(arm, friction=True)
    names = arm.parameter_names(rotor=False, friction=True)
    doc = {
        "robot": arm.name,
        "friction": True,
        "rotor": False,
        "offset": False,
        "base_names": list(base.names),
        "base_values": [1.0] * base.n,
        "classical": dict(zip(names, map(float, arm.parameters(rotor=False, friction=True)))),
        "friction_model": {"kind": "dahl", "sigma": [50.0, 50.0, 50.0], "chosen_by": "given"},
    }
    (tmp_path / "id.json").write_text(json.dumps(doc))
    capsys.readouterr()
    for argv in (
        [
            "codegen",
            str(robot_path),
            "--lang",
            "c",
            "--friction",
            "--params",
            str(tmp_path / "id.json"),
            "-o",
            str(tmp_path / "gen"),
        ],  # fmt: skip
        ["export", str(robot_path), str(tmp_path / "id.json"), "--yaml", str(tmp_path / "o.yaml")],
        ["detect", str(robot_path), str(tmp_path / "id.json"), "x.csv"],
    ):
        assert main(argv) != 0
        err = capsys.readouterr().err
        assert "Dahl friction model" in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "gen.h").exists() and not (tmp_path / "o.yaml").exists()
    doc["friction_model"]["sigma"] = [50.0, -1.0, 50.0]
    (tmp_path / "id.json").write_text(json.dumps(doc))
    assert main(["predict", str(robot_path), str(tmp_path / "id.json"), "x.csv", "-o",
                 str(tmp_path / "p.csv")]) != 0  # fmt: skip
    err = capsys.readouterr().err
    assert "sigma" in err and "positive" in err and len(err.strip().splitlines()) == 1, err


def test_dahl_needs_the_dynamic_model(arm):
    log, _ = dahl_log(arm, seconds=2.0)
    with pytest.raises(mindyn.Error, match="only with the dynamic model"):
        select_friction_model(arm, [log], kind="dahl", fit={"model": "energy"})


def test_auto_picks_dahl_on_a_dahl_log(arm):
    log, _ = dahl_log(arm, noise=0.01, seed=3)
    choice = select_friction_model(arm, [log], kind="auto")
    rec = choice.record
    assert rec["chosen_by"] == "held-out data" and rec["kind"] == "dahl", rec["candidates"]
    assert "dahl" in rec["candidates"] and isinstance(choice.base.sigma, np.ndarray)


def test_auto_leaves_out_a_fit_whose_friction_drives_the_motion(arm):
    """A log whose low-speed torque pushes the joints along (Stribeck term Fs = -2 Fc: f(v)
    sign(v) = -Fc just above zero, below a twentieth of the speeds) is not friction: auto leaves
    the Stribeck fit that reproduces it out, naming the slots, and chooses among the others."""
    rng = np.random.default_rng(5)
    t = np.arange(0.0, 8.0, 1 / 200)
    q, dq, ddq = (np.zeros((t.size, 3)) for _ in range(3))
    for k in range(3):
        for h in (1, 2, 3):
            a, om, ph = rng.uniform(0.2, 0.5) / h, 2 * np.pi * 0.25 * h * (1 + 0.1 * k), 1.0 * k
            q[:, k] += a * np.sin(om * t + ph)
            dq[:, k] += a * om * np.cos(om * t + ph)
            ddq[:, k] -= a * om**2 * np.sin(om * t + ph)
    w = np.full(3, 0.05)
    s = np.sign(dq)
    tau = (
        arm.inverse_dynamics(q, dq, ddq) + FV * dq + FC * s - 2 * FC * s * np.exp(-((dq / w) ** 2))
    )
    tau += 0.01 * tau.std(axis=0) * rng.standard_normal(tau.shape)
    log = JointData(t, q, dq, ddq, tau, "active log")
    rec = select_friction_model(arm, [log], kind="auto").record
    assert "stribeck" not in rec["candidates"] and rec["kind"] != "stribeck"
    why = rec["not_dissipative"]["stribeck"]
    assert all(f"joint {k}" in why for k in (1, 2, 3)), why
    # the same fit given explicitly is the user's choice: kept
    assert select_friction_model(arm, [log], kind="stribeck").record["kind"] == "stribeck"


def test_identify_refuses_to_write_a_description_of_a_dahl_estimate(arm, tmp_path, capsys):
    from mindyn.cli import main

    log, _ = dahl_log(arm, noise=0.01, seed=3)
    write_csv(tmp_path / "fit.csv", log.t, log.q, log.tau, log.dq, log.ddq)
    robot_path = random_arm_yaml(tmp_path / "arm.yaml", n=3, seed=4)
    capsys.readouterr()
    rc = main(["identify", str(robot_path), str(tmp_path / "fit.csv"), "--friction-model", "auto",
               "--filter", "none", "--consistent", "--prior-weight", "1", "--yaml",
               str(tmp_path / "out.yaml")])  # fmt: skip
    captured = capsys.readouterr()
    assert "friction model dahl" in captured.out
    assert rc != 0 and "Dahl friction model" in captured.err, captured.err
    assert len(captured.err.strip().splitlines()) == 1 and not (tmp_path / "out.yaml").exists()


def _dahl_robot(arm):
    r = arm.with_friction_model("coulomb")
    r.viscous, r.coulomb = FV, FC
    p = r.parameters(rotor=True, friction=True).reshape(r.n, -1).copy()
    p[:, 10] = 0.0  # no rotor inertia
    plant = p.copy()
    plant[:, 12] = 0.0  # the Coulomb term is the Dahl state's
    return r, p.reshape(-1), plant.reshape(-1)


def test_open_loop_simulation_follows_an_independent_integration(arm):
    from mindyn.control import SumOfSines, simulate_inverse

    r, _, plant = _dahl_robot(arm)
    ref = SumOfSines(r, period=2.0)
    log = simulate_inverse(r, ref, rate=500.0, friction=True, dahl_sigma=SIGMA)
    z = dahl_integrated(log.t, lambda s: ref.evaluate(s)[1], SIGMA)
    np.testing.assert_allclose(log.friction_state, z, atol=1e-3)
    rigid = r.inverse_dynamics(log.q_true, log.dq_true, log.ddq_true, plant)  # + viscous
    np.testing.assert_allclose(log.tau_true - rigid, FC * z, atol=2e-3 * FC.max())
    assert log.info["dahl"]["sigma"] == SIGMA.tolist()


def test_closed_loop_plant_integrates_the_state_with_the_motion(arm):
    """The plant with Dahl friction against scipy's adaptive RK45 of the same equations written
    out here (forward dynamics of the rigid body with viscous friction, the torque held over each
    period minus Fc z, dz/dt = sigma (dq - z |dq|)), from the same start, period by period."""
    from mindyn.control import SumOfSines, simulate
    from scipy.integrate import solve_ivp

    r, _, plant = _dahl_robot(arm)
    log = simulate(r, SumOfSines(r, period=2.0), rate=200.0, duration=0.5, friction=True,
                   dahl_sigma=SIGMA)  # fmt: skip
    n, period = r.n, 1 / 200.0
    x = np.concatenate([log.q_true[0], log.dq_true[0], np.zeros(n)])
    for i in range(log.t.size - 1):
        tau = log.tau_true[i]

        def f(_t, x, tau=tau):
            q, dq, z = x[:n], x[n : 2 * n], x[2 * n :]
            ddq = r.forward_dynamics(q, dq, tau - FC * z, plant)
            return np.concatenate([dq, ddq, SIGMA * (dq - z * np.abs(dq))])

        x = solve_ivp(f, (0, period), x, rtol=1e-10, atol=1e-12).y[:, -1]
        np.testing.assert_allclose(x[:n], log.q_true[i + 1], atol=1e-6)
        np.testing.assert_allclose(x[2 * n :], log.friction_state[i + 1], atol=1e-4)
    assert np.ptp(log.friction_state, axis=0).min() > 0.5  # the state moved


def test_simulation_checks_the_dahl_options(arm):
    from mindyn.control import SumOfSines, simulate

    r, _, _ = _dahl_robot(arm)
    ref = SumOfSines(r, period=2.0)
    for kw, message in (
        ({"friction": False, "dahl_sigma": SIGMA}, "friction=True"),
        ({"friction": True, "dahl_sigma": -SIGMA}, "positive"),
        ({"friction": True, "dahl_sigma": SIGMA, "integrator": "scipy"}, "rk4"),
    ):
        with pytest.raises(ValueError, match=message):
            simulate(r, ref, rate=200.0, duration=0.1, **kw)


def test_stateless_steps_refuse_a_dahl_base_set(arm):
    from mindyn.control import MomentumObserver
    from mindyn.identification.friction import dahl_base

    base = dahl_base(mindyn.base_parameters(arm, friction=True), SIGMA)
    with pytest.raises(mindyn.Error, match="no Dahl friction state"):
        MomentumObserver(base, np.ones(base.n), period=0.001)
    with pytest.raises(mindyn.Error, match="one sample has none"):
        base.regressor(np.zeros(3), np.zeros(3), np.zeros(3))
    # a path: the Coulomb column is the state, the rest the coulomb model's regressor
    q = np.linspace(0, 0.05, 11)[:, None] * np.array([1.0, -1.0, 0.5])
    W = base.regressor(q, np.ones_like(q), np.zeros_like(q))
    W0 = mindyn.base_parameters(arm, friction=True).regressor(q, np.ones_like(q), np.zeros_like(q))
    names = list(base.names)
    fc = [names.index(f"Fc{k + 1}") for k in range(3)]
    other = [c for c in range(base.n) if c not in fc]
    np.testing.assert_array_equal(W[:, :, other], W0[:, :, other])
    for k, c in enumerate(fc):
        np.testing.assert_allclose(W[:, k, c], dahl_state(q, SIGMA)[:, k], atol=1e-15)
        assert not np.any(np.delete(W[:, :, c], k, axis=1))
