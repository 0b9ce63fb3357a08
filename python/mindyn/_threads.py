"""BLAS threading for the small-matrix work of excitation and identification.

Products like ``W^T W`` with ``W`` of a few hundred rows and tens of columns, called thousands of
times, are slowed down (by an order of magnitude on a loaded two-core machine) when a
multi-threaded BLAS wakes its threads for each call; one thread is faster there.
"""

from __future__ import annotations

import functools

from threadpoolctl import threadpool_limits


def single_threaded_blas(func):
    """Decorator: run ``func`` with BLAS limited to one thread."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with threadpool_limits(limits=1, user_api="blas"):
            return func(*args, **kwargs)

    return wrapper
