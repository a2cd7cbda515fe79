"""Vectorized Monte Carlo of the double-impulse separation and the p sweep (seed 002, 'Monte Carlo simulation').

Dispersions, each drawn once per sample and shared by every p of a sweep (common random numbers, so differences
between p values are not sampling noise):

* f1 ~ N(1, spl_sigma): SPL magnitude factor on the ejection; f2 ~ N(1, thruster_sigma) on the drift-stop, as an
  error on the *unreduced* burn with the reduction |p| subtracted after it (seed 002 Eq. 18, see
  :func:`~roe_sep.core.relmotion.maneuvers.dispersed_dv`): dv_T2* = f2 dv_T2 - |p|.
* attitude errors eps_x, eps_y, eps_z ~ N(0, 30 arcsec) per axis on both impulses, applied with Eq. (22).
* differential ballistic coefficient dB = dB_nominal * N(1, ballistic_sigma), the drag of Eqs. (23)-(24).

No Python loop runs over samples: every quantity is an array over the sample axis.
"""

import functools
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import numpy as np

from ...errors import show
from ..constants import ARCSEC, SECONDS_PER_DAY
from ..relmotion.dynamics import arg_latitude_rate, ballistic_coefficient, drag_da_dot, propagate
from ..relmotion.maneuvers import delta_roe, dispersed_dv
from ..safety.metrics import approaching, fov_limit, min_rn_distance, nearest_crossing
from ..separation.double_impulse import DoubleImpulseDesign, SeparationConfig
from ..separation.double_impulse import design as make_design

DEFAULT_P_VALUES = (0.0, 0.01, 0.02, 0.03, 0.04, 0.05, 0.055, 0.06, 0.07, 0.08)


@dataclass(frozen=True)
class Spacecraft:
    """Drag properties of one spacecraft."""

    cd: float  # drag coefficient
    area: float  # m^2, cross-section at nominal attitude
    mass: float  # kg

    @property
    def ballistic(self) -> float:
        """B = c_d A / m [m^2/kg]."""
        return ballistic_coefficient(self.cd, self.area, self.mass)


@dataclass(frozen=True)
class MonteCarloConfig:
    """Monte Carlo settings; magnitude sigmas come from the design's :class:`SeparationConfig`."""

    samples: int = 100_000
    seed: int | None = 0
    attitude_sigma_arcsec: float = 30.0
    ballistic_sigma: float = 0.20  # relative 1-sigma of dB
    carrier: Spacecraft = field(default_factory=lambda: Spacecraft(cd=2.3, area=0.48, mass=140.0))  # 0.8 m x 0.6 m
    picosat: Spacecraft = field(default_factory=lambda: Spacecraft(cd=2.3, area=0.01, mass=1.0))  # 0.1 m x 0.1 m
    density: float = 1e-12  # kg/m^3 (1 g/km^3, seed 002)
    drag: bool = True
    j2: bool = False  # the seeds' Monte Carlo uses Keplerian + differential drag
    horizon: float = SECONDS_PER_DAY  # s, after the drift-stop (the third maneuver's epoch)
    evaporation_distance: float = 50e3  # m

    @property
    def delta_b(self) -> float:
        """Nominal differential ballistic coefficient B_picosat - B_carrier [m^2/kg] (0.0151 in seed 002)."""
        return self.picosat.ballistic - self.carrier.ballistic

    def validate(self) -> None:
        """Raise ValueError naming the first bad setting."""
        if isinstance(self.samples, bool) or not isinstance(self.samples, (int, np.integer)) or self.samples < 1:
            raise ValueError(f"samples must be a positive integer, got {show(self.samples)}")
        for name in ("attitude_sigma_arcsec", "ballistic_sigma", "density", "horizon", "evaporation_distance"):
            v = getattr(self, name)
            if not np.isfinite(v) or v < 0:
                raise ValueError(f"{name} must be finite and non-negative, got {v}")
        for who in ("carrier", "picosat"):
            sc = getattr(self, who)
            if not all(np.isfinite(x) and x > 0 for x in (sc.cd, sc.area, sc.mass)):
                raise ValueError(f"{who}: cd, area and mass must be finite and positive, got {show(sc)}")


@dataclass(frozen=True)
class Draws:
    """One set of dispersion samples (arrays over samples)."""

    f1: np.ndarray
    f2: np.ndarray
    eps1: np.ndarray  # (N, 3) rad
    eps2: np.ndarray  # (N, 3) rad
    db_factor: np.ndarray


