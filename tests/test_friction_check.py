"""The fitted friction of a model given or the default is checked to be dissipative
(:func:`~mindyn.identification.friction.dissipation_check`, the rule of ``auto``'s
:func:`~mindyn.identification.friction.active_friction`): a warning in the output and the
JSON's ``friction_model`` (``not_dissipative``, ``warning``) when it is not.

The logs are generated here: a multi-sine motion (analytic q, dq, ddq) with the rigid-body
torques plus friction written out. A least-squares line ``Fc + Fv v`` fitted to a Stribeck
curve stays positive over the speeds it was fitted on unless the breakaway is several times
the Coulomb level with little viscous friction: joint 3 of the stiction log has ``Fs = 8 Fc``
(breakaway 9 x Coulomb), ``Fv = 0``, Stribeck velocity 0.6 rad/s of its 2 rad/s; its Coulomb
fit then falls below zero at the largest speed by several standard deviations (about 8 on
this log)."""

from __future__ import annotations

import json
import re

import mindyn
import numpy as np
import pytest
from conftest import cli
from mindyn.identification import JointData, run, write_csv
from mindyn.identification.friction import dissipation_check, friction_lines
from random_arm import random_arm_yaml
from test_friction_models import multisine

FV, FC = np.array([0.8, 0.5, 0.0]), np.array([1.5, 1.0, 0.6])
FS, W = np.array([0.0, 0.0, 8 * FC[2]]), 0.6


