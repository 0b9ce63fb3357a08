"""The identification data path (mindyn.identification.preprocess) on logs generated here with
known answers: analytic Fourier motions sampled at jittered times, noisy velocities and
torques, several periods."""

from __future__ import annotations

import json

import mindyn
import numpy as np
import pytest
from mindyn import cli
from mindyn.identification import (
    JointData,
    dynamic_system,
    identify,
    true_base_values,
    validate,
    write_csv,
)
from mindyn.identification.data import DataError, fill_derivatives
from mindyn.identification.excitation import FourierTrajectory, random_trajectory
from mindyn.identification.preprocess import (
    concatenate,
    excited_band,
    preprocess,
    split_at_gaps,
    timing,
)

RATE = 500.0


def jittered_times(duration, rate=RATE, seed=0, gaps=(), jitter=0.3):
    """Sample times: intervals 1/rate x U(1 - jitter, 1 + jitter), plus ``gaps`` (index, factor):
    interval ``index`` made ``factor`` median intervals long."""
    rng = np.random.default_rng(seed)
    m = int(duration * rate)
    dt = np.full(m - 1, 1.0 / rate) * rng.uniform(1 - jitter, 1 + jitter, m - 1)
    for k, f in gaps:
        dt[k] = f / rate
    return np.concatenate([[0.0], np.cumsum(dt)])


def sine_log(t, freqs, amps, vel_noise=0.0, tau_noise=0.0, seed=1):
    """One joint per frequency: q = a sin(2 pi f t); torque = q (any signal in the band)."""
    rng = np.random.default_rng(seed)
    w = 2 * np.pi * np.asarray(freqs)
    a = np.asarray(amps)
    q = a * np.sin(np.outer(t, w))
    dq = a * w * np.cos(np.outer(t, w)) + vel_noise * rng.standard_normal(q.shape)
    tau = q + tau_noise * rng.standard_normal(q.shape)
    return JointData(t, q, dq, np.zeros_like(q), tau, source="sine")


def test_timing_reports_the_jitter_and_gaps_of_known_stamps():
    # 1 ms intervals with two gaps of exactly 5 ms and 3 ms: jitter 4 (400 % of the median)
    t = jittered_times(2.0, rate=1000.0, jitter=0.0, gaps=((100, 5.0), (700, 3.0)))
    info = timing(t)
    assert info["median_dt_s"] == pytest.approx(1e-3, rel=1e-9)
    assert info["jitter"] == pytest.approx(4.0, rel=1e-6)
    assert info["max_dt_s"] == pytest.approx(5e-3, rel=1e-9)
    assert info["gaps"] == 2


def test_derivatives_on_jittered_stamps_match_the_analytic_motion():
    """A 3-harmonic Fourier motion sampled with +-30 % jitter and gaps, logged velocity with
    noise 0.05 rad/s: the filtered velocity and the acceleration follow the analytic ones."""
    traj = FourierTrajectory(
        a=[[0.5, -0.3, 0.2], [0.2, 0.4, -0.1]],
        b=[[0.1, 0.2, -0.2], [-0.3, 0.1, 0.25]],
        q0=[0.1, -0.2],
        freq=0.25,
    )
    t = jittered_times(16.0, gaps=((1000, 6.0), (3000, 4.0)))
    q, dq, ddq = traj.evaluate(t)
    rng = np.random.default_rng(2)
    dq_meas = dq + 0.05 * rng.standard_normal(dq.shape)
    d = preprocess(JointData(t, q, dq_meas, np.zeros_like(q), q.copy(), source="fourier"))
    p = d.processing["preprocess"]
    assert "resampled" in p["time_base"]
    # the excited band is the third harmonic (0.75 Hz), within a few bins of the 16 s log
    assert 0.75 <= p["excited_band_Hz"] <= 0.75 + 4 / 16
    assert p["filter"]["cutoff_Hz"] == pytest.approx(10 * p["excited_band_Hz"])
    q_ref, dq_ref, ddq_ref = traj.evaluate(d.t)
    scale = np.abs(dq_ref).max(axis=0)
    # Noise left in the pass band: sd 0.05 x sqrt(2 fc / rate) ~ 0.012 rad/s; ends dropped, so
    # no edge transient: 5 % of the peak velocity is a margin of about 2.5 on the noise.
    assert np.max(np.abs(d.dq - dq_ref) / scale) < 0.05
    np.testing.assert_allclose(d.q, q_ref, atol=1e-4)  # spline of noise-free positions
    # acceleration from the filtered velocity: white noise of sd s band-limited to fc has
    # sd s sqrt(2 fc / rate) and its derivative that times 2 pi fc / sqrt(3); 1.5 x that bound
    fc = p["filter"]["cutoff_Hz"]
    rate = 1 / p["timing"]["median_dt_s"]
    bound = 0.05 * np.sqrt(2 * fc / rate) * 2 * np.pi * fc / np.sqrt(3)
    assert np.sqrt(np.mean((d.ddq - ddq_ref) ** 2)) < 1.5 * bound
    # without any filtering the acceleration of the noisy velocity is far off (the test can fail)
    raw = np.gradient(dq_meas, t, axis=0)
    assert np.max(np.abs(raw - ddq)) > 10 * np.max(np.abs(d.ddq - ddq_ref))


