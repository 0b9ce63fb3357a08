"""The recursive method: the same base set and the same Y as the projection method wherever the
projection runs (bundled robots, the example-robot-data arms, random arms with rotor inertia and
friction), the sampled numerical method's counts and Pinocchio's torques on 20-joint chains the
projection refuses and on trees, and the command line's choice of method."""

from __future__ import annotations

import json

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import ROBOTS_DIR, pinocchio_model
from random_arm import random_arm_yaml
from random_tree import random_tree_urdf
from test_base_parameters import ARMS, NEAR_EXACT, check_against_rnea, run_cli
from test_base_parameters_scale import counts, general_chain


def assert_same(robot, what, **options):
    """Same names, pivots and Y (to 1e-10: both are exact up to rounding, which stays below
    1e-12 on these robots) in all three sets, and the same statement about them."""
    proj = mindyn.base_parameters(robot, **options)
    rec = mindyn.base_parameters(robot, method="recursive", **options)
    assert rec.method == "recursive"
    assert rec.names == proj.names, what
    assert rec.pivots == proj.pivots, what
    np.testing.assert_allclose(rec.Y, proj.Y, rtol=0, atol=1e-10, err_msg=what)
    for key in ("lagrangian", "energy", "eom"):
        assert rec.sets[key]["names"] == proj.sets[key]["names"], (what, key)
        np.testing.assert_allclose(
            rec.sets[key]["Y"], proj.sets[key]["Y"], rtol=0, atol=1e-10, err_msg=f"{what} {key}"
        )
        assert rec.sets[key]["no_effect"] == proj.sets[key]["no_effect"], (what, key)
    assert rec.lagrangian_equals_eom == proj.lagrangian_equals_eom
    # The counts at the neighbouring tolerances, and so the warning, are the projection's.
    for key in ("near_degenerate", "rank_at_looser_tolerance", "rank_at_tighter_tolerance"):
        assert rec.margin[key] == proj.margin[key], (what, key)
    return rec


@pytest.mark.parametrize(
    "name", ["puma560", "puma560_3", "zcr07s", "stanford", "planar5", "planar5h", "planar1"]
)
@pytest.mark.parametrize("extras", [{}, {"rotor": True}, {"rotor": True, "friction": True}])
def test_bundled_robots(name, extras):
    assert_same(mindyn.load(name), name, **extras)


def test_zcr07s_with_rotor_friction_and_offsets():
    rec = assert_same(mindyn.load("zcr07s"), "zcr07s", rotor=True, friction=True, offset=True)
    # the ZCR07S study's published count with Ia, Fv, Fc: 52, and the offsets
    assert rec.n == 52 + 6


@pytest.mark.parametrize("rel", sorted(ARMS))
def test_arm_urdfs(rel):
    robot = mindyn.load(ROBOTS_DIR / rel, tip=ARMS[rel])
    assert_same(robot, rel)
    assert_same(robot, rel, rotor=True, friction=True)


@pytest.mark.parametrize("rel", sorted(NEAR_EXACT))
def test_near_right_angles_are_decided_as_snapped(rel):
    """An axis tilted by 2e-13 rad: the recursion's decision is that of the snapped model, and
    the margin shows a dropped residual well above rounding (1e-16), below the tolerance."""
    robot = mindyn.load(ROBOTS_DIR / rel, tip=ARMS[rel])
    rec = mindyn.base_parameters(robot, method="recursive", snap=False)
    snapped = mindyn.base_parameters(robot, snap=True)
    # The same pivots; a name may differ by its R when the tilt leaves a coefficient of 1e-13.
    assert rec.pivots == snapped.pivots
    np.testing.assert_allclose(rec.Y, snapped.Y, rtol=0, atol=1e-10)
    assert 1e-14 < rec.margin["largest_dropped"] < 1e-9


@pytest.mark.parametrize("seed", range(4))
def test_random_arms_with_rotor_and_friction(seed, tmp_path):
    robot = mindyn.load(str(random_arm_yaml(tmp_path / "arm.yaml", 6, seed)))
    assert_same(robot, f"random arm {seed}", rotor=True, friction=True)


def test_general_chain(tmp_path):
    robot = general_chain(tmp_path / "g.yaml", 7, seed=3)
    assert_same(robot, "general7", rotor=True)


@pytest.mark.parametrize("make", ["planar20", "general20", "random20"])
def test_20_joint_chains_against_the_sampled_regressor_and_pinocchio(make, tmp_path, rng):
    """The projection refuses them (more than 18 joints); the counts of the three sets equal the
    rank of the sampled regressors, and W_b Y pi equals Pinocchio's inverse dynamics."""
    if make == "planar20":
        robot = mindyn.load("planar20")
    elif make == "general20":
        robot = general_chain(tmp_path / "g.yaml", 20, seed=7)
    else:
        robot = mindyn.load(str(random_arm_yaml(tmp_path / "arm.yaml", 20, 3)))
    rec = mindyn.base_parameters(robot, method="recursive", rotor=True, friction=True)
    num = mindyn.base_parameters(robot, method="numerical", rotor=True, friction=True)
    assert counts(rec) == counts(num)
    assert rec.margin["near_degenerate"] is False
    with pytest.raises(mindyn.ModelError, match="at most 18 joints.*method='recursive'"):
        mindyn.base_parameters(robot, method="projection")
    assert mindyn.base_parameters(robot).method == "recursive"  # the default's choice
    # 1e-9: the lever arms out to the 20th link make Y's entries up to about 1e2.
    check_against_rnea(rec, robot, pinocchio_model(robot), rng, f"{make} recursive", tol=1e-9)


