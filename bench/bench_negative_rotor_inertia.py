"""Where negative rotor inertias of an unconstrained estimate come from: torque lag, velocity
source, cut-off, friction model, per-joint position terms.

A rotor inertia ``Ia_j`` fitted significantly below zero is inertia about joint axis ``j`` that
no body has; the physically consistent estimate must refuse it, which costs it validation
accuracy. For one robot description, its identification log(s) and a validation log (read as
``mindyn identify`` reads them by default: zero-phase low-pass, the validation log at the fit's
cut-off), with viscous and Coulomb friction and torque offsets, this measures which change of the
data path or of the model moves that direction:

1. **Torque lag.** The logged torques are shifted in time, ``tau(t) <- tau(t + d)`` (linear
   interpolation on the logged stamps; ``d > 0`` undoes torques lagging the motion by ``d``),
   before the data path, over a grid of ``d`` (default: 41 points, half a median sample interval
   apart). At each ``d`` the weighted residual of the least squares (all base parameters with
   rotor inertia, per-joint weights fixed at those of ``d = 0``) is printed, in noise variances;
   the lag is the minimum of a parabola through the best grid point and its neighbours, with a
   standard deviation from its curvature that assumes white residuals (a lower bound: the
   filtered residuals are correlated). The same search on the validation log alone gives a second,
   independent estimate; their difference is the honest measure of confidence.
2. At ``d = 0`` and at the fit log's lag: fit and validation errors (without rotor inertia, as
   ``mindyn identify --friction --offset``), the consistent estimate's validation error relative
   to the unconstrained one (prior weight chosen from the data, and without a prior), and the
   rotor inertias with their standard deviations (``t``: value over standard deviation).
3. The rotor inertias with velocities derived from the positions instead of the logged ones, and
   with the cut-off halved and doubled (a filtering artefact would move them).
4. The rotor inertias with the Dahl friction model (friction that lags a reversal: presliding).
5. The rotor inertias with terms the model lacks added per joint to the least squares (each acts
   in its own joint's equation only): a spring ``q_j``; a spring and a once-per-turn ripple
   ``q_j, sin q_j, cos q_j`` (a sensor or cable effect); a spring with the Dahl friction; each
   with the fit and validation errors (a term that only fits this trajectory shows as a
   validation error that rises on a log of another trajectory).

Sections 1, 4 and 5 solve their own weighted least squares on the regressor the data path
filters like the torques (per-joint weights from three ordinary passes, no pruning), so their
standard deviations differ a little from those of ``identify`` (sections 2 and 3).

Run: ``.venv/bin/python bench/bench_negative_rotor_inertia.py ROBOT FIT.csv [FIT2.csv ...]
--validate VAL.csv [--lags MS,MS,...]``, e.g. with the Panda of the real logs' folder,
``DIR/panda/panda_gaz2019.yaml DIR/panda/panda_gaz2019_traj1_fit_period1.csv --validate
DIR/panda/panda_gaz2019_traj1_val_repeat.csv``.
"""

from __future__ import annotations

import argparse
import textwrap

import mindyn
import mindyn.identification.consistent as C
import numpy as np
from mindyn.identification import JointData, identify, read_csv, validate
from mindyn.identification.friction import select_friction_model
from mindyn.identification.preprocess import preprocess, split_at_gaps


def shifted(raw: JointData, lag: float, derived_velocity: bool = False) -> JointData:
    """``raw`` with its torques read at ``t + lag``; velocities dropped when derived."""
    tau = np.column_stack([np.interp(raw.t + lag, raw.t, c) for c in raw.tau.T])
    proc = dict(raw.processing)
    if derived_velocity:
        proc["velocity"] = {"source": "derivative of the positions"}
    return JointData(
        raw.t, raw.q, None if derived_velocity else raw.dq, None, tau, raw.source, proc
    )


def read(raws, lag=0.0, cutoff=None, derived_velocity=False):
    return [
        preprocess(s, cutoff=cutoff)
        for raw in raws
        for s in split_at_gaps(shifted(raw, lag, derived_velocity))
    ]


def cutoff_of(logs) -> float:
    return max(d.processing["preprocess"]["filter"]["cutoff_Hz"] for d in logs)


def stacked(logs, base, extra=()):
    """Filtered regressor rows (m, n, nb + extras) and torques of ``logs``, with per-joint
    columns ``extra`` (each a function of the positions, in its joint's equation only)."""
    Ws, ys = [], []
    for d in logs:
        W = d.regressor_filter.regressor(base)
        cols = []
        for f in extra:
            for j in range(d.n):
                x = np.zeros((d.m, d.n))
                x[:, j] = f(d.q[:, j])
                cols.append(x)
        Ws.append(np.concatenate([W, *(c[:, :, None] for c in cols)], axis=2))
        ys.append(d.tau)
    return np.concatenate(Ws), np.concatenate(ys)


def weighted_ls(W, y, w=None):
    """Weighted least squares: ``(p, std, residual, w)``; the per-joint weights ``w`` from two
    ordinary passes unless given."""
    m, n, k = W.shape
    fixed = w is not None
    w = np.ones(n) if w is None else w
    for _ in range(1 if fixed else 3):
        A = (W * w[None, :, None]).reshape(m * n, k)
        s = np.linalg.norm(A, axis=0)
        s[s == 0] = 1.0
        p = np.linalg.lstsq(A / s, (y * w).reshape(-1), rcond=None)[0] / s
        r = y - np.einsum("mjk,k->mj", W, p)
        if not fixed:
            w = 1.0 / np.sqrt(np.mean(r**2, axis=0))
    A = (W * w[None, :, None]).reshape(m * n, k)
    s2 = float(np.sum((r * w) ** 2)) / max(m * n - k, 1)
    std = np.sqrt(np.diag(np.linalg.pinv(A.T @ A)) * s2)
    return p, std, r, w


