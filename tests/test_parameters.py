"""Parameter conventions and conversions: URDF inertials, Pinocchio order, names and layouts."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import URDFS, assert_close, load_urdf_pair, random_state

INERTIAL = ["XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M"]


def random_rotation(rng) -> np.ndarray:
    return pin.rpy.rpyToMatrix(*rng.uniform(-np.pi, np.pi, 3))


def point_cloud_params(m, x) -> np.ndarray:
    """Classical parameters of point masses m_i at x_i straight from the definitions."""
    X, Y, Z = x.T
    return np.array(
        [
            np.sum(m * (Y**2 + Z**2)),
            -np.sum(m * X * Y),
            -np.sum(m * X * Z),
            np.sum(m * (X**2 + Z**2)),
            -np.sum(m * Y * Z),
            np.sum(m * (X**2 + Y**2)),
            np.sum(m * X),
            np.sum(m * Y),
            np.sum(m * Z),
            np.sum(m),
        ]
    )


def com_inertia(m, x):
    M = m.sum()
    c = m @ x / M
    r = x - c
    Ic = np.einsum("i,ij,ik->jk", m, r, r)
    Ic = np.trace(Ic) * np.eye(3) - Ic
    return M, c, Ic


# --------------------------------------------------------------------------------------------
def test_inertial_from_com_and_urdf_point_cloud(rng):
    for _ in range(5):
        m = rng.uniform(0.1, 1.0, 12)
        x = rng.uniform(-0.3, 0.5, (12, 3))
        direct = point_cloud_params(m, x)
        M, c, Ic = com_inertia(m, x)
        assert_close(
            mindyn.inertial_from_com(M, c, Ic), direct, 1e-13, "inertial_from_com vs point masses"
        )
        # URDF gives the COM inertia in a frame rotated by R relative to the link axes:
        # its components there are R^T Ic R.
        R = random_rotation(rng)
        assert_close(
            mindyn.inertial_from_urdf(M, c, R, R.T @ Ic @ R),
            direct,
            1e-13,
            "inertial_from_urdf vs point masses",
        )
        # Pinocchio's own parameterisation of the same body
        dyn = pin.Inertia(M, c, Ic).toDynamicParameters()
        assert_close(
            mindyn.to_pinocchio_order(direct), dyn, 1e-13, "to_pinocchio_order vs pin.Inertia"
        )
        assert_close(
            mindyn.from_pinocchio_order(dyn), direct, 1e-13, "from_pinocchio_order vs pin.Inertia"
        )


def test_inertial_from_urdf_matches_pinocchio_ur5():
    """Each UR5 <inertial> element through inertial_from_urdf vs Pinocchio's parsed inertias."""
    robot, model = load_urdf_pair("ur5")
    root = ET.parse(URDFS["ur5"]).getroot()
    links = {link.get("name"): link for link in root.iter("link")}
    for k, name in enumerate(robot.link_names[1:]):
        el = links[name].find("inertial")
        origin = el.find("origin")
        xyz = np.array([float(v) for v in origin.get("xyz", "0 0 0").split()])
        rpy = np.array([float(v) for v in origin.get("rpy", "0 0 0").split()])
        mass = float(el.find("mass").get("value"))
        i = {a: float(v) for a, v in el.find("inertia").attrib.items()}
        Ic = np.array(
            [
                [i["ixx"], i["ixy"], i["ixz"]],
                [i["ixy"], i["iyy"], i["iyz"]],
                [i["ixz"], i["iyz"], i["izz"]],
            ]
        )
        p = mindyn.inertial_from_urdf(mass, xyz, pin.rpy.rpyToMatrix(rpy), Ic)
        ref = mindyn.from_pinocchio_order(model.inertias[k + 1].toDynamicParameters())
        assert_close(p, ref, 1e-12, "inertial_from_urdf vs pin (UR5 links)")
        assert_close(robot.params[10 * k : 10 * k + 10], ref, 1e-12, "URDF params vs pin")


@pytest.mark.parametrize("name", list(URDFS))
def test_urdf_params_match_pinocchio(name):
    """The merged link parameters (fixed children, Panda's locked fingers) equal Pinocchio's."""
    robot, model = load_urdf_pair(name)
    ref = np.concatenate([model.inertias[k].toDynamicParameters() for k in range(1, robot.n + 1)])
    assert_close(robot.params, mindyn.from_pinocchio_order(ref), 1e-12, "URDF params vs pin")
    assert robot.params[9::10].sum() == pytest.approx(
        sum(model.inertias[k].mass for k in range(1, robot.n + 1)), rel=1e-14
    )


