"""The default snap (``snap="auto"``): right angles a description writes rounded (1.5708,
1.57079632679) are rounded to them before the base set is computed, so that nothing downstream
estimates parameters whose regressor columns are the rounding; a deliberate angle near a right
angle (a calibrated offset of 1e-3 rad) is kept. Counts are checked against Pinocchio's
regressor rank and the numerical method of the geometry the test writes, identification
against the known answer of a log the test simulates."""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import ROBOTS_DIR, pinocchio_model
from mindyn.identification import IdentifyOptions, run
from mindyn.identification.joint_data import JointData

KINOVA = ROBOTS_DIR / "kinova_description/robots/kinova.urdf"  # 1.57079632679, 3.14159265359
XARM = ROBOTS_DIR / "xarm_description/urdf/xarm7.urdf"  # pi/2 written 1.5708
SO100 = ROBOTS_DIR / "so_arm_description/urdf/so100.urdf"  # 1.57079, 3.14158: cut, not rounded


def rewrite_right_angles(text: str, write) -> str:
    """``text`` with every number of a joint origin's ``rpy`` within 1e-4 of a multiple of pi/2
    (k pi/2, k != 0) replaced by ``write(k)``, in the order of the file."""

    def number(m: re.Match) -> str:
        x = float(m.group(0))
        k = round(x / (math.pi / 2))
        return write(k) if k and abs(x - k * math.pi / 2) < 1e-4 else m.group(0)

    def rpy(m: re.Match) -> str:
        return 'rpy="' + re.sub(r"-?[\d.]+(?:[eE][-+]?\d+)?", number, m.group(1)) + '"'

    def joint(m: re.Match) -> str:
        return re.sub(r'rpy="([^"]*)"', rpy, m.group(0))

    return re.sub(r"<joint\b.*?</joint>", joint, text, flags=re.DOTALL)


def exact(k: int) -> str:
    return repr(k * math.pi / 2)


def load(path, rotor: bool) -> mindyn.Robot:
    """The robot of ``path``; with ``rotor``, its rotor inertia on the joints."""
    robot = mindyn.load(path)
    return robot.with_drive_side("joint") if rotor and robot.transmission else robot


def pinocchio_rank(path, rng, rotor: bool = False, states: int = 60) -> int:
    """Rank of Pinocchio's stacked joint-torque regressor of the robot of ``path`` at random
    states (relative singular value tolerance 1e-8); with ``rotor``, beside a rotor inertia
    column per joint (its acceleration in its own joint's row)."""
    model = pinocchio_model(mindyn.load(path))
    data = model.createData()
    rows = []
    for _ in range(states):
        q, dq, ddq = (rng.uniform(-2, 2, model.nv) for _ in range(3))
        W = pin.computeJointTorqueRegressor(model, data, q, dq, ddq)
        rows.append(np.hstack([W, np.diag(ddq)]) if rotor else W)
    s = np.linalg.svd(np.vstack(rows), compute_uv=False)
    return int(np.sum(s > 1e-8 * s[0]))


def rounded(k: int) -> str:
    """k right angles written with four decimals, as shipped descriptions write them."""
    return repr(round(k * math.pi / 2, 4))


def first_tilted(tilt: float, others):
    """A rewrite of the right angles: the first tilted by ``tilt`` rad, the others ``others(k)``."""
    first = [True]

    def angle(k: int) -> str:
        if first[0]:
            first[0] = False
            return repr(k * math.pi / 2 + tilt)
        return others(k)

    return angle


