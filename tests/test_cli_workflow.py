"""The command line's chain from a log to generated code, and the logs it writes.

- ``codegen --params`` with the JSON ``identify --json`` wrote (CLI end to end): the parameters
  the identification pruned are taken as zero, the output counts them, and the compiled C gives
  the torques of the classical Newton-Euler recursion for a classical vector with the same base
  parameter values.
- ``simulate --controller pd -o``: the closed-loop log, checked against an independent
  integration of the forward dynamics from each logged state under the logged torque.
- CSV torque columns that say their unit (``tau1[permille]``), against the drive table.
- The demo prints the operation counts of the generated code once.
"""

from __future__ import annotations

import ctypes
import json
import shutil
import subprocess

import mindyn
import numpy as np
import pytest
from conftest import cli
from mindyn.cli import main
from mindyn.identification.data import DataError, read_csv, write_csv
from scipy.integrate import solve_ivp

GCC = shutil.which("gcc")


@pytest.mark.skipif(GCC is None, reason="gcc is needed to compile the generated C")
def test_codegen_takes_identify_json_with_pruned_parameters_as_zero(tmp_path):
    robot_name = "zcr07s"
    traj, data, ident = tmp_path / "traj.csv", tmp_path / "data.csv", tmp_path / "id.json"
    flags = ["--rotor", "--friction"]
    cli("excite", robot_name, *flags, "--starts", 1, "--maxiter", 20, "--quiet", "-o", traj)
    cli(
        "simulate",
        robot_name,
        "--trajectory",
        traj.with_suffix(".json"),
        *flags,
        "--torque-noise",
        "2%",
        "-o",
        data,
    )
    cli("identify", robot_name, data, *flags, "--json", ident)
    doc = json.loads(ident.read_text())
    # the same log in per mille of rated torque, the header saying so: identify reads the unit
    # from the header and finds the same parameters (the CSV holds 12 significant digits)
    permille, ident2 = tmp_path / "permille.csv", tmp_path / "id2.json"
    cli("simulate", robot_name, "--trajectory", traj.with_suffix(".json"), *flags,
        "--torque-noise", "2%", "--torque-unit", "permille", "-o", permille)  # fmt: skip
    assert "tau1[permille]" in permille.read_text().splitlines()[0]
    out = cli("identify", robot_name, permille, *flags, "--json", ident2)
    assert "torques converted from permille" in out
    doc2 = json.loads(ident2.read_text())
    assert doc2["names"] == doc["names"]
    assert np.allclose(doc2["values"], doc["values"], rtol=1e-7, atol=1e-9)
    pruned = [r["name"] for r in doc["removed"]]
    assert pruned, "the test needs an identification that pruned parameters"

    out = cli(
        "codegen", robot_name, "--lang", "c", *flags, "--params", ident, "--numeric", "-o",
        tmp_path / "dyn",
    )  # fmt: skip
    assert f"{len(pruned)} pruned in identification" in out
    assert "taken as zero: " + ", ".join(sorted(pruned, key=doc["base_names"].index)) in out
    # without --rotor --friction: the terms the JSON was identified with, the same code
    out = cli("codegen", robot_name, "--lang", "c", "--params", ident, "--numeric", "-o",
              tmp_path / "dyn2")  # fmt: skip
    assert f"--rotor, --friction: as identified in {ident}" in out
    same = (tmp_path / "dyn2.c").read_text().replace("dyn2.h", "dyn.h")
    assert same == (tmp_path / "dyn.c").read_text()

    # the base-parameter values as the JSON gives them, the pruned ones zero
    robot = mindyn.load(robot_name)
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    assert base.names == doc["base_names"]
    given = dict(zip(doc["names"], doc["values"]))
    p_b = np.array([given.get(k, 0.0) if k not in pruned else 0.0 for k in base.names])
    assert set(given) | set(pruned) == set(base.names)
    assert np.allclose(p_b, doc["base_values"], rtol=0, atol=0)  # identify's own full vector
    # a classical vector with these base values (minimum norm; Y has full row rank)
    pi = np.linalg.pinv(base.Y) @ p_b
    assert np.allclose(base.Y @ pi, p_b, rtol=0, atol=1e-10 * np.abs(p_b).max())

    so = tmp_path / "libdyn.so"
    cmd = [GCC, "-std=c99", "-O1", "-shared", "-fPIC", "-o", so, tmp_path / "dyn.c", "-lm"]
    res = subprocess.run([str(c) for c in cmd], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    lib = ctypes.CDLL(str(so))
    dbl = ctypes.POINTER(ctypes.c_double)
    ptr = lambda a: a.ctypes.data_as(dbl)  # noqa: E731
    rng = np.random.default_rng(7)
    n = robot.n
    for _ in range(20):
        q, dq, ddq = rng.uniform(-2, 2, (3, n))
        tau, g = np.zeros(n), np.zeros(n)
        lib.zcr07s_inverse_dynamics(ptr(q), ptr(dq), ptr(ddq), ptr(tau))
        lib.zcr07s_gravity(ptr(q), ptr(g))
        ref = robot.inverse_dynamics(q, dq, ddq, pi)
        ref_g = robot.gravity_torque(q, pi[np.arange(pi.size) % 13 < 10])
        # two exact recursions in double precision: round-off ~1e-13 of the torque scale
        scale = max(1.0, np.abs(ref).max())
        assert np.allclose(tau, ref, rtol=0, atol=1e-9 * scale)
        assert np.allclose(g, ref_g, rtol=0, atol=1e-9 * scale)


def test_codegen_params_errors_name_the_file(tmp_path, capsys):
    ident = tmp_path / "id.json"
    base = mindyn.base_parameters(mindyn.load("planar2"))
    names = list(base.names)
    doc = {"robot": "planar2", "rotor": False, "friction": False, "names": names[1:],
           "values": [1.0] * (len(names) - 1), "removed": []}  # fmt: skip
    ident.write_text(json.dumps(doc))
    argv = ["codegen", "planar2", "--lang", "c", "--params", str(ident), "-o", str(tmp_path / "x")]
    assert main(argv) == 2
    assert f"{ident}: missing parameter(s) {names[0]}" in capsys.readouterr().err
    doc["removed"] = [{"name": names[0], "rsd": 80.0}]
    ident.write_text(json.dumps(doc))
    assert main(argv) == 0
    assert "1 pruned in identification" in capsys.readouterr().out
    assert main([*argv[:4], "--rotor", *argv[4:]]) == 2
    assert "generate with the same --rotor, --friction" in capsys.readouterr().err
    assert main(["codegen", "planar3", *argv[2:]]) == 2
    assert "identified for robot 'planar2', not 'planar3'" in capsys.readouterr().err


def test_simulate_closed_loop_writes_a_log_that_follows_the_dynamics(tmp_path):
    log = tmp_path / "pd.csv"
    out = cli("simulate", "planar2", "--controller", "pd", "--duration", 0.4, "-o", log)
    assert f"wrote {log}" in out
    robot = mindyn.load("planar2")
    d = read_csv(log, robot, filter="none")
    assert d.m == 101 and np.allclose(np.diff(d.t), 0.004, rtol=0, atol=1e-12)
    truth = json.loads(log.with_name("pd.truth.json").read_text())
    p = np.array(truth["values"])
    assert truth["names"] == robot.parameter_names(rotor=True, friction=True)

    # from each logged state, the logged torque held over one period (what the controller
    # applies) must lead to the next logged state: scipy's RK45 at rtol 1e-10 against the
    # simulator's RK4 (4 steps of 1 ms: error ~ (1e-3)^5 * derivatives ~ 1e-12 rad)
    def f(_, x, tau):
        return np.concatenate([x[2:], robot.forward_dynamics(x[:2], x[2:], tau, p)])

    assert np.abs(d.tau).max() > 0.1  # the controller does act
    for k in range(0, d.m - 1, 9):
        x0 = np.concatenate([d.q[k], d.dq[k]])
        sol = solve_ivp(f, (0, 0.004), x0, args=(d.tau[k],), rtol=1e-10, atol=1e-12)
        # the CSV holds 12 significant digits: 1e-9 covers them and the integrators
        assert np.allclose(sol.y[:2, -1], d.q[k + 1], rtol=0, atol=1e-9)
        assert np.allclose(sol.y[2:, -1], d.dq[k + 1], rtol=0, atol=1e-8)


def test_torque_unit_in_the_header(tmp_path):
    robot = mindyn.load("zcr07s")
    rng = np.random.default_rng(1)
    t = np.arange(50) * 0.004
    q, tau = rng.normal(size=(2, 50, 6))
    p = write_csv(tmp_path / "p.csv", t, q, tau, torque_unit="permille")
    assert p.read_text().splitlines()[0].endswith(",tau6[permille]")
    scale = robot.drives["rated_torque"] * robot.drives["gear_ratio"] / 1000.0
    for unit in (None, "permille"):
        d = read_csv(p, robot, torque_unit=unit, filter="none")
        assert np.allclose(d.tau, tau * scale, rtol=1e-11, atol=0)  # 12 digits written
    with pytest.raises(DataError, match="header gives the torques in 'permille'.*'Nm'"):
        read_csv(p, robot, torque_unit="Nm")
    text = p.read_text()
    (tmp_path / "mixed.csv").write_text(text.replace("tau6[permille]", "tau6", 1))
    with pytest.raises(DataError, match="mixed.csv: the torque columns say different units"):
        read_csv(tmp_path / "mixed.csv", robot)
    (tmp_path / "kilo.csv").write_text(text.replace("[permille]", "[kNm]"))
    with pytest.raises(DataError, match="kilo.csv: unknown torque unit 'kNm'"):
        read_csv(tmp_path / "kilo.csv", robot)
    # a header without a unit: N m, as before
    d = read_csv(write_csv(tmp_path / "n.csv", t, q, tau), robot, filter="none")
    assert np.allclose(d.tau, tau, rtol=1e-11, atol=0)


def test_demo_prints_the_operation_counts_once(tmp_path, capsys):
    from mindyn.cli.demo import _codegen

    _codegen("planar2", tmp_path)
    out = capsys.readouterr().out
    assert (tmp_path / "inverse_dynamics.c").is_file()
    assert (tmp_path / "inverse_dynamics.st").is_file()
    assert out.count("inverse_dynamics ") == 1, out
    assert "C and Structured Text alike" in out


@pytest.mark.skipif(GCC is None, reason="gcc is needed to compile the generated C")
def test_codegen_takes_the_consistent_estimate_of_identify_json(tmp_path):
    """codegen --params ID.json --consistent: the compiled C gives the torques of the
    consistent estimate, which identify --urdf writes as a description: Pinocchio's rnea on
    that URDF plus the motors' rotor inertia and friction of its sidecar, by hand through the
    transmissions (a gear and a differential). Without --consistent the C is the unconstrained
    estimate's, and the output says the file holds a consistent one."""
    import pinocchio as pin
    import yaml
    from test_formulas import GEARED_URDF

    urdf, log, ident = tmp_path / "geared.urdf", tmp_path / "log.csv", tmp_path / "id.json"
    urdf.write_text(GEARED_URDF)
    flags = ["--rotor", "--friction"]
    cli("simulate", urdf, "--mode", "inverse", "--duration", "8", "--torque-noise", "2%", "-o", log)
    out_urdf = tmp_path / "identified.urdf"
    cli("identify", urdf, log, *flags, "--consistent", "--json", ident, "--urdf", out_urdf)
    model = pin.buildModelFromUrdf(str(out_urdf))
    data = model.createData()
    rows = yaml.safe_load(out_urdf.with_name("identified.joints.yaml").read_text())["joints"]
    Ia, Fv, Fc = (np.array([r.get(k, 0.0) for r in rows]) for k in ("Ia", "Fv", "Fc"))
    T = mindyn.load(urdf).transmission.T
    libs = {}
    for extra in ([], ["--consistent"]):
        name = f"dyn{len(extra)}"
        said = cli("codegen", urdf, "--lang", "c", *flags, "--params", ident, *extra, "--numeric",
                   "--name", name, "-o", tmp_path / name)  # fmt: skip
        words = "consistent estimate of" if extra else "the file's consistent estimate: --consist"
        assert words in said, said
        so = tmp_path / f"lib{name}.so"
        cmd = [GCC, "-std=c99", "-O1", "-shared", "-fPIC", "-o", so, tmp_path / f"{name}.c"]
        res = subprocess.run([str(c) for c in [*cmd, "-lm"]], capture_output=True, text=True)
        assert res.returncode == 0, res.stderr
        libs[len(extra)] = getattr(ctypes.CDLL(str(so)), f"{name}_inverse_dynamics")
    dbl = ctypes.POINTER(ctypes.c_double)
    ptr = lambda a: a.ctypes.data_as(dbl)  # noqa: E731
    rng = np.random.default_rng(5)
    gap = {0: 0.0, 1: 0.0}
    for _ in range(10):
        q, dq, ddq = rng.uniform(-2, 2, (3, 3))
        v = T @ dq
        ref = pin.rnea(model, data, q, dq, ddq) + T.T @ (Ia * (T @ ddq) + Fv * v + Fc * np.sign(v))
        for k, f in libs.items():
            tau = np.zeros(3)
            f(ptr(q), ptr(dq), ptr(ddq), ptr(tau))
            gap[k] = max(gap[k], float(np.max(np.abs(tau - ref)) / np.max(np.abs(ref))))
    assert gap[1] < 1e-9 < 1e-4 < gap[0], gap
