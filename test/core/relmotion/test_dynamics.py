import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from roe_sep.core.relmotion.dynamics import (
    arg_latitude_rate,
    ballistic_coefficient,
    drag_da_dot,
    eccentricity_vector_rotation_rate,
    j2_kappa,
    propagate,
    raan_rate,
    sun_synchronous_inclination,
)
from roe_sep.core.relmotion.orbit import circular_speed, mean_motion, semi_major_axis
from roe_sep.core.relmotion.roe import roe_to_rtn

A = float(semi_major_axis(515e3))
N = float(mean_motion(A))
INC = float(sun_synchronous_inclination(A))
roe_st = st.tuples(*[st.floats(-1e-3, 1e-3, allow_nan=False)] * 6).map(np.array)


def test_keplerian_only_dl_drifts():
    roe = np.array([-4e-5, 1e-3, 2e-5, -3e-5, 1e-5, 5e-5])
    out = propagate(roe, 5000.0, A, INC, j2=False)
    expected = roe.copy()
    expected[1] += -1.5 * N * roe[0] * 5000.0  # seed 000 Eq. (2)
    np.testing.assert_allclose(out, expected, rtol=0, atol=1e-16)


def test_drag_reduces_to_seed_eqs_23_24():
    """With J2 off: a da = -(1/n^2) dB rho v^2 (u - u0), a dl = 3/(4 n^2) dB rho v^2 (u - u0)^2."""
    db = ballistic_coefficient(2.3, 0.01, 1.0) - ballistic_coefficient(2.3, 0.48, 140.0)
    assert db == pytest.approx(0.0151, abs=5e-5)  # seed 002: dB = 0.0151 m^2/kg
    rho, v = 1e-12, float(circular_speed(A))
    t = 86400.0
    du = N * t
    out = propagate(np.zeros(6), t, A, INC, j2=False, da_dot=drag_da_dot(db, rho, A)) * A
    assert out[0] == pytest.approx(-db * rho * v**2 * du / N**2, rel=1e-12)
    assert out[1] == pytest.approx(0.75 * db * rho * v**2 * du**2 / N**2, rel=1e-12)
    # hand value: about -68 m and +4.8 km per day for the seed's numbers
    assert out[0] == pytest.approx(-68.2, abs=0.5)
    assert out[1] == pytest.approx(4870, abs=30)


def test_j2_eccentricity_rotation_about_3p5_deg_per_day_at_500km_sso():
    a = float(semi_major_axis(500e3))
    rate = np.degrees(eccentricity_vector_rotation_rate(a, sun_synchronous_inclination(a))) * 86400
    # seed 001: 'a clock-wise rotation of circa 3.6 degrees per day'; kappa Q by hand gives -3.51 deg/day
    assert -3.7 < rate < -3.4
    roe = np.array([0, 0, 1e-4, 0, 0, 0])
    out = propagate(roe, 86400.0, a, sun_synchronous_inclination(a), j2=True)
    assert np.degrees(np.arctan2(out[3], out[2])) == pytest.approx(rate, rel=1e-12)
    assert np.hypot(out[2], out[3]) == pytest.approx(1e-4, rel=1e-12)


def test_j2_diy_drift_driven_by_dix():
    """d(diy)/dt = 2 kappa sin^2 i dix when da = 0 (seed 001: ejection at the poles keeps dix ~ 0)."""
    dix = 400.0 / A
    out = propagate(np.array([0, 0, 0, 0, dix, 0]), 86400.0, A, INC, j2=True)
    kappa = 0.75 * N * 1.08262668e-3 * (6378137.0 / A) ** 2
    assert j2_kappa(A) == pytest.approx(kappa)
    assert out[5] == pytest.approx(2 * kappa * np.sin(INC) ** 2 * dix * 86400.0, rel=1e-12)
    assert out[5] * A == pytest.approx(53.0, abs=2.0)  # tens of meters per day for a 400 m dix
    assert out[4] == dix


