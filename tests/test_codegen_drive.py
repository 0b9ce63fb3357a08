"""Generated code with rotor inertia and friction on the motors of coupled transmissions, and with
each friction model, against a computation written out here.

The reference is independent of mindyn's dynamics: Pinocchio's rnea, joint-torque regressor,
mass matrix, Coriolis matrix and gravity (classical Newton-Euler) for the links, plus the drive
terms by their definition, sum_k t_k (Ia_k t_k . ddq + f(t_k . dq)), t_k row k of T (e_k on the
joints) and f the friction model's formula. Two arms: a 6R whose wrist is a four-bar linkage
(motor 6 turns with q5 + q6) and a WAM-like 7R with differentials on joints 2-3 and 5-6, both
with random geometry and links. Base-parameter code is compared column by column with the
classical regressor at the base set's pivots (W_b = W[:, pivots], tau = W[:, pivots] p for any
p), which holds whatever the regrouping values; the classical-parameter code covers the friction
models with a third column.
"""

from __future__ import annotations

import json
import re

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import assert_close
from mindyn import codegen
from mindyn.cli import main
from test_codegen import (
    GCC,
    CFunctions,
    STInterpreter,
    compile_c,
    compile_shared,
    skewed_urdf,
    st_tree,
)
from test_codegen_controller import STBlock, strict_compile
from test_transmissions import pair, simple

pytestmark = pytest.mark.skipif(GCC is None, reason="gcc is needed to compile generated C")
KINDS = ("coulomb", "asymmetric", "smooth", "stribeck")
# Pinocchio's order of a link's ten parameters from mindyn's: pin = TO_PIN @ mindyn
TO_PIN = np.column_stack([mindyn.to_pinocchio_order(e) for e in np.eye(10)])


def coupled6r() -> str:
    """Simple transmissions on joints 1-4, a four-bar linkage on the wrist (joints 5, 6)."""
    parts = [simple(f"t{k}", f"j{k}", f"m{k}", r) for k, r in zip(range(1, 5), (100, -120, 80, 60))]
    parts.append(
        pair(
            "FourBarLinkageTransmission", "wrist", ("j5", "j6"), ("m5", "m6"), (50, 40), (1.2, 0.9)
        )
    )
    return skewed_urdf(np.random.default_rng(56), 6, "coupled6r", "".join(parts))


def wam7r() -> str:
    diff = "DifferentialTransmission"
    parts = [
        simple("t1", "j1", "m1", 42.0),
        pair(diff, "shoulder", ("j2", "j3"), ("m2", "m3"), (30.0, -30.0), (1.0, 1.5)),
        simple("t4", "j4", "m4", 18.0),
        pair(diff, "wrist", ("j5", "j6"), ("m5", "m6"), (20.0, 20.0), (0.8, 1.0)),
        simple("t7", "j7", "m7", 10.0),
    ]
    return skewed_urdf(np.random.default_rng(77), 7, "wam7r", "".join(parts))


def differential3r() -> str:
    """A small arm for the Structured Text controller loop: a differential on joints 2-3."""
    parts = [simple("t1", "j1", "m1", 20.0)]
    parts.append(pair("DifferentialTransmission", "d", ("j2", "j3"), ("m2", "m3"), (8, 6), (1, 1)))
    return skewed_urdf(np.random.default_rng(33), 3, "diff3r", "".join(parts))


ARMS = {"coupled6r": coupled6r, "wam7r": wam7r, "diff3r": differential3r}


@pytest.fixture(scope="module")
def arms(tmp_path_factory):
    folder = tmp_path_factory.mktemp("drive")
    out = {}
    for name, text in ARMS.items():
        path = folder / f"{name}.urdf"
        path.write_text(text())
        out[name] = (mindyn.load(path), pin.buildModelFromUrdf(str(path)), path)
    return out


def arm(arms, name: str, kind: str, side: str = "motor"):
    """The arm with a friction model (velocity scales half each row's 1-norm of T: motor
    velocities t_k . dq of a few scales either side of them) on the given side."""
    robot, model, _ = arms[name]
    w = 0.5 * np.abs(robot.transmission.T).sum(axis=1)
    robot = robot.with_friction_model(kind, velocity=w if kind in ("smooth", "stribeck") else None)
    return robot.with_drive_side(side), model


