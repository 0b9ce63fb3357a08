"""A robot loaded with the joint-terms file that identify and export write beside a URDF
(``mindyn.load(path, joint_terms=FILE)``, ``--joint-terms FILE``): its rotor inertia, friction
and torque offsets, which URDF has no place for, are the file's. References: Pinocchio's rnea
on the written URDF plus the terms of the file written out by hand (through the transmission T
on the motor side), and the code generated from the identification JSON."""

from __future__ import annotations

import contextlib
import ctypes
import io
import shutil
import subprocess

import mindyn
import numpy as np
import pytest
import yaml
from conftest import cli
from coupled_arms import coupled_wrist_urdf, motor_terms, motor_values
from mindyn.cli import main
from mindyn.export import write_urdf
from test_formulas import GEARED_URDF

GCC = shutil.which("gcc")
FLAGS = ("--rotor", "--friction", "--offset")


@pytest.fixture(scope="module")
def identified(tmp_path_factory):
    """The geared arm (a gear on joint 1, a differential on joints 2 and 3), a log simulated
    with motor rotor inertia and friction from a joint-terms file written here, and ``identify
    --rotor --friction --offset --consistent --urdf OUT.urdf`` on it, per drive side: {side:
    (source, OUT.urdf, sidecar, ID.json)}."""
    tmp = tmp_path_factory.mktemp("joint_terms")
    urdf, log, true = tmp / "geared.urdf", tmp / "log.csv", tmp / "true.joints.yaml"
    urdf.write_text(GEARED_URDF)
    Ia, Fv, Fc = motor_values(3, seed=1)
    rows = [
        {
            "name": f"j{k + 1}",
            "motor": f"m{k + 1}",
            "Ia": float(Ia[k]),
            "Fv": float(Fv[k]),
            "Fc": float(Fc[k]),
        }
        for k in range(3)
    ]
    true.write_text(yaml.safe_dump({"drive_side": "motor", "joints": rows}))
    said = cli("simulate", urdf, "--joint-terms", true, "--mode", "inverse", "--duration", "6",
               "--rotor", "--friction", "--torque-noise", "2%", "-o", log)  # fmt: skip
    assert f"joint terms from {true}: Ia, Fv, Fc of the 3 motors" in said, said
    out = {}
    for side in ("motor", "joint"):
        ident, out_urdf = tmp / f"id_{side}.json", tmp / f"out_{side}.urdf"
        cli("identify", urdf, log, *FLAGS, "--drive-side", side, "--consistent", "--json",
            ident, "--urdf", out_urdf)  # fmt: skip
        out[side] = (urdf, out_urdf, out_urdf.with_name(f"out_{side}.joints.yaml"), ident)
    return out


def by_hand(urdf, sidecar, T, q, dq, ddq):
    """Pinocchio's rnea on ``urdf`` plus the sidecar's terms written out: on the motor side
    T^T (Ia T ddq + Fv T dq + Fc sign(T dq)), on the joint side Ia ddq + Fv dq + Fc sign(dq),
    and Off."""
    import pinocchio as pin

    model = pin.buildModelFromUrdf(str(urdf))
    doc = yaml.safe_load(sidecar.read_text())
    rows = doc["joints"]
    Ia, Fv, Fc, Off = (np.array([r[k] for r in rows]) for k in ("Ia", "Fv", "Fc", "Off"))
    if doc.get("drive_side") != "motor":
        T = np.eye(len(rows))
    else:
        assert [r["motor"] for r in rows] == ["m1", "m2", "m3"]  # rows in the order of T
    tau = pin.rnea(model, model.createData(), q, dq, ddq)
    return tau + motor_terms(T, Ia, Fv, Fc, dq, ddq) + Off


@pytest.mark.parametrize("side", ["motor", "joint"])
def test_the_identified_urdf_with_its_sidecar_gives_rnea_plus_the_terms(identified, side):
    """identify --urdf OUT.urdf, then OUT.urdf loaded with OUT.joints.yaml: the inverse
    dynamics of its own parameters (rotor inertia, friction, offsets included) equal Pinocchio's
    rnea on OUT.urdf plus the sidecar's terms by hand (the differential's motors turn with two
    joints each: no URDF <dynamics> carries their terms). Without the file they do not."""
    source, out_urdf, sidecar, _ = identified[side]
    robot = mindyn.load(out_urdf, joint_terms=sidecar)
    assert robot.drive_side == side
    T = mindyn.load(source).transmission.T
    p = robot.parameters(rotor=True, friction=True, offset=True)
    bare = mindyn.load(out_urdf).parameters(rotor=True, friction=True, offset=True)
    rng = np.random.default_rng(7)
    for _ in range(8):
        q, dq, ddq = rng.uniform(-2, 2, (3, 3))
        ref = by_hand(out_urdf, sidecar, T, q, dq, ddq)
        tau = robot.regressor(q, dq, ddq, rotor=True, friction=True, offset=True) @ p
        np.testing.assert_allclose(tau, ref, rtol=1e-9, atol=1e-9 * np.abs(ref).max())
        without = robot.regressor(q, dq, ddq, rotor=True, friction=True, offset=True) @ bare
        assert np.abs(without - ref).max() > 1e-6 * np.abs(ref).max()


