"""The pruning decided on held-out data (``rsd_threshold="auto"``).

Reference: logs the test makes from known base parameters (torques ``W_b(q, dq, ddq) theta``
plus white noise of unit variance, exact velocities and accelerations): half of the base
parameters are well determined (30 of their standard deviations), the other half either zero
(pruning them is right) or 2.5 of their standard deviations (pruning them leaves out torque that
is there), fitted by the dynamic and the integral model. Which candidate predicts better is
checked on the noise-free torques of another motion, not against mindyn's own output; the
held-out residual of the fit with every base parameter is checked against numpy's least squares
on the blocks."""

from __future__ import annotations

import json

import mindyn
import numpy as np
import pytest
from mindyn import cli
from mindyn.identification import identify
from mindyn.identification.data import JointData, write_csv
from mindyn.identification.excitation import random_trajectory
from mindyn.identification.held_out import held_out_residuals
from mindyn.identification.workflow import run

RATE = 100.0


@pytest.fixture(scope="module")
def zcr():
    robot = mindyn.load("zcr07s")
    return robot, mindyn.base_parameters(robot, rotor=True, friction=True)


def _motion(robot, seed: int, seconds: float):
    t = np.arange(0.0, seconds, 1.0 / RATE)
    return (t, *random_trajectory(robot, seed=seed, freq=0.1).evaluate(t))


def _case(robot, base, small: float, seed: int = 0):
    """A 10 s log of known base parameters ``theta``: 70 % of them ``small`` standard deviations
    (of this log's least squares with unit noise) from zero, the rest 30; and the noise-free
    torques of another motion."""
    rng = np.random.default_rng(seed)
    t, q, dq, ddq = _motion(robot, seed, 10.0)
    W = base.regressor(q, dq, ddq)
    A = W.reshape(-1, base.n)
    s = np.sqrt(np.diag(np.linalg.inv(A.T @ A)))
    size = np.full(base.n, 30.0)
    size[rng.permutation(base.n)[: int(0.7 * base.n)]] = small
    theta = size * s * rng.choice([-1.0, 1.0], base.n)
    tau = W @ theta + rng.standard_normal((t.size, robot.n))
    tv, qv, dqv, ddqv = _motion(robot, 100 + seed, 10.0)
    other = (base.regressor(qv, dqv, ddqv), base.regressor(qv, dqv, ddqv) @ theta)
    return JointData(t, q, dq, ddq, tau, "fit"), other


def _error(full, other) -> float:
    Wv, tau = other
    return float(np.linalg.norm(Wv @ full - tau) / np.linalg.norm(tau))


#: The models' options for a 10 s log at 100 Hz (integral: windows of 8 intervals).
MODELS = {"dynamic": {}, "integral": {"model": "integral", "integral_window": 8}}


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize(
    "small, pruned", [(0.0, True), (2.5, False)], ids=["zero: prune", "2.5 sd: keep all"]
)
def test_auto_pruning_follows_the_held_out_data_both_ways(zcr, small, pruned, model):
    robot, base = zcr
    data, other = _case(robot, base, small)
    fit = MODELS[model]
    rep = run(robot, [data], rotor=True, friction=True, rsd_threshold="auto", **fit)
    assert rep.base.names == base.names
    res = rep.result
    choice = res.settings["pruning_choice"]
    assert choice["chosen_by"] == "held-out data"
    assert choice["rsd_threshold"] == (70.7 if pruned else None)
    assert bool(res.removed) == pruned
    # the JSON records both candidates on the same blocks, and the rule's figures
    doc = rep.to_dict()["settings"]["pruning_choice"]
    scores = {c["rsd_threshold"]: c for c in doc["candidates"]}
    assert set(scores) == {70.7, None} and scores[None]["removed"] == 0
    assert scores[70.7]["removed"] > 5
    for c in scores.values():
        assert len(c["per_fold"]) == 5
        assert c["held_out"] == pytest.approx(sum(c["per_fold"]), rel=1e-12)
    excess = scores[70.7]["held_out"] - scores[None]["held_out"]
    se = max(c["standard_error"] for c in scores.values())
    assert (excess > se) != pruned  # keep all only when better by more than one error
    # against the truth: the candidate chosen predicts another motion better than the other
    other_threshold = None if pruned else 70.7
    rest = identify(robot, data, base=base, rsd_threshold=other_threshold, **fit)
    assert _error(res.full, other) < _error(rest.full, other)
    # the output states the decision in one line, naming the option
    text = rep.format()
    said = [line for line in text.splitlines() if "chosen on held-out data" in line]
    assert len(said) == 1 and "rsd_threshold=" in said[0]
    assert ("every base parameter kept" in said[0]) != pruned


