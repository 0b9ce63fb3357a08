"""CLI: ``mindyn excite``, ``mindyn simulate``, ``mindyn identify``, ``mindyn identify-payload``,
``mindyn predict``."""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from pathlib import Path

import numpy as np

from ..base import base_parameters
from ..robot import FRICTION_KINDS, load
from .args import (
    ZCR07S_STUDY,
    add_command,
    add_drive_side,
    add_joint_terms,
    add_offset,
    add_recorded_torque_reading,
    add_robot,
    check_radians,
    controller_period,
    deprecated,
    drive_side_words,
    joint_terms,
    joint_values,
    joint_vector,
    number,
    output_dir,
    output_file,
    seed,
    with_drive_side,
)
from .export import add_description_outputs, check_description_kind, write_description


# ---------------------------------------------------------------------------------------------
# excite
# ---------------------------------------------------------------------------------------------
def cmd_excite(args: argparse.Namespace) -> int:
    from ..identification.excitation import check_sampling, optimize_excitation

    if Path(args.output).suffix.lower() in (".json", ".png"):
        raise ValueError(
            f"-o {args.output}: the trajectory CSV needs another suffix than "
            f"{Path(args.output).suffix} (the coefficients and the plot are written beside it as "
            ".json and .png)"
        )
    try:  # before the optimisation, not after it
        check_sampling(args.harmonics, args.freq, args.rate)
    except ValueError as e:
        raise ValueError(f"--rate {args.rate:g}: {e}") from None
    if not args.samples > 2 * args.harmonics:
        raise ValueError(
            f"--samples {args.samples}: expected more than 2 x --harmonics = "
            f"{2 * args.harmonics}, so that the highest harmonic is sampled"
        )
    robot = with_drive_side(load(args.robot, tip=args.tip), args)
    start = None
    if args.start:
        start = np.array(joint_values(args.start, robot.n, "--start", broadcast=True))
        if args.degrees:
            rev = np.array([t == "revolute" for t in robot.joint_types])
            start = np.where(rev, np.radians(start), start)
        else:
            check_radians(start, "--start", "--deg", robot)
    res = optimize_excitation(
        robot,
        harmonics=args.harmonics,
        freq=args.freq,
        criterion=args.criterion,
        starts=args.starts,
        seed=args.seed,
        rotor=args.rotor,
        friction=args.friction,
        samples=args.samples,
        maxiter=args.maxiter,
        margin=args.margin,
        start=start,
        progress=not args.quiet,
    )
    paths = res.save(args.output, rate=args.rate)
    shown = {"cond": "condition number", "logdet": "log det(W^T W / rows)"}.get(
        res.criterion, "log Hadamard ratio"
    )
    print(
        f"{robot.name}: {res.trajectory.harmonics} harmonics at {res.trajectory.freq:g} Hz "
        f"(period {res.trajectory.period:g} s), {len(res.base_names)} base parameters"
    )
    print(f"  {shown}: {res.value:.6g} (initial guess {res.initial_value:.6g})")
    print(f"  limits respected on a fine grid (largest relative excess {res.max_violation:.2g})")
    print(f"  wrote {paths['csv']} ({args.rate:g} Hz), {paths['json']}, {paths['png']}")
    return 0


# ---------------------------------------------------------------------------------------------
# simulate
# ---------------------------------------------------------------------------------------------
def cmd_simulate(args: argparse.Namespace) -> int:
    from ..control.simulation import (
        SensorNoise,
        noise_from_spec,
        simulate,
        simulate_inverse,
        write_tracking_report,
    )
    from ..identification.data import convert_torque, write_csv
    from .control import reference_and_controller

    robot = with_drive_side(load(args.robot, tip=args.tip), args)
    rate = 1.0 / args.period if args.period else args.rate
    args.period = 1.0 / rate
    ref, ref_text, duration, cycle, controller, _ = reference_and_controller(
        args, robot, lambda r: r.duration
    )
    ref_tau = None
    if args.torque_noise and args.torque_noise.strip().endswith("%"):
        t = np.linspace(0, ref.duration, 200)
        ref_tau = robot.inverse_dynamics(*ref.evaluate(t))
    noise = SensorNoise(
        torque=noise_from_spec(args.torque_noise, robot, "torque", ref_tau),
        position=noise_from_spec(args.position_noise, robot, "position"),
        velocity=noise_from_spec(args.velocity_noise, robot, "velocity"),
        quantization=noise_from_spec(args.quantization, robot, "quantization"),
    )
    kwargs = dict(
        rate=rate,
        duration=duration,
        rotor=args.rotor,
        friction=args.friction,
        noise=noise,
        seed=args.seed,
    )
    if args.mode == "tracking":
        limit = None if args.torque_limit == "none" else args.torque_limit
        log = simulate(
            robot,
            ref,
            controller,
            substeps=args.substeps,
            integrator=args.integrator,
            torque_limit=limit,
            **kwargs,
        )
    else:
        log = simulate_inverse(robot, ref, **kwargs)
    path = log.save(args.output, robot.name, robot.joint_names)
    if args.torque_unit == "permille":
        scale, _ = convert_torque(np.ones((1, robot.n)), "permille", robot)
        write_csv(path, log.t, log.q, log.tau / scale, dq=log.dq, torque_unit="permille")
    info = log.info
    print(
        f"{robot.name}: {info['mode']} simulation, {log.t.shape[0]} samples at {rate:g} Hz "
        f"({info['duration_s']:g} s), rotor inertia {'on' if args.rotor else 'off'}, "
        f"friction {'on' if args.friction else 'off'}"
        + (f", {side}" if (side := drive_side_words(robot, args)) else "")
    )
    if info["mode"] == "tracking":
        err = np.degrees(info["max_tracking_error"])
        print(
            f"  controller {info['controller']}; max tracking error per joint [deg]: "
            + " ".join(f"{e:.3g}" for e in err)
        )
        for note in (
            getattr(getattr(controller, "gains", None), "note", ""),
            info.get("stability"),
        ):
            if note:
                print(f"  {note}")
    nz = info["noise"]
    print("  torque noise sd per joint: " + " ".join(f"{v:.3g}" for v in nz["torque"]))
    if any(nz["quantization"]) or any(nz["position"]) or any(nz["velocity"]):
        print(
            f"  encoder step {max(nz['quantization']):.3g}, position noise "
            f"{max(nz['position']):.3g}, velocity noise {max(nz['velocity']):.3g}"
        )
    unit = " (torques in permille of rated torque)" if args.torque_unit == "permille" else ""
    print(f"  wrote {path}{unit} and {path.with_name(path.stem + '.truth.json')}")
    if args.report:
        header = {"robot": robot.name, "reference": ref_text, "seed": args.seed}
        write_tracking_report(log, args.report, cycle, header)
        print(f"  report: {args.report}/ (summary.json, log.csv, plots)")
    return 0


