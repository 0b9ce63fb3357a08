"""The argument contract of the public Python API, walked function by function.

The public functions are enumerated from the package (``__all__`` of ``mindyn``, of
``mindyn.identification``, ``mindyn.control``, ``mindyn.codegen``, ``mindyn.inverse_kinematics``,
``mindyn.export`` and ``mindyn.mjcf``, the public methods of ``Robot`` and ``BaseParameters``, and
the constructors and methods of the classes of ``mindyn.codegen``); each has a
valid baseline call below, which is run once. Then every argument of the baseline is replaced,
one at a time, by a value of a wrong type and by a wrong value of the right type: each call must
raise ``mindyn.ArgumentError`` (a ``mindyn.Error``, ``ValueError`` and ``TypeError``) whose one
line names the argument. The functions that take a robot with multi-DOF joints on their own
paths (dynamics, kinematics, Slotine-Li regressor, Coriolis matrix) are walked a second time on
such a robot (``[multi-DOF]``). Options after the data arguments are keyword-only. Getters
return read-only arrays.
"""

from __future__ import annotations

import inspect
import json
import re
from pathlib import Path

import mindyn
import mindyn.codegen as codegen
import mindyn.control as control
import mindyn.export as export
import mindyn.formulas as formulas
import mindyn.identification as identification
import mindyn.inverse_kinematics as inverse_kinematics
import mindyn.mjcf as mjcf
import numpy as np
import pytest
from mindyn import ArgumentError, BaseParameters, Robot
from mindyn.cli import main as cli_main
from mindyn.control import controllers, stability
from mindyn.identification import (
    columns,
    consistent,
    currents,
    document,
    excitation,
    floating,
    floating_motion,
    floating_workflow,
    prediction,
    preprocess,
    report,
    rosbag,
)
from mindyn.identification import data as logs

ROBOT = mindyn.load("planar2")
BASE = mindyn.base_parameters(ROBOT)
N = ROBOT.n
Z = np.zeros(N)
Q = np.array([0.3, -0.4])
T0 = ROBOT.fk(Q)
TABLE = mindyn.load("puma560_3")  # a robot read from a YAML table (write_yaml)


def _log(m: int = 400, rate: float = 200.0) -> identification.JointData:
    """A log of ROBOT on sines, its torques the model's (a known answer)."""
    t = np.arange(m) / rate
    w = np.array([1.3, 2.1])
    q = np.sin(w * t[:, None])
    dq = w * np.cos(w * t[:, None])
    ddq = -(w**2) * np.sin(w * t[:, None])
    tau = ROBOT.inverse_dynamics(q, dq, ddq)
    return identification.JointData(t, q, dq, ddq, tau, "sines")


LOG = _log()
RESULT = identification.identify(ROBOT, LOG, base=BASE)
GAINS = control.default_gains(ROBOT, period=0.004, rotor=False)
P13 = ROBOT.parameters(rotor=True, friction=True)


class Opaque:
    """A value of no type any function of mindyn takes."""

    def __repr__(self) -> str:
        return "Opaque()"


WRONG_TYPE = Opaque()
SKIP = object()  # no wrong value of the right type for this argument (a path, a log, ...)


URDF = """<robot name="two">
  <link name="base"/>
  <link name="a"><inertial><mass value="1.0"/><origin xyz="0.1 0 0"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <link name="b"><inertial><mass value="0.5"/><origin xyz="0.1 0 0"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
  <joint name="j2" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0.3 0 0"/>
    <axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
</robot>
"""


def _floating() -> tuple[mindyn.Robot, floating.FloatingLog]:
    """The URDF's robot on a free-flyer root and a log of random states with a wrench on b."""
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        (Path(d) / "two.urdf").write_text(URDF)
        robot = mindyn.load(Path(d) / "two.urdf", root_joint="floating")
    rng = np.random.default_rng(0)
    m = 30
    quat = rng.normal(size=(m, 4))
    q = np.hstack([rng.normal(size=(m, 3)), quat / np.linalg.norm(quat, axis=1)[:, None]])
    q = np.hstack([q, rng.uniform(-1, 1, (m, 2))])
    dq, ddq = rng.normal(size=(m, 8)), rng.normal(size=(m, 8))
    return robot, floating.FloatingLog(
        q, dq, ddq, rng.normal(size=(m, 2)), {"b": rng.normal(size=(m, 6))}
    )


FLOATING, FLOATING_LOG = _floating()


def _files(tmp: Path) -> dict:
    log_csv = tmp / "log.csv"
    identification.write_csv(log_csv, LOG.t, LOG.q, LOG.tau)
    urdf = tmp / "two.urdf"
    urdf.write_text(URDF)
    gains = tmp / "gains.yaml"
    gains.write_text("{}\n")
    thresholds = tmp / "thresholds.json"
    thresholds.write_text(
        '{"robot": "planar2", "period_s": 0.004, "gains": [25, 25], "thresholds": [1, 1]}'
    )
    reference = tmp / "reference.csv"
    t = np.arange(0, 1, 0.01)
    reference.write_text("".join(f"{x},{np.sin(x)},{np.cos(x)}\n" for x in t))
    two = mindyn.load(urdf)
    names = two.parameter_names(rotor=True, friction=True)
    full = dict(zip(names, two.parameters(rotor=True, friction=True)))
    sidecar = export.write_urdf(two, full, tmp / "terms.urdf").sidecar
    currents_csv = tmp / "currents.csv"
    currents_csv.write_text(
        "t,i1,i2\n" + "".join(f"{t:.17g},{a:.17g},{b:.17g}\n" for t, (a, b) in zip(LOG.t, LOG.tau))
    )
    sim_csv = control.simulate_inverse(
        ROBOT, control.SumOfSines(ROBOT, period=0.5), rate=100.0
    ).save(tmp / "sim.csv", robot_name=ROBOT.name)
    from test_rosbag import messages, robot_log, write_bag

    bag = write_bag(tmp / "bag", messages(ROBOT, robot_log(ROBOT, m=200)))
    floating_csv = tmp / "floating.csv"
    L = FLOATING_LOG
    header = [f"q{i + 1}" for i in range(9)] + [f"dq{i + 1}" for i in range(8)]
    header += [f"ddq{i + 1}" for i in range(8)] + ["tau1", "tau2"]
    header += [f"b.{a}" for a in ("fx", "fy", "fz", "tx", "ty", "tz")]
    table = np.hstack([L.q, L.dq, L.ddq, L.tau, L.wrenches["b"]])
    for path, rows in ((floating_csv, table), (tmp / "floating_val.csv", table[::-1])):
        # (the validation log another file: the fit log as validation is refused)
        path.write_text(
            ",".join(header) + "\n" + "".join(",".join(map(repr, r.tolist())) + "\n" for r in rows)
        )
    arm_json = tmp / "arm.json"
    assert cli_main(["identify", "planar2", str(log_csv), "--json", str(arm_json)]) == 0
    return {
        "bag": bag,
        "currents": currents_csv,
        "sim_csv": sim_csv,
        "arm_json": arm_json,
        "log_csv": log_csv,
        "urdf": urdf,
        "gains": gains,
        "thresholds": thresholds,
        "reference": reference,
        "sidecar": sidecar,
        "floating_csv": floating_csv,
        "floating_val_csv": tmp / "floating_val.csv",
    }


