"""Readable and symbolic regrouping formulas (mindyn.formulas).

References: the rounding rules on numbers whose exact decimal is known; products of the
description's decimal lengths computed exactly with fractions; closed forms derived by hand from
the parallel-axis theorem (planar arms, ZCR07S rows); and, for the symbolic formulas, the numeric
regrouping matrix of robots that this test builds itself at random lengths (by editing the
description files), against the printed formula text evaluated at those lengths.
"""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET
from fractions import Fraction
from pathlib import Path

import mindyn
import numpy as np
import pytest
import yaml
from conftest import ROBOTS_DIR, assert_close
from mindyn import cli
from mindyn import formulas as F

ROBOTS = Path(mindyn.__file__).parent / "robots"
EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "urdf"


# --------------------------------------------------------------------------------------------
# Numbers
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "x, scale, expected",
    [
        (0.18645124000000002, 1.0, 0.18645124),  # 0.4318**2
        (1.0000000000000002, 1.0, 1.0),
        (-0.9999999999999999, 1.0, -1.0),
        (0.1 + 0.2, 1.0, 0.3),
        (0.0004120899999999992, 1.0, 0.00041209),  # 0.0203**2 after cancellation
        (0.02029999999999999, 1.0, 0.0203),
        (0.16434832749999997, 1.0, 0.1643483275),
        (2.5e-07 * (1 + 2e-16), 1.0, 2.5e-07),
        (0.0, 1.0, 0.0),
    ],
)
def test_round_coefficient_removes_round_off(x, scale, expected):
    assert F.round_coefficient(x, scale=scale) == expected


@pytest.mark.parametrize("x", [0.1234567890123, 1 / 3, -2.718281828459045, 1.5e-8, 123456.789])
def test_round_coefficient_keeps_real_digits(x):
    """A value with more digits than the round-off is kept to within 1e-13 of itself: 1/3 keeps
    13 or more significant digits, and a value already short is returned unchanged."""
    r = F.round_coefficient(x, scale=1.0)
    assert abs(r - x) <= 1e-13 * abs(x) + 1e-15
    if len(repr(x)) <= 14:
        assert r == x


def test_shortest_decimal_text():
    assert F.shortest_decimal(1.2000000000000002e-05, 1e-18) == "1.2e-5"
    assert F.shortest_decimal(3e6 + 1e-9, 1e-6) == "3e6"
    assert F.shortest_decimal(-0.5, 0.0) == "-0.5"


def _row_formula(row, names=("A", "B", "C", "D", "E")) -> str:
    return str(F.numeric_formulas(np.array([row], dtype=float), ["X"], list(names))[0])


def test_gathering_rules():
    eps = 2.0**-52
    # equal coefficients within round-off gathered, +-1 written as signs and not gathered
    assert _row_formula([1, 0.5 * (1 + eps), 0.5, -1, 0.25]) == "X = A + 0.5*(B + C) - D + 0.25*E"
    assert _row_formula([1, 1, 1, 0, 0]) == "X = A + B + C"
    assert _row_formula([-0.3, -0.3 * (1 - eps), 0, 0, 0]) == "X = -0.3*(A + B)"
    # coefficients that differ beyond round-off stay apart; opposite signs stay apart
    assert _row_formula([1, 0.5, 0.5 + 1e-9, 0, 0]) == "X = A + 0.5*B + 0.500000001*C"
    assert _row_formula([1, 0.5, -0.5, 0, 0]) == "X = A + 0.5*B - 0.5*C"
    # a round-off zero (1e-17 against a formula of size 1) is left out; an empty formula is 0
    assert _row_formula([1, 1e-17, 0, 0, 0]) == "X = A"
    assert _row_formula([0, 0, 0, 0, 0]) == "X = 0"


def test_gathered_members_keep_their_order():
    row = [0.2, 1, 0.2 * (1 + 2**-50), -1, 0.2]
    assert _row_formula(row) == "X = 0.2*(A + C + E) + B - D"


