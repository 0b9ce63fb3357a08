"""The README's examples run as written.

Every ```sh and ```python block of README.md is run in the order of the README, as a user would
after the two commands at its top: from a folder where the repository's relative paths
(``examples/...``) resolve, with the virtual environment's ``bin`` first on the ``PATH`` (what
``. .venv/bin/activate`` does), each line of a sh block as one command that must exit with 0
and print no traceback. The blocks not run are listed in ``NOT_RUN`` with the reason; a block
that is neither run nor listed fails the test, so none is left out silently.

Also here: the URDF the README uses, ``examples/urdf/ur5.urdf``, against the published UR5 DH
table it states (tool pose, and gravity torques against finite differences of the potential
energy computed from the published masses and centres of mass).
"""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import mindyn
import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]
README = REPO / "README.md"
BIN = Path(sys.executable).parent  # the environment running the tests: the one they check


@dataclass
class Block:
    lang: str
    section: str  # the "## " heading above the block ("" before the first)
    line: int  # README line of the opening fence
    text: str

    @property
    def id(self) -> str:
        return f"{self.lang}@{self.line}"


def readme_blocks() -> list[Block]:
    blocks, section, fence = [], "", None
    for no, line in enumerate(README.read_text().splitlines(), 1):
        if fence is None:
            if line.startswith("## "):
                section = line[3:].strip()
            m = re.match(r"^```(\w*)\s*$", line)
            if m:
                fence, lang, start, body = line, m.group(1), no, []
        elif line.startswith("```"):
            blocks.append(Block(lang, section, start, "\n".join(body)))
            fence = None
        else:
            body.append(line)
    assert fence is None, "README.md: a code fence is not closed"
    return blocks


def not_run_reason(b: Block) -> str | None:
    """Why a block is not run, or None when it is run."""
    if b.section == "" and "scripts/mindyn demo" in b.text and "scripts/test" in b.text:
        return "the two install commands at the top (the tests themselves run after them)"
    if b.section == "Benchmarks":
        return "benchmarks: minutes of timing runs, tried by hand"
    if b.lang == "cpp":
        return "a C++ fragment; the complete program is examples/consumer (ctest consumer.*)"
    if b.lang == "iecst":
        return "Structured Text for a PLC program; parsed by test_structured_text_blocks_parse"
    return None


BLOCKS = readme_blocks()
RUN = [b for b in BLOCKS if not_run_reason(b) is None]


def test_every_block_is_run_or_listed_with_a_reason():
    """The README has exactly these kinds of blocks; any other language would be left out."""
    for b in BLOCKS:
        if not_run_reason(b) is None:
            assert b.lang in ("sh", "python"), f"README.md:{b.line}: ```{b.lang} block not run"
    skipped = [b for b in BLOCKS if not_run_reason(b) is not None]
    # nothing else is left out: the top commands, the CODESYS program, the C++ fragment and
    # the benchmarks
    assert [b.section or "top" for b in skipped] == [
        "top",
        "Generated code",
        "C++",
        "Benchmarks",
    ], [(b.id, b.section) for b in skipped]
    assert sum(b.lang == "sh" for b in RUN) == 7 and sum(b.lang == "python" for b in RUN) == 1


def test_structured_text_blocks_parse():
    """The PLC program the README shows (calling the generated function block) is Structured
    Text by the independent IEC 61131-3 grammar."""
    from test_codegen import st_tree

    blocks = [b for b in BLOCKS if b.lang == "iecst"]
    assert blocks
    for b in blocks:
        st_tree(b.text)


def commands(block: Block) -> list[str]:
    """The commands of a sh block: its lines, a line ending in a backslash joined with the next
    as the shell does; comments and blank lines are not commands."""
    text = re.sub(r"\\\n", " ", block.text)
    return [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    """A folder standing in for the repository root: the relative paths of the README resolve
    (``examples`` is the repository's), the files the examples write stay out of the
    repository."""
    assert (BIN / "mindyn").is_file(), f"no 'mindyn' beside {sys.executable}"
    d = tmp_path_factory.mktemp("readme")
    (d / "examples").symlink_to(REPO / "examples", target_is_directory=True)
    return d


@pytest.fixture(scope="module")
def env():
    e = dict(os.environ)
    e["PATH"] = f"{BIN}{os.pathsep}{e.get('PATH', '')}"
    e["VIRTUAL_ENV"] = str(BIN.parent)
    e["MPLBACKEND"] = "Agg"
    return e


TIMES: dict[str, float] = {}
OUTPUT: dict[str, str] = {}
FAILED: list[str] = []


def _run(argv, cwd, env, what: str) -> subprocess.CompletedProcess:
    t0 = time.perf_counter()
    res = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True, timeout=300)
    TIMES[what] = time.perf_counter() - t0
    print(f"{TIMES[what]:7.1f} s  {what}")
    out = OUTPUT[what] = res.stdout + res.stderr
    if res.returncode != 0 or "Traceback" in out:
        FAILED.append(what)
        pytest.fail(f"{what}\nexit status {res.returncode}\n{out[-3000:]}")
    return res


DONE: set[str] = set()


def _run_block(block: Block, workdir, env) -> None:
    if block.lang == "python":
        _run([sys.executable, "-c", block.text], workdir, env, f"README.md:{block.line} python")
    else:
        for cmd in commands(block):
            _run(["bash", "-e", "-o", "pipefail", "-c", cmd], workdir, env, cmd)
    DONE.add(block.id)


