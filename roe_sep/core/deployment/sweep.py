"""Deployment direction and velocity of a CubeSat released from a mother craft (seed 003 Sec. 4.2, Figs. 4-6).

The CubeSat leaves the mother craft (zero relative state) with an impulsive deployer velocity ``dv`` in the orbital
plane, at the angle ``angle`` measured from +V-bar *clockwise* in the seed's LVLH picture (V-bar to the right,
zenith up): 0 deg = +V-bar (along the flight direction), 90 deg = +R-bar (towards the Earth), 180 deg = -V-bar,
270 deg = -R-bar (zenith). In RTN (R radially outwards): dv_RTN = dv [-sin(angle), cos(angle), 0].

Relative motion models (``DeploymentConfig.model``), both behind :func:`distance_curves`:

* ``nonlinear`` (default, the seed's kind of propagation): both spacecraft integrated numerically by
  :mod:`roe_sep.core.truth.nonlinear` (heyoka Taylor integrator, zonal geopotential J2-J4, drag in an exponential
  atmosphere co-rotating with the Earth), all cases at once in batch mode; the distance is the true Euclidean
  distance |r_CubeSat - r_mother|. The mother craft starts on a *mean* circular orbit (mean -> osculating, first
  order J2) and the CubeSat from the same state plus the deployer impulse in the mother craft's RTN frame. The seed
  propagates with GMAT (RK89, JGM-2 to J4, MSISE90, SRP, Sun/Moon); SRP and third bodies are left out (their
  differential effect is orders of magnitude below drag).
* ``linear``: the impulse enters the ROE by seed 002 Eq. (2) (:func:`~roe_sep.core.relmotion.maneuvers.delta_roe`),
  the ROE are propagated by the core's secular model (:func:`relative_motion`: Keplerian drift, J2 of the
  Koenig-Guffanti-D'Amico STM, differential drag as a constant d(da)/dt from
  :func:`~roe_sep.core.relmotion.dynamics.drag_da_dot`) and mapped to RTN with
  :func:`~roe_sep.core.relmotion.roe.roe_to_rtn`; the along-track distance is then the arc a*dl. Fast; the model of
  the planner, so the sweep also shows how far that model carries (compared in docs/seeds.md).

Drag: only the CubeSat is perturbed (seed 003 Sec. 4.1: the Space Rider is controlled, 'not perturbed, except for
gravitational effects'), so dB = B_cubesat - B_mother with B_mother = 0 by default. Default density: the US
Standard Atmosphere 1976 value at 400 km, 2.803e-12 kg/m^3 (the seed used MSISE90 for March 2022, which is not
reproduced here: absolute distances differ, the qualitative findings do not). The nonlinear model scales Vallado's
exponential profile (scale height of the band, :meth:`~roe_sep.core.truth.nonlinear.Atmosphere.scaled`) to this density
at the deployment altitude.
"""

from dataclasses import asdict, dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ...errors import show
from ..constants import SECONDS_PER_DAY
from ..relmotion.dynamics import arg_latitude_rate, ballistic_coefficient, drag_da_dot, propagate
from ..relmotion.maneuvers import delta_roe
from ..relmotion.orbit import mean_motion, semi_major_axis
from ..relmotion.roe import roe_to_rtn

MODELS = ("nonlinear", "linear")
PROPAGATION = {
    "nonlinear": "nonlinear truth (roe_sep.core.truth.nonlinear, heyoka): J2-J4 zonal geopotential + drag, exponential "
                 "atmosphere",
    "linear": "secular ROE model (roe_sep.core.relmotion.dynamics.propagate): Keplerian + J2 + differential drag",
}
FIRST_ORBIT_STEP = 2.0  # s, sampling of the first-orbit closest approach (refined by a parabola)

USSA76_DENSITY_400KM = 2.803e-12  # kg/m^3, US Standard Atmosphere 1976 at 400 km geometric altitude


@dataclass(frozen=True)
class CubeSat:
    """Drag properties of the deployed CubeSat (seed 003 Sec. 4.1: 12U, 24 kg, c_d 2.2, 0.06 m^2)."""

    cd: float = 2.2
    area: float = 0.06  # m^2
    mass: float = 24.0  # kg

    @property
    def ballistic(self) -> float:
        """B = c_d A / m [m^2/kg]."""
        return ballistic_coefficient(self.cd, self.area, self.mass)