# ---------------------------------------------------------------------------------------------
# identify
# ---------------------------------------------------------------------------------------------
def _read(path, robot, args, currents=None, cutoff=None, periodic=False):
    """The log at ``path`` (torques from the ``currents`` file when given) as a list of logs;
    with ``--filter lowpass`` cut at its breaks (:func:`~mindyn.identification.preprocess.
    split_at_gaps`) and each segment through the data path of :func:`~mindyn.identification.
    preprocess.preprocess` (``cutoff`` overrides ``--cutoff``; ``--periods`` /
    ``--excitation-period`` only when ``periodic``); otherwise one log."""
    from dataclasses import replace

    from ..identification.currents import attach_currents
    from ..identification.data import DataError, convert_torque, read_csv
    from ..identification.models import require_torque
    from ..identification.rosbag import is_rosbag, read_rosbag

    if args.filter == "lowpass":
        from ..identification.preprocess import preprocess, split_at_gaps

        unfiltered = argparse.Namespace(**{**vars(args), "filter": "none", "_raw": True})
        (raw,) = _read(path, robot, unfiltered, currents)
        segments = split_at_gaps(raw)
        if len(segments) > 1 and (args.periods or args.period):
            raise ValueError(
                f"--periods/--excitation-period: {path} has {len(segments) - 1} break(s) in its "
                "time stamps; a periodic log to be averaged must be one continuous recording"
            )
        return [
            preprocess(
                seg,
                cutoff=cutoff if cutoff is not None else args.cutoff,
                periods=args.periods if periodic else None,
                period=args.period if periodic else None,
                edge=args.edge,
                # The window models integrate over the logged samples: no decimation there.
                decimate=not args.no_decimate and args.model == "dynamic",
            )
            for seg in segments
        ]

    gain = (
        np.array(joint_values(args.drive_gain, robot.n, "--drive-gain", broadcast=True))
        if args.drive_gain
        else None
    )
    if Path(path).is_dir() and not is_rosbag(path):
        raise DataError(f"'{path}' is a folder but not a ROS 2 bag (it has no metadata.yaml)")
    unit = None if currents else args.torque_unit
    if is_rosbag(path):
        current = unit == "current"
        data = read_rosbag(
            path,
            robot,
            topic=args.topic,
            torque_unit="Nm" if current or not unit else unit,
            filter=args.filter,
            cutoff=args.cutoff,
        )
        if current:  # effort in A: the gains (given or of the drive table) turn it into N m
            tau, info = convert_torque(require_torque(data), "current", robot, gain)
            data = replace(data, tau=tau, processing={**data.processing, "torque": info})
    else:
        data = read_csv(
            path,
            robot=robot,
            torque_unit=unit,
            require_torque=not currents and not getattr(args, "_torque_optional", False),
            filter=args.filter,
            cutoff=args.cutoff,
            drive_gain=gain,
        )
    if currents:
        data = attach_currents(data, currents, robot, gain)
    if not getattr(args, "_raw", False):  # the raw read of the lowpass path: resampled later
        from ..identification.preprocess import require_even_stamps

        require_even_stamps(data, args.filter)
    if gain is not None and not data.processing["torque"]["unit"].startswith("motor current"):
        raise ValueError(
            f"--drive-gain: {path} holds torques in {data.processing['torque']['unit']}, not "
            "motor currents; expected --torque-unit current, columns i1..in or --currents"
        )
    return [data]


def _read_filtered(path, robot, args, currents=None, **kw):
    """:func:`_read`, with a filter that cannot be designed at ``--cutoff`` named as such."""
    try:
        return _read(path, robot, args, currents, **kw)
    except np.linalg.LinAlgError as e:
        if args.filter not in ("butter", "lowpass"):
            raise
        raise ValueError(
            f"--cutoff {args.cutoff:g} Hz: the zero-phase Butterworth filter "
            f"of {path} is singular at this cutoff ({e}); expected a cutoff of at least 1e-4 of "
            "half the log's sample rate"
            if args.cutoff is not None
            else f"{path}: the Butterworth filter for the derivatives is singular ({e})"
        ) from None


def _paired(logs, currents, flag, logs_flag):
    """One currents file per log (or none)."""
    if not currents:
        return [None] * len(logs)
    if len(currents) != len(logs):
        raise ValueError(
            f"{flag}: {len(currents)} currents file(s) for {len(logs)} log(s) of {logs_flag}; "
            "expected one per log, in the same order"
        )
    return currents


def _check_lowpass_options(args: argparse.Namespace) -> None:
    """Refuses the options of ``--filter lowpass`` with another filter."""
    if args.filter != "lowpass":
        for flag, value in (
            ("--periods", args.periods),
            ("--excitation-period", args.period),
            ("--edge", args.edge),
            ("--no-decimate", args.no_decimate or None),
        ):
            if value is not None:
                raise ValueError(f"{flag} needs --filter lowpass (got --filter {args.filter})")