# name -> (function, positional arguments, keyword arguments); arguments given as a callable
# of the temporary folder's files where they are files
def _api(tmp: Path) -> dict:
    f = _files(tmp)
    sim = control.simulate_inverse(ROBOT, control.SumOfSines(ROBOT, period=1.0), rate=100.0)
    classical = dict(zip(ROBOT.param_names, ROBOT.params))
    truth = {"names": ROBOT.param_names, "values": ROBOT.params.tolist()}
    two = mindyn.load(f["urdf"])
    two_classical = dict(zip(two.param_names, two.params))
    smooth = mindyn.base_parameters(
        ROBOT.with_friction_model("smooth", velocity=[0.1, 0.1]), friction=True
    )
    observer = control.MomentumObserver(BASE, BASE.values(ROBOT.params), period=0.004)
    closed = control.simulate(
        ROBOT, control.SumOfSines(ROBOT, period=0.5), duration=0.2, rate=250.0
    )
    kp, kd, lam = np.full(N, 100.0), np.full(N, 20.0), np.full(N, 5.0)
    qs = stability.workspace_samples(ROBOT, count=4)
    mm = ROBOT.mass_matrix(qs)
    arm = document.read_identification(f["arm_json"])
    pd = control.make_controller("pd", ROBOT, GAINS, period=0.004)
    p10 = ROBOT.params[:10]
    six = mindyn.load("zcr07s")  # a payload on the last of six joints
    # identified with friction (zero), which min_velocity= applies to
    six_base = mindyn.base_parameters(six, friction=True)
    six_classical = dict(zip(six.param_names, six.params, strict=True))
    six_arm = {
        "robot": six.name,
        "base_names": six_base.names,
        "base_values": six_base.values(
            [six_classical.get(k, 0.0) for k in six_base.classical_names]
        ).tolist(),
        "rotor": False,
        "friction": True,
        "offset": False,
    }
    with_payload = six.params.copy()
    with_payload[-10:] += [0.004, 0.0, 0.0, 0.005, 0.0, 0.003, 0.03, -0.015, 0.075, 1.5]
    six_log = control.simulate_inverse(
        six, excitation.random_trajectory(six, seed=1), rate=50.0, params=with_payload
    )
    payload_log = identification.JointData(
        six_log.t, six_log.q, six_log.dq, six_log.ddq_true, six_log.tau, "payload"
    )
    return {
        **_codegen_api(tmp),
        **_multidof_api(),
        **{
            "control.controllers.check_period": (controllers.check_period, (0.004,), {}),
            "control.controllers.coulomb_friction": (
                controllers.coulomb_friction,
                (ROBOT, P13),
                {},
            ),
            "control.controllers.friction_shortfall": (
                controllers.friction_shortfall,
                (ROBOT,),
                {"rotor": True},
            ),
            "control.controllers.model_friction_shortfall": (
                controllers.model_friction_shortfall,
                (ROBOT, BASE, BASE.values(ROBOT.params), np.full(N, 100.0)),
                {"tolerance": 0.01, "share": 1.0, "qs": qs[:2]},
            ),
            "control.controllers.friction_bound": (
                controllers.friction_bound,
                (ROBOT,),
                {"tolerance": 0.01},
            ),
            "control.controllers.controller_check": (
                controllers.controller_check,
                (ROBOT, pd, P13, 0.004),
                {},
            ),
            "control.estimate_box": (
                control.estimate_box,
                (ROBOT, BASE, GAINS),
                {"period": 0.004, "qs": qs[:2]},
            ),
            "control.stability.adaptation_step_ratio": (
                stability.adaptation_step_ratio,
                (np.ones((3, N, BASE.n)), kd, 1.0, 0.5, 0.004),
                {},
            ),
            "control.stability.check_loop": (
                stability.check_loop,
                ("pd", kp, kd, lam, 0.004, [np.linalg.inv(mm)], [mm], qs, ["robot"]),
                {},
            ),
            "control.stability.loop_matrix": (
                stability.loop_matrix,
                (kp, kd, np.eye(N), 0.004),
                {},
            ),
            "control.stability.workspace_samples": (
                stability.workspace_samples,
                (ROBOT,),
                {"count": 5, "seed": 1},
            ),
            "formulas.latex": (formulas.latex, (BASE.formula_terms(),), {}),
            "formulas.numeric_formulas": (
                formulas.numeric_formulas,
                (np.array(BASE.Y), list(BASE.names), list(BASE.classical_names)),
                {},
            ),
            "formulas.round_coefficient": (formulas.round_coefficient, (0.1,), {"scale": 1.0}),
            "formulas.shortest_decimal": (formulas.shortest_decimal, (0.1, 1e-9), {}),
            "formulas.symbolic_formulas": (formulas.symbolic_formulas, (BASE,), {"seed": 1}),
            "formulas.unit_formula": (formulas.unit_formula, ("Off1",), {}),
            "identification.consistent.consistent_estimate": (
                consistent.consistent_estimate,
                (RESULT,),
                {"prior_weight": 1e-3},
            ),
            "identification.consistent.pseudo_inertia": (consistent.pseudo_inertia, (p10,), {}),
            "identification.consistent.inertial_from_pseudo": (
                consistent.inertial_from_pseudo,
                (consistent.pseudo_inertia(p10),),
                {},
            ),
            "identification.columns.column_map": (
                columns.column_map,
                ({"t[ms]": "time", "q": "q{j}", "tau": ["T1", "T2"]},),
                {},
            ),
            "identification.currents.read_currents": (
                currents.read_currents,
                (f["currents"], N),
                {},
            ),
            "identification.currents.attach_currents": (
                currents.attach_currents,
                (LOG, f["currents"], ROBOT),
                {"drive_gain": [1.0, 1.0]},
            ),
            "identification.data.check_log_robot": (
                logs.check_log_robot,
                ({"robot": "planar2"}, ROBOT, "the log"),
                {},
            ),
            "identification.data.differentiate": (
                logs.differentiate,
                (LOG.t, LOG.q),
                {"filter": "butter", "order": 4},
            ),
            "identification.data.read_truth": (logs.read_truth, (f["sim_csv"], ROBOT), {}),
            "identification.data.truth_path": (logs.truth_path, (f["sim_csv"],), {}),
            "identification.data.write_trajectory_csv": (
                logs.write_trajectory_csv,
                (tmp / "traj.csv", LOG.t, LOG.q, LOG.dq, LOG.ddq),
                {},
            ),
            "identification.document.read_identification": (
                document.read_identification,
                (f["arm_json"],),
                {"need": ("robot",), "finite": False},
            ),
            "identification.document.robot_on_drive_side": (
                document.robot_on_drive_side,
                (ROBOT, arm),
                {"where": "arm"},
            ),
            "identification.document.with_identified_friction": (
                document.with_identified_friction,
                (ROBOT, arm),
                {"where": "arm"},
            ),
            "identification.excitation.check_sampling": (
                excitation.check_sampling,
                (5, 0.1, 100.0),
                {"periods": 1.0},
            ),
            "identification.excitation.criterion_value": (
                excitation.criterion_value,
                (BASE, LOG.q, LOG.dq, LOG.ddq),
                {"criterion": "cond"},
            ),
            "identification.excitation.excitation_limits": (
                excitation.excitation_limits,
                (ROBOT,),
                {"margin": 0.05},
            ),
            "identification.excitation.effort_acceleration_limits": (
                excitation.effort_acceleration_limits,
                (ROBOT,),
                {
                    "lower": -np.ones(ROBOT.n),
                    "upper": np.ones(ROBOT.n),
                    "velocity": np.ones(ROBOT.n),
                    "fixed": np.full(ROBOT.n, np.nan),
                    "fallback": np.full(ROBOT.n, 6.0),
                    "reach": np.full(ROBOT.n, 10.0),
                    "share": 0.8,
                    "rotor": True,
                    "friction": True,
                    "configurations": 8,
                    "seed": 1,
                },
            ),
            "identification.excitation.peak_torques": (
                excitation.peak_torques,
                (ROBOT, LOG.q, LOG.dq, LOG.ddq),
                {"rotor": True, "friction": True},
            ),
            "identification.excitation.random_trajectory": (
                excitation.random_trajectory,
                (ROBOT,),
                {"harmonics": 3, "seed": 1},
            ),
            "identification.excitation.optimize_excitation": (
                excitation.optimize_excitation,
                (ROBOT,),
                {"harmonics": 2, "starts": 1, "maxiter": 2, "samples": 20, "progress": False},
            ),
            "identification.excitation.plot_trajectory": (
                excitation.plot_trajectory,
                (tmp / "trajectory.png", LOG.t, LOG.q, LOG.dq, LOG.ddq),
                {"title": "sines"},
            ),
            "identification.prediction.identified_model": (
                prediction.identified_model,
                (RESULT,),
                {"estimate": "unconstrained"},
            ),
            "identification.prediction.predict": (prediction.predict, (RESULT, LOG), {}),
            "identification.preprocess.concatenate": (preprocess.concatenate, ([LOG],), {}),
            "identification.preprocess.excited_band": (
                preprocess.excited_band,
                (LOG.q, 0.005),
                {"energy": 0.9},
            ),
            "identification.preprocess.preprocess": (preprocess.preprocess, (LOG,), {"order": 4}),
            "identification.preprocess.require_even_stamps": (
                preprocess.require_even_stamps,
                (LOG, "butter"),
                {},
            ),
            "identification.preprocess.timing": (preprocess.timing, (LOG.t,), {}),
            "identification.report.format_table": (report.format_table, (RESULT,), {}),
            "identification.report.plot_torques": (
                report.plot_torques,
                (tmp / "torques.png", LOG.t, LOG.tau, LOG.tau),
                {"title": "sines"},
            ),
            "identification.report.write_report": (
                report.write_report,
                (tmp / "rep", RESULT, LOG),
                {},
            ),
            "identification.rosbag.is_rosbag": (rosbag.is_rosbag, (f["log_csv"],), {}),
            "identification.identify_payload": (
                identification.identify_payload,
                (six, six_arm, payload_log),
                {"consistent": False, "min_velocity": 0.01},
            ),
            "identification.rosbag.read_rosbag": (
                rosbag.read_rosbag,
                (f["bag"], ROBOT),
                {"topic": "/joint_states", "torque_unit": "Nm"},
            ),
            # mindyn
            "mindyn.load": (mindyn.load, ("planar2",), {"gravity": [0.0, 0.0, -9.81]}),
            "mindyn.base_parameters": (
                mindyn.base_parameters,
                (ROBOT,),
                {"rotor": False, "friction": False, "method": "projection", "tolerance": 1e-9},
            ),
            "mindyn.to_pinocchio_order": (mindyn.to_pinocchio_order, (ROBOT.params,), {}),
            "mindyn.from_pinocchio_order": (mindyn.from_pinocchio_order, (ROBOT.params,), {}),
            "mindyn.inertial_from_com": (
                mindyn.inertial_from_com,
                (1.0, np.zeros(3), np.eye(3)),
                {},
            ),
            "mindyn.inertial_from_urdf": (
                mindyn.inertial_from_urdf,
                (1.0, np.zeros(3), np.eye(3), np.eye(3)),
                {},
            ),
            "mindyn.coriolis_matrix": (mindyn.coriolis_matrix, (ROBOT, Q, Z), {}),
            "mindyn.slotine_li_regressor": (mindyn.slotine_li_regressor, (BASE, Q, Z, Z, Z), {}),
            "mindyn.ik": (mindyn.ik, (ROBOT, T0), {}),
            # Robot
            "Robot.parameter_names": (ROBOT.parameter_names, (), {"rotor": True, "friction": True}),
            "Robot.parameters": (ROBOT.parameters, (), {"rotor": True, "friction": True}),
            "Robot.inverse_dynamics": (ROBOT.inverse_dynamics, (Q, Z, Z, ROBOT.params), {}),
            "Robot.regressor": (ROBOT.regressor, (Q, Z, Z), {"rotor": True, "friction": False}),
            "Robot.gravity_torque": (ROBOT.gravity_torque, (Q,), {}),
            "Robot.mass_matrix": (ROBOT.mass_matrix, (Q,), {}),
            "Robot.link_poses": (ROBOT.link_poses, (Q,), {}),
            "Robot.momentum": (ROBOT.momentum, (Q, Z), {}),
            "Robot.forward_dynamics": (ROBOT.forward_dynamics, (Q, Z, Z), {}),
            "Robot.kinetic_energy": (ROBOT.kinetic_energy, (Q, Z), {}),
            "Robot.potential_energy": (ROBOT.potential_energy, (Q,), {}),
            "Robot.energy": (ROBOT.energy, (Q, Z), {}),
            "Robot.friction_shapes": (ROBOT.friction_shapes, (Z,), {}),
            "Robot.energy_regressors": (ROBOT.energy_regressors, (Q, Z), {"rotor": True}),
            "Robot.energy_regressor": (ROBOT.energy_regressor, (Q, Z), {"friction": True}),
            "Robot.lagrangian_regressor": (ROBOT.lagrangian_regressor, (Q, Z), {"rotor": False}),
            "Robot.momentum_regressors": (ROBOT.momentum_regressors, (Q, Z), {"rotor": True}),
            "Robot.fk": (ROBOT.fk, (Q,), {"link": 0}),
            "Robot.jacobian": (ROBOT.jacobian, (Q,), {}),
            "Robot.joint_transform": (ROBOT.joint_transform, (1, 0.3), {}),
            "Robot.joint_pre": (ROBOT.joint_pre, (1,), {}),
            "Robot.joint_post": (ROBOT.joint_post, (0,), {}),
            "Robot.with_gravity": (ROBOT.with_gravity, ([0.0, -9.81, 0.0],), {}),
            "Robot.with_friction_model": (
                ROBOT.with_friction_model,
                ("smooth",),
                {"velocity": [0.1, 0.1]},
            ),
            "Robot.slot_velocities": (ROBOT.slot_velocities, (Z,), {}),
            "Robot.drive_terms_given": (ROBOT.drive_terms_given, (), {}),
            # BaseParameters
            "BaseParameters.values": (BASE.values, (ROBOT.params,), {}),
            "BaseParameters.embed": (BASE.embed, (np.ones(BASE.n),), {}),
            "BaseParameters.regressor": (BASE.regressor, (Q, Z, Z), {}),
            "BaseParameters.energy_regressor": (BASE.energy_regressor, (Q, Z), {}),
            "BaseParameters.momentum_regressors": (BASE.momentum_regressors, (Q, Z), {}),
            "BaseParameters.latex": (BASE.latex, (), {"symbolic": False}),
            "BaseParameters.to_dict": (BASE.to_dict, (), {"symbolic": False}),
            "BaseParameters.snap_report": (BASE.snap_report, (), {"detail": False}),
            "BaseParameters.for_robot": (BASE.for_robot, (ROBOT,), {"offset": True}),
            # identification
            "identification.identify": (
                identification.identify,
                (ROBOT, LOG),
                # with friction (zero in LOG), which min_velocity= applies to
                {"model": "dynamic", "friction": True, "rsd_threshold": 30.0, "min_velocity": 0.01},
            ),
            "identification.dynamic_system": (
                identification.dynamic_system,
                (BASE, LOG),
                {"min_velocity": 0.0},
            ),
            "identification.energy_system": (
                identification.energy_system,
                (BASE, LOG),
                {"window": 5},
            ),
            "identification.integral_system": (
                identification.integral_system,
                (BASE, LOG),
                {"window": 20, "integration": "trapezoid"},
            ),
            "identification.validate": (identification.validate, (RESULT, LOG), {}),
            "identification.load_logs": (
                identification.load_logs,
                ([f["log_csv"]], ROBOT),
                {"model": "dynamic"},
            ),
            "identification.run": (
                identification.run,
                (ROBOT, LOG),
                {"friction": True, "rsd_threshold": 30.0, "min_velocity": 0.01},
            ),
            "identification.error_measures": (
                identification.error_measures,
                (LOG.tau, LOG.tau + 0.1),
                {},
            ),
            "identification.true_base_values": (
                identification.true_base_values,
                (BASE, truth),
                {},
            ),
            "identification.read_csv": (identification.read_csv, (f["log_csv"], ROBOT), {}),
            "identification.floating.contact_jacobian": (
                floating.contact_jacobian,
                (FLOATING, FLOATING_LOG.q[0], "b"),
                {"frame": "local"},
            ),
            "identification.floating.floating_system": (
                floating.floating_system,
                (FLOATING, FLOATING_LOG),
                {"model": "base"},
            ),
            "identification.floating.identify_floating": (
                floating.identify_floating,
                (FLOATING, FLOATING_LOG),
                {"model": "full", "base": None, "tolerance": 1e-9, "weighted": True},
            ),
            "identification.floating.read_floating_csv": (
                floating.read_floating_csv,
                (f["floating_csv"], FLOATING),
                {"wrench_frame": "world", "filter": "savgol", "cutoff": 5.0},
            ),
            "identification.floating_motion.configuration_derivatives": (
                floating_motion.configuration_derivatives,
                (FLOATING, np.arange(30) * 0.01, FLOATING_LOG.q),
                {"filter": "none", "cutoff": 5.0},
            ),
            "identification.floating_workflow.coordinate_names": (
                floating_workflow.coordinate_names,
                (FLOATING,),
                {},
            ),
            "identification.floating_workflow.load_floating_logs": (
                floating_workflow.load_floating_logs,
                ([f["floating_csv"]], FLOATING),
                {
                    "validate": [f["floating_val_csv"]],
                    "wrench_frame": "world",
                    "contacts": ["b"],
                    "filter": "butter",
                    "cutoff": 5.0,
                },
            ),
            "identification.floating_workflow.run_floating": (
                floating_workflow.run_floating,
                (FLOATING, floating_workflow.load_floating_logs([f["floating_csv"]], FLOATING)),
                {"model": "full", "tolerance": 1e-9, "weighted": False},
            ),
            "identification.write_csv": (
                identification.write_csv,
                (tmp / "w.csv", LOG.t, LOG.q, LOG.tau),
                {},
            ),
            # control
            "control.slotine_li_regressor_classical": (
                control.slotine_li_regressor_classical,
                (ROBOT, Q, Z, Z, Z),
                {"rotor": True},
            ),
            "control.simulate_inverse": (
                control.simulate_inverse,
                (ROBOT, control.SumOfSines(ROBOT, period=0.5)),
                {"rate": 100.0},
            ),
            "control.summary": (control.summary, (sim,), {}),
            "control.perturbed_parameters": (
                control.perturbed_parameters,
                (ROBOT.params, 0.1),
                {"seed": 1},
            ),
            "control.consistent_perturbation": (
                control.consistent_perturbation,
                (ROBOT, P13, 0.1),
                {"seed": 1},
            ),
            "control.default_gains": (control.default_gains, (ROBOT,), {"period": 0.004}),
            "control.default_observer_gain": (control.default_observer_gain, (0.004,), {}),
            "control.calibrate_thresholds": (
                control.calibrate_thresholds,
                (np.abs(LOG.tau[:50]),),
                {"quantile": 0.99, "margin": 1.5},
            ),
            "control.default_controller": (control.default_controller, (ROBOT, P13), {}),
            # inverse kinematics
            "inverse_kinematics.ik_solve": (inverse_kinematics.ik_solve, (ROBOT, T0), {}),
            "inverse_kinematics.pose_error": (inverse_kinematics.pose_error, (T0, T0), {}),
            "inverse_kinematics.pose_rank": (inverse_kinematics.pose_rank, (ROBOT,), {}),
            "inverse_kinematics.pose_from_xyz_rpy": (
                inverse_kinematics.pose_from_xyz_rpy,
                (np.zeros(3), np.zeros(3)),
                {},
            ),
            "inverse_kinematics.damped_pinv": (
                inverse_kinematics.damped_pinv,
                (ROBOT.jacobian(Q),),
                {"damping": 0.05},
            ),
            "inverse_kinematics.velocity_ik": (
                inverse_kinematics.velocity_ik,
                (ROBOT, Q, np.zeros(3)),
                {"task": "position", "damping": 0.05},
            ),
            "inverse_kinematics.limits_gradient": (
                inverse_kinematics.limits_gradient,
                (ROBOT, Q),
                {},
            ),
            "Robot.with_drive_side": (ROBOT.with_drive_side, ("joint",), {}),
            "Robot.with_joint_terms": (
                ROBOT.with_joint_terms,
                (),
                {
                    "rotor": np.full(ROBOT.n, 0.1),
                    "viscous": np.full(ROBOT.n, 0.2),
                    "coulomb": np.full(ROBOT.n, 0.3),
                    "offset": np.full(ROBOT.n, -0.4),
                    "drive_side": "joint",
                },
            ),
            "BaseParameters.with_friction_velocity": (
                smooth.with_friction_velocity,
                ([0.2, 0.2],),
                {},
            ),
            "control.alarm_intervals": (
                control.alarm_intervals,
                (LOG.t, LOG.tau, np.ones(N)),
                {},
            ),
            "control.score_alarms": (
                control.score_alarms,
                (
                    [{"joint": 1, "start": 0.1, "end": 0.2, "peak": 1.0}],
                    [{"start_s": 0.05, "stop_s": 0.15}],
                ),
                {"settle": 0.01},
            ),
            "control.check_gains": (control.check_gains, (ROBOT, GAINS), {"kind": "pd"}),
            "control.check_sampled_gains": (
                control.check_sampled_gains,
                ("pd", kp, kd, lam, 0.004),
                {},
            ),
            "control.load_gains": (control.load_gains, (f["gains"], ROBOT), {"period": 0.004}),
            "control.load_reference": (control.load_reference, (f["reference"], N), {}),
            "control.load_thresholds": (control.load_thresholds, (f["thresholds"], ROBOT), {}),
            "control.make_controller": (
                control.make_controller,
                ("pd", ROBOT, GAINS),
                {"period": 0.004},
            ),
            "control.residual_uncertainty": (
                control.residual_uncertainty,
                (observer, np.ones(BASE.n), LOG.q[:20], LOG.dq[:20]),
                {},
            ),
            "control.simulate": (
                control.simulate,
                (ROBOT, control.SumOfSines(ROBOT, period=0.5)),
                {"duration": 0.1, "rate": 250.0, "seed": 1},
            ),
            "control.write_tracking_report": (
                control.write_tracking_report,
                (closed, tmp / "report"),
                {},
            ),
            "identification.identify_consistent": (
                identification.identify_consistent,
                (ROBOT, LOG),
                {"prior_weight": 1e-3},
            ),
            "identification.select_friction_model": (
                identification.select_friction_model,
                (ROBOT, [LOG]),
                {"kind": "coulomb", "folds": 2},
            ),
            "inverse_kinematics.circle_path": (
                inverse_kinematics.circle_path,
                (T0, 0.05, 2.0),
                {"normal": [0.0, 0.0, 1.0]},
            ),
            "inverse_kinematics.line_path": (inverse_kinematics.line_path, (T0, T0, 1.0), {}),
            "inverse_kinematics.resolved_rate": (
                inverse_kinematics.resolved_rate,
                (ROBOT, Q, inverse_kinematics.line_path(T0, T0, 0.1), 0.1),
                {"dt": 0.01, "gain": 5.0},
            ),
            "export.read_joint_terms": (export.read_joint_terms, (f["sidecar"],), {}),
            "export.write_urdf": (export.write_urdf, (two, two_classical, tmp / "w.urdf"), {}),
            "mjcf.write_mjcf": (mjcf.write_mjcf, (two, two_classical, tmp / "w.xml"), {}),
            "mjcf.check_joints": (mjcf.check_joints, (two,), {}),
            # export
            "export.classical_terms": (export.classical_terms, (ROBOT, classical), {}),
            "export.write_yaml": (
                export.write_yaml,
                (TABLE, dict(zip(TABLE.param_names, TABLE.params)), tmp / "w.yaml"),
                {"source": None},
            ),
        },
    }


