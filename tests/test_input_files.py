"""Files a user gives where another kind is expected, and logs whose headers or motion the
reader's checks could misjudge: each is refused in one line naming the file and what it is, or
read right. The expectations come from the files the tests write (their columns, their units,
the torques of a known robot), not from the reader."""

from __future__ import annotations

import contextlib
import io
import json
import re
from pathlib import Path

import mindyn
import numpy as np
import pytest
from mindyn import cli
from mindyn.identification.data import DataError, read_csv, write_csv
from mindyn.identification.excitation import FourierTrajectory
from mindyn.identification.torque_units import check_torque_units

REPO = Path(__file__).resolve().parents[1]
UR5 = REPO / "examples/urdf/ur5.urdf"


def run(argv: list) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main([str(a) for a in argv])
    return rc, out.getvalue(), err.getvalue()


def one_line_error(rc: int, err: str) -> str:
    lines = err.strip().splitlines()
    assert rc == 2 and len(lines) == 1 and lines[0].startswith("mindyn: error: "), (rc, err)
    assert "a defect in mindyn" not in lines[0]
    return lines[0]


def write_log(path: Path, header: list[str], rows: np.ndarray) -> Path:
    lines = [",".join(header)] + [",".join(repr(float(x)) for x in row) for row in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_log_of_fewer_joints_names_each_missing_column_once(tmp_path):
    """predict reads logs whose torques are optional: a 4-joint log for a 6-joint robot names
    q5, q6, dq5, dq6, tau5, tau6, each once (tau5 and tau6 were named twice)."""
    n = 4
    header = ["t"] + [f"{k}{j}" for k in ("q", "dq", "tau") for j in range(1, n + 1)]
    path = write_log(tmp_path / "four.csv", header, np.zeros((5, len(header))))
    with pytest.raises(DataError) as e:
        read_csv(path, mindyn.load("puma560"), require_torque=False)
    said = re.search(r"missing ([^;)]*)", str(e.value)).group(1).split(", ")
    assert said == ["q5", "q6", "dq5", "dq6", "tau5", "tau6"]


@pytest.mark.parametrize(
    "text, kind",
    [
        (UR5.read_text(), "XML"),
        (json.dumps({"base_names": ["ZZR1"], "base_values": [1.0]}, indent=1), "JSON"),
        ("[1, 2, 3]\n", "JSON"),
        ("name: arm\nconvention: dh\njoints: []\n", "YAML"),
    ],
)
def test_a_file_of_another_kind_given_for_a_log_says_what_it_is(tmp_path, text, kind):
    path = tmp_path / "given.csv"
    path.write_text(text)
    with pytest.raises(DataError) as e:
        read_csv(path, mindyn.load("puma560"))
    said = str(e.value)
    assert said.startswith(f"{path}: not a CSV table") and f"is {kind}" in said, said
    rc, _, err = run(["identify", "puma560", path])
    assert "not a CSV table" in one_line_error(rc, err)


def test_units_of_the_motion_in_a_header_are_refused_with_the_map_that_reads_them(tmp_path):
    """A header's unit is read on the torque columns only: q1[deg] was refused as an unknown
    column whose remedy (rename it q1) read degrees as radians. The message gives a column map;
    read through it, the file's degrees are the radians the test wrote."""
    robot = mindyn.load("planar2")
    rng = np.random.default_rng(0)
    t = np.arange(400) / 100.0
    q = 0.3 * np.sin(np.outer(t, [1.0, 1.7]))
    dq = 0.3 * np.cos(np.outer(t, [1.0, 1.7])) * [1.0, 1.7]
    tau = robot.inverse_dynamics(q, dq, np.zeros_like(q)) + rng.normal(0, 1e-3, q.shape)
    header = ["t", "q1[deg]", "q2[deg]", "dq1[deg]", "dq2[deg]", "tau1", "tau2"]
    rows = np.column_stack([t, np.rad2deg(q), np.rad2deg(dq), tau])
    path = write_log(tmp_path / "deg.csv", header, rows)
    with pytest.raises(DataError) as e:
        read_csv(path, robot)
    said = str(e.value)
    assert "column 'q1[deg]' (column 2)" in said, said
    given = re.search(r"\(columns=\), its QUANTITY=NAME pairs '([^']*)'", said).group(1)
    assert given == "t=t,q[deg]=q{j}[deg],dq[deg/s]=dq{j}[deg],tau=tau{j}"
    data = read_csv(path, robot, columns=dict(pair.split("=") for pair in given.split(",")))
    k = np.searchsorted(t, data.t)  # the samples kept (the derivative's edges dropped)
    assert data.t.size > 300 and np.array_equal(t[k], data.t)
    np.testing.assert_allclose(data.q, q[k], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(data.dq, dq[k], rtol=1e-12, atol=1e-15)
    rc, _, err = run(["identify", "planar2", path])
    assert "(--columns), its QUANTITY=NAME pairs 't=t,q[deg]=" in one_line_error(rc, err)


def still_states(robot, q_still: np.ndarray, m: int = 500, moving=()):
    """Time stamps at 100 Hz and states at rest at ``q_still``, except the joints ``moving``,
    which follow slow sines."""
    t = np.arange(m) / 100.0
    q = np.tile(q_still, (m, 1))
    dq, ddq = np.zeros_like(q), np.zeros_like(q)
    for k, j in enumerate(moving):
        w = 0.5 + 0.3 * k
        q[:, j] += 0.4 * np.sin(w * t)
        dq[:, j] = 0.4 * w * np.cos(w * t)
        ddq[:, j] = -0.4 * w * w * np.sin(w * t)
    return t, q, dq, ddq


def test_joints_at_rest_are_not_taken_for_torques_in_another_unit():
    """A robot held still logs its gravity torques, constant: the unit check compared their
    round-off with the description's and refused the log as torques -2.6e15 times too large
    (joints 1, 3, 4, 5 of zcr07s). Logged as N m, such a log passes the check."""
    robot = mindyn.load("zcr07s")
    t, q, dq, ddq = still_states(robot, np.full(robot.n, 0.1))
    tau = robot.inverse_dynamics(q, dq, ddq, robot.parameters(rotor=True, friction=True))
    check_torque_units(t, q, dq, tau, robot, "still.csv", "")


def test_a_joint_at_rest_beside_moving_ones_leaves_the_check_of_the_others():
    """Joint 1 of zcr07s (vertical axis, no gravity torque) at rest, the others moving: the
    moving joints' torques in mN m are still refused, naming a moving joint, not joint 1."""
    robot = mindyn.load("zcr07s")
    t, q, dq, ddq = still_states(robot, np.full(robot.n, 0.1), moving=range(1, robot.n))
    tau = robot.inverse_dynamics(q, dq, ddq, robot.parameters(rotor=True, friction=True))
    check_torque_units(t, q, dq, tau, robot, "log.csv", "")
    with pytest.raises(DataError) as e:
        check_torque_units(t, q, dq, 1000 * tau, robot, "log.csv", "")
    said = re.search(r"the torques of joint ([0-9]+) .* are ([0-9.]+) times", str(e.value))
    assert said and said.group(1) != "1", str(e.value)
    assert 900 < float(said.group(2)) < 1100, str(e.value)  # low-passed at 2 Hz: about 1000


def test_a_still_log_is_refused_for_not_moving(tmp_path):
    robot = mindyn.load("zcr07s")
    t, q, dq, ddq = still_states(robot, np.full(robot.n, 0.1))
    tau = robot.inverse_dynamics(q, dq, ddq, robot.parameters(rotor=True, friction=True))
    path = tmp_path / "still.csv"
    write_csv(path, t, q, tau, dq=dq)
    rc, _, err = run(["identify", "zcr07s", path, "--rotor", "--friction"])
    line = one_line_error(rc, err)
    assert "do not move" in line and "times the description's" not in line, line


@pytest.fixture(scope="module")
def excitation_json(tmp_path_factory) -> Path:
    rng = np.random.default_rng(1)
    traj = FourierTrajectory(
        rng.normal(0, 0.1, (2, 3)), rng.normal(0, 0.1, (2, 3)), [0.1, 0.2], 0.2
    )
    path = tmp_path_factory.mktemp("excite") / "traj.json"
    path.write_text(json.dumps({"robot": "planar2", "trajectory": traj.to_dict()}))
    return path


def test_an_excitation_json_reads_back_its_series(excitation_json):
    d = json.loads(excitation_json.read_text())["trajectory"]
    t = np.linspace(0, 5, 11)
    q, dq, ddq = FourierTrajectory.load(excitation_json).evaluate(t)
    w = 2 * np.pi * d["freq"] * np.arange(1, 4)
    a, b = np.array(d["a"]), np.array(d["b"])
    want = (
        np.array(d["q0"]) + (np.sin(np.outer(t, w)) / w) @ a.T - (np.cos(np.outer(t, w)) / w) @ b.T
    )
    np.testing.assert_allclose(q, want, atol=1e-14)


@pytest.mark.parametrize(
    "change, said",
    [
        ({"a": "x"}, "entry 'a' is not a list of lists of numbers"),
        ({"freq": "x"}, "entry 'freq' is not a number"),
        ({"q0": [[0.1, 0.2]]}, "entry 'q0' is not a list of numbers"),
        ({"b": [[float("nan")] * 3] * 2}, "entry 'b' holds NaN or infinite values"),
        ({"freq": -1.0}, "base frequency must be positive"),
        ({"q0": [0.1]}, "do not fit together"),
    ],
)
def test_a_malformed_excitation_json_is_named_with_its_entry(
    tmp_path, excitation_json, change, said
):
    doc = json.loads(excitation_json.read_text())
    doc["trajectory"].update(change)
    path = tmp_path / "traj.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(DataError) as e:
        FourierTrajectory.load(path)
    assert str(e.value).startswith(f"{path}: ") and said in str(e.value), str(e.value)
    rc, _, err = run(["simulate", "planar2", "--trajectory", path, "-o", tmp_path / "s.csv"])
    assert said in one_line_error(rc, err)


@pytest.mark.parametrize(
    "doc, kind",
    [
        ({"robot": "planar2", "base_names": ["ZZR1"], "base_values": [1.0]}, "identification"),
        ({"robot": "planar2", "names": [], "values": [], "simulation": {}}, "truth file"),
        ({"robot": "planar2", "thresholds": [1, 1], "base_names": []}, "thresholds"),
        ({"trajectory": 5}, "expected a mapping of the Fourier coefficients"),
    ],
)
def test_another_json_given_for_an_excitation_says_what_it_is(tmp_path, doc, kind):
    path = tmp_path / "other.json"
    path.write_text(json.dumps(doc))
    rc, _, err = run(["track", "planar2", "--trajectory", path])
    line = one_line_error(rc, err)
    assert f"error: {path}: " in line and kind in line, line


def test_order_names_its_flag_and_the_parameters_named_twice_or_missing():
    names = mindyn.load("planar2").parameter_names()
    given = names[:5] + [names[0]]
    rc, _, err = run(["base", "planar2", "--order", ",".join(given)])
    line = one_line_error(rc, err)
    assert line.startswith(f"mindyn: error: --order must name each of the {len(names)} ")
    assert f"named twice: {names[0]}" in line
    assert f"{len(names) - 5} missing: {', '.join(names[5:13])}, ..." in line


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs Linux's /proc")
@pytest.mark.parametrize(
    "argv", [["base", "planar2", "--json"], ["simulate", "planar2", "--duration", "0.1", "-o"]]
)
def test_an_output_that_cannot_be_created_exits_with_status_1(argv):
    """errors.md: an output that cannot be written is a limit of the machine, status 1 (a file
    in /proc cannot be created: it was taken for a missing input, status 2, '[Errno 2] ...')."""
    path = "/proc/mindyn-output/x.csv"
    rc, _, err = run([*argv, path])
    lines = err.strip().splitlines()
    assert rc == 1 and len(lines) == 1, (rc, err)
    assert lines[0].startswith("mindyn: error: '/proc/mindyn-output") and "Errno" not in lines[0]
    rc, _, err = run(["base", "/proc/mindyn-no-robot.yaml"])  # a missing input stays status 2
    assert rc == 2 and "does not exist" in err


@pytest.mark.parametrize(
    "given, taken", [("30", 30.0), ("30%", 30.0), (" 5.5 %", 5.5), ("auto", "auto")]
)
def test_rsd_threshold_takes_a_percentage_with_or_without_its_sign(given, taken):
    """--rsd-threshold is a percentage, as simulate's --torque-noise P% is: '30%' was refused."""
    argv = ["identify", "planar2", "log.csv", "--rsd-threshold", given]
    assert cli.build_parser("identify").parse_args(argv).rsd_threshold == taken


def zcr07s_log(path: Path, shift: float = 0.0) -> tuple[Path, np.ndarray]:
    """A 20-s zcr07s log within its limits, joint 2 shifted by ``shift`` rad (another zero, or
    another robot's positions), torques of the description's inverse dynamics there."""
    robot = mindyn.load("zcr07s")
    lower, upper = np.array(robot.limits["lower"]), np.array(robot.limits["upper"])
    t = np.arange(2000) / 100.0
    mid, half = (lower + upper) / 2, 0.4 * (upper - lower) / 2
    w = 0.3 + 0.05 * np.arange(robot.n)
    q = mid + half * np.sin(np.outer(t, w))
    dq = half * w * np.cos(np.outer(t, w))
    ddq = -half * w * w * np.sin(np.outer(t, w))
    q[:, 1] += shift
    tau = robot.inverse_dynamics(q, dq, ddq, robot.parameters(rotor=True, friction=True))
    write_csv(path, t, q, tau, dq=dq)
    return path, q


def test_a_log_far_beyond_the_limits_is_warned_of(tmp_path):
    """A log of another robot with as many joints and no truth sidecar was fitted without a word
    (a UR5's log fitted as zcr07s: 34 % error, blamed on the excitation). Positions beyond a
    joint's limits by more than their range are named; positions within them are not."""
    robot = mindyn.load("zcr07s")
    inside, _ = zcr07s_log(tmp_path / "inside.csv")
    assert "beyond_limits" not in read_csv(inside, robot).processing
    path, q = zcr07s_log(tmp_path / "shifted.csv", shift=3.0)
    found = read_csv(path, robot).processing["beyond_limits"]
    assert [f["joint"] for f in found] == [2]
    assert found[0]["reached"] == pytest.approx(q[:, 1].max(), rel=1e-10)  # 12 digits
    assert (found[0]["lower"], found[0]["upper"]) == (
        robot.limits["lower"][1],
        robot.limits["upper"][1],
    )
    rc, out, err = run(["identify", "zcr07s", inside, "--validate", path, "--rotor", "--friction"])
    assert rc == 0, err
    said = [line for line in out.splitlines() if "WARNING" in line and "limits" in line]
    assert len(said) == 1 and f"{path}: the positions of joint 2 ('j2') reach" in said[0], out
    rc, out, _ = run(["identify", "--help"])  # its help, which states the form, prints
    assert rc == 0 and "(P or P%)" in " ".join(out.split())
