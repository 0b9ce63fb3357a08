"""Joint data in and out: the CSV format of ``mindyn simulate`` / ``mindyn identify``.

Format: one header line, then one row per sample, comma-separated::

    t, q1..qN, [dq1..dqN], [ddq1..ddqN], tau1..tauN

No other column is read: one is refused, named with its position and the ``cut`` command that
deletes it, unless a column map (``columns=``, :mod:`~mindyn.identification.columns`) names the
file's columns of each quantity (a controller's own names, such as ``actual_q_0``): the file's
other columns are then ignored. Cells are decimal numbers in ASCII (``-1.25``, ``3e-4``, blanks
around them allowed); the file is UTF-8 text (a leading byte-order mark is skipped). ``t`` in
seconds, strictly increasing; positions in rad (m for prismatic joints), velocities and
accelerations per second; torques in N m (N), or as relative values in per mille of the drive's
rated torque, as the ZCR07S controller logs them (``torque_unit="permille"``: ``tau = value *
rated_torque * gear_ratio / 1000``, with the drive table of the robot description). The torque
columns may say their unit in the header, ``tau1[permille]`` or ``tau1[Nm]`` (as
:func:`write_csv` writes with ``torque_unit``); the reader then needs no ``torque_unit``. Motor
currents in A may stand in for the torques, as columns ``i1..iN`` (or
``torque_unit="current"``): ``tau = i * K`` with the joint-side drive gain ``K = torque_constant
* gear_ratio`` of the drive table, or ``K`` given as ``drive_gain``; when the description
declares transmissions, ``tau = T^T (K_t i)`` with the motor torque constants ``K_t``
(``drive_gain``, else the transmission's) and the transmission matrix ``T`` (see
:func:`current_gains`).
Velocities and accelerations that are not logged are obtained from the positions (velocities) by
zero-phase low-pass filtering and central differences; the samples at each end where the
filter starts up are then dropped (:func:`without_derivative_edges`); the settings are reported
in :attr:`JointData.processing`.
"""

from __future__ import annotations

import csv
import hashlib
import json
import math
import re
import shlex
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from scipy import signal

from .. import _args
from .._core import Error, parse_csv_numbers
from .joint_data import JointData

__all__ = [
    "DataError",
    "DataFileNotFoundError",
    "JointData",
    "differentiate",
    "read_csv",
    "check_log_robot",
    "read_truth",
    "truth_path",
    "write_csv",
    "write_trajectory_csv",
]


class DataError(Error, ValueError):
    """Malformed or unusable joint data (names the file, line and column)."""


class UnusedGainError(DataError):
    """Drive gains given for a log whose torques are not motor currents (refuse_unused_gain)."""


class DataFileNotFoundError(Error, FileNotFoundError):
    """A data file that does not exist."""


_COLUMN = re.compile(r"(t|q|dq|ddq|tau)([1-9][0-9]*)?")
_UNIT = re.compile(r"(tau[1-9][0-9]*)\s*\[([^\]]*)\]")

# A cell holds a decimal number in ASCII: optional sign, digits with an optional point, optional
# exponent, ASCII blanks around it. Python's float() also takes digit-group underscores
# ("1_000"), non-ASCII digits and blanks, and "nan"/"inf"/"infinity" spelled out; none of these
# belongs in a log, so they are refused (the last two with their own message).
_NUMBER = re.compile(r"[ \t]*[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?[ \t]*")
_BLANKS = " \t"
_NONFINITE = re.compile(r"[ \t]*[+-]?(?:nan|inf|infinity)[ \t]*", re.IGNORECASE)


def _expected_columns(n, require_torque: bool) -> str:
    """The columns a log of ``n`` joints has, in words."""
    return f"t, q1..q{n}, optionally dq1..dq{n} and ddq1..ddq{n}" + (
        f", then tau1..tau{n}" if require_torque else f", optionally tau1..tau{n}"
    )


#: What a first line starting so is, when a file of another kind is given for a CSV table
_NOT_A_TABLE = (
    ("<", "XML (a URDF or MJCF robot description?)"),
    ("{", "JSON (an identification, excitation or truth file?)"),
    ("[", "JSON"),
)
#: A first line that is a YAML mapping's key (``name: r3``, ``joints:``)
_YAML_KEY = re.compile(r"[A-Za-z_][A-Za-z0-9_ -]*:(\s.*)?")


def _shorten(text: str, size: int = 40) -> str:
    return repr(text if len(text) <= size else text[: size - 3] + "...")


def check_header(header: list[str], path: str, expected: str) -> list[str]:
    """The names of a log's ``header``, stripped; DataError when the header is separated by
    semicolons or tabs, or is a row of numbers (no header), saying the columns ``expected``."""
    names = [h.strip() for h in header]
    # another kind of file given for a log: a robot description, a JSON the commands write
    first = names[0] if names else ""
    kind = next((k for c, k in _NOT_A_TABLE if first.startswith(c)), None)
    if kind is None and len(names) == 1 and _YAML_KEY.fullmatch(first):
        kind = "YAML (a robot description or a joint-terms file?)"
    if kind is not None:
        raise DataError(
            f"{path}: not a CSV table: its first line ({_shorten(','.join(header))}) is {kind}; "
            "a log is comma-separated, its first line naming the columns: " + expected
        )
    if len(names) == 1:
        for sep, word in ((";", "semicolons"), ("\t", "tabs")):
            if names[0].count(sep) >= 2:
                raise DataError(
                    f"{path}: the header is separated by {word}, not commas; a log is "
                    "comma-separated with '.' as the decimal point: " + expected
                )
    if any(names) and all(_NUMBER.fullmatch(h) or _NONFINITE.fullmatch(h) for h in names if h):
        shown = ", ".join(names[:3]) + (", ..." if len(names) > 3 else "")
        raise DataError(
            f"{path}: the first line (after any # comments) holds numbers ({shown}), not column "
            "names: the header is missing; a log starts with a header line naming its columns: "
            + expected
        )
    return names


def _columns(header: list[str], n: int | None, require_torque: bool, path: str) -> dict:
    """Maps header names to kinds; raises DataError naming missing and extra columns. A torque
    column may carry its unit, ``tau1[permille]``: all torque columns then say the same one,
    returned as ``torque_unit`` (None when the header names none)."""
    names = check_header(header, path, _expected_columns("N" if n is None else n, require_torque))
    _refuse_motion_units(names, path)
    currents = [i for i, h in enumerate(names) if re.fullmatch(r"i\d+", h)]
    if currents:
        if any(re.fullmatch(r"tau\d+(\s*\[.*\])?", h) for h in names):
            raise DataError(
                f"{path}: both torque columns (tau1..) and current columns (i1..) in the "
                "header; give one of them"
            )
        for i in currents:  # currents stand in for the torques, unit 'current'
            names[i] = f"tau{names[i][1:]}[current]"
    units = {}
    for i, name in enumerate(names):
        u = _UNIT.fullmatch(name)
        if u:
            names[i], units[u.group(1)] = u.group(1), u.group(2).strip()
    if units:
        taus = [h for h in names if re.fullmatch(r"tau[1-9][0-9]*", h)]
        if set(units) != set(taus) or len(set(units.values())) != 1:
            raise DataError(
                f"{path}: the torque columns say different units ("
                + ", ".join(f"{h}[{units[h]}]" if h in units else h for h in taus)
                + "); give one unit on every torque column or on none"
            )
    groups: dict[str, dict[int, int]] = {"q": {}, "dq": {}, "ddq": {}, "tau": {}}
    t_col = None
    # unexpected (name, column index) pairs; unnamed columns (trailing commas) may be several
    extra: list[tuple[str, int]] = []
    seen = set()
    for i, name in enumerate(names):
        if name and name in seen:
            raise DataError(f"{path}: column '{name}' appears twice in the header")
        seen.add(name)
        m = _COLUMN.fullmatch(name)
        if not m or (m.group(1) == "t") != (m.group(2) is None):
            extra.append((name, i))
            continue
        if m.group(1) == "t":
            t_col = i
        else:
            groups[m.group(1)][int(m.group(2))] = i
    if n is None:
        n = max(groups["q"]) if groups["q"] else 0
        if n == 0:
            other = f" (it has {', '.join(repr(e) for e, _ in extra)})" if extra else ""
            raise DataError(f"{path}: no position columns q1, q2, ... in the header{other}")
        if n > len(names):
            raise DataError(
                f"{path}: column 'q{n}' implies {n} joints, but the header has only "
                f"{len(names)} columns"
            )
    want = {"q": True, "dq": False, "ddq": False, "tau": require_torque}
    missing = [] if t_col is not None else ["t"]
    beyond = []  # columns of joints the robot does not have
    for kind, required in want.items():
        present = groups[kind]
        for j in present:
            if not 1 <= j <= n:
                extra.append((f"{kind}{j}", present[j]))
                beyond.append(f"{kind}{j}")
        if present or required:  # optional torques: all or none
            missing += [f"{kind}{j}" for j in range(1, n + 1) if j not in present]
    if missing or extra:
        parts = []
        if missing:
            parts.append("missing " + ", ".join(missing))
        if extra:
            parts.append("unexpected " + ", ".join(e or "an unnamed column" for e, _ in extra))
        raise DataError(
            f"{path}: wrong columns for a {n}-joint robot ({'; '.join(parts)}); expected "
            + _expected_columns(n, require_torque)
            + (_remedy(path, len(names), extra, beyond, n, missing) if extra else "")
        )
    unit = next(iter(units.values())) if units else None
    return {"t": t_col, "n": n, "torque_unit": unit, **groups}