# --------------------------------------------------------------------------------------------
# Reading printed formulas back (numeric and symbolic text alike)
# --------------------------------------------------------------------------------------------
def formula_rows(text: list[str], classical: list[str], symbols: dict[str, float]) -> np.ndarray:
    """The rows of Y that the printed formulas ``NAME = expression`` say, evaluated with every
    classical parameter a unit vector and every symbol its value."""
    P = len(classical)
    env: dict[str, object] = {name: np.eye(P)[i] for i, name in enumerate(classical)}
    env.update(symbols)
    rows = []
    for line in text:
        rhs = line.split(" = ", 1)[-1]
        value = eval(rhs.replace("^", "**"), {"__builtins__": {}}, env)  # noqa: S307 - own text
        rows.append(np.broadcast_to(np.asarray(value, dtype=float), (P,)))
    return np.array(rows)


def test_puma560_numeric_formulas():
    """No round-off digits, equal coefficients gathered, and the printed text still says Y."""
    bp = mindyn.base_parameters("puma560", rotor=True)
    f = dict(zip(bp.names, bp.formulas))
    a2 = Fraction("0.4318")  # DH a2 of the description, squared exactly
    assert f["XXR2"] == f"XXR2 = XX2 - YY2 + {float(a2**2)!r}*(M2 + M3 + M4 + M5 + M6)"
    assert f["MXR2"] == "MXR2 = MX2 + 0.4318*(M2 + M3 + M4 + M5 + M6)"
    for line in bp.formulas:
        for number in re.findall(r"\d+\.\d+(?:e-?\d+)?", line):
            digits = number.split("e")[0].replace(".", "").lstrip("0")
            assert len(digits) <= 10, f"{number} in {line}"
        assert "e-1" not in line  # no 1e-17 remainders
    Y = formula_rows(bp.formulas, bp.classical_names, {})
    assert np.max(np.abs(Y - bp.Y)) <= 1e-15
    assert bp.formulas_full[1].count("0.18645124000000002") == 5


def test_sets_and_json_carry_readable_and_full_formulas():
    bp = mindyn.base_parameters("puma560")
    out = bp.to_dict()
    assert out["formulas"] == bp.formulas and out["formulas_full"] == bp.formulas_full
    for s in bp.sets.values():
        assert len(s["formulas"]) == len(s["formulas_full"]) == s["n"]
        Y = formula_rows(s["formulas"], bp.classical_names, {})
        assert np.max(np.abs(Y - s["Y"])) <= 1e-15
    assert "formulas_symbolic" not in out


# --------------------------------------------------------------------------------------------
# Symbolic formulas against robots built at random lengths
# --------------------------------------------------------------------------------------------
def yaml_at(name: str, values: dict[str, float], path: Path) -> Path:
    """The bundled description ``name`` with the lengths named in ``values`` replaced (``d3``:
    joint 3's ``d``; ``a2``: joint 2's ``a``; ``r4``: joint 4's ``r``)."""
    doc = yaml.safe_load((ROBOTS / f"{name}.yaml").read_text())
    for sym, v in values.items():
        key, j = sym[0], int(sym[1:])
        assert doc["joints"][j - 1].get(key, 0) != 0, f"{sym} is zero in {name}"
        doc["joints"][j - 1][key] = float(v)
    path.write_text(yaml.safe_dump(doc))
    return path


def urdf_at(source: Path, robot: mindyn.Robot, values: dict[str, float], path: Path) -> Path:
    """The URDF ``source`` with joint ``j``'s origin component ``x_j``/``y_j``/``z_j`` replaced
    (joints numbered along the moving chain)."""
    tree = ET.parse(source)
    joints = {j.get("name"): j for j in tree.getroot().findall("joint")}  # not a transmission's
    for sym, v in values.items():
        axis, j = "xyz".index(sym[0]), int(sym[1:])
        origin = joints[robot.joint_names[j - 1]].find("origin")
        xyz = [float(t) for t in origin.get("xyz").split()]
        assert xyz[axis] != 0
        xyz[axis] = float(v)
        origin.set("xyz", " ".join(repr(t) for t in xyz))
    tree.write(path)
    return path


