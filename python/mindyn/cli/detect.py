"""``mindyn detect``: the generalised-momentum observer of an identified model over a log, its
residual per joint, thresholds calibrated on a collision-free log, and the intervals where a log
crosses them."""

from __future__ import annotations

import argparse

import numpy as np

from .args import UsageError, add_command, deprecated, given_options, remember_flags
from .columns import add_columns
from .number_options import add_recorded_torque_reading, joint_values, joint_vector, number
from .outputs import output_file
from .robot_options import add_robot, load_robot

#: The options of --calibrate, refused without it
CALIBRATE_ONLY = ("quantile", "margin", "model_sigma")


def _read_log(path, robot, doc, args) -> tuple:
    """The log at ``path`` read as the identification ``doc`` records (options given win), and a
    note when the recorded drive gains were not applied (None otherwise)."""
    from ..identification.data import DataError, UnusedGainError, read_csv, read_truth

    read_truth(path, robot)  # a simulated log of another robot is refused
    reading = doc.get("reading") or {}
    unit = args.torque_unit or reading.get("torque_unit")
    gain = args.drive_gain or reading.get("drive_gain")
    gain = np.array(joint_values(gain, robot.n, "--drive-gain", broadcast=True)) if gain else None
    columns = args.columns or reading.get("columns")
    try:
        data = read_csv(
            path, robot=robot, torque_unit=unit, filter="none", drive_gain=gain, columns=columns
        )
    except UnusedGainError:
        if args.drive_gain:
            raise
        # the recorded gains converted the identification's currents; this log holds torques
        data = read_csv(path, robot=robot, torque_unit=unit, filter="none", columns=columns)
        note = (
            "  the log holds torques, not motor currents: the drive gains recorded for the "
            "identification's currents are not applied"
        )
    else:
        note = None
    if data.tau is None:
        raise DataError(
            f"{path}: has no torque columns tau1..tau{robot.n}; the observer needs them"
        )
    return data, note


def _external_spans(path) -> list:
    """The runs of external torque a simulated log's truth sidecar records (empty without)."""
    from ..identification.data import read_json, truth_path

    p = truth_path(path)
    if not p.is_file():
        return []
    ext = read_json(p, what="truth file").get("external")
    spans = ext.get("spans") if isinstance(ext, dict) else None

    def number(x) -> bool:
        return isinstance(x, (int, float)) and not isinstance(x, bool)

    ok = isinstance(spans, list) and all(
        isinstance(s, dict)
        and all(number(s.get(k)) for k in ("start_s", "stop_s"))
        and isinstance(s.get("peak"), list)
        and all(number(x) for x in s["peak"])
        for s in spans
    )
    return list(spans) if ok and spans is not None else []


