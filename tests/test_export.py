"""Identified parameters written back as a robot description (mindyn.export, ``mindyn export``).

References: Pinocchio's own URDF parser and RNEA on the written file (independent of mindyn's
loader and its merging of fixed links), and the parameters the test itself drew. A URDF written
with the parameters a robot was loaded with must have the dynamics of the source URDF (Pinocchio
on both files), and one written with random physically consistent parameters must have mindyn's
inverse dynamics with those parameters. Thresholds: the Pinocchio comparisons run at 1e-9
relative (the target); double round-off in both recursions gives about 1e-14 here, so the margin
is five orders. Parameters read back must be the ones written: the mass exactly, the first
moments m (h / m) to two ulp, and the inertia about the link origin, which goes through the
centre of mass (I_c = I_o - [h]^T [h] / m on writing, back on reading), to 1e-15 of the link's
largest term |I_o| + |h|^2 / m (90 random links of the tree, Panda and UR5 gave at most 2.1e-16,
one ulp; margin about five).
"""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import mindyn
import numpy as np
import pinocchio as pin
import pytest
import yaml
from conftest import ROBOTS_DIR, URDFS, assert_close
from mindyn import cli
from mindyn.export import classical_terms, read_joint_terms, write_urdf, write_yaml
from mindyn.mjcf import write_mjcf
from random_arm import random_arm_yaml
from random_tree import com_inertia

REPO = Path(__file__).resolve().parents[1]
UR5 = REPO / "examples/urdf/ur5.urdf"
TOL_DYN = 1e-9
TOL_INERTIA = 1e-15

# A tree: a fixed pedestal with an inertial (before the first moving joint: kept), a second arm
# off the pedestal (off the chain: kept), fixed joints inside the chain (l1 -> l1b), a sensor on
# a fixed branch of l2, a finger on a moving joint off the chain (locked at its lower limit
# 0.1, clamping q = 0), a tool on a fixed joint at the tip; unaligned axes, a prismatic joint.
TREE = """<?xml version="1.0"?>
<!-- a test tree: this comment stays -->
<robot name="tree" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <link name="world"/>
  <joint name="pedestal" type="fixed">
    <parent link="world"/><child link="base"/>
    <origin xyz="0.1 0 0.3" rpy="0 0 0.2"/>
  </joint>
  <link name="base">
    <inertial>
      <mass value="20"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/>
    </inertial>
  </link>
  <joint name="other" type="revolute">
    <parent link="base"/><child link="other_link"/>
    <origin xyz="0 0.4 0" rpy="0 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/>
  </joint>
  <link name="other_link">
    <!-- off the chain -->
    <inertial>
      <origin xyz="0 0 0.1" rpy="0 0 0"/><mass value="1.5"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/>
    </inertial>
  </link>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.2" rpy="0.1 -0.2 0.3"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="100" velocity="2"/>
    <dynamics damping="0.5" friction="0.25"/>
  </joint>
  <link name="l1">
    <inertial>
      <origin xyz="0.01 0.02 0.1" rpy="0.3 0.2 0.1"/><mass value="3"/>
      <inertia ixx="0.05" ixy="0.001" ixz="-0.002" iyy="0.04" iyz="0.003" izz="0.03"/>
    </inertial>
  </link>
  <joint name="f1" type="fixed">
    <parent link="l1"/><child link="l1b"/>
    <origin xyz="0.05 0 0.3" rpy="0.5 0 0.4"/>
  </joint>
  <link name="l1b">
    <inertial>
      <origin xyz="0 0.03 0.02" rpy="0 0.4 0"/><mass value="1.2"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.012" iyz="0" izz="0.008"/>
    </inertial>
  </link>
  <joint name="j2" type="revolute">
    <parent link="l1b"/><child link="l2"/>
    <origin xyz="0.1 0.02 0.05" rpy="1.2 0.1 -0.3"/><axis xyz="0.3 -0.5 0.8"/>
    <limit lower="-2" upper="2" effort="100" velocity="2"/>
  </joint>
  <link name="l2">
    <inertial>
      <origin xyz="0.2 0 0.01" rpy="0 0 0"/><mass value="2.5"/>
      <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.09" iyz="0" izz="0.09"/>
    </inertial>
  </link>
  <joint name="sensor_mount" type="fixed">
    <parent link="l2"/><child link="sensor"/>
    <origin xyz="0.1 0.05 0" rpy="0 1.0 0"/>
  </joint>
  <link name="sensor">
    <inertial>
      <origin xyz="0 0 0.01" rpy="0 0 0"/><mass value="0.3"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/>
    </inertial>
  </link>
  <joint name="j3" type="prismatic">
    <parent link="l2"/><child link="l3"/>
    <origin xyz="0.4 0 0" rpy="0 1.5707963267948966 0"/><axis xyz="0 0 1"/>
    <limit lower="0" upper="0.3" effort="100" velocity="1"/>
    <dynamics damping="2"/>
  </joint>
  <link name="l3">
    <inertial>
      <origin xyz="0 0 0.05" rpy="0 0 0"/><mass value="1.0"/>
      <inertia ixx="0.004" ixy="0" ixz="0" iyy="0.004" iyz="0" izz="0.001"/>
    </inertial>
  </link>
  <joint name="finger" type="prismatic">
    <parent link="l3"/><child link="finger_link"/>
    <origin xyz="0 0.02 0.1" rpy="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="0.1" upper="0.5" effort="10" velocity="1"/>
  </joint>
  <link name="finger_link">
    <inertial>
      <origin xyz="0 0.01 0" rpy="0 0 0"/><mass value="0.2"/>
      <inertia ixx="0.0001" ixy="0" ixz="0" iyy="0.0001" iyz="0" izz="0.0001"/>
    </inertial>
  </link>
  <joint name="tool_mount" type="fixed">
    <parent link="l3"/><child link="tool"/>
    <origin xyz="0 0 0.15" rpy="0 0 0"/>
  </joint>
  <link name="tool">
    <inertial>
      <origin xyz="0 0 0.02" rpy="0 0 0"/><mass value="0.5"/>
      <inertia ixx="0.0005" ixy="0" ixz="0" iyy="0.0005" iyz="0" izz="0.0005"/>
    </inertial>
  </link>
</robot>
"""
TREE_LOCKED = {"finger": 0.1, "other": 0.0}  # where mindyn's loader locks the off-chain joints


