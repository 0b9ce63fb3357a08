"""The identification workflow: the options of one identification (:class:`IdentifyOptions`)
and :func:`run`, which fits the base parameters to the logs of :func:`load_logs`, optionally
chooses the friction model and estimates physically consistent parameters, scores the
estimates on the fit and validation logs and returns an :class:`IdentificationReport` (its
JSON document by ``to_dict()``, its terminal text by ``format()``). ``mindyn identify`` is this
workflow on the command line::

    logs = load_logs(["fit.csv"], robot, validate=["val.csv"])
    report = run(robot, logs, friction=True, consistent=True)
    print(report.format())
    doc = report.to_dict()
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, fields

import numpy as np

from .data import JointData
from .errors import IdentificationError
from .reading import Logs, LogSet, ReadingOptions, check_width, load_logs
from .summary import IdentificationReport

__all__ = ["IdentificationReport", "IdentifyOptions", "ReadingOptions", "load_logs", "run"]

MODELS = ("dynamic", "integral", "energy")
INTEGRATIONS = ("simpson", "trapezoid", "zoh")


@dataclass(frozen=True, kw_only=True)
class IdentifyOptions:
    """The options of one identification, with the defaults of ``mindyn identify``.

    ``model``: dynamic, integral or energy; ``rotor``, ``friction``, ``offset``: the joint terms
    identified; ``weighted``: weighted (else ordinary) least squares; ``rsd_threshold`` [%]:
    parameters above it removed (0 keeps all); ``energy_window``, ``integral_window``: sample
    intervals per window; ``integration``: simpson, trapezoid or zoh; ``min_velocity``: joint
    equations slower than this left out (dynamic model with friction); ``friction_model``: a
    friction kind or ``auto`` (implies ``friction``), ``friction_width``: the tanh widths
    (smooth or auto); ``consistent``: also the physically consistent estimate, with
    ``prior_weight`` (None: chosen from the data)."""

    model: str = "dynamic"
    rotor: bool = False
    friction: bool = False
    offset: bool = False
    weighted: bool = True
    rsd_threshold: float = 30.0
    energy_window: int = 10
    integration: str = "simpson"
    integral_window: int = 40
    min_velocity: float = 0.01
    friction_model: str | None = None
    friction_width: tuple[float, ...] | None = None
    consistent: bool = False
    prior_weight: float | None = None

    def __post_init__(self):
        if self.model not in MODELS:
            raise IdentificationError(f"model '{self.model}': expected one of {', '.join(MODELS)}")
        if self.integration not in INTEGRATIONS:
            raise IdentificationError(
                f"integration '{self.integration}': expected one of {', '.join(INTEGRATIONS)}"
            )
        if self.friction_width is not None:
            if self.friction_model is None:
                raise IdentificationError(
                    "--friction-width: expected --friction-model smooth or auto"
                )
            object.__setattr__(self, "friction_width", tuple(self.friction_width))
        if self.friction_model is not None:
            object.__setattr__(self, "friction", True)
        if self.prior_weight is not None and not self.consistent:
            raise IdentificationError("--prior-weight: expected --consistent as well")

    def fit_options(self) -> dict:
        """The keywords of :func:`~mindyn.identification.identify` these options give."""
        return dict(
            model=self.model,
            weighted=self.weighted,
            rsd_threshold=self.rsd_threshold,
            energy_window=self.energy_window,
            integration=self.integration,
            integral_window=self.integral_window,
            min_velocity=self.min_velocity,
        )

    def to_dict(self) -> dict:
        return asdict(self)


OPTION_NAMES = frozenset(f.name for f in fields(IdentifyOptions))


def _as_logs(logs, model: str) -> Logs:
    if isinstance(logs, Logs):
        return logs
    if isinstance(logs, JointData):
        logs = [logs]
    logs = list(logs)
    names = [d.source or f"log {k + 1}" for k, d in enumerate(logs)]
    return Logs(LogSet(names, [[d] for d in logs]), model=model, truth=[None] * len(logs))


def _truth(robot, base, logs: Logs, options: IdentifyOptions):
    """The true base values when every fit log is simulated with the same truth, and the drive
    side of a truth that cannot be compared (its rotor and friction values another side's)."""
    from .validation import true_base_values

    docs = logs.truth
    doc = docs[0] if docs and all(d == docs[0] for d in docs) else None
    side = None
    if doc and (options.rotor or options.friction):
        sim = doc.get("simulation")
        logged = sim.get("drive_side", "joint") if isinstance(sim, dict) else "joint"
        if logged != robot.drive_side:  # its Ia/Fv/Fc are another side's: nothing to compare
            doc, side = None, logged
    return (true_base_values(base, doc) if doc else None), side


def _fit(robot, data: list, files: list, options: IdentifyOptions, progress):
    """The friction choice (or None), the robot and base set it gives, and the fit."""
    from ..base import base_parameters
    from .estimation import identify

    friction = None
    if options.friction_model is not None:
        from .friction import select_friction_model

        width = None
        if options.friction_width is not None:
            width = check_width(options.friction_width, robot.n)
        friction = select_friction_model(
            robot,
            data,
            options.friction_model,
            rotor=options.rotor,
            offset=options.offset,
            width=width,
            fit=options.fit_options(),
            progress=progress,
        )
        robot, base = friction.robot, friction.base
    else:
        base = base_parameters(
            robot, rotor=options.rotor, friction=options.friction, offset=options.offset
        )
    try:
        res = identify(robot, data, base=base, **options.fit_options())
    except np.linalg.LinAlgError as e:
        raise IdentificationError(
            f"{options.model} model on {' + '.join(files)}: the "
            f"least-squares problem of the base regressor of this data is singular ({e}); the "
            f"data do not determine the {base.n} base parameters: use a longer or richer log, "
            "or fewer parameters"
        ) from None
    return friction, robot, base, res


def run(
    robot,
    logs: Logs | Sequence[JointData] | JointData,
    *,
    options: IdentifyOptions | None = None,
    tip: str | None = None,
    progress: Callable[[str], None] | None = None,
    **keywords,
) -> IdentificationReport:
    """Identify the base parameters of ``robot`` from ``logs`` (a :class:`Logs` of
    :func:`load_logs`, with its validation logs, or logs read otherwise) with ``options`` or the
    keywords of :class:`IdentifyOptions` (``friction=True``, ``consistent=True``, ...).

    Returns an :class:`IdentificationReport`: the fit, the friction choice and the consistent
    estimate when asked for, the error measures on the fit and validation logs, the true values
    when the logs are simulated. ``tip``: the chain identified (as ``load(robot, tip=...)``),
    recorded in the JSON; ``progress``: a callable taking one line per step of the long
    solves."""
    if options is not None and keywords:
        raise IdentificationError(f"run: give options or {', '.join(keywords)}, not both")
    unknown = sorted(set(keywords) - OPTION_NAMES)
    if unknown:
        raise IdentificationError(
            f"run: unknown option(s) {', '.join(unknown)}; expected some of "
            + ", ".join(sorted(OPTION_NAMES))
        )
    opts = options or IdentifyOptions(**keywords)
    logs = _as_logs(logs, opts.model)
    data, vdata = logs.fit.logs, logs.validation.logs
    from .validation import validate

    friction, robot, base, res = _fit(robot, data, logs.fit.files, opts, progress)
    cons = None
    if opts.consistent:
        from .consistent import consistent_estimate

        weight = "auto" if opts.prior_weight is None else opts.prior_weight
        cons = consistent_estimate(res, weight, data=data, progress=progress)
    truth, truth_side = _truth(robot, base, logs, opts)
    return IdentificationReport(
        robot=robot,
        options=opts,
        logs=logs,
        base=base,
        result=res,
        friction=friction,
        consistent=cons,
        fit=validate(res, data),
        validation=validate(res, vdata) if vdata else None,
        consistent_fit=validate(cons, data) if cons is not None else None,
        consistent_validation=validate(cons, vdata) if cons is not None and vdata else None,
        mass_matrix_min_eig=cons.mass_matrix_min_eig(data) if cons is not None else None,
        truth=truth,
        truth_side=truth_side,
        tip=tip,
    )
