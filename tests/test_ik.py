"""Inverse kinematics: the textbook's two-link closed form (8.17), the IK solver's own Jacobian
against Pinocchio and finite differences, velocity IK on the redundant Panda (commanded twist
reproduced, null-space motion), damping at a singularity, resolved-rate tracking, and position IK
checked with Pinocchio's forward kinematics and the joint limits; the ``ik`` command."""

from __future__ import annotations

import json

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import assert_close, load_urdf_pair, pinocchio_model, random_state
from mindyn import _core
from mindyn.cli import main
from mindyn.inverse_kinematics import (
    circle_path,
    damped_pinv,
    ik_solve,
    limits_gradient,
    line_path,
    pose_error,
    pose_from_xyz_rpy,
    resolved_rate,
    velocity_ik,
)

LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


def test_two_link_closed_form_8_17(rng):
    """Textbook, (8.17): dq1 = (c12 dx + s12 dy) / (l1 s2),
    dq2 = -((l1 c1 + l2 c12) dx + (l1 s1 + l2 s12) dy) / (l1 l2 s2); det J = l1 l2 s2.
    planar2h moves in the base x-y plane, the arm along +x at q = 0 (l1 = l2 = 0.5 m)."""
    robot = mindyn.load("planar2h")
    l1 = l2 = 0.5
    for _ in range(10):
        q1 = rng.uniform(-np.pi, np.pi)
        q2 = rng.choice([-1, 1]) * rng.uniform(0.2, np.pi - 0.2)  # away from sin q2 = 0
        q = np.array([q1, q2])
        dx, dy = rng.uniform(-1, 1, 2)
        c1, s1, s2 = np.cos(q1), np.sin(q1), np.sin(q2)
        c12, s12 = np.cos(q1 + q2), np.sin(q1 + q2)
        expected = [
            (c12 * dx + s12 * dy) / (l1 * s2),
            -((l1 * c1 + l2 * c12) * dx + (l1 * s1 + l2 * s12) * dy) / (l1 * l2 * s2),
        ]
        dq = velocity_ik(robot, q, [dx, dy], task=[0, 1])
        assert_close(dq, expected, 1e-12, "velocity IK vs the textbook (8.17)")
        J = robot.jacobian(q)[:2]
        assert np.linalg.det(J) == pytest.approx(l1 * l2 * s2, rel=1e-12)


@pytest.mark.parametrize("name", ["puma560", "zcr07s", "stanford", "ur5", "panda"])
def test_ik_solver_kinematics_match_pinocchio_and_finite_differences(name, rng):
    if name in ("ur5", "panda"):
        robot, model = load_urdf_pair(name, tip="tool0" if name == "ur5" else "panda_hand")
        frame = "tool0" if name == "ur5" else "panda_hand"
    else:
        robot = mindyn.load(name)
        model, frame = pinocchio_model(robot), "tool"
    data = model.createData()
    fid = model.getFrameId(frame)
    solver = _core.IkSolver(robot._m)
    h = 1e-6
    for _ in range(3):
        q, _, _ = random_state(robot, rng)
        pin.framesForwardKinematics(model, data, q)
        assert_close(solver.pose(q), data.oMf[fid].homogeneous, 1e-12, "IK chain pose vs pin")
        J = solver.jacobian(q)
        assert_close(J, pin.computeFrameJacobian(model, data, q, fid, LWA), 1e-12, "IK J vs pin")
        Jfd = np.zeros_like(J)
        for k in range(robot.n):
            e = np.zeros(robot.n)
            e[k] = h
            Tp, Tm = solver.pose(q + e), solver.pose(q - e)
            Jfd[:3, k] = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
            Jfd[3:, k] = pin.log3(Tp[:3, :3] @ Tm[:3, :3].T) / (2 * h)
        assert_close(J, Jfd, 1e-8, "IK J vs finite differences")


