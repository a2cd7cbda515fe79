import numpy as np
import pytest

from roe_sep.core.relmotion.dynamics import arg_latitude_rate, drag_da_dot
from roe_sep.core.relmotion.maneuvers import delta_roe
from roe_sep.core.separation.double_impulse import design
from roe_sep.core.truth.secular import ExecutionErrors, TruthModel, chief_from_u, time_to_arg_latitude

D = design()


def model(da_dot=0.0):
    return TruthModel(chief_from_u(D.a, D.inc, 0.3, D.u1), 0.0, da_dot)


def test_attached_until_the_ejection_then_secular_dynamics():
    m = model(da_dot=-1e-11)
    assert not np.any(m.roe_at(5000.0))  # no differential drag while attached
    m.apply(100.0, D.dv1_rtn)
    np.testing.assert_allclose(m.roe_at(100.0), delta_roe(D.dv1_rtn, D.u1 + arg_latitude_rate(D.a, D.inc) * 100.0,
                                                          D.a, D.n))
    assert m.roe_at(100.0 + 86400.0)[0] == pytest.approx(m.roe[0] - 1e-11 * 86400.0)
    pos, vel = m.rtn_at(100.0)
    np.testing.assert_allclose(pos, 0.0, atol=1e-6)  # the impulse changes velocity, not position
    np.testing.assert_allclose(vel, D.dv1_rtn, atol=1e-9)
    times, dist = m.distances(100.0, 200.0, 10.0)
    assert times[0] == 100.0 and times[-1] == 200.0 and dist[0] == pytest.approx(0.0, abs=1e-6)
    assert dist[-1] == pytest.approx(141.0, rel=0.05)  # |dv| t at the start


def test_time_to_arg_latitude():
    t = time_to_arg_latitude(np.radians(50), np.radians(88), D.a, D.inc)
    assert t == pytest.approx(np.radians(38) / arg_latitude_rate(D.a, D.inc))
    assert time_to_arg_latitude(np.radians(90), np.radians(88), D.a, D.inc) > 5000  # next revolution


def test_execution_errors_follow_eq22_statistics():
    errs = ExecutionErrors(np.random.default_rng(0), 0.1, 0.05, np.radians(30 / 3600))
    dv = np.array([0.0, 0.1, 0.0])
    carrier = np.array([errs.executed(dv, "carrier") for _ in range(4000)])
    assert np.std(carrier[:, 1]) / 0.1 == pytest.approx(0.05, rel=0.1)
    pico = np.array([errs.executed(dv, "picosatellite") for _ in range(4000)])
    assert np.std(pico[:, 1]) / 0.1 == pytest.approx(0.10, rel=0.1)
    assert np.std(pico[:, 0]) / 0.1 == pytest.approx(np.radians(30 / 3600), rel=0.1)  # attitude: eps_z
    exact = ExecutionErrors(np.random.default_rng(0), 0.0, 0.0, 0.0)
    np.testing.assert_array_equal(exact.executed(dv, "carrier"), dv)


def test_execution_errors_of_a_reduced_drift_stop_act_on_the_unreduced_burn():
    """The sim's execution errors follow seed 002 Eq. (18) like the Monte Carlo: the spread of a drift-stop
    commanded with |p| is sigma * |unreduced|, its mean the commanded burn."""
    from roe_sep.core.truth.secular import error_references

    p = 0.06
    stop = -D.drift_stop_dv(p)  # the carrier's own burn
    refs = error_references(["drift_stop", "ic_acquisition"], [stop, stop], p)
    np.testing.assert_allclose(refs[0], -D.drift_stop_dv(0.0), atol=1e-15)
    assert refs[1] is None
    assert error_references(["drift_stop"], [stop], 0.0) == [None]
    with pytest.raises(ValueError, match="p_reduction"):
        error_references(["drift_stop"], [stop], float("nan"))
    errs = ExecutionErrors(np.random.default_rng(1), 0.1, 0.05, 0.0)
    out = np.array([errs.executed(stop, "carrier", refs[0]) for _ in range(4000)])
    assert np.std(out[:, 1]) == pytest.approx(0.05 * abs(D.dv2_rtn[1]), rel=0.05)
    assert np.mean(out[:, 1]) == pytest.approx(stop[1], abs=5e-4)


def test_seed_drag_value():
    # the scenario's nominal drift: about -68 m/day of a*da (seed 002 Eq. 24, hand value)
    assert drag_da_dot(0.0151, 1e-12, D.a) * D.a * 86400 == pytest.approx(-68.4, abs=0.3)