SKEW_URDF = """<?xml version="1.0"?>
<robot name="skew">
  <link name="base">
    <inertial><mass value="5"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
  </link>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="l1"/>
    <origin xyz="0.1 -0.05 0.3" rpy="0.2 -0.3 0.5"/><axis xyz="0.6 0 0.8"/>
    <limit lower="-2" upper="2" effort="10" velocity="1"/>
  </joint>
  <link name="l1">
    <inertial>
      <origin xyz="0.05 0.02 0.1" rpy="0.4 0.1 -0.7"/><mass value="2.5"/>
      <inertia ixx="0.03" ixy="0.002" ixz="-0.001" iyy="0.025" iyz="0.003" izz="0.02"/>
    </inertial>
  </link>
  <joint name="j2" type="prismatic">
    <parent link="l1"/><child link="l2"/>
    <origin xyz="0.2 0.1 0" rpy="-0.6 0.2 0.1"/><axis xyz="0 0.6 0.8"/>
    <limit lower="-0.2" upper="0.3" effort="100" velocity="0.5"/>
  </joint>
  <link name="l2">
    <inertial>
      <origin xyz="-0.03 0.04 0.15" rpy="1.0 -0.5 0.3"/><mass value="1.5"/>
      <inertia ixx="0.012" ixy="-0.001" ixz="0.0005" iyy="0.015" iyz="0.001" izz="0.009"/>
    </inertial>
  </link>
  <joint name="sensor_mount" type="fixed">
    <parent link="l2"/><child link="sensor"/><origin xyz="0.05 0 0.2" rpy="0.3 0.3 -0.2"/>
  </joint>
  <link name="sensor">
    <inertial>
      <origin xyz="0.01 0.02 0.03" rpy="-0.2 0.7 0.1"/><mass value="0.4"/>
      <inertia ixx="0.001" ixy="0.0001" ixz="0" iyy="0.002" iyz="0.0002" izz="0.0015"/>
    </inertial>
  </link>
  <joint name="j3" type="revolute">
    <parent link="sensor"/><child link="l3"/>
    <origin xyz="0 0.1 0.05" rpy="0 0.9 0"/><axis xyz="1 0 0"/>
    <limit lower="-3" upper="3" effort="10" velocity="1"/>
  </joint>
  <link name="l3">
    <inertial>
      <origin xyz="0.1 0 0.02" rpy="0.1 0.2 0.3"/><mass value="0.8"/>
      <inertia ixx="0.004" ixy="0" ixz="0.0003" iyy="0.005" iyz="0" izz="0.003"/>
    </inertial>
  </link>
  <joint name="flange_joint" type="fixed">
    <parent link="l3"/><child link="flange"/><origin xyz="0.15 0 0" rpy="0 0 1.2"/>
  </joint>
  <link name="flange"/>
</robot>
"""


def test_skewed_urdf_matches_pinocchio(tmp_path, rng):
    """Rotated inertial frames, unaligned axes, a prismatic joint and a merged fixed child."""
    path = tmp_path / "skew.urdf"
    path.write_text(SKEW_URDF)
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    for tip in (None, "flange"):
        robot = mindyn.load(path, tip=tip)
        assert robot.n == 3
        assert robot.joint_types == ["revolute", "prismatic", "revolute"]
        ref = np.concatenate([model.inertias[k].toDynamicParameters() for k in (1, 2, 3)])
        assert_close(
            robot.params, mindyn.from_pinocchio_order(ref), 1e-12, "skew URDF params vs pin"
        )
        for _ in range(3):
            q, dq, ddq = random_state(robot, rng)
            assert_close(
                robot.inverse_dynamics(q, dq, ddq),
                pin.rnea(model, data, q, dq, ddq),
                1e-10,
                "skew URDF ID vs pin",
            )
            pin.framesForwardKinematics(model, data, q)
            frame = model.getFrameId(tip or "l3")
            assert_close(robot.fk(q), data.oMf[frame].homogeneous, 1e-12, "skew URDF fk vs pin")


def test_pinocchio_order_round_trip_and_layout(rng):
    p = rng.normal(size=30)
    assert_close(mindyn.from_pinocchio_order(mindyn.to_pinocchio_order(p)), p, 0.0, "round trip")
    assert_close(mindyn.to_pinocchio_order(mindyn.from_pinocchio_order(p)), p, 0.0, "round trip")
    # the documented order: m, mcx, mcy, mcz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz
    classical = dict(zip(INERTIAL, range(10)))
    expected = [classical[s] for s in ["M", "MX", "MY", "MZ", "XX", "XY", "YY", "XZ", "YZ", "ZZ"]]
    np.testing.assert_array_equal(mindyn.to_pinocchio_order(np.arange(10.0)), expected)
    np.testing.assert_array_equal(
        mindyn.to_pinocchio_order(np.arange(20.0)), expected + [e + 10 for e in expected]
    )
    # an argument of the wrong length: the argument's error, naming it (not a model's)
    with pytest.raises(mindyn.ArgumentError, match=r"params has 11 entries, not a multiple of 10"):
        mindyn.to_pinocchio_order(np.zeros(11))
    with pytest.raises(mindyn.ArgumentError, match=r"params has 9 entries, not a multiple of 10"):
        mindyn.from_pinocchio_order(np.zeros(9))


