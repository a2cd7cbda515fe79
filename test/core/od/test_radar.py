"""Radar geometry against hand and published values: time, Earth rotation, WGS-84, look angles, passes over TIRA."""

import math
from datetime import datetime, timedelta, timezone

import erfa
import numpy as np
import pytest

from roe_sep.core.constants import EARTH_ROTATION, MU_EARTH
from roe_sep.core.frames import gcrs_to_itrs
from roe_sep.core.od.radar import (
    TIRA,
    WGS84_A,
    WGS84_E2,
    Station,
    add_noise,
    chief_elevation,
    chief_from_kepler,
    chief_position_velocity,
    deputy_position,
    enu_matrix,
    geodetic_to_ecef,
    julian_date,
    look_angles,
    look_position,
    observe,
    pass_windows,
    raan_from_ltan,
    relative_distance,
    rtn_matrix,
    sun_right_ascension,
    truth_da_rate,
    two_way_look,
    two_way_position,
    visible,
)
from roe_sep.core.relmotion.dynamics import propagate_chief, sun_synchronous_inclination
from roe_sep.core.relmotion.orbit import semi_major_axis
from roe_sep.core.relmotion.roe import roe_to_rtn

A = float(semi_major_axis(515e3))
INC = float(sun_synchronous_inclination(A))
JD0 = julian_date("2016-07-01T00:00:00")
MASK = math.radians(10.0)


def test_julian_date():
    assert julian_date("2000-01-01T12:00:00") == 2451545.0
    assert julian_date("2016-07-01T00:00:00") == 2457570.5
    assert julian_date("2016-07-01T00:00:00Z") == 2457570.5
    assert julian_date("2016-07-01T02:00:00+02:00") == 2457570.5
    assert julian_date(datetime(2016, 7, 1, 6, tzinfo=timezone.utc)) == 2457570.75
    with pytest.raises(ValueError):
        julian_date("first of July")


def test_sun_right_ascension_and_ltan():
    # March equinox 2016-03-20 04:30 UTC (RA 0), June solstice 2016-06-20 22:34 UTC (RA 6 h)
    assert math.degrees(sun_right_ascension(julian_date("2016-03-20T04:30:00"))) == pytest.approx(0.0, abs=0.02)
    assert math.degrees(sun_right_ascension(julian_date("2016-06-20T22:34:00"))) == pytest.approx(90.0, abs=0.02)
    # the apparent solar noon at TIRA on 2016-07-01 is 12:24 UTC (longitude 28.5 min, equation of time -4 min)
    jd = julian_date("2016-07-01T12:00:00")
    gast = erfa.gst06a(jd, 0.0, jd, 0.0)  # Greenwich apparent sidereal time (UT1 ~ TT ~ UTC: < 2 s of time)
    hour_angle = (gast + TIRA.lon - sun_right_ascension(jd) + math.pi) % (2 * math.pi) - math.pi
    assert math.degrees(hour_angle) * 4.0 == pytest.approx(24.5, abs=0.5)  # minutes of time
    # LTAN 12:00 puts the node at the Sun, 09:30 2.5 h (37.5 deg) west of it
    assert raan_from_ltan(12.0, jd) == pytest.approx(sun_right_ascension(jd) % (2 * math.pi))
    assert math.degrees((raan_from_ltan(9.5, jd) - sun_right_ascension(jd)) % (2 * math.pi)) == \
        pytest.approx(360.0 - 37.5)


