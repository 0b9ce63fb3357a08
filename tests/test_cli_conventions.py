"""The command line's conventions, the same in every command:

- start-up: ``mindyn --help`` and the light commands (``info``, ``base``, ``codegen``, ...) do not
  import the libraries that only identification, plots or convex fits need (scipy.signal,
  scipy.stats, matplotlib, cvxpy): a command's module is imported when that command runs.
  Checked in a fresh interpreter through ``sys.modules`` (deterministic; the start-up time
  itself is measured by bench/bench_startup.py, not asserted);
- ``mindyn --version`` prints the version pyproject.toml declares;
- outputs, one rule for every output option of every command, applied before anything is
  written: two outputs naming the same file (also a file an option implies, such as codegen's
  NAME.c and NAME.h) are refused, and missing folders are created.
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


def test_codegen_refuses_plcopen_onto_its_c_files_before_writing(tmp_path):
    src = tmp_path / "arm.c"
    src.write_text("keep\n")
    for plcopen in ("arm.c", "arm.h", "./sub/../arm.c"):
        rc, out, err = run(
            ["codegen", "planar2", "--lang", "c", "-o", src, "--plcopen", tmp_path / plcopen]
        )
        assert rc == 2, (plcopen, out, err)
        assert err.startswith("mindyn: error: --plcopen") and "its own file" in err, err
        assert len(err.splitlines()) == 1, err
        assert src.read_text() == "keep\n"  # nothing written
        assert not (tmp_path / "arm.h").exists()
    st = tmp_path / "arm.st"
    rc, out, err = run(["codegen", "planar2", "--lang", "st", "-o", st, "--plcopen", st])
    assert rc == 2 and "its own file" in err, err
    assert not st.exists()


def test_codegen_creates_missing_folders_of_every_output(tmp_path):
    c = tmp_path / "a" / "b" / "arm"
    xml = tmp_path / "c" / "d" / "arm.xml"
    rc, out, err = run(["codegen", "planar2", "--lang", "c", "-o", c, "--plcopen", xml])
    assert rc == 0, err
    assert '#include "arm.h"' in (c.parent / "arm.c").read_text()  # the source includes its header
    assert (c.parent / "arm.h").is_file()
    assert xml.read_text().lstrip().startswith("<?xml")


def test_same_output_twice_is_refused_in_every_command(tmp_path):
    """Commands with several output options: the same file for two of them is refused before
    the command reads or writes anything (the log named here does not even exist)."""
    same = tmp_path / "new" / "out.json"
    cases = [
        ["identify", "planar2", tmp_path / "none.csv", "--json", same, "--urdf", same],
        ["export", "planar2", tmp_path / "none.json", "--yaml", same, "--sidecar", same],
    ]
    for argv in cases:
        rc, out, err = run(argv)
        assert rc == 2, (argv, err)
        assert "its own file" in err and len(err.splitlines()) == 1, err
        assert not (tmp_path / "new").exists()  # nothing created
