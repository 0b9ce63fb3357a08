"""``mindyn detect``: calibration on a collision-free log, detection on a log with an external
torque (the simulator's known profile), and one-line errors on bad input. The identification
JSON is written here from the simulated robot's true base values (a known answer), so that the
residual is the observer's alone."""

from __future__ import annotations

import json
from pathlib import Path

import mindyn
import numpy as np
import pytest
from mindyn.control import SumOfSines, TorqueProfile, simulate
from mindyn.identification.data import write_csv
from test_cli_errors import assert_one_line_error, run

N = 6


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("detect")
    robot = mindyn.load("puma560")
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    params = robot.parameters(rotor=True, friction=True)
    doc = {
        "robot": "puma560",
        "rotor": True,
        "friction": True,
        "offset": False,
        "base_names": list(base.names),
        "base_values": base.values(params).tolist(),
    }
    (d / "id.json").write_text(json.dumps(doc))
    (d / "other.json").write_text(json.dumps({**doc, "robot": "zcr07s"}))

    def log(name, seed, external=None):
        res = simulate(
            robot,
            SumOfSines(robot, period=2.0, fraction=0.4, seed=seed),
            rate=1000.0,
            duration=0.6,
            rotor=True,
            friction=True,
            external=external,
        )
        write_csv(d / name, res.t, res.q, res.tau, dq=res.dq)

    log("free.csv", 1)
    torque = np.zeros(N)
    torque[2] = 5.0
    log("hit.csv", 1, TorqueProfile(torque, start=0.3, stop=0.4))  # the same motion, then hit
    res = simulate(  # the same, saved with its truth sidecar (which says where the hit acted)
        robot,
        SumOfSines(robot, period=2.0, fraction=0.4, seed=1),
        rate=1000.0,
        duration=0.6,
        rotor=True,
        friction=True,
        external=TorqueProfile(torque, start=0.3, stop=0.4),
    )
    res.save(d / "hit_sim.csv", robot_name="puma560")
    write_csv(d / "notau.csv", np.arange(5) * 1e-3, np.zeros((5, N)), None, dq=np.zeros((5, N)))
    return d


def test_calibrate_then_detect_the_injected_torque(files):
    thr = files / "thr.json"
    rc, out, err = run(
        [
            "detect",
            "puma560",
            str(files / "id.json"),
            str(files / "free.csv"),
            "--calibrate",
            str(thr),
            "--torque",
            "held",
        ]
    )
    assert rc == 0, err
    assert "wrote" in out and json.loads(thr.read_text())["robot"] == "puma560"
    # the default quantile, 1, is the largest |r|, and the line says so
    assert "1.5 x the largest |r|" in out and "quantile" not in out, out
    rc, out, err = run(
        [
            "detect",
            "puma560",
            str(files / "id.json"),
            str(files / "hit.csv"),
            "--thresholds",
            str(thr),
            "--torque",
            "held",
            "--plot",
            str(files / "r.png"),
        ]
    )
    assert rc == 1, err  # intervals above the thresholds
    hits = [line for line in out.splitlines() if line.strip().startswith("joint ")]
    assert hits and hits[0].strip().startswith("joint 3:"), out  # first the joint hit ...
    start = float(hits[0].split(":")[1].split("s to")[0])
    assert 0.3 < start <= 0.305, out  # ... from the first sample after the onset
    assert (files / "r.png").stat().st_size > 0
    rc, out, err = run(
        [
            "detect",
            "puma560",
            str(files / "id.json"),
            str(files / "free.csv"),
            "--thresholds",
            str(thr),
            "--torque",
            "held",
        ]
    )
    assert rc == 0 and "0 interval(s) above" in out, out + err


def test_a_simulated_hit_is_scored_against_its_truth_sidecar(files):
    """The sidecar of the simulated log says the 5 N m hit on joint 3 acted from 0.3 to 0.4 s:
    detect reports it detected on joint 3 within a few periods, and no alarm outside it; the
    same log taken for calibration gets a warning that it is not collision-free."""
    thr = files / "thr_sim.json"
    base = ["detect", "puma560", str(files / "id.json")]
    rc, _, err = run([*base, str(files / "free.csv"), "--calibrate", str(thr)])
    assert rc == 0, err
    rc, out, err = run([*base, str(files / "hit_sim.csv"), "--thresholds", str(thr)])
    assert rc == 1, err
    assert "torque held over each step, as" in out  # its sidecar says the command was held
    line = next(x for x in out.splitlines() if x.strip().startswith("0.3000 s to 0.4000 s"))
    assert "peak per joint 0, 0, 5, 0, 0, 0" in line, line
    delay = float(line.split("detected after ")[1].split(" ms")[0])
    assert 0 < delay <= 5, line  # the first alarm within five periods of the onset
    # joint 3 first (with the true model the others cross thresholds calibrated on its tiny
    # collision-free residual, later)
    assert line.split("joint(s) ")[1].split(",")[0] == "3", line
    assert "alarms outside them (false): 0" in out, out
    rc, out, err = run([*base, str(files / "hit_sim.csv"), "--calibrate", str(thr)])
    assert rc == 0, err
    assert "WARNING: " in out and "it is not collision-free" in out, out


