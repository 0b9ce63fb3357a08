"""Accelerations derived by a reader of a short log, and the estimates fitted on them.

Reference: the true parameters and accelerations of logs the test simulates (torque noise of a
known level): the estimates with every base parameter against the true base values, in units of
the standard deviations reported; the derived accelerations against the true ones."""

from __future__ import annotations

import sys
from pathlib import Path

import mindyn
import numpy as np
import pytest
from mindyn.control import SensorNoise, simulate_inverse
from mindyn.identification import identify
from mindyn.identification.data import DataError, fill_derivatives, read_csv, write_csv
from mindyn.identification.excitation import random_trajectory

sys.path.insert(0, str(Path(__file__).parent))
from test_identification import truth_of  # noqa: E402

RATE = 500.0


def _log(duration: float, seed: int):
    robot = mindyn.load("zcr07s")
    traj = random_trajectory(robot, seed=seed, freq=0.1)  # starts at rest, period 10 s
    log = simulate_inverse(
        robot,
        traj,
        rate=RATE,
        duration=duration,
        friction=True,
        seed=seed,
        noise=SensorNoise(torque=0.01),
    )
    return robot, log


def _read(tmp_path, log, **kw):
    """The log as written by the simulation and read back: velocities logged, accelerations
    derived by the reader (zero-phase Butterworth at its default cut-off of 10 Hz)."""
    p = write_csv(tmp_path / "log.csv", log.t, log.q, log.tau, dq=log.dq)
    return read_csv(p, **kw)


def _z(robot, log, data):
    res = identify(robot, data, friction=True, rsd_threshold=None)  # every base parameter
    truth = truth_of(res.base, log)
    return (res.values - truth) / res.std


@pytest.mark.parametrize("seed", [1, 2])
def test_a_short_log_read_with_derived_accelerations_is_fitted_without_bias(tmp_path, seed):
    # 2 s of a 10-s excitation: with the filter's start-up at the ends fitted, 13 and 24 of 48
    # estimates were more than 3 standard deviations off the truth (up to 12)
    robot, log = _log(2.0, seed)
    data = _read(tmp_path, log)
    z = _z(robot, log, data)
    assert np.mean(np.abs(z) > 3) <= 0.05 and np.abs(z).max() < 5, np.round(z, 1)
    k = data.processing["derivative_edges"]["samples"]
    assert k == 100  # 2 periods of the 10 Hz cut-off at 500 Hz, at each end
    np.testing.assert_array_equal(data.t, log.t[k:-k])


def test_the_dropped_edges_hold_the_filters_start_up(tmp_path):
    # the derived accelerations against the true ones: off at the ends, not on what is kept
    _, log = _log(2.0, 1)
    data = _read(tmp_path, log)
    k = data.processing["derivative_edges"]["samples"]
    assert data.processing["derivative_edges"]["seconds"] == pytest.approx(k / RATE)
    true = log.ddq_true
    rms = np.sqrt(np.mean(true**2))
    kept = np.abs(data.ddq - true[k:-k]).max() / rms
    # the same derivation over the whole log, nothing dropped
    _, ddq_all, _ = fill_derivatives(log.t, log.q, log.dq, None)
    np.testing.assert_allclose(ddq_all[k:-k], data.ddq, rtol=1e-6, atol=1e-6 * rms)
    edges = np.concatenate([ddq_all[:k] - true[:k], ddq_all[-k:] - true[-k:]])
    assert kept < 2e-3
    assert np.abs(edges).max() / rms > 10 * kept


def test_a_long_log_is_fitted_as_before(tmp_path):
    # 10 s, a whole period: a few per cent of the samples dropped; the estimates agree with
    # those from the true accelerations within a fraction of their standard deviations
    robot, log = _log(10.0, 0)
    data = _read(tmp_path, log)
    assert data.m == log.t.size - 200
    z = _z(robot, log, data)
    assert np.abs(z).max() < 5
    exact = read_csv(
        write_csv(tmp_path / "exact.csv", log.t, log.q, log.tau, dq=log.dq, ddq=log.ddq_true)
    )
    assert exact.m == log.t.size and exact.processing["derivative_edges"]["samples"] == 0
    z_exact = _z(robot, log, exact)
    assert np.abs(z - z_exact).max() < 1.0


def test_a_log_shorter_than_its_filter_edges_is_refused(tmp_path):
    _, log = _log(2.0, 0)
    t, q, tau = log.t[:300], log.q[:300], log.tau[:300]  # 0.6 s, no velocities logged
    p = write_csv(tmp_path / "short.csv", t, q, tau)
    with pytest.raises(DataError, match=r"the 200 samples at each end .* leave 0 of 300"):
        read_csv(p)
    assert read_csv(p, cutoff=40.0).m == 300 - 2 * 2 * 25  # two derivations, 25 samples each


def test_the_command_line_states_the_dropped_edges(tmp_path, capsys):
    from mindyn import cli

    _, log = _log(2.0, 1)
    p = write_csv(tmp_path / "log.csv", log.t, log.q, log.tau, dq=log.dq)
    out = tmp_path / "o.json"
    argv = ["identify", "zcr07s", str(p), "--friction", "--filter", "butter", "--json", str(out)]
    assert cli.main(argv) == 0
    text = capsys.readouterr().out
    assert "100 samples (0.2 s) dropped at each end, where the derivatives' filter starts" in text
    assert f"{log.t.size - 200} samples at 500 Hz" in text
