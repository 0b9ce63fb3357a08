"""The generated controller steps checked with their own model: a step generated without the
rotor inertia that the default gains assume (a geared joint's reflected rotor inertia dominates
its link's) has computed torque's torque gains scaled down by the ratio, and a joint's Coulomb
friction is then no longer held within the stated tolerance."""

from __future__ import annotations

import math
import re

import mindyn
import numpy as np
from mindyn.cli import main
from mindyn.control import controllers

ZZ2, IA2, FC2 = 1e-3, 0.1, 1.0  # link 2's inertia about its axis, its rotor's, its friction


def geared_yaml(path) -> str:
    """Two joints about vertical axes (no gravity torque); link 2's centre of mass on its axis,
    so that M_22 = ZZ2 + Ia2 everywhere (closed form)."""
    path.write_text(f"""\
name: geared2
convention: mdh
angle_unit: deg
joints:
  - name: j1
    alpha: 0
    d: 0
    theta: 0
    r: 0
    limits: {{lower: -170, upper: 170, velocity: 90, effort: 100}}
    inertial: {{mass: 5.0, com: [0.2, 0, 0], inertia: {{xx: 0.01, yy: 0.05, zz: 0.05}}}}
    rotor_inertia: 0.5
  - name: j2
    alpha: 0
    d: 0.4
    theta: 0
    r: 0
    limits: {{lower: -170, upper: 170, velocity: 180, effort: 20}}
    inertial: {{mass: 0.5, com: [0, 0, 0], inertia: {{xx: {ZZ2}, yy: {ZZ2}, zz: {ZZ2}}}}}
    rotor_inertia: {IA2}
    friction: {{viscous: 0.0, coulomb: {FC2}}}
""")
    return str(path)


def test_model_friction_shortfall_against_the_closed_form(tmp_path):
    robot = mindyn.load(geared_yaml(tmp_path / "g.yaml"))
    tol = math.radians(2.0)
    kp_min = 2 * FC2 / (0.5 * tol)  # the friction bound on joint 2 [N m/rad]
    kp = np.array([100.0, kp_min / (ZZ2 + IA2)])  # computed torque's gain, 1/s^2
    whole = mindyn.base_parameters(robot, rotor=True, friction=True)
    p_whole = whole.values(robot.parameters(rotor=True, friction=True))
    assert controllers.model_friction_shortfall(robot, whole, p_whole, kp) == ""
    bare = mindyn.base_parameters(robot)
    text = controllers.model_friction_shortfall(robot, bare, bare.values(robot.parameters()), kp)
    gain = ZZ2 * kp[1]  # the model's M_22 = ZZ2 without the rotor
    error = math.degrees(2 * FC2 / gain)
    assert "joint(s) 2 (" in text and "joint(s) 1" not in text, text
    assert f"{gain:.3g} N m/rad against {kp_min:.3g} N m/rad" in text, text
    assert f"errors up to {error:.3g} deg" in text, text
    assert "within half the tracking tolerance" in text, text
    # an error between half the tolerance and the whole: short of the default gains' bound,
    # within the whole tolerance
    kp_between = np.array([100.0, 0.75 * kp_min / ZZ2])  # error 2 Fc / (0.75 kp_min) = 4/3 deg
    p_bare = bare.values(robot.parameters())
    assert "joint(s) 2 (" in controllers.model_friction_shortfall(robot, bare, p_bare, kp_between)
    assert controllers.model_friction_shortfall(robot, bare, p_bare, kp_between, share=1) == ""


def test_codegen_checks_the_model_it_generates(tmp_path, capsys):
    """The default gains assume the robot's rotor inertia; a computed-torque step generated
    without it is warned about, naming the joint, the torque gain and the error; with
    --rotor --friction nothing is."""
    path = geared_yaml(tmp_path / "g.yaml")
    argv = ["codegen", path, "--lang", "c", "--what", "computed-torque"]
    assert main([*argv, "-o", str(tmp_path / "bare")]) == 0
    out, err = capsys.readouterr()
    assert "generated step (its model without rotor inertia and friction)" in out, out
    warning = [line for line in err.splitlines() if "warning" in line]
    assert len(warning) == 1 and "joint(s) 2 (" in warning[0], err
    assert "--rotor puts the robot's rotor inertia into the model" in warning[0]
    assert "within the whole tracking tolerance" in warning[0]
    # the default gains raise Lambda_2 until (ZZ2 + Ia2) Lambda^2 reaches the friction bound
    # (or above it): the model's torque gain is ZZ2 Lambda^2, at most 1 / 101 of the bound
    gain = float(re.search(r"joint\(s\) 2 \(([0-9.e+]+) N m/rad", warning[0]).group(1))
    kp_min = 2 * FC2 / (0.5 * math.radians(2.0))
    lam = float(re.search(r"Lambda \[[^,]+, ([0-9.e+]+)\]", out).group(1))
    assert gain == float(f"{ZZ2 * lam**2:.3g}")
    assert lam**2 * (ZZ2 + IA2) >= kp_min * (1 - 1e-3)
    assert main([*argv, "--rotor", "--friction", "-o", str(tmp_path / "whole")]) == 0
    out, err = capsys.readouterr()
    assert "warning" not in err and "generated step (" not in out, (out, err)


def test_simulate_checks_a_compiled_step_given_no_base():
    """simulate checked the sampled loop of a compiled generated step only when it was given
    its base: without, a step whose gains no sampled loop of the robot keeps stable ran until
    it diverged. It is now refused before the run, as with its base, and the result of a stable
    one states the check."""
    import pytest
    from mindyn import codegen, control

    robot = mindyn.load("planar3")
    ref = control.SumOfSines(robot, period=2.0)
    gains = {"kd": 4000.0, "lambda": 10.0, "gamma": 1.0}
    code = codegen.generate_controller(robot, "adaptive-pd", gains=gains, p_min=-np.inf)
    # independent: a sampled loop without friction needs max eig(T M^-1 K_D) < 2 at rest
    m = robot.mass_matrix(np.zeros(robot.n), robot.parameters(rotor=True, friction=True))
    assert np.max(np.linalg.eigvals(0.004 * np.linalg.solve(m, 4000.0 * np.eye(3))).real) > 2
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    messages = []
    for given in (base, None):
        with pytest.raises(control.UnstableLoopError) as e:
            control.simulate(robot, ref, codegen.CompiledController(code, base=given), duration=1)
        messages.append(str(e.value))
    assert messages[0] == messages[1]
    stable = codegen.generate_controller(robot, "adaptive-pd", p_min=-np.inf)
    res = control.simulate(robot, ref, codegen.CompiledController(stable), duration=0.2)
    assert "stable" in res.info["stability"]