def written(tmp_path, name: str, text: str):
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    "source, rounding, rotor",
    [
        (KINOVA, None, False),  # as shipped: 1.57079632679, 3.14159265359, 1.570796327
        (XARM, None, True),  # as shipped: 1.5708, 3.7e-6 rad off
        (KINOVA, lambda k: repr(k * math.pi / 2 + k * 1e-12), False),  # 1e-12 rad per right angle
        (SO100, None, False),  # as shipped: 6.3e-6 and 1.3e-5 rad off
    ],
    ids=["kinova", "xarm7", "kinova-1e-12", "so100"],
)
def test_rounded_right_angles_give_the_count_of_the_exact_geometry(
    tmp_path, rng, source, rounding, rotor
):
    text = source.read_text()
    rounded = source
    if rounding is not None:
        rounded = written(tmp_path, "rounded.urdf", rewrite_right_angles(text, rounding))
    exact_path = written(tmp_path, "exact.urdf", rewrite_right_angles(text, exact))
    count = mindyn.base_parameters(
        load(exact_path, rotor), rotor=rotor, method="numerical", snap=False
    ).n
    assert count == pinocchio_rank(exact_path, rng, rotor)

    robot = load(rounded, rotor)
    bp = mindyn.base_parameters(robot, rotor=rotor)
    assert bp.n == count
    assert bp.snap_decision["applied"] and bp.snap_decision["rounded"]
    assert not bp.snap_decision["real"]
    assert not bp.margin["near_degenerate"]
    assert bp.snap_report()[0].startswith(f"{len(bp.snap_decision['rounded'])} right angle(s)")
    # the decision is in the JSON document
    assert bp.to_dict()["snap"]["applied"] is True
    # turned off, the description as written: round-off columns kept or decided in the band
    off = mindyn.base_parameters(robot, rotor=rotor, snap=False)
    assert off.snap_decision == {"mode": "off", "applied": False, "tolerance": 0.0}
    assert off.n > count or off.margin["near_degenerate"]


@pytest.mark.parametrize("tilt", [1e-3, 5e-5])
def test_a_deliberate_offset_near_a_right_angle_is_kept(tmp_path, rng, tilt):
    """One right angle of the xArm7 tilted by ``tilt`` rad (a calibration; 5e-5 is above the
    default's bound, 1e-5 rad and three times the 3.7e-6 rad of the 1.5708 the description
    writes), the others written with 4 decimals (as shipped), rotor inertia on the joints: the
    default snaps the rounded ones only and keeps the parameters the tilt makes identifiable;
    forcing a snap of 1e-2 rounds the tilt away too."""
    text = XARM.read_text()
    tilted = first_tilted(tilt, rounded)
    reference = first_tilted(tilt, exact)  # the same tilt, the other right angles exact
    path = written(tmp_path, "tilted.urdf", rewrite_right_angles(text, tilted))
    ref = written(tmp_path, "reference.urdf", rewrite_right_angles(text, reference))
    plain = written(tmp_path, "exact.urdf", rewrite_right_angles(text, exact))
    count = mindyn.base_parameters(load(ref, True), rotor=True, method="numerical", snap=False).n
    assert count == pinocchio_rank(ref, rng, rotor=True)
    # the tilt makes more parameters identifiable
    assert count > pinocchio_rank(plain, rng, rotor=True)

    robot = load(path, True)
    bp = mindyn.base_parameters(robot, rotor=True)
    assert bp.n == count
    d = bp.snap_decision
    assert d["applied"] and d["rounded"]
    assert len(d["real"]) == 1 and d["real"][0][1] == pytest.approx(tilt, rel=1e-6)
    assert d["tolerance"] < tilt
    assert any(line.startswith("kept as written: 1 deliberate") for line in bp.snap_report())
    forced = mindyn.base_parameters(robot, rotor=True, snap=1e-2)
    assert forced.n == pinocchio_rank(plain, rng, rotor=True)


def simulated_log(robot: mindyn.Robot, rng, noise: float = 0.01) -> JointData:
    """A smooth multi-sine trajectory of 20 s at 100 Hz, with torques from the robot's own
    inverse dynamics plus Gaussian noise of ``noise`` times each joint's torque spread."""
    t = np.arange(0.0, 20.0, 0.01)
    w = 2 * np.pi * 0.1 * np.arange(1, 6)
    a = rng.uniform(-0.25, 0.25, (robot.n, 5))
    b = rng.uniform(-0.25, 0.25, (robot.n, 5))
    s, c = np.sin(np.outer(t, w)), np.cos(np.outer(t, w))
    q = s @ a.T + c @ b.T
    dq = (c * w) @ a.T - (s * w) @ b.T
    ddq = -(s * w**2) @ a.T - (c * w**2) @ b.T
    tau = robot.inverse_dynamics(q, dq, ddq)
    tau = tau + noise * tau.std(axis=0) * rng.standard_normal(tau.shape)
    return JointData(t, q, dq, ddq, tau, "simulated")


