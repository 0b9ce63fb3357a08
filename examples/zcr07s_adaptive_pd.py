"""The ZCR07S study's adaptive PD experiment on the ZCR07S, in simulation.

K_D = diag(400, 350, 130, 22, 9, 2), Lambda = diag(10, 10, 10, 30, 30, 25), adaptation gains 1,
controller period 4 ms; 52 base parameters with rotor inertia and friction, the initial estimate
off by up to +-30 % per parameter (uniform, seeded). The true robot is the bundled zcr07s model
(synthetic inertial values, rotor inertia and friction), integrated by RK4 at 1 ms with the torque
held over each period. The study's desired trajectory is not legible, so the reference is a sum of
sines within half of each joint's range and speed limit, repeated every 10 s.

Beside the adaptive controller the same run is made with the estimate frozen (Gamma = 0), with
computed torque using the same wrong estimate, and with plain PD (K_P = Lambda K_D).

With ``--generated`` the adaptive run is repeated with the generated C controller step (``mindyn
codegen --what adaptive-pd``, compiled with the system C compiler) in place of the library's
AdaptivePD, and its figures are printed beside the library's.

    python examples/zcr07s_adaptive_pd.py [REPORT_DIR] [--cycles N] [--generated]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import mindyn
import numpy as np
from mindyn import control

SEED_MAX_DEG = [0.06, 0.22, 0.34, 0.29, 0.45, 0.85]
SEED_FINAL_DEG = [-0.06, 0.02, 0.04, -0.11, -0.11, 0.09]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("report", nargs="?", default="zcr07s-report")
    ap.add_argument("--cycles", type=int, default=10, help="10 s cycles to simulate (10)")
    ap.add_argument("--error", type=float, default=0.3, help="initial estimate error (0.3)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument(
        "--generated", action="store_true", help="also run the generated C adaptive PD step"
    )
    args = ap.parse_args()
    out = Path(args.report)
    out.mkdir(parents=True, exist_ok=True)

    robot = mindyn.load("zcr07s")
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    p_true = base.values(robot.parameters(rotor=True, friction=True))
    p0 = control.perturbed_parameters(p_true, args.error, seed=args.seed)
    gains = control.default_gains(robot, rotor=True)  # the study's (the robot has its rotors)
    cycle = 10.0
    ref = control.SumOfSines(robot, period=cycle, seed=args.seed)
    duration = cycle * args.cycles

    runs = {
        "adaptive-pd": control.make_controller("adaptive-pd", robot, gains, p0, base=base),
        "frozen-estimate": control.make_controller(
            "adaptive-pd", robot, dict(gains, gamma=0.0), p0, base=base
        ),
        "computed-torque": control.make_controller("computed-torque", robot, gains, p0, base=base),
        "pd": control.make_controller("pd", robot, gains),
    }
    if args.generated:
        from mindyn import codegen

        code = codegen.generate_controller(robot, "adaptive-pd", base=base, gains=gains, params=p0)
        runs["generated-adaptive-pd"] = codegen.CompiledController(code, base)
        step = code.counts["step"]
        print(f"generated adaptive PD step: {step['mul']} mul, {step['add']} add per step")
    summaries = {}
    for name, ctl in runs.items():
        result = control.simulate(
            robot,
            ref,
            ctl,
            rate=250.0,
            duration=duration,
            substeps=4,
            rotor=True,
            friction=True,
            endpoint=False,
        )
        header = {"run": name, "param_error": args.error, "seed": args.seed}
        summaries[name] = control.write_tracking_report(
            result, out / name, cycle=cycle, header=header
        )
        summaries[name]["max_error_last_cycle_deg"] = result.max_error_deg(
            t_from=duration - cycle
        ).tolist()
        print(f"{name}: done")

    def fmt(v, p=3):
        return " ".join(f"{x:7.{p}f}" for x in v)

    a = summaries["adaptive-pd"]
    lines = [
        "# The ZCR07S study adaptive PD on the ZCR07S, simulated",
        "",
        f"{base.n} base parameters (rotor inertia, friction); initial estimate = true x (1 + "
        f"{args.error:g} u), u ~ U[-1, 1], seed {args.seed}; reference: sum of sines, {cycle:g} s "
        f"cycle, {args.cycles} cycles; K_D, Lambda, Gamma = 1, 4 ms as in the study.",
        "",
        "```",
        f"{'joint':<36}" + " ".join(f"{k:>7d}" for k in range(1, 7)),
        f"{'the ZCR07S study, max |e| (real robot) [deg]':<36}{fmt(SEED_MAX_DEG, 2)}",
        f"{'adaptive PD, max |e| [deg]':<36}{fmt(a['max_error_deg'])}",
        f"{'adaptive PD, max |e| last cycle':<36}{fmt(a['max_error_last_cycle_deg'])}",
        f"{'the ZCR07S study, final error [deg]':<36}{fmt(SEED_FINAL_DEG, 2)}",
        f"{'adaptive PD, final error [deg]':<36}{fmt(a['final_error_deg'])}",
    ]
    if args.generated:
        gen = summaries["generated-adaptive-pd"]
        lines.insert(-2, f"{'generated C adaptive PD, max |e|':<36}{fmt(gen['max_error_deg'])}")
        lines.append(f"{'generated C, final error [deg]':<36}{fmt(gen['final_error_deg'])}")
    for name in ("frozen-estimate", "computed-torque", "pd"):
        lines.append(f"{name + ', max |e| [deg]':<36}{fmt(summaries[name]['max_error_deg'])}")
    lines.append("")
    lines.append("RMS position error per cycle [deg] (all joints), adaptive / frozen / PD:")
    for k in range(args.cycles):
        row = [
            np.sqrt(np.mean(np.square(summaries[n]["rms_error_deg_per_cycle"][k])))
            for n in ("adaptive-pd", "frozen-estimate", "pd")
        ]
        tp = np.sqrt(np.mean(np.square(a["torque_prediction_rms_per_cycle"][k])))
        lines.append(
            f"  cycle {k + 1:2d}: {row[0]:.4f} / {row[1]:.4f} / {row[2]:.4f}   "
            f"torque prediction error |Y (p_hat - p)| RMS {tp:.3f} N m"
        )
    pe = a["parameter_error_norm"]
    lines.append(f"parameter error |p_hat - p|: {pe[0]:.3f} at 0 s -> {pe[-1]:.3f} at the end")
    lines.append("```")
    text = "\n".join(lines)
    (out / "summary.md").write_text(text + "\n")
    (out / "summaries.json").write_text(json.dumps(summaries, indent=2) + "\n")
    print(text)


if __name__ == "__main__":
    main()
