"""Reading bags written by :mod:`roe_sep.bag.writer` (or rosbag2 with the mcap storage plugin), no rclpy.

A bag is a directory with ``metadata.yaml`` and one ``.mcap`` file, or a bare ``.mcap`` file. :func:`topics` and
:func:`messages` need a complete file (summary section); :func:`info` also describes an unfinished one (recorder
killed) by scanning it record by record, and says ``complete: false`` -- ``roe-sep bag recover`` repairs it.
"""

import collections
from pathlib import Path

from mcap.reader import make_reader

from ..checks import one_line
from ..errors import BagError
from . import metadata
from .scan import Scan

Message = collections.namedtuple("Message", "topic type data log_time publish_time sequence")


def resolve(path):
    """``(bag directory or None, .mcap file)`` for a bag directory or an ``.mcap`` file; BagError if neither."""
    bag_dir, file, _ = _resolve(path)
    return bag_dir, file


def _read_metadata(bag_dir):
    """``(metadata.read(bag_dir), None)``, or ``(None, the exception it raised)``."""
    try:
        return metadata.read(bag_dir), None
    except Exception as exc:  # noqa: BLE001  (the callers say what is wrong with it)
        return None, exc


def _resolve(path):
    """:func:`resolve` and what it read of ``metadata.yaml`` (:func:`_read_metadata`; None when not read)."""
    p = Path(path)
    if p.is_file():
        return None, p, None
    if not p.is_dir():
        raise BagError(f"{path}: no such bag (expected a bag directory or an .mcap file)")
    names = []
    meta = None
    if (p / metadata.FILE_NAME).is_file():
        meta = _read_metadata(p)
        try:
            if meta[1] is not None:
                raise meta[1]
            names = [n for n in meta[0].get("relative_file_paths") or [] if isinstance(n, str)]
        except Exception:  # noqa: BLE001  (a damaged metadata.yaml: fall back to the directory listing; info says so)
            names = []
    files = [p / n for n in names if (p / n).is_file()] or sorted(f for f in p.glob("*.mcap") if f.is_file())
    if not files:
        raise BagError(f"{path}: not a bag (no .mcap file in the directory)")
    if len(files) > 1:
        raise BagError(f"{path}: split bags are not supported ({len(files)} .mcap files)")
    return p, files[0], meta


def _summary(fh, file):
    try:
        reader = make_reader(fh)
        summary = reader.get_summary()
    except Exception as exc:  # noqa: BLE001  (truncated or not an MCAP file)
        raise BagError(f"{file}: no MCAP summary ({exc.__class__.__name__}: {exc}); the recording did not "
                       f"finish -- recover it with `roe-sep bag recover`") from None
    if summary is None or summary.statistics is None:
        raise BagError(f"{file}: MCAP file without summary/statistics; recover it with `roe-sep bag recover`")
    return reader, summary


def topics(path) -> list:
    """Per topic: name, type, offered_qos_profiles (list of dicts), type_description_hash, message_count,
    definition (schema text), in channel order."""
    _, file = resolve(path)
    with open(file, "rb") as fh:
        _, summary = _summary(fh, file)
    counts = summary.statistics.channel_message_counts
    out = []
    for cid, ch in sorted(summary.channels.items()):
        schema = summary.schemas.get(ch.schema_id)
        out.append({"name": ch.topic, "type": schema.name if schema else "",
                    "serialization_format": ch.message_encoding,
                    "offered_qos_profiles": metadata.parse_qos(ch.metadata.get("offered_qos_profiles", "")),
                    "type_description_hash": ch.metadata.get("topic_type_hash", ""),
                    "message_count": counts.get(cid, 0),
                    "definition": schema.data.decode("utf-8", "replace") if schema else ""})
    return out


def messages(path, topics=None):
    """Messages in log-time order as :class:`Message` (serialized CDR ``data``, times in ns)."""
    _, file = resolve(path)
    with open(file, "rb") as fh:
        reader, _ = _summary(fh, file)
        for schema, channel, msg in reader.iter_messages(topics=topics, log_time_order=True):
            yield Message(channel.topic, schema.name if schema else "", bytes(msg.data), msg.log_time,
                          msg.publish_time, msg.sequence)


RawMessage = collections.namedtuple("RawMessage", "schema decode data")
RawMessage.__doc__ = """A message of :func:`decoded_messages` left undecoded (``raw`` topics): its MCAP schema
record, its decoder (``decode(data)`` is the message) and its serialized ``data``."""


