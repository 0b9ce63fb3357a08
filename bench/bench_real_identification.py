"""Identification on real robot logs with default settings, beside reference figures.

``DIR`` is laid out as::

    DIR/panda/panda_gaz2019.yaml, panda_gaz2019_traj1_fit_period1.csv,
              panda_gaz2019_traj1_val_repeat.csv
    DIR/kuka_lwr4/kuka_lwr4.urdf, lwr4_meas1_trajA_run1.csv, lwr4_meas2_trajA_run2.csv,
                  lwr4_meas3_trajB.csv
    DIR/ur10e/ur10e.urdf, ur10e_fit_30sec_12harm.csv, ur10e_val_ptp_10_points.csv and their
              *_raw_currents.csv

(torques in N m; the UR10e's are taken from the raw motor currents times the drive gains of its
data's README, ``--currents`` and ``--drive-gain``). Each case is one fixed
``mindyn identify`` command line, printed, run with default settings (``--friction``, plus
``--rotor`` on the UR10e, and ``--offset``: the logs carry torque offsets, the KUKA's joint 1
about +0.85 N m; ``--no-offset`` leaves them out for comparison). The error is the overall
relative error ``|tau - tau_hat| / |tau|`` over all joints stacked, on the identification log
(fit) and on the validation log, against the torques as the data path leaves them (low-pass
filtered, edges dropped, decimated); it is recovered from the per-joint RMS and relative errors
(``fit.overall_relative`` and ``validation.overall_relative`` of the JSON output). Each case
also prints the error against the torques as logged (``raw``) and on the moving samples only
(``moving``, with the share of each joint's samples counted). A case whose command the CLI
refuses is reported as such.

With ``--consistent`` each command also gets ``--consistent`` (and ``--prior-weight W`` when
given; by default the command chooses it from the data), each case prints the weight and, per
link, the consistent estimate's mass with its standard deviation beside the description's and
whether the data or the prior determine it (the mass's own verdict: the fit with the mass held
at the description's; target: within a factor 3 of the description's, or determined by the
data), and a second table gives, per case: the smallest pseudo-inertia
eigenvalue of the consistent estimate over all links, the validation error of the consistent
estimate against the unconstrained one (target: at most 1.1 times), the total mass, the solver's
time and the whole command's wall time (target for the Panda: 10 s), the smallest mass-matrix
eigenvalue over the data, and a forward simulation of the consistent model (RK4, computed torque
with the same model, the log's own rate) along the first identification log: ``stable`` when it
stays finite (else ``DIVERGED``) and its largest tracking error [rad] is at most 0.05 rad or
twice that of the same simulation of the description's model (in parentheses; the torque held
over a sample period of the log and the Coulomb feedforward on the reference velocity leave
errors of this size with any model), ``WORSE`` when finite but beyond that.

With ``--friction-model KIND`` (coulomb, asymmetric, smooth, stribeck, dahl or auto) every
command gets that option. Each case prints the friction model used (for ``auto`` the
candidates' held-out residuals) and the warning when its fitted friction is not dissipative.
Every case prints each joint's validation error relative to that joint's torque
(``validation.relative`` and its ``raw`` and ``moving`` counterparts of the JSON), e.g. the
UR10e's joint 6 (target with ``auto``: at most 30 %). Every case also prints the prediction
uncertainty (``fit.prediction_uncertainty`` and ``validation.prediction_uncertainty``: the RMS
standard deviation of the predicted torques over the RMS torque), its share of the fit's
squared residual (per joint and mean) and whether the fit warns that the estimate does not
determine the torques (target with the default, dynamic model: no warning). ``--model MODEL``
gives every command that model (energy, integral). ``--rsd-threshold T`` gives every command
that threshold (``auto``: decided on held-out data); every case prints the fit's pruning (with
``auto`` the candidates' held-out residuals and standard errors).

With ``--weight-grid W1,W2,...`` (implies ``--consistent``) each case is also run with
``--prior-weight`` at each of those weights (0: no prior), and a table per case gives, per
weight, the consistent / unconstrained validation ratio (target at most 1.1), whether every link
mass is within a factor 3 of the description's or reported as determined by the data
(``masses``: the links that miss it; ``raw``: the ratio against the torques as logged), and per
link the mass over the description's with the mass's verdict (``d`` data, ``d+p`` data+prior,
``p`` prior). Below it, the weight that each rule of choosing it takes: ``marginal likelihood``
(the default run's choice); ``L-curve corner``: over the grid, the weight of largest curvature
of the log of the prior's divergence against the log of the fit's residual
(``fit_increase_noise_variances`` plus the unconstrained fit's own, ``rows - nb`` residual
variances over ``noise_variance_factor``), derivatives by finite differences in the log of the
weight (the grid's positive weights), and ``GCV``: the grid's weight of smallest generalised
cross-validation score ``n |r|^2 / (n - df)^2`` (``n`` equations, ``|r|^2`` the fit's residual,
``df = tr(H^-1 Q)`` the effective number of parameters, ``Q`` the Hessian of the fit term and
``H`` that of the whole objective at the estimate), computed in this process on
the same least-squares problem as the command (its options parsed by the command's parser).

Run: ``.venv/bin/python bench/bench_real_identification.py DIR [--no-offset] [--consistent
[--prior-weight W]] [--friction-model KIND] [--model MODEL] [--weight-grid W1,W2,...]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: Joint-side drive gains of the UR10e [N m/A], as its data's README gives them.
UR10E_DRIVE_GAINS = (10.0, 10.6956, 8.4566, 9.0029, 9.48, 10.1232)

#: (name, robot, identification logs, validation log, extra flags, reference fit, reference
#: validation, target fit, target validation); errors in percent, None: not given.
CASES = [
    (
        "Panda, fit period 1, validate repeat",
        "panda/panda_gaz2019.yaml",
        ["panda/panda_gaz2019_traj1_fit_period1.csv"],
        "panda/panda_gaz2019_traj1_val_repeat.csv",
        [],
        1.02,
        1.31,
        1.3,
        1.5,
    ),
    (
        "KUKA LWR4+, fit meas3, validate meas1",
        "kuka_lwr4/kuka_lwr4.urdf",
        ["kuka_lwr4/lwr4_meas3_trajB.csv"],
        "kuka_lwr4/lwr4_meas1_trajA_run1.csv",
        [],
        None,
        5.77,
        None,
        5.8,
    ),
    (
        "KUKA LWR4+, fit meas2+meas3, validate meas1",
        "kuka_lwr4/kuka_lwr4.urdf",
        ["kuka_lwr4/lwr4_meas2_trajA_run2.csv", "kuka_lwr4/lwr4_meas3_trajB.csv"],
        "kuka_lwr4/lwr4_meas1_trajA_run1.csv",
        [],
        None,
        2.49,
        None,
        2.6,
    ),
    (
        "UR10e, fit 12-harmonic excitation, validate point-to-point",
        "ur10e/ur10e.urdf",
        ["ur10e/ur10e_fit_30sec_12harm.csv"],
        "ur10e/ur10e_val_ptp_10_points.csv",
        [
            "--rotor",
            "--currents",
            "{dir}/ur10e/ur10e_fit_30sec_12harm_raw_currents.csv",
            "--validate-currents",
            "{dir}/ur10e/ur10e_val_ptp_10_points_raw_currents.csv",
            "--drive-gain",
            ",".join(map(str, UR10E_DRIVE_GAINS)),
        ],
        4.67,
        5.12,
        4.8,
        5.2,
    ),
]


def fmt(x) -> str:
    return "-" if x is None or not math.isfinite(x) else f"{x:.2f} %"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dir", type=Path, help="folder with panda/, kuka_lwr4/, ur10e/")
    ap.add_argument("--no-offset", action="store_true", help="leave out --offset (torque offsets)")
    ap.add_argument("--consistent", action="store_true", help="also the consistent estimate")
    ap.add_argument(
        "--prior-weight", type=float, help="with --consistent (default: the command's choice)"
    )
    ap.add_argument(
        "--friction-model",
        choices=["coulomb", "asymmetric", "smooth", "stribeck", "dahl", "auto"],
        help="give every command this --friction-model (default: none, viscous + Coulomb)",
    )
    ap.add_argument(
        "--model",
        choices=["dynamic", "energy", "integral"],
        help="give every command this --model (default: none, the dynamic model)",
    )
    ap.add_argument(
        "--rsd-threshold",
        help="give every command this --rsd-threshold (a percentage or auto; default: none)",
    )
    ap.add_argument(
        "--weight-grid",
        type=lambda text: [float(w) for w in text.split(",")],
        help="comma-separated prior weights: the consistent estimate at each (0: no prior)",
    )
    args = ap.parse_args()
    if args.weight_grid is not None:
        if args.prior_weight is not None:
            ap.error("--weight-grid: the default run chooses its weight; leave out --prior-weight")
        args.consistent = True
    grids = []
    cons_rows = []
    mindyn = [sys.executable, "-m", "mindyn"]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for k, (name, robot, fits, val, extra, ref_f, ref_v, tgt_f, tgt_v) in enumerate(CASES):
            out = Path(tmp) / f"case{k}.json"
            cmd = (
                ["mindyn", "identify", str(args.dir / robot)]
                + [str(args.dir / f) for f in fits]
                + ["--friction"]
                + (["--friction-model", args.friction_model] if args.friction_model else [])
                + (["--model", args.model] if args.model else [])
                + (["--rsd-threshold", args.rsd_threshold] if args.rsd_threshold else [])
                + [x.format(dir=args.dir) for x in extra]
                + ([] if args.no_offset else ["--offset"])
                + ["--validate", str(args.dir / val), "--json", str(out)]
                + (["--consistent"] if args.consistent else [])
                + (
                    ["--prior-weight", str(args.prior_weight)]
                    if args.prior_weight is not None
                    else []
                )
            )
            print("$ " + " ".join(cmd), flush=True)
            t0 = time.perf_counter()
            run = subprocess.run(mindyn + cmd[1:], capture_output=True, text=True)
            wall = time.perf_counter() - t0
            if args.weight_grid is not None and run.returncode == 0:
                table = weight_grid(cmd, args, out)
                gcv = gcv_weight(cmd, [w for w in args.weight_grid if w > 0])
                grids.append((name, json.loads(out.read_text()), table, gcv))
            if run.returncode != 0:
                msg = (run.stderr.strip().splitlines() or ["failed"])[-1]
                print(f"  refused: {msg}")
                rows.append((name, None, None, ref_f, ref_v, tgt_f, tgt_v, "refused"))
                continue
            doc = json.loads(out.read_text())
            pres = doc.get("settings", {}).get("preprocessing", [])
            for pre in pres if isinstance(pres, list) else [pres]:
                print(
                    f"  cut-off {pre['filter']['cutoff_Hz']:.3g} Hz, jitter "
                    f"{100 * pre['timing']['jitter']:.3g} %, {pre['edge_samples_dropped']} edge "
                    f"samples dropped, decimation {pre['decimation']}, {pre['samples']} samples"
                )
            f = 100 * doc["fit"]["overall_relative"]
            v = 100 * doc["validation"]["overall_relative"]
            for what in ("fit", "validation"):
                m = doc[what]
                print(
                    f"  {what}: filtered {fmt(100 * m['overall_relative'])}, raw "
                    + (fmt(100 * m["raw"]["overall_relative"]) if m.get("raw") else "-")
                    + ", moving "
                    + (
                        f"{fmt(100 * m['moving']['overall_relative'])} (counted "
                        + " ".join(f"{100 * x:.0f}%" for x in m["moving"]["fraction"])
                        + ")"
                        if m.get("moving")
                        else "-"
                    )
                )
            print(uncertainty_line(doc))
            print(pruning_line(doc))
            fm = doc.get("friction_model") or {}
            print(
                f"  friction model {fm.get('kind')} ({fm.get('chosen_by')})"
                + (
                    ", w " + " ".join(f"{x:.3g}" for x in fm["velocity"])
                    if fm.get("velocity")
                    else ""
                )
                + (
                    "; held-out: " + ", ".join(f"{k} {x:.4g}" for k, x in fm["candidates"].items())
                    if fm.get("candidates")
                    else ""
                )
                + (f"; WARNING: {fm['warning']}" if fm.get("warning") else "")
            )
            m = doc["validation"]
            for kind, sub in (("filtered", m), ("raw", m.get("raw")), ("moving", m.get("moving"))):
                if sub and sub.get("relative"):
                    print(
                        f"  validation per joint, {kind}: "
                        + " ".join(
                            f"j{j + 1} {fmt(100 * x if x is not None else None)}"
                            for j, x in enumerate(sub["relative"])
                        )
                    )
            ok = all(x is None or y <= x for x, y in ((tgt_f, f), (tgt_v, v)))
            rows.append((name, f, v, ref_f, ref_v, tgt_f, tgt_v, "met" if ok else "MISSED"))
            if args.consistent:
                cons_rows.append(
                    consistent_row(name, doc, wall, args.dir / robot, args.dir / fits[0])
                )
    print()
    head = ("case", "fit", "validation", "ref. fit", "ref. val.", "target fit", "target val.", "")
    width = max(len(r[0]) for r in rows)
    print(f"{head[0]:<{width}}  " + "  ".join(f"{h:>11}" for h in head[1:]))
    for r in rows:
        print(f"{r[0]:<{width}}  " + "  ".join(f"{fmt(x):>11}" for x in r[1:7]) + f"  {r[7]:>11}")
    if cons_rows:
        print()
        head = (
            "case",
            "min eig",
            "val. uncon.",
            "val. cons.",
            "ratio",
            "mass",
            "solve",
            "wall",
            "min eig A",
            "simulation",
        )
        print(f"{head[0]:<{width}}  " + "  ".join(f"{h:>11}" for h in head[1:]))
        for r in cons_rows:
            print(f"{r[0]:<{width}}  " + "  ".join(f"{x:>11}" for x in r[1:]))
        print(
            "(min eig: smallest pseudo-inertia eigenvalue of the consistent estimate [kg]; ratio: "
            "consistent / unconstrained validation error, target <= 1.1; mass [kg]; solve: the "
            "consistent solve [s]; wall: the whole command [s]; min eig A: smallest mass-matrix "
            "eigenvalue over the identification data)"
        )
    for name, doc, table, gcv in grids:
        print()
        print(weight_table(name, doc, table, gcv))
    return 0


def _threshold_words(threshold) -> str:
    return "none" if threshold is None else f"RSD > {threshold:g} %"


def pruning_line(doc) -> str:
    """The fit's pruning and, with ``--rsd-threshold auto``, how it was decided
    (``settings.pruning_choice``: the candidates' held-out residuals)."""
    c = doc["settings"].get("pruning_choice") or {
        "rsd_threshold": doc["settings"].get("rsd_threshold"),
        "chosen_by": "given",
    }
    held = "; held-out: " + ", ".join(
        f"{_threshold_words(d['rsd_threshold'])} {d['held_out']:.5g} "
        f"(se {d['standard_error']:.2g}, removes {d['removed']})"
        for d in c.get("candidates", [])
    )
    return (
        f"  pruning {_threshold_words(c.get('rsd_threshold'))} ({c.get('chosen_by')})"
        f", {len(doc['removed'])} of {len(doc['base_names'])} removed"
        + (held if c.get("candidates") else "")
    )


def uncertainty_line(doc) -> str:
    """The prediction uncertainty of the JSON ``doc`` on the fit and validation logs (overall,
    relative to the torques), the largest share of the fit's squared residual and the joints
    warned of (``fit.prediction_uncertainty``)."""
    fit, val = doc["fit"]["prediction_uncertainty"], doc["validation"]["prediction_uncertainty"]
    return (
        f"  prediction uncertainty: fit +-{fmt(100 * fit['overall_relative'])}, validation "
        f"+-{fmt(100 * val['overall_relative'])}; per joint (fit) "
        + " ".join(fmt(100 * x if x is not None else None) for x in fit["relative"])
        + f"; share of the fit's residual: mean {fit['mean_share']:.3g}, per joint "
        + " ".join("-" if x is None else f"{x:.2g}" for x in fit["share"])
        + f" (p / N_eff {fit['reference']:.3g}, warned above {fit['threshold']:g}): "
        + (
            f"WARNING joint(s) {', '.join(map(str, fit['joints']))}"
            if fit["joints"]
            else "no warning"
        )
    )


def gcv_weight(cmd, weights) -> float | None:
    """The weight of ``weights`` of smallest generalised cross-validation score on the
    least-squares problem of the command ``cmd`` (identified here without the consistent
    estimate, then the consistent estimate at each weight)."""
    import numpy as np
    from mindyn.cli import build_parser
    from mindyn.cli.identify import identify_options, read_logs
    from mindyn.cli.robot_options import load_robot, with_drive_side
    from mindyn.identification.consistent import (
        _Layout,
        _prior_matrices,
        consistent_estimate,
        description_vector,
        noise_scale,
    )
    from mindyn.identification.prior import BARRIER_END, PriorProblem
    from mindyn.identification.workflow import run

    if not weights:
        return None
    args = build_parser("identify").parse_args(cmd[1:])
    robot = with_drive_side(load_robot(args), args)
    options = identify_options(args, robot)
    logs = read_logs(args, robot, options)
    options = dataclasses.replace(options, consistent=False)
    res = run(robot, logs, options=options).result
    base, ls = res.base, res.reduced
    layout = _Layout(base)
    pi0 = description_vector(base)
    # the consistent estimate's fit term |M pi - z|^2 / s2 (its noise variance unfloored)
    problem = PriorProblem(
        (ls.R * ls.norms) @ base.Y,
        ls.z,
        ls.rho / (ls.r - base.n) * noise_scale(res)["factor"],
        layout,
        _prior_matrices(base, layout, pi0, None),
    )
    scores = []
    for w in weights:
        pi = consistent_estimate(res, prior_weight=w).classical
        _, H = problem.derivatives(pi, w, BARRIER_END)
        d = np.sqrt(np.maximum(np.diag(H), 1e-300))
        Hinv = np.linalg.pinv(H / np.outer(d, d), hermitian=True, rcond=1e-14) / np.outer(d, d)
        df = float(np.trace(Hinv @ problem.Q))
        rss = ls.rho / problem.s2 + problem.fit(pi)
        scores.append(ls.r * rss / (ls.r - df) ** 2)
    return float(weights[int(np.argmin(scores))])


def weight_grid(cmd, args, out) -> list:
    """The JSON of the command ``cmd`` (``--consistent`` without a weight, its output ``out``)
    rerun with ``--prior-weight`` at each weight of ``args.weight_grid``."""
    docs = []
    grid_out = out.with_name(out.stem + "_grid.json")
    cmd = [str(grid_out) if x == str(out) else x for x in cmd]
    for w in args.weight_grid:
        run = subprocess.run(
            [sys.executable, "-m", "mindyn", *cmd[1:], "--prior-weight", repr(w)],
            capture_output=True,
            text=True,
        )
        if run.returncode != 0:
            docs.append((w, (run.stderr.strip().splitlines() or ["failed"])[-1]))
        else:
            docs.append((w, json.loads(grid_out.read_text())))
    return docs


def _mass_ok(lk) -> bool:
    m, m0 = lk["mass"], lk["description_mass"]
    return (m0 > 0 and m0 / 3 <= m <= 3 * m0) or lk["mass_verdict"] == "data"


def weight_table(name, doc, table, gcv=None) -> str:
    """Per prior weight: the validation ratio, the mass target and each link's mass over the
    description's with its verdict; then the weight each rule of choosing it takes."""
    short = {"data": "d", "data+prior": "d+p", "prior": "p", "unknown": "?"}
    vu = doc["validation"]["overall_relative"]
    lines = [f"{name}: consistent estimate over the prior weight (default run's choice first)"]
    ce = doc["consistent_estimate"]
    rows = [("default " + f"{ce['prior_weight']:g}", doc)] + [(f"{w:g}", d) for w, d in table]
    for label, d in rows:
        if isinstance(d, str):
            lines.append(f"  W {label:>14}: refused: {d}")
            continue
        c = d["consistent_estimate"]
        ratio = c["validation"]["overall_relative"] / vu
        links = c.get("links") or []
        miss = [str(k + 1) for k, lk in enumerate(links) if not _mass_ok(lk)]
        raw = c["validation"].get("raw"), doc["validation"].get("raw")
        raw_ratio = raw[0]["overall_relative"] / raw[1]["overall_relative"] if all(raw) else None
        lines.append(
            f"  W {label:>14}: ratio {ratio:6.3f} {'ok ' if ratio <= 1.1 else 'MISSED'} (raw "
            + ("-" if raw_ratio is None else f"{raw_ratio:.3f}")
            + ")  masses "
            + (("MISSED " + ",".join(miss)) if miss else ("ok" if links else "-"))
            + "  "
            + " ".join(
                f"{lk['mass'] / lk['description_mass']:.2f}{short[lk['mass_verdict']]}"
                for lk in links
            )
        )
    lines.append(
        "  (per link: mass / description's mass and its verdict: d data, d+p data+prior, p prior)"
    )
    ch = ce.get("prior_weight_choice")
    rules = {"marginal likelihood": ch["chosen"]} if ch else {}
    corner = l_curve_corner(doc, table)
    if corner is not None:
        rules["L-curve corner"] = corner
    if gcv is not None:
        rules["GCV"] = gcv
    if rules:
        lines.append("  " + ", ".join(f"{r} -> W {w:g}" for r, w in rules.items()))
    return "\n".join(lines)


def l_curve_corner(doc, table) -> float | None:
    """The grid's weight of largest curvature of (log residual, log divergence) over log W."""
    import numpy as np

    pts = [(w, d["consistent_estimate"]) for w, d in table if w > 0 and not isinstance(d, str)]
    if len(pts) < 3:
        return None
    # the unconstrained fit's residual [noise variances: residual variances over the factor
    # for correlated samples]
    own = (doc["rows"] - len(doc["base_names"])) / pts[0][1]["noise_variance_factor"]["factor"]
    t = np.log([w for w, _ in pts])
    x = np.log([own + c["fit_increase_noise_variances"] for _, c in pts])
    y = np.log([c["prior_divergence"] for _, c in pts])
    dx, dy = np.gradient(x, t), np.gradient(y, t)
    ddx, ddy = np.gradient(dx, t), np.gradient(dy, t)
    kappa = (dx * ddy - dy * ddx) / np.maximum(dx**2 + dy**2, 1e-300) ** 1.5
    return float(pts[int(np.argmax(kappa))][0])


def link_masses(ce) -> str:
    """Per link: the consistent estimate's mass and its standard deviation beside the
    description's, and whether the data or the prior determine the mass; ``ok`` when the mass is
    within a factor 3 of the description's or determined by the data (target), else ``MISSED``.
    """
    choice = ce.get("prior_weight_choice")
    lines = [
        f"  prior weight {ce['prior_weight']:g}"
        + (
            " (chosen: "
            + ", ".join(
                f"{w:g}: {e:.1f}" for w, e in zip(choice["candidates"], choice["log_evidence"])
            )
            + " log marginal likelihood relative to the largest)"
            if choice
            else " (given)"
        )
    ]
    for lk in ce.get("links") or []:
        m, m0 = lk["mass"], lk["description_mass"]
        near = m0 > 0 and m0 / 3 <= m <= 3 * m0
        data = lk["mass_verdict"] == "data"
        ok = "ok" if near or data else "MISSED"
        lines.append(
            f"  {lk['link']:<16} mass {m:8.3f} +- {lk['mass_std']:.3g} kg, description "
            f"{m0:8.3f} kg, mass by {lk['mass_verdict']:<10}"
            + (
                f" (data's +- {lk['mass_data_std']:.3g} kg)"
                if lk["mass_verdict"] in ("data", "data+prior")
                else ""
            )
            + f" fit worse by {lk['mass_fit_increase']:.3g} at the description's, "
            f"link {lk['verdict']:<6} {ok}"
        )
    return "\n".join(lines)


def consistent_row(name, doc, wall, robot_path, log_path):
    """The consistent estimate's figures of one case, and a forward simulation along the log."""
    import mindyn
    import numpy as np
    from mindyn.control import simulate
    from mindyn.identification import read_csv

    ce = doc["consistent_estimate"]
    eig = min(doc["pseudo_inertia_min_eig"].values())
    print(link_masses(ce))
    vu = 100 * doc["validation"]["overall_relative"]
    vc = 100 * ce["validation"]["overall_relative"]
    robot = mindyn.load(str(robot_path))
    names = robot.parameter_names(rotor=doc["rotor"], friction=doc["friction"])
    params = np.array([doc["classical"][nm] for nm in names])
    data = read_csv(log_path, robot=robot, filter="butter")
    span = data.t[-1] - data.t[0]
    try:
        log = simulate(robot, data, rate=data.rate, duration=span, params=params)
        ref = simulate(robot, data, rate=data.rate, duration=span, friction=True)
        err = float(np.max(log.info["max_tracking_error"]))
        err0 = float(np.max(ref.info["max_tracking_error"]))
        if not np.all(np.isfinite(log.q)):
            verdict = "DIVERGED"
        else:
            verdict = "stable" if err <= max(0.05, 2 * err0) else "WORSE"
        sim = f"{verdict} {err:.2g} ({err0:.2g})"
    except ValueError as e:
        sim = f"failed: {e}"[:40]
    return (
        name,
        f"{eig:.2g}",
        fmt(vu),
        fmt(vc),
        f"{vc / vu:.3f}",
        f"{doc['total_mass']:.2f}",
        f"{ce['seconds']:.2f}",
        f"{wall:.2f}",
        f"{ce['mass_matrix_min_eig']:.3g}",
        sim,
    )


if __name__ == "__main__":
    sys.exit(main())
