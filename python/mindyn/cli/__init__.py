"""The ``mindyn`` command line. A command's module is imported, and its options declared, only
when that command runs or shows its help: ``mindyn --help`` and the light commands start without
the libraries that only identification, plots or convex fits need."""

from __future__ import annotations

import argparse
import difflib
import importlib
import os
import sys

from .._core import ArgumentError, Error
from .._threads import reuse_freed_memory
from .args import COMMANDS, Parser, UsageError, print_deprecation_notes
from .flags import argument_as_flag, library_options_as_flags
from .outputs import is_output, prepare_outputs
from .quiet import warnings_after_success


class _Version(argparse.Action):
    """``--version``: the package version (read when asked, from the installed package's
    metadata, which pyproject.toml writes)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, **kwargs):
        kwargs.setdefault("help", "print mindyn's version and exit")
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        from .._version import __version__

        print(f"mindyn {__version__}")
        parser.exit()


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The ``mindyn`` parser. ``command``: declare that command's options only (with those of
    the commands defined in the same module) and give the others their name and summary alone,
    so that their modules are not imported; an unknown name declares none. Default: every
    command."""
    parser = Parser(
        prog="mindyn",
        description="Minimal dynamic models of manipulators.",
    )
    parser.add_argument("--version", action=_Version)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    wanted = COMMANDS[command][0] if command in COMMANDS else None
    registered = set()
    for name, (module, summary) in COMMANDS.items():
        if command is not None and module != wanted:
            sub.add_parser(name, help=summary)
        elif module not in registered:
            importlib.import_module(f"{__name__}.{module}").register(sub)
            registered.add(module)
    return parser


def _command(argv: list[str]) -> str:
    """The command named on a command line: its first word that is not an option ("" if none)."""
    return next((a for a in argv if not a.startswith("-")), "")


def _unrecognized(parser: argparse.ArgumentParser, command: str, extra: list[str]) -> str:
    """The error for words that ``command`` does not take: named, with the options of that
    command they may be misspellings of, and the command's help (not the top-level one)."""
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    actions = sub.choices[command]._option_string_actions  # hidden former spellings left out
    flags = [f for f, a in actions.items() if a.help != argparse.SUPPRESS]
    hints = []
    for word in (w.split("=", 1)[0] for w in extra if w.startswith("--")):
        # an option the word extends (--frequency: --freq), else the options it abbreviates
        # (abbreviations are not taken: --controller could be any --controller-...), else
        # one close in spelling
        near = [f for f in flags if f.startswith("--") and word.startswith(f)]
        if near:
            near = [max(near, key=len)]
        else:
            near = sorted(f for f in flags if f.startswith(word))
            near = near or difflib.get_close_matches(word, flags, n=1, cutoff=0.8)
        if near:
            hints.append(f"unknown option {word}: did you mean {' or '.join(near)}?")
    said = f"unrecognized arguments: {' '.join(extra)}"
    if hints:
        said += f" ({'; '.join(hints)})"
    return f"{said} (see 'mindyn {command} --help')"


def _one_line(text: object) -> str:
    return "; ".join(line.strip() for line in str(text).splitlines() if line.strip())


def _error(text: object) -> None:
    said = str(text)
    if isinstance(text, ArgumentError):  # it starts with the library argument's name
        said = argument_as_flag(said)
    print(f"mindyn: error: {_one_line(library_options_as_flags(said))}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    """Runs the command line; returns the exit status. Every failure ends in one line on stderr,
    ``mindyn: error: ...``, and a non-zero status: 2 for the input (a :class:`mindyn.Error`, a
    missing file), 1 for a limit of the machine (an output that cannot be written, memory, a
    simulation past its wall-time bound, which is the Error that is a TimeoutError), 70 for
    anything else (a bare ValueError or IndexError too), which is a defect in mindyn, not in
    the input."""
    try:
        argv = list(sys.argv[1:] if argv is None else argv)
        parser = build_parser(_command(argv))
        args, extra = parser.parse_known_args(argv)
        if extra:
            raise UsageError(_unrecognized(parser, args.command, extra))
    except UsageError as e:
        _error(e)
        return 2
    except SystemExit as e:  # --help
        return e.code if isinstance(e.code, int) else 0
    try:
        reuse_freed_memory()  # long logs: large temporaries reused, not mapped anew each time
        prepare_outputs(args)
        status = warnings_after_success(args.func)(args)  # an error stays one line
        sys.stdout.flush()  # a closed pipe shows here, not at exit
        if status == 0:  # an error stays one line
            print_deprecation_notes(args)
        return status
    except FileNotFoundError as e:  # an output's path that cannot be created: as OSError below
        if isinstance(e, Error) or not is_output(args, e.filename):
            _error(e)  # the input: a missing file
            return 2
        _error(f"'{e.filename}': {e.strerror or e} (the output cannot be written there)")
        return 1
    except Error as e:  # the input: mindyn's errors
        _error(e)
        # a simulation past its wall-time bound (SimulationTimeoutError): the machine's limit,
        # as memory is, not an error in the input
        return 1 if isinstance(e, TimeoutError) else 2
    except KeyboardInterrupt:
        print("mindyn: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # The reader of stdout went away (e.g. `mindyn base ROBOT | head`): stop quietly, and
        # keep the interpreter from reporting the same error again when it flushes stdout.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 141
    except OSError as e:  # writing an output: permissions, a full disk, a folder in the way
        where = f"'{e.filename}': " if e.filename else ""
        _error(f"{where}{e.strerror or e}")
        return 1
    except MemoryError:
        _error("out of memory: the input asks for more memory than this machine has")
        return 1
    except Exception as e:  # anything else, a bare ValueError too: a defect in mindyn
        _error(
            f"unexpected {type(e).__name__}: {e} (a defect in mindyn; please report it with "
            "the command line)"
        )
        return 70


if __name__ == "__main__":
    raise SystemExit(main())
