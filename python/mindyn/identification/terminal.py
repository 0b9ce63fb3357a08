"""The terminal text of the identification workflow: what ``mindyn identify`` prints for an
:class:`~mindyn.identification.summary.IdentificationReport` (:func:`format_identification`)
and what ``mindyn identify-payload`` prints for a payload (:func:`format_payload`), and the
lines that describe the data path and the error measures. The first lines of the report are in
:mod:`~mindyn.identification.terminal_header`, the consistent estimate's in
:mod:`~mindyn.identification.terminal_consistent`: each is called once."""

from __future__ import annotations

import math
import re


def format_identification(report) -> str:
    """The terminal text of ``mindyn identify`` for ``report``."""
    from .report import format_table
    from .terminal_consistent import consistent_lines
    from .terminal_header import header_lines

    cons, fit, val = report.consistent, report.fit, report.validation
    vfiles = report.logs.validation.files
    out = header_lines(report)
    which = ""
    consistent: list[str] = []
    if cons is not None:
        headline, consistent = consistent_lines(report)
        out.append(headline)
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
        out += consistent
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
    if res.std_rule:
        out.insert(1, f"  fit and standard deviations: {res.std_rule}")
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
    lines += _uncertainty_lines(v.get("prediction_uncertainty"))
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


def _uncertainty_lines(u: dict | None) -> list[str]:
    """The prediction uncertainty of :func:`~mindyn.identification.validation.
    uncertainty_measures` beside the error table, with the fit's check and its warning
    (:func:`~mindyn.identification.validation.prediction_check`)."""
    if u is None:
        return []
    lines = [
        "  +- pred.  "
        + " ".join(_pct(x) for x in u["relative"])
        + "  (prediction uncertainty: RMS of sqrt(diag(Y Sigma Y^T)) / RMS torque)",
        "  the predicted torques are determined to +-"
        + _pct(u["overall_relative"]).strip()
        + " of |tau|, all joints stacked (covariance of all base parameters, before pruning)",
    ]
    if "share" in u:
        lines.append(
            "  share     "
            + " ".join(f"{x:9.3g}" for x in u["share"])
            + f"  (mean u^2 / residual variance; mean {u['mean_share']:.3g}, "
            f"{u['excess']:.3g} x the p / N_eff = {u['reference']:.2g} a fit of the torques "
            f"leaves; warned above {u['threshold']:g}, or where +- pred. reaches "
            f"{100 * u['relative_threshold']:g} %)"
        )
        if u["warning"]:
            lines.append(f"  WARNING: {u['warning']}")
    return lines


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
