"""Multi-impulse separation: SPL ejection at the orbit pole, then purely tangential carrier burns (seed 001 Sec. 3).

Seed 001 replaces the double impulse of seeds 000/002 (one large drift-stop with a radial component): the carrier
thrusters give at most ~0.3 m/s per burn, quantized to 1 mm/s (seed 001 Sec. 2.1), the SPL a fixed 1.53 m/s:

1. **Ejection** at u1 = 90 deg (orbit north pole, seed 001 Sec. 2.2 item 3), components as in seed 001 Sec. 3:

   * tangential: the least value keeping the drift outward under SPL under-performance (seed 002 Eq. 10):
     |dvT1| = e~ = spl_sigma |dv|, sign from safety #2;
   * normal: the relative inclination vector of the initial conditions, n a di_F = dvN1 (Eq. 2), with di_F the
     largest size still in the camera field of view at the smallest admissible separation (Table 2 a_di_max,
     visibility #3, Eq. 11): the larger dvN1, the smaller the radial part the carrier has to undo; the margin of
     safety #7 (e~/n) below it must stay above a_di_min;
   * radial: the rest of the fixed SPL size, Eq. (12).

2. **Blind drift reduction** (a carrier burn, purely tangential): dvT2 = -dvT1 reduced by |p| = e1 + e2 at
   ``p_sigma_level`` sigma (seed 002 Eqs. 18, 21, lower bound), so the residual drift stays outward (AC1). It is
   placed, at least half a revolution after the ejection, at the argument of latitude where its change of the
   relative eccentricity vector, 2 dvT (cos u, sin u) / (n a) (Eq. 2), points along the change still needed to make
   de anti-parallel to di: the drift-stop then also pays part of the e-vector correction.

3. **Tangential pair** after the radar orbit determination (``pair_delay`` after the ejection, seed 001 Sec. 5: OD
   and acquisition within 24 h): two tangential burns half a revolution apart, the first setting a more negative
   da (outward), the second cancelling the drift. They take the predicted de (secular J2 + nominal drag) along the
   shortest path to the ray anti-parallel to di with |de| >= the minimum R-N distance (seed 001 Sec. 3 'minimum
   delta-v fashion'; tangential burns: sum |dvT| >= n a/2 max(|Delta da|, |Delta de|)).

Every burn is quantized to ``dv_quantum``, split into burns of at most ``max_burn`` on consecutive revolutions, and
*relative* (picosatellite w.r.t. carrier; the carrier burns the opposite).
"""

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike

from ...errors import show
from ..constants import SECONDS_PER_DAY
from ..montecarlo.sweep import MonteCarloConfig
from ..relmotion.dynamics import (
    arg_latitude_rate,
    drag_da_dot,
    eccentricity_vector_rotation_rate,
    j2_kappa,
    propagate,
    sun_synchronous_inclination,
)
from ..relmotion.maneuvers import delta_roe
from ..relmotion.orbit import mean_motion, semi_major_axis
from ..relmotion.roe import e_vector_polar, i_vector_polar, wrap_angle
from ..relmotion.trajectory import Burn, Chief, trajectory
from ..safety.metrics import min_rn_distance
from .double_impulse import (
    InfeasibleDesignError,
    SeparationConfig,
    admissible_bounds,
    drift_stop_dv,
    reduction_bounds,
    validate_config,
)


