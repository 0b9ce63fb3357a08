"""The type of a joint-space log, :class:`JointData`: the samples every identification step
reads (time stamps, positions, velocities, accelerations, torques) and how they were obtained.
Reading and writing logs is :mod:`mindyn.identification.data`'s."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

__all__ = ["JointData", "RegressorFilter"]


class RegressorFilter(Protocol):
    """What :attr:`JointData.regressor_filter` provides: the regressor columns of a base-parameter
    set filtered like the torques, shape (m, n, nb); any columns ``fn(q, dq, ddq)`` of the
    motion ((k, w) for k samples) filtered alike, shape (m, w)."""

    def regressor(self, base: Any) -> np.ndarray: ...

    def signals(self, fn: Any) -> np.ndarray: ...


@dataclass
class JointData:
    """Samples of a joint-space log.

    Attributes
    ----------
    t : ndarray, shape (m,)
    q, dq, ddq : ndarray, shape (m, n)
    tau : ndarray, shape (m, n), or None for a trajectory without torques
    source : str
        Where the data came from (file name).
    processing : dict
        How ``dq`` / ``ddq`` were obtained (``logged`` or the filter and its settings) and the
        torque unit conversion.
    regressor_filter : optional
        Set by :func:`~mindyn.identification.preprocess.preprocess`: the low-pass, edge drop and
        decimation that turned the logged torques into ``tau``, to be applied alike to the
        regressor columns (parallel filtering); its ``regressor(base)`` gives them, shape
        (m, n, nb).
    logged : JointData, optional
        Set by :func:`~mindyn.identification.preprocess.preprocess`: the samples as logged (time
        stamps and torques as read, between the dropped filter edges) with the filtered motion
        at those stamps, on which the model's torques are compared with the logged ones
        (:func:`~mindyn.identification.validate`, ``raw`` and ``moving``), and its
        ``processing["velocity_noise"]`` (see :func:`~mindyn.identification.preprocess.preprocess`).
    starts : tuple of int
        Set by :func:`~mindyn.identification.preprocess.concatenate`: the first sample of each
        log joined (0 first); empty for a log not joined. The windows of the integral and
        energy models and the noise estimates from second differences do not span the junction
        between two logs (:meth:`log_slices`).
    units_checked : bool
        Whether its units have been checked (:func:`~mindyn.identification.data.check_units`:
        time stamps in s, positions in rad (m), velocities the positions' derivative, torques
        in N m of the description's sign). The
        readers (:func:`~mindyn.identification.data.read_csv` given the robot, ROS bags,
        :func:`~mindyn.identification.load_logs`) check and set it; a log built in Python is
        checked once, when it first reaches identification (:func:`~mindyn.identification.identify`,
        :func:`~mindyn.identification.run`, ...), which then sets it. Give ``True`` for a log
        whose units are right but which a check refuses (a log slower than 2 Hz, its stamps
        in s).
    """

    t: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    ddq: np.ndarray
    tau: np.ndarray | None = None
    source: str = ""
    processing: dict = field(default_factory=dict)
    regressor_filter: RegressorFilter | None = None
    logged: JointData | None = None
    starts: tuple[int, ...] = ()
    units_checked: bool = False

    @property
    def m(self) -> int:
        return self.t.shape[0]

    @property
    def n(self) -> int:
        return self.q.shape[1]

    @property
    def rate(self) -> float:
        """Mean sampling rate [Hz]."""
        return (self.m - 1) / (self.t[-1] - self.t[0]) if self.m > 1 else float("nan")

    def evaluate(self, t):
        """Reference interface (as
        :class:`~mindyn.identification.excitation.FourierTrajectory`): positions, velocities,
        accelerations at times ``t`` counted from the first sample, by cubic-spline
        interpolation, (m, n) each."""
        from scipy.interpolate import CubicSpline

        if not hasattr(self, "_splines"):
            self._splines = tuple(
                CubicSpline(self.t, x, axis=0) for x in (self.q, self.dq, self.ddq)
            )
        t = np.atleast_1d(np.asarray(t, dtype=float)) + self.t[0]
        t = np.clip(t, self.t[0], self.t[-1])
        return tuple(s(t) for s in self._splines)

    def log_slices(self) -> list[slice]:
        """The samples of each log joined into this one (:attr:`starts`), in order; one slice
        of every sample for a log not joined."""
        bounds = [s for s in self.starts if 0 < s < self.m]
        return [slice(a, b) for a, b in zip([0] + bounds, bounds + [self.m])]

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0])
