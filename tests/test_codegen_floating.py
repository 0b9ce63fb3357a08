"""Generated C of floating-base inverse dynamics against Pinocchio.

Solo12 and Go1 (example-robot-data) with a free-flyer root (Pinocchio's URDF parser with
JointModelFreeFlyer) and with a planar root, and random trees (tests/random_tree.py) loaded with a
free-flyer root: the generated C, compiled with gcc -std=c99 -Wall -Wextra -Werror -pedantic and
called through ctypes, against Pinocchio's rnea, generalized gravity and the base regressor's
product; with contact wrenches against rnea - sum_c J_c^T f_c, J_c from Pinocchio's
computeJointJacobians / getFrameJacobian of the contact link's frame (LOCAL_WORLD_ALIGNED for
world-axes wrenches, LOCAL for the link's axes): an independent computation of the contact
terms.

Tolerance 1e-12 relative: both sides sum O(n) products of order-one terms (~1e-15); the base
values p_b = Y pi of the numerical method add the round-off of its echelon form (~1e-14 here).
"""

from __future__ import annotations

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import assert_close, cli
from mindyn import codegen
from random_tree import random_multidof_tree_yaml, random_tree_urdf
from test_codegen import GCC, compile_c, compile_shared, ptr
from test_floating_cli import refused, run
from test_multibody import FLOATING, pin_q, random_state

pytestmark = pytest.mark.skipif(GCC is None, reason="gcc is needed to compile generated C")

TOL = 1e-12
FEET = ["FL_LOWER_LEG", "FR_LOWER_LEG", "HL_LOWER_LEG", "HR_LOWER_LEG"]


def solo(root: str = "floating", name: str = "solo12"):
    joint = pin.JointModelFreeFlyer() if root == "floating" else pin.JointModelPlanar()
    path = FLOATING[name]
    return mindyn.load(path, root_joint=root), pin.buildModelFromUrdf(str(path), joint)


class Floating:
    """The generated functions of a floating base through ctypes."""

    def __init__(self, code, folder, robot):
        self.lib, self.code, self.nv = compile_c(code, folder, code.name), code, robot.nv

    def _call(self, fn, args, size):
        out = np.zeros(size)
        arrays = [np.ascontiguousarray(a, dtype=float) for a in args]
        getattr(self.lib, f"{self.code.name}_{fn}")(*[ptr(a) for a in arrays], ptr(out))
        return out

    def id(self, q, v, a, p, f=None):
        args = [q, v, a] + ([] if p is None else [p]) + ([] if f is None else [f])
        return self._call("inverse_dynamics", args, self.nv)

    def gravity(self, q, p):
        return self._call("gravity", [q, p], self.nv)

    def regressor(self, q, v, a):
        return self._call("regressor", [q, v, a], self.nv * len(self.code.names)).reshape(
            self.nv, -1
        )


def contact_terms(model, data, qp, links, f, frame):
    """sum_c J_c^T f_c by Pinocchio: the Jacobian of each link's frame in world-aligned axes
    (frame "world") or in the link's own ("local")."""
    pin.computeJointJacobians(model, data, qp)
    pin.updateFramePlacements(model, data)
    ref = pin.LOCAL_WORLD_ALIGNED if frame == "world" else pin.LOCAL
    out = np.zeros(model.nv)
    for c, link in enumerate(links):
        J = pin.getFrameJacobian(model, data, model.getFrameId(link), ref)
        out += J.T @ f[6 * c : 6 * c + 6]
    return out


@pytest.mark.parametrize(
    "name, root", [("solo12", "floating"), ("go1", "floating"), ("solo12", "planar")]
)
def test_generated_c_of_a_floating_quadruped_matches_pinocchio(name, root, tmp_path, rng):
    robot, model = solo(root, name)
    bp = mindyn.base_parameters(robot)  # the default method, on the single-DOF expansion
    code = codegen.generate(robot, base=bp, name=f"{name}_{root}")
    assert code.contacts == [] and f"_NQ {robot.nq}" in code.header
    c = Floating(code, tmp_path, robot)
    p = bp.values(robot.params)
    data = model.createData()
    for _ in range(4):
        q, v, a = random_state(robot, rng)
        qp = pin_q(robot, model, q)
        ref = pin.rnea(model, data, qp, v, a).copy()
        assert_close(c.id(q, v, a, p), ref, TOL, f"generated C id, {name} {root} vs rnea")
        g = pin.computeGeneralizedGravity(model, data, qp)
        assert_close(c.gravity(q, p), g, TOL, f"generated C gravity, {name} {root}")
        assert_close(c.regressor(q, v, a) @ p, ref, TOL, f"generated C W_b p, {name} {root}")


