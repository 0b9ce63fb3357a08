"""Control: joint-space controllers (:mod:`mindyn.control.controllers`) and the closed-loop
simulation that runs them (:mod:`mindyn.control.simulation`).

The names most used are here: the controllers :class:`AdaptivePD`, :class:`ComputedTorque` and
:class:`PD` with their gains and registry, the Slotine-Li regressor, and :func:`simulate` with
its protocols (:class:`Controller`, :class:`Reference`), references and result; the
generalised-momentum observer of external torques with its thresholds
(:mod:`mindyn.control.observer`); the check of the sampled loop's stability
(:mod:`mindyn.control.stability`, :func:`check_gains`).
"""

from .controllers import (
    CONTROLLERS,
    PD,
    AdaptivePD,
    ComputedTorque,
    ControllerSettingError,
    Gains,
    check_gains,
    check_sampled_gains,
    consistent_perturbation,
    coriolis_matrix,
    default_controller,
    default_gains,
    estimate_box,
    load_gains,
    make_controller,
    perturbed_parameters,
    slotine_li_regressor,
    slotine_li_regressor_classical,
)
from .observer import (
    MomentumObserver,
    ObserverThresholds,
    ThresholdsError,
    alarm_intervals,
    calibrate_thresholds,
    default_observer_gain,
    load_thresholds,
    residual_uncertainty,
    score_alarms,
)
from .simulation import (
    ContactWrench,
    Controller,
    CsvTrajectory,
    Reference,
    SensorNoise,
    SimulationResult,
    SimulationTimeoutError,
    SumOfSines,
    TorqueProfile,
    load_reference,
    simulate,
    simulate_inverse,
    summary,
    write_tracking_report,
)
from .stability import LoopCheck, UnstableLoopError

__all__ = [
    "ContactWrench",
    "ControllerSettingError",
    "CONTROLLERS",
    "PD",
    "AdaptivePD",
    "ComputedTorque",
    "Controller",
    "Gains",
    "LoopCheck",
    "MomentumObserver",
    "ObserverThresholds",
    "ThresholdsError",
    "TorqueProfile",
    "alarm_intervals",
    "calibrate_thresholds",
    "default_observer_gain",
    "load_thresholds",
    "residual_uncertainty",
    "score_alarms",
    "CsvTrajectory",
    "Reference",
    "SensorNoise",
    "SimulationResult",
    "SimulationTimeoutError",
    "SumOfSines",
    "UnstableLoopError",
    "check_gains",
    "check_sampled_gains",
    "consistent_perturbation",
    "coriolis_matrix",
    "default_controller",
    "default_gains",
    "estimate_box",
    "load_gains",
    "load_reference",
    "make_controller",
    "perturbed_parameters",
    "simulate",
    "simulate_inverse",
    "slotine_li_regressor",
    "slotine_li_regressor_classical",
    "summary",
    "write_tracking_report",
]
