"""Shared fixtures and independent references for the mindyn test suite.

The references never come from mindyn's own output: Pinocchio models are built either by
Pinocchio's URDF parser or, for the bundled DH/MDH robots, directly from the geometry a mindyn
Robot exposes (pre/post transforms, axes) and its classical parameters, using only Pinocchio's
own joint, placement and inertia algebra.
"""

from __future__ import annotations

import contextlib
import io
import sys
from collections import defaultdict
from pathlib import Path

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from mindyn.cli import main

# --------------------------------------------------------------------------------------------
# Worst relative errors seen against each reference, printed at the end of the run.
# --------------------------------------------------------------------------------------------
WORST: dict[str, float] = defaultdict(float)


def rel_err(a, b) -> float:
    """Relative error ||a - b|| / ||b|| (Frobenius), with a floor of 1 on ||b|| when b ~ 0."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    scale = np.linalg.norm(b)
    if scale < 1e-12:
        scale = 1.0
    return float(np.linalg.norm(a - b) / scale)


def assert_close(a, b, tol: float = 1e-10, what: str = "value") -> float:
    """Asserts rel_err(a, b) <= tol and records it under `what` for the summary."""
    e = rel_err(a, b)
    WORST[what] = max(WORST[what], e)
    assert e <= tol, f"{what}: relative error {e:.3e} > {tol:.1e}\n got {a}\n expected {b}"
    return e


def pytest_terminal_summary(terminalreporter):
    if WORST:
        terminalreporter.write_sep("-", "worst relative errors")
        for k in sorted(WORST):
            terminalreporter.write_line(f"{k:<55s} {WORST[k]:.2e}")


def cli(*argv) -> str:
    """Runs ``mindyn ARGV`` in this process; returns its standard output; fails on an error."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        rc = main([str(a) for a in argv])
    assert rc == 0, f"mindyn {' '.join(map(str, argv))}: exit {rc}\n{out.getvalue()}"
    return out.getvalue()


# --------------------------------------------------------------------------------------------
# Paths and random numbers
# --------------------------------------------------------------------------------------------
def _robots_dir() -> Path:
    hits = sorted(
        Path(sys.prefix).glob(
            "lib/python*/site-packages/cmeel.prefix/share/example-robot-data/robots"
        )
    )
    if not hits:
        raise RuntimeError(
            f"example-robot-data robots not found under {sys.prefix}; "
            "install the test extras: pip install example-robot-data"
        )
    return hits[0]


ROBOTS_DIR = _robots_dir()

URDFS = {
    "ur3": ROBOTS_DIR / "ur_description/urdf/ur3_robot.urdf",
    "ur5": ROBOTS_DIR / "ur_description/urdf/ur5_robot.urdf",
    "ur10": ROBOTS_DIR / "ur_description/urdf/ur10_robot.urdf",
    "panda": ROBOTS_DIR / "panda_description/urdf/panda.urdf",
}
for _name, _path in URDFS.items():
    if not _path.is_file():
        raise RuntimeError(f"example-robot-data URDF for {_name} missing: {_path}")

BUNDLED = ["puma560", "puma560_3", "zcr07s", "stanford", "planar3", "planar4h"]


@pytest.fixture(scope="session")
def robots_dir() -> Path:
    return ROBOTS_DIR


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20240611)


# --------------------------------------------------------------------------------------------
# Pinocchio references
# --------------------------------------------------------------------------------------------
def se3(T) -> pin.SE3:
    T = np.asarray(T, dtype=float)
    return pin.SE3(T[:3, :3].copy(), T[:3, 3].copy())


