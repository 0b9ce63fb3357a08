"""The command line's one rule for the files it writes (mindyn.cli.outputs.output_path): a path
naming a folder (an existing one, or one ending in '/') means the command's default file name
inside it; no path (``codegen --plcopen`` alone) means the default path; any other path is the
file; the missing folders are created and the path written is stated."""

from __future__ import annotations

import json
from pathlib import Path

import mindyn
import numpy as np
import pytest
from mindyn.cli.outputs import output_file, output_path
from test_codegen_blocks import NS
from test_export import consistent_params, run


def test_output_path_rule(tmp_path, monkeypatch):
    # a file path: that file, its missing folders created
    deep = tmp_path / "a" / "b" / "x.json"
    assert output_path(output_file(str(deep)), "d.json") == deep
    assert deep.parent.is_dir() and not deep.exists()
    # an existing folder: the default name inside it
    assert output_path(output_file(str(tmp_path)), "sub/d.json") == tmp_path / "d.json"
    # a path ending in '/' is a folder, created
    new = str(tmp_path / "new") + "/"
    assert output_path(output_file(new), "d.json") == tmp_path / "new" / "d.json"
    assert (tmp_path / "new").is_dir()
    # no path: the default, relative to the current folder, its folder created
    monkeypatch.chdir(tmp_path)
    assert output_path(None, "defaults/d.json") == Path("defaults/d.json")
    assert (tmp_path / "defaults").is_dir()


def test_codegen_plcopen_alone_writes_the_default_path(tmp_path, monkeypatch):
    """--plcopen without a path and without -o: the project in mindyn-codegen/, created,
    stated (the schema check of such a project: test_codegen_blocks.py)."""
    monkeypatch.chdir(tmp_path)
    rc, out, err = run(["codegen", "planar2", "--plcopen"])
    assert rc == 0, err
    path = tmp_path / "mindyn-codegen" / "planar2.xml"
    assert "wrote mindyn-codegen/planar2.xml" in out
    assert _pous(path) == ["planar2_inverse_dynamics", "planar2_gravity", "planar2_regressor"]
    assert [p.name for p in tmp_path.rglob("*") if p.is_file()] == ["planar2.xml"]
    # a controller step: its own default name
    rc, out, err = run(["codegen", "planar2", "--what", "gravity-compensation", "--plcopen"])
    assert rc == 0, err
    assert "wrote mindyn-codegen/planar2_gravity_compensation.xml" in out
    path = tmp_path / "mindyn-codegen" / "planar2_gravity_compensation.xml"
    names = ["planar2_gravity_compensation", "planar2_inverse_dynamics", "planar2_gravity"]
    assert _pous(path) == names + ["planar2_regressor", "planar2_momentum_observer"]


@pytest.mark.parametrize(
    "given, written",
    [
        ("foo.bar", ("foo.bar.c", "foo.bar.h")),  # another suffix: kept in both names
        ("arm.v2.c", ("arm.v2.c", "arm.v2.h")),
        ("foo.c", ("foo.c", "foo.h")),
        ("foo.h", ("foo.c", "foo.h")),
        ("foo.st", ("foo.c", "foo.h")),
        ("foo", ("foo.c", "foo.h")),
    ],
)
@pytest.mark.parametrize("what", ["gravity", "momentum-observer"])
def test_codegen_c_names_both_files_by_one_rule(tmp_path, monkeypatch, given, written, what):
    """-o FILE with --lang c writes FILE.c and FILE.h, FILE the path without a .c, .h or .st
    suffix; the source includes the header by the name written (-o foo.bar wrote foo.bar.h
    and foo.c)."""
    monkeypatch.chdir(tmp_path)
    rc, out, err = run(["codegen", "planar2", "--what", what, "--lang", "c", "-o", given])
    assert rc == 0, err
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(written)
    assert f'#include "{written[1]}"' in (tmp_path / written[0]).read_text()
    assert f"wrote {written[1]}, {written[0]}" in out


