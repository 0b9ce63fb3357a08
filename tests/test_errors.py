"""One base class, mindyn.Error, for every error mindyn raises for its input, each error keeping
the standard base it had (ValueError, FileNotFoundError), so that both kinds of handler work."""

from __future__ import annotations

import ast
import builtins
import importlib
from pathlib import Path

import mindyn
import numpy as np
import pytest
from mindyn.identification.data import DataError, DataFileNotFoundError, read_csv
from mindyn.identification.errors import IdentificationError, RankDeficientError

PACKAGE = Path(mindyn.__file__).parent


def error_classes():
    """(module, class name) of every exception class defined in the package's sources: a
    class whose bases name an ...Error or Exception."""
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        module = ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        module = module.removesuffix(".__init__")
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ClassDef):
                names = [ast.unparse(b) for b in node.bases]
                if any(n.endswith(("Error", "Exception")) for n in names):
                    found.append((module, node.name))
    return found


def test_the_source_scan_finds_the_known_classes():
    found = {name for _, name in error_classes()}
    assert {"IdentificationError", "DataError", "UsageError", "RankDeficientError"} <= found


@pytest.mark.parametrize(("module", "name"), error_classes())
def test_every_error_class_of_the_package_derives_from_mindyn_error(module, name):
    cls = getattr(importlib.import_module(module), name)
    assert issubclass(cls, mindyn.Error), f"{module}.{name}: {cls.__mro__}"


@pytest.mark.parametrize(
    ("cls", "standard"),
    [
        (mindyn.ModelError, ValueError),
        (mindyn.ArgumentError, ValueError),
        (mindyn.ArgumentError, TypeError),
        (mindyn.RobotFileNotFoundError, FileNotFoundError),
        (IdentificationError, ValueError),
        (RankDeficientError, ValueError),
        (DataError, ValueError),
        (DataFileNotFoundError, FileNotFoundError),
    ],
)
def test_errors_keep_their_standard_base(cls, standard):
    assert issubclass(cls, mindyn.Error)
    assert issubclass(cls, standard)


def test_mindyn_error_is_not_a_builtin_exception_class():
    assert issubclass(mindyn.Error, Exception)
    assert not issubclass(mindyn.Error, ValueError)
    assert mindyn.Error not in vars(builtins).values()


def raises_both(standard, call):
    """The call raises an error that both an `except mindyn.Error` and an `except standard`
    handler catch."""
    with pytest.raises(mindyn.Error) as info:
        call()
    assert isinstance(info.value, standard), type(info.value).__mro__
    return info.value


def test_raised_errors_are_caught_by_either_handler(tmp_path):
    robot = mindyn.load("puma560")
    e = raises_both(FileNotFoundError, lambda: mindyn.load(str(tmp_path / "missing.urdf")))
    assert isinstance(e, mindyn.RobotFileNotFoundError)
    e = raises_both(ValueError, lambda: mindyn.load("no_such_robot"))
    assert isinstance(e, mindyn.ModelError)
    # raised by the C++ binding's argument checks
    e = raises_both(
        ValueError, lambda: robot._m.inverse_dynamics(np.zeros(5), np.zeros(6), np.zeros(6), None)
    )
    assert isinstance(e, mindyn.ArgumentError) and "q has shape (5,)" in str(e)
    e = raises_both(FileNotFoundError, lambda: read_csv(tmp_path / "missing.csv"))
    assert isinstance(e, DataFileNotFoundError)
    bad = tmp_path / "bad.csv"
    bad.write_text("t,q1\n0,notanumber\n", encoding="utf-8")
    e = raises_both(ValueError, lambda: read_csv(bad))
    assert isinstance(e, DataError)


@pytest.mark.parametrize(
    "text, needle",
    [
        ("joints:\n  - {Ia: 2001-13-45}\n", "month must be in 1..12"),  # a date YAML cannot build
        (f"joints:\n  - {{Ia: {'9' * 400}}}\n", "'Ia' is an integer beyond 1e16"),
        ("joints:\n  - {Fv: .inf}\n", "'Fv' is inf"),
        ("joints:\n  - {Fc: .nan}\n", "'Fc' is nan"),
    ],
)
def test_a_joint_terms_file_yaml_cannot_build_names_the_file(tmp_path, text, needle):
    """Values PyYAML refuses with a bare ValueError, or that are not finite numbers, are the
    file's error (a ModelError naming it), never a bare ValueError or OverflowError."""
    from mindyn.export import read_joint_terms

    path = tmp_path / "terms.yaml"
    path.write_text(text)
    with pytest.raises(mindyn.ModelError) as e:
        read_joint_terms(path)
    assert str(path) in str(e.value) and needle in str(e.value), e.value
    assert "\n" not in str(e.value)