@pytest.fixture
def tree(tmp_path) -> Path:
    path = tmp_path / "tree.urdf"
    path.write_text(TREE)
    return path


def consistent_params(robot: mindyn.Robot, rng, rotor=True, friction=True) -> dict:
    """Random physically consistent classical parameters as a name map: positive masses,
    centres of mass within 0.3 m, COM inertias of random orientation meeting the triangle
    inequalities; rotor inertia and friction positive."""
    p = []
    for _ in range(robot.n):
        m = rng.uniform(0.5, 5.0)
        inertia = com_inertia(rng, m, 0.3)
        p.append(mindyn.inertial_from_com(m, rng.uniform(-0.3, 0.3, 3), inertia))
    values = dict(zip(robot.param_names, np.concatenate(p)))
    for k in range(1, robot.n + 1):
        if rotor:
            values[f"Ia{k}"] = rng.uniform(0.01, 1.0)
        if friction:
            values[f"Fv{k}"] = rng.uniform(0.1, 5.0)
            values[f"Fc{k}"] = rng.uniform(0.1, 5.0)
    return values


def inertial_vector(robot: mindyn.Robot, classical: dict) -> np.ndarray:
    return np.array([classical[k] for k in robot.param_names])


def pin_chain(urdf: Path, robot: mindyn.Robot, locked: dict[str, float]) -> pin.Model:
    """Pinocchio's model of `urdf`, reduced to the robot's chain with the other joints locked."""
    full = pin.buildModelFromUrdf(str(urdf))
    q0 = pin.neutral(full)
    for name, value in locked.items():
        q0[full.joints[full.getJointId(name)].idx_q] = value
    lock = [full.getJointId(j) for j in list(full.names)[1:] if j not in robot.joint_names]
    model = pin.buildReducedModel(full, lock, q0) if lock else full
    assert list(model.names)[1:] == robot.joint_names
    model.gravity = pin.Motion(np.asarray(robot.gravity, dtype=float), np.zeros(3))
    return model


def pin_rnea(model: pin.Model, q, dq, ddq) -> np.ndarray:
    return np.array([pin.rnea(model, model.createData(), *s).copy() for s in zip(q, dq, ddq)])


def states(robot: mindyn.Robot, rng, m: int = 5):
    lim = robot.limits
    lo = np.where(np.isfinite(lim["lower"]), lim["lower"], -np.pi)
    hi = np.where(np.isfinite(lim["upper"]), lim["upper"], np.pi)
    return (
        rng.uniform(lo, hi, (m, robot.n)),
        rng.uniform(-2, 2, (m, robot.n)),
        rng.uniform(-2, 2, (m, robot.n)),
    )


def assert_inertial_roundtrip(robot: mindyn.Robot, got: np.ndarray, want: np.ndarray) -> None:
    """Mass and first moments exact to an ulp; inertia about the origin to TOL_INERTIA of the
    link's scale |I_o| + m |c|^2 (see the module docstring)."""
    for k in range(robot.n):
        g, w = got[10 * k : 10 * k + 10], want[10 * k : 10 * k + 10]
        assert g[9] == w[9], f"M{k + 1}"
        np.testing.assert_allclose(g[6:9], w[6:9], rtol=4.5e-16, atol=0, err_msg=f"link {k + 1}")
        scale = np.abs(w[:6]).max() + (np.dot(w[6:9], w[6:9]) / w[9] if w[9] else 0.0)
        err = np.abs(g[:6] - w[:6]).max() / scale if scale else np.abs(g[:6]).max()
        assert err <= TOL_INERTIA, f"link {k + 1}: inertia off by {err:.2e} of {scale:.3g}"


