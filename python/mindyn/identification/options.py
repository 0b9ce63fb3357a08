"""The options of an identification: how its logs are read (:class:`ReadingOptions`) and
what is identified and how (:class:`IdentifyOptions`), keyword-only, with the defaults of
``mindyn identify``, checked when made."""

from __future__ import annotations

import numbers
from dataclasses import asdict, dataclass, field, fields

import numpy as np

from .. import _args
from ..robot import FRICTION_KINDS
from .columns import ColumnMap, column_map
from .data import DataError, given_drive_gain
from .errors import IdentificationError

FILTERS = ("lowpass", "butter", "savgol", "none")
#: How a logged torque is read: a measurement at its sample, or a command held over its period
TORQUE_READINGS = ("sampled", "held")

#: The default RSD threshold [%]: a parameter is kept when its estimate is more than sqrt(2)
#: standard deviations from zero (100 / sqrt(2) = 70.7 %): Akaike's criterion for one
#: parameter, below which leaving it out lowers the expected prediction error. The standard
#: deviations count the low-passed noise's correlation between the samples fitted
#: (:func:`~mindyn.identification.estimation.correlation_factor`), without which they came out
#: about 2.3 times too small and the former 30 % acted like this rule. The ZCR07S study's 30 %
#: (a t-statistic above 3.3) is ``rsd_threshold=30``.
DEFAULT_RSD_THRESHOLD = 70.7
MODELS = ("dynamic", "integral", "energy")
INTEGRATIONS = ("auto", "simpson", "trapezoid", "zoh")
FRICTION_MODELS = (*FRICTION_KINDS, "dahl", "auto")
#: The default ``min_velocity`` of :func:`~mindyn.identification.identify` [rad/s, m/s]: told
#: apart from 0.01 given (given to a base without friction, refused).
DEFAULT_MIN_VELOCITY = _args.Default(0.01)
#: The defaults of the options of :class:`IdentifyOptions` that apply in one mode only (a
#: model, friction): what they are when not given.
MODE_DEFAULTS = {
    "energy_window": 10,
    "integration": "auto",
    "integral_window": 40,
    "min_velocity": float(DEFAULT_MIN_VELOCITY),
}


def _widths(width) -> tuple[float, ...]:
    """``friction_width``: one positive number (every joint's) or one per joint; the count is
    checked against the robot by the workflow."""
    if isinstance(width, numbers.Real) or not isinstance(width, (list, tuple, np.ndarray)):
        return (_args.number(width, "friction_width", positive=True),)
    if len(width) == 0:
        raise _args.fail("friction_width", "is empty; expected a positive number or one per joint")
    return tuple(_args.number(w, "friction_width", positive=True) for w in width)


