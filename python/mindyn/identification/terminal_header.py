"""The first lines of the terminal text of an identification (:func:`header_lines`): the robot,
model and joint terms, the logs, what the data path did, the regression's settings and the
parameters kept."""

from __future__ import annotations

from pathlib import Path

from .data import describe_beyond_limits
from .pruning import pruning_line
from .terminal import (
    _cutoff_range,
    _describe,
    _describe_preprocess,
    _segments_line,
)


def _integration_choice(res) -> str:
    """How ``integration="auto"`` chose the rule: the residual of each rule's fit."""
    c = res.settings.get("integration_choice")
    if not c:
        return ""
    other = ", ".join(f"{r} {v:.4g}" for r, v in c["rss"].items())
    return f" (auto: the smaller residual of the fits with every base parameter; {other})"


def joint_term_words(robot, *, rotor: bool, friction: bool, offset: bool) -> list[str]:
    """The joint terms identified, in words, for the first line (with where the rotor inertia
    and friction act when the robot has transmissions)."""
    named = (("rotor inertia", rotor), ("friction", friction), ("torque offsets", offset))
    words = [w for w, on in named if on]
    if robot.transmission is not None and (rotor or friction):
        words[int(rotor and friction)] += (
            " on the motors through the transmissions (robot.with_drive_side('joint') puts them on "
            "the joints)"
            if robot.drive_side == "motor"
            else " on the joints (drive_side='joint')"
        )
    return words


def _head(report) -> list[str]:
    """The first lines: robot, model, parameters, logs."""
    res, base, fit = report.result, report.base, report.logs.fit
    o = report.options
    extras = joint_term_words(report.robot, rotor=o.rotor, friction=o.friction, offset=o.offset)
    head = (
        f"{report.robot.name}: {res.model} model, {base.n} base parameters"
        + (f" ({', '.join(extras)})" if extras else "")
        + ", "
    )
    if len(fit.logs) == 1:
        return [head + f"{fit.samples[0]} samples at {fit.rates[0]:.4g} Hz from {fit.files[0]}"]
    # fit.logs are the pieces fitted (a file cut at breaks gives several), fit.files the files
    pieces = (
        f"{len(fit.files)} logs fitted together"
        if len(fit.files) > 1
        else f"1 log, its {len(fit.logs)} segments fitted together"
    )
    out = [head + f"{sum(fit.samples)} samples from {pieces}:"]
    k = 0
    for f, ds, seg in zip(fit.files, fit.parts, fit.segments):
        # a file cut at breaks: one line for its segments
        infos = res.settings["logs"][k : k + len(ds)]
        m = fit.samples[k : k + len(ds)]
        eq = sum(i["equations"] for i in infos)
        if seg is None:
            out.append(f"    {f}: {m[0]} samples at {fit.rates[k]:.4g} Hz, {eq} equations")
        else:
            out.append(f"    {f}: {_segments_line(seg)}, {sum(m)} samples, {eq} equations")
        k += len(ds)
    return out


def _processing(report) -> list[str]:
    """What the data path did to the fit logs."""
    res, fit = report.result, report.logs.fit
    logs = fit.logs
    pres = [d.processing.get("preprocess") for d in logs]
    out = []
    if "columns" in logs[0].processing:
        from .columns import describe

        out.append(
            f"  {describe(logs[0].processing['columns'])}"
            + (" (in the first log)" if len(logs) > 1 else "")
        )
    for logset in (fit, report.logs.validation):  # a log of another robot, or zero?
        for f, ds in zip(logset.files, logset.parts):
            beyond = next(
                (d.processing["beyond_limits"] for d in ds if "beyond_limits" in d.processing), None
            )
            if beyond:
                out.append(f"  WARNING: {describe_beyond_limits(f, beyond)}")
    if all(pres):
        k = 0
        for f, ds in zip(fit.files, fit.parts):
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
        proc = logs[0].processing
        edges = proc.get("derivative_edges") or {}
        out.append(
            f"  velocities: {_describe(proc.get('velocity', {}))}; accelerations: "
            f"{_describe(proc.get('acceleration', {}))}"
            + ("" if res.model == "dynamic" else f" (not used by the {res.model} model)")
            + (" (each log on its own)" if len(logs) > 1 else "")
        )
        if edges.get("samples"):
            out.append(
                f"  {edges['samples']} samples ({edges['seconds']:.3g} s) dropped at each end"
                + (" of the first log" if len(logs) > 1 else "")
                + ", where the derivatives' filter starts up"
            )
    return out