# -- URDF ---------------------------------------------------------------------------------------
def test_tree_own_parameters_keep_the_source_dynamics(tree, tmp_path):
    """Exporting the parameters mindyn merged from the tree: Pinocchio, merging the source's
    fixed links itself, gives the same torques on the source and on the written file."""
    robot = mindyn.load(tree, tip="tool")
    assert robot.link_names == ["world", "l1", "l2", "l3"]
    out = tmp_path / "own.urdf"
    res = write_urdf(robot, robot.params, out)
    # no friction in the parameters: the source's damping and friction (j1, j3) written as 0
    joints = {e.get("name"): e for e in _parse(out).iter("joint")}
    for name in ("j1", "j3"):
        dyn = joints[name].find("dynamics")
        assert float(dyn.get("damping")) == 0.0 and float(dyn.get("friction")) == 0.0, name
    assert joints["j2"].find("dynamics") is None  # none in the source, none written
    said = [n for n in res.notes if "the parameters have no friction" in n]
    assert said and "'j1', 'j3'" in said[0] and "'j2'" not in said[0], res.notes
    rng = np.random.default_rng(1)
    q, dq, ddq = states(robot, rng)
    want = pin_rnea(pin_chain(tree, robot, TREE_LOCKED), q, dq, ddq)
    got = pin_rnea(pin_chain(out, robot, TREE_LOCKED), q, dq, ddq)
    assert_close(got, want, TOL_DYN, "export: tree own params, Pinocchio source vs written")


def test_tree_random_parameters(tree, tmp_path):
    robot = mindyn.load(tree, tip="tool")
    rng = np.random.default_rng(2)
    classical = consistent_params(robot, rng)
    out = tmp_path / "out" / "tree_id.urdf"
    res = write_urdf(robot, classical, out)
    p = inertial_vector(robot, classical)
    q, dq, ddq = states(robot, rng)
    got = pin_rnea(pin_chain(out, robot, TREE_LOCKED), q, dq, ddq)
    assert_close(got, robot.inverse_dynamics(q, dq, ddq, p), TOL_DYN, "export: tree vs Pinocchio")

    # read back by mindyn's loader (urdfdom): the same classical parameters
    back = mindyn.load(out, tip="tool")
    assert_inertial_roundtrip(robot, back.params, p)
    np.testing.assert_array_equal(back.viscous, [classical[f"Fv{k}"] for k in (1, 2, 3)])
    np.testing.assert_array_equal(back.coulomb, [classical[f"Fc{k}"] for k in (1, 2, 3)])
    for k in range(robot.n):  # geometry untouched
        np.testing.assert_array_equal(back.joint_transform(k, 0.3), robot.joint_transform(k, 0.3))
    np.testing.assert_array_equal(back.tool, robot.tool)

    # the sidecar holds every joint term, with its unit
    assert res.sidecar == out.with_name("tree_id.joints.yaml")
    terms = read_joint_terms(res.sidecar)
    assert terms == {k: v for k, v in classical.items() if k[:2] in ("Ia", "Fv", "Fc")}
    doc = yaml.safe_load(res.sidecar.read_text())
    assert [j["units"]["Ia"] for j in doc["joints"]] == ["kg m^2", "kg m^2", "kg"]
    assert set(doc["terms"]) == {"Ia", "Fv", "Fc"}


def test_tree_merged_links_emptied_and_the_rest_kept(tree, tmp_path):
    robot = mindyn.load(tree, tip="tool")
    out = tmp_path / "tree_id.urdf"
    res = write_urdf(robot, consistent_params(robot, np.random.default_rng(3)), out)
    text = out.read_text()
    assert text.startswith('<?xml version="1.0"?>\n<!-- a test tree: this comment stays -->\n')
    assert "<!-- off the chain -->" in text
    links = {e.get("name"): e for e in _parse(out).iter("link")}
    for name in ("l1b", "sensor", "finger_link", "tool"):  # merged into l1, l2, l3
        assert links[name].find("inertial") is None, name
    src = {e.get("name"): e for e in _parse(tree).iter("link")}
    for name in ("base", "other_link"):  # before the chain, off the chain
        assert _text(links[name]) == _text(src[name]), name
    assert any("finger_link, tool" in note for note in res.notes), res.notes
    # the whole tree, moving the off-chain joints too, still loads in Pinocchio
    full = pin.buildModelFromUrdf(str(out))
    assert full.nq == 5


def test_ur5_example(tmp_path):
    robot = mindyn.load(UR5)
    rng = np.random.default_rng(4)
    classical = consistent_params(robot, rng, rotor=False, friction=False)
    out = tmp_path / "ur5_id.urdf"
    res = write_urdf(robot, classical, out)
    assert res.sidecar is None  # no joint terms, nothing beside the URDF
    p = inertial_vector(robot, classical)
    q, dq, ddq = states(robot, rng)
    got = pin_rnea(pin_chain(out, robot, {}), q, dq, ddq)
    assert_close(got, robot.inverse_dynamics(q, dq, ddq, p), TOL_DYN, "export: ur5 vs Pinocchio")
    back = mindyn.load(out)
    assert_inertial_roundtrip(robot, back.params, p)
    assert not back.viscous.any() and not back.coulomb.any()