def pinocchio_model(robot: mindyn.Robot, params=None) -> pin.Model:
    """A pin.Model built directly from a mindyn Robot's geometry (not from any file).

    Joint k sits at post_{k-1} * pre_k in the previous joint frame; link k's classical
    parameters (about the link origin, link axes) are moved into the joint-k frame with
    post_k. `params` (10 n classical values) defaults to robot.params.
    """
    p = robot.params if params is None else np.asarray(params, dtype=float)
    model = pin.Model()
    model.name = robot.name
    parent = 0
    for k in range(robot.n):
        placement = robot.joint_pre(k)
        if k > 0:
            placement = robot.joint_post(k - 1) @ placement
        axis = np.asarray(robot.axes[k], dtype=float)
        if robot.joint_types[k] == "revolute":
            joint = pin.JointModelRevoluteUnaligned(axis)
        else:
            joint = pin.JointModelPrismaticUnaligned(axis)
        parent = model.addJoint(parent, joint, se3(placement), robot.joint_names[k])
        # assigned, not appendBodyToJoint(): Pinocchio's Inertia addition clamps the total mass
        # to >= eps, which breaks the negative masses of random parameter vectors
        model.inertias[parent] = body_inertia(p[10 * k : 10 * k + 10], robot.joint_post(k))
    model.addFrame(
        pin.Frame(
            "tool",
            parent,
            0,
            se3(robot.joint_post(robot.n - 1) @ robot.tool),
            pin.FrameType.OP_FRAME,
        )
    )
    model.gravity = pin.Motion(np.asarray(robot.gravity, dtype=float), np.zeros(3))
    return model


def body_inertia(p10, post=None) -> pin.Inertia:
    """pin.Inertia of ten classical parameters about a link frame placed at `post`."""
    p10 = np.asarray(p10, dtype=float)
    if p10[9] == 0.0:
        # FromDynamicParameters divides by the mass; a massless link (PUMA link 1) carries only
        # a rotational inertia, which pin.Inertia takes directly (it must have no first moment).
        assert not np.any(p10[6:9]), "a massless link with a first moment has no pin.Inertia"
        xx, xy, xz, yy, yz, zz = p10[:6]
        tensor = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
        inertia = pin.Inertia(0.0, np.zeros(3), tensor)
    else:
        dyn = np.asarray(mindyn.to_pinocchio_order(p10))
        inertia = pin.Inertia.FromDynamicParameters(dyn)
    return inertia.se3Action(se3(np.eye(4) if post is None else post))


def set_pinocchio_params(model: pin.Model, robot: mindyn.Robot, params) -> None:
    """Sets model.inertias[1..n] from a classical 10 n vector (link frames = joint frames
    for URDF models; for models from pinocchio_model() the link offsets post_k are applied)."""
    params = np.asarray(params, dtype=float)
    for k in range(robot.n):
        model.inertias[k + 1] = body_inertia(params[10 * k : 10 * k + 10], robot.joint_post(k))


def load_urdf_pair(name: str, tip: str | None = None):
    """(mindyn Robot, pin.Model) from the same example-robot-data URDF.

    Panda: Pinocchio's model is reduced by locking both finger joints at 0 (mindyn merges the
    off-chain fingers locked at q = 0 into the last link); mindyn's tip defaults to 'panda_hand'
    (panda_link8 gives the same inertial parameters, only the tool frame differs).
    """
    path = URDFS[name]
    model = pin.buildModelFromUrdf(str(path))
    if name == "panda":
        tip = tip or "panda_hand"
        locked = [model.getJointId(j) for j in ("panda_finger_joint1", "panda_finger_joint2")]
        model = pin.buildReducedModel(model, locked, pin.neutral(model))
    robot = mindyn.load(path, tip=tip)
    assert model.nq == model.nv == robot.n
    return robot, model


def random_state(robot: mindyn.Robot, rng: np.random.Generator, m: int | None = None):
    """q inside the joint limits (or [-pi, pi] where none), dq and ddq uniform in [-2, 2]."""
    lim = robot.limits
    lo = np.where(np.isfinite(lim["lower"]), lim["lower"], -np.pi)
    hi = np.where(np.isfinite(lim["upper"]), lim["upper"], np.pi)
    shape = (robot.n,) if m is None else (m, robot.n)
    q = rng.uniform(lo, hi, shape)
    dq = rng.uniform(-2.0, 2.0, shape)
    ddq = rng.uniform(-2.0, 2.0, shape)
    return q, dq, ddq


# --------------------------------------------------------------------------------------------
# The command line in-process: its exit code and output, and the one-line error it must give
# --------------------------------------------------------------------------------------------
def cli_run(argv) -> tuple[int, str, str]:
    from mindyn import cli

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main([str(a) for a in argv])
    return rc, out.getvalue(), err.getvalue()


def one_line_error(rc: int, err: str, *needles: str) -> str:
    assert rc == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("mindyn: error: "), err
    for s in needles:
        assert s in lines[0], (s, err)
    return lines[0]
