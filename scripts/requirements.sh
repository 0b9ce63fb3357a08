# Sourced by bootstrap.sh, test and lock: what mindyn is built with (installed before the package,
# so that it builds without isolation and reuses build/). setuptools and wheel: dependencies
# published only as source (a tree-sitter grammar among the test extras) are built here too.
build_requirements=("scikit-build-core>=0.10" "pybind11>=2.12" "numpy>=1.23" setuptools wheel)

# build_dir PYTHON: the folder where pip's build of the package configures and compiles (passed
# to scikit-build-core as its build-dir by bootstrap.sh, one per interpreter). With --test it also
# holds the C++ tests, which scripts/test runs there: the core is compiled once.
build_dir() { echo "build/python-$("$1" -c 'import sys; print(sys.implementation.cache_tag)')"; }

# robot_data_dir PYTHON: example-robot-data's 'robots' folder (a test extra), for the C++ tests.
robot_data_dir() {
  "$1" -c 'import pathlib, sys
found = sorted(pathlib.Path(sys.prefix).glob(
    "lib/python*/site-packages/cmeel.prefix/share/example-robot-data/robots"))
if not found:
    sys.exit("example-robot-data (a test extra) is not installed in " + sys.prefix)
print(found[0])'
}
