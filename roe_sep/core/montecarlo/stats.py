"""Statistics of Monte Carlo outcomes: binomial score intervals, percentiles and the NEES consistency test.

Pure numpy/scipy; used by the Monte Carlo (open loop) and the closed-loop campaign (:mod:`roe_sep.campaign`).
"""

import math
from collections.abc import Iterable

import numpy as np
from numpy.typing import ArrayLike

from ...errors import show

Z95 = 1.959964  # two-sided 95 % standard-normal quantile
PERCENTILES = (5, 50, 95)


def wilson_interval(k: ArrayLike, n: ArrayLike, z: float = 1.959964) -> tuple:
    """Wilson score interval (lo, hi) of a binomial proportion with ``k`` events in ``n`` trials.

    Wilson (1927): centre (k + z^2/2) / (n + z^2), half-width z sqrt(k (n - k) / n + z^2/4) / (n + z^2). Unlike the
    Wald interval it stays inside [0, 1] and is not empty at k = 0: the upper end is then z^2 / (n + z^2) (about
    3.84 / n at 95 %, the 'rule of three' of the zero-count case). Vectorized over ``k`` and ``n``.

    Parameters
    ----------
    k : array_like
        Events, 0 <= k <= n.
    n : array_like
        Trials, > 0 (k = n = 0 for scalars gives (0, 1)).
    z : float
        The two-sided standard-normal quantile of the confidence (default 95 %).

    Returns
    -------
    (lo, hi) : two floats, or two numpy.ndarray of the broadcast shape
        The interval of the proportion, inside [0, 1].
    """
    k_given, n_given = k, n
    k = np.asarray(k, dtype=float)
    n = np.asarray(n, dtype=float)
    if n.ndim == 0 and n == 0 and k == 0:
        return 0.0, 1.0  # nothing observed: nothing is known
    if np.any(n <= 0) or np.any(k < 0) or np.any(k > n):
        raise ValueError(f"wilson_interval: need 0 <= k <= n and n > 0, got k = {show(k_given)}, n = {show(n_given)}")
    z2 = z * z
    centre = (k + 0.5 * z2) / (n + z2)
    half = z * np.sqrt(k * (n - k) / n + 0.25 * z2) / (n + z2)
    lo, hi = np.clip(centre - half, 0.0, 1.0), np.clip(centre + half, 0.0, 1.0)
    if lo.ndim == 0:
        return float(lo), float(hi)
    return lo, hi


def normal_interval(mean: ArrayLike, std_error: ArrayLike, z: float = Z95) -> tuple:
    """(lo, hi) = mean -/+ z * std_error, the large-sample interval of an importance-sampling estimate.

    Parameters
    ----------
    mean : array_like
        The estimate.
    std_error : array_like
        Its standard error (same unit).
    z : float
        The two-sided standard-normal quantile of the confidence.

    Returns
    -------
    (lo, hi)
        The interval, in the unit and broadcast shape of the inputs.
    """
    return mean - z * std_error, mean + z * std_error


def relative_half_width(lo: float, hi: float, p: float) -> float:
    """Half the width of the interval [``lo``, ``hi``] over the estimate ``p`` (dimensionless; inf where ``p`` is 0).

    Parameters
    ----------
    lo, hi : float
        The interval.
    p : float
        The estimate (same unit).

    Returns
    -------
    float
        (hi - lo) / (2 p), or inf for p <= 0.
    """
    return (hi - lo) / (2.0 * p) if p > 0 else math.inf


def proportion(k: int, n: int, z: float = Z95) -> dict:
    """``{"k", "n", "p", "ci95"}`` of a proportion (p None for n = 0) with its Wilson interval.

    Parameters
    ----------
    k : int
        Events.
    n : int
        Trials.
    z : float
        The quantile of :func:`wilson_interval` (the key stays ``ci95``).

    Returns
    -------
    dict
        ``k``, ``n``, ``p`` = k / n (None for n = 0) and ``ci95`` = [lo, hi].
    """
    lo, hi = wilson_interval(k, n, z)
    return {"k": int(k), "n": int(n), "p": (k / n) if n else None, "ci95": [lo, hi]}


