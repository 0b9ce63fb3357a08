"""Base inertial parameters by the projection or the recursive method (exact) or the numerical
method (sampled).

The three sets -- of the Lagrangian, of the total energy and of the equations of motion -- are
all computed. The equations-of-motion set is the one used for inverse dynamics, the base
regressor and the dynamic identification model; the energy-difference identification model
uses the same set (a constant in the energy cancels in differences).
"""

from __future__ import annotations

import copy
from collections import Counter
from collections.abc import Mapping, Sequence
from functools import cached_property
from types import MappingProxyType

import numpy as np

from . import _args, _core
from . import formulas as _formulas
from .robot import Robot, as_robot, drive_train_record

__all__ = [
    "BaseParameters",
    "base_parameters",
    "choose_method",
    "rounded_right_angles",
    "snap_changes",
]

DEFAULT_TOLERANCE = 1e-9
#: The rank tolerance is below this (a larger relative pivot is no round-off; the core refuses it)
MAX_TOLERANCE = 0.01


#: Terms the projection method may form before the default prefers the recursive method (the
#: same base set, exact): about a second of the recursion (a floating humanoid forms 2e7 to 8e7
#: terms in 1 to 4 s, where the recursive method takes milliseconds).
AUTO_PROJECTION_TERMS = 1e7


def choose_method(robot: Robot, *, rotor: bool = False, friction: bool = False) -> tuple[str, str]:
    """The method :func:`base_parameters` runs when none is given, and why: the projection
    method, or the recursive method (exact, the same base set) when any limit of the projection
    method -- joints, parameters, its memory estimate, all checked by the C++ core before
    computing -- refuses the robot with these joint terms or when the projection method would
    form more than :data:`AUTO_PROJECTION_TERMS` terms (its cost estimate, counted before
    computing), or the numerical method when the recursive one refuses it too (rotor inertia
    of motors that couple joints in a way it cannot decide; the reason is given)."""
    refused = _core.projection_refusal(robot._m, rotor=bool(rotor), friction=bool(friction))
    if not refused:
        terms = _core.projection_cost(robot._m, rotor=bool(rotor))["terms"]
        if terms > AUTO_PROJECTION_TERMS:
            refused = (
                f"the projection method would form up to {terms:.2g} terms (over "
                f"{AUTO_PROJECTION_TERMS:.0e}, about a second; method='projection' runs it)"
            )
    # the exact methods run on a multi-DOF robot's single-DOF expansion: said so
    pairs = "" if robot.single_dof else _EXPANDED
    if refused:
        also = _core.recursive_refusal(robot._m, rotor=bool(rotor), friction=bool(friction))
        if also:
            return "numerical", f"{refused}; {also}: the numerical method (sampled) runs instead"
        return "recursive", (
            f"{refused}; the recursive method is exact and gives the same base set{pairs}"
        )
    roots = [k for k, t in enumerate(robot.joint_types) if t == "floating" and robot.parents[k] < 0]
    if roots:  # the projection method takes a floating root as it is
        others = sum(not _single_dof_kind(t) for t in robot.joint_types) - len(roots)
        pairs = _FLOATING_ROOT + (_EXPANDED.replace(", each", " and each other") if others else "")
    return "projection", (
        "the default (exact: Gaussian elimination on the exact coordinates of the Lagrangian's "
        f"coefficients in a finite basis of functions of the joints, no sampling){pairs}"
    )


def _single_dof_kind(kind: str) -> bool:
    return kind in ("revolute", "continuous", "prismatic")


_EXPANDED = (
    ", each multi-DOF joint taken as its chain of single-DOF joints through massless links "
    "(the same motions of the links)"
)
_FLOATING_ROOT = (
    ", the floating root taken as it is (its body's twist and the direction of gravity in its "
    "frame)"
)


