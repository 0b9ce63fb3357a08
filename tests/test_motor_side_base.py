"""Base parameters with rotor inertia and friction on the motors of coupled transmissions: the
counts of the projection, recursive and numerical methods agree (on a coupled-wrist 6R, a
WAM-like 7R and random trees with random differentials and four-bar linkages), the base
regressor reproduces the classical dynamics (W_b (Y pi) = tau) at random states, and a case the
recursive method cannot decide is refused with its reason and left to the others."""

from __future__ import annotations

import mindyn
import numpy as np
import pytest
from coupled_arms import coupled_wrist_urdf, motor_terms, wam_like_urdf
from random_tree import random_tree_urdf

PREFIX = "transmission_interface/"
METHODS = ("projection", "recursive", "numerical")


def _pair(kind, name, joints, motors, a):
    parts = [
        f"<actuator name='{m}'><role>actuator{r + 1}</role>"
        f"<mechanicalReduction>{a[r]}</mechanicalReduction></actuator>"
        for r, m in enumerate(motors)
    ] + [
        f"<joint name='{j}'><role>joint{r + 1}</role><mechanicalReduction>1</mechanicalReduction>"
        "</joint>"
        for r, j in enumerate(joints)
    ]
    return f"<transmission name='{name}'><type>{PREFIX}{kind}</type>{''.join(parts)}</transmission>"


def coupled_tree(tmp_path, seed, n=6):
    """A random tree whose joints are coupled in random pairs by differentials and four-bar
    linkages (random reductions); a joint left over is driven directly."""
    path = random_tree_urdf(tmp_path / f"tree{seed}.urdf", n=n, seed=seed)
    names = mindyn.load(path).joint_names
    rng = np.random.default_rng(seed)
    order = rng.permutation(len(names))
    tr = []
    for i in range(0, len(order) - 1, 2):
        a, b = names[order[i]], names[order[i + 1]]
        kind = "DifferentialTransmission" if rng.uniform() < 0.5 else "FourBarLinkageTransmission"
        red = rng.uniform(5, 50, 2) * rng.choice([-1, 1], 2)
        tr.append(_pair(kind, f"t{i}", [a, b], [f"m_{a}", f"m_{b}"], red))
    text = path.read_text().replace("</robot>", "".join(tr) + "</robot>")
    path.write_text(text)
    robot = mindyn.load(path)
    assert robot.drive_side == "motor" and robot.transmission.n_motors == robot.n
    assert np.count_nonzero(robot.transmission.T) > robot.n  # coupled
    return robot


def counts(robot, methods=METHODS):
    out = {}
    for m in methods:
        b = mindyn.base_parameters(robot, rotor=True, friction=True, method=m)
        out[m] = {k: s["n"] for k, s in b.sets.items()}
    return out


def check_regrouping(robot, seed=0):
    """W_b (Y pi) = W pi for random classical pi at random states, and W pi is the rigid bodies'
    (joint-side dynamics without rotor and friction) plus the motor terms written out."""
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    rng = np.random.default_rng(seed)
    n = robot.n
    for _ in range(3):
        pi = rng.uniform(-1, 1, 13 * n)
        q, dq, ddq = rng.uniform(-2, 2, (3, n))
        tau = robot.inverse_dynamics(q, dq, ddq, pi)
        rigid = pi.copy()
        for c in (10, 11, 12):
            rigid[c::13] = 0.0
        T = robot.transmission.T
        ref = robot.with_drive_side("joint").inverse_dynamics(q, dq, ddq, rigid) + motor_terms(
            T, pi[10::13], pi[11::13], pi[12::13], dq, ddq
        )
        assert np.max(np.abs(ref - tau)) <= 1e-12 * np.max(np.abs(tau))
        tb = base.regressor(q, dq, ddq) @ base.values(pi)
        assert np.max(np.abs(tb - tau)) <= 1e-9 * max(1.0, np.max(np.abs(tau)))


@pytest.mark.parametrize("make", [coupled_wrist_urdf, wam_like_urdf])
def test_counts_agree_and_the_base_regressor_reproduces_the_dynamics(tmp_path, make):
    path, _ = make(tmp_path / "arm.urdf")
    robot = mindyn.load(path)
    c = counts(robot)
    assert c["projection"] == c["recursive"] == c["numerical"], c
    check_regrouping(robot)


@pytest.mark.parametrize("seed", range(4))
def test_random_trees_with_coupled_transmissions(tmp_path, seed):
    robot = coupled_tree(tmp_path, seed)
    refused = mindyn._core.recursive_refusal(robot._m, rotor=True, friction=True)
    c = counts(robot, ("projection", "numerical") if refused else METHODS)
    assert c["projection"] == c["numerical"], c
    if refused:
        # the reason names a coupled motor, and the method refuses to run with it
        assert "cannot decide" in refused and "motor" in refused
        with pytest.raises(mindyn.ModelError, match="cannot decide"):
            mindyn.base_parameters(robot, rotor=True, friction=True, method="recursive")
    else:
        assert c["recursive"] == c["numerical"], c
    check_regrouping(robot, seed)


def test_cli_base_says_where_the_terms_act_and_the_flag_moves_them(tmp_path):
    import contextlib
    import io

    from conftest import cli
    from mindyn.cli import main

    path, _ = coupled_wrist_urdf(tmp_path / "arm.urdf")
    motor = cli("base", path, "--rotor", "--friction").splitlines()[0]
    joint = cli("base", path, "--rotor", "--friction", "--drive-side", "joint").splitlines()[0]
    assert "on the motors" in motor and "on the joints" in joint
    track = cli("track", path, "--duration", "0.2").splitlines()[0]
    assert "on the motors" in track
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = main(["base", "puma560", "--rotor", "--drive-side", "motor"])
    assert rc != 0 and len(err.getvalue().splitlines()) == 1
    assert "declares no transmissions" in err.getvalue()


