import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from oracle import rtn_relative_position

from roe_sep.core.relmotion.orbit import mean_motion, semi_major_axis
from roe_sep.core.relmotion.roe import (
    e_vector_polar,
    i_vector_polar,
    kepler_to_roe,
    roe_to_kepler,
    roe_to_rtn,
    rtn_to_roe,
)

small = st.floats(-2e-3, 2e-3, allow_nan=False)
angle = st.floats(-np.pi, np.pi, allow_nan=False)
roe_vec = st.tuples(small, small, small, small, small, small).map(np.array)


@given(roe=roe_vec, raan=angle, u=angle, inc=st.floats(0.2, 3.0))
@settings(max_examples=200, deadline=None)
def test_kepler_roe_round_trip(roe, raan, u, inc):
    chief = np.array([7.0e6, 0.0, inc, raan, 0.0, u])
    back = kepler_to_roe(chief, roe_to_kepler(chief, roe))
    np.testing.assert_allclose(back, roe, atol=1e-12)


@given(roe=roe_vec, u=angle)
@settings(max_examples=200, deadline=None)
def test_rtn_round_trip(roe, u):
    pos, vel = roe_to_rtn(roe, u)
    np.testing.assert_allclose(rtn_to_roe(pos, vel, u), roe, atol=1e-15)


def test_rtn_vectorized_matches_scalar():
    rng = np.random.default_rng(1)
    roes = rng.normal(0, 1e-4, (50, 6))
    us = rng.uniform(0, 2 * np.pi, 50)
    pos, vel = roe_to_rtn(roes, us)
    for k in (0, 17, 49):
        p1, v1 = roe_to_rtn(roes[k], us[k])
        np.testing.assert_allclose(pos[k], p1)
        np.testing.assert_allclose(vel[k], v1)


def test_hand_values_of_the_rtn_map():
    # a pure relative-eccentricity orbit at u = 0: R = -dex a, T = -2 dey a; a pure di_x orbit at u = 90 deg: N = dix a
    pos, vel = roe_to_rtn(np.array([0, 0, 1e-4, 2e-4, 0, 0]), 0.0)
    np.testing.assert_allclose(pos, [-1e-4, -4e-4, 0.0])
    np.testing.assert_allclose(vel, [-2e-4, 2e-4, 0.0])
    pos, _ = roe_to_rtn(np.array([0, 0, 0, 0, 3e-5, 0]), np.pi / 2)
    np.testing.assert_allclose(pos, [0, 0, 3e-5], atol=1e-20)


@pytest.mark.parametrize("u", [0.3, 1.5, 2.9, 4.4])
def test_linear_map_matches_exact_two_body_geometry(u):
    """First-order agreement of the ROE->RTN map with exact positions from the two Keplerian orbits."""
    a = float(semi_major_axis(515e3))
    inc = np.radians(97.4)
    chief = np.array([a, 0.0, inc, 0.4, 0.0, u])
    roe = np.array([-40.0, 900.0, -20.0, -590.0, 14.0, 400.0]) / a
    deputy = roe_to_kepler(chief, roe)
    exact = rtn_relative_position(chief, deputy)
    linear = roe_to_rtn(roe, u)[0] * a
    # second-order terms are ~ |roe|^2 a ~ (1e3 m)^2 / 7e6 m ~ 0.1 m, plus curvature of the along-track arc
    np.testing.assert_allclose(linear, exact, atol=1.0)


def test_polar_forms():
    r = np.array([0, 0, 3.0, 4.0, 0.0, -2.0])
    assert e_vector_polar(r)[0] == pytest.approx(5.0)
    assert e_vector_polar(r)[1] == pytest.approx(np.arctan2(4, 3))
    assert i_vector_polar(r) == pytest.approx((2.0, -np.pi / 2))


def test_mean_motion_hand_value():
    # n = sqrt(mu / a^3) at 515 km, by hand: a = 6893137 m
    assert mean_motion(6893137.0) == pytest.approx(np.sqrt(3.986004418e14 / 6893137.0**3), rel=1e-15)
    assert mean_motion(6893137.0) == pytest.approx(1.1031727e-3, rel=1e-7)


def test_angle_between_vectorized_and_zero_vectors():
    from roe_sep.core.relmotion.orbit import angle_between

    a = np.array([[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 0.0]])
    b = np.array([[0.0, 2.0, 0.0], [-1.0, -1.0, 0.0], [1.0, 0.0, 0.0]])
    np.testing.assert_allclose(angle_between(a, b), [np.pi / 2, np.pi, 0.0])
    np.testing.assert_allclose(angle_between(a.T, b.T, axis=0), [np.pi / 2, np.pi, 0.0])
    assert float(angle_between([1.0, 0.0], [1.0, 1e-9])) == pytest.approx(1e-9)
