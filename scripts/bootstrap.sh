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
  libeigen3-dev liborocos-kdl-dev liburdfdom-dev libyaml-cpp-dev)
if ((test)); then
  apt_packages+=(libgtest-dev libbenchmark-dev clang-format git valgrind)
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
if [[ -x .venv/bin/mindyn && "${pins[0]:-}" != --upgrade ]] &&
  [[ "$installed" == "$mode" || ($test == 0 && "$installed" == test=1*) ]] &&
  [[ -z "$(find "${sources[@]}" -name __pycache__ -prune -o -newer "$stamp" -print -quit)" ]]; then
  exit 0
fi
rm -f "$stamp"
# shellcheck source=/dev/null
source scripts/requirements.sh
echo "bootstrap: updating pip and the build requirements in .venv"
$py -m pip install -q --upgrade pip "${pins[@]}"
# Build requirements first, so that the package builds without isolation and reuses build/.
$py -m pip install -q "${pins[@]}" "${build_requirements[@]}"
extra=""
((test)) && extra="[test]"
echo "bootstrap: building and installing mindyn${extra} into .venv (the C++ core is compiled;" \
  "minutes the first time, seconds later)"
$py -m pip install -q --no-build-isolation "${pins[@]}" ".${extra}"
echo "$mode" >"$stamp"
echo "bootstrap: mindyn is installed: .venv/bin/mindyn"
