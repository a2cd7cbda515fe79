"""Adaptive separation program for a nanosatellite cluster from a tumbling platform (seed 004).

Frame and dynamics (seed 004 Sec. 2): orbital frame centred on the platform (orbital stage, OS), x along the flight
direction, y up, z completing the triad; linear relative motion on a circular orbit (the HCW solution of seed 003
Eq. 2 on these axes) plus the along-track differential drag acceleration P_x = rho V_s^2 dQ, dQ = Q_OS - Q_NS,
Q = c_d S / (2 m); P_x = (n a / 2) * :func:`~roe_sep.core.relmotion.dynamics.drag_da_dot` (:func:`drag_acceleration`).

Random direction (seed 004 ref. [5]): the OS turns with a transverse angular velocity of independent N(0, sigma^2)
components; after a delay dt the deployer axis is tilted by theta = Omega dt, Omega ~ Rayleigh(sigma), about an axis
of uniform azimuth psi: the separation velocity is V (cos theta, sin theta sin psi, -sin theta cos psi). Every NS on
the same OS shares Omega and psi.

Moments (closed form of the seed's quadratures): with C(tau) = E[cos(Omega tau)] (:func:`mean_cos`), the mean
and variance of the separation velocity (:func:`velocity_moments`) and the covariance of two NS
(:func:`velocity_covariance`); the coordinates' (Eqs. 1-2) by the HCW map (:func:`hcw_matrix`, :func:`drag_offset`).

'With probability P*' (Eqs. 3-5), two analytical methods (``ClusterConfig.method``):

* ``envelope`` (default, :mod:`~roe_sep.core.deployment.cluster_envelope`): every condition must hold for every
  tumbling state of the set {Omega <= Omega*, any psi}, whose probability is exactly P*; the minimax cost is the
  largest pair distance over that set. The conditions then hold jointly with P >= P* (no distribution approximation).
* ``gaussian`` (the seed's model): each coordinate Gaussian with the moments above. Safe from the OS (3): the
  Bonferroni box E +- k sigma, k = Phi^-1(1 - (1 - P*)/6), clear of the r* ball (:func:`box_bounds`), or
  :func:`deterministic_bound`. Safe from each other (4, lower part): the independence assumption (K = 0),
  :func:`near_probability`, or :func:`deterministic_pair_bound`. Within r** (4, upper part) and the minimax (5): the
  farthest corner of the P* box.

Statistical validation (seed 004 Sec. 4): :func:`simulate_program`, the same dynamics over sampled angular
velocities (only the probability model differs); the comparison is in docs/seeds.md.
"""

import dataclasses
import itertools
from dataclasses import dataclass, field
from os import PathLike

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import dawsn, ndtr, ndtri

from ...errors import ConfigError, show
from ..relmotion.orbit import mean_motion, semi_major_axis
from .cluster_dynamics import drag_acceleration, drag_offset, hcw_matrix, hcw_terms, singular_values
from .cluster_envelope import conditions, omega_bound

USSA76_DENSITY_220KM = 1.43e-10  # kg/m^3: US Standard Atmosphere 1976, log-interpolated 200 km / 250 km
METHODS = ("envelope", "gaussian")  # how 'with probability P*' is evaluated (module docstring)


@dataclass(frozen=True)
class Nanosatellite:
    """One NS: separation speed [m/s], dQ = Q_NS - Q_OS [m^2/kg] (seed convention Q = c_d S/(2m)), cluster member."""

    name: str
    velocity: float
    delta_q: float
    cluster: bool = True


def _soyuz_sats():
    # seed 004 Sec. 5: dQ_os-1..4 = -0.006, -0.007, -0.008, -0.004 m^2/kg (Q_OS - Q_NS); dV1..3 = 2 m/s, dV4 = 1 m/s
    return (Nanosatellite("ns1", 2.0, 0.006), Nanosatellite("ns2", 2.0, 0.007),
            Nanosatellite("ns3", 2.0, 0.008), Nanosatellite("ns4", 1.0, 0.004, cluster=False))


