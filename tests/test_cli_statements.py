"""What the commands and functions state about the choices they made for the user, and the
inputs they refuse instead of taking silently, on inputs the other tests do not take: a
description with an effort limit on some joints only or a negative one, a tree given where a
chain is needed, reference files with odd cells or of another robot, options that do not apply
to the mode or function asked for, an optimiser that fails, a plant too stiff for RK4's step."""

from __future__ import annotations

import contextlib
import io
import json
import math

import mindyn
import numpy as np
import pinocchio as pin
import pytest
import yaml
from conftest import ROBOTS_DIR, pinocchio_model
from mindyn import cli

# a vertical two-link arm (joint 1's axis horizontal), an effort limit on joint 1 only
TWO_LINK = """\
name: half_limited
convention: mdh
angle_unit: deg
joints:
  - name: shoulder
    type: revolute
    alpha: 90
    d: 0
    theta: 0
    r: 0
    limits: {lower: -170, upper: 170, velocity: 3, effort: 50}
    inertial: {mass: 2.0, com: [0.2, 0, 0], inertia: {xx: 0.01, yy: 0.02, zz: 0.02}}
  - name: elbow
    type: revolute
    alpha: 0
    d: 0.4
    theta: 0
    r: 0
    limits: {lower: -150, upper: 150, velocity: 3}
    inertial: {mass: 1.0, com: [0.15, 0, 0], inertia: {xx: 0.005, yy: 0.01, zz: 0.01}}
"""


