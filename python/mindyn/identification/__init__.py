"""Identification of the base parameters from joint data, by concern:

- :mod:`~mindyn.identification.data`: joint logs (``JointData``), CSV reading and writing, torque
  units, derivatives by zero-phase filtering;
- :mod:`~mindyn.identification.columns`: column maps, a log read under a controller's own
  column names (``read_csv(columns=...)``);
- :mod:`~mindyn.identification.rosbag`: ``sensor_msgs/JointState`` from ROS bags;
- :mod:`~mindyn.identification.excitation`: optimised Fourier excitation trajectories;
- :mod:`~mindyn.identification.models`: the regression systems (dynamic, energy and integral
  models);
- :mod:`~mindyn.identification.estimation`: least squares with statistics and pruning;
- :mod:`~mindyn.identification.friction`: the friction model of an identification (given,
  derived from the data, or chosen on held-out data);
- :mod:`~mindyn.identification.validation`: torque prediction and error measures (against the
  filtered torques, the torques as logged, and on moving samples), the uncertainty of the
  predicted torques and whether an estimate determines them;
- :mod:`~mindyn.identification.prediction`: an identification's torques on any log;
- :mod:`~mindyn.identification.consistent`: physically consistent classical parameters and
  payload identification (convex, cvxpy);
- :mod:`~mindyn.identification.currents`: torques from motor currents logged apart;
- :mod:`~mindyn.identification.floating`: floating-base robots from logs with contact wrenches
  (the full and the base-link models, free flight);
- :mod:`~mindyn.identification.report`: tables and plots;
- :mod:`~mindyn.identification.workflow`: the workflow of ``mindyn identify`` as a library:
  :class:`IdentifyOptions` and :class:`ReadingOptions`
  (:mod:`~mindyn.identification.options`), :func:`load_logs`
  (:mod:`~mindyn.identification.reading`),
  :func:`run` returning an :class:`IdentificationReport`
  (:mod:`~mindyn.identification.summary`: its JSON by ``to_dict()``;
  :mod:`~mindyn.identification.terminal`: its text by ``format()``).

The names below are the ones a workflow needs; the modules hold the rest. A module not imported
here (``excitation``, ``floating``, ``rosbag``, ...) is imported when first named as an
attribute: ``mindyn.identification.excitation``.
"""

import importlib
import importlib.util

from .consistent import ConsistentResult, identify_consistent, identify_payload
from .data import DataError, read_csv, write_csv
from .errors import IdentificationError, RankDeficientError
from .estimation import IdentificationResult, identify
from .friction import FrictionChoice, select_friction_model
from .joint_data import JointData
from .models import MODELS, dynamic_system, energy_system, integral_system
from .options import IdentifyOptions, ReadingOptions
from .reading import Logs, load_logs
from .summary import IdentificationReport
from .validation import error_measures, true_base_values, validate
from .workflow import run

__all__ = [
    "MODELS",
    "ConsistentResult",
    "DataError",
    "FrictionChoice",
    "IdentificationError",
    "IdentificationReport",
    "IdentificationResult",
    "IdentifyOptions",
    "JointData",
    "Logs",
    "RankDeficientError",
    "ReadingOptions",
    "dynamic_system",
    "energy_system",
    "error_measures",
    "identify",
    "identify_consistent",
    "identify_payload",
    "integral_system",
    "load_logs",
    "read_csv",
    "run",
    "select_friction_model",
    "true_base_values",
    "validate",
    "write_csv",
]


def __getattr__(name: str):
    # the modules that the names above do not need are imported when first named
    if not name.startswith("_") and importlib.util.find_spec(f"{__name__}.{name}") is not None:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