def cmd_detect(args: argparse.Namespace) -> int:
    from ..control.observer import (
        MomentumObserver,
        ObserverThresholds,
        alarm_intervals,
        calibrate_thresholds,
        default_observer_gain,
        load_thresholds,
        residual_uncertainty,
        score_alarms,
    )
    from ..identification.data import truth_path
    from ..identification.document import read_identification
    from ..identification.prediction import identified_model

    doc = read_identification(args.identification)
    from ..identification.document import refuse_state

    refuse_state(doc, "the momentum observer", str(args.identification))
    robot = load_robot(args, tip=doc.get("tip"), command="detect")
    estimate = "consistent" if args.consistent else "unconstrained"
    base, values, _ = identified_model(args.identification, robot, estimate=estimate)
    given = given_options(args, *CALIBRATE_ONLY) if not args.calibrate else []
    if given:  # (they were ignored)
        raise UsageError(f"{given[0]} applies to --calibrate")
    if args.thresholds and args.calibrate:
        raise UsageError(
            "--thresholds and --calibrate exclude each other (calibrate on a "
            "collision-free log, then detect with the file it wrote)"
        )
    if args.thresholds and args.observer_gain:
        raise UsageError(
            "--observer-gain: the thresholds file gives the gains it was calibrated with"
        )
    thresholds = load_thresholds(args.thresholds, robot) if args.thresholds else None
    if thresholds is not None:
        _same_model(thresholds, base, values, estimate, args)
    data, gain_note = _read_log(args.log, robot, doc, args)
    t = data.t
    steps = np.diff(t)
    period = float(np.median(steps))
    if thresholds is not None:
        gains, how = thresholds.gains, f"those of {args.thresholds}"
    elif args.observer_gain:
        gains = np.array(
            joint_values(args.observer_gain, robot.n, "--observer-gain", broadcast=True)
        )
        how = "given"
    else:
        k = default_observer_gain(period)
        how = f"default 1 / (10 T) with the log's median period T = {period * 1e3:.4g} ms"
        if k * steps.max() >= 1.0:  # uneven stamps: K_O dt < 2 at the longest step, with margin
            k = 1.0 / steps.max()
            how = f"1 / the log's longest step of {steps.max() * 1e3:.4g} ms (below 1 / (10 T))"
        gains = np.full(robot.n, k)
    torque, torque_how = args.torque, ""
    if torque is None:
        from ..identification.reading import simulated_torque

        simulated = simulated_torque(args.log)
        if simulated is not None:  # the log's own simulation says how it logged its torque
            torque = simulated
            if torque == "held":
                torque_how = f", as {truth_path(args.log)} says (--torque sets it)"
        else:
            torque = (doc.get("reading") or {}).get("torque") or "sampled"
            if torque == "held":
                torque_how = f", as {args.identification} read its logs (--torque sets it)"
    obs = MomentumObserver(base, values, period=period, gains=gains, held_torque=torque == "held")
    r = obs.run(data.q, data.dq, data.tau, t)
    n = robot.n
    print(
        f"{robot.name}: momentum observer of the {estimate} estimate of {args.identification} "
        f"({base.n} base parameters) on {args.log}: {t.size} samples over {t[-1] - t[0]:.4g} s "
        f"(median step {period * 1e3:.4g} ms, {steps.min() * 1e3:.4g} to "
        f"{steps.max() * 1e3:.4g} ms)"
    )
    if gain_note:
        print(gain_note)
    if "columns" in data.processing:
        from ..identification.columns import describe

        print(f"  {describe(data.processing['columns'])}")
    print(
        f"  gains K_O [1/s] ({how}): "
        + ", ".join(f"{k:.4g}" for k in gains)
        + f"; torque {'held over each step' if torque == 'held' else 'sampled (trapezoid)'}"
        + torque_how
    )
    external = _external_spans(args.log)
    if args.calibrate and external:
        print(
            f"  WARNING: {truth_path(args.log)} says an external torque acted on this log "
            f"({len(external)} run(s), the first from {external[0]['start_s']:.4g} s): it is "
            "not collision-free, and thresholds calibrated on it take the hits in"
        )
    absr = np.abs(r)
    print("  residual |r| per joint (max / 99.9 % / RMS):")
    for j in range(n):
        print(
            f"    {j + 1}: {absr[:, j].max():.4g} / {np.quantile(absr[:, j], 0.999):.4g} / "
            f"{np.sqrt(np.mean(r[:, j] ** 2)):.4g}"
        )
    if args.calibrate:
        thr = calibrate_thresholds(r, quantile=args.quantile, margin=args.margin)
        info = {
            "calibration_log": str(args.log),
            "identification": str(args.identification),
            # the model whose residual the thresholds bound: what --thresholds compares
            "estimate": estimate,
            "base_names": list(base.names),
            "base_values": [float(v) for v in values],
        }
        if args.model_sigma:
            std = _base_std(doc, base, args.identification, estimate)
            sig = residual_uncertainty(obs, std, data.q, data.dq, t).max(0)
            band = args.model_sigma * sig
            print(
                f"  parameter uncertainty (the identification's standard deviations, "
                f"correlations left out): largest {args.model_sigma:g} sigma of r per joint "
                + ", ".join(f"{x:.4g}" for x in band)
            )
            thr = np.maximum(thr, band)
            info["model_sigma"] = args.model_sigma
        out = ObserverThresholds(
            robot.name,
            period,
            gains,
            thr,
            args.quantile,
            args.margin,
            info,
        )
        path = out.write(args.calibrate)
        print(
            f"  thresholds = {args.margin:g} x "
            + (
                "the largest |r|"
                if args.quantile == 1
                else f"the {args.quantile:g} quantile of |r|"
            )
            + " "
            "(this log taken as collision-free)"
            + (f", at least {args.model_sigma:g} sigma" if args.model_sigma else "")
            + ": "
            + ", ".join(f"{x:.4g}" for x in thr)
        )
        print(f"  wrote {path}")
        return 0
    if thresholds is None:
        return 0
    if not np.isclose(thresholds.period, period, rtol=0.02):
        print(
            f"  note: thresholds calibrated at a period of {thresholds.period * 1e3:.4g} ms, "
            f"this log's is {period * 1e3:.4g} ms"
        )
    alarms = alarm_intervals(t, r, thresholds.thresholds)
    print(
        "  thresholds: "
        + ", ".join(f"{x:.4g}" for x in thresholds.thresholds)
        + f"; {len(alarms)} interval(s) above"
    )
    for a in alarms:
        print(
            f"    joint {a['joint']}: {a['start']:.4f} s to {a['end']:.4f} s, peak {a['peak']:.4g}"
        )
    if external:
        settle = 5.0 / float(np.min(gains))
        score = score_alarms(alarms, external, settle=settle)
        print(
            f"  the external torque of the simulation ({truth_path(args.log)}), an alarm "
            f"counted for a run when it starts in it or within 5 / K_O = {settle:.4g} s after:"
        )
        for s, sc in zip(external, score["spans"]):
            peak = ", ".join(f"{x:.4g}" for x in s["peak"])
            print(
                f"    {s['start_s']:.4f} s to {s['stop_s']:.4f} s (peak per joint {peak}): "
                + (
                    f"detected after {sc['delay_s'] * 1e3:.4g} ms, joint(s) "
                    + ", ".join(map(str, sc["joints"]))
                    if sc["detected"]
                    else "not detected"
                )
            )
        print(f"    alarms outside them (false): {len(score['false'])}")
    if args.plot:
        _plot(args.plot, t, r, thresholds.thresholds, alarms, robot.name)
        print(f"  wrote {args.plot}")
    return 1 if alarms else 0


