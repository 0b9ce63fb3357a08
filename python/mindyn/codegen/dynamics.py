"""The runtime base-parameter dynamics: the customised recursion flattened in C++
(:class:`BaseDynamics`), the same program the generated code runs, without compiling."""

from __future__ import annotations

from numpy import ndarray

from .. import _args, _core
from ..base import BaseParameters

__all__ = ["BaseDynamics"]


class BaseDynamics:
    """Inverse dynamics, gravity torque and base regressor in the base parameters, by the
    customised Newton-Euler recursion flattened at construction (C++, allocation-free per call).

    Parameters
    ----------
    base : BaseParameters
        From :func:`mindyn.base_parameters` (its robot, rotor, friction and offset settings are
        used; offsets are added to the inverse dynamics, not to the gravity torque).

    Attributes
    ----------
    n, np : int
        Joints and base parameters.
    names : list of str
    counts : dict
        Operation counts per function.
    geometry_snap : dict
        Geometric constants taken as exactly 0 or +-1, as in :class:`GeneratedCode`.
    """

    def __init__(self, base: BaseParameters):
        self.base = _args.instance(base, "base", BaseParameters)
        self._d = _core.BaseDynamics(base._b, offset=base.offset)

    n = property(lambda self: self._d.n)
    np = property(lambda self: self._d.np)
    names = property(lambda self: self._d.names)
    counts = property(lambda self: self._d.counts)
    geometry_snap = property(lambda self: self._d.geometry_snap)

    @_args.finite_results("q", "dq", "ddq", "p")
    def inverse_dynamics(self, q, dq, ddq, p=None) -> ndarray:
        """tau, shape (n,) or (m, n) for batches of q, dq, ddq; ``p`` shape (np,), default the
        robot's own base-parameter values."""
        q, dq, ddq = _args.batch(self.n, q=q, dq=dq, ddq=ddq)
        return self._d.inverse_dynamics(q, dq, ddq, self._values(p))

    @_args.finite_results("q", "p")
    def gravity(self, q, p=None) -> ndarray:
        """Gravity torque, shape (n,) or (m, n)."""
        return self._d.gravity(_args.samples(q, "q", self.n), self._values(p))

    @_args.finite_results("q", "dq", "ddq")
    def regressor(self, q, dq, ddq) -> ndarray:
        """W_b, shape (n, np) or (m, n, np): ``tau = W_b @ p``."""
        q, dq, ddq = _args.batch(self.n, q=q, dq=dq, ddq=ddq)
        return self._d.regressor(q, dq, ddq)

    def _values(self, p):
        if p is None:
            rob = self.base.robot
            return self.base.values(
                rob.parameters(
                    rotor=self.base.rotor, friction=self.base.friction, offset=self.base.offset
                )
            )
        return _args.array(p, "p", (self.np,))

    def __repr__(self) -> str:
        return f"BaseDynamics(n={self.n}, np={self.np})"