def test_alarms_are_scored_against_known_spans():
    from mindyn.control.observer import score_alarms

    alarms = [
        {"joint": 2, "start": 0.05, "end": 0.06, "peak": 1.0},  # before: false
        {"joint": 3, "start": 0.31, "end": 0.4, "peak": 5.0},
        {"joint": 1, "start": 0.32, "end": 0.33, "peak": 0.5},
        {"joint": 3, "start": 0.44, "end": 0.45, "peak": -2.0},  # within the settling time
        {"joint": 3, "start": 0.6, "end": 0.61, "peak": 1.0},  # after it: false
    ]
    spans = [{"start_s": 0.3, "stop_s": 0.4}, {"start_s": 0.8, "stop_s": 0.9}]
    got = score_alarms(alarms, spans, settle=0.05)
    assert got["spans"][0]["detected"] and got["spans"][0]["joints"] == [3, 1]
    assert got["spans"][0]["delay_s"] == pytest.approx(0.01)
    assert got["spans"][1] == {"detected": False, "delay_s": None, "joints": []}
    assert [a["start"] for a in got["false"]] == [0.05, 0.6]


@pytest.mark.parametrize(
    "content, needle",
    [
        ("{not json", "not a thresholds JSON file"),
        ("[" * 5000 + "]" * 5000, "nested deeper than the JSON reader follows"),
        ('{"robot": "puma560"}', "lacks period_s, gains, thresholds"),
        ('{"robot": "zcr07s", "period_s": 0.001, "gains": [1], "thresholds": [1]}', "zcr07s"),
        (
            '{"robot": "puma560", "period_s": 0.001, "gains": [1, 1, 1, 1, 1, 1], '
            '"thresholds": [1, 1, "x", 1, 1, 1]}',
            "'thresholds' must be a list of 6 numbers",
        ),
    ],
)
def test_bad_thresholds_file(files, tmp_path, content, needle):
    bad = tmp_path / "thr.json"
    bad.write_text(content)
    rc, _, err = run(
        [
            "detect",
            "puma560",
            str(files / "id.json"),
            str(files / "free.csv"),
            "--thresholds",
            str(bad),
        ]
    )
    assert_one_line_error(rc, err, needle)


def test_gains_come_from_the_thresholds_file(files, tmp_path):
    thr = tmp_path / "thr.json"
    rc, _, err = run(
        [
            "detect",
            "puma560",
            str(files / "id.json"),
            str(files / "free.csv"),
            "--calibrate",
            str(thr),
            "--observer-gain",
            "50",
        ]
    )
    assert rc == 0 and json.loads(thr.read_text())["gains"] == [50.0] * N, err
    rc, _, err = run(
        [
            "detect",
            "puma560",
            str(files / "id.json"),
            str(files / "free.csv"),
            "--thresholds",
            str(thr),
            "--observer-gain",
            "60",
        ]
    )
    assert_one_line_error(rc, err, "--observer-gain")


def test_the_observer_gain_has_the_name_of_codegen(files, tmp_path):
    """detect and codegen --what momentum-observer name K_O --observer-gain; detect's former
    --gain still works for this release, with a note naming the new spelling."""
    thr = tmp_path / "thr.json"
    argv = ["detect", "puma560", str(files / "id.json"), str(files / "free.csv")]
    rc, _, err = run([*argv, "--calibrate", str(thr), "--gain", "40"])
    assert rc == 0 and json.loads(thr.read_text())["gains"] == [40.0] * N, err
    assert err.strip() == (
        "mindyn: note: --gain is deprecated and will be removed in the next release; use "
        "--observer-gain"
    )
    help_text = {}
    for command in ("detect", "codegen"):
        rc, out, _ = run([command, "--help"])
        help_text[command] = " ".join(out.split())
        assert "--observer-gain K_O" in help_text[command]
    assert "--gain" not in help_text["detect"].replace("--observer-gain", "")


