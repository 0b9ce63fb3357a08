"""A URDF transmission of a type the loader does not read (a plugin such as
my_pkg/HalfDifferentialTransmission, PR2's type attribute): its joints are modelled as driven
directly (a motor of their own, ratio 1), and the user is told so once, by the library (a
DriveTrainWarning from mindyn.load) and by every command that loads the robot (one line on
stderr), and the JSON outputs record it; --drive-side joint makes the direct drive explicit
and silences it; export keeps the transmission as written and says its joints were written as
directly driven."""

from __future__ import annotations

import contextlib
import io
import json
import warnings

import mindyn
import numpy as np
import pytest
from mindyn.cli import main
from test_transmissions import arm_urdf, simple

TYPE = "my_pkg/HalfDifferentialTransmission"
NOTE = "transmission(s) of a type not read"


def half(ros2: bool = False) -> str:
    """A transmission of a type not read driving j2 and j3 (two actuators, as a differential)."""
    if ros2:
        return (
            f"<transmission name='half'><plugin>{TYPE}</plugin>"
            "<actuator name='ma' role='actuator1'/><actuator name='mb' role='actuator2'/>"
            "<joint name='j2' role='joint1'/><joint name='j3' role='joint2'/></transmission>"
        )
    return (
        f"<transmission name='half'><type>{TYPE}</type>"
        "<joint name='j2'/><joint name='j3'/>"
        "<actuator name='ma'><mechanicalReduction>30</mechanicalReduction></actuator>"
        "<actuator name='mb'><mechanicalReduction>30</mechanicalReduction></actuator>"
        "</transmission>"
    )


def write_arm(tmp_path, ros2: bool = False):
    """Three revolute joints: j1 through a SimpleTransmission of 50, j2 and j3 through 'half'."""
    path = tmp_path / "arm.urdf"
    path.write_text(arm_urdf(3, simple("t1", "j1", "m1", 50.0, ros2=ros2) + half(ros2), ros2))
    return path


def check_note(text: str, explicit: str = "--drive-side joint") -> None:
    """The note names the transmission, its type and its joints, what is assumed and how to
    make it explicit (``explicit``: the command's flag, the library's keyword)."""
    assert "'half'" in text and TYPE in text and "'j2', 'j3'" in text, text
    assert "driven directly" in text and "ratio 1" in text, text
    assert explicit in text and "silences" in text, text
    assert "SimpleTransmission" in text, text  # the types that are read


@pytest.mark.parametrize("ros2", [False, True], ids=["ros1", "ros2"])
def test_load_warns_once_and_models_the_joints_as_driven_directly(tmp_path, ros2):
    path = write_arm(tmp_path, ros2)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = mindyn.load(path)
    notes = [w for w in caught if issubclass(w.category, mindyn.DriveTrainWarning)]
    assert len(notes) == 1, [str(w.message) for w in caught]
    check_note(str(notes[0].message), explicit="drive_side='joint'")
    assert str(path) in str(notes[0].message)
    # what the model is: j1 through its reduction, j2 and j3 each by a motor of its own
    tr = robot.transmission
    np.testing.assert_array_equal(tr.T, np.diag([50.0, 1.0, 1.0]))
    assert tr.motors == ("m1", "j2", "j3") and tr.types[1:] == ("direct", "direct")
    (rec,) = robot.unread_transmissions
    assert rec["name"] == "half" and rec["type"] == TYPE and rec["joints"] == ["j2", "j3"]
    assert rec["modelled_directly"] == ["j2", "j3"] and rec["assumed"] == "direct drive"
    assert rec["line"] >= 1
    # a robot derived from it keeps the record and does not warn again
    with warnings.catch_warnings():
        warnings.simplefilter("error", mindyn.DriveTrainWarning)
        assert robot.with_drive_side("joint").unread_transmissions[0]["name"] == "half"
        assert mindyn.load(robot) is robot