@dataclass(frozen=True)
class ClusterConfig:
    """The separation problem; defaults: the Soyuz orbital-stage example of seed 004 Sec. 5 (config/cluster.yaml).

    Values the seed does not state are assumptions, marked so: ``sigma``, ``r_safe``, ``altitude``/``density`` (the
    seed's Fig. 3 altitude, 220 km), ``departure_time``.
    """

    sats: tuple = field(default_factory=_soyuz_sats)
    altitude: float = 220e3  # m (seed 004 Fig. 3)
    density: float = USSA76_DENSITY_220KM  # kg/m^3
    sigma_deg_s: float = 0.3  # deg/s, 1-sigma of each transverse angular-velocity component (assumption)
    p_required: float = 0.997  # P*
    r_safe: float = 10.0  # m, r*: keep-out radius around the OS and between NS (assumption: stage size + margin)
    r_max: float = 10000.0  # m, r**: largest distance inside the cluster
    turns: float = 2.0  # orbits over which the conditions hold (seed: 'two turns')
    departure_time: float = 60.0  # s after its separation before the OS condition applies (the push phase)
    min_delay: float = 5.0  # s, earliest separation (deployer sequencing; the seed's lower bound)
    max_delay: float = 60.0  # s, latest delay searched
    delay_step: float = 1.0  # s, grid of the delays
    time_step: float = 20.0  # s, sampling of the analytical conditions and the simulation
    method: str = "envelope"  # 'envelope': every state of the P* tumbling set; 'gaussian': the seed's k-sigma model

    def validate(self) -> "ClusterConfig":
        """Raise ValueError naming the first bad field; ``self`` otherwise."""
        """Raise ValueError naming the first bad value."""
        if not self.sats:
            raise ValueError("sats: at least one nanosatellite is required")
        names = [s.name for s in self.sats]
        if len(set(names)) != len(names):
            raise ValueError(f"sats: names must be unique, got {names}")
        for s in self.sats:
            if not (np.isfinite(s.velocity) and 0 < s.velocity <= 100.0):
                raise ValueError(f"sats.{s.name}.velocity must be in (0, 100] m/s, got {s.velocity}")
            if not (np.isfinite(s.delta_q) and abs(s.delta_q) <= 1.0):
                raise ValueError(f"sats.{s.name}.delta_q must be finite and |delta_q| <= 1 [m^2/kg], got {s.delta_q}")
        if sum(s.cluster for s in self.sats) > 4:
            raise ValueError("sats: at most 4 cluster members (the minimax search is exhaustive)")
        checks = (
            ("altitude", 100e3 <= self.altitude <= 2000e3, "between 100 km and 2000 km [m]"),
            ("density", 0 <= self.density <= 1e-6, "in [0, 1e-6] kg/m^3"),
            ("sigma_deg_s", 0 < self.sigma_deg_s <= 90.0, "in (0, 90] deg/s"),
            ("p_required", 0.5 <= self.p_required < 1.0, "in [0.5, 1)"),
            ("r_safe", 0 < self.r_safe <= 1e6, "in (0, 1e6] m"),
            ("r_max", self.r_safe < self.r_max <= 1e7, "larger than r_safe and at most 1e7 [m]"),
            ("turns", 0 < self.turns <= 20, "in (0, 20]"),
            ("departure_time", 0 <= self.departure_time <= 86400.0, "in [0, 86400] s"),
            ("min_delay", 0 <= self.min_delay <= 3600.0, "in [0, 3600] s"),
            ("max_delay", self.min_delay < self.max_delay <= 3600.0, "larger than min_delay and at most 3600 [s]"),
            ("delay_step", self.delay_step > 0, "positive [s]"),
            ("time_step", 0 < self.time_step <= 120, "in (0, 120] s"),
        )
        for name, ok, what in checks:
            v = getattr(self, name)
            if not (np.isfinite(v) and ok):
                raise ValueError(f"{name} must be {what}, got {v}")
        if self.method not in METHODS:
            raise ValueError(f"method must be one of {list(METHODS)}, got {self.method!r}")
        if (self.max_delay - self.min_delay) / self.delay_step > 400:
            raise ValueError("delay grid too fine: (max_delay - min_delay) / delay_step must be <= 400")
        return self

    @property
    def a(self) -> float:
        """Semi-major axis [m] of the orbital stage's circular orbit."""
        return float(semi_major_axis(self.altitude))

    @property
    def n(self) -> float:
        """Mean motion [rad/s]."""
        return float(mean_motion(self.a))

    @property
    def sigma(self) -> float:
        """1-sigma of each transverse angular-velocity component [rad/s]."""
        return float(np.radians(self.sigma_deg_s))

    @property
    def omega_star(self) -> float:
        """Omega* [rad/s]: the tumbling rates of the P* set of :mod:`~roe_sep.core.deployment.cluster_envelope`."""
        return omega_bound(self.sigma, self.p_required)

    @property
    def horizon(self) -> float:
        """The time [s] over which the conditions hold: ``turns`` orbits."""
        return self.turns * 2.0 * np.pi / self.n

    @property
    def delays(self) -> np.ndarray:
        """The delay grid [s], ``min_delay`` to ``max_delay`` by ``delay_step``."""
        return np.arange(self.min_delay, self.max_delay + 0.5 * self.delay_step, self.delay_step)


def cluster_config_from_dict(data: dict | None) -> ClusterConfig:
    """Build a :class:`ClusterConfig` from a parsed YAML mapping; unknown keys and bad values are named."""
    from ..config import _coerce

    data = {} if data is None else data
    if not isinstance(data, dict):
        raise ConfigError(f"expected a mapping at the top level, got {type(data).__name__}")
    hints = {f.name: f.type for f in dataclasses.fields(ClusterConfig)}
    unknown = sorted(set(data) - set(hints))
    if unknown:
        raise ConfigError(f"unknown key(s) {unknown}; known keys: {sorted(hints)}")
    kw = {}
    for k, v in data.items():
        if k == "sats":
            if not isinstance(v, list) or not v:
                raise ConfigError("sats: expected a non-empty list of {name, velocity, delta_q, cluster}")
            sats = []
            for i, s in enumerate(v):
                if not isinstance(s, dict) or set(s) - {"name", "velocity", "delta_q", "cluster"} or \
                        not {"velocity", "delta_q"} <= set(s):
                    raise ConfigError(f"sats[{i}]: expected {{name, velocity, delta_q, cluster}}, got {show(s)}")
                sats.append(Nanosatellite(str(s.get("name", f"ns{i + 1}")), _coerce(f"sats[{i}].velocity",
                                          s["velocity"], float), _coerce(f"sats[{i}].delta_q", s["delta_q"], float),
                                          _coerce(f"sats[{i}].cluster", s.get("cluster", True), bool)))
            kw[k] = tuple(sats)
        else:
            kw[k] = _coerce(k, v, hints[k])
    cfg = ClusterConfig(**kw)
    try:
        return cfg.validate()
    except ValueError as exc:
        raise ConfigError(str(exc)) from exc