@pytest.mark.parametrize("frame", ["world", "local"])
def test_contact_wrenches_subtract_their_jacobian_transpose(frame, tmp_path, rng):
    robot, model = solo()
    code = codegen.generate(
        robot, what="id", base=False, numeric=True, contacts=FEET, wrench_frame=frame, name="solo"
    )
    for k, link in enumerate(FEET):
        assert f"{link}: f[{6 * k}..{6 * k + 5}]" in code.header
    assert f"const double f[{6 * len(FEET)}]" in code.source
    c = Floating(code, tmp_path, robot)
    data = model.createData()
    for _ in range(4):
        q, v, a = random_state(robot, rng)
        f = rng.uniform(-20, 20, 6 * len(FEET))
        qp = pin_q(robot, model, q)
        ref = pin.rnea(model, data, qp, v, a) - contact_terms(model, data, qp, FEET, f, frame)
        assert_close(c.id(q, v, a, None, f), ref, TOL, f"generated C id with contacts ({frame})")


def test_the_base_wrench_vanishes_when_the_contacts_explain_the_motion(tmp_path, rng):
    """With one contact whose wrench balances the base rows of rnea (solved from Pinocchio's
    Jacobian), the generated base wrench is zero and the joint rows are rnea - J^T f."""
    robot, model = solo()
    code = codegen.generate(robot, what="id", base=False, contacts=["HL_LOWER_LEG"], name="one")
    c = Floating(code, tmp_path, robot)
    data = model.createData()
    q, v, a = random_state(robot, rng)
    qp = pin_q(robot, model, q)
    tau = pin.rnea(model, data, qp, v, a).copy()
    pin.computeJointJacobians(model, data, qp)
    pin.updateFramePlacements(model, data)
    fid = model.getFrameId("HL_LOWER_LEG")
    J = pin.getFrameJacobian(model, data, fid, pin.LOCAL_WORLD_ALIGNED)
    f = np.linalg.solve(J[:, :6].T, tau[:6])
    out = c.id(q, v, a, robot.params, f)
    assert np.abs(out[:6]).max() <= 1e-11 * np.abs(tau).max()
    assert_close(out[6:], (tau - J.T @ f)[6:], TOL, "joint rows with a balancing contact")


@pytest.mark.parametrize("n, seed", [(7, 5), (9, 11)])
def test_generated_c_of_a_random_tree_with_a_free_flyer_root(n, seed, tmp_path, rng):
    path = random_tree_urdf(tmp_path / "tree.urdf", n, seed)
    robot = mindyn.load(path, root_joint="floating")
    model = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    assert robot.joint_types[0] == "floating" and not robot.is_serial
    bp = mindyn.base_parameters(robot)
    links = [robot.link_names[2], robot.link_names[-1]]
    code = codegen.generate(robot, base=bp, contacts=links, name="tree")
    c = Floating(code, tmp_path, robot)
    p = bp.values(robot.params)
    data = model.createData()
    for _ in range(3):
        q, v, a = random_state(robot, rng)
        f = rng.uniform(-10, 10, 12)
        qp = pin_q(robot, model, q)
        ref = pin.rnea(model, data, qp, v, a).copy()
        assert_close(c.regressor(q, v, a) @ p, ref, TOL, "generated C W_b p, floating tree")
        ref -= contact_terms(model, data, qp, links, f, "world")
        assert_close(c.id(q, v, a, p, f), ref, TOL, "generated C id, floating tree, contacts")


