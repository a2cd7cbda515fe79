"""The final drift trim of the initial-condition acquisition: a late OD, the predicted a da at the IC epoch, and one
quantized tangential carrier burn when that prediction is not safely inside the drift tolerance.

Why. The acquisition plan of :mod:`roe_sep.core.acquisition.planner` nulls the drift at the IC epoch t_F from an OD
made about a day
earlier; the OD's drift-rate error carried that far and the execution errors of the burns flown after it leave
|a da_F| outside the tolerance in some runs (docs/campaigns.md, "Why 9 runs missed the initial conditions"). A
flight-dynamics team closes the loop on the last information: a final radar OD shortly before t_F, then a trim
uplinked with the planning margin, flown before t_F.

Timeline. :func:`radar_passes` predicts the station's passes of the carrier (the chief's secular elements, the
IERS Earth of roe_sep.core.frames). The final OD is the solution after the last pass before t_F;
:func:`final_od_arc` gives its radar arc, from the latest pass that spans radar_od's ``min_arc`` with it and leaves
three passes in the arc (radar_od restarts its batch after every burn, so the plans keep their burns out of that
arc: ``no_burns`` of :func:`.planner.plan_acquisition`). The trim is the first grid epoch at or after the solution
+ planning_margin; when that falls after t_F, the IC epoch moves one grid step past it.

Decision (seed 002 Eq. 2: only a tangential impulse changes da, a Delta da = 2 dvT / n). The OD predicts a da at
t_F with the burns still to fly, and its 1-sigma from the OD covariance, sigma^2 = sigma_a_da^2 + (sigma_rate dt)^2
(the message carries no cross term: taken as independent). No trim when |a da_F| <= max(lattice / 2, tolerance -
z sigma): already inside the tolerance with z sigmas of margin (z = 3: one run in about 700 at the threshold). No
trim either when sigma > tolerance / z: such an OD cannot put a da inside the tolerance with that confidence (a
two-pass solution's sigma is tens of meters). Otherwise the trim is the integer number of quanta that brings the
predicted a da_F closest to zero; it leaves at most half the lattice spacing 2 dv_quantum / n (0.9 m at 515 km).
The trim's effect on dl, de and di is below a meter for a few mm/s, checked with :func:`trajectory` against the
along-track range, the e/i (anti-)parallelism, Eq. (25) and the field of view before the trim is proposed.
"""

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..frames import gcrs_to_itrs
from ..od.radar import TIRA, Station, chief_elevation, pass_windows
from ..relmotion.dynamics import arg_latitude_rate, propagate_chief
from ..relmotion.orbit import mean_motion
from ..relmotion.trajectory import Burn, Chief, trajectory
from ..safety.metrics import fov_limit, min_rn_distance
from .lp_transfer import grid_epochs
from .planner import AcquisitionConfig, AcquisitionInfeasible, ei_deviation

TRIM_SIGMAS = 3.0  # z of the decision threshold (one-sided normal tail 0.13 %)
FINAL_OD_PASSES = 3  # passes in the final OD's arc: two (radar_od's minimum) leave a da to tens of meters
CLUSTER_GAP = 7200.0  # s, passes closer than this (about one orbit apart) form a cluster


def a_da_change(dv_t: ArrayLike, a: float) -> np.ndarray:
    """Change [m] of a da by a tangential impulse ``dv_t`` [m/s] at semi-major axis ``a`` [m]: 2 dvT / n (seed 002
    Eq. 2; broadcasts)."""
    return 2.0 * np.asarray(dv_t, dtype=float) / float(mean_motion(a))


def drift_lattice(a: float, dv_quantum: float) -> float:
    """Spacing [m] of the a da values quantized tangential burns reach: :func:`a_da_change` of one quantum."""
    return float(a_da_change(dv_quantum, a))


def predicted_drift_sigma(sigma_a_da: float, sigma_rate: float, dt: float) -> float:
    """1-sigma [m] of a da predicted ``dt`` ahead from an OD, its two sigmas taken as independent (the OD message
    carries no cross-covariance).

    Parameters
    ----------
    sigma_a_da, sigma_rate, dt : float
        The OD's 1-sigma of a da [m] and of its drift rate [m/s]; the time ahead [s].

    Returns
    -------
    float
        The 1-sigma [m].
    """
    return math.hypot(sigma_a_da, sigma_rate * dt)