_MOTION_UNIT = re.compile(r"(t|q|dq|ddq)([1-9][0-9]*)?\s*\[([^\]]*)\]")


def _refuse_motion_units(names: list[str], path: str) -> None:
    """Refuses a header that gives the unit of the time or of a joint's motion (``q1[deg]``),
    which only a column map reads (a header's unit is read on the torque columns alone), with
    the column map that reads this header."""
    said = [(i, m) for i, name in enumerate(names) if (m := _MOTION_UNIT.fullmatch(name))]
    if not said:
        return
    i, first = said[0]
    pairs: dict[str, str] = {}
    for name in names:
        m = _MOTION_UNIT.fullmatch(name) or _UNIT.fullmatch(name) or _COLUMN.fullmatch(name)
        if m is None:
            continue
        quantity = re.match(r"[a-z]+", m.group(1)).group(0)  # type: ignore[union-attr]
        if quantity in pairs:
            continue
        unit = m.group(m.lastindex).strip() if m.re is not _COLUMN and m.lastindex else None
        if unit in ("deg", "rad") and quantity in ("dq", "ddq"):  # a rate's unit, per second
            unit += "/s" if quantity == "dq" else "/s^2"
        key = quantity + (f"[{unit}]" if unit else "")
        pattern = name if quantity == "t" else re.sub(r"[0-9]+", "{j}", name, count=1)
        pairs[quantity] = f"{key}={pattern}"
    raise DataError(
        f"{path}: column '{names[i]}' (column {i + 1}) gives the unit of {first.group(1)} in the "
        "header, where a log states the torques' unit only (tau1[permille], tau1[Nm]): give t "
        "in s and the motion in rad (m), or read the file through a column map that states the "
        f"units (columns=), its QUANTITY=NAME pairs '{','.join(pairs.values())}'"
    )


def _remedy(path: str, width: int, extra: list, beyond: list, n: int, missing: list) -> str:
    """What to do about the unexpected columns ``extra`` ((name, index) pairs) of a log of ``width``
    columns: the reader takes no other column and has no option to skip one, so they are
    deleted from the file (a ``cut`` command that does it, when nothing else is wrong), or
    renamed when they hold what the missing ones should."""
    cols = ", ".join(
        f"{name} (column {i + 1})" if name else f"the unnamed column {i + 1}" for name, i in extra
    )
    text = (
        "; a log holds these columns only, unless a column map names the ones to read "
        "(columns=, the others then ignored): "
    )
    if missing:
        text += (
            f"rename each of {cols} that holds a missing column to its name "
            f"({', '.join(missing)}), and delete the others from the file"
        )
    else:
        skip = {i for _, i in extra}
        keep = [i + 1 for i in range(width) if i not in skip]
        runs: list[list[int]] = []  # the columns kept as cut's ranges, 1-3,5
        for k in keep:
            if runs and runs[-1][1] == k - 1:
                runs[-1][1] = k
            else:
                runs.append([k, k])
        fields = ",".join(f"{a}" if a == b else f"{a}-{b}" for a, b in runs)
        stem = path[:-4] if path.lower().endswith(".csv") else path
        text += (
            f"delete {cols} from the file, e.g. cut -d, -f{fields} {shlex.quote(path)} > "
            f"{shlex.quote(stem + '.cut.csv')}"
        )
    if beyond:
        text += f" ({', '.join(beyond)} are of joints the {n}-joint robot does not have: a log of "
        text += "another robot?)"
    return text


def read_csv(
    path,
    robot=None,
    *,
    n: int | None = None,
    torque_unit: str | None = None,
    require_torque: bool = True,
    filter: str = "butter",
    cutoff: float | None = None,
    order: int = 4,
    window: float | None = None,
    polyorder: int = 3,
    drive_gain=None,
    columns=None,
) -> JointData:
    """Read a joint log.

    Parameters
    ----------
    path : str or Path
    robot : Robot, optional
        Gives the number of joints and the drive table (needed for ``permille``).
    n : int, optional
        Number of joints when no robot is given (default: from the header).
    torque_unit : {"Nm", "permille"}, optional
        ``permille``: torques logged relative to the motor rated torque, converted with
        ``value * rated_torque * gear_ratio / 1000`` per joint. Default: the unit the header
        gives (``tau1[permille]``), else N m; a unit given here that differs from the header's
        is an error. ``current``: motor currents in A (columns ``i1..iN`` say so themselves),
        converted with the drive gains, see :func:`convert_torque`.
    require_torque : bool
        False for a trajectory file (``t, q, [dq], [ddq]``).
    filter, cutoff, order, window, polyorder
        How missing velocities / accelerations are obtained, see :func:`differentiate`; the
        samples at each end where the filter starts up are dropped
        (:func:`without_derivative_edges`, ``processing["derivative_edges"]``).
    drive_gain : array (n,), optional
        Currents: joint-side gain per joint [N m/A], instead of the drive table's (the motor
        torque constants when the description declares transmissions); a gain that is zero or
        not finite is an ArgumentError naming its joint (or motor), whatever the log holds.
        Given for a log of torques (N m or permille), which has no currents for it to convert,
        it is a DataError.
    columns : mapping, optional
        A column map (:mod:`~mindyn.identification.columns`): the file's names of mindyn's
        quantities, e.g. ``{"t[ms]": "timestamp", "q": "actual_q_{j0}", "i":
        "actual_current_{j0}"}`` (``{j}`` the joint number from 1, ``{j0}`` from 0, ``{name}``
        the joint name, or a list of names; units ``t[ms]``, ``q[deg]``, ...). The file's other
        columns are then ignored (counted and the first few named in
        ``processing["columns"]``).

    Raises
    ------
    DataFileNotFoundError
        ``path`` does not exist.
    DataError
        Wrong or missing columns, a cell that is not a decimal number in ASCII (``1_000``,
        ``0x10``, non-ASCII digits), is NaN or infinite, or overflows a double (line and column
        named), a file that is not UTF-8 text (line and byte offset named), ``drive_gain`` given
        for a log of torques, not currents, time not strictly
        increasing (line named), fewer than 2 samples (or too few beyond the derivatives'
        filter edges), derivatives that overflow, logged velocities that are not the
        positions' derivative over the time stamps (:func:`check_velocity_units`: time in ms,
        velocities in deg/s, of the opposite sign), time stamps whose median interval is 0.5 s
        or more (:func:`check_time_units`: in ms or us; not checked when a column map states
        the unit of ``t``, ``t[s]`` for a log that slow); with ``robot``, positions in degrees
        or millimetres (:func:`check_position_units`) and, for a log read for its torques,
        torques of another unit or sign than the description's inverse dynamics on the logged
        motion (:func:`~mindyn.identification.torque_units.check_torque_units`: mN m, a negated
        column; not checked when ``torque_unit``, the header or the map states N m); a column of
        the map the file lacks
        (named, with the closest names the file has). The log read with ``robot`` has
        ``units_checked`` set.
    ArgumentError
        A column map with an unknown quantity or unit, a quantity given twice, a pattern
        without placeholder for several joints, a column mapped twice.
    """
    from ..robot import Robot

    _args.path(path, "path")
    _args.optional(_args.instance, robot, "robot", Robot)
    n = _args.optional(_args.integer, n, "n", 1)
    _args.optional(_args.text, torque_unit, "torque_unit")
    require_torque = _args.flag(require_torque, "require_torque")
    _args.choice(filter, "filter", ("butter", "savgol", "none"))
    cutoff = _args.optional(_args.number, cutoff, "cutoff", positive=True)
    order = _args.integer(order, "order", 1)
    window = _args.optional(_args.number, window, "window", positive=True)
    polyorder = _args.integer(polyorder, "polyorder", 0)
    drive_gain = given_drive_gain(drive_gain, robot)
    if columns is not None:
        from .columns import column_map

        columns = column_map(columns)
        if robot is None and n is None:
            n = next((len(v) for _, v in columns.entries.values() if not isinstance(v, str)), None)
            if n is None:
                raise _args.fail(
                    "columns",
                    "needs the robot or n= (the number of joints) to fill in its patterns",
                )
        columns.names(robot.n if robot is not None else n, _joint_names(robot))
        if require_torque and "tau" not in columns.entries and "i" not in columns.entries:
            raise _args.fail(
                "columns", "has no tau or i; the torques (or currents) of the log are needed"
            )
    path = Path(path)
    if not path.is_file():
        raise DataFileNotFoundError(f"data file '{path}' does not exist")
    try:
        derivatives = dict(
            filter=filter, cutoff=cutoff, order=order, window=window, polyorder=polyorder
        )
        return _read_csv(
            path, robot, n, torque_unit, require_torque, drive_gain, derivatives, columns
        )
    except DataError as e:
        # column names from the file may hold line breaks; the message stays one line
        raise type(e)(_CONTROL.sub(lambda m: repr(m.group())[1:-1], str(e))) from None


