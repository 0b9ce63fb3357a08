"""Column maps: a log written by a controller under its own column names, read without
rewriting it.

A map takes mindyn's quantities to the file's names: ``{"t": "timestamp", "q": "actual_q_{j0}",
"dq": "actual_qd_{j0}", "i": "actual_current_{j0}"}``. Quantities: ``t`` (time), ``q``, ``dq``,
``ddq`` (positions, velocities, accelerations), ``tau`` (torques) or ``i`` (motor currents in A,
converted as columns ``i1..iN`` are). A joint quantity's name is a pattern holding ``{j}`` (the
joint's number from 1), ``{j0}`` (from 0) or ``{name}`` (the robot's joint name), or a list of
the N names one by one; ``t`` names one column. A unit in brackets after the quantity says how
the file holds it: ``t[ms]`` (``s``, ``ms``, ``us``, ``ns``: divided by 1, 1e3, 1e6, 1e9),
``q[deg]``, ``dq[deg/s]``, ``ddq[deg/s^2]`` (the revolute joints' values times pi / 180,
``numpy.deg2rad``; a prismatic joint's stay in m), ``tau[permille]`` (as ``tau1[permille]`` in a
header). The map gives every quantity read: ``t`` and ``q`` always, the derivatives it lacks are
derived from the positions, and the file's other columns are ignored (counted in
``processing["columns"]``).
"""

from __future__ import annotations

import difflib
import re
from dataclasses import dataclass

import numpy as np

from .. import _args
from .data import DataError

__all__ = ["ColumnMap", "QUANTITIES", "column_map"]

#: The quantities a column map names, in the order of a log.
QUANTITIES = ("t", "q", "dq", "ddq", "tau", "i")

#: The time units of ``t[unit]``: the divisor that gives seconds.
TIME_UNITS = {"s": 1.0, "ms": 1e3, "us": 1e6, "µs": 1e6, "ns": 1e9}

#: The units of the joint quantities in a map (the first of each: the unit read without one).
JOINT_UNITS = {
    "q": ("rad", "deg"),
    "dq": ("rad/s", "deg/s"),
    "ddq": ("rad/s^2", "deg/s^2"),
    "tau": ("Nm", "permille", "current"),
    "i": ("A",),
}

_KEY = re.compile(r"\s*([A-Za-z_][A-Za-z0-9_]*)\s*(?:\[([^\]]*)\])?\s*")
_PLACEHOLDER = re.compile(r"\{([^{}]*)\}")
_PLACEHOLDERS = ("j", "j0", "name")
#: How many of the columns a map leaves out are named in the output.
SHOWN_IGNORED = 5


def _fail(message: str) -> _args.ArgumentError:
    return _args.fail("columns", message)


def _unit(quantity: str, unit: str | None) -> str | None:
    """The unit ``unit`` of ``quantity`` as a map gives it, checked (None: none given)."""
    if unit is None:
        return None
    u = unit.strip().replace(" ", "")
    known = tuple(TIME_UNITS) if quantity == "t" else JOINT_UNITS[quantity]
    if quantity == "tau" and u.lower() in ("nm", "n*m", "n.m", "permille", "‰", "current"):
        return u
    u = u.replace("s2", "s^2") if quantity == "ddq" else u
    if u not in known:
        raise _fail(
            f"gives {quantity} in '{unit}'; the units of {quantity} are " + ", ".join(known)
        )
    return u


@dataclass(frozen=True)
class ColumnMap:
    """A column map, checked: ``entries`` quantity -> (unit or None, name pattern or tuple of
    names), in the order of :data:`QUANTITIES`. :meth:`record` is the map as given (for the
    JSON), :meth:`names` the file's names of each quantity for a robot."""

    entries: dict

    def record(self) -> dict:
        """The map as a plain mapping, its keys with their units (``t[ms]``), lists for names
        given one by one."""
        return {
            (q if u is None else f"{q}[{u}]"): (v if isinstance(v, str) else list(v))
            for q, (u, v) in self.entries.items()
        }

    def unit(self, quantity: str) -> str | None:
        entry = self.entries.get(quantity)
        return None if entry is None else entry[0]

    def without(self, quantity: str) -> ColumnMap:
        """The map without ``quantity`` (a log whose currents come from a file of their own)."""
        return ColumnMap({q: e for q, e in self.entries.items() if q != quantity})

    def names(self, n: int, joint_names=None) -> dict[str, list[str]]:
        """The file's names of each quantity of the map for ``n`` joints named ``joint_names``
        (needed by ``{name}``): ``t`` one, the others ``n`` each. ArgumentError for a pattern
        that names one column for several joints, a list of another length, ``{name}`` without
        joint names, a column named twice."""
        out: dict[str, list[str]] = {}
        for q, (_, value) in self.entries.items():
            if q == "t":
                out[q] = [value]
            elif isinstance(value, str):
                out[q] = _expanded(q, value, n, joint_names)
            elif len(value) != n:
                raise _fail(
                    f"gives {len(value)} names of {q} for a robot of {n} joints; expected one per "
                    "joint, in order"
                )
            else:
                out[q] = list(value)
        where: dict[str, str] = {}
        for q, names in out.items():
            for j, name in enumerate(names):
                what = q if q == "t" else f"{q}{j + 1}"
                if name in where:
                    raise _fail(f"maps column '{name}' twice ({where[name]} and {what})")
                where[name] = what
        return out