def burns_drift_sigma(dv_t: ArrayLike, a: float, burn_sigma: float) -> float:
    """1-sigma [m] of a da from the magnitude errors of tangential burns still to fly, each ``burn_sigma`` of its a da
    change 2 |dvT| / n (seed 002 Eqs. 2 and 22), independent.

    Parameters
    ----------
    dv_t : array_like, shape (k,)
        The tangential burns [m/s].
    a, burn_sigma : float
        The semi-major axis [m]; the relative 1-sigma magnitude error.

    Returns
    -------
    float
        The 1-sigma [m].
    """
    return float(np.sqrt(np.sum((burn_sigma * a_da_change(dv_t, a)) ** 2)))


def ei_margin(roe_m: ArrayLike, cov_m2: ArrayLike, z: float) -> float:
    """Margin [m] to plan the e/i magnitudes and Eq. (25) with above min_ei: ``z`` times the larger 1-sigma of
    |a de| and |a di| of an OD, each along its own vector (the component that changes the magnitude); a plan that
    ends at min_ei would miss it in about half the runs.

    Parameters
    ----------
    roe_m, cov_m2 : array_like, shapes (6,) and (6, 6)
        The OD's a*ROE [m] and covariance [m^2].
    z : float
        Sigmas of margin.

    Returns
    -------
    float
        The margin [m].
    """
    x = np.asarray(roe_m, dtype=float)
    p = np.asarray(cov_m2, dtype=float).reshape(6, 6)
    out = 0.0
    for k in (2, 4):
        v = x[k:k + 2]
        norm = float(np.hypot(*v))
        if norm > 0.0:
            u = v / norm
            out = max(out, float(np.sqrt(max(u @ p[k:k + 2, k:k + 2] @ u, 0.0))))
    return z * out


def trim_threshold(tolerance: float, sigma: float, lattice: float, z: float = TRIM_SIGMAS) -> float:
    """|a da_F| [m] above which a trim is flown: ``tolerance - z sigma``, at least half the ``lattice`` (a smaller
    error no quantized trim can reduce) and at most the tolerance.

    Parameters
    ----------
    tolerance, sigma, lattice : float
        The |a da| tolerance, the prediction's 1-sigma and :func:`drift_lattice` [m].
    z : float
        Sigmas of margin.

    Returns
    -------
    float
        The threshold [m].
    """
    return min(tolerance, max(0.5 * lattice, tolerance - z * sigma))


def radar_passes(kep: ArrayLike, t0: float, t_start: float, t_end: float, jd0: float, *, station: Station = TIRA,
                 mask_deg: float = 10.0, min_duration: float = 60.0, j2: bool = True) -> np.ndarray:
    """The carrier's passes above ``mask_deg`` at ``station``: the chief's mean elements propagated secularly, the
    Earth oriented by :func:`~roe_sep.core.frames.gcrs_to_itrs` from the UTC Julian date ``jd0`` of sim time 0 (the
    picosatellite, kilometers away, has the same passes to a few seconds).

    Parameters
    ----------
    kep : array_like, shape (6,)
        The chief's mean elements ``[a, e, i, raan, argp, M]`` at ``t0`` [s].
    t0, t_start, t_end, jd0 : float
        Their epoch, the interval [s], and the UTC Julian date of sim time 0.
    station, mask_deg : Station, float
        The radar and its elevation mask [deg].
    min_duration, j2 : float, bool
        Shorter passes [s] are left out (radar_od counts a pass from 5 measurements 10 s apart); J2 rates.

    Returns
    -------
    numpy.ndarray, shape (k, 2)
        Rise and set times [s].
    """
    site_ef, site_enu = station.ecef, station.enu

    def elevation(t: ArrayLike) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        return chief_elevation(propagate_chief(kep, t - t0, j2), gcrs_to_itrs(jd0, t), site_ef, site_enu)

    p = pass_windows(elevation, t_start, t_end, math.radians(mask_deg))
    return p[p[:, 1] - p[:, 0] >= min_duration] if len(p) else np.zeros((0, 2))


def final_od_arc(passes: ArrayLike, t_final: float, min_arc: float, min_passes: int = FINAL_OD_PASSES,
                 cluster_gap: float = 0.0) -> tuple[float, float, float] | None:
    """The radar arc the final OD needs. Its last pass is the last one that ends before ``t_final`` or, with
    ``cluster_gap`` (e.g. :data:`CLUSTER_GAP`), the last of that pass's cluster (the passes that follow it within
    ``cluster_gap``, even after ``t_final``); it starts at the rise of the latest pass that spans ``min_arc`` with
    its end (radar_od's rule) with at least ``min_passes`` passes in the arc.

    Parameters
    ----------
    passes : array_like, shape (k, 2)
        Rise and set times [s] (:func:`radar_passes`).
    t_final, min_arc, cluster_gap : float
        The IC epoch [s], the OD's minimum arc [s], the cluster gap [s].
    min_passes : int
        Passes the arc needs.

    Returns
    -------
    (float, float, float) or None
        ``(start, last_rise, end)`` [s], or None when no such arc exists.
    """
    p = np.asarray(passes, dtype=float).reshape(-1, 2)
    last = np.flatnonzero(p[:, 1] < t_final)
    if not len(last):
        return None
    k = int(last[-1])
    while k + 1 < len(p) and p[k + 1, 0] - p[k, 1] < cluster_gap:
        k += 1
    if k + 1 < min_passes:
        return None
    end = float(p[k, 1])
    early = p[:k + 2 - min_passes]
    early = early[end - early[:, 0] >= min_arc]
    return (float(early[-1, 0]), float(p[k, 0]), end) if len(early) else None


