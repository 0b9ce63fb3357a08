"""Regrouping formulas written for reading, with numbers or with the description's own symbols.

Numeric formulas (:func:`numeric_formulas`)
    A row of the regrouping matrix ``Y`` is a double-precision vector: ``0.4318**2`` comes out as
    ``0.18645124000000002`` and five equal coefficients as five slightly different doubles. Each
    coefficient is printed as the shortest decimal within a tolerance of it, ``1e-13`` of its own
    size plus ``1e-15`` of the largest coefficient of its formula (the round-off of the
    projection is a few units in the last place of the numbers it combines, and the description's
    lengths, given with a few decimals, make coefficients with at most twice as many). Exact zeros
    are left out and ``+-1`` is written as a plain sign. Terms whose coefficients agree within that
    tolerance are gathered: ``0.18645124*(M2 + M3 + M4 + M5 + M6)``.

Symbolic formulas (:func:`symbolic_formulas`)
    The coefficients of ``Y`` as polynomials in the robot's lengths: for a DH table ``a_j, d_j``,
    for an MDH table ``d_j, r_j`` (the column names of the table), for a URDF ``x_j, y_j, z_j``, the
    translation of joint ``j``'s origin in the frame of the link before it (fixed joints merged).
    Twists of 0 and +-90 degrees keep their exact sines and cosines 0 and +-1, so the coefficients
    are polynomials in the lengths with small integer coefficients; any other twist ``alpha_j`` of
    a DH/MDH table brings two more symbols, ``C_alphaj`` and ``S_alphaj`` (its cosine and sine;
    ``C^2`` or ``1 - S^2``, whichever is shorter), unless lengths and twists together would need
    more than ``MAX_MONOMIALS`` monomials: then those sines and cosines stay numbers in the
    coefficients. A twist that turns a link frame scales that link's pivot coefficients (the
    inertia about a DH joint axis is ``C^2 ZZ + 2 C S YZ + S^2 YY``): such a row is a polynomial
    divided by one of ``C, S, C S, C^2, S^2`` of its twist, found by fitting each candidate's
    multiple of the row, and written ``(...)/(C_alphaj*S_alphaj)``.
    URDF rotations and the fixed ``theta`` of prismatic joints stay numbers. A length
    that is zero in the description is a structural zero, not a symbol (a non-zero value there
    describes another robot, whose base set can differ: zero offsets are what let parameters
    regroup across parallel or intersecting axes), and the offset of a prismatic joint's variable
    is no symbol either (shifting a joint variable changes no relation between the parameters).

    Degree bound. Moving link ``j``'s parameters to the frame of link ``j - 1`` (the
    parallel-axis theorem, which is what each regrouping relation does) keeps the mass, adds the
    mass times the translation to the first moment, and adds to the inertia the translation times
    the first moment and the translation squared times the mass. The translation is linear in the
    lengths and the rotation free of them. Carried from the last link inwards, the coefficient of a
    mass in a base parameter is therefore at most quadratic in the lengths, that of a first moment
    at most linear, that of an inertia, rotor inertia or friction constant; with every length scaled
    by ``s`` a coefficient scales by ``s**(w_b - w_p)`` with weights 2 for inertias, 1 for first
    moments, 0 for masses (the Lagrangian keeps its form when lengths and first moments scale by
    ``s`` and inertias by ``s**2``). So each coefficient is a polynomial of degree at most 2 in
    the lengths. The rotation across joint ``j`` and the translation are linear in
    ``cos alpha_j, sin alpha_j`` and each joint is crossed once, so the degree in those two is at
    most 2 per joint: with ``sin^2 = 1 - cos^2``, the five functions ``1, C, S, C^2, C S``.

    Recovery. The numeric ``Y`` is computed for robots with the same angles and random lengths
    (uniform in +-[0.4, 1.6] m: generic, so the base set must be the one of the description, which
    is checked), and random general angles for the symbolic twists, at more points than there
    are monomials, the monomial coefficients are solved for by least squares, rounded to fractions
    with denominators up to 1000 when within ``1e-12`` (otherwise to the shortest decimal within
    ``1e-13``), and every formula, as printed, is checked against the numeric ``Y`` at the
    description's geometry and at three further random geometries. The bound above assumes that
    the kept parameters take what is carried from link to link; a column order or a geometry for
    which a coefficient is not such a polynomial fails that check and is refused with a
    ModelError rather than printed wrong. So is a description with more than ``MAX_MONOMIALS``
    monomials in its lengths alone, or one whose computation, estimated from the first varied
    geometry, would take longer than ``MAX_SECONDS``.

ZCR07S: our formulas against the study's Table 1
    With ``rotor=True, friction=True`` the 52 symbolic formulas give the study's relations in its
    own symbols, for example ``MYR3 = MY3 - MZ4 - r4*(M4 + M5 + M6)``,
    ``ZZR2 = ZZ2 + Ia2 + d3^2*(M3 + M4 + M5 + M6)``, ``MXR2 = MX2 + d3*(M3 + M4 + M5 + M6)``,
    ``XXR2 = XX2 - YY2 - d3^2*(M3 + M4 + M5 + M6)``. The study's print differs in these places,
    where its own MDH table (Table 2) decides for our version:

    - the elbow offset ``d4 = 35 mm`` is missing from the study's relations. It belongs in
      ``XXR3 = XX3 - YY3 + YY4 + 2*r4*MZ4 + (r4^2 - d4^2)*(M4 + M5 + M6)``,
      ``ZZR3 = ZZ3 + YY4 + 2*r4*MZ4 + (r4^2 + d4^2)*(M4 + M5 + M6)``, and it regroups two
      parameters that the study keeps alone: ``MXR3 = MX3 + d4*(M4 + M5 + M6)`` and
      ``XYR3 = XY3 + d4*MZ4 + d4*r4*(M4 + M5 + M6)``; ``ZZR1`` gets ``d4^2*(M4 + M5 + M6)`` too;
    - the wrist first moments have the opposite signs: ``alpha5 = +90`` and ``alpha6 = -90``
      degrees give ``MYR4 = MY4 - MZ5`` and ``MYR5 = MY5 + MZ6``;
    - ``ZZ3`` enters ``ZZR3`` with ``+1`` (the study's print reads ``- Izz3``);
    - ``XZ3``, ``XZ4``, ``XZ5`` are not regrouped (the study marks them with ``r``): the relation
      that would feed them is proportional to ``cos(alpha_j)``, zero for ``alpha_4..6 = +-90``;
    - ``XZR2 = XZ2 - d3*MZ3``: with ``r3 = 0`` no mass term remains.
"""

