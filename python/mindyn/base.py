"""Base inertial parameters by the projection or the recursive method (exact) or the numerical
method (sampled).

The three sets -- of the Lagrangian, of the total energy and of the equations of motion -- are
all computed. The equations-of-motion set is the one used for inverse dynamics, the base
regressor and the dynamic identification model; the energy-difference identification model
uses the same set (a constant in the energy cancels in differences).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from functools import cached_property

import numpy as np

from . import _args, _core
from . import formulas as _formulas
from .robot import Robot, as_robot

__all__ = ["BaseParameters", "base_parameters", "choose_method"]

DEFAULT_TOLERANCE = 1e-9
#: The rank tolerance is below this (a larger relative pivot is no round-off; the core refuses it)
MAX_TOLERANCE = 0.01


def choose_method(robot: Robot, *, rotor: bool = False, friction: bool = False) -> tuple[str, str]:
    """The method :func:`base_parameters` runs when none is given, and why: the projection
    method, or the recursive method (exact, the same base set) when any limit of the projection
    method -- joints, parameters, its memory estimate, all checked by the C++ core before
    computing -- refuses the robot with these joint terms, or the numerical method when the
    recursive one refuses it too (rotor inertia of motors that couple joints in a way it
    cannot decide; the reason is given)."""
    refused = _core.projection_refusal(robot._m, rotor=bool(rotor), friction=bool(friction))
    # the exact methods run on a multi-DOF robot's single-DOF expansion: said so
    pairs = "" if robot.single_dof else _EXPANDED
    if refused:
        also = _core.recursive_refusal(robot._m, rotor=bool(rotor), friction=bool(friction))
        if also:
            return "numerical", f"{refused}; {also}: the numerical method (sampled) runs instead"
        return "recursive", (
            f"{refused}; the recursive method is exact and gives the same base set{pairs}"
        )
    return "projection", (
        "the default (exact: Gaussian elimination on the exact coordinates of the Lagrangian's "
        f"coefficients in a finite basis of functions of the joints, no sampling){pairs}"
    )


_EXPANDED = (
    ", each multi-DOF joint taken as its chain of single-DOF joints through massless links "
    "(the same motions of the links)"
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
    sets : dict
        ``lagrangian``, ``energy`` and ``eom``: each with ``n``, ``names``, ``formulas`` (readable),
        ``formulas_full``, ``Y``,
        ``pivots``, ``no_effect`` (classical parameters with no effect at all), ``regrouped``
        and ``margin`` (tolerance, smallest kept / largest dropped relative pivot, the counts at
        the neighbouring tolerances, ``near_degenerate``, and ``consistency``: how far ``W_b Y``
        is from the classical regressor, relative to the size of its terms; a set over the
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
        options: dict | None = None,
    ):
        self._b = core
        self.robot = robot
        self.offset = bool(core.offset)
        if self.offset != bool(offset):
            raise _core.ModelError("offset does not match the core's parameter layout")
        # the settings it was computed with (tolerance, snap, samples, seed), for symbolic()
        self.options = dict(options or {})
        self.method_reason = ""  # set by base_parameters

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
            snap=float(self.options.get("snap", 0.0)),
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
        return out

    @cached_property
    def sets(self) -> dict:
        """The three sets as mappings (see the class attributes), built on first use; each
        set's ``Y`` and formulas on first access (large for long chains and trees)."""
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

    @cached_property
    def formulas(self) -> list[str]:
        """The regrouping formulas of the equations-of-motion set, one per base parameter,
        readable: round-off removed and equal coefficients gathered (written on first use)."""
        return [str(f) for f in self.formula_terms()]

    @cached_property
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
        ``Off_j = Off_j``. Computed on first use."""
        return self._symbolic

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
    #: what ``snap`` would round (rotations or axes within 1e-3 of right angles, not exact)
    snappable = property(lambda self: list(self._b.snappable))
    lagrangian_equals_energy = property(lambda self: self._b.lagrangian_equals_energy)
    lagrangian_equals_eom = property(lambda self: self._b.lagrangian_equals_eom)

    @property
    def margin(self) -> dict:
        """Rank-decision report of the equations-of-motion set."""
        return self.sets["eom"]["margin"]

    @property
    def no_effect(self) -> list[str]:
        """Classical parameters that do not appear in the equations of motion at all."""
        return self.sets["eom"]["no_effect"]

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

    def embed(self, base) -> np.ndarray:
        """A classical vector with ``base`` at the pivot positions and zeros elsewhere, so that
        ``values(embed(p_b)) == p_b`` and any inverse dynamics linear in the classical
        parameters gives the same torques for it."""
        return self._b.embed(_args.array(base, "base", (self.n,)))

    @property
    def _offsets(self) -> int:
        """Entries of the classical vector's joint block (the torque offsets): n or 0."""
        return self.robot.n if self.offset else 0

    def regressor(self, q, dq, ddq) -> np.ndarray:
        """Base regressor ``W_b``, shape (n_joints, n) or (m, n_joints, n):
        ``tau = W_b @ values(params)``; an offset column is 1 in its joint's row. Multi-DOF
        joints: ``q``, ``dq``, ``ddq`` and the rows as :meth:`Robot.regressor` (``nq``, ``nv``),
        its columns at the pivots."""
        if not self.robot.single_dof:
            return self.robot.regressor(q, dq, ddq)[..., self.pivots]
        q, dq, ddq = _args.batch(self.robot.n, q=q, dq=dq, ddq=ddq)
        return self._b.regressor(q, dq, ddq)

    def energy_regressor(self, q, dq) -> np.ndarray:
        """Base total-energy regressor ``w_H,b``, shape (n,) or (m, n), over the
        equations-of-motion set: ``H = w_H,b @ p_b`` up to a constant; an offset's column is
        its work ``q_j`` (``Off_j q_j``), so that differences over a window are the
        energy model's columns."""
        self.robot._require_single_dof("BaseParameters.energy_regressor")
        q, dq = _args.batch(self.robot.n, q=q, dq=dq)
        return self._b.energy_regressor(q, dq)

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
        return self._data[key]

    def __iter__(self):
        return iter([*self._data, *self._later])

    def __len__(self) -> int:
        return len(self._data) + len(self._later)

    def __repr__(self) -> str:
        return f"{{{', '.join(repr(k) for k in self)}}}"


