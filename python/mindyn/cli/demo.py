"""CLI: ``mindyn demo`` -- the whole chain on one robot, every file in one folder.

base parameters -> optimised excitation -> simulated measurement with noise -> identification
(dynamic, integral and energy models) -> validation on a second trajectory -> generated code.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from ..base import base_parameters
from ..robot import bundled_robots, load
from .args import ZCR07S_STUDY, add_command, deprecated
from .number_options import number, seed
from .outputs import output_dir
from .robot_options import require_single_dof, robot_arg


def _step(no: int, title: str) -> float:
    print(f"\n[{no}] {title}", flush=True)
    return time.perf_counter()


def _done(t0: float) -> None:
    print(f"    ({time.perf_counter() - t0:.1f} s)", flush=True)


def _joints(values, fmt: str = "{:8.3g}") -> str:
    return " ".join(fmt.format(v) for v in values)


def cmd_demo(args: argparse.Namespace) -> int:
    from ..control.simulation import (
        SensorNoise,
        error_unit,
        noise_from_spec,
        simulate,
        torque_noise_scale,
        torque_unit,
    )
    from ..identification import load_logs, run, true_base_values
    from ..identification.data import convert_torque, write_csv
    from ..identification.excitation import (
        excitation_limits,
        optimize_excitation,
        random_trajectory,
    )
    from ..identification.report import ZCR07S_STUDY_TABLE6, format_table, plot_torques
    from ..identification.validation import prediction_check, validate

    t_all = time.perf_counter()
    robot = load(args.robot)
    require_single_dof(robot, "demo")
    out = Path(args.out or f"mindyn-demo-{robot.name}")
    out.mkdir(parents=True, exist_ok=True)
    print(f"mindyn demo: {robot.name} ({robot.n} joints), files in {out}/")
    if robot.synthetic_inertia:
        print("    (the description's inertial values are synthetic: they play the true robot)")

    # 1. base parameters ------------------------------------------------------------------------
    t0 = _step(1, "base parameters (projection method, with rotor inertia and friction)")
    base = base_parameters(robot, rotor=True, friction=True)
    counts = {k: s["n"] for k, s in base.sets.items()}
    print(
        f"    {base.n} base parameters of {len(base.classical_names)} classical "
        f"(Lagrangian {counts['lagrangian']}, energy {counts['energy']}, equations of motion "
        f"{counts['eom']}); computed in {base.seconds * 1e3:.1f} ms"
    )
    print("    " + " ".join(base.names))
    (out / "base_parameters.json").write_text(json.dumps(base.to_dict(), indent=2) + "\n")
    _done(t0)

    # 2. excitation -------------------------------------------------------------------------------
    full = args.full
    t0 = _step(2, f"excitation trajectory ({'full' if full else 'quick'} optimisation)")
    exc = optimize_excitation(
        robot,
        base=base,
        harmonics=args.harmonics,
        freq=0.1,
        criterion="cond",
        starts=6 if full else 2,
        maxiter=150 if full else 30,
        seed=args.seed,
        progress=True,
    )
    paths = exc.save(out / "excitation.csv")
    print(
        f"    condition number of the stacked base regressor {exc.initial_value:.4g} -> "
        f"{exc.value:.4g}; {args.harmonics} harmonics, 0.1 Hz, 10 s; wrote {paths['csv'].name}, "
        f"{paths['json'].name}, {paths['png'].name}"
    )
    lim, _ = excitation_limits(robot)
    val_traj = random_trajectory(robot, seed=args.seed + 1000, limits=lim)
    t = np.linspace(0, val_traj.period, 1001)
    (out / "validation_trajectory.json").write_text(
        json.dumps({"trajectory": val_traj.to_dict()}, indent=2) + "\n"
    )
    from ..identification.excitation import criterion_value

    print(
        f"    validation trajectory: random Fourier series within the limits (condition number "
        f"{criterion_value(base, *val_traj.evaluate(t[::10]), criterion='cond'):.4g})"
    )
    _done(t0)

    # 3. simulated measurement -------------------------------------------------------------------
    t0 = _step(3, "simulated measurement (true parameters, computed-torque tracking at 250 Hz)")
    ref_tau = robot.inverse_dynamics(*exc.trajectory.evaluate(t[::5]))
    sd = noise_from_spec(f"{args.noise:g}%", robot, "torque", reference_torque=ref_tau)
    noise = SensorNoise(torque=sd, quantization=2 * np.pi / 2**20)
    kw: dict[str, Any] = dict(rotor=True, friction=True, noise=noise, rate=250.0)
    log_e = simulate(robot, exc.trajectory, seed=args.seed + 1, **kw)
    log_v = simulate(robot, val_traj, seed=args.seed + 2, **kw)
    permille = bool(np.isfinite(robot.drives["rated_torque"]).all()) and bool(
        np.isfinite(robot.drives["gear_ratio"]).all()
    )
    files = {}
    for name, log in (("measurement", log_e), ("validation", log_v)):
        p = log.save(out / f"{name}.csv", robot_name=robot.name)
        if permille:  # torques as the ZCR07S study's controller logs them: per mille of rated
            scale, _ = convert_torque(np.ones((1, robot.n)), "permille", robot)
            write_csv(p, log.t, log.q, log.tau / scale, dq=log.dq, torque_unit="permille")
        files[name] = p
    print(
        f"    torque noise sd per joint ({args.noise:g} % of "
        f"{torque_noise_scale(robot, ref_tau)[2]}) [{torque_unit(robot.joint_types)}]: "
        f"{_joints(sd)}; 20-bit encoder"
    )
    print(
        f"    max tracking error per joint [{error_unit(robot.joint_types)}]: "
        + _joints(log_e.max_error_deg())
    )
    print(
        f"    wrote {files['measurement'].name}, {files['validation'].name} ({log_e.t.size} "
        "samples each: t, q, dq, tau"
        + (
            ", torques in per mille of rated torque as in the ZCR07S study (header "
            "tau1[permille]...)"
            if permille
            else ""
        )
        + ") and their .truth.json"
    )
    _done(t0)

    # 4. identification ---------------------------------------------------------------------------
    t0 = _step(4, "identification (weighted least squares, RSD pruning at 30 %)")
    # the torque unit from the header; derivatives by a zero-phase Butterworth filter
    logs = load_logs([files["measurement"]], robot, validate=[files["validation"]], filter="butter")
    # the window models take the held command by their integration rule, not read as held
    window_logs = load_logs(
        [files["measurement"]],
        robot,
        validate=[files["validation"]],
        filter="butter",
        model="integral",
    )
    data, vdata = logs.fit.logs[0], logs.validation.logs[0]
    dv = data.processing["acceleration"]
    held_torque = "held" in data.processing["torque"]
    print(
        f"    read {data.m} samples, torques in {data.processing['torque']['unit']} (as the "
        "header says)"
        + (
            ", the command held over each period (as the .truth.json says: the dynamic model "
            "takes it at the middle of its period, the window models by --integration zoh; "
            "every model is scored against it at the samples)"
            if held_torque
            else ""
        )
        + f"; accelerations by Butterworth order {dv['order']}, "
        f"{dv['cutoff_Hz']:g} Hz, zero-phase, + central differences"
    )
    truth = true_base_values(base, {"names": log_e.param_names, "values": log_e.params})
    results = {}
    for model in ("dynamic", "integral", "energy"):
        held: dict[str, Any] = {} if model == "dynamic" else {"integration": "zoh"}  # windows'
        # the study's pruning (the library's default keeps a t-statistic above sqrt(2))
        rep = run(
            robot,
            logs if model == "dynamic" else window_logs,
            model=model,
            rotor=True,
            friction=True,
            rsd_threshold=30.0,
            **held,
        )
        res, fit, val = rep.result, rep.fit, rep.validation
        if model != "dynamic" and held_torque:
            # scored as the dynamic model is: against the held torque at the samples
            fit = validate(res, logs.fit.logs)
            fit["prediction_uncertainty"].update(prediction_check(res, fit, logs.fit.logs))
            val = validate(res, logs.validation.logs)
        assert fit is not None and val is not None  # the demo always validates
        results[model] = (res, fit, val)
        kept = len(res.names)
        err = np.abs(res.full - truth)
        print(
            f"    {model:8s} model: {res.rows} equations, {base.n} estimated, {kept} kept "
            f"({len(res.removed)} removed), scaled condition number {res.cond:.3g}, "
            f"{res.seconds:.2f} s"
        )
        unit = torque_unit(robot.joint_types)
        print(f"      {f'RMS error [{unit}], identification data:':<40}{_joints(fit['rms'])}")
        print(f"      {f'RMS error [{unit}], validation data:':<40}{_joints(val['rms'])}")
        print(
            "      overall relative error |tau - tau_hat| / |tau|: identification "
            f"{100 * fit['overall_relative']:.2f} %, "
            f"validation {100 * val['overall_relative']:.2f} %"
        )
        unc = fit["prediction_uncertainty"]
        print(
            f"      predicted torques determined to +-{100 * unc['overall_relative']:.2f} % "
            f"(identification), +-"
            f"{100 * val['prediction_uncertainty']['overall_relative']:.2f} % (validation)"
        )
        if unc["warning"]:
            print(f"      WARNING: {unc['warning']}")
        big = np.argsort(-np.abs(truth))[:3]
        print(
            "      largest base parameters, estimate / true: "
            + ", ".join(f"{base.names[b]} {res.full[b]:.4g} / {truth[b]:.4g}" for b in big)
        )
        (out / f"identification_{model}.txt").write_text(format_table(res, truth=truth) + "\n")
        doc = res.to_dict()
        doc["fit"] = {"overall_relative": fit["overall_relative"], "rms": fit["rms"].tolist()}
        doc["validation"] = {
            "overall_relative": val["overall_relative"],
            "rms": val["rms"].tolist(),
            "relative": val["relative"].tolist(),
        }
        doc["true_values"] = truth.tolist()
        doc["max_abs_error"] = float(err.max())
        (out / f"identification_{model}.json").write_text(json.dumps(doc, indent=2) + "\n")
        plot_torques(
            out / f"torque_identification_{model}.png",
            data.t,
            data.tau,
            fit["tau_hat"][0],
            title=f"{robot.name}, {model} model: excitation trajectory",
        )
        plot_torques(
            out / f"torque_validation_{model}.png",
            vdata.t,
            vdata.tau,
            val["tau_hat"][0],
            title=f"{robot.name}, {model} model: validation trajectory",
        )
    unit = torque_unit(robot.joint_types)
    print(f"    {f'noise sd (reference) [{unit}]:':<42}{_joints(sd)}")
    if robot.name == "zcr07s":
        print(f"    RMS torque errors on the real robot in {ZCR07S_STUDY}, Table 6:")
        print(
            "    ZCR07S study, excitation [N m]:           "
            + _joints(ZCR07S_STUDY_TABLE6["excitation"])
        )
        print(
            "    ZCR07S study, validation [N m]:           "
            + _joints(ZCR07S_STUDY_TABLE6["validation"])
        )
    print(
        "    wrote identification_{dynamic,integral,energy}.{json,txt} and "
        "torque_{identification,validation}_{dynamic,integral,energy}.png"
    )
    _done(t0)

    # 5. generated code ---------------------------------------------------------------------------
    t0 = _step(5, "generated code")
    _codegen(args.robot, out)
    _done(t0)
    print(f"\ndone in {time.perf_counter() - t_all:.1f} s; everything is in {out}/")
    return 0


def _codegen(robot_arg: str, out: Path) -> None:
    """Generates the inverse dynamics, gravity and base regressor in C and Structured Text, as
    ``mindyn codegen ROBOT --rotor --friction`` does, when this build has the code generator."""
    try:
        from ..codegen import generate
    except ImportError:
        print("    unavailable: this build of mindyn has no code generator (mindyn.codegen)")
        return
    from .codegen import operation_table

    robot = load(robot_arg)
    base = base_parameters(robot, rotor=True, friction=True)
    tables = {}
    for lang, ext in (("c", "c"), ("st", "st")):
        target = out / f"inverse_dynamics.{ext}"
        same: dict[str, Any] = dict(lang=lang, rotor=True, friction=True)
        code = generate(robot, base=base, header_name="inverse_dynamics.h", **same)
        classical = generate(robot, base=False, name=code.name, **same)
        code.write(target)
        tables[lang] = operation_table(code, classical)
        print(f"    wrote {target.name}")
    if "c" in tables and tables.get("st", tables["c"]) == tables["c"]:
        print("    operation counts (C and Structured Text alike):")
        print("\n".join("      " + line for line in tables["c"]))
    else:
        for lang, table in tables.items():
            print(f"    operation counts ({'C' if lang == 'c' else 'Structured Text'}):")
            print("\n".join("      " + line for line in table))


def register(sub) -> None:
    """Adds ``demo`` to the ``mindyn`` subcommands."""
    p = add_command(
        sub,
        "demo",
        description="Runs the identification chain end to end on a robot (default zcr07s) and "
        "puts every file in one folder: base parameters, an optimised excitation trajectory, a "
        "simulated noisy measurement of the robot tracking it (and of a validation trajectory), "
        "identification with the dynamic, integral and energy models, validation, plots, and "
        "generated code when this build has the code generator.",
    )
    p.add_argument(
        "robot",
        nargs="?",
        type=robot_arg,
        default="zcr07s",
        metavar="ROBOT",
        help="a bundled robot (" + ", ".join(bundled_robots()) + "), URDF or YAML; default zcr07s",
    )
    p.add_argument(
        "--out",
        metavar="DIR",
        type=output_dir,
        help="output folder (default ./mindyn-demo-ROBOT)",
    )
    p.add_argument("--full", action="store_true", help="full excitation optimisation (slower)")
    number(
        p,
        "--harmonics",
        low=2,
        high=30,
        integer=True,
        default=10,
        help=f"harmonics of the excitation ({ZCR07S_STUDY} uses 5, enough for the dynamic "
        "model but not for the energy model, whose regressor needs richer motion)",
    )
    noise = number(
        p,
        "--torque-noise",
        dest="noise",
        metavar="PERCENT",
        low=0,
        high=100,
        default=1.0,
        suffix="%",
        help="torque noise sd in % (P or P%) of each joint's effort limit (of its peak torque "
        "along the excitation where the description gives none or a placeholder, as "
        "simulate's --torque-noise P%)",
    )
    deprecated(p, "--noise", noise)
    seed(p, "--seed")
    p.set_defaults(func=cmd_demo)
