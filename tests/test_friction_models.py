"""Friction models (viscous + Coulomb, direction-dependent Coulomb, smooth Coulomb, Stribeck):
their regressor columns and torques against the formulas written out here, the rigid part
against Pinocchio, base-parameter counts by the three methods, and identification from logs
this module generates with known friction (noise-free recovery, the Stribeck velocity found by
the search, the model chosen on held-out data)."""

from __future__ import annotations

import json
import re

import mindyn
import numpy as np
import pinocchio as pin
import pytest
import yaml
from conftest import cli, pinocchio_model
from mindyn.identification import JointData, identify, select_friction_model, write_csv
from random_arm import random_arm_yaml

KINDS = ("coulomb", "asymmetric", "smooth", "stribeck")


def sign(v):
    return np.sign(v)  # sign(0) = 0


def friction_formula(kind, v, w, fv, fc, f3):
    """The friction torque of each joint written out (the models' definitions)."""
    if kind == "coulomb":
        return fv * v + fc * sign(v)
    if kind == "asymmetric":
        return fv * v + fc * sign(v) + f3 * np.abs(sign(v))
    if kind == "smooth":
        return fv * v + fc * np.tanh(v / w)
    return fv * v + fc * sign(v) + f3 * sign(v) * np.exp(-((v / w) ** 2))


def columns_formula(kind, v, w):
    """The friction columns of one joint, written out."""
    cols = [v]
    if kind == "smooth":
        cols.append(np.tanh(v / w))
    else:
        cols.append(sign(v))
    if kind == "asymmetric":
        cols.append(np.abs(sign(v)))
    if kind == "stribeck":
        cols.append(sign(v) * np.exp(-((v / w) ** 2)))
    return np.array(cols)


def with_kind(robot, kind, w):
    return robot.with_friction_model(kind, velocity=w if kind in ("smooth", "stribeck") else None)


@pytest.fixture(scope="module")
def arm(tmp_path_factory):
    return mindyn.load(random_arm_yaml(tmp_path_factory.mktemp("arm") / "arm.yaml", n=3, seed=4))


@pytest.mark.parametrize("kind", KINDS)
def test_regressor_and_torques_follow_the_formulas(kind, rng):
    robot = mindyn.load("puma560")
    n = robot.n
    w = rng.uniform(0.05, 0.5, n)
    r = with_kind(robot, kind, w)
    q, ddq = rng.normal(size=n), rng.normal(size=n)
    dq = rng.normal(size=n) * 0.3
    dq[2] = 0.0  # at rest: sign(0) = 0
    c = 3 if kind in ("asymmetric", "stribeck") else 2
    W = r.regressor(q, dq, ddq, rotor=True, friction=True)
    assert W.shape == (n, n * (11 + c))
    names = r.parameter_names(rotor=True, friction=True)
    third = {"asymmetric": "Fa", "stribeck": "Fs"}.get(kind)
    W0 = robot.regressor(q, dq, ddq, rotor=True)  # rigid part and rotor
    for k in range(n):
        block = W[:, k * (11 + c) : (k + 1) * (11 + c)]
        np.testing.assert_allclose(block[:, :11], W0[:, 11 * k : 11 * k + 11], atol=1e-12)
        expect = np.zeros((n, c))
        expect[k] = columns_formula(kind, dq[k], w[k])
        np.testing.assert_allclose(block[:, 11:], expect, atol=1e-15)
        assert names[k * (11 + c) + 11 : (k + 1) * (11 + c)] == (
            [f"Fv{k + 1}", f"Fc{k + 1}"] + ([f"{third}{k + 1}"] if third else [])
        )
    # the rigid part against Pinocchio's recursive Newton-Euler
    pm = pinocchio_model(robot)
    tau_pin = pin.rnea(pm, pm.createData(), q, dq, ddq)
    np.testing.assert_allclose(W0[:, [i for i in range(11 * n) if i % 11 < 10]] @ robot.params,
                               tau_pin, atol=1e-9)  # fmt: skip
    # inverse dynamics with a parameter vector of the model's layout (read off its size)
    fv, fc, f3 = rng.uniform(0.5, 2, n), rng.uniform(0.5, 2, n), rng.uniform(-1, 1, n)
    p = np.zeros((n, 10 + c))
    p[:, :10] = robot.params.reshape(n, 10)
    p[:, 10], p[:, 11] = fv, fc
    if c == 3:
        p[:, 12] = f3
    tau = r.inverse_dynamics(q, dq, ddq, p.reshape(-1))
    expect = tau_pin + friction_formula(kind, dq, w, fv, fc, f3 if c == 3 else 0.0)
    np.testing.assert_allclose(tau, expect, atol=1e-9)
    # the simulation plant's forward dynamics inverts it (sign not smoothed)
    plant = mindyn._core.Integrator(r._m, p.reshape(-1), 0.0)
    np.testing.assert_allclose(plant.acceleration(q, dq, tau), ddq, atol=1e-8)
    np.testing.assert_allclose(r.forward_dynamics(q, dq, tau, p.reshape(-1)), ddq, atol=1e-8)


