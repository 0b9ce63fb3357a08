"""Base parameters do not depend on the robot's size: gravity against the motions.

A parameter that only gravity reveals (a prismatic joint's rotor inertia beside its link's mass
on an axis a little off horizontal; a first moment about an axis a little off vertical) is a
base parameter however long the robot is. The exact methods form their coordinates on the robot
scaled to unit length: with gravity divided by the length there, a robot of 1e5 m weighed the
potential energy by g / L against the kinetic energy, and the projection method regrouped such a
rotor inertia (23 base parameters) where the recursive one, which measures directions, kept it
(24); the numerical method, sampling rates of 1 rad/s, dropped such first moments (21). The
counts are checked against closed forms and against the rank of the stacked regressor computed
independently here in 60-digit decimal arithmetic from the URDF's numbers."""

from __future__ import annotations

import importlib.util
import random
import xml.etree.ElementTree as ET
from decimal import Decimal, localcontext
from pathlib import Path

import mindyn
import numpy as np
import pytest

METHODS = ("projection", "recursive", "numerical")
TREE = Path(__file__).parent / "data" / "odd_tree_1e5m.urdf"

_spec = importlib.util.spec_from_file_location(
    "base_consistency", Path(__file__).parents[1] / "fuzz" / "base_consistency.py"
)
odd = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(odd)


def one_joint(kind: str, axis: str, size: float) -> str:
    """One joint on the base, its origin and link of ``size`` metres."""
    s = size
    c = " ".join(repr(v * s) for v in (0.1, 0.02, 0.03))
    i = {k: repr(v * s * s) for k, v in zip(("xx", "yy", "zz"), (0.02, 0.03, 0.04))}
    travel = f'lower="{-s!r}" upper="{s!r}"' if kind == "prismatic" else 'lower="-3" upper="3"'
    return f"""<robot name="one"><link name="base"/>
  <link name="l1"><inertial><origin xyz="{c}" rpy="0 0 0"/><mass value="1.3"/>
    <inertia ixx="{i["xx"]}" ixy="{0.001 * s * s!r}" ixz="{0.002 * s * s!r}" iyy="{i["yy"]}"
      iyz="{0.003 * s * s!r}" izz="{i["zz"]}"/></inertial></link>
  <joint name="j1" type="{kind}"><parent link="base"/><child link="l1"/>
    <origin xyz="{0.3 * s!r} 0 {0.1 * s!r}" rpy="0 0 0"/><axis xyz="{axis}"/>
    <limit {travel} effort="10" velocity="1"/></joint></robot>"""


# Closed forms, with u the unit axis and g = (0, 0, -9.81):
# - prismatic on the base, rotor inertia: tau = M (q'' + |g| u_z) + Ia q''; M and Ia are two
#   base parameters when u_z != 0, one (M + Ia) when the axis is horizontal;
# - revolute on the base: tau = I_u q'' + |g| sin(tilt) (a MX' + b MY')(q), the inertia about
#   the axis and, when the axis is not vertical, the two first moments normal to it: 3, else 1.
CLOSED_FORM = {
    ("prismatic", "1 0 4e-06"): 2,
    ("prismatic", "1 0 0"): 1,
    ("revolute", "0 4e-06 1"): 3,
    ("revolute", "0 0 1"): 1,
}


@pytest.mark.parametrize("size", [1e-6, 1.0, 1e5, 1e8])
@pytest.mark.parametrize("kind, axis", list(CLOSED_FORM))
def test_a_parameter_only_gravity_reveals_is_kept_at_any_size(tmp_path, kind, axis, size):
    """At 1e5 m the projection method regrouped the tilted prismatic joint's rotor inertia into
    its mass, and the numerical method dropped the tilted revolute joint's first moments."""
    path = tmp_path / "one.urdf"
    path.write_text(one_joint(kind, axis, size))
    robot = mindyn.load(path)
    rotor = kind == "prismatic"
    for method in METHODS:
        bp = mindyn.base_parameters(robot, method=method, rotor=rotor, snap=False)
        assert bp.n == CLOSED_FORM[kind, axis], (method, size, bp.names)
        err = odd.consistency_error(robot, bp, np.random.default_rng(2))
        assert err <= 1e-12, (method, size, err)


