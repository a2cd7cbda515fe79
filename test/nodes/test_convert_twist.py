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
