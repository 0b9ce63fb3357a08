"""Error measures a reader can compare, predicted torques of an identification, and messages on
real-looking data. References: logs the test generates with known parameters and white noise of
known standard deviation (closed-form expectation of the error against the torques as logged),
the classical Newton-Euler recursion with a classical vector having the identified base values,
the generated C compiled with cc, and the motion the test builds (joints at rest, joints that
never reverse, breaks in the time stamps)."""

from __future__ import annotations

import ctypes
import json
import math
import shutil
import subprocess

import mindyn
import numpy as np
import pytest
from conftest import cli
from mindyn.identification import (
    JointData,
    RankDeficientError,
    identify,
    validate,
    write_csv,
)
from mindyn.identification.preprocess import preprocess, split_at_gaps

CC = shutil.which("cc") or shutil.which("gcc")
RATE = 500.0


def sines(t, phase=0.0):
    """A two-joint motion (planar2) and its exact derivatives: both joints reverse."""
    w = np.array([[0.7, 1.9], [0.5, 1.3]])
    a = np.array([[1.0, 0.5], [0.6, 0.4]])
    q = np.column_stack([(a[j] * np.sin(w[j] * t[:, None] + phase)).sum(1) for j in range(2)])
    dq = np.column_stack(
        [(a[j] * w[j] * np.cos(w[j] * t[:, None] + phase)).sum(1) for j in range(2)]
    )
    ddq = np.column_stack(
        [(-a[j] * w[j] ** 2 * np.sin(w[j] * t[:, None] + phase)).sum(1) for j in range(2)]
    )
    return q, dq, ddq


def test_raw_measure_is_the_noise_level_and_the_filtered_one_lower():
    robot = mindyn.load("planar2")
    t = np.arange(0, 30, 1 / RATE)
    q, dq, ddq = sines(t)
    tau_true = robot.inverse_dynamics(q, dq, ddq)
    sigma = 0.05 * np.sqrt(np.mean(tau_true**2, axis=0))  # per joint, 5 % of its RMS torque
    noise = np.random.default_rng(3).standard_normal(q.shape) * sigma
    log = JointData(t, q, dq, ddq, tau_true + noise, "noisy")
    data = preprocess(log)
    res = identify(robot, data)
    v = validate(res, data)
    raw = v["raw"]
    # the logged samples between the filter edges, their true torques known
    kept = np.isin(t, data.logged.t)
    m = int(kept.sum())
    assert raw["samples"] == m and m > 0.8 * t.size
    # closed form: E|e|^2 = m sum(sigma^2) with a model as good as the truth
    expect = math.sqrt(m * np.sum(sigma**2) / (np.sum(tau_true[kept] ** 2) + m * np.sum(sigma**2)))
    assert raw["overall_relative"] == pytest.approx(expect, rel=0.05)
    assert np.allclose(raw["rms"], sigma, rtol=0.06)
    # the filter removes most of the white noise from the torques the fit saw
    assert v["overall_relative"] < 0.5 * raw["overall_relative"]


def rest_log(seed: int, sd_v: float, disturbance: float):
    """planar2: joint 1 moves throughout; joint 2 moves (sin^4 strokes) and rests in turns, a
    constant torque ``disturbance`` (stiction, not in the model) on joint 2 while it rests."""
    robot = mindyn.load("planar2")
    t = np.arange(0, 40, 1 / RATE)
    q, dq, ddq = sines(t)
    period, stroke = 4.0, 2.0  # joint 2: moves for 2 s, rests for 2 s
    u = np.mod(t, period) / stroke
    moving = u < 1.0
    amp = np.where(np.floor(t / period) % 2 == 0, 0.8, -0.8)  # strokes in both directions
    s, c = np.sin(np.pi * u), np.cos(np.pi * u)  # strokes sin^4: continuous acceleration
    q[:, 1] = np.where(moving, amp * s**4, 0.0)
    dq[:, 1] = np.where(moving, amp * 4 * np.pi / stroke * s**3 * c, 0.0)
    ddq[:, 1] = np.where(moving, amp * 4 * np.pi**2 / stroke**2 * (3 * s**2 * c**2 - s**4), 0.0)
    tau = robot.inverse_dynamics(q, dq, ddq)
    rng = np.random.default_rng(seed)
    sigma = 0.01
    tau_log = tau + sigma * rng.standard_normal(tau.shape)
    tau_log[~moving, 1] += disturbance
    dq_log = dq + sd_v * rng.standard_normal(dq.shape)
    return robot, JointData(t, q, dq_log, ddq, tau_log, f"rest{seed}"), dq, sigma