def draw(design: DoubleImpulseDesign, mc: MonteCarloConfig) -> Draws:
    """Sample the dispersions of seed 002 (Eq. 22 and the 20 % dB uncertainty) with ``mc.seed``."""
    rng = np.random.default_rng(mc.seed)
    n, cfg = mc.samples, design.config
    sig_att = mc.attitude_sigma_arcsec * ARCSEC
    return Draws(
        f1=rng.normal(1.0, cfg.spl_sigma, n),
        f2=rng.normal(1.0, cfg.thruster_sigma, n),
        eps1=rng.normal(0.0, sig_att, (n, 3)),
        eps2=rng.normal(0.0, sig_att, (n, 3)),
        db_factor=rng.normal(1.0, mc.ballistic_sigma, n),
    )


@dataclass(frozen=True)
class PreStop:
    """Per-sample state from the ejection to just before the drift-stop (independent of p)."""

    roe_before_stop: np.ndarray  # (N, 6) dimensionless
    da_dot: np.ndarray  # (N,) 1/s
    crossing: np.ndarray  # (N,) m, |T| at the nearest R = 0 transit before the drift-stop
    dt_stop: float  # s, ejection to drift-stop


@dataclass(frozen=True)
class Outcome:
    """Per-sample results for one p [m]."""

    roe_after_stop: np.ndarray  # (N, 6) dimensionless
    roe_horizon: np.ndarray  # (N, 6) dimensionless, ``horizon`` after the drift-stop
    min_rn: np.ndarray  # m, Eq. (25) after the drift-stop


def ejection_roe(design: DoubleImpulseDesign, d: Draws) -> np.ndarray:
    """Dimensionless ROE ``(N, 6)`` right after the dispersed ejection (Eq. 2 of the burn of Eq. 22, f1 and eps1)."""
    return delta_roe(dispersed_dv(design.dv1_rtn, d.f1, d.eps1), design.u1, design.a, design.n)


def drift_stop_delta_roe(design: DoubleImpulseDesign, d: Draws, p: float) -> np.ndarray:
    """ROE change of the drift-stop commanded with reduction ``p`` and executed as Eq. (18): the thruster error f2
    on the unreduced burn, |p| subtracted after it, attitude errors of Eq. (22).

    Parameters
    ----------
    design : DoubleImpulseDesign
        The nominal design (the commanded ejection, u2, a, n).
    d : Draws
        The dispersions of N samples (f2, eps2 used).
    p : float
        The reduction [m/s].

    Returns
    -------
    numpy.ndarray, shape (N, 6)
        The dimensionless ROE change of each sample.
    """
    dv2 = dispersed_dv(design.drift_stop_dv(p), d.f2, d.eps2, design.drift_stop_dv(0.0))
    return delta_roe(dv2, design.u2, design.a, design.n)


def drift_stop_delta_roe_fast(design: DoubleImpulseDesign, d: Draws, p: float) -> tuple[np.ndarray, ...]:
    """:func:`drift_stop_delta_roe` to the bit (``test_montecarlo``), written out element by element on the
    sample axis: the same products and sums as :func:`~..relmotion.maneuvers.dispersed_dv` with a reference
    burn and :func:`~..relmotion.maneuvers.delta_roe` at the scalar u2 (every row of G(u) has at most two non-zero
    entries, so its contraction is one rounded sum in any order), without the (N, 3) and (N, 6, 3) temporaries;
    the hot loop of the p sweep.

    Parameters
    ----------
    design, d, p
        As for :func:`drift_stop_delta_roe`.

    Returns
    -------
    tuple of six numpy.ndarray, each shape (N,)
        The dimensionless changes of da, dl, dex, dey, dix, diy.
    """
    dv, ref = design.drift_stop_dv(p), design.drift_stop_dv(0.0)
    g = d.f2 - 1.0
    r, t, nn = dv[0] + g * ref[0], dv[1] + g * ref[1], dv[2] + g * ref[2]
    ex, ey, ez = d.eps2[:, 0], d.eps2[:, 1], d.eps2[:, 2]
    r, t, nn = r + ez * t - ey * nn, -ez * r + t + ex * nn, ey * r - ex * t + nn
    u = np.asarray(design.u2, dtype=float)
    s, c = np.sin(u), np.cos(u)
    na = design.n * design.a
    return ((2.0 * t) / na, (-2.0 * r) / na, (s * r + (2.0 * c) * t) / na, ((-c) * r + (2.0 * s) * t) / na,
            (c * nn) / na, (s * nn) / na)