def test_the_base_set_of_a_shape_is_that_of_its_copies_at_other_sizes(tmp_path):
    """The tree of 1e5 m scaled to 1 m (by 2^-17: exact) has the same base set by every
    method: the decisions see its shape, not its size (the projection method gave 23 base
    parameters at 1e5 m and 24 at 1 m, the numerical one 21 and 24)."""
    text = TREE.read_text()
    small = tmp_path / "small.urdf"
    root = ET.fromstring(text)
    for e in root.iter("origin"):
        e.set("xyz", " ".join(repr(float(v) * 2.0**-17) for v in e.get("xyz").split()))
    for e in root.iter("inertia"):
        for k, v in e.attrib.items():
            e.set(k, repr(float(v) * 2.0**-34))
    for j in root.iter("joint"):
        if j.get("type") == "prismatic":
            for k in ("lower", "upper"):
                j.find("limit").set(k, repr(float(j.find("limit").get(k)) * 2.0**-17))
    small.write_text(ET.tostring(root, encoding="unicode"))
    for method in METHODS:
        big = mindyn.base_parameters(TREE, method=method, rotor=True, snap=False)
        scaled = mindyn.base_parameters(small, method=method, rotor=True, snap=False)
        assert big.pivots == scaled.pivots, method
        if method != "numerical":  # (its Y carries sampling noise of 1e-17: names may differ)
            assert big.names == scaled.names, method


# ---------------------------------------------------------------------------------------------
# The rank of the stacked regressor in 60-digit decimal arithmetic, from the URDF's numbers
# ---------------------------------------------------------------------------------------------
DIGITS = 60


def _sin_cos(x: Decimal) -> tuple[Decimal, Decimal]:
    """Taylor series (|x| <= 4 here: the terms fall below 1e-70 after 70 of them)."""
    s, c, term, k = Decimal(0), Decimal(0), Decimal(1), 0
    while k < 120:
        if k % 4 == 0:
            c += term
        elif k % 4 == 1:
            s += term
        elif k % 4 == 2:
            c -= term
        else:
            s -= term
        k += 1
        term = term * x / k
    return s, c


def _mat(rows):
    return [list(r) for r in rows]


