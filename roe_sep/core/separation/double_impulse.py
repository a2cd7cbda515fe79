"""Double-impulse separation design: SPL ejection + the carrier's blind drift-stop (seeds 000/002).

Equation numbers are those of seed 002 (the conference version); seed 000 numbers them one higher from Eq. 2 on.

The ejection (impulse 1, by the spring mechanism, fixed magnitude, free direction) at mean argument of latitude u1
and the drift-stop (impulse 2, by the carrier) half-revolutions later, at u2 = u1 + k pi with k odd, realise the aimed
final relative orbit: da_F = 0, relative inclination vector of magnitude di_F at phase theta_F = u1, and relative
eccentricity vector of magnitude de_F at phase xi = theta_F + eta, eta = 0 (parallel) or pi (anti-parallel), Eq. (9):

    dvR1 = dvR2 = -(n a / 4) Delta dl*,   dvT1 = -dvT2 = +-(n a / 4) de_F,   dvN1 = n a di_F,   dvN2 = 0,

with the radial component fixed by the SPL magnitude, Eq. (12), and the mean along-track separation of Eq. (13),
dl_F = -3/2 k pi da1 + Delta dl*. Impulses here are *relative*: the velocity change of the picosatellite w.r.t. the
carrier, as in the seeds. The carrier executes the drift-stop as the opposite burn, ``-dv2``.
"""

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ...errors import InfeasibleDesignError, show
from ..relmotion.dynamics import arg_latitude_rate, propagate, sun_synchronous_inclination
from ..relmotion.maneuvers import delta_roe
from ..relmotion.orbit import mean_motion, semi_major_axis


@dataclass(frozen=True)
class SeparationConfig:
    """Inputs of the double-impulse design (defaults: the BIROS/picosatellite case of seeds 000/002)."""

    altitude: float = 515e3  # m, circular carrier orbit
    inclination_deg: float | None = None  # deg; None: sun-synchronous at ``altitude`` (used by J2 propagation)
    u1_deg: float = 88.0  # deg, mean argument of latitude of the ejection
    spl_dv: float = 1.41  # m/s, SPL ejection magnitude (fixed by the mechanism)
    a_de_f: float = 590.0  # m, aimed relative eccentricity vector magnitude
    a_di_f: float = 400.0  # m, aimed relative inclination vector magnitude
    leading: bool = True  # picosatellite ahead of the carrier at the end (dl_F > 0)
    k: int = 3  # odd number of half revolutions between ejection and drift-stop
    eta_deg: float | None = None  # 180 (anti-parallel) or 0 (parallel); None: implied by ``leading``
    spl_sigma: float = 0.10  # 1-sigma SPL magnitude error (fraction of |dv|): f1 of Eq. (22)
    thruster_sigma: float = 0.05  # 1-sigma carrier thruster magnitude error (fraction): f2 of Eq. (22)
    p_sigma_level: float = 3.0  # under-performance covered by p: e1 + e2 <= |p|, Eq. (21)
    a_dl_min: float = 5000.0  # m, radar (TIRA) separability: safety #1
    a_dl_max: float = 10000.0  # m, camera detectability: visibility #1
    min_rn_distance: float = 150.0  # m, passive safety minimum R-N distance: safety #5
    fov_half_r_deg: float = 6.8  # deg, camera half field of view, radial (horizontal)
    fov_half_n_deg: float = 9.15  # deg, camera half field of view, normal (vertical)


@dataclass(frozen=True)
class Bounds:
    """Admissible sizes of the final relative orbit [m], seed 002 Table 2, each derived from Table 1."""

    a_dl_min: float
    a_dl_max: float
    a_de_min: float
    a_de_max: float
    a_di_min: float
    a_di_max: float
    a_di_margin: float  # m, SPL error in the normal direction, e~/n (safety #7)


@dataclass(frozen=True)
class DoubleImpulseDesign:
    """Nominal double-impulse plan and its design quantities."""

    config: SeparationConfig
    a: float  # m
    n: float  # rad/s
    inc: float  # rad, carrier inclination
    u1: float  # rad
    u2: float  # rad
    k: int
    eta: float  # rad
    dv1_rtn: np.ndarray  # m/s, ejection (relative)
    dv2_rtn: np.ndarray  # m/s, drift-stop, relative effect (seed convention); carrier burns -dv2
    a_dl_star: float  # m, a Delta dl* of Eq. (9)
    a_da1: float  # m, relative semi-major axis after the ejection
    a_dl_f: float  # m, Eq. (13)
    k_admissible: tuple = field(default_factory=tuple)
    bounds: Bounds | None = None
    p_min: float = 0.0  # m/s, e1 + e2 at ``p_sigma_level`` sigma, Eq. (21)
    p_max: float = 0.0  # m/s, n a de_F / 4 - e2, Eq. (21)

    def drift_stop_dv(self, p: float = 0.0) -> np.ndarray:
        """Relative drift-stop impulse ``(3,)`` [m/s] RTN with the tangential part reduced by |p| [m/s], seed 002
        Eq. (18)."""
        return drift_stop_dv(self.dv1_rtn, p)

    def final_roe(self, p: float = 0.0, j2: bool = False) -> np.ndarray:
        """Dimensionless ROE ``(6,)`` right after a nominally executed drift-stop with reduction ``p`` [m/s] (Eq. 2;
        Keplerian unless ``j2``)."""
        return plan_drift_stop(self.dv1_rtn, self.u1, 0.0, self.a, self.inc, k=self.k, p=p, j2=j2).aimed_roe


