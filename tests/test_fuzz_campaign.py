"""Smoke test of the fuzz campaign tool (fuzz/campaign.py): its classification of outcomes and
one tiny seeded run. The campaign itself is too slow for the test suite (see fuzz/README.md)."""

from __future__ import annotations

import json
import os
import signal
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "fuzz"))
campaign = pytest.importorskip("campaign")


@pytest.mark.parametrize(
    "code, err, kind",
    [
        (0, "", "ok"),
        (2, "mindyn: error: --period must be a number > 0\n", "error"),
        (2, "usage: mindyn base ...\nmindyn: error: bad\n", "error"),
        (2, "x.py:3: RuntimeWarning: overflow\nmindyn: error: bad\n", "unclear"),
        (1, "Traceback (most recent call last):\n  ...\nKeyError: 1\n", "trace"),
        (70, "mindyn: error: unexpected KeyError: 1 (a defect in mindyn)\n", "internal"),
        (1, "mindyn: error: out of memory: the input asks for more\n", "memory"),
    ],
)
def test_cli_outcomes_are_classified(code, err, kind):
    assert campaign.cli_class(code, "", err)[0] == kind


def _segfault():
    os.kill(os.getpid(), signal.SIGSEGV)


def _sleep():
    import time

    time.sleep(30)