def test_cutoff_from_known_harmonics_and_given_cutoff():
    t = np.arange(0, 20.0, 1 / RATE)
    d = preprocess(sine_log(t, [0.2, 0.5], [1.0, 0.3]))
    p = d.processing["preprocess"]
    assert 0.5 <= p["excited_band_Hz"] <= 0.5 + 3 / 20  # highest frequency, a few bins of 20 s
    assert p["time_base"] == "uniform as logged"
    d2 = preprocess(sine_log(t, [0.2, 0.5], [1.0, 0.3]), cutoff=3.0)
    assert d2.processing["preprocess"]["filter"]["cutoff_Hz"] == 3.0
    assert d2.processing["preprocess"]["cutoff_source"] == "given"
    # excited_band alone: one 2 Hz sine over whole periods
    tt = np.arange(0, 5.0, 1e-3)
    assert excited_band(np.sin(2 * np.pi * 2.0 * tt)[:, None], 1e-3) == pytest.approx(2.0, abs=0.6)


def test_edges_dropped_and_decimation():
    t = np.arange(0, 10.0, 1 / RATE)
    d = preprocess(sine_log(t, [0.3], [1.0]), cutoff=5.0, edge=0.2, decimate=False)
    p = d.processing["preprocess"]
    assert p["edge_samples_dropped"] == 2 * 100  # 0.2 s at 500 Hz at each end
    assert d.t[0] == pytest.approx(0.2) and d.t[-1] == pytest.approx(t[-1] - 0.2)
    assert d.m == t.size - 200
    dd = preprocess(sine_log(t, [0.3], [1.0]), cutoff=5.0)
    pd = dd.processing["preprocess"]
    assert pd["edge_s"] == pytest.approx(2 / 5.0)  # default edge: two periods of the cut-off
    assert pd["decimation"] == 10  # 500 Hz down to 10 x 5 Hz
    assert np.allclose(np.diff(dd.t), 10 / RATE)


def test_filter_removes_torque_noise_and_keeps_the_signal():
    """Torque = a 0.4 Hz sine plus white noise 0.2: after the low-pass the error to the
    noise-free sine is close to the in-band noise sd 0.2 sqrt(2 fc / rate)."""
    t = np.arange(0, 20.0, 1 / RATE)
    d = preprocess(sine_log(t, [0.4], [1.0], tau_noise=0.2, seed=5), decimate=False)
    fc = d.processing["preprocess"]["filter"]["cutoff_Hz"]
    err = np.sqrt(np.mean((d.tau[:, 0] - np.sin(2 * np.pi * 0.4 * d.t)) ** 2))
    expect = 0.2 * np.sqrt(2 * fc / RATE)
    assert 0.5 * expect < err < 2.0 * expect


def test_period_averaging_of_a_periodic_log():
    """Four periods of 2.5 s with torque noise sd 0.1: four periods are averaged, the spread
    about the mean is the noise sd x sqrt(3/4), and the averaged, filtered period is the
    noise-free torque within the noise of the mean."""
    T, sd = 2.5, 0.1
    # uniform stamps: interpolating jittered ones would average the noise and shrink the spread
    t = np.arange(int(4 * T * RATE)) / RATE
    log = sine_log(t, [1 / T, 2 / T], [1.0, 0.5], tau_noise=sd, seed=4)
    for kw in ({"periods": 4}, {"period": T}):
        d = preprocess(log, **kw, decimate=False)
        avg = d.processing["preprocess"]["averaging"]
        assert avg["periods"] == 4 and avg["period_s"] == pytest.approx(T, rel=1e-3)
        assert d.processing["preprocess"]["edge_samples_dropped"] == 0  # periodic: no edges
        spread = np.array(avg["torque_spread_rms"])
        np.testing.assert_allclose(spread, sd * np.sqrt(3 / 4), rtol=0.1)  # 1250 x 4 samples
        q_true = np.column_stack([np.sin(2 * np.pi / T * d.t), 0.5 * np.sin(4 * np.pi / T * d.t)])
        err = np.sqrt(np.mean((d.tau - q_true) ** 2))
        assert err < sd / 2 * 0.5  # mean of 4: sd / 2, then the low-pass takes most of it
    with pytest.raises(DataError, match="shorter than the period"):
        preprocess(log, period=20.0)
    with pytest.raises(DataError, match="not both"):
        preprocess(log, periods=2, period=T)


def _friction_log(robot, t, seed=0, vel_noise=0.0, tau_noise=0.0):
    """Inverse dynamics along a random Fourier motion at times ``t`` plus viscous and Coulomb
    friction computed here, with noise; returns the log and the true base values."""
    traj = random_trajectory(robot, harmonics=5, freq=0.1, seed=seed)
    q, dq, ddq = traj.evaluate(t)
    p = robot.parameters(rotor=True, friction=True).reshape(robot.n, 13).copy()
    p[:, 10] = 0.0
    fv, fc = 0.5 + 0.1 * np.arange(robot.n), 1.0 + 0.2 * np.arange(robot.n)
    p[:, 11], p[:, 12] = 0.0, 0.0
    tau = robot.inverse_dynamics(q, dq, ddq, p.reshape(-1)) + fv * dq + fc * np.sign(dq)
    p[:, 11], p[:, 12] = fv, fc
    rng = np.random.default_rng(seed + 100)
    dqm = dq + vel_noise * rng.standard_normal(dq.shape)
    taum = tau + tau_noise * rng.standard_normal(tau.shape)
    log = JointData(t, q, dqm, np.zeros_like(q), taum, source=f"sim{seed}")
    names = robot.parameter_names(rotor=True, friction=True)
    return log, {"names": names, "values": p.reshape(-1)}, tau, traj


