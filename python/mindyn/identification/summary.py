"""The result of the identification workflow (:func:`~mindyn.identification.workflow.run`):
:class:`IdentificationReport`, each quantity computed once, and its JSON document
(``to_dict()``, what ``mindyn identify --json`` writes)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from ..base import BaseParameters
    from ..robot import Robot
    from .consistent import ConsistentResult
    from .estimation import IdentificationResult
    from .friction import FrictionChoice
    from .reading import Logs


def plain(d):
    """``d`` with numpy scalars as Python numbers and non-finite floats as None (for JSON)."""
    if isinstance(d, dict):
        return {k: plain(v) for k, v in d.items()}
    if isinstance(d, (list, tuple)):
        return [plain(v) for v in d]
    if isinstance(d, (np.floating, float)):
        return float(d) if math.isfinite(d) else None
    if isinstance(d, np.integer):
        return int(d)
    return d


def nan_list(a) -> list:
    return [float(x) if math.isfinite(x) else None for x in a]


def measures_doc(v: dict, files: list) -> dict:
    """The error measures of :func:`~mindyn.identification.validate` for the JSON: fractions
    (relative, NRMS) and N m (RMS), over all logs stacked and per log."""

    def base(m):
        return {
            "overall_relative": nan_list([m["overall_relative"]])[0],
            "rms": nan_list(m["rms"]),
            "relative": nan_list(m["relative"]),
            "nrms": nan_list(m["nrms"]),
            "nrms_missing_limit": m["nrms_missing"],
        }

    def one(m):
        out = base(m)
        raw, mov = m.get("raw"), m.get("moving")
        out["raw"] = None if raw is None else {**base(raw), "samples": raw["samples"]}
        if raw is not None:
            out["raw"]["against"] = raw["against"]
        out["moving"] = (
            None
            if mov is None
            else {
                **base(mov),
                "samples": mov["samples"],
                "threshold": nan_list(mov["threshold"]),
                "rule": mov["rule"],
                "fraction": nan_list(mov["fraction"]),
            }
        )
        return out

    out = one(v)
    out["samples"] = v["samples"]
    out["logs"] = [{"file": f, "samples": m["samples"], **one(m)} for f, m in zip(files, v["logs"])]
    return out


def segments(ds) -> dict:
    """A log cut at its breaks: segment count, shortest and longest [s], each one's span."""
    spans = [d.processing["segment"]["t_s"] for d in ds]
    length = [b - a for a, b in spans]
    return {
        "count": len(ds),
        "shortest_s": min(length),
        "longest_s": max(length),
        "spans_s": spans,
    }


@dataclass(frozen=True, kw_only=True)
class IdentificationReport:
    """What one identification found (:func:`~mindyn.identification.workflow.run`).

    ``robot``: the robot identified (with the friction model chosen); ``options``: the
    :class:`~mindyn.identification.workflow.IdentifyOptions`; ``logs``: the
    :class:`~mindyn.identification.reading.Logs`; ``base``: the base set; ``result``: the
    unconstrained least-squares fit; ``friction``: the friction choice (None: the robot's own
    model); ``consistent``: the physically consistent estimate (None unless asked for);
    ``fit``, ``validation``: the error measures of the unconstrained estimate on the fit and
    validation logs (:func:`~mindyn.identification.validate`; validation None without
    validation logs), ``consistent_fit``, ``consistent_validation`` those of the consistent
    estimate; ``mass_matrix_min_eig``: the smallest eigenvalue of the consistent model's mass
    matrix over the fit logs; ``truth``: the true base values when the logs are simulated;
    ``truth_side``: the drive side of a simulation whose true values cannot be compared;
    ``tip``: the chain identified."""

    robot: Robot
    options: Any
    logs: Logs
    base: BaseParameters
    result: IdentificationResult
    friction: FrictionChoice | None
    consistent: ConsistentResult | None
    fit: dict
    validation: dict | None
    consistent_fit: dict | None
    consistent_validation: dict | None
    mass_matrix_min_eig: float | None
    truth: np.ndarray | None
    truth_side: str | None
    tip: str | None = None

    @property
    def friction_record(self) -> dict | None:
        """The friction model and how it was chosen (None without friction)."""
        if not self.base.friction:
            return None
        from .friction import friction_record

        return friction_record(self.robot, record=self.friction.record if self.friction else None)

    def format(self) -> str:
        """The terminal text of ``mindyn identify``."""
        from .terminal import format_identification

        return format_identification(self)

    def to_dict(self) -> dict:
        """The JSON document of ``mindyn identify --json``."""
        cons, logs = self.consistent, self.logs
        fit, val = logs.fit, logs.validation
        data = fit.logs
        doc = self.result.to_dict()
        if self.base.friction:
            doc["friction_model"] = self.friction_record
        doc["tip"] = self.tip  # the chain identified (None: the whole description)
        doc["consistent"] = cons is not None
        if cons is not None:
            doc.update(plain(cons.to_dict()))
            ce = doc["consistent_estimate"]
            ce["fit"] = {"estimate": "consistent", **measures_doc(self.consistent_fit, fit.labels)}
            if self.consistent_validation is not None:
                ce["validation"] = {
                    "estimate": "consistent",
                    "file": ", ".join(val.files),
                    **measures_doc(self.consistent_validation, val.labels),
                }
            ce["mass_matrix_min_eig"] = self.mass_matrix_min_eig
        doc["reading"] = logs.record()
        doc["data"] = {
            "file": fit.files[0] if len(fit.files) == 1 else None,
            "files": list(fit.files),
            "samples": sum(int(d.processing.get("samples", d.m)) for d in data),  # as logged
            "samples_used": sum(d.m for d in data),  # after resampling, edges and decimation
            "processing": plain(data[0].processing),
            "logs": [
                {
                    "file": f,
                    "samples": int(d.processing.get("samples", d.m)),
                    "samples_used": d.m,
                    "processing": plain(d.processing),
                }
                for f, d in zip(fit.labels, data)
            ],
        }
        doc["data"]["segments"] = [
            {"file": f, **segments(ds)}
            for f, ds in zip(fit.files + val.files, fit.parts + val.parts)
            if len(ds) > 1
        ]
        doc["fit"] = measures_doc(self.fit, fit.labels)
        if self.validation is not None:
            doc["validation"] = {
                "file": ", ".join(val.files),
                **measures_doc(self.validation, val.labels),
            }
        if cons is not None:  # which estimate each set of figures is
            for key in ("fit", "validation"):
                if key in doc:
                    doc[key] = {"estimate": "unconstrained least squares", **doc[key]}
        if self.truth is not None:
            doc["true_values"] = [float(v) for v in self.truth]
        return doc
