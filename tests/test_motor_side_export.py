"""Export and description values with rotor inertia and friction on the motors: a directly
driven joint carries its motor's terms as they act on it (r^2 Ia, r^2 Fv, |r| Fc), a coupled
motor's go to the sidecar only (with a note), the description's joint-side values fill the motor
slots divided back, and a YAML table records the drive side and reads back."""

from __future__ import annotations

import mindyn
import numpy as np
import pytest
import yaml
from coupled_arms import coupled_wrist_urdf, motor_values
from mindyn.export import read_joint_terms, write_urdf, write_yaml


def motor_params(robot):
    p = robot.parameters(rotor=True, friction=True).reshape(robot.n, 13).copy()
    p[:, 10], p[:, 11], p[:, 12] = motor_values(robot.n, seed=3)
    return p.reshape(-1)


def test_urdf_export_reflects_direct_drives_and_notes_the_coupled_motors(tmp_path):
    path, T = coupled_wrist_urdf(tmp_path / "w.urdf")
    robot = mindyn.load(path)
    p = motor_params(robot)
    Ia, Fv, Fc = p[10::13], p[11::13], p[12::13]
    res = write_urdf(robot, p, tmp_path / "out.urdf")
    assert any("'j5', 'j6'" in note and "'m5', 'm6'" in note for note in res.notes), res.notes
    back = mindyn.load(res.path)
    r = np.diag(T)[:4]
    np.testing.assert_allclose(back.viscous[:4], r**2 * Fv[:4], rtol=1e-15)
    np.testing.assert_allclose(back.coulomb[:4], np.abs(r) * Fc[:4], rtol=1e-15)
    assert back.viscous[4] == back.viscous[5] == back.coulomb[4] == back.coulomb[5] == 0.0
    # the description's joint-side values fill the motor slots divided back; coupled ones 0
    q = back.parameters(rotor=False, friction=True).reshape(6, 12)
    np.testing.assert_allclose(q[:4, 10], Fv[:4], rtol=1e-14)
    np.testing.assert_allclose(q[:4, 11], Fc[:4], rtol=1e-14)
    assert (q[4:, 10:] == 0).all()
    # the sidecar holds the motor values, per motor
    side = yaml.safe_load(res.sidecar.read_text())
    assert side["drive_side"] == "motor"
    assert [row["motor"] for row in side["joints"]] == list(robot.transmission.motors)
    # each term said to be the row's motor's, not the joint's (nor the URDF joint's <dynamics>)
    for key in ("Ia", "Fv", "Fc"):
        assert "of the row's motor" in side["terms"][key], side["terms"][key]
        assert "joint side" not in side["terms"][key] and "<dynamics" not in side["terms"][key]
    # on the joint side the terms are the joint's
    joint = write_urdf(robot.with_drive_side("joint"), p, tmp_path / "joint.urdf")
    meaning = yaml.safe_load(joint.sidecar.read_text())["terms"]
    assert meaning["Ia"].startswith("rotor (armature) inertia reflected to the joint side")
    terms = read_joint_terms(res.sidecar)
    np.testing.assert_array_equal([terms[f"Ia{k + 1}"] for k in range(6)], Ia)
    np.testing.assert_array_equal([terms[f"Fc{k + 1}"] for k in range(6)], Fc)


def table_with_transmissions(tmp_path, rows):
    doc = yaml.safe_load(open(mindyn.load("puma560").source).read())
    doc["transmissions"] = {"matrix": rows, "motors": [f"m{k + 1}" for k in range(6)]}
    path = tmp_path / "puma_t.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


