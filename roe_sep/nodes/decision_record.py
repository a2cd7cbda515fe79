"""A planner's decisions outside its process (docs/run.md, "Decisions"): the decision record published on the node's
latched decisions topic after every decision, and read back when the node (re)starts, before it plans anything.

The node creates the topic's publisher and subscription (``interfaces.<NODE>_DECISIONS_TOPIC``, std_msgs/String
carrying :func:`roe_sep.core.decisions.common.decision_record`, RELIABLE + TRANSIENT_LOCAL, depth 1) and hands them
to :class:`DecisionRecord`. A latched sample lives only as long as its writer: the ``ground_bridge`` keeps the last
record of each planner and latches it again from its own writer (:class:`~roe_sep.nodes.ground_bridge.
GroundBridgeNode`), so a planner killed and restarted reads back what it decided.

Start-up: the node subscribes its inputs only once the read-back is over, so that the simulator's clock (which
waits for those subscribers) cannot run ahead of it. Over when a record arrives, or the keeper's empty string
(nothing kept: a fresh run), or ``recover_timeout`` wall seconds after the start (no keeper: a node started alone).
The graph is not asked whether a keeper exists: on a loaded host a new process took more than 2 s to discover it.
"""

import time

from rclpy.clock import Clock as RclpyClock
from rclpy.clock import ClockType
from std_msgs.msg import String

from ..core.decisions.common import decision_record, read_record
from .diagnostics import ERROR, publish_status

POLL = 0.05  # wall s between the read-back checks


class DecisionRecord:
    """The decision record of ``node`` (its name is the record's) on ``publisher``, read back from
    ``subscription``'s topic at start: ``start(state)`` is called once with the recovered state (a ``state_cls``
    read by ``restored``) or None. ``publish(state, stamp)`` after each event: a record when the persisted state
    changed."""

    def __init__(self, node, publisher, topic, state_cls, *, timeout, start):
        self.node, self.publisher, self.topic, self.state_cls = node, publisher, topic, state_cls
        self.timeout, self.start = float(timeout), start
        self.version = 0
        self.kept = None  # the persisted state of the last record
        self.recovered = None
        self.done = False
        self.t0 = time.monotonic()
        self.subscription = None
        self.timer = node.create_timer(POLL, self._check, clock=RclpyClock(clock_type=ClockType.STEADY_TIME))

    def on_record(self, msg: String):
        """A record on the topic (the keeper's latched one, during the read-back): the newest is recovered."""
        if self.done:
            return
        if msg.data == "":  # the keeper has nothing: a fresh start
            self._finish("the keeper holds no decision record")
            return
        try:
            version, _, persisted = read_record(msg.data, self.node.get_name())
            state = self.state_cls.restored(persisted)
        except ValueError as exc:
            publish_status(self.node, self.node.diag_pub, ERROR, f"decision record not recovered: {exc}")
            return
        if self.recovered is None or version > self.recovered[0]:
            self.recovered = (version, state, persisted)
        self._finish(f"decision record {version} read back")

    def _check(self):
        waited = time.monotonic() - self.t0
        if waited >= self.timeout:
            self._finish(f"no decision record within recover_timeout = {self.timeout:g} s")

    def _finish(self, why: str):
        if self.done:
            return
        self.node.get_logger().info(f"start: {why}")
        self.done = True
        self.timer.cancel()
        self.node.destroy_timer(self.timer)
        if self.subscription is not None:
            self.node.destroy_subscription(self.subscription)
        state = None
        if self.recovered is not None:
            self.version, state, self.kept = self.recovered
        self.start(state)

    def publish(self, state, stamp: float) -> bool:
        """Publish the record of ``state`` at sim time ``stamp`` [s] when its persisted part changed; whether it
        did."""
        persisted = state.persisted()
        if persisted == self.kept:
            return False
        self.kept = persisted
        self.version += 1
        self.publisher.publish(String(data=decision_record(self.node.get_name(), self.version, stamp, state)))
        return True
