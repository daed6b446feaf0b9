"""Shared timing for the benchmarks."""

from __future__ import annotations

import time

import numpy as np


def median_time(fn, n: int = 7) -> float:
    """The median wall time (s) of ``n`` calls of ``fn``."""
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))