def test_third_friction_parameter_is_stored_and_named(arm):
    r = arm.with_friction_model("stribeck", velocity=[0.1, 0.2, 0.3])
    r.third_friction = [1.0, 2.0, 3.0]
    names = r.parameter_names(rotor=False, friction=True)
    p = r.parameters(rotor=False, friction=True)
    assert len(p) == 13 * r.n
    assert [p[names.index(f"Fs{k + 1}")] for k in range(3)] == [1.0, 2.0, 3.0]
    assert "Fa2" in r.with_friction_model("asymmetric").parameter_names(rotor=False, friction=True)
    assert r.layout_sizes == (10, 11, 13, 14)


@pytest.mark.parametrize(
    "velocity, message",
    [([0.1, -0.2, 0.3], "positive"), ([0.1, 0.2], "shape"), (None, "velocity")],
)
def test_friction_model_errors_are_one_line(arm, velocity, message):
    with pytest.raises(mindyn.Error, match=message):
        arm.with_friction_model("stribeck", velocity=velocity)
    with pytest.raises(mindyn.ArgumentError, match="'coulomb', 'asymmetric', 'smooth', 'stribeck'"):
        arm.with_friction_model("viscous")


@pytest.mark.parametrize("kind", ["smooth", "stribeck"])
@pytest.mark.parametrize("bad", [-1e-7, 0.0, -3.0])
def test_a_velocity_scale_that_is_not_positive_is_a_bad_argument_naming_its_value(arm, kind, bad):
    """The velocity is an argument: a scale at or below zero is an ArgumentError naming it, the
    entry, its joint and the value as given (a small one printed as -0.000000 read as a zero)."""
    v = [0.1, bad, 0.3]
    with pytest.raises(mindyn.ArgumentError) as err:
        arm.with_friction_model(kind, velocity=v)
    expected = f"velocity has {bad:g} at entry 2 (joint '{arm.joint_names[1]}')"
    assert str(err.value).startswith(expected), str(err.value)
    assert arm.friction_model["kind"] == "coulomb"  # the robot is unchanged


@pytest.mark.parametrize("kind", ["asymmetric", "stribeck"])
def test_third_column_is_a_base_parameter_by_all_three_methods(arm, kind):
    r = with_kind(arm, kind, np.full(arm.n, 0.2))
    coulomb = mindyn.base_parameters(arm, friction=True).n
    counts = {m: mindyn.base_parameters(r, friction=True, method=m) for m in
              ("projection", "recursive", "numerical")}  # fmt: skip
    for m, b in counts.items():
        assert b.n == coulomb + arm.n, m
        assert all(f"F{'a' if kind == 'asymmetric' else 's'}{k + 1}" in b.names
                   for k in range(arm.n))  # fmt: skip


@pytest.mark.parametrize("side", ["joint", "motor"])
def test_asymmetric_friction_of_a_lift_with_a_rotor_is_its_own_base_parameter(tmp_path, side):
    """A prismatic joint along gravity with rotor inertia: tau = M (ddq + g) + Ia r^2 ddq +
    r (Fv r dq + Fc sign(r dq) + Fa |sign(r dq)|), r its reduction (1 on the joint side). While
    it moves, M g is a constant as Fa |sign v| is, but not at rest: five independent functions,
    five base parameters by every method, and each base set gives M g at rest."""
    doc = {"name": "lift", "convention": "dh", "gravity": [0, 0, -9.81], "joints": [
        {"name": "z", "type": "prismatic", "a": 0.0, "alpha": 0.0, "d": 0.0, "theta": 0.0,
         "limits": {"lower": -0.5, "upper": 0.5}, "inertial": {"mass": 2.0, "com": [0.1, 0, 0],
         "inertia": {"xx": 0.01, "yy": 0.01, "zz": 0.01}}}]}  # fmt: skip
    r = 1256.6  # a ball screw's reduction [rad/m]
    if side == "motor":
        doc["transmissions"] = {"matrix": [[r]]}
    path = tmp_path / "lift.yaml"
    path.write_text(yaml.safe_dump(doc), encoding="utf-8")
    robot = mindyn.load(path).with_friction_model("asymmetric")
    assert robot.drive_side == side
    names = robot.parameter_names(rotor=True, friction=True)
    p = np.zeros(len(names))
    m, ia, fv, fc, fa = 2.0, 3e-5, 1e-4, 0.02, 0.01
    for name, v in zip(("M1", "Ia1", "Fv1", "Fc1", "Fa1"), (m, ia, fv, fc, fa), strict=True):
        p[names.index(name)] = v
    ratio = r if side == "motor" else 1.0
    for method in ("projection", "recursive", "numerical"):
        b = mindyn.base_parameters(robot, method=method, rotor=True, friction=True)
        assert b.n == 5, (method, b.names)
        for dq in (0.0, 0.3, -0.2):
            ddq = 0.7
            v = ratio * dq
            want = m * (ddq + 9.81) + ratio * (
                ia * ratio * ddq + fv * v + fc * np.sign(v) + fa * abs(np.sign(v))
            )
            got = b.regressor([0.1], [dq], [ddq]) @ b.values(p)
            assert got[0] == pytest.approx(want, rel=1e-9), (method, dq)


