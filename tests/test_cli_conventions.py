"""The command line's conventions, the same in every command:

- start-up: ``mindyn --help`` and the light commands (``info``, ``base``, ``codegen``, ...) do not
  import the libraries that only identification, plots or convex fits need (scipy.signal,
  scipy.stats, matplotlib, cvxpy): a command's module is imported when that command runs.
  Checked in a fresh interpreter through ``sys.modules`` (deterministic; the start-up time
  itself is measured by bench/bench_startup.py, not asserted);
- ``mindyn --version`` prints the version pyproject.toml declares;
- outputs, one rule for every output option of every command, applied before anything is
  written: two outputs naming the same file (also a file an option implies, such as codegen's
  NAME.c and NAME.h) are refused, and missing folders are created;
- one spelling per meaning (``--deg``, ``--controller-period`` / ``--excitation-period``,
  ``--torque-noise`` / ``--position-noise`` / ``--velocity-noise``, ``--rank-tolerance`` /
  ``--pose-tolerance``), the former spellings kept for one release with a note; joint vectors
  with spaces or commas; every option with a help line; no reference left unexplained.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import re
import subprocess
import sys
from pathlib import Path

import pytest
from mindyn import cli
from mindyn.cli.args import UsageError

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


def test_a_file_output_that_is_a_report_folder_is_refused_first(tmp_path):
    """--json FILE and --report FILE: the report folder was made at FILE, the fit ran, then
    writing the JSON failed ('Is a directory'), a folder left behind. Refused before anything
    is read or made, as two outputs naming one file are."""
    same = tmp_path / "new" / "out.json"
    cases = [
        ["identify", "planar2", tmp_path / "none.csv", "--json", same, "--report", same],
        ["track", "planar2", "-o", same, "--report", same],
    ]
    for argv in cases:
        rc, out, err = run(argv)
        assert rc == 2, (argv, err)
        assert "is also the folder --report writes into" in err, err
        assert len(err.splitlines()) == 1 and not (tmp_path / "new").exists()


def subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = cli.build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


def test_every_option_has_a_help_line():
    missing = [
        f"{name} {a.option_strings[-1] if a.option_strings else a.dest}"
        for name, p in subparsers().items()
        for a in p._actions
        if not (isinstance(a.help, str) and a.help.strip())
    ]
    assert not missing, missing


def test_every_option_with_a_default_value_states_it():
    """An option that takes a value when not given (not None, a flag or an empty list) says so
    in its help line ('--integration' was simpson, '--torque-unit' Nm, '--rpy' 0 0 0 unsaid)."""
    unsaid = []
    for name, p in subparsers().items():
        for a in p._actions:
            if not a.option_strings or a.help == argparse.SUPPRESS or a.dest == "help":
                continue
            if a.default is None or isinstance(a.default, bool) or a.default in ([], ()):
                continue
            if "default" not in (a.help or "").lower():
                unsaid.append(f"{name} {a.option_strings[-1]}")
    assert not unsaid, unsaid


# (command line with a former spelling, the same with the new one)
RENAMED = [
    (["base", "planar2", "--tolerance", "1e-8"], ["base", "planar2", "--rank-tolerance", "1e-8"]),
    (
        ["ik", "planar2", "--xyz", "1", "0", "0", "--tolerance", "1e-4"],
        ["ik", "planar2", "--xyz", "1", "0", "0", "--pose-tolerance", "1e-4"],
    ),
    (
        ["track", "planar2", "--period", "0.002"],
        ["track", "planar2", "--controller-period", "0.002"],
    ),
    (
        ["track", "planar2", "--noise", "0.1", "0.2"],
        ["track", "planar2", "--position-noise", "0.1", "--velocity-noise", "0.2"],
    ),
    (
        ["simulate", "planar2", "-o", "s.csv", "--period", "0.01"],
        ["simulate", "planar2", "-o", "s.csv", "--controller-period", "0.01"],
    ),
    (
        ["codegen", "planar2", "--lang", "c", "-o", "x", "--period", "0.01"],
        ["codegen", "planar2", "--lang", "c", "-o", "x", "--controller-period", "0.01"],
    ),
    (
        ["identify", "planar2", "log.csv", "--period", "2"],
        ["identify", "planar2", "log.csv", "--excitation-period", "2"],
    ),
    (
        ["excite", "planar2", "-o", "e.csv", "--degrees", "--start", "10,20"],
        ["excite", "planar2", "-o", "e.csv", "--deg", "--start", "10", "20"],
    ),
    (["demo", "--noise", "2"], ["demo", "--torque-noise", "2"]),
]


def _parsed(argv):
    args = vars(cli.build_parser(argv[0]).parse_args(argv))
    notes = args.pop("_notes", [])
    return {k: v for k, v in args.items() if not callable(v)}, notes


def test_former_spellings_do_what_the_new_ones_do_with_a_note():
    for old, new in RENAMED:
        was, notes = _parsed(old)
        now, none = _parsed(new)
        assert was == now, (old, new)
        assert not none
        assert len(notes) == 1 and "deprecated" in notes[0], notes
        assert notes[0].startswith(old[old.index(next(a for a in old if a not in new))])
    # the note is printed, on stderr, when the command succeeds
    rc, out, err = run(["base", "planar2", "--tolerance", "1e-8"])

    def untimed(text):  # the line with the computing time differs from run to run
        return [line for line in text.splitlines() if not line.strip().startswith("computed")]

    assert rc == 0 and untimed(out) == untimed(
        run(["base", "planar2", "--rank-tolerance", "1e-8"])[1]
    )
    assert err == (
        "mindyn: note: --tolerance is deprecated and will be removed in the next release; use "
        "--rank-tolerance\n"
    )


def test_former_spellings_are_not_in_the_help():
    """Anywhere in a command's help, followed by a space, a comma, a full stop or the end of a
    line (track's description said 'stable at --period,')."""
    former = re.compile(r"--(degrees|period|noise|tolerance)(?![\w-])")
    for name, p in subparsers().items():
        found = former.findall(p.format_help())
        assert not found, (name, found)


def test_joint_vectors_take_spaces_commas_or_both():
    def parse(*words):
        return cli.build_parser("ik").parse_args(["ik", "planar3", "--xyz", "1", "0", "0", *words])

    for words in (["0.1", "-0.2", "3"], ["0.1,-0.2,3"], ["0.1,-0.2", "3"], ["0.1", "-0.2,3"]):
        assert parse("--q0", *words).q0 == [0.1, -0.2, 3.0], words
    for argv, option in (
        (["excite", "planar2", "-o", "e.csv", "--start", "1", "2"], "start"),
        (["identify", "planar2", "log.csv", "--drive-gain", "1", "2"], "drive_gain"),
        (["identify", "planar2", "log.csv", "--drive-gain", "1,2"], "drive_gain"),
    ):
        assert getattr(cli.build_parser(argv[0]).parse_args(argv), option) == [1.0, 2.0]
    assert parse("--q0", "-1e-3", "-2,-3").q0 == [-1e-3, -2.0, -3.0]
    for bad in (["1,,2"], ["1,"], ["x"], ["nan"], ["1", "inf"]):
        rc, _, err = run(["ik", "planar2", "--xyz", "1", "0", "0", "--q0", *bad])
        assert rc == 2 and err.startswith("mindyn: error: argument --q0:"), (bad, err)
        assert len(err.splitlines()) == 1
    rc, _, err = run(["ik", "planar2", "--xyz", "1", "0", "0", "--q0", "1", "2", "3"])
    assert rc == 2 and "--q0 needs 2 values" in err, err


@pytest.mark.parametrize("value", ["-1%", "-1", "-.5", "-1,2", "-inf", "-2deg"])
def test_a_value_starting_with_a_minus_and_a_digit_is_every_options_value(value):
    """A word such as -1% or -inf given to any option of any command is that option's value,
    refused (or taken) by the option's own check: argparse alone read '-1%' as an option and
    said '--torque-noise: expected one argument', which names no value."""
    confused = []
    for name, p in subparsers().items():
        for a in p._actions:
            if not a.option_strings or a.nargs == 0 or a.help == argparse.SUPPRESS:
                continue
            flag = max(a.option_strings, key=len)
            words = [value] * (a.nargs if isinstance(a.nargs, int) else 1)
            try:
                cli.build_parser(name).parse_args([name, flag, *words])
            except UsageError as e:
                if re.search(r"expected (one|at least one|\d+) argument", str(e)):
                    confused.append(f"{name} {flag}: {e}")
                elif flag in str(e):
                    assert value in str(e) or "required" in str(e), (name, flag, str(e))
    assert not confused, confused


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["simulate", "--torque-noise", "-1%"], "--torque-noise: -1% is negative; a noise level"),
        (["simulate", "--torque-noise", "-1"], "--torque-noise: -1 is negative; a noise level"),
        (["simulate", "--torque-noise", "1,-0.5"], "--torque-noise: -0.5 (joint 2) is negative"),
        (["simulate", "--velocity-noise", "-1,2"], "--velocity-noise: -1 (joint 1) is negative"),
        (["simulate", "--quantization", "-1e-3"], "--quantization: -1e-3 is negative; an encoder"),
        (
            ["simulate", "--rate", "-250"],
            "--rate: expected a finite number in (0, 1e+06], got a negative value, '-250'",
        ),
        (
            ["demo", "--torque-noise", "-1%"],
            "--torque-noise: expected a finite number in [0, 100], got a negative value, '-1%'",
        ),
    ],
)
def test_a_negative_value_is_refused_as_negative_in_every_command(argv, said, tmp_path):
    """A negative noise level, encoder step or rate is refused in one line that says the value
    is negative, whichever command and spelling (P%, one value, one per joint)."""
    name, *options = argv
    out = ["--mode", "inverse", "-o", tmp_path / "log.csv"]
    rc, _, err = run([name, "planar2", *options, *(out if name == "simulate" else [])])
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert said in err, err
    assert not any(tmp_path.iterdir())  # refused before anything is written