@dataclass(frozen=True)
class DeploymentConfig:
    """The deployment sweep of seed 003 Sec. 4.2 (defaults: the seed's scenarios at 400 km)."""

    altitude: float = 400e3  # m, circular orbit of the mother craft
    inclinations_deg: tuple = (97.03, 37.0, 5.0)  # scenarios 1/2, 3/4, 5
    dv: tuple = (1.0, 0.2)  # m/s, standard and customised deployer
    angles_deg: tuple = tuple(float(a) for a in range(0, 360, 15))  # from +V-bar, clockwise
    days: float = 10.0  # free drift after the deployment
    step: float = 600.0  # s, sampling of the distance-vs-time curves
    u0_deg: float = 0.0  # mean argument of latitude at the deployment (the seed starts at true anomaly 0)
    density: float = USSA76_DENSITY_400KM  # kg/m^3
    cubesat: CubeSat = field(default_factory=CubeSat)
    mother_ballistic: float = 0.0  # m^2/kg, 0: the mother craft is not perturbed by drag (seed 003)
    drag: bool = True
    j2: bool = True  # linear model only: the nonlinear model always carries J2-J4
    model: str = "nonlinear"  # "nonlinear" (heyoka, J2-J4 + drag) or "linear" (secular ROE model)

    def validate(self) -> "DeploymentConfig":
        """Raise ValueError naming the first bad field; ``self`` otherwise."""
        if not (np.isfinite(self.altitude) and 100e3 <= self.altitude <= 5000e3):
            raise ValueError(f"altitude must be between 100 km and 5000 km [m], got {self.altitude}")
        for name in ("inclinations_deg", "dv", "angles_deg"):
            v = np.asarray(getattr(self, name), dtype=float)
            if v.ndim != 1 or v.size == 0 or not np.all(np.isfinite(v)):
                raise ValueError(f"{name} must be a non-empty list of finite numbers, got {show(getattr(self, name))}")
        inc = np.asarray(self.inclinations_deg, dtype=float)
        if np.any((inc <= 0.0) | (inc >= 180.0)):
            raise ValueError(f"inclinations_deg must lie in (0, 180) deg, got {show(inc)}")
        if np.any(np.asarray(self.dv, dtype=float) <= 0.0):
            raise ValueError(f"dv must be positive [m/s], got {show(list(self.dv))}")
        if not (np.isfinite(self.days) and 0.0 < self.days <= 60.0):
            raise ValueError(f"days must be in (0, 60], got {self.days}")
        if not (np.isfinite(self.step) and 1.0 <= self.step <= 0.25 * self.days * SECONDS_PER_DAY):
            raise ValueError(f"step must be in [1 s, days/4], got {self.step}")
        if not (np.isfinite(self.density) and self.density >= 0.0):
            raise ValueError(f"density must be finite and non-negative [kg/m^3], got {self.density}")
        c = self.cubesat
        if not all(np.isfinite(x) and x > 0 for x in (c.cd, c.area, c.mass)):
            raise ValueError(f"cubesat: cd, area and mass must be finite and positive, got {show(c)}")
        if not (np.isfinite(self.mother_ballistic) and self.mother_ballistic >= 0.0):
            raise ValueError(f"mother_ballistic must be finite and non-negative [m^2/kg], got {self.mother_ballistic}")
        if not np.isfinite(self.u0_deg):
            raise ValueError(f"u0_deg must be finite, got {self.u0_deg}")
        if self.model not in MODELS:
            raise ValueError(f"model must be one of {MODELS}, got {self.model!r}")
        if self.model == "nonlinear":
            if not self.j2:
                raise ValueError("j2: switching J2 off needs model 'linear' (the nonlinear model carries J2-J4)")
            if not 200e3 <= self.altitude < 1100e3:
                raise ValueError(f"altitude must be between 200 km and 1100 km for model 'nonlinear' (the tabulated "
                                 f"exponential atmosphere) [m], got {self.altitude}")
        return self

    @property
    def a(self) -> float:
        """Semi-major axis [m] of the mother craft's circular orbit."""
        return float(semi_major_axis(self.altitude))

    @property
    def delta_b(self) -> float:
        """Differential ballistic coefficient B_cubesat - B_mother [m^2/kg]."""
        return self.cubesat.ballistic - self.mother_ballistic


