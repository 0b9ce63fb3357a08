"""Bounded, seeded, reproducible fuzz campaign over the CLI and the Python API.

usage: .venv/bin/python fuzz/campaign.py OUTDIR [--targets T1,T2] [--count N] [--budget S]
           [--seed S] [--timeout S] [--rss MIB] [--case TARGET:INDEX]

Targets (each case drawn from its own seed, ``(seed, target, index)``, so that one case can be
rerun alone with ``--case``):

  trees       random URDF chains and trees with odd geometry (axes within 1e-12..1e-6 of a
              coordinate axis, angles written rounded, lengths 1e-9..1e9 m): ``mindyn base`` with
              a random method; oracle ``W_b (Y pi) = tau`` (Newton-Euler) at random states, for
              an exact method the other exact method's count, and Pinocchio's rnea on every
              third case
  floating    the same robots on a free-flyer (``--root-joint floating``): oracle
              ``W_b (Y pi) = tau`` of the multibody inverse dynamics at random states (unit
              quaternions) and, for an exact method, the other exact method's count
  symbolic    random DH / MDH tables with odd twists and lengths: ``mindyn base --symbolic``;
              oracle: the formulas evaluated at the description's symbols equal the numeric Y
  ident       ``identify --consistent``, ``export`` and ``identify-payload`` on logs simulated by
              the package itself, with mutated JSON (types, huge numbers, nesting, booleans as
              strings) and odd options; oracle: estimates against the simulated truth, the
              exported file against the JSON's classical values
  controller  ``codegen --what adaptive-pd|computed-torque|gravity-compensation`` with odd gains
              and periods; the C step compiled with cc against the library's step on random
              inputs (equal to 1e-9 relative or both refuse)
  data        the data path: logs with jitter, gaps, rate drift, a missing header, NaNs, another
              robot's log, odd periods, through ``identify``; oracle: the estimate of a log whose
              samples are honest (only the time stamps irregular) against the simulated truth
  drives      random robots with random transmissions (URDF ROS 1 / ROS 2, YAML matrices), 40 %
              malformed: a malformed one refused in one line naming the element; T against
              ros_control's position maps on the file's numbers; the motor-side inverse dynamics
              against Pinocchio plus T^T (Ia T ddq + f(T dq)); base counts of the three methods
              with rotor and friction; export then load; motor currents through T; every
              fourth case the generated C computed-torque step against the same
  mjcf        random MuJoCo MJCF chains and trees (ball joints, a free root, every form of
              orientation, default classes, jointless bodies, inertia from <inertial> or geoms,
              joint and tendon terms, <option> flags), 40 % malformed: a malformed one refused
              in one line naming the element or file; inverse dynamics, W_b (Y pi) and the mass
              matrix against MuJoCo's mj_inverse and mj_fullM; every third case export --mjcf
              and a new MJCF, read back, with the same dynamics
  cli, files, api
              the earlier bad-input campaign: random command lines from the parser's options,
              mutated URDF / YAML / CSV files, Python API calls with bad arrays

Each case runs in a forked child (after the imports) with an address-space limit; the parent
kills it after the per-case timeout and reads its peak RSS. Classes:

  ok        exit 0 (and the oracle agrees where there is one)
  error     a precise error: non-zero exit with one stderr line "mindyn: error: ..." (API: a
            mindyn.Error, ValueError or FileNotFoundError), or a refusal with its reason
  findings  trace (a traceback), internal (exit 70 "unexpected" / another exception type),
            unclear (an error in more than one line, or without "mindyn: error:"), crash
            (a signal), hang (over the timeout), memory (peak RSS over the limit, or out of
            memory), wrong (a silent wrong answer caught by an oracle)

OUTDIR receives summary.txt / summary.json (counts per target and class, the refusals' most
frequent messages) and findings/<target>-<index>-<class>/ with case.json (the class, detail,
command line and the command that reruns it) and the input files.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import os
import random
import re
import resource
import shutil
import signal
import sys
import time
import traceback
from collections import Counter
from pathlib import Path

import mindyn
import numpy as np
import yaml
from mindyn import cli

ROOT = Path(__file__).resolve().parents[1]
URDF = ROOT / "examples" / "urdf" / "ur5.urdf"
FINDINGS = ("trace", "internal", "unclear", "crash", "hang", "memory", "wrong")
CLASSES = ("ok", "error") + FINDINGS + ("tool",)
TARGETS = (
    "trees",
    "symbolic",
    "ident",
    "controller",
    "data",
    "cli",
    "files",
    "api",
    "floating",
    "drives",
    "mjcf",
)
#: The targets run when none is given.
DEFAULT_TARGETS = (*TARGETS[:5], "floating", "drives", "mjcf")
ORACLE_TOL = 1e-9


# ---------------------------------------------------------------------------------------------
# Running one case
# ---------------------------------------------------------------------------------------------
class Case:
    """One case: ``fn()`` returns (class, detail); ``argv`` is the command line (if any) and
    ``files`` the inputs it reads, copied into the reproducer."""

    def __init__(self, target: str, index: int, label: str, fn, argv=None, files=()):
        self.target, self.index, self.label, self.fn = target, index, label, fn
        self.argv = argv
        self.files = [str(f) for f in files]


def _escaped(e: BaseException) -> str:
    """An exception that escaped a case: a traceback of mindyn's when raised inside the package
    and not one of its errors, else a defect of this campaign ("tool", not a finding)."""
    frames = traceback.extract_tb(e.__traceback__)
    inside = any(f"{os.sep}mindyn{os.sep}" in f.filename for f in frames[1:])
    return "trace" if inside and not isinstance(e, mindyn.Error) else "tool"


def run_child(fn, timeout: float, rss_mib: int):
    """Run fn() in a fork; returns (class, detail, seconds, peak RSS MiB)."""
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child
        os.close(r)
        os.setpgid(0, 0)  # the compiler and other children die with it
        with contextlib.suppress(Exception):
            import faulthandler

            faulthandler.disable()  # a crash is the parent's to report
        quiet = os.open(os.devnull, os.O_WRONLY)  # native parsers print on fd 2
        os.dup2(quiet, 1)
        os.dup2(quiet, 2)
        limit = (rss_mib + 3072) << 20  # address space: RSS limit plus room for mappings
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
        try:
            res = fn()
        except MemoryError:
            res = ("memory", "MemoryError")
        except BaseException as e:  # noqa: BLE001
            res = (_escaped(e), traceback.format_exc()[-600:])
        with contextlib.suppress(Exception):
            os.write(w, json.dumps(list(res)).encode()[:60000])
        os._exit(0)
    os.close(w)
    t0 = time.time()
    status, usage = 0, None
    while True:
        done, status, usage = os.wait4(pid, os.WNOHANG)
        if done:
            break
        if time.time() - t0 > timeout:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(pid, signal.SIGKILL)
            _, status, usage = os.wait4(pid, 0)
            os.close(r)
            return ("hang", f"over {timeout:g} s", time.time() - t0, usage.ru_maxrss / 1024)
        time.sleep(0.01)
    secs = time.time() - t0
    rss = usage.ru_maxrss / 1024
    data = b""
    while chunk := os.read(r, 65536):
        data += chunk
    os.close(r)
    if os.WIFSIGNALED(status):
        return ("crash", f"signal {os.WTERMSIG(status)}", secs, rss)
    try:
        kind, detail = json.loads(data)
    except ValueError:
        return ("crash", "the child ended without a result", secs, rss)
    if rss > rss_mib and kind not in FINDINGS:
        kind, detail = "memory", f"peak RSS {rss:.0f} MiB over {rss_mib} MiB ({detail})"[:400]
    return (kind, detail, secs, rss)


def run_cli(argv):
    """cli.main in this process; returns (exit code, stdout, stderr)."""
    err, out = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
        try:
            code = cli.main([str(a) for a in argv])
        except SystemExit as e:
            code = e.code if isinstance(e.code, int) else 2
        except BaseException:  # noqa: BLE001
            err.write(traceback.format_exc())
            code = -1
    return code, out.getvalue(), err.getvalue()


def cli_class(code: int, out: str, err: str):
    """(class, detail) of one command line by its exit status and stderr."""
    if "Traceback" in err:
        return ("trace", err[-600:])
    lines = [x for x in err.splitlines() if x.strip() and not x.startswith(("usage:", " "))]
    if code == 0:
        return ("ok", "")
    if code == 70:
        return ("internal", err.strip()[:400])
    if "out of memory" in err:
        return ("memory", err.strip()[:400])
    if len(lines) == 1 and lines[0].startswith("mindyn") and "error" in lines[0]:
        return ("error", lines[0][:400])
    return ("unclear", f"exit {code}: {err.strip()[:400]}")


def cli_fn(argv):
    def fn():
        return cli_class(*run_cli(argv))

    return fn


def api_refusal(e: BaseException):
    if isinstance(e, MemoryError):
        return ("memory", "MemoryError")
    if isinstance(e, (mindyn.Error, ValueError, FileNotFoundError)):
        msg = str(e)
        if "\n" in msg.strip():
            return ("unclear", f"{type(e).__name__}: {msg}"[:400])
        return ("error", msg[:400])
    return ("internal", f"{type(e).__name__}: {e}"[:400])


def rel_err(a, b, scale) -> float:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return float(np.max(np.abs(a - b)) / max(float(np.max(np.abs(scale))), 1e-300))


# ---------------------------------------------------------------------------------------------
# trees: odd URDF chains and trees, base parameters against inverse dynamics and Pinocchio
# ---------------------------------------------------------------------------------------------
ROUNDED = [1.5708, -1.5708, 3.14159, -3.14159, 1.571, 0.7854, 1.57079633, 0.0, 3.1416]


def _odd_axis(rng: random.Random) -> list[float]:
    a = [0.0, 0.0, 0.0]
    k = rng.randrange(3)
    a[k] = rng.choice([1.0, -1.0])
    kind = rng.random()
    if kind < 0.55:  # within 1e-12 .. 1e-6 of a coordinate axis
        for j in range(3):
            if j != k and rng.random() < 0.7:
                a[j] = rng.choice([1, -1]) * 10 ** rng.uniform(-12, -6)
    elif kind < 0.8:
        a = [rng.gauss(0, 1) for _ in range(3)]
    return a


def _odd_rpy(rng: random.Random) -> list[float]:
    if rng.random() < 0.6:
        return [rng.choice(ROUNDED) for _ in range(3)]
    return [rng.uniform(-np.pi, np.pi) for _ in range(3)]


def _fmt(v) -> str:
    return " ".join(repr(float(x)) for x in v)


_TENSOR = {"ixx": (0, 0), "ixy": (0, 1), "ixz": (0, 2), "iyy": (1, 1), "iyz": (1, 2), "izz": (2, 2)}


def _inertial_xml(rng: random.Random, L: float) -> str:
    m = rng.uniform(0.3, 4.0)
    nprng = np.random.default_rng(rng.randrange(2**32))
    while True:
        mom = nprng.uniform(0.2, 1.0, 3) * m * (0.2 * L) ** 2 / 12
        if 2 * mom.max() < mom.sum():
            break
    Q, _ = np.linalg.qr(nprng.normal(size=(3, 3)))
    inertia = Q @ np.diag(mom) @ Q.T
    com = [rng.uniform(-0.15, 0.15) * L for _ in range(3)]
    i = {k: repr(float(inertia[a, b])) for k, (a, b) in _TENSOR.items()}
    return (
        f'<inertial><origin xyz="{_fmt(com)}" rpy="{_fmt(_odd_rpy(rng))}"/>'
        f'<mass value="{m!r}"/><inertia ixx="{i["ixx"]}" ixy="{i["ixy"]}" ixz="{i["ixz"]}" '
        f'iyy="{i["iyy"]}" iyz="{i["iyz"]}" izz="{i["izz"]}"/></inertial>'
    )


def odd_urdf(rng: random.Random, path: Path, pinocchio: bool) -> Path:
    """A chain or tree of 1..7 moving joints (and a few fixed ones) with odd geometry."""
    n = rng.randint(1, 7)
    tree = rng.random() < 0.5 and n > 1
    L = 10 ** rng.uniform(-9, 9) if rng.random() < 0.35 else rng.choice([1.0, 0.1, 1e3])
    moving = ["revolute", "prismatic"] + ([] if pinocchio else ["continuous"])
    kinds = [rng.choice(moving) for _ in range(n)] + ["fixed"] * rng.randint(0, 2)
    rng.shuffle(kinds)
    links = ['<link name="l0">' + _inertial_xml(rng, L) + "</link>"]
    joints = []
    for k, kind in enumerate(kinds):
        parent = rng.randrange(k + 1) if tree else k
        links.append(f'<link name="l{k + 1}">{_inertial_xml(rng, L)}</link>')
        xyz = [rng.uniform(-0.3, 0.3) * L for _ in range(3)]
        if rng.random() < 0.3:
            xyz[rng.randrange(3)] = 0.0
        j = (
            f'<joint name="j{k + 1}" type="{kind}"><origin xyz="{_fmt(xyz)}" '
            f'rpy="{_fmt(_odd_rpy(rng))}"/><parent link="l{parent}"/><child link="l{k + 1}"/>'
        )
        if kind != "fixed":
            j += f'<axis xyz="{_fmt(_odd_axis(rng))}"/>'
            lim = "" if kind == "continuous" else ' lower="-2" upper="2"'
            j += f'<limit{lim} effort="50" velocity="3"/>'
        joints.append(j + "</joint>")
    path.write_text(
        '<?xml version="1.0"?>\n<robot name="odd">\n' + "\n".join(links + joints) + "\n</robot>\n"
    )
    return path


def check_base(robot, bp, rotor: bool, friction: bool, nprng) -> tuple[str, str]:
    """W_b (Y pi) against Newton-Euler (plus the rotor and friction columns) at three random
    states, relative to the largest sum of absolute terms of tau = W pi."""
    p = robot.parameters(rotor=rotor, friction=friction)
    full = robot.parameter_names(rotor=rotor, friction=friction)
    rigid = set(robot.parameter_names())
    extra = [i for i, name in enumerate(full) if name not in rigid]
    pb = bp.values(p)
    worst = 0.0
    for _ in range(3):
        q = nprng.uniform(-2, 2, robot.n)
        dq, ddq = nprng.uniform(-2, 2, robot.n), nprng.uniform(-2, 2, robot.n)
        W = robot.regressor(q, dq, ddq, rotor=rotor, friction=friction)
        tau = robot.inverse_dynamics(q, dq, ddq) + W[:, extra] @ p[extra]
        scale = np.abs(W) @ np.abs(p)
        worst = max(worst, rel_err(bp.regressor(q, dq, ddq) @ pb, tau, scale))
    near = bp.margin.get("near_degenerate")
    detail = f"W_b (Y pi) vs tau: {worst:.3g} relative (near_degenerate={near}, n_b={bp.n})"
    return ("wrong" if not worst <= ORACLE_TOL else "ok"), detail


def check_pinocchio(robot, path: Path, nprng) -> tuple[str, str]:
    import pinocchio as pin

    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    if model.nq != robot.n or model.nv != robot.n:
        return ("ok", "pinocchio: other joint count, not compared")
    idx = [model.joints[model.getJointId(name)].idx_v for name in robot.joint_names]
    p = robot.params
    worst = 0.0
    for _ in range(2):
        q = nprng.uniform(-2, 2, robot.n)
        dq, ddq = nprng.uniform(-2, 2, robot.n), nprng.uniform(-2, 2, robot.n)
        qp, dqp, ddqp = (np.zeros(robot.n) for _ in range(3))
        qp[idx], dqp[idx], ddqp[idx] = q, dq, ddq
        tau_pin = pin.rnea(model, data, qp, dqp, ddqp)[idx]
        scale = np.abs(robot.regressor(q, dq, ddq)) @ np.abs(p)
        worst = max(worst, rel_err(robot.inverse_dynamics(q, dq, ddq), tau_pin, scale))
    cls = "wrong" if not worst <= ORACLE_TOL else "ok"
    return cls, f"inverse dynamics vs pinocchio rnea: {worst:.3g} relative"


def compare_exact(robot, method: str, bp, detail: str, **terms) -> tuple[str, str]:
    """For an exact method, the other exact method's count on the same geometry (as written),
    near-degenerate or not: two exact methods that disagree are wrong. A refusal of the other
    method (with its reason) is its own outcome."""
    if method == "numerical":
        return "ok", detail
    other = "recursive" if method == "projection" else "projection"
    try:
        n_other = mindyn.base_parameters(robot, method=other, snap=False, **terms).n
    except BaseException as e:  # noqa: BLE001 - a refusal of the other method is its own
        return "ok", f"{detail}; the {other} method refuses: {api_refusal(e)[1]}"
    if n_other != bp.n:
        return "wrong", f"{detail}; the {other} method gives {n_other} base parameters"
    return "ok", detail


def case_trees(ctx, index: int, rng: random.Random) -> Case:
    pin_case = index % 3 == 0
    path = odd_urdf(rng, ctx.work / f"trees-{index}.urdf", pin_case)
    method = rng.choice(["projection", "recursive", "numerical"])
    rotor, friction = rng.random() < 0.3, rng.random() < 0.3
    # the geometry as written (--snap off), as the oracle's base set takes it
    argv = ["base", path, "--method", method, "--snap", "off"]
    argv += ["--rotor"] * rotor + ["--friction"] * friction
    seed = rng.randrange(2**32)

    def fn():
        cls, detail = cli_class(*run_cli(argv))
        if cls != "ok":
            return cls, detail
        nprng = np.random.default_rng(seed)
        robot = mindyn.load(path)
        try:
            bp = mindyn.base_parameters(  # the geometry as written, as check_base takes it
                robot, method=method, rotor=rotor, friction=friction, snap=False
            )
        except BaseException as e:  # noqa: BLE001 - the CLI accepted what the API refuses
            cls, detail = api_refusal(e)
            return ("unclear" if cls == "error" else cls), f"API refuses, CLI ran: {detail}"
        cls, detail = check_base(robot, bp, rotor, friction, nprng)
        if cls == "ok":
            cls, detail = compare_exact(robot, method, bp, detail, rotor=rotor, friction=friction)
        if cls == "ok" and pin_case:
            return check_pinocchio(robot, path, nprng)
        return cls, detail

    return Case("trees", index, f"base {method} {path.name}", fn, argv, [path])


def random_floating_state(robot, nprng) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """q (a unit quaternion for the free-flyer), v and its derivative, each entry in [-2, 2]."""
    q = nprng.uniform(-2, 2, robot.nq)
    quat = nprng.normal(size=4)
    q[3:7] = quat / np.linalg.norm(quat)  # the root free-flyer: x y z, qx qy qz qw
    return q, nprng.uniform(-2, 2, robot.nv), nprng.uniform(-2, 2, robot.nv)


def check_floating_base(robot, bp, nprng) -> tuple[str, str]:
    """W_b (Y pi) against the multibody inverse dynamics at three random states, relative to
    the largest sum of absolute terms of tau = W pi."""
    p = robot.params
    pb = bp.values(p)
    worst = 0.0
    for _ in range(3):
        q, v, a = random_floating_state(robot, nprng)
        W = robot.regressor(q, v, a)
        scale = np.abs(W) @ np.abs(p)
        worst = max(
            worst, rel_err(bp.regressor(q, v, a) @ pb, robot.inverse_dynamics(q, v, a), scale)
        )
    near = bp.margin.get("near_degenerate")
    detail = f"W_b (Y pi) vs tau: {worst:.3g} relative (near_degenerate={near}, n_b={bp.n})"
    return ("wrong" if not worst <= ORACLE_TOL else "ok"), detail


def case_floating(ctx, index: int, rng: random.Random) -> Case:
    path = odd_urdf(rng, ctx.work / f"floating-{index}.urdf", False)
    method = rng.choice(["projection", "recursive", "numerical"])
    argv = ["base", path, "--root-joint", "floating", "--method", method, "--snap", "off"]
    seed = rng.randrange(2**32)

    def fn():
        cls, detail = cli_class(*run_cli(argv))
        if cls != "ok":
            return cls, detail
        robot = mindyn.load(path, root_joint="floating")
        try:
            bp = mindyn.base_parameters(robot, method=method, snap=False)
        except BaseException as e:  # noqa: BLE001 - the CLI accepted what the API refuses
            cls, detail = api_refusal(e)
            return ("unclear" if cls == "error" else cls), f"API refuses, CLI ran: {detail}"
        cls, detail = check_floating_base(robot, bp, np.random.default_rng(seed))
        if cls != "ok":
            return cls, detail
        return compare_exact(robot, method, bp, detail)

    return Case(
        "floating", index, f"base --root-joint floating {method} {path.name}", fn, argv, [path]
    )


# ---------------------------------------------------------------------------------------------
# drives: transmissions (URDF ROS 1 / ROS 2, YAML), motor-side dynamics, export, base counts
# ---------------------------------------------------------------------------------------------
TI = "transmission_interface/"
DRIVE_TYPES = ("SimpleTransmission", "DifferentialTransmission", "FourBarLinkageTransmission")
#: actuator reductions: gear ratios of either sign, and (one draw in ten) huge and tiny ones
REDUCTIONS = [100.0, -80.0, 50.0, 1.0, -1.0, 0.5, 3.7, -160.0, 121.0, 2 * np.pi / 0.005]
ODD_REDUCTIONS = [1e4, 1e-3, 1e6, 1e-6, -1e5]
JOINT_REDUCTIONS = [None, None, 1.0, 1.5, -0.8, 2.0, 0.25, -1.0]
DRIVE_TWISTS = [0, 90, -90, 180, 45, 30, -60, 120]


def _reduction(rng: random.Random, values: list) -> float | None:
    return rng.choice(ODD_REDUCTIONS if rng.random() < 0.1 else values)


JOINT_NAMES = ["shoulder", "elbow", "wrist_1", "wrist_2", "j0", "joint-7", "a", "z9", "J", "q"]


def _decimal(rng: random.Random, v: float) -> str:
    """v written in one of the forms a description may hold; the oracle reads it back with
    float(), so the value compared is the one written."""
    form = rng.randrange(6)
    if form == 0:
        return f"{v:.17g}"
    if form == 1:
        return f"{v:e}"
    if form == 2:
        return f" {v!r}\n  "
    if form == 3 and math.copysign(1.0, v) > 0:  # not -0.0, which would read '+-0.0'
        return f"+{v!r}"
    if form == 4 and float(v).is_integer() and abs(v) < 1e6:
        return str(int(v))
    return repr(v)


def _drive_groups(rng: random.Random, joints: list[str]) -> list[dict]:
    """Transmissions on the joints (taken in a random order): simple ones, two-joint ones on any
    pair (not only neighbours), and now and then a joint left without one (a direct drive)."""
    order = list(joints)
    rng.shuffle(order)
    groups = []
    while order:
        r = rng.random()
        if r < 0.12:
            order.pop()  # driven directly
            continue
        kind = rng.choice(DRIVE_TYPES[1:]) if len(order) >= 2 and r < 0.55 else DRIVE_TYPES[0]
        k = 1 if kind == DRIVE_TYPES[0] else 2
        js = [order.pop() for _ in range(k)]
        i = len(groups) + 1
        g = {
            "name": rng.choice([f"t{i}", f"trans_{i}", f"T {i}"]),
            "type": kind,
            "joints": js,
            "acts": [rng.choice([f"m{i}_{r}", f"motor{i}{r}"]) for r in range(k)],
            "a": [_decimal(rng, _reduction(rng, REDUCTIONS)) for _ in range(k)],
            "j": [None] * k,
            "off": [None] * k,
        }
        if k == 2:
            g["j"] = [
                None if x is None else _decimal(rng, x)
                for x in (_reduction(rng, JOINT_REDUCTIONS) for _ in range(2))
            ]
        for r in range(k):
            if rng.random() < 0.2:
                g["off"][r] = _decimal(rng, rng.uniform(-1, 1))
        groups.append(g)
    return groups


def _group_rows(g: dict) -> dict:
    """ros_control's joint -> actuator position maps written out for one transmission, from the
    numbers as written: {motor: ({joint: coefficient}, motor offset)}, x_k = q_k - o_k:
    simple q_m1 = a1 x1; differential q_m1 = a1 (j1 x1 + j2 x2), q_m2 = a2 (j1 x1 - j2 x2);
    four-bar q_m1 = a1 j1 x1, q_m2 = a2 (x1 + j2 x2)."""
    a = [float(x) for x in g["a"]]
    jr = [1.0 if x is None else float(x) for x in g["j"]]
    off = [0.0 if x is None else float(x) for x in g["off"]]
    J, M = g["joints"], g["acts"]
    if g["type"] == "SimpleTransmission":
        coef = [{J[0]: a[0]}]
    elif g["type"] == "DifferentialTransmission":
        coef = [{J[0]: a[0] * jr[0], J[1]: a[0] * jr[1]}, {J[0]: a[1] * jr[0], J[1]: -a[1] * jr[1]}]
    else:
        coef = [{J[0]: a[0] * jr[0]}, {J[0]: a[1], J[1]: a[1] * jr[1]}]
    rows = {}
    for r, row in enumerate(coef):
        rows[M[r]] = (row, -sum(c * off[J.index(j)] for j, c in row.items()))
    return rows


def _member_xml(g: dict, what: str, r: int, ros2: bool, roles: bool) -> str:
    """The <joint> or <actuator> element of role r of transmission g in either form."""
    name = g["joints" if what == "joint" else "acts"][r]
    red = "mechanical_reduction" if ros2 else "mechanicalReduction"
    simple = g["type"] == "SimpleTransmission"
    if what == "actuator":  # ROS 2's simple transmission: the reduction is the joint's
        value = None if (simple and ros2) else g["a"][r]
    else:
        value = g["a"][0] if (simple and ros2) else g["j"][r]
    body = "" if value is None else f"<{red}>{value}</{red}>"
    if what == "joint" and g["off"][r] is not None:
        body = f"<offset>{g['off'][r]}</offset>" + body
    role = f"{what}{r + 1}"
    if ros2:
        attr = f' role="{role}"' if roles else ""
        return f'<{what} name="{name}"{attr}>{body}</{what}>'
    if roles:
        body = f"<role>{role}</role>" + body
    if what == "joint":
        body += "<hardwareInterface>hardware_interface/EffortJointInterface</hardwareInterface>"
    return f'<{what} name="{name}">{body}</{what}>'


def _transmission_xml(rng: random.Random, g: dict, ros2: bool) -> str:
    k = len(g["joints"])
    roles = k == 2 and (not ros2 or rng.random() < 0.7) or rng.random() < 0.3
    g["roles"] = roles
    parts = [_member_xml(g, w, r, ros2, roles) for w in ("joint", "actuator") for r in range(k)]
    if roles:  # the roles decide, not the order
        rng.shuffle(parts)
    tag = "plugin" if ros2 else "type"
    parts.insert(rng.randrange(len(parts) + 1), f"<{tag}>{TI}{g['type']}</{tag}>")
    return f'<transmission name="{g["name"]}">' + "".join(parts) + "</transmission>"


def _drive_chain(rng: random.Random, n: int) -> tuple[list[str], list[str], list[str]]:
    """(joint names in chain order, link elements, joint elements in a shuffled order) of a chain
    of n revolute / prismatic joints with odd names, generic geometry (the odd one is the trees
    target's), generic links and now and then a fixed joint."""
    names = rng.sample(JOINT_NAMES, n)
    links = [f'<link name="l0">{_inertial_xml(rng, 1.0)}</link>']
    joints = []
    k = 0
    for name in names:
        if rng.random() < 0.15:  # a fixed joint between two moving ones
            k += 1
            links.append(f'<link name="l{k}">{_inertial_xml(rng, 1.0)}</link>')
            joints.append(
                f'<joint name="fixed{k}" type="fixed"><origin xyz="0 0.05 0.1"/>'
                f'<parent link="l{k - 1}"/><child link="l{k}"/></joint>'
            )
        k += 1
        kind = "prismatic" if rng.random() < 0.2 else "revolute"
        xyz = [rng.uniform(-0.3, 0.3) for _ in range(3)]
        rpy = [rng.choice([0.0, rng.uniform(-np.pi, np.pi)]) for _ in range(3)]
        axis = [0.0, 0.0, 0.0]
        axis[rng.randrange(3)] = rng.choice([1.0, -1.0])
        if rng.random() < 0.3:
            axis = [rng.gauss(0, 1) for _ in range(3)]
        links.append(f'<link name="l{k}">{_inertial_xml(rng, 1.0)}</link>')
        joints.append(
            f'<joint name="{name}" type="{kind}"><origin xyz="{_fmt(xyz)}" '
            f'rpy="{_fmt(rpy)}"/><parent link="l{k - 1}"/><child link="l{k}"/>'
            f'<axis xyz="{_fmt(axis)}"/>'
            f'<limit lower="-2" upper="2" effort="50" velocity="3"/></joint>'
        )
    rng.shuffle(joints)
    return names, links, joints


#: values a malformed description writes for a number
BAD_NUMBERS = ["abc", "1O", "", "nan", "inf", "-inf", "1e400", "1,5", "0x10", "1e", "--1", "1 2"]


def _mutate_urdf(rng: random.Random, groups: list[dict], xml: list[str], ros2: bool):
    """One malformation of the transmissions' XML (a list of one string per transmission, edited
    in place): returns (what, the text the refusal must hold, whether leaving the transmission
    out with a note is a valid outcome instead, the index of the transmission); what is None when
    the change leaves the description valid."""
    i = rng.randrange(len(groups))
    g, s = groups[i], xml[i]
    name = g["name"]
    owner = f"transmission '{name}'"
    two = [k for k, h in enumerate(groups) if len(h["joints"]) == 2]
    red = "mechanical_reduction" if ros2 else "mechanicalReduction"
    kinds = ["type", "other-type", "number", "member", "no-name", "unknown-joint", "element"]
    kinds += ["wrong-side"] * (g["type"] == DRIVE_TYPES[0])
    kinds += ["role", "same-joint", "bad-role"] * bool(two)
    kinds += ["twice", "dup-name", "dup-actuator", "mixed"] * (len(groups) > 1)
    kinds += ["missing-reduction"] * (not ros2)
    kind = rng.choice(kinds)
    if kind in ("role", "same-joint", "bad-role"):
        i = rng.choice(two)
        g, s, name = groups[i], xml[i], groups[i]["name"]
        owner = f"transmission '{name}'"
    J, A = g["joints"], g["acts"]
    may_note = False
    if kind == "type":
        typo = rng.choice(["SimpleTransmision", "DifferentialTransmisson", "FourBarLinkage",
                           "simpletransmission", "FourBarLinkageTransmission "])  # fmt: skip
        s = s.replace(f"{TI}{g['type']}<", f"{TI}{typo}<")
        may_note = True  # refused as a misspelling, or another type: left out with a note
        if typo.strip() == g["type"]:  # white space around the type: still the type
            kind = None
    elif kind == "other-type":
        s = s.replace(f"{TI}{g['type']}<", rng.choice(
            ["pr2_mechanism_model/SimpleTransmission<", "my_robot/GearTransmission<",
             f"{TI}HalfDifferentialTransmission<"]))  # fmt: skip
        may_note = True
    elif kind == "number":
        texts = [t for t in g["a"] + g["j"] + g["off"] if t is not None]
        old = rng.choice(texts)
        bad = rng.choice(BAD_NUMBERS + ["0"] * (old not in g["off"]))
        s = s.replace(f">{old}<", f">{bad}<", 1)
    elif kind == "member":
        who = rng.choice(["joint", "actuator"])
        nm = rng.choice(J if who == "joint" else A)
        s = re.sub(rf'<{who} name="{re.escape(nm)}"[^>]*>.*?</{who}>', "", s, count=1,
                   flags=re.DOTALL)  # fmt: skip
    elif kind == "no-name":
        s = s.replace(f'<transmission name="{name}">', "<transmission>")
        owner = "<transmission> has no name"
    elif kind == "unknown-joint":
        for j in rng.sample(J, rng.randint(1, len(J))):
            s = s.replace(f'<joint name="{j}"', '<joint name="nosuch_' + j + '"')
        may_note = True  # a transmission naming no joint of the file at all is left out
    elif kind == "element":
        s = s.replace(f"{red}>", f"{red[:-3]}tion>" if ros2 else "mechanicalReducton>", 2)
        if f"{red}>" not in xml[i]:
            kind = None  # nothing to misspell: the transmission as it was
    elif kind == "wrong-side":
        if ros2:
            s = s.replace("</actuator>", f"<{red}>2</{red}></actuator>", 1)
        else:
            s = s.replace(f'<joint name="{J[0]}">', f'<joint name="{J[0]}"><{red}>2</{red}>', 1)
    elif kind == "role":
        r = rng.choice(["joint", "actuator"]) + rng.choice(["1", "2"])
        s = s.replace(f' role="{r}"', "") if ros2 else s.replace(f"<role>{r}</role>", "")
        if not g.get("roles"):
            kind = None  # no roles written: the order decides
    elif kind == "bad-role":
        r = rng.choice(["joint2", "actuator1"])
        new = rng.choice(["joint3", "actuator", "Joint1", r + " x"])
        s = s.replace(f'role="{r}"', f'role="{new}"') if ros2 else s.replace(
            f"<role>{r}</role>", f"<role>{new}</role>")  # fmt: skip
        if not g.get("roles"):
            kind = None
    elif kind == "missing-reduction":  # ROS 1: an actuator without one has reduction 1
        s = re.sub(rf'(<actuator name="{re.escape(A[0])}">.*?)<{red}>[^<]*</{red}>', r"\1", s,
                   count=1)  # fmt: skip
        g["a"][0] = "1"  # read so, with a warning (as Gazebo runs it): valid
        kind = None
    elif kind == "same-joint":
        s = s.replace(f'<joint name="{J[1]}"', f'<joint name="{J[0]}"')
    else:  # two transmissions
        o = rng.choice([k for k in range(len(groups)) if k != i])
        h, t = groups[o], xml[o]
        if kind == "twice":  # a joint of g named by transmission h as well
            t = t.replace(f'<joint name="{h["joints"][0]}"', f'<joint name="{J[0]}"', 1)
            owner = f"joint '{J[0]}'"
        elif kind == "dup-name":
            t = t.replace(f'<transmission name="{h["name"]}">', f'<transmission name="{name}">')
        elif kind == "dup-actuator":
            t = t.replace(f'<actuator name="{h["acts"][0]}"', f'<actuator name="{A[0]}"', 1)
            owner = f"actuator '{A[0]}'"
        else:  # one transmission written in the other form
            g2 = dict(h)
            t = "MIXED" + _transmission_xml(rng, g2, not ros2)
            owner = "both the ROS 1 form"
        xml[o] = t
    xml[i] = s
    return kind, owner, may_note, i


def _drive_table(rng: random.Random, n: int) -> tuple[list[str], dict]:
    """A DH table of n joints with odd names (revolute, now and then prismatic), right-angle
    twists (the odd ones are the symbolic target's)."""
    names = rng.sample(JOINT_NAMES, n)
    joints = []
    for name in names:
        kind = "prismatic" if rng.random() < 0.2 else "revolute"
        m = rng.uniform(0.5, 5)
        mom = sorted(rng.uniform(0.2, 1.0) * m * 0.04 / 12 for _ in range(3))
        mom[2] = min(mom[2], 0.9 * (mom[0] + mom[1]))
        a, d = (rng.choice([0.0, rng.uniform(0.05, 0.6)]) for _ in range(2))
        j = {"name": name, "type": kind, "a": a, "alpha": float(rng.choice(DRIVE_TWISTS)), "d": d,
             "theta": 0.0}  # fmt: skip
        if kind == "prismatic":
            j["limits"] = {"lower": -0.5, "upper": 0.5}
        j["inertial"] = {
            "mass": m,
            "com": [rng.uniform(-0.1, 0.1) for _ in range(3)],
            "inertia": {"xx": mom[0], "yy": mom[1], "zz": mom[2], "xy": 0, "xz": 0, "yz": 0},
        }
        joints.append(j)
    doc = {"name": "drives", "convention": "dh", "angle_unit": "deg", "gravity": [0, 0, -9.81],
           "joints": joints}  # fmt: skip
    return names, doc


def _drive_matrix(rng: random.Random, names: list[str]) -> tuple[list[list[float]], str]:
    """T of a YAML description: ros_control-like groups, a general coupled matrix, or a
    near-singular one (one row a relative 1e-15..1e-6 off a multiple of another)."""
    n = len(names)
    kind = rng.choice(["groups", "general", "near-singular"])
    T = np.zeros((n, n))
    if kind == "groups":
        rows = {}
        for g in _drive_groups(rng, names):
            rows.update({m: row for m, (row, _) in _group_rows(g).items()})
        driven = {j for row in rows.values() for j in row}
        rows.update({j: {j: 1.0} for j in names if j not in driven})
        for i, row in enumerate(rows.values()):
            for j, c in row.items():
                T[i, names.index(j)] = c
        T = T[rng.sample(range(n), n)]
    else:
        T = np.diag([_reduction(rng, REDUCTIONS) for _ in range(n)])
        for i in range(n):
            for k in range(n):
                if i != k and rng.random() < 0.3:
                    T[i, k] = rng.choice([-1, 1]) * rng.uniform(0.1, 2) * abs(T[k, k])
        if kind == "near-singular" and n >= 2:
            i, k = rng.sample(range(n), 2)
            eps = rng.choice([1e-15, 1e-13, 1e-11, 1e-9, 1e-6])
            T[k] = T[i] * rng.choice([1.0, -2.0, 0.5]) * (1 + eps)
            T[k, rng.randrange(n)] += eps * np.abs(T[i]).max()
    return T.tolist(), kind


def _yaml_transmissions(rng: random.Random, names, T, motors, offsets, listed: bool) -> tuple:
    """The `transmissions:` block as text (numbers in odd forms, read back by the oracle with
    float()) and the matrix of texts written."""
    text = [[v if isinstance(v, str) else _decimal(rng, v).strip() for v in row] for row in T]
    if listed:
        lines = ["transmissions:"]
        for i, m in enumerate(motors):
            cells = [f"{names[k]}: {text[i][k]}" for k in range(len(T[i])) if T[i][k] != 0]
            lines.append(f"- name: {m}\n  joints: {{{', '.join(cells)}}}")
            if offsets[i] is not None:
                lines.append(f"  offset: {offsets[i]}")
    else:
        lines = ["transmissions:", "  matrix:"] + [f"  - [{', '.join(r)}]" for r in text]
        if motors is not None:
            lines.append(f"  motors: [{', '.join(motors)}]")
        if any(o is not None for o in offsets):
            lines.append(f"  offset: [{', '.join(o or '0' for o in offsets)}]")
    return "\n".join(lines) + "\n", text


DRIVE_YAML_BAD = [
    "abc",
    ".nan",
    ".inf",
    "-.inf",
    "1e400",
    "null",
    "true",
    "[1]",
    "{a: 1}",
    "1O",
    "--1",
]


def _mutate_yaml(rng: random.Random, names, T, motors, listed: bool):
    """One malformation of a YAML description's transmissions, on the values before they are
    written: (what, the text the refusal must hold (or a tuple of alternatives), T, motors, an
    edit of the written text)."""
    n = len(T)
    kinds = ["number", "row-length", "zero-column", "rank", "unknown-key"]
    kinds += ["dup-motor", "unknown-joint", "dup-key"] if listed else ["dup-motor", "motors-length"]
    kind = rng.choice(kinds)
    T = [list(r) for r in T]
    motors = list(motors) if motors is not None else [f"motor{i + 1}" for i in range(n)]
    edit, owner = None, "transmissions"
    i = rng.randrange(n)
    if kind == "number":
        k = rng.choice([c for c in range(len(T[i])) if T[i][c] != 0])
        bad = rng.choice(DRIVE_YAML_BAD)
        T[i][k] = "BAD"
        edit = ("BAD", bad)
    elif kind == "row-length":
        if listed:  # a joint missing from a motor's mapping is a zero: drop a whole column
            kind, T = "zero-column", [[0.0 if c == i else v for c, v in enumerate(r)] for r in T]
            owner = f"'{names[i]}'"
        else:
            T[i] = T[i][:-1] if rng.random() < 0.5 else T[i] + [1.0]
    elif kind == "zero-column":
        k = rng.randrange(len(names))
        T = [[0.0 if c == k else v for c, v in enumerate(r)] for r in T]
        owner = f"'{names[k]}'"
    elif kind == "rank":
        if n < 2:
            return None, owner, T, motors, edit
        o = rng.choice([r for r in range(n) if r != i])
        T[i], T[o] = [repr(v) for v in T[i]], [repr(2.0 * v) for v in T[i]]  # written exactly
    elif kind == "unknown-key":
        edit = (
            "transmissions:\n" + ("- name" if listed else "  matrix"),
            "transmissions:\n" + ("- ratio: 3\n  name" if listed else "  rows: [1]\n  matrix"),
        )
        owner = "'rows'" if not listed else "'ratio'"
    elif kind == "dup-motor":
        if n < 2:
            return None, owner, T, motors, edit
        o = rng.choice([r for r in range(n) if r != i])
        motors[o] = motors[i]
        owner = f"'{motors[i]}'"
    elif kind == "motors-length":
        motors = motors[:-1]
    elif kind == "unknown-joint":
        owner = "'nosuch'"
        edit = (
            f"- name: {motors[i]}\n  joints: {{",
            f"- name: {motors[i]}\n  joints: {{nosuch: 3, ",
        )
    else:  # dup-key: a motor's mapping names one joint twice
        k = rng.choice([c for c in range(len(names)) if T[i][c] != 0])
        edit = (
            f"- name: {motors[i]}\n  joints: {{",
            f"- name: {motors[i]}\n  joints: {{{names[k]}: 7.5, ",
        )
        owner = f"'{names[k]}'"
    if kind == "zero-column" and listed:  # or a motor whose mapping that leaves empty
        owner = (owner, *(f"('{m}')" for m, row in zip(motors, T, strict=True) if not any(row)))
    return kind, owner, T, motors, edit


def expected_drives(groups: list[dict], joints: list[str]) -> dict:
    """{motor: (row {joint: coefficient}, offset)} of URDF transmissions, with a direct drive
    (a motor of the joint's name, ratio 1) for each joint that none drives, when any remain."""
    rows = {}
    for g in groups:
        rows.update(_group_rows(g))
    driven = {j for g in groups for j in g["joints"]}
    if rows:
        rows.update({j: ({j: 1.0}, 0.0) for j in joints if j not in driven})
    return rows


def check_drive_T(robot, rows: dict) -> tuple[str, str]:
    """T and the motor offsets as loaded against rows {motor: ({joint: c}, offset)}, to a few
    units in the last place of each entry."""
    tr = robot.transmission
    if not rows:
        return ("ok", "") if tr is None else ("wrong", f"a transmission where none: {tr.motors}")
    if tr is None:
        return "wrong", f"no transmission loaded; declared motors {sorted(rows)}"
    if sorted(tr.motors) != sorted(rows):
        return "wrong", f"motors {list(tr.motors)}, declared {sorted(rows)}"
    T = np.zeros(tr.T.shape)
    c = np.zeros(len(tr.motors))
    for i, m in enumerate(tr.motors):
        row, c[i] = rows[m]
        for j, v in row.items():
            T[i, robot.joint_names.index(j)] = v
    tol = 4 * np.finfo(float).eps
    bad = np.abs(np.asarray(tr.T) - T) > tol * np.abs(T)
    if bad.any():
        i, k = np.argwhere(bad)[0]
        return "wrong", (f"T[{tr.motors[i]}, {robot.joint_names[k]}] = {tr.T[i, k]!r}, the "
                         f"transmission's formula gives {T[i, k]!r}")  # fmt: skip
    if not np.all(np.abs(np.asarray(tr.offset) - c) <= 1e-12 * np.maximum(np.abs(c), 1.0)):
        return "wrong", f"motor offsets {list(tr.offset)}, the formula gives {list(c)}"
    return "ok", ""


def friction_terms(kind: str, v, w, fv, fc, f3):
    """The friction torque of each motor at motor velocity v, by the models' definitions."""
    s = np.sign(v)
    if kind == "smooth":
        return fv * v + fc * np.tanh(v / w)
    out = fv * v + fc * s
    if kind == "asymmetric":
        out = out + f3 * np.abs(s)
    elif kind == "stribeck":
        out = out + f3 * s * np.exp(-((v / w) ** 2))
    return out


def motor_side_robot(robot, kind: str, nprng, side: str = "motor"):
    """The robot with the friction model `kind`, rotor inertia and friction on `side`, and its
    parameters with random values of those terms: (robot, p, (Ia, Fv, Fc, F3, w, T)), T the
    transmission matrix on the motor side, the identity on the joint side."""
    T = np.asarray(robot.transmission.T) if side == "motor" else np.eye(robot.n)
    w = nprng.uniform(0.05, 2.0, T.shape[0]) * np.abs(T).max(axis=1)
    r = robot.with_drive_side(side)
    r = r.with_friction_model(kind, velocity=w if kind in ("smooth", "stribeck") else None)
    names = r.parameter_names(rotor=True, friction=True)
    p = np.asarray(r.parameters(rotor=True, friction=True), dtype=float).copy()
    m = T.shape[0]
    Ia, Fv, Fc = (nprng.uniform(1e-5, 1e-3, m), nprng.uniform(1e-4, 1e-2, m),
                  nprng.uniform(1e-3, 0.1, m))  # fmt: skip
    F3 = nprng.uniform(-0.05, 0.05, m) if kind in ("asymmetric", "stribeck") else np.zeros(m)
    third = {"asymmetric": "Fa", "stribeck": "Fs"}.get(kind)
    for k in range(m):
        for key, v in (("Ia", Ia), ("Fv", Fv), ("Fc", Fc), (third, F3)):
            if key is not None:
                p[names.index(f"{key}{k + 1}")] = v[k]
    return r, p, (Ia, Fv, Fc, F3, w, T)


def rigid_torque(robot, pin_model, q, dq, ddq):
    """The links' inverse dynamics: Pinocchio's rnea on the URDF, or (a YAML table) mindyn's
    joint-side Newton-Euler with the rigid parameters only."""
    if pin_model is None:
        return robot.with_drive_side("joint").inverse_dynamics(q, dq, ddq, robot.params)
    import pinocchio as pin

    model, data, idx = pin_model
    qp, dqp, ddqp = (np.zeros(model.nv) for _ in range(3))
    qp[idx], dqp[idx], ddqp[idx] = q, dq, ddq
    return pin.rnea(model, data, qp, dqp, ddqp)[idx]


def check_motor_side(robot, kind, pin_model, nprng, side="motor") -> tuple[str, str, tuple]:
    """Inverse dynamics and regressor of the motor-side (or joint-side: T = I) model against the
    rigid-body inverse dynamics plus T^T (Ia T ddq + f(T dq)) written out, at three random
    states, relative to the largest sum of absolute terms."""
    r, p, terms = motor_side_robot(robot, kind, nprng, side)
    Ia, Fv, Fc, F3, w, T = terms
    worst = 0.0
    for _ in range(3):
        q, dq, ddq = (nprng.uniform(-2, 2, robot.n) for _ in range(3))
        vm = T @ dq
        drive = T.T @ (Ia * (T @ ddq) + friction_terms(kind, vm, w, Fv, Fc, F3))
        want = rigid_torque(robot, pin_model, q, dq, ddq) + drive
        W = r.regressor(q, dq, ddq, rotor=True, friction=True)
        scale = np.abs(W) @ np.abs(p) + np.abs(T.T) @ (np.abs(Fc) + np.abs(F3))
        worst = max(worst, rel_err(r.inverse_dynamics(q, dq, ddq, p), want, scale),
                    rel_err(W @ p, want, scale))  # fmt: skip
    cls = "wrong" if not worst <= ORACLE_TOL else "ok"
    detail = f"{kind} {side}-side inverse dynamics vs rigid + T^T(...): {worst:.3g}"
    return cls, detail, (r, p, terms)


def check_drive_codegen(r, p, terms, pin_model, nprng) -> tuple[str, str]:
    """The generated C computed-torque step (compiled with cc) with the base values of p, at zero
    tracking error: its torque is the inverse dynamics at the reference acceleration, against
    the rigid-body inverse dynamics plus T^T (Ia T ddq + f(T dq)) written out."""
    from mindyn import codegen

    Ia, Fv, Fc, F3, w, T = terms
    kind = r.friction_model["kind"]
    bp = mindyn.base_parameters(r, rotor=True, friction=True)
    gen = codegen.generate_controller(
        r, "computed-torque", base=bp, params=bp.values(p), period=0.004
    )
    ctl = codegen.CompiledController(gen, bp)
    worst = 0.0
    for _ in range(3):
        q, dq, ddq = (nprng.uniform(-2, 2, r.n) for _ in range(3))
        want = rigid_torque(r, pin_model, q, dq, ddq)
        want = want + T.T @ (Ia * (T @ ddq) + friction_terms(kind, T @ dq, w, Fv, Fc, F3))
        W = r.regressor(q, dq, ddq, rotor=True, friction=True)
        scale = np.abs(W) @ np.abs(p) + np.abs(T.T) @ (np.abs(Fc) + np.abs(F3))
        worst = max(worst, rel_err(ctl(0.0, q, dq, q, dq, ddq), want, scale))
    cls = "wrong" if not worst <= ORACLE_TOL else "ok"
    return cls, f"generated C computed torque vs rigid + T^T(...): {worst:.3g}"


def check_drive_bases(r, p, nprng) -> tuple[str, str]:
    """With --rotor --friction on the motor side: the exact methods' base-parameter count equals
    the numerical method's (unless a method reports the robot near a degenerate geometry), and
    the projection set reproduces W p at random states."""
    counts, near, refused = {}, False, {}
    for method in ("projection", "recursive", "numerical"):
        try:
            bp = mindyn.base_parameters(r, method=method, rotor=True, friction=True, snap=False)
        except mindyn.Error as e:  # a refusal with its reason; the others are compared
            refused[method] = str(e)
            if "\n" in str(e):
                return "unclear", f"{method}: {e}"[:400]
            continue
        counts[method] = bp.n
        near = near or bool(bp.margin.get("near_degenerate"))
        if method == "projection":
            worst = 0.0
            for _ in range(2):
                q, dq, ddq = (nprng.uniform(-2, 2, r.n) for _ in range(3))
                W = r.regressor(q, dq, ddq, rotor=True, friction=True)
                got = bp.regressor(q, dq, ddq) @ bp.values(p)
                worst = max(worst, rel_err(got, W @ p, np.abs(W) @ np.abs(p)))
            if not worst <= ORACLE_TOL:
                return "wrong", f"W_b (Y pi) vs W pi with --rotor --friction: {worst:.3g}"
    detail = f"base counts {counts}" + (" (near degenerate)" if near else "")
    if refused:
        detail += "; refused by " + ", ".join(f"{m}: {e[:80]}" for m, e in refused.items())
    same = len(set(counts.values())) <= 1
    return ("ok" if same or near else "wrong"), detail


def check_drive_export(ctx, robot, p, path: Path, index: int) -> tuple[str, str]:
    """`mindyn export` of the robot with motor-side rotor inertia and Coulomb friction, then
    load: the same T, offsets and motors, and the same dynamics (a URDF keeps a directly driven
    motor's friction on its joint, <dynamics>, and every motor's terms in the sidecar; a YAML
    table all of them)."""
    from mindyn.export import read_joint_terms

    names = robot.parameter_names(rotor=True, friction=True)
    doc = {"robot": robot.name, "classical": dict(zip(names, map(float, p), strict=True)),
           "rotor": True, "friction": True, "drive_side": robot.drive_side}  # fmt: skip
    jfile = ctx.work / f"drives-{index}.id.json"
    jfile.write_text(json.dumps(doc))
    out = ctx.work / f"drives-{index}-export{path.suffix}"
    flag = "--yaml" if path.suffix == ".yaml" else "--urdf"
    cls, detail = cli_class(*run_cli(["export", path, jfile, flag, out]))
    if cls != "ok":
        return cls, f"export: {detail}"
    back = mindyn.load(out)
    tr, tb = robot.transmission, back.transmission
    if tb is None or tb.motors != tr.motors or not np.array_equal(tb.T, tr.T):
        return "wrong", f"export changed T: {None if tb is None else tb.T.tolist()}"
    if not np.array_equal(tb.offset, tr.offset) or back.drive_side != robot.drive_side:
        return "wrong", f"export changed the offsets {list(tb.offset)} or the drive side"
    T = np.asarray(tr.T)
    pd = p.copy()
    if path.suffix != ".yaml":  # the URDF's joints carry the terms of motors driving one alone
        side = read_joint_terms(out.with_suffix(".joints.yaml"))
        for k in range(T.shape[0]):
            for key in ("Ia", "Fv", "Fc"):
                want = p[names.index(f"{key}{k + 1}")]
                if side.get(f"{key}{k + 1}") != want:
                    return (
                        "wrong",
                        f"sidecar {key}{k + 1} = {side.get(f'{key}{k + 1}')}, not {want}",
                    )
            j = np.flatnonzero(T[k])
            alone = j.size == 1 and np.count_nonzero(T[:, j[0]]) == 1
            for key in ("Ia", "Fv", "Fc"):  # a URDF has no rotor inertia
                if key == "Ia" or not alone:
                    pd[names.index(f"{key}{k + 1}")] = 0.0
    pb = back.parameters(rotor=True, friction=True)
    nprng = np.random.default_rng(index)
    states = [[nprng.uniform(-2, 2, robot.n) for _ in range(3)] for _ in range(2)]
    worst = id_difference(robot, (pd, p), back, pb, states, rotor=True, friction=True)
    if not worst <= ORACLE_TOL:
        return "wrong", f"exported then loaded: inverse dynamics differ by {worst:.3g}"
    return "ok", ""


def id_difference(robot, p, again, pa, states, order=None, **terms) -> float:
    """The largest difference of the inverse dynamics of ``robot`` with ``p[0]`` and of
    ``again`` with ``pa`` over ``states`` [(q, v, a)], relative to the largest sum of absolute
    terms of ``W p[1]`` (``W`` the regressor of ``robot`` with ``terms``); ``order`` (q, v):
    the entries of ``robot``'s q and v in ``again``'s order of the joints, if another."""
    qi, vi = order if order is not None else (slice(None), slice(None))
    worst = 0.0
    for q, v, a in states:
        scale = np.abs(robot.regressor(q, v, a, **terms)) @ np.abs(p[1])
        got = np.empty(len(v))
        got[vi] = again.inverse_dynamics(q[qi], v[vi], a[vi], pa)
        worst = max(worst, rel_err(got, robot.inverse_dynamics(q, v, a, p[0]), scale))
    return worst


def _reorder(robot, again) -> tuple[np.ndarray, np.ndarray]:
    """For each entry of ``again``'s q and v, the index of the same joint's entry in
    ``robot``'s (joints by name)."""

    def slices(r):
        out, iq, iv = {}, 0, 0
        for name, kind in zip(r.joint_names, r.joint_types, strict=True):
            nq, nv = {"floating": (7, 6), "spherical": (4, 3)}.get(kind, (1, 1))
            out[name] = (np.arange(iq, iq + nq), np.arange(iv, iv + nv))
            iq, iv = iq + nq, iv + nv
        return out

    mine, theirs = slices(robot), slices(again)
    q = np.concatenate([mine[name][0] for name in again.joint_names])
    v = np.concatenate([mine[name][1] for name in again.joint_names])
    assert all(len(theirs[n][0]) == len(mine[n][0]) for n in mine)  # the same kinds
    return q, v


def check_currents(ctx, robot, index: int, nprng) -> tuple[str, str]:
    """Motor currents i of known joint torques (K_t i = T^-T tau) read from a log with the
    torque constants: tau = T^T K_t i."""
    from mindyn.identification.data import read_csv, write_csv

    T = np.asarray(robot.transmission.T)
    n = robot.n
    t = np.arange(60) * 0.01
    w = nprng.uniform(0.5, 2.0, n)
    q = 0.5 * np.sin(w * t[:, None])
    dq, ddq = 0.5 * w * np.cos(w * t[:, None]), -0.5 * w**2 * np.sin(w * t[:, None])
    tau = nprng.uniform(-5, 5, (t.size, n))
    kt = nprng.uniform(0.02, 0.5, n)
    i = np.linalg.solve(T.T, tau.T).T / kt
    log = write_csv(ctx.work / f"drives-{index}.currents.csv", t, q, i, dq=dq, ddq=ddq,
                    torque_unit="current")  # fmt: skip
    data = read_csv(log, robot=robot, drive_gain=kt)
    scale = np.abs(T.T) @ np.abs(kt * i).T
    err = rel_err(data.tau, tau, scale)
    return ("wrong" if not err <= ORACLE_TOL else "ok"), f"currents through T: {err:.3g}"


def _drive_description(ctx, index: int, rng: random.Random) -> tuple:
    """Writes a random robot with random transmissions (valid, or with one malformation) and
    returns (path, the form, the expected rows or None, malformation (what, must-name, whether
    a note is a valid outcome) or None)."""
    form = rng.choice(["ros1", "ros1", "ros2", "ros2", "yaml"])
    n = rng.randint(1, 6)
    bad = rng.random() < 0.4
    mal = None
    if form == "yaml":
        names, doc = _drive_table(rng, n)
        T, how = _drive_matrix(rng, names)
        listed = rng.random() < 0.5
        motors = [f"m_{k}" for k in rng.sample(range(100), n)]
        motors = None if not listed and rng.random() < 0.3 else motors
        offsets = [_decimal(rng, rng.uniform(-1, 1)).strip() if rng.random() < 0.2 else None
                   for _ in range(n)]  # fmt: skip
        edit = None
        if bad:
            what, owner, T, motors, edit = _mutate_yaml(rng, names, T, motors, listed)
            mal = None if what is None else (what, owner, False)
        block, text = _yaml_transmissions(rng, names, T, motors, offsets, listed)
        if edit is not None:
            block = block.replace(edit[0], edit[1], 1)
        path = ctx.work / f"drives-{index}.yaml"
        path.write_text(yaml.safe_dump(doc, sort_keys=False) + block)
        if mal is not None:
            return path, form, None, mal
        mnames = motors or [f"motor{i + 1}" for i in range(len(T))]
        rows = {}
        for i, m in enumerate(mnames):
            row = {names[k]: float(text[i][k]) for k in range(n) if float(text[i][k]) != 0}
            rows[m] = (row, 0.0 if offsets[i] is None else float(offsets[i]))
        return path, f"yaml {how}", rows, None
    ros2 = form == "ros2"
    names, links, joints = _drive_chain(rng, n)
    groups = _drive_groups(rng, names)
    while not groups:  # at least one transmission
        groups = _drive_groups(rng, names)
    xml = [_transmission_xml(rng, g, ros2) for g in groups]
    kept = groups
    if bad:
        what, owner, may_note, i = _mutate_urdf(rng, groups, xml, ros2)
        if what is not None:
            mal = (what, owner, may_note)
            kept = [g for k, g in enumerate(groups) if k != i]
    mixed = [x[5:] for x in xml if x.startswith("MIXED")]
    xml = [x for x in xml if not x.startswith("MIXED")]
    ros2_part, ros1_part = (xml, mixed) if ros2 else (mixed, xml)
    body = "".join(ros1_part)
    if ros2_part:
        body += (
            '<ros2_control name="hw" type="system"><hardware><plugin>mock_components/'
            "GenericSystem</plugin></hardware>" + "".join(ros2_part) + "</ros2_control>"
        )
    parts = links + joints + [body]
    if rng.random() < 0.5:  # transmissions before the links and joints
        parts = [body] + links + joints
    path = ctx.work / f"drives-{index}.urdf"
    path.write_text('<?xml version="1.0"?>\n<robot name="drives">\n' + "\n".join(parts)
                    + "\n</robot>\n")  # fmt: skip
    return path, form, expected_drives(kept, names), mal


def case_drives(ctx, index: int, rng: random.Random) -> Case:
    path, form, rows, mal = _drive_description(ctx, index, rng)
    kind = rng.choice(["coulomb", "asymmetric", "smooth", "stribeck"])
    side = "joint" if rng.random() < 0.25 else "motor"
    seed = rng.randrange(2**32)
    argv = ["info", path]

    def fn():
        cls, detail = cli_class(*run_cli(argv))
        if mal is not None:
            what, owner, may_note = mal
            if cls == "error":
                if not any(o in detail for o in (owner if isinstance(owner, tuple) else [owner])):
                    return "wrong", f"{what}: refused without naming {owner}: {detail}"
                return cls, detail
            if cls != "ok":
                return cls, detail
            if not may_note:
                return "wrong", f"malformed ({what}) accepted: {path.name}"
            robot = mindyn.load(path)
            name = owner.split("'")[1] if "'" in owner else owner
            # one naming no joint of the file is in the notes; one of a type not read, driving
            # joints of the model, in Robot.unread_transmissions (and its DriveTrainWarning)
            unread = [t["name"] for t in robot.unread_transmissions]
            if f"'{name}'" not in robot.notes and name not in unread:
                return "wrong", f"{what}: transmission '{name}' dropped without a note"
            return check_drive_T(robot, rows)
        if cls != "ok":
            return cls, detail
        robot = mindyn.load(path)
        cls, detail = check_drive_T(robot, rows)
        if cls != "ok" or robot.transmission is None:
            return cls, detail
        T = np.asarray(robot.transmission.T)
        if T.shape[0] != T.shape[1]:
            return "ok", "redundant drive: no motor-side model"
        pin_model = None
        if path.suffix == ".urdf":
            import pinocchio as pin

            model = pin.buildModelFromUrdf(str(path))
            idx = [model.joints[model.getJointId(j)].idx_v for j in robot.joint_names]
            pin_model = (model, model.createData(), idx)
        nprng = np.random.default_rng(seed)
        try:
            motor_side = check_motor_side(robot, kind, pin_model, nprng, side)
        except mindyn.Error as e:  # a refusal with its reason
            return api_refusal(e)
        r, p, terms = motor_side[2]
        checks = [
            lambda: motor_side[:2],
            lambda: check_drive_bases(r, p, nprng),
            lambda: check_drive_export(
                ctx, robot, motor_side_robot(robot, "coulomb", nprng)[1], path, index
            ),
            lambda: check_currents(ctx, robot, index, nprng),
        ]
        if index % 4 == 0:  # compiling takes a second or two
            checks.append(lambda: check_drive_codegen(r, p, terms, pin_model, nprng))
        details = []
        for check in checks:
            try:
                cls, detail = check()
            except mindyn.Error as e:  # a refusal with its reason (e.g. a degenerate geometry)
                cls, detail = api_refusal(e)
            if cls != "ok":
                return cls, detail
            details.append(detail)
        return "ok", "; ".join(d for d in details if d)

    label = f"{form} {path.name}" + (f" malformed: {mal[0]}" if mal else "") + f" {kind} {side}"
    return Case("drives", index, label, fn, argv, [path])


# ---------------------------------------------------------------------------------------------
# mjcf: MuJoCo MJCF robots read through MuJoCo's compiler, against MuJoCo's own dynamics
# ---------------------------------------------------------------------------------------------
EULERSEQS = ["xyz", "XYZ", "zyx", "ZYX", "zxz", "XZX", "xYz", "Zyx", "yzx", "YXY"]
#: <option><flag .../> attributes a valid case may disable (none changes what mindyn reads
#: beyond gravity, damping and frictionloss).
MJ_FLAGS = ["gravity", "damper", "frictionloss", "constraint", "contact", "limit", "spring",
            "actuation", "warmstart", "equality"]  # fmt: skip
#: The malformations of the mjcf target: each a refused feature of docs/mujoco.md or a file
#: MuJoCo cannot compile.
MJ_BAD = ["stiffness", "ref", "equality", "gravcomp", "two-free", "ball-terms", "free-terms",
          "velocity-limit", "broken-xml", "missing-include", "tendon-spring", "spatial-terms",
          "fluid", "mocap", "beside-free", "free-below", "bad-number", "too-many-motors",
          "tendon-with-ball", "massless", "negative-term", "name-clash"]  # fmt: skip


def _el(tag: str, attrs: dict | None = None, children=None) -> list:
    """An XML element under construction: [tag, attributes, children]."""
    return [tag, dict(attrs or {}), list(children or [])]


def _xml(e, depth: int = 0) -> str:
    pad = "  " * depth
    if isinstance(e, str):  # raw text (a comment, a malformation)
        return pad + e
    tag, attrs, children = e
    head = " ".join([tag] + [f'{k}="{v}"' for k, v in attrs.items()])
    if not children:
        return f"{pad}<{head}/>"
    inner = "\n".join(_xml(c, depth + 1) for c in children)
    return f"{pad}<{head}>\n{inner}\n{pad}</{tag}>"


def _fixed(attrs: dict, coefs: list) -> list:
    """A fixed tendon over the joints of ``coefs`` [(joint, coefficient)]."""
    return _el(
        "fixed", attrs, [_el("joint", {"joint": j, "coef": repr(float(c))}) for j, c in coefs]
    )


def _mj_fmt(rng: random.Random, v) -> str:
    """Numbers as MJCF takes them: repr, 17 significant digits or an exponent."""
    form = rng.random()
    out = []
    for x in np.atleast_1d(np.asarray(v, dtype=float)):
        if form < 0.7:
            out.append(repr(float(x)))
        elif form < 0.85:
            out.append(f"{x:.17g}")
        else:
            out.append(f"{x:.17e}")
    return " ".join(out)


def _mj_vec(rng: random.Random, n: int, lo: float = -1.0, hi: float = 1.0) -> list[float]:
    while True:
        v = [rng.uniform(lo, hi) for _ in range(n)]
        if np.linalg.norm(v) > 0.1 * max(abs(lo), abs(hi)):
            return v


def _mj_angle(rng: random.Random, degree: bool, x: float | None = None) -> float:
    a = rng.uniform(-np.pi, np.pi) if x is None else x
    if rng.random() < 0.2:
        a = rng.choice([np.pi / 2, -np.pi / 2, np.pi, np.pi / 4, 0.0])
    return math.degrees(a) if degree else a


def _mj_orientation(rng: random.Random, degree: bool) -> dict:
    """A random orientation written in one of MJCF's forms (or none)."""
    kind = rng.choice(["none", "quat", "axisangle", "euler", "euler", "xyaxes", "zaxis"])
    if kind == "quat":
        return {"quat": _mj_fmt(rng, _mj_vec(rng, 4))}
    if kind == "axisangle":
        return {"axisangle": _mj_fmt(rng, [*_mj_vec(rng, 3), _mj_angle(rng, degree)])}
    if kind == "euler":
        return {"euler": _mj_fmt(rng, [_mj_angle(rng, degree) for _ in range(3)])}
    if kind == "xyaxes":
        while True:
            x, y = np.array(_mj_vec(rng, 3)), np.array(_mj_vec(rng, 3))
            if np.linalg.norm(np.cross(x, y)) > 0.2 * np.linalg.norm(x) * np.linalg.norm(y):
                return {"xyaxes": _mj_fmt(rng, [*x, *y])}
    if kind == "zaxis":
        return {"zaxis": _mj_fmt(rng, _mj_vec(rng, 3))}
    return {}


def _mj_inertia(rng: random.Random, m: float, L: float) -> np.ndarray:
    """A body's inertia about its centre of mass (random axes, moments of a body)."""
    a = np.array([rng.uniform(0.05, 1.0) for _ in range(3)]) * m * (0.3 * L) ** 2
    Q, _ = np.linalg.qr(np.random.default_rng(rng.randrange(2**32)).normal(size=(3, 3)))
    return Q @ np.diag([a[0] + a[1], a[1] + a[2], a[0] + a[2]]) @ Q.T


def _mj_inertial(rng: random.Random, L: float, degree: bool) -> list:
    m = rng.uniform(0.2, 5.0)
    attrs = {"pos": _mj_fmt(rng, [rng.uniform(-0.3, 0.3) * L for _ in range(3)]),
             "mass": _mj_fmt(rng, m)}  # fmt: skip
    inertia = _mj_inertia(rng, m, L)
    if rng.random() < 0.5:
        full = [inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[0, 2],
                inertia[1, 2]]  # fmt: skip
        attrs["fullinertia"] = _mj_fmt(rng, full)
    else:
        attrs["diaginertia"] = _mj_fmt(rng, np.linalg.eigvalsh(inertia))
        attrs.update(_mj_orientation(rng, degree))
    return _el("inertial", attrs)


def _mj_geom(rng: random.Random, L: float, degree: bool) -> list:
    kind = rng.choice(["sphere", "box", "capsule", "cylinder", "ellipsoid", "capsule-fromto"])
    s = [rng.uniform(0.03, 0.15) * L for _ in range(3)]
    attrs = {"type": kind.split("-")[0]}
    if kind == "capsule-fromto":
        attrs["fromto"] = _mj_fmt(rng, [*(_mj_vec(rng, 3, -0.2 * L, 0.2 * L)),
                                        *(_mj_vec(rng, 3, -0.2 * L, 0.2 * L))])  # fmt: skip
        attrs["size"] = _mj_fmt(rng, s[0])
    else:
        n = {"sphere": 1, "capsule": 2, "cylinder": 2}.get(kind, 3)
        attrs["size"] = _mj_fmt(rng, s[:n])
        attrs["pos"] = _mj_fmt(rng, [rng.uniform(-0.2, 0.2) * L for _ in range(3)])
        attrs.update(_mj_orientation(rng, degree))
    if rng.random() < 0.3:
        attrs["mass"] = _mj_fmt(rng, rng.uniform(0.1, 3.0))
    elif rng.random() < 0.3:
        attrs["density"] = _mj_fmt(rng, rng.uniform(200, 3000))
    return _el("geom", attrs)


def _mj_terms(rng: random.Random) -> dict:
    """Some of a joint's or tendon's armature, damping, frictionloss (random, or 0)."""
    out = {}
    for key, hi in (("armature", 0.5), ("damping", 2.0), ("frictionloss", 1.0)):
        r = rng.random()
        if r < 0.35:
            out[key] = repr(round(rng.uniform(0.0, hi), 6))
        elif r < 0.45:
            out[key] = "0"
    return out


ZERO_TERMS = {"armature": "0", "damping": "0", "frictionloss": "0"}
#: Joint names of other forms (one is the name mindyn gives the fixed joint of the jointless
#: body 'fixed1', which is kept apart).
ODD_JOINT_NAMES = ["elbow joint", "ä1", "j.2", "J-3", "fixed1__fixed", "q", "x__y", "0"]
#: A body's mass whatever the compiler's inertiafromgeom.
MASS = ["inertial", {"pos": "0 0 0", "mass": "1", "diaginertia": "0.01 0.01 0.01"}, []]


def _mj_joint(rng: random.Random, name: str, kind: str, L: float, degree: bool, classes) -> list:
    attrs: dict = {"name": name}
    if kind != "hinge" or rng.random() < 0.5:
        attrs["type"] = kind
    if rng.random() < 0.6:
        axis = [0.0, 0.0, 0.0]
        axis[rng.randrange(3)] = rng.choice([1.0, -1.0, 2.5])
    else:
        axis = _mj_vec(rng, 3)
    attrs["axis"] = _mj_fmt(rng, axis)
    if rng.random() < 0.4:
        attrs["pos"] = _mj_fmt(rng, [rng.uniform(-0.1, 0.1) * L for _ in range(3)])
    if rng.random() < 0.1:
        attrs["limited"] = "false"
    if rng.random() < 0.5:
        lo, hi = -rng.uniform(0.3, 3.0), rng.uniform(0.3, 3.0)
        if kind == "hinge":
            lo, hi = _mj_angle(rng, degree, lo), _mj_angle(rng, degree, hi)
            lo, hi = min(lo, hi) - 1e-3, max(lo, hi) + 1e-3
        attrs["range"] = _mj_fmt(
            rng, [lo * (L if kind == "slide" else 1), hi * (L if kind == "slide" else 1)]
        )
    if rng.random() < 0.3:
        effort = rng.uniform(1.0, 100.0)
        attrs["actuatorfrcrange"] = _mj_fmt(rng, [-effort, effort])
    if classes and rng.random() < 0.4:
        attrs["class"] = rng.choice(classes)
    attrs.update(_mj_terms(rng))
    return _el("joint", attrs)


class MjcfCase:
    """A random MJCF robot (valid, or with one malformation): the element tree, its extra
    files and what the oracle needs to know of it (the velocity limits written, the
    malformation and the names the refusal must give)."""

    def __init__(self, rng: random.Random, path: Path, round_trip: bool):
        self.rng, self.path = rng, path
        self.files: dict[Path, str] = {}
        self.speeds: dict[str, float] = {}
        self.mal: tuple[str, tuple[str, ...]] | None = None
        self.degree = rng.random() < 0.5
        self.L = rng.choice([1.0, 1.0, 1.0, 0.5, 0.05, 10.0])
        self._draw(round_trip)

    # -- drawing ------------------------------------------------------------------------
    def _draw(self, round_trip: bool) -> None:
        rng, L, deg = self.rng, self.L, self.degree
        compiler: dict = {}
        if not self.degree or rng.random() < 0.5:
            compiler["angle"] = "degree" if deg else "radian"
        if rng.random() < 0.5:
            compiler["eulerseq"] = rng.choice(EULERSEQS)
        ifg = rng.choice(["", "auto", "true", "false"])
        if round_trip and ifg == "true":  # MuJoCo would override the inertials written back
            ifg = "auto"
        if ifg:
            compiler["inertiafromgeom"] = ifg
        if not round_trip:  # options that change the inertias written back
            for key, value in (
                ("balanceinertia", "true"),
                ("fusestatic", "true"),
                ("boundmass", "0.5"),
                ("boundinertia", "0.01"),
                ("settotalmass", "12.5"),
            ):
                if rng.random() < 0.1:
                    compiler[key] = value
        self.compiler = compiler
        # defaults, with classes
        self.classes = []
        top = _el("default", {}, [_el("joint", _mj_terms(rng))])
        if rng.random() < 0.5:
            top[2].append(_el("geom", {"density": repr(round(rng.uniform(300, 3000), 3))}))
        if rng.random() < 0.7:
            c1 = _el("default", {"class": "c1"}, [_el("joint", _mj_terms(rng))])
            self.classes.append("c1")
            if rng.random() < 0.5:
                c1[2].append(
                    _el(
                        "default",
                        {"class": "c2"},
                        [_el("joint", {**_mj_terms(rng), "axis": "0 1 0"})],
                    )
                )
                self.classes.append("c2")
            top[2].append(c1)
        self.defaults = top
        # the moving joints and their bodies
        n = rng.randint(1, 7)
        self.free = rng.random() < 0.25
        self.ball = rng.random() < 0.25
        tree = rng.random() < 0.5
        kinds = [rng.choice(["hinge", "hinge", "slide"]) for _ in range(n)]
        if self.ball:
            kinds[rng.randrange(n)] = "ball"
        self.world = _el("worldbody")
        self.moving: list[list] = []  # the bodies carrying joints
        self.joints: dict[str, tuple[str, list]] = {}  # name -> (kind, element)
        names = [f"j{k}" for k in rng.sample(range(100), n)]
        for k in range(n):  # now and then a name of another form
            if rng.random() < 0.15:
                odd = rng.choice(ODD_JOINT_NAMES)
                names[k] = odd if odd not in names else names[k]
        self.free_body = None
        if self.free:
            free_body = self._body("base", self.world, round_trip)
            if rng.random() < 0.5:
                joint = _el("freejoint", {"name": "root"})
            else:
                joint = _el("joint", {"name": "root", "type": "free", **ZERO_TERMS})
            free_body[2].insert(0, joint)
            self.joints["root"] = ("free", joint)
            self.moving.append(free_body)
            self.free_body = free_body
        k = 0
        while k < n:
            if self.moving and (tree or self.free):
                parent = rng.choice(self.moving) if tree else self.moving[-1]
            elif self.moving:
                parent = self.moving[-1]
            else:
                parent = self.world
            if parent is not self.world and rng.random() < 0.25:  # a jointless body between
                parent = self._body(f"fixed{k}", parent, round_trip, moving=False)
            body = self._body(f"b{k}", parent, round_trip)
            # two joints in one body (MuJoCo refuses a ball joint followed by another)
            for _ in range(2 if k + 1 < n and kinds[k] != "ball" and rng.random() < 0.15 else 1):
                kind, name = kinds[k], names[k]
                if kind == "ball":
                    attrs = {"name": name, "type": "ball", **ZERO_TERMS}
                    if rng.random() < 0.4:
                        attrs["pos"] = _mj_fmt(rng, [rng.uniform(-0.1, 0.1) * L for _ in range(3)])
                    if rng.random() < 0.2:  # a cone limit, not read (a warning)
                        attrs["range"] = _mj_fmt(rng, [0, _mj_angle(rng, deg, 1.0)])
                    if self.classes and rng.random() < 0.4:
                        attrs["class"] = rng.choice(self.classes)
                    joint = _el("joint", attrs)
                else:
                    joint = _mj_joint(rng, name, kind, L, deg, self.classes)
                body[2].insert(len([c for c in body[2] if c[0] == "joint"]), joint)
                self.joints[name] = (kind, joint)
                k += 1
            self.moving.append(body)
        for _ in range(rng.randint(0, 2)):  # jointless leaves
            self._body(f"leaf{_}", rng.choice(self.moving), round_trip, moving=False)
        if rng.random() < 0.3:  # a static body on the world
            self._body("stand", self.world, round_trip, moving=False)
        # tendons: over one joint (folded onto it), over several (motors, fixed base only)
        self.tendons = _el("tendon")
        single = [j for j, (kind, _) in self.joints.items() if kind in ("hinge", "slide")]
        for t in range(rng.randint(0, 2) if single else 0):
            j = rng.choice(single)
            coef = rng.choice([1.0, -1.0, 40.0, -80.0, 0.5, 3.7])
            self.tendons[2].append(_fixed({"name": f"t{t}", **_mj_terms(rng)}, [(j, coef)]))
        if not (self.free or self.ball) and len(single) >= 2 and rng.random() < 0.3:
            over = rng.sample(single, rng.choice([2, 2, 3]) if len(single) >= 3 else 2)
            for j in over:  # the motors' joints have no terms of their own
                self.joints[j][1][1].update(ZERO_TERMS)
            self.tendons[2] = [e for e in self.tendons[2] if e[2][0][1]["joint"] not in over]
            self._motor_tendon("m0", over, terms=True)
            if len(over) == 2 and rng.random() < 0.5:  # a differential
                self._motor_tendon("m1", over, terms=rng.random() < 0.7)
            if not self._one_branch(over):  # MuJoCo drops the armature between the branches
                self.mal = ("tendon armature across branches", ("'m0'", "'m1'"))
        # velocity limits, option, an include
        self.custom = _el("custom")
        for j in single:
            if rng.random() < 0.3:
                self.speeds[j] = round(rng.uniform(0.5, 10.0), 4)
                self.custom[2].append(
                    _el("numeric", {"name": f"velocity_limit:{j}", "data": repr(self.speeds[j])})
                )
        self.option = _el("option")
        if rng.random() < 0.5:
            self.option[1]["gravity"] = _mj_fmt(
                rng, [rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-12, 0)]
            )
        if rng.random() < 0.4:
            flags = rng.sample(MJ_FLAGS, rng.randint(1, 3))
            self.option[2].append(_el("flag", {f: "disable" for f in flags}))
        self.include = rng.random() < 0.2
        self.actuators = _el("actuator")
        for j in single:
            if rng.random() < 0.3:
                self.actuators[2].append(_el("motor", {"joint": j, "gear": "50"}))

    def _motor_tendon(self, name: str, over: list[str], terms: bool) -> None:
        rng = self.rng
        coefs = [rng.choice([1.0, -1.0, 20.0, -15.0, 0.5, 2.0]) * rng.uniform(0.5, 2) for _ in over]
        attrs = {"name": name}
        if terms:
            attrs.update({k: repr(round(self.rng.uniform(0.001, 0.5), 5)) for k in ZERO_TERMS})
        self.tendons[2].append(_fixed(attrs, list(zip(over, coefs))))

    def _one_branch(self, joints: list[str]) -> bool:
        """Whether ``joints`` are on one branch of the tree (each pair: one moves the other)."""
        paths = {}

        def walk(e, path):
            if e[0] == "joint" and e[1].get("name") in joints:
                paths[e[1]["name"]] = path
            for c in e[2]:
                if not isinstance(c, str):
                    walk(c, path + [id(e)] if e[0] == "body" else path)

        walk(self.world, [])
        for a in joints:
            for b in joints:
                pa, pb = paths[a], paths[b]
                if pa[: len(pb)] != pb and pb[: len(pa)] != pa:
                    return False
        return True

    def _drop(self, joints: set) -> None:
        """Leaves out the actuators, tendons and numerics of ``joints`` (gone)."""
        self.actuators[2] = [e for e in self.actuators[2] if e[1]["joint"] not in joints]
        self.tendons[2] = [e for e in self.tendons[2] if not {c[1]["joint"] for c in e[2]} & joints]
        self.custom[2] = [e for e in self.custom[2] if e[1]["name"].split(":")[1] not in joints]
        for j in joints:
            self.speeds.pop(j, None)

    def _body(self, name: str, parent: list, round_trip: bool, moving: bool = True) -> list:
        rng, L, deg = self.rng, self.L, self.degree
        attrs = {"name": name, "pos": _mj_fmt(rng, [rng.uniform(-0.5, 0.5) * L for _ in range(3)])}
        attrs.update(_mj_orientation(rng, deg))
        if self.classes and rng.random() < 0.3:
            attrs["childclass"] = rng.choice(self.classes)
        if not moving and not round_trip and rng.random() < 0.3:
            del attrs["name"]  # an unnamed jointless body
        body = _el("body", attrs)
        ifg = self.compiler.get("inertiafromgeom", "auto")
        inertial = ifg == "false" or (ifg == "auto" and rng.random() < 0.6)
        geoms = ifg == "true" or not inertial or rng.random() < 0.3
        if not moving and rng.random() < 0.4:  # a massless jointless body
            inertial = geoms = False
        if inertial:
            body[2].append(_mj_inertial(rng, L, deg))
        if geoms:
            body[2] += [_mj_geom(rng, L, deg) for _ in range(rng.randint(1, 2))]
        if rng.random() < 0.15:  # in a <frame>, which moves the body
            frame = {"pos": _mj_fmt(rng, [rng.uniform(-0.2, 0.2) * L for _ in range(3)])}
            parent[2].append(_el("frame", {**frame, **_mj_orientation(rng, deg)}, [body]))
        else:
            parent[2].append(body)
        return body

    # -- malformations ------------------------------------------------------------------
    def malform(self) -> None:
        """One malformation (a feature docs/mujoco.md refuses, or a file MuJoCo cannot compile):
        sets ``self.mal`` = (what, the names a refusal must give, any one of them)."""
        rng = self.rng
        what = rng.choice(MJ_BAD)
        single = [j for j, (kind, _) in self.joints.items() if kind in ("hinge", "slide")]
        file = self.path.name
        if what in ("stiffness", "ref", "bad-number", "negative-term") and single:
            j = rng.choice(single)
            key, value = {
                "stiffness": ("stiffness", "3.5"),
                "ref": ("ref", "0.25"),
                "bad-number": (
                    rng.choice(["damping", "armature", "pos", "range"]),
                    rng.choice(BAD_NUMBERS[:2] + ["1 x", "0x", "1e"]),
                ),
                "negative-term": (rng.choice(list(ZERO_TERMS)), "-0.5"),
            }[what]
            self.joints[j][1][1][key] = value
            self.mal = (what, (f"'{j}'",) if what not in ("bad-number",) else (file,))
            if what == "negative-term":  # MuJoCo may refuse it first, naming the file
                self.mal = (what, (f"'{j}'", file))
            return
        if what == "equality" and len(self.joints) >= 2:
            a, b = rng.sample(sorted(self.joints), 2)
            bodies = [e[1]["name"] for e in self.moving]
            eq = rng.choice(
                [
                    _el("joint", {"name": "eq_couple", "joint1": a, "joint2": b}),
                    _el("weld", {"name": "eq_couple", "body1": rng.choice(bodies)}),
                    _el(
                        "connect",
                        {"name": "eq_couple", "body1": rng.choice(bodies), "anchor": "0 0 0"},
                    ),
                ]
            )
            if eq[0] == "joint" and "ball" in (self.joints[a][0], self.joints[b][0]):
                eq = _el("weld", {"name": "eq_couple", "body1": bodies[-1]})
            if eq[0] == "joint" and "free" in (self.joints[a][0], self.joints[b][0]):
                eq = _el("weld", {"name": "eq_couple", "body1": bodies[-1]})
            self.equality = _el("equality", {}, [eq])
            self.mal = (what, ("'eq_couple'",))
            return
        if what == "gravcomp":
            body = rng.choice(self.moving)
            body[1]["gravcomp"] = "1"
            self.mal = (what, (f"'{body[1]['name']}'",))
            return
        if what == "two-free":
            body = _el(
                "body",
                {"name": "other", "pos": "1 0 0"},
                [
                    _el("freejoint", {"name": "other_free"}),
                    MASS,
                    _el("geom", {"type": "sphere", "size": "0.1"}),
                ],
            )
            self.world[2].append(body)
            self.mal = (what, ("'other_free'", "'other'"))
            return
        if what == "ball-terms" and self.ball:
            j = next(j for j, (kind, _) in self.joints.items() if kind == "ball")
            key = rng.choice(list(ZERO_TERMS))
            self.joints[j][1][1][key] = "0.1"
            self.mal = (what, (f"'{j}'",))
            return
        if what == "free-terms" and self.free:
            kind, joint = self.joints["root"]
            joint[0], joint[1] = "joint", {"name": "root", "type": "free", **ZERO_TERMS}
            joint[1][rng.choice(list(ZERO_TERMS))] = "0.2"
            self.mal = (what, ("'root'",))
            return
        if what == "velocity-limit":
            j = rng.choice(sorted(self.joints))
            name, data = rng.choice(
                [
                    ("velocity_limit:nojoint", "2"),
                    (f"velocity_limit:{j}", "-1"),
                    (f"velocity_limit:{j}", "1 2"),
                    (f"velocity_limit:{j}", "0"),
                    (f"velocity_limit:{j}", "inf"),
                    (f"velocity_limit:{j}", "nan"),
                ]
            )
            if self.joints[j][0] in ("ball", "free"):
                data = "2"  # a velocity limit on a joint of several degrees of freedom
            self.custom[2] = [e for e in self.custom[2] if e[1]["name"] != name]
            self.custom[2].append(_el("numeric", {"name": name, "data": data}))
            self.mal = (what, (name, file))  # MuJoCo refuses inf / nan itself
            return
        if what == "missing-include":
            self.extra = _el("include", {"file": "missing-part.xml"})
            self.mal = (what, ("missing-part.xml",))
            return
        if what in ("tendon-spring", "spatial-terms") and single:
            j = rng.choice(single)
            if what == "tendon-spring":
                t = _fixed({"name": "spring_t", "stiffness": "5", "damping": "0.1"}, [(j, 2)])
            else:
                body = self.joints[j][1]
                host = next(b for b in self.moving if body in b[2])
                host[2].append(_el("site", {"name": "s_end", "pos": "0.1 0 0"}))
                self.world[2].insert(0, _el("site", {"name": "s_start", "pos": "0 0 0.1"}))
                t = _el(
                    "spatial",
                    {"name": "spring_t", "frictionloss": "0.3"},
                    [_el("site", {"site": "s_start"}), _el("site", {"site": "s_end"})],
                )
            self.tendons[2].append(t)
            self.mal = (what, ("'spring_t'",))
            return
        if what == "fluid":
            self.option[1][rng.choice(["density", "viscosity"])] = "1.2"
            self.mal = (what, ("density",))
            return
        if what == "mocap":
            body = _el(
                "body",
                {"name": "target", "mocap": "true", "pos": "0 1 0"},
                [
                    _el(
                        "body",
                        {"name": "finger"},
                        [
                            _el("joint", {"name": "fj", "axis": "0 0 1"}),
                            MASS,
                            _el("geom", {"type": "sphere", "size": "0.05"}),
                        ],
                    )
                ],
            )
            self.world[2].append(body)
            self.mal = (what, ("'fj'", "'target'", "'base'"))  # or: not below the free body
            return
        if what == "beside-free" and self.free:
            body = _el(
                "body",
                {"name": "beside", "pos": "0 1 0"},
                [
                    _el("joint", {"name": "bj", "axis": "0 0 1"}),
                    MASS,
                    _el("geom", {"type": "sphere", "size": "0.05"}),
                ],
            )
            self.world[2].append(body)
            self.mal = (what, ("'bj'",))
            return
        if what == "free-below" and len(self.moving) > 1 + self.free:
            body = self.moving[-1]
            gone = {c[1]["name"] for c in body[2] if c[0] == "joint"}
            body[2] = [c for c in body[2] if c[0] != "joint"]
            self._drop(gone)
            body[2].insert(0, _el("freejoint", {"name": "inner_free"}))
            self.mal = (what, (file,))
            return
        if what == "too-many-motors" and len(single) >= 2 and not (self.free or self.ball):
            a, b = rng.sample(single, 2)
            self.joints[a][1][1]["damping"] = "0.3"
            self.joints[b][1][1]["armature"] = "0.2"
            self.tendons[2].append(_fixed({"name": "over_t", "damping": "0.1"}, [(a, 1), (b, 1)]))
            self.mal = (what, ("'over_t'",))
            return
        if what == "tendon-with-ball" and self.ball and len(single) >= 2:
            a, b = rng.sample(single, 2)
            self.tendons[2].append(_fixed({"name": "ball_t", "armature": "0.1"}, [(a, 1), (b, -2)]))
            self.mal = (what, ("'ball_t'",))
            return
        two = [b for b in self.moving if len([c for c in b[2] if c[0] == "joint"]) > 1]
        if what == "name-clash" and two:
            body = rng.choice(two)
            clash = f"{body[1]['name']}__{next(c for c in body[2] if c[0] == 'joint')[1]['name']}"
            self._body("leaf", rng.choice(self.moving), False, moving=False)[1]["name"] = clash
            self.mal = (what, (f"'{clash}'",))
            return
        if what == "massless":
            body = self.moving[-1]
            body[2] = [c for c in body[2] if c[0] not in ("inertial", "geom", "body", "frame")]
            self.compiler["inertiafromgeom"] = "auto"
            self.mal = (what, (file,))
            return
        # broken XML (also the fallback of a malformation the robot has no place for)
        self.broken = rng.choice(["truncate", "unclosed", "garbage", "attribute", "root"])
        self.mal = ("broken-xml " + self.broken, (file,))

    # -- writing ------------------------------------------------------------------------
    def write(self) -> Path:
        parts: list = [
            f"<!-- a random robot, {'degrees' if self.degree else 'radians'} -->",
            _el("compiler", self.compiler),
            self.option,
        ]
        if self.include:
            part = self.path.with_name(self.path.stem + "-defaults.xml")
            self.files[part] = "<mujoco>\n" + _xml(self.defaults, 1) + "\n</mujoco>\n"
            parts.append(_el("include", {"file": part.name}))
        else:
            parts.append(self.defaults)
        if getattr(self, "extra", None) is not None:
            parts.append(self.extra)
        parts.append(self.world)
        for e in (self.tendons, getattr(self, "equality", None), self.custom, self.actuators):
            if e is not None and e[2]:
                parts.append(e)
        text = '<mujoco model="mjcf">\n' + "\n".join(_xml(p, 1) for p in parts) + "\n</mujoco>\n"
        broken = getattr(self, "broken", None)
        if broken == "truncate":
            text = text[: self.rng.randrange(len(text) // 3, len(text) - 12)]
        elif broken == "unclosed":
            text = text.replace("</worldbody>", "", 1)
        elif broken == "garbage":
            text = text.replace("<worldbody>", "<worldbody>\n  <body <<>", 1)
        elif broken == "attribute":
            text = text.replace(
                "<worldbody>",
                '<worldbody>\n  <body name="x" pos="1 2 3"><geom size="0.1" fantasy="1"/></body>',
                1,
            )
        elif broken == "root":
            text = text.replace('<mujoco model="mjcf">', '<mujoco model="mjcf"><mujoco>', 1)
        for f, t in self.files.items():
            f.write_text(t)
        self.path.write_text(text)
        return self.path


def mj_to_mindyn(m, robot, q) -> np.ndarray:
    """S with MuJoCo's qvel = S v for mindyn's v at mindyn's q (joints by name): the free
    joint's linear velocity is R v (R the body's rotation), every other velocity the same.
    Generalised forces map back as S^T."""
    S = np.zeros((m.nv, robot.nv))
    iq = iv = 0
    for kind, name in zip(robot.joint_types, robot.joint_names, strict=True):
        dof = int(m.jnt_dofadr[m.joint(name).id])
        if kind == "floating":
            x, y, z, w = q[iq + 3 : iq + 7]
            S[dof : dof + 3, iv : iv + 3] = _wxyz_matrix([w, x, y, z])
            S[dof + 3 : dof + 6, iv + 3 : iv + 6] = np.eye(3)
            iq, iv = iq + 7, iv + 6
        elif kind == "spherical":
            S[dof : dof + 3, iv : iv + 3] = np.eye(3)
            iq, iv = iq + 4, iv + 3
        else:
            S[dof, iv] = 1.0
            iq, iv = iq + 1, iv + 1
    return S


def _wxyz_matrix(quat) -> np.ndarray:
    import mujoco

    out = np.zeros(9)
    mujoco.mju_quat2Mat(out, np.asarray(quat, dtype=float))
    return out.reshape(3, 3)


def mj_qpos(m, robot, q, v, a):
    """MuJoCo's qpos, qvel, qacc of mindyn's q, v, a: quaternions (w, x, y, z) for mindyn's
    (x, y, z, w); qvel = S v; the free joint's qacc = R (a + w x v) (the derivative of R v)."""
    qpos = np.array(m.qpos0)
    S = mj_to_mindyn(m, robot, q)
    qvel, qacc = S @ v, S @ a
    iq = iv = 0
    for kind, name in zip(robot.joint_types, robot.joint_names, strict=True):
        j = m.joint(name).id
        adr, dof = int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j])
        if kind == "floating":
            x, y, z, w = q[iq + 3 : iq + 7]
            qpos[adr : adr + 7] = [*q[iq : iq + 3], w, x, y, z]
            R = _wxyz_matrix([w, x, y, z])
            qacc[dof : dof + 3] += R @ np.cross(v[iv + 3 : iv + 6], v[iv : iv + 3])
            iq, iv = iq + 7, iv + 6
        elif kind == "spherical":
            x, y, z, w = q[iq : iq + 4]
            qpos[adr : adr + 4] = [w, x, y, z]
            iq, iv = iq + 4, iv + 3
        else:
            qpos[adr] = q[iq]
            iq, iv = iq + 1, iv + 1
    return qpos, qvel, qacc, S


