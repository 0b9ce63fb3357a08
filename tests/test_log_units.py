"""The units of a log's time stamps, and the unit checks of logs built in Python.

Time stamps in milliseconds without velocity columns were identified without a word (0.45 %
error, the inertias wrong by 1e6): a log whose median sample interval is 0.5 s or more is
refused wherever logs are read (CSV, ROS bag, the trajectory CSV of simulate) unless its unit
is stated (a column map's t[s], a trajectory's header). A JointData built in Python got none
of the unit checks a file gets; it gets them once, when it first reaches identification, named
by its argument. Every expectation is computed here from the log the test makes.
"""

from __future__ import annotations

import json

import mindyn
import numpy as np
import pytest
from conftest import cli_run, one_line_error
from mindyn.base import base_parameters
from mindyn.identification import data as data_module
from mindyn.identification import identify, load_logs, read_csv, run
from mindyn.identification.data import DataError, write_csv
from mindyn.identification.excitation import random_trajectory
from mindyn.identification.joint_data import JointData


def exact_log(robot, rate: float = 250.0):
    """A random trajectory of ``robot`` sampled at ``rate`` and its torques (no noise): the
    base parameters are the known answer."""
    traj = random_trajectory(robot, seed=2)
    t = np.arange(0.0, traj.duration, 1.0 / rate)
    q, dq, ddq = traj.evaluate(t)
    return t, q, dq, ddq, robot.inverse_dynamics(q, dq, ddq)


@pytest.fixture(scope="module")
def zcr(tmp_path_factory):
    """A simulated zcr07s log, its time stamps in ms and no velocity columns (the report)."""
    d = tmp_path_factory.mktemp("units")
    log = d / "z.csv"
    rc, _, err = cli_run(["simulate", "zcr07s", "--mode", "inverse", "--duration", "6", "-o", log])
    assert rc == 0, err
    header = log.read_text().splitlines()[0].split(",")
    values = np.loadtxt(log, delimiter=",", skiprows=1)
    keep = [k for k, h in enumerate(header) if not h.startswith("dq")]

    def scaled(name, factor):
        v = values[:, keep].copy()
        v[:, 0] *= factor
        path = d / name
        h = ",".join(header[k] for k in keep)
        np.savetxt(path, v, delimiter=",", header=h, comments="", fmt="%.17g")
        return path, float(np.median(np.diff(v[:, 0])))

    return {
        "t": values[:, 0],
        "s": scaled("s.csv", 1.0),
        "ms": scaled("ms.csv", 1e3),
        "us": scaled("us.csv", 1e6),
    }


def base_values(path) -> np.ndarray:
    return np.array(json.loads(path.read_text())["base_values"], dtype=float)


# -- 1. time stamps ------------------------------------------------------------------------------
@pytest.mark.parametrize("unit, factor", [("ms", 1e3), ("us", 1e6)])
def test_time_stamps_in_ms_or_us_without_velocities_are_refused(zcr, unit, factor):
    path, step = zcr[unit]
    rate = 1.0 / (step / factor)
    assert step >= 0.5 and round(rate) == 250  # the case: a 250 Hz log
    rc, _, err = cli_run(["identify", "zcr07s", path])
    said = {"ms": "milliseconds", "us": "microseconds"}[unit]
    one_line_error(
        rc,
        err,
        f"{path}: the median interval between its time stamps is {step:.4g} s",
        f"seem to be in {said} (a log of {rate:.4g} Hz)",
        "--columns with t[ms]",
        "t[s] for a log this slow",
    )
    with pytest.raises(DataError, match=f"{step:.4g} s.*columns= with t"):
        read_csv(path, robot=mindyn.load("zcr07s"))


