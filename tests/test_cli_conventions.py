"""The command line's conventions, the same in every command:

- start-up: ``mindyn --help`` and the light commands (``info``, ``base``, ``codegen``, ...) do not
  import the libraries that only identification, plots or convex fits need (scipy.signal,
  scipy.stats, matplotlib, cvxpy): a command's module is imported when that command runs.
  Checked in a fresh interpreter through ``sys.modules`` (deterministic; the start-up time
  itself is measured by bench/bench_startup.py, not asserted);
- ``mindyn --version`` prints the version pyproject.toml declares.
"""

from __future__ import annotations

import contextlib
import io
import re
import subprocess
import sys
from pathlib import Path

from mindyn import cli

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("scipy.signal", "scipy.stats", "matplotlib", "cvxpy")


def run(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main([str(a) for a in argv])
    return rc, out.getvalue(), err.getvalue()


def test_version_is_pyprojects():
    text = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    (version,) = re.findall(r'(?m)^version = "([^"]+)"$', text)
    rc, out, err = run(["--version"])
    assert rc == 0, err
    assert out == f"mindyn {version}\n"


LIGHT = """
import contextlib, io, sys
import mindyn.cli
with contextlib.redirect_stdout(io.StringIO()):
    for argv in ARGVS:
        status = mindyn.cli.main(argv)
        assert status == 0, (argv, status)
print(sorted(m for m in sys.modules if m.startswith(HEAVY)))
"""


def test_help_and_light_commands_import_no_heavy_library():
    argvs = [
        ["--help"],
        ["base", "--help"],
        ["base", "planar2"],
        ["info", "planar2"],
        ["codegen", "--help"],
        ["export", "--help"],
        ["ik", "--help"],
        ["track", "--help"],
        ["demo", "--help"],
    ]
    code = LIGHT.replace("ARGVS", repr(argvs)).replace("HEAVY", repr(HEAVY))
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=False
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]", done.stdout


def test_every_command_is_declared_and_listed():
    """The full parser (every command's module imported) and the one ``--help`` uses (the
    commands' summaries alone) list the same commands, in the same order, with the same
    summaries."""

    def listing(parser):
        sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
        return [(c.dest, c.help) for c in sub._choices_actions]

    full = listing(cli.build_parser())
    assert full == listing(cli.build_parser(""))
    assert [name for name, _ in full] == list(cli.COMMANDS)
    assert all(summary for _, summary in full)
