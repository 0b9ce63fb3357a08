"""Reading the logs of an identification: how a log is read (:class:`ReadingOptions`), one log
read and pre-processed (:func:`read_log`), and the fit and validation logs of one
identification together (:func:`load_logs`, :class:`Logs`), with the rule that validation logs
are filtered at the fit's cut-off."""

from __future__ import annotations

import copy
from collections.abc import Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field, fields
from os import PathLike
from pathlib import Path

import numpy as np

from .. import _args
from ..robot import as_robot
from .data import DataError, check_distinct_logs
from .joint_data import JointData
from .options import MODELS, ReadingOptions


@contextmanager
def _named_filter_error(path, opts: ReadingOptions):
    """A filter that cannot be designed at the cut-off, named as such."""
    try:
        yield
    except np.linalg.LinAlgError as e:
        if opts.filter not in ("butter", "lowpass"):
            raise
        raise DataError(
            f"cutoff={opts.cutoff:g} Hz: the zero-phase Butterworth filter "
            f"of {path} is singular at this cutoff ({e}); expected a cutoff of at least 1e-4 of "
            "half the log's sample rate"
            if opts.cutoff is not None
            else f"{path}: the Butterworth filter for the derivatives is singular ({e})"
        ) from None


def _gains(opts: ReadingOptions, n: int) -> np.ndarray | None:
    """The drive gains for ``n`` joints (one value given: the same for all), or None."""
    if opts.drive_gain is None:
        return None
    g = list(opts.drive_gain)
    if len(g) == 1:
        g *= n
    if len(g) != n:
        raise DataError(f"drive_gain= needs {n} values (or one for all), got {len(g)}")
    return np.array(g)


def _read_bag(path, robot, opts: ReadingOptions, unit, gain) -> JointData:
    from .rosbag import read_rosbag

    # effort in A (unit current): the gains (given or of the drive table) turn it into N m
    return read_rosbag(
        path,
        robot,
        topic=opts.topic,
        torque_unit=unit or "Nm",
        drive_gain=gain if unit == "current" else None,
        filter="none" if opts.filter == "lowpass" else opts.filter,
        cutoff=opts.cutoff,
    )


def _raw(
    paths,
    robot,
    opts: ReadingOptions,
    currents,
    require_torque,
    truth=None,
    because=None,
    sampled=None,
) -> list:
    """The logs at ``paths`` as read (CSV or ROS bag; torques from the ``currents`` file of
    each when given), by stages: which are bags, then (after the truth sidecars, when a list
    ``truth`` is given to fill) the reads, then the currents joined."""
    from .data import read_csv, read_truth, refuse_unused_gain
    from .rosbag import is_rosbag

    gain = _gains(opts, robot.n)
    bags = [is_rosbag(p) for p in paths]
    cmap = opts.columns
    if cmap is not None and any(bags):
        raise _args.fail("columns=", "applies to CSV logs; a ROS bag's joints are matched by name")
    if cmap is not None and any(currents) and "i" not in cmap.entries:
        raise _args.fail(
            "columns=",
            "has no i: a currents file is read through the map's t and i (the log through the "
            "others)",
        )
    if opts.topic is not None and not any(bags):
        raise _args.fail("topic=", "applies to ROS bags; none of the logs is one")
    if opts.torque_unit is not None and all(c is not None for c in currents):
        raise _args.fail(
            "torque_unit=", "does not apply: every log's torques come from its currents file"
        )
    for p, bag in zip(paths, bags):
        if Path(p).is_dir() and not bag:
            raise DataError(f"'{p}' is a folder but not a ROS 2 bag (it has no metadata.yaml)")
    if truth is not None:  # a log simulated for another robot is refused before any is read
        truth += [read_truth(p, robot) for p in paths]
    out = []
    for p, bag, cur in zip(paths, bags, currents):
        unit = None if cur else opts.torque_unit
        with _named_filter_error(p, opts):
            out.append(
                _read_bag(p, robot, opts, unit, gain)
                if bag
                else read_csv(
                    p,
                    robot=robot,
                    torque_unit=unit,
                    require_torque=not cur and require_torque,
                    filter="none" if opts.filter == "lowpass" else opts.filter,
                    cutoff=opts.cutoff,
                    drive_gain=None if cur else gain,  # a currents file's, not the log's
                    columns=cmap if cmap is None or not cur else cmap.without("i"),
                )
            )
    if any(currents):
        from .currents import attach_currents

        out = [
            d if c is None else attach_currents(d, c, robot, drive_gain=gain, columns=cmap)
            for d, c in zip(out, currents)
        ]
    for p, d in zip(paths, out):  # a log without torques (require_torque=False) passes
        remedy = "torque_unit='current', columns i1..in or currents="
        refuse_unused_gain(gain, p, d.processing.get("torque"), remedy)
    # ``because`` (torque not given): per log, why it is read as held (None: sampled)
    reasons = because if because is not None else [None] * len(out)
    if opts.torque == "held" or because is not None:
        out = [
            _held(d, b) if opts.torque == "held" or b is not None else d
            for d, b in zip(out, reasons)
        ]
    # ``sampled``: per log read as sampled, why, where its truth sidecar has a say (or None)
    for d, s in zip(out, sampled or []):
        if s is not None and d.tau is not None and "held" not in d.processing.get("torque", {}):
            d.processing["torque"] = {**d.processing.get("torque", {}), "sampled_because": s}
    return out