def test_the_unit_stated_in_the_column_map_is_taken(zcr, tmp_path):
    """t[ms] identifies what the log in s identifies; t[s] (a log this slow, as stated) is
    taken as given."""
    path, _ = zcr["ms"]
    rows = {}
    for name, argv in (
        ("s", [zcr["s"][0]]),
        ("ms", [path, "--columns", "t[ms]=t,q=q{j},tau=tau{j}"]),
        ("slow", [path, "--columns", "t[s]=t,q=q{j},tau=tau{j}"]),
    ):
        out = tmp_path / f"{name}.json"
        rc, _, err = cli_run(["identify", "zcr07s", *argv, "--json", out])
        assert rc == 0, err
        rows[name] = base_values(out)
    # the log in ms read through t[ms]: the log in s (velocities derived alike)
    np.testing.assert_allclose(rows["ms"], rows["s"], rtol=1e-6, atol=1e-9)
    # read as s, the inertias are 1e6 too large: the stated unit is taken, not refused
    assert np.abs(rows["slow"]).max() > 1e3 * np.abs(rows["s"]).max()
    robot = mindyn.load("zcr07s")
    d = read_csv(path, robot=robot, columns={"t[s]": "t", "q": "q{j}", "tau": "tau{j}"})
    assert d.units_checked
    np.testing.assert_allclose(np.diff(d.t).mean(), 1e3 * np.diff(zcr["t"]).mean(), rtol=1e-9)


def test_a_bag_stamped_in_milliseconds_is_refused(tmp_path):
    pytest.importorskip("rosbags")
    from test_rosbag import joint_state, write_bag

    robot = mindyn.load("planar2")
    t, q, dq, _, tau = exact_log(robot)
    names = list(robot.joint_names)
    for name, scale in (("ms", 1e3), ("s", 1.0)):
        bag = write_bag(
            tmp_path / name,
            [joint_state(t[i] * scale, names, q[i], None, tau[i]) for i in range(t.size)],
        )
        rc, _, err = cli_run(["identify", "planar2", bag])
        if scale == 1.0:
            assert rc == 0, err
            continue
        step = np.median(np.diff(t * scale))
        one_line_error(
            rc,
            err,
            f"{bag}, /joint_states: the median interval between its time stamps is {step:.4g} s",
            "milliseconds (a log of 250 Hz)",
            "record the stamps in s",
        )