def time_to_stop(design: DoubleImpulseDesign, mc: MonteCarloConfig) -> float:
    """s from the ejection to the drift-stop, k pi of argument of latitude (with J2 when ``mc.j2``)."""
    return (design.u2 - design.u1) / arg_latitude_rate(design.a, design.inc, mc.j2)


def pre_stop(design: DoubleImpulseDesign, mc: MonteCarloConfig, d: Draws) -> PreStop:
    """Ejection with its dispersion, propagation to the drift-stop and the nearest R = 0 transit in between.

    Parameters
    ----------
    design : DoubleImpulseDesign
        The nominal design.
    mc : MonteCarloConfig
        Drag, density, J2.
    d : Draws
        The dispersions of N samples.

    Returns
    -------
    PreStop
        Per-sample ROE ``(N, 6)`` before the drift-stop, da_dot ``(N,)`` [1/s] and nearest transit ``(N,)`` [m].
    """
    a, inc = design.a, design.inc
    roe1 = ejection_roe(design, d)
    da_dot = drag_da_dot(mc.delta_b * d.db_factor, mc.density, a) if mc.drag else np.zeros_like(d.f1)
    dt_stop = time_to_stop(design, mc)
    crossing, _ = nearest_crossing(roe1, design.u1, dt_stop, a, inc, j2=mc.j2, da_dot=da_dot)
    return PreStop(propagate(roe1, dt_stop, a, inc, mc.j2, da_dot=da_dot), da_dot, crossing * a, dt_stop)


def after_stop(design: DoubleImpulseDesign, mc: MonteCarloConfig, d: Draws, pre: PreStop, p: float) -> Outcome:
    """Drift-stop commanded with reduction ``p`` (:func:`drift_stop_delta_roe`, Eq. 18), then ``horizon`` of
    drift.

    Parameters
    ----------
    design, mc, d
        As for :func:`pre_stop`.
    pre : PreStop
        :func:`pre_stop` of the same draws.
    p : float
        The reduction [m/s].

    Returns
    -------
    Outcome
        Per-sample ROE after the drift-stop and at the horizon ``(N, 6)``, Eq. (25) distance ``(N,)`` [m].
    """
    roe2 = np.empty_like(pre.roe_before_stop)  # pre.roe_before_stop + drift_stop_delta_roe(design, d, p)
    for k, change in enumerate(drift_stop_delta_roe_fast(design, d, p)):
        np.add(pre.roe_before_stop[:, k], change, out=roe2[:, k])
    roe_h = propagate(roe2, mc.horizon, design.a, design.inc, mc.j2, da_dot=pre.da_dot)
    return Outcome(roe2, roe_h, min_rn_distance(roe2) * design.a)


def summarize(design: DoubleImpulseDesign, mc: MonteCarloConfig, p: float, out: Outcome) -> dict:
    """Fractions of samples per event for one p (seed 002 Table 3 and the Figs. 4-9 criteria).

    Visibility is reported twice: ``p_fov_violation`` applies Eq. (11) at each sample's own a dl after the
    drift-stop (the camera check proper); ``p_table2_violation`` uses the fixed Table 2 sizes (Eq. 11 at the
    smallest admissible a dl = 5 km, the design's worst case).

    Parameters
    ----------
    design : DoubleImpulseDesign
        The nominal design (its configuration's limits and the Table 2 bounds).
    mc : MonteCarloConfig
        The evaporation distance.
    p : float
        The reduction [m/s] of ``out``.
    out : Outcome
        :func:`after_stop` for ``p``.

    Returns
    -------
    dict
        ``p`` [m/s], fractions ``p_*`` and counts ``n_*`` of samples per event, means ``a_*_mean`` [m] and
        ``min_rn_min`` [m].
    """
    a, cfg = design.a, design.config
    b = design.bounds
    dl_after = out.roe_after_stop[:, 1] * a
    dl_h = out.roe_horizon[:, 1] * a
    side = 1.0 if cfg.leading else -1.0
    a_de = np.hypot(out.roe_after_stop[:, 2], out.roe_after_stop[:, 3]) * a
    a_di = np.hypot(out.roe_after_stop[:, 4], out.roe_after_stop[:, 5]) * a
    approach = approaching(out.roe_after_stop)
    evaporation = np.abs(dl_h) > mc.evaporation_distance
    return {
        "p": float(p),
        "p_approach": float(np.mean(approach)),
        "p_evaporation": float(np.mean(evaporation)),
        "n_approach": int(np.count_nonzero(approach)),
        "n_evaporation": int(np.count_nonzero(evaporation)),
        "p_below_radar_horizon": float(np.mean(side * dl_h < cfg.a_dl_min)),
        "p_overtaken_horizon": float(np.mean(side * dl_h < 0.0)),
        "p_min_rn_violation": float(np.mean(out.min_rn < cfg.min_rn_distance)),
        "p_ei_magnitude_violation": float(np.mean((a_de < cfg.min_rn_distance) | (a_di < cfg.min_rn_distance))),
        "p_fov_violation": float(np.mean((a_de > fov_limit(dl_after, np.radians(cfg.fov_half_r_deg)))
                                         | (a_di > fov_limit(dl_after, np.radians(cfg.fov_half_n_deg))))),
        "p_table2_violation": float(np.mean((a_de > b.a_de_max) | (a_di > b.a_di_max))),
        "a_da_mean": float(np.mean(out.roe_after_stop[:, 0] * a)),
        "a_dl_mean": float(np.mean(dl_after)),
        "a_dl_horizon_mean": float(np.mean(dl_h)),
        "min_rn_min": float(np.min(out.min_rn)),
    }