class BaseParameters:
    """Base parameters of a robot, with the regrouping matrix and the base regressors.

    Attributes
    ----------
    n : int
        Number of base parameters of the equations of motion (friction and offsets included
        when enabled).
    names : list of str
        Their names; a regrouped parameter gets ``R`` before its index (``XXR3``).
    Y : ndarray, shape (n, P)
        Regrouping matrix: ``p_b = Y @ params`` for a classical vector of length ``P``.
    formulas : list of str
        ``XXR2 = XX2 - YY2 + 0.18645124*(M2 + M3 + M4 + M5 + M6)``: coefficients without their
        round-off, equal ones gathered (see :mod:`mindyn.formulas`).
    formulas_full : list of str
        The same at full precision, one term per classical parameter
        (``... + 0.18645124000000002*M2 + ...``).
    sets : mapping
        ``lagrangian``, ``energy`` and ``eom``: each with ``n``, ``names``, ``formulas`` (readable),
        ``formulas_full``, ``Y``,
        ``pivots``, ``no_effect`` (classical parameters with no effect at all), ``regrouped``
        and ``margin`` (tolerance, smallest kept / largest dropped relative pivot, the counts at
        the neighbouring tolerances, ``near_degenerate``, ``decided_by_tolerance``: the
        parameters whose decision a neighbouring tolerance changes, and ``consistency``: how far
        ``W_b Y`` is from the classical regressor, relative to the size of its terms; a set over the
        tolerance is refused with a ModelError when computed). Each set is a read-only mapping
        whose ``Y`` and formulas are computed on first access.
    method_reason : str
        Why this method ran: ``method='recursive'`` when it was given, else the reason of
        :func:`choose_method` (``"the projection method handles at most 18 joints, ..."``).
    offset : bool
        A constant torque offset per joint, ``tau_j = ... + Off_j``: the parameters ``Off1 ..
        OffN`` (the core's parameter layout names them) follow all others, in the base set as
        in the classical vector, each a base parameter (its regressor column is 1 in its
        joint's equation, 0 elsewhere). A link parameter whose column differs from others by a
        constant regroups into the offset (a vertical prismatic joint's mass ``M`` beside its
        rotor inertia: ``IaR = Ia + M``, ``OffR = Off + g M``). The equations-of-motion set in
        ``sets`` ends with them; the Lagrangian and total-energy sets do not contain them.
    """

    def __init__(
        self,
        core: _core.BaseParameters,
        robot: Robot,
        offset: bool = False,
        options: Mapping | None = None,
    ):
        self._b = core
        self.robot = robot
        self.offset = bool(core.offset)
        if self.offset != bool(offset):
            raise _core.ModelError("offset does not match the core's parameter layout")
        self._options = _frozen(options or {})
        self.method_reason = ""  # set by base_parameters
        self._snap_decision = _frozen({"mode": "off", "applied": False})
        # A base set that differs from others only in some regressor columns (the friction
        # columns that with_friction_velocity changes): (the first set of that family, what
        # varies), else None. Filtered regressors of one family share the other columns
        # (preprocess.ParallelFilter filters the varied ones only).
        self._family: tuple | None = None
        if core.friction and robot.single_dof:
            if robot.friction_model["kind"] in ("smooth", "stribeck"):
                self._family = (self, "velocity")

    @property
    def options(self) -> Mapping:
        """The settings it was computed with (``tolerance``, ``snap``, ``samples``, ``seed``),
        read-only."""
        return self._options

    @property
    def snap_decision(self) -> Mapping:
        """What the snap did and why (see :func:`base_parameters`), read-only (its lists as
        tuples; ``to_dict()["snap"]`` is a plain copy)."""
        return self._snap_decision

    def for_robot(
        self, robot: Robot, *, order: Sequence[int] | Sequence[str] | None = None, offset=None
    ) -> BaseParameters:
        """The base parameters of ``robot`` (e.g. the same description at other lengths) by the
        same method, joint terms and settings as these; ``order`` (as :func:`base_parameters`
        takes it) replaces the column priority order, ``offset`` the offsets, when given."""
        _args.instance(robot, "robot", Robot)
        offset = _args.optional(_args.flag, offset, "offset")
        return base_parameters(
            robot,
            rotor=self.rotor,
            friction=self.friction,
            method=self.method,
            order=order,
            tolerance=float(self.options.get("tolerance", 1e-9)),
            samples=int(self.options.get("samples", 0)),
            seed=int(self.options.get("seed", 1)),
            snap=self.options.get("snap", "auto"),
            offset=self.offset if offset is None else offset,
        )

    def with_friction_velocity(self, velocity) -> BaseParameters:
        """The same base set for the robot whose friction model (smooth or Stribeck) has the
        velocity scale ``velocity`` (n,) instead: the friction parameters are base parameters
        of their own, so only the regressor's friction columns change."""
        kind = self.robot.friction_model["kind"]
        v = _args.array(velocity, "velocity", (self.robot.n,))
        robot = self.robot.with_friction_model(kind, velocity=v)
        out = BaseParameters(self._b.with_friction_velocity(v), robot, self.offset, self.options)
        out.method_reason = self.method_reason
        out._snap_decision = self._snap_decision  # the same geometry, snapped the same way
        if kind in ("smooth", "stribeck"):
            root = self._family[0] if self._family and self._family[1] == "velocity" else self
            out._family = (root, "velocity")
        return out

    def _varied(self) -> list[tuple[int, int, int]]:
        """The regressor columns that differ within the base set's family (``_family``): per
        column ``(base column, slot, column of the friction model's shapes)``; slot ``k``'s
        column is its friction shape at its velocity times row ``k`` of the drive matrix (the
        friction parameters are base parameters of their own)."""
        if self._family is None or self._family[1] != "velocity":
            return []
        i = 1 if self.robot.friction_model["kind"] == "smooth" else 2  # tanh(v/w), or s exp
        term = ("Fc", "Fc", "Fs")[i]
        names = list(self.names)
        return [
            (names.index(f"{term}{k + 1}"), k, i)
            for k in range(self.robot.n)
            if f"{term}{k + 1}" in names
        ]

    def _varied_regressor(self, q, dq, ddq) -> np.ndarray:
        """The columns of :meth:`_varied` of the regressor at ``(q, dq, ddq)`` (m, n_joints,
        len(_varied())): those columns of :meth:`regressor`, without forming the others."""
        cols = self._varied()
        phi = self.robot.friction_shapes(self.robot.slot_velocities(dq))  # (m, n, c)
        T = self.robot.drive_matrix
        out = np.empty((phi.shape[0], self.robot.n, len(cols)))
        for c, (_, k, i) in enumerate(cols):
            out[:, :, c] = phi[:, k, i, None] * T[k]
        return out

    @property
    def sets(self) -> Mapping:
        """The three sets as a read-only mapping of read-only mappings (see the class
        attributes), built on first use; each set's ``Y`` and formulas on first access (large
        for long chains and trees)."""
        return MappingProxyType(self._sets)

    @cached_property
    def _sets(self) -> dict:
        core = self._b
        out = {}
        for kind in ("lagrangian", "energy", "eom"):
            d = getattr(core, kind)
            out[kind] = _Set(
                d,
                Y=lambda k=kind: core.set_matrix(k),
                formulas_full=lambda k=kind: list(core.set_formulas(k)),
                formulas=lambda k=kind, n=d["names"]: [str(f) for f in self._readable(k, n)],
            )
        return out

    def _readable(self, kind: str, names: Sequence[str]) -> list[_formulas.Formula]:
        """The readable formulas of a set, from its rows of ``Y`` a block at a time (``Y`` is
        stored sparse: a dense copy of a 1000-joint tree's would take about 1 GB)."""
        core, classical = self._b, list(self._b.classical_names)
        out: list[_formulas.Formula] = []
        for first in range(0, len(names), _ROWS_AT_ONCE):
            rows, cols = core.set_rows(kind, first, _ROWS_AT_ONCE)  # only columns with entries
            out += _formulas.numeric_formulas(
                rows, names[first : first + _ROWS_AT_ONCE], [classical[c] for c in cols]
            )
        return out

    n = property(lambda self: self._b.n)
    names = property(lambda self: list(self._b.names))

    @property
    def formulas(self) -> list[str]:
        """The regrouping formulas of the equations-of-motion set, one per base parameter,
        readable: round-off removed and equal coefficients gathered (written on first use; each
        access gives a list of its own)."""
        return list(self._formula_texts)

    @cached_property
    def _formula_texts(self) -> tuple[str, ...]:
        return tuple(str(f) for f in self.formula_terms())

    @property
    def formulas_full(self) -> list[str]:
        """The regrouping formulas at full precision, one term per classical parameter."""
        return list(self._b.formulas)

    def formula_terms(self) -> list[_formulas.Formula]:
        """The readable formulas as :class:`mindyn.formulas.Formula` objects (``str()`` gives
        the text, ``.latex()`` a LaTeX row)."""
        return self._readable("eom", list(self._b.names))

    @cached_property
    def _symbolic(self) -> _formulas.SymbolicFormulas:
        return _formulas.symbolic_formulas(self)

    def symbolic(self) -> _formulas.SymbolicFormulas:
        """The regrouping formulas in the symbols of the robot's description (lengths ``d_j,
        r_j`` of an MDH table, ``a_j, d_j`` of a DH table, joint origins ``x_j, y_j, z_j`` of a
        URDF), recovered exactly and checked against the numeric ``Y`` at several geometries;
        see :func:`mindyn.formulas.symbolic_formulas`. Offsets, when enabled, are
        ``Off_j = Off_j``. Computed on first use; each call gives a copy of its own (its lists
        and dicts), so that what one caller does with it never changes another's."""
        return copy.deepcopy(self._symbolic)

    def latex(self, *, symbolic: bool = False) -> str:
        """The formulas (numeric, or symbolic) as a LaTeX ``align*`` environment."""
        symbolic = _args.flag(symbolic, "symbolic")
        if symbolic:
            return _formulas.latex(self.symbolic().formulas)
        return _formulas.latex(self.formula_terms())

    Y = property(lambda self: _args.readonly(self._b.Y))
    pivots = property(lambda self: list(self._b.pivots))
    classical_names = property(lambda self: list(self._b.classical_names))
    rotor = property(lambda self: self._b.rotor)
    friction = property(lambda self: self._b.friction)
    method = property(lambda self: self._b.method)
    seconds = property(lambda self: self._b.seconds)
    basis_rows = property(lambda self: self._b.basis_rows)
    terms_formed = property(lambda self: self._b.terms_formed)
    snapped = property(lambda self: self._b.snapped)
    #: what ``snap`` would round (rotations or axes within 1e-3 of right angles, not exact), as
    #: text; the same as data: :func:`snap_changes`
    snappable = property(lambda self: list(self._b.snappable))
    lagrangian_equals_energy = property(lambda self: self._b.lagrangian_equals_energy)
    lagrangian_equals_eom = property(lambda self: self._b.lagrangian_equals_eom)

    def snap_report(self, *, detail: bool = True) -> list[str]:
        """What the snap did, in sentences (none when nothing was near a right angle): with the
        default ``snap="auto"``, the rounded right angles rounded to them (how many, the largest
        deviation, the tolerance, the check against the description's torques) or why nothing
        was, and the deliberate angles kept; with ``detail``, each rotation changed too."""
        detail = _args.flag(detail, "detail")
        d = self.snap_decision
        if d.get("mode") != "auto" or not (d.get("rounded") or d.get("real")):
            return list(self.snapped)
        rounded, real = d["rounded"], d["real"]
        if d["applied"]:
            check = d.get("check")
            checked = (
                f"the snapped model reproduces the description's torques to {check:.2g} "
                f"relative (bound {d['check_bound']:.2g})"
                if check is not None
                else "not checked against the description (over 200 joints)"
            )
            coarse = d.get("precision", 0.0)
            bound = f"{d.get('bound', SNAP_AUTO_BOUND):.2g} rad" + (
                f", three times the coarsest right angle written with few decimals, "
                f"{coarse:.2g} rad"
                if 3 * coarse > SNAP_AUTO_BOUND
                else ""
            )
            out = [
                f"{len(rounded)} right angle(s) written rounded (each off by at most {bound}, "
                f"or by a decimal rounding of a multiple of pi/2; largest "
                f"{d['largest_rounding']:.2g} rad) rounded to them (snap auto, tolerance "
                f"{d['tolerance']:.2g}; snap off keeps them); {checked}"
            ]
        else:
            why = d.get("refused") or "none is a rounded right angle"
            out = [f"nothing snapped (snap auto): {why}"]
        if real:
            out.append(
                f"kept as written: {len(real)} deliberate angle(s) near right angles, smallest "
                f"deviation {d['smallest_real']:.2g} rad ({real[0][0]})"
            )
        return out + (list(self.snapped) if detail else [])

    @property
    def margin(self) -> dict:
        """Rank-decision report of the equations-of-motion set."""
        return self.sets["eom"]["margin"]

    @property
    def no_effect(self) -> list[str]:
        """Classical parameters that do not appear in the equations of motion at all."""
        return self.sets["eom"]["no_effect"]

    @_args.finite_results("params")
    def values(self, params) -> np.ndarray:
        """``p_b = Y @ params``; ``params`` in the classical layout of this set, shape (P,).
        With offsets, a vector without them (shape (P - n_joints,)) is accepted too: its
        offsets are zero."""
        P = len(self._b.classical_names)
        links = P - self._offsets
        p = params
        if self.offset and isinstance(p, (list, tuple, np.ndarray)) and np.shape(p) == (links,):
            p = np.concatenate([_args.array(p, "params", (links,)), np.zeros(self._offsets)])
        return self._b.values(_args.array(p, "params", (P,)))

    @_args.finite_results("base")
    def embed(self, base) -> np.ndarray:
        """A classical vector with ``base`` at the pivot positions and zeros elsewhere, so that
        ``values(embed(p_b)) == p_b`` and any inverse dynamics linear in the classical
        parameters gives the same torques for it."""
        return self._b.embed(_args.array(base, "base", (self.n,)))

    @property
    def _offsets(self) -> int:
        """Entries of the classical vector's joint block (the torque offsets): n or 0."""
        return self.robot.n if self.offset else 0

    @_args.finite_results("q", "dq", "ddq")
    def regressor(self, q, dq, ddq) -> np.ndarray:
        """Base regressor ``W_b``, shape (n_joints, n) or (m, n_joints, n):
        ``tau = W_b @ values(params)``; an offset column is 1 in its joint's row. Multi-DOF
        joints: ``q``, ``dq``, ``ddq`` and the rows as :meth:`Robot.regressor` (``nq``, ``nv``),
        its columns at the pivots."""
        if not self.robot.single_dof:
            return self.robot.regressor(q, dq, ddq)[..., self.pivots]
        q, dq, ddq = _args.batch(self.robot.n, q=q, dq=dq, ddq=ddq)
        return self._b.regressor(q, dq, ddq)

    @_args.finite_results("q", "dq")
    def energy_regressor(self, q, dq) -> np.ndarray:
        """Base total-energy regressor ``w_H,b``, shape (n,) or (m, n), over the
        equations-of-motion set: ``H = w_H,b @ p_b`` up to a constant; an offset's column is
        its work ``q_j`` (``Off_j q_j``), so that differences over a window are the
        energy model's columns."""
        self.robot._require_single_dof("BaseParameters.energy_regressor")
        q, dq = _args.batch(self.robot.n, q=q, dq=dq)
        return self._b.energy_regressor(q, dq)

    @_args.finite_results("q", "dq")
    def momentum_regressors(self, q, dq):
        """Base momentum regressors ``(W_p,b, W_l,b)``, shape (n_joints, n) or (m, n_joints, n)
        each, over the equations-of-motion set: ``p = A(q) dq = W_p,b @ p_b`` and
        ``-dL/dq + offsets = W_l,b @ p_b`` (an offset's column is 1 in its joint's row of
        ``W_l,b``, 0 in ``W_p,b``; see ``Robot.momentum_regressors``)."""
        self.robot._require_single_dof("BaseParameters.momentum_regressors")
        q, dq = _args.batch(self.robot.n, q=q, dq=dq)
        return self._b.momentum_regressors(q, dq)

    def to_dict(self, *, symbolic: bool = False) -> dict:
        """A JSON-ready summary (counts, names, formulas, margins); with ``symbolic``, also
        ``formulas_symbolic``, ``symbols`` and ``symbolic_check`` (see :meth:`symbolic`)."""
        symbolic = _args.flag(symbolic, "symbolic")
        out = {
            "robot": self.robot.name,
            "method": self.method,
            "rotor": self.rotor,
            "friction": self.friction,
            "offset": self.offset,
            "n_base": self.n,
            "names": self.names,
            "formulas": self.formulas,
            "formulas_full": self.formulas_full,
            "margin": _plain(self.margin),
            "no_effect": self.no_effect,
            "counts": {k: s["n"] for k, s in self.sets.items()},
            "lagrangian_equals_energy": self.lagrangian_equals_energy,
            "lagrangian_equals_eom": self.lagrangian_equals_eom,
            "used_for": {
                "inverse_dynamics": "eom",
                "dynamic_identification": "eom",
                "energy_identification": "eom",
                "integral_identification": "eom",
            },
            "sets": {
                k: {
                    "n": s["n"],
                    "names": s["names"],
                    "formulas": s["formulas"],
                    "no_effect": s["no_effect"],
                    "margin": _plain(s["margin"]),
                }
                for k, s in self.sets.items()
            },
            "basis_rows": self.basis_rows,
            "seconds": self.seconds,
            "snapped": self.snapped,
            "snappable": self.snappable,
            "snap": _plain(self.snap_decision),
            **drive_train_record(self.robot),
        }
        if symbolic:
            out.update(self.symbolic().to_dict())
        return out

    def __repr__(self) -> str:
        off = ", offset=True" if self.offset else ""
        return f"BaseParameters(robot={self.robot.name!r}, n={self.n}, method={self.method!r}{off})"


