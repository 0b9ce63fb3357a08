"""Generated code against independent references.

C: compiled with gcc (-std=c99 -Wall -Wextra -Werror -pedantic) into a shared object, called through
ctypes and compared with Pinocchio's rnea / generalized gravity for the classical parameters pi,
with p = Y pi (rotor inertia and friction added here by their definition). Structured Text:
syntax-checked by two independent parsers (tree-sitter's IEC 61131-3 grammar on every robot, blark's
TwinCAT grammar on a small one) and evaluated by a small interpreter over the tree-sitter parse
tree, compared with the C output.
"""

from __future__ import annotations

import ctypes
import re
import shutil
import subprocess

import mindyn
import numpy as np
import pinocchio as pin
import pytest
import tree_sitter
import tree_sitter_iec61131_3_st
from conftest import (
    URDFS,
    assert_close,
    load_urdf_pair,
    pinocchio_model,
    random_state,
    set_pinocchio_params,
)
from mindyn.cli import main
from mindyn.codegen import BaseDynamics, generate, read_parameter_file

GCC = shutil.which("gcc")
pytestmark = pytest.mark.skipif(GCC is None, reason="gcc is needed to compile generated C")

# --------------------------------------------------------------------------------------------
# Robots: (mindyn Robot, Pinocchio model with the same classical parameters)
# --------------------------------------------------------------------------------------------


def skewed_urdf(
    rng: np.random.Generator, n: int = 6, name: str = "skewed6r", extra: str = ""
) -> str:
    """An nR arm (joints j1..jn) with random joint origins, rotations and axes and random
    physical links; `extra` is written inside <robot> after them (transmissions)."""
    links = ['<link name="base"/>']
    joints = []
    for k in range(1, n + 1):
        m = rng.uniform(0.5, 3.0)
        c = rng.uniform(-0.1, 0.1, 3)
        A = rng.normal(size=(3, 3))
        inertia = A @ A.T * 0.01 + np.eye(3) * 0.005
        links.append(
            f'<link name="l{k}"><inertial><origin xyz="{c[0]} {c[1]} {c[2]}" rpy="0 0 0"/>'
            f'<mass value="{m}"/><inertia ixx="{inertia[0, 0]}" ixy="{inertia[0, 1]}" '
            f'ixz="{inertia[0, 2]}" iyy="{inertia[1, 1]}" iyz="{inertia[1, 2]}" '
            f'izz="{inertia[2, 2]}"/></inertial></link>'
        )
        xyz = rng.uniform(-0.3, 0.3, 3)
        rpy = rng.uniform(-np.pi, np.pi, 3)
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        parent = "base" if k == 1 else f"l{k - 1}"
        joints.append(
            f'<joint name="j{k}" type="revolute"><parent link="{parent}"/>'
            f'<child link="l{k}"/><origin xyz="{xyz[0]} {xyz[1]} {xyz[2]}" '
            f'rpy="{rpy[0]} {rpy[1]} {rpy[2]}"/><axis xyz="{axis[0]} {axis[1]} {axis[2]}"/>'
            '<limit lower="-3" upper="3" effort="100" velocity="3"/></joint>'
        )
    return f'<robot name="{name}">' + "".join(links + joints) + extra + "</robot>"


def rx90_yaml(rng: np.random.Generator) -> str:
    """The Staubli RX-90 in Khalil's modified DH table (D3 = RL4 = 0.45 m) with random physical
    inertial values: the robot of the published OpenSYMORO operation counts."""
    table = ((0, 0, 0), (-90, 0, 0), (0, 0.45, 0), (90, 0, 0.45), (-90, 0, 0), (90, 0, 0))
    lines = ["name: rx90", "convention: mdh", "angle_unit: deg", "joints:"]
    for k, (alpha, d, r) in enumerate(table):
        c = ", ".join(repr(float(x)) for x in rng.uniform(-0.1, 0.1, 3))
        xx, yy, zz = (float(x) for x in rng.uniform(0.02, 0.05, 3))
        xy, xz, yz = (float(x) for x in rng.uniform(-0.004, 0.004, 3))
        lines.append(
            f"  - {{name: j{k + 1}, type: revolute, alpha: {alpha}, d: {d}, theta: 0, r: {r}, "
            f"inertial: {{mass: {float(rng.uniform(1, 5))!r}, com: [{c}], inertia: {{xx: {xx!r}, "
            f"yy: {yy!r}, zz: {zz!r}, xy: {xy!r}, xz: {xz!r}, yz: {yz!r}}}}}}}"
        )
    return "\n".join(lines) + "\n"