def mj_state(robot, nprng, moving: bool = False):
    """Random q (unit quaternions), v, a of ``robot``; ``moving``: every velocity 0.5..2 in
    magnitude."""
    q, v = [], nprng.uniform(-2, 2, robot.nv)
    for kind in robot.joint_types:
        if kind == "floating":
            quat = nprng.normal(size=4)
            q += [*nprng.uniform(-1, 1, 3), *(quat / np.linalg.norm(quat))]
        elif kind == "spherical":
            quat = nprng.normal(size=4)
            q += list(quat / np.linalg.norm(quat))
        else:
            q.append(nprng.uniform(-2, 2))
    if moving:
        v = nprng.uniform(0.5, 2, robot.nv) * nprng.choice([-1, 1], robot.nv)
    return np.array(q), v, nprng.uniform(-2, 2, robot.nv)


def _mj_fixed_tendons(m) -> list[tuple[int, np.ndarray]]:
    """Each fixed tendon's id and its Jacobian (coefficients on the dofs)."""
    import mujoco

    out = []
    for t in range(m.ntendon):
        adr, num = int(m.tendon_adr[t]), int(m.tendon_num[t])
        if any(
            int(m.wrap_type[w]) != int(mujoco.mjtWrap.mjWRAP_JOINT) for w in range(adr, adr + num)
        ):
            continue
        J = np.zeros(m.nv)
        for w in range(adr, adr + num):
            J[int(m.jnt_dofadr[int(m.wrap_objid[w])])] += float(m.wrap_prm[w])
        out.append((t, J))
    return out