def test_velocity_ik_on_the_redundant_panda(rng):
    robot, _ = load_urdf_pair("panda")
    done = 0
    while done < 5:
        q, _, _ = random_state(robot, rng)
        J = robot.jacobian(q)
        if np.linalg.svd(J, compute_uv=False)[-1] < 0.05:
            continue  # near a singularity the damping applies (tested below)
        done += 1
        twist = rng.uniform(-0.5, 0.5, 6)
        dq = velocity_ik(robot, q, twist)
        assert_close(J @ dq, twist, 1e-10, "Panda velocity IK reproduces the twist")
        # the minimum-norm solution: orthogonal to the null space
        null = np.linalg.svd(J)[2][6:].T
        assert np.abs(null.T @ dq).max() < 1e-10
        # null-space motion changes dq, not the twist
        for z in (rng.uniform(-1, 1, 7), "limits"):
            dq2 = velocity_ik(robot, q, twist, nullspace=z)
            assert_close(J @ dq2, twist, 1e-10, "Panda velocity IK with null-space motion")
            assert np.linalg.norm(dq2 - dq) > 1e-3
        # self-motion that lowers sum ((q - q_mid) / half_range)^2, the twist staying zero
        dq3 = velocity_ik(robot, q, np.zeros(6), nullspace="limits")
        assert limits_gradient(robot, q) @ dq3 > 0
        assert np.abs(J @ dq3).max() < 1e-10


def test_damped_least_squares_near_a_singularity():
    """UR5 with the wrist nearly straight (q5 ~ 0): the plain pseudo-inverse asks for huge joint
    speeds; the damped one stays bounded and still follows the achievable directions."""
    robot, _ = load_urdf_pair("ur5")
    q = np.array([0.3, -1.2, 1.4, -0.6, 1e-6, 0.5])
    J = robot.jacobian(q)
    twist = np.array([0.0, 0.0, 0.0, 0.1, 0.2, 0.0])
    plain = np.linalg.pinv(J) @ twist
    dq = velocity_ik(robot, q, twist)
    assert np.linalg.norm(plain) > 1e3
    assert np.linalg.norm(dq) < 20
    assert twist @ (J @ dq) > 0
    assert_close(damped_pinv(J, threshold=0.0), np.linalg.pinv(J), 1e-6, "undamped == pinv")


def test_resolved_rate_tracks_a_circle_and_a_line(rng):
    robot, model = load_urdf_pair("panda")
    q0 = np.array([0.1, -0.3, 0.2, -2.0, 0.1, 1.8, 0.6])
    T0 = robot.fk(q0)
    res = resolved_rate(
        robot, q0, circle_path(T0, 0.05, 2.0, normal=(0, 1, 1)), 2.0, nullspace="limits"
    )
    assert res.max_position_error < 2e-4 and res.max_orientation_error < 1e-4
    # independent check of the end point with Pinocchio
    data = model.createData()
    pin.framesForwardKinematics(model, data, res.q[-1])
    fid = model.getFrameId("panda_hand")
    assert np.linalg.norm(data.oMf[fid].translation - T0[:3, 3]) < 2e-3
    T1 = T0.copy()
    T1[:3, 3] += [0.05, -0.1, 0.05]
    T1[:3, :3] = pin.rpy.rpyToMatrix(0.2, -0.1, 0.3) @ T0[:3, :3]
    res = resolved_rate(robot, q0, line_path(T0, T1, 1.0), 2.0)
    assert np.abs(pose_error(robot.fk(res.q[-1]), T1)).max() < 1e-6


