"""What ``mindyn identify`` and the commands reading its JSON accept: logs of the robot named
(not of another one with as many joints), the chain ``--tip`` chose, the periods a periodic log
holds, well-typed identification JSON, solver failures and time bases the filters can take.
Each answer is checked against data the test generates (a simulated robot with known
parameters) or against the input's own structure."""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import mindyn
import pytest
from mindyn import cli

REPO = Path(__file__).resolve().parents[1]
UR5 = str(REPO / "examples/urdf/ur5.urdf")


def run(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main([str(a) for a in argv])
    return rc, out.getvalue(), err.getvalue()


def one_line_error(rc: int, err: str, *needles: str) -> str:
    assert rc != 0, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("mindyn: error: "), err
    assert "a defect in mindyn" not in lines[0], err
    for s in needles:
        assert s in lines[0], (s, err)
    return lines[0]


def simulate(path: Path, robot: str, *extra) -> Path:
    rc, out, err = run(
        ["simulate", robot, "--mode", "inverse", "--duration", "6", "-o", path, *extra]
    )
    assert rc == 0, err
    return path


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    d = tmp_path_factory.mktemp("inputs")
    return {
        "ur5": simulate(d / "ur5.csv", UR5),
        "zcr07s": simulate(d / "zcr07s.csv", "zcr07s"),
        "dir": d,
    }


# -- a log of another robot -----------------------------------------------------------------
def test_log_of_another_robot_with_as_many_joints_is_refused(logs):
    assert mindyn.load(UR5).n == mindyn.load("zcr07s").n  # the case: the columns fit
    rc, _, err = run(["identify", "zcr07s", logs["ur5"]])
    one_line_error(rc, err, "ur5.csv", "'ur5_example'", "not 'zcr07s'")
    rc, _, err = run(["identify", "zcr07s", logs["zcr07s"], "--validate", logs["ur5"]])
    one_line_error(rc, err, "ur5.csv", "'ur5_example'", "not 'zcr07s'")
    # the robot's own log: the true column comes from its sidecar
    rc, out, err = run(["identify", "zcr07s", logs["zcr07s"]])
    assert rc == 0, err
    assert "true values from" in out


def test_log_whose_sidecar_names_other_joints_is_refused(logs, tmp_path):
    log = tmp_path / "renamed.csv"
    log.write_text(Path(logs["zcr07s"]).read_text())
    truth = json.loads(Path(logs["zcr07s"]).with_suffix(".truth.json").read_text())
    robot = mindyn.load("zcr07s")
    assert truth["joints"] == robot.joint_names  # what simulate writes
    truth["robot"] = ""  # no name: the joints alone decide
    truth["joints"] = [f"other_{j}" for j in robot.joint_names]
    (tmp_path / "renamed.truth.json").write_text(json.dumps(truth))
    rc, _, err = run(["identify", "zcr07s", log])
    one_line_error(rc, err, "renamed.csv", "other_", "not those of robot 'zcr07s'")


# -- the chain --tip chose -----------------------------------------------------------------
def test_identify_json_records_the_tip_and_payload_uses_it(tmp_path):
    log = simulate(tmp_path / "five.csv", UR5, "--tip", "wrist_2_link")
    js = tmp_path / "five.json"
    rc, _, err = run(["identify", UR5, "--tip", "wrist_2_link", log, "--json", js])
    assert rc == 0, err
    assert json.loads(js.read_text())["tip"] == "wrist_2_link"
    # the payload log is the arm's own (no payload): the payload found is nothing
    pj = tmp_path / "payload.json"
    rc, out, err = run(["identify-payload", UR5, js, log, "--no-consistent", "--json", pj])
    assert rc == 0, err
    assert "--tip wrist_2_link" in out
    assert abs(json.loads(pj.read_text())["unconstrained"]["mass"]) < 1e-3
    rc, _, err = run(["identify-payload", UR5, "--tip", "wrist_3_link", js, log])
    one_line_error(rc, err, "--tip wrist_3_link", "--tip wrist_2_link")
    # without the tip in the JSON (an older file), the message says which option it may be
    doc = json.loads(js.read_text())
    del doc["tip"]
    js.write_text(json.dumps(doc))
    rc, _, err = run(["identify-payload", UR5, js, log])
    one_line_error(rc, err, "--tip")