def _multidof() -> tuple[mindyn.Robot, np.ndarray, np.ndarray]:
    """A random tree of every joint kind (revolute, prismatic, spherical, universal,
    cylindrical, planar, floating) and a configuration and a velocity of it."""
    import tempfile

    from random_tree import random_multidof_tree_yaml

    with tempfile.TemporaryDirectory() as d:
        robot = mindyn.load(random_multidof_tree_yaml(Path(d) / "tree.yaml", n=7, seed=1))
    quat = [0.1, -0.2, 0.3, np.sqrt(1 - 0.14)]
    q_of = {
        "spherical": quat,
        "universal": [0.3, -0.2],
        "cylindrical": [0.1, 0.4],
        "planar": [0.1, 0.2, np.cos(0.5), np.sin(0.5)],
        "floating": [0.1, 0.2, 0.3, *quat],
    }
    q = np.concatenate([q_of.get(kind, [0.3]) for kind in robot.joint_types])
    return robot, q, np.linspace(-1.0, 1.0, robot.nv)


def _multidof_api() -> dict:
    """Baseline calls of the functions that take a robot with multi-DOF joints, which take
    their own paths (q of nq entries, the others of nv)."""
    r, q, v = _multidof()
    assert not r.single_dof and len(set(r.joint_types)) == 7
    base = mindyn.base_parameters(r)
    calls = {
        "Robot.inverse_dynamics": (r.inverse_dynamics, (q, v, v, r.params), {}),
        "Robot.regressor": (r.regressor, (q, v, v), {"rotor": False, "friction": False}),
        "Robot.gravity_torque": (r.gravity_torque, (q,), {}),
        "Robot.mass_matrix": (r.mass_matrix, (q,), {}),
        "Robot.link_poses": (r.link_poses, (q,), {}),
        "Robot.momentum": (r.momentum, (q, v, r.params), {}),
        "Robot.forward_dynamics": (r.forward_dynamics, (q, v, v), {}),
        "Robot.kinetic_energy": (r.kinetic_energy, (q, v), {}),
        "Robot.potential_energy": (r.potential_energy, (q,), {}),
        "Robot.energy": (r.energy, (q, v), {}),
        "Robot.fk": (r.fk, (q,), {"link": 0}),
        "Robot.jacobian": (r.jacobian, (q,), {}),
        "BaseParameters.regressor": (base.regressor, (q, v, v), {}),
        "mindyn.coriolis_matrix": (mindyn.coriolis_matrix, (r, q, v), {}),
        "control.slotine_li_regressor_classical": (
            control.slotine_li_regressor_classical,
            (r, q, v, v, v),
            {"rotor": False},
        ),
    }
    return {f"{name}[multi-DOF]": call for name, call in calls.items()}


