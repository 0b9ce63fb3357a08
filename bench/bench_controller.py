"""Generated controller steps: nanoseconds per step of the generated C and its operation counts.

    .venv/bin/python bench/bench_controller.py [--cflags "-O2"] [--steps 20000] [--repeats 7]

For each robot and controller the step is generated (base parameters with rotor inertia and
friction, the robot's default gains, 4 ms period), compiled with the system C compiler together
with a small driver that calls it on ``--steps`` precomputed inputs (a smooth reference, the
measured state off it by noise, so that the estimate moves) and reports the best mean over the
repeats (the least disturbed by other load on the machine). The targets for the ZCR07S adaptive
PD are at most 1500 multiplications and 5 us per step (the ZCR07S study ran a 4 ms cycle).
The library's AdaptivePD step (Python, numpy) is timed beside it for scale.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import mindyn
import numpy as np
from mindyn import codegen, control

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
  const int steps = atoi(argv[1]), repeats = atoi(argv[2]), n = N;
  FILE* f = fopen(argv[3], "rb");
  double* in = malloc(sizeof(double) * 5 * n * steps);
  if (!f || fread(in, sizeof(double), 5 * n * steps, f) != (size_t)(5 * n * steps)) return 1;
  fclose(f);
  T c;
  double tau[N], best = 1e300, sum = 0;
  for (int r = 0; r < repeats; ++r) {
    INIT(&c);
    const double t0 = now();
    for (int i = 0; i < steps; ++i) {
      const double* x = in + 5 * n * i;
      STEP(&c, x, x + n, x + 2 * n, x + 3 * n, x + 4 * n, tau);
      sum += tau[0];
    }
    const double ns = (now() - t0) / steps;
    if (ns < best) best = ns;
  }
  printf("%.1f %g\n", best, sum);
  return 0;
}
"""


def inputs(robot, steps: int) -> np.ndarray:
    ref = control.SumOfSines(robot, period=10.0, seed=0)
    rng = np.random.default_rng(0)
    out = np.empty((steps, 5, robot.n))
    Qd, dQd, ddQd = ref.evaluate(0.004 * np.arange(steps))
    for i, (qd, dqd, ddqd) in enumerate(zip(Qd, dQd, ddQd)):
        out[i] = [
            qd + rng.normal(0, 1e-3, robot.n),
            dqd + rng.normal(0, 1e-2, robot.n),
            qd,
            dqd,
            ddqd,
        ]
    return out


def bench(robot, kind, cc, cflags, steps, repeats, folder: Path):
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    code = codegen.generate_controller(robot, kind, base=base)
    src = code.write(folder / f"{code.function}.c")[1]
    fn = code.function
    driver = DRIVER.replace("HEADER", code.header_name)
    driver = driver.replace("T c;", f"{fn}_t c;").replace("INIT(", f"{fn}_init(")
    driver = driver.replace("STEP(", f"{fn}_step(").replace(
        "double tau[N]", f"double tau[{robot.n}]"
    )
    driver = driver.replace("n = N;", f"n = {robot.n};")
    (folder / "driver.c").write_text(driver)
    exe = folder / f"{fn}_bench"
    cmd = [
        cc,
        "-std=c99",
        *cflags.split(),
        "-o",
        str(exe),
        str(folder / "driver.c"),
        str(src),
        "-lm",
    ]
    subprocess.run(cmd, check=True)
    data = folder / "inputs.bin"
    x = inputs(robot, steps)
    x.astype(float).tofile(data)
    res = subprocess.run(
        [str(exe), str(steps), str(repeats), str(data)], capture_output=True, text=True, check=True
    )
    ns = float(res.stdout.split()[0])
    lib_us = float("nan")
    if kind == "adaptive-pd":
        ctl = control.make_controller(
            kind, robot, control.default_gains(robot, rotor=True), None, base=base
        )
        m = min(steps, 500)
        t0 = time.perf_counter()
        for i in range(m):
            ctl(0.0, x[i, 0], x[i, 1], x[i, 2], x[i, 3], x[i, 4])
        lib_us = (time.perf_counter() - t0) / m * 1e6
    return code, ns, lib_us


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cflags", default="-O2")
    ap.add_argument("--steps", type=int, default=20000)
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()
    cc = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if not cc:
        raise SystemExit("bench_controller: no C compiler (set CC)")
    print(
        f"generated controller steps, {cc} {args.cflags}; base parameters with rotor inertia "
        "and friction"
    )
    print(
        f"{'robot':<9}{'controller':<22}{'np':>4}{'mul':>7}{'add':>7}{'trig':>6}"
        f"{'ns/step':>10}{'library us':>12}"
    )
    with tempfile.TemporaryDirectory() as d:
        for name in ("zcr07s", "puma560"):
            robot = mindyn.load(name)
            for kind in codegen.CONTROLLERS:
                code, ns, lib = bench(
                    robot, kind, cc, args.cflags, args.steps, args.repeats, Path(d)
                )
                c = code.counts["step"]
                libs = f"{lib:12.1f}" if np.isfinite(lib) else f"{'':>12}"
                print(
                    f"{name:<9}{kind:<22}{len(code.names):>4}{c['mul']:>7}{c['add']:>7}"
                    f"{c['trig']:>6}{ns:>10.0f}{libs}"
                )
                if kind == "adaptive-pd":
                    for form, v in code.variants.items():
                        mark = "*" if form == code.form else " "
                        print(f"{'':<11}{mark} {form:<50}{v['mul']:>6} mul {v['add']:>6} add")


if __name__ == "__main__":
    main()
