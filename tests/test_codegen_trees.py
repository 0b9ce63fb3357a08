"""Generated code of fixed-base trees against Pinocchio.

Baxter (example-robot-data: head, both arms, a finger of each gripper) and random trees
(tests/random_tree.py: arbitrary axes, revolute, continuous and prismatic joints, fixed joints,
branches), loaded whole by mindyn and parsed by Pinocchio from the same URDF (test_trees: the
joint order, the mimic fingers locked, the configuration of continuous joints). The generated C
(compiled warning-free, called through ctypes) and the run-time tape of the same program
(BaseDynamics) against Pinocchio's rnea and generalized gravity; the Structured Text of a tree
evaluated like its C; the adaptive-PD step of a tree against mindyn.control's Slotine-Li
regressor; the CLI on a tree.

Tolerance 1e-10 relative: rnea and the generated recursion both sum O(n) products of order-one
terms in double precision (~1e-15); the base values p_b = Y pi of the numerical method add the
round-off of its echelon form (~1e-13); Baxter's URDF turns frames by truncated right angles,
whose 4.9e-12 residues the generated code takes as exact zeros (its geometry snap), ~1e-11.
"""

from __future__ import annotations

import mindyn
import pinocchio as pin
import pytest
from conftest import assert_close, random_state
from mindyn.cli import main
from mindyn.codegen import BaseDynamics, generate
from random_tree import random_tree_urdf
from test_codegen import GCC, CFunctions, STInterpreter, compile_c, joint_terms, st_tree
from test_codegen_controller import check_adaptive_steps
from test_trees import BAXTER, BAXTER_MIMIC, lock, pin_q

pytestmark = pytest.mark.skipif(GCC is None, reason="gcc is needed to compile generated C")

TOL = 1e-10


def tree_pair(case: str, folder):
    """(mindyn Robot, pin.Model) of Baxter or of the random tree 'tree<n>_<seed>'."""
    if case == "baxter":
        path = BAXTER
    else:
        n, seed = (int(x) for x in case[4:].split("_"))
        path = random_tree_urdf(folder / f"{case}.urdf", n, seed)
    model = pin.buildModelFromUrdf(str(path))
    if case == "baxter":
        model = lock(model, BAXTER_MIMIC)
    robot = mindyn.load(path)
    assert not robot.is_serial
    assert list(model.names)[1:] == robot.joint_names
    return robot, model


@pytest.mark.parametrize(
    "case, rotor, friction",
    [("baxter", False, False), ("tree6_21", True, True), ("tree9_22", False, False)],
)
def test_generated_c_of_a_tree_matches_pinocchio(case, rotor, friction, tmp_path, rng):
    robot, model = tree_pair(case, tmp_path)
    bp = mindyn.base_parameters(robot, rotor=rotor, friction=friction, method="numerical")
    code = generate(robot, base=bp, name="tree_dyn")
    c = CFunctions(compile_c(code, tmp_path, "tree"), code, robot.n)
    joints = "".join(
        f" *   {k + 1}. {name} (on {'the base' if p < 0 else robot.joint_names[p]})\n"
        for k, (name, p) in enumerate(zip(robot.joint_names, robot.parents, strict=True))
    )
    assert joints in code.header  # the order of q, with the joint each is mounted on
    classical = generate(robot, what="id", base=False, rotor=rotor, friction=friction, name="cl")
    cl = CFunctions(compile_c(classical, tmp_path, "cl"), classical, robot.n)
    pi = robot.parameters(rotor=rotor, friction=friction)
    p = bp.values(pi)
    tape = BaseDynamics(bp)  # the same program, run at run time
    data = model.createData()
    for _ in range(3):
        q, dq, ddq = random_state(robot, rng)
        qp = pin_q(model, q)
        ref = pin.rnea(model, data, qp, dq, ddq) + joint_terms(robot, dq, ddq, rotor, friction)
        assert_close(c.id(q, dq, ddq, p), ref, TOL, f"generated C id of a tree vs rnea ({case})")
        assert_close(tape.inverse_dynamics(q, dq, ddq, p), ref, TOL, f"tape id of a tree ({case})")
        assert_close(cl.id(q, dq, ddq, pi), ref, TOL, f"classical C id of a tree ({case})")
        g = pin.computeGeneralizedGravity(model, data, qp)
        assert_close(c.gravity(q, p), g, TOL, f"generated C gravity of a tree ({case})")
        assert_close(tape.gravity(q, p), g, TOL, f"tape gravity of a tree ({case})")
        W = c.regressor(q, dq, ddq)
        assert_close(W @ p, ref, TOL, f"generated C W_b p of a tree vs rnea ({case})")
        assert_close(W, bp.regressor(q, dq, ddq), TOL, f"generated C W_b of a tree ({case})")


def test_structured_text_of_a_tree_evaluates_like_the_c(tmp_path, rng):
    robot, _ = tree_pair("tree5_23", tmp_path)
    bp = mindyn.base_parameters(robot, rotor=True, friction=True, method="numerical")
    st = generate(robot, lang="st", base=bp, name="tree_st")
    code = generate(robot, base=bp, name="tree_c")
    c = CFunctions(compile_c(code, tmp_path, "tree_c"), code, robot.n)
    tree = st_tree(st.text)
    p = bp.values(robot.parameters(rotor=True, friction=True))
    q, dq, ddq = random_state(robot, rng)
    ins = {"q": q, "dq": dq, "ddq": ddq, "p": p}
    tau = STInterpreter(tree, "tree_st_inverse_dynamics").run(ins)["tau"]
    assert_close(tau, c.id(q, dq, ddq, p), 1e-12, "ST id of a tree vs C")
    g = STInterpreter(tree, "tree_st_gravity").run(ins)["tau"]
    assert_close(g, c.gravity(q, p), 1e-12, "ST gravity of a tree vs C")
    W = STInterpreter(tree, "tree_st_regressor").run(ins)["w"]
    assert_close(W, c.regressor(q, dq, ddq), 1e-12, "ST regressor of a tree vs C")


@pytest.mark.parametrize("nu, offset", [(0.0, False), (0.5, True)])
def test_adaptive_step_of_a_tree_matches_the_library(nu, offset, tmp_path, rng):
    """One step of the generated adaptive PD on a tree: tau and the next estimate as
    mindyn.control.AdaptivePD and its Slotine-Li regressor give them (1e-11 relative, as for
    chains in test_codegen_controller)."""
    robot, _ = tree_pair("tree6_24", tmp_path)
    check_adaptive_steps(robot, nu, offset, rng, method="numerical", what=" of a tree")


@pytest.mark.parametrize("method", [None, "recursive", "numerical"])
def test_cli_codegen_of_a_tree(method, tmp_path, capsys):
    """mindyn codegen on a tree by the default (projection) and the other methods: every method
    gives the same base set, and the header lists each joint with its parent."""
    robot, _ = tree_pair("tree5_25", tmp_path)
    path = tmp_path / "tree5_25.urdf"
    argv = ["codegen", str(path), "--lang", "c", "-o", str(tmp_path / "tree")]
    assert main(argv + (["--method", method] if method else [])) == 0
    bp = mindyn.base_parameters(robot, method="numerical")
    assert capsys.readouterr().out.startswith(f"{robot.name}: {bp.n} base parameters;")
    header = (tmp_path / "tree.h").read_text()
    assert f" *   {robot.n}. {robot.joint_names[-1]} (on " in header
