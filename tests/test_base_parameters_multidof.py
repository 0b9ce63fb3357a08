"""Base parameters of robots with multi-DOF joints and floating bases by the three methods: the
exact projection and recursive methods run on the single-DOF expansion of each pair
(docs/base-parameters.md, "Joints of several degrees of freedom"). Their counts are checked
against the rank of Pinocchio's joint-torque regressors stacked at random states and against
the numerical method; their base sets against Pinocchio's rnea (W_b (Y pi) = rnea(pi) for a
random pi); the known floating-base results (the floating body's ten parameters and the total
mass identifiable) against the same regressors.

The projection method takes a floating root as it is (not expanded); TALOS and G1 on a
free-flyer by it take 2 and 4 s (bench/bench_base_parameters_multidof.py times the methods)."""

from __future__ import annotations

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import assert_close
from mindyn import _core
from mindyn.base import AUTO_PROJECTION_TERMS, choose_method
from random_tree import random_multidof_tree_yaml
from test_multibody import (
    FLOATING,
    geometry_pair,
    in_row_space,
    pin_q,
    pinocchio_rank,
    random_state,
    urdf_pair,
)

EXACT = ("projection", "recursive")


def with_parameters(model, bodies, pi):
    """A copy of a pin.Model whose link k has the classical parameters pi[10k:10k+10] (about the
    link origin, in mindyn's order), for the URDF models (link k is body k + 1, its frame the
    joint's)."""
    m = model.copy()
    pinp = mindyn.to_pinocchio_order(pi)
    for k in range(len(pi) // 10):
        m.inertias[k + 1 if bodies is None else bodies[k]] = pin.Inertia.FromDynamicParameters(
            np.asarray(pinp[10 * k : 10 * k + 10], dtype=float)
        )
    return m


def check_rnea(robot, model, bodies, bp, rng, states: int = 3) -> float:
    """W_b (Y pi) (BaseParameters.regressor, the classical regressor's columns at the pivots)
    against Pinocchio's rnea(pi) at random states, pi random with each parameter
    of its robot's size (the robot's own values times a random factor in +-[0.5, 1.5], plus a
    random part so that zero parameters are not zero)."""
    pi = robot.params * rng.uniform(0.5, 1.5, robot.params.size) * rng.choice([-1, 1], 10 * robot.n)
    pi = pi + rng.uniform(-0.1, 0.1, pi.size) * np.abs(robot.params).max()
    if bodies is None:
        model_pi = with_parameters(model, None, pi)
    else:
        model_pi, _ = geometry_pair(robot, pi)
    data = model_pi.createData()
    pb = bp.Y @ pi
    worst = 0.0
    for _ in range(states):
        q, v, a = random_state(robot, rng)
        qp = q if bodies is not None else pin_q(robot, model, q)
        tau = pin.rnea(model_pi, data, qp, v, a)
        got = bp.regressor(q, v, a) @ pb
        assert_close(got, tau, 1e-9, f"{robot.name} {bp.method}: W_b (Y pi) vs rnea(pi)")
        worst = max(worst, float(np.abs(got - tau).max() / np.abs(tau).max()))
    return worst


def check_methods(robot, model, bodies, methods, states: int, seed: int = 0):
    """Counts of the given methods equal to the numerical method's and to Pinocchio's stacked
    rank (the Lagrangian and total-energy sets to the numerical method's, from sampled
    energies); the exact methods give one base set; W_b (Y pi) = rnea(pi) for each."""
    rng = np.random.default_rng(seed)
    rank, _ = pinocchio_rank(robot, model, rng, states, bodies)
    numerical = mindyn.base_parameters(robot, method="numerical")
    assert numerical.n == rank, robot.name
    sets = {m: mindyn.base_parameters(robot, method=m) for m in methods}
    for m, bp in sets.items():
        assert bp.method == m and bp.n == rank, (robot.name, m, bp.n, rank)
        for k in ("lagrangian", "energy"):
            assert bp.sets[k]["n"] == numerical.sets[k]["n"], (robot.name, m, k)
        check_rnea(robot, model, bodies, bp, rng)
    if len(sets) == 2:
        assert sets["projection"].names == sets["recursive"].names
        assert_close(sets["projection"].Y, sets["recursive"].Y, 1e-9, "Y of the exact methods")
    return rank


@pytest.mark.parametrize("name", ["solo12", "go1", "anymal", "tiago"])
def test_quadrupeds_and_a_planar_base_by_every_method(name):
    """A free-flyer root (Solo12, Go1, ANYmal: 18 joints in the expansion) and a planar root
    (TIAGo): projection, recursive and numerical counts equal Pinocchio's rank."""
    robot, model = urdf_pair(name)
    check_methods(robot, model, None, EXACT, states=8)


@pytest.mark.parametrize("name", ["talos", "g1"])
def test_humanoids_with_a_free_flyer_by_every_method(name):
    """TALOS and G1 on a free-flyer (33 and 30 joints): projection, recursive and numerical
    counts equal Pinocchio's rank, and the exact sets reproduce rnea. The projection method
    takes the floating root natively (its six velocities and the gravity direction in its
    frame); run as the chain of six single-DOF joints, G1 needed over 21 GiB."""
    robot, model = urdf_pair(name)
    cost = _core.projection_cost(robot._m)
    assert cost["bytes"] < 0.75 * cost["budget"], cost
    check_methods(robot, model, None, EXACT, states=12)


@pytest.mark.parametrize("seed", range(3))
def test_random_multidof_trees_by_every_method(tmp_path, seed):
    """Random trees of every joint kind (spherical, universal, cylindrical, planar, floating,
    revolute, prismatic; a Pinocchio model built with its own joint models)."""
    robot = mindyn.load(random_multidof_tree_yaml(tmp_path / "tree.yaml", n=9, seed=seed))
    assert {"spherical", "universal", "cylindrical"} <= set(robot.joint_types)
    model, bodies = geometry_pair(robot)
    check_methods(robot, model, bodies, EXACT, states=12, seed=seed)


@pytest.mark.parametrize("serial", [False, True])
@pytest.mark.parametrize("seed", range(2))
def test_random_floating_roots_by_every_method(tmp_path, seed, serial):
    """A free-flyer hanging from the world (the projection method's native floating root),
    under it random trees or chains of every other kind, with another free-flyer below it (run
    as its chain of single-DOF joints): counts, Lagrangian and energy sets equal the numerical
    method's and Pinocchio's rank; the exact sets agree and reproduce rnea."""
    robot = mindyn.load(
        random_multidof_tree_yaml(
            tmp_path / "tree.yaml", n=6, seed=10 + seed, first="floating", serial=serial
        )
    )
    assert robot.joint_types[0] == "floating" and robot.joint_types.count("floating") >= 1
    model, bodies = geometry_pair(robot)
    check_methods(robot, model, bodies, EXACT, states=12, seed=seed)


@pytest.mark.parametrize("name", ["solo12", "tiago", "talos"])
def test_the_projection_cost_bounds_what_it_forms_and_chooses_the_default(name):
    """projection_cost estimates the model the projection method runs (a floating root kept,
    other pairs expanded): an upper bound of the terms and rows it forms; the default method
    follows it, with the same base set."""
    robot, _ = urdf_pair(name)
    cost = _core.projection_cost(robot._m)
    bp = mindyn.base_parameters(robot, method="projection")
    assert bp.terms_formed <= cost["terms"], (bp.terms_formed, cost)
    assert bp.basis_rows <= cost["rows"], (bp.basis_rows, cost)
    method, _ = choose_method(robot)
    assert (method == "recursive") == (cost["terms"] > AUTO_PROJECTION_TERMS)
    assert mindyn.base_parameters(robot).names == bp.names


@pytest.mark.parametrize("method", (*EXACT, "numerical"))
def test_a_floating_base_makes_the_root_body_and_the_total_mass_identifiable(method):
    """Known floating-base results, by every method: each of the floating body's ten
    parameters is a base parameter (its ten regressor columns in Pinocchio's stack are
    independent), and the total mass is identifiable (a combination of the base parameters),
    neither of which holds on the fixed base."""
    floating, model = urdf_pair("solo12")
    fixed = mindyn.load(FLOATING["solo12"])
    assert fixed.single_dof and fixed.n == floating.n - 1
    bf = mindyn.base_parameters(floating, method=method)
    bx = mindyn.base_parameters(fixed, method=method)
    assert bf.method == method and bx.method == method
    assert set(range(10)) <= set(bf.pivots)
    _, W = pinocchio_rank(floating, model, np.random.default_rng(3), states=4)
    assert np.linalg.matrix_rank(W[:, :10]) == 10
    total = np.zeros(10 * floating.n)
    total[9::10] = 1.0
    assert in_row_space(bf.Y, total) < 1e-9
    assert in_row_space(bx.Y, total[10:]) > 1e-3  # a fixed base hides the total mass


def test_the_default_method_follows_the_single_dof_rule():
    """Without a method: the projection method where none of its limits refuses the model and
    its cost estimate is under AUTO_PROJECTION_TERMS, saying how the pairs were taken (Solo12:
    the floating root as it is; TIAGo: the planar root expanded), else the recursive method,
    with the projection method's reason (G1: the terms it would form), as on a single-DOF
    robot."""
    solo, _ = urdf_pair("solo12")
    bp = mindyn.base_parameters(solo)
    assert bp.method == "projection" and bp.method_reason.startswith("the default (exact")
    expanded = "each multi-DOF joint taken as its chain of single-DOF joints"
    assert "the floating root taken as it is" in bp.method_reason
    assert expanded not in bp.method_reason
    tiago, _ = urdf_pair("tiago")
    method, reason = choose_method(tiago)
    assert method == "projection" and expanded in reason
    g1, _ = urdf_pair("g1")
    assert _core.projection_refusal(g1._m) is None
    method, reason = choose_method(g1)
    assert _core.projection_cost(g1._m)["terms"] > AUTO_PROJECTION_TERMS
    assert method == "recursive"
    assert reason.startswith("the projection method would form up to")
    assert "the recursive method is exact and gives the same base set" in reason
    assert expanded in reason
    # a single-DOF robot's reason does not mention it
    assert expanded not in mindyn.base_parameters("puma560").method_reason


def test_rotor_inertia_friction_and_offsets_stay_refused_on_multidof_joints():
    robot, _ = urdf_pair("solo12")
    for method in (*EXACT, "numerical", None):
        with pytest.raises(mindyn.ModelError, match="rotor inertia and friction are defined"):
            mindyn.base_parameters(robot, method=method, rotor=True)
        with pytest.raises(mindyn.ModelError, match="torque offsets are defined for revolute"):
            mindyn.base_parameters(robot, method=method, offset=True)


def test_a_floating_body_s_lagrangian_in_the_projection_basis(tmp_path):
    """A free body hanging from the world, in the projection method's own basis
    (influence_coordinates, its floating root taken as it is): sum_r Z[r] pi * f_r, the basis
    functions evaluated from their names at a random twist v, gravity direction u = R^T g / |g|
    and height h = g . p / |g|, equals the closed form L = 1/2 m |v_o|^2 + m v_o . (w x c)
    + 1/2 w^T I_o w + |g| (m h + u . m c)."""
    import yaml

    rng = np.random.default_rng(3)
    inertia = {"xx": 0.3, "xy": 0.02, "xz": -0.01, "yy": 0.25, "yz": 0.03, "zz": 0.2}
    doc = {
        "name": "body",
        "convention": "mdh",
        "joints": [
            {
                "name": "free",
                "type": "floating",
                "parent": 0,
                "alpha": 0.0,
                "d": 0.0,
                "theta": 0.0,
                "r": 0.0,
                "inertial": {"mass": 2.5, "com": [0.1, -0.2, 0.05], "inertia": inertia},
            }
        ],
    }
    path = tmp_path / "body.yaml"
    path.write_text(yaml.safe_dump(doc))
    robot = mindyn.load(path)
    Z, basis = _core.influence_coordinates(robot._m)
    # the non-zero rows: the six squares, the three products of w, the six of v_o and w off
    # the diagonal (v_o . (w x c)); u and h
    assert len(basis) == 6 + 3 + 6 + 4, basis
    xx, xy, xz, yy, yz, zz, mx, my, mz, m = robot.params
    Io = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    mc = np.array([mx, my, mz])
    g = np.linalg.norm(robot.gravity)
    for _ in range(5):
        w, vo = rng.normal(size=3), rng.normal(size=3)
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        h = rng.normal()
        values = dict(zip(("vx1", "vy1", "vz1", "wx1", "wy1", "wz1"), (*vo, *w), strict=True))
        values.update({"ux1": u[0], "uy1": u[1], "uz1": u[2], "h1": h})

        lagrangian = sum(
            Z[r] @ robot.params * _evaluate(name, values) for r, name in enumerate(basis)
        )
        closed = 0.5 * m * vo @ vo + vo @ np.cross(w, mc) + 0.5 * w @ Io @ w + g * (m * h + u @ mc)
        assert abs(lagrangian - closed) <= 1e-12 * (abs(closed) + 1), (lagrangian, closed)


def _evaluate(name: str, values: dict) -> float:
    """A basis function's value from its name (factors joined by ``*``, powers by ``^``)."""
    out = 1.0
    for factor in name.split("*"):
        base, _, power = factor.partition("^")
        out *= (float(base) if base[0].isdigit() else values[base]) ** int(power or 1)
    return out


def test_a_forced_projection_refusal_says_how_the_joints_were_counted():
    """TIAGo (the full description) on a planar root: 49 joints, 51 once the planar pair is
    taken as its three single-DOF joints, over the projection method's 44 on a tree. The
    refusal with method='projection' says how 51 was counted, as the default method's reason
    does (it named 51 joints of a 49-joint model without saying why)."""
    path = FLOATING["talos"].parents[2] / "tiago_description" / "robots" / "tiago.urdf"
    robot = mindyn.load(path, root_joint="planar")
    expanded = robot.n - 1 + 3  # the planar pair: x, y, yaw
    assert robot.n == 49 and robot.nv == expanded
    _, reason = choose_method(robot)
    with pytest.raises(mindyn.ModelError) as info:
        mindyn.base_parameters(robot, method="projection")
    message = str(info.value)
    assert f"the model has {expanded} (" in message and "counted as its chain" in message
    assert message.startswith(reason.split("; the recursive method")[0])
