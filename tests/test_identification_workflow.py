"""The identification workflow as a library (:mod:`mindyn.identification.workflow`): the Python
API gives what ``mindyn identify`` prints and writes, its options are keyword-only with the
command line's defaults, and each quantity of the report is computed once."""

from __future__ import annotations

import json
import re

import mindyn
import numpy as np
import pytest
from conftest import cli
from mindyn.cli.flags import library_options_as_flags
from mindyn.identification import (
    IdentificationReport,
    IdentifyOptions,
    ReadingOptions,
    load_logs,
    run,
)


def _timeless(d):
    """``d`` without the solve times (the one field two runs do not share)."""
    if isinstance(d, dict):
        return {k: _timeless(v) for k, v in d.items() if k != "seconds"}
    if isinstance(d, list):
        return [_timeless(v) for v in d]
    return d


def _round_trip(doc: dict) -> dict:
    return _timeless(json.loads(json.dumps(doc)))


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    """A fit and a validation log of planar2 with friction and torque noise, and their truth."""
    from mindyn.control import SensorNoise, simulate_inverse
    from mindyn.identification.excitation import random_trajectory

    folder = tmp_path_factory.mktemp("workflow")
    robot = mindyn.load("planar2")
    paths = []
    for name, seed in (("fit", 3), ("val", 4)):
        traj = random_trajectory(robot, seed=seed)
        log = simulate_inverse(
            robot, traj, rate=100.0, friction=True, noise=SensorNoise(torque=0.02), seed=seed
        )
        paths.append(
            log.save(folder / f"{name}.csv", robot_name=robot.name, joint_names=robot.joint_names)
        )
    return robot, paths[0], paths[1]


def test_run_gives_the_json_of_identify_friction(logs, tmp_path):
    robot, fit, _ = logs
    report = run(robot, load_logs([fit], robot), friction=True)
    assert isinstance(report, IdentificationReport)
    out = tmp_path / "id.json"
    text = cli("identify", "planar2", fit, "--friction", "--json", out)
    assert _round_trip(report.to_dict()) == _timeless(json.loads(out.read_text()))
    # the terminal text is the command's, less the line naming the file it wrote, with the
    # library's keywords (the pruning choice's rsd_threshold=) as the command's flags
    assert library_options_as_flags(report.format()) + "\n" + f"wrote {out}\n" == text
    # and the estimate is the simulation's: the known answer of the generated data
    doc = report.to_dict()
    kept = [doc["base_names"].index(name) for name in doc["names"]]
    true, est = np.array(doc["true_values"])[kept], np.array(doc["values"])
    assert np.all(np.abs(est - true) <= 0.05 * np.abs(true).max()), (est, true)
    # every parameter the simulation gives a value (planar2 has no friction) is kept
    nonzero = {n for n, v in zip(doc["base_names"], doc["true_values"]) if v != 0}
    assert len(nonzero) >= 4 and nonzero <= set(doc["names"]), (nonzero, doc["names"])


def test_run_gives_the_json_of_identify_validate_consistent(logs, tmp_path, monkeypatch):
    from mindyn.identification.consistent import ConsistentResult

    robot, fit, val = logs
    calls = []
    original = ConsistentResult.mass_matrix_min_eig

    def counted(self, data):
        calls.append(1)
        return original(self, data)

    monkeypatch.setattr(ConsistentResult, "mass_matrix_min_eig", counted)
    opts = dict(friction=True, consistent=True)  # the prior's weight chosen from the data
    report = run(robot, load_logs([fit], robot, validate=[val]), **opts)
    text = report.format()
    doc = report.to_dict()
    assert len(calls) == 1  # computed once, in run(); the text and the JSON read it
    out = tmp_path / "id.json"
    argv = ["--validate", val, "--consistent", "--json", out]
    cli_text = cli("identify", "planar2", fit, "--friction", *argv)
    assert _round_trip(doc) == _timeless(json.loads(out.read_text()))
    assert doc["validation"]["file"] == str(val)
    assert doc["consistent_estimate"]["validation"]["estimate"] == "consistent"
    # the same lines but the solve's time, with the library's keywords as the command's flags
    assert not re.search(r"(?<![\w-])--[a-z]", text), text  # the library names keywords
    strip = [
        line.split(" s, ")[-1] if "s, prior weight" in line else line
        for line in library_options_as_flags(text).split("\n")
    ]
    cli_lines = cli_text.rstrip("\n").split("\n")[:-1]
    cli_strip = [
        line.split(" s, ")[-1] if "s, prior weight" in line else line for line in cli_lines
    ]
    assert strip == cli_strip


def test_validation_logs_are_filtered_at_the_fits_cutoff(logs):
    robot, fit, val = logs
    got = load_logs([fit], robot, validate=[val], cutoff=None)
    fit_cut = got.fit.logs[0].processing["preprocess"]["filter"]["cutoff_Hz"]
    val_cut = got.validation.logs[0].processing["preprocess"]["filter"]["cutoff_Hz"]
    assert got.cutoff == fit_cut == val_cut
    alone = load_logs([val], robot)  # read as a fit log, it gets its own cut-off
    assert alone.cutoff == alone.fit.logs[0].processing["preprocess"]["filter"]["cutoff_Hz"]


