"""Error measures of an identification, several logs fitted together, and torques from motor
currents. References: numpy on the test's own arrays, the regression system formed in the test,
and simulated logs with known parameters."""

from __future__ import annotations

import json
import sys
from dataclasses import replace
from pathlib import Path

import mindyn
import numpy as np
import pytest
import yaml
from mindyn import cli
from mindyn.control import SensorNoise, simulate_inverse
from mindyn.identification import (
    DataError,
    JointData,
    dynamic_system,
    energy_system,
    error_measures,
    identify,
    integral_system,
    read_csv,
    true_base_values,
    validate,
    write_csv,
)
from mindyn.identification.currents import attach_currents
from mindyn.identification.excitation import random_trajectory

sys.path.insert(0, str(Path(__file__).parent))
from random_arm import random_arm_yaml  # noqa: E402


def as_data(log, source="sim") -> JointData:
    """A log with its exact accelerations (the regression system is then the test's own)."""
    return JointData(log.t, log.q, log.dq, log.ddq_true, log.tau, source, {})


def kept(d: JointData, x: np.ndarray) -> np.ndarray:
    """The samples of a logged array ``x`` that the reader kept in ``d`` (it drops those at
    each end where a derived derivative is the filter's start-up)."""
    k = d.processing["derivative_edges"]["samples"]
    return x[k : len(x) - k]


def stacked(*logs: JointData) -> JointData:
    """One log holding the samples of several (time made increasing; no derivatives taken),
    where each starts recorded (``starts``: the residuals' correlation is measured within
    each)."""
    ts, t0 = [], 0.0
    for d in logs:
        ts.append(d.t - d.t[0] + t0)
        t0 = ts[-1][-1] + 1.0
    return JointData(
        np.concatenate(ts),
        *(np.vstack([getattr(d, k) for d in logs]) for k in ("q", "dq", "ddq", "tau")),
        source="stacked",
        starts=tuple(np.cumsum([0] + [d.m for d in logs[:-1]]).tolist()),
    )


@pytest.fixture(scope="module")
def two_logs():
    robot = mindyn.load("zcr07s")
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    sd = 0.01 * robot.limits["effort"]
    logs = []
    for seed in (11, 12):
        log = simulate_inverse(
            robot,
            random_trajectory(robot, seed=seed),
            rate=100.0,
            rotor=True,
            friction=True,
            noise=SensorNoise(torque=sd),
            seed=seed,
        )
        logs.append((log, as_data(log, f"log{seed}")))
    return robot, base, logs


# ---------------------------------------------------------------------------------------------
# Error measures
# ---------------------------------------------------------------------------------------------
def test_error_measures_on_known_arrays():
    tau = np.array([[3.0, 1.0, 0.0], [4.0, -1.0, 0.0]])
    hat = np.array([[2.0, 1.0, 1.0], [4.0, 1.0, 0.0]])
    m = error_measures(tau, hat, effort=[10.0, np.nan, 0.0])
    # errors: joint 1 (1, 0), joint 2 (0, -2), joint 3 (-1, 0)
    assert m["overall_relative"] == pytest.approx(np.sqrt(1 + 4 + 1) / np.sqrt(9 + 16 + 1 + 1))
    np.testing.assert_allclose(m["rms"], np.sqrt([0.5, 2.0, 0.5]), rtol=1e-15)
    np.testing.assert_allclose(m["relative"][:2], [1 / 5, 2 / np.sqrt(2)], rtol=1e-15)
    assert np.isnan(m["relative"][2])  # no torque on joint 3
    assert m["nrms"][0] == pytest.approx(np.sqrt(0.5) / 10) and np.isnan(m["nrms"][1:]).all()
    assert m["nrms_missing"] == [2, 3]