def mj_reference(m, robot, q, v, a, *, friction_on: bool = False):
    """MuJoCo's inverse dynamics and mass matrix at mindyn's (q, v, a), in mindyn's
    coordinates (tau = S^T qfrc, M = S^T M_mj S), with limits and contacts off. The file's own
    <option> flags stay; the frictionloss constraint is off and its saturated force
    (frictionloss sign of each dof's and fixed tendon's velocity) is added by hand where the
    file leaves it on; ``friction_on`` keeps the constraint instead, and also returns whether
    every friction row is saturated (MuJoCo's efc_state linear), where its force is exactly
    that."""
    import mujoco

    bits = mujoco.mjtDisableBit
    flags = int(m.opt.disableflags)
    active = not flags & (int(bits.mjDSBL_FRICTIONLOSS) | int(bits.mjDSBL_CONSTRAINT))
    off = int(bits.mjDSBL_LIMIT) | int(bits.mjDSBL_CONTACT)
    if not friction_on:
        off |= int(bits.mjDSBL_FRICTIONLOSS)
    m.opt.disableflags = flags | off
    warn = mujoco.get_mju_user_warning()
    # a random model's warnings (a nearly singular inertia) go nowhere: MuJoCo's default
    # handler appends them to MUJOCO_LOG.TXT in the folder the campaign runs from
    mujoco.set_mju_user_warning(lambda text: None)
    try:
        d = mujoco.MjData(m)
        qpos, qvel, qacc, S = mj_qpos(m, robot, q, v, a)
        d.qpos[:], d.qvel[:], d.qacc[:] = qpos, qvel, qacc
        mujoco.mj_inverse(m, d)
        qfrc = d.qfrc_inverse.copy()
        if active and not friction_on:
            qfrc += np.asarray(m.dof_frictionloss) * np.sign(qvel)
            for t, J in _mj_fixed_tendons(m):
                qfrc += J * float(m.tendon_frictionloss[t]) * np.sign(J @ qvel)
        full = np.zeros((m.nv, m.nv))
        if hasattr(d, "qM"):  # MuJoCo 3
            mujoco.mj_fullM(m, full, d.qM)
        else:  # MuJoCo 4
            mujoco.mj_fullM(m, d, full)
        saturated = True
        if friction_on:
            kinds = d.efc_type[: d.nefc]
            rows = np.isin(
                kinds,
                [
                    mujoco.mjtConstraint.mjCNSTR_FRICTION_DOF,
                    mujoco.mjtConstraint.mjCNSTR_FRICTION_TENDON,
                ],
            )
            linear = [
                mujoco.mjtConstraintState.mjCNSTRSTATE_LINEARNEG,
                mujoco.mjtConstraintState.mjCNSTRSTATE_LINEARPOS,
            ]
            saturated = bool(rows.any()) and bool(
                np.isin(d.efc_state[: d.nefc][rows], linear).all()
            )
    finally:
        m.opt.disableflags = flags
        mujoco.set_mju_user_warning(warn)
    return S.T @ qfrc, S.T @ full @ S, saturated