def clopper_pearson(k: int, n: int, confidence: float = 0.95) -> dict:
    """``{"k", "n", "p", "ci95", "method"}`` of a proportion with its exact (Clopper-Pearson) two-sided interval:
    lo = Beta^-1(alpha/2; k, n - k + 1) (0 for k = 0), hi = Beta^-1(1 - alpha/2; k + 1, n - k) (1 for k = n),
    alpha = 1 - ``confidence``; p and the interval None for n = 0.

    Parameters
    ----------
    k : int
        Events.
    n : int
        Trials.
    confidence : float
        Two-sided confidence of the interval (the key stays ``ci95``).

    Returns
    -------
    dict
        ``k``, ``n``, ``p`` = k / n, ``ci95`` = [lo, hi] and ``method`` = "clopper-pearson".
    """
    from scipy.stats import beta

    k, n = int(k), int(n)
    if not 0 <= k <= n:
        raise ValueError(f"need 0 <= k <= n, got k = {k}, n = {n}")
    alpha = 1.0 - confidence
    if not n:
        return {"k": 0, "n": 0, "p": None, "ci95": [None, None], "method": "clopper-pearson"}
    lo = 0.0 if k == 0 else float(beta.ppf(0.5 * alpha, k, n - k + 1))
    hi = 1.0 if k == n else float(beta.ppf(1.0 - 0.5 * alpha, k + 1, n - k))
    return {"k": k, "n": n, "p": k / n, "ci95": [lo, hi], "method": "clopper-pearson"}


def distribution(values: Iterable, percentiles: Iterable[int] = PERCENTILES) -> dict:
    """Summary of a sample: ``n``, ``min``, ``p5``/``p50``/``p95`` (linear interpolation), ``max`` and ``mean``;
    None entries (no value in that run) are left out and counted in ``missing``. Empty: the statistics are None."""
    vals = [float(v) for v in values if v is not None and math.isfinite(float(v))]
    out = {"n": len(vals), "missing": sum(1 for v in values if v is None or not math.isfinite(float(v)))}
    x = np.asarray(vals, dtype=float)
    out["min"] = float(x.min()) if x.size else None
    for q in percentiles:
        out[f"p{q}"] = float(np.percentile(x, q)) if x.size else None
    out["max"] = float(x.max()) if x.size else None
    out["mean"] = float(x.mean()) if x.size else None
    return out


def nees_bounds(dof: int, runs: int = 1, confidence: float = 0.95) -> tuple[float, float]:
    """Two-sided acceptance region of the average NEES over ``runs`` independent runs of a consistent estimator of
    dimension ``dof`` (Bar-Shalom, Li & Kirubarajan 2001, Sec. 5.4.2): runs * mean(NEES) ~ chi-square(runs * dof), so
    mean(NEES) lies in [chi2.ppf(a/2, runs dof), chi2.ppf(1 - a/2, runs dof)] / runs with probability 1 - a.

    Parameters
    ----------
    dof : int
        The state dimension (>= 1).
    runs : int
        The number of runs averaged (>= 1).
    confidence : float
        1 - a, in (0, 1).

    Returns
    -------
    (lo, hi) : float
        The bounds of the mean NEES (dimensionless).
    """
    from scipy.stats import chi2  # here, not at import: scipy.stats costs ~1.7 s and ~70 MB in every Dask worker

    if dof < 1 or runs < 1:
        raise ValueError(f"nees_bounds: need dof >= 1 and runs >= 1, got dof = {dof}, runs = {runs}")
    a = 1.0 - confidence
    return float(chi2.ppf(a / 2.0, runs * dof) / runs), float(chi2.ppf(1.0 - a / 2.0, runs * dof) / runs)


def nees_consistency(nees: Iterable, dof: int = 6, confidence: float = 0.95) -> dict:
    """The NEES test of a set of runs: mean NEES against :func:`nees_bounds` for that many runs, and the fraction
    of single-run NEES inside the single-run chi-square(dof) bounds (expected: ``confidence``, with its Wilson
    interval). An optimistic covariance (errors larger than it says) gives a mean above the upper bound.

    Parameters
    ----------
    nees : iterable of float or None
        The NEES of each run; None or non-finite values are left out.
    dof : int
        The state dimension.
    confidence : float
        The confidence of the bounds.

    Returns
    -------
    dict
        ``dof``, ``confidence``, ``n``, ``single_run_bounds``, ``mean``, ``mean_bounds`` and ``consistent`` (None
        without a value), with values also ``median`` and ``within_single_run_bounds`` (:func:`proportion`).
    """
    vals = [float(v) for v in nees if v is not None and math.isfinite(float(v))]
    single = nees_bounds(dof, 1, confidence)
    out = {"dof": dof, "confidence": confidence, "n": len(vals), "single_run_bounds": list(single),
           "mean": None, "mean_bounds": None, "consistent": None}
    if not vals:
        return out
    lo, hi = nees_bounds(dof, len(vals), confidence)
    mean = float(np.mean(vals))
    inside = sum(1 for v in vals if single[0] <= v <= single[1])
    out.update(mean=mean, mean_bounds=[lo, hi], consistent=bool(lo <= mean <= hi),
               median=float(np.median(vals)), within_single_run_bounds=proportion(inside, len(vals)))
    return out
