"""The lockstep protocol's bookkeeping on stand-in nodes (no DDS, no rclpy context): the acknowledgement a participant
publishes and the coordinator's count of the participants that acknowledged the current round."""

import math
import random

import pytest

pytest.importorskip("rclpy", reason="the message classes come with the project venv (make test)")

from roe_sep_msgs.msg import LockstepAck, LockstepStep  # noqa: E402

from roe_sep.nodes.convert import sec_to_time, time_to_sec  # noqa: E402
from roe_sep.nodes.lockstep import Coordinator, Lockstep  # noqa: E402


class Publisher:
    """Keeps a copy of the fields of every message published (a reused message changes after its publish)."""

    def __init__(self, log):
        self.log = log

    def publish(self, msg):
        if isinstance(msg, LockstepAck):
            self.log.append((msg.node, msg.step, msg.round, list(msg.inputs), list(msg.topics), list(msg.published),
                             msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id))
        else:
            self.log.append(msg)

    def get_subscription_count(self):
        return 0


class Node:
    def __init__(self, name="participant"):
        self.name, self.published, self.timers = name, [], []

    def get_name(self):
        return self.name

    def create_subscription(self, *args, **kwargs):
        return object()

    def destroy_subscription(self, sub):
        pass

    def create_publisher(self, *args, **kwargs):
        return Publisher(self.published)

    def create_timer(self, period, callback):
        self.timers.append(callback)
        return callback

    def destroy_timer(self, timer):
        pass


def step_msg(step, rnd, t, counts):
    msg = LockstepStep(step=step, round=rnd, topics=sorted(counts), counts=[counts[k] for k in sorted(counts)])
    msg.header.stamp = sec_to_time(t)
    return msg


def built_ack(lockstep, step):
    """The acknowledgement as it was built before it was reused: a new message with every list sorted again."""
    topics = sorted(lockstep.published)
    ack = LockstepAck(node=lockstep.name, step=step.step, round=step.round, inputs=sorted(lockstep.inputs),
                      topics=topics, published=[lockstep.published[t] for t in topics])
    ack.header.stamp = sec_to_time(time_to_sec(step.header.stamp))
    return (ack.node, ack.step, ack.round, list(ack.inputs), list(ack.topics), list(ack.published),
            ack.header.stamp.sec, ack.header.stamp.nanosec, ack.header.frame_id)


def test_the_reused_acknowledgement_is_the_one_built_anew_each_round():
    node = Node()
    ls = Lockstep(node)
    ls.subscribe(LockstepStep, "/b", lambda m: None, qos_of(10), stamp=lambda m: 0.0)
    pub = ls.publisher(LockstepStep, "/out", qos_of(10))
    expected = []
    times = [0.0, 600.0, 600.0, 1200.0, 1234.5678901234, 2.0**31 - 1.5, 1800.0]
    for k, t in enumerate(times):
        step = step_msg(k, k % 2, t, {})
        if k == 2:
            pub.publish(LockstepStep())
            pub.publish(LockstepStep())
        if k == 3:
            ls.subscribe(LockstepStep, "/a", lambda m: None, qos_of(10), stamp=lambda m: 0.0)
            ls.publisher(LockstepStep, "/another", qos_of(10))
        if k == 5:
            ls.unsubscribe("/b")
        if k == 6:  # one topic out and another in: as many inputs as before, other names
            ls.subscribe(LockstepStep, "/c", lambda m: None, qos_of(10), stamp=lambda m: 0.0)
            ls.unsubscribe("/a")
        ls.on_step_msg(step)
        expected.append(built_ack(ls, step))
        ls.on_step_msg(step)  # asked again: acknowledged again, the same
        expected.append(built_ack(ls, step))
    acks = [m for m in node.published if isinstance(m, tuple)]
    assert acks == expected
    assert acks[-1][3] == ["/c"] and acks[-1][4] == ["/another", "/out"]


def qos_of(depth):
    from rclpy.qos import QoSProfile

    return QoSProfile(depth=depth)