def test_parallel_filtering_is_exact_on_noise_free_data_with_coulomb_friction():
    """Filtering the torques but not the regressor breaks tau_f = W p at every Coulomb sign
    change; filtering both alike keeps it exact: the true parameters come back to rounding."""
    robot = mindyn.load("zcr07s")
    base = mindyn.base_parameters(robot, friction=True)
    log, truth, _, _ = _friction_log(robot, np.arange(0, 10.0, 1 / 250.0))
    true = true_base_values(base, truth)
    kw = dict(base=base, rsd_threshold=None, min_velocity=0, weighted=False)
    # 5 periods of the cut-off dropped at each end: the start-up of the filter on the Coulomb
    # steps decays to 3e-5 N m there (measured: 0.15 N m after 1 period, 1e-3 after 3)
    d = preprocess(log, cutoff=5.0, edge=1.0)
    res = identify(robot, d, **kw)
    big = np.abs(true) > 1e-3 * np.abs(true).max()
    err = np.max(np.abs(res.full - true)[big] / np.abs(true)[big])
    # what is left is the 3e-5 N m of edge and the central differences (1e-5 relative at the
    # fifth harmonic), magnified by the weakest excited parameters; 1e-3 is 4 x the measured
    assert err < 1e-3
    plain = preprocess(log, cutoff=5.0, edge=1.0, parallel=False)
    res2 = identify(robot, plain, **kw)
    err2 = np.max(np.abs(res2.full - true)[big] / np.abs(true)[big])
    assert err2 > 10 * err


def test_data_path_recovers_the_parameters_from_noisy_jittered_logs(tmp_path):
    """zcr07s with viscous and Coulomb friction, 40 s at 500 Hz with +-30 % jitter, velocity
    noise 0.05 rad/s, torque noise 2 % of the peak torque: the identified model predicts the
    noise-free torques of another trajectory within 1 %, and better than the path without the
    low-pass on velocities and torques."""
    robot = mindyn.load("zcr07s")
    base = mindyn.base_parameters(robot, friction=True)
    t = jittered_times(40.0, seed=7)
    log, truth, tau, _ = _friction_log(robot, t, seed=1, vel_noise=0.05)
    sd = 0.02 * np.abs(tau).max(axis=0)
    log.tau = tau + sd * np.random.default_rng(9).standard_normal(tau.shape)
    d = preprocess(log)
    res = identify(robot, d, base=base)
    true = true_base_values(base, truth)
    # validation: an exact, noise-free log of another motion, uniform stamps
    tv = np.arange(0, 10.0, 1 / 250.0)
    vlog, _, vtau, vtraj = _friction_log(robot, tv, seed=2)
    q, dq, ddq = vtraj.evaluate(tv)
    exact = JointData(tv, q, dq, ddq, vtau, source="exact")
    v = validate(res, exact)
    rel = np.linalg.norm(vtau - v["tau_hat"]) / np.linalg.norm(vtau)
    assert rel < 0.01  # measured 0.26 %
    # the old path: logged noisy velocities as they are, accelerations from them by the
    # derivative filter, raw torques on the jittered stamps (measured 2.6 %)
    dq2, ddq2, _ = fill_derivatives(log.t, log.q, log.dq, None)
    old = identify(robot, JointData(log.t, log.q, dq2, ddq2, log.tau), base=base)
    rel_old = np.linalg.norm(vtau - validate(old, exact)["tau_hat"]) / np.linalg.norm(vtau)
    assert rel_old > 3 * rel
    # the true parameters predict the same torques: the estimate is close in what matters
    Wt = base.regressor(q, dq, ddq) @ true
    assert np.linalg.norm(vtau - Wt) / np.linalg.norm(vtau) < 1e-9
    # CLI on the same log: the settings say what the data path did, the validation agrees
    write_csv(tmp_path / "log.csv", log.t, log.q, log.tau, dq=log.dq)
    write_csv(tmp_path / "val.csv", tv, q, vtau, dq=dq)
    out = tmp_path / "r.json"
    rc = cli.main(
        [
            "identify",
            "zcr07s",
            str(tmp_path / "log.csv"),
            "--friction",
            "--validate",
            str(tmp_path / "val.csv"),
            "--json",
            str(out),
        ]
    )
    assert rc == 0
    doc = json.loads(out.read_text())
    pre = doc["settings"]["preprocessing"]
    assert pre["filter"]["cutoff_Hz"] == pytest.approx(
        d.processing["preprocess"]["filter"]["cutoff_Hz"]
    )
    assert pre["timing"]["jitter"] == pytest.approx(timing(t)["jitter"])
    assert pre["parallel_filtering"] is True
    assert max(doc["validation"]["relative"]) < 0.05


def test_concatenate_keeps_each_logs_regressor_filter():
    robot = mindyn.load("zcr07s")
    base = mindyn.base_parameters(robot, friction=True)
    a, truth, _, _ = _friction_log(robot, np.arange(0, 8.0, 1 / 250.0), seed=3)
    b, _, _, _ = _friction_log(robot, np.arange(0, 8.0, 1 / 250.0), seed=4)
    parts = [preprocess(x, cutoff=4.0, edge=1.25) for x in (a, b)]
    d = concatenate(parts)
    assert np.all(np.diff(d.t) > 0) and d.m == parts[0].m + parts[1].m
    true = true_base_values(base, truth)
    # the stacked system holds for the true parameters as each log's does (edges: 5 periods
    # of the cut-off, 3e-5 N m left, see above): 1e-5 of the torques
    W, y, _ = dynamic_system(base, d)
    assert np.linalg.norm(W @ true - y) / np.linalg.norm(y) < 1e-5
    res = identify(robot, d, base=base, rsd_threshold=None, min_velocity=0, weighted=False)
    big = np.abs(true) > 1e-2 * np.abs(true).max()
    assert np.max(np.abs(res.full - true)[big] / np.abs(true)[big]) < 1e-3


