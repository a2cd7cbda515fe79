"""Nonlinear truth: carrier and picosatellite as two point masses in an inertial frame, integrated numerically.

Force model (per spacecraft, inertial equator-and-equinox-of-date frame of :mod:`roe_sep.core.od.radar`):

* Zonal geopotential to degree 2, 3 or 4 (EGM96 J2..J4): U = mu/r [1 - sum_n J_n (R_E/r)^n P_n(z/r)] (Vallado,
  *Fundamentals of Astrodynamics and Applications*, 4th ed., Eq. 8-19, m = 0); grad U differentiated by heyoka.
* Atmospheric drag a = -1/2 B rho(h) |v_r| v_r (Vallado Eq. 8-28), B = c_d A / m per spacecraft, v_r = v -
  omega_E x r relative to an atmosphere co-rotating with the Earth, h = |r| - R_E (spherical altitude). Density: an
  explicit choice of two models (:func:`truth_atmosphere`, ``ATMOSPHERES``):

  * ``normalised`` (default, the seeds' assumption): the exponential model rho = rho_ref exp(-(h - h_ref) / H)
    with the scale height H of Vallado's Table 8-4 for the orbit's band, normalised (:meth:`Atmosphere.normalised`)
    so that the *orbit-mean* drag <rho(h) |v_r| (v_r . v)> equals the stated density times v^2 = mu / a (seed 002
    Eqs. 23-24). Referenced at the mean altitude a - R_E instead (:meth:`Atmosphere.scaled`), the
    truth's drag is below Eq. (24) (the flattening and J2 raise the mean spherical altitude; docs/seeds.md).
  * ``msis``: NRLMSIS 2.0 (Emmert et al., Earth and Space Science 2021) through ``pymsis`` (F10.7, its 81-day mean
    and Ap are parameters, never looked up). heyoka needs the density as an expression, so :class:`MsisAtmosphere` fits
    ln rho by least squares over the band the pair flies through (the nominal orbit over the propagation span, +-20 km
    radially) in the basis :func:`msis_basis`: polynomials of the direction in a frame turning with the Sun (the diurnal
    bulge, latitude and season) times a quadratic in altitude. The fit's RMS error in ln rho is reported.

Integrator: heyoka's adaptive Taylor method (Biscani & Izzo, MNRAS 2021), JIT-compiled with LLVM. Both spacecraft
form one 12-dimensional system so that they share every step: integration error is then common-mode and largely
cancels in the relative state. The compiled integrator is cached (:func:`pair_integrator`); batch mode (SIMD lanes)
and a thread pool run the Monte Carlo (:func:`propagate_pairs`) and the sweeps (:func:`propagate_pairs_grid`).

State ``(..., 12)``: chief (carrier) position [m], velocity [m/s], then deputy (picosatellite). Parameters:
``[B_chief, B_deputy, *atmosphere.pars()]``: exponential ``[rho_ref, h_ref, H]`` (kg/m^3, m, m), msis
``[alpha_0, h_0, c_1 .. c_46]`` (rad, m, fit coefficients).
"""

import copy
import functools
import math
import os
from collections.abc import Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ...errors import show
from ..constants import EARTH_ROTATION, J2, J3, J4, MU_EARTH, R_EARTH, SECONDS_PER_DAY
from ..frames import gcrs_to_itrs
from ..od.radar import (
    DEFAULT_EPOCH_UTC,
    WGS84_E2,
    julian_date,
    rtn_matrix,
    sun_right_ascension,
)
from ..relmotion.dynamics import propagate_chief
from ..relmotion.roe import kepler_to_roe
from .mean_osc import cartesian_to_mean, mean_to_cartesian

if TYPE_CHECKING:  # heyoka is imported where it is used (it loads LLVM)
    import heyoka as hy

ZONALS = {2: (J2,), 3: (J2, J3), 4: (J2, J3, J4)}

VALLADO_EXPONENTIAL = (
    # h0 [km], rho0 [kg/m^3], H [km]: Vallado (2013) Table 8-4, exponential atmosphere (CIRA-72 based), LEO rows
    (200.0, 2.789e-10, 37.105),
    (250.0, 7.248e-11, 45.546),
    (300.0, 2.418e-11, 53.628),
    (350.0, 9.518e-12, 53.298),
    (400.0, 3.725e-12, 58.515),
    (450.0, 1.585e-12, 60.828),
    (500.0, 6.967e-13, 63.822),
    (600.0, 1.454e-13, 71.835),
    (700.0, 3.614e-14, 88.667),
    (800.0, 1.170e-14, 124.64),
    (900.0, 5.245e-15, 181.05),
    (1000.0, 3.019e-15, 268.00),
)


def vallado_band(h: float) -> tuple[float, float, float]:
    """Row ``(h0 [m], rho0 [kg/m^3], H [m])`` of Vallado Table 8-4 whose band [h0, next h0) contains ``h`` [m]."""
    h_km = float(h) / 1e3
    if not VALLADO_EXPONENTIAL[0][0] <= h_km < 1100.0:
        raise ValueError(f"altitude {h_km:.1f} km outside the tabulated 200-1100 km")
    row = [r for r in VALLADO_EXPONENTIAL if r[0] <= h_km][-1]
    return row[0] * 1e3, row[1], row[2] * 1e3


def vallado_density(h: ArrayLike) -> np.ndarray:
    """Vallado Table 8-4 density [kg/m^3] at altitude ``h`` [m]: rho = rho0 exp(-(h - h0)/H) (Vallado Eq. 8-33)."""
    h0, rho0, big_h = vallado_band(h)
    return rho0 * np.exp(-(float(h) - h0) / big_h)


@dataclass(frozen=True)
class Atmosphere:
    """Exponential density rho(h) = rho_ref exp(-(h - h_ref)/H) [kg/m^3], h the spherical altitude [m]."""

    rho_ref: float
    h_ref: float
    scale_height: float
    kind = "exponential"

    @classmethod
    def vallado(cls, h_ref: float) -> "Atmosphere":
        """Vallado Table 8-4 unscaled, referenced at ``h_ref`` [m]."""
        return cls(float(vallado_density(h_ref)), float(h_ref), vallado_band(h_ref)[2])

    @classmethod
    def scaled(cls, rho_ref: float, h_ref: float) -> "Atmosphere":
        """Vallado's scale height for the band of ``h_ref``, scaled so that rho(h_ref) = ``rho_ref`` (the seeds'
        1 g/km^3 at 515 km: Vallado's 0.551 g/km^3 times 1.82)."""
        return cls(float(rho_ref), float(h_ref), vallado_band(h_ref)[2])

    @classmethod
    def normalised(cls, rho_mean: float, chief_mean: ArrayLike) -> "Atmosphere":
        """The ``normalised`` truth atmosphere: Vallado's scale height at the mean altitude a - R_E of
        ``chief_mean`` (mean ``[a, e, i, raan, argp, M]``), scaled so that the orbit-mean drag of that orbit equals
        that of the constant density ``rho_mean`` [kg/m^3] (:func:`effective_density`), as seed 002 Eq. (24)
        assumes."""
        base = cls.scaled(1.0, float(chief_mean[0]) - R_EARTH)
        return cls(float(rho_mean) / effective_density(base, chief_mean), base.h_ref, base.scale_height)

    def density(self, h: ArrayLike) -> np.ndarray:
        """rho(h) [kg/m^3] at spherical altitudes ``h`` [m] (any shape)."""
        return self.rho_ref * np.exp(-(np.asarray(h, dtype=float) - self.h_ref) / self.scale_height)

    def density_at(self, pos: ArrayLike, t: ArrayLike = 0.0) -> np.ndarray:
        """rho [kg/m^3] ``(...)`` at inertial positions ``pos`` ``(..., 3)`` [m] (time-independent: ``t`` unused)."""
        return self.density(np.linalg.norm(np.asarray(pos, dtype=float), axis=-1) - R_EARTH)

    def pars(self) -> list[float]:
        """The integrator's density parameters: rho_ref [kg/m^3], h_ref [m], H [m]."""
        return [self.rho_ref, self.h_ref, self.scale_height]

    def describe(self) -> dict:
        """The model and its parameters (SI), for reports."""
        return {"model": self.kind, "rho_ref": self.rho_ref, "h_ref": self.h_ref, "scale_height": self.scale_height}


