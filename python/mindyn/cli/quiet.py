"""Numerical warnings of a command (every command, through :func:`mindyn.cli.main`): held back
until it succeeds, so that an error stays the one line it is (numpy's RuntimeWarnings, printed
as they happen, came before it); the library's notes (e.g. :class:`mindyn.DriveTrainWarning`)
alike, with the library's keywords as the command's flags."""

from __future__ import annotations

import functools
import sys
import warnings

from .flags import library_options_as_flags


def warnings_after_success(command):
    """Wraps a ``cmd_*(args)``: the warnings it raises are recorded; when it returns they are
    printed once each to stderr as ``mindyn: warning: ...`` lines, when it raises they are
    dropped (the error says what went wrong)."""

    @functools.wraps(command)
    def run(args):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", RuntimeWarning)
            status = command(args)
        seen = set()
        for w in caught:
            text = " ".join(str(w.message).split())
            if text not in seen:
                seen.add(text)
                kind = "numerical" if issubclass(w.category, RuntimeWarning) else "note"
                if kind == "note":
                    text = library_options_as_flags(text)
                print(f"mindyn: warning: {text} ({kind})", file=sys.stderr)
        return status

    return run