def _mj_without_drive_terms(m) -> None:
    """MuJoCo's model without armature, damping and frictionloss (mindyn's dynamics of a robot
    with a free or ball joint leave them out, docs/mujoco.md)."""
    for key in (
        "dof_armature",
        "dof_damping",
        "dof_frictionloss",
        "tendon_armature",
        "tendon_damping",
        "tendon_frictionloss",
    ):
        getattr(m, key)[:] = 0.0


def check_mjcf_dynamics(robot, path: Path, nprng) -> tuple[str, str]:
    """mindyn's inverse dynamics, mass matrix and W_b (Y pi) of ``robot`` (read from the MJCF
    ``path``) against MuJoCo's mj_inverse and mj_fullM at three random states, to 1e-9
    relative; with frictionloss, also at moving states where MuJoCo's dry friction is
    saturated."""
    import mujoco

    m = mujoco.MjModel.from_xml_path(str(path))
    single = robot.single_dof
    if not single:
        _mj_without_drive_terms(m)
    p = robot.parameters(rotor=single, friction=single)
    bp = mindyn.base_parameters(robot, rotor=single, friction=single)
    pb = bp.values(p)
    worst = [0.0, 0.0, 0.0]
    for _ in range(3):
        q, v, a = mj_state(robot, nprng)
        tau, M, _ = mj_reference(m, robot, q, v, a)
        W = robot.regressor(q, v, a, rotor=single, friction=single)
        scale = np.abs(W) @ np.abs(p)
        worst[0] = max(worst[0], rel_err(robot.inverse_dynamics(q, v, a, p), tau, scale))
        worst[1] = max(worst[1], rel_err(bp.regressor(q, v, a) @ pb, tau, scale))
        worst[2] = max(worst[2], rel_err(robot.mass_matrix(q, p), M, M))
    detail = (
        f"vs mj_inverse {worst[0]:.3g}, W_b (Y pi) {worst[1]:.3g}, mass matrix vs "
        f"mj_fullM {worst[2]:.3g} (n_b={bp.n})"
    )
    if not max(worst) <= ORACLE_TOL:
        return "wrong", detail
    if single and np.any(p[12::13]):
        seen = 0
        for _ in range(3):
            q, v, a = mj_state(robot, nprng, moving=True)
            tau, _, saturated = mj_reference(m, robot, q, v, a, friction_on=True)
            if not saturated:
                continue
            seen += 1
            scale = np.abs(robot.regressor(q, v, a, rotor=True, friction=True)) @ np.abs(p)
            err = rel_err(robot.inverse_dynamics(q, v, a, p), tau, scale)
            if not err <= ORACLE_TOL:
                return "wrong", f"{detail}; with MuJoCo's frictionloss, moving: {err:.3g}"
        detail += f"; frictionloss on at {seen} saturated states"
    return "ok", detail


