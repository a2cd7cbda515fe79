"""The live Foxglove view: foxglove_view as a real process, a real WebSocket client speaking the Foxglove WebSocket
protocol (subprotocol foxglove.sdk.v1) receives /clock, a plan and the 3-D scene and decodes them; the layout in
the repo refers only to topics and fields that exist."""

import json
import socket
import struct
import time
from pathlib import Path

import pytest
from builtin_interfaces.msg import Time
from rclpy.serialization import deserialize_message
from roe_sep_msgs.msg import ImpulsiveManeuver, ManeuverPlan, RelativeOrbitalElements
from rosgraph_msgs.msg import Clock
from rosutil import rclpy, spin_until, start_node, stop_node, wait_exit  # noqa: I001  (skips without rclpy)

from roe_sep import interfaces
from roe_sep.bag import definitions
from roe_sep.bag.reader import topics as bag_topics

websocket = pytest.importorskip("websocket", reason="the test client is websocket-client")
ROOT = Path(__file__).resolve().parents[2]
BAG = ROOT / "bags" / "default_run"
SUBPROTOCOL = "foxglove.sdk.v1"  # foxglove-sdk 0.30 (the Foxglove app speaks it; ws-protocol v1 framing)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.dds
def test_websocket_client_receives_clock_plan_and_scene(ros_context):
    port = free_port()
    view = start_node("foxglove_view", "-p", f"port:={port}")
    node = rclpy.create_node("foxglove_view_test")
    ws = None
    try:
        clock_pub = node.create_publisher(Clock, interfaces.CLOCK_TOPIC, 10)
        plan_pub = node.create_publisher(ManeuverPlan, interfaces.ACQUISITION_PLAN_TOPIC, interfaces.LATCHED)
        truth_pub = node.create_publisher(RelativeOrbitalElements, interfaces.TRUTH_ROE_TOPIC, interfaces.STREAM)
        plan = ManeuverPlan(strategy="ic_acquisition", maneuvers=[ImpulsiveManeuver(
            spacecraft="carrier", purpose="ic_acquisition", epoch=Time(sec=87247, nanosec=267903516))])
        plan.maneuvers[0].dv_rtn.y = -0.075
        plan_pub.publish(plan)
        deadline = time.monotonic() + 30.0
        while ws is None and time.monotonic() < deadline:
            try:
                ws = websocket.create_connection(f"ws://127.0.0.1:{port}", subprotocols=[SUBPROTOCOL], timeout=2.0)
            except (ConnectionRefusedError, OSError, websocket.WebSocketException):
                spin_until(node, lambda: False, 0.3)
        assert ws is not None, "no Foxglove WebSocket server"
        assert ws.getsubprotocol() == SUBPROTOCOL

        channels, subscribed, got = {}, {}, {}
        wanted = (interfaces.CLOCK_TOPIC, interfaces.ACQUISITION_PLAN_TOPIC, "/foxglove/scene")
        t_end = time.monotonic() + 40.0
        k = 0
        while time.monotonic() < t_end and not all(t in got for t in wanted):
            k += 1
            clock_pub.publish(Clock(clock=Time(sec=1000 + k)))
            truth = RelativeOrbitalElements(a_dl=8000.0, a_dey=-590.0, a_diy=400.0)
            truth.chief.semi_major_axis = 6893137.0
            truth.chief.inclination = 1.7
            truth.header.stamp = Time(sec=1000 + k)
            truth_pub.publish(truth)
            rclpy.spin_once(node, timeout_sec=0.05)
            try:
                frame = ws.recv()
            except websocket.WebSocketTimeoutException:
                continue
            if isinstance(frame, str):
                msg = json.loads(frame)
                if msg.get("op") == "advertise":
                    # foxglove-sdk 0.30.3 drops a subscription that arrives within milliseconds of the channel's
                    # advertisement ("unknown channel"); a client a few hundred ms later is served
                    time.sleep(0.2)
                    for ch in msg["channels"]:
                        channels[ch["id"]] = ch
                        if ch["topic"] in wanted and ch["topic"] not in subscribed.values():
                            sid = len(subscribed) + 1  # subscription id -> topic
                            subscribed[sid] = ch["topic"]
                            ws.send(json.dumps({"op": "subscribe",
                                                "subscriptions": [{"id": sid, "channelId": ch["id"]}]}))
                continue
            assert frame[0] == 0x01  # messageData: opcode, subscription id, log time, payload
            sid, log_time = struct.unpack_from("<IQ", frame, 1)
            got.setdefault(subscribed[sid], (log_time, frame[13:]))
        assert all(t in got for t in wanted), f"received {sorted(got)} of {wanted}"
        by_topic = {ch["topic"]: ch for ch in channels.values()}
        assert by_topic[interfaces.CLOCK_TOPIC]["encoding"] == "cdr"
        assert by_topic[interfaces.CLOCK_TOPIC]["schemaEncoding"] == "ros2msg"
        assert by_topic[interfaces.ACQUISITION_PLAN_TOPIC]["schemaName"] == "roe_sep_msgs/msg/ManeuverPlan"
        assert "MSG: roe_sep_msgs/ImpulsiveManeuver" in by_topic[interfaces.ACQUISITION_PLAN_TOPIC]["schema"]
        assert by_topic["/foxglove/scene"]["schemaName"] == "foxglove.SceneUpdate"
        clock = deserialize_message(got[interfaces.CLOCK_TOPIC][1], Clock)
        assert clock.clock.sec > 1000
        received = deserialize_message(got[interfaces.ACQUISITION_PLAN_TOPIC][1], ManeuverPlan)
        assert received.strategy == "ic_acquisition" and received.maneuvers[0].dv_rtn.y == -0.075
        assert len(got["/foxglove/scene"][1]) > 100
    finally:
        if ws is not None:
            ws.close()
        node.destroy_node()
        code, log = stop_node(view, 20.0)
    assert code == 0, log


