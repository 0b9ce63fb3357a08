"""``identify --report DIR``: the files it writes are named in its output and are outputs like
any other (another output naming one of them is refused before anything is written)."""

from __future__ import annotations

import json
import os

import pytest
from conftest import cli_run, one_line_error


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("report")
    out = []
    for seed in (0, 1):
        path = folder / f"log{seed}.csv"
        rc, _, err = cli_run(
            ["simulate", "planar2", "--mode", "inverse", "--torque-noise", "1%"]
            + ["--duration", "4", "--seed", seed, "-o", path]
        )
        assert rc == 0, err
        out.append(path)
    return out


def test_the_report_names_every_file_it_writes(logs, tmp_path):
    folder = tmp_path / "rep"
    rc, out, err = cli_run(
        ["identify", "planar2", logs[0], "--validate", logs[1], "--report", folder]
    )
    assert rc == 0, err
    line = next(x for x in out.splitlines() if x.startswith("wrote report to"))
    named = set(line.split(": ", 1)[1].split(", "))
    assert named == set(os.listdir(folder))
    assert {"identification.json", "table.txt", "torque_validation.png"} <= named
    assert json.loads((folder / "identification.json").read_text())["model"] == "dynamic"


@pytest.mark.parametrize("name", ["table.txt", "identification.json", "trajectory.png"])
def test_an_output_that_is_a_report_file_is_refused_before_writing(logs, tmp_path, name):
    folder = tmp_path / "rep"
    target = folder / name
    rc, _, err = cli_run(["identify", "planar2", logs[0], "--json", target, "--report", folder])
    one_line_error(rc, err, f"its report file '{target}' is also the file --json writes")
    assert not folder.exists() or not any(folder.iterdir())
