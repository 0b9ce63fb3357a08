"""Which constraint of the physically consistent estimate costs validation accuracy on a log.

For one robot description, its identification log(s) and a validation log (read as ``mindyn
identify`` reads them by default: zero-phase low-pass, the validation log at the fit's cut-off),
with viscous and Coulomb friction and torque offsets (and rotor inertia with ``--rotor``), the
consistent estimate without a prior (``--prior-weight 0``: the closest the consistent set comes
to the data) is solved again with one group of constraints released at a time:

- ``Ia, Fv, Fc >= 0`` (rotor inertia and friction non-negative);
- each link's pseudo-inertia positive semidefinite (the link's LMI), one link at a time;
- every link's LMI at once.

Each line prints the validation error relative to the unconstrained estimate's (the ratio the
consistent estimate is held to, target at most 1.1), and the fit term's increase over the
unconstrained optimum in noise variances. With ``--rotor`` the unconstrained estimate's rotor
inertias are printed with their standard deviations first: a rotor inertia significantly below
zero is a direction no physical drive has, which the consistent estimate must refuse.

Run: ``.venv/bin/python bench/bench_consistent_constraints.py ROBOT FIT.csv [FIT2.csv ...]
--validate VAL.csv [--rotor]``, e.g. with the Panda of the real logs' folder,
``DIR/panda/panda_gaz2019.yaml DIR/panda/panda_gaz2019_traj1_fit_period1.csv --validate
DIR/panda/panda_gaz2019_traj1_val_repeat.csv``.
"""

from __future__ import annotations

import argparse
import dataclasses

import cvxpy as cp
import mindyn
import mindyn.identification.consistent as C
import numpy as np
from mindyn.identification import identify, read_csv, validate
from mindyn.identification.preprocess import preprocess, split_at_gaps


def read(path, robot, cutoff=None):
    """The log as ``mindyn identify`` reads it by default (cut at breaks, each segment
    low-pass filtered, its edges dropped and decimated)."""
    return [
        preprocess(seg, cutoff=cutoff)
        for seg in split_at_gaps(read_csv(path, robot=robot, filter="none"))
    ]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("robot")
    ap.add_argument("data", nargs="+")
    ap.add_argument("--validate", required=True)
    ap.add_argument("--rotor", action="store_true")
    args = ap.parse_args()
    robot = mindyn.load(args.robot)
    logs = [d for f in args.data for d in read(f, robot)]
    cut = max(d.processing["preprocess"]["filter"]["cutoff_Hz"] for d in logs)
    vlogs = read(args.validate, robot, cutoff=cut)
    base = mindyn.base_parameters(robot, rotor=args.rotor, friction=True, offset=True)
    res = identify(robot, logs, base=base)
    vu = validate(res, vlogs)["overall_relative"]
    print(f"{robot.name}: unconstrained validation {100 * vu:.3f} %")
    if args.rotor:
        full = identify(robot, logs, base=base, rsd_threshold=None)
        for nm, v, s in zip(full.names, full.values, full.std):
            if nm.startswith("Ia"):
                print(f"  {nm} = {v:.4g} +- {s:.2g} kg m^2 ({v / s:+.1f} standard deviations)")
    cons0 = C.consistent_estimate(res, prior_weight=0)
    ls, b = res.reduced, res.base
    Y = b.Y
    M, z = (ls.R * ls.norms) @ Y, ls.z
    nb = b.n
    s2 = max(ls.rho / max(ls.r - nb, 1), 1e-300)
    beta = ls.solve(list(range(nb)))[0]
    best = float(np.sum((ls.R @ (beta * ls.norms) - z) ** 2))
    pi0 = C.description_vector(b)
    variable = cp.Variable

    def released(links=(), nonneg=True) -> tuple[float, float]:
        count = [0]

        def var(*a, **k):
            if k.get("PSD"):
                j = count[0]
                count[0] += 1
                if j in links:
                    k = {**{x: y for x, y in k.items() if x != "PSD"}, "symmetric": True}
            return variable(*a, **k)

        lay = C._Layout(b)
        if not nonneg:
            lay.nonneg[:] = False
        cp.Variable = var
        try:
            pi = C._solve(b, lay, M, z, s2, pi0, 0, [], beta)[0]
        finally:
            cp.Variable = variable
        c = dataclasses.replace(cons0, classical=pi, full=Y @ pi)
        v = validate(c, vlogs)["overall_relative"]
        return v, (float(np.sum((M @ pi - z) ** 2)) - best) / s2

    rows = [("all constraints (the consistent estimate, no prior)", (), True)]
    rows.append(("released: Ia, Fv, Fc >= 0", (), False))
    rows += [(f"released: the LMI of link {j + 1}", (j,), True) for j in range(robot.n)]
    rows.append(("released: every link's LMI", tuple(range(robot.n)), True))
    for label, links, nonneg in rows:
        v, rise = released(links, nonneg)
        print(
            f"  {label:<54} validation {100 * v:6.3f} %, ratio {v / vu:5.3f}, fit worse by "
            f"{rise:8.1f} noise variances"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