def _expanded(quantity: str, pattern: str, n: int, joint_names) -> list[str]:
    """The ``n`` names of ``pattern`` with ``{j}``, ``{j0}`` or ``{name}`` filled in."""
    found = _PLACEHOLDER.findall(pattern)
    if not found:
        if n == 1:
            return [pattern]
        raise _fail(
            f"maps {quantity} to the one column '{pattern}' for {n} joints; a pattern holds "
            "{j} (joint number from 1), {j0} (from 0) or {name} (joint name), or give a list "
            f"of {n} names"
        )
    if "name" in found and joint_names is None:
        raise _fail(f"{quantity}='{pattern}': {{name}} needs the robot (its joint names)")

    def one(j: int) -> str:
        values = {"j": str(j + 1), "j0": str(j), "name": joint_names[j] if joint_names else ""}
        return _PLACEHOLDER.sub(lambda m: values[m.group(1)], pattern)

    return [one(j) for j in range(n)]


def column_map(columns) -> ColumnMap:
    """``columns`` (a mapping quantity -> file name, pattern or list of names, or a
    :class:`ColumnMap`) checked: ArgumentError naming an unknown quantity or unit, a quantity
    given twice (``q`` and ``q[deg]``), torques and currents both, a map without ``t`` or ``q``,
    a name that is not text, an empty name, a placeholder other than ``{j}``, ``{j0}``,
    ``{name}``, one in ``t``."""
    if isinstance(columns, ColumnMap):
        return columns
    _args.mapping(columns, "columns")
    entries: dict = {}
    keys: dict[str, str] = {}
    for key, value in columns.items():
        m = _KEY.fullmatch(key) if isinstance(key, str) else None
        if m is None or m.group(1) not in QUANTITIES:
            raise _fail(
                f"names the quantity {key!r}; expected t, q, dq, ddq, tau or i (a unit in "
                "brackets after it: t[ms], q[deg])"
            )
        q = m.group(1)
        if q in keys:
            raise _fail(f"gives {q} twice ({keys[q]!r} and {key!r})")
        keys[q] = key
        entries[q] = (_unit(q, m.group(2)), _value(q, value))
    if "tau" in entries and "i" in entries:
        raise _fail("gives both tau and i; the torques come from one of them")
    missing = [q for q in ("t", "q") if q not in entries]
    if missing:
        raise _fail(
            f"has no {' or '.join(missing)}; a map names the time and position columns (and the "
            "velocities, accelerations, torques or currents the log has)"
        )
    return ColumnMap({q: entries[q] for q in QUANTITIES if q in entries})


def _value(quantity: str, value):
    """A map's value for ``quantity``: a name or pattern (text), or a list of names (taken as
    written)."""
    if isinstance(value, str):
        names = [value]
    elif isinstance(value, (list, tuple)) and quantity != "t":
        names = list(value)
        if not names:
            raise _fail(f"gives an empty list for {quantity}")
    else:
        expected = (
            "a column name" if quantity == "t" else "a column name pattern or a list of names"
        )
        _args.instance(value, f"columns {quantity}", str, expected)  # raises: it is not text
        names = []
    for name in names:
        _args.instance(name, f"columns {quantity}", str, "text (a column name)")
        if not name.strip():
            raise _fail(f"gives an empty column name for {quantity}")
    if not isinstance(value, str):
        return tuple(value)
    if "{" in _PLACEHOLDER.sub("", value) or "}" in _PLACEHOLDER.sub("", value):
        raise _fail(f"{quantity}={value!r} has an unmatched brace")
    found = _PLACEHOLDER.findall(value)
    bad = [p for p in found if p not in _PLACEHOLDERS]
    if bad:
        raise _fail(
            f"{quantity}={value!r} holds the placeholder {{{bad[0]}}}; expected {{j}} (joint "
            "number from 1), {j0} (from 0) or {name} (joint name)"
        )
    if found and quantity == "t":
        raise _fail(f"t={value!r} holds the placeholder {{{found[0]}}}; t names one column")
    return value


