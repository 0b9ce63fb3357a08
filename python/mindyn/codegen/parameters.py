"""Parameter values for generated code from a file (:func:`read_parameter_file`)."""

from __future__ import annotations

import json
import math
import re
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .. import _args, _core

__all__ = ["read_parameter_file"]

_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


def read_parameter_file(path: str | Path, names: Sequence[str]) -> np.ndarray:
    """Parameter values from a file, in the order of ``names``.

    Accepted: JSON, either a mapping ``{"NAME": value}`` or ``{"names": [...], "values": [...]}``
    or a plain list in order; or text with one ``NAME value`` (or ``NAME = value``) per line,
    ``#`` comments allowed. Every name must be given exactly once; unknown names are an error.
    """
    from ..identification.data import DataError

    path = Path(_args.path(path, "path"))
    if isinstance(names, (str, bytes)) or not isinstance(names, Sequence):
        raise _args.fail("names", "must be a list of parameter names")
    names = list(names)
    if not names or not all(isinstance(k, str) and k for k in names):
        raise _args.fail("names", "must be a non-empty list of non-empty strings")
    twice = sorted({k for k in names if names.count(k) > 1})
    if twice:
        raise _args.fail("names", f"gives {', '.join(twice[:5])} more than once")
    if not path.is_file():
        raise _core.RobotFileNotFoundError(f"parameter file '{path}' does not exist")
    text = path.read_text()
    mapping: dict[str, float] = {}
    if path.suffix.lower() == ".json" or text.lstrip().startswith(("{", "[")):
        try:
            data = json.loads(text)
        except json.JSONDecodeError as e:
            raise DataError(f"{path}:{e.lineno}: not valid JSON: {e.msg}") from None
        if isinstance(data, list):
            if len(data) != len(names):
                raise DataError(f"{path}: {len(data)} values; expected {len(names)}")
            mapping = dict(zip(names, data))
        elif isinstance(data, dict) and "names" in data and "values" in data:
            if len(data["names"]) != len(data["values"]):
                raise DataError(f"{path}: 'names' and 'values' differ in length")
            mapping = dict(zip(data["names"], data["values"]))
        elif isinstance(data, dict):
            mapping = data
        else:
            raise DataError(f"{path}: expected a JSON mapping or list")
    else:
        for lineno, line in enumerate(text.splitlines(), 1):
            line = line.split("#", 1)[0].strip()
            if not line:
                continue
            m = re.fullmatch(r"([A-Za-z_][A-Za-z0-9_]*)\s*(?:=|:|\s)\s*(" + _NUMBER + r")", line)
            if not m:
                raise DataError(f"{path}:{lineno}: expected 'NAME value', got '{line}'")
            if m.group(1) in mapping:
                raise DataError(f"{path}:{lineno}: '{m.group(1)}' given twice")
            mapping[m.group(1)] = float(m.group(2))
    unknown = [k for k in mapping if k not in names]
    if unknown:
        raise DataError(
            f"{path}: unknown parameter(s) {', '.join(unknown[:5])}; expected {', '.join(names)}"
        )
    missing = [k for k in names if k not in mapping]
    if missing:
        raise DataError(f"{path}: missing parameter(s) {', '.join(missing[:8])}")
    values = np.empty(len(names))
    for i, k in enumerate(names):
        try:
            values[i] = float(mapping[k])
        except (TypeError, ValueError):
            raise DataError(f"{path}: value of '{k}' is not a number") from None
        if not math.isfinite(values[i]):
            raise DataError(f"{path}: value of '{k}' is not finite")
    return values