def test_moving_measure_leaves_out_the_joint_at_rest():
    sd_v = 0.01
    robot, fit_log, _, sigma = rest_log(1, sd_v, 0.0)
    # a disturbance at rest of a few times the torque error: the rest samples the 3-sigma
    # threshold lets through by chance (about 0.3 %) add little to the moving measure
    _, val_log, dq_true, _ = rest_log(2, sd_v, 0.05)
    _, clean_log, _, _ = rest_log(2, sd_v, 0.0)  # the same noise, no disturbance at rest
    fit = preprocess(fit_log)
    cut = fit.processing["preprocess"]["filter"]["cutoff_Hz"]
    val, clean = preprocess(val_log, cutoff=cut), preprocess(clean_log, cutoff=cut)
    res = identify(robot, fit)
    v, v0 = validate(res, val), validate(res, clean)
    mov, raw = v["moving"], v["raw"]
    # the threshold from the velocity noise: 3 x sd_v through the low-pass, sqrt(2 fc / rate)
    expect = 3 * sd_v * math.sqrt(2 * cut / RATE)
    assert np.allclose(mov["threshold"], expect, rtol=0.25)
    assert "3 x the noise level" in mov["rule"]
    # joint 2 rests half of the time: the samples counted are those whose true speed exceeds
    # the threshold (within the filter's smearing of the stroke ends)
    kept = np.isin(val_log.t, val.logged.t)
    above = np.mean(np.abs(dq_true[kept, 1]) >= mov["threshold"][1])
    assert 0.4 < above < 0.6
    assert mov["fraction"][1] == pytest.approx(above, abs=0.03)
    assert mov["fraction"][0] > 0.97
    # the disturbance at rest is in the raw error, not in the moving one
    assert raw["rms"][1] > 1.5 * v0["raw"]["rms"][1]
    assert mov["rms"][1] == pytest.approx(v0["moving"]["rms"][1], rel=0.05)
    assert mov["rms"][0] == pytest.approx(v0["moving"]["rms"][0], rel=1e-9)


