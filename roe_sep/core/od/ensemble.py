"""A deterministic OD ensemble on the nonlinear truth, without DDS: is the batch OD's covariance honest?

Each member is one pair of :mod:`roe_sep.core.truth.nonlinear` (J2-J4, drag in the normalised exponential
atmosphere of the simulator, the differential ballistic coefficient dispersed as the simulator does) from just after
the drift-stop, with the picosatellite's along-track acquisition-sized burns at the closed loop's usual epochs
(:data:`BURNS`). The radar is simulated as ``radar_od`` does it (TIRA, 10 deg mask, a measurement every
``sample_interval`` from the truth's mean ROE and the carrier's mean elements, only >= ``min_separation`` apart,
a pass counted from ``min_pass`` measurements), and the OD runs as the node runs it: after every counted pass once
>= 2 passes since the latest burn span >= ``min_arc``, on the measurements since that burn, with the drift prior
(:class:`~roe_sep.core.od.batch.DriftPrior`) of the last solution before the burn when ``prior`` is on. Each
member's truth is observed with ``draws`` independent noise sequences.

Every solution is compared with the truth's secular state at its epoch (:func:`secular_state`, as the run report
does): its mean ROE with a da and the drift rate of the truth's secular drift (:func:`secular_drift`).
For a consistent estimator the 7-state NEES is chi-square with 7 degrees of freedom and the drift-rate z standard
normal (Bar-Shalom, Li, Kirubarajan 2001, Sec. 5.4): over N solutions the mean NEES lies in
chi2(7N, 0.025..0.975) / N and the mean z^2 in chi2(N, ...) / N with 95 % probability
(:func:`~roe_sep.core.montecarlo.stats.nees_bounds`).
"""

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..constants import R_EARTH, SECONDS_PER_DAY
from ..frames import gcrs_to_itrs
from ..montecarlo.stats import nees_bounds
from ..relmotion.dynamics import propagate_chief
from ..relmotion.orbit import mean_motion
from .batch import DragModel, DriftPrior, RadarBatch, batch_least_squares, nees
from .radar import DEFAULT_EPOCH_UTC, TIRA, julian_date, observe, raan_from_ltan, relative_distance

if TYPE_CHECKING:  # the nonlinear truth and the designs are imported where they are used (the report imports this)
    from ..separation.double_impulse import DoubleImpulseDesign
    from ..truth.nonlinear import Atmosphere

T0 = 9200.0
"""s, start of the ensemble: just after the default scenario's drift-stop (9156 s)."""

INITIAL_A_ROE = (np.array([-100.0, 8800.0, 50.0, -470.0, 12.0, 390.0]),
                 np.array([35.0, 500.0, 130.0, 25.0, 2.0, 35.0]))
"""m, mean and 1-sigma of the truth's a*ROE just after the drift-stop (the spread of seeds 1000-1013)."""

BURNS = ((87244.0, 0.065, 0.02), (90095.0, 0.095, 0.03), (172779.0, -0.010, 0.008), (175274.0, -0.004, 0.006),
         (247978.0, 0.008, 0.010))
"""(epoch [s], mean, 1-sigma [m/s]) of the picosatellite's along-track burns: the closed loop's acquisition burns
(carrier burns of the opposite sign, seeds 1000-1013)."""

DURATION = 280800.0
"""s, end of the ensemble (a run's duration)."""

MIN_DRIFT_ORBITS = 1.0
"""Shortest burn-free truth span, in orbits, over which the truth has a secular drift (:func:`secular_drift`)."""

QUADRATIC_ORBITS = 6.0
"""Shortest span, in orbits, over which :func:`secular_drift` fits the drift rate's growth (a quadratic): over
fewer, an orbit-periodic term of the truth's mean a da (drag's short-periodic terms, about 0.1 m) that the
harmonics do not take moves the quadratic's end slope by more than a line's (without harmonics, 0.09 m/day at
6 orbits, worst phase)."""


