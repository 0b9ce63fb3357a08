"""The identification workflow of a floating-base robot (a free-flyer or planar root joint):
:func:`load_floating_logs` reads the fit and validation logs (CSV with contact wrenches,
:func:`~mindyn.identification.floating.read_floating_csv`), :func:`run_floating` fits the base
parameters (:func:`~mindyn.identification.floating.identify_floating`), scores the estimate on
the fit and validation logs and returns a :class:`FloatingReport` (its JSON document by
``to_dict()``, its terminal text by ``format()``). ``mindyn identify`` on a floating-base robot
is this workflow on the command line::

    robot = mindyn.load("robot.urdf", root_joint="floating")
    logs = load_floating_logs(["walk.csv"], robot, validate=["walk2.csv"])
    report = run_floating(robot, logs, model="full")
    print(report.format())
    doc = report.to_dict()

The error measures are those of the fixed-base workflow, on the generalized forces of the
model's equations (``S^T tau + sum_c J_c^T f_c``; the base-link model: the root's rows):
``overall_relative`` ``|F - F_hat| / |F|`` over all samples and coordinates (Frobenius norms),
``rms`` and ``relative`` per coordinate, ``rms_all`` the RMS over all of them. Coordinates are
named by :func:`coordinate_names`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import _args
from ..base import BaseParameters, base_parameters
from ..robot import Robot
from .data import DataError, check_distinct_logs
from .document import identified_robot_record, model_record
from .errors import IdentificationError
from .floating import (
    _FRAMES,
    _MODELS,
    FloatingLog,
    FloatingResult,
    _root_dofs,
    identify_floating,
    read_floating_csv,
)
from .options import check_cutoff
from .summary import nan_list, plain

__all__ = [
    "FloatingLogs",
    "FloatingReport",
    "coordinate_names",
    "load_floating_logs",
    "run_floating",
]

_ROOT_AXES = {6: ("fx", "fy", "fz", "tx", "ty", "tz"), 3: ("fx", "fy", "tz")}
_BAGS = (".bag", ".mcap", ".db3")
ESTIMATOR_WORDS = {
    True: "weighted least squares, per coordinate",
    False: "ordinary least squares",
}
MODEL_WORDS = {
    "full": "full model: joint torques and contact wrenches, every equation of motion",
    "base": "base-link model: the root's equations, contact wrenches and motion only",
}


def coordinate_names(robot: Robot) -> list[str]:
    """The names of the generalized forces of a floating-base robot, in the order of its
    velocity: the root joint's (``<root>.fx, .fy, .fz, .tx, .ty, .tz`` for a free-flyer, in the
    base's axes; ``<root>.fx, .fy, .tz`` for a planar root), then ``tau1..tau<na>``, the actuated
    coordinates as the log's columns name them."""
    _args.instance(robot, "robot", Robot)
    r = _root_dofs(robot)
    root = robot.joint_names[0]
    return [f"{root}.{a}" for a in _ROOT_AXES[r]] + [f"tau{i + 1}" for i in range(robot.nv - r)]


@dataclass(frozen=True)
class FloatingLogs:
    """The logs of a floating-base identification: ``fit`` and ``validation``
    (:class:`~mindyn.identification.floating.FloatingLog` each, in the order given; ``files``
    and ``validation_files`` their paths), their ``wrench_frame`` and the ``contacts`` declared
    (None: each log's wrench columns)."""

    fit: list[FloatingLog]
    validation: list[FloatingLog]
    files: list[str]
    validation_files: list[str]
    wrench_frame: str = "world"
    contacts: tuple[str, ...] | None = None


def _paths(paths, name: str, *, empty: bool = False) -> list[str]:
    if isinstance(paths, (str, Path)):
        paths = [paths]
    if not isinstance(paths, (list, tuple)) or (not paths and not empty):
        raise _args.fail(name, "is not a path or a non-empty list of paths")
    return [str(_args.path(p, name)) for p in paths]


def _read(path: str, robot: Robot, frame: str, contacts, derive: dict) -> FloatingLog:
    p = Path(path)
    if p.is_dir() or p.suffix.lower() in _BAGS:
        raise DataError(
            f"{path}: a floating-base log is a CSV file (q, dq, ddq, tau and wrench columns); "
            "ROS bags are read for fixed-base robots only"
        )
    log = read_floating_csv(p, robot, wrench_frame=frame, **derive)
    if contacts is not None:
        missing = [c for c in contacts if c not in log.wrenches]
        if missing:
            raise DataError(
                f"{path}:1: no wrench columns {missing[0]}.fx..{missing[0]}.tz for the contact "
                f"link {missing[0]!r}"
            )
        other = [c for c in log.wrenches if c not in contacts]
        if other:
            raise DataError(
                f"{path}:1: wrench columns of link {other[0]!r}, not a declared contact link "
                f"({', '.join(contacts)}): a measured wrench acts on the robot; declare it or "
                "remove its columns"
            )
    return log


