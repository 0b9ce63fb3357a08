"""Bad arguments to the public Python API: every one gives a mindyn.ArgumentError (a ValueError
and a TypeError) whose message names the argument, instead of a pybind11 "incompatible function
arguments" error, a numpy error or a wrong number."""

from __future__ import annotations

import mindyn
import numpy as np
import pytest
from mindyn import codegen
from mindyn.control import coriolis_matrix, slotine_li_regressor, slotine_li_regressor_classical
from mindyn.inverse_kinematics import (
    damped_pinv,
    ik_solve,
    pose_error,
    pose_from_xyz_rpy,
    velocity_ik,
)

ROBOT = mindyn.load("puma560")
BASE = mindyn.base_parameters(ROBOT)
BD = codegen.BaseDynamics(BASE)
Z = np.zeros(6)
T0 = ROBOT.fk(Z)

nan6 = Z.copy()
nan6[2] = np.nan
inf6 = Z.copy()
inf6[0] = np.inf

# bad values for an argument that wants a (6,) or (m, 6) array
BAD_SAMPLES = {
    "None": None,
    "string": "0 0 0 0 0 0",
    "scalar": 0.5,
    "short list": [0.0] * 5,
    "long array": np.zeros(7),
    "3-D": np.zeros((2, 6, 1)),
    "wrong width": np.zeros((3, 5)),
    "complex": np.zeros(6, dtype=complex),
    "ragged": [[0.0] * 6, [0.0] * 5],
    "objects": [None] * 6,
    "NaN": nan6,
    "inf": inf6,
}

# (call with the bad value in place of the named argument, argument name)
PER_SAMPLE = {
    "inverse_dynamics q": (lambda x: ROBOT.inverse_dynamics(x, Z, Z), "q"),
    "inverse_dynamics dq": (lambda x: ROBOT.inverse_dynamics(Z, x, Z), "dq"),
    "inverse_dynamics ddq": (lambda x: ROBOT.inverse_dynamics(Z, Z, x), "ddq"),
    "regressor ddq": (lambda x: ROBOT.regressor(Z, Z, x), "ddq"),
    "gravity_torque q": (lambda x: ROBOT.gravity_torque(x), "q"),
    "mass_matrix q": (lambda x: ROBOT.mass_matrix(x), "q"),
    "forward_dynamics tau": (lambda x: ROBOT.forward_dynamics(Z, Z, x), "tau"),
    "kinetic_energy dq": (lambda x: ROBOT.kinetic_energy(Z, x), "dq"),
    "potential_energy q": (lambda x: ROBOT.potential_energy(x), "q"),
    "energy q": (lambda x: ROBOT.energy(x, Z), "q"),
    "energy_regressors dq": (lambda x: ROBOT.energy_regressors(Z, x), "dq"),
    "energy_regressor q": (lambda x: ROBOT.energy_regressor(x, Z), "q"),
    "lagrangian_regressor dq": (lambda x: ROBOT.lagrangian_regressor(Z, x), "dq"),
    "fk q": (lambda x: ROBOT.fk(x), "q"),
    "jacobian q": (lambda x: ROBOT.jacobian(x), "q"),
    "BaseParameters.regressor dq": (lambda x: BASE.regressor(Z, x, Z), "dq"),
    "BaseParameters.energy_regressor q": (lambda x: BASE.energy_regressor(x, Z), "q"),
    "slotine_li_regressor dqr": (lambda x: slotine_li_regressor(BASE, Z, Z, x, Z), "dqr"),
    "slotine_li_regressor_classical ddqr": (
        lambda x: slotine_li_regressor_classical(ROBOT, Z, Z, Z, x),
        "ddqr",
    ),
    "coriolis_matrix dq": (lambda x: coriolis_matrix(ROBOT, Z, x), "dq"),
    "BaseDynamics.inverse_dynamics q": (lambda x: BD.inverse_dynamics(x, Z, Z), "q"),
    "BaseDynamics.gravity q": (lambda x: BD.gravity(x), "q"),
    "BaseDynamics.regressor ddq": (lambda x: BD.regressor(Z, Z, x), "ddq"),
    "ik q0": (lambda x: ik_solve(ROBOT, T0, x), "q0"),
    "velocity_ik q": (lambda x: velocity_ik(ROBOT, x, Z), "q"),
}
SINGLE_ONLY = {"fk q", "jacobian q", "ik q0", "velocity_ik q"}


