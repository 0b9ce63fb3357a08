"""Several threads on one robot: the binding calls run with the GIL released, each with a
workspace of its own, so results computed concurrently are bit for bit those computed serially.

Four threads share one Robot and one base parameter set; each works on inputs of its own (so a
workspace shared between threads would mix one thread's link poses into another's results) and
repeats inverse dynamics, the classical and base regressors, the mass matrix, the base
Slotine-Li regressor and position IK many times, all starting together at a barrier. Every
result must equal, with np.array_equal, the one computed before in a single thread: the same
arithmetic on the same inputs gives the same bits, whatever the interleaving.
"""

from __future__ import annotations

import threading
import time

import mindyn
import numpy as np
from mindyn.inverse_kinematics import ik_solve

THREADS = 4
ROUNDS = 25
SAMPLES = 200


def workload(robot, base, seed):
    rng = np.random.default_rng(seed)
    n = robot.n
    q, dq, ddq, dqr, ddqr = rng.uniform(-2.0, 2.0, (5, SAMPLES, n))
    # IK targets: poses of random configurations (reachable), from the middle of the limits
    goal = rng.uniform(-1.0, 1.0, n)
    target = robot.fk(goal)

    def run():
        return {
            "inverse_dynamics": robot.inverse_dynamics(q, dq, ddq),
            "regressor": robot.regressor(q, dq, ddq, rotor=True, friction=True),
            "base_regressor": base.regressor(q, dq, ddq),
            "mass_matrix": robot.mass_matrix(q),
            "slotine_li": mindyn.slotine_li_regressor(base, q, dq, dqr, ddqr),
            # no time budget: the answer depends on the arithmetic only, not on the CPU time
            "ik": ik_solve(robot, target, max_time=0.0, tolerance=1e-9).q,
        }

    return run


def test_threads_on_one_robot_match_serial_results_bitwise():
    robot = mindyn.load("puma560")
    base = mindyn.base_parameters(robot)
    runs = [workload(robot, base, seed) for seed in range(THREADS)]
    serial = [run() for run in runs]
    # the inputs differ from thread to thread, so a shared workspace would show
    for k in serial[0]:
        assert not np.array_equal(serial[0][k], serial[1][k]), k

    barrier = threading.Barrier(THREADS)
    mismatches: list[str] = []
    errors: list[BaseException] = []

    def worker(i):
        try:
            barrier.wait()
            for r in range(ROUNDS):
                got = runs[i]()
                for k, expected in serial[i].items():
                    if not np.array_equal(got[k], expected):
                        mismatches.append(f"thread {i}, round {r}: {k}")
        except BaseException as e:  # reported below, not lost in the thread
            errors.append(e)

    threads = [threading.Thread(target=worker, args=(i,)) for i in range(THREADS)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors
    assert not mismatches, mismatches[:10]


def test_batch_calls_release_the_gil():
    """Another thread runs Python code while one is inside a long batch call. With the GIL held
    through the call nothing else could run between its start and its end; the test asks for one
    step of the other thread inside the middle 80 % of the call (a call of about 0.1 s or more,
    far longer than the 5 ms the interpreter gives a thread before it switches)."""
    robot = mindyn.load("planar200")
    q = np.random.default_rng(1).uniform(-1, 1, (300, robot.n))
    done = threading.Event()
    stamps: list[float] = []

    def counter():
        while not done.is_set():
            stamps.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=counter)
    t.start()
    time.sleep(0.01)
    t0 = time.perf_counter()
    robot.mass_matrix(q)
    t1 = time.perf_counter()
    done.set()
    t.join()
    lo, hi = t0 + 0.1 * (t1 - t0), t1 - 0.1 * (t1 - t0)
    assert any(lo < s < hi for s in stamps), (t1 - t0, len(stamps))