def cmd_identify(args: argparse.Namespace) -> int:
    from ..identification import identify, true_base_values, validate
    from ..identification.data import read_truth
    from ..identification.report import format_table, write_report

    if args.validate_currents and not args.validate:
        raise ValueError("--validate-currents: expected --validate with the logs they belong to")
    robot = with_drive_side(load(args.robot, tip=args.tip), args)
    if (args.urdf or args.yaml or args.mjcf or args.sidecar) and not args.consistent:
        given = "urdf" if args.urdf else "yaml" if args.yaml else "mjcf" if args.mjcf else "sidecar"
        raise ValueError(
            f"--{given}: expected "
            "--consistent as well (only a physically consistent estimate can be written as a robot "
            "description)"
        )
    if (args.urdf or args.yaml or args.mjcf) and args.friction_model not in (
        None,
        "coulomb",
        "auto",
    ):
        given = "urdf" if args.urdf else "yaml" if args.yaml else "mjcf"
        raise ValueError(
            f"--{given}: a robot description holds viscous and Coulomb friction only, not the "
            f"{args.friction_model} friction model"
        )
    if args.sidecar and not (args.urdf or args.yaml):
        raise ValueError("--sidecar: expected --urdf or --yaml (the description it goes with)")
    if args.urdf or args.yaml or args.mjcf:
        check_description_kind(robot, args.robot, args.urdf is not None, args.mjcf)
    _check_lowpass_options(args)
    files = list(args.data)
    vfiles = list(args.validate or [])
    cur = _paired(files, args.currents, "--currents", "the identification data")
    vcur = _paired(vfiles, args.validate_currents, "--validate-currents", "--validate")
    # a log simulated for another robot (its truth sidecar says so) is refused before any work
    truth_docs = [read_truth(f, robot) for f in files]
    for f in vfiles:
        read_truth(f, robot)
    # A file cut at breaks in its time stamps gives several logs (segments), fitted together.
    parts = [_read_filtered(f, robot, args, c, periodic=True) for f, c in zip(files, cur)]
    logs = [d for ds in parts for d in ds]
    labels = [d.source if len(ds) > 1 else f for f, ds in zip(files, parts) for d in ds]
    pres = [d.processing.get("preprocess") for d in logs]
    # Validation logs are filtered at the fit's cut-off (the highest of the fit logs').
    vcut = max(p["filter"]["cutoff_Hz"] for p in pres) if all(pres) else None
    vparts = [_read_filtered(f, robot, args, c, cutoff=vcut) for f, c in zip(vfiles, vcur)]
    vlogs = [d for ds in vparts for d in ds]
    vlabels = [d.source if len(ds) > 1 else f for f, ds in zip(vfiles, vparts) for d in ds]
    fit_options = dict(
        model=args.model,
        weighted=not args.ols,
        rsd_threshold=args.rsd_threshold,
        energy_window=args.energy_window,
        integration=args.integration,
        integral_window=args.integral_window,
        min_velocity=args.min_velocity,
    )
    friction = None
    if args.friction_model is not None or args.friction_width is not None:
        from ..identification.friction import select_friction_model

        if args.friction_model is None:
            raise ValueError("--friction-width: expected --friction-model smooth or auto")
        width = None
        if args.friction_width is not None:
            width = joint_values(args.friction_width, robot.n, "--friction-width", broadcast=True)
            if not all(math.isfinite(w) and w > 0 for w in width):
                raise ValueError("--friction-width: every width must be a positive number")
        args.friction = True
        friction = select_friction_model(
            robot,
            logs,
            args.friction_model,
            rotor=args.rotor,
            offset=args.offset,
            width=width,
            fit=fit_options,
            progress=_progress(),
        )
        robot, base = friction.robot, friction.base
    else:
        base = base_parameters(robot, rotor=args.rotor, friction=args.friction, offset=args.offset)
    try:
        res = identify(robot, logs, base=base, **fit_options)
    except np.linalg.LinAlgError as e:
        raise ValueError(
            f"{args.model} model on {' + '.join(files)}: the least-squares problem of the base "
            f"regressor of this data is singular ({e}); the data do not determine the {base.n} "
            "base parameters: use a longer or richer log, or fewer parameters"
        ) from None
    cons = None
    if args.consistent:
        from ..identification.consistent import consistent_estimate

        weight = "auto" if args.prior_weight is None else args.prior_weight
        cons = consistent_estimate(res, weight, data=logs, progress=_progress())
    elif args.prior_weight is not None:
        raise ValueError("--prior-weight: expected --consistent as well")
    truth_doc = truth_docs[0] if all(d == truth_docs[0] for d in truth_docs) else None

    truth_side = None
    if truth_doc and (args.rotor or args.friction):
        sim = truth_doc.get("simulation")
        side = sim.get("drive_side", "joint") if isinstance(sim, dict) else "joint"
        if side != robot.drive_side:  # its Ia/Fv/Fc are another side's: nothing to compare
            truth_doc, truth_side = None, side
    truth = true_base_values(base, truth_doc) if truth_doc else None
    fit = validate(res, logs)
    val = validate(res, vlogs) if vlogs else None

    data = logs[0]
    proc = data.processing
    extras = joint_terms(args, robot)
    head = (
        f"{robot.name}: {res.model} model, {base.n} base parameters"
        + (f" ({', '.join(extras)})" if extras else "")
        + ", "
    )
    if len(logs) == 1:
        out = [head + f"{data.m} samples at {data.rate:.4g} Hz from {files[0]}"]
    else:
        out = [head + f"{sum(d.m for d in logs)} samples from {len(logs)} logs fitted together:"]
        k = 0
        for f, ds in zip(files, parts):  # a file cut at breaks: one line for its segments
            infos = res.settings["logs"][k : k + len(ds)]
            k += len(ds)
            eq = sum(i["equations"] for i in infos)
            if len(ds) == 1:
                out.append(f"    {f}: {ds[0].m} samples at {ds[0].rate:.4g} Hz, {eq} equations")
            else:
                out.append(f"    {f}: {_segments_line(ds)}, {sum(d.m for d in ds)} samples, {eq} "
                           "equations")  # fmt: skip
    if all(pres):
        k = 0
        for f, ds in zip(files, parts):
            p = pres[k]
            k += len(ds)
            if len(logs) > 1:
                out.append(
                    f"  {f} (on its own):"
                    if len(ds) == 1
                    else f"  {f} (each segment on its own; the first shown, every one in the "
                    "JSON's data.logs"
                    + _cutoff_range([d.processing["preprocess"] for d in ds])
                    + "):"
                )
            indent = "  " if len(logs) > 1 else ""
            out += [indent + line for line in _describe_preprocess(p, res.model)]
    else:
        out.append(
            f"  velocities: {_describe(proc.get('velocity', {}))}; accelerations: "
            f"{_describe(proc.get('acceleration', {}))}"
            + ("" if res.model == "dynamic" else f" (not used by the {res.model} model)")
            + (" (each log on its own)" if len(logs) > 1 else "")
        )
    out += [
        f"  {res.rows} equations, {res.settings.get('weighting')}; condition number of the "
        f"column-scaled regressor {res.cond:.3g}",
    ]
    if res.model == "energy":
        out.append(
            f"  energy windows of {res.settings['energy_window']} sample interval(s), "
            f"{res.settings['integration']} integration"
        )
    elif res.model == "integral":
        out.append(
            f"  integral windows of {res.settings['integral_window']} sample interval(s), "
            f"{res.settings['integration']} integration"
        )
    elif res.settings.get("equations_left_out"):
        out.append(
            f"  {res.settings['equations_left_out']} joint equations below "
            f"{res.settings['min_velocity']:g} rad/s left out (Coulomb sign undetermined)"
        )
    elif base.friction:
        out.append(
            f"  no joint equation below {res.settings['min_velocity']:g} rad/s left out"
            if res.settings["min_velocity"] > 0
            else "  all joint equations kept (--min-velocity 0)"
        )
    if "torque" in proc and proc["torque"]["unit"] != "N m":
        what = "permille" if proc["torque"]["unit"].startswith("permille") else "motor currents"
        out.append(
            f"  torques converted from {what}: "
            + ("gain " if what != "permille" else "scale ")
            + " ".join(f"{s:.4g}" for s in proc["torque"]["scale_Nm_per_unit"])
            + " N m per "
            + ("A" if what != "permille" else "unit")
            + (
                f" ({proc['torque']['formula'].split('(')[-1].rstrip(')')})"
                if what != "permille"
                else ""
            )
        )
    kept = len(res.names)
    out.append(
        f"  {kept} of {base.n} parameters kept"
        + (
            f" after removing {len(res.removed)} with RSD > {args.rsd_threshold:g} %"
            if res.removed
            else ""
        )
        + (
            " (true values from " + str(Path(files[0]).with_suffix("")) + ".truth.json)"
            if truth is not None
            else ""
        )
    )
    if truth_side:
        out.append(
            f"  note: the log was simulated with rotor inertia and friction on the {truth_side}s, "
            f"this fit has them on the {robot.drive_side}s: its true values are not compared"
        )
    if base.friction:
        from ..identification.friction import friction_lines

        out += friction_lines(robot, record=friction.record if friction else None)
    for w in res.settings.get("warnings", []):
        out.append(f"  WARNING: {w}")
    cfit = cval = None
    which = ""
    if cons is not None:
        cfit = validate(cons, logs)
        cval = validate(cons, vlogs) if vlogs else None
        out.append(_headline(cfit, cval, fit, val))
        which = ", unconstrained least-squares estimate"
    out.append("")
    if cons is not None:
        out.append("Unconstrained least-squares estimate (base parameters):")
    out.append(format_table(res, truth))
    out.append("")
    out.append(_rms_lines(f"identification data{which}", fit))
    if val is not None:
        out.append(_rms_lines(f"validation data ({', '.join(vfiles)}){which}", val))
    if cons is not None:
        out.append("")
        out += _consistent_lines(cons, fit, val, cfit, cval, logs)
        assert cfit is not None  # validated with cons
        out.append(_rms_lines("identification data, consistent estimate", cfit))
        if cval is not None:
            out.append(
                _rms_lines(f"validation data ({', '.join(vfiles)}), consistent estimate", cval)
            )
    print("\n".join(out))

    doc = res.to_dict()
    if base.friction:
        from ..identification.friction import friction_record

        doc["friction_model"] = friction_record(robot, record=friction.record if friction else None)
    doc["tip"] = args.tip  # the chain identified (None: the whole description)
    doc["consistent"] = cons is not None
    if cons is not None:
        doc.update(_plain(cons.to_dict()))
        assert cfit is not None  # validated with cons
        ce = doc["consistent_estimate"]
        ce["fit"] = {"estimate": "consistent", **_measures_doc(cfit, labels)}
        if cval is not None:
            ce["validation"] = {
                "estimate": "consistent",
                "file": ", ".join(vfiles),
                **_measures_doc(cval, vlabels),
            }
        ce["mass_matrix_min_eig"] = cons.mass_matrix_min_eig(logs)
    # how a log is read for this model: what 'mindyn predict' does with another log
    doc["reading"] = {
        "filter": args.filter,
        "cutoff_Hz": vcut if args.filter == "lowpass" else args.cutoff,
        "edge_s": args.edge,
        "torque_unit": args.torque_unit,
        "drive_gain": args.drive_gain,
        "topic": args.topic,
    }
    doc["data"] = {
        "file": files[0] if len(files) == 1 else None,
        "files": files,
        "samples": sum(int(d.processing.get("samples", d.m)) for d in logs),  # as logged
        "samples_used": sum(d.m for d in logs),  # after resampling, edges and decimation
        "processing": _plain(proc),
        "logs": [
            {
                "file": f,
                "samples": int(d.processing.get("samples", d.m)),
                "samples_used": d.m,
                "processing": _plain(d.processing),
            }
            for f, d in zip(labels, logs)
        ],
    }
    doc["data"]["segments"] = [
        {"file": f, **_segments(ds)} for f, ds in zip(files + vfiles, parts + vparts) if len(ds) > 1
    ]
    doc["fit"] = _measures_doc(fit, labels)
    if val is not None:
        doc["validation"] = {"file": ", ".join(vfiles), **_measures_doc(val, vlabels)}
    if cons is not None:  # which estimate each set of figures is
        for key in ("fit", "validation"):
            if key in doc:
                doc[key] = {"estimate": "unconstrained least squares", **doc[key]}
    if truth is not None:
        doc["true_values"] = [float(v) for v in truth]
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(doc, indent=2) + "\n")
        print(f"wrote {args.json}")
    if args.urdf or args.yaml or args.mjcf:
        write_description(
            robot,
            doc["classical"],
            "the consistent estimate",
            args.robot,
            args.urdf,
            args.yaml,
            args.sidecar,
            mjcf=args.mjcf,
        )
    if args.report:
        from ..identification.excitation import excitation_limits

        lim, _ = excitation_limits(robot, margin=0.0)
        if cons is None:
            paths = write_report(args.report, res, logs, vlogs, val, fit, lim)
        else:  # the headline estimate, named in each plot's title
            paths = write_report(
                args.report, cons, logs, vlogs, cval, cfit, lim, estimate="consistent"
            )
        (Path(args.report) / "identification.json").write_text(json.dumps(doc, indent=2) + "\n")
        (Path(args.report) / "table.txt").write_text("\n".join(out) + "\n")
        print(f"wrote report to {Path(args.report)}/: " + ", ".join(p.name for p in paths))
    return 0