def _cases():
    for fname, (call, arg) in PER_SAMPLE.items():
        for vname, value in BAD_SAMPLES.items():
            if fname in SINGLE_ONLY and vname == "wrong width":
                continue
            if fname == "ik q0" and vname == "None":  # q0=None: the middle of the limits
                continue
            yield pytest.param(call, arg, value, id=f"{fname}-{vname}")


@pytest.mark.parametrize("call, arg, value", list(_cases()))
def test_bad_per_sample_argument(call, arg, value):
    with pytest.raises(mindyn.ArgumentError) as e:
        call(value)
    msg = str(e.value)
    assert msg.startswith(f"{arg} "), msg
    assert "\n" not in msg


P60 = ROBOT.params
BAD_PARAMS = {
    "scalar": 1.0,
    "string": "params",
    "wrong length": np.zeros(59),
    "2-D": np.zeros((6, 10)),
    "NaN": np.where(np.arange(60) == 4, np.nan, P60),
    "complex": P60.astype(complex),
}
OTHER = {
    "inverse_dynamics params": (lambda x: ROBOT.inverse_dynamics(Z, Z, Z, x), "params"),
    "mass_matrix params": (lambda x: ROBOT.mass_matrix(Z, x), "params"),
    "energy params": (lambda x: ROBOT.energy(Z, Z, x), "params"),
    "coriolis_matrix params": (lambda x: coriolis_matrix(ROBOT, Z, Z, x), "params"),
    "params setter": (lambda x: setattr(ROBOT, "params", x), "params"),
    "BaseParameters.values": (lambda x: BASE.values(x), "params"),
}


@pytest.mark.parametrize("call, arg", OTHER.values(), ids=OTHER.keys())
@pytest.mark.parametrize("value", BAD_PARAMS.values(), ids=BAD_PARAMS.keys())
def test_bad_parameter_vector(call, arg, value):
    with pytest.raises(mindyn.ArgumentError) as e:
        call(value)
    assert str(e.value).startswith(f"{arg} "), str(e.value)


