"""Joint torques from motor currents logged in a file of their own.

Some controllers log the motor currents apart from the joint positions, e.g. a file
``t, i1..iN, ...`` (further columns, such as desired currents, are ignored) beside a
``t, q1..qN, [dq1..dqN]`` log. :func:`attach_currents` joins the two on their time stamps (every
sample of the joint log needs a current sample at the same time, within a tolerance) and sets
the torques to ``tau = i * K`` with the joint-side drive gains ``K`` of
:func:`~mindyn.identification.data.drive_gains` (the robot's ``torque_constant * gear_ratio``,
or gains given per joint), or, when the description declares transmissions, to
``tau = T^T (K_t i)`` with the motor torque constants ``K_t`` (see
:func:`~mindyn.identification.data.current_gains`).
"""

from __future__ import annotations

import csv
import io
import re
from dataclasses import replace
from pathlib import Path

import numpy as np

from .. import _args
from .data import (
    DataError,
    DataFileNotFoundError,
    JointData,
    current_gains,
    decode_text,
    first_not_increasing,
    given_drive_gain,
    parse_cell,
)

__all__ = ["attach_currents", "read_currents"]


def read_currents(path, n: int, *, columns=None, robot=None) -> tuple[np.ndarray, np.ndarray]:
    """The time stamps (m,) and motor currents ``i1..in`` (m, n) [A] of a CSV with the header
    ``t, i1..in`` and any further columns (ignored), or the columns that the ``t`` and ``i`` of
    the column map ``columns`` name (:func:`~mindyn.identification.columns.column_map`; its
    time unit applied; ``robot`` gives the joint names of ``{name}``). Raises DataError naming
    the file, line and column of a missing column, a value that is not a finite number, or a
    time that does not increase."""
    from .columns import TIME_UNITS, column_map, missing_column

    _args.path(path, "path")
    n = _args.integer(n, "n", 1)
    cmap = None if columns is None else column_map(columns)
    if cmap is not None and "i" not in cmap.entries:
        raise _args.fail("columns", "has no i: the currents file is read through its t and i")
    path = Path(path)
    if not path.is_file():
        raise DataFileNotFoundError(f"currents file '{path}' does not exist")
    reader = csv.reader(io.StringIO(decode_text(path), newline=""))
    try:
        header = next(reader, None)
        while header is not None and header and header[0].lstrip().startswith("#"):
            header = next(reader, None)
        if not header:
            raise DataError(f"{path}: the file is empty")
        names = [h.strip() for h in header]
        want = ["t"] + [f"i{j}" for j in range(1, n + 1)]
        if cmap is not None:
            joints = None if robot is None else list(robot.joint_names)
            mapped = cmap.names(n, joints)
            want = mapped["t"] + mapped["i"]
            for k, w in enumerate(want):
                if w not in names:
                    what = "t" if k == 0 else f"i{k}"
                    raise DataError(f"{path}: {missing_column(w, what, names)}")
        missing = [w for w in want if w not in names]
        if missing:
            extra = [h for h in names if re.fullmatch(r"i\d+", h) and h not in want]
            raise DataError(
                f"{path}: missing column(s) {', '.join(missing)}"
                + (f" (unexpected {', '.join(extra)})" if extra else "")
                + f"; expected t, i1..i{n} (motor currents in A) and optionally other columns"
            )
        cols = [names.index(w) for w in want]
        t, cur, lines = [], [], []
        for row in reader:
            if not row or (len(row) == 1 and not row[0].strip()):
                continue
            if len(row) != len(names):
                raise DataError(
                    f"{path}, line {reader.line_num}: {len(row)} values for {len(names)} columns"
                )
            where = f"{path}, line {reader.line_num}, column "
            vals = [parse_cell(row[c], where + names[c]) for c in cols]
            t.append(vals[0])
            cur.append(vals[1:])
            lines.append(reader.line_num)
    except csv.Error as e:
        raise DataError(f"{path}, line {reader.line_num}: not readable as CSV ({e})") from None
    if len(t) < 2:
        raise DataError(f"{path}: {len(t)} data row(s); at least 2 samples are needed")
    t = np.array(t)
    r = first_not_increasing(t)
    if r is not None:
        raise DataError(
            f"{path}, line {lines[r]}: time is not increasing (t = {t[r]:.9g} after {t[r - 1]:.9g})"
        )
    unit = None if cmap is None else cmap.unit("t")
    if unit not in (None, "s"):
        t = t / TIME_UNITS[unit]
    return t, np.array(cur)


def attach_currents(
    data: JointData,
    path,
    robot=None,
    *,
    drive_gain=None,
    tolerance: float | None = None,
    columns=None,
) -> JointData:
    """``data`` with its torques replaced by the currents of the file ``path`` converted with
    the drive gains (see :func:`~mindyn.identification.data.current_gains`).

    The files are joined on their time stamps: each sample of ``data`` takes the current sample
    with the nearest time stamp, which must lie within ``tolerance`` seconds (default a
    thousandth of the median sample period of ``data``); current samples before, after or
    between those of ``data`` are left out. ``columns``: a column map, the file read through
    its ``t`` and ``i`` (:func:`read_currents`). Raises DataError naming the first time stamp
    without a match, or (with ``robot``) torques of another unit or sign than the description's
    (:func:`~mindyn.identification.torque_units.check_torque_units`: gains of the wrong sign or
    size)."""
    from ..robot import Robot

    _args.instance(data, "data", JointData)
    _args.path(path, "path")
    _args.optional(_args.instance, robot, "robot", Robot)
    drive_gain = given_drive_gain(drive_gain, robot, size=data.n)
    tolerance = _args.optional(_args.number, tolerance, "tolerance", positive=True)
    t_i, cur = read_currents(path, data.n, columns=columns, robot=robot)
    G, info = current_gains(robot, drive_gain=drive_gain)
    if G.shape[0] != data.n:
        raise DataError(f"drive gains: {G.shape[0]} values for {data.n} joints")
    tol = tolerance if tolerance is not None else 1e-3 * float(np.median(np.diff(data.t)))
    k = np.clip(np.searchsorted(t_i, data.t), 1, t_i.size - 1)
    k = np.where(np.abs(t_i[k - 1] - data.t) <= np.abs(t_i[k] - data.t), k - 1, k)
    gap = np.abs(t_i[k] - data.t)
    bad = np.flatnonzero(gap > tol)
    if bad.size:
        b = bad[0]
        raise DataError(
            f"{path}: no current sample at t = {data.t[b]:.9g} s of {data.source or 'the log'} "
            f"(nearest t = {t_i[k[b]]:.9g} s, {gap[b]:.3g} s away; tolerance {tol:.3g} s): "
            f"the time stamps of {bad.size} of {data.m} samples do not match"
        )
    processing = dict(data.processing)
    processing["torque"] = {
        "unit": "motor current [A]",
        **info,
        "currents_file": str(path),
        "time_tolerance_s": tol,
        "max_time_offset_s": float(gap.max()),
    }
    tau = cur[k] @ G
    if robot is not None:
        from .torque_units import CURRENTS_TORQUE_REMEDY, check_torque_units

        check_torque_units(
            data.t,
            data.q,
            data.dq,
            tau,
            robot,
            f"{path} (currents x drive gains)",
            CURRENTS_TORQUE_REMEDY,
        )
    return replace(data, tau=tau, processing=processing)