def _codegen_api(tmp: Path) -> dict:
    """Baseline calls of mindyn.codegen: generation, parameter files, controller and observer
    steps (their C compiled), PLCopen projects and the runtime base dynamics."""
    p = BASE.values(ROBOT.params)
    names_file = tmp / "params.json"
    names_file.write_text(json.dumps(dict(zip(BASE.names, p.tolist()))))
    ident_file = tmp / "id.json"
    ident = {"robot": ROBOT.name, "names": BASE.names, "values": p.tolist(), "removed": []}
    ident_file.write_text(json.dumps(ident | {"rotor": False, "friction": False}))
    st = codegen.generate(ROBOT, lang="st", base=BASE)
    names = {"name": "two", "header_name": "two.h"}
    code = codegen.generate(ROBOT, base=BASE, **names)
    ctl_code = codegen.generate_controller(ROBOT, base=BASE, gains=GAINS, params=p)
    obs_code = codegen.generate_observer(ROBOT, base=BASE, params=p)
    ctl = codegen.CompiledController(ctl_code, BASE)
    obs = codegen.CompiledObserver(obs_code)
    bd = codegen.BaseDynamics(BASE)
    return {
        "codegen.generate": (
            codegen.generate,
            (ROBOT,),
            {"lang": "c", "what": "id,gravity", "rotor": False, "friction": False, "params": p}
            | {"numeric": False, "base": True, "minimise": "operations", "trig": "inline"}
            | {"offset": False, "contacts": (), "wrench_frame": "world"}
            | names,
        ),
        "codegen.generate_controller": (
            codegen.generate_controller,
            (ROBOT, "adaptive-pd"),
            {"lang": "c", "base": BASE, "gains": GAINS, "params": p, "period": 0.004}
            | {"p_min": -100.0, "p_max": 100.0, "tau_max": 50.0, "trig": "libm"}
            | names,
        ),
        "codegen.generate_observer": (
            codegen.generate_observer,
            (ROBOT,),
            {"lang": "c", "base": BASE, "params": p, "period": 0.004, "gains": [20.0, 20.0]}
            | {"held_torque": True, "trig": "inline"}
            | names,
        ),
        "codegen.read_parameter_file": (codegen.read_parameter_file, (names_file, BASE.names), {}),
        "codegen.read_identified_parameters": (
            codegen.read_identified_parameters,
            (ident_file, BASE.names),
            {"robot": ROBOT, "rotor": False, "friction": False, "offset": False},
        ),
        "codegen.plcopen_project": (codegen.plcopen_project, ([st], "two"), {"comment": "c"}),
        "codegen.generation.identifier": (codegen.generation.identifier, ("two arms",), {}),
        "codegen.GeneratedCode.write": (code.write, (tmp / "two.c",), {}),
        "codegen.BaseDynamics": (codegen.BaseDynamics, (BASE,), {}),
        "codegen.BaseDynamics.inverse_dynamics": (bd.inverse_dynamics, (Q, Z, Z, p), {}),
        "codegen.BaseDynamics.gravity": (bd.gravity, (Q, p), {}),
        "codegen.BaseDynamics.regressor": (bd.regressor, (Q, Z, Z), {}),
        "codegen.CompiledController": (codegen.CompiledController, (ctl_code, BASE), {}),
        "codegen.CompiledController.__call__": (ctl.__call__, (0.0, Q, Z, Q, Z, Z), {}),
        "codegen.CompiledObserver": (codegen.CompiledObserver, (obs_code,), {}),
        "codegen.CompiledObserver.__call__": (obs.__call__, (Q, Z, Z), {}),
    }


