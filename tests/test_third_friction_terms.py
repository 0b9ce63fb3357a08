"""Which slots have the friction model's third term (``Fa`` of the asymmetric, ``Fs`` of the
Stribeck model): every joint on the joint side; on the motor side only a motor whose row of T has
one non-zero entry, in a column with no other entry (a motor that turns with several joints, or
shares its joint, has none). Identification, ``base_parameters``, ``predict`` and generated code
follow that one rule: on an arm with a differential, one with simple transmissions of large
reductions and one without transmissions, for the asymmetric, smooth and Stribeck models, the
names of identify's JSON, of the base set, of predict's model and of the parameters codegen
takes are the same, and predict's torques and the generated code's equal Pinocchio's rnea plus
the motor terms written out here.
"""

from __future__ import annotations

import json

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import assert_close, cli
from mindyn import codegen
from mindyn.identification import write_csv
from test_codegen import GCC, CFunctions, compile_shared, skewed_urdf
from test_friction_models import multisine
from test_transmissions import pair, simple

KINDS = ("asymmetric", "smooth", "stribeck")


def differential() -> str:
    parts = [simple("t1", "j1", "m1", 20.0)]
    parts.append(pair("DifferentialTransmission", "d", ("j2", "j3"), ("m2", "m3"), (8, 6), (1, 1)))
    return skewed_urdf(np.random.default_rng(31), 3, "diff3", "".join(parts))


def reduction() -> str:
    parts = [simple(f"t{k}", f"j{k}", f"m{k}", r) for k, r in ((1, 50.0), (2, -30.0), (3, 12.0))]
    return skewed_urdf(np.random.default_rng(32), 3, "geared3", "".join(parts))


def direct() -> str:
    return skewed_urdf(np.random.default_rng(33), 3, "direct3")


ARMS = {"differential": differential, "reduction": reduction, "none": direct}


def rows(robot) -> np.ndarray:
    """t_k of each slot: the rows of T on the motor side, e_k on the joints."""
    return robot.transmission.T if robot.drive_side == "motor" else np.eye(robot.n)


def holds_third(robot, k: int) -> bool:
    """The rule, written out: slot k has a third friction term unless it is a motor whose row
    of T has several non-zero entries or whose joint another motor turns too."""
    if robot.drive_side != "motor":
        return True
    T = robot.transmission.T
    cols = np.flatnonzero(T[k])
    return cols.size == 1 and np.count_nonzero(T[:, cols[0]]) == 1


def drive_torque(robot, kind, w, drive, dq, ddq) -> np.ndarray:
    """sum_k t_k (Ia_k a_k + Fv_k v_k + f(v_k)), a_k = t_k . ddq, v_k = t_k . dq, f the friction
    model written out; ``drive`` (n, 4): Ia, Fv, Fc, third per slot. (m, n) for (m, n) rates."""
    tau = np.zeros_like(dq)
    for k, t in enumerate(rows(robot)):
        a, v = ddq @ t, dq @ t
        ia, fv, fc, f3 = drive[k]
        s = np.sign(v)
        if kind == "smooth":
            f = fv * v + fc * np.tanh(v / w[k])
        else:
            f = fv * v + fc * s
            if holds_third(robot, k):
                f = f + f3 * (np.abs(s) if kind == "asymmetric" else s * np.exp(-((v / w[k]) ** 2)))
        tau += np.outer(ia * a + f, t)
    return tau


def rnea(model, q, dq, ddq) -> np.ndarray:
    data = model.createData()
    return np.array([pin.rnea(model, data, a, b, c) for a, b, c in zip(q, dq, ddq)])


def motion(n: int, seconds: float = 6.0, rate: float = 200.0, seed: int = 0):
    t = np.arange(0, seconds, 1 / rate)
    return (t, *multisine(n, t, np.random.default_rng(seed)))


def drive_values(robot) -> np.ndarray:
    """Ia, Fv, Fc, third per slot, in motor units on the motor side (scaled by the slot's
    largest ratio so that every term is of a size the fit resolves)."""
    r = np.abs(rows(robot)).max(axis=1)
    base = np.array([[0.02, 0.3, 0.8, 0.4], [0.03, 0.2, 0.5, -0.3], [0.01, 0.1, 0.3, 0.25]])
    return base / np.column_stack([r * r, r * r, r, r])