@pytest.fixture(scope="module")
def robots(tmp_path_factory):
    """name -> (robot, pin.Model, rotor, friction, number of base parameters: published, or
    the sampled method's where none is)."""
    out = {}
    for name, rotor, friction, nb in (("puma560", False, False, 36), ("zcr07s", True, True, 52)):
        robot = mindyn.load(name)
        out[name] = (robot, pinocchio_model(robot), rotor, friction, nb)
    robot, model = load_urdf_pair("ur5")
    out["ur5"] = (robot, model, False, False, 36)
    path = tmp_path_factory.mktemp("skewed") / "skewed6r.urdf"
    path.write_text(skewed_urdf(np.random.default_rng(7)))
    out["skewed6r"] = (mindyn.load(path), pin.buildModelFromUrdf(str(path)), False, False, 38)
    path = tmp_path_factory.mktemp("rx90") / "rx90.yaml"
    path.write_text(rx90_yaml(np.random.default_rng(90)))
    robot = mindyn.load(path)
    nb = mindyn.base_parameters(robot, method="numerical").n  # no published count: sampled method
    out["rx90"] = (robot, pinocchio_model(robot), False, False, nb)
    # a prismatic joint (the Stanford arm's third), with rotor inertia and friction
    robot = mindyn.load("stanford")
    nb = mindyn.base_parameters(robot, rotor=True, friction=True, method="numerical").n
    out["stanford"] = (robot, pinocchio_model(robot), True, True, nb)
    return out


def joint_terms(robot, dq, ddq, rotor: bool, friction: bool) -> np.ndarray:
    t = np.zeros(robot.n)
    if rotor:
        t += robot.rotor_inertia * ddq
    if friction:
        t += robot.viscous * dq + robot.coulomb * np.sign(dq)
    return t


# --------------------------------------------------------------------------------------------
# C through ctypes
# --------------------------------------------------------------------------------------------
_DBL = ctypes.POINTER(ctypes.c_double)


