"""Best-of-N wall-clock timing shared by the benchmarks."""

import time


def best_of(fn, repeat):
    """(shortest wall time [s] of ``repeat`` calls of ``fn``, the last call's result)."""
    best, out = float("inf"), None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out