def check_mjcf_read(robot, path: Path, speeds: dict) -> tuple[str, str]:
    """The joints read (names, kinds), the velocity limits written and, for a robot with a free
    or ball joint (whose dynamics leave them out), the hinges' armature, damping and
    frictionloss (with those of fixed tendons over one joint: c^2, c^2, |c|) against MuJoCo's
    compiled model."""
    import mujoco

    m = mujoco.MjModel.from_xml_path(str(path))
    kinds = {
        int(mujoco.mjtJoint.mjJNT_HINGE): ("revolute", "continuous"),
        int(mujoco.mjtJoint.mjJNT_SLIDE): ("prismatic",),
        int(mujoco.mjtJoint.mjJNT_BALL): ("spherical",),
        int(mujoco.mjtJoint.mjJNT_FREE): ("floating",),
    }
    want = {m.joint(j).name: kinds[int(m.jnt_type[j])] for j in range(m.njnt)}
    if sorted(want) != sorted(robot.joint_names):
        return "wrong", f"joints {robot.joint_names}, MuJoCo's {sorted(want)}"
    for name, kind in zip(robot.joint_names, robot.joint_types, strict=True):
        if kind not in want[name]:
            return "wrong", f"joint '{name}' read as {kind}, MuJoCo's {want[name]}"
    for k, name in enumerate(robot.joint_names):
        got = robot.limits["velocity"][k]
        if name in speeds and got != speeds[name] or name not in speeds and not np.isnan(got):
            return "wrong", f"velocity limit of '{name}' {got}, written {speeds.get(name)}"
    if robot.single_dof:
        return "ok", ""
    bits = mujoco.mjtDisableBit
    flags = int(m.opt.disableflags)
    terms = {}
    for j in range(m.njnt):
        dof = int(m.jnt_dofadr[j])
        terms[m.joint(j).name] = np.array(
            [m.dof_armature[dof], m.dof_damping[dof], m.dof_frictionloss[dof]]
        )
    for t, J in _mj_fixed_tendons(m):
        (dofs,) = np.nonzero(J)
        if len(dofs) == 1:
            c = J[dofs[0]]
            j = int(m.dof_jntid[dofs[0]])
            terms[m.joint(j).name] += [
                c * c * m.tendon_armature[t],
                c * c * m.tendon_damping[t],
                abs(c) * m.tendon_frictionloss[t],
            ]
    for k, name in enumerate(robot.joint_names):
        if robot.joint_types[k] in ("floating", "spherical"):
            continue
        want3 = terms[name].copy()
        if flags & int(bits.mjDSBL_DAMPER):
            want3[1] = 0.0
        if flags & (int(bits.mjDSBL_FRICTIONLOSS) | int(bits.mjDSBL_CONSTRAINT)):
            want3[2] = 0.0
        got = [robot.rotor_inertia[k], robot.viscous[k], robot.coulomb[k]]
        if rel_err(got, want3, np.maximum(np.abs(want3), 1e-300)) > 1e-12:
            return "wrong", f"joint '{name}': Ia, Fv, Fc {got}, MuJoCo's {list(want3)}"
    return "ok", ""


