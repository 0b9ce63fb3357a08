"""CLI: ``mindyn predict``, the torques an identified model predicts on a log."""

from __future__ import annotations

import argparse
from dataclasses import replace

from .args import UsageError, add_command
from .columns import add_columns
from .number_options import add_recorded_torque_reading, number
from .outputs import output_file
from .robot_options import add_robot, load_robot


def cmd_predict(args: argparse.Namespace) -> int:
    from ..identification.data import UnusedGainError
    from ..identification.document import read_identification
    from ..identification.options import ReadingOptions
    from ..identification.prediction import identified_model, predict
    from ..identification.reading import read_log

    doc = read_identification(args.identification)
    robot = load_robot(args, tip=doc.get("tip"), command="predict")
    estimate = "consistent" if args.consistent else "unconstrained"
    identified_model(args.identification, robot, estimate=estimate)  # errors before reading
    recorded = doc.get("reading")
    if recorded is None and args.filter is None:
        raise UsageError(
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
    filt = reading.get("filter", "lowpass")
    opts = ReadingOptions(
        filter=filt,
        cutoff=reading.get("cutoff_Hz"),
        edge=reading.get("edge_s") if filt == "lowpass" else None,
        torque_unit=args.torque_unit or reading.get("torque_unit"),
        drive_gain=args.drive_gain or reading.get("drive_gain"),
        topic=args.topic or reading.get("topic"),
        columns=args.columns or reading.get("columns"),
    )
    unapplied = False  # the recorded drive gains, for a log of torques
    try:
        logs = read_log(args.log, robot, options=opts, decimate=False, require_torque=False)
    except UnusedGainError:
        if args.drive_gain is not None:
            raise
        # the recorded gains converted the identification's currents; this log holds torques
        opts = replace(opts, drive_gain=None)
        logs = read_log(args.log, robot, options=opts, decimate=False, require_torque=False)
        unapplied = True
    pred = predict(args.identification, logs, robot=robot, estimate=estimate)
    path = pred.write_csv(args.output)
    cutoff = opts.cutoff
    derived = ""
    if cutoff is None and opts.filter == "lowpass":  # not recorded for this filter: the data's
        info = logs[0].processing.get("preprocess", {}).get("filter", {})
        cutoff, derived = info.get("cutoff_Hz"), ", derived from the log"
    how = (
        f"low-pass at {cutoff:.4g} Hz{derived} (zero-phase Butterworth order 4), the model on the "
        "filtered motion at the logged time stamps between the filter edges"
        if opts.filter == "lowpass"
        else f"--filter {opts.filter}"
        + (f" at {opts.cutoff:g} Hz" if opts.cutoff is not None else "")
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
    if unapplied:
        print(
            "  the log holds torques, not motor currents: the drive gains recorded for the "
            "identification's currents are not applied"
        )
    cols = "t, q, dq, ddq (the motion evaluated), tau_hat" + (
        ", tau (as logged, N m)" if pred.tau is not None else ""
    )
    if "columns" in logs[0].processing:
        from ..identification.columns import describe

        print(f"  {describe(logs[0].processing['columns'])}")
    print(f"  wrote {path} ({cols})")
    return 0


def register(sub) -> None:
    """Adds ``predict`` to the ``mindyn`` subcommands."""
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
    add_columns(p, recorded=True)
    p.set_defaults(func=cmd_predict)