def load_cluster_config(path: str | PathLike | None = None) -> ClusterConfig:
    """Read a cluster YAML (config/cluster.yaml layout); ``None`` gives the embedded Soyuz-stage example."""
    if path is None:
        return ClusterConfig()
    from ..config import load_yaml_config

    return load_yaml_config(path, cluster_config_from_dict, "cluster configuration")


# ---------------------------------------------------------------- the probabilistic model


def mean_cos(sigma: float, tau: ArrayLike) -> np.ndarray:
    """C(tau) = E[cos(Omega tau)], Omega ~ Rayleigh(sigma): 1 - sqrt(2) s D(s/sqrt(2)), s = sigma tau.

    Closed form of the seed 004 quadrature Q(V_x) (E_Vx = V C(dt)); D is the Dawson function. ``sigma`` [rad/s],
    ``tau`` [s] (any shape).
    """
    s = sigma * np.asarray(tau, dtype=float)
    return 1.0 - np.sqrt(2.0) * s * dawsn(s / np.sqrt(2.0))


def velocity_moments(v: ArrayLike, dt: ArrayLike, sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """(E[V], Var[V]) ``(..., 3)`` of the separation velocity after delay ``dt`` [s] (seed 004 E_V*, Var_V*):
    E[Vx] = V C(dt), E[Vy] = E[Vz] = 0, Var[Vx] = V^2 ((1 + C(2 dt))/2 - C(dt)^2), Var[Vy] = Var[Vz] =
    V^2 (1 - C(2 dt))/4, with C(tau) = 1 - sqrt(2) s D(s / sqrt(2)), s = sigma tau, D the Dawson function.

    Parameters
    ----------
    v : array_like, shape (...)
        Separation speed [m/s].
    dt : array_like, shape (...)
        Delay [s].
    sigma : float
        1-sigma of each transverse angular-velocity component [rad/s].

    Returns
    -------
    (numpy.ndarray, numpy.ndarray), each shape (..., 3)
        Mean [m/s] and variance [m^2/s^2] of (x, y, z).
    """
    v = np.asarray(v, dtype=float)
    c1, c2 = mean_cos(sigma, dt), mean_cos(sigma, 2.0 * np.asarray(dt, dtype=float))
    mean = np.stack([v * c1, 0.0 * c1, 0.0 * c1], axis=-1)
    vy = v**2 * (1.0 - c2) / 4.0
    return mean, np.stack([v**2 * ((1.0 + c2) / 2.0 - c1**2), vy, vy], axis=-1)


def velocity_covariance(vi: ArrayLike, dti: ArrayLike, vj: ArrayLike, dtj: ArrayLike, sigma: float) -> np.ndarray:
    """Cov[V_i, V_j] ``(..., 3)`` (diagonal: x, y, z) of two NS separated from the same tumbling OS:
    Cov[Vx_i, Vx_j] = V_i V_j ((C(dt_i - dt_j) + C(dt_i + dt_j))/2 - C(dt_i) C(dt_j)),
    Cov[Vy_i, Vy_j] = Cov[Vz_i, Vz_j] = V_i V_j (C(dt_i - dt_j) - C(dt_i + dt_j))/4 (C of :func:`velocity_moments`).

    Parameters
    ----------
    vi, vj : array_like, shape (...)
        Separation speeds [m/s].
    dti, dtj : array_like, shape (...)
        Delays [s].
    sigma : float
        1-sigma of each transverse angular-velocity component [rad/s].

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        The covariance [m^2/s^2] of each component.
    """
    cm = mean_cos(sigma, np.asarray(dti) - np.asarray(dtj))
    cp = mean_cos(sigma, np.asarray(dti) + np.asarray(dtj))
    vv = np.asarray(vi, dtype=float) * np.asarray(vj, dtype=float)
    cx = vv * (0.5 * (cm + cp) - mean_cos(sigma, dti) * mean_cos(sigma, dtj))
    cy = vv * 0.25 * (cm - cp)
    return np.stack([cx, cy, cy], axis=-1)


def position_moments(t: ArrayLike, v: ArrayLike, dt: ArrayLike, p_x: ArrayLike, sigma: float,
                     *, n: float) -> tuple[np.ndarray, np.ndarray]:
    """E and Var ``(..., 3)`` of one NS's position w.r.t. the OS at time ``t`` [s] from the program start (Eqs. 1-2).

    The NS separates at ``dt`` with speed ``v`` and differential drag acceleration ``p_x``:
    E_x = m00 E_Vx + D_x, E_y = m10 E_Vx + D_y, E_z = 0; Var_x = m00^2 Var_Vx + m01^2 Var_Vy,
    Var_y = m10^2 Var_Vx + m11^2 Var_Vy, Var_z = m22^2 Var_Vz (the seed's Eq. 2 coefficients).

    Parameters
    ----------
    t : array_like, shape (..., T)
        Times [s from the program start].
    v : array_like, shape (...)
        Separation speed [m/s].
    dt : array_like, shape (...)
        Delay [s].
    p_x : array_like, shape (...)
        Drag acceleration [m/s^2].
    sigma : float
        1-sigma of each transverse angular-velocity component [rad/s].
    n : float
        Mean motion [rad/s].

    Returns
    -------
    (numpy.ndarray, numpy.ndarray), each shape (..., T, 3)
        Mean [m] and variance [m^2] of (x, y, z).
    """
    tau = np.asarray(t) - np.asarray(dt)[..., None]
    m00, m01, m10, m11, m22 = hcw_terms(tau, n)
    ev, var = velocity_moments(v, dt, sigma)
    ex, vx, vy, vz = (ev[..., 0][..., None], var[..., 0][..., None], var[..., 1][..., None], var[..., 2][..., None])
    dd = drag_offset(tau, n, np.asarray(p_x)[..., None])
    mean = np.stack([m00 * ex + dd[..., 0], m10 * ex + dd[..., 1], 0.0 * m22], axis=-1)
    return mean, np.stack([m00**2 * vx + m01**2 * vy, m10**2 * vx + m11**2 * vy, m22**2 * vz], axis=-1)


def pair_moments(t: ArrayLike, vi: ArrayLike, dti: ArrayLike, pi: ArrayLike, vj: ArrayLike, *, dtj: ArrayLike,
                 pj: ArrayLike, sigma: float, n: float) -> tuple[np.ndarray, np.ndarray]:
    """E and Var ``(..., 3)`` of r_i - r_j at times ``t`` (exact second moments, shared tumbling).

    Parameters
    ----------
    t : array_like, shape (T,)
        Times [s from the program start].
    vi, vj : array_like, shape (...)
        Separation speeds of NS i and j [m/s].
    dti, dtj : array_like, shape (...)
        Their delays [s from the program start].
    pi, pj : array_like, shape (...)
        Their drag accelerations [m/s^2] (:func:`~.cluster_dynamics.drag_acceleration`).
    sigma : float
        1-sigma of each transverse angular-velocity component [rad/s].
    n : float
        Mean motion [rad/s].

    Returns
    -------
    (numpy.ndarray, numpy.ndarray), each shape (..., T, 3)
        Mean [m] and variance [m^2] of (x, y, z).
    """
    ti = np.asarray(t) - np.asarray(dti)[..., None]
    tj = np.asarray(t) - np.asarray(dtj)[..., None]
    a = hcw_terms(ti, n)
    b = hcw_terms(tj, n)
    evi, vari = velocity_moments(vi, dti, sigma)
    evj, varj = velocity_moments(vj, dtj, sigma)
    cov = velocity_covariance(vi, dti, vj, dtj, sigma)
    ex_i, ex_j = evi[..., 0][..., None], evj[..., 0][..., None]
    vi_, vj_, c_ = (x[..., None, :] for x in (vari, varj, cov))
    dd = drag_offset(ti, n, np.asarray(pi)[..., None]) - drag_offset(tj, n, np.asarray(pj)[..., None])
    mean = np.stack([a[0] * ex_i - b[0] * ex_j + dd[..., 0], a[2] * ex_i - b[2] * ex_j + dd[..., 1],
                     0.0 * a[4]], axis=-1)

    def var(k_a, k_b, comp):
        return a[k_a] ** 2 * vi_[..., comp] + b[k_a] ** 2 * vj_[..., comp] - 2.0 * a[k_a] * b[k_a] * c_[..., comp]

    vx = var(0, 0, 0) + var(1, 1, 1)
    vy = var(2, 2, 0) + var(3, 3, 1)
    vz = var(4, 4, 2)
    return mean, np.maximum(np.stack([vx, vy, vz], axis=-1), 0.0)


def quantile_factor(p_required: float, dims: int = 3) -> float:
    """k with P(all ``dims`` Gaussian coordinates within E +- k sigma) >= P* by Bonferroni:
    k = Phi^-1(1 - (1 - P*) / (2 dims))."""
    return float(ndtri(1.0 - (1.0 - p_required) / (2.0 * dims)))


def box_bounds(mean: ArrayLike, var: ArrayLike, k: float) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper) bounds of the distance that hold with probability >= P* (the k-sigma box, Eqs. 3-5).

    Parameters
    ----------
    mean, var : array_like, shape (..., 3)
        Mean [m] and variance [m^2] of the coordinates.
    k : float
        The box half-size in standard deviations (:func:`quantile_factor`).

    Returns
    -------
    (lower, upper) : numpy.ndarray, each shape (...)
        Distance bounds [m].
    """
    sd = np.sqrt(var)
    am = np.abs(mean)
    lower = np.sqrt(np.sum(np.maximum(am - k * sd, 0.0) ** 2, axis=-1))
    upper = np.sqrt(np.sum((am + k * sd) ** 2, axis=-1))
    return lower, upper


def near_probability(mean: ArrayLike, var: ArrayLike, r: float) -> np.ndarray:
    """P(|r| < r) upper estimate under the Gaussian model with independent coordinates (the seed's K = 0).

    The sphere lies inside the cube |x|, |y|, |z| < r, whose probability for independent coordinates is the product
    of Phi((r - E)/sd) - Phi((-r - E)/sd) (a zero-variance coordinate contributes 1 if |E| < r, else 0).

    Parameters
    ----------
    mean, var : array_like, shape (..., 3)
        Mean [m] and variance [m^2] of the coordinates.
    r : float
        The radius [m].

    Returns
    -------
    numpy.ndarray, shape (...)
        The probability estimate.
    """
    sd = np.sqrt(var)
    with np.errstate(invalid="ignore", divide="ignore"):
        p = ndtr((r - mean) / sd) - ndtr((-r - mean) / sd)
    p = np.where(sd > 0.0, p, (np.abs(mean) < r).astype(float))
    return np.prod(p, axis=-1)


def deterministic_bound(tau: ArrayLike, v: ArrayLike, p_x: ArrayLike, n: float) -> np.ndarray:
    """|r(tau)| >= s_min(M(tau)) V - |D(tau)| for every separation direction (fixed speed V).

    Parameters
    ----------
    tau : array_like, shape (T,)
        Times since the separation [s].
    v : array_like, shape (...)
        Separation speed [m/s].
    p_x : array_like, shape (...)
        Drag acceleration [m/s^2].
    n : float
        Mean motion [rad/s].

    Returns
    -------
    numpy.ndarray, shape (..., T)
        The lower bound of the distance [m].
    """
    smin, _ = singular_values(hcw_matrix(tau, n))
    return smin * np.asarray(v)[..., None] - np.linalg.norm(drag_offset(tau, n, np.asarray(p_x)[..., None]), axis=-1)


def deterministic_pair_bound(t: ArrayLike, vi: ArrayLike, dti: ArrayLike, pi: ArrayLike, vj: ArrayLike,
                             *, dtj: ArrayLike, pj: ArrayLike, n: float) -> np.ndarray:
    """|r_i - r_j| >= s_min(M_a) V_a - s_max(M_b) V_b - |D_i - D_j| for all directions, a = earlier separation.

    |M_a V_a e_a - M_b V_b e_b| >= s_min(M_a) V_a - s_max(M_b) V_b for unit e_a, e_b; in the straight-line phase
    right after the later separation (M ~ tau I) it is V delta: the earlier NS leads by its head start.

    Parameters
    ----------
    t, vi, dti, pi, vj, dtj, pj
        As for :func:`pair_moments`.
    n : float
        Mean motion [rad/s].

    Returns
    -------
    numpy.ndarray, shape (..., T)
        The lower bound of the pair distance [m].
    """
    ti = np.asarray(t) - np.asarray(dti)[..., None]
    tj = np.asarray(t) - np.asarray(dtj)[..., None]
    si_lo, si_hi = singular_values(hcw_terms(ti, n))
    sj_lo, sj_hi = singular_values(hcw_terms(tj, n))
    vi, vj = np.asarray(vi, dtype=float)[..., None], np.asarray(vj, dtype=float)[..., None]
    first_i = (np.asarray(dti) <= np.asarray(dtj))[..., None]
    bound = np.where(first_i, si_lo * vi - sj_hi * vj, sj_lo * vj - si_hi * vi)
    dd = drag_offset(ti, n, np.asarray(pi)[..., None]) - drag_offset(tj, n, np.asarray(pj)[..., None])
    return bound - np.linalg.norm(dd, axis=-1)


# ---------------------------------------------------------------- feasible regions and the minimax program


def _time_grid(cfg, start, length):
    return start + np.arange(0.0, length + 0.5 * cfg.time_step, cfg.time_step)


def platform_safe(cfg: ClusterConfig, sat: Nanosatellite, delays: ArrayLike | None = None) -> np.ndarray:
    """Analytical condition (3) for each delay: r_i(t) >= r* with P* at every t in [dt + t_dep, dt + horizon].

    Parameters
    ----------
    cfg : ClusterConfig
        The problem (orbit, density, r*, P*, method).
    sat : Nanosatellite
        The NS.
    delays : array_like, shape (D,), optional
        Delays [s]; default the configured grid.

    Returns
    -------
    numpy.ndarray, shape (D,)
        True where the delay is safe from the OS.
    """
    delays = cfg.delays if delays is None else np.asarray(delays, dtype=float)
    n = cfg.n
    p_x = drag_acceleration(-sat.delta_q, cfg.density, cfg.a)
    tau = _time_grid(cfg, cfg.departure_time, cfg.horizon - cfg.departure_time)
    if cfg.method == "envelope":
        zero = np.zeros_like(delays)
        return conditions(sat.velocity, delays, p_x, zero, delays, pj=zero, t=delays[:, None] + tau, n=n,
                          omega_star=cfg.omega_star,
                          r_min=cfg.r_safe)[0]
    mean, var = position_moments(delays[:, None] + tau, sat.velocity, delays, p_x, cfg.sigma, n=n)
    lower, _ = box_bounds(mean, var, quantile_factor(cfg.p_required))
    det = deterministic_bound(tau, sat.velocity, p_x, n)
    return np.all((lower >= cfg.r_safe) | (det >= cfg.r_safe), axis=-1)


def _pair_conditions(cfg, si, di, sj, dj, *, within=True):
    """(safe, within r**, largest distance bound) of NS ``si`` at delays ``di`` against ``sj`` at ``dj`` (arrays of
    one shape), every t from the later separation to the later separation + horizon, with P* (Eqs. 4-5)."""
    n = cfg.n
    t = np.maximum(di, dj)[..., None] + _time_grid(cfg, 0.0, cfg.horizon)
    pi = drag_acceleration(-si.delta_q, cfg.density, cfg.a)
    pj = drag_acceleration(-sj.delta_q, cfg.density, cfg.a)
    distinct = di != dj
    if cfg.method == "envelope":
        shape = di.shape
        clear, inside, upper = conditions(si.velocity, di.ravel(), pi, sj.velocity, dj.ravel(), pj=pj,
                                          t=t.reshape(di.size, -1), n=n, omega_star=cfg.omega_star, r_min=cfg.r_safe,
                                          r_max=cfg.r_max if within else None)
        if not within:
            return clear.reshape(shape) & distinct, None, None
        return clear.reshape(shape) & distinct, inside.reshape(shape) & distinct, upper.reshape(shape)
    mean, var = pair_moments(t, si.velocity, di, pi, sj.velocity, dtj=dj, pj=pj, sigma=cfg.sigma, n=n)
    _, upper = box_bounds(mean, var, quantile_factor(cfg.p_required))
    near = near_probability(mean, var, cfg.r_safe)
    det = deterministic_pair_bound(t, si.velocity, di, pi, sj.velocity, dtj=dj, pj=pj, n=n)
    safe = np.all((near <= 1.0 - cfg.p_required) | (det >= cfg.r_safe), axis=-1) & distinct
    return safe, np.all(upper <= cfg.r_max, axis=-1) & distinct, np.max(upper, axis=-1)


def pair_tables(cfg: ClusterConfig, si: Nanosatellite, sj: Nanosatellite,
                delays: ArrayLike | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Over the delay grid (dt_i, dt_j): (safe, within r**, max distance bound) of the pair, Eqs. (4)-(5).

    Parameters
    ----------
    cfg : ClusterConfig
        The problem.
    si, sj : Nanosatellite
        The pair.
    delays : array_like, shape (D,), optional
        Delays [s]; default the configured grid.

    Returns
    -------
    (safe, within, upper), each shape (D, D)
        Booleans over (dt_i, dt_j) and the largest distance bound [m].
    """
    d = cfg.delays if delays is None else np.asarray(delays, dtype=float)
    di, dj = np.meshgrid(d, d, indexing="ij")
    return _pair_conditions(cfg, si, di, sj, dj)


def pair_distance_bound(cfg: ClusterConfig, si: Nanosatellite, dt_i: float, sj: Nanosatellite, dt_j: float,
                        *, t: ArrayLike) -> np.ndarray:
    """P* upper bound [m] of |r_i - r_j| at each time of ``t`` ``(T,)`` by ``cfg.method`` (the minimax quantity).

    Parameters
    ----------
    cfg : ClusterConfig
        The problem.
    si, sj : Nanosatellite
        The pair.
    dt_i, dt_j : float
        Their delays [s].
    t : array_like, shape (T,)
        Times [s from the program start].

    Returns
    -------
    numpy.ndarray, shape (T,)
        The bound [m].
    """
    t = np.asarray(t, dtype=float)
    pi = drag_acceleration(-si.delta_q, cfg.density, cfg.a)
    pj = drag_acceleration(-sj.delta_q, cfg.density, cfg.a)
    if cfg.method == "envelope":
        return conditions(si.velocity, dt_i, pi, sj.velocity, dt_j, pj=pj, t=t[:, None], n=cfg.n,
                          omega_star=cfg.omega_star,
                          r_min=cfg.r_safe, r_max=cfg.r_max)[2]
    mean, var = pair_moments(t, si.velocity, np.asarray(dt_i, dtype=float), pi, sj.velocity,
                             dtj=np.asarray(dt_j, dtype=float), pj=pj, sigma=cfg.sigma, n=cfg.n)
    return box_bounds(mean, var, quantile_factor(cfg.p_required))[1]


def pair_safe_row(cfg: ClusterConfig, s_new: Nanosatellite, candidates: ArrayLike, s_old: Nanosatellite,
                  dt_old: float) -> np.ndarray:
    """Condition (4), lower part, for NS ``s_new`` at each candidate delay against ``s_old`` at ``dt_old``.

    Parameters
    ----------
    cfg : ClusterConfig
        The problem.
    s_new : Nanosatellite
        The NS to place.
    candidates : array_like, shape (D,)
        Its candidate delays [s].
    s_old : Nanosatellite
        An NS already placed.
    dt_old : float
        Its delay [s].

    Returns
    -------
    numpy.ndarray, shape (D,)
        True where the pair is safe.
    """
    c = np.asarray(candidates, dtype=float)
    return _pair_conditions(cfg, s_new, c, s_old, np.full_like(c, float(dt_old)), within=False)[0]


@dataclass
class ClusterProgram:
    """The selected program and the feasible regions (analytical)."""

    config: ClusterConfig
    delays: np.ndarray  # s per NS (config order); NaN if none feasible
    platform_delay_max: np.ndarray  # s per NS, largest safe delay of the contiguous region from min_delay
    platform_safe: np.ndarray  # (n_sats, n_grid) bool
    pair_regions: dict  # (i, j) -> dict(min_dd, max_dd) at dt_i = first delay of the program
    max_pair_distance: float  # m, the minimax value (P*-upper bound)
    feasible: bool


def _contiguous_max(delays, ok):
    """Largest delay of the run of True values that starts at the first grid point (NaN if the first is unsafe)."""
    if not ok[0]:
        return float("nan")
    bad = np.flatnonzero(~ok)
    return float(delays[-1] if bad.size == 0 else delays[bad[0] - 1])


def select_program(cfg: ClusterConfig | None = None) -> ClusterProgram:
    """Feasible regions of the delays and the minimax selection (seed 004 Eq. 5), exhaustive over the delay grid.

    Cluster members: delays on the grid, each safe from the OS (3), every pair safe and within r** (4); among those,
    the delays minimizing the largest P*-upper bound of any pair distance over the horizon (5), ties to the
    earliest program. Each other NS separates at the first free grid slot after the cluster where it is safe from
    the OS (seed 004 Sec. 5: 'only the separation condition ... in relation to the OS').
    """
    cfg = (cfg or ClusterConfig()).validate()
    d = cfg.delays
    sats = cfg.sats
    safe_os = np.stack([platform_safe(cfg, s, d) for s in sats])
    dmax = np.array([_contiguous_max(d, ok) for ok in safe_os])
    members = [i for i, s in enumerate(sats) if s.cluster]
    m = len(members)
    feasible = np.ones((len(d),) * m, dtype=bool)
    worst = np.zeros((len(d),) * m)
    tables = {}
    for a_, i in enumerate(members):
        shape = [1] * m
        shape[a_] = len(d)
        feasible &= safe_os[i].reshape(shape)
    for (a_, i), (b_, j) in itertools.combinations(enumerate(members), 2):
        safe, within, umax = pair_tables(cfg, sats[i], sats[j], d)
        tables[(i, j)] = (safe, within)
        shape = [1] * m
        shape[a_], shape[b_] = len(d), len(d)
        feasible &= (safe & within).reshape(shape)
        worst = np.maximum(worst, umax.reshape(shape))
    delays = np.full(len(sats), np.nan)
    value, ok = float("nan"), bool(m == 0 or np.any(feasible))
    last = cfg.min_delay - cfg.delay_step
    if m and ok:
        cost = np.where(feasible, worst, np.inf)
        flat = np.flatnonzero(cost == np.min(cost))
        grids = np.stack(np.unravel_index(flat, cost.shape), axis=-1)
        best = grids[np.argmin(np.max(grids, axis=-1) * len(d) + np.sum(grids, axis=-1))]
        value = float(np.min(cost))
        for a_, i in enumerate(members):
            delays[i] = d[best[a_]]
        last = float(np.nanmax(delays))
    if m == 1:
        value = 0.0
    for i, s in enumerate(sats):
        if not s.cluster:
            ok_slot = (d > last) & safe_os[i]
            for j in np.flatnonzero(np.isfinite(delays)):  # also safe from every NS already scheduled
                ok_slot &= pair_safe_row(cfg, s, d, sats[j], delays[j])
            slots = np.flatnonzero(ok_slot)
            if slots.size:
                delays[i] = d[slots[0]]
                last = delays[i]
            else:
                ok = False
    regions = {}
    for (i, j), (safe, within) in tables.items():
        # anchored at the earlier NS of the pair in the program (at min_delay when there is none)
        first_i = not (np.isfinite(delays[j]) and np.isfinite(delays[i]) and delays[j] < delays[i])
        anchor = delays[i] if first_i else delays[j]
        i0 = int(np.argmin(np.abs(d - (anchor if np.isfinite(anchor) else d[0]))))
        dd = d - d[i0]
        row_s, row_w = (safe[i0], within[i0]) if first_i else (safe[:, i0], within[:, i0])
        s_ok, w_ok = row_s & (dd > 0), row_w & (dd > 0)
        regions[(i, j)] = {
            "min_delay_difference_s": float(dd[s_ok][0]) if np.any(s_ok) else None,
            "max_delay_difference_s": float(dd[w_ok][-1]) if np.any(w_ok) else None,
            "at_delay_s": float(d[i0]), "first": sats[i if first_i else j].name,
        }
    return ClusterProgram(cfg, delays, dmax, safe_os, regions, value, ok)


# ---------------------------------------------------------------- statistical validation


@dataclass
class Draws:
    """Tumbling of the OS: Omega ~ Rayleigh(sigma) [rad/s] and the axis azimuth psi [rad], arrays over samples."""

    omega: np.ndarray
    psi: np.ndarray


def draw(cfg: ClusterConfig, samples: int, seed: int | None = 0) -> Draws:
    """The two transverse angular-velocity components, independent N(0, sigma^2).

    Parameters
    ----------
    cfg : ClusterConfig
        sigma.
    samples : int
        How many.
    seed : int or None
        The generator's seed.

    Returns
    -------
    Draws
        Tumbling rates Omega [rad/s] and axis azimuths psi [rad], each ``(samples,)``.
    """
    rng = np.random.default_rng(seed)
    w = rng.normal(0.0, cfg.sigma, size=(2, int(samples)))
    return Draws(np.hypot(w[0], w[1]), np.arctan2(w[1], w[0]))


def separation_velocity(draws: Draws, v: float, dt: float) -> np.ndarray:
    """V (cos theta, sin theta sin psi, -sin theta cos psi), theta = Omega dt.

    Parameters
    ----------
    draws : Draws
        The tumbling samples.
    v : float
        Separation speed [m/s].
    dt : float
        Delay [s].

    Returns
    -------
    numpy.ndarray, shape (samples, 3)
        The separation velocity [m/s] (x along-track, y radial, z normal).
    """
    th = draws.omega * dt
    return v * np.stack([np.cos(th), np.sin(th) * np.sin(draws.psi), -np.sin(th) * np.cos(draws.psi)], axis=-1)


def simulated_positions(cfg: ClusterConfig, draws: Draws, sat: Nanosatellite, dt: float, t: ArrayLike) -> np.ndarray:
    """Positions of NS ``sat`` separated at ``dt`` w.r.t. the OS at times ``t``.

    Parameters
    ----------
    cfg : ClusterConfig
        The problem.
    draws : Draws
        The tumbling samples.
    sat : Nanosatellite
        The NS.
    dt : float
        Its delay [s].
    t : array_like, shape (T,)
        Times [s from the program start].

    Returns
    -------
    numpy.ndarray, shape (samples, T, 3)
        Positions [m].
    """
    v = separation_velocity(draws, sat.velocity, dt)
    tau = np.asarray(t, dtype=float) - dt
    p_x = drag_acceleration(-sat.delta_q, cfg.density, cfg.a)
    return np.einsum("tij,sj->sti", hcw_matrix(tau, cfg.n), v) + drag_offset(tau, cfg.n, p_x)


def _min_distance(r):
    """Smallest |r| over the last-but-one axis, refined by a parabola in |r|^2 around the smallest sample."""
    d2 = np.sum(r * r, axis=-1)
    i = np.clip(np.argmin(d2, axis=-1), 1, d2.shape[-1] - 2)[..., None]
    y0, y1, y2 = (np.take_along_axis(d2, i + k, axis=-1)[..., 0] for k in (-1, 0, 1))
    den = y0 - 2.0 * y1 + y2
    with np.errstate(invalid="ignore", divide="ignore"):
        off = np.clip(np.where(den > 0.0, 0.5 * (y0 - y2) / den, 0.0), -1.0, 1.0)
    return np.sqrt(np.maximum(np.minimum(y1 - 0.25 * (y0 - y2) * off, np.min(d2, axis=-1)), 0.0))


def simulated_platform_safety(cfg: ClusterConfig, draws: Draws, sat: Nanosatellite, delays: ArrayLike) -> np.ndarray:
    """Statistical condition (3): fraction of samples with |r_i(t)| >= r* over the whole window, per delay.

    Parameters
    ----------
    cfg : ClusterConfig
        The problem.
    draws : Draws
        The tumbling samples.
    sat : Nanosatellite
        The NS.
    delays : array_like, shape (D,)
        Delays [s].

    Returns
    -------
    numpy.ndarray, shape (D,)
        The fraction of safe samples per delay.
    """
    tau = _time_grid(cfg, cfg.departure_time, cfg.horizon - cfg.departure_time)
    out = np.empty(len(delays))
    for k, dt in enumerate(np.asarray(delays, dtype=float)):  # loop over cases; samples are vectorized
        r = simulated_positions(cfg, draws, sat, dt, dt + tau)
        out[k] = np.mean(_min_distance(r) >= cfg.r_safe)
    return out


def simulate_program(cfg: ClusterConfig, delays: ArrayLike, draws: Draws) -> dict:
    """Statistical check of a program: per-sample outcomes of every condition, vectorized over samples.

    Returns dict with ``p_safe`` (all conditions at once), ``p_platform`` per NS, ``p_pairs`` (safe, within r**)
    per pair, and ``max_pair_distance_quantile`` (the P* quantile of the largest cluster pair distance).

    Parameters
    ----------
    cfg : ClusterConfig
        The problem.
    delays : array_like, shape (n_sats,)
        The program's delay of each NS [s], finite.
    draws : Draws
        The tumbling samples.

    Returns
    -------
    dict
        The probabilities and the distance quantile [m].
    """
    sats, d = cfg.sats, np.asarray(delays, dtype=float)
    if not np.all(np.isfinite(d)) or len(d) != len(sats):
        raise ValueError(f"simulate_program needs one finite delay per nanosatellite, got {d.tolist()}")
    t0, tend = float(np.min(d)), float(np.max(d)) + cfg.horizon
    t = np.arange(t0, tend + cfg.time_step, cfg.time_step)
    pos = [simulated_positions(cfg, draws, s, dt, t) for s, dt in zip(sats, d)]
    ok_all = np.ones(draws.omega.shape, dtype=bool)
    p_platform = []
    for s, dt, r in zip(sats, d, pos):
        w = (t >= dt + cfg.departure_time) & (t <= dt + cfg.horizon)
        ok = _min_distance(r[:, w]) >= cfg.r_safe
        p_platform.append(float(np.mean(ok)))
        ok_all &= ok
    p_pairs, worst = {}, np.zeros(draws.omega.shape)
    for i, j in itertools.combinations(range(len(sats)), 2):
        start = max(d[i], d[j])
        w = (t >= start) & (t <= start + cfg.horizon)
        rel = pos[i][:, w] - pos[j][:, w]
        safe = _min_distance(rel) >= cfg.r_safe
        ok_all &= safe
        entry = {"p_safe": float(np.mean(safe))}
        if sats[i].cluster and sats[j].cluster:
            dist_max = np.max(np.linalg.norm(rel, axis=-1), axis=-1)
            within = dist_max <= cfg.r_max
            ok_all &= within
            worst = np.maximum(worst, dist_max)
            entry["p_within"] = float(np.mean(within))
        p_pairs[(i, j)] = entry
    return {"p_safe": float(np.mean(ok_all)), "p_platform": p_platform, "p_pairs": p_pairs,
            "max_pair_distance_quantile": float(np.quantile(worst, cfg.p_required))}


def statistical_min_delay_difference(cfg: ClusterConfig, draws: Draws, si: Nanosatellite, sj: Nanosatellite,
                                     dt_i: float, *, differences: ArrayLike) -> float | None:
    """Smallest delay difference dt_j - dt_i (from ``differences``) with P(r_ij >= r* throughout) >= P*.

    Parameters
    ----------
    cfg : ClusterConfig
        The problem.
    draws : Draws
        The tumbling samples.
    si, sj : Nanosatellite
        The pair.
    dt_i : float
        The delay of NS i [s].
    differences : array_like
        Candidate differences [s], tried in order.

    Returns
    -------
    float or None
        The first difference [s] that meets P*, None if none does.
    """
    t_len = cfg.horizon
    for dd in np.asarray(differences, dtype=float):  # loop over cases; samples are vectorized
        dt_j = dt_i + dd
        t = dt_j + _time_grid(cfg, 0.0, t_len)
        rel = simulated_positions(cfg, draws, si, dt_i, t) - simulated_positions(cfg, draws, sj, dt_j, t)
        if np.mean(_min_distance(rel) >= cfg.r_safe) >= cfg.p_required:
            return float(dd)
    return None