BAD_MISC = {
    "embed short": (lambda: BASE.embed(np.zeros(BASE.n - 1)), "base"),
    "embed None": (lambda: BASE.embed(None), "base"),
    "BaseDynamics p NaN": (lambda: BD.inverse_dynamics(Z, Z, Z, np.full(BD.np, np.nan)), "p"),
    "BaseDynamics p short": (lambda: BD.gravity(Z, np.zeros(3)), "p"),
    "codegen params": (lambda: codegen.generate(ROBOT, params=[1.0, 2.0]), "params"),
    "codegen rotor": (lambda: codegen.generate(ROBOT, rotor="yes"), "rotor"),
    "gravity short": (lambda: ROBOT.with_gravity([0, -9.81]), "gravity"),
    "gravity None": (lambda: ROBOT.with_gravity(None), "gravity"),
    "rotor_inertia": (lambda: setattr(ROBOT, "rotor_inertia", np.zeros(5)), "rotor_inertia"),
    "viscous NaN": (lambda: setattr(ROBOT, "viscous", nan6), "viscous"),
    "regressor rotor": (lambda: ROBOT.regressor(Z, Z, Z, rotor="no"), "rotor"),
    "parameters friction": (lambda: ROBOT.parameters(friction=None), "friction"),
    "joint_transform q": (lambda: ROBOT.joint_transform(0, "x"), "q"),
    "joint_transform q NaN": (lambda: ROBOT.joint_transform(0, np.nan), "q"),
    "fk link": (lambda: ROBOT.fk(Z, link=1.5), "link"),
    "base_parameters tolerance": (
        lambda: mindyn.base_parameters(ROBOT, tolerance=np.nan),
        "tolerance",
    ),
    "base_parameters samples": (
        lambda: mindyn.base_parameters(ROBOT, method="numerical", samples=-1),
        "samples",
    ),
    "base_parameters method": (lambda: mindyn.base_parameters(ROBOT, method="qr"), "method"),
    "base_parameters order": (lambda: mindyn.base_parameters(ROBOT, order=5), "order"),
    "base_parameters rotor": (lambda: mindyn.base_parameters(ROBOT, rotor="True"), "rotor"),
    "ik T_target shape": (lambda: ik_solve(ROBOT, np.eye(3)), "T_target"),
    "ik T_target NaN": (lambda: ik_solve(ROBOT, np.full((4, 4), np.nan)), "T_target"),
    "ik T_target None": (lambda: ik_solve(ROBOT, None), "T_target"),
    "ik tolerance": (lambda: ik_solve(ROBOT, T0, tolerance=0.0), "tolerance"),
    "ik max_attempts": (lambda: ik_solve(ROBOT, T0, max_attempts=2.5), "max_attempts"),
    "ik seed": (lambda: ik_solve(ROBOT, T0, seed=-1), "seed"),
    "pose_error T": (lambda: pose_error([1, 2, 3], T0), "T"),
    "pose_from_xyz_rpy xyz": (lambda: pose_from_xyz_rpy([1, 2], [0, 0, 0]), "xyz"),
    "pose_from_xyz_rpy rpy": (lambda: pose_from_xyz_rpy([1, 2, 3], [0, np.inf, 0]), "rpy"),
    "velocity_ik twist": (lambda: velocity_ik(ROBOT, Z, np.zeros(5)), "twist"),
    "velocity_ik nullspace": (lambda: velocity_ik(ROBOT, Z, Z, nullspace=[1.0]), "nullspace"),
    "damped_pinv J": (lambda: damped_pinv(np.zeros(6)), "J"),
    "damped_pinv damping": (lambda: damped_pinv(np.eye(3), damping=np.nan), "damping"),
    "inertial_from_com mass": (
        lambda: mindyn.inertial_from_com(None, [0, 0, 0], np.eye(3)),
        "mass",
    ),
    "inertial_from_com inertia": (lambda: mindyn.inertial_from_com(1.0, [0, 0, 0], Z), "inertia"),
    "inertial_from_urdf com": (
        lambda: mindyn.inertial_from_urdf(1.0, [0, 0], np.eye(3), np.eye(3)),
        "com",
    ),
    "to_pinocchio_order": (lambda: mindyn.to_pinocchio_order("x"), "params"),
    "from_pinocchio_order": (lambda: mindyn.from_pinocchio_order(np.zeros((2, 10))), "params"),
}


@pytest.mark.parametrize("call, arg", BAD_MISC.values(), ids=BAD_MISC.keys())
def test_bad_other_argument(call, arg):
    with pytest.raises(mindyn.ArgumentError) as e:
        call()
    assert str(e.value).startswith(f"{arg} "), str(e.value)


def test_message_states_expected_and_given():
    with pytest.raises(
        mindyn.ArgumentError, match=r"^dq has shape \(5,\); expected \(6,\) or \(m, 6\)$"
    ):
        ROBOT.inverse_dynamics(Z, np.zeros(5), Z)
    with pytest.raises(
        mindyn.ArgumentError, match=r"^q is None; expected an array of shape \(6,\)"
    ):
        ROBOT.gravity_torque(None)
    with pytest.raises(
        mindyn.ArgumentError, match=r"^q has dtype complex128; expected real numbers"
    ):
        ROBOT.mass_matrix(np.zeros(6, dtype=complex))
    with pytest.raises(mindyn.ArgumentError, match=r"^q contains NaN at sample 1, joint 3"):
        ROBOT.gravity_torque(np.stack([Z, nan6]))


def test_good_arguments_still_accepted():
    """Lists, integers and non-contiguous views are converted, not refused."""
    q = np.zeros((6, 2))[:, 0]  # strided view
    assert ROBOT.inverse_dynamics([0, 0, 0, 0, 0, 0], q, [0.0] * 6).shape == (6,)
    assert ROBOT.regressor(np.zeros(6, dtype=np.float32), Z, Z, rotor=1).shape == (6, 66)