def test_a_given_threshold_is_honoured_and_nothing_is_scored(zcr, monkeypatch):
    import mindyn.identification.held_out as held_out

    robot, base = zcr
    data, _ = _case(robot, base, 2.5)

    def refuse(*args, **kwargs):
        raise AssertionError("a given threshold is not decided on held-out data")

    monkeypatch.setattr(held_out, "held_out_residuals", refuse)
    rep = run(robot, [data], rotor=True, friction=True, rsd_threshold=70.7)
    direct = identify(robot, data, base=base)
    assert rep.result.removed and [n for n, _ in rep.result.removed] == [
        n for n, _ in direct.removed
    ]
    np.testing.assert_allclose(rep.result.full, direct.full, rtol=1e-12, atol=0)
    assert "pruning_choice" not in rep.result.settings
    assert "chosen on held-out data" not in rep.format()


def test_held_out_residual_of_every_parameter_is_least_squares_on_the_other_blocks(zcr):
    robot, base = zcr
    data, _ = _case(robot, base, 2.5)
    res = identify(robot, data, base=base, weighted=False, min_velocity=0.0)
    (total, per_fold), _ = held_out_residuals(res, [data], folds=5, thresholds=[None, 70.7])
    W = base.regressor(data.q, data.dq, data.ddq)
    block = (np.arange(data.m) * 5) // data.m  # contiguous fifths of the samples
    rows = data.m * robot.n
    for k in range(5):
        fit, out = block != k, block == k
        p, *_ = np.linalg.lstsq(W[fit].reshape(-1, base.n), data.tau[fit].ravel(), rcond=None)
        r = W[out].reshape(-1, base.n) @ p - data.tau[out].ravel()
        assert per_fold[k] == pytest.approx(r @ r / rows, rel=1e-8)
    assert total == pytest.approx(sum(per_fold), rel=1e-12)


def test_cli_rsd_threshold_auto_prints_and_records_the_choice(zcr, tmp_path, capsys):
    robot, base = zcr
    data, _ = _case(robot, base, 0.0)
    log = write_csv(tmp_path / "fit.csv", data.t, data.q, data.tau, data.dq, data.ddq)
    js = tmp_path / "out.json"
    argv = ["identify", "zcr07s", str(log), "--rotor", "--friction", "--filter", "none"]
    assert cli.main([*argv, "--rsd-threshold", "auto", "--json", str(js)]) == 0
    out = capsys.readouterr().out
    said = [line for line in out.splitlines() if "chosen on held-out data" in line]
    assert len(said) == 1 and "--rsd-threshold sets it" in said[0]
    choice = json.loads(js.read_text())["settings"]["pruning_choice"]
    assert choice["chosen_by"] == "held-out data" and len(choice["candidates"]) == 2
    # a value that is neither a number nor auto is one line naming the option
    assert cli.main([*argv, "--rsd-threshold", "sometimes"]) != 0
    err = capsys.readouterr().err.strip()
    assert "--rsd-threshold" in err and "auto" in err and "\n" not in err


def test_options_refuse_a_threshold_word_other_than_auto():
    from mindyn.identification.options import IdentifyOptions

    with pytest.raises(mindyn.Error, match="rsd_threshold .*'auto'"):
        IdentifyOptions(rsd_threshold="sometimes")
    assert IdentifyOptions(rsd_threshold="auto").rsd_threshold == "auto"


def test_the_consistent_estimate_does_not_depend_on_the_pruning(zcr):
    # it starts from the least-squares problem of every base parameter, whatever was pruned
    from mindyn.identification.consistent import consistent_estimate

    robot, base = zcr
    data, _ = _case(robot, base, 2.5)
    pruned = identify(robot, data, base=base)
    kept = identify(robot, data, base=base, rsd_threshold=None)
    assert pruned.removed and not kept.removed
    a = consistent_estimate(pruned, prior_weight=0.0)
    b = consistent_estimate(kept, prior_weight=0.0)
    np.testing.assert_allclose(a.classical, b.classical, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("model", ["dynamic", "integral", "energy"])
def test_repruning_the_fit_equals_fitting_again_at_that_threshold(zcr, model):
    """The held-out choice that keeps every parameter re-prunes the fit it has instead of
    forming the least-squares problem again: the result equals identify's at that threshold
    (every field, every digit), for the three models."""
    from mindyn.identification.estimation import repruned

    robot, base = zcr
    data, _ = _case(robot, base, 2.5)
    opts = dict(base=base, model=model, integral_window=10, energy_window=4)
    first = identify(robot, data, rsd_threshold=70.7, **opts)
    for threshold in (None, 30.0):
        again = identify(robot, data, rsd_threshold=threshold, **opts).to_dict()
        got = repruned(first, threshold).to_dict()
        again.pop("seconds"), got.pop("seconds")
        assert json.dumps(got, sort_keys=True) == json.dumps(again, sort_keys=True), threshold
