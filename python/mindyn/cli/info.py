"""CLI: ``mindyn info``, a robot model: joints, geometry, limits, transmissions, parameters."""

from __future__ import annotations

import argparse
import math

import numpy as np

from .. import _sidecar
from .._core import OFFSET_PREFIX as OFF
from .._mujoco import is_mjcf
from .args import add_command
from .robot_options import add_robot, load_robot


def _fmt(x: float, width: int = 10) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-".rjust(width)
    return f"{x:{width}.4g}"


def _transmission_lines(robot) -> list[str]:
    """The motors of the robot's transmissions, each with its row of ``q_m = T q + offset``."""
    tr = robot.transmission
    if tr is None:
        return []
    form = {
        "ros1": "URDF, ROS 1 form",
        "ros2": "URDF, ROS 2 form",
        "mjcf": "MJCF, fixed tendons over several joints as motors",
    }.get(tr.format, tr.format)
    if not robot.single_dof:
        acts = (
            "rotor inertia and friction are not modelled with joints of several degrees of freedom"
        )
    elif robot.drive_side == "motor":
        acts = "with --rotor / --friction the motors' rotor inertia and friction act through T"
    else:
        acts = "rotor inertia and friction stay on the joints (drive side: joint)"
    out = [
        "",
        f"transmissions ({form}): motor positions q_m = T q + offset, joint torques "
        f"tau = T^T tau_m; {acts}",
    ]
    w = max([5] + [len(m) for m in tr.motors]) + 1
    wt = max([4] + [len(t) for t in tr.types]) + 1
    # the torque constants currents are converted with (identify --torque-unit current)
    kt = np.asarray(tr.torque_constant, dtype=float)
    given = bool(np.isfinite(kt).any())
    head = f"{'K_t [N m/A]':>12}  " if given else ""
    out.append(f"{'#':<3} {'motor':<{w}}{'type':<{wt}}{head}q_m")
    for i, motor in enumerate(tr.motors):
        terms = [
            f"{tr.T[i, k]:+.6g} {robot.joint_names[k]}" for k in range(robot.n) if tr.T[i, k] != 0.0
        ]
        if tr.offset[i] != 0.0:
            terms.append(f"{tr.offset[i]:+.6g}")
        cell = (f"{kt[i]:>12.6g}  " if np.isfinite(kt[i]) else f"{'-':>12}  ") if given else ""
        out.append(f"{'m' + str(i + 1):<3} {motor:<{w}}{tr.types[i]:<{wt}}{cell}{' '.join(terms)}")
    return out


def _motor_terms(robot) -> list[str]:
    """The motors' rotor inertia and friction (slot k = motor k, motor units): what the dynamics
    with rotor inertia and friction use and ``identify --rotor --friction`` estimates."""
    third = _sidecar.FRICTION_MODELS[robot.friction_model["kind"]][0]
    columns = ["Ia", "Fv", "Fc"] + ([third] if third else [])
    slots = robot.parameters(rotor=True, friction=True).reshape(robot.n, -1)[:, 10:]
    w = max([5] + [len(m) for m in robot.transmission.motors]) + 1
    out = [
        "",
        "rotor inertia and friction on the motors (slot k: motor k's, in motor units; what "
        "--rotor / --friction use and identify; the motor's own where the description or "
        "joint-terms file gives them, else a joint's value divided by r^2, r^2, |r| for a "
        "motor alone on it with ratio r, 0 for a coupled motor)",
        f"{'#':<3} {'motor':<{w}}" + "".join(f"{c:>11}" for c in columns),
    ]
    for i, motor in enumerate(robot.transmission.motors):
        out.append(f"{'m' + str(i + 1):<3} {motor:<{w}}" + "".join(f"{v:11.4g}" for v in slots[i]))
    return out


