"""Generated controller steps against the library's controllers.

The C step (compiled with gcc -std=c99 -Wall -Wextra -Werror -pedantic) is compared step by
step with mindyn.control.AdaptivePD / ComputedTorque and in the closed loop of
mindyn.control.simulate (the ZCR07S study's experiment, shortened); the Structured Text step is
run by the tree-sitter evaluator of test_codegen over a few hundred cycles, its estimate carried
from call to call, against the C step; the PLCopen XML is validated against the TC6 XML v2.01
schema (tests/data/plcopen).
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import mindyn
import numpy as np
import pytest
from conftest import assert_close, random_state
from mindyn import codegen, control
from mindyn.cli import main
from test_codegen import STInterpreter, st_tree

GCC = shutil.which("gcc")
pytestmark = pytest.mark.skipif(GCC is None, reason="gcc is needed to compile generated C")
XSD = Path(__file__).parent / "data" / "plcopen" / "tc6_xml_v201.xsd"


def strict_compile(code, folder: Path) -> None:
    src = code.write(folder / f"{code.function}.c")[1]
    cmd = [GCC, "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O1", "-c", str(src)]
    res = subprocess.run(cmd + ["-o", str(folder / "step.o")], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr


@pytest.mark.parametrize("kind", codegen.CONTROLLERS)
@pytest.mark.parametrize(
    "robot_name, nu, offset", [("zcr07s", 0.0, False), ("stanford", 0.5, True)]
)
def test_generated_steps_compile_warning_free(kind, robot_name, nu, offset, tmp_path):
    robot = mindyn.load(robot_name)
    base = mindyn.base_parameters(robot, rotor=True, friction=True, offset=offset)
    gains = dict(control.default_gains(robot), nu=nu)
    code = codegen.generate_controller(robot, kind, base=base, gains=gains, tau_max=50.0)
    strict_compile(code, tmp_path)
    assert code.counts["step"]["mul"] > 0 and "Per step" in code.header
    # math.h only, and no allocation
    includes = re.findall(r"#include [<\"](.+?)[>\"]", code.source + code.header)
    assert includes == [code.header_name, "math.h"]
    assert not re.search(r"\b(malloc|calloc|realloc|free)\(", code.source)
    # Structured Text: SIN and COS are the only functions called
    st = codegen.generate_controller(robot, kind, lang="st", base=base, gains=gains, tau_max=50.0)
    statements = re.sub(r"\(\*.*?\*\)", "", st.text, flags=re.DOTALL)
    assert set(re.findall(r"\b([A-Za-z_]\w*)\(", statements)) <= {"SIN", "COS"}


def one_step_reference(base, gains, p, q, dq, ref, dt, offset: bool):
    """AdaptivePD's tau and next estimate; with offsets the regressor gets a unit column per
    joint (tau += Off)."""
    n = base.robot.n
    nb = len(p) - (n if offset else 0)
    ctl = control.AdaptivePD(
        base, gains["kd"], gains["lambda"], np.ones(nb), p[:nb], nu=gains["nu"], period=dt
    )
    _, s, dqr, ddqr = ctl.terms(q, dq, ref)
    Y = control.slotine_li_regressor(base, q, dq, dqr, ddqr)
    if offset:
        Y = np.hstack([Y, np.eye(n)])
    tau = Y @ p - ctl.kd * s
    step = dt * np.asarray(gains["gamma"]) * (Y.T @ s)
    if gains["nu"]:
        step /= 1.0 + gains["nu"] * float(np.sum(Y * Y))
    return tau, p - step


@pytest.mark.parametrize(
    "robot_name, nu, offset",
    [
        ("zcr07s", 0.0, False),
        ("puma560", 0.3, True),
        ("stanford", 0.0, False),
        ("puma560_3", 1.0, False),
    ],
)
def test_adaptive_step_matches_the_library(robot_name, nu, offset, rng):
    """One step from random states: tau and the next estimate as AdaptivePD gives them (and, with
    offsets, the Slotine-Li regressor with unit offset columns); 1e-11 relative: round-off of
    sums of ~1000 products of order-one terms."""
    check_adaptive_steps(mindyn.load(robot_name), nu, offset, rng)


def check_adaptive_steps(robot, nu, offset, rng, method="projection", what="") -> None:
    """Three steps of the generated adaptive PD with random gains and estimate from random states
    against one_step_reference, to 1e-11 relative."""
    base0 = mindyn.base_parameters(robot, rotor=True, friction=True, method=method)
    base = mindyn.base_parameters(robot, rotor=True, friction=True, offset=offset, method=method)
    n = robot.n
    np_ = len(base.names)
    gamma = rng.uniform(0.5, 2.0, np_)
    gains = {"kd": rng.uniform(1, 50, n), "lambda": rng.uniform(1, 20, n), "gamma": gamma, "nu": nu}
    p0 = rng.normal(size=np_)
    code = codegen.generate_controller(
        robot, base=base, gains=gains, params=p0, period=0.002, p_min=-np.inf, p_max=np.inf
    )
    ctl = codegen.CompiledController(code, base)
    for _ in range(3):
        q, dq, _ = random_state(robot, rng)
        ref = random_state(robot, rng)
        p = ctl.p_hat
        tau = ctl(0.0, q, dq, *ref)
        tau_ref, p_ref = one_step_reference(base0, gains, p, q, dq, ref, 0.002, offset)
        assert_close(tau, tau_ref, 1e-11, f"generated adaptive step{what}: tau")
        assert_close(ctl.p_hat, p_ref, 1e-11, f"generated adaptive step{what}: estimate")


def test_torque_limit_and_box_are_applied(rng):
    """The library step, then np.clip: the torque at +-tau_max, the estimate in its box (half of
    the entries start on a bound)."""
    robot = mindyn.load("puma560")
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    nb = base.n
    p0 = rng.normal(size=nb)
    lo = p0 - np.where(np.arange(nb) % 2 == 0, 0.0, 1.0)
    hi = p0 + np.where(np.arange(nb) % 2 == 1, 0.0, 1.0)
    gains = {"kd": [30.0] * 6, "lambda": [10.0] * 6, "gamma": 50.0, "nu": 0.0}
    code = codegen.generate_controller(
        robot, base=base, gains=gains, params=p0, p_min=lo, p_max=hi, tau_max=5.0
    )
    ctl = codegen.CompiledController(code, base)
    q, dq, _ = random_state(robot, rng)
    ref = random_state(robot, rng)
    tau = ctl(0.0, q, dq, *ref)
    g = dict(gains, gamma=np.full(nb, 50.0))
    tau_ref, p_ref = one_step_reference(base, g, p0, q, dq, ref, 0.004, False)
    assert np.any(np.abs(tau_ref) > 5.0) and np.any(p_ref < lo) and np.any(p_ref > hi)
    assert_close(tau, np.clip(tau_ref, -5.0, 5.0), 1e-11, "generated step: torque limit")
    assert_close(ctl.p_hat, np.clip(p_ref, lo, hi), 1e-11, "generated step: box")


def in_the_loop(robot_name, kind, duration, substeps, error, seed, period):
    """control.simulate with the library's controller and with the generated C step (same
    gains, same initial estimate = the true base parameters off by +-`error`)."""
    robot = mindyn.load(robot_name)
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    p0 = control.perturbed_parameters(
        base.values(robot.parameters(rotor=True, friction=True)), error, seed=seed
    )
    gains = control.default_gains(robot)
    ref = control.SumOfSines(robot, period=period, seed=seed)
    library = control.make_controller(kind, robot, gains, p0, base=base)
    code = codegen.generate_controller(robot, kind, base=base, gains=gains, params=p0)
    generated = codegen.CompiledController(code, base)
    run = dict(rate=250.0, duration=duration, substeps=substeps, rotor=True, friction=True)
    a = control.simulate(robot, ref, library, **run)
    b = control.simulate(robot, ref, generated, **run)
    return a, b, library, generated


def test_zcr07s_study_in_the_loop_matches_the_library():
    """The ZCR07S study's experiment (examples/zcr07s_adaptive_pd.py) for 1.2 s (300 periods of
    4 ms): the generated C step in control.simulate against AdaptivePD; the trajectories agree
    to 1e-9 rad (the target; both evaluate the same formulas, in another order)."""
    a, b, library, generated = in_the_loop("zcr07s", "adaptive-pd", 1.2, 4, 0.3, 0, 10.0)
    assert np.abs(a.q - b.q).max() <= 1e-9
    assert np.abs(a.dq - b.dq).max() <= 1e-9
    assert_close(generated.p_hat, library.p_hat, 1e-9, "in the loop: estimate")
    assert np.abs(a.error).max() > 1e-5  # the loop tracks with an error that adapts


def test_computed_torque_in_the_loop_matches_the_library():
    a, b, _, _ = in_the_loop("puma560", "computed-torque", 0.4, 2, 0.2, 1, 4.0)
    assert np.abs(a.q - b.q).max() <= 1e-9 and np.abs(a.tau - b.tau).max() <= 1e-7


class STBlock(STInterpreter):
    """A FUNCTION_BLOCK instance: its variables kept from call to call, BOOL and NOT / OR."""

    def __init__(self, tree, name):
        super().__init__(tree, name)
        self.state: dict = {"initialised": False}
        self.bounds = self.declared_arrays()

    def __call__(self, inputs: dict) -> dict:
        self.env = dict(self.state)
        for name, bounds in self.bounds.items():
            shape = tuple(hi - lo + 1 for lo, hi in bounds)
            if name in inputs:
                self.env[name] = np.array(inputs[name], dtype=float).reshape(shape)
            elif name not in self.env:
                self.env[name] = np.full(shape, np.nan)
        self.env["reset"] = bool(inputs.get("reset", False))
        for stmt in self.fb.children:
            self.execute(stmt)
        self.state = {k: v for k, v in self.env.items() if k not in inputs}
        return self.env

    def eval(self, n):
        if n.type == "boolean_literal":
            return n.text.decode().upper() == "TRUE"
        op = n.child_by_field_name("operator")
        if op is not None and op.text.decode().upper() == "NOT":
            return not self.eval(n.child_by_field_name("operand"))
        if op is not None and op.text.decode().upper() == "OR":
            left = self.eval(n.child_by_field_name("left"))
            return bool(left or self.eval(n.child_by_field_name("right")))
        return super().eval(n)


@pytest.mark.parametrize("kind, cycles", [("adaptive-pd", 300), ("computed-torque", 100)])
def test_structured_text_step_matches_the_c_step(kind, cycles, tmp_path):
    """planar2 with friction and offsets, nu > 0, torque limit and a box that both act: the ST
    function block, its state kept by the evaluator, against the C step over `cycles` calls;
    1e-9 relative (sin and cos of numpy against the C library, carried through the
    adaptation)."""
    robot = mindyn.load("planar2")
    base = mindyn.base_parameters(robot, rotor=True, friction=True, offset=True)
    nb = len(base.names)
    p0 = np.linspace(0.2, 1.0, nb)
    gains = {"kd": [5.0, 3.0], "lambda": [10.0, 8.0], "gamma": 20.0, "nu": 0.5, "kp": [40, 20]}
    same = dict(base=base, gains=gains, params=p0, tau_max=[8.0, 4.0], name="planar2")
    if kind == "adaptive-pd":
        same.update(p_min=p0 - 0.05, p_max=p0 + 0.05)
    st = codegen.generate_controller(robot, kind, lang="st", **same)
    c = codegen.CompiledController(codegen.generate_controller(robot, kind, trig="libm", **same))
    tree = st_tree(st.text)
    block = STBlock(tree, st.function)
    reference = control.SumOfSines(robot, period=2.0, seed=3)
    rng = np.random.default_rng(7)
    saturated = clamped = 0
    for i in range(cycles):
        qd, dqd, ddqd = (x[0] for x in reference.evaluate([0.004 * i]))
        q = qd + rng.normal(0, 0.05, 2)
        dq = dqd + rng.normal(0, 0.3, 2)
        out = block({"q": q, "dq": dq, "q_d": qd, "dq_d": dqd, "ddq_d": ddqd})
        tau = c(0.0, q, dq, qd, dqd, ddqd)
        assert_close(out["tau"], tau, 1e-9, "ST step vs C: tau")
        assert_close(out["p"], c.p_hat, 1e-9, "ST step vs C: estimate")
        saturated += np.sum(np.abs(tau) == [8.0, 4.0])
        clamped += np.sum((c.p_hat == p0 - 0.05) | (c.p_hat == p0 + 0.05))
    assert saturated > 0
    if kind == "adaptive-pd":
        assert clamped > 0 and np.any(np.abs(c.p_hat - p0) > 1e-3)
    # reset: the estimate back to p0 before the step
    out = block({"q": q, "dq": dq, "q_d": qd, "dq_d": dqd, "ddq_d": ddqd, "reset": True})
    c.reset()
    tau = c(0.0, q, dq, qd, dqd, ddqd)
    assert_close(out["tau"], tau, 1e-9, "ST step vs C: tau")
    assert_close(out["p"], c.p_hat, 1e-9, "ST step vs C: estimate")


def test_structured_text_controller_passes_blark():
    blark = pytest.importorskip("blark")
    # one joint: blark takes about 20 ms per statement
    robot = mindyn.load("planar1")
    st = codegen.generate_controller(
        robot, lang="st", base=mindyn.base_parameters(robot), gains={"kd": 2.0, "nu": 0.1}
    )
    result = blark.parse_source_code(st.text[st.text.index("FUNCTION_BLOCK") :])
    assert result.exception is None, result.exception


def test_plcopen_project_validates_against_the_schema(tmp_path):
    xmlschema = pytest.importorskip("xmlschema")
    out = tmp_path / "zcr07s.xml"
    args = ["codegen", "zcr07s", "--what", "adaptive-pd", "--lang", "st", "--rotor", "--friction"]
    assert main(args + ["-o", str(tmp_path / "zcr07s.st"), "--plcopen", str(out)]) == 0
    schema = xmlschema.XMLSchema(str(XSD))
    schema.validate(str(out))
    doc = schema.to_dict(str(out))
    pous = {p["@name"]: p for p in doc["types"]["pous"]["pou"]}
    assert set(pous) == {
        "zcr07s_adaptive_pd",
        "zcr07s_inverse_dynamics",
        "zcr07s_gravity",
        "zcr07s_regressor",
        "zcr07s_momentum_observer",
    }
    # the ST body in the XML is the function block's body, which tree-sitter parses back
    import xml.etree.ElementTree as ET

    ns = {"x": codegen.PLCOPEN_NS, "h": "http://www.w3.org/1999/xhtml"}
    root = ET.parse(out).getroot()
    pou = root.find("x:types/x:pous/x:pou[@name='zcr07s_adaptive_pd']", ns)
    body = pou.find("x:body/x:ST/h:p", ns).text
    text = (tmp_path / "zcr07s.st").read_text()
    assert body.startswith("IF reset OR NOT initialised THEN") and body in text
    st_tree(text)
    names = [v.get("name") for v in pou.findall("x:interface/x:inputVars/x:variable", ns)]
    assert names == ["q", "dq", "q_d", "dq_d", "ddq_d", "reset"]
    # a broken project is refused by the schema
    bad = out.read_text().replace('pouType="functionBlock"', 'pouType="block"', 1)
    assert not schema.is_valid(bad)


def test_cli_controller(tmp_path, capsys):
    out = tmp_path / "ctl"
    args = ["codegen", "zcr07s", "--what", "adaptive-pd", "--lang", "c", "--rotor", "--friction"]
    assert main(args + ["-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "whole step" in text and "adjoint" in text
    assert (tmp_path / "ctl.h").is_file() and (tmp_path / "ctl.c").is_file()


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--what", "adaptive-pd,id"], "generated alone"),
        (["--what", "computed-torque", "--box", "0.1"], "adaptive-pd only"),
        (["--what", "adaptive-pd", "--box", "-1"], "--box: expected a finite number >= 0"),
        (["--what", "adaptive-pd", "--controller-period", "0"], "--controller-period"),
        # below the library's least period: said with this command's flag, not identify's
        # --excitation-period (the library's keyword period)
        (
            ["--what", "gravity-compensation", "--controller-period", "1e-9"],
            "--controller-period: expected a finite number in [1e-06, 10]",
        ),
        (
            ["--what", "momentum-observer", "--controller-period", "1e-300"],
            "--controller-period: expected a finite number in [1e-06",
        ),
        (["--what", "adaptive-pd", "--torque-limit", "x"], "--torque-limit"),
        (["--what", "adaptive-pd", "--torque-limit", "effort"], "effort limits"),
        (["--what", "adaptive-pd", "--numeric"], "--numeric"),
        (["--what", "id", "--gains", "g.yaml"], "controller steps only"),
    ],
)
def test_cli_controller_errors(extra, message, tmp_path, capsys):
    assert main(["codegen", "puma560", "--lang", "c", "-o", str(tmp_path / "x")] + extra) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mindyn: error: ") and message in err[0], err


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--wrench-frame", "local"], "--wrench-frame: applies with --contact"),
        (["--contact", "l1"], "--contact: applies to a floating-base robot"),
        (["--what", "adaptive-pd", "--classical-counts"], "--classical-counts: applies to"),
        (["--what", "adaptive-pd", "--observer-gain", "5"], "--observer-gain: applies to"),
        (["--observer-gain", "5"], "--observer-gain: applies to --what momentum-observer"),
        (["--gains", "g.yaml"], "--gains: applies to controller steps only"),
        (["--torque-limit", "5"], "--torque-limit: applies to controller steps only"),
        (["--box", "0.1"], "--box: applies to controller steps only"),
        (["--tracking-tolerance", "0.1"], "--tracking-tolerance: applies to controller steps"),
        (["--controller-period", "0.01"], "--controller-period: applies to controller and"),
        (["--what", "regressor", "--numeric"], "--numeric: applies to the inverse dynamics"),
        (["--what", "adaptive-pd,id"], "--what: a controller step is generated alone"),
        (["--what", "momentum-observer", "--gains", "g.yaml"], "--gains: applies to controller"),
        (["--what", "momentum-observer", "--numeric"], "--numeric: does not apply to the"),
        # the observer's step takes no tracking tolerance (it was ignored)
        (["--what", "momentum-observer", "--tracking-tolerance", "0.1"], "--tracking-tolerance"),
        (["--what", "adaptive-pd", "--numeric"], "--numeric: does not apply to controller"),
        (["--what", "computed-torque", "--box", "0.1"], "--box: applies to --what adaptive-pd"),
        (["--what", "adaptive-pd", "--box", "nan"], "--box: expected a finite number >= 0"),
    ],
)
def test_codegen_option_clashes_are_usage_errors(extra, message, tmp_path, monkeypatch):
    """Options that do not go together, or do not apply to the robot or step asked for, are the
    command line's errors (a UsageError, as the other commands' option clashes), not the robot
    description's (ModelError): one line, exit status 2, the option named first."""
    from mindyn import cli
    from mindyn.cli.args import UsageError

    seen = []
    monkeypatch.setattr(cli, "_error", seen.append)
    argv = ["codegen", "planar2", "--lang", "c", "-o", str(tmp_path / "x")]
    assert main(argv + extra) == 2
    assert len(seen) == 1 and type(seen[0]) is UsageError, repr(seen)
    assert str(seen[0]).startswith(message) and "\n" not in str(seen[0]), seen[0]
    assert not list(tmp_path.iterdir())  # nothing written