def cmd_identify_payload(args: argparse.Namespace) -> int:
    from ..identification.consistent import arm_tip, identify_payload, read_arm
    from ..identification.data import read_truth

    tip = arm_tip(args.identification, args.robot)
    if args.tip is not None and tip is not None and args.tip != tip:
        raise ValueError(
            f"--tip {args.tip}: {args.identification} was identified on the chain ending at "
            f"--tip {tip}; the payload sits on that chain's last link"
        )
    robot = load(args.robot, tip=args.tip or tip)
    read_arm(robot, args.identification)  # its errors before reading the logs
    args.model = "dynamic"
    _check_lowpass_options(args)
    files = list(args.data)
    for f in files:
        read_truth(f, robot)
    cur = _paired(files, args.currents, "--currents", "the payload data")
    logs = [d for f, c in zip(files, cur) for d in _read_filtered(f, robot, args, c, periodic=True)]
    res = identify_payload(
        robot,
        args.identification,
        logs,
        consistent=not args.no_consistent,
        min_velocity=args.min_velocity,
    )
    d = res.derived()
    out = [
        f"{robot.name}: payload on the last link ({robot.link_names[-1]}"
        + (f", chain to --tip {tip} as identified" if tip and not args.tip else "")
        + ") from "
        f"{', '.join(files)}: {res.rows} equations, regressor rank {res.rank} of 10, condition "
        f"number {res.cond:.3g}; arm torques from the {res.arm_values} of {args.identification}",
        "  parameters about the last link frame's origin, in its frame (least squares):",
    ]
    for nm, v, sd in zip(res.names, res.values, res.std):
        out.append(f"    {nm:<6} {v:12.5g} +- {sd:.3g}")
    out.append(
        f"  mass {d['mass']:.5g} +- {d['mass_std']:.3g} kg; centre of mass "
        + " ".join(f"{c:.4g}" for c in d["com"])
        + " +- "
        + " ".join(f"{c:.2g}" for c in d["com_std"])
        + " m"
    )
    out.append(
        "  inertia about the centre of mass XX XY XZ YY YZ ZZ: "
        + " ".join(f"{c:.4g}" for c in d["inertia_com"])
        + " +- "
        + " ".join(f"{c:.2g}" for c in d["inertia_com_std"])
        + " kg m^2"
    )
    out.append(
        f"  smallest pseudo-inertia eigenvalue {res.min_eig:.4g} kg"
        + ("" if res.min_eig >= 0 else " (physically inconsistent)")
    )
    if res.consistent is not None:
        c = res.derived(True)
        out.append(
            f"  consistent ({res.solver}, {res.status}): mass {c['mass']:.5g} kg, centre of "
            "mass "
            + " ".join(f"{x:.4g}" for x in c["com"])
            + " m, inertia about it "
            + " ".join(f"{x:.4g}" for x in c["inertia_com"])
            + f" kg m^2, smallest pseudo-inertia eigenvalue {res.consistent_min_eig:.3g} kg"
        )
    print("\n".join(out))
    if args.json:
        doc = _plain({"robot": robot.name, "files": files, **res.to_dict()})
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(doc, indent=2) + "\n")
        print(f"wrote {args.json}")
    return 0


def cmd_predict(args: argparse.Namespace) -> int:
    from ..identification.data import read_json
    from ..identification.prediction import identified_model, predict

    doc = read_json(args.identification)
    if not isinstance(doc, dict):
        raise ValueError(f"{args.identification}: not the JSON of 'mindyn identify'")
    robot = load(args.robot, tip=args.tip if args.tip is not None else doc.get("tip"))
    estimate = "consistent" if args.consistent else "unconstrained"
    identified_model(args.identification, robot, estimate=estimate)  # errors before reading
    recorded = doc.get("reading")
    if recorded is None and args.filter is None:
        raise ValueError(
            f"{args.identification}: does not record how identify read its logs; give --filter "
            "(and --cutoff) as identify had them"
        )
    reading = dict(recorded or {})
    if args.filter is not None and args.filter != reading.get("filter"):
        reading["cutoff_Hz"] = None  # the recorded cut-off belongs to the recorded filter
    stated = []
    for key, flag in (("filter", "filter"), ("cutoff_Hz", "cutoff")):
        given = getattr(args, flag)
        if given is not None:
            stated.append(f"--{flag} {given:g}" if key == "cutoff_Hz" else f"--{flag} {given}")
            reading[key] = given
    ns = argparse.Namespace(
        filter=reading.get("filter", "lowpass"),
        cutoff=reading.get("cutoff_Hz"),
        edge=reading.get("edge_s"),
        torque_unit=args.torque_unit or reading.get("torque_unit"),
        drive_gain=args.drive_gain or reading.get("drive_gain"),
        topic=args.topic or reading.get("topic"),
        periods=None,
        period=None,
        no_decimate=True,
        model="dynamic",
        _torque_optional=True,
    )
    logs = _read_filtered(args.log, robot, ns)
    pred = predict(args.identification, logs, robot=robot, estimate=estimate)
    path = pred.write_csv(args.output)
    how = (
        f"low-pass at {ns.cutoff:.4g} Hz (zero-phase Butterworth order 4), the model on the "
        "filtered motion at the logged time stamps between the filter edges"
        if ns.filter == "lowpass"
        else f"--filter {ns.filter}"
        + (f" at {ns.cutoff:g} Hz" if ns.cutoff is not None else "")
        + ", the model on the samples as read"
    )
    print(
        f"{robot.name}: {estimate} estimate of {args.identification} ({len(pred.values)} base "
        f"parameters) on {args.log}: {pred.t.size} samples"
        + (f" from {len(logs)} segments (cut at breaks)" if len(logs) > 1 else "")
    )
    print(
        f"  log read as for the identification ({'as recorded in the JSON' if recorded else ''}"
        + ("; " if recorded and stated else "")
        + (("given: " + ", ".join(stated)) if stated else "")
        + f"): {how}"
    )
    cols = "t, q, dq, ddq (the motion evaluated), tau_hat" + (
        ", tau (as logged, N m)" if pred.tau is not None else ""
    )
    print(f"  wrote {path} ({cols})")
    return 0


