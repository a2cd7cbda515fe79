"""Helpers for the standard ``/diagnostics`` topic (diagnostic_msgs/DiagnosticArray)."""

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

OK, WARN, ERROR = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR


def publish_status(node, publisher, level, message, values=None, hardware_id="roe_sep", part=""):
    """Publish one DiagnosticStatus named ``roe_sep/<node name>[/<part>]`` with ``values`` as key/value strings."""
    name = f"roe_sep/{node.get_name()}" + (f"/{part}" if part else "")
    if isinstance(level, int):  # the message field is a byte
        level = bytes([level])
    status = DiagnosticStatus(level=level, name=name, message=message,
                              hardware_id=hardware_id,
                              values=[KeyValue(key=str(k), value=str(v)) for k, v in (values or {}).items()])
    array = DiagnosticArray(status=[status])
    array.header.stamp = node.get_clock().now().to_msg()
    publisher.publish(array)