SUN_RATE = 2.0 * np.pi / (365.2422 * SECONDS_PER_DAY)
"""Mean rate of the Sun's right ascension [rad/s] (one tropical year)."""

MSIS_SCALE = 50e3
"""m, altitude normalisation of :func:`msis_basis`."""

MSIS_SPAN = 20e3
"""m, radial half-width of the band the NRLMSIS fit covers around the nominal orbit."""


def _monomials(x, y, z, degree):
    out = []
    for d in range(degree + 1):
        for i in range(d, -1, -1):
            for j in range(d - i, -1, -1):
                term = 1.0
                for base, k in ((x, i), (y, j), (z, d - i - j)):
                    for _ in range(k):
                        term = term * base
                out.append(term)
    return out


def msis_basis(x: "np.ndarray | hy.expression", y: "np.ndarray | hy.expression", z: "np.ndarray | hy.expression",
               dh: "np.ndarray | hy.expression") -> list:
    """The 46 basis functions of the NRLMSIS fit: monomials X^i Y^j Z^k of degree <= 4 of the unit position
    vector in the frame (X towards the Sun's right ascension, Z the Earth's axis) (35), ``dh`` times those of
    degree <= 2 (10) and dh^2, with dh = (|r| - R_E - h_0) / ``MSIS_SCALE``. Products and sums only, so the same
    code builds numpy arrays and heyoka expressions.

    Parameters
    ----------
    x, y, z : numpy.ndarray or heyoka.expression
        The unit position vector's components in the Sun-fixed frame.
    dh : numpy.ndarray or heyoka.expression
        The scaled altitude offset (|r| - R_E - h_0) / ``MSIS_SCALE``.

    Returns
    -------
    list
        The 46 basis functions, of the inputs' kind.
    """
    terms = _monomials(x, y, z, 4)
    terms += [dh * m for m in _monomials(x, y, z, 2)]
    return terms + [dh * dh]


N_MSIS_BASIS = 46


def _sun_frame(pos_x, pos_y, pos_z, r, alpha, *, cos=np.cos, sin=np.sin):
    ca, sa = cos(alpha), sin(alpha)
    return (pos_x * ca + pos_y * sa) / r, (pos_y * ca - pos_x * sa) / r, pos_z / r


