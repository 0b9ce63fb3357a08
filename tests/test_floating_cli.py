"""``mindyn identify`` on floating-base robots and ``--root-joint`` on the command line, against
logs the tests generate: Pinocchio's inverse dynamics (rnea) of a free-flyer (or planar) robot
at random states, the root's generalized force carried by contact wrenches split among the
contact links in a known way (random wrenches corrected by the least-norm wrench that makes the
root's rows hold, through Pinocchio's frame Jacobians), the actuated coordinates' torques the
rest. Noise of a known size is added to the torques and the wrenches; its generalized force is
computed with Pinocchio's Jacobians. The true base values are those of the description's
parameters in the numerical method's base set."""

from __future__ import annotations

import contextlib
import functools
import io
import json
from pathlib import Path

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import assert_close, cli
from mindyn import codegen
from mindyn.cli import main
from random_tree import random_multidof_tree_yaml, random_tree_urdf
from test_multibody import FLOATING, random_state

FEET = ["FL_LOWER_LEG", "FR_LOWER_LEG", "HL_LOWER_LEG", "HR_LOWER_LEG"]
AXES = ("fx", "fy", "fz", "tx", "ty", "tz")
TAU_NOISE, FORCE_NOISE, MOMENT_NOISE = 0.05, 0.5, 0.05


@functools.cache
def pair(path: str, root: str = "floating"):
    """(mindyn Robot, pin.Model) of a URDF with a free-flyer or planar root."""
    joint = pin.JointModelFreeFlyer() if root == "floating" else pin.JointModelPlanar()
    return mindyn.load(path, root_joint=root), pin.buildModelFromUrdf(path, joint)


def simulate(
    robot,
    model,
    contacts,
    rng,
    m: int,
    *,
    noise: bool = False,
    local: bool = False,
    sizes: tuple[float, float, float] = (TAU_NOISE, FORCE_NOISE, MOMENT_NOISE),
):
    """m samples: (table with the log's columns, header, the noise's generalized forces (m,
    nv)). Wrenches about each contact link's origin in world axes (or the link's own); without
    contacts (free flight) random torques and the accelerations of Pinocchio's aba. With
    ``noise``, Gaussian noise of the standard deviations ``sizes`` on the joint torques, the
    wrenches' forces and their moments."""
    tau_noise, force_noise, moment_noise = sizes
    data = model.createData()
    r = model.joints[1].nv
    rows, noise_gf = [], []
    for _ in range(m):
        q, v, a = random_state(robot, rng)
        if not contacts:  # free flight: nothing acts on the root; the motion follows (aba)
            a = pin.aba(model, data, q, v, np.r_[np.zeros(r), rng.normal(0.0, 1.0, model.nv - r)])
        F = pin.rnea(model, data, q, v, a)
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        frame = pin.LOCAL if local else pin.LOCAL_WORLD_ALIGNED
        J = [pin.getFrameJacobian(model, data, model.getFrameId(c), frame) for c in contacts]
        A = np.hstack([j.T for j in J]) if contacts else np.zeros((model.nv, 0))
        f = rng.normal(0.0, 5.0, A.shape[1])
        if contacts:  # the known split: the least-norm correction that balances the root
            f += np.linalg.pinv(A[:r]) @ (F[:r] - A[:r] @ f)
        tau = (F - A @ f)[r:]
        assert np.abs((F - A @ f)[:r]).max() < 1e-8 * max(1.0, np.abs(F).max())
        n_tau = rng.normal(0.0, tau_noise, tau.shape) if noise else 0 * tau
        scale = np.tile([force_noise] * 3 + [moment_noise] * 3, len(contacts))
        n_f = scale * rng.normal(size=f.shape) if noise else 0 * f
        noise_gf.append(np.r_[np.zeros(r), n_tau] + A @ n_f)
        rows.append(np.r_[q, v, a, tau + n_tau, f + n_f])
    header = [f"q{i + 1}" for i in range(robot.nq)] + [f"dq{i + 1}" for i in range(robot.nv)]
    header += [f"ddq{i + 1}" for i in range(robot.nv)]
    header += [f"tau{i + 1}" for i in range(robot.nv - r)]
    header += [f"{c}.{x}" for c in contacts for x in AXES]
    return np.array(rows), header, np.array(noise_gf)