def _settings(report) -> list[str]:
    """The regression: equations, weighting, windows, equations left out, torque units."""
    res, base = report.result, report.base
    proc = report.logs.fit.logs[0].processing
    out = [
        f"  {res.rows} equations, {res.settings.get('weighting')}; condition number of the "
        f"column-scaled regressor {res.cond:.3g}",
    ]
    if res.model == "energy":
        out.append(
            f"  energy windows of {res.settings['energy_window']} sample interval(s), "
            f"{res.settings['integration']} integration{_integration_choice(res)}"
        )
    elif res.model == "integral":
        out.append(
            f"  integral windows of {res.settings['integral_window']} sample interval(s), "
            f"{res.settings['integration']} integration{_integration_choice(res)}"
        )
    if res.model == "energy":  # no equation left out by min_velocity
        pass
    elif res.settings.get("equations_left_out"):
        out.append(
            f"  {res.settings['equations_left_out']} joint equations "
            + ("of windows slower at a sample than " if res.model == "integral" else "below ")
            + f"{res.settings['min_velocity']:g} rad/s left out (Coulomb sign undetermined)"
        )
    elif base.friction:
        out.append(
            f"  no joint equation below {res.settings['min_velocity']:g} rad/s left out"
            if res.settings["min_velocity"] > 0
            else "  all joint equations kept (min_velocity=0)"
        )
    corr = res.settings.get("std_correlation")
    if corr and corr["variance_factor"] > 1.0:
        out.append(f"  standard deviations: {corr['rule']}")
    out += [f"  base set: {line}" for line in base.snap_report(detail=False)]
    if "held" in proc.get("torque", {}):
        why = proc["torque"].get("held_because")
        out.append(
            f"  torques: {proc['torque']['held']} (torque='held'"
            + (f", {why}; torque='sampled' reads them at their samples)" if why else ")")
        )
    if "sampled_because" in proc.get("torque", {}):
        out.append(f"  torques: taken at their samples ({proc['torque']['sampled_because']})")
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
            + (
                f"; negative gain of {', '.join(proc['torque']['reversed'])} (a "
                "positive current drives it backwards: a reversed motor)"
                if proc["torque"].get("reversed")
                else ""
            )
            + (
                f"; joint(s) {', '.join(proc['torque']['direct'])} without a transmission in "
                "the description: driven directly (ratio 1), their torque the gain x current"
                if proc["torque"].get("direct")
                else ""
            )
        )
    return out


def _drive_terms_left_out(report) -> str:
    """The rotor inertia and friction that the robot's description gives (non-zero) and the
    fit leaves out, in words with the options that fit them ("" when none)."""
    base = report.base
    given = report.robot.drive_terms_given()
    words = []
    if not base.rotor and "Ia" in given:
        words.append("rotor inertia Ia (rotor=True)")
    friction = [k for k in given if k != "Ia"]
    if not base.friction and friction:
        words.append(f"friction {', '.join(friction)} (friction=True)")
    return " and ".join(words)


def _kept(report) -> list[str]:
    """Parameters kept, the truth compared, the friction model, the fit's warnings."""
    res, base = report.result, report.base
    out = [
        f"  {len(res.names)} of {base.n} parameters kept"
        + (
            f" after removing {len(res.removed)} with RSD > {res.rsd_threshold:g} %"
            if res.removed
            else ""
        )
        + (
            " (true values from "
            + str(Path(report.logs.fit.files[0]).with_suffix(""))
            + ".truth.json)"
            if report.truth is not None
            else ""
        )
    ]
    said = pruning_line(res.settings.get("pruning_choice"))
    if said:
        out.append(said)
    if report.truth_side:
        out.append(
            f"  note: the log was simulated with rotor inertia and friction on the "
            f"{report.truth_side}s, this fit has them on the {report.robot.drive_side}s: its "
            "true values are not compared"
        )
    left = _drive_terms_left_out(report)
    if left:
        out.append(
            f"  note: the description gives {left} that this fit leaves out: the kept "
            "parameters take up their torques (a large torque error and many parameters "
            "removed can come from that)"
        )
    if report.truth_frames:
        out.append(
            f"  note: {report.truth_frames}: the log's true values are about other link frames "
            "(another description of the robot), not compared"
        )
    if base.friction:
        out += report.friction_lines
    for w in res.settings.get("warnings", []):
        out.append(f"  WARNING: {w}")
    return out


def header_lines(report) -> list[str]:
    """The first lines of the text of ``report``, before the table of estimates."""
    return _head(report) + _processing(report) + _settings(report) + _kept(report)