def _joint_names(robot) -> list[str] | None:
    return None if robot is None else list(robot.joint_names)


_CONTROL = re.compile(r"[\x00-\x1f\x7f]")
_BOM = b"\xef\xbb\xbf"
# a line of text and its end: LF, CR LF or CR, as io.StringIO(text, newline="") splits lines
_LINE = re.compile(r"[^\r\n]*(?:\r\n|\r|\n)|[^\r\n]+")


class _Lines:
    """The lines of a text for ``csv.reader``, as ``io.StringIO(text, newline="")`` gives them,
    with ``end``: the offset after the last line given (where the data rows start once the
    header is read)."""

    def __init__(self, text: str):
        self._lines = _LINE.finditer(text)
        self.end = 0

    def __iter__(self):
        return self

    def __next__(self) -> str:
        line = next(self._lines)
        self.end = line.end()
        return line.group()


def _read_csv(
    path: Path, robot, n, torque_unit, require_torque, drive_gain, derivatives: dict, cmap=None
) -> JointData:
    if robot is not None:
        n = robot.n
    raw = path.read_bytes()
    text = _decoded(raw, path)
    lines = _Lines(text)
    reader = csv.reader(lines)
    try:
        try:
            header = next(reader)
        except StopIteration:
            raise DataError(f"{path}: the file is empty") from None
        while header and header[0].lstrip().startswith("#"):
            header = next(reader, [])
        if cmap is None:
            cols = _columns(header, n, require_torque, str(path))
        else:
            from .columns import mapped_columns

            cols = mapped_columns(header, cmap, robot, n, str(path), require_torque=require_torque)
        n = cols["n"]
        rows = []
        first_line = reader.line_num + 1
        # the data rows' bytes: after a byte-order mark and the header's text
        start = len(_BOM) if raw.startswith(_BOM) else 0
        start += lines.end if text.isascii() else len(text[: lines.end].encode())
        used = [cols["t"]] + [c for k in ("q", "dq", "ddq", "tau") for c in cols[k].values()]
        values = _fast_values(raw[start:], len(header), cols["t"])
        if values is None and cmap is not None:  # the columns read, without the others' cells
            values = _projected_values(raw[start:], len(header), used, cols["t"])
        for row in reader if values is None else ():
            if not row or (len(row) == 1 and not row[0].strip()):
                continue
            if len(row) != len(header):
                raise DataError(
                    f"{path}, line {reader.line_num}: {len(row)} values for {len(header)} columns"
                )
            rows.append((reader.line_num, row))
    except csv.Error as e:
        raise DataError(f"{path}, line {reader.line_num}: not readable as CSV ({e})") from None
    if values is None:
        values = _strict_values(rows, header, path, used)
    t = values[:, cols["t"]]
    r = first_not_increasing(t)
    if r is not None:
        raise DataError(
            f"{path}, line {rows[r][0]}: time is not increasing (t = {t[r]:.9g} after "
            f"{t[r - 1]:.9g})"
        )

    def block(kind):
        g = cols[kind]
        if not g:
            return None
        return values[:, [g[j] for j in range(1, n + 1)]]

    q, dq, ddq, tau = block("q"), block("dq"), block("ddq"), block("tau")
    processing: dict = {"samples": values.shape[0], "first_data_line": first_line}
    if cmap is not None:  # the map's units: seconds and radians
        from .columns import converted, record

        got, units = converted({"t": t, "q": q, "dq": dq, "ddq": ddq}, cmap, robot)
        t, q, dq, ddq = got["t"], got["q"], got["dq"], got["ddq"]
        processing["columns"] = record(cmap, cols["ignored"], units)
    # in seconds and radians (metres), a map's units converted
    if cmap is None or cmap.unit("t") is None:  # a unit the map states is taken as given
        check_time_units(t, str(path), CSV_TIME_REMEDY)
    if robot is not None:
        check_position_units(q, robot, str(path))
        beyond = positions_beyond_limits(q, robot)
        if beyond:
            processing["beyond_limits"] = beyond
    if dq is not None:
        check_velocity_units(t, q, dq, str(path))
    header_unit = cols["torque_unit"]
    said = "the header" if cmap is None else "the column map"
    if tau is not None and header_unit is not None:
        if _unit_key(header_unit) not in ("Nm", "permille", "current"):
            raise DataError(
                f"{path}: unknown torque unit '{header_unit}' in {said}; use Nm, permille "
                "or current"
            )
        if torque_unit is not None and _unit_key(torque_unit) != _unit_key(header_unit):
            raise DataError(
                f"{path}: {said} gives the torques in '{header_unit}', but the torque unit "
                f"'{torque_unit}' was asked for"
            )
        torque_unit = header_unit
    try:
        # overflow is checked below and reported once, not as numpy warnings
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            if tau is not None:
                tau, unit_info = convert_torque(
                    tau, torque_unit or "Nm", robot, drive_gain=drive_gain
                )
                processing["torque"] = unit_info
            dq, ddq, deriv = fill_derivatives(t, q, dq, ddq, **derivatives)
    except DataError as e:
        raise DataError(f"{path}: {e}") from None
    refuse_unused_gain(
        drive_gain, path, processing.get("torque"), "torque_unit='current' or columns i1..in"
    )
    processing.update(deriv)
    for what, a in (("velocities", dq), ("accelerations", ddq), ("torques", tau)):
        if a is not None and not np.isfinite(a).all():
            raise DataError(
                f"{path}: the {what} overflow (the largest logged magnitude is "
                f"{np.max(np.abs(values[:, used])):.3g}); the log's values are too large to process"
            )
    # torques stated to be in N m (torque_unit=, the header or the column map) are taken as
    # they are: the check judges them against the description, which can be far off
    stated_nm = torque_unit is not None and _unit_key(torque_unit) == "Nm"
    if robot is not None and tau is not None and require_torque and not stated_nm:
        from .torque_units import CSV_TORQUE_REMEDY, check_torque_units

        check_torque_units(t, q, dq, tau, robot, str(path), CSV_TORQUE_REMEDY)
    data = JointData(
        t, q, dq, ddq, tau, source=str(path), processing=processing, units_checked=robot is not None
    )
    return without_derivative_edges(data)


def _strict_values(rows: list, header: list[str], path: Path, used: list[int]) -> np.ndarray:
    """The cells of the columns ``used`` of ``rows`` (``(line, cells)`` pairs) parsed one by one
    by :func:`parse_cell`: the first that is not a finite decimal number raises DataError naming
    its line and column (the other columns, which a column map leaves out, are not read: NaN).
    At least 2 rows are required."""
    if len(rows) < 2:
        raise DataError(f"{path}: {len(rows)} data row(s); at least 2 samples are needed")
    names = [h.strip() for h in header]
    values = np.full((len(rows), len(header)), np.nan)
    cols = sorted(used)
    for r, (line, row) in enumerate(rows):
        for c in cols:
            values[r, c] = parse_cell(row[c], f"{path}, line {line}, column {names[c]}")
    return values


def _fast_values(data: bytes, columns: int, t_col: int) -> np.ndarray | None:
    """The data rows ``data`` (the bytes after the header) as an array (rows, ``columns``),
    parsed at once (``_core.parse_csv_numbers``: the grammar of :func:`parse_cell`, values
    correctly rounded as ``float()`` rounds them), or None when it cannot vouch that the strict
    cell-by-cell reading (:func:`_strict_values` after ``csv.reader``) gives the same array: a
    cell that is not a plain decimal number (quotes, words, other characters, a value out of the
    range of a double), a line break other than LF or CR LF, a row of another length, fewer
    than 2 rows, time (column ``t_col``) not strictly increasing. The strict reading then runs
    and names the line and column of what is wrong."""
    values = parse_csv_numbers(data, columns)
    if values is None or values.shape[0] < 2 or not np.isfinite(values).all():
        return None
    if first_not_increasing(values[:, t_col]) is not None:
        return None
    return values