def test_identification_of_a_rounded_pi_robot_matches_the_truth(rng):
    """The Kinova arm as shipped (right angles written with 9 and 11 decimals), a simulated
    log with 1 % torque noise: every estimate of the default base set is within 5 sigma of the
    true base value and of its size (no estimate of a round-off column), and the snap is
    stated in the text and the JSON document."""
    robot = mindyn.load(KINOVA)
    log = simulated_log(robot, rng)
    report = run(robot, log, rsd_threshold=0.0)
    base, res = report.base, report.result
    truth = base.values(robot.params)
    assert list(res.names) == list(base.names)  # rsd_threshold=0: every base parameter kept
    est, std = np.asarray(res.values), np.asarray(res.std)
    assert np.all(np.abs(est - truth) <= 5 * std + 1e-9 * np.abs(truth).max()), (
        np.abs(est - truth) / std
    )
    assert np.abs(est).max() < 100 * np.abs(truth).max()
    # the decision is stated
    assert base.snap_decision["applied"]
    assert report.to_dict()["base_snap"]["applied"] is True
    assert any(
        "base set: " in line and "right angle(s)" in line for line in report.format().splitlines()
    )


def test_cli_snap_option(tmp_path):
    """``--snap off`` keeps the description as written, ``--snap auto`` is the default and
    says what it did; a value that is not auto, off or a tolerance is refused in one line."""

    def cli(*args):
        return subprocess.run(
            [sys.executable, "-m", "mindyn", *map(str, args)],
            capture_output=True,
            text=True,
            timeout=120,
        )

    default = cli("base", KINOVA)
    assert default.returncode == 0, default.stderr
    assert "right angle(s) written rounded" in default.stdout and "WARNING" not in default.stdout
    off = cli("base", KINOVA, "--snap", "off")
    assert "WARNING        near-degenerate" in off.stdout
    bad = cli("base", KINOVA, "--snap", "sometimes")
    assert bad.returncode != 0 and len(bad.stderr.strip().splitlines()) == 1
    assert "expected auto, off or a finite number" in bad.stderr


def test_identification_snap_option(tmp_path, rng):
    """``snap=False`` identifies the base set of the angles as written (larger than the
    default's on the Kinova with its right angles written 1.5708: 3.7e-6 rad off, which the
    rank tolerance resolves, where the 2e-13 rad of its own 11 decimals are below it), said so
    in the JSON, and a snap that is not "auto", a flag or a tolerance is refused naming it."""
    four = rewrite_right_angles(KINOVA.read_text(), lambda k: repr(round(k * math.pi / 2, 4)))
    robot = mindyn.load(written(tmp_path, "kinova4.urdf", four))
    report = run(robot, simulated_log(robot, rng), snap=False)
    assert report.base.snap_decision["mode"] == "off"
    assert report.base.n == mindyn.base_parameters(robot, snap=False).n
    assert report.base.n > mindyn.base_parameters(robot).n
    assert report.to_dict()["base_snap"]["applied"] is False
    # a friction velocity scale changes only the friction columns: the same snap
    smooth = mindyn.base_parameters(
        robot.with_friction_model("smooth", velocity=[0.1] * robot.n), friction=True
    )
    assert smooth.with_friction_velocity([0.2] * robot.n).snap_decision == smooth.snap_decision
    assert smooth.snap_decision["applied"]
    with pytest.raises(mindyn.ArgumentError, match="snap"):
        IdentifyOptions(snap="sometimes")


SNAP_URDF = """<robot name="snap">
  <link name="base"/>
  <link name="a"><inertial><mass value="1.0"/><origin xyz="0.1 0.02 0.03"/>
    <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.04"/></inertial></link>
  <link name="b"><inertial><mass value="0.8"/><origin xyz="0.05 0.1 -0.02"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.03"/></inertial></link>
  <link name="c"><inertial><mass value="0.6"/><origin xyz="0.02 -0.03 0.1"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.015" iyz="0" izz="0.02"/></inertial></link>
  <link name="d"><inertial><mass value="0.4"/><origin xyz="0.03 0.04 0.05"/>
    <inertia ixx="0.005" ixy="0" ixz="0" iyy="0.006" iyz="0" izz="0.007"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/>
    <origin xyz="0 0 0.3" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
  <joint name="j2" type="revolute"><parent link="a"/><child link="b"/>
    <origin xyz="0.2 0 0" rpy="1.5708 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
  <joint name="j3" type="revolute"><parent link="b"/><child link="c"/>
    <origin xyz="0 0.25 0" rpy="-1.57079632679 0 3.14159"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
  <joint name="j4" type="revolute"><parent link="c"/><child link="d"/>
    <origin xyz="0.1 0 0.1" rpy="0 0.0004 0"/><axis xyz="0.0002 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
</robot>
"""


