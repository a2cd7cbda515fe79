"""A process's life cycle (roe_sep.nodes.spin.serve) with every node in the process, as a campaign's run has it: the
recorder records its peers' topics from their first message, and the short local drain loses nothing."""

import signal
import subprocess
import sys
import time

import pytest
from rclpy.serialization import deserialize_message  # noqa: E402
from rosutil import rclpy, ros_env  # noqa: I001  (skips without rclpy)
from std_msgs.msg import String  # noqa: E402

from roe_sep.bag import info  # noqa: E402
from roe_sep.bag import reader as bag_reader  # noqa: E402
from roe_sep.nodes.recorder import RecorderNode  # noqa: E402
from roe_sep.nodes.spin import serve, wait_for_acknowledgments  # noqa: E402

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


def test_in_process_delivery_is_synchronous(ros_context):
    """The premise of the local drain (spin.DRAIN_IDLE_LOCAL): a message published to a reader of the same process
    is in that reader when ``publish()`` returns."""
    a, b = rclpy.create_node("spin_test_a"), rclpy.create_node("spin_test_b")
    pub = a.create_publisher(String, TOPIC, 10)
    sub = b.create_subscription(String, TOPIC, lambda m: None, 10)
    assert pub.get_subscription_count() == 1  # local matching is immediate too
    for k in range(500):
        pub.publish(String(data=str(k)))
        taken = sub.handle.take_message(String, False)
        assert taken is not None and taken[0].data == str(k), k


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


LISTENER = """
import sys, rclpy
from std_msgs.msg import String
rclpy.init()
node = rclpy.create_node("spin_test_listener")
node.create_subscription(String, sys.argv[1], lambda m: None, 1000)
print("up", flush=True)
rclpy.spin(node)
"""


def test_a_process_waits_for_its_readers_to_acknowledge_before_it_ends(ros_context):
    """spin.wait_for_acknowledgments: a reader in another process that is not running (SIGSTOP: a descheduled
    listeners' process) holds the publisher's wait until the budget ends (False, after the budget, not before); once it
    runs again, everything is acknowledged (True, well inside the budget)."""
    topic = "/spin_test/acked"
    listener = subprocess.Popen([sys.executable, "-c", LISTENER, topic], env=ros_env(), stdout=subprocess.PIPE,
                                text=True)
    node = rclpy.create_node("spin_test_acked")
    try:
        assert listener.stdout.readline().strip() == "up"
        pub = node.create_publisher(String, topic, 1000)
        end = time.monotonic() + 30
        while pub.get_subscription_count() < 1:
            assert time.monotonic() < end, "the listener was not discovered"
            time.sleep(0.05)
        listener.send_signal(signal.SIGSTOP)
        for k in range(50):
            pub.publish(String(data=str(k)))
        start = time.monotonic()
        assert not wait_for_acknowledgments([node], budget=1.0)
        assert time.monotonic() - start >= 0.95
        listener.send_signal(signal.SIGCONT)
        start = time.monotonic()
        assert wait_for_acknowledgments([node], budget=20.0)
        # Fast DDS's default heartbeat period (3 s) bounds the time; a run's processes get 0.1 s (graph.dds_profile)
        assert time.monotonic() - start < 10.0
    finally:
        listener.send_signal(signal.SIGCONT)
        listener.kill()
        listener.wait()
        node.destroy_node()


LEAVING = """
import signal, rclpy
from roe_sep.nodes.spin import serve
before = signal.getsignal(signal.SIGINT)
for leaving in (False, True):
    code = serve([("t", lambda: rclpy.create_node("spin_leaving_test"))], [], until=lambda: True, leaving=leaving)
    print(code, signal.getsignal(signal.SIGINT) is (signal.SIG_IGN if leaving else before),
          signal.getsignal(signal.SIGTERM) is (signal.SIG_IGN if leaving else signal.SIG_DFL))
"""


def test_a_process_that_ends_after_serve_ignores_the_stop_signals_from_its_end():
    """``leaving`` (a node's main()): SIGINT and SIGTERM ignored as serve returns, never Python's KeyboardInterrupt
    handler in between (ros2 launch's late SIGINT there killed a cleanly stopped node, exit -2); without it, the
    handlers in place before are back."""
    out = subprocess.run([sys.executable, "-c", LEAVING], env=ros_env(), capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and out.stdout.split() == ["0", "True", "True", "0", "True", "True"], out
