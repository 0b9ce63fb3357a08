"""Nearly degenerate geometry: one revolute joint whose axis is tilted by 1e-12 .. 1e-6 rad off
the vertical. Any nonzero tilt lets gravity act on the link's first moments (3 base parameters
instead of 1), but at 1e-12 rad their regressor columns are 1e-11 of the inertial one, which no
floating-point rank decision resolves: the count that is right is the one the stated tolerance
gives. The reference is the rank of the stacked regressor written out in closed form and
computed with 60 digits (mpmath): the number of singular values above the tolerance times the
largest, in the unit-length model the methods decide in (here the robot's length is 0.5 m, the
time unit sqrt(0.5) s, joint accelerations sampled in [-2, 2] there, gravity 9.81). The three
methods must give that count at the default tolerance, each decision near the tolerance flagged
with the parameters it affects."""

from __future__ import annotations

import math

import mindyn
import mpmath
import numpy as np
import pytest

TOLERANCE = 1e-9  # the default rank tolerance, stated
GRAVITY = 9.81


def tilted_joint_urdf(tilt: float) -> str:
    """One revolute joint 0.5 m above the base, its axis ``tilt`` rad off z towards x, and a
    link with a first moment off the axis and a full inertia."""
    axis = f"{math.sin(tilt)!r} 0 {math.cos(tilt)!r}"
    return f"""<robot name="tilted">
  <link name="base"/>
  <link name="l1">
    <inertial><origin xyz="0.1 0.2 0.3"/><mass value="2"/>
      <inertia ixx="0.1" ixy="0.01" ixz="0.02" iyy="0.2" iyz="0.03" izz="0.3"/></inertial>
  </link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.5"/><axis xyz="{axis}"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>"""


def reference_singular_values(tilt: float, states: int = 40, seed: int = 7) -> list:
    """Singular values of the stacked regressor of the tilted joint, largest first, from the
    closed form with 60 digits. The axis is the description's (its floating-point numbers,
    normalised exactly); the link turns by q about it, R = Rot(a, q), so with the inertia J at
    the link's origin and its first moment h (link frame),
    tau = (a^T J a) q'' - g^T (a x R h)   (no velocity term: R a = a),
    linear in (XX, XY, XZ, YY, YZ, ZZ, MX, MY, MZ, M); the mass has no effect."""
    mpmath.mp.dps = 60
    a = [mpmath.mpf(math.sin(tilt)), mpmath.mpf(0), mpmath.mpf(math.cos(tilt))]
    norm = mpmath.sqrt(sum(x * x for x in a))
    a = [x / norm for x in a]
    g = [mpmath.mpf(0), mpmath.mpf(0), -mpmath.mpf(GRAVITY)]
    rng = np.random.default_rng(seed)
    rows = []
    for _ in range(states):
        q = mpmath.mpf(float(rng.uniform(-math.pi, math.pi)))
        ddq = mpmath.mpf(float(rng.uniform(-2.0, 2.0)))
        c, s = mpmath.cos(q), mpmath.sin(q)
        inertia = [
            a[0] * a[0],
            2 * a[0] * a[1],
            2 * a[0] * a[2],
            a[1] * a[1],
            2 * a[1] * a[2],
            a[2] * a[2],
        ]
        first = []
        for i in range(3):
            e = [mpmath.mpf(int(i == k)) for k in range(3)]
            # Rodrigues: R e = e c + (a x e) s + a (a . e)(1 - c)
            axe = [a[1] * e[2] - a[2] * e[1], a[2] * e[0] - a[0] * e[2], a[0] * e[1] - a[1] * e[0]]
            ae = sum(a[k] * e[k] for k in range(3))
            Re = [e[k] * c + axe[k] * s + a[k] * ae * (1 - c) for k in range(3)]
            aRe = [
                a[1] * Re[2] - a[2] * Re[1],
                a[2] * Re[0] - a[0] * Re[2],
                a[0] * Re[1] - a[1] * Re[0],
            ]
            first.append(-sum(g[k] * aRe[k] for k in range(3)))
        rows.append([x * ddq for x in inertia] + first + [mpmath.mpf(0)])
    sv = mpmath.svd_r(mpmath.matrix(rows), compute_uv=False)
    return sorted((sv[i] for i in range(sv.rows)), reverse=True)


def reference_count(tilt: float, tolerance: float) -> tuple[int, list[float]]:
    """The rank at ``tolerance`` (singular values above it times the largest) and the ratios
    sigma_i / sigma_1 (the tolerances at which the count changes)."""
    sv = reference_singular_values(tilt)
    ratios = [float(s / sv[0]) for s in sv]
    return sum(r > tolerance for r in ratios), ratios


@pytest.mark.parametrize("tilt", [0.0, 1e-12, 1e-9, 1e-6])
def test_three_methods_give_the_rank_at_the_stated_tolerance(tmp_path, tilt):
    path = tmp_path / "tilted.urdf"
    path.write_text(tilted_joint_urdf(tilt))
    count, ratios = reference_count(tilt, TOLERANCE)
    # the reference decides clearly: no singular value within a factor 5 of the tolerance
    assert all(r > 5 * TOLERANCE or r < TOLERANCE / 5 for r in ratios), ratios
    assert count == (1 if tilt < 1e-10 else 3)  # the closed form's 1 + 2 [gravity resolved]
    for method in ("projection", "recursive", "numerical"):
        bp = mindyn.base_parameters(path, method=method, snap=False, tolerance=TOLERANCE)
        assert bp.n == count, (method, tilt, bp.names, ratios)
        margin = bp.margin
        assert margin["tolerance"] == TOLERANCE
        if 0 < tilt < 1e-8:
            # within the band of the neighbouring tolerances: flagged, with the parameters the
            # decision affects (the first moments the tilt sets apart)
            assert margin["near_degenerate"], (method, margin)
            assert {"MX1", "MY1"} <= set(margin["decided_by_tolerance"]), (method, margin)
            assert margin["rank_at_tighter_tolerance"] == 3
        if tilt == 0.0:
            assert not margin["near_degenerate"], (method, margin)
            assert margin["decided_by_tolerance"] == []


@pytest.mark.parametrize("tilt", [1e-12, 1e-9])
def test_the_default_snap_rounds_a_tilt_within_the_tolerance(tmp_path, tilt):
    """snap="auto" takes an axis component within the rank tolerance of zero for a rounding
    and removes it (reported): the three methods then agree on the untilted count."""
    path = tmp_path / "tilted.urdf"
    path.write_text(tilted_joint_urdf(tilt))
    untilted, _ = reference_count(0.0, TOLERANCE)
    for method in ("projection", "recursive", "numerical"):
        bp = mindyn.base_parameters(path, method=method)
        assert bp.snap_decision["applied"], bp.snap_decision
        assert bp.n == untilted