def description_near_right_angles(text: str) -> list[tuple]:
    """From the URDF text alone (ElementTree): ``(joint index, joint name, frame, component,
    value, multiple of pi/2, deviation)`` of every rpy angle within 1e-3 of a multiple of pi/2
    without being one, and of every component of the unit axis within 1e-3 of 0 without being
    0 (a rotation about one axis or a roll-then-yaw one: its yaw, pitch, roll are the rpy's)."""
    import xml.etree.ElementTree as ET

    out = []
    for k, joint in enumerate(ET.fromstring(text).iter("joint")):
        name = joint.get("name")
        rpy = [float(x) for x in joint.find("origin").get("rpy").split()]
        for component, value in zip(("yaw", "pitch", "roll"), rpy[::-1]):
            right = round(value / (math.pi / 2)) * (math.pi / 2)
            if 0 < abs(value - right) <= 1e-3:
                out.append((k, name, "origin", component, value, right, abs(value - right)))
        axis = np.array([float(x) for x in joint.find("axis").get("xyz").split()])
        for component, value in zip("xyz", axis / np.linalg.norm(axis)):  # a unit axis
            if 0 < abs(value) <= 1e-3:
                out.append((k, name, "axis", component, value, 0.0, abs(value)))
    return out


def test_snap_changes_are_the_description_angles(tmp_path):
    """The core's structured list of what a snap rounds (``snap_changes``: joint, frame,
    component, value, snapped value, deviation) against the URDF's own numbers, read
    independently; its text (``BaseParameters.snappable``) names the same joints; the default
    snap rounds the decimal roundings (1.5708, 1.57079632679, 3.14159) and keeps the
    deliberate 4e-4 rad tilt and the 2e-4 axis component."""
    from mindyn.base import snap_changes

    path = written(tmp_path, "snap.urdf", SNAP_URDF)
    robot = mindyn.load(path)
    expected = description_near_right_angles(SNAP_URDF)
    assert len(expected) == 5
    got = snap_changes(robot)
    assert len(got) == len(expected)
    for c, (k, name, frame, component, value, right, deviation) in zip(got, expected):
        assert (c["joint"], c["joint_name"], c["frame"], c["component"]) == (
            k,
            name,
            frame,
            component,
        )
        assert math.isclose(c["value"], value, rel_tol=0, abs_tol=1e-13)
        assert math.isclose(c["snapped"], right, rel_tol=0, abs_tol=1e-15)
        assert math.isclose(c["deviation"], deviation, rel_tol=1e-9, abs_tol=1e-15)
    listed = mindyn.base_parameters(robot, snap=False).snappable
    assert {n for _, n, *_ in expected} == {re.match(r"joint '(\w+)'", x)[1] for x in listed}
    decision = mindyn.base_parameters(robot).snap_decision
    assert decision["applied"]
    assert sorted(w for w, _ in decision["rounded"]) == [
        "joint 'j2' origin roll",
        "joint 'j3' origin roll",
        "joint 'j3' origin yaw",
    ]
    assert sorted(w for w, _ in decision["real"]) == [
        "joint 'j4' axis x",
        "joint 'j4' origin pitch",
    ]


def test_the_default_snap_computes_the_base_set_once(tmp_path, monkeypatch):
    """When the default snap rounds angles, the base set is computed once (snapped), not first
    as written to find what is near a right angle."""
    from mindyn import _core

    robot = mindyn.load(written(tmp_path, "snap.urdf", SNAP_URDF))
    calls = []
    original = _core.base_parameters

    def counted(*args, **kwargs):
        calls.append(kwargs.get("snap"))
        return original(*args, **kwargs)

    monkeypatch.setattr(_core, "base_parameters", counted)
    assert mindyn.base_parameters(robot).snap_decision["applied"]
    assert len(calls) == 1 and calls[0] > 0


