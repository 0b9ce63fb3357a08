"""Argument checks of the public Python API, the one place that writes the messages of
:class:`mindyn.ArgumentError` (a ``mindyn.Error``, ``ValueError`` and ``TypeError``): every public
function checks its arguments here in its first lines. Every array argument goes through
:func:`array` (or :func:`samples` for per-sample arguments), which converts it to a C-contiguous
float64 array; options go through :func:`flag`, :func:`integer`, :func:`number`, :func:`choice`,
:func:`text` and the others below. Each message names the argument, what was expected and what was
given.

Finite inputs can still be too large for a computation: a velocity of 1e200 squares past the
double range (1.8e308) and the dynamics would return inf or NaN. Every public function of the
joint state is decorated with :func:`finite_results`, which checks its result instead (the bound
depends on the robot, the parameters and the function, the result does not): a result that is
not finite raises :class:`ArgumentError` naming the function and its largest inputs.
"""

from __future__ import annotations

import functools
import inspect
import numbers
from collections.abc import Sequence

import numpy as np

from ._core import ArgumentError

__all__ = [
    "ArgumentError",
    "Default",
    "array",
    "batch",
    "choice",
    "describe",
    "fail",
    "finite_results",
    "flag",
    "function",
    "instance",
    "integer",
    "mapping",
    "number",
    "optional",
    "overflow",
    "params",
    "path",
    "protocol",
    "readonly",
    "samples",
    "text",
    "unit_norms",
    "unknown_keywords",
]

#: How far from 1 the norm of a configuration's unit quaternion or (cos, sin) pair may be (the
#: core's check of a configuration): none is normalised.
UNIT_NORM_TOLERANCE = 1e-6


class Default(float):
    """A number keyword's default value, told apart from the same number given by identity
    (``x is DEFAULT``: not given); otherwise a float, shown as its value."""

    __slots__ = ()


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


def describe(x) -> str:
    """``x`` as a message names what was given: ``a str 'abc'``, ``the scalar 3``, ``None``,
    ``an array of shape (2,) and dtype float64`` ..."""
    return _describe(x)


def _shape_text(shape: Sequence) -> str:
    dims = [str(d) for d in shape]
    return "(" + ", ".join(dims) + ("," if len(dims) == 1 else "") + ")"