def compile_shared(source, so, optimise: str = "-O1"):
    """Compiles C99 warning-free under -Werror into a shared object and loads it."""
    cmd = [GCC, "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", optimise, "-shared"]
    cmd += ["-fPIC", "-o", str(so), str(source), "-lm"]
    res = subprocess.run(cmd, capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    return ctypes.CDLL(str(so))


def compile_c(code, folder, name: str):
    """Writes, compiles and loads the generated C."""
    header, source = code.write(folder / f"{name}.c")
    return compile_shared(source, folder / f"lib{name}.so")


def ptr(a: np.ndarray):
    return a.ctypes.data_as(_DBL)


class CFunctions:
    def __init__(self, lib, code, n: int):
        self.lib, self.name, self.n, self.np = lib, code.name, n, len(code.names)
        self.numeric = code.numeric

    def id(self, q, dq, ddq, p=None):
        tau = np.zeros(self.n)
        args = [q, dq, ddq] + ([] if self.numeric else [p]) + [tau]
        f = getattr(self.lib, f"{self.name}_inverse_dynamics")
        f(*[ptr(np.ascontiguousarray(a, dtype=float)) for a in args[:-1]], ptr(tau))
        return tau

    def gravity(self, q, p=None):
        tau = np.zeros(self.n)
        args = [q] + ([] if self.numeric else [p])
        f = getattr(self.lib, f"{self.name}_gravity")
        f(*[ptr(np.ascontiguousarray(a, dtype=float)) for a in args], ptr(tau))
        return tau

    def regressor(self, q, dq, ddq):
        W = np.zeros(self.n * self.np)
        f = getattr(self.lib, f"{self.name}_regressor")
        f(*[ptr(np.ascontiguousarray(a, dtype=float)) for a in (q, dq, ddq)], ptr(W))
        return W.reshape(self.n, self.np)


@pytest.mark.parametrize(
    "name, minimise, trig",
    [(r, "operations", None) for r in ("puma560", "zcr07s", "ur5", "skewed6r", "rx90", "stanford")]
    + [(r, "additions", None) for r in ("puma560", "zcr07s", "rx90")]
    + [(r, "operations", "libm") for r in ("ur5", "stanford")],
)
def test_generated_c_matches_pinocchio(name, minimise, trig, robots, tmp_path, rng):
    robot, model, rotor, friction, nb = robots[name]
    bp = mindyn.base_parameters(robot, rotor=rotor, friction=friction)
    assert bp.n == nb  # published counts (numerical method with Pinocchio), reference/robots.md
    code = generate(robot, lang="c", base=bp, name=f"{name}_dyn", minimise=minimise, trig=trig)
    assert ("_sincos(" in code.source) == (trig is None)
    assert code.names == bp.names
    c = CFunctions(compile_c(code, tmp_path, name), code, robot.n)
    data = model.createData()
    own = robot.parameters(rotor=rotor, friction=friction)
    per = len(own) // robot.n
    # the robot's own parameters, then random (non-physical) inertial parameters
    for trial in range(2):
        pi = own.copy()
        if trial == 1:
            for k in range(robot.n):
                pi[k * per : k * per + 10] = rng.uniform(-1, 1, 10)
        inertial = np.concatenate([pi[k * per : k * per + 10] for k in range(robot.n)])
        set_pinocchio_params(model, robot, inertial)
        p = bp.values(pi)
        for _ in range(4):
            q, dq, ddq = random_state(robot, rng)
            ref = pin.rnea(model, data, q, dq, ddq) + joint_terms(robot, dq, ddq, rotor, friction)
            assert_close(c.id(q, dq, ddq, p), ref, 1e-10, f"generated C id vs Pinocchio ({name})")
            g = pin.computeGeneralizedGravity(model, data, q)
            assert_close(c.gravity(q, p), g, 1e-10, f"generated C gravity vs Pinocchio ({name})")
            W = c.regressor(q, dq, ddq)
            assert_close(W, bp.regressor(q, dq, ddq), 1e-10, f"generated C W_b ({name})")
            assert_close(W @ p, ref, 1e-10, f"generated C W_b p vs Pinocchio ({name})")
    set_pinocchio_params(model, robot, robot.params)


def test_numeric_code_bakes_the_values_in(robots, tmp_path, rng):
    robot, model, _, _, _ = robots["puma560"]
    bp = mindyn.base_parameters(robot)
    sym = generate(robot, what="id,gravity", base=bp, name="sym")
    num = generate(robot, what="id,gravity", base=bp, name="num", numeric=True)
    assert num.counts["inverse_dynamics"]["mul"] < sym.counts["inverse_dynamics"]["mul"]
    c = CFunctions(compile_c(num, tmp_path, "num"), num, robot.n)
    assert "const double p[" not in num.header
    model = pinocchio_model(robot)
    data = model.createData()
    for _ in range(5):
        q, dq, ddq = random_state(robot, rng)
        assert_close(c.id(q, dq, ddq), pin.rnea(model, data, q, dq, ddq), 1e-10, "numeric C id")
        assert_close(c.gravity(q), pin.computeGeneralizedGravity(model, data, q), 1e-10, "num g")


def test_sines_and_cosines_come_first(robots):
    # They depend on q alone; the C computes them all before the recursion that waits on them:
    # inline, one routine call per angle for its sine and cosine; from math.h, one call each.
    robot = robots["puma560"][0]
    src = generate(robot, what="id").source
    body = src[src.index("_inverse_dynamics(") :].splitlines()[1:]
    calls = [i for i, line in enumerate(body) if "_sincos(" in line]
    assert calls == [1, 3, 5, 7, 9], body[:12]
    assert not re.search(r"\b(sin|cos)\(", "\n".join(body)), "math.h called outside the routine"
    src = generate(robot, what="id", trig="libm").source
    assert "_sincos" not in src
    body = src[src.index("_inverse_dynamics(") :].splitlines()[1:]
    trig = [i for i, line in enumerate(body) if re.search(r"= (sin|cos)\(", line)]
    assert trig == list(range(len(trig))) and len(trig) == 10, body[:12]


def test_inline_sine_cosine_matches_the_c_library(tmp_path, rng):
    # The routine of the generated source against glibc's sin and cos, both called from C.
    code = generate("planar2", what="gravity", name="arm")
    code.write(tmp_path / "arm.c")
    (tmp_path / "check.c").write_text(
        '#include "arm.c"\n'
        "void check(const double* x, long n, double* out) {\n"
        "  for (long i = 0; i < n; ++i) {\n"
        "    arm_sincos(x[i], &out[4 * i], &out[4 * i + 1]);\n"
        "    out[4 * i + 2] = sin(x[i]);\n"
        "    out[4 * i + 3] = cos(x[i]);\n"
        "  }\n"
        "}\n"
    )
    check = compile_shared(tmp_path / "check.c", tmp_path / "libcheck.so", "-O2").check
    check.argtypes = [_DBL, ctypes.c_long, _DBL]

    def run(x):
        x = np.ascontiguousarray(x, dtype=float)
        out = np.zeros((len(x), 4))
        check(ptr(x), len(x), ptr(out))
        return out

    half_pi = np.pi / 2
    k = rng.integers(-600000, 600000, 20000)
    x = np.concatenate(
        [
            rng.uniform(-np.pi, np.pi, 200000),
            rng.uniform(-50, 50, 100000),
            rng.uniform(-1e6, 1e6, 100000),
            k * half_pi + rng.uniform(-1e-9, 1e-9, k.size),  # near the quadrant boundaries
            (k + 0.5) * half_pi,  # where the nearest k changes
            [0.0, -0.0, 1e-300, -1e-300, 5e-324, 1e6, -1e6, np.nextafter(1e6, 0)],
        ]
    )
    out = run(x)
    err = np.abs(out[:, :2] - out[:, 2:])
    assert err.max() <= 2.3e-16, (err.max(), x[np.argmax(err.max(axis=1))])
    small = np.abs(x) < 1e-3  # relative accuracy of sin near 0
    rel = np.abs(out[small, 0] - out[small, 2]) / np.maximum(np.abs(out[small, 2]), 1e-320)
    assert rel.max() <= 2.3e-16
    # beyond |x| = 1e6, and NaN and infinities: exactly the C library
    big = run([np.nextafter(1e6, 2e6), -3e7, 1e300, np.inf, -np.inf, np.nan])
    np.testing.assert_array_equal(big[:, :2], big[:, 2:])


def test_base_recursion_needs_fewer_operations_than_classical(robots):
    for name in ("puma560", "zcr07s", "ur5"):
        robot = robots[name][0]
        base = generate(robot, what="id")
        classical = generate(robot, what="id", base=False)
        b, k = base.counts["inverse_dynamics"], classical.counts["inverse_dynamics"]
        assert b["mul"] < k["mul"] and b["add"] < k["add"], (name, b, k)
        # one sin and one cos at most per revolute joint
        assert b["trig"] <= 2 * robot.n


def test_operation_count_target_for_a_puma_class_arm(robots):
    # The Staubli RX-90 (PUMA-class 6R, Khalil's MDH table), no friction: at most 250
    # multiplications and 220 additions when the formulation is chosen for the fewest additions;
    # the values of this code are checked against Pinocchio in test_generated_c_matches_pinocchio.
    robot = robots["rx90"][0]
    c = generate(robot, what="id", minimise="additions").counts["inverse_dynamics"]
    assert c["mul"] <= 250 and c["add"] <= 220, c
    d = generate(robot, what="id").counts["inverse_dynamics"]
    assert d["mul"] + d["add"] <= c["mul"] + c["add"] and d["add"] >= c["add"], (c, d)


def test_truncated_right_angles_are_taken_as_exact_and_reported(robots, tmp_path, capsys):
    # The UR5 URDF turns two joint frames by the pitch 1.57079632679 (pi/2 to 11 decimals): in
    # each rotation two entries are cos(1.57079632679) = 4.9e-12, taken as 0 (the values still
    # match Pinocchio's on the unrounded model to 1e-10, test_generated_c_matches_pinocchio).
    # The base set's default snap (snap="auto") already rounds those angles in the model the
    # code is generated from; the geometry as written (snap=False) shows codegen's own rounding.
    ur5 = robots["ur5"][0]
    as_written = mindyn.base_parameters(ur5, snap=False)
    code = generate(ur5, what="id,gravity", base=as_written)
    snap = code.geometry_snap
    assert snap["count"] >= 4 and snap["tolerance"] == 1e-9, snap
    assert snap["largest"] == pytest.approx(abs(np.cos(1.57079632679)), rel=1e-3)
    assert f"Geometry: {snap['count']} constants within 1e-09 of 0 or +-1 taken as" in code.header
    assert BaseDynamics(as_written).geometry_snap == snap
    assert generate(ur5, what="id,gravity").geometry_snap["count"] == 0  # snapped before
    exact = generate(robots["puma560"][0], what="id")  # DH in degrees: round-off residues only
    assert exact.geometry_snap["count"] == 0 and "Geometry:" not in exact.header
    argv = ["codegen", str(URDFS["ur5"]), "--lang", "st", "-o", str(tmp_path / "u.st")]
    assert main([*argv, "--snap", "off"]) == 0
    out = capsys.readouterr().out
    assert "constants within 1e-09 of 0 or +-1 taken as exact" in out
    assert "(largest change 4.9e-12)" in out
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "base set: 2 right angle(s) written rounded" in out and "constants within" not in out


def test_unknown_objective_is_refused(robots):
    with pytest.raises(mindyn.ArgumentError, match="minimise is a str 'time'; expected one of"):
        generate(robots["rx90"][0], what="id", minimise="time")
    with pytest.raises(mindyn.ArgumentError, match="trig is a str 'table'; expected one of"):
        generate(robots["rx90"][0], what="id", trig="table")
    with pytest.raises(mindyn.ArgumentError, match="trig applies to C only"):
        generate(robots["rx90"][0], what="id", lang="st", trig="libm")
    with pytest.raises(mindyn.ArgumentError, match="what names an unknown function 'torque'"):
        generate(robots["rx90"][0], what="id,torque")
    with pytest.raises(mindyn.ArgumentError, match="name 'my-arm' is not an identifier"):
        generate(robots["rx90"][0], what="id", name="my-arm")
    with pytest.raises(mindyn.ArgumentError, match="header_name is 'arm'"):
        generate(robots["rx90"][0], what="id", header_name="arm")
    with pytest.raises(TypeError):  # options are keyword-only
        generate(robots["rx90"][0], "st")  # type: ignore[misc]


def test_fewer_operations_than_published_customised_recursions(robots):
    # Published inverse-dynamics code in base parameters (symbolic values): OpenSYMORO's output
    # for the Staubli RX-90, about 309 mul / 256 add; SymPyBotics' C for the PUMA 560, 387 / 368.
    for name, mul, add in (("rx90", 309, 256), ("puma560", 387, 368)):
        c = generate(robots[name][0], what="id").counts["inverse_dynamics"]
        assert c["mul"] < mul and c["add"] < add, (name, c)


def test_runtime_base_dynamics_matches_pinocchio(rng):
    robot = mindyn.load("zcr07s")
    model = pinocchio_model(robot)
    data = model.createData()
    bp = mindyn.base_parameters(robot, rotor=True, friction=True)
    bd = BaseDynamics(bp)
    assert bd.n == 6 and bd.np == bp.n and bd.names == bp.names
    Q, DQ, DDQ = random_state(robot, rng, 5)
    tau = bd.inverse_dynamics(Q, DQ, DDQ)
    W = bd.regressor(Q, DQ, DDQ)
    assert tau.shape == (5, 6) and W.shape == (5, 6, bp.n)
    for i in range(5):
        ref = pin.rnea(model, data, Q[i], DQ[i], DDQ[i])
        ref += joint_terms(robot, DQ[i], DDQ[i], True, True)
        assert_close(tau[i], ref, 1e-10, "runtime base NE vs Pinocchio")
        assert_close(
            W[i] @ bp.values(robot.parameters(rotor=True, friction=True)), ref, 1e-10, "runtime W_b"
        )
        g = pin.computeGeneralizedGravity(model, data, Q[i])
        assert_close(bd.gravity(Q[i]), g, 1e-10, "runtime gravity vs Pinocchio")
    with pytest.raises(ValueError, match="q has shape"):
        bd.inverse_dynamics(np.zeros(5), np.zeros(6), np.zeros(6))
    with pytest.raises(ValueError, match="NaN"):
        bd.gravity(np.full(6, np.nan))
    p_bad = bp.values(robot.parameters(rotor=True, friction=True))
    with pytest.raises(ValueError, match=rf"p has shape \({bp.n - 1},\); expected \({bp.n},\)"):
        bd.gravity(Q[0], p_bad[:-1])
    p_bad[2] = np.inf
    with pytest.raises(ValueError, match="p contains an infinite value at entry 3"):
        bd.inverse_dynamics(Q[0], DQ[0], DDQ[0], p_bad)


# --------------------------------------------------------------------------------------------
# Structured Text: two parsers and an evaluator over the tree-sitter tree
# --------------------------------------------------------------------------------------------
_ST = tree_sitter.Parser(tree_sitter.Language(tree_sitter_iec61131_3_st.language()))


def st_tree(text: str):
    tree = _ST.parse(text.encode())
    assert not tree.root_node.has_error, "tree-sitter found a syntax error"
    return tree


class STInterpreter:
    """Runs one FUNCTION_BLOCK of a tree-sitter parse tree: LREAL scalars and arrays, :=, + - *
    /, unary minus, comparisons, IF/ELSIF/ELSE, SIN, COS, EXP. Identifiers are case-insensitive."""

    FUNCS = {"sin": np.sin, "cos": np.cos, "exp": np.exp}

    def __init__(self, tree, fb_name: str):
        self.fb = None
        for node in tree.root_node.children:
            if node.type == "function_block_declaration":
                ident = next(c for c in node.children if c.type == "identifier")
                if ident.text.decode().lower() == fb_name.lower():
                    self.fb = node
        assert self.fb is not None, f"FUNCTION_BLOCK {fb_name} not found"

    def declared_arrays(self) -> dict:
        """Array variables: name -> list of (lower, upper) bounds."""
        out = {}

        def walk(n):
            if n.type == "variable_declaration":
                names = [c.text.decode().lower() for c in n.children if c.type == "identifier"]
                arr = [c for c in n.children if c.type == "array_type"]
                if arr:
                    bounds = [
                        tuple(int(x.text) for x in s.children if x.type == "integer_literal")
                        for s in arr[0].children
                        if s.type == "subrange"
                    ]
                    for name in names:
                        out[name] = bounds
            for c in n.children:
                walk(c)

        walk(self.fb)
        return out

    def run(self, inputs: dict) -> dict:
        self.env = {}
        for name, bounds in self.declared_arrays().items():
            shape = tuple(hi - lo + 1 for lo, hi in bounds)
            self.env[name] = (
                np.array(inputs[name], dtype=float).reshape(shape)
                if (name in inputs)
                else np.full(shape, np.nan)
            )
        self.bounds = self.declared_arrays()
        for stmt in self.fb.children:
            self.execute(stmt)
        return self.env

    def execute(self, n):
        t = n.type
        if t == "assignment_statement":
            value = self.eval(n.child_by_field_name("right"))
            left = n.child_by_field_name("left")
            if left.type == "identifier":
                self.env[left.text.decode().lower()] = value
            else:
                name, idx = self.index(left)
                self.env[name][idx] = value
        elif t == "if_statement":
            if self.eval(n.child_by_field_name("condition")):
                self.block(n, stop=("elsif_clause", "else_clause"))
                return
            for c in n.children:
                if c.type == "elsif_clause" and self.eval(c.child_by_field_name("condition")):
                    self.block(c)
                    return
                if c.type == "else_clause":
                    self.block(c)
                    return
        elif t in ("statement_list",):
            for c in n.children:
                self.execute(c)
        elif t.endswith("_statement") and t != "empty_statement":
            raise AssertionError(f"statement {t} not supported by the test interpreter")

    def block(self, n, stop=()):
        for c in n.children:
            if c.type in stop:
                break
            if c.type.endswith("statement") or c.type == "statement_list":
                self.execute(c)

    def index(self, n):
        name = n.child_by_field_name("object").text.decode().lower()
        subs = [
            self.eval(c) for c in n.children if c.is_named and c != n.child_by_field_name("object")
        ]
        lows = [lo for lo, _ in self.bounds[name]]
        return name, tuple(int(s) - lo for s, lo in zip(subs, lows))

    def eval(self, n):
        t = n.type
        if t in ("real_literal", "integer_literal"):
            return float(n.text.decode().replace("E", "e"))
        if t == "identifier":
            return self.env[n.text.decode().lower()]
        if t == "index_expression":
            name, idx = self.index(n)
            return self.env[name][idx]
        if t == "parenthesized_expression":
            return self.eval(next(c for c in n.children if c.is_named))
        if t == "unary_expression":
            op = n.child_by_field_name("operator").text.decode()
            v = self.eval(n.child_by_field_name("operand"))
            assert op == "-", op
            return -v
        if t == "binary_expression":
            op = n.child_by_field_name("operator").text.decode()
            a = self.eval(n.child_by_field_name("left"))
            b = self.eval(n.child_by_field_name("right"))
            return {
                "+": lambda: a + b,
                "-": lambda: a - b,
                "*": lambda: a * b,
                "/": lambda: a / b,
                ">": lambda: a > b,
                "<": lambda: a < b,
            }[op]()
        if t == "call_expression":
            fname = n.child_by_field_name("function").text.decode().lower()
            args = [c for c in n.child_by_field_name("arguments").children if c.is_named]
            return float(self.FUNCS[fname](self.eval(args[0])))
        raise AssertionError(f"expression {t} not supported by the test interpreter")


@pytest.mark.parametrize("name", ["puma560", "zcr07s", "ur5", "skewed6r", "stanford"])
def test_structured_text_parses_and_evaluates_like_the_c(name, robots, tmp_path, rng):
    robot, _, rotor, friction, _ = robots[name]
    bp = mindyn.base_parameters(robot, rotor=rotor, friction=friction)
    st = generate(robot, lang="st", base=bp, name=f"{name}_st")
    code = generate(robot, base=bp, name=f"{name}_c")
    c = CFunctions(compile_c(code, tmp_path, name), code, robot.n)
    text = st.text
    assert "**" not in text and "ATAN2" not in text.upper()
    assert max(len(line) for line in text.splitlines()) <= 100
    assert f"robot '{robot.name}'" in text and "mul" in text
    tree = st_tree(text)
    p = bp.values(robot.parameters(rotor=rotor, friction=friction))
    q, dq, ddq = random_state(robot, rng)
    dq[0] = 0.0  # sign(0) branch of the Coulomb term
    ins = {"q": q, "dq": dq, "ddq": ddq, "p": p}
    tau = STInterpreter(tree, f"{name}_st_inverse_dynamics").run(ins)["tau"]
    assert_close(tau, c.id(q, dq, ddq, p), 1e-12, "ST id vs C")
    g = STInterpreter(tree, f"{name}_st_gravity").run(ins)["tau"]
    assert_close(g, c.gravity(q, p), 1e-12, "ST gravity vs C")
    W = STInterpreter(tree, f"{name}_st_regressor").run(ins)["w"]
    assert_close(W, c.regressor(q, dq, ddq), 1e-12, "ST regressor vs C")


def test_structured_text_passes_blark():
    blark = pytest.importorskip("blark")
    st = generate("planar2", lang="st", what="id,gravity", friction=True)
    result = blark.parse_source_code(st.text)
    assert result.exception is None, result.exception
    # blark rejects what it should: a C-style assignment
    bad = blark.parse_source_code(st.text.replace(" := ", " = ", 1))
    assert bad.exception is not None


def test_tree_sitter_rejects_broken_text():
    st = generate("planar2", lang="st", what="gravity")
    assert _ST.parse(st.text.replace("END_VAR", "END", 1).encode()).root_node.has_error


# --------------------------------------------------------------------------------------------
# Parameter files and the command line
# --------------------------------------------------------------------------------------------
def test_parameter_files(tmp_path):
    names = ["ZZR1", "MX2", "Fv1"]
    (tmp_path / "p.json").write_text('{"MX2": 2.5, "ZZR1": -1, "Fv1": 0.25}')
    assert np.array_equal(read_parameter_file(tmp_path / "p.json", names), [-1, 2.5, 0.25])
    (tmp_path / "p.txt").write_text("# identified\nZZR1 = 1e-3\nMX2 2\nFv1: -4\n")
    assert np.array_equal(read_parameter_file(tmp_path / "p.txt", names), [1e-3, 2, -4])
    (tmp_path / "q.json").write_text('{"names": ["ZZR1", "MX2", "Fv1"], "values": [1, 2, 3]}')
    assert np.array_equal(read_parameter_file(tmp_path / "q.json", names), [1, 2, 3])
    (tmp_path / "bad.txt").write_text("ZZR1 1\nMX2 2\n")
    with pytest.raises(ValueError, match="missing parameter.*Fv1"):
        read_parameter_file(tmp_path / "bad.txt", names)
    (tmp_path / "bad2.txt").write_text("ZZR1 1\nMX2 2\nFv1 3\nXX9 1\n")
    with pytest.raises(ValueError, match="unknown parameter.*XX9"):
        read_parameter_file(tmp_path / "bad2.txt", names)
    (tmp_path / "bad3.txt").write_text("ZZR1 one\n")
    with pytest.raises(ValueError, match=r"bad3.txt:1: expected 'NAME value'"):
        read_parameter_file(tmp_path / "bad3.txt", names)
    with pytest.raises(FileNotFoundError):
        read_parameter_file(tmp_path / "none.txt", names)


def test_the_library_takes_an_identification_json_as_the_command_does(tmp_path):
    """generate, generate_controller and generate_observer take the JSON of ``mindyn identify
    --json`` as the command's --params does: the pruned parameters (``removed``) as zero, the
    others the values it holds; a JSON of other joint terms or of another friction model than
    the robot's is refused (its friction columns are another model's), and the robot with that
    model takes it."""
    import json

    from mindyn.codegen import generate_controller, generate_observer

    robot = mindyn.load("planar3")
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    names = list(base.names)
    rng = np.random.default_rng(7)
    values = rng.uniform(0.5, 2.0, len(names))
    pruned = names[1::4]  # every fourth, as the identification's pruning leaves them
    kept = [k for k in names if k not in pruned]
    doc = {
        "robot": robot.name,
        "rotor": True,
        "friction": True,
        "names": kept,
        "values": [float(values[names.index(k)]) for k in kept],
        "removed": [{"name": k, "rsd": 90.0} for k in pruned],
        "rsd_threshold": 70.7,
        "friction_model": {"kind": "coulomb", "velocity": None},
    }
    path = tmp_path / "id.json"
    path.write_text(json.dumps(doc))
    expected = np.where(np.isin(names, pruned), 0.0, values)
    code = generate(robot, rotor=True, friction=True, params=path, name="p3")
    np.testing.assert_array_equal(code.values, expected)
    observer = generate_observer(robot, base=base, params=path, period=0.004)
    np.testing.assert_array_equal(observer.values, expected)
    gains = {"kd": [50.0, 30.0, 10.0], "lambda": [10.0, 10.0, 10.0]}
    controller = generate_controller(robot, "computed-torque", base=base, params=path, gains=gains)
    assert controller.settings["p0"].tolist() == expected.tolist()
    with pytest.raises(mindyn.ModelError, match="identified with rotor=True friction=True"):
        generate(robot, params=path)
    doc["friction_model"] = {"kind": "smooth", "velocity": [0.01, 0.02, 0.03]}
    path.write_text(json.dumps(doc))
    with pytest.raises(mindyn.ModelError) as err:
        generate(robot, rotor=True, friction=True, params=path)
    assert "identified with the smooth friction model; robot 'planar3' has the coulomb" in str(
        err.value
    ) and "with_friction_model('smooth', velocity=[0.01, 0.02, 0.03])" in str(err.value)
    smooth = robot.with_friction_model("smooth", velocity=[0.01, 0.02, 0.03])
    code = generate(smooth, rotor=True, friction=True, params=path, name="p3")
    np.testing.assert_array_equal(code.values, expected)
    assert "tanh" in code.source


def test_cli_codegen_chooses_the_method_as_base_does(tmp_path, capsys):
    """A chain beyond the projection method (20 joints) is generated from the recursive
    method's base set, which the output says; --method projection keeps the refusal."""
    out = str(tmp_path / "p20")
    assert main(["codegen", "planar20", "--lang", "c", "--what", "id", "-o", out]) == 0
    text = capsys.readouterr().out
    assert "base parameters by the recursive method: the projection method handles at most" in text
    rec = mindyn.base_parameters("planar20", method="recursive")
    assert f"planar20: {rec.n} base parameters;" in text
    assert "; base set by the recursive method\n" in text
    argv = ["codegen", "planar20", "--lang", "c", "--method", "projection", "-o", out]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("mindyn: error: ") and "18 joints" in err and err.count("\n") == 1
    # the default method is named as such; a chosen one by its name
    assert main(["codegen", "planar3", "--lang", "c", "-o", out]) == 0
    assert "; base set by the projection method (the default)\n" in capsys.readouterr().out
    assert main(["codegen", "planar3", "--lang", "c", "--method", "numerical", "-o", out]) == 0
    assert "; base set by the numerical method\n" in capsys.readouterr().out


def test_cli_codegen(tmp_path, capsys):
    out = tmp_path / "puma"
    assert main(["codegen", "puma560", "--lang", "c", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert (tmp_path / "puma.c").is_file() and (tmp_path / "puma.h").is_file()
    base = generate("puma560", what="id")
    classical = generate("puma560", what="id", base=False)
    row = next(line for line in text.splitlines() if line.startswith("inverse_dynamics"))
    numbers = [int(x) for x in row.split()[1:]]
    b, k = base.counts["inverse_dynamics"], classical.counts["inverse_dynamics"]
    assert numbers == [b["mul"], b["add"], b["trig"], k["mul"], k["add"], k["trig"]]
    argv = ["codegen", "puma560", "--lang", "c", "--what", "id", "--minimise", "additions"]
    assert main(argv + ["-o", str(out)]) == 0
    row = next(ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("inverse_dyn"))
    a = generate("puma560", what="id", minimise="additions").counts["inverse_dynamics"]
    assert [int(x) for x in row.split()[1:3]] == [a["mul"], a["add"]]
    assert "chosen for the fewest additions:" in (tmp_path / "puma.h").read_text()
    assert "_sincos(" in (tmp_path / "puma.c").read_text()
    assert main(["codegen", "puma560", "--lang", "c", "--trig", "libm", "-o", str(out)]) == 0
    assert "_sincos" not in (tmp_path / "puma.c").read_text()
    capsys.readouterr()
    # --method: a chain of 20 joints, beyond the projection method, by the recursive method
    # (the same set as the numerical method's; the default, see the test above)
    argv = ["codegen", "planar20", "--lang", "c", "--what", "id", "-o", str(out)]
    assert main(argv + ["--method", "recursive"]) == 0
    names = mindyn.base_parameters("planar20", method="numerical").names
    assert capsys.readouterr().out.startswith(f"planar20: {len(names)} base parameters;")
    assert all(f'"{name}"' in (tmp_path / "puma.c").read_text() for name in names)

    bp = mindyn.base_parameters("puma560")
    values = np.arange(1, bp.n + 1) * 0.01
    pfile = tmp_path / "p.txt"
    pfile.write_text("".join(f"{n} {float(v)!r}\n" for n, v in zip(bp.names, values)))
    st = tmp_path / "puma.st"
    args = ["codegen", "puma560", "--lang", "st", "--what", "gravity", "--numeric"]
    assert main([*args, "--params", str(pfile), "--name", "pumaG", "-o", str(st)]) == 0
    text = st.read_text()
    assert "FUNCTION_BLOCK pumaG_gravity" in text and "p : ARRAY" not in text
    tree = st_tree(text)
    q = np.linspace(-1, 1, 6)
    g = STInterpreter(tree, "pumaG_gravity").run({"q": q})["tau"]
    assert_close(g, bp.regressor(q, np.zeros(6), np.zeros(6)) @ values, 1e-12, "ST --params")


@pytest.mark.parametrize(
    "args, message",
    [
        (["--what", "torque"], "unknown function 'torque'"),
        (["--name", "9x"], "is not an identifier"),
        (["--params", "/nonexistent/p.txt"], "does not exist"),
        (["-o", "/dev/null/x.c"], "is a file, not a folder"),
        (["--lang", "st", "--trig", "libm"], "trig applies to C only"),
    ],
)
def test_cli_codegen_errors(args, message, tmp_path, capsys):
    argv = ["codegen", "puma560_3"] + ([] if "--lang" in args else ["--lang", "c"]) + args
    if "-o" not in args:
        argv += ["-o", str(tmp_path / "x")]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mindyn: error: ") and message in err[0], err
