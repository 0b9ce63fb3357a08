"""Random fixed-base tree URDFs for the tests: each joint hangs from a random earlier link, joints
are revolute, continuous, prismatic or fixed, axes point anywhere (some along a coordinate axis,
either sign), origins have random xyz and rpy, inertial values are physically consistent and
given about a rotated COM frame. The joints are written in random document order under names
whose alphabetical order differs from the order they were drawn in, so a loader's joint order
is checked for real. Each test writes its own from a seed."""

from __future__ import annotations

import string
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np
import yaml

_MOVING = ("revolute", "continuous", "prismatic")


def random_tree_urdf(
    path: Path,
    n: int = 8,
    seed: int = 0,
    fixed: int | None = None,
    branches: bool = True,
    moving: tuple[str, ...] = _MOVING,
) -> Path:
    """Writes a random tree with ``n`` moving joints and ``fixed`` fixed joints (default
    ``n // 3 + 1``) to ``path`` and returns the path.

    With ``branches`` (default) the drawing is repeated until at least two moving leaves
    exist (the tree does not reduce to a chain). Fixed joints may sit before the first moving
    joint (part of the base), between moving joints, or end in a leaf without a moving joint
    below (folded into the body above); leaf links of fixed joints sometimes have no inertial
    element. ``moving`` lists the kinds of moving joints drawn (``floating`` and ``planar``,
    the latter in the xy plane of its frame, may be added)."""
    if n < 1 or (branches and n < 2):
        raise ValueError(f"n = {n}: a random tree needs at least {2 if branches else 1} joints")
    rng = np.random.default_rng(seed)
    fixed = n // 3 + 1 if fixed is None else fixed
    for _ in range(1000):
        kinds = [str(rng.choice(moving)) for _ in range(n)] + ["fixed"] * fixed
        rng.shuffle(kinds)
        parents = [int(rng.integers(0, k + 1)) for k in range(len(kinds))]  # 0 = base link
        if not branches or _moving_leaves(kinds, parents) >= 2:
            break
    else:  # pragma: no cover - the first few draws always branch for n >= 2
        raise RuntimeError("no branching tree drawn")

    links = [_link("base", _inertial(rng))]  # the root's inertia is the base's: ignored
    joints = []
    names = _names(rng, len(kinds))
    for k, (kind, parent) in enumerate(zip(kinds, parents, strict=True)):
        child = f"link_{names[k]}"
        leaf = k + 1 not in parents
        massless = kind == "fixed" and leaf and rng.uniform() < 0.4
        links.append(_link(child, None if massless else _inertial(rng)))
        parent_link = "base" if parent == 0 else f"link_{names[parent - 1]}"
        joints.append(_joint(rng, f"joint_{names[k]}", kind, parent_link, child))
    order = rng.permutation(len(joints))
    body = "\n".join(links + [joints[i] for i in order])
    path = Path(path)
    path.write_text(f'<?xml version="1.0"?>\n<robot name="tree{n}_{seed}">\n{body}\n</robot>\n')
    return path


def _moving_leaves(kinds: list[str], parents: list[int]) -> int:
    """Moving joints with no moving joint below them."""
    below = [False] * (len(kinds) + 1)  # link index -> a moving joint below it
    for k in reversed(range(len(kinds))):
        if kinds[k] != "fixed" or below[k + 1]:
            below[parents[k]] = True
    return sum(1 for k in range(len(kinds)) if kinds[k] != "fixed" and not below[k + 1])


def _names(rng: np.random.Generator, count: int) -> list[str]:
    """Distinct names whose alphabetical order is random, not the drawing order."""
    letters = np.array(list(string.ascii_lowercase))
    names: list[str] = []
    while len(names) < count:
        name = "".join(rng.choice(letters, 3)) + str(len(names))
        names.append(name)
    return names


def _vec(v) -> str:
    return " ".join(repr(float(x)) for x in v)


def _axis(rng: np.random.Generator) -> np.ndarray:
    if rng.uniform() < 0.25:  # along a coordinate axis, either sign
        a = np.zeros(3)
        a[rng.integers(3)] = rng.choice([-1.0, 1.0])
        return a
    a = rng.normal(size=3)
    return a / np.linalg.norm(a)


def _joint(rng: np.random.Generator, name: str, kind: str, parent: str, child: str) -> str:
    xyz = rng.uniform(-0.3, 0.3, 3)
    rpy = rng.uniform(-np.pi, np.pi, 3)
    text = (
        f"  <joint name={quoteattr(name)} type={quoteattr(kind)}>\n"
        f'    <origin xyz="{_vec(xyz)}" rpy="{_vec(rpy)}"/>\n'
        f'    <parent link="{parent}"/>\n    <child link="{child}"/>\n'
    )
    if kind == "planar":
        text += '    <axis xyz="0 0 1"/>\n'
    elif kind not in ("fixed", "floating"):
        text += f'    <axis xyz="{_vec(_axis(rng))}"/>\n'
    if kind == "revolute":
        lo, hi = -rng.uniform(0.5, 3.0), rng.uniform(0.5, 3.0)
        text += f'    <limit lower="{lo!r}" upper="{hi!r}" effort="50" velocity="3"/>\n'
    elif kind == "prismatic":
        lo, hi = -rng.uniform(0.1, 0.5), rng.uniform(0.1, 0.5)
        text += f'    <limit lower="{lo!r}" upper="{hi!r}" effort="200" velocity="1"/>\n'
    elif kind == "continuous":
        text += '    <limit effort="50" velocity="3"/>\n'
    return text + "  </joint>"


