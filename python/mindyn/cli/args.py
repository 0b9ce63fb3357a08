"""Arguments shared by the subcommands of the ``mindyn`` command line, and the validated types of
every numeric and output-path option: each says what it accepts, in its error message and in
its ``--help`` line alike.

The conventions of every command (docs/cli.md states them too):

- angles are in radians (lengths in metres); ``--deg`` takes the angles of an option, and the
  revolute joints' values of a joint vector, in degrees;
- a joint vector (one value per joint, or one value for every joint where a command says so)
  is given as separate words, comma-separated, or both: ``--q0 0 0.5 1`` = ``--q0 0,0.5,1``
  (:func:`joint_vector`);
- one name per meaning: ``--controller-period`` (the sample period of a controller),
  ``--excitation-period`` (the period of a periodic excitation in a log), ``--torque-noise``,
  ``--position-noise``, ``--velocity-noise`` (noise standard deviations),
  ``--rank-tolerance`` (the pivot size of a rank decision) and ``--pose-tolerance`` (a pose
  error);
- JSON: ``--format json`` prints the JSON document on standard output instead of the table,
  ``--json FILE`` writes it to FILE;
- outputs: every file or folder a command writes follows one rule (:func:`prepare_outputs`);
- every option has a help line;
- a former spelling is kept for one release as a hidden alias (:func:`deprecated`): it does
  what the new one does, and a note on standard error names the new spelling.
"""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
from pathlib import Path

from .._core import Error
from ..robot import bundled_robots

#: Largest seed accepted (the random generators take 32-bit seeds).
MAX_SEED = 2**32 - 1

#: What "the ZCR07S study" is, for the help texts that cite it.
ZCR07S_STUDY = (
    "the ZCR07S study (a published identification and adaptive PD control study of the ZCR07S "
    "six-axis industrial arm)"
)

#: The commands, in the order ``mindyn --help`` lists them: the module of :mod:`mindyn.cli` that
#: defines each (its ``register(subparsers)`` declares the options of all its commands) and the
#: command's summary.
COMMANDS: dict[str, tuple[str, str]] = {
    "info": ("info", "print a robot model: joints, geometry, limits, parameters"),
    "base": ("base", "base inertial parameters: counts of the three sets, formulas, rank margin"),
    "track": (
        "control",
        "closed-loop joint tracking simulation: adaptive PD, computed torque or PD",
    ),
    "ik": ("control", "position inverse kinematics of the tool frame, inside the joint limits"),
    "excite": ("excite", "optimised Fourier excitation trajectory for identification"),
    "simulate": ("simulate", "simulated joint log along a trajectory (stand-in for a robot)"),
    "identify": (
        "identify_args",
        "identify base parameters from joint logs (dynamic, integral or energy model)",
    ),
    "identify-payload": (
        "identify_args",
        "identify a payload fixed to the last link, with an identified arm",
    ),
    "predict": (
        "predict",
        "torques an identified model predicts on a log (CSV), to score it any way",
    ),
    "detect": (
        "detect",
        "collision detection: momentum-observer residual of an identified model on a log, "
        "thresholds calibrated on a collision-free log",
    ),
    "demo": (
        "demo",
        "the whole chain on a robot: base parameters, excitation, simulated measurement, "
        "identification, validation, generated code",
    ),
    "codegen": (
        "codegen",
        "generate inverse dynamics, gravity torque, base regressor or a controller step "
        "(adaptive PD, computed torque, gravity compensation) in C or ST",
    ),
    "export": (
        "export",
        "write identified classical parameters into the robot's URDF or YAML table, or an MJCF",
    ),
}


def add_command(subparsers, name: str, **kwargs) -> argparse.ArgumentParser:
    """The parser of command ``name``, with its summary from :data:`COMMANDS`."""
    return subparsers.add_parser(name, help=COMMANDS[name][1], **kwargs)


class UsageError(Error):
    """A command-line argument was rejected; the message names it and what was expected."""


class Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line, ``mindyn: error: ...``, raised as
    :class:`UsageError` for :func:`mindyn.cli.main` to print (instead of usage text and an
    exit). A word that starts with a minus and a digit is a value, not an option: negative
    numbers in any notation (``-1e-3``) and joint vectors (``-0.2,3``)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"^-\.?\d[\d.eE+,-]*$")

    def error(self, message: str):  # noqa: D102 - argparse API
        sub = self.prog.split(" ", 1)[1] if " " in self.prog else ""
        where = f" (see 'mindyn {sub} --help')" if sub else " (see 'mindyn --help')"
        raise UsageError(f"{message}{where}")


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
    ):
        self.low, self.high = low, high
        self.low_open, self.high_open = low_open, high_open
        self.integer = integer
        self.unit = unit
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
    help: str = "",
    **kwargs,
):
    """``p.add_argument(*flags, type=Number(...), help=...)`` with the accepted range appended
    to the help text."""
    kind = Number(low, high, low_open=low_open, high_open=high_open, integer=integer, unit=unit)
    text = f"{help}; " if help else ""
    text += f"{'integer' if integer else 'number'} {kind.range_text()}"
    if "default" in kwargs and kwargs["default"] is not None and "nargs" not in kwargs:
        text += f"; default {_fmt(kwargs['default'])}"
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
            raise ValueError(
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


class _Deprecated(argparse.Action):
    """A former spelling of an option, hidden from the help: does what the option it stands for
    does, and leaves a note for :func:`deprecation_notes`."""

    def __init__(self, option_strings, dest, *, target=None, new="", **kwargs):
        kwargs.setdefault("help", argparse.SUPPRESS)
        super().__init__(option_strings, dest, default=argparse.SUPPRESS, **kwargs)
        self.target, self.new = target, new

    def __call__(self, parser, namespace, values, option_string=None):
        notes = getattr(namespace, "_notes", None) or []
        notes.append(
            f"{option_string} is deprecated and will be removed in the next release; use {self.new}"
        )
        namespace._notes = notes
        if self.target is not None:
            self.target(parser, namespace, values, self.new)
        else:
            setattr(namespace, self.dest, values)


def deprecated(p, old: str, target: argparse.Action | None = None, *, new: str = "", **kwargs):
    """Keeps ``old``, a former spelling, for one release: as ``target`` (the action of the new
    option, whose dest, arity and type it shares), or, when one old option stands for several
    new ones, as a plain store of ``kwargs`` (dest, nargs, type) under the words ``new``."""
    if target is not None:
        new = new or max(target.option_strings, key=len)
        kwargs = dict(
            dest=target.dest,
            nargs=target.nargs,
            type=target.type,
            choices=target.choices,
            const=target.const,
            metavar=target.metavar,
        )
    return p.add_argument(old, action=_Deprecated, target=target, new=new, **kwargs)


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


def deprecation_notes(args: argparse.Namespace) -> list[str]:
    """The notes the former spellings on a command line left."""
    return list(getattr(args, "_notes", None) or [])


def print_deprecation_notes(args: argparse.Namespace) -> None:
    for note in deprecation_notes(args):
        print(f"mindyn: note: {note}", file=sys.stderr)


def seed(p, *flags: str, default: int = 0, help: str = "random seed") -> None:
    number(p, *flags, low=0, high=MAX_SEED, integer=True, default=default, help=help)


def _nearest_existing(path: Path) -> Path:
    path = path.absolute()
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def _check_parent(path: Path, text: str) -> None:
    anc = _nearest_existing(path.parent)
    if not anc.is_dir():
        raise argparse.ArgumentTypeError(f"'{text}': '{anc}' is a file, not a folder")
    if not os.access(anc, os.W_OK | os.X_OK):
        raise argparse.ArgumentTypeError(f"'{text}': the folder '{anc}' is not writable")


class OutputPath(str):
    """An output option's value (a ``str``), marked as a file or a folder to write, so that
    :func:`prepare_outputs` finds every output of a command line; ``into_folder``: a file
    option given an existing folder (or a path ending in ``/``), which :func:`output_path`
    turns into the command's default file name inside it."""

    folder = False
    into_folder = False


class OutputFolder(OutputPath):
    folder = True


def output_file(text: str) -> str:
    """An argparse ``type``: a file to write, by the rule of :func:`output_path` (a folder
    means the command's default file name inside it; the missing folders are created by
    :func:`prepare_outputs`)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a file name to write, got an empty string")
    path = Path(text)
    if path.is_dir() or text.endswith(("/", os.sep)):
        if path.is_dir() and not os.access(path, os.W_OK | os.X_OK):
            raise argparse.ArgumentTypeError(f"the folder '{text}' is not writable")
        if not path.exists():
            _check_parent(path, text)
        value = OutputPath(text)
        value.into_folder = True
        return value
    if path.exists() and not os.access(path, os.W_OK):
        raise argparse.ArgumentTypeError(f"'{text}' exists and is not writable")
    _check_parent(path, text)
    return OutputPath(text)


def output_path(value: str | None, default: str) -> Path:
    """The one rule for the file an output option of any command names: a path naming a folder
    (an existing one, or any path ending in ``/``) means ``default``'s file name inside that
    folder; no value means ``default`` itself (relative to the current folder); any other path
    is the file. The missing folders of the file are created. Commands state the path they
    wrote ("wrote PATH", unless standard output carries a JSON document)."""
    if value is None:
        path = Path(default)
    elif getattr(value, "into_folder", False) or Path(value).is_dir():
        path = Path(value) / Path(default).name
    else:
        path = Path(value)
    path.parent.mkdir(parents=True, exist_ok=True)
    return path


output_file.__name__ = "file name"


def output_dir(text: str) -> str:
    """An argparse ``type``: a folder to write into (created when missing)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a folder to write into, got an empty string")
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"'{text}' is a file; expected a folder to write into")
    if path.is_dir() and not os.access(path, os.W_OK | os.X_OK):
        raise argparse.ArgumentTypeError(f"the folder '{text}' is not writable")
    if not path.exists():
        _check_parent(path, text)
    return OutputFolder(text)