def compiled(code, folder, n: int) -> CFunctions:
    """The generated C compiled without optimisation (the classical regressors are long; the
    base-parameter code compiles with -O1), warnings as errors."""
    source = code.write(folder / f"{code.name}.c")[1]
    return CFunctions(compile_shared(source, folder / f"lib{code.name}.so", "-O0"), code, n)


def rows(robot) -> np.ndarray:
    """t_k of each slot: the rows of T on the motors, e_k on the joints."""
    return robot.transmission.T if robot.drive_side == "motor" else np.eye(robot.n)


def friction_shapes(kind: str, v: float, w: float | None) -> list[float]:
    """The friction model's columns (Fv, Fc[, Fa | Fs]) at a slot velocity v."""
    s = float(np.sign(v))
    if kind == "coulomb":
        return [v, s]
    if kind == "asymmetric":
        return [v, s, abs(s)]
    if kind == "smooth":
        return [v, float(np.tanh(v / w))]
    return [v, s, s * float(np.exp(-((v / w) ** 2)))]


def drive_torque(robot, pi, dq, acc) -> np.ndarray:
    """sum_k t_k (Ia_k t_k . acc + Fv_k v_k + shapes of v_k), v_k = t_k . dq: the drive terms
    written out for a classical vector `pi` (per joint: 10 inertial, Ia, Fv, Fc[, third])."""
    n, kind = robot.n, robot.friction_model["kind"]
    w = robot.friction_model["velocity"]
    per = len(pi) // n
    tau = np.zeros(n)
    for k, t in enumerate(rows(robot)):
        v = t @ dq
        f = friction_shapes(kind, v, w[k] if len(w) else None)
        torque = pi[k * per + 10] * (t @ acc) + sum(c * x for c, x in zip(pi[k * per + 11 :], f))
        tau += t * torque
    return tau


def classical_regressor(robot, model, data, q, dq, ddq, per: int) -> np.ndarray:
    """W (n x per n): Pinocchio's joint-torque regressor in mindyn's order for the links, the
    drive columns t_k (t_k . ddq), t_k shapes(t_k . dq) for each slot."""
    n = robot.n
    Wpin = pin.computeJointTorqueRegressor(model, data, q, dq, ddq)
    kind, w = robot.friction_model["kind"], robot.friction_model["velocity"]
    W = np.zeros((n, per * n))
    for k, t in enumerate(rows(robot)):
        W[:, k * per : k * per + 10] = Wpin[:, 10 * k : 10 * k + 10] @ TO_PIN
        shapes = friction_shapes(kind, t @ dq, w[k] if len(w) else None)
        W[:, k * per + 10 : (k + 1) * per] = np.outer(t, [t @ ddq] + shapes)
    return W


def drive_values(robot, rng, per: int) -> np.ndarray:
    """The robot's inertial parameters with random rotor inertia and friction (motor units)."""
    pi = np.zeros(per * robot.n)
    for k in range(robot.n):
        pi[k * per : k * per + 10] = robot.params[10 * k : 10 * k + 10]
        low, high = [1e-5, 1e-4, 0.01, -0.005], [1e-4, 1e-3, 0.05, 0.02]
        pi[k * per + 10 : (k + 1) * per] = rng.uniform(low[: per - 10], high[: per - 10])
    return pi


def states(robot, rng, count: int):
    """Random states; in the first, joint 1 rests (a motor velocity exactly 0: sign(0)) and
    joint 2 turns slowly (tanh's series)."""
    for i in range(count):
        q = rng.uniform(-np.pi, np.pi, robot.n)
        dq, ddq = rng.uniform(-2.0, 2.0, (2, robot.n))
        if i == 0:
            dq[0], dq[1] = 0.0, 1e-4
        yield q, dq, ddq


