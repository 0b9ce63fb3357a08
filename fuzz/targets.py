"""Fuzz targets for the robot-description loaders and the CSV log reader (atheris).

Each target writes the fuzzer's bytes to a file and loads it the way users do. An outcome is
acceptable when the load succeeds or raises one of the documented error types with a one-line
message that names the file; any other exception, a multi-line message or a crash is a finding.

Run one target:  python fuzz/targets.py urdf|yaml|csv [libFuzzer options] [corpus dirs]
"""

from __future__ import annotations

import os
import sys
import tempfile

import atheris
import numpy as np

with atheris.instrument_imports(include=["mindyn"]):
    import mindyn
    from mindyn.identification.data import DataError, read_csv

_DIR = tempfile.mkdtemp(prefix="mindyn-fuzz-")
_ALLOWED = (mindyn.ModelError, mindyn.RobotFileNotFoundError, DataError)


# The native parsers are not instrumented, so the fuzzer sees no coverage inside them. To give it
# feedback all the same, every kind of outcome gets a branch of its own here: an input that
# reaches a new error message (or loads a robot of a new size) counts as new coverage.
_PHRASES = [
    "not valid", "not UTF-8", "must be a mapping", "unknown key", "must be a number",
    "must be text", "must be true", "appears twice", "exceeds the bound", "is not finite",
    "joint type", "convention", "angle_unit", "non-empty list", "list of 3", "mass is negative",
    "lower limit", "tag", "key must", "second YAML document", "expands", "nested",
    "loop", "child of", "both its parent", "not connected", "branches", "tip link", "no moving",
    "not supported", "mimics", "axis", "origin", "inertia", "rigid", "deeper", "joints; at most",
    "Failed to build tree", "root link", "Error reading", "limit", "columns", "line",
    "is not a number", "NaN", "infinite", "too large", "not increasing", "data row", "overflow",
    "samples", "header", "implies", "empty", "twice",
]  # fmt: skip
_namespace: dict = {}
exec(  # noqa: S102 - builds one branch per phrase
    "def _feedback(msg, n):\n"
    + "".join(f"    if {p!r} in msg:\n        pass\n" for p in _PHRASES)
    + "".join(f"    if n == {k}:\n        pass\n" for k in range(1, 8)),
    _namespace,
)
_feedback = atheris.instrument_func(_namespace["_feedback"])


def _check(path: str, load) -> None:
    try:
        result = load(path)
    except _ALLOWED as e:
        msg = str(e)
        if os.path.basename(path) not in msg or "\n" in msg:
            raise AssertionError(f"error does not name the file in one line: {msg!r}") from e
        _feedback(msg, 0)
        return
    _feedback("", getattr(result, "n", 0))
    if isinstance(result, mindyn.Robot):
        # a loaded model must give finite dynamics at a moderate state
        q = np.full(result.n, 0.3)
        tau = result.inverse_dynamics(q, q, q)
        if not np.isfinite(tau).all():
            raise AssertionError(f"non-finite torques {tau} from an accepted description")
    elif not all(np.isfinite(a).all() for a in (result.t, result.q, result.dq, result.ddq)):
        raise AssertionError("non-finite values from an accepted log")


def _target(suffix: str, load):
    path = os.path.join(_DIR, "input" + suffix)

    def run(data: bytes) -> None:
        with open(path, "wb") as f:
            f.write(data)
        _check(path, load)

    return run


TARGETS = {
    "urdf": _target(".urdf", mindyn.load),
    "yaml": _target(".yaml", mindyn.load),
    "csv": _target(".csv", lambda p: read_csv(p, require_torque=False, filter="none")),
}


def main() -> None:
    if len(sys.argv) < 2 or sys.argv[1] not in TARGETS:
        sys.exit(f"usage: {sys.argv[0]} {{{'|'.join(TARGETS)}}} [libFuzzer options] [corpus]")
    target = TARGETS[sys.argv.pop(1)]
    atheris.Setup(sys.argv, target)
    atheris.Fuzz()


if __name__ == "__main__":
    main()
