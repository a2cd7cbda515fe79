"""recorder: logs topics to a rosbag2-compatible MCAP bag directory (``ros2 bag record -s mcap`` equivalent).

Every 0.5 s (wall time) it looks for new topics that have a publisher and subscribes to them with ``raw=True``
(serialized CDR bytes, never deserialized, so a bad message cannot stop it), with a QoS that matches every
publisher's offer: RELIABLE if all publishers are reliable, TRANSIENT_LOCAL if all are transient-local -- latched
messages published before the recorder started are recorded too. Each message is written with
``log_time`` = the node clock at reception (sim time under ``use_sim_time``; messages arriving before the first
``/clock`` wait and take the first clock time); ``publish_time`` = ``log_time``: the callback takes no DDS message
info, so the node runs on any executor, the ``EventsExecutor`` of :mod:`roe_sep.nodes.suite` included.
File format and crash safety: :mod:`roe_sep.bag.writer` (flushed and fsync'ed every ``flush_period``);
SIGINT/SIGTERM close the file (summary, footer, ``metadata.yaml``); after a SIGKILL run
``roe-sep bag recover``.

Parameters: :data:`roe_sep.nodes.parameters.RECORDER` (``recorder --help``, docs/parameters.md). ``topics`` and
``exclude`` are string arrays whose default ``[]`` is set (``ros2 param get /recorder topics`` shows it).

Publishes ``/diagnostics`` (1 Hz wall time) with the message counts per topic.
"""

import collections
import struct
import sys
import time
from datetime import datetime

from diagnostic_msgs.msg import DiagnosticArray
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from roe_sep_msgs.msg import LockstepStep

from .. import interfaces
from ..bag import BagError, definitions
from ..bag import qos as bag_qos
from ..bag.writer import BagWriter
from .diagnostics import ERROR, OK, WARN, publish_status
from .params import ParameterError, declare
from .serialized import subscribe_decoded

DISCOVERY_PERIOD = 0.5  # s, wall time
DIAGNOSTICS_PERIOD = 1.0  # s, wall time
SUBSCRIPTION_DEPTH = interfaces.RECORDED_DEPTH  # as deep as the writers of the streams: a lag loses nothing
PENDING_LIMIT = 10000  # messages held while waiting for the first /clock
STEP_READER = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=SUBSCRIPTION_DEPTH,
                         reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE)


def absolute(name: str) -> str:
    return name if name.startswith("/") else "/" + name


def hidden(name: str) -> bool:
    return any(part.startswith("_") for part in name.split("/"))


