"""Bags: rosbag2-compatible MCAP recording, reading, recovery and replay.

Modules, one job each: :mod:`.definitions` (schema text and type hash of a message type), :mod:`.qos` (QoS
profiles <-> rosbag2 dictionaries), :mod:`.metadata` (``metadata.yaml``), :mod:`.writer` (the MCAP bag writer),
:mod:`.scan` (record scan of an unfinished file), :mod:`.cdr` (decoders compiled from a bag's own
schemas), :mod:`.reader` (topics, messages, decoded messages, :func:`info`), :mod:`.recover` (rebuild a bag from an
unfinished file) and
:mod:`.replay` (``roe-sep replay``, the only one that needs rclpy). The recorder node is
:mod:`roe_sep.nodes.recorder`.
"""


from ..errors import BagError

__all__ = ["BagError", "info"]


def info(path) -> dict:
    """Summary of a bag directory or ``.mcap`` file: topics, types, counts, duration (see :func:`.reader.info`)."""
    from .reader import info as _info

    return _info(path)
