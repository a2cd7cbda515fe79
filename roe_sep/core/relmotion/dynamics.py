"""Secular relative dynamics in ROE: Keplerian drift, J2 and differential drag, composable in one transition.

Near-circular chief. With kappa = 3/4 n J2 (R_E/a)^2, P = 3 cos^2 i - 1, Q = 5 cos^2 i - 1 (first-order secular J2
rates of the mean elements: d raan/dt = -2 kappa cos i, d argp/dt = kappa Q, dM/dt = n + kappa P), the ROE rates
are those of the J2 state transition matrix of Koenig, Guffanti and D'Amico (JGCD 2017) for a circular chief:

* d(da)/dt  = da_dot (differential drag, constant: seed 002 Eq. 24 differentiated in time)
* d(dl)/dt  = -(3/2 n + 7 kappa P) da - 7 kappa sin(2i) dix       (Keplerian part: seed 000 Eq. 2)
* d(de)/dt  = kappa Q  J de          (rotation of the relative eccentricity vector at the perigee rate)
* d(dix)/dt = 0
* d(diy)/dt = 7/2 kappa sin(2i) da + 2 kappa sin^2(i) dix

With da(t) = da0 + da_dot t the integrals are closed form; with J2 off and drag on they reduce exactly to seed 002
Eqs. (23)-(24): a dl = 3/(4 n^2) dB rho v^2 (u - u0)^2 and a da = -(1/n^2) dB rho v^2 (u - u0).
"""

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ..constants import EARTH_ROTATION, J2, R_EARTH, SECONDS_PER_DAY
from .orbit import circular_speed, mean_motion, per_chief
from .roe import components, stack_last


def j2_kappa(a: ArrayLike) -> np.ndarray:
    """kappa = 3/4 n J2 (R_E/a)^2 [rad/s], the J2 secular rate scale of a circular orbit of semi-major axis ``a``."""
    return _kappa(a, mean_motion(a))


def _kappa(a, n):
    """:func:`j2_kappa` with the mean motion ``n`` of ``a`` given (its expression)."""
    return 0.75 * n * J2 * (R_EARTH / np.asarray(a, dtype=float)) ** 2


def raan_rate(a: ArrayLike, inc: ArrayLike) -> np.ndarray:
    """Secular J2 drift of the ascending node d(raan)/dt = -2 kappa cos i [rad/s] of a circular orbit of semi-major
    axis ``a`` [m] and inclination ``inc`` [rad] (broadcast)."""
    return -2.0 * j2_kappa(a) * np.cos(inc)


def sun_synchronous_inclination(a: ArrayLike) -> np.ndarray:
    """Inclination [rad] of the circular sun-synchronous orbit of semi-major axis ``a`` [m]: :func:`raan_rate`
    equals the mean Sun rate.

    -2 kappa cos i = 2 pi / (365.2422 days)  =>  cos i = -(2 pi / year) / (2 kappa).
    """
    cos_i = -(2.0 * np.pi / (365.2422 * SECONDS_PER_DAY)) / (2.0 * j2_kappa(a))
    if np.any(np.abs(cos_i) > 1.0):
        raise ValueError(f"no sun-synchronous orbit exists at a = {a} m")
    return np.arccos(cos_i)


def eccentricity_vector_rotation_rate(a: ArrayLike, inc: ArrayLike) -> np.ndarray:
    """d(phi)/dt = kappa (5 cos^2 i - 1) [rad/s]: secular J2 rotation of the relative eccentricity vector (chief
    semi-major axis ``a`` [m], inclination ``inc`` [rad], broadcast).

    Negative (clockwise) for sun-synchronous inclinations: about -3.5 deg/day at 500 km (seed 001 Sec. 3.3).
    """
    return j2_kappa(a) * (5.0 * np.cos(inc) ** 2 - 1.0)


def arg_latitude_rate(a: ArrayLike, inc: ArrayLike, j2: bool = True) -> np.ndarray:
    """Secular rate of the mean argument of latitude du/dt = n + kappa (P + Q) [rad/s] (n without J2).

    Parameters
    ----------
    a : array_like
        Semi-major axis [m] of the circular orbit.
    inc : array_like
        Inclination [rad]; broadcast with ``a``.
    j2 : bool
        With the J2 secular terms; False: the Keplerian mean motion n.

    Returns
    -------
    numpy.ndarray
        du/dt [rad/s], the broadcast shape of ``a`` and ``inc``.
    """
    return _arg_latitude_rate(a, inc, j2)


@per_chief(2)  # a chief's: once per (a, i, j2)
def _arg_latitude_rate(a, inc, j2):
    n = mean_motion(a)
    if not j2:
        return n
    c2 = np.cos(inc) ** 2
    return n + _kappa(a, n) * ((3.0 * c2 - 1.0) + (5.0 * c2 - 1.0))


