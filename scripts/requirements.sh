# Sourced by bootstrap.sh and lock: what mindyn is built with (installed before the package, so
# that it builds without isolation and reuses build/). setuptools and wheel: dependencies
# published only as source (a tree-sitter grammar among the test extras) are built here too.
build_requirements=("scikit-build-core>=0.10" "pybind11>=2.12" "numpy>=1.23" setuptools wheel)