@dataclass
class SweepResult:
    """A p sweep: one summary row per p, per-sample outcomes kept for the figures."""

    design: DoubleImpulseDesign
    mc: MonteCarloConfig
    draws: Draws
    pre: PreStop
    rows: list
    outcomes: dict  # p -> Outcome
    p_best: float

    def to_dict(self) -> dict:
        """The rows and the settings as ``roe-sep mc --json`` prints them (SI)."""
        return {
            "samples": self.mc.samples,
            "seed": self.mc.seed,
            "drag": self.mc.drag,
            "j2": self.mc.j2,
            "delta_b": self.mc.delta_b,
            "rows": self.rows,
            "p_best": self.p_best,
            "crossing_min": float(np.min(self.pre.crossing)),
            "crossing_min_within_3sigma_f1": float(np.min(self.pre.crossing[self.draws.f1 >= 0.7], initial=np.inf)),
        }


def sweep(design: DoubleImpulseDesign, mc: MonteCarloConfig, p_values: Iterable[float] = DEFAULT_P_VALUES,
          progress: Callable = iter) -> SweepResult:
    """Run the Monte Carlo for every p in ``p_values`` on one shared set of draws.

    ``p_best`` minimises P(approaching drift) + P(evaporation) (seed 002 Table 3); ties go to the smaller p.

    Parameters
    ----------
    design : DoubleImpulseDesign
        The nominal design.
    mc : MonteCarloConfig
        Samples, seed, dispersions, drag.
    p_values : iterable of float
        The reductions [m/s], finite and non-negative.
    progress : callable
        Wraps the iteration over p (e.g. ``tqdm``).

    Returns
    -------
    SweepResult
        One summary row per p, the per-sample outcomes and ``p_best``.
    """
    mc.validate()
    ps = [float(p) for p in p_values]
    if not ps or not all(np.isfinite(p) and p >= 0 for p in ps):
        raise ValueError(f"p values must be a non-empty list of finite non-negative numbers [m/s], "
                         f"got {show(p_values)}")
    d = draw(design, mc)
    pre = pre_stop(design, mc, d)
    rows, outcomes = [], {}
    for p in progress(ps):
        out = after_stop(design, mc, d, pre, p)
        outcomes[p] = out
        rows.append(summarize(design, mc, p, out))
    risk = [(r["p_approach"] + r["p_evaporation"], r["p"]) for r in rows]
    p_best = min(risk)[1]
    return SweepResult(design, mc, d, pre, rows, outcomes, p_best)


@functools.lru_cache(maxsize=8)
def p_best(separation: SeparationConfig, mc: MonteCarloConfig, p_values: tuple[float, ...]) -> float:
    """``p_best`` [m/s] of :func:`sweep` for the design of ``separation`` (seed 002 Table 3), memoised: a pure
    function of frozen, hashable inputs, so the planner's start-up sweep is computed once per process (and once per
    campaign worker, whose runs are forked from a process that computed it: :mod:`roe_sep.campaign.forkserver`).

    Parameters
    ----------
    separation : SeparationConfig
        The separation whose double-impulse design is swept.
    mc, p_values
        As for :func:`sweep` (``p_values`` a tuple, hashable).

    Returns
    -------
    float
        The reduction |p| [m/s] of least risk.
    """
    return float(sweep(make_design(separation), mc, tuple(float(p) for p in p_values)).p_best)