@dataclass(frozen=True)
class TrimDecision:
    """The final trim of an acquisition (see the module docstring); a*ROE in meters, times in seconds."""

    t_final: float  # IC epoch after the decision (the plan's, or one grid step after a trim that falls past it)
    predicted_a_da: float  # m, a da at t_final without the trim (the burns still to fly included)
    sigma_a_da: float  # m, its 1-sigma from the OD
    threshold: float  # m, trim when |predicted_a_da| exceeds it
    epoch: float | None  # s, trim burn epoch (None: no trim)
    u: float | None  # rad, chief mean argument of latitude at the trim
    dv_t: float  # m/s, the carrier's tangential trim (0 without trim)
    final_roe: np.ndarray  # dimensionless ROE predicted at t_final with the trim
    problems: tuple = ()  # the initial conditions missed at t_final even with the trim (it still nulls the drift)

    @property
    def trim(self) -> bool:
        return self.epoch is not None

    def summary(self) -> dict:
        """The decision's numbers for logs and the report."""
        return {"trim": self.trim, "trim_dv": abs(self.dv_t), "predicted_a_da": self.predicted_a_da,
                "sigma_a_da": self.sigma_a_da, "threshold": self.threshold, "t_final": self.t_final,
                "missed": "; ".join(self.problems)}


def ic_problems(final_roe: ArrayLike, a: float, cfg: AcquisitionConfig, leading: bool,
                ei_tolerance_deg: float = 10.0) -> dict[str, str]:
    """The initial conditions a trimmed plan must keep at t_F, apart from the drift: along-track range, e/i
    (anti-)parallel, minimum R-N distance (Eq. 25) and field of view (Eq. 11).

    Parameters
    ----------
    final_roe : array_like, shape (6,)
        The dimensionless ROE at t_F.
    a : float
        The semi-major axis [m].
    cfg : AcquisitionConfig
        The requirements.
    leading : bool
        The configuration (e/i anti-parallel when leading).
    ei_tolerance_deg : float
        The e/i angle allowed [deg].

    Returns
    -------
    dict
        ``{check: violation}``, the checks named as the report's (``along_track``, ``ei_parallel``,
        ``min_rn_distance``, ``fov``).
    """
    f = np.asarray(final_roe, dtype=float) * a
    out = {}
    s = 1.0 if leading else -1.0
    if not cfg.a_dl_min <= s * f[1] <= cfg.a_dl_max:
        out["along_track"] = f"|a dl_F| = {abs(f[1]):.1f} m outside [{cfg.a_dl_min:g}, {cfg.a_dl_max:g}] m"
    angle = math.degrees(float(ei_deviation(final_roe, leading)))
    if angle > ei_tolerance_deg:
        out["ei_parallel"] = f"e/i vectors {angle:.2f} deg from (anti-)parallel"
    if float(min_rn_distance(final_roe)) * a < cfg.min_ei:
        out["min_rn_distance"] = f"minimum R-N distance below min_ei = {cfg.min_ei:g} m"
    de, di = math.hypot(f[2], f[3]), math.hypot(f[4], f[5])
    if de > fov_limit(f[1], math.radians(cfg.fov_half_r_deg)) or di > fov_limit(f[1], math.radians(cfg.fov_half_n_deg)):
        out["fov"] = "outside the camera field of view (Eq. 11)"
    return out


def trim_problems(final_roe: ArrayLike, a: float, cfg: AcquisitionConfig, leading: bool,
                  ei_tolerance_deg: float = 10.0) -> list[str]:
    """The violations of :func:`ic_problems` as a list of texts.

    Parameters
    ----------
    final_roe, a, cfg, leading, ei_tolerance_deg
        As for :func:`ic_problems`.

    Returns
    -------
    list of str
        The violations ([] when the state meets them).
    """
    return list(ic_problems(final_roe, a, cfg, leading, ei_tolerance_deg).values())