def write(path, table, header, drop=()) -> str:
    keep = [j for j, h in enumerate(header) if h not in drop]
    head = ",".join(header[j] for j in keep)
    np.savetxt(path, table[:, keep], delimiter=",", header=head, comments="", fmt="%.17g")
    return str(path)


def library(robot, fit: list, *, model: str = "full", **reading):
    """The library's report of the floating-base workflow on the logs ``fit``."""
    from mindyn.identification.floating_workflow import load_floating_logs, run_floating

    return run_floating(robot, load_floating_logs(fit, robot, **reading), model=model)


def truth(robot):
    base = mindyn.base_parameters(robot, method="numerical")
    return base, base.values(robot.params)


def run(*argv) -> tuple[int, str, str]:
    """``mindyn ARGV`` in this process: (status, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main([str(a) for a in argv])
    return rc, out.getvalue(), err.getvalue()


def refused(*argv, match: str) -> str:
    rc, _, err = run(*argv)
    assert rc != 0, argv
    assert err.startswith("mindyn: error: ") and err.count("\n") == 1, err
    assert "Traceback" not in err
    assert match in err, err
    return err


SOLO = str(FLOATING["solo12"])


def test_the_json_of_identify_is_the_library_report_and_noise_free_logs_give_the_base_values(
    tmp_path,
):
    """Solo12 on a free-flyer, four feet in contact: the CLI's JSON equals
    run_floating(...).to_dict(); the full and the base-link models both give the true base
    values; the validation error is at round-off."""
    robot, model = pair(SOLO)
    rng = np.random.default_rng(11)
    fit = write(tmp_path / "fit.csv", *simulate(robot, model, FEET, rng, 40)[:2])
    val = write(tmp_path / "val.csv", *simulate(robot, model, FEET, rng, 15)[:2])
    out = tmp_path / "id.json"
    text = cli("identify", SOLO, fit, "--root-joint", "floating", "--validate", val, "--json", out)
    doc = json.loads(out.read_text())
    assert doc == json.loads(json.dumps(library(robot, [fit], validate=[val]).to_dict()))
    base, true = truth(robot)
    assert doc["names"] == list(base.names) and doc["n_base"] == base.n
    assert doc["rank"] == base.n and doc["base_link_rank"] == base.n
    assert_close(doc["values"], true, 1e-6, "CLI floating-base values (full model)")
    assert doc["validation"]["overall_relative"] < 1e-9
    assert len(doc["validation"]["rms"]) == robot.nv == len(doc["coordinates"])
    assert doc["contacts"] == sorted(FEET) and doc["wrench_frame"] == "world"
    assert "base-link model 94 of 94" in text and "validation data" in text
    # the base-link model needs no joint torques: the same log without them
    bare = tmp_path / "bare.csv"
    table, header, _ = simulate(robot, model, FEET, np.random.default_rng(12), 40)
    write(bare, table, header, drop=[h for h in header if h.startswith("tau")])
    cli("identify", SOLO, bare, "--root-joint", "floating", "--model", "base", "--json", out)
    link = json.loads(out.read_text())
    assert link["model"] == "base" and link["rank"] == base.n
    assert_close(link["values"], true, 1e-6, "CLI floating-base values (base-link model)")
    assert len(link["fit"]["rms"]) == 6


@pytest.mark.parametrize("root", ["floating", "planar"])
def test_a_random_tree_is_identified_and_the_base_link_model_agrees_where_identifiable(
    tmp_path, root
):
    """A random tree of revolute and prismatic joints on a free-flyer or planar root, two leaf
    links in contact (their wrenches in the links' own axes): the full model gives the true base
    values; the base-link model gives them on the combinations it identifies (all of them on a
    free-flyer; fewer on a planar root, whose rows see no gravity)."""
    urdf = str(random_tree_urdf(tmp_path / "tree.urdf", n=7, seed=3, moving=("revolute",)))
    robot, model = pair(urdf, root)
    children = {p for p in robot.parents}
    leaves = [robot.link_names[k + 1] for k in range(robot.n) if k not in children][:2]
    rng = np.random.default_rng(5)
    log = write(tmp_path / "fit.csv", *simulate(robot, model, leaves, rng, 60, local=True)[:2])
    out = tmp_path / "id.json"
    argv = ["identify", urdf, log, "--root-joint", root, "--wrench-frame", "local", "--json", out]
    cli(*argv, "--contact", *leaves)
    full = json.loads(out.read_text())
    base, true = truth(robot)
    assert full["rank"] == base.n
    assert_close(full["values"], true, 1e-6, f"random tree values ({root} root, full model)")
    cli(*argv, "--model", "base")
    link = json.loads(out.read_text())
    assert link["rank"] == full["base_link_rank"]
    result = library(robot, [log], model="base", wrench_frame="local").result
    assert_close(result.span @ link["values"], result.span @ true, 1e-6, f"base-link ({root})")
    if root == "floating":  # the base link's six rows identify every base parameter
        assert link["rank"] == base.n
        assert_close(link["values"], true, 1e-6, "random tree values (base-link model)")
        assert all(s is not None for s in link["std"])


def test_a_planar_root_base_link_model_identifies_combinations_only(tmp_path):
    """Solo12 on a planar root: the root's three rows (x, y, yaw) see no gravity; the base-link
    model identifies fewer combinations than the base set, says so, gives no standard deviation
    for a value outside its span, and agrees with the truth on its span."""
    robot, model = pair(SOLO, "planar")
    log = write(tmp_path / "p.csv", *simulate(robot, model, FEET, np.random.default_rng(8), 30)[:2])
    out = tmp_path / "id.json"
    text = cli("identify", SOLO, log, "--root-joint", "planar", "--model", "base", "--json", out)
    doc = json.loads(out.read_text())
    base, true = truth(robot)
    assert 0 < doc["rank"] < base.n and f"base-link model {doc['rank']} of {base.n}" in text
    assert "not identified alone" in text and any(s is None for s in doc["std"])
    result = library(robot, [log], model="base").result
    assert_close(result.span @ doc["values"], result.span @ true, 1e-6, "planar base-link span")
    assert doc["coordinates"][:3] == ["root_joint.fx", "root_joint.fy", "root_joint.tz"]


@pytest.mark.parametrize(
    "name, contacts, m",
    [("solo12", FEET, 300), ("talos", ["leg_left_6_link", "leg_right_6_link"], 150)],
)
def test_noisy_torques_and_wrenches_validate_within_the_noise(tmp_path, name, contacts, m):
    """Known noise on the torques (0.05 N m) and the wrenches (0.5 N, 0.05 N m), a quadruped on
    its four feet and a humanoid on its two: on a validation log the RMS error of the predicted
    generalized forces the CLI reports is within 1.2 times the RMS of the noise those
    measurements carry, and the standard deviations it gives describe the estimate's actual
    error."""
    urdf = str(FLOATING[name])
    robot, model = pair(urdf)
    rng = np.random.default_rng(21)
    table, header, _ = simulate(robot, model, contacts, rng, m, noise=True)
    fit = write(tmp_path / "fit.csv", table, header)
    table, header, noise = simulate(robot, model, contacts, rng, 60, noise=True)
    val = write(tmp_path / "val.csv", table, header)
    out = tmp_path / "id.json"
    cli("identify", urdf, fit, "--root-joint", "floating", "--validate", val, "--json", out)
    doc = json.loads(out.read_text())
    ratio = doc["validation"]["rms_all"] / np.sqrt(np.mean(noise**2))
    print(f"{name}: validation RMS / noise RMS = {ratio:.3f}")
    assert ratio <= 1.2, ratio
    per = np.array(doc["validation"]["rms"]) / np.sqrt(np.mean(noise**2, axis=0))
    # per coordinate too, looser: a coordinate with little noise (an arm joint, torque noise
    # only) sees the estimate's own error relatively more
    assert per.max() <= 2.5, per
    _, true = truth(robot)
    z = (np.array(doc["values"]) - true) / np.array(doc["std"])
    print(f"{name}: RMS of (estimate - truth) / std = {np.sqrt(np.mean(z**2)):.3f}")
    assert 0.3 < np.sqrt(np.mean(z**2)) < 3.0


@functools.cache
def _logs(folder):
    """A Solo12 log (clean), its header and table, in ``folder``."""
    robot, model = pair(SOLO)
    table, header, _ = simulate(robot, model, FEET, np.random.default_rng(31), 30)
    return table, header


def test_bad_floating_input_is_refused_in_one_line(tmp_path):
    table, header = _logs(str(tmp_path))
    good = write(tmp_path / "good.csv", table, header)
    ff = ["--root-joint", "floating"]
    bad = write(tmp_path / "w.csv", table, header, drop=["FR_LOWER_LEG.tz"])
    refused("identify", SOLO, bad, *ff, match="missing column 'FR_LOWER_LEG.tz'")
    refused(
        "identify", SOLO, good, *ff, "--contact", "FL_LOWER_LEG", "foot",
        match="--contact: 'foot' is no moving link of robot 'solo'",
    )  # fmt: skip
    refused(
        "identify", SOLO, good, *ff, "--contact", "FL_LOWER_LEG",
        match="wrench columns of link 'FR_LOWER_LEG', not a declared contact link",
    )  # fmt: skip
    only = write(tmp_path / "o.csv", table, header, drop=[f"FR_LOWER_LEG.{a}" for a in AXES])
    refused(
        "identify", SOLO, only, *ff, "--contact", *FEET,
        match="no wrench columns FR_LOWER_LEG.fx..FR_LOWER_LEG.tz",
    )  # fmt: skip
    q = table.copy()
    q[4, 3:7] *= 1.5  # a quaternion of norm 1.5
    refused(
        "identify", SOLO, write(tmp_path / "q.csv", q, header), *ff,
        match="q.csv:6: the quaternion of the floating joint 'root_joint' (columns q4..q7) has "
        "norm 1.5, not 1",
    )  # fmt: skip
    # a free-flyer's log read for a planar root: the columns do not fit
    refused("identify", SOLO, good, "--root-joint", "planar", match="unknown column")
    no_dq = write(tmp_path / "v.csv", table, header, drop=[h for h in header if "dq" in h])
    refused("identify", SOLO, no_dq, *ff, match="no dq and ddq columns and no time column 't'")
    no_tau = write(tmp_path / "t.csv", table, header, drop=[h for h in header if "tau" in h])
    refused("identify", SOLO, no_tau, *ff, match="the full model needs them (the base-link")
    refused("identify", SOLO, good, *ff, "--rotor", match="--rotor: does not apply")
    refused("identify", SOLO, good, *ff, "--consistent", match="--consistent: does not apply")
    refused("identify", SOLO, good, *ff, "--edge", "0.5", match="--edge: does not apply")
    # at its default too: --integration auto would be ignored
    refused("identify", SOLO, good, *ff, "--integration", "auto", match="--integration: does not")
    for f in ("savgol", "none"):  # their derivatives have no cut-off
        refused("identify", SOLO, no_dq, *ff, "--filter", f, "--cutoff", "5",
                match="--cutoff applies only with --filter lowpass or butter")  # fmt: skip
    refused("identify", SOLO, good, *ff, "--model", "energy", match="not the energy model")
    (tmp_path / "log.bag").write_bytes(b"#ROSBAG V2.0\n")
    refused("identify", SOLO, tmp_path / "log.bag", *ff, match="ROS bags are read for fixed")
    # the floating-base options on a fixed base
    refused("identify", SOLO, good, "--model", "base", match="--model base: applies to a floating")
    refused("identify", SOLO, good, "--contact", "FL_LOWER_LEG", match="--contact: applies to")
    # a YAML robot with multi-DOF joints and no floating root
    yaml = random_multidof_tree_yaml(tmp_path / "md.yaml", n=5, seed=1)
    refused("identify", yaml, good, match="and no floating or planar root joint")


def test_a_contact_on_a_link_fixed_to_a_moving_one_says_which(tmp_path):
    """Solo12's FL_FOOT hangs from FL_LOWER_LEG by a fixed joint (the loader merges it): a
    contact named by the foot is refused, naming the link it is fixed to, by the contact
    Jacobian, the generated code and identify (--contact and a log's wrench columns)."""
    from mindyn import codegen
    from mindyn.identification.floating import contact_jacobian

    robot, model = pair(SOLO)
    hint = "'FL_FOOT' is fixed to the moving link 'FL_LOWER_LEG', merged into it"
    q, _, _ = random_state(robot, np.random.default_rng(1))
    with pytest.raises(mindyn.ArgumentError) as err:
        contact_jacobian(robot, q, "FL_FOOT")
    assert str(err.value).endswith(hint)
    with pytest.raises(mindyn.ArgumentError) as err:
        codegen.generate(robot, what="id", contacts=["FL_FOOT"])
    assert str(err.value).endswith(hint)
    with pytest.raises(mindyn.ArgumentError) as err:  # a link of no joint: no hint
        contact_jacobian(robot, q, "NO_SUCH_LINK")
    assert "fixed to" not in str(err.value)
    table, header, _ = simulate(robot, model, ["FL_LOWER_LEG"], np.random.default_rng(2), 30)
    log = write(tmp_path / "log.csv", table, header)
    ff = ["--root-joint", "floating"]
    refused("identify", SOLO, log, *ff, "--contact", "FL_FOOT", match=hint)
    foot = tmp_path / "foot.csv"
    foot.write_text(Path(log).read_text().replace("FL_LOWER_LEG.", "FL_FOOT.", 6))
    refused("identify", SOLO, foot, *ff, match=hint)


def test_base_and_info_take_a_root_joint_and_other_commands_refuse_it_in_one_line(tmp_path):
    urdf = str(random_tree_urdf(tmp_path / "tree.urdf", n=5, seed=7, moving=("revolute",)))
    robot, model = pair(urdf)
    doc = json.loads(cli("base", urdf, "--root-joint", "floating", "--format", "json"))
    # the count against the rank of Pinocchio's joint-torque regressor at random states
    data, rng = model.createData(), np.random.default_rng(2)
    stack = np.vstack(
        [pin.computeJointTorqueRegressor(model, data, *random_state(robot, rng)) for _ in range(30)]
    )
    assert doc["n_base"] == np.linalg.matrix_rank(stack) and doc["method"] == "projection"
    assert "the floating root taken as it is" in doc["method_reason"]
    info = cli("info", urdf, "--root-joint", "floating")
    assert f"nq {robot.nq} configuration and nv {robot.nv} velocity" in info
    assert robot.nq == robot.n + 6 and "floating" in info
    yaml = random_multidof_tree_yaml(tmp_path / "md.yaml", n=5, seed=1)
    table, header, _ = simulate(robot, model, [], rng, 20)
    log = write(tmp_path / "log.csv", table, header)
    cli("identify", urdf, log, "--root-joint", "floating", "--json", tmp_path / "id.json")
    ident = tmp_path / "id.json"
    recorded = json.loads(ident.read_text())  # the robot it was identified for: Pinocchio's
    assert recorded["joints"] == list(model.names[1:]), recorded["joints"]
    assert recorded["description"] == Path(urdf).name
    for argv in (
        ["excite", "-o", tmp_path / "e.csv"],
        ["simulate", "-o", tmp_path / "s.csv"],
        ["track"],
        ["ik", "--xyz", "0", "0", "1"],
        ["codegen", "-o", tmp_path / "x.c", "--lang", "c", "--what", "adaptive-pd"],
        ["detect", ident, log],
        ["predict", ident, log, "-o", tmp_path / "p.csv"],
    ):
        for robot_args in ([urdf, "--root-joint", "floating"], [yaml]):
            refused(argv[0], *robot_args, *argv[1:], match="takes revolute and prismatic joints")
    refused("demo", yaml, match="demo takes revolute and prismatic joints only")
    # export --mjcf writes a floating root as a free joint (test_mjcf_floating), not this tree's
    # other multi-DOF joints; a floating identification has base parameters only
    refused("export", yaml, ident, "--mjcf", tmp_path / "o.xml", match="which MJCF out does not")
    mjcf = ["--mjcf", tmp_path / "o.xml"]
    refused("export", urdf, "--root-joint", "floating", ident, *mjcf, match="'classical'")
    # export --urdf takes the robot (its root joint is not written: see test_export); this
    # identification has base parameters only
    out = tmp_path / "o.urdf"
    refused("export", urdf, "--root-joint", "floating", ident, "--urdf", out, match="'classical'")
    refused("base", "puma560", "--root-joint", "floating", match="--root-joint applies to URDF")


def test_the_json_records_its_model_and_codegen_params_refuses_another(tmp_path):
    """The JSON of a floating-base identification records its base set's regrouping and
    regressor columns (``model_check``), as a fixed-base one does: the record is that of the
    numerical method's base set of the robot, recomputed. ``codegen --params``, which takes its
    names and values, takes it for that robot and refuses (one line, naming the file) the same
    joint and link names with the last joint's origin moved 1 mm or with another gravity; a
    document without the record (earlier versions) has only its robot checked."""
    import re

    from mindyn.identification.document import model_record

    urdf = random_tree_urdf(tmp_path / "tree.urdf", n=5, seed=7, moving=("revolute",))
    robot, model = pair(str(urdf))
    table, header, _ = simulate(robot, model, [], np.random.default_rng(2), 40)
    log = write(tmp_path / "log.csv", table, header)
    ident = tmp_path / "id.json"
    cli("identify", urdf, log, "--root-joint", "floating", "--json", ident)
    doc = json.loads(ident.read_text())
    base = mindyn.base_parameters(robot, method="numerical")
    assert doc["base_method"] == "numerical"
    assert doc["model_check"] == json.loads(json.dumps(model_record(base)))
    assert len(doc["model_check"]["regrouping"]) == base.n == len(doc["names"])
    code = ["--root-joint", "floating", "--params", ident, "--lang", "c"]
    cli("codegen", urdf, *code, "-o", tmp_path / "same.c")
    header_text = (tmp_path / "same.h").read_text()
    assert f"parameter_values[{base.n}]" in header_text
    # the same names, another model: the last joint's origin 1 mm further along x
    text = urdf.read_text()
    last = [m for m in re.finditer(r'<joint name="[^"]+" type="revolute">\s*<origin xyz="', text)]
    at = last[-1].end()
    x, rest = text[at:].split(" ", 1)
    moved = tmp_path / "moved" / "tree.urdf"
    moved.parent.mkdir()
    moved.write_text(text[:at] + repr(float(x) + 1e-3) + " " + rest)
    err = refused("codegen", moved, *code, "-o", tmp_path / "m.c", match="another model")
    assert f"{ident}: parameters: identified on another model than robot 'tree5_7'" in err
    assert not (tmp_path / "m.c").exists()
    # the library's reader: another gravity
    with pytest.raises(mindyn.ModelError, match="identified on another model") as e:
        codegen.generate(robot.with_gravity([0.0, 0.0, -9.7]), params=ident, what="id")
    assert str(e.value).startswith(f"{ident}: parameters: ") and "\n" not in str(e.value)
    codegen.generate(robot, params=ident, what="id")
    # a document of earlier versions: the robot is checked, the model is not
    old = tmp_path / "old.json"
    old.write_text(json.dumps({k: v for k, v in doc.items() if k != "model_check"}))
    cli("codegen", moved, "--root-joint", "floating", "--params", old, "--lang", "c",
        "-o", tmp_path / "old.c")  # fmt: skip
    refused("codegen", SOLO, "--root-joint", "floating", "--params", old, "--lang", "c",
            "-o", tmp_path / "solo.c", match="identified for robot 'tree5_7'")  # fmt: skip


def test_the_default_method_s_reason_names_the_command_s_flags():
    """G1 on a free-flyer: the projection method would form more terms than the default's
    budget, so ``mindyn base`` runs the recursive method and says how to force the projection
    method by the command's flag, not by the library's keyword (``method='projection'``)."""
    g1 = FLOATING["g1"]
    text = cli("base", g1, "--root-joint", "floating")
    line = next(s for s in text.splitlines() if s.strip().startswith("method"))
    assert line.split()[1] == "recursive:" and "would form up to" in line
    assert "--method projection runs it" in line and "method=" not in line
    doc = json.loads(cli("base", g1, "--root-joint", "floating", "--format", "json"))
    assert "--method projection" in doc["method_reason"] and "method=" not in doc["method_reason"]


@pytest.mark.parametrize("root", ["floating", "planar"])
def test_info_says_how_the_root_joint_s_configuration_is_written(tmp_path, root):
    """A free-flyer's configuration holds a quaternion x, y, z, w; a planar joint's its angle's
    cos, sin and no quaternion (Pinocchio's JointModelPlanar: x, y, cos, sin). The joint table
    gives a planar joint's normal as its axis and a free-flyer none."""
    urdf = str(random_tree_urdf(tmp_path / "tree.urdf", n=4, seed=3, moving=("revolute",)))
    robot, model = pair(urdf, root)
    assert robot.nq == model.nq
    state = next(s for s in cli("info", urdf, "--root-joint", root).splitlines() if "nq" in s)
    assert f"nq {model.nq} configuration and nv {model.nv} velocity" in state
    assert ("quaternion" in state) == (root == "floating")
    assert ("cos, sin" in state) == (root == "planar")
    # a free-flyer has no axis (it showed the default z axis); a planar joint its plane's normal
    text = cli("info", urdf, "--root-joint", root)
    row = next(s.split() for s in text.splitlines() if s.split()[:2] == ["1", "root_joint"])
    axis = row[row.index(root) + 1]  # the column after the type
    assert axis == ("-" if root == "floating" else "["), row
