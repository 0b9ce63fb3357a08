"""The length a too-short log is told to have is a length of the log as written.

The data path drops the filter edges of each log and decimates the dynamic model's samples,
so the samples an identification counts are fewer than the log's rows. A refusal for too few
equations states the rows the log needs: a log of that many rows (same rate, same cut-off) is
accepted and one row fewer is refused again, so the count is the data path's own."""

from __future__ import annotations

import re

import pytest
from conftest import cli_run, one_line_error

RATE = 250.0


def _log(tmp_path, rows: int):
    path = tmp_path / f"log{rows}.csv"
    rc, _, err = cli_run(
        ["simulate", "planar3", "--mode", "inverse", "--torque-noise", "1%"]
        + ["--duration", repr((rows - 1) / RATE), "--rate", repr(RATE), "-o", path]
    )
    assert rc == 0, err
    assert sum(1 for _ in open(path)) == rows + 1  # the header and the rows asked for
    return path


@pytest.mark.parametrize(
    "options",
    [
        ["--model", "energy", "--rotor", "--friction"],  # windows of every sample
        ["--model", "integral"],
        ["--model", "dynamic"],  # decimated to 10 x the cut-off
    ],
)
def test_the_rows_a_refused_log_is_told_to_have_suffice(tmp_path, options):
    identify = ["identify", "planar3", "--cutoff", "5", *options]
    rc, _, err = cli_run([*identify, _log(tmp_path, 300)])
    line = one_line_error(rc, err, "Use a longer log (at least ", "samples as logged")
    rows = int(re.search(r"at least (\d+) samples as logged", line).group(1))
    assert rows > 300
    rc, out, err = cli_run([*identify, _log(tmp_path, rows)])
    assert rc == 0, err
    rc, _, err = cli_run([*identify, _log(tmp_path, rows - 1)])
    one_line_error(rc, err, f"at least {rows} samples as logged")