def secular_drift(t: ArrayLike, a_da: ArrayLike, t_ref: float, period: float,
                  u: ArrayLike | None = None) -> tuple[float, float] | None:
    """The truth's secular a da and its rate at ``t_ref``: least squares of a quadratic in time (the drift rate grows
    as the pair decays, :meth:`~roe_sep.core.od.batch.DragModel.growth`) over at least :data:`QUADRATIC_ORBITS`
    orbital periods, a line over at least :data:`MIN_DRIFT_ORBITS`; with ``u``, plus the harmonics sin u, cos u,
    sin 2u, cos 2u. The OD's state is secular, the truth's first-order mean elements keep drag's orbit-periodic
    centimeters of a da, which a day-long batch resolves: the fit removes them (measured in docs/campaigns.md).

    Parameters
    ----------
    t, a_da : array_like, shape (n,)
        Sample times [s] over one burn-free span ending at ``t_ref``; the truth's mean a da there [m].
    t_ref, period : float
        The epoch [s]; the orbital period [s].
    u : array_like, shape (n,), optional
        The carrier's mean argument of latitude at ``t`` [rad].

    Returns
    -------
    (float, float) or None
        a da [m] and its rate [m/s] at ``t_ref``; None over too short a span.
    """
    t = np.asarray(t, dtype=float)
    a_da = np.asarray(a_da, dtype=float)
    span = float(np.ptp(t)) if t.size else 0.0
    if t.size < 8 or span < MIN_DRIFT_ORBITS * period:
        return None
    tau = t - t_ref
    cols = [np.ones_like(tau), tau] + ([tau * tau] if span >= QUADRATIC_ORBITS * period else [])
    if u is not None:
        u = np.asarray(u, dtype=float)
        cols += [np.sin(u), np.cos(u), np.sin(2.0 * u), np.cos(2.0 * u)]
    design = np.stack(cols, axis=-1)
    scale = np.linalg.norm(design, axis=0)
    c = np.linalg.lstsq(design / scale, a_da, rcond=None)[0] / scale
    return float(c[0]), float(c[1])


def secular_state(mean_a_roe: ArrayLike, t: ArrayLike, a_da: ArrayLike, t_ref: float, period: float, *,
                  u: ArrayLike | None = None) -> np.ndarray | None:
    """The truth's secular state at ``t_ref``: its mean a*ROE there with a da and the rate of :func:`secular_drift`.

    Parameters
    ----------
    mean_a_roe : array_like, shape (6,)
        The truth's mean a*ROE at ``t_ref`` [m].
    t, a_da, t_ref, period, u
        As for :func:`secular_drift`.

    Returns
    -------
    numpy.ndarray, shape (7,), or None
        a*ROE [m] and a*da_dot [m/s]; None where :func:`secular_drift` is None.
    """
    drift = secular_drift(t, a_da, t_ref, period, u)
    if drift is None:
        return None
    out = np.append(np.asarray(mean_a_roe, dtype=float), drift[1])
    out[0] = drift[0]
    return out


@dataclass(frozen=True)
class Solution:
    """One OD solution against the truth: member, noise draw, index in its chain, burn segment, epoch [s], drift
    rate estimate / truth / sigma [m/day], 7- and 6-state NEES and whether a drift prior was used."""

    member: int
    draw: int
    index: int
    segment: int
    t: float
    a_da_dot: float
    a_da_dot_truth: float
    a_da_dot_sigma: float
    nees7: float
    nees6: float
    prior: bool

    @property
    def z(self) -> float:
        return (self.a_da_dot - self.a_da_dot_truth) / self.a_da_dot_sigma