def mapped_columns(
    header: list[str], cmap: ColumnMap, robot, n: int, path: str, *, require_torque: bool = True
) -> dict:
    """The columns of a log's ``header`` that ``cmap`` names, as the reader's column table
    (``t`` its index; ``q``, ``dq``, ``ddq``, ``tau`` joint -> index; ``torque_unit``), with
    ``ignored`` the names of the file's other columns. Without ``require_torque`` (a log whose
    torques are optional) the map's torque or current columns are read when the file has any of
    them. DataError naming a mapped name the file lacks (with its quantity and the closest names
    the file has) or has twice."""
    from .data import check_header

    names = check_header(header, path, "the columns of the column map")
    joint_names = list(robot.joint_names) if robot is not None else None
    wanted = cmap.names(n, joint_names)
    for q in ("tau", "i"):
        if not require_torque and q in wanted and not set(wanted[q]) & set(names):
            del wanted[q]
    index: dict[str, int] = {}
    for k, h in enumerate(names):
        index.setdefault(h, k)
    groups: dict[str, dict[int, int]] = {"q": {}, "dq": {}, "ddq": {}, "tau": {}}
    used = set()
    t_col = -1
    for q, cols in wanted.items():
        for j, name in enumerate(cols):
            what = "t" if q == "t" else f"{q}{j + 1}"
            if name not in index:
                raise DataError(f"{path}: {missing_column(name, what, names)}")
            if names.count(name) > 1:
                raise DataError(
                    f"{path}: column '{name}' ({what} of the column map) appears twice in the "
                    "header"
                )
            used.add(index[name])
            if q == "t":
                t_col = index[name]
            else:
                groups["tau" if q == "i" else q][j + 1] = index[name]
    unit = "current" if "i" in wanted else cmap.unit("tau") if "tau" in wanted else None
    ignored = [h for k, h in enumerate(names) if k not in used]
    return {"t": t_col, "n": n, "torque_unit": unit, **groups, "ignored": ignored}


def missing_column(name: str, what: str, names: list[str]) -> str:
    """A mapped name the file lacks, with the closest names it has."""
    close = difflib.get_close_matches(name, [h for h in names if h], n=3, cutoff=0.6)
    said = f"no column '{name}' ({what} of the column map)"
    if close:
        return said + "; the closest the file has: " + ", ".join(f"'{c}'" for c in close)
    shown = ", ".join(f"'{h}'" for h in names[:SHOWN_IGNORED])
    more = ", ..." if len(names) > SHOWN_IGNORED else ""
    return said + f"; none of the file's {len(names)} columns is close ({shown}{more})"


def converted(values: dict, cmap: ColumnMap, robot) -> tuple[dict, dict]:
    """The arrays ``values`` (``t`` (m,), joint quantities (m, n) or None) in seconds and rad:
    the units of ``cmap`` applied. Returns the arrays and what was done, for
    ``processing["columns"]``."""
    out = dict(values)
    done: dict = {}
    t_unit = cmap.unit("t")
    if t_unit not in (None, "s"):
        out["t"] = values["t"] / TIME_UNITS[t_unit]
        done["t"] = f"t in {t_unit}, divided by {TIME_UNITS[t_unit]:g}"
    for q in ("q", "dq", "ddq"):
        unit = cmap.unit(q)
        if unit is None or not unit.startswith("deg") or values.get(q) is None:
            continue
        if robot is None:
            raise _fail(
                f"gives {q} in {unit}: the conversion needs the robot (its revolute joints)"
            )
        revolute = np.array([t == "revolute" for t in robot.joint_types[: values[q].shape[1]]])
        a = values[q].copy()
        a[:, revolute] = np.deg2rad(a[:, revolute])
        out[q] = a
        joints = [str(j + 1) for j in np.flatnonzero(revolute)]
        done[q] = (
            f"{q} in {unit}, x pi / 180 (numpy.deg2rad) on revolute joint(s) {', '.join(joints)}"
            if joints
            else f"{q} in {unit}: no revolute joint (prismatic values in m, unchanged)"
        )
    return out, done


def record(cmap: ColumnMap, ignored: list[str], units: dict) -> dict:
    """``processing["columns"]``: the map read with, the columns it left out (how many, the
    first few), the unit conversions."""
    return {
        "map": cmap.record(),
        "ignored": len(ignored),
        "ignored_first": ignored[:SHOWN_IGNORED],
        "units": units,
    }


def describe(info: dict) -> str:
    """``processing["columns"]`` in words: the map, the columns ignored, the conversions."""
    pairs = ", ".join(
        f"{k}={v if isinstance(v, str) else '[' + ' '.join(v) + ']'}"
        for k, v in info["map"].items()
    )
    k = info["ignored"]
    first = info["ignored_first"]
    shown = ", ".join(first) + (", ..." if k > len(first) else "")
    text = f"columns mapped: {pairs}; {k} other column(s) ignored" + (f" ({shown})" if k else "")
    if info["units"]:
        text += "; " + "; ".join(info["units"].values())
    return text
