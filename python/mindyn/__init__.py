"""mindyn: the minimal dynamic model of a manipulator.

- :func:`load` gives a :class:`Robot` (URDF, YAML DH/MDH table or bundled name) with inverse
  dynamics, regressors, energies, mass matrix and forward dynamics, linear in the classical
  parameters (C++ core), and KDL kinematics;
- :func:`base_parameters`: base inertial parameters by the projection method (or the numerical
  method), regrouping matrix, formulas, base regressors;
- :mod:`mindyn.codegen`: inverse dynamics, gravity and base regressor as C or Structured Text;
- :mod:`mindyn.identification`: excitation trajectories, joint logs, least-squares and
  physically consistent identification with statistics, validation and reports;
- :mod:`mindyn.control`: Slotine-Li regressor, adaptive PD and other controllers, and the one
  closed-loop simulation (simulated measurements and tracking experiments);
- :func:`ik`: inverse kinematics; :mod:`mindyn.export`: identified parameters written back
  into a robot description, :mod:`mindyn.mjcf` as a MuJoCo MJCF; :mod:`mindyn.cli`: the
  ``mindyn`` command.
"""

import importlib
import importlib.util

import numpy as np

from . import _args
from ._core import ArgumentError, Error, ModelError, RobotFileNotFoundError
from ._core import from_pinocchio_order as _from_pin
from ._core import inertial_from_com as _from_com
from ._core import inertial_from_urdf as _from_urdf
from ._core import to_pinocchio_order as _to_pin
from .base import BaseParameters, base_parameters
from .control import coriolis_matrix, slotine_li_regressor
from .inverse_kinematics import ik
from .robot import DriveTrainWarning, Robot, bundled_robots, load

__all__ = [
    "ArgumentError",
    "BaseParameters",
    "DriveTrainWarning",
    "Error",
    "base_parameters",
    "ModelError",
    "Robot",
    "RobotFileNotFoundError",
    "bundled_robots",
    "coriolis_matrix",
    "from_pinocchio_order",
    "inertial_from_com",
    "ik",
    "inertial_from_urdf",
    "load",
    "slotine_li_regressor",
    "to_pinocchio_order",
]


def __getattr__(name: str):
    # The version is read from the installed package's metadata when asked for (importing
    # importlib.metadata costs every command's start).
    if name == "__version__":
        from ._version import __version__

        return __version__
    # A submodule not imported above (identification, codegen, export, ...: their imports cost
    # every command's start) is imported when first named: ``mindyn.identification.run``.
    if not name.startswith("_") and importlib.util.find_spec(f"{__name__}.{name}") is not None:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module 'mindyn' has no attribute '{name}'")


def _inertial_vector(params) -> np.ndarray:
    """``params`` as a vector of ten inertial parameters per link, shape (10 n,)."""
    p = _args.array(params, "params", (None,))
    if p.size % 10:
        raise _args.fail(
            "params",
            f"has {p.size} entries, not a multiple of 10; expected ten per link, shape (10 n,)",
        )
    return p


def to_pinocchio_order(params):
    """Inertial parameters ``[XX XY XZ YY YZ ZZ MX MY MZ M]`` per link, shape (10 n,), to
    Pinocchio's dynamic-parameter order ``[m, mcx, mcy, mcz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]``;
    a length that is not a multiple of ten is an ArgumentError."""
    return _to_pin(_inertial_vector(params))


def from_pinocchio_order(params):
    """Inverse of :func:`to_pinocchio_order`."""
    return _from_pin(_inertial_vector(params))


def _symmetric(x, name: str):
    """A (3, 3) tensor, symmetric to round-off (a tensor's two triangles would give two
    different products of inertia)."""
    a = _args.array(x, name, (3, 3))
    if abs(a - a.T).max() > 1e-9 * abs(a).max():
        i, j = divmod(int(abs(a - a.T).argmax()), 3)
        raise _args.fail(
            name,
            f"is not symmetric: entry ({i}, {j}) is {a[i, j]:g}, entry ({j}, {i}) is "
            f"{a[j, i]:g}; expected an inertia tensor",
        )
    return a


def _rotation(x, name: str):
    """A (3, 3) rotation matrix, orthonormal to 1e-6 with determinant +1."""
    R = _args.array(x, name, (3, 3))
    if abs(R).max() > 1.0 + 1e-6 or abs(R.T @ R - np.eye(3)).max() > 1e-6:
        raise _args.fail(name, "is not a rotation matrix (R^T R differs from the identity)")
    if np.linalg.det(R) < 0:
        raise _args.fail(name, "is not a rotation matrix (a reflection: determinant -1)")
    return R


@_args.finite_results("mass", "com", "inertia")
def inertial_from_com(mass, com, inertia):
    """The ten inertial parameters about the link origin ``[XX XY XZ YY YZ ZZ MX MY MZ M]`` of a
    body of ``mass`` with centre of mass ``com`` (3,) and inertia tensor ``inertia`` (3, 3),
    symmetric, about the centre of mass, all in link axes. Any values are accepted as a
    parameter vector is (a negative mass too); a tensor that is not symmetric is an
    ArgumentError naming ``inertia``."""
    return _from_com(
        _args.number(mass, "mass"),
        _args.array(com, "com", (3,)),
        _symmetric(inertia, "inertia"),
    )


@_args.finite_results("mass", "com", "rotation", "inertia")
def inertial_from_urdf(mass, com, rotation, inertia):
    """As :func:`inertial_from_com` for a URDF ``<inertial>``: ``inertia`` (3, 3, symmetric)
    about the centre of mass in the axes of its origin, which is rotated by ``rotation`` (3, 3,
    a rotation matrix: orthonormal, determinant +1) from the link axes."""
    return _from_urdf(
        _args.number(mass, "mass"),
        _args.array(com, "com", (3,)),
        _rotation(rotation, "rotation"),
        _symmetric(inertia, "inertia"),
    )