@dataclass(frozen=True, kw_only=True)
class IdentifyOptions:
    """The options of one identification, with the defaults of ``mindyn identify``.

    ``model``: dynamic, integral or energy; ``rotor``, ``friction``, ``offset``: the joint terms
    identified; ``weighted``: weighted (else ordinary) least squares; ``rsd_threshold`` [%]:
    parameters above it removed (0 keeps all; ``"auto"``, the default:
    :data:`DEFAULT_RSD_THRESHOLD` or every base parameter, as held-out blocks of the fit logs
    decide, :mod:`~mindyn.identification.pruning`);
    ``energy_window``, ``integral_window``: sample
    intervals per window (10, 40); ``integration``: auto (the default), simpson, trapezoid or
    zoh; ``min_velocity``: joint equations slower than this left out (dynamic and integral
    models with friction; 0.01 rad/s or m/s). These four apply in one mode each: given (any
    value, the default's too) in another, they are refused; not given (None), they take their
    defaults (:data:`MODE_DEFAULTS`), which the attributes then hold;
    ``friction_model``: a friction kind, ``dahl`` or ``auto`` (implies ``friction``),
    ``friction_width``: the tanh width, one positive number for every joint or one per joint
    (per motor, in the motor's units, on the motor side; smooth or auto only);
    ``consistent``: also the physically consistent estimate, with ``prior_weight`` (None:
    chosen from the data); ``snap``: the rotations near right angles rounded before the base
    set is computed, as ``snap=`` of :func:`mindyn.base_parameters` (``"auto"``: the right
    angles the description writes rounded; False: none)."""

    model: str = "dynamic"
    rotor: bool = False
    friction: bool = False
    offset: bool = False
    weighted: bool = True
    rsd_threshold: float | str = "auto"
    # None: not given, the default of :data:`MODE_DEFAULTS` (an option of one mode given in
    # another is refused, whatever its value)
    energy_window: int | None = None
    integration: str | None = None
    integral_window: int | None = None
    min_velocity: float | None = None
    friction_model: str | None = None
    friction_width: tuple[float, ...] | None = None
    consistent: bool = False
    prior_weight: float | None = None
    snap: str | float | bool = "auto"
    #: the options of :data:`MODE_DEFAULTS` given (not None)
    _given: frozenset[str] = field(default=frozenset(), init=False, repr=False, compare=False)

    def __post_init__(self):
        given = frozenset(k for k in MODE_DEFAULTS if getattr(self, k) is not None)
        object.__setattr__(self, "_given", given)
        for k, default in MODE_DEFAULTS.items():
            if k not in given:
                object.__setattr__(self, k, default)
        _args.choice(self.model, "model", MODELS)
        for name in ("rotor", "friction", "offset", "weighted", "consistent"):
            object.__setattr__(self, name, _args.flag(getattr(self, name), name))
        if self.rsd_threshold != "auto":
            if isinstance(self.rsd_threshold, str):
                raise _args.fail(
                    "rsd_threshold", f"is {self.rsd_threshold!r}; expected a number >= 0 or 'auto'"
                )
            object.__setattr__(
                self,
                "rsd_threshold",
                _args.number(self.rsd_threshold, "rsd_threshold", minimum=0.0),
            )
        for name in ("energy_window", "integral_window"):
            object.__setattr__(self, name, _args.integer(getattr(self, name), name, 1))
        _args.choice(self.integration, "integration", INTEGRATIONS)
        object.__setattr__(
            self, "min_velocity", _args.number(self.min_velocity, "min_velocity", minimum=0.0)
        )
        _args.optional(_args.choice, self.friction_model, "friction_model", FRICTION_MODELS)
        object.__setattr__(self, "snap", _args.snap(self.snap))
        if self.prior_weight is not None:
            object.__setattr__(
                self, "prior_weight", _args.number(self.prior_weight, "prior_weight", minimum=0.0)
            )
        if self.model not in MODELS:
            raise IdentificationError(f"model '{self.model}': expected one of {', '.join(MODELS)}")
        if self.integration not in INTEGRATIONS:
            raise IdentificationError(
                f"integration '{self.integration}': expected one of {', '.join(INTEGRATIONS)}"
            )
        if self.friction_width is not None:
            object.__setattr__(self, "friction_width", _widths(self.friction_width))
            if self.friction_model not in ("smooth", "auto"):
                got = (
                    "no friction model is given"
                    if self.friction_model is None
                    else f"got friction_model='{self.friction_model}'"
                )
                raise _args.fail(
                    "friction_width",
                    "applies only with friction_model='smooth' or 'auto' (the tanh width of the "
                    f"smooth model); {got}",
                )
        if self.friction_model is not None:
            object.__setattr__(self, "friction", True)
        if self.prior_weight is not None and not self.consistent:
            raise IdentificationError("prior_weight=: expected consistent=True as well")
        self._refuse_what_does_not_apply()

    def _refuse_what_does_not_apply(self) -> None:
        """An option given (whatever its value) where it has no effect is refused, naming
        it: the window of one model with another, the integration rule with the dynamic model,
        ``min_velocity`` without friction or with the energy model."""
        dynamic = self.model == "dynamic"
        got = f"got model='{self.model}'"
        for name, applies, where, why in (
            ("energy_window", self.model == "energy", "model='energy'", got),
            ("integral_window", self.model == "integral", "model='integral'", got),
            ("integration", not dynamic, "model='energy' or 'integral'", got),
            (
                "min_velocity",
                self.model in ("dynamic", "integral") and self.friction,
                "model='dynamic' or 'integral' with friction (friction=True or friction_model=)",
                got if self.model == "energy" else "the model has no friction",
            ),
        ):
            if not applies and name in self._given:
                raise _args.fail(name, f"applies only with {where}; {why}")

    def to_dict(self) -> dict:
        """The options as given or defaulted (what was given aside)."""
        out = asdict(self)
        del out["_given"]
        return out