class Sim(Node):
    """The simulator's side for the coordinator: a lockstep without inputs, time that only advances."""

    def __init__(self):
        super().__init__("sim")
        self.done, self.duration, self.time_step, self.t = False, 1e9, 600.0, 0.0
        self.lockstep = Lockstep(self, acknowledge=False)

    def step_to(self, t):
        self.t = t

    def publish_clock(self):
        pass

    def status(self, level, text):
        pass


def test_the_coordinators_set_of_acknowledged_participants_is_the_scan_of_every_participant():
    sim = Sim()
    names = ["a", "b", "c", "d"]
    coord = Coordinator(sim, names, step_timeout=10.0, real_time_factor=0.0)
    coord.wall_start = 0.0
    coord._publish_step()
    rng = random.Random(5)
    rounds = []
    for _ in range(3000):
        key = (coord.step_index, coord.round)
        rounds.append(key)
        node = rng.choice(names + ["stranger"])
        step, rnd = key if rng.random() < 0.6 else rng.choice(rounds)  # else a late or repeated one
        coord.on_ack(LockstepAck(node=node, step=step, round=rnd))
        assert coord.acked == {p for p in names if coord._acked(p)}
    assert coord.step_index > 100  # the rounds did complete and sim time advanced
    # acknowledgements of rounds the coordinator has not asked for (never sent; the bookkeeping still holds)
    for node in names:
        key = (coord.step_index, coord.round)
        coord.on_ack(LockstepAck(node=node, step=key[0] + rng.randint(0, 1), round=key[1] + rng.randint(1, 2)))
        assert coord.acked == {p for p in names if coord._acked(p)}
        coord.on_ack(LockstepAck(node=node, step=key[0], round=key[1]))
        assert coord.acked == {p for p in names if coord._acked(p)}


class Logger:
    def __init__(self):
        self.errors = []

    def error(self, text):
        self.errors.append(text)


class RawNode(Node):
    """A stand-in node that keeps each subscription's callback and keyword arguments (``raw``)."""

    def __init__(self):
        super().__init__()
        self.subs, self.logger = {}, Logger()

    def create_subscription(self, msg_type, topic, callback, qos, **kwargs):
        self.subs[topic] = (callback, kwargs)
        return object()

    def get_logger(self):
        return self.logger


def truth_msg(t, a_da=12.5):
    from roe_sep_msgs.msg import RelativeOrbitalElements

    msg = RelativeOrbitalElements(a_da=a_da, a_dl=-1234.5678901234567, a_dex=1e-300, a_dey=-0.0, a_dix=3.25,
                                  a_diy=math.pi)
    msg.header.stamp = sec_to_time(t)
    msg.header.frame_id = "truth"
    msg.covariance = [k * 0.1 for k in range(36)]
    c = msg.chief
    c.semi_major_axis, c.eccentricity, c.inclination = 6_878_137.0 + 1.0 / 3.0, 1e-3, 1.7
    c.raan, c.arg_perigee, c.mean_arg_latitude = -2.5, 0.75, 123.0 / 7.0
    return msg


def test_a_raw_input_gives_the_callback_the_typed_messages_values_and_drops_bytes_that_do_not_decode():
    """``subscribe(..., raw=True)``: the bytes DDS delivers, decoded by the compiled CDR decoder, reach the callback
    with every field of the typed message, to the bit; bytes that do not decode and a decoded message the validator
    refuses are dropped and reported, and the node goes on."""
    from rclpy.serialization import serialize_message
    from roe_sep_msgs.msg import RelativeOrbitalElements

    from roe_sep.validate import ROE_FIELDS

    node, got = RawNode(), []
    ls = Lockstep(node)
    ls.subscribe(RelativeOrbitalElements, "/truth", got.append, qos_of(10), raw=True)
    deliver, kwargs = node.subs["/truth"]
    assert kwargs == {"raw": True}
    sent = truth_msg(1234.5678901234)
    deliver(serialize_message(sent))
    deliver(serialize_message(sent)[:-40])  # cut off
    deliver(serialize_message(truth_msg(1300.0, a_da=math.nan)))  # decodes, refused by the truth validator
    deliver(serialize_message(truth_msg(1400.0)))
    assert len(got) == 2 and ls.rejected["/truth"] == 2 and len(node.logger.errors) == 2
    assert "cannot be decoded" in node.logger.errors[0] and "a_da" in node.logger.errors[1]
    msg = got[0]
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id) == (
        sent.header.stamp.sec, sent.header.stamp.nanosec, "truth")
    for name in ROE_FIELDS:
        assert getattr(msg, name).hex() == getattr(sent, name).hex(), name
    for name in ("semi_major_axis", "eccentricity", "inclination", "raan", "arg_perigee", "mean_arg_latitude"):
        assert getattr(msg.chief, name).hex() == getattr(sent.chief, name).hex(), name
    assert [float(v).hex() for v in msg.covariance] == [float(v).hex() for v in sent.covariance]


