"""The base parameters of a larger tree through the sparse path: Y is read a block of rows at a
time on the columns those rows use, and its structure is the tree's (a link's parameters regroup
only into the pivots of its own link and its ancestors). Torques are checked against Pinocchio.
Speed and memory on 1000 joints: bench/bench_recursive_tree.py."""

from __future__ import annotations

import mindyn
import numpy as np
import pinocchio as pin
from mindyn.formulas import numeric_formulas
from random_tree import random_tree_urdf
from test_base_parameters import check_against_rnea


def test_a_120_joint_tree_through_the_sparse_path(tmp_path, rng):
    path = random_tree_urdf(tmp_path / "t.urdf", n=120, seed=7, fixed=0)
    robot = mindyn.load(path)
    assert robot.n == 120 and not robot.is_serial
    bp = mindyn.base_parameters(robot, rotor=True, friction=True)
    assert bp.method == "recursive"  # 1560 parameters: beyond the projection method
    Y = bp.Y
    P = len(bp.classical_names)
    assert Y.shape == (bp.n, P) and P == 13 * robot.n

    # the rows of Y as the readable formulas read them: a block at a time, on their columns
    rows, cols = bp._b.set_rows("eom", 40, 25)
    assert list(cols) == list(np.flatnonzero(np.any(Y[40:65] != 0.0, axis=0)))
    assert np.array_equal(rows, Y[40:65][:, cols])
    assert bp.formulas == [str(f) for f in numeric_formulas(Y, bp.names, bp.classical_names)]
    assert np.array_equal(bp.sets["eom"]["Y"], Y)

    # a link's parameters regroup only into its own link's and its ancestors' pivots
    per = 13

    def link(c: int) -> int:
        return c // per

    def ancestors(k: int) -> set[int]:
        out = {k}
        while robot.parents[k] >= 0:
            k = robot.parents[k]
            out.add(k)
        return out

    for b, c in zip(*np.nonzero(Y), strict=True):
        assert link(bp.pivots[b]) in ancestors(link(c)), (bp.names[b], bp.classical_names[c])

    # and the torques are Pinocchio's (W_b (Y pi) = rnea(pi)); lever arms over long root paths
    model = pin.buildModelFromUrdf(str(path))
    check_against_rnea(bp, robot, model, rng, "120-joint tree", tol=1e-9)