def drift_stop_dv(dv1_rtn: ArrayLike, p: float = 0.0) -> np.ndarray:
    """The blind drift-stop ``(..., 3)`` [m/s] from the *commanded* ejection ``(..., 3)`` [m/s] alone and the
    reduction ``p`` [m/s], seed 002 Eqs. (9) and (18).

    dvR2 = dvR1, dvT2 = -dvT1 reduced in magnitude by |p|, dvN2 = 0 (relative impulse; the carrier burns the
    opposite). Executed k pi after the ejection it cancels the commanded drift whatever the aimed de_F, di_F were.
    """
    dv1 = np.asarray(dv1_rtn, dtype=float)
    t2 = -dv1[..., 1]
    return np.stack([dv1[..., 0], t2 - np.copysign(abs(p), t2), np.zeros_like(t2)], axis=-1)


def reduction_bounds(dv_t1: float, cfg: SeparationConfig) -> tuple[float, float]:
    """Design range ``(lo, hi)`` of the drift-stop reduction for the tangential ejection ``dv_t1`` [m/s], seed 002
    Eq. (21): e1 + e2 <= |p| < |dvT1| - e2 [m/s].

    e1, e2: ``p_sigma_level``-sigma under-/over-performance of the two tangential impulses (|dvT2| = |dvT1|).
    """
    e1 = cfg.p_sigma_level * cfg.spl_sigma * abs(dv_t1)
    e2 = cfg.p_sigma_level * cfg.thruster_sigma * abs(dv_t1)
    return e1 + e2, abs(dv_t1) - e2


def _require_finite(name, value, positive=True):
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise ValueError(f"{name} must be a number, got {show(value)}")
    if not math.isfinite(value):
        raise ValueError(f"{name} must be finite, got {value}")
    if positive and value <= 0:
        raise ValueError(f"{name} must be positive, got {value}")


def validate_config(cfg: SeparationConfig) -> None:
    """Reject malformed input (NaN, negative, wrong type) with the offending field named."""
    for name in ("altitude", "spl_dv", "a_de_f", "a_di_f", "spl_sigma", "thruster_sigma", "p_sigma_level",
                 "a_dl_min", "a_dl_max", "min_rn_distance", "fov_half_r_deg", "fov_half_n_deg"):
        _require_finite(name, getattr(cfg, name))
    _require_finite("u1_deg", cfg.u1_deg, positive=False)
    if cfg.inclination_deg is not None:
        _require_finite("inclination_deg", cfg.inclination_deg, positive=False)
    if not isinstance(cfg.leading, bool):
        raise ValueError(f"leading must be true or false, got {show(cfg.leading)}")
    if isinstance(cfg.k, bool) or not isinstance(cfg.k, (int, np.integer)) or cfg.k < 1 or cfg.k % 2 == 0:
        raise ValueError(f"k must be an odd natural number (half revolutions to the drift-stop), got {show(cfg.k)}")
    if cfg.a_dl_min >= cfg.a_dl_max:
        raise ValueError(f"a_dl_min ({cfg.a_dl_min} m) must be below a_dl_max ({cfg.a_dl_max} m)")
    if cfg.eta_deg is not None:
        _require_finite("eta_deg", cfg.eta_deg, positive=False)


