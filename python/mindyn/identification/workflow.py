"""The identification workflow: :func:`run`, with the options of
:class:`~mindyn.identification.options.IdentifyOptions`, fits the base parameters to the logs
of :func:`~mindyn.identification.reading.load_logs`, optionally chooses the friction model and
estimates physically consistent parameters, scores the estimates on the fit and validation
logs and returns an :class:`~mindyn.identification.summary.IdentificationReport` (its JSON
document by ``to_dict()``, its terminal text by ``format()``). ``mindyn identify`` is this
workflow on the command line::

    logs = load_logs(["fit.csv"], robot, validate=["val.csv"])
    report = run(robot, logs, friction=True, consistent=True)
    print(report.format())
    doc = report.to_dict()
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from .. import _args
from ..robot import Robot, as_robot, load
from .errors import IdentificationError
from .estimation import distinct_logs
from .joint_data import JointData
from .options import DEFAULT_RSD_THRESHOLD, OPTION_NAMES, IdentifyOptions, ReadingOptions
from .reading import Logs, LogSet, load_logs
from .summary import IdentificationReport

__all__ = ["IdentificationReport", "IdentifyOptions", "ReadingOptions", "load_logs", "run"]


def _fit_keywords(options: IdentifyOptions) -> dict:
    """The keywords of :func:`~mindyn.identification.identify` the options give (threshold
    ``auto``: the default one, which the friction model's choice prunes at; the final fit's
    pruning is then decided on held-out data, :func:`_fit`; ``min_velocity`` only when given,
    which the options refuse without friction as identify does)."""
    threshold = options.rsd_threshold
    keywords = dict(
        model=options.model,
        weighted=options.weighted,
        rsd_threshold=DEFAULT_RSD_THRESHOLD if threshold == "auto" else threshold,
        energy_window=options.energy_window,
        integration=options.integration,
        integral_window=options.integral_window,
    )
    if "min_velocity" in options._given:
        keywords["min_velocity"] = options.min_velocity
    return keywords


def _chain(robot, tip: str | None) -> Robot:
    """The robot identified: ``robot`` loaded with ``tip`` (a description file), or the loaded
    ``robot`` once it is the chain ``tip`` names, so that the JSON's ``tip`` is the chain whose
    parameters it holds (the readers load a description with it)."""
    if tip is None or not isinstance(robot, Robot):
        return as_robot(robot) if tip is None else load(robot, tip=tip)
    import warnings

    try:
        with warnings.catch_warnings():  # the robot's own load said them
            warnings.simplefilter("ignore")
            joints = load(robot.source, tip=tip).joint_names
    except (ValueError, FileNotFoundError) as e:
        raise _args.fail("tip", f"does not apply to robot '{robot.name}': {e}") from None
    if joints != robot.joint_names:
        raise _args.fail(
            "tip",
            f"is '{tip}', whose chain in {robot.source} has the joints {', '.join(joints)}; "
            f"robot '{robot.name}' has {', '.join(robot.joint_names)} (load it with tip='{tip}', "
            "or give the tip it was loaded with)",
        )
    return robot


def _check_width(width, n: int) -> list[float]:
    """Friction widths for ``n`` joints (one value: the same for all; each positive, as
    :class:`IdentifyOptions` checked)."""
    w = [float(x) for x in width]
    if len(w) == 1:
        w *= n
    if len(w) != n:
        raise _args.fail("friction_width", f"has {len(w)} values; expected {n} (or one for all)")
    return w


def _as_logs(logs, model: str, robot) -> Logs:
    if isinstance(logs, Logs):
        read_for = (logs.robot, logs.joints)
        if logs.robot is not None and read_for != (robot.name, tuple(robot.joint_names)):
            raise _args.fail(
                "logs",
                f"were read for robot '{logs.robot}' (joints {', '.join(logs.joints or ())}), "
                f"not for robot '{robot.name}' (joints {', '.join(robot.joint_names)}): a log of "
                "another robot, even with as many joints, identifies nothing of this one; read "
                "them with load_logs(paths, robot) for this robot",
            )
        return logs
    alone = isinstance(logs, JointData)
    if alone:
        logs = [logs]
    if isinstance(logs, (str, bytes)) or not hasattr(logs, "__iter__"):
        raise _args.ArgumentError(
            f"logs is {type(logs).__name__}; expected the Logs of load_logs, a JointData or a "
            "list of them"
        )
    logs = list(logs)
    for d in logs:
        _args.instance(d, "logs", JointData, "the Logs of load_logs, a JointData or a list of them")
    distinct_logs(logs, "logs")
    if robot.single_dof and logs:  # their units, checked once (identify refuses other robots)
        from .estimation import _logs

        _logs(logs[0] if alone else logs, "logs", robot)
    names = [d.source or f"log {k + 1}" for k, d in enumerate(logs)]
    return Logs(LogSet(names, [[d] for d in logs]), model=model, truth=[None] * len(logs))


def _truth(robot, base, logs: Logs, options: IdentifyOptions):
    """The true base values when every fit log is simulated with the same truth, the drive
    side of a truth that cannot be compared (its rotor and friction values another side's),
    and why a truth about other link frames is not compared (None when it is)."""
    from .data import other_link_frames
    from .validation import true_base_values

    docs = logs.truth
    doc = docs[0] if docs and all(d == docs[0] for d in docs) else None
    side = None
    frames = other_link_frames(doc, robot) if doc else None
    if frames:
        return None, None, frames
    if doc and (options.rotor or options.friction):
        sim = doc.get("simulation")
        logged = sim.get("drive_side", "joint") if isinstance(sim, dict) else "joint"
        if logged != robot.drive_side:  # its Ia/Fv/Fc are another side's: nothing to compare
            doc, side = None, logged
    return (true_base_values(base, doc) if doc else None), side, None


def _friction(robot, data: list, options: IdentifyOptions, progress):
    """The friction choice (or None), the robot and base set it gives, and the friction model's
    record and lines (None and none without friction)."""
    from ..base import base_parameters

    if options.friction_model is None:
        base = base_parameters(
            robot,
            rotor=options.rotor,
            friction=options.friction,
            offset=options.offset,
            snap=options.snap,
        )
        if not base.friction:
            return None, robot, base, None, []
    from .friction import friction_lines, friction_record, select_friction_model

    choice = None
    if options.friction_model is not None:
        width = None
        if options.friction_width is not None:
            width = _check_width(options.friction_width, robot.n)
        choice = select_friction_model(
            robot,
            data,
            kind=options.friction_model,
            rotor=options.rotor,
            offset=options.offset,
            width=width,
            fit=_fit_keywords(options),
            progress=progress,
            snap=options.snap,
        )
        robot, base = choice.robot, choice.base
    record = choice.record if choice else None
    return (
        choice,
        robot,
        base,
        friction_record(robot, record=record),
        friction_lines(robot, record=record),
    )


def _dissipation(robot, res, data: list, record: dict | None, lines: list[str]):
    """The friction record and lines with the check of the fitted friction
    (:func:`~mindyn.identification.friction.dissipation_check`) of a model given or the
    default: ``not_dissipative`` and ``warning``; of the model ``auto`` chose, which it checked
    with its candidates, ``warning`` when it left it in as every candidate's fit is such."""
    if record is None:
        return record, lines
    from .friction import dissipation_check, friction_lines

    auto = record["chosen_by"] == "held-out data"
    if auto and record["kind"] not in (record.get("not_dissipative") or {}):
        return record, lines
    record = {**record, **dissipation_check(res, data, kind=record["kind"], auto=auto)}
    return record, friction_lines(robot, record=record)


def _fit(robot, base, data: list, files: list, options: IdentifyOptions, progress):
    """The least-squares fit and its JSON fields; its pruning at the threshold given, or with
    ``auto`` decided on held-out data (:func:`~mindyn.identification.pruning.choose_pruning`)."""
    from .estimation import identify
    from .pruning import choose_pruning

    try:
        if options.rsd_threshold == "auto":
            res = choose_pruning(robot, base, data, fit=_fit_keywords(options), progress=progress)
        else:
            res = identify(robot, data, base=base, **_fit_keywords(options))
    except np.linalg.LinAlgError as e:
        raise IdentificationError(
            f"{options.model} model on {' + '.join(files)}: the least-squares problem of the "
            f"base regressor of this data is singular ({e}); the data do not determine the "
            f"{base.n} base parameters: use a longer or richer log, or fewer parameters"
        ) from None
    return res, res.to_dict()


def _consistent(res, data: list, options: IdentifyOptions, progress):
    """The consistent estimate, its JSON fields and its mass matrix's smallest eigenvalue over
    the data (None, None, None unless asked for)."""
    if not options.consistent:
        return None, None, None
    from .consistent import consistent_estimate

    weight = "auto" if options.prior_weight is None else options.prior_weight
    cons = consistent_estimate(res, prior_weight=weight, progress=progress)
    return cons, cons.to_dict(), cons.mass_matrix_min_eig(data)


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
    recorded in the JSON: a description file is loaded with it, and a loaded ``robot`` must be
    that chain (its joints those of ``load(robot.source, tip=tip)``; ArgumentError naming
    ``tip`` otherwise); ``progress``: a callable taking one line per step of the long
    solves. Each stage runs once, in order: friction model, fit (its friction checked to be
    dissipative unless ``friction_model='auto'`` chose it, ``friction_record["warning"]``),
    consistent estimate, error measures. With ``rsd_threshold="auto"`` the fit's pruning is
    decided on held-out data (:mod:`~mindyn.identification.pruning`;
    ``settings["pruning_choice"]`` of the JSON)."""
    _args.optional(_args.text, tip, "tip")
    robot = _chain(robot, tip)
    _args.optional(_args.instance, options, "options", IdentifyOptions)
    _args.optional(_args.function, progress, "progress")
    if options is not None and keywords:
        raise IdentificationError(f"run: give options or {', '.join(keywords)}, not both")
    _args.unknown_keywords("run", keywords, OPTION_NAMES, error=IdentificationError)
    opts = options or IdentifyOptions(**keywords)
    logs = _as_logs(logs, opts.model, robot)
    r = logs.reading
    if r is not None and r.filter == "lowpass" and r.decimate and logs.model != opts.model:
        if "dynamic" in (logs.model, opts.model):  # decimated for the dynamic model only
            raise IdentificationError(
                f"run(model='{opts.model}'): the logs were read for the {logs.model} model "
                f"(decimated for the dynamic model only); read them with "
                f"load_logs(..., model='{opts.model}')"
            )
    held = [
        d
        for d in [*logs.fit.logs, *logs.validation.logs]
        if "held" in d.processing.get("torque", {})
    ]
    if opts.model != "dynamic" and held:
        raise IdentificationError(
            f"run(model='{opts.model}'): the torques of {held[0].source} were read as held for "
            "the dynamic model (taken at the middle of each period), which the window models "
            "integrate by integration='zoh' instead; read the logs with "
            f"load_logs(..., model='{opts.model}')"
        )
    data, vdata = logs.fit.logs, logs.validation.logs
    choice, robot, base, record, lines = _friction(robot, data, opts, progress)
    res, res_doc = _fit(robot, base, data, logs.fit.files, opts, progress)
    record, lines = _dissipation(robot, res, data, record, lines)
    cons, cons_doc, low = _consistent(res, data, opts, progress)
    from .validation import prediction_check, validate

    fit = validate(res, data)
    fit["prediction_uncertainty"].update(prediction_check(res, fit, data))
    val = validate(res, vdata) if vdata else None
    cfit = validate(cons, data) if cons is not None else None
    cval = validate(cons, vdata) if cons is not None and vdata else None
    truth, side, frames = _truth(robot, base, logs, opts)
    return IdentificationReport(
        robot=robot,
        options=opts,
        logs=logs,
        base=base,
        result=res,
        result_doc=res_doc,
        friction=choice,
        friction_record=record,
        friction_lines=lines,
        consistent=cons,
        consistent_doc=cons_doc,
        fit=fit,
        validation=val,
        consistent_fit=cfit,
        consistent_validation=cval,
        mass_matrix_min_eig=low,
        truth=truth,
        truth_side=side,
        truth_frames=frames,
        tip=tip,
    )