class RecorderNode(Node):
    def __init__(self):
        super().__init__("recorder")

        output = declare(self, "output")
        topics = declare(self, "topics")
        exclude = declare(self, "exclude")
        self.flush_period = declare(self, "flush_period")
        self.topics = {absolute(t.strip()) for t in topics or []}
        self.exclude = {absolute(t.strip()) for t in exclude or []}
        # the lockstep protocol's own traffic is not scenario data (record it by naming it in 'topics')
        self.exclude |= {interfaces.LOCKSTEP_STEP_TOPIC, interfaces.LOCKSTEP_ACK_TOPIC} - self.topics
        self.sim_time = bool(self.get_parameter("use_sim_time").value)
        try:
            self.writer = BagWriter(output or datetime.now().strftime("rosbag2_%Y_%m_%d-%H_%M_%S"))
        except (BagError, OSError) as exc:
            raise ParameterError(f"parameter 'output': {exc}") from exc

        self.subs = {}
        self.messages_received = 0  # the shutdown drain runs while it rises (roe_sep.nodes.spin)
        self.skipped = set()
        self.pending = []  # (topic, data, publish_time) received before the first /clock under sim time
        self.errors = 0
        self.last_error = ""
        self._last_error_log = 0.0
        self.diag_pub = self.create_publisher(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, interfaces.DIAGNOSTICS)
        # lockstep: log times from the simulator's steps (see on_step)
        # (counts, lo, hi) of the latest step messages, in order; as deep as the topics' readers: the recorder is no
        # lockstep participant, so under load it may fall behind the simulator by many steps, and a step message lost
        # (a 10-deep reader) or dropped from here logs the messages it counts at a later step's time
        self.steps = collections.deque(maxlen=SUBSCRIPTION_DEPTH)
        self.steps_seen = 0  # step messages appended to self.steps so far (the serial of the next one)
        self.first_step = {}  # topic -> serial of the first step that may attribute its next held message
        self.last_counted = {}  # topic -> serial of the latest step message that counts it
        self.received = collections.Counter()
        self.held = collections.defaultdict(collections.deque)  # topic -> (n, data, source) not attributed yet
        self.last_log = {}  # topic -> last log time [ns] (monotone per channel)
        self.step_time = None  # ns, sim time of the latest step
        subscribe_decoded(self, LockstepStep, interfaces.LOCKSTEP_STEP_TOPIC, self.on_step, STEP_READER,
                          on_error=lambda exc: self._error(f"step message dropped: cannot be decoded: {exc}"))
        wall = Clock(clock_type=ClockType.STEADY_TIME)
        self.create_timer(DISCOVERY_PERIOD, self.discover, clock=wall)
        self.create_timer(float(self.flush_period), self.flush, clock=wall)
        self.create_timer(DIAGNOSTICS_PERIOD, self.report, clock=wall)
        self.get_logger().info(
            f"recording to {self.writer.path} ({'all topics' if not self.topics else sorted(self.topics)}"
            f"{', excluding ' + str(sorted(self.exclude)) if self.exclude else ''}), "
            f"flush every {self.flush_period:g} s")
        self.discover()

    # -- topics --------------------------------------------------------------------------------------------------
    def wanted(self, name: str) -> bool:
        if name in self.exclude:
            return False
        return name in self.topics if self.topics else not hidden(name)

    def peers_constructed(self):
        """Every node of this process is constructed (:func:`roe_sep.nodes.spin.serve`): record their topics now.
        A managed node that starts itself (``autostart``) has its publishers by then, so a run in one process starts
        stepping without waiting for the first discovery tick (up to :data:`DISCOVERY_PERIOD` s)."""
        self.discover()

    def discover(self):
        try:
            for name, types in self.get_topic_names_and_types():
                if name in self.subs or name in self.skipped or not self.wanted(name):
                    continue
                publishers = self.get_publishers_info_by_topic(name)
                if publishers:
                    self.subscribe(name, types, publishers)
        except Exception as exc:  # noqa: BLE001  (graph queries fail during shutdown)
            self._error(f"topic discovery failed: {exc}")

    def subscribe(self, name, types, publishers):
        type_name = types[0]
        if len(types) > 1:
            self.get_logger().warning(f"{name} has several types {types}; recording {type_name}")
        try:
            cls = definitions.message_class(type_name)
        except Exception as exc:  # noqa: BLE001
            self.skipped.add(name)
            self._error(f"not recording {name}: type {type_name} is not available ({exc})")
            return
        try:
            definition = definitions.full_text(type_name)
        except (definitions.DefinitionNotFound, ValueError, RecursionError) as exc:
            definition = ""
            self.get_logger().warning(f"{name}: no message definition for {type_name} ({exc}); schema left empty")
        offers = [bag_qos.from_rclpy(p.qos_profile) for p in publishers]
        hashes = [str(p.topic_type_hash) for p in publishers if str(p.topic_type_hash) != "INVALID"]
        reliable, transient = bag_qos.request_for_offers(offers)
        profile = QoSProfile(
            history=HistoryPolicy.KEEP_LAST, depth=SUBSCRIPTION_DEPTH,
            reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
            durability=DurabilityPolicy.TRANSIENT_LOCAL if transient else DurabilityPolicy.VOLATILE)
        self.writer.add_topic(name, type_name, offers, hashes[0] if hashes else "", definition)
        self.subs[name] = self.create_subscription(
            cls, name, lambda data, topic=name: self.on_message(topic, data), profile, raw=True)
        self.get_logger().info(f"recording {name} [{type_name}] "
                               f"({'reliable' if reliable else 'best_effort'}, "
                               f"{'transient_local' if transient else 'volatile'})")

    # -- messages ------------------------------------------------------------------------------------------------
    def on_message(self, topic, data):
        self.messages_received += 1
        try:
            source = None  # publish_time = log_time
            if self.step_time is not None:
                self._lockstep_message(topic, data, source)
                return
            now = self.get_clock().now().nanoseconds
            if self.sim_time and now == 0 and len(self.pending) < PENDING_LIMIT:
                self.pending.append((topic, data, source))
                return
            self._write_pending(now)
            self.writer.write(topic, data, now, source or now)
        except Exception as exc:  # noqa: BLE001  (a node never dies on a bad message)
            self._error(f"message on {topic} not recorded: {exc}")

    # -- lockstep log times --------------------------------------------------------------------------------------
    # Under the lockstep clock (docs/run.md) every message is logged at the sim time at which it was
    # published, whatever order DDS delivers the topics in. A step message (j, r) counts the messages published on
    # each topic so far, so the n-th message of a topic was published just before the first step message whose
    # count reaches n: before round 0 of step j, by the simulator advancing over (t_{j-1}, t_j] or by a participant
    # in the last round of step j-1 (logged at its header stamp clamped to [t_{j-1}, t_j]); before a later round, by
    # a participant reacting at t_j (logged at t_j). /clock is logged at its own value, topics the protocol does not
    # count (e.g. /diagnostics) at the sim time of the latest step; log times never decrease on a channel.
    def on_step(self, step: LockstepStep):
        t = step.header.stamp.sec * 1_000_000_000 + step.header.stamp.nanosec
        lo = int(round(step.period_start * 1e9)) if step.round == 0 else t
        counts = dict(zip(step.topics, step.counts))
        self.steps.append((counts, min(lo, t), t))
        for topic in counts:
            self.last_counted[topic] = self.steps_seen
        self.steps_seen += 1
        if self.pending:  # received before the clock started (start-up statuses): published before this step
            self._write_pending(min(lo, t))
        self.step_time = t if self.step_time is None else max(self.step_time, t)
        for topic in list(self.held):
            self._release(topic)

    def _lockstep_message(self, topic, data, source):
        if topic == interfaces.CLOCK_TOPIC:
            self._write_monotone(topic, data, _stamp_ns(data), source)
            return
        # a step message still held counts the topic (the serial of the latest that does, against the oldest held)
        if self.last_counted.get(topic, -1) < self.steps_seen - len(self.steps):
            self._write_monotone(topic, data, self.step_time, source)
            return
        n = self.received[topic] = self.received[topic] + 1
        self.held[topic].append((n, data, source))
        self._release(topic)

    def _release(self, topic):
        """Write the held messages of ``topic`` that a step attributes: the n-th at the window of the first step
        whose count reaches n. Counts never decrease from one step message to the next (they are totals, and the
        simulator's single reliable writer delivers in order), so the search for a topic's next message resumes at
        the step where its previous one was found instead of scanning every step held from the oldest on."""
        held = self.held[topic]
        steps = self.steps
        count = len(steps)
        base = self.steps_seen - count  # serial of steps[0]
        k = max(self.first_step.get(topic, 0), base) - base
        while held:
            n, data, source = held[0]
            while k < count and steps[k][0].get(topic, 0) < n:
                k += 1
            self.first_step[topic] = base + k
            if k == count:
                return
            _, lo, hi = steps[k]
            held.popleft()
            log_ns = _stamp_ns(data)  # clamped to [lo, hi] (lo <= hi: on_step stores min(lo, t), t)
            self._write_monotone(topic, data, lo if log_ns < lo else hi if log_ns > hi else log_ns, source)

    def _write_monotone(self, topic, data, log_ns, source):
        log_ns = int(log_ns)
        last = self.last_log.get(topic, 0)
        if log_ns < last:  # never before the channel's previous log time
            log_ns = last
        self.last_log[topic] = log_ns
        self.writer.write(topic, data, log_ns, source or log_ns)

    def _flush_held(self):
        """At shutdown: what no step message attributed was published in the last step."""
        for topic, held in self.held.items():
            while held:
                _, data, source = held.popleft()
                self._write_monotone(topic, data, self.step_time or 0, source)

    def _write_pending(self, now):
        """What arrived before the first clock time, at ``now`` (a /clock message at its own value)."""
        pending, self.pending = self.pending, []
        for topic, data, source in pending:
            self._write_monotone(topic, data, _stamp_ns(data) if topic == interfaces.CLOCK_TOPIC else now, source)

    def flush(self):
        try:
            now = self.get_clock().now().nanoseconds
            if self.pending and (now or not self.sim_time):
                self._write_pending(now)
            if self.writer.dirty:
                self.writer.flush()
        except Exception as exc:  # noqa: BLE001  (disk full, ...): keep the node alive and say so
            self._error(f"flush to {self.writer.path} failed: {exc}")

    # -- status --------------------------------------------------------------------------------------------------
    def _error(self, text):
        self.errors += 1
        self.last_error = text
        if time.monotonic() - self._last_error_log > 1.0:
            self._last_error_log = time.monotonic()
            self.get_logger().error(text)

    def report(self):
        values = {"output": str(self.writer.path), "topics": len(self.subs), "messages": self.writer.message_count,
                  "errors": self.errors}
        values.update({name: t["message_count"] for name, t in sorted(self.writer.topics.items())})
        if self.errors:
            level, text = (ERROR if "flush" in self.last_error else WARN), self.last_error
        else:
            level, text = OK, f"recording {len(self.subs)} topics, {self.writer.message_count} messages"
        try:
            publish_status(self, self.diag_pub, level, text, values)
        except Exception:  # noqa: BLE001  (context shutting down)
            pass

    def destroy_node(self):
        writer = getattr(self, "writer", None)
        if writer is not None:
            try:
                self._write_pending(self.get_clock().now().nanoseconds)
                self._flush_held()
            except Exception:  # noqa: BLE001
                pass
            writer.close()
            text = f"bag closed: {writer.path} ({writer.message_count} messages, {len(writer.topics)} topics)"
            if self.context.ok():
                self.get_logger().info(text)
            else:  # after SIGINT/SIGTERM the context is already shut down: no /rosout any more
                print(f"[INFO] [recorder]: {text}", file=sys.stderr)
        return super().destroy_node()


def _stamp_ns(data: bytes) -> int:
    """The first builtin_interfaces/Time of a CDR-serialized message (its header stamp, a maneuver's epoch, a
    clock's value) [ns]; 0 if the data is too short. Only used to place a log time inside its step."""
    if len(data) < 12:
        return 0
    sec, nsec = (_STAMP_LE if data[1] == 1 else _STAMP_BE).unpack_from(data, 4)
    return sec * 1_000_000_000 + nsec


_STAMP_LE, _STAMP_BE = struct.Struct("<iI"), struct.Struct(">iI")  # a stamp (int32 sec, uint32 nanosec) in CDR


def main(args=None):
    from .spin import run

    return run(RecorderNode, args)


if __name__ == "__main__":
    from ..process_exit import exit_process

    exit_process(main())