def check_symbolic(bp, build, rng, geometries: int = 3, **options):
    """Every printed symbolic formula, evaluated at random lengths, equals the numeric Y of the
    robot built at those lengths (1e-10: the fit is exact up to round-off of order 1e-15 on
    coefficients of order 1; a wrong monomial would miss by the size of a length product)."""
    sym = bp.symbolic()
    assert sym.checked >= 4 and sym.largest_difference <= 1e-12
    names = list(sym.symbols)
    for _ in range(geometries):
        values = dict(
            zip(names, rng.choice([-1, 1], len(names)) * rng.uniform(0.05, 2, len(names)))
        )
        other = mindyn.base_parameters(
            build(values), rotor=bp.rotor, friction=bp.friction, **options
        )
        assert other.names == bp.names
        got = formula_rows(sym.text, other.classical_names, values)
        assert_close(got, other.Y, 1e-10, "symbolic formulas vs Y at random lengths")
        assert np.max(np.abs(got - other.Y)) <= 1e-10
    # and at the description's own lengths, against the numeric formulas
    assert np.max(np.abs(formula_rows(sym.text, bp.classical_names, sym.symbols) - bp.Y)) <= 1e-12
    return sym


@pytest.mark.parametrize(
    "name, rotor, friction, symbols",
    [
        ("zcr07s", True, True, ["d2", "d3", "d4", "r4"]),
        ("puma560", True, False, ["d1", "a2", "a3", "d3", "d4"]),
        ("puma560_3", False, False, None),
        ("stanford", True, True, None),
    ],
)
def test_symbolic_bundled_at_random_lengths(name, rotor, friction, symbols, tmp_path, rng):
    bp = mindyn.base_parameters(name, rotor=rotor, friction=friction)
    sym = check_symbolic(bp, lambda v: yaml_at(name, v, tmp_path / "r.yaml"), rng)
    if symbols is not None:
        assert list(sym.symbols) == symbols
    assert len(sym.formulas) == bp.n


def test_symbolic_urdf_at_random_origins(tmp_path, rng):
    """URDF: the symbols are the joint origins' components; UR5 (its rpy = 1.570796327 rounded
    to right angles with snap)."""
    source = EXAMPLES / "ur5.urdf"
    robot = mindyn.load(source)
    bp = mindyn.base_parameters(robot, rotor=True, snap=True)
    sym = check_symbolic(
        bp, lambda v: urdf_at(source, robot, v, tmp_path / "r.urdf"), rng, snap=True
    )
    assert list(sym.symbols) == ["z2", "x3", "x4", "z5", "z6"]
    assert sym.symbols["x3"] == -0.425
    f = dict(zip(bp.names, sym.text))
    # joint 3 sits x3 along the upper arm, joints 2 and 3 parallel: parallel-axis terms in x3
    assert f["MXR2"] == "MXR2 = MX2 + x3*(M3 + M4 + M5 + M6)"
    assert f["ZZR2"] == "ZZR2 = ZZ2 + Ia2 + x3^2*(M3 + M4 + M5 + M6)"


SKEWED = """name: skewed3
convention: mdh
angle_unit: deg
joints:
  - {type: revolute, alpha: 0, d: 0, r: 0}
  - {type: revolute, alpha: 90, d: 0.1, r: 0}
  - {type: revolute, alpha: %r, d: %r, r: %r}
"""


def test_symbolic_general_twist(tmp_path, rng):
    """A twist of 30 degrees brings C_alpha3, S_alpha3. Khalil's relations for link 3 carried
    into frame 2 through Rx(alpha3) and the translation (d3, -r3 S, r3 C) give, e.g.,
    MYR2 = MY2 - S MZ3 - r3 S M3, XZR2 = XZ2 - d3 C MZ3 - d3 r3 C M3; every formula is checked
    against robots built at random lengths and twists."""
    path = tmp_path / "skewed.yaml"
    path.write_text(SKEWED % (30.0, 0.4, 0.2))
    bp = mindyn.base_parameters(path)
    sym = bp.symbolic()
    assert list(sym.symbols) == ["d2", "d3", "r3", "C_alpha3", "S_alpha3"]
    f = dict(zip(bp.names, sym.text))
    assert f["MYR2"] == "MYR2 = MY2 - S_alpha3*MZ3 - r3*S_alpha3*M3"
    assert f["XZR2"] == "XZR2 = XZ2 - d3*C_alpha3*MZ3 - d3*r3*C_alpha3*M3"
    assert f["MXR2"] == "MXR2 = MX2 + d3*M3"
    assert r"\cos^{2}\alpha_{3}" in bp.latex(symbolic=True)
    for _ in range(3):
        alpha = rng.uniform(-3, 3)
        d3, r3 = rng.uniform(0.1, 1.5, 2)
        path.write_text(SKEWED % (float(np.degrees(alpha)), float(d3), float(r3)))
        values = {
            "d2": 0.1,
            "d3": d3,
            "r3": r3,
            "C_alpha3": np.cos(alpha),
            "S_alpha3": np.sin(alpha),
        }
        other = mindyn.base_parameters(path)
        assert other.names == bp.names
        got = formula_rows(sym.text, other.classical_names, values)
        assert_close(got, other.Y, 1e-10, "symbolic formulas vs Y at random lengths")
        assert np.max(np.abs(got - other.Y)) <= 1e-10


