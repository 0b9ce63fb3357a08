"""The manual builds and its examples run as written.

The manual is README.md and the pages of docs/ (mkdocs.yml). It is built by MkDocs in strict
mode, where a broken link or reference fails the build. Every code block of README.md and of the
pages is checked, as a user would meet it after the two commands at the top of the README:

- ```sh blocks: each line (a line ending in a backslash joined with the next) is one command run
  by bash from a folder where the repository's relative paths (``examples/...``) resolve, with
  the virtual environment's ``bin`` first on the ``PATH`` (what ``. .venv/bin/activate`` does);
  it must exit with 0 and print no traceback;
- ```python blocks: run by the environment's Python in that folder, likewise;
- ```cpp blocks: compiled against the headers the package installs (``cpp/include``, with
  Eigen);
- ```iecst blocks: parsed as Structured Text by the independent IEC 61131-3 grammar.

README.md runs in a folder of its own; the pages run in one folder, in the order of the manual's
navigation, since they build on each other (the identification writes the logs and the JSON
that the code generation and the collision detection read). The blocks not run are listed in
``not_run_reason`` with the reason; a block that is neither run nor listed fails the test, so
none is left out silently.

Also here: the command-line reference that the build generates equals what ``mindyn CMD
--help`` prints, the errors page names every error class, every public C++ header points to the
notation page, and the URDF the manual uses, ``examples/urdf/ur5.urdf``, against the published
UR5 DH table it states (tool pose, and gravity torques against finite differences of the
potential energy computed from the published masses and centres of mass).
"""

from __future__ import annotations

import importlib.util
import inspect
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import mindyn
import numpy as np
import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]
README = REPO / "README.md"
DOCS = REPO / "docs"
BIN = Path(sys.executable).parent  # the environment running the tests: the one they check


def nav_pages() -> list[Path]:
    """The pages of the manual in the order of its navigation (mkdocs.yml)."""

    def walk(items):
        for item in items:
            value = next(iter(item.values())) if isinstance(item, dict) else item
            if isinstance(value, list):
                yield from walk(value)
            else:
                yield DOCS / value

    return list(walk(yaml.safe_load((REPO / "mkdocs.yml").read_text())["nav"]))


@dataclass
class Block:
    file: Path
    lang: str
    line: int  # line of the opening fence
    text: str

    @property
    def id(self) -> str:
        return f"{self.file.relative_to(REPO)}:{self.line}"


def blocks_of(path: Path) -> list[Block]:
    blocks, fence = [], None
    for no, line in enumerate(path.read_text().splitlines(), 1):
        if fence is None:
            m = re.match(r"^```(\w*)\s*$", line)
            if m:
                fence, lang, start, body = line, m.group(1), no, []
        elif line.startswith("```"):
            blocks.append(Block(path, lang, start, "\n".join(body)))
            fence = None
        else:
            body.append(line)
    assert fence is None, f"{path}: a code fence is not closed"
    return blocks


def not_run_reason(b: Block) -> str | None:
    """Why a block is not run, or None when it is run."""
    if "scripts/mindyn demo" in b.text and "scripts/test" in b.text:
        return "the two install commands (the tests themselves run after them)"
    if b.text.strip() == ".venv/bin/mkdocs serve":
        return "a server; the site's build is test_docs_build_in_strict_mode"
    if b.file.name == "benchmarks.md":
        return "benchmarks: minutes of timing runs, tried by hand"
    return None


PAGES = nav_pages()
README_BLOCKS = blocks_of(README)
DOCS_BLOCKS = [b for page in PAGES for b in blocks_of(page)]
ALL = README_BLOCKS + DOCS_BLOCKS
RUNNABLE = ("sh", "python")


def test_every_page_is_in_the_navigation():
    on_disk = {p for p in DOCS.rglob("*.md")}
    assert on_disk == set(PAGES), on_disk ^ set(PAGES)