def carrier_after_drift_stop(chief: ArrayLike, carrier: "DoubleImpulseDesign") -> np.ndarray:
    """The carrier's mean elements ``chief`` (circular) with the eccentricity vector its own drift-stop gave it: the
    carrier burns -dv2 (the design's drift-stop, relative effect dv2) at u2, which changes its e vector by Gauss's
    equations (seed 002 Eq. 2, :func:`~roe_sep.core.relmotion.maneuvers.delta_roe` of its own burn), whose drag
    drift the OD models (:func:`~roe_sep.core.od.batch.drag_de_drift`). The argument of latitude is kept."""
    from ..relmotion.maneuvers import delta_roe

    de = delta_roe(-np.asarray(carrier.dv2_rtn, dtype=float), carrier.u2, carrier.a, carrier.n)[2:4]
    ev = chief[1] * np.array([math.cos(chief[4]), math.sin(chief[4])]) + de
    out = np.array(chief, dtype=float)
    u = chief[4] + chief[5]
    out[1], out[4] = float(np.hypot(*ev)), float(math.atan2(ev[1], ev[0]))
    out[5] = u - out[4]
    return out


def scenario_pairs(members: int, seed: int) -> tuple:
    """Initial pair states ``(members, 12)`` at :data:`T0`, carrier and picosatellite ballistic coefficients
    ``(members,)``, the atmosphere, the carrier's mean elements at T0 and the drag model (default scenario)."""
    from ..config import load_scenario
    from ..relmotion.roe import roe_to_kepler
    from ..separation.double_impulse import design
    from ..truth.nonlinear import Atmosphere, pair_state, vallado_band
    from ..truth.secular import chief_from_u

    sc = load_scenario(None)
    carrier, mc = design(sc.separation), sc.monte_carlo
    raan = float(raan_from_ltan(9.5, julian_date(DEFAULT_EPOCH_UTC)))
    chief0 = chief_from_u(carrier.a, carrier.inc, raan, math.radians(50.0))
    chief = carrier_after_drift_stop(propagate_chief(chief0, T0), carrier)
    rng = np.random.default_rng(seed)
    roe = (INITIAL_A_ROE[0] + INITIAL_A_ROE[1] * rng.standard_normal((members, 6))) / carrier.a
    deputy = roe_to_kepler(np.broadcast_to(chief, (members, 6)), roe)
    b_c = mc.carrier.ballistic
    b_d = b_c + mc.delta_b * rng.normal(1.0, mc.ballistic_sigma, members)
    dv = np.array([m + s * rng.standard_normal(members) for _, m, s in BURNS]).T  # (members, burns)
    model = DragModel(vallado_band(carrier.a - R_EARTH)[2], (b_c + mc.delta_b) / mc.delta_b)
    return (pair_state(np.broadcast_to(chief, (members, 6)), deputy), b_c, b_d, dv,
            Atmosphere.normalised(mc.density, chief0), model)


def truth_samples(states0: np.ndarray, b_c: ArrayLike, b_d: ArrayLike, dv: np.ndarray, atmosphere: "Atmosphere", *,
                  times: np.ndarray) -> np.ndarray:
    """Pair states at the sorted ``times`` (which hold every burn epoch), the picosatellite's along-track burns
    applied at the :data:`BURNS` epochs (a sample at a burn epoch is pre-burn).

    Parameters
    ----------
    states0 : numpy.ndarray, shape (members, 12)
        The pair states at :data:`T0`.
    b_c, b_d : array_like, shape (members,)
        Carrier and picosatellite ballistic coefficients.
    dv : numpy.ndarray, shape (members, burns)
        The along-track burns [m/s].
    atmosphere : Atmosphere
        The truth's atmosphere.
    times : numpy.ndarray, shape (n,)
        Sorted sample times [s].

    Returns
    -------
    numpy.ndarray, shape (members, n, 12)
        The pair states.
    """
    from ..truth.nonlinear import apply_impulse, propagate_pairs_grid

    out = np.empty((states0.shape[0], times.size, 12))
    state, t0, lo = states0, T0, 0
    for k, edge in enumerate([b[0] for b in BURNS] + [math.inf]):
        hi = int(np.searchsorted(times, edge, side="right"))
        if hi > lo:
            out[:, lo:hi] = propagate_pairs_grid(state, t0, times[lo:hi], b_c, b_d, atmosphere=atmosphere)
        if k < len(BURNS):
            pre = out[:, hi - 1]  # the burn epoch itself
            rtn = np.zeros((dv.shape[0], 3))
            rtn[:, 1] = dv[:, k]
            state, t0, lo = apply_impulse(pre, rtn, np.ones(dv.shape[0], bool)), edge, hi
    return out


