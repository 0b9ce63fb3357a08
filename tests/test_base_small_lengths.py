"""Nearly degenerate geometry where the recursive method's rules branch: a length of 1e-12 ..
1e-6 of the robot's size across two parallel axes, and an axis 1e-12 .. 1e-2 rad off parallel
to the one before it. The three methods must give the count of the reference: the rank of the
regressor stacked at random states, written out by Newton-Euler with 60 digits from the
description's own numbers (the regressor test_base_size_invariance checks against mindyn's),
its singular values with 50 digits (mpmath), in the unit-length model the methods decide in
(lengths divided by the robot's length L = 0.5 m, time in sqrt(L / 1 m) s, rates sampled in
[-2, 2] there, gravity 9.81), at the default tolerance (singular values above it times the
largest).

Small lengths: two parallel horizontal axes, each joint's origin s L across its link's line in
the plane of motion (the right angles written as 1.5707963267948966): a planar arm in a vertical
plane, whose count is 6 (7 with rotor inertia) for every s. The recursion normalised the motion
that s turns away from gravity (s / 0.4 of it) and with it the rounding of the written right
angles (6e-17) grew to 1e-10 in its rows: 8 base parameters at s = 1e-8, a refusal at 1e-6, a
near-degenerate flag at 1e-12 and 1e-10.

Nearly parallel axes (a right angle of 1.5708 written rounded leaves 3.7e-6): what the links'
inertia shows of the motion by which the axes differ is of the size of the angle, and what only
its square shows (1e-12 at 1e-6 rad) is below the tolerance. The recursion counted the
difference at full size once kept: 10 base parameters at 1e-6 rad where the regressor has 8."""

from __future__ import annotations

import math
from decimal import Decimal, localcontext

import mindyn
import mpmath
import numpy as np
import pytest
from test_base_size_invariance import DIGITS, exact_regressor
from test_base_size_invariance import _joints as exact_joints

TOLERANCE = 1e-9  # the default rank tolerance, stated
GRAVITY = 9.81
LENGTH = 0.5  # the robot's length as the methods take it: its longest root path, 0.6 or 0.55 m,
# rounded to a power of two
HALF_PI = 1.5707963267948966  # pi / 2 as a URDF writes it, to double precision

INERTIALS = [
    ("-0.03 0.03 -0.12", 2.5, (0.26, 0.006, -0.014, 0.2, -0.007, 0.15)),
    ("0.18 0.2 -0.18", 2.6, (0.22, -0.005, -0.009, 0.23, -0.002, 0.24)),
]


def offset_chain(s: float) -> list[dict]:
    """Joint 1 about the base's x axis (its frame turned -pi/2 about x), 0.4 m up and s L along
    y; joint 2 parallel to it (its frame turned so that its z axis is joint 1's x axis), 0.2 m
    along link 1's z axis and -s L along its y axis."""
    d = s * LENGTH
    return [
        {"xyz": (0.0, d, 0.8 * LENGTH), "rpy": (-HALF_PI, 0.0, 0.0), "axis": (1.0, 0.0, 0.0)},
        {"xyz": (0.0, -d, 0.4 * LENGTH), "rpy": (HALF_PI, 0.0, -HALF_PI), "axis": (0.0, 0.0, 1.0)},
    ]


def tilted_chain(angle: float) -> list[dict]:
    """Joint 1 about the base's x axis, joint 2 about an axis turned `angle` from it about z,
    0.245 m away."""
    return [
        {"xyz": (0.0, 0.0, 0.3), "rpy": (0.0, 0.0, 0.0), "axis": (1.0, 0.0, 0.0)},
        {
            "xyz": (0.1, 0.2, -0.1),
            "rpy": (0.0, 0.0, 0.0),
            "axis": (math.cos(angle), math.sin(angle), 0.0),
        },
    ]


