"""``--columns``: the column map of the commands that read joint logs (identify,
identify-payload, predict, detect), given inline (``t[ms]=timestamp,q=actual_q_{j0},...``) or
as a YAML file of the same mapping; the library's
:func:`~mindyn.identification.columns.column_map` checks it."""

from __future__ import annotations

import argparse
from pathlib import Path

from .._core import Error

_HELP = (
    "the log's column names of each quantity, for a log a controller wrote under its own names: "
    "QUANTITY=NAME pairs, comma-separated (t=timestamp,q=actual_q_{j0},dq=actual_qd_{j0},"
    "i=actual_current_{j0}), or a YAML file (.yaml, .yml) of the same mapping (where a list "
    "gives the names of a quantity one by one). Quantities: t, q, dq, ddq, tau or i (motor "
    "currents); a joint quantity's NAME holds {j} (joint number from 1), {j0} (from 0) or "
    "{name} (joint name); a unit after the quantity: t[ms] (s, ms, us, ns), q[deg], "
    "dq[deg/s], ddq[deg/s^2] (revolute joints x pi/180), tau[permille]. The log's other "
    "columns are ignored (counted in the output)"
)


def columns_value(text: str):
    """The checked column map of ``--columns TEXT``: a YAML file's mapping, or the inline
    QUANTITY=NAME pairs."""
    from ..identification.columns import column_map

    if Path(text).suffix.lower() in (".yaml", ".yml"):
        spec = _yaml_map(text)
    else:
        spec = {}
        for item in text.split(","):
            key, eq, value = item.partition("=")
            if not eq or not key.strip():
                raise argparse.ArgumentTypeError(
                    f"'{text}': '{item}' is not QUANTITY=NAME (expected pairs such as "
                    "t=timestamp,q=actual_q_{j0}, or a YAML file; names given one by one go in "
                    "a YAML list)"
                )
            if key.strip() in spec:
                raise argparse.ArgumentTypeError(f"gives {key.strip()} twice")
            spec[key.strip()] = value.strip()
    try:
        return column_map(spec)
    except Error as e:
        raise argparse.ArgumentTypeError(str(e).removeprefix("columns ")) from None


def _yaml_map(text: str) -> dict:
    """The mapping of the YAML file ``text``."""
    from .. import _yaml

    path = Path(text)
    if not path.is_file():
        raise argparse.ArgumentTypeError(f"column map file '{text}' does not exist")
    try:
        doc = _yaml.load(path.read_text(encoding="utf-8"), path, Error)
    except (Error, UnicodeDecodeError) as e:
        raise argparse.ArgumentTypeError(str(e)) from None
    if not isinstance(doc, dict):
        raise argparse.ArgumentTypeError(
            f"{text}: expected a mapping of quantities to column names (t: timestamp, ...)"
        )
    return doc


def add_columns(p, *, recorded: bool = False) -> None:
    """``--columns`` on the parser ``p``; ``recorded``: a command reading a log as an
    identification JSON records (predict, detect), whose recorded map applies by default."""
    p.add_argument(
        "--columns",
        metavar="MAP",
        type=columns_value,
        help=_HELP
        + (
            " (default: the map the JSON records, if any)"
            if recorded
            else "; a --currents file is read through the map's t and i"
        ),
    )