def test_symbolic_twist_stays_numeric_beyond_the_monomial_budget(tmp_path, monkeypatch):
    """Past MAX_MONOMIALS the twist's cosine and sine are numbers: MYR2 = MY2 - sin(30 deg) MZ3
    - r3 sin(30 deg) M3, with sin(30 deg) = 1/2 exactly as a fraction."""
    path = tmp_path / "skewed.yaml"
    path.write_text(SKEWED % (30.0, 0.4, 0.2))
    monkeypatch.setattr(F, "MAX_MONOMIALS", 20)
    bp = mindyn.base_parameters(path)
    sym = bp.symbolic()
    assert list(sym.symbols) == ["d2", "d3", "r3"]
    f = dict(zip(bp.names, sym.text))
    assert f["MYR2"] == "MYR2 = MY2 - 1/2*MZ3 - 1/2*r3*M3"
    assert sym.largest_difference <= 1e-12


def test_symbolic_with_offsets_and_json():
    bp = mindyn.base_parameters("planar2", offset=True)
    out = bp.to_dict(symbolic=True)
    assert out["formulas_symbolic"][-2:] == ["Off1 = Off1", "Off2 = Off2"]
    assert out["symbols"] == {"d2": 0.5}
    assert out["symbolic_check"]["largest_difference"] <= 1e-12
    json.dumps(out)


# --------------------------------------------------------------------------------------------
# Hand-derived closed forms
# --------------------------------------------------------------------------------------------
def test_planar_closed_forms():
    """Vertical planar arm, MDH, joint j + 1 at distance d_{j+1} along x_j, all axes parallel.
    Link j's kinetic energy is ½ ZZ_j (q̇_1 + ... + q̇_j)² + (first-moment terms) + ½ M_j |v_Oj|²,
    with |v_O2| = d2 q̇1: the mass of every link beyond joint 2 adds d2² to the coefficient of
    ½ q̇1², so ZZR1 = ZZ1 + d2² (M2 + M3); and in the potential the masses beyond joint 2 sit at
    d2 (cos q1, sin q1) + ..., so MXR1 = MX1 + d2 (M2 + M3). ZZ2 is not added to ZZ1: it
    multiplies (q̇1 + q̇2)², a different function, and stays a base parameter of its own. Link 2
    carries link 3 the same way with d3."""
    sym = mindyn.base_parameters("planar2").symbolic()
    assert sym.text == [
        "ZZR1 = ZZ1 + d2^2*M2",
        "MXR1 = MX1 + d2*M2",
        "MY1 = MY1",
        "ZZ2 = ZZ2",
        "MX2 = MX2",
        "MY2 = MY2",
    ]
    assert mindyn.base_parameters("planar2").formulas[:2] == [
        "ZZR1 = ZZ1 + 0.25*M2",  # d2 = 0.5 m
        "MXR1 = MX1 + 0.5*M2",
    ]
    f = dict(
        zip(
            mindyn.base_parameters("planar3").names,
            mindyn.base_parameters("planar3").symbolic().text,
        )
    )
    assert f["ZZR1"] == "ZZR1 = ZZ1 + d2^2*(M2 + M3)"
    assert f["MXR1"] == "MXR1 = MX1 + d2*(M2 + M3)"
    assert f["ZZR2"] == "ZZR2 = ZZ2 + d3^2*M3"
    assert f["MXR2"] == "MXR2 = MX2 + d3*M3"


