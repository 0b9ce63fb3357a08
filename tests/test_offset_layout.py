"""Torque offsets come from the core's parameter layout: their names are spelled in one place,
and the regressors the identification models build carry their columns (known answers: an
offset's column is 1 in its joint's row, its work over a window ``q(t_b) - q(t_a)``, its
integral over a window ``t_b - t_a``)."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import mindyn
import numpy as np
import pytest
from mindyn.identification import models

ROOT = Path(__file__).resolve().parents[1]
NAME = re.compile(r"^Off(\d|\{|$)")  # "Off", "Off1", f"Off{k}": an offset parameter's name


def _python_literals(path: Path) -> list[int]:
    """Lines of string literals (docstrings aside) that begin with an offset's name."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    docstrings = {
        id(node.body[0].value)
        for node in ast.walk(tree)
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
        and node.body
        and isinstance(node.body[0], ast.Expr)
        and isinstance(node.body[0].value, ast.Constant)
    }
    lines = set()  # an f-string's first part is also a Constant of its own
    for node in ast.walk(tree):
        if isinstance(node, ast.JoinedStr):
            first = node.values[0] if node.values else None
            if isinstance(first, ast.Constant) and NAME.match(str(first.value)):
                lines.add(node.lineno)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            if id(node) not in docstrings and NAME.match(node.value):
                lines.add(node.lineno)
    return sorted(lines)


def _cpp_literals(path: Path) -> list[int]:
    """Lines of C++ string literals (comments aside) that begin with an offset's name."""
    lines = []
    for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        code = re.sub(r"//.*", "", line)
        if re.search(r'"Off(\d|"|\{)', code):
            lines.append(i)
    return lines


def test_the_offset_name_is_spelled_in_one_place():
    hits = []
    for path in sorted((ROOT / "python" / "mindyn").rglob("*.py")):
        hits += [f"{path.relative_to(ROOT)}:{n}" for n in _python_literals(path)]
    for folder in ("cpp/include", "cpp/src", "python/src"):
        for path in sorted((ROOT / folder).rglob("*.[ch]pp")):
            hits += [f"{path.relative_to(ROOT)}:{n}" for n in _cpp_literals(path)]
    assert len(hits) == 1 and hits[0].startswith("cpp/include/mindyn/model.hpp:"), hits
    assert mindyn._core.OFFSET_PREFIX == "Off"


def test_the_scan_sees_offset_names_built_in_python(tmp_path):
    src = tmp_path / "m.py"
    src.write_text('"""Off1 in a docstring."""\na = [f"Off{k}" for k in range(3)]\nb = "Off"\n')
    assert _python_literals(src) == [2, 3]


def test_robot_regressor_with_offsets_is_the_regressor_and_identity_columns(rng):
    robot = mindyn.load("puma560")
    n = robot.n
    q, dq, ddq = rng.normal(size=(3, 4, n))
    W = robot.regressor(q, dq, ddq, rotor=True, friction=True)
    Wo = robot.regressor(q, dq, ddq, rotor=True, friction=True, offset=True)
    np.testing.assert_array_equal(Wo[..., : W.shape[-1]], W)
    np.testing.assert_array_equal(Wo[..., W.shape[-1] :], np.broadcast_to(np.eye(n), (4, n, n)))
    names = robot.parameter_names(rotor=True, friction=True, offset=True)
    assert names[-n:] == [f"Off{k + 1}" for k in range(n)]
    assert names[:-n] == robot.parameter_names(rotor=True, friction=True)


def _log(robot, rng, m=401):
    t = np.linspace(0.0, 2.0, m)
    w = rng.uniform(0.5, 2.0, robot.n)
    q = np.sin(np.outer(t, w))
    dq = np.cos(np.outer(t, w)) * w
    ddq = -np.sin(np.outer(t, w)) * w**2
    tau = robot.inverse_dynamics(q, dq, ddq)
    return mindyn.identification.JointData(t=t, q=q, dq=dq, ddq=ddq, tau=tau)


def test_energy_and_integral_models_carry_the_offset_columns(rng):
    robot = mindyn.load("planar2")
    base = mindyn.base_parameters(robot, friction=True, offset=True)
    n = robot.n
    cols = [base.names.index(f"Off{k + 1}") for k in range(n)]
    assert cols == list(range(base.n - n, base.n))
    data = _log(robot, rng)
    window = 40
    W, _ = models.energy_system(base, data, window=window)
    ends = np.arange(0, data.m, window)
    np.testing.assert_allclose(W[:, cols], np.diff(data.q[ends], axis=0), rtol=0, atol=1e-12)
    a, b = models.windows(data, window)
    Wi, _ = models.integral_system(base, data, window=window)
    expected = np.zeros((a.size, n, n))
    expected[:, range(n), range(n)] = (data.t[b] - data.t[a])[:, None]
    np.testing.assert_allclose(Wi[:, :, cols], expected, rtol=0, atol=1e-12)


LIFT = """<?xml version="1.0"?>
<robot name="lift">
  <link name="base"/>
  <link name="carriage">
    <inertial>
      <origin xyz="0.1 0 0.05"/>
      <mass value="3.0"/>
      <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/>
    </inertial>
  </link>
  <joint name="lift" type="prismatic">
    <parent link="base"/>
    <child link="carriage"/>
    <axis xyz="0 0 1"/>
    <limit lower="0" upper="1" effort="100" velocity="1"/>
  </joint>
</robot>
"""


def test_a_vertical_lift_regroups_its_mass_into_the_offset(tmp_path):
    # tau = M (ddq + g) + Ia ddq + Off = (Ia + M) ddq + (Off + g M): two base parameters, by hand
    path = tmp_path / "lift.urdf"
    path.write_text(LIFT)
    robot = mindyn.load(path)
    g = 9.81
    for method in ("projection", "recursive", "numerical"):
        bp = mindyn.base_parameters(robot, rotor=True, offset=True, method=method)
        assert bp.names == ["IaR1", "OffR1"], method
        names = bp.classical_names
        Y = np.zeros((2, len(names)))
        Y[0, names.index("Ia1")] = Y[0, names.index("M1")] = 1.0
        Y[1, names.index("Off1")], Y[1, names.index("M1")] = 1.0, g
        np.testing.assert_allclose(bp.Y, Y, rtol=0, atol=1e-9, err_msg=method)
    # without rotor inertia the mass column ddq + g is not constant: M1 and Off1 stay apart
    assert mindyn.base_parameters(robot, offset=True).names == ["M1", "Off1"]


def test_symbolic_formulas_refuse_offsets_that_took_link_parameters(tmp_path):
    path = tmp_path / "lift.urdf"
    path.write_text(LIFT)
    bp = mindyn.base_parameters(mindyn.load(path), rotor=True, offset=True)
    with pytest.raises(mindyn.Error, match="torque offsets OffR1 of 'lift' take link parameters"):
        bp.symbolic()


def test_asymmetric_friction_stays_apart_from_the_offset():
    # Fa |sign(dq)| is 1 while the joint moves but 0 at rest: not the constant column of Off
    robot = mindyn.load("puma560").with_friction_model("asymmetric")
    bp = mindyn.base_parameters(robot, friction=True, offset=True)
    without = mindyn.base_parameters(robot, friction=True)
    assert bp.names == without.names + [f"Off{k + 1}" for k in range(robot.n)]