@pytest.mark.parametrize("value", ["off", "sometimes"])
def test_a_snap_word_other_than_auto_is_refused_naming_what_snap_takes(value):
    """``snap="off"`` (the command line's word) is not the library's: the error lists what
    ``snap`` takes (it said "expected one of 'auto'", as if a number or False were refused),
    the same for base_parameters and the identification options."""
    for call in (
        lambda: mindyn.base_parameters("puma560", snap=value),
        lambda: IdentifyOptions(snap=value),
    ):
        with pytest.raises(mindyn.ArgumentError) as info:
            call()
        message = str(info.value)
        assert message.startswith(f"snap is '{value}'; expected 'auto'")
        assert "rotation tolerance in rad" in message and "False" in message


def test_snapped_zero_angles_print_as_0_not_minus_0(tmp_path):
    """A rotation's angles of zero read back from the matrix as -0 (a roll-only rotation's
    pitch), and a small negative angle snapped to zero was -0: ``base`` printed '(0, -0, 1.57..)
    rad -> (0, -0, ...)'. Every zero is printed as 0 in the snap lines and is +0 in the
    structured list; the other numbers are the description's (read back as written)."""
    from mindyn.base import snap_changes

    text = SNAP_URDF.replace('rpy="0 0.0004 0"', 'rpy="0 -0.0004 0"')
    path = written(tmp_path, "snapneg.urdf", text)
    robot = mindyn.load(path)
    minus_zero = re.compile(r"(?<![\w.])-0(?![\w.])")
    lines = mindyn.base_parameters(robot, snap=False).snappable
    assert lines and not any(minus_zero.search(x) for x in lines), lines
    pitch = [c for c in snap_changes(robot) if c["component"] == "pitch"]
    assert len(pitch) == 1 and math.isclose(pitch[0]["value"], -0.0004, rel_tol=1e-12)
    assert pitch[0]["snapped"] == 0.0 and math.copysign(1.0, pitch[0]["snapped"]) == 1.0
    out = subprocess.run(
        [sys.executable, "-m", "mindyn", "base", str(path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    snapped = [x for x in out.stdout.splitlines() if "rotation (yaw, pitch, roll)" in x]
    assert snapped and not any(minus_zero.search(x) for x in snapped), out.stdout


def test_predict_detect_and_codegen_take_the_snap_the_identification_had(tmp_path):
    """An identification with --snap off (the Kinova with its right angles written 1.5708: a
    larger base set) could not be used: predict, detect and codegen --params built the default
    snapped set and refused the JSON's parameter names. They now take the snap the JSON
    records; predict's torques on the noise-free log equal the simulated ones (the description
    as written), and the generated code has the JSON's base set."""
    from mindyn.cli import main

    four = rewrite_right_angles(KINOVA.read_text(), lambda k: repr(round(k * math.pi / 2, 4)))
    urdf = written(tmp_path, "kinova4.urdf", four)
    n = mindyn.load(urdf).n
    log, ident = tmp_path / "x.csv", tmp_path / "id.json"
    assert main([str(a) for a in ["simulate", urdf, "--mode", "inverse", "-o", log]]) == 0
    argv = ["identify", urdf, log, "--snap", "off", "--rsd-threshold", "0", "--json", ident]
    assert main([str(a) for a in argv]) == 0
    names = json.loads(ident.read_text())["base_names"]
    assert len(names) > mindyn.base_parameters(mindyn.load(urdf)).n  # the case: sets differ
    pred = tmp_path / "p.csv"
    assert main([str(a) for a in ["predict", urdf, ident, log, "-o", pred]]) == 0
    cols = pred.read_text().splitlines()[0].split(",")
    data = np.loadtxt(pred, delimiter=",", skiprows=1)
    hat = data[:, [cols.index(f"tau_hat{k}") for k in range(1, n + 1)]]
    tau = data[:, [cols.index(f"tau{k}") for k in range(1, n + 1)]]
    assert np.abs(hat - tau).max() <= 1e-4 * np.abs(tau).max()
    assert main([str(a) for a in ["detect", urdf, ident, log]]) == 0
    out = tmp_path / "g"
    argv = ["codegen", urdf, "--lang", "c", "--params", ident, "-o", out]
    assert main([str(a) for a in argv]) == 0
    assert f"[{len(names)}]" in (tmp_path / "g.h").read_text()