def test_demo_torque_noise_takes_a_percentage_as_simulate_does():
    """demo --torque-noise is in percent: '2%' (simulate's spelling) is '2'."""
    parse = cli.build_parser("demo").parse_args
    assert (
        parse(["demo", "--torque-noise", "2%"]).noise
        == parse(["demo", "--torque-noise", "2"]).noise
        == 2.0
    )


def test_json_to_stdout_or_to_a_file_alike(tmp_path):
    # the tool pose at q = (0.3, 0.5) rad: (0.826, 0, 0.506) m, pitch -0.8 rad
    pose = ["--xyz", "0.826022", "0", "0.506438", "--rpy", "1.570796", "-0.8", "0"]
    for argv in (["base", "planar2"], ["ik", "planar2", *pose, "--pose-tolerance", "1e-3"]):
        rc, out, err = run([*argv, "--format", "json"])
        assert rc == 0, err
        path = tmp_path / "new" / f"{argv[0]}.json"
        rc, table, err = run([*argv, "--json", path])
        assert rc == 0, err
        printed, written = json.loads(out), json.loads(path.read_text())
        if argv[0] == "ik":  # restarts within a CPU-time budget: the same answer, not the path
            assert printed["success"] and written["success"]
            for doc in (printed, written):
                del doc["q"], doc["pose_error"], doc["iterations"], doc["attempts"]
                del doc["position_error_m"], doc["orientation_error_rad"]
        printed.pop("seconds", None), written.pop("seconds", None)  # the timing of base
        assert printed == written
        assert not table.lstrip().startswith("{")  # the table is still printed


def test_messages_say_what_they_cite():
    """No "the thesis's method"; "the ZCR07S study" is said to be a published study of the
    ZCR07S arm wherever a help text or description names it."""
    rc, out, err = run(["base", "puma560"])
    assert rc == 0, err
    assert "thesis" not in out and "Gaussian elimination" in out
    for name, p in subparsers().items():
        text = " ".join(p.format_help().split())
        assert "thesis" not in text, name
        if "ZCR07S study" in text:
            assert "published identification and adaptive PD control study" in text, name