def test_window_models_on_joined_logs_equal_the_logs_fitted_together():
    """The integral and energy models' windows do not span the join of two logs (it would
    integrate two unrelated motions): identify on concatenate([a, b]) gives the estimates and
    standard deviations of identify on [a, b], windows, weights and noise estimates alike
    (with the windows across the join, the estimates differed by up to 100 times themselves
    and the energy model's standard deviations were 80 times larger)."""
    robot = mindyn.load("puma560_3")
    base = mindyn.base_parameters(robot, friction=True)
    parts = []
    for seed in (3, 4):
        log, _, tau, _ = _friction_log(robot, np.arange(0, 20.0, 1 / 250.0), seed=seed)
        log.tau = tau + 0.02 * np.abs(tau).max(axis=0) * np.random.default_rng(
            seed
        ).standard_normal(tau.shape)
        parts.append(preprocess(log, cutoff=5.0, decimate=False))
    joined = concatenate(parts)
    for model, integration in (("integral", "simpson"), ("energy", "simpson"), ("energy", "zoh")):
        kw = dict(base=base, model=model, integration=integration, rsd_threshold=None)
        apart, together = identify(robot, parts, **kw), identify(robot, joined, **kw)
        assert together.rows == apart.rows
        np.testing.assert_allclose(together.full, apart.full, rtol=1e-9, atol=0)
        np.testing.assert_allclose(together.std, apart.std, rtol=1e-9, atol=0)
    assert joined.starts == (0, parts[0].m)
    assert concatenate([joined, parts[0]]).starts == (0, parts[0].m, joined.m)


def test_bad_settings_are_named():
    t = np.arange(0, 4.0, 1 / RATE)
    log = sine_log(t, [0.5], [1.0])
    with pytest.raises(DataError, match="cutoff 300 Hz must be between 0 and half the rate"):
        preprocess(log, cutoff=300.0)
    with pytest.raises(DataError, match="dropping 3 s at each end"):
        preprocess(log, cutoff=5.0, edge=3.0)
    with pytest.raises(DataError, match="do not move"):
        preprocess(JointData(t, np.zeros((t.size, 1)), np.zeros((t.size, 1)), None, None))


def test_cli_prints_the_data_path_and_refuses_periods_without_it(tmp_path, capsys):
    t = jittered_times(30.0, rate=250.0, seed=2)
    robot = mindyn.load("zcr07s")
    log, _, _, _ = _friction_log(robot, t, seed=5)
    write_csv(tmp_path / "log.csv", log.t, log.q, log.tau, dq=log.dq)
    rc = cli.main(["identify", "zcr07s", str(tmp_path / "log.csv"), "--friction", "--cutoff", "3"])
    out = capsys.readouterr().out
    assert rc == 0
    assert "cut-off 3 Hz (given" in out and "jitter" in out and "parallel filtering" in out
    assert "edges dropped" in out
    rc = cli.main(
        ["identify", "zcr07s", str(tmp_path / "log.csv"), "--filter", "butter", "--periods", "2"]
    )
    err = capsys.readouterr().err
    assert rc != 0 and "--periods needs --filter lowpass" in err and len(err.splitlines()) == 1


def test_a_break_in_the_log_is_refused_whole_and_fitted_as_segments():
    """Two motions logged in one file with a 2 s break between them (the second resumes
    elsewhere): preprocess refuses to bridge the break; split_at_gaps gives the two motions,
    which go through the data path on their own and identify the parameters as if they had
    been logged apart. Bridged (the break taken as jitter), the estimate is far off."""
    robot = mindyn.load("zcr07s")
    base = mindyn.base_parameters(robot, friction=True)
    a, truth, _, _ = _friction_log(robot, np.arange(0, 8.0, 1 / 250.0), seed=3)
    b, _, _, _ = _friction_log(robot, 10.0 + np.arange(0, 8.0, 1 / 250.0), seed=4)
    whole = JointData(
        np.concatenate([a.t, b.t]),
        *(np.vstack([getattr(a, k), getattr(b, k)]) for k in ("q", "dq", "ddq", "tau")),
        source="one file",
    )
    with pytest.raises(DataError, match=r"one file: a break of 2\.004 s .* after t = 7\.996 s"):
        preprocess(whole, cutoff=4.0)
    segments = split_at_gaps(whole)
    assert [s.m for s in segments] == [a.m, b.m]
    assert segments[1].processing["segment"] == {"index": 1, "of": 2, "t_s": [10.0, b.t[-1]]}
    assert split_at_gaps(a) == [a]
    kw = dict(base=base, rsd_threshold=None, min_velocity=0, weighted=False)
    true = true_base_values(base, truth)
    big = np.abs(true) > 1e-2 * np.abs(true).max()
    parts = [preprocess(s, cutoff=4.0, edge=1.25) for s in segments]
    res = identify(robot, parts, **kw)
    assert np.max(np.abs(res.full - true)[big] / np.abs(true)[big]) < 1e-3
    bridged = identify(robot, preprocess(whole, cutoff=4.0, edge=1.25, gap=np.inf), **kw)
    assert np.max(np.abs(bridged.full - true)[big] / np.abs(true)[big]) > 0.05