from __future__ import annotations

import bisect
import itertools
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Union

import numpy as np

from . import _args, _core
from .robot import Robot

__all__ = [
    "Formula",
    "SymbolicFormulas",
    "latex",
    "numeric_formulas",
    "round_coefficient",
    "shortest_decimal",
    "symbolic_formulas",
    "unit_formula",
]

#: Numeric formulas: tolerance of a coefficient, relative to itself ...
RELATIVE = 1e-13
#: ... plus this much of the largest coefficient of its formula.
ABSOLUTE = 1e-15

Number = Union[Fraction, float]
# A polynomial: ((exponents, coefficient), ...), exponents one per symbol; the numeric formulas
# use no symbols, so their coefficients are constant polynomials ((), value).
Poly = tuple[tuple[tuple[int, ...], Number], ...]


# -- numbers ------------------------------------------------------------------------------------
def shortest_decimal(x: float, tol: float) -> str:
    """The shortest decimal (1 to 17 significant digits) within ``tol`` of ``x``, as text."""
    x = _args.number(x, "x")
    tol = _args.number(tol, "tol", minimum=0.0)
    x = float(x)
    if x == 0.0 or not math.isfinite(x):
        return "0" if x == 0.0 else repr(x)
    for digits in range(1, 18):
        s = f"{x:.{digits}g}"
        if abs(float(s) - x) <= tol:
            return _tidy(s)
    return _tidy(repr(x))


def _tidy(s: str) -> str:
    """``1.2e-05`` -> ``1.2e-5``, ``3e+06`` -> ``3e6``."""
    if "e" not in s:
        return s
    mant, exp = s.split("e")
    return f"{mant}e{int(exp)}"


def round_coefficient(x: float, *, scale: float = 0.0) -> float:
    """``x`` without its round-off: the shortest decimal within ``RELATIVE * |x| + ABSOLUTE *
    scale`` (``scale``: the largest coefficient of the formula), e.g. ``0.18645124000000002`` ->
    ``0.18645124``, ``1.0000000000000002`` -> ``1``."""
    x = _args.number(x, "x")
    scale = _args.number(scale, "scale", minimum=0.0)
    return float(shortest_decimal(x, RELATIVE * abs(x) + ABSOLUTE * abs(scale)))


# -- formulas -------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Term:
    """``coef * (params[0] + params[1] + ...)``: classical parameters sharing one coefficient."""

    coef: Poly
    params: tuple[str, ...]


@dataclass(frozen=True)
class Formula:
    """One base parameter: ``name = sum of terms``; ``symbols`` names the polynomial variables."""

    name: str
    terms: tuple[Term, ...]
    symbols: tuple[str, ...] = ()
    #: a polynomial every term is divided by (a twist's sines and cosines), or None
    denominator: Poly | None = None

    def __str__(self) -> str:
        return self.text()

    def text(self) -> str:
        """``XXR2 = XX2 - YY2 + 0.18645124*(M2 + M3)``; powers as ``d3^2``; with a denominator
        ``YZR1 = (2*C_alpha1*S_alpha1*YZ1 + S_alpha1^2*YY1)/(2*C_alpha1*S_alpha1)``."""
        body = _join([_term_text(t, self.symbols) for t in self.terms])
        if self.denominator is not None:
            neg, den, _ = _poly_body(self.denominator, self.symbols, latex=False)
            body = f"{'-' if neg else ''}({body})/({den})"
        return self.name + " = " + body

    def latex(self) -> str:
        """One ``align`` row: ``\\mathrm{XXR}_{2} &= ...``."""
        body = _join([_term_latex(t, self.symbols) for t in self.terms])
        if self.denominator is not None:
            neg, den, _ = _poly_body(self.denominator, self.symbols, latex=True)
            body = f"{'-' if neg else ''}\\frac{{{body}}}{{{den}}}"
        return f"{_latex_name(self.name)} &= {body}"


def _join(parts: list[tuple[bool, str]]) -> str:
    """Signed parts as a sum: ``a - b + c``; an empty sum is ``0``."""
    if not parts:
        return "0"
    out = ""
    for i, (neg, body) in enumerate(parts):
        if i == 0:
            out = ("-" if neg else "") + body
        else:
            out += (" - " if neg else " + ") + body
    return out