# ZCR07S rows, derived by hand from the MDH table (alpha = 0, 90, 0, 90, 90, -90 degrees; d2, d3,
# d4, r4 the non-zero lengths). Moving link j's YY, MZ, M into frame j - 1 through the translation
# (d_j, -r_j sin alpha_j, r_j cos alpha_j) and the twist alpha_j about x:
#   joint 4 (alpha = 90, translation (d4, -r4, 0)): z4 = -y3, so MZ4 and the carried mass
#     M4..6 at y = -r4 give MY3 - MZ4 - r4 (M4 + M5 + M6); x offset d4 gives MX3 + d4 (M4..6);
#     the inertia about z3 gains YY4 (z3 lies in link 4's x-y plane), 2 r4 MZ4 (the cross term
#     of the parallel-axis theorem) and (d4² + r4²)(M4..6) (squared distance from the z3 axis);
#     about x3 only r4 is off-axis: YY4 + 2 r4 MZ4 + r4² M, and about y3 only d4: d4² M;
#     XXR3 = XX3 - YY3(carried) therefore has r4² - d4²; the product of inertia -∫xy gains
#     d4 MZ4 + d4 r4 M;
#   joint 3 (alpha = 0, translation (d3, 0, 0)): axes parallel, z3 = z2: ZZ2 += d3² (M3..6),
#     MX2 += d3 (M3..6), YY2 += YY3 + d3² M, XX2 += YY3, so XXR2 = XX2 - YY2 - d3² (M3..6);
#     XZ2 gains -d3 MZ3 (the cross term with the first moment along z);
#   joint 2 (alpha = 90, translation (d2, 0, 0)) and joint 1 vertical: link 1 turns about z1
#     only, so only ZZ1 remains, gaining what links 2.. carry about z1: YY2, YY3 (z1 lies in
#     their x-y planes) and each mass times its squared distance from z1 (d2, then d2 and d3,
#     then d2, d3 and d4 at right angles); the rotor Ia1 turns with q1 alone and joins ZZ1, Ia2
#     joins ZZ2 (link 2 turns about z2 with q2 alone, z1 being at right angles to z2);
#   joints 4, 5, 6 (alpha = 90): XXR_j = XX_j - YY_j + YY_{j+1}, ZZR_j = ZZ_j + YY_{j+1};
#   joints 5, 6 (alpha = +90, -90, no lengths): MY4 - sin(90) MZ5, MY5 - sin(-90) MZ6.
ZCR07S_BY_HAND = {
    "ZZR1": "ZZ1 + Ia1 + YY2 + d2^2*M2 + YY3 + (d2^2 + d3^2)*M3"
    " + (d2^2 + d3^2 + d4^2)*(M4 + M5 + M6)",
    "XXR4": "XX4 - YY4 + YY5",
    "ZZR4": "ZZ4 + YY5",
    "XXR5": "XX5 - YY5 + YY6",
    "MYR3": "MY3 - MZ4 - r4*(M4 + M5 + M6)",
    "MXR3": "MX3 + d4*(M4 + M5 + M6)",
    "ZZR3": "ZZ3 + YY4 + 2*r4*MZ4 + (d4^2 + r4^2)*(M4 + M5 + M6)",
    "XXR3": "XX3 - YY3 + YY4 + 2*r4*MZ4 + (r4^2 - d4^2)*(M4 + M5 + M6)",
    "XYR3": "XY3 + d4*MZ4 + d4*r4*(M4 + M5 + M6)",
    "ZZR2": "ZZ2 + Ia2 + d3^2*(M3 + M4 + M5 + M6)",
    "MXR2": "MX2 + d3*(M3 + M4 + M5 + M6)",
    "XXR2": "XX2 - YY2 - d3^2*(M3 + M4 + M5 + M6)",
    "XZR2": "XZ2 - d3*MZ3",
    "MYR4": "MY4 - MZ5",
    "MYR5": "MY5 + MZ6",
    "XXR6": "XX6 - YY6",
    "ZZR5": "ZZ5 + YY6",
}


