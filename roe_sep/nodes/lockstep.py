"""Lockstep sim time: the participant side of the protocol (:class:`Lockstep`) and the simulator's side
(:class:`Coordinator`).

The idea of PX4 SITL lockstep and of steppable simulator clocks, over plain DDS topics:

* The simulator publishes its outputs of a step (truth samples, executed burns, ``/clock``), then a
  ``roe_sep_msgs/LockstepStep`` on ``/lockstep/step`` with, for every counted topic, how many messages the simulator
  and all participants have published on it so far.
* A participant buffers every message of its counted input topics. It processes a round only once it holds every
  message the round counts, and then exactly those, in one canonical order (header stamp, then the order in which
  the node declared its inputs, then arrival on the topic, which DDS keeps per publisher): what it computes depends
  on the data alone, never on which topic's message DDS delivered first, on thread scheduling or on machine load.
  Then it acknowledges the round (``roe_sep_msgs/LockstepAck`` on ``/lockstep/ack``) with the counts of what it
  published meanwhile.
* When every participant has acknowledged and nothing new was published on a topic that a participant reads, the
  step is over; otherwise the simulator opens another round of the same step with the new counts (an ejection
  event -> the drift-stop plan -> its safety check: three rounds). Only then does sim time advance.

A node that never receives a step message (run alone, or driven by a test) processes every message at once, as
before. Topics outside the step's counts (e.g. a ground segment's own publisher) are processed at once too.
"""

import collections
import time

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from roe_sep_msgs.msg import LockstepAck, LockstepStep

from .. import interfaces
from ..errors import BadMessage
from ..stamps import sec_nanosec
from ..validate import validator_for
from .convert import sec_to_time, time_to_sec
from .diagnostics import ERROR, OK, publish_status
from .serialized import subscribe_decoded

STEP_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=interfaces.RECORDED_DEPTH,
                      reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.VOLATILE)
READER_DEPTH = 1000  # messages a counted input may queue before the node takes them
ACK_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.VOLATILE)


def header_stamp(msg) -> float:
    """Sim time [s] a message describes: its ``header.stamp``."""
    return time_to_sec(msg.header.stamp)


class CountingPublisher:
    """A publisher that counts what it publishes for the lockstep acknowledgements."""

    def __init__(self, lockstep, publisher, topic):
        self._lockstep, self._pub, self.topic = lockstep, publisher, topic

    def publish(self, msg):
        self._pub.publish(msg)
        self._lockstep.published[self.topic] += 1

    def get_subscription_count(self):
        return self._pub.get_subscription_count()

    def __getattr__(self, name):  # everything else of rclpy's Publisher
        return getattr(self._pub, name)


