"""The lockstep protocol's bookkeeping on stand-in nodes (no DDS, no rclpy context): the acknowledgement a participant
publishes and the coordinator's count of the participants that acknowledged the current round."""

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
