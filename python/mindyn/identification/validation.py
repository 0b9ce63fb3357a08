"""Validation of an identification: torque prediction on other data, and the base values of a
known truth."""

from __future__ import annotations

import numpy as np

from ..base import BaseParameters
from .data import DataError, JointData
from .estimation import IdentificationResult
from .models import require_torque


def validate(result: IdentificationResult, data: JointData) -> dict:
    """Torque prediction on ``data``: per joint ``rms`` [N m | N] of ``tau - tau_hat`` and
    ``relative`` error ``|tau - tau_hat| / |tau|`` (fractions), plus the predicted torques
    ``tau_hat`` (m, n)."""
    require_torque(data)
    if data.n != result.base.robot.n:
        raise DataError(
            f"{data.source or 'data'} has {data.n} joints; expected {result.base.robot.n}"
        )
    pred = result.predict(data)
    err = data.tau - pred
    rms = np.sqrt(np.mean(err**2, axis=0))
    norm = np.linalg.norm(data.tau, axis=0)
    rel = np.where(norm > 0, np.linalg.norm(err, axis=0) / np.where(norm > 0, norm, 1), np.nan)
    return {"rms": rms, "relative": rel, "tau_hat": pred, "source": data.source}


def true_base_values(base: BaseParameters, truth: dict) -> np.ndarray:
    """Base-parameter values of a truth sidecar (classical names/values, any layout) in the layout
    of ``base``; classical parameters absent from the truth count as zero."""
    lookup = dict(zip(truth["names"], truth["values"]))
    pi = np.array([float(lookup.get(nm, 0.0)) for nm in base.classical_names])
    return base.values(pi)