@pytest.mark.parametrize(
    "name, kind, side",
    [(a, k, "motor") for a in ("coupled6r", "wam7r") for k in KINDS]
    + [("coupled6r", "smooth", "joint"), ("wam7r", "coulomb", "joint")],
)
def test_generated_c_equals_newton_euler_plus_the_drive_terms(
    name, kind, side, arms, tmp_path, rng
):
    """All classical parameters: tau = rnea + sum_k t_k (...), W and the gravity torque, 1e-12."""
    robot, model = arm(arms, name, kind, side)
    code = codegen.generate(robot, rotor=True, friction=True, base=False, name=name, trig="libm")
    per = 13 + (kind in ("asymmetric", "stribeck"))
    third = {"asymmetric": ["Fa"], "stribeck": ["Fs"]}.get(kind, [])
    assert code.names[10:per] == ["Ia1", "Fv1", "Fc1"] + [f"{x}1" for x in third]
    c = compiled(code, tmp_path, robot.n)
    data = model.createData()
    pi = drive_values(robot, rng, per)
    for q, dq, ddq in states(robot, rng, 3):
        ref = pin.rnea(model, data, q, dq, ddq) + drive_torque(robot, pi, dq, ddq)
        assert_close(c.id(q, dq, ddq, pi), ref, 1e-12, "generated C id with drive terms")
        g = pin.computeGeneralizedGravity(model, data, q)
        assert_close(c.gravity(q, pi), g, 1e-12, "generated C gravity with drive terms")
        W = classical_regressor(robot, model, data, q, dq, ddq, per)
        assert_close(c.regressor(q, dq, ddq), W, 1e-12, "generated C regressor with drive terms")
    header = code.header
    if side == "motor":
        assert f"Rotor inertia and friction on the {robot.n} motors" in header
        assert "m6 = 40.0 q5 + 36.0 q6" in header or name != "coupled6r"
    else:
        assert "on the joints, not through the transmissions" in header
        assert "motors (" not in header
    formula = {"coulomb": "Fc sign(v).", "asymmetric": "Fa |sign(v)|", "smooth": "tanh(v / w)"}
    assert formula.get(kind, "Fs sign(v) exp(-(v / w)^2)") in header


@pytest.mark.parametrize("name", ["coupled6r", "wam7r"])
@pytest.mark.parametrize("kind", ["coulomb", "smooth"])
def test_base_parameter_code_is_the_regressor_at_the_pivots(name, kind, arms, tmp_path, rng):
    """Base parameters (numerical method): W_b = W[:, pivots] and tau = W[:, pivots] p for
    random p, gravity likewise, 1e-12; the same from the runtime base dynamics (the tape of the
    generated recursion)."""
    robot, model = arm(arms, name, kind)
    bp = mindyn.base_parameters(robot, rotor=True, friction=True, method="numerical")
    code = codegen.generate(robot, base=bp, name=f"b{name}")
    c = CFunctions(compile_c(code, tmp_path, f"b{name}"), code, robot.n)
    pivots = bp.sets["eom"]["pivots"]
    data = model.createData()
    runtime = codegen.BaseDynamics(bp)
    for q, dq, ddq in states(robot, rng, 2):
        Wb = classical_regressor(robot, model, data, q, dq, ddq, 13)[:, pivots]
        p = rng.normal(size=bp.n)
        assert_close(c.regressor(q, dq, ddq), Wb, 1e-12, "generated C W_b with drive")
        assert_close(c.id(q, dq, ddq, p), Wb @ p, 1e-12, "generated C id_b with drive")
        G = classical_regressor(robot, model, data, q, 0 * dq, 0 * ddq, 13)[:, pivots]
        assert_close(c.gravity(q, p), G @ p, 1e-12, "generated C gravity_b with drive")
        assert_close(runtime.inverse_dynamics(q, dq, ddq, p), Wb @ p, 1e-12, "runtime id_b drive")
        assert_close(runtime.regressor(q, dq, ddq), Wb, 1e-12, "runtime W_b with drive")


