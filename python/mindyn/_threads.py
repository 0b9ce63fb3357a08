"""Threads: BLAS threading for the small-matrix work of excitation and identification, and
batched regressors evaluated ahead of their use.

Products like ``W^T W`` with ``W`` of a few hundred rows and tens of columns, called thousands of
times, are slowed down (by an order of magnitude on a loaded two-core machine) when a
multi-threaded BLAS wakes its threads for each call; one thread is faster there.
"""

from __future__ import annotations

import functools
import itertools
import os
from collections import deque
from concurrent.futures import ThreadPoolExecutor

from threadpoolctl import threadpool_limits

#: Threads of :func:`evaluated_ahead`.
WORKERS = min(2, os.cpu_count() or 1)


def single_threaded_blas(func):
    """Decorator: run ``func`` with BLAS limited to one thread."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with threadpool_limits(limits=1, user_api="blas"):
            return func(*args, **kwargs)

    return wrapper


def evaluated_ahead(func, bounds):
    """``func(a, b)`` for each ``(a, b)`` of ``bounds``, yielded in order, evaluated a few
    ahead on :data:`WORKERS` threads: for functions that run without the interpreter lock (the
    batched regressors) while the caller works on the result before."""
    with ThreadPoolExecutor(WORKERS) as pool:
        todo = iter(bounds)
        pending = deque(pool.submit(func, a, b) for a, b in itertools.islice(todo, WORKERS + 1))
        while pending:
            x = pending.popleft().result()
            for a, b in itertools.islice(todo, 1):
                pending.append(pool.submit(func, a, b))
            yield x
