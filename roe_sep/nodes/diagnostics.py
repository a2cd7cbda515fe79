"""Helpers for the standard ``/diagnostics`` topic (diagnostic_msgs/DiagnosticArray)."""

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

from ..core.decisions.common import Log
from .convert import sec_to_time

OK, WARN, ERROR = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR


def publish_status(node, publisher, level, message, values=None, *, hardware_id="roe_sep", part="", stamp=None):
    """Publish one DiagnosticStatus named ``roe_sep/<node name>[/<part>]`` with ``values`` as key/value strings.

    Stamped with ``stamp`` [s] if given, else the sim time of the node's current lockstep step, else its clock."""
    status = DiagnosticStatus(level=_level(level), name=_status_name(node, part), message=message,
                              hardware_id=hardware_id,
                              values=[KeyValue(key=str(k), value=str(v)) for k, v in (values or {}).items()])
    array = DiagnosticArray(status=[status])
    _stamp(node, array, stamp)
    publisher.publish(array)


def _status_name(node, part):
    return f"roe_sep/{node.get_name()}" + (f"/{part}" if part else "")


def _level(level):
    return bytes([level]) if isinstance(level, int) else level  # the message field is a byte


def _stamp(node, array, stamp=None):
    """The array's header stamp: ``stamp`` [s] if given, else the sim time of the node's current lockstep step, else
    its clock."""
    lockstep = getattr(node, "lockstep", None)
    if stamp is None and lockstep is not None and lockstep.active and lockstep.time is not None:
        stamp = lockstep.time
    if stamp is not None:
        array.header.stamp = sec_to_time(stamp)
    else:
        array.header.stamp = node.get_clock().now().to_msg()


class StatusMessages:
    """:func:`publish_status` for one status name whose values always have the same keys, in the same order: the
    messages built once and refilled at each publication (rclpy serializes a message when it is published, so the
    published bytes are those of a new message with these fields; a node that publishes a status at every
    assessment spares the construction of the array, its header, the status and its key/value pairs)."""

    def __init__(self, node, publisher, keys, hardware_id="roe_sep", part=""):
        self.node, self.publisher = node, publisher
        self.keys = tuple(str(k) for k in keys)
        self.pairs = [KeyValue(key=k, value="") for k in self.keys]
        self.status = DiagnosticStatus(name=_status_name(node, part), hardware_id=hardware_id, values=self.pairs)
        self.array = DiagnosticArray(status=[self.status])

    def publish(self, level, message, values):
        """As ``publish_status(node, publisher, level, message, values, hardware_id, part)``; ``values`` has the
        keys given at construction, in their order (ValueError otherwise)."""
        if tuple(str(k) for k in values) != self.keys:
            raise ValueError(f"status values {list(values)} are not the keys {list(self.keys)}")
        self.status.level, self.status.message = _level(level), message
        for pair, v in zip(self.pairs, values.values()):
            pair.value = str(v)
        _stamp(self.node, self.array)
        self.publisher.publish(self.array)


def report(node, publisher, action):
    """Carry out a decision's :class:`~roe_sep.core.decisions.common.Log` (logged) or
    :class:`~roe_sep.core.decisions.common.Status` (logged at its ``log`` level, if any, and published with
    :func:`publish_status`)."""
    if isinstance(action, Log):
        _log(node.get_logger(), action.level, action.text)
        return
    if action.log is not None:
        _log(node.get_logger(), action.log, action.message if action.log_text is None else action.log_text)
    publish_status(node, publisher, action.level, action.message, dict(action.values), part=action.part,
                   stamp=action.stamp)


def _log(logger, level, text):
    """``text`` at ``level``: one call site per severity (rclpy's logger keeps a call site's severity)."""
    if level == "debug":
        logger.debug(text)
    elif level == "info":
        logger.info(text)
    elif level == "warning":
        logger.warning(text)
    elif level == "error":
        logger.error(text)
    else:
        raise ValueError(f"unknown log level {level!r}")
