"""Identification of a floating-base robot from logs with contact wrenches, against logs the
tests simulate with Pinocchio: Solo12 on a free-flyer (and a planar) root, random states and
joint torques, random wrenches on the feet (Pinocchio's external forces, in the joint's local
frame), the accelerations from pinocchio.aba with those forces, so that the root's generalized
force is zero. The true base values are the numerical method's of the description's
parameters."""

from __future__ import annotations

import functools

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import assert_close, rel_err
from mindyn.identification.data import DataError
from mindyn.identification.errors import IdentificationError
from mindyn.identification.floating import (
    FloatingLog,
    contact_jacobian,
    floating_system,
    identify_floating,
    read_floating_csv,
)
from test_multibody import FLOATING, random_state

FEET = ["FL_LOWER_LEG", "FR_LOWER_LEG", "HL_LOWER_LEG", "HR_LOWER_LEG"]


@functools.cache
def solo(root: str = "floating"):
    joint = pin.JointModelFreeFlyer() if root == "floating" else pin.JointModelPlanar()
    model = pin.buildModelFromUrdf(str(FLOATING["solo12"]), joint)
    robot = mindyn.load(FLOATING["solo12"], root_joint=root)
    base = mindyn.base_parameters(robot, method="numerical")
    return robot, model, base


def simulate(robot, model, rng, m: int, contacts=FEET, *, local: bool = False) -> FloatingLog:
    """m random samples; wrenches about each contact link's origin in world axes (or the link's
    own axes with ``local``), accelerations from Pinocchio's forward dynamics with them."""
    data = model.createData()
    r = model.joints[1].nv
    Q, V, A, T = [], [], [], []
    W: dict[str, list] = {c: [] for c in contacts}
    for _ in range(m):
        q, v, _ = random_state(robot, rng)
        tau = rng.normal(0.0, 1.0, model.nv - r)
        fext = [pin.Force.Zero() for _ in range(model.njoints)]
        pin.forwardKinematics(model, data, q)
        for c in contacts:
            f = rng.normal(0.0, 5.0, 6)
            jid = model.frames[model.getFrameId(c)].parentJoint
            R = np.eye(3) if local else data.oMi[jid].rotation
            fext[jid] = pin.Force(R.T @ f[:3], R.T @ f[3:])
            W[c].append(f)
        a = pin.aba(model, data, q, v, np.r_[np.zeros(r), tau], fext)
        # the log is consistent: Pinocchio's inverse dynamics with the same forces gives zero on
        # the root
        assert np.abs(pin.rnea(model, data, q, v, a, fext)[:r]).max() < 1e-8
        Q.append(q), V.append(v), A.append(a), T.append(tau)
    return FloatingLog(
        np.array(Q),
        np.array(V),
        np.array(A),
        np.array(T),
        {c: np.array(w) for c, w in W.items()},
        wrench_frame="local" if local else "world",
    )


@pytest.mark.parametrize("root", ["floating", "planar"])
def test_contact_jacobian_agrees_with_pinocchio_frame_jacobian(root):
    robot, model, _ = solo(root)
    data = model.createData()
    rng = np.random.default_rng(4)
    for _ in range(3):
        q, _, _ = random_state(robot, rng)
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        for link in ["base_link", "FL_UPPER_LEG", *FEET]:
            fid = model.getFrameId(link)
            for frame, ref in (("world", pin.LOCAL_WORLD_ALIGNED), ("local", pin.LOCAL)):
                expected = pin.getFrameJacobian(model, data, fid, ref)
                assert_close(contact_jacobian(robot, q, link, frame=frame), expected, 1e-12, "J_c")


@pytest.mark.parametrize("root", ["floating", "planar"])
def test_noise_free_contact_logs_give_the_base_values_and_the_base_link_model_agrees(root):
    robot, model, base = solo(root)
    truth = base.values(robot.params)
    log = simulate(robot, model, np.random.default_rng(1), 50)
    full = identify_floating(robot, log, base=base)
    assert full.rank == base.n
    assert_close(full.values, truth, 1e-6, "floating-base values (full model)")
    link = identify_floating(robot, log, base=base, model="base")
    assert link.span.shape == (link.rank, base.n)
    # the combinations the base-link model identifies are the full model's (and the truth's)
    assert_close(link.span @ link.values, link.span @ full.values, 1e-6, "base-link model")
    assert_close(link.span @ link.values, link.span @ truth, 1e-6, "base-link model")
    if root == "floating":
        # with a free-flyer root the base link's equations identify every base parameter
        assert link.rank == base.n
        assert_close(link.values, truth, 1e-6, "floating-base values (base-link model)")
    else:
        # a planar root's three rows (x, y, yaw) see no gravity: fewer combinations
        assert 0 < link.rank < base.n


def test_a_humanoid_standing_on_its_feet_is_identified_by_both_models():
    """TALOS (38 velocities, 234 base parameters) with wrenches under both feet."""
    model = pin.buildModelFromUrdf(str(FLOATING["talos"]), pin.JointModelFreeFlyer())
    robot = mindyn.load(FLOATING["talos"], root_joint="floating")
    base = mindyn.base_parameters(robot, method="numerical")
    truth = base.values(robot.params)
    feet = ["leg_left_6_link", "leg_right_6_link"]
    log = simulate(robot, model, np.random.default_rng(3), 60, contacts=feet)
    full = identify_floating(robot, log, base=base)
    assert_close(full.values, truth, 1e-6, "humanoid base values (full model)")
    link = identify_floating(robot, log, base=base, model="base")
    assert link.rank == base.n
    assert_close(link.values, truth, 1e-6, "humanoid base values (base-link model)")