def test_planar_closed_form_count():
    """A vertical planar chain: ZZR, MXR, MY per link (test_planar_counts), and Ia per joint but
    the first, whose column q''_1 in joint 1's equation is ZZ1's (link 1 only turns about it)."""
    rec = mindyn.base_parameters("planar30", method="recursive", rotor=True)
    assert rec.n == 3 * 30 + 30 - 1
    assert "Ia1" not in rec.names and "Ia2" in rec.names


def test_cli_falls_back_to_recursive_and_says_why():
    r = run_cli("base", "planar20")
    assert r.returncode == 0, r.stderr
    assert "base parameters by the recursive method" in r.stdout
    assert "method         recursive: the projection method handles at most 18 joints" in r.stdout
    r = run_cli("base", "puma560", "--format", "json")
    out = json.loads(r.stdout)
    assert out["method"] == "projection" and out["method_reason"].startswith("the default")
    r = run_cli("base", "puma560", "--method", "recursive", "--format", "json")
    out = json.loads(r.stdout)
    assert out["method"] == "recursive" and out["method_reason"] == "--method recursive"
    assert out["n_base"] == 36


def test_cli_falls_back_when_the_cost_estimate_refuses(tmp_path):
    general_chain(tmp_path / "g.yaml", 12)
    r = run_cli("base", tmp_path / "g.yaml")
    assert r.returncode == 0, r.stderr
    assert "recursive: the projection method would need up to" in r.stdout
    assert "over its budget of 8 GiB" in r.stdout


def test_cli_explicit_projection_refusal_names_the_recursive_method():
    r = run_cli("base", "planar20", "--method", "projection")
    assert r.returncode != 0
    line = r.stderr.strip()
    assert line.startswith("mindyn: error: ") and "\n" not in line
    assert "--method recursive" in line


def test_bad_method_is_refused():
    with pytest.raises(
        mindyn.ArgumentError, match="^method .*'projection', 'recursive', 'numerical'"
    ):
        mindyn.base_parameters("puma560", method="recursiv")


PRISMATIC_FIRST = """name: pp_r
convention: dh
joints:
  - {type: prismatic, a: 0.1, alpha: 0, d: 0.2, theta: 0}
  - {type: prismatic, a: 0.1, alpha: 0.5, d: 0.2, theta: 0}
  - {a: 0.1, alpha: 1.0, d: 0.2, theta: 0}
"""


@pytest.mark.parametrize(
    "gravity, ia1_alone",
    [((0.0, 0.0, -9.81), True), ((9.81, 0.0, 0.0), False), ((0.0, 0.0, 0.0), False)],
)
def test_prismatic_rotor_inertia_and_gravity(gravity, ia1_alone, tmp_path):
    """A prismatic first joint along z: its rotor term Ia1 q''_1 is the unit mass M1 moving
    along z unless gravity acts along the joint (then M1 also carries a gravity force); without
    gravity nothing of link 1 is seen but its mass."""
    path = tmp_path / "pp_r.yaml"
    path.write_text(PRISMATIC_FIRST)
    robot = mindyn.load(path).with_gravity(gravity)
    rec = assert_same(robot, f"prismatic, g = {gravity}", rotor=True, friction=True)
    num = mindyn.base_parameters(robot, method="numerical", rotor=True, friction=True)
    assert counts(rec) == counts(num)
    assert ("Ia1" in rec.names) == ia1_alone


def test_zero_gravity():
    for name in ("puma560", "stanford"):
        robot = mindyn.load(name).with_gravity([0.0, 0.0, 0.0])
        rec = assert_same(robot, f"{name} without gravity", rotor=True)
        assert counts(rec) == counts(mindyn.base_parameters(robot, method="numerical", rotor=True))


@pytest.mark.parametrize("seed", range(3))
def test_random_trees_with_rotor_and_friction(seed, tmp_path):
    """Trees (tests/random_tree.py: random parents, axes and joint kinds): the numerical
    method's count, and Pinocchio's rnea of a random pi (armature, friction added) equals
    W_b (Y pi) (1e-9 relative: the method's own accuracy requirement)."""
    path = random_tree_urdf(tmp_path / "tree.urdf", 7 + 3 * seed, 40 + seed, fixed=0)
    robot = mindyn.load(path)
    assert not robot.is_serial
    model = pin.buildModelFromUrdf(str(path))
    rng = np.random.default_rng(seed)
    for extras in ({}, {"rotor": True, "friction": True}):
        rec = mindyn.base_parameters(robot, method="recursive", **extras)
        num = mindyn.base_parameters(robot, method="numerical", **extras)
        assert rec.n == num.n, (seed, extras)
        check_against_rnea(rec, robot, model, rng, f"tree {seed} {extras}", tol=1e-9)
