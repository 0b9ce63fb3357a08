"""Inputs a library user gets wrong, refused with one line naming the argument, and objects that
do not change under their users: controller steps given wrongly shaped or non-finite states, a
drive gain of zero, time stamps that are not increasing, unknown keywords, modules the manual
names, the base parameters' records and an identification's arrays and names."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import mindyn
import numpy as np
import pytest
from mindyn import control
from mindyn.identification import (
    DataError,
    JointData,
    ReadingOptions,
    identify,
    identify_consistent,
    load_logs,
    read_csv,
    write_csv,
)

ROBOT = mindyn.load("planar2")
BASE = mindyn.base_parameters(ROBOT)
DOCS = Path(__file__).resolve().parents[1] / "docs"


def _motion(m: int = 400, dt: float = 0.01):
    """Two joints on sines: t, q and its exact derivatives."""
    t = np.arange(m) * dt
    w = np.array([1.0, 1.7])
    q = np.sin(np.outer(t, w))
    dq = w * np.cos(np.outer(t, w))
    ddq = -(w**2) * np.sin(np.outer(t, w))
    return t, q, dq, ddq


# ---------------------------------------------------------------------------------------------
# 1. controller steps
# ---------------------------------------------------------------------------------------------
def _controllers():
    p = np.zeros(BASE.n)
    return [
        control.PD(2, [3.0, 5.0], [0.5, 0.25]),
        control.AdaptivePD(BASE, 2.0, 3.0, 0.1, p),
        control.ComputedTorque(BASE, p, 4.0, 2.0),
    ]


STATE = dict(q=[0.1, 0.2], dq=[0.3, -0.4], q_d=[0.0, 0.5], dq_d=[0.1, 0.1], ddq_d=[0.0, 0.0])


@pytest.mark.parametrize("ctl", _controllers(), ids=lambda c: c.name)
@pytest.mark.parametrize("name", list(STATE))
def test_a_controller_step_names_a_wrongly_shaped_or_non_finite_input(ctl, name):
    """A wrongly shaped array was a numpy broadcast error (or, of size 1, broadcast silently),
    a NaN reference came out as a NaN torque or an error naming an intermediate (dqr)."""
    for bad, message in (
        ([0.0, 0.0, 0.0], rf"^{name} has shape \(3,\); expected \(2,\)$"),
        ([1.0], rf"^{name} has shape \(1,\); expected \(2,\)$"),
        ([0.0, np.nan], rf"^{name} contains NaN at joint 2; expected finite values$"),
    ):
        state = {k: np.array(v) for k, v in STATE.items()}
        with pytest.raises(mindyn.ArgumentError, match=message):
            ctl(0.0, **{**state, name: np.array(bad)})


def test_a_controller_step_on_good_inputs_is_its_law():
    """The PD's torque is -K_P e - K_D de (closed form); lists are taken as arrays; the adaptive
    controller's terms follow its sign convention."""
    pd = control.PD(2, [3.0, 5.0], [0.5, 0.25])
    s = {k: np.array(v) for k, v in STATE.items()}
    expected = -np.array([3.0, 5.0]) * (s["q"] - s["q_d"]) - np.array([0.5, 0.25]) * (
        s["dq"] - s["dq_d"]
    )
    np.testing.assert_allclose(pd(0.0, **STATE), expected, rtol=0, atol=1e-15)
    adaptive = control.AdaptivePD(BASE, 2.0, 3.0, 0.1, np.zeros(BASE.n))
    e, sv, dqr, ddqr = adaptive.terms(STATE["q"], STATE["dq"], (s["q_d"], s["dq_d"], s["ddq_d"]))
    np.testing.assert_allclose(e, s["q"] - s["q_d"])
    np.testing.assert_allclose(sv, s["dq"] - s["dq_d"] + 3.0 * e)
    np.testing.assert_allclose(dqr, s["dq_d"] - 3.0 * e)
    np.testing.assert_allclose(ddqr, s["ddq_d"] - 3.0 * (s["dq"] - s["dq_d"]))
    with pytest.raises(mindyn.ArgumentError, match=r"^dq_d has shape \(3,\); expected \(2,\)$"):
        adaptive.terms(s["q"], s["dq"], (s["q_d"], np.zeros(3), s["ddq_d"]))
    with pytest.raises(mindyn.ArgumentError, match=r"^ref must be the three arrays"):
        adaptive.terms(s["q"], s["dq"], s["q_d"])


