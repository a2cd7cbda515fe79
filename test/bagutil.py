"""Bag helpers shared by the tests: messages as plain values, the bag's MCAP file, two independent readers of a
bag (mcap_ros2 and rosbags) and a ``roe_sep.bag.replay`` process."""

import dataclasses
import os
import subprocess
import sys
from types import SimpleNamespace

import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosutil import ROOT, ros_env

rosbags_rosbag2 = pytest.importorskip("rosbags.rosbag2")
rosbags_typesys = pytest.importorskip("rosbags.typesys")


def norm(v):
    """A message from rclpy, mcap_ros2 or rosbags as plain dicts/lists/numbers, so the three compare equal."""
    if hasattr(v, "get_fields_and_field_types"):
        return {k: norm(getattr(v, k)) for k in v.get_fields_and_field_types()}
    if isinstance(v, SimpleNamespace):
        return {k: norm(getattr(v, k)) for k in v.__slots__}
    if dataclasses.is_dataclass(v) and not isinstance(v, type):
        return {f.name: norm(getattr(v, f.name)) for f in dataclasses.fields(v)
                if not f.name.startswith("__") and not f.name.isupper()}  # rosbags: no type name, no constants
    if isinstance(v, bytes) and len(v) == 1:  # rclpy 'byte' fields
        return v[0]
    if isinstance(v, (str, bytes, bool, int, float)):
        return v
    if hasattr(v, "tolist"):
        return norm(v.tolist())
    if hasattr(v, "__iter__"):
        return [norm(x) for x in v]
    return v


def mcap_file(bag):
    (f,) = [p for p in os.listdir(bag) if p.endswith(".mcap")]
    return os.path.join(bag, f)


def read_mcap_ros2(path):
    """Independent reader #1: mcap + mcap_ros2's decoder -> {topic: [(msg, log_time, sequence)]}."""
    out = {}
    with open(path, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        for _schema, channel, message, decoded in reader.iter_decoded_messages(log_time_order=True):
            out.setdefault(channel.topic, []).append((decoded, message.log_time, message.sequence))
    return out


def read_rosbags(bag):
    """Independent reader #2: rosbags, with the roe_sep_msgs types registered from the bag's schema text."""
    store = rosbags_typesys.get_typestore(rosbags_typesys.Stores.ROS2_JAZZY)
    out, conns = {}, {}
    with rosbags_rosbag2.Reader(bag) as reader:
        types = {}
        for conn in reader.connections:
            conns[conn.topic] = conn
            if conn.msgtype.startswith("roe_sep_msgs/"):
                types.update(rosbags_typesys.get_types_from_msg(conn.msgdef.data, conn.msgtype))
        store.register(types)
        for conn, _t, raw in reader.messages():
            out.setdefault(conn.topic, []).append(store.deserialize_cdr(raw, conn.msgtype))
    return out, conns


def bag_replay_process(*args):
    return subprocess.Popen([sys.executable, "-m", "roe_sep.bag.replay", *args], env=ros_env(), cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