def _held(d, because: str | None = None):
    """Log ``d`` with its torques, held over each sample period, taken at the samples
    (:func:`~mindyn.identification.data.held_torque_at_samples`), as ``processing`` says (with
    ``because``: why they were read so, when not asked for)."""
    from .data import held_torque_at_samples

    if d.tau is None:
        return d
    d.tau = held_torque_at_samples(d.t, d.tau)
    d.processing["torque"] = {
        **d.processing.get("torque", {}),
        "held": "the command held over each sample period, taken at the samples: the "
        "interpolation between the middles of the periods",
        **({} if because is None else {"held_because": because}),
    }
    return d


def simulated_torque(path) -> str | None:
    """How the simulation that wrote the log at ``path`` logged its torque, as the log's truth
    sidecar says: ``"held"`` (``mindyn simulate``'s tracking mode: the controller's command,
    held over each period), ``"sampled"`` (inverse dynamics at the samples), or None (no
    sidecar, or one that does not say)."""
    from .data import read_json, truth_path

    p = truth_path(path)
    if not p.is_file():
        return None
    try:
        sim = read_json(p, what="truth file").get("simulation")
    except (DataError, AttributeError):  # read_truth names a broken sidecar where it matters
        return None
    if not isinstance(sim, dict):
        return None
    said = sim.get("torque")
    if said in ("held", "sampled"):
        return said
    # sidecars written before the key: the tracking mode held its command
    return {"tracking": "held", "inverse": "sampled"}.get(str(sim.get("mode")))


def simulated_held(paths) -> list[str | None]:
    """Per log at ``paths``, why the dynamic model reads its torque as held when ``torque`` is
    not given: its truth sidecar says its simulation held the command over each period
    (:func:`simulated_torque`); None: read as sampled (no sidecar, as a measured log, or one
    that says sampled)."""
    return [_held_reason(p) if simulated_torque(p) == "held" else None for p in paths]


def _held_reason(path) -> str:
    from .data import truth_path

    return f"as {truth_path(path)} says: simulated with the command held over each period"


def _processed(paths, raws, opts: ReadingOptions, cutoff, periodic, decimate) -> list[list]:
    """The logs ``raws`` of ``paths`` through the data path: with the low-pass, cut at their
    breaks and each segment through :func:`~mindyn.identification.preprocess.preprocess`;
    otherwise each checked for evenly spaced time stamps."""
    from .preprocess import preprocess, require_even_stamps, split_at_gaps

    if opts.filter != "lowpass":
        for d in raws:
            require_even_stamps(d, opts.filter)
        return [[d] for d in raws]
    out = []
    for p, raw in zip(paths, raws):
        segments = split_at_gaps(raw)
        if len(segments) > 1 and (opts.periods or opts.period):
            raise DataError(
                f"periods=/period=: {p} has {len(segments) - 1} break(s) in its "
                "time stamps; a periodic log to be averaged must be one continuous recording"
            )
        with _named_filter_error(p, opts):
            out.append(
                [
                    preprocess(
                        seg,
                        cutoff=cutoff if cutoff is not None else opts.cutoff,
                        periods=opts.periods if periodic else None,
                        period=opts.period if periodic else None,
                        edge=opts.edge,
                        decimate=decimate,
                    )
                    for seg in segments
                ]
            )
    return out


def read_log(
    path,
    robot,
    *,
    options: ReadingOptions | None = None,
    currents=None,
    cutoff: float | None = None,
    periodic: bool = False,
    decimate: bool = True,
    require_torque: bool = True,
) -> list[JointData]:
    """The log at ``path`` (a CSV or a ROS bag; torques from the ``currents`` file when given)
    as a list of logs: with the ``lowpass`` filter cut at its breaks
    (:func:`~mindyn.identification.preprocess.split_at_gaps`) and each segment through
    :func:`~mindyn.identification.preprocess.preprocess` (``cutoff`` overrides the options';
    periods averaged only when ``periodic``; decimated when ``decimate`` and the options allow);
    otherwise one log. A filter that cannot be designed at the cut-off is named as such, and a
    simulated log whose truth sidecar names another robot is refused."""
    opts = options or ReadingOptions()
    # truth=[]: a simulated log whose truth sidecar names another robot is refused
    raws = _raw([path], robot, opts, [currents], require_torque, truth=[])
    return _processed([path], raws, opts, cutoff, periodic, decimate and opts.decimate)[0]


