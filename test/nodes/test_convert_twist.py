"""The footage's ejection estimate through its message and back: the planner's writer
(``roe_sep.nodes.planner.estimate_msg``) and the readers' :func:`roe_sep.nodes.convert.twist_linear` (the safety
monitor's and the ic_planner's)."""

import numpy as np
import pytest
from rosutil import rclpy  # noqa: F401  (skips without rclpy)

from roe_sep.core.decisions.planner import PublishEstimate
from roe_sep.nodes.convert import twist_linear
from roe_sep.nodes.planner import estimate_msg


def test_the_estimate_round_trips_and_a_bad_covariance_is_refused():
    dv = (0.28, -0.03, 0.09)
    cov = np.arange(9.0).reshape(3, 3) * 1e-8
    msg = estimate_msg(PublishEstimate((600, 400_000_000), dv, tuple(cov.reshape(-1))))
    got_dv, got_cov = twist_linear(msg)
    np.testing.assert_array_equal(got_dv, dv)
    np.testing.assert_array_equal(got_cov, cov)
    msg.twist.covariance = [0.0] * 36
    assert not twist_linear(msg)[1].any()

    class Short:  # a message decoded from another tool's bytes with a short covariance
        class twist:
            covariance = [0.0] * 9
            twist = msg.twist.twist

    with pytest.raises(ValueError, match="36 entries, got 9"):
        twist_linear(Short)


def test_a_non_finite_estimate_is_refused_by_the_one_reader():
    msg = estimate_msg(PublishEstimate((600, 0), (0.28, -0.03, 0.09), tuple(np.eye(3).reshape(-1) * 1e-8)))
    msg.twist.twist.linear.y = float("nan")
    with pytest.raises(ValueError, match="non-finite ejection estimate"):
        twist_linear(msg)
    msg = estimate_msg(PublishEstimate((600, 0), (0.28, -0.03, 0.09), tuple(np.eye(3).reshape(-1) * 1e-8)))
    cov = list(msg.twist.covariance)
    cov[7] = float("inf")
    msg.twist.covariance = cov
    with pytest.raises(ValueError, match="non-finite ejection estimate"):
        twist_linear(msg)


def test_the_ejection_prior_of_an_event_and_a_bad_event_refused():
    """convert.ejection_prior: what the ic_planner and radar_od predict from (EjectionPrior.commanded), and the
    footage's estimate in its place (EjectionPrior.measured)."""
    from roe_sep_msgs.msg import EjectionEvent

    from roe_sep.core.config import load_scenario
    from roe_sep.core.decisions.ic_planner import EjectionPrior
    from roe_sep.nodes.convert import array_to_elements, ejection_prior

    scenario = load_scenario(None)
    kep = np.array([6.9e6, 0.001, 1.7, 0.3, 0.2, 0.4])
    ev = EjectionEvent()
    ev.header.stamp.sec = 600
    ev.chief = array_to_elements(kep)
    ev.ejection.dv_rtn.x, ev.ejection.dv_rtn.y, ev.ejection.dv_rtn.z = 0.1, 0.2, 0.05
    ev.ejection.mean_arg_latitude = 0.6
    prior = ejection_prior(ev, scenario)
    np.testing.assert_allclose(prior.kep, kep, rtol=0.0, atol=1e-12)  # through the message's wrapped angles
    assert prior == EjectionPrior.commanded(600.0, prior.kep, 0.6, [0.1, 0.2, 0.05], scenario)
    measured = prior.measured([0.09, 0.2, 0.05], np.eye(3) * 1e-8)
    assert measured.source == "footage" and measured.dv == (0.09, 0.2, 0.05) and len(measured.cov) == 9
    assert measured.t == prior.t and measured.kep == prior.kep
    ev.chief.semi_major_axis = float("nan")
    with pytest.raises(ValueError, match="non-finite dv or invalid chief"):
        ejection_prior(ev, scenario)