def _mul(A, B):
    return [[sum(A[i][k] * B[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def _mv(A, v):
    return [sum(A[i][k] * v[k] for k in range(3)) for i in range(3)]


def _tr(A):
    return [[A[j][i] for j in range(3)] for i in range(3)]


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _add(*vs):
    return [sum(v[i] for v in vs) for i in range(3)]


def _scale(a, v):
    return [a * x for x in v]


def _rpy(r, p, y):
    (sr, cr), (sp, cp), (sy, cy) = _sin_cos(r), _sin_cos(p), _sin_cos(y)
    one, zero = Decimal(1), Decimal(0)
    Rx = _mat([[one, zero, zero], [zero, cr, -sr], [zero, sr, cr]])
    Ry = _mat([[cp, zero, sp], [zero, one, zero], [-sp, zero, cp]])
    Rz = _mat([[cy, -sy, zero], [sy, cy, zero], [zero, zero, one]])
    return _mul(Rz, _mul(Ry, Rx))


def _about(u, q):
    s, c = _sin_cos(q)
    x, y, z = u
    d = 1 - c
    return [
        [c + x * x * d, x * y * d - z * s, x * z * d + y * s],
        [y * x * d + z * s, c + y * y * d, y * z * d - x * s],
        [z * x * d - y * s, z * y * d + x * s, c + z * z * d],
    ]


def _joints(path: Path) -> list[dict]:
    """The URDF's joints with their numbers as written, read without mindyn."""
    out = []
    for j in ET.parse(path).getroot().findall("joint"):
        o, a = j.find("origin"), j.find("axis")
        axis = [Decimal(v) for v in (a.get("xyz") if a is not None else "1 0 0").split()]
        norm = sum(v * v for v in axis).sqrt()
        out.append(
            {
                "name": j.get("name"),
                "type": j.get("type"),
                "parent": j.find("parent").get("link"),
                "child": j.find("child").get("link"),
                "R": _rpy(*(Decimal(v) for v in o.get("rpy").split())),
                "p": [Decimal(v) for v in o.get("xyz").split()],
                "axis": [v / norm for v in axis],
            }
        )
    return out


def exact_regressor(joints: list[dict], q, dq, ddq, g: Decimal) -> list[list[Decimal]]:
    """Joint torques of the moving joints, one row each, as linear in each moving link's ten
    parameters (inertia about the link frame's origin in its axes XX XY XZ YY YZ ZZ, first
    moment, mass; fixed joints merged) and a rotor inertia per joint (Ia q''): Newton-Euler in
    the world frame, gravity as the base accelerating upwards."""
    moving = [j for j in joints if j["type"] != "fixed"]
    index = {j["name"]: k for k, j in enumerate(moving)}
    n, zero = len(moving), [Decimal(0)] * 3
    frames = {}  # link: R, p, w, dw, a (of its origin), moving joint that carries it
    roots = {j["parent"] for j in joints} - {j["child"] for j in joints}
    for r in roots:
        frames[r] = (_mat(np.eye(3, dtype=int).tolist()), zero, zero, zero, [0, 0, g], -1)
    axis_w, origin_w = [None] * n, [None] * n
    pending = list(joints)
    while pending:
        later = []
        for j in pending:
            if j["parent"] not in frames:
                later.append(j)
                continue
            R0, p0, w0, dw0, a0, b = frames[j["parent"]]
            r = _mv(R0, j["p"])
            R, p = _mul(R0, j["R"]), _add(p0, r)
            a = _add(a0, _cross(dw0, r), _cross(w0, _cross(w0, r)))
            w, dw = w0, dw0
            if j["type"] != "fixed":
                k = index[j["name"]]
                u = _mv(R, j["axis"])
                axis_w[k], origin_w[k] = u, p
                if j["type"] in ("revolute", "continuous"):
                    R = _mul(R, _about(j["axis"], q[k]))
                    w = _add(w0, _scale(dq[k], u))
                    dw = _add(dw0, _scale(ddq[k], u), _cross(w0, _scale(dq[k], u)))
                else:
                    s = _scale(q[k], u)
                    p = _add(p, s)
                    a = _add(
                        a,
                        _cross(dw0, s),
                        _cross(w0, _cross(w0, s)),
                        _scale(ddq[k], u),
                        _scale(2 * dq[k], _cross(w0, u)),
                    )
                b = k
            frames[j["child"]] = (R, p, w, dw, a, b)
        pending = later
    parent = [frames[j["parent"]][5] for j in moving]
    W = [[Decimal(0)] * (11 * n) for _ in range(n)]
    for k, j in enumerate(moving):
        R, p, w, dw, a, _ = frames[j["child"]]
        for c in range(10):
            e = [Decimal(int(i == c)) for i in range(10)]
            J = [[e[0], e[1], e[2]], [e[1], e[3], e[4]], [e[2], e[4], e[5]]]
            h, m = _mv(R, e[6:9]), e[9]
            Iw = _mul(R, _mul(J, _tr(R)))
            f = _add(_scale(m, a), _cross(dw, h), _cross(w, _cross(w, h)))
            torque = _add(_mv(Iw, dw), _cross(w, _mv(Iw, w)), _cross(h, a))
            i = k
            while i >= 0:
                u = axis_w[i]
                if moving[i]["type"] == "prismatic":
                    W[i][11 * k + c] += sum(x * y for x, y in zip(u, f))
                else:
                    arm = _add(p, _scale(-1, origin_w[i]))
                    tot = _add(torque, _cross(arm, f))
                    W[i][11 * k + c] += sum(x * y for x, y in zip(u, tot))
                i = parent[i]
        W[k][11 * k + 10] = ddq[k]
    return W


def exact_rank(
    path: Path, rotor: bool, states: int = 14, seed: int = 3, friction: bool = False
) -> tuple[int, list]:
    """The rank of the regressor stacked over random states, by Gaussian elimination with
    complete pivoting on the columns scaled to unit norm (exactly zero columns left out), and
    the pivots: those of the rank stand out from the 60-digit round-off (below 1e-45).
    `friction`: with viscous and Coulomb friction columns per joint (dq_k and sign(dq_k) on
    joint k's torque)."""
    rng = random.Random(seed)
    with localcontext() as ctx:
        ctx.prec = DIGITS
        joints = _joints(path)
        n = sum(j["type"] != "fixed" for j in joints)
        rows = []
        for _ in range(states):
            q, dq, ddq = ([Decimal(rng.uniform(-2, 2)) for _ in range(n)] for _ in range(3))
            W = exact_regressor(joints, q, dq, ddq, Decimal("9.81"))
            for k, row in enumerate(W):
                for i in range(n if friction else 0):
                    on = Decimal(int(i == k))  # joint i's friction acts on joint i's torque
                    row += [on * dq[i], on * (1 if dq[i] > 0 else -1)]
            rows += W
        cols = [c for c in range(11 * n) if rotor or c % 11 != 10]
        cols += list(range(11 * n, len(rows[0])))
        A = []
        for c in cols:
            norm = sum(r[c] * r[c] for r in rows).sqrt()
            if norm > Decimal("1e-40"):
                A.append([r[c] / norm for r in rows])
        A = [list(r) for r in zip(*A)]  # rows x kept columns
        pivots = []
        for _ in range(min(len(A), len(A[0]) if A else 0)):
            size, i, j = max((abs(v), i, j) for i, r in enumerate(A) for j, v in enumerate(r))
            pivots.append(size)
            if size == 0:
                break
            pr = A.pop(i)
            for r in A:
                f = r[j] / pr[j]
                for c in range(len(r)):
                    r[c] -= f * pr[c]
            for r in A:
                r.pop(j)
        rank = sum(p > Decimal("1e-30") for p in pivots)
        return rank, pivots


@pytest.mark.parametrize("rotor", [False, True])
def test_the_counts_on_the_tree_of_1e5m_equal_the_exact_rank(rotor):
    """The geometry of the report: a tree of 1e5 m, axes 1e-12 .. 2e-7 off coordinate axes,
    right angles written rounded; the three methods give the rank of the regressor at 60
    digits (24 with rotor inertia, 19 without; the projection method gave 23 with it)."""
    rank, pivots = exact_rank(TREE, rotor)
    assert pivots[rank - 1] > Decimal("1e-20") and pivots[rank] < Decimal("1e-45"), pivots
    robot = mindyn.load(TREE)
    for method in METHODS:
        bp = mindyn.base_parameters(robot, method=method, rotor=rotor, snap=False)
        assert bp.n == rank, (method, bp.names)
        assert odd.consistency_error(robot, bp, np.random.default_rng(4)) <= 1e-12, method


def test_the_exact_regressor_is_mindyns(tmp_path):
    """The 60-digit regressor above is the classical one (mindyn's, in double) at one state:
    the check of the check."""
    joints = _joints(TREE)
    robot = mindyn.load(TREE)
    rng = np.random.default_rng(6)
    q, dq, ddq = rng.uniform(-2, 2, (3, robot.n))
    moving = [j["name"] for j in joints if j["type"] != "fixed"]
    at = [moving.index(name) for name in robot.joint_names]  # mindyn's joint k is at[k] here
    with localcontext() as ctx:
        ctx.prec = DIGITS
        mine = [[Decimal(0)] * robot.n for _ in range(3)]
        for k in range(robot.n):
            mine[0][at[k]], mine[1][at[k]], mine[2][at[k]] = (Decimal(x[k]) for x in (q, dq, ddq))
        W = np.array(exact_regressor(joints, *mine, Decimal("9.81")), dtype=float)
    ours = robot.regressor(q, dq, ddq, rotor=True)
    cols = [11 * at[k] + c for k in range(robot.n) for c in range(11)]
    expected = W[np.ix_(at, cols)]
    # to the round-off of the largest terms (lever arms of 1e5 m: M entries of 1e10)
    assert np.max(np.abs(ours - expected)) < 1e-14 * np.max(np.abs(expected))
    assert np.max(np.abs(expected)) > 1e9


@pytest.mark.parametrize("kind", ["smooth", "stribeck"])
def test_friction_with_a_velocity_scale_stays_its_own_at_any_size(tmp_path, kind):
    """Friction has a velocity scale of its own (w = 100 rad/s here): the numerical method
    samples it at the rates as given, where tanh(v / w) and exp(-(v / w)^2) differ from v / w
    and 1 by 1e-4, not at the rates of the unit-length model of a robot of 1e8 m (1e-4 rad/s),
    where they would differ by 1e-12 and regroup with the viscous and Coulomb columns. Every
    friction parameter is a base parameter of its own (a closed form: the link columns are
    polynomials in the rates), by every method."""
    path = tmp_path / "one.urdf"
    for size in (1.0, 1e8):
        path.write_text(one_joint("revolute", "0 4e-06 1", size))
        robot = mindyn.load(path).with_friction_model(kind, velocity=[100.0])
        columns = 3 if kind == "stribeck" else 2
        for method in METHODS:
            bp = mindyn.base_parameters(robot, method=method, friction=True, snap=False)
            assert bp.n == 3 + columns, (method, size, bp.names)
