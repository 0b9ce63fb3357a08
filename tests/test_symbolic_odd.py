"""Symbolic regrouping formulas on a general DH twist and on lengths of 1e6 m.

A DH twist of 45 degrees turns link 1's frame about x: the inertia about the joint axis is
c^2 ZZ + 2 c s YZ + s^2 YY, whose pivot YZ1 carries 2 c s, so the row of YZR1 is a polynomial
divided by C_alpha1 S_alpha1; it is written so, in C_alpha1 and S_alpha1 as documented, and checked
here against the numeric Y at other lengths and twists and against the inverse dynamics. An MDH
table of 1e6 m gives symbolic formulas that agree with the numeric ones entry by entry (the check
compared them against the largest coefficient, 1e12 there, and let a missing mass pass)."""

from __future__ import annotations

import math

import mindyn
import numpy as np
import pytest
from mindyn import formulas as F


def dh45(path, a1=0.3, d1=0.2, a2=0.4, alpha_deg=45.0):
    path.write_text(
        "name: dh45\nconvention: dh\nangle_unit: deg\njoints:\n"
        f"  - {{name: j1, a: {a1}, alpha: {alpha_deg}, d: {d1}, theta: 0, inertial: {{mass: 2, "
        "com: [0.1, 0.02, 0.03], inertia: {xx: 0.02, yy: 0.03, zz: 0.04, xy: 0.001}}}\n"
        f"  - {{name: j2, a: {a2}, alpha: 0, d: 0, theta: 0, inertial: {{mass: 1.5, "
        "com: [0.1, 0.01, 0.02], inertia: {xx: 0.02, yy: 0.03, zz: 0.04, yz: 0.002}}}\n"
    )
    return mindyn.load(path)


def test_45_degree_dh_twist_gives_cos_sin_formulas(tmp_path):
    bp = mindyn.base_parameters(dh45(tmp_path / "r.yaml"))
    sym = bp.symbolic()
    assert {"C_alpha1", "S_alpha1"} <= set(sym.symbols)
    assert any("C_alpha1" in t for t in sym.text)
    assert any(")/(" in t for t in sym.text)  # the row divided by its pivot's coefficient
    rng = np.random.default_rng(7)
    # at other lengths and twists: the formulas against the numeric Y of that robot, and the
    # base regressor times the formulas' values against the classical inverse dynamics
    for _ in range(3):
        a1, d1, a2 = rng.uniform(0.2, 1.2, 3)
        alpha = float(rng.uniform(20, 70))
        other = dh45(tmp_path / "o.yaml", a1, d1, a2, alpha)
        ob = mindyn.base_parameters(other)
        assert ob.names == bp.names
        c, s = math.cos(math.radians(alpha)), math.sin(math.radians(alpha))
        Y = sym.evaluate([a1, d1, a2, c, s])
        np.testing.assert_allclose(Y, ob.Y, rtol=1e-10, atol=1e-10)
        q, dq, ddq = rng.uniform(-2, 2, (3, other.n))
        tau = other.inverse_dynamics(q, dq, ddq)
        np.testing.assert_allclose(ob.regressor(q, dq, ddq) @ (Y @ other.params), tau, rtol=1e-10)


def test_45_degree_twist_formula_by_hand(tmp_path):
    """YZR1 of the one-link part: the inertia about z0 over its YZ1 coefficient 2 c s."""
    bp = mindyn.base_parameters(dh45(tmp_path / "r.yaml"))
    sym = bp.symbolic()
    row = bp.names.index("YZR1")
    Y = sym.evaluate(list(sym.symbols.values()))
    names = bp.classical_names
    c = s = math.sqrt(0.5)
    # J = s^2 YY1 + 2 c s YZ1 + c^2 ZZ1 (plus what link 2 adds): YZR1 = J / (2 c s)
    assert Y[row, names.index("YZ1")] == pytest.approx(1.0)
    assert Y[row, names.index("YY1")] == pytest.approx(s * s / (2 * c * s))
    assert Y[row, names.index("ZZ1")] == pytest.approx(c * c / (2 * c * s))


