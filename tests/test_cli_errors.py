"""Bad command lines end in one line ``mindyn: error: ...`` naming the argument and what was
expected, with a non-zero status; never a traceback, a hang or a silent wrong file.

Two parts: the cases found by generating bad inputs, each with the message it must give, and a
property-based test (hypothesis, bounded and derandomized) that mixes valid and invalid values
for every option of every subcommand (except ``demo``, which runs the whole chain) and checks
the contract of :func:`mindyn.cli.main`: status 0, or a non-zero status with exactly one line on
stderr, which starts with ``mindyn: error:`` and is not the last-resort message of an
unexpected exception.
"""

from __future__ import annotations

import contextlib
import io
import json
import math

import mindyn
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mindyn import cli
from mindyn.control.simulation import MAX_STEPS, SensorNoise, simulate_inverse
from mindyn.identification import IdentificationError, dynamic_system, identify
from mindyn.identification.data import JointData
from mindyn.identification.estimation import MIN_EQUATIONS_PER_PARAMETER, MIN_NOISE_DOF
from mindyn.identification.excitation import random_trajectory


def run(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main(argv)
    return rc, out.getvalue(), err.getvalue()


def assert_one_line_error(rc: int, err: str, *needles: str) -> str:
    assert rc != 0, err
    lines = err.splitlines()
    assert len(lines) == 1 and err.endswith("\n"), err
    assert lines[0].startswith("mindyn: error: "), err
    assert "a defect in mindyn" not in lines[0], err  # explicit validation, not the last resort
    for s in needles:
        assert s in lines[0], (s, err)
    return lines[0]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A planar2 trajectory (excite's JSON) and a noisy log of it (CSV with truth sidecar)."""
    d = tmp_path_factory.mktemp("cli")
    robot = mindyn.load("planar2")
    traj = random_trajectory(robot, seed=1, limits={"lower": -np.ones(2), "upper": np.ones(2)})
    (d / "traj.json").write_text(json.dumps(traj.to_dict()))
    log = simulate_inverse(robot, traj, noise=SensorNoise(torque=0.01), seed=3)
    log.save(d / "log.csv", robot_name="planar2")
    (d / "file.txt").write_text("a file, not a folder\n")
    return d


# ---------------------------------------------------------------------------------------------
# The cases found, each with its message
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "argv, needles",
    [
        (["track", "planar2", "--duration", "inf"], ["argument --duration", "finite number"]),
        (["track", "planar2", "--cycle", "1e308"], ["argument --cycle", "(0, 1e+06]"]),
        (["track", "planar2", "--controller-period", "nan"], ["argument --controller-period"]),
        (["simulate", "planar2", "--trajectory", "x", "--rate", "inf", "-o", "a.csv"], ["--rate"]),
        (["excite", "planar2", "--freq", "inf", "-o", "a.csv"], ["argument --freq"]),
        (["excite", "planar2", "--rate", "0", "-o", "a.csv"], ["argument --rate", "(0, "]),
        (["excite", "planar2", "--rate", "-1", "-o", "a.csv"], ["argument --rate"]),
        (["excite", "planar2", "--freq", "1e9", "-o", "a.csv"], ["argument --freq", "1000]"]),
        (["excite", "planar2", "--harmonics", "31", "-o", "a.csv"], ["--harmonics"]),
        (["ik", "planar2", "--xyz", "1", "0", "0", "--seed", "-1"], ["argument --seed", "[0, "]),
        (["ik", "planar2", "--xyz", "1", "0", "0", "--seed", "9" * 40], ["argument --seed"]),
        (["ik", "planar2", "--xyz", "1", "nan", "0"], ["argument --xyz"]),
        (["identify", "planar2", "x.csv", "--energy-window", "0"], ["--energy-window", "[1, "]),
        (["identify", "planar2", "x.csv", "--integral-window", "0"], ["--integral-window", "[1, "]),
        (["identify", "planar2", "x.csv", "--rsd-threshold", "-5"], ["--rsd-threshold", ">= 0"]),
        (["base", "planar2", "--rank-tolerance", "0"], ["argument --rank-tolerance"]),
        (["info", "planar9999999999999999999999999"], ["planar<N> takes a joint count N"]),
        (["info", ""], ["ROBOT", "empty string"]),
        (["track", "planar2", "--substeps", "0"], ["argument --substeps", "integer"]),
    ],
)
def test_bad_numbers_are_named_with_the_expected_range(argv, needles, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    rc, _, err = run(argv)
    line = assert_one_line_error(rc, err, *needles)
    assert f"(see 'mindyn {argv[0]} --help')" in line


@pytest.mark.parametrize(
    ("argv", "hint"),
    [
        (
            ["excite", "planar2", "-o", "x.csv", "--frequency", "0.1"],
            "unrecognized arguments: --frequency 0.1 (unknown option --frequency: did you mean "
            "--freq?) (see 'mindyn excite --help')",
        ),
        (["base", "planar2", "--rotor-inertia"], "option --rotor-inertia: did you mean --rotor?"),
        (
            ["simulate", "planar2", "-o", "x", "--torque-nosie=1"],
            "(unknown option --torque-nosie: did you mean --torque-noise?)",
        ),
        (["info", "planar2", "extra"], None),
        # an abbreviation is not taken for the option it abbreviates: the options it could be
        (
            ["codegen", "planar2", "--controller", "0.004"],
            "(unknown option --controller: did you mean --controller-period?)",
        ),
        (["base", "planar2", "--rot"], "(unknown option --rot: did you mean --rotor?)"),
        (
            ["identify", "planar2", "x.csv", "--fric"],
            "unknown option --fric: did you mean --friction or --friction-model or",
        ),
        (
            ["base", "planar2", "--rot", "--rotor-inertia"],
            "(unknown option --rot: did you mean --rotor?; unknown option --rotor-inertia: did "
            "you mean --rotor?)",
        ),
    ],
)
def test_an_unknown_option_points_to_its_command_and_a_near_spelling(
    argv, hint, tmp_path, monkeypatch
):
    """Words a command does not take were refused with the top-level help ('mindyn --help',
    which does not list the command's options) and no hint of the option meant; nothing is
    written."""
    monkeypatch.chdir(tmp_path)
    rc, _, err = run(argv)
    line = assert_one_line_error(rc, err, "unrecognized arguments")
    assert f"(see 'mindyn {argv[0]} --help')" in line and "(see 'mindyn --help')" not in line
    assert (hint in line) if hint else "did you mean" not in line
    assert not list(tmp_path.iterdir())


def test_help_shows_the_accepted_ranges(capsys):
    assert cli.main(["track", "--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "controller period [s]" in out and "number (0, 10]; default 0.004" in out
    assert "integer [0, 4294967295]" in out  # --seed
    assert cli.main(["excite", "--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "above 2 N freq" in out and "integer [2, 30]; default 5" in out


# a folder given to a file option names the default file inside it (test_output_path.py); a
# file given to a folder option is refused
@pytest.mark.parametrize(
    "cmd, where",
    [
        (cmd, where)
        for cmd in ["excite", "simulate", "codegen", "identify_json", "track_report"]
        for where in ["dir", "empty", "under_file", "proc"]
        if where != "dir" or cmd == "track_report"
    ],
)
def test_output_paths_that_cannot_be_written(cmd, where, files, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = {
        "dir": str(tmp_path),
        "empty": "",
        "under_file": str(files / "file.txt" / "out.csv"),
        "proc": "/proc/mindyn-no-such-dir/out.csv",
    }[where]
    argv = {
        "excite": ["excite", "planar2", "--quiet", "--maxiter", "1", "--starts", "1", "-o", path],
        "simulate": ["simulate", "planar2", "--trajectory", str(files / "traj.json"), "-o", path],
        "codegen": ["codegen", "planar2", "--lang", "c", "-o", path],
        "identify_json": ["identify", "planar2", str(files / "log.csv"), "--json", path],
        "track_report": ["track", "planar2", "--duration", "0.02", "--report", path],
    }[cmd]
    if cmd == "track_report" and where == "dir":
        argv[-1] = str(files / "file.txt")  # a folder option given a file
    rc, _, err = run(argv)
    assert_one_line_error(rc, err)


def test_step_count_is_bounded_before_any_work():
    rc, _, err = run(["track", "planar2", "--controller-period", "1e-7", "--duration", "1"])
    line = assert_one_line_error(
        rc, err, "--duration 1 with --controller-period 1e-07", "4e+07 steps"
    )
    assert f"{MAX_STEPS:,} integration steps" in line
    rc, _, err = run(
        ["track", "planar2", "--controller-period", "1e-6"]
    )  # default duration: 2 cycles
    assert_one_line_error(rc, err, "the duration is two cycles unless given")


def test_simulate_step_count_is_bounded(files):
    argv = ["simulate", "planar2", "--trajectory", str(files / "traj.json"), "-o", "x.csv"]
    rc, _, err = run([*argv, "--duration", "1e5", "--rate", "1000"])
    assert_one_line_error(rc, err, "1e+08 samples", "at most 1,000,000 samples")


@pytest.mark.parametrize(
    "option, value, needle",
    [
        ("--quantization", "1e308", "--quantization: expected finite values in [0, 1]"),
        ("--torque-noise", "abc%", "--torque-noise: expected a percentage in [0, 100]"),
        ("--torque-noise", "1e308", "--torque-noise: expected finite values in [0, 1e+06]"),
        ("--velocity-noise", "nan", "--velocity-noise: expected finite values in [0, 100]"),
        # an empty value is no level (it was read as 0: a run without the noise asked for)
        ("--torque-noise", "", "--torque-noise: expected a number"),
        ("--position-noise", " ", "--position-noise: expected a number"),
        ("--quantization", "", "--quantization: expected a number"),
        ("--torque-noise", "1,,2", "--torque-noise: expected a number"),
    ],
)
def test_simulate_noise_levels_are_bounded(option, value, needle, files, tmp_path):
    out = tmp_path / "s.csv"
    argv = ["simulate", "planar2", "--trajectory", str(files / "traj.json"), "-o", str(out)]
    rc, _, err = run([*argv, option, value])
    assert_one_line_error(rc, err, needle)
    assert not out.exists()


def test_excite_rate_must_sample_the_highest_harmonic(tmp_path):
    out = str(tmp_path / "e.csv")
    # 5 harmonics of 10 Hz: the highest is 50 Hz, sampled only above 100 Hz
    rc, _, err = run(["excite", "planar2", "--freq", "10", "--rate", "100", "-o", out])
    assert_one_line_error(rc, err, "--rate 100", "expected a rate above 100 Hz")
    rc, _, err = run(["excite", "planar2", "--freq", "0.001", "--rate", "1e6", "-o", out])
    assert_one_line_error(rc, err, "rows", "at most 1,000,000")
    rc, _, err = run(["excite", "planar2", "--harmonics", "20", "--samples", "30", "-o", out])
    assert_one_line_error(rc, err, "--samples 30", "more than 2 x --harmonics = 40")
    rc, _, err = run(["excite", "planar2", "-o", str(tmp_path / "e.json")])
    assert_one_line_error(rc, err, "another suffix than .json")
    assert not (tmp_path / "e.json").exists()


def test_excite_at_a_valid_rate_writes_finite_rows(tmp_path):
    out = tmp_path / "e.csv"
    argv = ["excite", "planar2", "--quiet", "--starts", "1", "--maxiter", "3"]
    rc, _, err = run([*argv, "--rate", "3", "-o", str(out)])  # above 2 x 5 x 0.1 Hz = 1 Hz
    assert rc == 0, err
    rows = np.loadtxt(out, delimiter=",", skiprows=1, ndmin=2)
    assert rows.shape[0] == 31 and np.isfinite(rows).all()  # 10 s at 3 Hz, both ends


def test_cutoff_below_one_cycle_over_the_log_is_named(files):
    """A cutoff so low that the low-pass keeps only the mean (at 1e-300 Hz the filter design is
    also singular, or not, depending on the platform's arithmetic) is refused before the
    design, with the range that is accepted."""
    for cutoff, shown in (("1e-300", "1e-300"), ("1e-3", "0.001")):
        rc, _, err = run(["identify", "planar2", str(files / "log.csv"), "--cutoff", cutoff])
        assert_one_line_error(rc, err, f"cutoff {shown} Hz", "below one cycle over", "log.csv")


# ---------------------------------------------------------------------------------------------
# Too few equations per parameter
# ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def zcr_log():
    robot = mindyn.load("zcr07s")
    base = mindyn.base_parameters(robot)
    log = simulate_inverse(
        robot,
        random_trajectory(robot, seed=8),
        noise=SensorNoise(torque=0.01 * robot.limits["effort"]),
        seed=2,
    )
    return robot, base, log


def _head(log, m):
    return JointData(log.t[:m], log.q[:m], log.dq[:m], log.ddq_true[:m], log.tau[:m], "head", {})


@pytest.mark.parametrize("m", [20, 50])
def test_identify_refuses_a_log_with_too_few_equations_per_parameter(zcr_log, m):
    """The first 20 or 50 samples of a 6-joint log: 120 or 300 equations for 36 base
    parameters, fewer than 10 per parameter."""
    robot, base, log = zcr_log
    need = max(MIN_EQUATIONS_PER_PARAMETER["dynamic"] * base.n, base.n + MIN_NOISE_DOF)
    assert need == 360 and m * 6 < need
    with pytest.raises(IdentificationError) as e:
        identify(robot, _head(log, m), base=base)
    assert f"{m * 6} equations for 36 base parameters; at least 360 are needed" in str(e.value)
    assert "at least 60 samples" in str(e.value)


def test_identify_flags_pruning_of_most_parameters(zcr_log):
    """100 samples (0.4 s) pass the count but excite few parameters: pruning (at the ZCR07S
    study's 30 %) removes most of them and the kept estimates are far from the truth; the
    result says so."""
    robot, base, log = zcr_log
    res = identify(robot, _head(log, 100), base=base, rsd_threshold=30.0)
    assert 2 * len(res.removed) > base.n
    assert "kept estimates take up what the removed ones contribute" in res.settings["warnings"][0]
    full = identify(robot, _head(log, 2500), base=base, rsd_threshold=None)
    assert "warnings" not in full.settings


def test_identify_energy_window_and_bounds_in_the_api(zcr_log):
    robot, base, log = zcr_log
    data = _head(log, 2500)
    for kw in ({"energy_window": 0}, {"min_velocity": math.nan}, {"rsd_threshold": math.inf}):
        with pytest.raises(ValueError):
            identify(robot, data, base=base, model="energy", **kw)


def test_chunked_reduction_equals_the_stacked_least_squares(zcr_log, monkeypatch):
    """The dynamic model reduced chunk by chunk (chunks of 7 samples here, so that every
    chunk boundary and a ragged last chunk occur) gives numpy's least squares on the stacked
    regressor, weighted and not."""
    import mindyn.identification.estimation as ident

    robot, base, log = zcr_log
    data = _head(log, 400)
    monkeypatch.setattr(ident, "CHUNK_SAMPLES", 7)
    res = identify(robot, data, base=base, weighted=False, rsd_threshold=None)
    W, y, joint = dynamic_system(base, data)
    p, *_ = np.linalg.lstsq(W, y, rcond=None)
    np.testing.assert_allclose(res.values, p, rtol=1e-7, atol=1e-10)
    wls = identify(robot, data, base=base, rsd_threshold=None)
    r = y - W @ p
    sig = np.sqrt([np.sum(r[joint == j] ** 2) / np.sum(joint == j) for j in range(6)])
    sig /= math.sqrt((len(y) - base.n) / len(y))
    np.testing.assert_allclose(wls.joint_sigma, sig, rtol=1e-7)
    w = 1.0 / sig[joint]
    pw, *_ = np.linalg.lstsq(W * w[:, None], y * w, rcond=None)
    np.testing.assert_allclose(wls.values, pw, rtol=1e-7, atol=1e-10)
    tau_hat = (W @ res.full).reshape(-1, 6)
    scale = np.abs(tau_hat).max()  # round-off of sums of that size
    np.testing.assert_allclose(res.predict(data), tau_hat, rtol=1e-12, atol=1e-13 * scale)


# ---------------------------------------------------------------------------------------------
# Property: any mix of valid and invalid values obeys the contract of cli.main
# ---------------------------------------------------------------------------------------------
BAD = ["-1", "0", "inf", "-inf", "nan", "1e308", "99999999999999999999999", "", "x", "1e-300"]


def _value(valid):
    return st.one_of(st.sampled_from(valid), st.sampled_from(BAD))


def _argv(head, options, files, outputs):
    """A strategy of argument lists: ``head`` then, for each option, nothing, a valid value
    or a bad one (an n-tuple for options of several values)."""

    def opt(name, valid, nargs=1):
        value = _value(valid)
        if nargs > 1:
            value = st.lists(_value(valid), min_size=nargs, max_size=nargs)
        return st.one_of(
            st.none(), value.map(lambda v, n=name: [n, *v] if isinstance(v, list) else [n, v])
        )

    parts = [opt(*o) for o in options]
    for name in outputs:
        parts.append(
            st.sampled_from(
                [
                    [name, str(files / "out" / f"o{name.strip('-')}.csv")],
                    [name, ""],
                    [name, str(files)],
                    [name, str(files / "file.txt" / "x")],
                    [name, "/proc/mindyn-no-such-dir/x"],
                ]
            )
        )
    return st.tuples(*parts).map(lambda ps: [*head, *(a for p in ps if p for a in p)])


SPECS = {
    "info": (["info"], []),
    "base": (
        ["base", "planar2"],
        [("--rank-tolerance", ["1e-9", "1e-3"]), ("--snap", ["1e-3", "0.05"])],
    ),
    "excite": (
        ["excite", "planar2", "--quiet", "--starts", "1"],
        [
            ("--harmonics", ["2", "3"]),
            ("--freq", ["0.1", "1"]),
            ("--maxiter", ["1", "3"]),
            ("--samples", ["7", "30"]),
            ("--margin", ["0", "0.1"]),
            ("--rate", ["20", "50"]),
            ("--seed", ["0", "4294967295"]),
            ("--start", ["0.1,0.2", "0.1", "1,2,3"]),
        ],
    ),
    "simulate": (
        ["simulate", "planar2", "--trajectory", "TRAJ"],
        [
            ("--duration", ["0.05", "0.2"]),
            ("--rate", ["100", "250"]),
            ("--substeps", ["1", "2"]),
            ("--seed", ["3"]),
            ("--torque-noise", ["0.1", "1%", "0.1,0.2"]),
            ("--quantization", ["1e-4"]),
            ("--mode", ["tracking", "inverse"]),
            ("--controller-period", ["0.004", "0.01"]),
            ("--torque-unit", ["Nm", "permille"]),
        ],
    ),
    "track": (
        ["track", "planar2", "--cycle", "0.2"],
        [
            ("--duration", ["0.02", "0.1"]),
            ("--controller-period", ["0.004", "0.01"]),
            ("--cycle", ["0.1", "0.5"]),
            ("--param-error", ["0", "0.5"]),
            ("--seed", ["1"]),
            ("--position-noise", ["0", "1e-3"]),
            ("--velocity-noise", ["0", "1e-3"]),
            ("--substeps", ["1", "4"]),
            ("--controller", ["pd", "computed-torque", "adaptive-pd"]),
            ("--integrator", ["rk4", "scipy"]),
            ("--torque-limit", ["effort", "none"]),
        ],
    ),
    "identify": (
        ["identify", "planar2", "LOG"],
        [
            ("--rsd-threshold", ["0", "30"]),
            ("--cutoff", ["5", "20"]),
            ("--energy-window", ["1", "10"]),
            ("--min-velocity", ["0", "0.01"]),
            ("--model", ["dynamic", "energy", "integral"]),
            ("--integral-window", ["1", "40"]),
            ("--filter", ["butter", "savgol", "none"]),
            ("--integration", ["simpson", "trapezoid", "zoh"]),
            ("--validate", ["LOG", "TRAJ"]),
            ("--torque-unit", ["Nm", "permille"]),
        ],
    ),
    "ik": (
        ["ik", "planar2", "--timeout", "0.05"],
        [
            ("--xyz", ["0.5", "0", "0.3"], 3),
            ("--rpy", ["0", "1.5"], 3),
            ("--q0", ["0.1", "0.2"], 2),
            ("--pose-tolerance", ["1e-5", "1e-3"]),
            ("--timeout", ["0.01"]),
            ("--seed", ["0", "7"]),
        ],
    ),
    "codegen": (
        ["codegen", "planar2", "--lang", "c"],
        [
            ("--what", ["id", "gravity,regressor"]),
            ("--name", ["arm", "1bad"]),
            ("--params", ["LOG", "TRAJ", "FILES", "no_such.json"]),
        ],
    ),
}
OUTPUTS = {
    "excite": ["-o"],
    "simulate": ["-o"],
    "identify": ["--json"],
    "codegen": ["-o"],
    "track": ["-o"],
}
ROBOTS = ["planar2", "planar0", "planar9999999999999999999999", "", "no_such_robot", "planar2h"]


@pytest.mark.parametrize("cmd", sorted(SPECS))
def test_any_mix_of_values_gives_status_0_or_one_error_line(cmd, files, tmp_path_factory):
    head, options = SPECS[cmd]
    named = {"TRAJ": files / "traj.json", "LOG": files / "log.csv", "FILES": files}

    def real(a):
        return str(named[a]) if a in named else a

    head = [real(a) for a in head]
    options = [(o[0], [real(v) for v in o[1]], *o[2:]) for o in options]
    strategy = _argv(head, options, files, OUTPUTS.get(cmd, []))
    if cmd == "info":
        strategy = st.sampled_from(ROBOTS).map(lambda r: ["info", r])
    elif cmd == "ik":  # --xyz is required
        strategy = strategy.map(lambda a: a if "--xyz" in a else [*a, "--xyz", "0.5", "0", "0.3"])
    elif cmd == "track":  # keep the run short whatever the default duration
        strategy = strategy.map(lambda a: a if "--duration" in a else [*a, "--duration", "0.02"])
    elif cmd == "simulate":
        strategy = strategy.map(lambda a: a if "-o" in a else [*a, "-o", str(files / "s.csv")])

    @settings(
        max_examples=12,
        deadline=None,
        derandomize=True,
        database=None,
        suppress_health_check=[HealthCheck.too_slow],
    )
    @given(strategy)
    def check(argv):
        rc, _, err = run(argv)
        if rc != 0:
            assert_one_line_error(rc, err)

    check()


def test_last_resort_is_one_line_naming_the_exception(monkeypatch):
    """An exception no validation foresaw (a defect) still ends in one line, with its type and
    a request to report it, and its own exit status."""

    def broken(args):
        raise TypeError("first line\nsecond line")

    import mindyn.cli.info

    monkeypatch.setattr(mindyn.cli.info, "cmd_info", broken)
    rc, _, err = run(["info", "planar2"])
    assert rc == 70 and err.count("\n") == 1
    assert err.startswith("mindyn: error: unexpected TypeError: first line; second line")
    assert "a defect in mindyn; please report it" in err


@pytest.mark.parametrize(
    "argv",
    [
        ["base", "planar2", "--rank-tolerance", "1e-6", "--snap", "0.05"],
        ["excite", "planar2", "--quiet", "--starts", "1", "--maxiter", "3", "-o", "OUT/e.csv"],
        ["simulate", "planar2", "--trajectory", "TRAJ", "--duration", "0.2", "-o", "OUT/s.csv"],
        ["track", "planar2", "--cycle", "0.4", "--duration", "0.1", "-o", "OUT/t.csv"],
        ["identify", "planar2", "LOG", "--json", "OUT/i.json", "--model", "energy"]
        + ["--energy-window", "1"],
        # the tool pose at q = (0.3, 0.5) rad: (0.826, 0, 0.506) m, pitch -0.8 rad
        ["ik", "planar2", "--xyz", "0.826022", "0", "0.506438", "--rpy", "1.570796", "-0.8", "0"]
        + ["--pose-tolerance", "1e-3", "--seed", "4294967295"],
        ["codegen", "planar2", "--lang", "st", "-o", "OUT/g.st"],
    ],
)
def test_valid_values_at_their_bounds_run(argv, files, tmp_path):
    """The property test's valid values are accepted: each command runs with them."""
    named = {"TRAJ": str(files / "traj.json"), "LOG": str(files / "log.csv")}
    argv = [named.get(a, a).replace("OUT", str(tmp_path)) for a in argv]
    rc, _, err = run(argv)
    assert rc == 0, err


@pytest.mark.parametrize(
    "exc",
    [
        IndexError("index 3 is out of bounds for axis 0 with size 3"),
        ValueError("matmul: Input operand 1 has a mismatch in its core dimension 0"),
        KeyError("tau"),
        np.linalg.LinAlgError("Singular matrix"),
    ],
    ids=lambda e: type(e).__name__,
)
def test_a_bare_standard_error_is_a_defect_not_the_users(monkeypatch, exc):
    """Only mindyn's own errors (and a missing file) are the input's: a bare ValueError,
    IndexError, KeyError or LinAlgError escaping a command is a defect in mindyn, reported with
    its type and exit status 70, never as if the command line were wrong."""

    def broken(args):
        raise exc

    import mindyn.cli.info

    monkeypatch.setattr(mindyn.cli.info, "cmd_info", broken)
    rc, _, err = run(["info", "planar2"])
    assert rc == 70 and err.count("\n") == 1, err
    assert err.startswith(f"mindyn: error: unexpected {type(exc).__name__}: "), err
    assert "a defect in mindyn; please report it" in err


@pytest.mark.parametrize(
    "argv, needles",
    [
        (
            ["simulate", "planar2", "--mode", "inverse", "--controller", "pd", "-o", "x.csv"],
            ["--controller:", "--mode tracking"],
        ),
        (["identify", "planar2", "LOG", "--urdf", "out.urdf"], ["--urdf:", "--consistent"]),
        (
            [
                "identify",
                "planar2",
                "LOG",
                "--consistent",
                "--mjcf",
                "o.xml",
                "--friction",
                "--friction-model",
                "smooth",
            ],
            ["--mjcf:", "smooth friction model"],
        ),
        (
            [
                "identify",
                "planar2",
                "LOG",
                "--consistent",
                "--urdf",
                "o.urdf",
                "--friction-model",
                "dahl",
            ],  # fmt: skip
            ["--urdf:", "Dahl friction model", "no robot description holds it"],
        ),
        (
            ["identify", "planar2", "LOG", "--consistent", "--sidecar", "s.yaml"],
            ["--sidecar:", "--urdf or --yaml"],
        ),
        (
            ["identify", "planar2", "LOG", "--validate-currents", "c.csv"],
            ["--validate-currents:", "--validate"],
        ),
        (
            ["excite", "planar2", "--start", "100", "0", "-o", "e.csv"],
            ["--start 100 (value 1)", "[-2pi, 2pi]", "--deg"],
        ),
        (["excite", "planar2", "-o", "e.json"], ["-o e.json", ".json"]),
        (["excite", "planar2", "--samples", "3", "-o", "e.csv"], ["--samples 3", "--harmonics"]),
        (
            ["track", "planar2", "--controller", "pd", "--param-error", "10"],
            ["--param-error:", "--controller pd"],
        ),
        (["track", "planar2", "--cycle", "0.01"], ["--cycle 0.01 s", "--controller-period"]),
        (["track", "planar2", "--duration", "1e-9"], ["--duration 1e-09 s", "--controller-period"]),
    ],
)
def test_option_conflicts_are_usage_errors(argv, needles, files, monkeypatch):
    """Options that do not go together, or a value the other options rule out, are refused as
    the command line's error (exit status 2, naming the option), not as a defect."""
    monkeypatch.chdir(files)
    argv = [str(files / "log.csv") if a == "LOG" else a for a in argv]
    rc, _, err = run(argv)
    assert rc == 2
    assert_one_line_error(rc, err, *needles)


@pytest.mark.parametrize("cmd", ["predict", "detect"])
def test_an_identification_json_that_is_not_an_object_names_the_file(cmd, files, tmp_path):
    (tmp_path / "list.json").write_text("[1, 2]")
    argv = [cmd, "planar2", str(tmp_path / "list.json"), str(files / "log.csv")]
    if cmd == "predict":
        argv += ["-o", str(tmp_path / "p.csv")]
    rc, _, err = run(argv)
    assert rc == 2
    assert_one_line_error(
        rc, err, "list.json: expected a JSON object (the JSON of mindyn identify)"
    )


def _identification(path, **fields):
    """A hand-written identification JSON of planar2 (its own base-parameter values)."""
    base = mindyn.base_parameters(mindyn.load("planar2"))
    doc = {"robot": "planar2", "rotor": False, "friction": False, "offset": False}
    doc.update(
        base_names=list(base.names), base_values=[float(v) for v in base.values(base.robot.params)]
    )
    doc.update(fields)
    path.write_text(json.dumps(doc))
    return path


@pytest.mark.parametrize(
    "fields, needle",
    [
        ({"reading": [[1]]}, "'reading' is"),
        ({"reading": {"filter": 3}}, "'reading' filter is 3; expected one of lowpass"),
        ({"reading": {"cutoff_Hz": "x"}}, "'reading' cutoff_Hz"),
        ({"reading": {"drive_gain": "x"}}, "'reading' drive_gain is 'x'"),
        ({"base_names": {"a": 1}}, "'base_names' is"),
    ],
)
def test_an_identification_json_with_odd_fields_names_the_field(fields, needle, files, tmp_path):
    """Fields of the wrong JSON type were bare TypeError, AttributeError or ValueError (a list
    where 'reading' is an object, a mapping as base_names): now the file's error."""
    path = _identification(tmp_path / "id.json", **fields)
    for argv in (
        ["predict", "planar2", str(path), str(files / "log.csv"), "-o", str(tmp_path / "p.csv")],
        ["detect", "planar2", str(path), str(files / "log.csv")],
    ):
        rc, _, err = run(argv)
        assert rc == 2
        assert_one_line_error(rc, err, f"{path}:", needle)


def test_predict_with_another_filter_than_recorded_states_the_derived_cutoff(files, tmp_path):
    """--filter lowpass on an identification recorded with butter and no cut-off: the low-pass
    takes the log's own cut-off, and the output states it (it failed formatting None)."""
    from mindyn.identification.data import read_csv
    from mindyn.identification.preprocess import preprocess

    path = _identification(tmp_path / "id.json", reading={"filter": "butter", "cutoff_Hz": None})
    log = files / "log.csv"
    rc, out, err = run(
        [
            "predict",
            "planar2",
            str(path),
            str(log),
            "-o",
            str(tmp_path / "p.csv"),
            "--filter",
            "lowpass",
        ]
    )
    assert rc == 0, err
    # the low-pass path reads the log without derivative filter (every sample kept)
    fc = preprocess(read_csv(log, filter="none")).processing["preprocess"]["filter"]["cutoff_Hz"]
    assert f"low-pass at {fc:.4g} Hz, derived from the log" in out, out


def test_predict_on_a_log_without_torques(files, tmp_path):
    """A log without torque columns is what predict takes (it predicts them): it failed with a
    bare KeyError looking up the unit of the torques it does not have. The prediction is the
    inverse dynamics at the motion it writes."""
    path = _identification(tmp_path / "id.json")
    lines = (files / "log.csv").read_text().splitlines()
    head = [c.strip() for c in lines[0].split(",")]
    keep = [k for k, c in enumerate(head) if not c.startswith("tau")]
    log = tmp_path / "motion.csv"
    log.write_text(
        "\n".join(",".join(line.split(",")[k] for k in keep) for line in lines if line) + "\n"
    )
    out_csv = tmp_path / "p.csv"
    argv = ["predict", "planar2", str(path), str(log), "-o", str(out_csv), "--filter", "lowpass"]
    rc, out, err = run(argv)
    assert rc == 0, err
    rows = np.loadtxt(out_csv, delimiter=",", skiprows=1)
    assert open(out_csv).readline().strip() == "t,q1,q2,dq1,dq2,ddq1,ddq2,tau_hat1,tau_hat2"
    robot = mindyn.load("planar2")
    tau = robot.inverse_dynamics(rows[:, 1:3], rows[:, 3:5], rows[:, 5:7])
    scale = np.abs(tau).max()
    assert np.abs(rows[:, 7:9] - tau).max() <= 1e-9 * scale
