"""The final drift trim of the initial-condition acquisition: a late OD, the predicted a da at the IC epoch, and one
quantized tangential carrier burn when that prediction is not safely inside the drift tolerance.

Why. The acquisition plan of :mod:`.planner` nulls the drift at the IC epoch t_F from an OD made about a day
earlier; the OD's drift-rate error carried that far and the execution errors of the burns flown after it leave
|a da_F| outside the tolerance in some runs (docs/campaigns.md, "Why 9 runs missed the initial conditions"). A
flight-dynamics team closes the loop on the last information: a final radar OD shortly before t_F, then a trim
uplinked with the planning margin, flown before t_F.

Timeline. :func:`radar_passes` predicts the station's passes of the carrier (the chief's secular elements, the
sidereal angle of the scenario's epoch). The final OD is the solution after the last pass before t_F;
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
from dataclasses import dataclass

import numpy as np

from ..constants import SECONDS_PER_DAY
from ..od.radar import TIRA, chief_elevation, gmst, pass_windows
from ..relmotion.dynamics import arg_latitude_rate, propagate_chief
from ..relmotion.orbit import mean_motion
from ..relmotion.trajectory import Burn, Chief, trajectory
from ..safety.metrics import fov_limit, min_rn_distance
from .lp_transfer import grid_epochs
from .planner import AcquisitionConfig, AcquisitionInfeasible, ei_deviation

TRIM_SIGMAS = 3.0  # z of the decision threshold (one-sided normal tail 0.13 %)
FINAL_OD_PASSES = 3  # passes in the final OD's arc: two (radar_od's minimum) leave a da to tens of meters
CLUSTER_GAP = 7200.0  # s, passes closer than this (about one orbit apart) form a cluster


def a_da_change(dv_t, a):
    """Change [m] of a da by a tangential impulse ``dv_t`` [m/s] at semi-major axis ``a`` [m]: 2 dvT / n (seed 002
    Eq. 2; broadcasts)."""
    return 2.0 * np.asarray(dv_t, dtype=float) / float(mean_motion(a))


def drift_lattice(a, dv_quantum):
    """Spacing [m] of the a da values quantized tangential burns reach: :func:`a_da_change` of one quantum."""
    return float(a_da_change(dv_quantum, a))


def predicted_drift_sigma(sigma_a_da, sigma_rate, dt):
    """1-sigma [m] of a da predicted ``dt`` [s] ahead from an OD: its a da sigma [m] and drift-rate sigma [m/s],
    taken as independent (the OD message carries no cross-covariance)."""
    return math.hypot(sigma_a_da, sigma_rate * dt)


def burns_drift_sigma(dv_t, a, burn_sigma):
    """1-sigma [m] of a da from the magnitude errors of tangential burns ``dv_t`` [m/s] still to fly, each
    ``burn_sigma`` (relative 1-sigma) of its a da change 2 |dvT| / n (seed 002 Eqs. 2 and 22), independent."""
    return float(np.sqrt(np.sum((burn_sigma * a_da_change(dv_t, a)) ** 2)))


def ei_margin(roe_m, cov_m2, z):
    """Margin [m] to plan the e/i magnitudes and Eq. (25) with above min_ei: ``z`` times the larger 1-sigma of
    |a de| and |a di| of an OD (``roe_m`` a*ROE [m], ``cov_m2`` its 6x6 covariance [m^2]), each along its own vector
    (the component that changes the magnitude). Radar ODs know a de to about 20 m: a plan that ends at min_ei misses
    it in about half the runs whose e/i vector the optimum puts there."""
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


def trim_threshold(tolerance, sigma, lattice, z=TRIM_SIGMAS):
    """|a da_F| [m] above which a trim is flown: ``tolerance - z sigma``, at least half the ``lattice`` (a smaller
    error no quantized trim can reduce) and at most the tolerance."""
    return min(tolerance, max(0.5 * lattice, tolerance - z * sigma))


def radar_passes(kep, t0, t_start, t_end, jd0, *, station=TIRA, mask_deg=10.0, min_duration=60.0, j2=True):
    """Rise/set times [s] ``(k, 2)`` of the carrier's passes above ``mask_deg`` at ``station`` in [t_start, t_end]:
    the chief's mean elements ``kep`` ``[a, e, i, raan, argp, M]`` at ``t0`` propagated secularly, the Earth turned
    by the sidereal angle of Julian date ``jd0`` at sim time 0 (the picosatellite is kilometers from the carrier:
    the same passes to a few seconds); passes shorter than ``min_duration`` [s] are left out (radar_od counts a
    pass from 5 measurements 10 s apart)."""
    site_ef, site_enu = station.ecef, station.enu

    def elevation(t):
        t = np.asarray(t, dtype=float)
        return chief_elevation(propagate_chief(kep, t - t0, j2), gmst(jd0 + t / SECONDS_PER_DAY), site_ef, site_enu)

    p = pass_windows(elevation, t_start, t_end, math.radians(mask_deg))
    return p[p[:, 1] - p[:, 0] >= min_duration] if len(p) else np.zeros((0, 2))


def final_od_arc(passes, t_final, min_arc, min_passes=FINAL_OD_PASSES, cluster_gap=0.0):
    """``(start, last_rise, end)`` [s] of the radar arc the final OD needs, or None. Its last pass is the last one
    that ends before ``t_final`` or, with ``cluster_gap`` (e.g. :data:`CLUSTER_GAP`), the last of that pass's
    cluster (the passes that follow it within ``cluster_gap``, even after ``t_final``): ``last_rise`` its rise,
    ``end`` its set; ``start`` the rise of the latest pass that spans ``min_arc`` [s] with ``end`` (radar_od's rule:
    from the first measurement of the first pass to the last of the last) with at least ``min_passes`` passes in the
    arc."""
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
    def trim(self):
        return self.epoch is not None

    def summary(self):
        return {"trim": self.trim, "trim_dv": abs(self.dv_t), "predicted_a_da": self.predicted_a_da,
                "sigma_a_da": self.sigma_a_da, "threshold": self.threshold, "t_final": self.t_final,
                "missed": "; ".join(self.problems)}


def ic_problems(final_roe, a, cfg: AcquisitionConfig, leading, ei_tolerance_deg=10.0):
    """The initial conditions a trimmed plan must keep at t_F, apart from the drift: along-track range, e/i
    (anti-)parallel, minimum R-N distance (Eq. 25) and field of view (Eq. 11); ``{check: violation}``, the checks
    named as the report's (``along_track``, ``ei_parallel``, ``min_rn_distance``, ``fov``)."""
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


