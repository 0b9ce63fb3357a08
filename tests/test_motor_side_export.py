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
def test_yaml_export_records_the_drive_side_and_reads_back(tmp_path, side):
    rows = np.diag([60.0, -100.0, 50.0, 40.0, 40.0, 30.0])
    rows[5, 4] = 30.0  # motor 6 turns with joints 5 and 6
    robot = mindyn.load(table_with_transmissions(tmp_path, rows.tolist())).with_drive_side(side)
    p = motor_params(robot)
    res = write_yaml(robot, p, tmp_path / "out.yaml")
    doc = yaml.safe_load(res.path.read_text())
    assert doc["drive_side"] == side
    back = mindyn.load(res.path)
    assert back.drive_side == side
    q = back.parameters(rotor=True, friction=True)
    if side == "joint":  # the slots are the joints': as written
        np.testing.assert_array_equal(q, p)
        assert res.sidecar is None
    else:  # direct drives divided back; the coupled motors 5 and 6 in the sidecar only
        keep = np.ones(13 * 6, bool)
        keep[[13 * k + c for k in (4, 5) for c in (10, 11, 12)]] = False
        np.testing.assert_allclose(q[keep], p[keep], rtol=1e-14)
        assert (q[~keep] == 0).all()
        assert any("'j5', 'j6'" in note for note in res.notes), res.notes
        assert read_joint_terms(res.sidecar)["Ia6"] == p[13 * 5 + 10]


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
    rotor inertia and friction there are refused in one line; on the joints they work."""
    rows = np.vstack([np.diag([60.0, -100.0, 50.0, 40.0, 40.0, 30.0]), np.ones((1, 6))])
    doc = yaml.safe_load(open(mindyn.load("puma560").source).read())
    doc["transmissions"] = {"matrix": rows.tolist()}
    path = tmp_path / "seven.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    robot = mindyn.load(path)
    q = np.zeros(6)
    with pytest.raises(mindyn.ModelError, match="7 motors for 6 joints") as e:
        robot.regressor(q, q, q, rotor=True)
    assert "\n" not in str(e.value)
    with pytest.raises(mindyn.ModelError, match="one motor per joint"):
        mindyn.base_parameters(robot, friction=True)
    robot.regressor(q, q, q)  # without rotor and friction: nothing to place
    robot.with_drive_side("joint").regressor(q, q, q, rotor=True, friction=True)
