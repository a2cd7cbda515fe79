"""``roe-sep replay BAG``: play a recorded bag back onto the same topics (``ros2 bag play`` equivalent).

Each topic gets a publisher of its recorded type and the QoS its publishers offered when it was recorded
(``offered_qos_profiles``): reliability and durability as recorded, so a latched (TRANSIENT_LOCAL) topic is latched
again and a subscriber that joins later -- even after the last message, while the replay lingers -- still receives
it. The history depth is not visible to a recorder (DDS does not announce it); when the bag says ``unknown``,
transient-local topics keep the depth of the project's QoS table (1 for latched plans and events, 50 for the
executed-maneuver logs) and volatile ones use 100. Messages are published as the recorded serialized bytes, at the
recorded log-time offsets divided by ``--rate``, starting as soon as every volatile topic has a subscriber (at the
latest after ``--delay`` s: DDS discovery of a new participant occasionally takes ~3 s). ``/clock`` in the bag is
replayed like any topic; ``--clock`` without a recorded ``/clock`` publishes one from the log times.
"""

import re
import sys
import time

from ..checks import OneLineParser, finite_float, one_line
from ..children import exit_status
from ..errors import BagError
from . import reader
from .qos import to_rclpy

CLOCK_TOPIC = "/clock"
_TOPIC = re.compile(r"^(/[A-Za-z_][A-Za-z0-9_]*)+$")


def _project_depths() -> dict:
    """Depths of the transient-local topics of :mod:`roe_sep.interfaces` (docs/ros_interface.md)."""
    try:
        from .. import interfaces as q
    except Exception:  # noqa: BLE001  (rclpy missing: nothing to play anyway)
        return {}
    depths = {}
    for topic_attr, profile_attr in (("EXECUTED_TOPIC", "EXECUTED"), ("PLAN_CHECK_TOPIC", "EXECUTED")):
        topic, profile = getattr(q, topic_attr, None), getattr(q, profile_attr, None)
        if topic and profile is not None:
            depths[topic] = profile.depth
    return depths


def publisher_depth(topic: dict, known: dict) -> int:
    offers = topic["offered_qos_profiles"]
    offer = offers[0] if offers else {}
    if offer.get("history") == "keep_last" and int(offer.get("depth", 0)) > 0:
        return int(offer["depth"])
    if offer.get("history") == "keep_all":
        return max(1, topic["message_count"])
    if offer.get("durability") == "transient_local":
        return known.get(topic["name"], 1)
    return 100


# --rate: the playback wall time is the bag's span / rate, so a tiny rate is a hang in disguise
RATE = finite_float(1e-3, 1e9, unit="(playback speed factor)")
CLOCK_HZ = finite_float(0.1, 1000.0, unit="Hz")
WAIT_S = finite_float(0.0, 3600.0, unit="s")


def parser():
    p = OneLineParser(prog="roe-sep replay", description="Play a recorded bag back onto its topics.")
    p.add_argument("bag", help="bag directory (or .mcap file) written by the recorder or ros2 bag record -s mcap")
    p.add_argument("--rate", type=RATE, default=1.0, help="playback speed factor in [0.001, 1e9] (default 1)")
    p.add_argument("--topics", nargs="+", metavar="TOPIC", help="replay only these topics")
    p.add_argument("--clock", type=CLOCK_HZ, nargs="?", const=40.0, metavar="HZ",
                   help="publish /clock from the log times at HZ in [0.1, 1000] (default 40 Hz) when the bag has no "
                        "/clock")
    p.add_argument("--delay", type=WAIT_S, default=1.0,
                   help="wait up to this many seconds, in [0, 3600], for subscribers of every volatile topic before "
                        "the first message (DDS discovery; default 1)")
    p.add_argument("--linger", type=WAIT_S, default=2.0,
                   help="seconds in [0, 3600] to stay up after the last message so latched data reaches late "
                        "joiners (default 2)")
    return p


