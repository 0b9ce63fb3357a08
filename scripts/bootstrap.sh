#!/usr/bin/env bash
# Installs what mindyn needs on Debian 12 (apt packages, a virtual environment in .venv, the
# package itself) and does nothing that is already done. Usage: bootstrap.sh [--test]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"

apt_packages=(build-essential cmake ninja-build pkg-config python3 python3-venv python3-dev
  libeigen3-dev liborocos-kdl-dev liburdfdom-dev libyaml-cpp-dev)
if [[ "${1:-}" == "--test" ]]; then
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
echo "bootstrap: updating pip and the build requirements in .venv"
$py -m pip install -q --upgrade pip
# Build requirements first, so that the package builds without isolation and reuses build/.
# setuptools and wheel: dependencies published only as source (a tree-sitter grammar among the
# test extras) are built in this environment too.
$py -m pip install -q "scikit-build-core>=0.10" "pybind11>=2.12" "numpy>=1.23" setuptools wheel
extra=""
[[ "${1:-}" == "--test" ]] && extra="[test]"
echo "bootstrap: building and installing mindyn${extra} into .venv (the C++ core is compiled;" \
  "minutes the first time, seconds later)"
$py -m pip install -q --no-build-isolation ".${extra}"
echo "bootstrap: mindyn is installed: .venv/bin/mindyn"
