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
import re
from decimal import Decimal, localcontext

import mindyn
import mpmath
import numpy as np
import pytest
from test_base_size_invariance import DIGITS, exact_rank, exact_regressor
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


# A chain of 1 km (robot length 1024 m) on a prismatic first joint, its right angles written
# rounded (1.5708, 3.14159, 3.1416, 1.57079633: 2.6e-6 .. 7.3e-6 rad off) and two axes 1e-8 ..
# 1e-10 off a coordinate axis: per joint the origin (xyz, rpy), the axis and the type; per link
# the inertial (com, its rpy, mass, ixx ixy ixz iyy iyz izz).
ROUNDED_JOINTS = [
    ("prismatic", "246.68838919503295 175.7479559212965 0.0", "1.57079633 0.7854 0.7854",
     "-3.007406119383881e-10 1.2494720573512096e-08 1.0"),
    ("continuous", "87.29124605310967 282.51700028203015 266.59145795003275",
     "3.1416 3.14159 3.14159", "1.0 0.0 0.0"),
    ("continuous", "-14.539375623435769 88.56241626465555 144.05546566587535",
     "0.0 1.57079633 3.14159", "0.0 -1.0 0.0"),
    ("revolute", "108.08452716778699 -267.64156323526464 -30.71757378218576",
     "-3.14159 1.5708 1.5708", "-9.115481941849996e-10 1.0 4.227960813446235e-10"),
]  # fmt: skip
ROUNDED_LINKS = [
    ("134.28039979463293 -36.9776317486017 31.67834018164628", "3.14159 3.1416 1.5708",
     0.8171202244216369, "1462.0813006006988 -312.76099250607854 -232.01146307963984 "
     "1639.3088164931653 100.46573996958418 1473.3140356532756"),
    ("14.691103802082385 28.144218289622742 -146.27229003684764",
     "0.6658014423329184 1.647459607169452 1.9486816670595077", 2.6704429696011682,
     "6262.74719110597 -411.85774154694906 -118.04013431360877 6001.169573135209 "
     "-73.48932164303274 6552.15806996598"),
    ("-88.77114930549097 106.58340357453986 118.4417335903333", "1.571 1.57079633 0.0",
     0.3003282593269164, "718.2722762476304 -18.564804275441247 127.41717121081363 "
     "860.1941851495214 -116.16088947035023 363.77280681123403"),
    ("-70.8291905913709 132.35817260764296 -33.057284264503274",
     "1.072585245649833 -3.047523205723109 3.0602547361798456", 2.3808963207210145,
     "2775.0012054505264 4.583963689713962 126.43117077968839 2733.506772301933 "
     "-296.25757145812946 2914.7990983356954"),
    ("-8.096690488279574 -136.12118346334168 -144.06842364619018",
     "0.2510526502862538 1.6350957292410175 0.12506837448725205", 2.354229029277869,
     "3928.4552315743535 -246.58165081879733 -493.74690486037474 3650.825100335091 "
     "76.67320168945383 3976.7216217380155"),
]  # fmt: skip


def rounded_chain_urdf() -> str:
    links = []
    for k, (com, rpy, mass, inertia) in enumerate(ROUNDED_LINKS):
        i = dict(zip(("ixx", "ixy", "ixz", "iyy", "iyz", "izz"), inertia.split()))
        attrs = " ".join(f'{key}="{value}"' for key, value in i.items())
        links.append(
            f'<link name="l{k}"><inertial><origin xyz="{com}" rpy="{rpy}"/>'
            f'<mass value="{mass!r}"/><inertia {attrs}/></inertial></link>'
        )
    joints = []
    for k, (kind, xyz, rpy, axis) in enumerate(ROUNDED_JOINTS, start=1):
        limit = "" if kind == "continuous" else ' lower="-2" upper="2"'
        joints.append(
            f'<joint name="j{k}" type="{kind}"><origin xyz="{xyz}" rpy="{rpy}"/>'
            f'<parent link="l{k - 1}"/><child link="l{k}"/><axis xyz="{axis}"/>'
            f'<limit{limit} effort="50" velocity="3"/></joint>'
        )
    return '<robot name="rounded">' + "".join(links + joints) + "</robot>"


@pytest.mark.parametrize("friction", [False, True])
def test_rounded_right_angles_on_a_prismatic_root(tmp_path, friction):
    """The rank of the regressor written out with 60 digits is 18 (26 with friction): the next
    pivot is at the 60-digit round-off. The recursion kept a row of 7.7e-8 beside the rows that
    only the rounded right angles set apart (directions of 3e-7 and 8e-8 of what link 2 shows
    of link 3): it sized a direction by what was left of the vector that brought it in, and
    then by the components of the vectors offered after it, so that its count depended on the
    order in which they came (19). Every method gives the rank, or refuses with the reason of
    the regrouping check (a base set of the right count whose regrouping misses the dynamics by
    more than the check allows); none gives another count."""
    path = tmp_path / "rounded.urdf"
    path.write_text(rounded_chain_urdf())
    rank, pivots = exact_rank(path, rotor=False, friction=friction)
    assert pivots[rank - 1] > Decimal("1e-20") and pivots[rank] < Decimal("1e-45"), pivots
    robot = mindyn.load(path)
    for method in ("projection", "recursive", "numerical"):
        try:
            bp = mindyn.base_parameters(robot, method=method, friction=friction, snap=False)
        except mindyn.ModelError as e:
            message = str(e)
            assert method == "recursive", (method, message)
            assert "does not reproduce the dynamics" in message, message
            # the refused set has the rank's count all the same
            assert re.search(rf"\({rank} parameters at rank tolerance", message), message
            continue
        assert bp.n == rank, (method, bp.names)