def load(bag, selected=None):
    """``(topics to play, bag has /clock)``; BagError for a bad bag, an unknown topic or a missing type."""
    from .definitions import message_class

    scanned = reader.info(bag)  # full record scan: a damaged bag is refused before anything is published
    if not scanned["complete"] or scanned["problems"]:
        raise BagError(f"{bag}: damaged bag ({'; '.join(scanned['problems'])}); recover it with `roe-sep bag recover` "
                       "and replay the result")
    topics = reader.topics(bag)
    names = {t["name"] for t in topics}
    if selected:
        bad = [s for s in selected if not _TOPIC.match(s if s.startswith("/") else "/" + s)]
        if bad:
            raise BagError(f"--topics: not a ROS topic name: {', '.join(repr(b) for b in bad)}")
        wanted = {s if s.startswith("/") else "/" + s for s in selected}
        missing = sorted(wanted - names)
        if missing:
            raise BagError(f"--topics: {', '.join(missing)} not in the bag {bag} (it has {', '.join(sorted(names))})")
        topics = [t for t in topics if t["name"] in wanted]
    if not any(t["message_count"] for t in topics):
        raise BagError(f"{bag}: no messages to replay")
    for t in topics:
        try:
            t["class"] = message_class(t["type"])
        except Exception as exc:  # noqa: BLE001
            raise BagError(f"{bag}: type {t['type']} of {t['name']} is not installed ({exc})") from None
    return topics, CLOCK_TOPIC in names


def play(bag, topics, args, has_clock) -> int:
    import rclpy
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from rclpy.signals import SignalHandlerOptions
    from rosgraph_msgs.msg import Clock

    rclpy.init(args=["roe-sep-replay"], signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node("replay")
    count, started = 0, time.monotonic()
    try:
        known = _project_depths()
        pubs = {t["name"]: node.create_publisher(
            t["class"], t["name"], to_rclpy((t["offered_qos_profiles"] or [{}])[0], publisher_depth(t, known)))
            for t in topics}
        clock_pub = None
        if args.clock and CLOCK_TOPIC not in pubs:
            if has_clock:
                print("roe-sep replay: /clock is in the bag but not selected; publishing it from the log times",
                      file=sys.stderr)
            clock_pub = node.create_publisher(Clock, CLOCK_TOPIC,
                                              QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))

        def publish_clock(ns):
            if clock_pub is not None:
                clock_pub.publish(Clock(clock=_time_msg(ns)))

        def wait_until(deadline, bag_ns_at, done=lambda: False):
            while True:
                left = deadline - time.monotonic()
                if left <= 0 or done():
                    return
                if clock_pub is not None:
                    publish_clock(bag_ns_at(time.monotonic()))
                    time.sleep(min(left, 1.0 / args.clock))
                else:
                    time.sleep(min(left, 0.1))

        # discovery: start when every volatile topic has a subscriber, at the latest after --delay
        volatile = [pubs[t["name"]] for t in topics
                    if (t["offered_qos_profiles"] or [{}])[0].get("durability") != "transient_local"]
        first = last = None
        t0 = time.monotonic() + args.delay
        for msg in reader.messages(bag, topics=list(pubs)):
            if first is None:
                first = msg.log_time
                wait_until(t0, lambda now: first,
                           lambda: volatile and all(p.get_subscription_count() for p in volatile))
                t0 = time.monotonic()
            target = t0 + (msg.log_time - first) * 1e-9 / args.rate
            wait_until(target, lambda now: first + int((now - t0) * args.rate * 1e9))
            publish_clock(msg.log_time)
            pubs[msg.topic].publish(msg.data)
            count, last = count + 1, msg.log_time
        wait_until(time.monotonic() + args.linger, lambda now: last)
    except KeyboardInterrupt as exc:
        print(f"roe-sep replay: interrupted after {count} messages", file=sys.stderr)
        return exit_status(exc)
    except Exception as exc:  # noqa: BLE001  (a record unreadable mid-play: stop with one line, not a traceback)
        print(f"roe-sep: error: replay stopped after {count} messages: {type(exc).__name__}: {one_line(exc)}",
              file=sys.stderr)
        return 1
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    print(f"replayed {count} messages on {len(topics)} topics from {bag} in {time.monotonic() - started:.1f} s "
          f"(rate {args.rate:g})")
    return 0


def _time_msg(ns: int):
    from builtin_interfaces.msg import Time

    return Time(sec=int(ns // 1_000_000_000), nanosec=int(ns % 1_000_000_000))


def main(argv=None) -> int:
    """``roe-sep replay BAG [--rate R] [--topics ...] [--clock [HZ]] [--delay S] [--linger S]``; exit 2 on a bad
    bag path, an unknown topic or a type that is not installed."""
    args = parser().parse_args(argv)
    try:
        topics, has_clock = load(args.bag, args.topics)
    except (BagError, OSError) as exc:
        print(f"roe-sep: error: {one_line(exc)}", file=sys.stderr)
        return 2
    return play(args.bag, topics, args, has_clock)


if __name__ == "__main__":
    raise SystemExit(main())