@pytest.mark.parametrize("side", ["motor", "joint"])
def test_yaml_export_records_the_drive_side_and_the_motor_values_and_reads_back(tmp_path, side):
    rows = np.diag([60.0, -100.0, 50.0, 40.0, 40.0, 30.0])
    rows[5, 4] = 30.0  # motor 6 turns with joints 5 and 6
    robot = mindyn.load(table_with_transmissions(tmp_path, rows.tolist())).with_drive_side(side)
    p = motor_params(robot)
    res = write_yaml(robot, p, tmp_path / "out.yaml")
    doc = yaml.safe_load(res.path.read_text())
    assert doc["drive_side"] == side
    back = mindyn.load(res.path)
    assert back.drive_side == side
    # the slots read back as written: the joints' (joint side) or the motors' own values,
    # coupled motors included (motor side)
    np.testing.assert_array_equal(back.parameters(rotor=True, friction=True), p)
    assert res.sidecar is None
    tr = doc["transmissions"]
    if side == "joint":
        assert "rotor_inertia" not in tr and "viscous" not in tr
    else:
        assert tr["rotor_inertia"] == list(p[10::13]) and tr["coulomb"] == list(p[12::13])
        assert any("'j5', 'j6'" in note and "under 'transmissions'" in note for note in res.notes)
        # the joints carry a direct drive's terms as they act on them
        r = np.diag(rows)[:4]
        j = back.with_drive_side("joint").parameters(rotor=True, friction=True)
        np.testing.assert_allclose(j[10 : 13 * 4 : 13], r**2 * p[10 : 13 * 4 : 13], rtol=1e-15)
        assert j[13 * 4 + 10] == j[13 * 5 + 10] == 0.0


def test_drive_side_key_is_checked(tmp_path):
    path = table_with_transmissions(tmp_path, np.eye(6).tolist())
    text = path.read_text()
    path.write_text(text + "drive_side: motors\n")
    with pytest.raises(mindyn.ModelError, match="'drive_side' must be 'motor' or 'joint'"):
        mindyn.load(path)
    plain = tmp_path / "plain.yaml"
    plain.write_text(open(mindyn.load("puma560").source).read() + "drive_side: motor\n")
    with pytest.raises(mindyn.ModelError, match="needs 'transmissions'"):
        mindyn.load(plain)


def test_motor_side_terms_need_one_motor_per_joint(tmp_path):
    """Seven motors on six joints (a redundant drive): the motor side has no slot per motor, so
    rotor inertia and friction act on the joints, by default (the base parameters are those of
    the robot without transmissions), and the motor side is refused in one line."""
    rows = np.vstack([np.diag([60.0, -100.0, 50.0, 40.0, 40.0, 30.0]), np.ones((1, 6))])
    doc = yaml.safe_load(open(mindyn.load("puma560").source).read())
    doc["transmissions"] = {"matrix": rows.tolist()}
    path = tmp_path / "seven.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    robot = mindyn.load(path)
    assert robot.drive_side == "joint"
    with pytest.raises(mindyn.ModelError, match="7 motors for 6 joints") as e:
        robot.with_drive_side("motor")
    assert "\n" not in str(e.value)
    plain = mindyn.base_parameters(mindyn.load("puma560"), rotor=True, friction=True)
    ours = mindyn.base_parameters(robot, rotor=True, friction=True)
    assert ours.names == plain.names


def test_per_motor_values_in_the_list_form_and_their_check(tmp_path):
    doc = yaml.safe_load(open(mindyn.load("puma560").source).read())
    joints = [j["name"] for j in doc["joints"]]
    motors = [{"name": f"m{k + 1}", "joints": {joints[k]: 50.0}} for k in range(6)]
    motors[5]["joints"][joints[4]] = 30.0  # motor 6 turns with joints 5 and 6
    motors[5].update({"rotor_inertia": 2e-4, "viscous": 1e-3, "coulomb": 0.05})
    doc["transmissions"] = motors
    path = tmp_path / "list.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    p = mindyn.load(path).parameters(rotor=True, friction=True)
    assert (p[13 * 5 + 10], p[13 * 5 + 11], p[13 * 5 + 12]) == (2e-4, 1e-3, 0.05)
    # motor 1 gives none: its joint's (published, joint-side) values divided back
    joint1 = doc["joints"][0]
    assert p[10] == pytest.approx(joint1["rotor_inertia"] / 50.0**2, rel=1e-15)
    motors[5]["viscous"] = -1.0
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    with pytest.raises(
        mindyn.ModelError,
        match=r"list\.yaml:\d+:\d+: transmissions, motor 6 \('m6'\): 'viscous' is -1; rotor "
        "inertia and friction are >= 0",
    ) as e:
        mindyn.load(path)
    assert "\n" not in str(e.value)
