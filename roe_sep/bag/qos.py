"""QoS profiles <-> rosbag2 ``offered_qos_profiles`` dictionaries (metadata version 9: policy names as strings).

A profile dictionary has the keys rosbag2 writes, in its order: history, depth, reliability, durability, deadline,
lifespan, liveliness, liveliness_lease_duration ({sec, nsec}) and avoid_ros_namespace_conventions. rclpy is only
imported by the functions that build or read rclpy objects.
"""

INFINITE_NS = 0x7FFFFFFFFFFFFFFF  # RMW_DURATION_INFINITE
_NAMES = {
    "history": {0: "system_default", 1: "keep_last", 2: "keep_all", 3: "unknown"},
    "reliability": {0: "system_default", 1: "reliable", 2: "best_effort", 3: "unknown", 4: "best_available"},
    "durability": {0: "system_default", 1: "transient_local", 2: "volatile", 3: "unknown", 4: "best_available"},
    "liveliness": {0: "system_default", 1: "automatic", 3: "manual_by_topic", 4: "unknown", 5: "best_available"},
}


def _time(ns: int) -> dict:
    ns = min(max(int(ns), 0), INFINITE_NS)
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}


def _ns(t) -> int:
    if not isinstance(t, dict):
        return INFINITE_NS
    return int(t.get("sec", 0)) * 1_000_000_000 + int(t.get("nsec", 0))


def profile_dict(history="unknown", depth=0, reliability="reliable", durability="volatile", deadline_ns=INFINITE_NS,
                 *, lifespan_ns=INFINITE_NS, liveliness="automatic", lease_ns=INFINITE_NS, avoid_ros_ns=False) -> dict:
    return {"history": history, "depth": int(depth), "reliability": reliability, "durability": durability,
            "deadline": _time(deadline_ns), "lifespan": _time(lifespan_ns), "liveliness": liveliness,
            "liveliness_lease_duration": _time(lease_ns), "avoid_ros_namespace_conventions": bool(avoid_ros_ns)}


def from_rclpy(profile) -> dict:
    """An rclpy QoSProfile (e.g. ``TopicEndpointInfo.qos_profile``) -> rosbag2 dictionary."""
    def name(kind, value):
        return _NAMES[kind].get(int(value), "unknown")

    return profile_dict(
        history=name("history", profile.history), depth=profile.depth,
        reliability=name("reliability", profile.reliability), durability=name("durability", profile.durability),
        deadline_ns=profile.deadline.nanoseconds, lifespan_ns=profile.lifespan.nanoseconds,
        liveliness=name("liveliness", profile.liveliness),
        lease_ns=profile.liveliness_lease_duration.nanoseconds,
        avoid_ros_ns=profile.avoid_ros_namespace_conventions)


def request_for_offers(offers):
    """The subscription QoS that matches every offered profile (rosbag2 ``adapt_request_to_offers``): RELIABLE only
    if all publishers are reliable, TRANSIENT_LOCAL only if all are transient-local (then latched samples published
    before we joined are delivered). Returns ``(reliable, transient_local)``."""
    offers = list(offers)
    if not offers:
        return True, False
    reliable = all(o.get("reliability") == "reliable" for o in offers)
    transient = all(o.get("durability") == "transient_local" for o in offers)
    return reliable, transient


def to_rclpy(offer: dict, depth: int):
    """A publisher profile that re-offers a recorded one: reliability and durability as recorded (anything other
    than best_effort/transient_local -> reliable/volatile), KEEP_LAST ``depth``, finite deadline/lifespan/lease kept.
    """
    from rclpy.duration import Duration
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    profile = QoSProfile(
        history=HistoryPolicy.KEEP_LAST, depth=max(1, int(depth)),
        reliability=(ReliabilityPolicy.BEST_EFFORT if offer.get("reliability") == "best_effort"
                     else ReliabilityPolicy.RELIABLE),
        durability=(DurabilityPolicy.TRANSIENT_LOCAL if offer.get("durability") == "transient_local"
                    else DurabilityPolicy.VOLATILE))
    for key, attr in (("deadline", "deadline"), ("lifespan", "lifespan")):
        ns = _ns(offer.get(key))
        if 0 < ns < INFINITE_NS:
            setattr(profile, attr, Duration(nanoseconds=ns))
    return profile