@dataclass(frozen=True)
class MultiImpulseConfig:
    """Inputs of the multi-impulse design that differ from the double impulse (seed 001 Secs. 2-3)."""

    spl_dv: float = 1.53  # m/s, SPL ejection magnitude (seed 001: BEESAT-4 8 % lighter than assumed before)
    u1_deg: float = 90.0  # deg, ejection at the orbit pole (seed 001 Sec. 2.2 item 3)
    a_di_f: float | None = None  # m, aimed |a di|; None: Table 2 a_di_max (largest in the camera FOV at 5 km)
    max_burn: float = 0.3  # m/s, largest single carrier burn (seed 001 Sec. 2.1 constraint 2)
    dv_quantum: float = 1e-3  # m/s, thruster discretization (seed 001 Sec. 2.1 constraint 2)
    min_stop_delay_rev: float = 0.5  # revolutions from the ejection to the earliest drift reduction
    pair_delay: float = SECONDS_PER_DAY  # s, ejection to the earliest burn of the tangential pair (after OD)

    def validate(self) -> None:
        """Raise ValueError naming the first field that is not finite and positive (``a_di_f``: or None)."""
        for name in ("spl_dv", "max_burn", "dv_quantum", "min_stop_delay_rev", "pair_delay"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
                raise ValueError(f"{name} must be a finite positive number, got {show(v)}")
        if not math.isfinite(self.u1_deg):
            raise ValueError(f"u1_deg must be finite, got {show(self.u1_deg)}")
        if self.a_di_f is not None and (not math.isfinite(self.a_di_f) or self.a_di_f <= 0):
            raise ValueError(f"a_di_f must be a finite positive number [m] or null, got {show(self.a_di_f)}")
        if self.dv_quantum > self.max_burn:
            raise ValueError(f"dv_quantum ({self.dv_quantum} m/s) must not exceed max_burn ({self.max_burn} m/s)")


# ---------------------------------------------------------------------------------------------------------------
# one function per formula


def spl_error(spl_dv: float, spl_sigma: float) -> float:
    """e~ = spl_sigma |dv| [m/s]: the SPL execution error of seed 002 Eq. (10) (10 % of the SPL size)."""
    return spl_sigma * spl_dv


def spl_tangential(e_tilde: float, leading: bool = True) -> float:
    """Least tangential SPL component with an outward drift under the error e~, seed 002 Eq. (10): |dvT1| = e~.

    Leading picosatellite: dvT1 < 0 (da < 0, drift towards positive along-track separation, safety #2). ``e_tilde``
    and the result in m/s.
    """
    return -e_tilde if leading else e_tilde


def spl_normal(a_di: float, n: float) -> float:
    """Normal SPL component establishing |a di| = ``a_di`` [m] at the ejection, seed 002 Eq. (2): n a |di| = |dvN|
    [m/s], ``n`` [rad/s]."""
    return n * a_di


def spl_radial(spl_dv: float, dv_t: float, dv_n: float, leading: bool = True) -> float:
    """The radial SPL component absorbing the rest of the fixed SPL size, seed 002 Eq. (12) (sign: safety #2).

    Parameters
    ----------
    spl_dv : float
        The SPL ejection magnitude [m/s].
    dv_t, dv_n : float
        Its tangential and normal components [m/s].
    leading : bool
        A leading picosatellite (negative radial component).

    Returns
    -------
    float
        The radial component [m/s].

    Raises
    ------
    InfeasibleDesignError
        When the tangential and normal components alone exceed ``spl_dv``.
    """
    rest = spl_dv**2 - dv_t**2 - dv_n**2
    if rest < 0:
        raise InfeasibleDesignError(
            f"SPL |dv| = {spl_dv:g} m/s is too small (Eq. 12): tangential and normal components alone need "
            f"{math.hypot(dv_t, dv_n):.4f} m/s")
    return (-1.0 if leading else 1.0) * math.sqrt(rest)


def inclination_vector_drift_rate(a: ArrayLike, inc: ArrayLike, dix: ArrayLike) -> np.ndarray:
    """Secular J2 drift of the relative inclination vector's y component, d(diy)/dt = 2 kappa sin^2(i) dix [1/s].

    The da-free part of the diy rate of :func:`~roe_sep.core.relmotion.dynamics.propagate` (seed 001 Sec. 2.2 item 3:
    'the J2 effect on the relative inclination vector affects only its y-component', driven by dix). Per orbit it
    is 3 pi J2 (R_E/a)^2 sin^2(i) dix. Belongs in ``dynamics.py`` (kept here: that module is not ours).

    Parameters
    ----------
    a : array_like
        The chief's semi-major axis [m].
    inc : array_like
        The chief's inclination [rad].
    dix : array_like
        The dimensionless relative inclination vector's x component.

    Returns
    -------
    numpy.ndarray
        d(diy)/dt [1/s], the broadcast shape.
    """
    return 2.0 * j2_kappa(a) * np.sin(inc) ** 2 * np.asarray(dix, dtype=float)


def ejection_dix(dv_n: ArrayLike, u: ArrayLike, a: ArrayLike, n: ArrayLike) -> np.ndarray | float:
    """dix = dvN cos(u) / (n a), seed 002 Eq. (2): zero for an ejection at the poles u = 90/270 deg.

    Parameters
    ----------
    dv_n : array_like
        The normal ejection component [m/s].
    u : array_like
        The mean argument of latitude of the ejection [rad].
    a : array_like
        The carrier's semi-major axis [m].
    n : array_like
        The carrier's mean motion [rad/s].

    Returns
    -------
    float or numpy.ndarray
        The dimensionless dix, the broadcast shape.
    """
    return dv_n * np.cos(u) / (n * a)


def anti_parallel_target(de: ArrayLike, di: ArrayLike, de_min: ArrayLike, parallel: bool = False) -> np.ndarray:
    """Closest point to ``de`` on the ray anti-parallel to ``di`` with |de| >= de_min (dimensionless 2-vectors).

    The target of the minimum-delta-v e-vector correction (seed 001 Sec. 3: 'shortest change towards the final
    configuration'): the projection of de onto -di_hat, clamped to at least de_min. ``parallel``: the ray along
    +di_hat instead (a following picosatellite, eta = 0, seed 002 safety #2).

    Parameters
    ----------
    de, di : array_like, shape (..., 2)
        The dimensionless relative eccentricity and inclination vectors.
    de_min : array_like, shape (...)
        The least |de| of the target (dimensionless).
    parallel : bool
        The ray along +di_hat instead of -di_hat.

    Returns
    -------
    numpy.ndarray, shape (..., 2)
        The target relative eccentricity vector (dimensionless).
    """
    de = np.asarray(de, dtype=float)
    di = np.asarray(di, dtype=float)
    d_hat = (1.0 if parallel else -1.0) * di / np.linalg.norm(di, axis=-1, keepdims=True)
    s = np.maximum(np.sum(de * d_hat, axis=-1), de_min)
    return s[..., None] * d_hat


def tangential_pair(da: float, dde: ArrayLike, n: float, a: float) -> tuple[float, float, float]:
    """Two tangential impulses x1 at u_a, x2 at u_a + pi giving Delta da = -da and Delta de = dde (Eq. 2).

    Eq. (2): Delta da = 2 (x1 + x2)/(n a), Delta de = 2 (x1 - x2)(cos u_a, sin u_a)/(n a). With u_a = phase(dde)
    + pi (first burn lowers da: outward for a leading picosatellite): x1 - x2 = -D, x1 + x2 = S with
    D = n a |dde| / 2, S = -n a da / 2. Minimum delta-v when |dde| >= |da| (then |x1| + |x2| = D).

    Parameters
    ----------
    da : float
        The dimensionless relative semi-major axis to cancel.
    dde : array_like, shape (2,)
        The wanted change of the dimensionless relative eccentricity vector.
    n : float
        The carrier's mean motion [rad/s].
    a : float
        The carrier's semi-major axis [m].

    Returns
    -------
    u_a : float
        Mean argument of latitude of the first burn [rad], wrapped to [-pi, pi).
    x1, x2 : float
        The tangential relative impulses at u_a and u_a + pi [m/s].
    """
    dde = np.asarray(dde, dtype=float)
    big_d = n * a * float(np.hypot(dde[0], dde[1])) / 2.0
    big_s = -n * a * float(da) / 2.0
    u_a = float(wrap_angle(math.atan2(dde[1], dde[0]) + math.pi))
    return u_a, (big_s - big_d) / 2.0, (big_s + big_d) / 2.0


def tangential_pair_following(da: float, dde: ArrayLike, n: float, a: float) -> tuple[float, float, float]:
    """:func:`tangential_pair` for a following picosatellite: the first burn raises da (outward behind the carrier):
    u_a = phase(dde), x1 = (S + D)/2 > 0, x2 = (S - D)/2.

    Parameters
    ----------
    da, dde, n, a
        As for :func:`tangential_pair`.

    Returns
    -------
    u_a : float
        Mean argument of latitude of the first burn [rad], wrapped to [-pi, pi).
    x1, x2 : float
        The tangential relative impulses at u_a and u_a + pi [m/s].
    """
    dde = np.asarray(dde, dtype=float)
    big_d = n * a * float(np.hypot(dde[0], dde[1])) / 2.0
    big_s = -n * a * float(da) / 2.0
    return float(wrap_angle(math.atan2(dde[1], dde[0]))), (big_s + big_d) / 2.0, (big_s - big_d) / 2.0


def quantize(dv: ArrayLike, quantum: float) -> np.ndarray:
    """Round an impulse [m/s] (any shape) to the thruster discretization ``quantum`` [m/s] (seed 001 Sec. 2.1
    constraint 2)."""
    return np.round(np.asarray(dv, dtype=float) / quantum) * quantum


def split_burn(dv: float, max_burn: float, quantum: float) -> list[float]:
    """Split a (quantized) scalar impulse into the fewest near-equal parts, each <= ``max_burn`` and an integer
    multiple of ``quantum`` (seed 001 Sec. 2.1: 0.3 m/s per burn, 1 mm/s pulses).

    Parameters
    ----------
    dv : float
        The impulse [m/s], signed.
    max_burn : float
        The largest part [m/s].
    quantum : float
        The thruster discretization [m/s].

    Returns
    -------
    list of float
        The parts [m/s], each with the sign of ``dv`` (empty for an impulse below half a quantum).
    """
    q = int(round(abs(float(dv)) / quantum))
    per = int(math.floor(max_burn / quantum + 1e-9))
    if q == 0:
        return []
    m = -(-q // per)
    sign = 1.0 if dv > 0 else -1.0
    return [sign * (q // m + (1 if i < q % m else 0)) * quantum for i in range(m)]


def first_u_after(target: float, u_from: float) -> float:
    """Smallest unwrapped argument of latitude >= ``u_from`` congruent to ``target`` mod 2 pi [rad]."""
    return u_from + (target - u_from) % (2.0 * math.pi)


# ---------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class CarrierBurn:
    """One planned carrier burn (purely tangential)."""

    purpose: str  # 'drift_reduction' | 'e_vector_pair'
    u: float  # rad, unwrapped mean argument of latitude (u1 + ...)
    epoch: float  # s
    dv_carrier_rtn: np.ndarray  # m/s, what the carrier burns
    dv_relative_rtn: np.ndarray  # m/s, relative effect (= -dv_carrier_rtn)


@dataclass(frozen=True)
class CarrierPlan:
    """The carrier's burns for one commanded ejection and the predicted relative orbit."""

    burns: tuple  # CarrierBurn, time ordered
    p: float  # m/s, drift reduction commanded (after quantization)
    roe_after_reduction: np.ndarray  # dimensionless, just after the (last) drift-reduction burn
    roe_final: np.ndarray  # dimensionless, just after the last burn (the IC epoch)
    ic_epoch: float  # s


def plan_carrier_burns(dv1_rtn: ArrayLike, u1: float, epoch1: float, a: float, inc: float, *, sep: SeparationConfig,
                       mcfg: MultiImpulseConfig, j2: bool = True, da_dot: float = 0.0) -> CarrierPlan:
    """Blind drift reduction and the tangential e-vector pair for a commanded ejection ``dv1_rtn`` at ``u1``.

    Seed 001 Sec. 3 (see the module docstring): the drift reduction is |dvT1| - |p| with |p| = e1 + e2 (seed 002
    Eq. 21) at the phase where it helps the e-vector correction; the pair is planned on the nominal prediction
    (secular J2 when ``j2``, nominal drag ``da_dot`` [1/s]) ``pair_delay`` after the ejection. All burns are
    quantized and split (``max_burn``).

    Parameters
    ----------
    dv1_rtn : array_like, shape (3,)
        The commanded ejection [m/s], relative, RTN.
    u1, epoch1 : float
        The carrier's mean argument of latitude [rad] and the epoch [s] at the ejection.
    a, inc : float
        The carrier's semi-major axis [m] and inclination [rad].
    sep : SeparationConfig
        Reduction sizing (Eq. 21), the minimum R-N distance and the side (leading/following).
    mcfg : MultiImpulseConfig
        Burn size limit, quantum and delays.
    j2 : bool
        With the J2 secular rates.
    da_dot : float
        Nominal differential-drag rate of da [1/s].

    Returns
    -------
    CarrierPlan
        The carrier burns in time order and the predicted ROE.
    """
    dv1 = np.asarray(dv1_rtn, dtype=float)
    if dv1.shape != (3,) or not np.all(np.isfinite(dv1)):
        raise ValueError(f"ejection dv must be three finite numbers [m/s], got {show(dv1_rtn)}")
    mcfg.validate()
    n = float(mean_motion(a))
    u_rate = float(arg_latitude_rate(a, inc, j2))
    chief = Chief(a=a, inc=inc, u0=u1, t0=epoch1)

    def epoch_of(u):
        return epoch1 + (u - u1) / u_rate

    roe1 = delta_roe(dv1, u1, a, n)
    de_min = sep.min_rn_distance / a
    # drift reduction: size from Eqs. (18)/(21), phase along the e-vector change still needed
    p = reduction_bounds(dv1[1], sep)[0]
    stop_rel = float(drift_stop_dv(np.array([0.0, dv1[1], 0.0]), p)[1])
    stop_parts = split_burn(-stop_rel, mcfg.max_burn, mcfg.dv_quantum)  # carrier burns
    u_from = u1 + 2.0 * math.pi * mcfg.min_stop_delay_rev
    roe_guess = propagate(roe1, (u_from - u1) / u_rate, a, inc, j2, da_dot=da_dot)
    dde = anti_parallel_target(roe_guess[2:4], roe_guess[4:6], de_min, not sep.leading) - roe_guess[2:4]
    phase = math.atan2(dde[1], dde[0]) + (0.0 if stop_rel > 0 else math.pi)  # 2 dvT (cos u, sin u) along dde
    u_stop = first_u_after(phase, u_from)
    burns = [Burn(epoch1, tuple(dv1))]
    plan = []
    for j, dv_c in enumerate(stop_parts):
        u = u_stop + 2.0 * math.pi * j
        rel = np.array([0.0, -dv_c, 0.0])
        plan.append(CarrierBurn("drift_reduction", u, epoch_of(u), -rel, rel))
        burns.append(Burn(epoch_of(u), tuple(rel)))
    t_red = plan[-1].epoch if plan else epoch1
    roe_red = trajectory(np.zeros(6), epoch1, burns, [t_red], chief, j2=j2, da_dot=da_dot)[0]

    # tangential pair on the predicted state at the earliest pair epoch
    t_p = epoch1 + mcfg.pair_delay
    if plan and t_p <= t_red:
        raise ValueError(f"pair_delay ({mcfg.pair_delay} s) must exceed the drift reduction "
                         f"({t_red - epoch1:.0f} s after the ejection)")
    roe_p = trajectory(np.zeros(6), epoch1, burns, [t_p], chief, j2=j2, da_dot=da_dot)[0]
    dde = anti_parallel_target(roe_p[2:4], roe_p[4:6], de_min, not sep.leading) - roe_p[2:4]
    # the state at the pair's first burn (up to one revolution later) differs by the J2 rotation of de and the
    # drag drift: refine once at that epoch
    u_p = chief.u_at(t_p, j2)
    pair = tangential_pair if sep.leading else tangential_pair_following
    for _ in range(2):
        u_a, x1, x2 = pair(roe_p[0], dde, n, a)
        u_first = first_u_after(u_a, float(u_p))
        roe_a = trajectory(np.zeros(6), epoch1, burns, [epoch_of(u_first)], chief, j2=j2, da_dot=da_dot)[0]
        dde = anti_parallel_target(roe_a[2:4], roe_a[4:6], de_min, not sep.leading) - roe_a[2:4]
        roe_p = roe_a
    u_a, x1, x2 = pair(roe_a[0], dde, n, a)
    u_first = first_u_after(u_a, float(u_p))
    for x, u0 in ((x1, u_first), (x2, u_first + math.pi)):
        for j, dv_c in enumerate(split_burn(-x, mcfg.max_burn, mcfg.dv_quantum)):
            u = u0 + 2.0 * math.pi * j
            rel = np.array([0.0, -dv_c, 0.0])
            plan.append(CarrierBurn("e_vector_pair", u, epoch_of(u), -rel, rel))
    plan.sort(key=lambda b: b.epoch)
    all_burns = [burns[0]] + [Burn(b.epoch, tuple(b.dv_relative_rtn)) for b in plan]
    t_ic = plan[-1].epoch
    roe_f = trajectory(np.zeros(6), epoch1, all_burns, [t_ic], chief, j2=j2, da_dot=da_dot)[0]
    p_eff = abs(dv1[1]) - abs(sum(float(b.dv_carrier_rtn[1]) for b in plan if b.purpose == "drift_reduction"))
    return CarrierPlan(tuple(plan), float(p_eff), roe_red, roe_f, t_ic)


def drift_free_state(dv1: ArrayLike, u1: float, a: float, inc: float, plan: CarrierPlan, *, sep: SeparationConfig,
                     j2: bool = True, da_dot: float = 0.0) -> np.ndarray:
    """ROE right after the nominal drift reduction for the SPL under-performance that leaves no drift.

    The commanded reduction is |dvT1| - |p| with |p| = e1 + e2 (Eq. 21): an SPL factor f1 = 1 - |p|/|dvT1| makes
    the residual da zero. Seed 001 AC3 asks this nearly drift-free orbit for a minimum R-N distance (Eq. 25) above
    the limit: that (not Eq. 10 alone) bounds the tangential SPL component from below, because only the tangential
    part builds the de component anti-parallel to di (at u1 = 90 deg the radial part gives de perpendicular to di).

    Parameters
    ----------
    dv1 : array_like, shape (3,)
        The commanded ejection [m/s], relative, RTN.
    u1 : float
        The carrier's mean argument of latitude at the ejection [rad].
    a, inc : float
        The carrier's semi-major axis [m] and inclination [rad].
    plan : CarrierPlan
        The plan of :func:`plan_carrier_burns` (its drift-reduction burns, epochs from the ejection at 0).
    sep : SeparationConfig
        The separation configuration (unused by the arithmetic; the plan carries its result).
    j2 : bool
        With the J2 secular rates.
    da_dot : float
        Differential-drag rate of da [1/s].

    Returns
    -------
    numpy.ndarray, shape (6,)
        Dimensionless ROE right after the last drift-reduction burn.
    """
    dv1 = np.asarray(dv1, dtype=float)
    f1 = 1.0 - plan.p / abs(dv1[1])
    chief = Chief(a=a, inc=inc, u0=u1, t0=0.0)
    burns = [Burn(0.0, tuple(f1 * dv1))] + [Burn(b.epoch, tuple(b.dv_relative_rtn)) for b in plan.burns
                                            if b.purpose == "drift_reduction"]
    t_red = max(b.epoch for b in burns)
    return trajectory(np.zeros(6), 0.0, burns, [t_red], chief, j2=j2, da_dot=da_dot)[0]


@dataclass(frozen=True)
class MultiImpulseDesign:
    """Nominal multi-impulse plan and its J2 diagnostics (seed 001 Secs. 2.2, 3)."""

    config: SeparationConfig  # the scenario's separation config with the SPL size/u1 of ``multi``
    multi: MultiImpulseConfig
    a: float
    n: float
    inc: float
    u1: float
    e_tilde: float  # m/s
    a_di_f: float  # m
    dv1_rtn: np.ndarray  # m/s, ejection (relative)
    plan: CarrierPlan
    bounds: object
    dv_t_eq10: float = 0.0  # m/s, least |dvT1| of seed 002 Eq. (10)
    dv_t_ac3: float = 0.0  # m/s, least |dvT1| with AC3 for the drift-free sample

    @property
    def thrusted_dv_total(self) -> float:
        """Sum of the carrier burn magnitudes [m/s]."""
        return float(sum(np.linalg.norm(b.dv_carrier_rtn) for b in self.plan.burns))

    @property
    def thrusted_to_ejection_ratio(self) -> float:
        """Thrusted / ejection delta-v (seed 001 Sec. 3 figure of merit; 95 % for the double impulse)."""
        return self.thrusted_dv_total / float(np.linalg.norm(self.dv1_rtn))

    def j2_effects(self) -> dict:
        """Secular J2 where it matters (seed 001 Sec. 2.2 item 3): e-vector rotation [deg/day], a dix at the
        ejection [m] and the a diy drift [m/day] it drives (also for an ejection at u1 = 88 deg and per m of a dix)."""
        a, inc, n = self.a, self.inc, self.n
        rot = float(eccentricity_vector_rotation_rate(a, inc)) * SECONDS_PER_DAY
        dix = ejection_dix(self.dv1_rtn[2], self.u1, a, n)
        dix_88 = ejection_dix(self.dv1_rtn[2], math.radians(88.0), a, n)
        day = SECONDS_PER_DAY
        return {
            "e_vector_rotation_deg_per_day": math.degrees(rot),
            "a_dix_at_ejection": float(dix * a),
            "a_diy_drift_m_per_day": float(inclination_vector_drift_rate(a, inc, dix) * day * a),
            "a_diy_drift_m_per_day_if_u1_88deg": float(inclination_vector_drift_rate(a, inc, dix_88) * day * a),
            "a_diy_drift_per_m_dix_m_per_day": float(inclination_vector_drift_rate(a, inc, 1.0) * day),
        }


def multi_config(sep: SeparationConfig, mcfg: MultiImpulseConfig) -> SeparationConfig:
    """The scenario's separation config with the multi-impulse SPL size and ejection latitude."""
    return replace(sep, spl_dv=mcfg.spl_dv, u1_deg=mcfg.u1_deg)


def design(sep: SeparationConfig = SeparationConfig(), mcfg: MultiImpulseConfig = MultiImpulseConfig(),
           mc: MonteCarloConfig | None = None, j2: bool = True) -> MultiImpulseDesign:
    """Nominal multi-impulse plan (seed 001 Sec. 3) at epoch 0; nominal drag from ``mc`` (default settings).

    Parameters
    ----------
    sep : SeparationConfig
        The scenario's separation configuration (its SPL size and u1 replaced by ``mcfg``'s).
    mcfg : MultiImpulseConfig
        The multi-impulse inputs.
    mc : MonteCarloConfig, optional
        The drag of the nominal prediction (``delta_b``, ``density``, ``drag``); default settings when None.
    j2 : bool
        With the J2 secular rates.

    Returns
    -------
    MultiImpulseDesign
        The ejection, the carrier plan and the design quantities.

    Raises
    ------
    InfeasibleDesignError
        When safety #7 or AC3 cannot be met; ValueError for a malformed configuration.
    """
    mcfg.validate()
    cfg = multi_config(sep, mcfg)
    validate_config(cfg)
    mc = MonteCarloConfig() if mc is None else mc
    a = float(semi_major_axis(cfg.altitude))
    n = float(mean_motion(a))
    inc = float(sun_synchronous_inclination(a)) if cfg.inclination_deg is None else math.radians(cfg.inclination_deg)
    b = admissible_bounds(cfg, n)
    e_tilde = spl_error(cfg.spl_dv, cfg.spl_sigma)
    a_di = b.a_di_max if mcfg.a_di_f is None else float(mcfg.a_di_f)
    if a_di - b.a_di_margin < b.a_di_min:
        raise InfeasibleDesignError(
            f"safety #7: a_di_f = {a_di:.2f} m leaves {a_di - b.a_di_margin:.2f} m under a {cfg.spl_sigma:.0%} "
            f"under-performance, below a_di_min = {b.a_di_min:.2f} m")
    dv_n = spl_normal(a_di, n)
    u1 = math.radians(cfg.u1_deg)
    da_dot = float(drag_da_dot(mc.delta_b, mc.density, a)) if mc.drag else 0.0
    side = 1.0 if cfg.leading else -1.0

    def ejection(t_abs):
        t = -side * t_abs
        return np.array([spl_radial(cfg.spl_dv, t, dv_n, cfg.leading), t, dv_n])

    def margin(t_abs):  # AC3 of the drift-free sample after the drift reduction, minus the requirement [m]
        dv1 = ejection(t_abs)
        plan = plan_carrier_burns(dv1, u1, 0.0, a, inc, sep=cfg, mcfg=mcfg, j2=j2, da_dot=da_dot)
        return a * float(min_rn_distance(drift_free_state(dv1, u1, a, inc, plan, sep=cfg, j2=j2, da_dot=da_dot))) \
            - cfg.min_rn_distance

    t_lo = abs(spl_tangential(e_tilde, cfg.leading))  # Eq. (10): outward drift under the SPL error
    t_hi = math.sqrt(max(cfg.spl_dv**2 - dv_n**2, 0.0)) * 0.999
    t_ac3 = t_lo
    if margin(t_lo) < 0.0:
        if margin(t_hi) < 0.0:
            raise InfeasibleDesignError(
                f"AC3: no tangential SPL component gives a minimum R-N distance of {cfg.min_rn_distance:g} m for "
                f"the drift-free sample with a_di_f = {a_di:.1f} m")
        lo, hi = t_lo, t_hi
        while hi - lo > 1e-6:  # bisection: the margin grows with |dvT1|
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if margin(mid) < 0.0 else (lo, mid)
        t_ac3 = hi
    dv1 = ejection(max(t_lo, t_ac3))
    plan = plan_carrier_burns(dv1, u1, 0.0, a, inc, sep=cfg, mcfg=mcfg, j2=j2, da_dot=da_dot)
    return MultiImpulseDesign(cfg, mcfg, a, n, inc, u1, e_tilde, a_di, dv1, plan, b, t_lo, t_ac3)


def design_report(d: MultiImpulseDesign) -> dict:
    """Machine-readable multi-impulse design (SI, angles in deg where named)."""
    a = d.a
    fin = d.plan.roe_final
    de, phi = e_vector_polar(fin)
    di, theta = i_vector_polar(fin)
    dl_red = d.plan.roe_after_reduction
    return {
        "strategy": "multi_impulse",
        "a": a,
        "n": d.n,
        "inclination_deg": math.degrees(d.inc),
        "u1_deg": math.degrees(d.u1),
        "spl_dv": d.config.spl_dv,
        "spl_error": d.e_tilde,
        "dv_t_min_eq10": d.dv_t_eq10,
        "dv_t_min_ac3": d.dv_t_ac3,
        "a_di_f": d.a_di_f,
        "ejection_dv_rtn": d.dv1_rtn.tolist(),
        "maneuvers": [
            {"purpose": b.purpose, "spacecraft": "carrier", "u_deg": math.degrees(b.u),
             "epoch": b.epoch, "dv_rtn": b.dv_carrier_rtn.tolist(), "dv_relative_rtn": b.dv_relative_rtn.tolist(),
             "dv": float(np.linalg.norm(b.dv_carrier_rtn))}
            for b in d.plan.burns],
        "p": d.plan.p,
        "thrusted_dv_total": d.thrusted_dv_total,
        "thrusted_to_ejection_ratio": d.thrusted_to_ejection_ratio,
        "max_burn": d.multi.max_burn,
        "dv_quantum": d.multi.dv_quantum,
        "roe_after_ejection": (delta_roe(d.dv1_rtn, d.u1, a, d.n) * a).tolist(),
        "roe_after_reduction": (dl_red * a).tolist(),
        "roe_final": (fin * a).tolist(),
        "ic_epoch": d.plan.ic_epoch,
        "final_ei_angle_deg": math.degrees(float(wrap_angle(phi - theta))),
        "final_min_rn_distance": float(min_rn_distance(fin) * a),
        "final_a_de": float(de * a),
        "final_a_di": float(di * a),
        "j2": d.j2_effects(),
        "bounds": {k: getattr(d.bounds, k) for k in ("a_de_min", "a_de_max", "a_di_min", "a_di_max",
                                                     "a_dl_min", "a_dl_max", "a_di_margin")},
    }
