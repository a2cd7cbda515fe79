"""rosbag2 ``metadata.yaml`` (bagfile information version 9, as ROS 2 Jazzy writes it) and QoS YAML, no rclpy.

The text is emitted in yaml-cpp's block style (what rosbag2 produces), so a Jazzy ``ros2 bag info``/``play`` and
any YAML reader accept it; :func:`read` parses it back with PyYAML.
"""

import json
import os
from pathlib import Path

import yaml

VERSION = 9
STORAGE_ID = "mcap"
FILE_NAME = "metadata.yaml"
NO_TIME = 0x7FFFFFFFFFFFFFFF  # rosbag2's starting_time when no message was written


def ros_distro() -> str:
    return os.environ.get("ROS_DISTRO") or "jazzy"


def _scalar(v) -> str:
    if v is None:
        return "~"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    s = str(v)
    try:
        plain_ok = s == s.strip() and "\n" not in s and yaml.safe_load(s) == s and not s.startswith(("-", "?", "["))
    except yaml.YAMLError:
        plain_ok = False
    return s if s and plain_ok else json.dumps(s)


def _emit(obj, indent: int) -> list:
    pad = " " * indent
    lines = []
    if isinstance(obj, dict):
        for key, value in obj.items():
            if isinstance(value, (dict, list)):
                if value:
                    lines.append(f"{pad}{key}:")
                    lines += _emit(value, indent + 2)
                else:
                    lines.append(f"{pad}{key}:")
                    lines.append(f"{pad}  {'{}' if isinstance(value, dict) else '[]'}")
            else:
                lines.append(f"{pad}{key}: {_scalar(value)}")
    else:
        for item in obj:
            if isinstance(item, (dict, list)) and item:
                sub = _emit(item, indent + 2)
                sub[0] = f"{pad}- " + sub[0][indent + 2:]
                lines += sub
            else:
                lines.append(f"{pad}- {_scalar(item)}")
    return lines


def dump(obj) -> str:
    """Block-style YAML of dicts/lists/scalars, yaml-cpp layout, no trailing newline (like ``YAML::Dump``)."""
    return "\n".join(_emit(obj, 0))


def qos_yaml(profiles) -> str:
    """The ``offered_qos_profiles`` string of an MCAP channel (rosbag2 ``serialize_rclcpp_qos_vector``)."""
    return dump(list(profiles)) if profiles else ""


def parse_qos(value):
    """Profiles from a channel's YAML string or a metadata.yaml list (numeric policies of version <= 8 mapped)."""
    from .qos import _NAMES

    if not value:
        return []
    items = _load(value) if isinstance(value, str) else value
    out = []
    for item in items or []:
        item = dict(item)
        for kind, names in _NAMES.items():
            if isinstance(item.get(kind), int):
                item[kind] = names.get(item[kind], "unknown")
        out.append(item)
    return out


def bag_info(files, topics, custom_data=None) -> dict:
    """The ``rosbag2_bagfile_information`` mapping.

    ``files``: ``[{"path", "starting_time" (ns), "duration" (ns), "message_count"}]``;
    ``topics``: ``[{"name", "type", "serialization_format", "offered_qos_profiles" (list of dicts),
    "type_description_hash", "message_count"}]``.
    """
    counted = [f for f in files if f["message_count"]]
    start = min((f["starting_time"] for f in counted), default=NO_TIME)
    end = max((f["starting_time"] + f["duration"] for f in counted), default=start)
    return {
        "version": VERSION,
        "storage_identifier": STORAGE_ID,
        "duration": {"nanoseconds": int(end - start)},
        "starting_time": {"nanoseconds_since_epoch": int(start)},
        "message_count": int(sum(f["message_count"] for f in files)),
        "topics_with_message_count": [
            {"topic_metadata": {"name": t["name"], "type": t["type"],
                                "serialization_format": t.get("serialization_format", "cdr"),
                                "offered_qos_profiles": list(t.get("offered_qos_profiles") or []),
                                "type_description_hash": t.get("type_description_hash", "")},
             "message_count": int(t["message_count"])}
            for t in topics],
        "compression_format": "",
        "compression_mode": "",
        "relative_file_paths": [f["path"] for f in files],
        "files": [{"path": f["path"], "starting_time": {"nanoseconds_since_epoch": int(f["starting_time"])},
                   "duration": {"nanoseconds": int(f["duration"])}, "message_count": int(f["message_count"])}
                  for f in files],
        "custom_data": custom_data or None,
        "ros_distro": ros_distro(),
    }


def write(bag_dir, info: dict) -> Path:
    """Write ``metadata.yaml`` atomically (temporary file + rename)."""
    path = Path(bag_dir) / FILE_NAME
    tmp = path.with_suffix(".yaml.tmp")
    tmp.write_text(dump({"rosbag2_bagfile_information": info}) + "\n", encoding="utf-8")
    os.replace(tmp, path)
    return path


_CSAFE = getattr(yaml, "CSafeLoader", None)  # PyYAML built with libyaml


def _load(source):
    """``yaml.safe_load(source)`` (a string or a text file), parsed by libyaml when PyYAML has it (ten times faster
    on a bag's metadata.yaml; the same SafeConstructor builds the values); anything libyaml refuses is parsed again
    by PyYAML itself, which raises what it raises."""
    if _CSAFE is not None:
        try:
            return yaml.load(source if isinstance(source, str) else source.read(), Loader=_CSAFE)  # noqa: S506
        except Exception:  # noqa: BLE001
            if not isinstance(source, str):
                source.seek(0)
    return yaml.safe_load(source)


def read(bag_dir) -> dict:
    """The ``rosbag2_bagfile_information`` mapping of a bag directory, QoS profiles parsed to lists of dicts."""
    path = Path(bag_dir) / FILE_NAME
    with open(path, encoding="utf-8") as fh:
        info = _load(fh)["rosbag2_bagfile_information"]
    for t in info.get("topics_with_message_count") or []:
        meta = t["topic_metadata"]
        meta["offered_qos_profiles"] = parse_qos(meta.get("offered_qos_profiles"))
    return info