output_dir.__name__ = "folder"


#: The extension of an output option's default file name (:func:`default_file_name`), by the
#: option's destination; CSV for ``-o``.
_EXTENSIONS = {
    "json": ".json",
    "calibrate": ".json",
    "urdf": ".urdf",
    "yaml": ".yaml",
    "mjcf": ".xml",
    "sidecar": ".joints.yaml",
    "plot": ".png",
    "output": ".csv",
}


def default_file_name(args: argparse.Namespace, dest: str) -> str:
    """The file an output option writes when given a folder: ROBOT_COMMAND.EXT, ROBOT the
    robot argument (a bundled name, or its description file's name without extension)."""
    robot = Path(str(getattr(args, "robot", "") or "mindyn")).stem or "mindyn"
    return f"{robot}_{getattr(args, 'command', 'mindyn')}{_EXTENSIONS.get(dest, '')}"


def _into_folders(args: argparse.Namespace) -> None:
    """Every file option given a folder names :func:`default_file_name` inside it
    (:func:`output_path`), for the commands that write what their options name."""
    for dest, value in vars(args).items():
        if isinstance(value, OutputPath) and value.into_folder:
            path = output_path(value, default_file_name(args, dest))
            setattr(args, dest, OutputPath(str(path)))


def declared_outputs(args: argparse.Namespace) -> list[tuple[str, Path, bool]]:
    """The outputs a command line names: ``(option, path, is_folder)`` for every value of an
    option typed :func:`output_file` or :func:`output_dir`."""
    found = []
    for dest, value in vars(args).items():
        for v in value if isinstance(value, list) else [value]:
            if isinstance(v, OutputPath):
                found.append(("--" + dest.replace("_", "-"), Path(v), v.folder or v.into_folder))
    return found