def test_a_trajectory_csv_in_milliseconds_is_refused_unless_its_header_says(tmp_path):
    """simulate --trajectory followed a trajectory in ms 1000 times too slowly; it is refused,
    and a header t[ms] gives the simulation of the trajectory in s (t[s]: a slow trajectory as
    stated)."""
    from mindyn.control.simulation import SumOfSines

    robot = mindyn.load("planar2")
    t = np.arange(0.0, 2.0, 0.004)
    q, dq, _ = SumOfSines(robot, period=2.0).evaluate(t)
    out = {}
    for name, header, scale in (
        ("s", "", 1.0),
        ("ms", "", 1e3),
        ("ms_header", "t[ms],q1,q2", 1e3),
        ("slow", "t[s],q1,q2", 1e3),
    ):
        traj = tmp_path / f"{name}.csv"
        np.savetxt(
            traj,
            np.column_stack([t * scale, q]),
            delimiter=",",
            header=header,
            comments="",
            fmt="%.17g",
        )
        argv = ["simulate", "planar2", "--mode", "inverse", "--trajectory", traj]
        rc, _, err = cli_run([*argv, "--duration", "2", "-o", tmp_path / f"{name}.out.csv"])
        if name == "ms":
            step = np.median(np.diff(t * scale))
            one_line_error(
                rc,
                err,
                f"{traj}: the median interval between its time stamps is {step:.4g} s",
                "milliseconds",
                "header's first name: t[ms]",
            )
            continue
        assert rc == 0, err
        out[name] = np.loadtxt(tmp_path / f"{name}.out.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(out["ms_header"], out["s"], rtol=1e-9, atol=1e-9)
    # read as s, 2 s of the slow trajectory move the joints far less than the one in s
    moved = {k: np.ptp(v[:, 1:3], axis=0).max() for k, v in out.items()}
    assert moved["slow"] < 0.01 * moved["s"]


# -- 2. JointData built in Python ------------------------------------------------------------------
@pytest.fixture(scope="module")
def planar():
    robot = mindyn.load("planar2")
    return robot, exact_log(robot)


def _wrong(planar, kind):
    robot, (t, q, dq, ddq, tau) = planar
    deg = 180 / np.pi
    return {
        "ms": (JointData(t * 1e3, q, dq, ddq, tau), "seem to be in milliseconds"),
        "deg": (JointData(t, q * deg, dq * deg, ddq * deg, tau), "seem to be in degrees"),
        "degps": (JointData(t, q, dq * deg, ddq, tau), "velocity dq1 is 57.3 times"),
    }[kind]


@pytest.mark.parametrize("kind", ["ms", "deg", "degps"])
def test_joint_data_built_in_python_is_checked_by_identify(planar, kind):
    robot, (t, q, dq, ddq, tau) = planar
    good = JointData(t, q, dq, ddq, tau, "good")
    bad, said = _wrong(planar, kind)
    with pytest.raises(DataError) as e:
        identify(robot, [good, bad], rsd_threshold=None)
    msg = str(e.value)
    assert msg.startswith("data[1]: ") and said in msg and "\n" not in msg, msg
    with pytest.raises(DataError, match=f"^logs\\[0\\]: .*{said}"):
        run(robot, [bad])
    with pytest.raises(DataError, match=f"^logs: .*{said}"):
        run(robot, bad)
    named = JointData(bad.t, bad.q, bad.dq, bad.ddq, bad.tau, "arm.csv")
    with pytest.raises(DataError, match=f"^data \\('arm.csv'\\): .*{said}"):
        identify(robot, named)
    # the known answer from the log in the right units
    res = identify(robot, good, rsd_threshold=None)
    truth = base_parameters(robot).values(robot.params)
    np.testing.assert_allclose(res.full[: truth.size], truth, rtol=1e-7, atol=1e-9)
    assert good.units_checked and not bad.units_checked


def test_the_other_entry_points_check_too(planar):
    from mindyn.identification import (
        dynamic_system,
        energy_system,
        integral_system,
        select_friction_model,
        validate,
    )
    from mindyn.identification.prediction import predict

    robot, (t, q, dq, ddq, tau) = planar
    good = JointData(t, q, dq, ddq, tau, "good")
    report = run(robot, good)
    res = identify(robot, good, rsd_threshold=None)
    for call, name in (
        (lambda bad: validate(res, [bad]), "data[0]"),
        (lambda bad: predict(report.to_dict(), bad, robot=robot), "data"),
        (lambda bad: select_friction_model(robot, [good, bad]), "logs[1]"),
        (lambda bad: dynamic_system(res.base, bad), "data"),
        (lambda bad: energy_system(res.base, bad), "data"),
        (lambda bad: integral_system(res.base, bad), "data"),
    ):
        for kind in ("ms", "deg", "degps"):
            bad, said = _wrong(planar, kind)
            with pytest.raises(DataError) as e:
                call(bad)
            assert str(e.value).startswith(f"{name}: ") and said in str(e.value), str(e.value)


def test_a_slow_log_stated_as_checked_is_taken(planar):
    robot, (t, q, dq, ddq, tau) = planar
    # the trajectory 1000 times slower, its stamps in s: a genuine 0.25 Hz log
    slow = JointData(
        t * 1e3, q, dq * 1e-3, ddq * 1e-6, robot.inverse_dynamics(q, dq * 1e-3, ddq * 1e-6)
    )
    with pytest.raises(DataError, match="milliseconds"):
        identify(robot, slow, rsd_threshold=None)
    slow.units_checked = True
    identify(robot, slow, rsd_threshold=None)  # taken as stated


def test_the_checks_run_once_per_log(planar, tmp_path, monkeypatch):
    """A log built in Python is checked once however many fits a run makes (the friction
    choice fits several models); logs read from files are checked by the reader alone."""
    robot, (t, q, dq, ddq, tau) = planar
    calls: list[str] = []
    real = data_module.check_units
    times = data_module.check_time_units

    def counted(d, r, label):
        calls.append(label)
        return real(d, r, label)

    def counted_time(*a, **k):
        calls.append("time")
        return times(*a, **k)

    monkeypatch.setattr(data_module, "check_units", counted)
    monkeypatch.setattr(data_module, "check_time_units", counted_time)
    logs = [JointData(t, q, dq, ddq, tau, "a"), JointData(t, q, dq, ddq, tau, "b")]
    run(robot, logs, friction_model="auto")
    assert calls == ["logs[0]", "time", "logs[1]", "time"], calls
    calls.clear()
    path = write_csv(tmp_path / "p.csv", t, q, tau, dq=dq)
    other = write_csv(tmp_path / "v.csv", t, q, tau * 1.001, dq=dq)  # not the fit log
    run(robot, load_logs([path], robot, validate=[other]), friction_model="auto")
    assert calls == ["time", "time"], calls  # the fit and the validation file, read once each