@pytest.fixture(scope="module", params=sorted(ARMS))
def case(request, tmp_path_factory):
    folder = tmp_path_factory.mktemp(request.param)
    path = folder / f"{request.param}.urdf"
    path.write_text(ARMS[request.param]())
    return request.param, path, mindyn.load(path), pin.buildModelFromUrdf(str(path))


def test_the_rule_is_the_one_written_here(case):
    name, _, robot, _ = case
    base = mindyn.base_parameters(
        robot.with_friction_model("stribeck", velocity=np.full(3, 0.05)), rotor=True, friction=True
    )
    have = [k for k in range(3) if f"Fs{k + 1}" in base.names]
    assert have == [k for k in range(3) if holds_third(robot, k)]
    assert have == ([0] if name == "differential" else [0, 1, 2])


@pytest.mark.parametrize("factor", [1e-3, 1e2])
@pytest.mark.parametrize("kind", ["stribeck", "smooth"])
def test_the_numerical_method_follows_the_rule_at_any_velocity_scale(case, kind, factor):
    """The numerical method samples the regressor: a Stribeck velocity far below the sampled
    speeds made the Stribeck column vanish (Fs dropped), one far above it made it Coulomb's (Fs
    regrouped with Fc), and a smooth width far above them made tanh(v / w) v / w. Its base set
    has the names of the default method's, Fs where the rule says, at widths 1e-3 and 1e2 times
    the slots' largest speed, and its regressor reproduces Pinocchio's rnea plus the motor terms
    written out here with those widths."""
    name, _, robot, model = case
    n = robot.n
    t, q, dq, ddq = motion(n)
    w = factor * np.abs(dq @ rows(robot).T).max(axis=0)
    r = robot.with_friction_model(kind, velocity=w)
    default = mindyn.base_parameters(r, rotor=True, friction=True)
    numerical = mindyn.base_parameters(r, rotor=True, friction=True, method="numerical")
    assert list(numerical.names) == list(default.names)
    third = [x for x in numerical.names if x.startswith("Fs")]
    expect = [f"Fs{k + 1}" for k in range(n) if holds_third(robot, k)] if kind == "stribeck" else []
    assert third == expect
    for k in range(n):  # every slot's viscous and scaled column is its own base parameter
        assert {f"Fv{k + 1}", f"Fc{k + 1}"} <= set(numerical.names)
    drive = drive_values(robot)
    pi = np.concatenate(
        [
            np.concatenate([robot.params[10 * k : 10 * k + 10], drive[k, : 3 + (kind != "smooth")]])
            for k in range(n)
        ]  # fmt: skip
    )
    i = np.random.default_rng(6).choice(t.size, 40, replace=False)
    got = numerical.regressor(q[i], dq[i], ddq[i]) @ numerical.values(pi)
    ref = rnea(model, q[i], dq[i], ddq[i]) + drive_torque(robot, kind, w, drive, dq[i], ddq[i])
    assert_close(got, ref, 1e-9, f"numerical base regressor vs rnea + motor terms ({name})")