def paired(logs: Sequence, currents, given: str, logs_given: str) -> list:
    """One currents file per log (or none); ``given`` / ``logs_given``: the keyword of the
    currents and the name of the logs in the message."""
    if not currents:
        return [None] * len(logs)
    if len(currents) != len(logs):
        raise DataError(
            f"{given}: {len(currents)} currents file(s) for {len(logs)} log(s) of {logs_given}; "
            "expected one per log, in the same order"
        )
    return list(currents)


def segments(ds: list[JointData]) -> dict:
    """A log cut at its breaks: segment count, shortest and longest [s], each one's span."""
    spans = [d.processing["segment"]["t_s"] for d in ds]
    length = [b - a for a, b in spans]
    return {
        "count": len(ds),
        "shortest_s": min(length),
        "longest_s": max(length),
        "spans_s": spans,
    }


@dataclass(frozen=True)
class LogSet:
    """The logs of some files: ``parts[k]`` the logs of ``files[k]`` (several when the file was
    cut at breaks in its time stamps); made from them, ``logs`` all of them in order, ``labels``
    each one's name (the file, or the segment's source), ``samples`` and ``rates`` each one's
    sample count and mean rate [Hz] as used, ``logged`` its sample count as logged, and
    ``segments`` per file the segments of :func:`segments` (None for a file not cut)."""

    files: list[str]
    parts: list[list[JointData]]
    logs: list[JointData] = field(init=False)
    labels: list[str] = field(init=False)
    samples: list[int] = field(init=False)
    rates: list[float] = field(init=False)
    logged: list[int] = field(init=False)
    segments: list[dict | None] = field(init=False)

    def __post_init__(self):
        logs = [d for ds in self.parts for d in ds]
        made = dict(
            logs=logs,
            labels=[
                d.source if len(ds) > 1 else f for f, ds in zip(self.files, self.parts) for d in ds
            ],
            samples=[d.m for d in logs],
            rates=[d.rate for d in logs],
            logged=[int(d.processing.get("samples", d.m)) for d in logs],
            segments=[segments(ds) if len(ds) > 1 else None for ds in self.parts],
        )
        for name, value in made.items():
            object.__setattr__(self, name, value)


@dataclass(frozen=True)
class Logs(Sequence):
    """The logs of one identification (:func:`load_logs`): ``fit`` and ``validation``
    (:class:`LogSet`, validation empty when none), how they were read (``reading``, ``model``),
    the cut-off the validation logs were filtered at (``cutoff``: the highest of the fit logs'
    with the low-pass, else None), the truth sidecars of the fit files (``truth``) and the
    robot they were read for (``robot``, its name, and ``joints``, its joint names; None for
    logs read otherwise), which :func:`~mindyn.identification.workflow.run` requires; made from
    them, ``record``: how the logs were read, for the JSON (what ``mindyn predict`` does with
    another log; None when ``reading`` is: logs read otherwise). As a sequence: the fit
    logs."""

    fit: LogSet
    validation: LogSet = field(default_factory=lambda: LogSet([], []))
    reading: ReadingOptions | None = None
    model: str = "dynamic"
    cutoff: float | None = None
    truth: list = field(default_factory=list)
    robot: str | None = None
    joints: tuple[str, ...] | None = None
    record: dict | None = field(init=False)

    def __post_init__(self):
        r = self.reading
        record = (
            None
            if r is None
            else {
                "filter": r.filter,
                "cutoff_Hz": self.cutoff if r.filter == "lowpass" else r.cutoff,
                "edge_s": r.edge,
                "torque_unit": r.torque_unit,
                "drive_gain": None if r.drive_gain is None else list(r.drive_gain),
                "topic": r.topic,
                "columns": None if r.columns is None else r.columns.record(),
                "torque": r.torque,
            }
        )
        object.__setattr__(self, "record", record)

    def __getitem__(self, k):
        return self.fit.logs[k]

    def __len__(self) -> int:
        return len(self.fit.logs)


#: The keywords :func:`load_logs` takes: its own and those of :class:`ReadingOptions`.
_LOAD_LOGS_KEYWORDS = frozenset(f.name for f in fields(ReadingOptions) if f.init) | {
    "validate",
    "currents",
    "validate_currents",
    "model",
    "options",
    "what",
}


