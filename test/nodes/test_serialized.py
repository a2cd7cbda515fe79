"""Messages serialized by filling a template's bytes (roe_sep.nodes.serialized) and the simulator's truth messages
(roe_sep.nodes.convert.TruthMessages): the bytes rclpy serializes from the typed messages, padding zero."""

import math

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="serializing messages needs the project venv (make test)")

from rclpy.serialization import serialize_message  # noqa: E402
from roe_sep_msgs.msg import ManeuverPlan, RelativeOrbitalElements, RelativeState  # noqa: E402

from roe_sep import interfaces  # noqa: E402
from roe_sep.nodes.convert import TruthMessages, array_to_elements, roe_to_msg, sec_to_time  # noqa: E402
from roe_sep.nodes.serialized import Serialized, layout  # noqa: E402

ROE_PADDING = list(range(22, 28))  # after the 4 + 4 + 4 + 6 bytes of stamp and "truth": a_da 8-aligned in the body


def typed(msg) -> bytes:
    """rclpy's serialization of ``msg``, its padding bytes zeroed (rmw leaves them as they were in its buffer; where
    they are: test_layout_of_the_truth_messages)."""
    data = np.frombuffer(serialize_message(msg), np.uint8).copy()
    data[np.frombuffer(layout(msg)[1], np.uint8) == 1] = 0
    return data.tobytes()


def test_layout_of_the_truth_messages():
    roe = RelativeOrbitalElements()
    roe.header.frame_id = interfaces.TRUTH_FRAME
    data, pad, fields = layout(roe)
    assert len(data) == 412 and [i for i, p in enumerate(pad) if p] == ROE_PADDING
    assert {k: fields[k][0] for k in ("header.stamp.sec", "header.stamp.nanosec", "a_da", "a_diy", "covariance",
                                      "chief.semi_major_axis", "chief.mean_arg_latitude")} == \
        {"header.stamp.sec": 4, "header.stamp.nanosec": 8, "a_da": 28, "a_diy": 68, "covariance": 76,
         "chief.semi_major_axis": 364, "chief.mean_arg_latitude": 404}
    assert fields["covariance"][2] == 36 and data == typed(roe)
    rtn = RelativeState()
    rtn.header.frame_id = interfaces.CARRIER_RTN_FRAME
    data, pad, fields = layout(rtn)
    assert len(data) == 76 and not any(pad) and fields["position.x"][0] == 28 and fields["velocity.z"][0] == 68
    assert data == serialize_message(rtn)


def test_truth_messages_are_the_typed_messages():
    """Each sample's two messages, byte for byte, as the per-row conversions (array_to_elements, roe_to_msg) fill
    the typed messages and rclpy serializes them: stamps with the nanosecond carry and negative times, special
    floats (-0.0, inf, nan), angles to wrap."""
    rng = np.random.default_rng(7)
    n = 9
    epochs = [0.0, 604.354448002123, 0.9999999999, -0.25, 280800.0, 1e6 / 3.0, 60.0, 3600.000000001, 7.5]
    kep = np.column_stack([rng.uniform(6.8e6, 7e6, n), rng.uniform(0, 1e-3, n), rng.uniform(1.6, 1.8, n),
                           rng.uniform(-10, 10, (n, 3))])
    roe = rng.normal(0.0, 1e-3, (n, 6))
    roe[0] = 0.0
    roe[1, 2] = -0.0
    pos, vel = rng.normal(0, 1e3, (n, 3)), rng.normal(0, 1.0, (n, 3))
    pos[2] = [-0.0, math.inf, -math.inf]
    vel[3] = [math.nan, 0.0, -0.0]
    out = TruthMessages()(epochs, (kep, roe, (pos, vel)))
    assert len(out) == n
    for t, k, r, p, v, (roe_bytes, rtn_bytes) in zip(epochs, kep, roe, pos, vel, out):
        msg = roe_to_msg(r, array_to_elements(k), sec_to_time(t), frame_id=interfaces.TRUTH_FRAME)
        assert roe_bytes == typed(msg)
        state = RelativeState()
        state.header.stamp = sec_to_time(t)
        state.header.frame_id = interfaces.CARRIER_RTN_FRAME
        state.position.x, state.position.y, state.position.z = p.tolist()
        state.velocity.x, state.velocity.y, state.velocity.z = v.tolist()
        assert rtn_bytes == typed(state)


def test_groups_and_types_checked():
    rtn = RelativeState()
    with pytest.raises(ValueError, match="not consecutive"):
        Serialized(rtn, {"xz": ("position.x", "position.z")})
    with pytest.raises(ValueError, match="not consecutive"):
        Serialized(rtn, {"stamp": ("header.stamp.sec", "header.stamp.nanosec")})  # int32 then uint32
    with pytest.raises(ValueError, match="not supported"):
        layout(ManeuverPlan())  # a sequence of maneuvers
    rows = Serialized(rtn, {"state": ("position.x", "position.y", "position.z", "velocity.x", "velocity.y",
                                      "velocity.z")}).rows(2)
    rows["state"] = [[1.0, 2.0, 3.0, 4.0, 5.0, 6.0], [0.0] * 6]
    assert [len(m) for m in Serialized.messages(rows)] == [68, 68]  # the empty frame_id: 4 + 4 + 4 + 1, 3 padding
    rtn.position.x, rtn.position.y, rtn.position.z = 1.0, 2.0, 3.0
    rtn.velocity.x, rtn.velocity.y, rtn.velocity.z = 4.0, 5.0, 6.0
    assert Serialized.messages(rows)[0] == typed(rtn)