@pytest.mark.parametrize(
    "name, kind", [("coupled6r", "smooth"), ("coupled6r", "stribeck"), ("wam7r", "asymmetric")]
)
def test_structured_text_with_drive_terms_evaluates_like_the_c(name, kind, arms, tmp_path, rng):
    """tanh written with EXP (three regions and +-1 beyond 20) and Stribeck's EXP: the ST
    inverse dynamics and regressor against the C (math.h tanh, exp), 1e-12, over states that
    reach every region of the tanh."""
    robot, _ = arm(arms, name, kind)
    same = dict(rotor=True, friction=True, base=False, what="id,regressor")
    st = codegen.generate(robot, lang="st", name="c6st", **same)
    code = codegen.generate(robot, name="c6c", **same)
    c = compiled(code, tmp_path, robot.n)
    text = st.text
    assert max(len(line) for line in text.splitlines()) <= 100
    statements = re.sub(r"\(\*.*?\*\)", "", text, flags=re.DOTALL)
    assert set(re.findall(r"\b([A-Za-z_]\w*)\(", statements)) <= {"SIN", "COS", "EXP"}
    tree = st_tree(text)
    per = len(code.names) // robot.n
    pi = drive_values(robot, rng, per)
    T = robot.transmission.T
    w = robot.friction_model["velocity"]
    reached = set()
    for q, dq, ddq in states(robot, rng, 4):
        if len(w):
            x = np.abs(T @ dq / w)
            reached |= {int(np.digitize(v, [0.0, 0.125, 20.0], right=True)) for v in x}
        ins = {"q": q, "dq": dq, "ddq": ddq, "p": pi}
        tau = STInterpreter(tree, "c6st_inverse_dynamics").run(ins)["tau"]
        assert_close(tau, c.id(q, dq, ddq, pi), 1e-12, f"ST id vs C ({kind} friction)")
        W = STInterpreter(tree, "c6st_regressor").run(ins)["w"]
        assert_close(W, c.regressor(q, dq, ddq), 1e-12, f"ST regressor vs C ({kind} friction)")
    if kind == "smooth":
        assert {0, 1, 2} <= reached  # |x| = 0, below 0.125 and between; above 20 just below


def test_structured_text_with_tanh_and_exp_passes_blark():
    blark = pytest.importorskip("blark")
    robot = mindyn.load("planar2")
    for kind in ("smooth", "stribeck"):
        r = robot.with_friction_model(kind, velocity=[0.1, 0.2])
        st = codegen.generate(r, lang="st", what="id", friction=True, base=False)
        assert "EXP(" in st.text
        result = blark.parse_source_code(st.text)
        assert result.exception is None, result.exception


def test_structured_text_tanh_saturates_without_overflow(arms):
    """Far beyond the tanh width (|v / w| up to 1e300) the ST gives +-1 exactly, and the
    smooth-friction torque stays finite."""
    robot, _ = arm(arms, "diff3r", "smooth")
    st = codegen.generate(robot, lang="st", what="regressor", rotor=True, friction=True, base=False)
    tree = st_tree(st.text)
    T = robot.transmission.T
    for scale in (1e-300, 1e-8, 0.3, 25.0, 1e150):
        dq = np.array([1.0, -0.5, 0.25]) * scale
        W = STInterpreter(tree, f"{st.name}_regressor").run(
            {"q": np.zeros(3), "dq": dq, "ddq": np.zeros(3)}
        )["w"]
        w = robot.friction_model["velocity"]
        expected = [np.outer(t, [np.tanh(t @ dq / w[k])]) for k, t in enumerate(T)]
        got = [W[:, 13 * k + 12 : 13 * k + 13] for k in range(3)]
        assert np.all(np.isfinite(np.hstack(got)))
        assert_close(np.hstack(got), np.hstack(expected), 1e-15, "ST tanh saturation")


def test_operation_counts_in_the_header_are_the_statements(arms):
    """Each computed value of the C is one operation of the header's counts: multiplications,
    additions, sines/cosines, signs, tanh and exp, with and without transmissions."""
    for kind in ("stribeck", "smooth", "asymmetric"):
        for side in ("motor", "joint"):
            robot, _ = arm(arms, "wam7r", kind, side)
            code = codegen.generate(
                robot, rotor=True, friction=True, what="id", trig="libm", base=False
            )
            got = {"mul": 0, "add": 0, "trig": 0, "sign": 0, "tanh": 0, "exp": 0}
            for rhs in re.findall(r"const double t\d+ = (.*);", code.source):
                key = (
                    "sign" if rhs.startswith("(double)")
                    else "trig" if rhs.startswith(("sin(", "cos("))
                    else "tanh" if rhs.startswith("tanh(")
                    else "exp" if rhs.startswith("exp(")
                    else "mul" if " * " in rhs
                    else "add"
                )  # fmt: skip
                got[key] += 1
            counts = code.counts["inverse_dynamics"]
            assert got == {k: counts[k] for k in got}, (kind, side)
            line = f"inverse_dynamics: {counts['mul']} mul, {counts['add']} add"
            assert line in code.header


