"""The numeric options of the command line: a number in a stated range (:class:`Number`,
:func:`number`), angles checked as radians, joint vectors (:func:`joint_vector`,
:func:`joint_values`), items of a vector option, the controller period and the seed."""

from __future__ import annotations

import argparse
import math

from .args import MAX_SEED, UsageError, deprecated


def _fmt(x: float) -> str:
    if isinstance(x, int) or (isinstance(x, float) and x.is_integer() and abs(x) < 1e6):
        return str(int(x))
    return f"{x:g}"


class Number:
    """An argparse ``type``: a finite float (or an int) within bounds, with the range stated in
    the error message and, through :func:`number`, in the help."""

    def __init__(
        self,
        low: float | None = None,
        high: float | None = None,
        *,
        low_open: bool = False,
        high_open: bool = False,
        integer: bool = False,
        unit: str = "",
        suffix: str = "",
    ):
        self.low, self.high = low, high
        self.low_open, self.high_open = low_open, high_open
        self.integer = integer
        self.unit = unit
        self.suffix = suffix  # may follow the number (``1%`` = ``1`` for a percentage)
        self.__name__ = "integer" if integer else "number"  # argparse names the type by this

    def describe(self) -> str:
        kind = "an integer" if self.integer else "a finite number"
        lo, hi = self.low, self.high
        if lo is not None and hi is not None:
            left = "(" if self.low_open else "["
            right = ")" if self.high_open else "]"
            rng = f" in {left}{_fmt(lo)}, {_fmt(hi)}{right}"
        elif lo is not None:
            rng = f" {'>' if self.low_open else '>='} {_fmt(lo)}"
        elif hi is not None:
            rng = f" {'<' if self.high_open else '<='} {_fmt(hi)}"
        else:
            rng = ""
        return kind + rng + (f" {self.unit}" if self.unit else "")

    def range_text(self) -> str:
        lo, hi = self.low, self.high
        if lo is not None and hi is not None:
            left = "(" if self.low_open else "["
            right = ")" if self.high_open else "]"
            return f"{left}{_fmt(lo)}, {_fmt(hi)}{right}"
        if lo is not None:
            return f"{'>' if self.low_open else '>='} {_fmt(lo)}"
        if hi is not None:
            return f"{'<' if self.high_open else '<='} {_fmt(hi)}"
        return "finite"

    def __call__(self, text: str):
        bad = argparse.ArgumentTypeError(f"expected {self.describe()}, got '{text}'")
        s = text.strip()
        if self.suffix and s.endswith(self.suffix):
            s = s[: -len(self.suffix)].strip()
        try:
            if self.integer:
                if len(s) > 30:  # int() of a huge digit string is slow, and no bound allows it
                    raise bad
                value = int(s)
            else:
                value = float(s)
        except ValueError:
            raise bad from None
        if not self.integer and not math.isfinite(value):
            raise bad
        lo, hi = self.low, self.high
        if lo is not None and lo >= 0 and value < 0:
            raise argparse.ArgumentTypeError(
                f"expected {self.describe()}, got a negative value, '{text}'"
            )
        if lo is not None and (value < lo or (self.low_open and value == lo)):
            raise bad
        if hi is not None and (value > hi or (self.high_open and value == hi)):
            raise bad
        return value


def number(
    p,
    *flags: str,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    integer: bool = False,
    unit: str = "",
    suffix: str = "",
    help: str = "",
    default_when_unset: float | None = None,
    **kwargs,
):
    """``p.add_argument(*flags, type=Number(...), help=...)`` with the accepted range appended
    to the help text; ``suffix`` may follow the number (``%``). ``default_when_unset``: the
    value the command takes when the option is not given, stated as its default while the
    option itself stays None (an option of one mode, refused in another whenever given)."""
    kind = Number(
        low, high, low_open=low_open, high_open=high_open, integer=integer, unit=unit, suffix=suffix
    )
    text = f"{help}; " if help else ""
    text += f"{'integer' if integer else 'number'} {kind.range_text()}"
    if "default" in kwargs and kwargs["default"] is not None and "nargs" not in kwargs:
        text += f"; default {_fmt(kwargs['default'])}"
    elif default_when_unset is not None:
        text += f"; default {_fmt(default_when_unset)}"
    return p.add_argument(*flags, type=kind, help=text.replace("%", "%%"), **kwargs)


