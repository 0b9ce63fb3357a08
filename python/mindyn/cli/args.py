"""The commands of the ``mindyn`` command line, its parser (one-line errors) and the former
spellings of its options. The validated types of the options are in
:mod:`~mindyn.cli.number_options` (numbers, angles, joint vectors) and
:mod:`~mindyn.cli.outputs` (the files written): each says what it accepts, in its error message
and in its ``--help`` line alike; the robot argument and the joint terms are in
:mod:`~mindyn.cli.robot_options`, the flags of library keywords in :mod:`~mindyn.cli.flags`.

The conventions of every command (docs/cli.md states them too):

- angles are in radians (lengths in metres); ``--deg`` takes the angles of an option, and the
  revolute joints' values of a joint vector, in degrees;
- a joint vector (one value per joint, or one value for every joint where a command says so)
  is given as separate words, comma-separated, or both: ``--q0 0 0.5 1`` = ``--q0 0,0.5,1``
  (:func:`~mindyn.cli.number_options.joint_vector`);
- a word that starts with a minus and a digit (``-1%``, ``-inf``, ``-0.2,3``) is a value
  (:class:`Parser`); an option that needs a non-negative one refuses it saying it is negative;
- options are spelled in full: an abbreviation is refused (naming the options it could stand
  for), never taken for one of them (:class:`Parser`);
- one name per meaning: ``--controller-period`` (the sample period of a controller),
  ``--excitation-period`` (the period of a periodic excitation in a log), ``--torque-noise``,
  ``--position-noise``, ``--velocity-noise`` (noise standard deviations),
  ``--rank-tolerance`` (the pivot size of a rank decision) and ``--pose-tolerance`` (a pose
  error);
- JSON: ``--format json`` prints the JSON document on standard output instead of the table,
  ``--json FILE`` writes it to FILE;
- outputs: every file or folder a command writes follows one rule
  (:func:`~mindyn.cli.outputs.prepare_outputs`);
- every option has a help line;
- a former spelling is kept for one release as a hidden alias (:func:`deprecated`): it does
  what the new one does, and a note on standard error names the new spelling.
"""

from __future__ import annotations

import argparse
import re
import sys

from .._core import Error

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
    exit). A word that starts with a minus and a digit (or ``.5``, ``inf``, ``nan``) is a value,
    not an option, whatever follows: negative numbers in any notation (``-1e-3``, ``-inf``),
    joint vectors (``-0.2,3``) and values with a unit (``-1%``); the option's own check then
    refuses or takes it, saying why (no option of the command line is spelled so)."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("allow_abbrev", False)  # an abbreviation is never taken for an option
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"^-(?:\.?\d|inf|nan)", re.IGNORECASE)

    def error(self, message: str):  # noqa: D102 - argparse API
        sub = self.prog.split(" ", 1)[1] if " " in self.prog else ""
        where = f" (see 'mindyn {sub} --help')" if sub else " (see 'mindyn --help')"
        raise UsageError(f"{message}{where}")


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


def remember_flags(p: argparse.ArgumentParser) -> None:
    """Records the flag and the default of every option of ``p`` (``args._flags``: dest ->
    (flag, default)), and makes each option note on the parsed arguments that it was given
    (``args._given``), so that :func:`given_options` tells which of them a command line set.
    Called after the last option is added."""
    flags = {}
    for a in p._actions:
        if a.option_strings and a.dest != "help":
            a.__class__ = _noting(type(a))
            if a.help != argparse.SUPPRESS:
                flags[a.dest] = (max(a.option_strings, key=len), a.default)
    p.set_defaults(_flags=flags)


_NOTING: dict[type, type] = {}


def _noting(kind: type) -> type:
    """The argparse action class ``kind`` that also adds its destination to the namespace's
    ``_given`` set when its option appears on the command line (one class per ``kind``)."""
    if kind in _NOTING or kind in _NOTING.values():
        return _NOTING.get(kind, kind)

    def __call__(self, parser, namespace, values, option_string=None):
        given = getattr(namespace, "_given", None)
        if given is None:
            given = set()
            namespace._given = given
        given.add(self.dest)
        return kind.__call__(self, parser, namespace, values, option_string)

    _NOTING[kind] = type(kind.__name__, (kind,), {"__call__": __call__})
    return _NOTING[kind]


def given_options(args: argparse.Namespace, *dests: str) -> list[str]:
    """The flags (``--param-error``) of the options ``dests`` (recorded by
    :func:`remember_flags`) that the command line gave, whatever their values (their defaults'
    too): an option that applies in one mode only is then refused in the others instead of
    ignored."""
    flags, given = args._flags, getattr(args, "_given", None) or set()
    return [flags[d][0] for d in dests if d in given]


def deprecation_notes(args: argparse.Namespace) -> list[str]:
    """The notes the former spellings on a command line left."""
    return list(getattr(args, "_notes", None) or [])


def print_deprecation_notes(args: argparse.Namespace) -> None:
    for note in deprecation_notes(args):
        print(f"mindyn: note: {note}", file=sys.stderr)