# Functions of the enumeration without a walk here, and why.
NOT_WALKED = {
    "mindyn.bundled_robots": "takes no argument",
    "BaseParameters.formula_terms": "takes no argument",
    "BaseParameters.symbolic": "takes no argument",
    "codegen.GeneratedCode": "the result of generate, not built by the user",
    "codegen.GeneratedController": "the result of generate_controller, not built by the user",
    "codegen.GeneratedObserver": "the result of generate_observer, not built by the user",
    "codegen.CompiledController.reset": "takes no argument",
    "codegen.CompiledObserver.reset": "takes no argument",
}

# Wrong values of the right type where the generic ones (NaN for numbers, a NaN entry for
# arrays, 'no-such-choice' for strings, 2 for flags, -10**9 for integers) are not wrong, or
# SKIP where there is none (a file, a log, a result).
WRONG_VALUE: dict[tuple[str, str], object] = {
    ("mindyn.load", "robot"): SKIP,  # an unknown name is a ModelError (not an argument's type)
    ("Robot.joint_transform", "k"): 5,
    ("control.score_alarms", "alarms"): [{"joint": 1}],  # no start
    ("control.score_alarms", "spans"): [{"start_s": float("nan"), "stop_s": 1.0}],
    ("identification.excitation.effort_acceleration_limits", "fixed"): -np.ones(2),
    ("Robot.joint_pre", "k"): 5,
    ("Robot.joint_post", "k"): -1,
    ("Robot.fk", "link"): 7,
    ("Robot.fk[multi-DOF]", "link"): 7,
    ("Robot.with_drive_side", "side"): "motors",
    ("control.check_gains", "kind"): "lqr",
    ("control.check_sampled_gains", "kind"): "lqr",
    ("control.make_controller", "kind"): "lqr",
    ("control.load_reference", "n"): 0,
    ("control.simulate", "seed"): -1,
    ("identification.select_friction_model", "folds"): 1,
    ("formulas.unit_formula", "name"): SKIP,  # any name
    ("control.stability.check_loop", "kind"): SKIP,  # a label
    ("identification.document.read_identification", "source"): SKIP,  # a missing file
    ("identification.preprocess.require_even_stamps", "filter"): SKIP,  # others are let by
    ("identification.consistent.consistent_estimate", "prior_weight"): -1.0,
    # the values of a log: the DataErrors of differentiate name the log's file
    ("identification.data.differentiate", "x"): SKIP,
    ("identification.data.differentiate", "filter"): SKIP,
    # its message names the gain 'lambda', as gains files do
    ("control.check_sampled_gains", "lam"): SKIP,
    # a topic the bag does not have, a unit the log does not say: DataErrors naming the bag
    ("identification.rosbag.read_rosbag", "topic"): SKIP,
    ("identification.rosbag.read_rosbag", "torque_unit"): SKIP,
    ("identification.excitation.check_sampling", "rate"): 0.5,  # below twice the top harmonic
    ("export.classical_terms", "classical"): {"XX9": 1.0},  # no name of the robot's
    ("codegen.generate_controller", "gains"): {"kd": 1.0, "lamda": 5.0},  # a key misspelt
    ("codegen.generate_controller", "p_min"): 200.0,  # above p_max
    ("codegen.generate_controller", "tau_max"): -1.0,
    ("codegen.generate_observer", "gains"): [20.0, 1000.0],  # beyond 2 / period
    ("codegen.read_parameter_file", "names"): ["a", "a"],
    ("codegen.plcopen_project", "codes"): [codegen.generate("planar1")],  # C, not ST
    ("codegen.plcopen_project", "project"): "",
    ("codegen.plcopen_project", "comment"): SKIP,  # any text
    ("codegen.generation.identifier", "name"): "",
}