def multisine(n: int, t, rng):
    """Analytic q, dq, ddq (m, n) of a multi-sine motion at the times ``t``: three harmonics of
    0.25 Hz (scaled by 1 + 0.1 k for joint k) per joint, random amplitudes and phases."""
    q, dq, ddq = (np.zeros((t.size, n)) for _ in range(3))
    for k in range(n):
        for h in range(1, 4):
            a = rng.uniform(0.2, 0.5) / h
            om = 2 * np.pi * 0.25 * h * (1 + 0.1 * k)
            ph = rng.uniform(0, 2 * np.pi)
            q[:, k] += a * np.sin(om * t + ph)
            dq[:, k] += a * om * np.cos(om * t + ph)
            ddq[:, k] -= a * om**2 * np.sin(om * t + ph)
    return q, dq, ddq


def make_log(robot, kind, w, fv, fc, f3, *, seconds=8.0, rate=200.0, noise=0.0, seed=0):
    """A log of a multi-sine motion (analytic q, dq, ddq) whose torques are the rigid-body ones
    plus the friction written out here, with white noise of ``noise`` times each joint's RMS."""
    rng = np.random.default_rng(seed)
    t = np.arange(0, seconds, 1 / rate)
    q, dq, ddq = multisine(robot.n, t, rng)
    tau = robot.inverse_dynamics(q, dq, ddq) + friction_formula(kind, dq, w, fv, fc, f3)
    if noise:
        tau = tau + noise * tau.std(axis=0) * rng.standard_normal(tau.shape)
    return JointData(t, q, dq, ddq, tau, f"{kind} log")


def truth(robot, kind, w, fv, fc, f3):
    r = with_kind(robot, kind, w)
    r.viscous, r.coulomb = fv, fc
    if kind in ("asymmetric", "stribeck"):
        r.third_friction = f3
    b = mindyn.base_parameters(r, friction=True)
    return b, b.values(r.parameters(rotor=False, friction=True))


FV, FC = np.array([0.8, 0.5, 0.3]), np.array([1.5, 1.0, 0.6])


@pytest.mark.parametrize(
    "kind, f3",
    [("asymmetric", np.array([0.4, -0.3, 0.2])), ("stribeck", np.array([1.0, 0.7, 0.5]))],
)
def test_noise_free_recovery_with_the_searched_stribeck_velocity(arm, kind, f3):
    w = np.array([0.15, 0.25, 0.1])
    log = make_log(arm, kind, w, FV, FC, f3)
    choice = select_friction_model(arm, [log], kind=kind, fit={"min_velocity": 0.0})
    res = identify(choice.robot, log, base=choice.base, rsd_threshold=None, min_velocity=0.0)
    base, expect = truth(arm, kind, w, FV, FC, f3)
    assert list(res.base.names) == list(base.names)
    np.testing.assert_allclose(res.full, expect, rtol=1e-6, atol=1e-6 * np.abs(expect).max())
    if kind == "stribeck":
        found = np.asarray(choice.record["velocity"])
        assert np.all(np.abs(found / w - 1) <= 1e-3), found
        assert choice.record["chosen_by"] == "given"


def test_noise_free_recovery_smooth_with_given_width(arm):
    w = np.array([0.05, 0.08, 0.03])
    log = make_log(arm, "smooth", w, FV, FC, 0.0)
    choice = select_friction_model(arm, [log], kind="smooth", width=w)
    res = identify(choice.robot, log, base=choice.base, rsd_threshold=None, min_velocity=0.0)
    _, expect = truth(arm, "smooth", w, FV, FC, 0.0)
    np.testing.assert_allclose(res.full, expect, rtol=1e-6, atol=1e-6 * np.abs(expect).max())


@pytest.mark.parametrize("model", ["energy", "integral"])
def test_energy_and_integral_models_carry_the_stribeck_terms(arm, model):
    w, f3 = np.array([0.15, 0.25, 0.1]), np.array([1.0, 0.7, 0.5])
    log = make_log(arm, "stribeck", w, FV, FC, f3, rate=1000.0, seconds=6.0)
    base, expect = truth(arm, "stribeck", w, FV, FC, f3)
    res = identify(base.robot, log, model=model, base=base, rsd_threshold=None, weighted=False)
    names = list(base.names)
    for k in range(arm.n):  # quadrature of the switching terms: 1 % on 1 kHz samples
        for nm, v in (("Fc", FC), ("Fs", f3)):
            got = res.full[names.index(f"{nm}{k + 1}")]
            assert abs(got / v[k] - 1) < 0.02, (model, nm, k, got, v[k])