def trim_problems(final_roe, a, cfg: AcquisitionConfig, leading, ei_tolerance_deg=10.0):
    """The violations of :func:`ic_problems` as a list of texts ([] when the state meets them)."""
    return list(ic_problems(final_roe, a, cfg, leading, ei_tolerance_deg).values())


def plan_trim(roe0, chief: Chief, da_dot, burns, t_final, t_earliest, sigma_a_da, sigma_rate, tolerance,
              cfg: AcquisitionConfig = AcquisitionConfig(), ei_tolerance_deg=10.0, t_od=None,
              sigma_burns=0.0) -> TrimDecision:
    """The trim decision from the estimate ``roe0`` (dimensionless, at ``chief.t0``, every burn flown so far applied)
    with the ``burns`` still to fly (:class:`Burn`, relative impulses), the IC epoch ``t_final`` in force and the
    earliest burn epoch ``t_earliest`` (now + uplink margin). ``sigma_a_da`` [m] and ``sigma_rate`` [m/s]: the OD's
    1-sigma of a da and of its drift rate; ``tolerance`` [m]: the |a da| initial condition (``ei_tolerance_deg``: its
    e/i one); ``t_od`` [s]: the OD's epoch, from which its drift-rate error grows (default ``chief.t0``);
    ``sigma_burns`` [m]: the 1-sigma of a da from the execution errors of the ``burns`` (:func:`burns_drift_sigma`),
    in the decision's sigma beside the OD's (the "too uncertain" rule is the OD's alone). The
    decision is made at ``t_final``; a trim aims at the (possibly later) t_F it leaves. Raises
    :class:`AcquisitionInfeasible` when the trim would break another initial condition that the untrimmed plan keeps;
    one the plan misses either way is in the decision's ``problems`` and the trim still nulls the drift."""
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