def _names(fn) -> list[str]:
    return list(inspect.signature(fn).parameters)


def _arguments(fn, args: tuple, kwargs: dict) -> list[tuple[str, object, bool]]:
    """(name, baseline value, given by keyword) of each argument of a baseline call."""
    names = _names(fn)
    return [(names[i], v, False) for i, v in enumerate(args)] + [
        (k, v, True) for k, v in kwargs.items()
    ]


# arguments with no wrong value of their type: a path (a missing file is a file error, not an
# argument's) and a label that only names things in messages
ANY_VALUE = {"path", "folder", "csv_path", "directory", "where", "title"}


def _generic_wrong_value(v):
    if isinstance(v, (bool, np.bool_)):
        return 2
    if isinstance(v, (int, np.integer)):
        return -(10**9)
    if isinstance(v, (float, np.floating)):
        return float("nan")
    if isinstance(v, str):
        return "no-such-choice"
    if isinstance(v, list) and v and all(isinstance(x, (int, float)) for x in v):
        return [float("nan")] * len(v)
    if isinstance(v, np.ndarray) and v.dtype.kind == "f" and v.size:
        bad = v.copy()
        bad.flat[0] = np.nan
        return bad
    return SKIP


@pytest.fixture(scope="module")
def api(tmp_path_factory):
    return _api(tmp_path_factory.mktemp("api"))


def _enumerated() -> dict:
    """The public functions of the package by qualified name, found from the package itself:
    the functions in the ``__all__`` of the package, its subpackages and their modules, and
    the public methods of Robot and BaseParameters."""
    import importlib

    modules = ["mindyn", "mindyn.inverse_kinematics", "mindyn.export", "mindyn.mjcf"]
    modules += ["mindyn.formulas", "mindyn.identification", "mindyn.control", "mindyn.codegen"]
    for package in ("identification", "control", "codegen"):
        folder = Path(mindyn.__file__).parent / package
        modules += [f"mindyn.{package}.{p.stem}" for p in sorted(folder.glob("[!_]*.py"))]
    out = {}
    for name in modules:
        module = importlib.import_module(name)
        for public in getattr(module, "__all__", []):
            obj = getattr(module, public)
            if inspect.isfunction(obj) or inspect.isbuiltin(obj):
                out[f"{name.removeprefix('mindyn.')}.{public}"] = obj
    for cls in (Robot, BaseParameters):
        for name, obj in vars(cls).items():
            if not name.startswith("_") and inspect.isfunction(obj):
                out[f"{cls.__name__}.{name}"] = obj
    for public in codegen.__all__:  # the classes of codegen: constructors and methods
        cls = getattr(codegen, public)
        if not inspect.isclass(cls):
            continue
        out[f"codegen.{public}"] = cls
        for name, obj in vars(cls).items():
            if (not name.startswith("_") or name == "__call__") and inspect.isfunction(obj):
                out[f"codegen.{public}.{name}"] = obj
    return out