def ballistic_coefficient(cd: ArrayLike, area: ArrayLike, mass: ArrayLike) -> np.ndarray | float:
    """Ballistic drag coefficient B = c_d A / m [m^2/kg] (seed 000 uses B, the inverse of the ballistic coefficient).

    Parameters
    ----------
    cd : array_like
        Drag coefficient (dimensionless).
    area : array_like
        Cross-section [m^2].
    mass : array_like
        Mass [kg].

    Returns
    -------
    float or numpy.ndarray
        B [m^2/kg], the broadcast shape of the inputs (a float for floats).
    """
    return cd * area / mass


def drag_da_dot(delta_b: ArrayLike, rho: ArrayLike, a: ArrayLike) -> np.ndarray:
    """Rate of the dimensionless relative semi-major axis under differential drag [1/s].

    Time derivative of seed 002 Eq. (24) with u - u0 = n t: d(da)/dt = -dB rho v^2 / (n a). Positive dB
    (picosatellite decays faster) lowers da.

    Parameters
    ----------
    delta_b : array_like
        Differential ballistic coefficient B_deputy - B_chief [m^2/kg].
    rho : array_like
        Atmospheric density [kg/m^3].
    a : array_like
        The chief's semi-major axis [m].

    Returns
    -------
    numpy.ndarray
        d(da)/dt [1/s], the broadcast shape of the inputs.
    """
    return -np.asarray(delta_b, dtype=float) * rho * circular_speed(a) ** 2 / (mean_motion(a) * a)


def drag_dix_dot(da_dot: ArrayLike, a: ArrayLike, inc: ArrayLike) -> np.ndarray:
    """Rate of the relative inclination vector's x-component [1/s] that differential drag drives through the
    atmosphere's rotation: d(dix)/dt = (omega_E a sin i / (4 v)) da_dot.

    The co-rotating atmosphere gives the drag a cross-track component proportional to omega_E r sin i cos u;
    Gauss's equation for di/dt (r cos u f_N / h) averaged over an orbit (<cos^2 u> = 1/2) lowers the inclination
    at di/dt = -B rho v omega_E sin i / (4 n) (King-Hele, *Theory of Satellite Orbits in an Atmosphere*, 1964,
    Ch. 5), and the difference of two spacecraft against d(da)/dt = -dB rho v^2 / (n a) (:func:`drag_da_dot`) is
    this ratio: 0.0164 at 515 km sun-synchronous (-1.3 m/day of a dix at a da_dot of -81 m/day, as the nonlinear
    truth shows).

    Parameters
    ----------
    da_dot : array_like
        Differential-drag rate of da [1/s] (:func:`drag_da_dot`).
    a : array_like
        The chief's semi-major axis [m].
    inc : array_like
        The chief's inclination [rad].

    Returns
    -------
    numpy.ndarray
        d(dix)/dt [1/s], the broadcast shape of the arguments.
    """
    return (EARTH_ROTATION * np.asarray(a, dtype=float) * np.sin(inc) / (4.0 * circular_speed(a))
            * np.asarray(da_dot, dtype=float))


def drag_short_period_de(da_dot: ArrayLike, a: ArrayLike, u: ArrayLike) -> np.ndarray:
    """Short-periodic relative eccentricity vector [dimensionless] ``(..., 2)`` of differential drag at mean argument
    of latitude ``u`` [rad]: (da_dot / n) (sin u, -cos u).

    A constant along-track acceleration f_T on a circular orbit drives de_x/dt = 2 f_T cos u / (n a), de_y/dt =
    2 f_T sin u / (n a) (Gauss's equations, e.g. Vallado Eq. 9-24 for e << 1), i.e. e = (2 f_T / (n^2 a)) (sin u,
    -cos u) about the mean; for the difference of two spacecraft 2 df_T / (n a) = d(da)/dt. First-order J2 mean
    elements (:func:`~roe_sep.core.truth.mean_osc.cartesian_to_mean`) keep it: 0.85 m of a de at a da_dot of
    -81 m/day at 515 km. In the relative position it is a constant along-track offset 2 a da_dot / n.

    Parameters
    ----------
    da_dot : array_like
        Differential-drag rate of da [1/s].
    a : array_like
        The chief's semi-major axis [m].
    u : array_like
        Mean argument of latitude [rad].

    Returns
    -------
    numpy.ndarray, shape (..., 2)
        (dex, dey) of the short-periodic term, the broadcast shape of the arguments.
    """
    k = np.asarray(da_dot, dtype=float) / mean_motion(a)
    u = np.asarray(u, dtype=float)
    return np.stack([k * np.sin(u), -k * np.cos(u)], axis=-1)