@given(roe=roe_st, t1=st.floats(0, 2e5), t2=st.floats(0, 2e5), dad=st.floats(-1e-9, 1e-9), j2=st.booleans())
@settings(max_examples=100, deadline=None)
def test_transition_composes(roe, t1, t2, dad, j2):
    once = propagate(roe, t1 + t2, A, INC, j2, da_dot=dad)
    twice = propagate(propagate(roe, t1, A, INC, j2, da_dot=dad), t2, A, INC, j2, da_dot=dad)
    np.testing.assert_allclose(twice, once, rtol=1e-9, atol=1e-13)


def test_propagation_is_consistent_with_rtn_velocity():
    """Finite-difference position derivative of the propagated orbit equals the RTN velocity of the map."""
    roe = np.array([-2e-5, 1e-3, -1e-4, 5e-5, 2e-5, 6e-5])
    u0, h = 0.7, 0.5
    udot = arg_latitude_rate(A, INC, j2=False)

    def pos(t):
        return roe_to_rtn(propagate(roe, t, A, INC, j2=False), u0 + udot * t)[0] * A

    t = 1234.0
    fd = (pos(t + h) - pos(t - h)) / (2 * h)
    vel = roe_to_rtn(propagate(roe, t, A, INC, j2=False), u0 + udot * t)[1] * A * N
    np.testing.assert_allclose(fd, vel, atol=1e-6)


def test_broadcasting_over_samples_and_times():
    rng = np.random.default_rng(3)
    roes = rng.normal(0, 1e-4, (10, 6))
    ts = np.linspace(0, 1e4, 4)
    out = propagate(roes[:, None, :], ts, A, INC, True, da_dot=rng.normal(0, 1e-10, 10)[:, None])
    assert out.shape == (10, 4, 6)


def test_sun_synchronous_inclination_hand_value():
    """cos i = -(2 pi / 365.2422 d) / (3/2 n J2 (R/a)^2): 97.46 deg at 515 km, 97.40 deg at 500 km."""
    assert np.degrees(INC) == pytest.approx(97.459, abs=1e-3)
    assert np.degrees(raan_rate(A, INC)) * 86400 * 365.2422 == pytest.approx(360.0, rel=1e-12)
    with pytest.raises(ValueError, match="no sun-synchronous orbit"):
        sun_synchronous_inclination(semi_major_axis(8000e3))


def test_a_chiefs_rates_are_computed_once_per_value_and_equal_the_array_ones():
    from roe_sep.core.relmotion.dynamics import secular_rates
    from roe_sep.core.relmotion.orbit import per_chief

    a, inc = 6893137.0, np.radians(97.459)
    # the cached scalars are the values of the same expressions on arrays, to the bit
    assert mean_motion(a) == mean_motion(np.array([a]))[0]
    for j2 in (True, False):
        assert arg_latitude_rate(a, inc, j2) == arg_latitude_rate(np.array([a]), np.array([inc]), j2)[0]
        scalar, array = secular_rates(a, inc, j2), secular_rates(np.array([a]), np.array([inc]), j2)
        assert [v for v in scalar] == [None if v is None else v[0] for v in array]
    calls = []

    @per_chief(2)
    def f(x, y, flag):
        calls.append((x, y, flag))
        return np.copysign(x, y) if flag else x + y

    assert f(1.0, 2.0, 1) == f(1.0, 2.0, True) == 1.0 and len(calls) == 1  # flags as bools: one entry
    assert f(1.0, -0.0, True) == -1.0 and f(1.0, 0.0, True) == 1.0  # -0.0 and 0.0 are separate entries
    assert len(calls) == 3
    f(np.array([1.0]), 2.0, True)
    f(np.array([1.0]), 2.0, True)  # arrays are computed every time
    assert len(calls) == 5


def test_the_in_plane_propagation_is_propagate_elements_da_dex_dey():
    from roe_sep.core.relmotion.dynamics import propagate_elements, propagate_in_plane

    rng = np.random.default_rng(3)
    el = rng.normal(0.0, 1e-4, (6, 50))
    dt = rng.uniform(0.0, 86400.0, 50)
    for j2 in (True, False):
        full = propagate_elements(el, dt, 6893137.0, 1.7, j2, da_dot=-1e-12)
        part = propagate_in_plane(el[0], el[2], el[3], dt, 6893137.0, inc=1.7, j2=j2, da_dot=-1e-12)
        for x, y in zip(part, (full[0], full[2], full[3])):
            assert np.array_equal(x, y)