def _held_mib() -> int:
    """The resident memory of this process now [MiB]."""
    with open("/proc/self/statm") as f:
        pages = int(f.read().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") >> 20


def _allocate():
    import numpy as np

    # 500 MiB above the parent's resident memory, touched: a forked child counts at most the
    # pages it shares with its parent, so its peak is at least this and at most their sum
    a = np.ones((_held_mib() + 500) << 17)
    return ("ok", str(a.sum()))


@pytest.mark.parametrize(
    "fn, timeout, kind", [(_segfault, 10, "crash"), (_sleep, 1, "hang"), (_allocate, 20, "memory")]
)
def test_child_failures_are_findings(fn, timeout, kind):
    """A signal, a case past its timeout and a peak RSS past the limit (here 200 MiB above what
    the test process holds now) are findings, not passes."""
    assert campaign.run_child(fn, timeout, _held_mib() + 200)[0] == kind


def test_oracle_catches_an_inconsistent_base_set():
    """check_base compares W_b (Y pi) with Newton-Euler: a base set of another robot's geometry
    (the same joint count and parameter layout, another regrouping) is a wrong answer."""
    import mindyn
    import numpy as np

    robot = mindyn.load("planar3")
    other = mindyn.base_parameters(mindyn.load("puma560_3"))
    ok = campaign.check_base(
        robot, mindyn.base_parameters(robot), False, False, np.random.default_rng(0)
    )
    assert ok[0] == "ok"
    assert campaign.check_base(robot, other, False, False, np.random.default_rng(0))[0] == "wrong"


def test_the_floating_oracle_catches_an_inconsistent_base_set(tmp_path):
    """check_floating_base compares W_b (Y pi) with the multibody inverse dynamics at states
    with unit quaternions: the base set of the robot passes, that of another geometry with the
    same joints (the same layout) is a wrong answer."""
    import mindyn
    import numpy as np

    def floating(length: float):
        path = tmp_path / f"arm{length}.urdf"
        path.write_text(_TWO_LINKS.format(length=length))
        return mindyn.load(path, root_joint="floating")

    robot, other = floating(0.4), floating(0.7)
    assert robot.joint_types[0] == "floating"
    rng = np.random.default_rng(0)
    bp = mindyn.base_parameters(robot)
    assert campaign.check_floating_base(robot, bp, rng)[0] == "ok"
    wrong = mindyn.base_parameters(other)
    assert campaign.check_floating_base(robot, wrong, rng)[0] == "wrong"


_TWO_LINKS = """<robot name="arm">
  <link name="base"><inertial><mass value="3"/><inertia ixx="0.1" iyy="0.2" izz="0.15"
    ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="l1"><inertial><origin xyz="0.1 0.02 0"/><mass value="1.5"/><inertia ixx="0.02"
    iyy="0.03" izz="0.025" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="l2"><inertial><origin xyz="0.2 0 0.01"/><mass value="1"/><inertia ixx="0.01"
    iyy="0.02" izz="0.015" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="{length} 0 0" rpy="1.2 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>
"""


def test_tiny_seeded_run(tmp_path):
    """Six cases (two of the mjcf target); the summary counts them and reruns of a case draw
    the same input."""
    pytest.importorskip("mujoco", reason="the mjcf target needs the 'mujoco' wheel")
    out = tmp_path / "run"
    campaign.main(
        [str(out), "--targets", "trees,api,floating,drives", "--count", "1", "--seed", "5"]
    )
    campaign.main([str(out / "mjcf"), "--targets", "mjcf", "--count", "2", "--seed", "5"])
    doc = json.loads((out / "summary.json").read_text())
    assert sum(sum(c.values()) for c in doc["counts"].values()) == 4
    doc = json.loads((out / "mjcf" / "summary.json").read_text())
    assert doc["counts"]["mjcf"].get("ok", 0) + doc["counts"]["mjcf"].get("error", 0) == 2
    ctx = campaign.Context(tmp_path / "again")
    again = Path(campaign.make_case(ctx, "mjcf", 1, 5).files[0])
    assert again.read_text() == (out / "mjcf" / "work" / again.name).read_text()
    for target in ("trees", "drives"):
        again = Path(campaign.make_case(ctx, target, 0, 5).files[0])
        assert again.read_text() == (out / "work" / again.name).read_text()


def _drive_case(tmp_path, coupled: bool):
    """The first valid URDF of the drives target (seed 3) with a two-joint transmission, or the
    first malformed one: (path, expected rows, malformation)."""
    import random

    ctx = campaign.Context(tmp_path)
    for index in range(200):
        rng = random.Random(f"3:drives:{index}")
        path, form, rows, mal = campaign._drive_description(ctx, index, rng)
        if coupled and mal is None and path.suffix == ".urdf":
            if any(len(row) == 2 for row, _ in rows.values()):
                return path, rows, mal
        if not coupled and mal is not None and not mal[2]:
            return path, rows, mal
    raise AssertionError("no such case drawn")


def test_the_drive_oracles_catch_a_wrong_T_and_wrong_motor_terms(tmp_path, monkeypatch):
    """check_drive_T compares T with ros_control's maps applied to the file's numbers: a
    coefficient one part in 1e12 off, or a motor of another name, is a wrong answer;
    check_motor_side compares with Pinocchio plus T^T (Ia T ddq + f(T dq)): a friction formula
    without its Coulomb term is one too."""
    import mindyn
    import numpy as np
    import pinocchio as pin

    path, rows, _ = _drive_case(tmp_path, coupled=True)
    robot = mindyn.load(path)
    assert campaign.check_drive_T(robot, rows)[0] == "ok"
    motor, (row, c) = next((m, r) for m, r in rows.items() if len(r[0]) == 2)
    joint = next(iter(row))
    off = dict(rows) | {motor: ({**row, joint: row[joint] * (1 + 1e-12)}, c)}
    assert campaign.check_drive_T(robot, off)[0] == "wrong"
    renamed = {("x" + m if m == motor else m): r for m, r in rows.items()}
    assert campaign.check_drive_T(robot, renamed)[0] == "wrong"
    model = pin.buildModelFromUrdf(str(path))
    idx = [model.joints[model.getJointId(j)].idx_v for j in robot.joint_names]
    pin_model = (model, model.createData(), idx)
    rng = np.random.default_rng(0)
    assert campaign.check_motor_side(robot, "coulomb", pin_model, rng)[0] == "ok"
    formula = campaign.friction_terms
    monkeypatch.setattr(
        campaign,
        "friction_terms",
        lambda kind, v, w, fv, fc, f3: formula(kind, v, w, fv, 0 * fc, f3),
    )
    assert campaign.check_motor_side(robot, "coulomb", pin_model, rng)[0] == "wrong"


def test_a_malformed_transmission_is_refused_naming_it(tmp_path):
    """A malformed transmission of the drives target is an error whose one line names the
    element the malformation is in (the case's own check)."""
    path, _, (what, owner, _) = _drive_case(tmp_path, coupled=False)
    kind, detail = campaign.cli_class(*campaign.run_cli(["info", path]))
    owners = owner if isinstance(owner, tuple) else (owner,)
    assert kind == "error" and any(o in detail for o in owners), (what, detail)


def _unread_type_case(tmp_path):
    """The first drives case (seed 3) whose malformation replaces a transmission's type by one
    ros_control does not read (e.g. my_robot/GearTransmission), left out with a note."""
    import random

    ctx = campaign.Context(tmp_path)
    for index in range(400):
        rng = random.Random(f"3:drives:{index}")
        path, _, _, mal = campaign._drive_description(ctx, index, rng)
        if mal is not None and mal[0] == "other-type":
            return campaign.make_case(ctx, "drives", index, 3)
    raise AssertionError("no such case drawn")


def test_a_transmission_of_a_type_not_read_is_found_in_the_robots_record(tmp_path, monkeypatch):
    """A transmission of a type not read is named by Robot.unread_transmissions (and warned
    about), not in Robot.notes: the drives oracle takes it as noted there, and calls it dropped
    without a note when the record does not name it."""
    import warnings

    import mindyn

    case = _unread_type_case(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mindyn.DriveTrainWarning)
        assert case.fn()[0] == "ok", case.fn()
        monkeypatch.setattr(mindyn.Robot, "unread_transmissions", property(lambda self: []))
        kind, detail = case.fn()
    assert kind == "wrong" and "dropped without a note" in detail, detail


@pytest.mark.parametrize("v", [-0.0, 0.0, -1.5, 2.0, 1e-300])
def test_a_number_written_in_an_odd_form_reads_back(v):
    """Every form _decimal writes a description's number in reads back as that number with
    float() (a negative zero was written '+-0.0', and drawing the case failed)."""
    import random

    rng = random.Random(0)
    for _ in range(60):
        text = campaign._decimal(rng, v)
        assert float(text) == v, text


_FLOATING_MJCF = """<mujoco model="f">
  <compiler angle="degree" eulerseq="zyx"/>
  <option gravity="0.5 -1 -9.5"/>
  <worldbody>
    <body name="base" pos="0 0 1" euler="10 20 30"><freejoint name="root"/>
      <inertial pos="0.01 0 0" mass="3" diaginertia="0.05 0.06 0.07" axisangle="1 1 0 40"/>
      <body name="a" pos="0.2 0 0" xyaxes="0 1 0 -1 0 0">
        <joint name="h" axis="0 1 0" armature="0.1" damping="0.4"/>
        <inertial pos="0.1 0 0" mass="1" fullinertia="0.01 0.02 0.02 0.001 0 0"/>
        <body name="b" pos="0.3 0 0" zaxis="0 1 1">
          <joint name="s" type="ball" pos="{anchor}"/>
          <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.03"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def test_the_mjcf_oracle_catches_other_dynamics(tmp_path):
    """check_mjcf_dynamics compares mindyn's inverse dynamics, W_b (Y pi) and mass matrix with
    MuJoCo's on a free root, a hinge and a ball joint (coordinates converted): the file's own
    robot passes, the same robot against a file whose ball joint sits 1 mm away is wrong."""
    pytest.importorskip("mujoco", reason="the mjcf target needs the 'mujoco' wheel")
    import warnings

    import mindyn
    import numpy as np

    path, moved = tmp_path / "f.xml", tmp_path / "moved.xml"
    path.write_text(_FLOATING_MJCF.replace("{anchor}", "0 0 0"))
    moved.write_text(_FLOATING_MJCF.replace("{anchor}", "0.001 0 0"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the hinge's terms, left out below a floating base
        robot = mindyn.load(path)
    assert robot.joint_types == ["floating", "revolute", "spherical"]
    rng = np.random.default_rng(0)
    assert campaign.check_mjcf_dynamics(robot, path, rng)[0] == "ok"
    assert campaign.check_mjcf_dynamics(robot, moved, rng)[0] == "wrong"
    assert campaign.check_mjcf_read(robot, path, {})[0] == "ok"
    assert campaign.check_mjcf_read(robot, path, {"h": 2.0})[0] == "wrong"


def test_a_malformed_mjcf_case_is_refused_naming_it(tmp_path):
    """The first malformed case of the mjcf target (seed 3) is an error whose one line names
    what the malformation is in; the same file with the names the refusal must give changed
    is called refused without naming them."""
    pytest.importorskip("mujoco", reason="the mjcf target needs the 'mujoco' wheel")
    ctx = campaign.Context(tmp_path)
    for index in range(60):
        case = campaign.make_case(ctx, "mjcf", index, 3)
        if "malformed" in case.label:
            break
    else:
        raise AssertionError("no malformed case drawn")
    kind, detail = case.fn()
    assert kind == "error", (case.label, detail)
    case.drawn.mal = (case.drawn.mal[0], ("'no such name'",))
    kind, detail = case.fn()
    assert kind == "wrong" and "refused without naming 'no such name'" in detail, detail