@pytest.mark.parametrize(
    "kind, f3, w",
    [
        ("stribeck", np.array([1.5, 1.0, 0.8]), np.array([0.15, 0.25, 0.1])),
        ("asymmetric", np.array([0.6, -0.5, 0.4]), None),
        ("smooth", 0.0, np.full(3, 0.05)),  # the width given (as --friction-width)
    ],
)
def test_auto_picks_the_true_family_on_held_out_data(arm, kind, f3, w):
    log = make_log(arm, kind, w, FV, FC, f3, noise=0.01, seed=3)
    choice = select_friction_model(arm, [log], kind="auto", width=w if kind == "smooth" else None)
    rec = choice.record
    assert rec["chosen_by"] == "held-out data"
    assert rec["kind"] == kind, rec["candidates"]
    assert set(rec["candidates"]) == {*KINDS, "dahl"}


class Chirp:
    """A reference whose speed grows through the log (a linear chirp per joint): contiguous
    time blocks see different speed ranges, so a friction term alive at low speeds only is
    determined by a few samples of one block."""

    def __init__(self, n, duration, f0, f1, seed):
        rng = np.random.default_rng(seed)
        self.duration = duration
        self.a, self.phase = rng.uniform(0.3, 0.8, n), rng.uniform(0, 2 * np.pi, n)
        self.f0, self.rate = f0, (f1 - f0) / duration
        self.scale = 1 + 0.15 * np.arange(n)

    def evaluate(self, t):
        t = np.asarray(t, float)[:, None]
        om = 2 * np.pi * self.scale
        ph = om * (self.f0 * t + 0.5 * self.rate * t**2) + self.phase
        w = om * (self.f0 + self.rate * t)
        q, c = self.a * np.sin(ph), self.a * np.cos(ph)
        return q, c * w, -q * w**2 + c * om * self.rate


def chirp_log(robot):
    """3 s at 200 Hz of the chirp, torques with the robot's friction and noise 0.05 N m."""
    from mindyn.control import SensorNoise, simulate_inverse

    ref = Chirp(robot.n, 3.0, 0.02, 1.0, seed=4)
    log = simulate_inverse(
        robot, ref, rate=200.0, friction=True, noise=SensorNoise(torque=0.05), seed=4
    )
    return JointData(log.t, log.q, log.dq, log.ddq_true, log.tau, "chirp")


def test_auto_held_out_residuals_measure_prediction_not_conditioning(arm):
    """Viscous and Coulomb friction on a short log: the Stribeck velocity the search finds
    makes a Stribeck column non-zero on a sample or two of one block only; a fold fit without
    that block cannot determine its Fs and, kept, fitted it to noise (held-out residual 5e3
    noise variances per equation, the others about 1). The fold fits now decide their
    parameters as the fit does. The coulomb, asymmetric and stribeck models all contain the
    true friction (Fa = Fs = 0): with the Coulomb fit's weights (1 / sigma_j) each predicts a
    block to the noise, about 1 per fitted equation, summed over the blocks (all samples / the
    fitted ones, the slow ones scored too), and within 1 + O(parameters / equations) of each
    other (margin: 1.5). The smooth and Dahl models differ from the truth at reversals (one
    sample each): bounded by 10 x the smallest."""
    log = chirp_log(arm)
    rec = select_friction_model(arm, [log], kind="auto").record
    scores = rec["candidates"]
    assert set(scores) == {*KINDS, "dahl"}, rec
    res = identify(arm, log, friction=True)
    scale = log.m * arm.n / res.rows  # every sample scored, the fit's rows fitted
    best = min(scores.values())
    for k in ("coulomb", "asymmetric", "stribeck"):
        assert scores[k] <= 1.5 * scale, (k, scores)
        assert scores[k] <= 1.5 * best, (k, scores)
    for k, v in scores.items():
        assert v <= 10 * best, (k, scores)
    assert rec["kind"] != "stribeck", scores


def test_auto_picks_stribeck_on_the_short_log_with_stribeck_friction(arm):
    w, f3 = np.array([0.15, 0.25, 0.1]), np.array([0.75, 0.5, 0.4])
    r = arm.with_friction_model("stribeck", velocity=w)
    r.third_friction = f3
    rec = select_friction_model(arm, [chirp_log(r)], kind="auto").record
    assert rec["kind"] == "stribeck", rec["candidates"]


def test_cli_records_the_friction_model_and_predict_uses_it(arm, tmp_path):

    w, f3 = np.array([0.15, 0.25, 0.1]), np.array([1.0, 0.7, 0.5])
    log = make_log(arm, "stribeck", w, FV, FC, f3)
    csv = tmp_path / "log.csv"
    write_csv(csv, log.t, log.q, log.tau, log.dq, log.ddq)
    robot_path = tmp_path / "arm.yaml"
    random_arm_yaml(robot_path, n=3, seed=4)
    out = cli("identify", robot_path, csv, "--friction-model", "stribeck", "--filter", "none",
              "--min-velocity", "0", "--json", tmp_path / "id.json")  # fmt: skip
    assert "friction model stribeck" in out
    doc = json.loads((tmp_path / "id.json").read_text())
    fm = doc["friction_model"]
    assert fm["kind"] == "stribeck" and fm["chosen_by"] == "given" and doc["friction"]
    assert np.all(np.abs(np.asarray(fm["velocity"]) / w - 1) <= 1e-3)
    cli("predict", robot_path, tmp_path / "id.json", csv, "--filter", "none",
        "-o", tmp_path / "pred.csv")  # fmt: skip
    pred = np.genfromtxt(tmp_path / "pred.csv", delimiter=",", names=True)
    tau_hat = np.column_stack([pred[f"tau_hat{k + 1}"] for k in range(3)])
    np.testing.assert_allclose(tau_hat, log.tau, atol=1e-4 * np.abs(log.tau).max())


