"""mindyn: the minimal dynamic model of a manipulator.

- :func:`load` gives a :class:`Robot` (URDF, YAML DH/MDH table or bundled name) with inverse
  dynamics, regressors, energies, mass matrix and forward dynamics, linear in the classical
  parameters (C++ core), and KDL kinematics;
- :func:`base_parameters`: base inertial parameters by the projection method (or the numerical
  method), regrouping matrix, formulas, base regressors;
- :mod:`mindyn.codegen`: inverse dynamics, gravity and base regressor as C or Structured Text;
- :mod:`mindyn.excitation`, :mod:`mindyn.data`, :mod:`mindyn.simulate`,
  :mod:`mindyn.identification`: excitation trajectories, joint logs, simulated measurements,
  least-squares identification with statistics and validation;
- :mod:`mindyn.control`, :func:`ik`: Slotine-Li regressor, adaptive PD and other controllers in
  closed-loop simulation, inverse kinematics.
"""

from ._core import ModelError, RobotFileNotFoundError, inertial_from_com, inertial_from_urdf
from ._core import from_pinocchio_order as _from_pin
from ._core import to_pinocchio_order as _to_pin
from .base import BaseParameters, base_parameters
from .control import coriolis_matrix, slotine_li_regressor
from .ik import ik
from .robot import Robot, bundled_robots, load

__version__ = "0.1.0"

__all__ = [
    "BaseParameters",
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


def to_pinocchio_order(params):
    """Inertial parameters ``[XX XY XZ YY YZ ZZ MX MY MZ M]`` per link, shape (10 n,), to
    Pinocchio's dynamic-parameter order ``[m, mcx, mcy, mcz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]``."""
    return _to_pin(params)


def from_pinocchio_order(params):
    """Inverse of :func:`to_pinocchio_order`."""
    return _from_pin(params)