def load_floating_logs(
    paths,
    robot: Robot,
    *,
    validate=(),
    wrench_frame: str = "world",
    contacts: Sequence[str] | None = None,
    filter: str = "butter",
    cutoff: float | None = None,
) -> FloatingLogs:
    """The fit logs ``paths`` and validation logs ``validate`` (CSV paths) of a floating-base
    robot, read by :func:`~mindyn.identification.floating.read_floating_csv` with
    ``wrench_frame`` (``"world"`` or ``"local"``), and ``filter`` and ``cutoff`` for a log
    without velocities or accelerations (derived from its configurations, each log alone).
    ``contacts``: the links in contact, each a moving link of the robot; every log must then
    carry the six wrench columns of each and of no other link (DataError naming the file).
    Default: the wrench columns each log has."""
    _args.instance(robot, "robot", Robot)
    fit = _paths(paths, "paths")
    val = _paths(validate, "validate", empty=True)
    check_distinct_logs(fit, val)
    frame = _args.choice(wrench_frame, "wrench_frame", _FRAMES)
    derive = dict(
        filter=_args.choice(filter, "filter", ("butter", "savgol", "none")),
        cutoff=_args.optional(_args.number, cutoff, "cutoff", positive=True),
    )
    check_cutoff(derive["filter"], derive["cutoff"])
    _root_dofs(robot)
    declared = None
    if contacts is not None:
        if isinstance(contacts, str) or not isinstance(contacts, (list, tuple)):
            raise _args.fail("contacts", "is not a list of link names")
        names = robot.link_names[1:]
        for c in contacts:
            _args.text(c, "contacts")
            if c not in names:
                raise _args.fail(
                    "contacts=:",
                    f"{c!r} is no moving link of robot '{robot.name}' ({', '.join(names)})"
                    + robot._fixed_link_hint(c),
                )
        declared = tuple(dict.fromkeys(contacts))
    return FloatingLogs(
        [_read(p, robot, frame, declared, derive) for p in fit],
        [_read(p, robot, frame, declared, derive) for p in val],
        fit,
        val,
        frame,
        declared,
    )


def _measures(result: FloatingResult, logs: list[FloatingLog], files: list[str]) -> dict:
    """The error measures of ``result`` on ``logs``: over all of them stacked and per log."""

    def measures(predicted: np.ndarray, measured: np.ndarray) -> dict:
        e = predicted - measured
        with np.errstate(divide="ignore", invalid="ignore"):
            overall = float(np.linalg.norm(e) / np.linalg.norm(measured))
            relative = np.linalg.norm(e, axis=0) / np.linalg.norm(measured, axis=0)
        return {
            "overall_relative": overall,
            "rms": np.sqrt(np.mean(e**2, axis=0)),
            "relative": relative,
            "rms_all": float(np.sqrt(np.mean(e**2))),
            "samples": len(e),
        }

    pairs = [result.forces(log) for log in logs]
    out = measures(np.vstack([p for p, _ in pairs]), np.vstack([m for _, m in pairs]))
    out["logs"] = [{"file": f, **measures(p, m)} for f, (p, m) in zip(files, pairs, strict=True)]
    return out


def _measures_doc(m: dict) -> dict:
    def one(x: dict) -> dict:
        return {
            "overall_relative": nan_list([x["overall_relative"]])[0],
            "rms_all": x["rms_all"],
            "rms": nan_list(x["rms"]),
            "relative": nan_list(x["relative"]),
            "samples": x["samples"],
        }

    return {**one(m), "logs": [{"file": x["file"], **one(x)} for x in m["logs"]]}