def test_cli_default_is_unchanged_and_options_are_checked(arm, tmp_path, capsys):

    log = make_log(arm, "coulomb", None, FV, FC, 0.0, noise=0.01)
    csv = tmp_path / "log.csv"
    write_csv(csv, log.t, log.q, log.tau, log.dq, log.ddq)
    robot_path = random_arm_yaml(tmp_path / "arm.yaml", n=3, seed=4)
    cli("identify", robot_path, csv, "--friction", "--json", tmp_path / "a.json")
    cli("identify", robot_path, csv, "--friction-model", "coulomb", "--json", tmp_path / "b.json")
    a, b = (json.loads((tmp_path / f).read_text()) for f in ("a.json", "b.json"))
    assert a["base_values"] == b["base_values"] and a["base_names"] == b["base_names"]
    assert (
        a["friction_model"]["kind"] == "coulomb" and a["friction_model"]["chosen_by"] == "default"
    )
    from mindyn.cli import main

    bad = [
        (["--friction-width", "0.1"], "applies only with --friction-model smooth or auto"),
        (["--friction-model", "smooth", "--friction-width", "-1"], "expected a positive number"),
        (["--friction-model", "stribeck", "--friction-width", "0.1"], "only with --friction-model"),
    ]
    capsys.readouterr()
    for extra, message in bad:
        assert main(["identify", str(robot_path), str(csv), *extra]) != 0
        err = capsys.readouterr().err
        assert message in err and len(err.strip().splitlines()) == 1, err


def test_simulations_apply_the_robots_friction_model(arm):
    """Open loop: the torques are the rigid-body ones plus the Stribeck friction written out;
    closed loop: the plant's applied torques, minus that friction, give the logged
    accelerations by the rigid-body dynamics."""
    from mindyn.control import SumOfSines, simulate, simulate_inverse

    w, f3 = np.array([0.15, 0.25, 0.1]), np.array([1.0, 0.7, 0.5])
    r = arm.with_friction_model("stribeck", velocity=w)
    r.viscous, r.coulomb, r.third_friction = FV, FC, f3
    ref = SumOfSines(r, period=2.0)
    log = simulate_inverse(r, ref, rate=200.0, friction=True)
    expect = r.inverse_dynamics(log.q_true, log.dq_true, log.ddq_true) + friction_formula(
        "stribeck", log.dq_true, w, FV, FC, f3
    )
    np.testing.assert_allclose(log.tau_true, expect, atol=1e-9)
    assert "Fs1" in log.param_names
    closed = simulate(r, ref, rate=200.0, duration=0.5, friction=True)
    rigid = r.inverse_dynamics(closed.q_true, closed.dq_true, closed.ddq_true)
    fr = friction_formula("stribeck", closed.dq_true, w, FV, FC, f3)
    np.testing.assert_allclose(rigid + fr, closed.tau_true, atol=1e-6 * np.abs(fr).max() + 1e-6)


def test_codegen_takes_the_friction_model_identified(arm, tmp_path, capsys):
    from mindyn.cli import main

    w = np.full(3, 0.05)
    log = make_log(arm, "smooth", w, FV, FC, 0.0)
    csv = tmp_path / "log.csv"
    write_csv(csv, log.t, log.q, log.tau, log.dq, log.ddq)
    robot_path = random_arm_yaml(tmp_path / "arm.yaml", n=3, seed=4)
    cli("identify", robot_path, csv, "--friction-model", "smooth", "--friction-width", "0.05",
        "--filter", "none", "--json", tmp_path / "id.json")  # fmt: skip
    capsys.readouterr()
    # the smooth model has the same parameter names as viscous + Coulomb: the JSON says which
    rc = main(["codegen", str(robot_path), "--lang", "c", "--friction", "--params",
               str(tmp_path / "id.json"), "-o", str(tmp_path / "gen")])  # fmt: skip
    assert rc == 0
    assert "friction model: smooth" in capsys.readouterr().out
    assert "Fv v + Fc tanh(v / w)" in (tmp_path / "gen.h").read_text()
    # and the momentum observer of the same model (one tanh per joint in its step)
    rc = main(["codegen", str(robot_path), "--lang", "c", "--friction", "--params",
               str(tmp_path / "id.json"), "--what", "momentum-observer", "--controller-period",
               "0.001", "-o", str(tmp_path / "obs")])  # fmt: skip
    assert rc == 0
    assert re.search(r"whole step: .*, 3 tanh$", capsys.readouterr().out, re.MULTILINE)
    header = (tmp_path / "obs.h").read_text()
    assert "Fv v + Fc tanh(v / w)" in header and "viscous and smooth Coulomb friction" in header