def _convert(x, name: str, expected: str) -> np.ndarray:
    """``x`` as a float64 array; `expected` is the shape text for the message."""
    if x is None or isinstance(x, (str, bytes, dict, set)):
        raise ArgumentError(f"{name} is {_describe(x)}; expected an array of shape {expected}")
    try:
        a = np.asarray(x)
    except (ValueError, TypeError):
        raise ArgumentError(
            f"{name} is {_describe(x)} that is not a regular array (rows of unequal length?); "
            f"expected an array of shape {expected}"
        ) from None
    if a.dtype == object or not (
        np.issubdtype(a.dtype, np.floating)
        or np.issubdtype(a.dtype, np.integer)
        or a.dtype == np.bool_
    ):
        raise ArgumentError(
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
    elif a.ndim == 2 and unit != "entry":
        where = f"sample {idx[0]}, {unit} {idx[1] + 1}"
    else:
        where = "index " + str(idx)
    raise ArgumentError(f"{name} contains {what} at {where}; expected finite values")


def _wrong_shape(name: str, a: np.ndarray, expected: str) -> ArgumentError:
    return ArgumentError(f"{name} has shape {a.shape}; expected {expected}")


def array(
    x, name: str, shape: Sequence[int | None], *, unit: str = "entry", finite: bool = True
) -> np.ndarray:
    """``x`` as a finite (unless not ``finite``: NaN allowed, for a value that is not known)
    C-contiguous float64 array of ``shape`` (``None``: any length there)."""
    expected = _shape_text(["*" if d is None else d for d in shape])
    a = _convert(x, name, expected)
    if a.ndim != len(shape) or any(d is not None and a.shape[i] != d for i, d in enumerate(shape)):
        raise _wrong_shape(name, a, expected)
    if finite:
        _finite(a, name, unit)
    return a


def samples(x, name: str, n: int, *, unit: str = "joint") -> np.ndarray:
    """A per-sample argument: shape (n,) for one sample or (m, n) for m samples (m >= 0);
    ``unit`` names an entry in the message of a non-finite one (``coordinate`` for a robot with
    multi-DOF joints, whose entries are not joints)."""
    expected = f"({n},) or (m, {n})"
    a = _convert(x, name, expected)
    if a.ndim not in (1, 2):
        raise ArgumentError(
            f"{name} must be 1-D ({n},) or 2-D (m, {n}), got {a.ndim}-D shape {a.shape}"
        )
    if not (a.shape == (n,) or (a.ndim == 2 and a.shape[1] == n)):
        raise _wrong_shape(name, a, f"(m, {n})" if a.ndim == 2 else expected)
    _finite(a, name, unit)
    return a


def batch(n: int | dict[str, int], **arrays) -> list[np.ndarray]:
    """Several per-sample arguments that must agree: all single samples or batches of one
    length. ``n`` is the size of each, or a dict of each argument's size (a robot with multi-DOF
    joints: q of nq entries, the others of nv; their entries are then coordinates, not joints).
    Returned in the order given."""
    sizes = n if isinstance(n, dict) else dict.fromkeys(arrays, n)
    unit = "coordinate" if isinstance(n, dict) else "joint"
    out = [samples(x, name, sizes[name], unit=unit) for name, x in arrays.items()]
    first_name, first = next(iter(arrays)), out[0]
    for (name, _), a in zip(arrays.items(), out):
        if a.shape[:-1] != first.shape[:-1] or a.ndim != first.ndim:
            size = sizes[name]
            raise ArgumentError(
                f"{name} has shape {a.shape}; expected "
                f"{first.shape[:-1] + (size,)} like {first_name}: all inputs must be single "
                f"samples ({size},) or batches of equal length (m, {size})"
            )
    return out


def unit_norms(q: np.ndarray, name: str, blocks) -> np.ndarray:
    """``q``, a configuration (nq,) or batch (m, nq) already checked by :func:`array` or
    :func:`samples`, whose ``blocks`` ``(start, size, what)`` (a quaternion or a (cos, sin) pair,
    ``what`` naming it) each have norm 1 within :data:`UNIT_NORM_TOLERANCE`."""
    for start, size, what in blocks:
        norm = np.linalg.norm(q[..., start : start + size], axis=-1)
        bad = np.flatnonzero(~(np.abs(norm - 1.0) <= UNIT_NORM_TOLERANCE))
        if bad.size:
            sample = f"sample {bad[0]}, " if q.ndim == 2 else ""
            raise ArgumentError(
                f"{name} has the {what} ({sample}coordinates {start + 1} to {start + size}) of "
                f"norm {norm.flat[bad[0]]:.9g}; expected norm 1 within {UNIT_NORM_TOLERANCE:g} "
                "(it is not normalised)"
            )
    return q


def flag(x, name: str) -> bool:
    """A true / false option: bool, numpy bool, or the integers 0 and 1 (strings and None are
    refused)."""
    if isinstance(x, (bool, np.bool_)) or (isinstance(x, numbers.Integral) and x in (0, 1)):
        return bool(x)
    raise ArgumentError(f"{name} is {_describe(x)}; expected True or False")


def integer(x, name: str, minimum: int | None = None, *, maximum: int | None = None) -> int:
    """An integer option (bools refused), at least ``minimum`` and at most ``maximum``."""
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, numbers.Integral):
        raise ArgumentError(f"{name} is {_describe(x)}; expected an integer")
    x = int(x)
    if minimum is not None and maximum is not None and not minimum <= x <= maximum:
        raise ArgumentError(f"{name} is {x}; expected an integer from {minimum} to {maximum}")
    if minimum is not None and x < minimum:
        raise ArgumentError(f"{name} is {x}; expected an integer >= {minimum}")
    if maximum is not None and x > maximum:
        raise ArgumentError(f"{name} is {x}; expected an integer <= {maximum}")
    return int(x)


