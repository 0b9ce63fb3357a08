"""Identification reports: plots (matplotlib, Agg backend, PNG files) and terminal tables."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .. import _args
from .validation import norm

__all__ = ["format_table", "plot_torques", "write_report"]

# The ZCR07S study, Table 6: RMS torque error [N m] of the identified ZCR07S model, per joint, on
# the excitation and the validation trajectory (measured on the real robot).
ZCR07S_STUDY_TABLE6 = {
    "excitation": [4.1301, 4.3332, 2.3701, 2.4848, 1.1972, 0.4701],
    "validation": [7.6313, 6.1961, 3.4130, 2.7433, 1.1433, 0.4757],
}


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_torques(path, t, tau, tau_hat, *, title: str = "", unit: str = "N m") -> Path:
    """Measured and estimated torque per joint, one panel each (as the ZCR07S study, Fig. 6-7).
    ``t`` (m,), ``tau``, ``tau_hat`` (m, n)."""
    _args.path(path, "path")
    t = _args.array(t, "t", (None,))
    tau = _args.array(tau, "tau", (t.shape[0], None))
    tau_hat = _args.array(tau_hat, "tau_hat", tau.shape)
    _args.text(title, "title", empty=True)
    _args.text(unit, "unit")
    plt = _pyplot()
    n = tau.shape[1]
    cols = 2 if n > 3 else 1
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(6 * cols, 2.1 * rows + 0.8), sharex=True)
    axes = np.atleast_1d(axes).reshape(-1)
    for k in range(n):
        ax = axes[k]
        rms = float(norm(tau[:, k] - tau_hat[:, k])) / math.sqrt(max(len(tau), 1))
        ax.plot(t, tau[:, k], lw=0.7, color="0.55", label="measured")
        ax.plot(t, tau_hat[:, k], lw=1.0, color="C3", label="estimated")
        ax.set_title(f"joint {k + 1}   RMS error {rms:.3g} {unit}", fontsize=9)
        ax.grid(alpha=0.3)
        ax.set_ylabel(f"[{unit}]", fontsize=8)
    for ax in axes[n:]:
        ax.set_visible(False)
    axes[0].legend(fontsize=7, loc="upper right")
    for ax in axes[max(0, n - cols) : n]:
        ax.set_xlabel("t [s]")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def format_table(result, *, truth=None) -> str:
    """Terminal table of an :class:`~mindyn.identification.IdentificationResult`: name,
    estimate, standard deviation, RSD and, when ``truth`` (base values, shape (nb,)) is given,
    the true value and the relative error (``-`` for a true value of 0)."""
    from .consistent import ConsistentResult
    from .estimation import PRUNING_STD_LISTED, IdentificationResult

    _args.instance(result, "result", (IdentificationResult, ConsistentResult))
    truth = _args.optional(_args.array, truth, "truth", (result.base.n,))
    names = list(result.base.names)
    width = max(8, max(len(n) for n in names))
    head = f"{'#':>3}  {'parameter':<{width}} {'estimate':>13} {'std':>11} {'RSD %':>8}"
    if truth is not None:
        head += f" {'true':>13} {'error %':>9}"
    lines = [head]
    kept = {n: i for i, n in enumerate(result.names)}
    for b, name in enumerate(names):
        if name not in kept:
            continue
        i = kept[name]
        rsd = result.rsd[i]
        line = (
            f"{b + 1:>3}  {name:<{width}} {result.values[i]:>13.6g} {result.std[i]:>11.3g} "
            f"{rsd:>8.2f}"
            if math.isfinite(rsd)
            else f"{b + 1:>3}  {name:<{width}} {result.values[i]:>13.6g} {result.std[i]:>11.3g} "
            f"{'inf':>8}"
        )
        if truth is not None:
            tv = truth[b]
            # a true value of 0 has no relative error
            err = f"{100 * abs(result.values[i] - tv) / abs(tv):>9.3g}" if tv != 0 else f"{'-':>9}"
            line += f" {tv:>13.6g} {err}"
        lines.append(line)
    if result.removed:
        lines.append("")
        lines.append(
            f"removed (RSD > {result.rsd_threshold:g} %), in order: "
            + ", ".join(
                f"{n} ({r:.0f} %)" if math.isfinite(r) else f"{n} (inf)" for n, r in result.removed
            )
        )
        wide = getattr(result, "settings", {}).get("pruning_std", {})
        if wide.get("listed"):
            lines.append(
                f"std with the removed parameters free (the fit with all base parameters): "
                f"{wide['listed']} kept estimate(s) above {PRUNING_STD_LISTED:g} x their std, "
                + ", ".join(
                    f"{n} ({r:.3g} x)" if r is not None else f"{n} (inf)"
                    for n, r in wide["largest"]
                )
                + (", ..." if wide["listed"] > len(wide["largest"]) else "")
                + "; as estimates of the base parameters they carry what the removed ones "
                "contribute"
            )
    return "\n".join(lines)


def _tau_hats(pred, logs, result) -> list:
    """Predicted torques per log from what the caller has: None, an array (one log), a list of
    arrays, or a :func:`~mindyn.identification.validate` result."""
    if pred is None:
        return [result.predict(d) for d in logs]
    if isinstance(pred, dict):
        pred = pred["tau_hat"]
    return [pred] if isinstance(pred, np.ndarray) else list(pred)


def _name(data) -> str:
    return Path(data.source).name if data.source else "data"


def write_report(
    directory,
    result,
    data,
    *,
    validation_data=None,
    validation=None,
    fit=None,
    trajectory_limits=None,
    estimate: str | None = None,
) -> list[Path]:
    """Writes the PNG plots of a report folder: measured vs estimated torques on the
    identification data (and on the validation data), and the joint trajectory of the
    identification data. ``data`` and ``validation_data`` are one log or a list of logs; with
    several, each gets its own plots (``torque_identification_2.png``, ...). ``fit`` and
    ``validation`` are the results of :func:`~mindyn.identification.validate` (or the predicted
    torques); a plot's title gives the log's overall relative errors when they are (filtered,
    raw and moving, see :func:`~mindyn.identification.validate`), and ``estimate``, when given,
    which estimate ``result`` is (``"consistent"``). Returns the paths written."""
    from .consistent import ConsistentResult
    from .estimation import IdentificationResult, _logs

    _args.path(directory, "directory")
    _args.instance(result, "result", (IdentificationResult, ConsistentResult))
    _logs(data)
    if not (validation_data is None or isinstance(validation_data, list) and not validation_data):
        _logs(validation_data, "validation_data")
    _args.optional(_args.mapping, trajectory_limits, "trajectory_limits")
    _args.optional(_args.choice, estimate, "estimate", ("unconstrained", "consistent"))
    from .excitation import plot_trajectory

    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    out = []
    tag = f"{result.base.robot.name}, {result.model} model" + (
        f", {estimate} estimate" if estimate else ""
    )

    def series(kind, logs, measures, pred):
        hats = _tau_hats(pred, logs, result)
        per = measures["logs"] if isinstance(measures, dict) and "logs" in measures else None
        for k, (log, hat) in enumerate(zip(logs, hats)):
            suffix = "" if k == 0 else f"_{k + 1}"
            err = ""
            if per is not None and np.isfinite(per[k]["overall_relative"]):
                err = f", relative error {100 * per[k]['overall_relative']:.2f} % filtered"
                for name in ("raw", "moving"):
                    m = per[k].get(name)
                    if m is not None and np.isfinite(m["overall_relative"]):
                        err += f", {100 * m['overall_relative']:.2f} % {name}"
            out.append(
                plot_torques(
                    d / f"torque_{kind}{suffix}.png",
                    log.t,
                    log.tau,
                    hat,
                    title=f"{tag}: {kind} data ({_name(log)}){err}",
                )
            )

    logs = [data] if not isinstance(data, (list, tuple)) else list(data)
    series("identification", logs, fit, fit)
    if validation_data is not None and validation is not None:
        vlogs = (
            [validation_data]
            if not isinstance(validation_data, (list, tuple))
            else list(validation_data)
        )
        if vlogs:
            series("validation", vlogs, validation, validation)
    for k, log in enumerate(logs):
        out.append(
            plot_trajectory(
                d / f"trajectory{'' if k == 0 else f'_{k + 1}'}.png",
                log.t,
                log.q,
                log.dq,
                log.ddq,
                limits=trajectory_limits,
                title=f"{result.base.robot.name}: excitation trajectory (identification data"
                + (f", {_name(log)})" if len(logs) > 1 else ")"),
            )
        )
    return out