def test_generated_code_write_adds_c_to_another_suffix(tmp_path):
    code = mindyn.codegen.generate("planar2", lang="c", what="gravity", header_name="g.v2.h")
    assert code.write(tmp_path / "g.v2") == [tmp_path / "g.v2.h", tmp_path / "g.v2.c"]
    assert code.write(tmp_path / "h.c")[1] == tmp_path / "h.c"


def _pous(path: Path) -> list[str]:
    import xml.etree.ElementTree as ET

    root = ET.parse(path).getroot()
    return [p.get("name") for p in root.findall("x:types/x:pous/x:pou", NS)]


def test_codegen_outputs_follow_the_rule(tmp_path):
    # -o a folder: NAME.st inside it; --plcopen a new folder ending in '/': created, NAME.xml
    folder = str(tmp_path / "plc") + "/"
    rc, out, err = run(["codegen", "planar2", "--lang", "st", "-o", tmp_path, "--plcopen", folder])
    assert rc == 0, err
    st, xml = tmp_path / "planar2.st", tmp_path / "plc" / "planar2.xml"
    assert f"wrote {st}, {xml}" in out
    assert st.read_text().count("FUNCTION_BLOCK planar2_") == 3
    # C into a folder: NAME_KIND.c and .h, the source including that header
    rc, out, err = run(
        ["codegen", "planar2", "--lang", "c", "--what", "adaptive-pd", "-o", tmp_path]
    )
    assert rc == 0, err
    src = tmp_path / "planar2_adaptive_pd.c"
    assert '#include "planar2_adaptive_pd.h"' in src.read_text()
    assert (tmp_path / "planar2_adaptive_pd.h").is_file() and str(src) in out
    # a file path in missing folders: created
    deep = tmp_path / "x" / "y" / "dyn.st"
    rc, out, err = run(["codegen", "planar2", "--lang", "st", "-o", deep])
    assert rc == 0 and deep.is_file() and f"wrote {deep}" in out