def propagate(roe: ArrayLike, dt: ArrayLike, a: float, inc: float, j2: bool = True, *,
              da_dot: ArrayLike = 0.0) -> np.ndarray:
    """Propagate dimensionless ROE over ``dt`` [s] with the secular model above (Keplerian alone: ``j2=False,
    da_dot=0``).

    Parameters
    ----------
    roe : array_like, shape (..., 6)
        Dimensionless ROE ``[da, dl, dex, dey, dix, diy]`` at the start.
    dt : array_like
        Propagation time [s]; broadcast against ``roe[..., 0]``.
    a : float
        The chief's semi-major axis [m].
    inc : float
        The chief's inclination [rad].
    j2 : bool
        With the J2 secular rates.
    da_dot : array_like
        Constant differential-drag rate of da [1/s] (:func:`drag_da_dot`); broadcast like ``dt``.

    Returns
    -------
    numpy.ndarray, shape (..., 6)
        The propagated ROE, the broadcast shape of ``roe``, ``dt`` and ``da_dot``.
    """
    r = np.asarray(roe, dtype=float)
    return stack_last(propagate_elements(components(r), dt, a, inc, j2, da_dot=da_dot))


def propagate_elements(elements: Sequence[ArrayLike], dt: ArrayLike, a: float, inc: float, j2: bool = True,
                       *, da_dot: ArrayLike = 0.0) -> tuple:
    """:func:`propagate` on the six ROE given apart, ``(da, dl, dex, dey, dix, diy)`` (arrays that broadcast with
    ``dt`` and ``da_dot``); returns the six propagated elements apart. The same arithmetic as :func:`propagate`
    (which is this function plus a stack), for vectorized callers that need only some elements: contiguous
    element arrays avoid the strided ``(..., 6)`` views and the stack.

    Parameters
    ----------
    elements : sequence of six array_like
        ``(da, dl, dex, dey, dix, diy)``, dimensionless, each of a shape that broadcasts with ``dt``.
    dt : array_like
        Propagation time [s].
    a : float
        The chief's semi-major axis [m].
    inc : float
        The chief's inclination [rad].
    j2 : bool
        With the J2 secular rates.
    da_dot : array_like
        Constant differential-drag rate of da [1/s].

    Returns
    -------
    tuple of six numpy.ndarray
        The propagated ``(da, dl, dex, dey, dix, diy)``, each of the broadcast shape.
    """
    return _elements(elements, np.asarray(dt, dtype=float), np.asarray(da_dot, dtype=float),
                     secular_rates(a, inc, j2))


def _elements(elements, dt, da_dot, rates, out_of_plane=True):
    """:func:`propagate_elements` with the chief's :class:`SecularRates` given (a caller that propagates several
    times with one chief looks them up once); ``dt`` must be an ndarray (0-d for one time): ``dt**2`` of an array is
    ``dt * dt``, of a scalar float ``pow(dt, 2)``, which can differ in the last bit. ``out_of_plane`` False: dix and
    diy are not formed (None), the other four are the same values."""
    da, dl, dex, dey, dix, diy = elements
    j2 = rates.e_rotation is not None
    da_int = da * dt + 0.5 * da_dot * dt**2
    if j2:
        dl_new = dl + rates.dl_da * da_int - rates.dl_dix * dix * dt
    else:
        dl_new = dl - rates.dl_da * da_int
    da_new, dex_new, dey_new = _in_plane(da, dex, dey, dt, da_dot, rates=rates)
    if not out_of_plane:
        return da_new, dl_new, dex_new, dey_new, None, None
    diy_new = diy + rates.diy_da * da_int + rates.diy_dix * dix * dt if j2 else diy + 0.0 * dt
    return da_new, dl_new, dex_new, dey_new, dix + 0.0 * dt, diy_new


def propagate_in_plane(da: ArrayLike, dex: ArrayLike, dey: ArrayLike, dt: ArrayLike, a: float, *, inc: float,
                       j2: bool = True, da_dot: ArrayLike = 0.0) -> tuple:
    """The da, dex and dey of :func:`propagate_elements` alone (what the radial motion R/a = da - dex cos u -
    dey sin u needs), with its arithmetic: the same values to the bit, without forming dl, dix and diy.

    Parameters
    ----------
    da, dex, dey : array_like
        The dimensionless elements, each of a shape that broadcasts with ``dt``.
    dt : array_like
        Propagation time [s].
    a : float
        The chief's semi-major axis [m].
    inc : float
        The chief's inclination [rad].
    j2 : bool
        With the J2 secular rates.
    da_dot : array_like
        Constant differential-drag rate of da [1/s].

    Returns
    -------
    tuple of three numpy.ndarray
        The propagated ``(da, dex, dey)``, each of the broadcast shape.
    """
    dt = np.asarray(dt, dtype=float)
    return _in_plane(da, dex, dey, dt, np.asarray(da_dot, dtype=float), rates=secular_rates(a, inc, j2))


