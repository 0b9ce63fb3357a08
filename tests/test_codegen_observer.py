"""The generated momentum-observer step against the library's observer.

The C step (gcc -std=c99 -Wall -Wextra -Werror -pedantic) and the Structured Text function block
(run by the tree-sitter evaluator of test_codegen, its state kept from call to call) are run over
a few hundred cycles of a motion with random torques beside mindyn.control.MomentumObserver, whose
momentum and beta come from the runtime regressors (a different computation: classical regressors
times the base-parameter map), and compared at every cycle."""

from __future__ import annotations

import re

import mindyn
import numpy as np
import pytest
from conftest import assert_close
from mindyn import codegen, control
from random_tree import random_tree_urdf
from test_codegen import st_tree
from test_codegen_controller import GCC, STBlock, strict_compile
from test_codegen_drive import coupled6r, drive_values

pytestmark = pytest.mark.skipif(GCC is None, reason="gcc is needed to compile generated C")


def motion(robot, cycles, period, seed):
    """A smooth motion (sum of sines) and random torques."""
    ref = control.SumOfSines(robot, period=1.0, fraction=0.4, seed=seed)
    q, dq, _ = ref.evaluate(np.arange(cycles) * period)
    tau = np.random.default_rng(seed).normal(0, 5.0, q.shape)
    return q, dq, tau


def library_and_generated(robot, base, values, gains, period, held, cycles, seed, trig=None):
    obs = control.MomentumObserver(base, values, period=period, gains=gains, held_torque=held)
    code = codegen.generate_observer(
        robot, base=base, params=values, period=period, gains=gains, held_torque=held, trig=trig
    )
    c = codegen.CompiledObserver(code)
    q, dq, tau = motion(robot, cycles, period, seed)
    want = obs.run(q, dq, tau)
    got = np.array([c(q[i], dq[i], tau[i]) for i in range(cycles)])
    return got, want, code


@pytest.mark.parametrize("held", [True, False])
def test_c_step_equals_the_library_zcr07s(held):
    """ZCR07S with rotor inertia, friction and offsets, 300 cycles at 1 ms."""
    robot = mindyn.load("zcr07s")
    base = mindyn.base_parameters(robot, rotor=True, friction=True, offset=True)
    values = base.values(robot.parameters(rotor=True, friction=True))
    values[-robot.n :] = np.linspace(-0.5, 0.5, robot.n)  # the offsets
    gains = np.linspace(50.0, 400.0, robot.n)
    got, want, _ = library_and_generated(robot, base, values, gains, 1e-3, held, 300, 1)
    assert np.abs(want).max() > 1.0  # the residual moves
    assert_close(got, want, 1e-12, "generated observer (C) vs library")


def test_c_step_equals_the_library_tree(tmp_path):
    robot = mindyn.load(random_tree_urdf(tmp_path / "tree.urdf", 6, seed=2))
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    values = base.values(robot.parameters(rotor=True, friction=True))
    got, want, _ = library_and_generated(robot, base, values, None, 2e-3, True, 200, 5)
    assert_close(got, want, 1e-12, "generated observer (C, tree) vs library")


