"""Reading the logs of an identification: how a log is read (:class:`ReadingOptions`), one log
read and pre-processed (:func:`read_log`), and the fit and validation logs of one
identification together (:func:`load_logs`, :class:`Logs`), with the rule that validation logs
are filtered at the fit's cut-off."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from .data import DataError, JointData

FILTERS = ("lowpass", "butter", "savgol", "none")


@dataclass(frozen=True, kw_only=True)
class ReadingOptions:
    """How a log is read and pre-processed (the options of ``mindyn identify`` of the same
    names).

    ``filter``: ``lowpass`` (the identification data path of
    :func:`~mindyn.identification.preprocess.preprocess`: resampling, one zero-phase low-pass,
    edges dropped, decimation), or ``butter``, ``savgol``, ``none`` (derivatives only);
    ``cutoff`` [Hz] (None: from the data); ``periods`` / ``period`` [s]: a periodic excitation
    averaged (lowpass, fit logs only); ``edge`` [s] dropped at each end (lowpass); ``decimate``
    (lowpass, dynamic model only); ``torque_unit`` (None: as the file says), ``drive_gain`` (per
    joint, or one for all), ``topic`` (ROS bag)."""

    filter: str = "lowpass"
    cutoff: float | None = None
    periods: int | None = None
    period: float | None = None
    edge: float | None = None
    decimate: bool = True
    torque_unit: str | None = None
    drive_gain: tuple[float, ...] | None = None
    topic: str | None = None

    def __post_init__(self):
        if self.filter not in FILTERS:
            raise DataError(f"filter '{self.filter}': expected one of {', '.join(FILTERS)}")
        if self.drive_gain is not None:
            object.__setattr__(self, "drive_gain", tuple(float(g) for g in self.drive_gain))
        if self.filter != "lowpass":  # the options of the low-pass path, refused with another
            for flag, value in (
                ("--periods", self.periods),
                ("--excitation-period", self.period),
                ("--edge", self.edge),
                ("--no-decimate", None if self.decimate else True),
            ):
                if value is not None:
                    raise DataError(f"{flag} needs --filter lowpass (got --filter {self.filter})")

    def gains(self, n: int) -> np.ndarray | None:
        """The drive gains for ``n`` joints (one value given: the same for all), or None."""
        if self.drive_gain is None:
            return None
        g = list(self.drive_gain)
        if len(g) == 1:
            g *= n
        if len(g) != n:
            raise DataError(f"--drive-gain needs {n} values (or one for all), got {len(g)}")
        return np.array(g)


def _read_one(path, robot, opts: ReadingOptions, currents, require_torque, even) -> JointData:
    """One log as read (no low-pass path): CSV or ROS bag, torques from ``currents`` if given."""
    from .currents import attach_currents
    from .data import convert_torque, read_csv
    from .rosbag import is_rosbag, read_rosbag

    gain = opts.gains(robot.n)
    if Path(path).is_dir() and not is_rosbag(path):
        raise DataError(f"'{path}' is a folder but not a ROS 2 bag (it has no metadata.yaml)")
    unit = None if currents else opts.torque_unit
    filt = "none" if opts.filter == "lowpass" else opts.filter
    if is_rosbag(path):
        current = unit == "current"
        data = read_rosbag(
            path,
            robot,
            topic=opts.topic,
            torque_unit="Nm" if current or not unit else unit,
            filter=filt,
            cutoff=opts.cutoff,
        )
        if current:  # effort in A: the gains (given or of the drive table) turn it into N m
            tau, info = convert_torque(data.tau, "current", robot, gain)
            data = replace(data, tau=tau, processing={**data.processing, "torque": info})
    else:
        data = read_csv(
            path,
            robot=robot,
            torque_unit=unit,
            require_torque=not currents and require_torque,
            filter=filt,
            cutoff=opts.cutoff,
            drive_gain=gain,
        )
    if currents:
        data = attach_currents(data, currents, robot, gain)
    if even:  # the low-pass path resamples: its raw read is not checked
        from .preprocess import require_even_stamps

        require_even_stamps(data, filt)
    if gain is not None and not data.processing["torque"]["unit"].startswith("motor current"):
        raise DataError(
            f"--drive-gain: {path} holds torques in {data.processing['torque']['unit']}, not "
            "motor currents; expected --torque-unit current, columns i1..in or --currents"
        )
    return data


def _read(path, robot, opts, currents, cutoff, periodic, decimate, require_torque):
    if opts.filter != "lowpass":
        return [_read_one(path, robot, opts, currents, require_torque, even=True)]
    from .preprocess import preprocess, split_at_gaps

    raw = _read_one(path, robot, opts, currents, require_torque, even=False)
    segments = split_at_gaps(raw)
    if len(segments) > 1 and (opts.periods or opts.period):
        raise DataError(
            f"--periods/--excitation-period: {path} has {len(segments) - 1} break(s) in its "
            "time stamps; a periodic log to be averaged must be one continuous recording"
        )
    return [
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
    otherwise one log. A filter that cannot be designed at the cut-off is named as such."""
    opts = options or ReadingOptions()
    try:
        return _read(
            path, robot, opts, currents, cutoff, periodic, decimate and opts.decimate,
            require_torque,
        )  # fmt: skip
    except np.linalg.LinAlgError as e:
        if opts.filter not in ("butter", "lowpass"):
            raise
        raise DataError(
            f"--cutoff {opts.cutoff:g} Hz: the zero-phase Butterworth filter "
            f"of {path} is singular at this cutoff ({e}); expected a cutoff of at least 1e-4 of "
            "half the log's sample rate"
            if opts.cutoff is not None
            else f"{path}: the Butterworth filter for the derivatives is singular ({e})"
        ) from None