def test_no_note_when_the_unread_transmission_drives_no_joint_of_the_model(tmp_path):
    path = write_arm(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error", mindyn.DriveTrainWarning)
        robot = mindyn.load(path, tip="l1")  # j2 and j3 are off the chain
    assert robot.n == 1 and robot.unread_transmissions[0]["modelled_directly"] == []


def test_pr2_type_attribute_is_noted_too(tmp_path):
    """PR2's belt compensator (a compliant belt, no linear map) in its type attribute."""
    other = (
        "<transmission name='pr2' type='pr2_mechanism_model/PR2BeltCompensatorTransmission'>"
        "<actuator name='x'/><joint name='j1'/><mechanicalReduction>1</mechanicalReduction>"
        "</transmission>"
    )
    path = tmp_path / "pr2.urdf"
    path.write_text(arm_urdf(2, other))
    with pytest.warns(mindyn.DriveTrainWarning, match="'pr2' of type 'pr2_mechanism_model/"):
        robot = mindyn.load(path)
    assert robot.transmission is None  # every joint driven directly, on the joint side
    assert robot.unread_transmissions[0]["modelled_directly"] == ["j1"]


def run(*argv) -> tuple[str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main([str(a) for a in argv])
    assert rc == 0, f"mindyn {' '.join(map(str, argv))}: exit {rc}\n{err.getvalue()}"
    return out.getvalue(), err.getvalue()


def noted_once(err: str) -> None:
    lines = [line for line in err.splitlines() if NOTE in line]
    assert len(lines) == 1, err
    assert lines[0].startswith("mindyn: warning: ")
    check_note(lines[0])


def test_every_command_prints_the_note_once_and_the_json_records_it(tmp_path):
    path = write_arm(tmp_path)
    log = tmp_path / "log.csv"
    ident = tmp_path / "id.json"
    base_json = tmp_path / "base.json"
    commands = [
        ["info", path],
        ["base", path, "--rotor", "--friction", "--json", base_json],
        ["codegen", path, "--lang", "c", "--rotor", "--friction", "-o", tmp_path / "gen"],
        ["track", path, "--duration", "0.2", "--report", tmp_path / "rep"],
        ["simulate", path, "--mode", "inverse", "--duration", "4", "--friction"]
        + ["--torque-noise", "0.01", "-o", log],
        [
            "identify",
            path,
            log,
            "--friction",
            "--consistent",
            "--prior-weight",
            "1",
            "--json",
            ident,
        ],
        ["predict", path, ident, log, "-o", tmp_path / "pred.csv"],
        ["export", path, ident, "--urdf", tmp_path / "out.urdf"],
    ]
    outputs = {}
    for argv in commands:
        out, err = run(*argv)
        noted_once(err)
        outputs[argv[0]] = out
    records = [
        json.loads(base_json.read_text()),
        json.loads(ident.read_text()),
        json.loads((tmp_path / "log.truth.json").read_text())["simulation"],
        json.loads((tmp_path / "rep" / "summary.json").read_text()),
    ]
    for doc in records:
        (rec,) = doc["unread_transmissions"]
        assert rec["name"] == "half" and rec["type"] == TYPE
        assert rec["modelled_directly"] == ["j2", "j3"] and rec["assumed"] == "direct drive"
    # export: the transmission it did not read is kept as written, and its note says so
    text = (tmp_path / "out.urdf").read_text()
    assert f"<type>{TYPE}</type>" in text and "SimpleTransmission" in text
    assert (
        "transmission 'half' (my_pkg/HalfDifferentialTransmission) was not read"
        in (outputs["export"])
    )
    with pytest.warns(mindyn.DriveTrainWarning):
        again = mindyn.load(tmp_path / "out.urdf")
    assert again.unread_transmissions[0]["joints"] == ["j2", "j3"]


def test_drive_side_joint_makes_the_direct_drive_explicit_and_silences_the_note(tmp_path):
    path = write_arm(tmp_path)
    _, err = run("base", path, "--rotor", "--friction", "--drive-side", "joint")
    assert NOTE not in err, err
    _, err = run("base", path, "--rotor", "--friction")
    noted_once(err)


def test_excite_records_the_note_in_its_json(tmp_path):
    path = write_arm(tmp_path)
    csv = tmp_path / "exc.csv"
    argv = ["excite", path, "--friction", "--harmonics", "2", "--starts", "1"]
    _, err = run(*argv, "--maxiter", "5", "--quiet", "-o", csv)
    noted_once(err)
    (rec,) = json.loads(csv.with_suffix(".json").read_text())["unread_transmissions"]
    assert rec["name"] == "half" and rec["modelled_directly"] == ["j2", "j3"]


def test_pr2_form_named_like_a_read_type_is_told_apart_from_the_types_read(tmp_path):
    """A type attribute naming a read type short (<transmission type="DifferentialTransmission">,
    which neither ros_control nor PR2's loader reads) is not read; the note listed the types read
    by their short names, 'DifferentialTransmission' among them, and then this transmission 'of
    type DifferentialTransmission' as not read. It names the types read in full, with where they
    are written."""
    pr2 = (
        "<transmission name='half' type='DifferentialTransmission'><actuator name='ma'/>"
        "<joint name='j2'/><mechanicalReduction>30</mechanicalReduction></transmission>"
    )
    path = tmp_path / "arm.urdf"
    path.write_text(arm_urdf(3, simple("t1", "j1", "m1", 50.0) + pr2, False))
    with pytest.warns(mindyn.DriveTrainWarning) as caught:
        mindyn.load(path)
    text = str(caught[0].message)
    assert "'half' of type 'DifferentialTransmission'" in text, text
    read = text.split("of a type not read (")[1].split(", are)")[0]
    for kind in ("Simple", "Differential", "FourBarLinkage"):
        assert f"transmission_interface/{kind}Transmission" in read, read
    for kind in ("Simple", "Wrist"):
        assert f"pr2_mechanism_model/{kind}Transmission" in read, read
    assert "<type> element" in read and "type attribute" in read, read
    assert "(DifferentialTransmission," not in text