@pytest.mark.parametrize(
    "text, needle",
    [
        ("kd: 2001-13-45\n", "month must be in 1..12"),
        (f"kd: {'9' * 5000}\n", "digits"),  # past Python's integer-string limit
        ("? [kd]\n: 1\n", ":1:3: not valid YAML: while constructing a mapping: found unhashable"),
        ("kd: [1,\n  2\n", "not valid YAML"),
    ],
)
def test_a_gains_file_yaml_cannot_build_names_the_file(tmp_path, text, needle):
    from mindyn.control import ControllerSettingError, load_gains

    path = tmp_path / "gains.yaml"
    path.write_text(text)
    with pytest.raises(ControllerSettingError) as e:
        load_gains(path, mindyn.load("planar2"))
    assert str(e.value).startswith(str(path)) and needle in str(e.value), e.value
    assert "\n" not in str(e.value)


# values PyYAML's safe loader cannot build, with a word of the reason each message gives
UNBUILDABLE = [
    ("!!python/object:os.system x", "could not determine a constructor"),
    ("!!python/name:os.system ''", "could not determine a constructor"),
    ("!!binary 'abc'", "failed to decode base64 data"),
    ("!!int abc", "cannot build 'abc' as !!int"),
    ("!!float abc", "cannot build 'abc' as !!float"),
    ("!!bool maybe", "cannot build 'maybe' as !!bool"),  # was a bare KeyError
    ("!!timestamp 2001-13-45", "month must be in 1..12"),
    ("!!timestamp abc", "cannot build 'abc' as !!timestamp"),  # was a bare AttributeError
    ("2001-02-30", "day is out of range for month"),  # a date by YAML 1.1's implicit rule
    ("!!str [1]", "expected a scalar node, but found sequence"),
    (f"{'9' * 5000}", "(5000 characters) as !!int"),
]


def _yaml_readers(tmp_path):
    """(name, text before the value on its line, lines before that line, reader of a path) of
    each PyYAML reader of the package: joint terms, gains and the table export rewrites."""
    from mindyn.control import load_gains
    from mindyn.export import read_joint_terms, write_yaml

    robot = mindyn.load("puma560")
    out = tmp_path / "out.yaml"
    return [
        ("terms.yaml", "  - Fv: ", "joints:\n  - {Ia: 1}\n", read_joint_terms),
        ("gains.yaml", "lambda: ", "kd: 1\ngamma: 1\n", lambda p: load_gains(p, robot)),
        (
            "table.yaml",
            "  - a: ",
            "name: x\njoints:\n",
            lambda p: write_yaml(robot, robot.params, out, source=p),
        ),
    ]


@pytest.mark.parametrize("value, needle", UNBUILDABLE)
def test_a_yaml_value_the_loader_cannot_build_is_named_by_file_line_and_column(
    tmp_path, value, needle
):
    """A value PyYAML's safe loader refuses (an unsafe or unknown tag, a tagged value its
    constructor cannot build, a date out of range) in any YAML file the package reads with
    PyYAML is a mindyn.Error of one line naming the file, the value's line and column."""
    for name, before, lines, read in _yaml_readers(tmp_path):
        path = tmp_path / name
        path.write_text(f"{lines}{before}{value}\n")
        line, column = lines.count("\n") + 1, len(before) + 1  # where the value starts
        with pytest.raises(mindyn.Error) as e:
            read(path)
        said = str(e.value)
        assert said.startswith(f"{path}:{line}:{column}: not valid YAML: "), said
        assert needle in said and "\n" not in said and len(said) < 400, said


