"""A KUKA-style coupled wrist on a YAML table: motor 4 drives joint 4 alone, motor 5 turns with
joints 4 and 5, motor 6 with joints 4, 5 and 6 (q_m = T q, T's wrist block lower triangular).
The export's note says of each motor why its terms cannot be written per joint, the table
written reads back to the values given, and ``info`` lists the torque constants that currents
are converted with."""

from __future__ import annotations

import mindyn
import numpy as np
from conftest import cli
from mindyn.export import write_yaml

RATIOS = [150.0, 80.0, 70.0, 50.0]
KT = [1.2, 0.45, 0.4, 0.3]


def wrist_table(path):
    """A 4R arm (a shoulder and a spherical wrist) whose joints 2-4 are coupled as a KUKA
    wrist's: m2 = 80 q2, m3 = 70 (q3 + 0.5 q2), m4 = 50 (q4 + 0.3 q2 + 0.8 q3)."""
    T = np.diag(RATIOS)
    T[2, 1] = RATIOS[2] * 0.5
    T[3, 1], T[3, 2] = RATIOS[3] * 0.3, RATIOS[3] * 0.8
    joints = []
    geometry = [(0.0, 0.0, 0.6), (-np.pi / 2, 0.3, 0.0), (np.pi / 2, 0.0, 0.5), (-np.pi / 2, 0, 0)]
    for k, (alpha, d, r) in enumerate(geometry):
        joints.append(
            f"  - {{name: j{k + 1}, type: revolute, alpha: {alpha!r}, d: {d}, theta: 0, r: {r},"
            f" limits: {{lower: -3, upper: 3, velocity: 3, effort: 300}},"
            f" inertial: {{mass: {8.0 - k}, com: [0.02, -0.01, 0.05],"
            f" inertia: {{xx: 0.08, yy: 0.07, zz: 0.05, xy: 0.004}}}}}}"
        )
    rows = "\n".join("    - [" + ", ".join(repr(float(x)) for x in row) + "]" for row in T)
    path.write_text(
        "name: wrist4\nconvention: mdh\nangle_unit: rad\njoints:\n"
        + "\n".join(joints)
        + f"\ntransmissions:\n  matrix:\n{rows}\n  motors: [m1, m2, m3, m4]\n"
        + f"  torque_constant: {KT}\n"
    )
    return path, T


def test_export_note_says_why_each_coupled_motor_is_not_written_per_joint(tmp_path):
    path, T = wrist_table(tmp_path / "wrist4.yaml")
    robot = mindyn.load(path)
    np.testing.assert_array_equal(robot.transmission.T, T)
    p = robot.parameters(rotor=True, friction=True).reshape(4, 13)
    p[:, 10:] = [[4e-4, 2e-3, 0.25], [8e-5, 6e-4, 0.06], [6e-5, 5e-4, 0.05], [4e-5, 3e-4, 0.03]]
    res = write_yaml(robot, p.reshape(-1), tmp_path / "out.yaml")
    (note,) = [n for n in res.notes if "cannot be written per joint" in n]
    assert "joints 'j2', 'j3', 'j4'" in note
    # m2 turns with j2 alone: it is left out because m3 and m4 drive j2 too, not because it
    # turns with several joints
    assert "'m3', 'm4' turn with several joints" in note
    assert "'m2' drives 'j2', which other motors drive too" in note
    back = mindyn.load(res.path)
    np.testing.assert_allclose(
        back.parameters(rotor=True, friction=True), p.reshape(-1), rtol=1e-15, atol=0
    )
    # the directly driven joint 1 carries its motor's terms as they act on it
    assert back.viscous[0] == RATIOS[0] ** 2 * 2e-3
    assert back.viscous[1] == back.viscous[2] == back.viscous[3] == 0.0


def test_info_lists_the_torque_constants(tmp_path):
    path, _ = wrist_table(tmp_path / "wrist4.yaml")
    out = cli("info", path)
    lines = out.splitlines()
    head = next(i for i, line in enumerate(lines) if line.startswith("#") and "q_m" in line)
    assert "K_t [N m/A]" in lines[head]
    for k in range(4):
        words = lines[head + 1 + k].split()
        assert float(words[3]) == KT[k]  # slot, motor, type, K_t, then q_m's terms
    assert lines[head + 4].endswith("+15 j2 +40 j3 +50 j4")


def test_info_without_torque_constants_has_no_column(tmp_path):
    path, _ = wrist_table(tmp_path / "wrist4.yaml")
    path.write_text(path.read_text().replace(f"  torque_constant: {KT}\n", ""))
    out = cli("info", path)
    assert "K_t" not in out