def _offset_lines(robot, w: int) -> list[str]:
    """The torque offsets per joint (``robot.torque_offset``, a joint-terms file's), when the
    robot has any (a description gives none); ``w`` the joint-name column's width."""
    if not robot.single_dof or not np.any(robot.torque_offset != 0.0):
        return []
    out = [
        "",
        f"torque offsets per joint, tau += {OFF} (N m, or N for a prismatic joint; what "
        "--offset uses and identifies)",
        f"{'#':>2} {'joint':<{w}}{OFF:>11}",
    ]
    for k, v in enumerate(robot.torque_offset):
        out.append(f"{k + 1:>2} {robot.joint_names[k]:<{w}}{v:11.4g}")
    return out


def cmd_info(args: argparse.Namespace) -> int:
    robot = load_robot(args)
    n = robot.n
    out = []
    tree = not robot.is_serial
    shape = f", a tree of {robot.branches} branches" if tree else ""
    kind = robot.convention
    if is_mjcf(robot.source):  # read as a URDF's link frames (robot.convention "urdf")
        kind = "MJCF, link frames as a URDF's"
    joints = "1 joint" if n == 1 else f"{n} joints"
    out.append(f"robot      {robot.name}  ({joints}, {kind}{shape})")
    out.append(f"source     {robot.source}")
    g = robot.gravity
    out.append(f"gravity    [{g[0]:g}, {g[1]:g}, {g[2]:g}] m/s^2")
    if not robot.single_dof:
        kinds = set(robot.joint_types)
        forms = [
            form
            for form, of in (
                ("quaternions x, y, z, w", {"floating", "spherical"}),
                ("a planar joint's angle as its cos, sin", {"planar"}),
            )
            if kinds & of
        ]
        out.append(
            f"state      nq {robot.nq} configuration and nv {robot.nv} velocity coordinates "
            f"(joints of several degrees of freedom{''.join('; ' + f for f in forms)})"
        )
    if robot.synthetic_inertia:
        out.append("inertia    SYNTHETIC: the inertial values are invented, not measured")
    if robot.notes:
        out.append(f"notes      {robot.notes.strip()}")
    impossible = _inconsistent_links(robot)
    if impossible:
        out.append(
            f"inertia    not a rigid body's: {', '.join(repr(k) for k in impossible)} (a "
            "pseudo-inertia is not positive semidefinite: a negative mass or principal moment, "
            "or principal moments that break the triangle inequality)"
        )
    out.append("")
    lim = robot.limits
    drv = robot.drives
    deg = {"revolute": 180.0 / math.pi, "prismatic": 1.0}
    dh = robot.dh
    w = max([13] + [len(j) for j in robot.joint_names]) + 1  # joint-name column
    # a tree: the link each joint hangs from (the base link, or the link of its parent joint)
    hang = [robot.link_names[p + 1] for p in robot.parents] if tree else []
    wp = max([12] + [len(h) for h in hang]) + 1 if tree else 0
    parent_head = f"{'parent link':<{wp}}" if tree else ""
    if robot.convention in ("dh", "mdh") and len(dh):
        if robot.convention == "dh":
            head = f"{'a [m]':>9} {'alpha[deg]':>10} {'d [m]':>9} {'theta[deg]':>10}"
        else:
            head = f"{'d [m]':>9} {'alpha[deg]':>10} {'r [m]':>9} {'theta[deg]':>10}"
    else:
        head = f"{'axis (joint frame)':>30}"
    out.append(
        f"{'#':>2} {'joint':<{w}}{parent_head}{'type':<10}{head} {'lower':>9} {'upper':>9} "
        f"{'vel':>9} {'effort':>9} {'rated':>7} {'gear':>7}"
    )
    out.append(
        "   (limits in deg, deg/s for revolute joints; m, m/s for prismatic; effort N m or N)"
    )
    for k in range(n):
        t = robot.joint_types[k]
        s = deg.get(t, 1.0)  # multi-DOF joints have no limits (NaN)
        if robot.convention in ("dh", "mdh") and len(dh):
            a, alpha, d, theta = dh[k]
            geo = f"{a:9.4f} {math.degrees(alpha):10.3f} {d:9.4f} {math.degrees(theta):10.3f}"
        else:
            ax = robot.axes[k]
            geo = (
                "-".rjust(30)  # a free body or a ball joint turns about every axis
                if t in ("floating", "spherical")
                else f"[{ax[0]:8.4f} {ax[1]:8.4f} {ax[2]:8.4f}]".rjust(30)
            )
        out.append(
            f"{k + 1:>2} {robot.joint_names[k]:<{w}}{hang[k] if tree else '':<{wp}}{t:<10}{geo} "
            f"{_fmt(lim['lower'][k] * s, 9)} {_fmt(lim['upper'][k] * s, 9)} "
            f"{_fmt(lim['velocity'][k] * s, 9)} "
            f"{_fmt(lim['effort'][k], 9)} {_fmt(drv['rated_torque'][k], 7)} "
            f"{_fmt(drv['gear_ratio'][k], 7)}"
        )
    out.extend(_transmission_lines(robot))
    out.append("")
    on_motors = robot.transmission is not None and robot.single_dof
    on_motors = on_motors and robot.drive_side == "motor"
    out.append(
        "classical parameters about each link-frame origin (SI)"
        + ("; Ia, Fv, Fc: the joints', as the description gives them" if on_motors else "")
    )
    names = ["XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M", "Ia", "Fv", "Fc"]
    model = robot.friction_model if robot.single_dof else {"kind": "coulomb"}
    third = _sidecar.FRICTION_MODELS[model["kind"]][0]
    wl = max([10] + [len(x) + 1 for x in robot.link_names[1:]])  # link-name column
    out.append(f"{'link':<{wl}}" + "".join(f"{c:>11}" for c in names + ([third] if third else [])))
    p = robot.params.reshape(n, 10)
    extra = np.column_stack(
        [robot.rotor_inertia, robot.viscous, robot.coulomb]
        + ([robot.third_friction] if third else [])
    )
    for k in range(n):
        row = list(p[k]) + list(extra[k])
        out.append(f"{robot.link_names[k + 1]:<{wl}}" + "".join(f"{v:11.4g}" for v in row))
    out.append(f"total moving mass {p[:, 9].sum():.4g} kg")
    if model["kind"] != "coulomb":  # as identify states it
        from ..identification.friction import friction_lines

        lines = friction_lines(robot, record={"chosen_by": "as loaded"})
        out.extend(line[2:] for line in lines)
    out.extend(_offset_lines(robot, w))
    if robot.transmission is not None and robot.transmission.n_motors != n:
        out += [
            "",
            f"rotor inertia and friction: on the joints (the values above): "
            f"{robot.transmission.n_motors} motors for {n} joints, and on the motors they "
            "need one motor per joint",
        ]
    elif on_motors:
        out.extend(_motor_terms(robot))
    print("\n".join(out))
    return 0


def register(sub) -> None:
    """Adds ``info`` to the ``mindyn`` subcommands."""
    p = add_command(sub, "info")
    add_robot(p)
    p.set_defaults(func=cmd_info, shows_offsets=True)


def _inconsistent_links(robot) -> list[str]:
    """The links whose 10 inertial parameters no rigid body has: a pseudo-inertia with an
    eigenvalue below -1e-9 of its largest magnitude (none for a robot with joints of several
    degrees of freedom, whose parameters are read as given)."""
    from ..robot import pseudo_inertia

    if not robot.single_dof:
        return []
    out = []
    for k, p in enumerate(np.asarray(robot.params).reshape(robot.n, 10)):
        ev = np.linalg.eigvalsh(pseudo_inertia(p))
        if ev[0] < -1e-9 * max(abs(ev[0]), abs(ev[-1])):
            out.append(robot.link_names[k + 1])
    return out