def load_logs(
    paths: Sequence,
    robot,
    *,
    validate: Sequence = (),
    currents: Sequence | None = None,
    validate_currents: Sequence | None = None,
    model: str = "dynamic",
    options: ReadingOptions | None = None,
    what: str = "the identification data",
    **reading,
) -> Logs:
    """The logs at ``paths`` (CSV or ROS bags, fitted together) and the validation logs at
    ``validate`` (a path alone: a list of it), read as ``options`` (a :class:`ReadingOptions`)
    or the keywords of :class:`ReadingOptions` say. ``currents`` / ``validate_currents``: a
    motor-current file per log. ``model``: the regression model the logs are for (the window
    models integrate over the logged samples: no decimation for them). ``what``: the logs'
    name in errors.

    A log simulated for another robot (its truth sidecar says so) is refused before any is read,
    as a fit log given twice and a validation log that is a fit log (the same file, or the same
    bytes); with the low-pass the fit logs average their periods (``periods``/``period``) and the
    validation logs are filtered at the fit's cut-off, the highest of the fit logs'. With the
    dynamic model and ``torque`` not given, each log is read as held when its truth sidecar
    says its simulation held the torque (:func:`simulated_held`; the processing record says
    why), as sampled otherwise; ``record`` says held when every log was."""
    _args.unknown_keywords("load_logs", reading, _LOAD_LOGS_KEYWORDS)
    robot = as_robot(robot)
    one = (str, PathLike)
    for name, value in (("paths", paths), ("validate", validate)):
        if not isinstance(value, one):
            _args.instance(value, name, (list, tuple), "a path or a list of paths")
            for p in value:
                _args.instance(p, name, one, "a path or a list of paths")
    for name, value in (("currents", currents), ("validate_currents", validate_currents)):
        if value is not None:
            _args.instance(value, name, (list, tuple), "a list of paths (one per log)")
    _args.choice(model, "model", MODELS)
    _args.optional(_args.instance, options, "options", ReadingOptions)
    _args.text(what, "what")
    if options is not None and reading:
        raise DataError(f"load_logs: give options or {', '.join(reading)}, not both")
    opts = options or ReadingOptions(**reading)
    if model not in MODELS:
        raise DataError(f"load_logs: model '{model}': expected one of {', '.join(MODELS)}")
    if opts._decimate_given and model != "dynamic":
        raise _args.fail(
            f"decimate={opts.decimate}",
            f"applies only to the dynamic model (the integral and energy models keep every "
            f"sample); got model='{model}'",
        )
    if opts._torque_given and model != "dynamic":
        raise _args.fail(
            f"torque='{opts.torque}'",
            "applies only to the dynamic model (the integral and energy models take a torque "
            f"held over each sample period by integration='zoh'); got model='{model}'",
        )
    one = (str, PathLike)  # one path given alone: a list of it
    paths = [paths] if isinstance(paths, one) else paths
    validate = [validate] if isinstance(validate, one) else validate or ()
    files, vfiles = [str(p) for p in paths], [str(p) for p in validate]
    if not files:
        raise DataError("load_logs: expected at least one log")
    check_distinct_logs(files, vfiles)
    if validate_currents and not vfiles:
        raise DataError("validate_currents=: expected validate= with the logs they belong to")
    cur = paired(files, currents, "currents=", what)
    vcur = paired(vfiles, validate_currents, "validate_currents=", "validate=")
    because, sampled = None, None
    if model == "dynamic":
        from .data import truth_path

        said = [simulated_torque(p) for p in files + vfiles]
        if not opts._torque_given:
            # (:func:`simulated_held`, from the sidecars read once)
            because = [
                _held_reason(p) if s == "held" else None for p, s in zip(files + vfiles, said)
            ]
            if all(b is not None for b in because):  # recorded as held (predict, detect follow)
                opts = copy.copy(opts)  # (replace() would take its defaults as given)
                object.__setattr__(opts, "torque", "held")
            sampled = [
                f"as {truth_path(p)} says: inverse dynamics at the samples"
                if s == "sampled"
                else None
                for p, s in zip(files + vfiles, said)
            ]
        elif opts.torque == "sampled":
            sampled = [
                f"torque='sampled' given; {truth_path(p)} says its simulation held the command"
                if s == "held"
                else None
                for p, s in zip(files + vfiles, said)
            ]
    truth: list = []
    raws = _raw(files + vfiles, robot, opts, cur + vcur, True, truth, because, sampled)
    decimate = model == "dynamic" and opts.decimate
    parts = _processed(files, raws[: len(files)], opts, None, True, decimate)
    pres = [d.processing.get("preprocess") for ds in parts for d in ds]
    cutoff = max(p["filter"]["cutoff_Hz"] for p in pres) if all(pres) else None
    vparts = _processed(vfiles, raws[len(files) :], opts, cutoff, False, decimate)
    truth = truth[: len(files)]
    return Logs(
        LogSet(files, parts),
        LogSet(vfiles, vparts),
        reading=opts,
        model=model,
        cutoff=cutoff,
        truth=truth,
        robot=robot.name,
        joints=tuple(robot.joint_names),
    )