def check_mjcf_round_trip(ctx, robot, path: Path, index: int, nprng) -> tuple[str, str]:
    """The robot's own parameters written with `mindyn export --mjcf` (the file written back)
    and, through the library, as a new MJCF: each read back has the same inverse dynamics and
    agrees with MuJoCo on the file written."""
    from mindyn.mjcf import write_mjcf

    single = robot.single_dof
    names = robot.parameter_names(rotor=True, friction=True)
    p = robot.parameters(rotor=True, friction=True)  # a free or ball joint's: 0
    doc = {
        "robot": robot.name,
        "classical": dict(zip(names, map(float, p), strict=True)),
        "rotor": True,
        "friction": True,
        "drive_side": robot.drive_side,
    }
    jfile = ctx.work / f"mjcf-{index}.id.json"
    jfile.write_text(json.dumps(doc))
    back = ctx.work / f"mjcf-{index}-back.xml"
    cls, detail = cli_class(*run_cli(["export", path, jfile, "--mjcf", back]))
    if cls != "ok":
        return cls, f"export --mjcf: {detail}"
    new = ctx.work / f"mjcf-{index}-new.xml"
    # a description that is not an MJCF to start from: a new file, one body per link
    write_mjcf(robot, p, new, source=ctx.work / f"mjcf-{index}-none.urdf")
    details = []
    for what, out in (("written back", back), ("new", new)):
        with warnings_off():
            again = mindyn.load(out)
        if sorted(again.joint_names) != sorted(robot.joint_names):
            return "wrong", f"{what}: joints {again.joint_names}, not {robot.joint_names}"
        order = [again.joint_names.index(name) for name in robot.joint_names]
        pa = again.parameters(rotor=True, friction=True)
        if not single:  # the hinges' terms kept, outside the dynamics (docs/mujoco.md)
            for key in ("rotor_inertia", "viscous", "coulomb"):
                got, want = np.asarray(getattr(again, key))[order], getattr(robot, key)
                if rel_err(got, want, np.maximum(np.abs(want), 1e-300)) > 1e-12:
                    return "wrong", f"{what} MJCF read back: {key} {list(got)}, not {list(want)}"
            pa, p10 = again.params, robot.params
        else:
            p10 = p
        states = [mj_state(robot, nprng) for _ in range(2)]
        worst = id_difference(
            robot,
            (p10, p10),
            again,
            pa,
            states,
            rotor=single,
            friction=single,
            order=_reorder(robot, again),
        )
        if not worst <= ORACLE_TOL:
            return "wrong", f"{what} MJCF read back: inverse dynamics differ by {worst:.3g}"
        cls, detail = check_mjcf_dynamics(again, out, nprng)
        if cls != "ok":
            return cls, f"{what} MJCF: {detail}"
        details.append(f"{what} {worst:.2g}")
    return "ok", "round trip: " + ", ".join(details)


@contextlib.contextmanager
def warnings_off():
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


def case_mjcf(ctx, index: int, rng: random.Random) -> Case:
    path = ctx.work / f"mjcf-{index}.xml"
    round_trip = index % 3 == 0
    case = MjcfCase(rng, path, round_trip)
    if rng.random() < 0.4 and case.mal is None:
        case.malform()
    case.write()
    seed = rng.randrange(2**32)
    argv = ["info", path]

    def fn():
        cls, detail = cli_class(*run_cli(argv))
        if case.mal is not None:
            what, names = case.mal
            if cls == "ok":
                return "wrong", f"malformed ({what}) loaded: {path.name}"
            if cls == "error" and not any(x in detail for x in names):
                return "wrong", f"{what}: refused without naming {' or '.join(names)}: {detail}"
            return cls, detail
        if cls != "ok":
            return cls, detail
        with warnings_off():
            robot = mindyn.load(path)
        nprng = np.random.default_rng(seed)
        checks = [
            lambda: check_mjcf_read(robot, path, case.speeds),
            lambda: check_mjcf_dynamics(robot, path, nprng),
        ]
        if round_trip:
            checks.append(lambda: check_mjcf_round_trip(ctx, robot, path, index, nprng))
        details = []
        for check in checks:
            try:
                cls, detail = check()
            except mindyn.Error as e:  # a refusal with its reason
                cls, detail = api_refusal(e)
            if cls != "ok":
                return cls, detail
            details.append(detail)
        return "ok", "; ".join(d for d in details if d)

    label = (
        f"{path.name} n={len(case.joints)}"
        + " free" * case.free
        + " ball" * case.ball
        + (f" malformed: {case.mal[0]}" if case.mal else "")
        + " round-trip" * round_trip
    )
    out = Case("mjcf", index, label, fn, argv, [path, *case.files])
    out.drawn = case  # what was drawn (the tests change its malformation's names)
    return out


# ---------------------------------------------------------------------------------------------
# symbolic: DH / MDH tables, formulas against the numeric Y
# ---------------------------------------------------------------------------------------------
TWISTS = [0, 90, -90, 180, 89.99, 90.0001, 45, 30, -60, 1e-7, 0.001, 120]


def odd_table(rng: random.Random, path: Path) -> Path:
    n = rng.randint(2, 6)
    conv = rng.choice(["dh", "mdh"])
    L = 10 ** rng.uniform(-9, 9) if rng.random() < 0.4 else 1.0
    joints = []
    for k in range(n):
        kind = "prismatic" if rng.random() < 0.2 else "revolute"
        m = rng.uniform(0.5, 5)
        mom = sorted(rng.uniform(0.2, 1.0) * m * (0.2 * L) ** 2 / 12 for _ in range(3))
        if mom[2] >= mom[0] + mom[1]:
            mom[2] = 0.9 * (mom[0] + mom[1])
        lengths = [rng.choice([0.0, rng.uniform(0.05, 0.6) * L]) for _ in range(2)]
        j = {"name": f"j{k + 1}", "type": kind, "alpha": float(rng.choice(TWISTS))}
        if conv == "dh":
            j.update(a=lengths[0], d=lengths[1], theta=0.0)
        else:
            j.update(d=lengths[0], r=lengths[1], theta=0.0)
        if kind == "prismatic":
            j["limits"] = {"lower": -0.5 * L, "upper": 0.5 * L}
        j["inertial"] = {
            "mass": m,
            "com": [rng.uniform(-0.1, 0.1) * L for _ in range(3)],
            "inertia": {"xx": mom[0], "yy": mom[1], "zz": mom[2], "xy": 0, "xz": 0, "yz": 0},
        }
        joints.append(j)
    doc = {
        "name": f"odd{conv}{n}",
        "convention": conv,
        "angle_unit": "deg",
        "gravity": [0, 0, -9.81],
        "joints": joints,
    }
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def case_symbolic(ctx, index: int, rng: random.Random) -> Case:
    path = odd_table(rng, ctx.work / f"symbolic-{index}.yaml")
    argv = ["base", path, "--symbolic", "--format", "json"]

    def fn():
        code, out, err = run_cli(argv)
        cls, detail = cli_class(code, out, err)
        if cls != "ok":
            return cls, detail
        robot = mindyn.load(path)
        bp = mindyn.base_parameters(robot)
        sf = bp.symbolic()
        Y = np.asarray(bp._b.Y)
        if list(sf.names) != list(bp._b.names):
            return "wrong", f"symbolic names {sf.names} != numeric {list(bp._b.names)}"
        Ys = sf.evaluate([float(v) for v in sf.symbols.values()])
        scale = np.maximum(np.abs(Y), np.abs(Ys)).max(axis=1, keepdims=True)
        err_ = float(np.max(np.abs(Ys - Y) / np.maximum(scale, 1e-300)))
        if not err_ <= ORACLE_TOL:
            i, j = np.unravel_index(np.argmax(np.abs(Ys - Y) / scale), Y.shape)
            return "wrong", (
                f"formulas at the description's symbols differ from Y by {err_:.3g} (row-"
                f"relative); {bp._b.names[i]} / {bp._b.classical_names[j]}: {Ys[i, j]!r} vs "
                f"{Y[i, j]!r}"
            )
        return "ok", f"{err_:.2g}"

    return Case("symbolic", index, f"symbolic {path.name}", fn, argv, [path])