@pytest.mark.dds
def test_port_in_use_exits_2():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        code, log = wait_exit(start_node("foxglove_view", "-p", f"port:={s.getsockname()[1]}"))
    assert code == 2 and "port" in log, log


def _fields(cls, path):
    """The type at a dotted field path of a message class (None if a field is missing)."""
    for name in path:
        types = cls.get_fields_and_field_types()
        if name not in types:
            return None
        t = types[name]
        if "/" in t:
            cls = definitions.message_class(t.split("<")[-1].rstrip(">"))
        else:
            return t
    return cls


def test_layout_refers_to_existing_topics_and_fields():
    layout = json.loads((ROOT / "config" / "foxglove_layout.json").read_text())
    panels = layout["configById"]

    def leaves(node):
        return [node] if isinstance(node, str) else leaves(node["first"]) + leaves(node["second"])

    assert sorted(leaves(layout["layout"])) == sorted(panels)
    types = {t["name"]: t["type"] for t in bag_topics(BAG)}
    paths = [p["value"] for cfg in panels.values() for p in cfg.get("paths", [])]
    paths += [cfg["topicPath"] for cfg in panels.values() if "topicPath" in cfg]
    assert len(paths) >= 15
    for path in paths:
        topic, _, rest = path.partition(".")
        topic = topic.split("{")[0]
        assert topic in types, f"{path}: {topic} is not a topic of the run"
        if rest:
            assert _fields(definitions.message_class(types[topic]), rest.split(".")) is not None, path
    assert "/foxglove/scene" in panels["3D!rtn"]["topics"]


def test_foxglove_option():
    import argparse

    from roe_sep.cli.foxglove import split_foxglove

    assert split_foxglove(["bags/default_run", "--foxglove"]) == (["bags/default_run"], 8765)
    assert split_foxglove(["b", "--foxglove", "9000", "--rate", "2"]) == (["b", "--rate", "2"], 9000)
    assert split_foxglove(["b", "--foxglove=9001", "--clock"]) == (["b", "--clock"], 9001)
    assert split_foxglove(["b", "--rate", "2"]) == (["b", "--rate", "2"], None)
    with pytest.raises(argparse.ArgumentTypeError, match="port in"):
        split_foxglove(["b", "--foxglove=70000"])
