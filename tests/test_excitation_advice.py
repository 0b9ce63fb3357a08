"""The excitation's warning of a peak torque beyond an effort limit gives the advice that
applies: it advised lowering the effort share, which only derives acceleration limits where
the description gives none, also for a description that gives them and for a joint whose
gravity torque alone exceeds its effort limit; and --effort-share was taken without effect
when every joint has an acceleration limit."""

from __future__ import annotations

import json

import mindyn
import numpy as np
import pinocchio as pin
from conftest import pinocchio_model
from mindyn import cli
from mindyn.identification.data import read_csv


def planar_yaml(path, gravity, effort1) -> str:
    """Two joints about z in the xy plane, acceleration limits given (2000 deg/s^2)."""
    path.write_text(f"""\
name: planar_acc
convention: mdh
angle_unit: deg
gravity: {gravity}
joints:
  - name: j1
    alpha: 0
    d: 0
    theta: 0
    r: 0
    limits: {{lower: -80, upper: 80, velocity: 300, acceleration: 2000, effort: {effort1}}}
    inertial: {{mass: 2.0, com: [0.25, 0, 0], inertia: {{xx: 0.01, yy: 0.04, zz: 0.04}}}}
  - name: j2
    alpha: 0
    d: 0.5
    theta: 0
    r: 0
    limits: {{lower: -90, upper: 90, velocity: 300, acceleration: 2000, effort: 100}}
    inertial: {{mass: 1.0, com: [0.2, 0, 0], inertia: {{xx: 0.005, yy: 0.02, zz: 0.02}}}}
""")
    return str(path)


def run(tmp_path, capsys, path, *extra):
    out = tmp_path / "traj.csv"
    argv = ["excite", path, "--harmonics", "3", "--starts", "1", "--maxiter", "10", "--quiet"]
    code = cli.main([*argv, *extra, "-o", str(out)])
    captured = capsys.readouterr()
    return code, captured.out + captured.err, out


def gravity_share(path, csv, effort):
    """The largest gravity torque of joint 1 along the CSV over its effort limit (Pinocchio)."""
    robot = mindyn.load(path)
    model = pinocchio_model(robot)
    data = model.createData()
    d = read_csv(csv, n=2, require_torque=False)
    g = [pin.computeGeneralizedGravity(model, data, q)[0] for q in d.q]
    return np.abs(g).max() / effort


def test_gravity_alone_beyond_the_effort_limit_is_said(tmp_path, capsys):
    path = planar_yaml(tmp_path / "a.yaml", [0, -9.81, 0], 1.0)  # g m c >= 1.8 N m at 80 deg
    code, text, csv = run(tmp_path, capsys, path)
    assert code == 0
    (line,) = [x for x in text.splitlines() if "WARNING: joint 1:" in x]
    share = gravity_share(path, csv, 1.0)
    assert share > 1
    assert f"gravity alone along it reaches {100 * share:.0f} %" in line, (line, share)
    assert "effort share" not in line
    doc = json.loads(csv.with_suffix(".json").read_text())
    assert doc["limits"]["acceleration_source"] == ["description"] * 2


def test_description_acceleration_limits_beyond_the_effort_limit_are_named(tmp_path, capsys):
    path = planar_yaml(tmp_path / "b.yaml", [0, 0, -9.81], 0.5)  # axes along gravity
    code, text, csv = run(tmp_path, capsys, path)
    assert code == 0
    (line,) = [x for x in text.splitlines() if "WARNING: joint 1:" in x]
    assert gravity_share(path, csv, 0.5) == 0
    assert "the acceleration limits are the description's (gravity alone reaches 0 %)" in line
    assert "lower them (the effort share applies only where no acceleration limit" in line
    code, text, _ = run(tmp_path, capsys, path, "--effort-share", "0.5")
    assert code == 2
    assert "--effort-share: applies where the description gives no acceleration limit" in text