def chain_urdf(joints: list[dict]) -> str:
    links, parts = ['<link name="base"/>'], []
    for k, (joint, (com, mass, inertia)) in enumerate(zip(joints, INERTIALS), start=1):
        ixx, ixy, ixz, iyy, iyz, izz = inertia
        links.append(
            f'<link name="l{k}"><inertial><origin xyz="{com}"/><mass value="{mass}"/>'
            f'<inertia ixx="{ixx}" ixy="{ixy}" ixz="{ixz}" iyy="{iyy}" iyz="{iyz}" izz="{izz}"/>'
            "</inertial></link>"
        )
        xyz = " ".join(repr(float(x)) for x in joint["xyz"])
        rpy = " ".join(repr(float(x)) for x in joint["rpy"])
        axis = " ".join(repr(float(x)) for x in joint["axis"])
        parent = "base" if k == 1 else f"l{k - 1}"
        parts.append(
            f'<joint name="j{k}" type="revolute"><parent link="{parent}"/><child link="l{k}"/>'
            f'<origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="{axis}"/>'
            '<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>'
        )
    return '<robot name="chain">' + "".join(links + parts) + "</robot>"


def reference_ratios(joints, rotor, tmp_path, states=20, seed=3):
    """sigma_i / sigma_1 of the regressor stacked at random states, largest first: the
    60-digit Newton-Euler regressor of the URDF's numbers (test_base_size_invariance) of the
    arm at unit length, its singular values with 50 digits."""
    path = tmp_path / "unit.urdf"
    path.write_text(chain_urdf([{**j, "xyz": tuple(x / LENGTH for x in j["xyz"])} for j in joints]))
    rng = np.random.default_rng(seed)
    n = len(joints)
    with localcontext() as ctx:
        ctx.prec = DIGITS
        unit = exact_joints(path)
        rows = []
        for _ in range(states):
            q = [Decimal(float(x)) for x in rng.uniform(-math.pi, math.pi, n)]
            dq, ddq = ([Decimal(float(x)) for x in rng.uniform(-2.0, 2.0, n)] for _ in range(2))
            rows += exact_regressor(unit, q, dq, ddq, Decimal(GRAVITY))
    cols = [c for c in range(11 * n) if rotor or c % 11 != 10]
    mpmath.mp.dps = 50
    A = mpmath.matrix([[mpmath.mpf(str(r[c])) for c in cols] for r in rows])
    sv = mpmath.svd_r(A, compute_uv=False)
    values = sorted((sv[i] for i in range(sv.rows)), reverse=True)
    return [float(s / values[0]) for s in values]


def check_three_methods(tmp_path, joints, rotor):
    path = tmp_path / "chain.urdf"
    path.write_text(chain_urdf(joints))
    ratios = reference_ratios(joints, rotor, tmp_path)
    # the reference decides clearly: no singular value within a factor 5 of the tolerance
    assert all(r > 5 * TOLERANCE or r < TOLERANCE / 5 for r in ratios), ratios
    count = sum(r > TOLERANCE for r in ratios)
    margins = {}
    for method in ("projection", "recursive", "numerical"):
        bp = mindyn.base_parameters(path, method=method, snap=False, rotor=rotor)
        assert bp.n == count, (method, bp.names, ratios)
        assert bp.margin["tolerance"] == TOLERANCE
        margins[method] = bp.margin
    return count, ratios, margins


@pytest.mark.parametrize("rotor", [False, True])
@pytest.mark.parametrize("s", [0.0, 1e-12, 1e-10, 1e-8, 1e-6])
def test_a_small_length_across_parallel_axes(tmp_path, s, rotor):
    count, _, margins = check_three_methods(tmp_path, offset_chain(s), rotor)
    assert count == (7 if rotor else 6)  # the planar arm's closed form, whatever s
    for method, margin in margins.items():
        # a clear decision: nothing near the tolerance, nothing said to depend on it
        assert not margin["near_degenerate"], (method, margin)
        assert margin["decided_by_tolerance"] == [], (method, margin)


@pytest.mark.parametrize("rotor", [False, True])
@pytest.mark.parametrize("angle", [1e-12, 1e-6, 1e-2])
def test_an_axis_nearly_parallel_to_the_one_before(tmp_path, angle, rotor):
    count, ratios, margins = check_three_methods(tmp_path, tilted_chain(angle), rotor)
    # the angle sets apart two columns at its size and two more at its square
    assert count == (6 if angle < 1e-10 else 8 if angle < 1e-4 else 10) + rotor, ratios
    for method, margin in margins.items():
        if angle == 1e-6:
            # the parameters the angle sets apart act within the band of the neighbouring
            # tolerances: flagged, and named (among them the first moments, which the angle
            # turns out of the plane of joint 1's motion)
            assert margin["near_degenerate"], (method, margin)
            assert {"MX2", "MY2"} <= set(margin["decided_by_tolerance"]), (method, margin)