@pytest.mark.skipif(CC is None, reason="a C compiler is needed for the generated code")
def test_predict_is_the_model_torque_and_the_generated_code_gives_it(tmp_path):
    robot = mindyn.load("planar2")
    t = np.arange(0, 30, 1 / RATE)
    q, dq, ddq = sines(t)
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    truth = robot.parameters(rotor=True, friction=True) * np.repeat([1.0, 1.0], 13)
    truth[[10, 23]] = 0.05  # rotor inertia Ia
    truth[[11, 24]] = [0.3, 0.2]  # viscous
    truth[[12, 25]] = [0.4, 0.25]  # Coulomb
    tau = robot.inverse_dynamics(q, dq, ddq, truth)
    tau += 0.01 * np.random.default_rng(5).standard_normal(tau.shape)
    fit_csv, val_csv = tmp_path / "fit.csv", tmp_path / "val.csv"
    write_csv(fit_csv, t, q, tau, dq=dq)
    qv, dqv, ddqv = sines(t[: t.size // 2], phase=0.4)
    write_csv(val_csv, t[: t.size // 2], qv, robot.inverse_dynamics(qv, dqv, ddqv, truth), dq=dqv)
    ident = tmp_path / "id.json"
    cli("identify", "planar2", fit_csv, "--rotor", "--friction", "--json", ident)
    out = cli("predict", "planar2", ident, val_csv, "-o", tmp_path / "pred.csv")
    assert "low-pass" in out
    header = (tmp_path / "pred.csv").read_text().splitlines()[0].split(",")
    a = np.loadtxt(tmp_path / "pred.csv", delimiter=",", skiprows=1)
    col = {h: k for k, h in enumerate(header)}

    def block(kind):
        return a[:, [col[f"{kind}{j}"] for j in (1, 2)]]

    ts, qs, dqs, ddqs, hat = a[:, 0], block("q"), block("dq"), block("ddq"), block("tau_hat")
    assert np.all(np.isin(np.round(ts * RATE), np.round(t[: t.size // 2] * RATE)))
    # the classical Newton-Euler recursion with a classical vector of the identified base values
    doc = json.loads(ident.read_text())
    assert doc["base_names"] == base.names
    p_b = np.array(doc["base_values"])
    pi = np.linalg.pinv(base.Y) @ p_b
    assert np.allclose(base.Y @ pi, p_b, atol=1e-10 * np.abs(p_b).max())
    ref = robot.inverse_dynamics(qs, dqs, ddqs, pi)
    scale = np.abs(ref).max()
    assert np.abs(hat - ref).max() <= 1e-9 * scale
    # the generated C with the same JSON, compiled, on the same states
    cli("codegen", "planar2", "--lang", "c", "--rotor", "--friction", "--params", ident,
        "--numeric", "-o", tmp_path / "dyn")  # fmt: skip
    so = tmp_path / "libdyn.so"
    cmd = [CC, "-std=c99", "-O1", "-shared", "-fPIC", "-o", so, tmp_path / "dyn.c", "-lm"]
    run = subprocess.run([str(c) for c in cmd], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    lib = ctypes.CDLL(str(so))
    dbl = ctypes.POINTER(ctypes.c_double)
    c = np.zeros_like(hat)
    for k in range(0, ts.size, 7):
        args = [np.ascontiguousarray(x[k]) for x in (qs, dqs, ddqs)]
        out_k = np.zeros(2)
        ptrs = [x.ctypes.data_as(dbl) for x in (*args, out_k)]
        lib.planar2_inverse_dynamics(*ptrs)
        c[k] = out_k
    sel = np.arange(0, ts.size, 7)
    assert np.abs(c[sel] - hat[sel]).max() <= 1e-9 * scale
    # and the model is close to the truth it was identified from (a sanity check of the data)
    assert np.abs(hat - robot.inverse_dynamics(qs, dqs, ddqs, truth)).max() < 0.05 * scale


def test_rank_deficiency_names_the_offset_when_a_joint_never_reverses():
    robot = mindyn.load("planar2")
    t = np.arange(0, 20, 1 / 250)
    q, dq, ddq = sines(t)
    # joint 2 turns one way only, within its limits (+-pi) over the 60 s
    q[:, 1] = -3.0 + 0.1 * t + 0.03 * np.sin(1.3 * t)
    dq[:, 1] = 0.1 + 0.039 * np.cos(1.3 * t)
    ddq[:, 1] = -0.338 * np.sin(1.3 * t)
    base = mindyn.base_parameters(robot, friction=True, offset=True)
    tau = base.regressor(q, dq, ddq) @ np.ones(base.n)
    with pytest.raises(RankDeficientError) as e:
        identify(robot, JointData(t, q, dq, ddq, tau, "one-way"), base=base)
    msg = str(e.value)
    assert "dependent on each other in this data: Fc2, Off2" in msg
    assert "Joint(s) 2 never reverse" in msg and "leave out offset=True" in msg
    assert "Joint(s) 1" not in msg
    # both joints reversing: the same parameters are identified
    q, dq, ddq = sines(t)
    tau = base.regressor(q, dq, ddq) @ np.ones(base.n)
    identify(robot, JointData(t, q, dq, ddq, tau, "both ways"), base=base)


def test_a_joint_that_never_moves_names_the_friction():
    robot = mindyn.load("zcr07s")
    t = np.arange(0, 20, 1 / 250)
    rng = np.random.default_rng(0)
    w, a = rng.uniform(0.3, 1.5, (robot.n, 3)), rng.uniform(0.2, 0.6, (robot.n, 3))
    q = np.column_stack([(a[j] * np.sin(w[j] * t[:, None])).sum(1) for j in range(robot.n)])
    dq = np.column_stack([(a[j] * w[j] * np.cos(w[j] * t[:, None])).sum(1) for j in range(6)])
    ddq = np.column_stack(
        [(-a[j] * w[j] ** 2 * np.sin(w[j] * t[:, None])).sum(1) for j in range(6)]
    )
    q[:, 5], dq[:, 5], ddq[:, 5] = 0.3, 0.0, 0.0  # joint 6 held still
    base = mindyn.base_parameters(robot, friction=True)
    tau = base.regressor(q, dq, ddq) @ np.ones(base.n)
    with pytest.raises(RankDeficientError) as e:
        identify(robot, JointData(t, q, dq, ddq, tau, "still"), base=base)
    msg = str(e.value)
    assert "no effect on this data: Fv6, Fc6" in msg
    assert "Joint(s) 6 never move" in msg and "leave out friction=True" in msg
    assert "--offset" not in msg and "never reverse" not in msg


def gappy_times(duration: float = 60.0, rate: float = 250.0, breaks: int = 20):
    """Time stamps with ``breaks`` breaks of 0.2 s spread evenly."""
    t = np.arange(0, duration, 1 / rate)
    keep = np.ones(t.size, bool)
    for k in range(breaks):
        a = int((k + 1) * t.size / (breaks + 1))
        keep[a : a + int(0.2 * rate)] = False
    return t[keep]


def test_a_rank_deficiency_on_a_log_with_breaks_counts_its_segments():
    robot = mindyn.load("planar2")
    t = gappy_times()
    q, dq, ddq = sines(t)
    # joint 2 turns one way only, within its limits (+-pi) over the 60 s
    q[:, 1] = -3.0 + 0.1 * t + 0.03 * np.sin(1.3 * t)
    dq[:, 1] = 0.1 + 0.039 * np.cos(1.3 * t)
    base = mindyn.base_parameters(robot, friction=True, offset=True)
    # the torques of a parameter vector of ones, no robot's: stated as checked, taken as they are
    # (the description's torques correlate negatively with them on some segments)
    tau = base.regressor(q, dq, ddq) @ np.ones(base.n)
    log = JointData(t, q, dq, ddq, tau, "oneway.csv", units_checked=True)
    segments = [preprocess(s) for s in split_at_gaps(log)]
    assert len(segments) == 21
    with pytest.raises(RankDeficientError) as e:
        identify(robot, segments, base=base)
    msg = str(e.value)
    assert msg.startswith("dynamic model on oneway.csv (21 segments): ")
    assert "s to" not in msg and len(msg) < 600
    assert "leave out offset=True" in msg


def test_a_log_with_twenty_breaks_is_summarised_in_one_line(tmp_path):
    robot = mindyn.load("planar2")
    t = gappy_times()
    q, dq, ddq = sines(t)
    tau = robot.inverse_dynamics(q, dq, ddq)
    tau += 0.01 * np.random.default_rng(2).standard_normal(q.shape)
    log, ident = tmp_path / "gaps.csv", tmp_path / "id.json"
    write_csv(log, t, q, tau, dq=dq)
    out = cli("identify", "planar2", log, "--json", ident)
    lines = out.splitlines()
    seg = [ln for ln in lines if "segment" in ln]
    assert len([ln for ln in seg if "21 segments" in ln and "20 break(s)" in ln]) == 1
    # one log (its segments fitted together), not 21 logs
    assert "from 1 log, its 21 segments fitted together:" in lines[0], lines[0]
    assert sum("low-pass:" in ln for ln in lines) == 1
    assert sum("time stamps:" in ln for ln in lines) == 1
    assert len(out) < 4000
    # the spans: the test's own cuts
    cuts = np.flatnonzero(np.diff(t) > 0.1) + 1
    bounds = np.concatenate([[0], cuts, [t.size]])
    spans = [t[b - 1] - t[a] for a, b in zip(bounds[:-1], bounds[1:])]
    (s,) = json.loads(ident.read_text())["data"]["segments"]
    assert s["count"] == 21
    assert s["shortest_s"] == pytest.approx(min(spans))
    assert s["longest_s"] == pytest.approx(max(spans))
    assert f"shortest {min(spans):.4g} s, longest {max(spans):.4g} s" in out