def run(argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main([str(a) for a in argv])
    return rc, out.getvalue(), err.getvalue()


def test_torque_noise_in_percent_states_what_it_is_taken_of(tmp_path):
    """`simulate --torque-noise 1%` on joints without an effort limit takes the peak torque
    along the reference: the output says so per joint, and the levels are 1 % of the effort
    limit and of the gravity torque that a resting reference needs (Pinocchio)."""
    (tmp_path / "arm.yaml").write_text(TWO_LINK)
    q = np.array([0.3, -0.5])
    rows = "\n".join(f"{t:g},{q[0]},{q[1]}" for t in np.linspace(0.0, 1.0, 11))
    (tmp_path / "rest.csv").write_text("t,q1,q2\n" + rows + "\n")
    rc, out, err = run(
        [
            "simulate",
            tmp_path / "arm.yaml",
            "--trajectory",
            tmp_path / "rest.csv",
            "--mode",
            "inverse",
            "--torque-noise",
            "1%",
            "-o",
            tmp_path / "log.csv",
        ]
    )
    assert rc == 0, err
    robot = mindyn.load(tmp_path / "arm.yaml")
    model = pinocchio_model(robot)
    g = pin.computeGeneralizedGravity(model, model.createData(), q)
    assert abs(g[1]) > 0.1  # the elbow holds a torque at rest
    truth = json.loads((tmp_path / "log.truth.json").read_text())
    sd = np.array(truth["simulation"]["noise"]["torque"])
    np.testing.assert_allclose(sd, [0.01 * 50.0, 0.01 * abs(g[1])], rtol=1e-9)
    (line,) = [s for s in out.splitlines() if "torque noise sd" in s]
    assert "1 % of the effort limit" in line, line
    assert "peak torque along the reference for joint(s) 2" in line, line


def _resting_arm(tmp_path, q, shoulder_effort, elbow_effort=None):
    """TWO_LINK with the effort limits given, and a reference CSV resting at ``q``."""
    text = TWO_LINK.replace("effort: 50}", f"effort: {shoulder_effort:g}}}")
    if elbow_effort is not None:
        text = text.replace("velocity: 3}", f"velocity: 3, effort: {elbow_effort:g}}}")
    (tmp_path / "arm.yaml").write_text(text)
    rows = "\n".join(f"{t:g},{float(q[0])!r},{float(q[1])!r}" for t in np.linspace(0.0, 1.0, 11))
    (tmp_path / "rest.csv").write_text("t,q1,q2\n" + rows + "\n")
    argv = ["simulate", tmp_path / "arm.yaml", "--trajectory", tmp_path / "rest.csv"]
    return argv + ["--mode", "inverse", "--torque-noise", "1%", "-o", tmp_path / "log.csv"]


@pytest.mark.parametrize(
    ("efforts", "placeholder"),
    [((1e6, 5.0), 0), ((50.0, 0.01), 1), ((1e6, 0.01), None)],
    ids=["far-above-every-peak", "far-below-its-peak", "both"],
)
def test_torque_noise_in_percent_of_a_placeholder_effort_limit_takes_the_peak(
    efforts, placeholder, tmp_path
):
    """An effort limit that the torques along the reference make no sense of (over 100 x the
    largest peak torque of any joint, or under 1/10 of the joint's own: the placeholders of
    Solo12 or Baxter's head) is not what `--torque-noise 1%` takes 1 % of: that joint takes its
    peak torque along the reference, here the gravity torque of a resting arm (Pinocchio), and
    the output names it as a placeholder."""
    q = np.array([0.3, -0.5])
    rc, out, err = run(_resting_arm(tmp_path, q, *efforts))
    assert rc == 0, err
    model = pinocchio_model(mindyn.load(tmp_path / "arm.yaml"))
    g = np.abs(pin.computeGeneralizedGravity(model, model.createData(), q))
    eff = np.array(efforts)
    wrong = (eff > 100 * g.max()) | (eff < 0.1 * g)  # the rule, on Pinocchio's torques
    expected = np.where(wrong, g, eff)
    assert wrong.tolist() == [placeholder in (0, None), placeholder in (1, None)]
    sd = np.array(
        json.loads((tmp_path / "log.truth.json").read_text())["simulation"]["noise"]["torque"]
    )
    np.testing.assert_allclose(sd, 0.01 * expected, rtol=1e-9)
    (line,) = [s for s in out.splitlines() if "torque noise sd" in s]
    assert "a placeholder" in line, line
    for j in [placeholder] if placeholder is not None else [0, 1]:
        assert f"joint(s) {j + 1} (" in line, line
    assert ("1 % of the effort limit" in line) == (placeholder is not None), line


def test_torque_noise_in_percent_on_baxter_keeps_the_arms_limits_and_not_the_heads():
    """Baxter's head pan has effort="50000" (a placeholder: its peak torque along the
    reference is far under 1 N m); its arm joints' limits (read from the URDF here) are real
    and kept along the default reference."""
    import xml.etree.ElementTree as ET

    urdf = ROBOTS_DIR / "baxter_description/urdf/baxter.urdf"
    robot = mindyn.load(urdf)
    joints = {j.get("name"): j for j in ET.parse(urdf).getroot().findall("joint")}
    eff = np.array([float(joints[n].find("limit").get("effort")) for n in robot.joint_names])
    assert eff[0] == 50000.0 and robot.joint_names[0] == "head_pan"
    from mindyn.control.simulation import SumOfSines, noise_from_spec

    ref = SumOfSines(robot, period=10.0, seed=0)  # the torques are the input here, not a result
    tau = robot.inverse_dynamics(*ref.evaluate(np.linspace(0.0, 10.0, 200)))
    sd = noise_from_spec("1%", robot, "torque", reference_torque=tau)
    np.testing.assert_allclose(sd[1:], 0.01 * eff[1:], rtol=1e-12)
    np.testing.assert_allclose(sd[0], 0.01 * np.abs(tau[:, 0]).max(), rtol=1e-12)
    assert sd[0] < 0.01  # not 500 N m


def test_torque_noise_in_percent_of_nothing_is_refused_naming_the_joint(tmp_path):
    """A joint with no effort limit and no torque along the reference (the elbow held upright)
    has nothing to take a percentage of: refused, saying to give the noise in N m."""
    q = np.array([0.3, np.pi / 2 - 0.3])
    argv = _resting_arm(tmp_path, q, 50.0)
    model = pinocchio_model(mindyn.load(tmp_path / "arm.yaml"))
    g = pin.computeGeneralizedGravity(model, model.createData(), q)
    assert abs(g[1]) < 1e-12 * abs(g[0])
    rc, out, err = run(argv)
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert "--torque-noise: 1% of nothing for joint(s) 2," in err, err
    assert "give the noise in N m" in err, err


def test_torque_noise_in_newton_metres_states_its_unit(tmp_path):
    rc, out, err = run(
        ["simulate", "planar2", "--mode", "inverse", "--torque-noise", "0.1", "-o", tmp_path]
    )
    assert rc == 0, err
    (line,) = [s for s in out.splitlines() if "torque noise sd" in s]
    assert line.split(":")[1].split() == ["0.1", "0.1", "[N", "m", "|", "N]"], line


def test_a_tree_refused_by_ik_names_the_tip_option_as_each_interface_spells_it():
    urdf = ROBOTS_DIR / "solo_description/robots/solo12.urdf"
    rc, _, err = run(["ik", urdf, "--xyz", "0.2", "0.1", "-0.2"])
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert "--tip <link>" in err and "mindyn.load(" not in err, err
    robot = mindyn.load(urdf)
    with pytest.raises(mindyn.ModelError, match="tip='<link>'"):
        mindyn.ik(robot, np.eye(4))


@pytest.mark.parametrize("cell", ["1_0", "0x1", "\u0661", "nan", "1e999"])
def test_a_trajectory_csv_cell_that_is_not_a_decimal_number_is_named(cell, tmp_path):
    """A reference CSV's cells follow a log's rule (ASCII decimals): Python's float() would read
    '1_0' as 10 and an Arabic-Indic one as 1, a silently different trajectory."""
    rows = ["t,q1,q2", "0,0,0", "0.25,0.05,0", f"0.5,{cell},0", "0.75,0.05,0", "1,0.1,0"]
    (tmp_path / "ref.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    rc, _, err = run(["simulate", "planar2", "--trajectory", tmp_path / "ref.csv", "-o", tmp_path])
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert "ref.csv, line 4, column q1" in err, err
    assert not (tmp_path / "planar2_simulate.csv").exists()


def test_a_trajectory_csv_that_is_not_utf8_is_one_line(tmp_path):
    (tmp_path / "ref.csv").write_bytes(b"t,q1,q2\n0,0,0\n0.25,0.05,0\n0.5,\xff,0\n1,0.1,0\n")
    rc, _, err = run(["simulate", "planar2", "--trajectory", tmp_path / "ref.csv", "-o", tmp_path])
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert "line 4: not UTF-8" in err and "defect" not in err, err


def test_a_trajectory_csv_of_decimals_is_followed(tmp_path):
    """The reference read back: at rest at its knots' end, the positions the file gives."""
    rows = ["t,q1,q2"] + [f"{t:g},{0.1 * t:g},{-0.2 * t:g}" for t in (0, 0.25, 0.5, 0.75, 1)]
    (tmp_path / "ref.csv").write_text("\n".join(rows) + "\n")
    rc, _, err = run(
        ["simulate", "planar2", "--trajectory", tmp_path / "ref.csv", "--mode", "inverse",
         "-o", tmp_path / "log.csv"]
    )  # fmt: skip
    assert rc == 0, err
    log = np.loadtxt(tmp_path / "log.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(log[:, 1:3], np.c_[0.1 * log[:, 0], -0.2 * log[:, 0]], atol=1e-12)


def test_a_wrong_options_object_is_named_with_its_class():
    from mindyn.identification import run

    robot = mindyn.load("planar2")
    expected = r"options is a dict; expected an IdentifyOptions$"
    with pytest.raises(mindyn.ArgumentError, match=expected):
        run(robot, [], options={"rotor": True})


def test_excite_says_when_the_optimiser_improved_on_no_start(monkeypatch, tmp_path):
    """SLSQP stopping at its first point on every start (as on a base set with columns 1e-13 of
    the others) leaves a random trajectory: the output and the JSON say so, with its message."""
    from mindyn.identification import excitation
    from scipy.optimize import OptimizeResult

    def stuck(fun, x0, **kw):
        msg = "Inequality constraints incompatible"
        return OptimizeResult(x=np.array(x0), success=False, message=msg, nit=1)

    monkeypatch.setattr(excitation, "minimize", stuck)
    rc, out, err = run(["excite", "planar2", "--starts", "2", "--quiet", "-o", tmp_path / "a.csv"])
    assert rc == 0, err
    (line,) = [s for s in out.splitlines() if "WARNING" in s]
    assert "failed on all 2 start(s) without improving on any (Inequality constraints" in line
    doc = json.loads((tmp_path / "a.json").read_text())
    assert len(doc["warnings"]) == 1
    assert not any(s["improved"] or s["converged"] for s in doc["starts"])
    monkeypatch.undo()
    rc, out, err = run(["excite", "planar2", "--starts", "1", "--quiet", "-o", tmp_path / "b.csv"])
    assert rc == 0 and "WARNING" not in out, out
    doc = json.loads((tmp_path / "b.json").read_text())
    assert doc["warnings"] == [] and doc["value"] < doc["initial_value"]


@pytest.mark.parametrize("tolerance", [0.01, 0.5])
def test_a_rank_tolerance_out_of_range_is_an_argument_error(tolerance):
    """The range the command line states, (0, 0.01), holds for the library's keyword too, as an
    ArgumentError naming it (the core's refusal was a ModelError, as for a bad description)."""
    with pytest.raises(mindyn.ArgumentError, match=r"^tolerance is .*; expected a number < 0\.01$"):
        mindyn.base_parameters("planar2", tolerance=tolerance)
    assert mindyn.base_parameters("planar2h", tolerance=0.009).n == 4  # ZZR1, ZZ2, MX2, MY2


@pytest.mark.parametrize("option", [{"tip": "link3"}, {"root_joint": "floating"}])
def test_a_loaded_robot_refuses_a_tip_or_root_joint_instead_of_ignoring_it(option):
    """mindyn.load(robot, tip=...) returned the whole robot unchanged: a chain asked for, a tree
    (or another chain) silently given."""
    robot = mindyn.load("puma560")
    (key,) = option
    with pytest.raises(mindyn.ArgumentError, match=f"^{key}= applies to a description file"):
        mindyn.load(robot, **option)
    assert mindyn.load(robot, gravity=[0, 0, -1.62]).gravity[2] == -1.62  # this one applies


@pytest.mark.parametrize(
    "option",
    [
        ["--controller", "pd"],
        ["--substeps", "8"],
        ["--integrator", "scipy"],
        ["--torque-limit", "effort"],
        ["--param-error", "0.1"],
        ["--controller", "computed-torque"],  # the default, given: refused as well
    ],
)
def test_simulate_inverse_refuses_the_closed_loops_options(option, tmp_path):
    """--mode inverse has no controller: a controller, gains or integrator given with it were
    ignored without a word, the log then not what the options asked for."""
    argv = ["simulate", "planar2", "--mode", "inverse", "--duration", "0.2", "-o", tmp_path]
    rc, _, err = run(argv + option)
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert err.startswith(f"mindyn: error: {option[0]}: an option of the closed loop"), err
    assert not (tmp_path / "planar2_simulate.csv").exists()
    rc, _, err = run(argv)
    assert rc == 0 and (tmp_path / "planar2_simulate.csv").is_file(), err


def test_excite_does_not_warn_when_the_start_is_already_optimal(tmp_path):
    """One joint, one base parameter: every trajectory has cond 1, so no start can improve; the
    optimiser converges at once and nothing is wrong."""
    (tmp_path / "one.yaml").write_text(
        "name: one\nconvention: mdh\njoints:\n"
        "  - {name: j1, type: revolute, alpha: 0, d: 0, theta: 0, r: 0,\n"
        "     inertial: {mass: 2.0, com: [0.2, 0, 0], inertia: {xx: 0.01, yy: 0.02, zz: 0.02}}}\n"
    )
    rc, out, err = run(["excite", tmp_path / "one.yaml", "--quiet", "-o", tmp_path / "e.csv"])
    assert rc == 0 and "WARNING" not in out, out
    doc = json.loads((tmp_path / "e.json").read_text())
    assert doc["value"] == pytest.approx(1.0) and doc["warnings"] == []


@pytest.mark.parametrize("key", ["velocity", "acceleration", "effort"])
def test_a_negative_limit_in_a_yaml_table_is_refused_by_name(key, tmp_path):
    """A URDF's negative <limit velocity/effort> was refused, a YAML table's was read: a
    negative effort then counted as no limit in simulate's noise and saturated the torque of
    track --torque-limit effort at a negative bound (the loop diverged)."""

    def table(sign: int) -> str:
        limits = {"lower": -1, "upper": 1, "velocity": 3, "acceleration": 10, "effort": 5}
        limits[key] *= sign
        given = "{" + ", ".join(f"{k}: {v}" for k, v in limits.items()) + "}"
        return TWO_LINK.replace("{lower: -170, upper: 170, velocity: 3, effort: 50}", given)

    (tmp_path / "arm.yaml").write_text(table(-1))
    where = next(
        f"{i + 1}:{line.index(f'{key}: -') + len(key) + 3}"  # the line and column of the value
        for i, line in enumerate(table(-1).splitlines())
        if f"{key}: -" in line
    )
    expected = (
        rf"arm.yaml:{where}: joint 1 \('shoulder'\): limits: '{key}' is -\d+: a limit on the "
    )
    with pytest.raises(mindyn.ModelError, match=expected + "magnitude cannot be negative"):
        mindyn.load(tmp_path / "arm.yaml")
    (tmp_path / "arm.yaml").write_text(table(1))
    value = mindyn.load(tmp_path / "arm.yaml").limits[key][0]
    degree = np.pi / 180 if key != "effort" else 1.0  # angle_unit: deg
    assert value == pytest.approx({"velocity": 3, "acceleration": 10, "effort": 5}[key] * degree)


def test_a_trajectory_json_of_another_robot_is_refused(tmp_path):
    """An excitation keeps the limits of the robot it was made for: simulate and track took
    one of another robot with as many joints without a word. simulate states its reference."""
    from mindyn.identification.excitation import random_trajectory

    for name in ("planar2", "planar2h"):
        traj = random_trajectory(mindyn.load(name), seed=1)
        doc = {"robot": name, "trajectory": traj.to_dict()}
        (tmp_path / f"{name}.json").write_text(json.dumps(doc))
    for cmd in (["simulate", "-o", tmp_path / "log.csv"], ["track", "--duration", "0.2"]):
        argv = [cmd[0], "planar2", "--trajectory", tmp_path / "planar2h.json", *cmd[1:]]
        rc, _, err = run(argv)
        assert rc == 2 and len(err.splitlines()) == 1, err
        assert "planar2h.json: an excitation of robot 'planar2h', not 'planar2'" in err, err
    argv = ["simulate", "planar2", "--trajectory", tmp_path / "planar2.json", "--mode", "inverse"]
    rc, out, err = run([*argv, "-o", tmp_path / "log.csv"])
    assert rc == 0, err
    assert out.splitlines()[1] == f"  reference: trajectory {tmp_path / 'planar2.json'} (10 s)"
    rc, out, err = run(["simulate", "planar2", "--mode", "inverse", "-o", tmp_path / "b.csv"])
    assert out.splitlines()[1] == "  reference: sum of sines within the limits, 10 s cycle"


def test_codegen_refuses_a_controller_period_for_functions_without_one(tmp_path):
    """--controller-period with the inverse dynamics, gravity or regressor was ignored (they are
    functions of the state), while --gains, --box and --torque-limit were refused there."""
    argv = ["codegen", "planar2", "--lang", "c", "-o", tmp_path / "a"]
    rc, _, err = run([*argv, "--controller-period", "0.01"])
    assert rc == 2 and "--controller-period: applies to controller and" in err, err
    assert not (tmp_path / "a.c").exists()
    step = ["--what", "momentum-observer", "--controller-period", "0.01"]
    rc, out, err = run([*argv, *step])
    assert rc == 0 and "period 0.01 s" in out, err
    assert "K_O [1/s] (default 1 / (10 T) = 10)" in out  # 1 / (10 x 0.01 s)
    rc, out, err = run([*argv, "--what", "momentum-observer"])
    assert rc == 0 and "period 0.004 s" in out, err  # the default, stated


DAMPED = """\
name: damped
convention: mdh
joints:
  - {name: j1, type: revolute, alpha: 0, d: 0, theta: 0, r: 0, friction: {viscous: 3.0},
     inertial: {mass: 2.0, com: [0.1, 0, 0], inertia: {xx: 0.001, yy: 0.001, zz: 0.0001}}}
"""


class _Ramp:
    """q_d = v t: the robot starts at speed v."""

    duration = 0.2

    def evaluate(self, t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        return 0.5 * t[:, None], np.full((t.size, 1), 0.5), np.zeros((t.size, 1))


def test_rk4_steps_follow_the_plants_damping_rate(tmp_path):
    """A joint whose viscous friction is fast on its inertia (rate Fv / I = 3 / (1e-4 + 2 x 0.1^2)
    = 149 1/s here, 1.4e4 1/s on the xArm7's wrist) made RK4 with 4 steps per period diverge
    (|R(h lambda)| > 1 beyond h lambda = 2.785) at t = 0; the default steps keep h lambda <= 2
    and the free motion then decays, as the exact v0 exp(-lambda t) does."""
    from mindyn.control import simulation

    (tmp_path / "damped.yaml").write_text(DAMPED)
    robot = mindyn.load(tmp_path / "damped.yaml")
    rate = 3.0 / (1e-4 + 2.0 * 0.1**2)
    period = 0.04  # h lambda = 1.49 with 4 steps: 4 suffice
    steps, found = simulation.rk4_substeps(robot, robot.parameters(friction=True), period)
    assert found == pytest.approx(rate, rel=1e-12) and steps == 4
    period = 0.1  # 14.9 for the period: 8 steps
    steps, _ = simulation.rk4_substeps(robot, robot.parameters(friction=True), period)
    assert steps == 8 == math.ceil(period * rate / 2.0)

    def idle(t, q, dq, q_d, dq_d, ddq_d):
        return np.zeros(1)

    res = simulation.simulate(robot, _Ramp(), idle, rate=10.0, friction=True)
    assert res.info["substeps"] == 8
    assert np.all(np.isfinite(res.dq)) and np.all(np.abs(res.dq[1:, 0]) < 0.5 * 0.5)
    assert "damping rate 149 1/s" in res.info["integrator"]
    with pytest.raises(mindyn.Error, match="diverged"):  # the former default
        simulation.simulate(robot, _Ramp(), idle, rate=10.0, friction=True, substeps=4)


def test_codegen_numeric_needs_a_function_that_takes_the_values(tmp_path):
    """--numeric with the regressor alone was ignored, and the output said 'values baked in'."""
    argv = ["codegen", "planar2", "--lang", "c", "--numeric", "-o", tmp_path / "a"]
    rc, _, err = run([*argv, "--what", "regressor"])
    assert rc == 2 and "--numeric: applies to the inverse dynamics and gravity" in err, err
    rc, out, err = run([*argv, "--what", "gravity,regressor"])
    assert rc == 0 and "values baked in" in out, err
    assert "const double p[" not in (tmp_path / "a.h").read_text()  # gravity takes no p


@pytest.mark.parametrize("cmd", [["track"], ["simulate", "-o", "OUT"]])
def test_a_parameter_error_for_pd_is_refused(cmd, tmp_path):
    """PD has no model: --param-error with it was ignored."""
    argv = [cmd[0], "planar2", "--controller", "pd", "--duration", "0.2"]
    argv += [a.replace("OUT", str(tmp_path / "log.csv")) for a in cmd[1:]]
    rc, _, err = run([*argv, "--param-error", "0.5"])
    assert rc == 2 and err.startswith("mindyn: error: --param-error: --controller pd"), err
    rc, _, err = run(argv)
    assert rc == 0, err


@pytest.mark.parametrize(
    "argv, said",
    [
        (["--lang", "st", "--trig", "libm"], "--trig applies to C only"),
        (["--lang", "c", "--what", "id,foo"], "--what names an unknown function 'foo'"),
        (["--lang", "c", "--what", ","], "--what names no function"),
        (["--lang", "c", "--name", "1abc"], "--name '1abc' is not an identifier"),
        (["--lang", "st", "--what", "adaptive-pd", "--trig", "inline"], "--trig applies to C"),
        (["--lang", "c", "--what", "computed-torque", "--name", "a__b"], "--name 'a__b' is not"),
        (["--lang", "st", "--what", "momentum-observer", "--trig", "libm"], "--trig applies"),
        (
            ["--lang", "c", "--what", "momentum-observer", "--observer-gain", "1000"],
            "--observer-gain gives observer gain K_O of joint 1 as 1000 1/s",
        ),
    ],
)
def test_codegen_refusals_name_the_flags(argv, said, tmp_path):
    """The library's refusals of generate, generate_controller and generate_observer name their
    keywords (trig, what, name, gains); the command line names its flags instead."""
    rc, _, err = run(["codegen", "planar2", *argv, "-o", tmp_path / "x"])
    assert rc == 2 and err.startswith(f"mindyn: error: {said}"), err
    assert err.count("\n") == 1, err


def test_info_gives_the_motor_terms_the_dynamics_use():
    """xArm7 (example-robot-data): its URDF gives each joint damping and friction and a
    SimpleTransmission of ratio 100; the table listed the joints' damping (10) under 'Fv' while
    --rotor / --friction use and identify the motors' (10 / 100^2). The table now says its Ia,
    Fv, Fc are the joints', and the motors' follow, from the URDF's numbers."""
    import xml.etree.ElementTree as ET

    path = ROBOTS_DIR / "xarm_description/urdf/xarm7.urdf"
    rc, out, err = run(["info", str(path)])
    assert rc == 0, err
    assert "Ia, Fv, Fc: the joints', as the description gives them" in out
    rows = out.split("rotor inertia and friction on the motors")[1].splitlines()[2:]
    doc = ET.parse(path).getroot()
    joints = {j.get("name"): j for j in doc.iter("joint") if j.get("type")}
    ratio = {
        t.find("joint").get("name"): float(t.find("actuator/mechanicalReduction").text)
        for t in doc.iter("transmission")
    }
    for k, row in enumerate(rows[:7]):
        name = f"joint{k + 1}"
        dyn = joints[name].find("dynamics")
        r = ratio[name]
        ia, fv, fc = map(float, row.split()[2:5])
        assert ia == 0.0
        assert fv == pytest.approx(float(dyn.get("damping")) / r**2, rel=1e-3)
        assert fc == pytest.approx(float(dyn.get("friction")) / abs(r), rel=1e-3)


@pytest.mark.parametrize(("robot", "said"), [("planar1", "(1 joint,"), ("planar2", "(2 joints,")])
def test_info_counts_the_joints_in_words(robot, said):
    rc, out, err = run(["info", robot])
    assert rc == 0, err
    assert said in out.splitlines()[0]


FLANGED = """<robot name="flanged">
  <link name="base"/>
  <link name="l1"><inertial><mass value="2"/><inertia ixx="0.1" iyy="0.1" izz="0.1"
    ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="l2"><inertial><mass value="1"/><inertia ixx="0.05" iyy="0.05" izz="0.05"
    ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="flange"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.3"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.4 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="1"/></joint>
  <joint name="f" type="fixed"><parent link="l2"/><child link="flange"/>
    <origin xyz="0.3 0 0"/></joint>
</robot>
"""


def test_ik_names_the_frame_it_places(tmp_path):
    """A whole URDF ending in a fixed flange: ik places the last moving link's frame (not the
    flange 0.3 m further), and says so in the table and the JSON; with --tip flange it places
    the flange. Reference: Pinocchio's placement of the joint frame j2 (and of the flange frame)
    at the answer, against the target."""
    path = tmp_path / "flanged.urdf"
    path.write_text(FLANGED)
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    q = np.array([0.3, 0.4])  # a pose each frame reaches: its placement at q
    for tip, frame, words in [
        ([], "j2", "the frame of link 'l2', the last moving link (a fixed link after it: --tip"),
        (["--tip", "flange"], "flange", "link 'l2' moved by the tool offset (xyz 0.3 0 0 m)"),
    ]:
        pin.framesForwardKinematics(model, data, q)
        target = data.oMf[model.getFrameId(frame)].translation.copy()
        pose = ["--xyz", *(repr(float(v)) for v in target), "--rpy", "0", "0", "0.7"]
        rc, out, err = run(["ik", path, *tip, *pose])
        assert rc == 0, err
        assert "  frame: " in out and words in out, out
        rc, js, err = run(["ik", path, *tip, *pose, "--format", "json"])
        doc = json.loads(js)
        assert words in doc["frame"], doc["frame"]
        pin.framesForwardKinematics(model, data, np.array(doc["q"]))
        placed = data.oMf[model.getFrameId(frame)].translation
        assert np.max(np.abs(placed - target)) < 1e-9, (frame, placed)


def test_simulate_says_when_rotor_and_friction_have_nothing_to_add(tmp_path):
    """--rotor --friction on a description that gives no rotor inertia or friction (a URDF
    without <dynamics>, which has no place for rotor inertia) change nothing: the output says
    so, and the log is the one without them. On a description that gives them it says nothing
    of the kind, and the torques differ."""
    urdf, table = tmp_path / "flanged.urdf", tmp_path / "arm.yaml"
    urdf.write_text(FLANGED)
    doc = yaml.safe_load(TWO_LINK)
    for joint in doc["joints"]:
        joint.update(rotor_inertia=0.05, friction={"viscous": 0.2, "coulomb": 0.5})
    table.write_text(yaml.safe_dump(doc))
    taus = {}
    for robot, rotor_said in ((urdf, True), (table, False)):
        for flags in ([], ["--rotor", "--friction"]):
            csv = tmp_path / f"{robot.stem}{len(flags)}.csv"
            rc, out, err = run(["simulate", robot, "--mode", "inverse", *flags, "-o", csv])
            assert rc == 0, err
            said = "rotor inertia on (zero in the description: no effect), friction on (zero"
            assert (said in out.splitlines()[0]) is (rotor_said and bool(flags)), out
            taus[robot.stem, len(flags)] = np.loadtxt(csv, delimiter=",", skiprows=1)[:, -2:]
    assert np.array_equal(taus["flanged", 0], taus["flanged", 2])
    assert not np.allclose(taus["arm", 0], taus["arm", 2])


def test_info_lists_the_torque_offsets_of_a_joint_terms_file(tmp_path):
    """``info --joint-terms FILE`` with torque offsets: it listed the rotor inertia and friction
    but not the offsets, and said they were not used; now a row per joint with the file's
    value, and the line says they are shown."""
    terms = tmp_path / "planar2.joints.yaml"
    offsets = {"joint1": 0.25, "joint2": -1.5}
    rows = [{"name": j, "Ia": 0.125, "Off": v} for j, v in offsets.items()]
    terms.write_text(json.dumps({"joints": rows}))  # JSON is YAML; "Off" quoted
    rc, out, err = run(["info", "planar2", "--joint-terms", terms])
    assert rc == 0, err
    lines = out.splitlines()
    said = "Ia on the joints, replacing the description's; torque offsets Off shown"
    assert lines[0] == f"joint terms from {terms}: {said}"
    at = next(i for i, x in enumerate(lines) if x.startswith("torque offsets per joint"))
    assert lines[at + 1].split() == ["#", "joint", "Off"]
    got = {r.split()[1]: float(r.split()[2]) for r in lines[at + 2 : at + 4]}
    assert got == offsets
    assert "torque offsets per joint" not in run(["info", "planar2"])[1]