def test_what_a_floating_base_cannot_have_is_refused_in_one_line(tmp_path):
    robot, _ = solo()
    fixed = mindyn.load(FLOATING["solo12"])
    cases = [
        (lambda: codegen.generate(robot, lang="st"), mindyn.ModelError, "Structured Text is"),
        (
            lambda: codegen.generate(robot, base=False, offset=True),
            mindyn.ModelError,
            "floating base takes the inertial parameters only",
        ),
        (
            lambda: codegen.generate(fixed, contacts=["FL_LOWER_LEG"]),
            mindyn.ArgumentError,
            "contacts apply to a floating base",
        ),
        (
            lambda: codegen.generate(robot, contacts=["FL_FOOT"]),
            mindyn.ArgumentError,
            "contacts names 'FL_FOOT', no moving link",
        ),
        (
            lambda: codegen.generate(robot, contacts=["FL_LOWER_LEG"] * 2),
            mindyn.ArgumentError,
            "names the link 'FL_LOWER_LEG' twice",
        ),
        (
            lambda: codegen.generate(robot, what="gravity", contacts=FEET),
            mindyn.ModelError,
            "contact wrenches enter the inverse dynamics only",
        ),
        (
            lambda: codegen.generate(robot, contacts=FEET, wrench_frame="body"),
            mindyn.ArgumentError,
            "wrench_frame is a str 'body'",
        ),
        (
            lambda: codegen.generate_controller(robot, base=False),
            mindyn.ModelError,
            "floating base takes the inertial parameters only",
        ),
        (
            lambda: codegen.generate_observer(robot, base=mindyn.base_parameters(robot)),
            mindyn.ModelError,
            "a generated momentum observer takes revolute and prismatic joints only",
        ),
    ]
    yaml = random_multidof_tree_yaml(tmp_path / "multi.yaml", 4, 3, ("revolute", "spherical"))
    tree = mindyn.load(yaml)
    joint = tree.joint_names[tree.joint_types.index("spherical")]
    msg = "code generation takes revolute and prismatic joints, and a free-flyer or planar joint "
    msg += f"on the fixed base; model '{tree.name}' has the spherical joint '{joint}'"
    cases.append((lambda: codegen.generate(tree, base=False), mindyn.ModelError, msg))
    for call, error, text in cases:
        with pytest.raises(error) as e:
            call()
        assert text in str(e.value) and "\n" not in str(e.value), str(e.value)


def test_the_command_line_generates_it_for_a_urdf_with_its_own_floating_joint(tmp_path, rng):
    """A URDF whose root link carries a `floating` joint (Pinocchio's parser: a free-flyer)."""
    text = FLOATING["solo12"].read_text()
    at = text.index("<link ")
    joint = '<joint name="float" type="floating"><parent link="world"/><child link="base_link"/>'
    path = tmp_path / "solo_float.urdf"
    path.write_text(text[:at] + f'<link name="world"/>\n{joint}</joint>\n' + text[at:])
    out = cli("codegen", path, "--lang", "c", "-o", tmp_path / "solo_cli", "--numeric")
    assert "inverse_dynamics" in out
    robot, model = mindyn.load(path), pin.buildModelFromUrdf(str(path))
    assert robot.joint_types[0] == "floating" and model.nq == robot.nq
    lib = compile_shared(tmp_path / "solo_cli.c", tmp_path / "libsolo_cli.so")
    data = model.createData()
    for _ in range(2):
        q, v, a = random_state(robot, rng)
        tau = np.zeros(robot.nv)
        args = [np.ascontiguousarray(x) for x in (q, v, a)]
        lib.solo_inverse_dynamics(*[ptr(x) for x in args], ptr(tau))
        ref = pin.rnea(model, data, pin_q(robot, model, q), v, a)
        assert_close(tau, ref, TOL, "generated C id by the command line, floating joint")


def test_the_command_line_takes_a_root_joint_and_contacts(tmp_path, rng):
    """`mindyn codegen URDF --root-joint floating --contact ...`: the C the command line writes
    (base parameters, the robot's values) against rnea - sum J_c^T f_c by Pinocchio; the options
    that do not apply to a floating base are refused in one line."""
    robot, model = solo()
    path = FLOATING["solo12"]
    feet = FEET[:2]
    out = cli(
        "codegen", path, "--root-joint", "floating", "--lang", "c", "-o", tmp_path / "s",
        "--name", "s", "--contact", *feet, "--wrench-frame", "local",
    )  # fmt: skip
    assert "inverse_dynamics" in out
    header = (tmp_path / "s.h").read_text()
    assert all(f"{link}: f[{6 * k}..{6 * k + 5}]" in header for k, link in enumerate(feet))
    lib = compile_shared(tmp_path / "s.c", tmp_path / "libs.so")
    bp = mindyn.base_parameters(robot)
    p = np.ascontiguousarray(bp.values(robot.params))
    data = model.createData()
    for _ in range(3):
        q, v, a = random_state(robot, rng)
        f = rng.uniform(-20, 20, 6 * len(feet))
        qp = pin_q(robot, model, q)
        ref = pin.rnea(model, data, qp, v, a) - contact_terms(model, data, qp, feet, f, "local")
        tau = np.zeros(robot.nv)
        args = [np.ascontiguousarray(x) for x in (q, v, a)]
        lib.s_inverse_dynamics(*[ptr(x) for x in args], ptr(p), ptr(f), ptr(tau))
        assert_close(tau, ref, TOL, "generated C id with contacts by the command line")
    for argv, said in [
        (["--what", "adaptive-pd", "--lang", "c"], "codegen --what adaptive-pd takes revolute"),
        (["--lang", "st"], "Structured Text is generated for a fixed base only"),
        (["--lang", "c", "--contact", "nope"], "--contact names 'nope', no moving link"),
        (["--lang", "c", "--wrench-frame", "local"], "--wrench-frame: applies with --contact"),
    ]:
        refused("codegen", path, "--root-joint", "floating", "-o", tmp_path / "x", *argv,
                match=said)  # fmt: skip
    refused("codegen", "planar2", "--lang", "c", "--contact", "a", "-o", tmp_path / "y",
            match="--contact: applies to a floating-base robot")  # fmt: skip
    for terms in ("--rotor", "--friction"):  # one line alone: no method statement before it
        argv = ["codegen", path, "--root-joint", "floating", "--lang", "c", terms]
        refused(*argv, "-o", tmp_path / "x", match="rotor inertia and friction are defined for")
        assert run(*argv, "-o", tmp_path / "x")[1] == ""