def test_descriptions_keep_other_friction_models_in_their_joint_terms_file(arm, tmp_path, capsys):
    """A description holds viscous and Coulomb friction; export --yaml of the smooth model
    writes the model and its widths to the joint-terms file beside the table, and the table
    loaded with it has them (the smooth model has the Coulomb model's parameter names: without
    the file it would be read back as Coulomb friction). MJCF, which has no place for them,
    refuses, as does identify --mjcf with such a model and identify --urdf with Dahl's."""
    from mindyn.cli import main

    robot_path = random_arm_yaml(tmp_path / "arm.yaml", n=3, seed=4)
    names = arm.parameter_names(rotor=False, friction=True)
    doc = {
        "robot": arm.name,
        "classical": dict(zip(names, map(float, arm.parameters(rotor=False, friction=True)))),
        "friction_model": {"kind": "smooth", "velocity": [0.1, 0.2, 0.3], "chosen_by": "given"},
    }
    (tmp_path / "id.json").write_text(json.dumps(doc))
    capsys.readouterr()
    assert main(["export", str(robot_path), str(tmp_path / "id.json"), "--yaml",
                 str(tmp_path / "out.yaml")]) == 0  # fmt: skip
    out = capsys.readouterr().out
    side = tmp_path / "out.joints.yaml"
    assert "friction model smooth: the table's 'friction' holds Fv and Fc only" in out, out
    back = mindyn.load(tmp_path / "out.yaml", joint_terms=side)
    assert back.friction_model["kind"] == "smooth"
    np.testing.assert_array_equal(back.friction_model["velocity"], [0.1, 0.2, 0.3])
    np.testing.assert_array_equal(
        back.parameters(rotor=False, friction=True), arm.parameters(rotor=False, friction=True)
    )
    assert mindyn.load(tmp_path / "out.yaml").friction_model["kind"] == "coulomb"
    rc = main(["export", str(robot_path), str(tmp_path / "id.json"), "--mjcf",
               str(tmp_path / "out.xml")])  # fmt: skip
    err = capsys.readouterr().err
    assert rc != 0 and "smooth friction model; MJCF holds viscous and dry friction only" in err
    assert not (tmp_path / "out.xml").exists()
    rc = main(["identify", str(robot_path), "x.csv", "--friction-model", "stribeck",
               "--consistent", "--mjcf", str(tmp_path / "o.xml")])  # fmt: skip
    assert rc != 0 and "not the stribeck friction model" in capsys.readouterr().err
    rc = main(["identify", str(robot_path), "x.csv", "--friction-model", "dahl",
               "--consistent", "--urdf", str(tmp_path / "o.urdf")])  # fmt: skip
    assert rc != 0 and "no robot description holds it" in capsys.readouterr().err


def test_auto_compares_models_on_the_same_blocks_paired():
    """Five blocks of very different difficulty; dahl is better than coulomb on every block by
    0.03 +- 0.005, smooth worse than coulomb on some: the one-standard-error rule on the
    block-by-block differences (written out here: sqrt(5) x their standard deviation) picks
    dahl, whose lead (0.15 in all) is far beyond the error of the difference (0.02), though it
    is within the spread of the blocks' own residuals (0.26), which an unpaired rule would take
    as the error and so keep coulomb."""
    from mindyn.identification.friction import simplest_within_one_error

    hard = np.array([0.30, 0.16, 0.34, 0.20, 0.23])
    lead = np.array([0.025, 0.035, 0.03, 0.03, 0.03])
    per_fold = {
        "coulomb": hard,
        "smooth": hard + [0.01, -0.01, 0.02, 0.0, 0.0],
        "dahl": hard - lead,
    }
    scores = {k: float(np.sum(v)) for k, v in per_fold.items()}
    chosen, best, se = simplest_within_one_error(scores, per_fold)
    assert best == "dahl" and chosen == "dahl"
    assert se["coulomb"] == pytest.approx(np.std(lead, ddof=1) * np.sqrt(5))
    assert np.std(per_fold["dahl"], ddof=1) * np.sqrt(5) > scores["coulomb"] - scores["dahl"]
    # a lead within its own error: the simpler model is kept
    noisy = {"coulomb": hard, "dahl": hard - [0.05, -0.04, 0.06, -0.05, 0.0]}
    chosen, best, _ = simplest_within_one_error(
        {k: float(np.sum(v)) for k, v in noisy.items()}, noisy
    )
    assert best == "dahl" and chosen == "coulomb"


