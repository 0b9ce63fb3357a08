"""What the pruning does to the kept estimates' standard deviations.

Reference: the true parameters of logs the test simulates (exact accelerations and torque noise
of a known level, so that the only bias is the pruning's): the kept estimates' errors against
the true base values, in units of the standard deviations reported."""

from __future__ import annotations

import sys
from pathlib import Path

import mindyn
import numpy as np
import pytest
from mindyn.cli.flags import library_options_as_flags
from mindyn.control import SensorNoise, simulate_inverse
from mindyn.identification import identify
from mindyn.identification.excitation import random_trajectory
from mindyn.identification.report import format_table

sys.path.insert(0, str(Path(__file__).parent))
from test_identification import as_data, truth_of  # noqa: E402


def _fit(duration: float, seed: int):
    robot = mindyn.load("zcr07s")
    traj = random_trajectory(robot, seed=seed, freq=0.1)
    log = simulate_inverse(
        robot,
        traj,
        rate=500.0,
        duration=duration,
        friction=True,
        seed=seed,
        noise=SensorNoise(torque=0.01),
    )
    res = identify(robot, as_data(log, logged_ddq=True), friction=True)
    truth = truth_of(res.base, log)
    kept = [res.base.names.index(n) for n in res.names]
    return res, res.values - truth[kept], np.asarray(res.initial["std"])[kept]


@pytest.mark.parametrize("seed", [0, 1])
def test_a_short_log_warns_that_pruning_understates_the_standard_deviations(seed):
    # a tenth of the trajectory's period: the kept estimates take up the removed parameters'
    # contributions, many standard deviations (after pruning) away from their base parameters
    res, err, std_all = _fit(1.0, seed)
    assert res.removed
    kept = [res.base.names.index(n) for n in res.names]
    inflation = res.settings["std_correlation"]["variance_factor"]
    _, pruned, _ = res.reduced.solve(kept, inflation=inflation)  # removed parameters zero
    z = np.abs(err) / pruned
    assert np.mean(z > 3) > 0.3, "the case no longer shows the pruning's bias"
    # the fit with all base parameters gives the same estimates a spread that covers the error
    assert np.mean(np.abs(err) / std_all <= 3) >= 0.95
    rec = res.settings["pruning_std"]
    assert rec["warn"] and rec["median"] > 3
    np.testing.assert_allclose(rec["median"], np.median(std_all / pruned), rtol=1e-12)
    # so the fit reports the larger of the two, which covers the error
    np.testing.assert_allclose(res.std, np.maximum(pruned, std_all), rtol=1e-12)
    assert rec["widened"] and np.mean(np.abs(err) / res.std <= 3) >= 0.95
    assert any(
        "smaller (median) than the fit with all base parameters" in w
        for w in res.settings["warnings"]
    )
    # the command line names its flag
    warning = next(w for w in res.settings["warnings"] if "smaller (median)" in w)
    assert "--rsd-threshold 0" in library_options_as_flags(warning)
    listed = {n for n, _ in rec["largest"]}
    worst = res.names[int(np.argmax(std_all / pruned))]
    assert worst in listed
    table = format_table(res)
    assert "std with the removed parameters free" in table


def test_a_log_of_half_the_period_does_not_warn():
    res, err, std_all = _fit(5.0, 0)
    assert res.removed
    assert np.mean(np.abs(err) / res.std <= 3) >= 0.95
    rec = res.settings["pruning_std"]
    assert not rec["warn"] and rec["median"] < 2
    assert "warnings" not in res.settings


def test_the_json_carries_the_standard_deviations_before_pruning():
    res, _, _ = _fit(5.0, 1)
    d = res.to_dict()
    assert len(d["initial"]["std"]) == res.base.n
    kept = [res.base.names.index(n) for n in res.names]
    # the pruned standard deviations are at most the full fit's (cov_all = cov_pruned + A C A^T)
    assert np.all(np.asarray(d["initial"]["std"])[kept] >= res.std * (1 - 1e-9))
