"""Ground-station radar geometry and measurement model (seed 001 Sec. 5: radar tracking of the picosatellite).

Frames and models:

* Time: sim time ``t`` [s] counts from a calendar epoch given as a Julian date ``jd0`` (UTC).
* Earth orientation: the inertial frame is the GCRF; Earth-fixed = ITRF, rotated by the matrix of
  :func:`roe_sep.core.frames.gcrs_to_itrs` (the one Earth-orientation model: ERFA's IAU 2000B with frame bias,
  Earth rotation angle of UT1, polar motion, IERS EOP). The chief's RAAN is referred to the GCRF equator and origin.
* Chief (carrier): its *mean* near-circular elements (a, i, raan, u) are used as if they were osculating
  (:func:`chief_position_velocity`, circular orbit, e neglected). The short-periodic J2 terms (~km) and the
  eccentricity (a e ~ km for a frozen orbit) shift the absolute position of both spacecraft together; the relative
  geometry the radar must separate is unaffected. Simulator and estimator use the same model.
* Picosatellite: chief + RTN relative position of the linear ROE map :func:`~roe_sep.core.relmotion.roe.roe_to_rtn`
  (rectilinear, so an along-track offset y leaves the sphere by y^2 / (2 a): 65 m at 30 km, common to truth and
  model of this stub).
* Stations: geodetic latitude/longitude/ellipsoidal height on WGS-84 (:func:`geodetic_to_ecef`); look angles in
  the local East-North-Up frame, azimuth from north towards east, no refraction.
* Measurements (:func:`observe`, :func:`two_way_look`): as a radar measures and the TDM declares them
  (``PATH = 1,2,1``, ``TIMETAG_REF = RECEIVE``): the two-way light-time range at the receive time tag, half the
  round trip c (tau_up + tau_down) / 2 of a signal that left the station at t - tau_down - tau_up, was reflected
  at t - tau_down and came back at t; the azimuth and elevation of the received signal, the direction to the
  picosatellite where it was at the reflection (no aberration, no refraction). The light time (4-6 ms) moves the
  picosatellite by 30-45 m along its orbit and the station by 1-3 m.
"""

import math
from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime, timezone

import numpy as np
from numpy.typing import ArrayLike

from ..constants import EARTH_ROTATION, MU_EARTH, R_EARTH, SECONDS_PER_DAY, SPEED_OF_LIGHT
from ..relmotion.roe import components, rtn_position, stack_last

WGS84_A = R_EARTH
"""WGS-84 semi-major axis [m]."""

WGS84_F = 1.0 / 298.257223563
"""WGS-84 flattening."""

WGS84_E2 = WGS84_F * (2.0 - WGS84_F)
"""WGS-84 first eccentricity squared."""

DEFAULT_EPOCH_UTC = "2016-07-01T00:00:00"
"""Calendar epoch of sim time 0 in the default scenario (the date of seed 001's operational plan)."""

JD_J2000 = 2451545.0
"""Julian date of the J2000.0 epoch (2000-01-01 12:00)."""

JD_UNIX_EPOCH = 2440587.5
"""Julian date of 1970-01-01 00:00 UTC."""


def julian_date(epoch_utc: datetime | str) -> float:
    """Julian date of a UTC calendar epoch: JD = 2440587.5 + (POSIX seconds) / 86400.

    ``epoch_utc`` is a :class:`datetime` or an ISO-8601 string (``2016-07-01T00:00:00``, optional ``Z`` or
    ``+hh:mm``); a naive value is taken as UTC. POSIX time has no leap seconds, so this is the UTC Julian date
    (:mod:`roe_sep.core.frames` takes it to TT and UT1). Raises ValueError for an unparseable string.
    """
    if isinstance(epoch_utc, str):
        text = epoch_utc.strip()
        if text.endswith(("Z", "z")):
            text = text[:-1] + "+00:00"
        epoch_utc = datetime.fromisoformat(text)
    if epoch_utc.tzinfo is None:
        epoch_utc = epoch_utc.replace(tzinfo=timezone.utc)
    return JD_UNIX_EPOCH + epoch_utc.timestamp() / SECONDS_PER_DAY