def _is_unit(poly: Poly) -> bool:
    return len(poly) == 1 and not any(poly[0][0]) and abs(poly[0][1]) == 1


def _negative(poly: Poly) -> bool:
    """Written with a minus in front: every coefficient negative."""
    return all(c < 0 for _, c in poly)


def _num_text(c: Number) -> str:
    """A fraction as ``n/d`` (``n`` when whole); a float, already rounded, as its shortest
    round-tripping text (``0.18645124``, ``2`` for 2.0)."""
    if isinstance(c, Fraction):
        return str(c.numerator) if c.denominator == 1 else f"{c.numerator}/{c.denominator}"
    c = float(c)
    if c.is_integer() and abs(c) < 1e15:
        return str(int(c))
    return _tidy(repr(c))


def _monomials(poly: Poly, symbols: Sequence[str], latex: bool) -> list[tuple[bool, str]]:
    """Positive monomials first, then by degree (highest first), then by symbol order."""

    def key(item: tuple[tuple[int, ...], Number]):
        e, c = item
        return (c < 0, -sum(e), [-x for x in e])

    out = []
    for e, c in sorted(poly, key=key):
        vars_ = []
        for s, k in zip(symbols, e):
            if k:
                if latex:
                    vars_.append(_latex_symbol(s, k))
                else:
                    vars_.append(s if k == 1 else f"{s}^{k}")
        a = abs(c) if isinstance(c, Fraction) else abs(float(c))
        num = _num_latex(a) if latex else _num_text(a)
        sep = r"\," if latex else "*"
        if vars_:
            body = (" " if latex else "*").join(vars_)
            body = body if a == 1 else f"{num}{sep}{body}"
        else:
            body = num
        out.append((c < 0, body))
    return out


def _poly_body(poly: Poly, symbols, latex: bool) -> tuple[bool, str, bool]:
    """(written negative, text without that sign, needs parentheses as a factor)."""
    neg = _negative(poly)
    if neg:
        poly = tuple((e, -c) for e, c in poly)
    mons = _monomials(poly, symbols, latex)
    return neg, _join(mons), len(mons) > 1


def _term_text(t: Term, symbols) -> tuple[bool, str]:
    return _term(t, symbols, latex=False)


def _term_latex(t: Term, symbols) -> tuple[bool, str]:
    return _term(t, symbols, latex=True)


def _term(t: Term, symbols, latex: bool) -> tuple[bool, str]:
    name = _latex_name if latex else str
    params = [name(p) for p in t.params]
    lp, rp = (r"\left(", r"\right)") if latex else ("(", ")")
    if _is_unit(t.coef):
        return t.coef[0][1] < 0, " + ".join(params)
    neg, body, compound = _poly_body(t.coef, symbols, latex)
    if compound:
        body = f"{lp}{body}{rp}"
    group = params[0] if len(params) == 1 else f"{lp}{' + '.join(params)}{rp}"
    times = r"\," if latex else "*"
    return neg, f"{body}{times}{group}"


def _latex_name(name: str) -> str:
    """``XXR3`` -> ``\\mathrm{XXR}_{3}``."""
    head = name.rstrip("0123456789")
    tail = name[len(head) :]
    return rf"\mathrm{{{head}}}_{{{tail}}}" if head and tail else rf"\mathrm{{{name}}}"


def _latex_symbol(s: str, power: int = 1) -> str:
    """``d3`` -> ``d_{3}``, ``C_alpha3`` -> ``cos alpha_{3}`` in LaTeX, with ``power``."""
    head = s.rstrip("0123456789")
    tail = s[len(head) :]
    up = "" if power == 1 else f"^{{{power}}}"
    trig = {"C_alpha": r"\cos", "S_alpha": r"\sin"}.get(head)
    if trig:
        return rf"{trig}{up}\alpha_{{{tail}}}"
    return (f"{head}_{{{tail}}}" if tail else s) + up


def _num_latex(c: Number) -> str:
    if isinstance(c, Fraction):
        if c.denominator == 1:
            return str(c.numerator)
        return rf"\tfrac{{{c.numerator}}}{{{c.denominator}}}"
    s = _num_text(c)
    if "e" in s:
        mant, exp = s.split("e")
        return rf"{mant}\cdot 10^{{{int(exp)}}}"
    return s


def unit_formula(name: str) -> Formula:
    """``name = name`` (a parameter that is its own base parameter, e.g. a torque offset)."""
    _args.text(name, "name")
    return Formula(name=name, terms=(Term(coef=(((), 1.0),), params=(name,)),))


def latex(formulas: Sequence[Formula]) -> str:
    """The formulas as one LaTeX ``align*`` environment."""
    _args.instance(formulas, "formulas", (list, tuple), "a list of Formula")
    if not all(isinstance(f, Formula) for f in formulas):
        raise _args.fail("formulas", "must hold Formula objects")
    body = " \\\\\n".join(f.latex() for f in formulas)
    return "\\begin{align*}\n" + body + "\n\\end{align*}"