def _projected_values(data: bytes, columns: int, used: list[int], t_col: int) -> np.ndarray | None:
    """The columns ``used`` of the data rows ``data`` (of ``columns`` columns each), as
    :func:`_fast_values` parses them (the other columns NaN) from the rows cut down to those
    columns, whatever the other columns hold (text, such as a robot mode); None, for the strict
    reading, when the cut could differ from the CSV reader's: quotes, a line break other than
    LF, a row of another length (a blank line), or when :func:`_fast_values` refuses the cut."""
    if b'"' in data or b"\r" in data:
        return None
    lines = data.split(b"\n")
    if lines and not lines[-1]:
        lines.pop()
    cut = []
    for line in lines:
        cells = line.split(b",")
        if len(cells) != columns:
            return None
        cut.append(b",".join([cells[c] for c in used]))
    got = _fast_values(b"\n".join(cut) + b"\n", len(used), used.index(t_col))
    if got is None:
        return None
    values = np.full((got.shape[0], columns), np.nan)
    values[:, used] = got
    return values


def parse_cell(text: str, where: str) -> float:
    """A CSV cell as a finite double: a decimal number in ASCII (``-1.25``, ``3e-4``, blanks
    around it allowed); anything else (``1_000``, ``0x10``, non-ASCII digits, NaN, infinities, a
    value too large for a double) raises DataError prefixed with ``where`` (file, line, column)."""
    if _NUMBER.fullmatch(text):
        value = float(text)
        if math.isfinite(value):
            return value
        raise DataError(f"{where}: {text.strip()!r} is too large for a double")
    if _NONFINITE.fullmatch(text):
        what = "NaN" if text.strip().lstrip("+-").lower() == "nan" else "an infinite value"
        raise DataError(f"{where}: {what}")
    raise DataError(
        f"{where}: {text.strip(_BLANKS)!r} is not a number (expected a decimal number such as "
        "-1.25 or 3e-4)"
    )


def decode_text(path: Path) -> str:
    """The file's text as UTF-8 (a leading byte-order mark is skipped), or DataError naming the
    line and byte offset of the first byte that is not UTF-8."""
    return _decoded(path.read_bytes(), path)


