"""The unit and sign of a log's torques.

Torques logged in mN m (x1000) or negated were identified without a word (the inertias 1000
times too large, or negative): a joint whose logged torques and the description's inverse
dynamics on the logged motion correlate (|r| >= 0.9) with a ratio outside 0.1 to 10 is refused,
naming it (a ratio above 10 only where the torques also exceed twice the effort limit, or above
100 without one); without a joint to judge, torques beyond 20 times the effort limits on most
joints are. Logs simulated from a robot whose truth differs from its description (masses x2 or
x0.5, friction dominating, 5 % torque noise, offsets, currents through drive gains) are taken.
Every expectation is computed here from the log the test makes.
"""

from __future__ import annotations

import re

import mindyn
import numpy as np
import pytest
from conftest import cli_run, one_line_error
from mindyn.identification import identify, read_csv, run
from mindyn.identification.currents import attach_currents
from mindyn.identification.data import DataError, check_units, write_csv
from mindyn.identification.excitation import random_trajectory
from mindyn.identification.joint_data import JointData

RATE = 250.0


def ratio(message: str) -> float:
    """The ratio a refusal states."""
    found = re.search(r" are (\S+) times the description's", message)
    assert found, message
    return float(found.group(1))


@pytest.fixture(scope="module")
def zcr():
    """zcr07s (masses, friction, effort limits) on a random trajectory at 250 Hz."""
    robot = mindyn.load("zcr07s")
    traj = random_trajectory(robot, seed=2)
    t = np.arange(0.0, traj.duration, 1.0 / RATE)
    q, dq, ddq = traj.evaluate(t)
    return robot, t, q, dq, ddq


def truth(robot, kind: str) -> np.ndarray:
    """The simulated robot's parameters (inertial, Ia, Fv, Fc per joint): the description's, or
    another robot's that the description only approximates."""
    p = robot.parameters(rotor=True, friction=True).copy()
    names = robot.parameter_names(rotor=True, friction=True)
    inertial = np.array([nm[:2] not in ("Ia", "Fv", "Fc") for nm in names])
    if kind == "masses x2":  # every link twice as heavy (inertias and first moments alike)
        p[inertial] *= 2.0
    elif kind == "masses x0.5":
        p[inertial] *= 0.5
    elif kind == "friction x8 on the wrist":  # joints 4 to 6 dominated by friction
        for j in (4, 5, 6):
            for nm in ("Fv", "Fc"):
                p[names.index(f"{nm}{j}")] *= 8.0
    return p


def torques(zcr, kind: str = "description", noise: float = 0.05, seed: int = 0) -> np.ndarray:
    """The simulated robot's torques on the trajectory, with white noise of ``noise`` times
    each joint's torque RMS."""
    robot, t, q, dq, ddq = zcr
    tau = robot.inverse_dynamics(q, dq, ddq, truth(robot, kind))
    rms = np.sqrt((tau**2).mean(axis=0))
    return tau + noise * rms * np.random.default_rng(seed).standard_normal(tau.shape)


# -- 1. refused --------------------------------------------------------------------------------
def test_torques_in_mNm_or_negated_are_refused_by_identify(zcr, tmp_path):
    robot, t, q, dq, _ = zcr
    tau = torques(zcr)
    good = write_csv(tmp_path / "good.csv", t, q, tau, dq=dq)
    rc, out, err = cli_run(["identify", "zcr07s", good, "--rotor", "--friction"])
    assert rc == 0, err
    said = {}
    for name, factor, cause in (
        ("mNm", 1e3, "torques in mN m (1000)"),
        ("neg", -1.0, "the torque column negated, a drive whose sign convention is opposite"),
    ):
        path = write_csv(tmp_path / f"{name}.csv", t, q, factor * tau, dq=dq)
        rc, _, err = cli_run(["identify", "zcr07s", path, "--rotor", "--friction"])
        line = one_line_error(
            rc,
            err,
            f"{path}: the torques of joint 1 ('{robot.joint_names[0]}') are ",
            "joint(s) 2, 3, 4, 5, 6 alike",
            cause,
            "--torque-unit permille or current with --drive-gain",
        )
        said[name] = ratio(line)
        corr = float(re.search(r"correlation (-?[\d.]+)", line).group(1))
        assert abs(corr) >= 0.9 and np.sign(corr) == np.sign(factor), line
    # the simulated robot is the description's: the ratios are the factors, to the noise and the
    # check's low-pass; one log is the other times -1000 exactly (to the 4 digits stated)
    assert said["neg"] == pytest.approx(-1.0, abs=0.05)
    assert said["mNm"] / said["neg"] == pytest.approx(-1e3, rel=1e-3)
    with pytest.raises(DataError, match="are -?[0-9.]+ times the description's"):
        read_csv(tmp_path / "neg.csv", robot=robot)