# -- numeric formulas --------------------------------------------------------------------------
def numeric_formulas(
    Y: np.ndarray, names: Sequence[str], classical_names: Sequence[str]
) -> list[Formula]:
    """Readable formulas of the rows of ``Y``: coefficients rounded (:func:`round_coefficient`),
    terms whose coefficients agree within that rounding gathered, ``+-1`` kept as signs."""
    Y = _args.array(Y, "Y", (None, None))
    _args.instance(names, "names", (list, tuple), "a list of names")
    _args.instance(classical_names, "classical_names", (list, tuple), "a list of names")
    if len(names) != Y.shape[0]:
        raise _args.fail("names", f"has {len(names)} names; Y has {Y.shape[0]} rows")
    if len(classical_names) != Y.shape[1]:
        raise _args.fail(
            "classical_names", f"has {len(classical_names)} names; Y has {Y.shape[1]} columns"
        )
    Y = np.asarray(Y, dtype=float)
    out = []
    for b, name in enumerate(names):
        row = Y[b]
        scale = float(np.max(np.abs(row))) if row.size else 0.0
        groups: list[tuple[float, float, list[str]]] = []  # (raw value, rounded, params)
        # the raw values of the groups that gather (not +-1), sorted, and their group indices:
        # a term joins the first group within twice its tolerance
        raws: list[float] = []
        where: list[int] = []
        for c in np.flatnonzero(row).tolist():
            y = float(row[c])
            tol = RELATIVE * abs(y) + ABSOLUTE * scale
            if abs(y) <= ABSOLUTE * scale:
                continue  # round-off of an exact zero
            r = round_coefficient(y, scale=scale)
            if abs(abs(r) - 1.0) == 0.0:
                groups.append((y, r, [classical_names[c]]))
                continue
            lo, hi = bisect.bisect_left(raws, y - 2 * tol), bisect.bisect_right(raws, y + 2 * tol)
            if lo < hi:
                groups[min(where[lo:hi])][2].append(classical_names[c])
            else:
                i = bisect.bisect_left(raws, y)
                raws.insert(i, y)
                where.insert(i, len(groups))
                groups.append((y, r, [classical_names[c]]))
        terms = tuple(Term(coef=(((), r),), params=tuple(ps)) for _, r, ps in groups)
        out.append(Formula(name=name, terms=terms))
    return out


# -- symbolic formulas -------------------------------------------------------------------------
class _Geometry:
    """The lengths of a robot's description that become symbols, and robots with other values."""

    def __init__(self, robot: Robot):
        self.robot = robot
        self.convention = robot.convention
        self.symbols: list[str] = []
        self.where: list[tuple[int, int]] = []
        types = robot.joint_types
        if self.convention in ("dh", "mdh"):
            self.rows = np.array(robot.dh, dtype=float)
            # (a, alpha, d, theta) slots 0 and 2; MDH stores (d_j, alpha_j, r_j, theta_j) there
            letters = ("a", "d") if self.convention == "dh" else ("d", "r")
            for k in range(robot.n):
                for slot, letter in zip((0, 2), letters):
                    if slot == 2 and types[k] == "prismatic":
                        continue  # the offset of the joint variable
                    if self.rows[k, slot] != 0.0:
                        self.symbols.append(f"{letter}{k + 1}")
                        self.where.append((k, slot))
            self.values = np.array([self.rows[k, s] for k, s in self.where])
            # twists other than multiples of 90 degrees: their cosine and sine become symbols
            self.twists = [
                k
                for k in range(robot.n)
                if min(abs(math.cos(self.rows[k, 1])), abs(math.sin(self.rows[k, 1]))) > 1e-9
            ]
        elif self.convention == "urdf":
            other = sorted({t for t in types if t not in _URDF_KIND})
            if other:
                raise _core.ModelError(
                    f"symbolic formulas: robot '{robot.name}' has {', '.join(other)} joints; "
                    f"expected {', '.join(_URDF_KIND)} joints"
                )
            self.pre = [np.array(robot.joint_pre(k)) for k in range(robot.n)]
            self.axes = np.array(robot.axes, dtype=float)
            for k in range(robot.n):
                for i, letter in enumerate("xyz"):
                    if self.pre[k][i, 3] != 0.0:
                        self.symbols.append(f"{letter}{k + 1}")
                        self.where.append((k, i))
            self.values = np.array([self.pre[k][i, 3] for k, i in self.where])
            self.twists = []
        else:
            raise _core.ModelError(
                f"symbolic formulas: robot '{robot.name}' has convention "
                f"'{self.convention}'; expected dh, mdh or urdf"
            )

    def build(self, values: np.ndarray, twists: Sequence[float] | np.ndarray = ()) -> Robot:
        """The robot with the symbol lengths ``values`` and, when given, the angles ``twists``
        (rad) for the joints in ``self.twists``."""
        robot = self.robot
        if self.convention == "urdf":
            return self._with_drive(self._build_urdf(values))
        rows = self.rows.copy()
        for (k, s), v in zip(self.where, values):
            rows[k, s] = v
        for k, a in zip(self.twists, twists):
            rows[k, 1] = a
        keys = ("a", "alpha", "d", "theta") if self.convention == "dh" else ("d", "alpha", "r")
        lines = [
            "name: geometry",
            f"convention: {self.convention}",
            "angle_unit: rad",
            "gravity: [" + ", ".join(repr(float(g)) for g in robot.gravity) + "]",
            "joints:",
        ]
        for k in range(robot.n):
            vals = list(rows[k]) if self.convention == "dh" else list(rows[k, :3])
            geo = ", ".join(f"{key}: {float(v)!r}" for key, v in zip(keys, vals))
            theta = "" if self.convention == "dh" else f", theta: {float(rows[k, 3])!r}"
            lines.append(f"  - {{type: {robot.joint_types[k]}, {geo}{theta}}}")
        return self._with_drive(
            Robot(_core.parse_yaml("\n".join(lines) + "\n", "<symbolic geometry>"))
        )

    def _with_drive(self, other: Robot) -> Robot:
        """``other`` (the geometry at other lengths) with the description's transmissions, drive
        side and friction model: with transmissions the rotor inertia and friction of a motor
        reach the joints through its row of ``T``, which the regrouping coefficients hold."""
        if self.robot.transmission is None:
            return other
        return Robot(other._m.with_drive_of(self.robot._m))

    def _build_urdf(self, values: np.ndarray) -> Robot:
        robot = self.robot
        xml = ['<robot name="geometry">', '<link name="L0"/>']
        pre = [p.copy() for p in self.pre]
        for (k, i), v in zip(self.where, values):
            pre[k][i, 3] = v
        for k in range(robot.n):
            xyz = " ".join(repr(float(v)) for v in pre[k][:3, 3])
            rpy = " ".join(repr(float(v)) for v in _rpy(pre[k][:3, :3]))
            axis = " ".join(repr(float(v)) for v in self.axes[k])
            kind = _URDF_KIND[robot.joint_types[k]]
            limit = '<limit lower="-1" upper="1" effort="1" velocity="1"/>'
            xml.append(
                f'<joint name="J{k + 1}" type="{kind}"><parent link="L{robot.parents[k] + 1}"/>'
                f'<child link="L{k + 1}"/><origin xyz="{xyz}" rpy="{rpy}"/>'
                f'<axis xyz="{axis}"/>{limit if kind == "prismatic" else ""}</joint>'
                f'<link name="L{k + 1}"/>'
            )
        xml.append("</robot>")
        core = _core.parse_urdf("\n".join(xml), "", "<symbolic geometry>")
        return Robot(core).with_gravity(robot.gravity)


