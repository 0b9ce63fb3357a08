"""Sensorless collision detection: the generalised-momentum observer (De Luca's residual) on the
base parameters of an identified or nominal model, and thresholds calibrated from data.

The residual, per joint,

    r(t) = K_O (p(t) - p(0) - int_0^t (tau - beta + r) ds),   p = A(q) dq = W_p,b p_b,
    beta = -dL/dq + tau_f + offset = W_l,b p_b + friction + offset,

(``-dL/dq = g - C^T dq``: ``tau - beta`` is De Luca's ``tau + C^T dq - g - tau_f``) obeys
``dr/dt = K_O (tau_ext - r)`` when the model is exact: ``r`` is the external torque through the
first-order filter ``K_O / (s + K_O)``, without accelerations.

Discretisation at the controller period ``T`` (C++ ``mindyn::MomentumObserver``, the generated
step alike): the integral advances by ``T tau_{k-1}`` (``held_torque``: the command held over the
period, exact for it) or by the trapezoid ``T/2 (tau_k + tau_{k-1})`` (a sampled, measured
torque), by ``-T/2 (beta_k + beta_{k-1})`` and by ``T/2 (r_k + r_{k-1})``, ``r_k`` solved from
its own implicit term. Then ``r_k = a r_{k-1} + c D_k`` with ``a = (1 - K_O T/2) / (1 + K_O
T/2)``, ``c = K_O / (1 + K_O T/2)`` and ``D_k`` the external-torque impulse of the period
(``T tau_ext`` for a held one): the bilinear (Tustin) image of ``K_O / (s + K_O)``, exact up to
the trapezoid's O(T^3) error on ``beta`` per period. Gains ``0 < K_O T < 2`` (``a > 0``: no
sign alternation); default ``K_O = 1 / (10 T)``, a time constant of ten periods. Where a
velocity reverses, the Coulomb term's sign switches within the period, which the trapezoid
integrates with an error of up to ``Fc T``: a spike of about ``K_O T Fc / 2`` in ``r``, which
calibrated thresholds take in and a lower ``K_O T`` keeps small.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import _args, _core
from ..base import BaseParameters
from ..robot import Robot
from .controllers import ControllerSettingError, check_period

__all__ = [
    "MomentumObserver",
    "ObserverThresholds",
    "ThresholdsError",
    "alarm_intervals",
    "calibrate_thresholds",
    "default_observer_gain",
    "load_thresholds",
    "residual_uncertainty",
    "score_alarms",
]


def default_observer_gain(period: float) -> float:
    """``K_O = 1 / (10 T)`` [1/s]: a time constant of ten periods ``T`` (a bandwidth of 1/31 of
    the Nyquist frequency)."""
    return float(_core.MomentumObserver.default_gain(check_period(period)))


class MomentumObserver:
    """Generalised-momentum residual of the model ``values`` of ``base`` (module docstring).

    Parameters
    ----------
    base : BaseParameters
        Its rotor, friction and offset settings decide the terms of the model.
    values : array (base.n,)
        Base-parameter values (offsets last, as ``base.names`` orders them).
    period : float
        Sample period ``T`` [s].
    gains : scalar or array (n,), optional
        ``K_O`` [1/s] per joint, each in ``(0, 2 / T)``; default :func:`default_observer_gain`.
    held_torque : bool
        The torque is the command held over each period (True) or a sampled measurement
        integrated by the trapezoid (False).

    The attributes ``values`` and ``gains`` are read-only copies of what the observer runs
    with: a later change of the arrays it was given does not change it.
    """

    def __init__(
        self, base: BaseParameters, values, *, period: float, gains=None, held_torque=True
    ):
        from ..identification.friction import DahlBase

        if isinstance(base, DahlBase):
            raise ControllerSettingError(
                "the momentum observer has no Dahl friction state: give it a base set of a "
                "static friction model"
            )
        _args.instance(base, "base", BaseParameters)
        n = base.robot.n
        self.base = base
        self.period = check_period(period)
        values = _args.array(values, "values", (None,))
        if values.shape != (base.n,):
            raise ControllerSettingError(
                f"values has {values.size} entries; the base parameters have {base.n}"
            )
        if gains is None:
            k = np.full(n, default_observer_gain(self.period))
        elif np.ndim(gains) == 0:
            k = np.full(n, _args.number(gains, "gains"))
        else:
            k = _args.array(gains, "gains", (n,))
        held_torque = _args.flag(held_torque, "held_torque")
        bad = np.flatnonzero(~((k > 0) & (k * self.period < 2)))
        if bad.size:
            j = int(bad[0])
            raise ControllerSettingError(
                f"observer gain K_O of joint {j + 1} is {k[j]:g} 1/s; expected 0 < K_O < 2 / T "
                f"= {2 / self.period:g} 1/s (K_O T >= 2 makes the discrete residual alternate)"
            )
        # the core keeps its own copies: the attributes are the observer's own, read-only
        # copies too, so that neither the caller's arrays nor an edit of them can part them
        # from the residual the core computes
        self.gains = _args.readonly(k)
        self.held_torque = bool(held_torque)
        self.values = _args.readonly(values)
        # the offsets are base parameters of the core's layout: in values, not a separate vector
        self._o = _core.MomentumObserver(
            base._b, values, k, self.period, np.zeros(n), held_torque=self.held_torque
        )

    def reset(self, q, dq, tau) -> None:
        """Sample 0: ``p(0)`` from ``(q, dq)``, the integral and ``r`` zero."""
        n = self.base.robot.n
        q, dq, tau = (_args.array(x, k, (n,)) for x, k in ((q, "q"), (dq, "dq"), (tau, "tau")))
        self._o.reset(q, dq, tau)

    @_args.finite_results("q", "dq", "tau")
    def step(self, q, dq, tau) -> np.ndarray:
        """The residual ``r_k`` (n,) of the next sample. Inputs so large that the residual
        overflows the double range are an ArgumentError (the observer then holds no finite
        state: :meth:`reset` it)."""
        n = self.base.robot.n
        q, dq, tau = (_args.array(x, k, (n,)) for x, k in ((q, "q"), (dq, "dq"), (tau, "tau")))
        return self._o.step(q, dq, tau)

    @_args.finite_results("q", "dq", "tau")
    def run(self, q, dq, tau, t=None) -> np.ndarray:
        """The residual (m, n) of a log: 0 at sample 0. Sampled at the period, or at the time
        stamps ``t`` (m,) when given (uneven steps; each must keep ``K_O dt < 2``). A log so
        large that the residual overflows the double range is an ArgumentError."""
        n = self.base.robot.n
        q = _args.array(q, "q", (None, n), unit="joint")
        if q.shape[0] < 1:
            raise _args.fail("q", f"has shape {q.shape}; expected a log of shape (m, {n}), m >= 1")
        m = q.shape[0]
        dq = _args.array(dq, "dq", (m, n), unit="joint")
        tau = _args.array(tau, "tau", (m, n), unit="joint")
        if t is not None:
            t = _args.array(t, "t", (m,))
            dt = np.diff(t)
            bad = np.flatnonzero(~(dt > 0))
            if bad.size:
                raise _args.fail("t", f"is not strictly increasing at sample {int(bad[0]) + 2}")
            kmax = float(self.gains.max())
            bad = np.flatnonzero(~(kmax * dt < 2.0))
            if bad.size:
                i = int(bad[0])
                raise _args.fail(
                    "t",
                    f"has a time step of {dt[i]:g} s at sample {i + 2}, which makes K_O dt >= 2 "
                    f"(largest K_O {kmax:g} 1/s); lower the gains below 2 / dt",
                )
        return self._o.run(q, dq, tau, t)

    @property
    def momentum(self) -> np.ndarray:
        """``p = W_p,b p_b`` of the last sample."""
        return _args.readonly(self._o.momentum)

    @property
    def beta(self) -> np.ndarray:
        """``beta = W_l,b p_b + friction + offset`` of the last sample."""
        return _args.readonly(self._o.beta)

    def filter_coefficients(self) -> tuple[np.ndarray, np.ndarray]:
        """``(a, c)`` per joint: ``r_k = a r_{k-1} + c D_k``."""
        h = 0.5 * self.gains * self.period
        return (1 - h) / (1 + h), self.gains / (1 + h)


# ---------------------------------------------------------------------------------------------
# Thresholds
# ---------------------------------------------------------------------------------------------
class ThresholdsError(_core.Error, ValueError):
    """A thresholds file that cannot be used (malformed, or made for another robot)."""


#: Default quantile of |r| over a collision-free log and the margin that multiplies it.
DEFAULT_QUANTILE = 1.0
DEFAULT_MARGIN = 1.5


@dataclass
class ObserverThresholds:
    """Per-joint thresholds on ``|r|`` and the observer they were calibrated for."""

    robot: str
    period: float
    gains: np.ndarray
    thresholds: np.ndarray
    quantile: float = DEFAULT_QUANTILE
    margin: float = DEFAULT_MARGIN
    info: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {
            "robot": self.robot,
            "period_s": self.period,
            "gains": self.gains.tolist(),
            "thresholds": self.thresholds.tolist(),
            "quantile": self.quantile,
            "margin": self.margin,
            **self.info,
        }

    def write(self, path) -> Path:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(self.to_dict(), indent=1) + "\n")
        return path


def calibrate_thresholds(
    residual, *, quantile: float = DEFAULT_QUANTILE, margin: float = DEFAULT_MARGIN
) -> np.ndarray:
    """Per-joint thresholds ``margin * quantile(|r_j|)`` from the residual (m, n) of a
    collision-free log (``quantile`` 1: the largest). A joint whose residual is zero throughout
    gets ``1e-9`` times the largest threshold (or 1e-12), never zero."""
    r = _args.array(residual, "residual", (None, None))
    if r.shape[0] < 2:
        raise _args.fail("residual", f"has {r.shape[0]} samples; expected at least 2")
    quantile = _args.number(quantile, "quantile", positive=True, maximum=1.0)
    margin = _args.number(margin, "margin", minimum=1.0)
    thr = margin * np.quantile(np.abs(r), quantile, axis=0)
    floor = max(1e-9 * float(thr.max()), 1e-12)
    return np.maximum(thr, floor)


@_args.finite_results("std", "q", "dq", "t")
def residual_uncertainty(observer: MomentumObserver, std, q, dq, t=None) -> np.ndarray:
    """The standard deviation (m, n) of the residual that the parameters' uncertainty alone
    explains along a motion: the residual is linear in the parameter values, so a value error
    ``dp`` adds the residual of ``dp`` with no torque; with independent errors of standard
    deviations ``std`` (base.n,) that is ``sqrt(sum_i std_i^2 r_i(t)^2)``, ``r_i`` the residual
    of the unit value of parameter i. (The identification's correlations are not taken: an
    estimate, not a bound.) Same period, gains and torque mode as ``observer``."""
    _args.instance(observer, "observer", MomentumObserver)
    base = observer.base
    std = _args.array(std, "std", (base.n,))
    if np.any(std < 0):
        raise _args.fail("std", "has a negative entry; expected standard deviations >= 0")
    q, dq = _args.batch(base.robot.n, q=q, dq=dq)
    if t is not None:
        t = _args.array(t, "t", (q.shape[0] if q.ndim == 2 else 1,))
    var = np.zeros(q.shape)
    zero = np.zeros(q.shape)
    for i in np.flatnonzero(std):
        unit = np.zeros(base.n)
        unit[i] = 1.0
        o = MomentumObserver(
            base,
            unit,
            period=observer.period,
            gains=observer.gains,
            held_torque=observer.held_torque,
        )
        var += (std[i] * o.run(q, dq, zero, t)) ** 2
    return np.sqrt(var)


def load_thresholds(path, robot) -> ObserverThresholds:
    """The thresholds file of ``mindyn detect`` for ``robot``; :class:`ThresholdsError` when it
    is not JSON, lacks a field, holds a non-number or was made for another robot."""
    _args.path(path, "path")
    _args.instance(robot, "robot", Robot)
    from ..identification.data import DataError, read_json

    where = str(path)
    if not Path(path).is_file():
        raise ThresholdsError(f"{where}: no such thresholds file")
    try:  # names the line and column; a file nested too deep or not UTF-8 too
        doc = read_json(path, what="thresholds file")
    except (OSError, DataError) as e:
        raise ThresholdsError(f"not a thresholds JSON file: {e}") from None
    if not isinstance(doc, dict):
        raise ThresholdsError(f"{where}: not a thresholds JSON file (not an object)")
    missing = [k for k in ("robot", "period_s", "gains", "thresholds") if k not in doc]
    if missing:
        raise ThresholdsError(f"{where}: lacks {', '.join(missing)} (not written by 'detect')")
    if doc["robot"] != robot.name:
        raise ThresholdsError(f"{where}: thresholds of robot '{doc['robot']}', not '{robot.name}'")
    n = robot.n

    def vector(key):
        v = doc[key]
        if not (isinstance(v, list) and len(v) == n):
            raise ThresholdsError(f"{where}: '{key}' must be a list of {n} numbers")
        if not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v):
            raise ThresholdsError(f"{where}: '{key}' must be a list of {n} numbers")
        a = np.array(v, dtype=float)
        if not np.all(np.isfinite(a) & (a > 0)):
            raise ThresholdsError(f"{where}: '{key}' must hold positive finite numbers")
        return a

    period = doc["period_s"]
    if not (isinstance(period, (int, float)) and math.isfinite(period) and period > 0):
        raise ThresholdsError(f"{where}: 'period_s' must be a positive number")
    info = {k: v for k, v in doc.items() if k not in ("robot", "period_s", "gains", "thresholds")}
    return ObserverThresholds(
        robot.name,
        float(period),
        vector("gains"),
        vector("thresholds"),
        float(doc.get("quantile", DEFAULT_QUANTILE)),
        float(doc.get("margin", DEFAULT_MARGIN)),
        {k: v for k, v in info.items() if k not in ("quantile", "margin")},
    )


def _records(value, name: str, keys: tuple[str, ...]) -> None:
    """``value`` is a list of dicts, each with the finite numbers ``keys``."""
    import numbers

    _args.instance(value, name, (list, tuple), f"a list of dicts with {', '.join(keys)}")
    for i, d in enumerate(value):
        bad = (
            keys
            if not isinstance(d, dict)
            else [
                k
                for k in keys
                if isinstance(d.get(k), bool)
                or not isinstance(d.get(k), numbers.Real)
                or not np.isfinite(d[k])
            ]
        )
        if bad:
            raise _args.fail(
                name,
                f"item {i} has no finite number '{bad[0]}'; expected dicts with " + ", ".join(keys),
            )


def score_alarms(alarms: list[dict], spans: list[dict], *, settle: float) -> dict:
    """The alarms of :func:`alarm_intervals` against the spans where an external torque is
    known to act (``start_s``, ``stop_s``, as a simulated log's truth sidecar gives them,
    :func:`~mindyn.control.simulation.external_spans`). An alarm starting within a span or up
    to ``settle`` [s] after its stop (the residual's decay, say 5 / K_O) belongs to it.
    Returns ``spans``: per span ``detected`` (bool), ``delay_s`` (its first alarm's start
    minus the span's start, None when not detected) and ``joints`` (1-based, in the order of
    their first alarm); ``false``: the alarms that belong to no span."""
    _records(alarms, "alarms", ("joint", "start"))
    _records(spans, "spans", ("start_s", "stop_s"))
    _args.number(settle, "settle", minimum=0.0)
    out, used = [], set()
    for s in spans:
        a, b = float(s["start_s"]), float(s["stop_s"]) + settle
        mine = [k for k, al in enumerate(alarms) if a <= al["start"] <= b]
        used.update(mine)
        joints: list[int] = []
        for k in mine:
            if alarms[k]["joint"] not in joints:
                joints.append(alarms[k]["joint"])
        out.append(
            {
                "detected": bool(mine),
                "delay_s": alarms[mine[0]]["start"] - a if mine else None,
                "joints": joints,
            }
        )
    return {"spans": out, "false": [al for k, al in enumerate(alarms) if k not in used]}


def alarm_intervals(t, residual, thresholds) -> list[dict]:
    """The intervals where ``|r_j| > threshold_j``: one dict per interval and joint, in time
    order, with ``joint`` (1-based), ``start``, ``end`` (time of its last sample above) and
    ``peak`` (the largest |r_j| in it, signed). ``t`` increases strictly and the thresholds
    are positive."""
    t = _args.array(t, "t", (None,))
    bad = np.flatnonzero(~(np.diff(t) > 0))
    if bad.size:
        raise _args.fail("t", f"is not strictly increasing at sample {int(bad[0]) + 2}")
    r = _args.array(residual, "residual", (t.shape[0], None))
    thr = _args.array(thresholds, "thresholds", (r.shape[1],))
    bad = np.flatnonzero(~(thr > 0))
    if bad.size:
        j = int(bad[0])
        raise _args.fail(
            "thresholds", f"has {thr[j]:g} for joint {j + 1}; expected positive values"
        )
    over = np.abs(r) > thr
    out = []
    for j in range(r.shape[1]):
        edges = np.diff(np.concatenate([[0], over[:, j].astype(np.int8), [0]]))
        for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True):
            k = a + int(np.argmax(np.abs(r[a:b, j])))
            out.append(
                {"joint": j + 1, "start": float(t[a]), "end": float(t[b - 1]), "peak": r[k, j]}
            )
    out.sort(key=lambda d: (d["start"], d["joint"]))
    return out