def test_bad_settings_are_refused():
    with pytest.raises(ValueError, match="outside"):
        codegen.generate_controller("planar2", params=[1.0] * 11, p_min=2.0)
    with pytest.raises(ValueError, match="'kd'"):
        codegen.generate_controller("planar2", gains={"kd": -1.0})
    with pytest.raises(mindyn.ArgumentError, match="kind is a str 'pid'; expected one of"):
        codegen.generate_controller("planar2", "pid")


def test_computed_torque_with_a_files_kp_alone_is_critically_damped(tmp_path):
    """A gains file giving computed torque's kp and no kd: the generated step's K_D is the
    critically damped 2 sqrt(K_P) its note states (it took the default kd, a torque gain of the
    other controllers). Measured from the C step alone: tau = M(q) v + h(q, dq) with
    v = ddq_d - K_D (dq - dq_d) - K_P (q - q_d), so a step of dq_d moves tau by M K_D (the
    step) and one of ddq_d by M (the step): their ratio is K_D, as one of q_d gives K_P."""
    robot = mindyn.load("planar3")
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    path = tmp_path / "gains.yaml"
    path.write_text("kp: 100.0\n")
    period = 0.004
    g = control.load_gains(path, robot, period=period, rotor=True)
    gen = codegen.generate_controller(robot, "computed-torque", base=base, gains=g, period=period)
    ctl = codegen.CompiledController(gen, base)
    rng = np.random.default_rng(3)
    q, dq, qd, dqd, ddqd = (rng.uniform(-1, 1, robot.n) for _ in range(5))
    tau = ctl(0.0, q, dq, qd, dqd, ddqd)
    for j in range(robot.n):
        e = np.eye(robot.n)[j]
        by_acc = ctl(0.0, q, dq, qd, dqd, ddqd + e) - tau  # M e_j
        by_vel = ctl(0.0, q, dq, qd, dqd + e, ddqd) - tau  # K_D,j M e_j
        by_pos = ctl(0.0, q, dq, qd + e, dqd, ddqd) - tau  # K_P,j M e_j
        k = int(np.argmax(np.abs(by_acc)))
        assert by_pos[k] / by_acc[k] == pytest.approx(100.0, rel=1e-9)
        assert by_vel[k] / by_acc[k] == pytest.approx(2 * np.sqrt(100.0), rel=1e-9)