def test_zcr07s_symbolic_rows_by_hand():
    bp = mindyn.base_parameters("zcr07s", rotor=True, friction=True)
    f = dict(zip(bp.names, bp.symbolic().text))
    for name, rhs in ZCR07S_BY_HAND.items():
        assert f[name] == f"{name} = {rhs}"
    # the study's XZ3..XZ5 are not regrouped (cos of the next twist is 0)
    assert all(f[f"XZ{j}"] == f"XZ{j} = XZ{j}" for j in (3, 4, 5))


def test_zcr07s_rows_by_hand_reproduce_the_torques(rng):
    """The hand-derived rows, evaluated at the table's lengths, give the torques of random
    classical parameters through the regressor columns of the kept parameters (independent of
    the projection: only the regressor W, tau = W pi)."""
    robot = mindyn.load("zcr07s")
    names = robot.parameter_names(rotor=True, friction=True)
    lengths = {"d2": 0.025, "d3": 0.455, "d4": 0.035, "r4": 0.420}
    kept = mindyn.base_parameters(robot, rotor=True, friction=True).names
    hand = dict(zip(ZCR07S_BY_HAND, formula_rows(list(ZCR07S_BY_HAND.values()), names, lengths)))
    # every other base parameter is a classical parameter alone
    Y = np.array([hand[n] if n in hand else np.eye(len(names))[names.index(n)] for n in kept])
    pivots = [names.index(re.sub(r"R(?=\d+$)", "", n)) for n in kept]
    for _ in range(3):
        q, dq, ddq = rng.uniform(-2, 2, (3, robot.n))
        pi = rng.uniform(-1, 1, len(names))
        W = robot.regressor(q, dq, ddq, rotor=True, friction=True)
        assert_close(W[:, pivots] @ (Y @ pi), W @ pi, 1e-12, "ZCR07S rows by hand vs W pi")


# --------------------------------------------------------------------------------------------
# Refusals
# --------------------------------------------------------------------------------------------
def test_symbolic_refuses_a_rational_coefficient():
    """With M2 offered before MX1 the planar arm keeps M2 and writes MX1 through it: the
    coefficient of MX1 is 1/d2, no polynomial; the check refuses it instead of printing a
    wrong formula."""
    robot = mindyn.load("planar2")
    order = ["M2"] + [p for p in robot.parameter_names() if p != "M2"]
    bp = mindyn.base_parameters(robot, order=order)
    assert bp.names[0].startswith("M")
    with pytest.raises(mindyn.ModelError, match="not polynomials of degree <= 2"):
        bp.symbolic()


def test_symbolic_budgets(monkeypatch):
    """Too many length monomials or too long an estimated run: refused, with the numbers."""
    bp = mindyn.base_parameters("zcr07s")
    monkeypatch.setattr(F, "MAX_MONOMIALS", 14)  # 4 lengths: 15 monomials of degree <= 2
    with pytest.raises(mindyn.ModelError, match="4 non-zero lengths, 15 monomials"):
        bp.symbolic()
    monkeypatch.setattr(F, "MAX_MONOMIALS", 600)
    monkeypatch.setattr(F, "MAX_SECONDS", 0.0)
    with pytest.raises(mindyn.ModelError, match=r"would take about .* the limit is 0 s"):
        mindyn.base_parameters("zcr07s").symbolic()


def test_symbolic_without_lengths(tmp_path):
    """Three intersecting axes (all lengths zero): no symbols, the formulas are numbers."""
    path = tmp_path / "wrist.yaml"
    path.write_text(SKEWED.replace("%r, d: %r, r: %r", "90, d: 0, r: 0").replace("0.1", "0"))
    bp = mindyn.base_parameters(path)
    sym = bp.symbolic()
    assert sym.symbols == {}
    assert sym.text == bp.formulas


def test_symbolic_refuses_a_changing_base_set(monkeypatch):
    """A robot whose base set differs at the sampled lengths (simulated: the geometry builder
    returns the arm turned horizontal, whose mass never changes height) is refused."""
    bp = mindyn.base_parameters("planar2")
    monkeypatch.setattr(F._Geometry, "build", lambda self, *a: mindyn.load("planar2h"))
    with pytest.raises(mindyn.ModelError, match="changes when its lengths vary"):
        bp.symbolic()


# --------------------------------------------------------------------------------------------
# Command line
# --------------------------------------------------------------------------------------------
class Run:
    def __init__(self, status: int, out: str, err: str):
        self.returncode, self.stdout, self.stderr = status, out, err


