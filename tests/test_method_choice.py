"""Which base-parameter method runs when none is given: the projection method's limits (joints,
parameters, memory) are known in one place, the C++ core, and `mindyn base`, `mindyn codegen`
and `mindyn.base_parameters` choose from them and say why. Counts are checked against the
numerical method (sampled regressors, independent of both exact methods)."""

from __future__ import annotations

import re

import mindyn
import pytest
from conftest import ROBOTS_DIR
from mindyn import _core
from mindyn.cli import main
from random_tree import random_tree_urdf
from test_base_parameters import run_cli

TALOS = ROBOTS_DIR / "talos_data/robots/talos_reduced.urdf"


@pytest.fixture(scope="module")
def talos() -> mindyn.Robot:
    return mindyn.load(TALOS)


@pytest.fixture(scope="module")
def talos_numerical_count(talos) -> int:
    return mindyn.base_parameters(talos, method="numerical").n


def test_talos_is_a_fixed_base_tree_beyond_the_parameter_limit(talos):
    # the premise: within the joint limits of the projection method on a tree, beyond its
    # parameter limit (10 per joint)
    assert not talos.is_serial and 26 <= talos.n <= 44
    assert 10 * talos.n > 256


def test_base_parameters_chooses_the_recursive_method(talos, talos_numerical_count):
    bp = mindyn.base_parameters(talos)
    assert bp.method == "recursive"
    assert bp.method_reason.startswith(
        f"the projection method handles at most 256 parameters, the model has {10 * talos.n}"
    )
    assert "the recursive method is exact" in bp.method_reason
    assert bp.n == talos_numerical_count
    explicit = mindyn.base_parameters(talos, method="recursive")
    assert explicit.method_reason == "method='recursive'" and explicit.names == bp.names


def test_cli_base_chooses_the_recursive_method(talos_numerical_count):
    r = run_cli("base", TALOS)
    assert r.returncode == 0, r.stderr
    assert "base parameters by the recursive method" in r.stdout
    assert "method         recursive: the projection method handles at most 256 parameters" in (
        r.stdout
    )
    m = re.search(r"equations of motion (\d+)", r.stdout)
    assert m and int(m.group(1)) == talos_numerical_count


def test_cli_codegen_chooses_the_recursive_method(talos_numerical_count, tmp_path, capsys):
    out = str(tmp_path / "talos")
    assert main(["codegen", str(TALOS), "--lang", "c", "--what", "gravity", "-o", out]) == 0
    text = capsys.readouterr().out
    assert (
        "base parameters by the recursive method: the projection method handles at most 256 "
        "parameters" in text
    )
    assert f": {talos_numerical_count} base parameters;" in text


def test_refusal_names_each_limit(tmp_path):
    """Each limit of the projection method, on robots just inside and just outside it."""
    refusal = _core.projection_refusal
    chain18, chain19 = mindyn.load("planar18"), mindyn.load("planar19")
    assert "joints" not in (refusal(chain18._m) or "")  # (its memory estimate refuses it)
    assert refusal(mindyn.load("puma560")._m) is None
    assert refusal(chain19._m).startswith("the projection method handles at most 18 joints")
    # parameters: 25 joints of 10 parameters fit, 26 do not; with rotor inertia and friction (13
    # per joint), 19 do not
    t25 = mindyn.load(random_tree_urdf(tmp_path / "t25.urdf", n=25, seed=3))
    t26 = mindyn.load(random_tree_urdf(tmp_path / "t26.urdf", n=26, seed=3))
    t19 = mindyn.load(random_tree_urdf(tmp_path / "t19.urdf", n=19, seed=3))
    for t in (t25, t26, t19):  # within the tree's joint and path limits
        assert not t.is_serial and max(_depths(t.parents)) <= 16
    assert "parameters" not in (refusal(t25._m) or "")
    assert refusal(t26._m).startswith(
        "the projection method handles at most 256 parameters, the model has 260 (26 joints, 10 "
        "per joint)"
    )
    assert "parameters" not in (refusal(t19._m) or "")
    assert "parameters" not in (refusal(t19._m, rotor=True, friction=True) or "")  # 19 x 13 fit
    t20 = mindyn.load(random_tree_urdf(tmp_path / "t20.urdf", n=20, seed=3))
    assert refusal(t20._m, rotor=True, friction=True).startswith(
        "the projection method handles at most 256 parameters, the model has 260 (20 joints, 13 "
        "per joint)"
    )
    t45 = mindyn.load(random_tree_urdf(tmp_path / "t45.urdf", n=45, seed=3))
    assert refusal(t45._m).startswith("the projection method handles at most 44 joints on a tree")
    # the same reason through base_parameters: the refusal is what the choice reports
    assert mindyn.base_parameters(t26).method_reason.startswith(refusal(t26._m))
    with pytest.raises(mindyn.ModelError, match="at most 256 parameters.*method='recursive'"):
        mindyn.base_parameters(t26, method="projection")


def _depths(parents: list[int]) -> list[int]:
    depth: list[int] = []
    for p in parents:
        depth.append(1 if p < 0 else depth[p] + 1)
    return depth
