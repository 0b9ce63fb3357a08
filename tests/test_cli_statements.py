"""What the commands state about the choices they made for the user, and how their refusals
name the options, on inputs the other tests do not take: a description with an effort limit on
some joints only, a tree given to a command that needs a chain."""

from __future__ import annotations

import contextlib
import io
import json

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import ROBOTS_DIR, pinocchio_model
from mindyn import cli

# a vertical two-link arm (joint 1's axis horizontal), an effort limit on joint 1 only
TWO_LINK = """\
name: half_limited
convention: mdh
angle_unit: deg
joints:
  - name: shoulder
    type: revolute
    alpha: 90
    d: 0
    theta: 0
    r: 0
    limits: {lower: -170, upper: 170, velocity: 3, effort: 50}
    inertial: {mass: 2.0, com: [0.2, 0, 0], inertia: {xx: 0.01, yy: 0.02, zz: 0.02}}
  - name: elbow
    type: revolute
    alpha: 0
    d: 0.4
    theta: 0
    r: 0
    limits: {lower: -150, upper: 150, velocity: 3}
    inertial: {mass: 1.0, com: [0.15, 0, 0], inertia: {xx: 0.005, yy: 0.01, zz: 0.01}}
"""


def run(argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main([str(a) for a in argv])
    return rc, out.getvalue(), err.getvalue()


def test_torque_noise_in_percent_states_what_it_is_taken_of(tmp_path):
    """`simulate --torque-noise 1%` on joints without an effort limit takes the peak torque
    along the reference: the output says so per joint, and the levels are 1 % of the effort
    limit and of the gravity torque that a resting reference needs (Pinocchio)."""
    (tmp_path / "arm.yaml").write_text(TWO_LINK)
    q = np.array([0.3, -0.5])
    rows = "\n".join(f"{t:g},{q[0]},{q[1]}" for t in np.linspace(0.0, 1.0, 11))
    (tmp_path / "rest.csv").write_text("t,q1,q2\n" + rows + "\n")
    rc, out, err = run(
        [
            "simulate",
            tmp_path / "arm.yaml",
            "--trajectory",
            tmp_path / "rest.csv",
            "--mode",
            "inverse",
            "--torque-noise",
            "1%",
            "-o",
            tmp_path / "log.csv",
        ]
    )
    assert rc == 0, err
    robot = mindyn.load(tmp_path / "arm.yaml")
    model = pinocchio_model(robot)
    g = pin.computeGeneralizedGravity(model, model.createData(), q)
    assert abs(g[1]) > 0.1  # the elbow holds a torque at rest
    truth = json.loads((tmp_path / "log.truth.json").read_text())
    sd = np.array(truth["simulation"]["noise"]["torque"])
    np.testing.assert_allclose(sd, [0.01 * 50.0, 0.01 * abs(g[1])], rtol=1e-9)
    (line,) = [s for s in out.splitlines() if "torque noise sd" in s]
    assert "1 % of the effort limit" in line, line
    assert "peak torque along the reference for joint(s) 2" in line, line


def test_torque_noise_in_newton_metres_states_its_unit(tmp_path):
    rc, out, err = run(
        ["simulate", "planar2", "--mode", "inverse", "--torque-noise", "0.1", "-o", tmp_path]
    )
    assert rc == 0, err
    (line,) = [s for s in out.splitlines() if "torque noise sd" in s]
    assert line.split(":")[1].split() == ["0.1", "0.1", "[N", "m", "|", "N]"], line


def test_a_tree_refused_by_ik_names_the_tip_option_as_each_interface_spells_it():
    urdf = ROBOTS_DIR / "solo_description/robots/solo12.urdf"
    rc, _, err = run(["ik", urdf, "--xyz", "0.2", "0.1", "-0.2"])
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert "--tip <link>" in err and "mindyn.load(" not in err, err
    robot = mindyn.load(urdf)
    with pytest.raises(mindyn.ModelError, match="tip='<link>'"):
        mindyn.ik(robot, np.eye(4))