def deployment_dv_rtn(angle: ArrayLike, dv: ArrayLike) -> np.ndarray:
    """Deployer impulse in RTN [m/s] for the in-plane angle [rad] from +V-bar, clockwise (seed 003 Sec. 4.2).

    dv_RTN = dv [-sin(angle), cos(angle), 0]: 90 deg is +R-bar (towards the Earth, -R), 180 deg is -V-bar.
    ``angle`` and ``dv`` broadcast; the result is ``(..., 3)``.
    """
    angle, dv = np.broadcast_arrays(np.asarray(angle, dtype=float), np.asarray(dv, dtype=float))
    return np.stack([-dv * np.sin(angle), dv * np.cos(angle), np.zeros_like(dv)], axis=-1)


def deployment_roe(dv_rtn: ArrayLike, u0: ArrayLike, a: float) -> np.ndarray:
    """ROE right after the deployment from a zero relative state: seed 002 Eq. (2), Delta(da) = G(u0) dv / (n a).

    Parameters
    ----------
    dv_rtn : array_like, shape (..., 3)
        The deployer impulse [m/s] in RTN.
    u0 : array_like
        The mean argument of latitude of the deployment [rad].
    a : float
        The mother craft's semi-major axis [m].

    Returns
    -------
    numpy.ndarray, shape (..., 6)
        Dimensionless ROE.
    """
    return delta_roe(dv_rtn, u0, a, mean_motion(a))


def relative_motion(roe0: ArrayLike, t: ArrayLike, a: float, inc: ArrayLike, da_dot: ArrayLike = 0.0,
                    *, j2: bool = True) -> np.ndarray:
    """Linear model: ROE ``(..., len(t), 6)`` at times ``t`` [s] after the deployment.

    The core's secular ROE model (:func:`~roe_sep.core.relmotion.dynamics.propagate`: Keplerian, J2, constant
    differential-drag d(da)/dt; seed 002 Eqs. 23-24).

    Parameters
    ----------
    roe0 : array_like, shape (..., 6)
        Dimensionless ROE at the deployment.
    t : array_like, shape (nt,)
        Times after the deployment [s].
    a : float
        The mother craft's semi-major axis [m].
    inc : array_like, shape (...)
        Inclination [rad], broadcast against ``roe0[..., 0]``.
    da_dot : array_like, shape (...)
        Differential-drag rate of da [1/s].
    j2 : bool
        With the J2 secular rates.

    Returns
    -------
    numpy.ndarray, shape (..., nt, 6)
        Dimensionless ROE.
    """
    r0 = np.asarray(roe0, dtype=float)[..., None, :]
    inc = np.asarray(inc, dtype=float)[..., None]
    return propagate(r0, np.asarray(t, dtype=float), a, inc, j2, da_dot=np.asarray(da_dot, dtype=float)[..., None])


def relative_distance(roe: ArrayLike, u: ArrayLike, a: float) -> np.ndarray:
    """Distance [m] between CubeSat and mother craft: a |r/a| of :func:`~roe_sep.core.relmotion.roe.roe_to_rtn` at
    ``u``.

    Parameters
    ----------
    roe : array_like, shape (..., 6)
        Dimensionless ROE.
    u : array_like, shape (...)
        The mother craft's mean argument of latitude [rad].
    a : float
        Its semi-major axis [m].

    Returns
    -------
    numpy.ndarray, shape (...)
        The distance [m].
    """
    pos, _ = roe_to_rtn(roe, u)
    return a * np.linalg.norm(pos, axis=-1)


def _linear_distances(cfg, dv_rtn, inc, times):
    a = cfg.a
    u0 = np.radians(cfg.u0_deg)
    da_dot = drag_da_dot(cfg.delta_b, cfg.density, a) if cfg.drag else 0.0
    roe = relative_motion(deployment_roe(dv_rtn, u0, a), times, a, inc, np.broadcast_to(da_dot, inc.shape), j2=cfg.j2)
    return relative_distance(roe, u0 + arg_latitude_rate(a, inc[..., None], cfg.j2) * times, a)


