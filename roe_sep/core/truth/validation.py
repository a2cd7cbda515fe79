"""Model error of the secular ROE propagation against the nonlinear truth, and the nonlinear Monte Carlo.

Model error (issue 5 item 3): for a separation case (a chief orbit and a time-ordered list of burns, generic, so
the double impulse of seeds 000/002 and the multi-impulse plan of seed 001 are two instances) the core's
:func:`~roe_sep.core.relmotion.trajectory.trajectory` (Keplerian, J2 or J2 + differential drag) is compared with
:func:`~roe_sep.core.truth.nonlinear.propagate_pair` whose states are converted to mean ROE
(:func:`~roe_sep.core.truth.nonlinear.mean_roe`), per ROE a*(model - truth) [m] at whole days after the ejection and as
the largest RTN position difference [m] over the interval (model: the linear map :func:`~roe_sep.core.relmotion.roe.
roe_to_rtn` of the mean ROE, truth: the numerical relative position in the carrier's RTN frame, which includes
the short-period J2 terms and the curvature the mean linear model leaves out).

Nonlinear Monte Carlo (item 4): the draws of :func:`~roe_sep.core.montecarlo.sweep.draw`, every sample pair integrated
numerically (batched, :func:`~roe_sep.core.truth.nonlinear.propagate_pairs`), the outcomes summarized with the same
:func:`~roe_sep.core.montecarlo.sweep.summarize` as the linear sweep.
"""

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ...errors import show
from ..constants import SECONDS_PER_DAY
from ..montecarlo.sweep import MonteCarloConfig, Outcome, draw, summarize, sweep
from ..od.radar import DEFAULT_EPOCH_UTC, julian_date, raan_from_ltan
from ..relmotion.dynamics import arg_latitude_rate, drag_da_dot
from ..relmotion.maneuvers import dispersed_dv
from ..relmotion.roe import ROE_NAMES, roe_to_rtn
from ..relmotion.trajectory import Burn, Chief, trajectory
from ..safety.metrics import min_rn_distance
from ..separation.double_impulse import DoubleImpulseDesign
from ..separation.multi_impulse import MultiImpulseDesign
from .nonlinear import (
    Atmosphere,
    Maneuver,
    apply_impulse,
    effective_density,
    mean_roe,
    pair_state,
    propagate_pair,
    propagate_pairs,
    relative_rtn,
)

MODELS = ("keplerian", "j2", "j2drag")
"""Settings of the core's secular model: (j2, drag) = (False, False), (True, False), (True, True)."""

MC_ZONALS = 2
"""Zonal degree of the nonlinear Monte Carlo. J3/J4 triple the cost of a step (measured) and change the ROE by less
than the table row ``j2-only truth`` shows (both spacecraft feel them almost identically)."""

MC_TOL = 1e-12
"""Taylor tolerance of the Monte Carlo (25 % faster than 1e-15; the relative state changes by < 1 mm, tested)."""


@dataclass(frozen=True)
class Case:
    """A separation case on a common time scale: chief mean elements at t = 0 (the ejection), the burns
    (:class:`~roe_sep.core.truth.nonlinear.Maneuver`), the drag properties, the scenario density (the linear
    model's rho) and the truth's atmosphere (``None``: the default, :meth:`Atmosphere.normalised` to ``density``;
    any other model of :func:`~roe_sep.core.truth.nonlinear.truth_atmosphere`)."""

    name: str
    chief_mean: np.ndarray  # [a, e, i, raan, argp, M] at t = 0
    maneuvers: tuple
    b_chief: float  # m^2/kg
    b_deputy: float  # m^2/kg
    density: float  # kg/m^3, the linear model's rho (seed 002: 1 g/km^3)
    truth_atmosphere: object = None

    @property
    def a(self) -> float:
        """The chief's semi-major axis [m]."""
        return float(self.chief_mean[0])

    @property
    def inc(self) -> float:
        """The chief's inclination [rad]."""
        return float(self.chief_mean[2])

    @property
    def chief(self) -> Chief:
        """The chief as the relative dynamics need it (u at t = 0 = argp + M)."""
        return Chief(self.a, self.inc, float(self.chief_mean[4] + self.chief_mean[5]), 0.0)

    @property
    def atmosphere(self) -> object:
        """The truth's density model (:class:`~roe_sep.core.truth.nonlinear.Atmosphere` or another model)."""
        if self.truth_atmosphere is not None:
            return self.truth_atmosphere
        return Atmosphere.normalised(self.density, self.chief_mean)

    def burns(self) -> list[Burn]:
        """The maneuvers as the core's relative burns (seed convention)."""
        return [Burn(m.epoch, tuple(m.relative())) for m in self.maneuvers]


