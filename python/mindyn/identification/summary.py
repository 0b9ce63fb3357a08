"""The result of the identification workflow (:func:`~mindyn.identification.workflow.run`):
:class:`IdentificationReport`, each quantity computed once, and its JSON document
(``to_dict()``, what ``mindyn identify --json`` writes)."""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from ..base import BaseParameters
    from ..robot import Robot
    from .consistent import ConsistentResult
    from .estimation import IdentificationResult
    from .friction import FrictionChoice
    from .options import IdentifyOptions
    from .reading import Logs


def plain(d):
    """``d`` with numpy scalars as Python numbers, non-finite floats as None, mappings (a
    read-only view too) as dicts and tuples as lists (for JSON)."""
    if isinstance(d, Mapping):
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
    (relative, NRMS) and N m (RMS), over all logs stacked and per log; beside them, for the
    unconstrained estimate, ``prediction_uncertainty``
    (:func:`~mindyn.identification.validation.uncertainty_measures`: ``overall_relative``,
    ``rms``, ``relative``), on the fit with the check of
    :func:`~mindyn.identification.validation.prediction_check` (``share``, ``mean_share``,
    ``reference``, ``excess``, ``threshold``, ``relative_threshold``, ``joints``, ``warning``,
    ``rule``)."""

    def base(m):
        return {
            "overall_relative": nan_list([m["overall_relative"]])[0],
            "rms": nan_list(m["rms"]),
            "relative": nan_list(m["relative"]),
            "nrms": nan_list(m["nrms"]),
            "nrms_missing_limit": m["nrms_missing"],
        }

    def uncertainty(u):
        out = {
            "overall_relative": nan_list([u["overall_relative"]])[0],
            "rms": nan_list(u["rms"]),
            "relative": nan_list(u["relative"]),
        }
        if "share" in u:  # the fit's check (prediction_check)
            out.update(
                share=nan_list(u["share"]),
                **plain(
                    {
                        k: u[k]
                        for k in (
                            "mean_share",
                            "reference",
                            "excess",
                            "threshold",
                            "relative_threshold",
                            "joints",
                            "warning",
                            "rule",
                        )
                    }
                ),
            )
        return out

    def one(m):
        out = base(m)
        if "prediction_uncertainty" in m:
            out["prediction_uncertainty"] = uncertainty(m["prediction_uncertainty"])
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


@dataclass(frozen=True, kw_only=True)
class IdentificationReport:
    """What one identification found (:func:`~mindyn.identification.workflow.run`), each
    quantity computed once.

    ``robot``: the robot identified (with the friction model chosen); ``options``: the
    :class:`~mindyn.identification.options.IdentifyOptions`; ``logs``: the
    :class:`~mindyn.identification.reading.Logs`; ``base``: the base set; ``result``: the
    unconstrained least-squares fit (``result_doc`` its JSON fields); ``friction``: the friction
    choice (None: the robot's own model), ``friction_record`` and ``friction_lines`` the friction
    model and how it was chosen, for the JSON and the text (None and empty without friction), with
    whether the fitted friction is dissipative (``not_dissipative``: model -> why, and ``warning``,
    one line or None; :func:`~mindyn.identification.friction.dissipation_check`); ``consistent``:
    the physically consistent estimate (None unless asked for; ``consistent_doc`` its JSON fields);
    ``fit``, ``validation``: the error measures of the unconstrained estimate on the fit and
    validation logs (:func:`~mindyn.identification.validate`; validation None without validation
    logs), ``consistent_fit``, ``consistent_validation`` those of the consistent estimate;
    ``mass_matrix_min_eig``: the smallest eigenvalue of the consistent model's mass matrix over the
    fit logs; ``truth``: the true base values when the logs are simulated; ``truth_side``: the drive
    side of a simulation whose true values cannot be compared; ``truth_frames``: why a simulation's
    true values, about other link frames, are not compared; ``tip``: the chain identified."""

    robot: Robot
    options: IdentifyOptions
    logs: Logs
    base: BaseParameters
    result: IdentificationResult
    result_doc: dict
    friction: FrictionChoice | None
    friction_record: dict | None
    friction_lines: list[str]
    consistent: ConsistentResult | None
    consistent_doc: dict | None
    fit: dict
    validation: dict | None
    consistent_fit: dict | None
    consistent_validation: dict | None
    mass_matrix_min_eig: float | None
    truth: np.ndarray | None
    truth_side: str | None
    tip: str | None = None
    truth_frames: str | None = None

    def format(self) -> str:
        """The terminal text of ``mindyn identify``."""
        from .terminal import format_identification

        return format_identification(self)

    def to_dict(self) -> dict:
        """The JSON document of ``mindyn identify --json``: a new document at each call, which
        the caller may change without changing the report or a later ``to_dict()``."""
        cons, logs = self.consistent_doc, self.logs
        fit, val = logs.fit, logs.validation
        doc = dict(self.result_doc)
        if self.friction_record is not None:
            doc["friction_model"] = self.friction_record
        doc["tip"] = self.tip  # the chain identified (None: the whole description)
        doc["base_snap"] = {**plain(self.base.snap_decision), "snapped": list(self.base.snapped)}
        doc["consistent"] = cons is not None
        if cons is not None:
            assert self.consistent_fit is not None  # computed with the consistent estimate
            doc.update(plain(cons))
            ce = doc["consistent_estimate"]
            ce["fit"] = {"estimate": "consistent", **measures_doc(self.consistent_fit, fit.labels)}
            if self.consistent_validation is not None:
                ce["validation"] = {
                    "estimate": "consistent",
                    "file": ", ".join(val.files),
                    **measures_doc(self.consistent_validation, val.labels),
                }
            ce["mass_matrix_min_eig"] = self.mass_matrix_min_eig
        doc["reading"] = None if logs.record is None else dict(logs.record)
        doc["data"] = {
            "file": fit.files[0] if len(fit.files) == 1 else None,
            "files": list(fit.files),
            "samples": sum(fit.logged),  # as logged
            "samples_used": sum(fit.samples),  # after resampling, edges and decimation
            "processing": plain(fit.logs[0].processing),
            "logs": [
                {
                    "file": f,
                    "samples": logged,
                    "samples_used": m,
                    "processing": plain(d.processing),
                }
                for f, d, m, logged in zip(fit.labels, fit.logs, fit.samples, fit.logged)
            ],
        }
        doc["data"]["segments"] = [
            {"file": f, **seg}
            for f, seg in zip(fit.files + val.files, fit.segments + val.segments)
            if seg is not None
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
        # the fit's, friction's and reading's records are the report's own: a copy, so that an
        # edit of the document never reaches them (nor the next document)
        return copy.deepcopy(doc)