def test_every_enumerated_public_function_is_walked(api):
    found = _enumerated()
    assert {"mindyn.load", "identification.identify", "Robot.regressor"} <= found.keys()
    assert "identification.excitation.optimize_excitation" in found
    assert {"codegen.generate", "codegen.BaseDynamics.gravity"} <= found.keys()
    walked = {getattr(fn, "__func__", fn) for fn, _, _ in api.values()}
    missing = sorted(
        name for name, obj in found.items() if obj not in walked and name not in NOT_WALKED
    )
    assert not missing, f"public functions without a baseline call: {missing}"


def _walk_ids() -> list[str]:
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        return sorted(_api(Path(d)))


WALK = _walk_ids()


def _check(name: str, arg: str, call, what: str) -> None:
    with pytest.raises(ArgumentError) as e:
        call()
    msg = str(e.value)
    assert "\n" not in msg, msg
    assert re.search(rf"(?<![\w.]){re.escape(arg)}(?!\w)", msg), (
        f"{name}: {what} for '{arg}' gave a message that does not name it: {msg}"
    )


@pytest.mark.parametrize("name", WALK)
def test_walk_wrong_types_and_values(api, name):
    fn, args, kwargs = api[name]
    fn(*args, **kwargs)  # the baseline is a valid call
    for i, (arg, value, by_keyword) in enumerate(_arguments(fn, args, kwargs)):

        def call_with(v, i=i, arg=arg, by_keyword=by_keyword):
            if by_keyword:
                return lambda: fn(*args, **{**kwargs, arg: v})
            a = list(args)
            a[i] = v
            return lambda: fn(*a, **kwargs)

        _check(name, arg, call_with(WRONG_TYPE), "a wrong type")
        wrong = WRONG_VALUE.get(
            (name, arg), SKIP if arg in ANY_VALUE else _generic_wrong_value(value)
        )
        if wrong is not SKIP:
            _check(name, arg, call_with(wrong), f"the wrong value {wrong!r}")


@pytest.mark.parametrize("name", WALK)
def test_options_after_the_data_are_keyword_only(api, name):
    fn, args, kwargs = api[name]
    params = inspect.signature(fn).parameters
    for k in kwargs:
        if k not in params:  # taken by **keywords: keyword-only by construction
            assert any(p.kind == inspect.Parameter.VAR_KEYWORD for p in params.values()), k
            continue
        assert params[k].kind == inspect.Parameter.KEYWORD_ONLY or k in DATA_WITH_DEFAULT, (
            f"{name}: option '{k}' can be given by position"
        )


def _all_finite(out, depth: int = 0) -> bool:
    """Whether every float in ``out`` (arrays, numbers, and the tuples, lists, dicts and
    dataclasses that hold them, four levels deep) is finite."""
    import dataclasses
    import numbers

    if depth > 4:
        return True
    if isinstance(out, (tuple, list)):
        return all(_all_finite(x, depth + 1) for x in out)
    if isinstance(out, dict):
        return all(_all_finite(x, depth + 1) for x in out.values())
    if dataclasses.is_dataclass(out) and not isinstance(out, type):
        return all(_all_finite(getattr(out, f.name), depth + 1) for f in dataclasses.fields(out))
    if isinstance(out, (np.ndarray, numbers.Number)) and not isinstance(out, bool):
        a = np.asarray(out)
        return not np.issubdtype(a.dtype, np.inexact) or bool(np.isfinite(a).all())
    return True


HUGE = 1e300  # finite, but its square overflows the double range
# the compiled generated C steps: generated code checks nothing (as the real-time C++ paths)
UNCHECKED = {"codegen.CompiledController.__call__", "codegen.CompiledObserver.__call__"}


@pytest.mark.filterwarnings("error::RuntimeWarning")
@pytest.mark.parametrize("name", WALK)
def test_huge_finite_inputs_raise_or_give_finite_results(api, name):
    """Every float array argument of the baseline with its first entry set to 1e300: the call
    raises a ``mindyn.Error`` in one line, or returns finite numbers wherever the baseline did:
    never a silent inf or NaN from an overflow, and no numpy RuntimeWarning (overflow) printed
    to the user on the way (a warning made an error here, so the call must not emit one)."""
    fn, args, kwargs = api[name]
    baseline_finite = _all_finite(fn(*args, **kwargs)) and name not in UNCHECKED
    for i, (arg, value, by_keyword) in enumerate(_arguments(fn, args, kwargs)):
        if not (isinstance(value, np.ndarray) and value.dtype.kind == "f" and value.size):
            continue
        huge = value.copy()
        huge.flat[0] = HUGE
        a, kw = list(args), dict(kwargs)
        if by_keyword:
            kw[arg] = huge
        else:
            a[i] = huge
        try:
            out = fn(*a, **kw)
        except mindyn.Error as e:
            assert "\n" not in str(e), f"{name}, {arg} = 1e300: {e}"
            continue
        assert _all_finite(out) or not baseline_finite, (
            f"{name}: {arg} with an entry of 1e300 gave a result with inf or NaN, silently"
        )


OVERFLOWING = {  # a velocity of 1e200: its square, in the velocity products, overflows
    "Robot.inverse_dynamics": lambda r, q, v: r.inverse_dynamics(q, v, 0 * q),
    "Robot.regressor": lambda r, q, v: r.regressor(q, v, 0 * q),
    "Robot.forward_dynamics": lambda r, q, v: r.forward_dynamics(q, v, 0 * q),
    "Robot.kinetic_energy": lambda r, q, v: r.kinetic_energy(q, v),
    "Robot.energy": lambda r, q, v: r.energy(q, v),
    "Robot.energy_regressors": lambda r, q, v: r.energy_regressors(q, v),
    "Robot.energy_regressor": lambda r, q, v: r.energy_regressor(q, v),
    "Robot.lagrangian_regressor": lambda r, q, v: r.lagrangian_regressor(q, v),
    "Robot.momentum_regressors": lambda r, q, v: r.momentum_regressors(q, v),
    "BaseParameters.regressor": lambda r, q, v: BASE.regressor(q, v, 0 * q),
    "BaseParameters.energy_regressor": lambda r, q, v: BASE.energy_regressor(q, v),
    "BaseParameters.momentum_regressors": lambda r, q, v: BASE.momentum_regressors(q, v),
    "slotine_li_regressor": lambda r, q, v: mindyn.slotine_li_regressor(BASE, q, v, v, 0 * q),
}


@pytest.mark.parametrize("name", OVERFLOWING)
@pytest.mark.parametrize("batch", [False, True])
def test_an_overflowing_result_names_the_function_and_the_input(name, batch):
    """A velocity of 1e200 on planar2 (finite; the dynamics square it: 1e400 overflows, and
    the unchecked result was NaN): ArgumentError naming the function and the velocity, one
    line; the same call at 1e100 gives finite numbers (no bound below the overflow)."""
    q, v = Q.copy(), np.array([1e200, 0.5])
    if batch:
        q, v = np.vstack([Q, q]), np.vstack([Z, v])
    with pytest.raises(ArgumentError) as e:
        OVERFLOWING[name](ROBOT, q, v)
    msg = str(e.value)
    assert "\n" not in msg and name.split(".")[-1] in msg and "overflows" in msg, msg
    where = "(sample 1, entry 1)" if batch else "(entry 1)"
    assert re.search(r"largest entries: dq\w* 1e\+200 " + re.escape(where), msg), msg
    out = OVERFLOWING[name](ROBOT, q, np.where(np.abs(v) > 1.0, 1e100, v))
    assert _all_finite(out)