OPTION_NAMES = frozenset(f.name for f in fields(IdentifyOptions) if f.init)


def check_cutoff(filter: str, cutoff: float | None) -> None:
    """A cut-off is that of a Butterworth filter: refused with another filter (``savgol``,
    ``none``), which would ignore it."""
    if cutoff is not None and filter not in ("lowpass", "butter"):
        raise _args.fail(
            "cutoff",
            "applies only with filter='lowpass' or 'butter' (the cut-off of a Butterworth "
            f"filter); got filter='{filter}'",
        )


@dataclass(frozen=True, kw_only=True)
class ReadingOptions:
    """How a log is read and pre-processed (the options of ``mindyn identify`` of the same
    names).

    ``filter``: ``lowpass`` (the identification data path of
    :func:`~mindyn.identification.preprocess.preprocess`: resampling, one zero-phase low-pass,
    edges dropped, decimation), or ``butter``, ``savgol``, ``none`` (derivatives only);
    ``cutoff`` [Hz] (None: from the data; lowpass and butter only); ``periods`` / ``period``
    [s]: a periodic excitation averaged (lowpass, fit logs only); ``edge`` [s] dropped at each
    end (lowpass); ``decimate`` (lowpass, dynamic model only; None: True, and given True or
    False where it does not apply, refused); ``torque_unit`` (None: as the
    file says; not with a currents file for every log), ``drive_gain`` (per
    joint, or one for all), ``topic`` (ROS bag), ``columns``: a column map of the CSV logs
    (:func:`~mindyn.identification.columns.column_map`; the currents files read through its
    ``t`` and ``i``); ``torque``: ``sampled`` (a measurement, taken at its sample) or ``held``
    (the command a digital controller holds over each sample period, as ``mindyn simulate``'s
    tracking mode logs it: taken at the middle of its period,
    :func:`~mindyn.identification.data.held_torque_at_samples`; dynamic model only, the window
    models take a held torque by ``integration='zoh'``; None: per log, held when its truth
    sidecar says its simulation held it, :func:`~mindyn.identification.reading.simulated_held`,
    else sampled; given where it does not apply, refused)."""

    filter: str = "lowpass"
    cutoff: float | None = None
    periods: int | None = None
    period: float | None = None
    edge: float | None = None
    # None: not given, True (decimated on the low-pass path of the dynamic model)
    decimate: bool | None = None
    torque_unit: str | None = None
    drive_gain: tuple[float, ...] | None = None
    topic: str | None = None
    columns: ColumnMap | None = None
    # None: not given, sampled
    torque: str | None = None

    #: whether ``decimate`` was given (True or False): refused where it does not apply
    _decimate_given: bool = field(default=False, init=False, repr=False, compare=False)
    #: whether ``torque`` was given: refused where it does not apply
    _torque_given: bool = field(default=False, init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "_torque_given", self.torque is not None)
        if self.torque is None:
            object.__setattr__(self, "torque", "sampled")
        _args.choice(self.torque, "torque", TORQUE_READINGS)
        object.__setattr__(self, "_decimate_given", self.decimate is not None)
        if self.decimate is None:
            object.__setattr__(self, "decimate", True)
        object.__setattr__(self, "decimate", _args.flag(self.decimate, "decimate"))
        if self.columns is not None:
            object.__setattr__(self, "columns", column_map(self.columns))
        if self.filter not in FILTERS:
            raise DataError(f"filter '{self.filter}': expected one of {', '.join(FILTERS)}")
        if self.drive_gain is not None:
            gains = given_drive_gain(self.drive_gain)
            assert gains is not None  # given
            object.__setattr__(self, "drive_gain", tuple(float(g) for g in gains))
        check_cutoff(self.filter, self.cutoff)
        if self.filter != "lowpass":  # the options of the low-pass path, refused with another
            for given, value in (
                ("periods=", self.periods),
                ("period=", self.period),
                ("edge=", self.edge),
                (f"decimate={self.decimate}", True if self._decimate_given else None),
            ):
                if value is not None:
                    raise DataError(f"{given} needs filter='lowpass' (got filter='{self.filter}')")
