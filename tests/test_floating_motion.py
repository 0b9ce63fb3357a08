"""Velocities and accelerations of floating-base logs derived from their configurations alone,
against a known motion: the configuration of a robot on a free-flyer (or planar) root as a
closed-form function of time (positions and joint angles as sines, the base's orientation the
exponential of a time-varying rotation vector, its quaternion's sign flipped every few samples
as a log may have it), the reference velocity from Pinocchio's Lie-group difference of the
configurations at t +- h (pin.difference: a free-flyer's body-axis twist, a planar joint's
local velocity) and the reference acceleration from the difference of those velocities. And
``mindyn identify`` on such a log with its q, torques and wrenches only."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest
from conftest import assert_close, cli, rel_err
from mindyn.identification.data import DataError
from random_tree import random_tree_urdf
from test_floating_cli import AXES, SOLO, pair, truth, write


def motion(root: str, n: int = 12, scale: float = 1.0):
    """q(t) of a robot with n joints on a free-flyer or planar root, as a closed form."""

    def q(t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        w = scale * (0.7 + 0.45 * np.arange(n))
        joints = 0.5 * np.sin(np.outer(t, w) + np.arange(n))
        p = np.column_stack([np.sin(t), np.cos(2 * t), 0.3 * t**2])
        if root == "floating":
            a = np.column_stack([2 * np.sin(1.3 * t), 0.8 * t, np.cos(0.9 * t)])
            Q = np.array([pin.Quaternion(pin.exp3(x)).coeffs() for x in a])
            Q[::7] *= -1  # the same rotations, another sign
            return np.hstack([p, Q, joints])
        th = 3 * np.sin(t) + t
        return np.hstack([p[:, :2], np.cos(th)[:, None], np.sin(th)[:, None], joints])

    return q


def reference(model, q, t, h: float = 1e-5):
    """Velocities and accelerations of q(t) from Pinocchio's Lie-group differences."""

    def v(s):
        return np.array([pin.difference(model, q(x - h)[0], q(x + h)[0]) / (2 * h) for x in s])

    return v(t), (v(t + 1e-4) - v(t - 1e-4)) / 2e-4


@pytest.mark.parametrize("root", ["floating", "planar"])
def test_velocities_and_accelerations_of_a_known_motion(root):
    from mindyn.identification.floating_motion import configuration_derivatives

    robot, model = pair(SOLO, root)
    q = motion(root)
    t = np.arange(0.0, 3.0, 0.002)
    V, A = reference(model, q, t)
    inner = slice(150, -150)  # the filter's edges
    for filt, tol_v, tol_a in (("none", 1e-4, 3e-4), ("butter", 1e-4, 1e-3)):
        qf, dq, ddq, info = configuration_derivatives(robot, t, q(t), filter=filt)
        assert info["filter"].startswith(filt if filt == "none" else "butterworth")
        assert_close(dq[inner], V[inner], tol_v, f"derived dq ({root}, {filt})")
        assert_close(ddq[inner], A[inner], tol_a, f"derived ddq ({root}, {filt})")
        # the configuration: the logged rotations (any quaternion sign), renormalised
        ref = q(t)
        if root == "floating":
            same = np.abs(np.sum(qf[inner, 3:7] * ref[inner, 3:7], axis=1))
            assert np.abs(same - 1).max() < 1e-6
    # the angular velocity is the body's, not the world's: they differ on this motion
    if root == "floating":
        R = np.array([pin.Quaternion(x).toRotationMatrix() for x in q(t)[inner, 3:7]])
        world = np.einsum("mij,mj->mi", R, V[inner, 3:6])
        assert rel_err(dq[inner, 3:6], world) > 0.1