def paired(logs: Sequence, currents, flag: str, logs_flag: str) -> list:
    """One currents file per log (or none)."""
    if not currents:
        return [None] * len(logs)
    if len(currents) != len(logs):
        raise DataError(
            f"{flag}: {len(currents)} currents file(s) for {len(logs)} log(s) of {logs_flag}; "
            "expected one per log, in the same order"
        )
    return list(currents)


@dataclass(frozen=True)
class LogSet:
    """The logs of some files: ``parts[k]`` the logs of ``files[k]`` (several when the file was
    cut at breaks in its time stamps), ``logs`` all of them in order, ``labels`` each one's name
    (the file, or the segment's source)."""

    files: list[str]
    parts: list[list[JointData]]

    @property
    def logs(self) -> list[JointData]:
        return [d for ds in self.parts for d in ds]

    @property
    def labels(self) -> list[str]:
        return [d.source if len(ds) > 1 else f for f, ds in zip(self.files, self.parts) for d in ds]


@dataclass(frozen=True)
class Logs(Sequence):
    """The logs of one identification (:func:`load_logs`): ``fit`` and ``validation``
    (:class:`LogSet`, validation empty when none), how they were read (``reading``, ``model``),
    the cut-off the validation logs were filtered at (``cutoff``: the highest of the fit logs'
    with the low-pass, else None) and the truth sidecars of the fit files (``truth``). As a
    sequence: the fit logs."""

    fit: LogSet
    validation: LogSet = field(default_factory=lambda: LogSet([], []))
    reading: ReadingOptions = field(default_factory=ReadingOptions)
    model: str = "dynamic"
    cutoff: float | None = None
    truth: list = field(default_factory=list)

    def __getitem__(self, k):
        return self.fit.logs[k]

    def __len__(self) -> int:
        return sum(len(ds) for ds in self.fit.parts)

    def record(self) -> dict:
        """How the logs were read, for the JSON: what ``mindyn predict`` does with another log."""
        r = self.reading
        return {
            "filter": r.filter,
            "cutoff_Hz": self.cutoff if r.filter == "lowpass" else r.cutoff,
            "edge_s": r.edge,
            "torque_unit": r.torque_unit,
            "drive_gain": None if r.drive_gain is None else list(r.drive_gain),
            "topic": r.topic,
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
    ``validate``, read as ``options`` (a :class:`ReadingOptions`) or the keywords of
    :class:`ReadingOptions` say. ``currents`` / ``validate_currents``: a motor-current file per
    log. ``model``: the regression model the logs are for (the window models integrate over
    the logged samples: no decimation for them). ``what``: the logs' name in errors.

    A log simulated for another robot (its truth sidecar says so) is refused before any is read;
    with the low-pass the fit logs average their periods (``periods``/``period``) and the
    validation logs are filtered at the fit's cut-off, the highest of the fit logs'."""
    if options is not None and reading:
        raise DataError(f"load_logs: give options or {', '.join(reading)}, not both")
    opts = options or ReadingOptions(**reading)
    from .data import read_truth

    files, vfiles = [str(p) for p in paths], [str(p) for p in validate or ()]
    if not files:
        raise DataError("load_logs: expected at least one log")
    if validate_currents and not vfiles:
        raise DataError("--validate-currents: expected --validate with the logs they belong to")
    cur = paired(files, currents, "--currents", what)
    vcur = paired(vfiles, validate_currents, "--validate-currents", "--validate")
    truth = [read_truth(f, robot) for f in files]
    for f in vfiles:
        read_truth(f, robot)
    kw = dict(options=opts, decimate=model == "dynamic")
    parts = [read_log(f, robot, currents=c, periodic=True, **kw) for f, c in zip(files, cur)]
    pres = [d.processing.get("preprocess") for ds in parts for d in ds]
    cutoff = max(p["filter"]["cutoff_Hz"] for p in pres) if all(pres) else None
    vparts = [read_log(f, robot, currents=c, cutoff=cutoff, **kw) for f, c in zip(vfiles, vcur)]
    return Logs(
        LogSet(files, parts),
        LogSet(vfiles, vparts),
        reading=opts,
        model=model,
        cutoff=cutoff,
        truth=truth,
    )


def check_width(width, n: int) -> list[float]:
    """Friction widths for ``n`` joints (one value: the same for all), each positive."""
    w = [float(x) for x in width]
    if len(w) == 1:
        w *= n
    if len(w) != n:
        raise DataError(f"--friction-width needs {n} values (or one for all), got {len(w)}")
    if not all(math.isfinite(x) and x > 0 for x in w):
        raise DataError("--friction-width: every width must be a positive number")
    return w
