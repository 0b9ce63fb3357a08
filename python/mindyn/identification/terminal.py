"""The terminal text of the identification workflow: what ``mindyn identify`` prints for an
:class:`~mindyn.identification.summary.IdentificationReport` (:func:`format_identification`)
and what ``mindyn identify-payload`` prints for a payload (:func:`format_payload`)."""

from __future__ import annotations

import math
import re
from pathlib import Path


def joint_term_words(robot, *, rotor: bool, friction: bool, offset: bool) -> list[str]:
    """The joint terms identified, in words, for the first line (with where the rotor inertia
    and friction act when the robot has transmissions)."""
    named = (("rotor inertia", rotor), ("friction", friction), ("torque offsets", offset))
    words = [w for w, on in named if on]
    if robot.transmission is not None and (rotor or friction):
        words[int(rotor and friction)] += (
            " on the motors through the transmissions (drive_side='joint': on the joints)"
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
    out = [head + f"{sum(fit.samples)} samples from {len(fit.logs)} logs fitted together:"]
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
        out.append(
            f"  velocities: {_describe(proc.get('velocity', {}))}; accelerations: "
            f"{_describe(proc.get('acceleration', {}))}"
            + ("" if res.model == "dynamic" else f" (not used by the {res.model} model)")
            + (" (each log on its own)" if len(logs) > 1 else "")
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
            else "  all joint equations kept (min_velocity=0)"
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
    return out


def _kept(report) -> list[str]:
    """Parameters kept, the truth compared, the friction model, the fit's warnings."""
    res, base = report.result, report.base
    out = [
        f"  {len(res.names)} of {base.n} parameters kept"
        + (
            f" after removing {len(res.removed)} with RSD > {report.options.rsd_threshold:g} %"
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
    if report.truth_side:
        out.append(
            f"  note: the log was simulated with rotor inertia and friction on the "
            f"{report.truth_side}s, this fit has them on the {report.robot.drive_side}s: its "
            "true values are not compared"
        )
    if base.friction:
        out += report.friction_lines
    for w in res.settings.get("warnings", []):
        out.append(f"  WARNING: {w}")
    return out


def format_identification(report) -> str:
    """The terminal text of ``mindyn identify`` for ``report``."""
    from .report import format_table

    cons, fit, val = report.consistent, report.fit, report.validation
    cfit, cval = report.consistent_fit, report.consistent_validation
    vfiles = report.logs.validation.files
    out = _head(report) + _processing(report) + _settings(report) + _kept(report)
    which = ""
    if cons is not None:
        out.append(_headline(cfit, cval, fit, val))
        which = ", unconstrained least-squares estimate"
    out.append("")
    if cons is not None:
        out.append("Unconstrained least-squares estimate (base parameters):")
    out.append(format_table(report.result, truth=report.truth))
    out.append("")
    out.append(_rms_lines(f"identification data{which}", fit))
    if val is not None:
        out.append(_rms_lines(f"validation data ({', '.join(vfiles)}){which}", val))
    if cons is not None:
        out.append("")
        out += _consistent_lines(
            report.consistent_doc, fit, val, cfit, cval, report.mass_matrix_min_eig
        )
        out.append(_rms_lines("identification data, consistent estimate", cfit))
        if cval is not None:
            out.append(
                _rms_lines(f"validation data ({', '.join(vfiles)}), consistent estimate", cval)
            )
    return "\n".join(out)


def format_payload(res, robot, files: list, identification: str, tip_note: str = "") -> str:
    """The terminal text of ``mindyn identify-payload``: the least-squares parameters with their
    standard deviations, mass, centre of mass and inertia, and the consistent estimate."""
    d = res.derived()
    out = [
        f"{robot.name}: payload on the last link ({robot.link_names[-1]}{tip_note}) from "
        f"{', '.join(files)}: {res.rows} equations, regressor rank {res.rank} of 10, condition "
        f"number {res.cond:.3g}; arm torques from the {res.arm_values} of {identification}",
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
        c = res.derived(consistent=True)
        out.append(
            f"  consistent ({res.solver}, {res.status}): mass {c['mass']:.5g} kg, centre of "
            "mass "
            + " ".join(f"{x:.4g}" for x in c["com"])
            + " m, inertia about it "
            + " ".join(f"{x:.4g}" for x in c["inertia_com"])
            + f" kg m^2, smallest pseudo-inertia eigenvalue {res.consistent_min_eig:.3g} kg"
        )
    return "\n".join(out)


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


def _weight_lines(ce: dict) -> list[str]:
    """How the prior's weight was chosen, and per link whether the data or the prior hold it
    (``ce``: the consistent estimate's ``consistent_estimate`` JSON fields)."""
    ch = ce["prior_weight_choice"]
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
                "beyond (give prior_weight= to go further)"
            )
    elif ce["prior_weight"]:
        lines.append(f"  prior weight {ce['prior_weight']:g} (given)")
    if ce["links"]:
        from .prior import MASS_EVIDENCE

        lines.append(
            "  per link: mass [kg] (posterior standard deviation), description's mass [kg], fit "
            "worse with the mass held at the description's [noise variances], the mass "
            "determined by (with the data's standard deviation); identifiable directions of "
            "the link's parameters determined by the data, the link's parameters determined by:"
        )
        for lk in ce["links"]:
            sd = lk["mass_data_std"]
            lines.append(
                f"  {lk['link']:<24} {lk['mass']:10.4g} ({lk['mass_std']:.3g}) "
                f"{lk['description_mass']:10.4g} {lk['mass_fit_increase']:10.4g} "
                f"{lk['mass_verdict']:<10}"
                + (f" ({sd:.3g})" if lk["mass_verdict"] in ("data", "data+prior") else " " * 8)
                + f" {lk['directions_by_data']:3d} of {lk['identifiable_directions']:<3d} "
                f"{lk['verdict']}"
                + ("" if lk["mass_profile_converged"] else " (mass profile not converged)")
            )
        lines.append(
            f"  (mass by data: held at the description's, the fit is worse by at least "
            f"{MASS_EVIDENCE:g} noise variances, the data's standard deviation |m - m0| / "
            "sqrt(worse); data+prior: the fit not, but the whole objective worse by as much "
            "(the prior ties the mass to the link's moments, which the data fix), standard "
            "deviation from that; else by the priors (the description's mass within two "
            "standard deviations); unknown: that fit did not converge; identifiable: "
            "the combinations of the link's own parameters that the torques determine, by the "
            "data when the priors' share of their variance, -d ln(variance) / d ln(weight), is "
            "below 0.5; data: their mean share "
            "below 0.5; partly: above, but some of them below; prior: none)"
        )
    return lines


def _consistent_lines(doc, fit, val, cfit, cval, low) -> list[str]:
    """The lines of ``mindyn identify --consistent``: pseudo-inertias, errors side by side
    (``doc``: the consistent estimate's JSON fields, ``low``: its mass matrix's smallest
    eigenvalue over the data)."""
    ce = doc["consistent_estimate"]
    un = ce["unconstrained_violating_links"]
    weight = ce["prior_weight"]
    lines = [
        f"Physically consistent estimate ({ce['solver']}, {ce['status']}, {ce['seconds']:.3g} s"
        + (f", prior weight {weight:g}" if weight else ", no prior")
        + f"): total mass {doc['total_mass']:.4g} kg; fit "
        f"{ce['fit_increase_noise_variances']:.4g} noise variances worse than the unconstrained "
        "fit with all base parameters",
        *_weight_lines(ce),
        "  smallest pseudo-inertia eigenvalue per link [kg] (unconstrained: its realisation "
        "nearest the description):",
        f"  {'link':<24} {'unconstrained':>14} {'consistent':>14}",
    ]
    before = ce["unconstrained_pseudo_inertia_min_eig"]
    for nm, b in doc["pseudo_inertia_min_eig"].items():
        lines.append(
            f"  {nm:<24} {before[nm]:14.4g} {b:14.4g}" + ("  violated" if nm in un else "")
        )
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
    lines.append(
        f"  mass matrix of the consistent model: smallest eigenvalue over the data {low:.4g} "
        + ("(positive definite at every sample)" if low > 0 else "(NOT positive definite)")
    )
    for note in ce["notes"]:
        lines.append(f"  note: {note}")
    return lines


def _segments_line(s: dict) -> str:
    """One line for a log cut at its breaks (the segments themselves are in the JSON)."""
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
    if raw is None or mov is None:
        return ["  (the torques as logged are not known for this data: no raw or moving measure)"]
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