@pytest.mark.parametrize("kind", KINDS)
def test_identify_base_parameters_predict_and_codegen_agree(case, kind, tmp_path):
    name, path, robot, model = case
    n = robot.n
    t, q, dq, ddq = motion(n)
    slot_speed = np.abs(dq @ rows(robot).T).max(axis=0)
    w = 0.2 * slot_speed
    drive = drive_values(robot)
    tau = rnea(model, q, dq, ddq) + drive_torque(robot, kind, w, drive, dq, ddq)
    csv = tmp_path / "log.csv"
    write_csv(csv, t, q, tau, dq, ddq)
    doc_path = tmp_path / "id.json"
    cli("identify", path, csv, "--rotor", "--friction-model", kind, "--filter", "none",
        "--min-velocity", "0", "--json", doc_path)  # fmt: skip
    doc = json.loads(doc_path.read_text())
    names = doc["base_names"]
    # base_parameters of the robot with the identified friction model
    velocity = doc["friction_model"]["velocity"]
    identified = robot.with_friction_model(kind, velocity=velocity)
    base = mindyn.base_parameters(identified, rotor=True, friction=True)
    assert list(base.names) == names
    third = "Fa" if kind == "asymmetric" else "Fs"
    expect = [f"{third}{k + 1}" for k in range(n) if holds_third(robot, k)]
    assert [x for x in names if x[:2] == third] == (expect if kind != "smooth" else [])
    # predict's model
    from mindyn.identification.prediction import identified_model

    assert list(identified_model(doc_path, robot)[0].names) == names
    # a known classical vector in the identified base set, all kept: predict and codegen
    rng = np.random.default_rng(5)
    inertial = robot.params.copy()
    pi = np.concatenate(
        [
            np.concatenate([inertial[10 * k : 10 * k + 10], drive[k, : 3 + (kind != "smooth")]])
            for k in range(n)
        ]  # fmt: skip
    )
    assert len(pi) == len(identified.parameter_names(rotor=True, friction=True))
    values = base.values(pi)
    known = dict(doc, names=names, values=list(map(float, values)), removed=[],
                 base_values=list(map(float, values)))  # fmt: skip
    known.pop("consistent_estimate", None)
    known_path = tmp_path / "known.json"
    known_path.write_text(json.dumps(known))
    w_id = np.asarray(velocity, float) if velocity else None
    cli("predict", path, known_path, csv, "--filter", "none", "-o", tmp_path / "pred.csv")
    pred = np.genfromtxt(tmp_path / "pred.csv", delimiter=",", names=True)
    qs, dqs, ddqs = (
        np.column_stack([pred[f"{x}{k + 1}"] for k in range(n)]) for x in ("q", "dq", "ddq")
    )
    tau_hat = np.column_stack([pred[f"tau_hat{k + 1}"] for k in range(n)])
    ref = rnea(model, qs, dqs, ddqs) + drive_torque(robot, kind, w_id, drive, dqs, ddqs)
    assert_close(tau_hat, ref, 1e-9, f"predict vs rnea + motor terms ({name}, {kind})")
    # codegen takes the identified JSON (its names) on the command line ...
    cli("codegen", path, "--rotor", "--friction", "--params", doc_path, "--lang", "c",
        "-o", tmp_path / "gen" / "cmd")  # fmt: skip
    # ... and the known values: the generated C against the same reference
    taken, pruned, _ = codegen.read_identified_parameters(
        known_path, base.names, robot=identified, rotor=True, friction=True
    )
    assert pruned == []
    if GCC is None:
        return
    code = codegen.generate(identified, base=base, name="agree", what="id")
    source = code.write(tmp_path / "agree.c")[1]
    c = CFunctions(compile_shared(source, tmp_path / "libagree.so"), code, n)
    for i in rng.choice(t.size, 5, replace=False):
        got = c.id(qs[i], dqs[i], ddqs[i], taken)
        assert_close(got, ref[i], 1e-9, f"generated C vs rnea + motor terms ({name}, {kind})")


def test_a_third_term_given_for_a_motor_that_turns_with_several_joints_acts_nowhere(case):
    """The dynamics and the friction columns follow the rule: a third term given for such a
    motor in a classical vector changes no torque."""
    name, _, robot, _ = case
    if name != "differential":
        pytest.skip("the other arms have no such motor")
    r = robot.with_friction_model("stribeck", velocity=np.full(3, 0.5))
    p = r.parameters(rotor=True, friction=True)
    per = len(p) // 3
    dq = np.array([[0.1, 0.2, -0.15]])
    q, ddq = np.zeros((1, 3)), np.zeros((1, 3))
    before = r.inverse_dynamics(q, dq, ddq, p)
    p[per + 13] = p[2 * per + 13] = 5.0  # Fs2, Fs3: motors of the differential
    assert_close(r.inverse_dynamics(q, dq, ddq, p), before, 1e-15, "Fs of coupled motors")
    assert r.friction_shapes(dq @ r.drive_matrix.T)[0, 1:, 2].tolist() == [0.0, 0.0]