@dataclass(frozen=True, kw_only=True)
class FloatingReport:
    """What one floating-base identification found (:func:`run_floating`): the ``robot``, its
    ``logs``, the ``base`` set (the numerical method's), the ``result`` of the model fitted, the
    base-link model's fit on the same logs (``base_link``: the result itself for the base-link
    model, None in free flight), the error measures on the fit logs (``fit``) and on the
    validation logs (``validation``, None without them), the ``coordinates`` named."""

    robot: Robot
    logs: FloatingLogs
    base: BaseParameters
    result: FloatingResult
    base_link: FloatingResult | None
    fit: dict
    validation: dict | None
    coordinates: list[str]

    def base_link_difference(self) -> float | None:
        """The relative difference between the base-link model's values and the full model's on
        the combinations the base-link model identifies (None unless both were fitted)."""
        link = self.base_link
        if link is None or link is self.result:
            return None
        ref = link.span @ self.result.values
        return float(np.linalg.norm(link.span @ link.values - ref) / np.linalg.norm(ref))

    def to_dict(self) -> dict:
        """The JSON document of ``mindyn identify --json`` for a floating-base robot."""
        robot, res, logs = self.robot, self.result, self.logs
        contacts = sorted({c for log in logs.fit + logs.validation for c in log.wrenches})
        doc = {
            **identified_robot_record(robot),  # robot, joints, description
            "floating_base": True,
            "root_joint": {
                "name": robot.joint_names[0],
                "type": robot.joint_types[0],
                "coordinates": _root_dofs(robot),
            },
            "nq": robot.nq,
            "nv": robot.nv,
            "model": res.model,
            "estimator": ESTIMATOR_WORDS[res.weighted],
            "weighted": res.weighted,
            "weighting": res.weighting,
            "coordinate_sigma": (
                None if res.coordinate_sigma is None else nan_list(res.coordinate_sigma)
            ),
            "wrench_frame": logs.wrench_frame,
            "contacts": contacts,
            "base_method": self.base.method,
            "names": list(self.base.names),
            "values": [float(v) for v in res.values],
            # the regrouping and regressor columns of the base set: what a reader compares
            # (check_floating_identification)
            "model_check": model_record(self.base),
            "std": nan_list(res.std),
            "rank": res.rank,
            "n_base": self.base.n,
            "base_link_rank": None if self.base_link is None else self.base_link.rank,
            "base_link_difference": self.base_link_difference(),
            "sigma": nan_list([res.sigma])[0],
            "rows": res.rows,
            "coordinates": list(self.coordinates),
            "data": {
                "files": list(logs.files),
                "samples": sum(log.m for log in logs.fit),
                "logs": [
                    {
                        "file": f,
                        "samples": log.m,
                        "contacts": sorted(log.wrenches),
                        "derivatives": dict(log.processing),
                    }
                    for f, log in zip(
                        logs.files + logs.validation_files, logs.fit + logs.validation, strict=True
                    )
                ],
            },
            "fit": _measures_doc(self.fit),
        }
        if self.validation is not None:
            doc["validation"] = {
                "file": ", ".join(logs.validation_files),
                **_measures_doc(self.validation),
            }
        return plain(doc)

    def format(self) -> str:
        """The terminal text of ``mindyn identify`` for a floating-base robot."""
        robot, res, logs = self.robot, self.result, self.logs
        r = _root_dofs(robot)
        contacts = sorted({c for log in logs.fit for c in log.wrenches})
        axes = "world axes" if logs.wrench_frame == "world" else "each link's axes"
        out = [
            f"{robot.name}: floating-base identification, {MODEL_WORDS[res.model]} "
            f"({ESTIMATOR_WORDS[res.weighted]})",
            f"  root           {robot.joint_types[0]} joint '{robot.joint_names[0]}', {r} "
            f"unactuated coordinates; nq {robot.nq}, nv {robot.nv}, {robot.nv - r} joint torques",
            f"  data           {', '.join(logs.files)}: {sum(log.m for log in logs.fit)} samples, "
            f"{res.rows} equations; contact wrenches "
            + (f"on {', '.join(contacts)} ({axes})" if contacts else "none (free flight)"),
            f"  derivatives    {_derivative_words(logs)}",
            f"  base set       {self.base.n} base parameters ({self.base.method} method)",
            "  rank           "
            + (f"full model {res.rank} of {self.base.n}; " if res.model == "full" else "")
            + self._base_link_words(),
            f"  weighting      {res.weighting}",
        ]
        if res.coordinate_sigma is not None:
            noise = ", ".join(
                f"{c} {v:.3g}" for c, v in zip(self.coordinates, res.coordinate_sigma)
            )
            out.append(f"  noise sigma    {noise} (N, N m)")
        out.append("")
        out.append(f"{'#':>3}  {'parameter':<12}{'value':>14}{'std':>12}{'std %':>9}")
        for i, (name, v, sd) in enumerate(zip(self.base.names, res.values, res.std), 1):
            if np.isfinite(sd):
                pct = f"{100 * sd / abs(v):8.2f}" if abs(v) > sd else "    >100"
                out.append(f"{i:>3}  {name:<12}{v:14.6g}{sd:12.3g} {pct}")
            else:
                out.append(f"{i:>3}  {name:<12}{v:14.6g}  not identified alone (minimum norm)")
        out.append("")
        out += _measure_lines("identification data", self.fit, self.coordinates)
        if self.validation is not None:
            out += _measure_lines(
                f"validation data ({', '.join(logs.validation_files)})",
                self.validation,
                self.coordinates,
            )
        return "\n".join(out)

    def _base_link_words(self) -> str:
        link = self.base_link
        if link is None:
            return "base-link model: none (free flight: no contact wrench)"
        words = f"base-link model {link.rank} of {self.base.n}"
        if link.rank < self.base.n:
            words += " (it identifies combinations of the base values only)"
        diff = self.base_link_difference()
        if diff is not None:
            words += f", its values {diff:.2g} from the full model's (relative, on its span)"
        return words


