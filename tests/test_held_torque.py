"""A torque held over each sample period (``--torque held``, ``ReadingOptions(torque="held")``).

A digital controller holds its command over the period that follows its sample, and
``mindyn simulate``'s tracking mode logs it so: taken at its own sample, such a torque lags the
motion by half a period. The tests check the reading against a closed form and the dynamic
model's estimate against the parameters of a simulation the test runs itself."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import cli_run, one_line_error
from mindyn import ArgumentError
from mindyn.identification.data import held_torque_at_samples
from mindyn.identification.options import ReadingOptions


def test_a_held_linear_torque_is_read_exactly_at_unevenly_spaced_samples():
    """Each held value is a linear torque c(t) at the middle of its period: at the samples the
    reading gives c(t_k) itself (the first sample extrapolated, the last period as long as the
    one before)."""
    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(0.002, 0.006, 40))
    a, b = np.array([1.5, -0.3]), np.array([20.0, 7.0])

    def c(x):
        return a + np.outer(x, b)

    dt = np.append(np.diff(t), t[-1] - t[-2])
    held = c(t + dt / 2)
    np.testing.assert_allclose(held_torque_at_samples(t, held), c(t), rtol=0, atol=1e-12)


def test_the_reading_is_a_keyword_with_two_values():
    assert ReadingOptions().torque == "sampled"
    assert ReadingOptions(torque="held").torque == "held"
    with pytest.raises(ArgumentError, match="torque is a str 'smooth'; expected one of"):
        ReadingOptions(torque="smooth")


@pytest.fixture(scope="module")
def tracking_log(tmp_path_factory):
    """planar3 under the default computed-torque loop for 6 s at 250 Hz, no noise: the logged
    torque is the command held over each period."""
    path = tmp_path_factory.mktemp("held") / "track.csv"
    rc, _, err = cli_run(["simulate", "planar3", "--duration", "6", "-o", path])
    assert rc == 0, err
    return path


def _errors(path, *options):
    out = path.with_name(f"id{len(options)}.json")
    rc, text, err = cli_run(
        ["identify", "planar3", path, "--rsd-threshold", "0", "--json", out, *options]
    )
    assert rc == 0, err
    doc = json.loads(out.read_text())
    true = np.array(doc["true_values"])
    big = np.abs(true) > 0.1  # the inertias and first moments; the zero ones have no scale
    return np.abs(np.array(doc["values"]) - true)[big] / np.abs(true[big]), doc, text


def test_the_dynamic_model_fits_a_held_command_when_told_so(tracking_log):
    held, doc, text = _errors(tracking_log, "--torque", "held")
    sampled, _, _ = _errors(tracking_log)
    # taken at its samples, the half period's lag biases the inertias by about 2 %
    assert sampled.max() > 5e-3
    # taken as held, the estimate is the simulation's to the data path's accuracy
    assert held.max() < 5e-4
    assert doc["reading"]["torque"] == "held"
    assert "(--torque held)" in text


def test_torque_held_is_refused_with_a_window_model(tracking_log):
    rc, _, err = cli_run(
        ["identify", "planar3", tracking_log, "--model", "energy", "--torque", "held"]
    )
    one_line_error(rc, err, "--torque held applies only to the dynamic model", "--integration zoh")


def _max_residual(text: str) -> float:
    lines = text.split("residual |r| per joint")[1].splitlines()[1:4]
    return max(float(line.split(":")[1].split("/")[0]) for line in lines)


def test_detect_takes_the_torque_as_the_identification_read_it(tracking_log, tmp_path):
    """On the noise-free tracking log, with the model fitted to it as held, the observer's
    residual is near zero when it integrates the held command and not when it takes the torque
    as sampled (a half period's lag of the whole torque): by default detect takes the reading
    the JSON records."""
    ident = tmp_path / "held.json"
    rc, _, err = cli_run(
        ["identify", "planar3", tracking_log, "--torque", "held", "--rsd-threshold", "0"]
        + ["--json", ident]
    )
    assert rc == 0, err
    runs = {}
    for name, extra in (
        ("default", []),
        ("held", ["--torque", "held"]),
        ("sampled", ["--torque", "sampled"]),
    ):
        rc, out, err = cli_run(["detect", "planar3", ident, tracking_log, *extra])
        assert rc == 0, err
        runs[name] = out
    assert "torque held over each step, as" in runs["default"]
    assert _max_residual(runs["default"]) == _max_residual(runs["held"])
    assert _max_residual(runs["held"]) < 0.01 * _max_residual(runs["sampled"])