def test_a_gains_file_the_loader_cannot_build_exits_2_naming_the_place(tmp_path, capsys):
    """``!!bool maybe`` in a gains file was a bare KeyError (exit 70, "a defect in mindyn")."""
    gains = tmp_path / "g.yaml"
    gains.write_text("kd: 10\nlambda: !!bool maybe\n")
    argv = ["codegen", "planar2", "--what", "adaptive-pd", "--gains", str(gains)]
    assert mindyn.cli.main([*argv, "--lang", "c", "-o", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"mindyn: error: {gains}:2:9: not valid YAML: cannot build 'maybe' as !!bool"]


@pytest.mark.parametrize(
    "change, needle",
    [
        ({"names": [["a"]], "values": [1.0]}, "'names' must list parameter names"),
        ({"friction_model": {"kind": "coulomb", "velocity": 3}}, "velocity must be a list"),
    ],
)
def test_an_identification_json_with_odd_types_names_the_file(tmp_path, change, needle):
    """A JSON whose names are not strings (unhashable in a set) or whose friction velocities
    are not a list is refused naming the file, not with a bare TypeError, and as the data error
    it is (as every reader of a file says it), not as a ModelError of the robot."""
    import json

    from mindyn.codegen.parameters import read_identified_parameters

    robot = mindyn.load("planar2")
    names = mindyn.base_parameters(robot).names
    doc = {"robot": "planar2", "names": list(names), "values": [1.0] * len(names), "removed": []}
    doc.update(change)
    if "friction_model" in change:
        doc["friction"] = True
    path = tmp_path / "ident.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(DataError) as e:
        read_identified_parameters(path, names, robot=robot, friction="friction_model" in change)
    assert str(e.value).startswith(str(path)) and needle in str(e.value), e.value


@pytest.mark.parametrize("consistent", [False, True])
def test_codegen_params_not_json_names_the_line_and_column(tmp_path, capsys, consistent):
    """``codegen --params`` with a file that is not JSON: the reader's error (file, line,
    column), also with --consistent, which said the file was not the JSON of identify."""
    from mindyn.codegen.parameters import read_identified_parameters

    path = tmp_path / "id.json"
    path.write_text('{"names": ["ZZR1"],\n "values": }')  # line 2, column 12: no value
    names = mindyn.base_parameters(mindyn.load("planar2")).names
    with pytest.raises(DataError, match=r":2:12: not valid JSON: Expecting value$"):
        read_identified_parameters(path, names, robot=mindyn.load("planar2"))
    argv = ["codegen", "planar2", "--lang", "c", "--params", str(path), "-o", str(tmp_path / "x")]
    assert mindyn.cli.main(argv + ["--consistent"] * consistent) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"mindyn: error: {path}:2:12: not valid JSON: Expecting value"], err


def test_codegen_params_of_the_wrong_shape_is_a_data_error(tmp_path, capsys):
    """An identification JSON whose 'removed' is not a list of names: a DataError naming the
    file and the field (it was a ModelError, the class of a robot that cannot be built)."""
    import json

    from mindyn.codegen.parameters import read_identified_parameters

    robot = mindyn.load("planar2")
    names = mindyn.base_parameters(robot).names
    path = tmp_path / "id.json"
    path.write_text(json.dumps({"names": names, "values": [1.0] * len(names), "removed": [3]}))
    with pytest.raises(DataError) as e:
        read_identified_parameters(path, names, robot=robot)
    assert not isinstance(e.value, mindyn.ModelError)
    assert str(e.value) == f"{path}: unknown parameter(s) 3; expected {', '.join(names)}"
    path.write_text(json.dumps({"names": names, "values": [1.0] * len(names), "removed": 3}))
    with pytest.raises(DataError, match="'removed' must list the pruned parameters by name"):
        read_identified_parameters(path, names, robot=robot)


@pytest.mark.parametrize(
    "data, needle",
    [
        (b"[" * 5000 + b"]" * 5000, "nested deeper than the JSON reader follows"),
        (b'{"ZZR1": 1,\n "MXR1": \xff}', "line 2: not UTF-8 text (byte 0xff"),
        (b'{"names": 3, "values": [1]}', "'names' and 'values' must be lists"),
        (b'{"names": [[1]], "values": [1]}', "'names' must list parameter names"),
        (b'{"ZZR1": 1,\n "MXR1" 2}', ":2:"),  # the line of a syntax error
    ],
)
def test_a_parameter_file_that_cannot_be_read_names_the_file(tmp_path, data, needle):
    """Files nested too deep, not UTF-8 or with names of the wrong type escaped as bare
    RecursionError, UnicodeDecodeError or TypeError."""
    from mindyn.codegen.parameters import read_parameter_file

    path = tmp_path / "params.json"
    path.write_bytes(data)
    with pytest.raises(DataError) as e:
        read_parameter_file(path, mindyn.base_parameters(mindyn.load("planar2")).names)
    assert str(e.value).startswith(str(path)) and needle in str(e.value), e.value


def test_a_csv_field_past_the_csv_modules_limit_names_the_file_and_line(tmp_path):
    """csv.Error (not a ValueError) escaped from the trajectory and floating-base log readers
    for a field longer than the csv module takes."""
    from mindyn.control.simulation import CsvTrajectory
    from mindyn.identification.floating import read_floating_csv

    path = tmp_path / "big.csv"
    path.write_text("t,q1,q2\n0,0,0\n0.1," + "1" * 200_000 + ",0\n")
    with pytest.raises(DataError) as e:
        CsvTrajectory(path, 2)
    assert str(e.value).startswith(f"{path}, line 3: not readable as CSV"), e.value
    ur5 = Path(__file__).resolve().parents[1] / "examples" / "urdf" / "ur5.urdf"
    robot = mindyn.load(str(ur5), root_joint="floating")
    with pytest.raises(DataError) as e:
        read_floating_csv(path, robot)
    assert str(e.value).startswith(f"{path}, line 3: not readable as CSV"), e.value
