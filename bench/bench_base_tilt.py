"""Base-parameter counts of nearly degenerate geometry, by the three methods.

usage: .venv/bin/python bench/bench_base_tilt.py [--tolerance T] [--tilts 0,1e-12,...]
           [--fuzz SEED:COUNT ...]

The table: one revolute joint whose axis is tilted off the vertical (tests/test_base_tilt.py's
robot), the ratios sigma_2 / sigma_1 and sigma_3 / sigma_1 of its stacked regressor with 60
digits (mpmath: the tolerances at which the count changes), the count that gives at the
tolerance, and each method's count with the default snap and with --snap off (``*``: flagged
near-degenerate, ``refused``: refused with its reason).

--fuzz SEED:COUNT redraws the fuzz campaign's ``trees`` cases (fuzz/campaign.py, the same
robots and options for that seed) and runs the three methods on each as written, printing how
many cases the methods disagree on (counts that differ among those that return a set), and how
many one of them refuses while another returns a set.
"""

from __future__ import annotations

import argparse
import importlib.util
import random
import sys
import tempfile
from pathlib import Path

import mindyn

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from test_base_tilt import reference_count, tilted_joint_urdf  # noqa: E402

METHODS = ("projection", "recursive", "numerical")


def count(path, method: str, tolerance: float, **options) -> str:
    try:
        bp = mindyn.base_parameters(path, method=method, tolerance=tolerance, **options)
    except mindyn.Error:
        return "refused"
    return f"{bp.n}{'*' if bp.margin['near_degenerate'] else ''}"


def table(tilts: list[float], tolerance: float) -> None:
    print(f"one revolute joint tilted off vertical, rank tolerance {tolerance:g}")
    head = ["tilt", "s2/s1", "s3/s1", "mpmath"]
    head += [f"{m[:4]} {s}" for s in ("auto", "off") for m in METHODS]
    print(" ".join(f"{h:>10}" for h in head))
    with tempfile.TemporaryDirectory() as tmp:
        for tilt in tilts:
            path = Path(tmp) / "tilted.urdf"
            path.write_text(tilted_joint_urdf(tilt))
            n, ratios = reference_count(tilt, tolerance)
            row = [f"{tilt:g}", f"{ratios[1]:.3g}", f"{ratios[2]:.3g}", str(n)]
            for snap in ("auto", False):
                row += [count(path, m, tolerance, snap=snap) for m in METHODS]
            print(" ".join(f"{c:>10}" for c in row))


def fuzz(seed: int, cases: int, tolerance: float) -> None:
    spec = importlib.util.spec_from_file_location("campaign", ROOT / "fuzz" / "campaign.py")
    campaign = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(campaign)
    disagree, refused_by_some, flagged = [], 0, 0
    with tempfile.TemporaryDirectory() as tmp:
        for index in range(cases):
            # as campaign.case_trees draws them
            rng = random.Random(f"{seed}:trees:{index}")
            path = campaign.odd_urdf(rng, Path(tmp) / f"trees-{index}.urdf", index % 3 == 0)
            rng.choice(["projection", "recursive", "numerical"])
            rotor, friction = rng.random() < 0.3, rng.random() < 0.3
            robot = mindyn.load(path)
            counts, near = {}, False
            for m in METHODS:
                try:
                    bp = mindyn.base_parameters(
                        robot,
                        method=m,
                        rotor=rotor,
                        friction=friction,
                        snap=False,
                        tolerance=tolerance,
                    )
                except mindyn.Error:
                    counts[m] = None
                    continue
                counts[m] = bp.n
                near = near or bool(bp.margin["near_degenerate"])
            returned = {n for n in counts.values() if n is not None}
            if len(returned) > 1:
                disagree.append((index, counts, near))
            elif returned and None in counts.values():
                refused_by_some += 1
            flagged += near
    print(
        f"seed {seed}, {cases} trees cases: the methods' counts differ on {len(disagree)}, "
        f"one refuses where another returns a set on {refused_by_some}, "
        f"flagged near-degenerate {flagged}"
    )
    for index, counts, near in disagree:
        print(f"  trees:{index} {counts}{' (near-degenerate)' if near else ''}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tolerance", type=float, default=1e-9)
    ap.add_argument("--tilts", default="0,1e-12,1e-10,1e-9,1e-8,1e-6")
    ap.add_argument("--fuzz", action="append", default=[], metavar="SEED:COUNT")
    args = ap.parse_args()
    table([float(t) for t in args.tilts.split(",")], args.tolerance)
    for item in args.fuzz:
        seed, cases = item.split(":")
        fuzz(int(seed), int(cases), args.tolerance)


if __name__ == "__main__":
    main()