# arguments with a default that are data, not options (they may be given by position)
DATA_WITH_DEFAULT = {"params", "q0", "t", "dq", "ddq", "robot", "controller", "p_hat"}


def test_base_parameters_method_auto_says_why_it_chose():
    from mindyn.base import choose_method

    auto = mindyn.base_parameters(ROBOT, method="auto")
    method, reason = choose_method(ROBOT)
    assert (auto.method, auto.method_reason) == (method, reason)
    assert mindyn.base_parameters(ROBOT).method_reason == reason
    given = mindyn.base_parameters(ROBOT, method="recursive")
    assert (given.method, given.method_reason) == ("recursive", "method='recursive'")


def test_identify_refuses_options_by_position():
    with pytest.raises(TypeError):
        identification.identify(ROBOT, LOG, "dynamic", True)


def test_identify_min_velocity_none_names_the_argument():
    with pytest.raises(ArgumentError, match=r"^min_velocity is None; expected a number"):
        identification.identify(ROBOT, LOG, min_velocity=None)


def test_argument_error_is_a_mindyn_error_value_error_and_type_error():
    assert issubclass(ArgumentError, mindyn.Error)
    assert issubclass(ArgumentError, ValueError) and issubclass(ArgumentError, TypeError)
    assert not issubclass(ArgumentError, mindyn.ModelError)


GETTERS = {
    "Robot.params": lambda: ROBOT.params,
    "Robot.rotor_inertia": lambda: ROBOT.rotor_inertia,
    "Robot.viscous": lambda: ROBOT.viscous,
    "Robot.coulomb": lambda: ROBOT.coulomb,
    "Robot.third_friction": lambda: ROBOT.third_friction,
    "Robot.axes": lambda: ROBOT.axes,
    "Robot.gravity": lambda: ROBOT.gravity,
    "Robot.tool": lambda: ROBOT.tool,
    "Robot.dh": lambda: mindyn.load("puma560").dh,
    "Robot.drive_matrix": lambda: ROBOT.drive_matrix,
    "Robot.limits[lower]": lambda: ROBOT.limits["lower"],
    "Robot.drives[gear_ratio]": lambda: ROBOT.drives["gear_ratio"],
    "Robot.friction_model[velocity]": lambda: ROBOT.with_friction_model(
        "smooth", velocity=[0.1, 0.1]
    ).friction_model["velocity"],
    "BaseParameters.Y": lambda: BASE.Y,
    "BaseParameters.Y with offsets": lambda: mindyn.base_parameters(ROBOT, offset=True).Y,
    "SimulationResult.error": lambda: (
        control.simulate_inverse(ROBOT, control.SumOfSines(ROBOT, period=0.5), rate=100.0).error
    ),
    "MomentumObserver.momentum": lambda: _observer().momentum,
    "MomentumObserver.beta": lambda: _observer().beta,
    "ConsistentResult.robot_params": lambda: (
        identification.identify_consistent(ROBOT, LOG, prior_weight=1e-3).robot_params
    ),
}


def _observer() -> control.MomentumObserver:
    o = control.MomentumObserver(BASE, BASE.values(ROBOT.params), period=0.004)
    o.run(LOG.q[:5], LOG.dq[:5], LOG.tau[:5])
    return o


@pytest.mark.parametrize("getter", GETTERS.values(), ids=GETTERS.keys())
def test_getters_return_read_only_arrays(getter):
    a = getter()
    assert isinstance(a, np.ndarray) and not a.flags.writeable
    before = a.copy()
    with pytest.raises(ValueError, match="read-only"):
        a.flat[0] = 1.0
    np.testing.assert_array_equal(getter(), before)


def test_an_assignment_to_an_entry_of_params_is_refused_not_lost():
    robot = mindyn.load("planar2")
    p = robot.params
    with pytest.raises(ValueError, match="read-only"):
        robot.params[3] = 1.0
    np.testing.assert_array_equal(robot.params, p)
    # the documented way: assign a whole vector
    q = robot.params.copy()
    q[3] = 1.0
    robot.params = q
    assert robot.params[3] == 1.0


def test_base_parameter_lists_and_reports_do_not_change_under_their_users():
    """What a base set gives as a list or a mapping (names, formulas, the rank report, each
    set's entries) is its reader's own: editing it leaves the set as a second computation of
    the same robot gives it, and the code generated from it (its header lists the formulas)."""
    robot = mindyn.load("puma560")
    bp = mindyn.base_parameters(robot)
    fresh = mindyn.base_parameters(robot)  # an independent computation to compare with
    bp.formulas.append("junk")
    bp.formulas[0] = "junk"
    bp.formulas_full.clear()
    bp.names.reverse()
    bp.no_effect.append("junk")
    bp.margin["tolerance"] = 5.0
    bp.margin["decided_by_tolerance"] = ["junk"]
    for kind in ("lagrangian", "energy", "eom"):
        bp.sets[kind]["names"].append("junk")
        bp.sets[kind]["formulas"].append("junk")
        bp.sets[kind]["margin"]["tolerance"] = 5.0
        with pytest.raises(ValueError, match="read-only"):
            bp.sets[kind]["Y"][0, 0] = 1.0
    assert bp.formulas == fresh.formulas and len(bp.formulas) == 36
    assert bp.formulas_full == fresh.formulas_full
    assert bp.names == fresh.names and bp.no_effect == fresh.no_effect
    assert bp.margin == fresh.margin and bp.margin["tolerance"] == 1e-9
    for kind in ("lagrangian", "energy", "eom"):
        for key in ("names", "formulas", "margin"):
            assert bp.sets[kind][key] == fresh.sets[kind][key], (kind, key)
        np.testing.assert_array_equal(bp.sets[kind]["Y"], fresh.sets[kind]["Y"])
    header = codegen.generate(robot, base=bp, name="p560").header
    assert "junk" not in header and fresh.formulas[0] in header


def test_the_mapping_of_sets_and_the_symbolic_formulas_do_not_change_under_their_users():
    """``sets`` itself (not only each set) is read-only: replacing or deleting a set was kept
    and broke ``margin`` and ``no_effect`` for every later user. ``symbolic()`` gives each
    caller its own lists and dicts: an edit of one was the next caller's formulas."""
    bp = mindyn.base_parameters("puma560")
    fresh = mindyn.base_parameters("puma560")
    with pytest.raises(TypeError):
        bp.sets["eom"] = {}
    with pytest.raises(TypeError):
        del bp.sets["eom"]
    assert sorted(bp.sets) == ["energy", "eom", "lagrangian"]
    assert bp.no_effect == fresh.no_effect and bp.margin == fresh.margin
    sym = bp.symbolic()
    sym.formulas.append(sym.formulas[0])
    sym.symbols.clear()
    sym.names[0] = "junk"
    again, other = bp.symbolic(), fresh.symbolic()
    assert again.text == other.text and len(again.formulas) == bp.n == 36
    assert again.symbols == other.symbols and again.names == other.names