def _decoded(data: bytes, path: Path) -> str:
    """``data`` (of the file ``path``) as :func:`decode_text` decodes it."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line = data.count(b"\n", 0, e.start) + 1
        raise DataError(
            f"{path}, line {line}: not UTF-8 text (byte 0x{data[e.start]:02x} at offset {e.start})"
        ) from None


def read_json(path, *, what: str = "JSON file", finite: bool = False):
    """The document of a JSON file, read as :func:`decode_text` reads text: DataFileNotFoundError
    when ``path`` (the ``what``) does not exist, DataError naming the file, line and column when
    it is not JSON, or, with ``finite``, when it holds NaN or Infinity (which Python's json
    writes for undefined figures, e.g. in the JSON of ``mindyn identify``)."""
    path = Path(path)
    if not path.is_file():
        raise DataFileNotFoundError(f"{what} '{path}' does not exist")
    text = decode_text(path)
    try:
        return json.loads(text, parse_constant=_no_constant if finite else None)
    except json.JSONDecodeError as e:
        raise DataError(f"{path}:{e.lineno}:{e.colno}: not valid JSON: {e.msg}") from None
    except ValueError as e:
        raise DataError(f"{path}: {e}") from None
    except RecursionError:
        raise DataError(
            f"{path}: not a {what}: its arrays or objects are nested deeper than the JSON "
            f"reader follows (about {sys.getrecursionlimit()} levels)"
        ) from None


def _no_constant(name: str) -> float:
    raise DataError(f"holds {name}; expected finite numbers")


def first_not_increasing(t: np.ndarray) -> int | None:
    """Index of the first time that does not exceed the one before it, or None."""
    with np.errstate(over="ignore", invalid="ignore"):  # t[k] - t[k-1] may overflow to inf > 0
        bad = np.flatnonzero(np.diff(t) <= 0)
    return int(bad[0]) + 1 if bad.size else None


def _unit_key(unit: str) -> str:
    u = unit.lower().replace(" ", "")
    if u in ("nm", "n*m", "n.m", "si"):
        return "Nm"
    if u in ("permille", "‰", "promille"):
        return "permille"
    if u in ("current", "a", "amp", "ampere"):
        return "current"
    return u


def _refuse_unusable_gains(K: np.ndarray, motors=None) -> None:
    """An ArgumentError naming every gain of ``K`` given as ``drive_gain=`` that is zero or not
    finite: by joint, or by motor name when ``motors`` (the transmissions' motors, whose torque
    constants the gains then are) is given."""
    bad = np.flatnonzero(~np.isfinite(K) | (K == 0))
    if not bad.size:
        return
    if motors is not None and len(motors) == K.size:
        given = ", ".join(f"{motors[b]} = {K[b]:g}" for b in bad)
        what, unit = "the motor torque constants", "N m/A per motor"
    else:
        given = ", ".join(f"joint {b + 1} = {K[b]:g}" for b in bad)
        what, unit = "the gains", "N m/A per joint"
    raise _args.ArgumentError(
        f"drive_gain=: {what} given are zero or not finite for {given} ({unit}, non-zero; a "
        "negative one is a reversed motor)"
    )


def given_drive_gain(drive_gain, robot=None, *, size: int | None = None) -> np.ndarray | None:
    """The gains given as ``drive_gain`` (None: not given) as a float array of ``size`` entries
    (None: any), checked where they are given whether or not the log turns out to hold
    currents: a gain that is zero or not finite is an ArgumentError naming its joint, or its motor
    when ``robot`` declares transmissions (the gains are then the motors' torque constants); a
    negative gain is kept (a reversed motor)."""
    if drive_gain is None:
        return None
    K = _args.array(drive_gain, "drive_gain", (size,), unit="joint", finite=False)
    tr = getattr(robot, "transmission", None) if robot is not None else None
    _refuse_unusable_gains(K, tr.motors if tr is not None else None)
    return K


def refuse_unused_gain(drive_gain, where, torque: dict | None, remedy: str) -> None:
    """A DataError when ``drive_gain`` is given for the log ``where`` whose torques, as read
    (``torque``: its ``processing["torque"]``, None without torques), are not motor currents:
    the gains convert currents into torques, and would go unused. ``remedy``: how the log's
    currents are read instead."""
    if drive_gain is None or torque is None or torque["unit"].startswith("motor current"):
        return
    raise UnusedGainError(
        f"drive_gain=: {where} holds torques in {torque['unit']}, not motor currents, which the "
        f"gains convert into torques; expected {remedy}, or no drive_gain="
    )


def drive_gains(robot=None, *, drive_gain=None) -> tuple[np.ndarray, str]:
    """Joint-side drive gains ``K`` [N m/A per joint] that turn motor currents into joint
    torques, and where they come from: ``drive_gain`` (n,) when given, else the robot's drive
    table, ``torque_constant * gear_ratio``. A negative gain is a sign convention, kept: the
    motor's positive current drives its joint backwards (a motor wired or mounted reversed).
    Raises DataError when a gain of the drive table is missing, not finite or zero, and
    ArgumentError when a gain given is not finite or zero."""
    if drive_gain is not None:
        K = np.asarray(drive_gain, dtype=float).reshape(-1)
        if robot is not None and K.size != robot.n:
            raise DataError(f"drive gains: {K.size} values for {robot.n} joints")
        _refuse_unusable_gains(K)
        return K, "given drive gains"
    if robot is None:
        raise DataError("torque unit 'current' needs drive gains or the robot's drive table")
    drives = robot.drives
    K = drives.get("torque_constant", np.full(robot.n, np.nan)) * drives["gear_ratio"]
    bad = np.flatnonzero(~np.isfinite(K) | (K == 0))
    if bad.size:
        table = (
            "add drive: {torque_constant, gear_ratio} to its YAML or give"
            if robot.convention in ("dh", "mdh")
            else "a URDF or MJCF has no drive table: give"
        )
        raise DataError(
            f"torque unit 'current': the description of '{robot.name}' gives no torque constant "
            f"/ gear ratio for joint(s) {', '.join(str(k + 1) for k in bad)}; {table} the "
            "joint-side gains (drive_gain=, K1,...,Kn in N m/A)"
        )
    return K, "drive table: torque_constant x gear_ratio"


def current_gains(robot=None, *, drive_gain=None) -> tuple[np.ndarray, dict]:
    """The matrix ``G`` (n, n) that turns motor currents ``i`` (m, n) [A] into joint torques
    ``tau = i @ G`` [N m], and how it was formed.

    Without transmissions ``G = diag(K)`` with the joint-side gains of :func:`drive_gains`.
    When the robot's description declares transmissions (:attr:`~mindyn.Robot.transmission`),
    current i drives motor i and ``tau = T^T (K_t * i)``, i.e. ``G = diag(K_t) T``, with the
    motor-side torque constants ``K_t`` [N m/A per motor] given as ``drive_gain`` or else the
    transmission's ``torque_constant``. A negative gain or constant is kept (a reversed motor,
    as in :func:`drive_gains`), the joints or motors named in ``reversed`` of the information.
    Raises DataError when a constant of the description is missing, not finite or zero, or when
    there are not as many motors as joints, and ArgumentError when a gain given is not finite
    or zero."""
    tr = getattr(robot, "transmission", None) if robot is not None else None
    if tr is None:
        K, source = drive_gains(robot, drive_gain=drive_gain)
        return np.diag(K), {
            "scale_Nm_per_unit": K.tolist(),
            "formula": f"current x gain ({source})",
            "reversed": [f"joint {k + 1}" for k in np.flatnonzero(K < 0)],
        }
    if tr.n_motors != robot.n:
        raise DataError(
            f"motor currents: the transmissions of '{robot.name}' have {tr.n_motors} motors for "
            f"{robot.n} joints; currents are converted for as many motors as joints"
        )
    if drive_gain is not None:
        Kt = np.asarray(drive_gain, dtype=float).reshape(-1)
        source = "given motor torque constants"
        if Kt.size != tr.n_motors:
            raise DataError(f"drive gains: {Kt.size} values for {tr.n_motors} motors")
    else:
        Kt = np.array(tr.torque_constant, dtype=float)
        source = "torque constants of the transmissions"
    if drive_gain is not None:
        _refuse_unusable_gains(Kt, tr.motors)
    bad = np.flatnonzero(~np.isfinite(Kt) | (Kt == 0))
    if bad.size:
        names = ", ".join(tr.motors[b] for b in bad)
        raise DataError(
            f"motor currents: no usable torque constant for motor(s) {names} of '{robot.name}' "
            "(zero, not a finite number or not given); give the motor torque constants "
            "(drive_gain=, Kt1,...,Ktn in N m/A, motor side: the description's transmissions "
            "apply the gear ratios and couplings)"
        )
    # motors the description does not declare (a joint without a transmission beside geared
    # ones): their currents become the joint's torque at ratio 1, which is said
    direct = [m for m, ty in zip(tr.motors, tr.types) if ty == "direct"]
    return Kt[:, None] * tr.T, {
        "scale_Nm_per_unit": Kt.tolist(),
        "formula": f"T^T (torque constant x current) ({source}; T of the transmissions)",
        "transmission_T": tr.T.tolist(),
        "reversed": [f"motor {tr.motors[k]}" for k in np.flatnonzero(Kt < 0)],
        "direct": direct if len(direct) < len(tr.motors) else [],
    }


def convert_torque(tau: np.ndarray, unit: str, robot=None, *, drive_gain=None):
    """Torques in N m from the logged unit (``Nm``, ``permille``, or ``current``: motor currents
    in A times the gains of :func:`drive_gains`); returns ``(tau, info)``."""
    unit_l = _unit_key(unit)
    if unit_l == "Nm":
        return tau, {"unit": "N m"}
    if unit_l == "current":
        G, info = current_gains(robot, drive_gain=drive_gain)
        if G.shape[0] != tau.shape[1]:
            raise DataError(f"drive gains: {G.shape[0]} values for {tau.shape[1]} joints")
        return tau @ G, {"unit": "motor current [A]", **info}
    if unit_l == "permille":
        if robot is None:
            raise DataError("torque unit 'permille' needs the robot's drive table")
        drives = robot.drives
        rated, gear = drives["rated_torque"], drives["gear_ratio"]
        bad = np.flatnonzero(~(np.isfinite(rated) & np.isfinite(gear)))
        if bad.size:
            raise DataError(
                f"torque unit 'permille': the description of '{robot.name}' gives no rated "
                f"torque / gear ratio for joint(s) {', '.join(str(k + 1) for k in bad)}"
            )
        scale = rated * gear / 1000.0
        return tau * scale, {
            "unit": "permille of rated torque",
            "scale_Nm_per_unit": scale.tolist(),
            "formula": "value x rated_torque x gear_ratio / 1000",
        }
    raise DataError(f"unknown torque unit '{unit}'; use Nm, permille or current")


#: Filter edges dropped at each end, in periods of the cut-off of a zero-phase Butterworth
#: low-pass (:func:`filter_edge`; the data path's edges,
#: :func:`~mindyn.identification.preprocess.preprocess`).
EDGE_PERIODS = 2.0


def check_cutoff(fc: float, rate: float, span: float, *, source: str = "the log") -> None:
    """Refuses a low-pass cut-off ``fc`` [Hz] outside (1 / span, rate / 2): at or above half the
    sample ``rate`` there is no filter to design, and below one cycle over the log's ``span`` [s]
    a low-pass leaves little more than the mean."""
    if not 0 < fc < rate / 2:
        raise DataError(
            f"cutoff {fc:g} Hz must be between 0 and half the rate of {source} ({rate / 2:g} Hz)"
        )
    if fc * span < 1.0:
        raise DataError(
            f"cutoff {fc:g} Hz is below one cycle over {source}'s {span:g} s "
            f"({1.0 / span:.3g} Hz); expected a cutoff between {1.0 / span:.3g} Hz and half "
            f"the rate ({rate / 2:g} Hz)"
        )


def differentiate(
    t: np.ndarray,
    x: np.ndarray,
    *,
    filter: str = "butter",
    cutoff: float | None = None,
    order: int = 4,
    window: float | None = None,
    polyorder: int = 3,
):
    """Zero-phase low-pass filtered signal and its time derivative.

    Parameters
    ----------
    t : ndarray, shape (m,)
    x : ndarray, shape (m, n)
    filter : {"butter", "savgol", "none"}
        ``butter``: Butterworth of ``order`` with ``cutoff`` Hz run forwards and backwards
        (``scipy.signal.filtfilt``), then central differences (``numpy.gradient``).
        ``savgol``: Savitzky-Golay of ``polyorder`` over ``window`` seconds, derivative from the
        local polynomial. ``none``: central differences of the raw signal.
    cutoff : float, optional
        Default ``min(10 Hz, rate / 10)``.

    Returns
    -------
    (xf, dx, info) : filtered signal (m, n), derivative (m, n), settings dict.
    """
    t = _args.array(t, "t", (None,))
    # the values may overflow and the filter be unknown: DataErrors below name the log
    x = _args.array(x, "x", (t.shape[0],) + ((None,) if np.ndim(x) == 2 else ()), finite=False)
    _args.text(filter, "filter")
    cutoff = _args.optional(_args.number, cutoff, "cutoff", positive=True)
    order = _args.integer(order, "order", 1)
    window = _args.optional(_args.number, window, "window", positive=True)
    polyorder = _args.integer(polyorder, "polyorder", 0)
    m = t.shape[0]
    if m > 1 and not np.all(np.diff(t) > 0):
        k = int(np.flatnonzero(~(np.diff(t) > 0))[0])
        raise _args.fail("t", f"is not increasing (t[{k + 1}] = {t[k + 1]:.6g} after {t[k]:.6g})")
    rate = (m - 1) / (t[-1] - t[0])
    jitter = float(np.max(np.abs(np.diff(t) * rate - 1.0))) if m > 1 else 0.0
    info: dict = {"rate_Hz": rate, "timing_jitter": jitter}
    if filter == "butter":
        fc = cutoff if cutoff is not None else min(10.0, rate / 10.0)
        check_cutoff(fc, rate, float(t[-1] - t[0]))
        # Second-order sections: the (b, a) form loses the filter at low normalised cut-offs.
        sos = signal.butter(order, fc / (rate / 2), output="sos")
        taps = 3 * (2 * len(sos) + 1)
        if m <= taps:
            raise DataError(f"{m} samples are too few for a Butterworth filter of order {order}")
        # Odd extension over a few filter time constants keeps the ends from ringing.
        padlen = min(m - 1, max(taps, int(3 * rate / fc)))
        xf = signal.sosfiltfilt(sos, x, axis=0, padlen=padlen)
        info.update(
            {
                "filter": "butterworth, zero-phase (sosfiltfilt, second-order sections)",
                "order": order,
                "cutoff_Hz": fc,
                "derivative": "central differences",
            }
        )
        return xf, np.gradient(xf, t, axis=0), info
    if filter == "savgol":
        win = window if window is not None else 0.1
        w = int(round(win * rate)) | 1
        w = max(w, polyorder + 2 + (polyorder + 2) % 2 - 1)
        if w % 2 == 0:
            w += 1
        if m < w:
            raise DataError(f"{m} samples are fewer than the Savitzky-Golay window ({w})")
        dt = 1.0 / rate
        xf = signal.savgol_filter(x, w, polyorder, axis=0)
        dx = signal.savgol_filter(x, w, polyorder, deriv=1, delta=dt, axis=0)
        info.update(
            {
                "filter": "savitzky-golay",
                "window_samples": w,
                "window_s": w / rate,
                "polyorder": polyorder,
                "derivative": "of the local polynomial",
            }
        )
        return xf, dx, info
    if filter == "none":
        info.update({"filter": "none", "derivative": "central differences"})
        return x, np.gradient(x, t, axis=0), info
    raise DataError(f"unknown filter '{filter}'; use butter, savgol or none")


def filter_edge(info: dict) -> int:
    """The samples at each end of a log where the filter of one :func:`differentiate` (its
    settings ``info``) starts up, so that the filtered signal and its derivative there are not
    the motion's: ``butter``, :data:`EDGE_PERIODS` periods of the cut-off (the zero-phase
    filter's odd extension beyond the ends continues the signal and its slope but reverses its
    curvature, and the filter spreads that over its impulse response); ``savgol``, half its
    window (fitted off-centre); ``none``, 0 (central differences, one-sided at the end samples
    alone)."""
    _args.mapping(info, "info")
    if "window_samples" in info:
        return int(info["window_samples"]) // 2
    if "cutoff_Hz" in info:
        span = EDGE_PERIODS * float(info["rate_Hz"]) / float(info["cutoff_Hz"])
        return int(math.ceil(span - 1e-9))
    return 0


def fill_derivatives(t, q, dq=None, ddq=None, **settings):
    """Velocities and accelerations: logged ones are kept, missing ones derived (velocities from
    filtered positions, accelerations from filtered velocities). Returns ``(dq, ddq, info)``,
    the derivatives for every sample of ``t``; ``info["derivative_edges"]["samples"]`` counts
    the samples at each end where a derived one is not the motion's: the :func:`filter_edge`
    of each derivation taken (an acceleration from derived velocities filters the velocities'
    edge error again), 0 when both are logged. :func:`without_derivative_edges` drops them."""
    info: dict = {}
    edge = 0
    if dq is None:
        _, dq, s = differentiate(t, q, **settings)
        info["velocity"] = {"source": "differentiated positions", **s}
        edge += filter_edge(s)
    else:
        info["velocity"] = {"source": "logged"}
    if ddq is None:
        _, ddq, s = differentiate(t, dq, **settings)
        info["acceleration"] = {"source": "differentiated velocities", **s}
        edge += filter_edge(s)
    else:
        info["acceleration"] = {"source": "logged"}
    info["derivative_edges"] = {
        "samples": edge,
        "rule": "per derivation, the filter's start-up: butterworth "
        f"{EDGE_PERIODS:g} / cutoff seconds, savitzky-golay half its window, none 0",
    }
    return dq, ddq, info


def held_torque_at_samples(t: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """The torque at the time stamps ``t`` of a torque held over each sample period (a digital
    controller's command: ``tau[k]`` acts from ``t[k]`` to ``t[k+1]``).

    Held, a torque is the smooth torque it samples delayed by half a period: taken as the value
    at its own sample, it lags the motion by that much, which biases a fit of the dynamic
    model (on a simulated 6-joint arm, 2 % on an inertia, many standard deviations at low
    noise). Each held value stands for the middle of its period, ``t[k] + (t[k+1] - t[k]) / 2``;
    the torque at ``t[k]`` is the linear interpolation between the middles of the periods
    before and after it (``(tau[k-1] + tau[k]) / 2`` for evenly spaced stamps; the first
    sample extrapolated, the last period taken as long as the one before). Its error is of
    second order in the period: a relative 3e-3 at a tenth of the sample rate."""
    tau = np.asarray(tau, dtype=float)
    if tau.shape[0] < 2:
        return tau.copy()
    dt = np.diff(np.asarray(t, dtype=float))
    dt = np.append(dt, dt[-1])
    mid = np.asarray(t, dtype=float) + dt / 2  # where each held value stands
    out = np.empty_like(tau)
    w = ((t[1:] - mid[:-1]) / (mid[1:] - mid[:-1]))[:, None]
    out[1:] = tau[:-1] + w * (tau[1:] - tau[:-1])
    w0 = (t[0] - mid[0]) / (mid[1] - mid[0])  # negative: extrapolated
    out[0] = tau[0] + w0 * (tau[1] - tau[0])
    return out


def without_derivative_edges(data: JointData) -> JointData:
    """``data`` (as :func:`fill_derivatives` made its derivatives, its ``processing`` holding
    that function's ``info``) without the samples at each end where a derived derivative is
    not the motion's: ``processing["derivative_edges"]["samples"]`` dropped at each end (a
    derivative there is off the motion by the filter's start-up, and equations fitted on it
    bias the estimates by many of their standard deviations on a short log). Records
    ``seconds``, the time dropped at each end, there. DataError (naming ``data.source``) when
    fewer than 8 samples would remain."""
    _args.instance(data, "data", JointData)
    edges = data.processing.get("derivative_edges") or {"samples": 0}
    k, m = int(edges["samples"]), data.m
    if k and m - 2 * k < 8:
        raise DataError(
            f"{data.source or 'the log'}: the {k} samples at each end whose derived velocities "
            f"or accelerations are the filter's start-up leave {max(m - 2 * k, 0)} of {m} "
            "samples; give a longer log, a higher cutoff or logged derivatives"
        )
    if not k:
        return data
    edges["seconds"] = float(data.t[k] - data.t[0])
    keep = slice(k, m - k)
    return JointData(
        data.t[keep],
        data.q[keep],
        data.dq[keep],
        data.ddq[keep],
        None if data.tau is None else data.tau[keep],
        source=data.source,
        processing=data.processing,
        units_checked=data.units_checked,
    )


def _header(n: int, kinds) -> list[str]:
    return ["t"] + [f"{k}{j}" for k in kinds for j in range(1, n + 1)]


#: Significant digits of the numbers :func:`write_csv` writes.
_WRITTEN_DIGITS = 12


def _written_times(t: np.ndarray) -> np.ndarray:
    """``t`` when its time stamps are strictly increasing as :func:`write_csv` writes them (as
    :func:`read_csv` needs them), else an ArgumentError naming the first sample that is not
    later than the one before it (also where the two differ only beyond the digits written)."""
    k = first_not_increasing(t)
    if k is not None:
        raise _args.fail(
            "t",
            f"is not strictly increasing: t[{k}] = {float(t[k])!r} is not later than t[{k - 1}] = "
            f"{float(t[k - 1])!r}; expected strictly increasing time stamps",
        )
    # two stamps written alike differ by less than one unit of the last digit written
    unit = 10.0 ** (1 - _WRITTEN_DIGITS) * np.maximum(np.abs(t[1:]), np.abs(t[:-1]))
    for k in np.flatnonzero(np.diff(t) <= unit) + 1:
        a, b = (f"{x:.{_WRITTEN_DIGITS}g}" for x in (t[k - 1], t[k]))
        if a == b:
            raise _args.fail(
                "t",
                f"is not strictly increasing as written ({_WRITTEN_DIGITS} significant digits): "
                f"t[{k}] = {float(t[k])!r} and t[{k - 1}] = {float(t[k - 1])!r} are both "
                f"written {a}; expected time stamps that differ in the digits written",
            )
    return t


def write_csv(path, t, q, tau, dq=None, ddq=None, *, torque_unit: str | None = None) -> Path:
    """Write ``t, q1..qn, [dq1..dqn], [ddq1..ddqn], tau1..taun``; shapes (m,) and (m, n). With
    ``torque_unit`` (e.g. ``"permille"``) the torque columns say it: ``tau1[permille]``. Numbers
    are written with 12 significant digits; time stamps that are not strictly increasing as
    written (which :func:`read_csv` refuses) are an ArgumentError naming the first such
    sample."""
    _args.path(path, "path")
    t = _written_times(_args.array(t, "t", (None,)))
    arrays = [t[:, None], _args.array(q, "q", (t.shape[0], None))]
    kinds = ["q"]
    n = arrays[1].shape[1]
    for kind, a in (("dq", dq), ("ddq", ddq), ("tau", tau)):
        if a is not None:
            arrays.append(_args.array(a, kind, (t.shape[0], n)))
            kinds.append(kind)
    _args.optional(_args.text, torque_unit, "torque_unit")
    header = _header(n, kinds)
    if torque_unit is not None and tau is not None:
        header = [f"{h}[{torque_unit}]" if h.startswith("tau") else h for h in header]
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savetxt(
        path,
        np.hstack(arrays),
        delimiter=",",
        header=",".join(header),
        comments="",
        fmt=f"%.{_WRITTEN_DIGITS}g",
    )
    return path


def write_trajectory_csv(path, t, q, dq, ddq) -> Path:
    """Write a reference trajectory ``t, q, dq, ddq`` (no torques)."""
    return write_csv(path, t, q, None, dq=dq, ddq=ddq)


def truth_path(csv_path) -> Path:
    """``data.csv`` -> ``data.truth.json``: the true parameters of a simulated log."""
    _args.path(csv_path, "csv_path")
    p = Path(csv_path)
    return p.with_name(p.stem + ".truth.json")


def read_truth(csv_path, robot=None) -> dict | None:
    """The truth sidecar of a simulated log, or None when there is none. With ``robot``, a
    sidecar that names another robot (``robot``) or other joints (``joints``, in order) than
    ``robot``'s is refused: the log was simulated for another robot, whatever its joint
    count."""
    from ..robot import Robot

    _args.path(csv_path, "csv_path")
    _args.optional(_args.instance, robot, "robot", Robot)
    p = truth_path(csv_path)
    if not p.is_file():
        return None
    d = read_json(p, what="truth file")
    if not isinstance(d, dict):
        raise DataError(f"{p}: a truth file is a JSON object")
    if "names" not in d or "values" not in d:
        raise DataError(f"{p}: a truth file needs 'names' and 'values'")
    names, values = d["names"], d["values"]
    if not (isinstance(names, list) and all(isinstance(n, str) for n in names)):
        raise DataError(f"{p}: 'names' must be a list of parameter names")
    if not isinstance(values, list) or len(values) != len(names):
        count = len(values) if isinstance(values, list) else "not a list of"
        raise DataError(f"{p}: 'values' holds {count} values for {len(names)} names")
    bad = [
        (n, v)
        for n, v in zip(names, values)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v)
    ]
    if bad:
        raise DataError(f"{p}: the value of {bad[0][0]} is {bad[0][1]!r}; expected a finite number")
    if robot is not None:
        check_log_robot(d, robot, f"{csv_path} (simulated, as {p} says)")
    return d


#: How far (m, and rad through the rotation's entries) a link frame at q = 0 of a truth sidecar
#: may sit from the identified description's before its classical values are taken as another
#: frame's: above the rounding of right angles a CAD export writes (3e-8).
LINK_FRAME_TOLERANCE = 1e-6


def link_frames(robot) -> list[list[float]] | None:
    """Each link's frame at q = 0 in the base frame, the top three rows of its pose row by row
    (12 numbers): the frames a truth sidecar's classical values are about. None for a robot
    with joints of several degrees of freedom (no zero configuration of the same meaning)."""
    if not robot.single_dof:
        return None
    q = np.zeros(robot.nq)
    return [[float(v) for v in np.asarray(robot.fk(q, link=k))[:3].ravel()] for k in range(robot.n)]


def other_link_frames(doc: dict, robot) -> str | None:
    """Why the classical values of a truth sidecar ``doc`` are about other link frames than
    ``robot``'s (a description of the same robot and joints written with other frames, such as
    a URDF and a DH table of one arm), or None when they are its own or ``doc`` does not say."""
    frames = doc.get("link_frames")
    ours = link_frames(robot)
    if frames is None or ours is None:
        return None
    try:
        theirs = np.asarray(frames, dtype=float)
    except (TypeError, ValueError):
        theirs = None
    if theirs is None or theirs.shape != (robot.n, 12) or not np.all(np.isfinite(theirs)):
        return f"its link_frames are not {robot.n} frames of 12 finite numbers"
    gap = np.max(np.abs(theirs - np.asarray(ours)), axis=1)
    if not np.any(gap > LINK_FRAME_TOLERANCE):
        return None
    k = int(np.argmax(gap > LINK_FRAME_TOLERANCE))
    return (
        f"the simulated description's frame of link '{robot.link_names[k + 1]}' at q = 0 is "
        f"off this description's by {gap[k]:.3g} (m, or rotation entries)"
    )


def check_log_robot(doc: dict, robot, where: str) -> None:
    """Refuses a document (a truth sidecar, an identification JSON) whose ``robot`` name or
    ``joints`` names differ from ``robot``'s; either field may be absent (or an empty name)."""
    from ..robot import Robot

    _args.mapping(doc, "doc")
    _args.instance(robot, "robot", Robot)
    _args.text(where, "where")
    name = doc.get("robot")
    if name not in (None, "") and name != robot.name:
        raise DataError(
            f"{where}: belongs to robot {_shown(name)}, not '{robot.name}' (a log of another "
            "robot, even with as many joints, tells nothing of this one)"
        )
    check_joint_names(doc.get("joints"), robot, where)


