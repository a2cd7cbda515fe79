"""Recover an unfinished MCAP recording (recorder killed, disk full, power loss) into a complete bag directory.

The damaged file is read record by record with the mcap library's record parser; reading stops at the first
record that is cut off or fails its CRC, and everything before it -- every chunk the recorder flushed -- is written
to a new bag (``.mcap`` with summary and footer + ``metadata.yaml``) with the same schemas, channels (QoS, type hash)
and message times::

    roe-sep bag recover BAG OUT      # BAG: the bag directory or its .mcap file; OUT: a new directory
"""

import argparse
import io
import struct
import sys

import yaml
from mcap.exceptions import EndOfFile
from mcap.stream_reader import StreamReader

from . import BagError, metadata
from .writer import BagWriter

MAGIC = b"\x89MCAP0\r\n"
_FOOTER = 0x02


class Scan:
    """Iterate the records of a possibly truncated MCAP file. After :meth:`records` is exhausted: ``complete``
    (the footer was reached), ``valid_bytes`` (length of the readable prefix), ``reason`` (why reading stopped)."""

    def __init__(self, file):
        self.file = file
        self.complete = False
        self.valid_bytes = 0
        self.reason = ""
        self.profile = self.library = None

    def records(self):
        with open(self.file, "rb") as fh:
            if fh.read(8) != MAGIC:
                raise BagError(f"{self.file}: not an MCAP file (bad magic)")
            self.valid_bytes = 8
            while True:
                head = fh.read(9)
                if len(head) < 9:
                    self.reason = "end of file" if not head else f"record header cut off at byte {self.valid_bytes}"
                    return
                opcode, length = struct.unpack("<BQ", head)
                body = fh.read(length) if length < 1 << 32 else b""
                if len(body) < length:
                    self.reason = f"record (opcode 0x{opcode:02x}) cut off at byte {self.valid_bytes}"
                    return
                try:
                    parsed = self._parse(head + body)
                except Exception as exc:  # noqa: BLE001  (corrupt record: keep what came before)
                    self.reason = f"unreadable record (opcode 0x{opcode:02x}) at byte {self.valid_bytes}: {exc}"
                    return
                self.valid_bytes += 9 + length
                for rec in parsed:
                    if type(rec).__name__ == "Header":
                        self.profile, self.library = rec.profile, rec.library
                    yield rec
                if opcode == _FOOTER:
                    self.complete = True
                    self.reason = "complete"
                    return

    @staticmethod
    def _parse(record: bytes) -> list:
        out = []
        reader = StreamReader(io.BytesIO(record), skip_magic=True, validate_crcs=True)
        try:
            for rec in reader.records:
                out.append(rec)
        except EndOfFile:
            pass
        return out


def recover(src, out) -> dict:
    """Write the readable part of bag ``src`` to a new bag directory ``out``; returns counts and the damage."""
    from .reader import resolve

    _, file = resolve(src)
    with open(file, "rb") as fh:
        if fh.read(8) != MAGIC:
            raise BagError(f"{file}: not an MCAP file (bad magic)")
    scan = Scan(file)
    schemas, channels, orphans = {}, {}, 0
    custom = None
    writer = BagWriter(out)
    try:
        for rec in scan.records():
            kind = type(rec).__name__
            if kind == "Schema":
                schemas[rec.id] = rec
            elif kind == "Channel":
                schema = schemas.get(rec.schema_id)
                if schema is None:
                    continue
                channels[rec.id] = rec.topic
                writer.add_topic(rec.topic, schema.name,
                                 metadata.parse_qos(rec.metadata.get("offered_qos_profiles", "")),
                                 rec.metadata.get("topic_type_hash", ""), schema.data.decode("utf-8", "replace"))
            elif kind == "Message":
                topic = channels.get(rec.channel_id)
                if topic is None:
                    orphans += 1
                    continue
                writer.write(topic, rec.data, rec.log_time, rec.publish_time, rec.sequence)
            elif kind == "Metadata" and rec.name == "rosbag2" and custom is None:
                try:
                    custom = (yaml.safe_load(rec.metadata.get("serialized_metadata", "")) or {}).get("custom_data")
                except Exception:  # noqa: BLE001
                    custom = None
        if custom:
            writer.custom_data.update(custom)
    finally:
        writer.close()
    return {"source": str(file), "output": str(writer.path), "messages": writer.message_count,
            "topics": len(writer.topics), "complete": scan.complete, "valid_bytes": scan.valid_bytes,
            "size_bytes": file.stat().st_size, "reason": scan.reason, "orphan_messages": orphans}


def main(argv=None) -> int:
    """``roe-sep bag recover BAG OUT``: exit 0 on success, 2 on a bad path or an unreadable file."""
    parser = argparse.ArgumentParser(prog="roe-sep bag recover",
                                     description="Rebuild a complete bag from an unfinished MCAP recording.")
    parser.add_argument("bag", help="bag directory or .mcap file to recover")
    parser.add_argument("out", help="new bag directory to write (must not exist or be empty)")
    args = parser.parse_args(argv)
    try:
        r = recover(args.bag, args.out)
    except (BagError, OSError) as exc:
        print(f"roe-sep: error: {exc}", file=sys.stderr)
        return 2
    state = "file was complete" if r["complete"] else f"stopped at byte {r['valid_bytes']} of {r['size_bytes']}: " \
                                                      f"{r['reason']}"
    print(f"recovered {r['messages']} messages on {r['topics']} topics from {r['source']} ({state}) -> {r['output']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