def test_window_models_are_exact_on_noise_free_low_passed_data_with_coulomb_friction():
    """The integral and energy models on preprocessed data: their friction columns filtered
    like the torques (the Coulomb step low-passed, not a step at the filtered velocity's sign
    change), the true parameters come back on a noise-free log. Integral model, zcr07s 10 s:
    measured 4e-6 relative (0.35 with the sign of the filtered velocity, parallel=False);
    energy model, puma560_3 40 s (the zcr07s log excites it too little): residual 2.5e-6
    against 2.2e-4, largest relative error 5e-3 against 12."""
    cases = (("zcr07s", 10.0, "integral", 1e-3), ("puma560_3", 40.0, "energy", 0.05))
    for name, duration, model, tol in cases:
        robot = mindyn.load(name)
        base = mindyn.base_parameters(robot, friction=True)
        log, truth, _, _ = _friction_log(robot, np.arange(0, duration, 1 / 250.0))
        true = true_base_values(base, truth)
        big = np.abs(true) > 1e-3 * np.abs(true).max()
        kw = dict(base=base, model=model, rsd_threshold=None, weighted=False)
        err = {}
        for parallel in (True, False):
            d = preprocess(log, cutoff=5.0, edge=1.0, decimate=False, parallel=parallel)
            res = identify(robot, d, **kw)
            err[parallel] = np.max(np.abs(res.full - true)[big] / np.abs(true)[big])
        print(f"\n{model}: largest relative error {err[True]:.2g} ({err[False]:.2g} unfiltered)")
        assert err[True] < tol, (model, err)
        assert err[False] > 10 * err[True], (model, err)


@pytest.mark.parametrize(
    "chunk, budget",
    [(173, 0), (173, 8 * 173 * 100 * 4), (173, 2**28), (100000, 2**28)],
)
def test_block_parallel_filter_equals_scipys_zero_phase_filter_of_the_whole_regressor(
    monkeypatch, chunk, budget
):
    from mindyn.identification import preprocess as P
    from scipy import signal

    robot = mindyn.load("zcr07s")
    base = mindyn.base_parameters(robot, friction=True)
    log, _, _, _ = _friction_log(robot, np.arange(0, 8.0, 1 / 250.0), seed=3)
    d = preprocess(log, cutoff=4.0)
    f = d.regressor_filter
    assert f.sos is not None and 0 < f.padlen < f.q.shape[0]
    monkeypatch.setattr(P, "_CHUNK", chunk)  # many blocks, or one
    monkeypatch.setattr(P, "KEEP_BUDGET", budget)  # none, a few or all blocks kept
    got = f.regressor(base)
    whole = base.regressor(f.q, f.dq, f.ddq)
    want = signal.sosfiltfilt(f.sos, whole, axis=0, padlen=f.padlen)[f.keep]
    assert got.shape == want.shape == (d.m, robot.n, base.n)
    np.testing.assert_array_equal(got, want)


def test_filtered_signals_of_one_log_and_of_joined_logs_equal_scipys_zero_phase_filter():
    """``regressor_filter.signals(fn)``: the columns ``fn`` of the full-rate filtered motion
    (here the Coulomb signs, a step at each reversal) through scipy's sosfiltfilt, edge-dropped
    like the torques; of concatenated logs, each log's filtered on its own and stacked."""
    from scipy import signal

    robot = mindyn.load("puma560_3")

    def signs(q, dq, ddq):
        return np.sign(dq)

    logs = []
    for seed in (1, 2):
        log, _, _, _ = _friction_log(robot, np.arange(0, 6.0, 1 / 250.0), seed=seed)
        d = preprocess(log, cutoff=4.0, decimate=False)
        f = d.regressor_filter
        want = signal.sosfiltfilt(f.sos, np.sign(f.dq), axis=0, padlen=f.padlen)[f.keep]
        got = f.signals(signs)
        assert got.shape == (d.m, robot.n)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
        logs.append((d, want))
    joined = concatenate([d for d, _ in logs]).regressor_filter.signals(signs)
    np.testing.assert_array_equal(
        joined, np.vstack([d.regressor_filter.signals(signs) for d, _ in logs])
    )


def test_block_filter_of_columns_zero_somewhere_or_everywhere_equals_scipys(monkeypatch):
    from mindyn.identification import preprocess as P
    from scipy import signal

    sos = signal.butter(4, 0.1, output="sos")
    monkeypatch.setattr(P, "_CHUNK", 50)
    monkeypatch.setattr(P, "KEEP_BUDGET", 8 * 50 * 5 * 3)  # the last few blocks kept
    x = np.random.default_rng(0).normal(size=(1000, 5))
    x[:, 1] = 0.0  # zero throughout: not filtered
    x[:, 3] = 0.0
    x[500:520, 3] = 1.0  # zero at both ends only: every column is filtered
    idx = np.arange(1000)[30:970:7]
    for y in (x, x[:, [1]], x[:, [1, 3]], np.zeros((1000, 2))):
        got = P._filtfilt_blocks(sos, 30, lambda a, b, y=y: y[a:b], 1000, idx)
        np.testing.assert_array_equal(got, signal.sosfiltfilt(sos, y, axis=0, padlen=30)[idx])


def _noise_draws(robot, base, log, tau, sd, draws, *, decimate, model="dynamic"):
    """Estimates and reported standard deviations, shapes (draws, nb), of ``model`` fitted
    without pruning on ``log`` with the noise-free torques ``tau`` plus white noise of
    standard deviations ``sd`` (noise seeds 0 to draws - 1), through the data path (cut-off
    5 Hz, decimated or not)."""
    est, std = [], []
    for s in range(draws):
        noisy = JointData(log.t, log.q, log.dq, log.ddq, tau, source="mc")
        noisy.tau = tau + sd * np.random.default_rng(s).standard_normal(tau.shape)
        d = preprocess(noisy, cutoff=5.0, decimate=decimate)
        res = identify(robot, d, base=base, model=model, rsd_threshold=None)
        est.append(res.full)
        std.append(res.std)
    return np.array(est), np.array(std)