# ---------------------------------------------------------------------------------------------
# 2. drive gains
# ---------------------------------------------------------------------------------------------
def test_a_zero_or_non_finite_drive_gain_is_refused_whatever_the_log_holds(tmp_path):
    """The manual: a zero gain is refused. With a log of torques, read_csv took drive_gain=[0, 0]
    without a word."""
    t, q, dq, ddq = _motion()
    path = write_csv(tmp_path / "log.csv", t, q, ROBOT.inverse_dynamics(q, dq, ddq), dq=dq)
    for gain, named in (
        ([0.0, 0.0], "joint 1 = 0, joint 2 = 0"),
        ([2.0, np.nan], "joint 2 = nan"),
        ([np.inf, 1.0], "joint 1 = inf"),
    ):
        message = rf"^drive_gain=: the gains given are zero or not finite for {named} \("
        with pytest.raises(mindyn.ArgumentError, match=message):
            read_csv(path, ROBOT, drive_gain=gain)
        with pytest.raises(mindyn.ArgumentError, match=message):
            ReadingOptions(drive_gain=gain)
    # currents through a gain given: tau = K i (the gains kept, a negative one too)
    gain = np.array([2.0, -0.5])
    tau = ROBOT.inverse_dynamics(q, dq, ddq)
    amps = write_csv(tmp_path / "i.csv", t, q, tau / gain, dq=dq, torque_unit="current")
    d = read_csv(amps, ROBOT, drive_gain=gain, filter="none")
    np.testing.assert_allclose(d.tau, tau, rtol=1e-9, atol=1e-9)
    with pytest.raises(mindyn.ArgumentError, match=r"for joint 2 = 0 \("):
        read_csv(amps, ROBOT, drive_gain=[2.0, 0.0], filter="none")