def one_motor_per_joint_refusal(tmp_path):
    """A differential whose second joint is off the loaded chain: 4 motors for 3 joints."""
    parts = "".join(simple(f"t{k}", f"j{k}", f"m{k}", 10.0 * k) for k in (1, 2))
    parts += pair("DifferentialTransmission", "mix", ("j3", "j4"), ("m3", "m4"), (5, 6), (1, 2))
    path = tmp_path / "four_motors.urdf"
    path.write_text(skewed_urdf(np.random.default_rng(4), 4, "fourmotors", parts))
    return mindyn.load(path, tip="l3")


def test_motor_side_needs_one_motor_per_joint(tmp_path):
    """A URDF chain cut (--tip) inside a differential: 4 motors for its 3 joints. The rotor
    inertia and friction act on the joints (no motor slot per joint), so the generated code
    has the joint-side terms: rotor columns the accelerations (checked on the runtime
    regressor, whose rotor columns are then diag(ddq)); the motor side is refused."""
    robot = one_motor_per_joint_refusal(tmp_path)
    assert robot.n == 3 and robot.transmission.T.shape == (4, 3)
    assert robot.drive_side == "joint"
    with pytest.raises(mindyn.ModelError, match="4 motors for 3 joints"):
        robot.with_drive_side("motor")
    code = codegen.generate(robot, rotor=True, base=False)
    assert code.counts["inverse_dynamics"]["mul"] > 0
    rng = np.random.default_rng(1)
    q, dq, ddq = (rng.standard_normal(3) for _ in range(3))
    W = robot.regressor(q, dq, ddq, rotor=True).reshape(3, 3, 11)
    np.testing.assert_array_equal(W[:, :, 10], np.diag(ddq))
    codegen.generate(robot, base=False, what="gravity")


# ---------------------------------------------------------------------------------------------
# The adaptive PD step (Slotine-Li) with transmissions
# ---------------------------------------------------------------------------------------------
def slotine_li_columns(robot, model, data, q, dq, dqr, ddqr, columns, per: int) -> np.ndarray:
    """Columns of the Slotine-Li regressor at classical indices `columns`: Pinocchio's
    M ddqr + C(q, dq) dqr + g of the unit parameter (by linearity, from a massive link added
    and taken away, as pin.Inertia needs a mass), the drive columns at (dq, ddqr)."""
    saved = [model.inertias[k + 1].copy() for k in range(robot.n)]

    def links(inertial):
        for k in range(robot.n):
            dyn = TO_PIN @ inertial[10 * k : 10 * k + 10]
            model.inertias[k + 1] = pin.Inertia.FromDynamicParameters(dyn)
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        C = pin.computeCoriolisMatrix(model, data, q, dq)
        return M @ ddqr + C @ dqr + pin.computeGeneralizedGravity(model, data, q)

    heavy = np.tile([0, 0, 0, 0, 0, 0, 0, 0, 0, 5.0], robot.n)
    base = links(heavy)
    out = np.zeros((robot.n, len(columns)))
    for i, col in enumerate(columns):
        k, j = divmod(col, per)
        unit = np.zeros(per * robot.n)
        unit[col] = 1.0
        if j < 10:
            e = heavy.copy()
            e[10 * k + j] += 1.0
            out[:, i] = links(e) - base
        else:
            out[:, i] = drive_torque(robot, unit, dq, ddqr)
    for k in range(robot.n):
        model.inertias[k + 1] = saved[k]
    return out