#: The URDF joint type that rebuilds a joint of each kind at other lengths (a revolute joint
#: without limits, a floating or planar root as it is)
_URDF_KIND = {
    "revolute": "continuous",
    "prismatic": "prismatic",
    "floating": "floating",
    "planar": "planar",
}


def _rpy(R: np.ndarray) -> tuple[float, float, float]:
    """URDF roll, pitch, yaw of ``R = Rz(yaw) Ry(pitch) Rx(roll)``."""
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    if math.hypot(R[0, 0], R[1, 0]) < 1e-12:  # pitch = +-90 degrees: roll and yaw share an axis
        return 0.0, pitch, math.atan2(-R[0, 1], R[1, 1])
    return math.atan2(R[2, 1], R[2, 2]), pitch, math.atan2(R[1, 0], R[0, 0])


def _exponents(n: int, degree: int = 2) -> list[tuple[int, ...]]:
    """All monomials of total degree <= ``degree`` (at most 2) in ``n`` symbols."""
    out = [tuple([0] * n)]
    for i in range(n):
        e = [0] * n
        e[i] = 1
        out.append(tuple(e))
    if degree >= 2:
        for i in range(n):
            for j in range(i, n):
                e = [0] * n
                e[i] += 1
                e[j] += 1
                out.append(tuple(e))
    return out


def _design(points: np.ndarray, exps: list[tuple[int, ...]]) -> np.ndarray:
    E = np.array(exps, dtype=float)  # (monomials, symbols)
    return (
        np.prod(points[:, None, :] ** E[None, :, :], axis=2)
        if len(exps[0])
        else np.ones((len(points), 1))
    )


#: Fractions with denominators up to this are tried for the fitted monomial coefficients ...
MAX_DENOMINATOR = 1000
#: ... and taken when within this of the fitted value (relative to max(1, |value|)); fitted
#: coefficients below it are zero. The fit, over lengths of order 1, is accurate to about 1e-14.
FRACTION_TOLERANCE = 1e-12
#: More monomials than this (lengths times the cos/sin of general twists) and the twists' sines
#: and cosines stay numbers.
MAX_MONOMIALS = 600
#: Estimated time (from the first varied geometry) beyond which symbolic formulas are refused.
MAX_SECONDS = 120.0
#: A symbolic formula must reproduce the numeric ``Y`` within this (relative to max(1, |Y|)).
CHECK_TOLERANCE = 1e-10


def _value(poly: Poly, x: np.ndarray) -> float:
    return sum(float(v) * np.prod(x ** np.array(e, dtype=float)) for e, v in poly)


def _denominators(ns: int, nt: int) -> list[Poly]:
    """Candidate denominators of a row of ``Y``: the products of a twist's cosine and sine of
    degree <= 2 (a link frame turned by a general twist makes its pivot's coefficient one of
    these, and the row's coefficients ratios with it)."""
    out: list[Poly] = []
    for j in range(nt):
        for c, s in ((1, 0), (0, 1), (1, 1), (2, 0), (0, 2)):
            e = [0] * (ns + 2 * nt)
            e[ns + 2 * j], e[ns + 2 * j + 1] = c, s
            out.append(((tuple(e), Fraction(1)),))
    return out


