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
    assert ReadingOptions().torque == "sampled"  # load_logs: per log, see below
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
    sampled, sdoc, _ = _errors(tracking_log, "--torque", "sampled")
    # taken at its samples, the half period's lag biases the inertias by about 2 %
    assert sampled.max() > 5e-3
    # taken as held, the estimate is the simulation's to the data path's accuracy
    assert held.max() < 5e-4
    assert doc["reading"]["torque"] == "held"
    assert sdoc["reading"]["torque"] == "sampled"
    assert "(--torque held)" in text
    _, _, stext = _errors(tracking_log, "--torque", "sampled")
    assert "torques: taken at their samples (--torque sampled given; " in stext  # overrides


def test_a_simulated_tracking_log_is_read_as_held_by_default(tracking_log):
    """Its truth sidecar says the simulation held the command: without --torque the dynamic
    model reads it so, and says why."""
    default, doc, text = _errors(tracking_log)
    assert default.max() < 5e-4
    assert doc["reading"]["torque"] == "held"
    sidecar = tracking_log.with_name("track.truth.json")
    assert json.loads(sidecar.read_text())["simulation"]["torque"] == "held"
    assert f"(--torque held, as {sidecar} says: simulated with the command held" in text
    assert "(read as held:" in doc["fit"]["raw"]["against"]  # the measure says what it scores


def _inverse_log(tmp_path, name="inverse.csv"):
    path = tmp_path / name
    rc, _, err = cli_run(
        ["simulate", "planar3", "--mode", "inverse", "--duration", "6", "-o", path]
    )
    assert rc == 0, err
    return path


def test_logs_whose_sidecar_says_sampled_or_have_none_are_read_as_sampled(tmp_path):
    """Inverse dynamics at the samples (its sidecar says sampled) fits exactly as sampled and
    is read so by default; the same log without a sidecar, a measured log, too. Read as held
    it would be biased: the default is not held for them."""
    from mindyn.identification.reading import simulated_held, simulated_torque

    inv = _inverse_log(tmp_path)
    assert simulated_torque(inv) == "sampled"
    default, doc, text = _errors(inv)
    assert doc["reading"]["torque"] == "sampled"
    assert "torques: the command held" not in text
    assert f"torques: taken at their samples (as {inv.with_name('inverse.truth.json')} says" in text
    assert "read as held" not in doc["fit"]["raw"]["against"]
    assert default.max() < 5e-4
    held, _, _ = _errors(inv, "--torque", "held")
    assert held.max() > 5e-3
    bare = tmp_path / "bare.csv"
    bare.write_bytes(inv.read_bytes())
    assert simulated_torque(bare) is None and simulated_held([bare]) == [None]


def test_a_sidecar_written_before_the_torque_key_says_held_by_its_mode(tracking_log, tmp_path):
    from mindyn.identification.reading import simulated_torque

    log = tmp_path / "old.csv"
    log.write_bytes(tracking_log.read_bytes())
    doc = json.loads(tracking_log.with_name("track.truth.json").read_text())
    del doc["simulation"]["torque"]
    log.with_name("old.truth.json").write_text(json.dumps(doc))
    assert simulated_torque(log) == "held"
    doc["simulation"]["mode"] = "inverse"
    log.with_name("old.truth.json").write_text(json.dumps(doc))
    assert simulated_torque(log) == "sampled"


def test_each_log_is_read_as_its_own_sidecar_says(tracking_log, tmp_path):
    """A held fit log and a sampled validation log: each read as its simulation logged it (the
    held one's torques are the interpolation between the middles of the periods), and the
    JSON records sampled, as not every log was held."""
    from mindyn.identification.data import read_csv
    from mindyn.identification.reading import load_logs

    inv = _inverse_log(tmp_path)
    logs = load_logs([tracking_log], "planar3", validate=[inv], filter="none")
    fit, val = logs.fit.logs[0], logs.validation.logs[0]
    assert "held_because" in fit.processing["torque"]
    assert "held" not in val.processing["torque"]
    raw, vraw = read_csv(tracking_log, filter="none"), read_csv(inv, filter="none")
    k, kv = np.searchsorted(raw.t, fit.t), np.searchsorted(vraw.t, val.t)  # edges dropped
    held = held_torque_at_samples(raw.t, raw.tau)[k]
    np.testing.assert_allclose(fit.tau, held, rtol=0, atol=1e-12)
    assert np.abs(raw.tau[k] - held).max() > 1e-3  # (held differs from sampled here)
    np.testing.assert_array_equal(val.tau, vraw.tau[kv])
    assert logs.record["torque"] == "sampled"
    both = load_logs([tracking_log], "planar3", filter="none")
    assert both.record["torque"] == "held"


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


def test_detect_takes_the_torque_as_the_logs_sidecar_says(tracking_log, tmp_path):
    """An identification that read its log as sampled, and a log whose sidecar says its
    simulation held the torque: by default detect integrates the held command, as the log's
    own sidecar says."""
    ident = tmp_path / "sampled.json"
    rc, _, err = cli_run(
        ["identify", "planar3", tracking_log, "--torque", "sampled", "--json", ident]
    )
    assert rc == 0, err
    assert json.loads(ident.read_text())["reading"]["torque"] == "sampled"
    rc, out, err = cli_run(["detect", "planar3", ident, tracking_log])
    assert rc == 0, err
    assert f"torque held over each step, as {tracking_log.with_name('track.truth.json')}" in out


def test_run_refuses_a_window_model_on_logs_read_as_held(tracking_log):
    """Logs read for the dynamic model with their torque as held (interpolated to the samples)
    are not what the window models integrate by integration='zoh': run says how to read them."""
    from mindyn.identification import load_logs, run
    from mindyn.identification.errors import IdentificationError

    logs = load_logs([tracking_log], "planar3", filter="butter")
    with pytest.raises(IdentificationError, match=r"read the logs with load_logs\(\.\.\., model"):
        run("planar3", logs, model="integral", integration="zoh")
    windows = load_logs([tracking_log], "planar3", filter="butter", model="integral")
    assert "held" not in windows.fit.logs[0].processing["torque"]
    assert run("planar3", windows, model="integral", integration="zoh").result is not None