def admissible_bounds(cfg: SeparationConfig, n: float) -> Bounds:
    """Seed 002 Table 2 from the constraints of Table 1.

    * a dl in [safety #1 radar separability, visibility #1 camera range].
    * a de_min = max(4 e~ / n (safety #6, Eq. 10: |dvT1| = n a de_F / 4 > e~), safety #5 minimum R-N distance),
      with e~ = spl_sigma |dv|.
    * a di_min = safety #5 minimum R-N distance + e~ / n (safety #7 margin).
    * a de_max, a di_max: camera half field of view at the smallest a dl (visibility #2, #3; Eq. 11).
    """
    e_tilde = cfg.spl_sigma * cfg.spl_dv
    margin = e_tilde / n
    return Bounds(
        a_dl_min=cfg.a_dl_min,
        a_dl_max=cfg.a_dl_max,
        a_de_min=max(4.0 * e_tilde / n, cfg.min_rn_distance),
        a_de_max=float(np.tan(math.radians(cfg.fov_half_r_deg)) * cfg.a_dl_min),
        a_di_min=cfg.min_rn_distance + margin,
        a_di_max=float(np.tan(math.radians(cfg.fov_half_n_deg)) * cfg.a_dl_min),
        a_di_margin=margin,
    )


def admissible_k(a_dl_star: float, a_da1: float, a_dl_min: float, a_dl_max: float) -> tuple[int, ...]:
    """Odd k with a dl_F = -3/2 k pi a da1 + a Delta dl* inside [a_dl_min, a_dl_max] in magnitude, Eq. (13)-(14).

    Parameters
    ----------
    a_dl_star : float
        a Delta dl* of Eq. (9) [m].
    a_da1 : float
        a da after the ejection [m].
    a_dl_min, a_dl_max : float
        The band of the final |a dl| [m].

    Returns
    -------
    tuple of int
        The admissible k, ascending (empty when none).
    """
    step = 1.5 * math.pi * abs(a_da1)
    lo = (a_dl_min - abs(a_dl_star)) / step
    hi = (a_dl_max - abs(a_dl_star)) / step
    first = max(1, math.ceil(lo))
    return tuple(k for k in range(first, math.floor(hi) + 1) if k % 2 == 1)


def design(cfg: SeparationConfig = SeparationConfig()) -> DoubleImpulseDesign:
    """Nominal double-impulse plan, seed 002 Eqs. (9)-(14) and (21); raises on any violated constraint."""
    validate_config(cfg)
    a = float(semi_major_axis(cfg.altitude))
    n = float(mean_motion(a))
    b = admissible_bounds(cfg, n)
    eta = math.pi if cfg.leading else 0.0
    if cfg.eta_deg is not None and not math.isclose(math.radians(cfg.eta_deg) % (2 * math.pi), eta, abs_tol=1e-9):
        side = "leading" if cfg.leading else "following"
        need = "anti-parallel (eta = 180 deg)" if cfg.leading else "parallel (eta = 0 deg)"
        raise InfeasibleDesignError(
            f"safety #2 (first along-track crossing): with the picosatellite {side} the e/i vectors must be "
            f"{need}, got eta = {cfg.eta_deg} deg")
    if cfg.a_de_f < b.a_de_min:
        which = "safety #6 (drift sign under SPL error, Eq. 10)" if b.a_de_min > cfg.min_rn_distance else "safety #5"
        raise InfeasibleDesignError(f"{which}: a_de_f = {cfg.a_de_f:g} m is below a_de_min = {b.a_de_min:.2f} m")
    if cfg.a_di_f < b.a_di_min:
        raise InfeasibleDesignError(
            f"safety #7 (truly obtainable di): a_di_f = {cfg.a_di_f:g} m is below a_di_min = {b.a_di_min:.2f} m "
            f"({cfg.min_rn_distance:g} m + margin {b.a_di_margin:.2f} m)")
    if cfg.a_de_f > b.a_de_max:
        raise InfeasibleDesignError(
            f"visibility #2 (camera FOV in R, Eq. 11): a_de_f = {cfg.a_de_f:g} m exceeds a_de_max = {b.a_de_max:.2f} m")
    if cfg.a_di_f > b.a_di_max:
        raise InfeasibleDesignError(
            f"visibility #3 (camera FOV in N, Eq. 11): a_di_f = {cfg.a_di_f:g} m exceeds a_di_max = {b.a_di_max:.2f} m")

    side = 1.0 if cfg.leading else -1.0  # sign of dl_F
    dv_t1 = -side * n * cfg.a_de_f / 4.0  # Eq. (9): leading needs dvT1 < 0 (eta = pi)
    dv_n1 = n * cfg.a_di_f  # Eq. (4): n a |Delta di| = |dvN|, dvN1 > 0 so theta_F = u1
    radial_sq = cfg.spl_dv**2 - dv_t1**2 - dv_n1**2
    if radial_sq <= 0.0:
        raise InfeasibleDesignError(
            f"SPL |dv| = {cfg.spl_dv:g} m/s is too small for the aimed orbit (Eq. 12): the tangential and normal "
            f"components alone need {math.hypot(dv_t1, dv_n1):.4f} m/s")
    dv_r1 = -side * math.sqrt(radial_sq)  # Eq. (12), sign from Eq. (9) and safety #2
    a_dl_star = -4.0 * dv_r1 / n  # Eq. (9), first line
    a_da1 = 2.0 * dv_t1 / n  # Eq. (2)
    ks = admissible_k(a_dl_star, a_da1, cfg.a_dl_min, cfg.a_dl_max)
    a_dl_f = -1.5 * cfg.k * math.pi * a_da1 + a_dl_star  # Eq. (13)
    if cfg.k not in ks:
        raise InfeasibleDesignError(
            f"safety #1 / visibility #1 (Eq. 14): k = {cfg.k} gives a_dl_F = {a_dl_f:.1f} m outside "
            f"[{cfg.a_dl_min:g}, {cfg.a_dl_max:g}] m; admissible k: {list(ks) or 'none'}")
    p_min, p_max = reduction_bounds(dv_t1, cfg)
    u1 = math.radians(cfg.u1_deg)
    inc = float(sun_synchronous_inclination(a)) if cfg.inclination_deg is None else math.radians(cfg.inclination_deg)
    return DoubleImpulseDesign(
        config=cfg,
        a=a,
        n=n,
        inc=inc,
        u1=u1,
        u2=u1 + cfg.k * math.pi,
        k=cfg.k,
        eta=eta,
        dv1_rtn=np.array([dv_r1, dv_t1, dv_n1]),
        dv2_rtn=drift_stop_dv([dv_r1, dv_t1, dv_n1]),
        a_dl_star=a_dl_star,
        a_da1=a_da1,
        a_dl_f=a_dl_f,
        k_admissible=ks,
        bounds=b,
        p_min=p_min,
        p_max=p_max,
    )