def test_coupled_motors_of_a_written_urdf_come_back_exactly(tmp_path):
    """write_urdf of motor-side values on a wrist whose last two motors are coupled: loaded with
    its sidecar, the motor slots hold the written values exactly, the directly driven joints
    carry r^2 Ia, r^2 Fv, |r| Fc, and the inverse dynamics equal rnea + T^T(...) by hand."""
    import pinocchio as pin

    path, T = coupled_wrist_urdf(tmp_path / "w.urdf")
    robot = mindyn.load(path)
    Ia, Fv, Fc = motor_values(robot.n, seed=4)
    p = robot.parameters(rotor=True, friction=True).reshape(robot.n, 13).copy()
    p[:, 10], p[:, 11], p[:, 12] = Ia, Fv, Fc
    res = write_urdf(robot, p.reshape(-1), tmp_path / "out.urdf")
    back = mindyn.load(res.path, joint_terms=res.sidecar)
    slots = back.parameters(rotor=True, friction=True).reshape(robot.n, 13)
    np.testing.assert_array_equal(slots[:, 10:], np.column_stack([Ia, Fv, Fc]))
    r = np.diag(T)[:4]
    np.testing.assert_allclose(back.rotor_inertia[:4], r**2 * Ia[:4], rtol=1e-15)
    np.testing.assert_allclose(back.coulomb[:4], np.abs(r) * Fc[:4], rtol=1e-15)
    model = pin.buildModelFromUrdf(str(res.path))
    rng = np.random.default_rng(2)
    q, dq, ddq = rng.uniform(-1.5, 1.5, (3, robot.n))
    ref = pin.rnea(model, model.createData(), q, dq, ddq) + motor_terms(T, Ia, Fv, Fc, dq, ddq)
    tau = back.inverse_dynamics(q, dq, ddq, back.parameters(rotor=True, friction=True))
    np.testing.assert_allclose(tau, ref, rtol=1e-9, atol=1e-12)


def _compiled(tmp_path, name, *argv):
    said = cli("codegen", *argv, "--lang", "c", *FLAGS, "--numeric", "--name", name, "-o",
               tmp_path / name)  # fmt: skip
    so = tmp_path / f"lib{name}.so"
    cmd = [GCC, "-std=c99", "-O1", "-shared", "-fPIC", "-o", so, tmp_path / f"{name}.c", "-lm"]
    res = subprocess.run([str(c) for c in cmd], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    return getattr(ctypes.CDLL(str(so)), f"{name}_inverse_dynamics"), said


@pytest.mark.skipif(GCC is None, reason="gcc is needed to compile the generated C")
@pytest.mark.parametrize("side", ["motor", "joint"])
def test_codegen_of_the_urdf_and_its_sidecar_equals_codegen_of_the_json(identified, tmp_path, side):
    """codegen OUT.urdf --joint-terms OUT.joints.yaml --rotor --friction --offset --numeric
    computes the torques of codegen ROBOT --params ID.json --consistent (the same values
    baked in) and of rnea + the sidecar's terms; the output says where the terms came from."""
    source, out_urdf, sidecar, ident = identified[side]
    from_file, said = _compiled(tmp_path, "viafile", out_urdf, "--joint-terms", sidecar)
    assert f"joint terms from {sidecar}: Ia, Fv, Fc" in said, said
    assert "torque offsets Off used (--offset)" in said, said
    from_json, _ = _compiled(
        tmp_path, "viajson", source, "--params", ident, "--consistent", "--drive-side", side
    )
    T = mindyn.load(source).transmission.T
    dbl = ctypes.POINTER(ctypes.c_double)
    ptr = lambda a: a.ctypes.data_as(dbl)  # noqa: E731
    rng = np.random.default_rng(11)
    for _ in range(8):
        q, dq, ddq = rng.uniform(-2, 2, (3, 3))
        a, b = np.zeros(3), np.zeros(3)
        from_file(ptr(q), ptr(dq), ptr(ddq), ptr(a))
        from_json(ptr(q), ptr(dq), ptr(ddq), ptr(b))
        scale = np.abs(b).max()
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-9 * scale)
        ref = by_hand(out_urdf, sidecar, T, q, dq, ddq)
        np.testing.assert_allclose(a, ref, rtol=1e-8, atol=1e-8 * scale)