@pytest.mark.parametrize("name", ["ur5", "panda", "puma560"])
def test_position_ik_checked_with_pinocchio(name, rng):
    if name == "puma560":
        robot = mindyn.load(name)
        model, frame = pinocchio_model(robot), "tool"
    else:
        robot, model = load_urdf_pair(name)
        frame = "wrist_3_link" if name == "ur5" else "panda_hand"
    data = model.createData()
    fid = model.getFrameId(frame)
    lo, hi = robot.limits["lower"], robot.limits["upper"]
    for _ in range(10):
        qt, _, _ = random_state(robot, rng)
        target = robot.fk(qt)
        q, ok = mindyn.ik(robot, target)
        assert ok
        assert np.all(q >= lo) and np.all(q <= hi)
        pin.framesForwardKinematics(model, data, q)
        M = data.oMf[fid]
        err = np.concatenate(
            [target[:3, 3] - M.translation, pin.log3(target[:3, :3] @ M.rotation.T)]
        )
        assert np.abs(err).max() <= 1e-5


def test_position_ik_status_and_errors():
    robot = mindyn.load("puma560")
    far = pose_from_xyz_rpy([3.0, 0.0, 0.0], [0, 0, 0])
    r = ik_solve(robot, far, max_time=0.02)
    assert not r.success and r.status in ("not converged", "timeout") and r.error > 1.0
    q, ok = mindyn.ik(robot, far, max_time=0.02)
    assert not ok and q.shape == (6,)
    with pytest.raises(ValueError, match=r"T_target has shape \(3, 3\); expected \(4, 4\)"):
        mindyn.ik(robot, np.eye(3))
    bad = np.eye(4)
    bad[0, 0] = 2.0
    with pytest.raises(ValueError, match="not a rotation"):
        mindyn.ik(robot, bad)
    with pytest.raises(ValueError, match=r"q0 has shape \(5,\)"):
        mindyn.ik(robot, np.eye(4), q0=np.zeros(5))
    # same seed, same answer
    target = robot.fk(np.array([0.3, -0.4, 0.5, 0.2, 0.6, -0.3]))
    assert np.array_equal(ik_solve(robot, target, seed=7).q, ik_solve(robot, target, seed=7).q)


def test_pose_from_xyz_rpy_is_urdf_convention():
    T = pose_from_xyz_rpy([1, 2, 3], [0.1, -0.2, 0.3])
    assert_close(T[:3, :3], pin.rpy.rpyToMatrix(0.1, -0.2, 0.3), 1e-14, "rpy vs pin.rpy")
    assert_close(T[:3, 3], [1, 2, 3], 0.0, "xyz")


