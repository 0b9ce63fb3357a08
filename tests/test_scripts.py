"""The install and test scripts, as far as they can be run without installing anything:

- they parse (``bash -n``);
- bootstrap.sh's progress filter passes the build tool's progress lines (Ninja's ``[k/N]``,
  Make's ``[ p%]``) line by line as they come, drops everything else, and ends with status 0;
- the C++ core is compiled once: scripts/test runs ctest in the build folder that bootstrap.sh
  gives pip's build (``build_dir`` of scripts/requirements.sh), configured there with the C++
  tests, and compiles nothing itself.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = ROOT / "scripts"
BASH = shutil.which("bash")
pytestmark = pytest.mark.skipif(BASH is None, reason="needs bash")


def bash(script: str, stdin: str = "", cwd: Path = ROOT) -> subprocess.CompletedProcess:
    return subprocess.run(
        [BASH, "-c", script],
        input=stdin,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
        cwd=cwd,
    )


def test_scripts_parse():
    for name in ("bootstrap.sh", "test", "requirements.sh", "mindyn", "lock", "stubs"):
        done = bash(f"bash -n scripts/{name}")
        assert done.returncode == 0, (name, done.stderr)


def _function(name: str) -> str:
    text = (SCRIPTS / "bootstrap.sh").read_text()
    m = re.search(rf"(?ms)^{name}\(\) \{{\n.*?^\}}\n", text)
    assert m, f"bootstrap.sh has no function {name}"
    return m.group(0)


def test_progress_filter_passes_progress_lines_as_they_come(tmp_path):
    feed = (
        "Collecting numpy\n"
        "  [1/40] Building CXX object CMakeFiles/mindyn.dir/cpp/src/model.cpp.o\n"
        "  -- Configuring done (2.2s)\n"
        "[ 45%] Building CXX object CMakeFiles/x.dir/y.cpp.o\n"
        "warning: [1/2] is not at the start\n"
        "  [40/40] Linking CXX shared module _core.so\n"
        "Successfully installed mindyn-0.2.0\n"
    )
    done = bash(_function("progress") + "set -euo pipefail\nprogress", feed)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == [
        "bootstrap:   [1/40] Building CXX object CMakeFiles/mindyn.dir/cpp/src/model.cpp.o",
        "bootstrap:   [ 45%] Building CXX object CMakeFiles/x.dir/y.cpp.o",
        "bootstrap:   [40/40] Linking CXX shared module _core.so",
    ]
    # one line in, one line out, before the input ends: the producer waits for the reader to
    # have the first line before it writes the second (a filter that buffers makes it "late")
    script = _function("progress") + (
        "set -euo pipefail\n"
        "{ echo '[1/2] a'; if read -r -t 20 line <> reply; then echo '[2/2] b'; "
        "else echo '[2/2] late'; fi; } | progress"
        ' | { read -r first; echo "$first"; echo go 1<> reply; cat; }\n'
    )
    done = bash(f'cd "$(mktemp -d)" && mkfifo reply && {{\n{script}}}')
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == ["bootstrap:   [1/2] a", "bootstrap:   [2/2] b"]


def test_cpp_tests_run_in_the_build_pip_made():
    done = bash(f"source scripts/requirements.sh && build_dir {sys.executable}")
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == f"build/python-{sys.implementation.cache_tag}"
    boot = (SCRIPTS / "bootstrap.sh").read_text()
    assert 'build="$(build_dir "$py")"' in boot
    assert '"--config-settings=build-dir=$build"' in boot
    assert "--config-settings=cmake.define.MINDYN_BUILD_TESTS=ON" in boot
    test = (SCRIPTS / "test").read_text()
    assert 'build="$(build_dir "$py")"' in test
    assert re.search(r'(?m)^ctest --test-dir "\$build" ', test)
    assert "cmake --build" not in test and "cmake -S" not in test  # nothing compiled twice
    # the wheel takes the extension alone; the C++ package goes to `cmake --install` only
    assert 'install.components = ["python"]' in (ROOT / "pyproject.toml").read_text()
    assert (
        "install(TARGETS _core DESTINATION mindyn COMPONENT python)"
        in (ROOT / "CMakeLists.txt").read_text()
    )
