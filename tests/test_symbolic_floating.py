"""Symbolic regrouping formulas of a floating-base robot (a URDF with ``root_joint`` floating or
planar): the description is rebuilt at other lengths with its root joint as it is.

The robot: a free (or planar) body carrying a two-link arm. The formulas, evaluated at other
lengths, give base parameters whose regressor reproduces Pinocchio's inverse dynamics of that
robot, and the total mass of the robot is a base parameter of the root body. A description
whose base set changes with its lengths (ANYmal) is refused naming the parameters that change."""

from __future__ import annotations

import mindyn
import numpy as np
import pinocchio as pin
import pytest


def urdf(x2=0.1, y2=0.05, x3=0.3) -> str:
    def inertial(m, c):
        return (
            f'<inertial><origin xyz="{c}"/><mass value="{m}"/><inertia ixx="0.01" ixy="0.001" '
            'ixz="0" iyy="0.02" iyz="0.002" izz="0.03"/></inertial>'
        )

    def joint(name, parent, child, xyz, rpy):
        return (
            f'<joint name="{name}" type="revolute"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="0 0 1"/>'
            '<limit lower="-3" upper="3" effort="10" velocity="5"/></joint>'
        )

    return (
        '<robot name="floating_arm">'
        f'<link name="base">{inertial(2.0, "0.01 0.02 0.03")}</link>'
        + joint("j1", "base", "l1", f"{x2} {y2} 0", "0 0 0")
        + f'<link name="l1">{inertial(1.0, "0.1 0 0.01")}</link>'
        + joint("j2", "l1", "l2", f"{x3} 0 0", "1.5707963267948966 0 0")
        + f'<link name="l2">{inertial(0.5, "0.1 0.02 0")}</link></robot>'
    )


@pytest.mark.parametrize("root", ["floating", "planar"])
def test_floating_root_symbolic_formulas_at_other_lengths(tmp_path, root):
    path = tmp_path / "r.urdf"
    path.write_text(urdf())
    robot = mindyn.load(path, root_joint=root)
    bp = mindyn.base_parameters(robot)
    sym = bp.symbolic()  # refused before: the root was rebuilt as a prismatic joint
    assert list(sym.symbols) == ["x2", "y2", "x3"]
    assert sym.names == bp.names
    # the root body's mass parameter is the total mass
    total = next(str(f) for f in sym.formulas if str(f).startswith("MR1 "))
    assert total.replace(" ", "") == "MR1=M1+M2+M3"
    joint = pin.JointModelFreeFlyer() if root == "floating" else pin.JointModelPlanar()
    rng = np.random.default_rng(3)
    for _ in range(3):
        x2, y2, x3 = rng.uniform(0.2, 1.2, 3) * rng.choice([-1.0, 1.0], 3)
        other_path = tmp_path / "o.urdf"
        other_path.write_text(urdf(x2, y2, x3))
        other = mindyn.load(other_path, root_joint=root)
        ob = mindyn.base_parameters(other, method="numerical")
        assert ob.names == bp.names
        values = sym.evaluate([x2, y2, x3]) @ other.params
        model = pin.buildModelFromXML(urdf(x2, y2, x3), joint)
        data = model.createData()
        q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
        v, a = rng.uniform(-2, 2, (2, model.nv))
        tau = pin.rnea(model, data, q, v, a)
        np.testing.assert_allclose(ob.regressor(q, v, a) @ values, tau, rtol=1e-9, atol=1e-9)


def test_a_base_set_that_changes_with_the_lengths_names_the_parameters():
    """ANYmal's lengths are special: at the general lengths the symbolic fit draws, its base set
    has as many parameters but named otherwise (regrouped or not). The refusal said '68 ... with
    the description's lengths, 68 with others', as if nothing changed; it names them now: those
    it lost are the description's base parameters, those it gained are not."""
    import re

    from test_multibody import FLOATING

    robot = mindyn.load(FLOATING["anymal"])
    bp = mindyn.base_parameters(robot)
    with pytest.raises(mindyn.ModelError) as info:
        bp.symbolic()
    message = str(info.value)
    assert f"({bp.n} base parameters with the description's lengths, {bp.n} with others" in message
    found = re.search(r"with others; (.*?) in place of (.*?)\)", message)
    assert found, message
    gained = [s for s in found.group(1).split(", ") if s != "..."]
    lost = [s for s in found.group(2).split(", ") if s != "..."]
    assert gained and lost
    assert all(name in bp.names for name in lost) and not set(gained) & set(bp.names)