def sun_right_ascension(jd: ArrayLike) -> np.ndarray:
    """Apparent right ascension of the Sun [rad, -pi..pi), low precision (Astronomical Almanac, Sec. C, 0.01 deg
    in 1950-2050).

    n = JD - 2451545.0; L = 280.460 + 0.9856474 n; g = 357.528 + 0.9856003 n (deg);
    lambda = L + 1.915 sin g + 0.020 sin 2g; eps = 23.439 - 0.0000004 n; alpha = atan2(cos eps sin lambda, cos lambda).
    """
    n = np.asarray(jd, dtype=float) - JD_J2000
    mean_lon = np.radians(280.460 + 0.9856474 * n)
    g = np.radians(357.528 + 0.9856003 * n)
    lam = mean_lon + np.radians(1.915) * np.sin(g) + np.radians(0.020) * np.sin(2.0 * g)
    eps = np.radians(23.439 - 0.0000004 * n)
    return np.arctan2(np.cos(eps) * np.sin(lam), np.cos(lam))


def sun_direction(jd: ArrayLike) -> np.ndarray:
    """The unit vector ``(..., 3)`` to the Sun in the equator and equinox of date: the ecliptic longitude lambda and
    obliquity eps of :func:`sun_right_ascension` (the same low-precision formulas), (cos lambda, cos eps sin lambda,
    sin eps sin lambda).

    Parameters
    ----------
    jd : array_like, shape (...)
        The Julian date (UTC).

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        The unit Sun direction, inertial.
    """
    n = np.asarray(jd, dtype=float) - JD_J2000
    mean_lon = np.radians(280.460 + 0.9856474 * n)
    g = np.radians(357.528 + 0.9856003 * n)
    lam = mean_lon + np.radians(1.915) * np.sin(g) + np.radians(0.020) * np.sin(2.0 * g)
    eps = np.radians(23.439 - 0.0000004 * n)
    return stack_last([np.cos(lam), np.cos(eps) * np.sin(lam), np.sin(eps) * np.sin(lam)])


def raan_from_sun(sun_ra: ArrayLike, ltan_hours: float) -> np.ndarray:
    """RAAN [rad, 0..2pi) of an orbit whose ascending node is at local time ``ltan_hours`` when the Sun is at right
    ascension ``sun_ra``: raan = alpha_sun + (LTAN - 12 h) * 15 deg/h (the node is LTAN - 12 h of hour angle east
    of the Sun)."""
    return np.mod(np.asarray(sun_ra, dtype=float) + (np.asarray(ltan_hours, dtype=float) - 12.0) * (np.pi / 12.0),
                  2.0 * np.pi)


def raan_from_ltan(ltan_hours: float, jd: ArrayLike) -> np.ndarray:
    """:func:`raan_from_sun` with the low-precision *apparent* Sun of :func:`sun_right_ascension` on date ``jd``,
    i.e. LTAN in apparent solar time; for mean solar time add the equation of time (at most 16 min, 4 deg of RAAN).
    BIROS: LTAN 09:30 (seed 002)."""
    return raan_from_sun(sun_right_ascension(jd), ltan_hours)


def geodetic_to_ecef(lat: ArrayLike, lon: ArrayLike, alt: ArrayLike) -> np.ndarray:
    """Earth-fixed position [m] of geodetic latitude/longitude [rad] and ellipsoidal height [m] on WGS-84.

    N = a / sqrt(1 - e^2 sin^2 lat):  x = (N + h) cos lat cos lon,  y = (N + h) cos lat sin lon,
    z = (N (1 - e^2) + h) sin lat.

    Parameters
    ----------
    lat, lon, alt : array_like, shape (...)
        Geodetic latitude and longitude [rad], ellipsoidal height [m].

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        The position [m].
    """
    lat, lon, alt = (np.asarray(v, dtype=float) for v in (lat, lon, alt))
    n = WGS84_A / np.sqrt(1.0 - WGS84_E2 * np.sin(lat) ** 2)
    return np.stack([(n + alt) * np.cos(lat) * np.cos(lon), (n + alt) * np.cos(lat) * np.sin(lon),
                     (n * (1.0 - WGS84_E2) + alt) * np.sin(lat)], axis=-1)