def test_a_typed_input_stays_typed():
    from roe_sep_msgs.msg import RelativeOrbitalElements

    node = RawNode()
    Lockstep(node).subscribe(RelativeOrbitalElements, "/truth", lambda m: None, qos_of(10))
    assert node.subs["/truth"][1] == {}


def test_step_messages_are_taken_raw_and_a_step_that_does_not_decode_is_reported():
    """A participant reads ``/lockstep/step`` raw (:func:`~roe_sep.nodes.serialized.subscribe_decoded`): the decoded
    step opens the round the typed message opens, and bytes that do not decode are reported, not raised."""
    from rclpy.serialization import serialize_message

    from roe_sep import interfaces

    runs = []
    for raw in (False, True):
        node = RawNode()
        ls = Lockstep(node)
        got = []
        ls.subscribe(LockstepStep, "/in", got.append, qos_of(10), stamp=lambda m: 0.0)
        deliver, kwargs = node.subs[interfaces.LOCKSTEP_STEP_TOPIC]
        assert kwargs == {"raw": True}
        step = step_msg(7, 0, 1234.5, {"/in": 0, "/other": 3})
        if raw:
            deliver(serialize_message(step)[:30])  # cut off: reported
            deliver(serialize_message(step))
        else:
            ls.on_step_msg(step)
        runs.append(([p for p in node.published], ls.last, ls.last_counts, ls.rejected.copy(), node.logger.errors))
    typed, decoded = runs
    assert decoded[:3] == typed[:3] and decoded[1] == (7, 0) and decoded[2] == {"/in": 0, "/other": 3}
    assert decoded[3][interfaces.LOCKSTEP_STEP_TOPIC] == 1 and "cannot be decoded" in decoded[4][0]


def test_bytes_of_another_encapsulation_go_to_rclpys_deserialization(monkeypatch):
    """Only the plain little-endian CDR that Fast DDS writes goes through the compiled decoder; other bytes (another
    encapsulation: big-endian, XCDR2) are deserialized by rclpy, as a typed subscription has them."""
    import rclpy.serialization
    from rclpy.serialization import serialize_message
    from roe_sep_msgs.msg import RelativeOrbitalElements

    from roe_sep.nodes import serialized

    compiled, by_rclpy = [], []
    real = serialized.decoder_for(RelativeOrbitalElements)
    monkeypatch.setattr(serialized, "decoder_for", lambda t: lambda d: compiled.append(d) or real(d))
    monkeypatch.setattr(rclpy.serialization, "deserialize_message", lambda d, t: by_rclpy.append(d) or t(a_da=1.0))
    node, got, errors = RawNode(), [], []
    serialized.subscribe_decoded(node, RelativeOrbitalElements, "/truth", got.append, qos_of(10),
                                 on_error=errors.append)
    deliver = node.subs["/truth"][0]
    data = serialize_message(truth_msg(60.0))
    other = [b"\x00\x00" + data[2:], b"\x00\x07" + data[2:]]  # big-endian CDR, XCDR2 little-endian headers
    for d in [data, *other]:
        deliver(d)
    assert compiled == [data] and by_rclpy == other and not errors
    assert got[0].a_da == 12.5 and [m.a_da for m in got[1:]] == [1.0, 1.0]
