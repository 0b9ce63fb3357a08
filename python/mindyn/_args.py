"""Argument checks of the public Python API: every array argument goes through :func:`array`
(or :func:`samples` for per-sample arguments), which converts it to a C-contiguous float64 array
and raises :class:`mindyn.ModelError` naming the argument, the expected shape and what was given.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence

import numpy as np

from ._core import ModelError

__all__ = ["array", "samples", "batch", "flag", "integer", "number", "params"]


def _describe(x) -> str:
    if x is None:
        return "None"
    if isinstance(x, np.ndarray):
        return f"an array of shape {x.shape} and dtype {x.dtype}"
    if isinstance(x, (str, bytes)):
        return f"a {type(x).__name__} {x!r:.40}"
    if isinstance(x, (bool, numbers.Number)):
        return f"the scalar {x!r}"
    if isinstance(x, (list, tuple)):
        return f"a {type(x).__name__} of length {len(x)}"
    return f"a {type(x).__name__}"


def _shape_text(shape: Sequence) -> str:
    dims = [str(d) for d in shape]
    return "(" + ", ".join(dims) + ("," if len(dims) == 1 else "") + ")"


def _convert(x, name: str, expected: str) -> np.ndarray:
    """``x`` as a float64 array; `expected` is the shape text for the message."""
    if x is None or isinstance(x, (str, bytes, dict, set)):
        raise ModelError(f"{name} is {_describe(x)}; expected an array of shape {expected}")
    try:
        a = np.asarray(x)
    except (ValueError, TypeError):
        raise ModelError(
            f"{name} is {_describe(x)} that is not a regular array (rows of unequal length?); "
            f"expected an array of shape {expected}"
        ) from None
    if a.dtype == object or not (
        np.issubdtype(a.dtype, np.floating)
        or np.issubdtype(a.dtype, np.integer)
        or a.dtype == np.bool_
    ):
        raise ModelError(
            f"{name} has dtype {a.dtype}; expected real numbers in an array of shape {expected}"
        )
    return np.ascontiguousarray(a, dtype=np.float64)


def _finite(a: np.ndarray, name: str, unit: str) -> None:
    bad = np.argwhere(~np.isfinite(a))
    if bad.size == 0:
        return
    idx = tuple(int(i) for i in bad[0])
    what = "NaN" if np.isnan(a[idx]) else "an infinite value"
    if a.ndim == 1:
        where = f"{unit} {idx[0] + 1}"
    elif a.ndim == 2 and unit == "joint":
        where = f"sample {idx[0]}, joint {idx[1] + 1}"
    else:
        where = "index " + str(idx)
    raise ModelError(f"{name} contains {what} at {where}; expected finite values")


def _wrong_shape(name: str, a: np.ndarray, expected: str) -> ModelError:
    return ModelError(f"{name} has shape {a.shape}; expected {expected}")


def array(x, name: str, shape: Sequence[int | None], *, unit: str = "entry") -> np.ndarray:
    """``x`` as a finite C-contiguous float64 array of ``shape`` (``None``: any length there)."""
    expected = _shape_text(["*" if d is None else d for d in shape])
    a = _convert(x, name, expected)
    if a.ndim != len(shape) or any(d is not None and a.shape[i] != d for i, d in enumerate(shape)):
        raise _wrong_shape(name, a, expected)
    _finite(a, name, unit)
    return a


def samples(x, name: str, n: int) -> np.ndarray:
    """A per-sample argument: shape (n,) for one sample or (m, n) for m samples (m >= 0)."""
    expected = f"({n},) or (m, {n})"
    a = _convert(x, name, expected)
    if a.ndim not in (1, 2):
        raise ModelError(
            f"{name} must be 1-D ({n},) or 2-D (m, {n}), got {a.ndim}-D shape {a.shape}"
        )
    if not (a.shape == (n,) or (a.ndim == 2 and a.shape[1] == n)):
        raise _wrong_shape(name, a, f"(m, {n})" if a.ndim == 2 else expected)
    _finite(a, name, "joint")
    return a


def batch(n: int, **arrays) -> list[np.ndarray]:
    """Several per-sample arguments that must agree: all single samples or batches of one
    length. Returned in the order given."""
    out = [samples(x, name, n) for name, x in arrays.items()]
    first_name, first = next(iter(arrays)), out[0]
    for (name, _), a in zip(arrays.items(), out):
        if a.shape != first.shape:
            raise ModelError(
                f"{name} has shape {a.shape}; expected {first.shape} like {first_name}: all "
                f"inputs must be single samples ({n},) or batches of equal length (m, {n})"
            )
    return out


def flag(x, name: str) -> bool:
    """A true / false option: bool, numpy bool, or the integers 0 and 1 (strings and None are
    refused)."""
    if isinstance(x, (bool, np.bool_)) or (isinstance(x, numbers.Integral) and x in (0, 1)):
        return bool(x)
    raise ModelError(f"{name} is {_describe(x)}; expected True or False")


def integer(x, name: str, minimum: int | None = None) -> int:
    """An integer option (bools refused), at least ``minimum``."""
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, numbers.Integral):
        raise ModelError(f"{name} is {_describe(x)}; expected an integer")
    if minimum is not None and x < minimum:
        raise ModelError(f"{name} is {x}; expected an integer >= {minimum}")
    return int(x)


def number(x, name: str, *, positive: bool = False, minimum: float | None = None) -> float:
    """A finite real option; ``positive``: > 0; ``minimum``: >= that."""
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, numbers.Real):
        raise ModelError(f"{name} is {_describe(x)}; expected a number")
    v = float(x)
    if not np.isfinite(v):
        raise ModelError(f"{name} is {v}; expected a finite number")
    if positive and not v > 0:
        raise ModelError(f"{name} is {v}; expected a positive number")
    if minimum is not None and v < minimum:
        raise ModelError(f"{name} is {v}; expected a number >= {minimum}")
    return v


def params(x, name: str, n: int, sizes_per_joint: Sequence[int] = (10, 11, 12, 13)):
    """A classical parameter vector (or None: the model's own values): shape (k n,) for one of
    ``sizes_per_joint``."""
    if x is None:
        return None
    sizes = [k * n for k in sizes_per_joint]
    expected = " or ".join(f"({s},)" for s in sizes)
    what = ", ".join(f"{k} n" for k in sizes_per_joint)
    a = _convert(x, name, expected)
    if a.ndim != 1:
        raise ModelError(f"{name} must be 1-D, got shape {a.shape}; expected {expected} or None")
    if a.shape[0] not in sizes:
        raise ModelError(
            f"{name} has shape {a.shape}: {a.shape[0]} entries fits no layout for {n} joints; "
            f"expected {expected} ({what}) or None"
        )
    _finite(a, name, "entry")
    return a