_ROWS_AT_ONCE = 64


class _Set(Mapping):
    """One set's dictionary (``n``, ``names``, ``margin``, ...) whose entries given as functions
    (``Y``, the formulas) are computed on first access."""

    def __init__(self, data: dict, **later):
        self._data = dict(data)
        self._later = later

    def __getitem__(self, key):
        if key not in self._data and key in self._later:
            self._data[key] = self._later.pop(key)()
        return _own_copy(self._data[key])

    def __iter__(self):
        return iter([*self._data, *self._later])

    def __len__(self) -> int:
        return len(self._data) + len(self._later)

    def __repr__(self) -> str:
        return f"{{{', '.join(repr(k) for k in self)}}}"


def _own_copy(value):
    """``value`` as its reader's own: lists and dicts copied (nested ones too), arrays read-only,
    so that what one user does with an entry never changes the set under another."""
    if isinstance(value, dict):
        return {k: _own_copy(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return type(value)(_own_copy(v) for v in value)
    if isinstance(value, np.ndarray):
        view = value.view()
        view.flags.writeable = False
        return view
    return value


def _frozen(x):
    """``x`` read-only, all the way down: mappings as read-only views of copies, lists and
    tuples as tuples (what a getter returns: the object never changes under its users)."""
    if isinstance(x, Mapping):
        return MappingProxyType({k: _frozen(v) for k, v in x.items()})
    if isinstance(x, (list, tuple)):
        return tuple(_frozen(v) for v in x)
    return x


def _plain(x):
    """``x`` (of :func:`_frozen`) as JSON takes it: dicts, lists and Python floats."""
    if isinstance(x, Mapping):
        return {k: _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    return float(x) if isinstance(x, (float, np.floating)) else x


# --------------------------------------------------------------------------------------------
# The default snap: right angles the description writes rounded
# --------------------------------------------------------------------------------------------
#: Largest deviation from a right angle that ``snappable`` lists (the C++ core's window)
SNAP_WINDOW = 1e-3
#: Largest deviation from a right angle [rad] that ``snap="auto"`` takes for a rounding whatever
#: its digits: descriptions exported from CAD write rotations and axes with 6 to 8 significant
#: digits, computed in single or double precision from a pose (``1.5707963``, an axis
#: ``(-1, 8.5e-11, 7e-8)``), so each number is off by up to a few 1e-6 rad and a rotation
#: composed of three such numbers by about 1e-5. A tilt this small changes the torques by about
#: as much, relatively (checked), far below what a torque measurement resolves, while the rank
#: decision (tolerance 1e-9) would take it for geometry: parameters of the size of the tilt.
SNAP_AUTO_BOUND = 1e-5
#: Deviations this close to a decimal rounding of a right angle are that rounding: 16 units of
#: round-off of an angle of size 2 pi (the angles are read back from the composed rotation)
_ROUNDING_MATCH = 16 * np.finfo(float).eps * 2 * np.pi


def _decimal_roundings() -> np.ndarray:
    """``|round(m pi/2, d) - m pi/2|`` and the same cut instead of rounded (3.14158) for
    m = 1..4 and d = 0..17 decimals, sorted. (Not their sums: the sum of two roundings of one
    angle is a round decimal, 1.571 - 1.57 = 1e-3, which is how a deliberate offset is
    written.)"""
    right = [m * np.pi / 2 for m in range(1, 5)]
    written = {round(a, d) for a in right for d in range(18)}
    written |= {np.floor(a * 10.0**d) / 10.0**d for a in right for d in range(18)}
    return np.array(sorted({min(abs(w - a) for a in right) for w in written}))


_ROUNDINGS = _decimal_roundings()


def _is_rounding(deviation: float, floor: float = 0.0) -> bool:
    """Whether ``deviation`` from a right angle is at most ``floor``, or a right angle written
    with fewer decimals than a double holds (1.5708, 1.571), or round-off."""
    if deviation <= max(_ROUNDING_MATCH, floor):
        return True
    return _is_decimal_rounding(deviation)


def _is_decimal_rounding(deviation: float) -> bool:
    """Whether ``deviation`` is, to round-off, what writing a right angle with fewer decimals
    than a double holds leaves, rounded or cut (1.5708: 3.67e-6; 1.571: 2.04e-4; 3.14158:
    1.27e-5)."""
    k = int(np.searchsorted(_ROUNDINGS, deviation))
    near = _ROUNDINGS[max(k - 1, 0) : k + 1]
    return bool(np.min(np.abs(near - deviation)) <= _ROUNDING_MATCH)


def snap_changes(robot: Robot | str, *, tolerance: float = SNAP_WINDOW) -> list[dict]:
    """What a snap of ``tolerance`` [rad] would round in ``robot`` (unchanged), as the core
    computes it: one dict per angle or axis component, with ``joint`` (0-based) and
    ``joint_name``, ``frame`` (``"origin"``: the joint's rotation before its motion, ``"link
    frame"``: the one after it, ``"axis"``), ``component`` (``"yaw"``, ``"pitch"``, ``"roll"``
    of the rotation ``Rz(yaw) Ry(pitch) Rx(roll)``, or ``"x"``, ``"y"``, ``"z"`` of the axis),
    ``value`` (the angle or component), ``snapped`` (the multiple of pi/2, or 0) and
    ``deviation`` (``|value - snapped|``, in (0, tolerance]). The same changes as text are
    :attr:`BaseParameters.snappable` (``tolerance`` 1e-3) and :attr:`BaseParameters.snapped`."""
    robot = as_robot(robot)
    tolerance = _args.number(tolerance, "tolerance", positive=True)
    return list(_core.snap_changes(robot._m, tolerance)[0])


def rounded_right_angles(
    changes: Sequence[Mapping],
    *,
    tolerance: float = DEFAULT_TOLERANCE,
    bound: float = SNAP_AUTO_BOUND,
) -> dict:
    """Which of the near right angles ``changes`` lists (:func:`snap_changes` of a robot: angles
    and axis components within 1e-3 of a right angle) are right angles written rounded, and the
    snap tolerance that rounds those and nothing else.

    The description's precision is the coarsest right angle it writes with few decimals: the
    largest deviation of an angle from its multiple of pi/2 that is exactly (to round-off) what
    writing the multiple with ``d`` decimals, rounded or cut, leaves, for some ``d``
    (``1.5708``: 3.67e-6; ``1.571``: 2.04e-4; ``3.14158``: 1.27e-5; 0 when there is none). An
    angle or axis component is a rounded right angle when its deviation from the nearest
    multiple of pi/2 (from 0, for an axis component) is at most the effective bound: ``bound``
    (default :data:`SNAP_AUTO_BOUND`, 1e-5 rad: what descriptions exported from CAD leave, 6 to
    8 significant digits, ``1.5707963``, an axis ``(-1, 8.5e-11, 7e-8)``), three times the
    precision (a rotation read back from three such angles) or the rank ``tolerance``, whichever
    is largest; an angle also when it is such a decimal rounding itself. A deliberate angle (a
    calibrated offset of 1e-3 rad beside right angles written 1.5708, a tilt of 5e-5 rad written
    with its own digits) is above the bound and no decimal rounding: real geometry, kept.
    Returns ``rounded`` and ``real`` (what, deviation in rad), ``largest_rounding``,
    ``smallest_real`` (None when there is none; every rounding is at most the bound, every real
    deviation above it), ``precision``, ``bound`` (the effective one) and ``tolerance``: the
    snap tolerance, twice the largest rounding (at most the geometric mean of it and the
    smallest real deviation, and at most 1e-3: a deviation beyond is not listed), 0 when
    nothing is rounded.
    """
    _args.instance(changes, "changes", (list, tuple), "a list of the dicts of snap_changes")
    tolerance = _args.number(tolerance, "tolerance", minimum=0.0)
    bound = _args.number(bound, "bound", minimum=0.0)
    near: list[tuple[str, float, bool]] = []
    for change in changes:
        try:
            what = f"joint '{change['joint_name']}' {change['frame']} {change['component']}"
            dev, axis = float(change["deviation"]), change["frame"] == "axis"
        except (TypeError, KeyError, ValueError):
            raise _args.fail("changes", f"holds {change!r}, not an entry of snap_changes") from None
        if 0 < dev <= SNAP_WINDOW:
            near.append((what, dev, axis))
    precision = max(
        (d for _, d, axis in near if not axis and d > _ROUNDING_MATCH and _is_decimal_rounding(d)),
        default=0.0,
    )
    # (1 + 1e-9): three roundings read back from one rotation sum to 3 p up to round-off
    bound = max(bound, 3 * precision * (1 + 1e-9), tolerance)
    rounded: list[tuple[str, float]] = []
    real: list[tuple[str, float]] = []
    for what, dev, axis in near:
        small = dev <= max(_ROUNDING_MATCH, bound) if axis else _is_rounding(dev, bound)
        (rounded if small else real).append((what, dev))
    largest = max((d for _, d in rounded), default=0.0)
    smallest = min((d for _, d in real), default=None)
    tolerance = 0.0
    if rounded:  # (at most the window: a deviation beyond it is not listed, but would be snapped)
        tolerance = min(2 * largest, SNAP_WINDOW)
        if smallest is not None:
            tolerance = min(tolerance, np.sqrt(largest * smallest))
    return {
        "rounded": rounded,
        "real": real,
        "largest_rounding": largest,
        "smallest_real": smallest,
        "precision": precision,
        "bound": bound,
        "tolerance": tolerance,
    }


def base_parameters(
    robot: Robot | str,
    *,
    rotor: bool = False,
    friction: bool = False,
    method: str | None = None,
    order: Sequence[int] | Sequence[str] | None = None,
    tolerance: float = DEFAULT_TOLERANCE,
    snap: float | bool | str | None = "auto",
    samples: int = 0,
    seed: int = 1,
    offset: bool = False,
) -> BaseParameters:
    """Base inertial parameters of ``robot``.

    Parameters
    ----------
    robot : Robot or str
        A robot or anything :func:`mindyn.load` accepts.
    rotor, friction : bool
        Include rotor inertia ``Ia`` and viscous / Coulomb friction ``Fv, Fc`` per joint.
    method : {"auto", "projection", "recursive", "numerical"}, optional
        Exact projection method; exact recursive method (the identifiable space link by
        link, cost linear in the number of joints, then the same echelon form: the same base
        set and ``Y``); or sampled regressors with QR (for cross-checks). The projection
        method's basis grows geometrically along runs of parallel or general joint axes: its
        memory is estimated before computing (an upper bound) and a chain over its memory
        budget, or beyond its joint limits, is refused with a ModelError that gives the
        estimate or the limit; the recursive method handles such chains, and so does the
        numerical one, up to its own budget of 2 GiB (about 340 joints). All three handle trees
        (``Robot.parents``). The projection method's limits (joints on a chain, on a tree and on
        one root path of a tree, parameters, memory budget) are those of the C++ core,
        ``mindyn._core.projection_limits()``. Default (``None`` or ``"auto"``): the
        projection method, or the recursive one where a limit of the projection method refuses
        the robot (:func:`choose_method`; the choice and its reason are in ``method`` and
        ``method_reason``). A robot with multi-DOF joints (spherical, universal, cylindrical,
        planar, floating; :attr:`Robot.single_dof` false) takes the three methods, without
        rotor inertia or friction: the exact ones run on each pair written as a chain of
        single-DOF joints through massless links (the manual's base-parameters page), whose
        joints the projection method's limits count, and the default chooses as above.
    order : sequence of int or str, optional
        Column priority: every classical parameter once, by index or name (``"XX1"``).
        Default: Khalil's order (link by link; ``YY, MZ, M`` last in each link; then ``Ia``).
    tolerance : float
        Relative size below which a pivot counts as zero (default 1e-9, below 0.01). Every
        decision's margin is reported in ``sets[...]["margin"]``. Each set is checked against
        the classical inverse dynamics (energies for the Lagrangian and total-energy sets) at
        random states; one whose regrouping misses them (near-degenerate geometry) raises a
        ModelError that says by how much and what to try.
    snap : "auto", float or bool, optional
        Which joint-origin rotations near multiples of pi/2 are rounded to them before
        computing. ``"auto"`` (the default): the right angles and axes the description writes
        rounded (:func:`rounded_right_angles`: within 1e-5 rad, :data:`SNAP_AUTO_BOUND`, as CAD
        exports write them, ``1.5707963``, an axis ``(-1, 8.5e-11, 7e-8)``; within three times
        the coarsest decimal rounding of a right angle the description writes, ``1.571``; or a
        decimal rounding itself), never a deliberate angle above that bound; the snapped set is
        checked against the description's own inverse dynamics (within 100 times the largest
        rounding, relative to the largest torque; else nothing is snapped). A number: every
        rotation and axis component within this many radians (``True``: 1e-3).
        ``False``, ``None`` or 0: none. What was done and why is in ``snap_decision`` and
        :meth:`~BaseParameters.snap_report`, what was changed in ``snapped`` (what a snap of
        1e-3 would change, when nothing was snapped, in ``snappable``).
    samples, seed : int
        Numerical method only: number of random states for the regressor (0: automatic,
        ``max(40, 3 P / n + 20)`` for ``P`` parameters and ``n`` joints; fewer than ``P / n`` are
        refused) and the random seed. The energies take at least ``P + max(20, P / 2)`` states,
        so that no set is capped by the number of samples.
    offset : bool
        Add a constant torque offset per joint, ``Off1 .. OffN``, after all other parameters
        (see :class:`BaseParameters`); ``order`` does not name them.
    """
    robot = as_robot(robot)
    rotor, friction = _args.flag(rotor, "rotor"), _args.flag(friction, "friction")
    offset = _args.flag(offset, "offset")
    _args.optional(_args.choice, method, "method", ("auto", "projection", "recursive", "numerical"))
    if method is None or method == "auto":
        method, reason = choose_method(robot, rotor=rotor, friction=friction)
    else:
        reason = f"method={method!r}"
    tolerance = _args.number(tolerance, "tolerance", positive=True, below=MAX_TOLERANCE)
    samples = _args.integer(samples, "samples", minimum=0)
    seed = _args.integer(seed, "seed", minimum=0)
    snap = _args.snap(snap)
    idx: list[int] = []
    if order is not None:
        names = robot.parameter_names(rotor=rotor, friction=friction)
        lookup = {name: i for i, name in enumerate(names)}
        if isinstance(order, (str, bytes)) or not hasattr(order, "__iter__"):
            raise _args.fail(
                "order", f"is {order!r}; expected a sequence of parameter indices or names"
            )
        for item in order:
            if isinstance(item, str):
                if item not in lookup:
                    raise _args.fail("order", f"names an unknown parameter '{item}'")
                idx.append(lookup[item])
            else:
                idx.append(_args.integer(item, "order entry"))
        if sorted(idx) != list(range(len(names))):
            twice = sorted(i for i, c in Counter(idx).items() if c > 1)
            missing = [names[i] for i in sorted(set(range(len(names))) - set(idx))]
            said = []
            if twice:
                named = (names[i] if 0 <= i < len(names) else str(i) for i in twice)
                said.append(f"named twice: {', '.join(named)}")
            if missing:
                more = ", ..." if len(missing) > 8 else ""
                said.append(f"{len(missing)} missing: {', '.join(missing[:8])}{more}")
            raise _args.fail(
                "order",
                f"must name each of the {len(names)} parameters exactly once"
                + "".join(f"; {s}" for s in said),
            )
    if snap is True:
        snap = SNAP_WINDOW

    def compute(at: float) -> _core.BaseParameters:
        return _core.base_parameters(
            robot._m,
            rotor=rotor,
            friction=friction,
            method=method,
            order=idx,
            tolerance=float(tolerance),
            samples=int(samples),
            seed=int(seed),
            snap=at,
            offset=offset,
        )

    decision: dict
    if snap == "auto":
        core, decision = _auto_snap(robot, compute, tolerance)
    else:
        core = compute(float(snap or 0.0))
        decision = {"mode": "given" if snap else "off", "applied": bool(core.snapped)}
        decision.update(tolerance=float(snap or 0.0))
    options = {"tolerance": float(tolerance), "snap": snap if snap == "auto" else float(snap or 0)}
    options.update(samples=int(samples), seed=int(seed))
    out = BaseParameters(core, robot, offset, options)
    out.method_reason = reason
    out._snap_decision = _frozen(decision)
    return out


def _auto_snap(robot: Robot, compute, tolerance: float) -> tuple[_core.BaseParameters, dict]:
    """``snap="auto"``: the base parameters with the right angles the description writes
    rounded snapped (:func:`rounded_right_angles` of the model's :func:`snap_changes`), checked
    against the description's own inverse dynamics; and the decision. The base set is computed
    once: snapped, or as written when nothing is snapped (or the snapped set fails the
    check)."""
    found = rounded_right_angles(snap_changes(robot), tolerance=tolerance)
    decision = {"mode": "auto", "applied": False, **found}
    decision["rounded"] = [list(x) for x in found["rounded"]]
    decision["real"] = [list(x) for x in found["real"]]
    if found["tolerance"] > 0:
        snapped = compute(found["tolerance"])
        check = _snap_check(robot, snapped)
        bound = 100 * found["largest_rounding"] + 1e-10
        decision.update(check=check, check_bound=bound)
        if check is None or check <= bound:
            decision["applied"] = True
            return snapped, decision
        decision["refused"] = (
            f"the snapped base set reproduces the description's torques only to {check:.2g} "
            f"(over {bound:.2g})"
        )
    return compute(0.0), decision  # (a refusal of the description as written is raised)


def _snap_check(robot: Robot, core: _core.BaseParameters) -> float | None:
    """Largest difference, relative to the largest torque, between the snapped base model
    (``W_b Y p``) and the description's inverse dynamics at a few random states (unit
    quaternions and (cos, sin) pairs where multi-DOF joints take them), with the description's
    link parameters; None where not checked (over 200 joints: the classical regressors would
    take too much memory)."""
    if robot.n > 200:
        return None
    rng = np.random.default_rng(0)
    q = rng.uniform(-1.0, 1.0, (4, robot.nq))
    for start, size, _ in robot._unit_blocks():
        block = q[:, start : start + size]
        block /= np.linalg.norm(block, axis=1, keepdims=True)
    dq, ddq = (rng.uniform(-1.0, 1.0, (4, robot.nv)) for _ in range(2))
    p = dict(zip(robot.param_names, robot.params))
    base = BaseParameters(core, robot, bool(core.offset))
    values = base.values(np.array([p.get(name, 0.0) for name in core.classical_names]))
    tau = np.array([robot.inverse_dynamics(*x) for x in zip(q, dq, ddq)])
    model = np.array([base.regressor(*x) @ values for x in zip(q, dq, ddq)])
    return float(np.max(np.abs(model - tau)) / max(np.max(np.abs(tau)), np.finfo(float).tiny))
