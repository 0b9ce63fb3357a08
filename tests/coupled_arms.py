"""Two arms with coupled transmissions for the tests, written as URDF with ros_control's ROS 1
transmissions: a 6R arm whose wrist is a four-bar linkage (motor 6 turns with q5 + q6) and a
WAM-like 7R arm with cable differentials on joints 2-3 and 5-6. Their matrices T (q_m = T q) are
returned as ros_control documents them, for the tests' own computations; the inertial values are
generic (offset centres of mass, products of inertia through rotated inertia frames)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

PREFIX = "transmission_interface/"


def _links_and_joints(axes, origins, rpys, seed):
    rng = np.random.default_rng(seed)
    links = ["<link name='base'/>"]
    joints = []
    for k, (axis, xyz, rpy) in enumerate(zip(axes, origins, rpys, strict=True), start=1):
        com = rng.uniform(-0.08, 0.08, 3)
        irpy = rng.uniform(-1, 1, 3)
        ixx, iyy, izz = rng.uniform(0.01, 0.05, 3)
        izz = min(izz, ixx + iyy - 1e-3)  # triangle inequality
        links.append(
            f"<link name='l{k}'><inertial><origin xyz='{com[0]} {com[1]} {com[2]}' "
            f"rpy='{irpy[0]} {irpy[1]} {irpy[2]}'/><mass value='{rng.uniform(0.5, 4.0)}'/>"
            f"<inertia ixx='{ixx}' ixy='0' ixz='0' iyy='{iyy}' iyz='0' izz='{izz}'/>"
            "</inertial></link>"
        )
        parent = "base" if k == 1 else f"l{k - 1}"
        joints.append(
            f"<joint name='j{k}' type='revolute'><parent link='{parent}'/><child link='l{k}'/>"
            f"<origin xyz='{xyz}' rpy='{rpy}'/><axis xyz='{axis}'/>"
            "<limit lower='-3' upper='3' effort='100' velocity='3'/></joint>"
        )
    return links, joints


def _simple(joint, motor, reduction):
    return (
        f"<transmission name='t_{joint}'><type>{PREFIX}SimpleTransmission</type>"
        f"<joint name='{joint}'><hardwareInterface>x</hardwareInterface></joint>"
        f"<actuator name='{motor}'><mechanicalReduction>{reduction}</mechanicalReduction>"
        "</actuator></transmission>"
    )


def _pair(kind, name, joints, motors, a, j):
    parts = []
    for r in range(2):
        parts.append(
            f"<actuator name='{motors[r]}'><role>actuator{r + 1}</role>"
            f"<mechanicalReduction>{a[r]}</mechanicalReduction></actuator>"
        )
    for r in range(2):
        parts.append(
            f"<joint name='{joints[r]}'><role>joint{r + 1}</role>"
            f"<mechanicalReduction>{j[r]}</mechanicalReduction></joint>"
        )
    return f"<transmission name='{name}'><type>{PREFIX}{kind}</type>{''.join(parts)}</transmission>"


def coupled_wrist_urdf(path: Path) -> tuple[Path, np.ndarray]:
    """A 6R arm (axes z y y z y z, offsets as an industrial arm's) whose joints 1-4 have simple
    transmissions and whose wrist joints 5-6 a four-bar linkage: q_m5 = 40 q5,
    q_m6 = 30 (q5 + q6). Returns the path and T."""
    axes = ["0 0 1", "0 1 0", "0 1 0", "0 0 1", "0 1 0", "0 0 1"]
    origins = ["0 0 0.4", "0.05 0.1 0", "0 0 0.45", "0.04 -0.05 0.1", "0 0 0.35", "0 0 0.08"]
    rpys = ["0 0 0", "0 0 0.3", "0 0 0", "0 0 -0.2", "0 0 0", "0 0 0.1"]
    links, joints = _links_and_joints(axes, origins, rpys, seed=6)
    red = [100.0, -80.0, 60.0, 50.0]
    tr = [_simple(f"j{k}", f"m{k}", red[k - 1]) for k in range(1, 5)]
    tr.append(
        _pair("FourBarLinkageTransmission", "wrist", ["j5", "j6"], ["m5", "m6"], [40, 30], [1, 1])
    )
    path = Path(path)
    path.write_text("<robot name='wrist6'>" + "".join(links + joints + tr) + "</robot>")
    T = np.zeros((6, 6))
    for k in range(4):
        T[k, k] = red[k]
    T[4, 4] = 40.0
    T[5, 4] = T[5, 5] = 30.0
    return path, T


def wam_like_urdf(path: Path) -> tuple[Path, np.ndarray]:
    """A 7R arm (axes z y z y z y z as the Barrett WAM's) with simple transmissions on joints 1,
    4 and 7 and cable differentials on joints 2-3 and 5-6:
    q_m = a (q_j1 + q_j2), a (q_j1 - q_j2) for each pair. Returns the path and T."""
    axes = ["0 0 1", "0 1 0", "0 0 1", "0 1 0", "0 0 1", "0 1 0", "0 0 1"]
    origins = [
        "0 0 0.35",
        "0 0 0",
        "0 0 0.1",
        "0.045 0 0.45",
        "-0.045 0 0.1",
        "0 0 0.3",
        "0 0 0.06",
    ]
    rpys = ["0 0 0", "0 0 0", "0 0 0", "0 0 0", "0 0 0", "0 0 0", "0 0 0"]
    links, joints = _links_and_joints(axes, origins, rpys, seed=7)
    tr = [  # in the order of the motors (rows of T)
        _simple("j1", "m1", 42.0),
        _pair("DifferentialTransmission", "shoulder", ["j2", "j3"], ["m2", "m3"], [28, 20], [1, 1]),
        _simple("j4", "m4", 18.0),
        _pair("DifferentialTransmission", "wrist", ["j5", "j6"], ["m5", "m6"], [9.5, 9.5], [1, 1]),
        _simple("j7", "m7", 14.9),
    ]
    path = Path(path)
    path.write_text("<robot name='wam7'>" + "".join(links + joints + tr) + "</robot>")
    T = np.zeros((7, 7))
    T[0, 0], T[3, 3], T[6, 6] = 42.0, 18.0, 14.9
    T[1, 1], T[1, 2], T[2, 1], T[2, 2] = 28.0, 28.0, 20.0, -20.0
    T[4, 4], T[4, 5], T[5, 4], T[5, 5] = 9.5, 9.5, 9.5, -9.5
    return path, T


def motor_values(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Motor-side rotor inertia [kg m^2], viscous [N m s/rad] and Coulomb [N m] values of a
    typical size for motors behind the reductions above."""
    rng = np.random.default_rng(seed)
    return (
        rng.uniform(1e-5, 1e-4, n),
        rng.uniform(1e-4, 1e-3, n),
        rng.uniform(0.01, 0.05, n),
    )


def motor_terms(T, Ia, Fv, Fc, dq, ddq) -> np.ndarray:
    """T^T (Ia T ddq + Fv T dq + Fc sign(T dq)) written out, for one state."""
    vm = T @ dq
    am = T @ ddq
    return T.T @ (Ia * am + Fv * vm + Fc * np.sign(vm))
