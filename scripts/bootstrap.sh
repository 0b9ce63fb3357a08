#!/usr/bin/env bash
# Installs what mindyn needs on Debian 12 (apt packages, a virtual environment in .venv, the
# package itself) and does nothing that is already done.
# Usage: bootstrap.sh [--test [--unpinned]]
#   --test      also the test toolchain (Debian packages and mindyn[test]), at the versions pinned
#               in constraints.txt (refreshed by scripts/lock)
#   --unpinned  with --test: the newest versions the package index serves instead of the pins
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
test=0 pins=(-c constraints.txt)
for arg in "$@"; do
  case "$arg" in
    --test) test=1 ;;
    --unpinned) pins=(--upgrade --upgrade-strategy eager) ;;
    *) echo "bootstrap: unknown option $arg (usage: bootstrap.sh [--test [--unpinned]])" >&2; exit 2 ;;
  esac
done
# The library itself (the main job) takes what the index serves within pyproject.toml's ranges.
((test)) || pins=()

apt_packages=(build-essential cmake ninja-build pkg-config python3 python3-venv python3-dev
  libeigen3-dev liborocos-kdl-dev liburdfdom-dev libyaml-cpp-dev libtinyxml-dev)
if ((test)); then
  # libx11-6, libsm6, libglib2.0-0: the shared libraries the drake wheel (a reference in the
  # tests) loads
  apt_packages+=(libgtest-dev libbenchmark-dev clang-format git valgrind libx11-6 libsm6
    libglib2.0-0)
fi

missing=()
for p in "${apt_packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})) || [[ ! -x .venv/bin/mindyn ]]; then
  echo "bootstrap: first run: installing what mindyn needs (Debian packages, .venv, the C++" \
    "build); this takes several minutes"
fi
if ((${#missing[@]})); then
  echo "bootstrap: installing Debian packages with apt-get: ${missing[*]}"
  sudo=""
  [[ $(id -u) -eq 0 ]] || sudo="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if [[ ! -x .venv/bin/python ]]; then
  echo "bootstrap: creating .venv"
  python3 -m venv .venv
fi
py=.venv/bin/python
# The installation is redone only when a source file, the requirements or the mode changed since
# the last one (the stamp holds the mode and is written after a successful installation; a test
# installation serves the main job too; --unpinned always asks the index again).
stamp=.venv/.mindyn-installed
mode="test=$test pins=${pins[*]:-none}"
installed="$(cat "$stamp" 2>/dev/null || true)"
sources=(cpp python cmake CMakeLists.txt pyproject.toml constraints.txt scripts/requirements.sh)
# shellcheck source=/dev/null
source scripts/requirements.sh
build="$(build_dir "$py")"
# A test installation also builds the C++ tests (in $build, for scripts/test): it is redone when
# they are missing there.
if [[ -x .venv/bin/mindyn && "${pins[0]:-}" != --upgrade ]] &&
  [[ "$installed" == "$mode" || ($test == 0 && "$installed" == test=1*) ]] &&
  [[ $test == 0 || -f "$build/cpp/tests/CTestTestfile.cmake" ]] &&
  [[ -z "$(find "${sources[@]}" -name __pycache__ -prune -o -newer "$stamp" -print -quit)" ]]; then
  exit 0
fi
rm -f "$stamp"
echo "bootstrap: updating pip and the build requirements in .venv"
$py -m pip install -q --upgrade pip "${pins[@]}"
# Build requirements first, so that the package builds without isolation and reuses $build.
$py -m pip install -q "${pins[@]}" "${build_requirements[@]}"
options=(--no-build-isolation "--config-settings=build-dir=$build")
extra=""
if ((test)); then
  extra="[test]"
  # The dependencies and the test toolchain before the package, so that its build can configure
  # the C++ tests too (they need example-robot-data's URDFs) and scripts/test reuses that build
  # instead of compiling the core a second time.
  echo "bootstrap: installing mindyn's dependencies and the test toolchain into .venv"
  deps="$($py -c 'import tomllib
with open("pyproject.toml", "rb") as f:
    p = tomllib.load(f)["project"]
print("\n".join(p["dependencies"] + p["optional-dependencies"]["test"]))')"
  mapfile -t deps <<<"$deps"
  $py -m pip install -q "${pins[@]}" "${deps[@]}"
  robots="$(robot_data_dir "$py")"
  options+=(--config-settings=cmake.define.MINDYN_BUILD_TESTS=ON
    "--config-settings=cmake.define.MINDYN_ROBOT_DATA_DIR=$robots")
fi
mkdir -p "$build"
log="$build/bootstrap.log"
echo "bootstrap: building and installing mindyn${extra} into .venv in $build (the C++ core is" \
  "compiled: minutes the first time, seconds later; the whole output goes to $log)"
# pip is verbose so that the build's output reaches the log; the console gets the build tool's
# progress lines ([k/N] with Ninja, [ p%] with Make) as they come (a shell loop: awk may wait for
# a full input buffer).
progress() {
  local line pattern='^[[:space:]]*(\[ *[0-9]+(/[0-9]+|%)\] .*)'
  while IFS= read -r line; do
    if [[ $line =~ $pattern ]]; then
      echo "bootstrap:   ${BASH_REMATCH[1]}"
    fi
  done
}
if ! PYTHONUNBUFFERED=1 $py -m pip install -v "${options[@]}" "${pins[@]}" ".${extra}" 2>&1 |
  tee "$log" | progress; then
  tail -n 30 "$log" >&2
  echo "bootstrap: building or installing mindyn failed; the whole output is in $log" >&2
  exit 1
fi
echo "$mode" >"$stamp"
echo "bootstrap: mindyn is installed: .venv/bin/mindyn"
