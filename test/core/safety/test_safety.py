import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import minimize_scalar

from roe_sep.core.relmotion.dynamics import arg_latitude_rate, propagate, sun_synchronous_inclination
from roe_sep.core.relmotion.maneuvers import delta_roe
from roe_sep.core.relmotion.orbit import mean_motion, semi_major_axis
from roe_sep.core.relmotion.roe import roe_to_rtn
from roe_sep.core.safety.metrics import approaching, fov_limit, min_rn_distance, nearest_crossing

A = float(semi_major_axis(515e3))
N = float(mean_motion(A))
INC = float(sun_synchronous_inclination(A))


def test_eq25_parallel_and_perpendicular():
    de, di = 590.0, 400.0
    anti = np.array([0, 0, -de, 0, di, 0])
    assert min_rn_distance(anti) == pytest.approx(400.0)  # (anti-)parallel: min(de, di)
    perp = np.array([0, 0, de, 0, 0, di])
    assert min_rn_distance(perp) == pytest.approx(0.0, abs=1e-9)
    assert min_rn_distance(np.zeros(6)) == 0.0


@given(de=st.floats(50, 1000), di=st.floats(50, 1000), phi=st.floats(0, 2 * np.pi), th=st.floats(0, 2 * np.pi))
@settings(max_examples=100, deadline=None)
def test_eq25_matches_brute_force_minimum_over_the_orbit(de, di, phi, th):
    roe = np.array([0, 0, de * np.cos(phi), de * np.sin(phi), di * np.cos(th), di * np.sin(th)])

    def rn(u):
        pos, _ = roe_to_rtn(roe, u)
        return np.hypot(pos[..., 0], pos[..., 2])

    u = np.linspace(0, 2 * np.pi, 20001)
    u_grid = u[np.argmin(rn(u))]
    brute = minimize_scalar(rn, bounds=(u_grid - 1e-3, u_grid + 1e-3), method="bounded",
                            options={"xatol": 1e-12}).fun
    assert min_rn_distance(roe) == pytest.approx(brute, rel=1e-6, abs=1e-6)


def test_eq11_fov_limits_of_table2():
    assert fov_limit(5000.0, np.radians(6.8)) == pytest.approx(596.2, abs=0.05)
    assert fov_limit(-5000.0, np.radians(9.15)) == pytest.approx(805.3, abs=0.05)


def test_approaching_drift_direction():
    assert approaching(np.array([1e-6, 1e-3, 0, 0, 0, 0]))  # leading and above: drifts back
    assert not approaching(np.array([-1e-6, 1e-3, 0, 0, 0, 0]))
    assert approaching(np.array([-1e-6, -1e-3, 0, 0, 0, 0]))  # following and below: catches up


def _brute_crossing(roe0, u0, duration, j2, dad):
    t = np.linspace(0, duration, 400001)
    udot = arg_latitude_rate(A, INC, j2)
    pos, _ = roe_to_rtn(propagate(roe0, t, A, INC, j2, da_dot=dad), u0 + udot * t)
    r = pos[:, 0]
    idx = np.nonzero((np.sign(r[1:]) != np.sign(r[:-1])) & (t[1:] > 0.1 * 2 * np.pi / udot))[0]
    if idx.size == 0:
        return np.inf
    return np.min(np.abs(pos[idx, 1]))


@pytest.mark.parametrize("f1", [0.6, 0.8, 1.0, 1.25])
@pytest.mark.parametrize("j2,dad", [(False, 0.0), (True, -2e-11)])
def test_nearest_crossing_matches_brute_force(f1, j2, dad):
    dv1 = f1 * np.array([-1.329250, -0.162718, 0.441269])
    u1 = np.radians(88.0)
    roe0 = delta_roe(dv1, u1, A, N)
    dur = 3 * np.pi / N
    fast, t = nearest_crossing(roe0, u1, dur, A, INC, j2=j2, da_dot=dad)
    assert fast * A == pytest.approx(_brute_crossing(roe0, u1, dur, j2, dad) * A, abs=0.5)
    assert 0 < t <= dur


def test_nearest_crossing_hand_value():
    # Keplerian, nominal ejection: the transit after one orbit happens at T = 3 pi |a da1| = 3 pi 295 m
    dv1 = np.array([-1.329250, -0.162718, 0.441269])
    roe0 = delta_roe(dv1, np.radians(88.0), A, N)
    best, t = nearest_crossing(roe0, np.radians(88.0), 3 * np.pi / N, A, INC, j2=False)
    assert best * A == pytest.approx(3 * np.pi * 295.0, rel=1e-5)
    assert t == pytest.approx(2 * np.pi / N, rel=1e-6)


def test_nearest_crossing_none_in_window():
    # da larger than de: the radial offset never vanishes
    best, t = nearest_crossing(np.array([1e-4, 0, 1e-5, 0, 0, 0]), 0.0, 1e4, A, INC)
    assert np.isinf(best) and np.isnan(t)
    # no radial motion at all: the orbit lies in the R = 0 plane, at its along-track distance
    best, t = nearest_crossing(np.array([[0, 0, 0, 0, 0, 0], [0, 1e-3, 0, 0, 2e-5, 0]]), 0.0, 1e4, A, INC)
    assert best[0] == 0.0 and best[1] == pytest.approx(1e-3, rel=1e-4)  # J2 moves dl a little (dix term)
