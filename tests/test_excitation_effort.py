"""Acceleration limits of the excitation derived from the effort limits, and the trajectory's
peak torques against them, checked with Pinocchio (crba, rnea) on the URDF itself."""

from __future__ import annotations

import json
import math

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import ROBOTS_DIR, pinocchio_model
from mindyn import cli
from mindyn.identification.data import read_csv
from mindyn.identification.excitation import effort_acceleration_limits, excitation_limits

HEAVY_ARM = """<?xml version="1.0"?>
<robot name="heavy_arm">
  <link name="base"/>
  <link name="turret">
    <inertial><origin xyz="0 0 0.1"/><mass value="20"/>
      <inertia ixx="0.3" iyy="0.3" izz="0.2" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <link name="upper">
    <inertial><origin xyz="0.4 0 0"/><mass value="10"/>
      <inertia ixx="0.05" iyy="0.6" izz="0.6" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <link name="fore">
    <inertial><origin xyz="0.4 0 0"/><mass value="5"/>
      <inertia ixx="0.02" iyy="0.3" izz="0.3" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="turret"/>
    <origin xyz="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-2.5" upper="2.5" velocity="0.5" effort="{e1}"/></joint>
  <joint name="j2" type="revolute"><parent link="turret"/><child link="upper"/>
    <origin xyz="0 0 0.4"/><axis xyz="0 1 0"/>
    <limit lower="-1.5" upper="1.5" velocity="0.5" effort="{e2}"/></joint>
  <joint name="j3" type="revolute"><parent link="upper"/><child link="fore"/>
    <origin xyz="0.8 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" velocity="0.5" effort="80"/></joint>
</robot>
"""


def heavy_arm(tmp_path, e1=15.0, e2=300.0):
    """A 35-kg arm whose base joint has a small effort limit for its inertia (8-9 kg m^2
    outstretched): 15 N m give it about 1.4 rad/s^2; the optimiser asked it for 20 N m within
    the fixed 6 rad/s^2."""
    path = tmp_path / "heavy_arm.urdf"
    path.write_text(HEAVY_ARM.format(e1=e1, e2=e2))
    return path


def pinocchio_rule(model, q, dq, share, effort, bound, rotor=0.0, friction=None):
    """The rule of effort_acceleration_limits written out with Pinocchio's crba and rnea (a
    model or a URDF path); ``rotor`` joint-side rotor inertias, ``friction(v)`` torques."""
    if not isinstance(model, pin.Model):
        model = pin.buildModelFromUrdf(str(model))
    data = model.createData()
    n = model.nv
    A = np.full(n, np.inf)
    for qs, vs in zip(q, dq):
        M = pin.crba(model, data, qs).copy()
        M = np.triu(M) + np.triu(M, 1).T + np.diag(np.broadcast_to(rotor, (n,)))
        h = pin.rnea(model, data, qs, vs, np.zeros(n)).copy()
        h += 0.0 if friction is None else friction(vs)
        for k in range(n):
            others = sum(abs(M[k, j]) * bound[j] for j in range(n) if j != k)
            A[k] = min(A[k], (share * effort[k] - abs(h[k]) - others) / M[k, k])
    return A


@pytest.mark.parametrize("name", ["ur5", "z1", "heavy"])
def test_derived_acceleration_limits_match_pinocchio(name, tmp_path):
    urdf = {
        "ur5": ROBOTS_DIR / "ur_description/urdf/ur5_robot.urdf",
        "z1": ROBOTS_DIR / "z1_description/urdf/z1.urdf",
        "heavy": heavy_arm(tmp_path),
    }[name]
    robot = mindyn.load(urdf)
    lim = robot.limits
    n = robot.n
    reach = 2 * math.pi * 0.1 * 5 * lim["velocity"]
    rule = effort_acceleration_limits(
        robot,
        lower=lim["lower"],
        upper=lim["upper"],
        velocity=lim["velocity"],
        fixed=np.full(n, np.nan),
        fallback=np.full(n, 6.0),
        reach=reach,
        share=0.8,
    )
    assert np.isfinite(rule["acceleration"]).all()
    # The bounds on the other joints: each joint's own limit without coupling, by Pinocchio.
    isolated = pinocchio_rule(urdf, rule["q"], rule["dq"], 0.8, lim["effort"], np.zeros(n))
    np.testing.assert_allclose(rule["isolated"], isolated, rtol=1e-8)
    bound = np.minimum(isolated, reach)
    expected = pinocchio_rule(urdf, rule["q"], rule["dq"], 0.8, lim["effort"], bound)
    np.testing.assert_allclose(rule["acceleration"], expected, rtol=1e-8)
    # The promise: any accelerations within the limits (and the others' bounds) keep every
    # torque within 80 % of its effort limit at the samples; the worst signs reach it.
    model = pin.buildModelFromUrdf(str(urdf))
    data = model.createData()
    rng = np.random.default_rng(1)
    for qs, vs in zip(rule["q"][:16], rule["dq"][:16]):
        for _ in range(8):
            a = np.minimum(rule["acceleration"], bound) * rng.choice([-1.0, 1.0], size=n)
            tau = pin.rnea(model, data, qs, vs, a)
            assert (np.abs(tau) <= 0.8 * lim["effort"] * (1 + 1e-9)).all()