@pytest.mark.parametrize("block", RUN, ids=[b.id for b in RUN])
def test_readme_block_runs(block, workdir, env):
    # The blocks build on each other (logs, then identification, then code from its JSON): the
    # earlier ones run first when they have not (a block selected alone with -k), and after a
    # failure the later ones are reported as failing for that reason, not skipped.
    for earlier in RUN[: RUN.index(block)]:
        if FAILED:
            break
        if earlier.id not in DONE:
            _run_block(earlier, workdir, env)
    if FAILED:
        pytest.fail(f"not run: an earlier README example failed ({FAILED[0]})")
    _run_block(block, workdir, env)


def test_readme_examples_made_what_they_say(workdir, env):
    """After the blocks ran: the files the README names exist, the validation log says its
    torque unit, and the code generator took the identified JSON with its pruned parameters as
    zero (as many as the JSON lists)."""
    for block in RUN:
        if not FAILED and block.id not in DONE:
            _run_block(block, workdir, env)
    if FAILED:
        pytest.fail(f"the README examples did not all run ({FAILED[0]} failed)")
    for f in (
        "out/traj.json",
        "out/data.csv",
        "out/other.csv",
        "out/id.json",
        "out/puma560_dyn.c",
        "out/puma560_dyn.h",
        "out/zcr07s.st",
        "out/pd.csv",
    ):
        assert (workdir / f).is_file(), f
    head = (workdir / "out/other.csv").read_text().splitlines()[0].split(",")
    assert head[-6:] == [f"tau{j}[permille]" for j in range(1, 7)]
    removed = json.loads((workdir / "out/id.json").read_text())["removed"]
    said = [o for c, o in OUTPUT.items() if "--params out/id.json" in c]
    # the code of the identified model, the two controller steps starting from it and the
    # momentum observer of it
    assert len(said) == 4, said
    assert all(f"; {len(removed)} pruned in identification" in o for o in said), said
    # the UR5 example follows an optimised excitation: no warning that most base parameters
    # were removed, and the five largest (by the simulation's true values) within 2 % of them
    ur5 = [o for c, o in OUTPUT.items() if c.startswith("mindyn identify examples/urdf/ur5")]
    assert len(ur5) == 1 and "WARNING" not in ur5[0], ur5
    doc = json.loads((workdir / "out/ur5_id.json").read_text())
    est, true = np.array(doc["base_values"]), np.array(doc["true_values"])
    big = np.argsort(-np.abs(true))[:5]
    assert np.all(np.abs(est[big] - true[big]) <= 0.02 * np.abs(true[big])), (est, true)
    assert len(doc["removed"]) < len(true) / 2


# ---------------------------------------------------------------------------------------------
# examples/urdf/ur5.urdf against the published table it states
# ---------------------------------------------------------------------------------------------
UR5_A = [0.0, -0.425, -0.39225, 0.0, 0.0, 0.0]
UR5_D = [0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823]
UR5_ALPHA = [math.pi / 2, 0.0, 0.0, math.pi / 2, -math.pi / 2, 0.0]
UR5_MASS = [3.7, 8.393, 2.33, 1.219, 1.219, 0.1879]
UR5_COM = [  # in DH frame i
    [0.0, -0.02561, 0.00193],
    [0.2125, 0.0, 0.11336],
    [0.15, 0.0, 0.0265],
    [0.0, -0.0018, 0.01634],
    [0.0, 0.0018, 0.01634],
    [0.0, 0.0, -0.001159],
]


def _dh_frames(q):
    """Standard DH: T_i = T_{i-1} Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i); frames 1..6."""
    T, out = np.eye(4), []
    for qi, a, d, al in zip(q, UR5_A, UR5_D, UR5_ALPHA):
        ct, st, ca, sa = math.cos(qi), math.sin(qi), math.cos(al), math.sin(al)
        A = np.array(
            [[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, d]]
        )
        T = T @ np.vstack([A, [0, 0, 0, 1]])
        out.append(T)
    return out


def _potential(q, g=9.81):
    return sum(
        m * g * (T @ np.append(c, 1.0))[2]
        for T, m, c in zip(_dh_frames(q), UR5_MASS, UR5_COM, strict=True)
    )


def test_example_urdf_is_the_published_ur5():
    robot = mindyn.load(str(REPO / "examples/urdf/ur5.urdf"), tip="tool0")
    assert robot.n == 6
    # masses as published (the URDF writes them with all their digits)
    assert np.allclose(robot.params.reshape(6, 10)[:, 9], UR5_MASS, rtol=0, atol=1e-12)
    rng = np.random.default_rng(3)
    for q in rng.uniform(-np.pi, np.pi, (5, 6)):
        # tool pose: the URDF rounds pi/2 to 1.570796327 (2.1e-10 rad off) in 3 joints of a
        # 1 m arm: up to ~1e-9 apart; 1e-8 leaves a margin and still catches any real offset
        assert np.allclose(robot.fk(q), _dh_frames(q)[-1], rtol=0, atol=1e-8)
        # gravity torque = dV/dq, V from the published masses and centres of mass; central
        # differences with h = 1e-6: truncation ~h^2 V'''/6 ~ 1e-11, round-off ~1e-16 V / h ~
        # 1e-8 N m (V ~ 100 J); the tolerance 1e-6 N m leaves a margin of 100
        h = 1e-6
        dv = [(_potential(q + h * e) - _potential(q - h * e)) / (2 * h) for e in np.eye(6)]
        assert np.allclose(robot.gravity_torque(q), dv, atol=1e-6)
