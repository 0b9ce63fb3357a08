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
# A chain of more joints than the projection method's basis index holds (18 on a chain).
LONG = "planar19"


@pytest.fixture(scope="module")
def talos() -> mindyn.Robot:
    return mindyn.load(TALOS)


@pytest.fixture(scope="module")
def long_numerical_count() -> int:
    return mindyn.base_parameters(LONG, method="numerical").n


def test_talos_is_within_the_projection_methods_limits(talos):
    """TALOS (a fixed-base tree of 32 joints, 320 parameters): no limit of the projection method
    refuses it (the parameters its row reduction takes exceed what a tree within the joint
    limits can have), and the method it runs by default, the projection method, gives the
    numerical method's count."""
    lim = _core.projection_limits()
    assert not talos.is_serial and 26 <= talos.n <= lim["tree_joints"]
    assert 10 * talos.n > 256 and lim["parameters"] >= 15 * lim["tree_joints"]
    assert _core.projection_refusal(talos._m) is None
    bp = mindyn.base_parameters(talos)
    assert bp.method == "projection"
    assert bp.n == mindyn.base_parameters(talos, method="numerical").n
    assert bp.names == mindyn.base_parameters(talos, method="recursive").names


def test_base_parameters_chooses_the_recursive_method(long_numerical_count):
    bp = mindyn.base_parameters(LONG)
    assert bp.method == "recursive"
    assert bp.method_reason.startswith(
        "the projection method handles at most 18 joints, the model has 19"
    )
    assert "the recursive method is exact" in bp.method_reason
    assert bp.n == long_numerical_count
    explicit = mindyn.base_parameters(LONG, method="recursive")
    assert explicit.method_reason == "method='recursive'" and explicit.names == bp.names


def test_cli_base_chooses_the_recursive_method(long_numerical_count):
    r = run_cli("base", LONG)
    assert r.returncode == 0, r.stderr
    assert "base parameters by the recursive method" in r.stdout
    assert "method         recursive: the projection method handles at most 18 joints" in (r.stdout)
    m = re.search(r"equations of motion (\d+)", r.stdout)
    assert m and int(m.group(1)) == long_numerical_count


def test_cli_codegen_chooses_the_recursive_method(long_numerical_count, tmp_path, capsys):
    out = str(tmp_path / "long")
    assert main(["codegen", LONG, "--lang", "c", "--what", "gravity", "-o", out]) == 0
    text = capsys.readouterr().out
    assert (
        "base parameters by the recursive method: the projection method handles at most 18 "
        "joints" in text
    )
    assert f": {long_numerical_count} base parameters;" in text


def test_refusal_names_each_limit(tmp_path):
    """Each limit of the projection method, on robots just inside and just outside it."""
    refusal = _core.projection_refusal
    chain18, chain19 = mindyn.load("planar18"), mindyn.load("planar19")
    assert "joints" not in (refusal(chain18._m) or "")  # (its memory estimate refuses it)
    assert refusal(mindyn.load("puma560")._m) is None
    assert refusal(chain19._m).startswith("the projection method handles at most 18 joints")
    # parameters: the row reduction takes more than a tree within the joint limits has (44
    # joints, 15 columns each with rotor inertia, three friction columns and an offset), so no
    # tree is refused for its parameters: 26 joints of 10 parameters, 20 of 13
    assert _core.projection_limits()["parameters"] >= 15 * 44
    t26 = mindyn.load(random_tree_urdf(tmp_path / "t26.urdf", n=26, seed=3))
    t20 = mindyn.load(random_tree_urdf(tmp_path / "t20.urdf", n=20, seed=3))
    for t in (t26, t20):  # within the tree's joint and path limits
        assert not t.is_serial and max(_depths(t.parents)) <= 16
    assert "parameters" not in (refusal(t26._m) or "")
    assert "parameters" not in (refusal(t20._m, rotor=True, friction=True) or "")
    t45 = mindyn.load(random_tree_urdf(tmp_path / "t45.urdf", n=45, seed=3))
    assert refusal(t45._m).startswith("the projection method handles at most 44 joints on a tree")
    # the same reason through base_parameters: the refusal is what the choice reports
    assert mindyn.base_parameters(t45).method_reason.startswith(refusal(t45._m))
    with pytest.raises(mindyn.ModelError, match="at most 44 joints on a tree.*method='recursive'"):
        mindyn.base_parameters(t45, method="projection")


def _depths(parents: list[int]) -> list[int]:
    depth: list[int] = []
    for p in parents:
        depth.append(1 if p < 0 else depth[p] + 1)
    return depth