# ---------------------------------------------------------------------------------------------
# logs shared by ident and data (simulated once, in the parent)
# ---------------------------------------------------------------------------------------------
IDENT_ROBOT = "zcr07s"  # every link physically consistent, so --consistent has a truth to meet
OTHER_ROBOT = "puma560"  # the same joint count, another robot


class Context:
    def __init__(self, out: Path):
        self.work = out / "work"
        self.work.mkdir(parents=True, exist_ok=True)
        self._logs = None

    def logs(self) -> dict:
        """Logs of IDENT_ROBOT (250 Hz, exact accelerations), with a payload, of OTHER_ROBOT,
        and the JSON of identify --consistent on the first."""
        if self._logs is not None:
            return self._logs
        from mindyn.control import simulate_inverse
        from mindyn.identification.data import write_csv
        from mindyn.identification.excitation import random_trajectory

        d = self.work / "logs"
        d.mkdir(exist_ok=True)
        robot = mindyn.load(IDENT_ROBOT)
        traj = random_trajectory(robot, seed=1)
        phi = _payload()
        logs = {}
        for name, rob, params in (
            ("log", robot, robot.params),
            ("payload", robot, np.concatenate([robot.params[:-10], robot.params[-10:] + phi])),
            ("other", mindyn.load(OTHER_ROBOT), None),
        ):
            tr = traj if rob is robot else random_trajectory(rob, seed=1)
            sim = simulate_inverse(rob, tr, rate=250.0, params=params)
            write_csv(d / f"{name}.csv", sim.t, sim.q, sim.tau, dq=sim.dq)
            logs[name] = {"t": sim.t, "q": sim.q, "dq": sim.dq, "tau": sim.tau}
        # the truth beside the other robot's log: identify must not compare with it silently
        with contextlib.redirect_stdout(io.StringIO()):
            run_cli(["simulate", OTHER_ROBOT, "--mode", "inverse", "-o", d / "other2.csv"])
        shutil.copy(d / "other2.truth.json", d / "other.truth.json")
        code, out, err = run_cli(
            ["identify", IDENT_ROBOT, d / "log.csv", "--consistent", "--json", d / "id.json"]
        )
        if code != 0:
            raise SystemExit(f"setup: identify --consistent failed: {err}")
        self._logs = {"dir": d, "arrays": logs, "id": d / "id.json", "phi": phi}
        return self._logs


def _payload() -> np.ndarray:
    m, c = 1.5, np.array([0.02, -0.01, 0.05])
    ic = np.array([[0.004, 0.0003, -0.0002], [0.0003, 0.005, 0.0001], [-0.0002, 0.0001, 0.003]])
    io_ = ic + m * (c @ c * np.eye(3) - np.outer(c, c))
    return np.concatenate([io_[np.triu_indices(3)], m * c, [m]])


def check_estimate(doc: dict, out: str, robot_name: str = IDENT_ROBOT) -> tuple[str, str]:
    """The kept estimates of an identify JSON against the truth of the simulated log (rigid
    body only), whatever the JSON says the truth is: |p - p_true| <= 5 std + 2 % of the
    largest true value; a WARNING in the output makes a miss a warned one, not a silent one."""
    robot = mindyn.load(robot_name)
    bp = mindyn.base_parameters(
        robot, rotor=bool(doc.get("rotor")), friction=bool(doc.get("friction"))
    )
    p = robot.parameters(rotor=bp.rotor, friction=bp.friction)
    names = robot.parameter_names(rotor=bp.rotor, friction=bp.friction)
    joint_terms = [k for k, name in enumerate(names) if name.startswith(("Ia", "Fv", "Fc"))]
    p[joint_terms] = 0.0  # the logs are simulated without rotor inertia and friction
    truth = dict(zip(bp.names, bp.values(p), strict=True))
    scale = max(abs(v) for v in truth.values())
    worst, what = 0.0, ""
    for name, v, sd in zip(doc["names"], doc["values"], doc["std"], strict=False):
        if name not in truth or v is None:  # "names": the kept parameters
            continue
        miss = abs(v - truth[name]) - 5 * (sd or 0.0)
        if miss > worst:
            worst, what = miss, f"{name} = {v:.6g} +- {sd:.2g}, true {truth[name]:.6g}"
    if worst <= 0.02 * scale:
        return "ok", ""
    if "WARNING" in out:
        return "ok", f"warned: {what}"
    return "wrong", f"estimate off the truth without a warning: {what} (scale {scale:.3g})"


# ---------------------------------------------------------------------------------------------
# ident: consistent identification, export, payload; mutated JSON
# ---------------------------------------------------------------------------------------------
def mutate_json(doc, rng: random.Random, path: tuple = ()):
    """One random mutation somewhere in a JSON document: (new document, path of the changed
    value, old value, new value)."""
    if isinstance(doc, (dict, list)) and doc and rng.random() < 0.8:
        key = rng.choice(list(doc)) if isinstance(doc, dict) else rng.randrange(len(doc))
        doc = dict(doc) if isinstance(doc, dict) else list(doc)
        if rng.random() < 0.1:
            old = doc.pop(key)
            return doc, (*path, key), old, "<deleted>"
        doc[key], where, old, new = mutate_json(doc[key], rng, (*path, key))
        return doc, where, old, new
    choices = [
        lambda: 7,
        lambda: "7",
        lambda: "no",
        lambda: "true",
        lambda: True,
        lambda: None,
        lambda: [],
        lambda: {},
        lambda: 1e308,
        lambda: -1e308,
        lambda: 10**400,
        lambda: "nan",
        lambda: [[[[doc]]]],
        lambda: DEEP,
        lambda: {"a": doc},
        lambda: str(doc),
        lambda: 0,
        lambda: -1,
    ]
    new = rng.choice(choices)()
    return new, path, doc, new


def _json_type(v) -> str:
    if isinstance(v, bool):
        return "boolean"
    if isinstance(v, (int, float)):
        return "number"
    return {str: "string", list: "array", dict: "object", type(None): "null"}.get(type(v), "?")


#: Top-level keys each command reads from the identification JSON.
READ_KEYS = {
    "export": {"robot", "classical", "rotor", "friction", "offset"},
    "payload": {"robot", "base_names", "base_values", "rotor", "friction", "offset"},
}


DEEP = "<5000 nested arrays>"  # written as text by _dump: Python's json recurses


def _dump(doc) -> str:
    return json.dumps(doc).replace(json.dumps(DEEP), "[" * 5000 + "]" * 5000)


def case_ident(ctx, index: int, rng: random.Random) -> Case:
    logs = ctx.logs()
    d = logs["dir"]
    out = ctx.work / f"ident-{index}"
    kind = rng.choice(["identify", "export", "payload", "export", "payload"])
    id_doc = json.loads(Path(logs["id"]).read_text())
    mutated = rng.random() < 0.8
    jfile = out.with_suffix(".json")
    typo = None
    if mutated:
        doc, where, old, new = mutate_json(id_doc, rng)
        jfile.write_text(_dump(doc))
        # (a deleted key is no value of another type: an absent flag reads as false)
        changed = new != "<deleted>" and _json_type(old) != _json_type(new)
        if where and where[0] in READ_KEYS.get(kind, ()) and changed:
            typo = f"{'/'.join(map(str, where))}: {_json_type(new)} where {_json_type(old)} was"
    else:
        jfile.write_text(json.dumps(id_doc))
    oracle = None
    if kind == "identify":
        opts = []
        for flag, vals in (
            ("--prior-weight", ["0", "1e-3", "1", "1e3", "1e200", "-1", "nan", "1e-300"]),
            ("--periods", ["1", "2", "3", "0", "100000"]),
            ("--period", ["10", "5", "1e-6", "1e6", "0.004"]),
            ("--rsd-threshold", ["0", "1e308", "5"]),
            ("--cutoff", ["1", "100", "1e-9", "124.9"]),
        ):
            if rng.random() < 0.25:
                opts += [flag, rng.choice(vals)]
        if "--periods" in opts and "--period" in opts:
            opts = opts[: opts.index("--period")] + opts[opts.index("--period") + 2 :]
        opts += rng.choice([[], ["--rotor"], ["--friction"], ["--rotor", "--friction"]])
        res = out.with_suffix(".res.json")
        argv = ["identify", IDENT_ROBOT, d / "log.csv", "--consistent", "--json", res, *opts]
        files = [d / "log.csv"]
        # the log holds one period of its excitation (random_trajectory: 0.1 Hz, 10 s)
        oracle = "estimate" if not any(x in opts for x in ("--periods", "--period")) else None
        if "--periods" in opts and opts[opts.index("--periods") + 1] != "1":
            oracle = "estimate"  # a wrong count of periods must not pass silently
        if "--period" in opts and opts[opts.index("--period") + 1] == "10":
            oracle = "estimate"
    elif kind == "export":
        res = out.with_suffix(".yaml")
        argv = ["export", IDENT_ROBOT, jfile, "--yaml", res]
        files = [jfile]
        oracle = None if mutated else "export"
    else:
        res = out.with_suffix(".res.json")
        argv = ["identify-payload", IDENT_ROBOT, jfile, d / "payload.csv", "--json", res]
        argv += rng.choice([[], ["--no-consistent"], ["--filter", "none"]])
        files = [jfile, d / "payload.csv"]
        oracle = None if mutated else "payload"

    def fn():
        code, so, se = run_cli(argv)
        cls, detail = cli_class(code, so, se)
        if cls == "ok" and typo:
            return "wrong", f"a value of the wrong type accepted: {typo}"[:400]
        if cls != "ok" or oracle is None:
            return cls, detail
        if oracle == "estimate":
            return check_estimate(json.loads(Path(res).read_text()), so)
        if oracle == "export":
            robot = mindyn.load(res)
            cl = id_doc["classical"]
            names = robot.parameter_names()
            got = dict(zip(names, robot.params, strict=True))
            scale = max(abs(float(v)) for v in cl.values())
            worst = max(abs(got[k] - float(cl[k])) for k in names if k in cl)
            if not worst <= 1e-9 * scale:
                return "wrong", f"exported parameters differ from the JSON by {worst:.3g}"
            return "ok", ""
        pdoc = json.loads(Path(res).read_text())
        est = pdoc.get("consistent") or pdoc.get("unconstrained") or {}
        m = est.get("mass") if isinstance(est, dict) else None
        if m is None or not abs(m - 1.5) / 1.5 < 0.05:
            return "wrong", f"payload mass {m} (true 1.5)"
        return "ok", ""

    return Case("ident", index, f"{kind} mutated={mutated}", fn, argv, files)


# ---------------------------------------------------------------------------------------------
# controller: generated steps against the library's
# ---------------------------------------------------------------------------------------------
ODD = [1e-300, 1e-9, 1.0, 40.0, 1e6, 1e200, 1e308, 0.0, -1.0]


def case_controller(ctx, index: int, rng: random.Random) -> Case:
    robot_name = rng.choice(["planar2", "planar3", "puma560_3", "stanford"])
    kind = rng.choice(["adaptive-pd", "computed-torque", "gravity-compensation"])
    gains = {}
    for key in ("kd", "lambda", "gamma", "nu", "kp"):
        r = rng.random()
        if r < 0.35:
            continue
        if key == "nu" or r < 0.8:
            gains[key] = rng.choice(ODD if rng.random() < 0.5 else [0.5, 2.0, 10.0, 100.0])
        else:
            gains[key] = rng.choice([[1.0, 2.0], [1e300] * 2, "1", True, [[1]], {"a": 1}])
    period = rng.choice(["0.004", "0.001", "1e-9", "1", "1e308", "1e-300", "0.1"])
    lang = rng.choice(["c", "c", "c", "st"])
    gfile = ctx.work / f"controller-{index}.gains.yaml"
    gfile.write_text(yaml.safe_dump(gains) if gains else "")
    out = ctx.work / f"controller-{index}"
    argv = ["codegen", robot_name, "--what", kind, "--lang", lang, "--rotor", "--friction"]
    argv += ["--gains", gfile, "--period", period, "-o", out]
    tau_max = None
    if rng.random() < 0.2:
        tau_max = rng.choice([5.0, 1e-9, 1e308])
        argv += ["--torque-limit", repr(tau_max)]
    seed = rng.randrange(2**32)

    def fn():
        code, so, se = run_cli(argv)
        cls, detail = cli_class(code, so, se)
        if cls != "ok" or lang != "c":
            return cls, detail
        from mindyn import codegen, control

        robot = mindyn.load(robot_name)
        base = mindyn.base_parameters(robot, rotor=True, friction=True)
        g = control.load_gains(gfile, robot, period=float(period), rotor=True)  # as the CLI
        gen = codegen.generate_controller(
            robot, kind, base=base, gains=g, period=float(period), tau_max=tau_max
        )
        p0 = gen.settings["p0"]
        try:
            if kind == "gravity-compensation":
                kd = np.broadcast_to(np.asarray(g["kd"], dtype=float), (robot.n,))
                lam = np.broadcast_to(np.asarray(g["lambda"], dtype=float), (robot.n,))
                kp = np.broadcast_to(np.asarray(g.get("kp", lam * kd), dtype=float), (robot.n,))

                def lib(t, q, dq, qd, dqd, ddqd):
                    grav = base.regressor(q, np.zeros(robot.n), np.zeros(robot.n)) @ p0
                    return grav - kp * (q - qd) - kd * (dq - dqd)
            else:
                lib = control.make_controller(
                    kind, robot, g, p_hat=p0, base=base, period=float(period)
                )
        except BaseException as e:  # noqa: BLE001
            c2, d2 = api_refusal(e)
            return ("wrong" if c2 == "error" else c2), f"codegen accepts, the library refuses: {d2}"
        ctl = codegen.CompiledController(gen, base)
        nprng = np.random.default_rng(seed)
        worst = 0.0
        for _ in range(3):
            x = [nprng.uniform(-2, 2, robot.n) for _ in range(5)]
            with np.errstate(all="ignore"):
                try:
                    want = np.asarray(lib(0.0, *x), dtype=float)
                except mindyn.Error as e:  # the C step cannot refuse: the settings must not pass
                    return "wrong", f"accepted settings make the library step refuse: {e}"
                if tau_max is not None:
                    want = np.clip(want, -tau_max, tau_max)
            got = ctl(0.0, *x)
            if not np.all(np.isfinite(want)) or not np.all(np.isfinite(got)):
                return "wrong", f"accepted settings give non-finite torques: lib {want}, C {got}"
            worst = max(worst, rel_err(got, want, np.maximum(np.abs(want), 1e-300)))
        if not worst <= ORACLE_TOL:
            return "wrong", f"C step vs library step: {worst:.3g} relative"
        return "ok", f"{worst:.2g}"

    return Case("controller", index, f"{kind} {robot_name} {lang}", fn, argv, [gfile])