def check_joint_names(
    joints, robot, where: str, *, error: type[Exception] = DataError, hint: str = ""
) -> None:
    """Refuses (``error``, naming ``where``) the joint names a document records (``joints``;
    None: not recorded) when they are not ``robot``'s: another count (the names on both
    sides, then ``hint``), or the joints whose names differ (each as the document and the robot
    name it)."""
    if joints is None:
        return
    own = list(robot.joint_names)
    if not (isinstance(joints, list) and all(isinstance(j, str) for j in joints)):
        raise error(f"{where}: 'joints' is {_shown(joints)}; expected a list of joint names")
    if len(joints) != len(own):
        raise error(
            f"{where}: made for {len(joints)} joints {_shown(joints)}; robot '{robot.name}' has "
            f"{len(own)} {_shown(own)}{hint}"
        )
    differ = [k for k in range(len(own)) if joints[k] != own[k]]
    if differ:
        pairs = "; ".join(f"joint {k + 1} '{joints[k]}' there, '{own[k]}' here" for k in differ[:4])
        more = f" and {len(differ) - 4} more" if len(differ) > 4 else ""
        raise error(f"{where}: its joints are not those of robot '{robot.name}': {pairs}{more}")


#: Per joint type: the unit of a log's positions, the unit a log is most often written in by
#: mistake, that unit's size in the right one, and a magnitude that a position in the right
#: unit outside the joint's limits rarely reaches (a full turn, a metre).
_MISTAKEN_UNITS = {
    "revolute": ("rad", "degrees", math.pi / 180.0, 2.0 * math.pi),
    "prismatic": ("m", "millimetres", 1e-3, 1.0),
}


