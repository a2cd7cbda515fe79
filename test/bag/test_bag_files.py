"""Bag files without DDS: schema text, metadata.yaml format, writer flushes, recovery of truncated files."""

import os

import pytest
import yaml

pytest.importorskip("rclpy", reason="serializing messages needs the project venv (make test)")

from rclpy.serialization import deserialize_message, serialize_message  # noqa: E402
from roe_sep_msgs.msg import ManeuverPlan, RelativeOrbitalElements  # noqa: E402
from rosgraph_msgs.msg import Clock  # noqa: E402

from roe_sep.bag import BagError, definitions, info, metadata, qos, reader  # noqa: E402
from roe_sep.bag.recover import recover  # noqa: E402
from roe_sep.bag.writer import BagWriter  # noqa: E402

rosbags_typesys = pytest.importorskip("rosbags.typesys")


def test_full_text_layout_and_dependencies():
    text = definitions.full_text("roe_sep_msgs/msg/EjectionEvent")
    sections = text.split("\n" + "=" * 80 + "\n")
    assert sections[0] == definitions.msg_text("roe_sep_msgs/msg/EjectionEvent")
    names = [s.splitlines()[0] for s in sections[1:]]
    assert len(names) == len(set(names))  # every dependency once
    assert set(names) == {"MSG: std_msgs/Header", "MSG: builtin_interfaces/Time", "MSG: roe_sep_msgs/ImpulsiveManeuver",
                          "MSG: geometry_msgs/Vector3", "MSG: roe_sep_msgs/OrbitalElements"}
    for s in sections[1:]:
        name = s.splitlines()[0][5:]
        assert s.split("\n", 1)[1] == definitions.msg_text(name)
    # an independent parser accepts it and finds every field type
    types = rosbags_typesys.get_types_from_msg(text, "roe_sep_msgs/msg/EjectionEvent")
    assert "roe_sep_msgs/msg/OrbitalElements" in types
    assert definitions.full_text("roe_sep_msgs/ManeuverPlan") == definitions.full_text("roe_sep_msgs/msg/ManeuverPlan")
    assert definitions.type_hash("std_msgs/msg/String") == (
        "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18")
    with pytest.raises(definitions.DefinitionNotFound):
        definitions.full_text("no_such_msgs/msg/Thing")
    with pytest.raises(ValueError):
        definitions.split_type("not a type")


def test_qos_yaml_matches_rosbag2():
    text = metadata.qos_yaml([qos.profile_dict(durability="transient_local")])
    assert text.splitlines()[:4] == ["- history: unknown", "  depth: 0", "  reliability: reliable",
                                     "  durability: transient_local"]
    assert "  deadline:\n    sec: 9223372036\n    nsec: 854775807" in text
    assert metadata.parse_qos(text) == [qos.profile_dict(durability="transient_local")]
    # version <= 8 bags stored the policies as numbers
    assert metadata.parse_qos("- history: 1\n  depth: 5\n  reliability: 2\n  durability: 1\n  liveliness: 1")[0][
        "reliability"] == "best_effort"
    assert metadata.dump({"a": "", "b": "true", "c": None, "d": []}) == 'a: ""\nb: "true"\nc: ~\nd:\n  []'


def _write_bag(path, n=60, flush_at=25, chunk_size=2048):
    """A bag with a latched plan, n ROE messages and /clock; returns (writer, file size right after the flush)."""
    w = BagWriter(path, chunk_size=chunk_size)
    w.add_topic("/plan", "roe_sep_msgs/msg/ManeuverPlan", [qos.profile_dict(durability="transient_local")])
    w.add_topic("/roe", "roe_sep_msgs/msg/RelativeOrbitalElements", [qos.profile_dict()])
    w.add_topic("/clock", "rosgraph_msgs/msg/Clock", [qos.profile_dict(reliability="best_effort")])
    w.write("/plan", serialize_message(ManeuverPlan(strategy="double_impulse")), 1_000)
    flushed = None
    for i in range(n):
        w.write("/roe", serialize_message(RelativeOrbitalElements(a_dl=float(i))), 2_000 + i, publish_time=5 + i)
        if i % 10 == 0:
            c = Clock()
            c.clock.sec = i
            w.write("/clock", serialize_message(c), 2_000 + i)
        if i == flush_at:
            w.flush()
            flushed = os.path.getsize(w.path / w.file_name)
    return w, flushed


def test_writer_bag_directory(tmp_path):
    w, _ = _write_bag(tmp_path / "bag")
    w.close()
    w.close()  # idempotent
    assert sorted(os.listdir(tmp_path / "bag")) == ["bag_0.mcap", "metadata.yaml"]
    meta = metadata.read(tmp_path / "bag")
    assert meta["message_count"] == 1 + 60 + 6
    assert meta["starting_time"] == {"nanoseconds_since_epoch": 1_000}
    assert meta["duration"] == {"nanoseconds": 2_059 - 1_000}
    msgs = list(reader.messages(tmp_path / "bag", topics=["/roe"]))
    assert [deserialize_message(m.data, RelativeOrbitalElements).a_dl for m in msgs] == [float(i) for i in range(60)]
    assert [m.publish_time for m in msgs][:3] == [5, 6, 7] and [m.sequence for m in msgs][:3] == [1, 2, 3]
    with pytest.raises(BagError, match="not an empty directory"):
        BagWriter(tmp_path / "bag")
    raw = yaml.safe_load((tmp_path / "bag" / "metadata.yaml").read_text())
    assert raw["rosbag2_bagfile_information"]["custom_data"] is None


