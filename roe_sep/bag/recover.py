"""Recover an unfinished MCAP recording (recorder killed, disk full, power loss) into a complete bag directory.

The damaged file is read record by record with the mcap library's record parser; reading stops at the first
record that is cut off or fails its CRC, and everything before it -- every chunk the recorder flushed -- is written
to a new bag (``.mcap`` with summary and footer + ``metadata.yaml``) with the same schemas, channels (QoS, type hash)
and message times::

    roe-sep bag recover BAG OUT      # BAG: the bag directory or its .mcap file; OUT: a new directory

Exit status: 0 when everything readable was kept and the file was complete or merely cut off (a recording killed
mid-write: only the unflushed tail is lost, and the message says how many bytes and up to which log time); 1 when
the file is corrupt inside (a record fails its CRC or claims an impossible length, or the file was closed but its
records stop before the footer): the readable prefix is written and the message says how many bytes were lost;
2 when nothing can be recovered (no such path, not an MCAP file, no message before the damage), nothing written.
"""

import shutil
import sys
from pathlib import Path

import yaml

from ..checks import OneLineParser, one_line
from ..errors import BagError
from . import metadata
from .reader import resolve
from .scan import MAGIC, Scan
from .writer import BagWriter, check_output


def recover(src, out) -> dict:
    """Write the readable part of bag ``src`` to a new bag directory ``out``; returns counts and the damage
    (``kind``: complete / truncated / corrupt, see :class:`~roe_sep.bag.scan.Scan`); with no message readable the
    new bag is empty (``messages`` 0; the command line removes it and exits 2)."""
    bag_dir, file = resolve(src)
    with open(file, "rb") as fh:
        if fh.read(8) != MAGIC:
            raise BagError(f"{file}: not an MCAP file (bad magic)")
    source_metadata = ""
    if bag_dir is not None:
        try:
            metadata.read(bag_dir)
        except Exception as exc:  # noqa: BLE001  (reported: the recovered bag gets a new one)
            source_metadata = f"{metadata.FILE_NAME} of the source unreadable ({type(exc).__name__}: {one_line(exc)})"
    scan = Scan(file)
    schemas, channels, orphans = {}, {}, 0
    custom = None
    last_time = None
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
                try:
                    writer.add_topic(rec.topic, schema.name,
                                     metadata.parse_qos(rec.metadata.get("offered_qos_profiles", "")),
                                     rec.metadata.get("topic_type_hash", ""), schema.data.decode("utf-8", "replace"))
                except (ValueError, TypeError, yaml.YAMLError):  # a damaged channel: its messages become orphans
                    continue
                channels[rec.id] = rec.topic
            elif kind == "Message":
                topic = channels.get(rec.channel_id)
                if topic is None:
                    orphans += 1
                    continue
                writer.write(topic, rec.data, rec.log_time, rec.publish_time, rec.sequence)
                last_time = rec.log_time if last_time is None else max(last_time, rec.log_time)
            elif kind == "Metadata" and rec.name == "rosbag2" and custom is None:
                try:
                    custom = (yaml.safe_load(rec.metadata.get("serialized_metadata", "")) or {}).get("custom_data")
                except Exception:  # noqa: BLE001
                    custom = None
        if isinstance(custom, dict):
            writer.custom_data.update(custom)
    finally:
        writer.close()
    return {"source": str(file), "output": str(writer.path), "messages": writer.message_count,
            "topics": len(writer.topics), "complete": scan.complete, "kind": scan.kind,
            "valid_bytes": scan.valid_bytes, "size_bytes": scan.size, "lost_bytes": scan.size - scan.valid_bytes,
            "reason": scan.reason, "orphan_messages": orphans, "last_log_time_ns": last_time,
            "source_metadata": source_metadata}


def summary_line(r: dict) -> str:
    """One line on what was recovered and what was lost."""
    if r["kind"] == "complete":
        state = "file was complete"
    else:
        what = "cut off (unflushed tail lost)" if r["kind"] == "truncated" else "CORRUPT"
        state = (f"{what}: read {r['valid_bytes']} of {r['size_bytes']} bytes, {r['lost_bytes']} lost: "
                 f"{r['reason']}")
    last = "" if r["last_log_time_ns"] is None else f", last message at log time {r['last_log_time_ns'] * 1e-9:.3f} s"
    extra = f"; {r['source_metadata']}: rebuilt" if r["source_metadata"] else ""
    orphans = f"; {r['orphan_messages']} messages without a channel dropped" if r["orphan_messages"] else ""
    return (f"recovered {r['messages']} messages on {r['topics']} topics from {r['source']} ({state}{last}){extra}"
            f"{orphans} -> {r['output']}")


def main(argv=None) -> int:
    """``roe-sep bag recover BAG OUT``: exit 0 (complete or cut-off file), 1 (corrupt file: prefix recovered) or 2
    (nothing recoverable, bad path); see the module docstring."""
    parser = OneLineParser(prog="roe-sep bag recover",
                           description="Rebuild a complete bag from an unfinished MCAP recording.")
    parser.add_argument("bag", help="bag directory or .mcap file to recover")
    parser.add_argument("out", help="new bag directory to write (must not exist or be empty)")
    args = parser.parse_args(argv)
    out_existed = Path(args.out).exists()
    try:
        check_output(args.out)
        r = recover(args.bag, args.out)
    except (BagError, OSError) as exc:
        print(f"roe-sep: error: {one_line(exc)}", file=sys.stderr)
        return 2
    if r["messages"] == 0:  # an empty bag is no recovery: remove what this call wrote (``out`` was empty)
        out = Path(r["output"])
        for f in out.iterdir():
            f.unlink()
        if not out_existed:
            shutil.rmtree(out, ignore_errors=True)
        print(f"roe-sep: error: {r['source']}: no message can be recovered ({r['kind']}: {r['reason']}); nothing "
              "written", file=sys.stderr)
        return 2
    print(summary_line(r))
    return 1 if r["kind"] == "corrupt" else 0


if __name__ == "__main__":
    raise SystemExit(main())