def rel(r, y) -> float:
    return float(np.linalg.norm(r) / np.linalg.norm(y))


def rotor_line(names, p, std) -> str:
    return " ".join(
        f"{nm} {v:+.4g} (t {v / s:+.1f})" for nm, v, s in zip(names, p, std) if nm.startswith("Ia")
    )


def lag_search(raws, base, grid):
    """Weighted residual over the lag grid, weights fixed at lag 0; the minimum and its
    curvature standard deviation (None at the grid's edge)."""
    W, y = stacked(read(raws, 0.0), base)
    w = weighted_ls(W, y)[3]
    rss = []
    for d in grid:
        W, y = stacked(read(raws, d), base)
        r = weighted_ls(W, y, w)[2]
        rss.append(float(np.sum((r * w) ** 2)))
    rss = np.array(rss)
    k = int(np.argmin(rss))
    if not 0 < k < len(grid) - 1:
        return rss, None, None
    a, b, _ = np.polyfit(grid[k - 1 : k + 2], rss[k - 1 : k + 2], 2)
    dof = y.size - W.shape[2]
    return rss, float(-b / (2 * a)), float(np.sqrt(rss[k] / dof / a))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("robot")
    ap.add_argument("data", nargs="+")
    ap.add_argument("--validate", required=True)
    ap.add_argument("--lags", help="lag grid in ms, comma-separated (default: see the docstring)")
    args = ap.parse_args()
    robot = mindyn.load(args.robot)
    raws = [read_csv(f, robot=robot, filter="none") for f in args.data]
    vraw = [read_csv(args.validate, robot=robot, filter="none")]
    rotor = mindyn.base_parameters(robot, rotor=True, friction=True, offset=True)
    plain = mindyn.base_parameters(robot, rotor=False, friction=True, offset=True)
    if args.lags:
        grid = np.array([float(x) for x in args.lags.split(",")]) * 1e-3
    else:
        dt = float(np.median(np.diff(raws[0].t)))
        grid = np.arange(-20, 21) * dt / 2
    print(f"{robot.name}: 1. torque lag, weighted residual [noise variances] at each shift")
    found = {}
    for label, logs in (("fit log(s)", raws), ("validation log", vraw)):
        rss, lag, sd = lag_search(logs, rotor, grid)
        i0 = int(np.argmin(np.abs(grid)))
        steps = [f"{1e3 * d:+.3g} ms {x - rss[i0]:+.1f}" for d, x in zip(grid, rss)]
        print(
            f"  {label}:\n"
            + textwrap.fill(", ".join(steps), 100, initial_indent="    ", subsequent_indent="    ")
        )
        if lag is None:
            print("    minimum at the edge of the grid: widen --lags")
        else:
            print(
                f"    lag {1e3 * lag:+.3f} ms, +- {1e3 * sd:.3f} ms from the curvature (white "
                f"residuals assumed), residual {rss.min() - rss[i0]:+.1f} noise variances from 0"
            )
        found[label] = lag
    lags = [0.0] + ([found["fit log(s)"]] if found["fit log(s)"] is not None else [])
    print("2. at each lag: errors [%], consistent / unconstrained validation, rotor inertias")
    for lag in lags:
        logs = read(raws, lag)
        vlogs = read(vraw, lag, cutoff=cutoff_of(logs))
        res = identify(robot, logs, base=plain)
        vu = validate(res, vlogs)["overall_relative"]
        ratios = []
        for weight in ("auto", 0):
            c = C.consistent_estimate(res, prior_weight=weight)
            ratios.append(
                f"{validate(c, vlogs)['overall_relative'] / vu:.3f} (weight {c.prior_weight:g})"
            )
        full = identify(robot, logs, base=rotor, rsd_threshold=None)
        print(
            f"  lag {1e3 * lag:+.3f} ms: fit {100 * validate(res, logs)['overall_relative']:.3f}, "
            f"validation {100 * vu:.3f}, ratio {', without prior '.join(ratios)}\n    "
            + rotor_line(full.names, full.values, full.std)
        )
    print("3. rotor inertias with another velocity source or cut-off")
    logs0 = read(raws)
    fc = cutoff_of(logs0)
    for label, kw in (
        ("velocities from the positions", {"derived_velocity": True}),
        (f"cut-off {fc / 2:.3g} Hz", {"cutoff": fc / 2}),
        (f"cut-off {2 * fc:.3g} Hz", {"cutoff": 2 * fc}),
    ):
        full = identify(robot, read(raws, **kw), base=rotor, rsd_threshold=None)
        print(f"  {label}: " + rotor_line(full.names, full.values, full.std))
    print("4-5. rotor inertias with the Dahl friction model and with per-joint terms")
    dahl = select_friction_model(robot, logs0, kind="dahl", rotor=True, offset=True).base
    vlogs0 = read(vraw, cutoff=fc)
    spring = (lambda q: q,)
    for label, b, extra in (
        ("coulomb", rotor, ()),
        ("dahl", dahl, ()),
        ("coulomb, spring q_j", rotor, spring),
        ("coulomb, spring and ripple q_j, sin q_j, cos q_j", rotor, (*spring, np.sin, np.cos)),
        ("dahl, spring q_j", dahl, spring),
    ):
        W, y = stacked(logs0, b, extra)
        p, std, r, _ = weighted_ls(W, y)
        Wv, yv = stacked(vlogs0, b, extra)
        ev = rel(yv - np.einsum("mjk,k->mj", Wv, p), yv)
        k = b.n
        print(
            f"  {label}: fit {100 * rel(r, y):.3f} %, validation {100 * ev:.3f} %;\n    "
            + rotor_line(list(b.names), p[:k], std[:k])
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