def sso_raan(ltan_hours: float = 9.5, epoch_utc: str = DEFAULT_EPOCH_UTC) -> float:
    """RAAN [rad] of the carrier's orbit at ``epoch_utc`` for a local time of the ascending node (BIROS: 09:30):
    where the Sun is relative to the orbit, which the empirical atmosphere's diurnal bulge depends on."""
    return float(raan_from_ltan(ltan_hours, julian_date(epoch_utc)))


def double_impulse_case(d: DoubleImpulseDesign, mc: MonteCarloConfig = MonteCarloConfig(), raan: float = 0.0) -> Case:
    """The nominal double impulse: SPL ejection (picosatellite, ``dv1``) at u1, t = 0; the carrier's drift-stop
    (its own burn -dv2, Eq. 9) k pi later at the secular J2 rate of u (as the planner node schedules it).

    Parameters
    ----------
    d : DoubleImpulseDesign
        The nominal design.
    mc : MonteCarloConfig
        The spacecraft's drag properties and the density.
    raan : float
        The chief's right ascension of the ascending node [rad] (:func:`sso_raan`).

    Returns
    -------
    Case
        The case named ``double_impulse``.
    """
    dt = d.k * math.pi / float(arg_latitude_rate(d.a, d.inc, True))
    chief = np.array([d.a, 0.0, d.inc, raan, 0.0, d.u1])
    burns = (Maneuver(0.0, tuple(d.dv1_rtn), True), Maneuver(dt, tuple(0.0 - d.dv2_rtn), False))
    return Case("double_impulse", chief, burns, mc.carrier.ballistic, mc.picosat.ballistic, mc.density)


def multi_impulse_case(md: MultiImpulseDesign, mc: MonteCarloConfig = MonteCarloConfig(), raan: float = 0.0) -> Case:
    """The nominal multi-impulse plan of :mod:`roe_sep.core.separation.multi_impulse` (ejection at t = 0, carrier
    burns).

    Parameters
    ----------
    md : MultiImpulseDesign
        The nominal design.
    mc : MonteCarloConfig
        The spacecraft's drag properties and the density.
    raan : float
        The chief's right ascension of the ascending node [rad].

    Returns
    -------
    Case
        The case named ``multi_impulse``.
    """
    chief = np.array([md.a, 0.0, md.inc, raan, 0.0, md.u1])
    burns = [Maneuver(0.0, tuple(md.dv1_rtn), True)]
    burns += [Maneuver(float(b.epoch), tuple(b.dv_carrier_rtn), False) for b in md.plan.burns]
    return Case("multi_impulse", chief, tuple(burns), mc.carrier.ballistic, mc.picosat.ballistic, mc.density)


def model_trajectory(case: Case, times: ArrayLike, model: str = "j2drag", density: float | None = None) -> np.ndarray:
    """The core's secular model along ``times`` [s]: dimensionless ROE ``(T, 6)``.

    Parameters
    ----------
    case : Case
        The case (its burns, chief and drag).
    times : array_like, shape (T,)
        Times after the ejection [s], >= 0.
    model : str
        One of ``MODELS``: ``keplerian``, ``j2`` or ``j2drag``.
    density : float, optional
        The drag model's density [kg/m^3]; default ``case.density``.

    Returns
    -------
    numpy.ndarray, shape (T, 6)
        Dimensionless ROE.
    """
    if model not in MODELS:
        raise ValueError(f"model must be one of {MODELS}, got {show(model)}")
    j2 = model != "keplerian"
    rho = case.density if density is None else density
    da_dot = float(drag_da_dot(case.b_deputy - case.b_chief, rho, case.a)) if model == "j2drag" else 0.0
    return trajectory(np.zeros(6), 0.0, case.burns(), times, case.chief, j2=j2, da_dot=da_dot)


def truth_states(case: Case, times: ArrayLike, zonals: int = 4) -> np.ndarray:
    """Nonlinear pair states ``(T, 12)`` along ``times`` [s] (both spacecraft start on the chief's state).

    Parameters
    ----------
    case : Case
        The case.
    times : array_like, shape (T,)
        Times after the ejection [s].
    zonals : int
        Highest zonal harmonic of the gravity field (2: J2 only, 4: J2-J4).

    Returns
    -------
    numpy.ndarray, shape (T, 12)
        Inertial position [m] and velocity [m/s] of the carrier, then of the picosatellite.
    """
    s0 = pair_state(case.chief_mean, case.chief_mean)
    return propagate_pair(s0, 0.0, times, case.maneuvers, case.b_chief, b_deputy=case.b_deputy,
                          atmosphere=case.atmosphere, zonals=zonals)


