"""Which base-parameter method a command runs on a robot, and why (``mindyn base`` and
``mindyn codegen``)."""

from __future__ import annotations

from .. import _core

# The projection method's limits (its packed basis index): joints of a chain; on a tree, joints
# on a root path and joints in all.
_PROJECTION_MAX_JOINTS = 18
_PROJECTION_MAX_PATH, _PROJECTION_MAX_TREE = 16, 44


def projection_limit(robot) -> str | None:
    """Why the projection method cannot take the robot, or None."""
    if robot.is_serial:
        if robot.n > _PROJECTION_MAX_JOINTS:
            return f"handles at most {_PROJECTION_MAX_JOINTS} joints, the robot has {robot.n}"
        return None
    depth: list[int] = []
    for p in robot.parents:
        depth.append(1 if p < 0 else depth[p] + 1)
    if robot.n > _PROJECTION_MAX_TREE:
        return f"handles at most {_PROJECTION_MAX_TREE} joints on a tree, the robot has {robot.n}"
    if max(depth) > _PROJECTION_MAX_PATH:
        return (
            f"handles root paths of up to {_PROJECTION_MAX_PATH} joints on a tree, the robot's "
            f"longest has {max(depth)}"
        )
    return None


def base_method(robot, rotor: bool, method: str | None) -> tuple[str, str]:
    """The method ``mindyn base`` runs and why: the one given, else the projection method, or
    the recursive method (exact, the same base set) when the projection method's cost estimate
    would refuse the chain."""
    if method is not None:
        return method, "--method " + method
    limit = projection_limit(robot)
    if limit:
        return "recursive", (
            f"the projection method {limit}; the recursive method is exact and gives the same "
            "base set"
        )
    cost = _core.projection_cost(robot._m, rotor=rotor)
    if cost["bytes"] > cost["budget"]:
        gib = 1024.0**3
        return "recursive", (
            f"the projection method would need up to {cost['bytes'] / gib:.2g} GiB (estimated "
            f"before computing), over its budget of {cost['budget'] / gib:.2g} GiB; the "
            "recursive method is exact and gives the same base set"
        )
    return "projection", (
        "the default (exact: Gaussian elimination on the exact coordinates of the Lagrangian's "
        "coefficients in a finite basis of functions of the joints, no sampling)"
    )