@pytest.mark.parametrize("kind, held", [("stribeck", True), ("smooth", False)])
def test_c_and_st_steps_with_drive_terms_on_coupled_motors(kind, held, tmp_path, rng):
    """A 6R with a four-bar wrist (motor 6 turns with q5 + q6), rotor inertia and friction on
    the motors (Stribeck or smooth), base parameters with offsets: 300 C and ST cycles against
    the library, whose p and beta come from the runtime regressors. The drive terms matter: the
    same motion with the motors' rotor and friction values zeroed gives another residual."""
    path = tmp_path / "coupled6r.urdf"
    path.write_text(coupled6r())
    robot = mindyn.load(path)
    T = robot.transmission.T
    assert robot.drive_side == "motor" and np.count_nonzero(T[5]) == 2
    robot = robot.with_friction_model(kind, velocity=0.5 * np.abs(T).sum(axis=1))
    base = mindyn.base_parameters(robot, rotor=True, friction=True, offset=True)
    per = 14 if kind == "stribeck" else 13
    pi = drive_values(robot, rng, per)
    values = base.values(pi)
    values[-robot.n :] = np.linspace(-0.2, 0.3, robot.n)  # the offsets
    period, cycles = 1e-3, 300
    got, want, code = library_and_generated(robot, base, values, None, period, held, cycles, 7)
    assert np.abs(want).max() > 1.0
    assert_close(got, want, 1e-12, f"generated observer (C, motors, {kind}) vs library")
    fn = "exp" if kind == "stribeck" else "tanh"  # one per motor, the coupled m5, m6 too
    count = robot.n
    assert code.counts["step"][fn] == count and f", {count} {fn}" in code.header
    assert "m6 = " in code.header and f"Fc {'sign' if fn == 'exp' else 'tanh'}(v" in code.header
    st = codegen.generate_observer(
        robot, lang="st", base=base, params=values, period=period, held_torque=held
    )
    block = STBlock(st_tree(st.text), st.function)
    q, dq, tau = motion(robot, cycles, period, 7)
    st_r = [block({"q": q[i], "dq": dq[i], "tau": tau[i]})["r_out"].copy() for i in range(cycles)]
    assert_close(np.array(st_r), want, 1e-12, f"generated observer (ST, motors, {kind}) vs library")
    drive = pi.copy()
    for k in range(robot.n):
        drive[k * per + 10 : (k + 1) * per] = 0.0
    rigid = base.values(drive)
    rigid[-robot.n :] = values[-robot.n :]
    other = control.MomentumObserver(base, rigid, period=period, held_torque=held).run(q, dq, tau)
    assert np.abs(other - want).max() > 1e-3 * np.abs(want).max()


def test_c_step_compiles_strictly_without_allocation(tmp_path):
    robot = mindyn.load("zcr07s")
    code = codegen.generate_observer(robot, period=1e-3)
    strict_compile(code, tmp_path)
    includes = re.findall(r"#include [<\"](.+?)[>\"]", code.source + code.header)
    assert includes == [code.header_name, "math.h"]
    assert not re.search(r"\b(malloc|calloc|realloc|free)\(", code.source)
    assert code.counts["step"]["mul"] > code.counts["momentum"]["mul"] > 0
    assert "Per step" in code.header


def test_structured_text_step_equals_the_library():
    """puma560 with rotor inertia, friction and offsets: 300 ST cycles against the library and
    the C step, then a reset restarts the observer."""
    robot = mindyn.load("puma560")
    base = mindyn.base_parameters(robot, rotor=True, friction=True, offset=True)
    values = base.values(robot.parameters(rotor=True, friction=True))
    values[-robot.n :] = 0.3  # the offsets
    period, cycles = 2e-3, 300
    st = codegen.generate_observer(robot, lang="st", base=base, params=values, period=period)
    statements = re.sub(r"\(\*.*?\*\)", "", st.text, flags=re.DOTALL)
    assert set(re.findall(r"\b([A-Za-z_]\w*)\(", statements)) <= {"SIN", "COS"}
    block = STBlock(st_tree(st.text), st.function)
    obs = control.MomentumObserver(base, values, period=period)
    q, dq, tau = motion(robot, cycles, period, 4)
    want = obs.run(q, dq, tau)
    got = np.array(
        [block({"q": q[i], "dq": dq[i], "tau": tau[i]})["r_out"].copy() for i in range(cycles)]
    )
    assert np.abs(want).max() > 1.0
    assert_close(got, want, 1e-12, "generated observer (ST) vs library")
    out = block({"q": q[5], "dq": dq[5], "tau": tau[5], "reset": True})["r_out"]
    assert np.all(out == 0.0)


def test_bad_observer_settings_are_refused():
    robot = mindyn.load("puma560")
    with pytest.raises(mindyn.ArgumentError, match="gains gives observer gain K_O of joint 1"):
        codegen.generate_observer(robot, period=1e-3, gains=2000.0)
    with pytest.raises(mindyn.Error, match="params"):
        codegen.generate_observer(robot, params=[1.0, 2.0])


def test_structured_text_observer_passes_blark():
    """The function block through a second, independent ST grammar (one joint with friction:
    blark takes about 20 ms per statement)."""
    blark = pytest.importorskip("blark")
    robot = mindyn.load("planar1")
    base = mindyn.base_parameters(robot, rotor=True, friction=True, offset=True)
    st = codegen.generate_observer(robot, lang="st", base=base, period=1e-3)
    result = blark.parse_source_code(st.text[st.text.index("FUNCTION_BLOCK") :])
    assert result.exception is None, result.exception