def _progress():
    """Progress lines on stderr when it is a terminal (``identify --consistent`` solves for
    seconds); None otherwise, so that a log or a pipe gets the result and errors only."""
    if not sys.stderr.isatty():
        return None
    return lambda line: print(f"identify: {line}", file=sys.stderr, flush=True)


def _headline(cfit, cval, fit, val) -> str:
    """The first figures of ``identify --consistent``: the consistent estimate's own errors."""
    return (
        "  Headline, the physically consistent estimate: overall relative error "
        f"{_pct(cfit['overall_relative']).strip()} on the identification data"
        + (f", {_pct(cval['overall_relative']).strip()} on the validation data" if cval else "")
        + f" (unconstrained least-squares estimate: {_pct(fit['overall_relative']).strip()}"
        + (f", {_pct(val['overall_relative']).strip()}" if val else "")
        + "); each table below names its estimate"
    )


def _weight_lines(cons) -> list[str]:
    """How the prior's weight was chosen, and per link whether the data or the prior hold it."""
    ch = cons.weight_choice
    lines = []
    if ch is not None:
        lines.append(
            f"  prior weight {ch['chosen']:g} chosen by {ch['rule']}; held-out residual per "
            f"equation [{ch['held_out_unit']}] at each candidate weight (smallest at "
            f"{ch['smallest_at']:g}, standard error {ch['held_out_standard_error']:.3g}):"
        )
        lines.append(
            "    "
            + "  ".join(
                f"{w:g}: {e:.5g}" + (" (chosen)" if w == ch["chosen"] else "")
                for w, e in zip(ch["candidates"], ch["held_out_residual"])
            )
        )
        if ch["newton_not_converged"]:
            lines.append(
                f"    {ch['newton_not_converged']} of the held-out fits stopped before the Newton "
                "descent converged (their residuals are approximate)"
            )
        if ch["at_grid_end"]:
            lines.append(
                "    the chosen weight is at the end of the candidates: the optimum may lie "
                "beyond (give --prior-weight to go further)"
            )
    elif cons.prior_weight:
        lines.append(f"  prior weight {cons.prior_weight:g} (given)")
    if cons.links:
        from ..identification.prior import MASS_EVIDENCE

        lines.append(
            "  per link: mass [kg] (posterior standard deviation), description's mass [kg], fit "
            "worse with the mass held at the description's [noise variances], the mass "
            "determined by (with the data's standard deviation); identifiable directions of "
            "the link's parameters determined by the data, the link's parameters determined by:"
        )
        for lk in cons.links:
            sd = lk["mass_data_std"]
            lines.append(
                f"  {lk['link']:<24} {lk['mass']:10.4g} ({lk['mass_std']:.3g}) "
                f"{lk['description_mass']:10.4g} {lk['mass_fit_increase']:10.4g} "
                f"{lk['mass_verdict']:<5}"
                + (f" ({sd:.3g})" if lk["mass_verdict"] == "data" else " " * 8)
                + f" {lk['directions_by_data']:3d} of {lk['identifiable_directions']:<3d} "
                f"{lk['verdict']}"
                + ("" if lk["mass_profile_converged"] else " (mass profile not converged)")
            )
        lines.append(
            f"  (mass by data: held at the description's, the fit is worse by at least "
            f"{MASS_EVIDENCE:g} noise variances, the data's standard deviation |m - m0| / "
            "sqrt(worse); else by the priors; unknown: that fit did not converge; identifiable: "
            "the combinations of the link's own parameters that the torques determine, by the "
            "data when the priors' share of their variance, -d ln(variance) / d ln(weight), is "
            "below 0.5; data: their mean share "
            "below 0.5; partly: above, but some of them below; prior: none)"
        )
    return lines


def _consistent_lines(cons, fit, val, cfit, cval, logs) -> list[str]:
    """The lines of ``mindyn identify --consistent``: pseudo-inertias, errors side by side."""
    un = cons.violating_links(True)
    lines = [
        f"Physically consistent estimate ({cons.solver}, {cons.status}, {cons.seconds:.3g} s"
        + (f", prior weight {cons.prior_weight:g}" if cons.prior_weight else ", no prior")
        + f"): total mass {cons.total_mass:.4g} kg; fit {cons.fit_increase:.4g} noise variances "
        "worse than the unconstrained fit with all base parameters",
        *_weight_lines(cons),
        "  smallest pseudo-inertia eigenvalue per link [kg] (unconstrained: its realisation "
        "nearest the description):",
        f"  {'link':<24} {'unconstrained':>14} {'consistent':>14}",
    ]
    for nm, a, b in zip(cons.link_names, cons.unconstrained_min_eig, cons.min_eig):
        lines.append(f"  {nm:<24} {a:14.4g} {b:14.4g}" + ("  violated" if nm in un else ""))
    lines.append(
        "  unconstrained estimate violates physical consistency at: " + ", ".join(un)
        if un
        else "  unconstrained estimate: a consistent realisation nearest the description"
    )
    lines.append(f"  {'overall relative error':<24} {'unconstrained':>14} {'consistent':>14}")
    lines.append(
        f"  {'identification data':<24} {_pct(fit['overall_relative']):>14} "
        f"{_pct(cfit['overall_relative']):>14}"
    )
    if cval is not None:
        lines.append(
            f"  {'validation data':<24} {_pct(val['overall_relative']):>14} "
            f"{_pct(cval['overall_relative']):>14}"
        )
    for what, un_m, co_m in (("identification", fit, cfit), ("validation", val, cval)):
        for kind in ("raw", "moving"):
            if co_m is not None and co_m.get(kind) is not None:
                lines.append(
                    f"  {what + ', ' + kind:<24} {_pct(un_m[kind]['overall_relative']):>14} "
                    f"{_pct(co_m[kind]['overall_relative']):>14}"
                )
    low = cons.mass_matrix_min_eig(logs)
    lines.append(
        f"  mass matrix of the consistent model: smallest eigenvalue over the data {low:.4g} "
        + ("(positive definite at every sample)" if low > 0 else "(NOT positive definite)")
    )
    for note in cons.notes:
        lines.append(f"  note: {note}")
    return lines


def _measures_doc(v: dict, files: list) -> dict:
    """The error measures of :func:`~mindyn.identification.validate` for the JSON: fractions
    (relative, NRMS) and N m (RMS), over all logs stacked and per log."""

    def base(m):
        return {
            "overall_relative": _nan_list([m["overall_relative"]])[0],
            "rms": _nan_list(m["rms"]),
            "relative": _nan_list(m["relative"]),
            "nrms": _nan_list(m["nrms"]),
            "nrms_missing_limit": m["nrms_missing"],
        }

    def one(m):
        out = base(m)
        raw, mov = m.get("raw"), m.get("moving")
        out["raw"] = None if raw is None else {**base(raw), "samples": raw["samples"]}
        if raw is not None:
            out["raw"]["against"] = raw["against"]
        out["moving"] = (
            None
            if mov is None
            else {
                **base(mov),
                "samples": mov["samples"],
                "threshold": _nan_list(mov["threshold"]),
                "rule": mov["rule"],
                "fraction": _nan_list(mov["fraction"]),
            }
        )
        return out

    out = one(v)
    out["samples"] = v["samples"]
    out["logs"] = [{"file": f, "samples": m["samples"], **one(m)} for f, m in zip(files, v["logs"])]
    return out


def _segments(ds) -> dict:
    """A log cut at its breaks: segment count, shortest and longest [s], each one's span."""
    spans = [d.processing["segment"]["t_s"] for d in ds]
    length = [b - a for a, b in spans]
    return {
        "count": len(ds),
        "shortest_s": min(length),
        "longest_s": max(length),
        "spans_s": spans,
    }