def _in_plane(da, dex, dey, dt, da_dot, *, rates):
    """da under the drag drift and the e vector turned by J2: the in-plane part of :func:`propagate_elements`."""
    return (da + da_dot * dt, *_rotate_e(dex, dey, dt, rates))


class SecularRates(NamedTuple):
    """The coefficients of :func:`propagate_elements` for one chief (a, i): d(dl)/d(da) rate
    -(3/2 n + 7 kappa P) (3/2 n without J2, subtracted), 7 kappa sin 2i, 7/2 kappa sin 2i, 2 kappa sin^2 i and the
    e-vector rotation rate kappa Q [1/s] (None without J2)."""

    dl_da: float
    dl_dix: float | None
    diy_da: float | None
    diy_dix: float | None
    e_rotation: float | None


def secular_rates(a: ArrayLike, inc: ArrayLike, j2: bool = True) -> SecularRates:
    """The coefficients of :func:`propagate_elements` for one chief: computed once per (a, i, j2) for scalar floats
    (the values of the expressions of the module docstring, evaluated as :func:`propagate_elements` always did),
    afresh for arrays.

    Parameters
    ----------
    a : array_like
        The chief's semi-major axis [m].
    inc : array_like
        The chief's inclination [rad]; broadcast with ``a``.
    j2 : bool
        With the J2 secular rates.

    Returns
    -------
    SecularRates
        The coefficients (scalars for scalar ``a`` and ``inc``, else arrays of their broadcast shape).
    """
    return _secular_rates(a, inc, j2)


@per_chief(2)
def _secular_rates(a, inc, j2):
    n = mean_motion(a)
    if not j2:
        return SecularRates(1.5 * n, None, None, None, None)
    kap = _kappa(a, n)  # j2_kappa(a), and below its cos^2 i once: the values of the functions, each formed once
    c2 = np.cos(inc) ** 2
    p_fac = 3.0 * c2 - 1.0
    s2i = np.sin(2.0 * inc)
    # left to right as in 7.0 * kap * s2i * dix * dt: the scalar factors first
    return SecularRates(-(1.5 * n + 7.0 * kap * p_fac), 7.0 * kap * s2i, 3.5 * kap * s2i,
                        2.0 * kap * np.sin(inc) ** 2, kap * (5.0 * c2 - 1.0))  # the last: the e-vector rotation


def _rotate_e(dex, dey, dt, rates):
    """The relative e vector after ``dt``: rotated at kappa Q with J2, unchanged (broadcast) without."""
    if rates.e_rotation is None:
        return dex + 0.0 * dt, dey + 0.0 * dt
    phi = rates.e_rotation * dt
    cph, sph = np.cos(phi), np.sin(phi)
    return dex * cph - dey * sph, dex * sph + dey * cph


def propagate_chief(kep: ArrayLike, dt: ArrayLike, j2: bool = True) -> np.ndarray:
    """Secular propagation of the chief's mean Keplerian elements ``[a, e, i, raan, argp, M]`` over ``dt`` [s].

    raan and argp drift at the J2 rates above, M at n + kappa P (all frozen at the initial a, i; near-circular).

    Parameters
    ----------
    kep : array_like, shape (..., 6)
        Mean Keplerian elements ``[a, e, i, raan, argp, M]`` (m, 1, rad, rad, rad, rad).
    dt : array_like
        Propagation time [s]; ``dt.shape + (6,)`` broadcasts with ``kep``.
    j2 : bool
        With the J2 secular rates (False: M advances at n, the rest stays).

    Returns
    -------
    numpy.ndarray, shape (..., 6)
        The propagated elements (angles not wrapped), the broadcast shape of ``kep`` and ``dt.shape + (6,)``.
    """
    k = np.array(kep, dtype=float)
    dt = np.asarray(dt, dtype=float)
    a, inc = k[..., 0], k[..., 2]
    n = mean_motion(a)
    out = np.broadcast_to(k, np.broadcast_shapes(k.shape, dt.shape + (6,))).copy()
    if j2:
        # raan_rate's -2 kappa cos i, the e-vector and mean-anomaly rates: their expressions, kappa (j2_kappa),
        # cos i and cos^2 i formed once
        kap = _kappa(a, n)
        c = np.cos(inc)
        c2 = c ** 2
        out[..., 3] = k[..., 3] + -2.0 * kap * c * dt
        out[..., 4] = k[..., 4] + kap * (5.0 * c2 - 1.0) * dt
        out[..., 5] = k[..., 5] + (n + kap * (3.0 * c2 - 1.0)) * dt
    else:
        out[..., 5] = k[..., 5] + n * dt
    return out