def plan_trim(roe0: ArrayLike, chief: Chief, da_dot: float, burns: Sequence[Burn], t_final: float,
              *, t_earliest: float, sigma_a_da: float, sigma_rate: float, tolerance: float,
              cfg: AcquisitionConfig = AcquisitionConfig(), ei_tolerance_deg: float = 10.0, t_od: float | None = None,
              sigma_burns: float = 0.0) -> TrimDecision:
    """The trim decision, made at ``t_final``; a trim aims at the (possibly later) t_F it leaves. The "too uncertain"
    rule is the OD's alone; ``sigma_burns`` adds to the decision's sigma.

    Parameters
    ----------
    roe0, chief, da_dot
        The estimate (dimensionless, at ``chief.t0``, every burn flown so far applied), its chief and drag [1/s].
    burns : sequence of Burn
        The burns still to fly (relative impulses).
    t_final, t_earliest : float
        The IC epoch in force and the earliest burn epoch (now + uplink margin) [s].
    sigma_a_da, sigma_rate, sigma_burns : float
        The OD's 1-sigma of a da [m] and of its drift rate [m/s]; a da's from the burns' errors [m].
    tolerance, ei_tolerance_deg : float
        The |a da| initial condition [m] and the e/i one [deg].
    cfg : AcquisitionConfig
        The planning knobs (grid, quantum, margins).
    t_od : float, optional
        The OD's epoch [s], from which its drift-rate error grows (default ``chief.t0``).

    Returns
    -------
    TrimDecision
        The decision; :class:`AcquisitionInfeasible` when the trim would break another initial condition the
        untrimmed plan keeps (one missed either way goes to ``problems``).
    """
    a = float(chief.a)
    x0 = np.asarray(roe0, dtype=float)
    if x0.shape != (6,) or not np.all(np.isfinite(x0)) or not all(
            math.isfinite(v) for v in (da_dot, t_final, t_earliest, sigma_a_da, sigma_rate, tolerance)):
        raise AcquisitionInfeasible("the trim inputs are not finite")
    leading = x0[1] > 0
    step = 2.0 * math.pi / cfg.grid_per_orbit / float(arg_latitude_rate(a, chief.inc, cfg.j2))
    pending = [b for b in burns if b.epoch >= chief.t0]
    kept = trajectory(x0, chief.t0, pending, [t_final], chief, j2=cfg.j2, da_dot=da_dot)[0]
    predicted = float(kept[0] * a)
    od_sigma = predicted_drift_sigma(sigma_a_da, sigma_rate, t_final - (chief.t0 if t_od is None else t_od))
    sigma = math.hypot(od_sigma, sigma_burns)  # with the execution errors of the burns still to fly
    lattice = drift_lattice(a, cfg.dv_quantum)
    threshold = trim_threshold(tolerance, sigma, lattice)
    if abs(predicted) <= threshold or od_sigma > tolerance / TRIM_SIGMAS:
        return TrimDecision(float(t_final), predicted, sigma, threshold, None, None, 0.0, kept)
    epoch = float(grid_epochs(t_earliest, t_earliest + step, chief, cfg.grid_per_orbit, cfg.j2)[0])
    t_f = max(float(t_final), epoch + step)
    free = trajectory(x0, chief.t0, pending, [t_f], chief, j2=cfg.j2, da_dot=da_dot)[0]
    # a carrier burn +dvT is the relative impulse -dvT: a da changes by -2 dvT / n (Eq. 2)
    quanta = round(float(free[0] * a) / lattice)
    dv_t = float(np.clip(quanta * cfg.dv_quantum, -cfg.max_burn_dv, cfg.max_burn_dv))
    trim = Burn(epoch, (0.0, -dv_t, 0.0))
    final = trajectory(x0, chief.t0, [*pending, trim], [t_f], chief, j2=cfg.j2, da_dot=da_dot)[0]
    problems = ic_problems(final, a, cfg, leading, ei_tolerance_deg)
    # an initial condition the plan misses anyway (a late burn's execution error drifted dl out of its band) does not
    # stop the trim: nulling the drift holds the formation; a check that only the trim would break does
    added = set(problems) - set(ic_problems(free, a, cfg, leading, ei_tolerance_deg))
    if added:
        raise AcquisitionInfeasible("the drift trim would break the initial conditions: "
                                    + "; ".join(problems[k] for k in sorted(added)))
    return TrimDecision(t_f, predicted, sigma, threshold, epoch, float(chief.u_at(epoch, cfg.j2)), dv_t, final,
                        tuple(problems.values()))


__all__ = [
    "TRIM_SIGMAS", "TrimDecision", "a_da_change", "burns_drift_sigma", "drift_lattice", "ei_margin", "final_od_arc",
    "ic_problems", "plan_trim", "predicted_drift_sigma", "radar_passes", "trim_problems", "trim_threshold",
]
