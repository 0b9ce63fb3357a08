"""The library's error contract, checked on its source: no bare ``ValueError`` or ``TypeError``
is raised by a library module (an argument error is a ``mindyn.ArgumentError``, any other a
``mindyn.Error`` subclass), and no message of the C++ core or of a library module names a
command-line flag (library messages name keywords; the command line translates them)."""

from __future__ import annotations

import ast
import io
import re
import tokenize
from pathlib import Path

import mindyn
import pytest
from mindyn.cli.flags import library_options_as_flags

ROOT = Path(__file__).resolve().parents[1]
# The terminal text of an identification (``report.format()``, identification/terminal.py) is
# checked too: it names keywords like any library message, and `mindyn identify` translates it
# to flags where it prints it.
LIBRARY = sorted(
    p for p in (ROOT / "python" / "mindyn").rglob("*.py") if "cli" not in p.relative_to(ROOT).parts
)
CORE = sorted(
    p
    for d in ("cpp/src", "cpp/include", "python/src")
    for p in (ROOT / d).rglob("*")
    if p.suffix in (".cpp", ".hpp", ".h")
)
FLAG = re.compile(r"(?<![\w-])--[a-z][a-z0-9]*(?:-[a-z0-9]+)*")


def test_the_library_modules_are_found():
    names = {p.name for p in LIBRARY}
    assert {"robot.py", "base.py", "estimation.py", "simulation.py"} <= names
    assert not any("cli" in p.parts for p in LIBRARY)
    assert any(p.name == "projection.cpp" for p in CORE)


@pytest.mark.parametrize("path", LIBRARY, ids=lambda p: p.name)
def test_no_bare_value_or_type_error(path):
    bad = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
            if node.func.id in ("ValueError", "TypeError"):
                bad.append(node.lineno)
        if isinstance(node, ast.Raise) and isinstance(node.exc, ast.Name):
            if node.exc.id in ("ValueError", "TypeError"):
                bad.append(node.lineno)
    text = path.read_text()
    bad += [i for i, line in enumerate(text.splitlines(), 1) if "ValueError(" in line]
    bad += [
        i
        for i, line in enumerate(text.splitlines(), 1)
        if re.search(r"raise (ValueError|TypeError)\b", line)
    ]
    assert not bad, f"{path.name}: bare ValueError/TypeError at lines {sorted(set(bad))}"


def _python_messages(path: Path):
    """The string literals of a module that are not docstrings, with their lines."""
    text = path.read_text()
    docstrings = set()
    for node in ast.walk(ast.parse(text)):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr):
            v = body[0].value
            if isinstance(v, ast.Constant) and isinstance(v.value, str):
                docstrings.add(v.lineno)
    for tok in tokenize.generate_tokens(io.StringIO(text).readline):
        if tok.type == tokenize.STRING or tok.type == getattr(tokenize, "FSTRING_MIDDLE", -1):
            if tok.start[0] not in docstrings:
                yield tok.start[0], tok.string


def _cpp_messages(path: Path):
    """The string literals of a C++ file outside comments, with their lines."""
    for i, line in enumerate(path.read_text().splitlines(), 1):
        code = line.split("//", 1)[0]
        for m in re.finditer(r'"((?:[^"\\]|\\.)*)"', code):
            yield i, m.group(1)


@pytest.mark.parametrize("path", LIBRARY + CORE, ids=lambda p: p.name)
def test_no_command_line_flag_in_a_library_message(path):
    messages = _python_messages(path) if path.suffix == ".py" else _cpp_messages(path)
    bad = [(i, s) for i, s in messages if FLAG.search(s)]
    assert not bad, f"{path.name}: command-line flags in messages: {bad[:5]}"


def test_the_check_finds_a_flag():
    assert FLAG.search("leave out --offset, or") and FLAG.search("'--friction-width'")
    assert not FLAG.search("x -- y") and not FLAG.search("a-b--c")


def test_the_command_line_names_the_flags_of_library_keywords():
    msg = "Joint(s) 2 never reverse direction: leave out offset=True (or friction=True), or"
    assert library_options_as_flags(msg).endswith("leave out --offset (or --friction), or")
    assert (
        library_options_as_flags("the recursive method (method='recursive') gives")
        == "the recursive method (--method recursive) gives"
    )
    assert library_options_as_flags("(give prior_weight=)") == "(give --prior-weight)"
    # keywords whose flag is spelled otherwise, values that are numbers or alternatives
    assert library_options_as_flags("period= needs filter='lowpass'") == (
        "--excitation-period needs --filter lowpass"
    )
    assert library_options_as_flags("decimate=False, friction=False") == (
        "--no-decimate, friction=False"
    )
    assert library_options_as_flags("cutoff=0.5 Hz (min_velocity=0)") == (
        "--cutoff 0.5 Hz (--min-velocity 0)"
    )
    assert library_options_as_flags(
        "friction_width=: expected friction_model='smooth' or 'auto'"
    ) == ("--friction-width: expected --friction-model smooth or auto")
    # other keywords and comparisons stay as they are
    assert library_options_as_flags("Ixx=0.5, dt >= 2, weight=3") == "Ixx=0.5, dt >= 2, weight=3"


def test_a_rank_deficiency_names_keywords_in_the_library_and_flags_on_the_command_line():
    import numpy as np
    from mindyn.identification import JointData, RankDeficientError, identify

    robot = mindyn.load("planar2")
    t = np.arange(0, 8, 1 / 100)
    q = np.stack([np.sin(t), 0.3 * t], axis=1)  # joint 2 turns one way only
    dq = np.stack([np.cos(t), np.full_like(t, 0.3)], axis=1)
    ddq = np.stack([-np.sin(t), np.zeros_like(t)], axis=1)
    base = mindyn.base_parameters(robot, friction=True, offset=True)
    tau = base.regressor(q, dq, ddq) @ np.ones(base.n)
    with pytest.raises(RankDeficientError) as e:
        identify(robot, JointData(t, q, dq, ddq, tau, "one-way"), base=base)
    msg = str(e.value)
    assert "leave out offset=True (or friction=True)" in msg, msg
    assert "--" not in msg
    assert "leave out --offset (or --friction)" in library_options_as_flags(msg)