def prepare_outputs(args: argparse.Namespace) -> None:
    """The one rule for the outputs of every command, applied before the command writes
    anything: a file option given a folder names its default file inside it
    (:func:`output_path`, :func:`default_file_name`), no two outputs may be the same file
    (compared as resolved paths), and the missing folders of each are created. The outputs are
    :func:`declared_outputs`, or those that the command's ``outputs(args)`` (a parser default)
    lists when it writes files the options only imply (``codegen -o NAME``: NAME.c and
    NAME.h); the commands state the paths they wrote (on standard output, unless it carries
    the JSON document of ``--format json``)."""
    if callable(getattr(args, "outputs", None)):
        outputs = args.outputs(args)  # the command names the files in a folder given
    else:
        _into_folders(args)
        outputs = declared_outputs(args)
    seen: dict[Path, tuple[str, Path]] = {}
    for option, path, folder in outputs:
        if folder:  # files inside it are named by the command (output_path)
            continue
        key = path.resolve()
        if key in seen:
            other, first = seen[key]
            raise UsageError(
                f"{option} '{path}' is also the file {other} writes ('{first}'): give each "
                "output its own file"
            )
        seen[key] = (option, path)
    for _, path, folder in outputs:
        (path if folder else path.parent).mkdir(parents=True, exist_ok=True)


def robot_help() -> str:
    return (
        "a bundled robot ("
        + ", ".join(bundled_robots())
        + "), a URDF file, a MuJoCo MJCF (.xml) or a YAML DH/MDH table"
    )


