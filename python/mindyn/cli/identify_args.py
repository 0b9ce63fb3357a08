"""The options of ``mindyn identify`` and ``mindyn identify-payload`` (run by
:mod:`mindyn.cli.identify`): how a log is read and pre-processed (shared), what is identified
and how, what is written."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..identification.options import DEFAULT_RSD_THRESHOLD
from ..robot import FRICTION_KINDS
from .args import add_command, deprecated, remember_flags
from .columns import add_columns
from .number_options import Number, joint_vector, number
from .outputs import add_description_outputs, output_dir, output_file
from .robot_options import add_joint_terms, add_offset, add_robot, add_snap

#: The models of ``identify`` on a floating-base robot (free-flyer or planar root).
FLOATING_MODELS = ("full", "base")


def add_data_options(p) -> None:
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
        "T^T (K_t x current) (default: the transmissions' torque constants). A negative gain "
        "is kept as a sign convention: that motor's positive current drives its joint "
        "backwards (a motor wired or mounted reversed); zero is refused, and so is a gain for "
        "a log of torques (N m or permille)",
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
        "accelerations, dropping the samples at each end where their filter starts up "
        "(torques unfiltered; butter and savgol refuse unevenly spaced time "
        "stamps, none differences them as they are). A floating-base log: the dq and ddq it "
        "lacks are derived by butter (lowpass too), savgol or none, torques and wrenches as "
        "logged",
    )
    number(
        p,
        "--cutoff",
        low=0,
        low_open=True,
        help="cut-off [Hz], below half the log's rate; lowpass: default 10 x the excited band of "
        "the identification log's positions (at most rate / 10), the validation log filtered at "
        "the same cut-off; butter (and a floating-base log's derivatives): default min(10, "
        "rate / 10); savgol and none have none (refused)",
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
    add_columns(p)
    p.add_argument(
        "--torque",
        choices=["sampled", "held"],
        default=None,
        help="dynamic model: the logged torque is a measurement or the command held over each "
        "sample period, as a digital controller (and simulate's tracking mode) logs it: then "
        "taken at the middle of its period (default: held for a log whose .truth.json says its "
        "simulation held it, sampled for any other; the window models take a held torque by "
        "--integration zoh)",
    )
    p.add_argument(
        "--no-decimate",
        action="store_true",
        help="lowpass, dynamic model: keep every sample (default: decimate to at least 10 x the "
        "cut-off; the integral and energy models keep every sample)",
    )


def _rsd_threshold(text: str):
    """``--rsd-threshold``'s value: ``auto`` or a percentage >= 0, its ``%`` sign optional
    (``30`` or ``30%``, as ``simulate --torque-noise`` takes a percentage)."""
    if text.strip().lower() == "auto":
        return "auto"
    number = text.strip()[:-1] if text.strip().endswith("%") else text
    try:
        return Number(0)(number)
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(
            f"expected a finite number >= 0 (a percentage, P or P%) or auto, got '{text}'"
        ) from None


_rsd_threshold.__name__ = "rsd threshold"  # argparse names the type by this


def report_files(args: argparse.Namespace) -> list[tuple[str, str, str, Path, str]]:
    """The files ``--report DIR`` writes that the command line determines (none without it),
    for the rule on outputs (:func:`~mindyn.cli.outputs.implied_outputs`): the JSON and the
    table, and per log given its torque plot and trajectory plot (a log cut at breaks adds
    plots of its further segments)."""
    folder = getattr(args, "report", None)
    if folder is None:
        return []
    names = ["identification.json", "table.txt"]
    for kind, logs in (("identification", args.data), ("validation", args.validate or [])):
        names += [f"torque_{kind}{'' if k == 0 else f'_{k + 1}'}.png" for k in range(len(logs))]
    names += [f"trajectory{'' if k == 0 else f'_{k + 1}'}.png" for k in range(len(args.data))]
    remedy = "give --report another folder"
    return [("--report", str(folder), "report file", Path(folder) / n, remedy) for n in names]


def add_identify(sub, func) -> None:
    """``mindyn identify``, run by ``func``."""
    from ..identification.consistent import MAX_PRIOR_WEIGHT
    from ..identification.prior import CANDIDATES

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
        "report. A floating-base robot (a free-flyer or planar root: --root-joint, or the root "
        "joint of a YAML table) is identified from CSV logs with contact wrenches (q1..q<nq>, "
        "[dq1..dq<nv>, ddq1..ddq<nv>], [tau1..tau<na>], <LINK>.fx, .fy, .fz, .tx, .ty, .tz per "
        "contact link; without dq and ddq, a t column to derive them) by weighted least "
        "squares, one noise level per coordinate: --model full or base, --contact, "
        "--wrench-frame, --validate, --json, --ols, --filter and --cutoff apply, the other "
        "options are refused.",
    )
    add_robot(p)
    p.add_argument(
        "data",
        nargs="+",
        metavar="LOG",
        help="CSV log (t, q1..qn, [dq1..dqn], [ddq1..ddqn], tau1..taun or currents i1..in) or "
        "ROS bag (a ROS 2 bag folder, .mcap, .db3, or a ROS 1 .bag); several logs are fitted "
        "together (derivatives taken on each log alone, regression systems stacked; each once)",
    )
    p.add_argument(
        "--model",
        choices=["dynamic", "integral", "energy", *FLOATING_MODELS],
        default=None,
        help="dynamic (the default): tau = W(q, dq, ddq) p per sample (needs accelerations); "
        "integral: each joint's equation of motion integrated over windows (momentum "
        "difference, no accelerations); energy: the energy theorem over windows (one equation "
        "per window). A floating-base robot (a free-flyer or planar root): full (the default "
        "there: W p = S^T tau + sum_c J_c^T f_c, every equation of motion, joint torques and "
        "contact wrenches) or base (the base-link model: the root's equations, contact "
        "wrenches and motion only, no joint torques)",
    )
    add_joint_terms(p, "identify")
    add_offset(p, "identify")
    add_snap(p)
    p.add_argument(
        "--validate",
        nargs="+",
        metavar="LOG",
        help="log(s) (CSV or bag) for validation, none of them a fit log",
    )
    p.add_argument("--json", metavar="FILE", type=output_file, help="write the results as JSON")
    p.add_argument(
        "--report",
        metavar="DIR",
        type=output_dir,
        help="write plots and tables to DIR: identification.json, table.txt (the "
        "JSON and the text printed), torque and trajectory plots",
    )
    p.add_argument(
        "--rsd-threshold",
        type=_rsd_threshold,
        default="auto",
        metavar="PERCENT|auto",
        help="remove parameters with RSD above this %%, largest first, re-estimating after "
        f"each removal ({DEFAULT_RSD_THRESHOLD:g} keeps a t-statistic above sqrt(2), Akaike's "
        "criterion for one parameter; 30 keeps one above 3.3; 0 keeps all); auto (the "
        f"default): {DEFAULT_RSD_THRESHOLD:g} or every base parameter, as cross-validation "
        "over blocks of the fit logs decides (printed); a finite number >= 0 (P or P%%) or "
        "auto",
    )
    add_data_options(p)
    p.add_argument(
        "--validate-currents",
        nargs="+",
        metavar="CSV",
        help="as --currents, one per --validate log",
    )
    p.add_argument(
        "--ols",
        action="store_true",
        help="ordinary instead of weighted least squares (weights per joint; on a floating-base "
        "robot, per coordinate: the root's and each joint's)",
    )
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
        f"default: the weight among {', '.join(f'{w:g}' for w in CANDIDATES)} under which the "
        "data are most probable (the marginal likelihood, the prior being a Wishart density of "
        "each pseudo-inertia about the description's; reported)",
    )
    add_description_outputs(p, "identify")
    # floating-base robots only (refused on others by cmd_identify)
    p.add_argument(
        "--contact",
        nargs="+",
        metavar="LINK",
        help="floating-base robot: the links in contact, whose wrench columns <LINK>.fx, .fy, "
        ".fz, .tx, .ty, .tz every log must carry (a log with another link's wrench is refused); "
        "default: the wrench columns each log has (none: free flight)",
    )
    p.add_argument(
        "--wrench-frame",
        choices=("world", "local"),
        default=None,
        help="floating-base robot: the axes of the logged wrenches (force, then moment about "
        "the link's origin): world (the default) or local, the link's own axes (a "
        "force/torque sensor fixed to it)",
    )
    number(
        p,
        "--energy-window",
        low=1,
        high=1000000,
        integer=True,
        default_when_unset=10,
        help="energy model: sample intervals per energy equation",
    )
    p.add_argument(
        "--integration",
        choices=["auto", "simpson", "trapezoid", "zoh"],
        help="energy and integral model integration rule (zoh: torque held over each period); "
        "default auto: simpson or zoh, whichever fit leaves the smaller residual (stated)",
    )
    number(
        p,
        "--integral-window",
        low=1,
        high=1000000,
        integer=True,
        default_when_unset=40,
        help="integral model: sample intervals per window (one equation per joint and window)",
    )
    number(
        p,
        "--min-velocity",
        low=0,
        default_when_unset=0.01,
        help=(
            "dynamic and integral models with friction: leave out joint equations slower than "
            "this [rad/s, m/s] (integral: at a sample of the window)"
        ),
    )
    p.add_argument(
        "--friction-model",
        choices=[*FRICTION_KINDS, "dahl", "auto"],
        help="friction per joint (implies --friction): coulomb Fv v + Fc sign v (the default), "
        "asymmetric + Fa |sign v| (direction-dependent Coulomb), smooth Fv v + Fc tanh(v / w) "
        "(w from the data's velocity noise unless --friction-width), stribeck + Fs sign v "
        "exp(-(v / w)^2) (w searched per joint on the fit's residual), dahl Fv v + Fc z with "
        "the presliding state dz/dq = sigma (1 - z sign v) following the filtered positions "
        "(sigma searched per joint on the fit's residual; dynamic model), or auto (the one with "
        "the smallest residual on held-out blocks of the fit logs); the choice is reported, and "
        "a fitted friction that drives the motion (f(v) v < 0 at a logged speed) warned of",
    )
    joint_vector(
        p,
        "--friction-width",
        help="--friction-model smooth or auto: the tanh width w [rad/s, m/s], positive, per "
        "joint (per motor, in the motor's units, on the motor side; or one value for all)",
    )
    p.set_defaults(func=func, implied=report_files)
    remember_flags(p)  # the floating-base command refuses the options it does not take


def add_identify_payload(sub, func) -> None:
    """``mindyn identify-payload``, run by ``func``."""
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
    add_data_options(p)
    number(
        p,
        "--min-velocity",
        low=0,
        default_when_unset=0.01,
        help="arm with friction: leave out joint equations slower than this [rad/s, m/s]",
    )
    p.add_argument(
        "--no-consistent", action="store_true", help="least squares only (no convex solve)"
    )
    p.add_argument("--json", metavar="FILE", type=output_file, help="write the results as JSON")
    p.set_defaults(func=func)


def register(sub) -> None:
    """Adds ``identify`` and ``identify-payload`` to the ``mindyn`` subcommands."""
    from .identify import cmd_identify, cmd_identify_payload

    add_identify(sub, cmd_identify)
    add_identify_payload(sub, cmd_identify_payload)