@pytest.mark.parametrize("kind", ["coulomb", "smooth"])
def test_a_motor_on_a_prismatic_joint_of_a_long_robot(tmp_path, kind):
    """A horizontal ball-screw axis (a motor of 1256.6 rad/m on a prismatic joint travelling
    +-3 m, so that the exact methods scale lengths by 4) under a revolute joint with a motor of
    its own: the rotor regroups with the axis's moving mass by r^2. Every method runs, the
    counts agree, and W_b (Y pi) reproduces the rigid bodies plus
    T^T (Ia T ddq + Fv T dq + Fc s(T dq)) written out, s = sign or tanh(./w) (w per motor)."""
    from test_transmissions import arm_urdf, simple

    text = arm_urdf(2, simple("t1", "j1", "m1", 1256.6) + simple("t2", "j2", "m2", -50.0))
    text = text.replace("type='revolute'", "type='prismatic'", 1)
    text = text.replace("<axis xyz='0 0 1'/>", "<axis xyz='0 1 0'/>", 1)
    path = tmp_path / "axis.urdf"
    path.write_text(text, encoding="utf-8")
    w = np.array([300.0, 5.0])  # motor speeds [rad/s]
    robot = mindyn.load(path).with_friction_model(kind, velocity=w if kind == "smooth" else None)
    assert list(robot.joint_types) == ["prismatic", "revolute"] and robot.drive_side == "motor"
    c = counts(robot)
    assert c["projection"] == c["recursive"] == c["numerical"], c
    T = robot.transmission.T
    rng = np.random.default_rng(1)
    for method in METHODS:
        base = mindyn.base_parameters(robot, rotor=True, friction=True, method=method)
        for _ in range(3):
            pi = rng.uniform(0.1, 1, 26) * np.tile(np.r_[np.ones(10), 1e-4, 1e-3, 0.05], 2)
            q, dq, ddq = rng.uniform(-2, 2, (3, 2))
            rigid = pi.copy()
            for col in (10, 11, 12):
                rigid[col::13] = 0.0
            vm = T @ dq
            shape = np.sign(vm) if kind == "coulomb" else np.tanh(vm / w)
            drive = T.T @ (pi[10::13] * (T @ ddq) + pi[11::13] * vm + pi[12::13] * shape)
            ref = robot.with_drive_side("joint").inverse_dynamics(q, dq, ddq, rigid) + drive
            tb = base.regressor(q, dq, ddq) @ base.values(pi)
            assert np.max(np.abs(tb - ref)) <= 1e-9 * np.max(np.abs(ref)), method


NEAR_PARALLEL_TABLE = """name: nearpar
convention: dh
angle_unit: deg
joints:
- {name: j1, type: revolute, a: 0.1, alpha: -60.0, d: 0.0, theta: 0.0,
   inertial: {mass: 4.4, com: [-0.08, -0.05, 0.08], inertia: {xx: 0.008, yy: 0.009, zz: 0.013}}}
- {name: j2, type: prismatic, a: 0.0, alpha: 120.0, d: 0.0, theta: 0.0,
   limits: {lower: -0.5, upper: 0.5},
   inertial: {mass: 3.8, com: [0.09, 0.03, 0.03], inertia: {xx: 0.0096, yy: 0.0107, zz: 0.0109}}}
- {name: j3, type: revolute, a: 0.0, alpha: 30.0, d: 0.58, theta: 0.0,
   inertial: {mass: 4.1, com: [0.03, -0.08, 0.04], inertia: {xx: 0.0035, yy: 0.0036, zz: 0.0065}}}
transmissions:
  matrix:
  - [T11, -65.67746716376892, T13]
  - [189.5, 121.0, 0]
  - [0.0, -65.677467163762358, 1.0]
"""


def sampled_rank(robot, tolerance=1e-9, states=300, seed=1):
    """The rank of the stacked regressor (rotor inertia and friction on the motors) at random
    states: singular values above tolerance times the largest."""
    rng = np.random.default_rng(seed)
    n = robot.n
    W = np.vstack(
        [
            robot.regressor(*rng.uniform(-2, 2, (3, n)), rotor=True, friction=True)
            for _ in range(states)
        ]
    )
    s = np.linalg.svd(W, compute_uv=False)
    return int(np.sum(s > tolerance * s[0])), s / s[0]


@pytest.mark.parametrize("t11, t13", [("6.567747e-12", "1.0000000000001"), ("3.0", "1.0")])
def test_friction_of_motors_turning_alike_regroups(tmp_path, t11, t13):
    """Motors 1 and 3 whose rows of T are parallel to 1e-13: their viscous and Coulomb columns
    are those of one motor at any state the regressor is sampled at, so the base set has two
    parameters fewer than with the rows apart (the second case). The projection method took each
    friction column as independent (two more than the regressor's rank, unflagged); every
    method now gives the rank of the sampled regressor (a gap of 1e6 around the tolerance)."""
    path = tmp_path / "nearpar.yaml"
    path.write_text(NEAR_PARALLEL_TABLE.replace("T11", t11).replace("T13", t13))
    robot = mindyn.load(path)
    rank, s = sampled_rank(robot)
    assert s[rank - 1] > 1e-8 and (rank == len(s) or s[rank] < 1e-12), s  # a clear gap
    for method in ("projection", "numerical"):
        bp = mindyn.base_parameters(robot, rotor=True, friction=True, method=method)
        assert bp.n == rank, (method, bp.n, rank)
    check_regrouping(robot)