class _PreviousWriter(BagWriter):
    """BagWriter.write as it was before its per-message bookkeeping was trimmed (the reference of the test below)."""

    def write(self, topic, data, log_time, publish_time=None, sequence=None):
        if topic not in self._channels:
            raise BagError(f"topic {topic} was not added to the bag")
        log_time = int(log_time)
        if sequence is None:
            self._sequence[topic] += 1
            sequence = self._sequence[topic]
        self._mcap.add_message(self._channels[topic], log_time=log_time, data=bytes(data),
                               publish_time=int(log_time if publish_time is None else publish_time),
                               sequence=int(sequence) & 0xFFFFFFFF)
        self.topics[topic]["message_count"] += 1
        self.message_count += 1
        self.start_time = log_time if self.start_time is None else min(self.start_time, log_time)
        self.end_time = log_time if self.end_time is None else max(self.end_time, log_time)
        self._dirty = True


def test_writer_write_equals_previous_write_to_the_byte(tmp_path):
    """Log times out of order (new minimum, new maximum, in between, equal), explicit publish times and sequences
    (one past 2**32), bytearray data: the same .mcap and metadata.yaml bytes, the same counts and times."""
    writers = [cls(tmp_path / name) for cls, name in ((BagWriter, "new"), (_PreviousWriter, "old"))]
    calls = [("/a", b"x" * 40, 500, None, None), ("/b", bytearray(b"yz"), 300, 7, None),
             ("/a", b"", 900, None, 2**32 + 5), ("/b", b"q" * 9, 600, None, None), ("/a", b"r", 300.0, 11, 3),
             ("/b", b"s" * 70_000, 900, None, None), ("/a", b"t", 100, None, None), ("/b", b"u", 950, 1, None)]
    for w in writers:
        w.add_topic("/a", "std_msgs/msg/String", (), "RIHS01_a", "string data")
        w.add_topic("/b", "std_msgs/msg/String", (), "RIHS01_b", "string data")
        for call in calls:
            w.write(*call)
        with pytest.raises(BagError, match="not added"):
            w.write("/c", b"", 1)
    new, old = writers
    assert (new.start_time, new.end_time, new.message_count, new._sequence, new.topics) == (
        old.start_time, old.end_time, old.message_count, old._sequence, old.topics)
    assert (new.start_time, new.end_time) == (100, 950)
    for w in writers:
        w.close()
    for name in ("new_0.mcap", "metadata.yaml"):
        a = (tmp_path / "new" / name).read_bytes()
        b = (tmp_path / "old" / name.replace("new", "old")).read_bytes()
        assert a.replace(b"new_0.mcap", b"old_0.mcap") == b


def test_recover_any_truncation(tmp_path):
    w, flushed = _write_bag(tmp_path / "bag")
    w.close()
    data = (tmp_path / "bag" / "bag_0.mcap").read_bytes()
    previous = -1
    cuts = sorted({9, 100, flushed - 1, flushed, flushed + 1} | set(range(200, len(data), len(data) // 23))
                  | {len(data) - 1})
    for k, cut in enumerate(cuts):
        src = tmp_path / f"cut{k}.mcap"
        src.write_bytes(data[:cut])
        scanned = info(src)
        assert scanned["complete"] is False
        result = recover(src, tmp_path / f"out{k}")
        got = info(tmp_path / f"out{k}")
        assert got["complete"] and got["message_count"] == result["messages"] == scanned["message_count"]
        assert result["messages"] >= previous  # a longer prefix never loses messages
        previous = result["messages"]
        if cut >= flushed:  # everything written before the flush survives
            counts = {t["name"]: t["message_count"] for t in got["topics"]}
            assert counts["/plan"] == 1 and counts["/roe"] >= 26 and counts["/clock"] >= 3
            assert metadata.read(tmp_path / f"out{k}")["message_count"] == result["messages"]
    assert previous == 67  # cut inside the footer: all messages


def test_unfinished_file_is_recoverable_while_open(tmp_path):
    """The recorder's situation at a SIGKILL: the writer is still open, only flushed data is on disk."""
    w, flushed = _write_bag(tmp_path / "bag")
    (tmp_path / "copy.mcap").write_bytes((w.path / w.file_name).read_bytes())
    result = recover(tmp_path / "copy.mcap", tmp_path / "out")
    assert result["messages"] >= 1 + 26 + 3 and not result["complete"]
    w.close()