def test_standard_deviations_on_the_data_path_match_the_scatter_of_the_estimates():
    """White torque noise low-passed and decimated to 10 x the cut-off (or not decimated) is
    correlated between the samples fitted: the reported standard deviations must still be those
    of the estimates. 20 noise realizations of one zcr07s log with friction: per base parameter
    the scatter of the estimates over the mean reported standard deviation, median over the
    parameters within [0.75, 1.33] (measured 0.96 both ways; samples taken as independent gave
    2.3 decimated and 5.1 not decimated, so that the RSDs and the pruning depended on the
    decimation)."""
    robot = mindyn.load("zcr07s")
    base = mindyn.base_parameters(robot, friction=True)
    log, _, tau, _ = _friction_log(robot, np.arange(0, 20.0, 1 / 250.0), seed=3)
    sd = 0.02 * np.abs(tau).max(axis=0)
    for decimate in (True, False):
        est, std = _noise_draws(robot, base, log, tau, sd, 20, decimate=decimate)
        ratio = np.median(np.std(est, axis=0, ddof=1) / np.mean(std, axis=0))
        print(f"\ndecimate={decimate}: scatter / reported standard deviation {ratio:.3f}")
        assert 0.75 <= ratio <= 1.33, (decimate, ratio)


@pytest.mark.parametrize("model", ["integral", "energy"])
def test_window_models_standard_deviations_on_the_data_path_match_the_scatter(model):
    """The integral and energy models' equations integrate the low-passed noise over windows
    (40 and 10 sample intervals: 0.8 s and 0.2 s decimated to 50 Hz, 0.16 s and 0.04 s at
    250 Hz, the window models' data path) against its correlation time of 0.11 s: neighbouring
    windows share noise, and the reported standard deviations must still be those of the
    estimates. 30 noise realisations (2 % of each joint's largest torque) of one 40 s
    puma560_3 log with friction: the RMS over parameters and realisations of
    (estimate - mean) / std within [0.75, 1.33] (measured 0.94 and 0.96 integral, 0.94 and 1.01
    energy, decimated and not; over batches of 30 draws the ratio spreads by 0.03 (integral)
    and 0.07 (energy), bench/bench_window_std.py). Windows taken as independent (and the
    friction columns not filtered like the torques) gave 0.83, 0.88, 0.99 and 1.72: the energy
    model's standard deviations 1.7 times too small without decimation."""
    robot = mindyn.load("puma560_3")
    base = mindyn.base_parameters(robot, friction=True)
    log, _, tau, _ = _friction_log(robot, np.arange(0, 40.0, 1 / 250.0), seed=3)
    sd = 0.02 * np.abs(tau).max(axis=0)
    for decimate in (True, False):
        est, std = _noise_draws(robot, base, log, tau, sd, 30, decimate=decimate, model=model)
        z = (est - np.mean(est, axis=0)) / std
        ratio = np.sqrt(np.sum(z**2) / (z.size - z.shape[1]))  # the mean's dof taken out
        print(f"\n{model} decimate={decimate}: scatter / reported standard deviation {ratio:.3f}")
        assert 0.75 <= ratio <= 1.33, (model, decimate, ratio)


def test_energy_weights_take_the_logged_torque_noise_and_its_density_after_the_low_pass():
    """The energy model's window weights on preprocessed data: the per-joint noise level is the
    logged torques' (measured: 0.96 to 1.02 of the simulated one; the second differences of the
    low-passed torques gave 0.014 to 0.033 of it decimated, 6e-4 to 1.3e-3 not, in proportions
    that differ between joints by a factor 2.4), and the rows' noise variances
    (energy_row_noise times its square) are those of the low-passed noise the windows
    integrate: over 2 s groups of windows (long against the filter's correlation time) the
    measured variance of the noise in the power integrals over the predicted one, 10 noise draws
    of a 40 s puma560_3 log: within [0.7, 1.4] (measured 0.90 here, 0.99 over 30 draws, 0.1 the
    spread of 10), decimated to 50 Hz and not (the trapezoid rule on the decimated samples
    alone, 5 times the density, gave 0.18)."""
    from mindyn.identification.models import energy_row_noise, energy_system

    robot = mindyn.load("puma560_3")
    base = mindyn.base_parameters(robot, friction=True)
    log, _, tau, _ = _friction_log(robot, np.arange(0, 40.0, 1 / 250.0), seed=3)
    sd = 0.02 * np.abs(tau).max(axis=0)
    for decimate in (True, False):
        exact = preprocess(
            JointData(log.t, log.q, log.dq, log.ddq, tau), cutoff=5.0, decimate=decimate
        )
        y0 = energy_system(base, exact, window=10)[1]
        got = want = 0.0
        for s in range(10):
            noisy = tau + sd * np.random.default_rng(s).standard_normal(tau.shape)
            d = preprocess(
                JointData(log.t, log.q, log.dq, log.ddq, noisy), cutoff=5.0, decimate=decimate
            )
            if s == 0:
                res = identify(robot, d, base=base, model="energy", rsd_threshold=None)
                np.testing.assert_allclose(res.joint_sigma, sd, rtol=0.1)
            per = int(round(2.0 * d.rate / 10))  # windows in 2 s
            noise = (
                energy_system(base, d, window=10)[1] - y0
            )  # the power integrals are linear in tau
            rows = energy_row_noise(d, 10) @ sd**2
            k = noise.size // per * per
            got += np.sum(noise[:k].reshape(-1, per).sum(axis=1) ** 2)
            want += np.sum(rows[:k])
        print(f"\ndecimate={decimate}: measured / predicted noise variance {got / want:.3f}")
        assert 0.7 <= got / want <= 1.4, (decimate, got / want)