def test_every_block_is_checked_or_listed_with_a_reason():
    """The blocks are of the kinds checked here; any other language would be left out."""
    for b in ALL:
        if not_run_reason(b) is None:
            assert b.lang in (*RUNNABLE, "cpp", "iecst"), f"{b.id}: ```{b.lang} block not checked"
    skipped = [b.id for b in ALL if not_run_reason(b) is not None]
    # the install commands of the README and of getting started, the manual's server and the
    # benchmarks: nothing else
    assert len(skipped) == 4, skipped
    assert sum(b.lang == "cpp" for b in ALL) == 2 and sum(b.lang == "iecst" for b in ALL) == 1


def test_structured_text_blocks_parse():
    """The PLC program the manual shows (calling the generated function block) is Structured
    Text by the independent IEC 61131-3 grammar."""
    from test_codegen import st_tree

    blocks = [b for b in ALL if b.lang == "iecst"]
    assert blocks
    for b in blocks:
        st_tree(b.text)


def _eigen_include() -> str:
    for d in ("/usr/include/eigen3", "/usr/local/include/eigen3"):
        if (Path(d) / "Eigen" / "Core").is_file():
            return d
    pytest.fail("Eigen's headers (libeigen3-dev) are not installed: the C++ examples need them")


@pytest.mark.parametrize("block", [b for b in ALL if b.lang == "cpp"], ids=lambda b: b.id)
def test_cpp_block_compiles(block, tmp_path):
    """A C++ example compiles against the installed headers as a complete program."""
    compiler = shutil.which("c++") or shutil.which("g++") or shutil.which("clang++")
    assert compiler, "no C++ compiler on the PATH"
    src = tmp_path / "example.cpp"
    src.write_text(block.text + "\n")
    res = subprocess.run(
        [
            compiler,
            "-std=c++17",
            "-fsyntax-only",
            "-Wall",
            "-Werror",
            "-I",
            str(REPO / "cpp/include"),
        ]
        + ["-isystem", _eigen_include(), str(src)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert res.returncode == 0, f"{block.id}\n{res.stderr[-3000:]}"


def commands(block: Block) -> list[str]:
    """The commands of a sh block: its lines, a line ending in a backslash joined with the next
    as the shell does; comments and blank lines are not commands."""
    text = re.sub(r"\\\n", " ", block.text)
    return [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]


@pytest.fixture(scope="module")
def workdirs(tmp_path_factory):
    """Folders standing in for the repository root, one for the README and one for the manual:
    the relative paths of the examples resolve (``examples`` and the bundled robots are the
    repository's), the files the examples write stay out of the repository."""
    assert (BIN / "mindyn").is_file(), f"no 'mindyn' beside {sys.executable}"
    out = {}
    for name in ("readme", "docs"):
        d = tmp_path_factory.mktemp(name)
        (d / "examples").symlink_to(REPO / "examples", target_is_directory=True)
        out[name] = d
    return out


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


def _run_block(block: Block, cwd, env) -> None:
    if block.lang == "python":
        _run([sys.executable, "-c", block.text], cwd, env, f"{block.id} python")
    else:
        for cmd in commands(block):
            _run(["bash", "-e", "-o", "pipefail", "-c", cmd], cwd, env, f"{block.id}: {cmd}")
    DONE.add(block.id)


def _runs(blocks: list[Block]) -> list[Block]:
    return [b for b in blocks if b.lang in RUNNABLE and not_run_reason(b) is None]


RUN = {"readme": _runs(README_BLOCKS), "docs": _runs(DOCS_BLOCKS)}


def _run_in_order(where: str, block: Block, workdirs, env) -> None:
    # The blocks build on each other (logs, then identification, then code from its JSON): the
    # earlier ones run first when they have not (a block selected alone with -k), and after a
    # failure the later ones are reported as failing for that reason, not skipped.
    run = RUN[where]
    for earlier in run[: run.index(block)]:
        if FAILED:
            break
        if earlier.id not in DONE:
            _run_block(earlier, workdirs[where], env)
    if FAILED:
        pytest.fail(f"not run: an earlier example failed ({FAILED[0]})")
    _run_block(block, workdirs[where], env)


@pytest.mark.parametrize("block", RUN["readme"], ids=lambda b: b.id)
def test_readme_block_runs(block, workdirs, env):
    _run_in_order("readme", block, workdirs, env)


@pytest.mark.parametrize("block", RUN["docs"], ids=lambda b: b.id)
def test_docs_block_runs(block, workdirs, env):
    _run_in_order("docs", block, workdirs, env)


def test_docs_examples_made_what_they_say(workdirs, env):
    """After the blocks ran: the files the manual names exist, the validation log says its
    torque unit, and the code generator took the identified JSON with its pruned parameters as
    zero (as many as the JSON lists)."""
    for block in RUN["docs"]:
        if not FAILED and block.id not in DONE:
            _run_block(block, workdirs["docs"], env)
    if FAILED:
        pytest.fail(f"the examples did not all run ({FAILED[0]} failed)")
    wd = workdirs["docs"]
    for f in (
        "out/traj.json",
        "out/data.csv",
        "out/other.csv",
        "out/id.json",
        "out/puma560_dyn.c",
        "out/puma560_dyn.h",
        "out/zcr07s.st",
        "out/pd.csv",
        "out/zcr07s_apd.c",
        "out/zcr07s.xml",
        "out/zcr07s_obs.c",
        "out/ur5_identified.xml",
    ):
        assert (wd / f).is_file(), f
    head = (wd / "out/other.csv").read_text().splitlines()[0].split(",")
    assert head[-6:] == [f"tau{j}[permille]" for j in range(1, 7)]
    removed = json.loads((wd / "out/id.json").read_text())["removed"]
    said = [o for c, o in OUTPUT.items() if "--params out/id.json" in c]
    # the code of the identified model, the two controller steps starting from it and the
    # momentum observer of it
    assert len(said) == 4, said
    assert all(f"; {len(removed)} pruned in identification" in o for o in said), said
    # the UR5 example follows an optimised excitation: no warning that most base parameters
    # were removed, and the five largest (by the simulation's true values) within 2 % of them
    ur5 = [
        o for c, o in OUTPUT.items() if ": mindyn identify examples/urdf/ur5.urdf out/ur5.csv" in c
    ]
    assert len(ur5) == 1 and "WARNING" not in ur5[0], ur5
    doc = json.loads((wd / "out/ur5_id.json").read_text())
    est, true = np.array(doc["base_values"]), np.array(doc["true_values"])
    big = np.argsort(-np.abs(true))[:5]
    assert np.all(np.abs(est[big] - true[big]) <= 0.02 * np.abs(true[big])), (est, true)
    # not the "most parameters removed" warning's case (more than half removed)
    assert 2 * len(doc["removed"]) <= len(true)
    # the count this run gives lies in the range the manual states
    page = (DOCS / "identification.md").read_text()
    stated = re.search(r"Here\s+(\d+)\s+to\s+(\d+)\s+of\s+the\s+(\d+)\s+are\s+kept", page)
    assert stated, "the UR5 example's kept count is no longer stated"
    low, high, total = (int(stated[k]) for k in (1, 2, 3))
    assert low <= len(doc["names"]) <= high and total == len(true), (stated[0], len(doc["names"]))
    # every file the examples write is in out/, which git ignores ("Running the examples")
    assert sorted(p.name for p in wd.iterdir()) == ["examples", "out"], list(wd.iterdir())


# ---------------------------------------------------------------------------------------------
# The site
# ---------------------------------------------------------------------------------------------
def _build(config: Path, site: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(config), "-d", str(site)],
        capture_output=True,
        text=True,
        timeout=600,
    )


def test_docs_build_in_strict_mode(tmp_path):
    """The manual builds with no warning (a broken link, anchor or API reference is one), into
    a folder outside the repository; the generated command-line reference is in it."""
    res = _build(REPO / "mkdocs.yml", tmp_path / "site")
    assert res.returncode == 0, res.stderr[-3000:]
    cli = (tmp_path / "site/cli/index.html").read_text()
    assert "mindyn identify-payload" in cli
    assert (tmp_path / "site/api/mindyn/index.html").is_file()


def test_a_broken_link_fails_the_build(tmp_path):
    """The configuration makes a link to a missing page, and one to a missing anchor, errors
    that fail the build."""
    shutil.copytree(DOCS, tmp_path / "docs")
    shutil.copy(REPO / "mkdocs.yml", tmp_path / "mkdocs.yml")
    page = tmp_path / "docs/errors.md"
    page.write_text(page.read_text() + "\n[a](no-such-page.md) [b](notation.md#no-such-section)\n")
    res = _build(tmp_path / "mkdocs.yml", tmp_path / "site")
    assert res.returncode != 0
    assert "no-such-page.md" in res.stderr and "no-such-section" in res.stderr, res.stderr[-2000:]


def _slug(heading: str) -> str:
    """The anchor of a heading, as MkDocs' and GitHub's renderers make it for plain headings."""
    return re.sub(r"\s+", "-", re.sub(r"[^\w\s-]", "", heading.strip().lower()))


def test_readme_links_into_the_manual_resolve():
    """The README is read outside the site (on the repository's page), so the strict build does
    not see its links: each relative link names an existing file, and a heading of it."""
    links = re.findall(r"\]\(([^)\s]+)\)", README.read_text())
    local = [link for link in links if not re.match(r"\w+://", link)]
    assert len(local) >= 10, local
    for link in local:
        path, _, anchor = link.partition("#")
        target = REPO / path
        assert target.is_file(), link
        if anchor:
            headings = re.findall(r"^#+ (.+)$", target.read_text(), re.M)
            assert anchor in {_slug(h) for h in headings}, link


def _hook():
    spec = importlib.util.spec_from_file_location("cli_reference", DOCS / "hooks/cli_reference.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_cli_reference_is_what_help_prints(env, monkeypatch, capsys):
    """The reference the build generates from the whole parser holds, for every command, the
    text that ``mindyn COMMAND --help`` prints at the same width (the command line declares only
    that command's options): the reference is the parser's."""
    from mindyn.cli import build_parser, main

    hook = _hook()
    text = hook.reference()
    commands = re.findall(r"^## mindyn (\S+)$", text, re.M)
    # every command the parser dispatches on, once
    dispatch = next(a for a in build_parser()._actions if a.dest == "command")
    assert sorted(commands) == sorted(dispatch.choices), commands
    monkeypatch.setenv("COLUMNS", hook.WIDTH)
    for name in commands:
        assert main([name, "--help"]) == 0
        assert capsys.readouterr().out.rstrip() in text, name
    # and the installed command's own help, as a user runs it
    res = subprocess.run(
        [str(BIN / "mindyn"), "--help"],
        env=dict(env, COLUMNS=hook.WIDTH),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert res.returncode == 0 and res.stdout.rstrip() in text, res.stderr
    assert hook.MARKER in (DOCS / "cli.md").read_text()


def _error_classes() -> set[type]:
    import mindyn.control
    import mindyn.identification
    import mindyn.identification.data

    found = set()
    for module in (mindyn, mindyn.identification, mindyn.identification.data, mindyn.control):
        for name, obj in vars(module).items():
            if not name.startswith("_") and inspect.isclass(obj) and issubclass(obj, mindyn.Error):
                found.add(obj)
    return found


def test_errors_page_names_every_error_class():
    page = (DOCS / "errors.md").read_text()
    classes = _error_classes()
    assert mindyn.ModelError in classes and len(classes) >= 10, classes
    for cls in classes:
        assert f"`{cls.__name__}`" in page or f".{cls.__name__}`" in page, cls.__name__
        # and with the standard base it keeps
        bases = [b.__name__ for b in cls.__mro__[1:] if b.__module__ == "builtins"]
        row = next(
            ln for ln in page.splitlines() if re.match(rf"\| `[\w.]*\b{cls.__name__}` \|", ln)
        )
        assert any(f"`{b}`" in row for b in bases), (cls.__name__, bases, row)


_FLOATING_YAML = """\
name: hop
convention: mdh
joints:
  - {name: base, type: floating, alpha: 0, d: 0, theta: 0, r: 0,
     inertial: {mass: 5.0, com: [0, 0, 0.1], inertia: {xx: 0.1, yy: 0.1, zz: 0.05}}}
  - {name: knee, type: revolute, alpha: 1.5708, d: 0, theta: 0, r: 0,
     inertial: {mass: 0.5, com: [0.2, 0, 0], inertia: {xx: 0.001, yy: 0.01, zz: 0.01}}}
"""


def test_the_commands_the_manual_says_take_or_refuse_a_floating_robot_do(tmp_path):
    """The identification page lists the commands that take a robot with a floating root and
    those that refuse it: each one does what the page says, on a YAML table whose root is a
    free-flyer (a revolute joint below it), and the page's two lists together are every command
    that the refusal's own message does not name as taking such a robot."""
    import contextlib
    import io

    from mindyn.cli import main

    text = " ".join((DOCS / "identification.md").read_text().split())
    start = text.index("The other commands take a robot with `--root-joint` where they can:")
    sentence = text[start : text.index("in one line.", start)]
    take_part, refuse_part = sentence.split(";")[0], sentence.split(";")[-1]
    assert "refuse a robot with joints of several degrees of freedom" in refuse_part
    taking = set(re.findall(r"`(?:mindyn )?([a-z-]+)`", take_part)) - {"--root-joint"}
    refusing = set(re.findall(r"`([a-z-]+)`", refuse_part))
    robot_yaml = tmp_path / "hop.yaml"
    robot_yaml.write_text(_FLOATING_YAML)
    robot = mindyn.load(robot_yaml)
    ident = tmp_path / "id.json"
    ident.write_text(json.dumps({"classical": dict(zip(robot.param_names, robot.params.tolist()))}))
    log = tmp_path / "log.csv"
    log.write_text("t,q1\n")
    extra = {
        "excite": ["-o", tmp_path / "e.csv"],
        "simulate": ["-o", tmp_path / "s.csv"],
        "track": [],
        "ik": ["--xyz", "0", "0", "1"],
        "detect": [ident, log],
        "predict": [ident, log, "-o", tmp_path / "p.csv"],
        "identify-payload": [ident, log],
        "demo": ["--out", tmp_path / "demo"],
        "info": [],
        "base": [],
        "codegen": ["--lang", "c", "-o", tmp_path / "hop"],
        "export": [ident, "--yaml", tmp_path / "out.yaml"],
    }

    def run(cmd):
        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            rc = main([cmd, str(robot_yaml), *map(str, extra[cmd])])
        return rc, err.getvalue()

    assert refusing and taking >= {"info", "base"}, (taking, refusing)
    for cmd in sorted(refusing):
        rc, err = run(cmd)
        assert rc == 2 and "takes revolute and prismatic joints only" in err, (cmd, err)
        # the refusal names what takes such a robot: the page's other list, and identify
        named = err.split("for such a robot:")[1]
        for other in taking | {"identify"}:
            assert re.search(rf"\b{other}\b", named), (other, err)
    for cmd in sorted(taking):
        rc, err = run(cmd)
        assert rc == 0, (cmd, err)


def test_every_public_header_points_to_the_notation_page():
    headers = sorted((REPO / "cpp/include/mindyn").rglob("*.hpp"))
    assert len(headers) > 20
    for h in headers:
        head = h.read_text().split("#pragma once")[0]
        assert "docs/notation.md" in head, h
    assert not [h for h in headers if re.search(r"docs, sections?", h.read_text())]


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