def test_the_command_line_runs_the_generator_once(tmp_path, rng, monkeypatch):
    """`mindyn codegen` runs the generator once: the classical-parameter recursion, generated
    only for its operation counts, is generated too with --classical-counts only (it doubled
    the time of a humanoid on a free-flyer). The files written are the library's generate()
    with the same base parameters, byte for byte, and the C equals Pinocchio's rnea."""
    from mindyn import _core

    calls = []
    real = _core.generate_code

    def counted(*args, **kwargs):
        calls.append(kwargs.get("name"))
        return real(*args, **kwargs)

    monkeypatch.setattr(_core, "generate_code", counted)
    robot, model = solo()
    argv = ["codegen", FLOATING["solo12"], "--root-joint", "floating", "--lang", "c", "--name", "s"]
    out = cli(*argv, "-o", tmp_path / "s")
    assert len(calls) == 1
    assert "--classical-counts" in out and "classical parameters" not in out
    code = codegen.generate(robot, lang="c", base=mindyn.base_parameters(robot), name="s")
    assert len(calls) == 2
    assert (tmp_path / "s.c").read_text() == code.source
    assert (tmp_path / "s.h").read_text() == code.header
    names = len(robot.parameter_names())
    assert f"{len(code.names)} base parameters; {names} classical" in out
    lib = compile_shared(tmp_path / "s.c", tmp_path / "libs.so")
    p = np.ascontiguousarray(code.values)
    data = model.createData()
    for _ in range(2):
        q, v, a = random_state(robot, rng)
        tau = np.zeros(robot.nv)
        lib.s_inverse_dynamics(*[ptr(np.ascontiguousarray(x)) for x in (q, v, a, p)], ptr(tau))
        ref = pin.rnea(model, data, pin_q(robot, model, q), v, a)
        assert_close(tau, ref, TOL, "generated C id by the command line, generated once")
    # with the classical counts: the classical recursion generated too, its counts beside
    calls.clear()
    (tmp_path / "both").mkdir()
    both = cli(*argv, "-o", tmp_path / "both" / "s", "--classical-counts")
    classical = codegen.generate(robot, lang="c", base=False, name="s")
    assert len(calls) == 3 and calls[:2] == ["s", "s"]
    row = both.splitlines()[-3].split()
    assert row[0] == "inverse_dynamics"
    counts = [code.counts["inverse_dynamics"][k] for k in ("mul", "add", "trig")]
    counts += [classical.counts["inverse_dynamics"][k] for k in ("mul", "add", "trig")]
    assert [int(x) for x in row[1:]] == counts
    assert (tmp_path / "both" / "s.c").read_text() == code.source


def test_a_single_dof_robot_gets_the_classical_counts_by_default(tmp_path):
    """The classical-parameter recursion's counts, beside the base ones, are the default on a
    robot of single-DOF joints (cheap there) and equal the library's; --no-classical-counts
    leaves the second generation out."""
    classical = codegen.generate("puma560", lang="c", base=False, name="p")
    base = codegen.generate("puma560", lang="c", name="p")
    out = cli("codegen", "puma560", "--lang", "c", "--name", "p", "-o", tmp_path / "p")
    row = next(line.split() for line in out.splitlines() if line.startswith("inverse_dynamics"))
    want = [base.counts["inverse_dynamics"][k] for k in ("mul", "add", "trig")]
    want += [classical.counts["inverse_dynamics"][k] for k in ("mul", "add", "trig")]
    assert [int(x) for x in row[1:]] == want
    off = cli("codegen", "puma560", "--lang", "c", "--name", "p", "-o", tmp_path / "q",
              "--no-classical-counts")  # fmt: skip
    row = next(line.split() for line in off.splitlines() if line.startswith("inverse_dynamics"))
    assert [int(x) for x in row[1:]] == want[:3]
    assert "classical parameters" not in off and "--classical-counts" in off