def _plain(d: dict) -> dict:
    return {k: (float(v) if isinstance(v, (float, np.floating)) else v) for k, v in d.items()}


def base_parameters(
    robot: Robot | str,
    *,
    rotor: bool = False,
    friction: bool = False,
    method: str | None = None,
    order: Sequence[int] | Sequence[str] | None = None,
    tolerance: float = DEFAULT_TOLERANCE,
    snap: float | bool | None = None,
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
    snap : float or bool, optional
        Round joint-origin rotations within this many radians of multiples of pi/2 (``True``:
        1e-3) before computing; what was changed is listed in ``snapped`` (and what it would
        change, when not given, in ``snappable``).
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
    if snap is not None and not isinstance(snap, bool):
        snap = _args.number(snap, "snap", minimum=0.0)
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
            missing = [names[i] for i in sorted(set(range(len(names))) - set(idx))]
            raise _args.fail(
                "order",
                f"must name each of the {len(names)} parameters exactly once"
                + (f"; missing: {', '.join(missing[:8])}" if missing else ""),
            )
    if snap is True:
        snap = 1e-3
    core = _core.base_parameters(
        robot._m,
        rotor=rotor,
        friction=friction,
        method=method,
        order=idx,
        tolerance=float(tolerance),
        samples=int(samples),
        seed=int(seed),
        snap=float(snap or 0.0),
        offset=offset,
    )
    options = {"tolerance": float(tolerance), "snap": float(snap or 0.0)}
    options.update(samples=int(samples), seed=int(seed))
    out = BaseParameters(core, robot, offset, options)
    out.method_reason = reason
    return out
