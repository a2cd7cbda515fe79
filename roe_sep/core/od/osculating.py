"""The osculating relative-position model of the offline OD, for a carrier known by its own ephemeris (issue 40).

radar_od's measurement model (:func:`roe_sep.core.od.radar.observe`) puts the picosatellite at the circular orbit of
the carrier's mean elements plus the linear (rectilinear) map of the mean ROE (D'Amico 2010, seed 002 Eq. 2):
r/a = [da - dex cos u - dey sin u, dl + 2 dex sin u - 2 dey cos u, dix sin u - diy cos u]. That is how the run's
radar simulates its measurements, so a run's own files are fitted exactly; against a real (numerically propagated)
pair it leaves three model errors the batch absorbs into the state: the map's second order (an along-track rho is a
chord of the orbit, radially rho^2 / (2 a) ~ 6 m at 9 km), the differential J2 short-period terms (Schaub &
Junkins Eq. F.7 at e = 0 differs by ~3 J2 (R/a)^2 sin^2 i a dl sin 2u between two spacecraft dl apart) and a circular
carrier (a = |r|, e = 0). Measured on Orekit's J2 propagation of the scenario (3 geometries, 5-9 km): up to 11.5 m.

Here instead, with the carrier's first-order Brouwer mean elements kep_c (Schaub & Junkins App. F, eccentricity
kept; :func:`~roe_sep.core.truth.mean_osc.cartesian_to_mean` of its ephemeris state) and the picosatellite's
kep_d = roe_to_kepler(kep_c, roe) (the inverse of D'Amico's definition, seed 002 Eq. 1), the picosatellite is

    x_d = x_c + X(osc(kep_d)) - X(osc(kep_c)),

x = (r, v), osc the first-order mean -> osculating map (Eqs. F.1-F.22), X Keplerian -> Cartesian (Vallado Alg. 10),
x_c the carrier's ephemeris state. The difference, not X(osc(kep_d)) alone: the theory's round trip
osc(mean(x_c)) misses x_c by O(J2^2) a (27 m measured), an error common to two spacecraft kilometres apart that
cancels in the difference (0.14 m at most against Orekit's truth on the same geometries). The map is nonlinear in
the ROE and carries the differential short-period J2 terms and the carrier's eccentricity.
"""

import numpy as np
from numpy.typing import ArrayLike

from ..relmotion.dynamics import propagate_chief
from ..relmotion.roe import roe_to_kepler
from ..truth.mean_osc import kepler_to_cartesian, mean_to_osculating


def osculating_state(kep_mean: ArrayLike) -> np.ndarray:
    """Position [m] and velocity [m/s] ``(..., 2, 3)`` of mean elements ``[a, e, i, raan, argp, M]`` ``(..., 6)``:
    first-order Brouwer mean -> osculating (Schaub & Junkins Eqs. F.1-F.22), then Vallado Alg. 10. M is taken modulo
    2 pi first: the map's equation of the centre f - M (F.11-F.13) holds for |M| < 2 pi only (f comes back within
    +-2 pi), and propagated elements are not wrapped."""
    kep_mean = np.array(kep_mean, dtype=float)
    kep_mean[..., 5] = np.mod(kep_mean[..., 5], 2.0 * np.pi)
    r, v = kepler_to_cartesian(mean_to_osculating(kep_mean))
    return np.stack([r, v], axis=-2)


def relative_state(roe: ArrayLike, chief_mean: ArrayLike) -> np.ndarray:
    """X(osc(kep_d)) - X(osc(kep_c)) (module docstring): the picosatellite's inertial position [m] and velocity
    [m/s] relative to the carrier ``(..., 2, 3)``, kep_d = roe_to_kepler(kep_c, roe) (seed 002 Eq. 1 inverted).

    Parameters
    ----------
    roe : array_like, shape (..., 6)
        Dimensionless mean ROE [da, dl, dex, dey, dix, diy].
    chief_mean : array_like, shape (..., 6)
        The carrier's mean elements ``[a, e, i, raan, argp, M]`` (m, rad), broadcast with ``roe``.

    Returns
    -------
    numpy.ndarray, shape (..., 2, 3)
        Relative position [m] and velocity [m/s] in the inertial frame of the elements.
    """
    roe = np.asarray(roe, dtype=float)
    chief_mean = np.asarray(chief_mean, dtype=float)
    return osculating_state(roe_to_kepler(chief_mean, roe)) - osculating_state(chief_mean)