def test_panda_hand_with_fingers(tmp_path):
    """example-robot-data's Panda to the hand: link8, the hand, its TCP frame and both fingers
    (off-chain prismatic joints, locked at 0) merged into link 7."""
    src = URDFS["panda"]
    robot = mindyn.load(src, tip="panda_hand")
    locked = {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}
    rng = np.random.default_rng(12)
    q, dq, ddq = states(robot, rng)
    own = tmp_path / "own.urdf"
    write_urdf(robot, robot.params, own)
    want = pin_rnea(pin_chain(src, robot, locked), q, dq, ddq)
    got = pin_rnea(pin_chain(own, robot, locked), q, dq, ddq)
    assert_close(got, want, TOL_DYN, "export: panda own params, Pinocchio source vs written")
    classical = consistent_params(robot, rng)
    out = tmp_path / "panda_id.urdf"
    res = write_urdf(robot, classical, out)
    assert "panda_leftfinger, panda_rightfinger" in res.notes[-1]
    p = inertial_vector(robot, classical)
    got = pin_rnea(pin_chain(out, robot, locked), q, dq, ddq)
    assert_close(got, robot.inverse_dynamics(q, dq, ddq, p), TOL_DYN, "export: panda vs Pinocchio")
    assert_inertial_roundtrip(robot, mindyn.load(out, tip="panda_hand").params, p)


def test_namespaces_and_compact_elements(tmp_path):
    """A default namespace and prefixed elements are written as they were declared and named."""
    src = tmp_path / "ns.urdf"
    src.write_text(
        '<robot name="ns" xmlns="http://example.org/urdf" xmlns:xacro="http://www.ros.org/'
        'wiki/xacro">\n  <link name="a"/>\n  <joint name="j" type="revolute"><parent link="a"/>'
        '<child link="b"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" '
        'velocity="1"/></joint>\n  <link name="b"><xacro:property name="x" value="1"/></link>\n'
        "</robot>\n"
    )
    robot = mindyn.load(src)
    classical = consistent_params(robot, np.random.default_rng(13))
    out = tmp_path / "out.urdf"
    write_urdf(robot, classical, out)
    text = out.read_text()
    assert text.startswith('<robot name="ns" xmlns="http://example.org/urdf" xmlns:xacro=')
    assert '<xacro:property name="x" value="1"/>' in text
    back = mindyn.load(out)
    assert_inertial_roundtrip(robot, back.params, inertial_vector(robot, classical))
    assert back.viscous[0] == classical["Fv1"] and back.coulomb[0] == classical["Fc1"]


def test_zero_mass_link(tree, tmp_path):
    """A massless link with a rotational inertia only (as PUMA 560's link 1): mass 0, the
    inertia about the link origin, and a note; with no inertia at all, a zero inertial."""
    robot = mindyn.load(tree, tip="tool")
    classical = consistent_params(robot, np.random.default_rng(5), rotor=False, friction=False)
    classical.update({"MX1": 0.0, "MY1": 0.0, "MZ1": 0.0, "M1": 0.0})
    classical.update({k: 0.0 for k in robot.param_names if k.endswith("3")})
    out = tmp_path / "massless.urdf"
    res = write_urdf(robot, classical, out)
    assert any("'l1': M1 = 0" in n and "link origin" in n for n in res.notes), res.notes
    assert any("'l3': M3 = 0" in n and "zero inertial" in n for n in res.notes), res.notes
    back = mindyn.load(out, tip="tool")
    assert_inertial_roundtrip(robot, back.params, inertial_vector(robot, classical))
    assert not back.viscous.any() and not back.coulomb.any()  # j1, j3 had damping / friction
    rng = np.random.default_rng(6)
    q, dq, ddq = states(robot, rng)
    got = pin_rnea(pin_chain(out, robot, TREE_LOCKED), q, dq, ddq)
    want = robot.inverse_dynamics(q, dq, ddq, inertial_vector(robot, classical))
    assert_close(got, want, TOL_DYN, "export: massless links vs Pinocchio")


def test_inertia_that_is_not_physical_is_written_and_noted(tree, tmp_path):
    """Least-squares values may break the triangle inequality: written as they are (the
    dynamics stay those of the parameters), with a note."""
    robot = mindyn.load(tree, tip="tool")
    classical = consistent_params(robot, np.random.default_rng(14), rotor=False, friction=False)
    classical["XX2"] += 1.0  # principal moment about x far above the other two
    res = write_urdf(robot, classical, tmp_path / "x.urdf")
    assert any(n.startswith("link 'l2': the inertia about its centre") for n in res.notes)
    # that one, the three links' merged inertials and the source's friction written as 0
    assert len(res.notes) == 5, res.notes
    back = mindyn.load(tmp_path / "x.urdf", tip="tool")
    assert_inertial_roundtrip(robot, back.params, inertial_vector(robot, classical))