def test_auto_output_states_each_excess_and_its_standard_error():
    """The output line of the choice gives, per candidate, its excess over the smallest and the
    standard error the rule compares it with (they were in the JSON only): figures written out
    here, dahl best on every block, coulomb's lead lost by 0.15 with a standard error of
    sqrt(5) x std(lead)."""
    from mindyn.identification.friction import friction_lines, simplest_within_one_error

    hard = np.array([0.30, 0.16, 0.34, 0.20, 0.23])
    lead = np.array([0.025, 0.035, 0.03, 0.03, 0.03])
    per_fold = {"coulomb": hard, "dahl": hard - lead}
    scores = {k: float(np.sum(v)) for k, v in per_fold.items()}
    chosen, best, se = simplest_within_one_error(scores, per_fold)
    record = {"candidates": scores, "smallest": best, "standard_error": se, "rule": "r"}
    text = "\n".join(friction_lines(mindyn.load("planar2"), record=record))
    excess = f"{lead.sum():.3g}"
    error = f"{np.std(lead, ddof=1) * np.sqrt(5):.3g}"
    assert (
        f"excess over the smallest (dahl) and its standard error: coulomb {excess} (se {error})"
        in text
    )
    alone = {"candidates": {"dahl": 1.0}, "smallest": "dahl", "standard_error": {"dahl": 0.0}}
    text = "\n".join(friction_lines(mindyn.load("planar2"), record={**alone, "rule": "r"}))
    assert "excess over the smallest" not in text  # no other candidate to compare


def geared(arm, tmp_path, ratios):
    """The arm of the ``arm`` fixture with a YAML transmission of one motor per joint, gear
    ratios ``ratios``: friction on the motor side by default, velocity scales in motor units."""
    doc = yaml.safe_load(random_arm_yaml(tmp_path / "arm.yaml", n=3, seed=4).read_text())
    doc["transmissions"] = {"matrix": np.diag(ratios).tolist(), "motors": ["m1", "m2", "m3"]}
    path = tmp_path / "geared.yaml"
    path.write_text(yaml.safe_dump(doc))
    robot = mindyn.load(path)
    assert robot.drive_side == "motor"
    return robot


RATIOS = np.array([50.0, -40.0, 30.0])


def test_motor_side_stribeck_velocity_is_found_in_the_motors_units(arm, tmp_path):
    """A motor of ratio r acting on its joint has the joint's friction at the velocity scale
    |r| w (r Fs sign(r dq) exp(-(r dq / (|r| w))^2) = |r| Fs sign(dq) exp(-(dq / w)^2)): on a
    log with Stribeck friction of velocity w on the joints (written out here), the motor side's
    search finds |r| w and the estimate is the joint side's truth divided as the loader divides
    (|r| Fc, r^2 Fv, |r| Fs). The search used to run over the joints' speeds, below every
    motor's (it ended at the top of its range, 1.6 to 2.0 rad/s instead of 3 to 10)."""
    w, f3 = np.array([0.15, 0.25, 0.1]), np.array([1.0, 0.7, 0.5])
    log = make_log(arm, "stribeck", w, FV, FC, f3)
    robot = geared(arm, tmp_path, RATIOS)
    choice = select_friction_model(robot, [log], kind="stribeck", fit={"min_velocity": 0.0})
    found = np.asarray(choice.record["velocity"])
    np.testing.assert_allclose(found, np.abs(RATIOS) * w, rtol=1e-3)
    res = identify(choice.robot, log, base=choice.base, rsd_threshold=None, min_velocity=0.0)
    names = list(res.base.names)
    for k, r in enumerate(RATIOS):
        for nm, want in (("Fv", FV[k] / r**2), ("Fc", FC[k] / abs(r)), ("Fs", f3[k] / abs(r))):
            got = res.full[names.index(f"{nm}{k + 1}")]
            assert got == pytest.approx(want, rel=1e-5), (nm, k, got, want)
    line = "\n".join(mindyn.identification.friction.friction_lines(choice.robot))
    assert "per motor" in line and "of the motor" in line, line


def test_motor_side_smooth_width_is_the_joint_sides_in_motor_units(arm, tmp_path):
    """tanh(r dq / (|r| w)) = sign(r) tanh(dq / w): the smooth model on the motor side is the
    joint side's with each width times |r|, so with widths derived from the same noisy log the
    two fits predict the same torques (to round-off) and the motor's width is |r| times the
    joint's. Before, the motor side took the joint's width for its motor: |r| times sharper."""
    w = np.array([0.05, 0.08, 0.03])
    log = make_log(arm, "smooth", w, FV, FC, 0.0, noise=0.01, seed=5)
    motor = geared(arm, tmp_path, RATIOS)
    joint = motor.with_drive_side("joint")
    on_m = select_friction_model(motor, [log], kind="smooth")
    on_j = select_friction_model(joint, [log], kind="smooth")
    wm, wj = (np.asarray(c.record["velocity"]) for c in (on_m, on_j))
    np.testing.assert_allclose(wm, np.abs(RATIOS) * wj, rtol=1e-12)
    fits = [identify(c.robot, log, base=c.base, rsd_threshold=None) for c in (on_m, on_j)]
    pm, pj = (
        c.base.regressor(log.q, log.dq, log.ddq) @ f.values for c, f in zip((on_m, on_j), fits)
    )
    np.testing.assert_allclose(pm, pj, rtol=0, atol=1e-9 * np.abs(pj).max())


