"""Binomial estimates of the Monte Carlo: the 95 % score interval of a fraction and its count."""

import numpy as np

Z95 = 1.959964  # two-sided 95 % standard-normal quantile


def wilson_interval(k, n, z=1.959964):
    """Wilson score interval (lo, hi) of a binomial proportion with ``k`` events in ``n`` trials.

    Wilson (1927): centre (k + z^2/2) / (n + z^2), half-width z sqrt(k (n - k) / n + z^2/4) / (n + z^2). Unlike the
    Wald interval it stays inside [0, 1] and is not empty at k = 0: the upper end is then z^2 / (n + z^2) (about
    3.84 / n at 95 %, the 'rule of three' of the zero-count case). Vectorized over ``k`` and ``n``.
    """
    k = np.asarray(k, dtype=float)
    n = np.asarray(n, dtype=float)
    if np.any(n <= 0) or np.any(k < 0) or np.any(k > n):
        raise ValueError(f"wilson_interval needs 0 <= k <= n and n > 0, got k={k}, n={n}")
    z2 = z * z
    centre = (k + 0.5 * z2) / (n + z2)
    half = z * np.sqrt(k * (n - k) / n + 0.25 * z2) / (n + z2)
    lo, hi = np.clip(centre - half, 0.0, 1.0), np.clip(centre + half, 0.0, 1.0)
    if lo.ndim == 0:
        return float(lo), float(hi)
    return lo, hi


def normal_interval(mean, std_error, z=Z95):
    """(lo, hi) = mean -/+ z * std_error, the large-sample interval of an importance-sampling estimate."""
    return mean - z * std_error, mean + z * std_error