def _derivative_words(logs: FloatingLogs) -> str:
    """How the logs' velocities and accelerations were obtained, in words."""
    words = []
    for f, log in zip(logs.files + logs.validation_files, logs.fit + logs.validation):
        p = log.processing
        if p.get("velocity") == "logged" and p.get("acceleration") == "logged":
            how = "dq and ddq logged"
        else:
            what = "dq and ddq" if p.get("velocity") != "logged" else "ddq"
            how = f"{what} derived ({p.get('filter', '?')}"
            if p.get("cutoff_Hz") is not None:
                how += f", cut-off {p['cutoff_Hz']:.3g} Hz"
            if p.get("window_s") is not None:
                how += f", window {p['window_s']:.3g} s"
            how += f"; {p.get('rate_Hz', float('nan')):.4g} Hz samples"
            how += f"; {p.get('edge_samples', 0)} samples dropped at each end)"
        words.append((f, how))
    if len({h for _, h in words}) == 1:
        return words[0][1] + ("" if len(words) == 1 else " in every log")
    return "; ".join(f"{f}: {h}" for f, h in words)


def _measure_lines(title: str, m: dict, coordinates: list[str]) -> list[str]:
    rms = " ".join(f"{c} {v:.3g}" for c, v in zip(coordinates, m["rms"]))
    return [
        f"{title}: overall relative error {m['overall_relative']:.4g}, RMS {m['rms_all']:.4g} "
        f"(N, N m) over {m['samples']} samples",
        f"  RMS per coordinate: {rms}",
    ]


def run_floating(
    robot: Robot,
    logs: FloatingLogs,
    *,
    model: str = "full",
    tolerance: float | None = None,
    weighted: bool = True,
) -> FloatingReport:
    """Identify the base parameters of a floating-base ``robot`` from ``logs``
    (:func:`load_floating_logs`) with ``model`` (``"full"`` or ``"base"``, as
    :func:`~mindyn.identification.floating.identify_floating`; ``tolerance`` its rank
    tolerance; ``weighted`` its weighted least squares, per coordinate, or ordinary ones with
    ``weighted=False``). With the full model and contact wrenches, the base-link model is fitted
    too (weighted alike), to state its rank and how far its values are from the full model's.
    The base set is the numerical method's (:func:`mindyn.base_parameters`)."""
    _args.instance(robot, "robot", Robot)
    _args.instance(logs, "logs", FloatingLogs)
    model = _args.choice(model, "model", _MODELS)
    _args.optional(_args.number, tolerance, "tolerance", positive=True, below=1.0)
    weighted = _args.flag(weighted, "weighted")
    _root_dofs(robot)
    if model == "full":
        files = logs.files + logs.validation_files
        missing = [f for f, log in zip(files, logs.fit + logs.validation) if log.tau is None]
        if missing:
            raise IdentificationError(
                f"{missing[0]}: no joint torque columns tau1..tau{robot.nv - _root_dofs(robot)}; "
                "the full model needs them (the base-link model, model='base', does not)"
            )
    base = base_parameters(robot, method="numerical")
    fit = dict(base=base, tolerance=tolerance, weighted=weighted)
    result = identify_floating(robot, logs.fit, model=model, **fit)
    link: FloatingResult | None = result if model == "base" else None
    if model == "full" and any(log.wrenches for log in logs.fit):
        link = identify_floating(robot, logs.fit, model="base", **fit)
    names = coordinate_names(robot)
    if model == "base":
        names = names[: _root_dofs(robot)]
    return FloatingReport(
        robot=robot,
        logs=logs,
        base=base,
        result=result,
        base_link=link,
        fit=_measures(result, logs.fit, logs.files),
        validation=(
            _measures(result, logs.validation, logs.validation_files) if logs.validation else None
        ),
        coordinates=names,
    )