def test_thresholds_of_another_model_are_refused_or_noted(files, tmp_path):
    """The thresholds file records the base values it was calibrated with: another
    identification (one value 10 % off) is refused naming the value; the same values under
    another file name are taken; a file written before the record (no values) naming another
    identification gets a one-line warning."""
    thr = str(tmp_path / "thr.json")
    ident, free = str(files / "id.json"), str(files / "free.csv")
    rc, _, err = run(["detect", "puma560", ident, free, "--calibrate", thr])
    assert rc == 0, err
    doc = json.loads(Path(ident).read_text())
    assert json.loads(Path(thr).read_text())["base_values"] == doc["base_values"]
    off = dict(doc, base_values=list(doc["base_values"]))
    off["base_values"][2] *= 1.1
    changed, copy = str(tmp_path / "changed.json"), str(tmp_path / "copy.json")
    Path(changed).write_text(json.dumps(off))
    Path(copy).write_text(Path(ident).read_text())
    rc, _, err = run(["detect", "puma560", changed, free, "--thresholds", thr])
    name, value = doc["base_names"][2], doc["base_values"][2]
    assert_one_line_error(
        rc,
        err,
        f"{thr}: calibrated with the unconstrained estimate of '{ident}': 1 of its "
        f"{len(doc['base_names'])} base parameter values differ from the unconstrained estimate "
        f"of '{changed}' ({name} {value:.6g} there, {value * 1.1:.6g} here)",
    )
    rc, _, err = run(["detect", "puma560", copy, free, "--thresholds", thr])
    assert rc == 0 and not err, err
    old = str(tmp_path / "old.json")
    recorded = json.loads(Path(thr).read_text())
    for key in ("estimate", "base_names", "base_values"):
        del recorded[key]
    Path(old).write_text(json.dumps(recorded))
    rc, _, err = run(["detect", "puma560", changed, free, "--thresholds", old])
    # (run, with alarms: the other model's residual on the collision-free log)
    assert rc in (0, 1) and err.strip().splitlines() == [
        f"mindyn: warning: {old}: calibrated with the identification '{ident}', not "
        f"'{changed}' (the file records no parameter values to compare: thresholds of another "
        "model's residual do not fit this one) (note)"
    ], err
    rc, _, err = run(["detect", "puma560", ident, free, "--thresholds", old])
    assert rc == 0 and not err, err


def test_bad_log_and_identification(files):
    rc, _, err = run(["detect", "puma560", str(files / "id.json"), str(files / "notau.csv")])
    assert_one_line_error(rc, err, "tau")
    rc, _, err = run(["detect", "puma560", str(files / "other.json"), str(files / "free.csv")])
    assert_one_line_error(rc, err, "zcr07s")


def test_cli_codegen_observer(files, tmp_path):
    doc = json.loads((files / "id.json").read_text())
    values = tmp_path / "values.json"  # a JSON mapping of the base parameters
    values.write_text(json.dumps(dict(zip(doc["base_names"], doc["base_values"], strict=True))))
    rc, out, err = run(
        [
            "codegen",
            "puma560",
            "--rotor",
            "--friction",
            "--what",
            "momentum-observer",
            "--lang",
            "c",
            "--params",
            str(values),
            "--controller-period",
            "0.001",
            "-o",
            str(tmp_path / "obs"),
        ]
    )
    assert rc == 0, err
    assert (tmp_path / "obs.c").exists() and (tmp_path / "obs.h").exists()
    assert "whole step:" in out and "gains K_O [1/s] (default 1 / (10 T) = 100): 100, 100" in out
    rc, _, err = run(
        [
            "codegen",
            "zcr07s",
            "--rotor",
            "--friction",
            "--what",
            "momentum-observer",
            "--lang",
            "c",
            "--params",
            str(values),
            "-o",
            str(tmp_path / "obs2"),
        ]
    )
    assert_one_line_error(rc, err, "unknown parameter")