def number(
    x,
    name: str,
    *,
    positive: bool = False,
    minimum: float | None = None,
    maximum: float | None = None,
    below: float | None = None,
) -> float:
    """A finite real option; ``positive``: > 0; ``minimum``: >= that; ``maximum``: <= that;
    ``below``: < that."""
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, numbers.Real):
        raise ArgumentError(f"{name} is {_describe(x)}; expected a number")
    v = float(x)
    if not np.isfinite(v):
        raise ArgumentError(f"{name} is {v}; expected a finite number")
    if positive and not v > 0:
        raise ArgumentError(f"{name} is {v}; expected a positive number")
    if minimum is not None and v < minimum:
        raise ArgumentError(f"{name} is {v}; expected a number >= {minimum}")
    if maximum is not None and v > maximum:
        raise ArgumentError(f"{name} is {v}; expected a number <= {maximum}")
    if below is not None and not v < below:
        raise ArgumentError(f"{name} is {v}; expected a number < {below}")
    return v


def params(
    x,
    name: str,
    n: int,
    sizes_per_joint: Sequence[int] = (10, 11, 12, 13),
    *,
    allow_none: bool = True,
):
    """A classical parameter vector (or None, with ``allow_none``: the model's own values):
    shape (k n,) for one of ``sizes_per_joint``."""
    sizes = [k * n for k in sizes_per_joint]
    if x is None:
        if allow_none:
            return None
        raise ArgumentError(
            f"{name} is None; expected a vector of shape "
            + " or ".join(f"({s},)" for s in sizes)
            + " or a mapping of parameter names to values"
        )
    shapes = " or ".join(f"({s},)" for s in sizes)
    none = " or None" if allow_none else ""
    expected = shapes + none
    what = ", ".join(f"{k} n" for k in sizes_per_joint)
    a = _convert(x, name, expected)
    if a.ndim != 1:
        raise ArgumentError(f"{name} must be 1-D, got shape {a.shape}; expected {expected}")
    if a.shape[0] not in sizes:
        raise ArgumentError(
            f"{name} has shape {a.shape}: {a.shape[0]} entries fits no layout for {n} joints; "
            f"expected {shapes} ({what}){none}"
        )
    _finite(a, name, "entry")
    return a


def fail(name: str, message: str) -> ArgumentError:
    """The error of argument ``name`` for a check made elsewhere: ``name`` then ``message``."""
    return ArgumentError(f"{name} {message}")


def optional(check, x, name: str, *args, **kwargs):
    """``None``, or ``x`` through ``check`` (one of the functions here)."""
    return None if x is None else check(x, name, *args, **kwargs)


def choice(x, name: str, choices):
    """One of the strings ``choices``."""
    if not isinstance(x, str) or x not in choices:
        listed = ", ".join(repr(c) for c in choices)
        raise ArgumentError(f"{name} is {_describe(x)}; expected one of {listed}")
    return x


def snap(x, name: str = "snap"):
    """The snap option of the base parameters: ``"auto"``, a rotation tolerance in rad (>= 0,
    as a float), ``True`` / ``False`` or ``None``."""
    if isinstance(x, bool) or x is None or (isinstance(x, str) and x == "auto"):
        return x
    if isinstance(x, str):
        raise ArgumentError(
            f"{name} is {x!r}; expected 'auto', a rotation tolerance in rad (>= 0), True (1e-3) "
            "or False / None (no snap)"
        )
    return number(x, name, minimum=0.0)


def text(x, name: str, *, empty: bool = False) -> str:
    """A string (non-empty unless ``empty``)."""
    if not isinstance(x, str):
        raise ArgumentError(f"{name} is {_describe(x)}; expected a string")
    if not empty and not x.strip():
        raise ArgumentError(f"{name} is empty; expected a non-empty string")
    return x


def instance(x, name: str, kind, what: str | None = None):
    """An object of class ``kind`` (a class or a tuple of classes); ``what`` names it in the
    message (default the class name)."""
    if not isinstance(x, kind):
        if what is None:
            kinds = kind if isinstance(kind, tuple) else (kind,)
            what = " or ".join(
                f"{'an' if k.__name__[0] in 'AEIOU' else 'a'} {k.__name__}" for k in kinds
            )
        raise ArgumentError(f"{name} is {_describe(x)}; expected {what}")
    return x


def readonly(a) -> np.ndarray:
    """``a`` as a read-only float array (what a getter returns: assigning to an entry raises
    instead of changing a copy that is then lost)."""
    out = np.array(a, dtype=float)
    out.flags.writeable = False
    return out