def test_options_are_keyword_only_with_the_command_lines_defaults(logs):
    from mindyn.cli import build_parser
    from mindyn.cli.identify import identify_options, reading_options

    robot, fit, _ = logs
    args = build_parser("identify").parse_args(["identify", "planar2", str(fit)])
    assert identify_options(args, robot) == IdentifyOptions()
    assert reading_options(args) == ReadingOptions()
    with pytest.raises(TypeError):
        IdentifyOptions("dynamic")
    with pytest.raises(TypeError):
        ReadingOptions("lowpass")
    data = load_logs([fit], robot)
    with pytest.raises(TypeError):
        run(robot, data, IdentifyOptions())
    with pytest.raises(TypeError):
        load_logs([fit], robot, [fit])


def test_workflow_errors_are_one_line_mindyn_errors(logs):
    robot, fit, _ = logs
    data = load_logs([fit], robot)
    with pytest.raises(mindyn.Error, match="unknown option"):
        run(robot, data, fricton=True)
    with pytest.raises(mindyn.Error, match="prior_weight=: expected consistent=True"):
        run(robot, data, prior_weight=1.0)
    with pytest.raises(mindyn.Error, match="not both"):
        run(robot, data, options=IdentifyOptions(), friction=True)
    with pytest.raises(mindyn.Error, match="edge= needs filter='lowpass'"):
        load_logs([fit], robot, filter="butter", edge=1.0)
    with pytest.raises(mindyn.Error, match="one per log"):
        load_logs([fit], robot, currents=[fit, fit])


def test_logs_read_otherwise_give_the_same_fit_and_no_reading_record(logs):
    from mindyn.identification import read_csv

    robot, fit, _ = logs
    loaded = run(robot, load_logs([fit], robot, filter="butter"), friction=True).to_dict()
    given = run(robot, [read_csv(fit, robot)], friction=True).to_dict()
    assert given["base_values"] == loaded["base_values"]
    assert loaded["reading"]["filter"] == "butter"
    assert given["reading"] is None  # how they were read is not known: not recorded


def test_logs_read_for_another_model_are_refused(logs):
    robot, fit, _ = logs
    with pytest.raises(mindyn.Error, match="load_logs\\(..., model='integral'\\)"):
        run(robot, load_logs([fit], robot), model="integral")
    got = run(robot, load_logs([fit], robot, model="integral"), model="integral")
    assert got.result.model == "integral"


def test_one_path_alone_is_one_log_and_an_unknown_model_is_named(logs):
    robot, fit, val = logs
    got = load_logs(fit, robot, validate=str(val))
    assert got.fit.files == [str(fit)] and got.validation.files == [str(val)]
    with pytest.raises(mindyn.ArgumentError, match="model is a str 'dynamc'"):
        load_logs([fit], robot, model="dynamc")


@pytest.mark.parametrize(
    "width", [-1, 0, float("nan"), "a", True, [], [0.1, -2.0], [0.1, "b"], [0.1, 0.2, 0.3]]
)
def test_a_friction_width_is_refused_naming_friction_width(logs, width):
    """A width that is not a positive number, or one per joint, is an argument error naming the
    keyword (as --friction-width is on the command line), not a TypeError or a bare
    ValueError."""
    robot, fit, _ = logs
    data = load_logs([fit], robot)
    with pytest.raises(mindyn.ArgumentError, match=r"^friction_width "):
        run(robot, data, friction=True, friction_model="smooth", friction_width=width)


def test_one_friction_width_is_every_joints(logs):
    robot, fit, _ = logs
    data = load_logs([fit], robot)
    for width in (0.05, [0.05], (0.05, 0.05), np.array([0.05, 0.05])):
        doc = run(robot, data, friction_model="smooth", friction_width=width).to_dict()
        assert doc["friction_model"]["velocity"] == [0.05, 0.05], doc["friction_model"]


def test_logs_read_for_another_robot_are_refused(logs, tmp_path):
    """planar2h has as many joints as planar2 (and the same joint names): logs read for one
    identify nothing of the other, and run() says so instead of fitting them."""
    import shutil

    robot, fit, _ = logs
    plain = tmp_path / "plain.csv"  # the log alone, without the truth sidecar naming planar2
    shutil.copy(fit, plain)
    other = mindyn.load("planar2h")
    assert other.n == robot.n and other.name != robot.name
    read = load_logs([plain], other)
    assert (read.robot, read.joints) == (other.name, tuple(other.joint_names))
    with pytest.raises(mindyn.ArgumentError, match=r"^logs were read for robot 'planar2h'"):
        run(robot, read, friction=True)
    with pytest.raises(mindyn.ArgumentError, match=r"^logs were read for robot 'planar2'"):
        run("planar2h", load_logs([plain], robot))
    # the same robot loaded again is the robot the logs were read for
    report = run(mindyn.load("planar2"), load_logs([plain], robot), friction=True)
    assert report.robot.name == "planar2"