def check_radians(values, option: str, flag: str, robot=None) -> None:
    """Refuses angles in radians that are degrees given without ``flag``: a value outside
    [-2 pi, 2 pi]. With ``robot``, ``values`` are joint positions: those of prismatic joints are
    not checked, and a revolute joint whose limits reach past 2 pi takes values up to them."""
    reach = [2 * math.pi] * len(values)
    if robot is not None:
        lim = robot.limits
        for k, kind in enumerate(robot.joint_types):
            ends = (lim["lower"][k], lim["upper"][k])
            wider = max((abs(x) for x in ends if not math.isnan(x)), default=0.0)
            reach[k] = math.inf if kind != "revolute" else max(reach[k], wider)
    for k, v in enumerate(values):
        if abs(v) > reach[k]:
            where = f" (value {k + 1})" if len(values) > 1 else ""
            r = reach[k]
            within = "[-2pi, 2pi]" if r == 2 * math.pi else f"[-{r:.4g}, {r:.4g}] (its limits)"
            raise UsageError(
                f"{option} {_fmt(v)}{where}: outside {within}, so not an angle in radians; "
                f"give {flag} if the angles are in degrees"
            )


class _JointVector(argparse.Action):
    """Values given as separate words, comma-separated, or both, each a finite number."""

    def __call__(self, parser, namespace, values, option_string=None):
        words = [w for v in values for w in v.split(",")]
        if any(not w.strip() for w in words):
            raise argparse.ArgumentError(
                self, f"expected numbers separated by spaces or commas, got '{' '.join(values)}'"
            )
        try:
            setattr(namespace, self.dest, [Number()(w) for w in words])
        except argparse.ArgumentTypeError as e:
            raise argparse.ArgumentError(self, str(e)) from None


def joint_vector(p, *flags: str, help: str, **kwargs):
    """A joint vector option: values as separate words, comma-separated, or both (a list of
    floats; :func:`joint_values` checks its length against the robot)."""
    kwargs.setdefault("metavar", "V")
    return p.add_argument(
        *flags,
        nargs="+",
        action=_JointVector,
        help=f"{help} (one value per joint, separated by spaces or commas)".replace("%", "%%"),
        **kwargs,
    )


def add_recorded_torque_reading(p) -> None:
    """``--torque-unit`` and ``--drive-gain`` of a command reading a log the way an
    identification JSON records (predict, detect): given, they replace the recorded ones."""
    p.add_argument(
        "--torque-unit",
        choices=["Nm", "permille", "current"],
        help="logged torque unit, as identify's (default: as recorded)",
    )
    joint_vector(
        p, "--drive-gain", metavar="K", help="as identify's (default: as recorded in the JSON)"
    )


def joint_values(values, n: int, what: str, *, broadcast: bool = False) -> list[float]:
    """The values of a :func:`joint_vector` option for ``n`` joints (one value for all of them
    when ``broadcast``), or a one-line error naming the option."""
    values = list(values)
    if broadcast and len(values) == 1:
        return values * n
    if len(values) != n:
        one = " (or one for all)" if broadcast else ""
        raise UsageError(f"{what} needs {n} values{one}, got {len(values)}")
    return values


class _Item(argparse.Action):
    """Stores its value as item ``index`` of the list ``dest`` (options that each set one part
    of a setting, such as ``--position-noise`` and ``--velocity-noise``)."""

    def __init__(self, option_strings, dest, *, index: int, **kwargs):
        super().__init__(option_strings, dest, **kwargs)
        self.index = index

    def __call__(self, parser, namespace, values, option_string=None):
        items = list(getattr(namespace, self.dest))
        items[self.index] = values
        setattr(namespace, self.dest, items)


def item(p, *flags: str, dest: str, index: int, default: list, **kwargs):
    """A :func:`number` option that sets item ``index`` of the list option ``dest``, whose
    value is ``default`` unless given."""
    action = number(
        p, *flags, dest=dest, action=_Item, index=index, default=default[index], **kwargs
    )
    action.default = list(default)
    return action


def controller_period(p, *, help: str, low: float = 0, high: float = 10, **kwargs):
    """``--controller-period`` (the sample period of a controller, in seconds; ``args.period``),
    with its former spelling ``--period``."""
    period = number(
        p,
        "--controller-period",
        dest="period",
        low=low,
        high=high,
        low_open=low == 0,
        help=help,
        **kwargs,
    )
    deprecated(p, "--period", period)
    return period


def seed(p, *flags: str, default: int = 0, help: str = "random seed") -> None:
    number(p, *flags, low=0, high=MAX_SEED, integer=True, default=default, help=help)