def _segments_line(ds) -> str:
    """One line for a log cut at its breaks (the segments themselves are in the JSON)."""
    s = _segments(ds)
    return (
        f"cut at {s['count'] - 1} break(s) in its time stamps into {s['count']} segments "
        f"(shortest {s['shortest_s']:.4g} s, longest {s['longest_s']:.4g} s)"
    )


def _cutoff_range(pres) -> str:
    cut = [p["filter"]["cutoff_Hz"] for p in pres]
    return "" if max(cut) == min(cut) else f"; cut-offs {min(cut):.4g} to {max(cut):.4g} Hz"


def _describe_preprocess(pre: dict, model: str) -> list[str]:
    """The lines of ``mindyn identify`` that say what the data path did."""
    tm, flt = pre["timing"], pre["filter"]
    lines = [
        f"  time stamps: median interval {1e3 * tm['median_dt_s']:.4g} ms "
        f"({1e3 * tm['min_dt_s']:.4g} to {1e3 * tm['max_dt_s']:.4g} ms, jitter "
        f"{100 * tm['jitter']:.3g} % of the median, {tm['gaps']} gap(s) over 1.5 intervals); "
        + pre["time_base"],
    ]
    avg = pre.get("averaging")
    if avg:
        spread = avg.get("torque_spread_rms")
        lines.append(
            f"  {avg['periods']} period(s) of {avg['period_s']:.6g} s averaged "
            f"({avg['samples_per_period']} samples per period"
            + (
                "; torque spread about the mean per joint " + " ".join(f"{v:.3g}" for v in spread)
                if spread
                else ""
            )
            + ")"
        )
    lines.append(
        f"  low-pass: Butterworth order {flt['order']}, zero-phase, cut-off {flt['cutoff_Hz']:.4g} "
        f"Hz ({pre['cutoff_source']}; excited band {pre['excited_band_Hz']:.4g} Hz), applied to "
        f"{flt['applied_to']}"
        + (" and the regressor columns (parallel filtering)" if pre["parallel_filtering"] else "")
    )
    lines.append(
        f"  velocities: {pre['velocity']}; accelerations: {pre['acceleration']}"
        + ("" if model == "dynamic" else f" (not used by the {model} model)")
    )
    lines.append(
        f"  {pre['edge_samples_dropped']} samples of filter edges dropped ({pre['edge_s']:.4g} s "
        f"at each end); decimated by {pre['decimation']} to {pre['rate_Hz']:.4g} Hz, "
        f"{pre['samples']} samples"
    )
    return lines


def _describe(info: dict) -> str:
    if not info or info.get("source") == "logged":
        return "logged"
    if info.get("filter", "").startswith("butter"):
        return (
            f"from {info['source'].split()[-1]}, Butterworth order {info['order']} at "
            f"{info['cutoff_Hz']:g} Hz zero-phase + central differences"
        )
    if info.get("filter") == "savitzky-golay":
        return (
            f"from {info['source'].split()[-1]}, Savitzky-Golay order {info['polyorder']} over "
            f"{info['window_samples']} samples"
        )
    return f"from {info['source'].split()[-1]}, central differences (no filter)"


def _pct(x) -> str:
    return f"{100 * x:8.2f}%" if math.isfinite(x) else f"{'-':>9}"


def _rms_lines(label: str, v: dict) -> str:
    """The error measures of :func:`~mindyn.identification.validate` as terminal lines."""
    n = len(v["rms"])
    lines = [
        f"RMS torque error on {label}:",
        "  joint     " + " ".join(f"{k + 1:>9}" for k in range(n)),
        "  per joint " + " ".join(f"{x:9.4g}" for x in v["rms"]) + "  [N m | N]",
        "  relative  " + " ".join(_pct(x) for x in v["relative"]),
        "  NRMS      "
        + " ".join(_pct(x) for x in v["nrms"])
        + "  (RMS / effort limit"
        + (
            f"; no effort limit for joint(s) {', '.join(map(str, v['nrms_missing']))})"
            if v["nrms_missing"]
            else ")"
        ),
        f"  overall relative error |tau - tau_hat| / |tau|, all joints stacked: "
        f"{_pct(v['overall_relative']).strip()}",
    ]
    lines += _three_measures(v)
    if len(v["logs"]) > 1:
        groups: dict = {}  # the segments of a file cut at its breaks: one line
        for m in v["logs"]:
            seg = re.fullmatch(r"(.*) \[\S+ s to \S+ s\]", m["source"] or "")
            groups.setdefault(seg.group(1) if seg else m["source"], []).append(m)
        for name, ms in groups.items():
            if len(ms) == 1:
                lines.append(
                    f"  {ms[0]['source']}: overall {_pct(ms[0]['overall_relative']).strip()}, RMS "
                    + " ".join(f"{x:.4g}" for x in ms[0]["rms"])
                )
            else:
                e = [m["overall_relative"] for m in ms]
                lines.append(
                    f"  {name}, {len(ms)} segments: overall {_pct(min(e)).strip()} to "
                    f"{_pct(max(e)).strip()} (each in the JSON)"
                )
    return "\n".join(lines)


def _three_measures(v: dict) -> list[str]:
    """The three measures of :func:`~mindyn.identification.validate`, named, side by side:
    overall relative error and per-joint RMS against the torques the fit saw, against the
    torques as logged, and on the moving samples only."""
    raw, mov = v.get("raw"), v.get("moving")
    rows = [("filtered (the torques the fit saw)", v)]
    if raw is None:
        return ["  (the torques as logged are not known for this data: no raw or moving measure)"]
    assert mov is not None  # measured with raw
    rows += [("raw (the torques as logged)", raw), ("moving (raw, moving samples)", mov)]
    lines = [
        f"  {'measure':<34} {'overall':>9}  {'samples':>8}  RMS per joint [N m | N]",
    ]
    for name, m in rows:
        lines.append(
            f"  {name:<34} {_pct(m['overall_relative'])}  {m['samples']:>8}  "
            + " ".join(f"{x:.4g}" for x in m["rms"])
        )
    lines.append(
        f"  raw: {raw['against']}; moving: {mov['rule']}; threshold per joint "
        + " ".join(f"{x:.3g}" for x in mov["threshold"])
        + " [rad/s | m/s], samples counted "
        + " ".join(f"{100 * x:.0f}%" for x in mov["fraction"])
    )
    return lines


def _nan_list(a):
    return [float(x) if math.isfinite(x) else None for x in a]


def _plain(d):
    if isinstance(d, dict):
        return {k: _plain(v) for k, v in d.items()}
    if isinstance(d, (list, tuple)):
        return [_plain(v) for v in d]
    if isinstance(d, (np.floating, float)):
        return float(d) if math.isfinite(d) else None
    if isinstance(d, np.integer):
        return int(d)
    return d