def mdh_1e6(path):
    path.write_text(
        "name: big\nconvention: mdh\nangle_unit: deg\njoints:\n"
        "  - {alpha: 0, d: 0, theta: 0, r: 300000.0, inertial: {mass: 2, com: [0, 0, 100000.0]}}\n"
        "  - {alpha: 90, d: 100000.0, theta: 0, r: 0, inertial: {mass: 1, com: [200000.0, 0, 0]}}\n"
        "  - {alpha: 0, d: 400000.0, theta: 0, r: 0, inertial: {mass: 0.5, com: [1.0e5, 0, 0]}}\n"
        "  - {alpha: 0, d: 1000000.0, theta: 0, r: 0, inertial: {mass: 0.5, com: [1.0e5, 0, 0]}}\n"
    )
    return mindyn.load(path)


@pytest.mark.parametrize("method", ["projection", "numerical"])
def test_mdh_of_1e6_m_numeric_and_symbolic_agree_or_refuse(tmp_path, method):
    robot = mdh_1e6(tmp_path / "big.yaml")
    bp = mindyn.base_parameters(robot, method=method)
    try:
        sym = bp.symbolic()
    except mindyn.Error as e:  # refused, with its reason in one line
        assert "\n" not in str(e) and "symbolic formulas" in str(e)
        return
    Y = sym.evaluate(list(sym.symbols.values()))
    # entry by entry: a coefficient of 1 is not lost next to one of 1e12
    assert np.array_equal(Y != 0, np.asarray(bp.Y) != 0), "different parameters in the formulas"
    np.testing.assert_allclose(Y, bp.Y, rtol=1e-9, atol=1e-9)


def test_symbolic_check_is_entry_by_entry(monkeypatch, tmp_path):
    """A formula missing a unit coefficient (YY2 in ZZR1) of a row that also holds coefficients
    of 1e12 is refused: the formulas' values are spoiled on that one entry, at the description's
    lengths (the random check geometries, of about 1 m, would catch it anyway)."""
    robot = mdh_1e6(tmp_path / "big.yaml")
    bp = mindyn.base_parameters(robot, method="numerical")
    orig = F.SymbolicFormulas.evaluate

    def spoiled(self, values):
        Y = orig(self, values)
        if np.max(np.abs(values)) > 1e3:  # at the description's lengths only
            Y[self.names.index("ZZR1"), self.classical_names.index("YY2")] = 0.0
        return Y

    monkeypatch.setattr(F.SymbolicFormulas, "evaluate", spoiled)
    with pytest.raises(mindyn.ModelError, match="not polynomials"):
        bp.symbolic()


@pytest.mark.parametrize("length", [4e2, 4e5])
def test_small_twist_far_from_one_metre_prints_what_y_holds_or_refuses(tmp_path, length):
    """A twist of 0.001 deg makes coefficients of sin^2 = 3.05e-10 that multiply squared lengths:
    rounded to an absolute step (3.046e-10), they moved the printed formula by 6e-5 of its largest
    coefficient at lengths of 4e5 m. Printed, each formula equals its row of the numeric Y at
    the description's lengths to 1e-9 of the row's largest coefficient, or the symbolic formulas
    are refused with the reason."""
    path = tmp_path / "twist.yaml"
    inertial = "inertial: {mass: 3, com: [0.3, 0.2, -0.1], inertia: {xx: 2, yy: 3, zz: 4}}"
    path.write_text(
        "name: twist\nconvention: mdh\nangle_unit: deg\njoints:\n"
        f"  - {{name: j1, alpha: 0, d: 0, r: 0, theta: 0, {inertial}}}\n"
        f"  - {{name: j2, alpha: 89.99, d: {length}, r: 0, theta: 0, {inertial}}}\n"
        f"  - {{name: j3, alpha: 0.001, d: 0, r: {0.85 * length}, theta: 0, {inertial}}}\n"
        f"  - {{name: j4, alpha: 0, d: {0.8 * length}, r: 0, theta: 0, {inertial}}}\n"
    )
    bp = mindyn.base_parameters(mindyn.load(path))
    Y = np.asarray(bp.Y)
    try:
        sym = bp.symbolic()
    except mindyn.ModelError as e:
        assert "at the lengths of 'twist'" in str(e) and "fitted at lengths of about 1 m" in str(e)
        return
    # the printed text read back: every coefficient as the reader sees it
    Ys = sym.evaluate([float(v) for v in sym.symbols.values()])
    row = np.maximum(np.abs(Y), np.abs(Ys)).max(axis=1, keepdims=True)
    assert np.max(np.abs(Ys - Y) / row) <= 1e-9