def check_position_units(q, robot, source: str) -> None:
    """Refuses joint positions ``q`` (samples x joints) that are in degrees (millimetres for
    prismatic joints) instead of radians (metres): some joint of that type leaves its limits by
    more than half their range and reaches beyond a full turn (1 m), and read in that unit
    every joint of the type with limits lies within them to the same margin. A log that only
    oversteps a description's limits (a calibration offset, a limit set tighter than the
    hardware's) is not refused. Robots with joints of several degrees of freedom are not
    checked (their positions hold quaternions)."""
    from ..robot import Robot

    _args.instance(robot, "robot", Robot)
    q = np.asarray(q, dtype=float)
    if not robot.single_dof or q.ndim != 2 or q.shape[1] != robot.n or q.shape[0] == 0:
        return
    lower, upper = robot.limits["lower"], robot.limits["upper"]
    lo, hi = q.min(axis=0), q.max(axis=0)
    for kind, (unit, other, size, far) in _MISTAKEN_UNITS.items():
        joints = [
            k
            for k, t in enumerate(robot.joint_types)
            if t == kind and np.isfinite(lower[k]) and np.isfinite(upper[k]) and upper[k] > lower[k]
        ]
        if not joints:
            continue
        margin = {k: 0.5 * (upper[k] - lower[k]) for k in joints}
        out = [
            k
            for k in joints
            if (lo[k] < lower[k] - margin[k] or hi[k] > upper[k] + margin[k])
            and max(-lo[k], hi[k]) > far
        ]
        inside = all(
            lo[k] * size >= lower[k] - margin[k] and hi[k] * size <= upper[k] + margin[k]
            for k in joints
        )
        if not out or not inside:
            continue
        k = out[0]
        v = lo[k] if lower[k] - lo[k] > hi[k] - upper[k] else hi[k]
        raise DataError(
            f"{source}: the positions of joint {k + 1} ('{robot.joint_names[k]}') reach {v:.4g}, "
            f"beyond its limits [{lower[k]:.4g}, {upper[k]:.4g}] {unit} by more than half their "
            f"range and beyond {far:.4g} {unit}, and read as {other} every {kind} joint's "
            "positions lie within its limits: "
            f"its positions seem to be in {other}; convert its {kind} joints' positions, "
            f"velocities and accelerations to {unit}"
        )


def positions_beyond_limits(q, robot) -> list[dict]:
    """The joints whose positions ``q`` (samples x joints, rad or m) leave the description's
    finite limits by more than their range: a log of another robot, another zero position or
    limits other than the robot's, which the fit takes as they are (a log that only oversteps
    the limits a little, a limit set tighter than the hardware's, is not named). Per joint:
    ``joint`` (from 1), ``name``, ``reached`` (the position farthest out), ``lower``,
    ``upper``, ``unit``. Robots with joints of several degrees of freedom give none."""
    from ..robot import Robot

    _args.instance(robot, "robot", Robot)
    q = np.asarray(q, dtype=float)
    if not robot.single_dof or q.ndim != 2 or q.shape[1] != robot.n or q.shape[0] == 0:
        return []
    lower = np.asarray(robot.limits["lower"], dtype=float)
    upper = np.asarray(robot.limits["upper"], dtype=float)
    found = []
    with np.errstate(invalid="ignore"):
        lo, hi = np.nanmin(q, axis=0), np.nanmax(q, axis=0)
    for k in range(robot.n):
        span = upper[k] - lower[k]
        if not (np.isfinite(span) and span > 0):
            continue
        below, above = lower[k] - lo[k], hi[k] - upper[k]
        if max(below, above) > span:
            found.append(
                {
                    "joint": k + 1,
                    "name": robot.joint_names[k],
                    "reached": float(lo[k] if below > above else hi[k]),
                    "lower": float(lower[k]),
                    "upper": float(upper[k]),
                    "unit": "m" if robot.joint_types[k] == "prismatic" else "rad",
                }
            )
    return found