def test_vector_input_and_offsets(tree, tmp_path):
    robot = mindyn.load(tree, tip="tool")
    classical = consistent_params(robot, np.random.default_rng(7), rotor=False)
    vector = np.array([classical[k] for k in robot.parameter_names(rotor=False, friction=True)])
    a, b = tmp_path / "a.urdf", tmp_path / "b.urdf"
    write_urdf(robot, vector, a)
    classical.update({"Off1": 0.5, "Off2": -1.0, "Off3": 2.0})
    res = write_urdf(robot, classical, b, sidecar=tmp_path / "side.yaml")
    assert a.read_text() == b.read_text()
    assert read_joint_terms(res.sidecar)["Off3"] == 2.0
    with pytest.raises(mindyn.ModelError, match="is the description file itself"):
        write_urdf(robot, classical, b, sidecar=b)
    assert yaml.safe_load(res.sidecar.read_text())["joints"][2]["units"]["Off"] == "N"


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"M2": -0.5}, "M2 = -0.5 (link 'l2') is negative"),
        ({"M2": 0.0}, "M2 = 0 (link 'l2') with a first moment"),
        # the mapping argument itself: an ArgumentError naming it
        ({"XX4": 1.0}, "classical parameters: unknown 'XX4'"),
        ({"XX3": None}, "classical parameters: missing 'XX3'"),
        ({"Fv2": None}, "classical parameters: missing 'Fv2'"),
        ({"ZZ1": float("nan")}, "classical parameters: 'ZZ1' is nan; expected a finite number"),
        ({"ZZ1": "1"}, "classical parameters: 'ZZ1' is '1'; expected a number"),
        ({1: 1.0}, "classical parameters: the names must be text, got 1"),
    ],
)
def test_urdf_bad_parameters(tree, tmp_path, change, message):
    robot = mindyn.load(tree, tip="tool")
    classical = consistent_params(robot, np.random.default_rng(8), rotor=False)
    for k, v in change.items():
        if v is None:
            del classical[k]
        else:
            classical[k] = v
    # values that are not a physical body are the model's; a mapping that is not one of the
    # robot's classical layouts is an argument error
    error = mindyn.ArgumentError if message.startswith("classical") else mindyn.ModelError
    with pytest.raises(error, match=message.replace("(", r"\(").replace(")", r"\)")) as e:
        write_urdf(robot, classical, tmp_path / "x.urdf")
    assert isinstance(e.value, mindyn.ArgumentError) == (error is mindyn.ArgumentError)
    assert not (tmp_path / "x.urdf").exists()


def test_urdf_wrong_source_or_kind(tree, tmp_path):
    robot = mindyn.load(tree, tip="tool")
    classical = consistent_params(robot, np.random.default_rng(9))
    with pytest.raises(mindyn.ModelError, match="has no joint 'j1' moving link 'l1'"):
        write_urdf(robot, classical, tmp_path / "x.urdf", source=UR5)
    puma = mindyn.load("puma560")
    with pytest.raises(mindyn.ModelError, match="is a dh table, not a URDF"):
        write_urdf(puma, puma.params, tmp_path / "x.urdf")
    with pytest.raises(mindyn.ModelError, match="not from a YAML DH/MDH table"):
        write_yaml(robot, robot.params, tmp_path / "x.yaml")


# -- YAML tables --------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["puma560", "puma560_3", "stanford", "zcr07s", "random"])
def test_yaml_roundtrip(name, tmp_path):
    robot = mindyn.load(random_arm_yaml(tmp_path / "arm.yaml", n=4) if name == "random" else name)
    rng = np.random.default_rng(10)
    classical = consistent_params(robot, rng)
    out = tmp_path / "id.yaml"
    res = write_yaml(robot, classical, out)
    assert res.sidecar is None
    back = mindyn.load(out)
    names = robot.parameter_names(rotor=True, friction=True)
    np.testing.assert_array_equal(
        back.parameters(rotor=True, friction=True), [classical[k] for k in names]
    )
    for k in range(robot.n):  # geometry, limits and drives untouched
        np.testing.assert_array_equal(back.joint_transform(k, 0.4), robot.joint_transform(k, 0.4))
    for a, b in ((back.limits, robot.limits), (back.drives, robot.drives)):
        for key in a:
            np.testing.assert_array_equal(a[key], b[key])
    np.testing.assert_array_equal(back.tool, robot.tool)
    np.testing.assert_array_equal(back.gravity, robot.gravity)
    assert back.name == robot.name and back.convention == robot.convention

    # without joint terms the table has none (the identified model has none)
    inertial = {k: classical[k] for k in robot.param_names}
    write_yaml(robot, inertial, out)
    back = mindyn.load(out)
    assert not back.rotor_inertia.any() and not back.viscous.any() and not back.coulomb.any()
    np.testing.assert_array_equal(back.params, robot_params(robot, inertial))


def robot_params(robot: mindyn.Robot, classical: dict) -> np.ndarray:
    return inertial_vector(robot, classical)


