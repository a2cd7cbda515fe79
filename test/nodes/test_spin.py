"""A process's life cycle (roe_sep.nodes.spin.serve) with every node in the process, as a campaign's run has it: the
recorder records its peers' topics from their first message, and the short local drain loses nothing."""

import pytest
from rclpy.serialization import deserialize_message  # noqa: E402
from rosutil import rclpy  # noqa: I001  (skips without rclpy)
from std_msgs.msg import String  # noqa: E402

from roe_sep.bag import info  # noqa: E402
from roe_sep.bag import reader as bag_reader  # noqa: E402
from roe_sep.nodes.recorder import RecorderNode  # noqa: E402
from roe_sep.nodes.spin import serve  # noqa: E402

pytestmark = pytest.mark.dds

TOPIC, N = "/spin_test/talk", 200


class Talker(rclpy.node.Node):
    """Publishes N messages, a burst of 20 at each tick of a 5 ms timer (the first tick before the recorder's first
    discovery tick, the last one right before ``until`` stops the spin)."""

    def __init__(self):
        super().__init__("spin_test_talker")
        self.pub = self.create_publisher(String, TOPIC, 1000)
        self.sent = 0
        self.timer = self.create_timer(0.005, self.tick)

    def tick(self):
        for _ in range(20):
            if self.sent < N:
                self.pub.publish(String(data=str(self.sent)))
                self.sent += 1


def test_in_process_delivery_is_synchronous():
    """The premise of the local drain (spin.DRAIN_IDLE_LOCAL): a message published to a reader of the same process
    is in that reader when ``publish()`` returns."""
    rclpy.init()
    try:
        a, b = rclpy.create_node("spin_test_a"), rclpy.create_node("spin_test_b")
        pub = a.create_publisher(String, TOPIC, 10)
        sub = b.create_subscription(String, TOPIC, lambda m: None, 10)
        assert pub.get_subscription_count() == 1  # local matching is immediate too
        for k in range(500):
            pub.publish(String(data=str(k)))
            taken = sub.handle.take_message(String, False)
            assert taken is not None and taken[0].data == str(k), k
    finally:
        rclpy.try_shutdown()


def test_a_process_records_its_peers_from_the_first_message(tmp_path):
    bag = tmp_path / "bag"
    nodes = {}

    def make(name, cls):
        def factory():
            nodes[name] = cls()
            return nodes[name]
        return name, factory

    code = serve([make("recorder", RecorderNode), make("talker", Talker)],
                 ["spin_test", "--ros-args", "-p", f"output:={bag}", "-p", f"topics:=[{TOPIC}]"],
                 until=lambda: "talker" in nodes and nodes["talker"].sent == N)
    assert code == 0
    assert info(bag)["complete"]
    got = [deserialize_message(m.data, String).data for m in bag_reader.messages(bag, topics=[TOPIC])]
    assert got == [str(k) for k in range(N)]
