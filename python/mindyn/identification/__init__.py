"""Identification of the base parameters from joint data, by concern:

- :mod:`~mindyn.identification.data`: joint logs (``JointData``), CSV reading and writing, torque
  units, derivatives by zero-phase filtering;
- :mod:`~mindyn.identification.rosbag`: ``sensor_msgs/JointState`` from ROS bags;
- :mod:`~mindyn.identification.excitation`: optimised Fourier excitation trajectories;
- :mod:`~mindyn.identification.models`: the regression systems (dynamic and energy models);
- :mod:`~mindyn.identification.estimation`: least squares with statistics and pruning;
- :mod:`~mindyn.identification.validation`: torque prediction on other data;
- :mod:`~mindyn.identification.report`: tables and plots.

The names below are the ones a workflow needs; the modules hold the rest.
"""

from .data import DataError, JointData, read_csv, write_csv
from .errors import IdentificationError, RankDeficientError
from .estimation import IdentificationResult, identify
from .models import MODELS, dynamic_system, energy_system
from .validation import true_base_values, validate

__all__ = [
    "MODELS",
    "DataError",
    "IdentificationError",
    "IdentificationResult",
    "JointData",
    "RankDeficientError",
    "dynamic_system",
    "energy_system",
    "identify",
    "read_csv",
    "true_base_values",
    "validate",
    "write_csv",
]