def decoded_messages(file, topics, raw=()) -> list:
    """``[(topic, log_time ns, message)]`` of the messages on ``topics`` in an ``.mcap`` file, in log-time order,
    decoded with the file's own schemas: what mcap_ros2's ``read_ros2_messages(file, topics)`` yields, the same
    messages in the same order. mcap's reader reads the file (``iter_messages(topics, log_time_order=True)``: by
    the chunk index of the summary, or linearly without one) and each schema's compiled decoder
    (:func:`roe_sep.bag.cdr.decoder`, mcap_ros2's for what it does not cover) decodes. The messages on the topics
    in ``raw`` come as :class:`RawMessage` (their decoding left to the caller). BagError, naming the file and the
    reason, when mcap cannot read the file, a wanted channel has no ROS 2 decoder, or a message does not decode."""
    from .cdr import decoder

    topics, raw = list(topics), frozenset(raw)
    decoders = {}  # per schema id, as mcap_ros2's DecoderFactory caches them
    out = []
    with open(file, "rb") as fh:
        records = make_reader(fh).iter_messages(topics=topics, log_time_order=True)
        while True:
            try:
                schema, channel, message = next(records)
            except StopIteration:
                break
            except Exception as exc:  # noqa: BLE001 -- mcap raises McapError, struct.error, ...: named, never hidden
                raise BagError(f"{file}: mcap cannot read it ({type(exc).__name__}: {one_line(exc)}); "
                               f"`roe-sep bag info` says what is damaged") from exc
            decode = decoders.get(channel.schema_id)
            if decode is None:
                try:
                    decode = decoders[channel.schema_id] = decoder(schema, channel.message_encoding)
                except Exception as exc:  # noqa: BLE001 -- a schema text mcap_ros2 cannot parse either
                    raise BagError(f"{file}: the schema of {channel.topic} does not parse ({one_line(exc)})") from exc
                if decode is None:
                    raise BagError(f"{file}: no ROS 2 decoder for {channel.topic} (message encoding "
                                   f"{channel.message_encoding!r}, schema "
                                   f"{schema.encoding if schema else 'none'!r})")
            if channel.topic in raw:
                out.append((channel.topic, message.log_time, RawMessage(schema, decode, message.data)))
                continue
            try:
                out.append((channel.topic, message.log_time, decode(message.data)))
            except Exception as exc:  # noqa: BLE001 -- cut off, bad UTF-8, ...: the message named
                raise BagError(f"{file}: the message on {channel.topic} logged at {message.log_time} ns does not "
                               f"decode as {schema.name} ({type(exc).__name__}: {one_line(exc)})") from exc
    return out


def _scan(file):
    """Every record of the file, CRCs checked: (scan, channels by id, schemas by id, per-channel counts, start, end)."""
    scan = Scan(file, message_counts=True)
    chans_by_id, schemas, per = {}, {}, collections.Counter()
    start = end = None
    for rec in scan.records():
        kind = type(rec).__name__
        if kind == "Schema":
            schemas[rec.id] = rec
        elif kind == "Channel":
            chans_by_id[rec.id] = rec
        elif kind == "Message":
            per[rec.channel_id] += 1
            start = rec.log_time if start is None else min(start, rec.log_time)
            end = rec.log_time if end is None else max(end, rec.log_time)
        elif kind == "MessageCounts" and rec.counts:  # a chunk's messages
            per.update(rec.counts)
            start = rec.start if start is None else min(start, rec.start)
            end = rec.end if end is None else max(end, rec.end)
    return scan, chans_by_id, schemas, per, start, end


def _summary_problems(file, per, count) -> list:
    """Disagreements between the summary section of a complete file and its records."""
    try:
        with open(file, "rb") as fh:
            _, summary = _summary(fh, file)
    except BagError as exc:
        return [f"summary section unreadable ({exc})"]
    stats = summary.statistics
    problems = []
    if stats.message_count != count:
        problems.append(f"summary statistics say {stats.message_count} messages, the records hold {count}")
    elif {k: v for k, v in stats.channel_message_counts.items() if v} != {k: v for k, v in per.items() if v}:
        problems.append("summary per-channel message counts differ from the records")
    return problems