@dataclass
class ModelError:
    """Model minus truth for one case and model."""

    case: str
    model: str
    days: list  # whole days after the ejection
    roe_error: np.ndarray  # (len(days), 6) m, a*(model - truth) at those days
    rtn_error_max: np.ndarray  # (len(days),) m, max |r_model - r_truth| over [first burn + 1 orbit, day]
    distance_error_max: np.ndarray  # (len(days),) m, max ||r_model| - |r_truth|| over the same interval
    truth_roe: np.ndarray  # (len(days), 6) m

    def to_dict(self) -> dict:
        """The errors as JSON (m; ROE errors per element)."""
        return {"case": self.case, "model": self.model, "days": self.days,
                "roe_error": {n: self.roe_error[:, k].tolist() for k, n in enumerate(ROE_NAMES)},
                "rtn_error_max": self.rtn_error_max.tolist(), "distance_error_max": self.distance_error_max.tolist(),
                "truth_roe": self.truth_roe.tolist()}


def model_errors(case: Case, days: Sequence[float] = (1, 2, 3), step: float = 60.0, models: Iterable[str] = MODELS,
                 zonals: int = 4, *, effective: bool = False) -> list[ModelError]:
    """Model error of each of ``models`` against the nonlinear truth (see the module docstring).

    One truth integration serves every model. The RTN comparison samples every ``step`` seconds. ``effective``
    adds the row ``j2drag_eff``: the j2drag model with the truth atmosphere's orbit-mean drag as its density
    (:func:`~roe_sep.core.truth.nonlinear.effective_density` over the span), what a perfectly known mean density
    would leave.

    Parameters
    ----------
    case : Case
        The case.
    days : sequence of float
        Whole days after the ejection at which the errors are taken.
    step : float
        Sampling of the RTN comparison [s].
    models : iterable of str
        Models of ``MODELS``.
    zonals : int
        Highest zonal harmonic of the truth.
    effective : bool
        Add the ``j2drag_eff`` row.

    Returns
    -------
    list of ModelError
        One per model, errors in m.
    """
    t_end = max(days) * SECONDS_PER_DAY
    times = np.arange(0.0, t_end + step / 2, step)
    states = truth_states(case, times, zonals)
    truth = mean_roe(states)
    r_true = relative_rtn(states)[0]
    idx = np.searchsorted(times, np.asarray(days, dtype=float) * SECONDS_PER_DAY)
    out = []
    runs = [(m, m, None) for m in models]
    if effective:
        runs.append(("j2drag_eff", "j2drag", truth_effective_density(case, times[-1])))
    for name, model, rho in runs:
        roe_m = model_trajectory(case, times, model, rho)
        u = case.chief.u_at(times, model != "keplerian")
        r_model = roe_to_rtn(roe_m, u)[0] * case.a
        dr = np.linalg.norm(r_model - r_true, axis=-1)
        dd = np.abs(np.linalg.norm(r_model, axis=-1) - np.linalg.norm(r_true, axis=-1))
        out.append(ModelError(case.name, name, list(days), (roe_m[idx] - truth[idx]) * case.a,
                              np.array([dr[:k + 1].max() for k in idx]), np.array([dd[:k + 1].max() for k in idx]),
                              truth[idx] * case.a))
    return out


def truth_effective_density(case: Case, span: float) -> float:
    """Orbit-mean drag of the case's truth atmosphere over [0, ``span``] s as a constant density [kg/m^3]."""
    return effective_density(case.atmosphere, case.chief_mean, 0.0, span, samples=max(720, int(span / 60.0)))


def zonal_effect(case: Case, days: Sequence[float] = (1, 2, 3)) -> np.ndarray:
    """a*(ROE with J2-J4 truth - ROE with J2-only truth) [m] at ``days``: what the Monte Carlo's J2-only truth
    (``MC_ZONALS``) leaves out; ``(len(days), 6)``."""
    t = np.asarray(days, dtype=float) * SECONDS_PER_DAY
    return (mean_roe(truth_states(case, t, 4)) - mean_roe(truth_states(case, t, 2))) * case.a


# ---------------------------------------------------------------- nonlinear Monte Carlo
@dataclass
class NonlinearSweep:
    """Nonlinear Monte Carlo of the double impulse next to the linear sweep on the same draws."""

    rows: list  # summarize() rows, nonlinear
    linear_rows: list  # summarize() rows of the linear model (same draws, mc.j2 as configured)
    agreement: list  # per p: fraction of samples with the same approach / evaporation verdict
    samples: int
    seconds: float  # wall time of the sweep (nonlinear propagation and the linear sweep)
    roe_diff_after_stop: dict = field(default_factory=dict)  # p -> per-ROE RMS a*(linear - nonlinear) [m]

    def to_dict(self) -> dict:
        """The sweep as JSON (rows as :func:`~roe_sep.core.montecarlo.sweep.summarize`, RMS in m)."""
        return {"samples": self.samples, "seconds": self.seconds, "rows": self.rows, "linear_rows": self.linear_rows,
                "agreement": self.agreement,
                "roe_rms_linear_minus_nonlinear_after_stop": {str(p): v for p, v in self.roe_diff_after_stop.items()}}