def test_torques_stated_in_newton_metres_are_taken_as_they_are(zcr, tmp_path):
    """The check judges the torques against the description, which can be far from the robot
    (a description ten times too heavy gives the ratio of mN m's inverse): torques whose unit
    the command line, the header or the column map states as N m are taken as they are, with
    the estimates of the robot that made them."""
    robot, t, q, dq, _ = zcr
    light = 0.05 * torques(zcr, noise=0.0)  # a robot 20 times lighter than the description
    path = write_csv(tmp_path / "light.csv", t, q, light, dq=dq)
    with pytest.raises(DataError, match="stated as N m"):
        read_csv(path, robot=robot)
    said = write_csv(tmp_path / "said.csv", t, q, light, dq=dq, torque_unit="Nm")
    for d in (read_csv(path, robot=robot, torque_unit="Nm"), read_csv(said, robot=robot)):
        rows = np.searchsorted(t, d.t - 1e-9)  # the samples kept (derivative edges dropped)
        np.testing.assert_allclose(d.tau, light[rows], rtol=1e-9, atol=1e-9)  # as written
    rc, out, err = cli_run(["identify", "zcr07s", path, "--torque-unit", "Nm"])
    assert rc == 0, err


@pytest.mark.parametrize("joint", [2, 4])
def test_a_single_negated_joint_is_refused_naming_it(zcr, tmp_path, joint):
    robot, t, q, dq, _ = zcr
    tau = torques(zcr)
    tau[:, joint - 1] *= -1.0
    path = write_csv(tmp_path / "one.csv", t, q, tau, dq=dq)
    with pytest.raises(DataError) as e:
        read_csv(path, robot=robot)
    msg = str(e.value)
    assert msg.startswith(
        f"{path}: the torques of joint {joint} ('{robot.joint_names[joint - 1]}') are -"
    ), msg
    assert "alike" not in msg and "\n" not in msg
    assert ratio(msg) == pytest.approx(-1.0, abs=0.05)


def test_currents_through_drive_gains_of_the_wrong_sign_are_refused(zcr, tmp_path):
    """Currents logged beside the positions (i1..in) and in a file of their own: taken with
    the right gains (one motor reversed, its gain negative), refused with that gain's sign
    lost."""
    robot, t, q, dq, _ = zcr
    tau = torques(zcr)
    gain = np.array([10.0, -8.0, 6.0, 4.0, 3.0, 2.0])
    currents = tau / gain
    path = write_csv(tmp_path / "i.csv", t, q, currents, dq=dq, torque_unit="current")
    d = read_csv(path, robot=robot, drive_gain=gain)
    k = np.searchsorted(t, d.t[0])  # the samples kept between the derivatives' edges
    np.testing.assert_allclose(d.tau, tau[k : k + d.m], rtol=1e-9, atol=1e-9)
    rc, _, err = cli_run(["identify", "zcr07s", path, "--drive-gain", ",".join(map(str, gain))])
    assert rc == 0, err
    lost = np.abs(gain)
    rc, _, err = cli_run(["identify", "zcr07s", path, "--drive-gain", ",".join(map(str, lost))])
    line = one_line_error(
        rc, err, f"{path}: the torques of joint 2 ('{robot.joint_names[1]}') are -", "drive"
    )
    assert ratio(line) == pytest.approx(-1.0, abs=0.05)
    # the currents in a file of their own, joined on the time stamps
    motion = read_csv(write_csv(tmp_path / "q.csv", t, q, None, dq=dq), robot, require_torque=False)
    cur = tmp_path / "currents.csv"
    np.savetxt(
        cur,
        np.column_stack([t, currents]),
        delimiter=",",
        header="t," + ",".join(f"i{j}" for j in range(1, 7)),
        comments="",
        fmt="%.17g",
    )
    attach_currents(motion, cur, robot, drive_gain=gain)
    with pytest.raises(DataError, match=re.escape(f"{cur} (currents x drive gains): the torques")):
        attach_currents(motion, cur, robot, drive_gain=lost)


# -- 2. taken ------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "kind, noise, offset",
    [
        ("description", 0.05, False),
        ("description", 0.05, True),
        ("masses x2", 0.05, False),
        ("masses x0.5", 0.05, False),
        ("friction x8 on the wrist", 0.05, False),
        ("masses x2", 0.0, True),
    ],
)
def test_logs_of_a_robot_the_description_approximates_are_taken(zcr, tmp_path, kind, noise, offset):
    """The log is read (velocities logged, and derived from the positions) and taken by
    identification from Python; the same log in mN m or negated is refused, so the check
    judged it."""
    robot, t, q, dq, ddq = zcr
    tau = torques(zcr, kind, noise)
    if offset:  # a constant offset per joint, up to half the joint's torque RMS
        tau = tau + 0.5 * np.sqrt((tau**2).mean(axis=0)) * np.linspace(1.0, -1.0, robot.n)
    for velocities in (dq, None):
        path = write_csv(tmp_path / "log.csv", t, q, tau, dq=velocities)
        assert read_csv(path, robot=robot).units_checked
    check_units(JointData(t, q, dq, ddq, tau), robot, "data")
    for factor in (1e3, -1.0):
        with pytest.raises(DataError, match="^data: the torques of joint"):
            check_units(JointData(t, q, dq, ddq, factor * tau), robot, "data")