def test_a_motor_that_never_moves_is_named(arm, tmp_path):
    """A motor whose velocity is zero throughout (here joint 3 held) is named as the motor in
    the one-line refusal of the smooth width and the Stribeck search."""
    log = make_log(arm, "coulomb", None, FV, FC, 0.0)
    held = JointData(
        log.t, log.q * [1, 1, 0], log.dq * [1, 1, 0], log.ddq * [1, 1, 0], log.tau, "held"
    )
    robot = geared(arm, tmp_path, RATIOS)
    for kind in ("smooth", "stribeck"):
        with pytest.raises(
            mindyn.identification.IdentificationError, match="motor\\(s\\) 'm3' never move"
        ):
            select_friction_model(robot, [held], kind=kind)


MOTORS = ["ma", "mb", "mc"]


def with_transmission(tmp_path, matrix, motors):
    """The arm of the ``arm`` fixture with the YAML transmission ``matrix`` (rows: motors)."""
    doc = yaml.safe_load(random_arm_yaml(tmp_path / "arm.yaml", n=3, seed=4).read_text())
    doc["transmissions"] = {"matrix": np.asarray(matrix, float).tolist(), "motors": motors}
    path = tmp_path / "t.yaml"
    path.write_text(yaml.safe_dump(doc))
    return mindyn.load(path)


def motor_stribeck_log(robot, w, fv, fc, fs):
    """A multi-sine log whose torques are the rigid-body ones (the robot's inverse dynamics,
    inertial parameters only) plus each motor's Stribeck friction written out here,
    T^T f(T dq), f with motor velocity scales ``w``."""
    T = robot.drive_matrix
    t = np.arange(0, 8.0, 1 / 200.0)
    q, dq, ddq = multisine(robot.n, t, np.random.default_rng(0))
    v = dq @ T.T
    f = fv * v + fc * sign(v) + fs * sign(v) * np.exp(-((v / w) ** 2))
    return JointData(t, q, dq, ddq, robot.inverse_dynamics(q, dq, ddq) + f @ T, "motors")


@pytest.mark.parametrize(
    "case",
    ["motors declared in another order", "a motor turning with two joints"],
)
def test_the_stribeck_search_pairs_each_motor_with_its_joints(tmp_path, case):
    """The search scores each motor's velocity on the residuals of the joints it acts on. With
    the motors declared in another order than the joints, it scored motor k on joint k's
    residual (another motor's); a motor turning with joints 2 and 3 shares joint 2 with motor 2,
    so the two are searched one after the other on the residuals of both joints. Noise-free,
    the Stribeck velocity of each motor (the coupled one's Fs too) is found to 1e-3 and the
    friction parameters to 1e-5."""
    if case.startswith("motors declared"):
        T = [[0, 0, 30.0], [50.0, 0, 0], [0, -40.0, 0]]
    else:
        T = [[50.0, 0, 0], [0, 40.0, 0], [0, 30.0, 30.0]]
    robot = with_transmission(tmp_path, T, MOTORS)
    assert robot.drive_side == "motor"
    top = np.abs(np.asarray(T)).max(axis=1)
    w = np.array([0.15, 0.25, 0.1]) * top
    fv, fc, fs = FV / top**2, FC / top, np.array([1.0, 0.7, 0.5]) / top
    log = motor_stribeck_log(robot, w, fv, fc, fs)
    choice = select_friction_model(robot, [log], kind="stribeck", fit={"min_velocity": 0.0})
    np.testing.assert_allclose(choice.record["velocity"], w, rtol=1e-3)
    res = identify(choice.robot, log, base=choice.base, rsd_threshold=None, min_velocity=0.0)
    names = list(res.base.names)
    for k in range(3):
        for nm, want in (("Fv", fv), ("Fc", fc), ("Fs", fs)):
            got = res.full[names.index(f"{nm}{k + 1}")]
            assert got == pytest.approx(want[k], rel=1e-5), (nm, k, got, want[k])


def test_a_given_width_below_the_resolved_speed_is_said(arm, tmp_path):
    """A width given per joint to a geared robot is |r| times too small for its motors: below
    the speed at which the data resolve each motor's sign (the width the data give, scaled
    here by hand from the joint side's), which the rule names; a width above it says nothing."""
    log = make_log(arm, "smooth", np.array([0.05, 0.08, 0.03]), FV, FC, 0.0, noise=0.01, seed=5)
    motor = geared(arm, tmp_path, RATIOS)
    joint_w = np.asarray(
        select_friction_model(motor.with_drive_side("joint"), [log], kind="smooth").record[
            "velocity"
        ]
    )
    small = select_friction_model(motor, [log], kind="smooth", width=joint_w).record
    rule = small["velocity_rule"]
    assert rule.startswith("given; below the speed at which the data resolve the sign"), rule
    assert "motor(s) m1, m2, m3" in rule and "|r| times a joint's" in rule, rule
    for v in np.abs(RATIOS) * joint_w:
        assert f"{v:.3g}" in rule, (v, rule)
    ok = select_friction_model(motor, [log], kind="smooth", width=2 * np.abs(RATIOS) * joint_w)
    assert ok.record["velocity_rule"] == "given"