@pytest.mark.parametrize(
    "option, value, needle",
    [
        ("--quantile", "0", "--quantile"),
        ("--quantile", "1.5", "--quantile"),
        ("--margin", "0.5", "--margin"),
        ("--margin", "nan", "--margin"),
        ("--observer-gain", "-1", "observer gain K_O of joint 1"),
        ("--observer-gain", "5000", "expected 0 < K_O < 2 / T = 2000"),
        ("--observer-gain", "1,2", "--observer-gain"),
    ],
)
def test_bad_settings_are_one_line_errors(files, tmp_path, option, value, needle):
    rc, _, err = run(
        [
            "detect",
            "puma560",
            str(files / "id.json"),
            str(files / "free.csv"),
            "--calibrate",
            str(tmp_path / "thr.json"),
            option,
            value,
        ]
    )
    assert_one_line_error(rc, err, needle)


def test_any_mix_of_arguments_gives_status_0_1_or_one_error_line(files, tmp_path_factory):
    """Valid and invalid values for every option and positional of detect, mixed: status 0 (no
    alarm) or 1 (alarms, on stdout) with nothing on stderr, or a non-zero status with exactly
    one error line."""
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    d = tmp_path_factory.mktemp("detect_mix")
    thr = d / "thr.json"
    assert (
        run(
            [
                "detect",
                "puma560",
                str(files / "id.json"),
                str(files / "free.csv"),
                "--calibrate",
                str(thr),
            ]
        )[0]
        == 0
    )
    (d / "bad.json").write_text("{")
    bad = ["-1", "0", "nan", "inf", "", "x", "1e308"]

    def opt(name, valid, invalid=bad):
        return st.one_of(st.none(), st.sampled_from(valid + invalid).map(lambda v: [name, v]))

    ids = [str(files / "id.json"), str(files / "other.json"), str(d / "bad.json"), "no.json"]
    logs = [str(files / "free.csv"), str(files / "hit.csv"), str(files / "notau.csv"), "no.csv"]
    strategy = st.tuples(
        st.sampled_from(ids),
        st.sampled_from(logs),
        opt("--thresholds", [str(thr), str(d / "bad.json"), "no.json"]),
        # (files to write: bad values only where they cannot land in the working folder)
        opt("--calibrate", [str(d / "out" / "t.json")], [str(d), "", str(d / "bad.json" / "x")]),
        opt("--quantile", ["0.5", "1"]),
        opt("--margin", ["1", "2"]),
        opt("--observer-gain", ["10", "10,20,30,40,50,60"]),
        opt("--torque", ["held", "sampled"]),
    ).map(lambda p: ["detect", "puma560", p[0], p[1], *(a for x in p[2:] if x for a in x)])

    @settings(
        max_examples=15,
        deadline=None,
        derandomize=True,
        database=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
    )
    @given(strategy)
    def check(argv):
        rc, _, err = run(argv)
        if rc in (0, 1) and not err:
            return
        assert_one_line_error(rc, err)

    check()


@pytest.mark.parametrize(
    "option", [["--margin", "3"], ["--quantile", "0.5"], ["--margin", "1.5"], ["--quantile", "1"]]
)
def test_the_calibration_options_need_calibrate(option, files):
    """--margin and --quantile without --calibrate were ignored (--model-sigma was refused), at
    their defaults (1.5 and 1) too."""
    argv = ["detect", "puma560", str(files / "id.json"), str(files / "free.csv"), *option]
    rc, _, err = run(argv)
    assert_one_line_error(rc, err, f"{option[0]} applies to --calibrate")


def test_model_sigma_needs_calibration_and_standard_deviations(files, tmp_path):
    rc, _, err = run(
        ["detect", "puma560", str(files / "id.json"), str(files / "free.csv"), "--model-sigma", "3"]
    )
    assert_one_line_error(rc, err, "--model-sigma applies to --calibrate")
    rc, _, err = run(
        [
            "detect",
            "puma560",
            str(files / "id.json"),
            str(files / "free.csv"),
            "--calibrate",
            str(tmp_path / "t.json"),
            "--model-sigma",
            "3",
        ]
    )
    assert_one_line_error(rc, err, "gives no standard deviations")
    doc = json.loads((files / "id.json").read_text())
    doc.update(names=doc["base_names"], std=[1e-3] * len(doc["base_names"]))
    (tmp_path / "id.json").write_text(json.dumps(doc))
    rc, out, err = run(
        [
            "detect",
            "puma560",
            str(tmp_path / "id.json"),
            str(files / "free.csv"),
            "--calibrate",
            str(tmp_path / "t.json"),
            "--model-sigma",
            "3",
        ]
    )
    assert rc == 0 and "at least 3 sigma" in out, err
    assert json.loads((tmp_path / "t.json").read_text())["model_sigma"] == 3
