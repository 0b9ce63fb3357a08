"""Joint data in and out: CSV format, torque units, derivatives, and precise errors."""

from __future__ import annotations

import numpy as np
import pytest
from mindyn import cli, load
from mindyn.identification import IdentificationError, identify
from mindyn.identification.data import (
    DataError,
    DataFileNotFoundError,
    differentiate,
    read_csv,
    read_truth,
    truth_path,
    write_csv,
)

# The ZCR07S study, Table 4: motor rated torque [N m] and reducer ratio of the ZCR07S joints.
SEED_RATED = [2.390, 2.390, 1.270, 0.318, 0.318, 0.318]
SEED_GEAR = [120, 120, 100, 116, 80, 50]


def _log(n=3, m=400, rate=250.0, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(m) / rate
    q = np.sin(np.outer(t, rng.uniform(0.5, 2, n)) + rng.uniform(0, 1, n))
    dq = np.cos(q)
    tau = rng.normal(size=(m, n))
    return t, q, dq, tau


def _write(path, header, rows):
    path.write_text(",".join(header) + "\n" + "\n".join(",".join(r) for r in rows) + "\n")
    return path


def test_roundtrip_with_logged_velocities(tmp_path):
    t, q, dq, tau = _log()
    p = write_csv(tmp_path / "a.csv", t, q, tau, dq=dq)
    assert p.read_text().splitlines()[0] == "t,q1,q2,q3,dq1,dq2,dq3,tau1,tau2,tau3"
    d = read_csv(p)
    assert d.n == 3 and d.m == t.size
    np.testing.assert_allclose(d.q, q, rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(d.dq, dq, rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(d.tau, tau, rtol=1e-11, atol=1e-12)
    assert d.processing["velocity"]["source"] == "logged"
    assert d.processing["acceleration"]["source"] == "differentiated velocities"
    assert d.rate == pytest.approx(250.0)


def test_permille_torques_use_the_drive_table(tmp_path):
    robot = load("zcr07s")
    t, q, _, _ = _log(n=6)
    per = np.full((t.size, 6), 1000.0)
    per[:, 3] = -500.0
    d = read_csv(write_csv(tmp_path / "p.csv", t, q, per), robot, torque_unit="permille")
    expect = np.array(SEED_RATED) * np.array(SEED_GEAR)  # value x rated x gear / 1000
    expect[3] *= -0.5
    np.testing.assert_allclose(d.tau[0], expect, rtol=1e-12)
    assert d.processing["torque"]["unit"].startswith("permille")


def test_permille_without_drive_table_is_an_error(tmp_path):
    t, q, _, tau = _log(n=3)
    p = write_csv(tmp_path / "p.csv", t, q, tau)
    with pytest.raises(DataError, match="no rated torque / gear ratio for joint"):
        read_csv(p, load("puma560_3"), torque_unit="permille")
    with pytest.raises(DataError, match="unknown torque unit 'kNm'"):
        read_csv(p, load("puma560_3"), torque_unit="kNm")


@pytest.mark.parametrize("method", ["butter", "savgol"])
def test_derivatives_of_positions_match_closed_form(tmp_path, method):
    rate, f = 250.0, 0.4
    t = np.arange(2501) / rate
    w = 2 * np.pi * f
    q = np.column_stack([np.sin(w * t), 0.5 * np.cos(2 * w * t)])
    dq_exact = np.column_stack([w * np.cos(w * t), -w * np.sin(2 * w * t)])
    ddq_exact = np.column_stack([-(w**2) * np.sin(w * t), -2 * w**2 * np.cos(2 * w * t)])
    noisy = q + np.random.default_rng(1).normal(scale=1e-5, size=q.shape)
    p = write_csv(tmp_path / "d.csv", t, noisy, np.zeros_like(q))
    d = read_csv(p, filter=method)
    inner = slice(60, -60)  # 0.24 s away from the ends, where the filters are one-sided
    e_v = np.abs(d.dq[inner] - dq_exact[inner]).max() / np.abs(dq_exact).max()
    e_a = np.abs(d.ddq[inner] - ddq_exact[inner]).max() / np.abs(ddq_exact).max()
    print(f"\n{method}: max relative error velocity {e_v:.2e}, acceleration {e_a:.2e}")
    assert e_v < 1e-3 and e_a < 1e-2
    info = d.processing["velocity"]
    assert info["source"] == "differentiated positions"
    if method == "butter":
        assert info["order"] == 4 and info["cutoff_Hz"] == pytest.approx(10.0)
    else:
        assert info["window_samples"] % 2 == 1 and info["polyorder"] == 3


def test_differentiate_rejects_bad_settings():
    t = np.arange(100) / 100.0
    x = np.zeros((100, 1))
    with pytest.raises(DataError, match="cutoff 60 Hz must be between 0 and half the rate"):
        differentiate(t, x, cutoff=60)
    with pytest.raises(DataError, match="unknown filter 'kalman'"):
        differentiate(t, x, filter="kalman")


def test_missing_and_extra_columns_are_named(tmp_path):
    rows = [["0", "1", "2", "3", "4"], ["0.004", "1", "2", "3", "4"]]
    p = _write(tmp_path / "c.csv", ["t", "q1", "q2", "tau1", "tau3"], rows)
    with pytest.raises(DataError) as e:
        read_csv(p, n=2)
    msg = str(e.value)
    assert "missing tau2" in msg and "unexpected tau3" in msg and "c.csv" in msg
    p = _write(
        tmp_path / "x.csv", ["t", "q1", "q2", "tau1", "tau2", "current1"], [r + ["0"] for r in rows]
    )
    with pytest.raises(DataError, match="unexpected current1"):
        read_csv(p, n=2)
    p = _write(
        tmp_path / "v.csv", ["t", "q1", "q2", "dq1", "tau1", "tau2"], [r + ["0"] for r in rows]
    )
    with pytest.raises(DataError, match="missing dq2"):
        read_csv(p, n=2)
    p = _write(tmp_path / "n.csv", ["time", "q1", "q2", "tau1", "tau2"], rows)
    with pytest.raises(DataError, match=r"missing t; unexpected time"):
        read_csv(p, n=2)


def test_wrong_joint_count_for_the_robot(tmp_path):
    t, q, _, tau = _log(n=3)
    p = write_csv(tmp_path / "a.csv", t, q, tau)
    with pytest.raises(DataError, match="6-joint robot.*missing q4, q5, q6"):
        read_csv(p, load("zcr07s"))


def test_time_must_increase_and_the_line_is_named(tmp_path):
    rows = [[f"{t}", "0", "0"] for t in (0.0, 0.004, 0.008, 0.006, 0.01)]
    p = _write(tmp_path / "t.csv", ["t", "q1", "tau1"], rows)
    with pytest.raises(
        DataError, match=r"t\.csv, line 5: time is not increasing \(t = 0\.006 after 0\.008\)"
    ):
        read_csv(p)


def test_nan_and_non_numbers_are_located(tmp_path):
    rows = [["0", "0", "0"], ["0.004", "0", "nan"], ["0.008", "0", "0"]]
    p = _write(tmp_path / "nan.csv", ["t", "q1", "tau1"], rows)
    with pytest.raises(DataError, match="line 3, column tau1: NaN"):
        read_csv(p)
    rows[1][1] = "abc"
    p = _write(tmp_path / "s.csv", ["t", "q1", "tau1"], rows)
    with pytest.raises(DataError, match="line 3, column q1: 'abc' is not a number"):
        read_csv(p)
    rows[1] = ["0.004", "0"]
    p = _write(tmp_path / "r.csv", ["t", "q1", "tau1"], rows)
    with pytest.raises(DataError, match="line 3: 2 values for 3 columns"):
        read_csv(p)


def test_empty_and_missing_files(tmp_path):
    (tmp_path / "e.csv").write_text("")
    with pytest.raises(DataError, match="empty"):
        read_csv(tmp_path / "e.csv")
    (tmp_path / "h.csv").write_text("t,q1,tau1\n0,0,0\n")
    with pytest.raises(DataError, match="1 data row"):
        read_csv(tmp_path / "h.csv")
    with pytest.raises(DataFileNotFoundError, match="does not exist"):
        read_csv(tmp_path / "nope.csv")
    assert issubclass(DataFileNotFoundError, FileNotFoundError)
    assert issubclass(DataError, ValueError)


def test_too_few_samples_for_the_parameters(tmp_path):
    robot = load("zcr07s")
    t, q, dq, tau = _log(n=6, m=8)
    d = read_csv(write_csv(tmp_path / "s.csv", t, q, tau, dq=dq), robot, filter="none")
    with pytest.raises(IdentificationError, match=r"8 samples x 6 joints = 48 equations for 52"):
        identify(robot, d, rotor=True, friction=True)
    with pytest.raises(IdentificationError, match="energy windows"):
        identify(robot, d, model="energy", rotor=True, friction=True, energy_window=1)


def test_truth_sidecar(tmp_path):
    p = tmp_path / "log.csv"
    assert truth_path(p).name == "log.truth.json"
    assert read_truth(p) is None
    truth_path(p).write_text('{"names": ["M1"], "values": [2.0]}')
    assert read_truth(p)["values"] == [2.0]
    truth_path(p).write_text("{nope")
    with pytest.raises(DataError, match="not valid JSON"):
        read_truth(p)


def test_cli_reports_bad_data_in_one_line(tmp_path, capsys):
    rows = [["0", "0", "0"], ["0.004", "0", "0"], ["0.002", "0", "0"]]
    p = _write(tmp_path / "bad.csv", ["t", "q1", "tau1"], rows)
    rc = cli.main(["identify", "planar1", str(p)])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.startswith("mindyn: error: ") and err.count("\n") == 1
    assert "line 4: time is not increasing" in err
    rc = cli.main(["identify", "planar1", str(tmp_path / "missing.csv")])
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("mindyn: error: data file") and err.count("\n") == 1