def _log(robot, *, stiction: bool, seed: int = 2) -> JointData:
    """16 s at 200 Hz, white torque noise of 1 % of each joint's RMS; without ``stiction``
    viscous and Coulomb friction on every joint (joint 3 given Fv = 0.3 as well)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 16.0, 1 / 200)
    q, dq, ddq = multisine(robot.n, t, rng)
    s = np.sign(dq)
    fv = FV if stiction else np.array([0.8, 0.5, 0.3])
    tau = robot.inverse_dynamics(q, dq, ddq) + fv * dq + FC * s
    if stiction:
        tau += FS * s * np.exp(-((dq / W) ** 2))
    tau += 0.01 * tau.std(axis=0) * rng.standard_normal(tau.shape)
    return JointData(t, q, dq, ddq, tau, "stiction log" if stiction else "coulomb log")


@pytest.fixture(scope="module")
def setup(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("check")
    robot_path = random_arm_yaml(tmp / "arm.yaml", n=3, seed=4)
    arm = mindyn.load(robot_path)
    paths = {}
    for name, stiction in (("stiction", True), ("coulomb", False)):
        log = _log(arm, stiction=stiction)
        paths[name] = tmp / f"{name}.csv"
        write_csv(paths[name], log.t, log.q, log.tau, log.dq, log.ddq)
    return tmp, robot_path, arm, paths


def _identify(setup, log: str, *extra):
    tmp, robot_path, _, paths = setup
    out = cli("identify", robot_path, paths[log], "--friction", *extra, "--json", tmp / "id.json")
    return out, json.loads((tmp / "id.json").read_text())


def test_a_coulomb_fit_of_strong_stiction_is_warned_naming_the_joint(setup):
    out, doc = _identify(setup, "stiction")
    warned = [line for line in out.splitlines() if "WARNING: friction model" in line]
    assert len(warned) == 1, out
    line = warned[0]
    assert "friction model coulomb: the fitted friction drives the motion" in line
    assert "joint 3 at v = " in line and "joint 1" not in line and "joint 2" not in line
    assert line.endswith("try --friction-model stribeck or auto"), line
    fm = doc["friction_model"]
    assert fm["kind"] == "coulomb" and fm["chosen_by"] == "default"
    assert set(fm["not_dissipative"]) == {"coulomb"}
    assert "joint 3 at v = " in fm["not_dissipative"]["coulomb"]
    assert fm["warning"].endswith("try friction_model='stribeck' or 'auto'")
    # the value reported is the fitted Fc3 + Fv3 |v| at the speed reported (both printed to 3
    # significant digits), below zero
    m = re.search(r"joint 3 at v = (\S+): f\(v\) sign\(v\) = (\S+) \+- ([^;\s]+)", line)
    assert m, line
    v, value, std = (float(x) for x in m.groups())
    fit = dict(zip(doc["base_names"], doc["base_values"]))
    rounding = abs(fit["Fv3"]) * 0.005 * abs(v) + 0.005 * abs(value)
    assert fit["Fc3"] + fit["Fv3"] * abs(v) == pytest.approx(value, abs=rounding)
    assert fit["Fc3"] > 0 and fit["Fv3"] < 0 and value < -4 * std


def test_the_library_report_carries_the_check(setup):
    _, _, arm, paths = setup
    log = _log(arm, stiction=True)
    report = run(arm, [log], friction=True)
    rec = report.friction_record
    assert rec["warning"] and "joint 3 at v = " in rec["warning"]
    assert report.to_dict()["friction_model"]["warning"] == rec["warning"]
    assert f"  WARNING: {rec['warning']}" in report.format().splitlines()
    # given the Stribeck model, the remedy is auto (not the Stribeck model again)
    given = dissipation_check(report.result, [log], kind="stribeck")
    assert "friction model stribeck:" in given["warning"]
    assert "'stribeck' or" not in given["warning"]
    assert given["warning"].endswith("friction_model='auto' leaves out a model whose fitted "
                                     "friction is not friction")  # fmt: skip


def test_viscous_and_coulomb_friction_is_not_warned(setup):
    """Fc of 0.6 to 1.5 N m on every joint, fitted to some hundredths: f(v) sign(v) is tens of
    standard deviations above zero, no false alarm."""
    out, doc = _identify(setup, "coulomb")
    assert "WARNING: friction model" not in out, out
    fm = doc["friction_model"]
    assert fm["not_dissipative"] == {} and fm["warning"] is None
    fit = dict(zip(doc["base_names"], doc["base_values"]))
    for k, fc in enumerate(FC):
        assert fit[f"Fc{k + 1}"] == pytest.approx(fc, rel=0.1)


def test_the_stribeck_fit_of_the_stiction_log_is_not_warned(setup):
    out, doc = _identify(setup, "stiction", "--friction-model", "stribeck")
    assert "WARNING: friction model" not in out, out
    fm = doc["friction_model"]
    assert fm["kind"] == "stribeck" and fm["not_dissipative"] == {} and fm["warning"] is None
    fit = dict(zip(doc["base_names"], doc["base_values"]))
    assert fit["Fs3"] == pytest.approx(FS[2], rel=0.1) and fit["Fc3"] > 0


def test_auto_says_when_every_candidate_was_kept_though_not_friction():
    """When every candidate's fit drives the motion none is left out: the lines say so and
    warn, instead of calling each left out."""
    robot = mindyn.load("planar2")
    why = "the fitted friction drives the motion (...): joint 1 at v = 1: f(v) sign(v) = -1 +- 0.1"
    rec = {
        "kind": "coulomb",
        "chosen_by": "held-out data",
        "rule": "the rule",
        "candidates": {"coulomb": 1.0},
        "not_dissipative": {"coulomb": why},
        "warning": f"friction model auto, coulomb: {why} (as does ...)",
    }
    lines = friction_lines(robot, record=rec)
    assert (
        f"    coulomb: not left out (every candidate's fit is such), not friction here ({why})"
        in (lines)
    )
    assert lines[-1] == f"  WARNING: {rec['warning']}"


def test_auto_warns_when_every_candidate_drives_the_motion(setup):
    """A log whose friction torque pushes every joint along above 0.4 rad/s (Fv = -0.8, Fc =
    0.3: f(v) sign(v) = 0.3 - 0.8 |v|, -1 N m at 1.6 rad/s): every model's fit reproduces it,
    none is left out, each is reported so and the choice is warned of."""
    _, _, arm, _ = setup
    rng = np.random.default_rng(1)
    t = np.arange(0.0, 8.0, 1 / 200)
    q, dq, ddq = multisine(arm.n, t, rng)
    tau = arm.inverse_dynamics(q, dq, ddq) - 0.8 * dq + 0.3 * np.sign(dq)
    tau += 0.01 * tau.std(axis=0) * rng.standard_normal(tau.shape)
    report = run(arm, [JointData(t, q, dq, ddq, tau, "pushing log")], friction_model="auto")
    rec = report.friction_record
    assert set(rec["not_dissipative"]) == set(rec["candidates"]) and len(rec["candidates"]) > 1
    assert rec["warning"].startswith(f"friction model auto, {rec['kind']}: the fitted friction")
    assert all(f"joint {k}" in rec["warning"] for k in (1, 2, 3)), rec["warning"]
    text = report.format().splitlines()
    assert f"  WARNING: {rec['warning']}" in text
    assert not any(": left out, not friction here" in line for line in text)


def test_the_warning_needs_a_material_value_beyond_the_multiple_test_threshold(setup):
    """The warning's rule: the slot's value below zero by more than the Bonferroni threshold of
    2 n one-sided tests at the level of one ACTIVE_SIGMAS test (3 joints: 2.64 standard
    deviations, from the normal distribution written out here), and at least MATERIAL_SHARE of
    some joint's RMS torque. Joint 3 of the stiction log passes both; a threshold just above its
    z many times over, or a share many times its |value| / RMS torque, silences it."""
    from math import erfc, sqrt

    from mindyn.identification.friction import ACTIVE_SIGMAS, active_friction

    _, _, arm, _ = setup
    log = _log(arm, stiction=True)
    report = run(arm, [log], friction=True)
    res = report.result
    why = active_friction(res, [log])
    m = re.search(r"joint 3 at v = (\S+): f\(v\) sign\(v\) = (\S+) \+- ([^;\s]+)", why or "")
    assert m, why
    _, value, std = (float(x) for x in m.groups())
    z = -value / std
    # the threshold dissipation_check uses for n = 3 solves erfc(s / sqrt 2) / 2 = p / 6
    level = 0.5 * erfc(ACTIVE_SIGMAS / sqrt(2)) / (2 * arm.n)
    said = re.search(r"beyond (\S+) standard deviations", report.friction_record["warning"])
    threshold = float(said.group(1))
    assert 0.5 * erfc(threshold / sqrt(2)) == pytest.approx(level, rel=2e-3)
    assert threshold < z  # warned: beyond the threshold at the speed reported
    assert active_friction(res, [log], sigmas=10 * z) is None  # nowhere 10 z below zero
    # the value reported (the first speed found) over joint 3's RMS torque: at most the most
    # negative value's share, which the friction at the largest speed does not exceed tenfold
    share = abs(value) / np.sqrt(np.mean(log.tau[:, 2] ** 2))
    assert active_friction(res, [log], material=0.5 * share) is not None
    assert active_friction(res, [log], material=10.0 * share) is None
