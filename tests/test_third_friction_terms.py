"""The friction model's third term (``Fa`` of the asymmetric, ``Fs`` of the Stribeck model) of
every slot: every joint on the joint side, every motor on the motor side, a motor that turns with
several joints (a differential's) too, at its own velocity ``t_k . dq`` through its row of T.
Identification, ``base_parameters``, ``predict`` and generated code agree: on an arm with a
differential, one with simple transmissions of large reductions and one without transmissions,
for the asymmetric, smooth and Stribeck models, the names of identify's JSON, of the base set, of
predict's model and of the parameters codegen takes are the same, and predict's torques and the
generated code's equal Pinocchio's rnea plus the motor terms written out here.
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


@pytest.mark.parametrize("method", ["projection", "numerical", "recursive"])
def test_every_slot_has_its_third_term_by_every_method(case, method):
    """Fs of each slot, the differential's two motors too, is a base parameter of its own
    (without rotor inertia: the recursive method cannot decide how a differential's rotors
    regroup, and says so)."""
    _, _, robot, _ = case
    base = mindyn.base_parameters(
        robot.with_friction_model("stribeck", velocity=np.full(3, 0.05)),
        rotor=False,
        friction=True,
        method=method,
    )
    assert [x for x in base.names if x.startswith("Fs")] == ["Fs1", "Fs2", "Fs3"]


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
    expect = [f"Fs{k + 1}" for k in range(n)] if kind == "stribeck" else []
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
    expect = [f"{third}{k + 1}" for k in range(n)]
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


@pytest.mark.parametrize("kind", ["asymmetric", "stribeck"])
def test_a_coupled_motors_third_term_acts_through_its_row(tmp_path, kind):
    """A third term of a differential's motor, given as the motor's own (with_joint_terms, as a
    joint-terms file gives it), is in parameters() and acts as t_k^T Fa_k |sign(v_k)| or
    t_k^T Fs_k sign(v_k) exp(-(v_k / w_k)^2), v_k = t_k . dq, written out here; a directly
    driven motor's value reaches its joint as r Fa or |r| Fs (robot.third_friction)."""
    path = tmp_path / "differential.urdf"
    path.write_text(differential())
    robot = mindyn.load(path)
    w = np.array([0.3, 0.5, 0.4])
    r = robot.with_friction_model(kind, velocity=w if kind == "stribeck" else None)
    third = np.array([0.2, -0.15, 0.1])
    got = r.with_joint_terms(third=third)
    p = got.parameters(rotor=True, friction=True)
    per = len(p) // 3
    np.testing.assert_array_equal(p[13::per], third)
    T = robot.transmission.T
    np.testing.assert_allclose(
        got.third_friction[0], third[0] * (T[0, 0] if kind == "asymmetric" else abs(T[0, 0]))
    )
    rng = np.random.default_rng(7)
    q, dq, ddq = rng.uniform(-1, 1, (3, 6, 3))
    dq[0] = [0.125, 0.25, 0.25]  # motor 3 of the differential at rest: v_3 = 0 exactly
    zero = p.copy()
    zero[13::per] = 0.0
    diff = got.inverse_dynamics(q, dq, ddq, p) - got.inverse_dynamics(q, dq, ddq, zero)
    v = dq @ T.T
    s = np.sign(v)
    shape = np.abs(s) if kind == "asymmetric" else s * np.exp(-((v / w) ** 2))
    want = (shape * third) @ T
    assert np.count_nonzero(v[0] == 0.0) == 1  # the state at rest is one
    assert_close(diff, want, 1e-12, f"third terms through T ({kind})")