def test_measures_and_scaled_condition_number_match_numpy(two_logs):
    robot, base, logs = two_logs
    (_, d1), (_, d2) = logs
    res = identify(robot, [d1, d2], base=base, rsd_threshold=None, min_velocity=0.05)
    # Scaled condition number of the stacked regressor, with the rows min_velocity leaves out
    W = np.vstack([dynamic_system(base, d, min_velocity=0.05)[0] for d in (d1, d2)])
    cond = np.linalg.cond(W / np.linalg.norm(W, axis=0))
    assert res.cond == pytest.approx(cond, rel=1e-6)  # SVD of a triangle vs of W: round-off
    assert res.to_dict()["condition_number_scaled"] == pytest.approx(cond, rel=1e-6)
    # Measures over both logs stacked and per log, from the predictions W_b p
    v = validate(res, [d1, d2])
    effort = robot.limits["effort"]
    hats = [(dynamic_system(base, d)[0] @ res.full).reshape(d.m, d.n) for d in (d1, d2)]
    tau, hat = np.vstack([d1.tau, d2.tau]), np.vstack(hats)
    assert v["overall_relative"] == pytest.approx(
        np.linalg.norm(tau - hat) / np.linalg.norm(tau), rel=1e-9
    )
    rms = np.sqrt(np.mean((tau - hat) ** 2, axis=0))
    np.testing.assert_allclose(v["rms"], rms, rtol=1e-9)
    np.testing.assert_allclose(
        v["relative"], np.linalg.norm(tau - hat, axis=0) / np.linalg.norm(tau, axis=0), rtol=1e-9
    )
    np.testing.assert_allclose(v["nrms"], rms / effort, rtol=1e-9)
    for d, h, per in zip((d1, d2), hats, v["logs"]):
        assert per["overall_relative"] == pytest.approx(
            np.linalg.norm(d.tau - h) / np.linalg.norm(d.tau), rel=1e-9
        )
    # Noise of 1 % of the effort limit per joint: the fit leaves about that as RMS error
    # (0.8 to 1.2: the parameters absorb a little, 2 x 6 x 5000 samples estimate it closely).
    assert np.all((v["nrms"] > 0.008) & (v["nrms"] < 0.012))


# ---------------------------------------------------------------------------------------------
# Several logs
# ---------------------------------------------------------------------------------------------
def test_two_logs_give_the_estimate_of_one_stacked_log(two_logs):
    robot, base, logs = two_logs
    (log1, d1), (_, d2) = logs
    one = stacked(d1, d2)
    for weighted in (False, True):
        a = identify(robot, [d1, d2], base=base, weighted=weighted, rsd_threshold=30.0)
        b = identify(robot, one, base=base, weighted=weighted, rsd_threshold=30.0)
        assert a.names == b.names and a.rows == b.rows
        np.testing.assert_allclose(a.values, b.values, rtol=1e-9)
        np.testing.assert_allclose(a.std, b.std, rtol=1e-9)
        if weighted:
            np.testing.assert_allclose(a.joint_sigma, b.joint_sigma, rtol=1e-9)
    assert [x["samples"] for x in a.settings["logs"]] == [d1.m, d2.m]
    truth = true_base_values(base, {"names": log1.param_names, "values": log1.params})
    kept = [list(base.names).index(n) for n in a.names]
    err = np.abs(a.values - truth[kept]) / np.maximum(a.std, 1e-12)
    assert np.all(err < 5)  # each estimate within 5 of its standard deviations of the truth


def test_energy_model_stacks_the_windows_of_each_log(two_logs):
    robot, base, logs = two_logs
    d1, d2 = logs[0][1], logs[1][1]
    res = identify(
        robot,
        [d1, d2],
        model="energy",
        base=base,
        weighted=False,
        rsd_threshold=None,
        energy_window=5,
    )
    rule = res.settings["integration"]  # the rule identify chose, on both logs together
    systems = [energy_system(base, d, window=5, integration=rule) for d in (d1, d2)]  # per log
    W = np.vstack([s[0] for s in systems])
    y = np.concatenate([s[1] for s in systems])
    p, *_ = np.linalg.lstsq(W, y, rcond=None)
    np.testing.assert_allclose(res.values, p, rtol=1e-7, atol=1e-9 * np.abs(p).max())
    assert res.rows == W.shape[0] == (d1.m - 1) // 5 + (d2.m - 1) // 5