def robot_arg(text: str) -> str:
    """An argparse ``type`` for ROBOT: the name, file or ``planar<N>`` is checked by the loader;
    here only what cannot reach it (an empty name, a ``planar<N>`` whose N is no integer the
    model builder takes)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a robot name or file, got an empty string")
    m = re.fullmatch(r"planar(\d+)h?", text)
    if m and (len(m.group(1)) > 9 or int(m.group(1)) > 2**31 - 1):
        raise argparse.ArgumentTypeError(
            f"'{text}': planar<N> takes a joint count N, not {m.group(1)}"
        )
    return text


robot_arg.__name__ = "robot"


def add_robot(p: argparse.ArgumentParser) -> None:
    """The positional ROBOT and ``--tip`` (the last link of a URDF chain)."""
    p.add_argument("robot", metavar="ROBOT", type=robot_arg, help=robot_help())
    p.add_argument(
        "--tip",
        help="URDF: the link that ends the chain root -> TIP (default: the whole URDF, a tree "
        "if it branches)",
    )


def add_joint_terms(p: argparse.ArgumentParser, verb: str = "include") -> None:
    """``--rotor``, ``--friction`` and ``--drive-side``; ``verb`` says what they do in this
    command."""
    p.add_argument(
        "--rotor", action="store_true", help=f"{verb} rotor inertia Ia per joint (or motor)"
    )
    p.add_argument("--friction", action="store_true", help=f"{verb} Fv, Fc per joint (or motor)")
    add_drive_side(p)


def add_drive_side(p: argparse.ArgumentParser) -> None:
    """``--drive-side``: where rotor inertia and friction act when the description declares
    transmissions."""
    p.add_argument(
        "--drive-side",
        choices=("motor", "joint"),
        default=None,
        help="where rotor inertia and friction act when the description declares transmissions: "
        "on the motors (the default then; Ia, Fv, Fc of slot k are motor k's, "
        "tau += T^T (Ia T ddq + Fv T dq + Fc sign(T dq))) or on the joints",
    )


def with_drive_side(robot, args):
    """The robot with the drive side of ``--drive-side`` (unchanged when not given); ``motor``
    on a robot without transmissions is refused (ModelError)."""
    side = getattr(args, "drive_side", None)
    return robot if side is None else robot.with_drive_side(side)


def drive_side_words(robot, args) -> str:
    """Where the rotor inertia and friction of this command act, in words for its first output
    line, when the robot has transmissions and they are asked for (a command without
    ``--rotor`` / ``--friction`` always has them); "" otherwise."""
    if robot.transmission is None or not (
        getattr(args, "rotor", True) or getattr(args, "friction", True)
    ):
        return ""
    if robot.drive_side == "motor":
        return "on the motors through the transmissions (--drive-side joint: on the joints)"
    return "on the joints (--drive-side joint)"


def drive_side(robot, args):
    """``robot`` with ``--drive-side`` applied (:func:`with_drive_side`), and the words saying
    where rotor inertia and friction act, for a command's output ("" when neither is asked
    for)."""
    side = getattr(args, "drive_side", None)
    robot = with_drive_side(robot, args)
    if not (getattr(args, "rotor", False) or getattr(args, "friction", False)):
        return robot, ""
    if robot.drive_side == "motor":
        n = len(robot.transmission.motors)
        how = "--drive-side motor" if side else "the default with transmissions"
        return robot, (
            f"rotor inertia and friction on the {n} motors (q_m = T q, tau = T^T tau_m; {how}"
            + ("" if side else "; --drive-side joint puts them on the joints")
            + ")"
        )
    why = "--drive-side joint" if side else "no transmissions declared"
    return robot, f"rotor inertia and friction on the joints ({why})"


def add_offset(p: argparse.ArgumentParser, verb: str = "include") -> None:
    """``--offset``: a constant torque offset per joint (Off1 .. OffN)."""
    p.add_argument(
        "--offset",
        action="store_true",
        help=f"{verb} a constant torque offset per joint, Off1..OffN (tau_j = ... + Off_j)",
    )


def joint_terms(args, robot=None) -> list[str]:
    """The joint terms a command line asked for (``--rotor``, ``--friction``, ``--offset``), in
    words, for the first line of a command's output; with ``robot``, where the rotor inertia
    and friction act when it has transmissions (:func:`drive_side_words`)."""
    named = (
        ("rotor inertia", "rotor"),
        ("friction", "friction"),
        ("torque offsets", "offset"),
    )
    words = [words for words, flag in named if getattr(args, flag, False)]
    side = drive_side_words(robot, args) if robot is not None else ""
    if side:
        k = 1 + max(i for i, w in enumerate(words) if w in ("rotor inertia", "friction"))
        words[k - 1] += " " + side
    return words


#: Library keywords that library messages name (``friction=True``, ``tip='link'``,
#: ``prior_weight=``) whose command-line flag is the keyword with dashes (``--prior-weight``).
LIBRARY_OPTIONS = (
    "consistent",
    "currents",
    "cutoff",
    "decimate",
    "drive_gain",
    "drive_side",
    "edge",
    "filter",
    "friction",
    "friction_model",
    "friction_width",
    "method",
    "min_velocity",
    "offset",
    "period",
    "periods",
    "position_noise",
    "prior_weight",
    "quantization",
    "rotor",
    "snap",
    "tip",
    "topic",
    "torque_noise",
    "torque_unit",
    "validate",
    "validate_currents",
    "velocity_noise",
)
# the keywords whose flag is not their name with dashes: (keyword, value) -> flag, None for any
# value (the value then follows the flag)
_FLAG_OF = {("period", None): "--excitation-period", ("decimate", "False"): "--no-decimate"}
_NUMBER = r"-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?"
_LIBRARY_OPTION = re.compile(
    r"\b(" + "|".join(LIBRARY_OPTIONS) + r")="
    r"(?:(True|False)\b|'([^']*)'(?: or '([^']*)')?|(" + _NUMBER + r")(?![\w.])|(?![\w'\"]))"
)


def library_options_as_flags(text: str) -> str:
    """A library message as the command line says it: the keywords of :data:`LIBRARY_OPTIONS`
    as their flags (``offset=True`` -> ``--offset``, ``decimate=False`` -> ``--no-decimate``,
    ``method='recursive'`` -> ``--method recursive``, ``friction_model='smooth' or 'auto'`` ->
    ``--friction-model smooth or auto``, ``min_velocity=0`` -> ``--min-velocity 0``,
    ``prior_weight=`` -> ``--prior-weight``, ``period=`` -> ``--excitation-period``)."""

    def flag(m: re.Match) -> str:
        key, truth, word, other, number = m.groups()
        special = _FLAG_OF.get((key, truth))
        if special is not None:
            return special
        if truth == "False":  # no flag says it
            return m.group(0)
        name = _FLAG_OF.get((key, None), "--" + key.replace("_", "-"))
        if word is not None:
            return f"{name} {word}" + ("" if other is None else f" or {other}")
        return name if number is None else f"{name} {number}"

    return _LIBRARY_OPTION.sub(flag, text)