def nonlinear_sweep(d: DoubleImpulseDesign, mc: MonteCarloConfig, p_values: Iterable[float], zonals: int = MC_ZONALS,
                    tol: float = MC_TOL, *, workers: int | None = None) -> NonlinearSweep:
    """The Monte Carlo p sweep with nonlinear propagation, every array over the sample axis (no per-sample loop).

    Per sample: the dispersed ejection (Eq. 22, f1, eps1) applied to the picosatellite at u1; both spacecraft
    integrated to the drift-stop epoch k pi later (secular J2 rate of u: the truth always has J2); the carrier's
    dispersed drift-stop (f2 on the unreduced burn as Eq. 18, eps2, its own burn -dv2(p)); then ``mc.horizon``.
    Differential drag: the carrier keeps its nominal B, the picosatellite gets B_c + dB_nominal * db_factor (the
    linear model's dB), the atmosphere is :meth:`Atmosphere.normalised` to ``mc.density`` (the default truth).
    Without ``mc.drag`` both B are 0.

    Parameters
    ----------
    d : DoubleImpulseDesign
        The nominal design.
    mc : MonteCarloConfig
        Samples, seed, dispersions, drag, horizon.
    p_values : iterable of float
        The reductions [m/s].
    zonals : int
        Highest zonal harmonic of the truth.
    tol : float
        Taylor integrator tolerance.
    workers : int, optional
        Threads of the batch integration (None: every CPU this process may use).

    Returns
    -------
    NonlinearSweep
        Nonlinear and linear rows on the same draws and their agreement.
    """
    import time

    mc.validate()
    draws = draw(d, mc)
    a = d.a
    n = mc.samples
    chief = np.array([a, 0.0, d.inc, 0.0, 0.0, d.u1])
    atm = Atmosphere.normalised(mc.density, chief)
    b_c = mc.carrier.ballistic if mc.drag else 0.0
    b_d = b_c + mc.delta_b * draws.db_factor if mc.drag else np.zeros(n)
    s0 = np.broadcast_to(pair_state(chief, chief), (n, 12))
    s1 = apply_impulse(s0, dispersed_dv(d.dv1_rtn, draws.f1, draws.eps1), np.ones(n, bool))
    dt_stop = d.k * math.pi / float(arg_latitude_rate(a, d.inc, True))
    t0 = time.perf_counter()
    s_stop = propagate_pairs(s1, 0.0, dt_stop, b_c, b_d, atmosphere=atm, zonals=zonals, tol=tol, workers=workers)
    lin = sweep(d, mc, p_values)
    rows, agreement, diffs = [], [], {}
    for lrow in lin.rows:
        pv = lrow["p"]
        dv2_own = dispersed_dv(0.0 - d.drift_stop_dv(pv), draws.f2, draws.eps2, 0.0 - d.drift_stop_dv(0.0))
        s2 = apply_impulse(s_stop, dv2_own, np.zeros(n, bool))
        roe2 = mean_roe(s2)
        s_h = propagate_pairs(s2, dt_stop, dt_stop + mc.horizon, b_c, b_d, atmosphere=atm, zonals=zonals, tol=tol,
                              workers=workers)
        out = Outcome(roe2, mean_roe(s_h), min_rn_distance(roe2) * a)
        rows.append(summarize(d, mc, pv, out))
        lo = lin.outcomes[pv]
        same_app = np.mean((lo.roe_after_stop[:, 0] * lo.roe_after_stop[:, 1] > 0)
                           == (out.roe_after_stop[:, 0] * out.roe_after_stop[:, 1] > 0))
        same_evap = np.mean((np.abs(lo.roe_horizon[:, 1] * a) > mc.evaporation_distance)
                            == (np.abs(out.roe_horizon[:, 1] * a) > mc.evaporation_distance))
        agreement.append({"p": pv, "approach": float(same_app), "evaporation": float(same_evap)})
        diffs[pv] = (np.sqrt(np.mean((lo.roe_after_stop - roe2) ** 2, axis=0)) * a).tolist()
    return NonlinearSweep(rows, lin.rows, agreement, n, time.perf_counter() - t0, diffs)
