import numpy as np
import pytest

from roe_sep.core.relmotion.dynamics import arg_latitude_rate, propagate, propagate_chief, raan_rate
from roe_sep.core.relmotion.trajectory import Burn, Chief, state_at, trajectory
from roe_sep.core.separation.double_impulse import design, plan_drift_stop

D = design()
CHIEF = Chief(a=D.a, inc=D.inc, u0=D.u1, t0=0.0)


def test_double_impulse_through_the_trajectory_matches_the_plan():
    stop = plan_drift_stop(D.dv1_rtn, D.u1, 0.0, D.a, D.inc, k=3, p=0.06, j2=True)
    burns = [Burn(0.0, tuple(D.dv1_rtn)), Burn(stop.epoch, tuple(stop.dv_relative_rtn))]
    after = state_at(np.zeros(6), 0.0, burns, stop.epoch, CHIEF)
    np.testing.assert_allclose(after, stop.aimed_roe, atol=1e-15)
    before = state_at(np.zeros(6), 0.0, burns, stop.epoch - 1e-6, CHIEF)
    assert before[0] * D.a == pytest.approx(-295.0, abs=1e-3)  # only the ejection yet


def test_samples_in_any_order_and_segments():
    burns = [Burn(100.0, (0.0, 0.01, 0.0)), Burn(50.0, (0.0, -0.02, 0.0))]
    times = np.array([300.0, 10.0, 75.0, 50.0, 100.0])
    out = trajectory(np.zeros(6), 0.0, burns, times, CHIEF, da_dot=-1e-11)
    np.testing.assert_allclose(out[1], propagate(np.zeros(6), 10.0, D.a, D.inc, True, da_dot=-1e-11))
    for k, t in enumerate(times):
        np.testing.assert_allclose(out[k], state_at(np.zeros(6), 0.0, burns, t, CHIEF, da_dot=-1e-11))
    # the burn at t = 50 s lowers da by 2 dv / (n a); the one at 100 s raises it by half of that
    assert out[3][0] * D.a == pytest.approx(-0.04 / D.n - 1e-11 * 50 * D.a, rel=1e-9)
    with pytest.raises(ValueError):
        trajectory(np.zeros(6), 10.0, [], [5.0], CHIEF)


def test_chief_propagation():
    kep = np.array([D.a, 0.0, D.inc, 0.3, 0.0, 1.0])
    out = propagate_chief(kep, 86400.0)
    assert out[3] - 0.3 == pytest.approx(raan_rate(D.a, D.inc) * 86400.0)
    assert (out[4] + out[5]) - 1.0 == pytest.approx(arg_latitude_rate(D.a, D.inc) * 86400.0)
    assert CHIEF.u_at(86400.0) == pytest.approx(D.u1 + arg_latitude_rate(D.a, D.inc) * 86400.0)
    assert propagate_chief(kep, np.array([0.0, 1.0])).shape == (2, 6)