@pytest.mark.parametrize(
    "name, kind, nu, base",
    [
        ("coupled6r", "smooth", 0.0, "numerical"),
        ("wam7r", "coulomb", 0.4, "numerical"),
        ("coupled6r", "stribeck", 0.3, "classical"),
        ("wam7r", "asymmetric", 0.0, "classical"),
    ],
)
def test_adaptive_step_with_transmissions_matches_the_formula(
    name, kind, nu, base, arms, tmp_path, rng
):
    """tau = Y_b p - kd s and p - period gamma Y_b^T s / (1 + nu |Y_b|^2) with Y_b the Slotine-Li
    regressor written out (Pinocchio plus the drive terms at dq and ddq_r) at the base set's
    pivots (numerical method), or all its columns (classical parameters: the friction models
    with a third column); the C compiles under -Werror (on the 6R), includes math.h only and
    allocates nothing."""
    robot, model = arm(arms, name, kind)
    per = 13 + (kind in ("asymmetric", "stribeck"))
    if base == "classical":
        bp, columns = False, list(range(per * robot.n))
    else:
        bp = mindyn.base_parameters(robot, rotor=True, friction=True, method="numerical")
        columns = bp.sets["eom"]["pivots"]
    n, nb = robot.n, len(columns)
    gains = {"kd": rng.uniform(1, 50, n), "lambda": rng.uniform(1, 20, n), "nu": nu}
    gains["gamma"] = rng.uniform(0.5, 2.0, nb)
    p0 = rng.normal(size=nb)
    # the bare step (the default box on the estimate, derived from the loop check, left out)
    code = codegen.generate_controller(
        robot, base=bp, gains=gains, params=p0, period=0.002, p_min=-np.inf, p_max=np.inf
    )
    if name == "coupled6r":  # once per friction form; the compiles take most of the time
        strict_compile(code, tmp_path)
    assert re.findall(r"#include [<\"](.+?)[>\"]", code.source + code.header) == [
        code.header_name,
        "math.h",
    ]
    assert not re.search(r"\b(malloc|calloc|realloc|free)\(", code.source)
    assert f"Rotor inertia and friction on the {n} motors" in code.header
    ctl = codegen.CompiledController(code)
    data = model.createData()
    for q, dq, _ in states(robot, rng, 2):
        qd, dqd, ddqd = rng.uniform(-1, 1, (3, n))
        p = ctl.p_hat
        tau = ctl(0.0, q, dq, qd, dqd, ddqd)
        e, de = q - qd, dq - dqd
        lam = gains["lambda"]
        dqr, ddqr, s = dqd - lam * e, ddqd - lam * de, de + lam * e
        Y = slotine_li_columns(robot, model, data, q, dq, dqr, ddqr, columns, per)
        assert_close(tau, Y @ p - gains["kd"] * s, 1e-12, "generated adaptive step: tau")
        step = 0.002 * gains["gamma"] * (Y.T @ s) / (1.0 + nu * np.sum(Y * Y))
        assert_close(ctl.p_hat, p - step, 1e-12, "generated adaptive step: estimate")


def test_structured_text_adaptive_step_with_a_differential_matches_the_c(arms):
    """The ST step of a 3R arm with a differential and smooth friction against the C step over
    200 cycles (estimate carried, torque limit and box acting)."""
    robot, _ = arm(arms, "diff3r", "smooth")
    bp = mindyn.base_parameters(robot, rotor=True, friction=True, method="numerical")
    nb = bp.n
    p0 = np.linspace(0.2, 1.0, nb)
    gains = {"kd": [5.0, 3.0, 2.0], "lambda": [10.0, 8.0, 6.0], "gamma": 20.0, "nu": 0.5}
    same = dict(base=bp, gains=gains, params=p0, tau_max=[8.0, 4.0, 3.0], name="diff3")
    same.update(p_min=p0 - 0.05, p_max=p0 + 0.05)
    st = codegen.generate_controller(robot, lang="st", **same)
    c = codegen.CompiledController(codegen.generate_controller(robot, trig="libm", **same))
    block = STBlock(st_tree(st.text), st.function)
    reference = mindyn.control.SumOfSines(robot, period=2.0, seed=3)
    rng = np.random.default_rng(7)
    worst = 0.0
    for i in range(200):
        qd, dqd, ddqd = (x[0] for x in reference.evaluate([0.004 * i]))
        q = qd + rng.normal(0, 0.05, 3)
        dq = dqd + rng.normal(0, 0.3, 3)
        out = block({"q": q, "dq": dq, "q_d": qd, "dq_d": dqd, "ddq_d": ddqd})
        tau = c(0.0, q, dq, qd, dqd, ddqd)
        worst = max(worst, assert_close(out["tau"], tau, 1e-12, "ST step vs C (drive): tau"))
        assert_close(out["p"], c.p_hat, 1e-12, "ST step vs C (drive): estimate")
    assert np.any(np.abs(c.p_hat - p0) > 1e-3)