def test_integral_model_stacks_the_windows_of_each_log(two_logs):
    """Per log, its own windows (none across the junction); the joint-wise stacked system of
    both logs solved by numpy gives the estimate."""
    robot, base, logs = two_logs
    d1, d2 = logs[0][1], logs[1][1]
    res = identify(
        robot,
        [d1, d2],
        model="integral",
        base=base,
        weighted=False,
        rsd_threshold=None,
        integral_window=8,
        min_velocity=0,  # every window (integral_system's)
    )
    rule = res.settings["integration"]  # the rule identify chose, on both logs together
    systems = [integral_system(base, d, window=8, integration=rule) for d in (d1, d2)]
    W = np.vstack([s[0].reshape(-1, base.n) for s in systems])
    y = np.concatenate([s[1].reshape(-1) for s in systems])
    p, *_ = np.linalg.lstsq(W, y, rcond=None)
    np.testing.assert_allclose(res.values, p, rtol=1e-7, atol=1e-9 * np.abs(p).max())
    assert res.rows == W.shape[0] == robot.n * ((d1.m - 1) // 8 + (d2.m - 1) // 8)


def test_junction_between_logs_does_not_leak_into_derivatives(tmp_path, capsys):
    """Two noise-free logs whose positions jump between the end of one and the start of the
    other, written as positions and torques only: each log's velocities and accelerations come
    from its own samples, so the estimate is as good as the filter allows; the same samples as
    one file differentiate across the jump and the estimate is far off."""
    robot = mindyn.load("zcr07s")
    base = mindyn.base_parameters(robot)
    files, logs = [], []
    for k, seed in enumerate((21, 22)):
        log = simulate_inverse(robot, random_trajectory(robot, seed=seed), rate=100.0)
        path = write_csv(tmp_path / f"log{k}.csv", log.t + 1000.0 * k, log.q, log.tau)
        files.append(path)
        logs.append(log)
    jump = np.abs(logs[1].q[0] - logs[0].q[-1]).max()
    assert jump > 0.1  # rad: a real junction
    truth = true_base_values(base, {"names": logs[0].param_names, "values": logs[0].params})
    data = [read_csv(f, robot) for f in files]
    for d, log in zip(data, logs):  # no leak: the ends of each log keep their derivatives
        end = kept(d, log.ddq_true)[-3:]
        assert np.abs(d.ddq[-3:] - end).max() < 0.05 * np.abs(log.ddq_true).max()
    sep = identify(robot, data, base=base, rsd_threshold=None)
    one = np.vstack([np.loadtxt(f, delimiter=",", skiprows=1) for f in files])
    joined = tmp_path / "joined.csv"
    write_csv(joined, one[:, 0], one[:, 1:7], one[:, 7:])
    together = identify(robot, read_csv(joined, robot), base=base, rsd_threshold=None)
    err_sep = np.linalg.norm(sep.full - truth) / np.linalg.norm(truth)
    err_joined = np.linalg.norm(together.full - truth) / np.linalg.norm(truth)
    print(f"\nrelative parameter error: logs apart {err_sep:.2g}, joined {err_joined:.2g}")
    assert err_sep < 0.01 and err_joined > 5 * err_sep
    # The command line fits both files the same way and reports each log
    out = tmp_path / "res.json"
    args = ["identify", "zcr07s", *map(str, files), "--rsd-threshold", "0", "--json", str(out)]
    args += ["--filter", "butter"]  # the reader's derivative filter, as read_csv above
    report = tmp_path / "report"
    checks = []  # two validation logs of their own (a fit log as validation is refused)
    for k, seed in enumerate((23, 24)):
        log = simulate_inverse(robot, random_trajectory(robot, seed=seed), rate=100.0)
        checks.append(str(write_csv(tmp_path / f"val{k}.csv", log.t, log.q, log.tau)))
    argv = args + ["--validate", *checks, "--report", str(report)]
    assert cli.main(argv) == 0
    text = capsys.readouterr().out
    assert "2 logs fitted together" in text and "overall relative error" in text
    for name in ("torque_identification", "torque_validation", "trajectory"):
        assert (report / f"{name}.png").is_file() and (report / f"{name}_2.png").is_file()
    assert json.loads((report / "identification.json").read_text()) == json.loads(out.read_text())
    doc = json.loads(out.read_text())
    np.testing.assert_allclose(doc["base_values"], sep.full, rtol=1e-9, atol=1e-12)
    v = validate(sep, data)
    assert doc["fit"]["overall_relative"] == pytest.approx(v["overall_relative"], rel=1e-9)
    checked = validate(sep, [read_csv(c, robot) for c in checks])
    assert doc["validation"]["overall_relative"] == pytest.approx(
        checked["overall_relative"], rel=1e-9
    )
    assert [x["samples"] for x in doc["fit"]["logs"]] == [d.m for d in data]
    np.testing.assert_allclose(doc["fit"]["logs"][0]["rms"], v["logs"][0]["rms"], rtol=1e-9)
    np.testing.assert_allclose(doc["fit"]["nrms"], v["rms"] / robot.limits["effort"], rtol=1e-9)
    assert doc["fit"]["nrms_missing_limit"] == []


# ---------------------------------------------------------------------------------------------
# Motor currents
# ---------------------------------------------------------------------------------------------
@pytest.fixture
def drive_arm(tmp_path):
    """A random 3-joint arm with a drive table (torque constant, gear ratio) and no effort limit
    on joint 2; returns the robot and its joint-side gains K = torque_constant x gear_ratio."""
    path = random_arm_yaml(tmp_path / "arm.yaml", n=3, seed=5)
    doc = yaml.safe_load(path.read_text())
    kt, gear = [0.11, 0.09, 0.07], [100.0, 120.0, -80.0]
    for j, a, b in zip(doc["joints"], kt, gear):
        j["drive"] = {"rated_torque": 1.0, "gear_ratio": b, "torque_constant": a}
    del doc["joints"][1]["limits"]["effort"]
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    robot = mindyn.load(str(path))
    return robot, str(path), np.array(kt) * np.array(gear)


def test_drive_table_gives_the_torque_constant(drive_arm):
    robot, _, K = drive_arm
    d = robot.drives
    np.testing.assert_array_equal(d["torque_constant"] * d["gear_ratio"], K)
    assert np.isnan(mindyn.load("zcr07s").drives["torque_constant"]).all()


def test_currents_times_gains_are_the_torques(drive_arm, tmp_path, capsys):
    robot, arm, K = drive_arm
    log = simulate_inverse(robot, random_trajectory(robot, seed=3), rate=100.0, friction=True)
    cur = log.tau / K
    # 1. columns i1..in in the log itself: torque unit 'current' from the header
    p = tmp_path / "i.csv"
    np.savetxt(
        p,
        np.column_stack([log.t, log.q, log.dq, cur]),
        delimiter=",",
        header="t,q1,q2,q3,dq1,dq2,dq3,i1,i2,i3",
        comments="",
        fmt="%.15g",
    )
    d = read_csv(p, robot)
    np.testing.assert_allclose(d.tau, kept(d, log.tau), rtol=1e-13, atol=1e-13)
    assert d.processing["torque"]["scale_Nm_per_unit"] == pytest.approx(list(K))
    # 2. gains given instead of the drive table: the torques scale with them
    d2 = read_csv(p, robot, drive_gain=2 * K)
    np.testing.assert_allclose(d2.tau, 2 * kept(d2, log.tau), rtol=1e-13, atol=1e-13)
    # 3. currents in a separate file (with extra columns), joined on the time stamps
    q = tmp_path / "q.csv"
    write_csv(q, log.t, log.q, None, dq=log.dq)
    c = tmp_path / "currents.csv"
    extra = np.zeros((log.t.size, 3))
    rows = np.column_stack([log.t + 1e-7, cur, extra])  # stamps off by 1e-7 s (< 1e-5 s)
    rows = np.vstack([[-0.5, 0, 0, 0, 0, 0, 0], rows])  # a current sample before the log
    np.savetxt(
        c, rows, delimiter=",", header="t,i1,i2,i3,i_des1,i_des2,i_des3", comments="", fmt="%.15g"
    )
    dq = read_csv(q, robot, require_torque=False)
    joined = attach_currents(dq, c, robot)
    np.testing.assert_allclose(joined.tau, kept(dq, log.tau), rtol=1e-13, atol=1e-13)
    # the command line: both ways give the estimate of the torque log itself
    ref = tmp_path / "tau.csv"
    write_csv(ref, log.t, log.q, log.tau, dq=log.dq)
    docs = []
    tau_as_current = tmp_path / "tau_current.csv"
    write_csv(tau_as_current, log.t, log.q, cur, dq=log.dq)  # tau columns holding currents
    for extra_args in (
        [str(p)],
        [str(tau_as_current), "--torque-unit", "current"],
        [str(ref), "--torque-unit", "Nm"],
        [str(q), "--currents", str(c)],
        [str(p), "--drive-gain", ",".join(f"{k:.17g}" for k in K)],
    ):
        out = tmp_path / "o.json"
        argv = ["identify", arm, *extra_args, "--friction", "--rsd-threshold", "0"]
        assert cli.main(argv + ["--json", str(out)]) == 0, capsys.readouterr().err
        docs.append(json.loads(out.read_text()))
    text = capsys.readouterr().out
    assert "torques converted from motor currents" in text
    assert "no effort limit for joint(s) 2" in text
    for doc in docs[1:]:
        np.testing.assert_allclose(doc["base_values"], docs[0]["base_values"], rtol=1e-8)
    assert docs[0]["fit"]["nrms"][1] is None and docs[0]["fit"]["nrms_missing_limit"] == [2]


def test_recorded_drive_gains_are_not_applied_to_a_log_of_torques(drive_arm, tmp_path, capsys):
    """An identification of currents through --drive-gain records the gains. ``predict`` and
    ``detect`` on a log of torques refused it, naming --drive-gain, which the user had not
    given. The recorded gains now apply to logs of currents only; gains given still refuse."""
    robot, arm, K = drive_arm
    K = -0.5 * K  # not the drive table's: the recorded gains are the ones applied
    log = simulate_inverse(robot, random_trajectory(robot, seed=4), rate=100.0, friction=True)
    cur = tmp_path / "i.csv"
    np.savetxt(
        cur,
        np.column_stack([log.t, log.q, log.dq, log.tau / K]),
        delimiter=",",
        header="t,q1,q2,q3,dq1,dq2,dq3,i1,i2,i3",
        comments="",
        fmt="%.17g",
    )
    tau = write_csv(tmp_path / "tau.csv", log.t, log.q, log.tau, dq=log.dq)
    gains = ",".join(f"{k:.17g}" for k in K)
    doc = tmp_path / "id.json"
    argv = ["identify", arm, str(cur), "--drive-gain", gains, "--friction", "--json", str(doc)]
    assert cli.main(argv) == 0, capsys.readouterr().err
    capsys.readouterr()
    out = {}
    for name, p in (("currents", cur), ("torques", tau)):
        csv = tmp_path / f"pred_{name}.csv"
        assert cli.main(["predict", arm, str(doc), str(p), "-o", str(csv)]) == 0
        out[name] = np.genfromtxt(csv, delimiter=",", names=True)
        text = capsys.readouterr().out
        assert ("recorded for the identification's currents are not applied" in text) is (
            name == "torques"
        )
    for j in range(1, 4):  # the same motion, the same torques: K i of the one, tau of the other
        np.testing.assert_allclose(
            out["torques"][f"tau{j}"], out["currents"][f"tau{j}"], rtol=1e-9, atol=1e-12
        )
        np.testing.assert_allclose(
            out["torques"][f"tau_hat{j}"], out["currents"][f"tau_hat{j}"], rtol=1e-8, atol=1e-10
        )
    residuals = []
    for p in (cur, tau):
        assert cli.main(["detect", arm, str(doc), str(p)]) == 0
        text = capsys.readouterr().out
        residuals.append(text[text.index("residual |r|") :].splitlines()[1:4])
    assert residuals[0] == residuals[1]
    # gains given for a log of torques are still refused
    assert (
        cli.main(
            [
                "predict",
                arm,
                str(doc),
                str(tau),
                "-o",
                str(tmp_path / "x.csv"),
                "--drive-gain",
                gains,
            ]
        )
        == 2
    )
    assert "holds torques in N m, not motor currents" in capsys.readouterr().err


def test_currents_of_a_urdf_without_gains_ask_for_the_gains_not_a_yaml_table(tmp_path, capsys):
    """A URDF has no drive table: the refusal of a current log without --drive-gain asks for
    the gains, not for a drive table in a YAML file the robot does not have."""
    urdf = Path(__file__).resolve().parents[1] / "examples" / "urdf" / "ur5.urdf"
    log = simulate_inverse(mindyn.load(urdf), random_trajectory(str(urdf), seed=1), rate=50.0)
    path = write_csv(tmp_path / "i.csv", log.t, log.q, log.tau, torque_unit="current")
    assert cli.main(["identify", str(urdf), str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "a URDF or MJCF has no drive table: give the joint-side gains (--drive-gain" in err
    assert "YAML" not in err and "\n" not in err, err
    yaml_table = cli.main(["identify", "zcr07s", str(path), "--torque-unit", "current"])
    assert yaml_table == 2 and "to its YAML" in capsys.readouterr().err


def test_current_errors_are_one_line(drive_arm, tmp_path, capsys):
    robot, arm, K = drive_arm
    log = simulate_inverse(robot, random_trajectory(robot, seed=3), rate=100.0)
    q = tmp_path / "q.csv"
    write_csv(q, log.t, log.q, None, dq=log.dq)
    c = tmp_path / "c.csv"
    t = log.t.copy()
    t[40] += 0.003  # a stamp 3 ms off at 100 Hz
    np.savetxt(
        c,
        np.column_stack([t, log.tau / K]),
        delimiter=",",
        header="t,i1,i2,i3",
        comments="",
        fmt="%.15g",
    )
    bad_header = tmp_path / "b.csv"
    bad_header.write_text("t,i1,i2\n0,1,2\n1,1,2\n")
    zcr = tmp_path / "zcr.csv"
    zlog = simulate_inverse("zcr07s", random_trajectory("zcr07s", seed=1), rate=50.0)
    write_csv(zcr, zlog.t, zlog.q, zlog.tau)
    cases = [
        ([arm, str(q), "--currents", str(c)], "no current sample at t = 0.4"),
        ([arm, str(q), "--currents", str(bad_header)], "missing column(s) i3"),
        ([arm, str(q), "--currents", str(c), str(c)], "2 currents file(s) for 1 log(s)"),
        (["zcr07s", str(zcr), "--torque-unit", "current"], "gives no torque constant"),
        ([arm, str(q), "--currents", str(c), "--drive-gain", "1,2"], "--drive-gain needs 3 values"),
        ([arm, str(q), "--validate-currents", str(c)], "expected --validate"),
        ([arm, str(q), "--currents", str(c), "--torque-unit", "Nm"], "--torque-unit does not"),
        (["zcr07s", str(zcr), "--drive-gain", "2"], "not motor currents"),
    ]
    for argv, msg in cases:
        assert cli.main(["identify", *argv]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("mindyn: error:") and "\n" not in err and msg in err, err
    # the currents file follows the same cell and text rules as the log itself
    from mindyn.identification.currents import read_currents

    (tmp_path / "u.csv").write_text("t,i1,i2,i3\n0,1_000,0,0\n0.01,0,0,0\n")
    with pytest.raises(DataError, match=r"u\.csv, line 2, column i1: '1_000' is not a number"):
        read_currents(tmp_path / "u.csv", 3)
    (tmp_path / "x.csv").write_bytes(b"t,i1,i2,i3\n0,0,0,0\n0.01,0,\xff,0\n")
    with pytest.raises(DataError, match=r"x\.csv, line 3: not UTF-8 text \(byte 0xff"):
        read_currents(tmp_path / "x.csv", 3)
    (tmp_path / "h.csv").write_text("t,i1,i2,i3\n0,1e400,0,0\n0.01,0,0,0\n")
    with pytest.raises(DataError, match=r"column i1: '1e400' is too large for a double"):
        read_currents(tmp_path / "h.csv", 3)
    with pytest.raises(DataError, match="both torque columns"):
        p = tmp_path / "both.csv"
        p.write_text("t,q1,q2,q3,tau1,tau2,tau3,i1,i2,i3\n" + "0,0,0,0,0,0,0,0,0,0\n" * 3)
        read_csv(p, robot)


def test_several_logs_refuse_a_wrong_joint_count(two_logs):
    robot, base, logs = two_logs
    d = logs[0][1]
    short = replace(d, q=d.q[:, :3], dq=d.dq[:, :3], ddq=d.ddq[:, :3], tau=d.tau[:, :3])
    with pytest.raises(DataError, match="has 3 joints"):
        identify(robot, [d, short], base=base)
    with pytest.raises(ValueError, match="^data must be a JointData or a non-empty list"):
        identify(robot, [], base=base)


def test_bag_efforts_in_amperes(tmp_path, capsys):
    """A ROS bag whose effort field holds motor currents: --torque-unit current with the gains
    gives the estimate of the same log in N m."""
    pytest.importorskip("rosbags")
    from test_rosbag import messages, robot_log, write_bag

    robot = mindyn.load("planar3")
    t, q, dq, tau = robot_log(robot)
    K = np.array([50.0, 40.0, 30.0])
    bag = write_bag(tmp_path / "run", messages(robot, (t, q, dq, tau / K)), storage="mcap")
    ref = write_bag(tmp_path / "ref", messages(robot, (t, q, dq, tau)), storage="mcap")
    out = {}
    for name, argv in (
        ("amps", [str(bag), "--torque-unit", "current", "--drive-gain", "50,40,30"]),
        ("ref", [str(ref)]),
    ):
        js = tmp_path / f"{name}.json"
        assert cli.main(["identify", "planar3", *argv, "--json", str(js)]) == 0
        out[name] = json.loads(js.read_text())
    capsys.readouterr()
    a, b = np.array(out["amps"]["base_values"]), np.array(out["ref"]["base_values"])
    np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-12 * np.abs(b).max())  # round-off
    assert out["amps"]["data"]["processing"]["torque"]["scale_Nm_per_unit"] == [50, 40, 30]


def test_a_negative_drive_gain_is_a_reversed_motor(drive_arm, tmp_path, capsys):
    """A negative --drive-gain was taken silently, its meaning nowhere said. It is a sign
    convention, as the drive table's negative gear ratio is: a motor whose positive current
    drives its joint backwards. A log of currents whose joint-2 motor is wired reversed, read
    with joint 2's gain negated, identifies as the torque log does; the output names the
    reversed joints; --help says so."""
    robot, arm, K = drive_arm  # the drive table's joint 3 has a negative gear ratio
    log = simulate_inverse(robot, random_trajectory(robot, seed=3), rate=100.0, friction=True)
    flip = np.array([1.0, -1.0, 1.0])
    cur = log.tau / K * flip  # the current as the reversed motor's amplifier logs it
    p, ref = tmp_path / "i.csv", tmp_path / "tau.csv"
    write_csv(p, log.t, log.q, cur, dq=log.dq)
    write_csv(ref, log.t, log.q, log.tau, dq=log.dq)
    gains = ",".join(f"{k:.17g}" for k in K * flip)
    d = read_csv(p, robot, drive_gain=K * flip, torque_unit="current")
    np.testing.assert_allclose(d.tau, kept(d, log.tau), rtol=1e-9)
    docs = []
    for extra in ([str(p), "--torque-unit", "current", "--drive-gain", gains], [str(ref)]):
        out = tmp_path / "o.json"
        argv = ["identify", arm, *extra, "--friction", "--rsd-threshold", "0", "--json", str(out)]
        assert cli.main(argv) == 0, capsys.readouterr().err
        docs.append(json.loads(out.read_text()))
        if len(docs) == 1:
            text = capsys.readouterr().out
    np.testing.assert_allclose(docs[0]["base_values"], docs[1]["base_values"], rtol=1e-8)
    assert "negative gain of joint 2, joint 3 (a positive current drives it backwards" in text
    assert cli.main(["identify", "--help"]) == 0
    helptext = " ".join(capsys.readouterr().out.split())
    assert "A negative gain is kept as a sign convention" in helptext, helptext
