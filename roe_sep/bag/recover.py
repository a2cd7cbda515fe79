"""Recover an unfinished MCAP recording (recorder killed, disk full, power loss) into a complete bag directory.

The damaged file is read record by record with the mcap library's record parser; reading stops at the first
record that is cut off or fails its CRC, and everything before it -- every chunk the recorder flushed -- is written
to a new bag (``.mcap`` with summary and footer + ``metadata.yaml``) with the same schemas, channels (QoS, type hash)
and message times::

    roe-sep bag recover BAG OUT      # BAG: the bag directory or its .mcap file; OUT: a new directory
"""

import argparse
import sys

import yaml

from . import metadata
from .errors import BagError
from .reader import resolve
from .scan import MAGIC, Scan
from .writer import BagWriter


def recover(src, out) -> dict:
    """Write the readable part of bag ``src`` to a new bag directory ``out``; returns counts and the damage."""
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