def _same_model(thresholds, base, values, estimate: str, args) -> None:
    """Refuses thresholds calibrated with another model than ``values`` (the ``base_values``
    their file records: another identification, or the other estimate), naming the largest
    difference; warns, in one line, when a file that records no values (written before them)
    names another identification JSON than the one given."""
    import warnings
    from pathlib import Path

    from ..control.observer import ThresholdsError

    info, where = thresholds.info, str(args.thresholds)
    made = info.get("identification")
    made_with = f"the {info.get('estimate', 'unconstrained')} estimate of '{made}'"
    names, recorded = info.get("base_names"), info.get("base_values")
    if isinstance(names, list) and isinstance(recorded, list):
        try:
            theirs = np.array(recorded, dtype=float)
        except (TypeError, ValueError):
            raise ThresholdsError(f"{where}: 'base_values' must be a list of numbers") from None
        ours = f"the {estimate} estimate of '{args.identification}'"
        if names != list(base.names) or theirs.shape != values.shape:
            raise ThresholdsError(
                f"{where}: calibrated with {made_with}, whose {len(names)} base parameters are "
                f"not the {base.n} of {ours}; calibrate again with it (--calibrate)"
            )
        differ = ~np.isclose(theirs, values, rtol=1e-9, atol=0.0)
        if differ.any():
            scale = np.maximum(np.maximum(np.abs(theirs), np.abs(values)), 1e-300)
            k = int(np.argmax(np.abs(theirs - values) / scale))
            raise ThresholdsError(
                f"{where}: calibrated with {made_with}: {int(differ.sum())} of its {base.n} base "
                f"parameter values differ from {ours} ({base.names[k]} {theirs[k]:.6g} there, "
                f"{values[k]:.6g} here); its thresholds bound another model's residual: "
                "calibrate again with this one (--calibrate)"
            )
        return
    if isinstance(made, str) and Path(made).resolve() != Path(args.identification).resolve():
        warnings.warn(
            f"{where}: calibrated with the identification '{made}', not "
            f"'{args.identification}' (the file records no parameter values to compare: "
            "thresholds of another model's residual do not fit this one)",
            stacklevel=2,
        )


