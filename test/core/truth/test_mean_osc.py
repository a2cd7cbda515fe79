"""Mean <-> osculating conversion (Schaub & Junkins App. F) and Cartesian <-> Keplerian states."""

import numpy as np
import pytest

from roe_sep.core.constants import J2, R_EARTH
from roe_sep.core.relmotion.dynamics import sun_synchronous_inclination
from roe_sep.core.truth import mean_osc as mo

A = R_EARTH + 515e3
INC = float(sun_synchronous_inclination(A))


def test_cartesian_round_trip():
    kep = np.array([[A, 1e-3, INC, 0.3, 0.5, 2.0], [A + 1e3, 0.0, 1.0, 4.0, 0.0, 5.5]])
    back = mo.cartesian_to_kepler(*mo.kepler_to_cartesian(kep))
    assert np.allclose(back[:, :4], kep[:, :4], rtol=1e-12, atol=1e-9)
    u = lambda k: np.mod(k[:, 4] + k[:, 5], 2 * np.pi)  # noqa: E731
    assert np.allclose(u(back), u(kep), atol=1e-10)


def test_circular_semi_major_axis_short_period_term():
    """Eq. (F.7) at e = 0: a_osc - a_mean = (3/2) J2 R_E^2 / a sin^2 i cos 2u (9.4 km amplitude at 515 km)."""
    u = np.linspace(0, 2 * np.pi, 37)
    kep = np.stack([A + 0 * u, 0 * u, INC + 0 * u, 0 * u, 0 * u, u], axis=-1)
    da = mo.mean_to_osculating(kep)[:, 0] - A
    assert np.allclose(da, 1.5 * J2 * R_EARTH**2 / A * np.sin(INC) ** 2 * np.cos(2 * u), atol=1e-6)


def test_round_trip_residual_is_second_order(monkeypatch):
    kep = np.array([A, 1e-3, INC, 0.3, 0.5, 1.0])
    res = []
    for scale in (1.0, 0.1):
        monkeypatch.setattr(mo, "J2", J2 * scale)
        res.append(abs(mo.osculating_to_mean(mo.mean_to_osculating(kep))[0] - A))
    assert res[0] < 100.0  # m
    assert res[1] == pytest.approx(res[0] * 0.01, rel=0.05)  # O(J2^2)


def test_numerical_orbit_has_constant_mean_elements():
    """J2-only truth over 6 h: the osculating a swings by +-9.4 km, the mean a by tens of m (O(J2^2)) and mean i by
    < 1e-6 rad: the first-order map removes the short-period terms."""
    from roe_sep.core.truth.nonlinear import Atmosphere, pair_state, propagate_pair

    kep = np.array([A, 0.0, INC, 0.3, 0.0, 1.0])
    t = np.linspace(0, 6 * 3600, 217)
    s = propagate_pair(pair_state(kep, kep), 0, t, (), 0.0, b_deputy=0.0, atmosphere=Atmosphere.scaled(1e-12, 515e3),
                       zonals=2)
    osc = mo.cartesian_to_kepler(s[:, :3], s[:, 3:6])
    mean = mo.cartesian_to_mean(s[:, :3], s[:, 3:6])
    assert np.ptp(osc[:, 0]) > 15e3
    assert np.ptp(mean[:, 0]) < 60.0
    assert np.ptp(mean[:, 2]) < 1e-6