def _rationalise(c: float, scale: float = 1.0) -> Number | None:
    """A fitted monomial coefficient as a fraction, a rounded float, or None for zero: round-off
    of the fit, at most :data:`FRACTION_TOLERANCE` of ``scale`` (the largest coefficient of its
    entry, at least 1: a motor's ``r^2`` of 2e4 leaves fitted zeros of 1e-11 beside it)."""
    tol = FRACTION_TOLERANCE * max(1.0, abs(c))
    if abs(c) <= FRACTION_TOLERANCE * max(1.0, scale):
        return None
    f = Fraction(c).limit_denominator(MAX_DENOMINATOR)
    if abs(float(f) - c) <= tol:
        return f
    # relative to the coefficient itself: a small one (sin^2 of a twist of 0.001 deg, 3e-10)
    # multiplies squared lengths that may be large, so rounding it to an absolute step would
    # move the formula at the description's lengths
    return float(shortest_decimal(c, RELATIVE * abs(c)))


@dataclass
class SymbolicFormulas:
    """Regrouping formulas of the equations-of-motion set in the description's symbols.

    Attributes
    ----------
    formulas : list of Formula
        One per base parameter (``str(f)`` writes it, ``f.latex()`` as LaTeX).
    symbols : dict
        Symbol name -> its value in the description (lengths in m; ``C_alphaj``, ``S_alphaj``
        the cosine and sine of a twist).
    polys : dict
        ``(base index, classical index) -> ((exponents, coefficient), ...)`` for every non-zero
        entry of ``Y``: a polynomial, exponents in the order of ``symbols``, coefficients
        fractions (or rounded floats where an angle stays a number).
    names, classical_names : list of str
        The base parameters (offsets excluded) and the classical parameters: the rows and
        columns of :meth:`evaluate`.
    checked : int
        Number of geometries every formula was checked at (the description's and random ones).
    largest_difference : float
        Largest difference between a formula evaluated there and the numeric ``Y``, entry by
        entry relative to the entry (or to the size lengths give it, if larger).
    """

    formulas: list[Formula]
    symbols: dict
    polys: dict
    names: list[str]
    classical_names: list[str]
    checked: int
    largest_difference: float
    #: base index -> the polynomial its row of ``polys`` is divided by (rows without: none)
    denominators: dict = None  # type: ignore[assignment]

    @property
    def text(self) -> list[str]:
        return [f.text() for f in self.formulas]

    def evaluate(self, values) -> np.ndarray:
        """``Y`` (base x classical) of the formulas at symbol values ``values`` (in the order of
        ``symbols``)."""
        x = np.asarray(values, dtype=float)
        Y = np.zeros((len(self.names), len(self.classical_names)))
        for (b, c), poly in self.polys.items():
            Y[b, c] = _value(poly, x)
        for b, den in (self.denominators or {}).items():
            Y[b] /= _value(den, x)
        return Y

    def to_dict(self) -> dict:
        return {
            "formulas_symbolic": self.text,
            "symbols": {k: float(v) for k, v in self.symbols.items()},
            "symbolic_check": {
                "geometries": self.checked,
                "largest_difference": self.largest_difference,
                "tolerance": CHECK_TOLERANCE,
            },
        }

    def latex(self) -> str:
        return latex(self.formulas)