def function(x, name: str):
    """A callable."""
    if not callable(x):
        raise ArgumentError(f"{name} is {_describe(x)}; expected a callable")
    return x


def path(x, name: str):
    """A file or folder path (str or os.PathLike; not an empty string)."""
    if isinstance(x, str) and x:
        return x
    if hasattr(x, "__fspath__") and not isinstance(x, (bytes, str)):
        return x
    raise ArgumentError(f"{name} is {_describe(x)}; expected a path")


def mapping(x, name: str):
    """A mapping (a dict)."""
    from collections.abc import Mapping

    if not isinstance(x, Mapping):
        raise ArgumentError(f"{name} is {_describe(x)}; expected a mapping (a dict)")
    return x


def unknown_keywords(function: str, given, accepted, *, error=None) -> None:
    """Refuses the keywords of ``given`` (names) that are not ``accepted``: an error naming
    ``function``, the one the user called (not the one it passes the keywords on to), the
    unknown keywords and every accepted one; ``error`` its class (default ArgumentError)."""
    unknown = sorted(set(given) - set(accepted))
    if unknown:
        raise (error or ArgumentError)(
            f"{function}: unknown option(s) {', '.join(unknown)}; expected some of "
            + ", ".join(sorted(accepted))
        )


def protocol(x, name: str, method: str, what: str):
    """An object with a callable ``method`` (``what`` names the kind in the message)."""
    if not callable(getattr(x, method, None)):
        raise ArgumentError(f"{name} is {_describe(x)}; expected {what}")
    return x


def _all_finite(out) -> bool:
    """Whether every number of ``out`` (an array, a number, or a tuple, list or dict of them)
    is finite; other values count as finite."""
    if isinstance(out, (tuple, list)):
        return all(_all_finite(x) for x in out)
    if isinstance(out, dict):
        return all(_all_finite(x) for x in out.values())
    if isinstance(out, (np.ndarray, numbers.Number)) and not isinstance(out, bool):
        a = np.asarray(out)
        return not np.issubdtype(a.dtype, np.inexact) or bool(np.isfinite(a).all())
    return True


def _largest(name: str, x) -> tuple[float, str]:
    """The largest magnitude of input ``x`` and where it is (text)."""
    a = np.asarray(x, dtype=float)
    if a.size == 0:
        return 0.0, name
    i = tuple(int(k) for k in np.unravel_index(int(np.argmax(np.abs(a))), a.shape))
    if a.ndim == 0:
        where = ""
    elif a.ndim == 1:
        where = f" (entry {i[0] + 1})"
    elif a.ndim == 2:
        where = f" (sample {i[0]}, entry {i[1] + 1})"
    else:
        where = f" (index {i})"
    return float(abs(a[i])), f"{name} {float(a[i]):.3g}{where}"


def finite_results(*names: str):
    """Decorator of a public function of the joint state: its result (array, number or tuple of
    them) must be finite, or :class:`ArgumentError` names the function and the largest entry of
    each of its inputs ``names`` (which were checked finite: the computation overflowed)."""

    def decorate(fn):
        signature = inspect.signature(fn)
        label = fn.__qualname__

        @functools.wraps(fn)
        def checked(*args, **kwargs):
            # an overflow shows in the result, checked here: numpy's warnings of it would reach
            # the user before the error
            with np.errstate(over="ignore", invalid="ignore"):
                out = fn(*args, **kwargs)
            if _all_finite(out):
                return out
            given = signature.bind(*args, **kwargs).arguments
            raise overflow(label, **{n: given[n] for n in names if given.get(n) is not None})

        return checked

    return decorate


def overflow(function: str, **inputs) -> ArgumentError:
    """The error of ``function`` whose computation overflowed the double range for the finite
    ``inputs``: it names the largest entry of each, the largest first."""
    found = sorted((_largest(name, x) for name, x in inputs.items()), key=lambda f: -f[0])
    listed = ", ".join(text for _, text in found)
    return ArgumentError(
        f"{function}: the result overflows the double range (inf or NaN) for finite inputs too "
        f"large for it; largest entries: {listed}; expected inputs whose products in the "
        "computation stay below 1.8e308"
    )