def test_wgs84_station_positions():
    np.testing.assert_allclose(geodetic_to_ecef(0.0, 0.0, 0.0), [WGS84_A, 0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(geodetic_to_ecef(math.pi / 2, 0.0, 0.0), [0.0, 0.0, 6356752.314245], atol=1e-6)
    np.testing.assert_allclose(geodetic_to_ecef(0.0, math.pi / 2, 1000.0), [0.0, WGS84_A + 1000.0, 0.0],
                               atol=1e-6)
    # TIRA: on the ellipsoid's normal, geocentric latitude from tan(phi') = (1 - e^2 N/(N + h)) tan(phi)
    r = TIRA.ecef
    n = WGS84_A / math.sqrt(1 - WGS84_E2 * math.sin(TIRA.lat) ** 2)
    assert math.atan2(r[2], math.hypot(r[0], r[1])) == pytest.approx(
        math.atan((1 - WGS84_E2 * n / (n + TIRA.alt)) * math.tan(TIRA.lat)), abs=1e-12)
    assert math.degrees(math.atan2(r[1], r[0])) == pytest.approx(7.1296)
    np.testing.assert_allclose(r, [4023921.553, 503317.140, 4906824.539], atol=1e-3)
    # the local up vector is the ellipsoid normal at the station
    up = enu_matrix(TIRA.lat, TIRA.lon)[2]
    np.testing.assert_allclose(np.cross(up, geodetic_to_ecef(TIRA.lat, TIRA.lon, 1300.0) - r), 0.0, atol=1e-6)


def test_look_angles_simple_configurations():
    site = Station("eq", 0.0, 0.0, 0.0)
    s, enu = site.ecef, site.enu
    np.testing.assert_allclose(enu @ enu.T, np.eye(3), atol=1e-15)
    rng, az, el = look_angles(s + [500e3, 0.0, 0.0], s, enu)
    assert (rng, math.degrees(el)) == (pytest.approx(500e3), pytest.approx(90.0))
    d = 100e3
    for offset, az_deg in (([0, 0, d], 0.0), ([0, d, 0], 90.0), ([0, 0, -d], 180.0), ([0, -d, 0], 270.0)):
        rng, az, el = look_angles(s + np.array(offset, dtype=float), s, enu)
        assert math.degrees(az) == pytest.approx(az_deg, abs=1e-9)
        assert el == pytest.approx(0.0, abs=1e-12) and rng == pytest.approx(d)
    # 45 deg elevation towards the north-east
    rng, az, el = look_angles(s + np.array([d, d / math.sqrt(2), d / math.sqrt(2)]), s, enu)
    assert (math.degrees(az), math.degrees(el), rng) == (pytest.approx(45.0), pytest.approx(45.0),
                                                          pytest.approx(d * math.sqrt(2)))
    # round trip at TIRA, vectorized
    z = np.array([[1.2e6, 0.1, 0.3], [6e5, 6.2, 1.4], [2e6, 3.0, 0.0]])
    np.testing.assert_allclose(look_angles(look_position(z, TIRA.ecef, TIRA.enu), TIRA.ecef, TIRA.enu), z,
                               rtol=1e-12, atol=1e-9)


def test_chief_orbit_and_rtn_frame():
    raan, u = 0.7, np.array([0.0, math.pi / 2, 2.0])
    r, v = chief_position_velocity(A, INC, raan, u)
    np.testing.assert_allclose(np.linalg.norm(r, axis=-1), A)
    np.testing.assert_allclose(np.linalg.norm(v, axis=-1), math.sqrt(MU_EARTH / A))
    np.testing.assert_allclose(np.sum(r * v, axis=-1), 0.0, atol=1e-3)
    np.testing.assert_allclose(r[0], A * np.array([math.cos(raan), math.sin(raan), 0.0]), atol=1e-6)
    assert r[1, 2] == pytest.approx(A * math.sin(INC))
    q = rtn_matrix(r, v)
    np.testing.assert_allclose(np.einsum("kji,kjl->kil", q, q), np.broadcast_to(np.eye(3), (3, 3, 3)), atol=1e-15)
    np.testing.assert_allclose(q[..., 1], v / np.linalg.norm(v, axis=-1, keepdims=True), atol=1e-15)
    assert np.all(np.linalg.det(q) > 0.999)


def test_deputy_position_is_chief_plus_rtn_offset():
    kep = np.array([A, 0.0, INC, 0.4, 0.0, 1.1])
    roe = np.array([-20.0, 9000.0, -20.6, -589.6, 14.0, 399.8]) / A
    rc, vc = chief_position_velocity(A, INC, 0.4, 1.1)
    rel = roe_to_rtn(roe, 1.1)[0] * A
    np.testing.assert_allclose(deputy_position(roe, kep), rc + rtn_matrix(rc, vc) @ rel, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(deputy_position(roe, kep) - rc), np.linalg.norm(rel))
    assert relative_distance(roe, A, 1.1) == pytest.approx(np.linalg.norm(rel))
    # a pure along-track offset lies along the velocity
    along = deputy_position(np.array([0, 5000.0 / A, 0, 0, 0, 0]), kep) - rc
    np.testing.assert_allclose(along, 5000.0 * vc / np.linalg.norm(vc), atol=1e-6)
    # observe = deputy_position -> Earth-fixed -> look angles, broadcast over samples
    earth = gcrs_to_itrs(JD0, 4000.0)
    z = observe(np.stack([roe, 0 * roe]), kep, earth, TIRA.ecef, TIRA.enu)
    r_ef = earth @ deputy_position(roe, kep)
    state = np.stack([r_ef, earth @ chief_position_velocity(*chief_from_kepler(kep))[1]])
    np.testing.assert_allclose(z[0], two_way_look(state, TIRA.ecef, TIRA.enu))
    assert 0.0 < abs(z[0, 0] - look_angles(r_ef, TIRA.ecef, TIRA.enu)[0]) < 60.0  # the light time's tens of metres
    # two_way_position inverts it (to the chief's velocity)
    np.testing.assert_allclose(two_way_position(z[0], state[1], TIRA.ecef, TIRA.enu), r_ef, atol=1e-3, rtol=0)
    assert z[1, 2] == pytest.approx(chief_elevation(kep, earth, TIRA.ecef, TIRA.enu))
    # the Earth-fixed frame turns eastwards: a fixed inertial point drifts west by omega_E dt about the pole
    x = np.linalg.solve(earth, [1.0, 0.0, 0.0])
    dt = 600.0
    c, s = math.cos(EARTH_ROTATION * dt), math.sin(EARTH_ROTATION * dt)
    np.testing.assert_allclose(gcrs_to_itrs(JD0, 4000.0 + dt) @ x, [c, -s, 0.0], atol=1e-7)


def _elevation(kep0, station):
    return lambda t: chief_elevation(propagate_chief(kep0, t), gcrs_to_itrs(JD0, t), station.ecef, station.enu)


def test_passes_of_the_515km_sso_over_tira():
    kep0 = np.array([A, 0.0, INC, raan_from_ltan(9.5, JD0), 0.0, 0.3])
    elevation = _elevation(kep0, TIRA)
    days = 3
    windows = pass_windows(elevation, 0.0, days * 86400.0, MASK)
    assert np.all(windows[:, 1] > windows[:, 0])
    assert 3 * days <= len(windows) <= 6 * days  # a 515 km SSO sees a mid-latitude site 3-6 times a day above 10 deg
    duration = windows[:, 1] - windows[:, 0]
    assert np.all(duration > 60.0) and np.all(duration < 11 * 60.0) and np.max(duration) > 6 * 60.0
    np.testing.assert_allclose(elevation(windows.reshape(-1)), MASK, atol=2e-5)  # 0.01 s x ~1 mrad/s near the horizon
    hours = (windows[:, 0] % 86400.0) / 3600.0
    # LTAN 09:30: morning (ascending) and evening (descending) passes only, as in seed 001 Fig. 7
    assert np.all(((hours > 6) & (hours < 11)) | ((hours > 19) & (hours < 24)))
    # against a brute-force 1 s scan of the first day
    t = np.arange(0.0, 86400.0, 1.0)
    up = visible(elevation(t), MASK)
    rises = t[1:][up[1:] & ~up[:-1]]
    first = windows[windows[:, 0] < 86400.0]
    assert len(rises) == len(first)
    np.testing.assert_allclose(first[:, 0], rises, atol=1.0)


def test_pass_in_progress_at_the_window_edges():
    windows = pass_windows(lambda t: np.sin(2 * math.pi * t / 1000.0), 0.0, 1500.0, 0.0, step=7.0)
    np.testing.assert_allclose(windows, [[0.0, 500.0], [1000.0, 1500.0]], atol=0.01)
    assert pass_windows(lambda t: -1.0 + 0 * t, 0.0, 100.0, 0.0).shape == (0, 2)


def test_noise_is_seeded_and_wraps_azimuth():
    z = np.tile([1e6, 2 * math.pi - 1e-5, 0.3], (20000, 1))
    sigma = np.array([10.0, math.radians(0.01), math.radians(0.01)])
    a = add_noise(z, sigma, np.random.default_rng(5))
    np.testing.assert_array_equal(a, add_noise(z, sigma, np.random.default_rng(5)))
    assert np.all((a[:, 1] >= 0) & (a[:, 1] < 2 * math.pi))
    assert np.any(a[:, 1] < 1.0)  # wrapped through north
    dev = a - z
    dev[:, 1] = (dev[:, 1] + math.pi) % (2 * math.pi) - math.pi
    np.testing.assert_allclose(dev.std(axis=0), sigma, rtol=0.03)
    np.testing.assert_allclose(dev.mean(axis=0) / sigma, 0.0, atol=0.03)


def test_utc_epoch_of_a_pass_is_reasonable():
    # seed 001: TIRA passes of BIROS on 01-02/07/2016 in the evening and the next morning (~19:35-21:10, ~8:30-10:10)
    kep0 = np.array([A, 0.0, INC, raan_from_ltan(9.5, JD0), 0.0, 0.3])
    windows = pass_windows(_elevation(kep0, TIRA), 0.0, 86400.0, MASK)
    start = datetime(2016, 7, 1, tzinfo=timezone.utc)
    evening = [start + timedelta(seconds=float(r)) for r, _ in windows if r > 12 * 3600]
    assert len(evening) >= 2 and all(18 <= e.hour <= 23 for e in evening)


def test_truth_da_rate_is_the_secant_of_da():
    roe0 = np.array([1e-6, 2e-4, 0.0, 0.0, 0.0, 0.0])
    roe1 = roe0 + np.array([-3e-8, 1e-6, 1.0, 1.0, 1.0, 1.0])
    assert truth_da_rate(100.0, roe0, 160.0, roe1) == pytest.approx(-3e-8 / 60.0, rel=1e-12)
    assert truth_da_rate(160.0, roe1, 160.0, roe1) == 0.0  # no span: no rate


def test_observe_is_the_two_way_light_time_measurement_at_the_receive_tag():
    """observe() against the light-time equations solved here to convergence with the model's own motion (the
    picosatellite's secular orbit at the reflection epoch, the station by the Earth's orientation at the transmit
    epoch): range to 0.1 m, angles to 0.1 urad over a pass; the instantaneous geometric range differs by tens of
    metres (the range rate times the light time)."""
    from roe_sep.core.constants import SPEED_OF_LIGHT

    kep0 = np.array([A, 0.0, INC, raan_from_ltan(9.5, JD0), 0.0, 0.3])
    roe = np.array([-40.0, 8000.0, 150.0, -400.0, 80.0, 350.0]) / A
    t_all = np.arange(0.0, 86400.0, 10.0)
    el = observe(roe, propagate_chief(kep0, t_all), gcrs_to_itrs(JD0, t_all), TIRA.ecef, TIRA.enu)[:, 2]
    t = t_all[el > MASK][:60]
    assert t.size == 60

    def pos(tk):
        return deputy_position(roe, propagate_chief(kep0, tk))

    def station(tk):
        return np.einsum("...ji,j->...i", gcrs_to_itrs(JD0, tk), TIRA.ecef)

    tau_d = np.zeros_like(t)
    for _ in range(6):
        tau_d = np.linalg.norm(pos(t - tau_d) - station(t), axis=-1) / SPEED_OF_LIGHT
    tau_u = np.zeros_like(t)
    for _ in range(6):
        tau_u = np.linalg.norm(pos(t - tau_d) - station(t - tau_d - tau_u), axis=-1) / SPEED_OF_LIGHT
    r_b = np.einsum("nij,nj->ni", gcrs_to_itrs(JD0, t), pos(t - tau_d))
    expected = look_angles(r_b, TIRA.ecef, TIRA.enu)
    expected[:, 0] = 0.5 * SPEED_OF_LIGHT * (tau_d + tau_u)
    z = observe(roe, propagate_chief(kep0, t), gcrs_to_itrs(JD0, t), TIRA.ecef, TIRA.enu)
    assert np.max(np.abs(z[:, 0] - expected[:, 0])) < 0.1
    assert np.max(np.abs(z[:, 1:] - expected[:, 1:])) < 1e-7
    geometric = look_angles(np.einsum("nij,nj->ni", gcrs_to_itrs(JD0, t), pos(t)), TIRA.ecef, TIRA.enu)
    assert np.max(np.abs(geometric[:, 0] - z[:, 0])) > 15.0