def _add_data_options(p) -> None:
    """The options of ``identify`` that say how a log is read and preprocessed (shared with
    ``identify-payload``)."""
    p.add_argument("--topic", help="ROS bag: the JointState topic (when there are several)")
    p.add_argument(
        "--torque-unit",
        choices=["Nm", "permille", "current"],
        help="logged torque unit; permille: value x rated torque x gear ratio / 1000; current: "
        "motor current [A] x drive gain (--drive-gain, else torque_constant x gear_ratio of the "
        "drive table) (default: the unit the CSV header gives, as in tau1[permille], or current "
        "for columns i1..in, else Nm)",
    )
    joint_vector(
        p,
        "--drive-gain",
        metavar="K",
        help="joint-side drive gains [N m/A] that turn motor currents into joint torques (or "
        "one value for all joints); default: the robot's drive table. When the description "
        "declares transmissions: motor torque constants K_t [N m/A, motor side], torques = "
        "T^T (K_t x current) (default: the transmissions' torque constants)",
    )
    p.add_argument(
        "--currents",
        nargs="+",
        metavar="CSV",
        help="motor currents from separate files (t, i1..in, other columns ignored), one per "
        "LOG in the same order, joined on the time stamps (each sample of the log needs a "
        "current sample within 1/1000 of its sample period); torques = currents x drive gains, "
        "torque columns of the log are ignored",
    )
    p.add_argument(
        "--filter",
        choices=["lowpass", "butter", "savgol", "none"],
        default="lowpass",
        help="lowpass (default): the identification data path: uniform resampling of jittered "
        "time stamps, one zero-phase Butterworth low-pass of positions, logged velocities, "
        "torques and regressor columns, derivatives of the filtered signals, filter edges "
        "dropped, decimation; butter, savgol, none: only derive missing velocities and "
        "accelerations (torques unfiltered; butter and savgol refuse unevenly spaced time "
        "stamps, none differences them as they are)",
    )
    number(
        p,
        "--cutoff",
        low=0,
        low_open=True,
        help="cut-off [Hz], below half the log's rate; lowpass: default 10 x the excited band of "
        "the identification log's positions (at most rate / 10), the validation log filtered at "
        "the same cut-off; butter: default min(10, rate / 10)",
    )
    g = p.add_mutually_exclusive_group()
    number(
        g,
        "--periods",
        low=1,
        high=100000,
        integer=True,
        help="lowpass: the identification log holds this many periods of a periodic excitation; "
        "they are averaged sample by sample",
    )
    period = number(
        g,
        "--excitation-period",
        dest="period",
        low=0,
        low_open=True,
        help="lowpass: period [s] of a periodic excitation; the whole periods the "
        "identification log holds are averaged",
    )
    deprecated(g, "--period", period)
    number(
        p,
        "--edge",
        low=0,
        help="lowpass: seconds dropped at each end after filtering (default 2 / cut-off; none "
        "for an averaged period)",
    )
    p.add_argument(
        "--no-decimate",
        action="store_true",
        help="lowpass: keep every sample (default for the dynamic model: decimate to at least "
        "10 x the cut-off; the integral and energy models keep every sample)",
    )