def test_yaml_offsets_go_to_a_sidecar(tmp_path):
    robot = mindyn.load("puma560_3")
    classical = dict(zip(robot.param_names, robot.params))
    classical.update({"Off1": 0.1, "Off2": 0.2, "Off3": 0.3})
    res = write_yaml(robot, classical, tmp_path / "p.yaml")
    assert res.sidecar == tmp_path / "p.joints.yaml"
    assert read_joint_terms(res.sidecar) == {"Off1": 0.1, "Off2": 0.2, "Off3": 0.3}
    np.testing.assert_array_equal(mindyn.load(tmp_path / "p.yaml").params, robot.params)


def test_classical_terms_layouts():
    robot = mindyn.load("planar2")
    v = np.arange(1.0, 27.0)  # 13 per joint: Ia, Fv, Fc
    t = classical_terms(robot, v)
    np.testing.assert_array_equal(t.rotor, [11, 24])
    np.testing.assert_array_equal(t.coulomb, [13, 26])
    np.testing.assert_array_equal(t.inertial[10:], np.arange(14.0, 24.0))
    with pytest.raises(mindyn.ArgumentError, match="^classical parameters has shape"):
        classical_terms(robot, np.ones(21))


# -- command line -------------------------------------------------------------------------------
def run(argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main([str(a) for a in argv])
    return rc, out.getvalue(), err.getvalue()


def test_cli_export(tree, tmp_path):
    robot = mindyn.load(tree, tip="tool")
    classical = consistent_params(robot, np.random.default_rng(11))
    ident = tmp_path / "id.json"
    ident.write_text(json.dumps({"classical": classical, "other": 1}))
    out = tmp_path / "sub" / "out.urdf"
    rc, stdout, err = run(["export", tree, ident, "--tip", "tool", "--urdf", out])
    assert rc == 0, err
    assert f"wrote {out}" in stdout and "out.joints.yaml" in stdout
    assert_inertial_roundtrip(
        robot, mindyn.load(out, tip="tool").params, inertial_vector(robot, classical)
    )

    puma = mindyn.load("puma560")
    ident.write_text(json.dumps({"classical": consistent_params(puma, np.random.default_rng(1))}))
    rc, _, err = run(["export", "puma560", ident, "--yaml", tmp_path / "p.yaml"])
    assert rc == 0, err
    assert mindyn.load(tmp_path / "p.yaml").n == 6


@pytest.mark.parametrize("root", ["floating", "planar"])
def test_a_root_joint_added_by_the_loader_is_not_written_and_loads_back(tmp_path, root):
    """write_urdf and `mindyn export --urdf` of a robot loaded with root_joint= (Solo12 with a
    free-flyer or planar root): the file holds the robot without the loader's root joint (a
    URDF joint of the file would be doubled by the same loading), one note says so and how to
    load it; loaded again with the same root joint, the robot has the same joints and, for
    random physically consistent parameters, the original's inverse dynamics with them, by
    mindyn and by Pinocchio's own parser and rnea on the written file (1e-12)."""
    from test_multibody import pin_q, random_state

    solo = ROBOTS_DIR / "solo_description/robots/solo12.urdf"
    robot = mindyn.load(solo, root_joint=root)
    rng = np.random.default_rng(4)
    classical = consistent_params(robot, rng, rotor=False, friction=False)
    p = inertial_vector(robot, classical)
    out = tmp_path / "solo.urdf"
    said = [n for n in write_urdf(robot, classical, out).notes if "root_joint" in n]
    assert len(said) == 1 and "not written" in said[0] and f"root_joint='{root}'" in said[0]
    again = mindyn.load(out, root_joint=root)
    assert (again.joint_names, again.joint_types) == (robot.joint_names, robot.joint_types)
    joint = pin.JointModelFreeFlyer() if root == "floating" else pin.JointModelPlanar()
    model = pin.buildModelFromUrdf(str(out), joint)
    data = model.createData()
    for _ in range(3):
        q, v, a = random_state(robot, rng)
        tau = robot.inverse_dynamics(q, v, a, params=p)
        assert_close(again.inverse_dynamics(q, v, a), tau, 1e-12, "exported root: mindyn")
        ref = pin.rnea(model, data, pin_q(again, model, q), v, a)
        assert_close(ref, tau, 1e-12, "exported root: Pinocchio on the file")
    ident = tmp_path / "id.json"
    ident.write_text(json.dumps({"robot": robot.name, "classical": classical}))
    by_cli = tmp_path / "cli.urdf"
    rc, stdout, err = run(["export", solo, ident, "--root-joint", root, "--urdf", by_cli])
    assert rc == 0, err
    assert by_cli.read_text() == out.read_text()
    assert stdout.count(f"note: the {root} root joint 'root_joint' was added by the loader") == 1
    assert f"load the file with --root-joint {root} for the same robot" in stdout
    # an MJCF takes a floating root as a free joint (test_mjcf_floating), not a planar one
    if root == "planar":
        with pytest.raises(mindyn.ModelError, match="has the planar joint 'root_joint'"):
            write_mjcf(robot, classical, tmp_path / "solo.xml")


def _params_of(name) -> dict:
    robot = mindyn.load(name)
    return dict(zip(robot.param_names, robot.params))


@pytest.mark.parametrize(
    ("robot", "content", "output", "message"),
    [
        ("puma560", {"parameters": {}}, "o.yaml", "has no 'classical' map"),
        ("puma560", [1, 2], "o.yaml", "has no 'classical' map"),
        ("puma560", '{"classical": {"XX1": 1.0,}}', "o.yaml", "id.json:1:27: not valid JSON"),
        ("puma560", '{"classical": {"XX1": NaN}}', "o.yaml", "id.json: holds NaN"),
        ("puma560", {"classical": {"XX1": 1.0}}, "o.yaml", "'classical': missing 'XY1'"),
        ("puma560_3", "puma560", "o.yaml", "'classical': unknown 'XX4'"),  # another robot's
        ("puma560", "puma560", "o.urdf", "--urdf needs a robot from a URDF: 'puma560' is a DH"),
        (str(UR5), str(UR5), "o.yaml", "--yaml needs a YAML DH/MDH table: "),
        ("planar3", "planar3", "o.yaml", "was not read from a description file"),
        ("stanford", {"robot": "puma560"}, "o.yaml", "identified for robot 'puma560', not 'st"),
    ],
)
def test_cli_export_errors(tmp_path, robot, content, output, message):
    ident = tmp_path / "id.json"
    if isinstance(content, str) and content.startswith("{"):
        ident.write_text(content)
    elif isinstance(content, str):
        ident.write_text(json.dumps({"classical": _params_of(content)}))
    elif "robot" in content:  # puma560's parameter names with its name, for stanford
        ident.write_text(json.dumps({**content, "classical": _params_of("puma560")}))
    else:
        ident.write_text(json.dumps(content))
    flag = "--yaml" if output.endswith(".yaml") else "--urdf"
    rc, _, err = run(["export", robot, ident, flag, tmp_path / output])
    assert rc == 2
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("mindyn: error: "), err
    assert message in lines[0], err
    assert not (tmp_path / output).exists()


@pytest.mark.parametrize(
    ("robot", "outputs", "message"),
    [
        ("puma560", ["--urdf", "o.urdf"], "--urdf needs a robot from a URDF: 'puma560' is a DH"),
        (str(UR5), ["--yaml", "o.yaml"], "--yaml needs a YAML DH/MDH table: "),
        (str(UR5), ["--mjcf", "o.xml", "--sidecar", "s.yaml"], "--sidecar: goes with --urdf or"),
    ],
)
def test_cli_export_option_clashes_are_usage_errors(tmp_path, monkeypatch, robot, outputs, message):
    """An output option that does not fit the robot's description (--urdf for a table, --yaml
    for a URDF) or the other outputs (--sidecar with --mjcf) is the command line's error (a
    UsageError, as the other commands' option clashes), not the description's (ModelError)."""
    from mindyn.cli.args import UsageError

    ident = tmp_path / "id.json"
    ident.write_text(json.dumps({"classical": _params_of(robot)}))
    seen = []
    monkeypatch.setattr(cli, "_error", seen.append)
    argv = ["export", robot, str(ident), *(str(tmp_path / w) if "." in w else w for w in outputs)]
    assert cli.main(argv) == 2
    assert len(seen) == 1 and type(seen[0]) is UsageError, repr(seen)
    assert str(seen[0]).startswith(message), seen[0]
    assert sorted(f.name for f in tmp_path.iterdir()) == ["id.json"]  # nothing written


def test_cli_export_needs_one_output(tmp_path):
    rc, _, err = run(["export", "puma560", tmp_path / "id.json"])
    assert rc == 2 and "one of the arguments --urdf --yaml --mjcf is required" in err
    rc, _, err = run(["export", "puma560", tmp_path / "none.json", "--yaml", tmp_path / "o.yaml"])
    assert rc == 2 and "identification file" in err and "does not exist" in err


def _parse(path: Path):
    import xml.etree.ElementTree as ET

    return ET.parse(path).getroot()


def _text(element) -> str:
    import xml.etree.ElementTree as ET

    return " ".join(ET.tostring(element, encoding="unicode").split()).replace(" />", "/>")


def test_read_joint_terms_errors(tmp_path):
    with pytest.raises(mindyn.RobotFileNotFoundError, match="joint-terms file '.*none.yaml'"):
        read_joint_terms(tmp_path / "none.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("joints: [1, 2]\n")
    with pytest.raises(mindyn.ModelError, match="expected a 'joints' list of mappings"):
        read_joint_terms(bad)
    bad.write_text("joints:\n- {name: j1, Ia: x}\n")
    with pytest.raises(mindyn.ModelError, match="joint 1: 'Ia' is 'x'; expected a number"):
        read_joint_terms(bad)
    bad.write_text("joints: [\n")
    with pytest.raises(mindyn.ModelError, match=r"bad.yaml:2:1: not valid YAML: while parsing"):
        read_joint_terms(bad)


def test_identify_consistent_writes_the_urdf_that_pinocchio_reproduces(tmp_path):
    """``identify --consistent --urdf``: the written URDF, loaded by Pinocchio, gives ``rnea``
    equal to mindyn's prediction of the consistent estimate, W_b(q, dq, ddq) (Y pi), with
    the identified base values from the JSON (the log is noisy, so these are not the truth)."""
    from mindyn.control import SensorNoise, simulate_inverse
    from mindyn.identification.data import write_csv
    from mindyn.identification.excitation import random_trajectory

    robot = mindyn.load(UR5)
    traj = random_trajectory(robot, seed=3)
    log = simulate_inverse(robot, traj, rate=50.0, noise=SensorNoise(torque=0.05), seed=2)
    fit = tmp_path / "fit.csv"
    write_csv(fit, log.t, log.q, log.tau, dq=log.dq)
    ident, out = tmp_path / "id.json", tmp_path / "ur5_id.urdf"
    argv = ["identify", UR5, fit, "--consistent", "--json", ident, "--urdf", out]
    rc, stdout, err = run(argv)
    assert rc == 0, err
    assert f"wrote {out}" in stdout
    doc = json.loads(ident.read_text())
    bp = mindyn.base_parameters(robot)
    assert doc["base_names"] == bp.names
    beta = bp.values(inertial_vector(robot, doc["classical"]))
    rng = np.random.default_rng(5)
    q, dq, ddq = states(robot, rng)
    predicted = np.einsum("mij,j->mi", bp.regressor(q, dq, ddq), beta)
    got = pin_rnea(pin_chain(out, robot, {}), q, dq, ddq)
    assert_close(got, predicted, TOL_DYN, "identify --consistent --urdf vs Pinocchio")
    # and the consistent estimate is the JSON's: its base values reproduce Y pi
    cons = doc["consistent_estimate"]
    if "base_values" in cons:
        np.testing.assert_allclose(cons["base_values"], beta, rtol=1e-9, atol=1e-12)


def test_identify_urdf_needs_consistent_and_a_urdf_robot(tmp_path):
    fit = tmp_path / "fit.csv"
    fit.write_text("t,q1,q2,tau1,tau2\n")
    rc, _, err = run(["identify", "planar2", fit, "--consistent", "--urdf", tmp_path / "x.urdf"])
    assert rc == 2 and "--urdf needs a robot from a URDF" in err, err
    rc, _, err = run(["identify", UR5, fit, "--urdf", tmp_path / "x.urdf"])
    assert rc == 2 and "expected --consistent" in err, err
    rc, _, err = run(["identify", UR5, fit, "--consistent", "--sidecar", tmp_path / "x.yaml"])
    assert rc == 2 and "--sidecar: expected --urdf or --yaml" in err, err


def test_a_classical_map_read_from_a_file_is_a_data_error(tmp_path):
    """The same map that is an argument error of classical_terms is the data's error once the
    command line read it from an identification file (the message names the file)."""
    from mindyn.cli.export import write_description
    from mindyn.identification.data import DataError

    robot = mindyn.load("puma560_3")
    classical = _params_of("puma560_3")
    del classical["XX2"]
    with pytest.raises(mindyn.ArgumentError, match="missing 'XX2'"):
        classical_terms(robot, classical)
    with pytest.raises(DataError, match=r"^id.json: 'classical': missing 'XX2'") as e:
        write_description(
            robot, classical, "id.json: 'classical'", "puma560_3", None, tmp_path / "o.yaml", None
        )
    assert not isinstance(e.value, mindyn.ArgumentError)
    assert not (tmp_path / "o.yaml").exists()


def test_yaml_export_refuses_a_negative_mass_and_notes_an_unphysical_inertia(tmp_path):
    """A URDF or MJCF export refuses a negative mass; the YAML table's wrote it (and the table
    read back held a link of -5 kg). Now refused the same way, nothing written; an inertia
    about the centre of mass that breaks the triangle inequality (Izz > Ixx + Iyy, a body no
    mass distribution gives) is written with a note, as for a URDF."""
    robot = mindyn.load("zcr07s")
    p = robot.params.copy()
    p[9] = -5.0  # M1
    out = tmp_path / "neg.yaml"
    with pytest.raises(mindyn.ModelError, match=r"M1 = -5.0 \(link 'link1'\) is negative"):
        write_yaml(robot, p, out)
    assert not out.exists()
    p = robot.params.copy()
    k = 2  # link3: a point mass at its centre of mass, then Izz = 3 (Ixx + Iyy) added about it
    m, h = p[10 * k + 9], p[10 * k + 6 : 10 * k + 9]
    Io = (h @ h * np.eye(3) - np.outer(h, h)) / m + np.diag([0.01, 0.01, 0.06])
    p[10 * k : 10 * k + 6] = Io[[0, 0, 0, 1, 1, 2], [0, 1, 2, 1, 2, 2]]
    written = write_yaml(robot, p, tmp_path / "odd.yaml")
    assert [
        n
        for n in written.notes
        if n.startswith("link 'link3'") and "not that of a physical body" in n
    ]
    assert not [n for n in written.notes if "link 'link1'" in n or "link 'link2'" in n]
    np.testing.assert_allclose(mindyn.load(written.path).params, p, rtol=1e-12, atol=1e-15)