def ecef_to_geodetic(r_ef: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """WGS-84 geodetic latitude [rad], longitude [rad] and ellipsoidal height [m] of Earth-fixed positions
    ``(..., 3)`` (fixed-point iteration on the latitude, converged to < 1e-12 rad in 6 steps in LEO)."""
    x, y, z = (np.asarray(r_ef, dtype=float)[..., k] for k in range(3))
    p = np.hypot(x, y)
    lat = np.arctan2(z, p * (1.0 - WGS84_E2))
    for _ in range(6):
        big_n = R_EARTH / np.sqrt(1.0 - WGS84_E2 * np.sin(lat) ** 2)
        h = p / np.cos(lat) - big_n
        lat = np.arctan2(z, p * (1.0 - WGS84_E2 * big_n / (big_n + h)))
    big_n = R_EARTH / np.sqrt(1.0 - WGS84_E2 * np.sin(lat) ** 2)
    return lat, np.arctan2(y, x), p / np.cos(lat) - big_n


def nrlmsis_density(pos: ArrayLike, t: ArrayLike, epoch_utc: str = DEFAULT_EPOCH_UTC, f107: float = 140.0,
                    f107a: float = 140.0, *, ap: float = 15.0) -> np.ndarray:
    """NRLMSIS 2.0 total mass density [kg/m^3] (``pymsis``, version 2.0) at inertial positions ``pos`` ``(N, 3)``
    [m] and times ``t`` ``(N,)`` [s after ``epoch_utc``]: Earth-fixed by :func:`roe_sep.core.frames.gcrs_to_itrs` (as
    :mod:`roe_sep.core.od.radar`), WGS-84 geodetic coordinates, the given F10.7 (previous day), its 81-day mean
    and daily Ap (every 3-h ap equal to it).

    Parameters
    ----------
    pos : array_like, shape (N, 3)
        Inertial positions [m].
    t : array_like, shape (N,)
        Times [s after ``epoch_utc``].
    epoch_utc : str
        ISO-8601 UTC epoch of t = 0.
    f107 : float
        F10.7 of the previous day [sfu].
    f107a : float
        Its 81-day mean [sfu].
    ap : float
        Daily Ap.

    Returns
    -------
    numpy.ndarray, shape (N,)
        Total mass density [kg/m^3].
    """
    from pymsis import msis

    pos = np.asarray(pos, dtype=float).reshape(-1, 3)
    t = np.broadcast_to(np.asarray(t, dtype=float), pos.shape[:1])
    jd0 = julian_date(epoch_utc)
    r_ef = np.einsum("nij,nj->ni", gcrs_to_itrs(jd0, t), pos)
    lat, lon, h = ecef_to_geodetic(r_ef)
    dates = np.datetime64(epoch_utc.rstrip("Zz"), "ms") + np.round(t * 1e3).astype("timedelta64[ms]")
    n = pos.shape[0]
    out = msis.calculate(dates, np.degrees(lon), np.degrees(lat), h / 1e3, np.full(n, float(f107)),
                         np.full(n, float(f107a)), np.full((n, 7), float(ap)), version=2.0)
    return np.asarray(out[..., msis.Variable.MASS_DENSITY], dtype=float).reshape(n)


@dataclass(frozen=True)
class MsisAtmosphere:
    """NRLMSIS 2.0 as the truth's density: ln rho = sum_k c_k phi_k (:func:`msis_basis`), fitted by
    :meth:`fit`. The frame of the basis turns with the Sun's mean right ascension alpha(t) = alpha_0 + SUN_RATE t,
    t the integrator's time [s after ``epoch_utc``]."""

    coefficients: tuple
    alpha0: float  # rad, Sun's right ascension at t = 0
    h0: float  # m, reference altitude of the basis
    epoch_utc: str
    f107: float
    f107a: float
    ap: float
    fit_rms: float  # RMS error of the fit in ln rho (relative density error)
    fit_max: float  # largest |error| in ln rho over the fit points
    kind = "msis"

    @classmethod
    def fit(cls, chief_mean: ArrayLike, span: float, epoch_utc: str = DEFAULT_EPOCH_UTC, f107: float = 140.0,
            f107a: float = 140.0, *, ap: float = 15.0, step: float = 60.0) -> "MsisAtmosphere":
        """Fit to NRLMSIS 2.0 (:func:`nrlmsis_density`) along the nominal orbit of ``chief_mean`` (mean elements at
        t = 0, secular J2, osculating positions) every ``step`` s over [0, ``span``] s, at radial offsets of
        0, +-``MSIS_SPAN``/2 and +-``MSIS_SPAN``.

        Parameters
        ----------
        chief_mean : array_like, shape (6,)
            The carrier's mean elements ``[a, e, i, raan, argp, M]`` at t = 0.
        span : float
            The fitted time span [s].
        epoch_utc, f107, f107a, ap
            As for :func:`nrlmsis_density`.
        step : float
            Sampling of the orbit [s].

        Returns
        -------
        MsisAtmosphere
            The fit, with its RMS and largest error in ln rho.
        """
        for name, v in (("f107", f107), ("f107a", f107a), ("ap", ap), ("span", span), ("step", step)):
            if not np.isfinite(v) or v < 0 or (name in ("span", "step") and v <= 0):
                raise ValueError(f"{name} must be a finite {'positive' if name in ('span', 'step') else 'non-negative'}"
                                 f" number, got {v}")
        t = np.arange(0.0, float(span) + step, step)
        pos = mean_to_cartesian(propagate_chief(np.asarray(chief_mean, dtype=float), t))[0]
        r = np.linalg.norm(pos, axis=-1, keepdims=True)
        offsets = np.linspace(-MSIS_SPAN, MSIS_SPAN, 5)
        pts = np.concatenate([pos * (1.0 + o / r) for o in offsets])
        tt = np.tile(t, offsets.size)
        rho = nrlmsis_density(pts, tt, epoch_utc, f107, f107a, ap=ap)
        alpha0 = float(sun_right_ascension(julian_date(epoch_utc)))
        h0 = float(chief_mean[0]) - R_EARTH
        basis = np.stack(_basis_numpy(pts, tt, alpha0, h0), axis=-1)
        coef, *_ = np.linalg.lstsq(basis, np.log(rho), rcond=1e-10)
        res = basis @ coef - np.log(rho)
        return cls(tuple(float(c) for c in coef), alpha0, h0, str(epoch_utc), float(f107), float(f107a), float(ap),
                   float(np.sqrt(np.mean(res**2))), float(np.max(np.abs(res))))

    def density_at(self, pos: ArrayLike, t: ArrayLike = 0.0) -> np.ndarray:
        """The fitted rho [kg/m^3] ``(...)`` at inertial positions ``(..., 3)`` [m] and times ``t`` [s]."""
        pos = np.asarray(pos, dtype=float)
        basis = np.stack(_basis_numpy(pos, np.asarray(t, dtype=float), self.alpha0, self.h0), axis=-1)
        return np.exp(basis @ np.asarray(self.coefficients))

    def pars(self) -> list[float]:
        """The integrator's density parameters: alpha_0 [rad], h_0 [m] and the fit's coefficients."""
        return [self.alpha0, self.h0, *self.coefficients]

    def describe(self) -> dict:
        """The model, its space-weather inputs and the fit's quality, for reports."""
        return {"model": self.kind, "epoch_utc": self.epoch_utc, "f107": self.f107, "f107a": self.f107a,
                "ap": self.ap, "fit_rms_ln_rho": self.fit_rms, "fit_max_ln_rho": self.fit_max}


def _basis_numpy(pos, t, alpha0, h0):
    pos = np.asarray(pos, dtype=float)
    r = np.linalg.norm(pos, axis=-1)
    x, y, z = _sun_frame(pos[..., 0], pos[..., 1], pos[..., 2], r, alpha0 + SUN_RATE * t)
    terms = msis_basis(x, y, z, (r - R_EARTH - h0) / MSIS_SCALE)
    return [np.broadcast_to(np.asarray(b, dtype=float), r.shape) for b in terms]


def effective_density(atmosphere: "Atmosphere | MsisAtmosphere", chief_mean: ArrayLike, t0: float = 0.0,
                      span: float | None = None, samples: int = 720) -> float:
    """Orbit-mean drag of ``atmosphere`` as a constant density [kg/m^3]: <rho |v_r| (v_r . v)> / (mu / a)^(3/2).

    Averaged over the osculating states of the nominal orbit of ``chief_mean`` (mean elements at ``t0``, secular J2)
    over one orbit (``span`` None) or ``span`` seconds, ``samples`` points evenly in time; v_r = v - omega_E x r.
    The secular drift of a is <da/dt> = (2 a^2 / mu) <v . a_drag> = -(a^2 / mu) B <rho |v_r| (v_r . v)>, which is
    seed 002 Eq. (24), da/dt = -B rho v^2 / n = -(a^2 / mu) B rho v^3 with v^2 = mu / a, for rho = rho_eff: the
    constant density the linear model needs to reproduce this atmosphere's orbit-mean drag.

    Parameters
    ----------
    atmosphere : Atmosphere or MsisAtmosphere
        The density model.
    chief_mean : array_like, shape (6,)
        Mean elements ``[a, e, i, raan, argp, M]`` at ``t0``.
    t0 : float
        Start of the average [s].
    span : float, optional
        Its length [s]; default one orbit.
    samples : int
        Points of the average.

    Returns
    -------
    float
        The effective density [kg/m^3].
    """
    from ..relmotion.orbit import mean_motion

    chief_mean = np.asarray(chief_mean, dtype=float)
    a = float(chief_mean[0])
    span = 2.0 * np.pi / float(mean_motion(a)) if span is None else float(span)
    t = t0 + np.arange(samples) * (span / samples)
    pos, vel = mean_to_cartesian(propagate_chief(chief_mean, t - t0))
    vr = vel - np.cross([0.0, 0.0, EARTH_ROTATION], pos)
    rho = atmosphere.density_at(pos, t)
    return float(np.mean(rho * np.linalg.norm(vr, axis=-1) * np.sum(vr * vel, axis=-1)) / (MU_EARTH / a) ** 1.5)


ATMOSPHERES = ("normalised", "msis")
"""The truth's density models (see the module docstring)."""


def truth_atmosphere(model: str, density: float, chief_mean: ArrayLike, span: float = 3.0 * SECONDS_PER_DAY,
                     epoch_utc: str = DEFAULT_EPOCH_UTC, *, f107: float = 140.0, f107a: float = 140.0,
                     ap: float = 15.0) -> "Atmosphere | MsisAtmosphere":
    """The truth's atmosphere by name: ``normalised`` (:meth:`Atmosphere.normalised` to ``density``, the default)
    or ``msis`` (:meth:`MsisAtmosphere.fit` over ``span`` s from ``epoch_utc``; ``density`` unused).

    Parameters
    ----------
    model : str
        ``normalised`` or ``msis`` (ValueError otherwise).
    density : float
        The scenario density [kg/m^3] (``normalised`` only).
    chief_mean : array_like, shape (6,)
        The carrier's mean elements at t = 0.
    span : float
        The span of the ``msis`` fit [s].
    epoch_utc, f107, f107a, ap
        As for :func:`nrlmsis_density`.

    Returns
    -------
    Atmosphere or MsisAtmosphere
        The density model.
    """
    if model == "normalised":
        return Atmosphere.normalised(density, chief_mean)
    if model == "msis":
        return MsisAtmosphere.fit(chief_mean, span, epoch_utc, f107, f107a, ap=ap)
    raise ValueError(f"atmosphere must be one of {ATMOSPHERES}, got {show(model)}")


@dataclass(frozen=True)
class Maneuver:
    """An impulsive burn of one spacecraft: epoch [s], ``deputy`` (picosatellite) or not (carrier), and its *own*
    velocity change [m/s] in its own RTN frame at that epoch."""

    epoch: float
    dv_rtn: tuple
    deputy: bool

    def relative(self) -> np.ndarray:
        """The relative impulse of the seed convention (picosatellite w.r.t. carrier): +dv or -dv."""
        dv = np.asarray(self.dv_rtn, dtype=float)
        return dv if self.deputy else -dv


# ---------------------------------------------------------------- dynamics (heyoka expressions)
def legendre(n: int, s: "hy.expression") -> "hy.expression":
    """Legendre polynomial P_n(s), n = 2..4, written with products only (heyoka's pow(s, k) recursion divides by
    s, which is 0 on the equator)."""
    s2 = s * s
    if n == 2:
        return 1.5 * s2 - 0.5
    if n == 3:
        return s * (2.5 * s2 - 1.5)
    if n == 4:
        return (35.0 * s2 * s2 - 30.0 * s2 + 3.0) / 8.0
    raise ValueError(f"zonal degree {n} not implemented")


def zonal_potential(x: "hy.expression", y: "hy.expression", z: "hy.expression", zonals: int) -> "hy.expression":
    """U = mu/r [1 - sum_n J_n (R_E/r)^n P_n(z/r)] (Vallado Eq. 8-19, zonal terms), heyoka expression.

    Parameters
    ----------
    x, y, z : heyoka.expression
        Inertial position [m].
    zonals : int
        Highest zonal harmonic, 2 to 4.

    Returns
    -------
    heyoka.expression
        U [m^2/s^2].
    """
    import heyoka as hy

    r = hy.sqrt(x * x + y * y + z * z)
    s = z / r
    q = R_EARTH / r
    pert, qn = 0.0, q
    for n, jn in enumerate(ZONALS[zonals], start=2):
        qn = qn * q
        pert = pert + jn * qn * legendre(n, s)
    return MU_EARTH / r * (1.0 - pert)


def density_expression(kind: str, x: "hy.expression", y: "hy.expression", z: "hy.expression") -> "hy.expression":
    """rho as a heyoka expression of the inertial position (and time, ``msis``), parameters from ``hy.par[2]``:
    ``exponential``: rho_ref exp((h_ref + R_E - r) / H); ``msis``: exp(sum_k c_k phi_k) (:func:`msis_basis`).

    Parameters
    ----------
    kind : str
        ``exponential`` or ``msis``.
    x, y, z : heyoka.expression
        Inertial position [m].

    Returns
    -------
    heyoka.expression
        rho [kg/m^3].
    """
    import heyoka as hy

    r = hy.sqrt(x * x + y * y + z * z)
    if kind == "exponential":
        return hy.par[2] * hy.exp((hy.par[3] + R_EARTH - r) / hy.par[4])
    if kind == "msis":
        sx, sy, sz = _sun_frame(x, y, z, r, hy.par[2] + SUN_RATE * hy.time, cos=hy.cos, sin=hy.sin)
        terms = msis_basis(sx, sy, sz, (r - R_EARTH - hy.par[3]) / MSIS_SCALE)
        log_rho = hy.par[4] * terms[0]
        for k, term in enumerate(terms[1:], start=5):
            log_rho = log_rho + hy.par[k] * term
        return hy.exp(log_rho)
    raise ValueError(f"unknown density model {kind!r}")


def drag_acceleration(pos: Sequence["hy.expression"], vel: Sequence["hy.expression"], b: "hy.expression",
                      rho: "hy.expression") -> tuple:
    """a = -1/2 B rho |v_r| v_r, v_r = v - omega_E x r (Vallado Eq. 8-28), heyoka expressions.

    Parameters
    ----------
    pos, vel : sequence of three heyoka.expression
        Inertial position [m] and velocity [m/s].
    b : heyoka.expression
        Ballistic coefficient B [m^2/kg] (a runtime parameter).
    rho : heyoka.expression
        Density [kg/m^3].

    Returns
    -------
    tuple of three heyoka.expression
        The acceleration [m/s^2].
    """
    import heyoka as hy

    x, y, z = pos
    vrx, vry, vrz = vel[0] + EARTH_ROTATION * y, vel[1] - EARTH_ROTATION * x, vel[2]
    k = -0.5 * b * rho * hy.sqrt(vrx * vrx + vry * vry + vrz * vrz)
    return k * vrx, k * vry, k * vrz


def pair_equations(zonals: int = 4, density: str = "exponential") -> list[tuple]:
    """The 12 first-order ODEs of chief and deputy (heyoka ``(var, rhs)`` pairs), parameters as in the module doc."""
    import heyoka as hy

    sys = []
    for k, tag in enumerate(("c", "d")):
        x, y, z, vx, vy, vz = hy.make_vars(*(f"{q}_{tag}" for q in ("x", "y", "z", "vx", "vy", "vz")))
        u = zonal_potential(x, y, z, zonals)
        dx, dy, dz = drag_acceleration((x, y, z), (vx, vy, vz), hy.par[k], density_expression(density, x, y, z))
        sys += [(x, vx), (y, vy), (z, vz),
                (vx, hy.diff(u, x) + dx), (vy, hy.diff(u, y) + dy), (vz, hy.diff(u, z) + dz)]
    return sys


def n_pars(density: str = "exponential") -> int:
    """Number of runtime parameters of the pair system with ``density``."""
    return 2 + (3 if density == "exponential" else 2 + N_MSIS_BASIS)


DEFAULT_TOL = 1e-15
SEGMENT = 3600.0  # s, the simulator truth integrates in segments ending on this grid (NonlinearTruth._extend)
"""Taylor integrator tolerance (relative/absolute, heyoka's default is machine epsilon ~2.2e-16)."""


@functools.lru_cache(maxsize=None)
def pair_integrator(zonals: int = 4, batch_size: int | None = None, tol: float = DEFAULT_TOL,
                    density: str = "exponential") -> "hy.taylor_adaptive | hy.taylor_adaptive_batch":
    """The compiled Taylor integrator for one pair (``batch_size`` None) or ``batch_size`` pairs (SIMD lanes).

    Cached per process; callers get a template and :func:`copy.deepcopy` it (no recompilation). Measured LLVM
    compile times on this machine: single pair in heyoka's compact mode ~1 s (it runs 1.4x slower per step, which
    does not matter for one pair); the batch integrator of the Monte Carlo in full (non-compact) mode ~2-5 s for
    degree 2 and ~10 s for degree 4 (3x the cost per step of degree 2, hence ``MC_ZONALS`` = 2).

    Parameters
    ----------
    zonals : int
        Highest zonal harmonic.
    batch_size : int, optional
        SIMD lanes; None: one pair.
    tol : float
        Taylor integrator tolerance.
    density : str
        ``exponential`` or ``msis``.

    Returns
    -------
    heyoka.taylor_adaptive or heyoka.taylor_adaptive_batch
        The cached template (deep-copy it before use).
    """
    import heyoka as hy

    sys = pair_equations(zonals, density)
    npar = n_pars(density)
    if batch_size is None:
        return hy.taylor_adaptive(sys, np.zeros(12), pars=np.zeros(npar), tol=tol, compact_mode=True)
    return hy.taylor_adaptive_batch(sys, np.zeros((12, batch_size)), pars=np.zeros((npar, batch_size)), tol=tol,
                                    compact_mode=density != "exponential")


def simd_size() -> int:
    """Recommended heyoka batch size (SIMD width in doubles: 4 with AVX2)."""
    import heyoka as hy

    return int(hy.recommended_simd_size())


# ---------------------------------------------------------------- states, burns, relative quantities
def pair_state(chief_mean: ArrayLike, deputy_mean: ArrayLike) -> np.ndarray:
    """Initial inertial state ``(..., 12)`` of two spacecraft from their *mean* elements (mean -> osculating, first
    order J2, then Cartesian)."""
    rc, vc = mean_to_cartesian(chief_mean)
    rd, vd = mean_to_cartesian(deputy_mean)
    return np.concatenate([rc, vc, rd, vd], axis=-1)


def apply_impulse(state: ArrayLike, dv_rtn: ArrayLike, deputy: ArrayLike) -> np.ndarray:
    """Add an impulse [m/s] given in the executing spacecraft's own RTN frame to its inertial velocity.

    dv_inertial = [R T N] dv_rtn with R = r/|r|, T = N x R, N = h/|h| (:func:`~roe_sep.core.od.radar.rtn_matrix`).
    Vectorized over ``state`` ``(..., 12)``, ``dv_rtn`` ``(..., 3)`` and the boolean ``deputy`` ``(...)``.

    Parameters
    ----------
    state : array_like, shape (..., 12)
        Pair states (positions [m], velocities [m/s]; chief first).
    dv_rtn : array_like, shape (..., 3)
        The impulse [m/s] in the executing spacecraft's RTN frame.
    deputy : array_like of bool, shape (...)
        True where the deputy burns, False for the chief.

    Returns
    -------
    numpy.ndarray, shape (..., 12)
        A new array of the states after the burn.
    """
    s = np.array(state, dtype=float, copy=True)
    dv = np.asarray(dv_rtn, dtype=float)
    deputy = np.asarray(deputy, dtype=bool)
    for off, mine in ((0, ~deputy), (6, deputy)):
        rot = rtn_matrix(s[..., off:off + 3], s[..., off + 3:off + 6])
        dvi = np.einsum("...ij,...j->...i", rot, dv)
        s[..., off + 3:off + 6] += np.where(mine[..., None], dvi, 0.0)
    return s


def mean_elements(state: ArrayLike) -> np.ndarray:
    """Mean Keplerian elements ``(..., 2, 6)`` (chief, deputy) of pair states (osculating -> mean, first order J2)."""
    s = np.asarray(state, dtype=float)
    pos = np.stack([s[..., 0:3], s[..., 6:9]], axis=-2)
    vel = np.stack([s[..., 3:6], s[..., 9:12]], axis=-2)
    return cartesian_to_mean(pos, vel)


def mean_roe(state: ArrayLike) -> np.ndarray:
    """Dimensionless mean ROE ``(..., 6)`` of the deputy w.r.t. the chief from pair states: each spacecraft is
    converted to mean elements separately, then seed 002 Eq. (1) (:func:`~roe_sep.core.relmotion.roe.kepler_to_roe`)."""
    kep = mean_elements(state)
    return kepler_to_roe(kep[..., 0, :], kep[..., 1, :])


def _relative_position(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The chief's RTN -> inertial rotation M ``(..., 3, 3)`` of pair states ``s`` ``(..., 12)`` and the deputy's
    position relative to the chief in it, M^T (r_d - r_c) ``(..., 3)`` [m] (:func:`relative_rtn`'s first half)."""
    rc = s[..., 0:3]
    rot = rtn_matrix(rc, s[..., 3:6])
    return rot, np.einsum("...ji,...j->...i", rot, s[..., 6:9] - rc)


def relative_rtn(state: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Deputy position [m] and velocity [m/s] relative to the chief in the chief's rotating RTN frame.

    r_rel = M^T (r_d - r_c),  v_rel = M^T (v_d - v_c) - omega x r_rel,  omega = (0, 0, |h_c| / |r_c|^2) in RTN.
    """
    s = np.asarray(state, dtype=float)
    rc, vc = s[..., 0:3], s[..., 3:6]
    rot, dr = _relative_position(s)
    dv = np.einsum("...ji,...j->...i", rot, s[..., 9:12] - vc)
    w = np.linalg.norm(np.cross(rc, vc), axis=-1) / np.sum(rc * rc, axis=-1)
    # dv - omega x r_rel, omega x r_rel = (-w dr_T, w dr_R, 0): the two non-zero components subtracted in place (the
    # radial one minus 0.0 is itself)
    dv[..., 0] -= -w * dr[..., 1]
    dv[..., 1] -= w * dr[..., 0]
    return dr, dv


# ---------------------------------------------------------------- single pair
def _pars(b_chief, b_deputy, atmosphere):
    return np.array([b_chief, b_deputy, *atmosphere.pars()], dtype=float)


def propagate_pair(state0: ArrayLike, t0: float, times: ArrayLike, maneuvers: Iterable[Maneuver], b_chief: float,
                   *, b_deputy: float, atmosphere: Atmosphere, zonals: int = 4, tol: float = DEFAULT_TOL) -> np.ndarray:
    """Integrate one pair from ``state0`` at ``t0`` and return the states ``(len(times), 12)`` at ``times``.

    ``maneuvers`` (:class:`Maneuver`, epochs >= t0) are applied at their epochs; a sample exactly at a burn epoch
    sees the post-burn state (as :func:`roe_sep.core.relmotion.trajectory.trajectory`).

    Parameters
    ----------
    state0 : array_like, shape (12,)
        The pair's state at ``t0``.
    t0 : float
        Its epoch [s].
    times : array_like, shape (T,)
        Output epochs [s], >= ``t0``.
    maneuvers : iterable of Maneuver
        The burns.
    b_chief, b_deputy : float
        Ballistic coefficients [m^2/kg].
    atmosphere : Atmosphere or MsisAtmosphere
        The truth's density.
    zonals : int
        Highest zonal harmonic.
    tol : float
        Taylor integrator tolerance.

    Returns
    -------
    numpy.ndarray, shape (T, 12)
        The states.
    """
    times = np.asarray(times, dtype=float)
    if np.any(times < t0):
        raise ValueError("propagation times must not precede t0")
    ta = copy.deepcopy(pair_integrator(zonals, None, tol, atmosphere.kind))
    ta.time = float(t0)
    ta.state[:] = np.asarray(state0, dtype=float)
    ta.pars[:] = _pars(b_chief, b_deputy, atmosphere)
    out = np.empty(times.shape + (12,))
    order = np.argsort(times, kind="stable")
    burns = sorted((m for m in maneuvers if m.epoch >= t0), key=lambda m: m.epoch)
    edges = [m.epoch for m in burns] + [np.inf]
    k0 = 0
    for k, hi in enumerate(edges):
        idx = order[k0:][times[order[k0:]] < hi]
        if idx.size:
            out[idx] = _grid(ta, times[idx])
            k0 += idx.size
        if k < len(burns):
            _until(ta, burns[k].epoch)
            ta.state[:] = apply_impulse(ta.state, burns[k].dv_rtn, burns[k].deputy)
    return out


def _until(ta, t):
    if t > ta.time:
        res = ta.propagate_until(float(t))
        _check(res[0])


def _grid(ta, times):
    """States at sorted ``times`` >= ta.time, leaving the integrator at the last one."""
    _until(ta, times[0])
    res = ta.propagate_grid(np.asarray(times, dtype=float))
    _check(res[0])
    return np.asarray(res[-1]).copy()


def _check(outcome):
    import heyoka as hy

    if outcome not in (hy.taylor_outcome.time_limit, hy.taylor_outcome.success):
        raise RuntimeError(f"nonlinear propagation failed: {outcome}")


# ---------------------------------------------------------------- many pairs (Monte Carlo, sweeps)
def _batch_worker(template, states, pars, t0, grid, *, out, lo, hi):
    """Propagate lanes ``lo:hi`` of ``states`` ``(12, N)`` from t0, ``batch_size`` lanes at a time (one integrator
    per worker thread; heyoka releases the GIL while it integrates). ``grid`` is the end time (float: ``states`` is
    overwritten with the final states) or sorted output times ``(n_t,)`` (states at those times go to ``out``
    ``(n_t, 12, N)``)."""
    ta = copy.deepcopy(template)
    bs = ta.batch_size
    for j in range(lo, hi, bs):
        ta.set_time(float(t0))
        ta.state[:] = states[:, j:j + bs]
        ta.pars[:] = pars[:, j:j + bs]
        if out is None:
            ta.propagate_until(float(grid))
        else:
            ta.propagate_until(float(grid[0]))
            out[:, :, j:j + bs] = ta.propagate_grid(np.repeat(grid[:, None], bs, axis=1))[1]
        if not all(o[0].name in ("time_limit", "success") for o in ta.propagate_res):
            raise RuntimeError(f"nonlinear propagation failed in lanes {j}..{j + bs}: {ta.propagate_res}")
        states[:, j:j + bs] = ta.state


def _run_lanes(states0, t0, grid, b_chief, b_deputy, *, atmosphere, zonals, tol, workers):
    """The lane layout shared by :func:`propagate_pairs` and :func:`propagate_pairs_grid`: states and parameters
    ``(12 | 5, N)`` padded to a multiple of the batch size, blocks of lanes over a thread pool of ``workers``
    (default: the cores available). Returns ``(final states (12, N_pad), grid output (n_t, 12, N_pad) or None)``."""
    s0 = np.asarray(states0, dtype=float)
    n = s0.shape[0]
    template = pair_integrator(zonals, simd_size(), tol, atmosphere.kind)
    bs = template.batch_size
    npad = -(-n // bs) * bs
    states = np.empty((12, npad))
    states[:, :n] = s0.T
    states[:, n:] = s0[-1:].T
    pars = np.empty((n_pars(atmosphere.kind), npad))
    pars[0, :n] = np.broadcast_to(np.asarray(b_chief, dtype=float), (n,))
    pars[1, :n] = np.broadcast_to(np.asarray(b_deputy, dtype=float), (n,))
    pars[:2, n:] = pars[:2, n - 1:n]
    pars[2:] = np.asarray(atmosphere.pars())[:, None]
    out = None if np.ndim(grid) == 0 else np.empty((len(grid), 12, npad))
    workers = workers or len(os.sched_getaffinity(0))
    blocks = np.linspace(0, npad // bs, workers + 1).astype(int) * bs
    with ThreadPoolExecutor(max_workers=workers) as pool:
        futures = [pool.submit(_batch_worker, template, states, pars, t0, grid, out=out, lo=lo, hi=hi)
                   for lo, hi in zip(blocks[:-1], blocks[1:]) if hi > lo]
        for f in futures:
            f.result()
    return states, out


def propagate_pairs(states0: ArrayLike, t0: float, t1: float, b_chief: ArrayLike, b_deputy: ArrayLike,
                    *, atmosphere: Atmosphere, zonals: int = 4, tol: float = DEFAULT_TOL,
                    workers: int | None = None) -> np.ndarray:
    """Propagate N pairs ``(N, 12)`` from ``t0`` to ``t1`` [s]: heyoka batch mode (``simd_size`` pairs per
    integrator call, each lane with its own adaptive steps) over a thread pool of ``workers`` (default: the
    cores available), the sample axis padded to a multiple of the batch size. ``b_chief``/``b_deputy`` broadcast
    to ``(N,)``. Returns ``(N, 12)``.

    Parameters
    ----------
    states0 : array_like, shape (N, 12)
        States at ``t0``.
    t0, t1 : float
        Start and end [s].
    b_chief, b_deputy : array_like
        Ballistic coefficients B = c_d A / m [m^2/kg], broadcast to ``(N,)``.
    atmosphere : Atmosphere or MsisAtmosphere
        The truth's density.
    zonals : int
        Highest zonal harmonic (2: J2 only, 4: J2-J4).
    tol : float
        Taylor integrator tolerance.
    workers : int, optional
        Threads (None: every CPU this process may use).

    Returns
    -------
    numpy.ndarray, shape (N, 12)
        The states at ``t1``.
    """
    n = np.shape(states0)[0]
    states, _ = _run_lanes(states0, t0, float(t1), b_chief, b_deputy, atmosphere=atmosphere, zonals=zonals, tol=tol,
                           workers=workers)
    return states[:, :n].T.copy()


def propagate_pairs_grid(states0: ArrayLike, t0: float, times: ArrayLike, b_chief: ArrayLike, b_deputy: ArrayLike,
                         *, atmosphere: Atmosphere, zonals: int = 4, tol: float = DEFAULT_TOL,
                         workers: int | None = None) -> np.ndarray:
    """As :func:`propagate_pairs`, but the states of every pair at the sorted ``times`` >= ``t0`` [s] (heyoka's
    dense output, exact to the integrator tolerance between steps). Returns ``(N, len(times), 12)``.

    Parameters
    ----------
    states0 : array_like, shape (N, 12)
        States at ``t0``.
    t0 : float
        Start [s].
    times : array_like, shape (T,)
        Sorted output epochs [s], >= ``t0``.
    b_chief, b_deputy, atmosphere, zonals, tol, workers
        As for :func:`propagate_pairs`.

    Returns
    -------
    numpy.ndarray, shape (N, T, 12)
        The states.
    """
    times = np.asarray(times, dtype=float)
    if times.ndim != 1 or times.size == 0 or times[0] < t0 or np.any(np.diff(times) < 0.0):
        raise ValueError("times must be a non-empty sorted 1-D array starting at or after t0")
    n = np.shape(states0)[0]
    _, out = _run_lanes(states0, t0, times, b_chief, b_deputy, atmosphere=atmosphere, zonals=zonals, tol=tol,
                        workers=workers)
    return np.moveaxis(out[:, :, :n], -1, 0).copy()


# ---------------------------------------------------------------- numpy reference (cross-check and benchmark)
def zonal_acceleration(pos: ArrayLike, zonals: int = 2) -> np.ndarray:
    """Closed-form zonal accelerations [m/s^2] (Vallado Eq. 8-30 style expansions of grad U), numpy, ``(..., 3)``.

    J2: -3/2 J2 mu R^2/r^4 [x/r (1 - 5 s^2), y/r (1 - 5 s^2), z/r (3 - 5 s^2)]
    J3: -5/2 J3 mu R^3/r^5 [x/r (3 s - 7 s^3), y/r (3 s - 7 s^3), 6 s^2 - 7 s^4 - 3/5]
    J4: 15/8 J4 mu R^4/r^6 [x/r (1 - 14 s^2 + 21 s^4), y/r (...), z/r (5 - 70/3 s^2 + 21 s^4)],  s = z/r.
    Independent of the symbolic gradient used by the integrator (the tests compare the two).
    """
    p = np.asarray(pos, dtype=float)
    r = np.linalg.norm(p, axis=-1)
    xr, yr, s = p[..., 0] / r, p[..., 1] / r, p[..., 2] / r
    s2 = s * s
    k = -1.5 * J2 * MU_EARTH * R_EARTH**2 / r**4
    acc = np.stack([k * xr * (1 - 5 * s2), k * yr * (1 - 5 * s2), k * s * (3 - 5 * s2)], axis=-1)
    if zonals >= 3:
        k = -2.5 * J3 * MU_EARTH * R_EARTH**3 / r**5
        acc = acc + np.stack([k * xr * (3 * s - 7 * s * s2), k * yr * (3 * s - 7 * s * s2),
                              k * (6 * s2 - 7 * s2 * s2 - 0.6)], axis=-1)
    if zonals >= 4:
        k = 15.0 / 8.0 * J4 * MU_EARTH * R_EARTH**4 / r**6
        f = 1 - 14 * s2 + 21 * s2 * s2
        acc = acc + np.stack([k * xr * f, k * yr * f, k * s * (5 - 70.0 / 3.0 * s2 + 21 * s2 * s2)], axis=-1)
    return acc - (MU_EARTH / r**3)[..., None] * p


def pair_rhs(t: float, y: np.ndarray, pars: Sequence[float], zonals: int = 2) -> np.ndarray:
    """d/dt of pair states ``(12,)`` or ``(12, N)`` with the same force model as :func:`pair_equations`, numpy
    (for ``scipy.integrate.solve_ivp``). ``pars`` = ``[B_chief, B_deputy, rho_ref, h_ref, H]``.

    Parameters
    ----------
    t : float
        Time [s] (the model is autonomous).
    y : numpy.ndarray, shape (12,) or (12, N)
        Pair states.
    pars : sequence of float
        ``[B_chief, B_deputy, rho_ref, h_ref, H]`` (m^2/kg, m^2/kg, kg/m^3, m, m).
    zonals : int
        Highest zonal harmonic.

    Returns
    -------
    numpy.ndarray, shape of ``y``
        The derivative (velocities [m/s], accelerations [m/s^2]).
    """
    y = np.asarray(y, dtype=float)
    out = np.empty_like(y)
    rho_ref, h_ref, big_h = pars[2], pars[3], pars[4]
    for k, off in enumerate((0, 6)):
        pos, vel = y[off:off + 3], y[off + 3:off + 6]
        r = np.sqrt(np.sum(pos * pos, axis=0))
        vr = np.stack([vel[0] + EARTH_ROTATION * pos[1], vel[1] - EARTH_ROTATION * pos[0], vel[2]])
        rho = rho_ref * np.exp((h_ref + R_EARTH - r) / big_h)
        drag = -0.5 * pars[k] * rho * np.sqrt(np.sum(vr * vr, axis=0)) * vr
        out[off:off + 3] = vel
        out[off + 3:off + 6] = np.moveaxis(zonal_acceleration(np.moveaxis(pos, 0, -1), zonals), -1, 0) + drag
    return out


# ---------------------------------------------------------------- the simulator's nonlinear truth
class NonlinearTruth:
    """Drop-in for :class:`roe_sep.core.truth.secular.TruthModel` with the numerical pair as truth (the ``sim`` node's
    ``dynamics: nonlinear``).

    Both spacecraft start on the chief's state (``chief0`` mean elements at ``t0``, mean -> osculating); before the
    ejection the picosatellite rides in the carrier (same B, identical states, ROE exactly zero). Burns are inertial
    velocity changes in the executing spacecraft's RTN frame (:func:`apply_impulse`). ROE are the *mean* ROE of
    the numerical states (:func:`mean_roe`), RTN the true relative state (:func:`relative_rtn`). Queries must not
    go back before the earliest time of the previous query (dense output of the steps since then is kept).
    ``da_dot`` is the secular model's value, reported in diagnostics only. ``storm`` (a contingency's
    :class:`~.contingency.DensityStorm`, None: none) multiplies both ballistic coefficients -- the density both
    spacecraft see -- by its factor in its window after the ejection; the window's edges end integration segments.
    """

    storm = None

    def __init__(self, chief0: ArrayLike, t0: float, b_chief: float, b_deputy: float, atmosphere: Atmosphere,
                 *, zonals: int = 4, da_dot: float = 0.0):
        self.chief0 = np.asarray(chief0, dtype=float)
        self.t0 = float(t0)
        self.da_dot = float(da_dot)
        self.b_deputy = float(b_deputy)
        self.b_chief = float(b_chief)
        self.separated = False
        self.ejected_at = None  # s, the separation (the storm's window starts from it)
        self._ta = copy.deepcopy(pair_integrator(zonals, None, DEFAULT_TOL, atmosphere.kind))
        self._ta.time = self.t0
        self._ta.state[:] = pair_state(self.chief0, self.chief0)
        self._ta.pars[:] = _pars(b_chief, b_chief, atmosphere)
        self._segments = []  # (t_from, t_to, heyoka continuous output)
        self.revision = 0  # burns applied: what was evaluated before a burn is stale after it
        self._distances = None  # (revision, step, times, |r| at them) of distances' last pass

    def integrated_to(self, t: float) -> float:
        """Integrate up to (at least) ``t`` [s] and return the end of the integrated span: the truth at any time up to
        it is dense output, without integrating further (until the next burn, :attr:`revision`)."""
        self._extend(t)
        return float(self._ta.time)

    @property
    def a(self) -> float:
        """The carrier's mean semi-major axis [m] at ``t0``."""
        return float(self.chief0[0])

    @property
    def inc(self) -> float:
        """The carrier's mean inclination [rad] at ``t0``."""
        return float(self.chief0[2])

    def _extend(self, t):
        """Integrate up to (at least) ``t`` in segments that end on the fixed grid of ``SEGMENT`` seconds from
        ``t0``: the integrator's steps, hence the truth to the last bit, depend on the burns alone, never on how the
        queries are spaced (the lockstep step size, the pacing)."""
        t = float(t)
        while t > self._ta.time:
            t_from = self._ta.time
            t_to = self.t0 + (math.floor((t_from - self.t0) / SEGMENT + 1e-9) + 1) * SEGMENT
            if self.storm is not None and self.ejected_at is not None:
                t_to = self._storm_segment(t_from, t_to)
            res = self._ta.propagate_until(t_to, c_output=True)
            _check(res[0])
            self._segments.append((t_from, t_to, res[4]))

    def _storm_segment(self, t_from, t_to):
        """The storm: the segment from ``t_from`` ends at the window's next edge before ``t_to``; both ballistic
        coefficients times the density factor over it (constant between edges). The segment's end [s]."""
        t_to = min([t_to, *(e for e in self.storm.window(self.ejected_at) if t_from < e)])
        f = float(self.storm.factor_at(t_from, self.ejected_at))
        self._ta.pars[0] = self.b_chief * f
        self._ta.pars[1] = (self.b_deputy if self.separated else self.b_chief) * f
        return t_to

    def states(self, times: ArrayLike) -> np.ndarray:
        """Pair states ``(..., 12)`` at ``times`` [s] (scalar or array, each >= the previous query's earliest)."""
        t = np.asarray(times, dtype=float)
        flat = t.reshape(-1)
        t_min, t_max = flat.min(), flat.max()
        self._extend(t_max)
        self._segments = [s for s in self._segments if s[1] >= t_min]
        out = np.empty((flat.size, 12))
        if self._segments and self._segments[0][0] <= t_min and t_max <= self._segments[0][1]:
            # all in the first segment kept (the usual step): the first segment holding each time, in one call
            out[:] = np.asarray(self._segments[0][2](flat)).reshape(-1, 12)
            return out.reshape(t.shape + (12,))
        done = np.zeros(flat.size, bool)
        for lo, hi, co in self._segments:
            sel = ~done & (flat >= lo) & (flat <= hi)
            if np.any(sel):
                out[sel] = np.asarray(co(flat[sel])).reshape(-1, 12)
                done |= sel
        at_now = ~done & (flat == self._ta.time)
        out[at_now] = self._ta.state
        done |= at_now
        if not np.all(done):
            raise ValueError(f"nonlinear truth queried before its dense output: t = {flat[~done].min():.3f} s")
        return out.reshape(t.shape + (12,))

    def chief_elements(self, t: ArrayLike) -> np.ndarray:
        """The carrier's mean Keplerian elements ``(..., 6)`` at ``t`` [s]."""
        return mean_elements(self.states(t))[..., 0, :]

    def u_at(self, t: ArrayLike) -> np.ndarray:
        """The carrier's mean argument of latitude [rad, 0..2pi) at ``t``."""
        k = self.chief_elements(t)
        return np.mod(k[..., 4] + k[..., 5], 2.0 * np.pi)

    def roe_at(self, t: ArrayLike) -> np.ndarray:
        """Dimensionless mean ROE ``(..., 6)`` at ``t`` [s]."""
        return mean_roe(self.states(t))

    def rtn_at(self, t: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """True relative position [m] and velocity [m/s], each ``(..., 3)``, in the carrier's RTN frame at ``t``
        [s]."""
        return relative_rtn(self.states(t))

    def samples(self, t: ArrayLike) -> tuple:
        """Carrier mean elements, mean ROE and the true RTN state at the times ``t`` (an array), in one pass."""
        st = self.states(np.asarray(t, dtype=float))
        mean = mean_elements(st)
        return mean[..., 0, :], kepler_to_roe(mean[..., 0, :], mean[..., 1, :]), relative_rtn(st)

    def distances(self, t_from: float, t_to: float, step: float) -> tuple[np.ndarray, np.ndarray]:
        """Times and |r| [m] over ``[t_from, t_to]`` every ``step`` seconds (and at both ends).

        |r| is evaluated in one pass on the grid of ``step`` from ``t_from`` to the end of the integrated span (the
        hour's end); the next windows on that grid (the simulator's next steps) take theirs from it, until a burn.
        Each distance is its own time's value to the bit whatever the pass (the evaluation is element-wise).

        Parameters
        ----------
        t_from, t_to : float
            The window [s].
        step : float
            The sampling [s].

        Returns
        -------
        (numpy.ndarray, numpy.ndarray), each shape (T,)
            Times [s] and distances [m].
        """
        times = np.append(np.arange(t_from, t_to, step), t_to)
        n = times.size
        if self._distances is not None and self._distances[:2] == (self.revision, step):
            grid, dist = self._distances[2:]
            i = int(np.searchsorted(grid, times[0]))
            if i + n <= grid.size and np.array_equal(grid[i:i + n], times):
                return times, dist[i:i + n]
        end = self.integrated_to(t_to)
        grid = np.append(np.arange(t_from, end, step), end)  # its first n times are the window's (same arange)...
        if grid.size < n or not np.array_equal(grid[:n], times):  # ... unless t_to is off the grid: the window alone
            grid = times
        dist = np.linalg.norm(_relative_position(self.states(grid))[1], axis=-1)
        dist.flags.writeable = False
        self._distances = (self.revision, step, grid, dist)
        return times, dist[:n]

    def apply(self, t: float, dv_rel: ArrayLike, spacecraft: str = "picosatellite") -> None:
        """Execute a burn at ``t``: ``dv_rel`` is the relative impulse of the seed convention (the picosatellite's
        own dv; minus the carrier's own dv), ``spacecraft`` who burns, in its own RTN frame.

        Parameters
        ----------
        t : float
            The epoch [s].
        dv_rel : array_like, shape (3,)
            The relative impulse [m/s] of the seed convention.
        spacecraft : str
            ``picosatellite`` or ``carrier``.

        Returns
        -------
        None
        """
        if spacecraft not in ("picosatellite", "carrier"):
            raise ValueError(f"unknown spacecraft {spacecraft!r}")
        deputy = spacecraft == "picosatellite"
        t = float(t)
        state = self.states(t)  # from the grid segment holding t (the integrator may have gone past it)
        dv = np.asarray(dv_rel, dtype=float) * (1.0 if deputy else -1.0)
        self._ta.time = t
        self._ta.state[:] = apply_impulse(state, dv, deputy)
        if deputy and not self.separated:
            self._ta.pars[1] = self.b_deputy
            self.ejected_at = t
        self.separated = True
        self._segments = []
        self.revision += 1
