"""The generated momentum-observer step beside the generated adaptive-PD step: operation counts
and nanoseconds per step of the compiled C.

    .venv/bin/python bench/bench_observer_step.py [--cflags "-O2"] [--steps 20000] [--repeats 7]
        [--robots zcr07s puma560]

Base parameters with rotor inertia and friction, the robot's own values, a 4 ms period. The
observer step is compiled with a driver that calls it on ``--steps`` precomputed inputs (a smooth
motion and torques) and reports the best mean over the repeats; the adaptive-PD step is timed by
bench/bench_controller.py's driver the same way.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import mindyn
import numpy as np
from mindyn import codegen, control

sys.path.insert(0, str(Path(__file__).parent))
from bench_controller import bench as bench_controller  # noqa: E402

DRIVER = r"""
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "HEADER"

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec * 1e9 + t.tv_nsec;
}

int main(int argc, char** argv) {
  const int steps = atoi(argv[1]), repeats = atoi(argv[2]), n = NJ;
  FILE* f = fopen(argv[3], "rb");
  double* in = malloc(sizeof(double) * 3 * n * steps);
  if (!f || fread(in, sizeof(double), 3 * n * steps, f) != (size_t)(3 * n * steps)) return 1;
  fclose(f);
  FN_t c;
  double r[NJ], best = 1e300, sum = 0;
  for (int k = 0; k < repeats; ++k) {
    FN_init(&c);
    const double t0 = now();
    for (int i = 0; i < steps; ++i) {
      const double* x = in + 3 * n * i;
      FN_step(&c, x, x + n, x + 2 * n, r);
      sum += r[0];
    }
    const double ns = (now() - t0) / steps;
    if (ns < best) best = ns;
  }
  printf("%.1f %g\n", best, sum);
  return 0;
}
"""


def bench_observer(robot, cc, cflags, steps, repeats, folder: Path):
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    code = codegen.generate_observer(robot, base=base, period=0.004)
    src = code.write(folder / f"{code.function}.c")[1]
    driver = DRIVER.replace("HEADER", code.header_name).replace("FN", code.function)
    (folder / "obs_driver.c").write_text(driver.replace("NJ", str(robot.n)))
    exe = folder / "obs_bench"
    cmd = [cc, "-std=c99", *cflags.split(), "-o", str(exe), str(folder / "obs_driver.c")]
    subprocess.run(cmd + [str(src), "-lm"], check=True)
    q, dq, _ = control.SumOfSines(robot, period=10.0, seed=0).evaluate(0.004 * np.arange(steps))
    tau = np.random.default_rng(0).normal(0, 5.0, q.shape)
    np.stack([q, dq, tau], axis=1).astype(float).tofile(folder / "obs_inputs.bin")
    res = subprocess.run(
        [str(exe), str(steps), str(repeats), str(folder / "obs_inputs.bin")],
        capture_output=True,
        text=True,
        check=True,
    )
    return code, float(res.stdout.split()[0])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cflags", default="-O2")
    ap.add_argument("--steps", type=int, default=20000)
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--robots", nargs="+", default=["zcr07s", "puma560"])
    args = ap.parse_args()
    cc = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if not cc:
        raise SystemExit("bench_observer_step: no C compiler (set CC)")
    print(f"generated steps, {cc} {args.cflags}; base parameters with rotor inertia and friction")
    print(f"{'robot':<9}{'step':<20}{'np':>4}{'mul':>7}{'add':>7}{'trig':>6}{'ns/step':>10}")
    with tempfile.TemporaryDirectory() as d:
        for name in args.robots:
            robot = mindyn.load(name)
            rows = [bench_observer(robot, cc, args.cflags, args.steps, args.repeats, Path(d))]
            code, ns, _ = bench_controller(
                robot, "adaptive-pd", cc, args.cflags, args.steps, args.repeats, Path(d)
            )
            rows.append((code, ns))
            for code, ns in rows:
                c = code.counts["step"]
                what = "momentum-observer" if "observer" in code.function else "adaptive-pd"
                print(
                    f"{name:<9}{what:<20}{len(code.names):>4}{c['mul']:>7}{c['add']:>7}"
                    f"{c['trig']:>6}{ns:>10.0f}"
                )


if __name__ == "__main__":
    main()
