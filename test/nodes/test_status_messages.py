"""StatusMessages (messages built once, refilled) publishes what publish_status publishes, field for field."""

from types import SimpleNamespace

from builtin_interfaces.msg import Time
from rclpy.serialization import deserialize_message, serialize_message

from roe_sep.nodes.diagnostics import ERROR, OK, WARN, StatusMessages, publish_status


class Capture:
    def __init__(self):
        self.sent = []

    def publish(self, msg):
        # serialized when published, as rclpy does (compared as messages: CDR padding bytes are not defined)
        self.sent.append(deserialize_message(serialize_message(msg), type(msg)))


def fake_node(active):
    clock = SimpleNamespace(now=lambda: SimpleNamespace(to_msg=lambda: Time(sec=7, nanosec=5)))
    return SimpleNamespace(get_name=lambda: "safety_monitor", get_clock=lambda: clock,
                           lockstep=SimpleNamespace(active=active, time=1234.5 if active else None))


def test_refilled_messages_are_the_new_ones():
    keys = ("t_s", "along_track_m", "min_rn_m")
    for active in (True, False):
        node = fake_node(active)
        old, new = Capture(), Capture()
        reused = StatusMessages(node, new, keys, part="truth")
        for k, level in enumerate((OK, WARN, ERROR, OK, b"\x01")):
            values = {"t_s": f"{600.0 * k:.0f}", "along_track_m": f"{-1.5 * k:.1f}", "min_rn_m": k}
            publish_status(node, old, level, f"truth: case {k}", values, part="truth")
            reused.publish(level, f"truth: case {k}", values)
            if active:
                node.lockstep.time += 60.0
        assert old.sent == new.sent


def test_other_keys_are_refused():
    reused = StatusMessages(fake_node(True), Capture(), ("a", "b"))
    try:
        reused.publish(OK, "x", {"b": 1, "a": 2})
    except ValueError as exc:
        assert "not the keys" in str(exc)
    else:
        raise AssertionError("keys in another order were accepted")