def com_inertia(rng: np.random.Generator, mass: float, length: float) -> np.ndarray:
    """A random inertia tensor about the centre of mass of a body of ``mass`` about ``length``
    in size: principal moments meeting the triangle inequalities, random orientation."""
    while True:
        mom = rng.uniform(0.2, 1.0, 3) * mass * length**2 / 12
        if 2 * mom.max() < mom.sum():
            break
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return Q @ np.diag(mom) @ Q.T


def _inertial(rng: np.random.Generator) -> str:
    """A physically consistent inertial element: principal moments meeting the triangle
    inequalities, rotated by a random rotation, given in a COM frame with random rpy."""
    mass = rng.uniform(0.3, 4.0)
    inertia = com_inertia(rng, mass, 0.2)
    com = rng.uniform(-0.15, 0.15, 3)
    rpy = rng.uniform(-np.pi, np.pi, 3)
    i = {k: repr(float(inertia[a, b])) for k, (a, b) in _TENSOR.items()}
    return (
        f'    <inertial>\n      <origin xyz="{_vec(com)}" rpy="{_vec(rpy)}"/>\n'
        f'      <mass value="{mass!r}"/>\n'
        f'      <inertia ixx="{i["ixx"]}" ixy="{i["ixy"]}" ixz="{i["ixz"]}" iyy="{i["iyy"]}" '
        f'iyz="{i["iyz"]}" izz="{i["izz"]}"/>\n    </inertial>\n'
    )


_TENSOR = {"ixx": (0, 0), "ixy": (0, 1), "ixz": (0, 2), "iyy": (1, 1), "iyz": (1, 2), "izz": (2, 2)}


def _link(name: str, inertial: str | None) -> str:
    if inertial is None:
        return f"  <link name={quoteattr(name)}/>"
    return f"  <link name={quoteattr(name)}>\n{inertial}  </link>"


_MULTI = ("revolute", "prismatic", "spherical", "universal", "cylindrical", "planar", "floating")


def random_multidof_tree_yaml(
    path: Path,
    n: int = 8,
    seed: int = 0,
    kinds=_MULTI,
    *,
    first: str | None = None,
    serial: bool = False,
) -> Path:
    """Writes a random tree of ``n`` joints of the given ``kinds`` (drawn with replacement, each
    kind at least once when ``n`` allows) as a modified-DH YAML description to ``path``: every
    joint hangs from a random earlier link (``parent``, depth-first order), or from the one
    before with ``serial``; ``first`` sets the kind of the first joint, which hangs from the
    base; alpha, d, theta, r random, inertial values physically consistent. Returns the path."""
    rng = np.random.default_rng(seed)
    drawn = list(kinds)[:n] + [str(rng.choice(kinds)) for _ in range(n - min(n, len(kinds)))]
    rng.shuffle(drawn)
    if first is not None:
        drawn[0] = first
    joints, parents = [], []
    for k, kind in enumerate(drawn):
        # depth-first order (Pinocchio's crba needs each subtree's velocities contiguous): the
        # parent is the base, the joint before or one of its ancestors
        chain = [k]
        while chain[-1] > 0:
            chain.append(parents[chain[-1] - 1])
        parents.append(k if serial else int(rng.choice(chain)))
        mass = float(rng.uniform(0.3, 4.0))
        inertia = com_inertia(rng, mass, 0.2)
        joints.append(
            {
                "name": f"j{k + 1}_{kind}",
                "type": kind,
                "parent": parents[k],
                "alpha": float(rng.uniform(-np.pi, np.pi)),
                "d": float(rng.uniform(-0.3, 0.3)),
                "theta": float(rng.uniform(-np.pi, np.pi)),
                "r": float(rng.uniform(-0.3, 0.3)),
                "inertial": {
                    "mass": mass,
                    "com": rng.uniform(-0.15, 0.15, 3).tolist(),
                    "inertia": {key: float(inertia[a, b]) for key, (a, b) in _YAML_TENSOR.items()},
                },
            }
        )
    doc = {"name": f"multidof{n}_{seed}", "convention": "mdh", "joints": joints}
    path = Path(path)
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


_YAML_TENSOR = {"xx": (0, 0), "xy": (0, 1), "xz": (0, 2), "yy": (1, 1), "yz": (1, 2), "zz": (2, 2)}