def _nonlinear_distances(cfg, dv_rtn, inc, times):
    from ..truth.nonlinear import Atmosphere, apply_impulse, pair_state, propagate_pairs_grid

    shape = inc.shape
    inc = inc.reshape(-1)
    zero = np.zeros_like(inc)
    mother = np.stack([np.full_like(inc, cfg.a), zero, inc, zero, zero, zero + np.radians(cfg.u0_deg)], axis=-1)
    s0 = apply_impulse(pair_state(mother, mother), dv_rtn.reshape(-1, 3), np.ones(inc.shape, dtype=bool))
    b_mother, b_cubesat = (cfg.mother_ballistic, cfg.cubesat.ballistic) if cfg.drag else (0.0, 0.0)
    states = propagate_pairs_grid(s0, 0.0, times, b_mother, b_cubesat,
                                  atmosphere=Atmosphere.scaled(cfg.density, cfg.altitude))
    return np.linalg.norm(states[..., 6:9] - states[..., 0:3], axis=-1).reshape(shape + (len(times),))


def distance_curves(cfg: DeploymentConfig, dv_rtn: ArrayLike, inc: ArrayLike, times: ArrayLike) -> np.ndarray:
    """THE propagation of the deployment analysis: CubeSat-mother craft distance [m] ``(..., len(times))``.

    Parameters
    ----------
    cfg : DeploymentConfig
        Altitude, u0, drag and the model (``cfg.model``, module docstring).
    dv_rtn : array_like, shape (..., 3)
        Deployer impulses [m/s] at ``cfg.u0_deg``.
    inc : array_like, shape (...)
        Inclinations [rad].
    times : array_like, shape (nt,)
        Sorted times after the deployment [s].

    Returns
    -------
    numpy.ndarray, shape (..., nt)
        The distance [m].
    """
    dv_rtn = np.asarray(dv_rtn, dtype=float)
    inc = np.broadcast_to(np.asarray(inc, dtype=float), dv_rtn.shape[:-1])
    times = np.asarray(times, dtype=float)
    if cfg.model == "linear":
        return _linear_distances(cfg, dv_rtn, inc, times)
    return _nonlinear_distances(cfg, dv_rtn, inc, times)


def first_orbit_window(a: float, step: float = FIRST_ORBIT_STEP) -> np.ndarray:
    """Sample times [s] of the first return, t in [T/2, 3T/2] with T = 2 pi / n the Keplerian period."""
    period = 2.0 * np.pi / mean_motion(a)
    return np.arange(0.5 * period, 1.5 * period + step, step)


def _parabolic_min(t, d2):
    """Vertex of the parabola through the smallest sample of ``d2`` (last axis) and its neighbours: (t*, d2*)."""
    i = np.clip(np.argmin(d2, axis=-1), 1, d2.shape[-1] - 2)[..., None]
    y0, y1, y2 = (np.take_along_axis(d2, i + k, axis=-1)[..., 0] for k in (-1, 0, 1))
    h = t[1] - t[0]
    den = y0 - 2.0 * y1 + y2
    with np.errstate(invalid="ignore", divide="ignore"):
        off = np.where(den > 0.0, 0.5 * (y0 - y2) / den, 0.0)
    off = np.clip(off, -1.0, 1.0)
    t_min = t[i[..., 0]] + off * h
    d2_min = y1 - 0.25 * (y0 - y2) * off
    return t_min, np.minimum(np.maximum(d2_min, 0.0), np.min(d2, axis=-1))