def _run(*argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main([str(a) for a in argv])
    return rc, out.getvalue(), err.getvalue()


def _edited(doc, edit):
    doc = yaml.safe_load(yaml.safe_dump(doc))
    rows = doc["joints"]
    kind, *what = edit
    if kind == "set":
        row, key, value = what
        rows[row][key] = value
    elif kind == "drop":
        (key,) = what
        if key == "row":
            rows.pop()
        else:
            rows[1].pop(key)
    elif kind == "top":
        key, value = what
        doc[key] = value
    return doc


MALFORMED = [
    (("set", 1, "name", "elbow"), "joint 2: 'name' is 'elbow', not a joint of robot"),
    (("drop", "row"), "2 joints; robot 'geared3' has 3 (missing: 'j3')"),
    (("set", 0, "Ia", -1e-4), "joint 1 ('j1'): 'Ia' is -0.0001; rotor inertia is >= 0"),
    (("set", 2, "Fc", -0.5), "joint 3 ('j3'): 'Fc' is -0.5; Coulomb friction is >= 0"),
    (("set", 0, "Fv", "x"), "joint 1: 'Fv' is 'x'; expected a number"),
    (("set", 0, "Fv", float("nan")), "joint 1: 'Fv' is nan; expected a finite number"),
    (("drop", "Fc"), "joint 2 ('j2') has no 'Fc', unlike joint 1"),
    (("set", 1, "damping", 0.1), "joint 2: unknown entry 'damping'"),
    (("set", 2, "motor", "m9"), "joint 3 ('j3'): 'motor' is 'm9', not a motor of robot"),
    (("set", 2, "motor", "m2"), "joint 3 ('j3'): motor 'm2' is named twice"),
    (("set", 0, "index", 2), "joint 1 ('j1'): 'index' is 2; robot 'geared3' numbers it 1"),
    (("top", "drive_side", "motors"), "'drive_side' is 'motors'; expected 'motor' or 'joint'"),
    (("top", "friction_model", "dahl"), "'friction_model' is 'dahl'; expected one of coulomb"),
    (("top", "friction_model", "stribeck"), "has a third term, 'Fs', which the joints lack"),
    (("top", "friction_model", "smooth"), "joint 1 ('j1') has no 'velocity', which the friction"),
    (("set", 0, "velocity", 0.1), "joint 1 ('j1') has a 'velocity', which the friction model"),
    (("set", 0, "velocity", -1), "joint 1: 'velocity' is -1; expected a positive number"),
]


@pytest.mark.parametrize("edit, needle", MALFORMED)
def test_a_malformed_sidecar_is_refused_in_one_line_naming_file_and_entry(
    identified, tmp_path, edit, needle
):
    """A sidecar that does not fit the robot: the library raises a ModelError, the command
    exits 1 with one line, both naming the file and the entry."""
    _, out_urdf, sidecar, _ = identified["motor"]
    bad = tmp_path / "bad.joints.yaml"
    bad.write_text(yaml.safe_dump(_edited(yaml.safe_load(sidecar.read_text()), edit)))
    with pytest.raises(mindyn.ModelError) as e:
        mindyn.load(out_urdf, joint_terms=bad)
    assert str(e.value).startswith(f"{bad}: ") and needle in str(e.value), e.value
    for command in (["info"], ["base"], ["simulate", "-o", tmp_path / "log.csv"]):
        rc, out, err = _run(command[0], out_urdf, "--joint-terms", bad, *command[1:])
        assert rc != 0 and out == "", out
        lines = err.strip().splitlines()
        assert len(lines) == 1 and str(bad) in lines[0] and needle in lines[0], err


def test_a_motor_side_file_on_a_robot_without_transmissions_and_a_contradicting_drive_side(
    identified, tmp_path
):
    """A motor-side sidecar needs the robot's transmissions; --drive-side against the file's
    drive side is refused rather than re-reading the values on the other side."""
    _, out_urdf, sidecar, _ = identified["motor"]
    plain = tmp_path / "plain.urdf"
    text = out_urdf.read_text()
    plain.write_text(text[: text.index("<transmission")] + "</robot>\n")
    with pytest.raises(mindyn.ModelError, match="'drive_side' is 'motor'.*declares no transm"):
        mindyn.load(plain, joint_terms=sidecar)
    rc, _, err = _run(
        "simulate", out_urdf, "--joint-terms", sidecar, "--drive-side", "joint", "-o",
        tmp_path / "log.csv",
    )  # fmt: skip
    assert rc != 0 and "--drive-side joint: the rotor inertia and friction of" in err, err
    assert len(err.strip().splitlines()) == 1, err


def test_every_command_says_what_it_takes_from_the_file(identified):
    """The line of --joint-terms: the terms and their side; the offsets used with --offset, not
    used without it, shown by info (with the file's values); nothing used where the values are
    an identification JSON's."""
    _, out_urdf, sidecar, ident = identified["motor"]
    said = cli("info", out_urdf, "--joint-terms", sidecar)
    assert f"joint terms from {sidecar}: Ia, Fv, Fc of the 3 motors (its drive_side: " in said
    assert "torque offsets Off shown" in said, said
    rows = said.split("torque offsets per joint")[1].splitlines()[2:5]
    offsets = [row["Off"] for row in yaml.safe_load(sidecar.read_text())["joints"]]
    assert [float(r.split()[2]) for r in rows] == pytest.approx(offsets, rel=1e-3, abs=1e-12)
    said = cli("base", out_urdf, "--joint-terms", sidecar, "--rotor", "--friction")
    assert "torque offsets Off not used (without --offset)" in said, said
    said = cli("base", out_urdf, "--joint-terms", sidecar, *FLAGS)
    assert "torque offsets Off used (--offset)" in said, said
    rc, out, err = _run("base", out_urdf, "--joint-terms", sidecar, "--format", "json")
    assert rc == 0 and out.lstrip().startswith("{") and "joint terms from" in err, (out, err)
    said = cli("export", out_urdf, ident, "--joint-terms", sidecar, "--urdf",
               sidecar.with_name("again.urdf"))  # fmt: skip
    assert f"joint terms of {sidecar}: not used (the parameter values" in said, said


def test_the_offsets_of_a_robot_reach_the_base_dynamics_and_its_code():
    """A robot with torque offsets (with_joint_terms): the base dynamics with offsets add them
    to its inverse dynamics and not to the gravity torque, by default values (before, the
    default values had zero offsets); the robot it came from is unchanged."""
    from mindyn.codegen import BaseDynamics

    plain = mindyn.load("puma560")
    off = np.array([0.5, -0.25, 0.125, 1.0, -2.0, 0.0625])
    robot = plain.with_joint_terms(offset=off)
    assert (plain.torque_offset == 0).all() and (robot.torque_offset == off).all()
    dyn = BaseDynamics(mindyn.base_parameters(robot, offset=True))
    rng = np.random.default_rng(3)
    q, dq, ddq = rng.uniform(-1, 1, (3, 6))
    ref = plain.inverse_dynamics(q, dq, ddq)
    np.testing.assert_allclose(dyn.inverse_dynamics(q, dq, ddq), ref + off, atol=1e-10)
    np.testing.assert_allclose(dyn.gravity(q), plain.gravity_torque(q), atol=1e-10)
    with pytest.raises(mindyn.ArgumentError, match="coulomb.*entry 2; rotor inertia and fric"):
        plain.with_joint_terms(coulomb=[0, -1, 0, 0, 0, 0])


def _friction_by_hand(kind, v, Fv, Fc, third, w):
    """The friction models' torques written out (the manual's formulas), per slot velocity v."""
    s = np.sign(v)
    f = Fv * v + (Fc * np.tanh(v / w) if kind == "smooth" else Fc * s)
    if kind == "asymmetric":
        f += third * np.abs(s)
    if kind == "stribeck":
        f += third * s * np.exp(-((v / w) ** 2))
    return f


@pytest.mark.parametrize("side", ["motor", "joint"])
@pytest.mark.parametrize("kind", ["smooth", "asymmetric", "stribeck"])
def test_a_friction_model_goes_into_the_sidecar_and_comes_back(tmp_path, kind, side):
    """write_urdf of a robot with the smooth, asymmetric or Stribeck friction model: the URDF's
    <dynamics> holds Fv and Fc, the sidecar the model, its third term and velocities (a note
    says so); loaded with the sidecar, the robot has the model and the values written, and its
    inverse dynamics equal Pinocchio's rnea plus T^T (Ia T ddq + f(T dq)) with the model's
    formula written out (T the identity on the joint side), the third term of motor 6, which
    turns with joints 5 and 6, too."""
    import pinocchio as pin

    path, T = coupled_wrist_urdf(tmp_path / "w.urdf")
    robot = mindyn.load(path).with_drive_side(side)
    n = robot.n
    rng = np.random.default_rng(5)
    w = rng.uniform(0.05, 0.5, n) if kind in ("smooth", "stribeck") else None
    robot = robot.with_friction_model(kind, velocity=w)
    c = 2 if kind == "smooth" else 3
    Ia, Fv, Fc = motor_values(n, seed=4)
    third = rng.uniform(0.2, 0.6, n) * Fc
    if side == "motor":
        assert np.count_nonzero(T[5]) == 2  # motor 6 turns with joints 5 and 6: its own third
    else:
        Ia, Fv, Fc = Ia * 900, Fv * 900, Fc * 30  # about the size they have on the joints
        third = third * 30
    p = robot.parameters(rotor=True, friction=True).reshape(n, 11 + c).copy()
    p[:, 10], p[:, 11], p[:, 12] = Ia, Fv, Fc
    if c == 3:
        p[:, 13] = third
    res = write_urdf(robot, p.reshape(-1), tmp_path / "out.urdf")
    assert any(f"friction model {kind}" in note and str(res.sidecar) in note for note in res.notes)
    back = mindyn.load(res.path, joint_terms=res.sidecar)
    assert back.friction_model["kind"] == kind and back.drive_side == side
    if w is not None:
        np.testing.assert_array_equal(back.friction_model["velocity"], w)
    np.testing.assert_allclose(
        back.parameters(rotor=True, friction=True).reshape(n, 11 + c)[:, 10:], p[:, 10:],
        rtol=1e-14, atol=0,
    )  # fmt: skip
    Tm = T if side == "motor" else np.eye(n)
    model = pin.buildModelFromUrdf(str(res.path))
    for q, dq, ddq in rng.uniform(-1.5, 1.5, (4, 3, n)):
        ref = pin.rnea(model, model.createData(), q, dq, ddq)
        ref += Tm.T @ (Ia * (Tm @ ddq) + _friction_by_hand(kind, Tm @ dq, Fv, Fc, third, w))
        tau = back.inverse_dynamics(q, dq, ddq, back.parameters(rotor=True, friction=True))
        np.testing.assert_allclose(tau, ref, rtol=1e-9, atol=1e-12)
    if side == "joint":  # info shows the model and its third term
        said = cli("info", res.path, "--joint-terms", res.sidecar)
        assert f"friction model {kind}: " in said, said
        if w is not None:
            assert " ".join(f"{v:.4g}" for v in w) in said, said
        if c == 3:
            head = next(x for x in said.splitlines() if x.startswith("link "))
            assert head.split()[-1] == ("Fa" if kind == "asymmetric" else "Fs"), head
    if side == "motor" and c == 3:  # info's motor table shows each motor's, m6's own too
        said = cli("info", res.path, "--joint-terms", res.sidecar).splitlines()
        head = next(x for x in said if x.startswith("#") and x.split()[-4:-1] == ["Ia", "Fv", "Fc"])
        assert head.split()[-1] == ("Fa" if kind == "asymmetric" else "Fs"), head
        for k in range(n):
            row = next(x for x in said[said.index(head) :] if x.startswith(f"m{k + 1} "))
            assert float(row.split()[-1]) == pytest.approx(third[k], rel=1e-3), row


def test_a_bare_off_key_is_named_as_the_boolean_yaml_reads(tmp_path):
    """YAML 1.1 reads a bare ``Off:`` as the boolean false: a hand-written file with it said
    "unknown entry 'False'"; now the error says why and how to write the key."""
    path = tmp_path / "planar2.joints.yaml"
    path.write_text("joints:\n  - {name: joint1, Off: 0.25}\n  - {name: joint2, Off: -1.5}\n")
    assert yaml.safe_load(path.read_text())["joints"][0] == {"name": "joint1", False: 0.25}
    with pytest.raises(mindyn.ModelError) as e:
        mindyn.load("planar2", joint_terms=path)
    assert str(e.value) == (
        f"{path}: joint 1: a key YAML reads as false: a bare Off, On, No or Yes is a boolean in "
        "YAML; write the torque offset's key quoted, 'Off':"
    )
    path.write_text(path.read_text().replace("Off:", "'Off':"))
    assert mindyn.load("planar2", joint_terms=path).torque_offset.tolist() == [0.25, -1.5]
