"""Drake as a second independent reference beside Pinocchio: ``MultibodyPlant``'s inverse
dynamics, from Drake's own URDF parser, on the same URDFs as mindyn and Pinocchio.

Drake gets the URDF without its visual and collision elements (their meshes are package URIs
Drake need not resolve) and without ``<dynamics>`` (the rigid-body dynamics are compared; joint
friction is not Drake's inverse dynamics). Joints off mindyn's chain are held where mindyn locks
them (``q = 0`` clamped into their limits, at rest) in Drake's and Pinocchio's whole models.
"""

from __future__ import annotations

import re
from pathlib import Path

import mindyn
import numpy as np
import pinocchio as pin
import pytest
from conftest import ROBOTS_DIR, URDFS, assert_close

try:
    import pydrake  # noqa: F401
except ImportError as e:  # not installed, or a system library it loads is missing
    pytest.skip(f"drake is not usable here: {e}", allow_module_level=True)
from pydrake.multibody.parsing import Parser  # noqa: E402
from pydrake.multibody.plant import MultibodyPlant  # noqa: E402
from pydrake.multibody.tree import MultibodyForces  # noqa: E402

TOL = 1e-12
CASES = {
    "ur5": (URDFS["ur5"], None),
    "ur5_example": (Path(__file__).parent.parent / "examples/urdf/ur5.urdf", None),
    "panda": (URDFS["panda"], "panda_hand"),
    "baxter_arm": (ROBOTS_DIR / "baxter_description/urdf/baxter.urdf", "left_hand_link"),
}


def drake_plant(path: Path):
    text = path.read_text(encoding="utf-8")
    text = re.sub(r"<(visual|collision)\b.*?</\1>", "", text, flags=re.S)
    text = re.sub(r"<dynamics\b[^>]*/>", "", text)
    plant = MultibodyPlant(0.0)
    Parser(plant).AddModelsFromString(text, "urdf")
    children = set(re.findall(r"<child\s+link\s*=\s*\"([^\"]+)\"", text))
    links = re.findall(r"<link\s+name\s*=\s*\"([^\"]+)\"", text)
    root = next(link for link in links if link not in children)
    if root != "world":  # Drake takes a link named world as the world itself
        plant.WeldFrames(plant.world_frame(), plant.GetFrameByName(root))
    plant.Finalize()
    return plant


def held(lower, upper):
    """Where mindyn locks a joint off the chain: 0 clamped into its limits."""
    lo = lower if np.isfinite(lower) else -np.inf
    hi = upper if np.isfinite(upper) else np.inf
    return float(np.clip(0.0, lo, hi)) if lo <= hi else 0.0


@pytest.mark.parametrize("case", sorted(CASES))
def test_drake_inverse_dynamics_equals_mindyn_and_pinocchio(case):
    path, tip = CASES[case]
    robot = mindyn.load(path, tip=tip)
    plant = drake_plant(path)
    context = plant.CreateDefaultContext()
    q0 = np.zeros(plant.num_positions())
    lo, hi = plant.GetPositionLowerLimits(), plant.GetPositionUpperLimits()
    for i in range(plant.num_positions()):
        q0[i] = held(lo[i], hi[i])
    joints = [plant.GetJointByName(name) for name in robot.joint_names]
    qi = [j.position_start() for j in joints]
    vi = [j.velocity_start() for j in joints]
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    pq = [model.idx_qs[model.getJointId(n)] for n in robot.joint_names]
    pv = [model.idx_vs[model.getJointId(n)] for n in robot.joint_names]
    p_q0 = np.array(
        [held(a, b) for a, b in zip(model.lowerPositionLimit, model.upperPositionLimit)]
    )
    rng = np.random.default_rng(17)
    lim = robot.limits
    low = np.where(np.isfinite(lim["lower"]), lim["lower"], -np.pi)
    high = np.where(np.isfinite(lim["upper"]), lim["upper"], np.pi)
    forces = MultibodyForces(plant)
    for _ in range(4):
        q = rng.uniform(low, high)
        dq, ddq = rng.uniform(-2.0, 2.0, (2, robot.n))
        x, v, a = q0.copy(), np.zeros(plant.num_velocities()), np.zeros(plant.num_velocities())
        x[qi], v[vi], a[vi] = q, dq, ddq
        plant.SetPositions(context, x)
        plant.SetVelocities(context, v)
        plant.CalcForceElementsContribution(context, forces)  # gravity
        drake = plant.CalcInverseDynamics(context, a, forces)[vi]
        px, pvel, pacc = p_q0.copy(), np.zeros(model.nv), np.zeros(model.nv)
        px[pq], pvel[pv], pacc[pv] = q, dq, ddq
        pinocchio = pin.rnea(model, data, px, pvel, pacc)[pv]
        ours = robot.inverse_dynamics(q, dq, ddq, robot.params)
        assert_close(ours, drake, TOL, "mindyn vs Drake")
        assert_close(pinocchio, drake, TOL, "Pinocchio vs Drake")