# -- 3. logs built in Python ---------------------------------------------------------------------
def test_joint_data_built_in_python_is_checked_once(zcr):
    robot, t, q, dq, ddq = zcr
    tau = torques(zcr)
    good = JointData(t, q, dq, ddq, tau, "good")
    bad = JointData(t, q, dq, ddq, 1e3 * tau)
    with pytest.raises(DataError) as e:
        identify(robot, [good, bad], rotor=True, friction=True)
    msg = str(e.value)
    assert msg.startswith("data[1]: the torques of joint 1") and "mN m (1000)" in msg, msg
    assert "JointData.tau is in N m" in msg and "units_checked=True" in msg
    assert good.units_checked and not bad.units_checked
    with pytest.raises(DataError, match=r"^logs: the torques of joint 1 .* -?0\.9\d* times"):
        run(robot, JointData(t, q, dq, ddq, -tau))
    res = identify(robot, good, rotor=True, friction=True)
    assert res.full.size and np.isfinite(res.full).all()
    bad.units_checked = True  # stated by its maker: taken as it is
    identify(robot, bad, rotor=True, friction=True)


def test_a_description_without_masses_or_effort_limits(zcr):
    """Without masses nothing is compared but the effort limits: torques beyond 20 times them
    are refused, a negated log cannot be told; without effort limits a ratio above 10 needs to
    exceed 100."""
    robot, t, q, dq, ddq = zcr
    tau = torques(zcr)
    massless = mindyn.load("zcr07s")
    massless.params = np.zeros(10 * robot.n)
    effort = robot.limits["effort"]
    peak = np.abs(tau).max(axis=0)
    assert (peak < effort).all()
    check_units(JointData(t, q, dq, ddq, tau), massless, "data")
    check_units(JointData(t, q, dq, ddq, -tau), massless, "data")
    over = int(np.sum(1e3 * peak > 20 * effort))
    assert 2 * over > robot.n  # the case: most joints beyond 20 times their limit
    with pytest.raises(DataError) as e:
        check_units(JointData(t, q, dq, ddq, 1e3 * tau), massless, "data")
    j = int(np.argmax(1e3 * peak > 20 * effort))
    assert str(e.value).startswith(
        f"data: the torques of {over} of the {robot.n} joints with an effort limit peak beyond "
        f"20 times it (joint {j + 1} ('{robot.joint_names[j]}'): {1e3 * peak[j]:.4g} for a "
        f"limit of {effort[j]:.4g})"
    ), str(e.value)
    # puma560's table gives masses and no effort limits
    puma = mindyn.load("puma560")
    assert not np.isfinite(puma.limits["effort"]).any()
    traj = random_trajectory(puma, seed=3)
    q, dq, ddq = traj.evaluate(t[t < traj.duration])
    tau = puma.inverse_dynamics(q, dq, ddq, puma.parameters(rotor=True, friction=True))
    tt = t[: q.shape[0]]
    check_units(JointData(tt, q, dq, ddq, 8.0 * tau), puma, "data")  # a heavier robot
    with pytest.raises(DataError, match="times the description's"):
        check_units(JointData(tt, q, dq, ddq, 1e3 * tau), puma, "data")


def test_bag_efforts_negated_are_refused_and_currents_taken(tmp_path):
    pytest.importorskip("rosbags")
    from test_rosbag import joint_state, write_bag

    robot = mindyn.load("zcr07s")
    traj = random_trajectory(robot, seed=2)
    t = np.arange(0.0, traj.duration, 1.0 / RATE)
    q, dq, ddq = traj.evaluate(t)
    tau = robot.inverse_dynamics(q, dq, ddq, robot.parameters(rotor=True, friction=True))
    names = list(robot.joint_names)
    gain = 5.0
    for name, effort, argv in (
        ("neg", -tau, []),
        ("amps", tau / gain, ["--torque-unit", "current", "--drive-gain", str(gain)]),
    ):
        bag = write_bag(
            tmp_path / name,
            [joint_state(t[i], names, q[i], dq[i], effort[i]) for i in range(t.size)],
        )
        rc, _, err = cli_run(["identify", "zcr07s", bag, *argv])
        if name == "amps":
            assert rc == 0, err
            continue
        one_line_error(rc, err, f"{bag}: the torques of joint 1", "record the efforts in N m")