def test_a_drive_gain_for_a_log_of_torques_is_refused_not_ignored(tmp_path):
    """read_csv took drive_gain=[2, 3] for a log of torques in N m and ignored it: the torques
    came out as logged, the gain given unused without a word. The command line says the same."""
    t, q, dq, ddq = _motion()
    tau = ROBOT.inverse_dynamics(q, dq, ddq)
    path = write_csv(tmp_path / "log.csv", t, q, tau, dq=dq)
    message = (
        f"drive_gain=: {path} holds torques in N m, not motor currents, which the gains convert "
        "into torques; expected torque_unit='current' or columns i1..in, or no drive_gain="
    )
    with pytest.raises(DataError) as e:
        read_csv(path, ROBOT, drive_gain=[2.0, 3.0], filter="none")
    assert str(e.value) == message
    # without the gain the log is read as written: the description's torques
    np.testing.assert_allclose(read_csv(path, ROBOT, filter="none").tau, tau, atol=1e-9)
    # the same log of currents (tau / K) with the gain: the gain is used, tau = K i
    gain = np.array([2.0, 3.0])
    amps = write_csv(tmp_path / "i.csv", t, q, tau / gain, dq=dq, torque_unit="current")
    np.testing.assert_allclose(
        read_csv(amps, ROBOT, drive_gain=gain, filter="none").tau, tau, rtol=1e-9, atol=1e-9
    )
    cli = subprocess.run(
        [sys.executable, "-m", "mindyn", "identify", "planar2", str(path), "--drive-gain", "2,3"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert cli.returncode == 2 and cli.stdout == "", cli.stdout
    assert cli.stderr == (
        f"mindyn: error: --drive-gain: {path} holds torques in N m, not motor currents, which "
        "the gains convert into torques; expected --torque-unit current or columns i1..in, or "
        "no --drive-gain\n"
    )


# ---------------------------------------------------------------------------------------------
# 3. time stamps written
# ---------------------------------------------------------------------------------------------
def test_write_csv_refuses_time_stamps_that_are_not_strictly_increasing(tmp_path):
    """write_csv wrote any time stamps, and read_csv refused the log it made."""
    q = np.zeros((4, 1))
    for t, message in (
        ([0.0, 0.1, 0.1, 0.2], r"^t is not strictly increasing: t\[2\] = 0\.1 is not later than "),
        ([0.0, 0.2, 0.1, 0.3], r"^t is not strictly increasing: t\[2\] = 0\.1 is not later than "),
        # distinct doubles, alike in the 12 digits written
        (
            [1e6, 1e6 + 1e-7, 1e6 + 1.0, 1e6 + 2.0],
            r"^t is not strictly increasing as written .*t\[1\]",
        ),
    ):
        path = tmp_path / "t.csv"
        with pytest.raises(mindyn.ArgumentError, match=message):
            write_csv(path, np.array(t), q, None)
        assert not path.exists()
    t = 1e6 + 1e-4 * np.arange(4)  # differing in the last digits written: read back as given
    path = write_csv(tmp_path / "ok.csv", t, q, None)
    np.testing.assert_allclose(read_csv(path, n=1, require_torque=False, filter="none").t, t)


# ---------------------------------------------------------------------------------------------
# 4. unknown keywords
# ---------------------------------------------------------------------------------------------
def test_unknown_keywords_name_the_function_called_and_the_accepted_ones(tmp_path):
    """load_logs(bogus=1) said ReadingOptions.__init__(), identify_consistent(bogus=1) said
    identify()."""
    t, q, dq, ddq = _motion()
    path = write_csv(tmp_path / "log.csv", t, q, ROBOT.inverse_dynamics(q, dq, ddq), dq=dq)
    with pytest.raises(mindyn.ArgumentError) as e:
        load_logs([path], ROBOT, bogus=1)
    text = str(e.value)
    assert text.startswith("load_logs: unknown option(s) bogus; expected some of "), text
    accepted = text.split("expected some of ")[1].split(", ")
    assert {"drive_gain", "cutoff", "validate", "currents", "model"} <= set(accepted)
    with pytest.raises(mindyn.ArgumentError) as e:
        identify_consistent(ROBOT, [], bogus=1, frction=True)
    text = str(e.value)
    assert text.startswith("identify_consistent: unknown option(s) bogus, frction; expected "), text
    accepted = text.split("expected some of ")[1].split(", ")
    assert {"prior_weight", "friction", "rotor", "model"} <= set(accepted)
    assert "\n" not in text


# ---------------------------------------------------------------------------------------------
# 5. modules the manual names
# ---------------------------------------------------------------------------------------------
def _dotted_names() -> list[str]:
    """Every ``mindyn.a.b...`` the manual writes (not a file name such as ``api/mindyn.md``)."""
    names: set[str] = set()
    for page in DOCS.rglob("*.md"):
        names |= set(re.findall(r"(?<![\w/.-])mindyn(?:\.\w+)+", page.read_text("utf-8")))
    return sorted(n for n in names if not n.endswith(".md"))


def test_every_name_the_manual_writes_is_an_attribute_after_import():
    """``from mindyn import identification as ident; ident.excitation`` was an AttributeError.
    Checked in a fresh interpreter (here, other tests have imported the modules already)."""
    names = _dotted_names()
    assert "mindyn.identification.excitation" in names and len(names) > 30
    code = (
        "import sys, mindyn\n"
        "from mindyn import identification as ident\n"
        "ident.excitation\n"
        "bad = []\n"
        f"for name in {names!r}:\n"
        "    obj = mindyn\n"
        "    try:\n"
        "        for part in name.split('.')[1:]:\n"
        "            obj = getattr(obj, part)\n"
        "    except AttributeError:\n"
        "        bad.append(name)\n"
        "print(bad)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]", out.stdout
    with pytest.raises(AttributeError, match="has no attribute 'no_such_module'"):
        mindyn.identification.no_such_module  # noqa: B018


# ---------------------------------------------------------------------------------------------
# 6. the base parameters' records
# ---------------------------------------------------------------------------------------------
def test_the_snap_decision_and_options_do_not_change_under_their_users():
    """snap_decision and options were plain dicts, and with_friction_velocity shared the same
    snap_decision dict with the new object."""
    robot = mindyn.load("zcr07s")
    smooth = mindyn.base_parameters(
        robot.with_friction_model("smooth", velocity=[0.1] * robot.n), friction=True
    )
    other = smooth.with_friction_velocity([0.2] * robot.n)
    before = json.loads(json.dumps(smooth.to_dict()["snap"]))
    for base in (smooth, other):
        with pytest.raises(TypeError):
            base.snap_decision["applied"] = "changed"  # type: ignore[index]
        with pytest.raises(TypeError):
            base.options["tolerance"] = 1.0  # type: ignore[index]
        with pytest.raises(AttributeError):
            base.snap_decision = {}  # type: ignore[misc]
        for value in base.snap_decision.values():
            assert not isinstance(value, (list, dict)), value
    assert other.snap_decision == smooth.snap_decision
    assert smooth.options["tolerance"] == 1e-9 and smooth.options["snap"] == "auto"
    # the JSON writers still take them, as before: plain values
    assert json.loads(json.dumps(smooth.to_dict()["snap"])) == before
    assert before["mode"] == "auto" and isinstance(before["rounded"], list)
    assert smooth.for_robot(robot).options == smooth.options


# ---------------------------------------------------------------------------------------------
# 7. an identification's arrays
# ---------------------------------------------------------------------------------------------
def test_an_identification_result_keeps_its_arrays():
    """values and std were writable: an edit changed the result under its users."""
    t, q, dq, ddq = _motion(2000)
    tau = ROBOT.inverse_dynamics(q, dq, ddq)
    rng = np.random.default_rng(3)
    data = JointData(t=t, q=q, dq=dq, ddq=ddq, tau=tau + 1e-3 * rng.standard_normal(tau.shape))
    res = identify(ROBOT, data)
    predicted = res.predict(data)
    np.testing.assert_allclose(predicted, tau, atol=5e-3)  # the data's own torques
    for name in ("values", "std", "rsd", "full", "joint_sigma"):
        a = getattr(res, name)
        with pytest.raises(ValueError, match="read-only"):
            a[0] = 1.0
    for a in res.initial.values():
        if isinstance(a, np.ndarray):
            with pytest.raises(ValueError, match="read-only"):
                a[0] = 1.0
    np.testing.assert_array_equal(res.predict(data), predicted)


def test_an_identification_result_keeps_its_kept_and_removed_names():
    """names and removed were lists: an edit (append, sort, an entry assigned) changed the
    result, and the JSON it writes, under its other users."""
    t, q, dq, ddq = _motion(2000)
    tau = ROBOT.inverse_dynamics(q, dq, ddq)
    rng = np.random.default_rng(3)
    data = JointData(t=t, q=q, dq=dq, ddq=ddq, tau=tau + 0.05 * rng.standard_normal(tau.shape))
    res = identify(ROBOT, data)
    # the description's first moments MY1, MY2 are zero: those estimates are noise, pruned
    truth = dict(zip(BASE.names, BASE.values(ROBOT.parameters())))
    zero = {name for name, v in truth.items() if abs(v) < 1e-12}
    assert zero == {"MY1", "MY2"}
    assert {name for name, _ in res.removed} == zero
    assert set(res.names) == set(BASE.names) - zero
    before = json.dumps(res.to_dict(), sort_keys=True, default=str)
    assert isinstance(res.names, tuple) and isinstance(res.removed, tuple)
    with pytest.raises(AttributeError):
        res.names.append("XX9")  # type: ignore[attr-defined]
    with pytest.raises(TypeError):
        res.names[0] = "XX9"  # type: ignore[index]
    with pytest.raises(AttributeError):
        res.removed.sort()  # type: ignore[attr-defined]
    with pytest.raises(TypeError):
        res.removed[0][1] = 0.0  # type: ignore[index]
    # the JSON as before: lists of the names, and of {name, rsd} in order of removal
    doc = json.loads(before)
    assert doc["names"] == list(res.names) and all(isinstance(n, str) for n in doc["names"])
    assert doc["removed"] == [{"name": n, "rsd": r} for n, r in res.removed]
    assert json.dumps(res.to_dict(), sort_keys=True, default=str) == before
    # the pruned estimate's full vector is zero exactly at the removed parameters
    assert [name for name, v in zip(BASE.names, res.full) if v == 0] == [
        name for name in BASE.names if name in zero
    ]


def test_a_consistent_estimate_keeps_its_arrays_links_and_notes():
    """classical, full and the eigenvalues were writable arrays, links and notes lists: an edit
    changed the estimate (its predictions, its JSON) under its other users."""
    t, q, dq, ddq = _motion(2000)
    tau = ROBOT.inverse_dynamics(q, dq, ddq)
    rng = np.random.default_rng(3)
    data = JointData(t=t, q=q, dq=dq, ddq=ddq, tau=tau + 1e-3 * rng.standard_normal(tau.shape))
    c = identify_consistent(ROBOT, data, prior_weight=1.0)  # a prior: the per-link records
    predicted = c.predict(data)
    np.testing.assert_allclose(predicted, tau, atol=5e-3)  # the data's own torques
    before = json.dumps(c.to_dict(), sort_keys=True, default=str)
    for name in ("classical", "full", "min_eig", "unconstrained_min_eig"):
        with pytest.raises(ValueError, match="read-only"):
            getattr(c, name)[0] = 1.0
    assert c.links is not None and c.notes  # the description's pseudo-inertias regularised
    assert isinstance(c.links, tuple) and isinstance(c.notes, tuple)
    with pytest.raises(TypeError):
        c.links[0]["mass"] = 100.0  # type: ignore[index]
    with pytest.raises(AttributeError):
        c.notes.append("edited")  # type: ignore[attr-defined]
    np.testing.assert_array_equal(c.predict(data), predicted)
    assert json.dumps(c.to_dict(), sort_keys=True, default=str) == before
    # the JSON as before: lists of plain dicts and of lines
    doc = json.loads(before)["consistent_estimate"]
    assert [lk["link"] for lk in doc["links"]] == list(ROBOT.link_names[1:])
    assert doc["notes"] == list(c.notes)


def test_code_is_not_generated_from_the_base_parameters_of_another_robot():
    """``base=`` of another robot with as many joints (the Stanford arm's for the PUMA 560)
    gave code of the PUMA's name and geometry with the Stanford arm's base set and values
    projected through its regrouping: silently wrong torques. It is refused naming ``base``,
    both robots and what differs; the same description loaded again, or with another friction
    model, is the same robot and is taken (its code equals the PUMA's own inverse dynamics)."""
    from mindyn import codegen

    puma = mindyn.load("puma560")
    stanford = mindyn.base_parameters("stanford", rotor=True, friction=True)
    expected = r"base is of robot 'stanford', whose joint 1 .* expected base parameters of robot"
    for generate in (codegen.generate, codegen.generate_controller, codegen.generate_observer):
        with pytest.raises(mindyn.ArgumentError, match=expected + " 'puma560'"):
            generate(puma, base=stanford)
    flat = mindyn.base_parameters(puma.with_gravity([0.0, 0.0, 0.0]))
    with pytest.raises(mindyn.ArgumentError, match="gravity"):
        codegen.generate(puma, base=flat)
    again = mindyn.base_parameters(mindyn.load("puma560"))
    code = codegen.generate(puma, base=again, what="id")
    assert code.names == again.names
    rng = np.random.default_rng(0)
    q, dq, ddq = rng.uniform(-1, 1, (3, 6))
    np.testing.assert_allclose(
        again.regressor(q, dq, ddq) @ code.values,
        puma.inverse_dynamics(q, dq, ddq),
        rtol=1e-12,
        atol=1e-12,
    )


def test_simulate_names_bad_noise_a_bad_controller_torque_and_parameters_of_no_body():
    """Three inputs of ``simulate`` that reached numpy or the plant as a bare ValueError (not a
    mindyn.Error): a noise level given as text or None, a controller returning text, and true
    parameters whose mass matrix is not positive definite (the PUMA's negated: -M(q))."""
    ref = control.SumOfSines(ROBOT, period=1.0)
    for value, given in (("a", "a str 'a'"), (None, "None")):
        with pytest.raises(mindyn.ArgumentError, match=f"torque noise is {given}; expected"):
            control.simulate(ROBOT, ref, duration=0.1, noise=control.SensorNoise(torque=value))
    with pytest.raises(mindyn.ArgumentError, match=r"controller returned a str 'x' at t = 0 s"):
        control.simulate(ROBOT, ref, lambda *a: "x", duration=0.1)
    puma = mindyn.load("puma560")
    q0 = np.zeros(6)
    assert np.linalg.eigvalsh(puma.mass_matrix(q0, -puma.params)).max() < 0  # -M(q)
    with pytest.raises(mindyn.ArgumentError, match="params: the simulated robot's mass matrix"):
        control.simulate(puma, control.SumOfSines(puma), duration=0.1, params=-puma.params)
    # good values still run: a noise-free log equals its truth
    res = control.simulate(ROBOT, ref, duration=0.1, noise=control.SensorNoise(torque=[0, 0]))
    np.testing.assert_array_equal(res.tau, res.tau_true)


def test_the_plant_refuses_a_mass_matrix_not_positive_definite_as_a_model_error():
    """The simulation plant's forward dynamics raised numpy's bare ValueError for parameters
    whose mass matrix is not positive definite, where the other forward dynamics raise
    ModelError (a mindyn.Error)."""
    from mindyn import _core

    puma = mindyn.load("puma560")
    q0 = np.zeros(6)
    plant = _core.Integrator(puma._m, -np.asarray(puma.params), 0.0)
    with pytest.raises(mindyn.ModelError, match="mass matrix is not positive definite"):
        plant.acceleration(q0, q0, q0)
    ddq = _core.Integrator(puma._m, np.asarray(puma.params), 0.0).acceleration(q0, q0, q0)
    np.testing.assert_allclose(  # gravity alone: M ddq = -g
        puma.mass_matrix(q0) @ ddq, -puma.inverse_dynamics(q0, q0, q0), atol=1e-9
    )