def symbolic_formulas(bp, *, seed: int = 20240607) -> SymbolicFormulas:
    """The regrouping formulas of ``bp`` (a :class:`mindyn.BaseParameters`) in the symbols of its
    robot's description (see the module documentation for the symbols, the degree bound and the
    checks). Raises ModelError when the base set changes with the lengths or a coefficient is
    not a polynomial of degree <= 2 in them."""
    _args.protocol(bp, "bp", "regressor", "a BaseParameters")
    seed = _args.integer(seed, "seed", 0)
    robot = bp.robot
    geo = _Geometry(robot)
    # the link parameters: the torque offsets (the layout's joint block, last) are their own
    k = bp.robot.n if bp.offset else 0
    if k and np.count_nonzero(np.array(bp._b.Y)[bp.n - k :]) != k:
        regrouped = [nm for nm in list(bp._b.names)[bp.n - k :] if nm not in bp.classical_names]
        raise _core.ModelError(
            f"symbolic formulas: the torque offsets {', '.join(regrouped)} of '{robot.name}' "
            "take link parameters that act as constant torques; the link parameters' symbolic "
            "formulas are those of the base parameters without offsets"
        )
    names = list(bp._b.names)[: bp.n - k]
    classical = list(bp._b.classical_names)[: len(bp._b.classical_names) - k]
    pivots = list(bp._b.pivots)[: bp.n - k]
    Y0 = np.array(bp._b.Y)[: bp.n - k, : len(classical)]
    P = len(classical)
    order = pivots + [c for c in range(P) if c not in set(pivots)]

    ns = len(geo.symbols)
    twists = list(geo.twists)
    trig_exps = [(0, 0), (1, 0), (0, 1), (2, 0), (1, 1)]  # in (cos, sin), sin^2 = 1 - cos^2
    # times a denominator of degree 2 (see _denominators): degree 4
    trig_wide = trig_exps + [(3, 0), (2, 1), (4, 0), (3, 1)]
    if len(_exponents(ns)) > MAX_MONOMIALS:
        raise _core.ModelError(
            f"symbolic formulas: '{robot.name}' has {ns} non-zero lengths, "
            f"{len(_exponents(ns))} monomials of degree <= 2 to recover; at most "
            f"{MAX_MONOMIALS} are supported (about 33 lengths)"
        )
    if len(_exponents(ns)) * len(trig_wide) ** len(twists) <= MAX_MONOMIALS:
        trig_exps = trig_wide
    elif len(_exponents(ns)) * len(trig_exps) ** len(twists) > MAX_MONOMIALS:
        twists = []  # too many general twists: their sines and cosines stay numbers
    nt = len(twists)
    geo.twists = twists
    symbols = list(geo.symbols)
    for k in twists:
        symbols += [f"C_alpha{k + 1}", f"S_alpha{k + 1}"]
    exps = []
    for e in _exponents(ns):
        for t in itertools.product(trig_exps, repeat=nt):
            exps.append(e + tuple(x for pair in t for x in pair))
    alpha0 = np.array([geo.rows[k, 1] for k in twists]) if nt else np.zeros(0)

    def numeric(values: np.ndarray, angles: np.ndarray) -> np.ndarray:
        other = bp.for_robot(geo.build(values, angles), order=order, offset=False)
        if other.names != names or other.pivots != pivots:
            gained = [nm for nm in other.names if nm not in names]
            lost = [nm for nm in names if nm not in other.names]
            which = (
                f"; {', '.join(gained[:3])}{', ...' if len(gained) > 3 else ''} in place of "
                f"{', '.join(lost[:3])}{', ...' if len(lost) > 3 else ''}"
                if gained or lost
                else "; other pivots"
            )
            raise _core.ModelError(
                f"symbolic formulas: the base set of '{robot.name}' changes when its lengths "
                f"vary ({len(names)} base parameters with the description's lengths, "
                f"{len(other.names)} with others{which}): the description's lengths are "
                "special, and its formulas have no form valid for general lengths"
            )
        return np.array(other.Y)

    def point(values: np.ndarray, angles: np.ndarray) -> np.ndarray:
        """Symbol values: the lengths, then cos and sin of each symbolic twist."""
        trig = [f(a) for a in angles for f in (math.cos, math.sin)]
        return np.concatenate([values, trig])

    rng = np.random.default_rng(seed)

    def draw(k: int) -> list[tuple[np.ndarray, np.ndarray]]:
        lengths = rng.choice([-1.0, 1.0], size=(k, ns)) * rng.uniform(0.4, 1.6, size=(k, ns))
        # general angles: at least 0.15 rad away from every multiple of 90 degrees
        angles = rng.uniform(0.15, math.pi / 2 - 0.15, size=(k, nt))
        angles += rng.integers(0, 4, size=(k, nt)) * math.pi / 2
        return list(zip(lengths, angles))

    fit = draw(len(exps) + 8)
    start = time.perf_counter()
    samples = [numeric(*fit[0]).ravel()]
    need = (len(fit) + 3) * (time.perf_counter() - start)
    if need > MAX_SECONDS:
        raise _core.ModelError(
            f"symbolic formulas: '{robot.name}' would take about {need:.0f} s "
            f"({len(fit) + 3} base-parameter computations of {need / (len(fit) + 3):.2g} s); "
            f"the limit is {MAX_SECONDS:.0f} s"
        )
    samples = np.array(samples + [numeric(x, a).ravel() for x, a in fit[1:]])
    points = np.array([point(x, a) for x, a in fit])
    A = _design(points, exps)
    C, *_ = np.linalg.lstsq(A, samples, rcond=None)  # (monomials, base * classical)
    # A row that is no polynomial may be one divided by a twist's cos/sin (the wide basis
    # holds the products): the first candidate whose multiple of the row fits is taken.
    denominators: dict[int, Poly] = {}
    if trig_exps is trig_wide:
        pinv = np.linalg.pinv(A)
        for b in range(len(names)):
            cols = slice(b * P, (b + 1) * P)
            rows = samples[:, cols]
            if _fits(A, C[:, cols], rows):
                continue
            for den in _denominators(ns, nt):
                target = rows * _design(points, [e for e, _ in den])[:, :1]
                fitted = pinv @ target
                if _fits(A, fitted, target):
                    C[:, cols] = fitted
                    denominators[b] = den
                    break

    polys: dict[tuple[int, int], Poly] = {}
    for flat in np.flatnonzero(np.max(np.abs(C), axis=0) > FRACTION_TOLERANCE):
        b, c = divmod(int(flat), P)
        poly = []
        scale = float(np.max(np.abs(C[:, flat])))
        for m, e in enumerate(exps):
            v = _rationalise(float(C[m, flat]), scale)
            if v is not None:
                poly.append((e, v))
        for j in range(nt):
            poly = _shorter_trig(poly, ns + 2 * j)
        if poly:
            polys[(b, c)] = tuple(poly)

    result = SymbolicFormulas(
        formulas=[],
        symbols=dict(zip(symbols, (float(v) for v in point(geo.values, alpha0)))),
        polys=polys,
        names=names,
        classical_names=classical,
        checked=0,
        largest_difference=0.0,
        denominators=denominators,
    )
    worst = 0.0
    checks = [(point(geo.values, alpha0), Y0)]
    checks += [(point(x, a), numeric(x, a)) for x, a in draw(3)]
    # Entry by entry, against the size the entry has at those lengths: with lengths scaled by s,
    # Y[b, c] scales by s^(w_b - w_c) (module documentation), so a coefficient of 1 next to one
    # of 1e12 (lengths of 1e6 m) is checked to 1e-10, not to 100.
    weight = np.array([_length_weight(c, len(classical) // robot.n) for c in range(P)])
    power = weight[pivots][:, None] - weight[None, :] if pivots else np.zeros((0, P))
    for i, (x, Yn) in enumerate(checks):
        size = max(1.0, float(np.max(np.abs(x[:ns]), initial=0.0)))
        scale = np.maximum(np.abs(Yn), size**power)
        Ys = result.evaluate(x)
        diff = float(np.max(np.abs(Ys - Yn) / scale)) if Yn.size else 0.0
        limit = CHECK_TOLERANCE
        if not diff <= limit:
            raise _core.ModelError(
                f"symbolic formulas: the regrouping coefficients of '{robot.name}' are not "
                f"polynomials of degree <= 2 in its lengths {', '.join(symbols) or '(none)'} "
                f"(a fitted formula misses the numeric one by {diff:.3g} at a check geometry)"
                + (
                    "; the geometry is near-degenerate: consider snap"
                    if bp.margin.get("near_degenerate")
                    else ""
                )
                + (
                    "; its joint origins hold rotations within 1e-3 of right angles but not at "
                    "them (rounded angles such as 1.5708 for pi/2): snap them (snap=True)"
                    if _rounded_right_angles(robot)
                    else ""
                )
            )
        if i == 0 and Yn.size:
            # at the description's own lengths each formula is also checked against its row's
            # largest coefficient, as a reader compares the printed numbers: coefficients fitted
            # at lengths of about 1 m and evaluated at lengths far from it can miss there
            rows = np.maximum(np.abs(Yn), np.abs(Ys)).max(axis=1, keepdims=True)
            row_diff = float(np.max(np.abs(Ys - Yn) / np.maximum(rows, 1e-300)))
            if not row_diff <= limit:
                raise _core.ModelError(
                    f"symbolic formulas: at the lengths of '{robot.name}' (up to {size:.3g} m) "
                    f"the coefficients fitted at lengths of about 1 m miss the numeric formulas "
                    f"by {row_diff:.3g} of a formula's largest coefficient (limit {limit:g}); "
                    "the numeric formulas (without symbolic) hold at these lengths"
                )
        worst = max(worst, diff)
    result.checked = len(checks)
    result.largest_difference = worst
    result.formulas = _gather(names, classical, polys, tuple(symbols), denominators)
    result.formulas += [unit_formula(o) for o in bp.names[len(names) :]]
    return result


def _length_weight(c: int, per_link: int) -> int:
    """Power of length in classical parameter ``c``'s unit over the mass's: 2 for inertias (rotor
    inertia and friction count as inertias), 1 for first moments, 0 for the mass."""
    p = c % per_link
    return 1 if 6 <= p <= 8 else 0 if p == 9 else 2


def _rounded_right_angles(robot) -> bool:
    """True when a joint origin's rotation is within 1e-3 (entry by entry) of a rotation by
    right angles without being one: right angles written rounded, which snapping makes exact."""
    for k in range(robot.n):
        a = np.abs(np.asarray(robot.joint_pre(k))[:3, :3])
        near = (a < 1e-3) | (np.abs(a - 1.0) < 1e-3)
        if near.all() and not ((a == 0.0) | (a == 1.0)).all():
            return True
    return False


def _shorter_trig(poly: list, i: int) -> list:
    """``poly`` with ``cos^2`` (exponent slot ``i``) written as ``1 - sin^2`` (slot ``i + 1``)
    when that takes fewer monomials."""
    alt: dict[tuple[int, ...], Number] = {}
    for e, v in poly:
        if e[i] == 2:
            for e2, sign in (((*e[:i], 0, *e[i + 1 :]), 1), ((*e[:i], 0, 2, *e[i + 2 :]), -1)):
                alt[e2] = alt.get(e2, 0) + sign * v
        else:
            alt[e] = alt.get(e, 0) + v
    alt_list = [(e, v) for e, v in alt.items() if v != 0]
    return alt_list if len(alt_list) < len(poly) else poly


def _fits(A: np.ndarray, C: np.ndarray, values: np.ndarray) -> bool:
    """The fitted polynomials reproduce the sampled values (to 1e-9 of their size)."""
    return bool(
        np.max(np.abs(A @ C - values), initial=0.0) <= 1e-9 * max(1.0, np.abs(values).max())
    )


def _gather(names, classical, polys, symbols, denominators=None) -> list[Formula]:
    out = []
    for b, name in enumerate(names):
        groups: list[tuple[Poly, list[str]]] = []
        entries = sorted((c, poly) for (bb, c), poly in polys.items() if bb == b)
        for c, poly in entries:
            key = _canonical(poly)
            if _is_unit(poly):
                groups.append((poly, [classical[c]]))
                continue
            for g in groups:
                if not _is_unit(g[0]) and _canonical(g[0]) == key:
                    g[1].append(classical[c])
                    break
            else:
                groups.append((poly, [classical[c]]))
        terms = tuple(Term(coef=p, params=tuple(ps)) for p, ps in groups)
        den = (denominators or {}).get(b)
        out.append(Formula(name=name, terms=terms, symbols=symbols, denominator=den))
    return out


def _canonical(poly: Poly) -> tuple:
    return tuple(sorted((e, float(v)) for e, v in poly))