# ---------------------------------------------------------------------------------------------
# data: the data path
# ---------------------------------------------------------------------------------------------
def case_data(ctx, index: int, rng: random.Random) -> Case:
    logs = ctx.logs()
    a = logs["arrays"]["log"]
    t, q, dq, tau = a["t"], a["q"], a["dq"], a["tau"]
    m = t.size
    mut = rng.choice(
        ["jitter", "gap", "drift", "decimate", "noheader", "nan", "other", "scale", "dup",
         "shuffle", "short", "constant", "text"]
    )  # fmt: skip
    rows = np.arange(m)
    honest = mut in ("jitter", "gap", "drift", "decimate")
    if mut == "jitter":  # samples at irregular instants: every k-th +- a few rows
        k = rng.choice([2, 4, 5])
        base_ = np.arange(0, m - k, k)
        rows = np.unique(
            np.clip(
                base_ + np.random.default_rng(rng.randrange(2**32)).integers(-1, 2, base_.size),
                0,
                m - 1,
            )
        )
    elif mut == "gap":
        i = rng.randrange(m // 4, m // 2)
        rows = np.r_[0:i, i + rng.choice([3, 20, 200]) : m]
    elif mut == "drift":  # the rate drifts by up to 30 %
        s = np.cumsum(1 + 0.3 * np.linspace(0, 1, m))
        rows = np.unique(np.clip(np.round(s * (m - 1) / s[-1]).astype(int), 0, m - 1))
    elif mut == "decimate":
        rows = np.arange(0, m, rng.choice([1, 3, 10, 25]))
    tt, qq, dd, uu = t[rows].copy(), q[rows].copy(), dq[rows].copy(), tau[rows].copy()
    if mut == "scale":
        tt = tt * rng.choice([1e-6, 1e-3, 1e3, 1e9])
    elif mut == "dup":
        tt[rng.randrange(1, tt.size)] = tt[0]
    elif mut == "shuffle":
        perm = np.random.default_rng(rng.randrange(2**32)).permutation(tt.size)
        tt, qq, dd, uu = tt[perm], qq[perm], dd[perm], uu[perm]
    elif mut == "short":
        n_ = rng.choice([1, 2, 5, 30])
        tt, qq, dd, uu = tt[:n_], qq[:n_], dd[:n_], uu[:n_]
    elif mut == "constant":
        qq[:, rng.randrange(qq.shape[1])] = 0.3
    n = q.shape[1]
    header = ["t"] + [f"q{j + 1}" for j in range(n)] + [f"dq{j + 1}" for j in range(n)]
    header += [f"tau{j + 1}" for j in range(n)]
    body = np.column_stack([tt, qq, dd, uu])
    lines = [",".join(repr(float(x)) for x in row) for row in body]
    if mut == "nan":
        i = rng.randrange(len(lines))
        cells = lines[i].split(",")
        cells[rng.randrange(len(cells))] = rng.choice(["nan", "inf", "", "NaN", "1e999"])
        lines[i] = ",".join(cells)
    if mut == "text":
        i = rng.randrange(len(lines))
        lines[i] = rng.choice(["", "a,b,c", lines[i] + ",1", lines[i][: len(lines[i]) // 2]])
    text = ("" if mut == "noheader" else ",".join(header) + "\n") + "\n".join(lines) + "\n"
    path = ctx.work / f"data-{index}.csv"
    if mut == "other":
        path = ctx.work / f"data-{index}-other.csv"
        shutil.copy(logs["dir"] / "other.csv", path)
        shutil.copy(logs["dir"] / "other.truth.json", path.with_suffix(".truth.json"))
    else:
        path.write_text(text)
    filt = rng.choice([None, None, "butter", "savgol", "none", "lowpass"])
    res = path.with_suffix(".res.json")
    argv = ["identify", IDENT_ROBOT, path, "--json", res] + (["--filter", filt] if filt else [])

    def fn():
        code, so, se = run_cli(argv)
        cls, detail = cli_class(code, so, se)
        if cls != "ok":
            return cls, detail
        if mut == "other":
            if "WARNING" not in so and re.search(r"\btrue\b", so):
                return "wrong", "another robot's log and truth accepted without a word"
            return "ok", ""
        if not honest:
            return "ok", ""
        return check_estimate(json.loads(Path(res).read_text()), so)

    return Case("data", index, f"{mut} filter={filt}", fn, argv, [path])


# ---------------------------------------------------------------------------------------------
# cli, files, api: the earlier bad-input campaign
# ---------------------------------------------------------------------------------------------
NUM_BAD = [
    "0", "-1", "-0", "1e308", "-1e308", "inf", "-inf", "nan", "1e-300", "1e9", "1_000", "",
    "abc", "0x10", "99999999999999999999999", "-99999999999999999999", "1.5", "3",
]  # fmt: skip
# values PyYAML's safe loader cannot build (a gains file) and tags the robot reader refuses
YAML_BAD = [
    "!!bool maybe", "!!int abc", "!!float ''", "!!timestamp 2001-13-45", "!!timestamp abc",
    "!!binary '%'", "!!binary abc", "2001-02-30", "!!python/object:os.system x", "!!set 3",
    "!!str [1]", "!!omap [1]",
]  # fmt: skip
ROBOTS = ["planar2", "puma560", "zcr07s", "stanford"]
#: a gains file for planar2's controller steps
GAINS = "kd: [6, 2]\nlambda: [10, 10]\ngamma: 1\nnu: 0.01\nkp: [0, 0]\n"


def parser_options():
    p = cli.build_parser()
    sub = [a for a in p._actions if a.__class__.__name__ == "_SubParsersAction"][0]
    return {
        name: [a for a in sp._actions if a.option_strings and a.option_strings[0] != "-h"]
        for name, sp in sub.choices.items()
    }


def random_cli_argv(rng, opts_by_cmd, files):
    cmd = rng.choice([c for c in opts_by_cmd if c != "demo"])
    robots = ROBOTS + [files["urdf"], files["yaml"], "planar17", "planar9999", "", files["dir"]]
    argv = [cmd, rng.choice(robots)]
    if cmd in ("identify", "identify-payload"):
        argv.append(rng.choice([files["csv"], files["csv"], files["dir"], ""]))
    for a in rng.sample(opts_by_cmd[cmd], k=min(len(opts_by_cmd[cmd]), rng.randint(1, 4))):
        flag = a.option_strings[-1]
        if a.nargs == 0:
            argv.append(flag)
            continue
        k = a.nargs if isinstance(a.nargs, int) else (1 if a.nargs in (None, "?") else 2)
        if a.choices:
            vals = [rng.choice(list(a.choices) + ["bogus"]) for _ in range(k)]
        elif flag in ("--output", "--json", "--report", "--urdf", "--yaml", "--plcopen"):
            outs = [files["dir"], "", "/proc/x/y", "/nonexistent/a.csv"]
            vals = [rng.choice(outs + [str(Path(files["dir"]) / f"o{rng.randint(0, 9)}.x")])]
        elif flag in ("--trajectory", "--validate", "--params", "--gains", "--currents"):
            vals = [rng.choice([files["csv"], files["yaml"], files["dir"], "", files["traj"]])]
        elif flag in ("--tip", "--order", "--what", "--name", "--topic", "--start"):
            vals = [rng.choice(["", "x", "link6", "1,2,3", "a" * 1000, "-1"])]
        else:
            vals = [rng.choice(NUM_BAD) for _ in range(k)]
        argv += [flag, *vals]
    if cmd == "excite":  # keep valid runs short
        argv += ["--maxiter", "3", "--starts", "1", "--quiet"]
    if cmd in ("track", "simulate") and "--duration" not in argv:
        argv += ["--duration", "0.2"]
    return argv


def case_cli(ctx, index: int, rng: random.Random) -> Case:
    files = ctx.cli_files()
    argv = random_cli_argv(rng, ctx.options(), files)
    return Case("cli", index, " ".join(map(repr, argv))[:200], cli_fn(argv), argv, [])


XML_MUT = [
    lambda s, r: s.replace('parent link="base_link"', 'parent link="wrist_3_link"', 1),
    lambda s, r: re.sub(r'<child link="([^"]+)"/>', r'\g<0><parent link="\1"/>', s, count=1),
    lambda s, r: re.sub(r'value="[^"]*"', r.choice(['value="1e308"', 'value="3.7.0"']), s, count=1),
    lambda s, r: re.sub(r'xyz="[^"]*"', r.choice(['xyz="1e308 0 0"', 'xyz="nan 0 0"']), s, count=1),
    lambda s, r: re.sub(
        r'ixx="[^"]*"', r.choice(['ixx="-1"', 'ixx="abc"', 'ixxx="1"']), s, count=1
    ),
    lambda s, r: re.sub(r'type="revolute"', 'type="floating"', s, count=1),
    lambda s, r: re.sub(r'<axis xyz="[^"]*"', '<axis xyz="0 0 0"', s, count=1),
    lambda s, r: s[: r.randint(0, len(s))],
    lambda s, r: s.replace('name="shoulder_link"', 'name="base_link"', 1),
    lambda s, r: s + "\xff",
    lambda s, r: re.sub(r'lower="[^"]*"', 'lower="5" upper="-5"', s, count=1),
    lambda s, r: s.replace("<inertia ", "<inertial ", 1),
    lambda s, r: re.sub(r'value="([0-9.]+)"', r'value="\1,5"', s, count=1),
]


def mutate_text(s, kind, rng):
    lines = s.splitlines()
    op = rng.randint(0, 9)
    if kind == "urdf" and op < 6:
        return rng.choice(XML_MUT)(s, rng)
    i = rng.randrange(len(lines))
    if op < 2:
        del lines[i]
    elif op < 4:
        lines.insert(i, lines[rng.randrange(len(lines))])
    elif op < 7:
        number = r"-?\d+(\.\d+)?(e-?\d+)?"
        bad = NUM_BAD + YAML_BAD if kind in ("yaml", "gains") else NUM_BAD
        lines[i] = re.sub(number, lambda m: rng.choice(bad), lines[i], count=1)
    elif op < 8:
        lines[i] = lines[i] + rng.choice([": [1, 2]", " !!python/object:os.system", "{", "]", "\t"])
    else:
        lines[i] = lines[i][: rng.randint(0, len(lines[i]))]
    return "\n".join(lines) + "\n"


def case_files(ctx, index: int, rng: random.Random) -> Case:
    files = ctx.cli_files()
    kind = rng.choice(["urdf", "yaml", "csv", "gains"])
    f = ctx.work / f"files-{index}.{'yaml' if kind == 'gains' else kind}"
    text = mutate_text(Path(files[kind]).read_text(), kind, rng)
    f.write_bytes(text.encode("utf-8", "surrogateescape") + (b"\xff\xfe" * (rng.random() < 0.1)))
    out = ["--lang", "c", "-o", ctx.work / f"files-{index}-o"]
    if kind == "csv":
        argv = ["identify", "planar2", f]
    elif kind == "gains":  # a controller step with a gains file (read by PyYAML)
        step = rng.choice(["adaptive-pd", "computed-torque"])
        argv = ["codegen", "planar2", "--what", step, "--gains", f, *out]
    else:
        command = rng.choice(["info", "base", "codegen"])
        argv = [command, f, *out] if command == "codegen" else [command, f]
    return Case("files", index, f"{argv[0]} {f.name}", cli_fn(argv), argv, [f])


def case_api(ctx, index: int, rng: random.Random) -> Case:
    bad = [
        ("empty (0,2)", lambda: np.empty((0, 2))),
        ("zeros(3)", lambda: np.zeros(3)),
        ("zeros(2,3)", lambda: np.zeros((2, 3))),
        ("nan(2)", lambda: np.full(2, np.nan)),
        ("inf(2)", lambda: np.full(2, np.inf)),
        ("1e308(2)", lambda: np.full(2, 1e308)),
        ("None", lambda: None),
        ("'x'", lambda: "x"),
        ("[1,2,3]", lambda: [1, 2, 3]),
        ("complex(2)", lambda: np.zeros(2, dtype=complex)),
        ("zeros(1,1,2)", lambda: np.zeros((1, 1, 2))),
        ("object(2)", lambda: np.zeros(2, dtype=object)),
        ("3.0", lambda: 3.0),
        ("zeros(5,2)", lambda: np.zeros((5, 2))),
    ]
    names = ["inverse_dynamics", "regressor", "mass_matrix", "gravity_torque", "forward_dynamics",
             "fk", "jacobian", "base_regressor", "slotine_li", "ik", "energy"]  # fmt: skip
    name = rng.choice(names)
    args = [("zeros(2)", lambda: np.zeros(2))] * 3
    for j in rng.sample(range(3), rng.randint(1, 3)):
        args[j] = rng.choice(bad)
    label = f"api {name}({', '.join(a[0] for a in args)})"

    def fn():
        robot = mindyn.load("planar2")
        bp = mindyn.base_parameters(robot)
        a, b, c = (x[1]() for x in args)
        calls = {
            "inverse_dynamics": lambda: robot.inverse_dynamics(a, b, c),
            "regressor": lambda: robot.regressor(a, b, c),
            "mass_matrix": lambda: robot.mass_matrix(a),
            "gravity_torque": lambda: robot.gravity_torque(a),
            "forward_dynamics": lambda: robot.forward_dynamics(a, b, c),
            "fk": lambda: robot.fk(a),
            "jacobian": lambda: robot.jacobian(a),
            "base_regressor": lambda: bp.regressor(a, b, c),
            "slotine_li": lambda: mindyn.slotine_li_regressor(bp, a, b, b, c),
            "ik": lambda: mindyn.ik(robot, a),
            "energy": lambda: robot.energy(a, b),
        }
        try:
            calls[name]()
        except BaseException as e:  # noqa: BLE001
            return api_refusal(e)
        return "ok", ""

    return Case("api", index, label, fn, None, [])


def _ctx_cli_files(self):
    if getattr(self, "_files", None):
        return self._files
    tmp = self.work / "cli"
    tmp.mkdir(exist_ok=True)
    traj = tmp / "traj.csv"
    with contextlib.redirect_stdout(io.StringIO()):
        run_cli(["excite", "planar2", "--maxiter", "5", "--starts", "1", "--quiet", "-o", traj])
        run_cli(["simulate", "planar2", "--trajectory", traj.with_suffix(".json"), "-o",
                 tmp / "log.csv"])  # fmt: skip
    self._files = {
        "dir": str(tmp),
        "urdf": str(URDF),
        "yaml": str(Path(mindyn.__file__).parent / "robots" / "puma560.yaml"),
        "csv": str(tmp / "log.csv"),
        "traj": str(traj.with_suffix(".json")),
        "gains": str(tmp / "gains.yaml"),
    }
    Path(self._files["gains"]).write_text(GAINS)
    return self._files


def _ctx_options(self):
    if getattr(self, "_opts", None) is None:
        self._opts = parser_options()
    return self._opts


Context.cli_files = _ctx_cli_files
Context.options = _ctx_options

MAKERS = {
    "trees": case_trees,
    "symbolic": case_symbolic,
    "ident": case_ident,
    "controller": case_controller,
    "data": case_data,
    "cli": case_cli,
    "files": case_files,
    "api": case_api,
    "floating": case_floating,
    "drives": case_drives,
    "mjcf": case_mjcf,
}


# ---------------------------------------------------------------------------------------------
# The campaign
# ---------------------------------------------------------------------------------------------
def make_case(ctx, target: str, index: int, seed: int) -> Case:
    rng = random.Random(f"{seed}:{target}:{index}")
    return MAKERS[target](ctx, index, rng)


def write_finding(out: Path, case: Case, kind: str, detail: str, seed: int, opts) -> Path:
    folder = "findings" if kind in FINDINGS else "tool"
    d = out / folder / f"{case.target}-{case.index:04d}-{kind}"
    d.mkdir(parents=True, exist_ok=True)
    for f in case.files:
        if Path(f).is_file():
            shutil.copy(f, d / Path(f).name)
    rerun = (
        f".venv/bin/python fuzz/campaign.py {out}/rerun --seed {seed} --case "
        f"{case.target}:{case.index} --timeout {opts.timeout:g} --rss {opts.rss}"
    )
    doc = {
        "class": kind,
        "target": case.target,
        "index": case.index,
        "seed": seed,
        "label": case.label,
        "detail": detail,
        "argv": None if case.argv is None else ["mindyn"] + [str(a) for a in case.argv],
        "rerun": rerun,
    }
    (d / "case.json").write_text(json.dumps(doc, indent=1) + "\n")
    return d


def cause(target: str, kind: str, detail: str) -> str:
    """A grouping key for findings: the target, the class and the detail without its numbers,
    paths and array contents."""
    d = re.sub(r"\[[^\]]*\]", "[..]", str(detail))
    d = re.sub(r"(/[\w.+-]+)+", "<path>", d)
    d = re.sub(r"[-+]?(\d+\.?\d*|\.\d+)(e[-+]?\d+)?", "#", d)
    d = d.strip().splitlines()[-1] if kind == "trace" and d.strip() else d
    return f"{target} {kind}: {d[:110]}"


def summary_table(counts: dict) -> str:
    cols = CLASSES
    rows = [["target", *cols, "total"]]
    for t, c in counts.items():
        rows.append([t, *(str(c.get(k, 0)) for k in cols), str(sum(c.values()))])
    tot = {k: sum(c.get(k, 0) for c in counts.values()) for k in cols}
    rows.append(["all", *(str(tot[k]) for k in cols), str(sum(tot.values()))])
    w = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    return "\n".join("  ".join(x.rjust(w[i]) for i, x in enumerate(r)) for r in rows)


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("out", type=Path, help="output folder (summary and findings)")
    p.add_argument("--targets", default=",".join(DEFAULT_TARGETS), help="comma-separated")
    p.add_argument("--count", type=int, default=200, help="cases per target (default 200)")
    p.add_argument("--budget", type=float, default=1800.0, help="total seconds (default 1800)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--timeout", type=float, default=60.0, help="per case [s] (default 60)")
    p.add_argument("--rss", type=int, default=2048, help="per-case peak RSS [MiB] (default 2048)")
    p.add_argument("--case", help="TARGET:INDEX: run this one case and print its outcome")
    return p.parse_args(argv)


def main(argv=None) -> int:
    opts = parse_args(argv)
    out = opts.out
    out.mkdir(parents=True, exist_ok=True)
    ctx = Context(out)
    if opts.case:
        target, index = opts.case.split(":")
        case = make_case(ctx, target, int(index), opts.seed)
        kind, detail, secs, rss = run_child(case.fn, opts.timeout, opts.rss)
        print(f"{case.target}:{case.index} {case.label}\n  {kind}: {detail}")
        print(f"  {secs:.1f} s, peak RSS {rss:.0f} MiB")
        if case.argv:
            print("  " + " ".join(["mindyn"] + [str(a) for a in case.argv]))
        return 0 if kind in ("ok", "error") else 1
    targets = [t.strip() for t in opts.targets.split(",") if t.strip()]
    unknown = set(targets) - set(TARGETS)
    if unknown:
        raise SystemExit(f"unknown target(s) {', '.join(sorted(unknown))}; use {TARGETS}")
    counts = {t: Counter() for t in targets}
    refusals = {t: Counter() for t in targets}
    findings = []
    secs_by = Counter()
    t0 = time.time()
    log = open(out / "cases.log", "w")  # noqa: SIM115
    for index in range(opts.count):
        if time.time() - t0 > opts.budget:
            break
        for target in targets:
            if time.time() - t0 > opts.budget:
                break
            try:
                case = make_case(ctx, target, index, opts.seed)
            except Exception:  # noqa: BLE001 - a defect of this tool: counted, the run goes on
                case = Case(target, index, "drawing the case failed", None)
                kind, detail, secs, rss = "tool", traceback.format_exc()[-600:], 0.0, 0.0
            else:
                kind, detail, secs, rss = run_child(case.fn, opts.timeout, opts.rss)
            counts[target][kind] += 1
            secs_by[target] += secs
            if kind == "error":
                refusals[target][re.sub(r"[-+]?\d[\d.e+-]*", "#", detail)[:120]] += 1
            log.write(f"{target}:{index} {kind} {secs:.1f}s {rss:.0f}MiB {case.label} | "
                      f"{str(detail)[:200]}\n")  # fmt: skip
            log.flush()
            if kind in FINDINGS or kind == "tool":
                d = write_finding(out, case, kind, detail, opts.seed, opts)
                if kind in FINDINGS:
                    findings.append(
                        {
                            "dir": str(d),
                            "class": kind,
                            "detail": detail,
                            "cause": cause(target, kind, detail),
                        }
                    )
    log.close()
    elapsed = time.time() - t0
    table = summary_table(counts)
    lines = [
        f"seed {opts.seed}, {sum(sum(c.values()) for c in counts.values())} cases in "
        f"{elapsed:.0f} s (budget {opts.budget:g} s, at most {opts.count} per target), per-case "
        f"timeout {opts.timeout:g} s, RSS limit {opts.rss} MiB",
        "",
        table,
        "",
        "seconds per target: " + ", ".join(f"{t} {secs_by[t]:.0f}" for t in targets),
        "",
        "most frequent refusals:",
    ]
    for t in targets:
        for msg, k in refusals[t].most_common(4):
            lines.append(f"  {t:10s} {k:4d}  {msg}")
    lines += ["", f"{len(findings)} findings in {out / 'findings'}, by cause (one reproducer):"]
    causes: dict = {}
    for f in findings:
        causes.setdefault(f["cause"], []).append(f["dir"])
    for key, dirs in sorted(causes.items(), key=lambda kv: -len(kv[1])):
        lines.append(f"  {len(dirs):4d}  {key}\n        {dirs[0]}")
    text = "\n".join(lines)
    (out / "summary.txt").write_text(text + "\n")
    (out / "summary.json").write_text(
        json.dumps(
            {"seed": opts.seed, "seconds": elapsed, "counts": counts, "findings": findings},
            indent=1,
        )
        + "\n"
    )
    print(text)
    return 1 if findings else 0


if __name__ == "__main__":
    sys.exit(main())