class Lockstep:
    """Participant in the lockstep protocol. ``subscribe`` and ``publisher`` replace the node's own
    ``create_subscription``/``create_publisher`` for the counted topics; ``on_step(t)`` (optional) runs after the
    messages of each step's first round, with the step's sim time ``t``."""

    def __init__(self, node, on_step=None, acknowledge=True):
        self.node = node
        self.name = node.get_name()
        self.on_step_callback = on_step
        self.acknowledge = acknowledge
        self.inputs = {}  # topic -> (callback, rank, stamp function)
        self.subscriptions = {}
        self.validators = {}
        self.what = {}  # topic -> how the node's reports name its messages
        self.rejected = collections.Counter()
        self.buffer = collections.defaultdict(collections.deque)  # topic -> messages not processed yet
        self.received = collections.Counter()
        self.processed = collections.Counter()
        self.published = collections.Counter()
        self.active = False  # a step message has arrived: lockstep mode
        self.pending = None  # the step round waiting for its messages
        self.last = None  # (step, round) last acknowledged
        self.time = None  # sim time of the current step [s]
        self.last_counts = {}  # topic -> count of the latest step message
        self.steps_done = 0
        self.on_round_done = None  # called after each round is processed (the coordinator's own bookkeeping)
        self.on_batch_done = None  # called after a round's messages, before on_step (work a node defers to it)
        self.in_batch = False  # the callbacks of a round's messages are running
        # the step messages of every round, decoded from their bytes (subscribe_decoded: the same values, cheaper)
        subscribe_decoded(node, LockstepStep, interfaces.LOCKSTEP_STEP_TOPIC, self.on_step_msg, STEP_QOS,
                          on_error=lambda exc: self.undecodable(interfaces.LOCKSTEP_STEP_TOPIC, exc))
        self.ack_pub = node.create_publisher(LockstepAck, interfaces.LOCKSTEP_ACK_TOPIC, ACK_QOS) \
            if acknowledge else None
        self._ack_msg = LockstepAck()  # refilled for every acknowledgement (_ack)
        self._inputs_version = 0  # counts the changes of ``inputs`` (the acknowledgement's list is rebuilt after one)
        self._ack_keys = None  # (_inputs_version, topics published) the acknowledgement's lists were built for
        self._ack_topics = []

    # ------------------------------------------------------------------ declaration
    def free_running(self, now, period=1.0):
        """Without lockstep steps (a free-running clock) run ``on_step(now())`` on a timer every ``period`` wall
        seconds. Once a step message has come (lockstep mode is never left) each step runs it and the timer is
        cancelled: it had nothing left to do, and the EventsExecutor still fired it about 50 times per 600 s step of
        sim time (24,000 callbacks a run). Returns the timer."""
        def tick():
            if self.active:
                timer.cancel()
                return
            self.on_step_callback(now())

        timer = self.node.create_timer(period, tick)
        return timer

    def subscribe(self, msg_type, topic, callback, qos, stamp=header_stamp, *, what=None, raw=False):
        """Subscribe ``callback`` to ``topic`` through the lockstep buffer (inputs are ranked in declaration
        order for messages with equal stamps). Every message is validated first (:mod:`.validate`); a bad one,
        or one whose callback raises, is reported on ``/diagnostics`` and the node goes on.

        ``raw``: take the serialized bytes and decode them with the compiled CDR decoder
        (:func:`~.serialized.decoder_for`: the same values, several times cheaper than rclpy's message for a
        stream read at every sample); the callback gets an object with the message's fields (a fixed array is a
        list). Typed when the type's definition cannot be compiled."""
        self.inputs[topic] = (self._guarded(topic, callback), len(self.inputs), stamp)
        self._inputs_version += 1
        self.validators[topic] = validator_for(msg_type)
        self.what[topic] = what or f"message on {topic}"
        # a deep reader queue: a counted message must never be overwritten before it is taken (a flood of bad
        # messages on a depth-1 latched topic would otherwise push out the good one)
        deep = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=max(qos.depth, READER_DEPTH),
                          reliability=qos.reliability, durability=qos.durability)
        take = lambda m, tp=topic: self._on_input(tp, m)  # noqa: E731
        if raw:
            self.subscriptions[topic] = subscribe_decoded(self.node, msg_type, topic, take, deep,
                                                          on_error=lambda exc, tp=topic: self.undecodable(tp, exc))
        else:
            self.subscriptions[topic] = self.node.create_subscription(msg_type, topic, take, deep)
        return self.subscriptions[topic]

    def unsubscribe(self, topic):
        """Stop reading ``topic`` (e.g. the ejector once the ejection is commanded): no step waits for it any more."""
        sub = self.subscriptions.pop(topic, None)
        if sub is not None:
            self.node.destroy_subscription(sub)
        self.inputs.pop(topic, None)
        self._inputs_version += 1
        self.buffer.pop(topic, None)

    def publisher(self, msg_type, topic, qos):
        self.published[topic] += 0
        return CountingPublisher(self, self.node.create_publisher(msg_type, topic, qos), topic)

    # ------------------------------------------------------------------ protocol
    def _report(self, text):
        self.node.get_logger().error(text)
        diag = getattr(self.node, "diag_pub", None)
        if diag is not None:
            try:
                publish_status(self.node, diag, ERROR, text, {"rejected": sum(self.rejected.values())})
            except Exception:  # noqa: BLE001  (shutting down)
                pass

    def _guarded(self, topic, callback):
        def call(msg):
            try:
                callback(msg)
            except Exception as exc:  # noqa: BLE001 -- a node never dies on a message; it says why it dropped it
                self._refuse(topic, f"dropped [{topic}]: {type(exc).__name__}: {exc}")
        return call

    def _refuse(self, topic, text):
        """A message of ``topic`` refused: counted in ``rejected`` and reported (``text`` follows its name)."""
        self.rejected[topic] += 1
        self._report(f"{self.what.get(topic, 'message on ' + topic)} {text}")

    def undecodable(self, topic, exc):
        """Bytes of a raw input (or of the protocol's own topics) that do not decode: dropped before they are
        counted, and reported."""
        self._refuse(topic, f"rejected [{topic}]: cannot be decoded: {type(exc).__name__}: {exc}")

    def _on_input(self, topic, msg):
        check = self.validators.get(topic)
        if check is not None:
            try:
                check(msg)
            except BadMessage as exc:  # dropped before it is counted: it cannot displace a good message
                self._refuse(topic, f"rejected [{topic}]: {exc}")
                return
        self.received[topic] += 1
        if self.active and topic in self.last_counts:
            self.buffer[topic].append(msg)
            self._try()
            return
        self.processed[topic] += 1
        self.inputs[topic][0](msg)

    @staticmethod
    def _counts(step: LockstepStep) -> dict:
        return dict(zip(step.topics, step.counts))

    def on_step_msg(self, step: LockstepStep):
        key = (step.step, step.round)
        if self.last is not None and key <= self.last:
            if key == self.last:
                self._ack(step)  # the coordinator asks again: our acknowledgement may have been lost
            return
        self.active = True
        self.pending = step
        self.last_counts = self._counts(step)
        self._try()

    def _try(self):
        step = self.pending
        if step is None:
            return
        counts = self.last_counts  # the pending step's counts (on_step_msg sets both), not rebuilt per message
        due = {}
        for topic in self.inputs:
            need = counts.get(topic, 0) - self.processed[topic]
            if need <= 0:
                continue
            if len(self.buffer[topic]) < need:
                return  # a counted message is still on its way
            due[topic] = need
        self.pending = None
        batch = []
        for topic, need in due.items():
            callback, rank, stamp = self.inputs[topic]
            for seq in range(need):
                msg = self.buffer[topic].popleft()
                batch.append((stamp(msg), rank, seq, callback, msg))
            self.processed[topic] += need
        batch.sort(key=lambda b: b[:3])
        self.time = time_to_sec(step.header.stamp)
        self.in_batch = True
        try:
            for _, _, _, callback, msg in batch:
                callback(msg)
        finally:
            self.in_batch = False
        if self.on_batch_done is not None:
            try:
                self.on_batch_done()
            except Exception as exc:  # noqa: BLE001 -- the round is still acknowledged: the loop goes on
                self._report(f"end-of-round work failed: {type(exc).__name__}: {exc}")
        if step.round == 0 and self.on_step_callback is not None and not step.final:
            self.on_step_callback(self.time)
        self.last = (step.step, step.round)
        self.steps_done += 1
        self._ack(step)
        if self.on_round_done is not None:
            self.on_round_done()

    def _ack(self, step):
        """Acknowledge ``step``'s round with the counts of what this node published so far. One message, refilled
        for every round (rclpy serializes it when it is published): the node's name, its inputs and its topics are
        set again only when they change (a subscription or a publisher added or removed)."""
        if self.ack_pub is None:
            return
        ack, published = self._ack_msg, self.published
        if self._ack_keys != (self._inputs_version, len(published)):
            self._ack_keys = (self._inputs_version, len(published))
            self._ack_topics = sorted(published)
            ack.node, ack.inputs, ack.topics = self.name, sorted(self.inputs), self._ack_topics
        ack.step, ack.round = step.step, step.round
        ack.published = [published[t] for t in self._ack_topics]
        stamp = ack.header.stamp
        stamp.sec, stamp.nanosec = sec_nanosec(time_to_sec(step.header.stamp))
        self.ack_pub.publish(ack)

    def now(self, fallback):
        """Sim time of the current step in lockstep mode, else ``fallback`` (the node clock)."""
        return self.time if self.active and self.time is not None else fallback