def deputy_state(roe: ArrayLike, chief_mean: ArrayLike, carrier: ArrayLike) -> np.ndarray:
    """The picosatellite's inertial position [m] and velocity [m/s] ``(..., 2, 3)``: the carrier's ephemeris
    state plus :func:`relative_state`.

    Parameters
    ----------
    roe, chief_mean : array_like, shapes (..., 6)
        As for :func:`relative_state`.
    carrier : array_like, shape (..., 2, 3)
        The carrier's inertial position [m] and velocity [m/s] (its own ephemeris) at the elements' epoch.

    Returns
    -------
    numpy.ndarray, shape (..., 2, 3)
        Position and velocity.
    """
    return np.asarray(carrier, dtype=float) + relative_state(roe, chief_mean)


def carrier_state(state: ArrayLike, chief_mean: ArrayLike, dt: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """The carrier ``dt`` [s] from an ephemeris state: its mean elements carried with the J2 secular rates
    (:func:`~roe_sep.core.relmotion.dynamics.propagate_chief`) and the state moved by their osculating change,
    x(t + dt) = x(t) + X(osc(kep(t + dt))) - X(osc(kep(t))) (exactly x(t) at dt = 0; the first-order theory's
    error then enters only through its change over dt).

    Parameters
    ----------
    state : array_like, shape (..., 2, 3)
        Position [m] and velocity [m/s] at t.
    chief_mean : array_like, shape (..., 6)
        Its mean elements at t.
    dt : array_like, shape (...)
        Times after t [s].

    Returns
    -------
    (numpy.ndarray, numpy.ndarray), shapes (..., 6) and (..., 2, 3)
        The mean elements and the state at t + dt.
    """
    chief_mean = np.asarray(chief_mean, dtype=float)
    kep = propagate_chief(chief_mean, np.asarray(dt, dtype=float))
    return kep, np.asarray(state, dtype=float) + (osculating_state(kep) - osculating_state(chief_mean))


def carrier_between(states: ArrayLike, chief_mean: ArrayLike, times: ArrayLike,
                    t: float) -> tuple[np.ndarray, np.ndarray]:
    """The carrier at ``t`` between two ephemeris states: each carried to ``t`` by :func:`carrier_state` and blended
    linearly in time, x = (1 - s) x_0(t) + s x_1(t), s = (t - t_0) / (t_1 - t_0). Carried alone, a state errs by the
    change of the first-order theory's round-trip error (~30 m at twice the orbital rate: ~3 m after 60 s); blended,
    by its second difference, ~|d2/dt2| (t - t_0) (t_1 - t) / 2: measured against a numerical J2 orbit at 515 km,
    0.5 m at most between states 120 s apart, 2.9 m 300 s apart (a few mm between Orekit's 10-s states).

    Parameters
    ----------
    states : array_like, shape (2, 2, 3)
        The states [m, m/s] before and after ``t``.
    chief_mean : array_like, shape (2, 6)
        Their mean elements.
    times : array_like, shape (2,)
        Their times t_0 < t_1 [s].
    t : float
        The time [s], t_0 <= t <= t_1.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray), shapes (6,) and (2, 3)
        The mean elements (the later state's, carried) and the state at ``t``.
    """
    times = np.asarray(times, dtype=float)
    kep, x = carrier_state(states, chief_mean, t - times)
    s = (t - times[0]) / (times[1] - times[0])
    return kep[1], (1.0 - s) * x[0] + s * x[1]


def roe_jacobian(roe: ArrayLike, chief_mean: ArrayLike, step: float = 1.0) -> np.ndarray:
    """d(relative position, velocity) / d(roe) ``(6, 6)`` of :func:`relative_state` at one state, by central
    differences of ``step`` [m] in each a*ROE (the map's curvature, ~1 / a, is far below that step's rounding).

    Parameters
    ----------
    roe, chief_mean : array_like, shapes (6,)
        As for :func:`relative_state`.
    step : float
        The step of a*roe [m].

    Returns
    -------
    numpy.ndarray, shape (6, 6)
        Rows [r (m), v (m/s)], columns the dimensionless ROE.
    """
    roe = np.asarray(roe, dtype=float)
    chief_mean = np.asarray(chief_mean, dtype=float)
    h = step / chief_mean[0]
    pert = roe + np.concatenate([np.eye(6), -np.eye(6)]) * h
    x = relative_state(pert, chief_mean).reshape(12, 6)
    return ((x[:6] - x[6:]) / (2.0 * h)).T