def test_free_flight_identifies_from_torques_and_refuses_the_base_link_model():
    robot, model, base = solo()
    log = simulate(robot, model, np.random.default_rng(2), 50, contacts=[])
    full = identify_floating(robot, log, base=base)
    assert_close(full.values, base.values(robot.params), 1e-6, "floating-base values (free)")
    with pytest.raises(IdentificationError, match="base-link model needs contact wrenches"):
        identify_floating(robot, log, base=base, model="base")


def test_noisy_torques_and_wrenches_validate_within_the_noise():
    """Gaussian noise on the torques (0.05 N m) and the wrenches (0.5 N, 0.05 N m): on a second
    log the prediction misses the measured generalized forces by no more than 1.2 times the
    noise those measurements carry."""
    robot, model, base = solo()
    rng = np.random.default_rng(5)
    noisy = []
    for m in (300, 60):  # the fit's log spans more than one block of the stacked system
        clean = simulate(robot, model, rng, m)
        log = FloatingLog(
            clean.q,
            clean.dq,
            clean.ddq,
            clean.tau + rng.normal(0, 0.05, clean.tau.shape),
            {
                c: w + np.r_[[0.5] * 3, [0.05] * 3] * rng.normal(size=w.shape)
                for c, w in clean.wrenches.items()
            },
        )
        noisy.append((clean, log))
    result = identify_floating(robot, noisy[0][1], base=base)
    assert_close(result.rms, np.sqrt(np.mean(result.residual(noisy[0][1]) ** 2)), 1e-9, "rms")
    clean, log = noisy[1]
    noise = floating_system(robot, log)[1] - floating_system(robot, clean)[1]
    ratio = np.sqrt(np.mean(result.residual(log) ** 2)) / np.sqrt(np.mean(noise**2))
    assert ratio <= 1.2, ratio
    # and the estimate is close to the truth, not only the fit
    assert rel_err(result.values, base.values(robot.params)) < 0.05


def _write(path, robot, log: FloatingLog) -> None:
    header = ["t", *(f"q{i + 1}" for i in range(robot.nq))]
    header += [f"dq{i + 1}" for i in range(robot.nv)] + [f"ddq{i + 1}" for i in range(robot.nv)]
    header += [f"tau{i + 1}" for i in range(log.tau.shape[1])]
    header += [f"{c}.{a}" for c in log.wrenches for a in ("fx", "fy", "fz", "tx", "ty", "tz")]
    rows = np.hstack(
        [np.arange(log.m)[:, None] * 0.01, log.q, log.dq, log.ddq, log.tau, *log.wrenches.values()]
    )
    text = ",".join(header) + "\n" + "\n".join(",".join(repr(float(x)) for x in r) for r in rows)
    path.write_text(text + "\n")


def test_csv_logs_with_sensor_frame_wrenches_identify_and_bad_files_are_refused(tmp_path):
    robot, model, base = solo()
    log = simulate(robot, model, np.random.default_rng(7), 40, local=True)
    _write(tmp_path / "log.csv", robot, log)
    read = read_floating_csv(tmp_path / "log.csv", robot, wrench_frame="local")
    assert set(read.wrenches) == set(FEET) and read.tau is not None
    result = identify_floating(robot, read, base=base)
    assert_close(result.values, base.values(robot.params), 1e-6, "floating-base values (CSV)")
    # the same wrenches read as world-axis ones make another, wrong system
    wrong = read_floating_csv(tmp_path / "log.csv", robot)
    assert rel_err(identify_floating(robot, wrong, base=base).values, result.values) > 1e-3

    text = (tmp_path / "log.csv").read_text()
    head, body = text.split("\n", 1)
    cases = {
        "unknown column 'FL_LOWER_LEG.fq'": head.replace("FL_LOWER_LEG.fx", "FL_LOWER_LEG.fq"),
        "no moving link 'foo'": head.replace("FL_LOWER_LEG", "foo"),
        "column 'dq3' appears twice": head.replace("dq4,", "dq3,", 1),
        "missing column 'tau2'": head.replace("tau2,", ""),
        "missing column 'FL_LOWER_LEG.tz'": head.replace(",FL_LOWER_LEG.tz", ""),
    }
    for i, (message, bad_head) in enumerate(cases.items()):
        (tmp_path / f"bad{i}.csv").write_text(bad_head + "\n" + body)
        with pytest.raises(DataError, match=message):
            read_floating_csv(tmp_path / f"bad{i}.csv", robot)
    rows = body.split("\n")
    cells = rows[3].split(",")
    cells[1] = "abc"
    rows[3] = ",".join(cells)
    (tmp_path / "cell.csv").write_text(head + "\n" + "\n".join(rows))
    with pytest.raises(DataError, match=":5: column 'q1': 'abc' is not a number"):
        read_floating_csv(tmp_path / "cell.csv", robot)
    bad = dict(read.wrenches, nope=read.wrenches["FL_LOWER_LEG"])
    with pytest.raises(IdentificationError, match="a wrench on 'nope', no moving link"):
        identify_floating(robot, FloatingLog(read.q, read.dq, read.ddq, read.tau, bad))
    bad = dict(read.wrenches, FL_LOWER_LEG=read.wrenches["FL_LOWER_LEG"].copy())
    bad["FL_LOWER_LEG"][7, 4] = np.nan
    with pytest.raises(
        IdentificationError, match="'FL_LOWER_LEG' has a non-finite value .sample 7"
    ):
        identify_floating(robot, FloatingLog(read.q, read.dq, read.ddq, read.tau, bad))
    with pytest.raises(IdentificationError, match="full model needs the joint torques"):
        identify_floating(robot, FloatingLog(read.q, read.dq, read.ddq, None, read.wrenches))
    with pytest.raises(IdentificationError, match="free-flyer or planar root joint"):
        identify_floating(mindyn.load(FLOATING["solo12"]), read)