@pytest.mark.parametrize(
    "argv, message",
    [
        (["codegen", "planar2"], "nothing to write"),
        (["codegen", "planar2", "-o", "x.txt"], "--lang is required with -o"),
    ],
)
def test_codegen_needs_an_output(tmp_path, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    rc, out, err = run(argv)
    assert rc == 2 and len(err.splitlines()) == 1 and message in err, err
    assert not any(tmp_path.iterdir())


def test_codegen_takes_the_language_a_file_name_says(tmp_path):
    """-o FILE.c (or .h) without --lang writes C (FILE.c and FILE.h), -o FILE.st Structured
    Text: the same files as with --lang."""
    for lang, name, made in (("c", "dyn.c", ("dyn.c", "dyn.h")), ("st", "dyn.st", ("dyn.st",))):
        given, implied = tmp_path / f"given_{lang}", tmp_path / f"implied_{lang}"
        rc, _, err = run(["codegen", "planar2", "--lang", lang, "-o", given / name])
        assert rc == 0, err
        rc, _, err = run(["codegen", "planar2", "-o", implied / name])
        assert rc == 0, err
        assert sorted(p.name for p in implied.iterdir()) == sorted(made)
        for f in made:
            assert (implied / f).read_text() == (given / f).read_text()


def test_export_into_a_folder(tmp_path):
    robot = mindyn.load("puma560")
    rng = np.random.default_rng(1)
    ident = tmp_path / "id.json"
    ident.write_text(json.dumps({"classical": consistent_params(robot, rng)}))
    out = tmp_path / "desc"
    out.mkdir()
    rc, stdout, err = run(["export", "puma560", ident, "--yaml", out])
    assert rc == 0, err
    assert f"wrote {out / 'puma560_export.yaml'}" in stdout
    assert mindyn.load(out / "puma560_export.yaml").n == 6


def test_identify_json_and_simulate_into_folders(tmp_path):
    """identify --json and simulate -o given folders (one existing, one new ending in '/'):
    ROBOT_COMMAND.json / .csv inside them, stated; the JSON is the identification's."""
    from mindyn.control.simulation import simulate_inverse
    from mindyn.identification.excitation import random_trajectory

    robot = mindyn.load("planar2")
    lim = {"lower": -np.ones(2), "upper": np.ones(2)}
    traj = random_trajectory(robot, seed=1, limits=lim)
    (tmp_path / "traj.json").write_text(json.dumps(traj.to_dict()))
    log = simulate_inverse(robot, traj, seed=3)
    log.save(tmp_path / "log.csv", robot_name="planar2")
    rc, out, err = run(["identify", "planar2", tmp_path / "log.csv", "--json", tmp_path])
    assert rc == 0, err
    path = tmp_path / "planar2_identify.json"
    assert f"wrote {path}" in out
    doc = json.loads(path.read_text())
    assert doc["base_names"] == mindyn.base_parameters(robot).names
    assert set(doc["names"]) <= set(doc["base_names"]) and len(doc["values"]) == len(doc["names"])
    new = str(tmp_path / "sim") + "/"
    argv = ["simulate", "planar2", "--trajectory", tmp_path / "traj.json", "-o", new]
    rc, out, err = run(argv)
    assert rc == 0, err
    assert (tmp_path / "sim" / "planar2_simulate.csv").is_file()
    assert str(tmp_path / "sim" / "planar2_simulate.csv") in out


def test_an_output_that_is_an_input_is_refused_and_the_input_kept(tmp_path):
    """identify --json LOG wrote the JSON over the log, simulate -o over its --trajectory,
    export --urdf over the robot's own URDF: each input was lost without a word. Each is
    refused in one line naming the input, and the file is unchanged byte for byte."""
    from mindyn.control.simulation import simulate_inverse
    from mindyn.identification.excitation import random_trajectory

    robot = mindyn.load("planar2")
    lim = {"lower": -np.ones(2), "upper": np.ones(2)}
    traj = random_trajectory(robot, seed=1, limits=lim)
    (tmp_path / "traj.json").write_text(json.dumps(traj.to_dict()))
    simulate_inverse(robot, traj, seed=3).save(tmp_path / "log.csv", robot_name="planar2")
    urdf = tmp_path / "ur5.urdf"
    urdf.write_text((Path(__file__).resolve().parents[1] / "examples/urdf/ur5.urdf").read_text())
    ident = tmp_path / "id.json"
    ur5 = mindyn.load(urdf)
    ident.write_text(json.dumps({"classical": consistent_params(ur5, np.random.default_rng(1))}))
    (tmp_path / "x.joints.yaml").write_text("robot: ur5_example\n")
    export = ["export", "ur5.urdf", "id.json", "--urdf"]
    cases = [
        (["identify", "planar2", "log.csv", "--json", "log.csv"], "--json", "LOG"),
        (
            ["simulate", "planar2", "--trajectory", "traj.json", "-o", "traj.json"],
            "--output",
            "--trajectory",
        ),
        ([*export, "ur5.urdf"], "--urdf", "ROBOT"),
        ([*export, "x.urdf", "--sidecar", "id.json"], "--sidecar", "the identification JSON"),
        # the joint-terms file that --urdf writes beside it by default
        ([*export, "x.urdf", "--joint-terms", "x.joints.yaml"], "--urdf", "--joint-terms"),
    ]
    for argv, option, name in cases:
        files = {p: p.read_bytes() for p in tmp_path.iterdir() if p.is_file()}
        paths = (".csv", ".json", ".urdf", ".yaml")
        rc, _, err = run([tmp_path / a if a.endswith(paths) else a for a in argv])
        assert rc == 2 and err.count("\n") == 1, err
        assert f"mindyn: error: {option} '" in err and f"reads as {name} (" in err, err
        assert {p: p.read_bytes() for p in tmp_path.iterdir() if p.is_file()} == files
    # another file beside them is written as before
    rc, _, err = run(["identify", "planar2", tmp_path / "log.csv", "--json", tmp_path / "o.json"])
    assert rc == 0 and (tmp_path / "o.json").is_file(), err


def test_a_file_written_beside_an_output_that_is_an_input_is_refused(tmp_path):
    """excite -o X.csv writes X.json and X.png beside it, simulate -o X.csv X.truth.json, and
    track and simulate --report DIR the report's files into DIR: one of them that is a file
    the command reads was overwritten without a word. Each is refused in one line naming the
    option, the file written beside it and the input, and every file is unchanged byte for
    byte."""
    from mindyn.control.simulation import simulate_inverse
    from mindyn.identification.excitation import random_trajectory

    robot = mindyn.load("planar2")
    lim = {"lower": -np.ones(2), "upper": np.ones(2)}
    traj = random_trajectory(robot, seed=1, limits=lim)
    doc = json.dumps(traj.to_dict())
    (tmp_path / "traj.truth.json").write_text(doc)
    (tmp_path / "rep").mkdir()
    simulate_inverse(robot, traj, seed=3).save(tmp_path / "rep" / "log.csv", robot_name="planar2")
    # joint terms are YAML, of which JSON is a part
    (tmp_path / "terms.json").write_text('{"robot": "planar2"}\n')
    (tmp_path / "terms.png").write_text('{"robot": "planar2"}\n')
    excite = ["excite", "planar2", "--quiet", "--starts", "1", "--maxiter", "1"]
    rep_log = ["--trajectory", tmp_path / "rep" / "log.csv", "--report", tmp_path / "rep"]
    cases = [
        (
            [*excite, "--joint-terms", tmp_path / "terms.json", "-o", tmp_path / "terms.csv"],
            f"--output '{tmp_path / 'terms.csv'}': its coefficients file "
            f"'{tmp_path / 'terms.json'}' is also the file the command reads as --joint-terms",
        ),
        (
            [*excite, "--joint-terms", tmp_path / "terms.png", "-o", tmp_path / "terms.csv"],
            f"its plot '{tmp_path / 'terms.png'}' is also the file the command reads as "
            "--joint-terms",
        ),
        (
            ["simulate", "planar2", "--trajectory", tmp_path / "traj.truth.json"]
            + ["-o", tmp_path / "traj.csv"],
            f"its truth file '{tmp_path / 'traj.truth.json'}' is also the file the command "
            "reads as --trajectory",
        ),
        (
            ["simulate", "planar2", *rep_log, "-o", tmp_path / "s.csv"],
            f"--report '{tmp_path / 'rep'}': its report file '{tmp_path / 'rep' / 'log.csv'}' "
            "is also the file the command reads as --trajectory",
        ),
        (
            ["track", "planar2", *rep_log],
            f"its report file '{tmp_path / 'rep' / 'log.csv'}' is also the file the command "
            "reads as --trajectory",
        ),
    ]

    def files():
        return {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}

    before = files()
    for argv, said in cases:
        rc, _, err = run(argv)
        assert rc == 2 and err.count("\n") == 1, err
        assert err.startswith("mindyn: error: ") and said in err, (said, err)
        assert "writing it would overwrite that input" in err, err
        assert files() == before
    # with their own names the files beside the outputs are written, as the rule lists them
    from mindyn.cli.closed_loop import REPORT_FILES

    out = tmp_path / "out"
    rc, _, err = run([*excite, "-o", out / "e.csv"])
    assert rc == 0, err
    assert {p.name for p in out.iterdir()} == {"e.csv", "e.json", "e.png"}
    rc, _, err = run(
        ["simulate", "planar2", "--controller", "adaptive-pd", "--duration", "0.2"]
        + ["--report", out / "r", "-o", out / "s.csv"]
    )
    assert rc == 0, err
    assert (out / "s.truth.json").is_file()
    assert {p.name for p in (out / "r").iterdir()} == set(REPORT_FILES)