@pytest.fixture
def run_cli(capsys):
    """The command line in this process (its output captured)."""

    def run(*args) -> Run:
        status = cli.main([str(a) for a in args])
        out = capsys.readouterr()
        return Run(status, out.out, out.err)

    return run


def test_cli_symbolic_table_json_latex(run_cli):
    r = run_cli("base", "zcr07s", "--rotor", "--friction", "--symbolic")
    assert r.returncode == 0, r.stderr
    assert "MYR3  = MY3 - MZ4 - r4*(M4 + M5 + M6)" in r.stdout
    assert "ZZR2  = ZZ2 + Ia2 + d3^2*(M3 + M4 + M5 + M6)" in r.stdout
    assert "symbols        d2 = 0.025, d3 = 0.455, d4 = 0.035, r4 = 0.42 (lengths in m)" in r.stdout
    r = run_cli("base", "zcr07s", "--rotor", "--friction", "--symbolic", "--format", "json")
    out = json.loads(r.stdout)
    assert len(out["formulas_symbolic"]) == out["n_base"] == 52
    assert "MYR3 = MY3 - MZ4 - r4*(M4 + M5 + M6)" in out["formulas_symbolic"]
    r = run_cli("base", "zcr07s", "--rotor", "--friction", "--symbolic", "--format", "latex")
    assert (
        r"\mathrm{MYR}_{3} &= \mathrm{MY}_{3} - \mathrm{MZ}_{4} - r_{4}\,\left(\mathrm{M}_{4} + "
        r"\mathrm{M}_{5} + \mathrm{M}_{6}\right)" in r.stdout
    )
    assert r"d_{3}^{2}" in r.stdout


def test_cli_numeric_latex_and_table_are_rounded(run_cli):
    r = run_cli("base", "puma560", "--format", "latex")
    assert r.returncode == 0, r.stderr
    assert r"0.18645124\,\left(\mathrm{M}_{2} + \mathrm{M}_{3}" in r.stdout
    r = run_cli("base", "puma560")
    assert "XXR2  = XX2 - YY2 + 0.18645124*(M2 + M3 + M4 + M5 + M6)" in r.stdout
    assert "0000000" not in r.stdout and "9999999" not in r.stdout


def test_cli_symbolic_refusal_is_one_line(run_cli):
    r = run_cli(
        "base",
        "planar2",
        "--order",
        "M2," + ",".join(p for p in mindyn.load("planar2").parameter_names() if p != "M2"),
        "--symbolic",
    )
    assert r.returncode == 2
    assert r.stderr.startswith("mindyn: error: symbolic formulas:") and r.stderr.count("\n") == 1


def test_symbolic_names_rounded_right_angles_and_works_once_snapped():
    """Baxter's arm writes its right angles rounded (1.57079632679): the fit misses, and the
    refusal says to snap; snapped, the symbolic formulas pass their checks against Y."""
    path = ROBOTS_DIR / "baxter_description/urdf/baxter.urdf"
    robot = mindyn.load(path, tip="left_gripper")
    with pytest.raises(mindyn.ModelError, match=r"not polynomials.*rounded.*snap") as info:
        mindyn.base_parameters(robot).symbolic()
    assert "\n" not in str(info.value)
    sym = mindyn.base_parameters(robot, snap=True).symbolic()
    assert sym.checked == 4 and len(sym.formulas) == mindyn.base_parameters(robot).n
    # planar2's refusal (test above) has nothing to snap, and says nothing of it
    order = ["M2"] + [p for p in mindyn.load("planar2").parameter_names() if p != "M2"]
    with pytest.raises(mindyn.ModelError) as plain:
        mindyn.base_parameters("planar2", order=order).symbolic()
    assert "snap" not in str(plain.value)