@dataclass(frozen=True)
class DriftStopPlan:
    """The carrier's blind drift-stop for one commanded ejection (what the planner node publishes)."""

    u2: float  # rad, mean argument of latitude of the drift-stop (unwrapped: u1 + k pi)
    epoch: float  # s, execution epoch on the same time scale as the ejection epoch
    dv_relative_rtn: np.ndarray  # m/s, relative effect (seed convention)
    dv_carrier_rtn: np.ndarray  # m/s, the carrier's own burn (= -dv_relative_rtn)
    aimed_roe: np.ndarray  # dimensionless, predicted right after a nominally executed drift-stop
    p: float  # m/s


def plan_drift_stop(dv1_rtn: ArrayLike, u1: float, epoch1: float, a: float, inc: float, *, k: int, p: float,
                    j2: bool = True) -> DriftStopPlan:
    """Plan the drift-stop k pi after a commanded ejection ``dv1_rtn`` at ``u1`` [rad] and ``epoch1`` [s].

    Eqs. (9)/(18) via :func:`drift_stop_dv`; the epoch follows from the secular rate of the argument of latitude
    (with J2 when ``j2``); the aimed ROE apply Eq. (2) to both commanded impulses with the secular propagation.

    Parameters
    ----------
    dv1_rtn : array_like, shape (3,)
        The commanded ejection [m/s], relative, RTN.
    u1, epoch1 : float
        The carrier's mean argument of latitude [rad] and the epoch [s] at the ejection.
    a, inc : float
        The carrier's semi-major axis [m] and inclination [rad].
    k : int
        Odd number of half revolutions from the ejection to the drift-stop.
    p : float
        The reduction of the tangential drift-stop [m/s] (its magnitude counts).
    j2 : bool
        With the J2 secular rates.

    Returns
    -------
    DriftStopPlan
        Epoch, argument of latitude, relative and carrier impulses and the aimed ROE.

    Raises
    ------
    ValueError
        For a k that is not an odd natural number or a non-finite input, naming it.
    """
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1 or k % 2 == 0:
        raise ValueError(f"k must be an odd natural number, got {show(k)}")
    dv1 = np.asarray(dv1_rtn, dtype=float)
    if dv1.shape != (3,) or not np.all(np.isfinite(dv1)):
        raise ValueError(f"ejection dv must be three finite numbers [m/s], got {show(dv1_rtn)}")
    for name, value in (("u1", u1), ("epoch1", epoch1), ("a", a), ("inc", inc), ("p", p)):
        _require_finite(name, float(value), positive=name == "a")
    n = float(mean_motion(a))
    dt = k * math.pi / float(arg_latitude_rate(a, inc, j2))
    u2 = u1 + k * math.pi
    dv2 = drift_stop_dv(dv1, p)
    roe = propagate(delta_roe(dv1, u1, a, n), dt, a, inc, j2) + delta_roe(dv2, u2, a, n)
    return DriftStopPlan(u2=u2, epoch=epoch1 + dt, dv_relative_rtn=dv2, dv_carrier_rtn=0.0 - dv2, aimed_roe=roe,
                         p=abs(p))