def test_integral_model_leaves_out_the_windows_of_a_joint_at_rest():
    """A joint that rests half of every 4 s (its path followed at the speed
    ``max(0, sin(2 pi t / 4))^3``, creeping into and out of each rest; no friction at rest,
    where the drive holds it) with 0.005 rad/s velocity noise: a window through a rest
    integrates a Coulomb sign the data do not determine. The integral model leaves out the
    joint's equations of the windows where it is slower than min_velocity at any sample, and
    every estimate lies within 4 standard deviations of the truth (measured: at most 1.5 on
    this draw, bias at most 0.65 over 30 draws, bench/bench_window_rests.py); keeping them
    (min_velocity=0, as before) the resting joint's Coulomb estimate was 13 standard deviations
    off (measured here 11.3)."""
    robot = mindyn.load("puma560_3")
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    t = np.arange(0, 40.0, 1 / 250.0)
    log, truth, _, traj = _friction_log(robot, t, seed=3)
    theta = np.mod(2 * np.pi * t / 4.0, 2 * np.pi)
    half = theta < np.pi  # moving
    rise = np.where(half, 2 / 3 - np.cos(theta) + np.cos(theta) ** 3 / 3, 4 / 3)
    u = 4.0 / (2 * np.pi) * (4 / 3 * np.floor(t / 4.0) + rise)  # the integral of the speed
    w = np.where(half, np.sin(theta), 0.0) ** 3
    dw = 3 * np.where(half, np.sin(theta), 0.0) ** 2 * np.cos(theta) * 2 * np.pi / 4.0
    q, dq, ddq = traj.evaluate(t)
    qu, dqu, ddqu = traj.evaluate(u)
    q[:, 1], dq[:, 1], ddq[:, 1] = qu[:, 1], dqu[:, 1] * w, ddqu[:, 1] * w**2 + dqu[:, 1] * dw
    p = np.asarray(truth["values"]).reshape(robot.n, 13)
    rigid = p.copy()
    rigid[:, 11:] = 0.0
    tau = robot.inverse_dynamics(q, dq, ddq, rigid.reshape(-1))
    tau += p[:, 11] * dq + p[:, 12] * np.sign(dq)
    rng = np.random.default_rng(7)
    tau += 0.02 * np.abs(tau).max(axis=0) * rng.standard_normal(tau.shape)
    d = preprocess(
        JointData(t, q, dq + 0.005 * rng.standard_normal(dq.shape), ddq, tau),
        cutoff=5.0,
        decimate=False,
    )
    true = true_base_values(base, truth)
    fc2 = list(base.names).index("Fc2")
    kw = dict(base=base, model="integral", rsd_threshold=None)
    res = identify(robot, d, **kw)
    z = (res.full - true) / res.std
    kept = identify(robot, d, min_velocity=0.0, **kw)
    off = (kept.full[fc2] - true[fc2]) / kept.std[fc2]
    print(f"\nlargest |z| {np.max(np.abs(z)):.2f}; Fc2 with every window {off:.1f}")
    assert np.max(np.abs(z)) < 4.0, z
    assert abs(off) > 6.0
    left = res.settings["equations_left_out"]
    assert res.settings["min_velocity"] == 0.01 and left > 0
    assert res.rows + left == kept.rows