GEARED_URDF = """<robot name="geared3">
  <link name="base"/>
  <link name="l1"><inertial><origin xyz="0.02 0.01 0.1"/><mass value="8"/>
    <inertia ixx="0.2" iyy="0.25" izz="0.15" ixy="0.01" ixz="0" iyz="0"/></inertial></link>
  <link name="l2"><inertial><origin xyz="0.2 0.01 0.03"/><mass value="5"/>
    <inertia ixx="0.02" iyy="0.1" izz="0.11" ixy="0" ixz="0.005" iyz="0"/></inertial></link>
  <link name="l3"><inertial><origin xyz="0.15 0 -0.02"/><mass value="2"/>
    <inertia ixx="0.01" iyy="0.04" izz="0.045" ixy="0" ixz="0" iyz="0.002"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.3"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="100" velocity="2"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.1 0 0.25" rpy="1.5707963267948966 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="100" velocity="2"/></joint>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>
    <origin xyz="0.4 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="100" velocity="2"/></joint>
  <transmission name="t1"><type>transmission_interface/SimpleTransmission</type>
    <joint name="j1"/><actuator name="m1"><mechanicalReduction>100</mechanicalReduction></actuator>
  </transmission>
  <transmission name="t23"><type>transmission_interface/DifferentialTransmission</type>
    <actuator name="m2"><role>actuator1</role>
      <mechanicalReduction>50</mechanicalReduction></actuator>
    <actuator name="m3"><role>actuator2</role>
      <mechanicalReduction>50</mechanicalReduction></actuator>
    <joint name="j2"><role>joint1</role><mechanicalReduction>1</mechanicalReduction></joint>
    <joint name="j3"><role>joint2</role><mechanicalReduction>1</mechanicalReduction></joint>
  </transmission>
</robot>
"""


@pytest.mark.parametrize("convention", ["urdf", "mdh"])
def test_symbolic_with_transmissions_on_the_motors(convention, tmp_path, rng):
    """Rotor inertia and friction of motors behind transmissions (a gear of 100 on joint 1, a
    differential of 50 on joints 2 and 3): the regrouping coefficients hold the rows of T, so
    the formulas at other lengths must be those of the robot with its transmissions. Reference:
    the numeric Y of descriptions this test writes at random lengths (transmissions kept), and
    joint 1's motor by hand: its rotor turns 100 times as fast, Ia1 counts 100^2 in ZZR1."""
    if convention == "urdf":
        source = tmp_path / "geared.urdf"
        source.write_text(GEARED_URDF)
        robot = mindyn.load(source)

        def build(v):
            return urdf_at(source, robot, v, tmp_path / "r.urdf")

    else:
        # the URDF's geometry and links as an MDH table (link frames at the joint frames)
        links = [  # alpha, d, r, mass, com, (xx, yy, zz)
            (0, 0, 0.3, 8, [0.02, 0.01, 0.1], (0.2, 0.25, 0.15)),
            (90, 0.1, 0, 5, [0.2, 0.01, 0.03], (0.02, 0.1, 0.11)),
            (0, 0.4, 0, 2, [0.15, 0, -0.02], (0.01, 0.04, 0.045)),
        ]
        joints = [
            {"name": f"j{k + 1}", "type": "revolute", "alpha": a, "d": d, "theta": 0, "r": r,
             "inertial": {"mass": m, "com": c, "inertia": dict(zip(("xx", "yy", "zz"), i))}}
            for k, (a, d, r, m, c, i) in enumerate(links)
        ]  # fmt: skip
        transmissions = [
            {"name": "m1", "joints": {"j1": 100}},
            {"name": "m2", "joints": {"j2": 50, "j3": 50}},
            {"name": "m3", "joints": {"j2": 50, "j3": -50}},
        ]
        doc = {"name": "geared3", "convention": "mdh", "angle_unit": "deg", "joints": joints}
        doc["transmissions"] = transmissions
        source = tmp_path / "geared.yaml"
        source.write_text(yaml.safe_dump(doc))
        robot = mindyn.load(source)

        def build(v):
            other = json.loads(json.dumps(doc))
            for sym, x in v.items():
                other["joints"][int(sym[1:]) - 1][sym[0]] = float(x)
            path = tmp_path / "r.yaml"
            path.write_text(yaml.safe_dump(other))
            return path

    assert robot.drive_side == "motor"
    bp = mindyn.base_parameters(robot, rotor=True, friction=True)
    sym = check_symbolic(bp, build, rng)
    zz1 = next(t for t in sym.text if t.startswith("ZZR1 ="))
    assert re.search(r"(?<![\d.])10000\*Ia1\b", zz1), zz1
