"""Base parameters of long chains. The numerical method's sample counts grow with the number of
parameters: its three counts equal the exact projection method's on generic 8-12 joint arms, and
a 100-joint chain gives the closed-form count. The projection method estimates its cost on the
sparsity patterns before computing (an upper bound, checked here against what it then forms) and
refuses a chain over its memory budget at once, with the estimate and what to use instead."""

from __future__ import annotations

import subprocess
import sys

import mindyn
import numpy as np
import pytest
import yaml
from mindyn import _core, codegen
from random_arm import random_arm_yaml


def general_chain(path, n: int, seed: int = 0) -> mindyn.Robot:
    """An n-joint revolute MDH chain with every twist a general angle (20-70 degrees): the
    basis grows by about five per joint, the worst case for the projection method."""
    rng = np.random.default_rng(seed)
    joints = [
        {
            "name": f"j{k + 1}",
            "type": "revolute",
            "alpha": float(rng.uniform(20, 70)),
            "d": float(rng.uniform(0.1, 0.3)),
            "theta": 0.0,
            "r": float(rng.uniform(0.05, 0.2)),
            "inertial": {
                "mass": float(rng.uniform(1, 3)),
                "com": rng.uniform(-0.05, 0.05, 3).tolist(),
                "inertia": {"xx": 0.02, "yy": 0.03, "zz": 0.025, "xy": 0.001, "xz": 0, "yz": 0},
            },
        }
        for k in range(n)
    ]
    doc = {"name": f"general{n}", "convention": "mdh", "angle_unit": "deg", "joints": joints}
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return mindyn.load(str(path))


def counts(bp) -> list[int]:
    return [bp.sets[k]["n"] for k in ("lagrangian", "energy", "eom")]


@pytest.mark.parametrize("n, seed", [(8, 1), (10, 2), (11, 3)])
def test_numerical_counts_equal_projection_on_random_arms(n, seed, tmp_path):
    """Before the sample counts grew with the parameters, a 10-joint arm gave 50/50/66 by the
    numerical method (50 energy samples) against 67/67/66."""
    robot = mindyn.load(str(random_arm_yaml(tmp_path / "arm.yaml", n, seed)))
    exact = mindyn.base_parameters(robot)
    sampled = mindyn.base_parameters(robot, method="numerical")
    assert counts(sampled) == counts(exact)
    assert sampled.pivots == exact.pivots
    if n >= 10:
        assert min(counts(exact)) > 50


def test_numerical_counts_equal_projection_on_a_general_chain(tmp_path):
    robot = general_chain(tmp_path / "g.yaml", 9)
    assert counts(mindyn.base_parameters(robot, method="numerical")) == counts(
        mindyn.base_parameters(robot)
    )


def test_numerical_method_on_a_100_joint_chain():
    """planar100: 3 n = 300 base parameters in each set (ZZR, MXR, MY per link, the closed form
    of test_planar_counts); the projection method refuses it (at most 18 joints)."""
    bp = mindyn.base_parameters("planar100", method="numerical")
    assert counts(bp) == [300, 300, 300]
    with pytest.raises(mindyn.ModelError, match="at most 18 joints.*numerical"):
        mindyn.base_parameters("planar100", method="projection")


def test_numerical_method_refuses_a_chain_over_its_budget():
    """planar400: 4000 parameters and 20000 stacked rows, about 2.4 GiB, over the 2 GiB."""
    with pytest.raises(
        mindyn.ModelError, match=r"about 2.4 GiB for this 400-joint chain.*budget of 2 GiB"
    ):
        mindyn.base_parameters("planar400", method="numerical")


def test_too_few_samples_refused():
    with pytest.raises(mindyn.ModelError, match="samples = 2 states give 12 regressor rows"):
        mindyn.base_parameters("puma560", method="numerical", samples=2)


@pytest.mark.parametrize(
    "make",
    [
        lambda p: general_chain(p / "g.yaml", 6),
        lambda p: general_chain(p / "g.yaml", 8, seed=4),
        lambda p: mindyn.load(str(random_arm_yaml(p / "a.yaml", 9, 5))),
        lambda p: mindyn.load("planar9"),
        lambda p: mindyn.load("puma560"),
        lambda p: mindyn.load("stanford"),
    ],
)
def test_cost_estimate_bounds_what_is_formed(make, tmp_path):
    robot = make(tmp_path)
    cost = _core.projection_cost(robot._m)
    bp = mindyn.base_parameters(robot)
    assert cost["terms"] >= bp.terms_formed
    assert cost["rows"] >= bp.basis_rows
    Z, _ = _core.influence_coordinates(robot._m)
    assert cost["entries"] >= np.count_nonzero(Z)
    print(
        f"\n{robot.name}: terms {bp.terms_formed} (estimate {cost['terms']:.0f}), rows "
        f"{bp.basis_rows} ({cost['rows']:.0f}), entries {np.count_nonzero(Z)} "
        f"({cost['entries']:.0f})"
    )


def test_cost_estimate_is_tight_for_general_axes(tmp_path):
    """With general twists nothing cancels: the terms estimate is within 1 % of the count."""
    for n in (5, 7, 9):
        robot = general_chain(tmp_path / "g.yaml", n, seed=n)
        estimate = _core.projection_cost(robot._m)["terms"]
        formed = mindyn.base_parameters(robot).terms_formed
        assert formed <= estimate <= 1.01 * formed


@pytest.mark.parametrize("n", [12, 14, 18])
def test_projection_refuses_long_general_chains(n, tmp_path):
    robot = general_chain(tmp_path / "g.yaml", n)
    cost = _core.projection_cost(robot._m)
    assert cost["bytes"] > cost["budget"]
    with pytest.raises(mindyn.ModelError) as e:
        mindyn.base_parameters(robot, method="projection")
    msg = str(e.value)
    assert f"{n}-joint chain" in msg and "GiB" in msg and "budget of 8 GiB" in msg
    assert "method='numerical'" in msg
    # the way out works
    assert counts(mindyn.base_parameters(robot, method="numerical"))[2] > 0


def test_codegen_chooses_the_recursive_method_where_the_projection_method_refuses():
    # planar18: over the projection method's memory estimate
    assert "budget" in _core.projection_refusal(mindyn.load("planar18")._m)
    code = codegen.generate("planar18", what="gravity")
    bp = mindyn.base_parameters("planar18", method="numerical")
    assert bp.n == 54 == len(code.names)
    assert "void" in codegen.generate("planar18", base=bp, what="gravity").source


@pytest.mark.parametrize(
    "args",
    [
        # without --method, `mindyn base` and `mindyn codegen` compute such a chain by the
        # recursive method
        ("base", "planar17", "--method", "projection"),
        ("codegen", "planar18", "--lang", "c", "--method", "projection", "-o", "robot.c"),
    ],
)
def test_cli_refuses_in_one_line(args, tmp_path):
    r = subprocess.run(
        [sys.executable, "-m", "mindyn", *args],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=tmp_path,
    )
    assert r.returncode != 0
    lines = r.stderr.splitlines()
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith("mindyn: error: ") and "numerical" in lines[0]
