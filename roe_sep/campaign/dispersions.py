"""The dispersions each run applied, against the distributions the scenario configures (Kolmogorov-Smirnov).

A dispersion silently not applied (a sigma read as zero, a draw that never reaches the dynamics) is a known failure
of Monte Carlo frameworks: the campaign looks robust because nothing was dispersed. Every run's report carries what
its simulator drew (:func:`roe_sep.report.dispersions_applied`, the ``dispersions`` column of ``runs.csv``); here
the samples of all completed runs are tested against the configured distributions with scipy's one-sample KS test:

* ``spl_factor``: SPL magnitude factor ~ N(1, spl_sigma) (one per run, the ejection);
* ``spl_attitude``: SPL direction errors ~ N(0, attitude_sigma), the three RTN angles of each ejection;
* ``thruster_factor``: carrier burn magnitude factor ~ N(1, thruster_sigma), every executed carrier burn;
* ``thruster_attitude``: carrier burn direction errors ~ N(0, attitude_sigma);
* ``drag_factor``: differential ballistic coefficient factor ~ N(1, ballistic_sigma);
* ``ejection_delay``: release delay ~ U(0, ejection_delay_max);
* ``radar_noise``: the first OD's post-fit residual RMS r (in measurement sigmas) of m measurements: 3 m r^2 ~
  chi-square(3 m - 7) for noise of the configured scale (7 estimated parameters), so its CDF value is U(0, 1).

A test is ``consistent`` when its p-value is at least :data:`ALPHA` (1 %: seven tests at 5 % would flag one of
them in about 30 % of honest campaigns). A configured sigma of 0 (``disperse`` false) is a point mass: consistent
when every sample equals it.
"""

import math

import numpy as np
from scipy import stats

from ..report import dispersions_applied

ALPHA = 0.01
OD_PARAMETERS = 7  # ROE and drift rate estimated by the batch OD (degrees of freedom taken by the fit)
MIN_SAMPLES = 5  # below this the KS test says nothing


def samples(rows):
    """``({test: [values]}, configured)`` from the completed rows' ``dispersions`` (configured: the first run's,
    None without any)."""
    out = {k: [] for k in ("spl_factor", "spl_attitude", "thruster_factor", "thruster_attitude", "drag_factor",
                           "ejection_delay", "radar_noise")}
    configured = None
    for row in rows:
        d = dispersions_applied(row.get("dispersions"))
        if d is None:
            continue
        configured = configured or d.get("configured")
        out["drag_factor"].append(d.get("drag_factor"))
        out["ejection_delay"].append(d.get("ejection_delay_s"))
        for spacecraft, factor, eps in d.get("burns") or ():
            kind = "spl" if spacecraft == "picosatellite" else "thruster"
            out[f"{kind}_factor"].append(factor)
            out[f"{kind}_attitude"].extend(eps)
        rms, m = row.get("od_residual_rms"), row.get("od_measurements")
        if rms is not None and m and 3 * m > OD_PARAMETERS:
            out["radar_noise"].append(float(stats.chi2.cdf(3 * m * rms * rms, 3 * m - OD_PARAMETERS)))
    return {k: [float(v) for v in vals if v is not None and math.isfinite(v)] for k, vals in out.items()}, configured


def reference(test, cfg):
    """``(label, distribution)`` the samples of ``test`` are drawn from per the configuration; distribution None
    for a point mass (its value as the label's number)."""
    disperse = cfg.get("disperse", True)
    sig = {"spl_factor": cfg.get("spl_sigma"), "thruster_factor": cfg.get("thruster_sigma"),
           "spl_attitude": cfg.get("attitude_sigma"), "thruster_attitude": cfg.get("attitude_sigma"),
           "drag_factor": cfg.get("ballistic_sigma") if disperse else 0.0}
    if test in sig:
        mean = 0.0 if test.endswith("attitude") else 1.0
        s = float(sig[test] or 0.0)
        unit = " rad" if test.endswith("attitude") else ""
        return (f"N({mean:g}, {s:.3g}{unit})", stats.norm(mean, s)) if s > 0 else (f"= {mean:g}", mean)
    if test == "ejection_delay":
        hi = float(cfg.get("ejection_delay_max_s") or 0.0) if disperse else 0.0
        return (f"U(0, {hi:g} s)", stats.uniform(0.0, hi)) if hi > 0 else ("= 0", 0.0)
    return "chi2 CDF ~ U(0, 1)", stats.uniform(0.0, 1.0)


def dispersion_checks(rows):
    """Each dispersion's sample against its configured distribution: n, sample mean and std, the reference, the
    KS statistic and p-value and ``consistent`` (see the module docstring); {} when no row carries dispersions."""
    values, cfg = samples(rows)
    if cfg is None:
        return {}
    out = {}
    for test, vals in values.items():
        label, dist = reference(test, cfg)
        arr = np.asarray(vals)
        entry = {"n": len(vals), "reference": label,
                 "mean": float(arr.mean()) if len(vals) else None,
                 "std": float(arr.std(ddof=1)) if len(vals) > 1 else None}
        if isinstance(dist, float):  # a point mass: no draw may differ from it
            entry.update(statistic=None, p_value=None, consistent=bool(len(vals)) and bool(np.all(arr == dist)))
        elif len(vals) < MIN_SAMPLES:
            entry.update(statistic=None, p_value=None, consistent=None)
        else:
            res = stats.kstest(arr, dist.cdf)
            entry.update(statistic=float(res.statistic), p_value=float(res.pvalue),
                         consistent=bool(res.pvalue >= ALPHA))
        out[test] = entry
    return out
