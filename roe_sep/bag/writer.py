"""The MCAP bag writer: a rosbag2-compatible bag directory (``<dir>/<dir name>_0.mcap`` + ``metadata.yaml``), no rclpy.

The file follows rosbag2_storage_mcap (Jazzy): header profile ``ros2``; one schema per type (encoding ``ros2msg``,
name ``pkg/msg/Type``, full definition text); one channel per topic (``cdr``, metadata ``offered_qos_profiles`` and
``topic_type_hash``); messages with log/publish time in ns and a per-channel sequence number; uncompressed chunks;
a ``rosbag2`` metadata record (``serialized_metadata``) when opened and again when closed.

Crash safety: chunks are small (:data:`CHUNK_SIZE`) and :meth:`BagWriter.flush` closes the open chunk and pushes
everything to the disk (``fsync``), so after a SIGKILL the file holds every message up to the last flush and
:mod:`roe_sep.bag.recover` rebuilds a complete bag from it.
"""

import os
from pathlib import Path

from mcap.writer import CompressionType, Writer

from ..errors import BagError
from . import definitions, metadata

CHUNK_SIZE = 64 * 1024
PROFILE = "ros2"
SCHEMA_ENCODING = "ros2msg"
MESSAGE_ENCODING = "cdr"


def library_id() -> str:
    from mcap.writer import LIBRARY_IDENTIFIER

    return f"roe_sep bag writer ({LIBRARY_IDENTIFIER})"


def check_output(bag_dir) -> Path:
    """The bag directory must not exist or be an empty directory; BagError otherwise."""
    path = Path(bag_dir)
    if path.exists() and (not path.is_dir() or any(path.iterdir())):
        raise BagError(f"{path} already exists and is not an empty directory; refusing to overwrite it")
    return path


class BagWriter:
    """Write one bag directory. Use :meth:`add_topic` before writing a topic's first message; :meth:`close` at the
    end (a context manager closes on exit)."""

    def __init__(self, bag_dir, chunk_size: int = CHUNK_SIZE, custom_data=None):
        self.path = check_output(bag_dir).resolve()
        self.path.mkdir(parents=True, exist_ok=True)
        self.file_name = f"{self.path.name}_0.mcap"
        self.custom_data = dict(custom_data or {})
        self.topics = {}  # name -> topic dict (metadata.yaml topic_metadata + message_count)
        self._channels = {}  # name -> channel id
        self._schemas = {}  # type -> schema id
        self._sequence = {}
        self.message_count = 0
        self.start_time = None
        self.end_time = None
        self._dirty = False
        self._fh = open(self.path / self.file_name, "wb")
        self._mcap = Writer(self._fh, chunk_size=chunk_size, compression=CompressionType.NONE)
        self._mcap.start(profile=PROFILE, library=library_id())
        self._write_metadata_record()
        self.flush()

    # -- topics and messages -------------------------------------------------------------------------------------
    def add_topic(self, name: str, type_name: str, offered_qos_profiles=(), type_hash: str = "", definition=None):
        """Register a topic. ``type_name`` as ``pkg/msg/Type``; ``definition`` defaults to the installed full text
        (:func:`roe_sep.bag.definitions.full_text`); ``type_hash`` to the installed RIHS01 hash."""
        if name in self._channels:
            return self._channels[name]
        type_name = definitions.canonical_type(type_name)
        if definition is None:
            definition = definitions.full_text(type_name)
        if not type_hash:
            type_hash = definitions.type_hash(type_name)
        profiles = list(offered_qos_profiles)
        if type_name not in self._schemas:
            self._schemas[type_name] = self._mcap.register_schema(type_name, SCHEMA_ENCODING, definition.encode())
        channel = self._mcap.register_channel(
            name, MESSAGE_ENCODING, self._schemas[type_name],
            {"offered_qos_profiles": metadata.qos_yaml(profiles), "topic_type_hash": type_hash})
        self._channels[name] = channel
        self._sequence[name] = 0
        self.topics[name] = {"name": name, "type": type_name, "serialization_format": MESSAGE_ENCODING,
                             "offered_qos_profiles": profiles, "type_description_hash": type_hash,
                             "message_count": 0}
        self._dirty = True
        return channel

    def write(self, topic: str, data: bytes, log_time: int, publish_time=None, sequence=None):
        """Append one serialized (CDR) message; times in ns (node clock: sim time under ``use_sim_time``)."""
        try:
            channel = self._channels[topic]
        except KeyError:
            raise BagError(f"topic {topic} was not added to the bag") from None
        log_time = int(log_time)
        if sequence is None:
            sequence = self._sequence[topic] = self._sequence[topic] + 1
        # positional: (channel_id, log_time, data, publish_time, sequence), mcap's Writer.add_message order
        self._mcap.add_message(channel, log_time, bytes(data),
                               int(log_time if publish_time is None else publish_time), int(sequence) & 0xFFFFFFFF)
        self.topics[topic]["message_count"] += 1
        self.message_count += 1
        if self.start_time is None:
            self.start_time = self.end_time = log_time
        elif log_time < self.start_time:  # the min and max of the log times, without two builtin calls a message
            self.start_time = log_time
        elif log_time > self.end_time:
            self.end_time = log_time
        self._dirty = True

    # -- durability ----------------------------------------------------------------------------------------------
    def flush(self):
        """Close the open chunk, write it and push the file to the disk."""
        self._mcap.flush()
        os.fsync(self._fh.fileno())
        self._dirty = False

    @property
    def dirty(self) -> bool:
        """Something was added since the last :meth:`flush`."""
        return self._dirty

    def info(self) -> dict:
        """The metadata.yaml mapping for what was written so far."""
        start = self.start_time if self.start_time is not None else metadata.NO_TIME
        duration = (self.end_time - self.start_time) if self.start_time is not None else 0
        files = [{"path": self.file_name, "starting_time": start, "duration": duration,
                  "message_count": self.message_count}]
        return metadata.bag_info(files, list(self.topics.values()), self.custom_data)

    def _write_metadata_record(self):
        self._mcap.add_metadata("rosbag2", {"serialized_metadata": metadata.dump(self.info())})

    def close(self):
        """Finish the MCAP (summary, footer) and write metadata.yaml; safe to call twice."""
        if self._fh.closed:
            return
        try:
            self._write_metadata_record()
            self._mcap.finish()
            self._fh.flush()
            os.fsync(self._fh.fileno())
        finally:
            self._fh.close()
        metadata.write(self.path, self.info())

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