# ---------------------------------------------------------------------------------------------
# The command line
# ---------------------------------------------------------------------------------------------
def test_cli_codegen_puts_the_drive_terms_on_the_motors_and_says_so(arms, tmp_path, capsys):
    _, _, path = arms["coupled6r"]
    out = tmp_path / "arm"
    argv = ["codegen", str(path), "--lang", "c", "--what", "id", "--rotor", "--friction"]
    argv += ["--method", "numerical", "-o", str(out)]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "rotor inertia and friction on the 6 motors" in text
    assert "friction model: coulomb (the default)" in text
    assert "on the 6 motors" in (tmp_path / "arm.h").read_text()
    assert main([*argv, "--drive-side", "joint"]) == 0
    text = capsys.readouterr().out
    assert "rotor inertia and friction on the joints (--drive-side joint)" in text
    assert "motors" not in (tmp_path / "arm.h").read_text()
    # the friction model an identification JSON records
    robot = mindyn.load(path).with_friction_model("smooth", velocity=np.full(6, 3.0))
    bp = mindyn.base_parameters(robot, rotor=True, friction=True, method="numerical")
    ident = tmp_path / "id.json"
    doc = {"robot": "coupled6r", "names": bp.names, "values": [0.1] * bp.n, "removed": []}
    doc.update(rotor=True, friction=True, friction_model={"kind": "smooth", "velocity": [3.0] * 6})
    ident.write_text(json.dumps(doc))
    assert main([*argv, "--params", str(ident)]) == 0
    text = capsys.readouterr().out
    assert f"friction model: smooth (tanh widths 3, 3, 3, 3, 3, 3), from {ident}" in text
    assert "Fv v + Fc tanh(v / w)" in (tmp_path / "arm.h").read_text()


@pytest.mark.parametrize(
    "robot, extra, message",
    [
        ("planar2", ["--drive-side", "motor"], "declares no transmissions"),
        ("planar2", ["--drive-side", "motors"], "invalid choice: 'motors'"),
    ],
)
def test_cli_drive_side_errors(robot, extra, message, tmp_path, capsys):
    argv = ["codegen", robot, "--lang", "c", "--rotor", "-o", str(tmp_path / "x"), *extra]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mindyn: error: ") and message in err[0], err