def _metadata_problems(bag_dir, count, result, read=None) -> list:
    """A bag directory's metadata.yaml: present, readable, and the same message count as the file. ``read``:
    what :func:`_read_metadata` returned for it (read here when None)."""
    if bag_dir is None:
        return []
    if not (bag_dir / metadata.FILE_NAME).is_file():
        return [f"no {metadata.FILE_NAME} in {bag_dir} (`roe-sep bag recover` writes one)"]
    meta, exc = read or _read_metadata(bag_dir)
    try:
        if exc is not None:
            raise exc
        result["ros_distro"] = meta.get("ros_distro")
        n = int(meta.get("message_count"))
    except Exception as exc:  # noqa: BLE001  (any damage: bad YAML, missing keys, wrong types)
        return [f"{metadata.FILE_NAME} unreadable ({type(exc).__name__}: {one_line(exc)}); `roe-sep bag recover` "
                "rebuilds it"]
    if n != count:
        return [f"{metadata.FILE_NAME} says {n} messages, the file holds {count}"]
    return []


def info(path) -> dict:
    """Topics, types, counts and times of a bag, from a full record scan (CRCs checked) of its file.

    ``complete``: the file ends with its footer; ``damage_kind``: ``complete``, ``truncated`` (recording cut off:
    `roe-sep bag recover` keeps everything before the cut) or ``corrupt`` (unreadable bytes inside the file);
    ``problems``: every inconsistency found (summary vs records, metadata.yaml), empty for a sound bag.
    """
    bag_dir, file, meta = _resolve(path)
    result = {"path": str(bag_dir or file), "file": str(file), "storage_identifier": metadata.STORAGE_ID,
              "size_bytes": file.stat().st_size}
    scan, chans_by_id, schemas, per, start, end = _scan(file)
    chans = [(ch, schemas.get(ch.schema_id), per[cid]) for cid, ch in sorted(chans_by_id.items())]
    count = sum(per.values())
    problems = []
    result.update(complete=scan.complete, damage_kind=scan.kind, profile=scan.profile, library=scan.library)
    if scan.complete:
        problems += _summary_problems(file, per, count)
    else:
        result.update(recoverable_bytes=scan.valid_bytes, damage=scan.reason)
        problems.append(f"{scan.kind}: {scan.reason}; {scan.size - scan.valid_bytes} of {scan.size} bytes unreadable")
    problems += _metadata_problems(bag_dir, count, result, meta)
    if count == 0:
        start = end = 0
    result.update(
        message_count=count, start_ns=start, end_ns=end, duration_s=(end - start) * 1e-9,
        topics=[{"name": ch.topic, "type": schema.name if schema else "", "message_count": n,
                 "serialization_format": ch.message_encoding,
                 "qos": [{k: q.get(k) for k in ("reliability", "durability", "history", "depth")}
                         for q in _qos(ch)],
                 "type_description_hash": ch.metadata.get("topic_type_hash", "")}
                for ch, schema, n in chans],
        problems=problems)
    return result


def _qos(channel) -> list:
    try:
        return [q for q in metadata.parse_qos(channel.metadata.get("offered_qos_profiles", "")) if isinstance(q, dict)]
    except Exception:  # noqa: BLE001  (a damaged QoS string is reported as no QoS, never a crash)
        return []


def format_info(d: dict) -> str:
    """Human-readable :func:`info` (the layout of ``ros2 bag info``)."""
    lines = [f"Files:             {d['file']}",
             f"Bag size:          {d['size_bytes'] / 1024:.1f} KiB",
             f"Storage id:        {d['storage_identifier']}" + ("" if d["complete"] else
                                                                f"   ({d['damage_kind'].upper()}: run `roe-sep bag "
                                                                f"recover`)"),
             f"Duration:          {d['duration_s']:.3f}s",
             f"Start:             {d['start_ns'] * 1e-9:.9f}",
             f"End:               {d['end_ns'] * 1e-9:.9f}",
             f"Messages:          {d['message_count']}"]
    for i, t in enumerate(d["topics"]):
        qos = ", ".join(f"{q['reliability']}/{q['durability']}" for q in t["qos"]) or "-"
        lines.append(("Topic information: " if i == 0 else " " * 19)
                     + f"Topic: {t['name']} | Type: {t['type']} | Count: {t['message_count']} | "
                       f"Serialization Format: {t['serialization_format']} | QoS: {qos}")
    lines += [f"PROBLEM:           {p}" for p in d.get("problems", [])]
    return "\n".join(lines)
