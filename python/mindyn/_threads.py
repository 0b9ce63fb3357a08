"""Threads: BLAS threading for the small-matrix work of excitation and identification, and
batched regressors evaluated ahead of their use; and the memory allocator of a process that
works through long logs (:func:`reuse_freed_memory`).

Products like ``W^T W`` with ``W`` of a few hundred rows and tens of columns, called thousands of
times, are slowed down (by an order of magnitude on a loaded two-core machine) when a
multi-threaded BLAS wakes its threads for each call; one thread is faster there.
"""

from __future__ import annotations

import functools
import itertools
import os
import sys
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


def reuse_freed_memory() -> None:
    """Has the C library's allocator (glibc, on Linux; elsewhere nothing is done) keep freed
    blocks of up to 256 MiB, and up to 1 GiB of free memory at the top of the heap, for reuse
    instead of returning each to the system: the arrays of a long log are tens of MiB each
    (10^6 samples of 6 joints: 48 MB), and mapping and unmapping every temporary one costs page
    faults and, with threads, TLB shootdowns: a fifth of the CPU time of ``identify`` on a
    10^6-row log. A process-wide setting, made by the command line for its own process (a
    library does not change its caller's allocator)."""
    if not sys.platform.startswith("linux"):
        return
    import ctypes

    try:
        mallopt = ctypes.CDLL(None).mallopt  # the interpreter's C library
    except (OSError, AttributeError):  # not glibc
        return
    mallopt(-3, 256 << 20)  # M_MMAP_THRESHOLD: larger blocks only are mapped on their own
    mallopt(-1, 1 << 30)  # M_TRIM_THRESHOLD: free memory kept at the top of the heap


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