@pytest.mark.parametrize("name", ["puma560", "stanford", "planar3"])
def test_parameter_names_and_layouts(name):
    robot = mindyn.load(name)
    n = robot.n
    assert robot.param_names == [f"{s}{k}" for k in range(1, n + 1) for s in INERTIAL]
    assert robot.parameter_names() == robot.param_names
    for rotor in (False, True):
        for friction in (False, True):
            extra = (["Ia"] if rotor else []) + (["Fv", "Fc"] if friction else [])
            names = robot.parameter_names(rotor=rotor, friction=friction)
            assert names == [f"{s}{k}" for k in range(1, n + 1) for s in INERTIAL + extra]
            values = robot.parameters(rotor=rotor, friction=friction)
            assert values.shape == (len(names),) == ((10 + len(extra)) * n,)
            for k in range(n):
                np.testing.assert_array_equal(
                    values[names.index(f"XX{k + 1}") : names.index(f"M{k + 1}") + 1],
                    robot.params[10 * k : 10 * k + 10],
                )
                if rotor:
                    assert values[names.index(f"Ia{k + 1}")] == robot.rotor_inertia[k]
                if friction:
                    assert values[names.index(f"Fv{k + 1}")] == robot.viscous[k]
                    assert values[names.index(f"Fc{k + 1}")] == robot.coulomb[k]
    # the full layout starts XX1..M1, Ia1, Fv1, Fc1, XX2
    assert robot.parameter_names(rotor=True, friction=True)[:14] == INERTIAL_1 + [
        "Ia1",
        "Fv1",
        "Fc1",
        "XX2",
    ]


INERTIAL_1 = [f"{s}1" for s in INERTIAL]


def test_puma560_drive_parameters_present():
    robot = mindyn.load("puma560")
    assert np.all(robot.rotor_inertia > 0)
    assert np.all(robot.viscous > 0)
    assert np.all(robot.coulomb > 0)
    assert robot.params[9] == 0.0  # link 1's mass was not measured
    assert robot.params[9::10].sum() == pytest.approx(23.45, abs=0.01)  # 17.4+4.8+0.82+0.34+0.09


def test_layout_recognised_from_length(rng):
    robot = mindyn.load("puma560")
    q, dq, ddq = random_state(robot, rng)
    base = robot.inverse_dynamics(q, dq, ddq, robot.params)
    for rotor, friction in [(True, False), (False, True), (True, True)]:
        p = robot.parameters(rotor=rotor, friction=friction)
        names = robot.parameter_names(rotor=rotor, friction=friction)
        zeroed = p.copy()
        for i, s in enumerate(names):
            if s.startswith(("Ia", "Fv", "Fc")):
                zeroed[i] = 0.0
        assert_close(robot.inverse_dynamics(q, dq, ddq, zeroed), base, 1e-15, "zero extras")
    with pytest.raises(ValueError, match="fits no layout"):
        robot.inverse_dynamics(q, dq, ddq, np.zeros(61))


def test_params_setter_validation(rng):
    robot = mindyn.load("planar3")
    p = rng.uniform(0.1, 1.0, 30)
    robot.params = p
    np.testing.assert_array_equal(robot.params, p)
    robot.params = list(p)  # any sequence
    np.testing.assert_array_equal(robot.params, p)
    # a read-only array comes back: an entry cannot be changed in place (and silently lost)
    got = robot.params
    with pytest.raises(ValueError, match="read-only"):
        got[0] = 123.0
    assert robot.params[0] == p[0]
    for bad, match in [
        (np.zeros(29), r"params.*shape \(29,\).*\(30,\)"),
        (np.zeros(31), r"params.*shape"),
        (np.zeros((3, 10)), r"params.*shape \(3, 10\)"),
        (np.zeros(39), r"params.*shape"),
        (np.r_[np.zeros(29), np.nan], r"params.*NaN"),
        (np.r_[np.inf, np.zeros(29)], r"params.*infinite"),
    ]:
        with pytest.raises(ValueError, match=match):
            robot.params = bad
        np.testing.assert_array_equal(robot.params, p)  # unchanged after a rejected value
    for attr in ("rotor_inertia", "viscous", "coulomb"):
        with pytest.raises(ValueError, match=rf"{attr}.*shape"):
            setattr(robot, attr, np.zeros(4))
        with pytest.raises(ValueError, match=rf"{attr}.*NaN"):
            setattr(robot, attr, [0.0, np.nan, 0.0])
        setattr(robot, attr, [0.1, 0.2, 0.3])
        np.testing.assert_array_equal(getattr(robot, attr), [0.1, 0.2, 0.3])