def test_window_variance_factor_against_the_spectrum_and_filtered_noise():
    """The factor of windows integrating low-passed white noise: against ``1 / (T int |H|^4
    sinc^2(f T) df)`` (the window's variance from the spectrum, scipy's analog Butterworth
    response, a dense trapezoid), its limits (``1 / (2 B T)`` for short windows, 1 for long
    ones), and on white noise run through scipy's zero-phase filter: the variance of the
    integral over 50 consecutive windows over 50 times that of one window."""
    from mindyn.identification.estimation import noise_bandwidth, window_variance_factor
    from scipy import integrate, signal

    for order, fc in ((4, 5.0), (1, 2.0), (8, 12.0)):
        b, a = signal.butter(order, 2 * np.pi * fc, analog=True)
        f = np.linspace(0, 60 * fc, 600001)
        h4 = np.abs(signal.freqs(b, a, worN=2 * np.pi * f)[1]) ** 4
        for T in (0.02 / fc, 0.5 / fc, 1.0 / fc, 4.0 / fc, 30.0 / fc):
            want = 1.0 / (T * 2 * integrate.trapezoid(h4 * np.sinc(f * T) ** 2, f))
            assert window_variance_factor(fc, order, T) == pytest.approx(want, rel=1e-3)
        short = window_variance_factor(fc, order, 1e-3 / fc)
        assert short == pytest.approx(1 / (2 * noise_bandwidth(fc, order) * 1e-3 / fc), rel=1e-3)
        assert 1.0 < window_variance_factor(fc, order, 100.0 / fc) < 1.01
    fs, fc, window = 1000.0, 5.0, 40  # windows of 0.04 s
    sos = signal.butter(4, fc, fs=fs, output="sos")
    x = signal.sosfiltfilt(sos, np.random.default_rng(0).standard_normal(1_000_000))
    w = x[: x.size // window * window].reshape(-1, window).sum(axis=1)  # window integrals / dt
    groups = w[: w.size // 50 * 50].reshape(-1, 50).sum(axis=1)
    measured = np.var(groups) / (50 * np.var(w))  # 500 groups: within about 6 %
    assert measured == pytest.approx(window_variance_factor(fc, 4, window / fs), rel=0.2)
    assert window_variance_factor(fc, 4, window / fs) > 2.5


def test_window_models_report_their_variance_factor():
    """identify states the window models' data-path factor for the windows' duration on
    low-passed data (integral: 40 intervals, energy: 10, at the decimated rate) and 1 on a log
    not low-passed; the factor used is at least that (the integral model's residuals may show
    more)."""
    from mindyn.identification.estimation import window_variance_factor

    robot = mindyn.load("puma560_3")
    t = np.arange(0, 40.0, 1 / 250.0)
    log, _, tau, traj = _friction_log(robot, t, seed=3)
    d = preprocess(log, cutoff=5.0)
    rate = d.processing["preprocess"]["rate_Hz"]
    exact = JointData(t, *traj.evaluate(t), tau, source="exact")
    for model, window in (("integral", 40), ("energy", 10)):
        res = identify(robot, d, model=model, friction=True)
        corr = res.settings["std_correlation"]
        assert corr["data_path"] == pytest.approx(
            window_variance_factor(5.0, 4, window / rate), rel=1e-9
        )
        assert corr["variance_factor"] >= corr["data_path"] > 1.0
        assert "windows" in corr["rule"]
        raw = identify(robot, exact, model=model, friction=True).settings["std_correlation"]
        assert raw["data_path"] == 1.0 and raw["variance_factor"] >= 1.0
        assert (raw["residuals"] is None) == (model == "energy")


def test_noise_bandwidth_of_the_zero_phase_filter_and_the_reported_factor():
    """The equivalent noise bandwidth against scipy's response of the same Butterworth filter
    integrated numerically (|H|^4: applied forwards and backwards), and the variance factor
    the dynamic model reports: the decimated rate over twice that bandwidth."""
    from mindyn.identification.estimation import noise_bandwidth
    from scipy import integrate, signal

    for order, fc in ((4, 5.0), (2, 12.0), (6, 1.5)):
        sos = signal.butter(order, fc, fs=1000.0, output="sos")
        f = np.linspace(0, 499.999, 400001)
        _, h = signal.sosfreqz(sos, worN=f, fs=1000.0)
        numeric = integrate.trapezoid(np.abs(h) ** 4, f)
        assert noise_bandwidth(fc, order) == pytest.approx(numeric, rel=1e-4)
    robot = mindyn.load("zcr07s")
    t = np.arange(0, 20.0, 1 / 250.0)
    log, _, tau, traj = _friction_log(robot, t, seed=3)
    d = preprocess(log, cutoff=5.0)
    res = identify(robot, d, friction=True)
    rate = d.processing["preprocess"]["rate_Hz"]
    corr = res.settings["std_correlation"]
    assert corr["variance_factor"] == pytest.approx(rate / (2 * noise_bandwidth(5.0, 4)))
    assert corr["variance_factor"] > 5  # decimated to 50 Hz, at least 10 x the cut-off
    exact = JointData(t, *traj.evaluate(t), tau, source="exact")
    raw = identify(robot, exact, friction=True)  # not low-passed: samples independent
    assert raw.settings["std_correlation"]["data_path"] == 1.0


def test_joined_logs_of_different_rates_keep_each_logs_correlation_factor():
    """Two logs low-passed alike, one decimated and one not (so their samples carry different
    numbers of independent noise values, fs / (2 B) each), joined by concatenate give the standard
    deviations of the same logs fitted as a list: the factor is each part's, by its samples
    (it was the first log's for the whole), and the residuals' Newey-West lags stay within a
    part. The factor is checked against the formula written out here."""
    robot = mindyn.load("puma560_3")
    base = mindyn.base_parameters(robot, friction=True)
    parts = []
    for seed, decimate in ((3, True), (4, False)):
        log, _, _, _ = _friction_log(robot, np.arange(0, 20.0, 1 / 250.0), seed=seed)
        log.tau = log.tau + 0.02 * np.abs(log.tau).max(axis=0) * np.random.default_rng(
            seed
        ).standard_normal(log.tau.shape)
        parts.append(preprocess(log, cutoff=4.0, decimate=decimate))
    joined = concatenate(parts)
    # every equation kept (min_velocity 0): a list is averaged by equations, a joined log's
    # parts by samples, the same then
    kw = dict(base=base, rsd_threshold=None, min_velocity=0.0)
    listed = identify(robot, parts, **kw)
    one = identify(robot, joined, **kw)

    def written_out(d):  # fs / (2 B), B the order-n Butterworth's noise bandwidth
        pre = d.processing["preprocess"]
        fc, n = pre["filter"]["cutoff_Hz"], pre["filter"]["order"]
        a = np.pi / (2 * n)
        return pre["rate_Hz"] / (2 * fc * (1 - 1 / (2 * n)) * a / np.sin(a))

    f = [written_out(d) for d in parts]
    assert f[0] > 1.5 * f[1] or f[1] > 1.5 * f[0]  # the parts differ
    expect = (parts[0].m * f[0] + parts[1].m * f[1]) / (parts[0].m + parts[1].m)
    assert one.settings["std_correlation"]["data_path"] == pytest.approx(expect, rel=1e-9)
    np.testing.assert_allclose(one.values, listed.values, rtol=1e-9, atol=0)
    np.testing.assert_allclose(one.std, listed.std, rtol=1e-9, atol=0)