def run_ensemble(members: int = 8, draws: int = 4, seed: int = 0, prior: bool = True, sample_interval: float = 10.0,
                 *, mask_deg: float = 10.0, min_separation: float = 5000.0, min_pass: int = 5, min_arc: float = 36000.0,
                 sigma_range: float = 10.0, sigma_angle_deg: float = 0.01, density_walk: float = 0.0,
                 noise_scale: float = 1.0) -> list[Solution]:
    """The ensemble (module docstring). Deterministic in ``seed`` (truth dispersions from ``seed``, noise of member
    m, draw d from SeedSequence([seed, m, d])).

    Parameters
    ----------
    members, draws, seed : int
        Truth pairs, noise draws per pair, the seed.
    prior, density_walk : bool, float
        Carry the drift prior across burns; its density random walk (per sqrt(day)).
    sample_interval, mask_deg, min_separation : float
        The radar's sampling [s], elevation mask [deg] and least resolvable separation [m].
    min_pass, min_arc : int, float
        Measurements of a pass; the OD's minimum arc [s].
    sigma_range, sigma_angle_deg, noise_scale : float
        Range [m] and angle [deg] 1-sigma; the noise actually drawn, as a multiple of them.

    Returns
    -------
    list of Solution
        Chain by chain in time order.
    """
    from ..truth.nonlinear import mean_elements, mean_roe

    states0, b_c, b_d, dv, atmosphere, model = scenario_pairs(members, seed)
    jd0 = julian_date(DEFAULT_EPOCH_UTC)
    # the carrier does not burn: its passes (padded by a minute) hold every epoch the picosatellite can be seen
    grid = np.arange(math.ceil(T0 / sample_interval), math.floor(DURATION / sample_interval) + 1) * sample_interval
    chief_nominal = mean_elements(states0[:1])[0, 0]
    period = 2.0 * math.pi / float(mean_motion(chief_nominal[0]))
    earth_g = gcrs_to_itrs(jd0, grid)
    el = observe(np.zeros(6), propagate_chief(chief_nominal, grid - T0), earth_g, TIRA.ecef, TIRA.enu)[:, 2]
    near = np.convolve(el > math.radians(mask_deg) - 0.05, np.ones(13), mode="same") > 0
    burn_t = np.array([b[0] for b in BURNS])
    coarse = np.arange(T0, DURATION, 300.0)
    times = np.unique(np.concatenate([grid[near], burn_t, coarse]))
    st = truth_samples(states0, b_c, b_d, dv, atmosphere, times=times)
    kep = mean_elements(st)  # (members, times, 2, 6)
    chief, roe = kep[..., 0, :], mean_roe(st)
    earth = gcrs_to_itrs(jd0, times)
    meas = np.isin(times, grid[near]) & ~np.isin(times, burn_t)
    uniform = np.isin(times, coarse)
    sigma = np.array([sigma_range, math.radians(sigma_angle_deg), math.radians(sigma_angle_deg)])
    segment_of = np.searchsorted(burn_t, times, side="left")  # a burn-epoch sample belongs to the segment it ends
    out = []
    for m in range(members):
        z_true = observe(roe[m], chief[m], earth, TIRA.ecef, TIRA.enu)
        sep = relative_distance(roe[m], chief[m, :, 0], chief[m, :, 4] + chief[m, :, 5])
        seen = meas & (z_true[:, 2] > math.radians(mask_deg)) & (sep >= min_separation)
        # a pass: consecutive measurement epochs (one sample_interval apart) of one segment
        idx = np.nonzero(seen)[0]
        breaks = np.nonzero((np.diff(times[idx]) > 1.5 * sample_interval)
                            | (np.diff(segment_of[idx]) != 0))[0] + 1
        passes = [p for p in np.split(idx, breaks) if p.size >= min_pass]
        a_da = roe[m, :, 0] * chief[m, :, 0]
        for d in range(draws):
            rng = np.random.default_rng(np.random.SeedSequence([seed, m, d]))
            z = z_true + noise_scale * sigma * rng.standard_normal(z_true.shape)
            z[:, 1] = np.mod(z[:, 1], 2.0 * np.pi)
            carried, last, seg_prev, k = None, None, -1, 0
            for j, p in enumerate(passes):
                seg = segment_of[p[0]]
                if seg != seg_prev:  # a burn since the last pass: the last solution before it becomes the prior
                    if last is not None and prior:
                        carried = DriftPrior.from_result(last[0], last[1], model)
                    seg_prev = seg
                mine = [q for q in passes[:j + 1] if segment_of[q[0]] == seg]
                if len(mine) < 2:
                    continue
                rows = np.concatenate(mine)
                if times[rows[-1]] - times[rows[0]] < min_arc:
                    continue
                batch = RadarBatch(t=times[rows], z=z[rows], sigma=np.tile(sigma, (rows.size, 1)),
                                   chief=chief[m, rows], earth=earth[rows],
                                   site_ef=np.tile(TIRA.ecef, (rows.size, 1)),
                                   site_enu=np.tile(TIRA.enu, (rows.size, 1, 1)))
                t_est = float(times[rows[-1]])
                res = batch_least_squares(batch, model=model, prior=None if carried is None else
                                          carried.carried(t_est, density_walk))
                a = float(chief[m, rows[-1], 0])
                last = (res, a)
                start = burn_t[seg - 1] if seg > 0 else T0
                # the uniform grid (the passes see the same orbital phases), after the burn (its sample is pre-burn)
                span = uniform & (times > start) & (times <= t_est)
                truth7 = secular_state(roe[m, rows[-1]] * a, times[span], a_da[span], t_est, period,
                                       u=chief[m, span, 4] + chief[m, span, 5]) / a
                mean, mean_cov = res.mean_state()
                out.append(Solution(m, d, k, int(seg), t_est, res.x[6] * a * SECONDS_PER_DAY,
                                    truth7[6] * a * SECONDS_PER_DAY, math.sqrt(res.cov[6, 6]) * a * SECONDS_PER_DAY,
                                    nees(mean, truth7, mean_cov), nees(mean[:6], truth7[:6], mean_cov[:6, :6]),
                                    carried is not None))
                k += 1
    return out