@pytest.mark.parametrize(
    "recorded, message",
    [
        ("smooth", "'friction_model' must be {kind, velocity}"),
        ({"kind": "lugre"}, "'lugre'; expected one of 'coulomb', 'asymmetric', 'smooth'"),
        ({"kind": "smooth", "velocity": ["fast", 1]}, "velocity must be a list of numbers"),
        ({"kind": "smooth", "velocity": [0.1, -1.0]}, "friction_model: velocity has -1 at entry 2"),
    ],
)
def test_cli_friction_model_of_a_json_is_checked(recorded, message, tmp_path, capsys):
    ident = tmp_path / "id.json"
    doc = {"names": [], "values": [], "removed": [], "friction_model": recorded}
    ident.write_text(json.dumps(doc))
    argv = ["codegen", "planar2", "--lang", "c", "--friction", "--params", str(ident)]
    assert main([*argv, "-o", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mindyn: error: ") and message in err[0], err


GEARED_2R = (
    """<robot name="geared2r"><link name="base"/>
<link name="l1"><inertial><origin xyz="0.1 0.02 0"/><mass value="2"/>
<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.025"/></inertial></link>
<link name="l2"><inertial><origin xyz="0.15 0 0.01"/><mass value="1.2"/>
<inertia ixx="0.004" ixy="0.001" ixz="0" iyy="0.012" iyz="0" izz="0.013"/></inertial></link>
<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
<origin rpy="1.5707963267948966 0 0"/><axis xyz="0 0 1"/>
<limit lower="-2.5" upper="2.5" effort="80" velocity="2"/><dynamics damping="0.5" friction="1.0"/>
</joint>
<joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
<origin xyz="0.3 0 0"/><axis xyz="0 0 1"/>
<limit lower="-2.5" upper="2.5" effort="40" velocity="2"/><dynamics damping="0.2" friction="0.4"/>
</joint>
"""
    + simple("t1", "j1", "m1", 50)
    + "</robot>"
)


def test_codegen_takes_the_drive_side_the_identification_json_records(tmp_path, rng):
    """A robot with a 50:1 transmission identified with --drive-side joint: codegen --params
    without --drive-side generated motor-side code with the joint-side values (joint 1's
    friction 2500 times too large). The code now takes the JSON's side and equals Pinocchio's
    rnea plus the URDF's damping and friction on the joints, which the noise-free log's
    identification recovers; the other side asked for is refused, and so is a robot on the
    other side in the library."""
    import subprocess

    urdf = tmp_path / "geared2r.urdf"
    urdf.write_text(GEARED_2R)
    log, ident, out = tmp_path / "log.csv", tmp_path / "id.json", tmp_path / "g"
    assert main(["simulate", str(urdf), "--mode", "inverse", "--friction", "-o", str(log)]) == 0
    argv = ["identify", str(urdf), str(log), "--friction", "--drive-side", "joint"]
    assert main([*argv, "--rsd-threshold", "0", "--json", str(ident)]) == 0
    assert json.loads(ident.read_text())["drive_side"] == "joint"
    argv = ["codegen", str(urdf), "--lang", "c", "--what", "id", "--friction", "--params"]
    assert main([*argv, str(ident), "-o", str(out)]) == 0
    model = pin.buildModelFromUrdf(str(urdf))
    data = model.createData()
    states = rng.uniform(-1.5, 1.5, (5, 3, 2))
    states[:, 1] = np.sign(states[:, 1]) * (0.2 + np.abs(states[:, 1]))  # away from rest
    rows = ",".join("{" + ",".join(f"{v:.17g}" for v in s.ravel()) + "}" for s in states)
    (tmp_path / "main.c").write_text(
        '#include <stdio.h>\n#include "g.h"\n'
        f"static const double S[5][6] = {{{rows}}};\n"
        "int main(void) { double tau[2];\n"
        "  for (int k = 0; k < 5; ++k) {\n"
        "    geared2r_inverse_dynamics(S[k], S[k] + 2, S[k] + 4, geared2r_parameter_values, tau);\n"
        '    printf("%.17g %.17g\\n", tau[0], tau[1]); }\n  return 0; }\n'
    )
    exe = tmp_path / "main"
    build = [GCC, "-std=c99", "-Wall", "-Wextra", "-Werror", "-o", str(exe)]
    subprocess.run([*build, str(tmp_path / "main.c"), f"{out}.c", "-lm"], check=True)
    text = subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout
    tau_c = np.array(text.split(), dtype=float).reshape(5, 2)
    damping, friction = np.array([0.5, 0.2]), np.array([1.0, 0.4])
    for (q, dq, ddq), tau in zip(states, tau_c):
        ref = pin.rnea(model, data, q, dq, ddq) + damping * dq + friction * np.sign(dq)
        np.testing.assert_allclose(tau, ref, rtol=1e-4, atol=1e-4 * np.abs(ref).max())
    assert main([*argv, str(ident), "--drive-side", "motor", "-o", str(out)]) == 2
    robot = mindyn.load(urdf)
    assert robot.drive_side == "motor"
    with pytest.raises(mindyn.ModelError, match=r"robot.with_drive_side\('joint'\)"):
        codegen.generate(robot, what="id", friction=True, params=str(ident))
    codegen.generate(robot.with_drive_side("joint"), what="id", friction=True, params=str(ident))