def first_orbit_min_distance(t: ArrayLike, distance: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Closest approach [m] to the mother craft around the first return and its time [s], from the distances
    ``(..., len(t))`` sampled on :func:`first_orbit_window` ``t``.

    Seed 003 Fig. 4: a purely radial deployment leaves the orbital period unchanged (da = 0), so after one orbit the
    CubeSat is back at the mother craft (collision risk); a V-bar component drifts it away by 3 pi a da per orbit.
    The window starts half an orbit after the deployment, so the departure itself (distance 0 at t = 0) is not
    counted. Refined by a parabola through the three samples around the minimum of d^2.
    """
    t_min, d2 = _parabolic_min(np.asarray(t, dtype=float), np.asarray(distance, dtype=float) ** 2)
    return np.sqrt(d2), t_min


@dataclass
class DeploymentSweep:
    """Results over (inclination, dv, angle); distances in m, times in s."""

    config: DeploymentConfig
    times: np.ndarray  # (nt,)
    dv_rtn: np.ndarray  # (ni, nd, na, 3)
    roe0: np.ndarray  # (ni, nd, na, 6), dimensionless
    distance: np.ndarray  # (ni, nd, na, nt)
    min_first_orbit: np.ndarray  # (ni, nd, na)
    t_min_first_orbit: np.ndarray  # (ni, nd, na)

    @property
    def distance_end(self) -> np.ndarray:
        """Distance ``(ni, nd, na)`` [m] at the end of the drift."""
        return self.distance[..., -1]

    def to_dict(self, curves: bool = False) -> dict:
        """The machine-readable sweep (the documented keys): cases, per-(inclination, dv) summary, config."""
        cfg = self.config
        cases, summary = [], []
        d_end, d_max = self.distance_end, np.max(self.distance, axis=-1)
        day_idx = [int(np.argmin(np.abs(self.times - k * SECONDS_PER_DAY)))
                   for k in range(1, int(np.floor(cfg.days + 1e-9)) + 1)]
        for ii, inc in enumerate(cfg.inclinations_deg):
            for jd, dv in enumerate(cfg.dv):
                for ka, ang in enumerate(cfg.angles_deg):
                    case = {
                        "inclination_deg": float(inc), "dv": float(dv), "angle_deg": float(ang),
                        "dv_rtn": self.dv_rtn[ii, jd, ka].tolist(),
                        "min_distance_first_orbit_m": float(self.min_first_orbit[ii, jd, ka]),
                        "t_min_first_orbit_s": float(self.t_min_first_orbit[ii, jd, ka]),
                        "distance_end_m": float(d_end[ii, jd, ka]),
                        "max_distance_m": float(d_max[ii, jd, ka]),
                        "distance_daily_m": [float(self.distance[ii, jd, ka, k]) for k in day_idx],
                    }
                    if curves:
                        case["distance_m"] = self.distance[ii, jd, ka].tolist()
                    cases.append(case)
                e = d_end[ii, jd]
                summary.append({
                    "inclination_deg": float(inc), "dv": float(dv),
                    "max_distance_end_m": float(np.max(e)), "max_angle_deg": float(cfg.angles_deg[int(np.argmax(e))]),
                    "min_distance_end_m": float(np.min(e)), "min_angle_deg": float(cfg.angles_deg[int(np.argmin(e))]),
                })
        out = {"cases": cases, "summary": summary, "days": cfg.days, "a": cfg.a,
               "period_s": [float(2 * np.pi / arg_latitude_rate(cfg.a, np.radians(i), cfg.j2))
                            for i in cfg.inclinations_deg],
               "delta_b": cfg.delta_b if cfg.drag else 0.0,
               "propagation": PROPAGATION[cfg.model],
               "config": asdict(cfg)}
        if curves:
            out["times_s"] = self.times.tolist()
        return out


def sweep(config: DeploymentConfig | None = None) -> DeploymentSweep:
    """The deployment sweep of seed 003 Sec. 4.2, vectorized over inclinations x dv x angles (no Python loop):
    one propagation per case on the union of the output grid and the first-orbit window."""
    cfg = (config or DeploymentConfig()).validate()
    inc = np.radians(np.asarray(cfg.inclinations_deg, dtype=float))[:, None, None]
    dv = np.asarray(cfg.dv, dtype=float)[None, :, None]
    ang = np.radians(np.asarray(cfg.angles_deg, dtype=float))[None, None, :]
    dv_rtn = deployment_dv_rtn(ang + 0.0 * inc + 0.0 * dv, dv + 0.0 * inc + 0.0 * ang)
    roe0 = deployment_roe(dv_rtn, np.radians(cfg.u0_deg), cfg.a)
    horizon = cfg.days * SECONDS_PER_DAY
    times = np.arange(0.0, horizon + 0.5 * cfg.step, cfg.step)
    times[-1] = horizon
    window = first_orbit_window(cfg.a)
    t_all = np.union1d(times, window)
    d_all = distance_curves(cfg, dv_rtn, np.broadcast_to(inc, roe0.shape[:-1]), t_all)
    distance = d_all[..., np.searchsorted(t_all, times)]
    d_min, t_min = first_orbit_min_distance(window, d_all[..., np.searchsorted(t_all, window)])
    return DeploymentSweep(cfg, times, dv_rtn, roe0, distance, d_min, t_min)