def consistency(solutions: list[Solution], which: str) -> dict:
    """Statistics of the first or last solution of every chain (``which`` 'first' | 'last' | 'all'): count, mean
    7-state NEES with its band, mean drift-rate z^2 with its band, mean 6-state NEES, the fraction of 7-state NEES
    inside the single-run 95 % bound chi2(7, 0.95) and of |z| inside 1.96, mean drift-rate sigma [m/day]."""
    from scipy.stats import chi2  # here, not at import: the run report imports this module

    chains = {}
    for s in solutions:
        chains.setdefault((s.member, s.draw), []).append(s)
    pick = {"first": lambda c: [c[0]], "last": lambda c: [c[-1]], "all": lambda c: c}[which]
    sel = [s for c in chains.values() for s in pick(c)]
    n = len(sel)
    nees7 = np.array([s.nees7 for s in sel])
    z = np.array([s.z for s in sel])
    return {"n": n, "nees7": float(nees7.mean()), "nees7_band": nees_bounds(7, n),
            "nees6": float(np.mean([s.nees6 for s in sel])), "nees6_band": nees_bounds(6, n),
            "z2": float(np.mean(z * z)), "z2_band": nees_bounds(1, n),
            "inside95_nees7": float(np.mean(nees7 <= chi2.ppf(0.95, 7))),
            "inside95_z": float(np.mean(np.abs(z) <= 1.96)),
            "sigma_m_per_day": float(np.mean([s.a_da_dot_sigma for s in sel])),
            "with_prior": int(sum(s.prior for s in sel))}