def test_ik_command(capsys):
    robot = mindyn.load("puma560")
    q = np.array([0.3, -0.4, 0.5, 0.2, 0.6, -0.3])
    T = robot.fk(q)
    rpy = pin.rpy.matrixToRpy(T[:3, :3])
    args = ["ik", "puma560", "--xyz", *map(str, T[:3, 3]), "--rpy", *map(str, rpy)]
    assert main(args + ["--format", "json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["success"] and out["status"] == "converged"
    assert np.abs(pose_error(robot.fk(out["q"]), T)).max() <= 1e-5
    assert main(args) == 0
    assert "converged" in capsys.readouterr().out
    assert main(["ik", "puma560", "--xyz", "3", "0", "0", "--timeout", "0.02"]) == 1
    assert "no joint solution" in capsys.readouterr().err
    assert main(["ik", "puma560", "--xyz", "0.5", "0", "0", "--q0", "1", "2"]) == 2
    err = capsys.readouterr().err
    assert err == "mindyn: error: --q0 needs 6 values, got 2\n"


def write_wide_urdf(tmp_path):
    """A revolute joint limited to +-4 pi, then a prismatic joint."""
    link = '<link name="{0}"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" '
    link += 'iyy="0.1" iyz="0" izz="0.1"/></inertial></link>'
    joint = '<joint name="{0}" type="{1}"><parent link="{2}"/><child link="{3}"/>'
    joint += '<axis xyz="0 0 1"/><limit lower="{4}" upper="{5}" effort="1" velocity="1"/></joint>'
    text = (
        '<robot name="wide"><link name="base"/>'
        + link.format("a")
        + link.format("b")
        + joint.format("j1", "revolute", "base", "a", -4 * np.pi, 4 * np.pi)
        + joint.format("j2", "prismatic", "a", "b", -1, 1)
        + "</robot>"
    )
    path = tmp_path / "wide.urdf"
    path.write_text(text)
    return path


def test_ik_command_refuses_degrees_given_as_radians(tmp_path, capsys, monkeypatch):
    # `--rpy 0 90 0` without --deg used to converge to a pose rotated by 90 rad
    base = ["ik", "puma560", "--xyz", "0.5", "0.1", "0.4"]
    for extra in (["--rpy", "0", "90", "0"], ["--rpy", "0", "-6.3", "0"], ["--q0", "0", "90"]):
        args = base + extra + (["0"] * 4 if extra[0] == "--q0" else [])
        assert main(args) == 2, extra
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and f"mindyn: error: {extra[0]} " in err, err
        assert "not an angle in radians" in err and "--deg" in err, err
    # the same pose in degrees: the pose reached is the one of rpy = (0, pi/2, 0) in radians
    assert main(base + ["--rpy", "0", "90", "0", "--deg", "--format", "json"]) == 0
    q = json.loads(capsys.readouterr().out)["q"]
    target = pin.SE3(pin.rpy.rpyToMatrix(0.0, np.pi / 2, 0.0), np.array([0.5, 0.1, 0.4]))
    assert np.abs(pose_error(mindyn.load("puma560").fk(q), target.homogeneous)).max() <= 1e-5
    # --deg converts the revolute joints of --q0 only; a prismatic joint's start stays in m
    seen = {}

    def spy(robot, T, q0, **kw):
        seen["q0"] = q0
        return ik_solve(robot, T, q0, **kw)

    monkeypatch.setattr(mindyn.inverse_kinematics, "ik_solve", spy)
    q0 = ["10", "20", "0.3", "40", "50", "60"]  # stanford: joint 3 is prismatic
    assert main(["ik", "stanford", "--xyz", "0.3", "0.2", "0.4", "--q0", *q0, "--deg"]) in (0, 1)
    capsys.readouterr()
    assert np.allclose(seen["q0"], np.radians([10, 20, 0, 40, 50, 60]) + [0, 0, 0.3, 0, 0, 0])
    # a revolute joint whose limits reach past 2 pi takes a start up to its limit in radians
    from mindyn.cli.number_options import check_radians

    wide = mindyn.load(write_wide_urdf(tmp_path))
    check_radians([7.0, 100.0], "--q0", "--deg", wide)  # 100 m on the prismatic joint
    with pytest.raises(mindyn.Error, match=r"--q0 13 \(value 1\): outside \[-12.57, 12.57\]"):
        check_radians([13.0, 0.0], "--q0", "--deg", wide)
    # excite's --start: the same check, naming its own option
    assert (
        main(["excite", "puma560", "--start", "90,0,0,0,0,0", "-o", str(tmp_path / "e.csv")]) == 2
    )
    err = capsys.readouterr().err
    assert "--start 90 (value 1)" in err and "give --deg" in err, err


def test_pose_error_is_position_difference_and_scipy_rotation_vector():
    """pose_error (the C++ map of the IK solver) against SciPy's rotation vector of R_d R^T,
    including angles within 1e-9 of pi where the axis comes from the symmetric part."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(5)
    for angle in [1e-9, 0.3, 2.0, np.pi - 1e-3, np.pi - 1e-9]:
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        T, Td = np.eye(4), np.eye(4)
        T[:3, :3] = Rotation.from_rotvec(rng.normal(size=3)).as_matrix()
        T[:3, 3] = rng.normal(size=3)
        Td[:3, :3] = Rotation.from_rotvec(angle * axis).as_matrix() @ T[:3, :3]
        Td[:3, 3] = rng.normal(size=3)
        e = pose_error(T, Td)
        assert np.array_equal(e[:3], Td[:3, 3] - T[:3, 3])
        # rounding of the rotation matrices (1e-16) shows as 1e-8 in the axis within 1e-9 of pi
        tol = 1e-7 if np.pi - angle < 1e-6 else 1e-12
        assert np.abs(e[3:] - angle * axis).max() <= tol, angle


def test_ik_command_aligns_long_joint_names(tmp_path, capsys):
    """Joint names longer than 16 characters (Panda's 'panda_finger_joint1') shifted their
    values out of the column; every value now starts in the same column and reads back as the
    JSON's."""
    text = write_wide_urdf(tmp_path).read_text().replace('"j1"', '"a_rather_long_joint_name"')
    path = tmp_path / "long.urdf"
    path.write_text(text)
    args = ["ik", str(path), "--xyz", "0", "0", "0.5"]
    assert main([*args, "--format", "json"]) in (0, 1)
    q = json.loads(capsys.readouterr().out)["q"]
    main(args)
    out = capsys.readouterr().out.splitlines()
    lines = [ln for ln in out if ln.startswith("  ") and not ln.startswith("  frame: ")]
    assert [ln.split()[0] for ln in lines] == ["a_rather_long_joint_name", "j2"]
    ends = {ln.index(" rad") if " rad" in ln else ln.index(" m") for ln in lines}
    assert len(ends) == 1, lines
    assert [float(ln.split()[1]) for ln in lines] == pytest.approx(q, abs=1e-6)


def test_ik_reports_position_and_orientation_errors_in_their_units(capsys):
    """The command printed 'best pose error 2.24' for an unreachable target: the norm of a
    twist of metres and radians, no unit. The result, the text and the JSON give the position
    error [m] (the distance of the tool frame's origin from the target's) and the orientation
    error [rad] (the angle of R_target^T R, SciPy's rotation vector), and say what the pose
    error combines."""
    from scipy.spatial.transform import Rotation

    robot = mindyn.load("puma560")
    target = np.eye(4)
    target[:3, 3] = [3.0, 0.0, 0.0]  # beyond the arm's reach
    r = ik_solve(robot, target, max_time=0.02)
    T = robot.fk(r.q)
    dist = np.linalg.norm(T[:3, 3] - target[:3, 3])
    angle = Rotation.from_matrix(target[:3, :3].T @ T[:3, :3]).magnitude()
    assert not r.success and dist > 1.0
    assert r.position_error == pytest.approx(dist, rel=1e-12)
    assert r.orientation_error == pytest.approx(angle, rel=1e-9, abs=1e-12)
    argv = ["ik", "puma560", "--xyz", "3", "0", "0", "--timeout", "0.02"]
    assert main([*argv, "--format", "json"]) == 1
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    T = robot.fk(doc["q"])
    dist = np.linalg.norm(T[:3, 3] - target[:3, 3])
    angle = Rotation.from_matrix(T[:3, :3]).magnitude()
    assert doc["position_error_m"] == pytest.approx(dist, rel=1e-12)
    assert doc["orientation_error_rad"] == pytest.approx(angle, rel=1e-9, abs=1e-12)
    assert "metres and radians" in doc["pose_error_definition"]
    err = captured.err
    assert f"position error {doc['position_error_m']:.3g} m, " in err, err
    assert f"orientation error {doc['orientation_error_rad']:.3g} rad (" in err, err
    assert "best pose error" not in err


@pytest.mark.parametrize("x", [1e308, 1e200, -1e160])
def test_a_target_so_far_that_the_errors_overflow_is_refused(x, capsys):
    """A target position whose distance from any tool position overflows the double range
    (|p| above about 1.3e154, squared in the norms): the errors were inf, with numpy's overflow
    warning on a second line and exit status 1. It is an ArgumentError naming the position, as
    every function whose result overflows for finite inputs; a far target whose errors stay
    finite is still answered (not converged)."""
    import warnings

    robot = mindyn.load("puma560")
    T = pose_from_xyz_rpy([x, 1e9, -1e20], [0.0, 0.0, 0.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no numpy warning before the error
        with pytest.raises(mindyn.ArgumentError, match=r"ik_solve: the result overflows") as e:
            ik_solve(robot, T)
    assert f"T_target's position {x:.3g} (entry 1)" in str(e.value), e.value
    assert "q0" not in str(e.value)  # not given: the default start is not the user's input
    assert main(["ik", "puma560", "--xyz", f"{x:g}", "1e9", "-1e20"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mindyn: error: ik_solve: the result"), err
    far = ik_solve(robot, pose_from_xyz_rpy([1e100, 0.0, 0.0], [0.0, 0.0, 0.0]))
    assert far.status == "not converged" and far.position_error == pytest.approx(1e100, rel=1e-9)


def test_ik_states_the_tool_offsets_rotation(capsys):
    """The Panda to panda_hand: the tool offset from panda_link7 turns by -45 deg about z, which
    the frame line left out (it gave the translation alone). The xyz and rpy it prints, taken as
    --xyz / --rpy take them, give Pinocchio's placement of panda_hand in panda_link7."""
    import re

    from conftest import URDFS

    args = ["ik", str(URDFS["panda"]), "--tip", "panda_hand", "--xyz", "0.4", "0", "0.4"]
    main([*args, "--rpy", "3.14159", "0", "0", "--format", "json"])
    frame = json.loads(capsys.readouterr().out)["frame"]
    m = re.search(r"xyz (\S+) (\S+) (\S+) m, rpy (\S+) (\S+) (\S+) rad", frame)
    assert m, frame
    values = [float(v) for v in m.groups()]
    model = pin.buildModelFromUrdf(str(URDFS["panda"]))
    data = model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model))
    link7 = data.oMf[model.getFrameId("panda_link7")]
    hand = data.oMf[model.getFrameId("panda_hand")]
    offset = (link7.inverse() * hand).homogeneous
    np.testing.assert_allclose(pose_from_xyz_rpy(values[:3], values[3:]), offset, atol=1e-5)
    assert abs(values[5] + np.pi / 4) < 1e-5


def test_position_only_ik_of_a_three_joint_arm_checked_with_pinocchio(rng, capsys):
    """orientation_weight=0 was accepted but still judged the answer by the whole pose: a
    three-joint arm never converged on a position reached in another orientation (and the
    command had no way to ask for the position alone). Position only, the tool origin lands
    on the target (Pinocchio's forward kinematics) while the orientation stays free."""
    robot = mindyn.load("puma560_3")
    model = pinocchio_model(robot)
    data = model.createData()
    fid = model.getFrameId("tool")
    for _ in range(5):
        qt = rng.uniform(-1.5, 1.5, robot.n)
        target = robot.fk(qt)
        target[:3, :3] = np.eye(3)  # an orientation the arm does not reach there
        assert not ik_solve(robot, target, max_time=0.05).success
        r = ik_solve(robot, target, orientation_weight=0.0)
        assert r.success and r.position_only and r.error == r.position_error
        pin.framesForwardKinematics(model, data, r.q)
        assert np.linalg.norm(data.oMf[fid].translation - target[:3, 3]) <= 1e-9
        assert r.orientation_error > 1e-3
    xyz = [str(v) for v in target[:3, 3]]
    assert main(["ik", "puma560_3", "--xyz", *xyz, "--position-only", "--format", "json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["success"] and doc["position_only"] and doc["position_error_m"] <= 1e-9
    assert main(["ik", "puma560_3", "--xyz", *xyz, "--timeout", "0.05"]) == 1
    assert "--position-only leaves the orientation free" in capsys.readouterr().err
    assert main(["ik", "puma560_3", "--xyz", *xyz, "--position-only", "--rpy", "0", "0", "0"]) == 2
    assert capsys.readouterr().err.count("\n") == 1
