"""Regression systems of the identification models, over the equations-of-motion base set of
:func:`mindyn.base_parameters`.

``dynamic``
    ``W_b(q_i, dq_i, ddq_i) p_b = tau_i`` for every sample ``i``, stacked (``m n`` rows).
``energy``
    The integral form of the energy theorem over consecutive windows ``[t_a, t_b]`` of
    ``window`` samples: ``(w_H(t_b) - w_H(t_a)) p_b + Fv_k int dq_k^2 dt + Fc_k int |dq_k| dt
    = int dq^T tau dt``; no accelerations are needed. The dissipated-energy columns of the
    friction parameters replace their (zero) energy columns; the integrals use the trapezoid or
    Simpson rule on the samples.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import integrate

from ..base import BaseParameters
from .data import DataError, JointData
from .errors import IdentificationError

MODELS = ("dynamic", "energy")


# ---------------------------------------------------------------------------------------------
def dynamic_system(base: BaseParameters, data: JointData, min_velocity: float = 0.0):
    """Stacked dynamic model: ``W`` (r, nb), ``y`` (r,) and the joint of each row (r,).

    With ``min_velocity > 0`` and Coulomb friction in the model, the equation of joint ``j`` at a
    sample where ``|dq_j| < min_velocity`` is left out: there the sign of the velocity, and so
    the Coulomb term, is not determined by the data (a torque held over a sample period, stiction,
    velocity noise). ``r = m n`` minus those equations."""
    require_torque(data)
    W = base.regressor(data.q, data.dq, data.ddq)  # (m, n, nb)
    m, n, nb = W.shape
    W, y, joint = W.reshape(m * n, nb), data.tau.reshape(m * n), np.tile(np.arange(n), m)
    if min_velocity > 0 and base.friction:
        keep = np.abs(data.dq).reshape(m * n) >= min_velocity
        W, y, joint = W[keep], y[keep], joint[keep]
    return W, y, joint


def _cumulative(f: np.ndarray, t: np.ndarray, rule: str) -> np.ndarray:
    """Cumulative integral of the samples ``f`` (m, ...) over ``t`` (m,), starting at 0."""
    if rule == "trapezoid":
        return integrate.cumulative_trapezoid(f, t, axis=0, initial=0)
    if rule == "simpson":
        if hasattr(integrate, "cumulative_simpson"):
            return integrate.cumulative_simpson(f, x=t, axis=0, initial=0)
        raise ValueError("Simpson integration needs scipy >= 1.12; use trapezoid")
    raise ValueError(f"unknown integration rule '{rule}'; use trapezoid or simpson")


def energy_system(
    base: BaseParameters, data: JointData, window: int = 1, integration: str = "simpson"
):
    """Energy model over non-overlapping windows of ``window`` sample intervals:
    ``W`` (r, nb) and ``y`` (r,), ``r = (m - 1) // window``."""
    require_torque(data)
    if window < 1:
        raise ValueError(f"energy window must be at least 1 sample interval, got {window}")
    t, dq = data.t, data.dq
    ends = np.arange(0, data.m, window)
    if ends.size < 2:
        raise IdentificationError(
            f"{data.m} samples give no complete energy window of {window} intervals"
        )
    W = np.diff(base.energy_regressor(data.q[ends], dq[ends]), axis=0)  # only at window ends
    power = np.einsum("ij,ij->i", dq, data.tau)
    if integration == "zoh":
        # Torque held over each sample interval: int dq^T tau dt = sum tau_k^T (q_k+1 - q_k).
        power_int = np.concatenate(
            [[0.0], np.cumsum(np.einsum("ij,ij->i", np.diff(data.q, axis=0), data.tau[:-1]))]
        )
        integration_f = "simpson"
    else:
        power_int = None
        integration_f = integration
    names = base.names
    cols = {}
    for k in range(data.n):
        for kind, f in (("Fv", dq[:, k] ** 2), ("Fc", np.abs(dq[:, k]))):
            name = f"{kind}{k + 1}"
            if name in names:
                cols[names.index(name)] = f
    F = np.column_stack([power] + list(cols.values())) if cols else power[:, None]
    cum = _cumulative(F, t, integration_f)
    if power_int is not None:
        cum[:, 0] = power_int
    dI = np.diff(cum[ends], axis=0)
    y = dI[:, 0]
    for j, c in enumerate(cols):
        W[:, c] = dI[:, j + 1]
    return W, y


def torque_noise(tau: np.ndarray) -> np.ndarray:
    """Per-joint standard deviation of white noise on sampled torques, shape (n,), estimated
    from second differences (robust: median absolute deviation); the smooth part of a torque
    sampled much faster than it changes hardly contributes."""
    d2 = np.diff(tau, n=2, axis=0)
    mad = np.median(np.abs(d2 - np.median(d2, axis=0)), axis=0)
    return 1.4826 * mad / math.sqrt(6.0)


def energy_row_noise(data: JointData, window: int) -> np.ndarray:
    """Per window and joint, ``sum_k (c_k dq_jk)^2`` with trapezoid weights ``c_k``: the
    variance of the window's power integral per unit torque-noise variance of joint ``j``;
    shape (rows, n). A row's noise variance is ``A @ sigma^2``."""
    dt = np.diff(data.t)
    c = np.zeros(data.m)
    ends = np.arange(0, data.m, window)
    rows = []
    for a, b in zip(ends[:-1], ends[1:]):
        c = np.zeros(b - a + 1)
        c[:-1] += 0.5 * dt[a:b]
        c[1:] += 0.5 * dt[a:b]
        rows.append(np.sum((c[:, None] * data.dq[a : b + 1]) ** 2, axis=0))
    return np.array(rows)


def require_torque(data: JointData) -> None:
    if data.tau is None:
        raise DataError(f"{data.source or 'data'}: no torque columns tau1..tau{data.n}")