def enu_matrix(lat: ArrayLike, lon: ArrayLike) -> np.ndarray:
    """Rotation Earth-fixed -> local East-North-Up at geodetic ``lat``/``lon`` [rad]: rows E, N, U, ``(..., 3, 3)``.

    E = (-sin lon, cos lon, 0), N = (-sin lat cos lon, -sin lat sin lon, cos lat), U = (cos lat cos lon,
    cos lat sin lon, sin lat).
    """
    lat, lon = np.asarray(lat, dtype=float), np.asarray(lon, dtype=float)
    sl, cl, sp, cp = np.sin(lon), np.cos(lon), np.sin(lat), np.cos(lat)
    z = np.zeros_like(sl * sp)
    return np.stack([np.stack([-sl + z, cl + z, z], -1), np.stack([-sp * cl, -sp * sl, cp + z], -1),
                     np.stack([cp * cl, cp * sl, sp + z], -1)], axis=-2)


@dataclass(frozen=True)
class Station:
    """A ground station: name, geodetic latitude/longitude [rad], ellipsoidal height [m] (WGS-84)."""

    name: str
    lat: float
    lon: float
    alt: float

    @property
    def ecef(self) -> np.ndarray:
        """Earth-fixed position [m], :func:`geodetic_to_ecef`."""
        return geodetic_to_ecef(self.lat, self.lon, self.alt)

    @property
    def enu(self) -> np.ndarray:
        """Earth-fixed -> ENU rotation, :func:`enu_matrix`."""
        return enu_matrix(self.lat, self.lon)


TIRA = Station("TIRA", math.radians(50.6166), math.radians(7.1296), 300.0)
"""FHR's Tracking and Imaging Radar, Wachtberg near Bonn: 50.6166 N, 7.1296 E; the site is at about 260 m above sea
level (the nearby highest point of Wachtberg is 269 m) and the geoid is about 47 m above WGS-84 there, so about
300 m ellipsoidal height."""