def test_rotor_inertia_and_friction_count_when_asked():
    """ZCR07S (rotor inertia, viscous and Coulomb friction on the joints), its given
    acceleration limits set aside: the rule with both terms, against Pinocchio plus them."""
    robot = mindyn.load("zcr07s")
    lim, n = robot.limits, robot.n
    kw = dict(lower=lim["lower"], upper=lim["upper"], velocity=lim["velocity"], share=0.8)
    kw.update(fixed=np.full(n, np.nan), fallback=np.full(n, 6.0), reach=np.full(n, 20.0))
    plain = effort_acceleration_limits(robot, **kw)
    rule = effort_acceleration_limits(robot, rotor=True, friction=True, **kw)
    model = pinocchio_model(robot)
    terms = dict(
        rotor=robot.rotor_inertia,
        friction=lambda v: robot.viscous * v + robot.coulomb * np.sign(v),
    )
    isolated = pinocchio_rule(
        model, rule["q"], rule["dq"], 0.8, lim["effort"], 0 * lim["effort"], **terms
    )
    np.testing.assert_allclose(rule["isolated"], isolated, rtol=1e-8)
    expected = pinocchio_rule(
        model, rule["q"], rule["dq"], 0.8, lim["effort"], np.minimum(isolated, 20.0), **terms
    )
    np.testing.assert_allclose(rule["acceleration"], expected, rtol=1e-8)
    assert (rule["acceleration"] < plain["acceleration"]).all()  # the terms cost torque


def test_heavy_arm_trajectory_stays_within_its_effort_limits(tmp_path, capsys):
    """The fixed 6 rad/s^2 let the optimiser ask the base joint for a third more than its 15 N m."""
    urdf = heavy_arm(tmp_path)
    out = tmp_path / "traj.csv"
    argv = ["excite", str(urdf), "--harmonics", "3", "--freq", "0.5", "--starts", "1"]
    assert cli.main([*argv, "--maxiter", "15", "--quiet", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "acceleration limits of joints 1-3 from their effort limits" in printed
    d = read_csv(out, n=3, require_torque=False)
    model = pin.buildModelFromUrdf(str(urdf))
    data = model.createData()
    tau = np.array([pin.rnea(model, data, *row).copy() for row in zip(d.q, d.dq, d.ddq)])
    effort = np.array([15.0, 300.0, 80.0])
    peak = np.abs(tau).max(0)
    assert (peak <= effort).all(), peak / effort
    doc = json.loads(out.with_suffix(".json").read_text())
    # The reported peak shares are Pinocchio's along the CSV (a finer grid: within 2 %).
    np.testing.assert_allclose(doc["peak_torque"]["share"], peak / effort, rtol=0.02)
    assert doc["limits"]["acceleration_source"] == ["effort"] * 3
    assert doc["acceleration_rule"]["share"] == 0.8


def test_fallback_is_stated_without_effort_limits(tmp_path, capsys):
    robot = mindyn.load("stanford")  # no velocity, acceleration or effort data
    lim, notes = excitation_limits(robot, margin=0.05)
    np.testing.assert_allclose(lim["acceleration"], [5.7, 5.7, 1.9, 5.7, 5.7, 5.7])
    assert list(lim["acceleration_source"]) == ["fallback"] * 6
    (line,) = [x for x in notes if x.startswith("acceleration limits")]
    assert "joints 1-6: the fixed fallback 6 rad/s^2 (2 m/s^2)" in line
    assert "no effort limit" in line
    out = tmp_path / "traj.csv"
    argv = ["excite", "puma560_3", "--harmonics", "3", "--starts", "1", "--maxiter", "5"]
    assert cli.main([*argv, "--quiet", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    doc = json.loads(out.with_suffix(".json").read_text())
    assert "joints 1-3: the fixed fallback" in printed and "per joint: -, -, -" in printed
    assert doc["acceleration_rule"]["source"] == ["fallback"] * 3
    assert doc["peak_torque"]["share"] == [None] * 3


def test_a_joint_its_gravity_saturates_falls_back_and_says_why(tmp_path):
    """With 100 N m at the shoulder, which holds up to 98 N m of gravity, no acceleration limit
    fits within 80 % of it: the fallback is used and the note gives the shares."""
    urdf = heavy_arm(tmp_path, e2=100.0)
    robot = mindyn.load(urdf)
    lim, notes = excitation_limits(robot, margin=0.05)
    assert list(lim["acceleration_source"]) == ["effort", "fallback", "effort"]
    assert lim["acceleration"][1] == pytest.approx(5.7)
    (line,) = [x for x in notes if x.startswith("joint 2:")]
    assert "gravity and velocity terms alone reach" in line
    src = robot.limits
    rule = effort_acceleration_limits(
        robot,
        lower=lim["lower"],
        upper=lim["upper"],
        velocity=lim["velocity"],
        fixed=np.full(3, np.nan),
        fallback=np.full(3, 5.7),
        share=0.8,
    )
    model = pin.buildModelFromUrdf(str(urdf))
    data = model.createData()
    h = np.array(
        [pin.rnea(model, data, q, v, np.zeros(3)).copy() for q, v in zip(rule["q"], rule["dq"])]
    )
    g = np.array([pin.computeGeneralizedGravity(model, data, q).copy() for q in rule["q"]])
    np.testing.assert_allclose(rule["held"], np.abs(h).max(0) / src["effort"], rtol=1e-9)
    np.testing.assert_allclose(rule["gravity"], np.abs(g).max(0) / src["effort"], rtol=1e-9)
    assert f"(gravity alone {100 * rule['gravity'][1]:.0f} %)" in line
    assert rule["saturated"] == [1]