def describe_beyond_limits(source: str, found: list[dict]) -> str:
    """The warning of :func:`positions_beyond_limits`' joints ``found`` in log ``source``."""
    first = found[0]
    others = [str(f["joint"]) for f in found[1:]]
    return (
        f"{source}: the positions of joint {first['joint']} ('{first['name']}') reach "
        f"{first['reached']:.4g} {first['unit']}, beyond its limits [{first['lower']:.4g}, "
        f"{first['upper']:.4g}] by more than their range"
        + (f" (joint(s) {', '.join(others)} alike)" if others else "")
        + ": a log of another robot, another zero position or limits other than the robot's? "
        "The fit takes the positions as they are"
    )


#: A joint whose logged velocity and the derivative of its logged position correlate at least
#: this much is in the velocity check; the ratio of the two must lie within these bounds.
VELOCITY_CHECK_CORRELATION = 0.9
VELOCITY_RATIO_BOUNDS = (0.2, 5.0)
#: Fewest samples for that correlation to judge (two unrelated signals of 20 samples correlate
#: that much with a probability of about 1e-7)
VELOCITY_CHECK_SAMPLES = 20


def check_velocity_units(t, q, dq, source: str) -> None:
    """Refuses logged velocities ``dq`` that are not the derivative of the logged positions
    ``q`` over the time stamps ``t`` (samples x joints): per joint whose two signals correlate
    (:data:`VELOCITY_CHECK_CORRELATION`, in magnitude: a joint held still is not judged; a log
    of fewer than :data:`VELOCITY_CHECK_SAMPLES` samples neither), the
    least-squares ratio ``d/dt q ~ k dq`` must lie within :data:`VELOCITY_RATIO_BOUNDS`. Time
    stamps in milliseconds give k = 1e-3, velocities in deg/s beside positions in rad 1/57.3, a
    velocity of the opposite sign -1; real logs give k within 1 % of 1."""
    t, q, dq = (np.asarray(a, dtype=float) for a in (t, q, dq))
    if t.size < VELOCITY_CHECK_SAMPLES or q.shape != dq.shape:
        return
    with np.errstate(all="ignore"):
        fd = np.gradient(q, t, axis=0)
        fd0, dq0 = fd - fd.mean(axis=0), dq - dq.mean(axis=0)
        corr = (fd0 * dq0).sum(axis=0) / np.sqrt((fd0**2).sum(axis=0) * (dq0**2).sum(axis=0))
        k = (fd * dq).sum(axis=0) / (dq**2).sum(axis=0)
    low, high = VELOCITY_RATIO_BOUNDS
    for j in range(q.shape[1]):
        if not (np.isfinite(corr[j]) and np.isfinite(k[j])):
            continue
        if abs(corr[j]) >= VELOCITY_CHECK_CORRELATION and not low <= k[j] <= high:
            causes = (
                "a velocity column of the opposite sign"
                if k[j] < 0
                else "time stamps in milliseconds (1000), velocities in degrees per second "
                "beside positions in radians (57.3), or other units"
            )
            raise DataError(
                f"{source}: the velocity dq{j + 1} is {1 / k[j]:.4g} times the derivative "
                f"of q{j + 1} over the time stamps (correlation {corr[j]:.3f}; expected 1): "
                f"{causes}; t in s, positions in rad (m), velocities in rad/s (m/s)"
            )


#: A log whose median sample interval is at least this [s] is refused (slower than 2 Hz: too
#: slow to carry accelerations; time stamps in ms of a log of up to 2 kHz have intervals of at
#: least 0.5)
SLOWEST_SAMPLE_INTERVAL = 0.5
#: The units time stamps are logged in by mistake, and their size in s
_MISTAKEN_TIME_UNITS = (("milliseconds", 1e-3), ("microseconds", 1e-6), ("nanoseconds", 1e-9))


def check_time_units(t, source: str, remedy: str) -> None:
    """Refuses time stamps ``t`` (read as s) whose median sample interval is at least
    :data:`SLOWEST_SAMPLE_INTERVAL`: a log slower than 2 Hz cannot carry accelerations, and a
    log of up to 2 kHz whose stamps are in milliseconds (microseconds, nanoseconds) has such
    intervals. The message names the median interval, the unit that makes the log's rate at
    least 2 Hz and that rate, and ends with ``remedy`` (how to give the stamps' unit)."""
    t = np.asarray(t, dtype=float).ravel()
    if t.size < 2:
        return
    with np.errstate(all="ignore"):
        dt = float(np.median(np.diff(t)))
    if not (np.isfinite(dt) and dt >= SLOWEST_SAMPLE_INTERVAL):
        return
    unit, size = next(
        ((u, s) for u, s in _MISTAKEN_TIME_UNITS if dt * s < SLOWEST_SAMPLE_INTERVAL),
        _MISTAKEN_TIME_UNITS[-1],
    )
    raise DataError(
        f"{source}: the median interval between its time stamps is {dt:.4g} s, a log slower "
        f"than {1 / SLOWEST_SAMPLE_INTERVAL:g} Hz, which cannot carry accelerations: its time "
        f"stamps seem to be in {unit} (a log of {1 / (dt * size):.4g} Hz); {remedy}"
    )


#: How a CSV log states the unit of its time stamps
CSV_TIME_REMEDY = (
    "give t in s, or state its unit in a column map, columns= with t[ms], t[us] or t[ns] "
    "(t[s] for a log this slow)"
)


def check_units(data: JointData, robot, label: str) -> None:
    """The unit checks of a log read from a file, on a :class:`JointData` built otherwise
    (``label``: its name in the message, such as ``data[0]``): time stamps in s
    (:func:`check_time_units`), positions in rad or m (:func:`check_position_units`),
    velocities the positions' derivative (:func:`check_velocity_units`), torques in N m of
    the description's sign (:func:`~mindyn.identification.torque_units.check_torque_units`).
    Once they pass,
    ``data.units_checked`` is set; a log with it set is not checked again."""
    if data.units_checked:
        return
    name = f"{label} ('{data.source}')" if data.source else label
    check_time_units(
        data.t,
        name,
        "JointData.t is in s: convert it, or give JointData(..., units_checked=True) for a "
        "log this slow",
    )
    check_position_units(data.q, robot, name)
    if data.dq is not None:
        check_velocity_units(data.t, data.q, data.dq, name)
    if data.tau is not None and data.dq is not None:
        from .torque_units import JOINT_DATA_TORQUE_REMEDY, check_torque_units

        check_torque_units(data.t, data.q, data.dq, data.tau, robot, name, JOINT_DATA_TORQUE_REMEDY)
    data.units_checked = True


def _shown(value) -> str:
    """A JSON value in a message: text quoted, lists joined, anything else as JSON."""
    if isinstance(value, str):
        return repr(value)
    if isinstance(value, list) and all(isinstance(v, str) for v in value):
        return "(" + ", ".join(value) + ")"
    text = json.dumps(value)
    return text if len(text) <= 60 else text[:57] + "..."


def finite_or_none(x) -> float | None:
    """JSON helper: a float, or None for NaN / inf."""
    x = float(x)
    return x if math.isfinite(x) else None


def check_distinct_logs(files: Sequence[str], validate: Sequence[str] = ()) -> None:
    """DataError (one line naming both) when a fit log is given twice, or a validation log
    is one of the fit logs or given twice: the same file (its resolved path) or files of the
    same bytes. A fit log twice fits its samples twice (its rows counted as independent twice
    over: other estimates, smaller standard deviations); validation on fitted data says nothing
    of other data. Paths that do not exist are left to the reader's error."""
    seen: list[tuple[str, str, Path]] = []  # (role, given path, resolved path)
    digests: dict[Path, str] = {}

    def same(a: Path, b: Path) -> str | None:
        if a == b:
            return "is"
        if not (a.is_file() and b.is_file()) or a.stat().st_size != b.stat().st_size:
            return None
        for p in (a, b):
            if p not in digests:
                digests[p] = hashlib.sha256(p.read_bytes()).hexdigest()
        return "has the same content as" if digests[a] == digests[b] else None

    for role, paths in (("fit log", files), ("validation log", validate)):
        for given in paths:
            resolved = Path(given).resolve()
            if resolved.exists():
                for other_role, other, where in seen:
                    said = same(resolved, where)
                    if said is None:
                        continue
                    if role == other_role:
                        raise DataError(
                            f"{given}: given twice as a {role}"
                            + ("" if said == "is" else f" ({said} '{other}')")
                            + (
                                ": its samples would be fitted twice"
                                if role == "fit log"
                                else ": it would be scored twice"
                            )
                        )
                    raise DataError(
                        f"{given}: the validation log {said} the fit log '{other}': validation "
                        "on the fitted data says nothing of other data (give a log not fitted)"
                    )
                seen.append((role, str(given), resolved))