def chief_position_velocity(a: ArrayLike, inc: ArrayLike, raan: ArrayLike,
                            u: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Inertial position [m] and velocity [m/s] of a circular orbit at argument of latitude ``u`` [rad].

    r = a (cos raan cos u - sin raan sin u cos i,  sin raan cos u + cos raan sin u cos i,  sin u sin i),
    v = sqrt(mu / a) (-cos raan sin u - sin raan cos u cos i,  -sin raan sin u + cos raan cos u cos i,  cos u sin i).
    Mean elements used as osculating (see the module docstring).

    Parameters
    ----------
    a, inc, raan, u : array_like, shape (...)
        Semi-major axis [m], inclination, RAAN and argument of latitude [rad].

    Returns
    -------
    (numpy.ndarray, numpy.ndarray), each shape (..., 3)
        Position [m] and velocity [m/s].
    """
    a, inc, raan, u = (np.asarray(v, dtype=float) for v in (a, inc, raan, u))
    co, so, ci, si, cu, su = np.cos(raan), np.sin(raan), np.cos(inc), np.sin(inc), np.cos(u), np.sin(u)
    r = a[..., None] * stack_last([co * cu - so * su * ci, so * cu + co * su * ci, su * si])
    v = np.sqrt(MU_EARTH / a)[..., None] * stack_last([-co * su - so * cu * ci, -so * su + co * cu * ci, cu * si])
    return r, v


def rtn_matrix(r: ArrayLike, v: ArrayLike) -> np.ndarray:
    """RTN -> inertial rotation ``(..., 3, 3)`` whose columns are R = r/|r|, T = N x R, N = (r x v)/|r x v|."""
    r, v = np.asarray(r, dtype=float), np.asarray(v, dtype=float)
    er = r / np.linalg.norm(r, axis=-1, keepdims=True)
    h = _cross(r, v)
    en = h / np.linalg.norm(h, axis=-1, keepdims=True)
    return stack_last([er, _cross(en, er), en])


def _cross(a, b):
    """a x b of ``(..., 3)`` arrays: :func:`numpy.cross`'s products and differences (a1 b2 - a2 b1, a2 b0 - a0 b2,
    a0 b1 - a1 b0), the same values, without its general-axis set-up (a few microseconds a call)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return stack_last([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def chief_from_kepler(kep: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(a, i, raan, u) of mean Keplerian elements ``[a, e, i, raan, argp, M]`` (u = argp + M)."""
    k = np.asarray(kep, dtype=float)
    return k[..., 0], k[..., 2], k[..., 3], k[..., 4] + k[..., 5]


def deputy_position(roe: ArrayLike, chief_kep: ArrayLike, rel: ArrayLike | None = None) -> np.ndarray:
    """Inertial position [m] of the picosatellite: chief + RTN relative position.

    r = r_chief + [R T N] (a * roe_to_rtn(roe, u)[0]), with the chief from :func:`chief_position_velocity` at its
    mean elements. Broadcasts over leading axes.

    Parameters
    ----------
    roe, chief_kep : array_like, shape (..., 6)
        Dimensionless ROE; the chief's mean elements ``[a, e, i, raan, argp, M]``.
    rel : array_like, shape (..., 3), optional
        ``rtn_position(roe, u)`` when the caller has it (u = argp + M of ``chief_kep``).

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        The position [m].
    """
    return _deputy(roe, chief_kep, rel)[0]


def _deputy(roe, chief_kep, rel):
    """:func:`deputy_position` and the chief's velocity (the picosatellite's to the relative velocity, ~ n rho:
    a few m/s, i.e. centimetres over a light time)."""
    a, inc, raan, u = chief_from_kepler(chief_kep)
    rc, vc = chief_position_velocity(a, inc, raan, u)
    rel = (rtn_position(roe, u) if rel is None else rel) * a[..., None]
    return rc + np.einsum("...ij,...j->...i", rtn_matrix(rc, vc), rel), vc


def relative_distance(roe: ArrayLike, a: ArrayLike, u: ArrayLike, rel: ArrayLike | None = None) -> np.ndarray:
    """|relative position| of the linear ROE map, a |roe_to_rtn(roe, u)[0]|: the radar separability distance.

    Parameters
    ----------
    roe, a, u : array_like
        Dimensionless ROE ``(..., 6)``, the chief's semi-major axis [m] and argument of latitude [rad].
    rel : array_like, shape (..., 3), optional
        ``rtn_position(roe, u)`` when the caller has it.

    Returns
    -------
    numpy.ndarray, shape (...)
        The distance [m].
    """
    return np.linalg.norm(rtn_position(roe, u) if rel is None else rel, axis=-1) * np.asarray(a, dtype=float)


def look_angles(r_ef: ArrayLike, site_ef: ArrayLike, site_enu: ArrayLike) -> np.ndarray:
    """Range [m], azimuth [rad, 0..2pi, from north towards east] and elevation [rad] of Earth-fixed ``r_ef``.

    rho = r - site rotated to ENU (``site_enu`` from :func:`enu_matrix`): range = |rho|,
    az = atan2(E, N), el = atan2(U, sqrt(E^2 + N^2)).

    Parameters
    ----------
    r_ef : array_like, shape (..., 3)
        The Earth-fixed position [m].
    site_ef, site_enu : array_like, shapes (3,) and (3, 3)
        The station's Earth-fixed position [m] and ENU rotation (:attr:`Station.ecef`, :attr:`Station.enu`).

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        [range, az, el].
    """
    d = np.asarray(r_ef, dtype=float) - np.asarray(site_ef, dtype=float)
    e, n, up = components(np.einsum("...ij,...j->...i", site_enu, d))
    return stack_last([np.sqrt(e * e + n * n + up * up), np.mod(np.arctan2(e, n), 2.0 * np.pi),
                       np.arctan2(up, np.hypot(e, n))])


def look_position(z: np.ndarray, site_ef: ArrayLike, site_enu: ArrayLike) -> np.ndarray:
    """Inverse of :func:`look_angles`: ENU = range (cos el sin az, cos el cos az, sin el), r = site + ENU^T rotated
    back.

    Parameters
    ----------
    z : numpy.ndarray, shape (..., 3)
        [range, az, el] [m, rad, rad].
    site_ef, site_enu : array_like, shapes (3,) and (3, 3)
        The station's Earth-fixed position [m] and ENU rotation (:attr:`Station.ecef`, :attr:`Station.enu`).

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        The Earth-fixed position [m].
    """
    z = np.asarray(z, dtype=float)
    rng, az, el = z[..., 0], z[..., 1], z[..., 2]
    enu = rng[..., None] * np.stack([np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)], axis=-1)
    return np.asarray(site_ef, dtype=float) + np.einsum("...ji,...j->...i", site_enu, enu)


def two_way_position(z: ArrayLike, v_ef: ArrayLike, site_ef: ArrayLike, site_enu: ArrayLike) -> np.ndarray:
    """Inverse of :func:`two_way_look` to first order in v / c: the target's position at the receive tag in the
    Earth-fixed axes, given its velocity in those axes.

    Down-leg length rho_d = range - u . (omega_E z x s) tau (u the line of sight, tau = range / c: the station's
    motion between transmission and reception), the reflection point :func:`look_position` of [rho_d, az, el], then
    p = p_B + v rho_d / c.

    Parameters
    ----------
    z : array_like, shape (..., 3)
        [two-way range, az, el] [m, rad, rad].
    v_ef : array_like, shape (..., 3)
        The target's inertial velocity [m/s] in the Earth-fixed axes of the tag.
    site_ef, site_enu : array_like, shapes (3,) and (3, 3)
        The station's Earth-fixed position [m] and ENU rotation (:attr:`Station.ecef`, :attr:`Station.enu`).

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        The target's position [m] at the tag.
    """
    z = np.asarray(z, dtype=float)
    s = np.asarray(site_ef, dtype=float)
    ws = EARTH_ROTATION * np.stack([-s[..., 1], s[..., 0], np.zeros_like(s[..., 0])], axis=-1)
    unit = look_position(np.concatenate([np.ones_like(z[..., :1]), z[..., 1:]], axis=-1), s, site_enu) - s
    tau = z[..., 0] / SPEED_OF_LIGHT
    rho_d = z[..., 0] - np.sum(unit * ws, axis=-1) * tau
    p_b = look_position(np.concatenate([rho_d[..., None], z[..., 1:]], axis=-1), s, site_enu)
    return p_b + np.asarray(v_ef, dtype=float) * (rho_d / SPEED_OF_LIGHT)[..., None]


def observe(roe: ArrayLike, chief_kep: ArrayLike, earth: ArrayLike, site_ef: ArrayLike,
            site_enu: ArrayLike) -> np.ndarray:
    """The measurement function: [two-way range, az, el] of the picosatellite seen from a station at the receive
    time tag (module docstring).

    :func:`deputy_earth_fixed_state` -> :func:`two_way_look`. Broadcasts over leading axes (epochs, samples).

    Parameters
    ----------
    roe, chief_kep, earth
        As for :func:`deputy_earth_fixed_state`.
    site_ef, site_enu : array_like, shapes (3,) and (3, 3)
        The station's Earth-fixed position [m] and ENU rotation (:attr:`Station.ecef`, :attr:`Station.enu`).

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        [range, az, el] [m, rad, rad].
    """
    return two_way_look(deputy_earth_fixed_state(roe, chief_kep, earth), site_ef, site_enu)


def deputy_earth_fixed_state(roe: ArrayLike, chief_kep: ArrayLike, earth: ArrayLike,
                             rel: ArrayLike | None = None) -> np.ndarray:
    """The picosatellite's inertial position and velocity expressed in the Earth-fixed axes of the epoch:
    :func:`deputy_position` and the chief's velocity (the picosatellite's to the relative velocity, ~ n rho: a few
    m/s, centimetres over a light time) rotated by ``earth`` (the same for every station: formed once for several).

    Parameters
    ----------
    roe, chief_kep, rel
        As for :func:`deputy_position`.
    earth : array_like, shape (..., 3, 3)
        The GCRS -> ITRS rotation of the epochs (:func:`roe_sep.core.frames.gcrs_to_itrs`).

    Returns
    -------
    numpy.ndarray, shape (..., 2, 3)
        Position [m] and velocity [m/s].
    """
    r, v = _deputy(roe, chief_kep, rel)
    r, v = np.einsum("...ij,...j->...i", earth, r), np.einsum("...ij,...j->...i", earth, v)
    return np.stack(np.broadcast_arrays(r, v), axis=-2)


def carrier_earth_fixed_state(chief_kep: ArrayLike, earth: ArrayLike) -> np.ndarray:
    """The carrier's inertial position and velocity in the Earth-fixed axes of the epoch: the state of
    :func:`deputy_earth_fixed_state` at zero ROE (the sensor's carrier ranges and the OD's model of them).

    Parameters
    ----------
    chief_kep : array_like, shape (..., 6)
        The chief's elements ``[a, e, i, raan, argp, M]``.
    earth : array_like, shape (..., 3, 3)
        The GCRS -> ITRS rotation of the epochs.

    Returns
    -------
    numpy.ndarray, shape (..., 2, 3)
        Position [m] and velocity [m/s].
    """
    chief_kep = np.asarray(chief_kep, dtype=float)
    return deputy_earth_fixed_state(np.zeros(chief_kep.shape[:-1] + (6,)), chief_kep, earth)


def two_way_look(state_ef: ArrayLike, site_ef: ArrayLike, site_enu: ArrayLike, *, iterations: int = 2) -> np.ndarray:
    """[range, az, el] of a two-way radar measurement with the receive time tag.

    Inertial geometry in the Earth-fixed axes of the tag, linear motion over the light time (its error:
    a tau^2 / 2 ~ 0.1 mm): down leg c tau_d = |p - v tau_d - s|, reflection point p_B = p - v tau_d; up leg
    c tau_u = |p_B - s + (omega_E z x s)(tau_d + tau_u)| (the station moves with the Earth's rotation);
    ``iterations`` fixed-point steps each, each gaining a factor v / c ~ 2.5e-5 from tau = |p - s| / c.
    Range = c (tau_d + tau_u) / 2; az, el of p_B from the station at the tag (:func:`look_angles`).

    Parameters
    ----------
    state_ef : array_like, shape (..., 2, 3)
        The target's position [m] and velocity [m/s] at the tag in those axes (:func:`deputy_earth_fixed_state`).
    site_ef, site_enu : array_like, shapes (3,) and (3, 3)
        The station's Earth-fixed position [m] and ENU rotation (:attr:`Station.ecef`, :attr:`Station.enu`).
    iterations : int
        Fixed-point steps of each leg.

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        [range, az, el] [m, rad, rad].
    """
    state_ef = np.asarray(state_ef, dtype=float)
    p, v = state_ef[..., 0, :], state_ef[..., 1, :]
    s = np.asarray(site_ef, dtype=float)
    ws = EARTH_ROTATION * np.stack([-s[..., 1], s[..., 0], np.zeros_like(s[..., 0])], axis=-1)
    tau_d = np.linalg.norm(p - s, axis=-1) / SPEED_OF_LIGHT
    for _ in range(iterations):
        tau_d = np.linalg.norm(p - v * tau_d[..., None] - s, axis=-1) / SPEED_OF_LIGHT
    p_b = p - v * tau_d[..., None]
    tau_u = tau_d
    for _ in range(iterations):
        tau_u = np.linalg.norm(p_b - s + ws * (tau_d + tau_u)[..., None], axis=-1) / SPEED_OF_LIGHT
    z = look_angles(p_b, s, site_enu)
    z[..., 0] = 0.5 * SPEED_OF_LIGHT * (tau_d + tau_u)
    return z


def chief_elevation(chief_kep: ArrayLike, earth: ArrayLike, site_ef: ArrayLike, site_enu: ArrayLike) -> np.ndarray:
    """Elevation of the chief itself (roe = 0) from a station: the carrier's passes.

    Parameters
    ----------
    chief_kep, earth, site_ef, site_enu
        As for :func:`observe`.

    Returns
    -------
    numpy.ndarray, shape (...)
        The elevation [rad].
    """
    return observe(np.zeros(6), chief_kep, earth, site_ef, site_enu)[..., 2]


def visible(elevation: ArrayLike, mask: float) -> np.ndarray:
    """True where the elevation is above the mask [rad]."""
    return np.asarray(elevation, dtype=float) > mask


def pass_windows(elevation: Callable[[np.ndarray], np.ndarray], t_start: float, t_end: float, mask: float,
                 step: float = 30.0, *, tol: float = 0.01) -> np.ndarray:
    """Rise/set times of the passes above ``mask``: scan on a ``step`` grid, then refine every sign change of
    elevation - mask by simultaneous bisection down to ``tol``. A pass in progress at ``t_start`` (``t_end``) starts
    (ends) there. Passes shorter than ``step`` can fall between grid points and be missed (the default 30 s is far
    below the minutes a LEO pass above a 10 deg mask lasts).

    Parameters
    ----------
    elevation : callable
        ``elevation(t)`` [rad], vectorized over an array of times [s].
    t_start, t_end, mask : float
        The interval [s] and the mask [rad].
    step, tol : float
        The scan step and the bisection tolerance [s].

    Returns
    -------
    numpy.ndarray, shape (k, 2)
        Rise and set times [s].
    """
    t = np.arange(t_start, t_end, step, dtype=float)
    t = np.append(t, float(t_end))
    up = visible(elevation(t), mask)
    change = np.nonzero(up[1:] != up[:-1])[0]
    lo, hi = t[change].copy(), t[change + 1].copy()
    rising = ~up[change]
    while lo.size and np.max(hi - lo) > tol:
        mid = 0.5 * (lo + hi)
        same = visible(elevation(mid), mask) == up[change]  # mid still on the 'before' side of the crossing
        lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
    cross = 0.5 * (lo + hi)
    rises = list(cross[rising])
    sets = list(cross[~rising])
    if up[0]:
        rises.insert(0, t[0])
    if up[-1]:
        sets.append(t[-1])
    return np.array([rises, sets], dtype=float).T.reshape(-1, 2)


def truth_da_rate(t0: float, roe0: ArrayLike, t1: float, roe1: ArrayLike) -> float:
    """The drift of da [1/s] between two truth samples, (da1 - da0) / (t1 - t0): what a measurement between them
    is simulated with (:func:`~roe_sep.core.relmotion.dynamics.propagate`'s ``da_dot``) instead of the later
    sample's da. Differential drag moves a da by about -70 m/day in the default scenario, so a measurement that
    took the sample's da at a truth period of 60 s would see a da 30 s ahead of its epoch on average: 2.4 cm of
    bias, four sigmas of a two-day batch's best-known direction.

    Parameters
    ----------
    t0, t1 : float
        The samples' epochs [s], t1 > t0.
    roe0, roe1 : array_like, shape (6,)
        Their dimensionless ROE.

    Returns
    -------
    float
        The rate [1/s]; 0 when t1 <= t0.
    """
    if not t1 > t0:
        return 0.0
    return float((roe1[0] - roe0[0]) / (t1 - t0))


def add_noise(z: ArrayLike, sigma: ArrayLike, rng: np.random.Generator) -> np.ndarray:
    """Noisy measurements: z + N(0, sigma) per component (range [m], az, el [rad]), azimuth wrapped to 0..2pi.

    Parameters
    ----------
    z, sigma : array_like, shape (..., 3)
        The measurements and their 1-sigma.
    rng : numpy.random.Generator
        Seeded by the caller for reproducibility.

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        The noisy measurements.
    """
    z = np.asarray(z, dtype=float)
    out = z + np.asarray(sigma, dtype=float) * rng.standard_normal(z.shape)
    out[..., 1] = np.mod(out[..., 1], 2.0 * np.pi)
    return out