def _base_std(doc, base, where, estimate):
    """The identification's standard deviation of each base parameter (0 for a pruned one)."""
    from ..identification.data import DataError

    if estimate != "unconstrained":
        raise UsageError("--model-sigma: the standard deviations are the unconstrained estimate's")
    names, std = doc.get("names"), doc.get("std")
    if not (isinstance(names, list) and isinstance(std, list) and len(names) == len(std)):
        raise DataError(f"--model-sigma: {where} gives no standard deviations (names, std)")
    out = np.zeros(base.n)
    index = {k: i for i, k in enumerate(base.names)}
    for name, s in zip(names, std, strict=True):
        if (
            not isinstance(name, str)
            or name not in index
            or not isinstance(s, (int, float))
            or not s >= 0
        ):
            raise DataError(f"--model-sigma: {where}: '{name}' has no usable standard deviation")
        out[index[name]] = float(s)
    return out


def _plot(path, t, r, thr, alarms, name):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = r.shape[1]
    fig, axes = plt.subplots(n, 1, figsize=(8, 1.6 * n + 0.8), sharex=True, squeeze=False)
    for j, ax in enumerate(axes[:, 0]):
        ax.plot(t, r[:, j], lw=0.8)
        ax.axhline(thr[j], color="r", lw=0.6)
        ax.axhline(-thr[j], color="r", lw=0.6)
        for a in alarms:
            if a["joint"] == j + 1:
                ax.axvspan(a["start"], a["end"], color="r", alpha=0.2)
        ax.set_ylabel(f"r{j + 1}")
    axes[-1, 0].set_xlabel("t [s]")
    fig.suptitle(f"{name}: momentum-observer residual and thresholds")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def register(sub) -> None:
    """Adds ``detect`` to the ``mindyn`` subcommands."""
    p = add_command(
        sub,
        "detect",
        description="Runs the generalised-momentum observer r = K_O (p - p(0) - int(tau - beta + "
        "r) dt) (p = A(q) dq, beta = -dL/dq + friction + offset, from the base parameters of "
        "'mindyn identify --json') over LOG at its time stamps (the logged dq, or central "
        "differences of q where the log has none; no filter) and "
        "reports the residual per joint. --calibrate FILE: LOG is collision-free; writes "
        "per-joint thresholds margin x quantile(|r|) with the gains. --thresholds FILE: marks "
        "the intervals where |r_j| exceeds its threshold (exit status 1 when there is any).",
    )
    add_robot(p)
    p.add_argument("identification", metavar="ID.json", help="JSON of 'mindyn identify'")
    p.add_argument("log", metavar="LOG", help="CSV log: t, q1..qN, [dq1..dqN], tau1..tauN")
    p.add_argument("--thresholds", metavar="FILE", help="thresholds written by --calibrate")
    p.add_argument(
        "--calibrate", metavar="FILE", type=output_file, help="write thresholds from this log"
    )
    number(
        p,
        "--quantile",
        low=0,
        high=1,
        low_open=True,
        default=1.0,
        help="--calibrate: quantile of |r| (1: the largest)",
    )
    number(p, "--margin", low=1, high=1e6, default=1.5, help="--calibrate: factor on it")
    number(
        p,
        "--model-sigma",
        low=0,
        high=100,
        default=0.0,
        help="--calibrate: thresholds at least this many standard deviations of the residual "
        "that the identification's parameter uncertainty explains along LOG (its standard "
        "deviations, correlations left out; 0: off)",
    )
    remember_flags(p)
    gain = joint_vector(
        p,
        "--observer-gain",
        metavar="K_O",
        help="observer gains K_O [1/s], one or one per joint (default 1 / (10 T), T the log's "
        "median step, or 1 / its longest step when that is lower)",
    )
    deprecated(p, "--gain", gain)
    p.add_argument(
        "--torque",
        choices=["sampled", "held"],
        default=None,
        help="the logged torque is a measurement (trapezoid) or the command held over each "
        "step (default: as the log's .truth.json says its simulation logged it; for any other "
        "log as the identification read its logs, its JSON's reading.torque; sampled when it "
        "records none)",
    )
    p.add_argument("--plot", metavar="PNG", type=output_file, help="plot of r and thresholds")
    p.add_argument("--consistent", action="store_true", help="the consistent estimate of the JSON")
    add_recorded_torque_reading(p)
    add_columns(p, recorded=True)
    p.set_defaults(func=cmd_detect)