# ---------------------------------------------------------------------------------------------
def register(sub) -> None:
    """Adds ``excite``, ``simulate``, ``identify``, ``identify-payload`` and ``predict`` to the
    ``mindyn`` subcommands."""
    from ..control.simulation import MAX_SAMPLES, MAX_STEPS
    from ..identification.consistent import MAX_PRIOR_WEIGHT
    from ..identification.excitation import MAX_TRAJECTORY_ROWS
    from ..identification.prior import CANDIDATES, FOLDS
    from .control import add_closed_loop_args

    p = add_command(
        sub,
        "excite",
        description="Finite Fourier series per joint, zero velocity and acceleration at start and "
        "end, optimised (SLSQP, several random starts) for a conditioning criterion of the "
        "stacked base regressor under the robot's position, velocity and acceleration limits. "
        "Writes the sampled trajectory (CSV), the coefficients (JSON, same name) and a plot (PNG).",
    )
    add_robot(p)
    number(
        p,
        "--harmonics",
        low=2,
        high=30,
        integer=True,
        default=5,
        help="harmonics N (the limits are imposed on max(100, 20 N) points per period, each "
        "a constraint of the optimisation)",
    )
    number(p, "--freq", low=0, high=1000, low_open=True, default=0.1, help="base frequency [Hz]")
    p.add_argument(
        "--criterion",
        choices=["cond", "logdet", "hadamard"],
        default="cond",
        help="condition number (default), D-optimality, or the Hadamard-bound ratio of "
        + ZCR07S_STUDY,
    )
    number(p, "--starts", low=1, high=100, integer=True, default=3, help="random starting guesses")
    seed(p, "--seed")
    number(
        p,
        "--maxiter",
        low=1,
        high=10000,
        integer=True,
        default=100,
        help="SLSQP iterations per start (the work is about --starts x --maxiter iterations)",
    )
    number(
        p,
        "--samples",
        low=1,
        high=10000,
        integer=True,
        default=100,
        help="regressor samples per period (more than 2 N: the highest harmonic is sampled)",
    )
    number(
        p,
        "--margin",
        low=0,
        high=0.5,
        high_open=True,
        default=0.05,
        help="fraction the limits are tightened by",
    )
    p.add_argument("--rotor", action="store_true", help="base parameters with rotor inertia")
    p.add_argument("--friction", action="store_true", help="base parameters with friction")
    add_drive_side(p)
    joint_vector(
        p, "--start", help="prescribed start position [rad, m] (or one value for all joints)"
    )
    deg = p.add_argument(
        "--deg",
        dest="degrees",
        action="store_true",
        help="the revolute joints of --start in degrees",
    )
    deprecated(p, "--degrees", deg)
    number(
        p,
        "--rate",
        low=0,
        high=1e6,
        low_open=True,
        default=250.0,
        help="CSV sample rate [Hz], above 2 N freq (the highest harmonic is sampled) and at most "
        f"{MAX_TRAJECTORY_ROWS:,} rows per period",
    )
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="CSV",
        type=output_file,
        help="trajectory CSV to write (and its .json and .png beside it)",
    )
    p.set_defaults(func=cmd_excite)

    p = add_command(
        sub,
        "simulate",
        description="Produces what a joint controller would log (t, q, dq, tau): the robot with "
        "its true parameters integrated (RK4) under a tracking controller, or torques from "
        "inverse dynamics along the reference (--mode inverse); optional sensor noise and "
        "encoder quantisation. Also writes <output>.truth.json with the true parameters. "
        "The controller and the reference are those of 'mindyn track' (default: computed torque "
        "with the true parameters and Coulomb friction on the reference velocity, K_P = 400, "
        "K_D = 40; a sum of sines within the limits when no --trajectory is given).",
    )
    add_robot(p)
    p.add_argument(
        "--mode",
        choices=["tracking", "inverse"],
        default="tracking",
        help="tracking: the robot integrated under the controller (default); inverse: torques "
        "from inverse dynamics along the reference, no controller",
    )
    add_closed_loop_args(p, "computed-torque")
    g = p.add_mutually_exclusive_group()
    number(
        g, "--rate", low=0, high=1e6, low_open=True, default=250.0, help="control and log rate [Hz]"
    )
    controller_period(g, low=1e-6, high=1e3, help="control and log period [s] (1 / rate)")
    number(
        p,
        "--duration",
        low=0,
        high=1e6,
        low_open=True,
        help=f"seconds (default: one period of the reference); at most {MAX_SAMPLES:,} samples "
        f"(duration x rate) and {MAX_STEPS:,} integration steps (x substeps)",
    )
    p.add_argument("--rotor", action="store_true", help="true robot with rotor inertia")
    p.add_argument("--friction", action="store_true", help="true robot with friction")
    add_drive_side(p)
    p.add_argument(
        "--torque-noise",
        metavar="SD",
        help="torque noise sd: one value, one per joint (comma-separated), or P%% of each "
        "joint's effort limit; in [0, 1e6] N m or [0, 100] %%",
    )
    p.add_argument(
        "--position-noise", metavar="SD", help="position noise sd (rad, m), each in [0, 1]"
    )
    p.add_argument(
        "--velocity-noise", metavar="SD", help="velocity noise sd (rad/s, m/s), each in [0, 100]"
    )
    p.add_argument("--quantization", metavar="STEP", help="encoder step (rad, m), each in [0, 1]")
    seed(p, "--seed", help="noise seed")
    p.add_argument(
        "--torque-unit",
        choices=["Nm", "permille"],
        default="Nm",
        help="write torques in N m or in permille of rated torque (drive table; the header "
        "then says tau1[permille]...)",
    )
    p.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="CSV",
        type=output_file,
        help="log to write (and its .truth.json beside it)",
    )
    p.set_defaults(func=cmd_simulate)

    p = add_command(
        sub,
        "identify",
        description="Least-squares identification of the base parameters from CSV logs "
        "(t, q1..qn, [dq1..dqn], tau1..taun) or ROS bags (sensor_msgs/JointState: position, "
        "[velocity], effort, joints matched by name), one or several fitted together, with "
        "statistics (RSD), pruning of parameters with large RSD, error measures (overall "
        "relative error, per-joint RMS, relative error and NRMS of the effort limit, scaled "
        "condition number) on the fit and on validation logs, against the filtered torques, "
        "against the torques as logged and on moving samples only, JSON output and a plot "
        "report.",
    )
    add_robot(p)
    p.add_argument(
        "data",
        nargs="+",
        metavar="LOG",
        help="CSV log (t, q1..qn, [dq1..dqn], [ddq1..ddqn], tau1..taun or currents i1..in) or "
        "ROS bag (a ROS 2 bag folder, .mcap, .db3, or a ROS 1 .bag); several logs are fitted "
        "together (derivatives taken on each log alone, regression systems stacked)",
    )
    p.add_argument(
        "--model",
        choices=["dynamic", "integral", "energy"],
        default="dynamic",
        help="dynamic: tau = W(q, dq, ddq) p per sample (needs accelerations); integral: each "
        "joint's equation of motion integrated over windows (momentum difference, no "
        "accelerations); energy: the energy theorem over windows (one equation per window)",
    )
    add_joint_terms(p, "identify")
    add_offset(p, "identify")
    p.add_argument(
        "--validate", nargs="+", metavar="LOG", help="log(s) (CSV or bag) for validation"
    )
    p.add_argument("--json", metavar="FILE", type=output_file, help="write the results as JSON")
    p.add_argument("--report", metavar="DIR", type=output_dir, help="write plots and tables to DIR")
    number(
        p,
        "--rsd-threshold",
        low=0,
        default=30.0,
        help="remove parameters with RSD above this % (0 keeps all)",
    )
    _add_data_options(p)
    p.add_argument(
        "--validate-currents",
        nargs="+",
        metavar="CSV",
        help="as --currents, one per --validate log",
    )
    p.add_argument("--ols", action="store_true", help="ordinary instead of weighted least squares")
    p.add_argument(
        "--consistent",
        action="store_true",
        help="also estimate physically consistent classical parameters (every link's "
        "pseudo-inertia positive semidefinite, rotor inertia and friction >= 0) minimising the "
        "same weighted residual plus the description's prior (convex: a Newton descent with "
        "the prior, cvxpy with Clarabel without; each solve reported on stderr when it is a "
        "terminal); the consistent estimate's errors are the headline; JSON: classical, "
        "pseudo_inertia_min_eig, total_mass, consistent_estimate",
    )
    number(
        p,
        "--prior-weight",
        low=0,
        high=MAX_PRIOR_WEIGHT,
        default=None,
        help="with --consistent: add W x the log-det divergence of each link's pseudo-inertia "
        "from the description's; the fit term is in units of the noise variance, so W = 1 makes "
        "a divergence of 1 cost as much as one standard deviation of the fit; 0: no prior; "
        f"default: chosen from the data by {FOLDS}-fold cross-validation over contiguous time "
        f"blocks among {', '.join(f'{w:g}' for w in CANDIDATES)}, the largest whose held-out "
        "residual is within one standard error of the smallest (reported)",
    )
    add_description_outputs(p, "identify")
    number(
        p,
        "--energy-window",
        low=1,
        high=1000000,
        integer=True,
        default=10,
        help="sample intervals per energy equation",
    )
    p.add_argument(
        "--integration",
        choices=["simpson", "trapezoid", "zoh"],
        default="simpson",
        help="energy and integral model integration rule (zoh: torque held over each period)",
    )
    number(
        p,
        "--integral-window",
        low=1,
        high=1000000,
        integer=True,
        default=40,
        help="sample intervals per integral-model window (one equation per joint and window)",
    )
    number(
        p,
        "--min-velocity",
        low=0,
        default=0.01,
        help="dynamic model with friction: leave out joint equations slower than this [rad/s, m/s]",
    )
    p.add_argument(
        "--friction-model",
        choices=[*FRICTION_KINDS, "auto"],
        help="friction per joint (implies --friction): coulomb Fv v + Fc sign v (the default), "
        "asymmetric + Fa |sign v| (direction-dependent Coulomb), smooth Fv v + Fc tanh(v / w) "
        "(w from the data's velocity noise unless --friction-width), stribeck + Fs sign v "
        "exp(-(v / w)^2) (w searched per joint on the fit's residual), or auto (the one with "
        "the smallest residual on held-out blocks of the fit logs); the choice is reported",
    )
    joint_vector(
        p,
        "--friction-width",
        help="--friction-model smooth or auto: the tanh width w [rad/s, m/s], positive (or "
        "one value for all joints)",
    )
    p.set_defaults(func=cmd_identify)

    p = add_command(
        sub,
        "identify-payload",
        description="The 10 inertial parameters (XX XY XZ YY YZ ZZ MX MY MZ M about the last "
        "link frame's origin, in its frame) of a payload rigidly fixed to the last link, from "
        "logs with the payload: tau - tau_arm = W_last phi, with tau_arm from the identified arm "
        "(the JSON of 'mindyn identify': its classical map when present, else its base values; "
        "friction, rotor inertia and offsets as identified; the chain to the --tip it was "
        "identified with, unless --tip is given). Least squares with standard "
        "deviations, and the estimate with a positive semidefinite pseudo-inertia (cvxpy, "
        "Clarabel). Refused, naming them, when the data do not determine all 10 parameters.",
    )
    add_robot(p)
    p.add_argument("identification", metavar="ID.json", help="JSON of 'mindyn identify'")
    p.add_argument("data", nargs="+", metavar="LOG", help="log(s) with the payload, as identify's")
    _add_data_options(p)
    number(
        p,
        "--min-velocity",
        low=0,
        default=0.01,
        help="arm with friction: leave out joint equations slower than this [rad/s, m/s]",
    )
    p.add_argument(
        "--no-consistent", action="store_true", help="least squares only (no convex solve)"
    )
    p.add_argument("--json", metavar="FILE", type=output_file, help="write the results as JSON")
    p.set_defaults(func=cmd_identify_payload)

    p = add_command(
        sub,
        "predict",
        description="The joint torques W_b(q, dq, ddq) p_b of the base-parameter values of "
        "'mindyn identify --json' on LOG, read as identify read its logs (the filter and "
        "cut-off recorded in the JSON: with the low-pass, the model is evaluated on the "
        "filtered motion at each logged time stamp between the filter edges; a log with breaks "
        "is cut into segments). Writes t, q, dq, ddq (the motion evaluated, 17 digits), tau_hat "
        "and, when the log has them, the torques as logged (N m). 'mindyn codegen --params "
        "ID.json' gives code computing the same torques.",
    )
    add_robot(p)
    p.add_argument("identification", metavar="ID.json", help="JSON of 'mindyn identify'")
    p.add_argument("log", metavar="LOG", help="CSV log or ROS bag (torques optional)")
    p.add_argument(
        "-o", "--output", required=True, metavar="CSV", type=output_file, help="CSV to write"
    )
    p.add_argument(
        "--consistent",
        action="store_true",
        help="the consistent estimate of the JSON (identify --consistent) instead of the "
        "unconstrained one",
    )
    p.add_argument(
        "--filter",
        choices=["lowpass", "butter", "savgol", "none"],
        help="read the log otherwise than the JSON records (as identify's --filter)",
    )
    number(p, "--cutoff", low=0, low_open=True, help="cut-off [Hz] instead of the recorded one")
    p.add_argument("--topic", help="ROS bag: the JointState topic (when there are several)")
    add_recorded_torque_reading(p)
    p.set_defaults(func=cmd_predict)