def test_a_log_of_configurations_is_identified_on_the_command_line(tmp_path):
    """A random tree on a free-flyer, two leaf links in contact, on a known motion at 250 Hz;
    the log holds t, q, torques and wrenches only: identify derives dq and ddq (--filter none:
    central differences; the default Butterworth), drops the samples at the ends where they are
    not the motion's, says so, and recovers the base values to the precision of the
    differences."""
    urdf = str(random_tree_urdf(tmp_path / "tree.urdf", n=6, seed=3, moving=("revolute",)))
    robot, model = pair(urdf)
    children = set(robot.parents)
    leaves = [robot.link_names[k + 1] for k in range(robot.n) if k not in children][:2]
    t = np.arange(0.0, 2.0, 1 / 250)
    q = motion("floating", n=robot.n - 1, scale=2.5)
    Q = q(t)
    V, A = reference(model, q, t)
    data, rng = model.createData(), np.random.default_rng(4)
    rows = []
    for qi, vi, ai in zip(Q, V, A):
        F = pin.rnea(model, data, qi, vi, ai)
        pin.computeJointJacobians(model, data, qi)
        pin.updateFramePlacements(model, data)
        frame = pin.LOCAL_WORLD_ALIGNED
        J = [pin.getFrameJacobian(model, data, model.getFrameId(c), frame) for c in leaves]
        Jt = np.hstack([j.T for j in J])
        f = rng.normal(0, 5, Jt.shape[1])
        f += np.linalg.pinv(Jt[:6]) @ (F[:6] - Jt[:6] @ f)
        rows.append(np.r_[(F - Jt @ f)[6:], f])
    header = ["t"] + [f"q{i + 1}" for i in range(robot.nq)]
    header += [f"tau{i + 1}" for i in range(robot.nv - 6)]
    header += [f"{c}.{a}" for c in leaves for a in AXES]
    log = write(tmp_path / "q.csv", np.hstack([t[:, None], Q, np.array(rows)]), header)
    out = tmp_path / "id.json"
    _, true = truth(robot)
    for filt, tol, edge in (("none", 2e-3, 2), ("butter", 5e-4, 102)):
        text = cli("identify", urdf, log, "--root-joint", "floating", "--filter", filt,
                   "--json", out)  # fmt: skip
        doc = json.loads(out.read_text())
        derived = doc["data"]["logs"][0]["derivatives"]
        assert derived["velocity"].startswith("differentiated configurations")
        # butter: 2 / (the default cut-off min(10 Hz, rate / 10)) at 250 Hz for each of the two
        # derivations (velocities, then accelerations from them), + 2
        assert derived["edge_samples"] == edge and doc["data"]["samples"] == len(t) - 2 * edge
        assert f"dq and ddq derived ({filt}" in text and f"{edge} samples dropped" in text
        err = rel_err(doc["values"], true)
        print(f"--filter {filt}: base values within {err:.2e} of the truth")
        assert err < tol
        assert doc["fit"]["overall_relative"] < 1e-2


def test_a_log_without_dq_needs_its_time_column(tmp_path):
    robot, model = pair(SOLO)
    t = np.arange(0.0, 0.5, 0.01)
    header = [f"q{i + 1}" for i in range(robot.nq)]
    path = tmp_path / "q.csv"
    write(path, motion("floating")(t), header)
    from mindyn.identification.floating import read_floating_csv

    with pytest.raises(DataError, match="no dq and ddq columns and no time column 't'"):
        read_floating_csv(path, robot)
    write(path, np.hstack([t[:, None], motion("floating")(t)]), ["t", *header])
    with pytest.raises(DataError, match="too few for a Butterworth|cutoff"):
        read_floating_csv(path, robot, cutoff=100.0)
    log = read_floating_csv(path, robot, filter="none")
    assert log.dq.shape == (len(t) - 4, robot.nv) and log.tau is None  # 2 edge samples each end


def test_a_log_of_configurations_stamped_in_milliseconds_is_refused(tmp_path):
    """Its velocities and accelerations derived over t in ms would be 1e3 and 1e6 too small:
    the median interval (10 here) is named with the unit and rate it suggests; with dq and
    ddq logged t is not used, and the same stamps are taken."""
    from mindyn.identification.floating import read_floating_csv

    robot, model = pair(SOLO)
    t = np.arange(0.0, 2.0, 0.01)
    header = [f"q{i + 1}" for i in range(robot.nq)]
    path = tmp_path / "ms.csv"
    Q = motion("floating")(t)
    write(path, np.hstack([1e3 * t[:, None], Q]), ["t", *header])
    step = np.median(np.diff(1e3 * t))
    with pytest.raises(DataError) as e:
        read_floating_csv(path, robot)
    msg = str(e.value)
    assert msg.startswith(f"{path}: the median interval between its time stamps is {step:.4g} s")
    assert "milliseconds (a log of 100 Hz)" in msg and "\n" not in msg, msg
    V, A = reference(model, motion("floating"), t)
    dv = [f"{k}{i + 1}" for k in ("dq", "ddq") for i in range(robot.nv)]
    write(path, np.hstack([1e3 * t[:, None], Q, V, A]), ["t", *header, *dv])
    assert read_floating_csv(path, robot).dq.shape == (len(t), robot.nv)