class Coordinator:
    """The simulator's side of the protocol: publishes the step messages, collects the acknowledgements, opens the
    reaction rounds of a step and advances sim time once a step is over.

    ``sim`` (the simulator node) provides: ``lockstep`` (its own :class:`Lockstep`, ``acknowledge=False``: it reads
    its inputs through the buffer too), ``t`` (sim time [s]), ``done``, ``duration``, ``time_step``, ``wait_for``
    ({topic: subscribers}), ``start_timeout``, ``waiting_since`` (wall time the start-up wait began), ``step_to(t)``
    (fly the burns due and move the truth to ``t``), ``publish_clock()``, ``status(level, message)``, ``fault(reason)``
    and the node's entity factories (``create_publisher``, ``create_timer``, ``count_subscribers``, ...)."""

    def __init__(self, sim, participants, step_timeout, real_time_factor):
        self.sim = sim
        self.participants = participants
        self.step_timeout, self.real_time_factor = step_timeout, real_time_factor
        self.lockstep = sim.lockstep
        self.lockstep.on_round_done = self.round_check
        self.step_pub = sim.create_publisher(LockstepStep, interfaces.LOCKSTEP_STEP_TOPIC, STEP_QOS)
        subscribe_decoded(sim, LockstepAck, interfaces.LOCKSTEP_ACK_TOPIC, self.on_ack, ACK_QOS,
                          on_error=lambda exc: self.lockstep.undecodable(interfaces.LOCKSTEP_ACK_TOPIC, exc))
        self.participant_set = frozenset(participants)
        self.acks = {}  # participant -> its latest LockstepAck
        self.acked = set()  # the participants whose latest acknowledgement is of the current round (_acked)
        self.step_index, self.round, self.t_prev = 0, 0, 0.0
        self.round_counts = {}
        self.round_sent = None  # wall time the current round was published (None: not started)
        self.wall_start = None
        self.continue_timer = None
        self.steps_published = 0
        self.timer = sim.create_timer(0.05, self.watch)

    def watch(self):
        """Wall-clock watchdog of the lockstep clock: starts the run once every participant is up, asks again for
        a lost acknowledgement, and fails the run with the silent participants named when a step waits longer
        than ``step_timeout`` (a fault detector only: it never changes what is simulated)."""
        if self.sim.done:
            return
        now = time.monotonic()
        if self.round_sent is None:  # not started: every participant and subscriber up?
            if self.ready(now):
                self.wall_start = now
                self._publish_step()
            return
        waited = now - self.round_sent
        if self.continue_timer is not None:
            return
        limit = self.sim.start_timeout if self.step_index == 0 else self.step_timeout
        if waited > limit:
            missing = [p for p in self.participants if self._acked(p) is False]
            step = f"step {self.step_index} round {self.round} (t = {self.sim.t:.0f} s)"
            self.sim.fault(f"lockstep: no acknowledgement of {step} from {', '.join(missing) or 'nobody'} within "
                           f"{limit:g} s" if missing else f"lockstep: {step} incomplete after {limit:g} s: the "
                           f"simulator still waits for counted messages {self._own_missing()}")
        elif waited > 1.0 and now - self.round_resent > 1.0:
            self.round_resent = now
            self.step_pub.publish(self.step_msg)  # a participant that missed it acknowledges again

    def ready(self, now):
        sim = self.sim
        missing = {t: n for t, n in sim.wait_for.items() if sim.count_subscribers(t) < n}
        if sim.count_subscribers(interfaces.LOCKSTEP_STEP_TOPIC) < len(self.participants):
            missing[interfaces.LOCKSTEP_STEP_TOPIC] = len(self.participants)
        if sim.count_publishers(interfaces.LOCKSTEP_ACK_TOPIC) < len(self.participants):
            missing[interfaces.LOCKSTEP_ACK_TOPIC + " (publishers)"] = len(self.participants)
        if not missing:
            return True
        if now - sim.waiting_since > sim.start_timeout:
            sim.fault(f"lockstep: participants not up within {sim.start_timeout:g} s: missing {missing}")
        return False

    def _own_missing(self):
        counts = self.lockstep.last_counts
        return {t: counts.get(t, 0) - self.lockstep.received[t] for t in self.lockstep.inputs
                if counts.get(t, 0) > self.lockstep.received[t]}

    def _acked(self, name):
        ack = self.acks.get(name)
        return ack is not None and (ack.step, ack.round) == (self.step_index, self.round)

    def on_ack(self, ack: LockstepAck):
        node = ack.node
        if node not in self.participant_set:
            return
        key = (ack.step, ack.round)
        prev = self.acks.get(node)
        if prev is None or key >= (prev.step, prev.round):
            self.acks[node] = ack
            if key == (self.step_index, self.round):
                self.acked.add(node)
            else:
                self.acked.discard(node)
        self.round_check()

    def _totals(self):
        """Messages published so far per counted topic: the simulator's and every participant's latest count."""
        totals = dict(self.lockstep.published)
        for ack in self.acks.values():
            for topic, n in zip(ack.topics, ack.published):
                totals[topic] = totals.get(topic, 0) + n
        return totals

    def _publish_step(self, final=False):
        totals = self._totals()
        topics = sorted(totals)
        msg = LockstepStep(step=self.step_index, round=self.round, period_start=float(self.t_prev), topics=topics,
                           counts=[int(totals[t]) for t in topics], final=final)
        msg.header.stamp = sec_to_time(self.sim.t)
        self.step_msg, self.round_counts = msg, totals
        self.acked = {p for p in self.participants if self._acked(p)}  # of the new round: none acknowledged it yet
        self.round_sent = self.round_resent = time.monotonic()
        self.steps_published += 1
        self.step_pub.publish(msg)
        if not final:
            self.lockstep.on_step_msg(msg)  # the simulator's own inputs of this round

    def round_check(self):
        """After every acknowledgement: the round is over when every participant and the simulator itself have
        processed it; a reaction (new messages on a topic someone reads) opens the next round of the same step,
        else sim time advances."""
        if self.sim.done or self.round_sent is None or self.continue_timer is not None:
            return
        if self.lockstep.last != (self.step_index, self.round):
            return
        if len(self.acked) < len(self.participant_set):  # the set holds _acked(p) for every p, kept by on_ack
            return
        totals = self._totals()
        read = set(self.lockstep.inputs)
        for ack in self.acks.values():
            read.update(ack.inputs)
        if any(totals.get(t, 0) != self.round_counts.get(t, 0) for t in read):
            self.round += 1
            self._publish_step()
            return
        self._continue()

    def _continue(self):
        """Advance to the next step now, or when the real-time factor allows."""
        sim = self.sim
        if self.continue_timer is not None:
            sim.destroy_timer(self.continue_timer)
            self.continue_timer = None
        if sim.t >= sim.duration:
            sim.done = True
            self._publish_step(final=True)
            sim.status(OK, "scenario complete")
            sim.get_logger().info(f"scenario complete: {self.steps_published} lockstep messages in "
                                  f"{time.monotonic() - self.wall_start:.1f} s")
            return
        t_next = min(sim.t + sim.time_step, sim.duration)
        if self.real_time_factor > 0:
            wait = self.wall_start + t_next / self.real_time_factor - time.monotonic()
            if wait > 0:
                self.continue_timer = sim.create_timer(wait, self._continue)
                return
        self.t_prev = sim.t
        sim.step_to(t_next)
        self.step_index += 1
        self.round = 0
        sim.publish_clock()
        self._publish_step()
